"""FEMNET's results: its summary figures of an equilibrium, computed by jaxnet (:func:`femnet_figures`), and its
``.sta`` equilibrium file (:func:`read_sta`), to compare the two programs.
"""

from __future__ import annotations

import pathlib

import numpy as np


def femnet_figures(scene, eq, symmetry_axes=(), fixity=None, groups=None):
    """FEMNET's summary figures of an equilibrium (N, m, m³), computed by jaxnet.

    drag_netting_N, drag_cables_N, catch_drag_N: x components (along the current when it is along x) and
    norms of the total drag on the netting, on the cables, and of the catch; total_force_N: the force the
    net exerts on its fixings (sum of the out-of-balance force at the held coordinates = minus jaxnet's
    reaction) as FEMNET prints it: at the coordinates ``fixity`` names ([node, axis] pairs: those FEMNET's node
    types hold by "Displacement" and not by a symmetry plane, the reader's ``info["fixity"]``), or else at every held coordinate less the
    ``symmetry_axes`` (FEMNET gives no reaction at a node held by a symmetry plane);
    catch: thickness, largest diameter, volume of the modelled part (FEMNET's convention).
    groups: jaxnet's force groups at the equilibrium (:func:`jaxnet.figures.force_breakdown`, result.json's
    ``forces_N``) when already computed.
    """
    from jaxnet import figures

    groups = figures.force_breakdown(scene, eq.x) if groups is None else groups
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


def sta_positions(path, n_nodes):
    """(N, 3) the node positions (m) of FEMNET's ``.sta`` (its first N lines: number, x, y, z): its equilibrium
    on its own mesh (``.mdg``), the start of its dynamics (``dyna``)."""
    from jaxnet.scene import SceneError

    lines = pathlib.Path(path).read_text().split("\n")
    out = np.zeros((n_nodes, 3))
    for i in range(n_nodes):
        words = lines[i].split() if i < len(lines) else []
        try:
            out[i] = [float(w) for w in words[1:4]]
        except ValueError:
            out[i] = np.nan
        if len(words) < 4 or not np.isfinite(out[i]).all():
            raise SceneError(f"{path}:{i + 1}: expected node {i + 1}'s number and x y z (the mesh has {n_nodes} "
                             f"nodes), got {lines[i].strip()[:80] if i < len(lines) else 'the end of the file'!r}")
    return out


def started_from_sta(case, path):
    """``case`` (read on FEMNET's mesh, ``read_mdg``) with every node at its position in FEMNET's ``.sta`` at
    ``path``, the held nodes too: the shape FEMNET's ``dyna`` starts from (the case's own .sta), or the one its
    ``phobos`` starts a case from (an earlier case's). A net held only at jaxnet's gauge (:func:`.mapping.gauge_of`)
    is then held where FEMNET's equilibrium has it. SceneError naming the file and line for a .sta too short for
    the mesh."""
    import dataclasses

    import equinox as eqx

    position = sta_positions(path, case.scene.n_nodes)
    return dataclasses.replace(case, scene=eqx.tree_at(lambda s: s.nodes.position, case.scene, position))


def read_sta(path, n_nodes, n_bars, n_triangles):
    """FEMNET's ``.sta``: (positions (N, 3) m, bar strains (B,), twine vectors (E, 2, 3) m as written (v then u),
    summary dict of the labelled lines)."""
    lines = pathlib.Path(path).read_text().split("\n")
    pos = sta_positions(path, n_nodes)
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


#: the unit of each kind of FEMNET text output
TEXT_OUTPUT_UNITS = {"distances": "m", "forces": "N", "tensions": "N", "sliding_tensions": "N", "positions": "m"}


def global_node(case, k) -> int:
    """The scene node of FEMNET's global node ``k`` (1-based, as its text outputs and its ``.sta`` name nodes: the
    joined points) of a case read by :func:`~.mapping.read_don`: e.g. the door of a ``Position`` output
    "half doors distance ... no global: 56". Raises ValueError naming k and the range."""
    nodes = case.info.get("global_nodes", [])
    if isinstance(k, bool) or int(k) != k or not 1 <= k <= len(nodes):
        raise ValueError(f"global node {k!r}: the case has global nodes 1 to {len(nodes)}")
    return int(nodes[int(k) - 1])


