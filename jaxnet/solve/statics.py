"""Static equilibrium: the damped Newton iteration (:mod:`jaxnet.solve.newton`) driven from the host, with a
stiffness continuation, its pieces compiled once per scene shape.

    eq = solve(scene)                       # an Equilibrium; eq.timing: compile and wall times (s)
    eq = solve(scene, Newton(tol=1e-6), x0=start, throw=False)

The driver. :func:`solve` compiles the evaluation of the residual and the tangent once each (in parallel,
:func:`compile_pieces`), and each iteration of :func:`host_loop` calls the tangent once, factorises on the
host (:func:`jaxnet.linalg.direct_solver`: PARDISO where MKL is installed, else SuperLU with its ordering kept
per sparsity pattern)
and calls the evaluation once per line-search trial, from the last accepted iterate's catch front
(:func:`jaxnet.solve.kernel.evaluate`'s ``previous``). Same rules and arithmetic as the jittable
:func:`jaxnet.solve.newton.newton_loop` (shared functions). Its compiled pieces are half the size of the
whole loop's program and hold no host callback, so they are kept whole between processes
(:mod:`jaxnet.solve.programs`, when a compilation cache directory is set: the command line sets one): a
second process loads them without tracing or compiling.

Stiffness continuation. A net that starts far from its equilibrium shape (FEMNET's cases start flat: a
panel drawn horizontal that must swing down to hang; a cod-end drawn as a cone that must bulge around its
catch) needs large rotations, and its twines are stiff: a Newton step, linear in the positions, stretches
the twines it rotates by O(step²), the energy line search cuts it back, and the iteration crawls (on
``nr_netting`` the residual bounces at 10²-10³ N for hundreds of iterations). The symptom is seen on the
iterates: the twines pull far harder than anything applied to them
(:func:`jaxnet.solve.newton.balancing_scale`: the factor on the elastic forces that would best balance the
loads there is 1e-5-1e-3). When plain Newton stalls on such iterates
(:func:`jaxnet.solve.newton.overstretched`), the solver continues from where it is with the *elastic
energies scaled by s* (twines, bars, mesh opening, knots, bending; not the potentials of weight and
buoyancy at the surface, nor the sea bed's): s = ``soft_start`` (1e-2), then s × ``stiffening`` (√10) each
time a stage is converged to ``stage_rtol`` of its starting residual, up to s = 1, the net as it is,
converged to ``tol``. A softer net (equivalently: the same net under loads 1/s times larger) finds its
shape in a few steps, because stretching is cheap, and each stiffening is a small correction from the
last shape. Only the path changes, not the answer: the last stage is the unscaled problem. The
continuation gets half the iterations left when it starts; if it does not finish in them, or a softened
net stalls, plain Newton goes on from the better of where the continuation began and where it got to (by
the largest residual of the net as it is): a misjudged start costs iterations, not the solve, and a
continuation that ran out of iterations a stage or two short of the end is not thrown away (the stability
suite's small curtains in a 1 m/s current from a crumpled start did not converge when plain Newton went
back to the crumpled start; ``validation/stability.py``). The continuation cuts the iterations of nets that
start far from their shape several-fold (``benchmarks/femnet_cases.py``: FEMNET's cases); nets that
converge steadily never soften, nor do slack curtains that stall while carrying their loads (balancing
scale 0.005-0.1: softened, they take more iterations, not fewer). The jitted
:func:`~jaxnet.solve.newton.newton_loop` has no continuation.

A solve stops with a named reason; :func:`solve` raises :class:`SolveError` (reason, iteration, worst
node) unless ``throw=False``, and never returns NaN silently.

Units: m, N, J, s.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import time

import jax
import numpy as np

from jaxnet import linalg, model as model_lib
from jaxnet.model import assemble
from jaxnet.scene import checks
from jaxnet.memo import Memo
from jaxnet.solve import diagnosis, interior, kernel, newton, programs
from jaxnet.solve.options import STATIC, Newton
from jaxnet.solve.results import CONVERGED, NON_FINITE, RUNNING, STALLED, Equilibrium, SolveError, Timing

__all__ = ["solve", "host_loop", "damped_loop", "compile_pieces", "damped_pieces", "start_coordinates",
           "FreeCoordinates", "step_loads", "constant_loads", "Continuation"]


# -- the compiled pieces ----------------------------------------------------------------------------------


def _evaluate_from(x, f_frozen, load, scale, scene, pattern, previous, step, model):
    """:func:`jaxnet.solve.kernel.evaluate` from the force terms' states ``previous``, in statics (``step``
    None) or in a time step (the host loop's evaluation: every dynamic argument positional, the model last)."""
    return kernel.evaluate(x, f_frozen, load, scale, scene, pattern, model, step, previous)


def _tangent_from(x, state, scale, scene, pattern, step, model, stiffness):
    """:func:`jaxnet.solve.kernel.tangent_blocks`, in statics or in a time step (every dynamic argument
    positional)."""
    return kernel.tangent_blocks(x, state, scale, scene, pattern, model, stiffness, step)


_evaluate_jit = programs.jit(_evaluate_from, static_argnames=("model",))
_tangent_blocks_jit = programs.jit(_tangent_from, static_argnames=("model", "stiffness"))
_scatter_jit = programs.jit(assemble.scatter_stiffnesses)
_springs_jit = programs.jit(kernel.springs, static_argnames=("model",))
# jitted although it runs once per solve: op by op, its vmaps would compile dozens of small programs
_loads_jit = programs.jit(kernel.loads, static_argnames=("model",))


def constant_loads(scene, model):
    """(N, 3) the constant nodal loads (N) of ``scene`` (weight, buoyancy, applied forces), by the solver's own
    compiled program ("loads", :mod:`jaxnet.solve.programs`): a solve of this scene has compiled it."""
    return np.asarray(programs.obtain("loads", _loads_jit, (scene,), {"model": model})(scene))


#: the force terms' state shapes per scene signature (:func:`jaxnet.solve.programs.identity` of the states'
#: arguments and terms): found by tracing the states alone, once per process for a scene shape, not at every
#: warm solve
_STATE_SHAPES = Memo(64)


def _unknown_states(scene, pattern, model):
    """:func:`jaxnet.solve.kernel.placeholders` of the force terms' states of ``scene`` (the first
    evaluation's ``previous``)."""
    key = programs.identity("states", (scene, pattern), {"model": model})
    return kernel.placeholders(_STATE_SHAPES.get_or_make(key, lambda: kernel.state_shapes(scene, pattern, model)))


def compile_pieces(start, scene, pattern, model, stiffness="autodiff", step=None, method="damped"):
    """The programs of :func:`host_loop` for ``method`` (:data:`jaxnet.solve.options.METHODS`): for the
    primal-dual method on a scene it suits (:func:`jaxnet.solve.interior.suits`),
    :func:`jaxnet.solve.interior.compile_pieces`; else :func:`damped_pieces`."""
    if method == "primal-dual" and interior.suits(model):
        return interior.compile_pieces(start, scene, pattern, model, stiffness, step)
    return damped_pieces(start, scene, pattern, model, stiffness, step)


def damped_pieces(start, scene, pattern, model, stiffness="autodiff", step=None):
    """The evaluation, the tangent's element matrices ("tangent"), their sum into the pattern ("scatter",
    :func:`jaxnet.solve.kernel.tangent_blocks` says why apart), the spring network and the loads, compiled
    for this scene's shape and terms (and for a time step, given one of its shape: ``step``, a
    :class:`jaxnet.solve.dynamics.TimeStep`), as a dict of callables taking their dynamic arguments only (and
    under "states" the placeholders of the force terms' states the first evaluation starts from)
    (:mod:`jaxnet.solve.programs`: from this process's memory, else from disk, else compiled in parallel
    threads). A second solve of a scene of the same shape (another load, another panel cut, another start)
    reuses them and compiles nothing; a second process loads them from disk, without tracing.

    The order matters on a first solve: tracing holds the GIL, XLA's compilation does not. So the
    evaluation is traced first and alone, and compiles while the tangent is traced, which then compiles
    while the small scatter, spring network and loads are traced (faster from start to all compiled than
    every program traced at once; ``benchmarks/femnet_cases.py`` times cold solves). Each trace gives the
    next one's argument shapes: the evaluation's, the force terms' states (the catch front); the tangent's,
    its element matrices."""
    zero = np.zeros(scene.nodes.position.shape)
    unknown = _unknown_states(scene, pattern, model)
    evaluate_args = (start, zero, zero, 1.0, scene, pattern, unknown, step)
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
        tangent_args = (start, state, 1.0, scene, pattern, step)
        tangent_static = {"model": model, "stiffness": stiffness}
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
    found["states"] = unknown  # the first evaluation's force-term states (placeholders), for the host loop
    return found


# -- the host loop ----------------------------------------------------------------------------------------


def host_loop(start, scene, pattern, model, solver: Newton, pieces=None, step=None):
    """The static iteration of ``solver.method`` from free coordinates ``start`` (m), driven from the host:
    :func:`damped_loop`, or for ``"primal-dual"`` on a scene it suits (:func:`jaxnet.solve.interior.suits`)
    :func:`jaxnet.solve.interior.host_loop` (at most :data:`jaxnet.solve.interior.BUDGET` iterations, or half of
    ``max_iter``), and where that stops short of convergence, :func:`damped_loop` from ``start`` with ``max_iter``
    iterations of its own: the damped method's own path from the same start, so that a net the damped method
    solves is solved, to its answer (bit for bit), at the cost of the primal-dual's iterations before it.
    ``pieces``: :func:`compile_pieces` of the same method. Returns an :class:`Equilibrium`, its iterations both
    methods', its history the primal-dual's residuals then the damped method's, its timing both (the damped
    method's compilation, when it runs, in ``timing.wall_s``)."""
    if not (solver.method == "primal-dual" and interior.suits(model)):
        return damped_loop(start, scene, pattern, model, solver, pieces, step)
    if pieces is None:
        pieces = interior.compile_pieces(np.asarray(start, dtype=float), scene, pattern, model, solver.stiffness, step)
    first = interior.host_loop(start, scene, pattern, model, solver, pieces, step)
    used = int(first.iterations)
    if first.converged:
        return first
    if solver.verbose:
        print(f"  primal-dual: {first.reason} after {used} iterations; the damped method from the start")
    if "damped" not in pieces:
        pieces["damped"] = damped_pieces(np.asarray(start, dtype=float), scene, pattern, model, solver.stiffness, step)
    second = damped_loop(start, scene, pattern, model, solver, pieces["damped"], step)
    history = np.concatenate([np.asarray(first.history)[:used + 1], np.asarray(second.history)[1:]])
    a, b = first.timing, second.timing
    timing = Timing(compile_s=a.compile_s + b.compile_s, wall_s=a.wall_s + b.wall_s, fallbacks=a.fallbacks + b.fallbacks,
                    **{name: getattr(a, name) + getattr(b, name) for name in
                       ("assembly_s", "factorisation_s", "evaluation_s", "factorisations", "evaluations")})
    return dataclasses.replace(second, iterations=second.iterations + used, history=jax.device_put(history),
                               timing=timing)


class FreeCoordinates:
    """A scene's free coordinates on the host (numpy), for the host loops: ``nodal(v)``, the norm per node (N,) of a
    vector on them (zero at fixed coordinates); ``positions(x)``, the (N, 3) positions (m) they give, the fixed
    coordinates the scene's."""

    def __init__(self, scene, pattern):
        self.free = np.asarray(pattern.free)
        self.n_nodes = scene.n_nodes
        self.start = np.asarray(scene.nodes.position, dtype=float).ravel()

    def nodal(self, v):
        full = np.zeros(3 * self.n_nodes)
        full[self.free] = v
        return np.sqrt(np.sum(full.reshape(-1, 3) ** 2, axis=1))

    def positions(self, x):
        X = self.start.copy()
        X[self.free] = x
        return X.reshape(-1, 3)


def step_loads(load_device, pattern, step):
    """(load, inertia, diagonal) of a host loop: the constant loads ``load_device`` (N, 3) (N), in a time step plus
    the water's inertia (M_a + ρV) γ_h (as :func:`jaxnet.solve.kernel.loads` adds it); in a time step the inertia's
    stiffness (M + M_a)/Δt² (N/m) on the free coordinates and the positions of the diagonal in the CSR entries (as
    :func:`jaxnet.solve.kernel.tangent` adds it), else None and None."""
    if step is None:
        return load_device, None, None
    inertia = (np.asarray(step.mass) / float(step.time_step) ** 2).ravel()[np.asarray(pattern.free)]
    return load_device + step.water_load, inertia, np.asarray(pattern.diagonal)


class Continuation:
    """The stiffness continuation of :func:`damped_loop` (module docstring), a small state machine over the
    stages of :func:`jaxnet.solve.newton.stiffness_stages`: the net solved at ``scale`` times its stiffness, then
    stiffened stage by stage. ``stage`` is the index of the scale in use, the last (1, the net as it is) for
    plain Newton, -1 before the first softened stage.

    It starts when plain Newton overstretches (:func:`jaxnet.solve.newton.overstretched`), with half the
    iterations left (:meth:`start_if_stalling`); it moves to the next stage when the residual falls below
    ``stage_rtol`` times the stage's first (:meth:`due_to_stiffen`); it ends when its iterations run out or a
    softened stage fails (:meth:`due_to_end`), and plain Newton goes on from the iterate it kept or from where
    it got to. An implicit time step (``static=False``) has plain Newton only."""

    def __init__(self, solver: Newton, static: bool = True):
        self.solver = solver
        self.scales = newton.stiffness_stages(solver) if static else [1.0]
        self.final = len(self.scales) - 1
        self.stage = self.final
        self.stage_start = np.inf   # the residual at the start of the stage (N)
        self.softened = False       # started once (it never starts twice)
        self.kept = None            # the iterate it started from
        self.until = None           # the iteration at which it ends

    @property
    def scale(self):
        """The stiffness scale of the stage in use."""
        return self.scales[self.stage]

    def start_if_stalling(self, it, history, balance, iterate):
        """Starts the continuation at iteration ``it`` if plain Newton is stalling on an overstretched net
        (``history``: the residuals so far, ``balance``: the balancing scales), keeping ``iterate``."""
        if not self.softened and self.final > 0 and newton.overstretched(history[1:it + 1], balance, self.solver):
            self.stage, self.softened = -1, True
            self.kept, self.until = iterate, it + (self.solver.max_iter - it) // 2

    def due_to_end(self, it):
        """Whether the softened stages end at iteration ``it`` (out of their iterations, or failed)."""
        return self.stage < self.final and self.softened and it >= self.until

    def end(self):
        """Plain Newton from now on; returns the iterate the continuation started from."""
        self.stage = self.final
        return self.kept

    def due_to_stiffen(self, residual):
        """Whether to move to the next stage at this ``residual`` (N)."""
        return self.stage < self.final and (
            self.stage < 0 or residual <= max(self.solver.tol, self.solver.stage_rtol * self.stage_start))

    def converged_softened(self, status):
        """A softened net's equilibrium is not the answer: RUNNING (go on stiffening) where ``status`` says
        CONVERGED on a softened stage."""
        return RUNNING if status == CONVERGED and self.stage < self.final else status

    def failed_softened(self, status, it):
        """A softened stage that stalled or met a non-finite value ends the continuation at the next
        iteration (:meth:`due_to_end`): RUNNING for now."""
        if status in (STALLED, NON_FINITE) and self.stage < self.final:
            self.until = it + 1
            return RUNNING
        return status


def damped_loop(start, scene, pattern, model, solver: Newton, pieces=None, step=None):
    """The Newton iteration of :func:`jaxnet.solve.newton.newton_loop` with the stiffness continuation,
    driven from Python: each iteration calls the compiled tangent once, factorises on the host and
    calls the compiled evaluation once per line-search trial. Same rules (shared functions), same result;
    prints progress as it goes when verbose. ``pieces``: the compiled programs (:func:`compile_pieces`),
    obtained here if not given. ``step``: None for a static equilibrium; for an implicit time step its past
    and masses (:class:`jaxnet.solve.dynamics.TimeStep`, on the device), as ``newton_loop``'s, without the
    continuation (a step starts near its answer: as the jitted loop, plain Newton). Returns an
    :class:`Equilibrium` whose :class:`Timing` splits the loop's time (its ``compile_s`` 0: :func:`solve` adds
    the compilation)."""
    t_start = time.perf_counter()
    if pieces is None:
        pieces = damped_pieces(np.asarray(start, dtype=float), scene, pattern, model, solver.stiffness, step)
    evaluate, tangent, scatter = pieces["evaluate"], pieces["tangent"], pieces["scatter"]
    free = np.asarray(pattern.free)
    indptr, indices = np.asarray(pattern.indptr), np.asarray(pattern.indices)
    factor = linalg.direct_solver(indptr, indices)
    spent = dict(assembly_s=0.0, factorisation_s=0.0, evaluation_s=0.0, factorisations=0, evaluations=0)

    def factor_solve(entries, rhs):
        t = time.perf_counter()
        out = factor.solve(entries, rhs)
        spent["factorisation_s"] += time.perf_counter() - t
        spent["factorisations"] += 1
        return out
    # The scene and pattern moved to the device once: the programs take them at every call, and a numpy
    # leaf would be copied to the device at each (a good part of a call's dispatch on small nets). A time step's
    # are there already (device_put would still walk every leaf, at every step).
    on_host = any(isinstance(leaf, np.ndarray) for leaf in jax.tree.leaves((scene, pattern)))
    scene_on_device, pattern_on_device = jax.device_put((scene, pattern)) if on_host else (scene, pattern)
    springs = np.asarray(pieces["springs"](scene_on_device, pattern_on_device))
    load_device = pieces["loads"](scene_on_device)  # constant: computed once, passed to every evaluation
    load_device, inertia, diagonal = step_loads(load_device, pattern, step)
    load = np.asarray(load_device)
    host = FreeCoordinates(scene, pattern)
    nodal, positions = host.nodal, host.positions

    def matvec(data, v):
        return linalg.host_matvec(data, indptr, indices, v)

    continuation = Continuation(solver, static=step is None)

    def run(x, f_frozen, previous):
        # previous: the force terms' states at the last accepted iterate, where their solutions start
        t = time.perf_counter()
        e, force, f_nc, m, state = evaluate(x, f_frozen, load_device, continuation.scale, scene_on_device,
                                            pattern_on_device, previous, step)
        # one transfer for the four (a float() or asarray per array would wait on the device each)
        e, force, f_nc, m = jax.device_get((e, force, f_nc, m))
        out = float(e), force, f_nc, float(m), state
        spent["evaluation_s"] += time.perf_counter() - t
        spent["evaluations"] += 1
        return out

    x = np.asarray(start, dtype=float)
    unknown = pieces["states"] if "states" in pieces else _unknown_states(scene, pattern, model)
    e_stored, force, f_nc, _, state = run(x, np.zeros_like(load), unknown)
    f = force.ravel()[free]
    if solver.verbose:
        newton.legend()
    hist = np.full(solver.max_iter + 1, np.nan)
    res = nodal(f).max()
    hist[0] = res
    it, mu = 0, solver.damping
    st = int(newton.status(0, res, e_stored, solver, np))
    continuation.stage_start = res
    balance = []  # after each iteration, the elastic scale that best balances the loads there
    tangent_at = None  # (x, state, stage) of the last tangent: held, so a new x or state is a new object
    while st == RUNNING:
        continuation.start_if_stalling(it, hist, balance, (x, f, e_stored, force, f_nc, state, mu))
        if continuation.due_to_end(it):
            # plain Newton goes on from the better start, by the residual of the net as it is: where the
            # continuation began, or where it got to (a net nearly stiffened back is often much closer)
            resume = continuation.end()
            here = run(x, f_nc, state)
            f_here = here[1].ravel()[free]
            if nodal(f_here).max() < nodal(resume[1]).max():
                e_stored, force, f_nc, state, f = here[0], here[1], here[2], here[4], f_here
                where = "from where it got to"
            else:
                (x, f, e_stored, force, f_nc, state, mu), where = resume, "from where it started"
            res = nodal(f).max()
            if solver.verbose:
                print(f"  stiffness continuation abandoned: plain Newton {where}")
        if continuation.due_to_stiffen(res):
            # next stage: the same positions, a stiffer net (the residual jumps, mu is kept)
            continuation.stage += 1
            e_stored, force, f_nc, _, state = run(x, f_nc, state)
            f = force.ravel()[free]
            res = continuation.stage_start = nodal(f).max()
            if solver.verbose:
                print(f"  stiffness x {continuation.scale:.3g}")
        X = positions(x)
        work = float(np.sum((load + f_nc) * X))
        e = e_stored - work
        if tangent_at is None or tangent_at[0] is not x or tangent_at[1] is not state or \
                tangent_at[2] != continuation.stage:
            # an iteration that took no step leaves x as it was: its tangent serves again, only mu changes
            # element matrices, on the device
            t = time.perf_counter()
            blocks = tangent(x, state, continuation.scale, scene_on_device, pattern_on_device, step)
            data, tangent_at = np.asarray(scatter(blocks, pattern_on_device)), (x, state, continuation.stage)
            if inertia is not None:
                data = data.copy()
                data[diagonal] += inertia
            spent["assembly_s"] += time.perf_counter() - t
            # what float64 resolves on each node at this iterate (newton.roundoff_floor, as the jitted loop)
            floor = nodal(newton.ROUNDOFF_FACTOR * np.finfo(float).eps * matvec(np.abs(data), np.abs(x)))
        dx, slope, predicted, usable, roundoff, res_now = newton.direction(f, data, springs, mu, e, work, solver,
                                                                           factor_solve, matvec, nodal, np)
        trials, alpha, accepted, m_new = 0, 1.0, False, np.inf
        while usable and trials < solver.line_search and not accepted:
            alpha = 1.0 if trials == 0 else 0.5 * alpha
            e_try, force_try, nc_try, m_new, s_try = run(x + alpha * dx, f_nc, state)
            f_try = force_try.ravel()[free]
            accepted = bool(newton.accepts(m_new, f_try, e, alpha, slope, roundoff, res_now, np))
            trials += 1
        if accepted:
            x, f, e_stored, force, f_nc, state = x + alpha * dx, f_try, e_try, force_try, nc_try, s_try
        nodal_now = nodal(f)
        res = nodal_now.max()
        st = int(newton.status(it + 1, res, m_new if accepted else e, solver, np,
                               excess=np.max(nodal_now - np.maximum(solver.tol, floor))))
        st = continuation.converged_softened(st)
        mu_next = float(newton.next_damping(mu, accepted, trials, e, m_new, predicted,
                                            res / max(hist[it], 1e-300), solver, np))
        if st == RUNNING and not accepted and mu >= solver.max_damping:
            st = STALLED
        st = continuation.failed_softened(st, it)
        hist[it + 1] = res
        balance.append(newton.balancing_scale((load + f_nc).ravel()[free], f))
        if solver.verbose:
            newton.progress(it + 1, res, mu, alpha if accepted else 0.0)
        it, mu = it + 1, mu_next
    nodal_f = nodal(f)
    X = positions(x)
    return Equilibrium(
        # device_put, not jnp.asarray: jax 0.10 stages numpy values through a program compiled per shape
        **jax.device_put(dict(x=X, force=force, residual_N=nodal_f.max(), iterations=np.int64(it), status=np.int64(st),
                              worst_node=np.int64(np.argmax(nodal_f)), history=hist,
                              energy=np.float64(e_stored - float(np.sum((load + f_nc) * X))))),
        timing=Timing(compile_s=0.0, wall_s=time.perf_counter() - t_start, fallbacks=int(factor.fallbacks), **spent),
    )


def start_coordinates(scene, free, x0=None, who="solve"):
    """The free coordinates (m) a solve starts from: ``x0`` ((N, 3) m, checked: its shape and finite values;
    ValueError naming the node, ``who`` the caller) or the scene's positions, at the indices ``free``."""
    if x0 is not None:
        x0 = np.asarray(x0, dtype=float)
        if x0.shape != (scene.n_nodes, 3):
            raise ValueError(f"{who}: x0 (start positions) must have shape ({scene.n_nodes}, 3), got {x0.shape}")
        bad = np.argwhere(~np.isfinite(x0))
        if bad.size:
            raise ValueError(f"{who}: x0 (start positions) of node {int(bad[0][0])} is not finite: "
                             f"{x0[bad[0][0]].tolist()}")
    return np.asarray(scene.nodes.position if x0 is None else x0, dtype=float).ravel()[np.asarray(free)]


def solve(scene, solver: Newton | None = None, x0=None, throw: bool = True, **options) -> Equilibrium:
    """Static equilibrium of ``scene``.

    Args:
      scene: a :class:`jaxnet.scene.Scene` (validated here, before anything is compiled). A
        :class:`jaxnet.case.Case` is solved by the run layer, with its own options: :func:`jaxnet.run.solve_static`.
      solver: a :class:`~jaxnet.solve.options.Newton` options object (default
        :data:`jaxnet.solve.options.STATIC`); keyword ``options`` override its fields.
      x0: optional (N, 3) start positions (default: the scene's node positions); fixed nodes keep the
        scene's positions.
      throw: raise :class:`SolveError` if the solve does not converge; with ``throw=False`` the caller reads
        the returned equilibrium's ``status``/``reason``.
    Returns:
      an :class:`Equilibrium`, its ``timing`` the compile and run wall times (s): ``timing.compile_s`` is
      ~0 when a program compiled for a scene of the same shape and terms is reused.
    """
    solver = dataclasses.replace(solver or STATIC, **options)
    checks.validate(scene)
    linalg.solver_choice()  # a sparse solver asked for that cannot run here: said before anything compiles
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    start = start_coordinates(scene, pattern.free, x0)
    t0 = time.perf_counter()
    pieces = compile_pieces(start, scene, pattern, model, solver.stiffness, method=solver.method)
    t1 = time.perf_counter()
    eq = host_loop(start, scene, pattern, model, solver, pieces)
    eq = dataclasses.replace(eq, timing=dataclasses.replace(eq.timing, compile_s=t1 - t0,
                                                            wall_s=time.perf_counter() - t0))
    if throw and not eq.converged:
        node = int(eq.worst_node)
        found = "".join(f"; {hint}" for hint in diagnosis.hints(scene, eq))
        raise SolveError(
            f"static solve failed after {int(eq.iterations)} iterations: {eq.reason}; largest residual "
            f"{float(eq.residual_N):.4g} N at node {node} (position {np.asarray(eq.x)[node].round(4).tolist()})"
            f"{found}", eq)
    return eq
