"""Time histories for dynamics: scalar histories (the speed of the current) and prescribed motions of nodes
(towing, the heave or surge of a collar).

Every history is an equinox Module (a pytree: its numbers are leaves, so a study can trace or
differentiate them) called as ``f(t)`` with t a scalar time (s); each is a pure jnp function of t,
jittable and differentiable in t (``jax.grad``/``jax.jacfwd``), and also gives its derivative in closed
form (the tests check both agree):

* scalar histories, ``f(t)`` in the unit of the quantity (m/s for a current speed), ``f.rate(t)`` its
  time derivative (unit/s; the dynamics takes d(speed)/dt for the water's acceleration γ_h of 4.265):
  :class:`Constant`, :class:`Ramp`, :class:`Step`, :class:`Oscillation`;
* motions, ``m(t)`` the displacement (3,) (m) of nodes from their start positions, ``m.velocity(t)`` its
  time derivative (3,) (m/s): :class:`Towing`, :class:`SpeedTable` (FEMNET's towing speed tables),
  :class:`Harmonic`;
* :class:`Sum` (also ``a + b``) adds histories, or motions;
* :class:`PrescribedMotion` pairs node indices with a motion: the dynamics holds those nodes at
  start + m(t);
* :class:`Winch` hauls in or pays out a cable by a speed table: the rest lengths of its bars at t.

Smoothness, and why it matters. The implicit step takes the water's acceleration from the derivative of
the current's speed, and a prescribed node's velocity from the derivative of its displacement; a kink in a
history is a jump of those, i.e. a sudden load that rings through a stiff net and costs Newton iterations
or halved steps. Hence the half-cosine ramp r(s) = (1 - cos πs)/2 (s from 0 to 1), whose slope is 0 at
both ends (C¹; the peak slope is π/2 times the linear ramp's): :class:`Ramp` uses it by default
(``smooth=True``; ``smooth=False`` gives the linear ramp of FEMNET-like inputs, whose rate jumps), and
:class:`Towing` and :class:`Harmonic` use it for their optional ``ramp`` (s) up. :class:`Step` is a true
jump: its rate is 0 (the Dirac impulse at the jump is not represented), so a current switched on by a Step
gives the net no water-acceleration load; prefer a short Ramp.

Clamps are written with ``where`` so that derivatives are exactly those of the active piece and never NaN;
at a junction the autodiff derivative and ``rate``/``velocity`` take the same side.

Validation: constructing a history with concrete numbers raises ValueError naming the parameter for NaN
or inf, a wrong shape, a non-positive period, a negative ramp or a ramp that ends before it starts. Traced
values (a history built inside ``jit``) are not checked.

Units: s, m, m/s, rad.
"""

from __future__ import annotations

import abc
from typing import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np


# -- helpers ---------------------------------------------------------------------------------------------


def _as_float(value):
    return jnp.asarray(value, dtype=float)


def _is_concrete(value):
    """True when ``value`` holds numbers, not tracers: only then can it be validated."""
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(value))


def _check(owner, name, value, shape=(), lower=None, strict=True):
    """Raise ValueError naming ``owner``'s parameter ``name`` if ``value`` (concrete) has the wrong shape,
    is NaN or infinite, or is not above ``lower`` (``strict``) / at least ``lower``."""
    if not _is_concrete(value):
        return
    array = np.asarray(value, dtype=float)
    if array.shape != shape:
        raise ValueError(f"{owner}: {name} must have shape {shape}, got {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{owner}: {name} must be finite (no NaN or inf), got {array.tolist()}")
    if lower is not None and not (array > lower if strict else array >= lower).all():
        raise ValueError(f"{owner}: {name} must be {'>' if strict else '>='} {lower}, got {array.tolist()}")


def _clamp_unit(s):
    """s clamped to [0, 1] with slope exactly 1 inside (ends included) and 0 outside."""
    return jnp.where(s < 0.0, 0.0, jnp.where(s > 1.0, 1.0, s))


