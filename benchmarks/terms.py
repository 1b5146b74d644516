"""Benchmark of the default scene (the fish cage in current) and of what each physical term costs.

    python benchmarks/terms.py [--steps 0.8 0.5 0.3] [--terms-step STEP] [--repeats 11]
                                     [--compile-repeats 3] [--only sizes|terms]

The scene is :func:`jaxnet.scenes.cage.fish_cage` with its defaults, meshed at the given steps (m): the
meshing step sets the node count, nothing else changes. Everything is timed with wall clocks on the
machine as it is (the load averages are printed before and after: on a shared machine, read the numbers
as ratios measured side by side in one run, not as absolute figures). Nothing is asserted.

1. Sizes. Each step runs in its own process, so that the peak resident memory printed is that size's.
   The scene is solved from its start shape by :func:`jaxnet.solve_static` (the Newton program's compile time
   is reported apart from its run time). At the solution are then timed:
     * assembly: one call of a jitted function computing the tangent (``assemble.tangent``) and the
       out-of-balance force (``assemble.nodal_force``) together, compiled before timing, median of
       ``--repeats`` calls;
     * linear solve in the loop: every factorisation + solve of the static solve's host loop
       (``linalg.HostSolver.solve``, wrapped by a timer for this solve), mean per call: the loop factorises
       K + mu S, the tangent damped by the spring network;
     * linear solve at the solution: one sparse LU factorisation + solve of the undamped tangent at the
       solution (diagonal raised by 1e-9 x max|K|, as in statics.py), median of ``--repeats``.
       This undamped matrix can need off-diagonal pivots where the damped ones of the loop do not (at
       the cage's solution, when this was written: a slightly indefinite symmetric part, rows whose
       diagonal is under a tenth of their largest entry), and then fills and costs more: both are printed;
     * per iteration: the solve's run time / Newton iterations; "rest" = per iteration - assembly -
       linear solve in the loop, i.e. the line search's energy and force evaluations and the loop's work
       (on small nets it can come out negative: the standalone assembly call pays a dispatch and a
       transfer of its result that the jitted loop does not).
   Then the growth exponents: least-squares slope of log(cost) against log(nodes).

2. Terms, at one refinement (the middle step by default), in one process, at the solution of the cage:
     * the assembly (as above: tangent + force, jitted, median of ``--repeats`` calls) with all the
       cage's active terms (``model.active_terms``), then with each term removed in turn (the model
       tuple without that ``ActiveTerm``; the sparsity pattern and the constant loads rebuilt for that
       model, as a solve would). The difference to the full assembly is that term's cost; its share is
       the difference over the full time. What no single term accounts for (gathers, scatters, the
       vmaps' fixed cost, and the sharing XLA finds between terms) is printed as "not attributed".
     * the same with a term the cage does not use switched on: the cage rebuilt with its twine given
       mesh opening stiffness, a knot size (knot contact), a bending stiffness (twine bending hinges),
       or a screen drag model in place of the per-twine drag, assembled at the same node positions.
     * for each, the compile time of that assembly (trace + lowering + XLA compile of a freshly made
       jitted function, so that no cache serves a later compile; median of ``--compile-repeats``).
   All these cases are compiled, then run, round-robin (one of each in turn, ``--repeats`` rounds), so
   that a change in the machine's load spreads over all of them; a first round of compiles, discarded,
   fills JAX's caches (the first trace of a term can cost more than the next ones). The spread (min-max)
   of the full assembly's runs and compiles is printed as a measure of the noise.
   The option values (OPTIONS below) are representative of a 2.5 mm polyamide twine; the cost of an
   assembly does not depend on them, only on which terms are traced.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

#: terms the cage does not use, as Twine fields a user can set: (row label, field, value, unit)
OPTIONS = (
    ("mesh opening", "opening_stiffness", 1e-3, "N·m/rad"),
    ("knot contact", "knot_size", 5e-3, "m"),
    ("twine bending", "bending_stiffness", 2e-4, "N·m²"),
    ("Løland screen drag", "drag_model", "loland", ""),
    ("Kristiansen-Faltinsen screen drag", "drag_model", "kristiansen-faltinsen", ""),
)


def _peak_mb():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024  # ru_maxrss is in KiB on Linux


def _median_time(fn, repeats):
    """Median wall time (s) of ``repeats`` calls of ``fn`` (which must block until its result is ready)."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _assembly(x, scene, pattern, load, model):
    """What every Newton iteration assembles: the tangent's CSR entries and the out-of-balance force."""
    from jaxnet.model import assemble

    return assemble.tangent(x, scene, model, pattern), assemble.nodal_force(x, scene, model, load)


