"""result.json explains itself (docs/result.md): a quarter model's figures for the modelled part and for the whole
net, ``load_N`` the non-hydrodynamic groups at the equilibrium (a free surface's weight too) and ``water_N`` the
hydrodynamic ones so that the balance closes, the weight and buoyancy by what carries it, the inputs, version and
date recorded, the worst node with its position, a line on each main figure, and ``jaxnet run`` writing and
printing them."""

import dataclasses
import datetime
import json
import re

import equinox as eqx
import numpy as np
import pytest

import jaxnet as jn
from jaxnet import cli, figures
from jaxnet.scene import mirror_copies
from jaxnet.scenes import codend, fish_cage
from jaxnet.terms import term


def hydrodynamic_groups():
    """The groups of the water's forces (drag, catch pressure): the rest of the balance besides reaction and load."""
    return set(term.groups(lambda group, t: group.hydrodynamic))


@pytest.fixture(scope="module")
def quarter():
    """The small quarter cod-end holding 2 litres (which it can: its front is inside the net), solved with a
    tolerance of its own (tight: the balance below is checked to the residual), and its summary."""
    case = codend(meshes_around=8, meshes_along=4, catch_m3=0.002)
    solver = dataclasses.replace(case.solver, tol=1e-6)
    eq = jn.solve_static(case.scene, solver)
    return case, eq, figures.summary(case.scene, eq, case=case, solver=solver)


@pytest.fixture(scope="module")
def cage():
    """A coarse fish cage with a free surface (its weight and buoyancy an energy of the positions), one node pushed
    up by 10 N (an external force), and its summary."""
    case = fish_cage(step=2.0, l0=0.2)
    scene = case.scene
    pushed = np.asarray(scene.nodes.force).copy()
    free = int(np.flatnonzero(~np.asarray(scene.nodes.fixed).any(axis=1))[0])
    pushed[free] = [0.0, 0.0, 10.0]
    scene = eqx.tree_at(lambda s: s.nodes.force, scene, pushed)
    # solved far below the library's threshold: the balance below is checked to what the solve leaves
    eq = jn.solve_static(scene, case.solver, tol=1e-6)
    return scene, eq, figures.summary(scene, eq, case=case)


def test_a_quarter_model_gives_its_part_and_the_whole_net(quarter):
    case, eq, result = quarter
    scene = case.scene
    assert result["modelled_part"] == "a quarter of the net (2 symmetry planes: y = 0 m, z = 0 m)"
    whole = result["whole_net"]
    assert whole["copies"] == mirror_copies(scene) == 4
    # the catch's drag (p × its front's section) of the whole cod-end is its 4 quarters' catch pressure along x
    catch, group = result["catch"], result["forces_N"]["catch_N"]
    assert catch["holds_the_volume"] and catch["volume_whole_net_m3"] == pytest.approx(0.002, rel=1e-9)
    assert catch["volume_m3"] == pytest.approx(0.0005, rel=1e-9)
    assert catch["drag_whole_net_N"] == pytest.approx(4 * group[0], rel=1e-9)
    assert catch["drag_N"] == pytest.approx(group[0], rel=1e-9)
    assert whole["forces_N"]["catch_N"][0] == pytest.approx(catch["drag_whole_net_N"], rel=1e-9)
    # the fixings of the whole net pull it straight back: the symmetry planes' holding forces cancel
    reaction = np.asarray(result["reaction_N"])
    assert abs(reaction[1]) > 1.0 and abs(reaction[2]) > 1.0  # the quarter's planes hold it
    assert whole["reaction_N"][0] == pytest.approx(4 * reaction[0], rel=1e-12) and whole["reaction_N"][0] < 0
    assert whole["reaction_N"][1:] == [0.0, 0.0]
    # the whole net in balance: its fixings hold what the water puts on it (no weight: a neutral cod-end), to
    # what the solve leaves on the free coordinates of the 4 copies
    drag = np.sum([whole["forces_N"][g] for g in hydrodynamic_groups()], axis=0)
    total = np.asarray(whole["reaction_N"]) + np.asarray(whole["load_N"]) + drag
    assert np.abs(total).max() <= 4 * scene.n_dof * result["residual_N"] < 1e-5 * np.abs(drag).max()
    # the whole net spans both sides of each plane
    low, high = np.asarray(whole["bounding_box_m"])
    np.testing.assert_allclose(low[1:], -high[1:], rtol=1e-12)
    assert result["bounding_box_m"][0][1:] == [0.0, 0.0]


