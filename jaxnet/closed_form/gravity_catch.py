"""Closed-form stiffness of the gravity catch (:mod:`jaxnet.terms.gravity_catch`), its level held fixed.

The force is the catch's at the element's own pressure,

    F_i = sign · p_e(x) · w_i(h) · n,     p_e = ρ_c g (h_1 + h_2 + h_3)/3,     h_j = x_j · a - s,

so the product rule gives the catch's stiffness at the fixed pressure p_e
(:func:`jaxnet.closed_form.pressure.catch_pressure_stiffness`) plus the derivative of the pressure,
∂p_e/∂x_j = ρ_c g a / 3 for every vertex j:

    K = -∂F/∂x = K_catch(p_e) - sign ρ_c g / 3 · (w_i n) a^T     (the same 3 × 3 block for every j),

entry (3 i + m, 3 j + n) of the second part -sign ρ_c g w_i n_m a_n / 3. Not symmetric (a follower load whose
pressure varies over the net, lumped per element); the level (a global state) is held fixed as the solver does.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.closed_form.pressure import catch_pressure_stiffness
from jaxnet.terms import gravity_catch, pressure


def gravity_catch_stiffness(x, specific_weight, front, axis, sign=1.0):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of :func:`jaxnet.terms.gravity_catch.gravity_catch_pressure`, level fixed.

    Args: as that function: x (3, 3) vertex positions (m), specific_weight ρ_c g (N/m³), front (the level's
      abscissa along ``axis`` in m, or a point of it), axis (3,) unit, pointing down, sign ±1.
    Returns: K (9, 9), vertex-major (entry (3 i + m, 3 j + n): force coordinate m on vertex i, position
      coordinate n of vertex j).
    """
    x = jnp.asarray(x)
    axis = jnp.asarray(axis)
    p = gravity_catch.element_pressure(x, specific_weight, front, axis)
    w = pressure.clipped_shape_integrals(pressure.front_heights(x, front, axis))
    n = geometry.surface_vector(x)
    load = (w[:, None] * n[None, :]).reshape(9)  # sign-free force per unit pressure, vertex-major
    pressure_part = jnp.tile(axis, 3) * (specific_weight / 3.0)  # ∂p_e/∂x, (9,)
    return catch_pressure_stiffness(x, p, front, axis, sign) - sign * jnp.outer(load, pressure_part)


def gravity_catch_on_element_stiffness(x, state, sign):
    """(9, 9) stiffness (N/m) of :func:`jaxnet.terms.gravity_catch.gravity_catch_on_element` (same arguments):
    the level of ``state`` held fixed."""
    return gravity_catch_stiffness(x, state["specific_weight"], state["front"], state["axis"], sign)
