"""FEMNET's case files: a ``.don`` description (and FEMNET's own ``.mdg`` mesh) read into jaxnet.

FEMNET is the C program of the same netting model. Its user writes a ``.don`` file; its mesher writes
the ``.mdg`` mesh; its solver the ``.sta`` equilibrium. Two readers:

* :func:`read_don` maps a ``.don`` case onto the :class:`~jaxnet.net.Net` builder (jaxnet meshes the
  panels itself);
* :func:`read_mdg` builds a :class:`~jaxnet.scene.Scene` from FEMNET's ``.mdg`` mesh directly (same
  nodes in the same order, same triangles, same bars) with the ``.don``'s materials and node types, so
  that the physics of the two programs can be compared without mesh differences.

Conventions established from the files (see ``tests/test_femnet.py``):

* **Twine coordinates.** A ``.don`` corner's (U, V), and the (U, V) of a triangle corner in the
  ``.mdg``, count *meshes* along the two *diagonals* of the meshes (U along the first diagonal, V
  along the second; with a meshing step of 2 l0 FEMNET's lattice steps by 1 in both). FEMNET's mesher
  converts them to twine coordinates u = U + V, v = V - U (phobos ``chargement_don.c``), which count
  *twines* along the two twine directions; those are jaxnet's twine coordinates. Check: with
  (u, v) = (U + V, V - U), jaxnet's :func:`~jaxnet.geometry.twine_vectors` of FEMNET's equilibrium
  positions reproduce the two twine vectors per triangle of the ``.sta`` to 1e-9 m (the ``.sta``
  lists the v vector first, then the u vector), and their lengths are l0 (one twine) as they must.
  The map has determinant 2: one mesh (U = 1) is one twine of each family; d(u, v) = 2 d(U, V) and
  the number of twines of each family in a triangle is |d(u, v)|/2 = |d(U, V)|.
* **Meshing step** (m): jaxnet's mesher uses step / l0 twines, as FEMNET's (7.27 twines in
  ``nr_netting``: 0.16 m / 0.022 m).
* **Node types.** Every node has a type (corner: its own; nodes created along a panel side: the
  side's "following type"; inside a panel or a cable: the element's "type of internal nodes").
  Fixity "Displacement X,Y,Z" = 1 holds that coordinate; "Symmetry" = 1 means the node lies on a
  symmetry plane normal to that axis, so that coordinate is held too (the plane is a mirror: the
  node's out-of-plane displacement is zero by symmetry). FEMNET reports no reaction there and zeroes
  the total force along symmetry axes; :func:`femnet_figures` does the same.
* **Cables along panel sides.** A cable whose two ends are two consecutive corners of a panel is sewn
  along that side (FEMNET's mesher makes the side nodes the cable nodes): if the cable is meshed
  before the panel ("Meshing order") its number of bars divides the side, otherwise the side's own
  division is used and the cable's "number of bars" is ignored, as FEMNET does (``nr_netting``'s
  one-bar cables 3, 4, 6 become 11, 16 and 16 bars in its ``.mdg``).
* **Catch.** FEMNET's catch volume is that of the *modelled* part (``c2``, a quarter model, asks for
  and reports 0.2 m³); jaxnet's :class:`~jaxnet.scene.Catch` takes the whole cod-end's volume and the
  number of copies (2 per symmetry plane used by the nodes): volume = 0.2 × 4 for ``c2``. The axis is
  the current's direction, through the intersection of the symmetry planes.
* **Convergence.** FEMNET stops when the *mean* nodal residual norm is below its threshold; jaxnet's
  Newton tests the *largest* nodal residual. The threshold is passed unchanged as jaxnet's ``tol``:
  max <= tol implies mean <= tol, so jaxnet's answer is at least as converged as FEMNET's.
* **Environment.** z is up, the water density FEMNET's default 1025 kg/m³ unless ``input
  water_density`` says otherwise, g = 9.81 m/s². The current direction (deg) turns from x towards y.
  The free surface is not modelled (both cases lie well below z = 0).

Strictness. FEMNET skips to the next colon and reads numbers, whatever the text before the colon;
this reader checks each label against the field it expects (the long and the short spellings found in
FEMNET's cases), and raises :class:`~jaxnet.scene.SceneError` naming the file, the LINE and the field
for: a misspelt label, a missing or non-numeric value (truncated file), NaN/inf, a negative stiffness
or length, a zero-length cable, a panel whose (U, V) contour has no area, and every FEMNET feature it
does not model when it is used (waves, added mass, node drag lengths, sea-bed limits, hexagonal
panels, links, sliding cables, dynamics, anisotropic node mass, unknown ``input`` commands, ...).
"""

from __future__ import annotations

import bisect
import dataclasses
import math
import pathlib
import re

import numpy as np

from jaxnet.net import Net, Rope, Side, Twine, _knot_stiffness, _outward
from jaxnet.scene import Bars, Catch, Environment, Netting, Nodes, Scene, SceneError, validate
from jaxnet.solve.statics import Newton

#: FEMNET's default water density (kg/m³, phobos ``chargement_don.c``: RHO = 1025)
WATER_DENSITY = 1025.0
GRAVITY = 9.81

#: ``input NAME ...`` commands understood: name -> number of numbers that follow
_INPUTS = {"auto_convergence": 0, "convergence_parameters": 3, "link": 1, "water_density": 1}
#: ``output NAME`` commands that only print figures (they do not change the case)
_OUTPUTS = {"element_drag", "surface_drag", "catch_drag", "no_visible_symmetry", "panel_drag", "cable_drag",
            "node_drag", "energy", "tension", "tensions"}


def _number_re(alternatives):
    return re.compile("|".join(f"(?:{a})" for a in alternatives))


def _lab(*alternatives):
    """A label pattern: normalised label text (lower case, single spaces) matching one alternative."""
    return _number_re(alternatives)


