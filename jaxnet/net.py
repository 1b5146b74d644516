"""Describe a net the way a designer does, and build it into a :class:`~jaxnet.scene.Scene`.

A :class:`Net` holds panels (polygons whose corners have start positions x, y, z and twine coordinates
U, V — as FEMNET's ``.don`` files describe them), cables, seams and what is attached to nodes::

    twine = Twine(l0=0.02, ea=1000.0, diameter=0.002)
    net = Net()
    p = net.panel("wall", corners=[(0, 0, 0, 0, 0), (1, 0, 0, 25, -25), (1, 0, 1, 50, 0), (0, 0, 1, 25, 25)],
                  twine=twine, step=0.1)
    net.cable("headline", along=p.side(2), rope=Rope(ea=5e4, diameter=0.008))
    net.fix(p.side(2))
    scene = net.build()

A panel may instead be meshed as numerical twines, chains of bars each standing for ``period`` real twines
(``net.panel(..., twines=NumericalTwines(period=10, bars=2))``, :mod:`jaxnet.mesh.twines`; FEMNET's ``input
netting2ropes``): then every side needs a cable along it, and no seam.

Joining rules (decided in :meth:`Net.build`):
  * Panel corners and cable ends at the same start position (within ``merge_tolerance``) are one node.
  * ``net.seam(a.side(i), b.side(j))`` makes two panel borders share their nodes: both sides are divided
    into the same number of segments (the larger of their defaults), also when the two panels have
    different mesh counts along the seam (50 meshes joined to 45, book Fig. 4.5): each panel keeps its
    own twine coordinates at the shared nodes. The direction is matched from the start positions.
  * ``net.cable(..., along=p.side(k))`` sews a rope along a border: one bar per border segment, rest
    length of each bar its share of the rope length (by default the border's start length).
  * A cable whose rope has a bending stiffness (``Rope(bending_stiffness=EI)``) is straight at rest: every
    node between two of its bars is a bending joint. ``net.cable_joint(a, b, neutral_angle)`` welds two cables
    where they share a node: the angle between them resists change from ``neutral_angle``
    (:mod:`jaxnet.terms.cable_bending`).

What is attached to nodes: ``attach`` (and ``sinker``, ``float``) *shares* a mass, volume, force or drag
area among the nodes of a reference and adds up over calls; ``body`` (a box-shaped body with a drag per
axis) and ``limit`` (a floor or ceiling per axis, the sea bed) are FEMNET's node-type properties, *given* to
every node of a reference, a later call replacing an earlier one on the nodes they share.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np

from jaxnet import materials
from jaxnet.materials import HexTwine, Rope, Twine
from jaxnet.mesh.twines import NumericalTwines
from jaxnet.scene import Environment, Scene, SceneError


@dataclasses.dataclass(frozen=True)
class Layout:
    """Where :meth:`Net.build` put each part of the description in the scene it returned (``Net.layout``),
    for maps from the description to the scene (:mod:`jaxnet.design.space`). Node indices are the scene's.

    meshes: panel name -> its :class:`~jaxnet.mesh.panel.PanelMesh` (weights, triangles, side nodes);
      twines: panel name -> its material (:class:`Twine` or :class:`HexTwine`).
    panel_nodes: panel name -> (n,) scene node of each mesh node (merged nodes share one).
    cable_nodes: cable name -> (k,) scene nodes from its start to its end; cable_sides: cable name -> the
      panel side it is sewn along (cables sewn along a side only).
    fixed: per :meth:`Net.fix` call, (reference, scene nodes, axes as 3 bools).
    attached: per :meth:`Net.attach` call (sinkers and floats included), the scene nodes sharing its amounts;
      attached_where: the reference of each call.
    sinkers: (attach call index, mass kg, density kg/m³) per :meth:`Net.sinker` call; floats: (attach call
      index, buoyancy N, gravity m/s², water density kg/m³, own mass kg) per :meth:`Net.float` call.
    """

    meshes: dict
    twines: dict
    panel_nodes: dict
    cable_nodes: dict
    cable_sides: dict
    fixed: tuple
    attached: tuple
    attached_where: tuple
    sinkers: tuple
    floats: tuple


# -- references to places in a net that is not built yet ------------------------------------------


@dataclasses.dataclass(frozen=True)
class Corner:
    """Corner ``index`` of a panel."""

    panel: str
    index: int


@dataclasses.dataclass(frozen=True)
class Side:
    """Side ``index`` of a panel: from corner ``index`` to corner ``index + 1`` (cyclic)."""

    panel: str
    index: int


@dataclasses.dataclass(frozen=True)
class Nearest:
    """The node of a panel nearest to a point (x, y, z) of the start geometry (m)."""

    panel: str
    point: tuple


@dataclasses.dataclass(frozen=True)
class CableEnd:
    """End 0 (start) or 1 (end) of a cable."""

    cable: str
    end: int


@dataclasses.dataclass(frozen=True)
class CableNodes:
    """All nodes of a cable."""

    cable: str


@dataclasses.dataclass(frozen=True)
class PanelRef:
    name: str

    def corner(self, k):
        return Corner(self.name, int(k))

    def side(self, k):
        return Side(self.name, int(k))

    def nearest(self, x, y, z):
        """The panel's node nearest to the start position (x, y, z) (m), e.g. for a sinker at its centre."""
        return Nearest(self.name, (float(x), float(y), float(z)))


