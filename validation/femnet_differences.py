"""Where jaxnet's answer to a FEMNET case differs from FEMNET's: the evidence that names the cause.

    python validation/femnet_differences.py [--records validation/results/femnet_corpus.json] [--above 0.01]
                                            [--only 12purse_seine/t1 ...] [--out validation/results/femnet_differences.json]
                                            [--resume] [--table FILE]

For every converged case of a corpus records file (``validation/femnet_corpus.py``) whose total force on the
fixings is more than ``--above`` (a fraction of the norm of FEMNET's force) off FEMNET's answer, and which FEMNET
stored with its mesh and equilibrium (``.mdg`` and ``.sta``), three measurements, each in a fresh process:

* **FEMNET's mesh**: the case read from FEMNET's ``.mdg`` (its own nodes, triangles and bars) and solved by jaxnet
  from FEMNET's drawn positions; its total force against the ``.sta``'s, the stored run on that very mesh. Within
  ``--above``: the difference on jaxnet's mesh is the mesh's (jaxnet's mesher places side nodes and breaks
  diagonal ties otherwise).
* **FEMNET's equilibrium**: jaxnet's forces at the ``.sta``'s positions on that mesh: the total on the fixings
  (FEMNET's sum: the coordinates its node types hold by "Displacement", not on a symmetry plane), against the
  ``.sta``'s printed total (the two programs' physics at one shape), and the sum of the out-of-balance forces
  left on the free coordinates (and where: the five free nodes most out of balance). FEMNET stops when its
  *mean* nodal residual is below its threshold, and the forces it leaves unbalanced, summed, go missing from its
  total: where the ``.sta``'s total plus that leftover is jaxnet's total on the same mesh, the difference is
  FEMNET's stopping rule.
* **FEMNET's two answers**: its current code's total (``ANSWERS.md``, the target where it converged) against its
  stored ``.sta``; where they differ by more than ``--above`` FEMNET does not reproduce itself.

The cause printed is the first that accounts for the difference, each figure relative to the norm of the compared
FEMNET force: *the mesh* (jaxnet on FEMNET's mesh gives the ``.sta``); *FEMNET's stopping rule* (the ``.sta``'s
total plus its leftover is jaxnet's on that mesh); *the .sta is no equilibrium* (the same physics at the ``.sta``,
jaxnet's answer on FEMNET's mesh nearer the ``.sta``'s total than the force the ``.sta`` leaves unbalanced, and
FEMNET either stopped at its cap or stopped by its mean rule, jaxnet's mean nodal residual there being within
:data:`MEAN_RULE` times FEMNET's threshold: its soft modes carry the shape far for the force it left); *FEMNET's
versions* (its current code, the target, differs from its ``.sta``); "not traced" where none does
(``docs/femnet.md`` traces those by hand from the records). Records are JSON lines written as each case ends
(``--resume`` skips those in ``--out``). A benchmark, not a test: the suite holds the checks on single cases
(``tests/io/test_femnet_corpus.py``, ``tests/terms/test_tarp.py``).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from validation.femnet_corpus import CORPUS, femnet_answers, femnet_target, read_records  # noqa: E402

#: wall-clock limit of one case's process (s): FEMNET's mesh of the largest trawls solves in about a minute
TIMEOUT_S = 900.0


def one(don):
    """The three measurements of one case (see the module docstring), in this process."""
    import dataclasses

    import jax.numpy as jnp
    import numpy as np

    from jaxnet import model as model_lib
    from jaxnet.model import assemble
    from jaxnet.io import femnet
    from jaxnet.solve.statics import solve

    don = pathlib.Path(don)
    case = femnet.read_mdg(don.with_suffix(".mdg"), don)
    scene, info = case.scene, case.info
    n_bars = 0 if scene.bars is None else int(scene.bars.ends.shape[0])
    n_triangles = 0 if scene.netting is None else int(scene.netting.vertices.shape[0])
    positions, _, _, summary = femnet.read_sta(don.with_suffix(".sta"), scene.n_nodes, n_bars, n_triangles)
    # the case's own cap is FEMNET's, for FEMNET's iteration; this measures the equilibrium, not the iterations
    eq = solve(scene, dataclasses.replace(case.solver, max_iter=max(case.solver.max_iter, 3000)), throw=False)
    on_mesh = femnet.femnet_figures(scene, eq, info["symmetry_axes"], info.get("fixity"))["total_force_N"]
    model = model_lib.active_terms(scene)
    force = np.asarray(assemble.nodal_force(jnp.asarray(positions), scene, model, assemble.loads(scene, model)))
    held = np.zeros(force.shape, bool)
    for i, j in info["fixity"]:
        held[i, j] = True
    free = ~np.asarray(scene.nodes.fixed)
    unbalanced = np.linalg.norm(np.where(free, force, 0.0), axis=1)
    worst = np.argsort(unbalanced)[::-1][:5]
    return {"nodes": scene.n_nodes, "iterations": int(eq.iterations), "converged": bool(eq.converged),
            "on_femnet_mesh_N": on_mesh, "sta_total_N": summary.get("forces along X Y and Z axes (N)"),
            "at_sta_total_N": np.where(held, force, 0.0).sum(axis=0).tolist(),
            "at_sta_leftover_N": np.where(free, force, 0.0).sum(axis=0).tolist(),
            "at_sta_largest_residual_N": float(unbalanced.max()),
            "at_sta_mean_residual_N": float(unbalanced[free.any(axis=1)].mean()),
            "threshold_N": float(case.solver.tol),
            # where it is: the five free nodes most out of balance, [node, x, y, z (m), force x, y, z (N)]
            "at_sta_worst_nodes": [[int(i), *positions[i].tolist(), *np.where(free[i], force[i], 0.0).tolist()]
                                   for i in worst]}


#: FEMNET stops when its mean nodal residual is below its threshold; jaxnet's mean nodal residual at FEMNET's .sta
#: (the norm per free node) is up to this many times that threshold where the two programs compute the same forces
#: (measured: 1.2-1.4x on the purse seines s1, t1 and u1, whose .sta's leftover closes on jaxnet's answer)
MEAN_RULE = 2.0


def norm(v):
    """Euclidean norm of a short list."""
    return sum(x * x for x in v) ** 0.5


def relative(a, b):
    """Largest component difference of a and b over the norm of b (None when either is missing)."""
    if a is None or b is None:
        return None
    return max(abs(x - y) for x, y in zip(a, b)) / max(norm(b), 1e-9)


def cause(jaxnet_total, answer, record, above):
    """The evidence's figures of one case and the first cause that accounts for its difference."""
    target, stored, current = femnet_target(answer), answer.get("stored"), answer.get("force")
    sta = record.get("sta_total_N")
    out = {"off": relative(jaxnet_total, target),
           "mesh": relative(record.get("on_femnet_mesh_N"), sta),
           "physics": relative(record.get("at_sta_total_N"), sta),
           "versions": relative(current, stored) if current and stored else None}
    closed = None
    if sta and record.get("at_sta_leftover_N") and record.get("on_femnet_mesh_N"):
        # FEMNET's total with what it left unbalanced, against jaxnet's equilibrium on the same mesh
        closed = relative([s + r for s, r in zip(sta, record["at_sta_leftover_N"])], record["on_femnet_mesh_N"])
    out["stopping"] = closed
    stored_is_target = target is stored or (out["versions"] is not None and out["versions"] <= above)
    mesh_gives_sta = out["mesh"] is not None and out["mesh"] <= above
    if mesh_gives_sta and stored_is_target:
        out["cause"] = "mesh: on FEMNET's mesh jaxnet gives its .sta"
    elif mesh_gives_sta:
        out["cause"] = "mesh, and FEMNET's versions: on FEMNET's mesh jaxnet gives its .sta; its current code differs"
    elif out["physics"] is not None and out["physics"] <= above and closed is not None and closed <= above:
        out["cause"] = "FEMNET's stopping rule: its .sta's total and the force it left unbalanced are jaxnet's"
    elif (out["physics"] is not None and out["physics"] <= above and sta and record.get("on_femnet_mesh_N")
          and norm([a - b for a, b in zip(record["on_femnet_mesh_N"], sta)]) <= norm(record["at_sta_leftover_N"])
          and (answer.get("converged", "").startswith("no")
               or record.get("at_sta_mean_residual_N", float("inf")) <= MEAN_RULE * record.get("threshold_N", 0.0))):
        out["cause"] = ("FEMNET's .sta is no equilibrium: it stopped " +
                        ("at its iteration cap" if answer.get("converged", "").startswith("no") else "by its mean rule")
                        + " with more force unbalanced than the difference")
    elif target is current and out["versions"] is not None and out["versions"] > above:
        out["cause"] = "FEMNET's versions differ: its current code and its .sta"
    else:
        out["cause"] = "not traced"
    return out


