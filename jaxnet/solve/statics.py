"""Static equilibrium by a damped (Levenberg-Marquardt) Newton method with an energy line search, jitted.

Why this globalisation. A net starts flat and stress-free: its tangent K is singular there (a slack membrane
has no out-of-plane stiffness, twines with zero compression stiffness none in compression, and the mesh
opening is a mechanism until the twines are loaded). FEMNET keeps a large added diagonal stiffness for
all iterations and needs thousands of them. Here each iteration solves ``(K + mu S) dx = F`` with S the
scene's *spring network* (every twine and bar a zero-length spring EA/l0; :mod:`jaxnet.solve.spring_network`):
``mu S`` acts as a fictitious prestrain ``mu`` (dimensionless) that gives the slack net the stiffness of a
prestressed one, so a damped step moves the net smoothly instead of node by node. ``mu`` is *adaptive*
(Nielsen's rule): raised when the quadratic model of the energy predicts its decrease badly, lowered
geometrically when it predicts it well, so it vanishes near the solution and the last iterations are pure
Newton steps (quadratic convergence). Every step is checked by a backtracking line search on the total
potential energy, which costs energy evaluations only: each iteration is one assembly and one sparse
factorisation. An optional per-iteration displacement limit (FEMNET's) caps the largest nodal move.

Convergence is judged as in FEMNET on forces: the largest nodal out-of-balance force over the free
coordinates, in newtons (FEMNET's default threshold is 1e-3 N). A solve stops with a named reason;
:func:`solve` raises :class:`SolveError` (reason, iteration, worst node) unless asked not to, and never
returns NaN silently.

Known limit. Nets whose equilibrium holds large *slack* regions (twines with EA_c = 0 and no tension: the
free sides of a curtain hanging from a rope, which gather and close their meshes) have a degenerate
minimum — the energy is flat over every arrangement of the slack netting and the last loads are carried by
twines a few 1e-7 in strain from their slack kink — and converge linearly, in a few hundred iterations
(issue 2's notes). Well-held nets converge in 5-17 iterations (measured up to 10⁵ nodes).
"""

from __future__ import annotations

import dataclasses
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import assemble, linalg, model as model_lib, scene as scene_lib
from jaxnet.solve import spring_network

#: stop reasons (``Equilibrium.status``)
RUNNING, CONVERGED, MAX_ITERATIONS, NON_FINITE, STALLED = 0, 1, 2, 3, 4
REASONS = {
    CONVERGED: "converged",
    MAX_ITERATIONS: "maximum number of iterations reached",
    NON_FINITE: "non-finite force or energy (NaN/inf)",
    STALLED: "no step decreases the energy even with maximal damping (singular or inconsistent problem)",
    RUNNING: "running",
}


class SolveError(RuntimeError):
    """A static solve failed; ``.equilibrium`` holds the last state reached."""

    def __init__(self, message, equilibrium):
        super().__init__(message)
        self.equilibrium = equilibrium


@dataclasses.dataclass(frozen=True)
class Newton:
    """Options of the static Newton solver (hashable: part of the compiled program's identity).

    tol: convergence threshold on the largest nodal out-of-balance force (N).
    max_iter: maximum number of Newton iterations (factorisations).
    max_step: largest displacement of any node in one iteration (m); inf for none.
    damping: initial damping mu, the fictitious prestrain of the spring-network metric (dimensionless).
    min_damping, max_damping: bounds of mu.
    line_search: maximum number of step halvings per iteration.
    verbose: print one line per iteration.
    """

    tol: float = 1e-3
    max_iter: int = 500
    max_step: float = float("inf")
    damping: float = 1e-3
    min_damping: float = 1e-12
    max_damping: float = 1e8
    line_search: int = 30
    verbose: bool = False


class Equilibrium(eqx.Module):
    """Result of a static solve.

    x: (N, 3) node positions (m). force: (N, 3) out-of-balance force (N); at fixed coordinates it is
    minus the reaction. residual_N: largest nodal out-of-balance force on free coordinates (N).
    history: (max_iter + 1,) residual at each iteration (NaN after the last). worst_node: node with the
    largest residual. status: stop reason code (see REASONS).
    """

    x: jax.Array
    force: jax.Array
    residual_N: jax.Array
    iterations: jax.Array
    status: jax.Array
    worst_node: jax.Array
    history: jax.Array
    energy: jax.Array

    @property
    def converged(self):
        return bool(self.status == CONVERGED)

    @property
    def reason(self):
        return REASONS[int(self.status)]

    def reaction(self, scene):
        """(N, 3) reaction forces (N) at the fixed coordinates, zero elsewhere."""
        fixed = np.asarray(scene.nodes.fixed)
        return np.where(fixed, -np.asarray(self.force), 0.0)


def _nodal_norm(f_free, pattern, n_nodes):
    full = jnp.zeros(3 * n_nodes).at[pattern.free].set(f_free).reshape(-1, 3)
    return jnp.sqrt(jnp.sum(full * full, axis=1))


