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
* **Links** ("Links number", phobos ``chargement_don.c``): one line per link, ``nb_pt: N`` then N
  points ``pa: k nd: c`` (corner c of diamond panel k), ``ha: k nd: c`` (hexagonal panel) or ``el: k
  nd: e`` (end e of cable k); FEMNET goes by the first letter, ``c`` and ``w`` being sliding cables and
  winches (refused here). The points of a link are one node; so are, with ``input link d``, all the
  points closer than d m (FEMNET's automatic links), and here also points at one place (jaxnet's
  :class:`~jaxnet.net.Net` joins them). The joined node starts at the mean of the points' start
  positions, as FEMNET's ``numerotation.c`` places it: the reader moves the joined corners and cable
  ends there before meshing. Sewing (``liaison_maille`` and ``maillage_contour_panneau2`` in
  ``maillage_panneau*.c``): a panel side whose two corners are joined to the two corners of another
  panel's side, or to the two ends of a cable, is sewn to it: the later-meshed part takes the number
  of nodes of the part meshed first, at the same proportions along the side, its nodes are linked to
  those, and each panel keeps its own twine coordinates there (interpolated along its own side). Here
  the sides become :meth:`~jaxnet.net.Net.seam` pairs and the cables ``Net.cable(along=side)``; the
  division of sewn sides is the cable's number of bars when a cable is meshed first ("Meshing order"),
  as FEMNET's (``nr_netting``'s one-bar cables 3, 4, 6, meshed after the panel, become 11, 16 and 16
  bars in its ``.mdg``; ``c2``'s cod line, meshed first, keeps its 7), and otherwise jaxnet's (the
  largest default division of the sewn sides; FEMNET's is the first-meshed panel's, whose side nodes
  sit where its twines cross the side: jaxnet's mesher differs from FEMNET's anyway). FEMNET does not
  sew a panel to itself; the reader refuses a panel (or cable) two of whose corners (ends) are joined,
  a point in two links, and a cable joined at both ends to a cable of several bars (FEMNET threads it
  on that cable's nodes). A joined node whose points have different node types is refused (FEMNET
  warns and keeps one).
* **Hexagonal panels** ("hexagonal panels number"; ``chargement_don.c``): laid out as diamond panels,
  but after the corners FEMNET skips one whole line (a field written there is lost to FEMNET; refused
  here), then reads three values (twine families l, m, n) for traction stiffness (N), compression
  stiffness (N), unstretched length (m) and hydrodynamic diameter (m), then volumic mass, normal Cd,
  tangential Cd, meshing step, type of internal nodes and meshing type (1, 2: triangles; 3: twines as
  bars, refused); no opening stiffness and no knot size. Their (U, V) count *base meshes* exactly as
  jaxnet's :mod:`jaxnet.terms.hexagonal` does, so they are passed unchanged (not turned into U + V,
  V - U): FEMNET's solver (unix ``etirement_hexa.c``, ``calcul_lmn_hexa``) takes the triangle's
  vectors U = dx/dU, V = dx/dV from the corners' (U, V) (``.mdg``, read into ``lon`` by
  ``lectureDo4.c``) and puts the three neighbours of a knot at 0 (twine m), (U + V)/2 (n) and V (l),
  which are jaxnet's P_m, P_n = P_m + (U + V)/2, P_l = P_m + V (book 4.83-4.84), with forces
  (T_l - T_m, -T_n) on (U, V) as jaxnet's. jaxnet's hexagonal netting has one twine diameter and no
  drag: the diameter D with FEMNET's three's weight, D² sum l0_i = sum d_i² l0_i, and a current with
  hexagonal panels is refused. jaxnet meshes a hexagonal panel with step / (3 mean l0) base meshes.
* **Added mass** acts in dynamics only (``lectureDo4.c``: "n'intervient qu'en dynamique"): read, kept
  in ``info["added_mass"]`` per node type, without effect here.
