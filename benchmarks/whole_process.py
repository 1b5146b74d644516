"""`jaxnet run CASE.don` timed as a whole process, as a user meets it, against FEMNET on the same case.

    python benchmarks/whole_process.py [--cases 5catch/c2 1pelagic_trawl/s3 1pelagic_trawl/s3a] [--repeat 3]
                                       [--corpus ../shared/femnet-corpus] [--femnet "COMMAND {case}"]

Per case, each run a fresh process (``python -m jaxnet.cli run CASE.don --quiet``), in alternation:

* **cold**: an empty directory of compiled programs (``--cache`` a new folder): the first run of a case of that
  shape, its programs traced and compiled;
* **warm**: the programs the cold run left on disk (the second run of a case of that shape: another current,
  another catch, the same case again);
* **warm, no pictures**: the same with ``--no-pictures`` (batch work: result.json and ParaView's files only).

Beside each run's wall time, what it printed of itself: the solve's wall and compile times and the outputs' time
(result.json, ParaView's files, net.png and net.html: the "wrote ... (in X s)" line); and, in separate processes,
the time to import what the command line needs first (``import jaxnet.cli``, ``jaxnet --version``) and what a
run of a FEMNET case imports before it solves. The times printed are the medians of ``--repeat`` runs, with their
ranges: a shared 2-core machine varies by tens of percent from run to run.

FEMNET's time: with ``--femnet "COMMAND {case}"`` (a shell command that runs FEMNET's mesher and static solver on
the case, ``{case}`` the .don's path without its suffix), timed in alternation with jaxnet's runs; otherwise the
wall time of FEMNET's current code on this kind of machine from the corpus' ``ANSWERS.md`` (its mesher and
solver, started as the corpus' job files start it: from the drawn shape, or from an earlier case's stored
equilibrium where the case is part of a chain; the table says which). The ratios are FEMNET's time over
jaxnet's. The project's targets (docs/validation.md): at least 2 cold and at least 4 warm on c2 and s3, the
outputs at most 1 s on c2, the import at most 1 s.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import re
import shlex
import statistics
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
CORPUS = ROOT.parent / "shared" / "femnet-corpus"


def femnet_answers(corpus):
    """{case ("5catch/c2"): (FEMNET's wall time s, how it started)} from the corpus' ANSWERS.md table."""
    out = {}
    for line in (corpus / "ANSWERS.md").read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) >= 5 and "/" in cells[0] and re.fullmatch(r"[\d.]+", cells[4]) and cells[3] == "yes":
            out[cells[0]] = (float(cells[4]), cells[1])
    return out


def timed(command, env=None):
    """(wall time s, stdout) of a shell-free command run to its end; raises if it fails."""
    t = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - t
    if done.returncode != 0:
        raise RuntimeError(f"{shlex.join(command)} exited {done.returncode}:\n{done.stdout}\n{done.stderr}")
    return wall, done.stdout


def printed_times(stdout):
    """The solve's wall and compile times and the outputs' time (s) a run printed of itself."""
    solve = re.search(r"wall ([\d.]+) s \(compile ([\d.]+) s", stdout)
    outputs = re.search(r"\(in ([\d.]+) s\)\s*$", stdout, flags=re.M)
    return (float(solve.group(1)) if solve else float("nan"), float(solve.group(2)) if solve else float("nan"),
            float(outputs.group(1)) if outputs else float("nan"))


def stats(values):
    values = [v for v in values if v == v]
    if not values:
        return "-"
    return f"{statistics.median(values):.2f} ({min(values):.2f}-{max(values):.2f})"


def median(values):
    values = [v for v in values if v == v]
    return statistics.median(values) if values else float("nan")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", nargs="*", default=["5catch/c2", "1pelagic_trawl/s3", "1pelagic_trawl/s3a"])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--corpus", type=pathlib.Path, default=CORPUS)
    parser.add_argument("--femnet", help="shell command running FEMNET's mesher and solver on {case} (the .don "
                                         "without its suffix), timed in alternation with jaxnet's runs")
    args = parser.parse_args()
    answers = femnet_answers(args.corpus)
    python = sys.executable
    env = dict(os.environ)
    print(f"{'import':42s} {'median (range) s':>22s}")
    probes = {"import jaxnet.cli (what --help needs)": [python, "-c", "import jaxnet.cli"],
              "jaxnet --version": [python, "-m", "jaxnet.cli", "--version"],
              "import for a FEMNET case's run": [python, "-c", "import jaxnet.cli, jaxnet.io.femnet, "
                                                 "jaxnet.solve.statics, jaxnet.figures, jaxnet.io.vtk"]}
    for name, command in probes.items():
        print(f"{name:42s} {stats([timed(command, env)[0] for _ in range(args.repeat)]):>22s}")
    print()
    header = (f"{'case':24s} {'run':18s} {'process s':>20s} {'solve s':>8s} {'compile s':>9s} {'outputs s':>9s} "
              f"{'FEMNET s':>9s} {'FEMNET/jaxnet':>13s}")
    print(header)
    print("-" * len(header))
    for case in args.cases:
        don = args.corpus / f"{case}.don"
        rows = {"cold": [], "warm": [], "warm, no pictures": []}
        femnet_runs = []
        for _ in range(args.repeat):
            with tempfile.TemporaryDirectory() as tmp:
                tmp = pathlib.Path(tmp)
                base = [python, "-m", "jaxnet.cli", "run", str(don), "--quiet", "--cache", str(tmp / "cache")]
                for run, extra in (("cold", []), ("warm", []), ("warm, no pictures", ["--no-pictures"])):
                    wall, out = timed([*base, "--out", str(tmp / run.replace(" ", "")), *extra], env)
                    rows[run].append((wall, *printed_times(out)))
                if args.femnet:
                    command = args.femnet.format(case=shlex.quote(str(don.with_suffix(""))))
                    t = time.perf_counter()
                    subprocess.run(command, shell=True, check=True, capture_output=True)
                    femnet_runs.append(time.perf_counter() - t)
        if femnet_runs:
            femnet, how = median(femnet_runs), "timed here"
        elif case in answers:
            femnet, how = answers[case][0], f"ANSWERS.md (FEMNET started {answers[case][1]})"
        else:
            femnet, how = float("nan"), "no time"
        for run, values in rows.items():
            walls = [v[0] for v in values]
            ratio = femnet / median(walls)
            print(f"{case:24s} {run:18s} {stats(walls):>20s} {median([v[1] for v in values]):8.2f} "
                  f"{median([v[2] for v in values]):9.2f} {median([v[3] for v in values]):9.2f} {femnet:9.2f} "
                  f"{ratio:13.2f}")
        print(f"{'':24s} FEMNET: {how}")


if __name__ == "__main__":
    main()