def table(corpus_records, records, answers, above):
    """The differences table (markdown): one row per case, the figures as percentages of FEMNET's force."""
    pct = lambda v: "" if v is None else f"{v:.2%}"  # noqa: E731
    rows = ["| case | off FEMNET | on FEMNET's mesh vs .sta | physics at .sta | .sta + leftover vs jaxnet "
            "| leftover X Y Z (N) | FEMNET current vs .sta | cause |", "|" + "---|" * 8]
    for name, r in records.items():
        if "error" in r:
            rows.append(f"| {name} | | | | | | | failed: {r['error'][:80]} |")
            continue
        c = cause(corpus_records[name]["total_force_N"], answers.get(name, {}), r, above)
        left = " ".join(f"{v:.1f}" for v in r["at_sta_leftover_N"])
        rows.append(f"| {name} | {pct(c['off'])} | {pct(c['mesh'])} | {pct(c['physics'])} | {pct(c['stopping'])} "
                    f"| {left} | {pct(c['versions'])} | {c['cause']} |")
    return "\n".join(rows)


def differing(corpus_records, answers, above, corpus):
    """The cases to trace: converged, more than ``above`` off FEMNET's answer, with a stored mesh and equilibrium."""
    out = []
    for name, r in corpus_records.items():
        target = femnet_target(answers.get(name, {}))
        off = relative(r.get("total_force_N"), target) if r.get("converged") else None
        don = pathlib.Path(corpus) / f"{name}.don"
        if off is not None and off > above and don.with_suffix(".mdg").exists() and don.with_suffix(".sta").exists():
            out.append(name)
    return out


