"""Scene files: a net described in JSON (``.json``) or TOML (``.toml``), read into a :class:`~jaxnet.case.Case`
(its :class:`~jaxnet.net.Net` built, with the file's solver options).

The format mirrors the Python API (see README, "Scene files"). Top-level keys::

    description  "..."                                                         free text, not read
    merge_tolerance  1e-6                       corners and cable ends closer than this (m) are one node
    environment  {gravity, water_density, up, current_speed, current_direction, profile_depth,
                  profile_factor, surface_level, bottom_stiffness, bottom_friction, bottom_band, bottom_moving,
                  time, added_mass_coefficient, floating: ["netting", "hexagonal", "bars", "nodes"],
                  waves?: {height, period, model?, direction?, depth?, phase?, ramp?}   regular waves
                        | {hs, tp, spectrum?, gamma?, spreading?, components?, band?, seed?,
                           direction?, depth?, stretching?}                       an irregular sea}
    twines       {NAME: {l0, ea, diameter, ea_compression?, density?, cd_normal?, tangential_ratio?,
                         drag_model?, opening_stiffness?, rest_angle?, knot_size?, knot_stiffness?,
                         knot_form?, bending_stiffness?, tarp_cd?}}          netting materials (diamond meshes)
    hex_twines   {NAME: {l0, ea, diameter, ea_compression?, density?}}      hexagonal-mesh netting materials
    ropes        {NAME: {ea, diameter, ea_compression?, density?, cd_normal?, tangential_ratio?,
                         bending_stiffness?}}
    panels       [{name, corners: [[x, y, z, U, V], ...], twine: NAME | {...} (or hex_twine: NAME | {...}),
                   step, numerical_twines?: {period, bars?, offset_u?, offset_v?, accuracy?, femnet_tangential?},
                   lattice?: [NU, NV]}]
    cables       [{name, rope: NAME | {...}, start?: REF, end?: REF, along?: SIDE, n_bars?, length?}]
    seams        [[SIDE, SIDE], ...]
    cable_joints [{cables: [A, B], neutral_angle?, stiffness?}]             welded cables (rad, N·m²)
    fix          [{at: REF, axes?: "xyz"}]
    symmetry_planes [{axis: "x" | "y" | "z", at?, hold?}]                   the model is part of a symmetric net
    attach       [{at: REF, mass?, volume?, force?: [fx, fy, fz], drag_area?, size?}]
    sinkers      [{at: REF, mass, density?}]
    floats       [{at: REF, buoyancy_N, mass?, size?, drag_area?}]
    bodies       [{at: REF, drag_length: [lx, ly, lz], drag_coefficient: [cx, cy, cz]}]  box drag
    limits       [{at: REF, limit: [x, y, z], sense: [sx, sy, sz]}]          sea bed, ceilings
    catch        {volume, drag_coefficient?, symmetry?, center?, axis?, density?}   fish catch in a cod-end
    panel_catches [{volume, panels: [NAME, ...], drag_coefficient?, symmetry?, axis?, center?}]
                                                                              catches held by chosen panels
    enclosure    {center: [x, y, z], axis: [ax, ay, az]}                     the net holds a volume
    solver       {tol, max_iter, max_step, ...}                               Newton options

Each key is the argument of the :class:`~jaxnet.net.Net` method of the same meaning (``Net.panel``'s
``twines=`` and ``lattice=``, ``Net.cable_joint``, ``Net.symmetry_plane``, ``Net.catch``, ``Net.enclose``, ...),
in the same units. A panel meshed as numerical twines or on a lattice of mesh diagonals needs no ``step``;
a hexagonal-mesh panel names its material with ``hex_twine`` (l0, ea and ea_compression one number or one
per twine family [l, m, n]) instead of ``twine``. Regular waves' ``model`` is "airy" (the default), "stokes2"
or "stokes3" (:class:`jaxnet.waves.Airy`, ``Stokes2``, ``Stokes3``); all waves take the environment's surface
level (0 where it has none), gravity and vertical. The solver's ``stall_window = false`` is Newton's None (no
stiffness continuation), which TOML, having no null, cannot write otherwise.

``bodies`` and ``limits`` are FEMNET's node types (see :class:`jaxnet.scene.Nodes`): *every* node of the
reference gets the body (sizes in m, a negative lz for a body hanging below its node) or the limits (m;
sense +1 floor, -1 ceiling, 0 none, per axis); a later entry replaces an earlier one on the nodes they
share. The sea bed's stiffness, friction and band are the environment's ``bottom_stiffness`` (N/m),
``bottom_friction`` and ``bottom_band`` (m); ``bottom_moving`` (true, the default, or false) says whether the bed
slides under the net at the current's velocity (a towed gear) or is still.

A REF is ``{"panel": P, "corner": k}``, ``{"panel": P, "side": k}`` (SIDE), ``{"panel": P}`` (all its
nodes), ``{"panel": P, "nearest": [x, y, z]}`` (its node nearest that start position), ``{"cable": C, "end": 0 |
1}``, ``{"cable": C}`` (all its nodes) or a point ``[x, y, z]``.
Every unknown key is an error naming where it is, so a misspelt parameter is never silently ignored.

Writing: :func:`to_dict` gives the document of a :class:`~jaxnet.net.Net` (from :meth:`Net.description
<jaxnet.net.Net.description>`), :func:`write` writes a net or a case to a .json or .toml file that :func:`read`
reads back into the same scene, to be edited (``jaxnet export``). TOML is written here: the standard library
reads it (``tomllib``) but has no writer, and the schema needs only tables, arrays of tables, inline tables,
numbers, strings, booleans and nested arrays.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import pathlib

import jax
import numpy as np

from jaxnet.case import Case, from_net
from jaxnet.mesh.twines import NumericalTwines
from jaxnet.materials import HexTwine
from jaxnet.net import CableEnd, CableNodes, CableRef, Corner, Nearest, Net, PanelRef, Rope, Side, Twine
from jaxnet.scene import FLOATING, Environment, SceneError
from jaxnet.solve.options import Newton

_TOP = {"environment", "twines", "hex_twines", "ropes", "panels", "cables", "seams", "cable_joints", "fix",
        "symmetry_planes", "attach", "sinkers", "floats", "catch", "panel_catches", "enclosure", "bodies", "limits",
        "solver", "description", "merge_tolerance"}
_STRINGS = {"drag_model", "knot_form"}  # material fields that are not numbers


def _keys(obj, allowed, where, required=()):
    if not isinstance(obj, dict):
        raise SceneError(f"{where}: expected a table/object, got {type(obj).__name__}")
    unknown = sorted(set(obj) - set(allowed))
    if unknown:
        raise SceneError(f"{where}: unknown key(s) {unknown} (allowed: {sorted(allowed)})")
    missing = [k for k in required if k not in obj]
    if missing:
        raise SceneError(f"{where}: missing key(s) {missing}")
    return obj


def _number(value, where):
    """A number of the file (not a string, a list or a boolean), or a SceneError naming where it is."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"{where}: expected a number, got {value!r}")
    return float(value)


