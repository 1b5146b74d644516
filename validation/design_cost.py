"""What a design gradient costs against one forward solve, compiled and run, in one process and the next (issue 28).

The targets: one gradient (``jax.value_and_grad`` of an objective of the equilibrium) runs in at most 2x one
forward solve once compiled; the first gradient of a scene compiles in at most 2x the forward solve's
compilation; compiled programs are reused across processes as the static solver's are.

For each scene, objective and design space θ (the panel cuts, or every family of
:class:`jaxnet.design.space.DesignSpace`), a worker process (a fresh one for each figure, so that no program
or trace of another figure is in memory) builds the design space, solves the reference and the design θ₁ one
optimisation step away (every cut 1 % larger, and with all families every twine diameter and EA 2 % up) with
the static solver (:func:`jaxnet.solve.statics.solve`, whose programs the persistent cache keeps), then
compiles ahead of time (trace, lower, compile: the first call's cost less its run) either the forward solve
``θ -> objective(equilibrium(scene(θ)))`` or its ``value_and_grad``, and times runs of it at θ₁ (median of
``REPEATS``) from two starts:

* warm: the static solver's equilibrium of θ₁ (its tolerance 1e-3 N: one or two Newton steps to 1e-8 N);
* perturbed: the reference's equilibrium (a few Newton iterations: an optimisation step).

Each worker runs twice with one JAX compilation cache directory (a new temporary one per benchmark run): the
second process's compilation is what reuse across processes gives. Columns: nodes, design parameters;
forward and gradient runs (ms) and their ratio, warm and perturbed (Newton iterations); forward and gradient
compilation (s, trace + lower + XLA) and their ratio, with the compiled programs' HLO instruction counts
(a measure of the program that does not vary with the machine's load); the second process's compilations (s).

    python validation/design_cost.py [--quick] [--implicit PATH]

``--implicit PATH``: time another version of :mod:`jaxnet.solve.implicit` (e.g. ``git show
HEAD:jaxnet/solve/implicit.py > /tmp/implicit_before.py``), loaded in its place: before/after a change.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

REPEATS = 5

#: (label, scene, objective, θ families); the scenes are built in the workers
CASES = [
    ("cage, step 1.6 m", "cage1.6", "volume", "cut"),
    ("cage, step 1.6 m", "cage1.6", "volume", "all"),
    ("cage, step 1.6 m", "cage1.6", "drag", "cut"),
    ("cage, step 0.8 m", "cage0.8", "volume", "cut"),
    ("cage, step 0.8 m", "cage0.8", "volume", "all"),
    ("trawl b1", "trawl", "drag", "cut"),
    ("trawl b1", "trawl", "drag", "all"),
]
QUICK = [CASES[0], CASES[1], CASES[5]]

TRAWL = "/work/shared/femnet-corpus/3bottom_trawl/b1.don"


def _net(name):
    import jaxnet
    from jaxnet.scenes import cage

    if name.startswith("cage"):
        return cage.fish_cage(step=float(name[len("cage"):]))
    return jaxnet.io.femnet.read_don(os.environ.get("JAXNET_TRAWL", TRAWL))


def _implicit(path):
    """jaxnet.solve.implicit, or the version of it in the file ``path``."""
    from jaxnet.solve import implicit

    if not path:
        return implicit
    import importlib.util

    spec = importlib.util.spec_from_file_location("jaxnet.solve.implicit_under_test", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def _instructions(compiled):
    """The number of instructions of a compiled program's optimised HLO."""
    return sum(1 for line in compiled.as_text().splitlines() if " = " in line)


