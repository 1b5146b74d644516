"""Geometry of the triangular netting element (book eqs 4.1-4.29).

Every vertex of a triangle carries fixed *twine coordinates* (U, V): real numbers counting twines along
the two twine directions of the netting. Because the twines are assumed parallel inside an element, the
triangle's sides are linear combinations of the two *twine vectors* U and V (4.1-4.2), which therefore
follow from the vertex positions (4.3-4.7). Every force on the netting derives from U and V, so this is
the only place that computes them.

Sign convention: ``d`` (4.7) is the *signed* twice-area of the triangle in twine coordinates. The book
assumes d > 0 (vertices counter-clockwise in twine coordinates); here every count (meshes, twines,
knots) uses |d|, so clockwise triangles (d < 0) are handled exactly. The formulas for U and V (4.3-4.4)
hold for either sign.

Units: positions in metres, twine coordinates in number of twines, U and V in metres (one twine each).
This module imports nothing from jaxnet.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp


def twine_determinant(uv):
    """Signed determinant d of eq. 4.7 (dimensionless, twines²).

    Args:
      uv: (..., 3, 2) twine coordinates (U_i, V_i) of the three vertices.
    Returns:
      (...,) d = (U2-U1)(V3-V1) - (U3-U1)(V2-V1). |d|/2 is the number of U (and of V) twines.
    """
    du2, dv2 = uv[..., 1, 0] - uv[..., 0, 0], uv[..., 1, 1] - uv[..., 0, 1]
    du3, dv3 = uv[..., 2, 0] - uv[..., 0, 0], uv[..., 2, 1] - uv[..., 0, 1]
    return du2 * dv3 - du3 * dv2


def twine_vectors(x, uv):
    """Twine vectors U and V of one triangle (eqs 4.3-4.4), in metres.

    Args:
      x: (3, 3) vertex positions (m), one row per vertex.
      uv: (3, 2) twine coordinates of the vertices.
    Returns:
      (U, V, d): the two twine vectors (3,) and the signed determinant d (4.7).
    """
    d = twine_determinant(uv)
    s12, s13 = x[1] - x[0], x[2] - x[0]
    du2, dv2 = uv[1, 0] - uv[0, 0], uv[1, 1] - uv[0, 1]
    du3, dv3 = uv[2, 0] - uv[0, 0], uv[2, 1] - uv[0, 1]
    U = (dv3 * s12 - dv2 * s13) / d
    V = (du2 * s13 - du3 * s12) / d
    return U, V, d


def twine_coefficients(uv):
    """Coefficients of the twine vectors on the vertex positions: U = a @ x, V = b @ x (eqs 4.3-4.4).

    U and V are linear in the vertex positions with coefficients fixed by the twine coordinates; the
    closed-form stiffness (:mod:`jaxnet.closed_form`) is built on them (the book's u_i, v_i factors of
    4.43-4.45 are d a_i and d b_i up to their signs).

    Args:
      uv: (3, 2) twine coordinates of the vertices.
    Returns:
      (a, b, d): (3,) coefficients (1/twine, dimensionless per vertex; each sums to 0) and the signed d of 4.7.
    """
    d = twine_determinant(uv)
    du2, dv2 = uv[1, 0] - uv[0, 0], uv[1, 1] - uv[0, 1]
    du3, dv3 = uv[2, 0] - uv[0, 0], uv[2, 1] - uv[0, 1]
    a = jnp.stack([dv2 - dv3, dv3, -dv2]) / d
    b = jnp.stack([du3 - du2, -du3, du2]) / d
    return a, b, d


def safe_norm(v, eps=1e-300):
    """Euclidean norm with a finite derivative at v = 0 (the derivative there is taken as 0).

    A twine vector of zero length is a collapsed element; its tension is then whatever the constitutive
    law gives at length 0, and the solver must not see NaN from d|v|/dv.
    """
    sq = jnp.sum(v * v, axis=-1)
    positive = sq > eps
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, sq, 1.0)), 0.0)


def mesh_count(d):
    """Number of meshes in a triangle, |d|/4 (eq. 4.24)."""
    return jnp.abs(d) / 4.0


def twine_count(d):
    """Number of U twines, equal to the number of V twines, |d|/2 (eqs 4.25-4.26)."""
    return jnp.abs(d) / 2.0


def knot_count(d):
    """Number of knots in a triangle, |d|/2 (eq. 4.27)."""
    return jnp.abs(d) / 2.0


def twine_volume(count, length, diameter):
    """Volume (m³) of ``count`` twines of ``length`` (m) and diameter D (m), count π D²/4 length: the twines
    of a diamond triangle (count |d|, eqs 4.25-4.26, length l0: the volume of the weight 4.277), of a
    hexagonal one (|d| of each family, length the sum of the three l0), a bar (count 1, its rest length), or
    a share of them (count 1/2: half a bar). Numpy or JAX arrays alike."""
    return count * jnp.pi * diameter**2 / 4.0 * length


def surface(x):
    """Cartesian surface of a triangle, |12 ^ 13| / 2 in m² (eq. 4.18)."""
    return 0.5 * safe_norm(jnp.cross(x[1] - x[0], x[2] - x[0]))


def mesh_surface(U, V):
    """Surface of one mesh, 2 |U ^ V| in m² (eq. 4.28)."""
    return 2.0 * safe_norm(jnp.cross(U, V))


def diamond_solidity(U, V, l0, diameter):
    """Solidity Sn of diamond netting (dimensionless, in [0, 1]), as FEMNET's ``Solidity_diamond`` computes it
    for Zhan's law: the twines' projected area in one mesh over the mesh's area,

        Sn = (4 D l0 - D²) / (2 |U ^ V|),   clipped to [0, 1],

    the mesh's area (book 4.28) from the twine vectors U, V (3,) of the current shape (m), so that Sn grows as
    the meshes close; l0 the unstretched twine length and D its diameter (m). A flat mesh (|U ^ V| = 0) has
    Sn = 1, the clip's value there."""
    twines = 4.0 * diameter * l0 - diameter**2
    mesh = mesh_surface(U, V)
    open_ = mesh > twines  # where Sn < 1: the division is safe there, and its derivative is used only there
    return jnp.clip(jnp.where(open_, twines / jnp.where(open_, mesh, 1.0), 1.0), 0.0, 1.0)


