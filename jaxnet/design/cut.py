"""The cut of a netting panel, in the netting maker's terms: meshes, cutting rates, whole-mesh rounding.

jaxnet describes a diamond-mesh panel by the *twine coordinates* (U, V) of its corners (book section
4.2.1): U counts the twines of one direction crossed from an origin knot, V those of the other. The netting
maker counts *meshes* instead, with mesh coordinates (u, v) (book eqs 4.12-4.15):

    U = u + v,   V = v - u;      u = (U - V) / 2,   v = (U + V) / 2.

``u`` counts meshes in the **T-direction** (transversal: along the general course of the twine, i.e. along
the mesh rows, "across" the panel: the width of a cage wall, the circumference of a cod-end) and ``v``
meshes in the **N-direction** (normal: across the rows, "along" or "down" the panel: the depth of a cage
wall, the length of a cod-end). One mesh (one unit of u by one of v: a mesh's width by its depth, two rows
of knots) is 2 twines along each of U and V: 2 knots and 4 bars, each a mesh side ``l0`` long. A panel of
area A in (U, V) holds A / 2 meshes and A l0 metres of twine (per triangle |d| / 4 meshes and |d| / 2 twines
of each direction, eqs 4.24-4.26): 4 l0 metres of twine per mesh.

A side of a panel is *cut* by repeating elementary steps (ISO 1107's N, T and B cuts), in (U, V):

  * **N** (point, "normal") step: one mesh in the N-direction, (U, V) += (1, 1);
  * **T** (transversal) step: one mesh in the T-direction, (U, V) += (1, -1);
  * **B** (bar) step: along one bar, half a mesh in each direction, (U, V) += (1, 0) or (0, 1).

A side (dU, dV) of integer twine counts is made of min(|dU|, |dV|) N steps (dU and dV of one sign) or
T steps (opposite signs), and ||dU| - |dV|| B steps. The **cutting rate** is the repeating pattern reduced
by the greatest common divisor: "AN" (all points: a straight cut along the N-direction, a selvedge), "AT"
(all transversal: straight along the rows), "AB" (all bars: along the twines, at 45° in a square mesh) and
mixed rates "1N2B", "3N2B", "2T1B"... as ISO 1107 and the FAO gear catalogues write them. A tapered panel
narrowing by k meshes on each side over a depth of m meshes has sides of 2k bars and m - k points: for
example 100 meshes at the top, 80 at the bottom, 40 deep: (m - k, 2k) = (30, 20), i.e. "3N2B".

The **meshes along a side** are max(|du|, |dv|) = (|dU| + |dV|) / 2 (the trade's count: the depth of a
tapered side, the width of an AT side, half the bars of an AB side), and its **stretched length** is
(|dU| + |dV|) l0 m: the longest the border can be drawn, every bar along it. The hanging ratio of a
rope mounted on it (:mod:`jaxnet.design.space`) is E = rope length / stretched length.

Continuous corner coordinates are what an optimiser moves; :func:`round_cut` brings a cut back to corners
on whole meshes (integer u and v from corner 0, so every side is whole N/T/B steps: a cut that can be made)
and reports each side as the netting maker writes it.

The differentiable functions (:func:`mesh_to_twine`, :func:`twine_to_mesh`, :func:`trapezoid`,
:func:`side_meshes`, :func:`stretched_length`, :func:`panel_meshes`) are jnp functions of their arguments;
the naming and rounding functions work on concrete numbers (numpy) and raise ValueError on bad input.
Whole meshes are counted from corner 0 of each panel (its own position in (U, V) is arbitrary).
"""

from __future__ import annotations

import dataclasses
import math

import jax.numpy as jnp
import numpy as np

__all__ = ["mesh_to_twine", "twine_to_mesh", "trapezoid", "side_meshes", "stretched_length", "panel_meshes",
           "side_steps", "cutting_rate", "SideCut", "ROUNDING_STEPS", "round_cut", "describe_sides"]

# a twine count this close to an integer is that integer (rounded cuts come back through float arithmetic)
_WHOLE = 1e-6


def mesh_to_twine(uv_mesh):
    """Twine coordinates (..., 2) (U, V) of mesh coordinates (..., 2) (u, v), meshes -> twines (4.12-4.13)."""
    uv_mesh = jnp.asarray(uv_mesh)
    u, v = uv_mesh[..., 0], uv_mesh[..., 1]
    return jnp.stack([u + v, v - u], axis=-1)


def twine_to_mesh(uv):
    """Mesh coordinates (..., 2) (u, v) of twine coordinates (..., 2) (U, V), twines -> meshes (4.14-4.15)."""
    uv = jnp.asarray(uv)
    U, V = uv[..., 0], uv[..., 1]
    return jnp.stack([0.5 * (U - V), 0.5 * (U + V)], axis=-1)