# labels (normalised: lower case, runs of blanks as one space), long and short spellings
L = {
    "orientation": _lab(r"design in the plane normal to axis"),
    "panels": _lab(r"panels number"),
    "panel": _lab(r"panel"),
    "corners": _lab(r"number of nodes around"),
    "contour": _lab(r"nodes of the contour.*"),
    "ea": _lab(r"traction stiffness( \(n\))?", r"kt"),
    "eac": _lab(r"compression stiffness( \(n\))?", r"kc"),
    "opening": _lab(r"mesh opening stiffness( \(n\.m/rad\))?"),
    "l0": _lab(r"unstretched length( \(m\))?", r"l"),
    "density": _lab(r"volumic mass( \(kg/m3\))?", r"vm"),
    "diameter": _lab(r"hydrodynamic diameter( \(m\))?", r"d"),
    "knot": _lab(r"knot size( \(m\))?"),
    "cd": _lab(r"normal cd", r"cd"),
    "f": _lab(r"tangential cd", r"f"),
    "step": _lab(r"meshing step( \(m\))?"),
    "inner_type": _lab(r"type of internal nodes", r"ty"),
    "mesh_type": _lab(r"meshing type"),
    "hexa": _lab(r"hexagonal panels number"),
    "cables": _lab(r"cables number"),
    "cable": _lab(r"cable"),
    "ends": _lab(r"extremities no x y z type"),
    "n_bars": _lab(r"bars number", r"nb"),
    "sliding": _lab(r"sliding cables number"),
    "links": _lab(r"links number"),
    "order": _lab(r"meshing order"),
    "order_item": _lab(r"el", r"pa", r"ha"),
    "types": _lab(r"number of types of nodes"),
    "type": _lab(r"no du type", r"type"),
    "mass": _lab(r"mass x,y,z( \(kg\))?"),
    "added_mass": _lab(r"added mass x,y,z( \(kg\))?"),
    "length": _lab(r"length x,y,z( \(m\))?"),
    "node_cd": _lab(r"drag coefficient x,y,z"),
    "force": _lab(r"external forces? x,y,z( \(n\))?"),
    "fixed": _lab(r"displacement x,y,z"),
    "limits": _lab(r"limits x,y,z( \(m\))?"),
    "limits_sense": _lab(r"limits sens(e)? x,y,z"),
    "symmetry": _lab(r"sym(m)?etry x,y,z"),
    "divisor": _lab(r"divisor( \(s\))?"),
    "threshold": _lab(r"convergence threshold( \(n\))?"),
    "max_step": _lab(r"displacement limit for each iteration( \(m\))?"),
    "max_iter": _lab(r"maximal number of iterations"),
    "dt": _lab(r"dynamic: time step( \(s\))?"),
    "record_dt": _lab(r"dynamic: record time step( \(s\))?"),
    "record_start": _lab(r"dynamic: beginning time of record( \(s\))?"),
    "record_end": _lab(r"dynamic: end time of record and calculation( \(s\))?"),
    "current_direction": _lab(r"current direction( \(deg\))?"),
    "current_speed": _lab(r"current speed( \(m/s\))?"),
    "wave_period": _lab(r"wave period( \(s\))?"),
    "wave_height": _lab(r"wave height( \(m\))?"),
    "wave_direction": _lab(r"wave direction relatively x( \(deg\))?"),
    "depth": _lab(r"depth( \(m\))?"),
    "catch_volume": _lab(r"volume( \(m3\))?"),
    "catch_accuracy": _lab(r"accuracy on this volume"),
    "catch_cd": _lab(r"drag coefficient on this volume"),
    "bottom_friction": _lab(r"wearing coefficient on the bottom"),
    "bottom_stiffness": _lab(r"stiffness of the insertion in the sea bottom( \(n/m\))?"),
    "distances": _lab(r"distances number"),
    "forces": _lab(r"forces number"),
    "tensions": _lab(r"tensions number"),
    "sliding_tensions": _lab(r"sliding tensions number"),
    "positions": _lab(r"positions number"),
    "show_forces": _lab(r"structure forces display"),
    "show_diameter": _lab(r"catch diameter display"),
    "show_thickness": _lab(r"catch thickness display"),
    "show_volume": _lab(r"catch volume display"),
    "show_surface": _lab(r"filt(e|ra)ted surface display"),
    "show_speed": _lab(r"speed display"),
}


@dataclasses.dataclass(frozen=True)
class Value:
    """A number read from a file, with the line it is on (for messages)."""

    value: float
    line: int


class _Reader:
    """FEMNET's way of reading: skip to the next colon, check the label before it, read numbers."""

    def __init__(self, text, path):
        self.text = text
        self.path = path
        self.pos = 0
        self.starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def line(self, pos=None):
        return bisect.bisect_right(self.starts, self.pos if pos is None else pos)

    def error(self, message, line=None):
        return SceneError(f"{self.path}:{line if line is not None else self.line()}: {message}")

    def label(self, key, what):
        """Skip to the next colon; the label before it (its last line) must be the field ``key``."""
        colon = self.text.find(":", self.pos)
        if colon < 0:
            raise self.error(f"the file ends before the field '{what}' (truncated file?)", self.line(len(self.text)))
        label = self.text[self.pos:colon].split("\n")[-1]
        self.pos = colon + 1
        norm = " ".join(label.lower().split())
        if norm == "dynamic":  # "Dynamic: Time step (s):" has two colons
            colon = self.text.find(":", self.pos)
            if colon >= 0 and "\n" not in self.text[self.pos:colon]:
                norm = "dynamic: " + " ".join(self.text[self.pos:colon].lower().split())
                self.pos = colon + 1
        if not L[key].fullmatch(norm):
            raise self.error(f"expected the field '{what}', found the label {label.strip()!r}", self.line(colon))
        return norm

    def token(self, what):
        m = re.compile(r"\S+").search(self.text, self.pos)
        if m is None:
            raise self.error(f"the file ends before the value of '{what}' (truncated file?)", self.line(len(self.text)))
        self.pos = m.end()
        return m.group(0), self.line(m.start())

    def number(self, what, check=None):
        tok, line = self.token(what)
        try:
            v = float(tok)
        except ValueError:
            raise self.error(f"'{what}': expected a number, found {tok!r}", line) from None
        if not math.isfinite(v):
            raise self.error(f"'{what}': {tok!r} is not a finite number", line)
        if check == ">=0" and v < 0:
            raise self.error(f"'{what}' must be >= 0, got {v!r}", line)
        if check == ">0" and not v > 0:
            raise self.error(f"'{what}' must be > 0, got {v!r}", line)
        return Value(v, line)

    def integer(self, what, minimum=None):
        v = self.number(what)
        if v.value != int(v.value) or (minimum is not None and v.value < minimum):
            raise self.error(f"'{what}' must be an integer{'' if minimum is None else f' >= {minimum}'}, got {v.value!r}", v.line)
        return Value(int(v.value), v.line)

    def field(self, key, what, check=None, integer=False, minimum=None):
        self.label(key, what)
        return self.integer(what, minimum) if integer else self.number(what, check)

    def triple(self, key, what, check=None):
        self.label(key, what)
        return [self.number(f"{what} {axis}", check) for axis in "XYZ"]


