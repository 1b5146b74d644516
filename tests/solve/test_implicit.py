"""Derivatives of a static equilibrium by the implicit function theorem (jaxnet.solve.implicit).

Every check is against finite differences of the *full solve*, in float64: the derivative must be that of the
root itself, whatever the Newton iterations did. The differences are fourth-order central ones with a step
of 1e-3 (relative) and every solve is converged to 1e-10 N: measured, their error is 1e-10-3e-9 of the
derivative; second-order differences would need a step so small (1e-5) that the solves' roundoff (a few
1e-12 N on these forces, over soft pendulum modes of ~1 N/m) shows at 1e-4.

The scenes are small (a hanging panel of 4 meshes in a current, 15 nodes) and every derivative goes
through one jitted function of a parameter vector, so the file compiles a handful of programs."""

import dataclasses
import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.net import Twine
from jaxnet.scene import Environment
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import implicit, results, statics
from jaxnet.solve.options import Newton

NEWTON = Newton(tol=1e-10, max_iter=100, damping=1e-6, stall_window=None, line_search=30)
#: the parameters and the scene field each one scales (the design families a scene carries)
FIELDS = {
    "twine diameter": lambda s: s.netting.diameter,
    "twine EA": lambda s: s.netting.ea_traction,
    "mesh side l0": lambda s: s.netting.l0,
    "twine coordinates": lambda s: s.netting.uv,
    "sinker bar length": lambda s: s.bars.rest_length,
    "fixed node positions": lambda s: s.nodes.position,
    "current speed": lambda s: s.environment.current_speed,
}


@functools.lru_cache(maxsize=None)
def panel_in_current(ea_compression=2000.0):
    """The hanging panel (4 meshes, 15 nodes, two fixed corners, its sinker bar hinged) in a 0.4 m/s current
    across it, solved."""
    twine = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=ea_compression)
    net = hanging_panel(meshes=4, step=0.05, twine=twine, sinker_bending_stiffness=0.0).net
    net.environment = Environment(current_speed=0.4, current_direction=np.array([0.0, 1.0, 0.0]))
    scene = net.build()
    first = statics.solve(scene, tol=1e-9)
    return scene, implicit.structure_of(scene), np.asarray(first.x)


def scaled(scene, theta):
    """The scene with each family of :data:`FIELDS` multiplied by (1 + theta[k]) (the fixed positions:
    moved by theta[k] along x for the fixed nodes, which is what a design moving a mounting does)."""
    for k, (name, field) in enumerate(FIELDS.items()):
        if name == "sinker bar length":
            # the sinker bar only: the headline spans the two fixed corners at exactly its rest length, so a
            # longer one goes slack (a kink of the force, no derivative there)
            sinker = jnp.asarray(np.asarray(scene.bars.cable) == scene.cable_names.index("sinker bar"))
            scene = eqx.tree_at(field, scene, jnp.asarray(field(scene)) * (1.0 + theta[k] * sinker))
        elif name == "fixed node positions":
            fixed = np.asarray(scene.nodes.fixed).all(axis=1)
            scene = eqx.tree_at(field, scene, jnp.asarray(scene.nodes.position) + theta[k] * jnp.asarray(fixed)[:, None]
                                * jnp.array([1.0, 0.0, 0.0]))
        else:
            scene = eqx.tree_at(field, scene, jnp.asarray(field(scene)) * (1.0 + theta[k]))
    return scene


@functools.lru_cache(maxsize=None)
def solver(ea_compression=2000.0):
    scene, structure, x0 = panel_in_current(ea_compression)

    @jax.jit
    def positions(theta):
        return implicit.equilibrium(scaled(scene, theta), structure, x0=x0, solver=NEWTON).x

    return positions


def central_differences(f, theta, h=1e-3):
    """Fourth-order central differences of f at theta, a column per parameter."""
    cols = []
    for k in range(theta.size):
        e = np.zeros_like(theta)
        e[k] = h
        g = lambda t: np.asarray(f(t))  # noqa: E731
        cols.append((8 * (g(theta + e) - g(theta - e)) - (g(theta + 2 * e) - g(theta - 2 * e))) / (12 * h))
    return np.stack(cols, axis=-1)


@functools.lru_cache(maxsize=None)
def jacobian(ea_compression=2000.0):
    """d x*/d θ (N, 3, families) by forward mode (jacfwd)."""
    return np.asarray(jax.jacfwd(solver(ea_compression))(np.zeros(len(FIELDS))))


