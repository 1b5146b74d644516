"""FEMNET's worked cases solved by jaxnet, figure by figure, with run times against FEMNET's.

    python benchmarks/femnet_cases.py [--cases nr_netting c2] [--data tests/data/femnet] [--repeat 3]
                                      [--stiffness autodiff closed_form]

Per case and per mesh (FEMNET's own `.mdg` mesh, and jaxnet's mesher from the `.don`): FEMNET's summary
figure (from its `.sta`), jaxnet's, and the relative difference; then jaxnet's nodes, elements, unknowns,
Newton iterations, and wall times cold (a fresh process: tracing and compilation included) and warm (the
median of three more solves of the same scene in that process: the compiled programs are reused), against FEMNET's own
times on this kind of machine (the median of 3 runs given in ../shared/femnet-cases/README.md).
Each case runs in its own subprocess, so "cold" is really cold: twice, with an empty JAX persistent
compilation cache and then with the programs the first run left there (what `jaxnet run` gives the second
time a case of that shape is run: its cache is on by default). Each such pair is repeated ``--repeat``
times and the times printed are the medians, with their ranges: on a shared 2-core machine one run's
times vary up to 1.7x. Each case is run with each tangent stiffness path asked for (``--stiffness``: autodiff,
and the book's closed forms of :mod:`jaxnet.closed_form`), side by side.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

#: warm solves per case and process, of which the median is reported
WARM_SOLVES = 3

#: FEMNET's own run times on this kind of machine (s) and Newton iterations (femnet-cases/README.md)
FEMNET_TIMES = {"nr_netting": (16.5, 4387), "c2": (6.9, 847)}


def one(case, data, mesh, stiffness="autodiff"):
    t0 = time.perf_counter()
    import numpy as np

    from jaxnet.io import femnet
    from jaxnet.solve.statics import solve

    don = data / f"{case}.don"
    loaded = femnet.read_mdg(data / f"{case}.mdg", don) if mesh else femnet.read_don(don)
    scene, solver, info = loaded.scene, loaded.solver, loaded.info
    eq = solve(scene, solver, throw=False, stiffness=stiffness)
    timing = eq.timing
    cold = time.perf_counter() - t0
    # warm: the median of WARM_SOLVES more solves of the same scene in this process (one alone varies by
    # up to 1.3x on a shared 2-core machine, and the first also shares the cores with the writing of the
    # programs to disk)
    warm_times = []
    for _ in range(WARM_SOLVES):
        t1 = time.perf_counter()
        solve(scene, solver, throw=False, stiffness=stiffness)
        warm_times.append(time.perf_counter() - t1)
    warm = float(np.median(warm_times))
    fig = femnet.femnet_figures(scene, eq, info["symmetry_axes"], info.get("fixity"))
    positions, _, _, summary = femnet.read_sta(data / f"{case}.sta", *_mdg_counts(data, case))
    rows = []

    def add(label, femnet_value, jaxnet_value):
        rows.append((label, float(femnet_value), float(jaxnet_value)))

    add("surface (netting) drag, x (N)", summary["surface drag (N)"][0], fig["drag_netting_N"][0])
    add("element (cable) drag, x (N)", summary["element drag (N)"][0], fig["drag_cables_N"][0])
    total = summary["forces along X Y and Z axes (N)"]
    for k, axis in enumerate("xyz"):
        add(f"total force, {axis} (N)", total[k], fig["total_force_N"][k])
    if "catch drag (N)" in summary and "catch" in fig:
        add("catch drag (N)", summary["catch drag (N)"][0], fig["catch_drag_N"][0])
        add("catch thickness (m)", summary["thickness of the catch (m)"][0], fig["catch"]["thickness_m"])
        add("max catch diameter (m)", summary["maximal catch diameter (m)"][0], fig["catch"]["diameter_m"])
        add("catch volume, modelled part (m3)", summary["volume of the catch (m3)"][0], fig["catch"]["volume_modelled_m3"])
    out = {
        "rows": rows,
        "nodes": scene.n_nodes,
        "elements": scene.n_elements,
        "dof": scene.n_dof,
        "iterations": int(eq.iterations),
        "converged": bool(eq.converged),
        "cold_s": cold,
        "compile_s": timing.compile_s,
        "warm_s": warm,
    }
    if mesh:  # same nodes in the same order: positions compare directly
        out["max_position_difference_m"] = float(np.linalg.norm(np.asarray(eq.x) - positions, axis=1).max())
        out.update(_at_femnet_positions(scene, positions))
    return out


def _at_femnet_positions(scene, positions):
    """jaxnet's out-of-balance force at FEMNET's equilibrium positions (mean and largest nodal norm, N), and
    how far one undamped Newton step from there moves the nodes (m): when that step is the whole position
    difference, the difference is the linear response of the net's soft modes to what FEMNET left
    unbalanced (its stopping rule is on the mean nodal force)."""
    import jax.numpy as jnp
    import numpy as np

    from jaxnet import linalg, model as model_lib
    from jaxnet.model import assemble

    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    free = np.asarray(pattern.free)
    X = jnp.asarray(positions)
    force = np.asarray(assemble.nodal_force(X, scene, model, assemble.loads(scene, model)))
    nodal = np.linalg.norm(np.where(np.asarray(scene.nodes.fixed), 0.0, force), axis=1)
    step, _ = linalg.HostSolver(pattern.indptr, pattern.indices).solve(
        np.asarray(assemble.tangent(X, scene, model, pattern)), force.ravel()[free])
    moved = np.zeros(force.size)
    moved[free] = step
    return {"femnet_residual_mean_N": float(nodal.mean()), "femnet_residual_max_N": float(nodal.max()),
            "newton_step_from_femnet_m": float(np.linalg.norm(moved.reshape(-1, 3), axis=1).max())}


def _mdg_counts(data, case):
    from jaxnet.io import femnet

    scene = femnet.read_mdg(data / f"{case}.mdg", data / f"{case}.don").scene
    return scene.n_nodes, (0 if scene.bars is None else int(scene.bars.ends.shape[0])), int(scene.netting.vertices.shape[0])


def _median_and_range(values):
    return float(np.median(values)), (min(values), max(values))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--cases", nargs="*", default=list(FEMNET_TIMES))
    parser.add_argument("--data", default=str(pathlib.Path(__file__).resolve().parents[1] / "tests" / "data" / "femnet"))
    parser.add_argument("--repeat", type=int, default=3,
                        help="runs per case and mesh; the times printed are their medians, with the range "
                             "(timings on a shared machine vary up to 1.7x between runs)")
    parser.add_argument("--stiffness", nargs="*", default=["autodiff", "closed_form"],
                        help="tangent stiffness paths to run each case with (Newton(stiffness=...))")
    parser.add_argument("--one", nargs=3, help=argparse.SUPPRESS)
    args = parser.parse_args()
    data = pathlib.Path(args.data)
    if args.one:
        case, mesh, stiffness = args.one
        print(json.dumps(one(case, data, mesh == "mdg", stiffness)))
        return
    for case, mesh, stiffness in [(c, m, s) for c in args.cases for m in ("mdg", "don") for s in args.stiffness]:
        title = f"{case} on {'FEMNET' if mesh == 'mdg' else 'jaxnet'}'s mesh, {stiffness} stiffness"
        pairs = []  # per repeat: a run with an empty persistent cache, then one with what it left there
        for _ in range(max(args.repeat, 1)):
            with tempfile.TemporaryDirectory() as cache:
                env = {**os.environ, "JAX_COMPILATION_CACHE_DIR": cache, "JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS": "0.2"}
                pairs.append([subprocess.run([sys.executable, __file__, "--data", str(data), "--one", case, mesh, stiffness],
                                             capture_output=True, text=True, env=env) for _ in range(2)])
        failed = [out for runs in pairs for out in runs if out.returncode != 0]
        if failed:
            out = failed[0]
            print(f"{title}: failed: {out.stderr.strip().splitlines()[-1] if out.stderr else out.returncode}")
            continue
        results = [[json.loads(out.stdout.strip().splitlines()[-1]) for out in runs] for runs in pairs]
        r, cached = results[0]
        timing = {key: _median_and_range([res[k][key] for res in results])
                  for k, key in ((0, "cold_s"), (0, "compile_s"), (0, "warm_s"))}
        cached_timing = {key: _median_and_range([res[1][key] for res in results]) for key in ("cold_s", "compile_s")}
        r = {**r, **{key: med for key, (med, _) in timing.items()}}
        cached = {**cached, **{key: med for key, (med, _) in cached_timing.items()}}
        print(f"\n{title}: {r['nodes']} nodes, {r['elements']} elements, {r['dof']} unknowns; "
              f"{r['iterations']} Newton iterations ({'converged' if r['converged'] else 'NOT converged'})")
        print(f"  {'figure':36s} {'FEMNET':>12s} {'jaxnet':>12s} {'difference':>11s}")
        for label, f, j in r["rows"]:
            diff = f"{(j - f) / abs(f) * 100:+10.2f}%" if abs(f) > 1e-9 else f"{j - f:+11.3g}"
            print(f"  {label:36s} {f:12.5g} {j:12.5g} {diff}")
        if "max_position_difference_m" in r:
            print(f"  {'largest node position difference (m)':36s} {'':12s} {r['max_position_difference_m']:12.4g}")
            print(f"  at FEMNET's positions jaxnet's nodal residual is {r['femnet_residual_mean_N']:.3g} N mean, "
                  f"{r['femnet_residual_max_N']:.3g} N max; one Newton step from there moves the nodes by "
                  f"{r['newton_step_from_femnet_m']:.4g} m")
        femnet_s, femnet_it = FEMNET_TIMES[case]
        if len(results) > 1:
            spread = ", ".join(f"{name} {lo:.2f}-{hi:.2f} s" for name, (_, (lo, hi)) in
                               (("cold", timing["cold_s"]), ("from disk", cached_timing["cold_s"]),
                                ("warm", timing["warm_s"])))
            print(f"  times: medians of {len(results)} runs (ranges: {spread})")
        print(f"  wall time: jaxnet cold {r['cold_s']:.1f} s (compile {r['compile_s']:.1f} s), cold with the compiled "
              f"programs on disk {cached['cold_s']:.1f} s (compile {cached['compile_s']:.1f} s), warm {r['warm_s']:.2f} s; "
              f"FEMNET {femnet_s} s ({femnet_it} iterations): {femnet_s / r['cold_s']:.1f}x cold, "
              f"{femnet_s / cached['cold_s']:.1f}x cold from disk, {femnet_s / r['warm_s']:.1f}x warm", flush=True)


if __name__ == "__main__":
    main()