def trapezoid(top_meshes, bottom_meshes, depth_meshes):
    """(4, 2) corner twine coordinates (U, V) of a symmetric tapered panel.

    top_meshes, bottom_meshes: meshes across (T-direction) at the top and the bottom; depth_meshes: meshes
    deep (N-direction). Corners, in order: top left (0, 0), top right (top, 0), bottom right, bottom left in
    mesh coordinates (u across, v down), the bottom centred under the top, so each tapered side narrows by
    (top - bottom) / 2 meshes: the layout of the cage wall in :func:`jaxnet.scenes.cage.fish_cage` when top =
    bottom. Differentiable in the three counts (continuous relaxation); whole counts with an even
    difference top - bottom give corners on whole meshes. Panel area: (top + bottom) depth / 2 meshes.
    """
    n1, n2, m = jnp.asarray(top_meshes, float), jnp.asarray(bottom_meshes, float), jnp.asarray(depth_meshes, float)
    zero = jnp.zeros_like(n1 + n2 + m)
    taper = 0.5 * (n1 - n2)
    mesh = jnp.stack([jnp.stack([zero, zero]), jnp.stack([n1 + zero, zero]),
                      jnp.stack([taper + n2, m + zero]), jnp.stack([taper + zero, m + zero])])
    return mesh_to_twine(mesh)


def side_meshes(d_uv):
    """Meshes along a side of twine extent d_uv (..., 2) = (dU, dV): (|dU| + |dV|) / 2 = max(|du|, |dv|).
    Not differentiable where dU or dV is 0 (an AB side): the count has a kink there."""
    d_uv = jnp.asarray(d_uv)
    return 0.5 * (jnp.abs(d_uv[..., 0]) + jnp.abs(d_uv[..., 1]))


def stretched_length(d_uv, l0):
    """Stretched length (m) of a side of twine extent d_uv (..., 2) in netting of mesh side l0 (m):
    (|dU| + |dV|) l0, the length of the border with every bar drawn along it (2 l0 per mesh)."""
    return 2.0 * side_meshes(d_uv) * l0


def panel_meshes(corners_uv):
    """Number of meshes in a panel of corners (C, 2) (U, V) (twines): |area in (U, V)| / 2 (eq. 4.24 summed).
    A trapezoid of n1 and n2 meshes across and m deep holds (n1 + n2) m / 2."""
    uv = jnp.asarray(corners_uv)
    nxt = jnp.roll(uv, -1, axis=0)
    area = 0.5 * jnp.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1])
    return 0.5 * jnp.abs(area)


def _whole(value, what):
    v = float(value)
    if not math.isfinite(v) or abs(v - round(v)) > _WHOLE:
        raise ValueError(f"{what}: {v!r} is not a whole number of twines (round the cut first: round_cut)")
    return int(round(v))


def side_steps(dU, dV) -> dict:
    """Cutting steps of a side of whole twine extents (dU, dV): {"N": points, "T": transversals, "B": bars}.

    A side whose extents have one sign runs along the N-direction (N steps and B steps), one of opposite
    signs along the T-direction (T steps and B steps). Raises ValueError for a non-integer extent or a side
    of zero length.
    """
    a, b = _whole(dU, "dU"), _whole(dV, "dV")
    if a == 0 and b == 0:
        raise ValueError("a side of zero length (dU = dV = 0) has no cutting rate")
    diagonal, bars = min(abs(a), abs(b)), abs(abs(a) - abs(b))
    same_sign = a * b > 0
    return {"N": diagonal if same_sign else 0, "T": 0 if same_sign else diagonal, "B": bars}


def cutting_rate(dU, dV) -> str:
    """The cutting rate of a side of whole twine extents (dU, dV), as the trade writes it.

    "AN", "AT", "AB" for straight cuts, else the repeating pattern reduced by the gcd, points or
    transversals first: (3, 1) -> "1N2B", (1, 1) -> "AN", (1, -1) -> "AT", (1, 0) -> "AB",
    (30, 50) -> "3N2B", (3, -1) -> "1T2B".
    """
    steps = side_steps(dU, dV)
    letter = "N" if steps["N"] else "T"
    diagonal, bars = steps[letter], steps["B"]
    if bars == 0:
        return "A" + letter
    if diagonal == 0:
        return "AB"
    g = math.gcd(diagonal, bars)
    return f"{diagonal // g}{letter}{bars // g}B"


