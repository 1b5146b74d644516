"""FEMNET's node types with a body (length and drag coefficient X,Y,Z) or limits (limits and sense X,Y,Z),
read from a ``.don`` (jaxnet.io.femnet) into ``Nodes.drag_length``/``drag_coefficient`` and ``Nodes.limit``/
``limit_sense`` through ``Net.body`` and ``Net.limit``; the sea bed's stiffness and friction into the
environment.

The cases are FEMNET's ``nr_netting`` with the sinker rope (cable 5), its two ends and the panel side it is
sewn to given a node type 3 of their own; type 3 then gets a floor, a ceiling or a box. Checked: the limits
and bodies land on exactly the nodes of their type (in the net jaxnet meshes and on FEMNET's own mesh), the
friction only with ``input moving_bottom``, FEMNET's box drag on them, a solved case whose sinker rope rests
on a floor at z = -2.5 m (FEMNET's free equilibrium sinks it to -2.6 m) no deeper than its load over the
stiffness, with the contact force k p of FEMNET's law; the errors name the line; Net.body and Net.limit
(each node gets the whole body, a later call replaces an earlier one).
"""

import json
import pathlib

import numpy as np
import pytest

from jaxnet import figures, model
from jaxnet.io import femnet
from jaxnet.net import Net, Twine
from jaxnet.scene import Environment, SceneError
from jaxnet.solve.statics import solve

DATA = pathlib.Path(__file__).parents[1] / "data" / "femnet"
SINKER_ROPE = 4  # cable 5 of nr_netting (0-based in the scene): 57 bars of 22.5 mm, 5665 kg/m3, 2.02 m
K_BOTTOM = 5e6  # N/m, nr_netting's "stiffness of the insertion in the sea bottom"

# type 3: the sinker rope's nodes (its ends are panel 1's corners 3 and 4, and its bars are sewn along side 3)
_RETYPE = [
    ("3    1.695000    0.730000    -1.000000    80.000000    120.000000    2    2",
     "3    1.695000    0.730000    -1.000000    80.000000    120.000000    3    3"),
    ("4    1.695000    -0.735000    -1.000000    0.000000    120.000000    2    2",
     "4    1.695000    -0.735000    -1.000000    0.000000    120.000000    3    2"),
    ("2  1.695000  -0.735000  -1.000000  2\nKt: 50000", "2  1.695000  -0.735000  -1.000000  3\nKt: 50000"),
    ("1  1.695000  -0.735000  -1.000000  2\n2  1.695000  0.730000  -1.000000  2\nKt: 1000000.000000",
     "1  1.695000  -0.735000  -1.000000  3\n2  1.695000  0.730000  -1.000000  3\nKt: 1000000.000000"),
    ("Nb: 57  Ty: 2", "Nb: 57  Ty: 3"),
    ("1  1.695000  0.730000  -1.000000  2\n2  0.000000  0.730000  -1.000000  2",
     "1  1.695000  0.730000  -1.000000  3\n2  0.000000  0.730000  -1.000000  2"),
    ("Number of types of nodes: 2", "Number of types of nodes: 3"),
]


def _fmt(values):
    return "  ".join(str(v) for v in values)


def _case_text(length=(0, 0, 0), cd=(1.2, 1.2, 1.2), limit=(0, 0, -2.5), sense=(0, 0, 1), stiffness="5000000.000000",
               inputs=(), base="nr_netting"):
    """nr_netting's text with node type 3 (the sinker rope) of the given length, drag coefficient, limits
    and senses, the bottom stiffness, and extra ``input`` lines."""
    text = (DATA / f"{base}.don").read_text()
    for old, new in _RETYPE:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
    type3 = (f"No du type :            3\nMass X,Y,Z (kg):        0.000000  0.000000  0.000000\n"
             f"Added mass X,Y,Z (kg):        0.000000  0.000000  0.000000\nLength X,Y,Z (m):        {_fmt(length)}\n"
             f"Drag coefficient X,Y,Z:        {_fmt(cd)}\nExternal forces X,Y,Z (N):    0.000000  0.000000  0.000000\n"
             f"Displacement X,Y,Z:        0 0 0\nLimits X,Y,Z (m):        {_fmt(limit)}\n"
             f"Limits sens X,Y,Z:        {_fmt(sense)}\nSymetry X,Y,Z:            0  0  0\n\n")
    text = text.replace("NUMERIC ENVIRONMENT", type3 + "NUMERIC ENVIRONMENT")
    old = "Stiffness of the insertion in the sea bottom (N/m):    5000000.000000"
    text = text.replace(old, old.replace("5000000.000000", stiffness))
    return text + "".join(f"input {line}\n" for line in inputs)


def _write(tmp_path, text, name="case"):
    path = tmp_path / f"{name}.don"
    path.write_text(text)
    return path