def test_load_is_the_non_hydrodynamic_groups_and_closes_the_balance(cage):
    scene, eq, result = cage
    forces = result["forces_N"]
    hydro = hydrodynamic_groups()
    load = np.asarray(result["load_N"])
    # with a free surface, weight and buoyancy are not constant loads: the constant ones are the 10 N push only
    np.testing.assert_allclose(figures.total_load(scene), [0.0, 0.0, 10.0], atol=1e-12)
    assert forces["weight_and_buoyancy_N"][2] < -10.0 and forces["external_N"] == [0.0, 0.0, 10.0]
    np.testing.assert_allclose(load, np.sum([forces[g] for g in forces if g not in hydro], axis=0), rtol=1e-12)
    np.testing.assert_allclose(load, np.add(forces["weight_and_buoyancy_N"], forces["external_N"]), rtol=1e-12)
    np.testing.assert_allclose(result["water_N"], np.sum([forces[g] for g in hydro], axis=0), rtol=1e-12)
    # the balance, to what the solve leaves on the free coordinates
    total = np.asarray(result["reaction_N"]) + load + np.sum([forces[g] for g in hydro], axis=0)
    largest = max(np.abs(result["reaction_N"]).max(), np.abs(load).max())
    assert np.abs(total).max() <= scene.n_dof * result["residual_N"] < 1e-4 * largest
    # a whole net: its figures are the top level's, not repeated in a whole_net
    assert result["modelled_part"] == "the whole net" and "whole_net" not in result
    assert result["enclosed_volume_m3"] > 0


def test_the_inputs_version_and_date_are_recorded(quarter, cage):
    case, eq, result = quarter
    inputs = result["inputs"]
    assert inputs["source"] is None and inputs["label"] == case.label
    environment = inputs["environment"]
    assert environment["current"]["speed_m_s"] == 1.5 and environment["current"]["direction"] == [1.0, 0.0, 0.0]
    assert environment["surface_level_m"] is None and environment["waves"] is None
    assert environment["water_density_kg_m3"] == float(case.scene.environment.water_density)
    assert inputs["catch"]["volume_whole_net_m3"] == 0.002 and inputs["catch"]["symmetry"] == 4.0
    assert inputs["symmetry_planes"] == [{"axis": "y", "position_m": 0.0}, {"axis": "z", "position_m": 0.0}]
    # the solver given, not the case's: its tolerance, and an unlimited step written as null
    assert inputs["solver"]["tol"] == 1e-6 and case.solver.tol != 1e-6
    assert inputs["solver"]["max_step"] is None and inputs["solver"]["max_iter"] == case.solver.max_iter
    assert result["jaxnet_version"] == jn.__version__
    date = datetime.datetime.fromisoformat(result["date"])
    assert date.utcoffset() == datetime.timedelta(0)
    assert abs(datetime.datetime.now(datetime.timezone.utc) - date) < datetime.timedelta(hours=1)
    json.dumps(result, allow_nan=False)  # plain JSON: no NaN, no infinity
    # the cage's surface and its lack of a catch, and the case's own solver where none is given
    _, _, cage_result = cage
    assert cage_result["inputs"]["environment"]["surface_level_m"] == 0.0
    assert cage_result["inputs"]["catch"] is None and cage_result["inputs"]["symmetry_planes"] == []
    assert cage_result["inputs"]["solver"]["tol"] == jn.Newton().tol


def test_the_worst_node_is_named_with_its_position(quarter, cage):
    for scene, eq, result in (quarter[0].scene, *quarter[1:]), cage:
        worst = result["worst_node"]
        assert worst["node"] == int(eq.worst_node)
        assert worst["position_m"] == np.asarray(eq.x)[worst["node"]].tolist()
        assert 0 <= worst["node"] < scene.n_nodes


def test_a_failed_solve_writes_null_not_nan(quarter):
    """A solve stopped by non-finite forces has a NaN residual: result.json says null, and stays JSON."""
    case, eq, _ = quarter
    x = np.asarray(eq.x).copy()
    x[0] = np.nan
    broken = dataclasses.replace(eq, x=x, residual_N=np.float64(np.nan))
    result = figures.summary(case.scene, broken)
    assert result["residual_N"] is None and result["bounding_box_m"][0][0] is None
    json.dumps(result, allow_nan=False)


def test_cli_writes_and_prints_the_whole_net(tmp_path, capsys):
    """`jaxnet run --scene codend` (the built-in quarter cod-end, made as small as :func:`quarter`'s: the built-in's
    800 nodes take 20-40 s): result.json with its inputs (the command line's solver options), its whole net, the
    catch's drag both ways; the printout gives the whole net's figures."""
    out = tmp_path / "codend"
    small = ["--set", "meshes_around=8", "--set", "meshes_along=4", "--set", "catch_m3=0.002"]
    assert cli.main(["run", "--scene", "codend", *small, "--out", str(out), "--quiet", "--no-cache",
                     "--max-iter", "300"]) == 0
    printed = capsys.readouterr().out
    result = json.loads((out / "result.json").read_text())
    for key in ("jaxnet_version", "date", "inputs", "modelled_part", "whole_net", "worst_node", "reaction_N",
                "load_N", "forces_N", "catch"):
        assert key in result
    assert result["inputs"]["source"] == "built-in scene 'codend'" and "cod-end" in result["inputs"]["label"]
    assert result["inputs"]["solver"]["max_iter"] == 300 and result["inputs"]["solver"]["verbose"] is False
    whole, catch = result["whole_net"], result["catch"]
    assert whole["copies"] == 4 and catch["volume_whole_net_m3"] == pytest.approx(0.002, rel=1e-6)
    assert catch["drag_whole_net_N"] == pytest.approx(4 * result["forces_N"]["catch_N"][0], rel=1e-9)
    assert f"whole net (4 mirrored copies): reaction [{whole['reaction_N'][0]:.4g}, 0, 0] N" in printed
    assert f"catch drag {catch['drag_whole_net_N']:.4g} N" in printed
    assert "max bar tension" in printed and "(the model: a quarter of the net" in printed


