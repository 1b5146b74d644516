"""Closed-form stiffness of the force of inertia (book eqs 4.269-4.271).

The force of :func:`jaxnet.terms.inertia.inertia_force`, F = M_a (γ_h - γ) + rho V γ_h - M γ (4.265), is
linear in the new position x through the backward-difference acceleration γ = (x - 2 x1 + x2)/Δt²
(4.268), and γ_h does not depend on x. So (4.269-4.270)

    K = -∂F/∂x = (M + M_a) ∂γ/∂x = (M + M_a)/Δt² I        (4.271),

the printed scalar of 4.271 times the 3 x 3 identity (a diagonal matrix when the added mass is given per
axis). It is what the implicit time step adds to the static tangent at every vertex. No singular point
for Δt > 0.

Units: masses in kg, time step in s, stiffness in N/m.
"""

from __future__ import annotations

import jax.numpy as jnp


def inertia_stiffness(x, x_previous, x_previous2, time_step, mass, added_mass, volume=0.0, water_density=0.0,
                      water_acceleration=0.0):
    """(3, 3) stiffness K = -∂F/∂x (N/m) of :func:`jaxnet.terms.inertia.inertia_force` with respect to the
    vertex's new position x: diag((M + M_a)/Δt²).

    Args: those of :func:`jaxnet.terms.inertia.inertia_force` (the same signature, so that the two paths
      are interchangeable); only ``time_step`` (s), ``mass`` (kg) and ``added_mass`` (kg, scalar or (3,)
      per axis) enter: the positions, the volume and the water acceleration do not.
    """
    dtype = jnp.result_type(x, time_step, mass, added_mass, float)
    diagonal = jnp.broadcast_to((mass + added_mass) / time_step**2, (3,)).astype(dtype)
    return jnp.diag(diagonal)
