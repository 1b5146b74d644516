"""Tests of jaxnet.mesh.panel: meshing of netting panels in twine space."""

import math

import numpy as np
import pytest

from jaxnet.mesh import panel as P, polygon
from jaxnet.mesh.panel import PanelMesh, mesh_panel
from jaxnet.mesh.polygon import PanelError, side_divisions

L0 = 0.02  # m per twine


def _d(uv, tri):
    a, b, c = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])


def _signed_area(c):
    c = np.asarray(c, float)
    n = np.roll(c, -1, axis=0)
    return 0.5 * float(np.sum(c[:, 0] * n[:, 1] - n[:, 0] * c[:, 1]))


def _min_angles(uv, tri):
    p = uv[tri]
    out = []
    for k in range(3):
        u = p[:, (k + 1) % 3] - p[:, k]
        v = p[:, (k + 2) % 3] - p[:, k]
        cos = (u * v).sum(1) / np.linalg.norm(u, axis=1) / np.linalg.norm(v, axis=1)
        out.append(np.degrees(np.arccos(np.clip(cos, -1, 1))))
    return np.min(out, axis=0)


def _xyz(c):
    """A simple planar start layout: 1 twine -> L0 m along x and z."""
    c = np.asarray(c, float)
    return np.c_[c[:, 0] * L0, np.zeros(len(c)), c[:, 1] * L0]


def _mesh(c, h, **kw):
    return mesh_panel(c, _xyz(c), h * L0, L0, **kw)


def _boundary_edges(tri):
    e = np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1)
    u, cnt = np.unique(e, axis=0, return_counts=True)
    return u, cnt


def _segments(mesh):
    return {tuple(sorted((int(a), int(b)))) for s in mesh.side_nodes for a, b in zip(s[:-1], s[1:])}


# name: (corners, exact area in twines^2)
SHAPES = {
    "rectangle": ([(0, 0), (100, 0), (100, 40), (0, 40)], 4000.0),
    "square45": ([(0, 0), (50, -50), (100, 0), (50, 50)], 5000.0),
    "trapezoid": ([(0, 0), (100, 0), (80, 30), (20, 30)], 2400.0),
    "triangle": ([(0, 0), (100, 0), (30, 70)], 3500.0),
    "cw_rectangle": ([(0, 0), (0, 40), (100, 40), (100, 0)], -4000.0),
    "taper": ([(0, 0), (60, -60), (100, -20), (100, 20), (60, 60)], 6800.0),
    "L_shape": ([(0, 0), (100, 0), (100, 40), (40, 40), (40, 100), (0, 100)], 6400.0),
    "U_shape_cw": ([(0, 0), (0, 100), (30, 100), (30, 30), (70, 30), (70, 100), (100, 100), (100, 0)],
                   -(100 * 100 - 40 * 70.0)),
}
CONVEX = ["rectangle", "square45", "trapezoid", "triangle", "cw_rectangle", "taper"]


@pytest.fixture(scope="module")
def meshes():
    return {k: _mesh(c, 3.0) for k, (c, _) in SHAPES.items()}


@pytest.mark.parametrize("shape", list(SHAPES))
def test_area_conserved(meshes, shape):
    corners, area = SHAPES[shape]
    assert _signed_area(corners) == pytest.approx(area, rel=1e-14)
    m = meshes[shape]
    total = 0.5 * np.abs(_d(m.uv, m.triangles)).sum()
    assert abs(total - abs(area)) <= 1e-9 * abs(area)


@pytest.mark.parametrize("shape", list(SHAPES))
def test_orientation_matches_polygon(meshes, shape):
    _, area = SHAPES[shape]
    m = meshes[shape]
    d = _d(m.uv, m.triangles)
    if area > 0:
        assert d.min() > 0.0
    else:
        assert d.max() < 0.0
    h = 3.0
    assert np.abs(d).min() >= 1e-3 * h * h