@dataclasses.dataclass(frozen=True)
class CableRef:
    name: str

    @property
    def start(self):
        return CableEnd(self.name, 0)

    @property
    def end(self):
        return CableEnd(self.name, 1)

    @property
    def nodes(self):
        return CableNodes(self.name)


def describe_reference(ref, short: bool = False) -> str:
    """A node reference in words: for messages, "corner 7 of panel 'wall'", "side 2 of panel 'wall'", "end 1
    of cable 'rope'", "the point (1.0, 0.0, -2.0)", ...; ``short``, a name of the place (a design space's keys:
    "wall corner 7", "wall side 2", "rope end", "(1, 0, -2)")."""
    if isinstance(ref, Corner):
        return f"{ref.panel} corner {ref.index}" if short else f"corner {ref.index} of panel '{ref.panel}'"
    if isinstance(ref, Side):
        return f"{ref.panel} side {ref.index}" if short else f"side {ref.index} of panel '{ref.panel}'"
    if isinstance(ref, Nearest):
        if short:
            return f"{ref.panel} near ({ref.point[0]:g}, {ref.point[1]:g}, {ref.point[2]:g})"
        return f"the node of panel '{ref.panel}' nearest {tuple(float(v) for v in ref.point)}"
    if isinstance(ref, CableEnd):
        if short:
            return f"{ref.cable} {'start' if ref.end == 0 else 'end'}"
        return f"end {ref.end} of cable '{ref.cable}'"
    if isinstance(ref, CableNodes):
        return ref.cable if short else f"cable '{ref.cable}'"
    if isinstance(ref, PanelRef):
        return ref.name if short else f"panel '{ref.name}'"
    if isinstance(ref, CableRef):
        return ref.name if short else f"cable '{ref.name}'"
    if short:
        return "(" + ", ".join(f"{v:g}" for v in np.asarray(ref, dtype=float).ravel()) + ")"
    try:
        return f"the point {tuple(float(v) for v in ref)}"
    except (TypeError, ValueError):
        return repr(ref)


@dataclasses.dataclass
class PanelDescription:
    name: str
    corners: np.ndarray  # (C, 5): x y z U V
    twine: Twine
    step: float
    twines: NumericalTwines | None = None   # meshed as numerical twines (bars) rather than triangles
    lattice: tuple | None = None   # (NU, NV) meshes: nodes on that lattice of mesh diagonals (mesh_panel)


@dataclasses.dataclass
class CableDescription:
    name: str
    start: object
    end: object
    rope: Rope
    length: float | None
    n_bars: int | None
    along: Side | None


