"""A hexagonal-mesh panel in a scene: built from a HexTwine, meshed, solved, balanced."""

import numpy as np

import jaxnet as jn
from jaxnet import model
from jaxnet.net import HexTwine, Net


def hanging_hexagonal_panel(meshes=8, a=0.02, pull=5.0):
    net = Net()
    w = meshes * 3 * a  # a base mesh is 3 twine lengths along U
    corners = [(0, 0, -w, 0, 0), (w, 0, -w, meshes, 0), (w, 0, 0, meshes, meshes), (0, 0, 0, 0, meshes)]
    panel = net.panel("hex", corners, HexTwine(l0=(a, a, 1.2 * a), ea=1000.0, diameter=1e-3), step=0.1)
    net.fix(panel.side(2))
    net.attach(panel.side(0), force=(0.0, 0.0, -pull))
    return net.build()


def test_hexagonal_panel_hangs_in_balance_with_its_weight():
    scene = hanging_hexagonal_panel()
    assert [t.name for t in model.active_terms(scene)] == ["node_force", "hexagonal_tension", "hexagonal_weight"]
    eq, _ = jn.solve(scene, tol=1e-6)
    # immersed weight of the twines: |d| twines of each family per triangle (text after 4.82)
    uv = np.asarray(scene.hexagonal.uv)
    d = (uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1]) - (uv[:, 2, 0] - uv[:, 0, 0]) * (uv[:, 1, 1] - uv[:, 0, 1])
    env = scene.environment
    weight = np.sum(np.abs(d) * np.pi * 1e-6 / 4 * (0.02 + 0.02 + 0.024) * (1140.0 - env.water_density) * env.gravity)
    np.testing.assert_allclose(eq.reaction(scene).sum(axis=0), [0.0, 0.0, 5.0 + weight], atol=scene.n_nodes * 1e-6)
    # the panel started drawn taller than its twines allow: it shortened to carry the pull in traction
    assert -8 * 3 * 0.02 < np.asarray(eq.x)[:, 2].min() < -8 * np.sqrt(3) * 0.02
