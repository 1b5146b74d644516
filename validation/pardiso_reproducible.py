"""PARDISO's reproducible mode (oneMKL's CNR, :data:`jaxnet.linalg.pardiso.CNR`) against MKL's default: cost and bits.

    python validation/pardiso_reproducible.py [--step 0.2] [--current 0.5] [--repeat 2]

The fish cage (:func:`jaxnet.scenes.fish_cage` at the meshing step given) solved from its drawn shape, in a fresh
process per run, alternately with jaxnet's default (``MKL_CBWR=AUTO``, set when jaxnet loads MKL) and with MKL's
default (``MKL_CBWR`` empty: no reproducible mode), ``--repeat`` times each: per run the iterations, the warm wall
time of the second solve in the process and its factorisation time (``Timing.factorisation_s``), and whether the
two solves of the process gave the same positions to the last bit (and how far apart they are otherwise, m).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys


def one(step, current):
    """Two solves of the cage in this process: the second's figures, and how the two differ."""
    import time

    import numpy as np

    import jaxnet as jn
    from jaxnet.scenes import fish_cage

    scene = fish_cage(step=step, current=current).scene
    first = jn.solve_static(scene, throw=False)
    t0 = time.perf_counter()
    second = jn.solve_static(scene, throw=False)
    warm = time.perf_counter() - t0
    difference = float(np.abs(np.asarray(first.x) - np.asarray(second.x)).max())
    return {"nodes": scene.n_nodes, "iterations": [int(first.iterations), int(second.iterations)], "warm_s": warm,
            "factorisation_s": second.timing.factorisation_s, "difference_m": difference,
            "mode": os.environ.get("MKL_CBWR", "")}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--step", type=float, default=0.2, help="the cage's meshing step (m)")
    parser.add_argument("--current", type=float, default=0.5, help="current speed (m/s)")
    parser.add_argument("--repeat", type=int, default=2, help="runs of each mode, alternated")
    parser.add_argument("--one", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.step, args.current)), flush=True)
        return
    print(f"fish cage, meshing step {args.step} m, current {args.current} m/s; each row a fresh process")
    print("| MKL_CBWR | nodes | iterations (1st, 2nd solve) | warm s | factorisation s | two solves bitwise equal "
          "| largest difference m |")
    print("|---|---|---|---|---|---|---|")
    for _ in range(args.repeat):
        for mode in ("AUTO", ""):
            env = {**os.environ, "MKL_CBWR": mode}
            run = subprocess.run([sys.executable, __file__, "--one", "--step", str(args.step), "--current",
                                  str(args.current)], capture_output=True, text=True, env=env)
            lines = [line for line in run.stdout.splitlines() if line.startswith("{")]
            if run.returncode or not lines:
                print(f"| {mode or '(empty)'} | failed: {(run.stderr or run.stdout).strip().splitlines()[-1:]} |")
                continue
            r = json.loads(lines[-1])
            print(f"| {mode or '(empty: MKL default)'} | {r['nodes']} | {r['iterations'][0]}, {r['iterations'][1]} "
                  f"| {r['warm_s']:.2f} | {r['factorisation_s']:.2f} | {r['difference_m'] == 0.0} "
                  f"| {r['difference_m']:.1e} |", flush=True)


if __name__ == "__main__":
    main()
