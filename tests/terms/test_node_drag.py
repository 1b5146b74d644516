"""Node drag of FEMNET's box-shaped node bodies (drag.box_drag, the term node_box_drag).

FEMNET (traineecourant2.c) loads a node with F_x = ½ ρ Cd_x (L_y h) |c| c_x and F_y = ½ ρ Cd_y (L_x h)
|c| c_y, h the immersed height of the box; jaxnet adds F_z = ½ ρ Cd_z (L_x L_y f) |c| c_z (zero in
FEMNET's horizontal current). Checked: the closed forms along x, along a diagonal and with a vertical
component; FEMNET's six immersion cases; the tangent (autodiff) against finite differences, element and
assembled; the term is compiled only when used; a pendulum in a current; validation; scene files.
"""

import dataclasses
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp

import jaxnet as jn
from jaxnet import model
from jaxnet.model import assemble
from jaxnet.io import scene_file
from jaxnet.net import Net, Rope
from jaxnet.scene.checks import validate
from jaxnet.scene import Environment, SceneError
from jaxnet.terms import drag
from traced import traced_terms  # tests/traced.py

RHO, G = 1025.0, 9.81
LENGTH = np.array([0.3, 0.5, 0.4])  # box sizes along x, y, z (m)
CD = np.array([1.1, 0.7, 0.9])
U = 0.8  # current speed (m/s)
NEUTRAL = Rope(ea=1e4, diameter=0.01, density=RHO, cd_normal=0.0)  # no weight, no drag


def pendulum(current_direction=(1.0, 0.0, 0.0), surface=float("nan"), profile=None, body=True,
             cd=CD, current=U, sinker=2.0, drag_area=0.0):
    """A neutral rope of 1 m hanging from a fixed point at the origin, a lead sinker (kg) and a box body
    at its lower end (node 1)."""
    depth, factor = profile if profile is not None else (np.zeros(0), np.zeros(0))
    env = Environment(current_speed=current, current_direction=np.asarray(current_direction, dtype=float),
                      surface_level=surface, profile_depth=depth, profile_factor=factor)
    net = Net(env)
    net.cable("rope", start=(0.0, 0.0, 0.0), end=(0.0, 0.0, -1.0), rope=NEUTRAL, n_bars=1)
    net.fix((0.0, 0.0, 0.0))
    if sinker:
        net.sinker((0.0, 0.0, -1.0), sinker)
    if drag_area:
        net.attach((0.0, 0.0, -1.0), drag_area=drag_area)
    scene = net.build()
    if body:
        scene = with_body(scene, 1, LENGTH, cd)
    return scene


def with_body(scene, node, length, cd):
    n = scene.n_nodes
    lengths, cds = np.zeros((n, 3)), np.zeros((n, 3))
    lengths[node], cds[node] = length, cd
    return dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, drag_length=lengths, drag_coefficient=cds))


_forces = jax.jit(assemble.forces, static_argnames=("model",))


def only(scene, name):
    terms = tuple(t for t in model.active_terms(scene) if t.name == name)
    assert len(terms) == 1
    return terms


def box_force(scene, x=None):
    x = np.asarray(scene.nodes.position) if x is None else x
    return np.asarray(_forces(jnp.asarray(x), scene, model=only(scene, "node_box_drag")))


# -- closed forms ---------------------------------------------------------------------------------


def test_current_along_x_drags_the_face_normal_to_x():
    f = box_force(pendulum())
    expected = 0.5 * RHO * CD[0] * LENGTH[1] * LENGTH[2] * U**2
    np.testing.assert_allclose(f[1], [expected, 0.0, 0.0], rtol=1e-13)
    np.testing.assert_allclose(f[0], 0.0, atol=0.0)  # the body is on node 1 only


def test_diagonal_current_is_dragged_per_axis_not_along_the_current():
    d = np.array([1.0, 1.0, 0.0]) / np.sqrt(2.0)
    f = box_force(pendulum(current_direction=d))[1]
    c = U * d
    faces = np.array([LENGTH[1] * LENGTH[2], LENGTH[0] * LENGTH[2], LENGTH[0] * LENGTH[1]])
    np.testing.assert_allclose(f, 0.5 * RHO * U * CD * faces * c, rtol=1e-13)
    # FEMNET's F_y / F_x = Cd_y L_x / (Cd_x L_y) tan(theta): not along the 45° current
    assert f[1] / f[0] == pytest.approx(CD[1] * LENGTH[0] / (CD[0] * LENGTH[1]), rel=1e-13)
    assert abs(f[1] / f[0] - 1.0) > 0.5
    # a vertical component meets the horizontal section L_x L_y with Cd_z (FEMNET's current has none)
    up = np.array([1.0, 0.0, 1.0]) / np.sqrt(2.0)
    fz = box_force(pendulum(current_direction=up))[1]
    np.testing.assert_allclose(fz[2], 0.5 * RHO * U * CD[2] * LENGTH[0] * LENGTH[1] * U * up[2], rtol=1e-13)


