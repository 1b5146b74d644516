"""Hydrodynamic drag (book section 4.3.3, eqs 4.114-4.135) on netting twines, cable bars and lumped bodies.

Every drag here is the Morison drag of a cylinder, split into a part normal to its axis (Landweber) and a
part along it (Richtmeyer). For the U twines of a triangle the book gives (4.114-4.117)

    |F| = ½ ρ Cd D l0 [|c| sin α]² |d|/2,      F/|F| = U ^ (c ^ U) / |U ^ (c ^ U)|,
    |T| = f ½ ρ Cd D l0 [|c| cos α]² |d|/2,    T/|T| = F ^ (c ^ F) / |F ^ (c ^ F)|,

with c the velocity of the water relative to the twine and α its angle to U (4.132); the V twines alike
with β. Split c into its parts along and across the twine, c_t = (c.û) û and c_n = c - c_t (û = U/|U|):
|c_n| = |c| sin α, |c_t| = |c| |cos α|, U ^ (c ^ U) = |U|² c_n, and F ^ (c ^ F) is (4.198) a positive
multiple of (c.U) U, i.e. of c_t. So, exactly,

    F = K_n |c_n| c_n,     T = K_t |c_t| c_t,     K = ½ ρ C D l0 |d|/2,

which is what is computed. The printed directions are 0/0 when the water runs along the twine (for both:
F = 0 there, and T, which is then largest, is built on F), across it (4.117) and in still water; the
stiffness derivation inherits these as the 1/sin α of 4.156-4.160 and 4.187-4.195 and the 1/|cos α| of
4.200-4.208. The product |v| v is continuously differentiable with zero derivative at v = 0, so the form
above is smooth, with finite value and ``jax.jacfwd`` in all these cases (norms through
:func:`jaxnet.geometry.safe_norm`, whose derivative at 0 is 0, the correct derivative of |v| v there).

Conventions and choices:

* Coefficients. The printed 4.115 multiplies Cd by f, which the book's list calls the "tangential drag
  coefficient". FEMNET's own source (``trainee_fil.c``, ``efforttraineeelem.c``: ``t = f*k*cos²`` with
  ``k = ½ ρ cdnormal D l0 |c|²``) confirms that f is a ratio to the normal coefficient. Here
  ``cd_tangential`` is the tangential drag coefficient itself, Ct = f Cd, so that a twine and a bar share
  one Morison form and a tangential drag does not vanish with Cd: a FEMNET input (cdnormal, ftangent)
  maps to ``cd_normal = cdnormal, cd_tangential = ftangent * cdnormal``.
* Length. The projected area is D l0 with l0 the *unstretched* twine (or bar) length, as in the book: a
  stretched twine also thins (Poisson), which the model does not represent, and for a constant-volume
  twine D L grows only as sqrt(L/l0); taking l0 keeps both effects out consistently. FEMNET does the same
  for twines and bars ("on ne prend pas en compte l'allongement"). Only the *direction* of U (of the bar)
  comes from the current positions.
* Counts. |d|/2 U twines and |d|/2 V twines per triangle (4.25-4.26); the printed d/2 gives the wrong
  sign for clockwise triangles (d < 0), as in the tension forces.
* Spreading. A triangle's drag is spread one third per vertex (text after 4.117); a bar's one half per
  end, as FEMNET does.
* Free surface. Water drags only what is in it: where the scene has a free surface (option ``wetted``), each
  vertex's share of a drag is weighed by the wetted part of the area it shows the flow (:func:`wetted_shares`),
  whatever ``Environment.floating`` says of weight and buoyancy. A collar pipe with its axis on the surface has
  half its drag, netting above the surface none. The share changes with height only within 3/4 of the band (a
  twine's or bar's diameter, a body's height) of the surface, where the tangent has the product rule's extra
  column.
* Relative velocity. ``water_velocity`` is the water velocity relative to the element (m/s): the current
  in statics (evaluated by the caller where it chooses, e.g. at the element's centroid, with
  :func:`jaxnet.water.current.current_velocity`); in dynamics the current minus the element's velocity. The
  force is along the relative velocity's components, i.e. it drags the net *with* the water.

Bodies at nodes. A float or sinker is either given a drag area Cd·A, whose drag ½ ρ (Cd A) |c| c is
along the current whatever its direction (:func:`node_drag`), or, as FEMNET's node types, the sizes
(L_x, L_y, L_z) of a box with a drag coefficient per axis (:func:`box_drag`). FEMNET (statics,
``unix_2004/traineecourant2.c``; data "Length X,Y,Z" and "Drag coefficient X,Y,Z" per node type,
``chargement_don.c``) loads each node with

    F_x = ½ ρ Cd_x (L_y h) U² cos θ,     F_y = ½ ρ Cd_y (L_x h) U² sin θ,

U the current's speed, θ its heading from x towards y, h the immersed height of the box: the drag along
x is that of the box's face normal to x, of width L_y and wetted height h, with the x component of the
velocity; along y the face of width L_x. Since U² cos θ = |c| c_x, this is F_i = ½ ρ Cd_i A_i |c| c_i:
each axis is its own Morison drag, so the force is not along the current unless the faces are alike.
The box stands on its node along the vertical: above it for L_z > 0 (a float), below it for L_z < 0 (a
sinker, FEMNET's "lest"); with the free surface at s, h = clip(s - z_bottom, 0, |L_z|), z_bottom = z +
min(L_z, 0), which is FEMNET's four cases (floating, flooded, emerged float; floating, flooded, emerged
sinker; FEMNET's surface is z = 0). Without a free surface the box is wholly immersed, h = |L_z|. FEMNET
has no vertical drag (its current is horizontal, and ``cdz`` is read but unused in statics); here a
vertical current meets the box's horizontal section, F_z = ½ ρ Cd_z (L_x L_y f) |c| c_z with f = h/|L_z|
the immersed fraction (a flat plate, L_z = 0, counts as immersed when its node is under the surface):
zero for FEMNET's horizontal current. h is piecewise linear in the node's height, as in FEMNET: the drag
of a body crossing the surface has a kink where it just emerges or submerges, a discontinuity of its
(small) stiffness, not of the force. FEMNET's stiffness of this term is that of h (its
``affectation_ze_rang(3*zi-1, 3*zi, ...)`` entries); its pardiso variant writes L_y for L_x in the y
entry of the floating sinker, an error there only.

FEMNET's netting drag ahead of a catch (:func:`netting_drag_femnet_catch`). FEMNET's statics (main
loop in ``unix_2004/unix.c``) loads diamond netting in one of two ways. Without a catch it calls
``filethydro4_sta``, which gives each U and each V twine ``basic_bar_drag1``: exactly the Morison form
above (normal ½ ρ Cd D l0 |c|² sin²α along c_n, tangential f ½ ρ Cd D l0 |c|² cos²α along ±U, l0 the
unstretched twine, |d|/2 twines of each kind, one third per vertex), i.e. :func:`netting_drag`. With a
catch (its volume above the "accuracy on this volume" of the .don, and no ``catch_gravity`` input) it calls
``catch_hexa`` and ``trainee_front`` instead: the netting behind the front gets no drag, a triangle
astride it the consistent load of its part ahead, and the drag of a triangle is ``trainee_fil``'s. That
routine works each twine in a frame of its own (``rota1`` then a turn about z): c on +x, the twine in the
xy plane with a positive y component. There the U twine's drag is (F_U.ĉ, F_U.ê_U, 0), its in-line part
and its part across the flow, ê_U the unit vector of U's component normal to c (with U's orientation).
The V twine is then worked the same way, but the two in-frame forces are *summed* and the sum is turned
back with the V twine's rotations only. The in-line parts come back along the current; U's cross part
comes back along ê_V instead of ê_U:

    F_femnet = (|d|/2) [ F_V + (F_U.ĉ) ĉ + (F_U.ê_U) ê_V ]     (exact: (|d|/2) [ F_V + F_U ]),

F_U, F_V one twine's drag (4.114-4.117). FEMNET's twine coordinates from a panel's mesh coordinates
(U, V) are u = U + V, v = V - U (``etirement5``, as :mod:`jaxnet.io.femnet`): in a cod-end meshed along
its axis the U twines run downstream and the V twines upstream on the same side of the axis, so
ê_U ≈ ê_V while F_U.ê_U ≈ -F_V.ê_V. The two cross parts then cancel along ê_V, and the netting keeps only
its drag along the current: the lift of the netting's cone across the flow, which the exact form gives
(on FEMNET's quarter cod-end ``c2``, -47 N along y and along z for 268 N along x), is lost (0.25 N left). On a flat panel in a current (FEMNET's ``nr_netting``, no catch) the
exact form applies. Two more details of ``trainee_fil`` are not reproduced: the V twine sees the current
as left by the U twine's rotation, |c| along +x, and the in-line parts return along +x: the same as the
form above when the current is along x (FEMNET's current direction 0, as in its cod-end cases), not
otherwise; and a twine exactly normal to c is given θ = π/4 (its ``atan`` guard). Where ê_V has no
direction (V along c) FEMNET's ``rota1`` picks an arbitrary normal; here U's cross part is then dropped,
so this force has a discontinuity on that set, as FEMNET's has.

FEMNET's netting drag laws (``input drag_forces_type N`` of its ``.don``: 1 Morison, the default; 2 Zhan; 3 "drop
pressure"; 4 Aarnes). ``chargement_don.c`` reads N into ``Structure.drag_forces_type``; the statics' main loop
(``unix_2004/unix.c``) uses it only where there is no catch, tarp or extra catch volume (with one, ``catch_hexa``
and ``trainee_front`` load the netting whatever N is: :func:`netting_drag_femnet_catch`), and its dynamics
(``dyna2``'s main) alike:

* 1, Morison: ``filethydro4_sta`` (``basic_bar_drag1`` per twine): :func:`netting_drag`, drag model "twines".
* 2, Zhan: ``filethydro4_sta_zhan`` and ``calculeffort_Zhan`` (``unix_2004/calculeffort_Zhan.c``), after Zhan et
  al. (2006, "Analytical and experimental investigation of drag on nets of fish cages", Aquacultural
  Engineering 35), per U and per V twine, with Sn the solidity (``Solidity_diamond``: (4 D l0 - D²) / (2 |U ^ V|),
  clipped to [0, 1], U, V the twine vectors of the current shape):

      F_n = ½ ρ D l0 |c_n| (|c_n| + 0.137 + 1.002 |c_n| Sn + 2.230 |c_n| Sn²)   along c_n,
      F_t = ½ ρ D l0 |c_t| (|c_t| - 0.211 + 0.947 |c_t| Sn)                    along c_t,

  |d|/2 twines of each kind, one third per vertex (FEMNET calls the routine three times per family, each adding
  a third of a third: the same total), the current without Cd nor f: :func:`netting_drag_zhan`, drag model
  "zhan". Its static loop calls it at the current, the dynamic one (``calculeffort_zhan_dyna``) per vertex.
* 3, drop pressure, and 4, Aarnes: named in ``chargement_don.c``'s and ``4c19.h``'s comments, and in the main
  statics' loop as ``//if (Structure.drag_forces_type == 3) filethydro4_sta();`` and the same for 4: commented
  out (the dynamics' loop calls only 1 and 2). FEMNET's current code has no such law: it gives its diamond netting *no* drag (its
  ``.sta`` then prints "surface drag (N) 0.0", as the corpus's ``3bottom_trawl/b2.sta``). jaxnet reproduces that
  with drag model "none" (a drop-pressure law, the pressure loss across a screen of Cd(Sn) times the dynamic
  pressure on the netting's area, would be a screen model like :mod:`jaxnet.terms.screen`'s; there is no
  FEMNET formula to take it from).

The drag of the cables (``courantelem8``) and of the node bodies (``traineecourant2``) does not depend on N.

These are forces (N), not energies: drag is not conservative. Its tangent -d force/dx (book 4.136-4.210)
is obtained by ``jax.jacfwd`` of these functions and is not symmetric; when the current depends on depth
the caller composes :func:`jaxnet.water.current.current_velocity` inside the differentiated function so that
the tangent sees dc/dz too (the book's 4.157 takes c constant).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import geometry
from jaxnet.water import current
from jaxnet.terms import pressure, screen, surface
from jaxnet.scene import has_free_surface
from jaxnet.terms.term import (DRAG_CABLES, DRAG_NETTING, DRAG_NODES, FORCE, ClosedForm, Term, any_nonzero, flowing, moving_options, register)


def twine_drag(axis, length, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Morison drag on one straight cylinder (a twine or a bar), split in normal and tangential parts.

    Normal part ½ ρ Cn D L |c_n| c_n (4.114, 4.116), tangential part ½ ρ Ct D L |c_t| c_t (4.115, 4.117),
    with c_t the component of the water velocity along ``axis`` and c_n the rest.

    Args:
      axis: (3,) any vector along the cylinder (m); only its direction is used. A zero axis (collapsed
        twine) has no direction: all the velocity is then taken as normal.
      length: length L used for the projected area D L (m); the unstretched length, see module docstring.
      diameter: hydrodynamic diameter D (m).
      cd_normal: normal drag coefficient Cn (dimensionless).
      cd_tangential: tangential drag coefficient Ct (dimensionless; the book's f times Cd).
      water_velocity: (3,) velocity of the water relative to the cylinder (m/s).
      water_density: ρ (kg/m³).
    Returns:
      (normal, tangential): two (3,) forces in N on the whole cylinder.
    """
    c = water_velocity
    c_t = _along(axis, c)
    c_n = c - c_t
    k = 0.5 * water_density * diameter * length
    normal = (k * cd_normal * geometry.safe_norm(c_n)) * c_n
    tangential = (k * cd_tangential * geometry.safe_norm(c_t)) * c_t
    return normal, tangential


