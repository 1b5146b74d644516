"""Figures computed from an equilibrium: twine and bar tensions, mesh opening angles, nodal forces by group,
reactions, loads, the catch report, and result.json's summary.

These are what a gear technologist reads off a solve; the writers in :mod:`jaxnet.io` only format them.
"""

from __future__ import annotations

import dataclasses
import datetime
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import geometry, model as model_lib, scene as scene_lib
from jaxnet.model import assemble, catch as catch_lib
from jaxnet.solve import programs, statics
from jaxnet.terms import cable, hexagonal as hexagonal_lib, pressure, tension, term as term_lib
from jaxnet.version import __version__


# The figures are computed by compiled programs, each for a scene shape, kept by :mod:`jaxnet.solve.programs`
# (on disk where the solver's are): evaluated op by op, jax 0.10 compiles a program for every operation,
# which made the figures of a first `jaxnet run` nearly as long as the solve.


def _netting_tensions(x, vertices, uv, l0, ea_traction, ea_compression):
    tu, tv = jax.vmap(tension.netting_tensions)(x[vertices], uv, l0, ea_traction, ea_compression)
    return jnp.stack([tu, tv], axis=1)


def _bar_tensions(x, ends, rest_length, ea_traction, ea_compression):
    return jax.vmap(cable.bar_tension)(x[ends], rest_length, ea_traction, ea_compression)


_netting_tensions_jit = programs.jit(_netting_tensions)
_bar_tensions_jit = programs.jit(_bar_tensions)


def twine_tensions(scene, x):
    """(E, 2) tensions (N) of the U and V twines of every netting triangle at positions x (N, 3)."""
    net = scene.netting
    if net is None:
        return np.zeros((0, 2))
    args = (np.asarray(x, dtype=float), net.vertices, net.uv, net.l0, net.ea_traction, net.ea_compression)
    return np.asarray(programs.obtain("twine_tensions", _netting_tensions_jit, args)(*args))


def bar_tensions(scene, x):
    """(B,) tensions (N) of the cable bars at positions x (N, 3)."""
    bars = scene.bars
    if bars is None:
        return np.zeros(0)
    args = (np.asarray(x, dtype=float), bars.ends, bars.rest_length, bars.ea_traction, bars.ea_compression)
    return np.asarray(programs.obtain("bar_tensions", _bar_tensions_jit, args)(*args))


class NetFigures(NamedTuple):
    """Every figure of a net at its positions that the outputs of a run read (result.json, ParaView's files, the
    pictures and the page), computed together by one compiled program (:func:`net_figures`).

    twine_tension: (E, 2) N, the U and V twines of every diamond netting triangle; opening_angle: (E,) rad, its
    meshes' opening angle; hexagonal_tension: (H, 3) N, the l, m, n twines of every hexagonal triangle;
    bar_tension: (B,) N, every cable bar; element_forces: per active term of a result group (the external forces:
    drag, catch, weight and buoyancy, applied forces, the sea bed; not the internal ones, twines and bars, mesh
    opening, knots, bending, which sum to zero over the net), (E, k, 3) N, the force each element of its family
    exerts on each of its vertices (:func:`jaxnet.model.assemble.forces_by_element`); nodal_forces: per such term,
    (N, 3) N, those forces summed onto the nodes."""

    twine_tension: np.ndarray
    opening_angle: np.ndarray
    hexagonal_tension: np.ndarray
    bar_tension: np.ndarray
    element_forces: dict
    nodal_forces: dict


def _net_figures(x, scene, model):
    """:class:`NetFigures`' arrays at positions x, in one program (``model``: the active terms whose forces it
    computes, static)."""
    out = {"element_forces": assemble.forces_by_element(x, scene, model)}
    net, bars, hexagonal = scene.netting, scene.bars, scene.hexagonal
    if net is not None:
        out["twine_tension"] = _netting_tensions(x, net.vertices, net.uv, net.l0, net.ea_traction, net.ea_compression)
        out["opening_angle"] = _opening_angles(x, net.vertices, net.uv)
    if bars is not None:
        out["bar_tension"] = _bar_tensions(x, bars.ends, bars.rest_length, bars.ea_traction, bars.ea_compression)
    if hexagonal is not None:
        out["hexagonal_tension"] = _hexagonal_tensions(x, hexagonal.vertices, hexagonal.uv, hexagonal.l0,
                                                       hexagonal.ea_traction, hexagonal.ea_compression)
    return out


