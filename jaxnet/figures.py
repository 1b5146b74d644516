"""Figures computed from an equilibrium: twine and bar tensions, reactions, loads, summary.

These are what a gear technologist reads off a solve; the writers in :mod:`jaxnet.io` only format them.
"""

from __future__ import annotations

import jax
import numpy as np

from jaxnet import assemble, catch as catch_lib, model as model_lib
from jaxnet.solve import programs
from jaxnet.terms import cable, pressure, tension

#: result.json force groups: name -> the terms whose total force (over all nodes) it sums
FORCE_GROUPS = {
    "drag_netting_N": ("netting_drag",),
    "drag_cables_N": ("bar_drag",),
    "drag_nodes_N": ("node_drag", "node_box_drag"),
    "catch_N": ("catch_pressure",),
    "weight_and_buoyancy_N": ("netting_weight", "bar_weight", "node_weight", "netting_gravity_at_surface",
                              "bar_gravity_at_surface", "node_gravity_at_surface"),
    "external_N": ("node_force",),
    "bottom_N": ("bottom_contact", "bottom_friction"),
}


def twine_tensions(scene, x):
    """(E, 2) tensions (N) of the U and V twines of every netting triangle at positions x (N, 3)."""
    net = scene.netting
    if net is None:
        return np.zeros((0, 2))
    x = np.asarray(x)
    tu, tv = jax.vmap(tension.netting_tensions)(x[np.asarray(net.vertices)], net.uv, net.l0, net.ea_traction, net.ea_compression)
    return np.stack([np.asarray(tu), np.asarray(tv)], axis=1)


def bar_tensions(scene, x):
    """(B,) tensions (N) of the cable bars at positions x (N, 3)."""
    bars = scene.bars
    if bars is None:
        return np.zeros(0)
    x = np.asarray(x)
    return np.asarray(jax.vmap(cable.bar_tension)(x[np.asarray(bars.ends)], bars.rest_length, bars.ea_traction, bars.ea_compression))


def total_load(scene):
    """(3,) sum of all constant loads (weight, buoyancy, external forces) in N."""
    return np.asarray(assemble.loads(scene, model_lib.active_terms(scene))).sum(axis=0)


def forces_by_term(scene, x):
    """Per active term, the total force (3,) in N it exerts on the net at positions x (N, 3).

    Internal terms (twine tension, bending, ...) sum to zero over the whole net; the external ones (drag,
    catch, weight and buoyancy, applied forces) make up, with the reactions, the balance of the net.
    """
    m = model_lib.active_terms(scene)
    per_term = _term_forces(jax.numpy.asarray(x), scene, model=m)
    return {name: np.asarray(f).sum(axis=0) for name, f in per_term.items()}


# compiled once per scene shape (evaluated op by op they take seconds on a large net)
_term_forces = programs.jit(assemble.term_forces, static_argnames="model")
_catch_front = programs.jit(catch_lib.catch_front)
_catch_summary = programs.jit(catch_lib.catch_summary)


def force_breakdown(scene, x):
    """result.json's force groups (:data:`FORCE_GROUPS`): total drag on netting, cables, nodes, catch, ... (N)."""
    by_term = forces_by_term(scene, x)
    return {group: np.sum([by_term[t] for t in terms if t in by_term] or [np.zeros(3)], axis=0)
            for group, terms in FORCE_GROUPS.items()}


def catch_report(scene, x):
    """Catch front, volume, drag, thickness and largest diameter (FEMNET's catch summary), or None."""
    c = scene.catch
    if c is None or scene.netting is None:
        return None
    net = scene.netting
    front = _catch_front(jax.numpy.asarray(x), net.vertices, c.axis, c.volume, c.symmetry, sign=net.outward)
    p = pressure.dynamic_pressure(scene.environment.water_density, c.drag_coefficient, scene.environment.current_speed)
    summary = _catch_summary(jax.numpy.asarray(x), net.vertices, c.axis, front.position, p, c.symmetry,
                                               sign=net.outward, center=c.center, up=scene.environment.up)
    return {
        "front_m": float(front.position),
        "holds_the_volume": bool(front.holds),
        "volume_m3": float(summary.volume),
        "drag_N": float(summary.drag),
        "thickness_m": float(summary.thickness),
        "diameter_m": float(summary.diameter),
    }


def enclosed_volume(scene, x):
    """Volume (m³) the net holds behind its opening (scenes with an enclosure), or None."""
    e = scene.enclosure
    if e is None or scene.netting is None:
        return None
    front = float(np.dot(e.center, e.axis))
    return float(catch_lib.enclosed_volume(np.asarray(x), scene.netting.vertices, front, e.axis, sign=scene.netting.outward))


def summary(scene, eq, timing=None):
    """The figures of ``result.json`` (see the README for their meaning and units)."""
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
    if timing is not None:
        out["wall_s"] = float(timing.wall_s)
        out["compile_s"] = float(timing.compile_s)
    return out
