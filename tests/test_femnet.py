"""FEMNET's case files (jaxnet.io.femnet): reading, strict errors, and the two worked cases against FEMNET.

The data in tests/data/femnet are FEMNET's own files (MIT licence, see the LICENSE there). FEMNET's
summary prints drags as integers (N) and its .sta positions with 9 decimals.
"""

import json
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxnet import assemble, cli, geometry, model as model_lib
from jaxnet.io import femnet
from jaxnet.scene import SceneError
from jaxnet.solve.statics import solve

DATA = pathlib.Path(__file__).parent / "data" / "femnet"
CASES = {  # nodes, triangles, bars in the .mdg headers; fixed components in the .efg; symmetry-held ones
    "nr_netting": (446, 770, 110, 6, 0),
    "c2": (657, 1243, 7, 15, 50),
}


def _sta(case, scene):
    nb = 0 if scene.bars is None else len(scene.bars.ends)
    return femnet.read_sta(DATA / f"{case}.sta", scene.n_nodes, nb, len(scene.netting.vertices))


def _residual_at(scene, x):
    """jaxnet's out-of-balance nodal forces (N, 3) at positions x, zero on held coordinates; and per term."""
    per = assemble.term_forces(jnp.asarray(x), scene, model=model_lib.active_terms(scene))
    total = sum(np.asarray(v) for v in per.values())
    return np.where(np.asarray(scene.nodes.fixed), 0.0, total), {k: np.asarray(v).sum(axis=0) for k, v in per.items()}


@pytest.mark.parametrize("case", sorted(CASES))
def test_mdg_counts_and_twine_convention(case):
    n_nodes, n_tri, n_bars, efg_fixed, symmetric = CASES[case]
    scene, solver, info = femnet.read_mdg(DATA / f"{case}.mdg", DATA / f"{case}.don")
    assert (scene.n_nodes, len(scene.netting.vertices), len(scene.bars.ends)) == (n_nodes, n_tri, n_bars)
    # unknowns: every coordinate but the .efg's fixed components and those held on symmetry planes
    assert scene.n_dof == 3 * n_nodes - efg_fixed - symmetric
    # FEMNET's (U, V) count meshes along the diagonals; twine coordinates (U + V, V - U) reproduce the .sta's
    # two twine vectors per triangle (written v first, then u) from its positions, to the print precision
    pos, _, vec, _ = _sta(case, scene)
    U, V, d = jax.vmap(geometry.twine_vectors)(pos[np.asarray(scene.netting.vertices)], scene.netting.uv)
    assert np.abs(np.asarray(U) - vec[:, 1]).max() < 2e-9 and np.abs(np.asarray(V) - vec[:, 0]).max() < 2e-9
    # ... and each is one twine long (l0, within the twines' elastic strain)
    np.testing.assert_allclose(np.linalg.norm(vec[:, 1], axis=1).max(), scene.netting.l0[0], rtol=2e-3)


def test_read_don_maps_types_symmetry_and_catch():
    net, solver, info = femnet.read_don(DATA / "c2.don")
    scene = net.build()
    x, fixed = np.asarray(scene.nodes.position), np.asarray(scene.nodes.fixed)
    # the two symmetry planes (y = 0, z = -10) hold y and z there; the front (x = 0) is held along x
    assert np.all(fixed[np.abs(x[:, 1]) < 1e-9, 1]) and np.all(fixed[np.abs(x[:, 2] + 10) < 1e-9, 2])
    assert np.all(fixed[np.abs(x[:, 0]) < 1e-9, 0])
    assert fixed[np.abs(x[:, 0]) > 1e-9, 0].sum() == 0
    # FEMNET's 0.2 m3 is the quarter's catch: jaxnet's catch holds 4 x 0.2 for the whole cod-end
    assert scene.catch.symmetry == 4 and scene.catch.volume == pytest.approx(0.8)
    np.testing.assert_allclose(scene.catch.axis, [1, 0, 0])
    assert (solver.tol, solver.max_iter, solver.max_step) == (1e-4, 1000, 0.1)
    # the cod line (7 bars, meshed before the panel) is sewn along the rear side and divides it
    assert len(scene.bars.ends) == 7 and info["cables_sewn_along_sides"] == {"cable 1": "panel 1 side 2"}
    net, solver, info = femnet.read_don(DATA / "nr_netting.don")
    scene = net.build()
    assert info["water_density"] == 1000.0 and scene.environment.water_density == 1000.0
    # the sinker rope (cable 5, meshed first) keeps its 57 bars; the one-bar cables 3, 4, 6 follow the sides
    per_cable = np.bincount(np.asarray(scene.bars.cable))
    assert per_cable[4] == 57 and per_cable[0] == 5 and min(per_cable[[2, 3, 5]]) > 1
    assert np.asarray(scene.nodes.fixed).sum() == 6  # the two rope ends, in x, y, z


