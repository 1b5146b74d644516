"""FEMNET's whole corpus of worked cases, read and solved by jaxnet from their ``.don``, against FEMNET's answers.

    python validation/femnet_corpus.py [--corpus ../shared/femnet-corpus] [--only 1pelagic_trawl/s2 ...]
                                       [--timeout 600] [--out validation/results/femnet_corpus.json] [--resume]
                                       [--table FILE]

Per case (each in its own process, so that its time is cold: reading, meshing, tracing, compilation and the solve
from the drawn shape; then a second, warm solve of the same scene in that process): whether it reads (else the
reader's first refusal, ``file:LINE: message``), nodes and unknowns, Newton iterations, converged and why not,
FEMNET's "forces along X Y and Z axes" against jaxnet's (the reactions at the coordinates FEMNET's node types hold by
"Displacement"), with the relative difference of each component to the norm of FEMNET's force, the figures FEMNET
prints (its text outputs: distances, forces, tensions and positions of the nodes it names) against those of its
stored ``.sta``, the height of the highest node box's top (floats, bodies: above 0, a box partly out of the water,
both programs floating it by its immersed part under z = 0),
and the cold and warm wall times against FEMNET's own (``ANSWERS.md``: its current code on this kind of machine,
from the start its job file uses, which may be an earlier case's equilibrium where jaxnet starts from the drawn
shape). FEMNET's target is its current code's answer where ``ANSWERS.md`` has one and FEMNET converged, else its stored
``.sta`` (FEMNET stops on its mean nodal residual, or at its iteration cap, short of the equilibrium).

The records are JSON lines, written as each case ends (``--resume`` skips the cases already in ``--out``); the
table is printed at the end (``--table`` prints it from a records file without running anything). This is a
benchmark, not a test: the suite holds one representative case per family (``tests/io/test_femnet_corpus.py``).
"""

from __future__ import annotations

import argparse
import json
import pathlib
import re
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
CORPUS = ROOT.parent / "shared" / "femnet-corpus"


