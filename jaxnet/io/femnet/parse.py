"""Reading a ``.don`` file into a :class:`~.grammar.DonFile` (phobos ``chargement_don.c``'s order), with the
tables of :mod:`.grammar`, and the checks that concern several fields of a part or a section.

Every error is a :class:`~jaxnet.scene.SceneError` ``file:LINE: message`` (see the package's docstring,
"Strictness").
"""

from __future__ import annotations

import math
import pathlib
import re

import numpy as np

from jaxnet.io.femnet.grammar import (
    CABLE_MATERIAL, CABLES_NUMBER, CATCH, DESIGN_PLANE, DISPLAYS, HEADINGS, HEXAGONAL_PANEL_MATERIAL,
    HEXAGONAL_PANELS_NUMBER, INPUTS, LINKS_NUMBER, MAX_PANEL_NODES, NODE_TYPE, NODE_TYPES_NUMBER, NUMERICS, OCEAN,
    PANEL_CORNERS, PANEL_MATERIAL, PANELS_NUMBER, PART_NAMES, SEA_BED, SLIDING_CABLES_NUMBER, TEXT_OUTPUT_COMMENT,
    TEXT_OUTPUT_DECIMALS, TEXT_OUTPUT_ENTRIES, TEXT_OUTPUT_HEADING, TEXT_OUTPUTS, DonCable, DonFile, DonLink,
    DonNodeType, DonPanel, Occurrence, TextOutput, read, read_all, twine_coordinates)
from jaxnet.io.femnet.reader import MAX_COORDINATE, Reader, Value
from jaxnet.scene import SceneError


def parse_don(path) -> DonFile:
    """Read a ``.don`` file into a :class:`~.grammar.DonFile` (values with their line numbers), checking every
    label."""
    path = pathlib.Path(path)
    if not path.exists():
        raise SceneError(f"FEMNET case {path} does not exist")
    r = Reader(path.read_text(errors="replace"), str(path))
    first = r.text.lstrip().split(None, 1)[0] if r.text.strip() else ""
    if first.lower().startswith("version"):
        raise r.error(f"FEMNET file format {first!r} is not supported (only the original format)")
    orientation = read(r, DESIGN_PLANE)
    n_panels = read(r, PANELS_NUMBER)
    panels = [_parse_panel(r, k, hexagonal=False) for k in range(n_panels.value)]
    n_hexa = read(r, HEXAGONAL_PANELS_NUMBER)
    hexagonal = [_parse_panel(r, k, hexagonal=True) for k in range(n_hexa.value)]
    n_cables = read(r, CABLES_NUMBER)
    cables = [_parse_cable(r, k) for k in range(n_cables.value)]
    read(r, SLIDING_CABLES_NUMBER)
    counts = {"pa": [len(p.corners) for p in panels], "ha": [len(p.corners) for p in hexagonal],
              "el": [2] * len(cables)}
    n_links = read(r, LINKS_NUMBER)
    links = [_parse_link(r, k, counts) for k in range(n_links.value)]
    order = _parse_order(r, counts)
    n_types = read(r, NODE_TYPES_NUMBER)
    types = {}
    for t in range(n_types.value):
        number, node_type = _parse_node_type(r, t)
        if number.value in types:
            raise r.error(f"node type {number.value} is described twice", number.line)
        types[number.value] = node_type
    numeric = read_all(r, NUMERICS)
    if numeric["record_end"].value > 0:
        for key, what in (("dt", "dynamic time step"), ("record_dt", "dynamic record time step")):
            if not numeric[key].value > 0:
                raise r.error(f"{what} {numeric[key].value!r} s: a dynamic case (end time "
                              f"{numeric['record_end'].value!r} s) needs it > 0", numeric[key].line)
    ocean = read_all(r, OCEAN)
    if ocean["wave_height"].value > 0 and not ocean["wave_period"].value > 0:
        raise r.error(f"wave period {ocean['wave_period'].value!r} s: waves of height {ocean['wave_height'].value!r} m "
                      "need a period > 0", ocean["wave_period"].line)
    catch = read_all(r, CATCH)
    ocean.update(read_all(r, SEA_BED))
    stiffness = ocean["bottom_stiffness"]
    limited = [(t, nt) for t, nt in types.items() if nt.has_limit]
    if limited and not stiffness.value > 0:
        # FEMNET's fond.c pushes a node back by (limit - x) times this stiffness: with 0 its floor does nothing
        t, nt = limited[0]
        raise r.error(f"stiffness of the insertion in the sea bottom is {stiffness.value!r} N/m, but node type {t} has "
                      f"limits (sense {[v.value for v in nt.sense]}, line {nt.sense[0].line}): FEMNET's floor or "
                      "ceiling pushes with this stiffness, so with 0 it does nothing; give a stiffness > 0 N/m (or the "
                      "senses 0)", stiffness.line)
    text_outputs = _parse_text_outputs(r)
    read_all(r, DISPLAYS)
    inputs, outputs, commands = _commands(r)
    for k, p in enumerate(panels):
        # FEMNET's maillage_panneau (maillage.c) honours Meshing_UV for meshing type 2 only (materials.meshing_lattices)
        lattice = inputs.get(f"meshing_uv {k + 1}")
        if lattice is not None and p.material["mesh_type"].value != 2:
            r.warnings.append(f"{path}:{lattice.line}: 'input Meshing_UV {k + 1}': panel {k + 1} has meshing type "
                              f"{p.material['mesh_type'].value}, and FEMNET uses the command for type 2 only: ignored")
            lattice = None
        _check_node_estimate(r, p, f"panel {k + 1}", lattice)
    for k, p in enumerate(hexagonal):
        _check_node_estimate(r, p, f"hexagonal panel {k + 1}")
    return DonFile(str(path), panels, cables, order, types, numeric, ocean, catch, inputs, outputs, hexagonal, links,
                   orientation.value, text_outputs, commands, r.warnings)


