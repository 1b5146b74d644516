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
    unset: float | None = None    # FEMNET's value when the file leaves it out (None: refused)
    unused: bool = False          # FEMNET never uses it: a stray value after it is dropped, with a warning

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
        if f.unset is not None and r.missing():
            # FEMNET's fscanf fails on the next label and leaves the value unset (zeroed memory): a drag coefficient
            # left out of a line (the seines' "Normal Cd:" of panel 26) is 0
            r.warnings.append(f"{r.path}:{r.last[1]}: '{what}' has no value: FEMNET leaves it unset, taken as "
                              f"{f.unset!r}")
            return Value(f.unset, r.last[1])
        v = r.integer(what, f.minimum) if f.integer else r.number(what, f.check)
        r.stray_ignored = f.unused
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


def _design_plane_axis(r, v, f, prefix):
    """FEMNET's design plane is the plane its mesher draws a panel in (1, 2, 3: normal to x, y, z): the mesher
    permutes the coordinates to draw and writes its mesh back in the file's order, so x y z are world
    coordinates whatever the axis, and jaxnet's mesher, which meshes in 3-D, needs nothing of it."""
    if v.value not in (1, 2, 3):
        raise r.error(f"{prefix}{f.what} {v.value}: an axis is 1, 2 or 3 (x, y or z)", v.line)


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
                     r"plane normal (to|yo) [xyz] axis",
                     r"calcul dans le plan perpendiculaire a [xyz] cad coordonnees [xyz] cstes",
                     integer=True, then=_design_plane_axis)
PANELS_NUMBER = field("panels", "panels number", r"panels number", r"diamond panel nb", r"nombre de panneaux", integer=True, minimum=0)
HEXAGONAL_PANELS_NUMBER = field("hexa", "hexagonal panels number", r"hexagonal panels number",
                                r"nombre de panneaux hexagonaux", integer=True,
                                minimum=0)
CABLES_NUMBER = field("cables", "cables number", r"cables number", r"cable nb", r"nombre d ?elements", integer=True, minimum=0)
SLIDING_CABLES_NUMBER = field("sliding", "sliding cables number", r"sliding cables number", r"nombre de coulisses?",
                              r"nb sliding ropes", integer=True, minimum=0,
                              then=_only_zero("sliding cables are not supported by this reader"))
LINKS_NUMBER = field("links", "links number", r"links number", r"nombre de liaisons?", r"links nb", integer=True, minimum=0)
NODE_TYPES_NUMBER = field("types", "number of types of nodes", r"number of types of nodes",
                          r"type of node in the structure", r"node types nb", r"nombre de types de noeuds? dans la structure", integer=True, minimum=1)

#: how messages name the parts of each kind (links and the meshing order name them by these keys)
PART_NAMES = {"pa": "panel", "ha": "hexagonal panel", "el": "cable"}

#: labels that open a part, or an entry of a list, read by that part's parser (messages name the part)
HEADINGS = {
    "panel": spelled(r"p?panel", r"panneau"),                                   # then its number
    "contour": spelled(r"nodes of the contour.*", r"nb x y z u v ty ty", r"points du contour.*"),                # then the corners: no x y z U V type side-type
    "cable": spelled(r"cable", r"element", r"el", r"ca", r"e"),                                   # then its number
    "cable ends": spelled(r"extremities no x y z type", r"description des extremites( no x y z no_type)?", r"no x y z no_type", r"d",
                          r"desc", r"ex", r"e"),          # then the two ends: no x y z type
    "link": spelled(r"nb_? ?pts?", r"number of (points|corners)", r"link( \d+)?", r"nb"),  # then its number of points
    "link structure": spelled(r"pa", r"panel", r"ha", r"he", r"hexa", r"el", r"element", r"co", r"wi", r"winch"),
    "link corner": spelled(r"nd", r"no", r"node", r"corner", r"extremity"),
    "meshing order": spelled(r"meshing order", r"ordre de maillage", r"numerical meshing ordering"),
    "meshing order entry": spelled(r"el", r"pa", r"ha", r"he"),
    "node type": spelled(r"no du type", r"type", r"type nb"),                 # then its number
}

