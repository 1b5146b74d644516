"""Fish catch pressure on the netting of a cod-end (book §4.3.6, eqs 4.246-4.264).

The catch is modelled as a uniform pressure (4.246)

    p = ½ rho Cd v²        (Pa)

on the netting *behind the catch front*: the plane normal to the cod-end axis ``a`` (a unit vector
pointing downstream, the direction of the current) placed so that the netting behind it encloses the
catch volume (see :mod:`jaxnet.model.catch`). A point y is behind the front when its height

    h(y) = (y - f) · a        (m; f a point of the front plane, or f·a = s an abscissa)

is positive. For a triangle wholly behind the front the book puts one third of p × (12 ^ 13)/2 on each
vertex (4.247-4.254) and differentiates it into the stiffness (4.256-4.264, which ``jax.jacfwd`` of this
module reproduces).

Triangles cut by the front (the ones the book does not treat)
-----------------------------------------------------------
Here the force is the *consistent* nodal load of the pressure on the part of the triangle behind the
front, the same one FEMNET computes case by case:

    F_i = sign · p · (12 ^ 13)/2 · w_i,     w_i = (1/S) ∫_{T ∩ {h > 0}} N_i dS,

N_i the linear shape function of vertex i and S the triangle's surface. A wholly-behind triangle has
w_i = 1/3 (4.247); the sum of the w_i is the fraction of the surface behind the front. Because h is
linear on the triangle the region {h > 0} is a corner triangle (one vertex behind) or the triangle minus
a corner triangle (two behind), and the integrals are closed forms (:func:`clipped_shape_integrals`).
This makes the forces continuous in the vertex positions and in the front, and continuously
differentiable when the front sweeps over a single vertex (the cut line moves continuously), so a Newton
iteration does not chatter when a vertex crosses the front; a rule loading a triangle wholly or not at
all (by its vertices or its centroid) would jump by the whole element's load. (An edge lying exactly in
the front plane leaves the forces continuous but kinked: ``jacfwd`` then gives the derivative on the
side where the edge is ahead.) It also makes the load *conservative*: on a netting that, with the front
plane and any symmetry planes, closes the catch, the assembled forces are p ∂V/∂x, V the enclosed
volume computed with the same weights (:func:`catch_volume`), so their tangent p ∂²V/∂x² is symmetric
for a fixed front.

Orientation
-----------
The force must push the netting outward of the cod-end. Its direction is taken from the vertex order:
``sign = +1`` (default) when 12 ^ 13 points out of the catch, as the book's 4.247 assumes; ``sign = -1``
when it points into it; a scalar for all the elements or one value per element. FEMNET writes
F = -p (12 ^ 13)/6 (prise.c, ``pression_totale``) on triangles its mesher orders so that d > 0 (4.7);
since 12 ^ 13 = d U ^ V, the catch is on the side of U ^ V (negating the V coordinates of a panel in a
.don file flips it). FEMNET's convention is therefore ``sign = -sign(d)``, d the twine determinant of
the element as meshed (either sign with jaxnet's mesher); in FEMNET's worked case c2, 1235 of the 1243
triangles have 12 ^ 13 pointing toward the cod-end axis. :func:`catch_volume` takes the same ``sign`` so that the
volume, the front section and the force agree.

Numerics: every function is a pure jnp function of ONE element, branch-free (``jnp.where`` with safe
denominators), with finite values, gradients and ``jacfwd`` when a vertex or an edge lies on the front
plane and when the whole triangle lies in it (then nothing is behind: zero force, zero derivative).
Units: positions in m, pressure in Pa, forces in N, volumes in m³.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.term import CATCH, FORCE, ClosedForm, Term, register


def dynamic_pressure(water_density, drag_coefficient, speed):
    """Catch pressure p = ½ rho Cd v² in Pa (eq. 4.246): rho in kg/m³, Cd dimensionless, v in m/s."""
    return 0.5 * water_density * drag_coefficient * speed**2


def front_abscissa(front, axis):
    """Abscissa s (m) of the front along ``axis``: ``front`` itself if a scalar, else front·axis for a
    point (3,) of the front plane. The plane is {y : y·axis = s}."""
    front = jnp.asarray(front)
    if front.ndim == 0:
        return front
    return jnp.dot(front, axis)


def front_heights(x, front, axis):
    """Heights h_i = x_i·axis - s (m) of the vertices x (k, 3) behind the front (positive behind)."""
    return x @ axis - front_abscissa(front, axis)


def clipped_shape_integrals(h):
    """w_i = (1/S) ∫_{T ∩ {h > 0}} N_i dS for a linear field h with vertex values h (3,) (dimensionless).

    All three heights positive: w = 1/3 each. One positive (vertex a): the corner triangle at a. Two
    positive: 1/3 minus the corner triangle at the third vertex (the part ahead of the front). None: 0.
    Heights equal to 0 count as ahead; the formulas agree on both sides of every such boundary (in value,
    and in first derivative when a single height crosses 0), so that choice only avoids 0/0.

    Corner triangle at a, heights g with g_a >= 0 > g_b, g_c (b, c the next vertices): the cut meets the
    sides ab and ac at the fractions t_b = g_a / (g_a - g_b) and t_c; the corner is a t_b t_c fraction of
    the surface and, N being linear, the integral of N_i on it is its surface times the mean of N_i at
    its corners a, a + t_b (b - a), a + t_c (c - a): (3 - t_b - t_c)/3 for a, t_b/3 for b, t_c/3 for c.
    """
    h = jnp.asarray(h)
    nxt, prv = jnp.array([1, 2, 0]), jnp.array([2, 0, 1])
    behind = h > 0.0
    # vertex a is alone on its side of the front (behind, or ahead with both others behind)
    alone_behind = behind & ~behind[nxt] & ~behind[prv]
    alone_ahead = ~behind & behind[nxt] & behind[prv]
    alone = alone_behind | alone_ahead
    # heights measured from a's side, so that g_a >= 0 > g_b, g_c and the denominators are > 0; the
    # other entries get harmless values (the double-where trick keeps their derivatives finite)
    sided = jnp.where(alone_behind, 1.0, -1.0)
    ga = jnp.where(alone, sided * h, 1.0)
    gb = jnp.where(alone, sided * h[nxt], -1.0)
    gc = jnp.where(alone, sided * h[prv], -1.0)
    tb, tc = ga / (ga - gb), ga / (ga - gc)
    frac = tb * tc
    at_a, at_b, at_c = frac * (3.0 - tb - tc) / 3.0, frac * tb / 3.0, frac * tc / 3.0

    def corner(apex):
        # the corner triangle of the apex vertex (mask), its weights on a, b = a + 1 and c = a + 2
        # gathered back per vertex (vertex i is the b of apex i - 1 and the c of apex i + 1)
        return jnp.where(apex, at_a, 0.0) + jnp.where(apex, at_b, 0.0)[prv] + jnp.where(apex, at_c, 0.0)[nxt]

    w_behind = corner(alone_behind)
    w_ahead = jnp.any(alone_ahead) / 3.0 - corner(alone_ahead)
    return jnp.where(jnp.all(behind), 1.0 / 3.0, w_behind + w_ahead)


def catch_pressure(x, pressure, front, axis, sign=1.0):
    """Nodal forces (3, 3) in N of the catch pressure on the part of one triangle behind the front.

    Args:
      x: (3, 3) vertex positions (m).
      pressure: catch pressure p (Pa), e.g. :func:`dynamic_pressure` (4.246).
      front: the catch front: its abscissa s along ``axis`` (m, scalar) or a point (3,) of its plane.
      axis: (3,) unit vector of the cod-end axis, pointing downstream (toward the catch).
      sign: +1 when 12 ^ 13 points out of the cod-end (the book's 4.247), -1 when it points into it
        (FEMNET: -sign(d)). The force is p × (surface behind the front) along the outward normal.
    Returns:
      F (3, 3), row i the force on vertex i: sign · p · (12 ^ 13)/2 · w_i (4.247-4.254 when the triangle
      is wholly behind the front; the consistent load of its part behind the front otherwise).
    """
    w = clipped_shape_integrals(front_heights(x, front, axis))
    return (sign * pressure) * w[:, None] * geometry.surface_vector(x)[None, :]


def volume_and_section(x, front, axis, sign=1.0):
    """This triangle's shares of the catch volume (m³) and of the front's cross-section (m²).

    Volume: divergence theorem with the field h(y) a (divergence 1): V = ∫_{netting behind the front}
    h (a·n) dS, n the outward normal, summed over the elements. The field vanishes on the front plane, so
    the catch's face on the front (the cap) adds nothing, and it is parallel to a, so symmetry planes
    containing the axis add nothing either: the sum over the netting alone is the enclosed volume. Per
    element: sign (a · (12 ^ 13)/2) Σ_i w_i h_i (h is linear, so ∫ h dS = S Σ w_i h_i); for a triangle
    wholly behind the front, its projected surface times its mean height, as FEMNET computes it.

    Section: sign (a · (12 ^ 13)/2) Σ_i w_i, the projection on the front plane of the part behind the
    front, signed by the outward normal. Summed over a netting that closes the catch it is the area of
    the catch's face on the front, = -dV/ds, and p times it is the catch drag (the axial component of
    the forces of :func:`catch_pressure`).
    """
    h = front_heights(x, front, axis)
    w = clipped_shape_integrals(h)
    projected = sign * jnp.dot(geometry.surface_vector(x), axis)
    return projected * jnp.dot(w, h), projected * jnp.sum(w)


def catch_volume(x, front, axis, sign=1.0):
    """This triangle's share (m³) of the volume enclosed by the netting and the front plane (see
    :func:`volume_and_section`)."""
    return volume_and_section(x, front, axis, sign)[0]


# -- the term --------------------------------------------------------------------------------------


def catch_pressure_on_element(x, state, sign):
    """:func:`catch_pressure` of one triangle at the front of ``state`` (:func:`jaxnet.model.catch.catch_state`)."""
    return catch_pressure(x, state["pressure"], state["front"], state["axis"], sign)


def _active(scene, dynamic):
    c = scene.catch
    if c is None or scene.netting is None or not scene.environment.current_speed > 0 or c.drag_coefficient == 0:
        return None
    if c.density > 0:  # a gravity catch: its hydrostatic pressure replaces this one (jaxnet.terms.gravity_catch)
        return None
    return {}


def off_tarps(p, value):
    """``value`` (per netting triangle) on the netting's triangles, 0 on a tarp's (``tarp_cd > 0``,
    :mod:`jaxnet.terms.tarp`: the water does not flow through a tarp, whose own term takes the pressure on its
    whole surface); ``value`` itself where the rows ``p`` have no ``tarp_cd`` column (rows made by hand)."""
    tarp_cd = getattr(p, "tarp_cd", None)
    return value if tarp_cd is None else jnp.where(tarp_cd > 0, 0.0, value)


def _arguments(p, env):
    # the catch's pressure, behind the front, is for the netting only (FEMNET's pres_pris_elem2:
    # Surface[elem].tarp == 0)
    return {"sign": off_tarps(p, p.outward)}


CATCH_PRESSURE = register(Term(
    name="catch_pressure", family="netting", kind=FORCE, element=catch_pressure_on_element,
    arguments=_arguments, active=_active, group=CATCH, state="jaxnet.model.catch:catch_state",
    closed_form=ClosedForm("jaxnet.closed_form.pressure:catch_pressure_on_element_stiffness")))