@dataclasses.dataclass(frozen=True)
class SideCut:
    """One side of a panel as the netting maker reads it.

    side: index k (from corner k to corner k + 1, cyclic); du, dv: extent in meshes across (T-direction)
    and along (N-direction); meshes: meshes along the side, max(|du|, |dv|); steps: {"N", "T", "B"} counts;
    rate: cutting rate ("AN", "1N2B", ...). whole: whether the side is whole twines; a side drawn on fractions
    of a twine (FEMNET's files allow it) has its exact extents and meshes, and the steps and rate of the nearest
    whole side, its rate written "≈1N2B".
    """

    side: int
    du: float
    dv: float
    meshes: float
    steps: dict
    rate: str
    whole: bool = True

    def __str__(self):
        steps = " ".join(f"{n}{k}" for k, n in self.steps.items() if n)
        return f"side {self.side}: {self.meshes:g} meshes, {self.rate} ({steps}; du {self.du:+g}, dv {self.dv:+g})"


def describe_sides(corners_uv) -> tuple:
    """(C,) :class:`SideCut` of a panel of corners (C, 2) (U, V): whole meshes or twines give exact steps and
    rates; a side on fractions of a twine is described by the nearest whole side (``SideCut.whole`` False)."""
    uv = np.asarray(corners_uv, dtype=float)
    out = []
    for k in range(len(uv)):
        dU, dV = uv[(k + 1) % len(uv)] - uv[k]
        whole = abs(dU - round(dU)) <= _WHOLE and abs(dV - round(dV)) <= _WHOLE
        if whole:
            dU, dV = float(round(dU)), float(round(dV))
        near = (round(dU), round(dV))
        if near == (0, 0):
            steps, rate = {"N": 0, "T": 0, "B": 0}, "-"
        else:
            steps, rate = side_steps(*near), cutting_rate(*near)
        out.append(SideCut(side=k, du=0.5 * (dU - dV), dv=0.5 * (dU + dV), meshes=0.5 * (abs(dU) + abs(dV)),
                           steps=steps, rate=rate if whole else "≈" + rate, whole=bool(whole)))
    return tuple(out)


#: the units a cut is rounded to (:func:`round_cut`): whole meshes (N and T steps, and B steps in pairs), or
#: whole twines (any N, T and B steps: a corner may end half a mesh off, a bar cut)
ROUNDING_STEPS = ("mesh", "twine")


def round_cut(corners_uv, name="panel", reference=None, step="mesh"):
    """Corners (C, 2) (U, V) moved to whole meshes (or twines) and the rounded sides.

    Without ``reference``, corner 0 stays where it is (only differences of twine coordinates mean anything)
    and every other corner's offset from it is rounded: to whole meshes (integer mesh coordinates (u, v),
    ``step="mesh"``: each corner moves by at most half a mesh along u and along v) or to whole twines (integer
    (U, V), ``step="twine"``: at most half a twine along each), so every side is whole N, T and B steps.
    With ``reference`` (C, 2), the cut as it was drawn (a FEMNET ``.don`` file's corners, which may sit on half
    meshes), what is rounded is each corner's change from it: a design that adds or removes whole meshes (or
    twines) of the drawn panel, and the reference itself comes back unchanged whatever its own fractions.
    A cut already whole is returned unchanged. Returns (corners (C, 2) numpy float, tuple of :class:`SideCut`).
    Raises ValueError naming the panel and the corner or side when the corners are not finite or the rounded
    polygon is degenerate (two corners on one mesh, zero area, crossing sides): a panel too small or too
    distorted to round.
    """
    from jaxnet.mesh.polygon import PanelError, check_polygon

    if step not in ROUNDING_STEPS:
        raise ValueError(f"panel {name!r}: step must be one of {ROUNDING_STEPS}, got {step!r}")
    uv = np.asarray(corners_uv, dtype=float)
    if uv.ndim != 2 or uv.shape[1] != 2:
        raise ValueError(f"panel {name!r}: corners must have shape (C, 2) (U, V), got {uv.shape}")
    bad = np.argwhere(~np.isfinite(uv))
    if bad.size:
        raise ValueError(f"panel {name!r}: corner {int(bad[0][0])} has a non-finite twine coordinate")
    if reference is None:
        origin = np.broadcast_to(uv[0], uv.shape)
    else:
        origin = np.asarray(reference, dtype=float)
        if origin.shape != uv.shape:
            raise ValueError(f"panel {name!r}: reference corners have shape {origin.shape}, the cut {uv.shape}")
    if step == "mesh":
        whole = np.rint(np.asarray(twine_to_mesh(uv - origin)))  # whole meshes from the origin
        rounded = origin + np.asarray(mesh_to_twine(whole))
    else:
        whole = np.rint(uv - origin)
        rounded = origin + whole
    try:
        check_polygon(rounded, name)
    except PanelError as err:
        raise ValueError(f"{err} (after rounding the cut to whole {step}es: corners moved by {whole.tolist()} "
                         f"{'meshes (u, v)' if step == 'mesh' else 'twines (U, V)'} from "
                         f"{'corner 0' if reference is None else 'the reference'})") from err
    return rounded, describe_sides(rounded)