def _along(axis, water_velocity):
    """The part (3,) of the water velocity along ``axis``, (c.W) W/|W|²; 0 for a zero axis."""
    sq = jnp.dot(axis, axis)
    has_axis = sq > 0.0
    # double where: 1/|axis|² must not be evaluated (nor differentiated) at a zero axis
    inv_sq = jnp.where(has_axis, 1.0 / jnp.where(has_axis, sq, 1.0), 0.0)
    return (jnp.dot(water_velocity, axis) * inv_sq) * axis


def netting_drag_parts(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Drag on the U twines and on the V twines of one triangle, each split in normal and tangential.

    Same arguments as :func:`netting_drag`. Returns a dict of (3,) forces in N on the whole element:
    ``u_normal``, ``u_tangential`` (4.114-4.117), ``v_normal``, ``v_tangential`` (the same with V, β).
    """
    U, V, d = geometry.twine_vectors(x, uv)
    count = geometry.twine_count(d)
    un, ut = twine_drag(U, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density)
    vn, vt = twine_drag(V, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density)
    return {
        "u_normal": count * un,
        "u_tangential": count * ut,
        "v_normal": count * vn,
        "v_tangential": count * vt,
    }


def netting_drag(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Per-vertex drag (3, 3) in N on one diamond-mesh triangle: its U and V twines, one third per vertex.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines); d may be negative.
      l0: unstretched length of one twine (mesh side) (m), used for the projected area D l0.
      diameter: hydrodynamic twine diameter D (m).
      cd_normal: normal drag coefficient of a twine (dimensionless), the book's Cd.
      cd_tangential: tangential drag coefficient of a twine (dimensionless), the book's f times Cd.
      water_velocity: (3,) velocity of the water relative to the netting (m/s).
      water_density: ρ (kg/m³).
    """
    parts = netting_drag_parts(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density)
    total = parts["u_normal"] + parts["u_tangential"] + parts["v_normal"] + parts["v_tangential"]
    return jnp.broadcast_to(total / 3.0, (3, 3))


def unit_across(axis, water_velocity, inv_c2):
    """Unit vector (3,) of the component of ``axis`` normal to the water velocity; 0 where there is none
    (axis along c, or a zero axis). ``inv_c2`` is 1/|c|² (0 in still water)."""
    across = axis - (jnp.dot(axis, water_velocity) * inv_c2) * water_velocity
    sq = jnp.dot(across, across)
    # relative threshold: an axis along c leaves a rounding residue whose direction is noise
    has = sq > 1e-24 * jnp.dot(axis, axis)
    return across * jnp.where(has, 1.0 / jnp.sqrt(jnp.where(has, sq, 1.0)), 0.0)


def netting_drag_femnet_catch(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Per-vertex drag (3, 3) in N on one diamond-mesh triangle as FEMNET loads netting ahead of a catch
    (``trainee_front`` -> ``trainee_fil``): each twine's in-line drag along the current, but the U twines'
    drag across the flow turned onto the V twines' cross direction (module docstring):

        F = (|d|/2) [ F_V + (F_U.ĉ) ĉ + (F_U.ê_U) ê_V ],   one third per vertex,

    with F_U, F_V the Morison drag of one U and one V twine (4.114-4.117, as :func:`netting_drag`) and
    ê_U, ê_V the unit vectors of the components of U and V normal to c. The drag along the current is
    that of :func:`netting_drag`; only the part across the flow differs.

    Same arguments as :func:`netting_drag` (x (3, 3) m; uv (3, 2) twines; l0, diameter m; cd_normal and
    cd_tangential = f Cd dimensionless; water_velocity (3,) m/s; water_density kg/m³). The result depends
    on which twine family is U and on their orientations (FEMNET's u = U + V, v = V - U).
    """
    U, V, _ = geometry.twine_vectors(x, uv)
    parts = netting_drag_parts(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density)
    force_u = parts["u_normal"] + parts["u_tangential"]
    force_v = parts["v_normal"] + parts["v_tangential"]
    c = water_velocity
    c2 = jnp.dot(c, c)
    still = c2 == 0.0
    inv_c2 = jnp.where(still, 0.0, 1.0 / jnp.where(still, 1.0, c2))
    in_line_u = (jnp.dot(force_u, c) * inv_c2) * c
    across_u = jnp.dot(force_u, unit_across(U, c, inv_c2))
    total = force_v + in_line_u + across_u * unit_across(V, c, inv_c2)
    return jnp.broadcast_to(total / 3.0, (3, 3))


#: Zhan et al. (2006)'s drag of a twine in netting, as FEMNET's ``calculeffort_Zhan.c`` has it: the normal
#: coefficients (c1 in m/s, c2, c3) and the tangential ones (c4 in m/s, c5) of :func:`zhan_twine_drag`
ZHAN_NORMAL = (0.137, 1.002, 2.230)
ZHAN_TANGENTIAL = (-0.211, 0.947)


def zhan_twine_drag(axis, length, diameter, solidity, water_velocity, water_density):
    """Zhan's drag on one twine of netting of solidity Sn (Zhan et al. 2006, Aquacultural Engineering 35: drag on
    nets of fish cages; FEMNET's ``calculeffort_Zhan``), split in normal and tangential parts:

        F_n = ½ ρ D L [ (1 + c2 Sn + c3 Sn²) |c_n| + c1 ] c_n,    F_t = ½ ρ D L [ (1 + c5 Sn) |c_t| + c4 ] c_t,

    c_n and c_t the water velocity's parts across and along ``axis`` (as :func:`twine_drag`), (c1, c2, c3) =
    :data:`ZHAN_NORMAL`, (c4, c5) = :data:`ZHAN_TANGENTIAL`. The constants c1 and c4 are velocities (m/s): the
    law is a fit in SI units, and ½ ρ D L |c| (|c| + c1) is a Cd of 1 + c1/|c|. FEMNET writes the magnitudes
    |c_n| (|c_n| + c1 + ...) along ĉ_n, which is this; with c4 < 0 the tangential part points *upstream* for
    |c_t| < -c4 / (1 + c5 Sn) (about 0.2 m/s), as in FEMNET. Every part is |v| v or linear in v: the force is
    continuously differentiable in the velocity and the axis (a zero axis: all the velocity normal).

    Args: axis (3,) m (only its direction), length L m (the unstretched twine), diameter D m, solidity Sn
      (:func:`jaxnet.geometry.diamond_solidity`), water_velocity (3,) m/s relative to the twine, water_density ρ kg/m³.
    Returns: (normal, tangential), two (3,) forces in N on the twine.
    """
    c1, c2, c3 = ZHAN_NORMAL
    c4, c5 = ZHAN_TANGENTIAL
    quadratic_n, quadratic_t = twine_drag(axis, length, diameter, 1.0 + c2 * solidity + c3 * solidity**2,
                                          1.0 + c5 * solidity, water_velocity, water_density)
    c_t = _along(axis, water_velocity)
    k = 0.5 * water_density * diameter * length
    return quadratic_n + (k * c1) * (water_velocity - c_t), quadratic_t + (k * c4) * c_t


def netting_drag_zhan(x, uv, l0, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Per-vertex drag (3, 3) in N on one diamond-mesh triangle by Zhan's law (FEMNET's ``input drag_forces_type
    2``, ``filethydro4_sta_zhan``): |d|/2 U twines and |d|/2 V twines, each :func:`zhan_twine_drag` with the
    triangle's solidity (:func:`jaxnet.geometry.diamond_solidity` of its U, V), one third per vertex, as :func:`netting_drag`.
    The law has its own coefficients: ``cd_normal`` and ``cd_tangential`` are not used (same arguments as
    :func:`netting_drag` otherwise)."""
    U, V, d = geometry.twine_vectors(x, uv)
    solidity = geometry.diamond_solidity(U, V, l0, diameter)
    total = 0.0
    for axis in (U, V):
        normal, tangential = zhan_twine_drag(axis, l0, diameter, solidity, water_velocity, water_density)
        total = total + normal + tangential
    return jnp.broadcast_to(geometry.twine_count(d) * total / 3.0, (3, 3))


def bar_drag(x, rest_length, diameter, cd_normal, cd_tangential, water_velocity, water_density):
    """Per-end drag (2, 3) in N on one cable bar (a cylinder), half on each end.

    Args:
      x: (2, 3) end positions (m); only the bar's direction is taken from them.
      rest_length: unstretched length of the bar (m), used for the projected area D L0 as for twines.
      diameter: hydrodynamic diameter D (m).
      cd_normal, cd_tangential: normal and tangential drag coefficients (dimensionless).
      water_velocity: (3,) velocity of the water relative to the bar (m/s).
      water_density: ρ (kg/m³).
    """
    normal, tangential = twine_drag(
        x[1] - x[0], rest_length, diameter, cd_normal, cd_tangential, water_velocity, water_density
    )
    return jnp.broadcast_to((normal + tangential) / 2.0, (2, 3))


def node_drag(drag_area, water_velocity, water_density):
    """Drag (3,) in N on a lumped body (float, sinker, ...): ½ ρ (Cd A) |c| c.

    Args:
      drag_area: drag coefficient times reference area, Cd·A (m²).
      water_velocity: (3,) velocity of the water relative to the body (m/s).
      water_density: ρ (kg/m³).
    """
    return (0.5 * water_density * drag_area * geometry.safe_norm(water_velocity)) * water_velocity


def box_immersed_fraction(height, vertical_length, surface_level):
    """Immersed fraction f in [0, 1] of the height of a box standing on its node (FEMNET's node body).

    The box spans heights [z + min(L_z, 0), z + max(L_z, 0)]: above the node for L_z > 0 (a float),
    below it for L_z < 0 (a sinker). Its immersed height is h = clip(s - z_bottom, 0, |L_z|) and
    f = h / |L_z|; a flat box (L_z = 0) is immersed (f = 1) when the node is under the surface.

    Args:
      height: height z of the node along ``up`` (m).
      vertical_length: L_z, signed height of the box (m).
      surface_level: height s of the free surface (m), finite.
    """
    size = jnp.abs(vertical_length)
    depth_of_bottom = surface_level - (height + jnp.minimum(vertical_length, 0.0))
    flat = size == 0.0
    immersed = jnp.clip(depth_of_bottom, 0.0, size)
    return jnp.where(flat, (depth_of_bottom > 0.0).astype(float), immersed / jnp.where(flat, 1.0, size))


def box_drag(length, drag_coefficient, water_velocity, water_density, immersed_fraction=1.0):
    """Drag (3,) in N on a box-shaped body at a node (FEMNET's node types), one Morison drag per axis:
    F_i = ½ ρ Cd_i A_i |c| c_i, with A_x = L_y h, A_y = L_x h, A_z = L_x L_y f and h = f |L_z|.

    Args:
      length: (3,) sizes (L_x, L_y, L_z) of the box (m); L_z may be negative (a box below its node).
      drag_coefficient: (3,) Cd along x, y, z (dimensionless).
      water_velocity: (3,) velocity of the water relative to the body (m/s).
      water_density: ρ (kg/m³).
      immersed_fraction: f in [0, 1], the immersed part of the box's height (1: wholly immersed; see
        :func:`box_immersed_fraction`).
    """
    lx, ly, lz = length[0], length[1], jnp.abs(length[2])
    area = immersed_fraction * jnp.stack([ly * lz, lx * lz, lx * ly])
    return (0.5 * water_density * geometry.safe_norm(water_velocity)) * drag_coefficient * area * water_velocity


# -- the water's velocity seen by an element ------------------------------------------------------


def water_velocity(x, env):
    """Current (3,) in m/s at the centroid of an element's vertices x (k, 3): what a static drag sees. Computed
    inside the differentiated function, so that the stiffness sees how the current varies with depth."""
    z = jnp.dot(geometry.centroid(x), env.up)
    return current.current_velocity(z, env.current_speed, env.current_direction, env.profile_depth,
                                    env.profile_factor, env.surface_level)


def water_velocity_at(points, env, waves):
    """Velocity (..., 3) in m/s of the water at ``points`` (..., 3) and at the environment's time: the
    current at each point's depth, plus the waves' orbital velocity when ``waves`` (static) is True."""
    z = points @ env.up
    c = current.current_velocity(z, env.current_speed, env.current_direction, env.profile_depth,
                                 env.profile_factor, env.surface_level)
    if waves:
        c = c + env.waves.velocity(points, env.time)
    return c


def per_vertex(force, x, env, velocity, waves):
    """Dynamics (book 4.272-4.276): vertex i of an element takes its share of the element's drag computed
    with the water's velocity relative to vertex i. ``force(c) -> (k, 3)`` is the element's drag shared
    over its k vertices for a uniform relative velocity c; row i of force(c_i) is vertex i's share."""
    relative = water_velocity_at(x, env, waves) - velocity
    # one batched evaluation (not k unrolled copies: a third of the program to compile)
    shares = jax.vmap(force)(relative)  # (k, k, 3): [i] the shares of all vertices for vertex i's velocity
    return shares[jnp.arange(x.shape[0]), jnp.arange(x.shape[0])]


# -- how the current loads netting -----------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class NettingDragModel:
    """One way the current loads diamond netting (``Netting.drag_model`` code: its index in
    :data:`NETTING_DRAG_MODELS`).

    name: the material's name for it (``Twine.drag_model``). scope: its name in compiled programs.
    force: ``force(x, uv, l0, diameter, cd_normal, cd_tangential, c, rho) -> (3, 3)`` vertex forces (N) of a
      triangle in a uniform relative velocity c (m/s); None for netting the current does not load (nothing is
      computed for its triangles). twines: made of twine drags (Cd, f), so present only where some Cd is not
      zero. closed_form: :mod:`jaxnet.closed_form.drag_elements` has its stiffness.
    """

    name: str
    scope: str
    force: Callable | None
    twines: bool
    closed_form: bool = False


def _screen_force(model):
    return lambda x, uv, l0, diameter, cd_normal, cd_tangential, c, rho: model(x, uv, l0, diameter, c, rho)


#: netting drag models, by code
NETTING_DRAG_MODELS = (
    NettingDragModel("twines", "twine_drag", netting_drag, twines=True, closed_form=True),
    NettingDragModel("loland", "loland_screen", _screen_force(screen.loland_force), twines=False),
    NettingDragModel("kristiansen-faltinsen", "kristiansen_faltinsen_screen",
                     _screen_force(screen.kristiansen_faltinsen_force), twines=False),
    # FEMNET's drag of netting ahead of a catch (trainee_front -> trainee_fil): the twine drag along the
    # current, the U twines' cross-flow part turned onto the V twines' (netting_drag_femnet_catch)
    NettingDragModel("femnet-catch", "femnet_catch_drag", netting_drag_femnet_catch, twines=True, closed_form=True),
    # Zhan et al.'s twine drag with the netting's solidity (FEMNET's drag_forces_type 2, netting_drag_zhan)
    NettingDragModel("zhan", "zhan_drag", netting_drag_zhan, twines=False, closed_form=True),
    # no drag: what FEMNET's current statics give diamond netting for its drag_forces_type 3 and 4 (module
    # docstring), to reproduce it
    NettingDragModel("none", "no_drag", None, twines=False),
)


# -- the terms -------------------------------------------------------------------------------------


def netting_drag_on_element(x, state, uv, l0, diameter, cd_normal, cd_tangential, drag_model, env, models,
                            shielded, moving=False, waves=False, velocity=None, selective=False, wetted=False):
    """Drag (3, 3) in N on one netting triangle, by its drag model (``drag_model``: a code of
    :data:`NETTING_DRAG_MODELS`; ``models``: the codes present in the scene that load it, static; ``selective``:
    some triangles have a model not in ``models``, which gives them no drag, static). In statics the water's
    velocity is the current at the centroid; in dynamics (``moving``) each vertex takes its share with the
    velocity relative to it (:func:`per_vertex`). ``shielded``: the scene has a catch, whose front is in
    ``state`` (:func:`jaxnet.model.catch.catch_state`). ``wetted``: the scene has a free surface; each vertex's share
    is then that of its wetted part (:func:`wetted_shares`, the twine diameter its band)."""
    rho = env.water_density
    total = jnp.zeros((3, 3))
    for code in models:
        model = NETTING_DRAG_MODELS[code]

        def force(c, model=model):
            return model.force(x, uv, l0, diameter, cd_normal, cd_tangential, c, rho)

        with jax.named_scope(model.scope):
            f = per_vertex(force, x, env, velocity, waves) if moving else force(water_velocity(x, env))
        total = total + (jnp.where(drag_model == code, f, 0.0) if len(models) > 1 or selective else f)
    if shielded:
        # netting behind the catch front is backed by fish: the water does not flow through it, and the
        # catch pressure replaces its drag, as in FEMNET. The part of the triangle ahead of the front keeps
        # its drag, spread as the consistent load of that part (continuous as the front sweeps the element).
        behind = pressure.clipped_shape_integrals(pressure.front_heights(x, state["front"], state["axis"]))
        total = total * (1.0 - 3.0 * behind)[:, None]
    if wetted:
        total = total * wetted_shares(x, surface.immersion_band(diameter), env)[:, None]
    return total


def bar_drag_on_element(x, state, rest_length, diameter, cd_normal, cd_tangential, env, moving=False, waves=False,
                        velocity=None, wetted=False):
    """Drag (2, 3) in N on one cable bar: at the current at its middle in statics, per end in dynamics; with
    ``wetted`` (a free surface) each end's half is that of its wetted part (:func:`wetted_shares`, the bar's
    diameter its band)."""
    def force(c):
        return bar_drag(x, rest_length, diameter, cd_normal, cd_tangential, c, env.water_density)

    f = per_vertex(force, x, env, velocity, waves) if moving else force(water_velocity(x, env))
    return f * wetted_shares(x, surface.immersion_band(diameter), env)[:, None] if wetted else f


def node_water_velocity(x, env, moving, waves, velocity):
    """The water's velocity (3,) in m/s relative to a node's body (x: (1, 3)): the current there in statics,
    minus the node's velocity in dynamics."""
    return water_velocity_at(x[0], env, waves) - velocity[0] if moving else water_velocity(x, env)


def node_drag_on_element(x, state, drag_area, env, moving=False, waves=False, velocity=None, wetted=False, band=None):
    """Drag (1, 3) in N on a node's body of drag area Cd·A (:func:`node_drag`); with ``wetted`` (a free surface)
    that of its wetted part (:func:`wetted_shares`; ``band``, m: the body's height,
    :func:`jaxnet.terms.surface.node_band`)."""
    c = node_water_velocity(x, env, moving, waves, velocity)
    f = node_drag(drag_area, c, env.water_density)[None, :]
    return f * wetted_shares(x, band, env)[:, None] if wetted else f


#: half-width of the rounded corners of the wetted share (:func:`wetted_shares`), as a fraction of the band
WETTED_ROUNDING = 0.25


def wetted_shares(x, band, env):
    """(k,) the wetted part (dimensionless) of each vertex's share of an element's drag, x (k, 3) its vertices (m):
    the water drags only what is in it. A drag is that of the area a body shows the flow, and of a body of height
    ``band`` (m: a twine's or a bar's diameter, a float's height) centred on the vertex, h above the water plane,
    the water holds the depth band/2 - h of that area: the share is the ramp clip(1/2 - t, 0, 1), t = h/band, all
    of it from t = -1/2 down, half with the body's axis on the surface, none from t = 1/2 up. (The part of a
    cylinder's *section* under water, by which it floats (:mod:`jaxnet.terms.surface`), is another function of h:
    the drag sees the depth, not the section.) FEMNET weighs its bars' and netting's drag with the same ramp
    (``pondFS``, ``miseajourPondFS.c``, over the side of the cube of the vertex's lumped volume).

    Why rounded. The ramp's corners are kinks of the force, jumps of the tangent: a float or a collar that sits
    near a corner makes Newton chatter across it (FEMNET's cage ``10fish_cage/f1`` went from 694 iterations,
    with a smooth share, to its cap of 3000, as FEMNET's own solve does). So each corner is replaced by the
    parabola tangent to both its sides over |t ∓ 1/2| < e, e = :data:`WETTED_ROUNDING`: the share is C¹,
    differs from the ramp by at most e/4 (at the corners) and nowhere beyond them, and keeps the ramp's integral
    over the heights (the two corners' differences cancel). The surface is ``env.surface_level``, as for buoyancy:
    the mean water plane, or in a time step in waves the wave's surface over each vertex
    (:func:`jaxnet.model.assemble.element_environment`), as FEMNET's ``dyna`` weighs its drags
    (``miseajourPondFS_dyna.c``)."""
    t = (x @ env.up - env.surface_level) / band
    e = WETTED_ROUNDING
    low, high = 1.0 - (t + 0.5 + e) ** 2 / (4.0 * e), (t - 0.5 - e) ** 2 / (4.0 * e)
    return jnp.where(t <= -0.5 - e, 1.0, jnp.where(t < -0.5 + e, low, jnp.where(
        t <= 0.5 - e, 0.5 - t, jnp.where(t < 0.5 + e, high, 0.0))))


def wetted_shares_slope(x, band, env):
    """(k,) the derivative (1/m) of :func:`wetted_shares` with each vertex's height (continuous: -1/band on the
    ramp, 0 beyond the corners)."""
    t = (x @ env.up - env.surface_level) / band
    e = WETTED_ROUNDING
    low, high = -(t + 0.5 + e) / (2.0 * e), (t - 0.5 - e) / (2.0 * e)
    return jnp.where(t <= -0.5 - e, 0.0, jnp.where(t < -0.5 + e, low, jnp.where(
        t <= 0.5 - e, -1.0, jnp.where(t < 0.5 + e, high, 0.0)))) / band


def box_drag_on_element(x, state, length, drag_coefficient, env, floating, moving=False, waves=False, velocity=None):
    """Drag (1, 3) in N on a node's box body (:func:`box_drag`); only with a free surface (``floating``) can
    a box be partly immersed, without one it is wholly under water."""
    c = node_water_velocity(x, env, moving, waves, velocity)
    f = box_immersed_fraction(jnp.dot(x[0], env.up), length[2], env.surface_level) if floating else 1.0
    return box_drag(length, drag_coefficient, c, env.water_density, f)[None, :]


def _netting_arguments(p, env, models, shielded, **motion):
    # a tarp's triangles (tarp_cd > 0, jaxnet.terms.tarp) have no twine drag: the water does not flow
    # through them, and its pressure replaces the drag, as in FEMNET (trainee_front skips them)
    cd_normal = pressure.off_tarps(p, p.cd_normal)
    return {"uv": p.uv, "l0": p.l0, "diameter": p.diameter, "cd_normal": cd_normal,
            "cd_tangential": p.tangential_ratio * cd_normal, "drag_model": p.drag_model, "env": env,
            "models": models, "shielded": shielded, **motion}


def _bar_arguments(p, env, **motion):
    return {"rest_length": p.rest_length, "diameter": p.diameter, "cd_normal": p.cd_normal,
            "cd_tangential": p.tangential_ratio * p.cd_normal, "env": env, **motion}


def _node_arguments(p, env, wetted=False, **motion):
    # the band of a body (its height) matters only where it can cross a free surface
    band = {"band": surface.node_band(p.size, p.volume), "wetted": True} if wetted else {}
    return {"drag_area": p.drag_area, "env": env, **band, **motion}


def _netting_active(scene, dynamic):
    net = scene.netting
    if net is None or not flowing(scene, dynamic) or net.drag_model is None:
        return None
    codes = np.asarray(net.drag_model)
    has_cd = (np.asarray(net.cd_normal) != 0) if net.cd_normal is not None else np.zeros(codes.shape, bool)
    present = set(codes.tolist())
    models = tuple(sorted(code for code in present if NETTING_DRAG_MODELS[code].force is not None
                          and (not NETTING_DRAG_MODELS[code].twines or np.any((codes == code) & has_cd))))
    if not models:
        return None
    # a triangle whose model is left out (no force, or twine drag with Cd = 0 in every triangle of it) gets none
    selective = present != set(models)
    return {"models": models, "shielded": scene.catch is not None, **({"selective": True} if selective else {}),
            **_wetted(scene), **moving_options(scene, dynamic)}


def _bar_active(scene, dynamic):
    bars = scene.bars
    if bars is None or not flowing(scene, dynamic) or not any_nonzero(bars.cd_normal):
        return None
    return {**_wetted(scene), **moving_options(scene, dynamic)}


def _node_active(scene, dynamic):
    if not flowing(scene, dynamic) or not any_nonzero(scene.nodes.drag_area):
        return None
    return {**_wetted(scene), **moving_options(scene, dynamic)}


def _wetted(scene):
    """Option ``wetted`` of the drags where the scene has a free surface: only the immersed part is dragged."""
    return {"wetted": True} if has_free_surface(scene) else {}


def _box_active(scene, dynamic):
    n = scene.nodes
    if not flowing(scene, dynamic) or n.drag_length is None or n.drag_coefficient is None:
        return None
    length, cd = np.abs(np.asarray(n.drag_length, dtype=float)), np.asarray(n.drag_coefficient, dtype=float)
    # Cd times the area of each face (the vertical one counts when it has any size)
    faces = np.stack([length[:, 1] * length[:, 2], length[:, 0] * length[:, 2], length[:, 0] * length[:, 1]], axis=1)
    return {"floating": has_free_surface(scene), **moving_options(scene, dynamic)} if any_nonzero(cd * faces) else None


NETTING_DRAG = register(Term(
    name="netting_drag", family="netting", kind=FORCE, element=netting_drag_on_element, arguments=_netting_arguments,
    active=_netting_active, group=DRAG_NETTING, moving=True, state="jaxnet.model.catch:catch_state",
    closed_form=ClosedForm("jaxnet.closed_form.drag_elements:netting_drag_on_element_stiffness",
                           covers=lambda options: all(NETTING_DRAG_MODELS[c].closed_form for c in options["models"]))))
BAR_DRAG = register(Term(
    name="bar_drag", family="bars", kind=FORCE, element=bar_drag_on_element, arguments=_bar_arguments,
    active=_bar_active, group=DRAG_CABLES, moving=True,
    closed_form=ClosedForm("jaxnet.closed_form.drag_elements:bar_drag_on_element_stiffness")))
NODE_DRAG = register(Term(
    name="node_drag", family="nodes", kind=FORCE, element=node_drag_on_element,
    arguments=_node_arguments,
    active=_node_active, group=DRAG_NODES, moving=True,
    closed_form=ClosedForm("jaxnet.closed_form.drag_elements:node_drag_on_element_stiffness")))
NODE_BOX_DRAG = register(Term(
    name="node_box_drag", family="nodes", kind=FORCE, element=box_drag_on_element,
    arguments=lambda p, env, floating, **motion: {"length": p.drag_length, "drag_coefficient": p.drag_coefficient,
                                                  "env": env, "floating": floating, **motion},
    active=_box_active, group=DRAG_NODES, moving=True))
