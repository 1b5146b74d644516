"""SuperLU's tuning options on the tangents jaxnet factorises: factorisation time by relaxed-supernode size.

    python validation/superlu_options.py [--cases nr_netting c2] [--cage-steps 1.6 0.5 0.3] [--repeats 7]

The matrices: the tangent of the middle Newton iteration of each FEMNET case's static solve (FEMNET's mesh,
closed-form stiffness, the spring-network damping included: what the solver factorises), and the tangent
of a time step of the cage in waves meshed at each ``--cage-steps`` (m), 0.1 s into a run from its static
equilibrium (inertia and drag damping included). Each is factorised the way :class:`jaxnet.linalg.HostSolver`
does after its first call (the stored minimum-degree order, diagonal pivots preferred), with SuperLU's
``relax`` (columns merged into relaxed supernodes) and ``panel_size`` varied; the options are taken in
turn, ``--repeats`` times each, and the fastest time of each is printed (ms), with the fill (entries of L
and U). jaxnet uses :data:`jaxnet.linalg.RELAX` and :data:`jaxnet.linalg.PANEL_SIZE`; SuperLU's own
defaults are relax 10 and panel size 20. Nothing is asserted: it is the measurement behind those constants.
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np
import scipy.sparse.linalg as spla

import jaxnet  # noqa: F401
from jaxnet import linalg

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "femnet"
if __package__ in (None, ""):  # run as a script: the repository root on the path, for validation.dynamics_cost
    sys.path.insert(0, str(ROOT))
OPTIONS = [dict(relax=r, panel_size=p) for p in (1, 20) for r in (1, 2, 3, 10)]


def femnet_tangent(case):
    """(data, indptr, indices): the matrix of the middle factorisation of the case's static solve."""
    from jaxnet.io import femnet
    from jaxnet.solve.statics import solve

    seen = []
    factorize = linalg.HostSolver.factorize

    def keep(self, data):
        seen.append((np.array(data), self.indptr, self.indices))
        return factorize(self, data)

    loaded = femnet.read_mdg(DATA / f"{case}.mdg", DATA / f"{case}.don")
    scene, solver = loaded.scene, loaded.solver
    linalg.HostSolver.factorize = keep
    try:
        solve(scene, solver, throw=False, stiffness="closed_form")
    finally:
        linalg.HostSolver.factorize = factorize
    return seen[len(seen) // 2]


def cage_tangent(step):
    """(data, indptr, indices): the tangent of a time step of the cage in waves meshed at ``step`` (m)."""
    import jax.numpy as jnp

    from jaxnet.solve import kernel
    from validation.dynamics_cost import time_step_problem

    scene, _, model, pattern, scene_t, step_, x, load = time_step_problem(step, 0.1)
    forces_state = kernel.evaluate(x, jnp.zeros_like(step_.x_previous), load, 1.0, scene_t, pattern, model,
                                   step_)[4]
    data = kernel.tangent(x, forces_state, 1.0, scene_t, pattern, model, "closed_form", step_)
    return np.asarray(data), np.asarray(pattern.indptr), np.asarray(pattern.indices)


def table(name, matrix, repeats):
    data, indptr, indices = matrix
    solver = linalg.HostSolver(indptr, indices)
    solver.factorize(data)  # the ordering, once
    splu = spla.splu
    times, fill = {k: [] for k in range(len(OPTIONS))}, {}
    try:
        for _ in range(repeats):
            for k, option in enumerate(OPTIONS):
                linalg.spla.splu = lambda a, option=option, **kw: splu(a, **{**kw, **option})
                t0 = time.perf_counter()
                solver.factorize(data)
                times[k].append(time.perf_counter() - t0)
                fill[k] = solver.factor_entries
    finally:
        linalg.spla.splu = splu
    best = min(min(t) for t in times.values())
    print(f"\n## {name}: {len(indptr) - 1} unknowns, {len(indices)} entries\n")
    print("| relax | panel size | factorisation (ms) | vs fastest | fill (L + U entries) |")
    print("|---|---|---|---|---|")
    for k, option in enumerate(OPTIONS):
        mark = " (jaxnet)" if (option["relax"], option["panel_size"]) == (linalg.RELAX, linalg.PANEL_SIZE) else ""
        print(f"| {option['relax']}{mark} | {option['panel_size']} | {min(times[k]) * 1e3:.2f} | "
              f"{min(times[k]) / best:.2f} | {fill[k]} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--cases", nargs="*", default=["nr_netting", "c2"])
    parser.add_argument("--cage-steps", type=float, nargs="*", default=[1.6, 0.5, 0.3])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    for case in args.cases:
        table(f"{case} (FEMNET's mesh, static Newton)", femnet_tangent(case), args.repeats)
    for step in args.cage_steps:
        table(f"cage in waves meshed at {step:g} m (a time step)", cage_tangent(step), args.repeats)


if __name__ == "__main__":
    main()