def _integer(value, where):
    """An integer of the file (a float with no fraction will do), or a SceneError naming where it is."""
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise SceneError(f"{where}: expected an integer, got {value!r}")
    return value


def _rows(value, where, width):
    """A (rows, width) array of the file's numbers (rows: lists of ``width`` numbers), or a SceneError naming where."""
    def numbers(row):
        return isinstance(row, (list, tuple)) and len(row) == width and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)

    if not isinstance(value, (list, tuple)) or not all(numbers(row) for row in value):
        raise SceneError(f"{where}: expected rows of {width} numbers, got {value!r}")
    return np.asarray(value, dtype=float).reshape(-1, width)


def _list(value, where):
    """A 1-D array of the file's numbers, or a SceneError naming where it is."""
    if not isinstance(value, (list, tuple)):
        raise SceneError(f"{where}: expected a list of numbers, got {value!r}")
    return np.array([_number(v, f"{where}[{k}]") for k, v in enumerate(value)], dtype=float)


def _material(spec, table, cls, where):
    if isinstance(spec, str):
        if spec not in table:
            raise SceneError(f"{where}: no material named '{spec}' (defined: {sorted(table)})")
        return table[spec]
    fields = [f.name for f in dataclasses.fields(cls)]
    required = [f.name for f in dataclasses.fields(cls) if f.default is dataclasses.MISSING]
    return cls(**{k: (v if k in _STRINGS else _number(v, f"{where}.{k}"))
                  for k, v in _keys(spec, fields, where, required).items()})


def _hex_material(spec, table, where):
    """A hexagonal-mesh material (:class:`HexTwine`) of the file: a name in ``hex_twines`` or a table whose l0,
    ea and ea_compression are one number or one per twine family [l, m, n]."""
    if isinstance(spec, str):
        if spec not in table:
            raise SceneError(f"{where}: no hexagonal-mesh material named '{spec}' (defined: {sorted(table)})")
        return table[spec]
    _keys(spec, [f.name for f in dataclasses.fields(HexTwine)], where, ("l0", "ea", "diameter"))
    values = {}
    for key, value in spec.items():
        if key in ("l0", "ea", "ea_compression") and isinstance(value, (list, tuple)):
            if len(value) != 3:
                raise SceneError(f"{where}.{key}: expected one number or 3 (families l, m, n), got {value!r}")
            values[key] = tuple(float(v) for v in _list(value, f"{where}.{key}"))
        else:
            values[key] = _number(value, f"{where}.{key}")
    return HexTwine(**values)


def _numerical_twines(spec, where):
    """How a panel is meshed as numerical twines (:class:`~jaxnet.mesh.twines.NumericalTwines`) of the file."""
    fields = [f.name for f in dataclasses.fields(NumericalTwines)]
    values = {}
    for key, value in _keys(spec, fields, where, ("period",)).items():
        if key == "femnet_tangential":
            if not isinstance(value, bool):
                raise SceneError(f"{where}.femnet_tangential: expected true or false, got {value!r}")
            values[key] = value
        elif key == "bars":
            values[key] = _integer(value, f"{where}.bars")
        else:
            values[key] = _number(value, f"{where}.{key}")
    return NumericalTwines(**values)


def _solver(spec):
    """Newton's options: numbers where numbers belong, a threshold > 0, at least one iteration, a displacement
    limit > 0 (the :class:`Newton` class itself takes anything)."""
    spec = dict(_keys(spec, {f.name for f in dataclasses.fields(Newton)}, "solver"))
    for key, value in spec.items():
        if key == "stall_window" and value is False:   # TOML has no null: false says None (never)
            spec[key] = None
            continue
        if key in ("stiffness", "verbose") or (key == "stall_window" and value is None):
            continue
        integer = key in ("max_iter", "line_search", "stall_window")
        spec[key] = _integer(value, f"solver.{key}") if integer else _number(value, f"solver.{key}")
    for key, low in (("tol", 0.0), ("max_step", 0.0), ("max_iter", 0)):
        if key in spec and not spec[key] > low:
            raise SceneError(f"solver.{key} must be > {low:g}, got {spec[key]!r}")
    try:
        return Newton(**spec)
    except ValueError as err:
        raise SceneError(f"solver: {err}") from None