def _figures_program(scene, x, forces):
    """The compiled program of :func:`net_figures` for ``scene``'s shape, its arguments and the terms it computes
    the forces of."""
    model = tuple(t for t in model_lib.active_terms(scene) if t.term.group is not None) if forces else ()
    args = (np.asarray(x, dtype=float), scene)
    return programs.obtain("net_figures", _net_figures_jit, args, {"model": model}), args, model


def prepare_figures(scene, forces=True):
    """Obtain the program of :func:`net_figures` for ``scene`` now (load it from disk or compile it), without
    running it, so that a later :func:`net_figures` of the same scene finds it in memory: the command line calls
    it in a thread of its own while the solver iterates, which then leaves the figures little more than their
    arithmetic to wait for."""
    _figures_program(scene, scene.nodes.position, forces)


def net_figures(scene, x, forces=True) -> NetFigures:
    """The :class:`NetFigures` of ``scene`` at positions x (N, 3) (m), by one compiled program kept by
    :mod:`jaxnet.solve.programs` (on disk where the solver's are): what a run's outputs read, computed once and
    handed to each of them (:func:`summary`'s and :func:`jaxnet.io.vtk.write_vtu`'s ``figures``, the pictures'
    tensions), where computing each figure on its own would compile a program for each. The forces are those of
    the terms in a result group (:attr:`jaxnet.terms.term.Term.group`): the internal terms, whose stiffness makes
    most of a solver's program, are left out; a reaction is the solve's own out-of-balance force
    (:meth:`jaxnet.solve.results.Equilibrium.reaction`). ``forces=False``: the tensions and angles only (the
    forces by term empty), for a record of a run in time."""
    program, args, model = _figures_program(scene, x, forces)
    raw = jax.device_get(program(*args))
    n = scene.n_nodes
    nodal = {}
    for term in model:
        per_element = np.asarray(raw["element_forces"][term.name])
        conn = np.asarray(assemble.connectivity(scene, term.term.family))
        total = np.zeros((n, 3))
        np.add.at(total, conn.ravel(), per_element.reshape(-1, 3))
        nodal[term.name] = total
    empty = np.zeros((0,))
    return NetFigures(
        twine_tension=np.asarray(raw.get("twine_tension", np.zeros((0, 2)))),
        opening_angle=np.asarray(raw.get("opening_angle", empty)),
        hexagonal_tension=np.asarray(raw.get("hexagonal_tension", np.zeros((0, 3)))),
        bar_tension=np.asarray(raw.get("bar_tension", empty)),
        element_forces={k: np.asarray(v) for k, v in raw["element_forces"].items()}, nodal_forces=nodal)


def total_load(scene):
    """(3,) sum of all constant loads (weight, buoyancy, external forces) in N."""
    return statics.constant_loads(scene, model_lib.active_terms(scene)).sum(axis=0)


def forces_by_term(scene, x, names=None):
    """Per active term, the total force (3,) in N it exerts on the net at positions x (N, 3); only the terms
    ``names`` when given.

    Internal terms (twine tension, bending, ...) sum to zero over the whole net; the external ones (drag,
    catch, weight and buoyancy, applied forces) make up, with the reactions, the balance of the net.
    """
    model = tuple(t for t in model_lib.active_terms(scene) if names is None or t.name in names)
    args = (np.asarray(x, dtype=float), scene)
    per_term = programs.obtain("term_forces", _term_forces, args, {"model": model})(*args)
    return {name: np.asarray(f).sum(axis=0) for name, f in per_term.items()}


_term_forces = programs.jit(assemble.term_forces, static_argnames="model")


def _catch(x, vertices, axis, volume, symmetry, sign, pressure_, center, up):
    """The catch front at positions x and FEMNET's catch summary there, in one program."""
    front = catch_lib.catch_front(x, vertices, axis, volume, symmetry, sign=sign)
    return front, catch_lib.catch_summary(x, vertices, axis, front.position, pressure_, symmetry, sign=sign,
                                          center=center, up=up)


