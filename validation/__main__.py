"""Regenerate the validation report: ``python -m validation [--quick] [--only NAME,...] [--report PATH]``.

Runs every section in order (or those named), writing ``validation/REPORT.md``, its plots
(``validation/plots/``) and raw records (``validation/results/``) as it goes. A section that raises is
reported as failed in the report (with the error) and the run goes on; the exit status is then 1.

``--quick`` runs every section on small sizes (minutes instead of the full study); the report says so.
"""

from __future__ import annotations

import argparse
import importlib
import pathlib
import sys
import time
import traceback

#: the sections, in report order: module name in this package
SECTIONS = ("convergence", "stability", "robustness", "femnet_corpus", "experiments", "bad_input", "benchmarks")


def main(argv=None):
    parser = argparse.ArgumentParser(prog="python -m validation", description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small sizes (the full study takes hours)")
    parser.add_argument("--only", default="", help=f"comma-separated sections among {', '.join(SECTIONS)}")
    parser.add_argument("--report", default=str(pathlib.Path(__file__).parent / "REPORT.md"),
                        help="the Markdown file written (plots/ and results/ beside it)")
    args = parser.parse_args(argv)
    chosen = [s.strip() for s in args.only.split(",") if s.strip()] or list(SECTIONS)
    unknown = [s for s in chosen if s not in SECTIONS]
    if unknown:
        parser.error(f"unknown section(s) {unknown}; the sections are {list(SECTIONS)}")

    import jaxnet  # noqa: F401  (float64 on before any section imports jax)

    from validation.report import Report

    modules = {name: importlib.import_module(f"validation.{name}") for name in SECTIONS}
    titles = [modules[name].TITLE for name in SECTIONS]
    report = Report(args.report, quick=args.quick)
    failed = []
    for name in chosen:
        module = modules[name]
        print(f"[validation] {name}: {module.TITLE}", flush=True)
        t0 = time.perf_counter()
        report.start(module.TITLE, titles)
        try:
            module.run(report, args.quick)
        except Exception as error:  # noqa: BLE001 -- a broken section is reported, the others still run
            failed.append(name)
            report.text(f"**This section failed**: `{type(error).__name__}: {error}`\n\n```\n"
                        f"{traceback.format_exc()}```\n")
            traceback.print_exc()
        report.text(f"*Section wall time: {time.perf_counter() - t0:.1f} s.*\n")
        print(f"[validation] {name}: done in {time.perf_counter() - t0:.1f} s", flush=True)
    print(f"[validation] report written to {report.path}" + (f"; FAILED: {failed}" if failed else ""))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