@dataclasses.dataclass
class _Panel:
    corners: np.ndarray   # (C, 5) x y z U V as in the file (U, V: meshes along the diagonals)
    corner_type: list
    side_type: list
    material: dict        # name -> Value
    line: int


@dataclasses.dataclass
class _Cable:
    ends: np.ndarray      # (2, 3)
    end_type: list
    material: dict
    line: int


@dataclasses.dataclass
class _NodeType:
    mass: list
    force: list
    fixed: list
    symmetry: list
    line: int


@dataclasses.dataclass
class Case:
    """A ``.don`` case as read (before mapping onto jaxnet)."""

    path: str
    panels: list
    cables: list
    order: list           # [("el" | "pa", index 1-based)]
    types: dict           # type number -> _NodeType
    numeric: dict
    ocean: dict
    catch: dict
    inputs: dict
    outputs: list


def _twine_coordinates(UV):
    """FEMNET's mesh coordinates (U, V) (meshes along the diagonals) -> twine coordinates (u, v) = (U + V, V - U)."""
    UV = np.asarray(UV, dtype=float)
    return np.stack([UV[..., 0] + UV[..., 1], UV[..., 1] - UV[..., 0]], axis=-1)


def parse_don(path) -> Case:
    """Read a ``.don`` file into a :class:`Case` (values with their line numbers), checking every label."""
    path = pathlib.Path(path)
    if not path.exists():
        raise SceneError(f"FEMNET case {path} does not exist")
    r = _Reader(path.read_text(errors="replace"), str(path))
    first = r.text.lstrip().split(None, 1)[0] if r.text.strip() else ""
    if first.lower().startswith("version"):
        raise r.error(f"FEMNET file format {first!r} is not supported (only the original format)")
    orientation = r.field("orientation", "design in the plane normal to axis", integer=True)
    if orientation.value != 3:
        raise r.error(f"design in the plane normal to axis {orientation.value}: only 3 (x y z as written) is supported",
                      orientation.line)
    n_panels = r.field("panels", "panels number", integer=True, minimum=0)
    panels = []
    for k in range(n_panels.value):
        r.label("panel", f"panel {k + 1}")
        r.integer(f"panel {k + 1} number")
        nc = r.field("corners", f"panel {k + 1}: number of nodes around", integer=True, minimum=3)
        r.label("contour", f"panel {k + 1}: nodes of the contour")
        rows, ctype, stype, lines = [], [], [], []
        for c in range(nc.value):
            what = f"panel {k + 1} corner {c + 1}"
            r.integer(f"{what} number")
            vals = [r.number(f"{what} {name}") for name in ("x", "y", "z", "U", "V")]
            rows.append([v.value for v in vals])
            lines.append(vals[0].line)
            ctype.append(r.integer(f"{what} node type", 1))
            stype.append(r.integer(f"{what} following side type", 1))
        mat = {}
        for key, what, check in (("ea", "traction stiffness", ">=0"), ("eac", "compression stiffness", ">=0"),
                                 ("opening", "mesh opening stiffness", ">=0"), ("l0", "unstretched length", ">0"),
                                 ("density", "volumic mass", ">=0"), ("diameter", "hydrodynamic diameter", ">=0"),
                                 ("knot", "knot size", ">=0"), ("cd", "normal Cd", ">=0"), ("f", "tangential Cd", ">=0"),
                                 ("step", "meshing step", ">0")):
            mat[key] = r.field(key, f"panel {k + 1}: {what}", check)
        mat["inner_type"] = r.field("inner_type", f"panel {k + 1}: type of internal nodes", integer=True, minimum=1)
        mat["mesh_type"] = r.field("mesh_type", f"panel {k + 1}: meshing type", integer=True)
        corners = np.array(rows)
        _check_contour(r, corners, lines, k + 1)
        panels.append(_Panel(corners, ctype, stype, mat, nc.line))
    n_hexa = r.field("hexa", "hexagonal panels number", integer=True, minimum=0)
    if n_hexa.value:
        raise r.error(f"hexagonal panels number {n_hexa.value}: hexagonal panels of FEMNET's .don are not supported "
                      "(their l, m, n coordinates are not mapped onto jaxnet's HexTwine)", n_hexa.line)
    n_cables = r.field("cables", "cables number", integer=True, minimum=0)
    cables = []
    for k in range(n_cables.value):
        r.label("cable", f"cable {k + 1}")
        r.integer(f"cable {k + 1} number")
        r.label("ends", f"cable {k + 1}: extremities")
        ends, etype = [], []
        for e in range(2):
            what = f"cable {k + 1} end {e + 1}"
            r.integer(f"{what} number")
            ends.append([r.number(f"{what} {name}").value for name in "xyz"])
            etype.append(r.integer(f"{what} node type", 1))
        mat = {}
        for key, what, check in (("ea", "traction stiffness", ">=0"), ("eac", "compression stiffness", ">=0"),
                                 ("l0", "unstretched length", ">0"), ("density", "volumic mass", ">=0"),
                                 ("diameter", "hydrodynamic diameter", ">=0"), ("cd", "normal Cd", ">=0"),
                                 ("f", "tangential Cd", ">=0")):
            mat[key] = r.field(key, f"cable {k + 1}: {what}", check)
        mat["n_bars"] = r.field("n_bars", f"cable {k + 1}: number of bars", integer=True, minimum=1)
        mat["inner_type"] = r.field("inner_type", f"cable {k + 1}: type of internal nodes", integer=True, minimum=1)
        cables.append(_Cable(np.array(ends), etype, mat, etype[0].line))
    for key, what in (("sliding", "sliding cables number"), ("links", "links number")):
        n = r.field(key, what, integer=True, minimum=0)
        if n.value:
            raise r.error(f"{what} {n.value}: {what.split(' number')[0]} are not supported by this reader", n.line)
    r.label("order", "meshing order")
    order, seen = [], set()
    for _ in range(n_panels.value + n_cables.value):
        kind = r.label("order_item", "meshing order entry (el: or pa:)")
        idx = r.integer(f"meshing order {kind}", 1)
        count = n_cables.value if kind == "el" else n_panels.value
        if kind == "ha" or idx.value > count or (kind, idx.value) in seen:
            raise r.error(f"meshing order: '{kind}: {idx.value}' is not a {'cable' if kind == 'el' else 'panel'} of the "
                          "case, or is listed twice", idx.line)
        seen.add((kind, idx.value))
        order.append((kind, idx.value))
    n_types = r.field("types", "number of types of nodes", integer=True, minimum=1)
    types = {}
    for t in range(n_types.value):
        r.label("type", f"node type {t + 1}")
        number = r.integer(f"node type {t + 1} number", 1)
        mass = r.triple("mass", f"node type {number.value}: mass", ">=0")
        added = r.triple("added_mass", f"node type {number.value}: added mass", ">=0")
        length = r.triple("length", f"node type {number.value}: length", ">=0")
        r.triple("node_cd", f"node type {number.value}: drag coefficient", ">=0")
        force = r.triple("force", f"node type {number.value}: external force")
        r.label("fixed", f"node type {number.value}: displacement")
        fixed = [_flag(r, f"node type {number.value}: displacement {a}") for a in "XYZ"]
        limits = r.triple("limits", f"node type {number.value}: limits")
        r.label("limits_sense", f"node type {number.value}: limits sense")
        sense = [r.integer(f"node type {number.value}: limits sense {a}") for a in "XYZ"]
        r.label("symmetry", f"node type {number.value}: symmetry")
        symmetry = [_flag(r, f"node type {number.value}: symmetry {a}") for a in "XYZ"]
        for name, values in (("added mass", added), ("length (node drag)", length), ("limits", limits),
                             ("limits sense", sense)):
            bad = [v for v in values if v.value != 0]
            if bad:
                raise r.error(f"node type {number.value}: {name} {bad[0].value!r} is not supported (only 0: no "
                              f"{'sea-bed limit' if 'limit' in name else name})", bad[0].line)
        if len({m.value for m in mass}) > 1:
            raise r.error(f"node type {number.value}: anisotropic mass {[m.value for m in mass]} is not supported "
                          "(give the same mass along X, Y and Z)", mass[0].line)
        if number.value in types:
            raise r.error(f"node type {number.value} is described twice", number.line)
        types[number.value] = _NodeType([m.value for m in mass], [f.value for f in force], fixed, symmetry, number.line)
    numeric = {}
    for key, what, check in (("divisor", "divisor", None), ("threshold", "convergence threshold", ">0"),
                             ("max_step", "displacement limit for each iteration", ">0")):
        numeric[key] = r.field(key, what, check)
    numeric["max_iter"] = r.field("max_iter", "maximal number of iterations", integer=True, minimum=1)
    for key, what in (("dt", "dynamic time step"), ("record_dt", "dynamic record time step"),
                      ("record_start", "dynamic beginning time of record"),
                      ("record_end", "dynamic end time of record and calculation")):
        numeric[key] = r.field(key, what)
    if numeric["record_end"].value > 0:
        raise r.error(f"dynamic end time {numeric['record_end'].value!r} s: dynamic calculations are not supported "
                      "(only statics: end time 0)", numeric["record_end"].line)
    ocean = {}
    for key, what, check in (("current_direction", "current direction", None), ("current_speed", "current speed", ">=0"),
                             ("wave_period", "wave period", None), ("wave_height", "wave height", ">=0"),
                             ("wave_direction", "wave direction", None), ("depth", "depth", ">=0")):
        ocean[key] = r.field(key, what, check)
    if ocean["wave_height"].value > 0:
        raise r.error(f"wave height {ocean['wave_height'].value!r} m: waves are not supported (only 0)",
                      ocean["wave_height"].line)
    catch = {}
    for key, what, check in (("catch_volume", "catch volume", ">=0"), ("catch_accuracy", "accuracy on the catch volume", ">=0"),
                             ("catch_cd", "drag coefficient of the catch", ">=0")):
        catch[key] = r.field(key, what, check)
    for key, what in (("bottom_friction", "wearing coefficient on the bottom"),
                      ("bottom_stiffness", "stiffness of the insertion in the sea bottom")):
        ocean[key] = r.field(key, what, ">=0")
    for key, what in (("distances", "distances number"), ("forces", "forces number"), ("tensions", "tensions number"),
                      ("sliding_tensions", "sliding tensions number"), ("positions", "positions number")):
        n = r.field(key, what, integer=True, minimum=0)
        if n.value:
            raise r.error(f"{what} {n.value}: text outputs of {key.replace('_', ' ')} are not supported (only 0)", n.line)
    for key, what in (("show_forces", "structure forces display"), ("show_diameter", "catch diameter display"),
                      ("show_thickness", "catch thickness display"), ("show_volume", "catch volume display"),
                      ("show_surface", "filtrated surface display"), ("show_speed", "speed display")):
        r.field(key, what, integer=True)
    inputs, outputs = _commands(r)
    return Case(str(path), panels, cables, order, types, numeric, ocean, catch, inputs, outputs)


