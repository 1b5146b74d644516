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
or "stokes3" (:class:`jaxnet.water.waves.Airy`, ``Stokes2``, ``Stokes3``); all waves take the environment's surface
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
Every unknown key is an error naming where it is, with the nearest known key (``did you mean current_speed?``),
so a misspelt parameter is never silently ignored. An error of :func:`read` names the file, the line and the key
path of its culprit (``my.toml:48: twines."wall 0": ea must be > 0, got 0.0 ...``); a material's error names its
table, checked as it is read, not a panel or cable that uses it. ``tomllib`` and ``json`` keep no positions: the
line of a key path is found by following the text (:func:`_toml_lines`, :func:`_json_lines`).

Writing: :func:`to_dict` gives the document of a :class:`~jaxnet.net.Net` (from :meth:`Net.description
<jaxnet.net.Net.description>`), :func:`write` writes a net or a case to a .json or .toml file that :func:`read`
reads back into the same scene, to be edited (``jaxnet export``). TOML is written here: the standard library
reads it (``tomllib``) but has no writer, and the schema needs only tables, arrays of tables, inline tables,
numbers, strings, booleans and nested arrays.
"""

from __future__ import annotations

import bisect
import contextlib
import dataclasses
import difflib
import inspect
import json
import math
import pathlib
import re

import jax
import numpy as np

from jaxnet import materials
from jaxnet.case import Case, from_net
from jaxnet.mesh.twines import NumericalTwines
from jaxnet.materials import HexTwine
from jaxnet.net import (CableEnd, CableNodes, CableRef, Corner, Nearest, Net, PanelRef, Rope, Side, Twine,
                        describe_reference)
from jaxnet.scene import FLOATING, Environment, SceneError
from jaxnet.solve.options import Newton

_TOP = {"environment", "twines", "hex_twines", "ropes", "panels", "cables", "seams", "cable_joints", "fix",
        "symmetry_planes", "attach", "sinkers", "floats", "catch", "panel_catches", "enclosure", "bodies", "limits",
        "solver", "description", "merge_tolerance"}
_STRINGS = {"drag_model", "knot_form"}  # material fields that are not numbers


class _Path(tuple):
    """Where a value is in a scene document: its keys and indices from the top (``("twines", "wall 0", "ea")``),
    shown as the file's key path (``twines."wall 0".ea``, ``panels[2].corners``; the document itself: ``scene``).
    ``path / key`` is the path of one of its entries (a key, or an index of an array)."""

    def __truediv__(self, key):
        return _Path((*self, key))

    def __str__(self):
        text = ""
        for key in self:
            text += f"[{key}]" if isinstance(key, int) else ("." if text else "") + _toml_key(str(key))
        return text or "scene"

    def __format__(self, spec):
        return format(str(self), spec)


_SCENE = _Path(())


def _fail(where, problem, at=None):
    """The SceneError "WHERE: PROBLEM" of the value at ``where`` (a :class:`_Path`), which :func:`read` prefixes
    with the file and the line of the value at ``at`` (default ``where``)."""
    error = SceneError(f"{where}: {problem}")
    error.where = where if at is None else at
    return error


@contextlib.contextmanager
def _within(where, entry=None, named=False):
    """The errors of the builder called inside (which name the panel or cable: "panel 'wall': ...") located at
    ``where``, the entry ``entry`` of the file it was given (at its key the message goes on to name, "step must
    be ..."); ``named``: prefixed with ``where`` too, for the builder's errors that name no part of the file."""
    try:
        yield
    except SceneError as err:
        if getattr(err, "where", None) is not None:
            raise
        if named:
            raise _fail(where, str(err), at=_refined(where, str(err), entry)) from None
        err.where = _refined(where, str(err), entry)
        raise


def _refined(where, message, entry, name=""):
    """``where / KEY`` when the builder's message about the entry ``entry`` (a table of the file) goes on, after
    ``name`` (the entry's name as the message gives it: "panel 'wall'"), to name one of its keys: "panel 'wall':
    step must be ...", "cable 'bridle' start: ..."; else ``where``."""
    rest = message.removeprefix(name)
    for found in (re.match(r"\W*([A-Za-z_]+)", rest), re.match(r"[^:]*:\s*([A-Za-z_]+)", rest)):
        if isinstance(entry, dict) and found and found.group(1) in entry:
            return where / found.group(1)
    return where


def _nearest(word, names):
    """The name of ``names`` nearest a misspelt ``word`` (case aside: ``EA`` is ``ea``), or None."""
    lower = {str(name).lower(): name for name in names}
    close = difflib.get_close_matches(str(word).lower(), list(lower), n=1)
    return lower[close[0]] if close else None


def _keys(obj, allowed, where, required=(), elsewhere=()):
    """``obj``, a table of the file whose keys are among ``allowed`` and include every one of ``required``; else a
    SceneError at the first unknown key (with the nearest allowed one, so that a misspelt key is never silently
    ignored; or of ``elsewhere``, the paths of keys of other tables: "environment.current_speed"), or at the table
    for a missing one."""
    if not isinstance(obj, dict):
        raise _fail(where, f"expected a table/object, got {type(obj).__name__}")
    unknown = [k for k in obj if k not in allowed]
    if unknown:
        others = {path.rsplit(".", 1)[-1]: path for path in elsewhere}
        guesses = {k: _nearest(k, allowed) or others.get(_nearest(k, others)) for k in unknown}
        guesses = {k: g for k, g in guesses.items() if g is not None}
        if len(unknown) == 1 and guesses:
            hint = f": did you mean {guesses[unknown[0]]}?"
        else:
            hint = f": did you mean {', '.join(f'{g} for {k!r}' for k, g in guesses.items())}?" if guesses else ""
        raise _fail(where, f"unknown key(s) {sorted(unknown)}{hint} (allowed: {sorted(allowed)})",
                    at=where / unknown[0])
    missing = [k for k in required if k not in obj]
    if missing:
        raise _fail(where, f"missing key(s) {missing}")
    return obj


def _number(value, where):
    """A number of the file (not a string, a list or a boolean), or a SceneError naming where it is."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise _fail(where, f"expected a number, got {value!r}")
    return float(value)


def _integer(value, where):
    """An integer of the file (a float with no fraction will do), or a SceneError naming where it is."""
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise _fail(where, f"expected an integer, got {value!r}")
    return value


def _rows(value, where, width):
    """A (rows, width) array of the file's numbers (rows: lists of ``width`` numbers), or a SceneError at the first
    row that is not."""
    def numbers(row):
        return isinstance(row, (list, tuple)) and len(row) == width and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in row)

    if not isinstance(value, (list, tuple)):
        raise _fail(where, f"expected rows of {width} numbers, got {value!r}")
    bad = [k for k, row in enumerate(value) if not numbers(row)]
    if bad:
        raise _fail(where, f"expected rows of {width} numbers, got {value!r}", at=where / bad[0])
    return np.asarray(value, dtype=float).reshape(-1, width)


def _list(value, where):
    """A 1-D array of the file's numbers, or a SceneError naming where it is."""
    if not isinstance(value, (list, tuple)):
        raise _fail(where, f"expected a list of numbers, got {value!r}")
    return np.array([_number(v, where / k) for k, v in enumerate(value)], dtype=float)


def _named_material(name, table, kind, where):
    """The material named ``name`` in ``table`` (name -> material), or a SceneError naming the nearest name."""
    if name not in table:
        guess = _nearest(name, table)
        hint = f": did you mean '{guess}'?" if guess is not None else ""
        raise _fail(where, f"no {kind} named '{name}'{hint} (defined: {sorted(table)})")
    return table[name]


def _made(cls, values, where):
    """``cls(**values)``, a material of the file checked whole (:func:`jaxnet.materials.check`): an error names its
    table (``twines."wall 0"``, or the panel's or cable's inline table) at the line of the parameter at fault, not
    a panel or cable that uses it."""
    try:
        material = cls(**values)
        materials.check(material)
    except materials.MaterialError as err:
        raise _fail(where, err.problem, at=where / err.parameter) from None
    return material


def _material(spec, table, cls, where):
    """A :class:`Twine` or :class:`Rope` of the file: a name in its table (``table``: name -> material) or a table
    of its fields."""
    if isinstance(spec, str):
        return _named_material(spec, table, "material", where)
    fields = [f.name for f in dataclasses.fields(cls)]
    required = [f.name for f in dataclasses.fields(cls) if f.default is dataclasses.MISSING]
    return _made(cls, {k: (v if k in _STRINGS else _number(v, where / k))
                       for k, v in _keys(spec, fields, where, required).items()}, where)


def _hex_material(spec, table, where):
    """A hexagonal-mesh material (:class:`HexTwine`) of the file: a name in ``hex_twines`` or a table whose l0,
    ea and ea_compression are one number or one per twine family [l, m, n]."""
    if isinstance(spec, str):
        return _named_material(spec, table, "hexagonal-mesh material", where)
    _keys(spec, [f.name for f in dataclasses.fields(HexTwine)], where, ("l0", "ea", "diameter"))
    values = {}
    for key, value in spec.items():
        if key in ("l0", "ea", "ea_compression") and isinstance(value, (list, tuple)):
            if len(value) != 3:
                raise _fail(where / key, f"expected one number or 3 (families l, m, n), got {value!r}")
            values[key] = tuple(float(v) for v in _list(value, where / key))
        else:
            values[key] = _number(value, where / key)
    return _made(HexTwine, values, where)


def _numerical_twines(spec, where):
    """How a panel is meshed as numerical twines (:class:`~jaxnet.mesh.twines.NumericalTwines`) of the file."""
    fields = [f.name for f in dataclasses.fields(NumericalTwines)]
    values = {}
    for key, value in _keys(spec, fields, where, ("period",)).items():
        if key == "femnet_tangential":
            if not isinstance(value, bool):
                raise _fail(where / key, f"expected true or false, got {value!r}")
            values[key] = value
        elif key == "bars":
            values[key] = _integer(value, where / key)
        else:
            values[key] = _number(value, where / key)
    return NumericalTwines(**values)


def _solver(spec):
    """Newton's options: numbers where numbers belong, a threshold > 0, at least one iteration, a displacement
    limit > 0 (the :class:`Newton` class itself takes anything)."""
    where = _SCENE / "solver"
    spec = dict(_keys(spec, {f.name for f in dataclasses.fields(Newton)}, where))
    for key, value in spec.items():
        if key == "stall_window" and value is False:   # TOML has no null: false says None (never)
            spec[key] = None
            continue
        if key in ("stiffness", "verbose", "method") or (key == "stall_window" and value is None):
            continue
        integer = key in ("max_iter", "line_search", "stall_window")
        spec[key] = _integer(value, where / key) if integer else _number(value, where / key)
    for key, low in (("tol", 0.0), ("max_step", 0.0), ("max_iter", 0)):
        if key in spec and not spec[key] > low:
            raise _fail(where / key, f"must be > {low:g}, got {spec[key]!r}")
    try:
        return Newton(**spec)
    except ValueError as err:
        named = [key for key in spec if str(err).startswith(f"Newton: {key} ")]
        raise _fail(where, str(err), at=where / named[0] if named else None) from None


def _ref(spec, where):
    if isinstance(spec, (list, tuple)):
        if len(spec) != 3:
            raise _fail(where, f"a point must be [x, y, z], got {spec!r}")
        return tuple(_number(v, where / k) for k, v in enumerate(spec))
    _keys(spec, {"panel", "corner", "side", "nearest", "cable", "end"}, where)
    if "panel" in spec:
        if len({"corner", "side", "nearest"} & set(spec)) > 1:
            raise _fail(where, "give one of a corner, a side or a nearest point, not several")
        if "nearest" in spec:
            return Nearest(spec["panel"], tuple(float(v) for v in _triple(spec["nearest"], where / "nearest")))
        if "corner" in spec:
            return Corner(spec["panel"], _integer(spec["corner"], where / "corner"))
        if "side" in spec:
            return Side(spec["panel"], _integer(spec["side"], where / "side"))
        return PanelRef(spec["panel"])
    if "cable" in spec:
        if "end" in spec:
            if spec["end"] not in (0, 1):
                raise _fail(where, f"cable end must be 0 (start) or 1 (end), got {spec['end']!r}", at=where / "end")
            return CableEnd(spec["cable"], int(spec["end"]))
        return CableNodes(spec["cable"])
    raise _fail(where, "a reference needs 'panel' or 'cable' (or is a point [x, y, z])")


def _triple(value, where):
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        arr = None
    if arr is None or arr.shape != (3,):
        raise _fail(where, f"expected 3 numbers (along x, y, z), got {value!r}")
    return arr


_REGULAR = {"height", "period", "model", "direction", "depth", "phase", "ramp"}
_IRREGULAR = {"hs", "tp", "spectrum", "gamma", "spreading", "components", "band", "seed", "direction", "depth",
              "stretching"}


def _waves(spec, env_spec, where):
    """The environment's waves of the file: regular ({height, period, direction?, depth?, phase?}:
    :class:`jaxnet.water.waves.Airy`) or an irregular sea ({hs, tp, spectrum?, gamma?, spreading?, components?, band?,
    seed?, direction?, depth?, stretching?}: :func:`jaxnet.water.waves.sea_state`), on the environment's surface
    level (0 where it has none), gravity and vertical; a bad value is a SceneError naming it."""
    from jaxnet.water import waves

    if spec is None:
        return None
    if not isinstance(spec, dict) or not ({"height", "hs"} & set(spec)):
        raise _fail(where, f"expected regular waves {{height, period, ...}} or a sea state {{hs, tp, ...}}, "
                           f"got {spec!r}")
    irregular = "hs" in spec
    _keys(spec, _IRREGULAR if irregular else _REGULAR, where, ("hs", "tp") if irregular else ("height", "period"))
    values = {}
    for key, value in spec.items():
        if key == "direction":
            values[key] = _triple(value, where / "direction")
        elif key in ("spectrum", "stretching", "model"):
            if not isinstance(value, str):
                raise _fail(where / key, f"expected a name, got {value!r}")
            values[key] = value
        elif key in ("components", "seed"):
            values[key] = _integer(value, where / key)
        elif key == "band":
            values[key] = tuple(_list(value, where / "band"))
        else:
            values[key] = _number(value, where / key)
    level = env_spec.get("surface_level", float("nan"))
    common = dict(surface_level=0.0 if np.isnan(level) else level, gravity=env_spec.get("gravity", 9.81),
                  up=env_spec.get("up", (0.0, 0.0, 1.0)))
    models = {"airy": waves.Airy, "stokes2": waves.Stokes2, "stokes3": waves.Stokes3}
    model = values.pop("model", "airy")
    if model not in models:
        raise _fail(where / "model", f"expected one of {sorted(models)}, got {model!r}")
    try:
        if irregular:
            return waves.sea_state(**values, **common)
        return models[model](**values, **common)
    except ValueError as err:
        raise _fail(where, str(err)) from None


def _culprit(message, doc, references):
    """The path of the entry of the document that an error of the built net names first: a panel or cable by its
    name ("panel 'wall': ...", "cable 'bridle' start: ..."), a reference of ``references`` ([(reference, path)]:
    "reference side 9 of panel 'wall': ..."), an environment key ("environment: current_speed ..."); None for
    another."""
    for key, word in (("panels", "panel"), ("cables", "cable")):
        entries = doc.get(key, [])
        for i, entry in enumerate(entries if isinstance(entries, list) else []):
            name = entry.get("name", f"{word}{i}") if isinstance(entry, dict) else None
            if isinstance(name, str) and message.startswith(f"{word} '{name}'"):
                return _refined(_SCENE / key / i, message, entry, f"{word} '{name}'")
    for ref, where in references:
        point = isinstance(ref, tuple) and f"no node at point {[float(v) for v in ref]}"
        if message.startswith(f"reference {describe_reference(ref)}") or (point and message.startswith(point)):
            return where
    if message.startswith("environment: "):
        return _SCENE / "environment" / message.removeprefix("environment: ").split(" ", 1)[0]
    return None


def from_dict(doc: dict, label: str = "scene document") -> Case:
    """The :class:`~jaxnet.case.Case` of a parsed scene document: its :class:`~jaxnet.net.Net` (built here) and
    solver options. A :class:`SceneError` names the key path of the culprit (``twines."wall 0"``,
    ``panels[2].corners``) and carries it as ``where`` (a tuple of keys and indices, None where the error names
    no entry of the document), which :func:`read` turns into the file's line."""
    # the free surface's elevation over each node is the dynamics' to set, step by step, not a file's
    env_fields = {f.name for f in dataclasses.fields(Environment)} - {"surface_elevation"}
    _keys(doc, _TOP, _SCENE, elsewhere=[f"environment.{k}" for k in sorted(env_fields)])
    at_env = _SCENE / "environment"
    env_spec = dict(_keys(doc.get("environment", {}), env_fields, at_env))
    for key, value in env_spec.items():
        if key in ("up", "current_direction"):
            env_spec[key] = _triple(value, at_env / key)
        elif key in ("profile_depth", "profile_factor"):
            env_spec[key] = _list(value, at_env / key)
        elif key == "bottom_moving":
            if not isinstance(value, bool):
                raise _fail(at_env / key, f"expected true or false, got {value!r}")
        elif key == "floating":
            if (not isinstance(value, list) or not all(isinstance(v, str) and v in FLOATING for v in value)
                    or len(set(value)) != len(value)):
                raise _fail(at_env / key, f"expected a list of distinct names from {list(FLOATING)}, got {value!r}")
            env_spec[key] = tuple(value)
        elif key != "waves":
            env_spec[key] = _number(value, at_env / key)
    if "waves" in env_spec:
        env_spec["waves"] = _waves(env_spec["waves"], env_spec, at_env / "waves")
    env = Environment(**env_spec)
    tolerance = {}
    if "merge_tolerance" in doc:
        tolerance["merge_tolerance"] = _number(doc["merge_tolerance"], _SCENE / "merge_tolerance")
        if not (math.isfinite(tolerance["merge_tolerance"]) and tolerance["merge_tolerance"] >= 0):
            raise _fail(_SCENE / "merge_tolerance", f"must be finite and >= 0 (m), got {doc['merge_tolerance']!r}")
    net = Net(environment=env, **tolerance)
    references = []   # (reference, its path): where an error of the built net that names a reference is
    # the materials are checked as their tables are read: an error names the table, not a panel that uses it
    tables = {}
    for key, make in (("twines", lambda v, w: _material(v, {}, Twine, w)),
                      ("hex_twines", lambda v, w: _hex_material(v, {}, w)),
                      ("ropes", lambda v, w: _material(v, {}, Rope, w))):
        entries = doc.get(key, {})
        if not isinstance(entries, dict):
            raise _fail(_SCENE / key, f"expected a table of named materials, got {type(entries).__name__}")
        tables[key] = {name: make(spec, _SCENE / key / name) for name, spec in entries.items()}
    for i, p in enumerate(doc.get("panels", [])):
        where = _SCENE / "panels" / i
        _keys(p, {"name", "corners", "twine", "hex_twine", "step", "numerical_twines", "lattice"}, where, ("corners",))
        if ("twine" in p) == ("hex_twine" in p):
            raise _fail(where, "give its material as twine (diamond meshes) or hex_twine (hexagonal), one of them")
        if "step" not in p and not ({"numerical_twines", "lattice"} & set(p)):
            raise _fail(where, "missing key(s) ['step'] (needed unless numerical_twines or lattice is given)")
        material = (_material(p["twine"], tables["twines"], Twine, where / "twine") if "twine" in p
                    else _hex_material(p["hex_twine"], tables["hex_twines"], where / "hex_twine"))
        lattice = None
        if "lattice" in p:
            lattice = tuple(_list(p["lattice"], where / "lattice"))
            if len(lattice) != 2:
                raise _fail(where / "lattice", f"expected [NU, NV], two numbers of meshes, got {p['lattice']!r}")
        corners = _rows(p["corners"], where / "corners", 5)
        step = _number(p["step"], where / "step") if "step" in p else None
        twines = (_numerical_twines(p["numerical_twines"], where / "numerical_twines") if "numerical_twines" in p
                  else None)
        with _within(where, p):   # Net.panel's errors name the panel
            net.panel(p.get("name", f"panel{i}"), corners, material, step, twines=twines, lattice=lattice)
    for i, c in enumerate(doc.get("cables", [])):
        where = _SCENE / "cables" / i
        _keys(c, {"name", "rope", "start", "end", "along", "n_bars", "length"}, where, ("rope",))
        options = dict(
            start=_ref(c["start"], where / "start") if "start" in c else None,
            end=_ref(c["end"], where / "end") if "end" in c else None,
            rope=_material(c["rope"], tables["ropes"], Rope, where / "rope"),
            n_bars=_integer(c["n_bars"], where / "n_bars") if "n_bars" in c else None,
            length=_number(c["length"], where / "length") if "length" in c else None,
            along=_ref(c["along"], where / "along") if "along" in c else None)
        with _within(where, c):   # Net.cable's errors name the cable
            net.cable(c.get("name", f"cable{i}"), **options)
    for i, pair in enumerate(doc.get("seams", [])):
        where = _SCENE / "seams" / i
        if not isinstance(pair, (list, tuple)) or len(pair) != 2:
            raise _fail(where, "a seam is a pair of panel sides")
        with _within(where):
            net.seam(_ref(pair[0], where / 0), _ref(pair[1], where / 1))
    for i, j in enumerate(doc.get("cable_joints", [])):
        where = _SCENE / "cable_joints" / i
        _keys(j, {"cables", "neutral_angle", "stiffness"}, where, ("cables",))
        names = j["cables"]
        if not isinstance(names, list) or len(names) != 2 or not all(isinstance(n, str) for n in names):
            raise _fail(where / "cables", f"expected the names of two cables [A, B], got {j['cables']!r}")
        options = {k: _number(j[k], where / k) for k in ("neutral_angle", "stiffness") if k in j}
        with _within(where, j, named=True):
            net.cable_joint(*j["cables"], **options)
    for i, f in enumerate(doc.get("fix", [])):
        where = _SCENE / "fix" / i
        _keys(f, {"at", "axes"}, where, ("at",))
        at = _ref(f["at"], where / "at")
        references.append((at, where / "at"))
        with _within(where, f):
            net.fix(at, f.get("axes", "xyz"))
    for i, plane in enumerate(doc.get("symmetry_planes", [])):
        where = _SCENE / "symmetry_planes" / i
        _keys(plane, {"axis", "at", "hold"}, where, ("axis",))
        if "hold" in plane and not isinstance(plane["hold"], bool):
            raise _fail(where / "hold", f"expected true or false, got {plane['hold']!r}")
        at = _number(plane.get("at", 0.0), where / "at")
        with _within(where, plane, named=True):
            net.symmetry_plane(plane["axis"], at, plane.get("hold", True))
    for i, a in enumerate(doc.get("attach", [])):
        where = _SCENE / "attach" / i
        _keys(a, {"at", "mass", "volume", "force", "drag_area", "size"}, where, ("at",))
        amounts = {k: _number(a[k], where / k) for k in ("mass", "volume", "drag_area", "size") if k in a}
        if "force" in a:
            amounts["force"] = _triple(a["force"], where / "force")
        at = _ref(a["at"], where / "at")
        references.append((at, where / "at"))
        with _within(where, a):
            net.attach(at, **amounts)
    for i, s in enumerate(doc.get("sinkers", [])):
        where = _SCENE / "sinkers" / i
        _keys(s, {"at", "mass", "density"}, where, ("at", "mass"))
        at = _ref(s["at"], where / "at")
        references.append((at, where / "at"))
        amounts = {k: _number(s[k], where / k) for k in ("mass", "density") if k in s}
        with _within(where, s):
            net.sinker(at, **amounts)
    for i, s in enumerate(doc.get("floats", [])):
        where = _SCENE / "floats" / i
        _keys(s, {"at", "buoyancy_N", "mass", "size", "drag_area"}, where, ("at", "buoyancy_N"))
        at = _ref(s["at"], where / "at")
        references.append((at, where / "at"))
        amounts = {k: _number(s[k], where / k) for k in ("buoyancy_N", "mass", "size", "drag_area") if k in s}
        with _within(where, s):
            net.float(at, **amounts)
    # FEMNET's node-type properties, given to every node of the reference (Net.body, Net.limit)
    for key, fields, give in (("bodies", ("drag_length", "drag_coefficient"), net.body),
                              ("limits", ("limit", "sense"), net.limit)):
        for i, entry in enumerate(doc.get(key, [])):
            where = _SCENE / key / i
            _keys(entry, {"at", *fields}, where, ("at", *fields))
            values = [_ref(entry["at"], where / "at"), *(_triple(entry[k], where / k) for k in fields)]
            references.append((values[0], where / "at"))
            with _within(where, entry, named=True):
                give(*values)
    if "catch" in doc:
        where = _SCENE / "catch"
        c = _keys(doc["catch"], {"volume", "drag_coefficient", "symmetry", "center", "axis", "density"}, where,
                  ("volume",))
        numbers = {k: _number(c[k], where / k) for k in ("volume", "drag_coefficient", "symmetry", "density") if k in c}
        if "center" in c:
            numbers["center"] = _triple(c["center"], where / "center")
        axis = _triple(c["axis"], where / "axis") if "axis" in c else None
        with _within(where, c):   # its errors name "catch"
            net.catch(**numbers, axis=axis)
    for i, entry in enumerate(doc.get("panel_catches", [])):
        where = _SCENE / "panel_catches" / i
        c = _keys(entry, {"volume", "panels", "drag_coefficient", "symmetry", "axis", "center"}, where, ("volume", "panels"))
        numbers = {k: _number(c[k], where / k) for k in ("volume", "drag_coefficient", "symmetry") if k in c}
        if not isinstance(c["panels"], list) or not all(isinstance(n, str) for n in c["panels"]):
            raise _fail(where / "panels", f"expected a list of panel names, got {c['panels']!r}")
        numbers.update({k: _triple(c[k], where / k) if k in c else None for k in ("axis", "center")})
        with _within(where, c, named=True):
            net.panel_catch(**numbers, panels=c["panels"])
    if "enclosure" in doc:
        where = _SCENE / "enclosure"
        e = _keys(doc["enclosure"], {"center", "axis"}, where, ("center", "axis"))
        center, axis = _triple(e["center"], where / "center"), _triple(e["axis"], where / "axis")
        with _within(where, e):
            net.enclose(center, axis)
    solver = _solver(doc.get("solver", {}))
    try:
        return from_net(net, solver, label=label)
    except SceneError as err:   # the built net's errors name a panel, a cable, ...: located at its entry
        err.where = _culprit(str(err), doc, references)
        raise


def read(path) -> Case:
    """Read a scene file (.json or .toml) into a :class:`~jaxnet.case.Case`. A :class:`SceneError` starts with the
    file and, where it can be told, the line of the culprit (``my.toml:12: twines."wall 0": ea must be > 0, got
    0.0 ...``; a misspelt key with the nearest known one: ``... unknown key(s) ['curent_speed']: did you mean
    current_speed? ...``); the line of an error of the built net is that of the panel or cable it names."""
    path = pathlib.Path(path)
    if not path.exists():
        raise SceneError(f"scene file {path} does not exist")
    if path.suffix not in (".json", ".toml"):
        raise SceneError(f"{path}: unknown scene file type '{path.suffix}' (use .json or .toml)")
    try:
        text = path.read_text(encoding="utf-8")   # what both formats are written in
        doc = _parse(text, path.suffix)
    except ValueError as err:   # a decoding error, a syntax error (they say where)
        line = getattr(err, "lineno", None) or _parse_error_line(str(err), text)
        raise SceneError(f"{path}:{line}: cannot parse: {err}" if line else f"{path}: cannot parse: {err}") from err
    try:
        return from_dict(doc, label=str(path))
    except SceneError as err:
        line = _line(text, path.suffix, getattr(err, "where", None))
        raise SceneError(f"{path}:{line}: {err}" if line else f"{path}: {err}") from None


def _parse_error_line(message, text):
    """The line a TOML syntax error names ("... (at line 3, column 9)", "... (at end of document)": the last line of
    ``text``), or None."""
    found = re.search(r"\bline (\d+)", message)
    if found:
        return int(found.group(1))
    return text.rstrip("\n").count("\n") + 1 if "end of document" in message else None


# -- where a key is in a file's text: its line ------------------------------------------------------------------


def _line(text, suffix, where):
    """The line (1-based) of the value at ``where`` (a path of keys and indices) in a scene file's text, or of the
    nearest entry above it that has one (a key's value is at its key's line, an entry of an array of tables at its
    ``[[...]]`` header); None without a path."""
    if where is None:
        return None
    try:
        lines = _toml_lines(text) if suffix == ".toml" else _json_lines(text)
    except (ValueError, IndexError):   # a text parsed but not followed here: its error keeps the file's name
        return None
    for n in range(len(where), 0, -1):
        if tuple(where[:n]) in lines:
            return lines[tuple(where[:n])]
    return None


def _line_of(text):
    """The function position -> line (1-based) of ``text``."""
    breaks = [i for i, ch in enumerate(text) if ch == "\n"]
    return lambda pos: bisect.bisect_left(breaks, pos) + 1


def _json_lines(text):
    """{path: line} of every key and array item of a JSON document's text (the standard library's parser keeps no
    positions): a key's line for the key, an item's first line for the item."""
    line, decoder, blank = _line_of(text), json.JSONDecoder(), re.compile(r"[ \t\r\n]*")
    lines = {}

    def value(pos, path):
        pos = blank.match(text, pos).end()
        lines.setdefault(path, line(pos))
        if text[pos] in "{[":
            closing, k = "}" if text[pos] == "{" else "]", 0
            pos = blank.match(text, pos + 1).end()
            while text[pos] != closing:
                if closing == "}":
                    key, pos = json.decoder.scanstring(text, pos + 1)
                    lines[path + (key,)] = line(pos)
                    pos = blank.match(text, pos).end() + 1   # past the colon
                    pos = value(pos, path + (key,))
                else:
                    pos = value(pos, path + (k,))
                    k += 1
                pos = blank.match(text, pos).end()
                if text[pos] == ",":
                    pos = blank.match(text, pos + 1).end()
            return pos + 1
        if text[pos] == '"':
            return json.decoder.scanstring(text, pos + 1)[1]
        return decoder.raw_decode(text, pos)[1]

    value(0, ())
    return lines


_TOML_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")
_TOML_SCALAR = re.compile(r"[^,\]\}\s#]+")   # a number, a boolean, a date: up to what ends it


def _toml_lines(text):
    """{path: line} of every key, table and array item of a TOML document's text (``tomllib`` keeps no positions):
    a table's header line for the table (``[twines."wall 0"]``), an array of tables' ``[[panels]]`` header for its
    entry (``("panels", 2)``), a key's line for its key (dotted keys and inline tables too), an item's first line
    for the item of an array. Follows the text ``tomllib`` has read: strings, comments, arrays over several lines."""
    line, n = _line_of(text), len(text)
    lines, arrays = {}, {}   # arrays: path of an array of tables -> its entries so far

    def end_of_line(pos):
        found = text.find("\n", pos)
        return n if found < 0 else found

    def skip(pos, newlines=False):
        """Past blanks and comments (and line ends where ``newlines``)."""
        while pos < n:
            if text[pos] in " \t" or (newlines and text[pos] in "\r\n"):
                pos += 1
            elif text[pos] == "#":
                pos = end_of_line(pos)
            else:
                break
        return pos

    def string(pos):
        """(the TOML string at ``pos``, the position after it)."""
        import tomllib

        for quote in ('"""', "'''"):
            if text.startswith(quote, pos):
                end = text.index(quote, pos + 3)
                while text.startswith(quote[0], end + 3):   # up to two quotes may end the string itself
                    end += 1
                return tomllib.loads(f"s = {text[pos:end + 3]}")["s"], end + 3
        if text[pos] == "'":
            end = text.index("'", pos + 1)
            return text[pos + 1:end], end + 1
        end = pos + 1
        while text[end] != '"':
            end += 2 if text[end] == "\\" else 1
        return tomllib.loads(f"s = {text[pos:end + 1]}")["s"], end + 1

    def key(pos):
        """(the parts of the (dotted) key at ``pos``, the position after it)."""
        parts = []
        while True:
            pos = skip(pos)
            if text[pos] in "\"'":
                part, pos = string(pos)
            else:
                bare = _TOML_BARE_KEY.match(text, pos)
                if bare is None:
                    raise ValueError(f"no key at {pos}")
                part, pos = bare.group(), bare.end()
            parts.append(part)
            pos = skip(pos)
            if text[pos] != ".":
                return tuple(parts), pos
            pos += 1

    def pair(pos, table):
        """The ``key = value`` at ``pos`` in ``table``: the position after its value."""
        at = line(pos)
        keys, pos = key(pos)
        for k in range(1, len(keys)):
            lines.setdefault(table + keys[:k], at)
        lines[table + keys] = at
        return value(skip(skip(pos) + 1), table + keys)   # past the '='

    def value(pos, path):
        lines.setdefault(path, line(pos))
        if text[pos] == "[":
            pos, k = skip(pos + 1, True), 0
            while text[pos] != "]":
                pos = skip(value(pos, path + (k,)), True)
                k += 1
                if text[pos] == ",":
                    pos = skip(pos + 1, True)
            return pos + 1
        if text[pos] == "{":
            pos = skip(pos + 1)
            while text[pos] != "}":
                pos = skip(pair(pos, path))
                if text[pos] == ",":
                    pos = skip(pos + 1)
            return pos + 1
        if text[pos] in "\"'":
            return string(pos)[1]
        return _TOML_SCALAR.match(text, pos).end()

    def header(keys, at, array):
        """The path of a table header's keys, through the last entry of each array of tables on the way; of a new
        entry for ``[[...]]``."""
        path = ()
        for k, part in enumerate(keys):
            path += (part,)
            lines.setdefault(path, at)
            if path in arrays and (k < len(keys) - 1 or not array):
                path += (arrays[path] - 1,)
        if array:
            arrays[path] = arrays.get(path, 0) + 1
            path += (arrays[path] - 1,)
        lines[path] = at
        return path

    table, pos = (), skip(0, True)
    while pos < n:
        array = text.startswith("[[", pos)
        if text[pos] == "[":
            keys, end = key(pos + (2 if array else 1))
            table = header(keys, line(pos), array)
            pos = text.index("]]" if array else "]", end) + (2 if array else 1)
        else:
            pos = pair(pos, table)
        pos = skip(end_of_line(pos), True)   # the rest of the line: a comment
    return lines


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
    from jaxnet.water import waves

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
