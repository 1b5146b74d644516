"""A tarp: an impermeable panel, loaded by the current as a pressure instead of twine drag (FEMNET's
``input tarp PANEL``).

The water cannot flow through a tarp (a canvas, a sheet of plastic, a panel with a blinder sewn on), so
the Morison drag of its twines (:mod:`jaxnet.terms.drag`) does not describe it. FEMNET loads each
triangle of a tarp panel with a uniform pressure on its whole surface,

    p = C ½ ρ |c|²                                      (Pa)
    F_i = -sign(d) (p / 3) (12 ^ 13)/2,   i = 1, 2, 3   (N)

c the velocity of the water relative to the triangle (the current at its centroid in statics; per
vertex, relative to the vertex, in dynamics, as the netting drag), ρ the water density, C the tarp's
pressure coefficient (``Twine.tarp_cd``), (12 ^ 13)/2 the triangle's area vector (m², length its surface
S) and d its twine determinant (eq. 4.7). Each vertex takes a third of p S.

FEMNET's law, as its static solver computes it (``dpriour/femnet``, ``unix_2004/``):

* ``chargement_don.c`` reads ``input tarp PANEL`` into ``panneau[PANEL].tarp = 1``; ``lectureDo4.c``
  copies it onto every triangle of the panel (``Surface[i].tarp``).
* ``unix.c``: a case with a tarp skips the twine drag of the netting (``filethydro4_sta``, called only when
  there is no tarp, no catch, ...) and calls ``catch_hexa()`` then ``trainee_front()``, as a case with a
  catch does.
* ``catch_hexa.c``, ``pres_pris_elem2`` (via ``pression_prise3``): a tarp triangle gets the pressure
  ``pression * surface`` along the normal of its vertex order, ``-force/3`` per vertex in the frame
  (``rotation4``) where 12 ^ 13 is vertical, turned back by ``base1``: F_i = -p (12 ^ 13)/6, the same as
  ``pression_totale``. The pressure is the catch's, ``Prise.cd * ½ RHO * V²`` (``pression_prise3``):
  C is the case's "Drag coefficient on this volume", not a panel's twine Cd. It applies on the tarp's
  whole surface, whatever the catch front, and whether or not there is a catch (volume 0 in 14tarp/c2).
  Triangles that are not tarps keep the catch pressure behind the front only (``Surface[elem].tarp == 0``).
* ``trainee_front.c``: only triangles with ``tarp == 0`` get twine drag: a tarp has none.
* There is no angle in the law: a tarp lying along the current (14tarp/c2, a tube along it) is pushed as
  hard as one facing it. The pressure acts on the side -sign(d) (12 ^ 13); FEMNET's mesher orders its
  triangles so that d > 0 (4.7), so that is -(12 ^ 13), the side of -(U ^ V) in jaxnet's twine frame
  (12 ^ 13 = d U ^ V), whatever a mesher's vertex order.

jaxnet keeps the law as it is, angle-free, so that a ``.don`` case gives FEMNET's answer. It is the
stagnation pressure of the flow on the upstream face of a sheet held across it (C of order 1-1.4), and
the pressure a catch pushes with: a model of a tarp *closing* a cod-end or a gear, where the water inside
is brought to rest. A tarp in open flow at an angle would see less; a law with the angle (C cos² θ, or
a flat plate's) would need a reference to fit, and FEMNET gives none. The side is fixed by the panel's
twine frame, not by the flow: flip the panel's V coordinates to push the other way.

With both a catch (a volume above its accuracy) and a tarp, FEMNET's ``unix.c`` calls ``catch_hexa()`` and
``trainee_front()`` twice, once for the catch and once for the tarp, which doubles the catch pressure, the
tarp pressure and the netting drag ahead of the front; jaxnet applies each once. (Read in the code only: the
corpus's tarp cases, 14tarp/c2, 14tarp/s3_catch and 15grid/trawl_1, all have a catch volume of 0.)

Closed form (:mod:`jaxnet.closed_form.tarp`): F is p(x) times the area vector n(x) = (12 ^ 13)/2 over 3;
its stiffness is -(s/3) [p ∂n/∂x_j + n ∂p/∂x_j], with ∂n/∂x_j the skew matrix of ½ (x_{j-1} - x_{j+1})
(as the catch pressure's) and ∂p/∂x_j = C ρ (c · dc/dz) up/3 in a current varying with depth (0 in a
uniform one). Like the catch pressure it is a follower load: the element matrix is not symmetric.

Units: positions in m, velocities in m/s, density in kg/m³, pressure in Pa, forces in N.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.drag import per_vertex, water_velocity
from jaxnet.terms.term import CATCH, FORCE, ClosedForm, Term, any_nonzero, flowing, moving_options, register


def tarp_side(uv):
    """-sign(d) (dimensionless, ±1): the tarp is pushed along sign · (12 ^ 13), i.e. towards -(U ^ V)
    (FEMNET: -(12 ^ 13) on triangles meshed with d > 0). ``uv``: (3, 2) twine coordinates."""
    return -jnp.sign(geometry.twine_determinant(uv))


def tarp_pressure(x, uv, pressure_coefficient, water_velocity, water_density):
    """Nodal forces (3, 3) in N of the current on one tarp triangle: F_i = -sign(d) (p/3) (12 ^ 13)/2 with
    p = C ½ ρ |c|² (module docstring).

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (only the sign of d is used: the side pushed).
      pressure_coefficient: C (dimensionless); 0 for netting the water flows through.
      water_velocity: (3,) velocity c of the water relative to the triangle (m/s).
      water_density: ρ (kg/m³).
    """
    p = pressure_coefficient * 0.5 * water_density * jnp.dot(water_velocity, water_velocity)
    return jnp.broadcast_to((tarp_side(uv) * p / 3.0) * geometry.surface_vector(x), (3, 3))


def tarp_pressure_on_element(x, state, uv, tarp_cd, env, moving=False, waves=False, velocity=None):
    """:func:`tarp_pressure` of one netting triangle of pressure coefficient ``tarp_cd``: at the current at its
    centroid in statics; in dynamics (``moving``) each vertex takes its third with the water's velocity
    relative to it (:func:`jaxnet.terms.drag.per_vertex`), as the netting drag does."""
    def force(c):
        return tarp_pressure(x, uv, tarp_cd, c, env.water_density)

    return per_vertex(force, x, env, velocity, waves) if moving else force(water_velocity(x, env))


def _active(scene, dynamic):
    net = scene.netting
    if net is None or not flowing(scene, dynamic) or not any_nonzero(net.tarp_cd):
        return None
    return moving_options(scene, dynamic)


TARP_PRESSURE = register(Term(
    name="tarp_pressure", family="netting", kind=FORCE, element=tarp_pressure_on_element,
    arguments=lambda p, env, **motion: {"uv": p.uv, "tarp_cd": p.tarp_cd, "env": env, **motion},
    active=_active, group=CATCH, moving=True,
    closed_form=ClosedForm("jaxnet.closed_form.tarp:tarp_pressure_on_element_stiffness",
                           covers=lambda options: not options.get("moving", False))))