def trace(corpus_records, corpus, out, above=0.01, only=None, resume=False, echo=print):
    """Measure every case :func:`differing` names (or those of them in ``only``), each in a fresh process,
    appending each record to ``out`` as it ends (``resume``: keep those already there). Returns {case: record}."""
    out = pathlib.Path(out)
    done = read_records(out) if resume and out.exists() else {}
    if out.exists() and not resume:
        out.unlink()
    out.parent.mkdir(parents=True, exist_ok=True)
    cases = [c for c in differing(corpus_records, femnet_answers(corpus), above, corpus) if not only or c in only]
    for k, name in enumerate(cases):
        if name in done:
            continue
        try:
            run = subprocess.run([sys.executable, __file__, "--one", str(pathlib.Path(corpus) / f"{name}.don")],
                                 capture_output=True, text=True, timeout=TIMEOUT_S)
            lines = [line for line in run.stdout.splitlines() if line.startswith("{")]
            record = json.loads(lines[-1]) if run.returncode == 0 and lines else {
                "error": ((run.stderr or run.stdout).strip().splitlines() or ["no output"])[-1][:300]}
        except subprocess.TimeoutExpired:
            record = {"error": f"timeout after {TIMEOUT_S} s"}
        done[name] = record = {"case": name, **record}
        with out.open("a") as f:
            f.write(json.dumps(record) + "\n")
        echo(f"[{k + 1}/{len(cases)}] {name}: {'failed' if 'error' in record else 'done'}")
    return {c: done[c] for c in cases if c in done}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--corpus", default=str(CORPUS))
    parser.add_argument("--records", default=str(ROOT / "validation" / "results" / "femnet_corpus.json"),
                        help="the corpus run's records (validation/femnet_corpus.py --out)")
    parser.add_argument("--above", type=float, default=0.01, help="the difference traced (fraction of FEMNET's force)")
    parser.add_argument("--only", nargs="*", help="family/case names")
    parser.add_argument("--out", default=str(ROOT / "validation" / "results" / "femnet_differences.json"))
    parser.add_argument("--resume", action="store_true", help="skip the cases already recorded in --out")
    parser.add_argument("--table", help="print the table of this records file and stop")
    parser.add_argument("--one", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one)), flush=True)
        return
    corpus_records = read_records(args.records)
    if args.table:
        done = read_records(args.table)
    else:
        done = trace(corpus_records, args.corpus, args.out, args.above, args.only, args.resume,
                     echo=lambda line: print(line, flush=True))
    print(table(corpus_records, {c: r for c, r in done.items() if c in corpus_records}, femnet_answers(args.corpus),
                args.above))


if __name__ == "__main__":
    main()
