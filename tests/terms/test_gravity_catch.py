"""The gravity catch (FEMNET's ``input catch_gravity``, :mod:`jaxnet.terms.gravity_catch`): its law against closed
forms (a box, a bowl), its declared stiffness against finite differences, the builder and the reader, and
FEMNET's case 13gravity_catch/g1 against FEMNET's answer (``ANSWERS.md``: 0 0 -262.26738 N).

The cases are FEMNET's own (copied into ``tests/data/femnet-corpus`` with its MIT licence, copyright 2026 dpriour).
"""

from __future__ import annotations

import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxnet import figures, model
from jaxnet.model.catch import catch_front, catch_state
from jaxnet.closed_form.gravity_catch import gravity_catch_stiffness
from jaxnet.io import femnet
from jaxnet.build import outward
from jaxnet.net import Net
from jaxnet.scene import Environment, SceneError
from jaxnet.terms import gravity_catch as gc

CORPUS = pathlib.Path(__file__).resolve().parents[1] / "data" / "femnet-corpus"
G1 = CORPUS / "13gravity_catch" / "g1.don"
RHO_C, G = 1000.0, 9.81
GAMMA = RHO_C * G  # specific weight of the catch (N/m³)
DOWN = np.array([0.0, 0.0, -1.0])


def _grid(origin, du, dv, nu, nv):
    """Nodes (nu+1)(nv+1) of the parallelogram origin + i du/nu + j dv/nv and its triangles, 12 ^ 13 along du ^ dv."""
    i, j = np.meshgrid(np.arange(nu + 1), np.arange(nv + 1), indexing="ij")
    x = origin + i.reshape(-1, 1) * du / nu + j.reshape(-1, 1) * dv / nv
    k = lambda a, b: a * (nv + 1) + b  # noqa: E731
    tri = [t for a in range(nu) for b in range(nv)
           for t in ((k(a, b), k(a + 1, b), k(a + 1, b + 1)), (k(a, b), k(a + 1, b + 1), k(a, b + 1)))]
    return x, np.array(tri)


def _box(side=1.0, height=1.0, n=4, rows=5):
    """An open box of netting (bottom at z = 0, four walls up to z = height), its faces meshed apart (an edge's
    nodes repeated: the volume and the forces are sums over triangles). Returns positions, triangles, outward."""
    L, H = side, height
    faces = [(np.array([-L / 2, -L / 2, 0.0]), np.array([L, 0, 0]), np.array([0, L, 0]), n, n)]
    corners = [(-L / 2, -L / 2), (L / 2, -L / 2), (L / 2, L / 2), (-L / 2, L / 2)]
    for (ax, ay), (bx, by) in zip(corners, corners[1:] + corners[:1]):
        faces.append((np.array([ax, ay, 0.0]), np.array([bx - ax, by - ay, 0.0]), np.array([0, 0, H]), n, rows))
    xs, ts, offset = [], [], 0
    for origin, du, dv, nu, nv in faces:
        x, t = _grid(origin, du, dv, nu, nv)
        xs.append(x)
        ts.append(t + offset)
        offset += len(x)
    x, tri = np.concatenate(xs), np.concatenate(ts)
    return x, tri, outward(x, tri, np.array([0.0, 0.0, H]))


def _forces(x, tri, sign, front):
    f = jax.vmap(gc.gravity_catch_pressure, in_axes=(0, None, None, None, 0))(
        jnp.asarray(x[tri]), GAMMA, front, jnp.asarray(DOWN), jnp.asarray(sign))
    return np.asarray(f)


def test_box_holds_its_catch_with_its_weight_and_hydrostatic_walls():
    """An open box 1 m square: a 0.6 m³ catch fills it to 0.6 m, a row of nodes (5 rows on 1 m: 0.2 m apart), so no
    triangle is cut. The catch's force on the box is its weight ρ_c g V down, and each wall carries ρ_c g h² / 2 per
    metre of width outward (exact: p_e is the exact mean pressure of a triangle wholly below the level)."""
    x, tri, sign = _box()
    front = catch_front(jnp.asarray(x), jnp.asarray(tri), jnp.asarray(DOWN), 0.6, sign=jnp.asarray(sign))
    assert bool(front.holds) and float(-front.position) == pytest.approx(0.6, abs=1e-9)  # the level, m
    f = _forces(x, tri, sign, front.position)
    np.testing.assert_allclose(f.sum(axis=(0, 1)), [0.0, 0.0, -GAMMA * 0.6], atol=1e-8)
    east = np.all(np.isclose(x[tri][:, :, 0], 0.5), axis=1)  # the wall x = +0.5 m
    np.testing.assert_allclose(f[east].sum(axis=(0, 1)), [GAMMA * 0.6**2 / 2, 0.0, 0.0], rtol=1e-12, atol=1e-8)
    # FEMNET shares each triangle's force equally between its vertices (1/3 each), deep or not
    bottom = np.all(np.isclose(x[tri][:, :, 2], 0.0), axis=1)
    np.testing.assert_allclose(f[bottom][:, :, 2], GAMMA * 0.6 * (1.0 / 16) / 2 / 3 * -1.0, rtol=1e-12)