def _inside_unit(s):
    """1.0 where the clamp of :func:`_clamp_unit` passes s through (slope 1), else 0.0."""
    return jnp.where((s >= 0.0) & (s <= 1.0), 1.0, 0.0)


def _half_cosine(s):
    """Smooth 0 → 1 step (1 - cos πs)/2 of s clamped to [0, 1], and its derivative in s (C¹: 0 at both
    ends and outside)."""
    c = _clamp_unit(s)
    return 0.5 * (1.0 - jnp.cos(jnp.pi * c)), 0.5 * jnp.pi * jnp.sin(jnp.pi * c) * _inside_unit(s)


def envelope(t, duration):
    """The smooth start of something that grows in over ``duration`` (s) from t = 0: (e(t), de/dt (1/s)),

        e = 0 (t <= 0),   s³ (10 - 15 s + 6 s²) with s = t/duration (during),   1 (t >= duration),

    C²: e, de/dt and d²e/dt² are continuous and the last two are 0 at both ends, so a motion or a wave
    multiplied by it starts with zero velocity *and acceleration*: the inertia of what it moves rises from 0
    instead of jumping, as it would under a half-cosine (whose second derivative jumps to (π/duration)²/2 at
    t = 0). ``duration`` 0 means no envelope (e = 1, de/dt = 0 at every t). What :class:`Harmonic`'s ``ramp``
    and the waves' (:mod:`jaxnet.water.waves`) use."""
    t = jnp.asarray(t, dtype=float)
    ramped = jnp.asarray(duration) > 0.0
    safe = jnp.where(ramped, duration, 1.0)
    s = _clamp_unit(t / safe)
    value = s**3 * (10.0 - 15.0 * s + 6.0 * s**2)
    slope = 30.0 * s**2 * (1.0 - s) ** 2 / safe
    return jnp.where(ramped, value, 1.0), jnp.where(ramped, slope, 0.0)


# -- base classes ----------------------------------------------------------------------------------------


class AbstractHistory(eqx.Module):
    """A scalar function of time: ``f(t)`` (the quantity's unit), ``f.rate(t)`` (unit/s)."""

    @abc.abstractmethod
    def __call__(self, t):
        raise NotImplementedError

    @abc.abstractmethod
    def rate(self, t):
        raise NotImplementedError

    def __add__(self, other):
        return Sum(self, other)


class AbstractMotion(eqx.Module):
    """A displacement (3,) (m) as a function of time: ``m(t)``, ``m.velocity(t)`` (m/s)."""

    @abc.abstractmethod
    def __call__(self, t):
        raise NotImplementedError

    @abc.abstractmethod
    def velocity(self, t):
        raise NotImplementedError

    def displacement(self, t):
        """Displacement (3,) (m) at time t (s); the same as calling the motion."""
        return self(t)

    def __add__(self, other):
        return Sum(self, other)


# -- scalar histories ------------------------------------------------------------------------------------


class Constant(AbstractHistory):
    """f(t) = value, for all t."""

    value: jax.Array = eqx.field(converter=_as_float)

    def __check_init__(self):
        _check("Constant", "value", self.value)

    def __call__(self, t):
        # + 0 t: the result is a function of t (a tracer under jit), as every history's is
        return self.value + 0.0 * jnp.asarray(t, dtype=float)

    def rate(self, t):
        return jnp.zeros_like(self(t))


