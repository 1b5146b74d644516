"""Weight and buoyancy near the free surface (jaxnet.terms.surface), checked against independent physics.

The reference immersed fraction is computed here by numerically integrating the chord width of a circle
(scipy quad), not from the closed form in the module; equilibrium drafts are roots found by brentq.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq

import jaxnet  # noqa: F401  (float64)
from jaxnet.terms import gravity, surface

RHO, G = 1025.0, 9.81
UP = jnp.array([0.3, -0.2, 0.9]) / np.linalg.norm([0.3, -0.2, 0.9])  # not an axis: catches a hard-coded z
LEVEL = 1.7  # water plane height along UP (m)


def reference_fraction(h, diameter):
    """Immersed fraction of a horizontal cylinder (axis h above water): wetted chord width integrated."""
    r = diameter / 2.0
    top = min(max(-h, -r), r)  # the water covers y in [-r, -h] relative to the axis
    wet, _ = quad(lambda y: 2.0 * np.sqrt(max(r * r - y * y, 0.0)), -r, top, epsabs=1e-15, epsrel=1e-13)
    return wet / (np.pi * r * r)


FRACTION = jax.jit(surface.immersed_fraction)
FRACTION_SLOPE = jax.jit(jax.grad(surface.immersed_fraction))
FRACTION_INTEGRAL = jax.jit(surface.immersed_fraction_integral)


def at_height(h, lateral=(0.4, -1.1, 0.2)):
    """A point h metres above the water plane (plus some horizontal offset)."""
    lateral = np.asarray(lateral) - np.dot(lateral, UP) * np.asarray(UP)
    return jnp.asarray(lateral + (LEVEL + h) * np.asarray(UP))


class Term:
    """Energy, force-gradient and stiffness of one element kind, each jitted once for every parameter set."""

    def __init__(self, energy, shape):
        flat = lambda x, params: energy(x.reshape(shape), *params)  # noqa: E731
        self._e, self._g = jax.jit(flat), jax.jit(jax.grad(flat))
        self._k = jax.jit(jax.jacfwd(jax.grad(flat)))

    def __call__(self, *params):
        params = tuple(jnp.asarray(p, dtype=float) for p in params)
        bound = lambda fn: (lambda x: fn(x, params))  # noqa: E731
        return bound(self._e), bound(self._g), bound(self._k)


NODE = Term(lambda x, m, v, t: surface.node_gravity_energy(x, m, v, t, RHO, G, UP, LEVEL), (3,))
BAR = Term(lambda x, l, d, rho: surface.bar_gravity_energy(x, l, d, rho, RHO, G, UP, LEVEL), (2, 3))
NETTING = Term(
    lambda x, uv, l0, d, rho, t: surface.netting_gravity_energy(x, uv, l0, d, rho, RHO, G, UP, LEVEL, thickness=t),
    (3, 3),
)


def node_energy(mass, volume, thickness):
    """(energy, gradient, stiffness) of a node body, functions of its position (3,)."""
    return NODE(mass, volume, thickness)


def bar_energy(rest_length, diameter, density):
    """(energy, gradient, stiffness) of a bar, functions of its flattened end positions (6,)."""
    return BAR(rest_length, diameter, density)


def netting_energy(uv, l0, diameter, density, thickness=None):
    """(energy, gradient, stiffness) of a triangle, functions of its flattened vertex positions (9,)."""
    return NETTING(uv, l0, diameter, density, diameter if thickness is None else thickness)


UV = jnp.array([[0.0, 0.0], [2.0, -5.0], [6.0, 4.0]])  # d = 38 (the book's example), clockwise if reordered


# ---------------------------------------------------------------- the profile


def test_fraction_is_the_wetted_area_of_a_horizontal_cylinder():
    thickness = 0.25
    for h in np.linspace(-0.2, 0.2, 17):
        np.testing.assert_allclose(
            float(FRACTION(h, thickness)), reference_fraction(h, thickness), rtol=1e-10, atol=1e-13
        )


def test_fraction_integral_is_its_antiderivative_and_a_smoothed_min():
    thickness = 0.25
    phi = lambda h: FRACTION_INTEGRAL(h, thickness)  # noqa: E731
    for h in np.linspace(-0.124, 0.124, 9):
        # Phi(h) = -∫_h^{T/2} f, integrated numerically from the reference fraction
        integral, _ = quad(lambda s: reference_fraction(s, thickness), h, thickness / 2, epsabs=1e-14)
        np.testing.assert_allclose(float(phi(h)), -integral, rtol=1e-9, atol=1e-13)
        eps = 1e-6
        slope = (float(phi(h + eps)) - float(phi(h - eps))) / (2 * eps)
        np.testing.assert_allclose(slope, float(FRACTION(h, thickness)), atol=1e-9)
    # exactly min(h, 0) outside the band, so that the deep loads are the constant ones
    for h in (-5.0, -0.125, 0.125, 3.0):
        assert float(phi(h)) == pytest.approx(min(h, 0.0), abs=1e-15)


def test_fraction_and_its_derivative_are_continuous_at_the_band_edges():
    thickness = 0.1
    f = lambda h: float(FRACTION(h, thickness))  # noqa: E731
    cap = 4.0 * np.sqrt(2.0) / (3.0 * np.pi)  # a circular cap of height a: area (4 sqrt2 / 3) sqrt(R) a^1.5
    for edge, outside in ((-thickness / 2, 1.0), (thickness / 2, 0.0)):
        assert f(edge) == outside
        for eps in (1e-5, 1e-7):
            inward = eps * np.sign(-edge)
            delta = eps / (thickness / 2)  # cap height in radii
            # C0, and how: the value leaves the constant outside as the wetted (or dry) cap, ~ delta^1.5
            np.testing.assert_allclose(abs(f(edge + inward) - outside), cap * delta**1.5, rtol=2e-4)
            # C1: the one-sided slope from inside tends to 0, the slope outside, like sqrt(delta) (a linear
            # ramp would give 1/thickness = 10 whatever eps, i.e. a kink)
            one_sided_inside = (f(edge + inward) - f(edge)) / inward
            one_sided_outside = (f(edge) - f(edge - inward)) / (-inward)
            assert one_sided_outside == 0.0
            np.testing.assert_allclose(abs(one_sided_inside), cap * delta**0.5 / (thickness / 2), rtol=2e-4)
    # and inside, the slope is -(2/pi) sqrt(1 - t²) (2/T): the chord of the circle over its area
    df = lambda h: FRACTION_SLOPE(h, thickness)  # noqa: E731
    for h in (-0.049, -0.02, 0.0, 0.03, 0.0499):
        fd = (f(h + 1e-7) - f(h - 1e-7)) / 2e-7
        chord = 2.0 * np.sqrt((thickness / 2) ** 2 - h * h)
        np.testing.assert_allclose(float(df(h)), fd, rtol=1e-6)
        np.testing.assert_allclose(float(df(h)), -chord / (np.pi * thickness**2 / 4), rtol=1e-12)


# ---------------------------------------------------------------- limits: deep and in air


def test_fully_immersed_loads_are_exactly_those_of_gravity():
    # node: a float and a sinker
    for mass, volume in ((3.0, 0.01), (40.0, 0.002)):
        _, grad, stiff = node_energy(mass, volume, 0.3)
        x = at_height(-0.2)
        np.testing.assert_allclose(-grad(x), gravity.node_weight(mass, volume, RHO, G, UP), rtol=1e-12, atol=0.0)
        assert float(jnp.max(jnp.abs(stiff(x)))) == 0.0  # no stiffness under water
    # bar: ends at different depths, both below the band
    _, grad, _ = bar_energy(1.3, 0.05, 1140.0)
    x = jnp.concatenate([at_height(-0.03), at_height(-2.0, lateral=(1.0, 0.0, 0.0))])
    np.testing.assert_allclose(
        -grad(x).reshape(2, 3), gravity.bar_weight(1.3, 0.05, 1140.0, RHO, G, UP), rtol=1e-12
    )
    # netting, both orientations of the triangle
    for uv in (UV, UV[jnp.array([0, 2, 1])]):
        _, grad, _ = netting_energy(uv, 0.02, 0.002, 1140.0)
        x = jnp.concatenate([at_height(-0.0011), at_height(-0.5, (1, 0, 0)), at_height(-3.0, (0, 1, 0))])
        np.testing.assert_allclose(
            -grad(x).reshape(3, 3),
            gravity.netting_weight(uv, 0.02, 0.002, 1140.0, RHO, G, UP),
            rtol=1e-12,
        )


def test_fully_emerged_body_weighs_its_weight_in_air():
    mass, volume = 3.0, 0.01
    f = -node_energy(mass, volume, 0.3)[1](at_height(0.15))
    np.testing.assert_allclose(f, -mass * G * UP, rtol=1e-13)
    # a netting triangle hanging in air: |d| pi D²/4 l0 rho_netting g, a third per vertex
    _, grad, _ = netting_energy(UV, 0.02, 0.002, 1140.0)
    x = jnp.concatenate([at_height(0.0011), at_height(0.5, (1, 0, 0)), at_height(3.0, (0, 1, 0))])
    per_vertex = 38 * np.pi * 0.002**2 / 4 * 0.02 * 1140.0 * G / 3
    np.testing.assert_allclose(-grad(x).reshape(3, 3), -per_vertex * np.tile(UP, (3, 1)), rtol=1e-13)


# ---------------------------------------------------------------- floating: draft and waterplane stiffness


def newton_in_height(term, x0, iterations=30):
    """Newton on the energy with every point moving along UP together (the horizontal carries no load)."""
    _, grad, hess = term
    shift = jnp.tile(UP, x0.size // 3)
    x = x0
    for _ in range(iterations):
        x = x - float(grad(x) @ shift) / float(shift @ hess(x) @ shift) * shift
    return x, grad(x)


@pytest.mark.parametrize("density_ratio", [0.12, 0.5, 0.93])
def test_floating_node_sits_where_displaced_water_weighs_its_mass(density_ratio):
    diameter, volume = 0.4, 0.08
    mass = density_ratio * RHO * volume
    x, residual = newton_in_height(node_energy(mass, volume, diameter), at_height(0.1))
    assert float(jnp.max(jnp.abs(residual))) < 1e-12 * mass * G
    h_root = brentq(lambda h: RHO * volume * reference_fraction(h, diameter) - mass, -0.2, 0.2, xtol=1e-14)
    assert float(x @ UP) - LEVEL == pytest.approx(h_root, abs=1e-10)


def test_horizontal_pipe_bar_floats_at_the_exact_draft():
    # a collar pipe bar of effective density 300 kg/m³: its wetted cross-section fraction is 300/1025
    diameter, density = 0.5, 300.0
    x0 = jnp.concatenate([at_height(0.2), at_height(0.2, lateral=(2.0, 0.0, 0.0))])
    x, residual = newton_in_height(bar_energy(2.0, diameter, density), x0)
    h_root = brentq(lambda h: reference_fraction(h, diameter) - density / RHO, -0.25, 0.25, xtol=1e-14)
    heights = x.reshape(2, 3) @ UP - LEVEL
    np.testing.assert_allclose(heights, [h_root, h_root], atol=1e-10)
    np.testing.assert_allclose(residual, 0.0, atol=1e-12 * density * np.pi * diameter**2 / 4 * 2.0 * G)


def test_hessian_is_the_waterplane_stiffness():
    diameter, volume, mass = 0.4, 0.08, 20.0
    _, _, hess = node_energy(mass, volume, diameter)
    for h in (-0.19, -0.1, 0.0, 0.07, 0.195):
        immersed = lambda s: volume * reference_fraction(s, diameter)  # noqa: E731
        step = 1e-5
        waterplane = -(immersed(h + step) - immersed(h - step)) / (2 * step)  # -dV_imm/dh (m²)
        np.testing.assert_allclose(hess(at_height(h)), RHO * G * waterplane * np.outer(UP, UP), rtol=1e-6)


def test_netting_vertex_stiffness_is_the_twines_waterplane_area():
    # vertex 0 on the surface (t = 0): peak stiffness (4/pi) rho g V_vertex / D with V_vertex = |d| pi D² l0 / 12,
    # i.e. rho g D |d| l0 / 3: the waterplane area of |d| l0 / 3 of horizontal twine cut along its axis
    l0, diameter = 0.02, 0.002
    _, _, stiff = netting_energy(UV, l0, diameter, 1140.0)
    x = jnp.concatenate([at_height(0.0), at_height(-0.5, (1, 0, 0)), at_height(0.4, (0, 1, 0))])
    k = stiff(x).reshape(3, 3, 3, 3)
    np.testing.assert_allclose(k[0, :, 0, :], RHO * G * diameter * 38 * l0 / 3 * np.outer(UP, UP), rtol=1e-12)
    assert float(jnp.max(jnp.abs(k[1:, :, 1:, :]))) == 0.0


# ---------------------------------------------------------------- derivatives


def random_band_positions(rng, n, thickness):
    """n points inside the immersion band, with random horizontal offsets."""
    return jnp.concatenate([at_height(h, rng.normal(size=3)) for h in rng.uniform(-0.45, 0.45, n) * thickness])


def central(fn, x, step):
    cols = []
    for i in range(x.size):
        e = jnp.zeros_like(x).at[i].set(step)
        cols.append((fn(x + e) - fn(x - e)) / (2 * step))
    return jnp.stack(cols, axis=-1)


@pytest.mark.parametrize("kind", ["node", "bar", "netting"])
def test_forces_and_stiffness_match_finite_differences(kind, rng):
    if kind == "node":
        e, thickness, n = node_energy(5.0, 0.02, 0.3), 0.3, 1
    elif kind == "bar":
        e, thickness, n = bar_energy(1.5, 0.3, 200.0), 0.3, 2
    else:
        e, thickness, n = netting_energy(UV[jnp.array([0, 2, 1])], 0.02, 0.01, 1140.0), 0.01, 3
    e, grad, stiff = e
    for _ in range(3):
        x = random_band_positions(rng, n, thickness)
        step = 1e-6 * thickness
        scale = float(jnp.max(jnp.abs(grad(x))))
        np.testing.assert_allclose(grad(x), central(e, x, step), rtol=1e-6, atol=1e-7 * scale)
        k = stiff(x)
        np.testing.assert_allclose(k, k.T, atol=1e-12 * float(jnp.max(jnp.abs(k))))
        np.testing.assert_allclose(k, central(grad, x, step), rtol=1e-5, atol=1e-6 * float(jnp.max(jnp.abs(k))))


def test_forces_are_weight_plus_buoyancy_of_the_wetted_part():
    mass, volume, diameter = 5.0, 0.02, 0.3
    _, grad, _ = node_energy(mass, volume, diameter)
    for h in (-0.14, -0.05, 0.0, 0.11):
        expected = (-mass * G + RHO * G * volume * reference_fraction(h, diameter)) * np.asarray(UP)
        np.testing.assert_allclose(-grad(at_height(h)), expected, rtol=1e-11, atol=1e-11)


def test_finite_at_band_edges_and_under_vmap():
    # vertices exactly on the band edges, on the surface, deep and high (vertical z, water plane z = 0 so
    # that the heights are exact): value, forces and stiffness finite under vmap, as the assembly uses them
    thickness = 0.01
    z = jnp.array([-thickness / 2, thickness / 2, 0.0, -1e3, 1e3, np.nextafter(-thickness / 2, 0.0)])
    xs = jnp.zeros((6, 3, 3)).at[:, :, 2].set(jnp.stack([z, jnp.roll(z, 1), jnp.roll(z, 2)], axis=1))

    def energy(x):
        return surface.netting_gravity_energy(x, UV, 0.02, thickness, 1140.0, RHO, G, jnp.array([0.0, 0.0, 1.0]), 0.0)

    def all_of(x):
        return energy(x), jax.grad(energy)(x), jax.jacfwd(jax.grad(energy))(x)

    values, forces, stiffness = jax.jit(jax.vmap(all_of))(xs)
    for a in (values, forces, stiffness):
        assert bool(jnp.all(jnp.isfinite(a)))
    # on the edges the stiffness is 0 (f' = 0 there), as outside: the stiffness is continuous across them
    # (element 2 has its vertices at z = 0, +T/2, -T/2)
    assert float(jnp.max(jnp.abs(stiffness[2, 1:, :, 1:, :]))) == 0.0
    # on the surface it is the peak, rho g (twine waterplane area)
    np.testing.assert_allclose(stiffness[2, 0, 2, 0, 2], RHO * G * thickness * 38 * 0.02 / 3, rtol=1e-12)


# ---------------------------------------------------------------- Newton with a thin band


def test_thin_band_two_cycle_and_its_cures():
    # A heavy netting lump (V, twine density 1140) on a spring of stiffness k anchored so that its dry and wet
    # equilibria are +-rho g V / (2 k) around the surface. When rho g V / k > band, undamped Newton from
    # outside jumps between exactly those two points (outside the band the term adds no stiffness); a band
    # >= rho g V / k, or a line search on the energy, converges.
    volume, k, diameter = 1e-5, 1.0, 0.002
    mass = 1140.0 * volume
    anchor = (mass - RHO * volume / 2) * G / k
    jump = RHO * G * volume / k

    def solve(band, line_search):
        # z: height of the lump above the water plane; the spring acts along UP
        node_e, node_g, node_k = node_energy(mass, volume, band)
        e = lambda z: 0.5 * k * (z - anchor) ** 2 + float(node_e(at_height(z)))  # noqa: E731
        r = lambda z: k * (z - anchor) + float(node_g(at_height(z)) @ UP)  # noqa: E731
        dr = lambda z: k + float(UP @ node_k(at_height(z)) @ UP)  # noqa: E731
        z, history = 0.05, []
        for _ in range(40):
            step, alpha = -float(r(z)) / float(dr(z)), 1.0
            while line_search and e(z + alpha * step) > e(z) and alpha > 1e-12:
                alpha /= 2
            z += alpha * step
            history.append(z)
        return history, r(z)

    history, residual = solve(diameter, line_search=False)
    np.testing.assert_allclose(np.abs(history[-4:]), jump / 2, rtol=1e-12)  # the two constant-load equilibria
    assert history[-1] * history[-2] < 0 and abs(residual) > 0.9 * RHO * G * volume
    for band, line_search in ((jump, False), (diameter, True)):
        history, residual = solve(band, line_search)
        assert abs(residual) < 1e-12 and abs(history[-1]) < band / 2  # equilibrium inside the band


# ---------------------------------------------------------------- FEMNET's boxes (flotteur2.c)


BOX = Term(lambda x, m, v, lz: surface.node_gravity_energy(x, m, v, 0.3, RHO, G, UP, LEVEL, box_height=lz), (3,))


@pytest.mark.parametrize("lz", [0.6, -0.6])
def test_box_potential_is_the_antiderivative_of_the_drag_boxs_fraction(lz):
    # dPhi/dz is the immersed fraction the box drag uses (terms.drag.box_immersed_fraction), by central differences
    # of Phi over heights that cross the box (above its node for L_z > 0, below it for L_z < 0)
    from jaxnet.terms.drag import box_immersed_fraction

    step = 1e-6
    for z in np.linspace(LEVEL - 1.3, LEVEL + 1.3, 53):
        slope = (float(surface.box_fraction_integral(z + step, lz, LEVEL))
                 - float(surface.box_fraction_integral(z - step, lz, LEVEL))) / (2 * step)
        assert slope == pytest.approx(float(box_immersed_fraction(z, lz, LEVEL)), abs=2e-6)
    # out of the water 0, immersed (its top under the surface) Phi = z_bottom - s + |L_z|/2
    top, bottom = max(lz, 0.0), min(lz, 0.0)
    assert float(surface.box_fraction_integral(LEVEL - bottom + 0.01, lz, LEVEL)) == 0.0
    z = LEVEL - top - 0.25
    assert float(surface.box_fraction_integral(z, lz, LEVEL)) == pytest.approx(z + bottom - LEVEL + abs(lz) / 2,
                                                                              abs=1e-14)


@pytest.mark.parametrize("lz", [0.5, -0.5])
def test_box_float_sits_at_femnets_draft_with_femnets_waterplane_stiffness(lz):
    # a box Lx x Ly x |Lz| of volume V on a node of mass m floats with rho Lx Ly h = m immersed; its top is then
    # |Lz| - h above the water whichever side of its node it stands on; FEMNET's stiffness rho g Lx Ly in the band
    lx, ly = 0.8, 0.5
    volume, mass = lx * ly * abs(lz), 0.3 * RHO * lx * ly * abs(lz)
    energy, grad, hess = BOX(mass, volume, lz)
    x, residual = newton_in_height((energy, grad, hess), at_height(-0.2 if lz > 0 else 0.2))  # in the band
    assert float(jnp.max(jnp.abs(residual))) < 1e-12 * mass * G
    draft = mass / (RHO * lx * ly)
    top = float(x @ UP) - LEVEL + max(lz, 0.0)
    assert top == pytest.approx(abs(lz) - draft, abs=1e-12)
    np.testing.assert_allclose(hess(x), RHO * G * lx * ly * np.outer(UP, UP), rtol=1e-12)
    # wholly immersed: exactly the constant load of gravity (weight less rho g V); out of the water its weight in air
    np.testing.assert_allclose(-grad(at_height(-1.0)), gravity.node_weight(mass, volume, RHO, G, UP), rtol=1e-12)
    np.testing.assert_allclose(-grad(at_height(1.0)), -mass * G * UP, rtol=1e-13)


def test_a_node_without_a_box_height_floats_as_the_cylinder():
    # box_height 0 selects the cylinder profile of the node's size (a body given no box height)
    mass, volume = 3.0, 0.01
    for h in (-0.2, -0.05, 0.0, 0.1, 0.2):
        np.testing.assert_allclose(BOX(mass, volume, 0.0)[1](at_height(h)),
                                   node_energy(mass, volume, 0.3)[1](at_height(h)), rtol=1e-13, atol=1e-15)


def test_a_bar_or_twine_of_no_diameter_has_no_load_and_no_nan_at_the_surface():
    # FEMNET's files have links of diameter 0: no volume, so no weight or buoyancy, wherever they are
    for h in (-0.3, 0.0, 1e-9, 0.4):
        x = jnp.concatenate([at_height(h), at_height(h, lateral=(2.0, 0.0, 0.0))])
        for fn in bar_energy(2.0, 0.0, 7800.0)[1:]:
            assert float(jnp.max(jnp.abs(fn(x)))) == 0.0
        x3 = jnp.concatenate([at_height(h), at_height(h, (1, 0, 0)), at_height(h, (0, 1, 0))])
        # the term's own call: no thickness given, the band is the twine's
        twines = Term(lambda x: surface.netting_gravity_energy(x, UV, 0.02, 0.0, 1140.0, RHO, G, UP, LEVEL), (3, 3))
        for fn in twines()[1:]:
            assert float(jnp.max(jnp.abs(fn(x3)))) == 0.0


def test_hexagonal_triangle_at_the_surface_weighs_as_gravity_says_under_it_and_in_air_above():
    l0 = jnp.array([0.02, 0.03, 0.025])  # the three families' twine lengths
    hexa = Term(lambda x: surface.hexagonal_gravity_energy(x, UV, l0, 0.002, 1140.0, RHO, G, UP, LEVEL), (3, 3))
    _, grad, _ = hexa()
    under = jnp.concatenate([at_height(-0.01), at_height(-0.5, (1, 0, 0)), at_height(-3.0, (0, 1, 0))])
    np.testing.assert_allclose(-grad(under).reshape(3, 3),
                               gravity.hexagonal_weight(UV, l0, 0.002, 1140.0, RHO, G, UP), rtol=1e-12)
    above = jnp.concatenate([at_height(0.01), at_height(0.5, (1, 0, 0)), at_height(3.0, (0, 1, 0))])
    per_vertex = 38 * np.pi * 0.002**2 / 4 * float(jnp.sum(l0)) * 1140.0 * G / 3
    np.testing.assert_allclose(-grad(above).reshape(3, 3), -per_vertex * np.tile(UP, (3, 1)), rtol=1e-13)