def is_heading(kind, values) -> bool:
    """Whether a text output of FEMNET (its ``kind`` and ``values``, :class:`~.grammar.TextOutput`'s) is a heading:
    a distance from a node to itself ("Distance: 1 comment: #PELAGIC TRAWL# no global 1: 1 no global 2: 1"), which
    is 0 m whatever the net does. FEMNET's cases use it to print their comment as a title above the figures that
    follow (the manual: "is zero m because the two nodes are the same")."""
    return kind == "distances" and values.get("node_1") is not None and values["node_1"] == values.get("node_2")


def text_output_figures(scene, eq, info):
    """FEMNET's text outputs of a case (its ``Distances``, ``Forces``, ``Tensions``, ``Positions`` lists: the
    figures it prints after its solve, with their comments), computed by jaxnet at the equilibrium ``eq``:
    [{"kind", "comment", "value", "unit"}] in the file's order, ``value`` None where jaxnet cannot compute it
    (a sliding cable). FEMNET names nodes by its global numbers (the joined points: ``info["global_nodes"]``):

    * distance between global nodes a and b (m);
    * force along an axis (1-3) on a global node (N): the out-of-balance force there, which at a held
      coordinate is what the net exerts on its fixing (FEMNET's sum of the forces on the node);
    * tension of cable k at its end at global node a (N): that of the cable's bar at that node;
    * position of a global node along an axis (m).

    A distance from a node to itself is a heading (:func:`is_heading`), not a measurement:
    ``{"kind": "heading", "comment": "PELAGIC TRAWL", "value": None, "unit": None}``, to be shown as a title.
    """
    from jaxnet import figures

    x = np.asarray(eq.x)
    force = np.asarray(eq.force)
    nodes = info.get("global_nodes", [])
    tensions = figures.bar_tensions(scene, x) if scene.bars is not None else np.zeros(0)
    out = []
    for t in info.get("text_outputs", []):
        kind, v = t["kind"], t["values"]

        def node(k):
            return nodes[k - 1] if 1 <= k <= len(nodes) else None

        if is_heading(kind, v):
            out.append({"kind": "heading", "comment": t["comment"], "value": None, "unit": None})
            continue
        value = None
        if kind == "distances" and node(v["node_1"]) is not None and node(v["node_2"]) is not None:
            value = float(np.linalg.norm(x[node(v["node_1"])] - x[node(v["node_2"])]))
        elif kind in ("forces", "positions") and node(v["node"]) is not None and 1 <= v["axis"] <= 3:
            value = float((force if kind == "forces" else x)[node(v["node"]), v["axis"] - 1])
        elif kind == "tensions" and node(v["node"]) is not None and scene.bars is not None:
            ends, cable = np.asarray(scene.bars.ends), np.asarray(scene.bars.cable)
            at = np.flatnonzero((cable == v["cable"] - 1) & np.any(ends == node(v["node"]), axis=1))
            value = float(tensions[at[0]]) if at.size else None
        out.append({"kind": kind, "comment": t["comment"], "value": value, "unit": TEXT_OUTPUT_UNITS[kind]})
    return out


def read_sta_summary(path):
    """The labelled lines of FEMNET's ``.sta`` (its summary and the figures of its text outputs, labelled by their
    comments), without its mesh's sizes: {label (blanks collapsed): [numbers]}."""
    summary = {}
    for ln in pathlib.Path(path).read_text(errors="replace").split("\n"):
        if ":" not in ln:
            continue
        key, value = ln.rsplit(":", 1)
        try:
            summary[" ".join(key.split())] = [float(w) for w in value.split()]
        except ValueError:
            continue
    return summary


def printed_figure(summary, comment):
    """The figure FEMNET printed in its ``.sta`` for the text output whose comment is ``comment`` (``summary``:
    :func:`read_sta_summary`'s labelled lines, whose labels are the comments), or None when it has none."""
    key = " ".join(comment.split())
    for label, values in summary.items():
        if " ".join(label.split()) == key and values:
            return values[0]
    return None
