"""ParaView files (jaxnet.io.vtk): read back with VTK's own reader, their numbers checked against the solve."""

import importlib
import re

import numpy as np
import pytest

import jaxnet
from jaxnet import figures
from jaxnet.io import timeseries as ts
from jaxnet.io import vtk as jvtk
from jaxnet.scene import mirror_signs, mirrored
from jaxnet.scenes.cage import fish_cage
from jaxnet.scenes.panel import hanging_panel
from jaxnet.scenes.textbook import hexagonal_hanging_panel

vtk = pytest.importorskip("vtk")
from vtk.util.numpy_support import vtk_to_numpy  # noqa: E402

OPENING = 0.1  # the cod-end's half opening angle at the start (rad)


def read(path):
    """(points, point data, cell data, field data, cell connectivity) of a .vtu, by VTK's XML reader."""
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()

    def arrays(data):
        return {data.GetArrayName(k): vtk_to_numpy(data.GetAbstractArray(k)) for k in range(data.GetNumberOfArrays())}

    cells = [[grid.GetCell(c).GetPointId(k) for k in range(grid.GetCell(c).GetNumberOfPoints())]
             for c in range(grid.GetNumberOfCells())]
    return (vtk_to_numpy(grid.GetPoints().GetData()), arrays(grid.GetPointData()), arrays(grid.GetCellData()),
            arrays(grid.GetFieldData()), cells)


def legend(field, kind):
    """{id: name} of the field arrays ``KIND ID: NAME`` holding ID."""
    out = {}
    for name, values in field.items():
        m = re.fullmatch(rf"{kind} (\d+): (.*)", name)
        if m:
            assert values.tolist() == [int(m.group(1))]
            out[int(m.group(1))] = m.group(2)
    return out


@pytest.fixture(scope="module")
def codend(tmp_path_factory):
    """The quarter cod-end solved, its files written: (scene, equilibrium, paths)."""
    case = importlib.import_module("jaxnet.scenes.codend").codend(meshes_around=8, meshes_along=4, opening=OPENING)
    eq = jaxnet.solve_static(case.scene, case.solver)
    assert eq.converged
    paths = jvtk.write_vtu(tmp_path_factory.mktemp("codend") / "net.vtu", case.scene, eq.x)
    return case.scene, eq, paths


def test_points_are_the_equilibrium_and_the_displacement_is_from_the_drawn_shape(codend):
    scene, eq, paths = codend
    points, point, _, _, _ = read(paths[0])
    x, start = np.asarray(eq.x), np.asarray(scene.nodes.position)
    np.testing.assert_array_equal(points, x)
    np.testing.assert_array_equal(point["displacement_m"], x - start)
    assert np.abs(point["displacement_m"]).max() > 0.01  # the catch bulges the cod-end
    held = np.asarray(scene.nodes.fixed)
    for axis, name in enumerate("xyz"):
        assert point[f"fixed_{name}"].dtype == np.int8
        np.testing.assert_array_equal(point[f"fixed_{name}"], held[:, axis])
    np.testing.assert_array_equal(point["mass_kg"], np.asarray(scene.nodes.mass))


def test_reactions_are_the_summary_s_and_balance_the_groups_at_equilibrium(codend):
    scene, eq, paths = codend
    _, point, _, _, _ = read(paths[0])
    summary = figures.summary(scene, eq)
    reaction = point["reaction_N"]
    np.testing.assert_allclose(reaction.sum(axis=0), summary["reaction_N"], rtol=1e-9, atol=1e-9)
    assert np.abs(summary["reaction_N"]).max() > 1.0  # the catch pulls on the fixings
    assert np.all(reaction[~np.asarray(scene.nodes.fixed)] == 0.0)
    groups = list(summary["forces_N"])
    assert set(groups) <= set(point)
    for group in groups:  # each group's nodal forces add up to result.json's total of it
        np.testing.assert_allclose(point[group].sum(axis=0), summary["forces_N"][group], rtol=1e-9, atol=1e-9)
    total = sum(point[group].sum(axis=0) for group in groups) + reaction.sum(axis=0)
    np.testing.assert_allclose(total, 0.0, atol=scene.n_nodes * 1e-6)
    assert np.abs(point["catch_N"]).sum() > 1.0


def test_node_types_say_which_nodes_are_held_only_across_the_mirror_planes(codend):
    scene, _, paths = codend
    points, point, _, field, _ = read(paths[0])
    start = np.asarray(scene.nodes.position)
    held = np.asarray(scene.nodes.fixed)
    kind = point["node_type"]
    assert legend(field, "node_type") == {code: meaning for code, meaning in jvtk.NODE_TYPES.items()}
    assert set(kind.tolist()) == {0, 1, 2}
    np.testing.assert_array_equal(kind == 0, ~held.any(axis=1))
    # the front is fixed along x too (type 1); the nodes held only along y lie on y = 0, those only along z on z = 0
    assert np.all(held[kind == 1, 0])
    only = kind == 2
    assert not held[only, 0].any()
    assert np.all(np.abs(start[only & held[:, 1], 1]) < 1e-9)
    assert np.all(np.abs(start[only & held[:, 2], 2]) < 1e-9)