def test_cli_of_a_scene_file_names_it_and_prints_no_bar_tension_without_bars(tmp_path, capsys):
    """A weightless wall pulled down by 2 N, from a scene file: result.json names the file; the printout has no
    bars' tension (it has none), no "-0", and no whole net (the wall is whole)."""
    doc = {
        "environment": {"gravity": 0.0},
        "twines": {"pa": {"l0": 0.02, "ea": 1000.0, "diameter": 0.001}},
        "panels": [{"name": "wall", "step": 0.1, "twine": "pa",
                    "corners": [[0, 0, 0, 0, 0], [0.5, 0, 0, 10, -10], [0.5, 0, 0.5, 20, 0], [0, 0, 0.5, 10, 10]]}],
        "fix": [{"at": {"panel": "wall", "side": k}} for k in (1, 2, 3)],
        "attach": [{"at": {"panel": "wall", "side": 0}, "force": [0, 0, -2.0]}],
    }
    path = tmp_path / "wall.json"
    path.write_text(json.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--no-cache", "--tol", "5e-4"]) == 0
    printed = capsys.readouterr().out
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    assert result["inputs"]["source"] == str(path) and result["inputs"]["solver"]["tol"] == 5e-4
    assert result["inputs"]["environment"]["gravity_m_s2"] == 0.0
    np.testing.assert_allclose(result["load_N"], [0.0, 0.0, -2.0], rtol=1e-12, atol=1e-15)
    assert result["n_bars"] == 0
    assert "max twine tension" in printed and "max bar tension" not in printed and "whole net" not in printed
    # no figure printed as "-0" (the files' paths, under a temporary folder such as pytest-0, left out)
    figures_printed = printed.replace(str(tmp_path), "DIR")
    assert not re.search(r"(?<![\w.])-0(?![.\de])", figures_printed), printed


def test_weight_and_buoyancy_are_split_by_what_carries_them(cage):
    """The cage's weight and buoyancy by carrier: the netting (its twines' immersed weight, which the free surface
    leaves below it), each collar pipe (buoyant: it floats, its share of the surface energy), the sinkers (20 kg of
    lead at the foot of each of the 8 seams, immersed: their weight less the water they displace); the carriers add
    up to the group, and each figure is what its own term gives."""
    scene, eq, result = cage
    carriers = result["weight_and_buoyancy_by_carrier_N"]
    names = list(carriers)
    assert names[0] == "netting" and names[-1] == "sinkers" and "floats" not in names
    assert [n for n in names if n.startswith("collar")] == [f"collar {k}" for k in range(8)]
    np.testing.assert_allclose(np.sum(list(carriers.values()), axis=0), result["forces_N"]["weight_and_buoyancy_N"],
                               rtol=1e-10, atol=1e-9)
    env = scene.environment
    lead = np.asarray(scene.nodes.mass) - float(env.water_density) * np.asarray(scene.nodes.volume)
    sinkers = -float(env.gravity) * lead[lead > 0].sum()
    assert sinkers < 0
    assert lead[lead > 0].sum() == pytest.approx(8 * 20.0 * (1 - float(env.water_density) / 11340.0), rel=1e-12)
    np.testing.assert_allclose(carriers["sinkers"], [0.0, 0.0, sinkers], rtol=1e-12, atol=1e-12)
    assert all(carriers[f"collar {k}"][2] > 0 for k in range(8))   # the collar floats
    assert carriers["netting"][2] < 0                                # polyamide is heavier than water


def test_every_figure_is_explained_and_a_built_in_is_named(tmp_path):
    """result.json's ``about`` has a line for each main figure it holds (the load and the water's forces among them:
    the balance), and the source of a built-in scene names it."""
    out = tmp_path / "panel"
    assert cli.main(["run", "--scene", "hanging", "--set", "meshes=8", "--set", "step=0.05", "--out", str(out),
                     "--quiet", "--no-cache", "--no-pictures"]) == 0
    result = json.loads((out / "result.json").read_text())
    assert result["inputs"]["source"] == "built-in scene 'hanging'"
    about = result["about"]
    for key in ("reaction_N", "load_N", "water_N", "forces_N", "weight_and_buoyancy_by_carrier_N", "residual_N"):
        assert key in about and len(about[key]) > 20
    assert "whole_net" not in about and "whole_net" not in result
    assert "reaction_N + load_N + water_N = 0" in about["load_N"]
    balance = np.add(np.add(result["reaction_N"], result["load_N"]), result["water_N"])
    assert np.abs(balance).max() <= result["n_dof"] * result["residual_N"]
