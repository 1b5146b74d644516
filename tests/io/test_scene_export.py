"""Writing a net as a scene file (``jaxnet.io.scene_export.to_dict``, ``write``; ``Net.description``): every built-in
scene, and nets using every part of the description, read back (``scene_file.read``) into the same scene and the
same solver options, in TOML and in JSON; what a scene file cannot hold is refused, naming it, and nothing is
written."""

from __future__ import annotations

import copy
import dataclasses
import math

import equinox as eqx
import jax
import numpy as np
import pytest

from jaxnet.water import waves
from jaxnet.case import Case, from_net
from jaxnet.io import scene_export, scene_file
from jaxnet.materials import HexTwine
from jaxnet.mesh.twines import NumericalTwines
from jaxnet.net import Net, Rope, Twine
from jaxnet.scene import Environment, SceneError
from jaxnet.scenes import cage_in_waves, codend, fish_cage, framed_panel, hanging_panel
from jaxnet.solve.options import Newton

#: the built-in scenes, small: name -> the Case
BUILT_INS = {
    "fish_cage": lambda: fish_cage(step=1.6),
    "cage_in_waves": lambda: cage_in_waves(step=1.6),
    "codend": lambda: codend(meshes_around=8, meshes_along=4),
    "hanging_panel": lambda: hanging_panel(meshes=6, step=0.05),
    "framed_panel": lambda: framed_panel(meshes=6, step=0.05),
}
SUFFIXES = (".toml", ".json")


