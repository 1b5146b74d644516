"""Triangle meshing of netting panels in twine-coordinate space.

A netting panel (diamond mesh) is a simple polygon given by its corners.  Each
corner has twine coordinates ``(U, V)`` -- the material coordinates of the
netting, counted in twines along the two twine directions -- and a Cartesian
start position ``(x, y, z)`` in metres.  The panel is meshed in ``(U, V)``
space, where it is a fixed polygon; ``U`` and ``V`` are treated as orthonormal
there and one twine is ``l0`` metres long, so a meshing step ``step`` (m) is
``h = step / l0`` twines.

Node ordering of a :class:`PanelMesh`: the ``C`` corner nodes come first (node
``k`` is corner ``k``), then the nodes strictly inside each side, side 0 first
(in the direction corner 0 -> corner 1), then side 1, ..., then the interior
nodes (row by row of the lattice).  Start positions of all nodes are
``weights @ corners_xyz``: linear along the sides, mean value coordinates
(Floater) inside, so an affine map of the corners is reproduced exactly.

The polygon is checked first (:mod:`jaxnet.mesh.polygon`: a :class:`~jaxnet.mesh.polygon.PanelError` names
the panel and the culprit). This module depends on numpy and scipy only.

**Meshing on a lattice of mesh diagonals** (``mesh_panel(..., lattice=(NU, NV))``, FEMNET's ``input
Meshing_UV PANEL NU NV``). FEMNET's mesh coordinates count meshes along the two diagonals of the meshes,
U = (u - v)/2 and V = (u + v)/2 for the twine coordinates (u, v) used here. With a lattice, the interior nodes
are the points U = U0 + i NU, V = V0 + j NV (i, j integers; U0, V0 the floors of the corners' smallest U and V)
strictly inside the panel, and the triangles are made in the *lattice coordinates* s = (U / NU, V / NV), where
the lattice is the unit square grid: a panel long along U (a gill net: 5000 meshes by 42, NU = 200, NV = 3)
gets the few nodes its shape needs across its length and enough across its height, with triangles long and
thin in twine space (200 meshes by 3), which the element takes as any other (its twine vectors come from the
triangle's (u, v), its twine counts are |d|/2). Every step of the isotropic mesher is done in s instead of
(u, v) with h = 1 cell: default side divisions ceil(side length in cells), lattice points kept at 0.6 cells
from the sides, Delaunay triangulation with the sides recovered. A square of four lattice nodes is cocircular
(Delaunay could split it either way, at rounding's whim), so the triangulation is made in the sheared
coordinates (s1 + s2 / 4, s2) (an affine map of determinant 1, which keeps orientation and areas): each
cell's parallelogram has one shorter diagonal, the one from (i + 1, j) to (i, j + 1), and every cell is split
along it. FEMNET's way (phobos ``maillage.c``, ``maillage_panneau``: for meshing type 2 with a step along U
set, ``maillage_interne4`` of ``maillage_panneau2.c`` replaces the isotropic ``maillage_interne3``): the
same lattice from i, j = 1 to int((U_max - U_min) / NU) and int((V_max - V_min) / NV) (so a band along the
largest U or V can be missed when U_min is not a whole number; here the whole panel is covered), each point
kept when it is inside the contour and farther than a quarter of the *isotropic* step (step / l0 twines) from
every contour segment and corner (``proche_contour_filaire``, ``proche_panneau_filaire`` of
``maillage_panneau1.c``; 0.6 lattice cells here), the sides divided as without the command (by the meshing step,
or by the cable sewn along it when the cable is meshed first, FEMNET's advice for this command), then all the
nodes triangulated in twine coordinates (Shewchuk's ``triangle.c``), where a rectangle of the lattice is a
rectangle too, cocircular.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from jaxnet.mesh.polygon import (REL_EPS, distance_to_boundary, inside, mean_value_coordinates, panel_error,
                                 validate_panel)

__all__ = ["PanelMesh", "lattice_coordinates", "lattice_divisions", "mesh_panel"]

#: Refuse to mesh a panel whose estimated node count exceeds this.
MAX_NODES = 5_000_000

# Lattice points closer than this fraction of h to the boundary are dropped.
_CLEARANCE = 0.6
# Shear of the lattice coordinates in which a lattice mesh is triangulated (see the module docstring).
_LATTICE_SHEAR = 0.25


@dataclasses.dataclass(frozen=True)
class PanelMesh:
    """Triangle mesh of one netting panel.

    Attributes
    ----------
    uv : np.ndarray, shape (n, 2), float64
        Twine coordinates ``(U, V)`` of the nodes (twines).  Exactly
        ``weights @ corners_uv``.
    xyz : np.ndarray, shape (n, 3), float64
        Cartesian start positions of the nodes (m).  Exactly
        ``weights @ corners_xyz``.
    triangles : np.ndarray, shape (t, 3), int64
        Local node indices of each triangle.  Every triangle has the
        orientation of the polygon in ``(U, V)``: with
        ``d = (U2-U1)(V3-V1) - (U3-U1)(V2-V1)``, ``d > 0`` for all triangles
        of a counter-clockwise panel, ``d < 0`` for all triangles of a
        clockwise one.
    corner_nodes : np.ndarray, shape (C,), int64
        Local index of each corner node, in corner order (always
        ``arange(C)``: corners are the first ``C`` nodes).
    side_nodes : tuple of C np.ndarray (int64)
        ``side_nodes[k]`` lists, in order, the local indices of the nodes on
        side ``k`` (from corner ``k`` to corner ``(k + 1) % C``), both corner
        nodes included; ``len(side_nodes[k]) == divisions[k] + 1``.
    weights : np.ndarray, shape (n, C), float64
        Interpolation weights of the nodes with respect to the corners
        (dimensionless); rows sum to 1.  Corner rows are unit rows, side
        nodes interpolate linearly between the two corners of their side,
        interior nodes carry mean value coordinates (which may be negative
        for a non-convex panel).
    """

    uv: np.ndarray
    xyz: np.ndarray
    triangles: np.ndarray
    corner_nodes: np.ndarray
    side_nodes: tuple
    weights: np.ndarray


# --------------------------------------------------------------------------
# geometry kernels (vectorised)
# --------------------------------------------------------------------------

def _signed_d(uv, tri):
    a, b, c = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])


def _triangle_angles(uv, tri):
    """Interior angles (degrees) of each triangle in twine space, shape (t, 3)."""
    p = uv[tri]                                         # (t, 3, 2)
    ang = np.empty(tri.shape)
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        cr = np.abs(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0])
        ang[:, k] = np.degrees(np.arctan2(cr, (u * v).sum(axis=1)))
    return ang


# --------------------------------------------------------------------------
# meshing
# --------------------------------------------------------------------------

def _boundary(uv, div):
    """Corner + side nodes: weights (nb, C), side node lists, segments (ns, 2)."""
    C = len(uv)
    rows = [np.eye(C)]
    sides = []
    nxt = C
    for k in range(C):
        n = int(div[k])
        t = np.arange(1, n) / n
        w = np.zeros((n - 1, C))
        w[:, k] = 1.0 - t
        w[:, (k + 1) % C] = t
        rows.append(w)
        idx = np.concatenate(([k], np.arange(nxt, nxt + n - 1), [(k + 1) % C])).astype(np.int64)
        sides.append(idx)
        nxt += n - 1
    weights = np.concatenate(rows, axis=0)
    segs = np.concatenate([np.stack([s[:-1], s[1:]], axis=1) for s in sides], axis=0)
    return weights, tuple(sides), segs


def _lattice(uv, area, h, seg, div):
    """Equilateral lattice points of spacing ~h covering the polygon's bounding box.

    The lattice is aligned with the longest side (rows parallel to it, the
    row spacing adjusted so that a parallel opposite side falls on a row).
    """
    C = len(uv)
    k = int(np.argmax(seg))
    L = float(seg[k])
    e1 = (uv[(k + 1) % C] - uv[k]) / L
    e2 = np.array([-e1[1], e1[0]]) * (1.0 if area > 0 else -1.0)   # into the polygon
    rel = uv - uv[k]
    lx, ly = rel @ e1, rel @ e2
    hx = L / int(div[k])
    if not (0.8 * h <= hx <= 1.25 * h):
        hx = h
    hy = hx * math.sqrt(3.0) / 2.0
    ext = float(ly.max())
    m = round(ext / hy)
    if m >= 2 and 0.8 <= (ext / m) / hy <= 1.25:
        hy = ext / m
    j0, j1 = math.floor(ly.min() / hy), math.ceil(ly.max() / hy)
    i0, i1 = math.floor(lx.min() / hx) - 1, math.ceil(lx.max() / hx) + 1
    jj = np.arange(j0, j1 + 1)
    ii = np.arange(i0, i1 + 1)
    J, I = np.meshgrid(jj, ii, indexing="ij")
    X = (I + 0.5 * (J % 2)) * hx
    Y = J * hy
    pts = uv[k] + X.reshape(-1, 1) * e1 + Y.reshape(-1, 1) * e2
    # cheap pre-filter on the local bounding box
    xl, yl = X.reshape(-1), Y.reshape(-1)
    keep = (xl > lx.min()) & (xl < lx.max()) & (yl > ly.min()) & (yl < ly.max())
    return pts[keep]


def _interior_points(uv, area, h, seg, div, convex, bpts, segs, pts=None):
    """The interior nodes: the candidate points ``pts`` (default: the equilateral lattice of spacing ~h)
    strictly inside the polygon, at least _CLEARANCE h from its boundary (and, for a non-convex polygon, off
    the diametral circles of the boundary segments)."""
    if pts is None:
        pts = _lattice(uv, area, h, seg, div)
    if len(pts) == 0:
        return pts
    pts = pts[inside(pts, uv)]
    if len(pts) == 0:
        return pts
    pts = pts[distance_to_boundary(pts, uv) >= _CLEARANCE * h]
    if not convex and len(pts):
        # keep every boundary segment Gabriel with respect to the interior points
        a, b = bpts[segs[:, 0]], bpts[segs[:, 1]]
        half = 0.5 * np.hypot(*(b - a).T)
        long = np.nonzero(half > _CLEARANCE * h * (1.0 - 1e-9))[0]
        if long.size:
            # imported here: scipy.spatial is slow to import, and a net read on FEMNET's mesh never needs it
            from scipy.spatial import cKDTree

            tree = cKDTree(pts)
            mid = 0.5 * (a[long] + b[long])
            drop = tree.query_ball_point(mid, half[long] * (1.0 + 1e-9))
            bad = np.unique(np.concatenate([np.asarray(x, dtype=np.int64) for x in drop]))
            pts = np.delete(pts, bad, axis=0)
    return pts


def _edge_keys(a, b, n):
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    return lo.astype(np.int64) * n + hi


def _is_convex(uv, area, scale):
    """Whether the polygon ``uv`` (C, 2) of signed ``area`` turns the same way at every corner, to a tolerance
    relative to its size ``scale`` (collinear corners count as convex)."""
    e = np.roll(uv, -1, axis=0) - uv
    turn = e[:, 0] * np.roll(e[:, 1], -1) - e[:, 1] * np.roll(e[:, 0], -1)
    return bool(np.all(turn * np.sign(area) >= -REL_EPS * scale * scale))


def _outline(corners, area, scale, div):
    """The outline of a polygon (C, 2) of signed ``area`` divided into ``div`` segments a side: whether it is
    convex, its boundary nodes' weights on the corners, the sides' node lists, the boundary segments, and the
    boundary nodes (the first steps of both meshers)."""
    convex = _is_convex(corners, area, scale)
    w_b, sides, segs = _boundary(corners, div)
    return convex, w_b, sides, segs, w_b @ corners


def mesh_panel(corners_uv, corners_xyz, step, l0, divisions=None, name="panel", lattice=None) -> PanelMesh:
    """Mesh a netting panel into triangles in twine-coordinate space.

    Parameters
    ----------
    corners_uv : array_like, shape (C, 2)
        Twine coordinates ``(U, V)`` of the corners (twines), ``C >= 3``, in
        order along the boundary of a simple polygon (either orientation).
    corners_xyz : array_like, shape (C, 3)
        Cartesian start positions of the corners (m).
    step : float
        Target triangle size (m); the size in twine space is
        ``h = step / l0`` twines.
    l0 : float
        Unstretched twine length (m per twine).
    divisions : array_like of int, shape (C,), optional
        Number of equal segments on each side ``k`` (from corner ``k`` to
        corner ``(k + 1) % C``); default :func:`side_divisions`.  Side nodes
        are equally spaced in ``(U, V)``: node ``i`` of side ``k`` sits at
        fraction ``i / divisions[k]``.  Two panels given the same divisions
        on a seam get matching border nodes.  With a ``lattice``, the default
        is :func:`lattice_divisions`.
    name : str
        Panel name used in error messages.
    lattice : (float, float), optional
        ``(NU, NV)``: put the interior nodes on the lattice of every ``NU``
        meshes along the U diagonal and every ``NV`` meshes along the V
        diagonal (FEMNET's ``input Meshing_UV``; see the module docstring)
        instead of the isotropic lattice of step ``h``; ``step`` and ``l0``
        are then unused.

    Returns
    -------
    PanelMesh
        Nodes ordered as: corners (node ``k`` is corner ``k``), then side
        nodes side by side (excluding corners), then interior nodes.

    Raises
    ------
    PanelError
        On invalid input (fewer than 3 corners, non-finite coordinates,
        repeated consecutive corners, zero-area or self-intersecting polygon,
        non-positive ``step`` or ``l0``, bad ``divisions``), or if the panel
        could not be meshed.
    """
    if lattice is not None:
        return _mesh_on_lattice(corners_uv, corners_xyz, lattice, divisions, name)
    uv_c, xyz_c, h, seg, area, scale, div = validate_panel(corners_uv, corners_xyz, step, l0, divisions, name)
    C = len(uv_c)
    if xyz_c is None:
        raise panel_error(name, "corners_xyz is required")

    perim = float(seg.sum())
    estimate = abs(area) / (h * h * math.sqrt(3.0) / 2.0) + float(div.sum()) + perim / h
    if estimate > MAX_NODES:
        raise panel_error(name, f"step={step} m with l0={l0} m gives h={h:g} twines and about "
                         f"{estimate:.3g} nodes (limit {MAX_NODES}); use a larger step")

    convex, w_b, sides, segs, b_pts = _outline(uv_c, area, scale, div)
    i_pts = _interior_points(uv_c, area, h, seg, div, convex, b_pts, segs)
    w_i = mean_value_coordinates(i_pts, uv_c) if len(i_pts) else np.zeros((0, C))
    weights = np.concatenate([w_b, w_i], axis=0)
    nodes = weights @ uv_c
    tri = _triangulate(nodes, uv_c, area, segs, scale, name)
    return _panel_mesh(weights, uv_c, xyz_c, tri, sides)


def _panel_mesh(weights, uv_c, xyz_c, triangles, sides) -> PanelMesh:
    """The :class:`PanelMesh` of nodes given by their ``weights`` (N, C) over the C corners: twine coordinates
    and start positions interpolated from the corners', every array read-only."""
    arrays = dict(uv=weights @ uv_c, xyz=weights @ xyz_c, triangles=triangles,
                  corner_nodes=np.arange(len(uv_c), dtype=np.int64), weights=weights)
    for a in [*arrays.values(), *sides]:
        a.setflags(write=False)
    return PanelMesh(side_nodes=sides, **arrays)


def _checked_lattice(lattice, name):
    """(NU, NV) as two finite floats > 0 (meshes), or a PanelError."""
    try:
        nu, nv = (float(x) for x in lattice)
    except (TypeError, ValueError):
        raise panel_error(name, f"lattice must be (NU, NV), two numbers of meshes, got {lattice!r}") from None
    if not (math.isfinite(nu) and math.isfinite(nv) and nu > 0 and nv > 0):
        raise panel_error(name, f"lattice (NU, NV) must be two finite numbers of meshes > 0, got {lattice!r}")
    return nu, nv


def lattice_coordinates(uv, lattice) -> np.ndarray:
    """Lattice coordinates s = (U / NU, V / NV) of points of twine coordinates ``uv`` (..., 2) (twines), with
    U = (u - v) / 2 and V = (u + v) / 2 their mesh coordinates (meshes along the two diagonals of the meshes:
    FEMNET's, the inverse of u = U + V, v = V - U) and ``lattice`` = (NU, NV) (meshes). One unit of s is one
    cell of the lattice; the map is linear, of determinant 1 / (2 NU NV) > 0 (it keeps orientation)."""
    uv = np.asarray(uv, dtype=float)
    nu, nv = _checked_lattice(lattice, "lattice_coordinates")
    return np.stack([(uv[..., 0] - uv[..., 1]) / (2.0 * nu), (uv[..., 0] + uv[..., 1]) / (2.0 * nv)], axis=-1)


def lattice_divisions(corners_uv, lattice) -> np.ndarray:
    """Default number of segments of each side of a panel meshed on a ``lattice`` (NU, NV) (meshes):
    ceil(side length in lattice cells) (at least 1), the length measured in the lattice coordinates of
    :func:`lattice_coordinates` (a side along U of 5000 meshes with NU = 200: 25 segments)."""
    uv = validate_panel(corners_uv, None, 1.0, 1.0, None, "lattice_divisions")[0]
    s = lattice_coordinates(uv, lattice)
    seg = np.hypot(*(np.roll(s, -1, axis=0) - s).T)
    return np.maximum(np.ceil(seg * (1.0 - 1e-12)), 1).astype(np.int64)


def _mesh_on_lattice(corners_uv, corners_xyz, lattice, divisions, name) -> PanelMesh:
    """:func:`mesh_panel` with a lattice (NU, NV): the isotropic mesher's steps in the lattice coordinates
    s (h = 1 cell), the interior candidates the lattice's nodes, the triangulation sheared (module
    docstring)."""
    nu, nv = _checked_lattice(lattice, name)
    # the polygon's checks in twine coordinates (its messages then give the caller's numbers)
    uv_c, xyz_c = validate_panel(corners_uv, corners_xyz, 1.0, 1.0, None, name)[:2]
    if xyz_c is None:
        raise panel_error(name, "corners_xyz is required")
    C = len(uv_c)
    s_c = lattice_coordinates(uv_c, (nu, nv))
    _, _, h, seg, area, scale, div = validate_panel(s_c, None, 1.0, 1.0, divisions, name)
    estimate = abs(area) + float(div.sum()) + float(seg.sum())
    if estimate > MAX_NODES:
        raise panel_error(name, f"lattice of {nu:g} x {nv:g} meshes gives about {estimate:.3g} nodes (limit "
                          f"{MAX_NODES}); use a coarser lattice")

    convex, w_b, sides, segs, b_pts = _outline(s_c, area, scale, div)
    # the lattice's nodes over the panel's bounding box, row by row (V, then U), from FEMNET's origin: the
    # floors of the smallest mesh coordinates U, V of the corners
    mesh_uv = s_c * np.array([nu, nv])
    origin = np.floor(mesh_uv.min(axis=0)) / np.array([nu, nv])
    extent = np.ceil(s_c.max(axis=0) - origin).astype(np.int64)
    J, I = np.meshgrid(np.arange(extent[1] + 1), np.arange(extent[0] + 1), indexing="ij")
    candidates = origin + np.stack([I.reshape(-1), J.reshape(-1)], axis=1).astype(float)
    i_pts = _interior_points(s_c, area, h, seg, div, convex, b_pts, segs, pts=candidates)
    w_i = mean_value_coordinates(i_pts, s_c) if len(i_pts) else np.zeros((0, C))
    weights = np.concatenate([w_b, w_i], axis=0)

    shear = np.array([[1.0, _LATTICE_SHEAR], [0.0, 1.0]])
    t_c = s_c @ shear.T
    t_scale = float(np.max(np.abs(t_c - t_c.mean(axis=0)))) or 1.0
    tri = _triangulate((weights @ s_c) @ shear.T, t_c, area, segs, t_scale, name)
    return _panel_mesh(weights, uv_c, xyz_c, tri, sides)


def _orient(p, a, b, c):
    """Twice the signed area of the triangle of node indices a, b, c."""
    return ((p[b, 0] - p[a, 0]) * (p[c, 1] - p[a, 1])
            - (p[b, 1] - p[a, 1]) * (p[c, 0] - p[a, 0]))


def _crosses(p, a, b, u, v):
    """Does segment (u, v) cross segment (a, b) at a point interior to both?"""
    if u in (a, b) or v in (a, b):
        return False
    o1, o2 = _orient(p, a, b, u), _orient(p, a, b, v)
    o3, o4 = _orient(p, u, v, a), _orient(p, u, v, b)
    return (o1 * o2 < 0.0) and (o3 * o4 < 0.0)


def _in_circle(p, a, b, c, d):
    """True if node d lies strictly inside the circumcircle of CCW triangle (a, b, c)."""
    rows = p[[a, b, c]] - p[d]
    m = np.column_stack([rows, (rows * rows).sum(axis=1)])
    det = float(np.linalg.det(m))
    size = float((rows * rows).sum(axis=1).max())
    return det > 1e-10 * size * size


class _LocalMesh:
    """Edge-flip bookkeeping on a subset of the (counter-clockwise) triangles."""

    def __init__(self, tri, ids):
        self.tri = tri
        self.edges = {}
        for t in ids:
            self._add(int(t))

    @staticmethod
    def _key(u, v):
        return (u, v) if u < v else (v, u)

    def _add(self, t):
        a, b, c = (int(x) for x in self.tri[t])
        for u, v in ((a, b), (b, c), (c, a)):
            self.edges.setdefault(self._key(u, v), []).append(t)

    def _remove(self, t):
        a, b, c = (int(x) for x in self.tri[t])
        for u, v in ((a, b), (b, c), (c, a)):
            lst = self.edges[self._key(u, v)]
            lst.remove(t)
            if not lst:
                del self.edges[self._key(u, v)]

    def quad(self, u, v):
        """For interior edge (u, v) return (t1, t2, p, q, r, s): t1 = (p, q, r), t2 = (q, p, s)."""
        ts = self.edges.get(self._key(u, v), [])
        if len(ts) != 2:
            return None
        t1, t2 = ts
        a, b, c = (int(x) for x in self.tri[t1])
        # rotate t1 so that it reads (p, q, r) with {p, q} == {u, v}
        for p, q, r in ((a, b, c), (b, c, a), (c, a, b)):
            if {p, q} == {u, v}:
                break
        s = next(int(x) for x in self.tri[t2] if int(x) not in (p, q))
        return t1, t2, p, q, r, s

    def flip(self, t1, t2, p, q, r, s):
        self._remove(t1)
        self._remove(t2)
        self.tri[t1] = (p, s, r)
        self.tri[t2] = (s, q, r)
        self._add(t1)
        self._add(t2)


def _recover_segments(nodes, tri, missing, constraint, name):
    """Insert the missing boundary segments into a CCW triangulation by edge flips.

    Sloan's algorithm (flip crossing edges whose quadrilateral is convex until
    none cross), followed by a local Lawson pass restoring the constrained
    Delaunay property of the new edges.  ``tri`` is modified in place.
    """
    n = len(nodes)
    e_all = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]], axis=0)
    t_all = np.tile(np.arange(len(tri)), 3)
    touched = set()
    for a, b in missing:
        # triangles with an edge crossing (a, b), found vectorised
        pa, pb = nodes[a], nodes[b]
        pu, pv = nodes[e_all[:, 0]], nodes[e_all[:, 1]]

        def orient(x, y, z):
            return (y[..., 0] - x[..., 0]) * (z[..., 1] - x[..., 1]) - (y[..., 1] - x[..., 1]) * (z[..., 0] - x[..., 0])

        cr = ((orient(pa, pb, pu) * orient(pa, pb, pv) < 0)
              & (orient(pu, pv, pa) * orient(pu, pv, pb) < 0))
        ids = np.unique(t_all[cr])
        lm = _LocalMesh(tri, ids)
        queue = [k for k in lm.edges if len(lm.edges[k]) == 2 and _crosses(nodes, a, b, *k)]
        budget = 50 * (len(queue) + 10) ** 2
        while queue:
            budget -= 1
            if budget < 0:
                raise panel_error(name, f"could not recover boundary segment between nodes {a} and {b} "
                                 f"(edge flipping did not converge)")
            u, v = queue.pop(0)
            qd = lm.quad(u, v)
            if qd is None:
                continue
            t1, t2, p, q, r, s = qd
            # the quadrilateral p, s, q, r is strictly convex iff p and q are on
            # opposite sides of r-s (r and s are on opposite sides of p-q already)
            if _orient(nodes, r, s, p) * _orient(nodes, r, s, q) < 0.0:
                lm.flip(t1, t2, p, q, r, s)
                touched.update((t1, t2))
                if _crosses(nodes, a, b, r, s):
                    queue.append((min(r, s), max(r, s)))
            else:
                queue.append((u, v))
        # refresh the edge lists for the next segment
        e_all = np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]], axis=0)

    # local Lawson pass: make the flipped region constrained-Delaunay again
    if touched:
        lm = _LocalMesh(tri, sorted(touched))
        stack = sorted(k for k in lm.edges if len(lm.edges[k]) == 2)
        budget = 100 * (len(stack) + 10) ** 2
        while stack and budget > 0:
            budget -= 1
            u, v = stack.pop()
            if u * n + v in constraint:
                continue
            qd = lm.quad(u, v)
            if qd is None:
                continue
            t1, t2, p, q, r, s = qd
            if _in_circle(nodes, p, q, r, s) and _orient(nodes, r, s, p) * _orient(nodes, r, s, q) < 0.0:
                lm.flip(t1, t2, p, q, r, s)
                for x, y in ((p, s), (s, q), (q, r), (r, p)):
                    stack.append((min(x, y), max(x, y)))
    return tri


