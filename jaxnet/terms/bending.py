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

   an in-plane kink plus the fold (``tests/test_bending.py`` checks the identity). The in-plane kink is
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

from jaxnet import geometry

# Squares of lengths (m²) or of products of lengths below this are treated as a collapsed hinge: the
# quantity divided by is replaced by 1 and the result by 0 ("double where"), so that value, gradient and
# jacfwd stay finite. Far below any netting scale (a 1 mm twine gives 1e-30 for the smallest product).
_TINY = 1e-300


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


def _fold_angle(x):
    """theta (rad) and the hinge's side e (m) and triangle normals n1, n2 (m²); see :func:`fold_angle`."""
    e = x[1] - x[0]
    n1 = jnp.cross(e, x[2] - x[0])
    n2 = jnp.cross(-e, x[3] - x[1])
    # |n1| |n2| |e| sin(theta) = (n1 ^ n2) . e = -|e|² n1 . (q - a)  (as (e ^ u) ^ (e ^ w) = (e . u ^ w) e):
    # the cheaper form keeps the traced Hessian, and its compile time, small
    sin_part = -_safe_sqrt(jnp.dot(e, e)) * jnp.dot(n1, x[3] - x[0])
    cos_part = jnp.dot(n1, n2)
    ok = sin_part**2 + cos_part**2 > _TINY
    theta = jnp.where(ok, jnp.arctan2(jnp.where(ok, sin_part, 0.0), jnp.where(ok, cos_part, 1.0)), 0.0)
    return theta, e, n1, n2


def fold_angle(x):
    """Signed fold (dihedral) angle theta of a hinge, in rad, in (-pi, pi]; 0 when flat.

    Args:
      x: (4, 3) positions (m) of the hinge nodes [a, b, p, q] (shared side a-b, opposite vertices p, q).
    Returns:
      theta = atan2((n1 ^ n2) . e/|e|, n1 . n2) with n1 = (b - a) ^ (p - a), n2 = (a - b) ^ (q - b),
      e = b - a: the rotation of n1 into n2 about e (right hand). A collapsed side or triangle (undefined
      angle) gives 0 with zero derivatives.
    """
    return _fold_angle(x)[0]


def _bending_geometry(x, uv):
    """theta (rad); per twine family (U, V): crossing count N (twines) and sin(phi_a) sin(phi_b); and
    |d_a| + |d_b| (twines²)."""
    theta, e, n1, n2 = _fold_angle(x)
    # static slices and a stack, not gathers of node rows: the Hessian of a gather compiles to scatters
    swap = lambda a: jnp.stack([a[1], a[0], a[3]])
    Ua, Va, da = geometry.twine_vectors(x[:3], uv[:3])
    Ub, Vb, db = geometry.twine_vectors(swap(x), swap(uv))
    du, dv = uv[1, 0] - uv[0, 0], uv[1, 1] - uv[0, 1]
    # U twines are lines of constant V: |dv| of them cross the side (the book's |V3 - V4|), and |du| V twines
    n_u, n_v = jnp.abs(dv), jnp.abs(du)
    # sin(phi_a) = |Ua ^ e| / (|Ua| |e|) = N |n1| / (|d_a| |Ua| |e|), as n1 = d_a Ua ^ Va and
    # e = du Ua + dv Va.
    # Written with N explicit (not as |Ua ^ e|) so that it is smooth, and exactly 0, for a family that does
    # not cross the side (N = 0).
    common = _safe_ratio(_safe_sqrt(jnp.dot(n1, n1) * jnp.dot(n2, n2)), jnp.dot(e, e) * jnp.abs(da * db))
    sin_u = n_u**2 * common * _safe_rsqrt(jnp.dot(Ua, Ua) * jnp.dot(Ub, Ub))
    sin_v = n_v**2 * common * _safe_rsqrt(jnp.dot(Va, Va) * jnp.dot(Vb, Vb))
    return theta, (n_u, sin_u), (n_v, sin_v), jnp.abs(da) + jnp.abs(db)


def hinge_energy(x, uv, l0, ei):
    """Bending energy (J) of the U and V twines crossing the shared side of two triangles of one panel.

    E = 2 EI theta² (N_U² sinphi_aU sinphi_bU + N_V² sinphi_aV sinphi_bV) / (l0 (|d_a| + |d_b|)); see the
    module docstring for the derivation from eqs 4.220-4.240.

    Args:
      x: (4, 3) positions (m) of the hinge nodes [a, b, p, q] (:func:`jaxnet.mesh.hinges.find_hinges`).
      uv: (4, 2) twine coordinates of the same nodes (twines); both triangles must have d != 0.
      l0: unstretched length of one twine (mesh side) (m), > 0.
      ei: flexural stiffness EI of one twine (N m²).
    """
    theta, (n_u, s_u), (n_v, s_v), d_sum = _bending_geometry(x, uv)
    return 2.0 * ei * theta**2 * (n_u**2 * s_u + n_v**2 * s_v) / (l0 * d_sum)


def hinge_couples(x, uv, l0, ei):
    """Bending couples (C_U, C_V) in N m on ONE U twine and ONE V twine crossing the hinge (eq. 4.220).

    C = EI / rho = 2 EI alpha_out / (A + B), with alpha_out = sqrt(sinphi_a sinphi_b) |theta| the twine's
    out-of-plane bending angle (rad) and A + B = (|d_a| + |d_b|) l0 / (2 N) the unstretched chords
    (4.229-4.232). 0 for a family that does not cross the side. For output; the solver uses the energy.
    """
    theta, (n_u, s_u), (n_v, s_v), d_sum = _bending_geometry(x, uv)
    # sqrt(N² sin sin) = N sqrt(sin sin); the square root is only for output, never differentiated at 0
    alpha_u = jnp.sqrt(s_u) * jnp.abs(theta)
    alpha_v = jnp.sqrt(s_v) * jnp.abs(theta)
    return 4.0 * ei * n_u * alpha_u / (l0 * d_sum), 4.0 * ei * n_v * alpha_v / (l0 * d_sum)