def _flag(r, what):
    v = r.integer(what)
    if v.value not in (0, 1):
        raise r.error(f"'{what}' must be 0 or 1, got {v.value}", v.line)
    return v


def _check_contour(r, corners, lines, k):
    """The panel's contour in twine coordinates must enclose an area (no repeated corner, not collinear)."""
    uv = _twine_coordinates(corners[:, 3:5])
    nxt = np.roll(uv, -1, axis=0)
    for c in range(len(uv)):
        if np.allclose(uv[c], nxt[c], rtol=0, atol=1e-12):
            raise r.error(f"panel {k}: corners {c + 1} and {(c + 1) % len(uv) + 1} have the same (U, V)", lines[c])
    area = 0.5 * np.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1])
    scale = np.ptp(uv, axis=0).max() ** 2
    if abs(area) <= 1e-9 * max(scale, 1e-300):
        raise r.error(f"panel {k}: the (U, V) contour of its corners is collinear (no area): "
                      f"{corners[:, 3:5].tolist()}", lines[0])


def _commands(r):
    """The free-order tail: ``input NAME values`` and ``output NAME`` lines, comments (# or //)."""
    inputs, outputs = {}, []
    start = r.line(r.pos)
    rest = r.text[r.pos:].split("\n")
    for i, raw in enumerate(rest):
        line_no = start + i
        words = raw.split()
        if i == 0 and words:  # the remainder of the last field's line: the display flag was read already
            raise r.error(f"unexpected text {raw.strip()!r} after the last field", line_no)
        if not words or words[0].startswith("#") or words[0].startswith("//"):
            continue
        kind = words[0].lower()
        if kind not in ("input", "output") or len(words) < 2:
            raise r.error(f"expected 'input NAME ...' or 'output NAME', found {raw.strip()!r}", line_no)
        name = words[1]
        if kind == "output":
            if name.lower() not in _OUTPUTS:
                raise r.error(f"'output {name}': not known to be a print-only output; not supported", line_no)
            outputs.append(name)
            continue
        if name.lower() not in _INPUTS:
            raise r.error(f"'input {name}': unknown input command, not supported (known: {sorted(_INPUTS)})", line_no)
        n = _INPUTS[name.lower()]
        try:
            values = [float(w) for w in words[2:2 + n]]
        except ValueError:
            raise r.error(f"'input {name}': expected {n} number(s), found {' '.join(words[2:])!r}", line_no) from None
        if len(values) != n or len(words) > 2 + n or not all(math.isfinite(v) for v in values):
            raise r.error(f"'input {name}': expected {n} finite number(s), found {' '.join(words[2:])!r}", line_no)
        if name.lower() == "water_density" and not values[0] > 0:
            raise r.error(f"'input water_density' must be > 0, got {values[0]!r}", line_no)
        inputs[name.lower()] = Value(values[0] if n == 1 else tuple(values), line_no) if n else Value(1.0, line_no)
    return inputs, outputs


