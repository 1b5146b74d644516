"""A tarp (FEMNET's ``input tarp PANEL``, :mod:`jaxnet.terms.tarp`): the law against its closed form, its declared
stiffness against finite differences, the builder and the reader, and FEMNET's case 14tarp/c2 against its answer.

The cases are FEMNET's own (copied into ``tests/data/femnet-corpus`` with its MIT licence, copyright 2026 dpriour); 14tarp/c2's answer
is FEMNET's current code's (``ANSWERS.md``: 3350.90959 0 0 N on its fixings, 300 iterations).
"""

from __future__ import annotations

import dataclasses
import pathlib

import jax
import numpy as np
import pytest

from jaxnet import figures
from jaxnet.closed_form import tarp as tarp_closed_form
from jaxnet.io import femnet
from jaxnet.net import Net, Twine
from jaxnet.scene import Environment, SceneError
from jaxnet.solve.statics import solve
from jaxnet.terms import tarp, term as term_lib

CORPUS = pathlib.Path(__file__).resolve().parents[1] / "data" / "femnet-corpus"
RHO, C, U = 1025.0, 1.4, 1.9
P = C * 0.5 * RHO * U**2  # 2590.0 Pa: 14tarp/c2's tarp pressure
C2_FEMNET_X = 3350.90959  # N, ANSWERS.md


def _triangle_normal_to_x(tilt=0.0):
    """A right triangle of legs 0.3 m (y) and 0.2 m (z), surface 0.03 m², turned by ``tilt`` (rad) about z; twine
    coordinates with d = +1."""
    x = np.array([[0.0, 0.0, 0.0], [0.0, 0.3, 0.0], [0.0, 0.0, 0.2]])
    c, s = np.cos(tilt), np.sin(tilt)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    return x @ rot.T, uv


def test_flat_triangle_across_the_flow_takes_the_pressure_on_its_surface():
    """Across the flow: C ½ρU² S along the normal, a third per vertex, on the side -sign(d) (12 ^ 13)."""
    x, uv = _triangle_normal_to_x()
    f = np.asarray(tarp.tarp_pressure(x, uv, C, np.array([U, 0.0, 0.0]), RHO))
    # 12 ^ 13 = (0.3 e_y) ^ (0.2 e_z) = +0.06 e_x, d = +1: pushed towards -x, 2590 Pa x 0.03 m² = 77.70 N
    np.testing.assert_allclose(f.sum(axis=0), [-P * 0.03, 0.0, 0.0], rtol=1e-14)
    np.testing.assert_allclose(f, np.tile(f.sum(axis=0) / 3.0, (3, 1)), rtol=1e-14)
    # the side is the twine frame's: V coordinates flipped (d = -1), the force turns over
    flipped = np.asarray(tarp.tarp_pressure(x, uv * [1.0, -1.0], C, np.array([U, 0.0, 0.0]), RHO))
    np.testing.assert_allclose(flipped, -f, rtol=1e-14)
    # and not the flow's: the current reversed pushes the same way (|c|² only)
    np.testing.assert_allclose(np.asarray(tarp.tarp_pressure(x, uv, C, np.array([-U, 0.0, 0.0]), RHO)), f, rtol=1e-14)


@pytest.mark.parametrize("tilt_deg", [30.0, 60.0, 90.0])
def test_the_pressure_does_not_depend_on_the_angle_to_the_current(tilt_deg):
    """FEMNET's law has no angle (catch_hexa.c: ``pression * surface``): the triangle turned by 30°, 60° or 90°
    about z (at 90° the flow runs along it) keeps |F| = p S, along its own normal."""
    x, uv = _triangle_normal_to_x(np.radians(tilt_deg))
    f = np.asarray(tarp.tarp_pressure(x, uv, C, np.array([U, 0.0, 0.0]), RHO)).sum(axis=0)
    t = np.radians(tilt_deg)
    np.testing.assert_allclose(f, -P * 0.03 * np.array([np.cos(t), np.sin(t), 0.0]), rtol=1e-13, atol=1e-12)


