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

from jaxnet import cli, figures, geometry, model as model_lib
from jaxnet.model import assemble
from jaxnet.io import femnet
from jaxnet.scene import SceneError
from jaxnet.solve.statics import solve

DATA = pathlib.Path(__file__).parents[1] / "data" / "femnet"
CASES = {  # nodes, triangles, bars in the .mdg headers; fixed components in the .efg; symmetry-held ones
    "nr_netting": (446, 770, 110, 6, 0),
    "c2": (657, 1243, 7, 15, 50),
}


def _sta(case, scene):
    nb = 0 if scene.bars is None else len(scene.bars.ends)
    return femnet.read_sta(DATA / f"{case}.sta", scene.n_nodes, nb, len(scene.netting.vertices))


def _residual_at(scene, x):
    """jaxnet's out-of-balance nodal forces (N, 3) at positions x, zero on held coordinates; and per term.
    (:func:`jaxnet.model.assemble.term_forces` of every active term, by the compiled program of
    :func:`jaxnet.figures.nodal_forces_by_term`, which the case's summary figures then reuse.)"""
    per = figures.nodal_forces_by_term(scene, x)
    total = sum(np.asarray(v) for v in per.values())
    return np.where(np.asarray(scene.nodes.fixed), 0.0, total), {k: np.asarray(v).sum(axis=0) for k, v in per.items()}


@pytest.mark.parametrize("case", sorted(CASES))
def test_mdg_counts_and_twine_convention(case):
    n_nodes, n_tri, n_bars, efg_fixed, symmetric = CASES[case]
    scene = femnet.read_mdg(DATA / f"{case}.mdg", DATA / f"{case}.don").scene
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


def test_reading_a_case_runs_no_jax_program(caplog):
    # a first run pays for every program it compiles: reading a case (c2: knots, a catch, a cable, symmetry)
    # and building its scene compile none (the knot stiffness once took three, 60 ms)
    jax.clear_caches()
    jax.config.update("jax_log_compiles", True)
    try:
        with caplog.at_level("WARNING"):
            scene = femnet.read_don(DATA / "c2.don").scene
    finally:
        jax.config.update("jax_log_compiles", False)
    compiled = [r.getMessage().split(" with ")[0] for r in caplog.records if r.getMessage().startswith("Compiling")]
    assert scene.n_nodes == 787 and compiled == []


def test_read_don_maps_types_symmetry_and_catch():
    case = femnet.read_don(DATA / "c2.don")
    scene, solver, info = case.scene, case.solver, case.info
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
    case = femnet.read_don(DATA / "nr_netting.don")
    scene, info = case.scene, case.info
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
    ("Traction stiffness (N):\t\t\t6000.000000", "Traction stiffness (N):\t\t\t-6000.000000", "-6000", "must be > 0"),
    # twines without traction stiffness hold nothing: a mechanism, refused at the line (0 stays legal in compression)
    ("Traction stiffness (N):\t\t\t6000.000000", "Traction stiffness (N):\t\t\t0.000000",
     "Traction stiffness (N):\t\t\t0.0", "'panel 1: traction stiffness' must be > 0, got 0.0"),
    ("L: 1.97", "L: 0.0", "L: 0.0", "must be > 0"),
    # (waves and dynamic settings are read: test_dynamic_settings_and_waves_are_read checks their errors)
    # a limit's sense is -1 (ceiling), 0 (none) or 1 (floor, fond.c's sea bed): anything else is refused
    ("Limits sens X,Y,Z:        0  0  0\nSymetry X,Y,Z:            0  0  0\n\nNUMERIC", "Limits sens X,Y,Z:        0  0  2\nSymetry X,Y,Z:            0  0  0\n\nNUMERIC",
     "0  0  2\nSymetry X,Y,Z:            0  0  0\n\nNUMERIC", "limits sense must be"),
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
    case = femnet.read_mdg(DATA / "nr_netting.mdg", DATA / "nr_netting.don")
    scene, solver, info = case.scene, case.solver, case.info
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
    eq = solve(scene, solver)
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
    # ... and quantitatively: ONE undamped Newton step of jaxnet's model from FEMNET's positions, driven by
    # that leftover force alone, lands within 0.5 mm of jaxnet's equilibrium, 10.5 mm away: the difference
    # is the linear response of the net's soft (slack) modes to the force FEMNET's criterion leaves.
    from jaxnet import linalg
    from jaxnet.solve import programs

    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    free = np.asarray(pattern.free)
    # compiled (op by op, its element vmaps would compile dozens of small programs), with the solver's XLA options
    K = np.asarray(programs.jit(assemble.tangent, static_argnames="model")(jnp.asarray(pos), scene, model, pattern))
    dx, ok = linalg.HostSolver(pattern.indptr, pattern.indices).solve(K, r.ravel()[free])
    newton = pos.ravel().copy()
    newton[free] += dx
    assert ok and np.linalg.norm(newton.reshape(-1, 3) - np.asarray(eq.x), axis=1).max() < 5e-4


