"""Fingerprints of jaxnet's answers, to show that a change which should not change any answer does not.

    python validation/fingerprints.py [--out FILE.json] [--compare BEFORE.json] [--only stability|femnet]

Per case: the Newton iterations and a digest of the exact bits of the answer (the final positions and
out-of-balance forces of a static solve; positions, velocities and forces of a dynamic run). Cases: every
case of the stability catalogue (``validation/stability.py``) at its test size from its flat start, statics
on both stiffness paths and its dynamic runs; FEMNET's ``nr_netting`` and ``c2`` on FEMNET's mesh and on
jaxnet's, both paths. ``--compare`` reads the fingerprints of another checkout (run there with ``--out``)
and lists every case that differs; the exit status is 1 when any does.

A refactoring run on the same machine, the same jax and jaxlib, should change no bit: the order of the
floating-point operations is part of the answer (XLA fuses and vectorises the same program the same way).
Across machines or versions the bits differ and only iteration counts are comparable. Within a process the
bits also depend on what was solved before: the very first factorisation of a sparsity structure in a
process lets SuperLU order it, every later one reuses that ordering through an explicit permutation
(:mod:`jaxnet.linalg`): the same ordering, rounded differently. So the cases run in a fixed order, and only runs of the same selection compare.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import json
import pathlib
import sys

import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
DATA = HERE.parent / "tests" / "data" / "femnet"


def digest(*arrays):
    """12 hex digits of the SHA-1 of the arrays' float64 bytes."""
    h = hashlib.sha1()
    for a in arrays:
        h.update(np.ascontiguousarray(np.asarray(a, dtype=float)).tobytes())
    return h.hexdigest()[:12]


def static(scene, solver, x0=None):
    from jaxnet.solve.statics import solve

    eq = solve(scene, solver, x0=x0, throw=False)
    return int(eq.iterations), digest(eq.x, eq.force)


def dynamic(problem):
    from jaxnet.solve import dynamics

    d = problem.dynamic
    run = dynamics.simulate(problem.scene, d.end_time, d.solver, d.loading, record_every=d.end_time, throw=False)
    state = run.state
    return int(state.iterations), digest(state.x, state.v, state.force)


def stability_fingerprints():
    sys.path.insert(0, str(HERE.parent))
    from validation import stability

    out = {}
    for case in stability.catalogue():
        if case.full_only:
            continue
        try:
            problem = case.build("test")
        except Exception as error:  # noqa: BLE001 -- a refused case is a fingerprint too
            out[case.name] = f"refused: {type(error).__name__}"
            continue
        if problem.dynamic:
            out[f"{case.name} [dynamic]"] = dynamic(problem)
            continue
        for stiffness in ("closed_form", "autodiff"):
            solver = dataclasses.replace(stability.newton_options(problem), stiffness=stiffness)
            out[f"{case.name} [{stiffness}]"] = static(problem.scene, solver)
    return out


def femnet_fingerprints():
    from jaxnet.io import femnet

    out = {}
    for name in ("nr_netting", "c2"):
        for mesh in ("mdg", "don"):
            case = (femnet.read_mdg(DATA / f"{name}.mdg", DATA / f"{name}.don") if mesh == "mdg"
                    else femnet.read_don(DATA / f"{name}.don"))
            for stiffness in ("closed_form", "autodiff"):
                out[f"femnet {name} {mesh} [{stiffness}]"] = static(case.scene, case.with_solver(stiffness=stiffness).solver)
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="write the fingerprints to this JSON file")
    parser.add_argument("--compare", help="fingerprints of another checkout (JSON) to compare with")
    parser.add_argument("--only", choices=("stability", "femnet"), help="one group of cases only")
    args = parser.parse_args(argv)
    import jaxnet  # noqa: F401  (float64)

    prints = {}
    if args.only in (None, "stability"):
        prints.update(stability_fingerprints())
    if args.only in (None, "femnet"):
        prints.update(femnet_fingerprints())
    for name, value in prints.items():
        print(f"{name:60s} {value}")
    if args.out:
        pathlib.Path(args.out).write_text(json.dumps(prints, indent=1))
    if args.compare:
        before = json.loads(pathlib.Path(args.compare).read_text())
        differ = [k for k in before if k in prints and json.dumps(before[k]) != json.dumps(prints[k])]
        missing = [k for k in before if k not in prints]
        print(f"\n{len(before)} cases before, {len(prints)} now: {len(differ)} differ, {len(missing)} missing")
        for k in differ:
            print(f"  {k}: {before[k]} -> {prints[k]}")
        return 1 if differ or missing else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