def _ref(spec, where):
    if isinstance(spec, (list, tuple)):
        if len(spec) != 3:
            raise SceneError(f"{where}: a point must be [x, y, z], got {spec!r}")
        return tuple(_number(v, f"{where}[{k}]") for k, v in enumerate(spec))
    _keys(spec, {"panel", "corner", "side", "nearest", "cable", "end"}, where)
    if "panel" in spec:
        if len({"corner", "side", "nearest"} & set(spec)) > 1:
            raise SceneError(f"{where}: give one of a corner, a side or a nearest point, not several")
        if "nearest" in spec:
            return Nearest(spec["panel"], tuple(float(v) for v in _triple(spec["nearest"], f"{where}.nearest")))
        if "corner" in spec:
            return Corner(spec["panel"], _integer(spec["corner"], f"{where}.corner"))
        if "side" in spec:
            return Side(spec["panel"], _integer(spec["side"], f"{where}.side"))
        return PanelRef(spec["panel"])
    if "cable" in spec:
        if "end" in spec:
            if spec["end"] not in (0, 1):
                raise SceneError(f"{where}: cable end must be 0 (start) or 1 (end), got {spec['end']!r}")
            return CableEnd(spec["cable"], int(spec["end"]))
        return CableNodes(spec["cable"])
    raise SceneError(f"{where}: a reference needs 'panel' or 'cable' (or is a point [x, y, z])")


def _triple(value, where):
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != (3,):
        raise SceneError(f"{where}: expected 3 numbers (along x, y, z), got {value!r}")
    return arr


_REGULAR = {"height", "period", "model", "direction", "depth", "phase", "ramp"}
_IRREGULAR = {"hs", "tp", "spectrum", "gamma", "spreading", "components", "band", "seed", "direction", "depth",
              "stretching"}


def _waves(spec, env_spec, where):
    """The environment's waves of the file: regular ({height, period, direction?, depth?, phase?}:
    :class:`jaxnet.waves.Airy`) or an irregular sea ({hs, tp, spectrum?, gamma?, spreading?, components?, band?,
    seed?, direction?, depth?, stretching?}: :func:`jaxnet.waves.sea_state`), on the environment's surface
    level (0 where it has none), gravity and vertical; a bad value is a SceneError naming it."""
    from jaxnet import waves

    if spec is None:
        return None
    if not isinstance(spec, dict) or not ({"height", "hs"} & set(spec)):
        raise SceneError(f"{where}: expected regular waves {{height, period, ...}} or a sea state {{hs, tp, ...}}, "
                         f"got {spec!r}")
    irregular = "hs" in spec
    _keys(spec, _IRREGULAR if irregular else _REGULAR, where, ("hs", "tp") if irregular else ("height", "period"))
    values = {}
    for key, value in spec.items():
        if key == "direction":
            values[key] = _triple(value, f"{where}.direction")
        elif key in ("spectrum", "stretching", "model"):
            if not isinstance(value, str):
                raise SceneError(f"{where}.{key}: expected a name, got {value!r}")
            values[key] = value
        elif key in ("components", "seed"):
            values[key] = _integer(value, f"{where}.{key}")
        elif key == "band":
            values[key] = tuple(_list(value, f"{where}.band"))
        else:
            values[key] = _number(value, f"{where}.{key}")
    level = env_spec.get("surface_level", float("nan"))
    common = dict(surface_level=0.0 if np.isnan(level) else level, gravity=env_spec.get("gravity", 9.81),
                  up=env_spec.get("up", (0.0, 0.0, 1.0)))
    models = {"airy": waves.Airy, "stokes2": waves.Stokes2, "stokes3": waves.Stokes3}
    model = values.pop("model", "airy")
    if model not in models:
        raise SceneError(f"{where}.model: expected one of {sorted(models)}, got {model!r}")
    try:
        if irregular:
            return waves.sea_state(**values, **common)
        return models[model](**values, **common)
    except ValueError as err:
        raise SceneError(f"{where}: {err}") from None