def _line(text, needle, after="No du type :            3"):
    """Line number (1-based) of the first ``needle`` after ``after`` (type 3's block by default)."""
    start = text.index(after) if after else 0
    return text[: text.index(needle, start)].count("\n") + 1


def _sinker_nodes(scene):
    ends, cable = np.asarray(scene.bars.ends), np.asarray(scene.bars.cable)
    return np.unique(ends[cable == SINKER_ROPE])


# -- what is read, and onto which nodes -------------------------------------------------------------


def test_a_floor_goes_to_exactly_the_nodes_of_its_type_with_femnet_stiffness_and_law(tmp_path):
    case = femnet.read_don(_write(tmp_path, _case_text()))
    scene, info = case.scene, case.info
    n = scene.n_nodes
    sinker = _sinker_nodes(scene)
    assert len(sinker) == 58  # 57 bars
    limited = np.zeros(n, bool)
    limited[sinker] = True
    sense, limit = np.asarray(scene.nodes.limit_sense), np.asarray(scene.nodes.limit)
    np.testing.assert_array_equal(sense[:, 2], np.where(limited, 1, 0))
    np.testing.assert_array_equal(sense[:, :2], 0)
    np.testing.assert_array_equal(limit[:, 2], np.where(limited, -2.5, 0.0))
    assert scene.nodes.drag_length is None and scene.nodes.drag_coefficient is None  # no body: no term
    env = scene.environment
    # FEMNET's fond.c law exactly (no band); a still bottom: no friction in statics although the case gives 0.5,
    # which rubs the nodes moving over the bed in time (fond_dyn.c)
    assert (env.bottom_stiffness, env.bottom_band, env.bottom_friction, env.bottom_moving) == (K_BOTTOM, 0.0, 0.5,
                                                                                              False)
    names = [t.name for t in model.active_terms(scene)]
    assert "bottom_contact" in names and "bottom_friction" not in names and "node_box_drag" not in names
    assert "bed_friction" in [t.name for t in model.active_terms(scene, dynamic=True)]
    assert info["sea_bed"] == {"stiffness_N_per_m": K_BOTTOM, "moving_bottom": False, "friction": 0.5,
                               "limits": {3: {"limit_m": [0.0, 0.0, -2.5], "sense": [0, 0, 1]}}}
    json.dumps(info)
    # the case as FEMNET wrote it has neither: the fields stay None
    plain = femnet.read_don(DATA / "nr_netting.don").scene
    assert plain.nodes.limit is None and plain.nodes.limit_sense is None and plain.nodes.drag_length is None


def test_moving_bottom_gives_the_friction_and_a_ceiling_reads_as_sense_minus_one(tmp_path):
    case = femnet.read_don(_write(tmp_path, _case_text(limit=(0, 0.9, 0), sense=(0, -1, 0),
                                                       inputs=("moving_bottom",))))
    scene, info = case.scene, case.info
    assert scene.environment.bottom_friction == 0.5 and info["sea_bed"]["moving_bottom"] is True
    assert scene.environment.bottom_moving is True
    sinker = _sinker_nodes(scene)
    sense = np.asarray(scene.nodes.limit_sense)
    assert set(np.flatnonzero(sense[:, 1] == -1)) == set(sinker.tolist()) and not sense[:, [0, 2]].any()
    np.testing.assert_array_equal(np.asarray(scene.nodes.limit)[sinker, 1], 0.9)
    # friction acts only on floors along z (fond.c): none here, so its term is not compiled
    assert "bottom_friction" not in [t.name for t in model.active_terms(scene)]


def test_limits_on_femnet_mesh_follow_the_mdg_node_types(tmp_path):
    # type 2 is every free node of FEMNET's mesh: give it a floor, read FEMNET's mesh with it
    text = (DATA / "nr_netting.don").read_text()
    block = ("Displacement X,Y,Z:        0 0 0\nLimits X,Y,Z (m):        0.000000  0.000000  0.000000\n"
             "Limits sens X,Y,Z:        0  0  0")
    assert text.count(block) == 1
    text = text.replace(block, block.replace("0.000000  0.000000  0.000000\nLimits sens X,Y,Z:        0  0  0",
                                             "0.000000  0.000000  -3.000000\nLimits sens X,Y,Z:        0  0  1"))
    scene = femnet.read_mdg(DATA / "nr_netting.mdg", _write(tmp_path, text, "nr_netting")).scene
    lines = (DATA / "nr_netting.mdg").read_text().split("\n")
    start = next(i for i, ln in enumerate(lines) if " ".join(ln.lower().split()).startswith("description des noeuds"))
    rows = [ln.split() for ln in lines[start + 1:] if ln.split()][: scene.n_nodes]
    mdg_type = np.array([int(r[5]) for r in rows])  # rows: i x y z i type type
    assert set(mdg_type.tolist()) == {1, 2}
    np.testing.assert_array_equal(np.asarray(scene.nodes.limit_sense)[:, 2], np.where(mdg_type == 2, 1, 0))
    np.testing.assert_array_equal(np.asarray(scene.nodes.limit)[:, 2], np.where(mdg_type == 2, -3.0, 0.0))
    assert scene.environment.bottom_stiffness == K_BOTTOM and scene.environment.bottom_band == 0.0