@pytest.mark.parametrize("shape", list(SHAPES))
def test_boundary_is_exactly_the_side_segments(meshes, shape):
    m = meshes[shape]
    edges, cnt = _boundary_edges(m.triangles)
    assert cnt.max() == 2
    once = {tuple(e) for e in edges[cnt == 1].tolist()}
    segs = _segments(m)
    assert len(segs) == sum(len(s) - 1 for s in m.side_nodes)
    assert once == segs
    # every node is used
    assert len(np.unique(m.triangles)) == len(m.uv)
    assert m.triangles.dtype == np.int64


def test_types_and_node_order(meshes):
    m = meshes["taper"]
    C = 5
    assert isinstance(m, PanelMesh)
    assert m.uv.shape == (len(m.uv), 2) and m.xyz.shape == (len(m.uv), 3)
    assert m.weights.shape == (len(m.uv), C)
    np.testing.assert_array_equal(m.corner_nodes, np.arange(C))
    np.testing.assert_array_equal(m.uv[:C], np.asarray(SHAPES["taper"][0], float))
    # side nodes (without corners) come right after the corners, side by side
    inner = np.concatenate([s[1:-1] for s in m.side_nodes])
    np.testing.assert_array_equal(inner, np.arange(C, C + len(inner)))
    for k, s in enumerate(m.side_nodes):
        assert s[0] == k and s[-1] == (k + 1) % C
        assert s.dtype == np.int64
    # the rest are interior nodes, none on the boundary
    n_b = C + len(inner)
    assert len(m.uv) > n_b
    assert not np.any(m.weights[n_b:].max(axis=1) == 1.0)


@pytest.mark.parametrize("shape", list(SHAPES))
def test_weights_reproduce_uv_and_xyz(meshes, shape):
    corners = np.asarray(SHAPES[shape][0], float)
    m = meshes[shape]
    np.testing.assert_allclose(m.weights.sum(axis=1), 1.0, rtol=0, atol=1e-13)
    np.testing.assert_allclose(m.weights @ corners, m.uv, rtol=0, atol=1e-12)
    np.testing.assert_allclose(m.weights @ _xyz(corners), m.xyz, rtol=0, atol=1e-12)
    C = len(corners)
    np.testing.assert_array_equal(m.weights[:C], np.eye(C))
    # side nodes: two non-zero weights, linear along the side
    for k, s in enumerate(m.side_nodes):
        n = len(s) - 1
        t = np.arange(n + 1) / n
        w = m.weights[s]
        np.testing.assert_allclose(w[:, k], 1 - t, atol=1e-15)
        np.testing.assert_allclose(w[:, (k + 1) % C], t, atol=1e-15)
        assert np.count_nonzero(np.abs(w) > 0, axis=1).max() == 2


@pytest.mark.parametrize("shape", CONVEX)
def test_convex_interior_weights_positive(meshes, shape):
    m = meshes[shape]
    n_b = max(int(s.max()) for s in m.side_nodes) + 1
    w = m.weights[n_b:]
    assert len(w) > 10
    assert w.min() > 0.0


def test_mean_value_coordinates_exact_for_linear_functions():
    rng = np.random.default_rng(0)
    for shape in ["taper", "L_shape", "U_shape_cw"]:
        poly = np.asarray(SHAPES[shape][0], float)
        pts = rng.uniform(poly.min(0), poly.max(0), size=(4000, 2))
        pts = pts[polygon.inside(pts, poly) & (polygon.distance_to_boundary(pts, poly) > 1e-6)]
        assert len(pts) > 1000
        w = polygon.mean_value_coordinates(pts, poly)
        np.testing.assert_allclose(w.sum(1), 1.0, atol=1e-13)
        np.testing.assert_allclose(w @ poly, pts, rtol=0, atol=1e-12)