# -- mapping onto jaxnet --------------------------------------------------------------------------


def _twine(p: _Panel) -> Twine:
    m = {k: v.value for k, v in p.material.items()}
    return Twine(l0=m["l0"], ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"],
                 cd_normal=m["cd"], tangential_ratio=m["f"], opening_stiffness=m["opening"], knot_size=m["knot"])


def _rope(c: _Cable) -> Rope:
    m = {k: v.value for k, v in c.material.items()}
    return Rope(ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"], cd_normal=m["cd"],
                tangential_ratio=m["f"])


def _environment(case: Case) -> Environment:
    angle = math.radians(case.ocean["current_direction"].value)
    rho = case.inputs["water_density"].value if "water_density" in case.inputs else WATER_DENSITY
    return Environment(gravity=GRAVITY, water_density=float(rho), up=np.array([0.0, 0.0, 1.0]),
                       current_speed=case.ocean["current_speed"].value,
                       current_direction=np.array([math.cos(angle), math.sin(angle), 0.0]))


def _solver(case: Case) -> Newton:
    n = case.numeric
    return Newton(tol=n["threshold"].value, max_iter=int(n["max_iter"].value), max_step=n["max_step"].value)


def _check_types(case: Case):
    used = [(t, f"panel {k + 1} corner {c + 1}") for k, p in enumerate(case.panels) for c, t in enumerate(p.corner_type)]
    used += [(t, f"panel {k + 1} side {c + 1}") for k, p in enumerate(case.panels) for c, t in enumerate(p.side_type)]
    used += [(p.material["inner_type"], f"panel {k + 1} internal nodes") for k, p in enumerate(case.panels)]
    used += [(t, f"cable {k + 1} end {e + 1}") for k, c in enumerate(case.cables) for e, t in enumerate(c.end_type)]
    used += [(c.material["inner_type"], f"cable {k + 1} internal nodes") for k, c in enumerate(case.cables)]
    for t, what in used:
        if t.value not in case.types:
            raise SceneError(f"{case.path}:{t.line}: {what}: node type {t.value} is not described (types: "
                             f"{sorted(case.types)})")


def _sewn_side(case: Case, cable: _Cable, tol=1e-9):
    """(panel index, side index) when the cable's ends are two consecutive corners of a panel, else None."""
    for k, p in enumerate(case.panels):
        xyz = p.corners[:, :3]
        n = len(xyz)
        hit = [int(np.flatnonzero(np.linalg.norm(xyz - e, axis=1) <= tol)[0]) if np.any(np.linalg.norm(xyz - e, axis=1) <= tol)
               else None for e in cable.ends]
        if None in hit:
            continue
        a, b = hit
        if b == (a + 1) % n:
            return k, a
        if a == (b + 1) % n:
            return k, b
    return None


def _symmetry(case: Case, position, node_type):
    """Symmetry planes used by the nodes: {axis: plane coordinate}; a plane must be flat at the start."""
    planes = {}
    for axis in range(3):
        on = [i for i, t in enumerate(node_type) if case.types[t].symmetry[axis].value]
        if not on:
            continue
        coords = position[on, axis]
        if np.ptp(coords) > 1e-6 * max(1.0, np.abs(coords).max()):
            t = node_type[on[int(np.argmax(np.abs(coords - coords[0])))]]
            raise SceneError(f"{case.path}:{case.types[t].line}: node type {t} puts nodes on a symmetry plane normal to "
                             f"{'XYZ'[axis]}, but they start at different {'xyz'[axis]} ({coords.min():.6g} to "
                             f"{coords.max():.6g} m)")
        planes[axis] = float(coords.mean())
    return planes


