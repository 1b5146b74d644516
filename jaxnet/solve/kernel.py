"""The residual, energy and tangent of a scene at free coordinates: what every solver iterates on.

The unknowns are the free coordinates x (m) of the nodes (:class:`jaxnet.model.assemble.Pattern` ``free``; the
fixed ones keep the scene's positions). At x the Newton iteration needs

* the out-of-balance force F = L - ∂E/∂x + F_nc (N): the constant loads L (:func:`loads`), minus the
  gradient of the stored energy E (:func:`stored_energy`: the terms' energies, the elastic ones scaled
  during the stiffness continuation; in a time step the inertia's too), plus the non-conservative forces
  F_nc (drag, catch pressure), which have no potential (:func:`evaluate`);
* a merit for its line search (:func:`merit`): the potential energy with F_nc frozen at the iterate;
* the tangent K = -∂F/∂x (N/m) on the sparse pattern (:func:`tangent`), or its element matrices before
  their sum (:func:`tangent_blocks`).

The static solve (:mod:`jaxnet.solve.statics`), the time steps (:mod:`jaxnet.solve.dynamics`), the implicit
differentiation (:mod:`jaxnet.solve.implicit`), the adjoints (:mod:`jaxnet.solve.adjoint_dynamics`) and the
figures all call these. Pure functions of their arguments, jittable (``model``, ``stiffness`` static), in
the order of floating operations the iteration has always used: no program cache and no driver logic here.

A time step (``step``, :class:`jaxnet.solve.dynamics.TimeStep`: the past positions and velocities, Δt, the
masses, the water's load) adds the inertia energy ½ (M + M_a)/Δt² |x - x_n - Δt v_n|² (4.265), the water's
acceleration as a load, and the drag on the velocities relative to the water (4.272-4.276); its tangent
gains (M + M_a)/Δt² on the diagonal (4.271).

Units: m, N, J, N/m.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet.model import assemble
from jaxnet.solve import spring_network


def loads(scene, model, step=None):
    """(N, 3) the constant nodal loads (N): weight, buoyancy, applied forces; in a time step plus the water's
    inertia (M_a + ρV) γ_h (``step.water_load``)."""
    load = assemble.loads(scene, model)
    return load if step is None else load + step.water_load


def stored_energy(X, scene, model, scale, step):
    """The energy (J) the Newton iteration minimises, loads apart: the terms' (elastic ones scaled by
    ``scale``), plus in a time step the inertia's ½ (M + M_a)/Δt² |x - x_predicted|², whose gradient is the
    force of inertia."""
    e = assemble.energy(X, scene, model, scale)
    return e if step is None else e + step.inertia_energy(X)


def merit(e_stored, X, frozen_load):
    """The line search's merit (J): the stored energy minus the work of ``frozen_load`` (N, 3) at X.

    Drag and catch pressure have no potential. Each iteration's line search uses the potential energy of
    the conservative terms under the loads *plus* these forces frozen at the iterate: its slope along the
    step is -F.dx as for a conservative net, and at a fixed point F = 0."""
    return e_stored - jnp.sum(frozen_load * X)


def evaluate(x, f_frozen, load, scale, scene, pattern, model, step=None, previous=None):
    """At free coordinates x: the residual and what the line search needs, in one traced evaluation.
    ``load``: the (N, 3) constant nodal loads (N, :func:`loads`), computed once per solve; ``scale``: the
    factor on the elastic energies (1, or less during the stiffness continuation); ``step``: None in
    statics, in a time step its past and masses (the inertia energy joins the stored energy, the drag takes
    the vertices' velocities); ``previous``: the force terms' states at the last accepted iterate (what this
    returns as ``state``), which start their solutions here (:func:`jaxnet.model.assemble.states`), or None.

    Returns (energy, force, f_nc, merit, state): the stored energy (J); the out-of-balance force (N, 3)
    at every node (at fixed coordinates minus the reactions); the non-conservative nodal forces (N, 3);
    the merit (J) with the non-conservative forces frozen at ``f_frozen`` (see :func:`merit`); the force
    terms' global states (the catch front), reused by the tangent at the same point.
    """
    X = assemble.positions(x, scene, pattern)
    e, grad = jax.value_and_grad(stored_energy)(X, scene, model, scale, step)
    if any(t.term.kind == "force" for t in model):
        state = assemble.states(X, scene, model, previous)
        f_nc = assemble.forces(X, scene, model, state, None if step is None else step.motion)
        # strongly typed, as the placeholders the tangent is compiled with (a weakly typed leaf, from a
        # Python scalar, would make a second compilation of the tangent at the first iteration)
        state = jax.tree.map(lambda a: jax.lax.convert_element_type(a, jnp.result_type(a)), state)
    else:
        state, f_nc = {}, jnp.zeros_like(X)
    return e, load - grad + f_nc, f_nc, merit(e, X, load + f_frozen), state


def force(x, scene, pattern, model, step=None):
    """(N, 3) the out-of-balance force F (N) at free coordinates x (m), fixed coordinates included (minus the
    reactions there): the loads minus the energy's gradient plus the non-conservative forces, the Newton
    iteration's own evaluation (:func:`evaluate`) from no earlier state; zero at the free coordinates of an
    equilibrium (of the time step ``step``, if not None)."""
    load = loads(scene, model, step)
    return evaluate(x, jnp.zeros_like(load), load, 1.0, scene, pattern, model, step)[1]


def tangent(x, state, scale, scene, pattern, model, stiffness="autodiff", step=None):
    """CSR entries (nnz,) of the tangent K = -dF/dx (N/m) at free coordinates x (force terms' states given,
    the elastic energies scaled by ``scale``; ``stiffness``: its path, see
    :class:`jaxnet.solve.options.Newton`; ``step``: in a time step, its inertia (M + M_a)/Δt² on the
    diagonal (4.271) and the drag's dependence on the velocities)."""
    X = assemble.positions(x, scene, pattern)
    if step is None:
        return assemble.tangent(X, scene, model, pattern, state, scale, stiffness)
    data = assemble.tangent(X, scene, model, pattern, state, scale, stiffness, step.motion)
    return data.at[pattern.diagonal].add(step.inertia_stiffness().ravel()[pattern.free])


def tangent_blocks(x, state, scale, scene, pattern, model, stiffness="autodiff", step=None):
    """The tangent's element matrices at free coordinates x, {family: (E, 3k, 3k)} (N/m,
    :func:`jaxnet.model.assemble.tangent_blocks`): what :func:`tangent` sums into the pattern, without the inertia's
    diagonal of a time step (``step``: its drag's dependence on the velocities is in). The host loop
    (:func:`jaxnet.solve.statics.host_loop`) sums them in a program of its own
    (:func:`jaxnet.model.assemble.scatter_stiffnesses`), which XLA runs faster than the pair compiled as one
    (``tangent_blocks`` says why; ``benchmarks/femnet_cases.py`` times the solves)."""
    X = assemble.positions(x, scene, pattern)
    return assemble.tangent_blocks(X, scene, model, state, scale, stiffness, None if step is None else step.motion)


def springs(scene, pattern, model):
    """CSR entries (nnz,) of the spring-network stiffness S (N/m) over the free coordinates: the metric of
    the Newton iteration's damping (:mod:`jaxnet.solve.spring_network`)."""
    return spring_network.stiffness(scene, model, pattern)


def nodal_norm(f_free, pattern, n_nodes):
    """(N,) the norm of a vector on the free coordinates at each node (zero at fixed coordinates)."""
    full = jnp.zeros(3 * n_nodes).at[pattern.free].set(f_free).reshape(-1, 3)
    return jnp.sqrt(jnp.sum(full * full, axis=1))


def state_shapes(scene, pattern, model):
    """The shapes and dtypes of the force terms' states (:func:`jaxnet.model.assemble.states`, the catch front) of
    ``scene``, found by tracing them alone (``jax.eval_shape``: no computation)."""
    x = jax.ShapeDtypeStruct(pattern.free.shape, jnp.float64)
    return jax.eval_shape(lambda x: assemble.states(assemble.positions(x, scene, pattern), scene, model), x)


def placeholders(shapes):
    """States standing for "none yet" (:func:`evaluate`'s ``previous`` before a first evaluation): NaN where
    the leaf is real (a NaN start is ignored: the catch front then starts from the middle of the net),
    zeros otherwise, with the shapes and dtypes of ``shapes``, strongly typed as :func:`evaluate` returns
    its states (a weakly typed leaf would compile the evaluation a second time)."""
    return jax.tree.map(
        lambda a: np.full(a.shape, np.nan if jnp.issubdtype(a.dtype, jnp.inexact) else 0, a.dtype), shapes)