def femnet_immersed_height(z, lz, surface=0.0):
    """FEMNET's immersion of a node body (traineecourant2.c), its four branches per sign of lonz."""
    z = z - surface
    if lz > 0:
        if z <= 0 <= z + lz:
            return -z  # floating float
        if z + lz < 0:
            return lz  # flooded float
        return 0.0  # emerged float
    if z >= 0 >= z + lz:
        return -lz - z  # floating sinker
    if z < 0:
        return -lz  # flooded sinker
    return 0.0  # emerged sinker


@pytest.mark.parametrize("lz", [0.4, -0.4])
def test_partly_immersed_body_has_femnet_wetted_height(lz):
    surface = 0.3
    c = jnp.array([U, 0.0, 0.0])
    for z in (-1.0, -0.39, -0.2, 0.0, 0.29, 0.31, 0.5, 0.69, 0.71, 1.0):
        h = femnet_immersed_height(z, lz, surface)
        f = drag.box_immersed_fraction(z, lz, surface)
        assert float(f) * abs(lz) == pytest.approx(h, abs=1e-15)
        force = drag.box_drag(jnp.array([LENGTH[0], LENGTH[1], lz]), jnp.asarray(CD), c, RHO, f)
        np.testing.assert_allclose(force, [0.5 * RHO * CD[0] * LENGTH[1] * h * U**2, 0.0, 0.0], rtol=1e-13, atol=1e-15)
    # some of those heights are partial, some full, some none
    hs = [femnet_immersed_height(z, lz, surface) for z in (-1.0, surface - 0.1 * np.sign(lz), 1.0)]
    assert hs[0] == abs(lz) and 0 < hs[1] < abs(lz) and hs[2] == 0


# -- tangent ----------------------------------------------------------------------------------------