def _catch(case: Case, position, netting_nodes, planes, env: Environment):
    """(volume of the whole cod-end, Cd, copies, center, axis) of the catch, or None without one."""
    volume = case.catch["catch_volume"].value
    if volume <= 0:
        return None
    if not env.current_speed > 0:
        raise SceneError(f"{case.path}:{case.catch['catch_volume'].line}: a catch needs a current (its axis is the "
                         "current's direction)")
    copies = 2.0 ** len(planes)
    axis = np.asarray(env.current_direction, dtype=float)
    pts = position[netting_nodes]
    center = pts.mean(axis=0)
    for a, c in planes.items():
        center[a] = c
    # the opening: the most upstream netting node's abscissa along the axis
    center = center + (pts @ axis).min() * axis - (center @ axis) * axis
    return volume * copies, case.catch["catch_cd"].value, copies, center, axis


def _describe(case: Case, env: Environment):
    """The panels and cables of the case on a new Net; and the cables sewn along panel sides."""
    net = Net(environment=env)
    for k, p in enumerate(case.panels):
        corners = np.concatenate([p.corners[:, :3], _twine_coordinates(p.corners[:, 3:5])], axis=1)
        net.panel(f"panel {k + 1}", corners, _twine(p), p.material["step"].value)
    rank = {item: i for i, item in enumerate(case.order)}
    sewn = {}
    for k, c in enumerate(case.cables):
        side = _sewn_side(case, c)
        name = f"cable {k + 1}"
        length, nb = c.material["l0"].value, c.material["n_bars"].value
        if side is not None:
            pk, s = side
            # meshed before the panel: its bars divide the side; after: the side's division is kept
            first = rank.get(("el", k + 1), 0) < rank.get(("pa", pk + 1), 0)
            net.cable(name, along=Side(f"panel {pk + 1}", s), rope=_rope(c), length=length, n_bars=nb if first else None)
            sewn[k] = side
        else:
            net.cable(name, start=tuple(c.ends[0]), end=tuple(c.ends[1]), rope=_rope(c), length=length, n_bars=nb)
    return net, sewn


def read_don(path):
    """Read FEMNET's ``.don`` case ``path`` into jaxnet.

    Returns:
      (net, solver, info): a :class:`~jaxnet.net.Net` (jaxnet meshes it; ``net.build()`` gives the scene),
      the :class:`~jaxnet.solve.statics.Newton` options (tol = FEMNET's threshold in N, max_iter, max_step
      = FEMNET's displacement limit in m), and a dict ``info`` of what the reader decided (symmetry
      planes and copies, FEMNET's solver settings, the inputs and outputs, the depth).
    Raises:
      SceneError naming the file and line (see the module docstring).
    """
    case = parse_don(path)
    _check_types(case)
    env = _environment(case)
    # a first build, held at every corner and cable end, tells where jaxnet's mesher put the nodes: their
    # FEMNET types (and so the fixings and loads of the real net) follow from where they were created
    probe, sewn = _describe(case, env)
    for p in case.panels:
        for xyz in p.corners[:, :3]:
            probe.fix(tuple(xyz))
    for c in case.cables:
        for xyz in c.ends:
            probe.fix(tuple(xyz))
    scene = probe.build()
    net, _ = _describe(case, env)
    node_type = _node_types(case, scene, sewn)
    position = np.asarray(scene.nodes.position)
    planes = _symmetry(case, position, node_type)
    for i, t in enumerate(node_type):
        nt = case.types[t]
        axes = "".join(a for j, a in enumerate("xyz") if nt.fixed[j].value or nt.symmetry[j].value)
        if axes:
            net.fix(tuple(position[i]), axes)
        if nt.mass[0] > 0 or any(nt.force):
            net.attach(tuple(position[i]), mass=nt.mass[0], force=nt.force)
    netting_nodes = np.unique(np.asarray(scene.netting.vertices)) if scene.netting is not None else np.arange(len(position))
    catch = _catch(case, position, netting_nodes, planes, env)
    if catch is not None:
        volume, cd, copies, center, axis = catch
        net.catch(volume, drag_coefficient=cd, symmetry=copies, center=tuple(center), axis=tuple(axis))
    return net, _solver(case), _info(case, planes, catch, sewn)


def _info(case, planes, catch, sewn):
    return {
        "source": case.path,
        "symmetry_axes": ["xyz"[a] for a in sorted(planes)],
        "symmetry_planes_m": {"xyz"[a]: c for a, c in planes.items()},
        "copies": 2 ** len(planes),
        "catch_volume_modelled_m3": case.catch["catch_volume"].value,
        "catch_volume_whole_m3": None if catch is None else catch[0],
        "femnet_threshold_N": case.numeric["threshold"].value,
        "femnet_criterion": "mean nodal residual norm (jaxnet: largest nodal residual, same threshold)",
        "femnet_max_iterations": int(case.numeric["max_iter"].value),
        "displacement_limit_m": case.numeric["max_step"].value,
        "depth_m": case.ocean["depth"].value,
        "water_density": _environment(case).water_density,
        "inputs": {k: v.value for k, v in case.inputs.items()},
        "outputs": list(case.outputs),
        "cables_sewn_along_sides": {f"cable {k + 1}": f"panel {p + 1} side {s + 1}" for k, (p, s) in sewn.items()},
    }


def _on_segment(points, a, b, tol):
    """(N,) True where a point lies strictly inside segment a-b (m)."""
    ab = b - a
    t = (points - a) @ ab / max(ab @ ab, 1e-300)
    d = np.linalg.norm(points - a - t[:, None] * ab, axis=1)
    return (d <= tol) & (t > 1e-9) & (t < 1 - 1e-9)


