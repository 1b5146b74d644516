"""Closed-form stiffness of the pressure of the current on a tarp (:mod:`jaxnet.terms.tarp`), in statics.

The force on each vertex of a tarp triangle is

    F_i = (s/3) p n,     n = (12 ^ 13)/2,     p = C ½ ρ |c|²,     s = -sign(d),

c the current at the triangle's centroid (it varies with the centroid's height z = x̄ · up in a current
profile). The product rule gives

    ∂F_i/∂x_j = (s/3) [ p ∂n/∂x_j + n (∂p/∂x_j)^T ],       K = -∂F/∂x (4.46),

* ∂n/∂x_j: the skew matrix of ½ (x_{j-1} - x_{j+1}) (indices mod 3), the derivative of the cross product
  (:func:`jaxnet.closed_form.pressure.surface_vector_jacobian`, the book's 4.255);
* ∂p/∂x_j = C ρ (c · dc/dz) up / 3: the centroid moves by a third of vertex j's move. Zero in a uniform
  current, where K is the catch pressure's p ∂n/∂x (FEMNET's ``pression_totale``) times s/3.

The same matrix for the three rows of vertices (the force is the same on each). Not symmetric: a follower
load. Only statics: in a time step the term keeps its autodiff stiffness (its declaration says so).
Units: N/m.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.closed_form.drag_elements import water_at_centroid
from jaxnet.closed_form.pressure import surface_vector_jacobian
from jaxnet.terms.tarp import tarp_side


def tarp_pressure_stiffness(x, uv, pressure_coefficient, water_velocity, water_density, slope=None, up=None):
    """(9, 9) stiffness K = -∂F/∂x (N/m) of :func:`jaxnet.terms.tarp.tarp_pressure`, vertex-major.

    Args: as :func:`jaxnet.terms.tarp.tarp_pressure` (x (3, 3) m, uv (3, 2), C, c (3,) m/s at the centroid,
      ρ kg/m³); ``slope`` (3,) dc/dz of the current at the centroid (1/s) and ``up`` (3,) the unit vertical,
      or None for a uniform current.
    """
    x = jnp.asarray(x)
    s = tarp_side(uv)
    p = pressure_coefficient * 0.5 * water_density * jnp.dot(water_velocity, water_velocity)
    n = geometry.surface_vector(x)
    dn = surface_vector_jacobian(x)  # [j, m, k]: ∂n_m/∂x_jk
    dF_row = p * jnp.transpose(dn, (1, 0, 2))  # [m, j, k]
    if slope is not None:
        dp = pressure_coefficient * water_density * jnp.dot(water_velocity, slope) * up / 3.0  # (3,), same for each j
        dF_row = dF_row + n[:, None, None] * dp[None, None, :]
    dF = jnp.broadcast_to((s / 3.0) * dF_row, (3, 3, 3, 3))  # [i, m, j, k]
    return -dF.reshape(9, 9)


def tarp_pressure_on_element_stiffness(x, state, uv, tarp_cd, env):
    """(9, 9) stiffness (N/m) of :func:`jaxnet.terms.tarp.tarp_pressure_on_element` in statics (same
    arguments): the current at the centroid, with its slope over depth when it varies."""
    c, slope = water_at_centroid(x, env)
    return tarp_pressure_stiffness(x, uv, tarp_cd, c, env.water_density, slope, env.up)
