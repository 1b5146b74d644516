"""Designs and optimisation results as a netting maker reads them: short tables of cuts and parameters.

A design θ of a whole net holds an array per panel corner set and a number per panel, sinker, mounting and
cable: printed as a dict of arrays it fills screens. :class:`Design` is θ (a dict, and a pytree of the same
leaves) that prints as two tables instead: each panel's sides, meshes along them and their cutting rates
(:mod:`jaxnet.design.cut`), then every other value with its unit. :func:`result_table` is the account of an
optimisation (:class:`jaxnet.design.optimize.DesignResult` prints it): the objective and the constraint
violation at the start, at the best iterate and rounded to whole meshes, why it stopped, the design vector,
the cuts at the start, optimised and rounded, and the parameters that changed.

Alike entries share a row: panels (or sinkers, ...) whose rows read the same, to the digits shown, are
named together ("wall 0..7" for names differing only in a number), so the eight walls of a cage cut alike
are one block. Every line is shorter than :data:`WIDTH` characters (long names are cut with "…").
"""

from __future__ import annotations

import re

import jax
import numpy as np

from jaxnet.design import cut as cut_lib
from jaxnet.design.space import FAMILIES

__all__ = ["WIDTH", "Design", "design_table", "result_table", "side_cells"]

#: the longest line the tables print (characters); a label column is cut to fit
WIDTH = 110
#: the widest a name column grows (characters) before names are cut
NAME_WIDTH = 30
#: the most numbers of a design vector listed (a reduced vector is a few numbers; a larger one is cut short)
Z_ROWS = 24
#: how an optimisation's cut was made whole (:attr:`jaxnet.design.optimize.DesignResult.rounding`)
NEAREST, INWARD = "nearest whole meshes", "whole meshes, corners rounded outward taken one mesh in"


class Design(dict):
    """A design θ, {family: {entry: value}} as :class:`~jaxnet.design.space.DesignSpace` takes it, that prints
    as tables (:func:`design_table`).

    It is a dict (``DesignSpace.scene``, ``check``, ``rounded``, ``json`` take it as one) and a pytree with a
    dict's leaves in a dict's order (``jax.tree.map`` over it gives a Design back). Its pytree type is its own,
    though: to combine it with a plain dict in one ``jax.tree.map`` (a difference of designs), pass
    ``dict(design)``, a plain dict of the same families.
    """

    def __repr__(self):
        return design_table(self)

    __str__ = __repr__

    def _repr_pretty_(self, printer, cycle):  # IPython and Jupyter's text output
        printer.text(repr(self))


def _flatten_with_keys(design):
    keys = tuple(sorted(design))
    return tuple((jax.tree_util.DictKey(k), design[k]) for k in keys), keys


jax.tree_util.register_pytree_with_keys(
    Design, _flatten_with_keys, lambda keys, children: Design(zip(keys, children)),
    lambda design: (tuple(design[k] for k in sorted(design)), tuple(sorted(design))))


# -- names -------------------------------------------------------------------------------------------------


def _clip(text, width):
    return text if len(text) <= width else text[: width - 1] + "…"


def _runs(numbers):
    """'0..3,5,7..8' for a sorted list of distinct integers."""
    out, start = [], 0
    for k in range(1, len(numbers) + 1):
        if k == len(numbers) or numbers[k] != numbers[k - 1] + 1:
            a, b = numbers[start], numbers[k - 1]
            out.append(str(a) if a == b else f"{a}..{b}")
            start = k
    return ",".join(out)


def _numbered(names):
    """``"wall 0..7"`` for names differing only in one number, else None."""
    parts = [re.split(r"(\d+)", n) for n in names]
    if len({len(p) for p in parts}) != 1:
        return None
    differ = [k for k in range(len(parts[0])) if len({p[k] for p in parts}) > 1]
    if len(differ) != 1 or differ[0] % 2 == 0:  # odd slots of re.split with a group are the numbers
        return None
    k = differ[0]
    numbers = sorted(int(p[k]) for p in parts)
    if len(set(numbers)) != len(numbers):
        return None
    return "".join(parts[0][:k]) + _runs(numbers) + "".join(parts[0][k + 1:])