_catch_jit = programs.jit(_catch)


def force_breakdown(scene, x, by_term=None):
    """result.json's force groups (the terms' declared groups, :func:`jaxnet.terms.term.groups`): total drag
    on netting, cables, nodes, catch, weight, ... (N), every group, zero where none of its terms is active: the
    nodal forces of :func:`nodal_forces_by_group` summed over the nodes. They are computed by the one program of
    every term's nodal forces that the ParaView file's forces come from (``by_term``: those forces at x when
    already computed), so a run compiles one, not two."""
    return {group: f.sum(axis=0) for group, f in nodal_forces_by_group(scene, x, by_term).items()}


def _catch_fields(x, vertices, axis, volume, symmetry, sign, pressure_, center, up):
    """One catch's front and FEMNET's summary of it as result.json's fields (:func:`_catch`'s arguments)."""
    args = (np.asarray(x, dtype=float), vertices, axis, volume, symmetry, sign, pressure_, center, up)
    front, summary = programs.obtain("catch_report", _catch_jit, args)(*args)
    return {
        "front_m": float(front.position),
        "holds_the_volume": bool(front.holds),
        "volume_m3": float(summary.volume),
        "drag_N": float(summary.drag),
        "thickness_m": float(summary.thickness),
        "diameter_m": float(summary.diameter),
    }


def catch_report(scene, x):
    """Catch front, volume, drag, thickness and largest diameter (FEMNET's catch summary), or None."""
    c = scene.catch
    if c is None or scene.netting is None:
        return None
    net, env = scene.netting, scene.environment
    p = pressure.dynamic_pressure(env.water_density, c.drag_coefficient, env.current_speed)
    return _catch_fields(x, net.vertices, c.axis, c.volume, c.symmetry, net.outward, p, c.center, env.up)


def panel_catch_report(scene, x):
    """For each panel catch (:class:`jaxnet.scene.PanelCatches`), in order: the panels holding it, and its front,
    volume, drag, thickness and largest diameter as :func:`catch_report` gives the main catch's, computed on its
    own panels' triangles (diameters: half the extent of its nodes behind the front); or None without any."""
    pc = scene.panel_catches
    if pc is None or scene.netting is None:
        return None
    net, env = scene.netting, scene.environment
    holder = np.asarray(pc.panel_catch)[np.asarray(net.panel)]
    p = pressure.dynamic_pressure(env.water_density, pc.drag_coefficient, env.current_speed)
    names = scene.panel_names or tuple(f"panel {k}" for k in range(len(pc.panel_catch)))
    out = []
    for k, volume in enumerate(np.asarray(pc.volume)):
        rows = holder == k
        fields = _catch_fields(x, np.asarray(net.vertices)[rows], pc.axis, volume, pc.symmetry,
                               np.asarray(net.outward)[rows], p, None, env.up)
        out.append({"panels": [names[j] for j in np.flatnonzero(np.asarray(pc.panel_catch) == k)], **fields})
    return out


def enclosed_volume(scene, x):
    """Volume (m³) the net holds behind its opening (scenes with an enclosure), or None."""
    e = scene.enclosure
    if e is None or scene.netting is None:
        return None
    front = float(np.dot(e.center, e.axis))
    return float(catch_lib.enclosed_volume(np.asarray(x), scene.netting.vertices, front, e.axis, sign=scene.netting.outward))


# -- result.json (docs/result.md: its schema) ---------------------------------------------------------------


