"""Sea-bed contact and the friction of a moving bottom (jaxnet.terms.bottom; terms bottom_contact and
bottom_friction), FEMNET's node limits (fond.c).

Checked: the C² penalty (values, continuity of g, g', g'' at contact and at the band's edge, FEMNET's k p
beyond the band, its bound inside it); forces = -grad energy and stiffness = Hessian by finite differences;
friction = mu times the normal reaction along the current, and its tangent (with the entry FEMNET
misplaces); solved, in one scene over a moving bottom: nodes pressed on a floor, a ceiling and a wall
settle at the penetration load/k (and the band's cubic root for a light one), a chain lying on the bottom
is held by a reaction mu times its weight on the floor, a net resting on the floor balances its weight and
its friction; terms compiled only when used; validation; scene files.
"""

import dataclasses
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet as jn
from jaxnet import model
from jaxnet.model import assemble
from jaxnet.io import scene_file
from jaxnet.net import Net, Rope, Twine
from jaxnet.scene.checks import validate
from jaxnet.scene import Environment, SceneError
from jaxnet.terms import bottom
from traced import traced_terms  # tests/traced.py

RHO, G, LEAD = 1025.0, 9.81, 11340.0


def with_limits(scene, limit, sense, **environment):
    """The scene with per-node limits (arrays or rows broadcast to every node) and environment changes."""
    n = scene.n_nodes
    nodes = dataclasses.replace(scene.nodes, limit=np.broadcast_to(np.asarray(limit, dtype=float), (n, 3)).copy(),
                                limit_sense=np.broadcast_to(np.asarray(sense, dtype=np.int32), (n, 3)).copy())
    return dataclasses.replace(scene, nodes=nodes, environment=dataclasses.replace(scene.environment, **environment))


def term_forces(scene, x):
    return {k: np.asarray(v) for k, v in _term_forces(jnp.asarray(x), scene, model=model.active_terms(scene)).items()}


_term_forces = jax.jit(assemble.term_forces, static_argnames=("model",))


# -- the penalty ------------------------------------------------------------------------------------

g = jax.jit(bottom.contact_penalty)
dg = jax.jit(jax.grad(bottom.contact_penalty))
ddg = jax.jit(jax.grad(jax.grad(bottom.contact_penalty)))


def test_penalty_is_c2_and_femnet_beyond_its_band():
    b = 2e-3
    eps = 1e-12
    for p in (0.0, b):  # both joints: value, slope and curvature agree on either side
        for f in (g, dg, ddg):
            assert float(f(p - eps, b)) == pytest.approx(float(f(p + eps, b)), abs=1e-8)
    assert float(g(b, b)) == pytest.approx(5 * b * b / 12, rel=1e-12)
    assert float(ddg(b, b)) == pytest.approx(1.0, rel=1e-9) and float(ddg(0.0, b)) == 0.0
    for p in (1.5 * b, 0.1, 3.0):  # beyond the band: FEMNET's force k p and stiffness k
        assert float(dg(p, b)) == pytest.approx(p, rel=1e-14)
        assert float(bottom.contact_force(p, b)) == pytest.approx(p, rel=1e-14)
        assert float(g(p, b)) == pytest.approx(p * p / 2 - b * b / 12, rel=1e-14)
        assert float(ddg(p, b)) == 1.0
    # inside: softer than FEMNET by p (1 - p/b)², at most 4 b / 27 (at p = b/3); stiffness peaks at 4/3
    p = np.linspace(0.0, b, 301)
    deficit = p - np.asarray(jax.vmap(bottom.contact_force, (0, None))(p, b))
    np.testing.assert_allclose(deficit, p * (1 - p / b) ** 2, atol=1e-18)
    assert deficit.max() == pytest.approx(4 * b / 27, rel=1e-4)
    assert float(ddg(2 * b / 3, b)) == pytest.approx(4 / 3, rel=1e-12)
    np.testing.assert_allclose(np.asarray(jax.vmap(dg, (0, None))(p, b)),
                               np.asarray(jax.vmap(bottom.contact_force, (0, None))(p, b)), rtol=1e-13, atol=1e-18)
    # band 0 is FEMNET's one-sided quadratic, and no side of the limit pulls
    for p in (-1.0, 0.0, 1e-7, 0.5):
        assert float(g(p, 0.0)) == pytest.approx(max(p, 0.0) ** 2 / 2, abs=0.0)
        assert float(bottom.contact_force(p, 0.0)) == max(p, 0.0)
    assert float(g(-0.3, b)) == 0.0 and float(dg(-0.3, b)) == 0.0


