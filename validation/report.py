"""The validation report: sections write Markdown, tables and plots into ``validation/REPORT.md`` as they run.

Every table of the report is generated from numbers measured in the run that writes it; none is typed by
hand. The report opens with the date, the machine and the versions, so that a reader knows what the
figures were measured on.

A section is a module of this package exposing ``TITLE`` (str) and ``run(report, quick)``. It calls the
methods of :class:`Report` below. The report is rewritten to disk after every call, so a long run that is
stopped keeps everything it measured (and ``validation/results/<section>.json`` keeps the raw records).
"""

from __future__ import annotations

import datetime
import json
import math
import os
import pathlib
import platform
import re
import subprocess
import sys
from collections.abc import Mapping, Sequence
from typing import Any

HERE = pathlib.Path(__file__).parent


def _git_revision():
    try:
        rev = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=HERE, capture_output=True, text=True,
                             timeout=10).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no"], cwd=HERE,
                               capture_output=True, text=True, timeout=10).stdout.strip()
        return (rev + (" (with uncommitted changes)" if dirty else "")) or "unknown"
    except (OSError, subprocess.SubprocessError):
        return "unknown"


def _cpu_name():
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def machine():
    """What the figures were measured on: a dict of strings."""
    import importlib.metadata as md

    import jax

    versions = {}
    for package in ("jax", "jaxlib", "equinox", "diffrax", "optax", "numpy", "scipy", "matplotlib"):
        try:
            versions[package] = md.version(package)
        except md.PackageNotFoundError:
            versions[package] = "absent"
    try:
        load = "{:.2f} {:.2f} {:.2f}".format(*os.getloadavg())
    except OSError:
        load = "unknown"
    return {
        "date": datetime.datetime.now().astimezone().isoformat(timespec="seconds"),
        "host": platform.node(),
        "cpu": f"{_cpu_name()}, {os.cpu_count()} logical cores",
        "devices": ", ".join(f"{d.platform}:{d.id}" for d in jax.devices()),
        "load average at start (1, 5, 15 min)": load,
        "python": sys.version.split()[0],
        "platform": platform.platform(),
        "jaxnet revision": _git_revision(),
        "versions": ", ".join(f"{k} {v}" for k, v in versions.items()),
    }


def fmt(value, spec=None):
    """A table cell: numbers to 4 significant figures (or ``spec``), booleans as yes/no, None as '-'."""
    if value is None:
        return "-"
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        if spec:
            return format(value, spec)
        if math.isnan(value):
            return "NaN"
        if value == 0 or 1e-3 <= abs(value) < 1e5:
            return f"{value:.4g}"
        return f"{value:.3e}"
    text = str(value)
    return text.replace("|", "\\|").replace("\n", " ")


def markdown_table(rows: Sequence[Mapping[str, Any]], columns: Sequence[str] | None = None,
                   formats: Mapping[str, str] | None = None) -> str:
    """Rows (dicts) as a Markdown table; ``columns`` picks and orders them (default: keys of the first row)."""
    if not rows:
        return "(no rows)\n"
    columns = list(columns or rows[0].keys())
    formats = formats or {}
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for row in rows:
        lines.append("| " + " | ".join(fmt(row.get(c), formats.get(c)) for c in columns) + " |")
    return "\n".join(lines) + "\n"


def _jsonable(value):
    import numpy as np

    if isinstance(value, Mapping):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else str(v)
    if isinstance(value, (np.integer, np.bool_)):
        return value.item()
    if isinstance(value, (int, bool, str)) or value is None:
        return value
    return str(value)