def _json(value):
    """``value`` as JSON's plain values: arrays and tuples as lists, numpy and JAX scalars as Python numbers,
    dataclasses as dicts; NaN and infinities as null, as JSON has neither (a NaN surface level: no free surface;
    an infinite depth: deep water; an infinite step limit: none); -0.0 as 0.0 (a held coordinate with no force
    on it is no "-0")."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {f.name: _json(getattr(value, f.name)) for f in dataclasses.fields(value)}
    if isinstance(value, dict):
        return {str(k): _json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json(v) for v in value]
    if value is None or isinstance(value, (bool, str)):
        return value
    array = np.asarray(value)
    if array.ndim:
        return [_json(v) for v in array]
    if np.issubdtype(array.dtype, np.bool_):
        return bool(array)
    if np.issubdtype(array.dtype, np.integer):
        return int(array)
    number = float(array)
    return number + 0.0 if np.isfinite(number) else None  # -0.0 + 0.0 is 0.0


def _waves_inputs(waves):
    """The waves of the environment, by their type and main numbers (m, s, rad), or None for still water.
    Regular waves (:class:`jaxnet.water.waves.Airy` and its Stokes orders) by height, period, direction, depth, phase
    and ramp; an irregular sea (:class:`jaxnet.water.waves.Irregular`) by its number of components, its significant
    height 4 √m0 (m0 = Σ a_i²/2, the variance of the elevation), its peak period and the energy-weighted mean
    of its components' headings, not component by component (hundreds of them)."""
    if waves is None:
        return None
    kind = type(waves).__name__
    if hasattr(waves, "height"):
        return {"type": kind, "height_m": _json(waves.height), "period_s": _json(waves.period),
                "direction": _json(waves.direction), "depth_m": _json(waves.depth), "phase_rad": _json(waves.phase),
                "ramp_s": _json(waves.ramp)}
    if hasattr(waves, "amplitude"):
        a = np.asarray(waves.amplitude, dtype=float)
        heading = (a[:, None] ** 2 * np.asarray(waves.direction, dtype=float)).sum(axis=0)
        norm = np.linalg.norm(heading)
        return {"type": kind, "components": int(a.size),
                "significant_height_m": float(4.0 * np.sqrt(0.5 * (a**2).sum())),
                "peak_period_s": _json(waves.peak_period),
                "mean_direction": _json(heading / norm if norm > 0 else heading),
                "depth_m": _json(waves.depth), "stretching": waves.stretching, "ramp_s": _json(waves.ramp)}
    return {"type": kind}


def _sea_bed_levels(scene):
    """The distinct heights (m) of the floors the nodes' limits put along ``up`` (the sea bed: FEMNET's node types
    may give several), sorted; empty where no node has one."""
    nodes, axis = scene.nodes, scene_lib.bottom_axis(scene.environment)
    if nodes.limit is None or nodes.limit_sense is None or axis is None:
        return []
    axis, floor = axis
    on_floor = np.asarray(nodes.limit_sense)[:, axis] == floor
    return sorted(set(np.asarray(nodes.limit, dtype=float)[on_floor, axis].tolist()))


def _environment_inputs(scene):
    """result.json's ``inputs.environment``: the surroundings' numbers (:class:`jaxnet.scene.Environment`)."""
    env = scene.environment
    return {
        "gravity_m_s2": _json(env.gravity),
        "water_density_kg_m3": _json(env.water_density),
        "up": _json(env.up),
        "current": {"speed_m_s": _json(env.current_speed), "direction": _json(env.current_direction),
                    "profile_depth_m": _json(env.profile_depth), "profile_factor": _json(env.profile_factor)},
        "surface_level_m": _json(env.surface_level),
        "floating": list(env.floating),
        "sea_bed": {"levels_m": _sea_bed_levels(scene), "stiffness_N_m": _json(env.bottom_stiffness),
                    "band_m": _json(env.bottom_band), "friction": _json(env.bottom_friction),
                    "moving": bool(env.bottom_moving)},
        "waves": _waves_inputs(env.waves),
        "time_s": _json(env.time),
        "added_mass_coefficient": _json(env.added_mass_coefficient),
    }


