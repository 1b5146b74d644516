"""Contact with the sea bed (and any floor or ceiling along a coordinate axis), the friction of a bottom
sliding under a towed gear, and in time the bed's friction on a net moving over it: FEMNET's node limits and
"BOTTOM SEA ENVIRONMENT".

What FEMNET does (statics, ``unix_2004/fond.c``, function ``fond``; data from ``chargement_don.c``:
per node type "Limits X,Y,Z" and "Limits sense X,Y,Z", then "Wearing coefficient on the bottom" and
"Stiffness of the insertion in the sea bottom (N/m)"; ``initialisation.c`` copies them per coordinate).
For every coordinate x_i of every node, with limit L_i and sense s_i:

    s_i = +1 and x_i < L_i  (below a floor):   F_i += k (L_i - x_i),   K_ii += k
    s_i = -1 and x_i > L_i  (above a ceiling): F_i += k (L_i - x_i),   K_ii += k

a linear penalty of stiffness k (N/m), on any axis, in either sense; s_i = 0 is no limit. Friction is
added only with the ``.don`` command ``input moving_bottom`` ("the bottom is moving at the water speed",
FEMNET's default is a still bottom and no friction), only on a floor along z (s_z = +1, z up), only in a
current; for such a node below its floor

    F_x += mu k (L_z - z) cos(theta),   F_y += mu k (L_z - z) sin(theta),

theta the current's direction in the horizontal plane: kinetic friction mu times the normal reaction,
along the current. In FEMNET's frame the net is still and the water flows past it at the towing speed,
so a towed gear's sea bed also slides under it, in the current's direction: the friction it exerts on
the net pulls the net *with* the current (it opposes the gear's motion over the ground). It is not
capped and has no static branch: the bottom always slides, so the friction is always fully developed.
jaxnet's statics add it where ``Environment.bottom_moving`` (the default; FEMNET's reader sets it from ``input
moving_bottom``) and ``bottom_friction`` > 0.

Here the same physics, written as an energy and a force:

* Contact is an *energy* ``bottom_stiffness * g(p)`` per limited coordinate, p = s (L - x) the
  penetration (m), so that its force is -grad and its stiffness the Hessian, by autodiff.
* FEMNET's penalty is k p₊²/2: C¹, its stiffness jumps from 0 to k when a node touches. A Newton step
  computed on one side of the contact is then wrong on the other, and nodes hovering at the sea bed flip
  in and out of contact from one iteration to the next (chatter) -- with k = 1e6 N/m against netting
  stiffnesses of 1-100 N/m, a node crossing the limit by a micron changes its force by a newton. So here

      g(p) = 0                                p <= 0
      g(p) = 2 p³ / (3 b) - p⁴ / (4 b²)        0 < p < b
      g(p) = p² / 2 - b² / 12                 p >= b,

  a C² function (g, g', g'' continuous): the contact force k g'(p) = k (2 p²/b - p³/b²) rises with a
  stiffness k g''(p) that grows continuously from 0 to k across the band b (peaking at 4k/3 at p = 2b/3),
  and *beyond the band it is FEMNET's k p exactly*, with FEMNET's stiffness k. Why this blend rather than
  the offset one of :mod:`jaxnet.terms.knot` (s³/(3b), then (s - b/2)²): here every contact loaded beyond
  k b sits at FEMNET's penetration W/k exactly, so results match FEMNET's wherever contact is firm; inside
  the band the force is at most 4 b k / 27 below FEMNET's (g'(p) - p = -p (1 - p/b)²), so a lightly
  loaded node sits deeper than FEMNET's by less than b. ``bottom_band`` = 0 gives FEMNET's penalty. Why a
  band: on a slack panel sagging onto a stiff floor, Newton converges in markedly fewer iterations with a
  band of 1 mm than with FEMNET's jump, which with k = 1e7 N/m may not converge at all. Hence the default
  b = 1 mm (:class:`jaxnet.scene.Environment`), well below mesh sizes and the uncertainty on where a soft
  sea bed is; on well-held nets with few contacts the band makes no difference to the iteration count.
* Friction is a non-conservative *force* (its work depends on the path), ``mu k g'(p) t`` on every node
  pressed against the sea bed, t the unit current direction projected on the sea-bed plane. It is
  continuous in the positions (it is proportional to the normal reaction, which is), with the same
  C¹ force / continuous tangent as the contact; its direction is fixed, so there is no sign(velocity)
  discontinuity to smooth in statics. Its tangent -dF/dx has the entries (-mu k g''(p) t) in the rows of
  the horizontal axes and the column of the vertical one; FEMNET puts the y one in row x, column y
  (``ze[3*zi-2][eca+1]``, pardiso ``(3*zi-2, 3*zi-1)``): a misplaced entry, harmless for a current along
  x (sin = 0), which slows its convergence otherwise; autodiff gets it right.

In time (FEMNET's ``dyna``, ``dyna2/fond_dyn.c``) the sea bed rubs every node pressed against it, whatever
``moving_bottom`` says: a Coulomb friction mu k (L_z - z) against the node's velocity v, -mu N v/|v| above a
sliding speed V_l = 5 mm/s and -mu N v/V_l below it. Here (:func:`bed_friction_force`) it opposes the node's
velocity relative to the bed along the bed's plane, v_r = v - v_bed with its normal part removed (v_bed the
current's velocity where the bed slides, ``Environment.bottom_moving``, else 0), as

    F = -mu N v_r / sqrt(|v_r|² + V_l²),

which is FEMNET's to O(V_l²/|v_r|²) when sliding and the same viscous slope mu N/V_l at rest, but smooth: its
derivative, which the implicit step's tangent holds (the velocity is (x - x_n)/Δt), has no jump at V_l. Two
differences from FEMNET, by choice: the friction acts along the bed only (FEMNET's also opposes the vertical
velocity of a node sinking into the bed, which is the penalty's business), and a sliding bed is friction against
the velocity relative to it (FEMNET adds its static pull along the current to the friction against the
velocity over the ground). At rest on a sliding bed it is the static friction above to O(V_l²/U²): a run in
time starts from a static equilibrium without a jump. In statics this term is absent (the net does not move).

Generalisation beyond FEMNET: FEMNET's friction uses the current's heading (its current is horizontal)
and acts only on floors along z with z up. Here the sea bed is the limit along the coordinate axis of
``up`` with the sense that forbids going down (see :func:`jaxnet.scene.bottom_axis`), and t is the
current direction with its component along that axis removed (the same as FEMNET's heading for a
horizontal current). Limits on other axes, and ceilings, have contact but no friction, as in FEMNET.

Units: positions and limits in m, stiffness in N/m, energies in J, forces in N.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxnet import scene as scene_lib
from jaxnet.terms.term import BOTTOM, ENERGY, FORCE, Term, any_nonzero, has_current, register


def penetration(x, limit, sense):
    """(3,) penetration (m) of a node beyond its limits: s (L - x), > 0 on the forbidden side, 0 on axes
    without limit.

    Args:
      x: (3,) node position (m).
      limit: (3,) limit coordinates (m); unused (may be anything finite or not) where sense is 0.
      sense: (3,) +1 (floor: x must stay >= L), -1 (ceiling: x <= L) or 0 (no limit).
    """
    limited = sense != 0
    safe_limit = jnp.where(limited, limit, 0.0)  # a NaN limit where there is none must not leak
    return jnp.where(limited, sense * (safe_limit - x), 0.0)


def contact_penalty(p, band):
    """The C² penalty g(p) (m²) of the module docstring: 0 for p <= 0, p²/2 - b²/12 beyond the band.

    Args:
      p: penetration (m).
      band: width b >= 0 (m) over which the stiffness rises; 0 gives FEMNET's p₊²/2.
    """
    b = jnp.where(band > 0.0, band, 1.0)  # the band branch is never selected when band = 0
    ramp = p**3 * (2.0 / (3.0 * b)) - p**4 / (4.0 * b * b)
    full = 0.5 * p * p - band * band / 12.0
    return jnp.where(p <= 0.0, 0.0, jnp.where(p < band, ramp, full))


def contact_force(p, band):
    """g'(p) (m): the contact force per unit stiffness, 2p²/b - p³/b² in the band, p beyond it, 0 outside."""
    b = jnp.where(band > 0.0, band, 1.0)
    ramp = p * p * (2.0 / b) - p**3 / (b * b)
    return jnp.where(p <= 0.0, 0.0, jnp.where(p < band, ramp, p))