def _node_types(case: Case, scene, sewn):
    """Node type of every scene node, from where it was created (see the module docstring)."""
    pos = np.asarray(scene.nodes.position)
    n = len(pos)
    tol = 1e-7 * max(1.0, float(np.abs(pos).max()))
    # (priority, type, what): a corner's own type wins over a side's or an element's internal type
    claims = [dict() for _ in range(n)]

    def claim(nodes, priority, t, what):
        for i in np.atleast_1d(nodes):
            have = claims[i].get(priority)
            if have is not None and have[0].value != t.value:
                raise SceneError(f"{case.path}:{t.line}: node at {pos[i].round(6).tolist()} is given type {t.value} "
                                 f"({what}) and type {have[0].value} ({have[1]}, line {have[0].line})")
            claims[i][priority] = (t, what)

    def at(point):
        return np.flatnonzero(np.linalg.norm(pos - point, axis=1) <= tol)

    panel_of = np.asarray(scene.netting.panel) if scene.netting is not None else np.zeros(0, int)
    tri = np.asarray(scene.netting.vertices) if scene.netting is not None else np.zeros((0, 3), int)
    for k, p in enumerate(case.panels):
        nodes = np.unique(tri[panel_of == k])
        claim(nodes, 0, p.material["inner_type"], f"panel {k + 1} internal nodes")
        C = len(p.corners)
        for c in range(C):
            a, b = p.corners[c, :3], p.corners[(c + 1) % C, :3]
            claim(nodes[_on_segment(pos[nodes], a, b, tol)], 1, p.side_type[c], f"panel {k + 1} side {c + 1}")
            claim(at(a), 2, p.corner_type[c], f"panel {k + 1} corner {c + 1}")
    if scene.bars is not None:
        ends, cable_of = np.asarray(scene.bars.ends), np.asarray(scene.bars.cable)
        for k, c in enumerate(case.cables):
            nodes = np.unique(ends[cable_of == k])
            inner = nodes[[not (np.linalg.norm(pos[i] - c.ends[0]) <= tol or np.linalg.norm(pos[i] - c.ends[1]) <= tol)
                           for i in nodes]]
            claim(inner, 1, c.material["inner_type"], f"cable {k + 1} internal nodes")
            for e in range(2):
                claim(at(c.ends[e]), 2, c.end_type[e], f"cable {k + 1} end {e + 1}")
    out = []
    for i in range(n):
        if not claims[i]:
            raise SceneError(f"{case.path}: node {i} at {pos[i].tolist()} belongs to no panel or cable")
        out.append(claims[i][max(claims[i])][0].value)
    return out


# -- FEMNET's own mesh ----------------------------------------------------------------------------


def read_mdg(path, don=None):
    """FEMNET's mesh ``path`` (.mdg) as a :class:`~jaxnet.scene.Scene`, with the materials and node types of
    the ``.don`` case ``don`` (default: the same name with ``.don``).

    The scene's nodes are the ``.mdg``'s, in its order (so the ``.sta``'s positions compare node by node);
    its triangles carry the ``.mdg``'s corner (U, V) turned into twine coordinates (U + V, V - U), and the
    material of the panel named in the triangle's line; its bars the rest length (pro2 - pro1) × L of
    their cable. Returns (scene, solver, info) as :func:`read_don`.
    """
    path = pathlib.Path(path)
    don = pathlib.Path(don) if don is not None else path.with_suffix(".don")
    case = parse_don(don)
    _check_types(case)
    if not path.exists():
        raise SceneError(f"FEMNET mesh {path} does not exist")
    lines = path.read_text(errors="replace").split("\n")
    where = str(path)

    def section(header, start=0):
        for i in range(start, len(lines)):
            if " ".join(lines[i].lower().split()).startswith(header):
                return i
        raise SceneError(f"{where}: no '{header}' section (truncated file?)")

    def count_after(header):
        i = section(header)
        try:
            return int(lines[i + 1].split()[0]), i + 1
        except (IndexError, ValueError):
            raise SceneError(f"{where}:{i + 2}: expected the count of '{header}'") from None

    def rows(header, count, width, after):
        i = section(header, after) + 1
        out = []
        while len(out) < count:
            if i >= len(lines):
                raise SceneError(f"{where}:{i}: the file ends inside '{header}' ({len(out)} of {count} rows; truncated?)")
            words = lines[i].split()
            if words:
                try:
                    values = [float(w) for w in words]
                except ValueError:
                    raise SceneError(f"{where}:{i + 1}: '{header}': expected numbers, found {lines[i].strip()!r}") from None
                if len(values) < width or not all(math.isfinite(v) for v in values):
                    raise SceneError(f"{where}:{i + 1}: '{header}': expected {width} finite numbers, found {lines[i].strip()!r}")
                out.append(values + [i + 1])
            i += 1
        return out

    n_nodes, at = count_after("nombre de noeuds")
    node_rows = rows("description des noeuds", n_nodes, 7, at)
    n_bars, at = count_after("nombre d'elements")
    bar_rows = rows("description des elements", n_bars, 6, at)
    n_tri, at = count_after("nombre de surfaces")
    tri_rows = rows("description des surfaces", n_tri, 11, at)
    for header in ("nombre de coulisses", "nombre de surfaces hexagonales"):
        n, at = count_after(header)
        if n:
            raise SceneError(f"{where}:{at + 1}: '{header}' {n}: not supported")
    position = np.array([r[1:4] for r in node_rows])
    node_type = [int(r[5]) for r in node_rows]
    for r in node_rows:
        if int(r[5]) not in case.types:
            raise SceneError(f"{where}:{r[-1]}: node {int(r[0])} has type {int(r[5])}, not described in {don}")
    env = _environment(case)
    planes = _symmetry(case, position, node_type)
    fixed = np.array([[case.types[t].fixed[a].value or case.types[t].symmetry[a].value for a in range(3)]
                      for t in node_type], dtype=bool)
    mass = np.array([case.types[t].mass[0] for t in node_type])
    force = np.array([case.types[t].force for t in node_type], dtype=float)
    nodes = Nodes(position=position, fixed=fixed, mass=mass, volume=np.zeros(n_nodes), force=force,
                  drag_area=np.zeros(n_nodes), size=np.zeros(n_nodes))

    def node_index(value, line):
        i = int(value) - 1
        if value != int(value) or not 0 <= i < n_nodes:
            raise SceneError(f"{where}:{line}: node number {value!r} outside 1..{n_nodes}")
        return i

    netting = None
    if n_tri:
        vertices = np.array([[node_index(v, r[-1]) for v in r[1:4]] for r in tri_rows])
        uv = _twine_coordinates(np.array([r[4:10] for r in tri_rows]).reshape(-1, 3, 2))
        panel = np.array([int(r[10]) - 1 for r in tri_rows])
        for r, p in zip(tri_rows, panel):
            if not 0 <= p < len(case.panels):
                raise SceneError(f"{where}:{r[-1]}: triangle {int(r[0])} belongs to panel {p + 1}, not in {don}")
        twines = [_twine(p) for p in case.panels]
        cols = {"l0": "l0", "ea_traction": "ea", "ea_compression": "ea_compression", "diameter": "diameter",
                "density": "density", "cd_normal": "cd_normal", "tangential_ratio": "tangential_ratio",
                "opening_stiffness": "opening_stiffness", "rest_angle": "rest_angle", "knot_size": "knot_size",
                "bending_stiffness": "bending_stiffness"}
        data = {k: np.array([float(getattr(twines[p], f)) for p in panel]) for k, f in cols.items()}
        data["knot_stiffness"] = np.array([_knot_stiffness(twines[p]) for p in panel])
        netting = Netting(vertices=vertices, uv=uv, panel=panel, drag_model=np.zeros(n_tri, dtype=int), **data)
    bars = None
    if n_bars:
        ends = np.array([[node_index(v, r[-1]) for v in r[1:3]] for r in bar_rows])
        cable = np.array([int(r[5]) - 1 for r in bar_rows])
        for r, c in zip(bar_rows, cable):
            if not 0 <= c < len(case.cables):
                raise SceneError(f"{where}:{r[-1]}: bar {int(r[0])} belongs to cable {c + 1}, not in {don}")
        share = np.array([r[4] - r[3] for r in bar_rows])
        bad = np.flatnonzero(~(share > 0))
        if bad.size:
            r = bar_rows[int(bad[0])]
            raise SceneError(f"{where}:{r[-1]}: bar {int(r[0])}: its share of the cable (pro2 - pro1 = {share[bad[0]]!r}) "
                             "must be > 0")
        ropes = [_rope(c) for c in case.cables]
        rest = share * np.array([case.cables[c].material["l0"].value for c in cable])
        bars = Bars(ends=ends, rest_length=rest, cable=cable,
                    **{k: np.array([float(getattr(ropes[c], f)) for c in cable])
                       for k, f in (("ea_traction", "ea"), ("ea_compression", "ea_compression"), ("diameter", "diameter"),
                                    ("density", "density"), ("cd_normal", "cd_normal"),
                                    ("tangential_ratio", "tangential_ratio"))})
    netting_nodes = np.unique(netting.vertices) if netting is not None else np.arange(n_nodes)
    catch_spec = _catch(case, position, netting_nodes, planes, env)
    catch = None
    if catch_spec is not None:
        volume, cd, copies, center, axis = catch_spec
        catch = Catch(volume=volume, drag_coefficient=cd, axis=axis, center=center, symmetry=copies)
        netting = dataclasses.replace(netting, outward=_outward(position, np.asarray(netting.vertices), center))
    scene = Scene(nodes=nodes, netting=netting, bars=bars, environment=env, catch=catch,
                  panel_names=tuple(f"panel {k + 1}" for k in range(len(case.panels))),
                  cable_names=tuple(f"cable {k + 1}" for k in range(len(case.cables))))
    validate(scene)
    return scene, _solver(case), _info(case, planes, catch_spec, {})