# -- materials (prefixed by the part's name: "panel 1: ", "hexagonal panel 1: ", "cable 1: ") ----------------
PANEL_CORNERS = field("corners", "number of nodes around", r"number of nodes around", r"nombre de points du contour", integer=True, minimum=3)
#: a traction stiffness of 0 leaves the twines or the cable holding nothing (a mechanism): refused at its line
TRACTION_STIFFNESS = field("ea", "traction stiffness", r"traction stiffness( \(n\))?", r"kt( \(n\))?", r"rt",
                           r"raideur traction( \(n\))?", check=">0")
COMPRESSION_STIFFNESS = field("eac", "compression stiffness", r"compression stiffness( \(n\))?", r"kc( \(n\))?",
                              r"rc", r"raideur compression( \(n\))?", check=">=0")
OPENING_STIFFNESS = field("opening", "mesh opening stiffness", r"mesh opening stiffness( \(n\.m/rad\))?",
                          r"raideur ouverture( \(n\.m/rad\))?", check=">=0")
UNSTRETCHED_LENGTH = field("l0", "unstretched length", r"unstretched length( \(m\))?", r"l", r"le", r"l0 \(m\)",
                           r"(maille|longueur) au repos( \(m\))?", check=">0")
VOLUMIC_MASS = field("density", "volumic mass", r"volumic mass( \(kg/m3\))?", r"vm", r"mv", r"de", r"m", r"rho \(kg/m3\)",
                     r"masse volumique( \(kg/m3\))?", check=">=0")
DIAMETER = field("diameter", "hydrodynamic diameter", r"hydrodynamic diameter( \(m\))?", r"d", r"di", r"d0 \(m\)",
                 r"diametre hydrodynamique( \(m\))?", check=">=0")
KNOT_SIZE = field("knot", "knot size", r"knot size( \(m\))?", r"largeur noeud", check=">=0")
NORMAL_CD = field("cd", "normal Cd", r"normal cd", r"cd", r"cd normal", r"coefficient de trainee normal", r"k_train_norm",
                  check=">=0", unset=0.0)
TANGENTIAL_CD = field("f", "tangential Cd", r"tangential cd", r"f", r"cf", r"cd tangentiel", r"k_train_tang",
                      r"coefficient de trainee tangent", check=">=0", unset=0.0)
MESHING_STEP = field("step", "meshing step", r"meshing step( \(m\))?", r"pas du maillage( \(m\))?", check=">0")
INTERNAL_NODES_TYPE = field("inner_type", "type of internal nodes", r"type of internal nodes", r"ty", r"t", r"type n",
                            r"type des noeuds interieurs", integer=True,
                            minimum=1)
MESHING_TYPE = field("mesh_type", "meshing type", r"meshing type", r"type de maillage", integer=True)

#: a diamond panel's material, after its corners
PANEL_MATERIAL = (TRACTION_STIFFNESS, COMPRESSION_STIFFNESS, OPENING_STIFFNESS, UNSTRETCHED_LENGTH, VOLUMIC_MASS,
                  DIAMETER, KNOT_SIZE, NORMAL_CD, TANGENTIAL_CD, MESHING_STEP, INTERNAL_NODES_TYPE, MESHING_TYPE)
