"""Wave spectra of irregular seas: Pierson-Moskowitz and JONSWAP, the directional spreading, and the
realisation of a sea state as a sum of linear wave components (what :class:`jaxnet.water.waves.Irregular` moves).

Spectra (DNV-RP-C205, *Environmental conditions and environmental loads*, section 3.5), as one-sided
spectral densities of the free surface's elevation in angular frequency ω (rad/s), S(ω) in m² s/rad, for a
significant wave height Hs (m) and a peak period Tp (s), ω_p = 2π/Tp:

    Pierson-Moskowitz   S_PM(ω) = 5/16 Hs² ω_p⁴ ω⁻⁵ exp(-5/4 (ω/ω_p)⁻⁴)                       (3.5.5.1)
    JONSWAP             S_J(ω)  = A_γ S_PM(ω) γ^exp(-½ ((ω - ω_p)/(σ ω_p))²),   A_γ = 1 - 0.287 ln γ (3.5.5.2)

with σ = σ_a = 0.07 for ω <= ω_p and σ_b = 0.09 above, γ the peak enhancement factor (1 gives PM).
Their moments m_n = ∫ ωⁿ S dω: for PM, with q = 5/4 (ω_p/ω)⁴, m_n = Hs²/16 ω_pⁿ (5/4)^(n/4) Γ(1 - n/4),
so m0 = Hs²/16 exactly (Hs = 4 √m0), the mean period T1 = 2π m0/m1 = 0.7718 Tp and the zero-crossing
period Tz = 2π √(m0/m2) = 0.7104 Tp. For JONSWAP A_γ is DNV's approximate normalisation: m0 differs from
Hs²/16 by -0.2 % at γ = 2, +0.24 % at 3.3 and -1.8 % at 7 (:func:`spectral_moment` on a fine grid).
:func:`jonswap_gamma` is DNV's γ from Hs and Tp (3.5.5.5) for when no γ is known.

Directional spreading (DNV 3.5.8.4): D(θ) = Γ(1 + n/2) / (√π Γ(½ + n/2)) cos^n(θ - θ_0) for |θ - θ_0| < π/2,
0 elsewhere, ∫ D dθ = 1; n = 2 to 4 for wind seas, larger for swell.

Realisation (:func:`components`): N components at the centres of N equal bins of ω over a band (default 0.5
to 5 ω_p: PM has 2e-9 of its energy below and 0.2 % above), moved by less than half a bin to whole multiples
of Δω, amplitudes a_i = √(2 S(ω_i) Δω), phases drawn uniformly from a seeded generator ("random phase"
method: deterministic amplitudes). The record repeats exactly after 2π/Δω (s): choose N for the duration
wanted. The amplitudes are then scaled so that Σ a_i²/2 = Hs²/16, so the
realised sea has the Hs asked for whatever A_γ's error and the band's cut. Short-crested seas take one
direction per component, drawn from D by its inverse distribution with the same generator (the "single
summation" method): every component keeps its own frequency, so the sea is ergodic at each point (the
variance of η in time is Σ a_i²/2 everywhere), which the "double summation" over a grid of frequencies
times directions is not (components of one frequency in several directions beat into a standing pattern).

Every spectrum function is a pure jnp function, differentiable in ω, Hs, Tp and γ (the design of a cage for
a sea state may want d/dHs); :func:`components` draws its phases and directions with numpy at construction.
Units: m, s, rad.
"""

from __future__ import annotations

import math

import jax.numpy as jnp
import numpy as np

#: DNV's σ of JONSWAP's peak below and above ω_p
SIGMA_BELOW, SIGMA_ABOVE = 0.07, 0.09
#: the default band of a realisation, in multiples of ω_p
BAND = (0.5, 5.0)


def _positive(omega):
    """(ω > 0, ω with 1 where it is not): the double where that keeps ω⁻⁵ at ω = 0 out of every branch."""
    omega = jnp.asarray(omega, dtype=float)
    inside = omega > 0.0
    return inside, jnp.where(inside, omega, 1.0)


def pierson_moskowitz(omega, hs, tp):
    """S_PM(ω) (m² s/rad) at angular frequencies ``omega`` (rad/s) for Hs (m) and Tp (s) (DNV-RP-C205
    3.5.5.1); 0 at ω <= 0."""
    inside, w = _positive(omega)
    wp = 2.0 * jnp.pi / jnp.asarray(tp, dtype=float)
    ratio = wp / w
    s = 5.0 / 16.0 * jnp.asarray(hs, dtype=float) ** 2 * ratio**4 / w * jnp.exp(-1.25 * ratio**4)
    return jnp.where(inside, s, 0.0)


def jonswap(omega, hs, tp, gamma=3.3, sigma_a=SIGMA_BELOW, sigma_b=SIGMA_ABOVE):
    """S_J(ω) (m² s/rad) at angular frequencies ``omega`` (rad/s) for Hs (m), Tp (s) and the peak
    enhancement ``gamma`` (>= 1; 1 is Pierson-Moskowitz), DNV-RP-C205 3.5.5.2 with its normalisation
    A_γ = 1 - 0.287 ln γ; 0 at ω <= 0."""
    omega = jnp.asarray(omega, dtype=float)
    gamma = jnp.asarray(gamma, dtype=float)
    wp = 2.0 * jnp.pi / jnp.asarray(tp, dtype=float)
    sigma = jnp.where(omega <= wp, sigma_a, sigma_b)
    peak = jnp.exp(-0.5 * ((omega - wp) / (sigma * wp)) ** 2)
    return (1.0 - 0.287 * jnp.log(gamma)) * pierson_moskowitz(omega, hs, tp) * gamma**peak


