"""The primal-dual static method (jaxnet.solve.interior): the rods it gives unknowns to are the terms' own energy,
it reaches the damped Newton's equilibrium and the cone program's minimum, and it is chosen by name."""

import math
import pathlib

import jax
import numpy as np
import pytest

import jaxnet as jn
from jaxnet import cli, model as model_lib
from jaxnet.model import assemble
from jaxnet.io.femnet import read_don
from jaxnet.materials import rod_bending_stiffness
from jaxnet.solve import interior, options
from jaxnet.scenes.panel import framed_panel, hanging_panel
from jaxnet.terms import cable, tension
from validation import cone_reference


@pytest.mark.parametrize("compression", [False, True])
def test_the_rods_of_a_triangle_and_a_bar_sum_to_their_energy(rng, compression):
    """A term's Rods form: sum_r (k_r / 2) max(0, L_r - l0_r)² is the element's energy when no compression stiffness
    is given (stretched, slack and mixed twines), and a term with one is not covered."""
    uv = np.array([[0.0, 0.0], [4.0, 0.0], [0.0, 6.0]])
    for trial in range(6):
        drawn = np.array([[0.0, 0.0, 0.0], [4 * 0.025, 0.0, 0.0], [0.0, 6 * 0.025, 0.0]])
        x = drawn * rng.uniform(0.6, 1.4, 3)[:, None]
        x = x + rng.normal(scale=0.01, size=(3, 3))
        L, l0, k = tension.netting_rods(x, uv, 0.025, 2000.0)
        expected = tension.netting_energy(x, uv, 0.025, 2000.0)
        rods_energy = float(np.sum(0.5 * k * np.maximum(L - l0, 0.0) ** 2))
        assert rods_energy == pytest.approx(float(expected), rel=1e-12, abs=1e-300)
        ends = rng.normal(size=(2, 3))
        L, l0, k = cable.bar_rods(ends, 1.3, 5e4)
        expected = cable.bar_energy(ends, 1.3, 5e4)
        rods_energy = float(np.sum(0.5 * k * np.maximum(L - l0, 0.0) ** 2))
        assert rods_energy == pytest.approx(float(expected), rel=1e-12, abs=1e-300)
    twine = jn.Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=200.0 if compression else 0.0)
    scene = framed_panel(meshes=4, step=0.1, twine=twine).scene
    rods, rest = interior.split(model_lib.active_terms(scene))
    assert ("netting_tension" in [t.name for t in rest]) == compression
    assert ("netting_tension" in [t.name for t in rods]) != compression


def test_the_rods_forces_are_the_energys_gradient():
    """interior.measure's pull of the rods' own tensions k max(0, L - l0) is the gradient of the tension terms'
    energy: the residual the method converges on is the damped Newton's."""
    scene = cone_reference.wall_in_still_water(0.1, meshes=10)
    model = model_lib.active_terms(scene)
    rods, _ = interior.split(model)
    pattern = assemble.build_pattern(scene, model)
    rng = np.random.default_rng(4)
    x = np.asarray(scene.nodes.position).ravel()[np.asarray(pattern.free)]
    x = x * (1.0 + 0.05 * rng.normal(size=x.shape))
    *_, pull_own, energy = interior.measure(x, np.zeros(interior.count(scene, rods)), scene, pattern, rods)
    X = assemble.positions(x, scene, pattern)
    gradient = jax.grad(lambda X: assemble.energy(X, scene, rods))(X)
    np.testing.assert_allclose(np.asarray(pull_own), np.asarray(gradient), rtol=1e-10, atol=1e-10)
    assert float(energy) == pytest.approx(float(assemble.energy(X, scene, rods)), rel=1e-12)


def test_the_still_water_wall_is_the_cone_programs_minimum_in_tens_of_iterations():
    """A curtain of tension-only twines under a sinker in still water: the primal-dual method balances it to the
    tolerance and reaches the minimum Clarabel finds (the potential energy, to 1e-9), in far fewer iterations than
    the damped Newton (measured: 22 against 236 on this wall; validation/REPORT.md has the three sizes)."""
    scene = cone_reference.wall_in_still_water(0.1)
    eq = jn.solve_static(scene, method="primal-dual")
    damped = jn.solve_static(scene, method="damped")
    cone = cone_reference.solve_cone(scene)
    residual, energy = cone_reference.balance(scene, eq.x)
    _, cone_energy = cone_reference.balance(scene, cone.x)
    assert residual <= options.TOL_N
    assert energy == pytest.approx(cone_energy, rel=1e-9)
    assert int(eq.iterations) <= 50 < int(damped.iterations)