class Net:
    """A net under construction: panels, cables, seams, fixings and attachments. See the module docstring.

    merge_tolerance: corners and cable ends closer than this (m) at the start are one node.
    """

    def __init__(self, environment: Environment | None = None, merge_tolerance: float = 1e-6):
        self.environment = environment or Environment()
        self.merge_tolerance = merge_tolerance
        self.main_catch = None
        self.panel_catches: list[tuple] = []   # (volume m³, panel names, centre m or None), in call order
        self.panel_catch_options = None   # (drag_coefficient, symmetry, axis or None): the last call's
        self.enclosure = None
        self.panels: dict[str, PanelDescription] = {}
        self.cables: dict[str, CableDescription] = {}
        self.seams: list[tuple[Side, Side]] = []
        self.cable_joints: list[tuple[str, str, float, float | None]] = []   # (cable a, cable b, angle rad, EI)
        self.fixings: list[tuple[object, tuple[bool, bool, bool]]] = []
        self.symmetry_planes: list[tuple[int, float, bool]] = []   # (axis, position m, hold its nodes)
        self.attachments: list[tuple[object, float, float, np.ndarray, float, float]] = []
        self.bodies: list[tuple[object, np.ndarray, np.ndarray]] = []   # (where, sizes m, Cd), in call order
        self.limits: list[tuple[object, np.ndarray, np.ndarray]] = []   # (where, limits m, senses), in call order
        # which attachments are sinkers (attach index, mass, density) and floats (attach index, buoyancy, g,
        # rho, own mass): the design space (jaxnet.design.space) varies their mass and buoyancy
        self.sinkers: list[tuple[int, float, float]] = []
        self.floats: list[tuple[int, float, float, float, float]] = []
        #: what the last :meth:`build` made of the description (:class:`Layout`); None before any build
        self.layout: Layout | None = None

    # -- description ------------------------------------------------------------------------------

    def panel(self, name, corners, twine: Twine | HexTwine, step: float | None = None,
              twines: NumericalTwines | None = None, lattice: tuple | None = None) -> PanelRef:
        """Add a panel. corners: (C, 5) rows x, y, z (m), U, V (twines of a diamond mesh, or base meshes of a
        hexagonal mesh when ``twine`` is a :class:`HexTwine`); step: meshing step (m) of its triangles.

        twines: a :class:`~jaxnet.mesh.twines.NumericalTwines` to mesh the (diamond) panel as numerical twines,
        chains of bars along its twines, each standing for ``period`` real twines (book 4.1.2; FEMNET's ``input
        netting2ropes``), instead of triangles; ``step`` is then unused. Their bars are the scene's bars of a
        cable named "<name> twines" (after the net's cables), of :func:`~jaxnet.mesh.twines.numerical_twine_rope`
        material. The twines end on the panel's border, where only a rope holds them: every side of such a
        panel needs a cable sewn along it (``Net.cable(along=...)``, as FEMNET requires), and it cannot be
        seamed to another panel.

        lattice: (NU, NV), numbers of meshes (> 0), to put the (diamond) panel's nodes on the lattice of every
        NU meshes along the U diagonal and every NV meshes along the V diagonal of its meshes, U = (u - v)/2 and
        V = (u + v)/2 for the twine coordinates (u, v) of ``corners`` (FEMNET's ``input Meshing_UV PANEL NU NV``;
        :func:`~jaxnet.mesh.panel.mesh_panel`), instead of an isotropic step: a long, low panel (a gill net)
        then gets long thin triangles. ``step`` is then unused; a side's default division is its length in
        lattice cells."""
        if name in self.panels or name in self.cables:
            raise SceneError(f"panel '{name}': the name is already used")
        if not isinstance(twine, (Twine, HexTwine)):
            raise SceneError(f"panel '{name}': its material must be a Twine or a HexTwine, got {twine!r}")
        corners = np.asarray(corners, dtype=float)
        if corners.ndim != 2 or corners.shape[1] != 5:
            raise SceneError(f"panel '{name}': corners must be rows of x y z U V, got shape {corners.shape}")
        if twines is not None:
            if not isinstance(twines, NumericalTwines):
                raise SceneError(f"panel '{name}': twines must be a NumericalTwines, got {twines!r}")
            if not isinstance(twine, Twine):
                raise SceneError(f"panel '{name}': numerical twines need a diamond-mesh Twine, got {twine!r}")
            bad = twines.check(f"panel '{name}'")
            if bad:
                raise SceneError(bad)
            _check_material(twine, f"panel '{name}'")
            self.panels[name] = PanelDescription(name, corners, twine, float("nan") if step is None else float(step), twines)
            return PanelRef(name)
        if lattice is not None:
            if twines is not None or not isinstance(twine, Twine):
                raise SceneError(f"panel '{name}': a lattice of mesh diagonals meshes a diamond-mesh panel into "
                                 f"triangles (not numerical twines nor hexagonal netting), got {twine!r}")
            try:
                lattice = tuple(float(x) for x in lattice)
            except (TypeError, ValueError):
                raise SceneError(f"panel '{name}': lattice must be (NU, NV), two numbers of meshes, got {lattice!r}") from None
            if len(lattice) != 2 or not all(np.isfinite(x) and x > 0 for x in lattice):
                raise SceneError(f"panel '{name}': lattice must be (NU, NV), two numbers of meshes > 0, got {lattice!r}")
            step = float("nan") if step is None else step
        if step is None:
            raise SceneError(f"panel '{name}': give its meshing step (m), or twines= to mesh it as numerical twines")
        _check_material(twine, f"panel '{name}'")
        if isinstance(twine, HexTwine):
            self.panels[name] = PanelDescription(name, corners, twine, float(step))
            return PanelRef(name)
        self.panels[name] = PanelDescription(name, corners, twine, float(step), lattice=lattice)
        return PanelRef(name)

    def cable(self, name, start=None, end=None, rope: Rope | None = None, n_bars: int | None = None,
              length: float | None = None, along: Side | None = None) -> CableRef:
        """Add a cable of ``n_bars`` bars between ``start`` and ``end`` (references or (x, y, z) points), or
        sewn ``along`` a panel side. length: unstretched length (m), default the start distance."""
        if name in self.panels or name in self.cables:
            raise SceneError(f"cable '{name}': the name is already used")
        if rope is None:
            raise SceneError(f"cable '{name}': no rope material given")
        _check_material(rope, f"cable '{name}'")
        if along is None and (start is None or end is None):
            raise SceneError(f"cable '{name}': give both ends (start=, end=) or a panel side (along=)")
        if n_bars is not None and (int(n_bars) != n_bars or n_bars < 1):
            raise SceneError(f"cable '{name}': number of bars must be a positive integer, got {n_bars!r}")
        if length is not None and not (np.isfinite(length) and length > 0):
            raise SceneError(f"cable '{name}': length must be > 0, got {length!r}")
        self.cables[name] = CableDescription(name, start, end, rope, length, n_bars, along)
        return CableRef(name)

    def cable_joint(self, a, b, neutral_angle=float(np.pi), stiffness=None):
        """Weld cable ``a`` to cable ``b`` where they share a node (an end of one on a node of the other, as
        built): the angle between them there resists bending away from ``neutral_angle`` (FEMNET's
        ``link_flexion_elem2``; :mod:`jaxnet.terms.cable_bending`).

        a, b: the cables (:class:`CableRef` or names), which must share at least one node once built (each shared
          node makes a joint between each bar of ``a`` and each bar of ``b`` meeting there).
        neutral_angle: the angle between the two cables at rest (rad, in [0, pi]), measured inside the corner
          they make: pi when b continues a straight on, pi/2 for a square corner (FEMNET's angle, in radians).
        stiffness: EI of the joint (N·m², >= 0); None for the smaller of the two ropes' ``bending_stiffness``,
          FEMNET's rule (a joint with a rope without bending stiffness then does nothing).
        """
        names = []
        for ref in (a, b):
            name = ref.name if isinstance(ref, CableRef) else ref
            if not isinstance(name, str) or name not in self.cables:
                raise SceneError(f"cable joint: no cable named {name!r} (cables: {sorted(self.cables)})")
            names.append(name)
        if names[0] == names[1]:
            raise SceneError(f"cable joint: cable '{names[0]}' is joined to itself (its own joints bend with its "
                             "rope's bending_stiffness)")
        what = f"cable joint '{names[0]}'-'{names[1]}'"
        if not (np.isfinite(neutral_angle) and 0.0 <= neutral_angle <= np.pi):
            raise SceneError(f"{what}: neutral_angle must be in [0, pi] rad (pi: aligned), got {neutral_angle!r}")
        if stiffness is not None and not (np.isfinite(stiffness) and stiffness >= 0):
            raise SceneError(f"{what}: stiffness EI must be >= 0 (N·m²), got {stiffness!r}")
        self.cable_joints.append((names[0], names[1], float(neutral_angle), None if stiffness is None else float(stiffness)))

    def seam(self, a: Side, b: Side):
        """Sew panel side ``a`` to panel side ``b``: they share their border nodes."""
        if a == b:  # its nodes would merge pairwise from both ends: the side folded onto itself
            raise SceneError(f"seam: side {getattr(a, 'index', '?')} of panel '{getattr(a, 'panel', '?')}' is sewn to itself")
        self.seams.append((a, b))

    def fix(self, where, axes="xyz"):
        """Hold the node(s) at ``where`` (a reference or (x, y, z) point) along ``axes`` (e.g. "xyz", "z")."""
        bad = set(axes) - set("xyz")
        if bad:
            raise SceneError(f"fix: unknown axes {sorted(bad)} (use x, y, z)")
        self.fixings.append((where, tuple(a in axes for a in "xyz")))

    def symmetry_plane(self, axis, at=0.0, hold=True):
        """Declare the net the modelled part of a net symmetric about the plane ``axis`` = ``at`` (axis "x", "y"
        or "z", at in m): a cod-end modelled as a quarter has two. With ``hold`` every node lying on the plane (to
        1e-9 of the net's size) is held along ``axis``, which makes the model symmetric; the results then give the
        whole net's figures beside the modelled part's, and the pictures and ParaView files draw the whole net
        (:attr:`jaxnet.scene.Scene.symmetry_planes`)."""
        if axis not in ("x", "y", "z"):
            raise SceneError(f"symmetry_plane: axis must be 'x', 'y' or 'z', got {axis!r}")
        if not np.isfinite(at):
            raise SceneError(f"symmetry_plane: 'at' must be a finite position (m), got {at!r}")
        index = "xyz".index(axis)
        if any(a == index for a, _, _ in self.symmetry_planes):
            raise SceneError(f"symmetry_plane: the net already has a symmetry plane across {axis}")
        self.symmetry_planes.append((index, float(at), bool(hold)))

    def attach(self, where, mass=0.0, volume=0.0, force=(0.0, 0.0, 0.0), drag_area=0.0, size=0.0):
        """Attach a lumped mass (kg) displacing ``volume`` (m³), an external force (N) and/or a drag area
        Cd·A (m²) to the node(s) at ``where``; on several nodes (a side, a cable) the amounts are shared
        equally. ``size`` (m): the vertical size of the body, over which it goes from immersed to
        emerged when it crosses the free surface (floats)."""
        self.attachments.append((where, float(mass), float(volume), np.asarray(force, dtype=float), float(drag_area), float(size)))

    def sinker(self, where, mass, density=11340.0):
        """A sinker of ``mass`` kg of a material of ``density`` (kg/m³, lead by default)."""
        self.attach(where, mass=mass, volume=mass / density)
        self.sinkers.append((len(self.attachments) - 1, float(mass), float(density)))

    def float(self, where, buoyancy_N, mass=0.0, size=0.0, drag_area=0.0):
        """A float pulling up with ``buoyancy_N`` newtons net of its own weight (+ optional mass, kg) when
        immersed; ``size`` (m) its height, for a float at the free surface; ``drag_area`` Cd·A (m²). (Named as
        the gear's floats are; inside the class's methods ``float`` is still Python's number type.)"""
        g, rho = self.environment.gravity, self.environment.water_density
        self.attach(where, mass=mass, volume=(buoyancy_N / g + mass) / rho, drag_area=drag_area, size=size)
        self.floats.append((len(self.attachments) - 1, float(buoyancy_N), float(g), float(rho), float(mass)))

    def float_(self, *args, **kwargs):
        """The former name of :meth:`float`, kept for one release: it warns and calls :meth:`float`."""
        warnings.warn("Net.float_ is now Net.float", DeprecationWarning, stacklevel=2)
        return self.float(*args, **kwargs)

    def body(self, where, length, drag_coefficient):
        """Give the node(s) at ``where`` a box-shaped body with a drag per axis, as FEMNET's node types
        ("Length X,Y,Z", "Drag coefficient X,Y,Z"; :func:`jaxnet.terms.drag.box_drag`).

        length: (L_x, L_y, L_z), the box's sizes (m) along x, y and z. L_x, L_y >= 0; L_z is the height
          along ``up`` and its sign says where the box stands: above its node for L_z > 0 (a float), below
          it for L_z < 0 (a sinker); that matters only at a free surface, for the immersed part.
        drag_coefficient: (Cd_x, Cd_y, Cd_z) >= 0. The drag along x is ½ ρ Cd_x (L_y h) |c| c_x, the face
          normal to x being L_y wide and h (the immersed part of |L_z|) high; along y the face L_x h;
          along z the section L_x L_y.

        Every node of ``where`` gets the whole box (unlike :meth:`attach`, which shares its amounts among
        the nodes): a body is a property of each node, as a FEMNET node type is. A later call replaces the
        body of an earlier one on the nodes they share. The box has drag only: its buoyancy (FEMNET also
        floats it) is given, if wanted, as a displaced volume with :meth:`attach`.
        """
        length = _triple(length, "body: length")
        cd = _triple(drag_coefficient, "body: drag_coefficient")
        # a negative height is a box hanging below its node (FEMNET's sinker); a negative width is no box
        if np.any(length[:2] < 0):
            raise SceneError(f"body: length along x and y must be >= 0 (m), got {length.tolist()}")
        if np.any(cd < 0):
            raise SceneError(f"body: drag_coefficient must be >= 0 along x, y and z, got {cd.tolist()}")
        self.bodies.append((where, length, cd))

    def limit(self, where, value, sense):
        """Give the node(s) at ``where`` a floor or a ceiling per axis, as FEMNET's node types ("Limits X,Y,Z",
        "Limits sense X,Y,Z"; the sea bed, :mod:`jaxnet.terms.bottom`).

        value: (x, y, z) limit coordinates (m); only those of the axes with a sense are used.
        sense: (s_x, s_y, s_z), each +1 (a floor: the coordinate stays >= its limit; along ``up``, the sea
          bed), -1 (a ceiling: it stays <= its limit) or 0 (no limit along that axis).

        A node beyond its limit is pushed back with the environment's ``bottom_stiffness`` (N/m, which must
        be > 0 for a limit to act) and, on a floor along ``up`` over a moving bottom, dragged by
        ``bottom_friction``. Every node of ``where`` gets the limits; a later call replaces all three axes of
        an earlier one on the nodes they share (as a node has one FEMNET node type).
        """
        sense_arr = _triple(sense, "limit: sense")
        if not np.all(np.isin(sense_arr, (-1.0, 0.0, 1.0))):
            raise SceneError(f"limit: limit_sense must be +1 (floor), -1 (ceiling) or 0 (none) per axis, got "
                             f"{np.asarray(sense).tolist()}")
        used = sense_arr != 0
        # the limit of an axis without a sense is never read: any number (or NaN) is allowed there
        values = _triple(value, "limit: value (m)", finite=False)
        if not np.all(np.isfinite(values[used])):
            raise SceneError(f"limit: value must be finite on the axes with a sense, got {values.tolist()}")
        self.limits.append((where, np.where(used, values, 0.0), sense_arr.astype(np.int32)))

    def catch(self, volume, drag_coefficient=1.4, symmetry=1.0, center=(0.0, 0.0, 0.0), axis=None, density=0.0):
        """Fill the cod-end with ``volume`` m³ of catch (whole cod-end; ``symmetry`` copies of the modelled
        part make it, e.g. 4 for a quarter model), of drag coefficient Cd. The cod-end's axis passes through
        ``center`` (a point at its opening, m) along ``axis`` (downstream; default the current's
        direction). The netting's outward side is found from the start shape: away from ``center``.

        ``density`` > 0 (kg/m³) makes it a gravity catch (FEMNET's ``input catch_gravity``): the catch weighs on
        a bag hanging out of the water, filling it up to a horizontal level, with the hydrostatic pressure
        density × g × the depth below that level; ``axis`` then defaults to down (-up), no current is needed
        and ``drag_coefficient`` is not used. See :class:`jaxnet.scene.Catch`."""
        if not volume > 0 or not drag_coefficient >= 0 or not symmetry >= 1:
            raise SceneError(f"catch: volume must be > 0, drag_coefficient >= 0 and symmetry >= 1, got "
                             f"{volume!r}, {drag_coefficient!r}, {symmetry!r}")
        if not (np.isfinite(density) and density >= 0):
            raise SceneError(f"catch: density must be finite and >= 0 (kg/m³; 0 for a catch in a current), got {density!r}")
        self.main_catch = dict(volume=float(volume), drag_coefficient=float(drag_coefficient), symmetry=float(symmetry),
                           center=_point(center, "catch: center"), axis=None if axis is None else _unit(axis, "catch: axis"),
                           density=float(density))

    def panel_catch(self, volume, panels, drag_coefficient=1.4, symmetry=1.0, axis=None, center=None):
        """Fill the netting of ``panels`` (their names) with ``volume`` m³ of catch of its own, behind its own
        front (FEMNET's ``input catch2_volume``: twin cod-ends, the compartments of a grid section). Each call adds
        one catch; a panel holds at most one. ``center``: a point (m) on the axis of the cod-end these panels
        form, from which their netting is oriented outward (:meth:`catch`'s ``center``); default the mean of their
        nodes' start positions, inside a cod-end drawn whole (give it for a quarter or half model, whose nodes
        lie on one side of the axis); with a main catch or an enclosure as well, theirs orients all the netting.
        ``drag_coefficient``, ``symmetry`` (copies of the modelled part in the whole
        net: ``volume`` is the whole net's) and ``axis`` (downstream; default the current's direction) are shared
        by the panel catches: the last call's hold. See :class:`jaxnet.scene.PanelCatches` and
        :mod:`jaxnet.terms.panel_catch`."""
        if not (np.isfinite(volume) and volume > 0) or not drag_coefficient >= 0 or not symmetry >= 1:
            raise SceneError(f"panel_catch: volume must be finite and > 0, drag_coefficient >= 0 and symmetry >= 1, "
                             f"got {volume!r}, {drag_coefficient!r}, {symmetry!r}")
        names = tuple(panels)
        if not names:
            raise SceneError("panel_catch: give the panels that hold the catch")
        for name in names:
            self.panel_named(name, "panel_catch")
        taken = {n for _, held, _ in self.panel_catches for n in held}
        twice = [n for n in names if n in taken or names.count(n) > 1]
        if twice:
            raise SceneError(f"panel_catch: panel '{twice[0]}' already holds a catch (a panel holds at most one)")
        self.panel_catches.append((float(volume), names, None if center is None else _point(center, "panel_catch: center")))
        self.panel_catch_options = (float(drag_coefficient), float(symmetry),
                                     None if axis is None else _unit(axis, "panel_catch: axis"))

    def enclose(self, center, axis):
        """Declare the net closed but for the opening through ``center`` (m) normal to ``axis`` (pointing into
        the net): the result reports the volume it holds. See :class:`jaxnet.scene.Enclosure`."""
        self.enclosure = dict(center=_point(center, "enclose: center"), axis=_unit(axis, "enclose: axis"))

    def description(self) -> dict:
        """What was described, as plain data (copies, in call order), for writers of the description
        (:func:`jaxnet.io.scene_export.to_dict`) and readers of it that must not reach into the net.

        Values are the API's own: references (:class:`Corner`, :class:`Side`, :class:`Nearest`,
        :class:`PanelRef`, :class:`CableEnd`, :class:`CableNodes`, :class:`CableRef`, or an (x, y, z) point as
        given), materials (:class:`Twine`, :class:`HexTwine`, :class:`Rope`,
        :class:`~jaxnet.mesh.twines.NumericalTwines`), the :class:`Environment` as given (its current direction
        not normalised); numbers are floats (m, kg, N, rad), points and vectors (3,) arrays. Keys:

        * ``environment``; ``merge_tolerance`` (m);
        * ``panels``: {name, corners (C, 5) x y z U V, twine, step (m, None where unused), twines
          (NumericalTwines or None), lattice ((NU, NV) or None)};
        * ``cables``: {name, start, end, rope, n_bars, length (m), along} (None where not given);
        * ``seams``: (side, side) pairs; ``cable_joints``: {cables (a, b), neutral_angle, stiffness (None: the
          ropes')};
        * ``fixed``: {at, axes ("xyz", "z", ...)}; ``symmetry_planes``: {axis ("x", "y" or "z"), at, hold};
        * ``attached``: {at, mass, volume, force, drag_area, size}, every :meth:`attach` call, sinkers' and
          floats' included; ``sinkers``: {attached (index in ``attached``), mass, density}; ``floats``:
          {attached, buoyancy_N, gravity, water_density, mass} (g and rho of the environment at the call, from
          which the float's volume was worked out);
        * ``bodies``: {at, length, drag_coefficient}; ``limits``: {at, value (0 on axes without a sense), sense};
        * ``catch``: {volume, drag_coefficient, symmetry, center, axis (None: the current's), density} or None;
        * ``panel_catches``: {volume, panels, center, drag_coefficient, symmetry, axis}: the last three are
          shared by all of them (the last :meth:`panel_catch` call's), repeated in each;
        * ``enclosure``: {center, axis} or None.
        """
        def copy(value):
            return None if value is None else np.array(value, dtype=float)

        def ref(where):
            return copy(where) if isinstance(where, (list, tuple, np.ndarray)) else where

        options = self.panel_catch_options or (None, None, None)
        return {
            "environment": self.environment,
            "merge_tolerance": float(self.merge_tolerance),
            "panels": [dict(name=p.name, corners=copy(p.corners), twine=p.twine,
                            step=float(p.step) if np.isfinite(p.step) else None, twines=p.twines,
                            lattice=None if p.lattice is None else tuple(p.lattice)) for p in self.panels.values()],
            "cables": [dict(name=c.name, start=ref(c.start), end=ref(c.end), rope=c.rope, n_bars=c.n_bars,
                            length=c.length, along=c.along) for c in self.cables.values()],
            "seams": [tuple(pair) for pair in self.seams],
            "cable_joints": [dict(cables=(a, b), neutral_angle=angle, stiffness=ei)
                             for a, b, angle, ei in self.cable_joints],
            "fixed": [dict(at=ref(where), axes="".join(a for a, on in zip("xyz", axes) if on))
                      for where, axes in self.fixings],
            "symmetry_planes": [dict(axis="xyz"[axis], at=at, hold=hold) for axis, at, hold in self.symmetry_planes],
            "attached": [dict(at=ref(where), mass=m, volume=v, force=copy(f), drag_area=a, size=h)
                         for where, m, v, f, a, h in self.attachments],
            "sinkers": [dict(attached=k, mass=m, density=rho) for k, m, rho in self.sinkers],
            "floats": [dict(attached=k, buoyancy_N=b, gravity=g, water_density=rho, mass=m)
                       for k, b, g, rho, m in self.floats],
            "bodies": [dict(at=ref(where), length=copy(length), drag_coefficient=copy(cd))
                       for where, length, cd in self.bodies],
            "limits": [dict(at=ref(where), value=copy(value), sense=np.array(sense))
                       for where, value, sense in self.limits],
            "catch": None if self.main_catch is None else {k: copy(v) if k in ("center", "axis") else v
                                                       for k, v in self.main_catch.items()},
            "panel_catches": [dict(volume=volume, panels=tuple(names), center=copy(center),
                                   drag_coefficient=options[0], symmetry=options[1], axis=copy(options[2]))
                              for volume, names, center in self.panel_catches],
            "enclosure": None if self.enclosure is None else {k: copy(v) for k, v in self.enclosure.items()},
        }

    # -- building ---------------------------------------------------------------------------------

    def build(self) -> Scene:
        """Mesh every panel, join panels and cables, and return the :class:`Scene` (validated); what was made of
        the description is then :attr:`layout` (:func:`jaxnet.build.scene_of`)."""
        from jaxnet.build import scene_of

        scene, self.layout = scene_of(self)
        return scene

    def panel_named(self, name, what):
        """The description of the panel ``name``, or a SceneError for ``what`` (the call or reference that
        named it) listing the net's panels."""
        if name not in self.panels:
            raise SceneError(f"{what}: no panel named '{name}' (panels: {sorted(self.panels)})")
        return self.panels[name]


def _check_material(material, what):
    """SceneError naming ``what`` (the panel or cable) and the parameter of its material out of its range
    (:func:`jaxnet.materials.check`)."""
    try:
        materials.check(material)
    except materials.MaterialError as err:
        raise SceneError(f"{what}: {err.problem}") from None


def _triple(value, what, finite=True):
    """(3,) floats along x, y, z (finite unless ``finite`` is False), or a SceneError naming ``what``."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != (3,) or (finite and not np.all(np.isfinite(arr))):
        raise SceneError(f"{what}: expected 3 {'finite ' if finite else ''}values (x, y, z), got {value!r}")
    return arr


def _point(value, what):
    p = np.asarray(value, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise SceneError(f"{what}: expected a finite point (x, y, z), got {value!r}")
    return p


def _unit(value, what):
    v = _point(value, what)
    n = np.linalg.norm(v)
    if not n > 0:
        raise SceneError(f"{what}: expected a non-zero vector, got {value!r}")
    return v / n
