"""Scene files: a net described in JSON (``.json``) or TOML (``.toml``), read into a :class:`~jaxnet.case.Case`
(its :class:`~jaxnet.net.Net` built, with the file's solver options).

The format mirrors the Python API (see README, "Scene files"). Top-level keys::

    environment  {gravity, water_density, up, current_speed, current_direction, profile_depth,
                  profile_factor, surface_level, bottom_stiffness, bottom_friction, bottom_band, bottom_moving,
                  waves?: {height, period, direction?, depth?, phase?}             regular (Airy) waves
                        | {hs, tp, spectrum?, gamma?, spreading?, components?, band?, seed?,
                           direction?, depth?, stretching?}                       an irregular sea}
    twines       {NAME: {l0, ea, diameter, ea_compression?, density?, cd_normal?, tangential_ratio?,
                         drag_model?, opening_stiffness?, rest_angle?, knot_size?, knot_stiffness?,
                         bending_stiffness?, tarp_cd?}}                      netting materials
    ropes        {NAME: {ea, diameter, ea_compression?, density?, cd_normal?, tangential_ratio?}}
    panels       [{name, corners: [[x, y, z, U, V], ...], twine: NAME | {...}, step}]
    cables       [{name, rope: NAME | {...}, start?: REF, end?: REF, along?: SIDE, n_bars?, length?}]
    seams        [[SIDE, SIDE], ...]
    fix          [{at: REF, axes?: "xyz"}]
    attach       [{at: REF, mass?, volume?, force?: [fx, fy, fz], drag_area?, size?}]
    sinkers      [{at: REF, mass, density?}]
    floats       [{at: REF, buoyancy_N, mass?, size?, drag_area?}]
    bodies       [{at: REF, drag_length: [lx, ly, lz], drag_coefficient: [cx, cy, cz]}]  box drag
    limits       [{at: REF, limit: [x, y, z], sense: [sx, sy, sz]}]          sea bed, ceilings
    catch        {volume, drag_coefficient?, symmetry?, axis?}              fish catch in a cod-end
    panel_catches [{volume, panels: [NAME, ...], drag_coefficient?, symmetry?, axis?, center?}]
                                                                              catches held by chosen panels
    solver       {tol, max_iter, max_step, ...}                               Newton options

``bodies`` and ``limits`` are FEMNET's node types (see :class:`jaxnet.scene.Nodes`): *every* node of the
reference gets the body (sizes in m, a negative lz for a body hanging below its node) or the limits (m;
sense +1 floor, -1 ceiling, 0 none, per axis); a later entry replaces an earlier one on the nodes they
share. The sea bed's stiffness, friction and band are the environment's ``bottom_stiffness`` (N/m),
``bottom_friction`` and ``bottom_band`` (m); ``bottom_moving`` (true, the default, or false) says whether the bed
slides under the net at the current's velocity (a towed gear) or is still.

A REF is ``{"panel": P, "corner": k}``, ``{"panel": P, "side": k}`` (SIDE), ``{"panel": P}`` (all its
nodes), ``{"cable": C, "end": 0 | 1}``, ``{"cable": C}`` (all its nodes) or a point ``[x, y, z]``.
Every unknown key is an error naming where it is, so a misspelt parameter is never silently ignored.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib

import numpy as np

from jaxnet.case import Case, from_net
from jaxnet.net import CableEnd, CableNodes, Corner, Net, PanelRef, Rope, Side, Twine
from jaxnet.scene import Environment, SceneError
from jaxnet.solve.options import Newton

_TOP = {"environment", "twines", "ropes", "panels", "cables", "seams", "fix", "attach", "sinkers", "floats", "catch",
        "panel_catches", "bodies", "limits", "solver", "description"}
_STRINGS = {"drag_model"}  # material fields that are not numbers


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


def _solver(spec):
    """Newton's options: numbers where numbers belong, a threshold > 0, at least one iteration, a displacement
    limit > 0 (the :class:`Newton` class itself takes anything)."""
    spec = dict(_keys(spec, {f.name for f in dataclasses.fields(Newton)}, "solver"))
    for key, value in spec.items():
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
    _keys(spec, {"panel", "corner", "side", "cable", "end"}, where)
    if "panel" in spec:
        if "corner" in spec and "side" in spec:
            raise SceneError(f"{where}: give a corner or a side, not both")
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


_REGULAR = {"height", "period", "direction", "depth", "phase"}
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
        elif key in ("spectrum", "stretching"):
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
    try:
        if irregular:
            return waves.sea_state(**values, **common)
        return waves.Airy(**values, **common)
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
        elif key != "waves":
            env_spec[key] = _number(value, f"environment.{key}")
    if "waves" in env_spec:
        env_spec["waves"] = _waves(env_spec["waves"], env_spec, "environment.waves")
    env = Environment(**env_spec)
    net = Net(environment=env)
    twines = {k: _material(v, {}, Twine, f"twines.{k}") for k, v in doc.get("twines", {}).items()}
    ropes = {k: _material(v, {}, Rope, f"ropes.{k}") for k, v in doc.get("ropes", {}).items()}
    for i, p in enumerate(doc.get("panels", [])):
        where = f"panels[{i}]"
        _keys(p, {"name", "corners", "twine", "step"}, where, ("corners", "twine", "step"))
        net.panel(p.get("name", f"panel{i}"), _rows(p["corners"], f"{where}.corners", 5),
                  _material(p["twine"], twines, Twine, f"{where}.twine"), _number(p["step"], f"{where}.step"))
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
    for i, f in enumerate(doc.get("fix", [])):
        _keys(f, {"at", "axes"}, f"fix[{i}]", ("at",))
        net.fix(_ref(f["at"], f"fix[{i}].at"), f.get("axes", "xyz"))
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
        c = _keys(doc["catch"], {"volume", "drag_coefficient", "symmetry", "axis"}, "catch", ("volume",))
        numbers = {k: _number(c[k], f"catch.{k}") for k in ("volume", "drag_coefficient", "symmetry") if k in c}
        net.catch(**numbers, axis=_triple(c["axis"], "catch.axis") if "axis" in c else None)
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
    return from_net(net, _solver(doc.get("solver", {})), label=label)


def read(path) -> Case:
    """Read a scene file (.json or .toml) into a :class:`~jaxnet.case.Case`."""
    path = pathlib.Path(path)
    if not path.exists():
        raise SceneError(f"scene file {path} does not exist")
    text = path.read_text()
    try:
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
