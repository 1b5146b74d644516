"""SuperLU's factors on the C heap: page faults and time per factorisation with and without the heap kept.

    python validation/superlu_memory.py [--cases nr_netting c2] [--factorisations 30] [--rounds 3]

Each factorisation of :class:`jaxnet.linalg.HostSolver` allocates SuperLU's L and U afresh (a few MB on the
FEMNET cases) and frees them at the next. glibc's malloc serves such blocks by mmap until it has seen one
that large freed, so each new factor is faulted into memory again page by page;
:func:`jaxnet.linalg.keep_factor_memory` frees one 16 MB block once per process, after which glibc keeps
them on its heap. The matrices: the tangent of the middle Newton iteration of each FEMNET case's static
solve (FEMNET's mesh, what the solver factorises). Each setting runs in fresh processes (the setting is
once per process), alternately, ``--rounds`` times: a child builds a solver on the matrix (its ordering
computed at the first factorisation) and times ``--factorisations`` more factorisations, counting the
process's minor page faults. The table prints the medians over the rounds of the per-factorisation time
(ms) and faults, side by side, with their ratio. Nothing is asserted: it is the measurement behind
``keep_factor_memory``.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import resource
import subprocess
import sys
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
if __package__ in (None, ""):  # run as a script: the repository root on the path, for validation.*
    sys.path.insert(0, str(ROOT))
SETTINGS = ("heap kept", "as glibc starts")


def child(case, setting, factorisations, matrix_file):
    """Run in a fresh process: time the factorisations of the stored matrix; print JSON (ms, faults per
    factorisation)."""
    from jaxnet import linalg

    if setting != SETTINGS[0]:
        linalg.MALLOC_PRIMER = 0  # no primer: the heap is left as glibc starts
    data = np.load(matrix_file)
    solver = linalg.HostSolver(data["indptr"], data["indices"])
    assert solver.factorize(data["data"])  # the ordering, computed once
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    t0 = time.perf_counter()
    for _ in range(factorisations):
        assert solver.factorize(data["data"])
    elapsed = time.perf_counter() - t0
    faults = resource.getrusage(resource.RUSAGE_SELF).ru_minflt - faults
    print(json.dumps({"ms": 1e3 * elapsed / factorisations, "faults": faults / factorisations}))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["nr_netting", "c2"])
    parser.add_argument("--factorisations", type=int, default=30)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--child", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        case, setting, matrix_file = args.child
        child(case, setting, args.factorisations, matrix_file)
        return
    import tempfile

    from validation.superlu_options import femnet_tangent

    print(f"| case | n | time per factorisation (ms): {SETTINGS[0]} | {SETTINGS[1]} | ratio | "
          f"page faults per factorisation: {SETTINGS[0]} | {SETTINGS[1]} |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for case in args.cases:
            data, indptr, indices = femnet_tangent(case)
            matrix_file = str(pathlib.Path(folder) / f"{case}.npz")
            np.savez(matrix_file, data=np.asarray(data), indptr=np.asarray(indptr), indices=np.asarray(indices))
            runs = {setting: [] for setting in SETTINGS}
            for _ in range(args.rounds):
                for setting in SETTINGS:  # in turn, so that a busy moment of the machine hits both
                    out = subprocess.run([sys.executable, __file__, "--factorisations", str(args.factorisations),
                                          "--child", case, setting, matrix_file],
                                         check=True, capture_output=True, text=True).stdout
                    runs[setting].append(json.loads(out.strip().splitlines()[-1]))
            ms = {s: float(np.median([r["ms"] for r in runs[s]])) for s in SETTINGS}
            faults = {s: float(np.median([r["faults"] for r in runs[s]])) for s in SETTINGS}
            kept, fresh = SETTINGS
            print(f"| {case} | {len(indptr) - 1} | {ms[kept]:.2f} | {ms[fresh]:.2f} | {ms[fresh] / ms[kept]:.2f} | "
                  f"{faults[kept]:.0f} | {faults[fresh]:.0f} |", flush=True)


if __name__ == "__main__":
    main()
