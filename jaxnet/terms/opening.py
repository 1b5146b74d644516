"""Mesh opening stiffness: in-plane flexion of the twines at the knots (book eqs 4.211-4.219).

Angle convention. α is the *half* opening angle of the meshes (4.211): the angle between the twine
vectors U and V is 2α, so α = π/4 for square meshes, α → 0 for a mesh closed along the U + V diagonal
and α → π/2 for a mesh closed the other way (U and V antiparallel, the "fully open" limit of 2α = π).
The rest angle α0 is the same *half* angle of the unloaded netting: a net knitted with an angle θ0
between its twines (full angle, knot to knot) is given ``rest_angle = θ0 / 2``. α is computed with
:func:`jaxnet.geometry.half_opening_angle`, α = ½ atan2(|U ^ V|, U.V), rather than with the ½ acos of
4.211: acos has an infinite derivative at both limits, atan2 is accurate and finite everywhere.

The energy. At each knot the book puts a couple C_u = -C_v = H (α - α0) (4.212) on the U and V twines.
When α grows by ∂α, the U twine turns by ∂α and the V twine by -∂α about the bisector (the full angle
grows by 2∂α), so the work per knot is C_u ∂α - C_v ∂α = 2 H (α - α0) ∂α, the derivative of
H (α - α0)²; with |d|/2 knots in the element (4.27) that is Fx1 = H (α - α0) d ∂α/∂x1 of 4.216-4.217.
The vertex forces are therefore minus the gradient of

    E = (|d| / 2) H (α - α0)²          (J),

i.e. H (α - α0)² per knot, 2 H (α - α0)² per mesh (two knots per mesh). Writing E instead of the
forces gives the forces by ``jax.grad`` and the tangent stiffness 4.219 by ``jax.jacfwd``, symmetric by
construction; |d| makes clockwise triangles (d < 0) correct.

Limits. E is a function of the unsigned angle α ∈ [0, π/2]: for one element a "turned over" mesh
is the same mesh seen from the other side, so there is no sign to give it. Hence at closure (α = 0 or
π/2), with α0 strictly inside, E has a cone-shaped kink in the vertex positions: α grows whichever way
the mesh moves in its plane (dE/dα = -|d| H α0 at α = 0), and the stiffness grows like 1/|U ^ V| for
motions that turn V about U out of the plane. This is the book's model, not a numerical artefact; knot
contact (:mod:`jaxnet.terms.knot`) keeps real meshes away from it. At the exactly closed configuration
the derivative of |U ^ V| is taken as 0 (``geometry.safe_norm``), so energy, forces and stiffness are
finite there. A twine of zero length has no direction and carries no couple: the energy of such a
collapsed element is taken as 0.

Errata found in 4.211-4.219 (the mathematics above is what is implemented; tests/terms/test_opening.py checks
each): 4.214 with C_v = -C_u gives zero work, the V twine turns by -∂α; 4.215 is -d of 4.7; 4.218 has
sin(α) for sin(2α) (d acos(c)/dc = -1/sin(2α) when c = cos 2α), and its two u_i terms carry the same
sign where the derivative of U.V/(|U||V|) gives them opposite signs, as its two v_i terms have. With d of
4.7 in 4.217-4.218 and u_i, v_i the factors of 4.43-4.45, the force on the vertices is
F_wi = -H (α - α0) |d| ∂α/∂w_i = -∂E/∂w_i; 4.217 prints +H (α - α0) d ∂α/∂w_i, right only with the d
of 4.215.

Units: positions in m, H in N·m/rad, angles in rad, energy in J.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.term import ENERGY, ClosedForm, Term, any_nonzero, register

# |U|²|V|² below this (m⁴) is a collapsed twine: atan2(0, 0) has no derivative.
_COLLAPSED = 1e-200


def half_angle(x, uv):
    """Half opening angle α (rad, eq. 4.211) of the meshes of one triangle, with d and a validity flag.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
    Returns:
      (alpha, d, valid): α in [0, π/2] (0 where a twine vector has zero length), the signed determinant
      d of 4.7, and False where U or V has zero length (the angle is then undefined).
    """
    U, V, d = geometry.twine_vectors(x, uv)
    valid = jnp.sum(U * U) * jnp.sum(V * V) > _COLLAPSED
    # double where: the discarded branch must not see atan2(0, 0), whose derivative is NaN
    unit = jnp.array([1.0, 0.0, 0.0])
    alpha = geometry.half_opening_angle(jnp.where(valid, U, unit), jnp.where(valid, V, unit))
    return jnp.where(valid, alpha, 0.0), d, valid


def opening_energy(x, uv, stiffness, rest_angle):
    """Elastic energy (J) of the in-plane flexion of the twines of one diamond-mesh triangle.

    E = (|d|/2) H (α - α0)²: H (α - α0)² per knot, |d|/2 knots (see the module docstring).

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
      stiffness: mesh opening stiffness H (N·m/rad): the couple per knot per radian of *half* angle.
      rest_angle: rest half opening angle α0 (rad), in [0, π/2]; π/4 for square unloaded meshes, half
        the angle between the twines of the unloaded netting in general.
    """
    alpha, d, valid = half_angle(x, uv)
    return jnp.where(valid, geometry.knot_count(d) * stiffness * (alpha - rest_angle) ** 2, 0.0)


def opening_couple(x, uv, stiffness, rest_angle):
    """Couple per knot C_u = H (α - α0) (N·m, eq. 4.212), positive when the mesh is more open than at rest."""
    alpha, _, valid = half_angle(x, uv)
    return jnp.where(valid, stiffness * (alpha - rest_angle), 0.0)


def netting_parameter_activity(name):
    """The activity rule of a netting term set by one parameter: present where the netting has it, not zero."""

    def active(scene, dynamic):
        net = scene.netting
        return {} if net is not None and any_nonzero(getattr(net, name)) else None

    return active


MESH_OPENING = register(Term(
    name="mesh_opening", family="netting", kind=ENERGY, element=opening_energy,
    arguments=lambda p, env: {"uv": p.uv, "stiffness": p.opening_stiffness, "rest_angle": p.rest_angle},
    active=netting_parameter_activity("opening_stiffness"), elastic=True,
    closed_form=ClosedForm("jaxnet.closed_form.opening:opening_stiffness")))