def test_c2_on_femnet_mesh_with_femnet_laws_gives_femnet_answer():
    # With FEMNET's knot contact (fermeture2) and its netting drag of cases with a catch (trainee_fil; both in
    # docs/errata.md), jaxnet's equilibrium is FEMNET's: node by node and in every summary figure.
    case = femnet.read_mdg(DATA / "c2.mdg", DATA / "c2.don")
    scene, solver, info = case.scene, case.solver, case.info
    assert info["femnet_laws"]
    assert set(np.asarray(scene.netting.knot_form).tolist()) == {1} and set(np.asarray(scene.netting.drag_model).tolist()) == {3}
    pos, _, _, summary = _sta("c2", scene)
    eq = solve(scene, solver)
    assert np.linalg.norm(np.asarray(eq.x) - pos, axis=1).max() <= 1e-4  # m
    fig = femnet.femnet_figures(scene, eq, info["symmetry_axes"])
    total = summary["forces along X Y and Z axes (N)"][0]
    assert abs(fig["total_force_N"][0] / total - 1.0) <= 1e-3
    # FEMNET prints the catch and netting drags rounded to the newton
    assert abs(fig["catch_drag_N"][0] - summary["catch drag (N)"][0]) <= 0.5 + 1e-3 * 978.0
    assert abs(fig["drag_netting_N"][0] - summary["surface drag (N)"][0]) <= 0.5 + 1e-3 * 268.0
    for name, key in (("thickness_m", "thickness of the catch (m)"), ("diameter_m", "maximal catch diameter (m)")):
        np.testing.assert_allclose(fig["catch"][name], summary[key][0], rtol=1e-2)
    assert fig["catch"]["holds_the_volume"] and fig["catch"]["volume_modelled_m3"] == pytest.approx(0.2, rel=1e-6)


def test_c2_iterations_without_a_step_reuse_their_tangent(monkeypatch, capsys):
    """c2's damped solve has iterations whose direction the line search cannot use (at the start of a softened
    stage): x stays, so the next iteration's tangent is the same matrix and is not computed again. One
    tangent per iteration, less one per iteration that took no step (its progress line says "step 0.000"),
    and the same equilibrium as FEMNET's."""
    from jaxnet.solve import statics

    calls = {"tangent": 0}
    compile_pieces = statics.compile_pieces

    def counting(*args, **kwargs):
        pieces = dict(compile_pieces(*args, **kwargs))
        tangent = pieces["tangent"]

        def counted(*a):
            calls["tangent"] += 1
            return tangent(*a)

        pieces["tangent"] = counted
        return pieces

    monkeypatch.setattr(statics, "compile_pieces", counting)
    case = femnet.read_mdg(DATA / "c2.mdg", DATA / "c2.don")
    scene, solver = case.scene, case.solver
    eq = solve(scene, solver, verbose=True, method="damped")
    steps = [float(line.split("step")[1]) for line in capsys.readouterr().out.splitlines() if "newton" in line]
    assert len(steps) == int(eq.iterations) and eq.converged
    no_step = sum(step == 0.0 for step in steps[:-1])
    assert no_step >= 1  # the case has some (else this test tests nothing)
    assert calls["tangent"] == int(eq.iterations) - no_step
    pos, _, _, _ = _sta("c2", scene)
    assert np.linalg.norm(np.asarray(eq.x) - pos, axis=1).max() <= 1e-4  # m