energy = jax.jit(bottom.contact_energy)
grad_energy = jax.jit(jax.grad(bottom.contact_energy))
hessian = jax.jit(jax.hessian(bottom.contact_energy))


def test_contact_forces_and_stiffness_are_the_derivatives_of_its_energy(rng):
    k, b, h = 1e4, 1e-2, 1e-7
    for _ in range(6):
        limit = rng.normal(size=3)
        sense = rng.choice([-1, 0, 1], size=3)
        x = limit - sense * rng.uniform(-1.5 * b, 3 * b, size=3)  # outside, in the band and beyond
        fd_grad = np.array([(energy(x + h * e, limit, sense, k, b) - energy(x - h * e, limit, sense, k, b)) / (2 * h)
                            for e in np.eye(3)])
        gr = np.asarray(grad_energy(x, limit, sense, k, b))
        np.testing.assert_allclose(gr, fd_grad, rtol=1e-6, atol=1e-6)
        # the force on a limited coordinate pushes back out: -grad = sense k g'(p)
        p = sense * (limit - x)
        np.testing.assert_allclose(-gr, sense * k * np.asarray(bottom.contact_force(p, b)) * (sense != 0), rtol=1e-12, atol=1e-12)
        fd_hess = np.stack([(np.asarray(grad_energy(x + h * e, limit, sense, k, b))
                             - np.asarray(grad_energy(x - h * e, limit, sense, k, b))) / (2 * h) for e in np.eye(3)], axis=1)
        np.testing.assert_allclose(np.asarray(hessian(x, limit, sense, k, b)), fd_hess, rtol=1e-5, atol=1e-3)
    # a NaN limit on an axis without limit stays out of the value and the derivatives
    x, limit, sense = np.array([0.0, 0.0, -0.1]), np.array([np.nan, np.nan, 0.0]), np.array([0, 0, 1])
    assert np.isfinite(float(energy(x, limit, sense, k, b)))
    assert np.all(np.isfinite(np.asarray(hessian(x, limit, sense, k, b))))


friction = jax.jit(bottom.friction_force, static_argnames=("axis", "floor"))
friction_jac = jax.jit(jax.jacfwd(bottom.friction_force), static_argnames=("axis", "floor"))


def test_friction_is_mu_times_the_normal_reaction_along_the_sliding_bottom():
    k, b, mu = 1e5, 1e-3, 0.4
    theta = np.radians(30.0)
    t = np.asarray(bottom.sliding_direction(np.array([np.cos(theta), np.sin(theta), 0.3]), 2))
    np.testing.assert_allclose(t, [np.cos(theta), np.sin(theta), 0.0], rtol=1e-14)  # heading, as FEMNET
    limit, sense = np.array([0.0, 0.0, -2.0]), np.array([0, 0, 1])
    for depth in (0.3 * b, 5 * b):
        x = np.array([0.1, 0.2, -2.0 - depth])
        normal = -np.asarray(grad_energy(x, limit, sense, k, b))[2]
        f = np.asarray(friction(x, limit, sense, k, b, mu, t, axis=2, floor=1))
        np.testing.assert_allclose(f, mu * normal * t, rtol=1e-13)
        if depth > b:
            assert normal == pytest.approx(k * depth, rel=1e-12)  # FEMNET's amplitude mu k (L - z)
        # tangent: only the vertical column, -dF_y/dz = mu k g'' sin(theta) where FEMNET writes it at (x, y)
        jac = np.asarray(friction_jac(x, limit, sense, k, b, mu, t, axis=2, floor=1))
        h = 1e-8
        fd = np.stack([(np.asarray(friction(x + h * e, limit, sense, k, b, mu, t, axis=2, floor=1))
                        - np.asarray(friction(x - h * e, limit, sense, k, b, mu, t, axis=2, floor=1))) / (2 * h)
                       for e in np.eye(3)], axis=1)
        np.testing.assert_allclose(jac, fd, rtol=1e-6, atol=1e-6)
        curvature = float(ddg(depth, b))
        np.testing.assert_allclose(jac[:, 2], -mu * k * curvature * t, rtol=1e-12)
        np.testing.assert_allclose(jac[:, :2], 0.0, atol=0.0)
    # a ceiling, or a node above its floor, has no friction
    assert not np.any(np.asarray(friction(np.array([0, 0, -1.0]), limit, sense, k, b, mu, t, axis=2, floor=1)))
    ceiling = np.array([0, 0, -1])
    assert not np.any(np.asarray(friction(np.array([0, 0, 1.0]), limit, ceiling, k, b, mu, t, axis=2, floor=1)))


