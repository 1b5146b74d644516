"""A reference solution of the net's equations of motion: error-controlled, higher-order (diffrax).

What it integrates. The same equations of motion as the book's implicit scheme
(:mod:`jaxnet.solve.dynamics`, eqs 4.265-4.276), written as a first-order ODE in the free coordinates:

    dx/dt = v,      (M + M_a) dv/dt = F(x, v, t)        (m/s, N),

y = (x_free, v_free) the state, M + M_a the lumped inertia per node and axis
(:func:`jaxnet.solve.masses.lumped_masses`, kg), F = :func:`jaxnet.solve.dynamics.out_of_balance` (N):
the loads, minus the gradient of the stored energy, the drag on the water's velocity relative to v, the
water's inertia (M_a + ρV) γ_h. The fixed coordinates are not states: their positions are the scene's
(moved by the loading's prescribed motions, :func:`jaxnet.solve.dynamics.scene_at`) and their velocities
the motions' derivatives (:func:`jaxnet.solve.dynamics.prescribed_velocity`), both at t.

Why it is the reference for the book scheme's error. The book's scheme is backward differences (implicit
Euler on x and v): first order, its error proportional to Δt, and a numerical damping of every oscillation
(amplitude × (1 + ω²Δt²)^(-1/2) per step). Here an embedded Runge-Kutta pair (by default Kvaerno5, an
A-L-stable ESDIRK of order 5 with an order-4 error estimate) adapts its step so that the estimated local
error stays within ``atol + rtol |y|`` in every component: tighten rtol and atol and the solution converges
at high order, so a tight-tolerance run is "the exact solution" against which the scheme's error at a given
Δt is measured (``tests/solve/test_reference.py`` does this and finds the scheme's first order). Both integrate
the same F, so the difference is the time discretisation alone, not the model.

Save times. The solution is saved at ``saveat`` and the steps are made to land on those times
(``diffrax.ClipStepSizeController(step_ts=...)``): diffrax's dense output for the Kvaerno methods is a
third-order Hermite interpolant, whose error is *not* controlled and would spoil a fifth-order
reference between steps. Many close save times therefore cap the step.

Newton inside each step: sparse, dense or GMRES. Each implicit stage solves f_i = F(y + γ h f_i) by Newton.
diffrax's default (a chord iteration on a *dense* Jacobian, LU-factorised) costs n Jacobian-vector products
and an n³ factorisation per step (n = 2 × free coordinates): fine for a few hundred states, hopeless beyond
(``docs/solvers.md``, "The diffrax reference"). The default here ("sparse", :class:`SparseLU`) uses the element
graph instead: the stage Jacobian couples only the coordinates of nodes sharing an element, so a greedy
distance-2 colouring of its columns recovers every entry from one JVP per colour (a few dozen, whatever n),
and the matrix is factorised densely in JAX for small systems or by SuperLU on the host above
``dense_limit`` states. ``optx.Newton`` with matrix-free ``lineax.GMRES`` (a JVP per Krylov iteration,
nothing n × n) is the alternative where the pattern does not hold (a catch). Chord or VeryChord with GMRES crash in this diffrax / optimistix / lineax
version set, hence Newton (a fresh linearisation every iteration). GMRES is unpreconditioned: its iteration
count grows with ω_max h, the stiffest twine's frequency times the step, and a stage whose Krylov solve
does not converge is a failed Newton, so diffrax rejects the step and halves it. Stiff twines therefore
cost small steps either way: with an L-stable method the stiff modes do not limit stability, but the error
control resolves every vibration whose amplitude exceeds ``atol`` (a twine of EA 1e5-1e9 N on grams of
netting rings at 1e3-1e5 rad/s after any sudden load). Keep a reference to small nets and short runs, and
start it from a state close to equilibrium where possible.

The sparse solvers are the fastest of these on the hanging panel of ``tests/solve/test_reference.py`` (with
and without the host's SuperLU alike), GMRES several times slower, and diffrax's chord iteration the
slowest: it keeps its Jacobian across steps, the stiff twines make it fail to converge, and diffrax answers
by cutting the step, an order of magnitude more steps than with a fresh Newton linearisation
(``docs/solvers.md``).

Reverse-mode gradients through diffrax's implicit solvers form and factorise a dense Jacobian whatever
the root finder (diffrax calls optx.root_find without an adjoint): differentiate the reference only on
small problems.

A failed solve (``max_steps`` reached, a step size driven to nothing, a non-finite state) raises
:class:`ReferenceError` with diffrax's message and the time reached; nothing non-finite is returned.

Units: m, s, kg, N.
"""