def test_c2_on_femnet_mesh_with_jaxnet_laws_differs_as_named():
    case = femnet.read_mdg(DATA / "c2.mdg", DATA / "c2.don", femnet_laws=False)
    scene, solver, info = case.scene, case.solver, case.info
    assert not info["femnet_laws"] and not np.any(np.asarray(scene.netting.drag_model))
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
    in_front = np.asarray(drag)[ahead].sum(axis=(0, 1))
    assert abs(in_front[0] - summary["surface drag (N)"][0]) <= 5e-3 * summary["surface drag (N)"][0]
    assert np.asarray(drag)[~ahead].sum(axis=(0, 1))[0] > 400.0
    # Difference 1: the book's twine drag pushes the cod-end's netting across the flow (about 47 N along y
    # and along z on the quarter); FEMNET's trainee_fil cancels that part.
    assert in_front[1] < -30.0 and in_front[2] < -30.0
    # Difference 2: jaxnet's knot contact is the book's (stiffness 4.280, 5x FEMNET's; no 2 cos a factor);
    # FEMNET's equilibrium has 267 triangles closed past the 1 cm knots (half angle > 90 deg - 5 deg)
    U, V = vec[:, 1], vec[:, 0]
    half = np.arctan2(np.linalg.norm(U - V, axis=1), np.linalg.norm(U + V, axis=1))
    alpha_min = np.arcsin(0.010 / (2 * 0.05765))
    assert np.sum(half > np.pi / 2 - alpha_min) == 267 and np.sum(half < alpha_min) == 0
    assert np.linalg.norm(r, axis=1).max() > 100.0  # N: jaxnet's residual at FEMNET's positions, from these knots
    # jaxnet's own equilibrium: the catch, unpushed inward by the cross-flow drag, is 3-4 % less loaded
    eq = solve(scene, solver)
    fig = femnet.femnet_figures(scene, eq, info["symmetry_axes"])
    np.testing.assert_allclose(fig["total_force_N"][0], fig["drag_netting_N"][0] + fig["drag_cables_N"][0]
                               + fig["catch_drag_N"][0], rtol=1e-6)
    assert -0.045 < fig["total_force_N"][0] / summary["forces along X Y and Z axes (N)"][0] - 1.0 < -0.015


def femnet_drag(x, uv, l0, d, cd, f, c, rho):
    from jaxnet.terms import drag

    return drag.netting_drag(x, uv, l0, d, cd, f * cd, c, rho)


def test_cli_runs_a_femnet_case_on_its_mesh(tmp_path):
    out = tmp_path / "out"
    code = cli.main(["run", str(DATA / "nr_netting.don"), "--mesh", str(DATA / "nr_netting.mdg"), "--out", str(out),
                     "--quiet", "--no-cache"])
    assert code == 0
    result = json.loads((out / "result.json").read_text())
    assert result["n_nodes"] == 446 and result["converged"]
    assert abs(result["femnet"]["drag_netting_N"][0] - 138) <= 0.5
    assert result["femnet_case"]["water_density"] == 1000.0
    assert cli.main(["run", str(DATA / "c2.mdg"), "--mesh", str(DATA / "c2.mdg"), "--out", str(out), "--no-cache"]) == 2


def test_a_case_meshed_finer_keeps_its_net_and_converges_to_the_same_answer():
    # read_don(refine=2): every panel's step halved and every cable's bars doubled; the same netting (the panels'
    # area in twine coordinates, i.e. their number of meshes), its fixings and its catch on a mesh of about 4x
    # the nodes. The cod-end's total drag moves by 0.24 % from FEMNET's mesh density to twice it
    # (measured: 1234.76 N at refine 1, 1237.72 N at refine 2; FEMNET's current code 1243.04 N): mesh
    # convergence, not a different net.
    coarse = femnet.read_don(DATA / "c2.don")
    fine = femnet.read_don(DATA / "c2.don", refine=2)
    assert fine.label.endswith("c2.don, meshed 2 times finer than its file") and coarse.label.endswith("c2.don")
    assert 3.5 < fine.scene.n_nodes / coarse.scene.n_nodes < 4.2
    assert len(fine.scene.bars.ends) == 2 * len(coarse.scene.bars.ends)
    for case in (coarse, fine):  # the triangles' total area in twine coordinates (U, V)
        tri = np.asarray(case.scene.netting.uv)
        area = 0.5 * np.abs((tri[:, 1, 0] - tri[:, 0, 0]) * (tri[:, 2, 1] - tri[:, 0, 1])
                            - (tri[:, 2, 0] - tri[:, 0, 0]) * (tri[:, 1, 1] - tri[:, 0, 1]))
        case.info["twine_area"] = area.sum()
    assert fine.info["twine_area"] == pytest.approx(coarse.info["twine_area"], rel=1e-12)
    assert int(np.asarray(fine.scene.nodes.fixed).sum()) > int(np.asarray(coarse.scene.nodes.fixed).sum())
    forces = []
    for case in (coarse, fine):
        eq = solve(case.scene, case.solver)
        forces.append(femnet.femnet_figures(case.scene, eq, case.info["symmetry_axes"])["total_force_N"][0])
    assert forces[1] / forces[0] - 1.0 == pytest.approx(0.0024, abs=0.0015)


@pytest.mark.parametrize("refine", [0, -1.0, float("nan"), float("inf"), "2", True])
def test_a_bad_refinement_is_refused_naming_the_file(refine):
    with pytest.raises(SceneError, match=r"c2\.don: refine .* must be a number > 0"):
        femnet.read_don(DATA / "c2.don", refine=refine)


