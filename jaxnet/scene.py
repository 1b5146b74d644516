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
Nodes carry fixity per axis, lumped mass and displaced volume (sinkers, floats) and an external force;
optionally the box-shaped body of FEMNET's node types (anisotropic node drag) and limits per axis (the
sea bed, a ceiling).

:func:`validate` checks a scene and raises :class:`SceneError` naming the culprit (node, element, cable,
parameter) — always before anything is compiled.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import numpy as np
import scipy.sparse as sp


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
      direction; :func:`jaxnet.terms.drag.netting_drag_femnet_catch`), for reproducing FEMNET only.
    opening_stiffness: (E,) mesh opening stiffness H (N·m/rad, eqs 4.211-4.219); rest_angle: (E,) rest
      half opening angle α0 (rad).
    knot_size: (E,) knot size (m, eq. 4.278); knot_stiffness: (E,) contact stiffness (N·m/rad, default 4.280).
    knot_form: (E,) int, the knot contact law (:mod:`jaxnet.terms.knot`): 0 the book's (4.278-4.280, with a
      stiffness ramp), 1 FEMNET's (``fermeture2``: contact at atan(k / 2 l0), couple 2 H cos α (α - α_c));
      None for 0 everywhere.
    bending_stiffness: (E,) flexural stiffness EI of one twine (N·m², eqs 4.220-4.245): makes hinges.
    outward: (E,) +1 where 12 ^ 13 points out of the volume the net encloses (cod-end, cage), -1 where
      it points in; set with a catch or an enclosure, from the start shape.
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


class Catch(eqx.Module):
    """Fish catch in a cod-end (eqs 4.246-4.264): the netting behind the catch front, placed so that the
    enclosed volume is ``volume``, carries the pressure ½ ρ Cd v² (v: the current speed).

    volume: catch volume (m³) of the whole cod-end. drag_coefficient: Cd of the catch. symmetry: how many
    copies of the modelled part make the whole cod-end (4 for a quarter model). axis: unit vector of the
    cod-end axis, pointing downstream. center: a point (m) on the axis at the opening of the cod-end.
    The netting's outward side is ``Netting.outward``.
    """

    volume: float
    drag_coefficient: float
    axis: np.ndarray
    center: np.ndarray
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
      increasing; linear in between, constant beyond; empty: uniform). See :mod:`jaxnet.current`.
    surface_level: height of the free surface along ``up`` (m); NaN (default) for none: everything is
      fully immersed and weight is a constant load.
    bottom_stiffness: stiffness (N/m) of the penetration of a node beyond its limit (``Nodes.limit``):
      FEMNET's "stiffness of the insertion in the sea bottom".
    bottom_friction: friction coefficient mu (dimensionless) of the sea bed *sliding under the net* in the
      current's direction (FEMNET's "wearing coefficient" with ``input moving_bottom``: a towed gear on
      the bottom); 0 for a still bottom, which in FEMNET's statics exerts no friction at all.
    time: the time (s) at which the surroundings are taken (dynamics: the current's history and the waves
      are evaluated at it; 0 in statics).
    waves: regular waves (:class:`jaxnet.waves.Airy`), or None for none. Only dynamics feels them: their
      velocity adds to the current's in the drag, their acceleration gives the inertia force of the water.
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
    added_mass_coefficient: float = 1.0


class Scene(eqx.Module):
    """One net problem. ``netting`` or ``bars`` may be None; names are for messages and reports."""

    nodes: Nodes
    netting: Netting | None = None
    bars: Bars | None = None
    environment: Environment = dataclasses.field(default_factory=Environment)
    hinges: Hinges | None = None
    hexagonal: HexagonalNetting | None = None
    catch: Catch | None = None
    enclosure: Enclosure | None = None
    panel_names: tuple = eqx.field(static=True, default=())
    cable_names: tuple = eqx.field(static=True, default=())

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


# --------------------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------------------


def _panel_name(scene, family, e):
    """Name of the panel of element e of a netting family (for messages)."""
    p = int(np.asarray(family.panel)[e])
    return scene.panel_names[p] if p < len(scene.panel_names) else f"panel {p}"