def test_affine_start_shape_is_reproduced_exactly():
    corners = np.asarray(SHAPES["taper"][0], float)
    A = np.array([[0.011, -0.004], [0.002, 0.017], [0.009, 0.006]])  # m per twine, 3x2
    b = np.array([1.5, -2.0, 30.0])
    m = mesh_panel(corners, corners @ A.T + b, 2.0 * L0, L0)
    n_b = max(int(s.max()) for s in m.side_nodes) + 1
    assert len(m.uv) - n_b > 1000
    np.testing.assert_allclose(m.xyz, m.uv @ A.T + b, rtol=0, atol=1e-12)
    # and the interior nodes really sit inside the panel, away from the border
    dist = polygon.distance_to_boundary(m.uv[n_b:], corners)
    assert dist.min() >= 0.6 * 2.0 * (1 - 1e-9)


def test_default_side_divisions():
    rect = SHAPES["rectangle"][0]
    np.testing.assert_array_equal(side_divisions(rect, 3 * L0, L0), [34, 14, 34, 14])
    np.testing.assert_array_equal(side_divisions(rect, 10 * L0, L0), [10, 4, 10, 4])  # exact, no extra
    sq = SHAPES["square45"][0]  # sides of 50*sqrt(2) = 70.71 twines
    np.testing.assert_array_equal(side_divisions(sq, 7 * L0, L0), [11, 11, 11, 11])
    np.testing.assert_array_equal(side_divisions(rect, 1000 * L0, L0), [1, 1, 1, 1])
    m = _mesh(rect, 3.0)
    assert [len(s) - 1 for s in m.side_nodes] == [34, 14, 34, 14]


def test_side_nodes_with_requested_divisions_equally_spaced():
    corners = np.asarray(SHAPES["trapezoid"][0], float)
    div = [7, 3, 5, 2]
    m = _mesh(corners, 4.0, divisions=div)
    C = 4
    for k, s in enumerate(m.side_nodes):
        assert len(s) == div[k] + 1
        a, b = corners[k], corners[(k + 1) % C]
        expect = a + np.outer(np.arange(div[k] + 1) / div[k], b - a)
        np.testing.assert_allclose(m.uv[s], expect, rtol=0, atol=1e-12)
        seglen = np.linalg.norm(np.diff(m.uv[s], axis=0), axis=1)
        np.testing.assert_allclose(seglen, np.linalg.norm(b - a) / div[k], rtol=1e-12)
    edges, cnt = _boundary_edges(m.triangles)
    assert {tuple(e) for e in edges[cnt == 1].tolist()} == _segments(m)
    # integral floats are accepted
    m2 = _mesh(corners, 4.0, divisions=np.array(div, dtype=float))
    np.testing.assert_array_equal(m2.triangles, m.triangles)


def test_seam_nodes_match_between_panels():
    # two panels sharing the side U=100 of A / U=0 of B, with the same divisions
    a_uv = [(0, 0), (100, 0), (100, 40), (0, 40)]
    b_uv = [(0, 0), (60, 0), (60, 40), (0, 40)]
    a_xyz = np.array([[0, 0, 0], [2.0, 0, 0], [2.0, 0, 0.8], [0, 0, 0.8]])
    b_xyz = np.array([[2.0, 0, 0], [2.0, 1.2, 0], [2.0, 1.2, 0.8], [2.0, 0, 0.8]])
    h = 3.0
    da = side_divisions(a_uv, h * L0, L0)
    db = side_divisions(b_uv, h * L0, L0)
    n = int(max(da[1], db[3]))
    da[1] = db[3] = n + 3  # force something non-default on the seam
    ma = mesh_panel(a_uv, a_xyz, h * L0, L0, divisions=da, name="A")
    mb = mesh_panel(b_uv, b_xyz, h * L0, L0, divisions=db, name="B")
    sa, sb = ma.side_nodes[1], mb.side_nodes[3]
    assert len(sa) == len(sb) == n + 4
    np.testing.assert_allclose(ma.xyz[sa], mb.xyz[sb[::-1]], rtol=0, atol=1e-14)


def test_node_count_scales_like_area_over_h2():
    corners, area = SHAPES["square45"]
    n = {h: len(_mesh(corners, h).uv) for h in (1.0, 2.0, 4.0)}
    for h in (1.0, 2.0):
        assert 4 * 0.8 <= n[h] / n[2 * h] <= 4 * 1.2
    # and the absolute density is that of an equilateral lattice of spacing h
    for h, count in n.items():
        expect = abs(area) / (h * h * math.sqrt(3) / 2)
        assert 0.8 <= count / expect <= 1.2


