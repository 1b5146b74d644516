"""A panel meshed on a lattice of mesh diagonals (``mesh_panel(lattice=(NU, NV))``, ``Net.panel(lattice=...)``,
FEMNET's ``input Meshing_UV PANEL NU NV``): the lattice's counts, the exact covering of the panel, and FEMNET's gill
net h1 (9gill_net, copied unchanged with FEMNET's MIT licence into ``tests/data/femnet-corpus``): its mesh, its
long thin triangles against FEMNET's twine vectors, and its equilibrium against FEMNET's answer (ANSWERS.md, on
FEMNET's stored mesh: 1960.30541 -0.00046 535.77364 N).
"""

from __future__ import annotations

import pathlib

import numpy as np
import pytest

from jaxnet import figures, geometry
from jaxnet.io import femnet
from jaxnet.io.femnet.results import read_sta
from jaxnet.mesh import lattice_coordinates, lattice_divisions, mesh_panel
from jaxnet.net import Net, Twine
from jaxnet.scene import SceneError

H1 = pathlib.Path(__file__).resolve().parents[1] / "data" / "femnet-corpus" / "9gill_net" / "h1"
#: FEMNET's answer on h1's stored mesh (ANSWERS.md): force on the fixings (N)
FEMNET_H1 = np.array([1960.30541, -0.00046, 535.77364])


def _twine(UV):
    """FEMNET's mesh coordinates (U, V) -> twine coordinates (u, v) = (U + V, V - U)."""
    UV = np.asarray(UV, dtype=float)
    return np.stack([UV[:, 0] + UV[:, 1], UV[:, 1] - UV[:, 0]], axis=1)


def _d(uv, tri):
    """d of each triangle, (u2 - u1)(v3 - v1) - (u3 - u1)(v2 - v1) (twines²)."""
    a, b, c = uv[tri[:, 0]], uv[tri[:, 1]], uv[tri[:, 2]]
    return (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])


def _shoelace(uv):
    nxt = np.roll(uv, -1, axis=0)
    return 0.5 * float(np.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1]))


def _xyz(UV):
    """Start positions of the corners: the (U, V) plane laid flat, 0.1 m per mesh along U, 0.3 m along V."""
    UV = np.asarray(UV, dtype=float)
    return np.stack([np.zeros(len(UV)), 0.1 * UV[:, 0], 0.3 * UV[:, 1]], axis=1)


def test_rectangle_on_the_lattice_has_the_lattice_counts():
    """A rectangle of a x b cells of NU x NV meshes (U from 3 to 3 + a NU, V from 0 to b NV): (a + 1)(b + 1) nodes,
    2 a b triangles, each half a cell (|d(u, v)| = 2 |d(U, V)| = 2 NU NV), the interior nodes on the lattice, the
    sides divided one cell per segment; a counter-clockwise panel gives d > 0, a clockwise one d < 0."""
    nu, nv, a, b = 7.0, 2.5, 9, 5
    UV = np.array([[3, 0], [3 + a * nu, 0], [3 + a * nu, b * nv], [3, b * nv]])
    m = mesh_panel(_twine(UV), _xyz(UV), None, None, lattice=(nu, nv))
    assert len(m.uv) == (a + 1) * (b + 1) and len(m.triangles) == 2 * a * b
    d = _d(m.uv, m.triangles)
    np.testing.assert_allclose(d, 2 * nu * nv, rtol=1e-12)
    s = lattice_coordinates(m.uv, (nu, nv)) - np.array([3 / nu, 0])
    np.testing.assert_allclose(s, np.round(s), atol=1e-9)
    assert [len(x) - 1 for x in m.side_nodes] == [a, b, a, b]
    np.testing.assert_array_equal(lattice_divisions(_twine(UV), (nu, nv)), [a, b, a, b])
    flipped = mesh_panel(_twine(UV[::-1]), _xyz(UV[::-1]), None, None, lattice=(nu, nv))
    assert len(flipped.triangles) == 2 * a * b and np.all(_d(flipped.uv, flipped.triangles) < 0)


def test_lattice_mesh_covers_the_panel_exactly():
    """A non-convex panel with sides across the lattice (an L with a slanted side): the triangles' |d|/2 add up to
    the panel's area in twine coordinates, all with the panel's orientation; the interior nodes are lattice nodes
    (from FEMNET's origin, the floors of the smallest U and V), the start positions are the corners' affine map."""
    nu, nv = 40.0, 3.0
    UV = np.array([[0.5, 0], [1000, 0], [1000, 20], [430, 20], [300, 60], [0.5, 60]])
    uv = _twine(UV)
    m = mesh_panel(uv, _xyz(UV), None, None, lattice=(nu, nv))
    d = _d(m.uv, m.triangles)
    area = _shoelace(uv)
    assert area > 0 and np.all(d > 0)
    assert 0.5 * float(np.abs(d).sum()) == pytest.approx(area, rel=1e-12)
    n_boundary = sum(len(x) - 1 for x in m.side_nodes)
    s = lattice_coordinates(m.uv[n_boundary:], (nu, nv))
    np.testing.assert_allclose(s, np.round(s), atol=1e-9)
    assert len(s) > 0.8 * abs(_shoelace(lattice_coordinates(uv, (nu, nv))))
    UVn = np.stack([(m.uv[:, 0] - m.uv[:, 1]) / 2, (m.uv[:, 0] + m.uv[:, 1]) / 2], axis=1)
    np.testing.assert_allclose(m.xyz, _xyz(UVn), atol=1e-9)


