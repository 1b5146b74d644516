"""jaxnet's JONSWAP spectrum (``jaxnet.water.spectra``) against wavespectra's, the spectral package of the registry.

    pip install wavespectra   # not a jaxnet dependency
    python validation/spectra_against_wavespectra.py [--hs 3] [--tp 10] [--gamma 3.3]

Both on one grid of frequencies (Hz), both scaled so that 4 √m0 = Hs on it (wavespectra's ``hs=`` does so; jaxnet
gives S(ω) with DNV's normalisation A_γ, turned into S(f) = 2π S(ω) and scaled the same): the largest difference
relative to the peak, and the peak frequencies. Why jaxnet keeps its own: its spectra are jax.numpy functions,
differentiable in Hs, Tp and γ for design, and wavespectra (xarray, numpy) would be a dependency for a formula
of a few lines. A benchmark, not a test.
"""

from __future__ import annotations

import argparse

import numpy as np


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--hs", type=float, default=3.0)
    parser.add_argument("--tp", type=float, default=10.0)
    parser.add_argument("--gamma", type=float, default=3.3)
    args = parser.parse_args(argv)
    from wavespectra.construct import frequency

    import jaxnet  # noqa: F401  (float64)
    from jaxnet.water import spectra

    f = np.linspace(0.02, 0.6, 2000)
    theirs = np.asarray(frequency.jonswap(freq=f, fp=1.0 / args.tp, gamma=args.gamma, hs=args.hs))
    ours = 2.0 * np.pi * np.asarray(spectra.jonswap(2.0 * np.pi * f, args.hs, args.tp, args.gamma))
    ours *= (args.hs**2 / 16.0) / np.trapezoid(ours, f)
    print(f"JONSWAP Hs {args.hs:g} m, Tp {args.tp:g} s, gamma {args.gamma:g}: largest difference "
          f"{np.abs(ours - theirs).max() / theirs.max():.2e} of the peak; peak at {f[np.argmax(ours)]:.4f} Hz "
          f"(jaxnet) and {f[np.argmax(theirs)]:.4f} Hz (wavespectra)")


if __name__ == "__main__":
    main()
