"""The checks of a scene before anything is compiled: :func:`validate` raises :class:`~jaxnet.scene.SceneError`
naming the culprit (the node, the triangle and its panel, the bar and its cable, the parameter) and what is
wrong with it: shapes, indices, finite and signed values (a traction stiffness EA > 0: an element without it
holds nothing, and the net is a mechanism that a solve would only report as no step lowering the energy), the
codes of the netting's drag model and knot law (the terms' own tables), a net held somewhere in every
direction, every piece of it connected to a fixed node.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import scipy.sparse as sp

from jaxnet.scene import FLOATING, Bars, Netting, Scene, SceneError, bottom_axis, has_free_surface
from jaxnet.terms import drag, knot

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


def _check_symmetry_planes(scene):
    """Mirror planes: (axis 0, 1 or 2, finite position) pairs, one per axis at most."""
    planes = scene.symmetry_planes
    if not isinstance(planes, tuple) or any(not (isinstance(p, tuple) and len(p) == 2 and p[0] in (0, 1, 2)
                                                 and np.isfinite(p[1])) for p in planes):
        raise SceneError(f"symmetry_planes: expected ((axis 0, 1 or 2, position m), ...), got {planes!r}")
    if len({axis for axis, _ in planes}) != len(planes):
        raise SceneError(f"symmetry_planes: one plane per axis at most, got {planes!r}")


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
    if not isinstance(env.bottom_moving, (bool, np.bool_)):
        raise SceneError(f"environment: bottom_moving says whether the sea bed slides under the net (True or False), "
                         f"got {env.bottom_moving!r}")
    unknown = [f for f in env.floating if f not in FLOATING]
    if unknown or not isinstance(env.floating, tuple):
        raise SceneError(f"environment: floating names the families that feel the free surface, a tuple among "
                         f"{FLOATING}; got {env.floating!r}")
    if not np.isfinite(_scalar(env.time, "environment: time")):
        raise SceneError(f"environment: time must be finite (s), got {env.time!r}")
    ca = _scalar(env.added_mass_coefficient, "environment: added_mass_coefficient")
    if not (np.isfinite(ca) and ca >= 0):
        raise SceneError(f"environment: added_mass_coefficient must be finite and >= 0, got {env.added_mass_coefficient!r}")
    if env.waves is not None and not (hasattr(env.waves, "velocity") and hasattr(env.waves, "acceleration")):
        raise SceneError(f"environment: waves must be None or waves such as jaxnet.water.waves.Airy, got {env.waves!r}")


def _check_catch(scene):
    """The catch's numbers (finite volume > 0, Cd >= 0, symmetry >= 1, unit axis, finite centre) and netting to
    hold it. A volume larger than the net holds is allowed: the front then sits at the opening and the whole net
    carries the pressure (FEMNET's behaviour; :func:`jaxnet.model.catch.catch_front` reports ``holds`` False)."""
    catch = scene.catch
    volume, cd, symmetry = (_scalar(getattr(catch, k), f"catch: {k}") for k in ("volume", "drag_coefficient", "symmetry"))
    if not (np.isfinite(volume) and volume > 0):
        raise SceneError(f"catch: volume must be finite and > 0 (m³), got {catch.volume!r}")
    if not (np.isfinite(cd) and cd >= 0):
        raise SceneError(f"catch: drag_coefficient must be finite and >= 0, got {catch.drag_coefficient!r}")
    if not (np.isfinite(symmetry) and symmetry >= 1):
        raise SceneError(f"catch: symmetry (copies of the modelled part) must be finite and >= 1, got {catch.symmetry!r}")
    density = _scalar(catch.density, "catch: density")
    if not (np.isfinite(density) and density >= 0):
        raise SceneError(f"catch: density must be finite and >= 0 (kg/m³; > 0 for a gravity catch), got {catch.density!r}")
    if abs(np.linalg.norm(_vector(catch.axis, "catch: axis")) - 1.0) > 1e-9:
        raise SceneError(f"catch: axis must be a unit vector, got {catch.axis!r}")
    _vector(catch.center, "catch: center")
    if scene.netting is None:
        raise SceneError("catch: the scene has no diamond-mesh netting to hold the catch")


def _check_panel_catches(scene):
    """The panel catches' numbers (finite volumes > 0, Cd >= 0, symmetry >= 1, unit axis), one entry per panel
    naming a catch or -1, every catch held by some panel, and oriented netting to hold them."""
    pc = scene.panel_catches
    volume = np.asarray(pc.volume, dtype=float)
    if volume.ndim != 1 or volume.size == 0:
        raise SceneError(f"panel_catches: volume must be a list of one volume per catch (m³), got {pc.volume!r}")
    bad = np.flatnonzero(~(np.isfinite(volume) & (volume > 0)))
    if bad.size:
        raise SceneError(f"panel_catches: catch {int(bad[0])}: volume must be finite and > 0 (m³), got {volume[bad[0]]!r}")
    cd, symmetry = _scalar(pc.drag_coefficient, "panel_catches: drag_coefficient"), _scalar(pc.symmetry, "panel_catches: symmetry")
    if not (np.isfinite(cd) and cd >= 0):
        raise SceneError(f"panel_catches: drag_coefficient must be finite and >= 0, got {pc.drag_coefficient!r}")
    if not (np.isfinite(symmetry) and symmetry >= 1):
        raise SceneError(f"panel_catches: symmetry (copies of the modelled part) must be finite and >= 1, got {pc.symmetry!r}")
    if abs(np.linalg.norm(_vector(pc.axis, "panel_catches: axis")) - 1.0) > 1e-9:
        raise SceneError(f"panel_catches: axis must be a unit vector, got {pc.axis!r}")
    if scene.netting is None:
        raise SceneError("panel_catches: the scene has no diamond-mesh netting to hold the catches")
    holder = np.asarray(pc.panel_catch)
    panels = int(np.max(np.asarray(scene.netting.panel), initial=-1)) + 1
    if holder.ndim != 1 or holder.size < panels or not np.issubdtype(holder.dtype, np.integer):
        raise SceneError(f"panel_catches: panel_catch must hold one integer per panel ({panels} at least), got "
                         f"{holder.size} of dtype {holder.dtype}")
    wrong = np.flatnonzero((holder < -1) | (holder >= volume.size))
    if wrong.size:
        raise SceneError(f"panel_catches: panel {int(wrong[0])} holds catch {int(holder[wrong[0]])}, not among the "
                         f"{volume.size} catches (or -1 for none)")
    held = set(holder[np.asarray(scene.netting.panel)].tolist())
    empty = [k for k in range(volume.size) if k not in held]
    if empty:
        raise SceneError(f"panel_catches: catch {empty[0]} is held by no netting panel")
    if scene.netting.outward is None:
        raise SceneError("panel_catches: the netting has no outward side (Netting.outward), which orients the "
                         "catches' pressure; Net.panel_catch sets it")


def _check_enclosure(enclosure):
    _vector(enclosure.center, "enclosure: center")
    if abs(np.linalg.norm(_vector(enclosure.axis, "enclosure: axis")) - 1.0) > 1e-9:
        raise SceneError(f"enclosure: axis must be a unit vector, got {enclosure.axis!r}")


def _check_cable_joints(scene, n):
    """Joints of stiff cables (:class:`~jaxnet.scene.CableJoints`): three distinct nodes, unstretched bar lengths
    > 0, EI >= 0 and a neutral turning angle in [0, pi]; a joint is named by its cables."""
    joints = scene.cable_joints
    vertices = np.asarray(joints.vertices)
    if vertices.ndim != 2 or vertices.shape[1] != 3:
        raise SceneError(f"cable joints: vertices must have shape (J, 3), got {vertices.shape}")
    _check_indices(vertices, "cable joints: vertices")
    count = len(vertices)
    _check_shapes(joints, "cable joints", {"rest_length": (count, 2), "stiffness": (count,), "rest_angle": (count,),
                                           "cable": (count, 2)})

    def culprit(j):
        names = [scene.cable_names[c] if c < len(scene.cable_names) else f"cable {c}"
                 for c in np.asarray(joints.cable)[j].tolist()]
        where = f"of '{names[0]}'" if names[0] == names[1] else f"between '{names[0]}' and '{names[1]}'"
        return f"cable joint {j} {where}"

    if vertices.size and (vertices.min() < 0 or vertices.max() >= n):
        j = int(np.argwhere((vertices < 0) | (vertices >= n))[0][0])
        raise SceneError(f"{culprit(j)}: node index outside 0..{n - 1}")
    repeated = np.flatnonzero((vertices[:, 0] == vertices[:, 1]) | (vertices[:, 1] == vertices[:, 2])
                              | (vertices[:, 0] == vertices[:, 2]))
    if repeated.size:
        raise SceneError(f"{culprit(int(repeated[0]))}: nodes {vertices[repeated[0]].tolist()} are not three distinct nodes")
    _check_positive(np.asarray(joints.rest_length, dtype=float).min(axis=1), "unstretched bar length", culprit)
    _check_positive(joints.stiffness, "bending stiffness EI", culprit, strict=False)
    angle = np.asarray(joints.rest_angle, dtype=float)
    bad = np.flatnonzero(~((angle >= 0.0) & (angle <= np.pi)))
    if bad.size:
        raise SceneError(f"{culprit(int(bad[0]))}: neutral turning angle must be in [0, pi] rad, got {angle[bad[0]]!r}")


def validate(scene: Scene, dynamic: bool = False) -> None:
    """Raise :class:`SceneError` if the scene cannot be solved; the message names the culprit. ``dynamic``: for
    a run in time, where the nodes' masses hold a net that nothing fixes (along an axis, or at all): the
    checks that a static equilibrium is held are left out. The checks run in this order: the nodes, the
    environment, each element family (the nodes each uses and the edges joining them), the cable joints and
    catches, and then that every node and every piece of the net is held."""
    if not isinstance(scene, Scene):
        raise TypeError(f"expected a jaxnet Scene, got a {type(scene).__name__}: a Case is run by "
                        "jaxnet.solve_static(case) or jaxnet.simulate(case) (jaxnet.run), its scene is case.scene")
    n = _check_nodes(scene)
    _check_environment(scene.environment)
    _check_symmetry_planes(scene)
    _check_current_profile(scene.environment)
    _check_node_bodies(scene.nodes, n)
    _check_limits(scene, n)
    used = np.zeros(n, dtype=bool)
    edges = []
    for family in (_check_netting, _check_hexagonal, _check_bars):
        nodes_of_elements = family(scene, n)
        if nodes_of_elements is not None:
            elements, family_edges = nodes_of_elements
            used[elements.ravel()] = True
            edges += family_edges
    if scene.cable_joints is not None:
        _check_cable_joints(scene, n)
    if scene.catch is not None:
        _check_catch(scene)
    if scene.panel_catches is not None:
        _check_panel_catches(scene)
    if scene.enclosure is not None:
        _check_enclosure(scene.enclosure)
    _check_held(scene, used, edges, dynamic)


def _check_nodes(scene):
    """The nodes' arrays: shapes, finite values, masses and volumes >= 0. Returns the number of nodes."""
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
    for name in ("drag_area", "size"):
        if getattr(nodes, name) is not None:
            _check_positive(getattr(nodes, name), name, lambda i: f"node {i}", strict=False)
    return n


def _check_current_profile(env):
    """The current's profile: factors at strictly increasing depths, finite, of one length."""
    depth, factor = np.asarray(env.profile_depth, dtype=float), np.asarray(env.profile_factor, dtype=float)
    if depth.shape != factor.shape or depth.ndim != 1:
        raise SceneError(f"environment: profile_depth and profile_factor must be 1-D of one length, got "
                         f"{depth.shape} and {factor.shape}")
    if not (np.all(np.isfinite(depth)) and np.all(np.isfinite(factor)) and np.all(np.diff(depth) > 0)):
        raise SceneError("environment: the current profile needs finite factors at strictly increasing depths")


def _check_netting(scene, n):
    """The netting's triangles and their parameters; (triangles, edges) or None without netting."""
    if scene.netting is None:
        return None
    net = scene.netting
    culprit = lambda e: f"triangle {e} ({_panel_name(scene, net, e)})"  # noqa: E731
    tri = _check_triangles(net, n, culprit, "netting")
    per_triangle = {f.name: (len(tri),) for f in dataclasses.fields(Netting) if f.name not in ("vertices", "uv")}
    _check_shapes(net, "netting", per_triangle)
    _check_positive(net.l0, "unstretched twine length l0", culprit)
    _check_positive(net.ea_traction, "traction stiffness EA", culprit)
    _check_positive(net.ea_compression, "compression stiffness EA", culprit, strict=False)
    _check_positive(net.diameter, "twine diameter", culprit, strict=False)
    _check_positive(net.density, "volumic mass", culprit, strict=False)
    for name in ("cd_normal", "tangential_ratio", "opening_stiffness", "knot_size", "knot_stiffness", "bending_stiffness",
                 "tarp_cd"):
        if getattr(net, name) is not None:
            _check_positive(getattr(net, name), name.replace("_", " "), culprit, strict=False)
    if net.rest_angle is not None:
        a = np.asarray(net.rest_angle, dtype=float)
        bad = np.flatnonzero(~((a > 0) & (a <= np.pi / 2)))
        if bad.size:
            raise SceneError(f"{culprit(int(bad[0]))}: rest half opening angle must be in (0, pi/2] rad, got {a[bad[0]]!r}")
    for field, kind, names in (("drag_model", "drag model", [m.name for m in drag.NETTING_DRAG_MODELS]),
                               ("knot_form", "knot contact form", list(knot.FORMS))):
        if getattr(net, field) is not None:
            m = np.asarray(getattr(net, field))
            bad = np.flatnonzero(~np.isin(m, np.arange(len(names))))
            if bad.size:
                codes = ", ".join(f"{code} ({name})" for code, name in enumerate(names))
                raise SceneError(f"{culprit(int(bad[0]))}: {kind} code must be one of {codes}, got {m[bad[0]]!r}")
    return tri, [tri[:, [0, 1]], tri[:, [1, 2]]]


def _check_hexagonal(scene, n):
    """The hexagonal netting's triangles and their parameters; (triangles, edges) or None without it."""
    if scene.hexagonal is None:
        return None
    hexa = scene.hexagonal
    culprit = lambda e: f"hexagonal triangle {e} ({_panel_name(scene, hexa, e)})"  # noqa: E731
    tri = _check_triangles(hexa, n, culprit, "hexagonal")
    _check_shapes(hexa, "hexagonal", {"l0": (len(tri), 3), "ea_traction": (len(tri), 3),
                                      "ea_compression": (len(tri), 3), "diameter": (len(tri),),
                                      "density": (len(tri),), "panel": (len(tri),)})
    for name in ("l0", "ea_traction", "ea_compression"):
        values = np.asarray(getattr(hexa, name), dtype=float).min(axis=1)   # the smallest of its families
        _check_positive(values, name, culprit, strict=(name != "ea_compression"))
    _check_positive(hexa.diameter, "twine diameter", culprit, strict=False)
    _check_positive(hexa.density, "volumic mass", culprit, strict=False)
    # say so rather than leave hexagonal netting silently without this load
    if scene.environment.current_speed > 0:
        raise SceneError(f"{culprit(0)}: hexagonal netting has no drag model yet; it cannot be put in a current")
    return tri, [tri[:, [0, 1]], tri[:, [1, 2]]]


def _check_bars(scene, n):
    """The bars' ends and parameters; (ends, [ends]) or None without bars."""
    if scene.bars is None:
        return None
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
    _check_positive(bars.ea_traction, "traction stiffness EA", culprit)
    _check_positive(bars.ea_compression, "compression stiffness EA", culprit, strict=False)
    _check_positive(bars.diameter, "diameter", culprit, strict=False)
    _check_positive(bars.density, "volumic mass", culprit, strict=False)
    for name in ("cd_normal", "tangential_ratio"):
        if getattr(bars, name) is not None:
            _check_positive(getattr(bars, name), name.replace("_", " "), culprit, strict=False)
    same = np.flatnonzero(ends[:, 0] == ends[:, 1])
    if same.size:
        raise SceneError(f"{culprit(int(same[0]))}: both ends on node {ends[same[0], 0]}")
    return ends, [ends]


def _check_held(scene, used, edges, dynamic):
    """Every free node belongs to an element; for a static solve, something holds the net along every axis
    and every connected piece of it (``edges``: the node pairs joined by elements) has a fixed node."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool)
    n = scene.n_nodes
    free_unused = np.flatnonzero(~used & ~fixed.all(axis=1))
    if free_unused.size:
        raise SceneError(f"node {int(free_unused[0])} belongs to no element and is not fixed: nothing holds it")
    if dynamic:
        return
    if not fixed.any():
        raise SceneError("no node is fixed: the net is free to drift as a rigid body (fix at least one node)")
    floating = has_free_surface(scene)
    for axis, label in enumerate("xyz"):
        # a net at the free surface is held vertically by its buoyancy (waterplane stiffness)
        if floating and abs(float(np.asarray(scene.environment.up)[axis])) > 1e-12:
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
