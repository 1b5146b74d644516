"""Irregular seas (jaxnet.water.spectra, jaxnet.water.waves.Irregular and sea_state): the spectra against their closed-form
moments, a long synthetic record's significant height and moments against the spectrum's, the directional
spreading realised, the kinematics against linear theory, and the ramp that starts a run."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.water import forcing, spectra, waves

G = 9.81
HS, TP = 3.0, 10.0
WP = 2 * np.pi / TP
FINE = np.linspace(1e-3, 40 * WP, 400_001)  # rad/s: the moments' quadrature grid


def pm_moment(n, hs=HS, tp=TP):
    """Pierson-Moskowitz's m_n in closed form: Hs²/16 ω_p^n (5/4)^(n/4) Γ(1 - n/4) (the spectra module's
    docstring, from the substitution q = 5/4 (ω_p/ω)⁴)."""
    wp = 2 * np.pi / tp
    return hs**2 / 16 * wp**n * 1.25 ** (n / 4) * math.gamma(1 - n / 4)


def test_pierson_moskowitz_moments_are_the_closed_forms():
    for n in (0, 1, 2):
        m = spectra.spectral_moment(lambda w: spectra.pierson_moskowitz(w, HS, TP), n, FINE)
        # the tail beyond the grid, where exp(...) = 1 to 1e-6: ∫ ωⁿ 5/16 Hs² ω_p⁴ ω⁻⁵ dω
        tail = 5 / 16 * HS**2 * WP**4 * FINE[-1] ** (n - 4) / (4 - n)
        assert m + tail == pytest.approx(pm_moment(n), rel=2e-6), n
    # DNV-RP-C205's period ratios for PM: T1 = 0.772 Tp, Tz = 0.710 Tp
    assert 2 * np.pi * pm_moment(0) / pm_moment(1) / TP == pytest.approx(0.7718, abs=1e-4)
    assert 2 * np.pi * math.sqrt(pm_moment(0) / pm_moment(2)) / TP == pytest.approx(0.7104, abs=1e-4)
    # its peak is at ω_p (dS/dω = 0 there) and S is 0, not NaN, at ω <= 0
    assert float(jax.grad(spectra.pierson_moskowitz)(WP, HS, TP)) == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_array_equal(np.asarray(spectra.pierson_moskowitz(np.array([-1.0, 0.0]), HS, TP)), 0.0)
    assert np.isfinite(np.asarray(jax.grad(spectra.pierson_moskowitz)(0.0, HS, TP)))


@pytest.mark.parametrize("gamma, m0_error", [(1.0, 0.0), (2.0, -0.0022), (3.3, 0.0024), (7.0, -0.0175)])
def test_jonswap_is_pm_enhanced_at_its_peak_with_dnvs_normalisation(gamma, m0_error):
    # γ = 1 is Pierson-Moskowitz; at ω_p the enhancement is exactly A_γ γ
    w = np.array([0.6 * WP, WP, 1.7 * WP])
    ratio = np.asarray(spectra.jonswap(w, HS, TP, gamma)) / np.asarray(spectra.pierson_moskowitz(w, HS, TP))
    a_gamma = 1 - 0.287 * math.log(gamma)
    assert ratio[1] == pytest.approx(a_gamma * gamma, rel=1e-14)
    # σ: 0.07 below the peak, 0.09 above
    assert ratio[0] == pytest.approx(a_gamma * gamma ** math.exp(-0.5 * (0.4 / 0.07) ** 2), rel=1e-12)
    assert ratio[2] == pytest.approx(a_gamma * gamma ** math.exp(-0.5 * (0.7 / 0.09) ** 2), rel=1e-12)
    # DNV's A_γ makes m0 = Hs²/16 only approximately: its error, measured on a fine grid
    m0 = spectra.spectral_moment(lambda v: spectra.jonswap(v, HS, TP, gamma), 0, FINE)
    assert m0 / (HS**2 / 16) - 1 == pytest.approx(m0_error, abs=2e-4)


def test_dnvs_peak_enhancement_from_hs_and_tp():
    # Tp/√Hs = 3, 4.2, 6 for Hs = 4 m
    assert spectra.jonswap_gamma(4.0, 6.0) == 5.0
    assert spectra.jonswap_gamma(4.0, 8.4) == pytest.approx(math.exp(5.75 - 1.15 * 4.2), rel=1e-14)
    assert spectra.jonswap_gamma(4.0, 12.0) == 1.0


@pytest.mark.parametrize("n", [1.0, 2.0, 4.0, 10.0])
def test_spreading_integrates_to_one(n):
    angle = np.linspace(-np.pi, np.pi, 200_001)
    assert np.trapezoid(np.asarray(spectra.spreading(angle, n)), angle) == pytest.approx(1.0, rel=1e-8)


@jax.jit
def _record(sea, x, t):
    return jax.vmap(lambda s: sea.elevation(x, s))(t)


def test_a_long_record_has_the_spectrums_significant_height_and_moments():
    """One repeat period (2π/Δω) of η at a point: its variance is Σ a²/2 = Hs²/16 by construction, and its
    periodogram's moments m1, m2 are the JONSWAP spectrum's (within the band, scaled as the sea is)."""
    sea = waves.sea_state(HS, TP, gamma=3.3, components=400, seed=7)
    omega = np.asarray(sea.angular_frequency)
    d_omega = omega[1] - omega[0]
    period = 2 * np.pi / d_omega
    samples = 2**15
    t = np.arange(samples) * period / samples
    eta = np.asarray(_record(sea, jnp.array([3.0, -2.0, 0.0]), t))
    assert 4 * eta.std() == pytest.approx(HS, rel=1e-9)
    assert abs(eta.mean()) < 1e-12 * HS
    # the periodogram over exactly one repeat period: the components sit at whole multiples of Δω, so bin j
    # (frequency j Δω) and its mirror hold a²/4 each of the component there
    power = 2 * np.abs(np.fft.rfft(eta) / samples) ** 2
    bins = np.arange(power.size) * d_omega
    record = {n: float(np.sum(bins**n * power)) for n in (0, 1, 2)}
    band = np.linspace(0.5 * WP, 5.0 * WP, 200_001)
    spectrum = {n: spectra.spectral_moment(lambda w: spectra.jonswap(w, HS, TP, 3.3), n, band) for n in (0, 1, 2)}
    assert record[0] == pytest.approx(HS**2 / 16, rel=1e-6)
    t1 = 2 * np.pi * record[0] / record[1]
    tz = 2 * np.pi * math.sqrt(record[0] / record[2])
    assert t1 == pytest.approx(2 * np.pi * spectrum[0] / spectrum[1], rel=2e-4)
    assert tz == pytest.approx(2 * np.pi * math.sqrt(spectrum[0] / spectrum[2]), rel=2e-4)


def test_a_short_crested_sea_is_ergodic_and_spread_as_asked():
    sea = waves.sea_state(HS, TP, direction=(0.0, 1.0, 0.0), spreading=2.0, components=2000, seed=3)
    heading = np.asarray(sea.direction)
    # every component horizontal and of unit length; the angles from the mean direction (y) follow cos²:
    # E[sin² θ] = ∫ (2/π) cos² θ sin² θ dθ = 1/4 (standard error of 2000 draws: 0.005)
    np.testing.assert_allclose(np.linalg.norm(heading, axis=1), 1.0, rtol=1e-14)
    np.testing.assert_array_equal(heading[:, 2], 0.0)
    assert (heading[:, 1] > 0).all()
    assert np.mean(heading[:, 0] ** 2) == pytest.approx(0.25, abs=0.02)
    assert abs(np.mean(heading[:, 0])) < 0.03
    # one frequency per component: the variance of η over the repeat period is Σ a²/2 at every point
    omega = np.asarray(sea.angular_frequency)
    period = 2 * np.pi / (omega[1] - omega[0])
    t = np.arange(2**16) * period / 2**16
    for x in ([0.0, 0.0, 0.0], [250.0, -40.0, 0.0]):
        assert 4 * np.asarray(_record(sea, jnp.array(x), t)).std() == pytest.approx(HS, rel=1e-6)


def test_the_same_seed_gives_the_same_sea():
    a, b, c = (waves.sea_state(HS, TP, seed=s, components=16) for s in (1, 1, 2))
    np.testing.assert_array_equal(np.asarray(a.phase), np.asarray(b.phase))
    assert not np.allclose(np.asarray(a.phase), np.asarray(c.phase))
    np.testing.assert_array_equal(np.asarray(a.amplitude), np.asarray(c.amplitude))


# -- kinematics --------------------------------------------------------------------------------------------

NAMES = ("elevation", "velocity", "acceleration", "velocity_gradient")


@jax.jit
def kinematics(wave, x, t):
    """Everything a wave gives at points x and time t, compiled once per kind of wave (eager calls would
    compile each primitive on first use: slow)."""
    return {name: getattr(wave, name)(x, t) for name in NAMES}


POINTS = np.array([[0.0, 0.0, -1.0], [12.0, -3.0, -7.5], [-30.0, 8.0, -19.0], [5.0, 5.0, -0.2]])


@pytest.mark.parametrize("depth", [20.0, float("inf")])
def test_without_stretching_the_sea_is_the_sum_of_its_airy_waves(depth):
    sea = waves.sea_state(HS, TP, spreading=4.0, components=6, seed=11, depth=depth, stretching="none")
    airy = [waves.Airy(2 * float(a), 2 * np.pi / float(w), direction=np.asarray(d), depth=depth, phase=float(p))
            for a, w, d, p in zip(sea.amplitude, sea.angular_frequency, sea.direction, sea.phase)]
    t = 3.7
    each = [kinematics(w, POINTS, t) for w in airy]
    mine = kinematics(sea, POINTS, t)
    for name in NAMES:
        total = sum(np.asarray(k[name]) for k in each)
        np.testing.assert_allclose(np.asarray(mine[name]), total, rtol=1e-12, atol=1e-14, err_msg=name)


def test_wheeler_stretching_maps_the_surface_to_the_mean_level():
    depth = 25.0
    sea = waves.sea_state(HS, TP, components=12, seed=5, depth=depth)
    linear = waves.Irregular(sea.amplitude, sea.angular_frequency, sea.direction, sea.phase, depth=depth,
                             stretching="none")
    t = np.array(2.3)
    surface = POINTS.copy()
    surface[:, 2] = np.asarray(sea.elevation(POINTS, t))
    bed = POINTS.copy()
    bed[:, 2] = -depth
    at_mean_level = POINTS.copy()
    at_mean_level[:, 2] = 0.0
    # at the instantaneous surface Wheeler's field is linear theory's at z = 0, and so above it
    np.testing.assert_allclose(np.asarray(sea.velocity(surface, t)), np.asarray(linear.velocity(at_mean_level, t)),
                               rtol=1e-12, atol=1e-14)
    above = surface + np.array([0.0, 0.0, 1.5])
    np.testing.assert_allclose(np.asarray(sea.velocity(above, t)), np.asarray(sea.velocity(surface, t)), rtol=1e-12)
    # at the bed the vertical velocity is 0 and the horizontal one is linear theory's there
    np.testing.assert_allclose(np.asarray(sea.velocity(bed, t))[:, 2], 0.0, atol=1e-14)
    np.testing.assert_allclose(np.asarray(sea.velocity(bed, t)), np.asarray(linear.velocity(bed, t)), rtol=1e-12,
                               atol=1e-14)


def test_acceleration_and_gradient_are_the_derivatives_of_the_stretched_velocity():
    sea = waves.sea_state(HS, TP, spreading=2.0, components=10, seed=2, depth=30.0)
    t, h = 4.1, 1e-5
    fd_t = (np.asarray(sea.velocity(POINTS, t + h)) - np.asarray(sea.velocity(POINTS, t - h))) / (2 * h)
    np.testing.assert_allclose(np.asarray(sea.acceleration(POINTS, t)), fd_t, rtol=1e-6, atol=1e-9)
    gradient = np.asarray(sea.velocity_gradient(POINTS, t))
    for n in range(3):
        step = np.zeros(3)
        step[n] = h
        fd = (np.asarray(sea.velocity(POINTS + step, t)) - np.asarray(sea.velocity(POINTS - step, t))) / (2 * h)
        np.testing.assert_allclose(gradient[:, :, n], fd, rtol=1e-6, atol=1e-9)


def test_sea_state_refuses_what_cannot_make_a_sea():
    for kwargs, word in [(dict(hs=0.0), "hs"), (dict(tp=-1.0), "tp"), (dict(components=0), "count"),
                         (dict(band=(2.0, 1.0)), "band"), (dict(spectrum="bretschneider"), "spectrum"),
                         (dict(spreading=0.0), "spreading_n"), (dict(gamma=0.5), "gamma"),
                         (dict(direction=(0.0, 0.0, 1.0)), "direction"), (dict(stretching="delta"), "stretching")]:
        with pytest.raises(ValueError, match=word):
            waves.sea_state(**{"hs": HS, "tp": TP, **kwargs})


# -- the ramp ----------------------------------------------------------------------------------------------


def test_envelope_is_c2_and_rises_from_zero_to_one():
    duration = 4.0
    t = np.array([-1.0, 0.0, 1.0, 2.0, 4.0, 6.0])
    value, rate = (np.asarray(a) for a in forcing.envelope(t, duration))
    np.testing.assert_allclose(value, [0.0, 0.0, 0.103515625, 0.5, 1.0, 1.0], rtol=1e-14, atol=0)
    second = jax.vmap(jax.grad(lambda s: forcing.envelope(s, duration)[1]))(jnp.asarray(t))
    np.testing.assert_allclose(rate, jax.vmap(jax.grad(lambda s: forcing.envelope(s, duration)[0]))(jnp.asarray(t)),
                               rtol=1e-14, atol=1e-15)
    # the second derivative is 0 at both ends: what starts under it starts without a jump of acceleration
    assert np.abs(np.asarray(second)[[1, 4]]).max() == 0.0
    np.testing.assert_array_equal(np.asarray(forcing.envelope(t, 0.0)[0]), 1.0)


@pytest.mark.parametrize("make", [lambda: waves.Airy(2.0, 6.0, depth=30.0),
                                  lambda: waves.sea_state(HS, TP, components=8, seed=1, depth=30.0)])
def test_ramped_waves_grow_from_still_water_and_keep_their_derivatives(make):
    import equinox as eqx
    wave = make()
    ramped = eqx.tree_at(lambda w: w.ramp, wave, jnp.asarray(5.0))
    np.testing.assert_array_equal(np.asarray(ramped.velocity(POINTS, 0.0)), 0.0)
    np.testing.assert_array_equal(np.asarray(ramped.acceleration(POINTS, 0.0)), 0.0)
    np.testing.assert_allclose(np.asarray(ramped.velocity(POINTS, 7.0)), np.asarray(wave.velocity(POINTS, 7.0)),
                               rtol=1e-14)
    np.testing.assert_allclose(np.asarray(ramped.elevation(POINTS, 2.5)), 0.5 * np.asarray(wave.elevation(POINTS, 2.5)),
                               rtol=1e-12)
    # during the ramp the acceleration is the time derivative of the ramped velocity
    t = jnp.asarray(1.9)
    by_autodiff = jax.jacfwd(lambda s: ramped.velocity(POINTS, s))(t)
    np.testing.assert_allclose(np.asarray(ramped.acceleration(POINTS, t)), np.asarray(by_autodiff), rtol=1e-10,
                               atol=1e-13)


# -- in scene files ----------------------------------------------------------------------------------------

PANEL = {
    "twines": {"pa": {"l0": 0.025, "ea": 2000, "diameter": 0.0015}},
    "panels": [{"name": "wall", "step": 0.5, "twine": "pa",
                "corners": [[0, 0, -1.414, 0, 0], [1.414, 0, -1.414, 40, -40], [1.414, 0, 0, 80, 0], [0, 0, 0, 40, 40]]}],
    "fix": [{"at": {"panel": "wall", "side": 2}}],
}


def test_scene_files_describe_regular_waves_and_sea_states():
    from jaxnet.io import scene_file

    regular = scene_file.from_dict({**PANEL, "environment": {"surface_level": 0.5, "waves": {
        "height": 1.2, "period": 5.0, "direction": [0, 1, 0], "depth": 30}}}).scene.environment.waves
    assert isinstance(regular, waves.Airy)
    assert (float(regular.height), float(regular.period), float(regular.depth), float(regular.surface_level)) == \
        (1.2, 5.0, 30.0, 0.5)
    sea = scene_file.from_dict({**PANEL, "environment": {"waves": {
        "hs": 2.0, "tp": 8.0, "spreading": 4, "components": 50, "seed": 9, "stretching": "none"}}}).scene.environment.waves
    same = waves.sea_state(2.0, 8.0, spreading=4.0, components=50, seed=9, stretching="none")
    assert isinstance(sea, waves.Irregular) and sea.stretching == "none"
    np.testing.assert_array_equal(np.asarray(sea.phase), np.asarray(same.phase))
    np.testing.assert_array_equal(np.asarray(sea.direction), np.asarray(same.direction))


@pytest.mark.parametrize("spec, words", [
    ({"height": 1.0}, "missing"),
    ({"hs": 2.0, "tp": 8.0, "period": 3.0}, "unknown key"),
    ({"hs": 2.0, "tp": 8.0, "seed": 1.5}, "environment.waves.seed"),
    ({"hs": -2.0, "tp": 8.0}, "environment.waves: sea state: hs"),
    ({"height": 1.0, "period": 0.0}, "environment.waves: Airy: period"),
    ({"amplitude": 1.0}, "expected regular waves"),
])
def test_scene_file_waves_errors_name_the_key(spec, words):
    from jaxnet.io import scene_file
    from jaxnet.scene import SceneError

    with pytest.raises(SceneError, match=words):
        scene_file.from_dict({**PANEL, "environment": {"waves": spec}})
