"""FEMNET's netting drag laws, ``input drag_forces_type N`` (:mod:`jaxnet.terms.drag`'s docstring): 1 Morison
(drag model "twines"), 2 Zhan ("zhan"), 3 drop pressure and 4 Aarnes, which FEMNET's current code leaves out
(commented calls: no netting drag, "none"). Each law on a flat panel against its formula, Zhan's declared
stiffness against finite differences, the reader's mapping and its refusals, and the corpus's b2 (law 3) on
FEMNET's own mesh at FEMNET's equilibrium.
"""

import dataclasses
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxnet import geometry, model as model_lib
from jaxnet.model import assemble
from jaxnet.closed_form.drag import moving_netting_drag_zhan_stiffness, netting_drag_zhan_stiffness
from jaxnet.io import femnet
from jaxnet.materials import DRAG_MODELS
from jaxnet.net import Net, Twine
from jaxnet.scene import SceneError
from jaxnet.solve import programs
from jaxnet.terms import drag as drag_term

jax.config.update("jax_enable_x64", True)

RHO = 1025.0
L0, D = 0.02, 0.002          # m: twine length and diameter
B2 = pathlib.Path(__file__).resolve().parents[1] / "data" / "femnet-corpus" / "3bottom_trawl" / "b2.don"
C1, C2, C3, C4, C5 = 0.137, 1.002, 2.230, -0.211, 0.947   # FEMNET's calculeffort_Zhan.c
ZHAN = {"normal": (C1, C2, C3), "tangential": (C4, C5)}


def _panel(tilt, spin, opening=np.pi / 4, n=10):
    """A triangle of n x n twines of square-ish meshes (half opening ``opening``), in a plane whose normal is
    tilted by ``tilt`` from x (the current's direction) about z, the twines turned by ``spin`` in the plane:
    (x (3, 3), uv (3, 2), U, V, area of the triangle m²)."""
    e1 = np.array([-np.sin(tilt), np.cos(tilt), 0.0])
    e2 = np.array([0.0, 0.0, 1.0])
    a, b = spin + opening, spin - opening      # U and V at ±opening from the spin direction
    U = L0 * (np.cos(a) * e1 + np.sin(a) * e2)
    V = L0 * (np.cos(b) * e1 + np.sin(b) * e2)
    x = np.array([np.zeros(3), n * U, n * V]) + np.array([1.0, 2.0, -3.0])
    uv = np.array([[0.0, 0.0], [n, 0.0], [0.0, n]])
    return x, uv, U, V, 0.5 * np.linalg.norm(np.cross(n * U, n * V))


def _zhan_formula(U, V, c):
    """Force per area (N/m²) of netting of twine vectors U, V in the current c by FEMNET's formulas, written as
    it writes them: magnitudes |c_n| (|c_n| + c1 + c2 |c_n| Sn + c3 |c_n| Sn²) along ĉ_n, |c_t| (|c_t| + c4 +
    c5 |c_t| Sn) along ĉ_t, from the angle α of each twine to the current; one U and one V twine per mesh of
    area |U ^ V|."""
    mesh = np.linalg.norm(np.cross(U, V))
    sn = min(max((4 * D * L0 - D**2) / (2 * mesh), 0.0), 1.0)
    speed = np.linalg.norm(c)
    total = np.zeros(3)
    for w in (U, V):
        cos_a = np.dot(c, w) / (speed * np.linalg.norm(w))
        vn, vt = speed * np.sqrt(max(1 - cos_a**2, 0.0)), speed * abs(cos_a)
        c_t = np.dot(c, w) / np.dot(w, w) * w
        c_n = c - c_t
        unit_n = c_n / vn if vn > 0 else np.zeros(3)
        unit_t = c_t / vt if vt > 0 else np.zeros(3)
        total += 0.5 * RHO * L0 * D * (vn * (vn + C1 + C2 * vn * sn + C3 * vn * sn**2) * unit_n
                                       + vt * (vt + C4 + C5 * vt * sn) * unit_t)
    return total / mesh


def _morison_formula(U, V, c, cd=1.2, f=0.08):
    """Force per area (N/m²) by FEMNET's Morison twine drag (``basic_bar_drag1``): ½ ρ Cd D l0 |c|² sin²α across,
    f ½ ρ Cd D l0 |c|² cos²α along, per twine, one U and one V twine per mesh."""
    speed = np.linalg.norm(c)
    total = np.zeros(3)
    for w in (U, V):
        cos_a = np.dot(c, w) / (speed * np.linalg.norm(w))
        c_t = np.dot(c, w) / np.dot(w, w) * w
        c_n = c - c_t
        normal = 0.5 * RHO * cd * D * L0 * speed**2 * (1 - cos_a**2)
        along = f * 0.5 * RHO * cd * D * L0 * speed**2 * cos_a**2
        total += (normal * c_n / np.linalg.norm(c_n) if np.linalg.norm(c_n) > 0 else 0.0) + along * np.sign(cos_a) * w / np.linalg.norm(w)
    return total / np.linalg.norm(np.cross(U, V))