@jax.custom_jvp
def half_opening_angle(U, V):
    """Half angle between the twine vectors, in radians (eq. 4.211): pi/4 for square meshes.

    Computed with atan2 so that it is accurate for nearly closed and nearly square meshes alike.

    Its derivative is given by hand (:func:`_half_opening_angle_jvp`), the same as autodiff's of this
    formula: with N = U ^ V, n = |N| and c = U.V,

        dα = ½ (c dn - n dc) / (n² + c²),   dn = (dU.(V ^ N) + dV.(N ^ U)) / n,   dc = dU.V + U.dV

    (dn by the triple product: N.(dU ^ V) = dU.(V ^ N), N.(U ^ dV) = dV.(N ^ U); 0 where n = 0, as
    :func:`safe_norm`'s). Why by hand: the tangent is then made of dot products with vectors of the
    primal, and its transpose (the gradient) of scalings. Autodiff goes through ``jnp.cross``, whose
    operands are sliced component by component; the transpose of each slice is a pad, and XLA (CPU)
    computed the whole chain of the knot contact's derivative again in each of the six.
    """
    return 0.5 * jnp.arctan2(safe_norm(jnp.cross(U, V)), jnp.dot(U, V))


@half_opening_angle.defjvp
def _half_opening_angle_jvp(primals, tangents):
    """JVP of :func:`half_opening_angle` (formula in its docstring); differentiable again (Hessians)."""
    U, V = primals
    dU, dV = tangents
    N = jnp.cross(U, V)
    n, c = safe_norm(N), jnp.dot(U, V)
    has = n > 0.0
    dn = jnp.where(has, (jnp.dot(dU, jnp.cross(V, N)) + jnp.dot(dV, jnp.cross(N, U))) / jnp.where(has, n, 1.0), 0.0)
    dc = jnp.dot(dU, V) + jnp.dot(U, dV)
    scale = n * n + c * c
    dalpha = jnp.where(scale > 0.0, 0.5 * (c * dn - n * dc) / jnp.where(scale > 0.0, scale, 1.0), 0.0)
    return 0.5 * jnp.arctan2(n, c), dalpha


def surface_vector(x):
    """Area vector of a triangle, (12 ^ 13) / 2 in m²: normal to it, of length its surface (eq. 4.18).

    Its direction follows the vertex order (right-hand rule); a scene orients it (e.g. outward of a
    cod-end) by the order of the triangle's vertices.
    """
    return 0.5 * jnp.cross(x[1] - x[0], x[2] - x[0])


def centroid(x):
    """Centroid of an element's vertices (m): x (k, 3) -> (3,)."""
    return jnp.mean(x, axis=0)