def _progress(it, res, damping, step):
    print(f"  newton {int(it):4d}  residual {float(res):11.4e} N  damping {float(damping):8.1e}  step {float(step):6.3f}")


def newton_loop(x0, scene, pattern, model, opts: Newton):
    """Jittable Newton iteration from free coordinates ``x0``; returns an :class:`Equilibrium`.

    ``model`` (active terms) and ``opts`` are static; ``scene`` and ``pattern`` are array arguments.
    """
    n_nodes = scene.nodes.position.shape[0]
    load = assemble.loads(scene, model)

    def full(x):
        return assemble.positions(x, scene, pattern)

    nonconservative = any(t.term.kind == "force" for t in model)
    energy_and_gradient = jax.value_and_grad(assemble.energy)

    def evaluate(x):
        """At free coordinates x: stored energy (J), out-of-balance force on the free coordinates (N) and
        the non-conservative nodal forces (N, 3). The one place the residual is traced: each copy of it
        in the program costs compile time, so the loop calls this once per line-search trial."""
        X = full(x)
        e, grad = energy_and_gradient(X, scene, model)
        f_nc = assemble.forces(X, scene, model) if nonconservative else jnp.zeros_like(X)
        return e, (load - grad + f_nc).ravel()[pattern.free], f_nc

    def merit(x, e_stored, f_nc):
        # Drag and catch pressure have no potential. Each iteration's line search uses the potential
        # energy of the conservative terms under the loads *plus* these forces frozen at the iterate:
        # its slope along the step is -F.dx as for a conservative net, and at a fixed point F = 0.
        return e_stored - jnp.sum((load + f_nc) * full(x))

    def status_of(it, f, e):
        res = jnp.max(_nodal_norm(f, pattern, n_nodes))
        finite = jnp.isfinite(res) & jnp.isfinite(e)
        return res, jnp.where(
            ~finite, NON_FINITE, jnp.where(res <= opts.tol, CONVERGED, jnp.where(it >= opts.max_iter, MAX_ITERATIONS, RUNNING))
        )

    springs = spring_network.stiffness(scene, model, pattern)
    e0, f0, nc0 = evaluate(x0)
    res0, st0 = status_of(0, f0, e0)
    hist0 = jnp.full(opts.max_iter + 1, jnp.nan).at[0].set(res0)
    state0 = (x0, f0, e0, nc0, jnp.asarray(opts.damping), jnp.asarray(0), st0, hist0)

    def cond(state):
        return state[6] == RUNNING

    def body(state):
        x, f, e_stored, f_nc, mu, it, _, hist = state
        e = merit(x, e_stored, f_nc)
        data = assemble.tangent(full(x), scene, model, pattern)
        damped = data + mu * springs
        dx, ok = linalg.solve(damped, f, pattern.indptr, pattern.indices)
        # FEMNET's displacement limit: scale the step so that no node moves more than max_step.
        biggest = jnp.max(_nodal_norm(dx, pattern, n_nodes))
        dx = dx * jnp.minimum(1.0, opts.max_step / jnp.maximum(biggest, 1e-300))
        slope = jnp.dot(f, dx)  # -d(merit)/d(alpha) at alpha = 0: > 0 for a descent direction
        curvature = jnp.dot(dx, linalg.matvec(data, pattern.rows, pattern.indices, dx))
        predicted = slope - 0.5 * curvature  # decrease predicted by the undamped quadratic model
        usable = ok & (slope > 0)

        # Backtracking (Armijo) line search on the merit. Near the solution the energy decrease falls below
        # the roundoff of the energy itself; there a step is judged by the force.
        roundoff = 1e-12 * (jnp.abs(e) + jnp.abs(jnp.sum((load + f_nc) * full(x))))
        res_now = jnp.linalg.norm(f)

        def ls_cond(s):
            k, done = s[0], s[-1]
            return usable & (k < opts.line_search) & ~done

        def ls_body(s):
            k, alpha, *_ = s
            alpha = jnp.where(k == 0, 1.0, 0.5 * alpha)
            e_try, f_try, nc_try = evaluate(x + alpha * dx)
            m_try = merit(x + alpha * dx, e_try, f_nc)
            armijo = m_try <= e - 1e-4 * alpha * slope
            flat = (alpha * slope <= roundoff) & (jnp.abs(m_try - e) <= roundoff) & (jnp.linalg.norm(f_try) < res_now)
            done = jnp.isfinite(m_try) & jnp.all(jnp.isfinite(f_try)) & (armijo | flat)
            return k + 1, alpha, m_try, e_try, f_try, nc_try, done

        first = (jnp.asarray(0), jnp.asarray(1.0), jnp.asarray(jnp.inf), e_stored, f, f_nc, jnp.asarray(False))
        trials, alpha, m_new, e_try, f_try, nc_try, accepted = jax.lax.while_loop(ls_cond, ls_body, first)
        accepted = usable & accepted
        x_new = jnp.where(accepted, x + alpha * dx, x)
        f_new = jnp.where(accepted, f_try, f)
        e_new = jnp.where(accepted, e_try, e_stored)
        nc_new = jnp.where(accepted, nc_try, f_nc)
        res, st = status_of(it + 1, f_new, jnp.where(accepted, m_new, e))
        # Gain ratio of the full step decides the damping (Levenberg-Marquardt, Nielsen's update) ...
        full_step = accepted & (trials == 1)
        rho = jnp.where(full_step, (e - m_new) / jnp.maximum(predicted, 1e-300), 0.0)
        mu_good = mu * jnp.maximum(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
        # ... and a good step lowers it at least as fast as the residual: mu = O(|F|) near the solution
        # makes the last steps quadratic (Nielsen's rule alone divides mu by 3 at most: linear); a step
        # that raises the residual (possible: the energy decides) raises it.
        ratio = res / jnp.maximum(hist[it], 1e-300)
        mu_good = jnp.where(ratio > 1.0, mu_good * jnp.minimum(ratio, 10.0), jnp.minimum(mu_good, mu * ratio))
        mu_next = jnp.where(full_step & (rho > 0.25), mu_good, mu * jnp.where(accepted, 2.0, 10.0))
        mu_next = jnp.clip(mu_next, opts.min_damping, opts.max_damping)
        st = jnp.where((st == RUNNING) & ~accepted & (mu >= opts.max_damping), STALLED, st)
        hist = hist.at[it + 1].set(res)
        if opts.verbose:
            jax.debug.callback(_progress, it + 1, res, mu, jnp.where(accepted, alpha, 0.0), ordered=True)
        return x_new, f_new, e_new, nc_new, mu_next, it + 1, st, hist

    x, f, e_stored, f_nc, mu, it, st, hist = jax.lax.while_loop(cond, body, state0)
    nodal = _nodal_norm(f, pattern, n_nodes)
    # the force at every node (fixed ones included: minus the reactions), from the final state
    force_full = (load - jax.grad(assemble.energy)(full(x), scene, model) + f_nc)
    return Equilibrium(
        x=full(x),
        force=force_full,
        residual_N=jnp.max(nodal),
        iterations=it,
        status=st,
        worst_node=jnp.argmax(nodal),
        history=hist,
        energy=merit(x, e_stored, f_nc),
    )


_newton_jit = jax.jit(newton_loop, static_argnames=("model", "opts"))

#: compiled Newton programs, keyed by what identifies them: the active terms and their options, the solver
#: options, and the structure, shapes and dtypes of the arguments. A second solve of a scene of the same
#: shape (another load, another panel cut, another start) reuses the program and compiles nothing.
_compiled: dict = {}


def _compiled_newton(start, scene, pattern, model, opts):
    leaves, treedef = jax.tree.flatten((start, scene, pattern))
    key = (model, opts, treedef, tuple((np.shape(a), np.asarray(a).dtype.str if not hasattr(a, "dtype") else a.dtype.str) for a in leaves))
    program = _compiled.get(key)
    if program is None:
        program = _newton_jit.lower(start, scene, pattern, model=model, opts=opts).compile()
        _compiled[key] = program
    return program


@dataclasses.dataclass
class Timing:
    compile_s: float
    wall_s: float


def solve(scene, solver: Newton | None = None, x0=None, raise_on_failure=True, **options):
    """Static equilibrium of ``scene``.

    Args:
      scene: a :class:`jaxnet.scene.Scene` (validated here, before anything is compiled).
      solver: a :class:`Newton` options object; keyword ``options`` override its fields.
      x0: optional (N, 3) start positions (default: the scene's node positions); fixed nodes keep the
        scene's positions.
      raise_on_failure: raise :class:`SolveError` if the solve does not converge.
    Returns:
      (equilibrium, timing): an :class:`Equilibrium` and the compile and run wall times (s); ``compile_s``
      is ~0 when a program compiled for a scene of the same shape and terms is reused.
    """
    solver = dataclasses.replace(solver or Newton(), **options)
    scene_lib.validate(scene)
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    start = np.asarray(scene.nodes.position if x0 is None else x0, dtype=float).ravel()[np.asarray(pattern.free)]
    t0 = time.perf_counter()
    compiled = _compiled_newton(jnp.asarray(start), scene, pattern, model, solver)
    t1 = time.perf_counter()
    eq = compiled(jnp.asarray(start), scene, pattern)
    eq = jax.block_until_ready(eq)
    t2 = time.perf_counter()
    timing = Timing(compile_s=t1 - t0, wall_s=t2 - t0)
    if raise_on_failure and not eq.converged:
        node = int(eq.worst_node)
        raise SolveError(
            f"static solve failed after {int(eq.iterations)} iterations: {eq.reason}; largest residual "
            f"{float(eq.residual_N):.4g} N at node {node} (position {np.asarray(eq.x)[node].round(4).tolist()})",
            eq,
        )
    return eq, timing