ANGLES = [(0.0, 0.0), (np.pi / 6, 0.3), (np.pi / 3, -0.4), (1.4, 1.0)]


@pytest.mark.parametrize("tilt, spin", ANGLES)
@pytest.mark.parametrize("speed", [0.15, 1.0, 2.0])
def test_zhan_flat_panel_force_per_area_is_femnets_formula(tilt, spin, speed):
    x, uv, U, V, area = _panel(tilt, spin)
    c = np.array([speed, 0.0, 0.0])
    model = drag_term.NETTING_DRAG_MODELS[DRAG_MODELS["zhan"]]
    f = np.asarray(model.force(jnp.asarray(x), jnp.asarray(uv), L0, D, 1.2, 0.096, jnp.asarray(c), RHO))
    np.testing.assert_allclose(f[0], f[2])   # a third on each vertex
    np.testing.assert_allclose(f.sum(axis=0) / area, _zhan_formula(U, V, c), rtol=1e-12, atol=1e-12)


def test_zhan_numbers_normal_to_a_square_mesh_panel():
    """The current normal to a panel of square meshes (l0 = 20 mm, D = 2 mm): both twines across it, so
    F/A = 2 · ½ ρ D l0 |c|(|c| + c1 + c2 |c| Sn + c3 |c| Sn²) / l0², Sn = (4 D l0 - D²)/(2 l0²) = 0.195;
    at 1 m/s: 1025 · 0.1 · (1.137 + 0.195 · 1.002 + 0.195² · 2.230) = 145.26 N/m², where Morison with Cd = 1.2
    gives 123.0 N/m²; at 0.1 m/s Zhan's c1 = 0.137 m/s makes it 2.07 times its quadratic part."""
    x, uv, U, V, area = _panel(0.0, 0.0)
    sn = float(geometry.diamond_solidity(jnp.asarray(U), jnp.asarray(V), L0, D))
    assert sn == pytest.approx(0.195, rel=1e-12)
    zhan = drag_term.NETTING_DRAG_MODELS[DRAG_MODELS["zhan"]].force
    per_area = float(zhan(x, uv, L0, D, 1.2, 0.096, jnp.array([1.0, 0.0, 0.0]), RHO).sum(axis=0)[0]) / area
    assert per_area == pytest.approx(145.26, abs=0.01)
    twines = drag_term.netting_drag(x, uv, L0, D, 1.2, 0.096, jnp.array([1.0, 0.0, 0.0]), RHO)
    assert float(twines.sum(axis=0)[0]) / area == pytest.approx(123.0, rel=1e-12)
    slow = float(zhan(x, uv, L0, D, 1.2, 0.096, jnp.array([0.1, 0.0, 0.0]), RHO).sum(axis=0)[0]) / area
    quadratic = RHO * D * 0.1 * 0.1 * (1 + C2 * sn + C3 * sn**2) / L0
    assert slow / quadratic == pytest.approx(2.07, abs=0.005)


@pytest.mark.parametrize("tilt, spin", ANGLES)
def test_morison_flat_panel_force_per_area_is_femnets_formula(tilt, spin):
    x, uv, U, V, area = _panel(tilt, spin, opening=0.6)
    c = np.array([1.3, 0.0, 0.0])
    f = np.asarray(drag_term.netting_drag(jnp.asarray(x), jnp.asarray(uv), L0, D, 1.2, 0.08 * 1.2, jnp.asarray(c), RHO))
    np.testing.assert_allclose(f.sum(axis=0) / area, _morison_formula(U, V, c), rtol=1e-12, atol=1e-12)


def test_zhan_tangential_drag_points_upstream_below_its_threshold():
    """FEMNET's c4 = -0.211 m/s: water along a twine slower than -c4/(1 + c5 Sn) pulls it upstream."""
    U = np.array([L0, 0.0, 0.0])
    sn = 0.3
    for speed, sign in ((0.1, -1.0), (0.5, 1.0)):
        normal, tangential = drag_term.zhan_twine_drag(jnp.asarray(U), L0, D, sn, jnp.array([speed, 0.0, 0.0]), RHO)
        assert float(jnp.abs(normal).max()) == 0.0
        expected = 0.5 * RHO * D * L0 * speed * (speed + C4 + C5 * speed * sn)
        assert float(tangential[0]) == pytest.approx(expected, rel=1e-12) and np.sign(expected) == sign