def _scene_env(profile):
    env = Environment(current_speed=U)
    if profile:  # the current halves 20 m down: its slope acts on the pressure through the centroid's depth
        env = dataclasses.replace(env, profile_depth=np.array([0.0, 20.0]), profile_factor=np.array([1.0, 0.5]))
    return env


@pytest.mark.parametrize("profile", [False, True])
def test_declared_stiffness_is_the_finite_difference_jacobian(profile):
    """The declared closed form K = -dF/dx of a skewed triangle 5 m down, in a uniform current and in one
    varying with depth, against central differences of the element force (h = 1e-6 m)."""
    env = _scene_env(profile)
    x = np.array([[0.1, -0.2, -5.0], [0.4, 0.5, -5.3], [-0.2, 0.3, -4.6]])
    uv = np.array([[0.0, 0.0], [3.0, 1.0], [1.0, 4.0]])
    declared = term_lib.resolve(tarp.TARP_PRESSURE.closed_form.stiffness)
    assert declared is tarp_closed_form.tarp_pressure_on_element_stiffness
    k = np.asarray(declared(x, None, uv, C, env))

    def force(flat):
        return np.asarray(tarp.tarp_pressure_on_element(flat.reshape(3, 3), None, uv, C, env)).ravel()

    h, fd = 1e-6, np.zeros((9, 9))
    for j in range(9):
        e = np.zeros(9)
        e[j] = h
        fd[:, j] = -(force(x.ravel() + e) - force(x.ravel() - e)) / (2 * h)
    assert np.abs(k).max() > 100.0  # N/m: p times metres
    np.testing.assert_allclose(k, fd, rtol=1e-7, atol=1e-6 * np.abs(k).max())
    auto = -np.asarray(jax.jacfwd(lambda y: tarp.tarp_pressure_on_element(y.reshape(3, 3), None, uv, C, env).ravel())(x.ravel()))
    np.testing.assert_allclose(k, auto, rtol=1e-12, atol=1e-10 * np.abs(k).max())
    if profile:  # the depth term is there: without it the matrix differs
        uniform = np.asarray(declared(x, None, uv, C, _scene_env(False)))
        assert np.abs(k - uniform).max() > 1e-3 * np.abs(k).max()


def _square(net, name, twine):
    """A 1 m x 1 m panel in the plane x = 0 (U along y, V along z: U ^ V along +x), fixed all round."""
    corners = [(0.0, 0.0, -1.0, 0, 0), (0.0, 1.0, -1.0, 10, 0), (0.0, 1.0, 0.0, 10, 10), (0.0, 0.0, 0.0, 0, 10)]
    p = net.panel(name, corners, twine, 0.25)
    for k in range(4):
        net.fix(p.side(k))
    return p