def test_net_panel_with_a_lattice():
    """``Net.panel(lattice=(NU, NV))`` meshes the panel on the lattice (step unused); a lattice on a numerical-twine
    or hexagonal panel, or not two numbers > 0, is refused."""
    UV = np.array([[0, 0], [600, 0], [600, 30], [0, 30]])
    corners = np.concatenate([_xyz(UV), _twine(UV)], axis=1)
    twine = Twine(l0=0.1, ea=1000.0, diameter=0.002, density=1100.0)
    net = Net()
    net.panel("wall", corners, twine, lattice=(100, 5))
    net.fix((0.0, 0.0, 0.0))
    scene = net.build()
    assert scene.n_nodes == 7 * 7 and len(scene.netting.vertices) == 2 * 6 * 6
    for bad in ((100,), (100, 0), (100, -5), (100, float("nan"))):
        with pytest.raises(SceneError, match="lattice"):
            Net().panel("wall", corners, twine, lattice=bad)


def test_h1_mesh_is_femnets_lattice():
    """h1 (a gill net 5000 meshes long by 42 high, ``input Meshing_UV 1 200 3``, cables meshed first with 25 and 14
    bars along its sides): 26 x 15 = 390 nodes and 2 x 25 x 14 = 700 triangles, as FEMNET's h1.mdg, at FEMNET's
    places (the same 390 start positions to 0.1 mm); 660 of FEMNET's 700 triangles are jaxnet's, the other 20 cells
    being split along the other diagonal (a cell's four nodes are cocircular in twine coordinates: either split is
    Delaunay, FEMNET's triangle.c picks one at rounding's whim). Without the command the isotropic step (1 m = 5
    twines) would make about 19,000 nodes."""
    case = femnet.read_don(H1.with_suffix(".don"))
    ours, theirs = case.scene, femnet.read_mdg(H1.with_suffix(".mdg"), H1.with_suffix(".don")).scene
    assert ours.n_nodes == theirs.n_nodes == 390
    assert len(ours.netting.vertices) == len(theirs.netting.vertices) == 700
    key_a = np.round(np.asarray(ours.nodes.position), 4)
    key_b = np.round(np.asarray(theirs.nodes.position), 4)
    assert set(map(tuple, key_a)) == set(map(tuple, key_b))

    def triangles(scene, key):
        return {frozenset(map(tuple, key[t])) for t in np.asarray(scene.netting.vertices)}

    assert len(triangles(ours, key_a) & triangles(theirs, key_b)) == 660
    assert case.info["inputs"]["meshing_uv 1"] == (1.0, 200.0, 3.0)
    iso = femnet.parse_don(H1.with_suffix(".don")).panels[0]
    area = abs(_shoelace(_twine(iso.corners[:, 3:5])))
    h = iso.material["step"].value / iso.material["l0"].value
    assert 18_000 < area / (h * h * np.sqrt(3) / 2) < 20_000


def test_h1_long_thin_triangles_have_femnets_twines():
    """h1's triangles are 200 meshes long and 3 high: on FEMNET's mesh and equilibrium (h1.sta), jaxnet's twine
    vectors of every triangle are FEMNET's (to 1e-6 m, the .sta's print), their twine counts |d|/2 add up to 2 x 5000
    x 42 twines per family (the panel's twine area), and the twines are stretched by the 0.2 m long twine (l0)
    at most by FEMNET's few per cent."""
    case = femnet.read_mdg(H1.with_suffix(".mdg"), H1.with_suffix(".don"))
    scene = case.scene
    pos, _, vec, _ = read_sta(H1.with_suffix(".sta"), scene.n_nodes, scene.bars.ends.shape[0],
                              scene.netting.vertices.shape[0])
    tri = np.asarray(scene.netting.vertices)
    uv = np.asarray(scene.netting.uv)
    assert np.ptp(uv[..., 0] - uv[..., 1], axis=1).max() / 2 == pytest.approx(200.0)   # 200 meshes long along U
    U, V, d = (np.asarray(a) for a in __import__("jax").vmap(geometry.twine_vectors)(pos[tri], uv))
    np.testing.assert_allclose(U, vec[:, 1], atol=2e-6)
    np.testing.assert_allclose(V, vec[:, 0], atol=2e-6)
    assert float(np.asarray(geometry.twine_count(d)).sum()) == pytest.approx(2 * 5000 * 42, rel=1e-12)
    assert 0.19 < np.linalg.norm(U, axis=1).min() and np.linalg.norm(U, axis=1).max() < 0.21


