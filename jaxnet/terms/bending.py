"""Out-of-plane bending of the twines across the edge shared by two triangles (book eqs 4.220-4.245).

The book's model
----------------
Two triangles a = (1, 3, 4) and b = (2, 4, 3) of one panel share the side 3-4 (the *hinge*). A U twine
runs along ``Ua`` in a and along ``Ub`` in b (4.221, 4.223); where it crosses the common side it turns
by the angle alpha between them (4.240). Each U twine is approximated by two chords ``n_a Ua`` and
``n_b Ub`` (4.229-4.233), with n_a = |d_a| / (2 N_U) twine vectors, |d_a|/2 the number of U twine
vectors in triangle a (4.25) and N_U = |V3 - V4| the number of U twines crossing the side. The radius
of curvature rho is that of the circle through the chord ends (4.234-4.236); the couple on one twine is
C = EI / rho (4.220) and the vertex forces follow by virtual work, F = -N_U C d(alpha)/dx (4.237-4.239).
The V twines bend the same way with N_V = |U3 - U4| and the V twine vectors.

What is computed here, and why
------------------------------
An energy, so that forces are ``-jax.grad`` and the stiffness (4.245) is ``jax.jacfwd(jax.grad(.))``,
exactly as :mod:`jaxnet.terms.tension` does. Three choices make it finite and conservative:

1. **Only the out-of-plane part of alpha bends the twine.** Let phi_a (phi_b) be the angle between the
   twine and the hinge in triangle a (b), and theta the fold (dihedral) angle of the hinge. The book's
   angle splits exactly as

       4 sin²(alpha/2) = 4 sin²((phi_a - phi_b)/2) + sin(phi_a) sin(phi_b) 4 sin²(theta/2),

   an in-plane kink plus the fold (``tests/terms/test_bending.py`` checks the identity). The in-plane kink is
   a change of mesh shape between neighbouring elements; it is not twine flexion *outside* the netting
   plane (the section's subject) and the book's alpha would make a flat net bend itself. It is dropped:
   the twine's bending angle here is ``alpha_out = sqrt(sin(phi_a) sin(phi_b)) |theta|``, and a flat
   panel, however distorted in its plane, carries no bending force.
2. **The fold angle is theta, by atan2.** theta is the signed dihedral angle between the two triangles'
   normals, ``atan2((n_a ^ n_b) . e_hat, n_a . n_b)``: 0 on a flat hinge, smooth there, accurate at any
   fold. The energy holds theta² (for 4 sin²(theta/2), the same to leading order), so nothing divides by
   sin(alpha) as 4.241-4.242 do, and a flat net (rho = infinity in 4.234) has zero force and the finite
   stiffness of the fold. theta² jumps at theta = ±pi only (two triangles folded flat onto each other).
3. **The couple is EI/rho with the small-angle radius of 4.234 on unstretched chords.** For a small
   turn the circle through the chord ends has rho = (A + B) / (2 alpha) (the law of sines gives
   rho = |A ua + B ub| / (2 sin alpha) exactly). The energy whose alpha-derivative is that couple is the
   discrete-rod energy EI alpha² / (A + B) per twine. The chord lengths A = n_a l0, B = n_b l0 are taken
   unstretched (material lengths, as discrete elastic rods do) rather than n_a |Ua|: then the couple
   conjugate to alpha_out is exactly EI/rho and no force comes from stretching the chords, and the
   stiffness does not blow up as a slack twine vector shortens. In tension |Ua| = l0 (1 + eps), so this
   differs from the book's chords by the twine strain only.

Resulting hinge energy (J)::

    E = EI theta² sum_{f = U, V} N_f sin(phi_af) sin(phi_bf) / (A_f + B_f)
      = 2 EI theta² / (l0 (|d_a| + |d_b|)) sum_f N_f² sin(phi_af) sin(phi_bf),

    sin(phi_aU) = |Ua ^ e| / (|Ua| |e|) = N_U |n_a| / (|d_a| |Ua| |e|)
                  (e = Δu Ua + Δv Va is the shared side, n_a = d_a Ua ^ Va triangle a's normal)

with N_U = |Δv|, N_V = |Δu| over the shared side. The turn of a twine acts over (A + B)/2 =
(|d_a| + |d_b|) l0 / (4 N) of its length (the curvature is 2 alpha_out / (A + B)). The forces are
exactly F = -sum_f N_f (EI/rho_f) grad(alpha_out,f): the book's 4.239 with alpha_out for alpha and the
small-angle rho of 4.234 on unstretched chords. Against the printed 4.239 (sign fixed) they differ by
O(alpha²) relative for a pure fold of an unstretched net, and by the in-plane kink terms otherwise.

Limits: the energy lives on the hinges, so how well a mesh renders a smooth bend depends on how its
sides lie. A panel laid on a cylinder (nodes on it) stores, against the continuum sum of
EI kappa_n² l0 / 2 over twine vectors: 2x with square meshes and sides along the twines (all the turn
is at the sides across the curvature; the diagonals stay flat), about 10x with the sides at 45° (the
triangulated cylinder is corrugated); refining the mesh does not change these factors.

How it is differentiated
------------------------
The assembly takes the stiffness as ``jax.jacfwd(jax.grad(.))`` of the element energy. Traced through
atan2, square roots and guards, that Hessian costs ~150 energy evaluations per hinge and seconds of
compile time, so the derivatives are written out instead. The energy is an explicit function of nine
quantities z of the hinge, polynomials of its edges e = b - a, r = p - a, s = q - a:

    z = (|e|², tau, n1 . n2, |n1|², |n2|², |Ua|², |Va|², |Ub|², |Vb|²),   tau = (e ^ r) . s,
    E = 2 EI f(z) / (l0 (|d_a| + |d_b|)),   f = theta² (T_U + T_V),   theta = atan2(-|e| tau, n1 . n2),
    T_f = N_f² sin(phi_af) sin(phi_bf) = N_f⁴ |n1| |n2| / (|d_a d_b| |e|² |F_a| |F_b|)   (F = U, V)

(the twine vectors are fixed combinations of the edges, from the twine coordinates). df/dz and d²f/dz²
are closed forms (theta through atan2's derivatives; T_f a monomial: dT = T sum_i a_i dz_i / z_i); dz/dx
comes from cross products, and the second derivatives of the z themselves from their forms in the Gram
matrix of the edges (constants, or linear in the edges for tau). ``jax.custom_jvp`` attaches the gradient
to the energy and the Hessian to the gradient, so ``jax.grad`` evaluates the first and ``jax.jacfwd`` of it
the second (several times faster to run and to compile than autodiff of the same formula). Nothing in
the value changes: same formula, same guards (where a guard holds a quantity at 0, so are its derivatives).
Tangents in uv, never taken by the solver, fall back on autodiff of the same function; derivatives of
higher order in x differentiate the closed forms. ``tests/terms/test_bending.py`` checks energy, forces and
stiffness against autodiff of an independent transcription of the formula.

Conventions
-----------
Hinge node order (as :func:`jaxnet.mesh.hinges.find_hinges` gives it): ``[a, b, p, q]`` with a-b the
shared side, p the third vertex of triangle 1 and q of triangle 2; the two triangles are taken as
(a, b, p) and (b, a, q), so their normals agree on a flat hinge whatever the elements' own vertex order
(orientation, sign of d, is immaterial: counts use |d|). theta > 0 when q has rotated about a->b (right
hand) out of the plane of triangle 1. Units: positions and l0 in m, twine coordinates in twines,
EI in N m², energy in J, couples in N m.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
from jax.custom_derivatives import SymbolicZero

from jaxnet import geometry
from jaxnet.terms.term import ENERGY, ClosedForm, Term, any_nonzero, register

# Squares of lengths (m²) or of products of lengths below this are treated as a collapsed hinge: the
# quantity divided by is replaced by 1 and the result by 0 ("double where"), so that value, gradient and
# jacfwd stay finite. Far below any netting scale (a 1 mm twine gives 1e-30 for the smallest product).
_TINY = 1e-300

# The hinge seen from node a: W has rows e = b - a, r = p - a, s = q - a (m); W = C x with C = [-1 | I].
# Its Gram entries (G_ee, G_rr, G_ss, G_er, G_es, G_rs) are G_k = tr(T_k W W^T) / 2 with T_k = E_ij + E_ji
# (twice E_ii on the diagonal): dG_k/dW = T_k W and d²G_k/dW² = T_k (x) I3, constants.
_GRAM_T = np.zeros((6, 3, 3))
for _k, (_i, _j) in enumerate(((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))):
    _GRAM_T[_k, _i, _j] += 1.0
    _GRAM_T[_k, _j, _i] += 1.0
# second derivatives in the Gram entries of n1 . n2 = G_er G_es - G_ee G_rs, |n1|² = G_ee G_rr - G_er² and
# |n2|² = G_ee G_ss - G_es² (the other z are linear in them)
_GRAM_HESSIANS = np.zeros((3, 6, 6))
for _m, _entries in enumerate(((((3, 4), 1.0), ((0, 5), -1.0)),
                               (((0, 1), 1.0), ((3, 3), -1.0)),
                               (((0, 2), 1.0), ((4, 4), -1.0)))):
    for (_i, _j), _v in _entries:
        _GRAM_HESSIANS[_m, _i, _j] += _v
        _GRAM_HESSIANS[_m, _j, _i] += _v
# Levi-Civita symbol: tau = det W, d²tau/dW_ia dW_jb = eps_ijk eps_abc W_kc
_LEVI_CIVITA = np.zeros((3, 3, 3))
for _i, _j, _k in ((0, 1, 2), (1, 2, 0), (2, 0, 1)):
    _LEVI_CIVITA[_i, _j, _k], _LEVI_CIVITA[_j, _i, _k] = 1.0, -1.0
# positions of a, b, p, q on the basis (e, r, s): fed to the (linear) twine_vectors, they give each twine
# vector's coefficients on the edges
_EDGE_BASIS = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
# exponents of the monomials T_U, T_V in z (see _invariants)
_EXPONENTS = np.array([[-1.0, 0.0, 0.0, 0.5, 0.5, -0.5, 0.0, -0.5, 0.0],
                       [-1.0, 0.0, 0.0, 0.5, 0.5, 0.0, -0.5, 0.0, -0.5]])


def _safe_ratio(num, den):
    """num / den, with 0 (and zero derivatives) where den is (numerically) zero."""
    ok = jnp.abs(den) > _TINY
    return jnp.where(ok, num / jnp.where(ok, den, 1.0), 0.0)


def _safe_sqrt(r):
    """sqrt(r) for r >= 0, with a zero derivative (not an infinite one) at r = 0."""
    ok = r > _TINY
    return jnp.where(ok, jnp.sqrt(jnp.where(ok, r, 1.0)), 0.0)


def _safe_rsqrt(r):
    """1 / sqrt(r) for r >= 0, and 0 (with zero derivatives) where r is (numerically) zero."""
    ok = r > _TINY
    return jnp.where(ok, jax.lax.rsqrt(jnp.where(ok, r, 1.0)), 0.0)


# ---------------------------------------------------------------- the hinge's quantities z


def _edges(x):
    """W (3, 3) m: the edges e = b - a, r = p - a, s = q - a from node a (static slices, not gathers)."""
    return jnp.stack([x[1] - x[0], x[2] - x[0], x[3] - x[0]])


def _normals(x):
    """n1 = (b - a) ^ (p - a) and n2 = (a - b) ^ (q - b) = s ^ e (m²), each from its triangle's own sides
    (so that it is exactly 0 when the triangle is collapsed onto a node)."""
    return jnp.cross(x[1] - x[0], x[2] - x[0]), jnp.cross(x[0] - x[1], x[3] - x[1])


def _twine_rows(uv):
    """Ua, Va, Ub, Vb as rows (4, 3) of coefficients on the edges (e, r, s), d_a, d_b, and N_U, N_V."""
    swap = lambda a: jnp.stack([a[1], a[0], a[3]])
    Ua, Va, da = geometry.twine_vectors(_EDGE_BASIS[:3], uv[:3])
    Ub, Vb, db = geometry.twine_vectors(swap(_EDGE_BASIS), swap(uv))
    du, dv = uv[1, 0] - uv[0, 0], uv[1, 1] - uv[0, 1]
    # U twines are lines of constant V: |dv| of them cross the side (the book's |V3 - V4|), and |du| V twines
    return jnp.stack([Ua, Va, Ub, Vb]), da, db, jnp.abs(dv), jnp.abs(du)


def _invariants(x, uv):
    """The quantities z the energy is an explicit function of, and what their derivatives need.

    Returns (W, gram, z, consts, vectors): W (3, 3) the edges (m); gram (6,) their Gram entries (m²);
    z = (|e|², tau (m³), n1 . n2, |n1|², |n2|² (m⁴), |Ua|², |Va|², |Ub|², |Vb|² (m²)), polynomials of
    the Gram entries and tau = det W, but computed from the vectors, which lose no digits to
    cancellation (the Gram forms do, for slender triangles); consts = (twine rows, d_a, d_b, N_U, N_V)
    from uv; vectors = (n1, n2, twine vectors (4, 3)).
    """
    W = _edges(x)
    e, r, s = W
    rows, da, db, n_u, n_v = _twine_rows(uv)
    n1, n2 = _normals(x)
    tw = rows[:, :1] * e + rows[:, 1:2] * r + rows[:, 2:] * s  # Ua, Va, Ub, Vb
    gram = jnp.stack([e @ e, r @ r, s @ s, e @ r, e @ s, r @ s])
    z = jnp.concatenate([jnp.stack([gram[0], n1 @ s, n1 @ n2, n1 @ n1, n2 @ n2]), jnp.sum(tw * tw, axis=1)])
    return W, gram, z, (rows, da, db, n_u, n_v), (n1, n2, tw)


# ---------------------------------------------------------------- the energy as a function of z


def _theta(g_ee, tau, n12):
    """theta (rad) from |e|² (m²), tau = n1 . s (m³) and n1 . n2 (m⁴); 0 for a collapsed hinge.

    |n1| |n2| |e| sin(theta) = (n1 ^ n2) . e = -|e|² n1 . s (as (e ^ u) ^ (e ^ w) = (e . u ^ w) e).
    """
    sin_part, cos_part = -_safe_sqrt(g_ee) * tau, n12
    ok = sin_part**2 + cos_part**2 > _TINY
    return jnp.where(ok, jnp.arctan2(jnp.where(ok, sin_part, 0.0), jnp.where(ok, cos_part, 1.0)), 0.0)


def _monomials(z, consts):
    """(T_U, T_V), T_f = N_f² sin(phi_af) sin(phi_bf) (twines²); 0 for a collapsed hinge.

    sin(phi_aU) = |Ua ^ e| / (|Ua| |e|) = N_U |n1| / (|d_a| |Ua| |e|), as n1 = d_a Ua ^ Va and
    e = du Ua + dv Va. Written with N explicit (not as |Ua ^ e|) so that it is smooth, and exactly 0, for a
    family that does not cross the side (N = 0).
    """
    _, da, db, n_u, n_v = consts
    common = _safe_ratio(_safe_sqrt(z[3] * z[4]), z[0] * jnp.abs(da * db))
    s_u = n_u**2 * common * _safe_rsqrt(z[5] * z[7])  # sin(phi_aU) sin(phi_bU)
    s_v = n_v**2 * common * _safe_rsqrt(z[6] * z[8])
    return jnp.stack([n_u**2 * s_u, n_v**2 * s_v])


def _reduced_energy(z, consts):
    """f = theta² (T_U + T_V) (rad² twines²): the energy over 2 EI / (l0 (|d_a| + |d_b|))."""
    return _theta(z[0], z[1], z[2]) ** 2 * jnp.sum(_monomials(z, consts))


def _z_derivatives(z, consts, hessian):
    """f, df/dz (9,) and, if ``hessian``, d²f/dz² (9, 9), in closed form.

    f = theta² S: theta = atan2(y, c) with y = -|e| tau, c = n1 . n2 (z[0], z[1], z[2]); S = T_U + T_V,
    monomials (dT = T sum_i a_i dz_i / z_i). Where a guard of the value holds a quantity at 0, its
    derivatives here are 0 too, as autodiff of the guarded value gives.
    """
    g_ee, tau, c = z[0], z[1], z[2]
    root, inv_root = _safe_sqrt(g_ee), _safe_rsqrt(g_ee)
    y = -root * tau
    rho2 = y**2 + c**2
    theta = _theta(g_ee, tau, c)
    inv = _safe_ratio(1.0, rho2)  # 1 / rho², 0 where theta is held at 0
    th_y, th_c = c * inv, -y * inv
    y_z = jnp.stack([-0.5 * tau * inv_root, -root])  # dy/d|e|², dy/dtau
    d_theta = jnp.concatenate([th_y * y_z, th_c[None], jnp.zeros(6)])
    monomials = _monomials(z, consts)
    S = jnp.sum(monomials)
    inv_z = _safe_ratio(1.0, jnp.where(z > _TINY, z, 0.0))  # 0 where z <= 0 (tau, n1 . n2: exponent 0)
    log_grads = _EXPONENTS * inv_z  # d log T_f / dz (2, 9)
    d_S = monomials @ log_grads
    f = theta**2 * S
    d_f = 2.0 * theta * S * d_theta + theta**2 * d_S
    if not hessian:
        return f, d_f
    # d²theta = theta_yy dy dy + theta_yc (dy dc + dc dy) + theta_cc dc dc + theta_y d²y, theta_cc = -theta_yy
    th_yy, th_yc = -2.0 * y * c * inv**2, (y**2 - c**2) * inv**2
    y_ee, y_et = 0.25 * tau * inv_root**3, -0.5 * inv_root  # d²y/d|e|², d²y/d|e|² dtau
    h_theta = jnp.stack([
        jnp.stack([th_yy * y_z[0] ** 2 + th_y * y_ee, th_yy * y_z[0] * y_z[1] + th_y * y_et, th_yc * y_z[0]]),
        jnp.stack([th_yy * y_z[0] * y_z[1] + th_y * y_et, th_yy * y_z[1] ** 2, th_yc * y_z[1]]),
        jnp.stack([th_yc * y_z[0], th_yc * y_z[1], -th_yy]),
    ])
    h_theta = jnp.pad(h_theta, ((0, 6), (0, 6)))
    # d²T = T (g g^T - diag(a / z²)) with g = a / z
    h_S = (jnp.einsum("f,fi,fj->ij", monomials, log_grads, log_grads)
           - jnp.diag(monomials @ (log_grads * inv_z)))
    h_f = (2.0 * S * jnp.outer(d_theta, d_theta) + 2.0 * theta * S * h_theta
           + 2.0 * theta * (jnp.outer(d_theta, d_S) + jnp.outer(d_S, d_theta)) + theta**2 * h_S)
    return f, d_f, h_f


# ---------------------------------------------------------------- from z to the nodes


def _z_gradients(W, vectors, rows):
    """dz/dW (9, 3, 3) (columns d/de, d/dr, d/ds), from cross products (no cancellation)."""
    e, r, s = W
    n1, n2, tw = vectors  # n1 = e ^ r, n2 = s ^ e
    zero = jnp.zeros(3)
    cross = jnp.cross
    return jnp.concatenate([
        jnp.stack([
            jnp.stack([2.0 * e, zero, zero]),  # |e|²
            jnp.stack([cross(r, s), cross(s, e), n1]),  # tau = det W
            jnp.stack([cross(r, n2) + cross(n1, s), cross(n2, e), cross(e, n1)]),  # n1 . n2
            jnp.stack([2.0 * cross(r, n1), 2.0 * cross(n1, e), zero]),  # |n1|²
            jnp.stack([2.0 * cross(n2, s), zero, 2.0 * cross(e, n2)]),  # |n2|²
        ]),
        2.0 * rows[:, :, None] * tw[:, None, :],  # |Ua|², |Va|², |Ub|², |Vb|²
    ])


def _z_gram_jacobian(gram, rows):
    """dz/dG (9, 6): z in the Gram entries, differentiated (tau does not depend on them)."""
    g_ee, g_rr, g_ss, g_er, g_es, g_rs = gram
    one, zero = jnp.ones_like(g_ee), jnp.zeros_like(g_ee)
    k0, k1, k2 = rows[:, 0], rows[:, 1], rows[:, 2]
    return jnp.concatenate([
        jnp.stack([
            jnp.stack([one, zero, zero, zero, zero, zero]),
            jnp.stack([zero, zero, zero, zero, zero, zero]),
            jnp.stack([-g_rs, zero, zero, g_es, g_er, -g_ee]),
            jnp.stack([g_rr, g_ee, zero, -2.0 * g_er, zero, zero]),
            jnp.stack([g_ss, zero, g_ee, zero, -2.0 * g_es, zero]),
        ]),
        jnp.stack([k0**2, k1**2, k2**2, 2.0 * k0 * k1, 2.0 * k0 * k2, 2.0 * k1 * k2], axis=1),  # |k W|²
    ])


def _lift(a, axis):
    """From derivatives in the edges W to derivatives in the nodes x (W = C x): C^T a along ``axis``."""
    return jnp.concatenate([-jnp.sum(a, axis=axis, keepdims=True), a], axis=axis)


def _derivatives(x, uv, hessian):
    """f, df/dx (4, 3) (rad² twines² / m) and, if ``hessian``, d²f/dx² (4, 3, 4, 3) (/ m²).

    Chain x -> W -> z: d²f/dW² = (dz/dW)^T (d²f/dz²) (dz/dW) + sum_m df/dz_m d²z_m/dW², and the last sum,
    through the Gram entries G of which the z are polynomials, is J^T D J + (sum_k df/dG_k T_k) (x) I3
    + df/dtau eps eps W, with J = dG/dW, D = sum_m df/dz_m d²z_m/dG² and df/dG = (dz/dG)^T df/dz.
    """
    W, gram, z, consts, vectors = _invariants(x, uv)
    out = _z_derivatives(z, consts, hessian)
    z_w = _z_gradients(W, vectors, consts[0])
    grad = _lift(jnp.tensordot(out[1], z_w, 1), 0)
    if not hessian:
        return out[0], grad
    d_f, h_f = out[1], out[2]
    zw = z_w.reshape(9, 9)
    jac = jnp.einsum("kmn,na->kma", _GRAM_T, W)  # dG/dW (6, 3, 3)
    d_gram = d_f @ _z_gram_jacobian(gram, consts[0])
    hess_w = (
        (zw.T @ h_f @ zw).reshape(3, 3, 3, 3)
        + jnp.einsum("kma,kl,lnb->manb", jac, jnp.tensordot(d_f[2:5], _GRAM_HESSIANS, 1), jac)
        + jnp.einsum("mn,ab->manb", jnp.tensordot(d_gram, _GRAM_T, 1), jnp.eye(3))
        + d_f[1] * jnp.einsum("mnk,abc,kc->manb", _LEVI_CIVITA, _LEVI_CIVITA, W)
    )
    return out[0], grad, _lift(_lift(hess_w, 0), 2)


def _reduced_energy_of_nodes(x, uv):
    _, _, z, consts, _ = _invariants(x, uv)
    return _reduced_energy(z, consts)


# ---------------------------------------------------------------- closed-form derivatives, attached


@jax.custom_jvp
def _reduced_energy_x(x, uv):
    """f (rad² twines²) of the nodes x (4, 3); its x-derivative is :func:`_reduced_value_and_gradient`."""
    return _reduced_energy_of_nodes(x, uv)


@jax.custom_jvp
def _reduced_value_and_gradient(x, uv):
    """(f, df/dx); its x-derivative is the closed-form Hessian."""
    return _derivatives(x, uv, hessian=False)


def _reduced_energy_x_jvp(primals, tangents):
    (x, uv), (x_dot, uv_dot) = primals, tangents
    if isinstance(x_dot, SymbolicZero):
        value = _reduced_energy_of_nodes(x, uv)
        tangent = jnp.zeros_like(value)
    else:
        value, grad = _reduced_value_and_gradient(x, uv)
        tangent = jnp.sum(grad * x_dot)
    if not isinstance(uv_dot, SymbolicZero):
        tangent = tangent + jax.jvp(lambda u: _reduced_energy_of_nodes(x, u), (uv,), (uv_dot,))[1]
    return value, tangent


def _reduced_value_and_gradient_jvp(primals, tangents):
    (x, uv), (x_dot, uv_dot) = primals, tangents
    if isinstance(x_dot, SymbolicZero):
        value, grad = _derivatives(x, uv, hessian=False)
        out_dot = jnp.zeros_like(value), jnp.zeros_like(grad)
    else:
        value, grad, hess = _derivatives(x, uv, hessian=True)
        out_dot = jnp.sum(grad * x_dot), jnp.einsum("iajb,jb->ia", hess, x_dot)
    if not isinstance(uv_dot, SymbolicZero):
        extra = jax.jvp(lambda u: _derivatives(x, u, hessian=False), (uv,), (uv_dot,))[1]
        out_dot = out_dot[0] + extra[0], out_dot[1] + extra[1]
    return (value, grad), out_dot


# symbolic zeros: the solver differentiates in x only, and then no uv tangent is computed
_reduced_energy_x.defjvp(_reduced_energy_x_jvp, symbolic_zeros=True)
_reduced_value_and_gradient.defjvp(_reduced_value_and_gradient_jvp, symbolic_zeros=True)


# ---------------------------------------------------------------- public


def fold_angle(x):
    """Signed fold (dihedral) angle theta of a hinge, in rad, in (-pi, pi]; 0 when flat.

    Args:
      x: (4, 3) positions (m) of the hinge nodes [a, b, p, q] (shared side a-b, opposite vertices p, q).
    Returns:
      theta = atan2((n1 ^ n2) . e/|e|, n1 . n2) with n1 = (b - a) ^ (p - a), n2 = (a - b) ^ (q - b),
      e = b - a: the rotation of n1 into n2 about e (right hand). A collapsed side or triangle (undefined
      angle) gives 0 with zero derivatives.
    """
    e = x[1] - x[0]
    n1, n2 = _normals(x)
    return _theta(e @ e, n1 @ (x[3] - x[0]), n1 @ n2)


def _count_sum(uv):
    """|d_a| + |d_b| (twines²) of the hinge's triangles (a, b, p) and (b, a, q)."""
    swap = lambda a: jnp.stack([a[1], a[0], a[3]])
    return jnp.abs(geometry.twine_determinant(uv[:3])) + jnp.abs(geometry.twine_determinant(swap(uv)))