# -- FEMNET's figures and results ---------------------------------------------------------------


def femnet_figures(scene, eq, symmetry_axes=()):
    """FEMNET's summary figures of an equilibrium (N, m, m³), computed by jaxnet.

    drag_netting_N, drag_cables_N, catch_drag_N: x components (along the current when it is along x) and
    norms of the total drag on the netting, on the cables, and of the catch; total_force_N: the force the
    net exerts on its fixings (sum of the out-of-balance force at the held coordinates = minus jaxnet's
    reaction), with the components along symmetry axes set to zero as FEMNET prints them;
    catch: thickness, largest diameter, volume of the modelled part (FEMNET's convention).
    """
    from jaxnet import figures

    groups = figures.force_breakdown(scene, eq.x)
    fixed = np.asarray(scene.nodes.fixed)
    total = np.where(fixed, np.asarray(eq.force), 0.0).sum(axis=0)
    for a in symmetry_axes:
        total["xyz".index(a)] = 0.0
    out = {
        "drag_netting_N": np.asarray(groups["drag_netting_N"]).tolist(),
        "drag_cables_N": np.asarray(groups["drag_cables_N"]).tolist(),
        "catch_drag_N": np.asarray(groups["catch_N"]).tolist(),
        "total_force_N": total.tolist(),
    }
    report = figures.catch_report(scene, eq.x)
    if report is not None:
        copies = float(scene.catch.symmetry)
        out["catch"] = {"front_m": report["front_m"], "thickness_m": report["thickness_m"],
                        "diameter_m": report["diameter_m"], "volume_modelled_m3": report["volume_m3"] / copies,
                        "drag_N": report["drag_N"], "holds_the_volume": report["holds_the_volume"]}
    return out


def read_sta(path, n_nodes, n_bars, n_triangles):
    """FEMNET's ``.sta``: (positions (N, 3) m, bar strains (B,), twine vectors (E, 2, 3) m as written (v then u),
    summary dict of the labelled lines)."""
    lines = pathlib.Path(path).read_text().split("\n")
    pos = np.array([[float(w) for w in lines[i].split()[1:4]] for i in range(n_nodes)])
    strain = np.array([float(lines[n_nodes + i]) for i in range(n_bars)])
    rest = [ln for ln in lines[n_nodes + n_bars:] if ln.strip()]
    vec = np.array([[float(w) for w in rest[i].split()] for i in range(n_triangles)]).reshape(-1, 2, 3)
    summary = {}
    for ln in rest[n_triangles:]:
        if ":" in ln:
            key, value = ln.split(":", 1)
            summary[" ".join(key.split())] = [float(w) for w in value.split()]
        else:
            summary["front"] = [float(w) for w in ln.split()]
    return pos, strain, vec, summary