def from_dict(doc: dict, label: str = "scene document") -> Case:
    """The :class:`~jaxnet.case.Case` of a parsed scene document: its :class:`~jaxnet.net.Net` (built here) and
    solver options."""
    _keys(doc, _TOP, "scene")
    # the free surface's elevation over each node is the dynamics' to set, step by step, not a file's
    env_fields = {f.name for f in dataclasses.fields(Environment)} - {"surface_elevation"}
    env_spec = dict(_keys(doc.get("environment", {}), env_fields, "environment"))
    for key, value in env_spec.items():
        if key in ("up", "current_direction"):
            env_spec[key] = _triple(value, f"environment.{key}")
        elif key in ("profile_depth", "profile_factor"):
            env_spec[key] = _list(value, f"environment.{key}")
        elif key == "bottom_moving":
            if not isinstance(value, bool):
                raise SceneError(f"environment.bottom_moving: expected true or false, got {value!r}")
        elif key == "floating":
            if (not isinstance(value, list) or not all(isinstance(v, str) and v in FLOATING for v in value)
                    or len(set(value)) != len(value)):
                raise SceneError(f"environment.floating: expected a list of distinct names from {list(FLOATING)}, "
                                 f"got {value!r}")
            env_spec[key] = tuple(value)
        elif key != "waves":
            env_spec[key] = _number(value, f"environment.{key}")
    if "waves" in env_spec:
        env_spec["waves"] = _waves(env_spec["waves"], env_spec, "environment.waves")
    env = Environment(**env_spec)
    tolerance = {}
    if "merge_tolerance" in doc:
        tolerance["merge_tolerance"] = _number(doc["merge_tolerance"], "merge_tolerance")
        if not (math.isfinite(tolerance["merge_tolerance"]) and tolerance["merge_tolerance"] >= 0):
            raise SceneError(f"merge_tolerance: must be finite and >= 0 (m), got {doc['merge_tolerance']!r}")
    net = Net(environment=env, **tolerance)
    twines = {k: _material(v, {}, Twine, f"twines.{k}") for k, v in doc.get("twines", {}).items()}
    hex_twines = {k: _hex_material(v, {}, f"hex_twines.{k}") for k, v in doc.get("hex_twines", {}).items()}
    ropes = {k: _material(v, {}, Rope, f"ropes.{k}") for k, v in doc.get("ropes", {}).items()}
    for i, p in enumerate(doc.get("panels", [])):
        where = f"panels[{i}]"
        _keys(p, {"name", "corners", "twine", "hex_twine", "step", "numerical_twines", "lattice"}, where, ("corners",))
        if ("twine" in p) == ("hex_twine" in p):
            raise SceneError(f"{where}: give its material as twine (diamond meshes) or hex_twine (hexagonal), "
                             "one of them")
        if "step" not in p and not ({"numerical_twines", "lattice"} & set(p)):
            raise SceneError(f"{where}: missing key(s) ['step'] (needed unless numerical_twines or lattice is given)")
        material = (_material(p["twine"], twines, Twine, f"{where}.twine") if "twine" in p
                    else _hex_material(p["hex_twine"], hex_twines, f"{where}.hex_twine"))
        lattice = None
        if "lattice" in p:
            lattice = tuple(_list(p["lattice"], f"{where}.lattice"))
            if len(lattice) != 2:
                raise SceneError(f"{where}.lattice: expected [NU, NV], two numbers of meshes, got {p['lattice']!r}")
        # Net.panel's errors name the panel
        net.panel(p.get("name", f"panel{i}"), _rows(p["corners"], f"{where}.corners", 5), material,
                  _number(p["step"], f"{where}.step") if "step" in p else None,
                  twines=_numerical_twines(p["numerical_twines"], f"{where}.numerical_twines")
                  if "numerical_twines" in p else None, lattice=lattice)
    for i, c in enumerate(doc.get("cables", [])):
        where = f"cables[{i}]"
        _keys(c, {"name", "rope", "start", "end", "along", "n_bars", "length"}, where, ("rope",))
        along = _ref(c["along"], f"{where}.along") if "along" in c else None
        net.cable(
            c.get("name", f"cable{i}"),
            start=_ref(c["start"], f"{where}.start") if "start" in c else None,
            end=_ref(c["end"], f"{where}.end") if "end" in c else None,
            rope=_material(c["rope"], ropes, Rope, f"{where}.rope"),
            n_bars=_integer(c["n_bars"], f"{where}.n_bars") if "n_bars" in c else None,
            length=_number(c["length"], f"{where}.length") if "length" in c else None,
            along=along,
        )
    for i, pair in enumerate(doc.get("seams", [])):
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise SceneError(f"seams[{i}]: a seam is a pair of panel sides")
        net.seam(_ref(pair[0], f"seams[{i}][0]"), _ref(pair[1], f"seams[{i}][1]"))
    for i, j in enumerate(doc.get("cable_joints", [])):
        where = f"cable_joints[{i}]"
        _keys(j, {"cables", "neutral_angle", "stiffness"}, where, ("cables",))
        names = j["cables"]
        if not isinstance(names, list) or len(names) != 2 or not all(isinstance(n, str) for n in names):
            raise SceneError(f"{where}.cables: expected the names of two cables [A, B], got {j['cables']!r}")
        options = {k: _number(j[k], f"{where}.{k}") for k in ("neutral_angle", "stiffness") if k in j}
        try:
            net.cable_joint(*j["cables"], **options)
        except SceneError as err:
            raise SceneError(f"{where}: {err}") from None
    for i, f in enumerate(doc.get("fix", [])):
        _keys(f, {"at", "axes"}, f"fix[{i}]", ("at",))
        net.fix(_ref(f["at"], f"fix[{i}].at"), f.get("axes", "xyz"))
    for i, plane in enumerate(doc.get("symmetry_planes", [])):
        where = f"symmetry_planes[{i}]"
        _keys(plane, {"axis", "at", "hold"}, where, ("axis",))
        if "hold" in plane and not isinstance(plane["hold"], bool):
            raise SceneError(f"{where}.hold: expected true or false, got {plane['hold']!r}")
        try:
            net.symmetry_plane(plane["axis"], _number(plane.get("at", 0.0), f"{where}.at"), plane.get("hold", True))
        except SceneError as err:
            raise SceneError(f"{where}: {err}") from None
    for i, a in enumerate(doc.get("attach", [])):
        where = f"attach[{i}]"
        _keys(a, {"at", "mass", "volume", "force", "drag_area", "size"}, where, ("at",))
        amounts = {k: _number(a[k], f"{where}.{k}") for k in ("mass", "volume", "drag_area", "size") if k in a}
        if "force" in a:
            amounts["force"] = _triple(a["force"], f"{where}.force")
        net.attach(_ref(a["at"], f"{where}.at"), **amounts)
    for i, s in enumerate(doc.get("sinkers", [])):
        where = f"sinkers[{i}]"
        _keys(s, {"at", "mass", "density"}, where, ("at", "mass"))
        net.sinker(_ref(s["at"], f"{where}.at"), **{k: _number(s[k], f"{where}.{k}") for k in ("mass", "density") if k in s})
    for i, s in enumerate(doc.get("floats", [])):
        where = f"floats[{i}]"
        _keys(s, {"at", "buoyancy_N", "mass", "size", "drag_area"}, where, ("at", "buoyancy_N"))
        net.float_(_ref(s["at"], f"{where}.at"), **{k: _number(s[k], f"{where}.{k}")
                                                    for k in ("buoyancy_N", "mass", "size", "drag_area") if k in s})
    # FEMNET's node-type properties, given to every node of the reference (Net.body, Net.limit)
    for key, fields, give in (("bodies", ("drag_length", "drag_coefficient"), net.body),
                              ("limits", ("limit", "sense"), net.limit)):
        for i, entry in enumerate(doc.get(key, [])):
            where = f"{key}[{i}]"
            _keys(entry, {"at", *fields}, where, ("at", *fields))
            try:
                give(_ref(entry["at"], f"{where}.at"), *(_triple(entry[k], f"{where}.{k}") for k in fields))
            except SceneError as err:
                raise SceneError(f"{where}: {err}") from None
    if "catch" in doc:
        c = _keys(doc["catch"], {"volume", "drag_coefficient", "symmetry", "center", "axis", "density"}, "catch",
                  ("volume",))
        numbers = {k: _number(c[k], f"catch.{k}")
                   for k in ("volume", "drag_coefficient", "symmetry", "density") if k in c}
        if "center" in c:
            numbers["center"] = _triple(c["center"], "catch.center")
        net.catch(**numbers, axis=_triple(c["axis"], "catch.axis") if "axis" in c else None)   # errors name "catch"
    for i, entry in enumerate(doc.get("panel_catches", [])):
        where = f"panel_catches[{i}]"
        c = _keys(entry, {"volume", "panels", "drag_coefficient", "symmetry", "axis", "center"}, where, ("volume", "panels"))
        numbers = {k: _number(c[k], f"{where}.{k}") for k in ("volume", "drag_coefficient", "symmetry") if k in c}
        if not isinstance(c["panels"], list) or not all(isinstance(n, str) for n in c["panels"]):
            raise SceneError(f"{where}.panels: expected a list of panel names, got {c['panels']!r}")
        try:
            net.panel_catch(**numbers, panels=c["panels"], axis=_triple(c["axis"], f"{where}.axis") if "axis" in c else None,
                            center=_triple(c["center"], f"{where}.center") if "center" in c else None)
        except SceneError as err:
            raise SceneError(f"{where}: {err}") from None
    if "enclosure" in doc:
        e = _keys(doc["enclosure"], {"center", "axis"}, "enclosure", ("center", "axis"))
        net.enclose(_triple(e["center"], "enclosure.center"), _triple(e["axis"], "enclosure.axis"))
    return from_net(net, _solver(doc.get("solver", {})), label=label)