def _catch_inputs(scene):
    """result.json's ``inputs.catch`` (:class:`jaxnet.scene.Catch`) and ``inputs.panel_catches``
    (:class:`jaxnet.scene.PanelCatches`), each None where the scene has none."""
    c, pc = scene.catch, scene.panel_catches
    catch = None if c is None else {
        "volume_whole_net_m3": _json(c.volume), "drag_coefficient": _json(c.drag_coefficient),
        "symmetry": _json(c.symmetry), "axis": _json(c.axis), "center_m": _json(c.center),
        "density_kg_m3": _json(c.density)}
    panels = None
    if pc is not None:
        names = scene.panel_names or tuple(f"panel {k}" for k in range(len(pc.panel_catch)))
        holder = np.asarray(pc.panel_catch)
        panels = {"catches": [{"volume_whole_net_m3": _json(v),
                               "panels": [names[j] for j in np.flatnonzero(holder == k)]}
                              for k, v in enumerate(np.asarray(pc.volume))],
                  "drag_coefficient": _json(pc.drag_coefficient), "symmetry": _json(pc.symmetry),
                  "axis": _json(pc.axis)}
    return catch, panels


def _inputs(scene, case, source, solver):
    """result.json's ``inputs``: what was solved, and how (summary's arguments)."""
    catch, panels = _catch_inputs(scene)
    solver = solver if solver is not None else None if case is None else case.solver
    return {
        "source": None if source is None else str(source),
        "label": None if case is None else case.label,
        "environment": _environment_inputs(scene),
        "catch": catch,
        "panel_catches": panels,
        "symmetry_planes": [{"axis": "xyz"[axis], "position_m": float(at)} for axis, at in scene.symmetry_planes],
        "solver": None if solver is None else _json(solver),
    }


#: the modelled part of a net, by its number of copies in the whole net
_PARTS = {1: "the whole net", 2: "a half", 4: "a quarter", 8: "an eighth"}


def _modelled_part(scene):
    """What the model is of the whole net, in words: "the whole net", or "a quarter of the net (2 symmetry planes:
    y = 0 m, z = 0 m)"."""
    copies = scene_lib.mirror_copies(scene)
    if copies == 1:
        return _PARTS[1]
    planes = ", ".join(f"{'xyz'[axis]} = {at:g} m" for axis, at in scene.symmetry_planes)
    n = len(scene.symmetry_planes)
    return f"{_PARTS.get(copies, f'1/{copies}')} of the net ({n} symmetry plane{'s' if n > 1 else ''}: {planes})"


def _whole(signs, force):
    """The whole net's total of a force (3,) (N) of the modelled part: its mirror images summed (``signs``:
    :func:`jaxnet.scene.mirror_signs`); along a plane's normal the images cancel."""
    return (signs * np.asarray(force, dtype=float)).sum(axis=0)


def _catch_parts(report, copies):
    """A catch report (:func:`catch_report`'s, of the whole net) as result.json gives it: volume and drag of the
    modelled part and of the whole net (``copies``: the catch's ``symmetry``), the front, thickness and largest
    diameter, which are the same for both."""
    return {
        "front_m": report["front_m"],
        "holds_the_volume": report["holds_the_volume"],
        "copies": _json(copies),
        "volume_m3": report["volume_m3"] / copies,
        "volume_whole_net_m3": report["volume_m3"],
        "drag_N": report["drag_N"] / copies,
        "drag_whole_net_N": report["drag_N"],
        "thickness_m": report["thickness_m"],
        "diameter_m": report["diameter_m"],
    }


#: one line on each of result.json's main figures, written into the file as its ``about`` (docs/result.md has
#: the whole schema)
ABOUT = {
    "reaction_N": "the force the fixings exert on the net (N, [x, y, z]), the symmetry planes' holding included",
    "load_N": "every force on the net that is not the water's: weight and buoyancy, forces applied to nodes, the sea "
              "bed, a catch's weight (N); reaction_N + load_N + water_N = 0 at the equilibrium",
    "water_N": "the water's forces on the net: drag of the netting, cables and nodes, and the catch's pressure (N)",
    "forces_N": "the force of each group of terms on the net (N); load_N and water_N are their sums",
    "weight_and_buoyancy_by_carrier_N": "forces_N.weight_and_buoyancy_N split by what carries it: the netting, each "
                                        "cable, the sinkers (lumped masses heavier than the water they displace) "
                                        "and the floats (lighter) (N; - along up is weight, + buoyancy)",
    "max_twine_tension_N": "the largest tension of a netting twine (N), the top of net.png's colour bar",
    "max_bar_tension_N": "the largest tension of a cable bar (N)",
    "residual_N": "the largest out-of-balance force left on a node (N): how far from equilibrium the answer is",
    "whole_net": "the force figures of the whole net, the modelled part and its mirror images (present only for a "
                 "model with symmetry planes)",
}


