"""The static Newton: convergence from the flat stress-free start, its rate, and how it fails."""

import numpy as np
import pytest

import jaxnet as jn
from jaxnet.net import Twine
from jaxnet.scenes.panel import hanging_panel


@pytest.mark.parametrize("ea_compression", [0.0, 2000.0])
def test_flat_start_of_a_2000_node_panel_converges_within_20_iterations(ea_compression):
    twine = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=ea_compression)
    scene = hanging_panel(meshes=40, step=0.028, twine=twine).build()
    assert scene.n_nodes >= 2000
    eq, _ = jn.solve(scene, tol=1e-3, max_iter=20)
    assert eq.converged and int(eq.iterations) <= 20
    assert float(eq.residual_N) <= 1e-3


def test_quadratic_convergence_near_the_solution():
    twine = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=2000.0)
    scene = hanging_panel(meshes=20, step=0.08, twine=twine).build()
    eq, _ = jn.solve(scene, tol=1e-10, max_iter=60)
    hist = np.asarray(eq.history)
    hist = hist[np.isfinite(hist)]
    # the last three residuals: r2 <= C r1² with C set by the first of them (quadratic, not linear)
    r0, r1, r2 = hist[-3:]
    assert r2 < 1e-10
    assert r1 < 0.1 * r0
    assert r2 <= 10 * r1**2 / r0 + 1e-13


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