def _triangulate(nodes, uv_c, area, segs, scale, name):
    n = len(nodes)
    # Delaunay is translation/scale invariant; centre and normalise for robustness
    centre = uv_c.mean(axis=0)
    try:
        from scipy.spatial import Delaunay  # imported here, as cKDTree above

        dl = Delaunay((nodes - centre) / scale)
    except Exception as exc:  # qhull failure
        raise panel_error(name, f"Delaunay triangulation failed ({exc})") from exc
    tri = np.array(dl.simplices, dtype=np.int64)
    d = _signed_d(nodes, tri)
    good = np.abs(d) > 1e-13 * scale * scale
    tri, d = tri[good], d[good]
    tri[d < 0] = tri[d < 0][:, [0, 2, 1]]              # all counter-clockwise

    sk = np.unique(_edge_keys(segs[:, 0], segs[:, 1], n))
    ek = np.unique(np.concatenate([_edge_keys(tri[:, a], tri[:, b], n)
                                   for a, b in ((0, 1), (1, 2), (2, 0))]))
    missing = sk[~np.isin(sk, ek)]
    if missing.size:
        pairs = [(int(k // n), int(k % n)) for k in missing]
        tri = _recover_segments(nodes, tri, pairs, set(sk.tolist()), name)

    d = _signed_d(nodes, tri)
    cen = nodes[tri].mean(axis=1)
    kept = inside(cen, uv_c)
    tri, d = tri[kept], d[kept]

    # orientation: same sign as the polygon
    if area < 0:
        tri = tri[:, [0, 2, 1]]
        d = -d

    # every boundary segment is an edge of exactly one triangle, and no other
    # edge is used by only one triangle
    ek = np.concatenate([_edge_keys(tri[:, a], tri[:, b], n) for a, b in ((0, 1), (1, 2), (2, 0))])
    uk, cnt = np.unique(ek, return_counts=True)
    sk = np.unique(_edge_keys(segs[:, 0], segs[:, 1], n))
    pos = np.searchsorted(uk, sk)
    pos = np.minimum(pos, len(uk) - 1)
    present = (uk[pos] == sk) & (cnt[pos] == 1)
    if not present.all():
        miss = sk[~present][0]
        a, b = int(miss // n), int(miss % n)
        raise panel_error(name, f"boundary segment between nodes {a} at UV ({nodes[a, 0]:.6g}, "
                         f"{nodes[a, 1]:.6g}) and {b} at UV ({nodes[b, 0]:.6g}, {nodes[b, 1]:.6g}) "
                         f"is missing from the triangulation")
    once = uk[cnt == 1]
    if len(once) != len(sk) or np.any(cnt > 2):
        raise panel_error(name, "triangulation is not a manifold covering of the polygon")
    if np.any(d * np.sign(area) <= 0.0):
        raise panel_error(name, "triangulation produced an inverted or degenerate triangle")
    tot = 0.5 * float(np.abs(d).sum())
    if abs(tot - abs(area)) > 1e-9 * abs(area):
        raise panel_error(name, f"triangles cover area {tot!r} but the polygon has area {abs(area)!r} (twines^2)")
    if len(np.unique(tri)) != n:
        raise panel_error(name, "some nodes are not used by any triangle")
    return tri
