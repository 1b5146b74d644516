"""Differentiable static equilibrium: the derivative of x*(θ) by the implicit function theorem.

The equilibrium x* of a scene is the root of the out-of-balance force on the free coordinates,

    F(x*, θ) = L(θ) - ∂E/∂x (x*, θ) + F_nc(x*, θ) = 0         (N),

θ standing for every float array of the scene (twine coordinates, mesh side, EA, diameters, masses, fixed
node positions, current, ...). Differentiating the identity F(x*(θ), θ) = 0 gives

    K dx* = ∂F/∂θ dθ,        K = -∂F/∂x at x*                  (N/m),

the tangent stiffness the Newton solver factorises. So the sensitivity of the equilibrium costs one
linear solve with K per direction dθ (forward mode, ``jax.jvp``/``jax.jacfwd``) or one solve with K^T per
output (reverse mode, ``jax.grad``/``jax.vjp``: the adjoint), never a differentiation through the Newton
iterations: those are neither needed (only x* matters) nor cheap (the while loop, the line search and the
damping would all be unrolled), and their derivative is not the derivative of the solution until they
have converged anyway.

How it is wired. :func:`equilibrium` solves by :func:`jaxnet.solve.newton.newton_loop` (the jittable
iteration, its factorisations a host callback) inside a ``jax.custom_jvp``. Its JVP rule forms the
right-hand side ∂F/∂θ dθ by ``jax.jvp`` of the residual in θ at the converged x*, assembles K's sparse
entries at x* (:func:`jaxnet.solve.kernel.tangent`, the same code as the solver: closed-form or autodiff
stiffness), and solves through ``jax.lax.custom_linear_solve`` with SuperLU on the host
(:func:`jaxnet.linalg.solve`). ``custom_linear_solve`` is told how to solve with K and with K^T, so JAX
transposes the rule for reverse mode: the same code gives ``jax.grad``, ``jax.jacfwd``, ``jax.jacrev``,
under ``jit`` and ``vmap``. The factorisation of K is kept on the host and reused by every later solve
with the same matrix: K and K^T solves of one equilibrium (a Jacobian's many columns, a gradient's adjoint)
factorise once.

The matrix. K is the exact Jacobian -∂F/∂x for every term whose tangent is exact: all of them except the
catch pressure, whose tangent holds the catch front fixed (the front moves with the net so that the
volume behind it stays the catch's: :mod:`jaxnet.model.assemble`). With a catch the linear solve is therefore
*iterated*: x ← x + K⁻¹ (b - J x), J the exact Jacobian-vector product of F (``jax.jvp`` through the
front's own implicit differentiation), until the relative residual is below 1e-12; the sparse K is then a
preconditioner, each refinement one residual evaluation and one solve with the stored factor.

Conditions. The derivative exists where K is non-singular: a net whose equilibrium holds a mechanism (a
slack region with no stiffness: compression EA 0 and no tension, a mesh free to open with no opening
stiffness) has a singular K and no unique derivative: the sensitivity solve then fails and returns NaN,
which is the honest answer there (a finite number would be a guess). At a design where twines are exactly at their slack length the force is not differentiable
(the tension's kink at zero strain); the derivative returned is the one-sided one of the branch the
tangent takes (slack twines carry the compression stiffness).

Convergence. The derivative is that of the exact root: its accuracy is that of the forward solve, so the
default options (:data:`jaxnet.solve.options.DIFFERENTIABLE`) converge far below the static solver's
:data:`~jaxnet.solve.options.TOL_N`. The solve starts at
``x0`` (default: the scene's positions): for a design optimisation, start each solve at the last
equilibrium (:mod:`jaxnet.design.optimize` does), and solve the first from a flat net with
:func:`jaxnet.solve.statics.solve`, whose stiffness continuation this jittable iteration does not have.

Units: m, N, and whatever θ's units are (the sensitivities are in m per unit of θ).
"""

from __future__ import annotations

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import linalg, model as model_lib
from jaxnet.model import assemble
from jaxnet.scene import checks
from jaxnet.solve import kernel, newton, statics
from jaxnet.solve.options import DIFFERENTIABLE, Newton
from jaxnet.solve.results import CONVERGED, REASONS, Equilibrium

#: refinements of a linear solve when K is not the exact Jacobian (catch), and their relative tolerance
REFINEMENTS = 20
REFINE_RTOL = 1e-12


class ImplicitError(RuntimeError):
    """A differentiable equilibrium did not converge, so neither it nor its derivative is meaningful."""


class Structure(eqx.Module):
    """What a family of designs shares and the differentiable solve needs, computed once on the host from
    a reference scene: ``model``, the active terms (static: part of the compiled program's identity) and
    ``pattern``, the sparse structure of the tangent (index arrays: arguments of the compiled program).
    Every scene solved with it must have the reference's shapes, fixities and connectivity."""

    pattern: assemble.Pattern
    model: tuple = eqx.field(static=True)
    #: True when the assembled K is the exact Jacobian -∂F/∂x: no catch, whose front (a global state the
    #: tangent holds fixed) moves with the net
    exact_tangent: bool = eqx.field(static=True, default=True)