def _bowl(n_rings, radius=1.0, n_sectors=16):
    """A hemispherical bowl (open at z = 0, bottom at -radius) of n_rings rings of triangles."""
    rings = [np.array([[0.0, 0.0, -radius]])]
    for k in range(1, n_rings + 1):
        phi = 0.5 * np.pi * k / n_rings  # from the bottom
        a = 2 * np.pi * np.arange(n_sectors) / n_sectors
        rings.append(np.stack([radius * np.sin(phi) * np.cos(a), radius * np.sin(phi) * np.sin(a),
                               -radius * np.cos(phi) * np.ones_like(a)], axis=1))
    x = np.concatenate(rings)
    start = np.cumsum([0] + [len(r) for r in rings])
    tri = [(0, start[1] + s, start[1] + (s + 1) % n_sectors) for s in range(n_sectors)]
    for k in range(1, n_rings):
        for s in range(n_sectors):
            a, b = start[k] + s, start[k] + (s + 1) % n_sectors
            c, d = start[k + 1] + s, start[k + 1] + (s + 1) % n_sectors
            tri += [(a, c, d), (a, d, b)]
    tri = np.array(tri)
    return x, tri, outward(x, tri, np.zeros(3))


def test_bowl_weight_is_exact_hydrostatics_up_to_the_triangles_the_level_cuts():
    """A hemispherical bowl holding a third of what it can: the level cuts triangles. The exact hydrostatic force on
    the netting below the level is the catch's weight ρ_c g V to round-off (divergence theorem on the discrete
    bowl); FEMNET's law, the pressure of each whole triangle's centroid, differs on the cut triangles only, by an
    amount that shrinks as the mesh is refined."""
    errors = []
    for n_rings in (4, 8, 16):
        x, tri, sign = _bowl(n_rings, n_sectors=4 * n_rings)
        full = float(catch_front(jnp.asarray(x), jnp.asarray(tri), jnp.asarray(DOWN), 10.0, sign=jnp.asarray(sign)).volume)
        v = full / 3.0
        front = catch_front(jnp.asarray(x), jnp.asarray(tri), jnp.asarray(DOWN), v, sign=jnp.asarray(sign))
        exact = jax.vmap(gc.hydrostatic_resultant, in_axes=(0, None, None, None, 0))(
            jnp.asarray(x[tri]), GAMMA, front.position, jnp.asarray(DOWN), jnp.asarray(sign))
        np.testing.assert_allclose(np.asarray(exact).sum(axis=0), [0.0, 0.0, -GAMMA * v], rtol=1e-10, atol=1e-8)
        femnet_law = _forces(x, tri, sign, front.position).sum(axis=(0, 1))
        assert abs(femnet_law[0]) < 1e-9 and abs(femnet_law[1]) < 1e-9
        errors.append(abs(femnet_law[2] / (-GAMMA * v) - 1.0))
    assert errors[0] < 0.05 and errors[2] < errors[1] < errors[0] and errors[2] < 0.01, errors