def test_cli_refines_a_femnet_case_only_where_jaxnet_meshes_it(tmp_path):
    nodes = {}
    for refine in ("1", "2"):
        out = tmp_path / refine
        assert cli.main(["run", str(DATA / "links_hub.don"), "--refine", refine, "--out", str(out), "--quiet",
                         "--no-cache"]) == 0
        result = json.loads((out / "result.json").read_text())
        assert result["converged"] and result["femnet_case"]["refine"] == float(refine)
        nodes[refine] = result["n_nodes"]
    assert 3.0 < nodes["2"] / nodes["1"] < 4.5
    assert cli.main(["run", str(DATA / "c2.don"), "--mesh", str(DATA / "c2.mdg"), "--refine", "2",
                     "--out", str(tmp_path), "--no-cache"]) == 2
    assert cli.main(["run", "--refine", "2", "--out", str(tmp_path), "--no-cache"]) == 2


# -- links, hexagonal panels, node types (synthetic cases in tests/data/femnet) --------------------------------
#
# links_hub.don: a square of netting (10 x 10 meshes, twines stretched 5 %, square meshes) written as four
# triangular panels around a hub at its centre, joined by five links (the hub: four corners; each outer
# corner: two) whose consecutive corners sew the four diagonals; every outer side is held (node type 1), the
# hub and the diagonals are free. Each panel draws the hub at a different point, off the centre and 3 cm off
# the plane; their mean starts 7 cm from the centre. links_hub_single.don: the same net as one panel.
# links_cable.don: two panels of 10 and 8 meshes across sewn on one border, and a cable (6 bars, meshed
# first) linked to the lower panel's bottom corners from ends drawn 2 cm outside them.
# hexagonal.don: one hexagonal panel (8 x 6 base meshes) hanging from its top side, 0.5 N on every node of
# its bottom side.


def _node_uv(scene):
    """Twine coordinates of every node, from the triangles (one panel's, where panels share a node)."""
    uv = np.zeros((scene.n_nodes, 2))
    tri = np.asarray(scene.netting.vertices)
    uv[tri.ravel()] = np.asarray(scene.netting.uv).reshape(-1, 2)
    return uv


def test_links_make_one_node_and_sew_the_sides_between_them():
    from jaxnet.mesh.panel import mesh_panel

    loaded = femnet.read_don(DATA / "links_hub.don")
    scene, info = loaded.scene, loaded.info
    case = femnet.parse_don(DATA / "links_hub.don")
    # each panel alone: its nodes, and the division of its diagonals (all four have one length in (U, V))
    meshes = [mesh_panel(femnet.twine_coordinates(p.corners[:, 3:5]), p.corners[:, :3], p.material["step"].value,
                         p.material["l0"].value) for p in case.panels]
    d = {len(m.side_nodes[s]) - 1 for m in meshes for s in (1, 2)}
    assert len(d) == 1
    d = d.pop()
    # one node per link: the hub's 4 corners make 1 node (-3), each outer corner's 2 make 1 (-4), and the
    # d - 1 nodes inside each of the 4 sewn diagonals are shared by two panels (-4 (d - 1))
    assert scene.n_nodes == sum(len(m.uv) for m in meshes) - 3 - 4 - 4 * (d - 1)
    tri, panel = np.asarray(scene.netting.vertices), np.asarray(scene.netting.panel)
    nodes = [set(np.unique(tri[panel == k])) for k in range(4)]
    hub = set.intersection(*nodes)
    assert len(hub) == 1
    # a sewn diagonal: d + 1 nodes shared by its two panels, none by the panels across the hub
    assert len(nodes[0] & nodes[1]) == d + 1 and nodes[0] & nodes[2] == hub
    # FEMNET's joined node starts at the mean of the linked corners' start positions (numerotation.c)
    drawn = np.array([p.corners[2, :3] for p in case.panels])
    np.testing.assert_allclose(scene.nodes.position[hub.pop()], drawn.mean(axis=0), atol=1e-12)
    assert info["seams"] == ["panel 1 side 2 = panel 2 side 3", "panel 1 side 3 = panel 4 side 2",
                             "panel 2 side 2 = panel 3 side 3", "panel 3 side 2 = panel 4 side 3"]
    assert ["panel 1 corner 3", "panel 2 corner 3", "panel 3 corner 3", "panel 4 corner 3"] in info["joined"]


