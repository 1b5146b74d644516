"""Weight and buoyancy (book eq. 4.277) of netting, cable bars and lumped node masses.

Immersed weight acts along -``up`` (the unit vertical, z by default). For one netting triangle it is
(4.277), with |d| the number of U plus V twine vectors of the element:

    W = |d| (pi D² / 4) l0 (rho_netting - rho_water) g        (N),

the twine length taken as the unstretched l0 as in the book. W is split one third per vertex; a bar's
weight (pi D²/4) L0 (rho_bar - rho_water) g is split one half per end; a node of mass m (kg) and
displaced volume Vol (m³) weighs (m - rho_water Vol) g. A negative weight is buoyancy (floats).

These loads do not depend on the positions of a fully immersed net, so they enter the residual as a
constant vector and contribute nothing to the tangent stiffness (the book notes the exception of a net
crossing the free surface, which is a separate term).
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry


def netting_weight(uv, l0, diameter, density, water_density, g, up):
    """Per-vertex immersed weight (3, 3) in N of one triangle: one third of eq. 4.277 on each vertex."""
    d = geometry.twine_determinant(uv)
    w = jnp.abs(d) * jnp.pi * diameter**2 / 4.0 * l0 * (density - water_density) * g
    return jnp.broadcast_to(-(w / 3.0) * up, (3, 3))


def bar_weight(rest_length, diameter, density, water_density, g, up):
    """Per-end immersed weight (2, 3) in N of one cable bar, half on each end."""
    w = jnp.pi * diameter**2 / 4.0 * rest_length * (density - water_density) * g
    return jnp.broadcast_to(-(w / 2.0) * up, (2, 3))


def node_weight(mass, volume, water_density, g, up):
    """Immersed weight (3,) in N of a lumped node mass (kg) displacing ``volume`` (m³)."""
    return -((mass - water_density * volume) * g) * up