#: a hexagonal panel's material, after its corners and one skipped line: three values (twine families l, m, n)
#: for the stiffnesses, lengths and diameters; no opening stiffness, no knot size
HEXAGONAL_PANEL_MATERIAL = (
    field("ea", "traction stiffness l m n", r"traction stiffness( l,? ?m,? ?n)?( \(n\))?", r"kt", check=">0",
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
                  field("n_bars", "number of bars", r"bars number", r"nb", r"n", r"bn", r"b", r"nb barres?", integer=True, minimum=1,
                        then=_at_most_max_bars),
                  INTERNAL_NODES_TYPE)

#: a node type, after its number (prefixed "node type N: "); keys are :class:`DonNodeType`'s attributes.
#: The X Y Z of numbers are on one line; the flags and senses are not checked so
NODE_TYPE = (
    field("mass", "mass", r"mass(es)?( x[,.]y[,.]z)?( \(kg\))?", check=">=0", values=XYZ, one_line=True),
    field("added_mass", "added mass", r"added mass( x[,.]y[,.]z)?( \(kg\))?", r"masses ajoutees x[,.]y[,.]z( \(kg\))?",
           check=">=0", values=XYZ, one_line=True),
    field("length", "length", r"length x[,.]y[,.]z( \(m\))?", r"size( \(m\))?", r"longueurs x[,.]y[,.]z( \(m\))?",
          values=XYZ, one_line=True),
    field("drag_coefficient", "drag coefficient", r"drag coefficient x[,.]y[,.]z", r"drag coef\.",
          r"coef\. trainee x[,.]y[,.]z", check=">=0", values=XYZ, one_line=True),
    field("force", "external force", r"external forces?( x[,.]y[,.]z)?( \(n\))?",
          r"efforts exterieurs x[,.]y[,.]z( \(n\))?", values=XYZ, one_line=True),
    field("fixed", "displacement", r"displacement( x[,.]y[,.]z)?", r"deplacement x[,.]y[,.]z", check="0 or 1", integer=True, values=XYZ),
    field("limit", "limits", r"limits x[,.]y[,.]z( \(m\))?", r"limit( \(m\))?", r"limites x[,.]y[,.]z( \(m\))?",
          values=XYZ, one_line=True),
    field("sense", "limits sense", r"limits sens(e)? x[,.]y[,.]z", r"sens of limit", r"sens des limites x[,.]y[,.]z",
          integer=True, values=XYZ),
    field("symmetry", "symmetry", r"sym(m)?etry( x[,.]y[,.]z)?", r"symetrie x[,.]y[,.]z", check="0 or 1", integer=True, values=XYZ),
)

#: FEMNET's solver settings (statics, then dynamics; ``lectureDo4.c``)
NUMERICS = (
    field("divisor", "divisor", r"divisor( \(s\))?", r"diviseur( \(s\))?", unused=True),
    field("threshold", "convergence threshold", r"convergence threshold( \(n\))?",
          r"seuil ?(de )?convergence( \(n\))?", check=">0"),
    field("max_step", "displacement limit for each iteration", r"displacement limit for each iteration( \(m\))?",
          r"limite de deplacement a chaque iteration( \(m\))?",
          r"deplacement", check=">0"),
    field("max_iter", "maximal number of iterations", r"maximal number of iterations",
          r"(nombre )?maximum d'iterations", r"nbmaxiterations", integer=True, minimum=1),
    field("dt", "dynamic time step", r"dynamic: time step( \(s\))?", r"dynamic: pas de temps du calcul( \(s\))?",
          r"dynamic: pascalcul"),
    field("record_dt", "dynamic record time step", r"dynamic: record time step( \(s\))?",
          r"dynamic: pas de temps de stockage( \(s\))?",
          r"dynamic: passtockage"),
    field("record_start", "dynamic beginning time of record", r"dynamic: beginning time of record( \(s\))?",
          r"dynamic: temps de debut du stockage( \(s\))?",
          r"dynamic: debutstockage"),
    field("record_end", "dynamic end time of record and calculation",
          r"dynamic: end time of record and calculation( \(s\))?",
          r"dynamic: temps de fin du calcul et du stockage( \(s\))?",
          r"dynamic: finstockage"),
)

#: the current (direction in deg from x towards y, speed in m/s) and the waves (s, m, deg, depth m)
OCEAN = (
    field("current_direction", "current direction", r"current direction( \(deg\))?", r"direction( \(deg\))?"),
    field("current_speed", "current speed", r"current speed( \(m/s\))?", r"vitesse( \(m/s\))?", check=">=0"),
    field("wave_period", "wave period", r"wave period( \(s\))?", r"periode( \(s\))?"),
    field("wave_height", "wave height", r"wave height( \(m\))?", r"hauteur( \(m\))?", check=">=0"),
    field("wave_direction", "wave direction", r"wave direction relatively x( \(deg\))?", r"direction",
          r"direction par rapport a x( \(deg\))?"),
    field("depth", "depth", r"depth( \(m\))?", r"hauteur d'eau( \(m\))?", check=">=0"),
)

#: the catch: the modelled part's volume (m³), its accuracy, its drag coefficient
CATCH = (
    field("catch_volume", "catch volume", r"volume( \(m3\))?", check=">=0"),
    field("catch_accuracy", "accuracy on the catch volume", r"accuracy on this volume( \(m3\))?",
          r"precision sur ce volume", r"seuil \(m3\)", check=">=0"),
    field("catch_cd", "drag coefficient of the catch", r"drag coefficient on this volume",
          r"coefficient de trainee sur ce volume", r"cd", check=">=0"),
)

#: the sea bed (``fond.c``), kept with the ocean: friction coefficient, penalty stiffness (N/m)
SEA_BED = (
    field("bottom_friction", "wearing coefficient on the bottom", r"wearing coefficient on the bottom",
          r"coefficient de frottement du sol", r"drag coef\.", check=">=0"),
    field("bottom_stiffness", "stiffness of the insertion in the sea bottom",
          r"stiffness of the insertion in the sea bottom( \(n/m\))?",
          r"raideur d'enfoncement dans le sol( \(n/m\))?",
          r"stiffness \(n/m\)", check=">=0"),
)

#: FEMNET's text outputs: the counts of its lists of figures to print after the solve, each count followed by its
#: entries (:data:`TEXT_OUTPUT_ENTRIES`)
TEXT_OUTPUTS = (
    field("distances", "distances number", r"distances number", r"nombre de distances?", r"distance nb", integer=True, minimum=0),
    field("forces", "forces number", r"forces number", r"nombre d ?efforts?", r"force nb", integer=True, minimum=0),
    field("tensions", "tensions number", r"tensions number", r"nombre de tensions?", r"tension nb", integer=True, minimum=0),
    field("sliding_tensions", "sliding tensions number", r"sliding tensions number",
          r"nombre de tensions? coulisses?", r"sliding rope tension nb", integer=True, minimum=0),
    field("positions", "positions number", r"positions number", r"nombre de positions?", r"position nb", integer=True, minimum=0),
)


def _after_comment(*alternatives):
    """A label that follows a text output's comment (``comment: #words#``): the comment's text may come first on the
    label's line."""
    return spelled(*(rf"(#.*#)? ?(?:{a})" for a in alternatives))


#: the heading of a text output's entry and its comment (``Distance: 1 comment: #Boat to door#``), which FEMNET
#: prints beside the figure
TEXT_OUTPUT_HEADING = spelled(r"(distance|force|effort|tension|sliding tension|tension coulisse|position)( numero)?",
                              r"numero")
TEXT_OUTPUT_COMMENT = spelled(r"comment(aire)?")
#: the fields of each kind of text output's entries, after its comment: (key, label, what)
TEXT_OUTPUT_ENTRIES = {
    "distances": (("node_1", _after_comment(r"no (noeud )?global 1"), "first global node"),
                  ("node_2", _after_comment(r"no (noeud )?global 2"), "second global node")),
    "forces": (("node", _after_comment(r"no (noeud )?global"), "global node"),
               ("axis", _after_comment(r"axe", r"axis"), "axis")),
    "tensions": (("cable", _after_comment(r"cable", r"element"), "cable"),
                 ("node", _after_comment(r"extremity node", r"no (noeud )?extremite"), "extremity node")),
    "sliding_tensions": (("cable", _after_comment(r"(sliding )?cable", r"coulisse"), "sliding cable"),
                         ("node", _after_comment(r"extremity node", r"no (noeud )?extremite"), "extremity node")),
    "positions": (("node", _after_comment(r"no (noeud )?global"), "global node"),
                  ("axis", _after_comment(r"axe", r"axis"), "axis")),
}
TEXT_OUTPUT_DECIMALS = _after_comment(r"decimal nb", r"nombre de decimales?")


@dataclasses.dataclass
class TextOutput:
    """One of FEMNET's text outputs: a figure it prints after the solve. ``kind``: "distances" (between two of its
    global nodes, m), "forces" (the force on a global node along an axis, N), "tensions" (of a cable at one of its
    extremity nodes, N), "sliding_tensions", "positions" (of a global node along an axis, m); ``values``: its
    fields (:data:`TEXT_OUTPUT_ENTRIES`, integers: FEMNET's global node numbers, axes 1-3, cable numbers);
    ``comment``: the words FEMNET prints beside it; ``decimals``; ``line``."""

    kind: str
    values: dict
    comment: str
    decimals: int
    line: int


#: FEMNET's display switches (integers, read and unused)
DISPLAYS = (
    field("show_forces", "structure forces display", r"structure forces display", r"affichage de l ?effort sur la structure",
          r"force on structure", integer=True),
    field("show_diameter", "catch diameter display", r"catch diameter display", r"affichage du diametre de la prise", r"catch diameter", integer=True),
    field("show_thickness", "catch thickness display", r"catch thickness display", r"affichage de l ?epaisseur de la prise",
          r"catch thi(c)?kness", integer=True),
    field("show_volume", "catch volume display", r"catch volume display", r"affichage du volume de la prise", r"catch volume", integer=True),
    field("show_surface", "filtrated surface display", r"filt(e|ra)ted surface display", r"affichage de la surface filtree",
          r"swept area", integer=True),
    field("show_speed", "speed display", r"speed display", r"affichage de la vitesse", r"water speed", integer=True),
)


# -- the free-order tail: commands ----------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Command:
    """A line ``input NAME v1 ... vN`` (it changes the case) or ``output NAME ...`` (it only prints or draws).

    ``n_values``: the numbers that follow the name (an int, or a tuple of the counts allowed); ``check``: None, or
    check(values) giving the message that refuses them (None when they are accepted); ``use``: what a static
    run does with it: "model" (the reader maps it), "dynamic" (it acts in FEMNET's dynamics only: kept in the
    case, left out of a static run, which says so), "ignored" (FEMNET itself does nothing with it), or
    "unsupported" (refused, ``reason`` saying why); ``per_panel``: the first value names a panel, the command
    may be given once per panel and :attr:`DonFile.inputs` keeps it as "NAME PANEL"; ``repeatable``: the command may
    be given on several lines (one per cable, per pair of cables), each an :class:`Occurrence`, kept in the file's
    order (the parsed file's ``inputs[name]`` is then a Value of the tuple of them, at the first one's line)."""

    kind: str
    name: str
    n_values: int | tuple = 0
    check: Callable | None = None
    use: str = "model"
    reason: str = ""
    table: tuple | None = None    # (rows, index of the value giving each row's length): a table on the next lines
    repeatable: bool = False
    per_panel: bool = False   # its first value is a panel: one line per panel, kept as "NAME PANEL"

    @property
    def counts(self):
        return self.n_values if isinstance(self.n_values, tuple) else (self.n_values,)


class Occurrence(NamedTuple):
    """One line of a repeatable command: its numbers and its line."""

    values: tuple
    line: int


def _positive_water_density(values):
    return None if values[0] > 0 else f"'input water_density' must be > 0, got {values[0]!r}"


def _sphere_element(values):
    cable, count, diameter, buoyancy = values[:4]
    if len(values) == 5 and not values[4] > 0:
        return f"'input sphere_element2': the length the spheres are spread over must be > 0 m, got {values[4]!r}"
    if cable != int(cable) or cable < 1 or count != int(count) or count < 1:
        return f"'input sphere_element CABLE COUNT D B': cable and count must be integers >= 1, got {values[:2]}"
    if not diameter > 0:
        return f"'input sphere_element': the spheres' diameter must be > 0 m, got {diameter!r}"
    return None


def _window(values):
    mode, new_type = values[0], values[-1]
    # FEMNET's modes (manual, index): 1-6 one bound on one axis, 7-9 an interval on one axis, 10-12 on two, 13
    # on the three; the values between are the bounds
    bounds = {1: 1, 2: 1, 3: 1, 4: 1, 5: 1, 6: 1, 7: 2, 8: 2, 9: 2, 10: 4, 11: 4, 12: 4, 13: 6}
    if mode not in bounds:
        return f"'input type_noeud_XYZ_SUPINF': mode {mode!r} is not one of FEMNET's 1-13"
    if len(values) != bounds[mode] + 2:
        return (f"'input type_noeud_XYZ_SUPINF {int(mode)}' takes {bounds[mode]} bound(s) then a node type, got "
                f"{len(values) - 2} bound(s)")
    if new_type != int(new_type) or new_type < 1:
        return f"'input type_noeud_XYZ_SUPINF': the node type must be an integer >= 1, got {new_type!r}"
    return None


def _translation(values):
    first, last = values[1], values[2]
    if first != int(first) or last != int(last) or not 1 <= first <= last:
        return f"a translation's parts FIRST LAST must be integers with 1 <= FIRST <= LAST, got {values[1:]}"
    return None


_UNSUPPORTED = "a FEMNET feature jaxnet does not model yet"


def _netting2ropes_values(values):
    """``input netting2ropes PANEL PERIOD GAP_U GAP_V ACCURACY BARS`` (phobos ``chargement_don.c``, which reads
    PANEL, PERIOD and BARS as integers): a panel number, a period of >= 1 twines, two finite gaps (fractions of
    the period), an accuracy >= 0 (twines) and >= 1 bars per period dividing the period (FEMNET spaces the nodes
    int(PERIOD / BARS) twines apart but gives each bar PERIOD / BARS twines of rest length)."""
    panel, period, _gap_u, _gap_v, accuracy, bars = values
    for what, v in (("panel", panel), ("period", period), ("number of bars", bars)):
        if v != int(v) or v < 1:
            return f"'input netting2ropes': the {what} must be an integer >= 1, got {v!r}"
    if accuracy < 0:
        return f"'input netting2ropes': the accuracy must be >= 0 (twines), got {accuracy!r}"
    if int(period) % int(bars):
        return (f"'input netting2ropes': the period ({int(period)} twines) must be a multiple of the number of bars "
                f"({int(bars)}): FEMNET spaces their nodes int(period / bars) twines apart")
    return None


def _tarp_panel(values):
    """``input tarp PANEL`` (FEMNET's ``chargement_don.c``: ``panneau[PANEL].tarp = 1``): a diamond panel number."""
    return None if values[0] == int(values[0]) and values[0] >= 1 else \
        f"'input tarp': the panel number must be a whole number >= 1, got {values[0]!r}"


def _meshing_uv(values):
    """``input Meshing_UV PANEL NU NV`` (phobos ``chargement_don.c``: ``panneau[PANEL].pas_U``, ``pas_V``, read as
    floats): a diamond panel number, then two numbers of meshes > 0 (FEMNET takes a step 0 along U for no command,
    and divides by the one along V)."""
    panel, nu, nv = values
    if panel != int(panel) or panel < 1:
        return f"'input Meshing_UV': the panel number must be a whole number >= 1, got {panel!r}"
    if not (nu > 0 and nv > 0):
        return f"'input Meshing_UV' {panel:g}: the numbers of meshes along U and V must be > 0, got {nu!r} and {nv!r}"
    return None


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


def _towing(values):
    """``input speed_type_node2 TYPE K``: a node type and K >= 2 times in the table that follows (FEMNET's manual,
    "Bottom seine": the speeds vary linearly between times; its times are checked where the table is mapped,
    :func:`jaxnet.io.femnet.motion.towing_of`)."""
    node_type, k = values[0], values[1]
    if node_type != int(node_type) or node_type < 1 or k != int(k) or k < 2:
        return f"'input speed_type_node2 TYPE K': TYPE must be a node type and K >= 2 times, got {values[:2]}"
    return None


def _wave_model(values):
    """``input wave_model N`` (FEMNET's manual, "Waves"): 1 Airy, 2 Stokes second order (intermediate and deep
    water), 3 Stokes third order in deep water (used by no worked case)."""
    n = values[0]
    return None if n in (1, 2, 3) else \
        f"'input wave_model': the model must be 1 (Airy), 2 (Stokes second order) or 3 (Stokes third order in " \
        f"deep water), got {n!r}"


def _drag_forces_type(values):
    """``input drag_forces_type N``: FEMNET's netting drag law, one of its 1 to 4 (``chargement_don.c``'s comments;
    its solver does nothing for another value, which a line asking for a law does not mean)."""
    n = values[0]
    return None if n in (1, 2, 3, 4) else f"'input drag_forces_type': the law must be 1, 2, 3 or 4, got {n!r}"


def _catch2_volume(values):
    """``input catch2_volume V N P1 .. PN`` (FEMNET's ``chargement_don.c``, ``catch2_volume.c``): a catch of V m³
    (> 0) held by the N diamond panels listed (whole numbers >= 1), N >= 1 and exactly N of them."""
    what = "'input catch2_volume'"
    volume, count, panels = values[0], values[1], values[2:]
    if not (np.isfinite(volume) and volume > 0):
        return f"{what}: the catch's volume must be > 0 (m³), got {volume!r}"
    if count != int(count) or count < 1 or len(panels) != count:
        return (f"{what} {volume:g}: the number of panels must be a whole number >= 1 followed by that many panel "
                f"numbers, got {count!r} and {len(panels)} number(s)")
    bad = [p for p in panels if p != int(p) or p < 1]
    if bad:
        return f"{what} {volume:g}: a panel number must be a whole number >= 1, got {bad[0]!r}"
    return None


def _catch_gravity(values):
    """``input catch_gravity RHO_C``: the gravity catch's density, finite and > 0 (kg/m³; FEMNET reads 0 as no
    gravity catch, which a line asking for one does not mean)."""
    rho = values[0]
    return None if np.isfinite(rho) and rho > 0 else f"'input catch_gravity': the catch's density must be > 0 (kg/m³), got {rho!r}"


COMMANDS = (
    Command("input", "auto_convergence"),
    Command("input", "convergence_parameters", 3),
    Command("input", "link", 1),            # FEMNET's automatic links: points closer than this (m) are one node
    Command("input", "moving_bottom"),      # the bottom slides at the current's speed: its friction acts (fond.c)
    Command("input", "water_density", 1, _positive_water_density),   # kg/m³
    # spherical floats along a cable: CABLE COUNT DIAMETER (m) BUOYANCY (N each, net of their weight), Cd 0.6
    Command("input", "sphere_element", 4, _sphere_element),
    # the same spread over a length (m) of the cable, its fifth value (FEMNET's chargement_don.c; not in its manual)
    Command("input", "sphere_element2", 5, _sphere_element),
    # re-type the nodes inside a window of coordinates: MODE BOUNDS... TYPE (manual, index)
    Command("input", "type_noeud_xyz_supinf", (3, 4, 6, 8), _window),
    # translations of the design: DISTANCE (m) FIRST LAST cables (ele) or panels (pan), along x, y or z
    *(Command("input", f"add_{axis}_{part}", 3, _translation) for axis in "xyz" for part in ("ele", "pan")),
    # FEMNET's dynamics only: winches, towing speeds, the wave model (kept for a dynamic run)
    # (their time tables follow on the next lines: times, speeds, hauled ends; times, speeds along x, y, z)
    Command("input", "hauling_cable4", 4, use="dynamic", table=(3, -1)),
    Command("input", "hauling_cable6", 4, use="dynamic", table=(3, -1)),
    # towing speeds of a node type: TYPE K, then its time table (times; speeds along x, y, z), run in dynamics
    Command("input", "speed_type_node2", 2, _towing, table=(4, 1)),
    # the waves' theory (jaxnet.io.femnet.surroundings.environment_of): 1 Airy, 2 Stokes second order; felt in dynamics
    Command("input", "wave_model", 1, _wave_model),
    # FEMNET's current code has no handler for it (its reader skips the line)
    Command("input", "node_position", 1, use="ignored"),
    *(Command("input", name, tuple(range(0, 12)), use="unsupported", reason=reason) for name, reason in (
        ("spheric_limit", "a spherical limit: " + _UNSUPPORTED),
        ("deck", "a deck: " + _UNSUPPORTED))),
    # the netting's drag law: 1 Morison, 2 Zhan, 3 drop pressure, 4 Aarnes (jaxnet.terms.drag's docstring)
    Command("input", "drag_forces_type", 1, _drag_forces_type),
    # an impermeable panel (a tarp, jaxnet.terms.tarp): PANEL, loaded by the catch's pressure instead of drag
    Command("input", "tarp", 1, _tarp_panel, per_panel=True),
    # a panel meshed on a lattice of mesh diagonals: PANEL NU NV (meshes along U, along V; Net.panel(lattice=...));
    # FEMNET's 'Meshing_uv' (small uv: along the twines) is another command, refused by the reader
    Command("input", "meshing_uv", 3, _meshing_uv, per_panel=True),
    # a panel meshed as numerical twines (bars): PANEL PERIOD GAP_U GAP_V ACCURACY BARS (jaxnet.io.femnet.twines)
    Command("input", "netting2ropes", 6, _netting2ropes_values, per_panel=True),
    # cable bending (jaxnet.terms.cable_bending): EI (N·m²) of a cable; two cables welded at an angle (degrees)
    Command("input", "ei_flexion_cable", 2, _ei_flexion_cable, repeatable=True),
    Command("input", "link_flexion_elem2", 3, _link_flexion_elem2, repeatable=True),
    # the gravity catch (jaxnet.terms.gravity_catch): the catch's density (kg/m³) weighing on a bag out of the water
    Command("input", "catch_gravity", 1, _catch_gravity),
    # a catch held by listed diamond panels (jaxnet.terms.panel_catch): VOLUME (m³) N PANEL1 .. PANELN, one line each
    Command("input", "catch2_volume", tuple(range(3, 3 + 64)), _catch2_volume, repeatable=True),
)
INPUTS = {c.name: c for c in COMMANDS if c.kind == "input"}
#: FEMNET's output commands (``output NAME ...``) print figures or draw: all are read and none changes the case;
#: these are the ones whose figures jaxnet's result also gives (drags of the parts, the catch's)
OUTPUTS = ("element_drag", "surface_drag", "catch_drag", "bottom_drag", "panel_drag", "cable_drag", "node_drag",
           "energy", "tension", "tensions")


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
    def box_volume(self):
        """The volume (m³) of the type's box, |L_x L_y L_z|: FEMNET floats it (``flotteur2.c``: rho g L_x L_y times
        its immersed height, along z), so wholly immersed it is a buoyancy rho g V."""
        lx, ly, lz = (v.value for v in self.length)
        return abs(lx * ly * lz)

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
    inputs: dict          # input command name -> Value (its number, or tuple of numbers; 1.0 without any): the last
    outputs: list         # output commands, as written (FEMNET's print and drawing commands)
    hexagonal: list = dataclasses.field(default_factory=list)   # hexagonal panels (DonPanel, hexagonal=True)
    links: list = dataclasses.field(default_factory=list)       # DonLink
    orientation: int = 3                                        # the design plane's normal axis (drawing only)
    text_outputs: list = dataclasses.field(default_factory=list)  # TextOutput
    commands: list = dataclasses.field(default_factory=list)      # every input command: (name, values, line)
    warnings: list = dataclasses.field(default_factory=list)      # read as FEMNET would, worth saying (file:LINE:)


def twine_coordinates(UV):
    """FEMNET's mesh coordinates (U, V) (meshes along the diagonals) -> twine coordinates (u, v) = (U + V, V - U)
    (phobos ``chargement_don.c``; see the package's docstring, "Twine coordinates")."""
    UV = np.asarray(UV, dtype=float)
    return np.stack([UV[..., 0] + UV[..., 1], UV[..., 1] - UV[..., 0]], axis=-1)