from __future__ import annotations

import dataclasses
import time as _time

import diffrax
import equinox as eqx
import equinox.internal as eqxi
import jax
import jax.flatten_util
import jax.numpy as jnp
import lineax as lx
import numpy as np
import optimistix as optx
import scipy.sparse as sp

from jaxnet import linalg, model as model_lib
from jaxnet.model import assemble
from jaxnet.scene import checks
from jaxnet.solve import dynamics, programs
from jaxnet.solve.masses import lumped_masses
from jaxnet.solve.results import Timing

#: the solvers by name: implicit (stiff, error-controlled) and explicit (non-stiff checks only)
IMPLICIT = {"Kvaerno3": diffrax.Kvaerno3, "Kvaerno4": diffrax.Kvaerno4, "Kvaerno5": diffrax.Kvaerno5}
EXPLICIT = {"Tsit5": diffrax.Tsit5, "Dopri5": diffrax.Dopri5, "Dopri8": diffrax.Dopri8}
AXES = "xyz"
#: how each implicit stage's Newton iteration solves its linear systems (see the module docstring)
LINEAR_SOLVERS = ("sparse", "sparse-host", "dense", "gmres", "chord")


class ReferenceError(RuntimeError):
    """The reference integration failed (diffrax's reason and the time reached are in the message)."""


@dataclasses.dataclass
class ReferenceTrajectory:
    """A reference run.

    times: (R,) the save times (s). positions, velocities: (R, N, 3) every node's position (m) and velocity
    (m/s), the fixed coordinates filled in (prescribed motions included). steps_accepted, steps_rejected:
    diffrax's step counts. timing: the :class:`~jaxnet.solve.results.Timing` of the call (s: ``wall_s`` the
    whole call, ``compile_s`` the part spent compiling). solver, rtol, atol: what was asked for; linear_solver: "dense" (diffrax's chord iteration on a
    dense LU) or "gmres" (Newton with matrix-free GMRES), "none" for an explicit solver.
    """

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    steps_accepted: int
    steps_rejected: int
    timing: Timing
    solver: str
    rtol: float
    atol: float
    linear_solver: str


# -- the sparse stage Jacobian ------------------------------------------------------------------------


class StagePattern(eqx.Module):
    """The sparsity of the stage equations' Jacobian I - c ∂f/∂y over y = (x_free, v_free), and a colouring
    of its columns (arrays: jit arguments, so one compiled program serves every scene of the same shape).

    indptr, indices, rows: CSR structure (2n unknowns); colour: (2n,) the colour of each column, no two
    columns of one colour having a nonzero in the same row; entry_colour: (nnz,) the colour of each entry's
    column. One Jacobian-vector product per colour (seeded with the sum of that colour's unit vectors)
    gives every entry: entry (i, j) is row i of the product of colour(j).
    """

    indptr: jax.Array
    indices: jax.Array
    rows: jax.Array
    colour: jax.Array
    entry_colour: jax.Array
    transpose_order: jax.Array
    transpose_indptr: jax.Array
    transpose_indices: jax.Array

    @property
    def n_colours(self):
        return int(np.max(np.asarray(self.colour))) + 1


def greedy_colouring(indptr, indices):
    """(n,) colours of the columns of the n × n CSR pattern (indptr, indices): columns sharing a row get
    different colours (a distance-2 colouring of the element graph), greedily in column order."""
    n = len(indptr) - 1
    a = sp.csr_matrix((np.ones(len(indices)), indices, indptr), shape=(n, n))
    conflicts = (a.T @ a).tocsr()  # columns j, k conflict when some row has both
    colour = np.full(n, -1, dtype=np.int64)
    for j in range(n):
        taken = colour[conflicts.indices[conflicts.indptr[j]:conflicts.indptr[j + 1]]]
        used = np.zeros(taken.size + 1, dtype=bool)
        used[taken[(taken >= 0) & (taken <= taken.size)]] = True
        colour[j] = int(np.argmin(used))
    return colour


