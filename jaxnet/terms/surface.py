"""Weight and buoyancy near the free surface, as per-element potential energies (book §4.3.9, eq. 4.277).

:mod:`jaxnet.terms.gravity` gives the *immersed* weight (4.277) as constant nodal loads, which holds for a
net that is entirely under water. The book notes that a net crossing the water surface adds a stiffness
("not described here", end of §4.3.9). Floating collars (HDPE pipes), float lines and surface buoys float
*because* they are partly immersed; their vertical stiffness is the change of immersed volume with height.
This module writes weight and buoyancy together as one conservative potential.

Potential. A body of mass m (kg) and volume V (m³) whose centre is at height h = x·up - surface_level (m)
above the water plane has the energy

    E = m g (x·up) - rho g V Phi(h),       Phi(h) = -∫_h^∞ f(h') dh'   (m),

with f the immersed fraction (below). Then -dE/dh = -m g + rho g V f(h): weight plus the buoyancy of the
immersed volume V f(h) (Archimedes), and d²E/dh² = -rho g V f'(h) = rho g A_wp, the waterplane stiffness
(A_wp = -dV_imm/dh, m², the area the body cuts in the water plane). The energy is the hydrostatic one:
pushing a float down by dh costs rho g V_imm dh. Because f = 1 below the band, Phi(h) = h there *exactly*
(the profile is point-symmetric, so its mean over the band is 1/2) and -grad E is exactly the constant
load -(m - rho V) g up of :mod:`jaxnet.terms.gravity`; above the band Phi = 0 and the body weighs m g in air.

Profile (why a horizontal cylinder). f is the exact immersed fraction of a horizontal circular cylinder
of diameter T = ``thickness`` whose axis is at height h; with t = 2h/T,

    f(t) = (acos t - t sqrt(1 - t²)) / pi   for |t| < 1,   1 for t <= -1,   0 for t >= 1,
    f'(t) = -(2/pi) sqrt(1 - t²),
    Phi(h) = (T/2) phi(t),   phi(t) = (t acos t - sqrt(1 - t²) (2 + t²)/3) / pi,   phi = t (t <= -1), 0 (t >= 1).

The bodies that float in a fish-farm model are horizontal pipes (collar, float lines): for them this
profile is not a smoothing but the exact waterplane physics, so the draft and heave stiffness of a
floating collar come out right with no tuning parameter. f is C¹ (f' -> 0 at both edges), so E is C²
and its Hessian, the stiffness Newton needs, is continuous everywhere. f'' (hence the derivative of the
stiffness) grows like 1/sqrt(1 - t²) at the edges; this only matters when an equilibrium sits exactly
where a body touches the surface, and Newton converges quadratically for any equilibrium inside the band.
A C² polynomial (smoothstep) would be smoother but is no body's exact fraction; a sphere (cubic fraction)
is C¹ only, like the cylinder. For a node float of another shape, ``thickness`` is its height and the
cylinder profile is an approximation of its draft curve with the right volume and the right limits.

Boxes (FEMNET's node bodies). A node whose body is a box (``Nodes.drag_length``, L_z != 0: FEMNET's node types)
floats as that box, not as a cylinder centred on the node: the box stands on its node (above it for L_z > 0,
below for L_z < 0), its waterplane area is constant, so its immersed fraction is linear in the height and its
stiffness rho g L_x L_y while it crosses the surface (:func:`box_fraction_integral`, FEMNET's ``flotteur2.c``).

Families. ``Environment.floating`` names the families whose weight and buoyancy feel the surface (all by
default); the others keep their constant immersed load (:mod:`jaxnet.terms.gravity`) wherever they are. The
drag of every family sees the surface whatever ``floating`` says (:func:`jaxnet.terms.drag.wetted_shares`).
Hexagonal netting floats as diamond netting does, its three families' twines lumped a third at each vertex.

Derivatives. f and phi carry analytic derivative rules (``jax.custom_jvp``): differentiating acos and
sqrt by automatic differentiation near |t| = 1 cancels terms of size 1/sqrt(1 - t²), and is NaN at
|t| = 1. The rules phi' = f, f' = -(2/pi) sqrt(1 - t²) are exact and finite everywhere, so grad and
jacfwd(grad) are NaN-free at the band edges, at h = 0 and deep or high above it.

Lumping. Like :mod:`jaxnet.terms.gravity`, volume and mass are lumped at nodes: a cable bar puts half of
its volume at each end, each end immersed according to its own height with T = the bar diameter; a
netting triangle puts one third on each vertex with T = the twine diameter. For a horizontal bar (a collar
at rest) the lumped immersed volume is exact. Integrating along an inclined bar in closed form is possible
(exact slices perpendicular to the axis have the cylinder fraction with T = D |cos(slope)|, and the
integral of Phi along a straight bar is a divided difference of the second antiderivative of f by
(h1 - h0)²) but that quotient is a removable 0/0 precisely for the horizontal bar, the common case, where
its second derivatives cannot be evaluated stably. On an inclined bar crossing the surface the lumped
immersed volume is a two-step staircase in the waterline height instead of a ramp (steps as far apart as
the ends' height difference): the error vanishes as the cable is refined, and a vertical spar crossing
the surface needs several bars.

Netting and a thin band (Newton). With T = twine diameter (mm) the netting's fraction is nearly a step:
a vertex's load changes by rho g V_vertex when it crosses a band of width T, so its peak surface stiffness
is (4/pi) rho g V_vertex / T = rho g (waterplane area of the twines lumped at the vertex), i.e. 1 N/m
for ~1e-4 m² of twine, tiny next to the stiffness of a taut net (T_twine/l0 ~ 10-1000 N/m per twine).
Outside the band the term adds no stiffness, so a Newton step taken from outside lands at the
equilibrium for the constant load of that side. If the vertex's structural vertical stiffness k is
below rho g V_vertex / T (slack netting lying at the surface), the dry and wet equilibria lie on
opposite sides of the band and *undamped* Newton can 2-cycle between them. Because this term is an
energy, the energy line search of :mod:`jaxnet.solve.statics` rejects such steps and converges; no
minimum width is needed for correctness. Where pure Newton must be used, or to make convergence fast for
slack netting at the surface, pass ``thickness`` >= rho g V_vertex / k to :func:`netting_gravity_energy`
(it changes only the transition, never the immersed or emerged loads).

Waves. In a time step in waves the water plane is the wave's surface: ``surface_level`` is then the surface's
height over each vertex (one per vertex, the elevation η over its node at the step's start added to the mean
level: :attr:`jaxnet.scene.Environment.surface_elevation`, :func:`jaxnet.model.assemble.element_environment`), so a
float rides the wave and a collar under a crest is more immersed than under a trough, as in FEMNET's ``dyna``
(``flotteurelement_dyna2.c``). Within the step η is held (a number per vertex, not a function of the position),
so the energy above stays an energy and its gradient is vertical.

Conventions: ``up`` is the unit vertical (m/m), ``surface_level`` the height of the water plane along up
(m; a scalar, or one height per vertex in waves, which every formula here takes element-wise), g > 0 (m/s²). Every function here is a pure jnp function of one element (vmappable, no Python
control flow on traced values). ``thickness`` must be > 0; a bar or twine of diameter 0 has no volume, and its
band is taken as 1 m so that it stays finite.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np


from jaxnet import geometry
from jaxnet.terms.gravity import weight_activity
from jaxnet.scene import feels_surface
from jaxnet.terms.term import ENERGY, WEIGHT, Term, any_nonzero, register


def _inside(t):
    return jnp.abs(t) < 1.0


def _half_chord(t):
    """sqrt(1 - t²) inside the band, 0 outside, with finite derivatives everywhere (double where)."""
    inside = _inside(t)
    return jnp.where(inside, jnp.sqrt(jnp.where(inside, 1.0 - t * t, 1.0)), 0.0)


def fraction_slope(t):
    """Derivative df/dt of the dimensionless cylinder fraction: -(2/pi) sqrt(1 - t²), 0 for |t| >= 1."""
    return -(2.0 / jnp.pi) * _half_chord(t)


@jax.custom_jvp
def cylinder_fraction(t):
    """Immersed fraction (dimensionless) of a horizontal cylinder whose axis is at t radii above the water."""
    inside = _inside(t)
    tc = jnp.where(inside, t, 0.0)
    segment = (jnp.arccos(tc) - tc * _half_chord(tc)) / jnp.pi
    return jnp.where(inside, segment, jnp.where(t <= -1.0, 1.0, 0.0))


@cylinder_fraction.defjvp
def _cylinder_fraction_jvp(primals, tangents):
    (t,), (dt,) = primals, tangents
    return cylinder_fraction(t), fraction_slope(t) * dt


@jax.custom_jvp
def cylinder_fraction_integral(t):
    """phi(t) = -∫_t^∞ f (dimensionless): t below the band (t <= -1), 0 above it (t >= 1)."""
    inside = _inside(t)
    tc = jnp.where(inside, t, 0.0)
    band = (tc * jnp.arccos(tc) - _half_chord(tc) * (2.0 + tc * tc) / 3.0) / jnp.pi
    return jnp.where(inside, band, jnp.where(t <= -1.0, t, 0.0))


@cylinder_fraction_integral.defjvp
def _cylinder_fraction_integral_jvp(primals, tangents):
    (t,), (dt,) = primals, tangents
    return cylinder_fraction_integral(t), cylinder_fraction(t) * dt


def immersed_fraction(h, thickness):
    """Immersed fraction (0..1) of a body whose centre is ``h`` (m) above the water plane.

    The exact fraction of a horizontal cylinder of diameter ``thickness`` (m, > 0): 1 for
    h <= -thickness/2, 0 for h >= thickness/2, C¹ in between (see the module docstring).
    """
    return cylinder_fraction(2.0 * h / thickness)


def immersed_fraction_integral(h, thickness):
    """Antiderivative Phi(h) = -∫_h^∞ f (m) of :func:`immersed_fraction`: a smoothed min(h, 0).

    Equal to h for h <= -thickness/2 and to 0 for h >= thickness/2; dPhi/dh = immersed_fraction(h).
    """
    return 0.5 * thickness * cylinder_fraction_integral(2.0 * h / thickness)


def box_fraction_integral(height, vertical_length, surface_level):
    """Antiderivative Phi (m) in the node's height of the immersed fraction of a box standing on its node
    (FEMNET's node body, :func:`jaxnet.terms.drag.box_immersed_fraction`: the box spans
    [z + min(L_z, 0), z + max(L_z, 0)], above its node for L_z > 0, below it for L_z < 0).

    With d = s - z_bottom the depth of the box's bottom under the surface and H = |L_z|: Phi = 0 while the box
    is out of the water (d <= 0), -d²/(2H) while it crosses the surface, H/2 - d once immersed (d >= H). So
    dPhi/dz = d/H clipped to [0, 1], the immersed fraction, which is linear in the height because a box's
    waterplane area is constant: FEMNET's buoyancy rho g L_x L_y h (``flotteur2.c``) and its stiffness
    rho g L_x L_y while crossing. A flat box (H = 0) is immersed when its node is under the surface
    (Phi = min(-d, 0)), as the drag's fraction has it.

    Args:
      height: the node's height z along ``up`` (m).
      vertical_length: L_z, the box's signed height (m).
      surface_level: height s of the water plane (m).
    """
    size = jnp.abs(vertical_length)
    d = surface_level - (height + jnp.minimum(vertical_length, 0.0))
    flat = size == 0.0
    safe = jnp.where(flat, 1.0, size)
    crossing = -jnp.clip(d, 0.0, safe) ** 2 / (2.0 * safe)
    immersed = 0.5 * safe - d
    box = jnp.where(d >= safe, immersed, crossing)
    return jnp.where(flat, jnp.minimum(-d, 0.0), box)


def immersion_band(diameter):
    """The immersion band (m) of a bar or twine: its diameter; 1 m where the diameter is 0 (a link of no volume,
    common in FEMNET's files: it then has no weight, buoyancy nor drag at all, and the band only keeps h / band
    finite)."""
    return jnp.where(diameter > 0.0, diameter, 1.0)


def node_band(size, volume):
    """The immersion band (m) of a body lumped at a node: its ``size`` (m) where given (> 0; None: nowhere), else
    the diameter of the sphere of its ``volume`` (m³), 1 mm at least."""
    sphere = jnp.cbrt(6.0 * volume / jnp.pi)
    return jnp.maximum(sphere if size is None else jnp.where(size > 0, size, sphere), 1e-3)


def _height(x, up, surface_level):
    """Height (m) above the water plane of points x (..., 3)."""
    return x @ up - surface_level


def node_gravity_energy(x, mass, volume, thickness, water_density, g, up, surface_level, box_height=None):
    """Potential energy (J) of weight and buoyancy of one body lumped at a node.

    Args:
      x: (3,) node position (m).
      mass: mass of the body (kg).
      volume: its volume (m³), fully immersed.
      thickness: its vertical extent (m, > 0), over which it goes from immersed to emerged (a floating
        pipe or horizontal cylindrical float: its diameter).
      water_density: (kg/m³). g: gravity (m/s²). up: (3,) unit vertical. surface_level: height of the
        water plane along up (m).
      box_height: None, or the signed height L_z (m) of a box body standing on the node (FEMNET's node types):
        where it is not 0 the body floats as that box (:func:`box_fraction_integral`), not as a cylinder
        centred on the node.
    Returns:
      m g (x·up) - rho g V Phi(h): -grad is the weight in air plus the buoyancy of the immersed part (N).
    """
    h = _height(x, up, surface_level)
    phi = immersed_fraction_integral(h, thickness)
    if box_height is not None:
        phi = jnp.where(box_height != 0.0, box_fraction_integral(x @ up, box_height, surface_level), phi)
    return mass * g * (x @ up) - water_density * g * volume * phi


def bar_gravity_energy(x, rest_length, diameter, density, water_density, g, up, surface_level):
    """Potential energy (J) of weight and buoyancy of one cable bar, half lumped at each end.

    Args:
      x: (2, 3) end positions (m).
      rest_length: unstretched length L0 (m); the bar's volume is (pi D²/4) L0.
      diameter: outer diameter D (m), also the immersion band of each end (exact for a horizontal pipe).
      density: mass of the bar over its outer volume (kg/m³): for a hollow collar pipe, its mass per metre
        (plus ballast) divided by pi D²/4.
      water_density, g, up, surface_level: as in :func:`node_gravity_energy`.
    """
    half_volume = geometry.twine_volume(0.5, rest_length, diameter)
    h = _height(x, up, surface_level)
    return jnp.sum(
        density * half_volume * g * (x @ up)
        - water_density * g * half_volume * immersed_fraction_integral(h, immersion_band(diameter))
    )


def netting_gravity_energy(x, uv, l0, diameter, density, water_density, g, up, surface_level, thickness=None):
    """Potential energy (J) of weight and buoyancy of the twines of one netting triangle.

    The triangle holds |d| twines of length l0 and diameter D (eq. 4.277); one third of their volume
    |d| (pi D²/4) l0 is lumped at each vertex, immersed according to the vertex's own height. Fully
    immersed, -grad equals :func:`jaxnet.terms.gravity.netting_weight` exactly.

    Args:
      x: (3, 3) vertex positions (m). uv: (3, 2) twine coordinates (twines); clockwise (d < 0) allowed.
      l0: unstretched twine length (m). diameter: twine diameter D (m). density: twine material (kg/m³).
      water_density, g, up, surface_level: as in :func:`node_gravity_energy`.
      thickness: immersion band (m); None means the twine diameter. A wider band only smooths the
        transition (see the module docstring on Newton with a thin band).
    """
    d = geometry.twine_determinant(uv)
    vertex_volume = geometry.twine_volume(jnp.abs(d), l0, diameter) / 3.0
    band = immersion_band(diameter) if thickness is None else thickness
    h = _height(x, up, surface_level)
    return jnp.sum(
        density * vertex_volume * g * (x @ up)
        - water_density * g * vertex_volume * immersed_fraction_integral(h, band)
    )


def hexagonal_gravity_energy(x, uv, l0, diameter, density, water_density, g, up, surface_level):
    """Potential energy (J) of weight and buoyancy of the twines of one hexagonal-mesh triangle: |d| twines of
    each family l, m, n (lengths ``l0``, (3,) m) of diameter D, lumped a third at each vertex as for diamond
    netting (:func:`netting_gravity_energy` of the summed length); fully immersed, -grad equals
    :func:`jaxnet.terms.gravity.hexagonal_weight` exactly."""
    return netting_gravity_energy(x, uv, jnp.sum(l0), diameter, density, water_density, g, up, surface_level)


# -- the terms -------------------------------------------------------------------------------------


def _netting_arguments(p, env):
    return {"uv": p.uv, "l0": p.l0, "diameter": p.diameter, "density": p.density, "water_density": env.water_density,
            "g": env.gravity, "up": env.up, "surface_level": env.surface_level}


def _bar_arguments(p, env):
    return {"rest_length": p.rest_length, "diameter": p.diameter, "density": p.density,
            "water_density": env.water_density, "g": env.gravity, "up": env.up, "surface_level": env.surface_level}


def _node_arguments(p, env, boxes=False):
    # a body given no size is taken as the sphere of its volume (1 mm at least) for its waterline band
    return {"mass": p.mass, "volume": p.volume, "thickness": node_band(p.size, p.volume),
            "water_density": env.water_density,
            "g": env.gravity, "up": env.up, "surface_level": env.surface_level,
            **({"box_height": p.drag_length[2]} if boxes else {})}


def _node_gravity(x, mass, volume, thickness, water_density, g, up, surface_level, box_height=None):
    return node_gravity_energy(x[0], mass, volume, thickness, water_density, g, up, surface_level, box_height)


def _node_activity(scene, dynamic):
    """Present with a free surface the nodes feel (``Environment.floating``) and a node of some mass or volume;
    option ``boxes`` where a node with a volume has a box body of some height (``Nodes.drag_length``): it floats
    as that box."""
    n = scene.nodes
    if scene.environment.gravity == 0 or not feels_surface(scene, "nodes") or not (any_nonzero(n.mass)
                                                                                 or any_nonzero(n.volume)):
        return None
    boxes = n.drag_length is not None and bool(np.any((np.asarray(n.drag_length, dtype=float)[:, 2] != 0.0)
                                                     & (np.asarray(n.volume, dtype=float) > 0.0)))
    return {"boxes": True} if boxes else {}


NETTING_GRAVITY_AT_SURFACE = register(Term(
    name="netting_gravity_at_surface", family="netting", kind=ENERGY, element=netting_gravity_energy,
    arguments=_netting_arguments, active=weight_activity("netting", at_surface=True), group=WEIGHT))
BAR_GRAVITY_AT_SURFACE = register(Term(
    name="bar_gravity_at_surface", family="bars", kind=ENERGY, element=bar_gravity_energy,
    arguments=_bar_arguments, active=weight_activity("bars", at_surface=True), group=WEIGHT))
HEXAGONAL_GRAVITY_AT_SURFACE = register(Term(
    name="hexagonal_gravity_at_surface", family="hexagonal", kind=ENERGY, element=hexagonal_gravity_energy,
    arguments=_netting_arguments, active=weight_activity("hexagonal", at_surface=True), group=WEIGHT))
NODE_GRAVITY_AT_SURFACE = register(Term(
    name="node_gravity_at_surface", family="nodes", kind=ENERGY, element=_node_gravity, arguments=_node_arguments,
    active=_node_activity, group=WEIGHT))