def _without_fronts(*parts):
    """True when none of the scenes (or parts of one) has a catch or panel catches: their fronts, global states
    the assembled tangent holds fixed, move with the net."""
    return all(p.catch is None and p.panel_catches is None for p in parts)


def structure_of(scene, dynamic=False) -> Structure:
    """The :class:`Structure` of ``scene`` (validated here): its active terms and tangent pattern."""
    checks.validate(scene)
    linalg.solver_choice()  # a sparse solver asked for that cannot run here: said before anything compiles
    model = model_lib.active_terms(scene, dynamic=dynamic)
    return Structure(pattern=assemble.build_pattern(scene, model), model=model, exact_tangent=_without_fronts(scene))


def residual(x_free, scene, structure: Structure, step=None):
    """(n,) out-of-balance force F (N) on the free coordinates at free positions ``x_free`` (m): loads minus
    the energy's gradient plus the non-conservative forces (drag, catch pressure); zero at equilibrium. The
    Newton solver's own evaluation (:func:`jaxnet.solve.kernel.force`). ``step``: None, or in an implicit
    time step its :class:`jaxnet.solve.dynamics.TimeStep` (inertia, the water's acceleration, drag on
    relative velocities), whose root is the next positions."""
    pattern = structure.pattern
    return kernel.force(x_free, scene, pattern, structure.model, step).ravel()[pattern.free]


def _split(scene):
    """(float leaves, the rest): the differentiable part of a scene and its structure (ints, bools)."""
    return eqx.partition(scene, eqx.is_inexact_array)


@functools.partial(jax.custom_jvp, nondiff_argnums=(0, 1))
def _root(model, solver, params, rest, pattern, x0, step):
    """Free coordinates of the equilibrium (of the time step ``step``, if not None), and the solve's
    (status, residual_N, iterations, worst_node)."""
    scene = eqx.combine(params, rest)
    eq = newton.newton_loop(x0, scene, pattern, model, solver, step)
    return eq.x.ravel()[pattern.free], (eq.status, eq.residual_N, eq.iterations, eq.worst_node)


def _tangent_solver(x_free, scene, structure, stiffness, step=None):
    """The solves with K = -∂F/∂x at ``x_free`` for ``custom_linear_solve``: (matvec, solve, transpose_solve).

    matvec is the exact Jacobian-vector product J v = -∂F/∂x v: where the assembled K is exact, the product
    with its sparse entries (differentiable in the design: a second derivative differentiates K); with a
    catch, ``jax.jvp`` of the residual. ``custom_linear_solve`` traces matvec and its transpose whether or not
    the solves use them, and the residual's JVP and its transpose are a program as large as the residual's
    (``benchmarks/design.py``), where the sparse product is a gather and a segment sum. The solves use
    K's sparse factorisation (one, kept on the host for all of them) and, where K is not exactly J (a
    catch), refine against J."""
    pattern = structure.pattern
    stiffness_entries = kernel.tangent(x_free, None, 1.0, scene, pattern, structure.model, stiffness, step)
    data = jax.lax.stop_gradient(stiffness_entries)

    if structure.exact_tangent:
        def matvec(v):
            return linalg.matvec(stiffness_entries, pattern.rows, pattern.indices, v)
    else:
        def matvec(v):
            return -jax.jvp(lambda x: residual(x, scene, structure, step), (x_free,), (v,))[1]

    def direct(b, transpose):
        x, ok = linalg.solve(data, b, pattern.indptr, pattern.indices, transpose=transpose, reuse=True)
        return jnp.where(ok, x, jnp.nan)  # a singular K: no unique derivative, NaN rather than a finite guess

    def refined(operator, b, transpose):
        x = direct(b, transpose)
        if structure.exact_tangent:
            return x
        scale = jnp.linalg.norm(b)

        def cond(c):
            x, r, k = c
            return (k < REFINEMENTS) & (jnp.linalg.norm(r) > REFINE_RTOL * scale)

        def body(c):
            x, r, k = c
            x = x + direct(r, transpose)
            return x, b - operator(x), k + 1

        return jax.lax.while_loop(cond, body, (x, b - operator(x), 0))[0]

    def solve(operator, b):
        return refined(operator, b, False)

    def transpose_solve(operator, b):
        return refined(operator, b, True)

    return matvec, solve, transpose_solve


@_root.defjvp
def _root_jvp(model, solver, primals, tangents):
    params, rest, pattern, x0, step = primals
    d_params, d_step = tangents[0], tangents[4]
    x_free, info = _root(model, solver, params, rest, pattern, x0, step)
    structure_ = Structure(pattern=pattern, model=model, exact_tangent=_without_fronts(rest, params))
    scene = eqx.combine(params, rest)
    # ∂F/∂θ dθ at the root: the residual's change with the design (and the step's past), the positions held
    _, rhs = jax.jvp(lambda p, st: residual(x_free, eqx.combine(p, rest), structure_, st), (params, step),
                     (d_params, d_step))
    matvec, solve, transpose_solve = _tangent_solver(x_free, scene, structure_, solver.stiffness, step)
    dx = jax.lax.custom_linear_solve(matvec, rhs, solve, transpose_solve)
    zeros = jax.tree.map(
        lambda a: np.zeros(np.shape(a), jax.dtypes.float0) if not jnp.issubdtype(jnp.result_type(a), jnp.inexact)
        else jnp.zeros_like(a), info)
    return (x_free, info), (dx, zeros)