def stage_pattern(scene, model) -> StagePattern:
    """The :class:`StagePattern` of ``scene``: ∂F/∂x and ∂F/∂v couple the coordinates of the nodes of one
    element (:func:`jaxnet.model.assemble.build_pattern`'s tangent pattern P, n free coordinates), so with
    y = (x, v) the stage Jacobian I - c [[0, I], [M⁻¹ ∂F/∂x, M⁻¹ ∂F/∂v]] has the blocks [[I, I], [P, P]].
    Columns x_j and v_j have the same rows, and x_j, x_k share a row exactly when v_j, v_k do: the colours
    are P's distance-2 colouring for the x columns and the same shifted by its count for the v columns."""
    p = assemble.build_pattern(scene, model)
    n = p.n
    p_indptr, p_indices = np.asarray(p.indptr), np.asarray(p.indices)
    p_rows = np.repeat(np.arange(n), np.diff(p_indptr))
    eye = np.arange(n)
    # (row, column) of the four blocks
    rows = np.concatenate([eye, eye, n + p_rows, n + p_rows])
    cols = np.concatenate([eye, n + eye, p_indices, n + p_indices])
    order = np.lexsort((cols, rows))
    rows, cols = rows[order], cols[order]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=2 * n))])
    c = greedy_colouring(p_indptr, p_indices)
    colour = np.concatenate([c, c + c.max() + 1])
    # the transpose: its CSR entries are ours ordered by (column, row)
    t_order = np.lexsort((rows, cols))
    t_indptr = np.concatenate([[0], np.cumsum(np.bincount(cols, minlength=2 * n))])
    return StagePattern(indptr=jnp.asarray(indptr), indices=jnp.asarray(cols.astype(np.int32)),
                        rows=jnp.asarray(rows), colour=jnp.asarray(colour), entry_colour=jnp.asarray(colour[cols]),
                        transpose_order=jnp.asarray(t_order), transpose_indptr=jnp.asarray(t_indptr),
                        transpose_indices=jnp.asarray(rows[t_order].astype(np.int32)))


def coloured_entries(mv, pattern: StagePattern, n_colours: int):
    """(nnz,) the CSR entries of the linear map ``mv`` (flat vector -> flat vector) on ``pattern``'s
    structure, from ``n_colours`` Jacobian-vector products."""
    seeds = (pattern.colour[None, :] == jnp.arange(n_colours)[:, None]).astype(float)
    products = jax.vmap(mv)(seeds)  # (n_colours, 2n)
    return products[pattern.entry_colour, pattern.rows]


class SparseLU(lx.AbstractLinearSolver):
    """lineax solver for the stage equations: the Jacobian's entries from one JVP per colour
    (:func:`coloured_entries`), then factorised either densely in JAX (``host=False``: for small systems,
    where a host call would cost more than the factorisation) or by SuperLU on the host
    (``host=True``: :func:`jaxnet.linalg.solve`, with its checks of the backward error). The operator must
    act on (x_free, v_free) as ``pattern`` says."""

    pattern: StagePattern
    n_colours: int = eqx.field(static=True)
    host: bool = eqx.field(static=True)

    def init(self, operator, options):
        del options
        structure = jax.tree_util.tree_map(lambda s: jnp.zeros(s.shape, s.dtype), operator.in_structure())
        _, unflatten = jax.flatten_util.ravel_pytree(structure)

        def mv(v):
            return jax.flatten_util.ravel_pytree(operator.mv(unflatten(v)))[0]

        data = coloured_entries(mv, self.pattern, self.n_colours)
        if self.host:
            return data, eqxi.Static(False), structure
        n = self.pattern.colour.shape[0]
        matrix = jnp.zeros((n, n)).at[self.pattern.rows, self.pattern.indices].set(data)
        return jax.scipy.linalg.lu_factor(matrix), eqxi.Static(False), structure

    def compute(self, state, vector, options):
        del options
        factor, transposed, structure = state
        p = self.pattern
        rhs, unflatten = jax.flatten_util.ravel_pytree(vector)
        if not self.host:
            x = jax.scipy.linalg.lu_solve(factor, rhs, trans=1 if transposed.value else 0)
            ok = jnp.asarray(True)
        elif transposed.value:
            x, ok = linalg.solve(factor[p.transpose_order], rhs, p.transpose_indptr, p.transpose_indices)
        else:
            x, ok = linalg.solve(factor, rhs, p.indptr, p.indices)
        ok = ok & jnp.all(jnp.isfinite(x))
        return unflatten(x), lx.RESULTS.where(ok, lx.RESULTS.successful, lx.RESULTS.singular), {}

    def transpose(self, state, options):
        factor, transposed, structure = state
        return (factor, eqxi.Static(not transposed.value), structure), {}

    def conj(self, state, options):
        return state, {}  # real matrices

    def assume_full_rank(self):
        return True