def jonswap_gamma(hs, tp):
    """DNV-RP-C205's peak enhancement for a sea of Hs (m) and Tp (s) when none is known (3.5.5.5): 5 for
    Tp/√Hs <= 3.6, exp(5.75 - 1.15 Tp/√Hs) up to 5, and 1 (Pierson-Moskowitz) beyond."""
    r = float(tp) / math.sqrt(float(hs))
    return 5.0 if r <= 3.6 else (math.exp(5.75 - 1.15 * r) if r < 5.0 else 1.0)


def spreading(angle, n):
    """DNV's cos^n directional spreading D(θ) (1/rad) at ``angle`` θ - θ_0 (rad), n > 0: Γ(1 + n/2) /
    (√π Γ(½ + n/2)) cos^n θ for |θ| < π/2, else 0; ∫ D dθ = 1."""
    angle = jnp.asarray(angle, dtype=float)
    norm = math.gamma(1.0 + 0.5 * n) / (math.sqrt(math.pi) * math.gamma(0.5 + 0.5 * n))
    inside = jnp.abs(angle) < 0.5 * jnp.pi
    return jnp.where(inside, norm * jnp.abs(jnp.cos(jnp.where(inside, angle, 0.0))) ** n, 0.0)


def spectral_moment(spectrum, order, omega):
    """m_n = ∫ ωⁿ S(ω) dω by the trapezoidal rule on the grid ``omega`` (rad/s): ``spectrum`` a function
    ω -> S(ω) (m² s/rad) or its values on the grid."""
    omega = np.asarray(omega, dtype=float)
    values = np.asarray(spectrum(omega) if callable(spectrum) else spectrum, dtype=float)
    return float(np.trapezoid(omega**order * values, omega))


def _spreading_directions(u, n):
    """Angles θ - θ_0 (rad) with the cos^n distribution at uniform numbers u in [0, 1): its distribution
    function tabulated on a fine grid and inverted by interpolation (exact to the grid, 4096 points)."""
    grid = np.linspace(-0.5 * np.pi, 0.5 * np.pi, 4097)
    density = np.asarray(spreading(grid, n))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (density[1:] + density[:-1]) * np.diff(grid))])
    return np.interp(u, cdf / cdf[-1], grid)


def components(hs, tp, spectrum="jonswap", gamma=None, count=200, band=BAND, seed=0, spreading_n=None):
    """The linear components of one realisation of a sea state: (amplitudes (N,) m, angular frequencies (N,)
    rad/s, phases (N,) rad, angles (N,) rad of each component's heading from the mean direction).

    hs: significant height Hs (m), > 0. tp: peak period Tp (s), > 0. spectrum: "jonswap" or
    "pierson-moskowitz". gamma: JONSWAP's peak enhancement (None: :func:`jonswap_gamma`'s). count: N
    components. band: (low, high) in multiples of ω_p. seed: the generator's seed (phases, directions).
    spreading_n: None for a long-crested sea (every angle 0), else the exponent n of :func:`spreading`.
    Raises ValueError naming the parameter for a value that cannot make a sea.
    """
    for name, value in (("hs", hs), ("tp", tp)):
        if not (np.isfinite(value) and value > 0):
            raise ValueError(f"sea state: {name} must be finite and > 0, got {value!r}")
    if not (int(count) == count and count >= 1):
        raise ValueError(f"sea state: count (of components) must be an integer >= 1, got {count!r}")
    if not (len(band) == 2 and 0 < band[0] < band[1] and np.isfinite(band[1])):
        raise ValueError(f"sea state: band must be (low, high) multiples of the peak frequency with 0 < low < high, "
                         f"got {band!r}")
    if spectrum not in ("jonswap", "pierson-moskowitz"):
        raise ValueError(f"sea state: spectrum must be 'jonswap' or 'pierson-moskowitz', got {spectrum!r}")
    if spreading_n is not None and not spreading_n > 0:
        raise ValueError(f"sea state: spreading_n must be > 0 (or None for a long-crested sea), got {spreading_n!r}")
    if gamma is None:
        gamma = jonswap_gamma(hs, tp) if spectrum == "jonswap" else 1.0
    if not gamma >= 1:
        raise ValueError(f"sea state: gamma must be >= 1, got {gamma!r}")
    count = int(count)
    wp = 2.0 * np.pi / tp
    # bins of width Δω over the band, their centres moved (by less than half a bin) to whole multiples of Δω:
    # the sea then repeats exactly after 2π/Δω, over which the components are orthogonal
    d_omega = (band[1] - band[0]) * wp / count
    first = max(1, round(band[0] * wp / d_omega + 0.5))
    omega = (first + np.arange(count)) * d_omega
    density = np.asarray(jonswap(omega, hs, tp, gamma) if spectrum == "jonswap" else pierson_moskowitz(omega, hs, tp))
    amplitude = np.sqrt(2.0 * density * d_omega)
    amplitude *= 0.25 * hs / math.sqrt(0.5 * float(np.sum(amplitude**2)))  # Σ a²/2 = Hs²/16
    rng = np.random.default_rng(seed)
    phase = rng.uniform(0.0, 2.0 * np.pi, count)
    angle = np.zeros(count) if spreading_n is None else _spreading_directions(rng.uniform(0.0, 1.0, count), spreading_n)
    return amplitude, omega, phase, angle


__all__ = ["pierson_moskowitz", "jonswap", "jonswap_gamma", "spreading", "spectral_moment", "components", "BAND"]
