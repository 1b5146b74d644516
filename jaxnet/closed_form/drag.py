"""Closed-form stiffness of hydrodynamic drag (book section 4.3.3, eqs 4.136-4.210, corrected).

K = -∂F/∂x (4.46) of the drag forces of :mod:`jaxnet.terms.drag`, written without autodiff. Drag is not
conservative: K is not symmetric.

The book's derivation and the compact form used here. The book differentiates the normal drag of the U
twines as F = |F| E/|E| with E = U ^ (c ^ U) (4.136-4.145), |F| ∝ sin²α (4.154-4.155) and α' from
4.156-4.160, with U' and |U|' per vertex coordinate (4.161-4.186) giving ∂α/∂x_i (4.187-4.195); the
tangential drag likewise as T = |T| cos α U/(|cos α| |U|) (4.196-4.208) with |T| ∝ cos²α (4.209-4.210).
Since E = |U|² c_n, |c_n| = |c| sin α and c_t = (c.û) û (û = U/|U|), these forces are exactly

    F = K_n |c_n| c_n,    T = K_t |c_t| c_t,    K_n = ½ ρ Cn D l0,  K_t = ½ ρ Ct D l0 (one twine),

and the product rule the book applies to |F| and E/|E| (the sin α α' of 4.155 and the 1/sin α of 4.156,
which cancel) is, once collected, the derivative of g(v) = |v| v,

    ∂g/∂v = |v| I + v v^T/|v|            (0 at v = 0: |v| v is C¹ with zero derivative there),

times the derivative of the split c -> (c_n, c_t) with respect to the twine vector W (U or V, ê = W/|W|):

    ∂c_t/∂W = [ê c_n^T + (c.ê)(I - ê ê^T)] / |W| = -∂c_n/∂W,     ∂c_t/∂c = ê ê^T,  ∂c_n/∂c = I - ê ê^T.

(The first is the book's (U/|U|)' of 4.158 seen from c: the book's α' of 4.160 is -ĉ.(∂û/∂W)/sin α.)
So one twine has, with G_n = ∂g/∂v at c_n and G_t at c_t (:func:`twine_drag_jacobians`),

    ∂(F + T)/∂W = (K_t G_t - K_n G_n) ∂c_t/∂W,     ∂(F + T)/∂c = K_n G_n (I - ê ê^T) + K_t G_t ê ê^T.

The chain rule to the vertices is that of 4.162-4.176 (U = Σ a_i x_i, V = Σ b_i x_i,
:func:`jaxnet.geometry.twine_coefficients`), the drag being spread one third per vertex; the count of
twines is |d|/2 (the printed d/2 of 4.114-4.115, 4.154-4.155 and 4.209-4.210 has the wrong sign for
clockwise triangles, see ``/work/exp5/errata_drag.md``).

Depth-varying current. The book takes c constant (4.157: only U varies). jaxnet's solver evaluates the
current at the element's centroid z = up . (Σ x_i)/k inside the differentiated function, so the tangent
also holds ∂F/∂c · dc/dz · up^T / k on every vertex column (k = 3 vertices of a triangle, 2 ends of a
bar, 1 node). ``velocity_slope`` is that dc/dz (m/s per m) at the centroid (:func:`current_slope`);
``None`` (a uniform current) leaves the term out, which is the book's stiffness.

Singular points, all returned as the autodiff path's ``jax.jacfwd`` gives them (no NaN, no inf):

* water along a twine (c_n = 0), across it (c_t = 0), still water (both 0): the book's 1/sin α, 1/|cos α|
  and 1/|E| are 0/0 there; the derivative of |v| v at v = 0 is 0, so the vanishing part contributes
  nothing (``jaxnet.geometry.safe_norm`` treats |v|² <= 1e-300 as 0, and so does this module).
* a collapsed twine (zero axis): ``twine_drag`` then takes all of c as normal with no dependence on the
  axis (its double ``where``), so ∂/∂W = 0 and ∂/∂c = K_n G(c).
* FEMNET's catch variant: its unit vectors across the flow are set to 0 where they have no direction
  (twine along c; the same relative threshold as :mod:`jaxnet.terms.drag`), and with them their
  derivatives; 1/|c|² is 0 in still water with zero derivative.

Units: positions and lengths in m, velocities in m/s, density kg/m³; stiffness in N/m, velocity
Jacobians in N·s/m.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry

_EYE = jnp.eye(3)


def _inverse(value):
    """1/value where value > 0, else 0 (the autodiff path's double ``where``), elementwise."""
    has = value > 0.0
    return jnp.where(has, 1.0 / jnp.where(has, value, 1.0), 0.0)


def _abs_times_jacobian(v):
    """(3, 3) ∂(|v| v)/∂v = |v| I + v v^T/|v|; 0 at v = 0 (|v| by ``safe_norm``, as the force uses)."""
    length = geometry.safe_norm(v)
    return length * _EYE + jnp.outer(v, v) * _inverse(length)


def _split(axis, water_velocity):
    """Split of the water velocity along and across the axis W, as :func:`jaxnet.terms.drag.twine_drag`
    computes it: (c_t, c_n, ∂c_t/∂W, ∂c_t/∂c), the last two (3, 3). A zero axis gives c_t = 0 with zero
    derivatives (the force's double ``where`` on 1/|W|²)."""
    c = water_velocity
    sq = jnp.dot(axis, axis)
    inv_sq = _inverse(sq)
    along = jnp.dot(c, axis)
    c_t = (along * inv_sq) * axis
    c_n = c - c_t
    # ∂c_t/∂W = [W c^T + (c.W) I]/|W|² - 2 (c.W) W W^T/|W|⁴ (= [ê c_n^T + (c.ê)(I - ê ê^T)]/|W|)
    dct_daxis = (jnp.outer(axis, c) + along * _EYE) * inv_sq - (2.0 * along * inv_sq * inv_sq) * jnp.outer(axis, axis)
    dct_dc = jnp.outer(axis, axis) * inv_sq
    return c_t, c_n, dct_daxis, dct_dc


def twine_drag_jacobians(axis, length, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Derivatives of the whole drag (normal + tangential) of one cylinder, :func:`jaxnet.terms.drag.twine_drag`.

    The book's 4.136-4.210 in compact form (module docstring): with g(v) = |v| v,
    ∂/∂W = (K_t G_t - K_n G_n) ∂c_t/∂W and ∂/∂c = K_n G_n (I - ê ê^T) + K_t G_t ê ê^T.

    Args: as :func:`jaxnet.terms.drag.twine_drag`: axis (3,) m (only its direction matters), length m
      (the unstretched L of the area D L), diameter m, cd_normal and cd_tangential dimensionless,
      water_velocity (3,) m/s (relative to the cylinder), water_density kg/m³.
    Returns:
      (j_axis, j_velocity): (3, 3) ∂F/∂axis in N/m and ∂F/∂water_velocity in N·s/m (row: force
      component, column: axis or velocity component). Both finite everywhere; j_axis = 0 for a zero axis.
    """
    c_t, c_n, dct_daxis, dct_dc = _split(axis, water_velocity)
    k = 0.5 * water_density * diameter * length
    normal = (k * cd_normal) * _abs_times_jacobian(c_n)
    tangential = (k * cd_tangential) * _abs_times_jacobian(c_t)
    j_axis = (tangential - normal) @ dct_daxis
    j_velocity = normal @ (_EYE - dct_dc) + tangential @ dct_dc
    return j_axis, j_velocity


def _vertical(velocity_slope, up):
    """dc/dz up^T as a (3, 3) ∂c/∂(centroid) (0 for a uniform current); up defaults to +z."""
    if velocity_slope is None:
        return jnp.zeros((3, 3))
    up = jnp.array([0.0, 0.0, 1.0]) if up is None else jnp.asarray(up, dtype=float)
    return jnp.outer(jnp.asarray(velocity_slope, dtype=float), up)


def _spread_stiffness(coefficients, jacobians, j_velocity, dc_dcentroid, vertices):
    """(3 v, 3 k) K = -∂F/∂x of an element force spread equally on its ``vertices`` (v) from the element
    total's Jacobians: Σ_p coefficients[p][j] jacobians[p] (twine vectors W_p = Σ_j coefficients[p][j] x_j)
    plus j_velocity ∂c/∂centroid / k (the current taken at the centroid of the k positions)."""
    k = coefficients[0].shape[0]
    blocks = sum(w[:, None, None] * j[None, :, :] for w, j in zip(coefficients, jacobians))  # (k, 3, 3)
    blocks = blocks + (j_velocity @ dc_dcentroid)[None, :, :] / k
    # every vertex gets 1/vertices of the total: the same row block for each
    per_vertex = -jnp.transpose(blocks, (1, 0, 2)) / vertices  # (3 force comps, k, 3 coords)
    return jnp.broadcast_to(per_vertex[None], (vertices, 3, k, 3)).reshape(3 * vertices, 3 * k)


def _twine_parts(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """What both netting drag stiffnesses start from: the coefficients a, b (U = a @ x, V = b @ x), U, V,
    the twine count |d|/2, the twine arguments, and each family's :func:`twine_drag_jacobians`."""
    a, b, d = geometry.twine_coefficients(uv)
    U, V = a @ x, b @ x
    args = (l0, diameter, cd_normal, cd_tangential, water_velocity, water_density)
    return a, b, U, V, geometry.twine_count(d), args, twine_drag_jacobians(U, *args), twine_drag_jacobians(V, *args)


def netting_drag_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density,
                           velocity_slope=None, up=None):
    """(9, 9) drag stiffness K = -∂F/∂x (N/m) of one diamond-mesh triangle, :func:`jaxnet.terms.drag.netting_drag`
    (book 4.136-4.210 for the U and V twines, corrected: |d|/2 twines, no 1/sin α, 1/|cos α| singularity).

    Args:
      x: (3, 3) vertex positions (m); uv: (3, 2) twine coordinates (d may be negative).
      l0, diameter: unstretched twine length and diameter (m); cd_normal, cd_tangential: dimensionless.
      water_velocity: (3,) water velocity relative to the netting (m/s), at the element's centroid.
      water_density: ρ (kg/m³).
      velocity_slope: None for a uniform current (the book's 4.157: c constant); else (3,) dc/dz (m/s per m)
        of the current at the centroid, z = centroid . up (:func:`current_slope`), which adds the term of
        the current moving with the element's height.
      up: (3,) unit vertical along which z is measured; None is (0, 0, 1). Only used with velocity_slope.
    Vertex-major layout (entry (3 i + m, 3 j + n): coordinate m of vertex i, n of vertex j).
    """
    a, b, _, _, count, _, (ju_axis, ju_c), (jv_axis, jv_c) = _twine_parts(x, uv, l0, diameter, cd_normal,
                                                                         cd_tangential, water_velocity,
                                                                         water_density)
    return _spread_stiffness((a, b), (count * ju_axis, count * jv_axis), count * (ju_c + jv_c),
                             _vertical(velocity_slope, up), 3)


def _twine_force(axis, length, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """(normal, tangential) drag of one cylinder (N), as :func:`jaxnet.terms.drag.twine_drag` (the value the
    catch variant's derivative needs)."""
    c_t, c_n, _, _ = _split(axis, water_velocity)
    k = 0.5 * water_density * diameter * length
    return (k * cd_normal * geometry.safe_norm(c_n)) * c_n, (k * cd_tangential * geometry.safe_norm(c_t)) * c_t


def _unit_across_jacobians(axis, water_velocity, inv_c2):
    """ê (3,) of :func:`jaxnet.terms.drag._unit_across` and its derivatives (3, 3) with respect to the axis
    and to the water velocity: ∂ê = (I - ê ê^T)/|a| ∂a, a = W - (W.c) c/|c|²; all 0 where ê is set to 0."""
    c = water_velocity
    along = jnp.dot(axis, c)
    across = axis - (along * inv_c2) * c
    sq = jnp.dot(across, across)
    has = sq > 1e-24 * jnp.dot(axis, axis)
    inv_length = jnp.where(has, 1.0 / jnp.sqrt(jnp.where(has, sq, 1.0)), 0.0)
    e = across * inv_length
    project = (_EYE - jnp.outer(e, e)) * inv_length
    da_daxis = _EYE - jnp.outer(c, c) * inv_c2
    # d(1/|c|²)/dc = -2 c/|c|⁴ (0 in still water, where 1/|c|² is the constant 0)
    da_dc = -inv_c2 * (along * _EYE + jnp.outer(c, axis)) + (2.0 * along * inv_c2 * inv_c2) * jnp.outer(c, c)
    return e, project @ da_daxis, project @ da_dc


def netting_drag_femnet_catch_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity,
                                        water_density, velocity_slope=None, up=None):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of FEMNET's netting drag ahead of a catch,
    :func:`jaxnet.terms.drag.netting_drag_femnet_catch`: F = (|d|/2)[F_V + (F_U.ĉ) ĉ + (F_U.ê_U) ê_V] / 3.

    Differentiated term by term: ∂(P F_U) with P = c c^T/|c|², ∂(F_U.ê_U) ê_V and (F_U.ê_U) ∂ê_V, with
    ∂ê the derivative of a unit vector across the flow (module docstring for its singular set).

    Args: as :func:`netting_drag_stiffness` (same units, same ``velocity_slope`` and ``up``).
    """
    a, b, U, V, count, args, (ju_axis, ju_c), (jv_axis, jv_c) = _twine_parts(x, uv, l0, diameter, cd_normal,
                                                                             cd_tangential, water_velocity,
                                                                             water_density)
    normal_u, tangential_u = _twine_force(U, *args)
    force_u = count * (normal_u + tangential_u)
    c = water_velocity
    inv_c2 = _inverse(jnp.dot(c, c))
    in_line = jnp.outer(c, c) * inv_c2
    e_u, de_u_daxis, de_u_dc = _unit_across_jacobians(U, c, inv_c2)
    e_v, de_v_daxis, de_v_dc = _unit_across_jacobians(V, c, inv_c2)
    across_u = jnp.dot(force_u, e_u)
    # F_U reaches the total through P F_U + (F_U.ê_U) ê_V: a linear map of F_U
    carry_u = in_line + jnp.outer(e_v, e_u)
    along_c = jnp.dot(force_u, c)
    d_in_line_dc = inv_c2 * (jnp.outer(c, force_u) + along_c * _EYE) - (2.0 * along_c * inv_c2 * inv_c2) * jnp.outer(c, c)
    j_u = carry_u @ (count * ju_axis) + jnp.outer(e_v, force_u @ de_u_daxis)
    j_v = count * jv_axis + across_u * de_v_daxis
    j_c = (count * jv_c + d_in_line_dc + carry_u @ (count * ju_c)
           + jnp.outer(e_v, force_u @ de_u_dc) + across_u * de_v_dc)
    return _spread_stiffness((a, b), (j_u, j_v), j_c, _vertical(velocity_slope, up), 3)


def bar_drag_stiffness(x, rest_length, diameter, cd_normal, cd_tangential, water_velocity, water_density,
                       velocity_slope=None, up=None):
    """(6, 6) drag stiffness K = -∂F/∂x (N/m) of one cable bar, :func:`jaxnet.terms.drag.bar_drag` (half the
    bar's drag on each end; the bar's vector is x1 - x0).

    Args:
      x: (2, 3) end positions (m); rest_length, diameter: m; cd_normal, cd_tangential: dimensionless;
      water_velocity: (3,) m/s at the bar's midpoint; water_density: kg/m³;
      velocity_slope, up: as :func:`netting_drag_stiffness` (dc/dz at the midpoint, m/s per m; vertical).
    """
    j_axis, j_c = twine_drag_jacobians(x[1] - x[0], rest_length, diameter, cd_normal, cd_tangential,
                                       water_velocity, water_density)
    ends = jnp.array([-1.0, 1.0])
    return _spread_stiffness((ends,), (j_axis,), j_c, _vertical(velocity_slope, up), 2)


def node_drag_stiffness(drag_area, water_velocity, water_density, velocity_slope, up=None):
    """(3, 3) stiffness K = -∂F/∂x (N/m) of the drag ½ ρ (Cd A) |c| c on a body at a node,
    :func:`jaxnet.terms.drag.node_drag`, with the current taken at the node's height z = x . up:
    K = -½ ρ (Cd A) (|c| I + c c^T/|c|) dc/dz up^T (0 in still water and in a uniform current).

    Args:
      drag_area: Cd·A (m²); water_velocity: (3,) m/s at the node; water_density: kg/m³;
      velocity_slope: (3,) dc/dz at the node (m/s per m), or None (uniform current: K = 0);
      up: (3,) unit vertical, None for (0, 0, 1).
    """
    j_c = (0.5 * water_density * drag_area) * _abs_times_jacobian(water_velocity)
    return _spread_stiffness((jnp.zeros(1),), (jnp.zeros((3, 3)),), j_c, _vertical(velocity_slope, up), 1)


def current_slope(z, speed, direction, profile_depth, profile_factor, surface_level=0.0):
    """dc/dz (m/s per m) of :func:`jaxnet.current.current_velocity` at height ``z`` (m).

    c(z) = speed f(s - z) ĉ with f piecewise linear in depth, so dc/dz = -speed f'(depth) ĉ: the slope of
    the segment the point is on (the same segment ``searchsorted`` picks: at an interior profile point the
    deeper one), 0 strictly beyond the first and last points (where the factor is constant; at those points
    themselves the adjoining segment's slope, as the clamp by ``where`` gives), 0 with fewer than 2 points.

    Args: as :func:`jaxnet.current.current_velocity` (speed m/s, direction (3,) any length, profile_depth
      (P,) m strictly increasing, profile_factor (P,), surface_level m; NaN means 0).
    Returns:
      (3,) dc/dz; (..., 3) if z is an array.
    """
    direction = jnp.asarray(direction, dtype=float)
    unit = direction * _inverse(geometry.safe_norm(direction))
    profile_depth = jnp.asarray(profile_depth, dtype=float)
    profile_factor = jnp.asarray(profile_factor, dtype=float)
    surface_level = jnp.asarray(surface_level, dtype=float)
    surface_level = jnp.where(jnp.isnan(surface_level), 0.0, surface_level)
    depth = surface_level - jnp.asarray(z, dtype=float)
    points = profile_depth.shape[0]  # static
    if points < 2:
        slope = jnp.zeros_like(depth)
    else:
        first, last = profile_depth[0], profile_depth[-1]
        inside = (depth >= first) & (depth <= last)
        clamped = jnp.where(depth < first, first, jnp.where(depth > last, last, depth))
        segment = jnp.clip(jnp.searchsorted(profile_depth, clamped, side="right") - 1, 0, points - 2)
        rise = profile_factor[segment + 1] - profile_factor[segment]
        run = profile_depth[segment + 1] - profile_depth[segment]
        slope = jnp.where(inside, rise / run, 0.0)
    # depth = s - z: d/dz = -d/d(depth)
    return (-speed * slope)[..., None] * unit
