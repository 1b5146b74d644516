"""The gravity catch: a catch weighing on a netting bag out of the water (FEMNET's ``input catch_gravity``).

FEMNET's manual (chapter "Gravity catch", case 13gravity_catch/g1): a catch "which presses on the netting bag by
its own weight", the netting being out of the water (fish on deck, or bags of water as in O'Neill 1997). The catch
lies below a horizontal surface, its level, placed so that the catch volume (the CATCH DESCRIPTION's volume and
accuracy, as for any catch) is enclosed by the netting below it. This module is that law as FEMNET's static solver
computes it (source files of ``unix_2004/`` in FEMNET's repository):

* ``chargement_don.c`` reads ``input catch_gravity RHO_C`` into ``Prise.catch_gravity`` (kg/m³); the statics call
  the catch (``catch_hexa``) when the catch volume exceeds its accuracy, with either law, and a gravity catch
  replaces the dynamic one (``Prise.catch_gravity > 0``).
* ``prise.c``, ``changement_variable_catch``: with a gravity catch the catch's axis is the vertical downward (its
  abscissa is -z), instead of the current's direction. The level is then found by the catch's own front search
  (``surface_volume2``, ``nouveau_front2``) on that axis: the same volume law as a catch in a current
  (:mod:`jaxnet.model.catch`, axis a = -up, front abscissa s = -level).
* ``prise.c``, ``pression_prise3``: each netting triangle takes the uniform pressure

      p_e = ρ_c g (h_1 + h_2 + h_3) / 3        (Pa),     h_i = x_i · a - s = level - z_i,

  ρ_c g times the depth below the level of the centroid of the *whole* triangle (FEMNET's G = 9.81 m/s²), and
  ``pres_pris_elem2`` puts it on the part of the triangle below the level as the catch in a current does
  (:func:`jaxnet.terms.pressure.catch_pressure`: the consistent load of a uniform pressure on the clipped part):

      F_i = sign · p_e · w_i(h) · (12 ^ 13)/2,

  w_i the clipped shape integrals (1/3 each for a triangle wholly below the level). No water acts on the catch
  (no buoyancy: the bag is out of the water), and the catch has no drag (``Prise.cd`` is not used).

What this law is, against exact hydrostatics. On a triangle wholly below the level, ∫ ρ_c g h n dS = p_e S n
exactly (h is linear), so its total force is the exact hydrostatic one; FEMNET shares it equally between the three
vertices where the consistent load would give the deeper ones more ((2 h_i + h_j + h_k)/12 of the integral). On a
triangle the level cuts, the pressure is that of the whole triangle's centroid, not of the part below (it is even
negative, a suction, when that centroid is above the level). So the resultant of the catch on a net that holds it
is ρ_c g V (its weight) exactly when no triangle is cut — e.g. at a level through a row of nodes — and otherwise up
to the cut triangles' error, which vanishes as the mesh is refined. Measured with FEMNET's own meshes and
equilibria (13gravity_catch/g1 and g2, ``.mdg`` and ``.sta``; ρ_c g V = 259.97 N): this law gives 268.14 N on g1's
coarse bag (+3.1 %) and 260.48 N on g2's fine one (+0.2 %), and with the twines' buoyancy (5.89 N up, which FEMNET
counts out of the water too: ``flotteursurf3.c``) FEMNET's printed forces on the fixings, 262.27 N and 254.60 N, to
0.01 %; the levels (9.025 m, 8.869 m), thicknesses and diameters are FEMNET's too. jaxnet follows FEMNET's law, to
give FEMNET's answers; :func:`hydrostatic_resultant` is the exact one.

The force is continuous in the positions (p_e is linear in them, w_i continuous; see
:mod:`jaxnet.terms.pressure`), and, like the catch in a current, a follower load whose level (the front) is a
global state of the net held fixed in the tangent. The closed-form stiffness
(:mod:`jaxnet.closed_form.gravity_catch`) adds to the catch's stiffness at pressure p_e the derivative of p_e:
∂p_e/∂x_j = ρ_c g a / 3 for each vertex j.

Units: m, kg/m³, N/m³ (specific weight ρ_c g), Pa, N.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms import pressure
from jaxnet.terms.term import FORCE, ClosedForm, Group, Term, register

#: the result group of the gravity catch: the weight of the catch on the net (not a hydrodynamic force: it does
#: not count in a towed gear's resistance)
CATCH_WEIGHT = Group("catch_weight_N")


def element_pressure(x, specific_weight, front, axis):
    """FEMNET's pressure p_e (Pa) on one triangle: ρ_c g (``specific_weight``, N/m³) times the depth below the
    level of the triangle's centroid, (h_1 + h_2 + h_3)/3 with h_i = x_i·axis - s (negative when the centroid is
    above the level). ``front``: the level as the abscissa s along ``axis`` (m, = -level for axis = -up) or a
    point (3,) of it; ``axis``: (3,) unit, pointing down."""
    return specific_weight * jnp.mean(pressure.front_heights(x, front, axis))


def gravity_catch_pressure(x, specific_weight, front, axis, sign=1.0):
    """Nodal forces (3, 3) in N of a gravity catch on one triangle (module docstring).

    Args:
      x: (3, 3) vertex positions (m).
      specific_weight: ρ_c g of the catch (N/m³).
      front: the catch's level: abscissa s along ``axis`` (m) or a point (3,) of the level plane.
      axis: (3,) unit vector pointing down (-up): positions deeper below the level have larger x·axis.
      sign: +1 when 12 ^ 13 points out of the bag, -1 into it (as :func:`jaxnet.terms.pressure.catch_pressure`).
    Returns:
      F (3, 3), row i the force on vertex i: sign · p_e · w_i · (12 ^ 13)/2, p_e = :func:`element_pressure`.
    """
    p = element_pressure(x, specific_weight, front, axis)
    return pressure.catch_pressure(x, p, front, axis, sign)


def hydrostatic_resultant(x, specific_weight, front, axis, sign=1.0):
    """The exact hydrostatic force (3,) in N on the part of one triangle below the level, ∫ ρ_c g h⁺ n dS
    (n the outward unit normal): what :func:`gravity_catch_pressure` sums to on a triangle wholly below the level,
    and what it approximates on a cut one. With w_i the clipped shape integrals and h linear, ∫_{h>0} h dS is
    S Σ_i w_i h_i."""
    h = pressure.front_heights(x, front, axis)
    w = pressure.clipped_shape_integrals(h)
    return (sign * specific_weight * jnp.dot(w, h)) * geometry.surface_vector(x)


# -- the term --------------------------------------------------------------------------------------


def gravity_catch_on_element(x, state, sign):
    """:func:`gravity_catch_pressure` of one triangle at the level and specific weight of ``state``
    (:func:`jaxnet.model.catch.catch_state`)."""
    return gravity_catch_pressure(x, state["specific_weight"], state["front"], state["axis"], sign)


def _active(scene, dynamic):
    c = scene.catch
    if c is None or scene.netting is None or not c.density > 0:
        return None
    return {}


GRAVITY_CATCH = register(Term(
    name="gravity_catch", family="netting", kind=FORCE, element=gravity_catch_on_element,
    arguments=lambda p, env: {"sign": p.outward}, active=_active, group=CATCH_WEIGHT, state="jaxnet.model.catch:catch_state",
    closed_form=ClosedForm("jaxnet.closed_form.gravity_catch:gravity_catch_on_element_stiffness")))