@pytest.mark.parametrize("tilt, spin, opening", [(0.3, 0.2, 0.5), (1.2, -0.7, 0.9), (0.0, 0.0, np.pi / 4)])
def test_zhan_declared_stiffness_is_finite_differences(tilt, spin, opening):
    """K = -∂F/∂x of the closed form against central differences of the force (the solidity moves with the
    meshes' opening; a profile of the current adds dc/dz), and the moving net's against differences of the
    per-vertex forces at the relative velocities."""
    x, uv, _, _, _ = _panel(tilt, spin, opening, n=3)
    x = x + 0.01 * np.array([[0.0, 0.1, 0.2], [0.3, -0.1, 0.0], [0.1, 0.2, -0.3]])   # not flat, not square
    slope, up = np.array([0.05, 0.02, 0.0]), np.array([0.0, 0.0, 1.0])
    c0 = np.array([0.9, 0.3, -0.1])

    def force(y):
        c = c0 + slope * (geometry.centroid(y) @ up)
        return drag_term.netting_drag_zhan(y, uv, L0, D, 1.2, 0.1, c, RHO).ravel()

    c = c0 + slope * (x.mean(axis=0) @ up)
    k = np.asarray(netting_drag_zhan_stiffness(jnp.asarray(x), uv, L0, D, 1.2, 0.1, jnp.asarray(c), RHO, slope, up,
                                               **ZHAN))
    h = 1e-6
    fd = np.zeros((9, 9))
    for j in range(9):
        e = np.zeros(9)
        e[j] = h
        fd[:, j] = -(np.asarray(force(jnp.asarray(x + e.reshape(3, 3)))) - np.asarray(force(jnp.asarray(x - e.reshape(3, 3))))) / (2 * h)
    assert np.abs(k).max() > 0.05
    np.testing.assert_allclose(k, fd, atol=1e-6 * np.abs(k).max())

    # a time step: vertex i's share with c_i = w - (x_i - x_prev_i)/dt, w uniform here
    dt, prev = 0.1, x - 0.02

    def moving(y):
        rel = c0 - (y - prev) / dt
        return jnp.stack([drag_term.netting_drag_zhan(y, uv, L0, D, 1.2, 0.1, rel[i], RHO)[i] for i in range(3)]).ravel()

    rel = c0 - (x - prev) / dt
    km = np.asarray(moving_netting_drag_zhan_stiffness(jnp.asarray(x), uv, L0, D, 1.2, 0.1, jnp.asarray(rel),
                                                        jnp.zeros((3, 3, 3)), dt, RHO, **ZHAN))
    fdm = np.zeros((9, 9))
    for j in range(9):
        e = np.zeros(9)
        e[j] = h
        fdm[:, j] = -(np.asarray(moving(jnp.asarray(x + e.reshape(3, 3)))) - np.asarray(moving(jnp.asarray(x - e.reshape(3, 3))))) / (2 * h)
    np.testing.assert_allclose(km, fdm, atol=1e-6 * np.abs(km).max())


def _square_net(drag_model, env=None):
    net = Net(env)
    # U along y, V along z: 10 twines of 0.1 m each way, in the plane x = 0 across the current
    net.panel("p", [(0, 0, 0, 0, 0), (0, 1, 0, 10, 0), (0, 1, 1, 10, 10), (0, 0, 1, 0, 10)],
              Twine(l0=0.1, ea=1e4, diameter=0.002, drag_model=drag_model), 0.2)
    net.fix((0.0, 0.0, 0.0))
    return net


