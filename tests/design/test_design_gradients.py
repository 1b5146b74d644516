"""Design gradients end to end: θ -> scene -> equilibrium -> figure, for every design family.

The rig of tests/design/test_design_space.py (a tapered panel on two bridles with a headline, a footrope, a float
and two sinkers, in a current) carries every family of the design space; its twines here have no knots and
no bending (not design families; their element Hessians triple the compile time). Twines across the current
are slack (in compression, against a compression stiffness of a tenth of EA: checked), so the derivative is
taken on a design with slack twines, away from the kink at zero strain. Along one
direction per family (the cut: every corner but corner 0 moved; the others: a relative change of each
entry), the derivative of two figures of the equilibrium (the drag, N, and the mean depth of the net, m) by
forward mode and by reverse mode (the adjoint) is compared with fourth-order central differences of the full
solve (step 1e-3, solves to 1e-10 N: see tests/solve/test_implicit.py), to 1e-6 relative."""

import functools

import jax
import jax.numpy as jnp
import numpy as np

import jaxnet  # noqa: F401
from jaxnet.design import objectives
from jaxnet.design.space import DesignSpace
from jaxnet.solve import implicit, programs, statics
from jaxnet.solve.options import Newton
from jaxnet.net import Twine
from test_design_space import L0, rig

NEWTON = Newton(tol=1e-10, max_iter=100, damping=1e-6, stall_window=None, line_search=30)


@functools.lru_cache(maxsize=1)
def setup():
    space = DesignSpace(rig(Twine(l0=L0, ea=1000.0, diameter=2e-3, ea_compression=100.0)))
    structure = implicit.structure_of(space.reference)
    theta0 = space.initial()
    x0 = np.asarray(statics.solve(space.reference, tol=NEWTON.tol).x)  # the reference's equilibrium, to 1e-10 N
    rng = np.random.default_rng(7)
    families = [f for f in sorted(theta0) if theta0[f]]
    directions = {}
    for f in families:
        if f == "cut":
            directions[f] = {k: np.vstack([np.zeros((1, 2)), rng.choice([-1.0, 1.0], size=(len(v) - 1, 2))])
                             for k, v in theta0[f].items()}
        else:
            directions[f] = {k: np.asarray(v) * rng.uniform(0.5, 1.0, size=np.shape(v)) for k, v in theta0[f].items()}

    def theta(t):
        return {f: {k: theta0[f][k] + t[i] * directions[f][k] for k in theta0[f]} for i, f in enumerate(families)}

    drag = objectives.drag()

    @jax.jit
    def figures(t):
        scene = space.scene(theta(t))
        eq = implicit.equilibrium(scene, structure, x0=x0, solver=NEWTON)
        return jnp.stack([drag(objectives.Outcome(eq.x, scene, structure.model)), jnp.mean(eq.x[:, 2])])

    def figures_and_value(t):
        value = figures(t)
        return value, value

    # one program gives the forward derivative and the figures themselves: the differences' full solves are
    # its values at the neighbouring designs (the same solve, from the same start, to the same tolerance).
    # Both derivatives compiled with the XLA options of jaxnet's own programs (programs.jit)
    forward = programs.jit(jax.jacfwd(figures_and_value, has_aux=True))
    reverse = programs.jit(jax.jacrev(figures))
    return families, forward, reverse, space, x0


def test_every_family_forward_reverse_and_finite_differences():
    families, forward_and_value, adjoint, space, x0 = setup()
    assert families == ["buoyancy", "cable_length", "cut", "ea", "hanging_ratio", "mesh_side", "sinker_mass",
                        "twine_diameter"]
    t0 = np.zeros(len(families))
    forward = np.asarray(forward_and_value(t0)[0])           # (2 figures, families)
    reverse = np.asarray(adjoint(t0))                        # the adjoint: one K^T solve per figure
    np.testing.assert_allclose(reverse, forward, rtol=0, atol=1e-9 * np.abs(forward).max(axis=1, keepdims=True).max())
    h = 1e-3
    for k, family in enumerate(families):
        e = np.zeros_like(t0)
        e[k] = h
        f = lambda t: np.asarray(forward_and_value(t)[1])  # noqa: E731
        fd = (8 * (f(t0 + e) - f(t0 - e)) - (f(t0 + 2 * e) - f(t0 - 2 * e))) / (12 * h)
        for i, figure in enumerate(("drag", "mean depth")):
            assert abs(fd[i]) > 1e-9, (family, figure)  # every family changes both figures
            assert abs(forward[i, k] - fd[i]) <= 1e-6 * abs(fd[i]), (family, figure, forward[i, k], fd[i])
    from jaxnet import figures as figures_lib

    tensions = figures_lib.twine_tensions(space.reference, x0)
    assert (tensions <= 0).any()  # slack twines at this design (x0 is its equilibrium)