def worker(scene_name, objective, families, mode, implicit_path):
    """One figure in this process: compile ``mode`` ("forward" or "gradient") and time its runs; a JSON line."""
    import jax
    import numpy as np

    from jaxnet.design import objectives, space as space_lib
    from jaxnet.solve import statics

    implicit = _implicit(implicit_path)
    space = space_lib.DesignSpace(_net(scene_name))
    structure = implicit.structure_of(space.reference)
    theta0 = space.initial()
    theta1 = dict(theta0, cut={k: 1.01 * np.asarray(v) for k, v in theta0["cut"].items()})
    if families == "all":
        theta1 = dict(theta1, twine_diameter={k: 1.02 * v for k, v in theta0["twine_diameter"].items()},
                      ea={k: 1.02 * v for k, v in theta0["ea"].items()})
    else:
        theta1 = {"cut": theta1["cut"]}
    x_reference = np.asarray(statics.solve(space.reference).x)
    x_warm = np.asarray(statics.solve(space.scene(theta1)).x)
    figure = {"volume": objectives.volume(), "drag": objectives.drag()}[objective]

    def solve(theta, start):
        scene = space.scene(theta)
        eq = implicit.equilibrium(scene, structure, x0=start)
        return figure(objectives.Outcome(eq.x, scene, structure.model)), eq.iterations

    function = jax.jit(solve) if mode == "forward" else jax.jit(jax.value_and_grad(solve, has_aux=True))
    t = time.perf_counter()
    compiled = function.trace(theta1, x_warm).lower().compile()
    compile_s = time.perf_counter() - t
    out = {"compile_s": compile_s, "instructions": _instructions(compiled),
           "nodes": int(space.reference.n_nodes),
           "parameters": int(sum(np.size(leaf) for leaf in jax.tree.leaves(theta1)))}
    for start_name, start in (("warm", x_warm), ("perturbed", x_reference)):
        result = jax.block_until_ready(compiled(theta1, start))
        iterations = result[1] if mode == "forward" else result[0][1]
        times = []
        for _ in range(REPEATS):
            t = time.perf_counter()
            jax.block_until_ready(compiled(theta1, start))
            times.append(time.perf_counter() - t)
        out[start_name] = {"run_ms": 1e3 * statistics.median(times), "iterations": int(iterations)}
    print("RESULT " + json.dumps(out), flush=True)


def _run_worker(case, mode, cache, implicit_path):
    _, scene_name, objective, families = case
    env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=str(cache), JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0",
               JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES="0")
    command = [sys.executable, __file__, "--worker", scene_name, objective, families, mode]
    if implicit_path:
        command += ["--implicit", implicit_path]
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    for line in done.stdout.splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT "):])
    raise RuntimeError(f"worker {command} failed:\n{done.stderr[-3000:]}")


def main(quick=False, implicit_path=None):
    cases = QUICK if quick else CASES
    print("| scene | objective | θ | nodes | parameters | warm: forward, gradient (ms), ratio (Newton it.) "
          "| perturbed: forward, gradient (ms), ratio (Newton it.) | compile forward, gradient (s), ratio "
          "| HLO instructions forward, gradient | 2nd process: compile forward, gradient (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="jaxnet-design-cost-") as cache:
        for case in cases:
            cache_of_case = pathlib.Path(cache) / f"{case[1]}-{case[2]}-{case[3]}"
            first = {mode: _run_worker(case, mode, cache_of_case, implicit_path) for mode in ("forward", "gradient")}
            second = {mode: _run_worker(case, mode, cache_of_case, implicit_path) for mode in ("forward", "gradient")}
            f, g = first["forward"], first["gradient"]
            runs = []
            for start in ("warm", "perturbed"):
                a, b = f[start], g[start]
                runs.append(f"{a['run_ms']:.1f}, {b['run_ms']:.1f}, {b['run_ms'] / a['run_ms']:.2f}x "
                            f"({a['iterations']})")
            print(f"| {case[0]} | {case[2]} | {case[3]} | {f['nodes']} | {f['parameters']} | {runs[0]} | {runs[1]} | "
                  f"{f['compile_s']:.1f}, {g['compile_s']:.1f}, {g['compile_s'] / f['compile_s']:.2f}x | "
                  f"{f['instructions']}, {g['instructions']} | "
                  f"{second['forward']['compile_s']:.1f}, {second['gradient']['compile_s']:.1f} |", flush=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the cage at step 1.6 m and the trawl's cuts only")
    parser.add_argument("--implicit", help="a file holding another version of jaxnet/solve/implicit.py to time")
    parser.add_argument("--worker", nargs=4, metavar=("SCENE", "OBJECTIVE", "FAMILIES", "MODE"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(*args.worker, args.implicit)
    else:
        main(args.quick, args.implicit)