def _parse_text_outputs(r):
    """FEMNET's text outputs (``lectureDo4.c``): per kind, its count, then per entry a heading and its number, a
    comment (``#words#``, what FEMNET prints beside the figure), the entry's fields
    (:data:`~.grammar.TEXT_OUTPUT_ENTRIES`) and its number of decimals. Returns [:class:`~.grammar.TextOutput`]."""
    out = []
    for f in TEXT_OUTPUTS:
        count = read(r, f)
        for i in range(count.value):
            what = f"{f.what.removesuffix(' number')} {i + 1}"
            r.label(TEXT_OUTPUT_HEADING, f"{what}: heading")
            r.integer(f"{what} number")
            r.label(TEXT_OUTPUT_COMMENT, f"{what}: comment")
            # the comment is written between two '#', and may hold a colon itself ("#z_max (m) : #")
            opening = re.compile(r"[ \t]*#").match(r.text, r.pos)
            closing = r.text.find("#", opening.end()) if opening else -1
            comment = ""
            if closing >= 0 and "\n" not in r.text[r.pos:closing]:
                comment = r.text[opening.end():closing]
                r.pos = closing + 1
            values = {}
            for key, label, name in TEXT_OUTPUT_ENTRIES[f.key]:
                r.label(label, f"{what}: {name}")
                values[key] = r.integer(f"{what}: {name}", 0).value
            r.label(TEXT_OUTPUT_DECIMALS, f"{what}: decimal nb")
            decimals = r.integer(f"{what}: decimal nb", 0)
            out.append(TextOutput(f.key, values, " ".join(comment.strip("#").split()), decimals.value, count.line))
    return out