def test_a_box_without_volume_takes_femnet_drag_on_its_nodes(tmp_path):
    # a plate normal to x, 0.5 m wide (y), hanging 0.2 m below its node: FEMNET's "lest inonde" drag along x is
    # 1/2 rho Cd_x L_y |L_z| U^2 (traineecourant2.c), nothing along y (L_x = 0) nor z (horizontal current)
    text = _case_text(length=(0, 0.5, -0.2), cd=(1.0, 1.2, 1.3), sense=(0, 0, 0))
    case = femnet.read_don(_write(tmp_path, text))
    scene, info = case.scene, case.info
    sinker = _sinker_nodes(scene)
    length, cd = np.asarray(scene.nodes.drag_length), np.asarray(scene.nodes.drag_coefficient)
    boxed = np.zeros(scene.n_nodes, bool)
    boxed[sinker] = True
    np.testing.assert_array_equal(length, np.where(boxed[:, None], [0.0, 0.5, -0.2], 0.0))
    np.testing.assert_array_equal(cd, np.where(boxed[:, None], [1.0, 1.2, 1.3], 0.0))
    assert scene.nodes.limit is None  # senses 0: no limit
    assert info["node_bodies"] == {3: {"length_m": [0.0, 0.5, -0.2], "drag_coefficient": [1.0, 1.2, 1.3]}}
    rho, speed = 1000.0, 0.6  # nr_netting: input water_density 1000, current 0.6 m/s along x
    per_node = 0.5 * rho * 1.0 * 0.5 * 0.2 * speed**2  # 18 N
    total = figures.forces_by_term(scene, scene.nodes.position)["node_box_drag"]
    np.testing.assert_allclose(total, [len(sinker) * per_node, 0.0, 0.0], rtol=1e-12, atol=1e-9)


def test_a_floor_holds_the_sinker_rope_no_deeper_than_its_load_over_the_stiffness(tmp_path):
    case = femnet.read_don(_write(tmp_path, _case_text()))
    scene, solver = case.scene, case.solver
    eq = solve(scene, solver)
    x = np.asarray(eq.x)
    sinker = _sinker_nodes(scene)
    penetration = -2.5 - x[sinker, 2]
    # without the floor FEMNET's equilibrium sinks the rope to z = -2.5994 m (nr_netting.sta): the floor bites
    assert penetration.max() > 0
    by_term = figures.forces_by_term(scene, x)
    # FEMNET's law, k times the penetration of every node below the floor (no band): the contact's total force
    np.testing.assert_allclose(by_term["bottom_contact"], [0, 0, K_BOTTOM * np.clip(penetration, 0, None).sum()],
                               rtol=1e-9, atol=1e-9)
    # the fixings hold the net up, so the floor carries at most the downward loads: the weight in water
    # (the sinker rope's alone is pi/4 D^2 L (5665 - 1000) 9.81 = 36.8 N) and any downward drag
    fixed = np.asarray(scene.nodes.fixed)
    assert np.where(fixed, -np.asarray(eq.force), 0.0).sum(axis=0)[2] > 0
    # the constant loads and, FEMNET's surface z = 0 being modelled, the bars' weight and buoyancy as an energy
    weight = -(figures.total_load(scene)[2] + sum(by_term[t][2] for t in by_term if t.endswith("gravity_at_surface")))
    drag_down = max(0.0, -sum(by_term[t][2] for t in ("netting_drag", "bar_drag") if t in by_term))
    rope = np.pi / 4 * 0.0225**2 * 2.02 * (5665.0 - 1000.0) * 9.81
    assert rope < weight < rope + 3.0  # the netting (38400 twines) weighs 2.0 N, the other ropes 0.3 N
    bound = (weight + drag_down) / K_BOTTOM
    assert penetration.max() <= bound, (penetration.max(), bound)
    assert x[:, 2].min() >= -2.5 - bound


# -- errors name the line ---------------------------------------------------------------------------


