"""Winches (FEMNET's ``input hauling_cable4``): the rest lengths against FEMNET's step-by-step rule, the
hauled length against the table's integral, a winch hauling a hanging weight against its closed form, and the
errors of a bad winch."""

import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.water import forcing
from jaxnet.scene import Bars, Environment, Nodes, Scene, SceneError
from jaxnet.solve import dynamics, statics
from jaxnet.solve.options import Newton


def femnet_steps(rest, order, speeds_at, dt, n_steps, shortest, longest):
    """FEMNET's ``hauling_cable`` rule, step by step: each step's length s dt goes to the first bar of ``order``
    that can still change (above ``shortest`` hauling in, below ``longest`` paying out), what is left of it to the
    next one."""
    rest = np.array(rest, dtype=float)
    for k in range(n_steps):
        left = speeds_at(k * dt) * dt
        for b in order:
            if left == 0.0:
                break
            if left > 0 and rest[b] > shortest:
                take = min(left, rest[b] - shortest)
                rest[b] -= take
                left -= take
            elif left < 0 and rest[b] < longest:
                give = min(-left, longest - rest[b])
                rest[b] += give
                left += give
    return rest


@pytest.mark.parametrize("speed", [0.7, -0.7])
def test_rest_lengths_are_femnets_step_by_step_lengths(speed):
    """A constant speed: the closed form equals FEMNET's rule applied step by step, bars of unequal lengths taken in
    the winch's order (not the index order), to rounding; the sum changes by exactly H until the bars reach their
    limits."""
    rest = np.array([2.0, 1.5, 3.0, 0.5, 2.5])
    order = np.array([3, 1, 4, 0])  # bar 2 is not the winch's
    winch = forcing.Winch(order, drum_bar=3, times=[0.0, 100.0], speeds=[speed, speed], shortest=0.05, longest=4.0)
    dt = 0.01
    for t in (0.3, 1.7, 4.2, 6.9, 20.0):
        n = int(round(t / dt))
        expected = femnet_steps(rest, order, lambda _: speed, dt, n, 0.05, 4.0)
        got = np.asarray(winch.rest_lengths(rest, t))
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
        assert got[2] == rest[2]
    capacity = np.sum(rest[order] - 0.05) if speed > 0 else np.sum(4.0 - rest[order])
    t = 0.5 * capacity / abs(speed)
    assert np.sum(np.asarray(winch.rest_lengths(rest, t))) == pytest.approx(rest.sum() - speed * t, rel=1e-13)
    # past its capacity the winch has stopped: every bar at its limit
    done = np.asarray(winch.rest_lengths(rest, 2.0 * capacity / abs(speed)))[order]
    np.testing.assert_allclose(done, 0.05 if speed > 0 else 4.0, rtol=1e-14)


def test_hauled_length_is_the_tables_integral():
    """H(t) = ∫ s: the speed linear between the table's times and 0 outside, integrated exactly (checked against
    adaptive quadrature), and d H/dt the speed."""
    import jax
    from scipy.integrate import quad

    times, speeds = [2.0, 5.0, 9.0], [0.0, 1.2, 0.4]
    winch = forcing.Winch([0], 0, times, speeds, 0.01, 10.0)
    for t in (1.0, 3.3, 5.0, 7.1, 12.0):
        expected = quad(lambda s: np.interp(s, times, speeds, left=0.0, right=0.0), 0.0, t, points=times, limit=200)[0]
        assert float(winch.hauled(t)) == pytest.approx(expected, abs=1e-12)
        assert float(jax.grad(winch.hauled)(t)) == pytest.approx(float(winch.speed(t)), abs=1e-12)
    assert float(winch.speed(7.0)) == pytest.approx(1.2 + (0.4 - 1.2) * 2.0 / 4.0, rel=1e-14)


def hanging_weight(m, n_bars, bar_length, ea):
    """A weight of mass m (kg) hanging at the bottom of a vertical cable of ``n_bars`` bars, its top held at
    the origin; the cable without mass, volume or drag to speak of (so that its tension is the weight's)."""
    z = -bar_length * np.arange(n_bars + 1)
    pos = np.stack([np.zeros_like(z), np.zeros_like(z), z], axis=1)
    fixed = np.zeros((n_bars + 1, 3), dtype=bool)
    fixed[0] = True
    fixed[1:, :2] = True  # the cable moves along z only
    mass = np.zeros(n_bars + 1)
    mass[-1] = m
    nodes = Nodes(position=pos, fixed=fixed, mass=mass, volume=np.zeros(n_bars + 1), force=np.zeros((n_bars + 1, 3)))
    ends = np.stack([np.arange(n_bars), np.arange(1, n_bars + 1)], axis=1)
    bars = Bars(ends=ends, rest_length=np.full(n_bars, bar_length), ea_traction=np.full(n_bars, ea),
                ea_compression=np.full(n_bars, ea), diameter=np.full(n_bars, 1e-4), density=np.full(n_bars, 1e-9),
                cable=np.zeros(n_bars, dtype=int))
    env = Environment(gravity=9.81, added_mass_coefficient=0.0, current_speed=0.0, water_density=1e-9)
    return Scene(nodes=nodes, bars=bars, environment=env)


