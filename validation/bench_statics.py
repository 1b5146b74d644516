"""Benchmark of the static solver: panels of 10² to 10⁵ nodes under weight, from the flat stress-free start.

    python validation/bench_statics.py [--sizes 100 1000 10000 100000] [--scene framed|hanging]
                                       [--ea-compression EA_C]

Scenes (jaxnet.scenes.panel): ``framed`` — a horizontal panel of 100 x 100 meshes held along its border,
sagging under its weight and a 20 kg sinker (twines EA_c = 0 by default: slack allowed); ``hanging`` — the
default scene, a curtain of 100 x 100 meshes hanging from a headline with a sinker bar (twines EA_c = EA
by default). The meshing step sets the node count.

Each size runs in its own process (so that peak memory is that size's). Printed per size: nodes, unknowns,
tangent non-zeros, compile time, Newton iterations, time of one tangent assembly and of one sparse
factorisation + solve at the solution, total solve time, total / (iterations x factorisation), peak resident
memory; then the growth exponents (least squares of log cost against log nodes).
"""

from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import time


def one(n_target, scene_name, ea_compression):
    import jax
    import numpy as np

    import jaxnet as jn
    from jaxnet import assemble, linalg, model
    from jaxnet.net import Twine
    from jaxnet.scenes.panel import framed_panel, hanging_panel

    meshes, l0 = 100, 0.025
    width = meshes * l0 * np.sqrt(2.0)
    step = width / np.sqrt(n_target / 1.15)  # the mesher's lattice holds about 1.15 nodes per step²
    if ea_compression is None:
        ea_compression = 0.0 if scene_name == "framed" else 2000.0
    twine = Twine(l0=l0, ea=2000.0, diameter=1.5e-3, ea_compression=ea_compression)
    if scene_name == "framed":
        scene = framed_panel(meshes=meshes, l0=l0, step=step, twine=twine, sinker_kg=20.0).scene
    else:
        scene = hanging_panel(meshes=meshes, l0=l0, step=step, twine=twine).scene
    eq = jn.solve_static(scene, max_iter=200)
    timing = eq.timing
    m = model.active_terms(scene)
    pattern = assemble.build_pattern(scene, m)
    tangent = jax.jit(assemble.tangent, static_argnames="model")
    data = jax.block_until_ready(tangent(eq.x, scene, model=m, pattern=pattern))
    t0 = time.perf_counter()
    for _ in range(3):
        data = jax.block_until_ready(tangent(eq.x, scene, model=m, pattern=pattern))
    t_assembly = (time.perf_counter() - t0) / 3
    rhs = np.ones(pattern.n)
    d = np.asarray(data).copy()
    d[np.asarray(pattern.diagonal)] += 1e-9 * np.abs(d).max()
    t0 = time.perf_counter()
    linalg.host_solve(d, rhs, np.asarray(pattern.indptr), np.asarray(pattern.indices))
    t_factor = time.perf_counter() - t0
    run_s = timing.wall_s - timing.compile_s
    return {
        "nodes": scene.n_nodes,
        "dof": scene.n_dof,
        "nnz": int(pattern.nnz),
        "compile_s": timing.compile_s,
        "iterations": int(eq.iterations),
        "assembly_s": t_assembly,
        "factor_s": t_factor,
        "run_s": run_s,
        "ratio": run_s / max(int(eq.iterations), 1) / t_factor,
        "residual_N": float(eq.residual_N),
        "peak_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--sizes", type=int, nargs="*", default=[100, 1000, 10000, 100000])
    parser.add_argument("--scene", choices=("framed", "hanging"), default="framed")
    parser.add_argument("--ea-compression", type=float, default=None, help="twine EA_c (N); default per scene")
    parser.add_argument("--one", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one, args.scene, args.ea_compression)))
        return
    import numpy as np

    rows = []
    head = f"{'nodes':>7} {'dof':>7} {'nnz':>9} {'compile s':>9} {'iter':>4} {'assembly s':>10} {'factor s':>9} {'total s':>8} {'tot/(it*fac)':>12} {'residual N':>10} {'peak MB':>8}"
    print(f"{args.scene} panel, flat stress-free start, twine EA_c = {args.ea_compression if args.ea_compression is not None else 'scene default'} N")
    print(head)
    for n in args.sizes:
        extra = [] if args.ea_compression is None else ["--ea-compression", str(args.ea_compression)]
        out = subprocess.run([sys.executable, __file__, "--one", str(n), "--scene", args.scene, *extra],
                             capture_output=True, text=True)
        if out.returncode != 0:
            print(f"{n:>7} failed: {out.stderr.strip().splitlines()[-1] if out.stderr else out.returncode}")
            continue
        r = json.loads(out.stdout.strip().splitlines()[-1])
        rows.append(r)
        print(f"{r['nodes']:>7} {r['dof']:>7} {r['nnz']:>9} {r['compile_s']:>9.2f} {r['iterations']:>4} {r['assembly_s']:>10.4f} "
              f"{r['factor_s']:>9.4f} {r['run_s']:>8.2f} {r['ratio']:>12.2f} {r['residual_N']:>10.2e} {r['peak_MB']:>8.0f}", flush=True)
    if len(rows) >= 2:
        n = np.log([r["nodes"] for r in rows])
        for key in ("assembly_s", "factor_s", "run_s", "compile_s", "peak_MB"):
            slope = np.polyfit(n, np.log([r[key] for r in rows]), 1)[0]
            print(f"growth exponent of {key}: {slope:.2f}")


if __name__ == "__main__":
    main()
