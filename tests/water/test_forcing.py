"""Time histories (current speed) and prescribed motions of nodes: values, derivatives, smoothness."""

import math

import jax
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.water import forcing
from jaxnet.water.forcing import (Constant, Harmonic, Oscillation, PrescribedMotion, Ramp, Step, Sum, Towing)


SAMPLES = 32  # times per evaluation, padded: one shape, so one compilation per kind of history


def _padded(evaluate):
    def at(f, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = evaluate(f, np.concatenate([t, np.zeros(SAMPLES - t.size)]))
        return tuple(np.asarray(a)[: t.size] for a in out)

    return at


@_padded
@jax.jit
def history_at(history, t):
    """(value, closed-form rate, autodiff rate) of a scalar history at times t (n,)."""
    return jax.vmap(lambda s: (history(s), history.rate(s), jax.grad(history)(s)))(t)


@_padded
@jax.jit
def motion_at(motion, t):
    """(displacement, closed-form velocity, autodiff velocity) (n, 3) of a motion at times t (n,)."""
    return jax.vmap(lambda s: (motion(s), motion.velocity(s), jax.jacfwd(motion)(s)))(t)


def check_rates_agree(values):
    _, closed, autodiff = (np.asarray(v) for v in values)
    np.testing.assert_allclose(closed, autodiff, rtol=1e-13, atol=1e-15)


def test_constant():
    t = np.array([-3.0, 0.0, 2.5])
    value, rate, grad = (np.asarray(v) for v in history_at(Constant(1.7), t))
    np.testing.assert_array_equal(value, 1.7)
    np.testing.assert_array_equal(rate, 0.0)
    np.testing.assert_array_equal(grad, 0.0)


@pytest.mark.parametrize("smooth", [True, False])
def test_ramp_against_closed_forms(smooth):
    v0, v1, t0, t1 = 0.2, 1.4, 1.0, 5.0
    t = np.array([-1.0, 0.99, 1.5, 3.0, 4.2, 5.01, 9.0])
    values = history_at(Ramp(v0, v1, t0, t1, smooth=smooth), t)
    s = np.clip((t - t0) / (t1 - t0), 0.0, 1.0)
    inside = (t > t0) & (t < t1)
    if smooth:
        value = v0 + (v1 - v0) * (1 - np.cos(np.pi * s)) / 2
        rate = (v1 - v0) * np.pi / (2 * (t1 - t0)) * np.sin(np.pi * s) * inside
    else:
        value = v0 + (v1 - v0) * s
        rate = (v1 - v0) / (t1 - t0) * inside
    np.testing.assert_allclose(values[0], value, rtol=1e-14)
    np.testing.assert_allclose(values[1], rate, rtol=1e-13, atol=1e-15)
    check_rates_agree(values)
    assert float(values[0][3]) == pytest.approx((v0 + v1) / 2, rel=1e-14)  # halfway in time, halfway in value


def test_smooth_ramp_is_c1_and_the_linear_one_is_not():
    t0, t1, h = 1.0, 3.0, 1e-5
    for end in (t0, t1):
        t = np.array([end - 2 * h, end - h, end, end + h, end + 2 * h])
        smooth_value, smooth_rate, _ = (np.asarray(v) for v in history_at(Ramp(0.0, 2.0, t0, t1), t))
        # rate continuous through the end: 0 outside, rising linearly inside, as Δv π² |t - end| / (2 (t1 - t0)²)
        # (2.47 |t - end| here); and one-sided finite differences of the value agree (no kink)
        np.testing.assert_allclose(smooth_rate, 2.0 * np.pi**2 / 8.0 * np.abs(t - end) * (np.abs(t - 2.0) < 1.0),
                                   rtol=1e-8, atol=1e-15)
        left = (smooth_value[2] - smooth_value[0]) / (2 * h)
        right = (smooth_value[4] - smooth_value[2]) / (2 * h)
        assert abs(left - right) < 1e-4
        linear_value = np.asarray(history_at(Ramp(0.0, 2.0, t0, t1, smooth=False), t)[0])
        left = (linear_value[2] - linear_value[0]) / (2 * h)
        right = (linear_value[4] - linear_value[2]) / (2 * h)
        assert abs(left - right) == pytest.approx(1.0, rel=1e-6)  # the slope jumps by (v1 - v0)/(t1 - t0)
    # inside, central differences of the value match the closed-form rate
    t = np.linspace(1.1, 2.9, 7)
    ramp = Ramp(0.0, 2.0, t0, t1)
    fd = (np.asarray(history_at(ramp, t + h)[0]) - np.asarray(history_at(ramp, t - h)[0])) / (2 * h)
    np.testing.assert_allclose(fd, np.asarray(history_at(ramp, t)[1]), rtol=1e-8)


def test_step():
    values = history_at(Step(0.5, 2.0, 3.0), np.array([0.0, 2.999, 3.0, 7.0]))
    np.testing.assert_array_equal(values[0], [0.5, 0.5, 2.0, 2.0])  # "after" from the time of the jump on
    np.testing.assert_array_equal(values[1], 0.0)
    check_rates_agree(values)


def test_oscillation():
    mean, amplitude, period, phase = 1.0, 0.3, 4.0, 0.7
    t = np.linspace(-2.0, 9.0, 7)
    values = history_at(Oscillation(mean, amplitude, period, phase), t)
    omega = 2 * np.pi / period
    np.testing.assert_allclose(values[0], mean + amplitude * np.sin(omega * t + phase), rtol=1e-14)
    np.testing.assert_allclose(values[1], amplitude * omega * np.cos(omega * t + phase), rtol=1e-13, atol=1e-15)
    check_rates_agree(values)


def integral_of_velocity(motion, pieces, order=SAMPLES):
    """∫ velocity dt (3,) over consecutive intervals ``pieces`` by Gauss-Legendre quadrature on each: its
    nodes are inside the intervals, so a velocity that jumps at a boundary is integrated side by side."""
    nodes, weights = np.polynomial.legendre.leggauss(order)
    total = np.zeros(3)
    for a, b in zip(pieces[:-1], pieces[1:]):
        t = 0.5 * (b - a) * nodes + 0.5 * (a + b)
        total += 0.5 * (b - a) * weights @ np.asarray(motion_at(motion, t)[1])
    return total


@pytest.mark.parametrize("ramp", [0.0, 2.5])
def test_towing_displacement_is_the_integral_of_its_velocity(ramp):
    V, start = np.array([1.2, 0.0, -0.3]), 1.0
    towing = Towing(V, start_time=start, ramp=ramp)
    end = 7.0
    # the quadrature is split where the velocity or its derivative jumps (start, end of the ramp)
    pieces = [0.0, start] + ([start + ramp] if ramp > 0 else []) + [end]
    integral = integral_of_velocity(towing, pieces)
    displacement = np.asarray(motion_at(towing, np.array([0.0, end]))[0])
    np.testing.assert_allclose(displacement[1] - displacement[0], integral, rtol=1e-12, atol=1e-14)
    # closed form after the ramp: V (t - start - R/2)
    np.testing.assert_allclose(displacement[1], V * (end - start - ramp / 2), rtol=1e-14)
    check_rates_agree(motion_at(towing, np.linspace(-1.0, 8.0, 10)))


def test_towing_ramp_is_smooth():
    # velocity and acceleration continuous at both ends of the ramp: d, v at the ends, finite differences
    V, start, ramp, h = np.array([0.0, 2.0, 0.0]), 0.5, 3.0, 1e-5
    towing = Towing(V, start_time=start, ramp=ramp)
    for end, speed in ((start, 0.0), (start + ramp, 1.0)):
        t = np.array([end - h, end, end + h])
        d, v, _ = (np.asarray(a) for a in motion_at(towing, t))
        np.testing.assert_allclose(v, np.outer(np.full(3, speed), V), atol=1e-9)
        np.testing.assert_allclose((d[2] - d[0]) / (2 * h), speed * V, atol=1e-9)
    # a quarter into the ramp: V (τ/2 - R/(2π) sin(πτ/R)) at τ = R/4
    tau = ramp / 4
    d = np.asarray(motion_at(towing, np.array([start + tau]))[0][0])
    np.testing.assert_allclose(d, V * (tau / 2 - ramp / (2 * np.pi) * np.sin(np.pi / 4)), rtol=1e-14)


def test_harmonic_without_and_with_ramp():
    A, period, phase = np.array([0.0, 0.1, 0.5]), 6.0, 0.4
    omega = 2 * np.pi / period
    t = np.linspace(-3.0, 20.0, 9)
    plain = motion_at(Harmonic(A, period, phase), t)
    np.testing.assert_allclose(plain[0], np.outer(np.sin(omega * t + phase), A), rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(plain[1], np.outer(omega * np.cos(omega * t + phase), A), rtol=1e-13, atol=1e-14)
    check_rates_agree(plain)
    # with phase 0 and no ramp the nodes start in place but already moving (documented)
    d0, v0, _ = (np.asarray(a[0]) for a in motion_at(Harmonic(A, period), np.array([0.0])))
    np.testing.assert_array_equal(d0, 0.0)
    np.testing.assert_allclose(v0, omega * A, rtol=1e-14)
    # a ramp of 1.5 periods starts from rest and equals the plain motion once it is over
    ramped = Harmonic(A, period, phase, ramp=9.0)
    d, v, autodiff = (np.asarray(a) for a in motion_at(ramped, np.array([-1.0, 0.0, 4.0, 9.0, 13.0])))
    np.testing.assert_array_equal(d[:2], 0.0)
    np.testing.assert_array_equal(v[:2], 0.0)
    s = 4.0 / 9.0
    envelope = s**3 * (10 - 15 * s + 6 * s**2)
    np.testing.assert_allclose(d[2], A * np.sin(omega * 4.0 + phase) * envelope, rtol=1e-14)
    np.testing.assert_allclose(d[3:], np.outer(np.sin(omega * np.array([9.0, 13.0]) + phase), A), rtol=1e-13,
                               atol=1e-14)
    np.testing.assert_allclose(v, autodiff, rtol=1e-13, atol=1e-14)
    # the displacement is the integral of the velocity, through the ramp and beyond
    np.testing.assert_allclose(integral_of_velocity(ramped, [0.0, 9.0, 13.0]), d[4], rtol=1e-12, atol=1e-14)


def test_sum_of_motions_and_of_histories():
    tow, heave = Towing([1.0, 0.0, 0.0], ramp=2.0), Harmonic([0.0, 0.0, 0.4], 5.0, ramp=5.0)
    t = np.linspace(0.0, 8.0, 5)
    both = motion_at(tow + heave, t)
    for k in range(3):
        np.testing.assert_allclose(both[k], np.asarray(motion_at(tow, t)[k]) + np.asarray(motion_at(heave, t)[k]),
                                   rtol=1e-14)
    speed = Sum(Constant(0.5), Oscillation(0.0, 0.1, 3.0))
    values = history_at(speed, t)
    np.testing.assert_allclose(values[0], 0.5 + 0.1 * np.sin(2 * np.pi * t / 3.0), rtol=1e-14)
    check_rates_agree(values)


def test_histories_are_differentiable_pytrees():
    # d/d(end_value) of a smooth ramp at a quarter of its duration is its shape (1 - cos(π/4))/2
    dv = jax.jit(jax.grad(lambda v: Ramp(0.0, v, 0.0, 4.0)(1.0)))(3.0)
    assert float(dv) == pytest.approx((1 - math.cos(math.pi / 4)) / 2, rel=1e-14)
    # d/d(period) of a heave: -A ω t/T cos(ωt)
    A, T, t = 0.5, 6.0, 1.3
    dT = jax.jit(jax.grad(lambda p: Harmonic([0.0, 0.0, A], p)(t)[2]))(T)
    omega = 2 * math.pi / T
    assert float(dT) == pytest.approx(-A * omega * t / T * math.cos(omega * t), rel=1e-13)
    # a prescribed motion goes through jit as a pytree
    prescribed = PrescribedMotion([0, 4], Towing([1.0, 0.0, 0.0]))
    d, v = jax.jit(lambda p, s: (p.displacement(s), p.velocity(s)))(prescribed, 2.0)
    np.testing.assert_allclose(d, [2.0, 0.0, 0.0], rtol=1e-15)
    np.testing.assert_allclose(v, [1.0, 0.0, 0.0], rtol=1e-15)
    assert np.asarray(prescribed.nodes).tolist() == [0, 4]


@pytest.mark.parametrize("make, name", [
    (lambda: Oscillation(0.0, 1.0, -2.0), "period"),
    (lambda: Oscillation(0.0, 1.0, 0.0), "period"),
    (lambda: Harmonic([0.0, 0.0, 1.0], -1.0), "period"),
    (lambda: Harmonic([0.0, 1.0], 2.0), "amplitude"),
    (lambda: Harmonic([0.0, 0.0, 1.0], 2.0, ramp=-1.0), "ramp"),
    (lambda: Towing([1.0, float("nan"), 0.0]), "velocity"),
    (lambda: Towing([1.0, 0.0]), "velocity"),
    (lambda: Towing([1.0, 0.0, 0.0], ramp=-0.5), "ramp"),
    (lambda: Towing([1.0, 0.0, 0.0], start_time=float("nan")), "start_time"),
    (lambda: Ramp(0.0, 1.0, 2.0, 2.0), "end_time"),
    (lambda: Ramp(0.0, float("nan"), 0.0, 1.0), "end_value"),
    (lambda: Constant(float("inf")), "value"),
    (lambda: Step(0.0, 1.0, float("nan")), "time"),
    (lambda: PrescribedMotion([-1, 2], Towing([1.0, 0.0, 0.0])), "nodes"),
    (lambda: PrescribedMotion([[1, 2]], Towing([1.0, 0.0, 0.0])), "nodes"),
    (lambda: PrescribedMotion([1.0], Towing([1.0, 0.0, 0.0])), "nodes"),
    (lambda: PrescribedMotion([1], Constant(1.0)), "motion"),
    (lambda: Sum(), "parts"),
])
def test_bad_parameters_name_the_parameter(make, name):
    with pytest.raises(ValueError, match=name):
        make()


def test_traced_parameters_are_not_validated_but_work():
    # built inside jit the numbers are tracers: no check can run, and none must fail
    f = jax.jit(lambda T, t: Oscillation(1.0, 2.0, T)(t))
    assert float(f(4.0, 1.0)) == pytest.approx(1.0 + 2.0 * math.sin(math.pi / 2), rel=1e-14)
    assert isinstance(Towing([1.0, 0.0, 0.0]), forcing.AbstractMotion)


def test_speed_table_is_femnets_linear_speeds_and_their_exact_integral():
    from jaxnet.water.forcing import SpeedTable

    table = SpeedTable([10.0, 20.0, 40.0], [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 2.0, -1.0]])
    t = np.array([0.0, 10.0, 15.0, 20.0, 30.0, 40.0, 55.0])
    d, v, autodiff = (np.asarray(a) for a in motion_at(table, t))
    # still before and after the table; linear in between
    np.testing.assert_allclose(v, [[0, 0, 0], [0, 0, 0], [0.5, 0, 0], [1, 0, 0], [1, 1, -0.5], [1, 2, -1], [0, 0, 0]],
                               atol=1e-15)
    np.testing.assert_allclose(v, autodiff, atol=1e-15)
    # the displacement: trapezoids of the linear speeds, held after the table
    np.testing.assert_allclose(d, [[0, 0, 0], [0, 0, 0], [1.25, 0, 0], [5, 0, 0], [15, 5, -2.5], [25, 20, -10],
                                   [25, 20, -10]], atol=1e-13)
    np.testing.assert_allclose(integral_of_velocity(table, [0.0, 10.0, 20.0, 40.0, 55.0]), d[-1], rtol=1e-12)
    for times, velocities, word in (([1.0], [[0.0, 0.0, 0.0]], "at least 2"), ([1.0, 1.0], np.zeros((2, 3)), "increase"),
                                    ([0.0, 1.0], np.zeros((3, 3)), "velocities")):
        with pytest.raises(ValueError, match=word):
            SpeedTable(times, velocities)