class Ramp(AbstractHistory):
    """From ``start_value`` (held before ``start_time``) to ``end_value`` (held after ``end_time``), times in s.

    ``smooth=True`` (default): half-cosine, f = v0 + (v1 - v0) (1 - cos πs)/2, s = (t - t0)/(t1 - t0),
    C¹ (its rate rises from and falls back to 0). ``smooth=False``: linear, f = v0 + (v1 - v0) s, whose
    rate jumps to (v1 - v0)/(t1 - t0) at t0 and back at t1. ``end_time`` must exceed ``start_time``
    (a jump is a :class:`Step`).
    """

    start_value: jax.Array = eqx.field(converter=_as_float)
    end_value: jax.Array = eqx.field(converter=_as_float)
    start_time: jax.Array = eqx.field(converter=_as_float)
    end_time: jax.Array = eqx.field(converter=_as_float)
    smooth: bool = eqx.field(default=True, static=True)

    def __check_init__(self):
        for name in ("start_value", "end_value", "start_time", "end_time"):
            _check("Ramp", name, getattr(self, name))
        if _is_concrete((self.start_time, self.end_time)) and not float(self.end_time) > float(self.start_time):
            raise ValueError(f"Ramp: end_time ({float(self.end_time)}) must be > start_time "
                             f"({float(self.start_time)}); use Step for a jump")

    def _fraction(self, t):
        return (jnp.asarray(t, dtype=float) - self.start_time) / (self.end_time - self.start_time)

    def __call__(self, t):
        s = self._fraction(t)
        shape = _half_cosine(s)[0] if self.smooth else _clamp_unit(s)
        return self.start_value + (self.end_value - self.start_value) * shape

    def rate(self, t):
        s = self._fraction(t)
        slope = _half_cosine(s)[1] if self.smooth else _inside_unit(s)
        return (self.end_value - self.start_value) * slope / (self.end_time - self.start_time)


class Step(AbstractHistory):
    """``before`` for t < ``time`` (s), ``after`` from ``time`` on. Its rate is 0 everywhere: the jump's
    impulse is not represented (see the module docstring; a short :class:`Ramp` is kinder to dynamics)."""

    before: jax.Array = eqx.field(converter=_as_float)
    after: jax.Array = eqx.field(converter=_as_float)
    time: jax.Array = eqx.field(converter=_as_float)

    def __check_init__(self):
        for name in ("before", "after", "time"):
            _check("Step", name, getattr(self, name))

    def __call__(self, t):
        t = jnp.asarray(t, dtype=float)
        return jnp.where(t < self.time, self.before, self.after) + 0.0 * t

    def rate(self, t):
        return jnp.zeros_like(self(t))


class Oscillation(AbstractHistory):
    """f(t) = mean + amplitude sin(2π t/period + phase); period in s (> 0), phase in rad."""

    mean: jax.Array = eqx.field(converter=_as_float)
    amplitude: jax.Array = eqx.field(converter=_as_float)
    period: jax.Array = eqx.field(converter=_as_float)
    phase: jax.Array = eqx.field(default=0.0, converter=_as_float)

    def __check_init__(self):
        for name in ("mean", "amplitude", "phase"):
            _check("Oscillation", name, getattr(self, name))
        _check("Oscillation", "period", self.period, lower=0.0)

    def __call__(self, t):
        return self.mean + self.amplitude * jnp.sin(2.0 * jnp.pi * jnp.asarray(t, dtype=float) / self.period
                                                    + self.phase)

    def rate(self, t):
        omega = 2.0 * jnp.pi / self.period
        return self.amplitude * omega * jnp.cos(omega * jnp.asarray(t, dtype=float) + self.phase)


# -- motions ---------------------------------------------------------------------------------------------