@pytest.mark.parametrize("offset", [-0.9, -0.3, 0.0, 0.4, 2.0])
def test_declared_stiffness_against_autodiff_and_finite_differences(offset):
    """The closed form (the catch's stiffness at the element's pressure, plus ∂p_e/∂x = ρ_c g a / 3) is -∂F/∂x: on a
    triangle the level cuts (one or two vertices below) or not, against jacfwd and central differences."""
    x = np.array([[0.1, 0.2, 0.0], [0.9, -0.1, -0.8], [0.3, 0.7, -1.3]])
    front = float(np.mean(x @ DOWN)) + offset
    k = np.asarray(gravity_catch_stiffness(x, GAMMA, front, DOWN, -1.0))
    f = lambda y: gc.gravity_catch_pressure(y.reshape(3, 3), GAMMA, front, jnp.asarray(DOWN), -1.0).reshape(9)  # noqa: E731
    np.testing.assert_allclose(k, -np.asarray(jax.jacfwd(f)(jnp.asarray(x).reshape(9))), rtol=1e-12, atol=1e-9)
    h = 1e-6
    fd = np.stack([(np.asarray(f(jnp.asarray(x.reshape(9) + h * e))) - np.asarray(f(jnp.asarray(x.reshape(9) - h * e))))
                   / (2 * h) for e in np.eye(9)], axis=1)
    np.testing.assert_allclose(k, -fd, rtol=1e-6, atol=1e-4 * np.abs(k).max())
    if offset > 1.0:  # the triangle is wholly above the level: no force, no stiffness
        assert np.abs(k).max() == 0.0
    else:
        assert np.abs(k).max() > 100.0  # a real stiffness (N/m), not zeros


def test_builder_gravity_catch_points_down_and_replaces_the_dynamic_pressure():
    """Net.catch(density=...): the axis defaults to down, no current is needed, the term is the gravity catch (the
    dynamic catch pressure stays out even in a current), and its state holds ρ_c g."""
    x, tri, _ = _box(n=2, rows=2)
    for current in (0.0, 0.5):
        net = Net(Environment(current_speed=current))
        p = net.panel("bottom", [(-0.5, -0.5, 0.0, 0, 0), (0.5, -0.5, 0.0, 20, 0), (0.5, 0.5, 0.0, 20, 20),
                                 (-0.5, 0.5, 0.0, 0, 20)], _twine(), 0.25)
        net.fix(p.side(0))
        net.catch(0.1, center=(0.0, 0.0, 1.0), density=RHO_C)
        scene = net.build()
        np.testing.assert_allclose(scene.catch.axis, DOWN)
        names = [t.name for t in model.active_terms(scene)]
        assert "gravity_catch" in names and "catch_pressure" not in names
        state = catch_state(jnp.asarray(scene.nodes.position), scene)
        assert float(state["specific_weight"]) == pytest.approx(GAMMA)
    with pytest.raises(SceneError, match=r"catch: density must be finite and >= 0"):
        Net().catch(0.1, density=-1.0)


def _twine():
    from jaxnet.net import Twine

    return Twine(l0=0.05, ea=1000.0, diameter=1e-3)


def test_g1_reads_its_gravity_catch():
    case = femnet.read_don(G1)
    c = case.scene.catch
    assert float(c.density) == RHO_C and float(c.volume) == pytest.approx(0.0265) and float(c.symmetry) == 1.0
    np.testing.assert_allclose(c.axis, DOWN)
    assert float(c.center[2]) == pytest.approx(10.0)  # the opening: the bag's top
    names = [t.name for t in model.active_terms(case.scene)]
    assert "gravity_catch" in names and "cable_bending" in names and "catch_pressure" not in names


def test_g1_law_on_femnets_mesh_and_equilibrium_is_femnets_force():
    """FEMNET's mesh and its equilibrium (g1.mdg, g1.sta): the level jaxnet finds for the volume and the force of
    the law are FEMNET's (level 9.025 m, thickness 0.452 m, diameter 0.380 m, 262.26737 N on the fixings = the catch's
    268.14 N less the twines' buoyancy 5.89 N, which FEMNET counts out of the water too), while the exact hydrostatic
    force is the catch's weight ρ_c g V = 259.97 N: FEMNET's centroid pressure on the cut triangles of its coarse mesh
    adds 3.1 %."""
    from jaxnet.io.femnet.results import read_sta

    case = femnet.read_mdg(G1.with_suffix(".mdg"), G1)
    scene = case.scene
    pos, *_ = read_sta(G1.with_suffix(".sta"), scene.n_nodes, scene.bars.ends.shape[0], scene.netting.vertices.shape[0])
    report = figures.catch_report(scene, pos)
    assert report["holds_the_volume"] and -report["front_m"] == pytest.approx(9.025, abs=5e-4)
    assert report["thickness_m"] == pytest.approx(0.452, abs=5e-4) and report["diameter_m"] == pytest.approx(0.380, abs=5e-4)
    forces = figures.force_breakdown(scene, pos)
    total = forces["catch_weight_N"] + forces["weight_and_buoyancy_N"]
    np.testing.assert_allclose(total, [0.0, 0.0, -262.26737], atol=0.02)
    state = catch_state(jnp.asarray(pos), scene)
    exact = jax.vmap(gc.hydrostatic_resultant, in_axes=(0, None, None, None, 0))(
        jnp.asarray(pos[np.asarray(scene.netting.vertices)]), state["specific_weight"], state["front"], state["axis"],
        jnp.asarray(scene.netting.outward))
    assert float(np.asarray(exact).sum(axis=0)[2]) == pytest.approx(-GAMMA * 0.0265, rel=1e-9)
    assert forces["catch_weight_N"][2] / (-GAMMA * 0.0265) - 1.0 == pytest.approx(0.0315, abs=0.001)