def _mutate(tmp_path, case, old, new, count=1):
    text = (DATA / f"{case}.don").read_text()
    assert text.count(old) >= 1
    text = text.replace(old, new, count)
    path = tmp_path / f"{case}.don"
    path.write_text(text)
    return path, text


def _line_of(text, needle):
    return text[: text.index(needle)].count("\n") + 1


@pytest.mark.parametrize("old, new, needle, words", [
    ("Traction stiffness (N):\t\t\t6000.000000", "Traction stiffnes (N):\t\t\t6000.000000", "Traction stiffnes",
     "expected the field"),
    ("Unstretched length (m):\t\t\t0.022000", "Unstretched length (m):\t\t\tnan", "nan", "not a finite number"),
    ("Traction stiffness (N):\t\t\t6000.000000", "Traction stiffness (N):\t\t\t-6000.000000", "-6000", "must be >= 0"),
    ("L: 1.97", "L: 0.0", "L: 0.0", "must be > 0"),
    ("Wave height (m):                    0.000000", "Wave height (m):                    1.5", "1.5", "waves"),
    ("Added mass X,Y,Z (kg):        0.000000  0.000000  0.000000\nLength X,Y,Z (m):        0.000000  0.000000  0.000000\nDrag coefficient X,Y,Z:        1.200000  1.200000  1.200000\nExternal forces X,Y,Z (N):    0.000000  0.000000  0.000000\nDisplacement X,Y,Z:        0 0 0",
     "Added mass X,Y,Z (kg):        0.000000  0.000000  2.000000\nLength X,Y,Z (m):        0.000000  0.000000  0.000000\nDrag coefficient X,Y,Z:        1.200000  1.200000  1.200000\nExternal forces X,Y,Z (N):    0.000000  0.000000  0.000000\nDisplacement X,Y,Z:        0 0 0",
     "2.000000\nLength", "added mass"),
    ("input water_density 1000", "input wind_speed 10", "wind_speed", "unknown input"),
    ("4    1.695000    -0.735000    -1.000000    0.000000    120.000000", "4    1.695000    -0.735000    -1.000000    80.000000    120.000000",
     "3    1.695000    0.730000", "same (U, V)"),
])
def test_strict_errors_name_the_line(tmp_path, old, new, needle, words):
    path, text = _mutate(tmp_path, "nr_netting", old, new)
    with pytest.raises(SceneError) as err:
        femnet.read_don(path)
    message = str(err.value)
    assert words in message
    assert f"nr_netting.don:{_line_of(text, needle)}:" in message, message


def test_truncated_and_collinear(tmp_path):
    text = (DATA / "c2.don").read_text()
    cut = text[: text.index("No du type :\t\t\t4")]
    (tmp_path / "cut.don").write_text(cut)
    with pytest.raises(SceneError, match=r"cut\.don:\d+: .*(truncated|ends)"):
        femnet.read_don(tmp_path / "cut.don")
    # a contour whose corners lie on one line in (U, V): no netting between them
    path, text = _mutate(tmp_path, "c2", "4\t0.000000\t0.270468\t-10.000000\t0.000000\t-25.000000",
                         "4\t0.000000\t0.270468\t-10.000000\t150.000000\t0.000000")
    path.write_text(text.replace("3\t5.765000\t0.270468\t-10.000000\t50.000000\t-25.000000",
                                 "3\t5.765000\t0.270468\t-10.000000\t100.000000\t0.000000"))
    with pytest.raises(SceneError, match=r"c2\.don:\d+: panel 1: the \(U, V\) contour .* collinear"):
        femnet.read_don(path)