def test_linked_panels_reach_the_equilibrium_of_the_one_panel_net():
    # Patch test: the outer sides are held where the affine map of (U, V) puts them and every twine is in
    # traction, so the equilibrium is that affine map whatever the triangles (each element is in equilibrium
    # under a uniform strain) and unique (the energy is strictly convex in the free nodes). The one-panel net
    # starts there; the linked one starts 7 cm away (the hub). The same equilibrium to 1e-9 m: Newton stops at
    # 1e-9 N against stiffnesses of order EA / l0 = 2e4 N/m (axial) and T / l = 1e3 N/m (transverse).
    case = femnet.read_don(DATA / "links_hub_single.don")
    single, solver = case.scene, case.solver
    eq1 = solve(single, solver)
    x1, uv1 = np.asarray(eq1.x), _node_uv(single)
    X1 = np.c_[uv1, np.ones(len(uv1))]
    affine, *_ = np.linalg.lstsq(X1, x1, rcond=None)
    assert np.abs(X1 @ affine - x1).max() < 1e-9
    case = femnet.read_don(DATA / "links_hub.don")
    linked, solver = case.scene, case.solver
    X2 = np.c_[_node_uv(linked), np.ones(linked.n_nodes)]
    assert np.abs(X2 @ affine - np.asarray(linked.nodes.position)).max() > 0.05
    eq2 = solve(linked, solver)
    assert eq2.converged
    np.testing.assert_allclose(np.asarray(eq2.x), X2 @ affine, rtol=0, atol=1e-9)


def test_a_linked_cable_divides_the_side_and_seams_join_different_mesh_counts():
    from jaxnet.mesh.polygon import side_divisions

    loaded = femnet.read_don(DATA / "links_cable.don")
    scene, info = loaded.scene, loaded.info
    case = femnet.parse_don(DATA / "links_cable.don")
    upper, lower = case.panels
    # the cable, meshed first, keeps its 6 bars and the lower panel's bottom side takes them
    assert len(scene.bars.ends) == 6 and info["cables_sewn_along_sides"] == {"cable 1": "panel 2 side 1"}
    tri, panel = np.asarray(scene.netting.vertices), np.asarray(scene.netting.panel)
    lower_nodes = np.unique(tri[panel == 1])
    assert set(np.unique(scene.bars.ends)) <= set(lower_nodes)
    # its ends are joined to the corners, at the mean of their start positions
    start = np.array([case.cables[0].ends[0], lower.corners[0, :3]]).mean(axis=0)
    assert np.min(np.linalg.norm(scene.nodes.position - start, axis=1)) < 1e-12
    # the seam joins 10 meshes to 8: both sides take one division (jaxnet: the larger default; FEMNET: that
    # of the panel meshed first) and each panel keeps its own twine coordinates on the shared nodes
    div = [side_divisions(femnet.twine_coordinates(p.corners[:, 3:5]), p.material["step"].value,
                          p.material["l0"].value) for p in case.panels]
    seam = np.intersect1d(np.unique(tri[panel == 0]), lower_nodes)
    assert div[0][0] != div[1][2] and len(seam) == max(div[0][0], div[1][2]) + 1
    corner = seam[np.argmax(scene.nodes.position[seam, 0])]
    uv = np.asarray(scene.netting.uv)
    at = {k: {tuple(uv[e][list(tri[e]).index(corner)]) for e in np.flatnonzero((panel == k) & (tri == corner).any(axis=1))}
          for k in (0, 1)}
    assert at == {0: {(10.0, -10.0)}, 1: {(13.0, -3.0)}}  # (U, V) = (10, 0) and (8, 5): u = U + V, v = V - U


def _edit(tmp_path, case, edits, name=None):
    text = (DATA / f"{case}.don").read_text()
    for old, new in edits:
        assert text.count(old) >= 1, old
        text = text.replace(old, new, 1)
    path = tmp_path / f"{name or case}.don"
    path.write_text(text)
    return path, text


_SECOND_CABLE = """
Cable: 7
Extremities no x y z type:
1  0.000000  -1.350000  -1.000000  1
2  0.000000  -0.735000  -1.000000  2
Kt: 50000.000000  Kc: 0.000000  L: 0.817500  Vm: 1140.000000  D:0.005000  Cd: 1.200000  f: 0.080000  Nb: 3  Ty: 2
"""


@pytest.mark.parametrize("case, edits, needle, words", [
    ("links_cable", [("pa: 2\tnd: 4", "pa: 3\tnd: 4")], "pa: 3\tnd: 4", "there is no panel 3"),
    ("links_cable", [("pa: 2\tnd: 4", "pa: 2\tnd: 5")], "pa: 2\tnd: 5", "panel 2 has no corner 5"),
    ("links_cable", [("el: 1\tnd: 1", "co: 1\tnd: 1")], "co: 1\tnd: 1", "sliding cable"),
    ("links_cable", [("nb_pt :2\tel: 1\tnd: 1\tpa: 2\tnd: 1", "nb_pt :2\tel: 1\tnd: 1\tpa: 1\tnd: 1")],
     "el: 1\tnd: 1\tpa: 1\tnd: 1", "already in the link of line"),
    ("links_cable", [("pa: 1\tnd: 1\tpa: 2\tnd: 4", "pa: 1\tnd: 1\tpa: 1\tnd: 3")],
     "3    0.707107    0.000000    0.000000", "joined to itself"),
    ("nr_netting", [("Cables number: 6", "Cables number: 7"), ("\nSliding cables", _SECOND_CABLE + "\nSliding cables"),
                    ("el:     4 el:     6", "el:     4 el:     6 el:     7")],
     "1  0.000000  -1.350000  -1.000000  1\n2  0.000000  -0.735000  -1.000000  2\nKt: 50000.000000  Kc: 0.000000  "
     "L: 0.817500  Vm: 1140.000000  D:0.005000  Cd: 1.200000  f: 0.080000  Nb: 3", "threads it on that cable's nodes"),
])
def test_link_errors_name_the_line(tmp_path, case, edits, needle, words):
    path, text = _edit(tmp_path, case, edits)
    with pytest.raises(SceneError) as err:
        femnet.read_don(path)
    message = str(err.value)
    assert words in message and f"{case}.don:{_line_of(text, needle)}:" in message, message