def read(path) -> Case:
    """Read a scene file (.json or .toml) into a :class:`~jaxnet.case.Case`."""
    path = pathlib.Path(path)
    if not path.exists():
        raise SceneError(f"scene file {path} does not exist")
    try:
        text = path.read_text(encoding="utf-8")   # what both formats are written in
        if path.suffix == ".toml":
            import tomllib

            doc = tomllib.loads(text)
        elif path.suffix == ".json":
            doc = json.loads(text)
        else:
            raise SceneError(f"{path}: unknown scene file type '{path.suffix}' (use .json or .toml)")
    except (json.JSONDecodeError, ValueError) as err:
        if isinstance(err, SceneError):
            raise
        raise SceneError(f"{path}: cannot parse: {err}") from err
    return from_dict(doc, label=str(path))


# -- writing --------------------------------------------------------------------------------------------------


def to_dict(net: Net, solver: Newton | None = None, description: str | None = None) -> dict:
    """The scene document of ``net`` (:class:`~jaxnet.net.Net`): what :meth:`Net.description
    <jaxnet.net.Net.description>` holds, in this module's schema, from which :func:`from_dict` builds the same
    scene. ``solver``: the Newton options to write (those that differ from :class:`Newton`'s defaults);
    ``description``: a line of free text for the file.

    The environment and every material are written whole (defaults included), so that the file shows each
    parameter there is to edit; materials are named tables (``twines``, ``hex_twines``, ``ropes``), one per
    distinct material, named after the first panel or cable that uses it. Sinkers and floats stay sinkers and
    floats (a float whose volume was worked out with another gravity or water density than the net's
    environment is written as the attachment it made). Raises :class:`SceneError` naming what the format
    cannot hold: an irregular sea (it keeps its realised components, not the spectrum they were drawn from),
    waves on another surface level, gravity or vertical than the environment's, a free-surface elevation over
    the nodes (the dynamics' to set), a reference that is not one of the file's."""
    d = net.description()
    env = d["environment"]
    doc = {}
    if description:
        doc["description"] = str(description)
    if d["merge_tolerance"] != inspect.signature(Net).parameters["merge_tolerance"].default:
        doc["merge_tolerance"] = d["merge_tolerance"]
    doc["environment"] = _environment_spec(env)
    twines, hex_twines, ropes = {}, {}, {}
    panels = []
    for p in d["panels"]:
        where = f"panel '{p['name']}'"
        spec = {"name": p["name"], "corners": [_floats(row, where) for row in p["corners"]]}
        if isinstance(p["twine"], HexTwine):
            spec["hex_twine"] = _named(hex_twines, _hex_spec(p["twine"], where), p["name"])
        else:
            spec["twine"] = _named(twines, _material_spec(p["twine"], where), p["name"])
        if p["step"] is not None:
            spec["step"] = float(p["step"])
        if p["twines"] is not None:
            spec["numerical_twines"] = {f.name: _scalar(getattr(p["twines"], f.name), f"{where}: numerical twines")
                                        for f in dataclasses.fields(NumericalTwines)}
            spec["numerical_twines"]["bars"] = int(spec["numerical_twines"]["bars"])
        if p["lattice"] is not None:
            spec["lattice"] = _floats(p["lattice"], f"{where}: lattice")
        panels.append(spec)
    cables = []
    for c in d["cables"]:
        where = f"cable '{c['name']}'"
        spec = {"name": c["name"], "rope": _named(ropes, _material_spec(c["rope"], where), c["name"])}
        for key in ("start", "end", "along"):
            if c[key] is not None:
                spec[key] = _ref_spec(c[key], f"{where}: {key}")
        if c["n_bars"] is not None:
            spec["n_bars"] = int(c["n_bars"])
        if c["length"] is not None:
            spec["length"] = float(c["length"])
        cables.append(spec)
    doc.update(twines=twines, **({"hex_twines": hex_twines} if hex_twines else {}), ropes=ropes, panels=panels,
               cables=cables)
    doc["seams"] = [[_ref_spec(a, "seam"), _ref_spec(b, "seam")] for a, b in d["seams"]]
    doc["cable_joints"] = [{"cables": list(j["cables"]), "neutral_angle": float(j["neutral_angle"]),
                            **({} if j["stiffness"] is None else {"stiffness": float(j["stiffness"])})}
                           for j in d["cable_joints"]]
    doc["fix"] = [{"at": _ref_spec(f["at"], "fix"), **({} if f["axes"] == "xyz" else {"axes": f["axes"]})}
                  for f in d["fixed"]]
    doc["symmetry_planes"] = [{"axis": s["axis"], "at": float(s["at"]), "hold": bool(s["hold"])}
                              for s in d["symmetry_planes"]]
    doc.update(_attachments(d, env))
    doc["bodies"] = [{"at": _ref_spec(b["at"], "body"), "drag_length": _floats(b["length"], "body: length"),
                      "drag_coefficient": _floats(b["drag_coefficient"], "body: drag_coefficient")}
                     for b in d["bodies"]]
    doc["limits"] = [{"at": _ref_spec(b["at"], "limit"), "limit": _floats(b["value"], "limit: value"),
                      "sense": [int(v) for v in b["sense"]]} for b in d["limits"]]
    if d["catch"] is not None:
        c = d["catch"]
        doc["catch"] = {"volume": float(c["volume"]), "drag_coefficient": float(c["drag_coefficient"]),
                        "symmetry": float(c["symmetry"]), "center": _floats(c["center"], "catch: center")}
        if c["axis"] is not None:
            doc["catch"]["axis"] = _floats(c["axis"], "catch: axis")
        if c["density"]:
            doc["catch"]["density"] = float(c["density"])
    doc["panel_catches"] = []
    for c in d["panel_catches"]:
        spec = {"volume": float(c["volume"]), "panels": list(c["panels"]),
                "drag_coefficient": float(c["drag_coefficient"]), "symmetry": float(c["symmetry"])}
        for key in ("axis", "center"):
            if c[key] is not None:
                spec[key] = _floats(c[key], f"panel catch: {key}")
        doc["panel_catches"].append(spec)
    if d["enclosure"] is not None:
        doc["enclosure"] = {k: _floats(v, f"enclosure: {k}") for k, v in d["enclosure"].items()}
    doc["solver"] = _solver_spec(solver or Newton())
    # an empty list or table says nothing: left out, so that the file shows what the net has (the solver's table
    # stays, the place to add options)
    return {k: v for k, v in doc.items() if (v != [] and v != {}) or k == "solver"}