def _solve_root(params, rest, pattern, x0, step, model, solver):
    return _root(model, solver, params, rest, pattern, x0, step)


# compiled once per scene shape, terms and options: a call from plain Python (a design loop, a test) reuses
# the program; inside a caller's jit, grad or vmap it is inlined into the caller's program
# plain jax.jit: it runs inside the caller's traced functions (a loss, a gradient), where XLA refuses options
root_jit = jax.jit(_solve_root, static_argnames=("model", "solver"))


def equilibrium(scene, structure: Structure | None = None, x0=None, solver: Newton | None = None,
                throw: bool = True, step=None) -> Equilibrium:
    """The static equilibrium of ``scene``, differentiable with respect to every float array in it.

    Args:
      scene: a :class:`jaxnet.scene.Scene`, its float leaves possibly traced (under ``jax.grad``, ``jit``,
        ``vmap``); e.g. the output of :meth:`jaxnet.design.space.DesignSpace.scene`.
      structure: the :class:`Structure` of a reference scene of the same shapes (:func:`structure_of`); None to
        compute it from ``scene`` itself, which must then be concrete (not traced).
      x0: (N, 3) start positions (m), not differentiated; default the scene's positions. Start near the
        answer (the last design's equilibrium): the iteration is plain damped Newton.
      solver: the forward solve's options (:class:`jaxnet.solve.options.Newton`); default
        :data:`jaxnet.solve.options.DIFFERENTIABLE`. Its ``stiffness`` also chooses the tangent of the
        sensitivity solves.
      throw: raise when the solve did not converge: :class:`ImplicitError` from here when ``scene`` is
        concrete, an equinox runtime error (``eqx.error_if``) under ``jit``/``vmap``/``grad``. With
        ``throw=False`` the caller reads ``status``/``residual_N``/``worst_node`` of the result.
      step: None for a static equilibrium; for one implicit time step of the book's scheme, its
        :class:`jaxnet.solve.dynamics.TimeStep` (past positions and velocities, Δt, masses, the water's load:
        differentiable too), the root then being the positions at the end of the step. ``structure`` must
        then be the dynamic one (``structure_of(scene, dynamic=True)``).
    Returns:
      an :class:`~jaxnet.solve.results.Equilibrium`; its ``x`` (N, 3, m) carries the derivatives (the fixed
      coordinates are the scene's own, differentiable as such); ``force`` and ``history`` are not computed
      (zeros / NaN) on this path, nor ``timing`` (None); the other fields describe the forward solve.
    """
    if structure is None:
        structure = structure_of(scene)
    solver = solver or DIFFERENTIABLE
    pattern = structure.pattern
    start = jnp.asarray(scene.nodes.position if x0 is None else x0, dtype=float)
    start = jax.lax.stop_gradient(start.ravel()[pattern.free])
    params, rest = _split(scene)
    x_free, (status, residual_N, iterations, worst) = root_jit(params, rest, pattern, start, step, structure.model,
                                                               solver)
    converged = status == CONVERGED
    if throw:
        if isinstance(converged, jax.core.Tracer):
            x_free = eqx.error_if(x_free, ~converged, "jaxnet.solve.implicit.equilibrium: the Newton solve did not "
                                  "converge (run with throw=False and read status, residual_N and worst_node)")
        elif not bool(converged):
            raise ImplicitError(
                f"differentiable equilibrium: {REASONS[int(status)]} after {int(iterations)} iterations; "
                f"largest residual {float(residual_N):.4g} N at node {int(worst)} (tolerance {solver.tol:g} N). "
                "Start nearer the answer (x0: e.g. jaxnet.solve.statics.solve's equilibrium) or loosen solver.tol")
    x = assemble.positions(x_free, scene, pattern)
    return Equilibrium(x=x, force=jnp.zeros_like(x), residual_N=residual_N, iterations=iterations, status=status,
                       worst_node=worst, history=jnp.full(solver.max_iter + 1, jnp.nan), energy=jnp.asarray(jnp.nan))


def solve(scene, solver: Newton | None = None, structure: Structure | None = None) -> Equilibrium:
    """The equilibrium of a concrete ``scene`` from its flat start, robustly (the host solver's stiffness
    continuation, :func:`jaxnet.solve.statics.solve`) then polished by :func:`equilibrium` to
    ``solver.tol`` (``solver``: its options, default :data:`jaxnet.solve.options.DIFFERENTIABLE`): the usual
    first solve of a design study. Returns the differentiable path's
    :class:`~jaxnet.solve.results.Equilibrium`."""
    structure = structure or structure_of(scene)
    first = statics.solve(scene)
    return equilibrium(scene, structure, x0=first.x, solver=solver)