def hinge_energy(x, uv, l0, ei):
    """Bending energy (J) of the U and V twines crossing the shared side of two triangles of one panel.

    E = 2 EI theta² (N_U² sinphi_aU sinphi_bU + N_V² sinphi_aV sinphi_bV) / (l0 (|d_a| + |d_b|)); see the
    module docstring for the derivation from eqs 4.220-4.240, and for how it is differentiated.

    Args:
      x: (4, 3) positions (m) of the hinge nodes [a, b, p, q] (:func:`jaxnet.mesh.hinges.find_hinges`).
      uv: (4, 2) twine coordinates of the same nodes (twines); both triangles must have d != 0.
      l0: unstretched length of one twine (mesh side) (m), > 0.
      ei: flexural stiffness EI of one twine (N m²).
    """
    return 2.0 * ei * _reduced_energy_x(x, uv) / (l0 * _count_sum(uv))


def hinge_couples(x, uv, l0, ei):
    """Bending couples (C_U, C_V) in N m on ONE U twine and ONE V twine crossing the hinge (eq. 4.220).

    C = EI / rho = 2 EI alpha_out / (A + B), with alpha_out = sqrt(sinphi_a sinphi_b) |theta| the twine's
    out-of-plane bending angle (rad) and A + B = (|d_a| + |d_b|) l0 / (2 N) the unstretched chords
    (4.229-4.232). 0 for a family that does not cross the side. For output; the solver uses the energy.
    """
    _, _, z, consts, _ = _invariants(x, uv)
    theta, (t_u, t_v) = _theta(z[0], z[1], z[2]), _monomials(z, consts)
    # N sqrt(sinphi_a sinphi_b) = sqrt(T_f); the square root is only for output, never differentiated at 0
    scale = 4.0 * ei * jnp.abs(theta) / (l0 * _count_sum(uv))
    return scale * jnp.sqrt(t_u), scale * jnp.sqrt(t_v)


TWINE_BENDING = register(Term(
    name="twine_bending", family="hinges", kind=ENERGY, element=hinge_energy,
    arguments=lambda p, env: {"uv": p.uv, "l0": p.l0, "ei": p.stiffness},
    active=lambda scene, dynamic: {} if scene.hinges is not None and any_nonzero(scene.hinges.stiffness) else None,
    elastic=True, closed_form=ClosedForm("jaxnet.closed_form.bending:hinge_stiffness")))
