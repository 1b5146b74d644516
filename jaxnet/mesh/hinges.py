"""Hinges of a triangle mesh: the pairs of triangles that share a side (for twine bending, eqs 4.220-4.245).

Twine flexion out of the netting plane (:mod:`jaxnet.terms.bending`) acts across every side shared by two
triangles of the same panel. This module finds those sides once per scene, with numpy, before anything is
traced: every side of every triangle is keyed by its two nodes (sorted) and, when panels are given, its
panel; one sort brings equal keys together. No Python loop runs over triangles.

Conventions
-----------
- ``pairs[h] = (t1, t2)`` with t1 < t2 (triangle indices).
- ``nodes[h] = (a, b, p, q)``: a-b is the shared side, in the order it has in t1's vertex cycle, so that
  (a, b, p) is t1 with its own orientation; p is t1's third vertex, q is t2's.
- Hinges are sorted by (min(a, b), max(a, b), panel): the output is a function of the triangles alone.
- A side shared by triangles of different panels is a seam, not a hinge: the panels' twines are not
  continuous there. A side shared by more than two triangles of one panel (non-manifold) is refused.
"""

from __future__ import annotations

import numpy as np

__all__ = ["find_hinges", "hinge_rows", "netting_hinges"]

# Sides listed in the refusal message, at most.
_REPORTED = 5


def _as_index_array(name, a, ndim):
    arr = np.asarray(a)
    if arr.ndim != ndim or (ndim == 2 and arr.shape[1] != 3):
        raise ValueError(f"{name} must have shape {'(E, 3)' if ndim == 2 else '(E,)'}, got {arr.shape}")
    if arr.size and not np.issubdtype(arr.dtype, np.integer):
        if not np.all(np.equal(np.mod(arr, 1), 0)):
            raise ValueError(f"{name} must hold integers")
    return arr.astype(np.int64)


def find_hinges(triangles, panel=None):
    """Pairs of triangles sharing a side, and the four nodes of each hinge.

    Args:
      triangles: (E, 3) node indices of the triangles (any orientation).
      panel: optional (E,) panel index of each triangle; sides shared across panels give no hinge.
    Returns:
      (pairs, nodes): int64 arrays (H, 2) of triangle indices and (H, 4) of node indices
      [shared node a, shared node b, third node of triangle 1, third node of triangle 2].
    Raises:
      ValueError: bad shapes, a triangle with a repeated node, two triangles on the same three nodes, or
      a side shared by more than two triangles (of one panel), naming the side's nodes.
    """
    tri = _as_index_array("triangles", triangles, 2)
    n_tri = tri.shape[0]
    if panel is None:
        group = np.zeros(n_tri, dtype=np.int64)
    else:
        group = _as_index_array("panel", panel, 1)
        if group.shape[0] != n_tri:
            raise ValueError(f"panel has {group.shape[0]} entries for {n_tri} triangles")
    if n_tri == 0:
        return np.zeros((0, 2), np.int64), np.zeros((0, 4), np.int64)
    repeated = (tri[:, 0] == tri[:, 1]) | (tri[:, 1] == tri[:, 2]) | (tri[:, 2] == tri[:, 0])
    if repeated.any():
        t = int(np.flatnonzero(repeated)[0])
        raise ValueError(f"triangle {t} has a repeated node: {tri[t].tolist()}")

    # side k of a triangle goes from vertex k to vertex k+1 (its own cycle); its third vertex is k+2
    start = tri.ravel()
    end = tri[:, [1, 2, 0]].ravel()
    third = tri[:, [2, 0, 1]].ravel()
    owner = np.repeat(np.arange(n_tri, dtype=np.int64), 3)
    lo, hi, grp = np.minimum(start, end), np.maximum(start, end), group[owner]

    order = np.lexsort((owner, grp, hi, lo))  # last key first: by side, then panel, then triangle
    lo_s, hi_s, grp_s = lo[order], hi[order], grp[order]
    new_key = np.ones(order.size, dtype=bool)
    new_key[1:] = (lo_s[1:] != lo_s[:-1]) | (hi_s[1:] != hi_s[:-1]) | (grp_s[1:] != grp_s[:-1])
    first = np.flatnonzero(new_key)
    count = np.diff(np.append(first, order.size))

    if (count > 2).any():
        bad = first[count > 2]
        lines = []
        for f, c in zip(bad[:_REPORTED], count[count > 2][:_REPORTED]):
            owners = owner[order[f:f + c]].tolist()
            where = "" if panel is None else f" of panel {int(grp_s[f])}"
            lines.append(
                f"side (nodes {int(lo_s[f])}, {int(hi_s[f])}) is shared by {c} triangles {owners}{where}")
        more = f" (and {bad.size - _REPORTED} more)" if bad.size > _REPORTED else ""
        raise ValueError(
            "non-manifold netting: " + "; ".join(lines) + more
            + ". A side may border at most two triangles of one panel.")

    f = first[count == 2]
    i, j = order[f], order[f + 1]  # the stable sort on owner puts the lower triangle index first
    if np.any(third[i] == third[j]):
        k = int(np.flatnonzero(third[i] == third[j])[0])
        raise ValueError(
            f"triangles {int(owner[i[k]])} and {int(owner[j[k]])} have the same nodes "
            f"{sorted([int(start[i[k]]), int(end[i[k]]), int(third[i[k]])])}")
    pairs = np.stack([owner[i], owner[j]], axis=1)
    nodes = np.stack([start[i], end[i], third[i], third[j]], axis=1)
    return pairs, nodes


def hinge_rows(netting):
    """Where each bending hinge of ``netting`` (a :class:`~jaxnet.scene.Netting`) takes its data: the pairs of
    triangles of one panel sharing an edge (:func:`find_hinges`) where the twines have a flexural stiffness
    (the mean EI of the two triangles > 0). Returns (triangles, slots, nodes, ei): triangles (H, 4), the
    triangle whose twine coordinates each hinge node takes (the first triangle's for the shared edge and its
    opposite node, the second's for its own opposite node: one panel, so the edge nodes agree); slots (H, 4),
    that node's vertex slot in that triangle; nodes (H, 4), the hinge nodes [a, b, p, q]; ei (H,), the mean EI
    (N·m²)."""
    vertices = np.asarray(netting.vertices)
    pairs, nodes = find_hinges(vertices, np.asarray(netting.panel))
    bending = np.asarray(netting.bending_stiffness)
    ei = 0.5 * (bending[pairs[:, 0]] + bending[pairs[:, 1]])
    keep = ei > 0
    pairs, nodes, ei = pairs[keep], nodes[keep], ei[keep]
    triangles = np.stack([pairs[:, 0]] * 3 + [pairs[:, 1]], axis=1)
    slots = np.argmax(vertices[triangles] == nodes[:, :, None], axis=2)
    return triangles, slots, nodes, ei


def netting_hinges(netting):
    """The :class:`~jaxnet.scene.Hinges` of ``netting`` (a :class:`~jaxnet.scene.Netting`): its pairs of triangles
    of one panel sharing an edge, where the twines have a flexural stiffness EI (:func:`hinge_rows`); None
    without any."""
    if netting is None or not np.any(np.asarray(netting.bending_stiffness) > 0):
        return None
    from jaxnet.scene import Hinges

    triangles, slots, nodes, ei = hinge_rows(netting)
    first = triangles[:, 0]
    return Hinges(vertices=nodes, uv=np.asarray(netting.uv)[triangles, slots], l0=np.asarray(netting.l0)[first],
                  stiffness=ei, panel=np.asarray(netting.panel)[first])