@pytest.mark.parametrize("changes, needle, words", [
    (dict(length=(-0.1, 0.5, 0)), "Length X,Y,Z", "length X must be >= 0"),
    (dict(length=(0, 0.5, 1e6)), "Length X,Y,Z", "out of range"),
    (dict(sense=(0, 0, 2)), "Limits sens X,Y,Z", "limits sense must be -1"),
    (dict(limit=(0, 0, -2e5)), "Limits X,Y,Z", "out of range"),
    # a floor without a stiffness does nothing in FEMNET (fond.c): refused at the stiffness's line
    (dict(stiffness="0.0"), "Stiffness of the insertion", "with 0 it does nothing"),
    (dict(inputs=("moving_bottom 1",)), "input moving_bottom 1", "expected 0 finite number"),
])
def test_errors_name_the_line(tmp_path, changes, needle, words):
    text = _case_text(**changes)
    path = _write(tmp_path, text)
    with pytest.raises(SceneError) as err:
        femnet.read_don(path)
    message = str(err.value)
    after = "No du type :            3" if needle in ("Length X,Y,Z", "Limits X,Y,Z", "Limits sens X,Y,Z") else None
    assert words in message, message
    assert f"case.don:{_line(text, needle, after)}:" in message, message
    if "stiffness" in changes:  # it also says which node type asks for a floor, and where
        assert "node type 3" in message and f"line {_line(text, 'Limits sens X,Y,Z')}" in message, message


# -- Net.body and Net.limit -------------------------------------------------------------------------


def _square(environment):
    net = Net(environment=environment)
    p = net.panel("wall", [(0, 0, 0, 0, 0), (1, 0, 0, 5, -5), (1, 0, -1, 10, 0), (0, 0, -1, 5, 5)],
                  Twine(l0=0.1, ea=1000.0, diameter=0.002), step=0.25)
    net.fix(p.side(3))
    return net, p


def test_net_gives_each_node_the_whole_body_and_limit_and_a_later_call_replaces():
    net, p = _square(Environment(bottom_stiffness=1e4))
    assert net.build().nodes.drag_length is None and net.build().nodes.limit is None
    net.body(p, length=(0.1, 0.2, -0.3), drag_coefficient=(1.0, 1.1, 1.2))
    net.body(p.side(1), length=(0.4, 0.5, 0.6), drag_coefficient=(2.0, 2.1, 2.2))
    net.limit(p, value=(0.0, 0.0, -0.8), sense=(0, 0, 1))
    net.limit(p.corner(2), value=(0.9, float("nan"), 0.0), sense=(-1, 0, 0))  # NaN where there is no sense
    scene = net.build()
    x = np.asarray(scene.nodes.position)
    side = np.isclose(x[:, 0], 1.0)  # side 1: from (1, 0, 0) to (1, 0, -1)
    corner = np.isclose(x[:, 0], 1.0) & np.isclose(x[:, 2], -1.0)
    assert side.sum() >= 3 and corner.sum() == 1
    # not a share: every node has the whole box, the side's replacing the panel's
    np.testing.assert_array_equal(np.asarray(scene.nodes.drag_length), np.where(side[:, None], [0.4, 0.5, 0.6],
                                                                                [0.1, 0.2, -0.3]))
    np.testing.assert_array_equal(np.asarray(scene.nodes.drag_coefficient), np.where(side[:, None], [2.0, 2.1, 2.2],
                                                                                     [1.0, 1.1, 1.2]))
    # the corner's limits replace all three axes of the panel's: its floor is gone
    np.testing.assert_array_equal(np.asarray(scene.nodes.limit_sense), np.where(corner[:, None], [-1, 0, 0], [0, 0, 1]))
    np.testing.assert_array_equal(np.asarray(scene.nodes.limit), np.where(corner[:, None], [0.9, 0.0, 0.0],
                                                                          [0.0, 0.0, -0.8]))
    assert np.asarray(scene.nodes.limit_sense).dtype == np.int32


@pytest.mark.parametrize("call, words", [
    (lambda net, p: net.body(p, length=(-0.1, 0.2, 0.3), drag_coefficient=(1, 1, 1)), "x and y must be >= 0"),
    (lambda net, p: net.body(p, length=(0.1, 0.2), drag_coefficient=(1, 1, 1)), "3 finite values"),
    (lambda net, p: net.body(p, length=(0.1, 0.2, 0.3), drag_coefficient=(1, -1, 1)), "drag_coefficient must be >= 0"),
    (lambda net, p: net.limit(p, value=(0, 0, -1), sense=(0, 0, 2)), r"sense must be \+1"),
    (lambda net, p: net.limit(p, value=(0, 0, float("inf")), sense=(0, 0, 1)), "finite on the axes with a sense"),
])
def test_net_body_and_limit_refuse_bad_values(call, words):
    net, p = _square(Environment(bottom_stiffness=1e4))
    with pytest.raises(SceneError, match=words):
        call(net, p)


def test_net_limit_without_bottom_stiffness_is_refused_at_build():
    net, p = _square(Environment())
    net.limit(p, value=(0.0, 0.0, -0.8), sense=(0, 0, 1))
    with pytest.raises(SceneError, match="bottom_stiffness > 0"):
        net.build()