def write(path, net_or_case, solver: Newton | None = None) -> pathlib.Path:
    """Write a :class:`~jaxnet.net.Net` or a :class:`~jaxnet.case.Case` built from one (a built-in scene, a scene
    file) to the scene file ``path``: JSON for ``.json``, TOML for ``.toml`` (:func:`to_dict`'s document), which
    :func:`read` reads back into the same scene. Returns the path.

    solver: the Newton options to write; default the case's own (a net's: the defaults). A case's label is the
    file's ``description``. A case is written only if its net rebuilt from the file is its scene (every array to
    1e-10 relative): one whose scene was changed after its net was built (FEMNET's gauge node) or was read whole
    (FEMNET's mesh: no net) is refused with a :class:`SceneError`, as is what :func:`to_dict` cannot write. A
    case's time settings (the run in time's end, steps and loading) are not part of a scene file: they are left
    out, and the description says so. Nothing is written when an error is raised."""
    path = pathlib.Path(path)
    if path.suffix not in (".json", ".toml"):
        raise SceneError(f"{path}: unknown scene file type '{path.suffix}' (use .json or .toml)")
    case = None
    if isinstance(net_or_case, Case):
        case = net_or_case
        if case.net is None:
            raise SceneError(f"{case.label or 'the case'}: its scene was read whole (no Net describes it): it cannot "
                             "be written as a scene file")
        net, label = case.net, case.label
        solver = solver or case.solver
        if case.time is not None:
            label = (f"{label} (written without its time settings: end time, steps and loading in time are not "
                     "part of a scene file)").lstrip()
    elif isinstance(net_or_case, Net):
        net, label = net_or_case, ""
    else:
        raise TypeError(f"write: expected a jaxnet Net or Case, got {type(net_or_case).__name__}")
    doc = to_dict(net, solver, description=label)
    text = _toml(doc) if path.suffix == ".toml" else _json(doc)
    if case is not None:
        parsed = _parse(text, path.suffix)
        differs = _difference(case.scene, from_dict(parsed, label=str(path)).scene)
        if differs:
            raise SceneError(f"{case.label or 'the case'}: its scene is not what its net builds ({differs}): it was "
                             "changed after the net was built, which a scene file cannot say")
    path.write_text(text, encoding="utf-8")
    return path


def _parse(text, suffix):
    """The document of a scene file's text."""
    if suffix == ".toml":
        import tomllib

        return tomllib.loads(text)
    return json.loads(text)