def test_h1_equilibrium_against_femnet():
    """h1 solved from its drawn shape, with FEMNET's free surface z = 0: jaxnet's mesh and FEMNET's give the same force
    on the fixings, 1959.99 0 508.51 N against FEMNET's 1960.31 0 535.77 N (-0.016 % and -5.1 %; taken wholly immersed,
    as before the surface was modelled, its 500 floats of 60 N gave 2647.18 0 28093.82 N, the net standing 2 m up,
    taut; with the surface but drag out of the water, 2223.81 0 851.69 N). The float line floats at the surface, as
    FEMNET's (z = +0.0074 m against FEMNET's +0.066 m). At FEMNET's equilibrium (h1.sta) jaxnet's netting drag,
    each vertex's share weighed by its wetted part, is FEMNET's "surface drag" (1586.34 N against 1586 N);
    its cable drag is 261.0 N against FEMNET's "element drag" 374 N: the float line's bars, 6.6 cm up there, are out
    of the band of their diameter in jaxnet (jaxnet.terms.drag.wetted_shares) and still in FEMNET's ramp, the side of
    the cube of each end's lumped volume (miseajourPondFS.c), which the folded floats make large."""
    from jaxnet.solve.statics import solve

    totals = []
    for case in (femnet.read_don(H1.with_suffix(".don")), femnet.read_mdg(H1.with_suffix(".mdg"), H1.with_suffix(".don"))):
        eq = solve(case.scene, case.solver)
        assert eq.converged
        totals.append(np.array(femnet.femnet_figures(case.scene, eq, case.info["symmetry_axes"], case.info["fixity"])
                               ["total_force_N"]))
        assert 0.0 < np.asarray(eq.x)[:, 2].max() < 0.0658  # the float line at the surface, lower than FEMNET's
    np.testing.assert_allclose(totals[0], totals[1], rtol=0, atol=0.05)
    np.testing.assert_allclose(totals[0][[0, 2]], [1959.99, 508.51], atol=0.05)

    scene = case.scene
    pos, _, _, summary = read_sta(H1.with_suffix(".sta"), scene.n_nodes, scene.bars.ends.shape[0],
                                  scene.netting.vertices.shape[0])
    np.testing.assert_allclose(summary["forces along X Y and Z axes (N)"], [1960.30521, -0.00045, 535.77367])
    assert pos[:, 2].max() == pytest.approx(0.0658, abs=2e-4)
    forces = figures.force_breakdown(scene, pos)
    assert forces["drag_netting_N"][0] == pytest.approx(summary["surface drag (N)"][0], rel=5e-4)
    assert forces["drag_cables_N"][0] == pytest.approx(261.0, abs=0.1) and summary["element drag (N)"][0] == 374.0


def test_meshing_uv_is_read_strictly(tmp_path):
    """The node-count estimate honours the lattice (h1 with a 0.2 m step, one twine, would mesh ~490,000 nodes and is
    refused without the command, read with it); FEMNET's 'Meshing_uv' (twines) and other spellings, a panel that
    does not exist and steps <= 0 are refused at their line; a panel of meshing type 1, which FEMNET meshes without
    the command, is meshed isotropically with a warning."""
    text = H1.with_suffix(".don").read_text()
    line = text[:text.index("input Meshing_UV")].count("\n") + 1
    fine = text.replace("Meshing step (m):\t\t\t1.000000", "Meshing step (m):\t\t\t0.200000", 1)
    assert fine != text
    path = tmp_path / "h1.don"
    path.write_text(fine)
    assert femnet.parse_don(path).inputs["meshing_uv 1"].value == (1.0, 200.0, 3.0)
    path.write_text(fine.replace("input Meshing_UV 1 200 3", "", 1))
    with pytest.raises(SceneError, match=r"panel 1: meshing step 0\.2 m gives about 4\.\d+e\+05 nodes"):
        femnet.parse_don(path)
    for replaced, message in (("input Meshing_uv 1 200 3", "'Meshing_uv' .* not supported"),
                              ("input meshing_UV 1 200 3", "no other spelling"),
                              ("input Meshing_UV 1 0 3", "must be > 0"),
                              ("input Meshing_UV 1.5 200 3", "whole number")):
        path.write_text(text.replace("input Meshing_UV 1 200 3", replaced, 1))
        with pytest.raises(SceneError, match=rf"h1\.don:{line}: .*{message}"):
            femnet.parse_don(path)
    path.write_text(text.replace("input Meshing_UV 1 200 3", "input Meshing_UV 2 200 3", 1))
    with pytest.raises(SceneError, match=rf"h1\.don:{line}: 'input Meshing_UV 2': panel 2 does not exist"):
        femnet.read_don(path)
    path.write_text(text.replace("Meshing type:\t\t\t\t2", "Meshing type:\t\t\t\t1", 1))
    case = femnet.parse_don(path)
    assert any("meshing type 1" in w and f":{line}:" in w for w in case.warnings)
    assert femnet.materials.meshing_lattices(case) == {}