def _parse_panel(r, k, hexagonal):
    """One diamond or hexagonal panel (phobos ``chargement_don.c``): corners, then the material fields
    (:data:`~.grammar.PANEL_MATERIAL`, :data:`~.grammar.HEXAGONAL_PANEL_MATERIAL`)."""
    name = f"{'hexagonal ' if hexagonal else ''}panel {k + 1}"
    r.label(HEADINGS["panel"], name)
    r.integer(f"{name} number")
    nc = read(r, PANEL_CORNERS, f"{name}: ")
    r.label(HEADINGS["contour"], f"{name}: nodes of the contour")
    rows, ctype, stype, lines = [], [], [], []
    for c in range(nc.value):
        what = f"{name} corner {c + 1}"
        number = r.integer(f"{what} number")
        vals = [r.number(f"{what} {coord}", "position" if coord in "xyz" else "meshes")
                for coord in ("x", "y", "z", "U", "V")]
        rows.append([v.value for v in vals])
        lines.append(vals[0].line)
        ctype.append(r.integer(f"{what} node type", 1))
        stype.append(r.integer(f"{what} following side type", 1))
        r.one_line([number, *vals, ctype[-1], stype[-1]], number.line, what, "no x y z U V type following-type",
                   (f"{name} corner {c}", lines[-2]) if c else None)
    if hexagonal:
        # FEMNET reads the rest of the last corner's line, then skips one whole line (two fgets) before the
        # fields: a field written on that line would be lost to FEMNET, so it must hold none
        skipped = stype[-1].line + 1
        if skipped <= len(r.starts):
            text = r.line_text(skipped)
            if ":" in text:
                raise r.error(f"{name}: FEMNET skips the line after the last corner of a hexagonal panel, but it holds "
                              f"a field ({text.strip()!r}); leave a line (blank or a comment without ':') there",
                              skipped)
    mat = read_all(r, HEXAGONAL_PANEL_MATERIAL if hexagonal else PANEL_MATERIAL, f"{name}: ")
    t = mat["mesh_type"]
    # FEMNET meshes netting into triangles with types 1 and 2; higher types model the twines as bars
    # (maillage.c: 3 and 4 for diamond panels, 3 for hexagonal ones), another model. Type 4 is numerical twines,
    # the type 'input netting2ropes' gives its panel (with its parameters: jaxnet.io.femnet.twines checks that
    # a panel of type 4 has them); type 3 (maillage_interne5: a bar per twine of a rectangular panel) is refused
    if t.value == 3:
        raise r.error(f"{name}: meshing type {t.value} (twines as bar elements) is not supported (only 1 or 2: "
                      "triangular netting elements, or numerical twines with 'input netting2ropes')", t.line)
    if t.value not in ((1, 2) if hexagonal else (1, 2, 4)):
        raise r.error(f"{name}: meshing type must be 1 or 2{'' if hexagonal else ' (4: numerical twines)'}, got "
                      f"{t.value}", t.line)
    corners = np.array(rows)
    _check_contour(r, corners, lines, name)
    return DonPanel(corners, ctype, stype, mat, nc.line, hexagonal)


def _check_node_estimate(r, p, name, lattice=None):
    """Refuse a panel whose mesh would be too large to be meant (FEMNET's own limit is 20000 nodes in all,
    phobos.h NBMAXNOEUD) before trying to make it: jaxnet meshes with a step of h twines (base meshes for
    hexagonal netting), or, with ``input Meshing_UV`` (``lattice`` = its line's Value (PANEL, NU, NV)), on the
    lattice of every NU, NV meshes (:func:`~jaxnet.mesh.panel.mesh_panel`): about one node per lattice cell
    (area / (NU NV), the area in meshes²) and one per cell along the sides. Checked once the commands are
    read, since the command comes after the panels."""
    mat = p.material
    if lattice is not None:
        UV = p.corners[:, 3:5] / np.array(lattice.value[1:])
        nxt = np.roll(UV, -1, axis=0)
        area = 0.5 * abs(np.sum(UV[:, 0] * nxt[:, 1] - nxt[:, 0] * UV[:, 1]))
        estimate = area + np.hypot(*(nxt - UV).T).sum()
        if not estimate <= MAX_PANEL_NODES:
            raise r.error(f"{name}: 'input Meshing_UV' {lattice.value[1]:g} {lattice.value[2]:g} gives about "
                          f"{estimate:.3g} nodes (limit {MAX_PANEL_NODES}); use a coarser lattice", lattice.line)
        return
    if p.hexagonal:
        uv, h = p.corners[:, 3:5], mat["step"].value / (3.0 * np.mean([v.value for v in mat["l0"]]))
    else:
        uv, h = twine_coordinates(p.corners[:, 3:5]), mat["step"].value / mat["l0"].value
    nxt = np.roll(uv, -1, axis=0)
    area = 0.5 * abs(np.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1]))
    with np.errstate(all="ignore"):  # a step that underflows h to 0 estimates inf nodes, refused below
        estimate = area / (h * h * math.sqrt(3.0) / 2.0) + np.hypot(*(nxt - uv).T).sum() / h
    if not estimate <= MAX_PANEL_NODES:
        raise r.error(f"{name}: meshing step {mat['step'].value!r} m gives about {estimate:.3g} nodes (limit "
                      f"{MAX_PANEL_NODES}); use a larger step", mat["step"].line)


