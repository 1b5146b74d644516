"""The ``.don`` grammar as tables, and :class:`DonFile`, a file as read (:func:`~.parse.parse_don` reads one
with these tables).

FEMNET's ``.don`` (phobos ``chargement_don.c``) is a fixed sequence of labelled fields, each a label ending in
a colon and one or more values, then a free-order tail of ``input NAME values`` and ``output NAME`` lines.
Every field is one :class:`Field` entry (its key, its label with the long and short spellings found in
FEMNET's cases, how messages name it, its check), grouped in tuples per section (:data:`PANEL_MATERIAL`,
:data:`NODE_TYPE`, :data:`OCEAN`, ...); the labels that open a part or an entry of a list are
:data:`HEADINGS`; the tail's commands are :data:`COMMANDS`. Adding a field or a command is adding its entry
(with its check) where the file has it. The checks that need several fields (a dynamic case needs a time
step, waves a period, ...) follow their section in :func:`~.parse.parse_don`.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Callable, NamedTuple

import numpy as np

from jaxnet.io.femnet.reader import Reader, Value

#: the most nodes a panel may get: larger meshes are surely a mistake (and take long to make)
MAX_PANEL_NODES = 50_000
#: the most bars of a cable (FEMNET's phobos.h: NBMAXBARRE 5000 in all); a cable sewn along a side divides it
MAX_BARS = 5_000


def spelled(*alternatives):
    """A label pattern: the normalised label text (lower case, runs of blanks as one space) matching one of the
    ``alternatives`` (regular expressions: FEMNET's long and short spellings)."""
    return re.compile("|".join(f"(?:{a})" for a in alternatives))


@dataclasses.dataclass(frozen=True)
class Field:
    """One labelled field of the ``.don``: a label, its colon, then its value or values.

    ``key``: where the parsed file keeps it (a key of its section's dict); ``label``: its label pattern
    (:func:`spelled`); ``what``: how messages name it (after the part's name: "cable 2: traction stiffness");
    ``check``: that of a number (:meth:`Reader.number`: ">=0", ">0", "position", "meshes"), or "0 or 1" for
    integer flags; ``integer`` with its ``minimum``; ``values``: the names of its values when it has several,
    one per axis ("X", "Y", "Z") or twine family ("l", "m", "n"), in which case the values are named by
    ``what`` and their name, less the names when ``what`` ends with them ("traction stiffness l m n" ->
    "traction stiffness l"); ``one_line``: its several values must be on the label's line; ``then``: a check
    of a single value as soon as it is read, ``then(reader, value, field, prefix)``."""

    key: str
    label: re.Pattern
    what: str
    check: str | None = None
    integer: bool = False
    minimum: int | None = None
    values: tuple = ()
    one_line: bool = False
    then: Callable | None = None

    def value_names(self, prefix=""):
        """How messages name its several values, after the part's ``prefix``."""
        base = self.what.removesuffix(" " + " ".join(self.values))
        return [f"{prefix}{base} {name}" for name in self.values]


def field(key, what, *spellings, **options):
    """A :class:`Field` entry: its key, how messages name it, its label's spellings, then its options."""
    return Field(key, spelled(*spellings), what, **options)


def read(r: Reader, f: Field, prefix=""):
    """Read the field ``f`` at the reader's position: a :class:`~.reader.Value`, or a list of them when it has
    several values; ``prefix`` names the part it belongs to in messages ("panel 2: ")."""
    what = prefix + f.what
    r.label(f.label, what)
    if not f.values:
        v = r.integer(what, f.minimum) if f.integer else r.number(what, f.check)
        if f.then is not None:
            f.then(r, v, f, prefix)
        return v
    start = r.last[1]
    values = []
    for name in f.value_names(prefix):
        v = r.integer(name, f.minimum) if f.integer else r.number(name, f.check)
        if f.check == "0 or 1" and v.value not in (0, 1):
            raise r.error(f"'{name}' must be 0 or 1, got {v.value}", v.line)
        values.append(v)
    if f.one_line:
        r.one_line(values, start, what, " ".join(f.values))
    return values


def read_all(r: Reader, fields, prefix=""):
    """Read the fields of a section in their order: {key: value or values}."""
    return {f.key: read(r, f, prefix) for f in fields}


def _only_design_plane_3(r, v, f, prefix):
    """FEMNET's design plane 3 takes x y z as written; 1 and 2 permute them (not supported)."""
    if v.value != 3:
        raise r.error(f"{prefix}{f.what} {v.value}: only 3 (x y z as written) is supported", v.line)


def _only_zero(reason):
    """A ``then`` check refusing a count other than 0: ``reason`` says why ("{}": the field's key in words)."""
    def check(r, v, f, prefix):
        if v.value:
            raise r.error(f"{prefix}{f.what} {v.value}: {reason.format(f.key.replace('_', ' '))}", v.line)
    return check


def _at_most_max_bars(r, v, f, prefix):
    """A cable of at most :data:`MAX_BARS` bars."""
    if v.value > MAX_BARS:
        raise r.error(f"{prefix}{v.value} bars (limit {MAX_BARS}, FEMNET's own)", v.line)


XYZ = ("X", "Y", "Z")
LMN = ("l", "m", "n")

# -- the counts of the file's parts, in the file's order ------------------------------------------------------
DESIGN_PLANE = field("orientation", "design in the plane normal to axis", r"design in the plane normal to axis",
                     integer=True, then=_only_design_plane_3)
PANELS_NUMBER = field("panels", "panels number", r"panels number", integer=True, minimum=0)
HEXAGONAL_PANELS_NUMBER = field("hexa", "hexagonal panels number", r"hexagonal panels number", integer=True,
                                minimum=0)
CABLES_NUMBER = field("cables", "cables number", r"cables number", integer=True, minimum=0)
SLIDING_CABLES_NUMBER = field("sliding", "sliding cables number", r"sliding cables number", integer=True, minimum=0,
                              then=_only_zero("sliding cables are not supported by this reader"))
LINKS_NUMBER = field("links", "links number", r"links number", integer=True, minimum=0)
NODE_TYPES_NUMBER = field("types", "number of types of nodes", r"number of types of nodes", integer=True, minimum=1)

#: how messages name the parts of each kind (links and the meshing order name them by these keys)
PART_NAMES = {"pa": "panel", "ha": "hexagonal panel", "el": "cable"}

#: labels that open a part, or an entry of a list, read by that part's parser (messages name the part)
HEADINGS = {
    "panel": spelled(r"panel"),                                   # then its number
    "contour": spelled(r"nodes of the contour.*"),                # then the corners: no x y z U V type side-type
    "cable": spelled(r"cable"),                                   # then its number
    "cable ends": spelled(r"extremities no x y z type"),          # then the two ends: no x y z type
    "link": spelled(r"nb_? ?pts?", r"number of (points|corners)", r"link( \d+)?"),  # then its number of points
    "link structure": spelled(r"pa", r"panel", r"ha", r"he", r"hexa", r"el", r"element", r"co", r"wi", r"winch"),
    "link corner": spelled(r"nd", r"no", r"node", r"corner", r"extremity"),
    "meshing order": spelled(r"meshing order"),
    "meshing order entry": spelled(r"el", r"pa", r"ha", r"he"),
    "node type": spelled(r"no du type", r"type"),                 # then its number
}

# -- materials (prefixed by the part's name: "panel 1: ", "hexagonal panel 1: ", "cable 1: ") ----------------
PANEL_CORNERS = field("corners", "number of nodes around", r"number of nodes around", integer=True, minimum=3)
TRACTION_STIFFNESS = field("ea", "traction stiffness", r"traction stiffness( \(n\))?", r"kt", check=">=0")
COMPRESSION_STIFFNESS = field("eac", "compression stiffness", r"compression stiffness( \(n\))?", r"kc", check=">=0")
OPENING_STIFFNESS = field("opening", "mesh opening stiffness", r"mesh opening stiffness( \(n\.m/rad\))?", check=">=0")
UNSTRETCHED_LENGTH = field("l0", "unstretched length", r"unstretched length( \(m\))?", r"l", check=">0")
VOLUMIC_MASS = field("density", "volumic mass", r"volumic mass( \(kg/m3\))?", r"vm", check=">=0")
DIAMETER = field("diameter", "hydrodynamic diameter", r"hydrodynamic diameter( \(m\))?", r"d", check=">=0")
KNOT_SIZE = field("knot", "knot size", r"knot size( \(m\))?", check=">=0")
NORMAL_CD = field("cd", "normal Cd", r"normal cd", r"cd", check=">=0")
TANGENTIAL_CD = field("f", "tangential Cd", r"tangential cd", r"f", check=">=0")
MESHING_STEP = field("step", "meshing step", r"meshing step( \(m\))?", check=">0")
INTERNAL_NODES_TYPE = field("inner_type", "type of internal nodes", r"type of internal nodes", r"ty", integer=True,
                            minimum=1)
MESHING_TYPE = field("mesh_type", "meshing type", r"meshing type", integer=True)

#: a diamond panel's material, after its corners
PANEL_MATERIAL = (TRACTION_STIFFNESS, COMPRESSION_STIFFNESS, OPENING_STIFFNESS, UNSTRETCHED_LENGTH, VOLUMIC_MASS,
                  DIAMETER, KNOT_SIZE, NORMAL_CD, TANGENTIAL_CD, MESHING_STEP, INTERNAL_NODES_TYPE, MESHING_TYPE)
#: a hexagonal panel's material, after its corners and one skipped line: three values (twine families l, m, n)
#: for the stiffnesses, lengths and diameters; no opening stiffness, no knot size
HEXAGONAL_PANEL_MATERIAL = (
    field("ea", "traction stiffness l m n", r"traction stiffness( l,? ?m,? ?n)?( \(n\))?", r"kt", check=">=0",
          values=LMN),
    field("eac", "compression stiffness l m n", r"compression stiffness( l,? ?m,? ?n)?( \(n\))?", r"kc", check=">=0",
          values=LMN),
    field("l0", "unstretched length l m n", r"unstretched lengths?( l,? ?m,? ?n)?( \(m\))?", r"l", check=">0",
          values=LMN),
    field("diameter", "hydrodynamic diameter l m n", r"hydrodynamic diameters?( l,? ?m,? ?n)?( \(m\))?", r"d",
          check=">=0", values=LMN),
    VOLUMIC_MASS, NORMAL_CD, TANGENTIAL_CD, MESHING_STEP, INTERNAL_NODES_TYPE, MESHING_TYPE)
#: a cable's material, after its ends
CABLE_MATERIAL = (TRACTION_STIFFNESS, COMPRESSION_STIFFNESS, UNSTRETCHED_LENGTH, VOLUMIC_MASS, DIAMETER, NORMAL_CD,
                  TANGENTIAL_CD,
                  field("n_bars", "number of bars", r"bars number", r"nb", integer=True, minimum=1,
                        then=_at_most_max_bars),
                  INTERNAL_NODES_TYPE)

#: a node type, after its number (prefixed "node type N: "); keys are :class:`DonNodeType`'s attributes.
#: The X Y Z of numbers are on one line; the flags and senses are not checked so
NODE_TYPE = (
    field("mass", "mass", r"mass x,y,z( \(kg\))?", check=">=0", values=XYZ, one_line=True),
    field("added_mass", "added mass", r"added mass x,y,z( \(kg\))?", check=">=0", values=XYZ, one_line=True),
    field("length", "length", r"length x,y,z( \(m\))?", values=XYZ, one_line=True),
    field("drag_coefficient", "drag coefficient", r"drag coefficient x,y,z", check=">=0", values=XYZ, one_line=True),
    field("force", "external force", r"external forces? x,y,z( \(n\))?", values=XYZ, one_line=True),
    field("fixed", "displacement", r"displacement x,y,z", check="0 or 1", integer=True, values=XYZ),
    field("limit", "limits", r"limits x,y,z( \(m\))?", values=XYZ, one_line=True),
    field("sense", "limits sense", r"limits sens(e)? x,y,z", integer=True, values=XYZ),
    field("symmetry", "symmetry", r"sym(m)?etry x,y,z", check="0 or 1", integer=True, values=XYZ),
)

#: FEMNET's solver settings (statics, then dynamics; ``lectureDo4.c``)
NUMERICS = (
    field("divisor", "divisor", r"divisor( \(s\))?"),
    field("threshold", "convergence threshold", r"convergence threshold( \(n\))?", check=">0"),
    field("max_step", "displacement limit for each iteration", r"displacement limit for each iteration( \(m\))?",
          check=">0"),
    field("max_iter", "maximal number of iterations", r"maximal number of iterations", integer=True, minimum=1),
    field("dt", "dynamic time step", r"dynamic: time step( \(s\))?"),
    field("record_dt", "dynamic record time step", r"dynamic: record time step( \(s\))?"),
    field("record_start", "dynamic beginning time of record", r"dynamic: beginning time of record( \(s\))?"),
    field("record_end", "dynamic end time of record and calculation",
          r"dynamic: end time of record and calculation( \(s\))?"),
)

#: the current (direction in deg from x towards y, speed in m/s) and the waves (s, m, deg, depth m)
OCEAN = (
    field("current_direction", "current direction", r"current direction( \(deg\))?"),
    field("current_speed", "current speed", r"current speed( \(m/s\))?", check=">=0"),
    field("wave_period", "wave period", r"wave period( \(s\))?"),
    field("wave_height", "wave height", r"wave height( \(m\))?", check=">=0"),
    field("wave_direction", "wave direction", r"wave direction relatively x( \(deg\))?"),
    field("depth", "depth", r"depth( \(m\))?", check=">=0"),
)

#: the catch: the modelled part's volume (m³), its accuracy, its drag coefficient
CATCH = (
    field("catch_volume", "catch volume", r"volume( \(m3\))?", check=">=0"),
    field("catch_accuracy", "accuracy on the catch volume", r"accuracy on this volume", check=">=0"),
    field("catch_cd", "drag coefficient of the catch", r"drag coefficient on this volume", check=">=0"),
)

#: the sea bed (``fond.c``), kept with the ocean: friction coefficient, penalty stiffness (N/m)
SEA_BED = (
    field("bottom_friction", "wearing coefficient on the bottom", r"wearing coefficient on the bottom", check=">=0"),
    field("bottom_stiffness", "stiffness of the insertion in the sea bottom",
          r"stiffness of the insertion in the sea bottom( \(n/m\))?", check=">=0"),
)

_NO_TEXT_OUTPUTS = _only_zero("text outputs of {} are not supported (only 0)")
#: FEMNET's text outputs: the counts of the lists that follow, none supported (only 0)
TEXT_OUTPUTS = (
    field("distances", "distances number", r"distances number", integer=True, minimum=0, then=_NO_TEXT_OUTPUTS),
    field("forces", "forces number", r"forces number", integer=True, minimum=0, then=_NO_TEXT_OUTPUTS),
    field("tensions", "tensions number", r"tensions number", integer=True, minimum=0, then=_NO_TEXT_OUTPUTS),
    field("sliding_tensions", "sliding tensions number", r"sliding tensions number", integer=True, minimum=0,
          then=_NO_TEXT_OUTPUTS),
    field("positions", "positions number", r"positions number", integer=True, minimum=0, then=_NO_TEXT_OUTPUTS),
)

#: FEMNET's display switches (integers, read and unused)
DISPLAYS = (
    field("show_forces", "structure forces display", r"structure forces display", integer=True),
    field("show_diameter", "catch diameter display", r"catch diameter display", integer=True),
    field("show_thickness", "catch thickness display", r"catch thickness display", integer=True),
    field("show_volume", "catch volume display", r"catch volume display", integer=True),
    field("show_surface", "filtrated surface display", r"filt(e|ra)ted surface display", integer=True),
    field("show_speed", "speed display", r"speed display", integer=True),
)


# -- the free-order tail: commands ----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Command:
    """A line ``input NAME v1 ... vN`` (it changes the case) or ``output NAME`` (it only prints figures).

    ``n_values``: the numbers that follow the name; ``check``: None, or check(values) giving the message that
    refuses them (None when they are accepted); ``repeatable``: the command may be given on several lines (one
    per cable, per pair of cables), each an :class:`Occurrence`, kept in the file's order (the parsed file's
    ``inputs[name]`` is then a Value of the tuple of them, at the first one's line)."""

    kind: str
    name: str
    n_values: int = 0
    check: Callable | None = None
    repeatable: bool = False


class Occurrence(NamedTuple):
    """One line of a repeatable command: its numbers and its line."""

    values: tuple
    line: int


def _positive_water_density(values):
    return None if values[0] > 0 else f"'input water_density' must be > 0, got {values[0]!r}"


def _cable_number(value, what):
    """The message refusing a cable number that is not a whole number >= 1 (None when it is one)."""
    return None if value == int(value) and value >= 1 else f"{what}: the cable number must be a whole number >= 1, got {value!r}"


def _ei_flexion_cable(values):
    """``input EI_flexion_cable K EI``: cable K's flexural stiffness EI >= 0 (N·m²)."""
    return (_cable_number(values[0], "'input EI_flexion_cable'")
            or (None if values[1] >= 0 else f"'input EI_flexion_cable' {values[0]:g}: EI must be >= 0 (N·m²), got {values[1]!r}"))


def _link_flexion_elem2(values):
    """``input link_flexion_elem2 A B angle``: two different cables, welded at the angle (degrees, 180 when they are
    aligned) in [0, 180]."""
    what = "'input link_flexion_elem2'"
    refused = _cable_number(values[0], what) or _cable_number(values[1], what)
    if refused:
        return refused
    if values[0] == values[1]:
        return f"{what}: cable {values[0]:g} is linked to itself"
    if not 0.0 <= values[2] <= 180.0:
        return f"{what} {values[0]:g} {values[1]:g}: the angle between the cables must be in [0, 180] degrees (180: aligned), got {values[2]!r}"
    return None


COMMANDS = (
    Command("input", "auto_convergence"),
    Command("input", "convergence_parameters", 3),
    Command("input", "link", 1),            # FEMNET's automatic links: points closer than this (m) are one node
    Command("input", "moving_bottom"),      # the bottom slides at the current's speed: its friction acts (fond.c)
    Command("input", "water_density", 1, _positive_water_density),   # kg/m³
    # cable bending (jaxnet.terms.cable_bending): EI (N·m²) of a cable; two cables welded at an angle (degrees)
    Command("input", "ei_flexion_cable", 2, _ei_flexion_cable, repeatable=True),
    Command("input", "link_flexion_elem2", 3, _link_flexion_elem2, repeatable=True),
    Command("output", "color_element"),     # the colour batz draws a cable in (display only; 6flexion/c1)
    *(Command("output", name) for name in ("element_drag", "surface_drag", "catch_drag", "no_visible_symmetry",
                                           "panel_drag", "cable_drag", "node_drag", "energy", "tension", "tensions")),
)
INPUTS = {c.name: c for c in COMMANDS if c.kind == "input"}
OUTPUTS = {c.name: c for c in COMMANDS if c.kind == "output"}


# -- what a .don holds, as read (before mapping onto jaxnet) -----------------------------------------------------


@dataclasses.dataclass
class DonPanel:
    """A diamond or hexagonal panel: its corners, their node types, its material, the line of its corners' count."""

    corners: np.ndarray   # (C, 5) x y z (m) U V as in the file (diamond: meshes along the diagonals, see
                          # twine_coordinates; hexagonal: base meshes)
    corner_type: list     # [Value] per corner: the corner node's type
    side_type: list       # [Value] per corner: the type of the nodes created on the side to the next corner
    material: dict        # PANEL_MATERIAL key -> Value (hexagonal: ea, eac, l0, diameter -> [Value l, m, n])
    line: int
    hexagonal: bool = False


@dataclasses.dataclass
class DonCable:
    """A cable: its two ends (m), their node types, its material (CABLE_MATERIAL), the line of its ends."""

    ends: np.ndarray      # (2, 3)
    end_type: list
    material: dict
    line: int


@dataclasses.dataclass
class DonNodeType:
    """A node type: the mass (kg, isotropic) and force (N) of its nodes, which coordinates it holds (``fixed``,
    ``symmetry``: [Value 0 or 1] along X, Y, Z), its added mass (kg, dynamics only), its box and its sea-bed
    limits, and the line of its number."""

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
class DonLink:
    """A link: panel corners and cable ends that are one node. members: [(kind, index, corner, line)] with kind
    "pa" (diamond panel), "ha" (hexagonal panel) or "el" (cable), 0-based index and corner (cable end 0 or 1)."""

    members: list
    line: int


@dataclasses.dataclass
class DonFile:
    """A ``.don`` file as read (before mapping onto jaxnet): its parts, and its sections' fields as
    {key: Value} (``numeric``: NUMERICS; ``ocean``: OCEAN and SEA_BED; ``catch``: CATCH)."""

    path: str
    panels: list
    cables: list
    order: list           # [("el" | "pa" | "ha", index 1-based)]
    types: dict           # type number -> DonNodeType
    numeric: dict
    ocean: dict
    catch: dict
    inputs: dict          # input command name -> Value (its number, or tuple of numbers; 1.0 without any)
    outputs: list
    hexagonal: list = dataclasses.field(default_factory=list)   # hexagonal panels (DonPanel, hexagonal=True)
    links: list = dataclasses.field(default_factory=list)       # DonLink


def twine_coordinates(UV):
    """FEMNET's mesh coordinates (U, V) (meshes along the diagonals) -> twine coordinates (u, v) = (U + V, V - U)
    (phobos ``chargement_don.c``; see the package's docstring, "Twine coordinates")."""
    UV = np.asarray(UV, dtype=float)
    return np.stack([UV[..., 0] + UV[..., 1], UV[..., 1] - UV[..., 0]], axis=-1)