def test_min_angle_on_convex_panels():
    for shape in CONVEX:
        corners = SHAPES[shape][0]
        for h in (0.7, 3.0, 7.3):
            m = _mesh(corners, h)
            ang = _min_angles(m.uv, m.triangles)
            assert ang.min() >= 20.0, (shape, h, ang.min())
            n_b = max(int(s.max()) for s in m.side_nodes) + 1
            interior = (m.triangles >= n_b).all(axis=1)
            assert interior.sum() > 0
            assert ang[interior].min() >= 50.0
            edge = np.linalg.norm(m.uv[m.triangles] - m.uv[np.roll(m.triangles, 1, axis=1)], axis=2)
            assert edge.max() <= 2.0 * h


def test_triangle_size_independent_of_mesh_count():
    # h = 0.3 twine (many triangles per mesh) and h = 50 twines (many meshes per triangle)
    small = [(0, 0), (6, 0), (6, 4), (0, 4)]
    m = _mesh(small, 0.3)
    assert 0.8 <= len(m.uv) / (24 / (0.09 * math.sqrt(3) / 2)) <= 1.25
    big = [(0, 0), (1000, 0), (1000, 600), (0, 600)]
    m = _mesh(big, 50.0)
    assert 0.8 <= len(m.uv) / (600000 / (2500 * math.sqrt(3) / 2)) <= 1.25


def test_single_triangle_when_h_larger_than_panel():
    c = [(0, 0), (2, 0), (0.5, 1.5)]
    m = _mesh(c, 10.0)
    assert m.uv.shape == (3, 2)
    assert m.triangles.shape == (1, 3)
    assert _d(m.uv, m.triangles)[0] == pytest.approx(3.0)
    quad = [(0, 0), (3, 0), (3, 1), (0, 1)]
    m = _mesh(quad, 10.0)
    assert m.triangles.shape == (2, 3) and len(m.uv) == 4
    assert 0.5 * np.abs(_d(m.uv, m.triangles)).sum() == pytest.approx(3.0, rel=1e-12)


@pytest.mark.parametrize("corners,h", [
    ([(18, 2), (-6, -1), (-12, -11), (-8, -14), (-2, -5), (-3, -14), (4, -8)], 10.0),
    ([(-4, 16), (2, -11), (5, -3), (17, -10), (7, -2)], 40.0),
])
def test_non_convex_segment_recovery(monkeypatch, corners, h):
    calls = []
    real = P._recover_segments

    def spy(nodes, tri, missing, *args):
        calls.append(len(missing))
        return real(nodes, tri, missing, *args)

    monkeypatch.setattr(P, "_recover_segments", spy)
    m = _mesh(corners, h)
    assert sum(calls) >= 1           # the plain Delaunay missed a side segment
    area = _signed_area(corners)
    d = _d(m.uv, m.triangles)
    assert np.all(np.sign(d) == np.sign(area))
    assert abs(0.5 * np.abs(d).sum() - abs(area)) <= 1e-9 * abs(area)
    edges, cnt = _boundary_edges(m.triangles)
    assert {tuple(e) for e in edges[cnt == 1].tolist()} == _segments(m)


def test_collinear_corner_in_a_side_is_allowed():
    c = [(0, 0), (50, 0), (100, 0), (100, 40), (0, 40)]
    m = _mesh(c, 3.0)
    assert 0.5 * np.abs(_d(m.uv, m.triangles)).sum() == pytest.approx(4000.0, rel=1e-12)
    assert _d(m.uv, m.triangles).min() > 0