class Towing(AbstractMotion):
    """Towing at a constant velocity (3,) (m/s), reached after a smooth ramp up.

    Velocity V r(τ), τ = t - start_time: r = 0 before start_time, (1 - cos(πτ/R))/2 during the ramp
    (R = ``ramp``, s), 1 after. Displacement (m), its integral from the start:

        0 (τ <= 0),   V (τ/2 - R/(2π) sin(πτ/R)) (0 < τ < R),   V (τ - R/2) (τ >= R).

    With R > 0 the displacement is C² (velocity and acceleration continuous), so a net towed from rest
    starts smoothly; with R = 0 (default) the velocity jumps from 0 to V at start_time.

    Args: velocity: (3,) towing velocity (m/s); start_time: s; ramp: R (s), >= 0.
    """

    towing_velocity: jax.Array
    start_time: jax.Array
    ramp: jax.Array

    def __init__(self, velocity, start_time=0.0, ramp=0.0):
        _check("Towing", "velocity", velocity, shape=(3,))
        _check("Towing", "start_time", start_time)
        _check("Towing", "ramp", ramp, lower=0.0, strict=False)
        self.towing_velocity = _as_float(velocity)
        self.start_time = _as_float(start_time)
        self.ramp = _as_float(ramp)

    def _ramped(self, t):
        """τ (s), whether the ramp is on (R > 0), and R with 1 in its place when R = 0 (no division by 0)."""
        tau = jnp.asarray(t, dtype=float) - self.start_time
        ramped = self.ramp > 0.0
        return tau, ramped, jnp.where(ramped, self.ramp, 1.0)

    def __call__(self, t):
        tau, ramped, ramp = self._ramped(t)
        during = 0.5 * tau - ramp / (2.0 * jnp.pi) * jnp.sin(jnp.pi * tau / ramp)
        distance = jnp.where(tau >= self.ramp, tau - 0.5 * self.ramp,
                             jnp.where(ramped & (tau > 0.0), during, 0.0))
        return distance * self.towing_velocity

    def velocity(self, t):
        tau, ramped, ramp = self._ramped(t)
        fraction = jnp.where(tau >= self.ramp, 1.0, jnp.where(ramped & (tau > 0.0), _half_cosine(tau / ramp)[0], 0.0))
        return fraction * self.towing_velocity


class SpeedTable(AbstractMotion):
    """A velocity (3,) (m/s) given by a time table: linear between the table's times t_1 < ... < t_K (s), 0 before
    t_1 and after t_K (the nodes stand still there): FEMNET's ``input speed_type_node2`` towing speeds. The
    displacement (m) is its integral from t_1, exact (piecewise quadratic in t):

        d(t) = Σ_{j < i} (v_j + v_{j+1})/2 Δ_j + v_i τ + (v_{i+1} - v_i) τ²/(2 Δ_i),   τ = t - t_i in segment i,

    held at its last value after t_K. The velocity jumps where the table starts or ends at a non-zero speed, as
    FEMNET's does (a smooth start: a first row at speed 0, or the run's start ramp).

    Args: times: (K,) increasing times (s), K >= 2; velocities: (K, 3) the velocity at each (m/s).
    """

    times: jax.Array
    velocities: jax.Array

    def __init__(self, times, velocities):
        if _is_concrete((times, velocities)):
            t, v = np.asarray(times, dtype=float), np.asarray(velocities, dtype=float)
            if t.ndim != 1 or t.size < 2:
                raise ValueError(f"SpeedTable: times must be a 1-D array of at least 2 times (s), got shape {t.shape}")
            _check("SpeedTable", "times", t, shape=t.shape)
            if not (np.diff(t) > 0).all():
                raise ValueError(f"SpeedTable: times must increase, got {t.tolist()}")
            _check("SpeedTable", "velocities", v, shape=(t.size, 3))
        self.times = _as_float(times)
        self.velocities = _as_float(velocities)

    def _segment(self, t):
        """(i, τ, Δ_i): the segment of t (clamped to the table), the time into it (s) and its length (s)."""
        t = jnp.asarray(t, dtype=float)
        k = self.times.shape[0]
        clamped = jnp.where(t < self.times[0], self.times[0], jnp.where(t > self.times[-1], self.times[-1], t))
        i = jnp.clip(jnp.searchsorted(self.times, clamped, side="right") - 1, 0, k - 2)
        return i, clamped - self.times[i], self.times[i + 1] - self.times[i]

    def __call__(self, t):
        i, tau, span = self._segment(t)
        v = self.velocities
        done = jnp.concatenate([jnp.zeros((1, 3)), jnp.cumsum(0.5 * (v[1:] + v[:-1]) * jnp.diff(self.times)[:, None],
                                                              axis=0)])
        return done[i] + v[i] * tau + (v[i + 1] - v[i]) * tau**2 / (2.0 * span)

    def velocity(self, t):
        t = jnp.asarray(t, dtype=float)
        i, tau, span = self._segment(t)
        inside = (t >= self.times[0]) & (t <= self.times[-1])
        return jnp.where(inside, self.velocities[i] + (self.velocities[i + 1] - self.velocities[i]) * tau / span, 0.0)


