"""Figures computed from an equilibrium: twine and bar tensions, reactions, loads, summary.

These are what a gear technologist reads off a solve; the writers in :mod:`jaxnet.io` only format them.
"""

from __future__ import annotations

import jax
import numpy as np

from jaxnet import assemble, model as model_lib
from jaxnet.terms import cable, tension


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
    }
    if timing is not None:
        out["wall_s"] = float(timing.wall_s)
        out["compile_s"] = float(timing.compile_s)
    return out