# -- solved: single nodes against a floor, a ceiling, a wall; a chain on a moving bottom --------------

K, BAND, MU = 1e6, 1e-6, 0.5  # N/m, m: a kilogram of lead sinks 8.9 µm, beyond the band; 0.1 kg within it
SLACK = Rope(ea=1e4, ea_compression=0.0, diameter=0.01, density=RHO, cd_normal=0.0)  # neutral, slack
CHAIN = Rope(ea=1e5, diameter=0.02, density=7800.0, cd_normal=0.0)
N_BARS, LENGTH = 10, 5.0
L0, MESHES, NET_Z, FLOOR = 0.05, 4, -3.0, -0.01
HEAVY_TWINE = Twine(l0=L0, ea=500.0, diameter=3e-3, density=1140.0, cd_normal=0.0)
PRESSED = {"heavy": (0.0, 0.0, -1.0), "light": (1.0, 0.0, -1.0), "float": (2.0, 0.0, -0.5), "pushed": (3.0, 0.0, -1.0)}
ANCHORS = {"heavy": (0.0, 0.0, 0.0), "light": (1.0, 0.0, 0.0), "float": (2.0, 0.0, -1.5), "pushed": (2.0, 0.0, -1.0)}


def sea_bed(with_net=True, **environment):
    """In a current along x over a bottom that slides with it (FEMNET's moving_bottom):

    * four bodies, each on a slack neutral rope from a fixed anchor and free along one axis only: 1 kg and
      0.1 kg of lead above a floor at z = -1, a float under a ceiling at z = -0.5, a node pushed by 7 N
      along +x against a wall at x = 3;
    * a chain of 10 bars lying along x on the floor z = -2, held at its upstream end;
    * a panel of 4 x 4 meshes of heavy netting slung at z = -3 between two fixed sides along x, 2 % closer
      than its size: it sags onto a floor 10 mm below, most of it lying there.
    """
    env = dict(current_speed=1.0, bottom_stiffness=K, bottom_band=BAND, bottom_friction=MU) | environment
    net = Net(Environment(**env))
    for name in PRESSED:
        net.cable(name, start=ANCHORS[name], end=PRESSED[name], rope=SLACK, n_bars=1, length=1.2)
        net.fix(ANCHORS[name])
    for name in ("heavy", "light", "float"):
        net.fix(PRESSED[name], axes="xy")
    net.fix(PRESSED["pushed"], axes="yz")
    net.sinker(PRESSED["heavy"], 1.0, LEAD)
    net.sinker(PRESSED["light"], 0.1, LEAD)
    net.float(PRESSED["float"], buoyancy_N=5.0)
    net.attach(PRESSED["pushed"], force=(7.0, 0.0, 0.0))
    net.cable("chain", start=(0.0, -1.0, -2.0), end=(LENGTH, -1.0, -2.0), rope=CHAIN, n_bars=N_BARS)
    net.fix((0.0, -1.0, -2.0))
    if with_net:
        n, shrink = MESHES, 0.98
        a, b = n * 2 * L0 * np.sin(np.radians(40)) * shrink, n * 2 * L0 * np.cos(np.radians(40)) * shrink
        corners = [(0, 2, NET_Z, 0, 0), (a, 2, NET_Z, n, n), (a, 2 + b, NET_Z, 0, 2 * n), (0, 2 + b, NET_Z, -n, n)]
        p = net.panel("net", corners, HEAVY_TWINE, step=0.05)
        net.fix(p.side(0))
        net.fix(p.side(2))
    scene = net.build()
    x = np.asarray(scene.nodes.position)
    node = {name: int(np.flatnonzero(np.all(np.isclose(x, e), axis=1))[0]) for name, e in PRESSED.items()}
    chain = np.flatnonzero(np.isclose(x[:, 1], -1.0))
    limit, sense = np.zeros((scene.n_nodes, 3)), np.zeros((scene.n_nodes, 3), dtype=np.int32)
    limit[node["heavy"], 2] = limit[node["light"], 2] = -1.0
    sense[node["heavy"], 2] = sense[node["light"], 2] = 1
    limit[node["float"], 2], sense[node["float"], 2] = -0.5, -1
    limit[node["pushed"], 0], sense[node["pushed"], 0] = 3.0, -1
    limit[chain, 2], sense[chain, 2] = -2.0, 1
    if with_net:
        netting = np.unique(np.asarray(scene.netting.vertices))
        limit[netting, 2], sense[netting, 2] = NET_Z + FLOOR, 1
        node["net"] = netting
    return with_limits(scene, limit, sense), node, chain


