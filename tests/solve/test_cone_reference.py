"""jaxnet's static solver against an independent one: the net in still water as a second-order cone program
(validation/cone_reference.py), solved by Clarabel's interior-point method. Where the equilibrium is the minimum
of a convex program, both answers balance, reach the same minimum of the potential energy, and the cones'
multipliers are the twines' and bars' tensions."""

import dataclasses

import numpy as np
import pytest

import jaxnet as jn
from jaxnet import figures, geometry
from jaxnet.net import Twine
from jaxnet.scenes.panel import framed_panel
from validation import cone_reference

CASES = {
    # a curtain of 10 x 10 meshes hanging from a headline, lead along its foot: twines, bars and lumped masses
    "curtain": lambda: cone_reference.wall_in_still_water(0.1, meshes=10, sinker_kg=0.5),
    # a horizontal panel held along its border, sagging under a sinker: taut only where the sinker pulls
    "framed panel": lambda: framed_panel(meshes=10, step=0.05).scene,
}


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_damped_newton_equilibrium_is_the_cone_programs_minimum(name):
    scene = CASES[name]()
    solver = jn.Newton(method="damped")
    eq = jn.solve_static(scene, solver)
    cone = cone_reference.solve_cone(scene)
    assert cone.status == "Solved"
    ours_residual, ours_energy = cone_reference.balance(scene, eq.x)
    theirs_residual, theirs_energy = cone_reference.balance(scene, cone.x)
    # both balance to the Newton tolerance, each by jaxnet's residual
    assert ours_residual <= solver.tol and theirs_residual <= solver.tol
    # the same minimum: jaxnet's answer is no lower than the program's (measured: equal to 1e-11 relative), and
    # the program's own value is jaxnet's potential at Clarabel's positions
    assert ours_energy == pytest.approx(theirs_energy, rel=1e-9)
    assert cone.potential == pytest.approx(theirs_energy, rel=1e-8)
    # these two have one equilibrium, not a flat set of them: the same positions (measured: 1e-6 m apart)
    assert np.abs(np.asarray(eq.x) - cone.x).max() < 1e-4
    # the cones' multipliers are the rods' tensions: n T for a family of a triangle's n = |d|/2 twines, T for a bar;
    # to 1e-4 of the largest, the interior point's accuracy on rods that are just straight (|U| = l0: both the
    # multiplier and the gap near zero; measured: 3e-3 N of 38 N)
    tension = np.asarray(figures.twine_tensions(scene, cone.x))
    count = np.abs(np.asarray([float(geometry.twine_determinant(uv)) for uv in np.asarray(scene.netting.uv)])) / 2
    expected = [count * tension[:, 0], count * tension[:, 1]]
    if scene.bars is not None:
        expected.append(np.asarray(figures.bar_tensions(scene, cone.x)))
    expected = np.concatenate(expected)
    np.testing.assert_allclose(cone.tension, expected, rtol=0, atol=1e-4 * expected.max())


def test_what_is_not_convex_is_refused_by_name():
    still = cone_reference.wall_in_still_water(0.1, meshes=10)
    moving = dataclasses.replace(still, environment=jn.Environment(current_speed=0.5))
    with pytest.raises(ValueError, match="netting_drag"):
        cone_reference.solve_cone(moving)
    stiff = framed_panel(meshes=4, step=0.1, twine=Twine(l0=0.025, ea=2000.0, diameter=1.5e-3,
                                                          ea_compression=2000.0)).scene
    with pytest.raises(ValueError, match="ea_compression"):
        cone_reference.solve_cone(stiff)


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_primal_dual_method_reaches_the_cone_programs_minimum(name):
    """jaxnet's primal-dual method (jaxnet.solve.interior: the rods' tensions and gaps eliminated into the node
    system) balances the net to the tolerance and reaches Clarabel's minimum of the potential, at its positions."""
    scene = CASES[name]()
    eq = jn.solve_static(scene, jn.Newton(method="primal-dual"))
    cone = cone_reference.solve_cone(scene)
    residual, energy = cone_reference.balance(scene, eq.x)
    assert residual <= jn.Newton().tol
    assert energy == pytest.approx(cone_reference.balance(scene, cone.x)[1], rel=1e-9)
    assert np.abs(np.asarray(eq.x) - cone.x).max() < 1e-4
