"""FEMNET's dynamic cases run by jaxnet against FEMNET's stored time series (``.dyn``).

    python validation/femnet_dynamics.py [--only 7fad/g3 ...] [--out validation/results/femnet_dynamics.json]
                                         [--resume] [--table FILE]

Every corpus case with time settings (an end time > 0) and a stored ``.dyn``. Each is read on FEMNET's own mesh
(``.mdg``: the nodes in the ``.dyn``'s order), solved statically from FEMNET's stored equilibrium (``.sta``, where
FEMNET's ``dyna`` starts; the drawn shape without one; how far jaxnet's equilibrium lies from it is recorded; a
net held only at jaxnet's gauge whose loads do not balance has no equilibrium and starts from the ``.sta`` as it
is), its gauge then released (FEMNET's dynamics has none), then run in time by
:func:`jaxnet.solve.dynamics.simulate` with the case's time step, to its end time, records every record step
of the case (the default start ramp: one wave period). FEMNET's ``.dyn`` holds, per line, the time and x y z
of every node from its "beginning time of record". jaxnet's records are interpolated linearly in time to the
``.dyn``'s times (FEMNET's records fall a time step after jaxnet's; at 0.1 s between records of motions of
periods of seconds the interpolation is good to millimetres), then per case:

* the largest and the RMS difference of the node positions over every common time and node (m);
* the motion itself, the largest range of a node's coordinate over the window (m), to weigh the differences
  against; and the largest difference of the nodes' mean positions over the window (the offset of the mean
  shape, m), apart from the motion's;
* jaxnet's wall time per step (the first record interval, which compiles, apart) and its steps. FEMNET's own
  dynamic wall time is not in the corpus's answers (``ANSWERS.md`` times its statics), so no ratio is printed.

A case that cannot run says why (the reader's error: a FEMNET command jaxnet does not run in time). Each
case runs in its own process, its record written as it ends (``--resume`` skips the cases in ``--out``). A
benchmark, not a test.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from validation.femnet_corpus import CORPUS  # noqa: E402

#: wall-clock limit of one case's process (s)
TIMEOUT_S = 1800.0


def cases():
    """The corpus cases with a stored time series, as 'family/name'."""
    return sorted(f"{p.parent.name}/{p.stem}" for p in CORPUS.glob("*/*.dyn"))


def read_dyn(path, n_nodes):
    """(times (R,), positions (R, N, 3)) of FEMNET's ``.dyn``: one line per record, the time then x y z per node."""
    import numpy as np

    rows = [np.array(line.split(), dtype=float) for line in pathlib.Path(path).read_text().splitlines() if line.strip()]
    rows = [r for r in rows if r.size == 1 + 3 * n_nodes]
    data = np.array(rows)
    return data[:, 0], data[:, 1:].reshape(len(data), n_nodes, 3)