def _compile_assembly(x, scene, pattern, load, model):
    """Freshly traced, lowered and compiled assembly for ``model``; returns (executable, seconds)."""
    import functools

    import jax

    # a new function object each time: nothing cached from an earlier compile of the same model serves it
    fn = jax.jit(functools.partial(_assembly, model=model))
    t0 = time.perf_counter()
    executable = fn.lower(x, scene, pattern, load).compile()
    return executable, time.perf_counter() - t0


def _prepare(x, scene, model):
    """Everything an assembly of ``scene`` with ``model`` at x needs, the pattern and loads built for that model."""
    from jaxnet.model import assemble

    pattern = assemble.build_pattern(scene, model)
    return {"args": (x, scene, pattern, assemble.loads(scene, model)), "model": model, "nnz": int(pattern.nnz)}


def _time_assemblies(cases, repeats, compile_repeats):
    """Compile time and run time (medians) of the assembly of every case (see :func:`_prepare`).

    Compiles and runs go round-robin over the cases, so that a change of the machine's load during the
    benchmark spreads over all of them instead of biasing the ones timed at that moment; the first
    compile of every case (it also fills JAX's caches of the functions the terms call) is discarded.
    """
    import jax

    for case in cases:  # warm-up round, discarded: the first trace of each term fills JAX's inner caches
        _compile_assembly(*case["args"], case["model"])
    compile_s = [[] for _ in cases]
    executables = [None] * len(cases)
    for _ in range(compile_repeats):
        for k, case in enumerate(cases):
            executables[k], seconds = _compile_assembly(*case["args"], case["model"])
            compile_s[k].append(seconds)
    for executable, case in zip(executables, cases):
        jax.block_until_ready(executable(*case["args"]))  # first call: allocations, transfers
    run_s = [[] for _ in cases]
    for _ in range(repeats):
        for k, (executable, case) in enumerate(zip(executables, cases)):
            t0 = time.perf_counter()
            jax.block_until_ready(executable(*case["args"]))
            run_s[k].append(time.perf_counter() - t0)
    return [{"nnz": case["nnz"], "compile_s": statistics.median(c), "assembly_s": statistics.median(r),
             "compile_range_s": (min(c), max(c)), "assembly_range_s": (min(r), max(r))}
            for case, c, r in zip(cases, compile_s, run_s)]


def _cage(step, twine=None):
    from jaxnet.scenes.cage import fish_cage

    return fish_cage(step=step, twine=twine).scene


class _TimedSolves:
    """Times every call of ``linalg.HostSolver.solve`` (the static solve's host loop factorises and solves
    K + mu S with it at each iteration) while in use: the factorisations the loop really does, on the damped
    matrices, are timed. A context manager; ``seconds`` the wall time of each call."""

    def __init__(self, linalg):
        self.linalg, self.seconds = linalg, []

    def __enter__(self):
        original = self.original = self.linalg.HostSolver.solve
        seconds = self.seconds

        def solve(solver, *args, **kwargs):
            t0 = time.perf_counter()
            out = original(solver, *args, **kwargs)
            seconds.append(time.perf_counter() - t0)
            return out

        self.linalg.HostSolver.solve = solve
        return self

    def __exit__(self, *exc):
        self.linalg.HostSolver.solve = self.original
        return False