def _make_solver(solver: str, rtol, atol, linear_solver: str, gmres_rtol: float, pattern, n_colours):
    if solver in EXPLICIT:
        return EXPLICIT[solver]()
    if linear_solver == "chord":
        return IMPLICIT[solver]()  # diffrax's default: VeryChord on a dense LU, tolerances from the controller
    if linear_solver in ("sparse", "sparse-host"):
        linear = SparseLU(pattern, n_colours, host=linear_solver == "sparse-host")
    elif linear_solver == "dense":
        linear = lx.LU()
    else:
        # inexact Newton: GMRES's residual relative to the Newton residual it solves for (a forcing term)
        linear = lx.GMRES(rtol=gmres_rtol, atol=gmres_rtol * atol, restart=50, stagnation_iters=50, max_steps=2000)
    return IMPLICIT[solver](root_finder=optx.Newton(rtol=rtol, atol=atol, linear_solver=linear))


def _full(free_values, fixed_values, free_index):
    """(N, 3) array: ``fixed_values`` with the free coordinates (flat indices ``free_index``) replaced."""
    return fixed_values.ravel().at[free_index].set(free_values).reshape(fixed_values.shape)


def _solve(y0, ts, t_end, dt0, rtol, atol, scene, masses, free_index, loading, pattern, model, solver,
           linear_solver, gmres_rtol, n_colours, max_steps, progress):
    """The jitted integration: returns (ys at ts, the time reached, diffrax's result, accepted, rejected)."""
    inverse_mass = 1.0 / jnp.asarray(masses[0]).ravel()[free_index]

    def field(t, y, args):
        scene, masses, free_index, loading = args
        x_free, v_free = y
        x = _full(x_free, dynamics.scene_at(scene, loading, t).nodes.position, free_index)
        v = _full(v_free, dynamics.prescribed_velocity(scene, loading, t), free_index)
        force = dynamics.out_of_balance(x, v, t, scene, masses, loading, model)
        return v_free, force.ravel()[free_index] * inverse_mass

    controller = diffrax.ClipStepSizeController(diffrax.PIDController(rtol=rtol, atol=atol), step_ts=ts)
    saveat = diffrax.SaveAt(subs=[diffrax.SubSaveAt(ts=ts), diffrax.SubSaveAt(t1=True, fn=lambda t, y, a: t)])
    sol = diffrax.diffeqsolve(
        diffrax.ODETerm(field), _make_solver(solver, rtol, atol, linear_solver, gmres_rtol, pattern, n_colours), t0=0.0, t1=t_end, dt0=dt0,
        y0=y0, args=(scene, masses, free_index, loading), saveat=saveat, stepsize_controller=controller,
        max_steps=max_steps, throw=False,
        progress_meter=diffrax.TqdmProgressMeter() if progress else diffrax.NoProgressMeter())
    ys, reached = sol.ys
    return (ys, reached[0], sol.result, sol.stats["num_accepted_steps"], sol.stats["num_rejected_steps"])


_solve_jit = programs.jit(_solve, static_argnames=("model", "solver", "linear_solver", "gmres_rtol", "n_colours", "max_steps",
                                              "progress"))


def _fill(ts, ys, scene, loading, free_index):
    """Full (R, N, 3) positions and velocities from the saved free coordinates."""

    def one(t, x_free, v_free):
        x = _full(x_free, dynamics.scene_at(scene, loading, t).nodes.position, free_index)
        v = _full(v_free, dynamics.prescribed_velocity(scene, loading, t), free_index)
        return x, v

    return jax.vmap(one)(ts, *ys)


_fill_jit = programs.jit(_fill)