def one(name):
    """The record of one case (module docstring), in this process."""
    import time

    import equinox as eqx
    import numpy as np

    from jaxnet.io import femnet
    from jaxnet.solve import dynamics
    from jaxnet.solve.statics import solve

    don, mdg = CORPUS / f"{name}.don", CORPUS / f"{name}.mdg"
    case = femnet.read_mdg(mdg, don)
    # FEMNET's dyna starts from the case's .sta; jaxnet's static solve starts there too (from the drawn shape
    # without one): where the statics has many equilibria (a seine with no load left, s4), this is the one
    sta = CORPUS / f"{name}.sta"
    start = None
    if sta.exists():
        case = femnet.started_from_sta(case, sta)
        start = np.asarray(case.scene.nodes.position)
    settings = case.time
    if settings is None or settings.end_time is None:
        return {"case": name, "ran": False, "reason": "no end time"}
    scene, loading, ramp = dynamics.with_start_ramp(case.scene, settings.loading)
    eq = solve(dynamics.scene_at(scene, loading, 0.0), case.solver, throw=False)
    x0, start_kind = np.asarray(eq.x), "jaxnet's equilibrium"
    gauge = case.info.get("gauge")
    if gauge is not None and start is not None:
        # a free net whose loads do not balance has no equilibrium (s4_traction: 7 kN along x on the gauge):
        # it starts, as FEMNET's, from the .sta as it is
        axes = ["xyz".index(a) for a in gauge["axes"]]
        if np.abs(np.asarray(eq.force)[gauge["node"], axes]).max() > case.solver.tol:
            x0, start_kind = start, "FEMNET's .sta (no equilibrium: the gauge holds the loads' imbalance)"
    t0 = time.perf_counter()
    # a net held only at jaxnet's gauge for its static start is free in time, as FEMNET's dyna has it
    scene = eqx.tree_at(lambda s: s.nodes.fixed, scene, femnet.released_gauge(case).nodes.fixed)
    run = dynamics.simulate(scene, settings.end_time, settings.solver, loading, record_every=settings.record_every,
                            x0=x0, throw=False)
    wall = time.perf_counter() - t0
    femnet_t, femnet_x = read_dyn(CORPUS / f"{name}.dyn", scene.n_nodes)
    inside = (femnet_t >= run.times[0]) & (femnet_t <= run.times[-1])
    femnet_t, femnet_x = femnet_t[inside], femnet_x[inside]
    ours = np.stack([np.stack([np.interp(femnet_t, run.times, run.positions[:, i, a]) for a in range(3)], axis=-1)
                     for i in range(scene.n_nodes)], axis=1)
    diff = np.linalg.norm(ours - femnet_x, axis=-1)
    motion = float((femnet_x.max(axis=0) - femnet_x.min(axis=0)).max()) if len(femnet_t) else float("nan")
    mean_offset = float(np.linalg.norm(ours.mean(axis=0) - femnet_x.mean(axis=0), axis=-1).max()) if len(femnet_t) \
        else float("nan")
    steps = int(run.steps)
    per_step = (wall - run.timing.compile_s) / max(steps - int(round(settings.record_every / settings.solver.time_step)), 1)
    return {"case": name, "ran": True, "status": run.reason, "reached_s": float(run.times[-1]),
            "end_s": float(settings.end_time), "nodes": scene.n_nodes, "winches": len(loading.winches), "waves": type(scene.environment.waves).__name__
            if scene.environment.waves is not None else "none", "start_ramp_s": ramp,
            "static_converged": bool(eq.converged), "static_from": "FEMNET's .sta" if start is not None else
            "the drawn shape", "start": start_kind,
            "start_from_sta_m": float(np.linalg.norm(x0 - start, axis=1).max()) if start is not None
            else None, "records_compared": int(len(femnet_t)),
            "window_s": [float(femnet_t[0]), float(femnet_t[-1])] if len(femnet_t) else None,
            "largest_difference_m": float(diff.max()) if diff.size else float("nan"),
            "rms_difference_m": float(np.sqrt(np.mean(diff**2))) if diff.size else float("nan"),
            "largest_motion_m": motion, "mean_shape_offset_m": mean_offset, "steps": steps,
            "newton_per_step": run.mean_iterations, "retries": int(run.state.retries), "wall_s": wall,
            "compile_s": run.timing.compile_s, "s_per_step": per_step}


def table(records):
    lines = ["| case | nodes | waves | winches | start off .sta m | ran | records | largest difference m | RMS m | "
             "largest motion m | mean shape offset m | steps | Newton/step | s/step | wall s |", "|" + "---|" * 15]
    for r in records:
        if not r["ran"]:
            lines.append(f"| {r['case']} | | | | | no: {r['reason']} | | | | | | | | | |")
            continue
        off = r.get("start_from_sta_m")
        lines.append(f"| {r['case']} | {r['nodes']} | {r['waves']} | {r.get('winches', 0)} | "
                     f"{'' if off is None else f'{off:.3g}'} | {r['status']} to {r['reached_s']:g} s | "
                     f"{r['records_compared']} | {r['largest_difference_m']:.3g} | {r['rms_difference_m']:.3g} | "
                     f"{r['largest_motion_m']:.3g} | {r['mean_shape_offset_m']:.3g} | {r['steps']} | "
                     f"{r['newton_per_step']:.2f} | {r['s_per_step']:.2e} | {r['wall_s']:.1f} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--only", nargs="*", help="cases 'family/name' (default: every case with a .dyn)")
    parser.add_argument("--out", default=str(ROOT / "validation" / "results" / "femnet_dynamics.json"))
    parser.add_argument("--resume", action="store_true", help="skip the cases already in --out")
    parser.add_argument("--table", help="print the table of the records in this file and stop")
    parser.add_argument("--one", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one:
        print(json.dumps(one(args.one)))
        return 0
    out = pathlib.Path(args.table or args.out)
    if args.table:
        print(table([json.loads(line) for line in out.read_text().splitlines() if line.strip()]))
        return 0
    done = set()
    if args.resume and out.exists():
        done = {json.loads(line)["case"] for line in out.read_text().splitlines() if line.strip()}
    elif out.exists():
        out.unlink()
    out.parent.mkdir(parents=True, exist_ok=True)
    records = []
    for name in args.only or cases():
        if name in done:
            continue
        try:
            proc = subprocess.run([sys.executable, __file__, "--one", name], capture_output=True, text=True,
                                  timeout=TIMEOUT_S)
            lines = [line for line in proc.stdout.splitlines() if line.startswith("{")]
            record = json.loads(lines[-1]) if lines else {
                "case": name, "ran": False, "reason": (proc.stderr.strip().splitlines() or ["no output"])[-1][:300]}
        except subprocess.TimeoutExpired:
            record = {"case": name, "ran": False, "reason": f"timeout after {TIMEOUT_S:g} s"}
        records.append(record)
        with out.open("a") as f:
            f.write(json.dumps(record) + "\n")
        print(table([record]).splitlines()[-1], flush=True)
    print(table(records))
    return 0


if __name__ == "__main__":
    sys.exit(main())