def _check_triangles(family, n, culprit, what):
    """Vertex indices within 0..n-1, finite twine coordinates, d != 0 (eq. 4.7); returns the (E, 3) indices."""
    tri = np.asarray(family.vertices)
    if tri.ndim != 2 or tri.shape[1] != 3:
        raise SceneError(f"{what}: vertices must have shape (E, 3) (three nodes per triangle), got {tri.shape}")
    _check_indices(tri, f"{what}: vertices")
    if tri.size and (tri.min() < 0 or tri.max() >= n):
        e = int(np.argwhere((tri < 0) | (tri >= n))[0][0])
        raise SceneError(f"{culprit(e)}: vertex index outside 0..{n - 1}")
    twice = np.flatnonzero((tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 0] == tri[:, 2]))
    if twice.size:
        e = int(twice[0])
        raise SceneError(f"{culprit(e)}: a node appears twice among its vertices {tri[e].tolist()}")
    _check_shapes(family, what, {"uv": (len(tri), 3, 2)})
    uv = np.asarray(family.uv, dtype=float)
    _check_finite(uv, f"{what} twine coordinates")
    d = (uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1]) - (uv[:, 2, 0] - uv[:, 0, 0]) * (uv[:, 1, 1] - uv[:, 0, 1])
    flat = np.flatnonzero(np.abs(d) < 1e-12)
    if flat.size:
        e = int(flat[0])
        raise SceneError(f"{culprit(e)}: collinear twine coordinates (d = {d[e]:.3g}), vertices {tri[e].tolist()} "
                         f"with (U, V) = {uv[e].tolist()}")
    return tri


def _cable_name(scene, b):
    c = int(np.asarray(scene.bars.cable)[b])
    return scene.cable_names[c] if c < len(scene.cable_names) else f"cable {c}"


def _check_finite(values, what):
    values = np.asarray(values, dtype=float)
    bad = np.argwhere(~np.isfinite(values))
    if bad.size:
        raise SceneError(f"{what}: non-finite value at index {tuple(int(i) for i in bad[0])}")


def _check_positive(values, what, culprit, strict=True):
    values = np.asarray(values, dtype=float)
    infinite = np.flatnonzero(np.isinf(values))
    if infinite.size:  # inf passes the sign test but makes every force NaN
        i = int(infinite[0])
        raise SceneError(f"{culprit(i)}: {what} must be finite, got {float(values[i])!r}")
    bad = np.flatnonzero(~(values > 0) if strict else ~(values >= 0))
    if bad.size:
        i = int(bad[0])
        sign = "> 0" if strict else ">= 0"
        raise SceneError(f"{culprit(i)}: {what} must be {sign}, got {float(values[i])!r}")


def _per_axis(nodes, name, n):
    """The nodes' field ``name`` as an (N, 3) float array (per node, along x, y, z), or a SceneError."""
    arr = np.asarray(getattr(nodes, name), dtype=float)
    if arr.shape != (n, 3):
        raise SceneError(f"nodes: {name} must have shape ({n}, 3) (per node, along x, y, z), got {arr.shape}")
    return arr


def _check_shapes(family, what, shapes):
    """Every field of ``family`` named in ``shapes`` (field -> expected shape) that is not None has that shape:
    per-element arrays of the wrong length would otherwise fail inside the compiled program, unnamed."""
    for name, shape in shapes.items():
        value = getattr(family, name)
        if value is None:
            continue
        got = np.shape(value)
        if got != shape:
            raise SceneError(f"{what}: {name} must have shape {shape}, got {got}")


def _check_indices(values, what):
    """Node indices must be integers (a float index is a mistake, not a node)."""
    values = np.asarray(values)
    if values.size and not np.issubdtype(values.dtype, np.integer):
        raise SceneError(f"{what} must be integer node indices, got dtype {values.dtype}")


def _scalar(value, what):
    """A scalar parameter as a float, or a SceneError naming it (a string or an array where a number belongs)."""
    try:
        return float(value)
    except (TypeError, ValueError):
        raise SceneError(f"{what} must be a number, got {value!r}") from None


def _vector(value, what):
    """A (3,) finite vector, or a SceneError naming it."""
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        v = None
    if v is None or v.shape != (3,) or not np.all(np.isfinite(v)):
        raise SceneError(f"{what} must be 3 finite numbers (x, y, z), got {value!r}")
    return v


def _axis_culprit(arr_index):
    node, axis = divmod(int(arr_index), 3)
    return f"node {node}", "xyz"[axis]