def _check_contour(r, corners, lines, name):
    """The panel's contour in twine coordinates must enclose an area (no repeated corner, not collinear)."""
    uv = twine_coordinates(corners[:, 3:5])
    nxt = np.roll(uv, -1, axis=0)
    for c in range(len(uv)):
        if np.allclose(uv[c], nxt[c], rtol=0, atol=1e-12):
            raise r.error(f"{name}: corners {c + 1} and {(c + 1) % len(uv) + 1} have the same (U, V)", lines[c])
    area = 0.5 * np.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1])
    scale = np.ptp(uv, axis=0).max() ** 2
    if not abs(area) > 1e-9 * max(scale, 1e-300):
        raise r.error(f"{name}: the (U, V) contour of its corners is collinear (no area): "
                      f"{corners[:, 3:5].tolist()}", lines[0])


def _parse_cable(r, k):
    """One cable (``chargement_don.c``): its two ends (no x y z type on one line each), then its material
    (:data:`~.grammar.CABLE_MATERIAL`)."""
    r.label(HEADINGS["cable"], f"cable {k + 1}")
    r.integer(f"cable {k + 1} number")
    r.label(HEADINGS["cable ends"], f"cable {k + 1}: extremities")
    ends, etype, rows = [], [], []
    for e in range(2):
        what = f"cable {k + 1} end {e + 1}"
        number = r.integer(f"{what} number")
        row = [r.number(f"{what} {name}", "position") for name in "xyz"]
        etype.append(r.integer(f"{what} node type", 1))
        rows.append((what, [number, *row, etype[-1]]))
        ends.append([v.value for v in row])
    # one end per line, or FEMNET's short syntax: both ends on one line (``Ca: 1 D: 1 x y z type 2 x y z type
    # Kt: ...``, the cable's whole description on its line)
    (what1, first), (what2, second) = rows
    if second[0].line == first[0].line:
        r.one_line(first + second, first[0].line, f"cable {k + 1}: extremities", "no x y z type no x y z type")
    else:
        r.one_line(first, first[0].line, what1, "no x y z type")
        r.one_line(second, second[0].line, what2, "no x y z type", (what1, first[0].line))
    mat = read_all(r, CABLE_MATERIAL, f"cable {k + 1}: ")
    return DonCable(np.array(ends), etype, mat, etype[0].line)


def _parse_node_type(r, t):
    """The ``t``-th node type (0-based): (its number, :class:`~.grammar.DonNodeType`), its fields
    :data:`~.grammar.NODE_TYPE` checked together."""
    r.label(HEADINGS["node type"], f"node type {t + 1}")
    number = r.integer(f"node type {t + 1} number", 1)
    f = read_all(r, NODE_TYPE, f"node type {number.value}: ")
    # added mass only acts in dynamics (FEMNET's lectureDo4.c): kept in the info, no effect in statics
    _check_body(r, number.value, f["length"])
    for v in f["sense"]:
        if v.value not in (-1, 0, 1):
            raise r.error(f"node type {number.value}: limits sense must be -1 (ceiling), 0 (none) or 1 (floor), "
                          f"got {v.value}", v.line)
    for a, (v, s) in enumerate(zip(f["limit"], f["sense"])):
        # a limit without a sense is never read (FEMNET's fond.c tests the sense first): any number will do
        if s.value and not abs(v.value) <= MAX_COORDINATE:
            raise r.error(f"node type {number.value}: limits {'XYZ'[a]} {v.value!r} m is out of range (at most "
                          f"{MAX_COORDINATE:g} m from the origin)", v.line)
    mass = f["mass"]
    if len({m.value for m in mass}) > 1:
        raise r.error(f"node type {number.value}: anisotropic mass {[m.value for m in mass]} is not supported "
                      "(give the same mass along X, Y and Z)", mass[0].line)
    return number, DonNodeType([m.value for m in mass], [v.value for v in f["force"]], f["fixed"], f["symmetry"],
                               number.line, [v.value for v in f["added_mass"]], f["length"], f["drag_coefficient"],
                               f["limit"], f["sense"])


def _check_body(r, t, length):
    """A node type's box (FEMNET's "Length X,Y,Z"): widths X, Y >= 0 (FEMNET's drag takes them signed, a negative
    one would be a drag against the current), a height Z of either sign (< 0: the box hangs below its node, a
    sinker), sizes in range. A box with a volume floats (``flotteur2.c``: rho g L_x L_y times its immersed height,
    along z): see :func:`~.surroundings.node_type_fields`."""
    for a, v in enumerate(length):
        if a < 2 and v.value < 0:
            raise r.error(f"node type {t}: length {'XYZ'[a]} must be >= 0 m (a width of its box), got {v.value!r}",
                          v.line)
        if not abs(v.value) <= MAX_COORDINATE:
            raise r.error(f"node type {t}: length {'XYZ'[a]} {v.value!r} m is out of range (at most "
                          f"{MAX_COORDINATE:g} m)", v.line)


