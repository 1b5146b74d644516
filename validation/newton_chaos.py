"""How far the static solver's iteration count moves under changes that leave the answer as it is.

    python validation/newton_chaos.py [--cases FAMILY/CASE ...] [--corpus DIR] [--timeout S]
    python validation/newton_chaos.py --trace FAMILY/CASE ITERATION

Each of FEMNET's cases named is solved from its ``.don`` (FEMNET's laws, its own Newton options) three times,
each in a fresh process, changing only what should not matter:

* ``closed form``: the library's defaults (the tangent's element matrices by hand where a term has them,
  PARDISO in oneMKL's reproducible mode, :data:`jaxnet.linalg.pardiso.CNR`);
* ``autodiff``: the tangent's element matrices by ``jax.jacfwd`` of every term (``stiffness="autodiff"``:
  the same matrices to rounding, tested per element and on whole solves);
* ``MKL default``: the closed form again, with ``MKL_CBWR`` empty (MKL's default code branch: the same
  factorisation, its sums in another order).

It prints, per case, the iterations of each run and the largest difference between the runs' total forces
on the fixings, relative to the largest component (the same equilibrium to the solver's tolerance, or
another one). A change to the static solver judged on one case's iteration count is judged on noise of
this size: judge it on the robustness set (``validation/robustness.py``) and the corpus
(``validation/femnet_corpus.py``).

``--trace CASE K`` looks at one solve's iterate K (the library's defaults): the node of the largest residual,
the strains of the bars and twines at it and, for each bar, how far the next full Newton step turns it and how
much it lengthens it against what the step's linear model expected: a bar that carries little (strain ε) and
is turned by an angle θ is stretched by about L0 θ²/2 more than expected, a tension EA θ²/2 that outweighs its
own EA ε once θ exceeds √(2ε) (the stretch barrier of large rotations: the next step first undoes that
stretch, and the net turns such bars a little at each iteration).

The default cases are small ones of FEMNET's corpus that take hundreds of iterations (trawls, a seine, the
gravity catch, the fish cage); ``../shared/femnet-corpus/`` must be there.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
CORPUS = ROOT.parent / "shared" / "femnet-corpus"
CASES = ("1pelagic_trawl/toto1", "1pelagic_trawl/t1", "1pelagic_trawl/t2", "3bottom_trawl/q1",
         "11bottom_seine/s1", "13gravity_catch/g1", "10fish_cage/f1", "12purse_seine/u1")
#: run name -> (the Newton options' stiffness path, the MKL_CBWR the process starts with: None for jaxnet's own)
RUNS = {"closed form": ("closed_form", None), "autodiff": ("autodiff", None), "MKL default": ("closed_form", "")}


def one(don, stiffness):
    """Solve ``don`` in this process with the tangent path ``stiffness``: its record."""
    import dataclasses

    import numpy as np

    from jaxnet.io import femnet
    from jaxnet.solve.statics import solve

    case = femnet.read_don(don)
    eq = solve(case.scene, dataclasses.replace(case.solver, stiffness=stiffness), throw=False)
    total = femnet.femnet_figures(case.scene, eq, case.info["symmetry_axes"], case.info.get("fixity"))["total_force_N"]
    return {"nodes": case.scene.n_nodes, "iterations": int(eq.iterations), "converged": bool(eq.converged),
            "total_force_N": np.asarray(total, dtype=float).tolist()}


def run(don, name, timeout):
    """One run of :data:`RUNS` in a fresh process (its own MKL code branch): its record, or the reason it has
    none."""
    stiffness, cbwr = RUNS[name]
    env = dict(os.environ)
    env.pop("MKL_CBWR", None)  # unset: jaxnet.linalg.pardiso chooses its own (the reproducible mode)
    if cbwr is not None:
        env["MKL_CBWR"] = cbwr
    try:
        done = subprocess.run([sys.executable, __file__, "--one", str(don), stiffness], capture_output=True,
                              text=True, timeout=timeout, env=env, cwd=ROOT)
    except subprocess.TimeoutExpired:
        return {"error": f"timeout after {timeout:g} s"}
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = (done.stderr or done.stdout).strip().splitlines()[-1:] or ["no output"]
        return {"error": tail[0][:200]}
    return json.loads(lines[-1])


def spread(records):
    """The largest difference between the runs' total forces, relative to the largest component (None when
    fewer than two runs converged)."""
    import numpy as np

    forces = [np.asarray(r["total_force_N"]) for r in records if r.get("converged")]
    if len(forces) < 2:
        return None
    scale = max(float(np.abs(f).max()) for f in forces) or 1.0
    return max(float(np.abs(a - b).max()) for a in forces for b in forces) / scale


def trace(don, k):
    """Print what :func:`main`'s ``--trace`` describes, for iterate ``k`` of the solve of ``don``."""
    import jax
    import numpy as np

    from jaxnet import figures, model as model_lib
    from jaxnet.model import assemble
    from jaxnet.io import femnet
    from jaxnet.solve import kernel, statics

    case = femnet.read_don(don)
    scene, solver = case.scene, case.solver
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    free = np.asarray(pattern.free)
    start = np.asarray(scene.nodes.position, dtype=float).ravel()[free]
    pieces = statics.compile_pieces(start, scene, pattern, model, solver.stiffness)
    iterates, trials = [], {}  # the tangent is taken once per iteration, at the iterate; then the trials

    def at_iterate(x, *rest):
        iterates.append(np.asarray(x).copy())
        return pieces["tangent"](x, *rest)

    def at_trial(x, *rest):
        if iterates:
            trials.setdefault(len(iterates) - 1, np.asarray(x).copy())  # the first: the full Newton step
        return pieces["evaluate"](x, *rest)

    recording = {**pieces, "tangent": at_iterate, "evaluate": at_trial}
    eq = statics.host_loop(start, scene, pattern, model, solver, recording)
    print(f"{don}: {eq.reason} after {int(eq.iterations)} iterations; iterate {k}:")
    force = jax.jit(lambda x: kernel.force(x, scene, pattern, model).ravel()[pattern.free])

    def positions(x):
        X = np.asarray(scene.nodes.position, dtype=float).ravel().copy()
        X[free] = x
        return X.reshape(-1, 3)

    f = np.zeros(3 * scene.n_nodes)
    f[free] = np.asarray(force(iterates[k]))
    node = int(np.argmax(np.linalg.norm(f.reshape(-1, 3), axis=1)))
    X, full = positions(iterates[k]), positions(trials[k])
    print(f"  largest residual {np.linalg.norm(f[3 * node:3 * node + 3]):.4g} N at node {node}")
    bars = scene.bars
    if bars is not None:
        ends = np.asarray(bars.ends)
        for b in np.nonzero((ends == node).any(axis=1))[0]:
            rest, ea = float(np.asarray(bars.rest_length)[b]), float(np.asarray(bars.ea_traction)[b])
            w = X[ends[b, 1]] - X[ends[b, 0]]
            length = np.linalg.norm(w)
            dw = full[ends[b, 1]] - full[ends[b, 0]] - w
            linear = float(w @ dw) / length  # the length change the Newton step's linear model expects
            actual = np.linalg.norm(w + dw) - length
            turn = np.linalg.norm(dw - linear * w / length) / length
            print(f"  bar {b} {ends[b].tolist()}: rest length {rest:g} m, EA {ea:g} N, "
                  f"strain {(length - rest) / rest:.3e}; "
                  f"the full Newton step turns it by {turn:.2e} rad and lengthens it by {actual:.3e} m where its "
                  f"linear model says {linear:.3e}: {ea * (actual - linear) / rest:.3g} N of tension it did not expect")
    net = scene.netting
    if net is not None:
        tensions = figures.twine_tensions(scene, X)
        for e in np.nonzero((np.asarray(net.vertices) == node).any(axis=1))[0]:
            strains = tensions[e] / float(np.asarray(net.ea_traction)[e])
            print(f"  triangle {e}: twine strains U {strains[0]:.3e}, V {strains[1]:.3e} (0 when slack)")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="*", default=list(CASES), help="FEMNET cases, family/name")
    parser.add_argument("--corpus", default=str(CORPUS))
    parser.add_argument("--timeout", type=float, default=300.0, help="wall-clock limit of one run (s)")
    parser.add_argument("--trace", nargs=2, metavar=("CASE", "ITERATION"), help="look at one iterate of one case")
    parser.add_argument("--one", nargs=2, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.trace:
        trace(pathlib.Path(args.corpus) / f"{args.trace[0]}.don", int(args.trace[1]))
        return
    if args.one:
        print(json.dumps(one(*args.one)))
        return
    print("FEMNET's cases from their .don, each solved three times in fresh processes: Newton iterations "
          "(* not converged) and the largest difference between the runs' totals on the fixings.\n")
    print("| case | nodes | " + " | ".join(f"it {name}" for name in RUNS) + " | largest / smallest it "
          "| force difference |")
    print("|---|---|" + "---|" * len(RUNS) + "---|---|")
    t0 = time.perf_counter()
    for case in args.cases:
        don = pathlib.Path(args.corpus) / f"{case}.don"
        records = [run(don, name, args.timeout) for name in RUNS]
        shown = [r["error"] if "error" in r else f"{r['iterations']}{'' if r['converged'] else '*'}" for r in records]
        counts = [r["iterations"] for r in records if r.get("converged")]
        ratio = f"{max(counts) / min(counts):.1f}" if len(counts) > 1 else "-"
        nodes = next((r["nodes"] for r in records if "nodes" in r), "-")
        difference = spread(records)
        print(f"| {case} | {nodes} | " + " | ".join(shown) + f" | {ratio} | "
              + ("-" if difference is None else f"{difference:.1e}") + " |", flush=True)
    print(f"\n*{time.perf_counter() - t0:.0f} s in all.*")


if __name__ == "__main__":
    if str(ROOT) not in sys.path:
        sys.path.insert(0, str(ROOT))
    main()
