"""FEMNET's results: its summary figures of an equilibrium, computed by jaxnet (:func:`femnet_figures`), and its
``.sta`` equilibrium file (:func:`read_sta`), to compare the two programs.
"""

from __future__ import annotations

import pathlib

import numpy as np


def femnet_figures(scene, eq, symmetry_axes=(), fixity=None):
    """FEMNET's summary figures of an equilibrium (N, m, m³), computed by jaxnet.

    drag_netting_N, drag_cables_N, catch_drag_N: x components (along the current when it is along x) and
    norms of the total drag on the netting, on the cables, and of the catch; total_force_N: the force the
    net exerts on its fixings (sum of the out-of-balance force at the held coordinates = minus jaxnet's
    reaction) as FEMNET prints it: at the coordinates ``fixity`` names ([node, axis] pairs: those FEMNET's node
    types hold by "Displacement", the reader's ``info["fixity"]``), or else at every held coordinate less the
    ``symmetry_axes`` (FEMNET gives no reaction at a node held by a symmetry plane);
    catch: thickness, largest diameter, volume of the modelled part (FEMNET's convention).
    """
    from jaxnet import figures

    groups = figures.force_breakdown(scene, eq.x)
    if fixity is not None:
        # FEMNET's sum: the reactions at the coordinates its node types hold by "Displacement" only
        held = np.zeros(np.asarray(scene.nodes.fixed).shape, bool)
        for i, j in fixity:
            held[i, j] = True
    else:
        held = np.asarray(scene.nodes.fixed).copy()
        for a in symmetry_axes:
            held[:, "xyz".index(a)] = False
    total = np.where(held, np.asarray(eq.force), 0.0).sum(axis=0)
    out = {
        "drag_netting_N": np.asarray(groups["drag_netting_N"]).tolist(),
        "drag_cables_N": np.asarray(groups["drag_cables_N"]).tolist(),
        "catch_drag_N": np.asarray(groups["catch_N"]).tolist(),
        "total_force_N": total.tolist(),
    }
    report = figures.catch_report(scene, eq.x)
    if report is not None:
        copies = float(scene.catch.symmetry)
        out["catch"] = {"front_m": report["front_m"], "thickness_m": report["thickness_m"],
                        "diameter_m": report["diameter_m"], "volume_modelled_m3": report["volume_m3"] / copies,
                        "drag_N": report["drag_N"], "holds_the_volume": report["holds_the_volume"]}
    return out


def read_sta(path, n_nodes, n_bars, n_triangles):
    """FEMNET's ``.sta``: (positions (N, 3) m, bar strains (B,), twine vectors (E, 2, 3) m as written (v then u),
    summary dict of the labelled lines)."""
    lines = pathlib.Path(path).read_text().split("\n")
    pos = np.array([[float(w) for w in lines[i].split()[1:4]] for i in range(n_nodes)])
    strain = np.array([float(lines[n_nodes + i]) for i in range(n_bars)])
    rest = [ln for ln in lines[n_nodes + n_bars:] if ln.strip()]
    vec = np.array([[float(w) for w in rest[i].split()] for i in range(n_triangles)]).reshape(-1, 2, 3)
    summary = {}
    for ln in rest[n_triangles:]:
        if ":" in ln:
            key, value = ln.split(":", 1)
            summary[" ".join(key.split())] = [float(w) for w in value.split()]
        else:
            summary["front"] = [float(w) for w in ln.split()]
    return pos, strain, vec, summary