def free_masses(scene):
    """The free coordinates' flat indices (into (N, 3).ravel()) and their inertia M + M_a (kg); raises
    ValueError naming the node and axis of a free coordinate without inertia (the ODE would be a DAE)."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool)
    mass, water = lumped_masses(scene)
    free_index = np.flatnonzero(~fixed.ravel())
    m = mass.ravel()[free_index]
    bad = np.flatnonzero(~(m > 0))
    if bad.size:
        node, axis = divmod(int(free_index[bad[0]]), 3)
        raise ValueError(f"reference: node {node} is free along {AXES[axis]} but has no inertia (M + M_a = "
                         f"{m[bad[0]]:g} kg); the equations of motion would be differential-algebraic. Give it a "
                         "mass or an added mass, or fix that coordinate")
    return free_index, (mass, water)


def reference(scene, end_time, loading=None, saveat=None, rtol=1e-6, atol=1e-9, solver="Kvaerno5", x0=None,
              v0=None, dt0=None, max_steps=100000, progress=False, linear_solver="auto",
              dense_limit=600, gmres_rtol=1e-3) -> ReferenceTrajectory:
    """Integrates the equations of motion of ``scene`` from time 0 to ``end_time`` (s) with error control.

    Args:
      scene: a :class:`jaxnet.scene.Scene` (validated here).
      end_time: the final time (s).
      loading: :class:`jaxnet.solve.dynamics.Loading` (current history, prescribed motions, the start ramp of
        the waves and motions, applied as :func:`jaxnet.solve.dynamics.simulate` does); None for none.
      saveat: the save times (s), increasing, within [0, end_time]; default 101 times evenly from 0 to
        end_time. The steps land on them (see the module docstring).
      rtol, atol: the step-size controller's relative and absolute tolerances (absolute in m for positions
        and m/s for velocities: one atol for both).
      solver: "Kvaerno3", "Kvaerno4", "Kvaerno5" (implicit, for stiff nets) or "Tsit5", "Dopri5", "Dopri8"
        (explicit: for non-stiff checks only; a stiff twine makes them take steps of 1/ω_max).
      x0, v0: (N, 3) start positions (m) and velocities (m/s); default: the scene's positions (moved by the
        prescribed motions at t = 0), at rest. Their fixed coordinates are ignored (the scene's are used).
      dt0: the first step (s); None lets diffrax choose it.
      max_steps: the most steps the run may take before it fails.
      progress: show diffrax's tqdm progress meter.
      linear_solver: how each implicit stage's Newton iteration solves its linear systems:
        "sparse" (the stage Jacobian's entries from one JVP per colour of the element graph,
        :class:`SparseLU`; factorised densely in JAX up to ``dense_limit`` states, by SuperLU on the host
        above), "sparse-host" (always SuperLU), "dense" (optx.Newton on lineax's dense LU), "chord"
        (diffrax's default: VeryChord on a dense LU), "gmres" (Newton + matrix-free GMRES with relative
        tolerance ``gmres_rtol``), or "auto": "sparse", except with a catch (or panel catches), whose pressure couples every
        node of the cod-end through the volume (the element pattern does not hold): "dense" up to
        ``dense_limit`` states (twice the free coordinates), "gmres" above.
      dense_limit: see ``linear_solver``.
      gmres_rtol: GMRES's tolerance relative to the Newton residual (an inexact Newton forcing term).
    Returns:
      a :class:`ReferenceTrajectory`. Raises ValueError for a free coordinate without inertia or bad
      arguments, :class:`ReferenceError` when the integration fails.
    """
    loading = loading or dynamics.Loading()
    checks.validate(scene)
    scene, loading, _ = dynamics.with_start_ramp(scene, loading)  # the run's start, as simulate's
    dynamics.check_loading(scene, loading)
    if loading.winches:
        raise ValueError("reference: winches (Loading.winches) are not integrated here: its masses are the start's, "
                         "where a winch's cable changes length; run them with dynamics.simulate")
    if not (np.isfinite(end_time) and end_time > 0):
        raise ValueError(f"reference: end_time must be finite and > 0, got {end_time!r}")
    if solver not in IMPLICIT and solver not in EXPLICIT:
        raise ValueError(f"reference: unknown solver {solver!r}; choose one of {sorted(IMPLICIT) + sorted(EXPLICIT)}")
    if not (rtol > 0 and atol > 0):
        raise ValueError(f"reference: rtol and atol must be > 0, got {rtol!r}, {atol!r}")
    ts = np.linspace(0.0, end_time, 101) if saveat is None else np.asarray(saveat, dtype=float).ravel()
    if ts.size == 0 or not np.all(np.isfinite(ts)) or np.any(np.diff(ts) <= 0) or ts[0] < 0 or ts[-1] > end_time:
        raise ValueError("reference: saveat must be finite, strictly increasing and within [0, end_time]")
    free_index, masses = free_masses(scene)
    model = model_lib.active_terms(scene, dynamic=True)
    if linear_solver == "auto":
        fronts = scene.catch is not None or scene.panel_catches is not None
        linear_solver = "sparse" if not fronts else "dense" if 2 * free_index.size <= dense_limit else "gmres"
    n_states = 2 * free_index.size
    if linear_solver not in LINEAR_SOLVERS:
        raise ValueError(f"reference: linear_solver must be 'auto' or one of {LINEAR_SOLVERS}, got {linear_solver!r}")
    if solver in EXPLICIT:
        linear_solver = "none"
    start = np.asarray(dynamics.scene_at(scene, loading, 0.0).nodes.position)
    x_start = start if x0 is None else np.asarray(x0, dtype=float)
    v_start = np.zeros_like(start) if v0 is None else np.asarray(v0, dtype=float)
    if x_start.shape != start.shape or v_start.shape != start.shape:
        raise ValueError(f"reference: x0 and v0 must have the shape {start.shape}")
    for name, value in (("x0", x_start), ("v0", v_start)):
        bad = np.argwhere(~np.isfinite(value.ravel()[free_index]))
        if bad.size:
            node, axis = divmod(int(free_index[bad[0, 0]]), 3)
            raise ValueError(f"reference: {name} is not finite at node {node}, {AXES[axis]}")
    y0 = (jnp.asarray(x_start.ravel()[free_index]), jnp.asarray(v_start.ravel()[free_index]))
    pattern, n_colours = None, 0
    if linear_solver == "sparse" and n_states > dense_limit:
        linear_solver = "sparse-host"
    if linear_solver.startswith("sparse"):
        pattern = stage_pattern(scene, model)
        n_colours = pattern.n_colours
    # the tolerances and times are traced: a study over rtol or over end times compiles once
    args = (y0, jnp.asarray(ts), jnp.asarray(end_time, dtype=float), None if dt0 is None else jnp.asarray(dt0, dtype=float),
            jnp.asarray(rtol, dtype=float), jnp.asarray(atol, dtype=float), scene,
            tuple(jnp.asarray(m) for m in masses), jnp.asarray(free_index), loading, pattern)
    static = dict(model=model, solver=solver, linear_solver=linear_solver, gmres_rtol=float(gmres_rtol),
                  n_colours=n_colours, max_steps=int(max_steps), progress=bool(progress))
    t0 = _time.perf_counter()
    compiled = _solve_jit.lower(*args, **static).compile()
    compile_s = _time.perf_counter() - t0
    ys, reached, result, accepted, rejected = jax.block_until_ready(compiled(*args))
    if result != diffrax.RESULTS.successful:
        raise ReferenceError(f"reference ({solver}, rtol {rtol:g}, atol {atol:g}) failed at t = {float(reached):.6g} s "
                             f"of {end_time:g} s after {int(accepted)} accepted and {int(rejected)} rejected steps: "
                             f"{diffrax.RESULTS[result]}")
    if not all(bool(jnp.all(jnp.isfinite(y))) for y in ys):
        raise ReferenceError(f"reference ({solver}): the solution is not finite although diffrax reports success")
    positions, velocities = _fill_jit(jnp.asarray(ts), ys, scene, loading, jnp.asarray(free_index))
    return ReferenceTrajectory(times=ts, positions=np.asarray(positions), velocities=np.asarray(velocities),
                               steps_accepted=int(accepted), steps_rejected=int(rejected),
                               timing=Timing(compile_s=compile_s, wall_s=_time.perf_counter() - t0), solver=solver,
                               rtol=float(rtol), atol=float(atol), linear_solver=linear_solver)