def test_nr_netting_on_femnet_mesh_matches_femnet():
    scene, solver, info = femnet.read_mdg(DATA / "nr_netting.mdg", DATA / "nr_netting.don")
    pos, strain, _, summary = _sta("nr_netting", scene)
    # FEMNET's equilibrium is one of jaxnet's model to FEMNET's own criterion: at FEMNET's positions jaxnet's
    # residual on the netting nodes has a MEAN norm below the case's 1e-3 N threshold (on the sinker rope,
    # EA = 1e6 N, the .sta's 1e-9 m print precision alone makes ~0.03 N)
    r, per_term = _residual_at(scene, pos)
    on_bars = np.zeros(scene.n_nodes, bool)
    on_bars[np.asarray(scene.bars.ends)] = True
    netting_only = ~on_bars & ~np.asarray(scene.nodes.fixed).any(axis=1)
    assert np.linalg.norm(r[netting_only], axis=1).mean() < 1e-3
    # FEMNET's bar strains are jaxnet's (printed with 7 decimals)
    x = pos[np.asarray(scene.bars.ends)]
    jstrain = np.linalg.norm(x[:, 1] - x[:, 0], axis=1) / np.asarray(scene.bars.rest_length) - 1
    assert np.abs(jstrain - strain).max() < 2e-7
    eq, timing = solve(scene, solver)
    fig = femnet.femnet_figures(scene, eq, info["symmetry_axes"])
    femnet_total = summary["forces along X Y and Z axes (N)"]
    # drags, printed as integers by FEMNET
    assert abs(fig["drag_netting_N"][0] - summary["surface drag (N)"][0]) <= 0.5
    assert abs(fig["drag_cables_N"][0] - summary["element drag (N)"][0]) <= 0.5
    # Total force: 0.12 % in x, 0.33 N (1.6 %) in z, and node positions within 11 mm, not the 1e-4 m hoped
    # for: FEMNET stops when the MEAN nodal residual is below 1e-3 N, so its answer keeps up to ~1e-3 N per
    # node of out-of-balance force; summed over the 444 free nodes that is (-0.08, 0, -0.34) N of jaxnet's
    # loads that FEMNET's reactions do not carry. That leftover force points from FEMNET's positions towards
    # jaxnet's equilibrium (converged here to 1e-5 N per node): it is the part of the way FEMNET's damped
    # iteration had not gone yet, and the slack netting moves by cm under such forces.
    assert abs(fig["total_force_N"][0] - femnet_total[0]) <= 1.5e-3 * femnet_total[0]
    assert abs(fig["total_force_N"][2] - femnet_total[2]) <= 0.02 * abs(femnet_total[2])
    step = np.asarray(eq.x) - pos
    cos = np.einsum("ij,ij->i", r, step) / np.maximum(np.linalg.norm(r, axis=1) * np.linalg.norm(step, axis=1), 1e-300)
    assert cos[netting_only].mean() > 0.8
    assert np.linalg.norm(np.asarray(eq.x) - pos, axis=1).max() < 0.011


