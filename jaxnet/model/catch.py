"""The catch of a cod-end: its front, the volume it fills, and what FEMNET reports about it.

The catch (book §4.3.6) is a volume of fish at the rear of a cod-end. Its upstream face, the *catch
front*, is the plane {y : y·a = s} normal to the cod-end axis a (unit, pointing downstream); the netting
behind the front carries the catch pressure (:mod:`jaxnet.terms.pressure`), and s is placed so that the
volume enclosed by that netting and the front plane is the catch volume. The book does not say how; this
follows FEMNET (prise.c: ``surface_volume``, ``nouveau_front2``, ``rayon_maxi``, ``catch_hexa``):

* Volume (:func:`enclosed_volume`): divergence theorem with the field (y·a - s) a, whose divergence is 1.
  It vanishes on the front plane, so the cap closing the catch there contributes nothing, and it is
  parallel to a, so symmetry planes containing the axis (quarter and half models) contribute nothing
  either: summing over the netting triangles behind the front gives the volume of the modelled part.
  ``symmetry`` (4 for a quarter model, 2 for a half) scales it to the whole cod-end. FEMNET sums the
  same prisms (projected surface × mean height, signed by the element's orientation) but reports the
  volume of the modelled part: its worked case c2 (a quarter model) asks for and reports 0.2 m³, which
  is 0.8 m³ for the whole cod-end, i.e. ``volume=0.8, symmetry=4`` here.
* Front (:func:`catch_front`): V(s) decreases from V(s_min) (front at the most upstream netting node:
  the most the net can hold) to 0 at s_max (the rearmost node); dV/ds = -A(s), A the front's
  cross-section. A Newton iteration on s safeguarded by bisection of the bracket [s_min, s_max] solves
  V(s) = volume (jax.lax.while_loop, fixed tolerances). When the net cannot hold the volume, the front
  is put at s_min and ``holds`` is False (FEMNET does the same, silently). Differentiating the front
  position uses the implicit function theorem, ds = (∂V/∂x dx - dvolume) / (symmetry A), instead of
  differentiating through the iteration.
* Report (:func:`catch_summary`), as FEMNET prints it: catch thickness = rearmost node abscissa - s;
  maximal catch diameter = twice the largest half-width of the netting nodes behind the front, measured
  along the two transverse directions (horizontal and vertical for a horizontal axis): from the axis
  when its position ``center`` is given (FEMNET measures from the symmetry planes), else half the extent
  of those nodes; catch drag = p × front cross-section = the axial component of the pressure forces.
  With c2's equilibrium (FEMNET's positions, front 4.450 m) this gives 0.628 m, 1.452 m and 978 N for
  the quarter model, as FEMNET prints (p = ½ 1025 · 1.4 · 1.9² Pa).

Orientation: ``sign`` is the one of :func:`jaxnet.terms.pressure.catch_pressure` (+1: 12 ^ 13 points out
of the cod-end), a scalar or one value per triangle. All functions take every node at once, are jnp and
jittable, and build no dense matrix.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms import pressure as catch_pressure_term


def _element_sums(x, triangles, s, axis, sign):
    """(volume, front section) of the modelled netting behind the front at abscissa s (m³, m²)."""
    sign = jnp.broadcast_to(jnp.asarray(sign, dtype=x.dtype), triangles.shape[:1])
    per_element = jax.vmap(catch_pressure_term.volume_and_section, in_axes=(0, None, None, 0))
    volume, section = per_element(x[triangles], s, axis, sign)
    return jnp.sum(volume), jnp.sum(section)


def enclosed_volume(x, triangles, front, axis, symmetry=1.0, sign=1.0):
    """Volume (m³) enclosed by the netting behind the front plane, for the whole cod-end.

    Args:
      x: (N, 3) node positions (m).
      triangles: (E, 3) int node indices of the netting triangles.
      front: abscissa s along ``axis`` (m), or a point (3,) of the front plane.
      axis: (3,) unit cod-end axis, pointing downstream.
      symmetry: copies of the modelled part in the whole cod-end (4 for a quarter model).
      sign: orientation, scalar or (E,): +1 where 12 ^ 13 points out of the cod-end.
    """
    s = catch_pressure_term.front_abscissa(front, axis)
    return symmetry * _element_sums(x, triangles, s, axis, sign)[0]


def front_area(x, triangles, front, axis, symmetry=1.0, sign=1.0):
    """Area (m²) of the catch's cross-section on the front plane, for the whole cod-end (= -dV/ds)."""
    s = catch_pressure_term.front_abscissa(front, axis)
    return symmetry * _element_sums(x, triangles, s, axis, sign)[1]