def test_a_tarp_panel_in_a_net_has_pressure_and_no_twine_drag():
    """Through the builder: a 1 m² tarp across a 1.9 m/s current takes C ½ρU² x 1 m² (towards -(U ^ V) = -x) in
    the catch group and no netting drag; the same panel as netting has twine drag and no pressure."""
    base = Twine(l0=0.05, ea=1000.0, diameter=2e-3, density=RHO)
    out = {}
    for cd in (0.0, C):
        net = Net(Environment(current_speed=U))
        _square(net, "panel", dataclasses.replace(base, tarp_cd=cd))
        scene = net.build()
        out[cd] = figures.force_breakdown(scene, np.asarray(scene.nodes.position))
    np.testing.assert_allclose(out[C]["catch_N"], [-P, 0.0, 0.0], rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(out[C]["drag_netting_N"], 0.0, atol=1e-12)
    assert out[0.0]["drag_netting_N"][0] > 1.0 and np.allclose(out[0.0]["catch_N"], 0.0)


def test_builder_refuses_a_tarp_with_a_screen_model_or_a_negative_coefficient():
    base = Twine(l0=0.05, ea=1000.0, diameter=2e-3, density=RHO)
    with pytest.raises(SceneError, match=r"panel 'p': a tarp \(tarp_cd 1.4\) .* 'loland' is a screen model"):
        _square(Net(), "p", dataclasses.replace(base, tarp_cd=1.4, drag_model="loland"))
    with pytest.raises(SceneError, match=r"panel 'p': tarp_cd must be >= 0, got -1.0"):
        _square(Net(), "p", dataclasses.replace(base, tarp_cd=-1.0))


def test_c2_on_femnet_mesh_gives_femnet_answer():
    """14tarp/c2: a tube of tarp along the current, closed at its end by a short cable, on FEMNET's own mesh
    (its .mdg, 17 nodes): the catch's Cd (1.4, the .don's "Drag coefficient on this volume") pushes every
    triangle outward; the reaction on the fixings is FEMNET's 3350.90959 N to 1e-4."""
    case = femnet.read_mdg(CORPUS / "14tarp/c2.mdg", CORPUS / "14tarp/c2.don")
    scene = case.scene
    np.testing.assert_array_equal(np.asarray(scene.netting.tarp_cd), C)
    eq = solve(scene, case.solver)
    assert eq.converged
    fig = femnet.femnet_figures(scene, eq, case.info["symmetry_axes"], case.info["fixity"])
    # FEMNET prints 3350.90959 0 0: its node types 5 and 6 are held along y and z by "Displacement" and lie on
    # the symmetry planes y = 0 and z = 0, where FEMNET sums no reaction (3053 N and 4316 N were summed there)
    np.testing.assert_allclose(fig["total_force_N"], [C2_FEMNET_X, 0.0, 0.0], rtol=1e-4, atol=1e-9)
    assert fig["drag_netting_N"][0] == 0.0  # no twine drag on a tarp


def test_c2_read_from_its_don_on_jaxnets_mesh():
    """14tarp/c2 read from its .don: the tarp is read (its 1.4, FEMNET's drag of cases with a catch for the rest)
    and solved. On jaxnet's own mesh the answer is 21 % above FEMNET's: the panel is 50 x 25 meshes drawn with a
    1.153 m step, 20 triangles, and jaxnet's mesher places its side nodes differently (19 nodes, FEMNET's 17), so
    the inflated bag takes another shape; on FEMNET's mesh the answer is FEMNET's (the test above)."""
    case = femnet.read_don(CORPUS / "14tarp/c2.don")
    scene = case.scene
    assert set(np.asarray(scene.netting.tarp_cd).tolist()) == {C}
    assert set(np.asarray(scene.netting.drag_model).tolist()) == {3}
    eq = solve(scene, case.solver)
    assert eq.converged
    fig = femnet.femnet_figures(scene, eq, case.info["symmetry_axes"], case.info["fixity"])
    assert 1.18 < fig["total_force_N"][0] / C2_FEMNET_X < 1.24, fig["total_force_N"]


def test_a_tarp_naming_no_panel_is_refused_with_its_line(tmp_path):
    text = (CORPUS / "14tarp/c2.don").read_text()
    assert "input tarp 1\n" in text
    bad = tmp_path / "c2.don"
    bad.write_text(text.replace("input tarp 1\n", "input tarp 3\n"))
    with pytest.raises(SceneError, match=r"c2\.don:195: 'input tarp 3': panel 3 does not exist \(diamond panels: 1 to 1\)"):
        femnet.read_don(bad)
    bad.write_text(text.replace("input tarp 1\n", "input tarp 1.5\n"))
    with pytest.raises(SceneError, match=r"c2\.don:195: 'input tarp': the panel number must be a whole number >= 1, got 1.5"):
        femnet.read_don(bad)