def test_g1_solved_on_jaxnets_mesh_against_femnet():
    """g1 solved from its drawn shape on jaxnet's mesh (94 nodes; FEMNET's has 64): the bag holds the catch with its
    level near FEMNET's, and the force on the fixings is within 2 % of FEMNET's 262.27 N. The remaining 1.7 % is the
    law's dependence on the mesh, measured: on jaxnet's mesh the catch's force exceeds its weight ρ_c g V by 1.4 %,
    on FEMNET's by 3.1 % (previous test); the buoyancy of the twines (5.89 N) is the same on both."""
    from jaxnet.solve.statics import solve

    case = femnet.read_don(G1)
    eq = solve(case.scene, case.solver)
    assert eq.converged
    fig = femnet.femnet_figures(case.scene, eq, case.info["symmetry_axes"], case.info["fixity"])
    total = np.array(fig["total_force_N"])
    assert abs(total[2] / -262.26737 - 1.0) < 0.02 and np.abs(total[:2]).max() < 0.01 * 262.27, total
    forces = figures.force_breakdown(case.scene, eq.x)
    # the twines' buoyancy (5.888 N: FEMNET's statics keep diamond netting buoyant out of the water) less the
    # weight of the bag's bars, which lie above FEMNET's surface z = 0 and float by their immersed part, none
    assert forces["weight_and_buoyancy_N"][2] == pytest.approx(5.876, abs=2e-3)
    excess = forces["catch_weight_N"][2] / (-GAMMA * 0.0265) - 1.0
    assert 0.005 < excess < 0.025, excess
    assert fig["catch"]["holds_the_volume"] and -fig["catch"]["front_m"] == pytest.approx(9.025, abs=0.05)


@pytest.mark.parametrize("old, new, message", [
    ("input catch_gravity 1000", "input catch_gravity -5", r"g1\.don:(\d+): 'input catch_gravity': the catch's density must be > 0"),
    ("Current speed (m/s):\t\t\t\t\t0.000000", "Current speed (m/s):\t\t\t\t\t1.000000",
     r"g1\.don:(\d+): 'input catch_gravity' with a current of 1\.0 m/s: FEMNET then gives the netting no drag"),
])
def test_g1_bad_gravity_catch_names_its_line(tmp_path, old, new, message):
    text = G1.read_text()
    assert old in text
    bad = tmp_path / "g1.don"
    bad.write_text(text.replace(old, new, 1))
    with pytest.raises(SceneError, match=message) as err:
        femnet.read_don(bad)
    line = int(err.value.args[0].split(":")[1])
    assert bad.read_text().split("\n")[line - 1].startswith("input catch_gravity")


def test_panel_catches_beside_a_gravity_catch_carry_nothing(tmp_path):
    """``input catch2_volume VOLUME N PANEL...`` beside a gravity catch: FEMNET's statics call its panel catches only
    without one (``unix.c``: ``nb_catch2_volume != 0 && catch_gravity == 0``); jaxnet reads them, and with no current
    (the gravity catch's case) their pressure term is not even active."""
    text = G1.read_text().replace("input link 0.001", "input link 0.001\ninput catch2_volume 0.01 2 1 2", 1)
    path = tmp_path / "g1.don"
    path.write_text(text)
    case = femnet.read_don(path)
    assert case.scene.panel_catches is not None and case.scene.environment.current_speed == 0.0
    names = [t.name for t in model.active_terms(case.scene)]
    assert "gravity_catch" in names and "panel_catch_pressure" not in names
