"""Waves in water of finite or infinite depth: the water's elevation, velocity and acceleration at a point and a
time, for the drag (relative velocity, book 4.272-4.276) and the force of inertia (the water's acceleration γ_h
of 4.265) in dynamics. :class:`Airy`, regular linear waves (below); :class:`Stokes2`, regular second-order
Stokes waves (FEMNET's ``wave_model 2``); :class:`Stokes3`, third-order ones in deep water (``wave_model 3``);
:class:`Irregular` and :func:`sea_state`, an irregular sea as a sum of linear components drawn from a spectrum
(:mod:`jaxnet.water.spectra`). Each takes a ``ramp`` over which a dynamic run grows it in from still water
(:attr:`jaxnet.water.forcing.Loading.ramp`).

The book gives no wave model (γ_h and the water's velocity c_i are inputs there); this is textbook theory.
Units: m, s, rad; velocities m/s, accelerations m/s². What follows is :class:`Airy`'s first-order theory, on
which the others build.

Conventions. ``up`` is the unit vertical (z along it, up positive); z is measured from the mean free
surface, z = up·x - surface_level, so z = 0 at the mean surface and z = -h at the sea bed (h the depth,
m). The waves travel along the horizontal unit vector e (``direction``, with its vertical part removed and
normalised); the phase is

    θ = k e·x - ω t + phase,        ω = 2π/T (rad/s),   k the wavenumber (rad/m),

and a = H/2 is the amplitude (H the height, crest to trough). With s = z + h the height above the bed:

    velocity potential   Φ = (g a / ω) cosh(k s)/cosh(k h) sin θ                      (m²/s)
    elevation            η = -(1/g) ∂Φ/∂t at z = 0 = a cos θ                             (m)
    velocity             u = ∇Φ = a ω [cosh(k s)/sinh(k h) cos θ e + sinh(k s)/sinh(k h) sin θ up]
    acceleration         ∂u/∂t = a ω² [cosh(k s)/sinh(k h) sin θ e - sinh(k s)/sinh(k h) cos θ up]
    velocity gradient    ∂u/∂x = a ω k [e (sinh(k s) cos θ up - cosh(k s) sin θ e)^T
                                        + up (cosh(k s) sin θ up + sinh(k s) cos θ e)^T] / sinh(k h)
    dispersion           ω² = g k tanh(k h)

(g a k/ω · 1/cosh(kh) = a ω/sinh(kh) by the dispersion relation). The acceleration is the *local*
acceleration ∂u/∂t: the convective part (u·∇)u is of second order in a and linear theory drops it, as it
drops the difference between the mean and the instantaneous surface. This is the γ_h that the dynamics
puts in 4.265.

Limits. Deep water (k h → ∞, ``depth = inf``): k = ω²/g, the ratios become e^{kz}: circular orbits of
radius a e^{kz}. Shallow water (k h → 0): k → ω/√(g h), the celerity ω/k → √(g h), the horizontal
velocity a √(g/h) cos θ is uniform over depth and the vertical one falls linearly to 0 at the bed.

Evaluation without overflow. cosh(ks)/sinh(kh) and sinh(ks)/sinh(kh) overflow as written for kh > 710
and are 0/0-prone for kh → 0, so they are computed as

    cosh(k s)/sinh(k h) = e^{kz} (1 + e^{-2ks}) / (1 - e^{-2kh}),
    sinh(k s)/sinh(k h) = e^{kz} (1 - e^{-2ks}) / (1 - e^{-2kh}),

with 1 - e^{-2q} as -expm1(-2q) (exact for small q). All exponents are <= 0 in the water. Deep water
(h = inf) takes the exact limit e^{kz} with the depth replaced by a harmless 1 in the discarded branch (the
"double where": no inf·0 in any derivative).

Outside the water column. Linear theory defines the field for -h <= z <= 0 only. Points above the mean
surface (z > 0, under a crest, or a float or collar in the air) get the kinematics at z = 0: *constant
extrapolation*, the choice of many net and Morison codes. Why: it is continuous in z (no jump of the drag
when a node crosses the mean level), it does not blow up like the exponential extrapolation e^{kz} under
crests, its derivative in z is exactly 0 above (finite everywhere), and it needs no elevation inside the
kinematics as Wheeler stretching would (which mixes in η(x, t), makes ∂u/∂x depend on the surface slope
and changes the field below the surface, a refinement beyond first order). Whether an emerged node feels
any water at all is the free surface's business, not the waves'. Points below the bed (z < -h) get the
bed values. Both clamps are written with ``where`` so that the derivative in z is that of linear theory
inside, exactly 0 outside, and never NaN.

Differentiability. Every function is a pure jnp function, jittable, vmappable, differentiable in position,
time and the wave's parameters, float64. A zero height gives exactly zero kinematics and finite
derivatives (the field is linear in a). :func:`wavenumber` solves the dispersion relation by Newton's
method from Fenton & McKee's explicit approximation (error < 2 %, so five steps reach rounding) and
differentiates by the implicit function theorem (a ``jax.custom_jvp``): derivatives of every order are
exact, not those of the truncated iteration.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import geometry
from jaxnet.water import forcing, spectra

#: Newton steps on y tanh y = x after Fenton & McKee's start: its relative error is below 2 %, Newton
#: squares it each step, so 4 steps give < 1e-16; one more is a margin.
_NEWTON_STEPS = 5


@jax.custom_jvp
def _dimensionless_wavenumber(x):
    """y = k h solving y tanh(y) = x = ω² h / g (both dimensionless, x > 0)."""
    # Fenton & McKee (1990): y ≈ x coth(x^{3/4})^{2/3}, exact in both limits (y → √x, y → x)
    y = x / jnp.tanh(x**0.75) ** (2.0 / 3.0)
    for _ in range(_NEWTON_STEPS):  # unrolled: traceable, fixed cost
        tanh = jnp.tanh(y)
        # y sech²y written as y (1 - tanh²) loses nothing: it only matters where tanh is not 1
        y = y - (y * tanh - x) / (tanh + y * (1.0 - tanh**2))
    return y


@_dimensionless_wavenumber.defjvp
def _dimensionless_wavenumber_jvp(primals, tangents):
    # implicit function theorem on f(y, x) = y tanh y - x = 0: dy/dx = 1 / (tanh y + y sech² y); the rule
    # is itself differentiable (y inside is the custom function), so higher derivatives are exact too
    (x,), (dx,) = primals, tangents
    y = _dimensionless_wavenumber(x)
    tanh = jnp.tanh(y)
    return y, dx / (tanh + y * (1.0 - tanh**2))


def wavenumber(period, depth, gravity=9.81):
    """Wavenumber k (rad/m) of linear waves of period T (s) in water of depth h (m), g in m/s².

    Solves ω² = g k tanh(k h) with ω = 2π/T; ``depth = inf`` gives the deep-water k = ω²/g exactly.
    Works for every k h (tested from 1e-3 to 50 to 1e-12 relative residual); jittable, vmappable, and
    differentiable in period, depth and gravity through the implicit function theorem (exact derivatives).
    A period of inf (no wave) gives k = 0.
    """
    period = jnp.asarray(period, dtype=float)
    depth = jnp.asarray(depth, dtype=float)
    omega = 2.0 * jnp.pi / period
    deep_k = omega**2 / gravity
    # double where: the finite-depth branch never sees h = inf (inf·0 would poison its derivatives)
    deep = jnp.isinf(depth)
    h = jnp.where(deep, 1.0, depth)
    x = deep_k * h
    still = x <= 0.0  # ω = 0: no wave, k = 0 (and no 0/0 in the start value)
    y = _dimensionless_wavenumber(jnp.where(still, 1.0, x))
    return jnp.where(deep, deep_k, jnp.where(still, 0.0, y / h))


def _is_concrete(value):
    """True when ``value`` holds numbers (not a tracer inside jit/grad): only then can it be validated."""
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(value))


def _horizontal_unit(direction, up):
    """Unit vector (3,) of ``direction`` with its component along ``up`` removed (zero if none is left)."""
    horizontal = direction - jnp.dot(direction, up) * up
    length = geometry.safe_norm(horizontal)
    return horizontal * jnp.where(length > 0.0, 1.0 / jnp.where(length > 0.0, length, 1.0), 0.0)


def depth_ratios(k, z, depth):
    """(cosh(ks)/sinh(kh), sinh(ks)/sinh(kh)) of linear waves of wavenumber k (rad/m) at heights z (m) above
    the mean surface (s = z + h), z clamped to [-h, 0] (constant extrapolation above the surface and below
    the bed, slope exactly 0 there), written without overflow (the module docstring); ``depth`` h (m) may be
    inf (deep water: both e^{kz}). k and z broadcast together."""
    deep = jnp.isinf(depth)
    h = jnp.where(deep, 1.0, depth)  # double where: the finite branch never sees inf
    z = jnp.where(z > 0.0, 0.0, z)
    z = jnp.where(deep, z, jnp.where(z < -h, -h, z))
    surface_decay = jnp.exp(k * z)
    # 1 - e^{-2ks} and 1 - e^{-2kh} with expm1: exact as k s, k h → 0 (shallow water, near the bed)
    s = z + h
    bed_factor = jnp.where(deep, 1.0, -jnp.expm1(-2.0 * k * s))
    denominator = jnp.where(deep, 1.0, -jnp.expm1(-2.0 * k * h))
    return surface_decay * (2.0 - bed_factor) / denominator, surface_decay * bed_factor / denominator


class Airy(eqx.Module):
    """Regular linear (Airy) waves (a pytree: its numbers can be traced and differentiated).

    Args:
      height: H, crest to trough (m), >= 0 (0: still water, zero kinematics).
      period: T (s), > 0.
      direction: (3,) direction of propagation; its component along ``up`` is removed and it is
        normalised (stored as the horizontal unit vector e).
      depth: h, water depth from the mean surface to the sea bed (m), > 0; ``inf`` for deep water.
      phase: phase (rad) added to θ = k e·x - ω t; η = H/2 cos θ, so phase 0 puts a crest at x = 0, t = 0.
      surface_level: height of the mean free surface along ``up`` (m).
      gravity: g (m/s²).
      up: (3,) the vertical (normalised), z along it.
      ramp: time (s) over which the waves grow in from still water at t = 0 (:func:`jaxnet.water.forcing.envelope`:
        elevation and velocity times e(t), the acceleration gaining de/dt times the velocity); 0 (default):
        the textbook field at every t. A dynamic run sets it (:attr:`jaxnet.water.forcing.Loading.ramp`).
    Raises ValueError naming the parameter for a negative height or ramp, a non-positive period, depth or
    gravity, NaN, a wrong shape or a vertical (or zero) direction, when the values are concrete.
    """

    height: jax.Array
    period: jax.Array
    direction: jax.Array
    depth: jax.Array
    phase: jax.Array
    surface_level: jax.Array
    gravity: jax.Array
    up: jax.Array
    ramp: jax.Array

    def __init__(self, height, period, direction=(1.0, 0.0, 0.0), depth=float("inf"), phase=0.0,
                 surface_level=0.0, gravity=9.81, up=(0.0, 0.0, 1.0), ramp=0.0):
        scalars = dict(height=height, period=period, depth=depth, phase=phase, surface_level=surface_level,
                       gravity=gravity, ramp=ramp)
        vectors = dict(direction=direction, up=up)
        for name, value in {**scalars, **vectors}.items():
            if not _is_concrete(value):
                continue
            array = np.asarray(value, dtype=float)
            expected = (3,) if name in vectors else ()
            if array.shape != expected:
                raise ValueError(f"Airy: {name} must have shape {expected}, got {array.shape}")
            if np.isnan(array).any():
                raise ValueError(f"Airy: {name} is NaN")
            finite_required = name != "depth"
            if finite_required and not np.isfinite(array).all():
                raise ValueError(f"Airy: {name} must be finite, got {value!r}")
        checks = (("height", lambda v: v >= 0.0, ">= 0"), ("period", lambda v: v > 0.0, "> 0"),
                  ("depth", lambda v: v > 0.0, "> 0 (inf for deep water)"), ("gravity", lambda v: v > 0.0, "> 0"),
                  ("ramp", lambda v: v >= 0.0, ">= 0 (s)"))
        for name, ok, what in checks:
            value = scalars[name]
            if _is_concrete(value) and not ok(float(value)):
                raise ValueError(f"Airy: {name} must be {what}, got {value!r}")
        if _is_concrete((up, direction)):
            # numbers: normalise with numpy (no eager jax operations to compile) and check
            up, direction = np.asarray(up, dtype=float), np.asarray(direction, dtype=float)
            if not np.linalg.norm(up) > 0.0:
                raise ValueError("Airy: up must be a non-zero vector")
            up = up / np.linalg.norm(up)
            horizontal = direction - np.dot(direction, up) * up
            if not np.linalg.norm(horizontal) > 1e-12 * np.linalg.norm(direction):
                raise ValueError(f"Airy: direction must have a horizontal component (not zero nor along up), "
                                 f"got {direction.tolist()}")
            up, direction = jnp.asarray(up), jnp.asarray(horizontal / np.linalg.norm(horizontal))
        else:
            up = jnp.asarray(up, dtype=float)
            up = up / geometry.safe_norm(up)
            direction = _horizontal_unit(jnp.asarray(direction, dtype=float), up)
        self.height = jnp.asarray(height, dtype=float)
        self.period = jnp.asarray(period, dtype=float)
        self.direction = direction
        self.depth = jnp.asarray(depth, dtype=float)
        self.phase = jnp.asarray(phase, dtype=float)
        self.surface_level = jnp.asarray(surface_level, dtype=float)
        self.gravity = jnp.asarray(gravity, dtype=float)
        self.up = up
        self.ramp = jnp.asarray(ramp, dtype=float)

    # -- derived quantities ------------------------------------------------------------------------------

    @property
    def angular_frequency(self):
        """ω = 2π/T (rad/s)."""
        return 2.0 * jnp.pi / self.period

    @property
    def wavenumber(self):
        """k (rad/m), from the dispersion relation (:func:`wavenumber`)."""
        return wavenumber(self.period, self.depth, self.gravity)

    @property
    def wavelength(self):
        """L = 2π/k (m)."""
        return 2.0 * jnp.pi / self.wavenumber

    @property
    def celerity(self):
        """Phase speed c = ω/k (m/s)."""
        return self.angular_frequency / self.wavenumber

    @property
    def characteristic_period(self):
        """T (s): what a dynamic run grows these waves in over by default (:attr:`jaxnet.water.forcing.Loading.ramp`)."""
        return self.period

    # -- kinematics at points ----------------------------------------------------------------------------

    def _phase(self, x, t):
        """θ = k e·x - ω t + phase (rad) at points x (..., 3) and time t."""
        return self.wavenumber * (x @ self.direction) - self.angular_frequency * t + self.phase

    def _depth_ratios(self, x):
        """(cosh(ks)/sinh(kh), sinh(ks)/sinh(kh)) at points x (..., 3), z clamped to [-h, 0]."""
        return depth_ratios(self.wavenumber, x @ self.up - self.surface_level, self.depth)

    def elevation(self, x, t):
        """Elevation η (m) of the free surface above its mean level, at the horizontal position of points
        x (..., 3) (m) and time t (s): η = H/2 cos θ. Shape (...)."""
        x = jnp.asarray(x, dtype=float)
        return 0.5 * self.height * forcing.envelope(t, self.ramp)[0] * jnp.cos(self._phase(x, t))

    def velocity(self, x, t):
        """Orbital velocity (..., 3) (m/s) of the water at points x (..., 3) (m), time t (s)."""
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        cosh_ratio, sinh_ratio = self._depth_ratios(x)
        amplitude = 0.5 * self.height * self.angular_frequency * forcing.envelope(t, self.ramp)[0]
        horizontal = amplitude * cosh_ratio * jnp.cos(theta)
        vertical = amplitude * sinh_ratio * jnp.sin(theta)
        return horizontal[..., None] * self.direction + vertical[..., None] * self.up

    def velocity_gradient(self, x, t):
        """Gradient ∂u/∂x (..., 3, 3) (1/s) of the orbital velocity at points x (..., 3) (m), time t (s), entry
        [..., m, n] = ∂u_m/∂x_n: what the drag stiffness of a moving net needs (the water's velocity at a
        vertex changes as the vertex moves; :mod:`jaxnet.closed_form.drag`). Written out, not by autodiff:
        with u = A [C cos θ e + S sin θ up], θ = k e·x - ω t + phase, and along the vertical C' = k S, S' = k C
        (C, S the ratios cosh(ks)/sinh(kh), sinh(ks)/sinh(kh); deep water: both e^{kz}),

            ∂u/∂x = A k [ e (S cos θ m up - C sin θ e)^T + up (C sin θ m up + S cos θ e)^T ],

        m = 1 where z lies between the bed and the mean surface, 0 where :meth:`velocity` holds it constant
        (above the surface, below the bed: the same ``where`` as there, so the same derivative as jacfwd's).
        """
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        cosh_ratio, sinh_ratio = self._depth_ratios(x)
        z = x @ self.up - self.surface_level
        inside = ((z <= 0.0) & (z >= -self.depth)).astype(x.dtype)  # depth inf: no bed
        scale = 0.5 * self.height * self.angular_frequency * self.wavenumber * forcing.envelope(t, self.ramp)[0]
        cos, sin = jnp.cos(theta), jnp.sin(theta)
        e, up = self.direction, self.up
        # d(horizontal)/dx and d(vertical)/dx, (..., 3) each
        d_horizontal = scale * ((sinh_ratio * cos * inside)[..., None] * up - (cosh_ratio * sin)[..., None] * e)
        d_vertical = scale * ((cosh_ratio * sin * inside)[..., None] * up + (sinh_ratio * cos)[..., None] * e)
        return e[:, None] * d_horizontal[..., None, :] + up[:, None] * d_vertical[..., None, :]

    def acceleration(self, x, t):
        """Local acceleration ∂u/∂t (..., 3) (m/s²) of the water at points x (..., 3) (m), time t (s): the
        linear-theory γ_h (the convective (u·∇)u, second order in H, is left out). During the ramp it is
        e ∂u/∂t + (de/dt) u: the time derivative of the ramped velocity."""
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        cosh_ratio, sinh_ratio = self._depth_ratios(x)
        grow, grow_rate = forcing.envelope(t, self.ramp)
        amplitude = 0.5 * self.height * self.angular_frequency
        # d/dt of e a ω [C cos θ e + S sin θ up], θ = ... - ω t
        omega, cos, sin = self.angular_frequency, jnp.cos(theta), jnp.sin(theta)
        horizontal = amplitude * cosh_ratio * (grow * omega * sin + grow_rate * cos)
        vertical = amplitude * sinh_ratio * (-grow * omega * cos + grow_rate * sin)
        return horizontal[..., None] * self.direction + vertical[..., None] * self.up


def _time_derivative(velocity, x, t):
    """∂u/∂t (..., 3) of ``velocity(x, t)`` at points x (..., 3) and time t: forward-mode autodiff."""
    x = jnp.asarray(x, dtype=float)
    t = jnp.asarray(t, dtype=float)
    return jax.jvp(lambda s: velocity(x, s), (t,), (jnp.ones_like(t),))[1]


def _gradient(velocity, x, t):
    """∂u/∂x (..., 3, 3) of ``velocity(x, t)``, entry [..., m, n] = ∂u_m/∂x_n: forward-mode autodiff per point."""
    x = jnp.asarray(x, dtype=float)
    gradient = jax.vmap(jax.jacfwd(lambda p: velocity(p, t)))(x.reshape(-1, 3))
    return gradient.reshape(x.shape[:-1] + (3, 3))


class Stokes2(Airy):
    """Regular second-order Stokes waves in water of finite or infinite depth: FEMNET's ``input wave_model 2``
    (a pytree; the same parameters as :class:`Airy`, whose first-order field it adds to).

    With a = H/2, θ = k e·x - ω t + phase, s = z + h, and k from the linear dispersion relation (at second
    order the frequency is unchanged; Dean & Dalrymple, *Water wave mechanics*, 1991, ch. 11):

        η = a cos θ + (k a²/4) (3 - tanh² kh)/tanh³ kh · cos 2θ
        u = a ω cosh(ks)/sinh(kh) cos θ e + a ω sinh(ks)/sinh(kh) sin θ up
            + (3/4) a² ω k [cosh(2ks) cos 2θ e + sinh(2ks) sin 2θ up] / sinh⁴(kh)

    the potential Φ = a ω/k cosh(ks)/sinh(kh) sin θ + (3/8) a² ω cosh(2ks)/sinh⁴(kh) sin 2θ, whose velocity this
    is (divergence-free, irrotational, w = 0 at the bed: the tests check them). FEMNET's kinematics
    (``vitesse_houle``/``acceleration_houle``) and elevation are these. In deep water the second-order velocity
    vanishes (1/sinh⁴ → 0) and η's second harmonic is k a²/2 cos 2θ. The factor 2 cosh(kh)/sinh³(kh) =
    8 E (1 + E)/(1 - E)³ with E = e^{-2kh} keeps it finite there. Valid where the second harmonic stays small
    (Ursell number H L²/h³ below about 25; in shallow water 1/sinh⁴ grows without bound).

    Above the mean surface the kinematics are held at their z = 0 values, as :class:`Airy`'s (FEMNET evaluates
    the series above it as written). The local acceleration and the velocity gradient are the exact
    derivatives of this velocity (forward-mode autodiff); the ramp acts as :class:`Airy`'s.
    """

    def _second_order(self, z):
        """(cosh(2ks), sinh(2ks)) / sinh⁴(kh) at heights z, clamped as :func:`depth_ratios` clamps."""
        k = self.wavenumber
        cosh2, sinh2 = depth_ratios(2.0 * k, z, self.depth)  # cosh(2ks)/sinh(2kh), sinh(2ks)/sinh(2kh)
        deep = jnp.isinf(self.depth)
        e = jnp.where(deep, 0.0, jnp.exp(-2.0 * k * jnp.where(deep, 1.0, self.depth)))
        factor = 8.0 * e * (1.0 + e) / (1.0 - e) ** 3  # sinh(2kh)/sinh⁴(kh) = 2 cosh(kh)/sinh³(kh)
        return cosh2 * factor, sinh2 * factor

    def elevation(self, x, t):
        """Elevation η (m) of the free surface above its mean level at points x (..., 3), time t (s)."""
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        a, k = 0.5 * self.height, self.wavenumber
        deep = jnp.isinf(self.depth)
        tanh = jnp.where(deep, 1.0, jnp.tanh(k * jnp.where(deep, 1.0, self.depth)))
        second = k * a**2 / 4.0 * (3.0 - tanh**2) / tanh**3
        return forcing.envelope(t, self.ramp)[0] * (a * jnp.cos(theta) + second * jnp.cos(2.0 * theta))

    def velocity(self, x, t):
        """Orbital velocity (..., 3) (m/s) of the water at points x (..., 3) (m), time t (s)."""
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        z = x @ self.up - self.surface_level
        cosh2, sinh2 = self._second_order(z)
        a, k, omega = 0.5 * self.height, self.wavenumber, self.angular_frequency
        second = 0.75 * a**2 * omega * k * forcing.envelope(t, self.ramp)[0]
        horizontal = second * cosh2 * jnp.cos(2.0 * theta)
        vertical = second * sinh2 * jnp.sin(2.0 * theta)
        return Airy.velocity(self, x, t) + horizontal[..., None] * self.direction + vertical[..., None] * self.up

    def acceleration(self, x, t):
        """Local acceleration ∂u/∂t (..., 3) (m/s²) at points x (..., 3) (m), time t (s)."""
        return _time_derivative(self.velocity, x, t)

    def velocity_gradient(self, x, t):
        """Gradient ∂u/∂x (..., 3, 3) (1/s), entry [..., m, n] = ∂u_m/∂x_n, at points x (..., 3) (m), time t (s)."""
        return _gradient(self.velocity, x, t)


class Stokes3(Airy):
    """Regular third-order Stokes waves in deep water: FEMNET's ``input wave_model 3`` (a pytree; the parameters
    of :class:`Airy`, its ``depth`` not used: the theory is the deep-water one, as FEMNET's, whatever the depth).

    With a = H/2 (as FEMNET takes it), ε = k a, θ = k e·x - ω t + phase (the series of the Stokes wave in
    deep water to third order, e.g. Whitham, *Linear and nonlinear waves*, 1974, §13.13; FEMNET's
    ``vitesse_houle``, ``acceleration_houle`` and elevation):

        ω = √(g k) (1 + ε²/2)                          (amplitude dispersion: k from T by Newton's method)
        η = a [(1 - ε²/16) cos θ + (ε/2) cos 2θ + (3ε²/8) cos 3θ]
        Φ = a √(g/k) e^{kz} sin θ,    u = a √(g k) e^{kz} [cos θ e + sin θ up]

    In deep water the potential has no second or third harmonic at this order: the waves are steeper than
    Airy's (crest above trough H (1 + 5ε²/16)) and faster (their k is smaller for a given T), their
    velocity profile the first-order one with amplitude a √(g k), not a ω. Above the mean surface the
    kinematics are held at their z = 0 values, as :class:`Airy`'s. The local acceleration and the velocity
    gradient are the exact derivatives of this velocity (forward-mode autodiff); the ramp acts as Airy's.
    Valid for small steepness (ε below about 0.3; the series diverges near the limiting wave, H/L = 0.142).
    """

    @property
    def wavenumber(self):
        """k (rad/m) of ω = √(g k) (1 + (k a)²/2), a = H/2: Newton's method from the linear k = ω²/g (which it
        reaches at H = 0); a fixed number of iterations, differentiable."""
        omega, g, a = self.angular_frequency, self.gravity, 0.5 * self.height

        def newton(_, k):
            root = jnp.sqrt(g * k)
            f = root * (1.0 + 0.5 * (a * k) ** 2) - omega
            df = 0.5 * root / k * (1.0 + 0.5 * (a * k) ** 2) + root * a**2 * k
            return k - f / df

        return jax.lax.fori_loop(0, 30, newton, omega**2 / g)

    def elevation(self, x, t):
        """Elevation η (m) of the free surface above its mean level at points x (..., 3), time t (s)."""
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        a = 0.5 * self.height
        eps = self.wavenumber * a
        series = ((1.0 - eps**2 / 16.0) * jnp.cos(theta) + 0.5 * eps * jnp.cos(2.0 * theta)
                  + 0.375 * eps**2 * jnp.cos(3.0 * theta))
        return forcing.envelope(t, self.ramp)[0] * a * series

    def velocity(self, x, t):
        """Orbital velocity (..., 3) (m/s) of the water at points x (..., 3) (m), time t (s)."""
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        k = self.wavenumber
        decay = jnp.exp(k * jnp.minimum(x @ self.up - self.surface_level, 0.0))
        amplitude = 0.5 * self.height * jnp.sqrt(self.gravity * k) * forcing.envelope(t, self.ramp)[0] * decay
        horizontal, vertical = amplitude * jnp.cos(theta), amplitude * jnp.sin(theta)
        return horizontal[..., None] * self.direction + vertical[..., None] * self.up

    def acceleration(self, x, t):
        """Local acceleration ∂u/∂t (..., 3) (m/s²) at points x (..., 3) (m), time t (s)."""
        return _time_derivative(self.velocity, x, t)

    def velocity_gradient(self, x, t):
        """Gradient ∂u/∂x (..., 3, 3) (1/s), entry [..., m, n] = ∂u_m/∂x_n, at points x (..., 3) (m), time t (s)."""
        return _gradient(self.velocity, x, t)


class Irregular(eqx.Module):
    """An irregular sea: the sum of linear waves, each a component of :class:`Airy`'s theory with its own
    amplitude a_i, angular frequency ω_i, heading e_i and phase φ_i (a pytree: its numbers can be traced and
    differentiated). Build one from a spectrum with :func:`sea_state`; the components come from
    :func:`jaxnet.water.spectra.components`.

        η = e(t) Σ a_i cos θ_i,    θ_i = k_i e_i·x - ω_i t + φ_i,    ω_i² = g k_i tanh(k_i h)
        u = e(t) Σ a_i ω_i [C_i(z*) cos θ_i e_i + S_i(z*) sin θ_i up]

    (C_i, S_i: :func:`depth_ratios` of k_i; e(t) the ramp's envelope). z* is where the linear profile is read
    at a point of height z above the mean surface:

    * ``stretching="wheeler"`` (default; Wheeler 1970): z* = h (z - η)/(h + η) (deep water: z - η), which
      maps the instantaneous surface η to 0 and the bed to itself. Linear theory's exponential profile taken
      up to z = η under a crest overestimates the velocity there, and stopping it at the mean level misses
      the crest; for the broad spectra of irregular seas Wheeler's rule is the usual choice (DNV-RP-C205
      3.2.3). Points above the instantaneous surface get the kinematics at it.
    * ``stretching="none"``: z* = z, constant above the mean surface: :class:`Airy`'s rule, so that one
      component is exactly :class:`Airy`.

    The local acceleration ∂u/∂t at a fixed point and the gradient ∂u/∂x are the exact derivatives of this
    u (forward-mode autodiff: with stretching, u depends on t and x through η too).

    Cost: every evaluation sums all N components at every point: N × points work and memory.

    Args (arrays of one length N): amplitude a_i (m), angular_frequency ω_i (rad/s), heading (N, 3) the
    components' directions (their vertical part removed, normalised), phase φ_i (rad); depth h (m, inf for
    deep water); surface_level (m); gravity (m/s²); up (3,); stretching; ramp (s, as :class:`Airy`'s);
    peak_period: the sea's Tp (s), a run's default ramp.
    """

    amplitude: jax.Array
    angular_frequency: jax.Array
    direction: jax.Array
    phase: jax.Array
    depth: jax.Array
    surface_level: jax.Array
    gravity: jax.Array
    up: jax.Array
    ramp: jax.Array
    peak_period: jax.Array
    stretching: str = eqx.field(static=True, default="wheeler")

    def __init__(self, amplitude, angular_frequency, heading, phase, depth=float("inf"), surface_level=0.0,
                 gravity=9.81, up=(0.0, 0.0, 1.0), stretching="wheeler", ramp=0.0, peak_period=None):
        if stretching not in ("wheeler", "none"):
            raise ValueError(f"Irregular: stretching must be 'wheeler' or 'none', got {stretching!r}")
        arrays = dict(amplitude=amplitude, angular_frequency=angular_frequency, phase=phase)
        if _is_concrete((arrays, heading, depth, ramp)):
            n = np.shape(amplitude)
            for name, value in {**arrays, "heading": heading}.items():
                array = np.asarray(value, dtype=float)
                expected = n + (3,) if name == "heading" else n
                if array.ndim != len(expected) or array.shape != expected or len(n) != 1:
                    raise ValueError(f"Irregular: {name} must have shape {expected} (N components), got {array.shape}")
                if not np.isfinite(array).all():
                    raise ValueError(f"Irregular: {name} must be finite, got {array.tolist()}")
            if (np.asarray(amplitude) < 0).any() or not (np.asarray(angular_frequency) > 0).all():
                raise ValueError("Irregular: amplitudes must be >= 0 m and angular frequencies > 0 rad/s")
            if not float(depth) > 0 or not float(ramp) >= 0:
                raise ValueError(f"Irregular: depth must be > 0 (inf for deep water) and ramp >= 0 s, got {depth!r}, "
                                 f"{ramp!r}")
        up = jnp.asarray(up, dtype=float)
        self.up = up / geometry.safe_norm(up)
        self.direction = jax.vmap(lambda d: _horizontal_unit(d, self.up))(jnp.asarray(heading, dtype=float))
        self.amplitude = jnp.asarray(amplitude, dtype=float)
        self.angular_frequency = jnp.asarray(angular_frequency, dtype=float)
        self.phase = jnp.asarray(phase, dtype=float)
        self.depth = jnp.asarray(depth, dtype=float)
        self.surface_level = jnp.asarray(surface_level, dtype=float)
        self.gravity = jnp.asarray(gravity, dtype=float)
        self.ramp = jnp.asarray(ramp, dtype=float)
        if peak_period is None:  # the period of the largest component
            peak_period = 2.0 * jnp.pi / self.angular_frequency[jnp.argmax(self.amplitude)]
        self.peak_period = jnp.asarray(peak_period, dtype=float)
        self.stretching = stretching

    @property
    def wavenumber(self):
        """k_i (N,) (rad/m), from the dispersion relation (:func:`wavenumber`)."""
        return wavenumber(2.0 * jnp.pi / self.angular_frequency, self.depth, self.gravity)

    @property
    def characteristic_period(self):
        """Tp (s): what a dynamic run grows this sea in over by default (:attr:`jaxnet.water.forcing.Loading.ramp`)."""
        return self.peak_period

    def _phase(self, x, t):
        """θ_i (..., N) at points x (..., 3) and time t."""
        return self.wavenumber * (x @ self.direction.T) - self.angular_frequency * t + self.phase

    def elevation(self, x, t):
        """Elevation η (m) of the free surface above its mean level at the horizontal position of points x
        (..., 3) (m), time t (s). Shape (...)."""
        x = jnp.asarray(x, dtype=float)
        return forcing.envelope(t, self.ramp)[0] * (jnp.cos(self._phase(x, t)) @ self.amplitude)

    def velocity(self, x, t):
        """Orbital velocity (..., 3) (m/s) of the water at points x (..., 3) (m), time t (s)."""
        x = jnp.asarray(x, dtype=float)
        theta = self._phase(x, t)
        z = x @ self.up - self.surface_level
        grow = forcing.envelope(t, self.ramp)[0]
        if self.stretching == "wheeler":
            eta = grow * (jnp.cos(theta) @ self.amplitude)
            deep = jnp.isinf(self.depth)
            h = jnp.where(deep, 1.0, self.depth)
            # above the instantaneous surface z* > 0: depth_ratios holds the surface's kinematics there
            z = jnp.where(deep, z - eta, h * (z - eta) / jnp.maximum(h + eta, 1e-9 * h))
        cosh_ratio, sinh_ratio = depth_ratios(self.wavenumber, z[..., None], self.depth)
        scale = grow * self.amplitude * self.angular_frequency
        horizontal = (scale * cosh_ratio * jnp.cos(theta)) @ self.direction
        vertical = jnp.sum(scale * sinh_ratio * jnp.sin(theta), axis=-1)
        return horizontal + vertical[..., None] * self.up

    def acceleration(self, x, t):
        """Local acceleration ∂u/∂t (..., 3) (m/s²) of the water at points x (..., 3) (m), time t (s): the
        exact time derivative of :meth:`velocity` at a fixed point (linear theory's γ_h per component, plus
        the stretching's and the ramp's parts)."""
        x = jnp.asarray(x, dtype=float)
        t = jnp.asarray(t, dtype=float)
        return jax.jvp(lambda s: self.velocity(x, s), (t,), (jnp.ones_like(t),))[1]

    def velocity_gradient(self, x, t):
        """Gradient ∂u/∂x (..., 3, 3) (1/s), entry [..., m, n] = ∂u_m/∂x_n, at points x (..., 3) (m), time t (s):
        the exact derivative of :meth:`velocity` (what the drag stiffness of a moving net needs)."""
        x = jnp.asarray(x, dtype=float)
        flat = x.reshape(-1, 3)
        gradient = jax.vmap(jax.jacfwd(lambda p: self.velocity(p, t)))(flat)
        return gradient.reshape(x.shape[:-1] + (3, 3))


def sea_state(hs, tp, direction=(1.0, 0.0, 0.0), spectrum="jonswap", gamma=None, spreading=None, components=200,
              band=spectra.BAND, seed=0, depth=float("inf"), surface_level=0.0, gravity=9.81, up=(0.0, 0.0, 1.0),
              stretching="wheeler"):
    """An irregular sea of significant height ``hs`` (m) and peak period ``tp`` (s) travelling along the
    horizontal ``direction``: an :class:`Irregular` of ``components`` linear waves realised from a JONSWAP
    (``gamma``: its peak enhancement, None for DNV's from Hs and Tp) or Pierson-Moskowitz spectrum with the
    generator's ``seed`` (:func:`jaxnet.water.spectra.components`: the same seed, the same sea). ``spreading``: None
    for a long-crested sea, else the exponent n of DNV's cos^n spreading about ``direction`` (2-4 for a wind
    sea): a short-crested one. ``band``: the frequencies covered, in multiples of the peak's. ``depth`` (m, inf
    for deep water), ``surface_level`` (m), ``gravity``, ``up``, ``stretching``: as :class:`Irregular`'s. The
    record repeats after 2π/Δω = components × Tp / (band[1] - band[0]) seconds (444 s for the defaults and
    Tp = 10 s)."""
    amplitude, omega, phase, angle = spectra.components(hs, tp, spectrum, gamma, components, band, seed, spreading)
    up_unit = np.asarray(up, dtype=float) / np.linalg.norm(up)
    mean = np.asarray(direction, dtype=float)
    mean = mean - np.dot(mean, up_unit) * up_unit
    if not np.linalg.norm(mean) > 0:
        raise ValueError(f"sea state: direction must have a horizontal component, got {list(direction)}")
    mean = mean / np.linalg.norm(mean)
    side = np.cross(up_unit, mean)
    heading = np.cos(angle)[:, None] * mean + np.sin(angle)[:, None] * side
    return Irregular(amplitude, omega, heading, phase, depth=depth, surface_level=surface_level, gravity=gravity, up=up,
                     stretching=stretching, peak_period=tp)


__all__ = ["Airy", "Stokes2", "Stokes3", "Irregular", "sea_state", "wavenumber", "depth_ratios"]
