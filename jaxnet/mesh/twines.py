"""Numerical twines: a netting panel meshed as bars along its twines (book section 4.1.2; FEMNET's ``input
netting2ropes``, its manual's "Numerical twines").

Instead of triangles (the triangular netting element), the panel becomes chains of bars along the two twine
directions. One *numerical twine* stands for ``period`` real twines side by side: the lines of constant u
(which run along v) are ``period`` twines apart, and so are the lines of constant v; along each line a bar
spans ``period / bars`` twines. A numerical twine therefore carries the material of ``period`` real twines
(:func:`numerical_twine_rope`): the same tension for the same strain as the netting it replaces, and the same
weight and drag.

Twine coordinates (u, v) are jaxnet's (:mod:`jaxnet.mesh.panel`: counted in twines, a twine ``l0`` metres
long; FEMNET's (U, V) turned into (U + V, V - U) by the ``.don`` reader). The lines are laid out as FEMNET's
mesher lays them (``meshing_netting_2_ropes3.c``): with p the period, h = p / bars the bar length in twines and
``trunc`` C's conversion to an integer,

    u_k = trunc(min u - p) + (offset_u + k) p     (lines of constant u; their nodes at v = v_0 + j h),
    v_k = trunc(min v - p) + (offset_v + k) p     (lines of constant v; their nodes at u = u_0 + j h),

min u and min v over the corners, so that a crossing of two lines is a node of both. Each line is clipped to
the panel: every stretch of it inside the polygon becomes a chain of bars from the border point where it
enters, through the lattice nodes inside, to the border point where it leaves. A line along a side (or
touching only a corner) makes no bar: the rope along that side is there. Nodes closer than ``accuracy``
twines merge: a lattice node that near to its chain's border point is dropped (the bar then runs from the
border point to the next node), a border point that near to a corner or to an earlier border point becomes
that node.

Differences from FEMNET's mesher, which makes the same mesh where the lattice falls on the border (FEMNET's
cases ``0simple/nr_*``): FEMNET projects a lattice node within ``accuracy`` of a side onto the side (across
the side, so the bar leaves its twine line), where this mesher keeps every bar on its line; FEMNET ignores a
line that crosses the border twice within one bar (its manual: "numerical twines which cut two boundaries are
not taken into account"), where this mesher clips it like any other; and FEMNET's solver gives every bar of
numerical twines the full rest length ``l0 p / bars`` (``lectureDo4.c``), also to a bar cut by the border, where
here a bar's rest length is the twines it spans along its line, ``l0 |Δ|``, Δ the change of the line's own
coordinate (v for a line of constant u) between its ends.

Node ordering of a :class:`TwineMesh`: the C corners, then the border nodes side by side (side k from corner
k to corner k + 1, in order along it), then the nodes inside. Start positions are ``weights @ corners_xyz``:
linear along the sides, mean value coordinates inside (as :mod:`jaxnet.mesh.panel`; FEMNET interpolates in
the triangles of its contour, which is the same for a panel whose (u, v) -> (x, y, z) map is affine).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jaxnet.materials import Rope, Twine
from jaxnet.mesh.polygon import distance_to_boundary, inside, mean_value_coordinates, panel_error, validate_panel

__all__ = ["NumericalTwines", "TwineMesh", "mesh_twines", "numerical_twine_rope"]

#: Refuse to mesh a panel into more bars than this (FEMNET's own limit is 5000 bars in all).
MAX_BARS = 200_000


@dataclasses.dataclass(frozen=True)
class NumericalTwines:
    """How to mesh a panel as numerical twines (FEMNET's ``input netting2ropes PANEL period offset_u offset_v
    accuracy bars``).

    period: real twines per numerical twine (> 0): the lines are ``period`` twines apart, and each stands for
      that many real twines (FEMNET's "period of twines": "numerical twines are 10 times larger than actual
      twines" for 10).
    bars: bars per ``period`` along a line (>= 1), each ``period / bars`` twines long (FEMNET's "number of bar
      elements inside a full numerical twine").
    offset_u, offset_v: where the lines of constant u (resp. v) lie within the period, as a fraction of it
      (FEMNET's positions of the numerical U and V twines relatively to the period): u_k = u_0 + (offset_u + k)
      period. 0.5 puts the lines half a period off the lattice of the corners, which keeps them off sides
      that lie on it.
    accuracy: nodes closer than this (twines) merge (see the module docstring); 0 merges only coincident ones.
    femnet_tangential: with False, the numerical twines' tangential drag is that of the real twines they stand
      for (f unchanged); with True, FEMNET's: its solver scales f, as Cd, by sqrt(period) (``lectureDo4.c``), and
      its bar drag takes f times Cd (``basic_bar_drag1.c``), so its tangential drag is sqrt(period) times that
      of the real twines. The ``.don`` reader sets it with FEMNET's laws.
    """

    period: float
    bars: int = 1
    offset_u: float = 0.0
    offset_v: float = 0.0
    accuracy: float = 0.0
    femnet_tangential: bool = False

    def check(self, what):
        """A message naming ``what`` for the first bad value, or None when all are usable."""
        if not (math.isfinite(self.period) and self.period > 0):
            return f"{what}: numerical twines: period must be > 0 (twines), got {self.period!r}"
        if int(self.bars) != self.bars or self.bars < 1:
            return f"{what}: numerical twines: bars (per period) must be an integer >= 1, got {self.bars!r}"
        for name in ("offset_u", "offset_v"):
            if not math.isfinite(getattr(self, name)):
                return f"{what}: numerical twines: {name} must be finite, got {getattr(self, name)!r}"
        if not (math.isfinite(self.accuracy) and self.accuracy >= 0):
            return f"{what}: numerical twines: accuracy must be >= 0 (twines), got {self.accuracy!r}"
        return None


def numerical_twine_rope(twine: Twine, twines: NumericalTwines) -> Rope:
    """The bar material of a numerical twine standing for p = ``twines.period`` real twines of ``twine``.

    Traction and compression stiffness EA p: p twines side by side, strained alike, pull p times as hard (so
    that a panel's force is that of its real twines). Diameter D sqrt(p): the section pi D² p / 4 of p twines,
    so the weight and buoyancy are theirs. Normal drag coefficient Cd sqrt(p): the drag per length
    ½ ρ (Cd sqrt(p)) (D sqrt(p)) |c_n|² is p times a twine's. Tangential ratio f (the tangential drag p times a
    twine's too), or FEMNET's f sqrt(p) with ``twines.femnet_tangential``. Density unchanged. These are FEMNET's
    scalings (``lectureDo4.c``, the bars of type -PANEL), the tangential ratio aside.
    """
    p = float(twines.period)
    root = math.sqrt(p)
    return Rope(ea=twine.ea * p, ea_compression=twine.ea_compression * p, diameter=twine.diameter * root,
                density=twine.density, cd_normal=twine.cd_normal * root,
                tangential_ratio=twine.tangential_ratio * (root if twines.femnet_tangential else 1.0))


@dataclasses.dataclass(frozen=True)
class TwineMesh:
    """A panel meshed as numerical twines.

    uv: (n, 2) twine coordinates of the nodes (twines); xyz: (n, 3) start positions (m), ``weights @
      corners_xyz``; weights: (n, C) interpolation weights w.r.t. the corners (rows sum to 1).
    bars: (B, 2) node indices of each bar; twines: (B,) its rest length in twines (times l0: metres);
      family: (B,) 0 for a bar along u (on a line of constant v), 1 for a bar along v.
    corner_nodes: (C,) ``arange(C)``; side_nodes: C arrays, ``side_nodes[k]`` the nodes on side k in order
      from corner k to corner k + 1, both included.
    triangles: (0, 3): none (for code that reads a panel's triangles).
    """

    uv: np.ndarray
    xyz: np.ndarray
    weights: np.ndarray
    bars: np.ndarray
    twines: np.ndarray
    family: np.ndarray
    corner_nodes: np.ndarray
    side_nodes: tuple
    triangles: np.ndarray


def _line_intervals(poly, c, tol):
    """Stretches [a, b] (a < b) of the line {x[0] = c} (parameter t = x[1]) inside the polygon ``poly`` (C, 2),
    in (across, along) coordinates. A stretch along a side, or a single point, is not inside."""
    nxt = np.roll(poly, -1, axis=0)
    ts = []
    for p, q in zip(poly, nxt):
        if abs(q[0] - p[0]) <= tol:
            if abs(p[0] - c) <= tol:
                ts += [p[1], q[1]]
            continue
        s = (c - p[0]) / (q[0] - p[0])
        if -1e-12 <= s <= 1.0 + 1e-12:
            ts.append(p[1] + s * (q[1] - p[1]))
    if len(ts) < 2:
        return []
    ts = np.unique(np.round(np.sort(ts) / tol) * tol) if tol > 0 else np.unique(ts)
    out = []
    for a, b in zip(ts[:-1], ts[1:]):
        if b - a <= tol:
            continue
        mid = np.array([[c, 0.5 * (a + b)]])
        if inside(mid, poly)[0] and distance_to_boundary(mid, poly)[0] > tol:
            if out and abs(out[-1][1] - a) <= tol:
                out[-1][1] = b
            else:
                out.append([a, b])
    return out


def mesh_twines(corners_uv, corners_xyz, twines: NumericalTwines, divisions=None, name="panel") -> TwineMesh:
    """Mesh a panel as numerical twines (see the module docstring).

    corners_uv: (C, 2) twine coordinates (u, v) of the corners (twines), a simple polygon in either
      orientation; corners_xyz: (C, 3) their start positions (m).
    twines: the :class:`NumericalTwines` layout.
    divisions: (C,) ints or None: a side k with ``divisions[k] = n >= 1`` also gets nodes at the fractions
      j / n of its length (the nodes of a cable of n bars sewn along it, which FEMNET keeps and into which it
      inserts the numerical twines' border nodes); 0 or None: only the twines' border nodes.
    name: the panel's name in error messages.

    Raises :class:`~jaxnet.mesh.polygon.PanelError` for a bad polygon or layout, or a panel that no numerical
    twine crosses.
    """
    bad = twines.check(f"panel '{name}'")
    if bad:
        raise panel_error(name, bad.removeprefix(f"panel '{name}': "))
    uv_c, xyz_c, _h, seg, _area, scale, _div = validate_panel(corners_uv, corners_xyz, 1.0, 1.0, None, name)
    if xyz_c is None:
        raise panel_error(name, "corners_xyz is required")
    C = len(uv_c)
    p, nb = float(twines.period), int(twines.bars)
    h = p / nb
    tol = 1e-9 * max(scale, p)
    merge = max(float(twines.accuracy), tol)
    lo, hi = uv_c.min(axis=0), uv_c.max(axis=0)
    origin = np.trunc(lo - p) + np.array([twines.offset_u, twines.offset_v]) * p
    estimate = 2 * np.prod((hi - lo) / p + 2) * nb
    if estimate > MAX_BARS:
        raise panel_error(name, f"period {p:g} twines gives about {estimate:.3g} bars (limit {MAX_BARS}); use a "
                          "larger period")

    border, interior, chains = _twine_lines(uv_c, origin, p, nb, lo, hi, merge, tol)
    on_side = _border_nodes(border, uv_c, divisions, seg, tol)
    index, weights, sides, inner_uv = _numbering(uv_c, on_side, interior, origin, h)
    n = len(weights)
    uv = weights @ uv_c
    if len(inner_uv):
        uv[n - len(inner_uv):] = inner_uv    # exactly on the lattice (the weights reproduce it to rounding)

    bars, fam = [], []
    for family, keys in chains:
        ids = [index[key] for key in keys]
        for i, j in zip(ids[:-1], ids[1:]):
            if i != j:
                bars.append((i, j))
                fam.append(family)
    if not bars:
        raise panel_error(name, f"no numerical twine crosses the panel (period {p:g} twines, offsets "
                          f"{twines.offset_u:g}, {twines.offset_v:g}): use a smaller period")
    bars = np.array(bars, dtype=np.int64)
    fam = np.array(fam, dtype=np.int64)
    # the twines a bar spans along its line: the change of the line's own coordinate (u for family 0)
    span = np.where(fam == 0, np.abs(uv[bars[:, 1], 0] - uv[bars[:, 0], 0]),
                    np.abs(uv[bars[:, 1], 1] - uv[bars[:, 0], 1]))
    if np.any(span <= tol):
        b = int(np.flatnonzero(span <= tol)[0])
        raise panel_error(name, f"numerical twines: a bar between nodes at (u, v) = {uv[bars[b, 0]].tolist()} and "
                          f"{uv[bars[b, 1]].tolist()} spans no twine (accuracy {twines.accuracy:g} merged its ends "
                          "across the line); use a smaller accuracy")
    xyz = weights @ xyz_c
    arrays = dict(uv=uv, xyz=xyz, weights=weights, bars=bars, twines=span, family=fam,
                  corner_nodes=np.arange(C, dtype=np.int64), triangles=np.zeros((0, 3), dtype=np.int64))
    for a in arrays.values():
        a.setflags(write=False)
    for s in sides:
        s.setflags(write=False)
    return TwineMesh(side_nodes=tuple(sides), **arrays)


def _twine_lines(uv_c, origin, p, nb, lo, hi, merge, tol):
    """The numerical twines crossing the polygon ``uv_c``: lines of constant v (family 0, bars along u) and of
    constant u (family 1) every ``p`` twines from ``origin``, each cut into its intervals inside the polygon and
    divided every p / ``nb`` twines. Returns (border nodes' (u, v), lattice index (iu, iv) -> interior node key,
    chains: (family, [node keys along the line])); a node within ``merge`` of a corner or of a border node is
    that node."""
    h = p / nb
    corner_uv = [q for q in uv_c]
    border = []          # [uv] of border nodes (projected onto their side)
    interior = {}        # (iu, iv) lattice index -> node key
    chains = []          # per family: list of (list of node keys, along params)

    def border_node(point):
        for k, q in enumerate(corner_uv):
            if np.hypot(*(point - q)) <= merge:
                return ("c", k)
        for k, q in enumerate(border):
            if np.hypot(*(point - q)) <= merge:
                return ("b", k)
        border.append(_onto_border(point, uv_c))
        return ("b", len(border) - 1)

    for family in (0, 1):
        across, along = (1, 0) if family == 0 else (0, 1)   # family 0: bars along u, on lines of constant v
        poly = uv_c[:, [across, along]]
        k0 = math.floor((lo[across] - origin[across]) / p) - 1
        k1 = math.ceil((hi[across] - origin[across]) / p) + 1
        for k in range(k0, k1 + 1):
            c = origin[across] + k * p
            for a, b in _line_intervals(poly, c, tol):
                j0, j1 = math.ceil((a - origin[along]) / h), math.floor((b - origin[along]) / h)
                params = [a]
                keys = []
                for j in range(j0, j1 + 1):
                    t = origin[along] + j * h
                    if t - a <= merge or b - t <= merge:
                        continue
                    params.append(t)
                    idx = [0, 0]
                    idx[across], idx[along] = k * nb, j
                    keys.append(("i", interior.setdefault(tuple(idx), len(interior))))
                params.append(b)
                ends = []
                for t in (a, b):
                    point = np.empty(2)
                    point[across], point[along] = c, t
                    ends.append(border_node(point))
                chains.append((family, [ends[0], *keys, ends[1]]))
    return border, interior, chains


def _border_nodes(border, uv_c, divisions, seg, tol):
    """The border nodes side by side: per side k, [(fraction along it, node key)] in order, the twines' border
    nodes and the ``divisions[k]`` - 1 nodes of a cable sewn along it (those not within ``tol`` of a twine's)."""
    C = len(uv_c)
    divisions = np.zeros(C, dtype=int) if divisions is None else np.asarray(divisions, dtype=int)
    on_side = [[] for _ in range(C)]   # (fraction, key)
    for k, q in enumerate(border):
        s, frac = _side_of(q, uv_c)
        on_side[s].append((frac, ("b", k)))
    for s in range(C):
        n = int(divisions[s]) if s < len(divisions) else 0
        for j in range(1, n):
            frac = j / n
            if not any(abs(f - frac) * seg[s] <= tol for f, _ in on_side[s]):
                key = ("d", (s, j))
                on_side[s].append((frac, key))
        on_side[s].sort(key=lambda fk: fk[0])
    return on_side


def _numbering(uv_c, on_side, interior, origin, h):
    """The nodes numbered: corners, border nodes side by side, interior nodes. Returns (node key -> index, (n, C)
    weights of the corners, each side's node indices from its corner to the next, the interior nodes' (u, v))."""
    C = len(uv_c)
    index = {("c", k): k for k in range(C)}
    rows = [np.eye(C)]
    n = C
    sides = []
    for s in range(C):
        ids = [s]
        for frac, key in on_side[s]:
            index[key] = n
            w = np.zeros((1, C))
            w[0, s], w[0, (s + 1) % C] = 1.0 - frac, frac
            rows.append(w)
            ids.append(n)
            n += 1
        ids.append((s + 1) % C)
        sides.append(np.array(ids, dtype=np.int64))
    inner = sorted(interior, key=lambda ij: interior[ij])
    inner_uv = origin + np.array(inner, dtype=float).reshape(-1, 2) * h
    if len(inner_uv):
        rows.append(mean_value_coordinates(inner_uv, uv_c))
    for ij in inner:
        index[("i", interior[ij])] = n
        n += 1
    return index, np.concatenate(rows, axis=0), sides, inner_uv


def _side_of(point, poly):
    """(side k, fraction along it in [0, 1]) of the side of ``poly`` nearest to ``point``."""
    a = poly
    e = np.roll(poly, -1, axis=0) - poly
    t = np.clip(((point - a) * e).sum(axis=1) / (e * e).sum(axis=1), 0.0, 1.0)
    d = np.hypot(*(a + t[:, None] * e - point).T)
    k = int(np.argmin(d))
    return k, float(t[k])


def _onto_border(point, poly):
    """``point`` moved onto the nearest side of ``poly`` (twine coordinates)."""
    k, t = _side_of(point, poly)
    return poly[k] + t * (poly[(k + 1) % len(poly)] - poly[k])