def one_size(step, repeats):
    """Part 1 for one meshing step (run in its own process)."""
    import jax

    import jaxnet as jn
    from jaxnet import linalg, model
    from jaxnet.model import assemble

    scene = _cage(step)
    with _TimedSolves(linalg) as timed:  # this solve's own factorisations and solves
        eq = jn.solve_static(scene, throw=False)
    timing = eq.timing
    m = model.active_terms(scene)
    pattern = assemble.build_pattern(scene, m)
    load = assemble.loads(scene, m)
    executable, _ = _compile_assembly(eq.x, scene, pattern, load, m)
    data, _ = jax.block_until_ready(executable(eq.x, scene, pattern, load))
    t_assembly = _median_time(lambda: jax.block_until_ready(executable(eq.x, scene, pattern, load)), repeats)

    d = np.asarray(data).copy()
    d[np.asarray(pattern.diagonal)] += 1e-9 * np.abs(d).max()
    rhs, indptr, indices = np.ones(pattern.n), np.asarray(pattern.indptr), np.asarray(pattern.indices)
    solved = []
    t_solve = _median_time(lambda: solved.append(linalg.host_solve(d, rhs, indptr, indices)[1]), repeats)

    iterations = int(eq.iterations)
    run_s = timing.wall_s - timing.compile_s
    per_iteration = run_s / max(iterations, 1)
    loop_solve = float(np.mean(timed.seconds)) if timed.seconds else float("nan")
    return {
        "step": step,
        "nodes": scene.n_nodes,
        "dof": scene.n_dof,
        "nnz": int(pattern.nnz),
        "iterations": iterations,
        "converged": eq.converged,
        "residual_N": float(eq.residual_N),
        "compile_s": timing.compile_s,
        "assembly_s": t_assembly,
        "solve_s": t_solve,
        "solve_ok": all(bool(ok) for ok in solved),
        "loop_solve_s": loop_solve,
        "loop_solves": len(timed.seconds),
        "iteration_s": per_iteration,
        "rest_s": per_iteration - t_assembly - loop_solve,
        "run_s": run_s,
        "peak_MB": _peak_mb(),
    }


def _cage_twine(scene):
    """The cage's twine (a Twine), read back from its built netting, which the cage makes of one twine.

    Read back rather than restated here, so that the options below are switched on the cage's own twine
    whatever its defaults become; ``terms`` checks that this twine rebuilds the same model.
    """
    from jaxnet.materials import DRAG_MODELS, Twine

    n = scene.netting
    field = {"ea": "ea_traction"}  # Twine field -> Netting column, where the names differ
    values = {f: float(np.asarray(getattr(n, field.get(f, f)))[0])
              for f in ("l0", "ea", "ea_compression", "diameter", "density", "cd_normal", "tangential_ratio",
                        "opening_stiffness", "rest_angle", "knot_size", "bending_stiffness")}
    drag = {code: name for name, code in DRAG_MODELS.items()}[int(np.asarray(n.drag_model)[0])]
    return Twine(drag_model=drag, **values)


def _change(full, model):
    """How ``model`` differs from ``full``: terms added (+), removed (-), or with other options (~)."""
    before, after = {a.name: a.options for a in full}, {a.name: a.options for a in model}
    out = [f"+{n}" for n in after if n not in before] + [f"-{n}" for n in before if n not in after]
    out += [f"~{n} {dict(before[n])} -> {dict(after[n])}" for n in after if n in before and after[n] != before[n]]
    return " ".join(out)


def terms(step, repeats, compile_repeats):
    """Part 2 at one meshing step (run in its own process)."""
    import jaxnet as jn
    from jaxnet import model

    scene = _cage(step)
    eq = jn.solve_static(scene, throw=False)
    full = model.active_terms(scene)
    rows = [{"label": "all active terms", "term": None}]
    cases = [_prepare(eq.x, scene, full)]
    for t in full:
        rows.append({"label": f"without {t.name}", "term": t.name})
        cases.append(_prepare(eq.x, scene, tuple(a for a in full if a is not t)))

    twine = _cage_twine(scene)
    if model.active_terms(_cage(step, twine)) != full:
        raise RuntimeError("the twine read back from the cage does not rebuild the cage's model")
    options = []
    for label, field, value, unit in OPTIONS:
        rebuilt = _cage(step, dataclasses.replace(twine, **{field: value}))
        if rebuilt.n_nodes != scene.n_nodes:
            raise RuntimeError(f"{label}: the rebuilt cage has {rebuilt.n_nodes} nodes, not {scene.n_nodes}")
        m = model.active_terms(rebuilt)
        options.append({"label": label, "setting": f"{field}={value} {unit}".strip(), "change": _change(full, m)})
        cases.append(_prepare(eq.x, rebuilt, m))

    timed = _time_assemblies(cases, repeats, compile_repeats)
    for row, t in zip(rows + options, timed):
        row.update(t)
    return {"step": step, "nodes": scene.n_nodes, "dof": scene.n_dof, "iterations": int(eq.iterations),
            "converged": eq.converged, "rows": rows, "options": options, "peak_MB": _peak_mb()}