def contact_energy(x, limit, sense, stiffness, band):
    """Energy (J) of one node's contacts with its limits: stiffness * sum over axes of g(p_i).

    Args:
      x: (3,) node position (m).
      limit: (3,) limit coordinates (m). sense: (3,) +1 floor, -1 ceiling, 0 none.
      stiffness: penetration stiffness k (N/m).
      band: width (m) of the stiffness rise (see :func:`contact_penalty`).
    """
    return stiffness * jnp.sum(contact_penalty(penetration(x, limit, sense), band))


def sliding_direction(current_direction, axis):
    """(3,) unit direction in which a moving sea bed (normal to coordinate ``axis``) slides: the current's
    direction without its component along the axis; zero for a current along the axis.

    Args:
      current_direction: (3,) direction of the current (any length).
      axis: index 0, 1 or 2 of the sea bed's normal (a Python int).
    """
    t = jnp.asarray(current_direction, dtype=float).at[axis].set(0.0)
    length_sq = jnp.dot(t, t)
    has = length_sq > 0.0
    return t * jnp.where(has, 1.0 / jnp.sqrt(jnp.where(has, length_sq, 1.0)), 0.0)


def friction_force(x, limit, sense, stiffness, band, friction, direction, axis, floor):
    """Friction (3,) in N of a bottom sliding in ``direction`` on a node pressed against it:
    mu k g'(p) t, p the penetration beyond the floor along ``axis`` (zero if that limit is not a floor).

    Args:
      x: (3,) node position (m). limit: (3,) limits (m). sense: (3,) limit senses.
      stiffness: k (N/m). band: width of the stiffness rise (m). friction: mu (dimensionless).
      direction: (3,) unit sliding direction of the bottom (:func:`sliding_direction`).
      axis: the sea bed's axis (Python int); floor: the sense of a floor along it (+1 if up is +axis).
    """
    p = penetration(x, limit, sense)[axis]
    on_floor = sense[axis] == floor
    normal = stiffness * contact_force(jnp.where(on_floor, p, 0.0), band)
    return (friction * normal) * direction


