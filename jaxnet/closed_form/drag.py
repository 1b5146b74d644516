"""Closed-form stiffness of hydrodynamic drag (book section 4.3.3, eqs 4.136-4.210, corrected; a moving net:
4.272-4.276, whose stiffness the book does not give).

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

A moving net (an implicit time step, 4.266 and 4.272-4.276). Vertex i of an element takes its share of the
element's drag computed with the water's velocity relative to it, c_i = w(x_i) - v_i, w the current at the
vertex's depth plus the waves' orbital velocity, v_i = (x_i - x_i^n)/Δt (:func:`jaxnet.terms.drag.per_vertex`).
Row block i of K = -∂F/∂x then holds the same twine terms as above taken at c_i, and on its diagonal block
∂F/∂c (∂w/∂x(x_i) - I/Δt): the water's velocity varying over the vertex's position (current profile,
:meth:`jaxnet.water.waves.Airy.velocity_gradient`) and the damping of the vertex's own velocity
(:func:`moving_netting_drag_stiffness`, :func:`moving_bar_drag_stiffness`, :func:`moving_node_drag_stiffness`).
Why a closed form: the autodiff path differentiates the element's drag once per vertex (``jax.jacfwd`` of a
k-fold ``vmap``), most of a time step's tangent; the closed form takes about half of it
(``benchmarks/dynamics.py`` times both). The helpers work on stacks (leading axes), so one call takes both
twine families at the three vertices' velocities. The book's dynamic stiffness is the inertia's alone (4.271),
its 4.272-4.276 give the force only: without the drag's damping -(1/Δt) ∂F/∂c Newton needs tens of times more
iterations per step on a net in waves, and most steps are retried at half the step.

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


def _identity():
    """The 3x3 identity, made where it is used: a module-level jnp constant would start JAX's backend when
    the package is imported (a delay, and before a user could choose the platform)."""
    return jnp.eye(3)

# The helpers below work on stacks of vectors and matrices (leading axes "..."): one call computes the
# Jacobians of both twine families at the relative velocities of all three vertices of a moving element (6
# twine drags) in one set of operations: on a small net XLA's cost is per operation more than per element.


def _dot(u, v):
    """u . v over the last axis, (...)."""
    return jnp.sum(u * v, axis=-1)


def _outer(u, v):
    """u v^T over the last axis, (..., 3, 3)."""
    return u[..., :, None] * v[..., None, :]


def _matrices(s):
    """A stack of scalars (...) as (..., 1, 1), to scale a stack of matrices."""
    return jnp.asarray(s)[..., None, None]


def _inverse(value):
    """1/value where value > 0, else 0 (the autodiff path's double ``where``), elementwise."""
    has = value > 0.0
    return jnp.where(has, 1.0 / jnp.where(has, value, 1.0), 0.0)


def _abs_times_jacobian(v):
    """(..., 3, 3) ∂(|v| v)/∂v = |v| I + v v^T/|v|; 0 at v = 0 (|v| by ``safe_norm``, as the force uses)."""
    length = geometry.safe_norm(v)
    return _matrices(length) * _identity() + _outer(v, v) * _matrices(_inverse(length))


def _split(axis, water_velocity):
    """Split of the water velocity along and across the axis W, as :func:`jaxnet.terms.drag.twine_drag`
    computes it: (c_t, c_n, ∂c_t/∂W, ∂c_t/∂c), the last two (..., 3, 3). A zero axis gives c_t = 0 with zero
    derivatives (the force's double ``where`` on 1/|W|²)."""
    c = water_velocity
    inv_sq = _inverse(_dot(axis, axis))
    along = _dot(c, axis)
    c_t = (along * inv_sq)[..., None] * axis
    c_n = c - c_t
    # ∂c_t/∂W = [W c^T + (c.W) I]/|W|² - 2 (c.W) W W^T/|W|⁴ (= [ê c_n^T + (c.ê)(I - ê ê^T)]/|W|)
    dct_daxis = ((_outer(axis, c) + _matrices(along) * _identity()) * _matrices(inv_sq)
                 - _matrices(2.0 * along * inv_sq * inv_sq) * _outer(axis, axis))
    dct_dc = _outer(axis, axis) * _matrices(inv_sq)
    return c_t, c_n, dct_daxis, dct_dc


def twine_drag_jacobians(axis, length, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Derivatives of the whole drag (normal + tangential) of one cylinder, :func:`jaxnet.terms.drag.twine_drag`.

    The book's 4.136-4.210 in compact form (module docstring): with g(v) = |v| v,
    ∂/∂W = (K_t G_t - K_n G_n) ∂c_t/∂W and ∂/∂c = K_n G_n (I - ê ê^T) + K_t G_t ê ê^T.

    Args: as :func:`jaxnet.terms.drag.twine_drag`: axis (3,) m (only its direction matters), length m
      (the unstretched L of the area D L), diameter m, cd_normal and cd_tangential dimensionless,
      water_velocity (3,) m/s (relative to the cylinder), water_density kg/m³. ``axis`` and
      ``water_velocity`` may be stacks (..., 3) that broadcast against each other (several twines, several
      velocities), the coefficients scalars.
    Returns:
      (j_axis, j_velocity): (3, 3) (or (..., 3, 3)) ∂F/∂axis in N/m and ∂F/∂water_velocity in N·s/m (row:
      force component, column: axis or velocity component). Both finite everywhere; j_axis = 0 for a zero axis.
    """
    _, j_axis, j_velocity = _twine_drag_and_jacobians(axis, length, diameter, cd_normal, cd_tangential,
                                                      water_velocity, water_density)
    return j_axis, j_velocity


def _twine_drag_and_jacobians(axis, length, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """(force, j_axis, j_velocity): the whole drag (normal + tangential, N, (..., 3)) of
    :func:`jaxnet.terms.drag.twine_drag` with the derivatives of :func:`twine_drag_jacobians`, from one
    split of the velocity (the catch variant's stiffness and the shielding need the force too)."""
    c_t, c_n, dct_daxis, dct_dc = _split(axis, water_velocity)
    k = 0.5 * water_density * diameter * length
    force = ((k * cd_normal * geometry.safe_norm(c_n))[..., None] * c_n
             + (k * cd_tangential * geometry.safe_norm(c_t))[..., None] * c_t)
    normal = _matrices(k * cd_normal) * _abs_times_jacobian(c_n)
    tangential = _matrices(k * cd_tangential) * _abs_times_jacobian(c_t)
    j_axis = (tangential - normal) @ dct_daxis
    j_velocity = normal @ (_identity() - dct_dc) + tangential @ dct_dc
    return force, j_axis, j_velocity


def _vertical(velocity_slope, up):
    """dc/dz up^T as a (3, 3) ∂c/∂(centroid); None for a uniform current (no term at all, rather than
    products with zeros that XLA would compute); up defaults to +z."""
    if velocity_slope is None:
        return None
    up = jnp.array([0.0, 0.0, 1.0]) if up is None else jnp.asarray(up, dtype=float)
    return _outer(jnp.asarray(velocity_slope, dtype=float), up)


def _spread_stiffness(coefficients, jacobians, j_velocity, dc_dcentroid, vertices):
    """(3 v, 3 k) K = -∂F/∂x of an element force spread equally on its ``vertices`` (v) from the element
    total's Jacobians: Σ_p coefficients[p][j] jacobians[p] (twine vectors W_p = Σ_j coefficients[p][j] x_j)
    plus j_velocity ∂c/∂centroid / k (the current taken at the centroid of the k positions)."""
    k = coefficients[0].shape[0]
    blocks = sum(w[:, None, None] * j[None, :, :] for w, j in zip(coefficients, jacobians))  # (k, 3, 3)
    if dc_dcentroid is not None:
        blocks = blocks + (j_velocity @ dc_dcentroid)[None, :, :] / k
    # every vertex gets 1/vertices of the total: the same row block for each
    per_vertex = -jnp.transpose(blocks, (1, 0, 2)) / vertices  # (3 force comps, k, 3 coords)
    return jnp.broadcast_to(per_vertex[None], (vertices, 3, k, 3)).reshape(3 * vertices, 3 * k)


def _twine_geometry(x, uv):
    """What every netting drag stiffness starts from: the coefficients (a, b) of U = a @ x and V = b @ x
    (:func:`jaxnet.geometry.twine_coefficients`), U, V and the twine count |d|/2."""
    a, b, d = geometry.twine_coefficients(uv)
    return (a, b), a @ x, b @ x, geometry.twine_count(d)


def _both_families(U, V, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """:func:`_twine_drag_and_jacobians` of one U and one V twine in one call: ((drag, ∂/∂U, ∂/∂c of a U
    twine), (drag, ∂/∂V, ∂/∂c of a V twine)), the drags (..., 3), the derivatives (..., 3, 3), for water
    velocities (..., 3)."""
    force, j_axis, j_c = _twine_drag_and_jacobians(jnp.stack([U, V]), l0, diameter, cd_normal, cd_tangential,
                                                   water_velocity[..., None, :], water_density)
    return ((force[..., 0, :], j_axis[..., 0, :, :], j_c[..., 0, :, :]),
            (force[..., 1, :], j_axis[..., 1, :, :], j_c[..., 1, :, :]))


def _netting_jacobians(U, V, count, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """(∂F/∂U, ∂F/∂V, ∂F/∂c, F): the derivatives (..., 3, 3) of a triangle's whole twine drag F (three times
    one vertex's share of :func:`jaxnet.terms.drag.netting_drag`) and F itself (..., 3): |d|/2 U twines
    and |d|/2 V twines, each :func:`twine_drag_jacobians`, with the water velocity c (..., 3) relative to
    the netting."""
    (fu, ju_axis, ju_c), (fv, jv_axis, jv_c) = _both_families(U, V, l0, diameter, cd_normal, cd_tangential,
                                                              water_velocity, water_density)
    return count * ju_axis, count * jv_axis, count * (ju_c + jv_c), count * (fu + fv)


def netting_drag_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density,
                           velocity_slope=None, up=None, with_force=False):
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
      with_force: also return the drag itself, :func:`jaxnet.terms.drag.netting_drag`'s (3, 3) per-vertex
        forces (N), from the same intermediate values (a Python bool).
    Vertex-major layout (entry (3 i + m, 3 j + n): coordinate m of vertex i, n of vertex j).
    """
    coefficients, U, V, count = _twine_geometry(x, uv)
    j_u, j_v, j_c, total = _netting_jacobians(U, V, count, l0, diameter, cd_normal, cd_tangential, water_velocity,
                                              water_density)
    stiffness = _spread_stiffness(coefficients, (j_u, j_v), j_c, _vertical(velocity_slope, up), 3)
    return (stiffness, _per_vertex(total)) if with_force else stiffness


def _per_vertex(total):
    """A triangle's total force (3,) as the (3, 3) per-vertex forces of the drag terms: a third on each."""
    return jnp.broadcast_to(total / 3.0, (3, 3))


def _unit_across_jacobians(axis, water_velocity, inv_c2):
    """ê (..., 3) of :func:`jaxnet.terms.drag.unit_across` and its derivatives (..., 3, 3) with respect to the
    axis and to the water velocity: ∂ê = (I - ê ê^T)/|a| ∂a, a = W - (W.c) c/|c|²; all 0 where ê is set to 0."""
    c = water_velocity
    along = _dot(axis, c)
    across = axis - (along * inv_c2)[..., None] * c
    sq = _dot(across, across)
    has = sq > 1e-24 * _dot(axis, axis)
    inv_length = jnp.where(has, 1.0 / jnp.sqrt(jnp.where(has, sq, 1.0)), 0.0)
    e = across * inv_length[..., None]
    project = (_identity() - _outer(e, e)) * _matrices(inv_length)
    da_daxis = _identity() - _outer(c, c) * _matrices(inv_c2)
    # d(1/|c|²)/dc = -2 c/|c|⁴ (0 in still water, where 1/|c|² is the constant 0)
    da_dc = (-_matrices(inv_c2) * (_matrices(along) * _identity() + _outer(c, axis))
             + _matrices(2.0 * along * inv_c2 * inv_c2) * _outer(c, c))
    return e, project @ da_daxis, project @ da_dc


def _row_times(v, m):
    """v^T m over the last axes: (..., 3) for v (..., 3) and m (..., 3, 3)."""
    return jnp.sum(v[..., :, None] * m, axis=-2)


def _femnet_catch_jacobians(U, V, count, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """(∂F/∂U, ∂F/∂V, ∂F/∂c, F): the derivatives (..., 3, 3) of a triangle's whole drag as FEMNET loads
    netting ahead of a catch, F = (|d|/2)[F_V + (F_U.ĉ) ĉ + (F_U.ê_U) ê_V]
    (:func:`jaxnet.terms.drag.netting_drag_femnet_catch`, three thirds), and F itself (..., 3), with the
    water velocity c (..., 3) relative to the netting.

    Differentiated term by term: ∂(P F_U) with P = c c^T/|c|², ∂(F_U.ê_U) ê_V and (F_U.ê_U) ∂ê_V, with
    ∂ê the derivative of a unit vector across the flow (module docstring for its singular set).
    """
    (fu, ju_axis, ju_c), (fv, jv_axis, jv_c) = _both_families(U, V, l0, diameter, cd_normal, cd_tangential,
                                                              water_velocity, water_density)
    force_u = count * fu
    c = water_velocity
    inv_c2 = _inverse(_dot(c, c))
    in_line = _outer(c, c) * _matrices(inv_c2)
    e_u, de_u_daxis, de_u_dc = _unit_across_jacobians(U, c, inv_c2)
    e_v, de_v_daxis, de_v_dc = _unit_across_jacobians(V, c, inv_c2)
    across_u = _dot(force_u, e_u)
    # F_U reaches the total through P F_U + (F_U.ê_U) ê_V: a linear map of F_U
    carry_u = in_line + _outer(e_v, e_u)
    along_c = _dot(force_u, c)
    d_in_line_dc = (_matrices(inv_c2) * (_outer(c, force_u) + _matrices(along_c) * _identity())
                    - _matrices(2.0 * along_c * inv_c2 * inv_c2) * _outer(c, c))
    j_u = carry_u @ (count * ju_axis) + _outer(e_v, _row_times(force_u, de_u_daxis))
    j_v = count * jv_axis + _matrices(across_u) * de_v_daxis
    j_c = (count * jv_c + d_in_line_dc + carry_u @ (count * ju_c)
           + _outer(e_v, _row_times(force_u, de_u_dc)) + _matrices(across_u) * de_v_dc)
    total = count * fv + (along_c * inv_c2)[..., None] * c + across_u[..., None] * e_v
    return j_u, j_v, j_c, total


def netting_drag_femnet_catch_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity,
                                        water_density, velocity_slope=None, up=None, with_force=False):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of FEMNET's netting drag ahead of a catch,
    :func:`jaxnet.terms.drag.netting_drag_femnet_catch`: F = (|d|/2)[F_V + (F_U.ĉ) ĉ + (F_U.ê_U) ê_V] / 3
    (:func:`_femnet_catch_jacobians` for its derivatives).

    Args: as :func:`netting_drag_stiffness` (same units, same ``velocity_slope``, ``up`` and ``with_force``:
    the forces are :func:`jaxnet.terms.drag.netting_drag_femnet_catch`'s).
    """
    coefficients, U, V, count = _twine_geometry(x, uv)
    j_u, j_v, j_c, total = _femnet_catch_jacobians(U, V, count, l0, diameter, cd_normal, cd_tangential,
                                                   water_velocity, water_density)
    stiffness = _spread_stiffness(coefficients, (j_u, j_v), j_c, _vertical(velocity_slope, up), 3)
    return (stiffness, _per_vertex(total)) if with_force else stiffness


def _solidity_gradients(U, V, l0, diameter):
    """Sn of :func:`jaxnet.geometry.diamond_solidity` and its gradients ∂Sn/∂U, ∂Sn/∂V (3,) in 1/m: with
    n = U ^ V and M = 2 |n| the mesh's area, Sn = T/M (T = 4 D l0 - D²) where 0 < T < M, so
    ∂Sn/∂U = -(Sn/M) 2 (V ^ n)/|n| and ∂Sn/∂V = -(Sn/M) 2 (n ^ U)/|n|; 0 where the clip holds Sn at 0 or 1."""
    solidity = geometry.diamond_solidity(U, V, l0, diameter)
    n = jnp.cross(U, V)
    mesh = geometry.mesh_surface(U, V)
    twines = 4.0 * diameter * l0 - diameter**2
    free = (mesh > twines) & (twines > 0.0)
    # -(Sn/M) (2/|n|) = -4 Sn/M² (M = 2|n|), 0 where Sn is clipped
    scale = jnp.where(free, -4.0 * solidity * _inverse(mesh) ** 2, 0.0)
    return solidity, scale * jnp.cross(V, n), scale * jnp.cross(n, U)


def _zhan_jacobians(U, V, count, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density, normal,
                    tangential):
    """(∂F/∂U, ∂F/∂V, ∂F/∂c, F) of a triangle's whole drag by Zhan's law
    (:func:`jaxnet.terms.drag.netting_drag_zhan`, three thirds), with the water velocity c (..., 3) relative to the netting (``cd_normal``, ``cd_tangential``
    unused, as there). Per twine F = K[a_n |c_n| c_n + a_t |c_t| c_t] + K[c1 c_n + c4 c_t] (K = ½ ρ D l0,
    a_n = 1 + c2 Sn + c3 Sn², a_t = 1 + c5 Sn): the first bracket is the Morison form with Cn = a_n, Ct = a_t
    (:func:`_both_families`), the second linear in the split (∂/∂W = K (c4 - c1) ∂c_t/∂W, ∂/∂c = K [c1 I +
    (c4 - c1) ∂c_t/∂c]); Sn depends on U and V (:func:`_solidity_gradients`), adding ∂F/∂Sn ∂Sn/∂W^T with
    ∂F/∂Sn = K Σ_twines [(c2 + 2 c3 Sn) |c_n| c_n + c5 |c_t| c_t]. ``normal`` = (c1, c2, c3), ``tangential`` =
    (c4, c5): the law's coefficients (:data:`jaxnet.terms.drag.ZHAN_NORMAL`, ``ZHAN_TANGENTIAL``), given by the
    caller as this module does not import the terms."""
    c1, c2, c3 = normal
    c4, c5 = tangential
    solidity, ds_du, ds_dv = _solidity_gradients(U, V, l0, diameter)
    (fu, ju_axis, ju_c), (fv, jv_axis, jv_c) = _both_families(
        U, V, l0, diameter, 1.0 + c2 * solidity + c3 * solidity**2, 1.0 + c5 * solidity, water_velocity, water_density)
    k = 0.5 * water_density * diameter * l0
    c = water_velocity
    force, j_c, j_axes, d_solidity = fu + fv, ju_c + jv_c, [ju_axis, jv_axis], 0.0
    for i, axis in enumerate((U, V)):
        c_t, c_n, dct_daxis, dct_dc = _split(axis, c)
        force = force + k * (c1 * c_n + c4 * c_t)
        j_axes[i] = j_axes[i] + (k * (c4 - c1)) * dct_daxis
        j_c = j_c + k * (c1 * _identity() + (c4 - c1) * dct_dc)
        d_solidity = d_solidity + k * ((c2 + 2.0 * c3 * solidity) * geometry.safe_norm(c_n)[..., None] * c_n
                                       + c5 * geometry.safe_norm(c_t)[..., None] * c_t)
    j_u = count * (j_axes[0] + _outer(d_solidity, ds_du))
    j_v = count * (j_axes[1] + _outer(d_solidity, ds_dv))
    return j_u, j_v, count * j_c, count * force


def netting_drag_zhan_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density,
                                velocity_slope=None, up=None, with_force=False, *, normal, tangential):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of Zhan's netting drag, :func:`jaxnet.terms.drag.netting_drag_zhan`
    (:func:`_zhan_jacobians`). Args as :func:`netting_drag_stiffness` (the forces of ``with_force`` are
    :func:`jaxnet.terms.drag.netting_drag_zhan`'s), and the law's coefficients ``normal`` (c1 m/s, c2, c3) and
    ``tangential`` (c4 m/s, c5)."""
    coefficients, U, V, count = _twine_geometry(x, uv)
    j_u, j_v, j_c, total = _zhan_jacobians(U, V, count, l0, diameter, cd_normal, cd_tangential, water_velocity,
                                           water_density, normal, tangential)
    stiffness = _spread_stiffness(coefficients, (j_u, j_v), j_c, _vertical(velocity_slope, up), 3)
    return (stiffness, _per_vertex(total)) if with_force else stiffness


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


# -- a moving net (dynamics) ----------------------------------------------------------------------------


def _relative_stiffness(coefficients, jacobians, j_velocity, water_gradient, time_step):
    """(3k, 3k) K = -∂F/∂x (N/m) of an element force of which vertex i takes 1/k of the element's drag
    computed with the water's velocity relative to vertex i, c_i = w(x_i) - (x_i - x_i^n)/Δt (book
    4.272-4.276; :func:`jaxnet.terms.drag.per_vertex`).

    Row block i, column block j:
        -(1/k) [Σ_p coefficients[p][j] jacobians[p][i] + δ_ij j_velocity[i] (∂w/∂x(x_i) - I/Δt)].

    Args:
      coefficients: per twine vector p of the element, (k,) the weights of W_p = Σ_j coefficients[p][j] x_j.
      jacobians: per twine vector p, (k, 3, 3) ∂F/∂W_p of the element's drag at each c_i (N/m).
      j_velocity: (k, 3, 3) ∂F/∂c of the element's drag at each c_i (N·s/m).
      water_gradient: (k, 3, 3) ∂w/∂x of the water's velocity at each vertex (1/s).
      time_step: Δt (s) of the backward difference v_i = (x_i - x_i^n)/Δt (4.266).
    """
    k = coefficients[0].shape[0]
    # vertex i's own position moves c_i twice: the water's velocity there, and its velocity (x_i - x_i^n)/Δt
    own = j_velocity @ (water_gradient - _identity() / time_step)
    # built in the layout of the result, (i, m, j, n): a transpose at the end would cost as much as the rest
    blocks = jnp.eye(k)[:, None, :, None] * own[:, :, None, :]
    for w, j in zip(coefficients, jacobians):
        blocks = blocks + j[:, :, None, :] * w[None, None, :, None]
    return -blocks.reshape(3 * k, 3 * k) / k


def _moving_netting(element_jacobians, x, uv, l0, diameter, cd_normal, cd_tangential, relative_velocity,
                    water_gradient, time_step, water_density):
    """:func:`_relative_stiffness` of a triangle, its element Jacobians (:func:`_netting_jacobians` or
    :func:`_femnet_catch_jacobians`) taken at the three vertices' relative velocities in one call."""
    (a, b), U, V, count = _twine_geometry(x, uv)
    j_u, j_v, j_c, _ = element_jacobians(U, V, count, l0, diameter, cd_normal, cd_tangential, relative_velocity,
                                         water_density)
    return _relative_stiffness((a, b), (j_u, j_v), j_c, water_gradient, time_step)


def moving_netting_drag_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, relative_velocity, water_gradient,
                                  time_step, water_density):
    """(9, 9) drag stiffness K = -∂F/∂x (N/m) of one diamond-mesh triangle of a moving net in an implicit
    time step: vertex i takes a third of :func:`jaxnet.terms.drag.netting_drag` computed with the water's
    velocity relative to it, c_i = w(x_i) - (x_i - x_i^n)/Δt (book 4.272-4.276, with the corrections of
    :func:`netting_drag_stiffness`). K holds the twines' turning (as in statics, at each c_i), the water's
    velocity varying over the vertex's position (current profile, waves' orbital velocity) and the damping
    -(1/Δt) ∂F/∂c of the vertex's own velocity.

    Args:
      x: (3, 3) vertex positions (m); uv: (3, 2) twine coordinates.
      l0, diameter: m; cd_normal, cd_tangential: dimensionless.
      relative_velocity: (3, 3) c_i, the water's velocity relative to each vertex (m/s).
      water_gradient: (3, 3, 3) ∂w/∂x of the water's velocity at each vertex (1/s), [i, m, n] = ∂w_m/∂x_n.
      time_step: Δt (s). water_density: ρ (kg/m³).
    Vertex-major layout, as :func:`netting_drag_stiffness`.
    """
    return _moving_netting(_netting_jacobians, x, uv, l0, diameter, cd_normal, cd_tangential, relative_velocity,
                           water_gradient, time_step, water_density)


def moving_netting_drag_femnet_catch_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, relative_velocity,
                                               water_gradient, time_step, water_density):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of FEMNET's netting drag ahead of a catch
    (:func:`jaxnet.terms.drag.netting_drag_femnet_catch`) on a moving net: vertex i takes a third of it
    computed with c_i. Args as :func:`moving_netting_drag_stiffness`."""
    return _moving_netting(_femnet_catch_jacobians, x, uv, l0, diameter, cd_normal, cd_tangential,
                           relative_velocity, water_gradient, time_step, water_density)


def moving_netting_drag_zhan_stiffness(x, uv, l0, diameter, cd_normal, cd_tangential, relative_velocity,
                                       water_gradient, time_step, water_density, *, normal, tangential):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of Zhan's netting drag (:func:`jaxnet.terms.drag.netting_drag_zhan`) on
    a moving net: vertex i takes a third of it computed with c_i. Args as :func:`moving_netting_drag_stiffness`,
    and the law's coefficients as :func:`netting_drag_zhan_stiffness`."""
    def element_jacobians(*args):
        return _zhan_jacobians(*args, normal, tangential)

    return _moving_netting(element_jacobians, x, uv, l0, diameter, cd_normal, cd_tangential, relative_velocity,
                           water_gradient, time_step, water_density)


def moving_bar_drag_stiffness(x, rest_length, diameter, cd_normal, cd_tangential, relative_velocity, water_gradient,
                              time_step, water_density):
    """(6, 6) drag stiffness K = -∂F/∂x (N/m) of one cable bar of a moving net: end e takes half of
    :func:`jaxnet.terms.drag.bar_drag` computed with the water's velocity relative to it, c_e (4.272-4.276).

    Args:
      x: (2, 3) end positions (m); rest_length, diameter: m; cd_normal, cd_tangential: dimensionless;
      relative_velocity: (2, 3) c_e (m/s); water_gradient: (2, 3, 3) ∂w/∂x at each end (1/s);
      time_step: Δt (s); water_density: kg/m³.
    """
    j_axis, j_c = twine_drag_jacobians(x[1] - x[0], rest_length, diameter, cd_normal, cd_tangential, relative_velocity,
                                       water_density)  # (2, 3, 3) each: at the two ends' relative velocities
    return _relative_stiffness((jnp.array([-1.0, 1.0]),), (j_axis,), j_c, water_gradient, time_step)


def moving_node_drag_stiffness(drag_area, relative_velocity, water_gradient, time_step, water_density):
    """(3, 3) stiffness K = -∂F/∂x (N/m) of the drag ½ ρ (Cd A) |c| c on a moving body at a node, c = w(x) - v
    the water's velocity relative to it, v = (x - x^n)/Δt: K = -½ ρ (Cd A) (|c| I + c c^T/|c|) (∂w/∂x - I/Δt).

    Args: drag_area Cd·A (m²); relative_velocity (3,) c (m/s); water_gradient (3, 3) ∂w/∂x at the node (1/s);
      time_step Δt (s); water_density kg/m³.
    """
    j_c = (0.5 * water_density * drag_area) * _abs_times_jacobian(relative_velocity)
    return -j_c @ (water_gradient - _identity() / time_step)


def current_slope(z, speed, direction, profile_depth, profile_factor, surface_level=0.0):
    """dc/dz (m/s per m) of :func:`jaxnet.water.current.current_velocity` at height ``z`` (m).

    c(z) = speed f(s - z) ĉ with f piecewise linear in depth, so dc/dz = -speed f'(depth) ĉ: the slope of
    the segment the point is on (the same segment ``searchsorted`` picks: at an interior profile point the
    deeper one), 0 strictly beyond the first and last points (where the factor is constant; at those points
    themselves the adjoining segment's slope, as the clamp by ``where`` gives), 0 with fewer than 2 points.

    Args: as :func:`jaxnet.water.current.current_velocity` (speed m/s, direction (3,) any length, profile_depth
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

