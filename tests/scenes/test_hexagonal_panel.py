"""A hexagonal-mesh panel in a scene: built from a HexTwine, meshed, solved, balanced."""

import numpy as np

import jaxnet as jn
from jaxnet import model
from jaxnet.scenes import textbook


def hanging_hexagonal_panel(meshes=8, a=0.02, pull=5.0):
    return textbook.hexagonal_hanging_panel(meshes, a, pull)[0]


def test_hexagonal_panel_hangs_in_balance_with_its_weight():
    scene = hanging_hexagonal_panel()
    assert [t.name for t in model.active_terms(scene)] == ["node_force", "hexagonal_tension", "hexagonal_weight"]
    eq = jn.solve_static(scene, tol=1e-6)
    # immersed weight of the twines: |d| twines of each family per triangle (text after 4.82)
    uv = np.asarray(scene.hexagonal.uv)
    d = (uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1]) - (uv[:, 2, 0] - uv[:, 0, 0]) * (uv[:, 1, 1] - uv[:, 0, 1])
    env = scene.environment
    weight = np.sum(np.abs(d) * np.pi * 1e-6 / 4 * (0.02 + 0.02 + 0.024) * (1140.0 - env.water_density) * env.gravity)
    np.testing.assert_allclose(eq.reaction(scene).sum(axis=0), [0.0, 0.0, 5.0 + weight], atol=scene.n_nodes * 1e-6)
    # the panel started drawn taller than its twines allow: it shortened to carry the pull in traction
    assert -8 * 3 * 0.02 < np.asarray(eq.x)[:, 2].min() < -8 * np.sqrt(3) * 0.02
