"""Bad input gets a clear error naming the culprit, raised before anything is compiled."""

import json

import numpy as np
import pytest

import jaxnet as jn
from jaxnet.io import scene_file
from jaxnet.net import Net, Rope, Twine
from jaxnet.solve import newton, statics

TWINE = Twine(l0=0.02, ea=1000.0, diameter=1e-3)
SQUARE = [(0, 0, 0, 0, 0), (1, 0, 0, 20, -20), (1, 0, 1, 40, 0), (0, 0, 1, 20, 20)]


@pytest.fixture(autouse=True)
def no_compilation(monkeypatch):
    """Any attempt to compile the solver during these tests fails loudly."""

    class Forbidden:
        def lower(self, *a, **k):
            raise AssertionError("the solver was compiled before the bad input was caught")

    def forbidden(*a, **k):
        raise AssertionError("the solver was compiled before the bad input was caught")

    monkeypatch.setattr(newton, "newton_loop_jit", Forbidden())
    monkeypatch.setattr(statics, "compile_pieces", forbidden)


def solve_net(net):
    return jn.solve_static(net.build())


def hanging(corners=SQUARE, twine=TWINE, fix=True):
    net = Net()
    p = net.panel("wall", corners, twine, 0.1)
    if fix:
        net.fix(p.side(2))
    return net, p


def test_collinear_twine_coordinates_in_a_panel():
    net, _ = hanging([(0, 0, 0, 0, 0), (1, 0, 0, 10, 10), (2, 0, 0, 20, 20)])
    with pytest.raises(jn.SceneError, match="wall"):
        solve_net(net)


def test_collinear_twine_coordinates_of_a_triangle():
    scene = hanging()[0].build()
    uv = np.asarray(scene.netting.uv).copy()
    uv[7] = [[0, 0], [1, 1], [2, 2]]
    bad = jn.Scene(nodes=scene.nodes, netting=scene.netting.__class__(**{**scene.netting.__dict__, "uv": uv}),
                   environment=scene.environment, panel_names=scene.panel_names)
    with pytest.raises(jn.SceneError, match=r"triangle 7 \(wall\): collinear twine coordinates"):
        jn.solve_static(bad)


def test_self_intersecting_panel():
    bowtie = [(0, 0, 0, 0, 0), (1, 0, 1, 20, 20), (1, 0, 0, 20, 0), (0, 0, 1, 0, 20)]
    net, _ = hanging(bowtie, fix=False)
    with pytest.raises(jn.SceneError, match=r"wall.*(intersect|cross)"):
        solve_net(net)


def test_negative_stiffness():
    # refused where the material is made, naming it, the parameter and its value
    with pytest.raises(jn.SceneError, match=r"^Twine: ea must be > 0, got -5\.0 \(traction stiffness EA, N\)$"):
        Twine(l0=0.02, ea=-5.0, diameter=1e-3)
    with pytest.raises(jn.SceneError, match=r"^Rope: ea_compression must be >= 0, got -1\.0 \(compression stiffness"):
        Rope(ea=1e4, diameter=0.01, ea_compression=-1.0)
    # a scene built by hand is checked too, naming the element
    scene = hanging()[0].build()
    ea = np.asarray(scene.netting.ea_traction).copy()
    ea[3] = -1.0
    bad = jn.Scene(nodes=scene.nodes, netting=scene.netting.__class__(**{**scene.netting.__dict__, "ea_traction": ea}),
                   panel_names=scene.panel_names)
    with pytest.raises(jn.SceneError, match=r"triangle 3 \(wall\): traction stiffness EA must be > 0"):
        jn.solve_static(bad)


def test_zero_traction_stiffness_is_bad_input():
    """A twine or a rope without traction stiffness holds nothing (a mechanism, which a solve reported only as "no
    step decreases the energy"): refused before anything is built, naming EA; a compression, opening, knot or
    bending stiffness of 0 is none (slack twines, free meshes) and accepted."""
    from jaxnet.materials import HexTwine

    with pytest.raises(jn.SceneError, match=r"^Twine: ea must be > 0, got 0\.0 \(traction stiffness EA, N\)$"):
        Twine(l0=0.02, ea=0.0, diameter=1e-3)
    with pytest.raises(jn.SceneError, match=r"^Rope: ea must be > 0, got 0\.0"):
        Rope(ea=0.0, diameter=0.01)
    with pytest.raises(jn.SceneError, match=r"^HexTwine: ea must be > 0 per twine family \(l, m, n\), got "
                                            r"\[1000\.0, 0\.0, 1000\.0\]"):
        HexTwine(l0=0.02, ea=(1000.0, 0.0, 1000.0), diameter=1e-3)
    for name in ("opening_stiffness", "knot_stiffness", "bending_stiffness"):
        with pytest.raises(jn.SceneError, match=rf"^Twine: {name} must be >= 0, got -1\.0"):
            Twine(l0=0.02, ea=1000.0, diameter=1e-3, **{name: -1.0})
    slack = Twine(l0=0.02, ea=1000.0, diameter=1e-3, ea_compression=0.0, opening_stiffness=0.0, knot_stiffness=0.0,
                  bending_stiffness=0.0)
    assert hanging(twine=slack)[0].build().n_nodes > 4
    # a scene built by hand: a bar of zero EA is named
    net, p = hanging()
    net.cable("rope", along=p.side(2), rope=Rope(ea=1e4, diameter=0.01))
    scene = net.build()
    ea = np.asarray(scene.bars.ea_traction).copy()
    ea[1] = 0.0
    with pytest.raises(jn.SceneError, match=r"bar 1 \(rope\): traction stiffness EA must be > 0, got 0\.0"):
        jn.solve_static(jn.Scene(nodes=scene.nodes, netting=scene.netting, bars=scene.bars.__class__(
            **{**scene.bars.__dict__, "ea_traction": ea}), panel_names=scene.panel_names, cable_names=scene.cable_names))


