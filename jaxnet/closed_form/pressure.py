"""Closed-form stiffness of the fish catch pressure (book eqs 4.246-4.264), front held fixed.

The force is that of :func:`jaxnet.terms.pressure.catch_pressure`,

    F_i = sign · p · w_i(h) · n,     n = (12 ^ 13)/2,     h_j = x_j · a - s,

n the surface vector of the triangle (m², 4.250-4.251 as 4.252-4.254 use them), a the cod-end axis, s the
front's abscissa and w_i the clipped shape integrals (the share of vertex i of the surface behind the
front; 1/3 for a triangle wholly behind, the book's 4.247-4.249). The front (a global state of the net)
is held constant in the tangent, as the solver does. The product rule gives

    ∂F_i/∂x_j = sign · p · [ w_i ∂n/∂x_j + n (∂w_i/∂h_j) a^T ],      K = -∂F/∂x (4.46),

two parts:

* the derivative of the cross product (the book's 4.255, 4.256-4.264 written per coordinate): with
  n = ½ (x1 ^ x2 + x2 ^ x3 + x3 ^ x1), ∂n/∂x_j δ = ½ (x_{j-1} - x_{j+1}) ^ δ, i.e. ∂n/∂x_j is the
  skew matrix of ½ (x_{j-1} - x_{j+1}) (indices mod 3). For j = 1 and δ = e_x that is
  ½ (0, z3 - z2, y2 - y3), the book's 4.256 divided by p/3. The book's 4.256-4.264 are ∂F/∂x, the
  stiffness is minus them (4.46), and they hold only for triangles wholly behind the front;
* the derivative of the weights, for triangles cut by the front (which the book does not treat):
  ∂w/∂h in closed form (:func:`clipped_shape_integrals_jacobian`) times ∂h_j/∂x_j = a.

The element matrix is not symmetric (a follower load); the assembled tangent of a netting closing the
catch is p ∂²V/∂x², symmetric, for a fixed front (see :mod:`jaxnet.terms.pressure`).

Singular points: none. The corner fractions t = g_a/(g_a - g_b) have g_a >= 0 > g_b on the cases where
they are used, so no denominator vanishes; elsewhere they are replaced by harmless constants, as the
autodiff path does. A zero-area triangle has n = 0 and a finite stiffness (the cross-product part only).
Where the force is only continuous (an edge, or two vertices, lying exactly in the front plane, or a
flat triangle in it) the value returned is the one-sided derivative the autodiff path returns: heights
equal to 0 count as *ahead* of the front.

Units: positions in m, pressure in Pa, stiffness in N/m.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms import pressure as pressure_term


def _corner_jacobian(ga, gb, gc):
    """(3, 3) derivatives of the corner weights (w_a, w_b, w_c) of the corner triangle at vertex a with
    respect to the heights (g_a, g_b, g_c), g_a >= 0 > g_b, g_c (dimensionless per m: 1/m).

    With t_b = g_a/(g_a - g_b), t_c = g_a/(g_a - g_c), the weights are t_b t_c (3 - t_b - t_c)/3,
    t_b² t_c/3, t_b t_c²/3 (:func:`jaxnet.terms.pressure.clipped_shape_integrals`); this is their
    product rule, with ∂t_b/∂g_a = -g_b/(g_a - g_b)², ∂t_b/∂g_b = g_a/(g_a - g_b)², t_c alike.
    """
    db, dc = ga - gb, ga - gc
    tb, tc = ga / db, ga / dc
    zero = jnp.zeros_like(ga)
    dtb = jnp.stack([-gb / db**2, ga / db**2, zero])  # ∂t_b/∂(g_a, g_b, g_c)
    dtc = jnp.stack([-gc / dc**2, zero, ga / dc**2])
    row_a = (tc * (3.0 - 2.0 * tb - tc) * dtb + tb * (3.0 - tb - 2.0 * tc) * dtc) / 3.0
    row_b = (2.0 * tb * tc * dtb + tb**2 * dtc) / 3.0
    row_c = (tc**2 * dtb + 2.0 * tb * tc * dtc) / 3.0
    return jnp.stack([row_a, row_b, row_c])


def clipped_shape_integrals_jacobian(h):
    """(3, 3) Jacobian ∂w_i/∂h_j (1/m) of :func:`jaxnet.terms.pressure.clipped_shape_integrals` at the
    vertex heights h (3,) (m, positive behind the front).

    Piecewise rational, one piece per sign pattern of h (heights equal to 0 count as ahead):

    * all behind (w = 1/3) or none behind (w = 0): zero;
    * one vertex a behind: the corner Jacobian (:func:`_corner_jacobian`) at g = (h_a, h_b, h_c),
      (b, c) = (a + 1, a + 2) mod 3;
    * two behind, c ahead alone: w = 1/3 - corner at c with g = -h, so ∂w/∂h = +(corner Jacobian at
      g = (-h_c, -h_{c+1}, -h_{c+2})), the two sign flips cancelling.

    Each piece is laid out in the vertex order (a, a + 1, a + 2) and rolled back to (1, 2, 3).
    """
    h = jnp.asarray(h)
    behind = h > 0.0
    total = jnp.zeros((3, 3), dtype=h.dtype)
    for apex in range(3):  # static: the three possible lone vertices
        local = jnp.roll(h, -apex)  # heights in the order (apex, apex + 1, apex + 2)
        here = jnp.roll(behind, -apex)
        alone_behind = here[0] & ~here[1] & ~here[2]
        alone_ahead = ~here[0] & here[1] & here[2]
        alone = alone_behind | alone_ahead
        # heights from the lone vertex's side; harmless constants (1, -1, -1) on the other patterns so
        # that the unused branch is finite (the autodiff path uses the same double where)
        sided = jnp.where(alone_behind, local, -local)
        g = jnp.where(alone, sided, jnp.array([1.0, -1.0, -1.0]))
        jac = jnp.where(alone, _corner_jacobian(g[0], g[1], g[2]), 0.0)
        total = total + jnp.roll(jac, (apex, apex), axis=(0, 1))
    return total


def _skew(v):
    """(3, 3) matrix of v ^ · (cross product on the left)."""
    zero = jnp.zeros_like(v[0])
    return jnp.array([[zero, -v[2], v[1]], [v[2], zero, -v[0]], [-v[1], v[0], zero]])


def surface_vector_jacobian(x):
    """(3, 3, 3) derivatives ∂n/∂x_j (m) of n = (12 ^ 13)/2: entry [j] is the skew matrix of
    ½ (x_{j-1} - x_{j+1}) (indices mod 3), the 12' ^ 13 + 12 ^ 13' of the book's 4.255."""
    x = jnp.asarray(x)
    return jnp.stack([_skew(0.5 * (x[(j - 1) % 3] - x[(j + 1) % 3])) for j in range(3)])