def _reactions(scene, eq):
    """The force on the fixings (N, 3 components summed over the fixed nodes): minus the out-of-balance force there."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool)
    return -(np.asarray(eq.force) * fixed).sum(axis=0)


@pytest.mark.parametrize("speed", [0.0, 0.5])
def test_both_methods_reach_the_same_equilibrium(speed):
    """The hanging panel (its sinker bar bends: not a cone program) in still water and in a current: both methods
    converge, and the forces on the fixings agree to 0.1 % (the issue's criterion; measured: 2.2e-6 of the force, in
    still water and in 0.5 m/s)."""
    rod = math.sqrt(4.0 * 1.0 / (math.pi * 11340.0))  # the diameter (m) of a lead rod of 1 kg/m
    net = hanging_panel(meshes=12, step=0.1, twine=jn.Twine(l0=0.025, ea=2000.0, diameter=1.5e-3),
                        sinker_bending_stiffness=rod_bending_stiffness(rod)).net
    if speed:
        net.environment = jn.Environment(current_speed=speed, current_direction=(0.0, 1.0, 0.0))
    scene = net.build()
    a = jn.solve_static(scene, method="primal-dual")
    b = jn.solve_static(scene, method="damped")
    ra, rb = _reactions(scene, a), _reactions(scene, b)
    assert np.linalg.norm(ra - rb) <= 1e-3 * np.linalg.norm(rb)


def test_a_scene_without_tension_only_rods_is_solved_by_the_damped_method():
    """Twines with a compression stiffness have no rods: "primal-dual" is the damped Newton, bit for bit."""
    twine = jn.Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=2000.0)
    scene = framed_panel(meshes=4, step=0.1, twine=twine).scene
    a = jn.solve_static(scene, method="primal-dual")
    b = jn.solve_static(scene, method="damped")
    assert int(a.iterations) == int(b.iterations)
    np.testing.assert_array_equal(np.asarray(a.x), np.asarray(b.x))


def test_the_method_is_checked_and_offered_on_the_command_line():
    with pytest.raises(ValueError, match="method must be one of"):
        jn.Newton(method="interior")
    parser = cli.argument_parser()
    assert parser.parse_args(["run", "--method", "primal-dual"]).method == "primal-dual"
    choices = next(a.choices for a in parser._subparsers._group_actions[0].choices["run"]._actions
                   if a.dest == "method")
    assert tuple(choices) == options.METHODS


def test_where_the_primal_dual_method_stops_short_the_damped_method_solves_from_the_start():
    """FEMNET's nr_20_0_0_3_2 (a flat panel of stiff twines that must swing down to hang: turned through large
    angles from the drawn start): the primal-dual method does not balance it within its budget, and the damped
    method then solves it from the start, along its own path: the same iterations after the budget and the same
    answer, bit for bit."""
    case = read_don(pathlib.Path(__file__).resolve().parents[1] / "data" / "femnet" / "nr_20_0_0_3_2.don")
    both = jn.solve_static(case, method="primal-dual")
    damped = jn.solve_static(case, method="damped")
    budget = min(interior.BUDGET, case.solver.max_iter * interior.SHARE)
    assert both.converged and int(both.iterations) == budget + int(damped.iterations)
    np.testing.assert_array_equal(np.asarray(both.x), np.asarray(damped.x))
    assert np.asarray(both.history)[int(both.iterations)] == float(damped.residual_N)


def test_a_net_with_a_catch_is_left_to_the_damped_method():
    """A cod-end holding a catch (its pressure gives it an inverted balanced shape too, which the primal-dual method's
    merit does not tell from the filled one) is solved by the damped method, bit for bit; a cage in a current, whose
    drag reads no catch front, by the primal-dual method."""
    from jaxnet.scenes.cage import fish_cage
    from jaxnet.scenes.codend import codend

    case = codend(meshes_around=8, meshes_along=6, catch_m3=0.01)
    assert not interior.suits(model_lib.active_terms(case.scene))
    a = jn.solve_static(case.scene, method="primal-dual")
    b = jn.solve_static(case.scene, method="damped")
    assert int(a.iterations) == int(b.iterations)
    np.testing.assert_array_equal(np.asarray(a.x), np.asarray(b.x))
    assert interior.suits(model_lib.active_terms(fish_cage(step=2.0).scene))