def test_a_hexagonal_panel_keeps_femnet_coordinates_counts_its_twines_and_hangs_in_balance():
    case = femnet.read_don(DATA / "hexagonal.don")
    scene, solver, info = case.scene, case.solver, case.info
    hexa = scene.hexagonal
    assert scene.netting is None and hexa is not None
    # FEMNET's hexagonal (U, V) count base meshes as jaxnet's do (etirement_hexa.c: the knot's neighbours at
    # 0, (U + V)/2 and V, as jaxnet.terms.hexagonal): the corners keep them, not (U + V, V - U)
    tri, uv = np.asarray(hexa.vertices), np.asarray(hexa.uv)
    corner = int(np.argmin(np.linalg.norm(scene.nodes.position - [0.504, 0.0, 0.0], axis=1)))
    assert {tuple(uv[e][list(tri[e]).index(corner)]) for e in np.flatnonzero((tri == corner).any(axis=1))} == {(8.0, 6.0)}
    # the contour holds 8 x 6 = 48 base meshes: sum |d|/2 over the triangles, |d| twines of each family each
    d = np.asarray(jax.vmap(geometry.twine_determinant)(hexa.uv))
    np.testing.assert_allclose(np.abs(d).sum(), 2 * 48.0, rtol=1e-12)
    np.testing.assert_array_equal(hexa.l0[0], [0.02, 0.02, 0.024])
    np.testing.assert_array_equal(hexa.ea_traction[0], [1000.0, 1000.0, 1200.0])
    # one diameter with the weight of FEMNET's three (jaxnet's hexagonal netting has no drag)
    dl = 0.01**2 * 0.02 + 0.012**2 * 0.02 + 0.01**2 * 0.024
    np.testing.assert_allclose(hexa.diameter[0] ** 2 * 0.064, dl, rtol=1e-12)
    eq = solve(scene, solver)
    assert eq.converged
    pulled = int(np.sum(np.asarray(scene.nodes.force)[:, 2] == -0.5))
    env = scene.environment
    weight = 96.0 * np.pi / 4 * dl * (1140.0 - env.water_density) * env.gravity
    np.testing.assert_allclose(eq.reaction(scene).sum(axis=0), [0, 0, weight + 0.5 * pulled], atol=scene.n_nodes * 1e-6)
    assert pulled >= 3 and info["hexagonal_twine_diameter_m"]["hexagonal panel 1"] == pytest.approx(hexa.diameter[0])


@pytest.mark.parametrize("edits, needle, words", [
    ([("Current speed (m/s):                    0.000000", "Current speed (m/s):                    0.5")],
     "Current speed", "no drag model for hexagonal netting"),
    # FEMNET skips the line after the last corner of a hexagonal panel: a field there would be lost to it
    ([("                                        l            m            n\n", "")],
     "Traction stiffness l m n", "FEMNET skips the line after the last corner"),
    ([("Meshing type:				2", "Meshing type:				3")], "Meshing type", "twines as bar elements"),
])
def test_hexagonal_errors_name_the_line(tmp_path, edits, needle, words):
    path, text = _edit(tmp_path, "hexagonal", edits)
    with pytest.raises(SceneError) as err:
        femnet.read_don(path)
    message = str(err.value)
    assert words in message and f"hexagonal.don:{_line_of(text, needle)}:" in message, message