@pytest.fixture(scope="module")
def solved_sea_bed():
    scene, node, chain = sea_bed()
    assert {t.name for t in model.active_terms(scene)} == {"netting_tension", "bar_tension", "netting_weight", "node_weight",
                                                           "bar_weight", "node_force", "bottom_contact", "bottom_friction"}
    eq = jn.solve_static(scene, tol=1e-9)
    return scene, node, chain, eq, term_forces(scene, eq.x)


def test_bodies_settle_at_the_penetration_of_their_load(solved_sea_bed):
    scene, node, _, eq, forces = solved_sea_bed
    x = np.asarray(eq.x)
    heavy = 1.0 * (1 - RHO / LEAD) * G
    assert heavy / K > BAND
    assert x[node["heavy"], 2] == pytest.approx(-1.0 - heavy / K, abs=1e-14)  # W / k, FEMNET's
    assert x[node["float"], 2] == pytest.approx(-0.5 + 5.0 / K, abs=1e-14)  # a ceiling, from below
    assert x[node["pushed"], 0] == pytest.approx(3.0 + 7.0 / K, abs=1e-14)  # a wall along x
    # the light sinker stays in the band: k (2 p²/b - p³/b²) = W, the root in (0, b)
    light = 0.1 * (1 - RHO / LEAD) * G
    roots = np.roots([-K / BAND**2, 2 * K / BAND, 0.0, -light])
    p = [r.real for r in roots if abs(r.imag) < 1e-12 and 0 < r.real < BAND]
    assert len(p) == 1 and p[0] > light / K  # deeper than FEMNET's W/k, by less than the band
    assert x[node["light"], 2] == pytest.approx(-1.0 - p[0], abs=1e-14)
    contact = forces["bottom_contact"]
    np.testing.assert_allclose(contact[node["heavy"]], [0, 0, heavy], rtol=1e-9)
    np.testing.assert_allclose(contact[node["pushed"]], [-7.0, 0, 0], rtol=1e-9)
    # the floors along z slide with the current: friction mu W along x, taken here by the node's x fixing
    np.testing.assert_allclose(forces["bottom_friction"][node["heavy"]], [MU * heavy, 0, 0], rtol=1e-9)
    assert not np.any(forces["bottom_friction"][[node["float"], node["pushed"]]])  # ceiling, wall: none


def test_moving_bottom_drags_a_chain_with_mu_times_its_weight(solved_sea_bed):
    scene, _, chain, eq, forces = solved_sea_bed
    x = np.asarray(eq.x)
    normal, fric = forces["bottom_contact"][chain], forces["bottom_friction"][chain]
    np.testing.assert_allclose(fric, MU * normal[:, 2:3] * np.array([1.0, 0.0, 0.0]), rtol=1e-12, atol=1e-12)
    free = ~np.asarray(scene.nodes.fixed)[chain].all(axis=1)
    held = chain[~free][0]
    reaction = eq.reaction(scene)[held]
    bar_weight = LENGTH / N_BARS * np.pi * 0.01**2 * (7800.0 - RHO) * G
    # vertically the floor and the fixing carry the chain; along x the fixing holds mu times the floor's share
    residual = N_BARS * 1e-9  # the solve's tolerance on each free node
    np.testing.assert_allclose(normal[free, 2].sum() + reaction[2], N_BARS * bar_weight, rtol=0, atol=residual)
    np.testing.assert_allclose(reaction[0], -MU * normal[free, 2].sum(), rtol=0, atol=residual)
    np.testing.assert_allclose(normal[free, 2].sum(), bar_weight * (N_BARS - 0.5), rtol=1e-4)  # half a bar held
    # the chain is stretched by the friction accumulated downstream of each bar
    assert np.all(np.diff(np.sort(x[chain, 0])) > LENGTH / N_BARS)


