"""A net written as a scene file (``.json`` or ``.toml``, the format :mod:`jaxnet.io.scene_file` reads): what
``jaxnet export`` writes. :func:`to_dict` makes the document of a :class:`~jaxnet.net.Net` (its description, the
solver options), :func:`write` the file, read back and checked to build the same scene."""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import pathlib

import jax
import numpy as np

from jaxnet.case import Case
from jaxnet.io.scene_file import STRING_FIELDS, from_dict, parse_text, toml_key, toml_string
from jaxnet.materials import HexTwine
from jaxnet.mesh.twines import NumericalTwines
from jaxnet.net import CableEnd, CableNodes, CableRef, Corner, Nearest, Net, PanelRef, Side
from jaxnet.scene import SceneError
from jaxnet.solve.options import Newton


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
        parsed = parse_text(text, path.suffix)
        differs = _difference(case.scene, from_dict(parsed, label=str(path)).scene)
        if differs:
            raise SceneError(f"{case.label or 'the case'}: its scene is not what its net builds ({differs}): it was "
                             "changed after the net was built, which a scene file cannot say")
    path.write_text(text, encoding="utf-8")
    return path


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
        spec[f.name] = str(value) if f.name in STRING_FIELDS else float(_scalar(value, f"{where}: {f.name}"))
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
        return toml_string(value)
    if isinstance(value, dict):
        return "{" + ", ".join(f"{toml_key(k)} = {_toml_value(v, inline=True)}" for k, v in value.items()) + "}"
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
        lines.append(f"{toml_key(key)} = {_toml_value(value, len(toml_key(key)) + 3)}")

    def section(path, table):
        for k, v in table.items():
            if not isinstance(v, dict) and not is_tables(v):
                pair(k, v)
        for k, v in table.items():
            name = ".".join(toml_key(p) for p in (*path, k))
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