def test_added_mass_is_recorded_and_limits_without_sense_are_no_limits(tmp_path):
    plain = femnet.read_don(DATA / "nr_netting.don")
    info = plain.info
    assert info["added_mass"] == {1: [0.0, 0.0, 0.0], 2: [0.0, 0.0, 0.0]}
    # type 2 (every free node) with an added mass (dynamics only) and a limit whose sense is 0 (none)
    block = ("Added mass X,Y,Z (kg):        0.000000  0.000000  0.000000\nLength X,Y,Z (m):        0.000000  0.000000  "
             "0.000000\nDrag coefficient X,Y,Z:        1.200000  1.200000  1.200000\nExternal forces X,Y,Z (N):    "
             "0.000000  0.000000  0.000000\nDisplacement X,Y,Z:        0 0 0\nLimits X,Y,Z (m):        0.000000  "
             "0.000000  0.000000")
    edited = block.replace("Added mass X,Y,Z (kg):        0.000000  0.000000  0.000000",
                           "Added mass X,Y,Z (kg):        1.500000  2.000000  0.250000").replace(
                           "Limits X,Y,Z (m):        0.000000  0.000000  0.000000",
                           "Limits X,Y,Z (m):        0.000000  0.000000  -2.000000")
    path, _ = _edit(tmp_path, "nr_netting", [(block, edited)])
    edited = femnet.read_don(path)
    info = edited.info
    assert info["added_mass"] == {1: [0.0, 0.0, 0.0], 2: [1.5, 2.0, 0.25]}
    a, b = plain.scene, edited.scene
    for field in ("position", "fixed", "mass", "volume", "force"):
        np.testing.assert_array_equal(getattr(a.nodes, field), getattr(b.nodes, field))
    json.dumps(info)
    # the nodes carry it for dynamics: type 2's nodes (the free ones) the whole of it, or the half on a symmetry
    # plane, as their mass would be (FEMNET's masses are the whole structure's)
    assert a.nodes.added_mass is None
    added = np.asarray(b.nodes.added_mass)
    free = ~np.asarray(b.nodes.fixed).all(axis=1)
    share = added[:, 0] / 1.5
    assert set(np.round(share[free], 12)) <= {0.5, 1.0} and (share[free] == 1.0).sum() > 0.5 * free.sum()
    np.testing.assert_allclose(added, share[:, None] * [1.5, 2.0, 0.25], rtol=1e-15)
    # and so does FEMNET's own mesh read with the same .don
    on_mdg = femnet.read_mdg(DATA / "nr_netting.mdg", path).scene
    assert np.asarray(on_mdg.nodes.added_mass)[:, 1].max() == 2.0


def test_meshing_order_shorthand(tmp_path):
    # FEMNET's 'a...' meshes the cables first (the cod line's 7 bars divide the side), 'b...' the panels first
    # (the cable takes the side's division, 18 segments of jaxnet's mesher)
    for word, bars in (("all", 7), ("bll", 18)):
        path, _ = _edit(tmp_path, "c2", [("Meshing order:\nel:1    pa:     1  ", f"Meshing order: {word}")])
        assert len(femnet.read_don(path).scene.bars.ends) == bars


def test_dynamic_settings_and_waves_are_read(tmp_path):
    """A FEMNET case with an end time and waves: the time settings go to info["dynamic"], the waves to the
    environment (linear waves with FEMNET's period, height and heading); a zero record step is an error."""
    lines = (DATA / "nr_netting.don").read_text().splitlines()

    def edit(label, value):
        k = next(i for i, line in enumerate(lines) if line.startswith(label))
        lines[k] = lines[k].rsplit(":", 1)[0] + ":\t" + value

    edit("Dynamic: End time of record", "30.0")
    edit("Wave height", "1.5")
    edit("Wave direction", "90.0")
    path = tmp_path / "waves.don"
    path.write_text("\n".join(lines) + "\n")
    case = femnet.read_don(path)
    net, info = case.net, case.info
    assert info["dynamic"] == {"time_step_s": 0.1, "record_every_s": 0.2, "record_start_s": 0.0, "end_time_s": 30.0}
    waves = net.environment.waves
    assert float(waves.height) == 1.5 and float(waves.period) == 10.0
    np.testing.assert_allclose(np.asarray(waves.direction), [0.0, 1.0, 0.0], atol=1e-15)
    # deep-water dispersion at T = 10 s where FEMNET's depth is 0 or large: L = g T² / (2π)
    if not np.isfinite(float(waves.depth)):
        assert float(waves.wavelength) == pytest.approx(9.81 * 100 / (2 * np.pi), rel=1e-12)
    assert type(waves).__name__ == "Airy"  # FEMNET's default theory
    # 'input wave_model 2' and 3: Stokes second and third order, the same parameters; 4 is refused naming its line
    for model, theory in ((2, "Stokes2"), (3, "Stokes3")):
        path.write_text("\n".join(lines) + f"\ninput wave_model {model}\n")
        stokes = femnet.read_don(path).scene.environment.waves
        assert type(stokes).__name__ == theory and float(stokes.height) == 1.5 and float(stokes.period) == 10.0
    path.write_text("\n".join(lines) + "\ninput wave_model 4\n")
    with pytest.raises(SceneError, match=rf"waves.don:{len(lines) + 1}: 'input wave_model': the model must be 1"):
        femnet.read_don(path)
    edit("Wave period", "0.0")
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(SceneError, match=r"waves.don:\d+: wave period 0.0 s: waves of height 1.5 m need a period > 0"):
        femnet.read_don(path)
    edit("Wave period", "10.0")
    edit("Dynamic: Record time step", "0.0")
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(SceneError, match=r"waves.don:\d+: dynamic record time step 0.0 s"):
        femnet.read_don(path)