def _check_node_bodies(nodes, n):
    """Box-shaped node bodies (FEMNET node types): both fields or none, finite, sizes and Cd >= 0."""
    length, cd = nodes.drag_length, nodes.drag_coefficient
    if (length is None) != (cd is None):
        missing = "drag_coefficient" if cd is None else "drag_length"
        raise SceneError(f"nodes: drag_length and drag_coefficient go together (node drag of a box-shaped "
                         f"body); {missing} is missing")
    if length is None:
        return
    for name, allow_negative_z in (("drag_length", True), ("drag_coefficient", False)):
        arr = _per_axis(nodes, name, n)
        bad = np.flatnonzero(~np.isfinite(arr))
        if bad.size:
            node, axis = _axis_culprit(bad[0])
            raise SceneError(f"{node}: {name} along {axis} is not finite ({arr.ravel()[bad[0]]!r})")
        negative = arr < 0
        if allow_negative_z:  # a body below its node (a sinker) has a negative height, as in FEMNET
            negative[:, 2] = False
        bad = np.flatnonzero(negative)
        if bad.size:
            node, axis = _axis_culprit(bad[0])
            what = "size" if name == "drag_length" else "drag coefficient"
            raise SceneError(f"{node}: {name} ({what}) along {axis} must be >= 0, got {arr.ravel()[bad[0]]!r}")


def _check_limits(scene, n):
    """Limits per axis (sea bed): both fields or none, senses in {-1, 0, 1}, finite limits where used, and
    an environment that makes them act (stiffness > 0; friction needs a coordinate axis as vertical)."""
    nodes, env = scene.nodes, scene.environment
    for name in ("bottom_stiffness", "bottom_friction", "bottom_band"):
        value = getattr(env, name)
        if not (np.isfinite(value) and value >= 0):
            raise SceneError(f"environment: {name} must be finite and >= 0, got {value!r}")
    limit, sense = nodes.limit, nodes.limit_sense
    if (limit is None) != (sense is None):
        missing = "limit_sense" if sense is None else "limit"
        raise SceneError(f"nodes: limit and limit_sense go together (a floor or ceiling per axis); {missing} is missing")
    if limit is None:
        return
    sense_arr = _per_axis(nodes, "limit_sense", n)
    bad = np.flatnonzero(~np.isin(sense_arr, (-1.0, 0.0, 1.0)))
    if bad.size:
        node, axis = _axis_culprit(bad[0])
        raise SceneError(f"{node}: limit_sense along {axis} must be +1 (floor: stay above the limit), -1 "
                         f"(ceiling: stay below) or 0 (none), got {sense_arr.ravel()[bad[0]]!r}")
    limit_arr = _per_axis(nodes, "limit", n)
    bad = np.flatnonzero((sense_arr != 0) & ~np.isfinite(limit_arr))
    if bad.size:
        node, axis = _axis_culprit(bad[0])
        raise SceneError(f"{node}: limit along {axis} is not finite ({limit_arr.ravel()[bad[0]]!r}) but its sense is "
                         f"{int(sense_arr.ravel()[bad[0]])}")
    used = np.flatnonzero(sense_arr != 0)
    if used.size and not env.bottom_stiffness > 0:
        node, axis = _axis_culprit(used[0])
        raise SceneError(f"{node}: a limit along {axis} needs environment bottom_stiffness > 0 (N/m) to act, got "
                         f"{env.bottom_stiffness!r}")
    if used.size and env.bottom_friction > 0 and env.current_speed > 0 and bottom_axis(env) is None:
        raise SceneError(f"environment: sea-bed friction (bottom_friction {env.bottom_friction!r}) needs 'up' along a "
                         f"coordinate axis (the sea bed is a limit along one axis), got {env.up!r}")


def bottom_axis(env):
    """(axis, floor sense) of the sea bed: the coordinate axis along ``up`` and the limit sense that forbids
    going down along it (+1 when up is +z, as in FEMNET); None when ``up`` is along no coordinate axis."""
    up = np.asarray(env.up, dtype=float)
    axis = int(np.argmax(np.abs(up)))
    if abs(abs(up[axis]) - 1.0) > 1e-12:
        return None
    return axis, int(np.sign(up[axis]))


