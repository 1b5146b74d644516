"""Runs in time driven from the host (``Implicit(loop="host")``, the default: programs kept on disk) against the
compiled loop (``loop="compiled"``: one program per run, with the factorisation as a host callback, compiled by
every process), as a user meets them: whole ``jaxnet run --dynamic`` processes.

    python benchmarks/dynamics_loops.py [--repeat 2]

Per scene and loop, in a fresh compilation cache: a first run to T1, then the same run resumed to T2 in a new
process (``--resume``), then resumed again to T3. Printed per process: its wall time (s, the interpreter's
start and JAX's import included), the first record interval's time (s: the compilation, or the programs'
loading, and that interval's steps) and the time per step after it (ms). Scenes: the built-in cage in waves
(the default of ``--dynamic``) and FEMNET's bottom seine s4 on its own mesh from its stored equilibrium, its
winch hauling. A benchmark, not a test: compare the loops within one run of this script.
"""

from __future__ import annotations

import argparse
import pathlib
import re
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
CORPUS = ROOT.parent / "shared" / "femnet-corpus"

#: (name, arguments of `jaxnet run`, time step (s), record interval (s), end times of the three processes (s))
SCENES = [
    ("cage_waves", ["--scene", "cage_waves"], 0.01, 0.1, (0.5, 1.0, 1.5)),
    ("femnet s4 (winch)", [str(CORPUS / "11bottom_seine" / "s4.don"), "--mesh", str(CORPUS / "11bottom_seine" / "s4.mdg"),
                           "--start", str(CORPUS / "11bottom_seine" / "s4.sta")], 0.5, 10.0, (40.0, 80.0, 120.0)),
]

SUMMARY = re.compile(r"(\d+) steps, .* wall ([\d.]+) s \(first interval with compilation ([\d.]+) s")


def one_process(args, end, resume, loop, cache, out, dt, record):
    cmd = [sys.executable, "-m", "jaxnet.cli", "run", *args, "--dynamic", "--end", str(end), "--dt", str(dt),
           "--record", str(record), "--loop", loop, "--cache", str(cache), "--out", str(out), "--quiet"]
    if resume:
        cmd.append("--resume")
    t0 = time.perf_counter()
    done = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT)
    wall = time.perf_counter() - t0
    match = SUMMARY.search(done.stdout)
    if done.returncode != 0 or match is None:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{done.stdout}\n{done.stderr}")
    return wall, int(match.group(1)), float(match.group(2)), float(match.group(3))


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeat", type=int, default=1, help="rounds of every scene and loop (default 1)")
    args = parser.parse_args(argv)
    print("| scene | loop | process | process wall s | first interval s | ms per step after it |")
    print("|---|---|---|---|---|---|")
    for _ in range(args.repeat):
        for name, run_args, dt, record, ends in SCENES:
            for loop in ("host", "compiled"):
                with tempfile.TemporaryDirectory() as tmp:
                    cache, out = pathlib.Path(tmp) / "cache", pathlib.Path(tmp) / "out"
                    steps_before = 0
                    for k, end in enumerate(ends):
                        wall, steps, run_wall, first = one_process(run_args, end, k > 0, loop, cache, out, dt, record)
                        per_interval = round(record / dt)
                        later = steps - steps_before - per_interval
                        per_step = 1e3 * (run_wall - first) / max(later, 1)
                        what = "first run" if k == 0 else f"resumed ({k})"
                        print(f"| {name} | {loop} | {what} | {wall:.2f} | {first:.2f} | {per_step:.2f} |", flush=True)
                        steps_before = steps
    return 0


if __name__ == "__main__":
    sys.exit(main())