def test_net_resting_on_a_moving_bottom_balances_its_weight_and_friction(solved_sea_bed):
    scene, node, _, eq, forces = solved_sea_bed
    net = node["net"]
    x = np.asarray(eq.x)[net]
    contact, fric = forces["bottom_contact"][net], forces["bottom_friction"][net]
    floor = NET_Z + FLOOR
    on_floor = x[:, 2] < floor
    free = ~np.asarray(scene.nodes.fixed)[net].all(axis=1)
    assert np.count_nonzero(on_floor & free) > np.count_nonzero(free) / 2
    np.testing.assert_array_equal(contact[~on_floor], 0.0)  # only nodes on the floor are pushed...
    assert np.all(contact[on_floor & free, 2] > 0) and not np.any(contact[:, :2])  # ...upward only
    assert x[free, 2].min() > floor - 1e-3  # no deeper than the band
    np.testing.assert_allclose(fric, MU * contact[:, 2:3] * np.array([1.0, 0.0, 0.0]), rtol=1e-12, atol=1e-15)
    volume = 4 * MESHES**2 * L0 * np.pi * HEAVY_TWINE.diameter**2 / 4  # 4 n² twines
    weight = volume * (HEAVY_TWINE.density - RHO) * G
    carried = contact[free, 2].sum()
    assert carried > 0.5 * weight  # the floor takes most of it
    reaction = eq.reaction(scene)[net]
    residual = np.count_nonzero(free) * 1e-9  # the solve's tolerance on each free node
    np.testing.assert_allclose(carried + reaction[:, 2].sum(), weight, rtol=0, atol=residual)
    np.testing.assert_allclose(reaction[:, 0].sum(), -MU * carried, rtol=0, atol=residual)


# -- presence in the compiled program -------------------------------------------------------------



def test_contact_and_friction_are_compiled_only_when_used():
    moving = sea_bed(with_net=False)[0]
    on = traced_terms(moving)
    assert {"bottom_contact", "bottom_friction"} <= on
    still = traced_terms(sea_bed(False, bottom_friction=0.0)[0])
    assert "bottom_contact" in still and on - still == {"bottom_friction"}
    assert on - traced_terms(sea_bed(False, current_speed=0.0)[0]) == {"bottom_friction"}
    no_limits = dataclasses.replace(moving, nodes=dataclasses.replace(moving.nodes, limit=None, limit_sense=None))
    assert on - traced_terms(no_limits) == {"bottom_contact", "bottom_friction"}
    # ceilings only, or walls across the current: contact without friction
    for limit, sense in (([0.0, 0.0, 1.0], [0, 0, -1]), ([-1.0, 0.0, 0.0], [1, 0, 0])):
        assert {t.name for t in model.active_terms(with_limits(moving, limit, sense))} == still


# -- validation and scene files ---------------------------------------------------------------------


def test_bad_limits_are_named():
    scene, _, chain = sea_bed(with_net=False)
    i = int(chain[3])
    sense = np.array(scene.nodes.limit_sense)
    sense[i, 1] = 2
    with pytest.raises(SceneError, match=rf"node {i}: limit_sense along y must be \+1 \(floor"):
        validate(dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, limit_sense=sense)))
    limit = np.array(scene.nodes.limit)
    limit[i, 2] = np.nan
    with pytest.raises(SceneError, match=rf"node {i}: limit along z is not finite"):
        validate(dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, limit=limit)))
    limit[i, 2], limit[i, 0] = -2.0, np.nan  # a NaN where there is no limit is no limit
    validate(dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, limit=limit)))
    with pytest.raises(SceneError, match="node 0: a limit along z needs environment bottom_stiffness > 0"):
        validate(with_limits(scene, 0.0, [0, 0, 1], bottom_stiffness=0.0))
    with pytest.raises(SceneError, match="environment: bottom_friction must be finite and >= 0"):
        validate(with_limits(scene, 0.0, [0, 0, 1], bottom_friction=-0.1))
    tilted = np.array([0.0, np.sin(0.1), np.cos(0.1)])
    with pytest.raises(SceneError, match="sea-bed friction .* needs 'up' along a coordinate axis"):
        validate(with_limits(scene, 0.0, [0, 0, 1], up=tilted))
    with pytest.raises(SceneError, match="limit_sense is missing"):
        validate(dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, limit_sense=None)))