def has_free_surface(scene) -> bool:
    """Whether the scene has a free surface (``environment.surface_level`` not NaN)."""
    return bool(np.isfinite(scene.environment.surface_level))


def _check_environment(env):
    """Scalars finite numbers (surface_level NaN for none), unit 'up' and current direction, waves or None."""
    gravity, rho, speed = (_scalar(getattr(env, k), f"environment: {k}") for k in ("gravity", "water_density",
                                                                                 "current_speed"))
    if not np.isfinite(gravity) or gravity < 0:
        raise SceneError(f"environment: gravity must be finite and >= 0, got {env.gravity!r}")
    if not (np.isfinite(rho) and rho > 0):
        raise SceneError(f"environment: water density must be > 0, got {env.water_density!r}")
    if abs(np.linalg.norm(_vector(env.up, "environment: 'up'")) - 1.0) > 1e-9:
        raise SceneError(f"environment: 'up' must be a unit vector, got {env.up!r}")
    if not (np.isfinite(speed) and speed >= 0):
        raise SceneError(f"environment: current_speed must be finite and >= 0, got {env.current_speed!r}")
    direction = _vector(env.current_direction, "environment: current_direction")
    if speed > 0 and abs(np.linalg.norm(direction) - 1.0) > 1e-9:
        raise SceneError(f"environment: current_direction must be a unit vector, got {env.current_direction!r}")
    if np.isinf(_scalar(env.surface_level, "environment: surface_level")):
        raise SceneError(f"environment: surface_level must be a finite height (m), or NaN for no free surface, got "
                         f"{env.surface_level!r}")
    if not np.isfinite(_scalar(env.time, "environment: time")):
        raise SceneError(f"environment: time must be finite (s), got {env.time!r}")
    ca = _scalar(env.added_mass_coefficient, "environment: added_mass_coefficient")
    if not (np.isfinite(ca) and ca >= 0):
        raise SceneError(f"environment: added_mass_coefficient must be finite and >= 0, got {env.added_mass_coefficient!r}")
    if env.waves is not None and not (hasattr(env.waves, "velocity") and hasattr(env.waves, "acceleration")):
        raise SceneError(f"environment: waves must be None or waves such as jaxnet.waves.Airy, got {env.waves!r}")


def _check_catch(scene):
    """The catch's numbers (finite volume > 0, Cd >= 0, symmetry >= 1, unit axis, finite centre) and netting to
    hold it. A volume larger than the net holds is allowed: the front then sits at the opening and the whole net
    carries the pressure (FEMNET's behaviour; :func:`jaxnet.catch.catch_front` reports ``holds`` False)."""
    catch = scene.catch
    volume, cd, symmetry = (_scalar(getattr(catch, k), f"catch: {k}") for k in ("volume", "drag_coefficient", "symmetry"))
    if not (np.isfinite(volume) and volume > 0):
        raise SceneError(f"catch: volume must be finite and > 0 (m³), got {catch.volume!r}")
    if not (np.isfinite(cd) and cd >= 0):
        raise SceneError(f"catch: drag_coefficient must be finite and >= 0, got {catch.drag_coefficient!r}")
    if not (np.isfinite(symmetry) and symmetry >= 1):
        raise SceneError(f"catch: symmetry (copies of the modelled part) must be finite and >= 1, got {catch.symmetry!r}")
    if abs(np.linalg.norm(_vector(catch.axis, "catch: axis")) - 1.0) > 1e-9:
        raise SceneError(f"catch: axis must be a unit vector, got {catch.axis!r}")
    _vector(catch.center, "catch: center")
    if scene.netting is None:
        raise SceneError("catch: the scene has no diamond-mesh netting to hold the catch")


def _check_enclosure(enclosure):
    _vector(enclosure.center, "enclosure: center")
    if abs(np.linalg.norm(_vector(enclosure.axis, "enclosure: axis")) - 1.0) > 1e-9:
        raise SceneError(f"enclosure: axis must be a unit vector, got {enclosure.axis!r}")


