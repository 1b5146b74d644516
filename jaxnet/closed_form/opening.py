"""Closed-form stiffness of the mesh opening (book eqs 4.211-4.219, corrected).

K = -∂F/∂x (4.46, 4.219) of the opening forces 4.216-4.218, i.e. the Hessian of the energy of
:mod:`jaxnet.terms.opening`, E = (|d|/2) H (α - α0)², written without autodiff:

    K = |d| H [∂α ⊗ ∂α + (α - α0) ∂²α]          (N/m),

with α the *half* opening angle (4.211) and ∂α, ∂²α its first and second derivatives in the vertex
positions. The book prints ∂α (4.218, with errata) and leaves ∂²α to the reader ("4.219"); both are
derived here in twine space, on U and V, then carried to the vertices by :mod:`jaxnet.closed_form.chain`.

Twine space. Let n = U ^ V, s = |n| = |U||V| sin 2α, c = U.V, p = |U|², q = |V|² and θ = 2α the angle
between the twines, θ = atan2(s, c) (the accurate form of 4.211's acos). Then

    ∂α/∂U = -(n ^ U) / (2 p s),          ∂α/∂V = (n ^ V) / (2 q s),

which is 4.218 corrected: n ^ U = p V - c U, so ∂α/∂U = -(V - c U / p) / (2 |U||V| sin 2α); carried
to the vertices (∂U/∂x_i = a_i = -v_i/d, ∂V/∂x_i = b_i = -u_i/d with u_i, v_i the factors of 4.43-4.45)
this is the printed 4.218 with sin 2α for its sin α (the derivative of ½ acos(cos 2α) is -1/(2 sin 2α))
and +U_w u_i for its -U_w u_i. Writing |U||V| sin 2α as |U ^ V| keeps the formula accurate near closure, where
1 - cos² 2α loses all its digits. ∂α/∂U is perpendicular to U, of length 1/(2|U|): turning U towards V
by an angle ε closes the mesh by ε/2.

The second derivatives follow from the geometry of the angle θ between two vectors. In the frame of
the mesh plane (û = U/|U|, the in-plane direction e_u = (n ^ U)/(s |U|) normal to U towards V, and the
normal n̂ = n/s): lengthening U by ε changes ∂θ/∂U = -e_u/|U| by ε e_u/|U|², turning U in the plane by
ε/|U| turns e_u into e_u - (ε/|U|) û, and lifting U out of the plane by ε opens θ by
cot θ ε²/(2|U|²); lifting U and V out of the plane together by ε and η changes cos θ by εη/(|U||V|).
Hence, for α = θ/2,

    ∂²α/∂U²   = [ (U m_uᵀ + m_u Uᵀ) / (p² s) + c n nᵀ / (p s³) ] / 2,   m_u = n ^ U,
    ∂²α/∂V²   = [ (V m_vᵀ + m_v Vᵀ) / (q² s) + c n nᵀ / (q s³) ] / 2,   m_v = V ^ n,
    ∂²α/∂U∂V = -n nᵀ / (2 s³),

symmetric (∂²α/∂V∂U is the transpose of the last, itself symmetric). There is no in-plane ∂²α/∂U∂V:
in the plane θ is the difference of the polar angles of V and U.

Singular points.

* Closure (α -> 0, U along V, and α -> π/2, U against V; s -> 0): ∂α stays finite (length 1/(2|U|)
  on U) but its direction is that of the plane, which is undefined at closure, and the out-of-plane
  entries of ∂²α grow like 1/s: E has a cone-shaped kink there (see :mod:`jaxnet.terms.opening`). For
  s > 0 the formulas are exact. At the exactly closed mesh (|n|² <= 1e-300, ``geometry.safe_norm``'s
  threshold) the autodiff path takes the derivative of |n| as 0, which makes its ∂α and ∂²α exactly
  0 (the derivative of atan2(s, c) is (c ds - s dc)/(s² + c²), zero with s = ds = 0, and so is its
  derivative); the closed form returns the same zeros, so K = 0 there, the value of neither side's
  limit (the side limits differ with the direction of approach: a kink).
* Collapsed twine (|U|²|V|² <= 1e-200, :func:`jaxnet.terms.opening.half_angle`'s threshold): no
  angle, no energy: α, ∂α, ∂²α and K are 0, ``valid`` False, as the autodiff path.

Units: positions in m, H in N·m/rad, angles in rad; ∂α in rad/m, ∂²α in rad/m², K in N/m.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.closed_form import chain
from jaxnet.terms.opening import half_angle

# |U ^ V|² at or below this (m⁴) is an exactly closed mesh: geometry.safe_norm's threshold, below which
# the autodiff path takes d|U ^ V| as 0
_CLOSED = 1e-300


def twine_angle_derivatives(U, V):
    """α and its derivatives in twine space for twine vectors U, V (3,) (m), neither of zero length.

    Returns:
      (alpha, g_u, g_v, h_uu, h_uv, h_vv): α (rad) = ½ atan2(|U ^ V|, U.V); ∂α/∂U, ∂α/∂V (3,) (rad/m);
      ∂²α/∂U², ∂²α/∂U∂V (rows along U, columns along V), ∂²α/∂V² (3, 3) (rad/m²). All derivatives are
      0 at the exactly closed mesh (module docstring).
    """
    n = jnp.cross(U, V)
    s2 = jnp.sum(n * n)
    open_ = s2 > _CLOSED
    # double where: the closed branch must not divide by s = 0
    s = jnp.sqrt(jnp.where(open_, s2, 1.0))
    c = jnp.dot(U, V)
    p, q = jnp.sum(U * U), jnp.sum(V * V)
    alpha = 0.5 * jnp.arctan2(jnp.where(open_, s, 0.0), c)
    nh = n / s  # n̂; divided once by s at a time so that nothing under- or overflows for tiny s
    m_u, m_v = jnp.cross(nh, U), jnp.cross(V, nh)  # (n ^ U)/s = |U| e_u, (V ^ n)/s = |V| e_v
    # corrected 4.218 in twine space
    g_u = -m_u / (2.0 * p)
    g_v = -m_v / (2.0 * q)
    normal = jnp.outer(nh, nh) / s
    h_uu = 0.5 * ((jnp.outer(U, m_u) + jnp.outer(m_u, U)) / p**2 + c * normal / p)
    h_vv = 0.5 * ((jnp.outer(V, m_v) + jnp.outer(m_v, V)) / q**2 + c * normal / q)
    h_uv = -0.5 * normal
    zero3, zero33 = jnp.zeros(3), jnp.zeros((3, 3))
    return (alpha, jnp.where(open_, g_u, zero3), jnp.where(open_, g_v, zero3), jnp.where(open_, h_uu, zero33),
            jnp.where(open_, h_uv, zero33), jnp.where(open_, h_vv, zero33))


def half_angle_derivatives(x, uv):
    """Half opening angle α of one triangle and its first and second derivatives on the vertices.

    Closed form of the corrected 4.218 and of its derivative (the ∂²α that 4.219 needs); module docstring.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
    Returns:
      (alpha, gradient, hessian, d, valid): α in [0, π/2] (rad); ∂α/∂x (9,) (rad/m) and ∂²α/∂x² (9, 9)
      (rad/m²), vertex-major (``x.ravel()`` order); the signed d of 4.7; valid False where U or V has zero
      length (then α, gradient and hessian are 0, as :func:`jaxnet.terms.opening.half_angle`).
    """
    a, b, _ = geometry.twine_coefficients(uv)
    # α from the autodiff path's own value function, bit for bit: the knot contact's branches (onset,
    # band edge) must be chosen on the same side of their thresholds by both paths
    alpha, d, valid = half_angle(x, uv)
    U, V, _ = geometry.twine_vectors(x, uv)
    # double where: a collapsed twine would divide by |U|² = 0
    unit = jnp.array([1.0, 0.0, 0.0])
    _, g_u, g_v, h_uu, h_uv, h_vv = twine_angle_derivatives(jnp.where(valid, U, unit), jnp.where(valid, V, unit))
    gradient = chain.vertex_gradient(a, b, g_u, g_v).ravel()
    hessian = chain.vertex_block(a, b, h_uu, h_uv, h_uv.T, h_vv)
    return (jnp.where(valid, alpha, 0.0), jnp.where(valid, gradient, 0.0), jnp.where(valid, hessian, 0.0), d, valid)


def angle_energy_hessian(x, uv, slope, curvature):
    """(9, 9) Hessian (N/m) of E = (|d|/2) f(α) for any f of the half angle, given f'(α) and f''(α).

    ∂²E/∂x² = (|d|/2) [f''(α) ∂α ⊗ ∂α + f'(α) ∂²α]: the structure shared by the opening and knot contact
    terms (4.3.4 and 4.3.10). ``slope`` and ``curvature`` are callables of α (rad) returning f' (J/rad per
    knot) and f'' (J/rad² per knot); 0 for a collapsed element.
    """
    alpha, gradient, hessian, d, valid = half_angle_derivatives(x, uv)
    k = geometry.knot_count(d) * (curvature(alpha) * jnp.outer(gradient, gradient) + slope(alpha) * hessian)
    return jnp.where(valid, k, 0.0)


def opening_stiffness(x, uv, stiffness, rest_angle):
    """(9, 9) mesh opening stiffness K = -∂F/∂x (N/m) of one diamond-mesh triangle (4.219, corrected).

    K = (|d|/2) H [2 ∂α ⊗ ∂α + 2 (α - α0) ∂²α], the Hessian of
    :func:`jaxnet.terms.opening.opening_energy`, vertex-major (entry (3 i + m, 3 j + n): coordinate m of
    vertex i, n of vertex j). 0 at the exactly closed mesh and for a collapsed twine (module docstring).

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
      stiffness: mesh opening stiffness H (N·m/rad) per knot per radian of half angle.
      rest_angle: rest half opening angle α0 (rad).
    """
    return angle_energy_hessian(x, uv, lambda alpha: 2.0 * stiffness * (alpha - rest_angle),
                                lambda alpha: 2.0 * stiffness + 0.0 * alpha)
