"""The benchmarks, run by the report: FEMNET's cases, dynamics, cost against size, stiffness paths, design.

Each script of ``benchmarks/`` (and the cone-program check of ``validation/``) measures one thing and prints its
own tables (see its docstring); the report runs it in a fresh process (so that compile caches and memory peaks
are its own) and keeps what it printed, verbatim. ``--quick`` passes each script the small sizes given in
:data:`SCRIPTS`.
"""

from __future__ import annotations

import pathlib
import subprocess
import sys
import time

TITLE = "Benchmarks: FEMNET's cases, dynamics, cost against size"

ROOT = pathlib.Path(__file__).resolve().parent.parent

#: script, by its path in the repository (with the arguments every run of it takes, when one script gives several studies) -> (what it
#: measures, arguments for --quick, arguments for the full study); ``{plots}`` is the report's folder of plots
SCRIPTS = {
    "benchmarks/femnet_cases.py": ("FEMNET's cases: FEMNET's figures beside jaxnet's, iterations, cold and warm times",
                        ["--repeat", "1"], []),
    "benchmarks/whole_process.py": ("`jaxnet run CASE.don` as a whole process, cold and with its programs on disk, against FEMNET",
                         ["--repeat", "1", "--cases", "5catch/c2"], []),
    "validation/cone_reference.py": ("A wall in still water: jaxnet's two static methods against Clarabel's interior point on "
                          "the cone program",
                          ["--steps", "0.1", "0.05"], ["--steps", "0.1", "0.05", "0.025"]),
    "benchmarks/dynamics.py": ("Dynamics: error against run time of the book's scheme and the diffrax reference, "
                         "cost per step against FEMNET's, steps per second against size",
                         ["--sizes", "1.6", "--cage-end", "1.0", "--cage-reference-end", "0.2",
                          "--plot", "{plots}/dynamics_work_precision.png"],
                         ["--plot", "{plots}/dynamics_work_precision.png"]),
    "benchmarks/statics.py": ("Static solver against size: panels from a flat start, iterations, assembly and "
                         "factorisation times, growth exponents", ["--sizes", "100", "1000", "10000"], []),
    "benchmarks/statics.py --scene trawl": ("Static solver against size on real gear: FEMNET's pelagic trawl s3 meshed "
                                       "finer", ["--sizes", "424", "1700", "--max-iter", "2000"],
                                       ["--sizes", "424", "1700", "6800", "--max-iter", "2000"]),
    "benchmarks/factorisation.py": ("Sparse direct factorisations side by side on the cage's and a FEMNET trawl's "
                               "tangents", ["--matrices", "cage0.5-it5", "trawl-s3x2-it5", "trawl-s3x2-it60",
                                            "--solvers", "HostSolver", "PARDISO-11nm", "MUMPS", "UMFPACK"],
                               ["--matrices", "cage0.5-it5", "trawl-s3x2-it5", "trawl-s3x2-it60", "cage0.17-it5",
                                "trawl-s3x5-it5", "trawl-s3x5-it60", "cage0.1-it5", "trawl-s3x9-it5",
                                "cage0.053-it5", "trawl-s3x15-it5"]),
    "benchmarks/stiffness.py": ("Closed-form and autodiff stiffness side by side, per term",
                          ["--elements", "1000", "10000", "--repeats", "3"], []),
    "benchmarks/terms.py": ("The cage at several refinements and the cost of every term",
                       ["--steps", "0.8", "0.5", "--repeats", "3", "--compile-repeats", "1"], []),
    "benchmarks/design.py": ("Design gradients on the cage and a FEMNET trawl, host-driven and traced: forward and gradient, "
                       "run and compile, and a second process's compile", ["--quick"], []),
    "benchmarks/design_sweep.py": ("Design sweeps: one process against a local cluster of two workers, cold and warm",
                        ["--scene", "panel", "--designs", "8"], ["--scene", "cage", "--designs", "24"]),
}


def _as_markdown(stdout: str) -> str:
    """A script's output in the report: Markdown tables kept as they are, plain text fenced; its headings
    demoted below the report's own (## is a section of the report)."""
    lines = [("#### " + line.lstrip("#").lstrip()) if line.startswith("#") else line for line in stdout.splitlines()]
    blocks, plain = [], []

    def flush():
        if any(p.strip() for p in plain):
            blocks.append("```\n" + "\n".join(plain).strip("\n") + "\n```")
        plain.clear()

    for line in lines:
        if line.startswith("|") or line.startswith("#### ") or (not line.strip() and not plain):
            flush()
            blocks.append(line)
        else:
            plain.append(line)
    flush()
    return "\n".join(blocks) + "\n"


def run(report, quick):
    report.text(__doc__.split("\n", 2)[2])
    report.plots.mkdir(parents=True, exist_ok=True)
    failed = []
    for key, (what, quick_args, full_args) in SCRIPTS.items():
        script, *fixed = key.split()
        args = fixed + [a.format(plots=report.plots) for a in (quick_args if quick else full_args)]
        command = [sys.executable, str(ROOT / script), *args]
        report.heading(f"`{key}`: {what}")
        print(f"  [benchmarks] {' '.join(command[1:])}", flush=True)
        t0 = time.perf_counter()
        out = subprocess.run(command, capture_output=True, text=True, cwd=ROOT)
        wall = time.perf_counter() - t0
        report.text(f"`python {script} {' '.join(args)}` ({wall:.0f} s):\n")
        if out.returncode:
            tail = "\n".join(out.stderr.strip().splitlines()[-15:])
            report.text(f"**Failed** (exit {out.returncode}):\n\n```\n{tail}\n```\n")
            failed.append(script)
            continue
        report.text(_as_markdown(out.stdout))
        if "--plot" in args:
            plot = pathlib.Path(args[args.index("--plot") + 1])
            report.text(f"![{script}]({plot.relative_to(report.path.parent)})\n")
    if failed:
        raise RuntimeError(f"benchmark scripts failed: {failed}")