def _difference(a, b):
    """Where scene ``b`` differs from scene ``a`` (a field's path), or "" when they are the same: the same
    structure and names, every array of the same shape and equal to 1e-10 relative (sums of attachments taken in
    another order differ in their last bits)."""
    (leaves_a, tree_a), (leaves_b, tree_b) = jax.tree_util.tree_flatten_with_path(a), jax.tree_util.tree_flatten(b)
    if tree_a != tree_b:
        return "its parts, names or options"
    for (key, x), y in zip(leaves_a, leaves_b):
        x, y = np.asarray(x), np.asarray(y)
        if x.shape != y.shape or not np.allclose(x, y, rtol=1e-10, atol=1e-12, equal_nan=True):
            return f"scene{jax.tree_util.keystr(key)}"
    return ""


def _scalar(value, where):
    """A Python number or boolean of a value of the description (numpy's and jax's included)."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    try:
        array = np.asarray(value)
    except Exception:   # a traced value, an object: not a number of a file
        array = None
    if array is None or array.shape != () or array.dtype.kind not in "biuf":
        raise SceneError(f"{where}: {value!r} is not a number a scene file can hold")
    return int(array) if array.dtype.kind in "iu" else float(array)


def _floats(values, where):
    """A list of floats of a vector of the description."""
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise SceneError(f"{where}: {values!r} is not a list of numbers a scene file can hold") from None
    return [float(v) for v in array.reshape(-1)]


def _named(table, spec, name):
    """The name of material ``spec`` in ``table`` (name -> spec), adding it under ``name`` if it is not there."""
    for key, value in table.items():
        if value == spec:
            return key
    table[name] = spec
    return name


def _material_spec(material, where):
    """A :class:`Twine` or :class:`Rope` as a table: every field, strings for its named choices (None: left out)."""
    spec = {}
    for f in dataclasses.fields(material):
        value = getattr(material, f.name)
        if value is None:
            continue
        spec[f.name] = str(value) if f.name in _STRINGS else float(_scalar(value, f"{where}: {f.name}"))
    return spec


def _hex_spec(material, where):
    """A :class:`HexTwine` as a table: l0, ea and ea_compression one number, or one per family when they differ."""
    spec = {}
    for f in dataclasses.fields(material):
        values = _floats(getattr(material, f.name), f"{where}: {f.name}")
        spec[f.name] = values[0] if len(values) == 1 else values
    return spec


def _ref_spec(ref, where):
    """A reference of the description as the file's REF."""
    if isinstance(ref, Corner):
        return {"panel": ref.panel, "corner": int(ref.index)}
    if isinstance(ref, Side):
        return {"panel": ref.panel, "side": int(ref.index)}
    if isinstance(ref, Nearest):
        return {"panel": ref.panel, "nearest": _floats(ref.point, where)}
    if isinstance(ref, PanelRef):
        return {"panel": ref.name}
    if isinstance(ref, CableEnd):
        return {"cable": ref.cable, "end": 0 if ref.end == 0 else 1}
    if isinstance(ref, (CableNodes, CableRef)):
        return {"cable": ref.cable if isinstance(ref, CableNodes) else ref.name}
    point = _floats(ref, where) if isinstance(ref, (list, tuple, np.ndarray)) else None
    if point is None or len(point) != 3:
        raise SceneError(f"{where}: {ref!r} is not a reference a scene file can write (a panel corner, side, "
                         "nearest node or all its nodes, a cable end or all its nodes, or a point [x, y, z])")
    return point


def _environment_spec(env):
    """The environment as the file's table: every field but the free-surface elevation over the nodes, a
    surface level of NaN (none: the default) left out."""
    spec = {}
    for f in dataclasses.fields(env):
        value = getattr(env, f.name)
        where = f"environment.{f.name}"
        if f.name == "surface_elevation":
            if value is not None:
                raise SceneError(f"{where}: the free surface's elevation over each node is a time step's to set, not "
                                 "a scene file's: it cannot be written")
        elif f.name == "waves":
            if value is not None:
                spec["waves"] = _waves_spec(value, env)
        elif f.name == "bottom_moving":
            spec[f.name] = bool(value)
        elif f.name == "floating":
            spec[f.name] = [str(v) for v in value]
        elif f.name in ("up", "current_direction", "profile_depth", "profile_factor"):
            spec[f.name] = _floats(value, where)
        elif not (f.name == "surface_level" and np.isnan(value)):
            spec[f.name] = float(_scalar(value, where))
    return spec


def _waves_spec(w, env):
    """Regular waves as the file's table; a SceneError for what the file cannot hold."""
    from jaxnet import waves

    where = "environment.waves"
    models = {waves.Airy: "airy", waves.Stokes2: "stokes2", waves.Stokes3: "stokes3"}
    if isinstance(w, waves.Irregular):
        raise SceneError(f"{where}: an irregular sea keeps its realised components, not the spectrum they were drawn "
                         "from: it cannot be written (give it in the file as {hs, tp, spectrum, seed, ...})")
    if type(w) not in models:
        raise SceneError(f"{where}: {type(w).__name__} waves cannot be written (a scene file holds "
                         f"{', '.join(c.__name__ for c in models)} and sea states)")
    level = float(env.surface_level) if np.isfinite(env.surface_level) else 0.0
    up = np.asarray(env.up, dtype=float) / np.linalg.norm(env.up)
    mismatched = [name for name, ours, theirs in (("surface_level", level, w.surface_level),
                                                  ("gravity", env.gravity, w.gravity), ("up", up, w.up))
                  if not np.allclose(np.asarray(theirs, dtype=float), ours, rtol=1e-12, atol=1e-12)]
    if mismatched:
        raise SceneError(f"{where}: the waves' {', '.join(mismatched)} differ from the environment's, which a scene "
                         "file's waves take: they cannot be written")
    spec = {"height": float(w.height), "period": float(w.period)}
    if models[type(w)] != "airy":
        spec["model"] = models[type(w)]
    spec["direction"] = _floats(w.direction, f"{where}.direction")
    if np.isfinite(w.depth):
        spec["depth"] = float(w.depth)
    spec["phase"] = float(w.phase)
    if float(w.ramp):
        spec["ramp"] = float(w.ramp)
    return spec