def test_deterministic():
    c, _ = SHAPES["taper"]
    m1, m2 = _mesh(c, 2.5), _mesh(c, 2.5)
    for f in ("uv", "xyz", "triangles", "corner_nodes", "weights"):
        np.testing.assert_array_equal(getattr(m1, f), getattr(m2, f))
    assert len(m1.side_nodes) == len(m2.side_nodes) == 5
    for a, b in zip(m1.side_nodes, m2.side_nodes):
        np.testing.assert_array_equal(a, b)
    assert len(m1.triangles) > 100


def test_arrays_are_read_only():
    m = _mesh(SHAPES["triangle"][0], 10.0)
    with pytest.raises(ValueError):
        m.uv[0, 0] = 1.0
    assert m.uv[0, 0] == 0.0


RECT = [(0, 0), (100, 0), (100, 40), (0, 40)]
RECT_XYZ = _xyz(RECT)


def _nan_at(arr, k, c, value=np.nan):
    a = np.array(arr, dtype=float)
    a[k, c] = value
    return a


@pytest.mark.parametrize("kwargs,fragments", [
    (dict(corners_uv=RECT[:2], corners_xyz=RECT_XYZ[:2]), ["at least 3 corners", "got 2"]),
    (dict(corners_uv=_nan_at(RECT, 2, 1)), ["corner 2", "V coordinate"]),
    (dict(corners_uv=_nan_at(RECT, 0, 0, np.inf)), ["corner 0", "U coordinate"]),
    (dict(corners_xyz=_nan_at(RECT_XYZ, 3, 2)), ["corner 3", "z coordinate"]),
    (dict(corners_uv=[(0, 0), (100, 0), (100, 0), (0, 40)]), ["corners 1 and 2", "same twine coordinates"]),
    (dict(corners_uv=[(0, 0), (100, 0), (0, 40), (0, 0)]), ["corners 3 and 0", "same twine coordinates"]),
    (dict(corners_uv=[(0, 0), (50, 50), (100, 100), (20, 20)]), ["zero area"]),
    (dict(corners_uv=[(0, 0), (100, 40), (100, 0), (0, 40)]), ["sides 0 and 2 cross"]),
    (dict(corners_uv=[(0, 0), (100, 0), (100, 40), (50, -10)]), ["sides 0 and 2 cross"]),
    (dict(corners_uv=[(0, 0), (100, 0), (50, 0), (50, 40)]), ["sides 0 and 1 overlap"]),
    (dict(corners_uv=[(0, 0), (1, 1), (2, 2)]), ["zero area", "collinear"]),
    (dict(step=0.0), ["step", "step=0.0"]),
    (dict(step=-0.1), ["step", "-0.1"]),
    (dict(step=float("nan")), ["step", "nan"]),
    (dict(l0=0.0), ["l0", "l0=0.0"]),
    (dict(l0=-1), ["l0", "-1"]),
    (dict(divisions=[3, 3, 3]), ["divisions", "one entry per side (4)"]),
    (dict(divisions=[3, 2.5, 3, 3]), ["divisions[1]", "2.5"]),
    (dict(divisions=[3, 3, 0, 3]), ["divisions[2]", "positive integer"]),
    (dict(divisions=[3, 3, 3, -2]), ["divisions[3]", "-2"]),
    (dict(corners_xyz=RECT_XYZ[:3]), ["corners_xyz has 3 corners", "4"]),
])
def test_bad_input_raises_named_error(kwargs, fragments):
    args = dict(corners_uv=RECT, corners_xyz=RECT_XYZ, step=0.06, l0=L0, name="wing_top")
    args.update(kwargs)
    if "corners_uv" in kwargs and "corners_xyz" not in kwargs:
        args["corners_xyz"] = np.zeros((len(kwargs["corners_uv"]), 3))
    with pytest.raises(PanelError) as exc:
        mesh_panel(**args)
    msg = str(exc.value)
    assert "'wing_top'" in msg
    for frag in fragments:
        assert frag in msg, (frag, msg)
    assert isinstance(exc.value, ValueError)


def test_too_many_nodes_is_refused_before_meshing():
    with pytest.raises(PanelError, match="nodes"):
        mesh_panel(RECT, RECT_XYZ, 1e-4 * L0, L0, name="huge")