def test_towing_speed_tables_become_prescribed_motions(tmp_path):
    """FEMNET's ``input speed_type_node2 TYPE K`` and its table (0simple/a1b: type 1 towed at -0.6 m/s along x,
    reached linearly from 0 s to 10 s, to 41 s) are the nodes of that type moved by a SpeedTable; a type that does
    not hold its nodes on every axis is refused at the command's line."""
    corpus = pathlib.Path(__file__).resolve().parents[1] / "data" / "femnet-corpus" / "0simple"  # FEMNET's, its licence there
    text = (corpus / "a1b.don").read_text()
    case = femnet.read_don(corpus / "a1b.don")
    assert "speed_type_node2" not in " ".join(case.info["dynamic_only"])
    (motion,) = case.time.loading.motions
    fixed = np.asarray(case.scene.nodes.fixed).all(axis=1)
    assert len(motion.nodes) >= 1 and fixed[np.asarray(motion.nodes)].all()
    np.testing.assert_allclose(np.asarray(motion.motion.times), [0.0, 10.0, 41.0])
    np.testing.assert_allclose(np.asarray(motion.motion.velocity(25.0)), [-0.6, 0.0, 0.0], rtol=1e-15)
    np.testing.assert_allclose(np.asarray(motion.motion(41.0)), [-0.6 * (41.0 - 5.0), 0.0, 0.0], rtol=1e-14)
    line = text[: text.index("input speed_type_node2")].count("\n") + 1
    path = tmp_path / "a1b.don"
    path.write_text(text.replace("input speed_type_node2  1 3", "input speed_type_node2  2 3"))
    with pytest.raises(SceneError, match=rf"a1b.don:{line}: 'input speed_type_node2': the nodes of type 2 are towed"):
        femnet.read_don(path)


def test_the_docs_command_table_names_every_input_command_of_the_grammar():
    """docs/femnet.md's table of `input` commands says what jaxnet does with each: it names every command the
    reader knows, and no other."""
    import re

    from jaxnet.io.femnet import grammar

    text = (pathlib.Path(__file__).resolve().parents[2] / "docs" / "femnet.md").read_text()
    section = text.split("## The `.don` file's `input` commands", 1)[1].split("\n## ", 1)[0]
    rows = [line.split("|")[1] for line in section.splitlines() if line.startswith("| `")]
    named = set()
    for cell in rows:
        for name in re.findall(r"`([^`]+)`", cell):
            if "{" in name:  # add_{x,y,z}_{ele,pan}
                named |= {f"add_{a}_{p}" for a in "xyz" for p in ("ele", "pan")}
            else:
                named.add(name)
    assert named == set(grammar.INPUTS)


def test_a_distance_from_a_node_to_itself_is_a_heading():
    """FEMNET's cases print a title as a distance from global node 1 to itself ("PELAGIC TRAWL", 0 m, no decimals;
    the manual: "is zero m because the two nodes are the same"): reported as a heading, with no value or unit, not
    as a measurement of 0 m; a distance between two nodes stays a figure (m), in the file's order."""
    import dataclasses
    from types import SimpleNamespace

    don = femnet.parse_don(pathlib.Path(__file__).parents[1] / "data" / "femnet-corpus" / "1pelagic_trawl" / "s2.don")
    outputs = [dataclasses.asdict(t) for t in don.text_outputs]
    assert outputs[0]["kind"] == "distances" and outputs[0]["values"] == {"node_1": 1, "node_2": 1}
    n = 60   # global node k is node k - 1 here, each at (k, 2k, 0): boat 48 to door 49 is sqrt(5) m
    x = np.stack([np.arange(n), 2.0 * np.arange(n), np.zeros(n)], axis=1)
    eq = SimpleNamespace(x=x, force=np.zeros_like(x))
    printed = femnet.text_output_figures(SimpleNamespace(bars=None), eq,
                                         {"text_outputs": outputs, "global_nodes": list(range(n))})
    assert len(printed) == len(outputs)
    assert printed[0] == {"kind": "heading", "comment": "PELAGIC TRAWL", "value": None, "unit": None}
    assert printed[1] == {"kind": "distances", "comment": "Boat to door distance", "value": pytest.approx(np.sqrt(5.0)),
                          "unit": "m"}
    assert [p["kind"] for p in printed].count("heading") == 1
