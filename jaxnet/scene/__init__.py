"""A scene: the data of one net problem (nodes, element families, parameters, boundary conditions).

A scene is plain data (an equinox pytree of arrays), so it can be passed through ``jax.jit``, ``vmap``
and ``grad`` as an argument: parameters (stiffness, lengths, twine coordinates, loads) are leaves that
design gradients can flow into. What the scene *contains* — which element families, which terms have
non-zero parameters — is read from its concrete values once, before tracing, by :mod:`jaxnet.model`.

Units are SI throughout: m, N, kg, kg/m³, s.

Element families:
  * :class:`Netting` — diamond-mesh triangles (book section 4.2), one row per triangle, every per-element
    parameter an array so that panels of different netting share one vmapped family.
  * :class:`Bars` — straight cable bars (ropes), one row per bar.
  * :class:`Hinges` — pairs of neighbouring triangles, for twine bending (built from the netting).
  * :class:`CableJoints` — pairs of consecutive bars of stiff cables, for cable bending (built from the
    cables' bending stiffness and their joints).
Nodes carry fixity per axis, lumped mass and displaced volume (sinkers, floats) and an external force;
optionally the box-shaped body of FEMNET's node types (anisotropic node drag) and limits per axis (the
sea bed, a ceiling).

:func:`jaxnet.scene.checks.validate` checks a scene and raises :class:`SceneError` naming the culprit (node,
element, cable, parameter) — always before anything is compiled.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import numpy as np


class SceneError(ValueError):
    """A scene (or its description) is malformed; the message names the culprit."""


class Nodes(eqx.Module):
    """Nodes of the net.

    position: (N, 3) start positions (m); fixed nodes stay there.
    fixed: (N, 3) bool, True where the coordinate is held (per axis).
    mass: (N,) lumped mass (kg): sinkers, floats, anything attached to the node.
    volume: (N,) displaced volume (m³) of what is attached (buoyancy rho_water g volume).
    force: (N, 3) external force applied to the node (N).
    drag_area: (N,) drag area Cd·A of what is attached (m²): node drag ½ρ Cd A |c| c; None for none.
    size: (N,) vertical size of what is attached (m): the band over which a float crossing the free
      surface goes from immersed to emerged; None where the scene has no free surface.
  Optional, FEMNET's node types (None: the term is absent; see :mod:`jaxnet.terms.drag` and
  :mod:`jaxnet.terms.bottom`):
    drag_length: (N, 3) size (m) along x, y, z of a box-shaped body at the node (FEMNET "Length X,Y,Z"),
      for the node drag along each axis. The z size is the body's height along ``up``; its sign says on
      which side of the node the body lies (> 0 above it: a float, < 0 below it: a sinker), which matters
      only for the part immersed under a free surface. x and y sizes are >= 0.
    drag_coefficient: (N, 3) drag coefficient (dimensionless) along x, y, z (FEMNET "Drag coefficient
      X,Y,Z"): the drag along x is ½ ρ Cd_x (L_y h) |c| c_x, h the immersed height, and so on.
    limit: (N, 3) limit coordinate (m) along x, y, z (FEMNET "Limits X,Y,Z"), for ``limit_sense`` != 0.
    limit_sense: (N, 3) int, which side of the limit is forbidden (FEMNET "Limits sense X,Y,Z"): +1 the
      coordinate must stay >= the limit (a floor: the sea bed when along up), -1 it must stay <= the limit
      (a ceiling), 0 no limit. Penetration is resisted by ``Environment.bottom_stiffness``.
  Optional, dynamics only:
    added_mass: (N, 3) added mass (kg) of what is attached, along x, y, z (FEMNET "Added mass X,Y,Z"):
      the mass of water it carries along when it accelerates relative to the water (book 4.265's M_a).
    """

    position: np.ndarray
    fixed: np.ndarray
    mass: np.ndarray
    volume: np.ndarray
    force: np.ndarray
    drag_area: np.ndarray | None = None
    size: np.ndarray | None = None
    drag_length: np.ndarray | None = None
    drag_coefficient: np.ndarray | None = None
    limit: np.ndarray | None = None
    limit_sense: np.ndarray | None = None
    added_mass: np.ndarray | None = None


class Netting(eqx.Module):
    """Diamond-mesh netting triangles (one row per triangle).

    vertices: (E, 3) node indices.
    uv: (E, 3, 2) twine coordinates (U, V) of each vertex, in number of twines (eqs 4.1-4.7).
    l0: (E,) unstretched twine length = mesh side (m).
    ea_traction, ea_compression: (E,) twine stiffness in traction and in compression (N).
    diameter: (E,) twine diameter (m), for weight and drag.
    density: (E,) volumic mass of the twine material (kg/m³).
    panel: (E,) index of the panel each triangle belongs to (for reports).
  Optional (None: the term is absent):
    cd_normal: (E,) normal drag coefficient Cd of a twine; tangential_ratio: (E,) f, the tangential drag
      as a fraction of Cd (tangential drag f ½ρ Cd D l0 (c cos α)², eqs 4.114-4.115).
    drag_model: (E,) int, how the current loads the netting: 0 twine drag (Morison per twine, the book),
      1 Løland screen model, 2 Kristiansen-Faltinsen screen model, 3 FEMNET's twine drag of cases with a
      catch (``trainee_fil``: the U twines' cross-flow drag turned along the V twines' cross-flow
      direction; :func:`jaxnet.terms.drag.netting_drag_femnet_catch`), for reproducing FEMNET only, 4 Zhan's
      twine drag with the solidity (:func:`jaxnet.terms.drag.netting_drag_zhan`), 5 none (FEMNET's drag laws
      3 and 4, which its code leaves out).
    opening_stiffness: (E,) mesh opening stiffness H (N·m/rad, eqs 4.211-4.219); rest_angle: (E,) rest
      half opening angle α0 (rad).
    knot_size: (E,) knot size (m, eq. 4.278); knot_stiffness: (E,) contact stiffness (N·m/rad, default 4.280).
    knot_form: (E,) int, the knot contact law (:mod:`jaxnet.terms.knot`): 0 the book's (4.278-4.280, with a
      stiffness ramp), 1 FEMNET's (``fermeture2``: contact at atan(k / 2 l0), couple 2 H cos α (α - α_c));
      None for 0 everywhere.
    bending_stiffness: (E,) flexural stiffness EI of one twine (N·m², eqs 4.220-4.245): makes hinges.
    outward: (E,) +1 where 12 ^ 13 points out of the volume the net encloses (cod-end, cage), -1 where
      it points in; set with a catch or an enclosure, from the start shape.
    tarp_cd: (E,) pressure coefficient of a tarp (:mod:`jaxnet.terms.tarp`), 0 for permeable netting: where
      it is > 0 the current's pressure replaces the twine drag and the catch pressure.
    """

    vertices: np.ndarray
    uv: np.ndarray
    l0: np.ndarray
    ea_traction: np.ndarray
    ea_compression: np.ndarray
    diameter: np.ndarray
    density: np.ndarray
    panel: np.ndarray
    cd_normal: np.ndarray | None = None
    tangential_ratio: np.ndarray | None = None
    drag_model: np.ndarray | None = None
    opening_stiffness: np.ndarray | None = None
    rest_angle: np.ndarray | None = None
    knot_size: np.ndarray | None = None
    knot_stiffness: np.ndarray | None = None
    knot_form: np.ndarray | None = None
    bending_stiffness: np.ndarray | None = None
    outward: np.ndarray | None = None
    tarp_cd: np.ndarray | None = None


class Bars(eqx.Module):
    """Cable bars (one row per bar): a cable of length L in n bars gives n rows of rest length L/n.

    ends: (B, 2) node indices.
    rest_length: (B,) unstretched length (m).
    ea_traction, ea_compression: (B,) stiffness (N).
    diameter: (B,) (m); density: (B,) volumic mass (kg/m³); cable: (B,) index of the cable.
    cd_normal: (B,) Morison normal drag coefficient; tangential_ratio: (B,) f, tangential drag as a fraction of
      Cd, as for twines (None: no drag).
    """

    ends: np.ndarray
    rest_length: np.ndarray
    ea_traction: np.ndarray
    ea_compression: np.ndarray
    diameter: np.ndarray
    density: np.ndarray
    cable: np.ndarray
    cd_normal: np.ndarray | None = None
    tangential_ratio: np.ndarray | None = None


class HexagonalNetting(eqx.Module):
    """Hexagonal-mesh triangles (book eqs 4.76-4.113), one row per triangle.

    vertices: (E, 3) node indices. uv: (E, 3, 2) twine coordinates in base meshes. l0, ea_traction,
    ea_compression: (E, 3) per twine family (l, m, n): unstretched length (m), stiffness (N). diameter (E,)
    (m), density (E,) (kg/m³), panel (E,) index.
    """

    vertices: np.ndarray
    uv: np.ndarray
    l0: np.ndarray
    ea_traction: np.ndarray
    ea_compression: np.ndarray
    diameter: np.ndarray
    density: np.ndarray
    panel: np.ndarray


class Hinges(eqx.Module):
    """Pairs of triangles of one panel sharing an edge, for twine bending (eqs 4.220-4.245); one row per pair.

    vertices: (H, 4) node indices: the shared edge's two nodes, then the opposite node of each triangle.
    uv: (H, 4, 2) twine coordinates of those nodes. l0: (H,) twine length (m). stiffness: (H,) EI (N·m²).
    panel: (H,) panel index.
    """

    vertices: np.ndarray
    uv: np.ndarray
    l0: np.ndarray
    stiffness: np.ndarray
    panel: np.ndarray


class CableJoints(eqx.Module):
    """Joints where a cable bends: two bars meeting at a node, one row per joint (cable bending,
    :mod:`jaxnet.terms.cable_bending`).

    vertices: (J, 3) node indices (the far end of the first bar, the joint node, the far end of the second
      bar): the bars are vertices[0] -> vertices[1] and vertices[1] -> vertices[2].
    rest_length: (J, 2) unstretched lengths (m) of the two bars (the cables' own bars).
    stiffness: (J,) flexural stiffness EI of the joint (N·m²).
    rest_angle: (J,) the neutral turning angle β (rad, in [0, pi]): the angle between the two bars' directions
      at which the joint carries no couple; 0 for a cable that is straight at rest (FEMNET's neutral angle
      between linked cables, 180° when aligned, is pi - β).
    cable: (J, 2) index of the cable of each bar (for messages and reports): equal inside one cable,
      different at a joint between two cables.
    """

    vertices: np.ndarray
    rest_length: np.ndarray
    stiffness: np.ndarray
    rest_angle: np.ndarray
    cable: np.ndarray


class Catch(eqx.Module):
    """Fish catch in a cod-end (eqs 4.246-4.264): the netting behind the catch front, placed so that the
    enclosed volume is ``volume``, carries the pressure ½ ρ Cd v² (v: the current speed).

    volume: catch volume (m³) of the whole cod-end. drag_coefficient: Cd of the catch. symmetry: how many
    copies of the modelled part make the whole cod-end (4 for a quarter model). axis: unit vector of the
    cod-end axis, pointing downstream. center: a point (m) on the axis at the opening of the cod-end.
    The netting's outward side is ``Netting.outward``.
    density: 0 (default) for the catch above; > 0 for a *gravity catch* (FEMNET's ``input catch_gravity``): a
    catch of that density ρ_c (kg/m³) weighing on a bag out of the water, below a horizontal level placed so that
    the enclosed volume is ``volume``; the axis then points down (-up) and the pressure is hydrostatic,
    ρ_c g × the depth below the level, instead of ½ ρ Cd v² (:mod:`jaxnet.terms.gravity_catch`).
    """

    volume: float
    drag_coefficient: float
    axis: np.ndarray
    center: np.ndarray
    symmetry: float = 1.0
    density: float = 0.0


class PanelCatches(eqx.Module):
    """Catches held by chosen panels (FEMNET's ``input catch2_volume V N P1 .. PN``): each a volume of catch
    filling the netting of its own panels from the rear, behind its own front, with the pressure ½ ρ Cd v² of
    :class:`Catch` on that netting (:mod:`jaxnet.terms.panel_catch`). Twin cod-ends, or the compartments of a
    grid section, each take one. Independent of :class:`Catch` (the scene's main catch, on all its netting).

    volume: (K,) catch volume (m³) of each catch, for the whole net (``symmetry`` copies of the modelled part).
    panel_catch: (P,) int, for each panel of the scene (``Netting.panel``) the catch it holds (0..K-1), or -1
      for none; a panel holds at most one.
    drag_coefficient: Cd of the catches. axis: (3,) unit vector along which the fronts advance, downstream.
    symmetry: copies of the modelled part in the whole net (as :class:`Catch`'s).
    The netting's outward side is ``Netting.outward``.
    """

    volume: np.ndarray
    panel_catch: np.ndarray
    drag_coefficient: float
    axis: np.ndarray
    symmetry: float = 1.0


class Enclosure(eqx.Module):
    """The opening of a closed net (a cage's collar): the result reports the volume the net holds behind
    the plane through ``center`` (m) normal to ``axis`` (unit, pointing into the net, e.g. down for a
    cage). The netting's outward side is ``Netting.outward``."""

    center: np.ndarray
    axis: np.ndarray


class Environment(eqx.Module):
    """Surroundings.

    gravity: g (m/s²); water_density (kg/m³); up: unit vertical (weight acts along -up).
    current_speed (m/s) and current_direction (unit vector, normalised by the builders): a uniform
      current, scaled with depth by profile_factor (dimensionless) at profile_depth (m below the surface,
      increasing; linear in between, constant beyond; empty: uniform). See :mod:`jaxnet.water.current`.
    surface_level: height of the free surface along ``up`` (m); NaN (default) for none: everything is
      fully immersed and weight is a constant load.
    floating: the element families whose weight and buoyancy feel the free surface (:data:`FLOATING`, the
      default: all of them, :mod:`jaxnet.terms.surface`); the others keep their fully immersed load wherever
      they are. FEMNET's statics float bars and node boxes by their immersed part but keep diamond netting
      buoyant out of the water (``flotteursurf3.c``): its scenes name ("bars", "nodes").
    bottom_stiffness: stiffness (N/m) of the penetration of a node beyond its limit (``Nodes.limit``):
      FEMNET's "stiffness of the insertion in the sea bottom".
    bottom_friction: friction coefficient mu (dimensionless) of the sea bed on the nodes pressed against it
      (FEMNET's "wearing coefficient on the bottom"), kinetic friction mu times the normal reaction. In statics it
      acts only where the bed slides under the net (``bottom_moving``), in the current's direction; in time it
      opposes each node's velocity over the bed (:mod:`jaxnet.terms.bottom`), as FEMNET's ``dyna`` does.
    bottom_moving: whether the sea bed slides under the net at the current's velocity (True, the default: a gear
      towed over the ground, seen from the gear, FEMNET's ``input moving_bottom``) or is still (False: FEMNET's
      default, whose statics have no friction at all). Static (it decides which terms a scene has).
    time: the time (s) at which the surroundings are taken (dynamics: the current's history and the waves
      are evaluated at it; 0 in statics).
    waves: regular waves (:class:`jaxnet.water.waves.Airy`), or None for none. Only dynamics feels them: their
      velocity adds to the current's in the drag, their acceleration gives the inertia force of the water.
    surface_elevation: (N,) height (m) of the free surface above ``surface_level`` over each node, or None
      (default) for the mean level everywhere. A time step in waves sets it to the waves' elevation η at the
      nodes' positions at the step's start (:func:`jaxnet.solve.dynamics.scene_at`), so that buoyancy and the
      wetted share of the drags follow the wave's surface, as FEMNET's ``dyna`` does (its immersion is taken
      from the wave's height at each node, ``miseajourPondFS_dyna.c``). Each element sees the level over its
      own vertices (:func:`jaxnet.model.assemble.element_environment`).
    added_mass_coefficient: Ca (dimensionless): the added mass of twines and bars is Ca rho V, V their
      volume (book 4.265's M_a, for which the book gives no formula; 1 is the potential-flow value of a
      cylinder moving across its axis, taken in every direction). Dynamics only.
    bottom_band: width (m) of the band of penetration over which the contact stiffness rises from 0 to
      ``bottom_stiffness`` (a C² penalty, :mod:`jaxnet.terms.bottom`); beyond it the contact force is
      FEMNET's k p exactly; 0 for FEMNET's plain penalty (stiffness jumps at contact). The default 1 mm
      moves a lightly loaded node (load < k b) less than 1 mm deeper than FEMNET's and spares Newton the
      chatter of nodes hovering at the sea bed.
    """

    gravity: float = 9.81
    water_density: float = 1025.0
    up: np.ndarray = dataclasses.field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    current_speed: float = 0.0
    current_direction: np.ndarray = dataclasses.field(default_factory=lambda: np.array([1.0, 0.0, 0.0]))
    profile_depth: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    profile_factor: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0))
    surface_level: float = float("nan")
    bottom_stiffness: float = 0.0
    bottom_friction: float = 0.0
    bottom_band: float = 1e-3
    time: float = 0.0
    waves: object | None = None
    surface_elevation: np.ndarray | None = None
    added_mass_coefficient: float = 1.0
    floating: tuple = eqx.field(static=True, default=("netting", "hexagonal", "bars", "nodes"))
    bottom_moving: bool = eqx.field(static=True, default=True)


#: the element families that can feel a free surface (``Environment.floating``)
FLOATING = ("netting", "hexagonal", "bars", "nodes")


class Scene(eqx.Module):
    """One net problem. ``netting`` or ``bars`` may be None; names are for messages and reports.

    symmetry_planes: the mirror planes of a model that is part of a symmetric net (a cod-end's quarter, a trawl's
      half): ((axis, position m), ...), axis 0, 1 or 2 (x, y, z), the plane x_axis = position; () for a whole
      net. What the results say of the whole net (the mirrored copies) and what the pictures and ParaView files
      draw of it; the nodes on a plane are held across it by the scene's fixity (:meth:`jaxnet.net.Net.
      symmetry_plane` holds them), which is what makes the model symmetric.
    """

    nodes: Nodes
    netting: Netting | None = None
    bars: Bars | None = None
    environment: Environment = dataclasses.field(default_factory=Environment)
    hinges: Hinges | None = None
    cable_joints: CableJoints | None = None
    hexagonal: HexagonalNetting | None = None
    catch: Catch | None = None
    enclosure: Enclosure | None = None
    panel_catches: PanelCatches | None = None
    panel_names: tuple = eqx.field(static=True, default=())
    cable_names: tuple = eqx.field(static=True, default=())
    symmetry_planes: tuple = eqx.field(static=True, default=())

    @property
    def n_nodes(self):
        return int(self.nodes.position.shape[0])

    @property
    def n_elements(self):
        """Netting triangles (diamond and hexagonal) and cable bars."""
        return sum(0 if f is None else int(f.vertices.shape[0] if hasattr(f, "vertices") else f.ends.shape[0])
                   for f in (self.netting, self.hexagonal, self.bars))

    @property
    def n_dof(self):
        """Number of free coordinates (the unknowns of the equilibrium)."""
        return int(np.size(self.nodes.fixed) - np.count_nonzero(self.nodes.fixed))


def bottom_axis(env):
    """(axis, floor sense) of the sea bed: the coordinate axis along ``up`` and the limit sense that forbids
    going down along it (+1 when up is +z, as in FEMNET); None when ``up`` is along no coordinate axis."""
    up = np.asarray(env.up, dtype=float)
    axis = int(np.argmax(np.abs(up)))
    if abs(abs(up[axis]) - 1.0) > 1e-12:
        return None
    return axis, int(np.sign(up[axis]))


#: a node lies on a symmetry plane when it is within this fraction of the net's size (1 m at least) of it
PLANE_TOLERANCE = 1e-9


def on_symmetry_planes(position, planes) -> np.ndarray:
    """(N, 3) bool: True at (node, axis) where the node at ``position`` (N, 3) (m) lies on the plane across that
    axis among ``planes`` ((axis, position m), ...: :attr:`Scene.symmetry_planes`), to :data:`PLANE_TOLERANCE`
    of the net's extent. What :meth:`jaxnet.net.Net.symmetry_plane` holds, and what the writers tell apart from
    a fixing."""
    position = np.asarray(position, dtype=float)
    extent = max(float(np.ptp(position, axis=0).max()), 1.0) if len(position) else 1.0
    on = np.zeros(position.shape, dtype=bool)
    for axis, at in planes:
        on[:, axis] |= np.abs(position[:, axis] - at) <= PLANE_TOLERANCE * extent
    return on


def mirror_copies(scene) -> int:
    """How many copies of the modelled part make the whole net: 2 per symmetry plane."""
    return 2 ** len(scene.symmetry_planes)


def mirrored(scene, points):
    """``points`` (N, 3) (m) and their images in the symmetry planes, copy after copy: (copies, N, 3); the first
    copy is the modelled part itself. Vectors (forces, velocities) mirror with :func:`mirror_signs`."""
    points = np.asarray(points, dtype=float)
    out = [points]
    for axis, at in scene.symmetry_planes:
        images = [p.copy() for p in out]
        for image in images:
            image[..., axis] = 2.0 * at - image[..., axis]
        out = out + images
    return np.stack(out)


def mirror_signs(scene) -> np.ndarray:
    """(copies, 3) the signs of a vector's components in each copy of :func:`mirrored` (-1 along the normal of
    each plane it is mirrored in)."""
    signs = [np.ones(3)]
    for axis, _ in scene.symmetry_planes:
        images = [s.copy() for s in signs]
        for image in images:
            image[axis] = -image[axis]
        signs = signs + images
    return np.stack(signs)


def has_free_surface(scene) -> bool:
    """Whether the scene has a free surface (``environment.surface_level`` not NaN)."""
    return bool(np.isfinite(scene.environment.surface_level))


def feels_surface(scene, family) -> bool:
    """Whether the weight and buoyancy of ``family`` ("netting", "hexagonal", "bars", "nodes") feel the scene's
    free surface: it has one, and the family is among ``environment.floating``."""
    return has_free_surface(scene) and family in scene.environment.floating