#: V_l (m/s): the sliding speed of FEMNET's sea-bed friction in time, below which its friction is viscous
#: (``fond_dyn.c``); here the speed scale of its smooth form (:func:`bed_friction_force`)
SLIDING_SPEED = 0.005


def bed_friction_force(x, velocity, limit, sense, stiffness, band, friction, bed_velocity, axis, floor):
    """Friction (3,) in N of the sea bed on a node moving over it (a time step): -mu N v_r/sqrt(|v_r|² + V_l²),
    N = k g'(p) the normal reaction, v_r the node's velocity relative to the bed along the bed's plane (module
    docstring), V_l = :data:`SLIDING_SPEED`.

    Args:
      x: (3,) node position (m). velocity: (3,) its velocity (m/s). limit, sense, stiffness, band, friction,
        axis, floor: as :func:`friction_force`'s.
      bed_velocity: (3,) velocity of the bed (m/s): the current's where it slides, 0 where it is still.
    """
    v = (velocity - bed_velocity).at[axis].set(0.0)
    resisting = -v / jnp.sqrt(jnp.dot(v, v) + SLIDING_SPEED**2)
    return friction_force(x, limit, sense, stiffness, band, friction, resisting, axis, floor)


# -- the terms -------------------------------------------------------------------------------------


def _contact(x, limit, sense, stiffness, band):
    return contact_energy(x[0], limit, sense, stiffness, band)