def weight_by_carrier(scene, element_forces):
    """The weight and buoyancy of the net (N, (3,) each) by what carries it, from ``element_forces`` (per term,
    (E, k, 3) N: :attr:`NetFigures.element_forces`): ``"netting"``, ``"hexagonal netting"``, each cable by its name
    (:attr:`jaxnet.scene.Scene.cable_names`), ``"sinkers"`` (the lumped masses whose weight exceeds their buoyancy:
    sinkers, clump weights) and ``"floats"`` (those lighter than the water they displace: floats, buoys); only the
    carriers present, in that order. They sum to the ``weight_and_buoyancy_N`` group of :func:`force_breakdown`,
    whose terms they split: the constant loads of a net under water and the energies of the heights of what
    floats at a free surface alike."""
    weight_terms = term_lib.groups().get(term_lib.WEIGHT.name, ())
    families = {t.name: t.family for t in term_lib.registered()}
    out = {}

    def add(name, force):
        out[name] = out.get(name, np.zeros(3)) + force

    for name in weight_terms:
        if name not in element_forces:
            continue
        per_element = np.asarray(element_forces[name]).sum(axis=1)        # (E, 3) N
        family = families[name]
        if family == "netting":
            add("netting", per_element.sum(axis=0))
        elif family == "hexagonal":
            add("hexagonal netting", per_element.sum(axis=0))
        elif family == "bars":
            cable = np.asarray(scene.bars.cable)
            for c in np.unique(cable):
                label = scene.cable_names[c] if c < len(scene.cable_names) else f"cable {c}"
                add(label, per_element[cable == c].sum(axis=0))
        elif family == "nodes":
            lumped = np.asarray(scene.nodes.mass) - float(scene.environment.water_density) * np.asarray(scene.nodes.volume)
            for label, rows in (("sinkers", lumped > 0), ("floats", lumped < 0)):
                if rows.any():
                    add(label, per_element[rows].sum(axis=0))
        else:
            add(family, per_element.sum(axis=0))
    order = ["netting", "hexagonal netting", *scene.cable_names, "sinkers", "floats"]
    ranked = sorted(out, key=lambda k: order.index(k) if k in order else len(order))
    return {k: out[k] for k in ranked if np.any(out[k] != 0) or k in ("sinkers", "floats")}


