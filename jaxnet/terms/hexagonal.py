"""Twine tension in hexagonal-mesh netting (book eqs 4.76-4.113), as a per-element elastic energy.

Geometry (4.76-4.84). A hexagonal net has three twine families l, m, n; every knot joins one twine of each.
The *base mesh* is the parallelogram spanned by the vectors U and V joining equivalent knots,

    U = -m + 2n - l      (4.83),        V = l - m      (4.84);

it holds 2 l, 2 m and 2 n twines and 4 knots (twice the primitive cell of the honeycomb). The twine
coordinates (U_i, V_i) of the vertices count base meshes, and U, V follow from the vertex positions exactly
as for the diamond mesh (4.78-4.82 = 4.3-4.7), so :func:`jaxnet.geometry.twine_vectors` is reused. A triangle
holds |d|/2 base meshes, |d| twines of each family and 2|d| knots (text after 4.82; |d| for clockwise
triangles). Parallel twines inside the element (the element's basic assumption) fix U and V, but not the
position of the knot where l, m, n meet: with l, m, n the vectors from one knot K to its three neighbours
P_l, P_m, P_n,

    P_l - P_m = V,    P_n - P_m = W = (U + V) / 2     (the triangle of Fig. 4.10),

and K is free. The book fixes it by the equilibrium of the knot, T_l + T_m + T_n = 0 (4.88-4.90), solved by
Newton (4.97-4.105) on an approximated form (4.91-4.96). Here the *exact* equilibrium (4.89-4.90) is solved.

Energy. The knot equilibrium is the stationarity of the energy of the three twines in the knot position,
so the element is conservative with the energy

    E(x) = |d| min_K [ phi_l(|l|) + phi_m(|m|) + phi_n(|n|) ],    phi(L) = EA L0 eps² / 2  (4.85-4.87),

(:func:`jaxnet.terms.tension.elastic_energy`, whose derivative is the tension), |d| twines of each family.
By the envelope theorem (the knot is in equilibrium, so its motion does not change E to first order) the
derivatives at fixed knot are dE/dU = |d|/2 T_n and dE/dV = |d|/2 (T_l - T_m), with T_i = T_i l_i/|l_i|
the tension *vectors* along the twines away from the knot: -grad E is then exactly the vertex forces of
4.106-4.113 (F_U = T_l - T_m, F_V = -T_n) for d > 0; for d < 0 the printed forces have the wrong sign, as
4.43-4.45 do. The stiffness, which the book does not give, is ``jax.jacfwd(jax.grad(E))``: the knot's
motion with the vertices enters it through the implicit function theorem (custom JVPs on the knot solve
and on the equilibrium energy), so it is exact, not the frozen-knot approximation, and symmetric.

Knot unknowns. K is sought in the plane of its three neighbours (as the book does, having "turned the
triangle into XOY"), written with two *knot weights* theta = (s, t):

    K = P_m + s V + t W,   so   m = -(s V + t W),  l = V + m,  n = W + m,

theta = (1/3, 1/3) being the centroid of the neighbours, the knot of a regular honeycomb. Why not a free 3-D
knot: the out-of-plane stiffness of a knot is sum T_i/|l_i|, which vanishes or turns negative for mixed
or compressed twines, making the 3-D problem singular where the planar one is not; for twines in traction
both give the same knot (it lies in the plane at the minimum). The weights are invariant under rigid
motions and need no in-plane basis.

Solver. Newton on f(theta) = sum phi_i (its gradient in theta is minus the in-plane resultant of 4.89-4.90
projected on V and W), started at the regular knot, with the Hessian's eigenvalues replaced by their
moduli (saddle-free Newton: compressed twines make f concave in some directions) and a backtracking line
search on f, so that it descends to a minimum even where twines are slack or compressed; f is convex when
no twine resists compression, and its minimum is then global. A lax.while_loop stops when the resultant
is at round-off (after one more polishing step), at most 60 iterations; 4 to 8 are typical, about 20 for
meshes sheared to a few degrees. A slack region (every twine shorter than its rest length, no compression
stiffness) has a flat energy: the solve stops at once there and the energy, forces and stiffness are
exactly 0. A tiny Tikhonov shift (1e-13 of the element's stiffness scale) keeps the 2x2 systems solvable
when the base mesh is closed (U parallel to V) or the twines all slack, where theta is not unique but the
energy is.

Parameters may differ per family: l0, EA (and compression stiffness) are scalars or (3,) arrays ordered
(l, m, n). Units: positions in m, twine coordinates in base meshes, lengths m, stiffness N, energy J.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.tension import elastic_energy, tension, tension_activity
from jaxnet.terms.gravity import hexagonal_weight, netting_arguments, weight_activity
from jaxnet.terms.term import ENERGY, LOAD, WEIGHT, Term, register

#: Order of the twine families in every (3,) parameter or result of this module.
FAMILIES = ("l", "m", "n")

#: Knot weights of the regular honeycomb: the knot at the centroid of its three neighbours.
REGULAR_KNOT = (1.0 / 3.0, 1.0 / 3.0)

_MAX_ITERATIONS = 60
_GRADIENT_TOLERANCE = 1e-12  # relative to sum |T_i| (|V| + |W|): the scale of the knot's force balance
_REGULARISATION = 1e-13  # Tikhonov shift, relative to the element's stiffness scale
_STEP_HALVINGS = 24  # line-search candidates alpha = 1, 1/2, ..., 1/2^23
_ARMIJO = 1e-4


# -- counts (text after 4.82) -----------------------------------------------------------------------


def base_mesh_count(d):
    """Number of base meshes (parallelograms U, V) in a hexagonal-mesh triangle, |d|/2."""
    return jnp.abs(d) / 2.0


def family_twine_count(d):
    """Number of twines of each family (l, m or n) in a hexagonal-mesh triangle, |d| (3|d| in all)."""
    return jnp.abs(d)


def hexagonal_knot_count(d):
    """Number of knots in a hexagonal-mesh triangle, 2|d| (4 per base mesh)."""
    return 2.0 * jnp.abs(d)


# -- the three twines of one knot ---------------------------------------------------------------------


def knot_twines(theta, U, V):
    """Twine vectors l, m, n (m) from the knot to its three neighbours, as rows of a (..., 3, 3) array.

    Args:
      theta: (..., 2) knot weights (s, t): the knot is at P_m + s V + t (U + V)/2 (dimensionless).
      U, V: (3,) sides of the base mesh (m).
    """
    W = 0.5 * (U + V)
    m = -(theta[..., 0:1] * V + theta[..., 1:2] * W)
    return jnp.stack([V + m, m, W + m], axis=-2)


def knot_energy(theta, U, V, l0, ea_traction, ea_compression=None):
    """Energy (J) of one l, one m and one n twine for the knot at weights theta (any knot position).

    Args:
      theta: (..., 2) knot weights (dimensionless); the result has theta's batch shape.
      U, V: (3,) base mesh sides (m); l0 (m), ea_traction, ea_compression (N): as :func:`hexagonal_energy`.
    """
    lengths = geometry.safe_norm(knot_twines(theta, U, V))
    return jnp.sum(elastic_energy(lengths, l0, ea_traction, ea_compression), axis=-1)


def _family_tensions(theta, U, V, l0, ea_traction, ea_compression):
    twines = knot_twines(theta, U, V)
    lengths = geometry.safe_norm(twines)
    return twines, lengths, tension(lengths, l0, ea_traction, ea_compression)


def knot_force(theta, U, V, l0, ea_traction, ea_compression=None):
    """Resultant (N) of the three twine tensions on the knot, T_l + T_m + T_n (4.88): 0 at equilibrium.

    Args:
      theta: (2,) knot weights; U, V: (3,) base mesh sides (m); l0 (m), ea_traction, ea_compression (N):
        scalars or (3,) per family (l, m, n), as in :func:`hexagonal_energy`.
    """
    twines, lengths, tensions = _family_tensions(theta, U, V, l0, ea_traction, ea_compression)
    positive = lengths > 0.0
    unit = jnp.where(positive[:, None], twines / jnp.where(positive, lengths, 1.0)[:, None], 0.0)
    return jnp.sum(tensions[:, None] * unit, axis=0)


# Gradient and Hessian of the triple energy in the knot weights (the residual of 4.89-4.90 and its
# Jacobian, up to the projection on V and W).
_knot_gradient = jax.grad(knot_energy)
_knot_hessian = jax.jacfwd(_knot_gradient)


def _stiffness_scale(U, V, l0, ea_traction, ea_compression):
    """Characteristic size (J) of the Hessian in theta: sum EA/l0 (|V|² + |W|²)."""
    ea = jnp.abs(jnp.asarray(ea_traction, dtype=float))
    if ea_compression is not None:
        ea = ea + jnp.abs(jnp.asarray(ea_compression, dtype=float))
    W = 0.5 * (U + V)
    per_family = jnp.broadcast_to(ea / jnp.asarray(l0, dtype=float), (3,))
    return jnp.sum(per_family) * (jnp.sum(V * V) + jnp.sum(W * W))


def _solve_2x2(a, b):
    """Solve a (2, 2) system by its adjugate; 0 where singular (no NaN in values or derivatives).

    Singular only where theta is not unique (all twines slack, or a closed base mesh) and the right-hand
    side then vanishes with the tensions, so 0 is the right answer there.
    """
    det = a[0, 0] * a[1, 1] - a[0, 1] * a[1, 0]
    ok = det != 0.0
    inv_det = jnp.where(ok, 1.0 / jnp.where(ok, det, 1.0), 0.0)
    return inv_det * jnp.stack([a[1, 1] * b[0] - a[0, 1] * b[1], a[0, 0] * b[1] - a[1, 0] * b[0]])


def _inverse_modulus_2x2(H, floor):
    """|H|^-1 of a symmetric (2, 2) matrix, eigenvalues lifted to max(|lambda|, 1e-9 max|lambda|, floor).

    The Newton matrix of the knot solve: where compressed twines make the energy concave in some
    direction, the step goes down that direction instead of up to the saddle or maximum (saddle-free
    Newton); the relative lift bounds the step along nearly flat directions. Not differentiated.
    """
    centre = 0.5 * (H[0, 0] + H[1, 1])
    radius = jnp.sqrt((0.5 * (H[0, 0] - H[1, 1])) ** 2 + H[0, 1] * H[1, 0])
    lam_hi, lam_lo = centre + radius, centre - radius
    lift = jnp.maximum(1e-9 * jnp.maximum(jnp.abs(lam_hi), jnp.abs(lam_lo)), floor)
    lift = jnp.maximum(lift, jnp.finfo(float).tiny)  # never 1/0, even for an element collapsed to a point
    f_hi = 1.0 / jnp.maximum(jnp.abs(lam_hi), lift)
    f_lo = 1.0 / jnp.maximum(jnp.abs(lam_lo), lift)
    eye = jnp.eye(2)
    # spectral calculus of a 2x2: f(H) = [f_hi (H - lam_lo) - f_lo (H - lam_hi)] / (lam_hi - lam_lo)
    distinct = radius > 1e-12 * (jnp.abs(centre) + floor)
    gap = jnp.where(distinct, 2.0 * radius, 1.0)
    spectral = (f_hi * (H - lam_lo * eye) - f_lo * (H - lam_hi * eye)) / gap
    return jnp.where(distinct, spectral, f_hi * eye)


def _knot_gradient_and_hessian(theta, U, V, l0, ea_traction, ea_compression):
    """Closed-form gradient (2,) and Hessian (2, 2) of the triple energy in theta, for the Newton loop.

    With B = (V, W) and every twine r_i = (fixed) - B theta: g = -B^T sum T_i e_i and
    H = B^T [sum k_i e_i e_i^T + T_i/L_i (I - e_i e_i^T)] B, k_i = dT_i/dL_i. Written out because the
    autodiff Hessian inside the loop multiplies the compile time of every element function; the
    implicit derivative (:func:`_knot_equilibrium_jvp`) uses the autodiff forms, exact at every branch.
    """
    twines, lengths, tensions = _family_tensions(theta, U, V, l0, ea_traction, ea_compression)
    strain_rate = jnp.asarray(ea_traction, dtype=float) / l0  # dT/dL in traction
    compression_rate = 0.0 if ea_compression is None else jnp.asarray(ea_compression, dtype=float) / l0
    k = jnp.where(lengths > l0, strain_rate, compression_rate)
    # a twine of (nearly) zero length has no direction; its geometric stiffness is bounded, not infinite
    floor = 1e-9 * jnp.asarray(l0, dtype=float)
    geometric = tensions / jnp.maximum(lengths, floor)
    B = jnp.stack([V, 0.5 * (U + V)], axis=1)  # (3, 2)
    positive = lengths > 0.0
    unit = jnp.where(positive[:, None], twines / jnp.where(positive, lengths, 1.0)[:, None], 0.0)
    p = unit @ B  # (3, 2): e_i projected on V and W
    g = -jnp.sum(tensions[:, None] * p, axis=0)
    H = jnp.einsum("i,ia,ib->ab", k - geometric, p, p) + jnp.sum(geometric) * (B.T @ B)
    return g, H, tensions, lengths


def _newton_knot(U, V, l0, ea_traction, ea_compression):
    """Damped Newton minimisation of the triple energy over the knot weights (not differentiated)."""
    params = (U, V, l0, ea_traction, ea_compression)
    mu = _REGULARISATION * _stiffness_scale(*params)
    alphas = 0.5 ** jnp.arange(_STEP_HALVINGS, dtype=float)
    eps = jnp.finfo(float).eps
    size = jnp.linalg.norm(V) + 0.5 * jnp.linalg.norm(U + V)

    def body(state):
        theta, k, done = state
        g, H, tensions, lengths = _knot_gradient_and_hessian(theta, *params)
        small = jnp.max(jnp.abs(g)) <= _GRADIENT_TOLERANCE * jnp.sum(jnp.abs(tensions)) * size
        step = -_inverse_modulus_2x2(H, mu) @ g
        # backtracking on f (Armijo). f = sum EA l0 eps²/2 carries a round-off of about eps_machine T L per
        # twine (the strain is a difference of nearly equal lengths): within it, the full Newton step is
        # taken, which is the end game where quadratic convergence makes f's change invisible.
        f0 = knot_energy(theta, *params)
        trial = knot_energy(theta + alphas[:, None] * step, *params)
        noise = 16.0 * eps * (jnp.sum(jnp.abs(tensions) * lengths) + jnp.abs(f0))
        accept = trial <= f0 + _ARMIJO * alphas * jnp.dot(g, step) + noise
        best = jnp.argmin(trial)
        alpha = jnp.where(
            jnp.any(accept), alphas[jnp.argmax(accept)], jnp.where(trial[best] < f0, alphas[best], 0.0)
        )
        moved = jnp.max(jnp.abs(alpha * step)) > 4.0 * eps * (1.0 + jnp.max(jnp.abs(theta)))
        # the step taken once the balance is reached polishes theta to round-off, then stop
        return theta + alpha * step, k + 1, done | small | ~moved

    def cond(state):
        _, k, done = state
        return (~done) & (k < _MAX_ITERATIONS)

    theta0 = jnp.asarray(REGULAR_KNOT, dtype=U.dtype)
    theta, _, _ = jax.lax.while_loop(cond, body, (theta0, 0, jnp.asarray(False)))
    return theta


@jax.custom_jvp
def knot_equilibrium(U, V, l0, ea_traction, ea_compression=None):
    """Knot weights theta (2,) at the equilibrium of the knot (4.88-4.90, exact form), for one element.

    The knot is at P_m + s V + t (U + V)/2; the twines follow from :func:`knot_twines`. Differentiable in
    all arguments by the implicit function theorem: d theta = -H^-1 (d grad_theta f), H the Hessian of
    the triple energy in theta at the solution.

    Args:
      U, V: (3,) sides of the base mesh (m), from :func:`jaxnet.geometry.twine_vectors`.
      l0: unstretched twine length (m), scalar or (3,) per family (l, m, n).
      ea_traction: traction stiffness EA (N), scalar or (3,).
      ea_compression: compression stiffness (N), scalar or (3,), or None for twines that cannot push.
    """
    return _newton_knot(U, V, l0, ea_traction, ea_compression)


@knot_equilibrium.defjvp
def _knot_equilibrium_jvp(primals, tangents):
    theta = knot_equilibrium(*primals)
    _, d_gradient = jax.jvp(lambda *p: _knot_gradient(theta, *p), primals, tangents)
    H = _knot_hessian(theta, *primals)
    mu = _REGULARISATION * _stiffness_scale(*primals)
    return theta, -_solve_2x2(H + mu * jnp.eye(2), d_gradient)


@jax.custom_jvp
def equilibrium_knot_energy(U, V, l0, ea_traction, ea_compression=None):
    """Energy (J) of one l, one m and one n twine with their knot at equilibrium: min over the knot.

    Its derivative is taken at fixed knot (envelope theorem: the knot's motion does not change the energy
    to first order, since the knot is in equilibrium); its second derivative adds the knot's motion,
    through :func:`knot_equilibrium`'s implicit derivative. Written so, the stiffness needs second
    derivatives of the twine energies only, not the third ones that differentiating through the
    stationarity condition would bring in.

    Args: as :func:`knot_equilibrium`.
    """
    theta = knot_equilibrium(U, V, l0, ea_traction, ea_compression)
    return knot_energy(theta, U, V, l0, ea_traction, ea_compression)


@equilibrium_knot_energy.defjvp
def _equilibrium_knot_energy_jvp(primals, tangents):
    theta = knot_equilibrium(*primals)
    return jax.jvp(lambda *p: knot_energy(theta, *p), primals, tangents)


# -- the element --------------------------------------------------------------------------------------


def hexagonal_energy(x, uv, l0, ea_traction, ea_compression=None):
    """Elastic energy (J) of the twines of one hexagonal-mesh triangle, at the equilibrium of its knots.

    E = |d| (phi_l + phi_m + phi_n) with the knot at equilibrium; forces are -jax.grad, the exact stiffness
    jax.jacfwd(jax.grad).

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices in base meshes (U_i, V_i of Fig. 4.9); either
        orientation (sign of d).
      l0: unstretched twine length (m), scalar or (3,) for the families (l, m, n).
      ea_traction: traction stiffness EA (N), scalar or (3,).
      ea_compression: compression stiffness (N), scalar or (3,), or None (slack twines carry nothing).
    """
    U, V, d = geometry.twine_vectors(x, uv)
    return family_twine_count(d) * equilibrium_knot_energy(U, V, l0, ea_traction, ea_compression)


def hexagonal_twines(x, uv, l0, ea_traction, ea_compression=None):
    """Twine vectors l, m, n (m) of one triangle at knot equilibrium, rows of a (3, 3) array, for output."""
    U, V, _ = geometry.twine_vectors(x, uv)
    return knot_twines(knot_equilibrium(U, V, l0, ea_traction, ea_compression), U, V)


def hexagonal_tensions(x, uv, l0, ea_traction, ea_compression=None):
    """Tensions (T_l, T_m, T_n) in N of the three twine families of one triangle (4.85-4.87), for output."""
    U, V, _ = geometry.twine_vectors(x, uv)
    theta = knot_equilibrium(U, V, l0, ea_traction, ea_compression)
    return _family_tensions(theta, U, V, l0, ea_traction, ea_compression)[2]


def _arguments(p, env, compression):
    return {"uv": p.uv, "l0": p.l0, "ea_traction": p.ea_traction,
            "ea_compression": p.ea_compression if compression else None}


HEXAGONAL_TENSION = register(Term(
    name="hexagonal_tension", family="hexagonal", kind=ENERGY, element=hexagonal_energy, arguments=_arguments,
    active=tension_activity("hexagonal"), elastic=True))
HEXAGONAL_WEIGHT = register(Term(
    name="hexagonal_weight", family="hexagonal", kind=LOAD, element=hexagonal_weight, arguments=netting_arguments,
    active=weight_activity("hexagonal", at_surface=False), group=WEIGHT))