def test_negative_length():
    with pytest.raises(jn.SceneError, match=r"panel 'wall': l0 must be > 0"):
        hanging(twine=Twine(l0=-0.02, ea=1000.0, diameter=1e-3))
    net, p = hanging()
    with pytest.raises(jn.SceneError, match=r"cable 'rope': length must be > 0, got -1"):
        net.cable("rope", start=p.corner(0), end=(0, 0, -1), rope=Rope(ea=1e4, diameter=0.01), length=-1.0)


def test_nan_coordinates():
    corners = [list(c) for c in SQUARE]
    corners[2][1] = float("nan")
    net, _ = hanging(corners)
    with pytest.raises(jn.SceneError, match=r"wall.*corner 2"):
        solve_net(net)
    scene = hanging()[0].build()
    pos = np.asarray(scene.nodes.position).copy()
    pos[5, 2] = np.nan
    nodes = scene.nodes.__class__(**{**scene.nodes.__dict__, "position": pos})
    with pytest.raises(jn.SceneError, match="node 5: position is not finite"):
        jn.solve_static(jn.Scene(nodes=nodes, netting=scene.netting))


def test_cable_end_on_no_node():
    net, p = hanging()
    net.cable("bridle", start=p.corner(7), end=(0, 0, 2), rope=Rope(ea=1e4, diameter=0.01))
    with pytest.raises(jn.SceneError, match=r"cable 'bridle' start: panel 'wall' has no corner 7"):
        solve_net(net)
    net, p = hanging()
    net.cable("bridle", start=jn.net.Corner("roof", 0), end=(0, 0, 2), rope=Rope(ea=1e4, diameter=0.01))
    with pytest.raises(jn.SceneError, match=r"cable 'bridle' start: no panel named 'roof'"):
        solve_net(net)
    net, p = hanging()
    net.fix((5.0, 5.0, 5.0))
    with pytest.raises(jn.SceneError, match=r"no node at point \[5.0, 5.0, 5.0\]"):
        solve_net(net)


def test_no_fixed_node():
    net, _ = hanging(fix=False)
    with pytest.raises(jn.SceneError, match="no node is fixed"):
        solve_net(net)


def test_loose_piece_of_net():
    net, p = hanging()
    net.panel("loose", [(3, 0, 0, 0, 0), (4, 0, 0, 20, -20), (4, 0, 1, 40, 0), (3, 0, 1, 20, 20)], TWINE, 0.2)
    with pytest.raises(jn.SceneError, match="connected to no fixed node"):
        solve_net(net)


def test_unknown_keys_in_scene_file(tmp_path):
    doc = {
        "twines": {"pa": {"l0": 0.02, "ea": 1000.0, "diameter": 0.001}},
        "panels": [{"name": "wall", "corners": [list(c) for c in SQUARE], "twine": "pa", "step": 0.1}],
        "fix": [{"at": {"panel": "wall", "side": 2}}],
    }
    path = tmp_path / "ok.json"
    path.write_text(json.dumps(doc))
    assert scene_file.read(path).scene.n_nodes > 4
    doc["panels"][0]["mesh_size"] = 3
    path.write_text(json.dumps(doc))
    with pytest.raises(jn.SceneError, match=r"ok\.json:1: panels\[0\]: unknown key\(s\) \['mesh_size'\]"):
        scene_file.read(path)
    del doc["panels"][0]["mesh_size"]
    doc["twines"]["pa"]["EA"] = 5
    path.write_text(json.dumps(doc))
    with pytest.raises(jn.SceneError, match=r"twines.pa: unknown key\(s\) \['EA'\]: did you mean ea\?"):
        scene_file.read(path)
    del doc["twines"]["pa"]["EA"]
    doc["currents"] = {}
    path.write_text(json.dumps(doc))
    # a key of another table is suggested with its path
    with pytest.raises(jn.SceneError,
                       match=r"scene: unknown key\(s\) \['currents'\]: did you mean environment\.current_speed\?"):
        scene_file.read(path)


def test_a_reference_is_named_in_words():
    """A reference that designates no node is named as the user wrote it (corner 7 of panel 'wall'), not as a
    Python object."""
    from jaxnet.net import Corner

    net = Net()
    net.panel("wall", [(0, 0, 0, 0, 0), (1, 0, 0, 5, -5), (1, 0, 1, 10, 0), (0, 0, 1, 5, 5)],
              Twine(l0=0.1, ea=100.0, diameter=1e-3), 0.25)
    net.fix(Corner("wall", 7))
    with pytest.raises(jn.SceneError, match=r"^reference corner 7 of panel 'wall': panel 'wall' has no corner 7 "
                                         r"\(it has 4\)$"):
        net.build()