class Harmonic(AbstractMotion):
    """Harmonic displacement amplitude sin(2π t/period + phase) e(t) (m), amplitude (3,) in m, period in s
    (> 0), phase in rad: the heave or surge of a collar.

    e(t) is an optional smooth envelope rising over ``ramp`` seconds from t = 0 (:func:`envelope`, C²): 0
    before, s³ (10 - 15 s + 6 s²) with s = t/R during, 1 after; ``ramp = 0`` (default) means no envelope (e = 1
    at all t). Without it, phase 0 gives a zero displacement at t = 0 but a velocity 2π/period × amplitude: a
    net starting at rest is jerked into motion; a nonzero phase even displaces the nodes at t = 0. A ramp of a
    period or two starts the motion
    with zero displacement and zero velocity.
    """

    amplitude: jax.Array
    period: jax.Array
    phase: jax.Array
    ramp: jax.Array

    def __init__(self, amplitude, period, phase=0.0, ramp=0.0):
        _check("Harmonic", "amplitude", amplitude, shape=(3,))
        _check("Harmonic", "period", period, lower=0.0)
        _check("Harmonic", "phase", phase)
        _check("Harmonic", "ramp", ramp, lower=0.0, strict=False)
        self.amplitude = _as_float(amplitude)
        self.period = _as_float(period)
        self.phase = _as_float(phase)
        self.ramp = _as_float(ramp)

    def __call__(self, t):
        t = jnp.asarray(t, dtype=float)
        envelope_value, _ = envelope(t, self.ramp)
        return self.amplitude * (jnp.sin(2.0 * jnp.pi * t / self.period + self.phase) * envelope_value)

    def velocity(self, t):
        t = jnp.asarray(t, dtype=float)
        omega = 2.0 * jnp.pi / self.period
        envelope_value, envelope_rate = envelope(t, self.ramp)
        angle = omega * t + self.phase
        return self.amplitude * (omega * jnp.cos(angle) * envelope_value + jnp.sin(angle) * envelope_rate)


# -- composition -----------------------------------------------------------------------------------------


class Sum(eqx.Module):
    """The sum of histories (``rate`` sums their rates) or of motions (``velocity`` sums their velocities),
    e.g. ``Towing(...) + Harmonic(...)``: towing a net whose head rope heaves."""

    parts: tuple

    def __init__(self, *parts):
        if not parts:
            raise ValueError("Sum: parts must not be empty")
        for k, part in enumerate(parts):
            if not isinstance(part, (AbstractHistory, AbstractMotion, Sum)):
                raise ValueError(f"Sum: parts[{k}] must be a history or a motion of jaxnet.water.forcing, got "
                                 f"{type(part).__name__}")
        self.parts = tuple(parts)

    def __call__(self, t):
        return sum(part(t) for part in self.parts)

    def rate(self, t):
        return sum(part.rate(t) for part in self.parts)

    def velocity(self, t):
        return sum(part.velocity(t) for part in self.parts)

    def displacement(self, t):
        return self(t)

    def __add__(self, other):
        return Sum(*self.parts, other)


# -- prescribed motion of nodes --------------------------------------------------------------------------


def _as_nodes(value):
    if _is_concrete(value):
        array = np.asarray(value)
        return array.astype(np.int64) if array.dtype.kind in "iu" else array
    return jnp.asarray(value)


