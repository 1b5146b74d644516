"""Force of inertia on a vertex, for an implicit time step (book §4.3.7, eqs 4.265-4.271).

The book computes the inertia per vertex, each vertex of a triangle carrying one third of the element's
netting: its mass M, displaced volume V and added mass M_a (4.265's "of 1/3 of the triangular element";
summed over the elements that share a node). Its force on the vertex (4.265) is

    F = M_a (γ_h - γ) + rho V γ_h - M γ        (N),

γ the acceleration of the vertex and γ_h that of the water around it (m/s²), rho the water density: the
Morison form of the fluid force (Froude-Krylov rho V γ_h plus added mass M_a (γ_h - γ)) with the
vertex's own inertia -M γ moved to the force side (d'Alembert), so that a time step solves
"sum of forces = 0" with the static solver. For a water at rest or a steady current (γ_h = 0) it is
-(M + M_a) γ.

The scheme is implicit (backward differences, 4.266-4.268): at the new time t the position x is the
unknown and the two previous positions x1 (t - Δt) and x2 (t - 2 Δt) are known, and

    γ = (x - 2 x1 + x2) / Δt²        (4.268),

the second backward difference, first-order accurate (γ = x''(t) - Δt x'''(t) + O(Δt²)) and exact for a
uniform acceleration. (The printed 4.266 and 4.267 each have the opposite sign, v = (x1 - x)/Δt: the two
signs cancel in 4.268, which is right; see the errata.) The force is linear in x, so the tangent
stiffness is constant (4.269-4.271):

    K = -∂F/∂x = (M + M_a) ∂γ/∂x = (M + M_a)/Δt² I        (N/m),

the scalar of the printed 4.271 times the 3 x 3 identity: no coupling between the coordinates or between
the vertices (the water acceleration γ_h does not depend on x). The closed form is
:func:`jaxnet.closed_form.inertia.inertia_stiffness`.

The book gives no formula for the added mass; it is a parameter here (a scalar, or one value per axis
for a direction-dependent one). :func:`netting_vertex_mass` gives M and V of one third of a triangle of
netting, with the twine volume of the weight 4.277.

Units: positions in m, time step in s, masses in kg, volume in m³, density in kg/m³, accelerations in
m/s², forces in N.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry


def vertex_acceleration(x, x_previous, x_previous2, time_step):
    """Backward-difference acceleration γ = (x - 2 x1 + x2)/Δt² (m/s², eq. 4.268) of positions x at t,
    x_previous at t - Δt and x_previous2 at t - 2 Δt (m, any shape (..., 3)), time step Δt (s)."""
    return (x - 2.0 * x_previous + x_previous2) / time_step**2


def inertia_force(x, x_previous, x_previous2, time_step, mass, added_mass, volume=0.0, water_density=0.0,
                  water_acceleration=0.0):
    """Force of inertia (3,) in N on one vertex at the new time step (eq. 4.265 with 4.268).

    Args:
      x: (3,) position of the vertex at the new time t (m), the unknown of the implicit step.
      x_previous, x_previous2: (3,) its positions at t - Δt and t - 2 Δt (m).
      time_step: Δt (s).
      mass: M, the netting mass carried by the vertex (kg).
      added_mass: M_a (kg), scalar or (3,) per axis.
      volume: V, the volume of netting carried by the vertex (m³); with ``water_density`` rho (kg/m³)
        it gives the Froude-Krylov force rho V γ_h.
      water_acceleration: γ_h (3,) or scalar, the acceleration of the water around the vertex (m/s²);
        0 in water at rest or a steady current.
    Returns:
      M_a (γ_h - γ) + rho V γ_h - M γ, γ = (x - 2 x_previous + x_previous2)/Δt².
    """
    gamma = vertex_acceleration(x, x_previous, x_previous2, time_step)
    return added_mass * (water_acceleration - gamma) + (water_density * volume) * water_acceleration - mass * gamma


def inertia_energy(x, x_previous, velocity, time_step, mass):
    """The potential (J) whose gradient is minus the force of inertia -(M + M_a) γ of the implicit step:

        E = (M + M_a)/(2 Δt²) |x - x_previous - Δt v_previous|²,    γ = (x - x_previous - Δt v_previous)/Δt²,

    with v_previous = (x_previous - x_previous2)/Δt the velocity of the last step, so that γ is 4.268's
    (x - 2 x1 + x2)/Δt² for a constant step; written with the velocity, it also holds when the step
    changes (a step retried with a smaller Δt). Its Hessian is 4.271's (M + M_a)/Δt² per axis. Added to
    the net's stored energy it lets the static Newton iteration, with its energy line search, solve the
    time step.

    Args (any leading shape, last axis 3): x, x_previous (m); velocity (m/s); time_step Δt (s); mass
      M + M_a (kg), broadcast against x (per node and axis).
    """
    gap = x - x_previous - time_step * velocity
    return 0.5 * jnp.sum(mass * gap * gap) / time_step**2


def netting_vertex_mass(uv, l0, diameter, density):
    """(mass in kg, volume in m³) of the netting carried by each vertex of one triangle: one third of the
    element's |d| twine vectors of length l0 (m) and diameter D (m), |d| π D²/4 l0 / 3 (the twine volume
    of the weight 4.277), times the netting ``density`` (kg/m³) for the mass. uv: (3, 2) twine
    coordinates."""
    volume = geometry.twine_volume(jnp.abs(geometry.twine_determinant(uv)), l0, diameter) / 3.0
    return density * volume, volume
