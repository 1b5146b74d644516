"""XLA's CPU options on jaxnet's programs: compilation and run time with and without ``programs.COMPILER_OPTIONS``.

    python validation/compile_options.py [--cases nr_netting c2 cage] [--runs 30]

For each case (FEMNET's cases on their own meshes; ``cage``: the cage in waves meshed at 1.6 m, at rest) the
static solver's programs, the evaluation of the residual, the closed-form tangent's element matrices (the
host loop's "tangent") and the whole tangent summed into the pattern (the jitted loop's, one program), are
traced once and compiled in this process with three settings: XLA's default options; XLA's older
elemental emitter instead of its MLIR "fusion emitters" (``xla_cpu_use_fusion_emitters=False``); and
that plus no YNNPACK fusions (``xla_cpu_experimental_ynn_fusion_type=""``), which is
:data:`jaxnet.solve.programs.COMPILER_OPTIONS`. Each compiled program is then run ``--runs`` times at the
case's start, the settings in turn, and the median is printed (ms), with the compile times (s) and each
setting's ratio to jaxnet's. Nothing is asserted: it is the measurement behind ``COMPILER_OPTIONS``.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxnet  # noqa: F401  (float64)
from jaxnet import model as model_lib
from jaxnet.model import assemble
from jaxnet.solve import kernel, programs

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "femnet"
SETTINGS = {"XLA default": {}, "elemental": {"xla_cpu_use_fusion_emitters": False},
            "jaxnet": programs.COMPILER_OPTIONS}


def scene_of(case):
    if case == "cage":
        from jaxnet.scenes import cage_in_waves

        return cage_in_waves(step=1.6).scene
    from jaxnet.io import femnet

    return femnet.read_mdg(DATA / f"{case}.mdg", DATA / f"{case}.don").scene


def programs_of(scene):
    """{name: (traced program, its arguments)} of the evaluation, the closed-form tangent's element matrices
    and the whole closed-form tangent, at the start."""
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    x = jnp.asarray(np.asarray(scene.nodes.position).ravel()[np.asarray(pattern.free)])
    zero = jnp.zeros(scene.nodes.position.shape)
    evaluate_args = (x, zero, zero, 1.0, scene, pattern)
    evaluate = jax.jit(kernel.evaluate, static_argnames=("model",)).trace(*evaluate_args, model=model)
    # placeholders for the catch's state (not computed: that would compile the evaluation once more)
    state = jax.tree.map(lambda s: jnp.zeros(s.shape, s.dtype), evaluate.out_info[4])
    tangent_args = (x, state, 1.0, scene, pattern)
    blocks = jax.jit(kernel.tangent_blocks, static_argnames=("model", "stiffness")).trace(
        *tangent_args, model=model, stiffness="closed_form")
    tangent = jax.jit(kernel.tangent, static_argnames=("model", "stiffness")).trace(
        *tangent_args, model=model, stiffness="closed_form")
    return {"evaluate": (evaluate, evaluate_args), "blocks": (blocks, tangent_args),
            "tangent": (tangent, tangent_args)}


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
    names = list(SETTINGS)
    reference = names[-1]
    ratios = " ".join(f"{n + ' / jaxnet':>21s}" for n in names[:-1])
    print(f"{'case':11s} {'program':8s} | compile (s): {' '.join(f'{n:>11s}' for n in names)} {ratios} | "
          f"run (ms): {' '.join(f'{n:>11s}' for n in names)} {ratios}", flush=True)
    for case in args.cases:
        for k, (name, (traced, call_args)) in enumerate(programs_of(scene_of(case)).items()):
            lowered = traced.lower()
            compiled, compile_s = {}, {}
            # the settings compiled in a rotating order from one program to the next: the first compilation
            # of a process pays for warming XLA up
            for setting in names[k % len(names):] + names[:k % len(names)]:
                t0 = time.perf_counter()
                compiled[setting] = lowered.compile(SETTINGS[setting])
                compile_s[setting] = time.perf_counter() - t0
            run_ms = {setting: [] for setting in names}
            for _ in range(3):  # the settings in turn, so that a busy moment hits all
                for setting in names:
                    run_ms[setting].append(median_ms(compiled[setting], call_args, args.runs))
            run = {setting: float(np.median(v)) for setting, v in run_ms.items()}
            print(f"{case:11s} {name:8s} | {'':13s}{' '.join(f'{compile_s[n]:11.2f}' for n in names)} "
                  f"{' '.join(f'{compile_s[n] / compile_s[reference]:21.2f}' for n in names[:-1])} | {'':9s} "
                  f"{' '.join(f'{run[n]:11.2f}' for n in names)} "
                  f"{' '.join(f'{run[n] / run[reference]:21.2f}' for n in names[:-1])}", flush=True)


if __name__ == "__main__":
    main()
