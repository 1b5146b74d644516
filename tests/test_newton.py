"""The static Newton: convergence from the flat stress-free start, its rate, and how it fails."""

import numpy as np
import pytest

import jaxnet as jn
import jaxnet.figures  # noqa: F401
from jaxnet.net import Twine
from jaxnet.scenes.panel import framed_panel, hanging_panel


def balance(scene, eq):
    """Total reaction + total load: zero at equilibrium, whatever the shape (N, [x, y, z])."""
    return eq.reaction(scene).sum(axis=0) + np.asarray(jn.figures.total_load(scene))


def test_flat_start_of_a_2000_node_panel_with_slack_twines_converges_in_20_iterations():
    # A horizontal panel held along its border, sagging under its weight and a 20 kg sinker: the flat,
    # stress-free start has no out-of-plane stiffness at all, and the twines have EA_c = 0.
    scene = framed_panel(meshes=80, step=0.06, sinker_kg=20.0).build()
    assert scene.n_nodes >= 2000 and not np.any(np.asarray(scene.netting.ea_compression))
    eq, _ = jn.solve(scene, tol=1e-3, max_iter=20)
    assert eq.converged and float(eq.residual_N) <= 1e-3
    assert float(np.asarray(eq.x)[:, 2].min()) < -0.1  # it really sagged (about 0.23 m)
    np.testing.assert_allclose(balance(scene, eq), 0.0, atol=scene.n_nodes * 1e-3)


def test_flat_start_of_the_2000_node_default_scene_converges_in_20_iterations():
    scene = hanging_panel(meshes=80, step=0.06).build()
    assert scene.n_nodes >= 2000
    eq, _ = jn.solve(scene, tol=1e-3, max_iter=20)
    assert eq.converged
    np.testing.assert_allclose(balance(scene, eq), 0.0, atol=scene.n_nodes * 1e-3)


def test_badly_crumpled_start_reaches_the_same_equilibrium():
    # With EA_c = 0 the energy is convex in the positions and this equilibrium (all twines taut) is
    # unique: from a crumpled start (every free node moved at random by up to three twine lengths,
    # many triangles turned inside out) Newton must find the flat start's answer.
    scene = framed_panel(meshes=20, step=0.08, sinker_kg=2.0).build()
    flat, _ = jn.solve(scene, tol=1e-8)
    rng = np.random.default_rng(0)
    x0 = np.asarray(scene.nodes.position) + rng.uniform(-0.075, 0.075, (scene.n_nodes, 3))
    crumpled, _ = jn.solve(scene, x0=x0, tol=1e-8)
    np.testing.assert_allclose(np.asarray(crumpled.x), np.asarray(flat.x), atol=1e-7)


def test_slack_curtain_converges_even_though_slowly():
    # The hanging curtain with slack twines has a degenerate equilibrium (gathered, slack sides): Newton
    # converges linearly there, but it must converge, and balance the weight.
    slack = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=0.0)
    scene = hanging_panel(meshes=40, step=0.1, twine=slack).build()
    eq, _ = jn.solve(scene, tol=1e-3, max_iter=500)
    assert eq.converged
    np.testing.assert_allclose(balance(scene, eq), 0.0, atol=scene.n_nodes * 1e-3)


def test_quadratic_convergence_near_the_solution():
    scene = framed_panel(meshes=20, step=0.08, sinker_kg=2.0).build()
    eq, _ = jn.solve(scene, tol=1e-9, max_iter=60)
    hist = np.asarray(eq.history)
    hist = hist[np.isfinite(hist)]
    r1, r2 = hist[-2:]
    scale = float(np.abs(np.asarray(jn.figures.total_load(scene))).max())  # N
    # quadratic: r2 <= C r1² / scale with a modest C; a linearly converging solver has r2 / r1 ~ 0.1-0.5,
    # which fails this by orders of magnitude once r1 is small.
    assert r1 < 1e-3 * scale and r2 <= 100.0 * r1 * r1 / scale, hist


def test_failed_solve_names_the_reason_and_the_node():
    scene = hanging_panel(meshes=20, step=0.08).build()
    with pytest.raises(jn.SolveError, match=r"after 2 iterations: maximum number of iterations reached; largest residual .* N at node \d+"):
        jn.solve(scene, max_iter=2)
    eq, _ = jn.solve(scene, max_iter=2, raise_on_failure=False)
    assert not eq.converged and eq.reason == "maximum number of iterations reached"
    assert np.all(np.isfinite(np.asarray(eq.x)))
    worst = int(eq.worst_node)
    free = ~np.asarray(scene.nodes.fixed)
    nodal = np.linalg.norm(np.where(free, np.asarray(eq.force), 0.0), axis=1)
    assert nodal[worst] == pytest.approx(float(eq.residual_N))