def catch_forces(x, triangles, pressure, front, axis, sign=1.0):
    """Nodal catch-pressure forces (N, 3) in N on the modelled netting (assembled without dense matrix)."""
    xe = x[triangles]
    sign = jnp.broadcast_to(jnp.asarray(sign, dtype=x.dtype), triangles.shape[:1])
    f = jax.vmap(catch_pressure_term.catch_pressure, in_axes=(0, None, None, None, 0))(xe, pressure, front, axis, sign)
    return jnp.zeros_like(x).at[triangles.reshape(-1)].add(f.reshape(-1, 3))


class CatchFront(NamedTuple):
    """Result of :func:`catch_front`.

    position: front abscissa s (m) along the axis; the front plane is {y : y·axis = s}, its point s·axis.
    volume: enclosed volume at that position (m³, whole cod-end).
    holds: False when the net cannot hold the requested volume (then position = s_min, the most upstream
      netting node, and volume < the requested one).
    converged: the iteration met its tolerance (|V - volume| <= rtol · volume, or a bracket narrower than
      rtol times the net's length) within max_iter steps.
    passes: the passes over the elements the search took (one volume and section each): 2 (the most upstream
      node's plane, the start) plus its Newton or bisection steps.
    """

    position: jax.Array
    volume: jax.Array
    holds: jax.Array
    converged: jax.Array
    passes: jax.Array


def _extent(x, triangles, axis, members):
    """(s_min, s_max): the abscissae along ``axis`` of the most upstream and the rearmost vertex of the triangles
    (of the ``members`` among them, (E,) bool, when not None)."""
    abscissae = x[triangles] @ axis
    if members is None:
        return jnp.min(abscissae), jnp.max(abscissae)
    inside = members[:, None]
    return jnp.min(jnp.where(inside, abscissae, jnp.inf)), jnp.max(jnp.where(inside, abscissae, -jnp.inf))


def _solve_front(x, triangles, axis, volume, symmetry, sign, guess, rtol, max_iter, members=None):
    """Newton on V(s) = volume, safeguarded by bisection. Returns (s, V(s), holds, converged, passes).

    One loop, one pass over the elements per step: the first at s_min (does the net hold the volume at
    all?), the second at the start, then up to ``max_iter`` Newton or bisection steps while the net holds
    it. So the program holds the element sums once, not three times (the front is a large part of a catch
    solve's compilation). ``members``: (E,) bool, the triangles that hold this catch (their ``sign`` is that
    of the others times 0), or None for all."""
    s_min, s_max = _extent(x, triangles, axis, members)

    def volume_and_slope(s):
        v, section = _element_sums(x, triangles, s, axis, sign)
        return symmetry * v, symmetry * section  # V(s), -dV/ds

    tol_v = rtol * jnp.abs(volume)
    tol_s = rtol * (s_max - s_min)
    s0 = jnp.where((guess > s_min) & (guess < s_max), guess, 0.5 * (s_min + s_max))

    def holds_of(v_min):
        return v_min >= volume - tol_v

    def fine(lo, hi, v):
        return (jnp.abs(v - volume) <= tol_v) | (hi - lo <= tol_s)

    def running(state):
        lo, hi, s, v, a, v_min, it = state
        searching = holds_of(v_min) & (volume > 0.0) & ~fine(lo, hi, v) & (it < max_iter + 2)
        return (it < 2) | searching

    def step(state):
        lo, hi, s, v, a, v_min, it = state
        # from the start on, keep V(lo) >= volume >= V(hi)
        newton_phase = it >= 2
        lo = jnp.where(newton_phase & (v > volume), s, lo)
        hi = jnp.where(newton_phase & (v <= volume), s, hi)
        newton = s + (v - volume) / jnp.where(a > 0.0, a, 1.0)
        inside = (a > 0.0) & (newton > lo) & (newton < hi)
        s = jnp.where(it == 0, s_min, jnp.where(it == 1, s0, jnp.where(inside, newton, 0.5 * (lo + hi))))
        v, a = volume_and_slope(s)
        return lo, hi, s, v, a, jnp.where(it == 0, v, v_min), it + 1

    zero = jnp.zeros_like(s_min)
    lo, hi, s, v, a, v_min, it = jax.lax.while_loop(
        running, step, (s_min, s_max, s_min, zero, zero, zero, jnp.zeros((), jnp.int32)))
    holds = holds_of(v_min)
    converged = fine(lo, hi, v)
    s = jnp.where(volume <= 0.0, s_max, jnp.where(holds, s, s_min))
    v = jnp.where(volume <= 0.0, 0.0, jnp.where(holds, v, v_min))
    converged = jnp.where(holds & (volume > 0.0), converged, True)
    return s, v, holds, converged, it


