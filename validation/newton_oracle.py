"""The static solver against a textbook trust-region Newton, on conservative nets: is the globalisation the cause?

    python validation/newton_oracle.py [--nodes 100] [--cases NAME ...]

The robustness set's slack curtains (``validation/robustness.py``) take a hundred to a few hundred Newton
iterations. Is that the fault of the static solver's globalisation (Levenberg-Marquardt damping on the spring
network, an energy line search, the stiffness continuation: :mod:`jaxnet.solve.newton`), or of the problem?
In still water a net is conservative: its equilibrium is a minimum of its potential energy, and a textbook
method applies. This script minimises the same energy, with the same gradient (minus the residual) and the
same tangent stiffness (the exact Hessian), by SciPy's exact trust-region Newton (``trust-exact``: Moré and
Sorensen's nearly exact subproblem on the dense Hessian, which copes with indefinite and singular Hessians),
from the same drawn start, and counts its iterations until the largest nodal residual first falls below
jaxnet's tolerance (1e-3 N). Beside it, ``jaxnet.solve_static``'s iterations on the same scene.

The cases are the still-water curtains of the robustness set at about ``--nodes`` nodes (dense Hessians:
keep them small): the README's panel without its sinker bar, with it, and the built-in hanging panel with a
weightless bottom bar, all with the physical twine (no compression stiffness).

Units: N, m.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parent.parent
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

#: the largest nodal residual (N) at which both count a solve as converged: jaxnet's tolerance
TOL_N = 1e-3
#: the trust-region method's iteration cap
MAX_ITERATIONS = 1000
#: (name, robustness family, with sinker): the still-water curtains
CASES = (("readme, no sinker", "readme", False), ("readme, sinker bar", "readme", True),
         ("hanging, weightless bar", "hanging", False))


def energy_problem(scene):
    """The scene's potential energy as a function of its free coordinates: (x0, energy_and_gradient(x),
    hessian(x) dense, largest_residual(gradient)), from jaxnet's own compiled evaluation and tangent."""
    import jax
    import scipy.sparse as sp

    from jaxnet import model as model_lib
    from jaxnet.model import assemble
    from jaxnet.scene import checks
    from jaxnet.solve import kernel

    checks.validate(scene)
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    free = np.asarray(pattern.free)
    x0 = np.asarray(scene.nodes.position, dtype=float).ravel()[free]
    load = jax.jit(lambda s: kernel.loads(s, model))(scene)
    zero = np.zeros_like(np.asarray(load))
    evaluate = jax.jit(lambda x: kernel.evaluate(x, zero, load, 1.0, scene, pattern, model))
    tangent = jax.jit(lambda x, state: kernel.tangent(x, state, 1.0, scene, pattern, model, "closed_form"))
    shape = (x0.size, x0.size)
    indices, indptr = np.asarray(pattern.indices), np.asarray(pattern.indptr)

    def energy_and_gradient(x):
        _, force, _, merit, _ = evaluate(x)
        return float(merit), -np.asarray(force).ravel()[free]

    def hessian(x):
        state = evaluate(x)[4]
        return sp.csr_matrix((np.asarray(tangent(x, state)), indices, indptr), shape=shape).toarray()

    def largest_residual(gradient):
        full = np.zeros(3 * scene.n_nodes)
        full[free] = gradient
        return float(np.sqrt((full.reshape(-1, 3) ** 2).sum(axis=1)).max())

    return x0, energy_and_gradient, hessian, largest_residual


def trust_region(scene):
    """SciPy's ``trust-exact`` from the drawn start: (iterations until the largest residual is below
    :data:`TOL_N`, or None; its iterations in all; wall s)."""
    import scipy.optimize as so

    x0, energy_and_gradient, hessian, largest_residual = energy_problem(scene)
    residuals = []

    def record(x, *_):
        residuals.append(largest_residual(energy_and_gradient(x)[1]))

    t0 = time.perf_counter()
    result = so.minimize(energy_and_gradient, x0, jac=True, hess=hessian, method="trust-exact", callback=record,
                         options={"gtol": TOL_N / 10, "maxiter": MAX_ITERATIONS})
    first = next((k + 1 for k, r in enumerate(residuals) if r <= TOL_N), None)
    return first, int(result.nit), time.perf_counter() - t0


def jaxnet_static(scene):
    """``jaxnet.solve_static`` (the library's options, at most :data:`MAX_ITERATIONS` iterations): (iterations
    or None if it did not converge, wall s)."""
    import jaxnet as jn

    eq = jn.solve_static(scene, max_iter=MAX_ITERATIONS, throw=False)
    return (int(eq.iterations) if eq.converged else None), eq.timing.wall_s


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nodes", type=int, default=100, help="about this many nodes per curtain")
    parser.add_argument("--cases", nargs="*", default=None, help="a subset of the case names")
    args = parser.parse_args(argv)
    import jaxnet  # noqa: F401  (float64 on)

    from validation import robustness

    print(f"Still-water curtains of about {args.nodes} nodes, physical twine; iterations to a largest residual "
          f"of {TOL_N:g} N from the drawn start (at most {MAX_ITERATIONS}).\n")
    print("| case | nodes | jaxnet.solve_static it | wall s | scipy trust-exact it | its iterations in all | wall s |")
    print("|---|---|---|---|---|---|---|")
    for name, family, sinker in CASES:
        if args.cases and name not in args.cases:
            continue
        scene = robustness.PANELS[family](args.nodes, 0.0, 0, sinker)
        jn_it, jn_s = jaxnet_static(scene)
        tr_it, tr_all, tr_s = trust_region(scene)
        show = lambda it: "not converged" if it is None else str(it)  # noqa: E731
        print(f"| {name} | {scene.n_nodes} | {show(jn_it)} | {jn_s:.1f} | {show(tr_it)} | {tr_all} | {tr_s:.1f} |",
              flush=True)


if __name__ == "__main__":
    main()