SCENE = {
    "environment": {"current_speed": 1.0, "bottom_stiffness": 2e6, "bottom_friction": 0.3, "bottom_band": 5e-4},
    "ropes": {"chain": {"ea": 1e5, "diameter": 0.02, "density": 7800.0, "cd_normal": 0.0}},
    "cables": [{"name": "chain", "rope": "chain", "start": [0, 0, 0], "end": [2, 0, 0], "n_bars": 4}],
    "fix": [{"at": {"cable": "chain", "end": 0}}],
    "limits": [{"at": {"cable": "chain"}, "limit": [0, 0, -0.01], "sense": [0, 0, 1]},
               {"at": {"cable": "chain", "end": 1}, "limit": [2.5, 0, -0.01], "sense": [-1, 0, 1]}],
}


def test_scene_file_limits_and_bottom_reach_the_scene(tmp_path):
    path = tmp_path / "chain.json"
    path.write_text(json.dumps(SCENE))
    scene = scene_file.read(path).scene
    env = scene.environment
    assert (env.bottom_stiffness, env.bottom_friction, env.bottom_band) == (2e6, 0.3, 5e-4)
    x = np.asarray(scene.nodes.position)
    end = int(np.argmax(x[:, 0]))
    sense, limit = np.asarray(scene.nodes.limit_sense), np.asarray(scene.nodes.limit)
    np.testing.assert_array_equal(sense[end], [-1, 0, 1])
    np.testing.assert_array_equal(limit[end], [2.5, 0, -0.01])
    others = np.arange(scene.n_nodes) != end
    np.testing.assert_array_equal(sense[others], np.tile([0, 0, 1], (4, 1)))
    assert {"bottom_contact", "bottom_friction"} <= {t.name for t in model.active_terms(scene)}
    bad = dict(SCENE, limits=[{"at": [2, 0, 0], "limit": [0, 0, 0], "sense": [0, 0, 2]}])
    with pytest.raises(SceneError, match=r"limit_sense must be \+1 \(floor\), -1 \(ceiling\) or 0"):
        scene_file.from_dict(bad)
    bad = dict(SCENE, limits=[{"at": [2, 0, 0], "limit": [0, 0, 0], "sense": [0, 0, 1], "stiffness": 1}])
    with pytest.raises(SceneError, match=r"limits\[0\]: unknown key\(s\) \['stiffness'\]"):
        scene_file.from_dict(bad)


# -- the sea bed in time ----------------------------------------------------------------------------


def sliding_body(mu=0.5, mass=2.0, stiffness=1e6, **environment):
    """A body of ``mass`` kg resting on a still sea bed z >= 0 (FEMNET's penalty law, no band: it sits at the
    penetration m g / k), its slack, weightless link to a far anchor; ``mu`` the bed's friction."""
    from jaxnet.scene import Bars, Nodes, Scene

    depth = mass * 9.81 / stiffness
    nodes = Nodes(position=np.array([[-20.0, 0.0, 0.0], [0.0, 0.0, -depth]]), fixed=np.array([[True] * 3, [False] * 3]),
                  mass=np.array([0.0, mass]), volume=np.zeros(2), force=np.zeros((2, 3)),
                  limit=np.zeros((2, 3)), limit_sense=np.array([[0, 0, 0], [0, 0, 1]]))
    bars = Bars(ends=np.array([[0, 1]]), rest_length=np.array([40.0]), ea_traction=np.array([1.0]),
                ea_compression=np.zeros(1), diameter=np.zeros(1), density=np.zeros(1), cable=np.array([0]))
    env = Environment(**{"bottom_stiffness": stiffness, "bottom_friction": mu, "bottom_band": 0.0,
                         "bottom_moving": False, "added_mass_coefficient": 0.0, **environment})
    return Scene(nodes=nodes, bars=bars, environment=env)