def _parse_link(r, k, counts):
    """One link (``chargement_don.c``): its number of points, then per point the structure (pa: diamond panel,
    ha: hexagonal panel, el: cable; FEMNET goes by the first letter) and its corner or end (nd:). ``counts``:
    {kind: [number of corners (ends) per part]}."""
    r.label(HEADINGS["link"], f"link {k + 1}")
    n = r.integer(f"link {k + 1}: number of points", 1)
    members, seen = [], set()
    for i in range(n.value):
        what = f"link {k + 1} point {i + 1}"
        label = r.label(HEADINGS["link structure"], f"{what}: structure (pa:, ha: or el:)")
        if label[0] in "cw":
            raise r.error(f"{what}: '{label}:' links a {'sliding cable' if label[0] == 'c' else 'winch'}, not supported",
                          r.line(r.pos - 1))
        kind = {"p": "pa", "h": "ha", "e": "el"}[label[0]]
        name = PART_NAMES[kind]
        idx = r.integer(f"{what}: {name} number", 1)
        if idx.value > len(counts[kind]):
            raise r.error(f"{what}: there is no {name} {idx.value} (the case has {len(counts[kind])})", idx.line)
        r.label(HEADINGS["link corner"], f"{what}: corner (nd:)")
        corner = r.integer(f"{what}: corner of {name} {idx.value}", 1)
        if corner.value > counts[kind][idx.value - 1]:
            raise r.error(f"{what}: {name} {idx.value} has no {'end' if kind == 'el' else 'corner'} {corner.value} "
                          f"(it has {counts[kind][idx.value - 1]})", corner.line)
        key = (kind, idx.value - 1, corner.value - 1)
        if key in seen:
            raise r.error(f"{what}: {name} {idx.value} corner {corner.value} is listed twice in link {k + 1}",
                          corner.line)
        seen.add(key)
        members.append((*key, corner.line))
    return DonLink(members, n.line)


def _parse_order(r, counts):
    """The meshing order: ``el: k``, ``pa: k``, ``ha: k`` entries, every cable and panel once; or FEMNET's
    shorthand, a word beginning with 'a' (cables, then panels, then hexagonal panels, each in number order)
    or 'b' (panels, hexagonal panels, then cables)."""
    r.label(HEADINGS["meshing order"], "meshing order")
    words = re.compile(r"\s*(\S+)").match(r.text, r.pos)
    if words and words.group(1)[0].lower() in "ab" and ":" not in words.group(1):
        r.pos = words.end()
        entries = {kind: [(kind, j + 1) for j in range(len(counts[kind]))] for kind in counts}
        first = words.group(1)[0].lower() == "a"
        return entries["el"] + entries["pa"] + entries["ha"] if first else entries["pa"] + entries["ha"] + entries["el"]
    order, seen = [], set()
    for _ in range(sum(len(v) for v in counts.values())):
        kind = r.label(HEADINGS["meshing order entry"], "meshing order entry (el:, pa: or ha:)")
        kind = "ha" if kind == "he" else kind
        idx = r.integer(f"meshing order {kind}", 1)
        if idx.value > len(counts[kind]) or (kind, idx.value) in seen:
            raise r.error(f"meshing order: '{kind}: {idx.value}' is not a {PART_NAMES[kind]} of the case, or is "
                          "listed twice", idx.line)
        seen.add((kind, idx.value))
        order.append((kind, idx.value))
    return order