@jax.custom_jvp
def _implicit_front(x, triangles, axis, volume, symmetry, sign, solved, holds, members):
    """The solved front abscissa, differentiated by the implicit function theorem (not through the loop).
    ``members``: (E,) bool, the triangles holding the catch (all of them: an array of True)."""
    return solved


@_implicit_front.defjvp
def _implicit_front_jvp(primals, tangents):
    x, triangles, axis, volume, symmetry, sign, solved, holds, members = primals
    dx, _, daxis, dvolume, dsymmetry, _, _, _, _ = tangents
    _, d_min = jax.jvp(lambda x_, a_: _extent(x_, triangles, a_, members)[0], (x, axis), (dx, daxis))
    _, d_max = jax.jvp(lambda x_, a_: _extent(x_, triangles, a_, members)[1], (x, axis), (dx, daxis))
    # symmetry V(x, axis, s) = volume with dV/ds = -symmetry section: ds = (dV|_s - dvolume) / (symmetry section)
    (v, section), (dv, _) = jax.jvp(lambda x_, a_: _element_sums(x_, triangles, solved, a_, sign), (x, axis),
                                    (dx, daxis))
    slope = symmetry * section
    ds = (symmetry * dv + dsymmetry * v - dvolume) / jnp.where(slope > 0.0, slope, 1.0)
    ds = jnp.where(slope > 0.0, ds, 0.0)
    ds = jnp.where(volume <= 0.0, d_max, jnp.where(holds, ds, d_min))
    return solved, ds


def catch_front(x, triangles, axis, volume, symmetry=1.0, sign=1.0, guess=None, rtol=1e-10, max_iter=100,
                members=None):
    """Front abscissa s (m) such that the netting behind the plane {y·axis = s} encloses ``volume``.

    Args:
      x: (N, 3) node positions (m); triangles: (E, 3) int netting triangles.
      axis: (3,) unit cod-end axis, pointing downstream.
      volume: catch volume (m³) of the whole cod-end.
      symmetry: copies of the modelled part in the whole cod-end (4 for a quarter model).
      sign: orientation (scalar or (E,)), as in :func:`enclosed_volume`.
      guess: a starting abscissa (m), e.g. the previous front; ignored when outside the net.
      rtol: relative tolerance on the volume (and on the bracket, relative to the net's length).
      max_iter: most Newton/bisection steps.
      members: (E,) bool, the triangles that hold the catch (the others count neither in its volume nor in
        its extent), or None for all of them.
    Returns:
      :class:`CatchFront` (position, volume, holds, converged). ``position`` is differentiable in x, axis,
      volume and symmetry (implicit function theorem, not through the iteration).
    """
    x = jnp.asarray(x)
    axis = jnp.asarray(axis, dtype=x.dtype)
    triangles = jnp.asarray(triangles)
    volume = jnp.asarray(volume, dtype=x.dtype)
    symmetry = jnp.asarray(symmetry, dtype=x.dtype)
    sign = jnp.asarray(sign, dtype=x.dtype)
    guess = jnp.asarray(jnp.nan if guess is None else guess, dtype=x.dtype)
    if members is not None:
        members = jnp.asarray(members, dtype=bool)
        sign = jnp.where(members, jnp.broadcast_to(sign, members.shape), 0.0)
    solved, _, holds, converged, passes = jax.lax.stop_gradient(
        _solve_front(x, triangles, axis, volume, symmetry, sign, guess, rtol, max_iter, members))
    every = jnp.ones(triangles.shape[:1], dtype=bool) if members is None else members
    s = _implicit_front(x, triangles, axis, volume, symmetry, sign, solved, holds, every)
    v = symmetry * _element_sums(x, triangles, s, axis, sign)[0]
    return CatchFront(s, v, holds, converged, passes)


