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
import json
import math
import pathlib
import re

import numpy as np

from jaxnet import materials
from jaxnet.case import Case, from_net
from jaxnet.materials import HexTwine
from jaxnet.mesh.twines import NumericalTwines
from jaxnet.net import CableEnd, CableNodes, Corner, Nearest, Net, PanelRef, Rope, Side, Twine, describe_reference
from jaxnet.scene import FLOATING, Environment, SceneError
from jaxnet.solve.options import Newton

_TOP = {"environment", "twines", "hex_twines", "ropes", "panels", "cables", "seams", "cable_joints", "fix",
        "symmetry_planes", "attach", "sinkers", "floats", "catch", "panel_catches", "enclosure", "bodies", "limits",
        "solver", "description", "merge_tolerance"}


STRING_FIELDS = {"drag_model", "knot_form"}  # material fields that are not numbers


class _Path(tuple):
    """Where a value is in a scene document: its keys and indices from the top (``("twines", "wall 0", "ea")``),
    shown as the file's key path (``twines."wall 0".ea``, ``panels[2].corners``; the document itself: ``scene``).
    ``path / key`` is the path of one of its entries (a key, or an index of an array)."""

    def __truediv__(self, key):
        return _Path((*self, key))

    def __str__(self):
        text = ""
        for key in self:
            text += f"[{key}]" if isinstance(key, int) else ("." if text else "") + toml_key(str(key))
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
    return _made(cls, {k: (v if k in STRING_FIELDS else _number(v, where / k))
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
    net = Net(environment=_environment(doc), **_merge_tolerance(doc))
    tables = _materials(doc)
    _add_panels(net, doc, tables)
    _add_cables(net, doc, tables)
    _add_joins(net, doc)
    references = []   # (reference, its path): where an error of the built net that names a reference is
    _add_fixings(net, doc, references)
    _add_attachments(net, doc, references)
    _add_catches(net, doc)
    solver = _solver(doc.get("solver", {}))
    try:
        return from_net(net, solver, label=label)
    except SceneError as err:   # the built net's errors name a panel, a cable, ...: located at its entry
        err.where = _culprit(str(err), doc, references)
        raise


def _environment(doc):
    """The document's ``environment`` table as an :class:`~jaxnet.scene.Environment`, its keys checked, and first
    the document's own top-level keys (a misspelt one may be an environment key put at the top)."""
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
    return Environment(**env_spec)


def _merge_tolerance(doc):
    """``{"merge_tolerance": m}`` where the document gives one (m, finite and >= 0), else ``{}``."""
    tolerance = {}
    if "merge_tolerance" in doc:
        tolerance["merge_tolerance"] = _number(doc["merge_tolerance"], _SCENE / "merge_tolerance")
        if not (math.isfinite(tolerance["merge_tolerance"]) and tolerance["merge_tolerance"] >= 0):
            raise _fail(_SCENE / "merge_tolerance", f"must be finite and >= 0 (m), got {doc['merge_tolerance']!r}")
    return tolerance


def _materials(doc):
    """The named materials: ``{"twines": {name: Twine}, "hex_twines": ..., "ropes": ...}``."""
    # the materials are checked as their tables are read: an error names the table, not a panel that uses it
    tables = {}
    for key, make in (("twines", lambda v, w: _material(v, {}, Twine, w)),
                      ("hex_twines", lambda v, w: _hex_material(v, {}, w)),
                      ("ropes", lambda v, w: _material(v, {}, Rope, w))):
        entries = doc.get(key, {})
        if not isinstance(entries, dict):
            raise _fail(_SCENE / key, f"expected a table of named materials, got {type(entries).__name__}")
        tables[key] = {name: make(spec, _SCENE / key / name) for name, spec in entries.items()}
    return tables


def _add_panels(net, doc, tables):
    """The document's panels, added to ``net`` (their materials named in ``tables`` or given inline)."""
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


def _add_cables(net, doc, tables):
    """The document's cables, added to ``net``."""
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


def _add_joins(net, doc):
    """The document's seams and cable joints, added to ``net``."""
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


def _add_fixings(net, doc, references):
    """The document's fixings and symmetry planes (what holds the net), added to ``net``; each reference and its
    path appended to ``references``."""
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


def _add_attachments(net, doc, references):
    """What the document attaches to nodes (masses, sinkers, floats, bodies, limits), added to ``net``; each
    reference and its path appended to ``references``."""
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


def _add_catches(net, doc):
    """The document's catch, panel catches and enclosure, added to ``net``."""
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
        doc = parse_text(text, path.suffix)
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


def parse_text(text, suffix):
    """The document of a scene file's text."""
    if suffix == ".toml":
        import tomllib

        return tomllib.loads(text)
    return json.loads(text)


def toml_string(value: str) -> str:
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


def toml_key(key: str) -> str:
    bare = key and all(ch.isascii() and (ch.isalnum() or ch in "_-") for ch in key)
    return key if bare else toml_string(key)