def femnet_answers(corpus):
    """FEMNET's answers per case from ``ANSWERS.md``: {family/case: {"iterations", "converged", "wall_s", "force"
    (its current code's X Y Z, N, or None), "stored" (the .sta's), "start"}}."""
    answers = {}
    for line in (pathlib.Path(corpus) / "ANSWERS.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 8 or "/" not in cells[0] or cells[0].startswith("case"):
            continue

        def floats(text):
            try:
                values = [float(v) for v in text.split()]
            except ValueError:
                return None
            return values if len(values) == 3 else None

        iterations = re.match(r"(\d+)", cells[2])
        try:
            wall = float(cells[4])
        except ValueError:
            wall = None
        answers[cells[0]] = {"start": cells[1], "iterations": int(iterations.group(1)) if iterations else None,
                             "converged": cells[3], "wall_s": wall, "force": floats(cells[5]),
                             "stored": floats(cells[6])}
    return answers


def one(don):
    """Read and solve one case in this process: its record (see the module docstring)."""
    t0 = time.perf_counter()
    import numpy as np

    from jaxnet.io import femnet
    from jaxnet.scene import SceneError
    from jaxnet.solve.statics import solve

    try:
        case = femnet.read_don(don)
    except SceneError as e:
        return {"reads": False, "refusal": str(e).split("\n")[0], "cold_s": time.perf_counter() - t0}
    scene, info = case.scene, case.info
    eq = solve(scene, case.solver, throw=False)
    cold = time.perf_counter() - t0
    t1 = time.perf_counter()
    solve(scene, case.solver, throw=False)
    warm = time.perf_counter() - t1
    x = np.asarray(eq.x)
    boxes = info.get("boxes", {})
    tops = [x[int(i), 2] + h for i, h in boxes.items()]
    figures = femnet.femnet_figures(scene, eq, info["symmetry_axes"], info.get("fixity"))
    # FEMNET's printed figures (its text outputs) against those of its stored .sta, where it has one
    sta = pathlib.Path(don).with_suffix(".sta")
    summary = femnet.read_sta_summary(sta) if sta.exists() else {}
    printed = [{**f, "femnet": femnet.printed_figure(summary, f["comment"])}
               for f in femnet.text_output_figures(scene, eq, info)]
    return {"reads": True, "nodes": scene.n_nodes, "dof": scene.n_dof, "iterations": int(eq.iterations),
            "converged": bool(eq.converged), "reason": str(getattr(eq, "reason", "")),
            "largest_residual_N": float(np.abs(np.where(np.asarray(scene.nodes.fixed), 0.0, np.asarray(eq.force))).max()),
            "total_force_N": figures["total_force_N"], "boxes": len(boxes),
            "highest_box_top_m": float(max(tops)) if tops else None,
            "printed": printed,
            "warnings": len(info.get("warnings", [])), "dynamic_only": len(info.get("dynamic_only", [])),
            "cold_s": cold, "warm_s": warm}


def femnet_target(answer):
    """FEMNET's answer a case is compared with (X Y Z, N; None when it has none): its current code's
    (``ANSWERS.md``), unless that stopped unconverged (its cap, a timeout) and the stored ``.sta`` has one."""
    converged = answer.get("converged", "").startswith("yes")
    current, stored = answer.get("force"), answer.get("stored")
    return current if (current and (converged or not stored)) else stored


def run_case(don, timeout):
    """One case in a fresh process (cold), with a wall-clock limit (s)."""
    t0 = time.perf_counter()
    try:
        # a plain process: no persistent compilation cache (only the CLI turns it on), so the time is cold
        done = subprocess.run([sys.executable, __file__, "--one", str(don)], capture_output=True, text=True,
                              timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"reads": True, "converged": False, "reason": f"timeout after {timeout} s", "cold_s": timeout}
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    if done.returncode != 0 or not lines:
        tail = (done.stderr or done.stdout).strip().splitlines()[-1:] or ["no output"]
        return {"reads": None, "error": tail[0][:300], "cold_s": time.perf_counter() - t0}
    return json.loads(lines[-1])


def printed_summary(printed):
    """FEMNET's printed figures of a case against jaxnet's: "k/n within 2 %" over those both have (distances and
    positions within 2 % of their scale, the largest |value| of their kind), and the worst one's difference."""
    pairs = [p for p in printed if p.get("value") is not None and p.get("femnet") is not None]
    if not pairs:
        return ""
    scale = {}
    for p in pairs:
        scale[p["kind"]] = max(scale.get(p["kind"], 0.0), abs(p["femnet"]), abs(p["value"]), 1e-9)
    rel = [abs(p["value"] - p["femnet"]) / scale[p["kind"]] for p in pairs]
    worst = pairs[max(range(len(rel)), key=rel.__getitem__)]
    return (f"{sum(r <= 0.02 for r in rel)}/{len(pairs)} within 2 % (worst: {worst['comment'][:30]} "
            f"{worst['value']:.4g} vs {worst['femnet']:.4g} {worst['unit']})")


def ratio(femnet_s, jaxnet_s):
    """FEMNET's time over jaxnet's, as "12x" (empty when either is missing)."""
    return f"{femnet_s / jaxnet_s:.2g}x" if femnet_s and jaxnet_s else ""


def table(records, answers):
    """The corpus table (markdown) and its summary lines."""
    head = ("| case | reads | nodes | it | conv | jaxnet X Y Z (N) | FEMNET X Y Z (N) | max rel diff | printed figures "
            "| highest box top z (m) | cold s | warm s | FEMNET s (it) | cold ratio | warm ratio |")
    rows = [head, "|" + "---|" * 15]
    stats = {"cases": 0, "read": 0, "converged": 0, "within_1pct": 0, "compared": 0, "iterations": []}
    for name, r in records.items():
        a = answers.get(name, {})
        stats["cases"] += 1
        if not r.get("reads"):
            why = r.get("refusal") or r.get("error") or ""
            rows.append(f"| {name} | no: {why.split(': ', 1)[-1][:110]} |" + " |" * 13)
            continue
        stats["read"] += 1
        target = femnet_target(a)
        force = r.get("total_force_N")
        diff = ""
        if target is not None and force is not None and r.get("converged"):
            scale = max(sum(v * v for v in target) ** 0.5, 1e-9)
            rel = max(abs(f - t) for f, t in zip(force, target)) / scale
            diff = f"{rel:.2%}"
            stats["compared"] += 1
            stats["within_1pct"] += rel <= 0.01
        if r.get("converged"):
            stats["converged"] += 1
            stats["iterations"].append(r["iterations"])
        femnet_s = a.get("wall_s")
        top = r.get("highest_box_top_m")
        under = "" if not r.get("boxes") or top is None else f"{top:.2f}"
        fmt = (lambda v: " ".join(f"{x:.1f}" for x in v)) if force else (lambda v: "")
        rows.append(
            f"| {name} | yes | {r.get('nodes', '')} | {r.get('iterations', '')} | "
            f"{'yes' if r.get('converged') else 'no: ' + str(r.get('reason', ''))[:40]} | {fmt(force) if force else ''} | "
            f"{fmt(target) if target else ''} | {diff} | {printed_summary(r.get('printed', []))} | {under} | "
            f"{r.get('cold_s', 0):.1f} | "
            f"{r.get('warm_s', 0) or 0:.2f} | {'' if femnet_s is None else f'{femnet_s:.2f}'} ({a.get('iterations', '')}) | "
            f"{ratio(femnet_s, r.get('cold_s'))} | {ratio(femnet_s, r.get('warm_s'))} |")
    its = sorted(stats["iterations"])
    median = its[len(its) // 2] if its else None
    summary = (f"{stats['cases']} cases: {stats['read']} read, {stats['converged']} converged (median "
               f"{median} Newton iterations, largest {its[-1] if its else None}); total force within 1 % of FEMNET's "
               f"answer in {stats['within_1pct']} of the {stats['compared']} converged cases with an answer")
    return "\n".join(rows), summary


#: the report section's title (``python -m validation``)
TITLE = "FEMNET's corpus: the worked cases from their .don"
#: the quick set: one case per family, the ones tests/io/test_femnet_corpus.py also reads
QUICK = ("0simple/a1", "0simple/nr_20_0_0_3_2", "1pelagic_trawl/s2", "3bottom_trawl/b1", "5catch/d5a",
         "6flexion/c1", "11bottom_seine/s1", "14tarp/s3", "15grid/nephrop_1")


def read_records(path):
    """{case: record} of a records file (JSON lines)."""
    records = {}
    for line in pathlib.Path(path).read_text().splitlines():
        record = json.loads(line)
        records[record["case"]] = record
    return records


def run_cases(cases, corpus, out, timeout, resume=False, echo=print):
    """Run ``cases`` (family/case names), each in a fresh process, appending each record to ``out`` as it ends
    (``resume``: keep those already there). Returns {case: record}."""
    out = pathlib.Path(out)
    records = read_records(out) if resume and out.exists() else {}
    if out.exists() and not resume:
        out.unlink()
    out.parent.mkdir(parents=True, exist_ok=True)
    for k, name in enumerate(cases):
        if name in records:
            continue
        record = {"case": name, **run_case(pathlib.Path(corpus) / f"{name}.don", timeout)}
        records[name] = record
        with out.open("a") as f:
            f.write(json.dumps(record) + "\n")
        state = ("refused" if record.get("reads") is False else
                 f"{record.get('iterations')} it, {'converged' if record.get('converged') else 'not converged'}")
        echo(f"[{k + 1}/{len(cases)}] {name}: {state}, {record.get('cold_s', 0):.1f} s")
    return {c: records[c] for c in cases if c in records}


def all_cases(corpus):
    """Every case of the corpus, as family/case names."""
    corpus = pathlib.Path(corpus)
    return sorted(str(p.relative_to(corpus).with_suffix("")) for p in corpus.rglob("*.don"))


def run(report, quick: bool) -> None:
    """The report section (``python -m validation``): the whole corpus (quick: one case per family, :data:`QUICK`),
    its table and summary."""
    report.text(" ".join(__doc__.split("\n\n")[2].split()) + "\n")
    cases = list(QUICK) if quick else all_cases(CORPUS)
    records = run_cases(cases, CORPUS, report.results / "femnet_corpus.json", timeout=600.0,
                        echo=lambda line: print(line, flush=True))
    text, summary = table(records, femnet_answers(CORPUS))
    report.text(summary + "\n\n" + text + "\n")
    if not quick:
        from validation import femnet_differences

        report.text("*Where the total force is more than 1 % off FEMNET's* (`python validation/femnet_differences.py`, "
                    "whose docstring says what each column measures): jaxnet on FEMNET's own mesh against the stored "
                    ".sta; jaxnet's total at the .sta's positions against the .sta's (the same physics?); the .sta's "
                    "total plus the force FEMNET left unbalanced on the free nodes against jaxnet's equilibrium on that "
                    "mesh (FEMNET's stopping rule); FEMNET's current code against its .sta; each as a fraction of "
                    "FEMNET's force.\n")
        traced = femnet_differences.trace(records, CORPUS, report.results / "femnet_differences.json",
                                          echo=lambda line: print(line, flush=True))
        report.text(femnet_differences.table(records, traced, femnet_answers(CORPUS), 0.01) + "\n")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--corpus", default=str(CORPUS))
    parser.add_argument("--only", nargs="*", help="family/case names (e.g. 1pelagic_trawl/s2)")
    parser.add_argument("--quick", action="store_true", help="one case per family (QUICK)")
    parser.add_argument("--timeout", type=float, default=600.0, help="wall-clock limit per case (s)")
    parser.add_argument("--out", default=str(ROOT / "validation" / "results" / "femnet_corpus.json"))
    parser.add_argument("--resume", action="store_true", help="skip the cases already recorded in --out")
    parser.add_argument("--table", help="print the table of this records file and stop")
    parser.add_argument("--one", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.one:
        print(json.dumps(one(args.one)), flush=True)
        return
    corpus = pathlib.Path(args.corpus)
    answers = femnet_answers(corpus)
    if args.table:
        text, summary = table(read_records(args.table), answers)
        print(text + "\n\n" + summary)
        return
    cases = list(QUICK) if args.quick else all_cases(corpus)
    if args.only:
        cases = [c for c in cases if c in args.only]
    records = run_cases(cases, corpus, args.out, args.timeout, resume=args.resume,
                        echo=lambda line: print(line, flush=True))
    text, summary = table(records, answers)
    print(text + "\n\n" + summary)


if __name__ == "__main__":
    main()