def test_c2_on_femnet_mesh_differences_are_named():
    scene, solver, info = femnet.read_mdg(DATA / "c2.mdg", DATA / "c2.don")
    pos, _, vec, summary = _sta("c2", scene)
    front = summary["front"][0]
    r, per_term = _residual_at(scene, pos)
    # Same catch model: at FEMNET's equilibrium jaxnet's catch pressure has FEMNET's catch drag (978 N)
    assert abs(per_term["catch_pressure"][0] - summary["catch drag (N)"][0]) <= 0.5
    # Shielding (the model, as FEMNET): the netting behind the catch front carries the catch pressure and no
    # twine drag. At FEMNET's equilibrium the twine drag ahead of the front is FEMNET's 268 N (0.2 %); the
    # more than 400 N the netting behind the front would otherwise carry is left out.
    net = scene.netting
    c = jnp.asarray(scene.environment.current_speed * np.asarray(scene.environment.current_direction))
    drag = jax.vmap(lambda x, uv, l0, d, cd, f: femnet_drag(x, uv, l0, d, cd, f, c, scene.environment.water_density))(
        pos[np.asarray(net.vertices)], net.uv, net.l0, net.diameter, net.cd_normal, net.tangential_ratio)
    ahead = pos[np.asarray(net.vertices)].mean(axis=1)[:, 0] < front
    in_front = np.asarray(drag)[ahead].sum(axis=(0, 1))[0]
    assert abs(in_front - summary["surface drag (N)"][0]) <= 5e-3 * summary["surface drag (N)"][0]
    assert np.asarray(drag)[~ahead].sum(axis=(0, 1))[0] > 400.0
    # Difference 2 (modelling choice): jaxnet's knots touch on both diagonals (jaxnet.terms.knot); FEMNET's
    # equilibrium has 267 triangles whose meshes are closed past the 1 cm knots (half angle > 90° - 5°)
    U, V = vec[:, 1], vec[:, 0]
    half = np.arctan2(np.linalg.norm(U - V, axis=1), np.linalg.norm(U + V, axis=1))
    alpha_min = np.arcsin(0.010 / (2 * 0.05765))
    assert np.sum(half > np.pi / 2 - alpha_min) == 267 and np.sum(half < alpha_min) == 0
    # jaxnet's equilibrium against FEMNET's summary
    eq, timing = solve(scene, solver)
    fig = femnet.femnet_figures(scene, eq, info["symmetry_axes"])
    assert fig["catch"]["holds_the_volume"] and fig["catch"]["volume_modelled_m3"] == pytest.approx(0.2, rel=1e-6)
    # balance: the fixings carry the netting drag, the cod line's drag and the catch (no weight: density 1025)
    np.testing.assert_allclose(fig["total_force_N"][0], fig["drag_netting_N"][0] + fig["drag_cables_N"][0]
                               + fig["catch_drag_N"][0], rtol=1e-6)
    # netting drag (ahead of the front) as FEMNET's 268 N within its print rounding and 0.5 %
    assert abs(fig["drag_netting_N"][0] - summary["surface drag (N)"][0]) <= 0.5 + 5e-3 * 268.0
    # catch diameter within the 1 % on shape figures
    np.testing.assert_allclose(fig["catch"]["diameter_m"], summary["maximal catch diameter (m)"][0], rtol=1e-2)
    # Open difference (not yet traced, see the notes of issue 4): the catch drag and the total are 3-4 % below
    # FEMNET's (942 N vs 978 N; 1210 N vs 1246.5 N), the thickness 2 % above (0.640 vs 0.628 m); jaxnet's
    # residual at FEMNET's positions is radial and concentrated near the cod line. Bounded here so that a
    # change in either direction is seen.
    assert -0.045 < fig["total_force_N"][0] / summary["forces along X Y and Z axes (N)"][0] - 1.0 < -0.015
    assert 0.005 < fig["catch"]["thickness_m"] / summary["thickness of the catch (m)"][0] - 1.0 < 0.03


def femnet_drag(x, uv, l0, d, cd, f, c, rho):
    from jaxnet.terms import drag

    return drag.netting_drag(x, uv, l0, d, cd, f * cd, c, rho)


def test_cli_runs_a_femnet_case_on_its_mesh(tmp_path):
    out = tmp_path / "out"
    code = cli.main(["run", str(DATA / "nr_netting.don"), "--mesh", str(DATA / "nr_netting.mdg"), "--out", str(out),
                     "--quiet"])
    assert code == 0
    result = json.loads((out / "result.json").read_text())
    assert result["n_nodes"] == 446 and result["converged"]
    assert abs(result["femnet"]["drag_netting_N"][0] - 138) <= 0.5
    assert result["femnet_case"]["water_density"] == 1000.0
    assert cli.main(["run", str(DATA / "c2.mdg"), "--mesh", str(DATA / "c2.mdg"), "--out", str(out)]) == 2