def test_builder_names_and_terms():
    """drag_model "zhan" and "none" on a Twine: the codes in the scene; "none" alone leaves the netting drag term
    out; mixed with "twines", the "none" triangles get no drag (its force is zero there, the twines' is not)."""
    from jaxnet.scene import Environment

    env = Environment(current_speed=1.0)
    assert [drag_term.NETTING_DRAG_MODELS[DRAG_MODELS[n]].name for n in ("zhan", "none")] == ["zhan", "none"]
    for name in ("zhan", "none"):
        scene = _square_net(name, env).build()
        assert set(np.asarray(scene.netting.drag_model).tolist()) == {DRAG_MODELS[name]}
        names = [t.name for t in model_lib.active_terms(scene)]
        assert ("netting_drag" in names) == (name == "zhan")
    net = _square_net("twines", env)
    net.panel("q", [(1, 0, 0, 0, 0), (1, 1, 0, 10, 0), (1, 1, 1, 10, 10), (1, 0, 1, 0, 10)],
              Twine(l0=0.1, ea=1e4, diameter=0.002, drag_model="none"), 0.2)
    net.fix((1.0, 0.0, 0.0))
    scene = net.build()
    model = model_lib.active_terms(scene)
    x = jnp.asarray(scene.nodes.position)
    f = np.asarray(assemble.nodal_force(x, scene, model, assemble.loads(scene, model)))
    on_q = np.asarray(scene.nodes.position)[:, 0] > 0.5
    # weight and buoyancy are vertical: the x components are the drag's (fixed nodes: their reaction left out)
    free = ~np.asarray(scene.nodes.fixed).any(axis=1)
    assert np.abs(f[on_q & free, 0]).max() < 1e-12 < 1e-3 < np.abs(f[~on_q & free, 0]).max()
    with pytest.raises(SceneError, match="drag_model must be one of"):
        _square_net("drop-pressure", env).build()


def _b2_with(tmp_path, line):
    text = B2.read_text()
    assert "input drag_forces_type 3" in text
    out = tmp_path / "b2.don"
    out.write_text(text.replace("input drag_forces_type 3", line))
    return out


@pytest.mark.parametrize("law, model", [(1, "twines"), (2, "zhan"), (3, "none"), (4, "none")])
def test_reader_maps_each_law(tmp_path, law, model):
    don = B2 if law == 3 else _b2_with(tmp_path, f"input drag_forces_type {law}")
    parsed = femnet.parse_don(don)
    assert parsed.inputs["drag_forces_type"].value == law
    assert femnet.materials.drag_law(parsed) == model
    case = femnet.read_mdg(B2.with_suffix(".mdg"), don)
    assert set(np.asarray(case.scene.netting.drag_model).tolist()) == {DRAG_MODELS[model]}


@pytest.mark.parametrize("value", ["0", "5", "2.5"])
def test_reader_refuses_another_law_at_its_line(tmp_path, value):
    don = _b2_with(tmp_path, f"input drag_forces_type {value}")
    with pytest.raises(SceneError, match=r"b2\.don:(\d+): .*drag_forces_type") as err:
        femnet.parse_don(don)
    line = int(str(err.value).split(":")[1])
    assert don.read_text().split("\n")[line - 1].startswith("input drag_forces_type")


def test_b2_on_femnets_mesh_at_femnets_equilibrium():
    """b2 (law 3) on FEMNET's mesh (b2.mdg) at its equilibrium (b2.sta, whose "surface drag (N)" is 0.0): with no
    netting drag jaxnet's nodal residual is 0.2 N mean (99 % of the nodes under 1 N; two nodes on the sea bed at
    the ground rope's end carry 55 N and 4 N: FEMNET's contact kink, as b1 has), while giving the netting the
    Morison drag of law 1 leaves 66 N mean: FEMNET's law 3 is no drag."""
    case = femnet.read_mdg(B2.with_suffix(".mdg"), B2)
    scene = case.scene
    pos, _, _, summary = femnet.read_sta(B2.with_suffix(".sta"), scene.n_nodes, scene.bars.ends.shape[0],
                                         scene.netting.vertices.shape[0])
    assert summary["surface drag (N)"][0] == 0.0

    # one compiled program per set of terms (op by op, the element vmaps would compile dozens of small
    # programs), with the XLA options of jaxnet's own programs
    nodal_force = programs.jit(lambda x, s, model: assemble.nodal_force(x, s, model, assemble.loads(s, model)),
                               static_argnames="model")

    def residual(s):
        model = model_lib.active_terms(s)
        force = np.asarray(nodal_force(jnp.asarray(pos), s, model))
        return np.linalg.norm(np.where(np.asarray(s.nodes.fixed), 0.0, force), axis=1), [t.name for t in model]

    nodal, names = residual(scene)
    assert "netting_drag" not in names and "bar_drag" in names
    assert nodal.mean() < 0.25 and np.percentile(nodal, 99) < 1.0 and np.sort(nodal)[-3] < 2.0, (nodal.mean(), np.sort(nodal)[-5:])
    twines = dataclasses.replace(scene, netting=dataclasses.replace(
        scene.netting, drag_model=np.full_like(np.asarray(scene.netting.drag_model), DRAG_MODELS["twines"])))
    with_drag, _ = residual(twines)
    assert with_drag.mean() > 50.0
