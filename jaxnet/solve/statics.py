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

Two drivers run the same iteration (the functions below are shared). :func:`solve` drives it from the
host: the evaluation of the residual and the tangent are compiled once each (in parallel), and each
iteration calls the tangent once, factorises on the host (SuperLU, the ordering computed once per sparsity
pattern and kept: :class:`jaxnet.linalg.HostSolver`) and calls the evaluation once per line-search trial,
from the last accepted iterate's catch front (:func:`_evaluate`'s ``previous``). Its compiled pieces
are half the size of the whole loop's program and hold no host callback, so they are kept whole between
processes (:mod:`jaxnet.solve.programs`, when a compilation cache directory is set: the command line sets
one): a second process loads them without tracing or compiling. :func:`newton_loop` is the whole
iteration as one jittable program (the factorisation a host callback), for use inside traced code.

Stiffness continuation. A net that starts far from its equilibrium shape (FEMNET's cases start flat: a
panel drawn horizontal that must swing down to hang; a cod-end drawn as a cone that must bulge around its
catch) needs large rotations, and its twines are stiff: a Newton step, linear in the positions, stretches
the twines it rotates by O(step²), the energy line search cuts it back, and the iteration crawls (267
iterations on ``nr_netting``, the residual bouncing at 10²-10³ N for 250 of them). The symptom is seen on
the iterates: the twines pull far harder than anything applied to them (:func:`_balancing_scale`: the
factor on the elastic forces that would best balance the loads there is 1e-5-1e-3). When plain Newton
stalls on such iterates (:func:`_overstretched`), the solver continues from where it is with the *elastic
energies scaled by s* (twines, bars, mesh opening, knots, bending; not the potentials of weight and
buoyancy at the surface, nor the sea bed's): s = ``soft_start`` (1e-2), then s × ``stiffening`` (√10) each
time a stage is converged to ``stage_rtol`` of its starting residual, up to s = 1, the net as it is,
converged to ``tol``. A softer net (equivalently: the same net under loads 1/s times larger) finds its
shape in a few steps, because stretching is cheap, and each stiffening is a small correction from the
last shape. Only the path changes, not the answer: the last stage is the unscaled problem. The
continuation gets half the iterations left when it starts; if it does not finish in them, or a softened
net stalls, plain Newton goes on from the better of where the continuation began and where it got to (by
the largest residual of the net as it is): a misjudged start costs iterations, not the solve, and a
continuation that ran out of iterations a stage or two short of the end is not thrown away (measured on
the stability suite's small curtains in a 1 m/s current from a crumpled start, ``validation/stability.py``:
not converged in 500 iterations when plain Newton went back to the crumpled start, 293 and 317 iterations
going on from where the continuation got to).
Measured: ``nr_netting`` 267 -> 83 iterations, ``c2`` 64 -> 42, the default cage 157 -> 91; nets that
converge steadily never soften (the default 2000-node scene: 11 iterations), nor do slack curtains that
stall while carrying their loads (balancing scale 0.005-0.1; softened, one took 377 iterations instead of
125). The jitted :func:`newton_loop` has no continuation.

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

import concurrent.futures
import dataclasses
import threading
import time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import assemble, linalg, model as model_lib, scene as scene_lib
from jaxnet.solve import programs, spring_network

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
    stall_window: the stiffness continuation starts when the best residual of the last ``stall_window``
      iterations is not half the best before them (0: from the first iteration; None: never).
    soften_below: ... and the iterates' twines pull far harder than the loads: the elastic scale that best
      balances the loads there (:func:`_balancing_scale`, median over the window) is below this.
    soft_start: the first stage's factor on the elastic energies (dimensionless, in (0, 1)).
    stiffening: the factor between consecutive stages (> 1).
    stage_rtol: a stage ends when the residual is this fraction of the residual it started with (or the
      tolerance ``tol``); the last stage (the net as it is) ends at ``tol``.
    stiffness: the tangent's path, ``"closed_form"`` (the default: the hand-derived stiffness of
      :mod:`jaxnet.closed_form` where a term has one, autodiff for the others) or ``"autodiff"``
      (``jax.jacfwd`` of every term). Both are the same matrix to rounding (tested per element and on whole
      solves), and the answer does not depend on it: the residual is always the energies' gradient and the
      forces themselves, only the steps towards it are the tangent's. The closed forms are the default
      because they are cheaper: FEMNET's c2 on jaxnet's mesh, warm 0.30 s against 0.42 s, cold 2.8 s against
      3.7 s (``validation/femnet_cases.py``, medians of 3).
    verbose: print one line per iteration.
    """

    tol: float = 1e-3
    max_iter: int = 500
    max_step: float = float("inf")
    damping: float = 1e-3
    min_damping: float = 1e-12
    max_damping: float = 1e8
    line_search: int = 30
    stall_window: int | None = 5
    soften_below: float = 1e-3
    soft_start: float = 1e-2
    stiffening: float = 10**0.5
    stage_rtol: float = 1e-2
    stiffness: str = "closed_form"
    verbose: bool = False

    def __post_init__(self):
        if self.stiffness not in assemble.STIFFNESS_PATHS:
            raise ValueError(f"Newton: stiffness must be one of {assemble.STIFFNESS_PATHS}, not {self.stiffness!r}")
        # refused here, before anything compiles: tol <= 0 would run to max_iter and report a failure that is
        # the caller's, max_iter 0 would compile a solve that cannot take a step
        if not (np.isfinite(self.tol) and self.tol > 0):
            raise ValueError(f"Newton: tol (N) must be finite and > 0, got {self.tol!r}")
        if isinstance(self.max_iter, bool) or int(self.max_iter) != self.max_iter or self.max_iter < 1:
            raise ValueError(f"Newton: max_iter must be an integer >= 1, got {self.max_iter!r}")
        if not self.max_step > 0:
            raise ValueError(f"Newton: max_step (m) must be > 0 (inf for no limit), got {self.max_step!r}")
        if self.line_search < 0:
            raise ValueError(f"Newton: line_search (halvings) must be >= 0, got {self.line_search!r}")
        if not (0 < self.min_damping <= self.damping <= self.max_damping):
            raise ValueError(f"Newton: damping must lie in [min_damping, max_damping] with min_damping > 0, got "
                             f"{self.min_damping!r} <= {self.damping!r} <= {self.max_damping!r}")


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
        return int(self.status) == CONVERGED  # on the host: no JAX comparison (a program compiled)

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


# -- the pieces of one iteration, shared by the two drivers (jitted loop and host loop) ----------------


def _placeholders(shapes):
    """States standing for "none yet" (:func:`_evaluate`'s ``previous`` before a first evaluation): NaN where
    the leaf is real (a NaN start is ignored: the catch front then starts from the middle of the net),
    zeros otherwise, with the shapes and dtypes of ``shapes``, strongly typed as :func:`_evaluate` returns
    its states (a weakly typed leaf would compile the evaluation a second time)."""
    return jax.tree.map(
        lambda a: np.full(a.shape, np.nan if jnp.issubdtype(a.dtype, jnp.inexact) else 0, a.dtype), shapes)


#: the force terms' state shapes per scene signature (:func:`jaxnet.solve.programs.identity` of the states'
#: arguments and terms): found by tracing the states alone (c2: 20-50 ms), once per process for a scene
#: shape, not at every warm solve
_STATE_SHAPES: dict = {}
_STATE_SHAPES_LOCK = threading.Lock()
_MAX_STATE_SHAPES = 64


def _unknown_states(scene, pattern, model):
    """:func:`_placeholders` of the force terms' states of ``scene`` (the first evaluation's ``previous``)."""
    key = programs.identity("states", (scene, pattern), {"model": model})
    with _STATE_SHAPES_LOCK:
        shapes = _STATE_SHAPES.get(key)
    if shapes is None:
        x = jax.ShapeDtypeStruct(pattern.free.shape, jnp.float64)
        shapes = jax.eval_shape(lambda x: assemble.states(assemble.positions(x, scene, pattern), scene, model), x)
        with _STATE_SHAPES_LOCK:  # solves may run in several threads
            if len(_STATE_SHAPES) >= _MAX_STATE_SHAPES:
                _STATE_SHAPES.pop(next(iter(_STATE_SHAPES)))
            _STATE_SHAPES[key] = shapes
    return _placeholders(shapes)


def _evaluate(x, f_frozen, load, scale, scene, pattern, model, step=None, previous=None):
    """At free coordinates x: the residual and what the line search needs, in one traced evaluation.
    ``load``: the (N, 3) constant nodal loads (N), computed once per solve; ``scale``: the factor on the
    elastic energies (1, or less during the stiffness continuation); ``step``: None in statics, in a time
    step its past and masses (:class:`jaxnet.solve.dynamics.TimeStep`: the inertia energy joins the stored
    energy, the drag takes the vertices' velocities); ``previous``: the force terms' states at the last
    accepted iterate (what this returns as ``state``), which start their solutions here
    (:func:`jaxnet.assemble.states`), or None.

    Returns (energy, force, f_nc, merit, state): the stored energy (J); the out-of-balance force (N, 3)
    at every node (at fixed coordinates minus the reactions); the non-conservative nodal forces (N, 3);
    the merit (J) with the non-conservative forces frozen at ``f_frozen`` (see :func:`_merit`); the force
    terms' global states (the catch front), reused by the tangent at the same point.
    """
    X = assemble.positions(x, scene, pattern)
    e, grad = jax.value_and_grad(_stored_energy)(X, scene, model, scale, step)
    if any(t.term.kind == "force" for t in model):
        state = assemble.states(X, scene, model, previous)
        f_nc = assemble.forces(X, scene, model, state, None if step is None else step.motion)
        # strongly typed, as the placeholders the tangent is compiled with (a weakly typed leaf, from a
        # Python scalar, would make a second compilation of the tangent at the first iteration)
        state = jax.tree.map(lambda a: jax.lax.convert_element_type(a, jnp.result_type(a)), state)
    else:
        state, f_nc = {}, jnp.zeros_like(X)
    return e, load - grad + f_nc, f_nc, _merit(e, X, load + f_frozen), state


def _stored_energy(X, scene, model, scale, step):
    """The energy (J) the Newton iteration minimises, loads apart: the terms' (elastic ones scaled), plus in a
    time step the inertia's ½ (M + M_a)/Δt² |x - x_predicted|², whose gradient is the force of inertia."""
    e = assemble.energy(X, scene, model, scale)
    return e if step is None else e + step.inertia_energy(X)


def _merit(e_stored, X, frozen_load):
    # Drag and catch pressure have no potential. Each iteration's line search uses the potential energy of
    # the conservative terms under the loads *plus* these forces frozen at the iterate: its slope along
    # the step is -F.dx as for a conservative net, and at a fixed point F = 0.
    return e_stored - jnp.sum(frozen_load * X)


def _tangent(x, state, scale, scene, pattern, model, stiffness="autodiff", step=None):
    """CSR entries of the tangent K = -dF/dx at free coordinates x (force terms' states given, the elastic
    energies scaled by ``scale``; ``stiffness``: its path, see :class:`Newton`; ``step``: in a time step, its
    inertia (M + M_a)/Δt² on the diagonal (4.271) and the drag's dependence on the velocities)."""
    X = assemble.positions(x, scene, pattern)
    if step is None:
        return assemble.tangent(X, scene, model, pattern, state, scale, stiffness)
    data = assemble.tangent(X, scene, model, pattern, state, scale, stiffness, step.motion)
    return data.at[pattern.diagonal].add(step.inertia_stiffness().ravel()[pattern.free])


def _accepts(m_try, f_try, e, alpha, slope, roundoff, res_now, xp):
    """Backtracking (Armijo) test of a trial step on the merit. Near the solution the energy decrease falls
    below the roundoff of the energy itself; there a step is judged by the force."""
    armijo = m_try <= e - 1e-4 * alpha * slope
    flat = (alpha * slope <= roundoff) & (xp.abs(m_try - e) <= roundoff) & (xp.linalg.norm(f_try) < res_now)
    return xp.isfinite(m_try) & xp.all(xp.isfinite(f_try)) & (armijo | flat)


def _next_damping(mu, accepted, trials, e, m_new, predicted, ratio, opts, xp):
    """Levenberg-Marquardt damping after a step. ``ratio``: new over old largest residual.

    The gain ratio of the full step decides (Nielsen's update); a good step also lowers mu at least as
    fast as the residual: mu = O(|F|) near the solution makes the last steps quadratic (Nielsen's rule
    alone divides mu by 3 at most: linear); a step that raises the residual (possible: the energy decides)
    raises it.
    """
    full_step = accepted & (trials == 1)
    rho = xp.where(full_step, (e - m_new) / xp.maximum(predicted, 1e-300), 0.0)
    mu_good = mu * xp.maximum(1.0 / 3.0, 1.0 - (2.0 * rho - 1.0) ** 3)
    mu_good = xp.where(ratio > 1.0, mu_good * xp.minimum(ratio, 10.0), xp.minimum(mu_good, mu * ratio))
    mu_next = xp.where(full_step & (rho > 0.25), mu_good, mu * xp.where(accepted, 2.0, 10.0))
    return xp.clip(mu_next, opts.min_damping, opts.max_damping)


def _status(it, res, e, opts, xp):
    finite = xp.isfinite(res) & xp.isfinite(e)
    return xp.where(~finite, NON_FINITE, xp.where(res <= opts.tol, CONVERGED, xp.where(it >= opts.max_iter, MAX_ITERATIONS, RUNNING)))


def newton_loop(x0, scene, pattern, model, opts: Newton, step=None):
    """The whole Newton iteration as one jittable program (``jax.lax.while_loop``), from free coordinates
    ``x0``; returns an :class:`Equilibrium`. ``model`` (active terms) and ``opts`` are static. ``step``: None
    for a static equilibrium; for an implicit time step, its past and masses
    (:class:`jaxnet.solve.dynamics.TimeStep`), which add the force of inertia, the water's acceleration and
    the drag on relative velocities to the same iteration.

    :func:`solve` drives the same iteration from the host instead (:func:`host_loop`): its compiled pieces
    are smaller and cacheable on disk. This form is for callers who need the solve inside a traced
    function (the dynamic step loop), and it is what the tests lower to see which terms a scene compiles.

    Its shape: one ``while_loop`` whose every pass evaluates the residual once, at the start point first,
    then at the line search's trial points; when a line search ends (or at the start) the tangent is
    assembled and factorised for the next direction (a ``lax.cond``). So the program holds the evaluation
    and the tangent once each: the start, the trials and the final force share them (compiling them twice
    would double the program), and the last accepted evaluation gives the returned force.
    """
    n_nodes = scene.nodes.position.shape[0]
    load = assemble.loads(scene, model)
    if step is not None:
        load = load + step.water_load
    free = pattern.free
    springs = spring_network.stiffness(scene, model, pattern)

    def status_of(it, f, e):
        res = jnp.max(_nodal_norm(f, pattern, n_nodes))
        return res, _status(it, res, e, opts, jnp)

    def direction(x, f, e_stored, f_nc, s, mu):
        """The damped Newton step at x and what the line search needs to judge its trials."""
        X = assemble.positions(x, scene, pattern)
        e = _merit(e_stored, X, load + f_nc)
        data = _tangent(x, s, 1.0, scene, pattern, model, opts.stiffness, step)
        dx, ok = linalg.solve(data + mu * springs, f, pattern.indptr, pattern.indices)
        # FEMNET's displacement limit: scale the step so that no node moves more than max_step.
        biggest = jnp.max(_nodal_norm(dx, pattern, n_nodes))
        dx = dx * jnp.minimum(1.0, opts.max_step / jnp.maximum(biggest, 1e-300))
        slope = jnp.dot(f, dx)  # -d(merit)/d(alpha) at alpha = 0: > 0 for a descent direction
        curvature = jnp.dot(dx, linalg.matvec(data, pattern.rows, pattern.indices, dx))
        predicted = slope - 0.5 * curvature  # decrease predicted by the undamped quadratic model
        usable = ok & (slope > 0)
        roundoff = 1e-12 * (jnp.abs(e) + jnp.abs(jnp.sum((load + f_nc) * X)))
        return dx, slope, predicted, usable, e, roundoff, jnp.linalg.norm(f)

    zero_free = jnp.zeros_like(x0)
    zero = jnp.zeros_like(load)
    # placeholders of the right types for the accepted iterate and its direction, filled by the first pass
    s0 = _placeholders(jax.eval_shape(lambda: _evaluate(x0, zero, load, 1.0, scene, pattern, model, step)[4]))
    f64 = jnp.asarray(0.0)
    carry0 = dict(
        x=x0, f=zero_free, force=zero, e_stored=f64, f_nc=zero, s=s0, mu=jnp.asarray(opts.damping), it=jnp.asarray(0),
        st=jnp.asarray(RUNNING), hist=jnp.full(opts.max_iter + 1, jnp.nan),
        dx=zero_free, slope=f64, predicted=f64, usable=jnp.asarray(False), e=f64, roundoff=f64, res_now=f64,
        k=jnp.asarray(0), alpha=jnp.asarray(1.0), started=jnp.asarray(False))

    def cond(c):
        return c["st"] == RUNNING

    def body(c):
        started, usable = c["started"], c["usable"]
        alpha = jnp.where(c["k"] == 0, 1.0, 0.5 * c["alpha"])
        # the start point first; an unusable direction is judged without a trial (its pass re-evaluates x)
        x_try = c["x"] + jnp.where(started & usable, alpha, 0.0) * c["dx"]
        e_try, force_try, nc_try, m_try, s_try = _evaluate(x_try, jnp.where(started, c["f_nc"], zero), load, 1.0,
                                                           scene, pattern, model, step, c["s"])
        f_try = force_try.ravel()[free]
        done = usable & _accepts(m_try, f_try, c["e"], alpha, c["slope"], c["roundoff"], c["res_now"], jnp)
        trials = jnp.where(usable, c["k"] + 1, 0)
        ends = ~started | done | ~usable | (trials >= opts.line_search)  # this pass ends an iteration
        accepted = ~started | done
        keep = lambda new, old: jnp.where(accepted, new, old)  # noqa: E731
        x, f, force = keep(x_try, c["x"]), keep(f_try, c["f"]), keep(force_try, c["force"])
        e_stored, f_nc = keep(e_try, c["e_stored"]), keep(nc_try, c["f_nc"])
        s = jax.tree.map(keep, s_try, c["s"])
        it = jnp.where(started & ends, c["it"] + 1, c["it"])
        res, st = status_of(it, f, jnp.where(started, jnp.where(done, m_try, c["e"]), e_try))
        mu = _next_damping(c["mu"], done, trials, c["e"], m_try, c["predicted"],
                           res / jnp.maximum(c["hist"][c["it"]], 1e-300), opts, jnp)
        mu = jnp.where(started & ends, mu, c["mu"])
        st = jnp.where(started & (st == RUNNING) & ~done & (c["mu"] >= opts.max_damping), STALLED, st)
        st = jnp.where(ends, st, RUNNING)
        hist = jnp.where(ends, c["hist"].at[it].set(res), c["hist"])
        if opts.verbose:
            jax.lax.cond(started & ends, lambda: jax.debug.callback(
                _progress, it, res, c["mu"], jnp.where(done, alpha, 0.0), ordered=False), lambda: None)

        def new_direction(_):
            return direction(x, f, e_stored, f_nc, s, mu)

        def same_direction(_):
            return c["dx"], c["slope"], c["predicted"], usable, c["e"], c["roundoff"], c["res_now"]

        dx, slope, predicted, usable_next, e, roundoff, res_now = jax.lax.cond(
            ends & (st == RUNNING), new_direction, same_direction, None)
        return dict(x=x, f=f, force=force, e_stored=e_stored, f_nc=f_nc, s=s, mu=mu, it=it, st=st, hist=hist,
                    dx=dx, slope=slope, predicted=predicted, usable=usable_next, e=e, roundoff=roundoff,
                    res_now=res_now, k=jnp.where(ends, 0, trials), alpha=alpha, started=jnp.asarray(True))

    c = jax.lax.while_loop(cond, body, carry0)
    X = assemble.positions(c["x"], scene, pattern)
    nodal = _nodal_norm(c["f"], pattern, n_nodes)
    return Equilibrium(
        x=X,
        force=c["force"],
        residual_N=jnp.max(nodal),
        iterations=c["it"],
        status=c["st"],
        worst_node=jnp.argmax(nodal),
        history=c["hist"],
        energy=_merit(c["e_stored"], X, load + c["f_nc"]),
    )


_newton_jit = programs.jit(newton_loop, static_argnames=("model", "opts"))


# -- the host loop: the same iteration driven from Python, its pieces compiled once --------------------

def _tangent_blocks(x, state, scale, scene, pattern, model, stiffness="autodiff"):
    """The tangent's element matrices at free coordinates x, {family: (E, 3k, 3k)} (N/m,
    :func:`jaxnet.assemble.tangent_blocks`): what :func:`_tangent` sums into the pattern. The host loop sums
    them in a program of its own (:data:`_scatter_jit`), which XLA runs far faster than the pair compiled
    as one (``tangent_blocks`` says why; FEMNET's c2 on jaxnet's mesh: the whole tangent 3.2-3.4 ms in one
    program, 1.7-1.9 ms in two)."""
    X = assemble.positions(x, scene, pattern)
    return assemble.tangent_blocks(X, scene, model, state, scale, stiffness)


def _evaluate_from(x, f_frozen, load, scale, scene, pattern, previous, model):
    """:func:`_evaluate` in statics from the force terms' states ``previous`` (the host loop's evaluation:
    every dynamic argument positional, the model last)."""
    return _evaluate(x, f_frozen, load, scale, scene, pattern, model, None, previous)


_evaluate_jit = programs.jit(_evaluate_from, static_argnames=("model",))
_tangent_blocks_jit = programs.jit(_tangent_blocks, static_argnames=("model", "stiffness"))
_scatter_jit = programs.jit(assemble.scatter_stiffnesses)


def _springs(scene, pattern, model):
    return spring_network.stiffness(scene, model, pattern)


_springs_jit = programs.jit(_springs, static_argnames=("model",))
# jitted although it runs once per solve: op by op, its vmaps compile dozens of small programs (1.7 s cold)
_loads_jit = programs.jit(assemble.loads, static_argnames=("model",))


def _compile_pieces(start, scene, pattern, model, stiffness="autodiff"):
    """The evaluation, the tangent's element matrices ("tangent"), their sum into the pattern ("scatter",
    :func:`_tangent_blocks` says why apart), the spring network and the loads, compiled for this scene's
    shape and terms, as a dict of callables taking their dynamic arguments only
    (:mod:`jaxnet.solve.programs`: from this process's memory, else from disk, else compiled in parallel
    threads). A second solve of a scene of the same shape (another load, another panel cut, another start)
    reuses them and compiles nothing; a second process loads them from disk, without tracing.

    The order matters on a first solve: tracing holds the GIL, XLA's compilation does not. So the
    evaluation is traced first and alone, and compiles while the tangent is traced, which then compiles
    while the small scatter, spring network and loads are traced. Each trace gives the next one's
    argument shapes: the evaluation's, the force terms' states (the catch front); the tangent's, its
    element matrices. (Measured on FEMNET's c2, 2 cores: 2.2 s from start to all compiled, against 2.6 s
    with every program traced at once.)"""
    zero = np.zeros(scene.nodes.position.shape)
    evaluate_args = (start, zero, zero, 1.0, scene, pattern, _unknown_states(scene, pattern, model))
    found = {"evaluate": programs.lookup("evaluate", evaluate_args, {"model": model})}
    jobs = {}
    with concurrent.futures.ThreadPoolExecutor(4) as pool:
        if found["evaluate"] is None:
            traced = _evaluate_jit.trace(*evaluate_args, model=model)
            jobs["evaluate"] = pool.submit(programs.compile, "evaluate", _evaluate_jit, evaluate_args,
                                           {"model": model}, traced)
            shapes = traced.out_info[4]
        else:
            shapes = found["evaluate"].out_info[4]
        # placeholders for the states: strongly typed as the evaluation returns them
        state = jax.tree.map(lambda s: np.zeros(s.shape, s.dtype), shapes)
        tangent_args, tangent_static = (start, state, 1.0, scene, pattern), {"model": model, "stiffness": stiffness}
        found["tangent"] = programs.lookup("tangent", tangent_args, tangent_static)
        if found["tangent"] is None:
            traced = _tangent_blocks_jit.trace(*tangent_args, **tangent_static)
            jobs["tangent"] = pool.submit(programs.compile, "tangent", _tangent_blocks_jit, tangent_args,
                                          tangent_static, traced)
            blocks = traced.out_info
        else:
            blocks = found["tangent"].out_info
        # the element matrices' placeholders, for the program that sums them into the pattern
        blocks = jax.tree.map(lambda b: np.zeros(b.shape, b.dtype), blocks)
        rest = {"scatter": (_scatter_jit, (blocks, pattern), {}),
                "springs": (_springs_jit, (scene, pattern), {"model": model}),
                "loads": (_loads_jit, (scene,), {"model": model})}
        for name, (jitted, args, static) in rest.items():
            found[name] = programs.lookup(name, args, static)
            if found[name] is None:
                jobs[name] = pool.submit(programs.compile, name, jitted, args, static)
        found.update({name: job.result() for name, job in jobs.items()})
    return found


def _stalled(hist, window):
    """True when the best residual of the last ``window`` iterations is not half the best one before them
    (``hist``: the residuals after each iteration, the start's excluded: a flat start has a tiny one)."""
    if window == 0:
        return True
    if window is None or len(hist) < 2 * window:
        return False
    return bool(np.min(hist[-window:]) > 0.5 * np.min(hist[:-window]))


def _balancing_scale(applied, f):
    """The factor s on the elastic forces that best balances the applied forces (least squares): with
    ``applied`` the loads and non-conservative forces and ``f`` the out-of-balance force, the elastic
    forces are applied - f and s = argmin |applied - s (applied - f)|. s ~ 1 where the net carries its loads;
    s << 1 where its twines pull far harder than anything applied to them: an over-stretched iterate."""
    internal = applied - f
    return float(applied @ internal) / max(float(internal @ internal), 1e-300)


def _overstretched(hist, balance, opts):
    """Start the stiffness continuation? When plain Newton stalls (:func:`_stalled`) on iterates whose
    twines pull much harder than the loads (median balancing scale of the stall window below
    ``soften_below``): the stretch barrier of large rotations. A net that stalls while carrying its loads
    (slack regions chattering, s ~ 0.1-1) gains nothing from softening."""
    if opts.stall_window == 0:
        return True
    return _stalled(hist, opts.stall_window) and float(np.median(balance[-opts.stall_window:])) < opts.soften_below


def stiffness_stages(opts: Newton):
    """Elastic energy scales of the stiffness continuation: soft_start, soft_start * stiffening, ... then 1."""
    if opts.stall_window is None or not 0.0 < opts.soft_start < 1.0:
        return [1.0]
    n = int(np.ceil(np.log(1.0 / opts.soft_start) / np.log(opts.stiffening) - 1e-9))
    return [float(opts.soft_start * opts.stiffening**k) for k in range(n)] + [1.0]


def host_loop(start, scene, pattern, model, opts: Newton, pieces=None):
    """The Newton iteration of :func:`newton_loop`, driven from Python: each iteration calls the compiled
    tangent once, factorises on the host (SuperLU) and calls the compiled evaluation once per line-search
    trial. Same rules (shared functions), same result; prints progress as it goes when verbose.
    ``pieces``: the compiled programs (:func:`_compile_pieces`), obtained here if not given."""
    if pieces is None:
        pieces = _compile_pieces(np.asarray(start, dtype=float), scene, pattern, model, opts.stiffness)
    evaluate, tangent, scatter = pieces["evaluate"], pieces["tangent"], pieces["scatter"]
    n_nodes = scene.n_nodes
    free = np.asarray(pattern.free)
    indptr, indices = np.asarray(pattern.indptr), np.asarray(pattern.indices)
    factor = linalg.HostSolver(indptr, indices)
    # The scene and pattern moved to the device once: the programs take them at every call, and a numpy
    # leaf is copied to the device at each (c2: 22 copies per call, 30-40 us of its 100-140 us dispatch).
    scene_on_device, pattern_on_device = jax.device_put((scene, pattern))
    springs = np.asarray(pieces["springs"](scene_on_device, pattern_on_device))
    load_device = pieces["loads"](scene_on_device)  # constant: computed once, passed to every evaluation
    load = np.asarray(load_device)
    X0 = np.asarray(scene.nodes.position, dtype=float).ravel()

    def nodal(v):
        full = np.zeros(3 * n_nodes)
        full[free] = v
        return np.sqrt(np.sum(full.reshape(-1, 3) ** 2, axis=1))

    def positions(x):
        X = X0.copy()
        X[free] = x
        return X.reshape(-1, 3)

    scales = stiffness_stages(opts)
    stage = len(scales) - 1  # plain Newton (the net as it is) until the continuation starts

    def run(x, f_frozen, previous):
        # previous: the force terms' states at the last accepted iterate, where their solutions start
        e, force, f_nc, m, state = evaluate(x, f_frozen, load_device, scales[stage], scene_on_device,
                                            pattern_on_device, previous)
        return float(e), np.asarray(force), np.asarray(f_nc), float(m), state

    x = np.asarray(start, dtype=float)
    e_stored, force, f_nc, _, state = run(x, np.zeros_like(load), _unknown_states(scene, pattern, model))
    f = force.ravel()[free]
    hist = np.full(opts.max_iter + 1, np.nan)
    res = nodal(f).max()
    hist[0] = res
    it, mu = 0, opts.damping
    st = int(_status(0, res, e_stored, opts, np))
    stage_start, softened = res, False
    balance = []  # after each iteration, the elastic scale that best balances the loads there
    final = len(scales) - 1
    tangent_at = None  # (x, state, stage) of the last tangent: held, so a new x or state is a new object
    while st == RUNNING:
        if not softened and final > 0 and _overstretched(hist[1:it + 1], balance, opts):
            # plain Newton is stalling: the stiffness continuation starts here, with half the iterations
            # left; if it fails or runs out of them, plain Newton goes on from here or from where it got to
            stage, softened = -1, True
            resume, soft_until = (x, f, e_stored, force, f_nc, state, mu), it + (opts.max_iter - it) // 2
        if stage < final and softened and it >= soft_until:
            # plain Newton goes on from the better start, by the residual of the net as it is: where the
            # continuation began, or where it got to (a net nearly stiffened back is often much closer)
            stage = final
            here = run(x, f_nc, state)
            f_here = here[1].ravel()[free]
            if nodal(f_here).max() < nodal(resume[1]).max():
                e_stored, force, f_nc, state, f = here[0], here[1], here[2], here[4], f_here
                where = "from where it got to"
            else:
                (x, f, e_stored, force, f_nc, state, mu), where = resume, "from where it started"
            res = nodal(f).max()
            if opts.verbose:
                print(f"  stiffness continuation abandoned: plain Newton {where}")
        if stage < final and (stage < 0 or res <= max(opts.tol, opts.stage_rtol * stage_start)):
            # next stage: the same positions, a stiffer net (the residual jumps, mu is kept)
            stage += 1
            e_stored, force, f_nc, _, state = run(x, f_nc, state)
            f = force.ravel()[free]
            res = stage_start = nodal(f).max()
            if opts.verbose:
                print(f"  stiffness x {scales[stage]:.3g}")
        X = positions(x)
        e = e_stored - float(np.sum((load + f_nc) * X))
        if tangent_at is None or tangent_at[0] is not x or tangent_at[1] is not state or tangent_at[2] != stage:
            # an iteration that took no step leaves x as it was: its tangent serves again, only mu changes
            # element matrices, on the device
            blocks = tangent(x, state, scales[stage], scene_on_device, pattern_on_device)
            data, tangent_at = np.asarray(scatter(blocks, pattern_on_device)), (x, state, stage)
        dx, ok = factor.solve(data + mu * springs, f)
        biggest = nodal(dx).max()
        dx = dx * min(1.0, opts.max_step / max(biggest, 1e-300))
        slope = float(f @ dx)
        curvature = float(dx @ linalg.host_matvec(data, indptr, indices, dx))
        predicted = slope - 0.5 * curvature
        usable = bool(ok) and slope > 0
        roundoff = 1e-12 * (abs(e) + abs(float(np.sum((load + f_nc) * X))))
        res_now = np.linalg.norm(f)
        trials, alpha, accepted, m_new = 0, 1.0, False, np.inf
        while usable and trials < opts.line_search and not accepted:
            alpha = 1.0 if trials == 0 else 0.5 * alpha
            e_try, force_try, nc_try, m_new, s_try = run(x + alpha * dx, f_nc, state)
            f_try = force_try.ravel()[free]
            accepted = bool(_accepts(m_new, f_try, e, alpha, slope, roundoff, res_now, np))
            trials += 1
        if accepted:
            x, f, e_stored, force, f_nc, state = x + alpha * dx, f_try, e_try, force_try, nc_try, s_try
        res = nodal(f).max()
        st = int(_status(it + 1, res, m_new if accepted else e, opts, np))
        if st == CONVERGED and stage < final:
            st = RUNNING  # a softened net's equilibrium: go on stiffening
        mu_next = float(_next_damping(mu, accepted, trials, e, m_new, predicted,
                                      res / max(hist[it], 1e-300), opts, np))
        if st == RUNNING and not accepted and mu >= opts.max_damping:
            st = STALLED
        if st in (STALLED, NON_FINITE) and stage < final:
            st, soft_until = RUNNING, it + 1  # a softened net failed: abandon the continuation (above)
        hist[it + 1] = res
        balance.append(_balancing_scale((load + f_nc).ravel()[free], f))
        if opts.verbose:
            _progress(it + 1, res, mu, alpha if accepted else 0.0)
        it, mu = it + 1, mu_next
    nodal_f = nodal(f)
    X = positions(x)
    return Equilibrium(
        # device_put, not jnp.asarray: jax 0.10 stages numpy values through a program compiled per shape
        **jax.device_put(dict(x=X, force=force, residual_N=nodal_f.max(), iterations=np.int64(it), status=np.int64(st),
                              worst_node=np.int64(np.argmax(nodal_f)), history=hist,
                              energy=np.float64(e_stored - float(np.sum((load + f_nc) * X))))),
    )


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
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (scene.n_nodes, 3):
            raise ValueError(f"solve: x0 (start positions) must have shape ({scene.n_nodes}, 3), got {x0.shape}")
        bad = np.argwhere(~np.isfinite(x0))
        if bad.size:
            raise ValueError(f"solve: x0 (start positions) of node {int(bad[0][0])} is not finite: "
                             f"{x0[bad[0][0]].tolist()}")
    start = np.asarray(scene.nodes.position if x0 is None else x0, dtype=float).ravel()[np.asarray(pattern.free)]
    t0 = time.perf_counter()
    pieces = _compile_pieces(start, scene, pattern, model, solver.stiffness)
    t1 = time.perf_counter()
    eq = host_loop(start, scene, pattern, model, solver, pieces)
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
