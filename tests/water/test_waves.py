"""Linear (Airy) waves: dispersion, the field's potential-flow properties, boundary conditions, limits."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.water import waves
from jaxnet.water.waves import Airy

G = 9.81
N = 6  # points per evaluation: one shape, so that every test reuses the same compiled code


@jax.jit
def field(wave, x, t):
    """Everything the tests look at, at N points x (N, 3) and times t (N,), compiled once for every wave
    (a wave is a pytree of arrays). Eager calls would compile each primitive on first use: slow."""

    def at(x, t):
        return dict(
            u=wave.velocity(x, t), a=wave.acceleration(x, t), eta=wave.elevation(x, t),
            du_dx=jax.jacfwd(wave.velocity)(x, t), du_dt=jax.jacfwd(wave.velocity, argnums=1)(x, t),
            deta_dt=jax.grad(wave.elevation, argnums=1)(x, t))

    out = jax.vmap(at)(x, t)
    out["k"], out["c"], out["L"] = wave.wavenumber, wave.celerity, wave.wavelength
    # derivatives of a scalar mixing every output in every number of the wave (a pytree of the same shape)
    out["d_wave"] = jax.grad(lambda w: jnp.sum(w.velocity(x, t) ** 2) + jnp.sum(w.acceleration(x, t))
                             + jnp.sum(w.elevation(x, t)))(wave)
    return out


# wavenumbers of many (period, depth) pairs; derivatives of k in (T, h): first and second in T, first in h
wavenumbers = jax.jit(jax.vmap(waves.wavenumber))
wavenumber_derivatives = jax.jit(jax.vmap(lambda T, h: (
    jax.grad(waves.wavenumber)(T, h), jax.grad(jax.grad(waves.wavenumber))(T, h),
    jax.grad(waves.wavenumber, argnums=1)(T, h))))


def period_for(kh, depth, g=G):
    """The period (s) whose wavenumber in ``depth`` (m) is kh/depth: ω² = g k tanh(kh) read backwards."""
    k = kh / depth
    return 2.0 * math.pi / math.sqrt(g * k * math.tanh(kh))


def test_dispersion_residual_over_all_depths():
    kh = np.logspace(-3, math.log10(50.0), 41)
    depth = 12.0
    periods = np.array([period_for(y, depth) for y in kh])
    k = np.asarray(wavenumbers(periods, np.full(41, depth)))
    omega = 2.0 * np.pi / periods
    residual = np.abs(omega**2 - G * k * np.tanh(k * depth)) / omega**2
    assert residual.max() < 1e-12
    np.testing.assert_allclose(k * depth, kh, rtol=1e-12)


def test_deep_and_shallow_limits():
    T = 6.0
    omega = 2.0 * math.pi / T
    h_shallow = 2.0  # kh = 1e-3 there
    T_long = 2.0 * math.pi / (1e-3 / h_shallow * math.sqrt(G * h_shallow))
    k = np.asarray(wavenumbers(np.array([T, T, T_long]), np.array([np.inf, 50.0 * G / omega**2, h_shallow])))
    # infinite depth: exactly ω²/g; kh = 50: tanh(50) = 1 to rounding
    assert k[0] == pytest.approx(omega**2 / G, rel=1e-15)
    assert k[1] == pytest.approx(omega**2 / G, rel=1e-14)
    # shallow water: c = ω/k → √(g h), with c = √(g h) (1 - (kh)²/6 + ...) so kh = 1e-3 is within 2e-7
    assert k[2] * h_shallow == pytest.approx(1e-3, rel=1e-6)
    c = (2.0 * math.pi / T_long) / k[2]
    assert c == pytest.approx(math.sqrt(G * h_shallow), rel=2e-7)
    assert c < math.sqrt(G * h_shallow)


def test_wavenumber_derivatives_are_those_of_the_dispersion_relation():
    # implicit differentiation at fixed ω: dk/dh = -k² sech²(kh) / (tanh(kh) + kh sech²(kh)); the
    # second derivative in T against central differences of the first (exact higher derivatives)
    T, h, e = 7.0, 15.0, 1e-4
    k = float(wavenumbers(np.array([T, T, T]), np.full(3, h))[0])
    sech2 = 1.0 / math.cosh(k * h) ** 2
    dk_dT, d2k_dT2, dk_dh = (np.asarray(a) for a in wavenumber_derivatives(np.array([T, T + e, T - e]),
                                                                           np.full(3, h)))
    assert dk_dh[0] == pytest.approx(-k**2 * sech2 / (math.tanh(k * h) + k * h * sech2), rel=1e-12)
    assert d2k_dT2[0] == pytest.approx((dk_dT[1] - dk_dT[2]) / (2 * e), rel=1e-7)
    # dk/dT from the dispersion relation: 2ω dω = g (tanh kh + kh sech² kh) dk, dω/dT = -ω/T
    omega = 2 * math.pi / T
    assert dk_dT[0] == pytest.approx(2 * omega * (-omega / T) / (G * (math.tanh(k * h) + k * h * sech2)), rel=1e-12)


WAVES = [
    Airy(2.0, 8.0, (1.0, 2.0, 0.5), 20.0, phase=0.4, surface_level=1.5),  # direction made horizontal
    Airy(3.0, 5.0, (0.0, -1.0, 0.0), jnp.inf, phase=-1.0),
    Airy(1.0, 9.0, (1.0, 0.0, 0.0), 6.0, up=(0.0, 1.0, 0.0), surface_level=-2.0),  # y is up
]


def below_surface(rng, wave):
    """N random points strictly inside the water column (m), and times (s). In deep water, down to half a
    wavelength: deeper, the motion is below e^-pi = 4 % of the surface's (drawn down to 40 m, a wavelength of the
    5 s wave, all the points of some draws were that deep, their acceleration under the 0.1 m/s² that
    test_acceleration_is_the_time_derivative_of_velocity asks for, to compare something)."""
    up, e = np.asarray(wave.up), np.asarray(wave.direction)
    depth = min(float(wave.depth), 0.5 * float(wave.wavelength))
    z = rng.uniform(-0.95 * depth, -0.05 * depth, N) + float(wave.surface_level)
    side = np.cross(up, e)
    points = (rng.uniform(-50, 50, N)[:, None] * e + rng.uniform(-50, 50, N)[:, None] * side
              + z[:, None] * up)
    return points, rng.uniform(0.0, 20.0, N)


@pytest.mark.parametrize("wave", WAVES)
def test_velocity_is_divergence_free_and_irrotational(wave, rng):
    points, times = below_surface(rng, wave)
    for J in np.asarray(field(wave, points, times)["du_dx"]):
        scale = np.abs(J).max()
        assert scale > 1e-4  # a gradient that vanished would pass the checks below trivially
        assert abs(np.trace(J)) < 1e-10 * scale
        np.testing.assert_allclose(J - J.T, 0.0, atol=1e-10 * scale)


@pytest.mark.parametrize("wave", WAVES)
def test_surface_and_bed_conditions(wave, rng):
    points, times = below_surface(rng, wave)
    up, level = np.asarray(wave.up), float(wave.surface_level)
    # kinematic surface condition of linear theory: ∂η/∂t = w at the mean surface z = 0
    at_surface = field(wave, points + (level - points @ up)[:, None] * up, times)
    w = np.asarray(at_surface["u"] @ up)
    np.testing.assert_allclose(at_surface["deta_dt"], w, rtol=1e-12, atol=1e-14)
    assert np.abs(w).max() > 0.1
    if np.isfinite(float(wave.depth)):  # no flow through the bed: w = 0 at z = -h
        bed = level - float(wave.depth)
        u = np.asarray(field(wave, points + (bed - points @ up)[:, None] * up, times)["u"])
        scale = 0.5 * float(wave.height) * 2 * np.pi / float(wave.period)
        np.testing.assert_allclose(u @ up, 0.0, atol=1e-13 * scale)
        assert np.abs(u @ np.asarray(wave.direction)).max() > 1e-3 * scale


@pytest.mark.parametrize("wave", WAVES)
def test_acceleration_is_the_time_derivative_of_velocity(wave, rng):
    points, times = below_surface(rng, wave)
    points[0] += 5.0 * np.asarray(wave.up)  # one point above the surface, one below the bed
    points[1] -= 100.0 * np.asarray(wave.up)
    out = field(wave, points, times)
    np.testing.assert_allclose(out["a"], out["du_dt"], rtol=1e-12, atol=1e-14)
    assert np.abs(np.asarray(out["a"])).max() > 0.1


@pytest.mark.parametrize("depth", [3.0, 20.0, 300.0])
def test_surface_velocity_amplitude(depth):
    H, T = 1.6, 7.0
    wave = Airy(H, T, (1.0, 0.0, 0.0), depth)
    # at x = 0, t = 0 the phase is 0: the crest, where u is at its maximum and w is 0; a quarter period
    # later (θ = -π/2) the horizontal velocity is 0 and the surface falls at (H/2) ω
    out = field(wave, np.zeros((N, 3)), np.array([0.0, T / 4, 0.0, 0.0, 0.0, 0.0]))
    k, omega = float(out["k"]), 2 * math.pi / T
    amplitude = H / 2 * omega / math.tanh(k * depth)  # (H/2) ω coth(kh)
    u = np.asarray(out["u"])
    assert u[0, 0] == pytest.approx(amplitude, rel=1e-13)
    assert abs(u[0, 2]) < 1e-15
    assert abs(u[1, 0]) < 1e-12 * amplitude
    assert u[1, 2] == pytest.approx(-H / 2 * omega, rel=1e-13)


def test_extrapolation_is_continuous_and_constant_above_and_below():
    wave = WAVES[0]
    surface, bed = float(wave.surface_level), float(wave.surface_level - wave.depth)
    t = np.full(N, 1.3)
    for level, outside in ((surface, 4.0), (bed, -30.0)):
        side = np.sign(outside)
        # on the level, just inside, far outside, just outside, half a metre inside, far outside again
        z = np.array([level, level - 1e-9 * side, level + outside, level + 1e-9 * side, level - 0.5 * side,
                       level + 2 * outside])
        out = field(wave, np.stack([np.full(N, 3.0), np.full(N, -4.0), z], axis=1), t)
        u, a = np.asarray(out["u"]), np.asarray(out["a"])
        np.testing.assert_allclose(u[1], u[0], rtol=1e-8, atol=1e-9)  # continuous from inside
        np.testing.assert_array_equal(u[[2, 3, 5]], u[[0, 0, 0]])  # constant outside
        np.testing.assert_array_equal(a[[2, 3, 5]], a[[0, 0, 0]])
        # derivative in z: exactly 0 outside, that of linear theory inside (finite, nonzero)
        dz = np.asarray(out["du_dx"])[:, :, 2]
        np.testing.assert_array_equal(dz[[2, 3, 5]], 0.0)
        assert np.all(np.isfinite(dz)) and np.abs(dz[4]).max() > 1e-4


def test_zero_height_gives_zero_and_finite_derivatives():
    points = np.array([[1.0, 2.0, 3.0], [0.0, 0.0, 0.0], [4.0, -1.0, -2.0], [1.0, 1.0, -50.0],
                        [5.0, 0.0, -10.0], [0.0, 5.0, -3.0]])
    for depth in (10.0, np.inf):
        out = field(Airy(0.0, 6.0, (1.0, 1.0, 0.0), depth), points, np.full(N, 2.0))
        for name in ("u", "a", "eta", "du_dx", "du_dt", "deta_dt"):
            np.testing.assert_array_equal(out[name], 0.0)


def test_no_nan_in_derivatives_anywhere():
    # positions above the surface, on it, on the bed, below it; deep and finite water; zero height;
    # derivatives in position, time and every number of the wave
    points = np.array([[0.0, 0.0, 2.0], [1.0, 0.0, 0.0], [2.0, 1.0, -20.0], [3.0, 2.0, -500.0], [0.0, 0.0, -1e-300],
                       [1.0, 1.0, -19.999999]])
    for height, depth in ((2.0, 20.0), (2.0, np.inf), (0.0, 20.0)):
        out = field(Airy(height, 8.0, (1.0, 0.3, 0.0), depth, phase=0.3), points, np.full(N, 1.1))
        assert all(np.all(np.isfinite(leaf)) for leaf in jax.tree_util.tree_leaves(out))
        d_wave = out["d_wave"]
        assert float(d_wave.height) != 0.0  # the height always matters (at H = 0 too: linear in H)
        if height > 0:  # period, phase and level matter; the depth only when finite
            assert min(abs(float(d_wave.period)), abs(float(d_wave.phase)), abs(float(d_wave.surface_level))) > 0
            assert (float(d_wave.depth) != 0.0) == np.isfinite(depth)


def test_broadcasts_over_points_like_vmap(rng):
    wave = WAVES[0]
    points = rng.normal(size=(2, 3, 3)) * 10.0

    def both(w, x):
        return w.velocity(x, 0.7), w.elevation(x, 0.7)

    batched = jax.jit(both)(wave, points)
    one_by_one = field(wave, points.reshape(N, 3), np.full(N, 0.7))
    for b, name, shape in zip(batched, ("u", "eta"), ((2, 3, 3), (2, 3))):
        assert b.shape == shape
        np.testing.assert_allclose(b, np.asarray(one_by_one[name]).reshape(shape), rtol=1e-14, atol=1e-15)


def test_worked_example_8_s_in_20_m():
    # By hand: ω = 2π/8 = 0.785398 rad/s; ω²h/g = 0.616850 × 20 / 9.81 = 1.25759 = kh tanh(kh).
    # kh = 1.40: 1.40 tanh 1.40 = 1.23949; kh = 1.42: 1.26323; interpolating, kh = 1.41525, and one Newton
    # step from there changes the 6th digit only: kh = 1.415249, k = 0.0707624 rad/m, L = 2π/k = 88.79 m
    # (deep water: gT²/2π = 99.92 m), c = L/T = 11.099 m/s. For H = 2 m the surface velocity amplitude is
    # ω coth(kh) = 0.785398/0.888604 = 0.88386 m/s, at the bed ω/sinh(kh) = 0.785398/1.937322 = 0.40540 m/s.
    wave = Airy(2.0, 8.0, (1.0, 0.0, 0.0), 20.0)
    points = np.zeros((N, 3))
    points[1, 2] = -20.0
    out = field(wave, points, np.zeros(N))
    assert float(out["k"]) == pytest.approx(0.0707624, rel=2e-6)
    assert float(out["L"]) == pytest.approx(88.79, abs=0.01)
    assert float(out["c"]) == pytest.approx(11.099, abs=0.001)
    assert float(out["u"][0, 0]) == pytest.approx(0.88386, abs=2e-5)
    assert float(out["u"][1, 0]) == pytest.approx(0.40540, abs=2e-5)


def test_bad_parameters_name_the_parameter():
    with pytest.raises(ValueError, match="period"):
        Airy(1.0, -2.0, (1.0, 0.0, 0.0), 10.0)
    with pytest.raises(ValueError, match="height"):
        Airy(-1.0, 2.0, (1.0, 0.0, 0.0), 10.0)
    with pytest.raises(ValueError, match="depth"):
        Airy(1.0, 2.0, (1.0, 0.0, 0.0), 0.0)
    with pytest.raises(ValueError, match="direction"):
        Airy(1.0, 2.0, (0.0, 0.0, 1.0), 10.0)
    with pytest.raises(ValueError, match="direction"):
        Airy(1.0, 2.0, (1.0, 0.0), 10.0)
    with pytest.raises(ValueError, match="phase"):
        Airy(1.0, 2.0, (1.0, 0.0, 0.0), 10.0, phase=float("nan"))


# -- second-order Stokes waves (FEMNET's wave_model 2) -----------------------------------------------------


def _stokes_textbook(H, T, h, x, z, t):
    """Dean & Dalrymple's second-order Stokes series written out with numpy (moderate kh only): η, u, w at
    (x, z) for waves along x, phase 0."""
    k = float(waves.wavenumber(T, h))
    a, w = H / 2, 2 * np.pi / T
    th = k * x - w * t
    s = z + h
    eta = a * np.cos(th) + k * a**2 / 4 * np.cosh(k * h) * (2 + np.cosh(2 * k * h)) / np.sinh(k * h) ** 3 * np.cos(2 * th)
    u = (a * w * np.cosh(k * s) / np.sinh(k * h) * np.cos(th)
         + 0.75 * a**2 * w * k * np.cosh(2 * k * s) / np.sinh(k * h) ** 4 * np.cos(2 * th))
    v = (a * w * np.sinh(k * s) / np.sinh(k * h) * np.sin(th)
         + 0.75 * a**2 * w * k * np.sinh(2 * k * s) / np.sinh(k * h) ** 4 * np.sin(2 * th))
    return eta, u, v


def test_stokes2_is_the_textbook_series_and_a_potential_flow():
    H, T, h = 2.0, 8.0, 15.0
    wave = waves.Stokes2(H, T, depth=h)
    x = np.array([[0.0, 0.0, -1.0], [7.0, 0.0, -6.0], [23.0, 0.0, -14.5], [41.0, 0.0, -15.0]])
    t = np.full(4, 1.3)
    out = field(wave, x, t)
    for k in range(4):
        eta, u, w = _stokes_textbook(H, T, h, x[k, 0], x[k, 2], 1.3)
        assert float(out["eta"][k]) == pytest.approx(eta, rel=1e-12)
        np.testing.assert_allclose(np.asarray(out["u"][k]), [u, 0.0, w], rtol=1e-12, atol=1e-14)
    # a potential flow: divergence-free, irrotational (symmetric gradient), no flow through the bed
    grad = np.asarray(out["du_dx"])
    np.testing.assert_allclose(np.trace(grad, axis1=1, axis2=2), 0.0, atol=1e-13)
    np.testing.assert_allclose(grad, np.swapaxes(grad, 1, 2), atol=1e-13)
    assert abs(float(out["u"][3, 2])) < 1e-15
    # the acceleration is the velocity's time derivative; the gradient the one of velocity_gradient
    np.testing.assert_allclose(np.asarray(out["a"]), np.asarray(out["du_dt"]), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.asarray(wave.velocity_gradient(x, 1.3)), grad, rtol=1e-12, atol=1e-15)
    # the second harmonic raises the crest and flattens the trough (crest a + k a²/4 (3 - tanh²)/tanh³)
    k = float(waves.wavenumber(T, h))
    crest = 1.0 + k / 4 * (3 - np.tanh(k * h) ** 2) / np.tanh(k * h) ** 3
    assert float(wave.elevation(np.zeros(3), 0.0)) == pytest.approx(crest, rel=1e-14)


def test_stokes2_in_deep_water_is_airy_with_a_second_harmonic_surface():
    H, T = 10.0, 14.0  # FEMNET's FAD (7fad/g3): 10 m, 14 s waves in 1500 m of water
    deep, airy = waves.Stokes2(H, T), waves.Airy(H, T)
    x = np.array([[3.0, 0.0, -5.0], [50.0, 4.0, -30.0]])
    np.testing.assert_array_equal(np.asarray(deep.velocity(x, 2.0)), np.asarray(airy.velocity(x, 2.0)))
    k = float(deep.wavenumber)
    theta = k * x[:, 0] - 2 * np.pi / T * 2.0
    np.testing.assert_allclose(np.asarray(deep.elevation(x, 2.0)), 5.0 * np.cos(theta) + k * 25.0 / 2 * np.cos(2 * theta),
                               rtol=1e-13)
    # 1500 m is deep for these waves: the finite depth gives the deep answer to rounding
    finite = waves.Stokes2(H, T, depth=1500.0)
    np.testing.assert_allclose(np.asarray(finite.velocity(x, 2.0)), np.asarray(deep.velocity(x, 2.0)), rtol=1e-12)


# -- third-order Stokes waves in deep water (FEMNET's wave_model 3) ------------------------------------------


def test_stokes3_is_the_deep_water_series_and_a_potential_flow():
    """Whitham's deep-water series to third order, with a = H/2 as FEMNET takes it: k from ω = √(gk)(1 + (ka)²/2),
    the elevation's three harmonics, u = a √(gk) e^{kz} (cos θ, sin θ); a potential flow (divergence-free,
    irrotational); the acceleration the velocity's time derivative; the wavenumber differentiable in H."""
    H, T, g = 6.0, 9.0, 9.81
    wave = waves.Stokes3(H, T)
    a, omega = H / 2, 2 * np.pi / T
    k = float(wave.wavenumber)
    assert np.sqrt(g * k) * (1 + 0.5 * (k * a) ** 2) == pytest.approx(omega, rel=1e-14)
    assert k < omega**2 / g  # amplitude dispersion: longer and faster than Airy's
    x = np.array([[0.0, 0.0, -1.0], [11.0, 0.0, -6.0], [37.0, 0.0, -40.0], [60.0, 0.0, 0.5]])
    t = np.full(4, 2.1)
    out = field(wave, x, t)
    theta = k * x[:, 0] - omega * 2.1
    eps = k * a
    eta = a * ((1 - eps**2 / 16) * np.cos(theta) + eps / 2 * np.cos(2 * theta) + 3 * eps**2 / 8 * np.cos(3 * theta))
    np.testing.assert_allclose(np.asarray(out["eta"]), eta, rtol=1e-12)
    speed = a * np.sqrt(g * k) * np.exp(k * np.minimum(x[:, 2], 0.0))  # above the surface: its z = 0 value
    expected = np.stack([speed * np.cos(theta), 0.0 * theta, speed * np.sin(theta)], axis=1)
    np.testing.assert_allclose(np.asarray(out["u"]), expected, rtol=1e-12, atol=1e-14)
    grad = np.asarray(out["du_dx"])[:3]
    np.testing.assert_allclose(np.trace(grad, axis1=1, axis2=2), 0.0, atol=1e-13)
    np.testing.assert_allclose(grad, np.swapaxes(grad, 1, 2), atol=1e-13)
    np.testing.assert_allclose(np.asarray(out["a"]), np.asarray(out["du_dt"]), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(np.asarray(wave.velocity_gradient(x, 2.1)), np.asarray(out["du_dx"]), rtol=1e-12,
                               atol=1e-15)
    # dk/dH by autodiff against the implicit function theorem on ω = √(gk)(1 + (ka)²/2), a = H/2
    dk_dh = float(jax.grad(lambda h: waves.Stokes3(h, T).wavenumber)(H))
    df_dk = 0.5 * np.sqrt(g / k) * (1 + 0.5 * eps**2) + np.sqrt(g * k) * a**2 * k
    df_da = np.sqrt(g * k) * a * k**2
    assert dk_dh == pytest.approx(-df_da * 0.5 / df_dk, rel=1e-10)


def test_stokes3_of_small_waves_is_airy_in_deep_water():
    """As H → 0 the velocity reduces to Airy's in deep water, relative to it as ε² (k and a √(gk) against a ω):
    a quarter of the difference when H halves."""
    T = 8.0
    x = np.array([[5.0, 1.0, -3.0], [30.0, 0.0, -12.0]])
    gaps = []
    for H in (0.4, 0.2):
        s3, airy = waves.Stokes3(H, T), waves.Airy(H, T)
        du = np.abs(np.asarray(s3.velocity(x, 1.7)) - np.asarray(airy.velocity(x, 1.7))).max()
        gaps.append(du / (H / 2 * 2 * np.pi / T))
    assert gaps[1] / gaps[0] == pytest.approx(0.25, rel=0.05)
    assert gaps[1] < 1e-3