def test_tangent_of_a_floating_body_in_a_sheared_current_is_its_finite_difference():
    # The body straddles the free surface (its wetted height changes with the node's height) in a current
    # that halves over 2 m of depth: the drag depends on the node's position both ways.
    profile = (np.array([0.0, 2.0]), np.array([1.0, 0.5]))
    d = np.array([0.8, 0.6, 0.0])
    scene = pendulum(current_direction=d, surface=-0.85, profile=profile)
    assert model.active_terms(scene) and "node_box_drag" in {t.name for t in model.active_terms(scene)}
    terms = only(scene, "node_box_drag")
    x0 = np.asarray(scene.nodes.position).copy()
    x0[1] += [0.05, -0.02, 0.0]  # node 1 at z = -1: its box spans [-1, -0.6], 0.15 m of it under water

    @jax.jit
    def node_force(p):
        return assemble.forces(jnp.asarray(x0).at[1].set(p), scene, terms)[1]

    jac = np.asarray(jax.jit(jax.jacfwd(node_force))(jnp.asarray(x0[1])))
    h = 1e-6
    fd = np.stack([(np.asarray(node_force(jnp.asarray(x0[1] + h * e))) - np.asarray(node_force(jnp.asarray(x0[1] - h * e))))
                   / (2 * h) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(jac, fd, rtol=1e-7, atol=1e-9 * np.abs(fd).max())
    assert abs(jac[0, 2]) > 1.0 and abs(jac[1, 2]) > 1.0  # the wetted height and the current vary with z
    np.testing.assert_allclose(jac[:, :2], 0.0, atol=0.0)  # nothing depends on x, y
    # the assembled tangent K = -dF/dx holds that block at node 1 (free), and nothing else of this term
    pattern = assemble.build_pattern(scene, terms)
    data = np.asarray(jax.jit(assemble.tangent, static_argnames="model")(jnp.asarray(x0), scene, terms, pattern))
    k = sp.csr_matrix((data, np.asarray(pattern.indices), np.asarray(pattern.indptr))).toarray()
    free = list(np.asarray(pattern.free))
    rows = [free.index(3 + i) for i in range(3)]
    np.testing.assert_allclose(k[np.ix_(rows, rows)], -jac, rtol=1e-12, atol=1e-12)


# -- presence in the compiled program -------------------------------------------------------------



def test_box_drag_is_compiled_only_when_a_body_meets_a_current():
    on = traced_terms(pendulum())
    assert "node_box_drag" in on
    for off_scene in (pendulum(body=False), pendulum(cd=np.zeros(3)), pendulum(current=0.0)):
        off = traced_terms(off_scene)
        assert "node_box_drag" not in off
        assert {t.name for t in model.active_terms(off_scene)} == off
    assert on - traced_terms(pendulum(body=False)) == {"node_box_drag"}


def test_isotropic_drag_area_still_acts_beside_the_box():
    scene = pendulum(drag_area=0.05)
    names = [t.name for t in model.active_terms(scene)]
    assert "node_drag" in names and "node_box_drag" in names
    total = np.asarray(_forces(jnp.asarray(scene.nodes.position), scene, model=model.active_terms(scene)))[1]
    box = 0.5 * RHO * CD[0] * LENGTH[1] * LENGTH[2] * U**2
    np.testing.assert_allclose(total, [box + 0.5 * RHO * 0.05 * U**2, 0.0, 0.0], rtol=1e-13)


# -- solved ---------------------------------------------------------------------------------------


def test_sinker_with_a_box_body_trails_at_the_angle_of_drag_to_weight():
    sinker = 2.0
    scene = pendulum(sinker=sinker)
    eq = jn.solve_static(scene, tol=1e-10)
    weight = sinker * (1.0 - RHO / 11340.0) * G
    drag_x = 0.5 * RHO * CD[0] * LENGTH[1] * LENGTH[2] * U**2
    np.testing.assert_allclose(eq.reaction(scene)[0], [-drag_x, 0.0, weight], rtol=1e-9, atol=1e-9)
    end = np.asarray(eq.x)[1]
    stretch = 1.0 + np.hypot(drag_x, weight) / NEUTRAL.ea
    np.testing.assert_allclose(end, stretch * np.array([drag_x, 0.0, -weight]) / np.hypot(drag_x, weight), atol=1e-9)


# -- validation and scene files ---------------------------------------------------------------------


def test_bad_bodies_are_named():
    scene = pendulum()
    bad_cd = CD.copy()
    bad_cd[1] = -0.5
    with pytest.raises(SceneError, match=r"node 1: drag_coefficient \(drag coefficient\) along y must be >= 0"):
        validate(with_body(scene, 1, LENGTH, bad_cd))
    with pytest.raises(SceneError, match=r"node 1: drag_length \(size\) along x must be >= 0"):
        validate(with_body(scene, 1, [-0.1, 0.5, 0.4], CD))
    validate(with_body(scene, 1, [0.1, 0.5, -0.4], CD))  # a body hanging below its node (a sinker)
    with pytest.raises(SceneError, match="node 1: drag_length along z is not finite"):
        validate(with_body(scene, 1, [0.1, 0.5, np.nan], CD))
    half = dataclasses.replace(scene.nodes, drag_coefficient=None)
    with pytest.raises(SceneError, match="drag_coefficient is missing"):
        validate(dataclasses.replace(scene, nodes=half))
    flat = dataclasses.replace(scene.nodes, drag_length=np.zeros(scene.n_nodes))
    with pytest.raises(SceneError, match=r"drag_length must have shape \(2, 3\)"):
        validate(dataclasses.replace(scene, nodes=flat))


SCENE = {
    "environment": {"current_speed": U},
    "ropes": {"neutral": {"ea": 1e4, "diameter": 0.01, "density": RHO, "cd_normal": 0.0}},
    "cables": [{"name": "rope", "rope": "neutral", "start": [0, 0, 0], "end": [0, 0, -1], "n_bars": 2}],
    "fix": [{"at": {"cable": "rope", "end": 0}}],
    "bodies": [{"at": {"cable": "rope"}, "drag_length": [0.1, 0.2, 0.3], "drag_coefficient": [1.0, 1.0, 1.0]},
               {"at": {"cable": "rope", "end": 1}, "drag_length": LENGTH.tolist(), "drag_coefficient": CD.tolist()}],
}


def test_scene_file_bodies_reach_every_node_of_their_reference(tmp_path):
    path = tmp_path / "pendulum.json"
    path.write_text(json.dumps(SCENE))
    scene = scene_file.read(path).scene
    x = np.asarray(scene.nodes.position)
    end = int(np.argmin(x[:, 2]))
    lengths, cds = np.asarray(scene.nodes.drag_length), np.asarray(scene.nodes.drag_coefficient)
    np.testing.assert_array_equal(lengths[end], LENGTH)  # the later entry wins on the end node
    np.testing.assert_array_equal(cds[end], CD)
    others = np.arange(scene.n_nodes) != end
    np.testing.assert_array_equal(lengths[others], np.tile([0.1, 0.2, 0.3], (2, 1)))
    assert "node_box_drag" in {t.name for t in model.active_terms(scene)}
    toml = tmp_path / "pendulum.toml"
    toml.write_text("""
[environment]
current_speed = 0.8
[ropes.neutral]
ea = 1e4
diameter = 0.01
[[cables]]
name = "rope"
rope = "neutral"
start = [0, 0, 0]
end = [0, 0, -1]
[[fix]]
at = {cable = "rope", end = 0}
[[bodies]]
at = [0, 0, -1]
drag_length = [0.3, 0.5, -0.4]
drag_coefficient = [1.1, 0.7, 0.9]
""")
    scene = scene_file.read(toml).scene
    np.testing.assert_array_equal(np.asarray(scene.nodes.drag_length)[1], [0.3, 0.5, -0.4])
    bad = dict(SCENE, bodies=[{"at": [0, 0, -1], "drag_length": [0.1, 0.2], "drag_coefficient": [1, 1, 1]}])
    with pytest.raises(SceneError, match=r"bodies\[0\].drag_length: expected 3 numbers"):
        scene_file.from_dict(bad)
    bad = dict(SCENE, bodies=[{"at": [0, 0, -1], "drag_length": [0.1, 0.2, 0.3]}])
    with pytest.raises(SceneError, match=r"bodies\[0\]: missing key\(s\) \['drag_coefficient'\]"):
        scene_file.from_dict(bad)