def catch_pressure_stiffness(x, pressure, front, axis, sign=1.0):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of :func:`jaxnet.terms.pressure.catch_pressure`, front fixed.

    Args: as :func:`jaxnet.terms.pressure.catch_pressure`: x (3, 3) vertex positions (m), pressure p
      (Pa), front (abscissa along ``axis`` in m, or a point (3,) of the front plane), axis (3,) unit
      vector of the cod-end axis, sign ±1 (+1 when 12 ^ 13 points out of the cod-end).
    Returns:
      K (9, 9), vertex-major (entry (3 i + m, 3 j + n): force coordinate m on vertex i, position
      coordinate n of vertex j): -sign p [w_i ∂n/∂x_j + n (∂w_i/∂h_j) a^T]. For a triangle wholly behind
      the front it is -(4.256-4.264) (the nine columns, the same for the three vertices); cut triangles
      add the second term.
    """
    x = jnp.asarray(x)
    axis = jnp.asarray(axis)
    h = pressure_term.front_heights(x, front, axis)
    w = pressure_term.clipped_shape_integrals(h)
    dw = clipped_shape_integrals_jacobian(h)
    n = geometry.surface_vector(x)
    dn = surface_vector_jacobian(x)  # [j, m, n]
    # [i, m, j, n]: w_i ∂n_m/∂x_jn + n_m ∂w_i/∂h_j a_n
    dF = w[:, None, None, None] * jnp.transpose(dn, (1, 0, 2))[None] \
        + n[None, :, None, None] * dw[:, None, :, None] * axis[None, None, None, :]
    return (-(sign * pressure) * dF).reshape(9, 9)


def catch_pressure_on_element_stiffness(x, state, sign):
    """(9, 9) stiffness (N/m) of :func:`jaxnet.terms.pressure.catch_pressure_on_element` (same arguments): the
    catch front of ``state`` held fixed (:mod:`jaxnet.model.assemble` says why)."""
    return catch_pressure_stiffness(x, state["pressure"], state["front"], state["axis"], sign)


def panel_catch_pressure_stiffness(x, state, sign, panel):
    """(9, 9) stiffness (N/m) of :func:`jaxnet.terms.panel_catch.panel_catch_pressure` (same arguments): that of
    the catch its panel holds, its front held fixed, or zero where the panel holds none."""
    k = state["catch_of_panel"][panel]
    stiffness = catch_pressure_stiffness(x, state["pressure"], state["fronts"][jnp.maximum(k, 0)], state["axis"], sign)
    return jnp.where(k >= 0, stiffness, 0.0)