class CatchSummary(NamedTuple):
    """What FEMNET prints about the catch (whole cod-end values, see :func:`catch_summary`).

    volume (m³), front_area (m²), drag (N, along the axis), thickness (m), diameter (m).
    """

    volume: jax.Array
    front_area: jax.Array
    drag: jax.Array
    thickness: jax.Array
    diameter: jax.Array


def transverse_directions(axis, up=(0.0, 0.0, 1.0)):
    """Two unit vectors (2, 3) normal to ``axis``: e1 = up ^ axis normalised (horizontal when up is the
    vertical) and e2 = axis ^ e1; for an axis along x and up along z they are y and z, FEMNET's axes."""
    axis = jnp.asarray(axis)
    up = jnp.asarray(up, dtype=axis.dtype)
    e1 = jnp.cross(up, axis)
    # an axis along up: any horizontal direction will do
    fallback = jnp.cross(jnp.array([1.0, 0.0, 0.0], dtype=axis.dtype), axis)
    fallback = jnp.where(geometry.safe_norm(fallback) > 1e-6, fallback, jnp.cross(jnp.array([0.0, 1.0, 0.0]), axis))
    e1 = jnp.where(geometry.safe_norm(e1) > 1e-9, e1, fallback)
    e1 = e1 / geometry.safe_norm(e1)
    return jnp.stack([e1, jnp.cross(axis, e1)])


def catch_summary(x, triangles, axis, front, pressure=0.0, symmetry=1.0, sign=1.0, center=None,
                  up=(0.0, 0.0, 1.0)):
    """Catch volume, front area, drag, thickness and diameter, as FEMNET reports them.

    Args:
      x, triangles, axis, symmetry, sign: as in :func:`enclosed_volume`.
      front: front abscissa s (m) or a point (3,) of the front plane (e.g. ``catch_front(...).position``).
      pressure: catch pressure p (Pa), ``jaxnet.terms.pressure.dynamic_pressure(rho, Cd, v)`` (4.246).
      center: a point (3,) of the cod-end axis line (for quarter and half models: on both symmetry
        planes), from which half-widths are measured; None: half the extent of the nodes behind the front.
      up: the vertical, to name the two transverse directions (:func:`transverse_directions`).
    Returns:
      :class:`CatchSummary`: volume (m³) and front_area (m²) of the whole cod-end (× symmetry); drag =
      pressure × front_area (N), the axial component of the catch forces; thickness = rearmost netting
      node abscissa - s (m); diameter (m) = 2 × the largest half-width, along either transverse
      direction, of the netting nodes on or behind the front (FEMNET's "maximal catch diameter"; 0 when
      no node is behind). FEMNET prints volume and drag of the modelled part: use symmetry=1 to compare.
    """
    x = jnp.asarray(x)
    axis = jnp.asarray(axis, dtype=x.dtype)
    triangles = jnp.asarray(triangles)
    s = catch_pressure_term.front_abscissa(front, axis)
    v, section = _element_sums(x, triangles, s, axis, sign)
    volume, area = symmetry * v, symmetry * section

    netting = jnp.zeros(x.shape[0], dtype=bool).at[triangles.reshape(-1)].set(True)
    abscissa = x @ axis
    thickness = jnp.max(jnp.where(netting, abscissa, -jnp.inf)) - s
    behind = netting & (abscissa >= s)
    any_behind = jnp.any(behind)
    e = transverse_directions(axis, up)
    if center is None:
        t = x @ e.T  # (N, 2)
        hi = jnp.max(jnp.where(behind[:, None], t, -jnp.inf), axis=0)
        lo = jnp.min(jnp.where(behind[:, None], t, jnp.inf), axis=0)
        half_width = 0.5 * (jnp.where(any_behind, hi, 0.0) - jnp.where(any_behind, lo, 0.0))
        radius = jnp.max(half_width)
    else:
        t = jnp.abs((x - jnp.asarray(center, dtype=x.dtype)) @ e.T)
        radius = jnp.max(jnp.where(behind[:, None], t, 0.0))
    return CatchSummary(volume, area, pressure * area, thickness, 2.0 * radius)