class PrescribedMotion(eqx.Module):
    """Node indices paired with a motion: the dynamics holds node i (fixed in the scene) at
    start_i + motion(t).

    nodes: (K,) integer indices (>= 0) of nodes into the scene. motion: a motion of this module
    (:class:`Towing`, :class:`Harmonic`, a :class:`Sum` of them) or any pytree callable t -> (3,)
    displacement (m) with a ``velocity(t)``.
    """

    nodes: np.ndarray | jax.Array = eqx.field(converter=_as_nodes)
    motion: AbstractMotion | Sum

    def __check_init__(self):
        if _is_concrete(self.nodes):
            nodes = np.asarray(self.nodes)
            if nodes.ndim != 1:
                raise ValueError(f"PrescribedMotion: nodes must be a 1-D array of node indices, got shape "
                                 f"{nodes.shape}")
            if nodes.dtype.kind not in "iu":
                raise ValueError(f"PrescribedMotion: nodes must be integers, got dtype {nodes.dtype}")
            if (nodes < 0).any():
                raise ValueError(f"PrescribedMotion: nodes must be >= 0, got {int(nodes.min())}")
        if not callable(self.motion) or not hasattr(self.motion, "velocity"):
            raise ValueError(f"PrescribedMotion: motion must be callable t -> (3,) displacement with a "
                             f"velocity(t), got {type(self.motion).__name__}")
        shape = jax.eval_shape(self.motion, jnp.zeros(())).shape
        if shape != (3,):
            raise ValueError(f"PrescribedMotion: motion must return a (3,) displacement, got shape {shape}")

    def displacement(self, t):
        """Displacement (3,) (m) of the nodes from their start positions at time t (s)."""
        return self.motion(t)

    def velocity(self, t):
        """Velocity (3,) (m/s) of the nodes at time t (s)."""
        return self.motion.velocity(t)


class Winch(eqx.Module):
    """A winch hauling in or paying out a cable by a speed table: FEMNET's ``input hauling_cable4``.

    The cable keeps its bars and nodes (none is added or removed, as in FEMNET): the winch changes the bars'
    rest lengths. The length hauled in by time t is

        H(t) = ∫ s(τ) dτ    (m),

    the speed s (m/s; > 0 hauls in, < 0 pays out) linear between the table's times and 0 outside them,
    integrated exactly (:class:`SpeedTable`). Hauling in shortens the bars in the order of ``bars``, each down
    to ``shortest`` before the next starts; paying out lengthens them in that order, each up to ``longest``:

        l_k(t) = l_k(0) - clip(H - Σ_{j<k} c_j, 0, c_k),    c_k = max(l_k(0) - shortest, 0)    (H >= 0)
        l_k(t) = l_k(0) + clip(-H - Σ_{j<k} c_j, 0, c_k),   c_k = max(longest - l_k(0), 0)     (H < 0)

    the lengths FEMNET's ``dyna`` reaches step by step (``hauling_cable``: the first bar of its list above
    the shortest length is shortened, the rest of the step's length passing to the next). The sum of the
    rest lengths changes by exactly H until every bar is at its limit; the winch then stops. The lengths are
    continuous and piecewise quadratic in t (the bars' tensions change smoothly; their rates jump where a
    bar reaches its limit and the next one starts).

    bars: (K,) indices into ``scene.bars``, in the order the winch takes them. drum_bar: the bar at the
    drum, whose tension is the winch's pull (the records' ``winch_tension_N``). times: (M,) increasing
    times (s), M >= 2; speeds: (M,) the hauling speed at them (m/s), all >= 0 (hauling) or all <= 0
    (paying out): a table of both signs is refused (FEMNET then changes the bar it starts from).
    shortest, longest: the bars' limits (m), 0 < shortest < longest.
    """

    bars: np.ndarray = eqx.field(converter=_as_nodes)
    drum_bar: int = eqx.field(static=True)
    table: SpeedTable
    shortest: jax.Array
    longest: jax.Array

    def __init__(self, bars, drum_bar, times, speeds, shortest, longest):
        if _is_concrete((times, speeds, shortest, longest)):
            v = np.asarray(speeds, dtype=float)
            if v.ndim != 1:
                raise ValueError(f"Winch: speeds must be a 1-D array (m/s), got shape {v.shape}")
            if (v > 0).any() and (v < 0).any():
                raise ValueError(f"Winch: the speeds must all haul in (>= 0) or all pay out (<= 0), got {v.tolist()}")
            _check("Winch", "shortest", shortest, lower=0.0)
            _check("Winch", "longest", longest, lower=float(shortest))
        bars = _as_nodes(bars)
        if _is_concrete(bars):
            array = np.asarray(bars)
            if array.ndim != 1 or array.size == 0 or array.dtype.kind not in "iu" or (array < 0).any():
                raise ValueError(f"Winch: bars must be a non-empty 1-D array of bar indices >= 0, got {array!r}")
            if int(drum_bar) not in array.tolist():
                raise ValueError(f"Winch: drum_bar {drum_bar} is not one of its bars")
        self.bars = bars
        self.drum_bar = int(drum_bar)
        speeds = _as_float(speeds)
        self.table = SpeedTable(times, jnp.stack([speeds, jnp.zeros_like(speeds), jnp.zeros_like(speeds)], axis=-1))
        self.shortest = _as_float(shortest)
        self.longest = _as_float(longest)

    def hauled(self, t):
        """H(t): the length (m) hauled in by time t (s), negative when paid out."""
        return self.table(t)[0]

    def speed(self, t):
        """The hauling speed (m/s) at time t (s)."""
        return self.table.velocity(t)[0]

    def rest_lengths(self, rest_length, t):
        """(B,) every bar's rest length (m) at time t: ``rest_length`` (the scene's, at the start) with the
        winch's bars shortened or lengthened by H(t), in their order."""
        rest_length = jnp.asarray(rest_length, dtype=float)
        start = rest_length[self.bars]
        h = self.hauled(t)
        hauling = h >= 0.0
        capacity = jnp.where(hauling, jnp.maximum(start - self.shortest, 0.0), jnp.maximum(self.longest - start, 0.0))
        before = jnp.cumsum(capacity) - capacity
        moved = jnp.clip(jnp.abs(h) - before, 0.0, capacity)
        return rest_length.at[self.bars].set(jnp.where(hauling, start - moved, start + moved))