def summary(scene, eq, *, case=None, source=None, solver=None, figures=None):
    """The figures of ``result.json`` (``docs/result.md``: every key, its unit, the balance they obey).

    scene, eq: the scene solved and its :class:`~jaxnet.solve.results.Equilibrium`. case: the
    :class:`~jaxnet.case.Case` it came from, for its label (and solver options where ``solver`` is not given);
    source: what was solved: the file read (a path), a built-in scene's name (``"built-in scene 'cage'"``), None
    for a scene made in Python; solver: the :class:`~jaxnet.solve.options.Newton` options the solve ran with (the
    case's with the command line's changes); figures: the :class:`NetFigures` at the equilibrium when already
    computed (the command line hands the same to every output), else computed here.
    Recorded under ``inputs`` with the scene's environment, catches and symmetry planes, so that a result says
    what it is a result of.

    The force figures (``reaction_N``, ``load_N``, ``water_N``, ``forces_N``) are of the modelled part; for a
    model with symmetry planes ``whole_net`` holds them for the whole net (its mirrored copies). ``load_N`` is the
    total of the groups that are not the water's (weight and buoyancy, external forces, the sea bed, a catch's
    weight) at the equilibrium, ``water_N`` that of the water's (the hydrodynamic groups), so that ``reaction_N +
    load_N + water_N = 0`` to the residual, with a free surface too (where weight is an energy of the positions,
    not a constant load). ``weight_and_buoyancy_by_carrier_N`` splits the weight and buoyancy by what carries it
    (:func:`weight_by_carrier`); ``about`` says in a line what the main figures are (:data:`ABOUT`).
    Plain JSON values throughout: a non-finite number (a failed solve's NaN residual) is null.
    """
    x = np.asarray(eq.x, dtype=float)
    figures = net_figures(scene, x) if figures is None else figures
    reaction = eq.reaction(scene).sum(axis=0)
    tw, bt = figures.twine_tension, figures.bar_tension
    hist = np.asarray(eq.history)
    forces = force_breakdown(scene, x, figures.nodal_forces)
    loads = term_lib.groups(lambda group, term: not group.hydrodynamic)
    load = np.sum([forces[g] for g in loads] or [np.zeros(3)], axis=0)
    water = np.sum([forces[g] for g in forces if g not in loads] or [np.zeros(3)], axis=0)
    # a carrier whose weight is rounding beside the forces on the net (a rope as dense as the water) is left out
    scale = float(np.linalg.norm(reaction) + np.linalg.norm(load) + np.linalg.norm(water))
    carriers = {k: v for k, v in weight_by_carrier(scene, figures.element_forces).items()
                if np.linalg.norm(v) > 1e-12 * scale}
    worst = int(eq.worst_node)
    out = {
        "jaxnet_version": __version__,
        "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "converged": bool(eq.converged),
        "reason": eq.reason,
        "iterations": int(eq.iterations),
        "residual_N": float(eq.residual_N),
        "worst_node": {"node": worst, "position_m": x[worst].tolist()},
        "residual_history_N": [float(r) for r in hist[np.isfinite(hist)]],
        "n_nodes": scene.n_nodes,
        "n_elements": scene.n_elements,
        "n_triangles": 0 if scene.netting is None else int(scene.netting.vertices.shape[0]),
        "n_bars": 0 if scene.bars is None else int(scene.bars.ends.shape[0]),
        "n_dof": scene.n_dof,
        "terms": [t.name for t in model_lib.active_terms(scene)],
        "modelled_part": _modelled_part(scene),
        "reaction_N": reaction.tolist(),
        "load_N": load.tolist(),
        "water_N": water.tolist(),
        "weight_and_buoyancy_by_carrier_N": {k: v.tolist() for k, v in carriers.items()},
        "max_twine_tension_N": float(tw.max()) if tw.size else 0.0,
        "max_bar_tension_N": float(bt.max()) if bt.size else 0.0,
        "bounding_box_m": [x.min(axis=0).tolist(), x.max(axis=0).tolist()],
        "forces_N": {k: np.asarray(v).tolist() for k, v in forces.items()},
    }
    signs = scene_lib.mirror_signs(scene)
    images = scene_lib.mirrored(scene, x).reshape(-1, 3)
    whole = {
        "copies": scene_lib.mirror_copies(scene),
        "reaction_N": _whole(signs, reaction).tolist(),
        "load_N": _whole(signs, load).tolist(),
        "water_N": _whole(signs, water).tolist(),
        "forces_N": {k: _whole(signs, v).tolist() for k, v in forces.items()},
        "bounding_box_m": [images.min(axis=0).tolist(), images.max(axis=0).tolist()],
    }
    volume = enclosed_volume(scene, x)
    if volume is not None:
        out["enclosed_volume_m3"] = volume
        whole["enclosed_volume_m3"] = whole["copies"] * volume
    if whole["copies"] > 1:   # a whole net's figures are the top level's: not repeated
        out["whole_net"] = whole
    report = catch_report(scene, x)
    if report is not None:
        out["catch"] = _catch_parts(report, float(scene.catch.symmetry))
    panels = panel_catch_report(scene, x)
    if panels is not None:
        copies = float(scene.panel_catches.symmetry)
        out["panel_catches"] = [{"panels": p["panels"], **_catch_parts(p, copies)} for p in panels]
    out["inputs"] = _inputs(scene, case, source, solver)
    out["about"] = {k: v for k, v in ABOUT.items() if k in out}
    if eq.timing is not None:
        out["wall_s"] = float(eq.timing.wall_s)
        out["compile_s"] = float(eq.timing.compile_s)
    return _json(out)  # a failed solve's NaN as null: result.json stays JSON


# -- per node and per triangle: what the ParaView files draw (:mod:`jaxnet.io.vtk`) ----------------------------