def test_a_winch_hauls_a_hanging_weight_at_its_speed():
    """A 50 kg weight on five 2 m bars (EA 1e7 N) hauled in from the top, the speed rising to 0.2 m/s over 2 s
    then held: at the end the weight rises at the winch's speed (stretched by m g/EA), the drum's tension is its weight m g, the cable
    hangs at its rest length stretched by m g/EA, and the winch has taken the bars from the drum down, each to
    its shortest length before the next."""
    m, n_bars, bar, ea, g, v = 50.0, 5, 2.0, 1e7, 9.81, 0.2
    scene = hanging_weight(m, n_bars, bar, ea)
    winch = forcing.Winch(np.arange(n_bars), drum_bar=0, times=[1.0, 3.0, 40.0], speeds=[0.0, v, v],
                          shortest=0.01, longest=50.0)
    loading = dynamics.Loading(winches=(winch,))
    newton = Newton(tol=1e-7, max_iter=30, damping=1e-12, stall_window=None)
    end = 30.0
    x0 = np.asarray(statics.solve(scene, tol=1e-7).x)
    tr = dynamics.simulate(scene, end, dynamics.Implicit(time_step=0.01, newton=newton), loading, record_every=5.0,
                           x0=x0)
    hauled = v * (end - 3.0) + 0.5 * v * 2.0
    assert tr.figures["winch_hauled_m"][-1][0] == pytest.approx(hauled, rel=1e-12)
    rest = bar * n_bars - hauled
    weight = tr.positions[-1, -1, 2]
    assert weight == pytest.approx(-rest * (1.0 + m * g / ea), rel=1e-9)
    # the cable's rest length shortens at v, its stretched length at v (1 + m g/EA)
    assert tr.velocities[-1, -1, 2] == pytest.approx(v * (1.0 + m * g / ea), rel=1e-9)
    assert tr.figures["winch_tension_N"][-1][0] == pytest.approx(m * g, rel=1e-6)
    # the bars from the drum down: two at their shortest, the third part-hauled, two untouched
    lengths = np.diff(-tr.positions[-1, :, 2]) / (1.0 + m * g / ea)
    np.testing.assert_allclose(lengths, [0.01, 0.01, 2.0 - (hauled - 2 * 1.99), 2.0, 2.0], rtol=1e-8)
    # at the start, the weight hangs still at the static equilibrium
    assert tr.positions[0, -1, 2] == pytest.approx(-bar * n_bars * (1.0 + m * g / ea), rel=1e-12)


def test_the_host_loop_hauls_as_the_compiled_loop():
    """A winch hauling a weight (its masses following the cable): the host-driven steps are the compiled loop's."""
    from test_dynamics import same_run_both_loops

    scene = hanging_weight(50.0, 4, 2.0, 1e7)
    winch = forcing.Winch(np.arange(4), 0, [0.0, 1.0, 9.0], [0.0, 2.0, 2.0], shortest=0.01, longest=50.0)
    newton = Newton(tol=1e-7, max_iter=30, damping=1e-12, stall_window=None)
    same_run_both_loops(scene, 3.0, 0.01, newton, dynamics.Loading(winches=(winch,)))


def test_bad_winches_are_refused_naming_the_culprit():
    with pytest.raises(ValueError, match="all haul in"):
        forcing.Winch([0, 1], 0, [0.0, 1.0], [1.0, -1.0], 0.01, 5.0)
    with pytest.raises(ValueError, match="longest"):
        forcing.Winch([0, 1], 0, [0.0, 1.0], [1.0, 1.0], 0.01, 0.005)
    with pytest.raises(ValueError, match="drum_bar 3"):
        forcing.Winch([0, 1], 3, [0.0, 1.0], [1.0, 1.0], 0.01, 5.0)
    with pytest.raises(ValueError, match="times must increase"):
        forcing.Winch([0, 1], 0, [1.0, 0.0], [1.0, 1.0], 0.01, 5.0)
    scene = hanging_weight(1.0, 3, 1.0, 1e5)
    opts = dynamics.Implicit(time_step=0.1)
    outside = forcing.Winch([1, 7], 1, [0.0, 1.0], [1.0, 1.0], 0.01, 5.0)
    with pytest.raises(SceneError, match="bar index 7 outside the scene's 3 bars"):
        dynamics.simulate(scene, 1.0, opts, dynamics.Loading(winches=(outside,)))
    a = forcing.Winch([0, 1], 0, [0.0, 1.0], [1.0, 1.0], 0.01, 5.0)
    b = forcing.Winch([2, 1], 2, [0.0, 1.0], [1.0, 1.0], 0.01, 5.0)
    with pytest.raises(SceneError, match="winches 0 and 1 both take bar 1"):
        dynamics.simulate(scene, 1.0, opts, dynamics.Loading(winches=(a, b)))
