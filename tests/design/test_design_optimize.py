"""Design optimisation with optax (jaxnet.design.optimize): an inverse problem with a known answer.

A small panel (4 × 4 meshes) hangs in a current. The target is the equilibrium shape of another design: one
mesh more across its foot (a T step on corner 1: a tapered side) and a twine 30 % thicker. Starting from
the reference design, the optimiser recovers a design that hangs like the target, under a material
constraint and a bound on the diameter, and the design rounded to whole meshes is the target's cut.
One optimisation run, checked from every side (it dominates this file's time: compiling the program)."""

import functools
import json

import numpy as np
import optax
import pytest

import jaxnet  # noqa: F401
from jaxnet.design import constraints, objectives, optimize, space as space_lib
from jaxnet.scene import Environment
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import implicit

STEPS = 50


@functools.lru_cache(maxsize=1)
def problem():
    net = hanging_panel(meshes=4, step=0.05).net
    net.environment = Environment(current_speed=0.4, current_direction=np.array([0.0, 1.0, 0.0]))
    space = space_lib.DesignSpace(net)
    reference = space.initial()
    corners = np.asarray(reference["cut"]["netting"])
    diameter = float(reference["twine_diameter"]["netting"])
    target = {"cut": {"netting": corners + np.array([[0, 0], [1, -1], [0, 0], [0, 0]])},
              "twine_diameter": {"netting": np.asarray(1.3 * diameter)}}
    target_x = np.asarray(implicit.solve(space.scene(target)).x)
    return space, reference, target, target_x


@pytest.fixture(scope="module")
def optimised(tmp_path_factory):
    out = tmp_path_factory.mktemp("design")
    return (*run(out), out)


def setup():
    """(space, objective, start, bounds, twine, diameter) of the inverse problem."""
    space, reference, target, target_x = problem()
    twine = float(space.twine_length(reference)["netting"])
    # the material may grow by 20 % at most (the target's grows by 2/16 = 12.5 %: feasible)
    material = constraints.Constraint(objectives.twine_length(), upper=1.2 * twine)
    objective = constraints.penalised(objectives.shape_distance(target_x), [material], weight=10.0)
    start = {"cut": {"netting": reference["cut"]["netting"]}, "twine_diameter": {"netting": reference["twine_diameter"]["netting"]}}
    diameter = float(reference["twine_diameter"]["netting"])
    bounds = constraints.Bounds(upper={"cut": {"netting": None}, "twine_diameter": {"netting": 1.25 * diameter}})
    return space, objective, start, bounds, twine, diameter


def run(out):
    space, objective, start, bounds, twine, diameter = setup()
    result = optimize.optimize(space, objective, start, optimizer=optax.adam(0.05), steps=STEPS, bounds=bounds,
                               out=out, progress=False)
    return result, objective, twine, diameter


def test_the_optimiser_recovers_the_target_and_rounds_to_its_cut(optimised):
    result, objective, twine, diameter, out = optimised
    space, reference, target, target_x = problem()
    first = result.history[0]["objective"]
    # the objective (RMS distance to the target shape, m) falls by 90 % at least (measured: 97 %)
    assert result.value < 0.1 * first
    # the bound holds: the diameter cannot reach the target's 1.3 x
    assert float(result.theta["twine_diameter"]["netting"]) <= 1.25 * diameter + 1e-15
    # rounded to whole meshes, the cut is the target's (corners relative to corner 0), and it is feasible
    rounded = np.asarray(result.rounded["cut"]["netting"])
    np.testing.assert_array_equal(rounded, target["cut"]["netting"])  # corner 0 is held (default_scale)
    assert result.rounded_violation == 0.0
    assert result.rounded_value < 0.1 * first
    # its foot: 5 meshes of all-transversal cut; its side from foot to top: 3 points and 2 bars, (3, 5) twines
    foot, side = result.cut_report["netting"][:2]
    assert (foot.meshes, foot.rate) == (5, "AT") and side.rate == "3N2B"
    # the history on disk is the one returned, a line per iteration
    lines = [json.loads(line) for line in (out / "history.jsonl").read_text().splitlines()]
    assert len(lines) == len(result.history) == STEPS + 1
    assert min(row["objective"] for row in lines) == pytest.approx(result.value, rel=1e-12)  # the best iterate
    assert all(np.isfinite(row["gradient_norm"]) for row in lines)
    saved = json.loads((out / "design.json").read_text())
    assert saved["rounded_objective"] == pytest.approx(result.rounded_value, rel=1e-12)


def test_the_traced_adjoint_takes_the_same_steps(optimised):
    """adjoint="traced" (jax.value_and_grad of one jitted program around implicit.equilibrium) and the default
    host-driven adjoint compute the same objective and gradient: the first three steps' histories agree to the
    solves' accuracy, and a mistyped path is refused before anything is solved."""
    result, *_ = optimised
    space, objective, start, bounds, *_ = setup()
    traced = optimize.optimize(space, objective, start, optimizer=optax.adam(0.05), steps=3, bounds=bounds,
                               progress=False, round_cut=False, adjoint="traced")
    for host_row, traced_row in zip(result.history[:4], traced.history):
        assert traced_row["objective"] == pytest.approx(host_row["objective"], rel=1e-9)
        assert traced_row["gradient_norm"] == pytest.approx(host_row["gradient_norm"], rel=1e-6)
    with pytest.raises(ValueError, match="adjoint must be one of"):
        optimize.optimize(space, objective, start, steps=1, adjoint="forward")