def braking_recurrence(v0, mu_g, h, n):
    """The book scheme's exact steps of a body braked by the bed's smooth Coulomb friction,
    (v_{k+1} - v_k)/h = -mu g v_{k+1}/sqrt(v_{k+1}² + V_l²), each step's root by bisection: the speeds."""
    out = [v0]
    for _ in range(n):
        lo, hi = 0.0, out[-1]
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            if mid - out[-1] + h * mu_g * mid / np.sqrt(mid**2 + bottom.SLIDING_SPEED**2) > 0:
                hi = mid
            else:
                lo = mid
        out.append(0.5 * (lo + hi))
    return np.array(out)


def test_in_time_the_bed_brakes_a_sliding_body_by_mu_times_its_weight_against_its_velocity():
    """FEMNET's dyna rubs every node that presses on the bed (``fond_dyn.c``), moving bottom or not. A body sent
    sliding at 1 m/s along (0.6, 0.8, 0) over a still bed of mu = 0.5 slows on a straight line at mu g (the
    scheme's exact steps of the friction's smooth form) and stops after v0²/(2 mu g) to the scheme's accuracy."""
    from jaxnet.solve import dynamics
    from jaxnet.solve.options import Newton

    scene = sliding_body()
    names = {t.name for t in model.active_terms(scene, dynamic=True)}
    assert "bed_friction" in names and "bottom_friction" not in names
    assert "bed_friction" not in {t.name for t in model.active_terms(scene)}  # statics: nothing moves
    h, n, heading = 0.005, 60, np.array([0.6, 0.8, 0.0])
    newton = Newton(tol=1e-10, max_iter=30, damping=1e-12, stall_window=None)
    v0 = np.zeros((2, 3))
    v0[1] = heading
    tr = dynamics.simulate(scene, n * h, dynamics.Implicit(time_step=h, newton=newton), v0=v0)
    travel = tr.positions[:, 1] - tr.positions[0, 1]
    speeds = braking_recurrence(1.0, 0.5 * 9.81, h, n)
    np.testing.assert_allclose(travel[:, :2], np.outer(h * np.concatenate([[0], np.cumsum(speeds[1:])]),
                                                       heading[:2]), rtol=0, atol=1e-9)
    np.testing.assert_allclose(travel[:, 2], 0.0, atol=1e-12)  # the friction acts along the bed only
    stop = 1.0 / (2 * 0.5 * 9.81)
    assert abs(np.linalg.norm(travel[-1]) - stop) < 2 * h  # it stops where Coulomb friction stops it
    assert speeds[-1] < 1e-3


def test_a_sliding_bed_pulls_a_body_at_rest_by_its_static_friction():
    """On a bed sliding with a 1 m/s current (a towed gear seen from the gear) the friction in time at rest is the
    static one, mu N along the current, to O(V_l²/U²): a run starts from a static equilibrium without a jump."""
    from jaxnet.solve import dynamics

    still = sliding_body(current_speed=1.0)
    moving = sliding_body(current_speed=1.0, bottom_moving=True)
    assert "bottom_friction" in {t.name for t in model.active_terms(moving)}
    assert "bottom_friction" not in {t.name for t in model.active_terms(still)}
    x = jnp.asarray(moving.nodes.position)
    for scene, expected in ((still, 0.0), (moving, 0.5 * 2.0 * 9.81 / np.sqrt(1 + bottom.SLIDING_SPEED**2))):
        masses = dynamics.lumped_masses(scene)
        f = dynamics.out_of_balance(x, jnp.zeros_like(x), 0.0, scene, masses, dynamics.Loading(),
                                    model.active_terms(scene, dynamic=True))
        np.testing.assert_allclose(np.asarray(f[1]), [expected, 0.0, 0.0], atol=1e-9)
    static = term_forces(moving, x)["bottom_friction"][1]
    np.testing.assert_allclose(static, [0.5 * 2.0 * 9.81, 0.0, 0.0], rtol=1e-12)


def test_scene_file_says_whether_the_bed_slides():
    doc = dict(SCENE, environment=dict(SCENE["environment"], bottom_moving=False))
    scene = scene_file.from_dict(doc).scene
    assert scene.environment.bottom_moving is False
    assert "bottom_friction" not in {t.name for t in model.active_terms(scene)}
    assert "bed_friction" in {t.name for t in model.active_terms(scene, dynamic=True)}
    with pytest.raises(SceneError, match=r"environment.bottom_moving: expected true or false, got 1"):
        scene_file.from_dict(dict(SCENE, environment=dict(SCENE["environment"], bottom_moving=1)))