def _friction(x, state, limit, sense, stiffness, band, friction, direction, axis, floor):
    return friction_force(x[0], limit, sense, stiffness, band, friction, direction, axis, floor)[None, :]


def _bed_friction(x, state, limit, sense, stiffness, band, friction, bed_velocity, axis, floor, moving=True,
                  velocity=None):
    return bed_friction_force(x[0], velocity[0], limit, sense, stiffness, band, friction, bed_velocity, axis,
                              floor)[None, :]


def _contact_arguments(p, env):
    return {"limit": p.limit, "sense": p.limit_sense, "stiffness": env.bottom_stiffness, "band": env.bottom_band}


def _friction_arguments(p, env, axis, floor):
    return {**_contact_arguments(p, env), "friction": env.bottom_friction,
            "direction": sliding_direction(env.current_direction, axis), "axis": axis, "floor": floor}


def _bed_friction_arguments(p, env, axis, floor, bed_moving, moving):
    bed = env.current_speed * sliding_direction(env.current_direction, axis) if bed_moving else jnp.zeros(3)
    return {**_contact_arguments(p, env), "friction": env.bottom_friction, "bed_velocity": bed, "axis": axis,
            "floor": floor, "moving": moving}


def _floor(scene):
    """(axis, floor sense) of the sea bed where some node has it as a floor, else None."""
    where = scene_lib.bottom_axis(scene.environment)
    if where is None:
        return None  # jaxnet.scene.checks.validate names the problem where friction needs it
    axis, floor = where
    return where if np.any(np.asarray(scene.nodes.limit_sense)[:, axis] == floor) else None


def _contact_active(scene, dynamic):
    n = scene.nodes
    limited = n.limit is not None and n.limit_sense is not None and any_nonzero(n.limit_sense)
    return {} if limited and scene.environment.bottom_stiffness > 0 else None


def _friction_active(scene, dynamic):
    """Statics only (in time :data:`BED_FRICTION` holds the sliding bed too), on a bed that slides."""
    env = scene.environment
    if (dynamic or not env.bottom_moving or _contact_active(scene, dynamic) is None or not env.bottom_friction > 0
            or not has_current(scene)):
        return None
    where = _floor(scene)
    if where is None:
        return None
    axis, floor = where
    sliding = np.any(np.delete(np.asarray(env.current_direction, dtype=float), axis) != 0)
    return {"axis": axis, "floor": floor} if sliding else None


def _bed_friction_active(scene, dynamic):
    """In time, wherever the bed has friction and some node has it as a floor, still or sliding."""
    env = scene.environment
    if not dynamic or _contact_active(scene, dynamic) is None or not env.bottom_friction > 0:
        return None
    where = _floor(scene)
    if where is None:
        return None
    axis, floor = where
    return {"axis": axis, "floor": floor, "bed_moving": bool(env.bottom_moving), "moving": True}


BOTTOM_CONTACT = register(Term(
    name="bottom_contact", family="nodes", kind=ENERGY, element=_contact, arguments=_contact_arguments,
    active=_contact_active, group=BOTTOM))
BOTTOM_FRICTION = register(Term(
    name="bottom_friction", family="nodes", kind=FORCE, element=_friction, arguments=_friction_arguments,
    active=_friction_active, group=BOTTOM))
BED_FRICTION = register(Term(
    name="bed_friction", family="nodes", kind=FORCE, element=_bed_friction, arguments=_bed_friction_arguments,
    active=_bed_friction_active, group=BOTTOM, moving=True))