def validate(scene: Scene) -> None:
    """Raise :class:`SceneError` if the scene cannot be solved; the message names the culprit."""
    nodes = scene.nodes
    pos = np.asarray(nodes.position, dtype=float)
    if pos.ndim != 2 or pos.shape[1] != 3:
        raise SceneError(f"node positions must have shape (N, 3), got {pos.shape}")
    n = scene.n_nodes
    _check_shapes(nodes, "nodes", {"fixed": (n, 3), "mass": (n,), "volume": (n,), "force": (n, 3), "drag_area": (n,),
                                   "size": (n,), "added_mass": (n, 3)})
    for name in ("position", "force", "mass", "volume"):
        arr = np.asarray(getattr(nodes, name), dtype=float)
        bad = np.argwhere(~np.isfinite(arr))
        if bad.size:
            raise SceneError(f"node {int(bad[0][0])}: {name} is not finite ({float(arr[tuple(bad[0])])!r})")
    _check_positive(nodes.mass, "mass", lambda i: f"node {i}", strict=False)
    _check_positive(nodes.volume, "displaced volume", lambda i: f"node {i}", strict=False)
    env = scene.environment
    _check_environment(env)
    depth, factor = np.asarray(env.profile_depth, dtype=float), np.asarray(env.profile_factor, dtype=float)
    if depth.shape != factor.shape or depth.ndim != 1:
        raise SceneError(f"environment: profile_depth and profile_factor must be 1-D of one length, got "
                         f"{depth.shape} and {factor.shape}")
    if not (np.all(np.isfinite(depth)) and np.all(np.isfinite(factor)) and np.all(np.diff(depth) > 0)):
        raise SceneError("environment: the current profile needs finite factors at strictly increasing depths")
    for name in ("drag_area", "size"):
        if getattr(nodes, name) is not None:
            _check_positive(getattr(nodes, name), name, lambda i: f"node {i}", strict=False)
    _check_node_bodies(nodes, n)
    _check_limits(scene, n)

    used = np.zeros(n, dtype=bool)
    edges = []
    if scene.netting is not None:
        net = scene.netting
        culprit = lambda e: f"triangle {e} ({_panel_name(scene, net, e)})"  # noqa: E731
        tri = _check_triangles(net, n, culprit, "netting")
        per_triangle = {f.name: (len(tri),) for f in dataclasses.fields(Netting) if f.name not in ("vertices", "uv")}
        _check_shapes(net, "netting", per_triangle)
        _check_positive(net.l0, "unstretched twine length l0", culprit)
        _check_positive(net.ea_traction, "traction stiffness EA", culprit, strict=False)
        _check_positive(net.ea_compression, "compression stiffness EA", culprit, strict=False)
        _check_positive(net.diameter, "twine diameter", culprit, strict=False)
        _check_positive(net.density, "volumic mass", culprit, strict=False)
        for name in ("cd_normal", "tangential_ratio", "opening_stiffness", "knot_size", "knot_stiffness", "bending_stiffness"):
            if getattr(net, name) is not None:
                _check_positive(getattr(net, name), name.replace("_", " "), culprit, strict=False)
        if net.rest_angle is not None:
            a = np.asarray(net.rest_angle, dtype=float)
            bad = np.flatnonzero(~((a > 0) & (a <= np.pi / 2)))
            if bad.size:
                raise SceneError(f"{culprit(int(bad[0]))}: rest half opening angle must be in (0, pi/2] rad, got {a[bad[0]]!r}")
        from jaxnet.terms import drag, knot  # the terms read the scene's helpers: imported when needed

        for field, kind, names in (("drag_model", "drag model", [m.name for m in drag.NETTING_DRAG_MODELS]),
                                   ("knot_form", "knot contact form", list(knot.FORMS))):
            if getattr(net, field) is not None:
                m = np.asarray(getattr(net, field))
                bad = np.flatnonzero(~np.isin(m, np.arange(len(names))))
                if bad.size:
                    codes = ", ".join(f"{code} ({name})" for code, name in enumerate(names))
                    raise SceneError(f"{culprit(int(bad[0]))}: {kind} code must be one of {codes}, got {m[bad[0]]!r}")
        used[tri.ravel()] = True
        edges += [tri[:, [0, 1]], tri[:, [1, 2]]]
    if scene.hexagonal is not None:
        hexa = scene.hexagonal
        culprit = lambda e: f"hexagonal triangle {e} ({_panel_name(scene, hexa, e)})"  # noqa: E731
        tri = _check_triangles(hexa, n, culprit, "hexagonal")
        _check_shapes(hexa, "hexagonal", {"l0": (len(tri), 3), "ea_traction": (len(tri), 3),
                                          "ea_compression": (len(tri), 3), "diameter": (len(tri),),
                                          "density": (len(tri),), "panel": (len(tri),)})
        for name in ("l0", "ea_traction", "ea_compression"):
            values = np.asarray(getattr(hexa, name), dtype=float).min(axis=1)
            _check_positive(values, name, culprit, strict=(name == "l0"))
        _check_positive(hexa.diameter, "twine diameter", culprit, strict=False)
        _check_positive(hexa.density, "volumic mass", culprit, strict=False)
        # say so rather than leave hexagonal netting silently without these loads
        if env.current_speed > 0:
            raise SceneError(f"{culprit(0)}: hexagonal netting has no drag model yet; it cannot be put in a current")
        if has_free_surface(scene):
            raise SceneError(f"{culprit(0)}: hexagonal netting has no free-surface weight yet; use a scene without a "
                             "free surface (surface_level NaN)")
        used[tri.ravel()] = True
        edges += [tri[:, [0, 1]], tri[:, [1, 2]]]
    if scene.bars is not None:
        bars = scene.bars
        ends = np.asarray(bars.ends)
        if ends.ndim != 2 or ends.shape[1] != 2:
            raise SceneError(f"bars: ends must have shape (B, 2) (two nodes per bar), got {ends.shape}")
        _check_indices(ends, "bars: ends")
        _check_shapes(bars, "bars", {f.name: (len(ends),) for f in dataclasses.fields(Bars) if f.name != "ends"})
        if ends.size and (ends.min() < 0 or ends.max() >= n):
            b = int(np.argwhere((ends < 0) | (ends >= n))[0][0])
            raise SceneError(f"bar {b} ({_cable_name(scene, b)}): end node index outside 0..{n - 1}")
        culprit = lambda b: f"bar {b} ({_cable_name(scene, b)})"  # noqa: E731
        _check_positive(bars.rest_length, "unstretched length", culprit)
        _check_positive(bars.ea_traction, "traction stiffness EA", culprit, strict=False)
        _check_positive(bars.ea_compression, "compression stiffness EA", culprit, strict=False)
        _check_positive(bars.diameter, "diameter", culprit, strict=False)
        _check_positive(bars.density, "volumic mass", culprit, strict=False)
        for name in ("cd_normal", "tangential_ratio"):
            if getattr(bars, name) is not None:
                _check_positive(getattr(bars, name), name.replace("_", " "), culprit, strict=False)
        same = np.flatnonzero(ends[:, 0] == ends[:, 1])
        if same.size:
            raise SceneError(f"{culprit(int(same[0]))}: both ends on node {ends[same[0], 0]}")
        used[ends.ravel()] = True
        edges.append(ends)

    if scene.catch is not None:
        _check_catch(scene)
    if scene.enclosure is not None:
        _check_enclosure(scene.enclosure)

    fixed = np.asarray(nodes.fixed, dtype=bool)
    free_unused = np.flatnonzero(~used & ~fixed.all(axis=1))
    if free_unused.size:
        raise SceneError(f"node {int(free_unused[0])} belongs to no element and is not fixed: nothing holds it")
    if not fixed.any():
        raise SceneError("no node is fixed: the net is free to drift as a rigid body (fix at least one node)")
    floating = has_free_surface(scene)
    for axis, label in enumerate("xyz"):
        # a net at the free surface is held vertically by its buoyancy (waterplane stiffness)
        if floating and abs(float(np.asarray(env.up)[axis])) > 1e-12:
            continue
        if not fixed[:, axis].any():
            raise SceneError(f"no node is fixed along {label}: the net is free to translate along {label}")
    # Every connected piece of the net must be held somewhere, or it drifts as a rigid body.
    if edges:
        e = np.concatenate(edges)
        graph = sp.coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n))
        n_comp, label = sp.csgraph.connected_components(graph, directed=False)
        if n_comp > 1:
            held = np.zeros(n_comp, dtype=bool)
            held[label[fixed.any(axis=1)]] = True
            loose = np.flatnonzero(~held)
            if loose.size:
                members = np.flatnonzero(label == loose[0])
                raise SceneError(
                    f"nodes {members[:5].tolist()}{'...' if members.size > 5 else ''} ({members.size} nodes) "
                    "form a piece of net connected to no fixed node: it is free to drift as a rigid body"
                )
