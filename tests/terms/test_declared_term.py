"""A term declared outside jaxnet is a full term: declaring it is all it takes.

The toy term here ties every node to its start position by a linear spring of stiffness K (N/m): an energy
on the nodes family, ½ K |x - x_start|², with a hand-written stiffness K I and a result group of its own.
Registered for the length of a test, it must be traced, solved (on both stiffness paths), reported in the
force breakdown and given its closed form, with nothing else in jaxnet edited. On a single bar pulled along
its axis by a force F the equilibrium is analytic: the free end moves u = F / (EA/L + K), the bar carries
EA u/L and the springs K u.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
import pytest

from jaxnet import figures, model
from jaxnet.net import Net, Rope
from jaxnet.scene import Environment
from jaxnet.solve import statics
from jaxnet.solve.options import Newton
from jaxnet.terms import term as term_lib

K = 40.0       # N/m, the toy spring
EA = 2000.0    # N, the bar
L = 1.5        # m, the bar's length
F = 12.0       # N, the pull on the free end


def anchor_energy(x, anchor, stiffness):
    """½ K |x - anchor|² (J) of one node (x: (1, 3))."""
    gap = x[0] - anchor
    return 0.5 * stiffness * jnp.dot(gap, gap)


def anchor_stiffness(x, anchor, stiffness):
    """Its Hessian, K I (N/m), written by hand."""
    return stiffness * jnp.eye(3)


ANCHORS = term_lib.Group("anchors_N")
TOY = term_lib.Term(
    name="toy_anchor_spring", family="nodes", kind=term_lib.ENERGY, element=anchor_energy,
    arguments=lambda p, env: {"anchor": p.position, "stiffness": K},
    active=lambda scene, dynamic: {}, group=ANCHORS, closed_form=term_lib.ClosedForm(anchor_stiffness))


@pytest.fixture
def toy_term():
    term_lib.register(TOY)
    try:
        yield TOY
    finally:
        term_lib.unregister(TOY.name)


def pulled_bar():
    net = Net(environment=Environment(gravity=0.0))
    net.cable("bar", start=(0.0, 0.0, 0.0), end=(L, 0.0, 0.0), rope=Rope(ea=EA, diameter=0.004), n_bars=1)
    net.fix((0.0, 0.0, 0.0))
    net.attach((L, 0.0, 0.0), force=(F, 0.0, 0.0))
    return net.build()


@pytest.mark.parametrize("stiffness", ["closed_form", "autodiff"])
def test_a_declared_term_is_solved_and_reported(toy_term, stiffness):
    scene = pulled_bar()
    active = model.active_terms(scene)
    assert [t.name for t in active] == ["bar_tension", "node_force", "toy_anchor_spring"]
    assert model.stiffness_paths(active, stiffness)["toy_anchor_spring"] == stiffness
    eq = statics.solve(scene, Newton(tol=1e-9, stiffness=stiffness))
    u = F / (EA / L + K)
    np.testing.assert_allclose(np.asarray(eq.x)[1], [L + u, 0.0, 0.0], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(eq.reaction(scene).sum(axis=0), [-EA * u / L, 0.0, 0.0], rtol=1e-8)
    result = figures.summary(scene, eq)
    assert "toy_anchor_spring" in result["terms"]
    np.testing.assert_allclose(result["forces_N"]["anchors_N"], [-K * u, 0.0, 0.0], rtol=1e-8)
    # the balance of the net: the external groups and the reactions sum to zero
    total = sum(np.asarray(v) for v in result["forces_N"].values()) + np.asarray(result["reaction_N"])
    np.testing.assert_allclose(total, 0.0, atol=1e-8)


def test_the_term_is_gone_once_unregistered(toy_term):
    term_lib.unregister(TOY.name)
    scene = pulled_bar()
    assert "toy_anchor_spring" not in [t.name for t in model.active_terms(scene)]
    assert "anchors_N" not in term_lib.groups()
    eq = statics.solve(scene, Newton(tol=1e-9))
    np.testing.assert_allclose(np.asarray(eq.x)[1], [L + F * L / EA, 0.0, 0.0], rtol=1e-10)  # the bar alone


def test_a_name_is_declared_once():
    with pytest.raises(ValueError, match="already registered"):
        term_lib.register(term_lib.Term(
            name="netting_tension", family="nodes", kind=term_lib.ENERGY, element=anchor_energy,
            arguments=lambda p, env: {}, active=lambda scene, dynamic: None))