def catch_state(x, scene, previous=None):
    """The catch front for positions x (N, 3): ``{"front": abscissa along the axis (m), "pressure": ½ ρ Cd v²
    (Pa), "axis": the cod-end's axis, "specific_weight": ρ_c g of a gravity catch (N/m³, 0 for a catch in a
    current)}``, or None without a catch. The state of the catch pressure, of the gravity catch
    (:mod:`jaxnet.terms.gravity_catch`) and of the netting drag (the netting behind the front is shielded): one
    function, so that the front is solved for once per evaluation. ``previous``: this state at the solver's last
    iterate, whose front starts the search (the front moves little from one iterate to the next)."""
    c, env = scene.catch, scene.environment
    if c is None:
        return None
    guess = None if previous is None else previous["front"]
    front = catch_front(x, scene.netting.vertices, c.axis, c.volume, c.symmetry, sign=scene.netting.outward, guess=guess)
    p = catch_pressure_term.dynamic_pressure(env.water_density, c.drag_coefficient, env.current_speed)
    return {"front": front.position, "pressure": p, "axis": c.axis,
            "specific_weight": jnp.asarray(c.density, dtype=x.dtype) * env.gravity}


def panel_catch_state(x, scene, previous=None):
    """The fronts of the scene's panel catches (:class:`jaxnet.scene.PanelCatches`) for positions x (N, 3):
    ``{"fronts": (K,) abscissae along the axis (m), "pressure": ½ ρ Cd v² (Pa), "axis": (3,), "catch_of_panel":
    (P,) int}``, or None without them. Each front is :func:`catch_front` on the triangles of its own panels
    only (their volume, their extent), as FEMNET's ``catch2_volume.c`` places each; the K searches run side by
    side (one batched loop). ``previous``: this state at the solver's last iterate, whose fronts start the
    searches."""
    pc, env = scene.panel_catches, scene.environment
    if pc is None:
        return None
    catch_of_panel = jnp.asarray(pc.panel_catch)
    holder = catch_of_panel[jnp.asarray(scene.netting.panel)]  # (E,) the catch each triangle holds, -1 none
    volume = jnp.asarray(pc.volume, dtype=x.dtype)
    guess = jnp.full(volume.shape, jnp.nan, dtype=x.dtype) if previous is None else previous["fronts"]

    def front(k, volume_k, guess_k):
        return catch_front(x, scene.netting.vertices, pc.axis, volume_k, pc.symmetry, sign=scene.netting.outward,
                           guess=guess_k, members=holder == k).position

    fronts = jax.vmap(front)(jnp.arange(volume.shape[0]), volume, guess)
    p = catch_pressure_term.dynamic_pressure(env.water_density, pc.drag_coefficient, env.current_speed)
    return {"fronts": fronts, "pressure": p, "axis": jnp.asarray(pc.axis, dtype=x.dtype),
            "catch_of_panel": catch_of_panel}