def _attachments(d, env):
    """The description's attachments as the file's ``attach``, ``sinkers`` and ``floats``."""
    sinkers = {s["attached"]: s for s in d["sinkers"]}
    floats = {s["attached"]: s for s in d["floats"]}
    out = {"attach": [], "sinkers": [], "floats": []}
    for k, a in enumerate(d["attached"]):
        at = _ref_spec(a["at"], "attachment")
        if k in sinkers:
            out["sinkers"].append({"at": at, "mass": float(sinkers[k]["mass"]),
                                   "density": float(sinkers[k]["density"])})
        elif k in floats and (floats[k]["gravity"], floats[k]["water_density"]) == (float(env.gravity),
                                                                                   float(env.water_density)):
            spec = {"at": at, "buoyancy_N": float(floats[k]["buoyancy_N"])}
            spec.update({key: float(v) for key, v in (("mass", floats[k]["mass"]), ("size", a["size"]),
                                                      ("drag_area", a["drag_area"])) if v})
            out["floats"].append(spec)
        else:
            spec = {"at": at}
            spec.update({key: float(a[key]) for key in ("mass", "volume", "drag_area", "size") if a[key]})
            if np.any(a["force"]):
                spec["force"] = _floats(a["force"], "attachment: force")
            out["attach"].append(spec)
    return out


def _solver_spec(solver):
    """Newton's options that differ from its defaults, as the file's ``solver`` table (None: false)."""
    if not isinstance(solver, Newton):
        raise TypeError(f"solver must be jaxnet.solve.options.Newton, got {type(solver).__name__}")
    spec = {}
    for f in dataclasses.fields(Newton):
        value = getattr(solver, f.name)
        if value == f.default:
            continue
        if f.name == "stall_window" and value is None:
            spec[f.name] = False
        elif isinstance(value, (str, bool)):
            spec[f.name] = value
        else:
            spec[f.name] = _scalar(value, f"solver.{f.name}")
    return spec


# -- the text of the files --------------------------------------------------------------------------------------

_LINE = 110   # the widest line a value is written on before it is broken over several


def _json(doc) -> str:
    """JSON text of a document: a value on one line where it fits, else one item a line."""
    def text(value, indent):
        flat = json.dumps(value, ensure_ascii=False)
        if len(flat) + indent <= _LINE or not isinstance(value, (list, dict)) or not value:
            return flat
        pad = " " * (indent + 2)
        if isinstance(value, dict):
            items = [f"{pad}{json.dumps(k, ensure_ascii=False)}: {text(v, indent + 2)}" for k, v in value.items()]
            return "{\n" + ",\n".join(items) + "\n" + " " * indent + "}"
        return "[\n" + ",\n".join(pad + text(v, indent + 2) for v in value) + "\n" + " " * indent + "]"

    return text(doc, 0) + "\n"


def _toml_string(value: str) -> str:
    """A TOML basic string: quotes, backslashes and control characters escaped."""
    out = []
    for ch in value:
        if ch in '"\\':
            out.append("\\" + ch)
        elif ord(ch) < 0x20 or ord(ch) == 0x7F:
            out.append(f"\\u{ord(ch):04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


def _toml_key(key: str) -> str:
    bare = key and all(ch.isascii() and (ch.isalnum() or ch in "_-") for ch in key)
    return key if bare else _toml_string(key)


def _toml_value(value, column=0, indent=0, inline=False) -> str:
    """A TOML value starting at ``column`` on a line indented by ``indent``: booleans, integers, floats (Python's
    shortest repr, which TOML reads back to the same double; inf and nan as TOML spells them), strings, arrays
    (one item a line where they do not fit, unless ``inline``: within an inline table, which TOML keeps on one
    line) and inline tables (for tables)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)   # repr: 'inf', '-inf', '1e-05', '0.25'
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v, inline=True)}" for k, v in value.items()) + "}"
    if isinstance(value, list):
        flat = "[" + ", ".join(_toml_value(v, inline=True) for v in value) + "]"
        if len(flat) + column <= _LINE or not value or inline:
            return flat
        pad = " " * (indent + 4)
        return ("[\n" + "".join(f"{pad}{_toml_value(v, indent + 4, indent + 4)},\n" for v in value)
                + " " * indent + "]")
    raise SceneError(f"scene file: cannot write {value!r} ({type(value).__name__}) in TOML")


def _toml(doc) -> str:
    """TOML text of a document: a table's plain keys first (as TOML requires: a key after a section header belongs
    to that section), then, in the document's order, its tables as sections ([a.b]) and its arrays of tables as
    [[a]] entries (whose own tables are written inline)."""
    lines = []

    def is_tables(value):
        return isinstance(value, list) and value and all(isinstance(v, dict) for v in value)

    def pair(key, value):
        lines.append(f"{_toml_key(key)} = {_toml_value(value, len(_toml_key(key)) + 3)}")

    def section(path, table):
        for k, v in table.items():
            if not isinstance(v, dict) and not is_tables(v):
                pair(k, v)
        for k, v in table.items():
            name = ".".join(_toml_key(p) for p in (*path, k))
            if isinstance(v, dict):
                # a table of tables only (the materials) needs no header of its own
                if not v or not all(isinstance(x, dict) for x in v.values()):
                    lines.extend(["", f"[{name}]"])
                section((*path, k), v)
            elif is_tables(v):
                for entry in v:
                    lines.extend(["", f"[[{name}]]"])
                    for key, value in entry.items():
                        pair(key, value)

    section((), doc)
    return "\n".join(lines).lstrip("\n") + "\n"
