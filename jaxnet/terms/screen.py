"""Screen models of the hydrodynamic force on netting: another option besides the book's twine drag (4.114-4.117).

The book sums Morison drag on each twine (sect. 4.3.3). Aquaculture engineers more often treat a piece of
netting as a permeable *screen*: a flat panel of area A and solidity Sn whose drag and lift coefficients
were measured in a flume as functions of Sn and of the inflow angle theta, the angle between the panel's
normal and the flow. For one triangular element of netting

    F = 1/2 rho A |c|² ( Cd(Sn, theta) e_drag + Cl(Sn, theta) e_lift ),                       (S1)

split one third per vertex as the book does with the twine drag. Here

* ``c`` is the velocity of the water relative to the netting (m/s): the current in statics;
* ``A`` is the element's deformed surface S = |12 ^ 13| / 2 (4.18), openings included, because the screen
  coefficients are per unit *panel* area;
* ``e_drag = c / |c|``;
* ``e_lift`` is the unit vector perpendicular to c, in the plane of c and of the normal, on the side the
  *downstream* face of the panel faces. With n_d the normal oriented downstream (n_d . c >= 0),
  e_lift = (n_d - (n_d . e_drag) e_drag) / sin(theta). Every fit below gives Cl > 0 for
  0 < theta < 90°, so the resultant leans from c towards n_d: the pressure drop across a screen pushes
  it along its normal, and the lift is the cross-flow part of that push. Example: flow along +x, panel
  normal (1, 1, 0)/sqrt 2 (theta = 45°): the lift points along +y. The test file checks this.
* ``theta`` is in [0, 90°]: cos(theta) = |n . c| / |c|, whatever the orientation of the normal n.

**Written without angles.** With x = n . c / |c| (signed; n either normal), Cl sin-type terms reduce to
polynomials: Cl(theta) e_lift = P(x²) x (n - x e_drag) for Cl = sin(2 theta) Q(cos² theta), and
Cd depends on |x|. Both are even in n, so a panel flipped over (vertex order reversed, d -> -d) gets the
same force, and no 0/0 appears at theta = 0 (where e_lift is undefined but Cl = 0). Expressed with the
area vector a = A n, (S1) needs no unit normal at all: A x n = x a and A |c|² Cd e_drag = A |c| Cd c,
so a collapsed element (A = 0) and still water (c = 0) give 0 with finite derivatives (double-where
guards on x, the only ratio).

**The kink at theta = 90°.** Cd is linear in |cos theta| in both fits: when the flow crosses the panel
plane the drag has a kink, and the tangent stiffness a jump. A netting panel aligned with the current is
common (the sides of a cage), so |x| is replaced by the smooth x tanh(x / w) with ``kink_width`` w
(default 0.01): equal to |x| to 1e-15 relative for |x| > 18 w (theta < 79.7° for w = 0.01), C-infinity
everywhere, 0 with zero slope at x = 0. ``kink_width=0`` gives the exact |x| (JAX then uses the
subgradient 0 at x = 0: finite, but the stiffness jumps across theta = 90°).

**Solidity** (:func:`solidity`). An element holds |d|/2 U twines and |d|/2 V twines (4.25-4.26), each a
cylinder of diameter D lying in the element plane, so their projected area on the panel is
|d|/2 D (L_U + L_V). The twine length is taken as the unstretched l0, as the book does for the twine drag
(sect. 4.3.3.1: elongation thins the twine by Poisson's effect, so D l0 approximates the stretched twine's
area better than D |U|), and for slack twines (|U| < l0, bowed) the material is still there. Hence

    Sn = |d| D l0 / S = 2 D l0 / |U ^ V|                  (S = |d| |U ^ V| / 2, by 4.28-4.29),

which gives the usual Sn = 2 D / l0 for an unstretched square mesh. The overlap of the two twines at a
knot (about D² per knot, i.e. the -(D / l0)² in the alternative 2 D/l0 - (D/l0)²) is neglected.
As meshes close, S -> 0 and this geometric Sn grows without bound, while the fits were made for
Sn <~ 0.4 and the Kristiansen-Faltinsen formulas are singular at Sn = 1. The force therefore uses a
smooth cap (:func:`effective_solidity`): 1/Sn is replaced by a softplus-max of 1/Sn and 1/Sn_max,
exact to ~1e-13 below 0.8 Sn_max. The default Sn_max = 0.5 is where the usual Løland formulas and
K&F (Cd_cyl = 1.2) reach Cd(0) ~ 1.8-1.9, about the drag of a solid flat plate: a closing netting panel
is never draggier than a plate.

**The two models.**

1. Løland-type polynomial fits (Løland 1991; Aarsnes, Rudi & Løland 1990):
       Cd = 0.04 + (-0.04 + p1 Sn + p2 Sn² + p3 Sn³) cos theta,
       Cl = (q1 Sn + q2 Sn² + q3 Sn³) sin 2 theta.
   Two coefficient sets circulate under these names. :data:`AARSNES_1990` (p = 1, -1.24, 13.7;
   q = 0.57, -3.54, 10.1) is the set usually quoted as "Løland's formulas" (and the one this module
   was asked to implement); Cheng et al. (2020, model S1) attribute it to Aarsnes et al. (1990) and give
   for Løland (1991) (their S2) :data:`LOLAND_1991` (p = 0.33, 6.54, -4.88; q = -0.05, 2.3, -1.76).
   :func:`loland_force` uses the first by default; pass ``coefficients=LOLAND_1991`` for the second.

2. Kristiansen & Faltinsen (2012), two-term Fourier series in theta:
       Cd = Cd(0) (a1 cos theta + a3 cos 3 theta),     a1 = 0.9, a3 = 0.1  (a1 + a3 = 1),
       Cl = Cl(45°) (b2 sin 2 theta + b4 sin 4 theta), b2 = 1.0, b4 = 0.1  (b2 sin 90° = 1),
       Cd(0)   = Cd_cyl Sn (2 - Sn) / (2 (1 - Sn)²),
       Cl(45°) = (Cn - Ct) / sqrt 2   with   Cn = Cd(0) cos² 45° = Cd(0) / 2,
                 Ct = pi Cn* / (8 + Cn*),   Cn* = Cd_cyl Sn / (2 (1 - Sn)²),
   Cd_cyl the drag coefficient of a smooth cylinder (the twine) at the Reynolds number
   Re = |c| D / (nu (1 - Sn)) of the flow accelerated through the openings, from the degree-7 fit in
   log10 Re of Cheng et al. (2020), held constant outside 10^1.5 <= Re <= 10^4.2 where it diverges.
   The Cd(0) expression is Bernoulli's pressure drop across the screen, Cd_cyl/2 [(1 - Sn)^-2 - 1]; the
   Fourier coefficients and Cl(45°) follow the implementation of Cheng et al. (2020). The Cl(45°) line
   is the least certain (see :func:`kristiansen_faltinsen_lift_45`).

**Velocity reduction.** Behind a screen the current is reduced by r = 1 - 0.46 Cd (Løland 1991),
Cd that of the upstream panel at its own inflow angle. :func:`velocity_reduction_factor` gives it; it
is *not* applied automatically, since which panels shadow which is a property of the scene.

References:
  Løland, G. (1991). Current forces on and flow through fish farms. Dr. ing. thesis, NTH Trondheim.
  Aarsnes, J. V., Rudi, H., Løland, G. (1990). Current forces on cage, net deflection. In: Engineering
    for Offshore Fish Farming, Thomas Telford, London.
  Kristiansen, T., Faltinsen, O. M. (2012). Modelling of current loads on aquaculture net cages.
    Journal of Fluids and Structures 34, 218-235.
  Cheng, H., Li, L., Aarsæther, K. G., Ong, M. C. (2020). Typical hydrodynamic models for aquaculture
    nets: a comparative study under pure current conditions. Aquacultural Engineering 90, 102070.

Units: positions m, velocities m/s, densities kg/m³, kinematic viscosity m²/s, forces N.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp

from jaxnet import geometry


class ScreenPolynomials(NamedTuple):
    """Coefficients of a Løland-type screen fit (dimensionless).

    Cd = 0.04 + (-0.04 + p1 Sn + p2 Sn² + p3 Sn³) cos theta,  Cl = (q1 Sn + q2 Sn² + q3 Sn³) sin 2 theta.
    """

    drag: tuple[float, float, float]  # (p1, p2, p3)
    lift: tuple[float, float, float]  # (q1, q2, q3)


#: The set usually quoted as Løland's formulas; Cheng et al. (2020) attribute it to Aarsnes et al. (1990).
AARSNES_1990 = ScreenPolynomials(drag=(1.0, -1.24, 13.7), lift=(0.57, -3.54, 10.1))
#: Løland (1991) as given by Cheng et al. (2020), model S2.
LOLAND_1991 = ScreenPolynomials(drag=(0.33, 6.54, -4.88), lift=(-0.05, 2.3, -1.76))

#: Fourier coefficients of Kristiansen & Faltinsen (2012): Cd ~ a1 cos + a3 cos 3, Cl ~ b2 sin 2 + b4 sin 4.
KF_A1, KF_A3, KF_B2, KF_B4 = 0.9, 0.1, 1.0, 0.1

#: Cheng et al. (2020) fit of the smooth-cylinder drag coefficient, coefficients of (log10 Re)^k, k = 0..7.
CYLINDER_DRAG_FIT = (-78.46675, 254.73873, -327.8864, 223.64577, -87.92234, 20.00769, -2.44894, 0.12479)
#: log10 Re range where that fit follows the cylinder curve; outside it the fit diverges (-78 at Re = 1).
CYLINDER_DRAG_LOG10_RE_RANGE = (1.5, 4.2)

#: Sharpness of the solidity cap, in units of Sn_max: the softplus in 1/Sn has sharpness 100 Sn_max, so the
#: capped Sn equals the geometric one to ~1e-13 relative below 0.8 Sn_max, and 0.993 Sn_max at Sn = Sn_max.
_CAP_SHARPNESS = 100.0


# ---------------------------------------------------------------------------------------------------
# Coefficients (functions of the solidity and of cos theta, theta in [0, 90°])


def _loland_drag_slope(sn, coefficients):
    """-0.04 + p1 Sn + p2 Sn² + p3 Sn³: the factor of cos theta in the Løland-type Cd."""
    p1, p2, p3 = coefficients.drag
    return -0.04 + sn * (p1 + sn * (p2 + sn * p3))


def _loland_lift_amplitude(sn, coefficients):
    """q1 Sn + q2 Sn² + q3 Sn³: the factor of sin 2 theta in the Løland-type Cl (= Cl at 45°)."""
    q1, q2, q3 = coefficients.lift
    return sn * (q1 + sn * (q2 + sn * q3))


def loland_coefficients(solidity, inflow_angle, coefficients=AARSNES_1990):
    """Drag and lift coefficients (Cd, Cl) of a Løland-type screen fit.

    Args:
      solidity: Sn (dimensionless), the fits being made for about 0.1 <= Sn <= 0.4.
      inflow_angle: theta in [0, pi/2] (rad), between the panel normal and the flow.
      coefficients: :data:`AARSNES_1990` (default, the usual "Løland formulas") or :data:`LOLAND_1991`.
    """
    cos_t, sin_t = jnp.cos(inflow_angle), jnp.sin(inflow_angle)
    cd = 0.04 + _loland_drag_slope(solidity, coefficients) * cos_t
    cl = _loland_lift_amplitude(solidity, coefficients) * 2.0 * sin_t * cos_t
    return cd, cl


def cylinder_drag_coefficient(reynolds):
    """Drag coefficient of a smooth circular cylinder (dimensionless) vs Reynolds number (Cheng et al. 2020).

    A polynomial of degree 7 in log10 Re; it matches the cylinder curve (1.36 at Re = 100, 1.005 at 1e3,
    1.09 at 1e4) only for 10^1.5 <= Re <= 10^4.2 and diverges outside (-78 at Re = 1, 10.9 at 1e5), so Re
    is clamped to that range (the end values are held). Re = 0 (still water) is safe.
    """
    lo, hi = CYLINDER_DRAG_LOG10_RE_RANGE
    log_re = jnp.log10(jnp.clip(reynolds, 10.0**lo, 10.0**hi))
    cd = jnp.zeros_like(log_re)
    for coefficient in reversed(CYLINDER_DRAG_FIT):  # Horner
        cd = cd * log_re + coefficient
    return cd


def twine_reynolds_number(speed, diameter, solidity, kinematic_viscosity=1.05e-6):
    """Reynolds number of a twine in a screen, |c| D / (nu (1 - Sn)) (Kristiansen & Faltinsen 2012).

    The velocity through the openings is |c| / (1 - Sn) by continuity. speed in m/s, diameter in m,
    kinematic_viscosity in m²/s.
    """
    return speed * diameter / (kinematic_viscosity * (1.0 - solidity))


def kristiansen_faltinsen_normal_drag(solidity, cylinder_drag):
    """Cd(0) = Cd_cyl Sn (2 - Sn) / (2 (1 - Sn)²): drag of a screen normal to the flow (K&F 2012).

    Bernoulli's pressure drop across the screen, Cd_cyl / 2 [(1 - Sn)^-2 - 1]. Singular at Sn = 1.
    """
    return cylinder_drag * solidity * (2.0 - solidity) / (2.0 * (1.0 - solidity) ** 2)


def kristiansen_faltinsen_lift_45(solidity, cylinder_drag):
    """Cl(45°) of Kristiansen & Faltinsen (2012) as implemented by Cheng et al. (2020).

    At 45° the normal and tangential force coefficients Cn, Ct give Cl = (Cn - Ct) / sqrt 2. The normal one
    is taken as Cd(0) cos² 45° = Cd(0) / 2, the tangential one as Ct = pi Cn* / (8 + Cn*) with
    Cn* = Cd_cyl Sn / (2 (1 - Sn)²). Uncertain: this is reproduced from Cheng et al.'s public code, not
    checked against the 2012 paper (an earlier version of that code had pi Cn*/(8 + Cn*) alone).
    """
    cn_star = cylinder_drag * solidity / (2.0 * (1.0 - solidity) ** 2)
    ct = jnp.pi * cn_star / (8.0 + cn_star)
    return (0.5 * kristiansen_faltinsen_normal_drag(solidity, cylinder_drag) - ct) / jnp.sqrt(2.0)


def _kf_drag_shape(cos_t):
    """a1 cos theta + a3 cos 3 theta, written as a polynomial in cos theta (cos 3t = 4 cos³ t - 3 cos t)."""
    return (KF_A1 - 3.0 * KF_A3) * cos_t + 4.0 * KF_A3 * cos_t**3


def _kf_lift_shape_over_sin_cos(cos_t):
    """(b2 sin 2t + b4 sin 4t) / (sin t cos t) = 2 b2 + 4 b4 cos 2t, a polynomial in cos² t."""
    return 2.0 * KF_B2 + 4.0 * KF_B4 * (2.0 * cos_t**2 - 1.0)


def kristiansen_faltinsen_coefficients(solidity, inflow_angle, cylinder_drag):
    """Drag and lift coefficients (Cd, Cl) of the Kristiansen & Faltinsen (2012) screen model.

    Args:
      solidity: Sn in [0, 1) (dimensionless).
      inflow_angle: theta in [0, pi/2] (rad), between the panel normal and the flow.
      cylinder_drag: Cd_cyl of the twine (e.g. :func:`cylinder_drag_coefficient` of
        :func:`twine_reynolds_number`, or a constant such as 1.2).
    """
    cos_t, sin_t = jnp.cos(inflow_angle), jnp.sin(inflow_angle)
    cd = kristiansen_faltinsen_normal_drag(solidity, cylinder_drag) * _kf_drag_shape(cos_t)
    cl = kristiansen_faltinsen_lift_45(solidity, cylinder_drag) * _kf_lift_shape_over_sin_cos(cos_t) * sin_t * cos_t
    return cd, cl


def velocity_reduction_factor(drag_coefficient):
    """Ratio r = u_behind / u_front of the current behind a screen, r = 1 - 0.46 Cd (Løland 1991).

    ``drag_coefficient`` is the Cd of the upstream screen at its own inflow angle (any model). For
    panels in series, the current on panel k is prod_{j<k} r_j times the free current. Floored at 0 (a
    screen with Cd > 2.17 would otherwise reverse the flow). Not applied by the force functions.
    """
    return jnp.maximum(1.0 - 0.46 * drag_coefficient, 0.0)


# ---------------------------------------------------------------------------------------------------
# Geometry of the screen


def _twine_area(uv, l0, diameter):
    """Projected area (m²) of the twines of one element: |d|/2 twines per family, each D l0."""
    d = geometry.twine_determinant(uv)
    return 2.0 * geometry.twine_count(d) * diameter * l0


def solidity(x, uv, l0, diameter):
    """Geometric solidity Sn = |d| D l0 / S of one deformed element (dimensionless); see the module text.

    For output: a collapsed element (S = 0) gives inf. The forces use :func:`effective_solidity`.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices.
      l0: unstretched twine length (m).
      diameter: twine diameter D (m).
    """
    area = geometry.surface(x)
    positive = area > 0.0
    return jnp.where(positive, _twine_area(uv, l0, diameter) / jnp.where(positive, area, 1.0), jnp.inf)


def _capped_solidity(area, twine_area, max_solidity):
    # 1/Sn = area / twine_area is bounded below by 0 and smooth in the positions; a softplus-max of it with
    # 1/Sn_max caps Sn smoothly without ever dividing by the (possibly zero) element area.
    has_twines = twine_area > 0.0
    inverse = area / jnp.where(has_twines, twine_area, 1.0)
    floor = 1.0 / max_solidity
    sharpness = _CAP_SHARPNESS * max_solidity  # in 1/Sn units: the same relative rounding for any cap
    capped_inverse = floor + jax.nn.softplus(sharpness * (inverse - floor)) / sharpness
    return jnp.where(has_twines, 1.0 / capped_inverse, 0.0)


def effective_solidity(x, uv, l0, diameter, max_solidity=0.5):
    """Solidity used by the forces: :func:`solidity` smoothly capped at ``max_solidity`` (dimensionless).

    Equal to the geometric Sn to ~1e-13 relative below 0.8 max_solidity; tends to max_solidity as the
    meshes close (S -> 0); finite, with finite derivatives, for a collapsed element.
    """
    return _capped_solidity(geometry.surface(x), _twine_area(uv, l0, diameter), max_solidity)


def inflow_angle(x, water_velocity):
    """Inflow angle theta in [0, pi/2] (rad) between the element normal and the flow, for output."""
    a = geometry.surface_vector(x)
    return jnp.arctan2(geometry.safe_norm(jnp.cross(a, water_velocity)), jnp.abs(jnp.dot(a, water_velocity)))


def _smooth_abs(value, width):
    # |value| rounded over |value| < ~3 width; width is a Python float (static: it selects the branch)
    if width == 0.0:
        return jnp.abs(value)
    return value * jnp.tanh(value / width)


class _Screen(NamedTuple):
    area_vector: jax.Array  # a = A n (m²), n either normal
    area: jax.Array  # A (m²)
    velocity: jax.Array  # c (m/s)
    speed: jax.Array  # |c| (m/s)
    cos_signed: jax.Array  # x = n . c / |c|, 0 when A = 0 or c = 0
    cos_abs: jax.Array  # cos theta = |x| (smoothed)
    solidity: jax.Array  # capped Sn


def _screen(x, uv, l0, diameter, water_velocity, max_solidity, kink_width):
    a = geometry.surface_vector(x)
    area = geometry.safe_norm(a)
    c = jnp.asarray(water_velocity, dtype=a.dtype)
    speed = geometry.safe_norm(c)
    scale = area * speed
    defined = scale > 0.0
    cos_signed = jnp.where(defined, jnp.dot(a, c) / jnp.where(defined, scale, 1.0), 0.0)
    sn = _capped_solidity(area, _twine_area(uv, l0, diameter), max_solidity)
    return _Screen(a, area, c, speed, cos_signed, _smooth_abs(cos_signed, kink_width), sn)


def _screen_force(screen, water_density, drag_coefficient, lift_over_sin_cos):
    """Eq. (S1) for one element, spread one third per vertex: (3, 3) N.

    ``lift_over_sin_cos`` is Cl / (sin theta cos theta), a function of cos² theta: then
    A |c|² Cl e_lift = lift_over_sin_cos (|c|² x a - A |c| x² c), with x = n . c / |c| signed.
    """
    s = screen
    drag = s.area * s.speed * drag_coefficient * s.velocity
    x = s.cos_signed
    lift = lift_over_sin_cos * (s.speed**2 * x * s.area_vector - s.area * s.speed * x**2 * s.velocity)
    total = 0.5 * water_density * (drag + lift)
    return jnp.broadcast_to(total / 3.0, (3, 3))


def loland_force(
    x, uv, l0, diameter, water_velocity, water_density, *, coefficients=AARSNES_1990, max_solidity=0.5, kink_width=1e-2
):
    """Nodal forces (3, 3) in N of a Løland-type screen model on one diamond-mesh triangle, 1/3 per vertex.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines); either orientation (d < 0 allowed).
      l0: unstretched twine length (m).
      diameter: twine diameter D (m).
      water_velocity: (3,) velocity of the water relative to the netting (m/s).
      water_density: rho (kg/m³).
      coefficients: :data:`AARSNES_1990` (default) or :data:`LOLAND_1991`.
      max_solidity: cap of the solidity (see :func:`effective_solidity`).
      kink_width: rounding of |cos theta| at theta = 90°, a Python float (0: exact; see the module text).
    """
    s = _screen(x, uv, l0, diameter, water_velocity, max_solidity, kink_width)
    cd = 0.04 + _loland_drag_slope(s.solidity, coefficients) * s.cos_abs
    lift = 2.0 * _loland_lift_amplitude(s.solidity, coefficients)  # sin 2t = 2 sin t cos t
    return _screen_force(s, water_density, cd, lift)


def kristiansen_faltinsen_force(
    x,
    uv,
    l0,
    diameter,
    water_velocity,
    water_density,
    kinematic_viscosity=1.05e-6,
    *,
    cylinder_drag=None,
    max_solidity=0.5,
    kink_width=1e-2,
):
    """Nodal forces (3, 3) in N of the Kristiansen & Faltinsen (2012) screen model on one triangle.

    Args:
      x, uv, l0, diameter, water_velocity, water_density: as :func:`loland_force`.
      kinematic_viscosity: nu of the water (m²/s), for the twine Reynolds number.
      cylinder_drag: None (default) for Cd_cyl from :func:`cylinder_drag_coefficient` at the twine Reynolds
        number :func:`twine_reynolds_number`, or a constant Cd_cyl (dimensionless).
      max_solidity: cap of the solidity, < 1 (the formulas are singular at Sn = 1).
      kink_width: rounding of |cos theta| at theta = 90°, a Python float.
    """
    s = _screen(x, uv, l0, diameter, water_velocity, max_solidity, kink_width)
    if cylinder_drag is None:
        reynolds = twine_reynolds_number(s.speed, diameter, s.solidity, kinematic_viscosity)
        cylinder_drag = cylinder_drag_coefficient(reynolds)
    cd = kristiansen_faltinsen_normal_drag(s.solidity, cylinder_drag) * _kf_drag_shape(s.cos_abs)
    lift = kristiansen_faltinsen_lift_45(s.solidity, cylinder_drag) * _kf_lift_shape_over_sin_cos(s.cos_signed)
    return _screen_force(s, water_density, cd, lift)
