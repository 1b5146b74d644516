"""XLA's CPU emitters on jaxnet's programs: compilation and run time with and without ``programs.COMPILER_OPTIONS``.

    python validation/compile_options.py [--cases nr_netting c2 cage] [--runs 30]

For each case (FEMNET's cases on their own meshes; ``cage``: the cage in waves meshed at 1.6 m, at rest) the
static solver's two programs, the evaluation of the residual and the closed-form tangent, are traced once
and compiled twice in this process: with XLA's default options (its MLIR "fusion emitters") and with
:data:`jaxnet.solve.programs.COMPILER_OPTIONS` (its older elemental emitter), the settings taken in turn.
Each compiled program is then run ``--runs`` times at the case's start, alternately with its twin, and the
median is printed (ms), with the compile times (s) and the ratios default / jaxnet side by side. Nothing
is asserted: it is the measurement behind ``COMPILER_OPTIONS``.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxnet  # noqa: F401  (float64)
from jaxnet import assemble, model as model_lib
from jaxnet.solve import programs, statics

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "femnet"
SETTINGS = {"XLA default": {}, "jaxnet": programs.COMPILER_OPTIONS}


def scene_of(case):
    if case == "cage":
        from jaxnet.scenes import cage_in_waves

        return cage_in_waves(step=1.6)[0]
    from jaxnet.io import femnet

    return femnet.read_mdg(DATA / f"{case}.mdg", DATA / f"{case}.don")[0]


def programs_of(scene):
    """{name: (traced program, its arguments)} of the evaluation and the closed-form tangent at the start."""
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    x = jnp.asarray(np.asarray(scene.nodes.position).ravel()[np.asarray(pattern.free)])
    zero = jnp.zeros(scene.nodes.position.shape)
    evaluate_args = (x, zero, zero, 1.0, scene, pattern)
    evaluate = jax.jit(statics._evaluate, static_argnames=("model",)).trace(*evaluate_args, model=model)
    # placeholders for the catch's state (not computed: that would compile the evaluation once more)
    state = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), evaluate.out_info[4])
    tangent_args = (x, state, 1.0, scene, pattern)
    tangent = jax.jit(statics._tangent, static_argnames=("model", "stiffness")).trace(
        *tangent_args, model=model, stiffness="closed_form")
    return {"evaluate": (evaluate, evaluate_args), "tangent": (tangent, tangent_args)}


def median_ms(program, args, runs):
    jax.block_until_ready(program(*args))
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        jax.block_until_ready(program(*args))
        times.append(time.perf_counter() - t0)
    return 1e3 * float(np.median(times))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", nargs="+", default=["nr_netting", "c2", "cage"])
    parser.add_argument("--runs", type=int, default=30)
    args = parser.parse_args(argv)
    print(f"{'case':11s} {'program':9s} | {'compile (s): default':>20s} {'jaxnet':>7s} {'ratio':>6s} | "
          f"{'run (ms): default':>17s} {'jaxnet':>7s} {'ratio':>6s}", flush=True)
    for case in args.cases:
        for name, (traced, call_args) in programs_of(scene_of(case)).items():
            lowered = traced.lower()
            compiled, compile_s = {}, {}
            # the settings compiled in alternate orders from one program to the next: the first compilation
            # of a process pays for warming XLA up
            order = list(SETTINGS.items())
            for setting, options in (order if name == "evaluate" else order[::-1]):
                t0 = time.perf_counter()
                compiled[setting] = lowered.compile(options)
                compile_s[setting] = time.perf_counter() - t0
            run_ms = {setting: [] for setting in SETTINGS}
            for _ in range(3):  # the settings in turn, so that a busy moment hits both
                for setting in SETTINGS:
                    run_ms[setting].append(median_ms(compiled[setting], call_args, args.runs))
            run = {setting: float(np.median(v)) for setting, v in run_ms.items()}
            a, b = SETTINGS
            print(f"{case:11s} {name:9s} | {compile_s[a]:20.2f} {compile_s[b]:7.2f} {compile_s[a] / compile_s[b]:6.2f} | "
                  f"{run[a]:17.2f} {run[b]:7.2f} {run[a] / run[b]:6.2f}", flush=True)


if __name__ == "__main__":
    main()
