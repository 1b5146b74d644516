"""Joining the parts of a net: the nodes of panels and cables before they are merged, and their merging.

:meth:`jaxnet.net.Net.build` adds every panel's mesh nodes and every cable's nodes to a :class:`NodeJoiner`,
says which pairs are one node (seams: side nodes pairwise) and which nodes may merge with any other at the
same start position (panel corners and cable ends, :meth:`NodeJoiner.mergeable`), then resolves the pairs
(union-find by connected components) into the scene's node numbers, in order of first appearance so that
node numbers follow the description. Positions in m.
"""

from __future__ import annotations

import numpy as np


class NodeJoiner:
    """Nodes before merging: positions (m), merge pairs, resolution into the scene's node numbers.

    tolerance: corners and cable ends closer than this (m) at the start are one node.
    """

    def __init__(self, tolerance):
        self.tolerance = tolerance
        self.chunks = []
        self.n = 0
        self.pairs = []
        self.candidates = []

    @property
    def xyz(self):
        return np.concatenate(self.chunks) if self.chunks else np.zeros((0, 3))

    def add_nodes(self, xyz):
        """Add nodes at positions ``xyz`` (k, 3) (m); their indices (k,) before merging."""
        xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
        self.chunks.append(xyz)
        idx = np.arange(self.n, self.n + len(xyz))
        self.n += len(xyz)
        return idx

    def position(self, idx):
        return self.xyz[idx]

    def merge_pairs(self, a, b):
        """The nodes ``a`` (k,) and ``b`` (k,) are one node, pairwise (a seam)."""
        self.pairs.append(np.stack([np.asarray(a), np.asarray(b)], axis=1))

    def mergeable(self, idx):
        """Mark nodes (panel corners, cable ends) that merge with any other such node at the same point."""
        self.candidates.append(np.asarray(idx, dtype=np.int64))

    def merge_close(self):
        """Merge corners and cable ends that start at the same point. Other nodes never merge by position:
        panels drawn overlapping (the upper and lower panels of a cod-end) must stay apart."""
        from scipy.spatial import cKDTree

        if not self.candidates:
            return
        cand = np.unique(np.concatenate(self.candidates))
        pairs = cKDTree(self.xyz[cand]).query_pairs(self.tolerance, output_type="ndarray")
        if len(pairs):
            self.pairs.append(cand[pairs])

    def resolve(self):
        """(n,) the scene's node number of every node added, merged ones sharing one."""
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components

        pairs = np.concatenate(self.pairs) if self.pairs else np.zeros((0, 2), dtype=int)
        g = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(self.n, self.n))
        _, label = connected_components(g, directed=False)
        # renumber in order of first appearance so that node numbers follow the description
        _, first = np.unique(label, return_index=True)
        order = np.argsort(first)
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        return rank[label]
