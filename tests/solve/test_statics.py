"""The host-driven static solve (jaxnet.solve.statics): its stiffness continuation, its start coordinates and
what it refuses. The damped Newton's rules and their jittable loop are tested in test_newton.py, the primal-dual
method in test_interior.py."""

import numpy as np
import pytest

import jaxnet as jn
from jaxnet.scenes.panel import framed_panel
from jaxnet.solve import results, statics
from jaxnet.solve.options import Newton

#: a continuation that starts at once (``stall_window=0``), softened to 1 % then stiffened 10-fold a stage
SOLVER = Newton(method="damped", stall_window=0, soft_start=0.01, stiffening=10.0, stage_rtol=0.1, tol=1e-3,
                max_iter=100)


def test_the_continuation_softens_stiffens_stage_by_stage_and_gives_back_its_start():
    c = statics.Continuation(SOLVER)
    assert c.scales == pytest.approx([0.01, 0.1, 1.0]) and c.scale == 1.0  # plain Newton until it starts
    history, balance = np.full(101, np.nan), []
    c.start_if_stalling(10, history, balance, "iterate at 10")
    assert c.stage == -1 and c.until == 10 + (100 - 10) // 2  # half the iterations left
    assert c.due_to_stiffen(5.0)  # the first stage comes at once
    c.stage += 1
    c.stage_start = 5.0
    assert c.scale == pytest.approx(0.01)
    assert not c.due_to_stiffen(0.6) and c.due_to_stiffen(0.4)  # at stage_rtol of the stage's start
    assert c.converged_softened(results.CONVERGED) == results.RUNNING  # a softened equilibrium is not the answer
    assert c.failed_softened(results.STALLED, 20) == results.RUNNING
    assert not c.due_to_end(20) and c.due_to_end(21)  # a failed stage ends it at the next iteration
    assert c.end() == "iterate at 10" and c.scale == 1.0
    assert c.converged_softened(results.CONVERGED) == results.CONVERGED
    assert c.failed_softened(results.STALLED, 30) == results.STALLED
    c.start_if_stalling(40, history, balance, "iterate at 40")
    assert c.stage == c.final  # it starts once only


def test_a_time_step_has_no_continuation():
    c = statics.Continuation(SOLVER, static=False)
    assert c.scales == [1.0]
    c.start_if_stalling(10, np.full(101, np.nan), [], "iterate")
    assert c.stage == 0 and not c.due_to_stiffen(1e9) and not c.due_to_end(10**6)


def test_the_continuation_reaches_the_plain_answer():
    """The continuation changes the path, not the answer: the framed panel solved with a continuation that starts
    at once ends where plain Newton does, to what the tolerance allows."""
    scene = framed_panel(meshes=10, step=0.1, sinker_kg=1.0).scene
    plain = jn.solve_static(scene, method="damped", stall_window=None, tol=1e-9)
    softened = jn.solve_static(scene, SOLVER, tol=1e-9, max_iter=200)
    assert plain.converged and softened.converged
    scale = np.ptp(np.asarray(plain.x), axis=0).max()
    np.testing.assert_allclose(np.asarray(softened.x), np.asarray(plain.x), rtol=0, atol=1e-6 * scale)


def test_start_coordinates_are_the_free_ones_and_a_bad_start_is_named():
    scene = framed_panel(meshes=10, step=0.1).scene
    x0 = np.asarray(scene.nodes.position) + 0.01
    free = np.flatnonzero(~np.asarray(scene.nodes.fixed).ravel())
    np.testing.assert_array_equal(statics.start_coordinates(scene, free, x0), x0.ravel()[free])
    node = free[7] // 3
    x0[node, 1] = np.nan
    with pytest.raises(ValueError, match=rf"solve: x0 \(start positions\) of node {node} is not finite"):
        statics.solve(scene, x0=x0)
    with pytest.raises(ValueError, match=r"must have shape \(\d+, 3\), got \(3,\)"):
        statics.solve(scene, x0=np.zeros(3))
