"""Closed-form stiffness of out-of-plane twine bending across a hinge (book eqs 4.220-4.245), corrected.

The Hessian of :func:`jaxnet.terms.bending.hinge_energy`, written out by hand: K = -dF/dx (4.245, the
sign of 4.46) with F the bending forces on the four hinge nodes.

What the book gives, and what is computed here
----------------------------------------------
The book derives the forces by virtual work, F = (EI/rho) (V3 - V4) d(alpha)/dx (4.237-4.239), with alpha
the angle between the twine vectors Ua, Ub of the two triangles (4.240, derivatives 4.241-4.244) and rho the
circumradius of the chord triangle n_a Ua, n_b Ub (4.229-4.236); its stiffness 4.245 is only named,
"-dF_wi/dt_j". Sign fixed (the count is |V3 - V4| and the force restoring, see the errata), the book's own
stiffness for its own angle would be, per twine family,

    K_book = N (EI/rho) d²alpha/dx² + N d(alpha)/dx (x) d(EI/rho)/dx,

which is not symmetric: 1/rho = 2 sin(alpha) / |n_a Ua + n_b Ub| depends on x through the stretched chords
as well as through alpha, so the book's forces are not the gradient of an energy (asymmetry 6-12 % of the
largest entry on random folded hinges, O(theta) on a pure fold). Against jaxnet's K below, on a pure fold of
an unstretched net, K_book = K + sum_f N_f 2 EI / (A_f + B_f) dkappa_f dkappa_f^T + O(theta), kappa_f =
phi_af - phi_bf the in-plane kink of the twine: the book's angle makes the hinge resist an in-plane kink of
the twines (0.67 of K's largest entry on the test hinge of ``tests/closed_form/test_closed_form_bending.py``), which
jaxnet does not count as bending. jaxnet's model
(:mod:`jaxnet.terms.bending`) differs in three stated ways: only the out-of-plane part of alpha bends the
twine, alpha_f = |theta| sqrt(sin(phi_a) sin(phi_b)) (theta the fold angle, phi the angles of the twine to
the side, the row 4.240 (model) of docs/errata.md); rho is the small-turn radius (A + B) / (2 alpha) on
unstretched chords A + B = (|d_a| + |d_b|) l0 / (2 N); and so the couple EI/rho = 2 EI alpha / (A + B) is a
function of alpha alone and the forces derive from the energy

    E = sum_f N_f EI alpha_f² / (A_f + B_f) = sum_f w_f theta² sigma_f,
    w_f = 2 EI N_f² / (l0 (|d_a| + |d_b|))  (N m² / m),   sigma_f = sin(phi_af) sin(phi_bf),

(N_U = |V3 - V4|, N_V = |U3 - U4|). With it the book's structure holds exactly and symmetrically:

    F   = -sum_f N_f (EI/rho_f) d(alpha_f)/dx                                  (4.239, sign fixed)
        = -sum_f w_f (2 theta sigma_f dtheta + theta² dsigma_f),
    K   = sum_f N_f [(EI/rho_f) d²alpha_f + d(alpha_f) (x) d(EI/rho_f)]        (4.245)
        = sum_f w_f [2 sigma dtheta dtheta^T + 2 theta sigma d²theta
                     + 2 theta (dtheta dsigma^T + dsigma dtheta^T) + theta² d²sigma],

the second form of each (alpha_f² = theta² sigma_f differentiated, so that nothing divides by alpha, which
the first form does where the hinge is flat, as 4.241-4.243 divide by sin(alpha)).

How the derivatives are taken
-----------------------------
theta and sigma_f are explicit functions of nine invariants of the hinge (the same ones the energy is
computed from, in :mod:`jaxnet.terms.bending`), with e = b - a, r = p - a, s = q - a,
n1 = e ^ r, n2 = s ^ e (triangle normals) and Ua, Va, Ub, Vb the twine vectors (4.221-4.224):

    z = (|e|², tau = n1 . s, n1 . n2, |n1|², |n2|², |Ua|², |Va|², |Ub|², |Vb|²),
    theta = atan2(-|e| tau, n1 . n2),         (|n1| |n2| sin(theta) = -|e| tau)
    sigma_U = N_U² |n1| |n2| / (|d_a d_b| |e|² |Ua| |Ub|)   (sigma_V with Va, Vb),

(sin(phi_aU) = |Ua ^ e| / (|Ua| |e|) = N_U |n1| / (|d_a| |Ua| |e|), as n1 = d_a Ua ^ Va and
e = dU Ua + dV Va). Three steps, each by hand:

1. dz/dx and d²z/dx² in the 12 coordinates, by vector calculus on the node rows P of e, r, s (e = P_e x...).
   Twine vectors F = c x are linear: d|F|² = 2 c (x) F, d²|F|² = 2 c c^T (x) I3. The normals
   n = (P x) ^ (Q x) are bilinear: dn = -[w]x du + [u]x dw (u = P x, w = Q x, [v]x w = v ^ w), and
   for fixed m the second derivative of m . n is the constant (Q_i P_j - P_i Q_j) [m]x on nodes i, j.
   Products of two of them (tau = n1 . s, n1 . n2, |n|²) by the product rule.
2. dtheta/dz, d²theta/dz² through atan2 (theta_y = c/rho², theta_c = -y/rho², theta_yy = -theta_cc =
   -2yc/rho⁴, theta_yc = (y² - c²)/rho⁴ with y = -|e| tau, c = n1 . n2, rho² = y² + c² = |n1|² |n2|²);
   sigma_f is a monomial in z: dsigma = sigma g, d²sigma = sigma (g g^T - diag(a / z²)), g = a / z with a
   its exponents.
3. The chain rule to x: d²theta/dx² = sum_mn theta_mn dz_m dz_n^T + sum_m theta_m d²z_m (sigma alike), then
   the product rule above.

This is not the route of :mod:`jaxnet.terms.bending`'s own closed form (which goes through the Gram matrix
of the edges); the tests compare the two, and both with finite differences of the energy.

Singular points and degenerate hinges (the same guards as the energy, so the same values)
------------------------------------------------------------------------------------------
- Flat hinge (theta = 0): regular. E = 0, F = 0, K = 2 sum_f w_f sigma_f dtheta dtheta^T (rank one, the
  fold's stiffness); the book's 4.241-4.243 are 0/0 there (sin(alpha) = 0 on an undistorted flat net).
- theta -> +-pi (the triangles folded flat onto each other): regular up to it; theta² jumps at pi.
- A side not crossed by one family (N_f = 0): that family's sigma_f is exactly 0 with its derivatives
  (the book's 4.229-4.230 divide by N = 0 there).
- Collapsed side (e = 0) or triangle (n1 = 0 or n2 = 0): theta has no limit there (E is discontinuous at
  e = 0, has a |n| kink at n = 0). The energy's guards hold theta, sigma and their derivatives at 0 where
  |n1|² |n2|² <= 1e-300 or |e|² |d_a d_b| <= 1e-300; so does this module: E, F, K are all 0 there (the
  value autodiff of the guarded energy gives; not a limit).
- d_a d_b < 0 (the two triangles of opposite orientations in twine coordinates) changes nothing: counts use
  |d|, sigma_f uses |d_a d_b|.

Units: positions and l0 in m, twine coordinates in twines, EI in N m², gradient in N (= J/m), stiffness in
N/m. Layout vertex-major over the hinge nodes [a, b, p, q]: entry (3 i + m, 3 j + n) couples coordinate m
of node i with coordinate n of node j, as ``x.ravel()`` of the (4, 3) positions.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxnet import geometry

# The energy's guard (jaxnet.terms.bending._TINY): a squared length, area or product of them at or below
# it is a collapsed hinge, held at 0 with zero derivatives. The same threshold, so that both paths return
# 0 on the same inputs.
_TINY = 1e-300

# Node rows over [a, b, p, q] of the edges from a: e = b - a (the shared side, the book's 34 with book
# vertices 3 = a, 4 = b, 1 = p, 2 = q), r = p - a, s = q - a.
_ROW_E = np.array([-1.0, 1.0, 0.0, 0.0])
_ROW_R = np.array([-1.0, 0.0, 1.0, 0.0])
_ROW_S = np.array([-1.0, 0.0, 0.0, 1.0])

# Exponents of sigma_U, sigma_V in z = (|e|², tau, n1.n2, |n1|², |n2|², |Ua|², |Va|², |Ub|², |Vb|²).
_SIGMA_EXPONENTS = np.array([[-1.0, 0.0, 0.0, 0.5, 0.5, -0.5, 0.0, -0.5, 0.0],
                             [-1.0, 0.0, 0.0, 0.5, 0.5, 0.0, -0.5, 0.0, -0.5]])


def _guarded_inverse(r):
    """1 / r for r > _TINY, else 0 (a collapsed hinge: the quantity divided is held at 0)."""
    ok = r > _TINY
    return jnp.where(ok, 1.0 / jnp.where(ok, r, 1.0), 0.0)


def _guarded_sqrt(r):
    """sqrt(r) for r > _TINY, else 0."""
    ok = r > _TINY
    return jnp.where(ok, jnp.sqrt(jnp.where(ok, r, 1.0)), 0.0)


def _cross_matrix(v):
    """[v]x (3, 3), the matrix of w -> v ^ w."""
    zero = jnp.zeros_like(v[0])
    return jnp.stack([jnp.stack([zero, -v[2], v[1]]),
                      jnp.stack([v[2], zero, -v[0]]),
                      jnp.stack([-v[1], v[0], zero])])


def _node_jacobian(row):
    """(3, 12) d(row @ x)/dx of a vector linear in the nodes, row (4,) its node coefficients: row (x) I3."""
    return jnp.kron(row[None, :], jnp.eye(3))


# ---------------------------------------------------------------- the hinge's invariants and their derivatives


def _twine_rows(uv):
    """(4, 4) node rows c of Ua, Va, Ub, Vb (F = c @ x, eqs 4.221-4.224 corrected), d_a, d_b, N_U, N_V.

    Triangle 1 is (a, b, p), triangle 2 (b, a, q) (the book's 134 and 243 up to a cyclic shift: same d).
    """
    a1, b1, d_a = geometry.twine_coefficients(uv[:3])
    a2, b2, d_b = geometry.twine_coefficients(jnp.stack([uv[1], uv[0], uv[3]]))
    zero = jnp.zeros_like(d_a)
    on_1 = lambda c: jnp.stack([c[0], c[1], c[2], zero])
    on_2 = lambda c: jnp.stack([c[1], c[0], zero, c[2]])
    rows = jnp.stack([on_1(a1), on_1(b1), on_2(a2), on_2(b2)])
    # U twines are the lines of constant V: |V_b - V_a| of them cross the side (the book's |V3 - V4|)
    return rows, d_a, d_b, jnp.abs(uv[1, 1] - uv[0, 1]), jnp.abs(uv[1, 0] - uv[0, 0])


def _normal_jacobian(row_u, row_w, u, w):
    """(3, 12) dn/dx of n = u ^ w, u = row_u @ x, w = row_w @ x: dn = -[w]x du + [u]x dw."""
    return -_cross_matrix(w) @ _node_jacobian(row_u) + _cross_matrix(u) @ _node_jacobian(row_w)


def _normal_curvature(row_u, row_w, m):
    """(12, 12) d²(m . n)/dx² at fixed m of n = (row_u @ x) ^ (row_w @ x): the constant block
    (Q_i P_j - P_i Q_j) [m]x on nodes i, j (P = row_u, Q = row_w), as m . (a ^ b) = -a^T [m]x b."""
    return jnp.kron(jnp.outer(row_w, row_u) - jnp.outer(row_u, row_w), _cross_matrix(m))


def _symmetric_product(j1, j2):
    """(12, 12) j1^T j2 + j2^T j1: the part of d²(n1 . n2) made of first derivatives (product rule)."""
    p = j1.T @ j2
    return p + p.T


def _invariant_derivatives(x, rows, weights=None):
    """z (9,), dz/dx (9, 12) and, given weights g (9,), sum_k g_k d²z_k/dx² (12, 12) of the hinge (module
    docstring, step 1; None without weights).

    The second derivatives are only ever needed contracted with dE/dz: summing them as they are formed keeps
    nine (12, 12) matrices per hinge out of memory (materialised, they made this closed form slower than
    autodiff). z is computed from the vectors as the energy computes it (n2 = (a - b) ^ (q - b), exactly 0 for
    a triangle collapsed onto b), so that the guards trip on the same inputs.
    """
    e, r, s = x[1] - x[0], x[2] - x[0], x[3] - x[0]
    n1 = jnp.cross(e, r)
    n2 = jnp.cross(x[0] - x[1], x[3] - x[1])  # = s ^ e
    twines = rows[:, 1:2] * e + rows[:, 2:3] * r + rows[:, 3:4] * s  # Ua, Va, Ub, Vb (rows sum to 0)

    d_e, d_s = _node_jacobian(_ROW_E), _node_jacobian(_ROW_S)
    j1 = _normal_jacobian(_ROW_E, _ROW_R, e, r)  # n1 = e ^ r
    j2 = _normal_jacobian(_ROW_S, _ROW_E, s, e)  # n2 = s ^ e
    d_twines = jnp.stack([_node_jacobian(c) for c in rows])  # (4, 3, 12)

    z = jnp.concatenate([jnp.stack([e @ e, n1 @ s, n1 @ n2, n1 @ n1, n2 @ n2]), jnp.sum(twines**2, axis=1)])
    dz = jnp.concatenate([
        jnp.stack([
            2.0 * e @ d_e,
            s @ j1 + n1 @ d_s,  # tau = n1 . s
            n2 @ j1 + n1 @ j2,
            2.0 * n1 @ j1,
            2.0 * n2 @ j2,
        ]),
        2.0 * jnp.einsum("fk,fkn->fn", twines, d_twines),
    ])
    if weights is None:
        return z, dz, None
    g = weights
    # d²z_k/dx² for k = |e|², tau, n1.n2, |n1|², |n2|², the four |twine|², each times g_k; the curvature of
    # m . n (m fixed) is linear in m, so the n-terms of tau, n1.n2, |n1|² and |n2|² combine into one m each
    curvature = (_normal_curvature(_ROW_E, _ROW_R, g[1] * s + g[2] * n2 + 2.0 * g[3] * n1)
                 + _normal_curvature(_ROW_S, _ROW_E, g[2] * n1 + 2.0 * g[4] * n2)
                 + g[1] * _symmetric_product(j1, d_s) + g[2] * _symmetric_product(j1, j2)
                 + 2.0 * g[3] * (j1.T @ j1) + 2.0 * g[4] * (j2.T @ j2) + 2.0 * g[0] * (d_e.T @ d_e)
                 + 2.0 * jnp.einsum("f,fkm,fkn->mn", g[5:], d_twines, d_twines))
    return z, dz, curvature


# ---------------------------------------------------------------- theta and sigma as functions of z


def _fold_angle_of_invariants(z):
    """theta (rad), dtheta/dz (9,) and d²theta/dz² (9, 9) (module docstring, step 2); all 0 where
    |n1|² |n2|² = y² + c² <= _TINY (a collapsed triangle or side: theta undefined, held at 0)."""
    g, tau, c = z[0], z[1], z[2]
    root, inv_root = _guarded_sqrt(g), jnp.sqrt(_guarded_inverse(g))
    y = -root * tau  # |n1| |n2| sin(theta)
    rho2 = y**2 + c**2  # |n1|² |n2|²
    ok = rho2 > _TINY
    theta = jnp.where(ok, jnp.arctan2(jnp.where(ok, y, 0.0), jnp.where(ok, c, 1.0)), 0.0)
    inv = _guarded_inverse(rho2)
    th_y, th_c = c * inv, -y * inv
    th_yy, th_yc = -2.0 * y * c * inv**2, (y**2 - c**2) * inv**2  # th_cc = -th_yy (atan2 is harmonic)
    # y = -sqrt(g) tau: y_g = -tau / (2 sqrt g), y_tau = -sqrt g, y_gg = tau / (4 g^1.5), y_gtau = -1 / (2 sqrt g)
    y_g, y_t = -0.5 * tau * inv_root, -root
    y_gg, y_gt = 0.25 * tau * inv_root**3, -0.5 * inv_root
    d_theta = jnp.concatenate([jnp.stack([th_y * y_g, th_y * y_t, th_c]), jnp.zeros(6)])
    block = jnp.stack([
        jnp.stack([th_yy * y_g**2 + th_y * y_gg, th_yy * y_g * y_t + th_y * y_gt, th_yc * y_g]),
        jnp.stack([th_yy * y_g * y_t + th_y * y_gt, th_yy * y_t**2, th_yc * y_t]),
        jnp.stack([th_yc * y_g, th_yc * y_t, -th_yy]),
    ])
    return theta, d_theta, jnp.pad(block, ((0, 6), (0, 6)))


def _sines_of_invariants(z, d_a, d_b, n_u, n_v):
    """sigma_f = sin(phi_af) sin(phi_bf) for f = U, V (2,), dsigma/dz (2, 9), d²sigma/dz² (2, 9, 9).

    sigma_U = N_U² |n1| |n2| / (|d_a d_b| |e|² |Ua| |Ub|), a monomial in z; 0 with its derivatives where the
    family does not cross the side (N = 0) or the hinge is collapsed (as the energy's guards).
    """
    common = _guarded_sqrt(z[3] * z[4]) * _guarded_inverse(jnp.abs(z[0] * d_a * d_b))
    sigma = jnp.stack([n_u**2 * common * jnp.sqrt(_guarded_inverse(z[5] * z[7])),
                       n_v**2 * common * jnp.sqrt(_guarded_inverse(z[6] * z[8]))])
    inv_z = _guarded_inverse(z)  # 0 for tau and n1 . n2 where <= 0: their exponent is 0 anyway
    log_grad = _SIGMA_EXPONENTS * inv_z  # d log sigma / dz
    d_sigma = sigma[:, None] * log_grad
    h_sigma = sigma[:, None, None] * (log_grad[:, :, None] * log_grad[:, None, :]
                                      - jnp.einsum("fi,ij->fij", log_grad * inv_z, jnp.eye(9)))
    return sigma, d_sigma, h_sigma


def _energy_of_invariants(uv, l0, ei, z):
    """E = sum_f w_f theta² sigma_f (J) as a function of the invariants z, with dE/dz (9,) and d²E/dz² (9, 9)
    (module docstring, step 2: theta and sigma_f of z, w_f = 2 EI N_f² / (l0 (|d_a| + |d_b|)))."""
    _, d_a, d_b, n_u, n_v = _twine_rows(uv)
    theta, d_theta, h_theta = _fold_angle_of_invariants(z)
    sigma, d_sigma, h_sigma = _sines_of_invariants(z, d_a, d_b, n_u, n_v)
    # w_f sigma_f = N_f EI sin(phi_a) sin(phi_b) / (A_f + B_f), A + B = (|d_a| + |d_b|) l0 / (2 N_f) (4.229-4.232)
    weight = 2.0 * ei * jnp.stack([n_u, n_v]) ** 2 / (l0 * (jnp.abs(d_a) + jnp.abs(d_b)))  # w_f (N m)
    # the families share theta: sum_f w_f sigma_f and its derivatives first
    total, d_total, h_total = weight @ sigma, weight @ d_sigma, jnp.tensordot(weight, h_sigma, 1)
    mixed = jnp.outer(d_theta, d_total)
    energy = theta**2 * total
    grad = 2.0 * theta * total * d_theta + theta**2 * d_total
    hess = (2.0 * total * jnp.outer(d_theta, d_theta) + 2.0 * theta * total * h_theta
            + 2.0 * theta * (mixed + mixed.T) + theta**2 * h_total)
    return energy, grad, hess


# ---------------------------------------------------------------- public


def hinge_gradient(x, uv, l0, ei):
    """(12,) dE/dx (N) of :func:`jaxnet.terms.bending.hinge_energy`: minus the bending forces on a, b, p, q.

    F = -sum_f N_f (EI/rho_f) d(alpha_f)/dx = -sum_f w_f (2 theta sigma_f dtheta + theta² dsigma_f) (4.239 with
    the out-of-plane angle alpha_f = |theta| sqrt(sigma_f), the restoring sign and the count |V3 - V4|).

    Args: as :func:`jaxnet.terms.bending.hinge_energy`: x (4, 3) node positions (m) of [a, b, p, q], uv (4, 2)
      twine coordinates, l0 (m) the unstretched twine length, ei (N m²) the flexural stiffness of one twine.
    """
    z, dz, _ = _invariant_derivatives(x, _twine_rows(uv)[0])
    _, grad_z, _ = _energy_of_invariants(uv, l0, ei, z)
    return grad_z @ dz


def hinge_stiffness(x, uv, l0, ei):
    """(12, 12) stiffness K = -dF/dx = d²E/dx² (N/m) of the twine bending across one hinge (4.245, corrected).

    K = sum_f w_f [2 sigma dtheta dtheta^T + 2 theta sigma d²theta + 2 theta (dtheta dsigma^T + dsigma dtheta^T)
    + theta² d²sigma] (module docstring): exactly ``jax.jacfwd(jax.grad(bending.hinge_energy))`` written by hand.
    Symmetric; finite for every input the energy accepts (0 on a collapsed side or triangle, like the energy).

    Args: as :func:`hinge_gradient`. Layout vertex-major over [a, b, p, q] (entry (3 i + m, 3 j + n): coordinate
      m of node i, n of node j), as ``x.ravel()``.
    """
    rows = _twine_rows(uv)[0]
    z, _, _ = _invariant_derivatives(x, rows)
    _, grad_z, hess_z = _energy_of_invariants(uv, l0, ei, z)
    # step 3, the chain rule z -> x: K = dz^T (d²E/dz²) dz + sum_k dE/dz_k d²z_k/dx²
    _, dz, curvature = _invariant_derivatives(x, rows, grad_z)
    return dz.T @ hess_z @ dz + curvature
