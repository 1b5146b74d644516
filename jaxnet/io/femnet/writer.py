"""A design of a FEMNET case written back as a ``.don`` file FEMNET (and :func:`~.mapping.read_don`) can open.

A design study of a ``.don`` case (:class:`jaxnet.design.space.DesignSpace` of :func:`~.mapping.read_don`'s
case) changes numbers the file holds: its panels' corner mesh coordinates (U, V), their unstretched mesh side,
hydrodynamic diameter and traction stiffness, and its cables' unstretched lengths (a free cable's directly,
a rope sewn along netting through its hanging ratio). :func:`write_design` copies the source file line by line
and rewrites exactly those numbers on the lines they were read from, so the rest (node types, the ocean,
the solver's settings, comments, the commands at the end) stays as the author wrote it, and a design equal to
the file's writes the file unchanged.

What cannot be written: a mounting on fixed nodes whose hanging ratio changed (the fixed nodes' positions
would move: FEMNET's node positions are the corners' and cables' ends), sinkers and floats (a ``.don`` file's
weights are node types shared by many nodes), and hexagonal panels (no design family varies them).
Those raise ValueError naming the entry, before anything is written.

Conversions (the package's docstring, "Twine coordinates"): a corner's twine coordinates (u, v) of jaxnet are
FEMNET's mesh coordinates (U, V) as u = U + V, v = V - U, so U = (u - v) / 2 and V = (u + v) / 2.
"""

from __future__ import annotations

import pathlib
import re

import numpy as np

from jaxnet.io.femnet.links import all_panels
from jaxnet.io.femnet.parse import parse_don

__all__ = ["write_design", "mesh_coordinates"]

#: a number as FEMNET's files write them (C's %f and %e)
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")
#: values closer than this (relative) to the file's are the file's: written unchanged
_SAME = 1e-12


def mesh_coordinates(twines):
    """FEMNET's mesh coordinates (U, V) of corners at jaxnet's twine coordinates ``twines`` (..., 2) (u, v):
    U = (u - v) / 2, V = (u + v) / 2 (the inverse of :func:`~.grammar.twine_coordinates`)."""
    t = np.asarray(twines, dtype=float)
    return np.stack([0.5 * (t[..., 0] - t[..., 1]), 0.5 * (t[..., 0] + t[..., 1])], axis=-1)


def _format(value):
    """A number as FEMNET's files write it: fixed point with 6 decimals, more where they would round it away
    (a rope's length optimised to a tenth of a millimetre keeps its digits)."""
    text = f"{value:.6f}"
    return text if abs(float(text) - value) <= 1e-9 * max(1.0, abs(value)) else repr(float(value))


def _replace_numbers(line, columns, values, path, number):
    """``line`` with its numbers at ``columns`` (indices among the numbers after the label's colon, or of the
    whole line where it has no colon) replaced by ``values``."""
    start = line.rfind(":") + 1
    head, tail = line[:start], line[start:]
    spans = [m.span() for m in _NUMBER.finditer(tail)]
    if max(columns) >= len(spans):
        raise ValueError(f"{path}:{number}: expected {max(columns) + 1} numbers on the line, found {len(spans)}")
    out, last = [], 0
    for k, (a, b) in enumerate(spans):
        out.append(tail[last:a])
        out.append(_format(values[columns.index(k)]) if k in columns else tail[a:b])
        last = b
    out.append(tail[last:])
    return head + "".join(out)


def _changed(new, old):
    return abs(float(new) - float(old)) > _SAME * max(1.0, abs(float(old)))


def _cable_lengths(scene):
    """{cable name: total rest length (m)} of a scene's cables (the sum of their bars')."""
    if scene.bars is None:
        return {}
    cable, rest = np.asarray(scene.bars.cable), np.asarray(scene.bars.rest_length)
    return {name: float(rest[cable == k].sum()) for k, name in enumerate(scene.cable_names)}


def write_design(source, space, theta, path) -> pathlib.Path:
    """Write design ``theta`` of ``space`` as a ``.don`` file at ``path``, a copy of the ``source`` ``.don`` file
    with the design's numbers (see the module docstring).

    source: the ``.don`` file ``space`` was built from (``DesignSpace(read_don(source))``; read with
      ``refine=1`` or not, the numbers written are the design's, not the mesh's).
    theta: a design of ``space`` (partial: the rest is the reference), e.g. a rounded one
      (:meth:`~jaxnet.design.space.DesignSpace.rounded`): corners on fractions of a mesh are written as they are,
      FEMNET meshes them as it meshes its own.
    Returns the path written. Raises ValueError, before writing, for a design the file cannot hold (the module
    docstring), or a space whose panels or cables are not the file's.
    """
    source = pathlib.Path(source)
    full = space.complete(theta)
    space.check(full)
    don = parse_don(source)
    lines = source.read_text(errors="replace").split("\n")
    edits = {}  # line number (1-based) -> (columns, values)

    for name, mounting in space.mountings.items():
        if mounting.fixed and _changed(full["hanging_ratio"][name], space.initial()["hanging_ratio"][name]):
            raise ValueError(f"write_design: hanging_ratio[{name!r}] changed a border mounted on fixed nodes: their "
                             "positions would move, and a .don file holds them as the corners' own; keep it at "
                             "the reference to write the design")
    for family in ("sinker_mass", "buoyancy"):
        for name, value in full[family].items():
            if _changed(value, space.initial()[family][name]):
                raise ValueError(f"write_design: {family}[{name!r}] changed: a .don file's weights and floats are "
                                 "node types and sphere elements, which this writer does not rewrite")

    panels = {name: p for kind, _, p, name in all_panels(don) if kind == "pa"}
    for name in space.panels:
        if name not in panels:
            raise ValueError(f"write_design: the design's {name!r} is not a diamond panel of {source}")
        p = panels[name]
        corners = mesh_coordinates(np.asarray(full["cut"][name], dtype=float))
        if corners.shape != (len(p.corners), 2):
            raise ValueError(f"write_design: {name!r} has {len(p.corners)} corners in {source}, the design "
                             f"{corners.shape[0]}")
        for k, (U, V) in enumerate(corners):
            if _changed(U, p.corners[k, 3]) or _changed(V, p.corners[k, 4]):
                # the corner's line: number, x, y, z, U, V, type, following type
                edits[p.corner_type[k].line] = ([4, 5], [U, V])
        m = p.material
        for family, key in (("mesh_side", "l0"), ("twine_diameter", "diameter"), ("ea", "ea")):
            value = full[family].get(name)
            if value is not None and _changed(value, m[key].value):
                edits[m[key].line] = ([0], [float(value)])

    reference, lengths = _cable_lengths(space.reference), _cable_lengths(space.scene(full))
    for k, c in enumerate(don.cables):
        name = f"cable {k + 1}"
        if name in lengths and _changed(lengths[name], reference[name]):
            # the design's rope is the file's rope, longer or shorter by what the design changed
            edits[c.material["l0"].line] = ([0], [c.material["l0"].value * lengths[name] / reference[name]])

    for number, (columns, values) in edits.items():
        lines[number - 1] = _replace_numbers(lines[number - 1], columns, values, source, number)
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text("\n".join(lines))
    return path