def nodal_forces_by_term(scene, x):
    """Per active term (:func:`jaxnet.model.active_terms`), the (N, 3) nodal forces (N) it exerts on the net at
    positions x (N, 3): :func:`jaxnet.model.assemble.term_forces`, by the program :func:`forces_by_term` runs for all
    the terms (one compilation serves both). Their sum is the out-of-balance force on every node."""
    model = model_lib.active_terms(scene)
    args = (np.asarray(x, dtype=float), scene)
    per_term = programs.obtain("term_forces", _term_forces, args, {"model": model})(*args)
    return {name: np.asarray(f) for name, f in per_term.items()}


def nodal_forces_by_group(scene, x, by_term=None):
    """Every result group (:func:`jaxnet.terms.term.groups`: ``drag_netting_N``, ``catch_N``,
    ``weight_and_buoyancy_N``, ``bottom_N``...) -> (N, 3) the force (N) its active terms exert on each node at
    positions x (N, 3), zero where none of its terms is active; summed over the nodes, :func:`force_breakdown`.
    ``by_term``: :func:`nodal_forces_by_term` at x when already computed. The internal terms (twine tension,
    bending...), in no group, are left out: they move forces between nodes and sum to zero over the net."""
    by_term = nodal_forces_by_term(scene, x) if by_term is None else by_term
    zero = np.zeros((scene.n_nodes, 3))
    return {group: np.sum([by_term[t] for t in terms if t in by_term] or [zero], axis=0)
            for group, terms in term_lib.groups().items()}


def nodal_reactions(scene, x, by_term=None):
    """(N, 3) the reactions (N) at the held coordinates at positions x (N, 3), zero on the free ones: minus the
    out-of-balance force there (the sum of every active term's nodal force), as
    :meth:`jaxnet.solve.results.Equilibrium.reaction` takes them from a solve's own force. ``by_term``:
    :func:`nodal_forces_by_term` at x when already computed."""
    by_term = nodal_forces_by_term(scene, x) if by_term is None else by_term
    force = np.sum([*by_term.values(), np.zeros((scene.n_nodes, 3))], axis=0)
    return np.where(np.asarray(scene.nodes.fixed, dtype=bool), -force, 0.0)


def _opening_angles(x, vertices, uv):
    def angle(xe, uve):
        U, V, _ = geometry.twine_vectors(xe, uve)
        return 2.0 * geometry.half_opening_angle(U, V)

    return jax.vmap(angle)(x[vertices], uv)


_opening_angles_jit = programs.jit(_opening_angles)


def mesh_opening_angles(scene, x):
    """(E,) the opening angle (rad) of the meshes of every diamond netting triangle at positions x (N, 3): the
    angle between its U and V twine vectors (:func:`jaxnet.geometry.twine_vectors`), twice the half angle of the
    mesh opening term (eq. 4.211); pi/2 for square meshes, 0 for closed ones."""
    net = scene.netting
    if net is None:
        return np.zeros(0)
    args = (np.asarray(x, dtype=float), net.vertices, net.uv)
    return np.asarray(programs.obtain("mesh_opening_angles", _opening_angles_jit, args)(*args))


def _hexagonal_tensions(x, vertices, uv, l0, ea_traction, ea_compression):
    return jax.vmap(hexagonal_lib.hexagonal_tensions)(x[vertices], uv, l0, ea_traction, ea_compression)


_hexagonal_tensions_jit = programs.jit(_hexagonal_tensions)


def hexagonal_twine_tensions(scene, x):
    """(E, 3) tensions (N) of the three twine families (l, m, n) of every hexagonal netting triangle at positions
    x (N, 3), at the equilibrium of its knots (eqs 4.85-4.87)."""
    hexagonal = scene.hexagonal
    if hexagonal is None:
        return np.zeros((0, 3))
    args = (np.asarray(x, dtype=float), hexagonal.vertices, hexagonal.uv, hexagonal.l0, hexagonal.ea_traction,
            hexagonal.ea_compression)
    return np.asarray(programs.obtain("hexagonal_twine_tensions", _hexagonal_tensions_jit, args)(*args))


_net_figures_jit = programs.jit(_net_figures, static_argnames="model")
