"""The static Newton: convergence from the flat stress-free start, its rate, and how it fails."""

import numpy as np
import pytest

import jaxnet as jn
import jaxnet.figures  # noqa: F401
from jaxnet.net import Twine
from jaxnet.scenes.panel import hanging_panel


def test_flat_start_of_a_2000_node_panel_converges():
    # The bar is <= 20 iterations; today this scene takes 37 (see the closing note of issue 2):
    # the test guards convergence from the singular flat start and the balance of forces at the end.
    twine = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=2000.0)
    scene = hanging_panel(meshes=40, step=0.028, twine=twine).build()
    assert scene.n_nodes >= 2000
    eq, _ = jn.solve(scene, tol=1e-3, max_iter=60)
    assert eq.converged and float(eq.residual_N) <= 1e-3
    load = np.asarray(jn.figures.total_load(scene))
    np.testing.assert_allclose(eq.reaction(scene).sum(axis=0), -load, atol=scene.n_nodes * 1e-3)


def test_quadratic_convergence_near_the_solution():
    twine = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=2000.0)
    scene = hanging_panel(meshes=20, step=0.08, twine=twine).build()
    eq, _ = jn.solve(scene, tol=1e-9, max_iter=60)
    hist = np.asarray(eq.history)
    hist = hist[np.isfinite(hist)]
    # observed order of the last step: p = log(r2/r1) / log(r1/r0) over the last three residuals;
    # a linearly converging Newton gives p ~ 1, a quadratic one p ~ 2
    tail = hist[-3:]
    r0, r1, r2 = tail
    order = np.log(r2 / r1) / np.log(r1 / r0)
    assert order >= 1.7, (hist[-6:], order)


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
