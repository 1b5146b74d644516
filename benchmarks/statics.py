"""Benchmark of the static solver against size: panels, the cage in a current, FEMNET's cases, from their drawn start.

    python benchmarks/statics.py [--scene framed|hanging|cage|trawl|femnet] [--sizes 100 1000 10000 100000]
                                       [--ea-compression EA_C] [--current U] [--max-iter N]
                                       [--methods damped primal-dual]

Scenes:

* ``framed`` (jaxnet.scenes.panel): a horizontal panel of 100 x 100 meshes held along its border, sagging
  under its weight and a 20 kg sinker (twines EA_c = 0 by default: slack allowed);
* ``hanging``: the default panel scene, a curtain of 100 x 100 meshes hanging from a headline with a sinker
  bar (twines EA_c = EA by default);
* ``cage`` (jaxnet.scenes.cage): the fish cage (physical twine, EA_c = 0) in a current of ``--current`` m/s
  (default 0.5), meshed finer for more nodes (step 0.5 m gives 1161 nodes; nodes grow as 1/step²);
* ``trawl``: a trawl of FEMNET's corpus (``--trawl``, default the pelagic trawl ``1pelagic_trawl/s3``: 424
  nodes on FEMNET's mesh), meshed finer for more nodes (``read_don(refine=...)``: nodes grow about as
  refine²; the refinement that gives each size is found from the file's own node count), with FEMNET's
  solver settings from the file (its threshold: 0.01 N for s3);
* ``femnet``: FEMNET's worked cases that jaxnet reads (``--cases``: .don files, default the cod-end c2 and
  nr_netting of ``tests/data/femnet``), each at its own size (``--sizes`` unused).

The meshing step sets the node count. Each size runs in its own process (so that peak memory is that size's),
with at most ``--max-iter`` Newton iterations. Printed per size, from the solve's own :class:`Timing`: nodes,
unknowns, tangent non-zeros, compile time, Newton iterations, factorisations, the time of one tangent assembly
and of one factorisation with its solve (means over the solve), the time of one iteration, that time over
(one assembly + one factorisation), the whole solve over (iterations x one factorisation), peak resident
memory; then the growth exponents (least squares of log cost against log nodes). A solve that does not
converge is printed with its reason: its costs still count.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import resource
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
#: FEMNET's cases timed by default (``--scene femnet``)
FEMNET_CASES = tuple(str(ROOT / "tests" / "data" / "femnet" / name) for name in ("c2.don", "nr_netting.don"))
#: the cage's meshing step (m) and node count it gives: nodes grow as 1/step²
CAGE_STEP, CAGE_NODES = 0.5, 1161
#: the trawl timed by default (``--scene trawl``), a case of FEMNET's corpus
TRAWL = ROOT.parent / "shared" / "femnet-corpus" / "1pelagic_trawl" / "s3.don"


def build(scene_name, size, ea_compression, current, trawl=TRAWL):
    """The scene of one row: a panel, the cage or the trawl of about ``size`` nodes, or the FEMNET case at path
    ``size``."""
    import numpy as np

    from jaxnet.io.femnet import read_don
    from jaxnet.net import Twine
    from jaxnet.scenes.cage import fish_cage
    from jaxnet.scenes.panel import framed_panel, hanging_panel

    if scene_name == "femnet":
        return read_don(size)
    if scene_name == "trawl":
        own = read_don(trawl).scene.n_nodes
        return read_don(trawl, refine=max(1.0, float(np.sqrt(int(size) / own))))
    if scene_name == "cage":
        return fish_cage(step=CAGE_STEP * float(np.sqrt(CAGE_NODES / int(size))), current=current)
    meshes, l0 = 100, 0.025
    width = meshes * l0 * np.sqrt(2.0)
    step = width / np.sqrt(int(size) / 1.15)  # the mesher's lattice holds about 1.15 nodes per step²
    if ea_compression is None:
        ea_compression = 0.0 if scene_name == "framed" else 2000.0
    twine = Twine(l0=l0, ea=2000.0, diameter=1.5e-3, ea_compression=ea_compression)
    if scene_name == "framed":
        return framed_panel(meshes=meshes, l0=l0, step=step, twine=twine, sinker_kg=20.0)
    return hanging_panel(meshes=meshes, l0=l0, step=step, twine=twine)


def one(size, scene_name, ea_compression, current, max_iter, trawl=TRAWL, method=None):
    """Solve one scene in this process; its row (a dict). ``method``: the static method (None: the library's
    default, or the case's)."""
    import jaxnet as jn

    case = build(scene_name, size, ea_compression, current, trawl)
    scene = case.scene
    chosen = {} if method is None else {"method": method}
    eq = jn.solve_static(case, throw=False, max_iter=max_iter, **chosen)  # FEMNET's threshold for its cases
    t = eq.timing
    from jaxnet import model
    from jaxnet.model import assemble

    pattern = assemble.build_pattern(scene, model.active_terms(scene))
    iterations = max(int(eq.iterations), 1)
    assembly = t.assembly_s / max(t.factorisations, 1)
    factor = t.factorisation_each_s
    run_s = t.wall_s - t.compile_s
    return {
        "case": (pathlib.Path(size).stem if scene_name == "femnet" else f"{scene_name} {size}")
                + ("" if method is None else f" {method}"),
        "nodes": scene.n_nodes,
        "dof": scene.n_dof,
        "nnz": int(pattern.nnz),
        "compile_s": t.compile_s,
        "iterations": int(eq.iterations),
        "factorisations": t.factorisations,
        "reason": eq.reason,
        "assembly_s": assembly,
        "factor_s": factor,
        "iteration_s": run_s / iterations,
        "per_iteration": run_s / iterations / (assembly + factor),
        "run_s": run_s,
        "ratio": run_s / (iterations * factor),
        "residual_N": float(eq.residual_N),
        "peak_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", type=int, nargs="*", default=[100, 1000, 10000, 100000])
    parser.add_argument("--scene", choices=("framed", "hanging", "cage", "trawl", "femnet"), default="framed")
    parser.add_argument("--trawl", default=str(TRAWL), help="with --scene trawl: the .don case refined")
    parser.add_argument("--cases", nargs="*", default=list(FEMNET_CASES), help="with --scene femnet: .don files")
    parser.add_argument("--ea-compression", type=float, default=None, help="panels' twine EA_c (N); default per scene")
    parser.add_argument("--current", type=float, default=0.5, help="the cage's current (m/s)")
    parser.add_argument("--max-iter", type=int, default=500, help="Newton iterations at most")
    parser.add_argument("--methods", nargs="*", default=[None],
                        help="the static methods, each size solved by each in turn (default: the library's)")
    parser.add_argument("--method", help=argparse.SUPPRESS)
    parser.add_argument("--one", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.scene, args.ea_compression, args.current, args.max_iter, args.trawl,
                             args.method)))
        return
    import numpy as np

    import jax

    from jaxnet import linalg

    rows = []
    columns = ("case", "nodes", "dof", "nnz", "compile s", "it", "fact", "assembly s", "factor s", "s/it",
               "it/(asm+fac)", "total/(it*fac)", "residual N", "peak MB")
    print({"framed": "framed panel, flat stress-free start", "hanging": "hanging panel, flat stress-free start",
           "cage": f"fish cage in a {args.current:g} m/s current, drawn start",
           "trawl": f"FEMNET's trawl {pathlib.Path(args.trawl).parent.name}/{pathlib.Path(args.trawl).stem} meshed "
                    f"finer, drawn start, FEMNET's threshold",
           "femnet": "FEMNET's cases, drawn start"}[args.scene]
          + ("" if args.scene in ("cage", "trawl", "femnet") else
             f", twine EA_c = {args.ea_compression if args.ea_compression is not None else 'scene default'} N")
          + f"; at most {args.max_iter} Newton iterations; JAX on {jax.default_backend()}, tangents factorised by "
            f"{linalg.solver_choice()} (JAXNET_SPARSE_SOLVER)\n")
    print("| " + " | ".join(columns) + " |\n|" + "---|" * len(columns))
    sizes = args.cases if args.scene == "femnet" else [str(n) for n in args.sizes]
    for size, method in ((size, method) for size in sizes for method in args.methods):
        extra = [] if args.ea_compression is None else ["--ea-compression", str(args.ea_compression)]
        extra += [] if method is None else ["--method", method]
        out = subprocess.run([sys.executable, __file__, "--one", size, "--scene", args.scene, "--current",
                              str(args.current), "--max-iter", str(args.max_iter), "--trawl", args.trawl, *extra],
                             capture_output=True, text=True)
        if out.returncode != 0:
            print(f"| {size} | failed: {out.stderr.strip().splitlines()[-1] if out.stderr else out.returncode} |")
            continue
        r = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(r)
        stop = "" if r["reason"] == "converged" else f" ({r['reason']})"
        print(f"| {r['case']}{stop} | {r['nodes']} | {r['dof']} | {r['nnz']} | {r['compile_s']:.2f} | "
              f"{r['iterations']} | "
              f"{r['factorisations']} | {r['assembly_s']:.4f} | {r['factor_s']:.4f} | {r['iteration_s']:.4f} | "
              f"{r['per_iteration']:.2f} | {r['ratio']:.2f} | {r['residual_N']:.2e} | {r['peak_MB']:.0f} |", flush=True)
    if len(rows) >= 2 and args.scene != "femnet" and len(args.methods) == 1:
        n = np.log([r["nodes"] for r in rows])
        print()
        for key in ("assembly_s", "factor_s", "iteration_s", "run_s", "compile_s", "peak_MB"):
            slope = np.polyfit(n, np.log([r[key] for r in rows]), 1)[0]
            print(f"growth exponent of {key}: {slope:.2f}")


if __name__ == "__main__":
    main()