* **Node bodies.** A node type's **length** X,Y,Z (m) and **drag coefficient** X,Y,Z make its nodes boxes
  (``Net.body``: ``Nodes.drag_length``, ``Nodes.drag_coefficient``; :func:`jaxnet.terms.drag.box_drag`).
  FEMNET's statics (``traineecourant2.c``) drags a box along x by ½ ρ Cd_x L_y h U² cos θ and along y by
  ½ ρ Cd_y L_x h U² sin θ, h its immersed height (the box stands above its node for L_z > 0, below it for
  L_z < 0, FEMNET's "lest"), which is jaxnet's box drag for a horizontal current. FEMNET's water surface
  is z = 0 and jaxnet's scenes from FEMNET have none (h = |L_z|), so a box must start wholly below z = 0
  (refused otherwise; the equilibrium is not checked). FEMNET also *floats* a box (``flotteur2.c``:
  rho g L_x L_y times its immersed height, along z, stiffness rho g L_x L_y while it crosses z = 0), which
  jaxnet's node box has no term for: a length whose three values are all non-zero (a box with a volume) is
  refused; one with a zero length (a plate: drag without buoyancy) is read. Widths X, Y must be >= 0
  (FEMNET takes them signed: a negative one would drag against the current).
* **Sea bed** (``fond.c``). Where a node type's **limits sense** is 1 (a floor) or -1 (a ceiling) along an
  axis, its **limit** (m) along that axis is read (``Net.limit``: ``Nodes.limit``, ``Nodes.limit_sense``):
  FEMNET pushes a node beyond it back by k (limit - x), k the "stiffness of the insertion in the sea bottom"
  (N/m), which is ``Environment.bottom_stiffness``; ``bottom_band`` = 0 gives this law exactly (jaxnet's
  default band smooths the contact: :mod:`jaxnet.terms.bottom`). A sense 0 is no limit (its value is
  unused). A limit with a stiffness 0 does nothing in FEMNET and is refused. The "wearing coefficient on the
  bottom" is FEMNET's friction of a bottom sliding at the current's speed, which it applies only with
  ``input moving_bottom`` (a still bottom exerts none, ``Bottom.moving`` = 0): ``bottom_friction`` is the
  coefficient with that input, else 0. ``info["sea_bed"]`` and ``info["node_bodies"]`` say what was read.
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

Strictness. FEMNET skips to the next colon and reads numbers, whatever the text before the colon; this
reader checks each label against the field it expects (the long and the short spellings found in
FEMNET's cases), and raises :class:`~jaxnet.scene.SceneError` naming the file, the LINE and the field
for: a misspelt label, a missing or non-numeric value (truncated file; numbers as C's scanf reads them),
NaN/inf, a negative stiffness or length (a node box's height excepted: it hangs below its node), a
zero-length cable, a panel whose (U, V) contour has no area, positions, limits and node box sizes beyond
1e5 m, meshes of more than 50000 nodes per panel or cables of more than 5000 bars (FEMNET's own limits are
20000 nodes and 5000 bars in all), a link to a part that does not exist, and every FEMNET feature it does
not model when it is used (node boxes with a volume or reaching above z = 0, sea-bed limits without a
stiffness, hexagonal netting in a current, twines meshed as bars, sliding cables, winches, anisotropic node
mass, unknown ``input`` commands, ...). Dynamic cases (an end time > 0) and waves are read: the time settings
go to ``info["dynamic"]`` (``jaxnet run CASE.don --dynamic``), the waves to ``Environment.waves`` (linear
waves on FEMNET's surface z = 0, a depth of 0 taken as deep water); the node types' added masses are read
into ``info["added_mass"]``, and a dynamic run of a case that has any stops with an error (not yet mapped). :func:`read_don` also builds the net it
returns, so that errors of meshing and of the scene (a net held nowhere, ...) come named with the file and
a line too. "Meshing order" may be FEMNET's shorthand: a word beginning with ``a`` (cables, then panels,
then hexagonal panels) or ``b`` (panels, hexagonal panels, cables).
"""

from __future__ import annotations

import bisect
import contextlib
import dataclasses
import math
import pathlib
import re

import numpy as np

from jaxnet import waves as waves_lib
from jaxnet.net import HexTwine, Net, Rope, Side, Twine, bar_rows, netting_rows, outward
from jaxnet.scene import Bars, Catch, Environment, Netting, Nodes, Scene, SceneError, validate
from jaxnet.solve.statics import Newton
from jaxnet.terms import knot

#: FEMNET's default water density (kg/m³, phobos ``chargement_don.c``: RHO = 1025)
WATER_DENSITY = 1025.0
GRAVITY = 9.81

#: ``input NAME ...`` commands understood: name -> number of numbers that follow
#: (``moving_bottom``: FEMNET's bottom slides at the current's speed, which makes its friction act: fond.c)
_INPUTS = {"auto_convergence": 0, "convergence_parameters": 3, "link": 1, "moving_bottom": 0, "water_density": 1}
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
    "hexa_ea": _lab(r"traction stiffness( l,? ?m,? ?n)?( \(n\))?", r"kt"),
    "hexa_eac": _lab(r"compression stiffness( l,? ?m,? ?n)?( \(n\))?", r"kc"),
    "hexa_l0": _lab(r"unstretched lengths?( l,? ?m,? ?n)?( \(m\))?", r"l"),
    "hexa_diameter": _lab(r"hydrodynamic diameters?( l,? ?m,? ?n)?( \(m\))?", r"d"),
    "cables": _lab(r"cables number"),
    "cable": _lab(r"cable"),
    "ends": _lab(r"extremities no x y z type"),
    "n_bars": _lab(r"bars number", r"nb"),
    "sliding": _lab(r"sliding cables number"),
    "links": _lab(r"links number"),
    "link": _lab(r"nb_? ?pts?", r"number of (points|corners)", r"link( \d+)?"),
    "link_item": _lab(r"pa", r"panel", r"ha", r"he", r"hexa", r"el", r"element", r"co", r"wi", r"winch"),
    "link_corner": _lab(r"nd", r"no", r"node", r"corner", r"extremity"),
    "order": _lab(r"meshing order"),
    "order_item": _lab(r"el", r"pa", r"ha", r"he"),
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


#: the most nodes a panel may get: larger meshes are surely a mistake (and take long to make)
MAX_PANEL_NODES = 50_000
#: the most bars of a cable (FEMNET's phobos.h: NBMAXBARRE 5000 in all); a cable sewn along a side divides it
MAX_BARS = 5_000
#: positions (m) and panel coordinates U, V (meshes) beyond these are surely mistakes
MAX_COORDINATE = 1e5
MAX_MESHES = 1e7

#: a decimal number as C's scanf reads it
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


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
        self.last = None  # (what, line) of the last value or label read: named when a value is missing or stray

    def line(self, pos=None):
        return bisect.bisect_right(self.starts, self.pos if pos is None else pos)

    def error(self, message, line=None):
        return SceneError(f"{self.path}:{line if line is not None else self.line()}: {message}")

    def label(self, key, what):
        """Skip to the next colon; the label before it (its last line) must be the field ``key``."""
        colon = self.text.find(":", self.pos)
        if colon < 0:
            raise self.error(f"the file ends before the field '{what}' (truncated file?)", self.line(len(self.text)))
        before = self.text[self.pos:colon].split("\n")
        label = before[-1]
        # FEMNET skips whatever lies between a value and the next label; a number there is a value too many (a
        # line with more fields than its entry has), which FEMNET would drop silently
        for k, text in enumerate(before[:-1]):
            stray = [t for t in text.split() if _NUMBER.fullmatch(t) or t.lower().lstrip("+-") in ("nan", "inf")]
            if stray:
                after = f" after {self.last[0]}" if self.last else ""
                raise self.error(f"unexpected value {stray[0]!r}{after}, before the field '{what}': a line with more "
                                 "values than its entry has?", self.line(self.pos) + k)
        self.pos = colon + 1
        self.last = (f"the label {label.strip()!r}", self.line(colon))
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
        if tok.lower().lstrip("+-") in ("nan", "inf", "infinity"):
            raise self.error(f"'{what}': {tok!r} is not a finite number", line)
        # a decimal number as C's scanf reads it (Python's float() would also take "1_000" or "0x1p3")
        if not _NUMBER.fullmatch(tok):
            if self.last is not None and line > self.last[1]:
                # the value is missing from the line above (too few values there), not wrong here
                raise self.error(f"'{what}': missing: the line ends after {self.last[0]} (too few values on the "
                                 f"line?); the next line starts with {tok!r}", self.last[1])
            raise self.error(f"'{what}': expected a number, found {tok!r}", line)
        self.last = (f"'{what}'", line)
        v = float(tok)
        if not math.isfinite(v):
            raise self.error(f"'{what}': {tok!r} is not a finite number", line)
        if check == "position" and not abs(v) <= MAX_COORDINATE:
            raise self.error(f"'{what}': {v!r} m is out of range (a net within {MAX_COORDINATE:g} m of the origin)", line)
        if check == "meshes" and not abs(v) <= MAX_MESHES:
            raise self.error(f"'{what}': {v!r} meshes is out of range (at most {MAX_MESHES:g})", line)
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
        start = self.last[1]
        values = [self.number(f"{what} {axis}", check) for axis in "XYZ"]
        self.one_line(values, start, what, "X Y Z")
        return values

    def one_line(self, values, line, what, fields, previous=None):
        """The values of a row (a corner, a cable end, X Y Z) must all be on its line ``line``, and a row must not
        start on the line of the ``previous`` row (its (what, line)): a row with a value missing or one too many
        would otherwise shift the next rows, and the error show up lines later, or never."""
        if previous is not None and previous[1] == line:
            what, line = previous  # the previous row had a value too many: this one began on its line
        elif all(v.line == line for v in values):
            return
        text = self.text[self.starts[line - 1]:self.starts[line] if line < len(self.starts) else len(self.text)]
        found = len(text.split(":")[-1].split())
        raise self.error(f"{what}: expected {len(fields.split())} values on its line ({fields}), found {found}", line)


@dataclasses.dataclass
class _Panel:
    corners: np.ndarray   # (C, 5) x y z U V as in the file (diamond: meshes along the diagonals; hexagonal:
                          # base meshes)
    corner_type: list
    side_type: list
    material: dict        # name -> Value (hexagonal: ea, eac, l0, diameter -> [Value l, m, n])
    line: int
    hexagonal: bool = False


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
    added_mass: list = dataclasses.field(default_factory=lambda: [0.0, 0.0, 0.0])
    # the box body and the limits, as [Value] along X, Y, Z (lengths and limits in m; senses -1, 0, 1)
    length: list = dataclasses.field(default_factory=lambda: [Value(0.0, 0)] * 3)
    drag_coefficient: list = dataclasses.field(default_factory=lambda: [Value(0.0, 0)] * 3)
    limit: list = dataclasses.field(default_factory=lambda: [Value(0.0, 0)] * 3)
    sense: list = dataclasses.field(default_factory=lambda: [Value(0, 0)] * 3)

    @property
    def has_body(self):
        """Whether the type's box takes drag in FEMNET's horizontal current: a face normal to x or y (L_y |L_z|
        or L_x |L_z|) with its drag coefficient. (FEMNET's box terms need L_z != 0: a flat box has none.)"""
        lx, ly, lz = (abs(v.value) for v in self.length)
        cx, cy = self.drag_coefficient[0].value, self.drag_coefficient[1].value
        return cx * ly * lz > 0 or cy * lx * lz > 0

    @property
    def has_limit(self):
        return any(v.value != 0 for v in self.sense)


@dataclasses.dataclass
class _Link:
    """A link: panel corners and cable ends that are one node. members: [(kind, index, corner, line)] with kind
    "pa" (diamond panel), "ha" (hexagonal panel) or "el" (cable), 0-based index and corner (cable end 0 or 1)."""

    members: list
    line: int


@dataclasses.dataclass
class Case:
    """A ``.don`` case as read (before mapping onto jaxnet)."""

    path: str
    panels: list
    cables: list
    order: list           # [("el" | "pa" | "ha", index 1-based)]
    types: dict           # type number -> _NodeType
    numeric: dict
    ocean: dict
    catch: dict
    inputs: dict
    outputs: list
    hexagonal: list = dataclasses.field(default_factory=list)   # hexagonal panels (_Panel, hexagonal=True)
    links: list = dataclasses.field(default_factory=list)       # _Link


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
    panels = [_parse_panel(r, k, hexagonal=False) for k in range(n_panels.value)]
    n_hexa = r.field("hexa", "hexagonal panels number", integer=True, minimum=0)
    hexagonal = [_parse_panel(r, k, hexagonal=True) for k in range(n_hexa.value)]
    n_cables = r.field("cables", "cables number", integer=True, minimum=0)
    cables = []
    for k in range(n_cables.value):
        r.label("cable", f"cable {k + 1}")
        r.integer(f"cable {k + 1} number")
        r.label("ends", f"cable {k + 1}: extremities")
        ends, etype = [], []
        previous = None
        for e in range(2):
            what = f"cable {k + 1} end {e + 1}"
            number = r.integer(f"{what} number")
            row = [r.number(f"{what} {name}", "position") for name in "xyz"]
            etype.append(r.integer(f"{what} node type", 1))
            r.one_line([number, *row, etype[-1]], number.line, what, "no x y z type", previous)
            ends.append([v.value for v in row])
            previous = (what, number.line)
        mat = {}
        for key, what, check in (("ea", "traction stiffness", ">=0"), ("eac", "compression stiffness", ">=0"),
                                 ("l0", "unstretched length", ">0"), ("density", "volumic mass", ">=0"),
                                 ("diameter", "hydrodynamic diameter", ">=0"), ("cd", "normal Cd", ">=0"),
                                 ("f", "tangential Cd", ">=0")):
            mat[key] = r.field(key, f"cable {k + 1}: {what}", check)
        mat["n_bars"] = nb = r.field("n_bars", f"cable {k + 1}: number of bars", integer=True, minimum=1)
        if nb.value > MAX_BARS:
            raise r.error(f"cable {k + 1}: {nb.value} bars (limit {MAX_BARS}, FEMNET's own)", nb.line)
        mat["inner_type"] = r.field("inner_type", f"cable {k + 1}: type of internal nodes", integer=True, minimum=1)
        cables.append(_Cable(np.array(ends), etype, mat, etype[0].line))
    n = r.field("sliding", "sliding cables number", integer=True, minimum=0)
    if n.value:
        raise r.error(f"sliding cables number {n.value}: sliding cables are not supported by this reader", n.line)
    counts = {"pa": [len(p.corners) for p in panels], "ha": [len(p.corners) for p in hexagonal],
              "el": [2] * len(cables)}
    n_links = r.field("links", "links number", integer=True, minimum=0)
    links = [_parse_link(r, k, counts) for k in range(n_links.value)]
    order = _parse_order(r, counts)
    n_types = r.field("types", "number of types of nodes", integer=True, minimum=1)
    types = {}
    for t in range(n_types.value):
        r.label("type", f"node type {t + 1}")
        number = r.integer(f"node type {t + 1} number", 1)
        mass = r.triple("mass", f"node type {number.value}: mass", ">=0")
        added = r.triple("added_mass", f"node type {number.value}: added mass", ">=0")
        length = r.triple("length", f"node type {number.value}: length")
        node_cd = r.triple("node_cd", f"node type {number.value}: drag coefficient", ">=0")
        force = r.triple("force", f"node type {number.value}: external force")
        r.label("fixed", f"node type {number.value}: displacement")
        fixed = [_flag(r, f"node type {number.value}: displacement {a}") for a in "XYZ"]
        limit = r.triple("limits", f"node type {number.value}: limits")
        r.label("limits_sense", f"node type {number.value}: limits sense")
        sense = [r.integer(f"node type {number.value}: limits sense {a}") for a in "XYZ"]
        r.label("symmetry", f"node type {number.value}: symmetry")
        symmetry = [_flag(r, f"node type {number.value}: symmetry {a}") for a in "XYZ"]
        # added mass only acts in dynamics (FEMNET's lectureDo4.c): kept in the info, no effect in statics
        _check_body(r, number.value, length)
        for v in sense:
            if v.value not in (-1, 0, 1):
                raise r.error(f"node type {number.value}: limits sense must be -1 (ceiling), 0 (none) or 1 (floor), "
                              f"got {v.value}", v.line)
        for a, (v, s) in enumerate(zip(limit, sense)):
            # a limit without a sense is never read (FEMNET's fond.c tests the sense first): any number will do
            if s.value and not abs(v.value) <= MAX_COORDINATE:
                raise r.error(f"node type {number.value}: limits {'XYZ'[a]} {v.value!r} m is out of range (at most "
                              f"{MAX_COORDINATE:g} m from the origin)", v.line)
        if len({m.value for m in mass}) > 1:
            raise r.error(f"node type {number.value}: anisotropic mass {[m.value for m in mass]} is not supported "
                          "(give the same mass along X, Y and Z)", mass[0].line)
        if number.value in types:
            raise r.error(f"node type {number.value} is described twice", number.line)
        types[number.value] = _NodeType([m.value for m in mass], [f.value for f in force], fixed, symmetry, number.line,
                                        [a.value for a in added], length, node_cd, limit, sense)
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
        for key, what in (("dt", "dynamic time step"), ("record_dt", "dynamic record time step")):
            if not numeric[key].value > 0:
                raise r.error(f"{what} {numeric[key].value!r} s: a dynamic case (end time "
                              f"{numeric['record_end'].value!r} s) needs it > 0", numeric[key].line)
    ocean = {}
    for key, what, check in (("current_direction", "current direction", None), ("current_speed", "current speed", ">=0"),
                             ("wave_period", "wave period", None), ("wave_height", "wave height", ">=0"),
                             ("wave_direction", "wave direction", None), ("depth", "depth", ">=0")):
        ocean[key] = r.field(key, what, check)
    if ocean["wave_height"].value > 0 and not ocean["wave_period"].value > 0:
        raise r.error(f"wave period {ocean['wave_period'].value!r} s: waves of height {ocean['wave_height'].value!r} m "
                      "need a period > 0", ocean["wave_period"].line)
    catch = {}
    for key, what, check in (("catch_volume", "catch volume", ">=0"), ("catch_accuracy", "accuracy on the catch volume", ">=0"),
                             ("catch_cd", "drag coefficient of the catch", ">=0")):
        catch[key] = r.field(key, what, check)
    for key, what in (("bottom_friction", "wearing coefficient on the bottom"),
                      ("bottom_stiffness", "stiffness of the insertion in the sea bottom")):
        ocean[key] = r.field(key, what, ">=0")
    stiffness = ocean["bottom_stiffness"]
    limited = [(t, nt) for t, nt in types.items() if nt.has_limit]
    if limited and not stiffness.value > 0:
        # FEMNET's fond.c pushes a node back by (limit - x) times this stiffness: with 0 its floor does nothing
        t, nt = limited[0]
        raise r.error(f"stiffness of the insertion in the sea bottom is {stiffness.value!r} N/m, but node type {t} has "
                      f"limits (sense {[v.value for v in nt.sense]}, line {nt.sense[0].line}): FEMNET's floor or "
                      "ceiling pushes with this stiffness, so with 0 it does nothing; give a stiffness > 0 N/m (or the "
                      "senses 0)", stiffness.line)
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
    return Case(str(path), panels, cables, order, types, numeric, ocean, catch, inputs, outputs, hexagonal, links)


def _flag(r, what):
    v = r.integer(what)
    if v.value not in (0, 1):
        raise r.error(f"'{what}' must be 0 or 1, got {v.value}", v.line)
    return v


def _check_body(r, t, length):
    """A node type's box (FEMNET's "Length X,Y,Z"): widths X, Y >= 0 (FEMNET's drag takes them signed, a negative
    one would be a drag against the current), a height Z of either sign (< 0: the box hangs below its node, a
    sinker), sizes in range, and no volume: FEMNET floats a box (``flotteur2.c``: rho g L_x L_y times its
    immersed height, along z), a buoyancy jaxnet's node box does not have (see the module docstring)."""
    for a, v in enumerate(length):
        if a < 2 and v.value < 0:
            raise r.error(f"node type {t}: length {'XYZ'[a]} must be >= 0 m (a width of its box), got {v.value!r}",
                          v.line)
        if not abs(v.value) <= MAX_COORDINATE:
            raise r.error(f"node type {t}: length {'XYZ'[a]} {v.value!r} m is out of range (at most "
                          f"{MAX_COORDINATE:g} m)", v.line)
    lx, ly, lz = (v.value for v in length)
    if lx != 0 and ly != 0 and lz != 0:
        raise r.error(f"node type {t}: length {[lx, ly, lz]} m is not supported: FEMNET's box of "
                      f"{abs(lx * ly * lz):.6g} m³ floats (flotteur2.c: buoyancy rho g L_x L_y times its immersed "
                      "height), which jaxnet's node box does not model; only boxes without volume (one length 0: "
                      "drag without buoyancy)", length[0].line)


def _check_contour(r, corners, lines, name):
    """The panel's contour in twine coordinates must enclose an area (no repeated corner, not collinear)."""
    uv = _twine_coordinates(corners[:, 3:5])
    nxt = np.roll(uv, -1, axis=0)
    for c in range(len(uv)):
        if np.allclose(uv[c], nxt[c], rtol=0, atol=1e-12):
            raise r.error(f"{name}: corners {c + 1} and {(c + 1) % len(uv) + 1} have the same (U, V)", lines[c])
    area = 0.5 * np.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1])
    scale = np.ptp(uv, axis=0).max() ** 2
    if not abs(area) > 1e-9 * max(scale, 1e-300):
        raise r.error(f"{name}: the (U, V) contour of its corners is collinear (no area): "
                      f"{corners[:, 3:5].tolist()}", lines[0])


def _parse_panel(r, k, hexagonal):
    """One diamond or hexagonal panel (phobos ``chargement_don.c``): corners, then the material fields; a
    hexagonal panel has three values (twine families l, m, n) for the stiffnesses, lengths and diameters, and
    neither opening stiffness nor knot size."""
    name = f"{'hexagonal ' if hexagonal else ''}panel {k + 1}"
    r.label("panel", name)
    r.integer(f"{name} number")
    nc = r.field("corners", f"{name}: number of nodes around", integer=True, minimum=3)
    r.label("contour", f"{name}: nodes of the contour")
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
    mat = {}
    if hexagonal:
        # FEMNET reads the rest of the last corner's line, then skips one whole line (two fgets) before the
        # fields: a field written on that line would be lost to FEMNET, so it must hold none
        skipped = stype[-1].line + 1
        if skipped <= len(r.starts):
            text = r.text[r.starts[skipped - 1]:r.starts[skipped] if skipped < len(r.starts) else len(r.text)]
            if ":" in text:
                raise r.error(f"{name}: FEMNET skips the line after the last corner of a hexagonal panel, but it holds "
                              f"a field ({text.strip()!r}); leave a line (blank or a comment without ':') there",
                              skipped)
        for key, what, check in (("hexa_ea", "traction stiffness l m n", ">=0"),
                                 ("hexa_eac", "compression stiffness l m n", ">=0"),
                                 ("hexa_l0", "unstretched length l m n", ">0"),
                                 ("hexa_diameter", "hydrodynamic diameter l m n", ">=0")):
            r.label(key, f"{name}: {what}")
            mat[key[5:]] = [r.number(f"{name}: {what[:-6]} {family}", check) for family in "lmn"]
        fields = (("density", "volumic mass", ">=0"), ("cd", "normal Cd", ">=0"), ("f", "tangential Cd", ">=0"),
                  ("step", "meshing step", ">0"))
    else:
        fields = (("ea", "traction stiffness", ">=0"), ("eac", "compression stiffness", ">=0"),
                  ("opening", "mesh opening stiffness", ">=0"), ("l0", "unstretched length", ">0"),
                  ("density", "volumic mass", ">=0"), ("diameter", "hydrodynamic diameter", ">=0"),
                  ("knot", "knot size", ">=0"), ("cd", "normal Cd", ">=0"), ("f", "tangential Cd", ">=0"),
                  ("step", "meshing step", ">0"))
    for key, what, check in fields:
        mat[key] = r.field(key, f"{name}: {what}", check)
    mat["inner_type"] = r.field("inner_type", f"{name}: type of internal nodes", integer=True, minimum=1)
    mat["mesh_type"] = t = r.field("mesh_type", f"{name}: meshing type", integer=True)
    # FEMNET meshes netting into triangles with types 1 and 2; higher types model the twines as bars
    # (maillage.c: 3 and 4 for diamond panels, 3 for hexagonal ones), another model
    bars = (3,) if hexagonal else (3, 4)
    if t.value in bars:
        raise r.error(f"{name}: meshing type {t.value} (twines as bar elements) is not supported (only 1 or 2: "
                      "triangular netting elements)", t.line)
    if t.value not in (1, 2):
        raise r.error(f"{name}: meshing type must be 1 or 2, got {t.value}", t.line)
    corners = np.array(rows)
    _check_contour(r, corners, lines, name)
    # jaxnet meshes with a step of h twines (base meshes for hexagonal netting): refuse a mesh too large to be
    # meant (FEMNET's own limit is 20000 nodes in all, phobos.h NBMAXNOEUD) before trying to make it
    if hexagonal:
        uv, h = corners[:, 3:5], mat["step"].value / (3.0 * np.mean([v.value for v in mat["l0"]]))
    else:
        uv, h = _twine_coordinates(corners[:, 3:5]), mat["step"].value / mat["l0"].value
    nxt = np.roll(uv, -1, axis=0)
    area = 0.5 * abs(np.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1]))
    with np.errstate(all="ignore"):  # a step that underflows h to 0 estimates inf nodes, refused below
        estimate = area / (h * h * math.sqrt(3.0) / 2.0) + np.hypot(*(nxt - uv).T).sum() / h
    if not estimate <= MAX_PANEL_NODES:
        raise r.error(f"{name}: meshing step {mat['step'].value!r} m gives about {estimate:.3g} nodes (limit "
                      f"{MAX_PANEL_NODES}); use a larger step", mat["step"].line)
    return _Panel(corners, ctype, stype, mat, nc.line, hexagonal)


def _parse_link(r, k, counts):
    """One link (``chargement_don.c``): its number of points, then per point the structure (pa: diamond panel,
    ha: hexagonal panel, el: cable; FEMNET goes by the first letter) and its corner or end (nd:)."""
    names = {"pa": "panel", "ha": "hexagonal panel", "el": "cable"}
    r.label("link", f"link {k + 1}")
    n = r.integer(f"link {k + 1}: number of points", 1)
    members, seen = [], set()
    for i in range(n.value):
        what = f"link {k + 1} point {i + 1}"
        label = r.label("link_item", f"{what}: structure (pa:, ha: or el:)")
        if label[0] in "cw":
            raise r.error(f"{what}: '{label}:' links a {'sliding cable' if label[0] == 'c' else 'winch'}, not supported",
                          r.line(r.pos - 1))
        kind = {"p": "pa", "h": "ha", "e": "el"}[label[0]]
        idx = r.integer(f"{what}: {names[kind]} number", 1)
        if idx.value > len(counts[kind]):
            raise r.error(f"{what}: there is no {names[kind]} {idx.value} (the case has {len(counts[kind])})", idx.line)
        r.label("link_corner", f"{what}: corner (nd:)")
        corner = r.integer(f"{what}: corner of {names[kind]} {idx.value}", 1)
        if corner.value > counts[kind][idx.value - 1]:
            raise r.error(f"{what}: {names[kind]} {idx.value} has no {'end' if kind == 'el' else 'corner'} {corner.value} "
                          f"(it has {counts[kind][idx.value - 1]})", corner.line)
        key = (kind, idx.value - 1, corner.value - 1)
        if key in seen:
            raise r.error(f"{what}: {names[kind]} {idx.value} corner {corner.value} is listed twice in link {k + 1}",
                          corner.line)
        seen.add(key)
        members.append((*key, corner.line))
    return _Link(members, n.line)


def _parse_order(r, counts):
    """The meshing order: ``el: k``, ``pa: k``, ``ha: k`` entries, every cable and panel once; or FEMNET's
    shorthand, a word beginning with 'a' (cables, then panels, then hexagonal panels, each in number order)
    or 'b' (panels, hexagonal panels, then cables)."""
    r.label("order", "meshing order")
    words = re.compile(r"\s*(\S+)").match(r.text, r.pos)
    if words and words.group(1)[0].lower() in "ab" and ":" not in words.group(1):
        r.pos = words.end()
        entries = {kind: [(kind, j + 1) for j in range(len(counts[kind]))] for kind in counts}
        first = words.group(1)[0].lower() == "a"
        return entries["el"] + entries["pa"] + entries["ha"] if first else entries["pa"] + entries["ha"] + entries["el"]
    names = {"pa": "panel", "ha": "hexagonal panel", "el": "cable"}
    order, seen = [], set()
    for _ in range(sum(len(v) for v in counts.values())):
        kind = r.label("order_item", "meshing order entry (el:, pa: or ha:)")
        kind = "ha" if kind == "he" else kind
        idx = r.integer(f"meshing order {kind}", 1)
        if idx.value > len(counts[kind]) or (kind, idx.value) in seen:
            raise r.error(f"meshing order: '{kind}: {idx.value}' is not a {names[kind]} of the case, or is listed twice",
                          idx.line)
        seen.add((kind, idx.value))
        order.append((kind, idx.value))
    return order


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


def _twine(p: _Panel, case: Case, femnet_laws: bool) -> Twine:
    """The panel's netting material; with ``femnet_laws``, with FEMNET's laws where they differ from the book
    (``docs/errata.md``, "Where FEMNET differs"): its knot contact (``fermeture2``), and, in a case with a
    catch, its netting drag (``trainee_fil``)."""
    m = {k: v.value for k, v in p.material.items()}
    twine = Twine(l0=m["l0"], ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"],
                  cd_normal=m["cd"], tangential_ratio=m["f"], opening_stiffness=m["opening"], knot_size=m["knot"])
    if not femnet_laws:
        return twine
    return dataclasses.replace(
        twine, knot_form="femnet", knot_stiffness=float(knot.femnet_knot_stiffness(m["l0"], m["knot"], m["ea"])),
        drag_model="femnet-catch" if _femnet_catch_drag(case) else "twines")


def _femnet_catch_drag(case: Case) -> bool:
    """Whether FEMNET loads this case's netting with its drag of cases with a catch (``unix.c``: a catch
    volume above its accuracy, in a current) rather than its twine drag (``filethydro4_sta``)."""
    return (case.catch["catch_volume"].value > case.catch["catch_accuracy"].value
            and case.ocean["current_speed"].value > 0)


def _hextwine(p: _Panel) -> HexTwine:
    m = p.material
    l0 = np.array([v.value for v in m["l0"]])
    d = np.array([v.value for v in m["diameter"]])
    return HexTwine(l0=tuple(l0.tolist()), ea=tuple(v.value for v in m["ea"]), diameter=_hexagonal_diameter(l0, d),
                    ea_compression=tuple(v.value for v in m["eac"]), density=m["density"].value)


def _hexagonal_diameter(l0, d):
    """jaxnet's hexagonal netting has one twine diameter, used only for the twines' weight (it has no drag
    model): the one with the weight of FEMNET's three families, pi/4 sum d_i² l0_i = pi/4 D² sum l0_i (m)."""
    d, l0 = np.asarray(d, dtype=float), np.asarray(l0, dtype=float)
    scale = d.max()  # scaled, so that no square overflows for any finite diameters
    return float(scale * np.sqrt(np.sum((d / scale) ** 2 * l0) / np.sum(l0))) if scale > 0 else 0.0


def _panels(case: Case):
    """Every panel of the case as (kind, index, panel, jaxnet name), diamond panels first: the order in which
    :func:`_describe` adds them to the Net, so the position is the ``panel`` index in the scene."""
    return ([("pa", k, p, f"panel {k + 1}") for k, p in enumerate(case.panels)]
            + [("ha", k, p, f"hexagonal panel {k + 1}") for k, p in enumerate(case.hexagonal)])


def _rope(c: _Cable) -> Rope:
    m = {k: v.value for k, v in c.material.items()}
    return Rope(ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"], cd_normal=m["cd"],
                tangential_ratio=m["f"])


def _environment(case: Case) -> Environment:
    """The surroundings: FEMNET's water and current, and its sea bed (``fond.c``): the limits' penalty stiffness,
    its law exactly (no band), and the friction of the bottom only where FEMNET applies it, with ``input
    moving_bottom`` (a still bottom exerts none)."""
    angle = math.radians(case.ocean["current_direction"].value)
    rho = case.inputs["water_density"].value if "water_density" in case.inputs else WATER_DENSITY
    friction = case.ocean["bottom_friction"].value if "moving_bottom" in case.inputs else 0.0
    waves = None
    if case.ocean["wave_height"].value > 0:
        # regular linear waves on FEMNET's surface z = 0 (felt in dynamics only); a depth of 0 is deep water
        heading = math.radians(case.ocean["wave_direction"].value)
        depth = case.ocean["depth"].value
        waves = waves_lib.Airy(case.ocean["wave_height"].value, case.ocean["wave_period"].value,
                               direction=(math.cos(heading), math.sin(heading), 0.0),
                               depth=depth if depth > 0 else float("inf"), surface_level=0.0, gravity=GRAVITY)
    return Environment(gravity=GRAVITY, water_density=float(rho), up=np.array([0.0, 0.0, 1.0]),
                       current_speed=case.ocean["current_speed"].value,
                       current_direction=np.array([math.cos(angle), math.sin(angle), 0.0]),
                       bottom_stiffness=float(case.ocean["bottom_stiffness"].value), bottom_friction=float(friction),
                       bottom_band=0.0, waves=waves)


def _node_type_fields(case: Case, position, node_type):
    """The nodes' box bodies and limits from their types: {Nodes field: (N, 3) array}, a field pair absent when no
    node has a body (or a limit), so that its term is not compiled. Checks that every body starts wholly under
    FEMNET's water surface z = 0 when there is a current to drag it (see the module docstring)."""
    types = [case.types[t] for t in node_type]
    fields = {}
    if any(nt.has_body for nt in types):
        length = np.array([[v.value for v in nt.length] if nt.has_body else [0.0] * 3 for nt in types])
        cd = np.array([[v.value for v in nt.drag_coefficient] if nt.has_body else [0.0] * 3 for nt in types])
        top = np.asarray(position)[:, 2] + np.maximum(length[:, 2], 0.0)
        above = np.flatnonzero(top > 0.0) if case.ocean["current_speed"].value > 0 else np.zeros(0, int)
        if above.size:
            i = int(above[0])
            nt = types[i]
            raise SceneError(f"{case.path}:{nt.length[0].line}: node type {node_type[i]}: the box of length "
                             f"{length[i].tolist()} m of the node at {np.round(position[i], 6).tolist()} reaches "
                             f"z = {top[i]:.6g} m, above FEMNET's water surface z = 0: FEMNET then takes the drag of "
                             "its immersed part only, jaxnet (no free surface here) of the whole box")
        fields.update(drag_length=length, drag_coefficient=cd)
    if any(nt.has_limit for nt in types):
        fields["limit"] = np.array([[v.value if s.value else 0.0 for v, s in zip(nt.limit, nt.sense)] for nt in types])
        fields["limit_sense"] = np.array([[s.value for s in nt.sense] for nt in types], dtype=np.int32)
    return fields


def _solver(case: Case) -> Newton:
    n = case.numeric
    return Newton(tol=n["threshold"].value, max_iter=int(n["max_iter"].value), max_step=n["max_step"].value)


def _check_types(case: Case):
    used = []
    for kind, k, p, name in _panels(case):
        used += [(t, f"{name} corner {c + 1}") for c, t in enumerate(p.corner_type)]
        used += [(t, f"{name} side {c + 1}") for c, t in enumerate(p.side_type)]
        used += [(p.material["inner_type"], f"{name} internal nodes")]
    used += [(t, f"cable {k + 1} end {e + 1}") for k, c in enumerate(case.cables) for e, t in enumerate(c.end_type)]
    used += [(c.material["inner_type"], f"cable {k + 1} internal nodes") for k, c in enumerate(case.cables)]
    for t, what in used:
        if t.value not in case.types:
            raise SceneError(f"{case.path}:{t.line}: {what}: node type {t.value} is not described (types: "
                             f"{sorted(case.types)})")


def _check_supported(case: Case):
    """What a case may read but jaxnet cannot model: said with the line that asks for it."""
    speed = case.ocean["current_speed"]
    if case.hexagonal and speed.value > 0:
        raise SceneError(f"{case.path}:{speed.line}: current speed {speed.value!r} m/s with hexagonal panels (hexagonal "
                         f"panel 1 at line {case.hexagonal[0].line}): jaxnet has no drag model for hexagonal netting yet")


#: corners and cable ends closer than this (m) at the start are one node (jaxnet's Net joins them)
MERGE_TOLERANCE = 1e-6


@dataclasses.dataclass
class _Plan:
    """How the case's parts are joined (see the module docstring, "Links"): start positions after joining,
    panel sides sewn together, cables sewn along panel sides, the bars of the other cables."""

    corners: dict        # (kind, index) -> (C, 3) start positions of a panel's corners (m)
    ends: list           # per cable: (2, 3) start positions of its ends (m)
    seams: list          # [(Side, Side)]
    along: dict          # cable index -> (Side, number of bars or None: the side's division)
    n_bars: list         # per cable: number of bars when it is not sewn along a side
    joined: list         # [[point names]]: the points made one node, groups of two or more


def _point_names(case: Case):
    """Every panel corner and cable end: [((kind, index, corner), name, line)]."""
    out = []
    for kind, k, p, name in _panels(case):
        out += [((kind, k, c), f"{name} corner {c + 1}", p.corner_type[c].line) for c in range(len(p.corners))]
    for k, c in enumerate(case.cables):
        out += [(("el", k, e), f"cable {k + 1} end {e + 1}", c.end_type[e].line) for e in range(2)]
    return out


def _plan(case: Case) -> _Plan:
    """Join the case's parts as FEMNET's mesher does (phobos ``chargement_don.c``, ``maillage*.c``,
    ``numerotation.c``):

    * the points of a link, those closer than ``input link`` d (FEMNET's automatic links) and those at one
      place (jaxnet joins them anyway) are one node, which starts at the mean of their start positions;
    * a panel side whose two corners are joined to the two corners of another panel's side, or to the two
      ends of a cable, is sewn to it; the division of a sewn side is that of the part meshed first when it
      is a cable (its number of bars); otherwise jaxnet's (the largest default of the sewn sides);
    * cables joined at both ends to the ends of another cable would share its nodes: only when that one has
      a single bar (then they are parallel bars), otherwise refused.
    """
    points = _point_names(case)
    index = {key: i for i, (key, _, _) in enumerate(points)}
    xyz = np.array([(_panel_of(case, key).corners[key[2], :3] if key[0] != "el" else case.cables[key[1]].ends[key[2]])
                    for key, _, _ in points], dtype=float).reshape(-1, 3)
    parent = list(range(len(points)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner = {}
    for link in case.links:
        ids = [index[m[:3]] for m in link.members]
        for m, i in zip(link.members, ids):
            if i in owner:
                raise SceneError(f"{case.path}:{m[3]}: {points[i][1]} is already in the link of line {owner[i]}: a point "
                                 "belongs to one link (list all the points that are one node in that link)")
            owner[i] = link.line
        for i in ids[1:]:
            parent[find(i)] = find(ids[0])
    radius = MERGE_TOLERANCE
    if "link" in case.inputs:
        radius = max(radius, float(case.inputs["link"].value))
    if len(xyz) > 1:
        from scipy.spatial import cKDTree

        for i, j in cKDTree(xyz).query_pairs(radius):
            parent[find(i)] = find(j)
    group = [find(i) for i in range(len(points))]
    members = {}
    for i, g in enumerate(group):
        members.setdefault(g, []).append(i)
    for ids in members.values():
        seen = {}
        for i in ids:
            part = points[i][0][:2]
            if part in seen:
                a, b = points[seen[part]], points[i]
                raise SceneError(f"{case.path}:{b[2]}: {a[1]} and {b[1]} are joined (by a link, or closer than the "
                                 f"automatic link distance {radius:g} m): a panel or cable cannot be joined to itself")
            seen[part] = i
    # FEMNET's joined node starts at the mean of the joined points (numerotation.c); moving them there before
    # meshing makes jaxnet's Net join them by position, and the sides to sew end at the same two points
    moved = xyz.copy()
    for ids in members.values():
        moved[ids] = xyz[ids].mean(axis=0)
    reps = list(members)
    if len(reps) > 1:
        from scipy.spatial import cKDTree

        close = sorted(cKDTree(moved[reps]).query_pairs(MERGE_TOLERANCE))
        if close:
            a, b = points[reps[close[0][0]]], points[reps[close[0][1]]]
            raise SceneError(f"{case.path}:{b[2]}: {b[1]} is not joined to {a[1]} but starts at the same place (after "
                             "joining linked points at the mean of their positions): they would be one node")
    # sides and cables by the pair of nodes at their ends
    rank = {item: i for i, item in enumerate(case.order)}
    names = {kind: name for kind, name in (("pa", "panel"), ("ha", "hexagonal panel"))}
    ends = {}
    for kind, k, p, name in _panels(case):
        n = len(p.corners)
        for s in range(n):
            pair = frozenset((group[index[(kind, k, s)]], group[index[(kind, k, (s + 1) % n)]]))
            ends.setdefault(pair, []).append((rank.get((kind, k + 1), 0), kind, k, s))
    for k in range(len(case.cables)):
        pair = frozenset((group[index[("el", k, 0)]], group[index[("el", k, 1)]]))
        ends.setdefault(pair, []).append((rank.get(("el", k + 1), 0), "el", k, None))
    seams, along = [], {}
    n_bars = [c.material["n_bars"].value for c in case.cables]
    for items in ends.values():
        if len(items) < 2:
            continue
        items.sort()
        sides = [it for it in items if it[1] != "el"]
        cables = [it for it in items if it[1] == "el"]
        if sides:
            base = sides[0]
            side = Side(f"{names[base[1]]} {base[2] + 1}", base[3])
            seams += [(side, Side(f"{names[it[1]]} {it[2] + 1}", it[3])) for it in sides[1:]]
            for it in cables:
                # meshed before every side: its bars divide them; after: it follows the side's division
                along[it[2]] = (side, n_bars[it[2]] if it is cables[0] and it[0] < base[0] else None)
        else:
            first = cables[0][2]
            for it in cables[1:]:
                k = it[2]
                if n_bars[first] > 1:
                    raise SceneError(f"{case.path}:{case.cables[k].line}: cable {k + 1} is joined at both ends to the ends "
                                     f"of cable {first + 1}, meshed before it with {n_bars[first]} bars: FEMNET threads "
                                     "it on that cable's nodes, which jaxnet cannot do (a cable is sewn along a panel "
                                     "side only)")
                n_bars[k] = 1  # FEMNET gives it the single bar of the cable it lies on
    corners = {}
    for kind, k, p, name in _panels(case):
        corners[(kind, k)] = moved[[index[(kind, k, c)] for c in range(len(p.corners))]]
    cable_ends = [moved[[index[("el", k, 0)], index[("el", k, 1)]]] for k in range(len(case.cables))]
    joined = [[points[i][1] for i in ids] for ids in members.values() if len(ids) > 1]
    return _Plan(corners, cable_ends, seams, along, n_bars, joined)


def _panel_of(case: Case, key):
    return (case.panels if key[0] == "pa" else case.hexagonal)[key[1]]


def _joined(case: Case, plan: _Plan) -> Case:
    """The case with its corners and cable ends at their joined start positions."""
    def panel(p, xyz):
        corners = p.corners.copy()
        corners[:, :3] = xyz
        return dataclasses.replace(p, corners=corners)

    return dataclasses.replace(
        case,
        panels=[panel(p, plan.corners[("pa", k)]) for k, p in enumerate(case.panels)],
        hexagonal=[panel(p, plan.corners[("ha", k)]) for k, p in enumerate(case.hexagonal)],
        cables=[dataclasses.replace(c, ends=plan.ends[k]) for k, c in enumerate(case.cables)])


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


def _describe(case: Case, env: Environment, plan: _Plan, femnet_laws: bool = True) -> Net:
    """The panels and cables of the (joined) case on a new Net, sewn as ``plan`` says."""
    net = Net(environment=env, merge_tolerance=MERGE_TOLERANCE)
    for kind, k, p, name in _panels(case):
        if kind == "pa":
            corners = np.concatenate([p.corners[:, :3], _twine_coordinates(p.corners[:, 3:5])], axis=1)
            net.panel(name, corners, _twine(p, case, femnet_laws), p.material["step"].value)
        else:
            # hexagonal: FEMNET's (U, V) count base meshes, as jaxnet's (see the module docstring)
            net.panel(name, p.corners, _hextwine(p), p.material["step"].value)
    for a, b in plan.seams:
        net.seam(a, b)
    for k, c in enumerate(case.cables):
        name, length = f"cable {k + 1}", c.material["l0"].value
        if k in plan.along:
            side, n_bars = plan.along[k]
            net.cable(name, along=side, rope=_rope(c), length=length, n_bars=n_bars)
        else:
            net.cable(name, start=tuple(c.ends[0]), end=tuple(c.ends[1]), rope=_rope(c), length=length,
                      n_bars=plan.n_bars[k])
    return net


@contextlib.contextmanager
def _located(case: Case, what: str):
    """Name the file and the line of the part it names in a SceneError from jaxnet's Net (describing or
    building the net)."""
    try:
        yield
    except SceneError as err:
        if str(err).startswith(f"{case.path}:"):
            raise
        raise SceneError(f"{case.path}:{_culprit_line(case, str(err))}: {what}: {err}") from None


def _culprit_line(case: Case, message: str) -> int:
    """The line of the panel or cable a message names; else of the first node type (fixings, loads)."""
    m = re.search(r"(hexagonal panel|panel|cable) (\d+)", message)
    if m:
        parts = {"hexagonal panel": case.hexagonal, "panel": case.panels, "cable": case.cables}[m.group(1)]
        k = int(m.group(2)) - 1
        if 0 <= k < len(parts):
            return parts[k].line
    return min((t.line for t in case.types.values()), default=1)


def read_don(path, femnet_laws=True):
    """Read FEMNET's ``.don`` case ``path`` into jaxnet.

    ``femnet_laws``: use FEMNET's own laws where they differ from the book (knot contact; netting drag in a
    case with a catch; ``docs/errata.md``), so that jaxnet gives FEMNET's answers (the default); False for
    jaxnet's own physics (the book's laws, corrected).

    Returns:
      (net, solver, info): a :class:`~jaxnet.net.Net` (jaxnet meshes it; ``net.build()`` gives the scene,
      checked here to build), the :class:`~jaxnet.solve.statics.Newton` options (tol = FEMNET's threshold in
      N, max_iter, max_step = FEMNET's displacement limit in m), and a dict ``info`` of what the reader
      decided (symmetry planes and copies, FEMNET's solver settings, the inputs and outputs, the depth, the
      joined points, seams and sewn cables, the added masses per node type, the sea bed and the node bodies read).
    Raises:
      SceneError naming the file and line (see the module docstring).
    """
    case = parse_don(path)
    _check_types(case)
    _check_supported(case)
    env = _environment(case)
    plan = _plan(case)
    case = _joined(case, plan)
    # a first build, held at every corner and cable end, tells where jaxnet's mesher put the nodes: their
    # FEMNET types (and so the fixings and loads of the real net) follow from where they were created
    with _located(case, "meshing the case"):
        probe = _describe(case, env, plan, femnet_laws)
        for kind, k, p, name in _panels(case):
            for xyz in p.corners[:, :3]:
                probe.fix(tuple(xyz))
        for c in case.cables:
            for xyz in c.ends:
                probe.fix(tuple(xyz))
        scene = probe.build()
        net = _describe(case, env, plan, femnet_laws)
    node_type = _node_types(case, scene)
    position = np.asarray(scene.nodes.position)
    planes = _symmetry(case, position, node_type)
    for i, t in enumerate(node_type):
        nt = case.types[t]
        axes = "".join(a for j, a in enumerate("xyz") if nt.fixed[j].value or nt.symmetry[j].value)
        if axes:
            net.fix(tuple(position[i]), axes)
        if nt.mass[0] > 0 or any(nt.force):
            net.attach(tuple(position[i]), mass=nt.mass[0], force=nt.force)
    fields = _node_type_fields(case, position, node_type)
    for i, t in enumerate(node_type):
        if "drag_length" in fields and case.types[t].has_body:
            net.body(tuple(position[i]), fields["drag_length"][i], fields["drag_coefficient"][i])
        if "limit" in fields and case.types[t].has_limit:
            net.limit(tuple(position[i]), fields["limit"][i], fields["limit_sense"][i])
    netting_nodes = np.unique(np.asarray(scene.netting.vertices)) if scene.netting is not None else np.arange(len(position))
    catch = _catch(case, position, netting_nodes, planes, env)
    with _located(case, "the net with its node types"):
        if catch is not None:
            volume, cd, copies, center, axis = catch
            net.catch(volume, drag_coefficient=cd, symmetry=copies, center=tuple(center), axis=tuple(axis))
        net.build()
    return net, _solver(case), {**_info(case, planes, catch, plan), "femnet_laws": bool(femnet_laws)}


def _info(case, planes, catch, plan=None):
    along = {} if plan is None else plan.along
    differences = []
    if any(p.material["opening"].value > 0 for p in case.panels):
        differences.append("mesh opening stiffness: the book's law (FEMNET's flexion2 applies 4.218 as printed: its "
                           "couple is 2 H cos(a) (a - a0)); docs/errata.md")
    return {
        "laws_differing_from_femnet": differences,
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
        "cables_sewn_along_sides": {f"cable {k + 1}": f"{side.panel} side {side.index + 1}"
                                    for k, (side, _) in sorted(along.items())},
        "seams": [] if plan is None else [f"{a.panel} side {a.index + 1} = {b.panel} side {b.index + 1}"
                                          for a, b in plan.seams],
        "joined": [] if plan is None else plan.joined,
        # FEMNET's added mass acts in dynamics only (lectureDo4.c): read, kept here, without effect in statics
        "added_mass": {t: list(nt.added_mass) for t, nt in sorted(case.types.items())},
        # FEMNET's dynamic settings (None for a static case): what `jaxnet run CASE.don --dynamic` uses
        "dynamic": None if not case.numeric["record_end"].value > 0 else {
            "time_step_s": case.numeric["dt"].value, "record_every_s": case.numeric["record_dt"].value,
            "record_start_s": case.numeric["record_start"].value, "end_time_s": case.numeric["record_end"].value},
        "sea_bed": {"stiffness_N_per_m": case.ocean["bottom_stiffness"].value,
                    "moving_bottom": "moving_bottom" in case.inputs,
                    "friction": _environment(case).bottom_friction,
                    "limits": {t: {"limit_m": [v.value for v in nt.limit], "sense": [v.value for v in nt.sense]}
                               for t, nt in sorted(case.types.items()) if nt.has_limit}},
        "node_bodies": {t: {"length_m": [v.value for v in nt.length],
                            "drag_coefficient": [v.value for v in nt.drag_coefficient]}
                        for t, nt in sorted(case.types.items()) if nt.has_body},
        "hexagonal_twine_diameter_m": {f"hexagonal panel {k + 1}": _hexagonal_diameter(
            [v.value for v in p.material["l0"]], [v.value for v in p.material["diameter"]])
            for k, p in enumerate(case.hexagonal)},
    }


def _on_segment(points, a, b, tol):
    """(N,) True where a point lies strictly inside segment a-b (m)."""
    ab = b - a
    t = (points - a) @ ab / max(ab @ ab, 1e-300)
    d = np.linalg.norm(points - a - t[:, None] * ab, axis=1)
    return (d <= tol) & (t > 1e-9) & (t < 1 - 1e-9)


def _node_types(case: Case, scene):
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

    nettings = [f for f in (scene.netting, scene.hexagonal) if f is not None]
    panel_of = np.concatenate([np.asarray(f.panel) for f in nettings]) if nettings else np.zeros(0, int)
    tri = np.concatenate([np.asarray(f.vertices) for f in nettings]) if nettings else np.zeros((0, 3), int)
    for j, (kind, k, p, name) in enumerate(_panels(case)):
        nodes = np.unique(tri[panel_of == j])
        claim(nodes, 0, p.material["inner_type"], f"{name} internal nodes")
        C = len(p.corners)
        for c in range(C):
            a, b = p.corners[c, :3], p.corners[(c + 1) % C, :3]
            claim(nodes[_on_segment(pos[nodes], a, b, tol)], 1, p.side_type[c], f"{name} side {c + 1}")
            claim(at(a), 2, p.corner_type[c], f"{name} corner {c + 1}")
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
            raise SceneError(f"{case.path}:{_culprit_line(case, '')}: node {i} at {pos[i].tolist()} belongs to no "
                             "panel or cable")
        out.append(claims[i][max(claims[i])][0].value)
    return out


# -- FEMNET's own mesh ----------------------------------------------------------------------------


def read_mdg(path, don=None, femnet_laws=True):
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
    bar_lines = rows("description des elements", n_bars, 6, at)
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
                  drag_area=np.zeros(n_nodes), size=np.zeros(n_nodes), **_node_type_fields(case, position, node_type))

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
        twines = [_twine(p, case, femnet_laws) for p in case.panels]
        netting = Netting(vertices=vertices, uv=uv, panel=panel, **netting_rows(twines, panel))
    bars = None
    if n_bars:
        ends = np.array([[node_index(v, r[-1]) for v in r[1:3]] for r in bar_lines])
        cable = np.array([int(r[5]) - 1 for r in bar_lines])
        for r, c in zip(bar_lines, cable):
            if not 0 <= c < len(case.cables):
                raise SceneError(f"{where}:{r[-1]}: bar {int(r[0])} belongs to cable {c + 1}, not in {don}")
        share = np.array([r[4] - r[3] for r in bar_lines])
        bad = np.flatnonzero(~(share > 0))
        if bad.size:
            r = bar_lines[int(bad[0])]
            raise SceneError(f"{where}:{r[-1]}: bar {int(r[0])}: its share of the cable (pro2 - pro1 = {share[bad[0]]!r}) "
                             "must be > 0")
        ropes = [_rope(c) for c in case.cables]
        rest = share * np.array([case.cables[c].material["l0"].value for c in cable])
        bars = Bars(ends=ends, rest_length=rest, cable=cable, **bar_rows(ropes, cable))
    netting_nodes = np.unique(netting.vertices) if netting is not None else np.arange(n_nodes)
    catch_spec = _catch(case, position, netting_nodes, planes, env)
    catch = None
    if catch_spec is not None:
        volume, cd, copies, center, axis = catch_spec
        catch = Catch(volume=volume, drag_coefficient=cd, axis=axis, center=center, symmetry=copies)
        netting = dataclasses.replace(netting, outward=outward(position, np.asarray(netting.vertices), center))
    scene = Scene(nodes=nodes, netting=netting, bars=bars, environment=env, catch=catch,
                  panel_names=tuple(f"panel {k + 1}" for k in range(len(case.panels))),
                  cable_names=tuple(f"cable {k + 1}" for k in range(len(case.cables))))
    validate(scene)
    return scene, _solver(case), {**_info(case, planes, catch_spec), "femnet_laws": bool(femnet_laws)}


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