class Report:
    """A Markdown report written as it is built.

    path: the Markdown file (``validation/REPORT.md``); plots go to ``<path's folder>/plots/`` and raw records
    to ``<path's folder>/results/``. ``sections`` holds each section's Markdown so far; sections not run in
    this invocation keep the text they had in the file before (so ``--only`` refreshes one section without
    losing the others).
    """

    def __init__(self, path: str | os.PathLike, header: Mapping[str, str] | None = None, quick: bool = False):
        self.path = pathlib.Path(path)
        self.plots = self.path.parent / "plots"
        self.results = self.path.parent / "results"
        self.header = dict(header if header is not None else machine())
        self.quick = quick
        self.sections: dict[str, list[str]] = {}
        self.order: list[str] = []
        self.current: str | None = None
        self._previous = self._read_previous()

    # -- structure ----------------------------------------------------------------------------------------------
    def _read_previous(self):
        """Sections of the report already on disk: title -> Markdown body."""
        if not self.path.exists():
            return {}
        text = self.path.read_text()
        parts = re.split(r"^## (.+)$", text, flags=re.M)
        return {parts[i].strip(): parts[i + 1] for i in range(1, len(parts) - 1, 2) if parts[i].strip() != "Contents"}

    def start(self, title: str, known_titles: Sequence[str] = ()):
        """Begin the section ``title``; ``known_titles`` orders the sections of the whole report."""
        for t in known_titles:
            if t not in self.order:
                self.order.append(t)
        if title not in self.order:
            self.order.append(title)
        self.current = title
        self.sections[title] = []
        stamp = datetime.datetime.now().astimezone().isoformat(timespec="minutes")
        # each section dated with the commit it measured: sections of other runs keep theirs
        self._add(f"*Measured {stamp} at `{self.header.get('jaxnet revision', '?')}` on {self.header.get('host', '?')}"
                  + (" (quick sizes: `--quick`)" if self.quick else "") + ".*\n")

    def _add(self, markdown: str):
        if self.current is None:
            raise RuntimeError("Report: call start(title) before adding to a section")
        self.sections[self.current].append(markdown.rstrip("\n") + "\n")
        self._write()

    # -- content ------------------------------------------------------------------------------------------------
    def heading(self, text: str):
        """A sub-heading (###) inside the current section."""
        self._add(f"### {text}\n")

    def text(self, markdown: str):
        """A paragraph (or any Markdown) inside the current section."""
        self._add(markdown)

    def table(self, rows: Sequence[Mapping[str, Any]], columns: Sequence[str] | None = None,
              formats: Mapping[str, str] | None = None, caption: str | None = None):
        """A table from measured rows (dicts). ``formats`` maps a column to a format spec (e.g. ``".2e"``)."""
        md = (f"*{caption}*\n\n" if caption else "") + markdown_table(rows, columns, formats)
        self._add(md)

    def figure(self, fig, name: str, caption: str):
        """Save a matplotlib figure as ``plots/<name>.png`` and link it with its caption."""
        import matplotlib.pyplot as plt

        self.plots.mkdir(parents=True, exist_ok=True)
        target = self.plots / f"{name}.png"
        fig.savefig(target, dpi=110, bbox_inches="tight")
        plt.close(fig)
        rel = os.path.relpath(target, self.path.parent)
        self._add(f"![{caption}]({rel})\n\n*{caption}*\n")

    def record(self, name: str, data):
        """Keep raw records as ``results/<name>.json`` (numbers as measured, for anyone who wants to re-plot)."""
        self.results.mkdir(parents=True, exist_ok=True)
        (self.results / f"{name}.json").write_text(json.dumps(_jsonable(data), indent=1))

    # -- output -------------------------------------------------------------------------------------------------
    def markdown(self) -> str:
        lines = ["# jaxnet validation report", "",
                 "Generated by `python -m validation" + (" --quick" if self.quick else "") + "`; every table below"
                 " is measured by that run, none is typed by hand. Sections not run in the last invocation keep"
                 " their text from the run that wrote them.", ""]
        lines += [f"- **{k}**: {v}" for k, v in self.header.items()]
        titles = self.order + [t for t in self._previous if t not in self.order]
        lines += ["", "## Contents", ""]
        lines += [f"{i + 1}. [{t}](#{_anchor(t)})" for i, t in enumerate(titles)]
        lines.append("")
        for t in titles:
            if t in self.sections:
                body = "\n".join(self.sections[t])
            elif t in self._previous:
                body = self._previous[t].strip("\n") + "\n"
            else:
                body = "(not run yet)\n"
            lines += [f"## {t}", "", body.rstrip("\n"), ""]
        return "\n".join(lines)

    def _write(self):
        self.path.parent.mkdir(parents=True, exist_ok=True)
        tmp = self.path.with_suffix(".md.tmp")
        tmp.write_text(self.markdown())
        tmp.replace(self.path)


def _anchor(title: str) -> str:
    # GitHub's heading anchors: lower case, punctuation dropped, spaces to hyphens
    return re.sub(r"[^\w\- ]", "", title.lower()).replace(" ", "-")