# -- the driver: subprocesses and tables ------------------------------------------------------------


def _run(args):
    """Run this file with ``args`` in a new process; its last stdout line is JSON. (result, error line)"""
    out = subprocess.run([sys.executable, __file__, *args], capture_output=True, text=True)
    if out.returncode != 0:
        lines = (out.stderr or "").strip().splitlines()
        return None, lines[-1] if lines else f"exit status {out.returncode}"
    return json.loads(out.stdout.strip().splitlines()[-1]), None


def _load():
    averages = " ".join(f"{v:.2f}" for v in os.getloadavg())
    return f"load average {averages} (1, 5, 15 min) on {os.cpu_count()} cores"


def print_sizes(steps, repeats):
    print("1. Fish cage (jaxnet.scenes.cage defaults) at three refinements, solved from the start shape")
    print("   assembly = jitted tangent + out-of-balance force at the solution (median); LU loop = mean time of the")
    print("   factorisation + solve calls made inside the Newton loop (on K + mu S); LU sol. = factorisation + solve")
    print("   of the tangent at the solution (median; as statics.py); it = run time / iterations;")
    print("   rest = it - assembly - LU loop (line search energies and forces, the loop's own work; it can come")
    print("   out negative on small nets, where the standalone assembly's dispatch and transfer weigh more)")
    print(f"{'step m':>6} {'nodes':>6} {'dof':>6} {'nnz':>7} {'iter':>4} {'conv':>4} {'resid N':>7} {'compile s':>9} "
          f"{'assembly ms':>11} {'LU loop ms':>10} {'LU sol. ms':>10} {'it ms':>7} {'rest ms':>7} {'run s':>7} "
          f"{'peak MB':>7}")
    rows = []
    for step in steps:
        r, error = _run(["--one-size", str(step), "--repeats", str(repeats)])
        if r is None:
            print(f"{step:>6} failed: {error}", flush=True)
            continue
        rows.append(r)
        conv = "yes" if r["converged"] else "NO"
        solve_ms = f"{1e3 * r['solve_s']:>10.1f}" if r["solve_ok"] else f"{'singular':>10}"
        print(f"{r['step']:>6} {r['nodes']:>6} {r['dof']:>6} {r['nnz']:>7} {r['iterations']:>4} {conv:>4} "
              f"{r['residual_N']:>7.1e} {r['compile_s']:>9.2f} {1e3 * r['assembly_s']:>11.1f} "
              f"{1e3 * r['loop_solve_s']:>10.1f} {solve_ms} {1e3 * r['iteration_s']:>7.1f} {1e3 * r['rest_s']:>7.1f} "
              f"{r['run_s']:>7.2f} {r['peak_MB']:>7.0f}", flush=True)
        if r["loop_solves"] != r["iterations"]:
            print(f"       ({r['loop_solves']} linear solves in the loop for {r['iterations']} iterations)")
    if len(rows) >= 2:
        log_n = np.log([r["nodes"] for r in rows])
        print("growth exponents vs nodes (slope of log cost on log nodes):")
        for key in ("iterations", "compile_s", "assembly_s", "loop_solve_s", "solve_s", "iteration_s", "run_s",
                    "peak_MB"):
            slope = np.polyfit(log_n, np.log([max(r[key], 1e-12) for r in rows]), 1)[0]
            print(f"  {key:<12} {slope:6.2f}")