def _commands(r):
    """The free-order tail: ``input NAME values`` and ``output NAME ...`` lines (:data:`~.grammar.COMMANDS`),
    comments (# or //). Every ``output`` is read (FEMNET's print and drawing commands change nothing); an ``input``
    must be one of :data:`~.grammar.INPUTS`, with its number of values and their checks, and is refused when
    jaxnet does not model it. Returns ({input name: Value of its last occurrence}, [output lines as written],
    [(input name, values, line) of every input])."""
    inputs, outputs, commands = {}, [], []
    start = r.line(r.pos)
    rest = r.text[r.pos:].split("\n")
    table_lines = set()
    for i, raw in enumerate(rest):
        line_no = start + i
        words = raw.split()
        if i in table_lines:
            continue
        if i == 0 and words:  # the remainder of the last field's line: the display flag was read already
            raise r.error(f"unexpected text {raw.strip()!r} after the last field", line_no)
        if not words:
            continue
        if words[0].startswith("#") or words[0].startswith("//"):
            # a command commented out: its time table, if it has one, is commented out with it (FEMNET's reader
            # skips the numbers that follow no command)
            commented = raw.strip().lstrip("#/").split()
            command = INPUTS.get(commented[1].lower()) if len(commented) >= 2 and commented[0] == "input" else None
            if command is not None and command.table is not None:
                try:
                    values = [float(w) for w in commented[2:]]
                    if len(values) in command.counts:
                        _table(r, rest, i, start, command, values, table_lines)
                except (ValueError, SceneError):
                    pass
            continue
        kind = words[0].lower()
        if kind not in ("input", "output") or len(words) < 2:
            raise r.error(f"expected 'input NAME ...' or 'output NAME', found {raw.strip()!r}", line_no)
        name = words[1]
        if kind == "output":
            outputs.append(" ".join(words[1:]))
            continue
        if name.lower() not in INPUTS:
            raise r.error(f"'input {name}': unknown input command, not supported (known: {sorted(INPUTS)})", line_no)
        command = INPUTS[name.lower()]
        if command.name == "meshing_uv" and name != "Meshing_UV":
            # FEMNET's strcmp tells them apart: Meshing_uv puts nodes every nu, nv *twines* (maillage_interne6)
            raise r.error(f"'input {name}': FEMNET reads 'Meshing_UV' (nodes every NU, NV meshes along the mesh "
                          "diagonals, supported) and 'Meshing_uv' (every nu, nv twines, not supported) and no other "
                          "spelling", line_no)
        if command.use == "unsupported":
            raise r.error(f"'input {name}': {command.reason}", line_no)
        try:
            values = [float(w) for w in words[2:]]
        except ValueError:
            raise r.error(f"'input {name}': expected {' or '.join(map(str, command.counts))} number(s), found "
                          f"{' '.join(words[2:])!r}", line_no) from None
        if len(values) not in command.counts or not all(math.isfinite(v) for v in values):
            raise r.error(f"'input {name}': expected {' or '.join(map(str, command.counts))} finite number(s), found "
                          f"{' '.join(words[2:])!r}", line_no)
        refused = command.check(values) if command.check is not None else None
        if refused is not None:
            raise r.error(refused, line_no)
        n = len(values)
        if command.table is not None:
            values += _table(r, rest, i, start, command, values, table_lines)
        commands.append((name.lower(), tuple(values), line_no))
        if command.repeatable:
            before = inputs.get(name.lower(), Value((), line_no))
            inputs[name.lower()] = Value(before.value + (Occurrence(tuple(values), line_no),), before.line)
            continue
        key = f"{name.lower()} {int(values[0])}" if command.per_panel else name.lower()
        if command.per_panel and key in inputs:
            raise r.error(f"'input {name}' for panel {int(values[0])} is given twice (line {inputs[key].line})", line_no)
        inputs[key] = Value(values[0] if n == 1 else tuple(values), line_no) if n else Value(1.0, line_no)
    return inputs, outputs, commands


def _table(r, rest, i, start, command, values, table_lines):
    """The time table that follows an input command on its next non-blank lines (``command.table``: its rows, and
    which of the command's values gives their length): its rows' numbers, in order; their lines are marked
    read in ``table_lines`` (indices into ``rest``, the tail's lines from ``start``)."""
    rows, length_at = command.table
    length = values[length_at]
    if length != int(length) or length < 1:
        raise r.error(f"'input {command.name}': its table's length must be an integer >= 1, got {length!r}", start + i)
    numbers, j = [], i + 1
    for row in range(rows):
        while j < len(rest) and not rest[j].split():
            j += 1
        if j >= len(rest):
            raise r.error(f"'input {command.name}': the file ends inside its table (row {row + 1} of {rows})", start + j)
        try:
            got = [float(w) for w in rest[j].split()]
        except ValueError:
            got = []
        if len(got) != int(length) or not all(math.isfinite(v) for v in got):
            raise r.error(f"'input {command.name}': row {row + 1} of its table must hold {int(length)} numbers, found "
                          f"{rest[j].strip()!r}", start + j)
        numbers += got
        table_lines.add(j)
        j += 1
    return numbers