def test_mirror_planes_are_stated_and_the_whole_net_is_the_four_mirrored_copies(codend):
    scene, eq, paths = codend
    assert [p.name for p in paths] == ["net.vtu", "net_whole.vtu"]
    points, point, cell, field, cells = read(paths[0])
    whole, whole_point, whole_cell, whole_field, whole_cells = read(paths[1])
    n = scene.n_nodes
    np.testing.assert_array_equal(field["symmetry_planes"], [[1.0, 0.0], [2.0, 0.0]])
    assert field["mirror_copies"].tolist() == [4] and whole_field["mirror_copies"].tolist() == [4]
    assert whole.shape == (4 * n, 3) and len(whole_cells) == 4 * len(cells)
    np.testing.assert_allclose(whole, mirrored(scene, eq.x).reshape(-1, 3), rtol=0, atol=0)
    copies = whole_point["mirror_copy"].reshape(4, n)
    np.testing.assert_array_equal(copies, np.arange(4)[:, None] * np.ones(n, int))
    # the copies mirrored across y = 0 and z = 0: y, z of every vector flip
    signs = mirror_signs(scene)
    np.testing.assert_array_equal(signs, [[1, 1, 1], [1, -1, 1], [1, 1, -1], [1, -1, -1]])
    d = whole_point["displacement_m"].reshape(4, n, 3)
    for c in range(4):
        np.testing.assert_array_equal(d[c], point["displacement_m"] * signs[c])
        np.testing.assert_allclose(d[c], whole[c * n:(c + 1) * n] - mirrored(scene, scene.nodes.position)[c],
                                   atol=1e-12)
    assert np.abs(d[1, :, 1]).max() > 0 and np.all(np.sign(d[1, :, 1]) == -np.sign(d[0, :, 1]))
    # the whole net's reactions: four times the quarter's along the axis, none across the planes
    r = whole_point["reaction_N"].sum(axis=0)
    np.testing.assert_allclose(r, [4 * point["reaction_N"][:, 0].sum(), 0.0, 0.0], atol=1e-9)
    # cell data repeated copy by copy; a mirrored triangle keeps its normal on the same side of the netting
    triangles = np.flatnonzero(cell["panel_id"] >= 0)
    t = len(triangles)
    for name in ("twine_tension_U_N", "mesh_opening_angle_deg", "panel_id"):
        np.testing.assert_array_equal(whole_cell[name][:4 * t].reshape(4, t), np.tile(cell[name][triangles], (4, 1)))

    def normals(xyz, conn):
        v = xyz[np.asarray(conn)]
        return np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])

    quarter = normals(points, [cells[k] for k in triangles])
    for c in range(4):
        np.testing.assert_allclose(normals(whole, whole_cells[c * t:(c + 1) * t]), quarter * signs[c], atol=1e-12)


def test_the_residual_of_a_failed_solve_is_written_on_the_free_coordinates(codend, tmp_path):
    scene, _, _ = codend
    failed = jaxnet.solve_static(scene, jaxnet.Newton(max_iter=1), throw=False)
    assert not failed.converged
    paths = jvtk.write_vtu(tmp_path / "failed.vtu", scene, failed.x, residual=failed.force, write_whole=False)
    assert paths == [tmp_path / "failed.vtu"]
    _, point, _, _, _ = read(paths[0])
    held = np.asarray(scene.nodes.fixed)
    residual = point["residual_N"]
    np.testing.assert_array_equal(residual, np.where(held, 0.0, np.asarray(failed.force)))
    # the solve's own residual: the largest out-of-balance force on a node's free coordinates, at its worst node
    norms = np.linalg.norm(residual, axis=1)
    np.testing.assert_allclose(norms.max(), float(failed.residual_N), rtol=1e-12)
    assert int(np.argmax(norms)) == int(failed.worst_node)
    # the reactions at the last iterate are what the solve reports there
    np.testing.assert_allclose(point["reaction_N"], failed.reaction(scene), rtol=1e-9, atol=1e-9)


