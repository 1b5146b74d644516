"""`jaxnet run`: the default scene and a scene file, with result.json, VTK and PNG written."""

import json

import meshio
import numpy as np

from jaxnet import cli


def test_default_scene_is_a_cage_in_current(tmp_path, capsys):
    assert cli.main(["run", "--out", str(tmp_path)]) == 0
    printed = capsys.readouterr().out
    assert "newton" in printed and "converged in" in printed and "cage" in printed
    result = json.loads((tmp_path / "result.json").read_text())
    for key in ("converged", "iterations", "residual_N", "n_nodes", "n_elements", "n_dof", "reaction_N", "wall_s",
                "compile_s", "forces_N", "enclosed_volume_m3"):
        assert key in result
    assert result["converged"] and result["residual_N"] <= 1e-3
    forces = result["forces_N"]
    # balance of the whole net: the moorings hold what drag, weight and buoyancy put on it
    total = np.sum([forces[k] for k in forces], axis=0) + np.asarray(result["reaction_N"])
    np.testing.assert_allclose(total, 0.0, atol=result["n_nodes"] * 1e-3)
    assert forces["drag_netting_N"][0] > 0 and forces["drag_cables_N"][0] > 0  # the current flows along +x
    # the cage keeps part of its 8-sided start volume (8 · ½ R² sin 45° · depth)
    start = 8 * 0.5 * 5.0**2 * np.sin(np.pi / 4) * 5.0
    assert 0.3 * start < result["enclosed_volume_m3"] < start
    mesh = meshio.read(tmp_path / "net.vtu")
    assert len(mesh.points) == result["n_nodes"]
    tu, tv = mesh.cell_data["twine_tension_U_N"][0], mesh.cell_data["twine_tension_V_N"][0]
    assert len(tu) == result["n_triangles"]
    np.testing.assert_allclose(max(tu.max(), tv.max()), result["max_twine_tension_N"], rtol=1e-12)
    assert (tmp_path / "net.png").stat().st_size > 10_000


def test_hanging_scene_reaction_carries_the_weight(tmp_path):
    assert cli.main(["run", "--scene", "hanging", "--out", str(tmp_path), "--quiet"]) == 0
    result = json.loads((tmp_path / "result.json").read_text())
    # the fixings carry the whole immersed weight (within the residual left on the free nodes)
    assert abs(result["reaction_N"][2] + result["load_N"][2]) <= result["n_nodes"] * 1e-3
    assert result["load_N"][2] < 0
    np.testing.assert_allclose(result["forces_N"]["weight_and_buoyancy_N"], result["load_N"], rtol=1e-12)


def test_scene_file_and_bad_scene_file(tmp_path, capsys):
    w = 0.5
    doc = {
        "environment": {"gravity": 0.0},
        "twines": {"pa": {"l0": 0.02, "ea": 1000.0, "diameter": 0.001}},
        "panels": [{"name": "wall", "step": 0.1, "twine": "pa",
                    "corners": [[0, 0, 0, 0, 0], [w, 0, 0, 10, -10], [w, 0, w, 20, 0], [0, 0, w, 10, 10]]}],
        "fix": [{"at": {"panel": "wall", "side": 2}}, {"at": {"panel": "wall", "side": 1}}, {"at": {"panel": "wall", "side": 3}}],
        "attach": [{"at": {"panel": "wall", "side": 0}, "force": [0, 0, -2.0]}],
    }
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    np.testing.assert_allclose(result["reaction_N"], [0, 0, 2.0], atol=result["n_nodes"] * 1e-3)
    doc["panels"][0]["stepp"] = 1
    path.write_text(json.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "bad")]) == 2
    assert "unknown key(s) ['stepp']" in capsys.readouterr().err
