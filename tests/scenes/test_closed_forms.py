"""Whole-panel closed forms: a biaxially stretched panel, and the balance of a hanging panel."""

import numpy as np
import pytest

import jaxnet as jn
from jaxnet import figures
from jaxnet.scenes.textbook import biaxial_panel


@pytest.mark.parametrize("theta", [np.pi / 4, 0.3])
def test_biaxial_panel_edge_forces(theta):
    nx, ny, strain, ea = 12, 8, 0.01, 1000.0
    scene, across, up = biaxial_panel(nx, ny, theta, strain, step=0.05, ea=ea)
    exact = scene.nodes.position.copy()
    # start from a perturbed interior: Newton must bring it back to the uniform state
    free = ~scene.nodes.fixed.all(axis=1)
    rng = np.random.default_rng(1)
    start = exact.copy()
    start[free] += rng.normal(scale=0.002, size=(free.sum(), 3))
    eq = jn.solve_static(scene, x0=start, tol=1e-9)
    np.testing.assert_allclose(np.asarray(eq.x), exact, atol=1e-9)
    T = ea * strain
    np.testing.assert_allclose(figures.twine_tensions(scene, eq.x), T, rtol=1e-9)
    x = np.asarray(eq.x)
    reaction = eq.reaction(scene)
    right = np.isclose(x[:, 0], nx * across)
    top = np.isclose(x[:, 2], ny * up)
    # 2 twines per mesh row cross a vertical line, each pulling T sin(theta) across it
    np.testing.assert_allclose(reaction[right, 0].sum(), 2 * ny * T * np.sin(theta), rtol=1e-9)
    np.testing.assert_allclose(reaction[top, 2].sum(), 2 * nx * T * np.cos(theta), rtol=1e-9)
    # the net is in equilibrium as a whole
    np.testing.assert_allclose(reaction.sum(axis=0), 0.0, atol=1e-9 * T * ny)


def test_hanging_panel_reaction_equals_immersed_weight():
    from jaxnet.scenes.panel import hanging_panel

    scene = hanging_panel(meshes=20, step=0.08).scene
    eq = jn.solve_static(scene, tol=1e-9, max_iter=200)
    weight = figures.total_load(scene)
    # immersed weight: netting (4.277), sinker bar and headline, all computed independently here
    net, bars, env = scene.netting, scene.bars, scene.environment
    uv = np.asarray(net.uv)
    d = (uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1]) - (uv[:, 2, 0] - uv[:, 0, 0]) * (uv[:, 1, 1] - uv[:, 0, 1])
    w_net = np.sum(np.abs(d) * np.pi * net.diameter**2 / 4 * net.l0 * (net.density - env.water_density) * env.gravity)
    w_bar = np.sum(np.pi * bars.diameter**2 / 4 * bars.rest_length * (bars.density - env.water_density) * env.gravity)
    np.testing.assert_allclose(weight, [0, 0, -(w_net + w_bar)], rtol=1e-12, atol=1e-12)
    reaction = eq.reaction(scene).sum(axis=0)
    np.testing.assert_allclose(reaction[2], w_net + w_bar, rtol=1e-9)
    np.testing.assert_allclose(reaction[:2], 0.0, atol=1e-9 * (w_net + w_bar))