def group_name(names) -> str:
    """One label for alike entries: the name itself; ``"wall 0..7"`` for names differing only in one number
    (``"wall 0..7, bottom 0..7"`` for several such families of names); the names listed when short; else
    the first name and how many more."""
    names = [str(n) for n in names]
    if len(names) == 1:
        return names[0]
    kinds = {}  # names by their skeleton, the numbers taken out
    for n in names:
        kinds.setdefault(re.sub(r"\d+", "#", n), []).append(n)
    labels = [(_numbered(group) if len(group) > 1 else group[0]) for group in kinds.values()]
    if all(labels):
        listed = ", ".join(labels)
        if len(listed) <= NAME_WIDTH:
            return listed
    listed = ", ".join(names)
    return listed if len(listed) <= NAME_WIDTH else f"{names[0]} (+{len(names) - 1} alike)"


def _grouped(items):
    """[(label, rows)] from [(name, rows)], the names with equal rows together, in order of first appearance."""
    groups = {}
    for name, rows in items:
        groups.setdefault(tuple(map(tuple, rows)), []).append(name)
    return [(group_name(names), [list(r) for r in rows]) for rows, names in groups.items()]


# -- cuts -------------------------------------------------------------------------------------------------


def side_cells(corners) -> list:
    """Per side of a panel of corners (C, 2) (U, V): (meshes along it, cutting rate, du, dv) as text, read by
    :func:`jaxnet.design.cut.describe_sides`: a whole side exactly, a side between whole twines (an optimiser's
    real cut) with its meshes to two decimals and the rate of the nearest whole side, marked "≈"."""
    out = []
    for s in cut_lib.describe_sides(np.asarray(corners, dtype=float)):
        if s.whole:
            out.append((f"{s.meshes:g}", s.rate, f"{s.du:+g}", f"{s.dv:+g}"))
        else:
            out.append((f"{s.meshes:.2f}", s.rate, f"{s.du:+.4g}", f"{s.dv:+.4g}"))
    return out


def _table(header, rows, right):
    """Lines of a table: columns as wide as their widest cell, right-aligned where ``right`` says."""
    widths = [max(len(str(r[k])) for r in [header, *rows]) for k in range(len(header))]
    lines = []
    for r in [header, *rows]:
        cells = [str(c).rjust(w) if a else str(c).ljust(w) for c, w, a in zip(r, widths, right)]
        lines.append("  ".join(cells).rstrip())
    return lines


def _cut_block(labelled):
    """Rows [panel, side, *cells] of grouped panels: the panel named on its first side only."""
    rows = []
    for label, sides in labelled:
        for k, cells in enumerate(sides):
            rows.append([_clip(label, NAME_WIDTH) if k == 0 else "", str(k), *cells])
    return rows


def _value(v):
    """A parameter's value as text: a number, or an array's shape."""
    a = np.asarray(v, dtype=float)
    return f"{float(a):.6g}" if a.ndim == 0 else f"array {a.shape}"


def design_table(theta) -> str:
    """A design θ ({family: {entry: value}}, any subset of the families) as text: each panel's sides (meshes
    along, cutting rate, extent du, dv in meshes), then every other value with its unit; alike panels and
    entries share a row (see the module docstring)."""
    theta = dict(theta)
    lines = []
    cuts = theta.get("cut") or {}
    if cuts:
        lines.append("cut: meshes along each side, cutting rate (≈: between whole meshes), extent du, dv (meshes)")
        labelled = _grouped([(p, side_cells(c)) for p, c in cuts.items()])
        lines += _table(["panel", "side", "meshes", "rate", "du", "dv"], _cut_block(labelled),
                        [False, True, True, False, True, True])
    rows = []
    for family, entries in theta.items():
        if family == "cut":
            continue
        unit = FAMILIES.get(family, ("",))[0]
        if not isinstance(entries, dict):
            rows.append([_clip(str(family), NAME_WIDTH + 20), _value(entries), unit])
            continue
        for label, (row,) in _grouped([(name, [[_value(v)]]) for name, v in entries.items()]):
            rows.append([_clip(f"{family}[{label}]", NAME_WIDTH + 20), row[0], unit])
    if rows:
        lines += ([""] if lines else []) + _table(["parameter", "value", "unit"], rows, [False, True, False])
    return "\n".join(lines) if lines else "(an empty design)"


