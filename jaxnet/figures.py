"""Figures computed from an equilibrium: twine and bar tensions, reactions, loads, summary.

These are what a gear technologist reads off a solve; the writers in :mod:`jaxnet.io` only format them.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import assemble, catch as catch_lib, model as model_lib
from jaxnet.solve import programs, statics
from jaxnet.terms import cable, pressure, tension, term as term_lib


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


def force_breakdown(scene, x):
    """result.json's force groups (the terms' declared groups, :func:`jaxnet.terms.term.groups`): total drag
    on netting, cables, nodes, catch, weight, ... (N), every group, zero where none of its terms is active.
    Only the terms of the groups are computed (the internal ones, which sum to zero, are not asked for)."""
    groups = term_lib.groups()
    by_term = forces_by_term(scene, x, names={t for terms in groups.values() for t in terms})
    return {group: np.sum([by_term[t] for t in terms if t in by_term] or [np.zeros(3)], axis=0)
            for group, terms in groups.items()}


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


def summary(scene, eq):
    """The figures of ``result.json`` (see the README for their meaning and units); the solve's wall and
    compile times where the equilibrium holds them (``eq.timing``)."""
    reaction = eq.reaction(scene)
    tw = twine_tensions(scene, eq.x)
    bt = bar_tensions(scene, eq.x)
    hist = np.asarray(eq.history)
    out = {
        "converged": bool(eq.converged),
        "reason": eq.reason,
        "iterations": int(eq.iterations),
        "residual_N": float(eq.residual_N),
        "worst_node": int(eq.worst_node),
        "residual_history_N": [float(r) for r in hist[np.isfinite(hist)]],
        "n_nodes": scene.n_nodes,
        "n_elements": scene.n_elements,
        "n_triangles": 0 if scene.netting is None else int(scene.netting.vertices.shape[0]),
        "n_bars": 0 if scene.bars is None else int(scene.bars.ends.shape[0]),
        "n_dof": scene.n_dof,
        "terms": [t.name for t in model_lib.active_terms(scene)],
        "reaction_N": reaction.sum(axis=0).tolist(),
        "load_N": total_load(scene).tolist(),
        "max_twine_tension_N": float(tw.max()) if tw.size else 0.0,
        "max_bar_tension_N": float(bt.max()) if bt.size else 0.0,
        "bounding_box_m": [np.asarray(eq.x).min(axis=0).tolist(), np.asarray(eq.x).max(axis=0).tolist()],
        "forces_N": {k: v.tolist() for k, v in force_breakdown(scene, eq.x).items()},
    }
    volume = enclosed_volume(scene, eq.x)
    if volume is not None:
        out["enclosed_volume_m3"] = volume
    report = catch_report(scene, eq.x)
    if report is not None:
        out["catch"] = report
    panels = panel_catch_report(scene, eq.x)
    if panels is not None:
        out["panel_catches"] = panels
    if eq.timing is not None:
        out["wall_s"] = float(eq.timing.wall_s)
        out["compile_s"] = float(eq.timing.compile_s)
    return out
