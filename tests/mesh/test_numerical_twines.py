"""Numerical twines (jaxnet.mesh.twines; FEMNET's ``input netting2ropes``): the mesh against FEMNET's, the
material against the triangle element in closed form, and FEMNET's case ``0simple/nr_20_0_0_3_2`` solved.

The data nr_20_0_0_3_2.{don,mdg} are FEMNET's own files (tests/data/femnet/LICENSE). FEMNET's answers are its
current code's (the FEMNET corpus's ``ANSWERS.md``): total force 158.10718 -0.00104 -60.45722 N.
"""

import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.io import femnet
from jaxnet.io.femnet.grammar import twine_coordinates
from jaxnet.materials import Rope, Twine
from jaxnet.mesh.twines import NumericalTwines, mesh_twines, numerical_twine_rope
from jaxnet.net import Net
from jaxnet.scene import SceneError
from jaxnet.solve.statics import solve
from jaxnet.terms import cable, tension
from validation.numerical_twines import with_femnets_second_rope

DATA = pathlib.Path(__file__).parents[1] / "data" / "femnet"
CASE = "nr_20_0_0_3_2"
FEMNET_TOTAL = np.array([158.10718, -0.00104, -60.45722])   # N, FEMNET's current code (ANSWERS.md)

# FEMNET's 0simple/nr_netting panel (U, V meshes) and its start positions (m)
NR_UV = np.array([[0, 0], [80, 0], [80, 120], [0, 120.0]])
NR_XYZ = np.array([[0, -0.735, -1], [0, 0.73, -1], [1.695, 0.73, -1], [1.695, -0.735, -1.0]])


