"""What a design gradient costs against one forward solve, compiled and run, in one process and the next (issue 28).

The targets: one gradient of an objective of the equilibrium runs in at most 2x one forward solve once
compiled; the first gradient of a scene compiles in at most 2x the forward solve's compilation; compiled
programs are reused across processes as the static solver's are. Two paths to the gradient, a table each:

* ``host``: :class:`jaxnet.design.gradient.Sensitivity` (what ``optimize`` calls): the forward solve is its
  ``value``, the gradient its ``value_and_grad``, both driven from Python over compiled programs that hold no
  host callback. Its "compilation" is the first call less a run from the same start (every program looked up
  or compiled, and the first call's set-up); HLO instruction counts are not given (several programs).
* ``jax``: ``jax.jit`` of ``θ -> objective(implicit.equilibrium(scene(θ)))`` or of its ``jax.value_and_grad``,
  compiled ahead of time (trace, lower, compile), one program each.

For each scene, objective and design space θ (the panel cuts, or every family of
:class:`jaxnet.design.space.DesignSpace`), a first process solves the reference and the design θ₁ one
optimisation step away (every cut 1 % larger, and with all families every twine diameter and EA 2 % up) with
the static solver, without a cache directory, and writes the two equilibria; then a worker process per figure
(a fresh one each, nothing compiled in it before) builds the design space, compiles forward or gradient and
times runs of it at θ₁ (median of ``REPEATS``) from two starts:

* warm: the static solver's equilibrium of θ₁ (its tolerance 1e-3 N: one or two Newton steps to 1e-8 N);
* perturbed: the reference's equilibrium (a few Newton iterations: an optimisation step).

Each worker runs twice with one JAX compilation cache directory (a new temporary one per benchmark run): the
second process's compilation is what reuse across processes gives. Columns: nodes, design parameters;
forward and gradient runs (ms) and their ratio, warm and perturbed (Newton iterations); forward and gradient
compilation (s) and their ratio, with the compiled programs' HLO instruction counts (a measure of the
program that does not vary with the machine's load); the second process's compilations (s).

    python benchmarks/design.py [--quick] [--path host|jax|both] [--implicit PATH]

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


def _design(space, families):
    """θ₁: every cut 1 % larger (and with all families every twine diameter and EA 2 % up)."""
    import numpy as np

    theta0 = space.initial()
    theta1 = dict(theta0, cut={k: 1.01 * np.asarray(v) for k, v in theta0["cut"].items()})
    if families == "all":
        return dict(theta1, twine_diameter={k: 1.02 * v for k, v in theta0["twine_diameter"].items()},
                    ea={k: 1.02 * v for k, v in theta0["ea"].items()})
    return {"cut": theta1["cut"]}


def prepare(scene_name, families, path):
    """The starts (the reference's and θ₁'s equilibria by the static solver) into ``path`` (.npz), in a process
    of their own without a cache directory: the workers then start with nothing compiled."""
    import numpy as np

    from jaxnet.design import space as space_lib
    from jaxnet.solve import statics

    space = space_lib.DesignSpace(_net(scene_name))
    np.savez(path, perturbed=np.asarray(statics.solve(space.reference).x),
             warm=np.asarray(statics.solve(space.scene(_design(space, families))).x))


def worker(scene_name, objective, families, mode, implicit_path, starts):
    """One figure in this process: compile ``mode`` (PATH-forward or PATH-gradient, PATH "jax" or "host") and
    time its runs; a JSON line."""
    import jax
    import numpy as np

    from jaxnet.design import gradient, objectives, space as space_lib

    path, mode = mode.split("-")
    space = space_lib.DesignSpace(_net(scene_name))
    theta1 = _design(space, families)
    starts = dict(np.load(starts))
    figure = {"volume": objectives.volume(), "drag": objectives.drag()}[objective]
    out = {"nodes": int(space.reference.n_nodes),
           "parameters": int(sum(np.size(leaf) for leaf in jax.tree.leaves(theta1)))}
    if path == "jax":
        implicit = _implicit(implicit_path)
        structure = implicit.structure_of(space.reference)

        def solve(theta, start):
            scene = space.scene(theta)
            eq = implicit.equilibrium(scene, structure, x0=start)
            return figure(objectives.Outcome(eq.x, scene, structure.model)), eq.iterations

        function = jax.jit(solve) if mode == "forward" else jax.jit(jax.value_and_grad(solve, has_aux=True))
        t = time.perf_counter()
        compiled = function.trace(theta1, starts["warm"]).lower().compile()
        out.update(compile_s=time.perf_counter() - t, instructions=_instructions(compiled))

        def run(start):
            result = jax.block_until_ready(compiled(theta1, start))
            return int(result[1] if mode == "forward" else result[0][1])
    else:
        sensitivity = gradient.Sensitivity(space, figure)
        call = sensitivity.value if mode == "forward" else sensitivity.value_and_grad

        def run(start):
            evaluation = call(theta1, start)
            jax.block_until_ready(evaluation.grad)
            return evaluation.iterations

        # the first call compiles every program (or loads it) and runs once: its compilation is the first call
        # less a run from the same start
        t = time.perf_counter()
        run(starts["warm"])
        out.update(first_s=time.perf_counter() - t, instructions=None)
    for start_name in ("warm", "perturbed"):
        iterations = run(starts[start_name])
        times = []
        for _ in range(REPEATS):
            t = time.perf_counter()
            run(starts[start_name])
            times.append(time.perf_counter() - t)
        out[start_name] = {"run_ms": 1e3 * statistics.median(times), "iterations": iterations}
    if path == "host":
        out["compile_s"] = out.pop("first_s") - out["warm"]["run_ms"] / 1e3
    print("RESULT " + json.dumps(out), flush=True)


def _run(command, env):
    done = subprocess.run(command, env=env, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"worker {command} failed:\n{done.stderr[-3000:]}")
    return done.stdout


def _run_worker(case, mode, cache, implicit_path, starts):
    _, scene_name, objective, families = case
    env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=str(cache), JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0",
               JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES="0")
    command = [sys.executable, __file__, "--worker", scene_name, objective, families, mode, str(starts)]
    if implicit_path:
        command += ["--implicit", implicit_path]
    for line in _run(command, env).splitlines():
        if line.startswith("RESULT "):
            return json.loads(line[len("RESULT "):])
    raise RuntimeError(f"worker {command} printed no result")


def main(quick=False, implicit_path=None, paths=("host", "jax")):
    cases = QUICK if quick else CASES
    without_cache = {k: v for k, v in os.environ.items() if k != "JAX_COMPILATION_CACHE_DIR"}
    with tempfile.TemporaryDirectory(prefix="jaxnet-design-cost-") as work:
        work = pathlib.Path(work)
        starts = {}
        for case in cases:
            key = (case[1], case[3])
            if key not in starts:
                starts[key] = work / f"starts-{case[1]}-{case[3]}.npz"
                _run([sys.executable, __file__, "--prepare", case[1], case[3], str(starts[key])], without_cache)
        for path in paths:
            print(f"\n{PATHS[path]}\n")
            print("| scene | objective | θ | nodes | parameters | warm: forward, gradient (ms), ratio (Newton it.) "
                  "| perturbed: forward, gradient (ms), ratio (Newton it.) | compile forward, gradient (s), ratio "
                  "| HLO instructions forward, gradient | 2nd process: compile forward, gradient (s) |")
            print("|---|---|---|---|---|---|---|---|---|---|")
            for case in cases:
                cache = work / f"cache-{path}-{case[1]}-{case[2]}-{case[3]}"
                start = starts[(case[1], case[3])]
                modes = (f"{path}-forward", f"{path}-gradient")
                first = {m: _run_worker(case, m, cache, implicit_path, start) for m in modes}
                second = {m: _run_worker(case, m, cache, implicit_path, start) for m in modes}
                f, g = first[modes[0]], first[modes[1]]
                runs = []
                for name in ("warm", "perturbed"):
                    a, b = f[name], g[name]
                    runs.append(f"{a['run_ms']:.1f}, {b['run_ms']:.1f}, {b['run_ms'] / a['run_ms']:.2f}x "
                                f"({a['iterations']})")
                hlo = "-" if f["instructions"] is None else f"{f['instructions']}, {g['instructions']}"
                print(f"| {case[0]} | {case[2]} | {case[3]} | {f['nodes']} | {f['parameters']} | {runs[0]} | "
                      f"{runs[1]} | {f['compile_s']:.1f}, {g['compile_s']:.1f}, "
                      f"{g['compile_s'] / f['compile_s']:.2f}x | {hlo} | "
                      f"{second[modes[0]]['compile_s']:.1f}, {second[modes[1]]['compile_s']:.1f} |", flush=True)


#: the two ways to a design gradient, as the tables are titled
PATHS = {"host": "Host-driven adjoint (jaxnet.design.gradient: what optimize calls)",
         "jax": "jax.value_and_grad through jaxnet.solve.implicit.equilibrium (one jitted program)"}


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the cage at step 1.6 m and the trawl's cuts only")
    parser.add_argument("--path", choices=("host", "jax", "both"), default="both",
                        help="which gradient to time (default both)")
    parser.add_argument("--implicit", help="a file holding another version of jaxnet/solve/implicit.py to time")
    parser.add_argument("--worker", nargs=5, metavar=("SCENE", "OBJECTIVE", "FAMILIES", "MODE", "STARTS"),
                        help=argparse.SUPPRESS)
    parser.add_argument("--prepare", nargs=3, metavar=("SCENE", "FAMILIES", "STARTS"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(*args.worker[:4], args.implicit, args.worker[4])
    elif args.prepare:
        prepare(*args.prepare)
    else:
        main(args.quick, args.implicit, ("host", "jax") if args.path == "both" else (args.path,))