def test_jacobian_of_the_equilibrium_matches_finite_differences(ea_compression=2000.0):
    """d x*/d θ for every family (forward mode) against differences of the solve, to 1e-6 of the largest
    entry. (With EA_c = 0 the twines across the current go slack and the same holds, measured; a design with
    slack twines is in tests/design/test_design_gradients.py, kept once for the suite's time.)"""
    positions = solver(ea_compression)
    theta = np.zeros(len(FIELDS))
    forward = jacobian(ea_compression)
    fd = central_differences(positions, theta)
    for k, name in enumerate(FIELDS):
        scale = np.abs(fd[..., k]).max()
        assert scale > 1e-8, name  # every family does move the net
        np.testing.assert_allclose(forward[..., k], fd[..., k], rtol=0, atol=1e-6 * scale, err_msg=name)


@functools.lru_cache(maxsize=None)
def deflection_gradient():
    """jax.grad of the mean downstream displacement of the nodes (the net's deflection by the current, m)."""
    positions = solver()
    return jax.jit(jax.grad(lambda t: jnp.mean(positions(t)[:, 1])))


def test_gradient_of_a_figure_by_the_adjoint():
    """jax.grad (reverse mode: one solve with K^T) of a scalar figure of the equilibrium equals the
    forward-mode Jacobian's contraction (tested against differences above), to the linear solves' accuracy."""
    g = np.asarray(deflection_gradient()(np.zeros(len(FIELDS))))
    forward = jacobian()[:, 1, :].mean(axis=0)
    np.testing.assert_allclose(g, forward, rtol=0, atol=1e-9 * np.abs(forward).max())
    # a stiffer twine and a faster current: the net deflects less, more
    assert g[list(FIELDS).index("current speed")] > 0
    assert g[list(FIELDS).index("twine EA")] < 0



def test_second_derivative_by_forward_over_adjoint_matches_differences_of_the_gradient():
    """The derivative of the adjoint gradient along a design direction (a Hessian-vector product: forward mode
    over reverse) against fourth-order differences of the gradient itself. Its one term that the first
    derivative lacks is the change of K with the design (``custom_linear_solve`` differentiates its matvec,
    the assembled tangent's sparse product), so a matvec that is not K's exact derivative shows here."""
    gradient = deflection_gradient()
    theta = np.zeros(len(FIELDS))
    direction = np.linspace(1.0, -0.5, len(FIELDS))
    hvp = np.asarray(jax.jvp(gradient, (theta,), (direction,))[1])
    fd = central_differences(lambda t: gradient(theta + t[0] * direction), np.zeros(1))[:, 0]
    scale = np.abs(fd).max()
    assert scale > 1e-8
    np.testing.assert_allclose(hvp, fd, rtol=0, atol=1e-5 * scale)

def test_vmap_of_gradients_over_designs_equals_the_loop():
    gradient = deflection_gradient()
    batch = np.array([np.zeros(len(FIELDS)), np.full(len(FIELDS), 0.01), np.linspace(-0.02, 0.02, len(FIELDS))])
    together = np.asarray(jax.vmap(gradient)(batch))
    one_by_one = np.stack([np.asarray(gradient(t)) for t in batch])
    # the batched Newton iterations round differently: 6e-11 of the gradient measured
    np.testing.assert_allclose(together, one_by_one, rtol=0, atol=1e-9 * np.abs(one_by_one).max())
    assert np.abs(together[1] - together[0]).max() > 1e-6 * np.abs(together[0]).max()  # the designs differ


def test_equilibrium_is_the_static_solvers_and_failures_are_reported():
    scene, structure, x0 = panel_in_current()
    eq = implicit.equilibrium(scene, structure, x0=x0, solver=NEWTON)
    assert float(eq.residual_N) <= NEWTON.tol and int(eq.status) == results.CONVERGED
    np.testing.assert_allclose(np.asarray(eq.x), np.asarray(solver()(np.zeros(len(FIELDS)))), rtol=0, atol=1e-12)
    reference = statics.solve(scene, tol=1e-10)
    np.testing.assert_allclose(np.asarray(eq.x), np.asarray(reference.x), rtol=0, atol=1e-9)
    # from the flat start, two iterations are not enough: the reason, the residual and the node are named
    few = dataclasses.replace(NEWTON, max_iter=2)
    with pytest.raises(implicit.ImplicitError, match=r"maximum number of iterations reached after 2 iterations; "
                                                     r"largest residual .* N at node \d+"):
        implicit.equilibrium(scene, structure, solver=few)
    eq = implicit.equilibrium(scene, structure, solver=few, throw=False)
    assert int(eq.status) == results.MAX_ITERATIONS and float(eq.residual_N) > 1e-3
    # under a transformation the error is raised when the program runs
    with pytest.raises(Exception, match="did not converge"):
        jax.block_until_ready(jax.vmap(lambda x: implicit.equilibrium(scene, structure, x0=x, solver=few).x)(
            np.asarray(scene.nodes.position)[None]))