# -- the mesh ---------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("layout, femnet_nodes, femnet_twine_bars, femnet_rope_nodes", [
    # (period, bars, gap U, gap V, accuracy) of the nr_* cases; FEMNET's .mdg: its nodes less the 10 of cables
    # 1 and 2 (not on the panel), its bars of type -1, the nodes inside the sinker rope's side (its 57 - 1 plus
    # the twines' border nodes inserted there)
    ((10, 2, 0.0, 0.0, 3.0), 663 - 10, 768, 56 + 7),
    ((20, 2, 0.25, 0.25, 3.0), 228 - 10, 192, 56 + 8),
    ((20, 2, 0.5, 0.0, 3.0), 231 - 10, 192, 56 + 7),
    ((20, 2, 0.0, 0.0, 3.0), 221 - 10, 192, 56 + 3),
    ((5, 1, 0.0, 0.0, 1.0), 875 - 10, 1536, 56 + 15),
])
def test_mesh_of_the_nr_cases_is_femnets(layout, femnet_nodes, femnet_twine_bars, femnet_rope_nodes):
    period, bars, gu, gv, accuracy = layout
    twines = NumericalTwines(period, bars, gu, gv, accuracy)
    m = mesh_twines(twine_coordinates(NR_UV), NR_XYZ, twines, divisions=[0, 0, 57, 0])
    assert len(m.uv) == femnet_nodes and len(m.bars) == femnet_twine_bars
    # half along u, half along v, every bar a full period / bars twines (the lattice falls on the border)
    assert np.bincount(m.family).tolist() == [femnet_twine_bars // 2] * 2
    np.testing.assert_allclose(m.twines, period / bars)
    assert len(m.side_nodes[2]) - 2 == femnet_rope_nodes
    # nodes sit where their twine coordinates say: the panel's map (u, v) -> (x, y, z) is affine
    A = np.linalg.lstsq(np.c_[twine_coordinates(NR_UV), np.ones(4)], NR_XYZ, rcond=None)[0]
    np.testing.assert_allclose(np.c_[m.uv, np.ones(len(m.uv))] @ A, m.xyz, atol=1e-12)


def test_read_case_has_femnets_nodes_and_bars():
    case = femnet.read_don(DATA / f"{CASE}.don")
    scene = case.scene
    femnet_scene = femnet.read_mdg(DATA / f"{CASE}.mdg", DATA / f"{CASE}.don").scene
    mine = np.bincount(np.asarray(scene.bars.cable))
    theirs = np.bincount(np.asarray(femnet_scene.bars.cable))
    assert scene.n_nodes == femnet_scene.n_nodes == 221
    assert scene.cable_names[-1] == "panel 1 twines" and mine[-1] == theirs[-1] == 192
    # every cable as FEMNET's, but the sinker rope (cable 5): FEMNET's mesher keeps its 57 bars and adds the 60 of
    # the chain through the inserted twine nodes (jaxnet.io.femnet.twines), jaxnet's rope is that chain alone
    assert mine.tolist() == [5, 5, 4, 6, 60, 6, 192] and theirs[4] == 57 + 60
    assert np.delete(mine, 4).tolist() == np.delete(theirs, 4).tolist()
    # the twines' material: the panel's scaled by the period, 20 (FEMNET's lectureDo4.c)
    b = scene.bars
    row = int(np.flatnonzero(np.asarray(b.cable) == 6)[0])
    p = 20.0
    assert (b.ea_traction[row], b.rest_length[row]) == pytest.approx((6000.0 * p, 0.022 * p / 2))
    assert (b.diameter[row], b.cd_normal[row]) == pytest.approx((0.0015 * p ** 0.5, 1.2 * p ** 0.5))
    assert b.tangential_ratio[row] == pytest.approx(0.08 * p ** 0.5)     # FEMNET's, with its laws
    plain = femnet.read_don(DATA / f"{CASE}.don", femnet_laws=False).scene.bars
    assert plain.tangential_ratio[row] == pytest.approx(0.08)


# -- the material, in closed form -------------------------------------------------------------------------------

L0, EA, D = 0.02, 1500.0, 0.002
N_TWINES = 40         # the square panel: 40 x 40 twines, u along x, v along y (square meshes)
STRAIN = 0.01


def _square_net(twines=None):
    side = N_TWINES * L0
    corners = [(0, 0, 0, 0, 0), (side, 0, 0, N_TWINES, 0), (side, side, 0, N_TWINES, N_TWINES),
               (0, N_TWINES * L0, 0, 0, N_TWINES)]
    net = Net()
    twine = Twine(l0=L0, ea=EA, diameter=D, density=1140.0)
    p = net.panel("square", corners, twine, step=5 * L0, twines=twines)
    if twines is not None:
        for k in range(4):
            net.cable(f"rope {k}", along=p.side(k), rope=Rope(ea=1e5, diameter=0.004))
    net.fix(p.side(3))
    return net, net.build()


def _pull_on_side(scene, energy_of, side_nodes):
    """x force (N) the panel's elements exert on the nodes of its side u = N when stretched by STRAIN along x."""
    x = np.asarray(scene.nodes.position).copy()
    x[:, 0] *= 1.0 + STRAIN
    force = -np.asarray(jax.grad(energy_of)(jnp.asarray(x)))
    return -force[side_nodes, 0].sum()


@pytest.mark.parametrize("offset, lines", [(0.5, 4), (0.0, 3)])
def test_numerical_twines_pull_as_the_triangles_of_the_real_twines(offset, lines):
    # 40 u-twine lines of EA, strained by 1 % along x: the side u = 40 is pulled by 40 EA e (the triangle element,
    # exact under a uniform stretch). Numerical twines of period 10 at v = 5, 15, 25, 35 (offset 0.5): 4 lines
    # of EA x 10, the same force. With offset 0 the lines at v = 0 and 40 lie along the sides (left to the
    # ropes): 3 lines inside, 3/4 of it.
    exact = N_TWINES * EA * STRAIN
    net, scene = _square_net()
    tri = np.asarray(scene.netting.vertices)
    uv = jnp.asarray(scene.netting.uv)

    def netting(x):
        return jnp.sum(jax.vmap(lambda t, w: tension.netting_energy(x[t], w, L0, EA))(tri, uv))

    right = net.layout.panel_nodes["square"][net.layout.meshes["square"].side_nodes[1]]
    assert _pull_on_side(scene, netting, right) == pytest.approx(exact, rel=1e-9)

    twines = NumericalTwines(period=10, bars=2, offset_u=offset, offset_v=offset)
    net, scene = _square_net(twines)
    b = scene.bars
    mine = np.flatnonzero(np.asarray(b.cable) == scene.cable_names.index("square twines"))
    ends, rest, ea = np.asarray(b.ends)[mine], np.asarray(b.rest_length)[mine], np.asarray(b.ea_traction)[mine]

    def bars(x):
        return jnp.sum(jax.vmap(lambda e, r, k: cable.bar_energy(x[e], r, k))(ends, rest, ea))

    right = net.layout.panel_nodes["square"][net.layout.meshes["square"].side_nodes[1]]
    assert _pull_on_side(scene, bars, right) == pytest.approx(exact * lines / 4, rel=1e-9)
    # ... and with offset 0.5 they weigh what the netting's 2 x 40 x 40 twines weigh
    twine_mass = 2 * N_TWINES ** 2 * L0 * np.pi * D ** 2 / 4 * 1140.0
    bar_mass = np.sum(rest * np.pi * np.asarray(b.diameter)[mine] ** 2 / 4 * np.asarray(b.density)[mine])
    assert bar_mass == pytest.approx(twine_mass * lines / 4, rel=1e-12)


def test_numerical_twine_rope_scales_by_the_period():
    twine = Twine(l0=0.02, ea=1000.0, diameter=0.002, ea_compression=10.0, cd_normal=1.2, tangential_ratio=0.08)
    rope = numerical_twine_rope(twine, NumericalTwines(period=16))
    assert (rope.ea, rope.ea_compression, rope.diameter, rope.cd_normal, rope.tangential_ratio) == pytest.approx(
        (16000.0, 160.0, 0.008, 4.8, 0.08))
    # drag per length: normal Cd D = 16 x a twine's; FEMNET's tangential f Cd D = 64 x (sqrt(16) more)
    femnet_rope = numerical_twine_rope(twine, NumericalTwines(period=16, femnet_tangential=True))
    assert femnet_rope.tangential_ratio * femnet_rope.cd_normal * femnet_rope.diameter == pytest.approx(
        64 * 0.08 * 1.2 * 0.002)


# -- FEMNET's case, solved --------------------------------------------------------------------------------------

def _total(scene, case):
    eq = solve(scene, case.solver)
    assert eq.converged
    return np.array(femnet.femnet_figures(scene, eq, case.info["symmetry_axes"])["total_force_N"])


def test_nr_20_0_0_3_2_solved_gives_femnets_total_force():
    case = femnet.read_don(DATA / f"{CASE}.don")
    # FEMNET's mesh, solved by jaxnet: its answer to 0.02 % in x and 0.23 % in z (FEMNET stops on the MEAN nodal
    # residual, 1e-3 N here, as tests/io/test_femnet.py measures on nr_netting; FEMNET's stored .sta, of an older
    # code, is at 158.09964 -0.00095 -60.48545)
    on_femnet_mesh = _total(femnet.read_mdg(DATA / f"{CASE}.mdg", DATA / f"{CASE}.don").scene, case)
    assert abs(on_femnet_mesh[0] / FEMNET_TOTAL[0] - 1) < 5e-4
    assert abs(on_femnet_mesh[2] / FEMNET_TOTAL[2] - 1) < 4e-3
    # jaxnet's mesh with FEMNET's second sinker rope (57 bars, validation/numerical_twines.py) gives the same
    # answer as FEMNET's mesh, to 1e-6
    doubled, n_extra = with_femnets_second_rope(case)
    assert n_extra == 57
    np.testing.assert_allclose(_total(doubled, case), on_femnet_mesh, rtol=1e-6, atol=1e-5)
    # jaxnet's mesh as read (one sinker rope): the measured difference is that second rope, 0.974 of the
    # rope's length of a 22.5 mm rope of 5665 kg/m3 (36 N in water) that also drags and stiffens the border:
    # -19.0 N in x and +28.7 N in z (-12.0 %, -47.5 %)
    single = _total(case.scene, case)
    np.testing.assert_allclose(single, [139.1621, 0.0, -31.7367], rtol=1e-4, atol=1e-3)
    assert 18.0 < (on_femnet_mesh - single)[0] < 20.0 and 27.0 < (single - on_femnet_mesh)[2] < 30.0


# -- the reader's and the builder's checks ----------------------------------------------------------------------


def _edited(tmp_path, old, new):
    text = (DATA / f"{CASE}.don").read_text()
    assert old in text
    text = text.replace(old, new)
    path = tmp_path / f"{CASE}.don"
    path.write_text(text)
    return path, text


def _line(text, needle):
    return text[: text.index(needle)].count("\n") + 1


@pytest.mark.parametrize("new, needle, words", [
    # FEMNET's 1pelagic_trawl/s1.don: an older form with 5 values (FEMNET reads BARS from the next line's text,
    # gets 0 and divides by zero: ANSWERS.md)
    ("input netting2ropes 3 10 10 0.0 0.0\n", "input netting2ropes 3", "expected 6 finite number"),
    ("input netting2ropes 2 20 0.0 0.0 3 2\n", "input netting2ropes 2", "panel 2 does not exist"),
    ("input netting2ropes 1 20.5 0.0 0.0 3 2\n", "input netting2ropes 1", "period must be an integer"),
    ("input netting2ropes 1 20 0.0 0.0 3 3\n", "input netting2ropes 1", "multiple of the number of bars"),
    ("input netting2ropes 1 20 0.0 0.0 -1 2\n", "input netting2ropes 1", "accuracy must be >= 0"),
    ("input netting2ropes 1 20 0.0 0.0 3 2\ninput netting2ropes 1 10 0.0 0.0 3 2\n", "input netting2ropes 1 10",
     "given twice"),
])
def test_reader_refuses_bad_netting2ropes_naming_the_line(tmp_path, new, needle, words):
    path, text = _edited(tmp_path, "input netting2ropes 1 20 0.0 0.0 3 2 \n", new)
    with pytest.raises(SceneError) as err:
        femnet.read_don(path)
    assert f"{CASE}.don:{_line(text, needle)}:" in str(err.value) and words in str(err.value), str(err.value)


def test_meshing_type_4_is_numerical_twines(tmp_path):
    # FEMNET's meshing type 4 is what 'input netting2ropes' sets: accepted with the line, refused without it
    path, text = _edited(tmp_path, "Meshing type:\t\t\t\t2", "Meshing type:\t\t\t\t4")
    assert femnet.read_don(path).scene.cable_names[-1] == "panel 1 twines"
    path.write_text(text.replace("input netting2ropes 1 20 0.0 0.0 3 2 \n", ""))
    with pytest.raises(SceneError, match=rf"{CASE}\.don:{_line(text, 'Meshing type')}: panel 1: meshing type 4"):
        femnet.read_don(path)


def test_numerical_twines_need_ropes_all_around():
    net = Net()
    twine = Twine(l0=L0, ea=EA, diameter=D)
    corners = [(0, 0, 0, 0, 0), (0.8, 0, 0, 40, 0), (0.8, 0.8, 0, 40, 40), (0, 0.8, 0, 0, 40)]
    p = net.panel("square", corners, twine, twines=NumericalTwines(period=10, offset_u=0.5, offset_v=0.5))
    for k in range(3):
        net.cable(f"rope {k}", along=p.side(k), rope=Rope(ea=1e5, diameter=0.004))
    net.fix(p.side(0))
    with pytest.raises(SceneError, match="panel 'square': side 3 has no cable sewn along it"):
        net.build()
    with pytest.raises(SceneError, match="period must be > 0"):
        Net().panel("bad", corners, twine, twines=NumericalTwines(period=0))