def print_terms(step, repeats, compile_repeats):
    r, error = _run(["--terms", str(step), "--repeats", str(repeats), "--compile-repeats", str(compile_repeats)])
    print(f"\n2. Cost of each term: fish cage at step {step} m", end="")
    if r is None:
        print(f": failed: {error}")
        return
    print(f", {r['nodes']} nodes, {r['dof']} dof, solved in {r['iterations']} iterations"
          f"{'' if r['converged'] else ' (NOT converged)'}; assembly at the solution,")
    print(f"   median of {repeats} runs; compile = trace + lower + XLA compile, median of {compile_repeats}; "
          f"peak {r['peak_MB']:.0f} MB")
    full = r["rows"][0]
    t_full, c_full = full["assembly_s"], full["compile_s"]
    head = (f"{'':<40} {'nnz':>8} {'assembly ms':>11} {'term ms':>8} {'share':>6} {'compile s':>9} {'term s':>7}")
    print(head)
    print(f"{full['label']:<40} {full['nnz']:>8} {1e3 * t_full:>11.2f} {'':>8} {'':>6} {c_full:>9.2f}")
    attributed = 0.0
    for row in r["rows"][1:]:
        cost, compile_cost = t_full - row["assembly_s"], c_full - row["compile_s"]
        attributed += cost
        print(f"{row['label']:<40} {row['nnz']:>8} {1e3 * row['assembly_s']:>11.2f} {1e3 * cost:>8.2f} "
              f"{cost / t_full:>6.1%} {row['compile_s']:>9.2f} {compile_cost:>7.2f}")
    print(f"{'not attributed to a single term':<40} {'':>8} {'':>11} {1e3 * (t_full - attributed):>8.2f} "
          f"{(t_full - attributed) / t_full:>6.1%}")
    print("   term ms / term s: full assembly minus the assembly without that term (its run / compile cost)")
    (a0, a1), (c0, c1) = full["assembly_range_s"], full["compile_range_s"]
    print(f"   noise: the full assembly's runs spread over {1e3 * a0:.2f}-{1e3 * a1:.2f} ms, its compiles over "
          f"{c0:.2f}-{c1:.2f} s")

    print("\n   Terms the cage does not use, switched on (cage rebuilt with that twine option, same node positions):")
    print(f"{'':<40} {'nnz':>8} {'assembly ms':>11} {'extra ms':>8} {'ratio':>6} {'compile s':>9} {'extra s':>7}"
          "  terms changed")
    for row in r["options"]:
        cost, compile_cost = row["assembly_s"] - t_full, row["compile_s"] - c_full
        print(f"{row['label']:<40} {row['nnz']:>8} {1e3 * row['assembly_s']:>11.2f} {1e3 * cost:>8.2f} "
              f"{row['assembly_s'] / t_full:>6.2f} {row['compile_s']:>9.2f} {compile_cost:>7.2f}  {row['change']}")
    print("   settings: " + "; ".join(f"{row['label']}: {row['setting']}" for row in r["options"]))
    print("   extra ms / extra s: that assembly minus the cage's (all active terms); ratio: its time over the cage's")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, nargs="*", default=[0.8, 0.5, 0.3], help="meshing steps (m)")
    parser.add_argument("--terms-step", type=float, default=None, help="step of part 2 (default: the middle one)")
    parser.add_argument("--repeats", type=int, default=11, help="timed runs per measurement (median)")
    parser.add_argument("--compile-repeats", type=int, default=3, help="compiles per assembly in part 2 (median)")
    parser.add_argument("--only", choices=("sizes", "terms"), default=None, help="run one part only")
    parser.add_argument("--one-size", type=float, help=argparse.SUPPRESS)
    parser.add_argument("--terms", type=float, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one_size is not None:
        print(json.dumps(one_size(args.one_size, args.repeats)))
        return
    if args.terms is not None:
        print(json.dumps(terms(args.terms, args.repeats, args.compile_repeats)))
        return

    steps = sorted(args.steps, reverse=True)  # coarse to fine
    print(f"start: {_load()}", flush=True)
    t0 = time.perf_counter()
    if args.only in (None, "sizes"):
        print_sizes(steps, args.repeats)
    if args.only in (None, "terms"):
        step = args.terms_step if args.terms_step is not None else steps[len(steps) // 2]
        print_terms(step, args.repeats, args.compile_repeats)
    print(f"\nend: {_load()}; benchmark wall time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