class Loading(eqx.Module):
    """What changes with time besides the net (pytree: its numbers can be traced and differentiated): what a
    run in time (:func:`jaxnet.solve.dynamics.simulate`) is given with its scene.

    current_speed: a history t -> speed (m/s) of the current (a scalar history of this module), scaling the
      environment's current (its direction and depth profile kept); None: the environment's constant speed.
    motions: prescribed motions (:class:`PrescribedMotion`): each moves its nodes, which must be fixed in the
      scene, to their start positions plus its displacement at t.
    winches: :class:`Winch` es: each sets its cable's bars' rest lengths at t from the scene's. Not ramped (a
      winch starts at its table's first time, with its speed there).
    ramp: the time (s) over which a run grows in what its static start leaves out, so that it starts without
      a shock: the waves (their ``ramp``: elevation and velocity times :func:`envelope`) and the
      :class:`Towing` and :class:`Harmonic` motions that have no ramp of their own (theirs set to it: a towing
      speed rises to its value, a heave's amplitude grows, its phase kept). None (default): one period of the
      waves (:attr:`jaxnet.water.waves.Airy.characteristic_period`, an irregular sea's peak period), 0 without
      waves; 0: nothing ramped. The current is not ramped: the run starts from the static equilibrium in it.
      :func:`jaxnet.solve.dynamics.with_start_ramp` applies it, in :func:`jaxnet.solve.dynamics.simulate` and
      :func:`jaxnet.solve.reference.reference`; the run's records state it. The differentiable runs of
      :mod:`jaxnet.solve.adjoint_dynamics` take the scene and loading as given (their leaves may be traced):
      give them ``with_start_ramp(scene, loading)[:2]`` for the same start.
    """

    current_speed: Callable | None = None
    motions: tuple = ()
    ramp: float | None = None
    winches: tuple = ()


__all__ = [
    "AbstractHistory", "AbstractMotion", "Constant", "Ramp", "Step", "Oscillation", "Towing", "SpeedTable", "Harmonic",
    "Sum",
    "PrescribedMotion", "Winch", "Loading", "envelope",
]