def assert_same_scene(a, b):
    """Scene ``b`` is scene ``a``: node count, positions (1e-12 m), fixity, every array of the nodes, netting, bars,
    hinges, cable joints, hexagonal netting, catches and enclosure (1e-12 relative: the reader adds attachments up
    in its own order), the environment's numbers, the names and the symmetry planes."""
    assert b.n_nodes == a.n_nodes
    np.testing.assert_allclose(np.asarray(b.nodes.position), np.asarray(a.nodes.position), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(np.asarray(b.nodes.fixed), np.asarray(a.nodes.fixed))
    assert (b.panel_names, b.cable_names, b.symmetry_planes) == (a.panel_names, a.cable_names, a.symmetry_planes)
    for part in ("nodes", "netting", "bars", "hinges", "cable_joints", "hexagonal", "catch", "panel_catches",
                 "enclosure", "environment"):
        x, y = getattr(a, part), getattr(b, part)
        assert (x is None) == (y is None), part
        if x is None:
            continue
        for field in dataclasses.fields(x):
            u, v = getattr(x, field.name), getattr(y, field.name)
            where = f"{part}.{field.name}"
            if u is None or isinstance(u, (str, bool, tuple)):
                assert v == u, where
            elif field.name == "waves":
                assert type(v) is type(u), where
                for f in dataclasses.fields(u):
                    np.testing.assert_allclose(np.asarray(getattr(v, f.name)), np.asarray(getattr(u, f.name)),
                                               rtol=1e-12, atol=1e-15, err_msg=f"{where}.{f.name}")
            else:
                u, v = np.asarray(u), np.asarray(v)
                assert v.shape == u.shape and v.dtype.kind == u.dtype.kind, where
                np.testing.assert_allclose(v, u, rtol=1e-12, atol=1e-15, equal_nan=True, err_msg=where)
    # and nothing else differs: the same parts, static options and leaves
    (leaves_a, tree_a), (leaves_b, tree_b) = jax.tree_util.tree_flatten(a), jax.tree_util.tree_flatten(b)
    assert tree_b == tree_a
    for x, y in zip(leaves_a, leaves_b):
        np.testing.assert_allclose(np.asarray(y), np.asarray(x), rtol=1e-12, atol=1e-15, equal_nan=True)


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize("name", sorted(BUILT_INS))
def test_every_built_in_scene_reads_back_the_same(name, suffix, tmp_path):
    case = BUILT_INS[name]()
    path = scene_export.write(tmp_path / f"{name}{suffix}", case)
    back = scene_file.read(path)
    assert_same_scene(case.scene, back.scene)
    assert back.solver == case.solver
    scene = back.scene
    if name == "codend":   # the quarter model's planes, its catch
        assert scene.symmetry_planes == ((1, 0.0), (2, 0.0))
        assert (float(scene.catch.volume), float(scene.catch.symmetry)) == (0.2, 4.0)
        np.testing.assert_array_equal(np.asarray(scene.catch.axis), [1.0, 0.0, 0.0])
    if name.startswith(("fish_cage", "cage_in_waves")):   # 8 sinkers of 20 kg, the volume below the collar
        assert math.isclose(float(np.sum(scene.nodes.mass)), 8 * 20.0, rel_tol=1e-14)
        np.testing.assert_array_equal(np.asarray(scene.enclosure.axis), [0.0, 0.0, -1.0])
    if name == "cage_in_waves":   # the waves are the scene's; the run in time is not a scene file's
        assert (float(scene.environment.waves.height), float(scene.environment.waves.depth)) == (2.0, 50.0)
        assert back.time is None and case.time is not None
        assert "written without its time settings" in path.read_text(encoding="utf-8")
    if name == "framed_panel":   # the sinker on the node nearest the centre
        assert float(np.max(scene.nodes.mass)) == 5.0 and int(np.count_nonzero(scene.nodes.mass)) == 1


def rich_net():
    """A net using what the built-ins do not: a lattice of mesh diagonals, numerical twines sewn to stiff ropes,
    welded cables, cables between corners and points, knots and twine stiffnesses, every kind of reference,
    attachments, sinkers and floats, bodies and limits (with an unused NaN limit), second-order Stokes waves, a
    current profile, a still sea bed, a subset of floating families and another merge tolerance."""
    env = Environment(current_speed=0.3, current_direction=np.array([1.0, 0.5, 0.0]), surface_level=0.0,
                      bottom_stiffness=1e4, bottom_friction=0.3, bottom_moving=False,
                      profile_depth=np.array([0.0, 10.0]), profile_factor=np.array([1.0, 0.5]),
                      floating=("bars", "nodes"), added_mass_coefficient=0.8,
                      waves=waves.Stokes2(1.0, 5.0, direction=(1.0, 1.0, 0.0), depth=30.0, phase=0.3,
                                          surface_level=0.0))
    net = Net(environment=env, merge_tolerance=1e-5)
    twine = Twine(l0=0.05, ea=1000.0, diameter=0.002, knot_stiffness=2.0, knot_size=0.004, opening_stiffness=0.01,
                  bending_stiffness=1e-4)
    uv = np.array([[0, 0], [600, 0], [600, 30], [0, 30]])
    gill = net.panel("gill net", np.column_stack([uv[:, 0] * 0.001, np.zeros(4), -uv[:, 1] * 0.01, uv]), twine,
                     lattice=(100, 5))
    square = [(2, 0, 0, 0, 0), (2.8, 0, 0, 40, 0), (2.8, 0.8, 0, 40, 40), (2, 0.8, 0, 0, 40)]
    p = net.panel("square", square, Twine(l0=0.01, ea=500.0, diameter=0.001),
                  twines=NumericalTwines(period=10, bars=2, offset_u=0.5, offset_v=0.5))
    stiff = Rope(ea=1e5, diameter=0.004, bending_stiffness=0.5)
    for k in range(4):
        net.cable(f"rope {k}", along=p.side(k), rope=stiff)
    a = net.cable("a", start=(5.0, 0.0, 0.0), end=(6.0, 0.0, 0.0), rope=stiff, n_bars=2)
    b = net.cable("b", start=(6.0, 0.0, 0.0), end=(6.5, 0.8, 0.0), rope=stiff, n_bars=3, length=1.0)
    net.cable("tie", start=gill.corner(1), end=p.corner(0), rope=Rope(ea=1e4, diameter=0.003), n_bars=2)
    net.cable_joint(a, b, neutral_angle=2.0, stiffness=0.3)
    net.fix(gill.side(3))
    net.fix(p.side(0), axes="z")
    net.fix(a.start)
    net.fix(a.nodes, axes="y")
    net.fix((6.5, 0.8, 0.0), axes="xz")
    net.attach(gill.corner(2), mass=1.0, volume=0.001, force=(0.0, 1.0, -2.0), drag_area=0.01, size=0.1)
    net.sinker(p.side(2), 2.0, density=7800.0)
    net.float(a.end, 30.0, mass=0.5, size=0.2, drag_area=0.02)
    net.attach(b.nodes, mass=0.25)
    net.body(p, (0.1, 0.1, -0.2), (1.0, 1.0, 0.5))
    net.body(p.nearest(2.4, 0.4, 0.0), (0.2, 0.2, 0.3), (1.2, 1.2, 1.2))
    net.limit(gill, (0.0, 0.0, -5.0), (0, 0, 1))
    net.limit(b.end, (7.0, float("nan"), -4.0), (-1, 0, 1))
    return net


def catch_net():
    """Two cod-end quarters each holding its own catch (their axis given, in still water), and a hexagonal-mesh panel
    whose families differ in length."""
    net = Net()
    twine = Twine(l0=0.06, ea=1e5, diameter=4e-3, density=1025.0)
    n, m, opening = 2, 4, 0.1
    length, r = m * 2 * 0.06 * math.cos(opening), 4 * n * 2 * 0.06 * math.sin(opening) / (2 * math.pi)
    for name, y0 in (("port", 0.0), ("starboard", 3.0)):
        corners = [(0.0, y0, r, 0, 0), (0.0, y0 + r, 0.0, n, -n), (length, y0 + r, 0.0, n + m, m - n),
                   (length, y0, r, m, m)]
        net.fix(net.panel(name, corners, twine, 0.12).side(0))
    net.panel_catch(0.1, ["port"], drag_coefficient=1.3, symmetry=4.0, center=(0.0, 0.0, 0.0))
    net.panel_catch(0.2, ["starboard"], drag_coefficient=1.3, symmetry=4.0, center=(0.0, 3.0, 0.0),
                    axis=(1.0, 0.0, 0.1))
    hexagonal = [(0, 5, 0, 0, 0), (1, 5, 0, 4, 0), (1, 6, 0, 4, 4), (0, 6, 0, 0, 4)]
    net.fix(net.panel("hex", hexagonal, HexTwine(l0=(0.05, 0.05, 0.06), ea=1000.0, diameter=1e-3), 0.2).side(0))
    return net


SOLVER = Newton(tol=1e-4, max_iter=50, max_step=0.2, stall_window=None, stiffness="autodiff")


@pytest.mark.parametrize("suffix", SUFFIXES)
@pytest.mark.parametrize("make", [rich_net, catch_net])
def test_every_part_of_a_description_reads_back_the_same(make, suffix, tmp_path):
    case = from_net(make(), SOLVER, label="a net of every part")
    back = scene_file.read(scene_export.write(tmp_path / f"net{suffix}", case))
    assert_same_scene(case.scene, back.scene)
    assert back.solver == SOLVER   # stall_window None included (false in the file: TOML has no null)
    scene = back.scene
    if make is rich_net:
        assert type(scene.environment.waves) is waves.Stokes2 and scene.environment.floating == ("bars", "nodes")
        assert len(scene.cable_joints.vertices) > 0 and scene.cable_names[-1] == "square twines"
        # 1 + 2 + 0.5 + 0.25 kg attached, the limit's unused NaN written as the 0 the net keeps
        assert math.isclose(float(np.sum(scene.nodes.mass)), 3.75, rel_tol=1e-14)
        assert np.isfinite(np.asarray(scene.nodes.limit)).all()
    else:
        np.testing.assert_array_equal(np.asarray(scene.panel_catches.volume), [0.1, 0.2])
        np.testing.assert_allclose(np.asarray(scene.hexagonal.l0)[0], [0.05, 0.05, 0.06], rtol=0, atol=0)


def test_a_written_net_is_its_description_and_the_description_is_a_copy(tmp_path):
    net = rich_net()
    d = net.description()
    assert [s["attached"] for s in d["sinkers"]] == [1] and [f["attached"] for f in d["floats"]] == [2]
    assert d["panels"][0]["step"] is None and d["panels"][0]["lattice"] == (100.0, 5.0)
    d["panels"][0]["corners"][:] = 0.0   # the description is the caller's: the net keeps its own
    doc = scene_export.to_dict(net)
    assert doc["panels"][0]["corners"][1] == [0.6, 0.0, 0.0, 600.0, 0.0]
    assert doc["sinkers"] == [{"at": {"panel": "square", "side": 2}, "mass": 2.0, "density": 7800.0}]
    assert doc["floats"] == [{"at": {"cable": "a", "end": 1}, "buoyancy_N": 30.0, "mass": 0.5, "size": 0.2,
                              "drag_area": 0.02}]
    assert doc["merge_tolerance"] == 1e-5 and doc["solver"] == {}
    # a bare net (no case to compare with) is written too, and builds the same scene
    back = scene_file.read(scene_export.write(tmp_path / "net.toml", net))
    assert_same_scene(net.build(), back.scene)


def test_what_a_scene_file_cannot_hold_is_refused_and_nothing_is_written(tmp_path):
    path = tmp_path / "sea.toml"
    net = rich_net()
    net.environment = eqx.tree_at(lambda e: e.waves, net.environment, waves.sea_state(2.0, 8.0, components=8))
    with pytest.raises(SceneError, match=r"environment\.waves: an irregular sea keeps its realised components"):
        scene_export.write(path, net)
    # waves on another level than the environment's surface
    net.environment = eqx.tree_at(lambda e: e.waves, net.environment, waves.Airy(1.0, 5.0, surface_level=1.0))
    with pytest.raises(SceneError, match=r"environment\.waves: the waves' surface_level differ"):
        scene_export.write(path, net)
    # a case whose scene was changed after its net was built (as FEMNET's gauge node is)
    case = BUILT_INS["framed_panel"]()
    fixed = np.array(case.scene.nodes.fixed)
    fixed[0] = False
    changed = dataclasses.replace(case, scene=eqx.tree_at(lambda s: s.nodes.fixed, case.scene, fixed))
    with pytest.raises(SceneError, match=r"its scene is not what its net builds \(scene\.nodes\.fixed\)"):
        scene_export.write(path, changed)
    with pytest.raises(SceneError, match="read whole"):
        scene_export.write(path, Case(scene=case.scene, label="a FEMNET mesh"))
    with pytest.raises(SceneError, match=r"unknown scene file type '\.yaml'"):
        scene_export.write(tmp_path / "net.yaml", case)
    assert not list(tmp_path.iterdir())


def test_the_keys_added_for_writing_are_checked_where_they_are(tmp_path):
    doc = scene_export.to_dict(BUILT_INS["codend"]().net)
    for change, message in (
            (lambda d: d["symmetry_planes"][1].update(axis="w"), r"symmetry_planes\[1\]: .*axis must be"),
            (lambda d: d["symmetry_planes"][0].update(hold=1), r"symmetry_planes\[0\]\.hold: expected true or false"),
            (lambda d: d["panels"][0].update(hex_twine="cod-end"), r"panels\[0\]: give its material as twine"),
            (lambda d: d["panels"][0].pop("step"), r"panels\[0\]: missing key\(s\) \['step'\]"),
            (lambda d: d["panels"][0].update(lattice=[1.0]), r"panels\[0\]\.lattice: expected \[NU, NV\]"),
            (lambda d: d["fix"][0]["at"].update(nearest=[0, 0]), r"fix\[0\]\.at: give one of a corner, a side"),
            (lambda d: d["catch"].update(centre=[0, 0, 0]), r"catch: unknown key\(s\) \['centre'\]"),
            (lambda d: d["environment"].update(floating=["net"]), r"environment\.floating: expected a list"),
            (lambda d: d.update(enclosure={"center": [0, 0, 0]}), r"enclosure: missing key\(s\) \['axis'\]"),
            (lambda d: d.update(cable_joints=[{"cables": ["cod line"]}]), r"cable_joints\[0\]\.cables"),
            (lambda d: d.update(merge_tolerance=-1.0), r"merge_tolerance: must be finite and >= 0")):
        bad = copy.deepcopy(doc)
        change(bad)
        with pytest.raises(SceneError, match=message):
            scene_file.from_dict(bad)