# -- an optimisation's account ------------------------------------------------------------------------------


def _number(v, digits=7):
    return "-" if v is None else f"{float(v):.{digits}g}"


def result_table(result) -> str:
    """The account of an optimisation (:class:`jaxnet.design.optimize.DesignResult`) as text; see the module
    docstring. The cuts are those of the panels the optimisation varied, at the start, optimised (the best
    iterate, real) and rounded to whole meshes (``result.rounded``, as ``result.cut_report`` reads it)."""
    h = result.history
    best = result.step
    lines = [f"stopped: {result.reason} after {len(h) - 1} step{'s' if len(h) != 2 else ''} (best: step {best}); "
             f"{sum(r['newton_iterations'] for r in h)} Newton iterations in {h[-1]['wall_s']:.0f} s"]
    rounded = result.rounded is not None
    header = ["", "start", "best", *(["rounded"] if rounded else [])]
    rows = [["objective", _number(h[0]["objective"]), _number(result.value),
             *([_number(result.rounded_value)] if rounded else [])],
            ["violation", _number(h[0]["violation"], 3), _number(h[best]["violation"], 3),
             *([_number(result.rounded_violation, 3)] if rounded else [])]]
    lines += _table(header, rows, [False, True, True, True])
    if rounded and getattr(result, "rounding", None) not in (None, NEAREST):
        lines.append(f"rounded to {result.rounding}")
    if result.z is not None:
        from jaxnet.design.reduced import coordinate_names

        names = coordinate_names(result.z)
        start = np.concatenate([np.ravel(a) for a in jax.tree.leaves(result.z_start)])
        end = np.concatenate([np.ravel(a) for a in jax.tree.leaves(result.z)])
        rows = [[_clip(n, NAME_WIDTH), _number(a, 6), _number(b, 6)] for n, a, b in zip(names, start, end)]
        lines += [""] + _table(["design vector", "start", "best"], rows[:Z_ROWS], [False, True, True])
        if len(rows) > Z_ROWS:
            lines.append(f"… and {len(rows) - Z_ROWS} more numbers (result.z)")
    cuts = result.theta.get("cut") or {}
    if cuts:
        lines += ["", "cut: meshes along each side and cutting rate (≈: between whole meshes)"]
        items = []
        for p in cuts:
            columns = [side_cells(result.start["cut"][p]), side_cells(cuts[p])]
            if rounded:
                columns.append(side_cells(result.rounded["cut"][p]))
            items.append((p, [[f"{c[0]} {c[1]}" for c in sides] for sides in zip(*columns)]))
        lines += _table(["panel", "side", "start", "optimised", *(["rounded"] if rounded else [])],
                        _cut_block(_grouped(items)), [False, True, False, False, False])
    rows = []
    for family, entries in result.theta.items():
        if family == "cut":
            continue
        unit = FAMILIES.get(family, ("",))[0]
        if not isinstance(entries, dict):  # not a design family: a value of its own
            entries = {None: entries}
        changed = []
        for name, v in entries.items():
            at = (lambda d: d[family]) if name is None else (lambda d: d[family][name])  # noqa: E731
            values = [at(result.start), v]
            if rounded:
                values.append(at(result.rounded))
            cells = [_value(a) for a in values]
            if any(not np.allclose(np.asarray(a, float), np.asarray(values[0], float), rtol=1e-12, atol=0.0)
                   for a in values[1:]):
                changed.append((name, [cells]))
        for label, (cells,) in _grouped(changed):
            rows.append([_clip(str(family) if label is None else f"{family}[{label}]", NAME_WIDTH + 10), *cells, unit])
    if rows:
        lines += [""] + _table(["parameter", "start", "optimised", *(["rounded"] if rounded else []), "unit"], rows,
                               [False, True, True, *([True] if rounded else []), False])
    return "\n".join(lines)