def test_opening_angle_of_square_meshes_is_90_degrees_and_of_the_drawn_cod_end_its_drawn_meshes(tmp_path):
    panel = hanging_panel(meshes=4, step=0.05).scene
    jvtk.write_vtu(tmp_path / "panel.vtu", panel, panel.nodes.position, forces=False)
    _, _, cell, _, _ = read(tmp_path / "panel.vtu")
    triangles = cell["panel_id"] >= 0
    np.testing.assert_allclose(cell["mesh_opening_angle_deg"][triangles], 90.0, rtol=1e-12)
    assert np.all(np.isnan(cell["mesh_opening_angle_deg"][~triangles]))
    cod = importlib.import_module("jaxnet.scenes.codend").codend(meshes_around=8, meshes_along=4, opening=OPENING).scene
    jvtk.write_vtu(tmp_path / "cod.vtu", cod, cod.nodes.position, forces=False, write_whole=False)
    _, _, cell, _, _ = read(tmp_path / "cod.vtu")
    # the quarter is drawn flat: its meshes span the chord r√2 of the quarter circle, not the arc πr/2, so that
    # across a mesh its diagonal is 2√2/π of the tube's 2 l0 sin(0.1) and along it the tube's 2 l0 cos(0.1)
    angles = cell["mesh_opening_angle_deg"][cell["panel_id"] >= 0]
    drawn = 2 * np.arctan(2 * np.sqrt(2) / np.pi * np.tan(OPENING))
    np.testing.assert_allclose(angles, np.degrees(drawn), rtol=1e-9)


def test_panel_and_cable_ids_map_to_their_names(tmp_path):
    scene = fish_cage(radius=2.0, depth=1.0, sides=4, l0=0.1, step=0.5).scene
    jvtk.write_vtu(tmp_path / "cage.vtu", scene, scene.nodes.position, forces=False)
    points, _, cell, field, cells = read(tmp_path / "cage.vtu")
    panels, cables = legend(field, "panel"), legend(field, "cable")
    assert panels == dict(enumerate(scene.panel_names)) and cables == dict(enumerate(scene.cable_names))
    assert "symmetry_planes" not in field and field["mirror_copies"].tolist() == [1]
    assert not (tmp_path / "cage_whole.vtu").exists()
    panel_id, cable_id = cell["panel_id"], cell["cable_id"]
    assert np.all((panel_id >= 0) != (cable_id >= 0))  # a cell is a triangle or a bar
    assert np.all(np.isnan(cell["twine_tension_U_N"][cable_id >= 0]))
    assert np.all(np.isnan(cell["bar_tension_N"][panel_id >= 0]))

    def heights(rows):
        return np.concatenate([points[cells[c], 2] for c in np.flatnonzero(rows)])

    for k, name in panels.items():  # at the start the bottom panels lie at the cage's depth, the walls stand
        z = heights(panel_id == k)
        assert z.size and (np.allclose(z, -1.0) if name.startswith("bottom") else np.ptp(z) > 0.5)
    for k, name in cables.items():  # the collars float at the surface
        assert name.startswith("collar")
        z = heights(cable_id == k)
        assert z.size and np.allclose(z, 0.0)


def test_hexagonal_netting_has_the_tensions_of_its_three_twine_families(tmp_path):
    scene, _ = hexagonal_hanging_panel(meshes=2, step=0.1)
    x = np.asarray(scene.nodes.position) * np.array([1.02, 1.0, 1.05])  # stretched: every family pulls
    jvtk.write_vtu(tmp_path / "hex.vtu", scene, x, forces=False)
    _, _, cell, _, _ = read(tmp_path / "hex.vtu")
    tensions = np.stack([cell[f"twine_tension_{f}_N"] for f in "lmn"], axis=1)
    np.testing.assert_allclose(tensions, figures.hexagonal_twine_tensions(scene, x), rtol=1e-12)
    assert np.all(tensions > 0)
    assert np.all(np.isnan(cell["twine_tension_U_N"])) and np.all(np.isnan(cell["mesh_opening_angle_deg"]))
    np.testing.assert_array_equal(cell["panel_id"], np.asarray(scene.hexagonal.panel))


def test_a_record_of_a_run_in_time_holds_its_displacement_velocity_and_reactions(tmp_path):
    scene = hanging_panel(meshes=2, step=0.05).scene
    n = scene.n_nodes
    held = np.flatnonzero(np.asarray(scene.nodes.fixed).any(axis=1))
    rng = np.random.default_rng(1)
    x = np.asarray(scene.nodes.position) + 0.01 * rng.standard_normal((n, 3))
    v, reaction = rng.standard_normal((n, 3)), rng.standard_normal((len(held), 3))
    record = ts.Record(time=0.5, step=10, position=x, velocity=v, figures={"reaction_N": reaction})
    with ts.SeriesWriter(tmp_path, scene, vtk=True, run={"reaction_nodes": held.tolist()}) as writer:
        writer.write(record)
    points, point, cell, _, _ = read(tmp_path / "net_00000.vtu")
    np.testing.assert_array_equal(points, x)
    np.testing.assert_array_equal(point["displacement_m"], x - np.asarray(scene.nodes.position))
    np.testing.assert_array_equal(point["velocity_m_s"], v)
    expected = np.zeros((n, 3))
    expected[held] = reaction
    np.testing.assert_array_equal(point["reaction_N"], expected)
    tw = figures.twine_tensions(scene, x)
    np.testing.assert_allclose(cell["twine_tension_U_N"][:len(tw)], tw[:, 0], rtol=1e-12)
    assert "catch_N" not in point  # no static force balance at an instant of a run
