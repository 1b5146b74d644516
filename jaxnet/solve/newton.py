"""The damped (Levenberg-Marquardt) Newton iteration with an energy line search: its rules, and the whole
iteration as one jittable program.

Why this globalisation. A net starts flat and stress-free: its tangent K is singular there (a slack membrane
has no out-of-plane stiffness, twines with zero compression stiffness none in compression, and the mesh
opening is a mechanism until the twines are loaded). FEMNET keeps a large added diagonal stiffness for
all iterations and needs thousands of them. Here each iteration solves ``(K + mu S) dx = F`` with S the
scene's *spring network* (every twine and bar a zero-length spring EA/l0; :mod:`jaxnet.solve.spring_network`):
``mu S`` acts as a fictitious prestrain ``mu`` (dimensionless) that gives the slack net the stiffness of a
prestressed one, so a damped step moves the net smoothly instead of node by node. ``mu`` is *adaptive*
(Nielsen's rule, :func:`next_damping`): raised when the quadratic model of the energy predicts its decrease
badly, lowered geometrically when it predicts it well, so it vanishes near the solution and the last
iterations are pure Newton steps (quadratic convergence). Every step is checked by a backtracking line
search on the total potential energy (:func:`accepts`), which costs energy evaluations only: each
iteration is one assembly and one sparse factorisation. An optional per-iteration displacement limit
(FEMNET's) caps the largest nodal move (:func:`direction`).

Convergence is judged as in FEMNET on forces: the largest nodal out-of-balance force over the free
coordinates, in newtons (:data:`jaxnet.solve.options.TOL_N` by default). A solve stops with a named reason
(:func:`status`, :data:`jaxnet.solve.results.REASONS`) and never returns NaN silently.

Two drivers run this iteration with these rules: :func:`newton_loop` here, the whole iteration as one
jittable program (the factorisation a host callback), for use inside traced code (time steps, the
differentiable equilibrium); and :func:`jaxnet.solve.statics.host_loop`, which drives it from the host
with compiled pieces and adds the stiffness continuation (:func:`stalled`, :func:`balancing_scale`,
:func:`overstretched`, :func:`stiffness_stages`). The rules take the array module ``xp`` (numpy on the
host, jax.numpy in the traced loop), so that both drivers run the same arithmetic.

Known limit. Nets whose equilibrium holds large *slack* regions (twines with EA_c = 0 and no tension: the
free sides of a curtain hanging from a rope, which gather and close their meshes) have a degenerate
minimum — the energy is flat over every arrangement of the slack netting and the last loads are carried by
twines a few 1e-7 in strain from their slack kink — and converge linearly, in a few hundred iterations
(the stability suite, ``validation/stability.py``, holds such nets). Well-held nets converge in a few to a
few tens of iterations, whatever their size (``benchmarks/statics.py``). A second limit, on FEMNET's
gear: a bar that carries little (a 1 cm link of EA 1.6e6 N stretched by ε = 4e-5) can be turned by only about
√(2ε) (9e-3 rad) in one step before the stretch the step makes (L0 θ²/2 more than its linear model expects)
outweighs its tension; where the net must still turn such bars, each iteration undoes the last one's stretch and
turns them a little further, for hundreds of iterations at a residual of a few newtons, and the path taken around
that barrier hangs on the last bits of the arithmetic (``docs/investigations.md``).

Units: m, N, J; damping dimensionless.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import linalg
from jaxnet.model import assemble
from jaxnet.solve import kernel, programs
from jaxnet.solve.options import Newton
from jaxnet.solve.results import CONVERGED, MAX_ITERATIONS, NON_FINITE, RUNNING, STALLED, Equilibrium


#: what the columns of :func:`progress` and the continuation's lines mean, printed once above them
LEGEND = ("  (damped: one line per Newton iteration. residual: the largest out-of-balance force on a node (N), "
          "converged below tol; damping: the fictitious prestrain mu that steadies a slack net's step, vanishing near the answer; "
          "step: the fraction of the damped step the energy line search took, 0 when it took none; "
          "\"stiffness x s\": stiffness continuation, the net solved at s times its stiffness, then stiffened)")


def legend():
    """Print :data:`LEGEND` (``Newton.verbose``), once before a solve's first :func:`progress` line."""
    print(LEGEND)


def progress(it, res, damping, step):
    """Print one iteration's line (``Newton.verbose``): residual (N), damping and the step taken (0: none);
    :data:`LEGEND` says what they are."""
    print(f"  newton {int(it):4d}  residual {float(res):11.4e} N  damping {float(damping):8.1e}  step {float(step):6.3f}")


# -- the rules of one iteration, shared by the two drivers -------------------------------------------------


def direction(f, data, springs, mu, e, work, solver: Newton, solve, matvec, nodal, xp):
    """The damped Newton step at an iterate and what the line search needs to judge its trials.

    f: (n,) the out-of-balance force on the free coordinates (N); data: the tangent's CSR entries (N/m);
    springs: the spring network's (N/m); mu: the damping; e: the merit there (J); work: the frozen loads'
    work there, sum((L + F_nc) . X) (J), the scale of the merit's roundoff. ``solve(entries, rhs)`` ->
    (dx, ok) solves with the CSR entries on the tangent's pattern, ``matvec(data, v)`` multiplies by the
    tangent, ``nodal(v)`` gives a free-coordinate vector's norm per node; ``xp`` numpy or jax.numpy.

    Returns (dx, slope, predicted, usable, roundoff, res_now): the step (m), limited so that no node moves
    more than ``max_step`` (FEMNET's displacement limit); the merit's decrease rate -d(merit)/d(alpha) at
    alpha = 0 (J, > 0 for a descent direction); the decrease the undamped quadratic model predicts for the
    full step (J); whether the step can be searched along (solved, and a descent direction); the merit's
    roundoff (J); |f| (N), which a step judged by the force must lower.
    """
    dx, ok = solve(data + mu * springs, f)
    biggest = xp.max(nodal(dx))
    dx = dx * xp.minimum(1.0, solver.max_step / xp.maximum(biggest, 1e-300))
    slope = xp.dot(f, dx)
    curvature = xp.dot(dx, matvec(data, dx))
    predicted = slope - 0.5 * curvature
    usable = ok & (slope > 0)
    roundoff = 1e-12 * (xp.abs(e) + xp.abs(work))
    return dx, slope, predicted, usable, roundoff, xp.linalg.norm(f)


def accepts(m_try, f_try, e, alpha, slope, roundoff, res_now, xp):
    """Backtracking (Armijo) test of a trial step on the merit. Near the solution the energy decrease falls
    below the roundoff of the energy itself; there a step is judged by the force."""
    armijo = m_try <= e - 1e-4 * alpha * slope
    flat = (alpha * slope <= roundoff) & (xp.abs(m_try - e) <= roundoff) & (xp.linalg.norm(f_try) < res_now)
    return xp.isfinite(m_try) & xp.all(xp.isfinite(f_try)) & (armijo | flat)


def next_damping(mu, accepted, trials, e, m_new, predicted, ratio, solver: Newton, xp):
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
    return xp.clip(mu_next, solver.min_damping, solver.max_damping)


#: the roundoff of a force, in units of eps x its row of |K| |x| (:func:`roundoff_floor`)
ROUNDOFF_FACTOR = 4.0


def roundoff_floor(data, rows, indices, x):
    """(n,) the smallest out-of-balance force (N) float64 resolves on each free coordinate: ``ROUNDOFF_FACTOR``
    eps Σ_j |K_ij| |x_j|, K the tangent (CSR ``data`` on ``rows``, column ``indices``, N/m) and x the free
    coordinates (m). The forces on a coordinate are sums of stiffnesses times coordinates, each known to eps
    |x_j|: ropes of EA 27 MN in short bars 280 m from the origin (a trawl's warp and bridles) put the floor of
    their nodes between 1e-6 and 1e-4 N, above the differentiable solve's 1e-8 N, and there Newton's iterates
    wander at the floor and never meet the tolerance. :func:`status` compares each node's residual with the larger
    of the two."""
    return ROUNDOFF_FACTOR * jnp.finfo(x.dtype).eps * linalg.matvec(jnp.abs(data), rows, indices, jnp.abs(x))


def status(it, res, e, solver: Newton, xp, excess=None):
    """The stop reason after ``it`` iterations with largest residual ``res`` (N) and merit ``e`` (J).
    ``excess``: with a roundoff floor (:func:`roundoff_floor`), the largest excess of a node's residual over
    max(tol, its floor) (N): converged when it is <= 0, whatever ``res`` is."""
    finite = xp.isfinite(res) & xp.isfinite(e)
    converged = res <= solver.tol if excess is None else excess <= 0.0
    return xp.where(~finite, NON_FINITE, xp.where(converged, CONVERGED,
                                                  xp.where(it >= solver.max_iter, MAX_ITERATIONS, RUNNING)))


# -- the stiffness continuation's rules (the host loop's) ---------------------------------------------------


def stalled(hist, window):
    """True when the best residual of the last ``window`` iterations is not half the best one before them
    (``hist``: the residuals after each iteration, the start's excluded: a flat start has a tiny one)."""
    if window == 0:
        return True
    if window is None or len(hist) < 2 * window:
        return False
    return bool(np.min(hist[-window:]) > 0.5 * np.min(hist[:-window]))


def balancing_scale(applied, f):
    """The factor s on the elastic forces that best balances the applied forces (least squares): with
    ``applied`` the loads and non-conservative forces and ``f`` the out-of-balance force, the elastic
    forces are applied - f and s = argmin |applied - s (applied - f)|. s ~ 1 where the net carries its loads;
    s << 1 where its twines pull far harder than anything applied to them: an over-stretched iterate."""
    internal = applied - f
    return float(applied @ internal) / max(float(internal @ internal), 1e-300)


def overstretched(hist, balance, solver: Newton):
    """Start the stiffness continuation? When plain Newton stalls (:func:`stalled`) on iterates whose
    twines pull much harder than the loads (median balancing scale of the stall window below
    ``soften_below``): the stretch barrier of large rotations. A net that stalls while carrying its loads
    (slack regions chattering, s ~ 0.1-1) gains nothing from softening."""
    if solver.stall_window == 0:
        return True
    return (stalled(hist, solver.stall_window)
            and float(np.median(balance[-solver.stall_window:])) < solver.soften_below)


def stiffness_stages(solver: Newton):
    """Elastic energy scales of the stiffness continuation: soft_start, soft_start * stiffening, ... then 1."""
    if solver.stall_window is None or not 0.0 < solver.soft_start < 1.0:
        return [1.0]
    n = int(np.ceil(np.log(1.0 / solver.soft_start) / np.log(solver.stiffening) - 1e-9))
    return [float(solver.soft_start * solver.stiffening**k) for k in range(n)] + [1.0]


# -- the whole iteration, jittable --------------------------------------------------------------------------


def newton_loop(x0, scene, pattern, model, solver: Newton, step=None):
    """The whole Newton iteration as one jittable program (``jax.lax.while_loop``), from free coordinates
    ``x0``; returns an :class:`~jaxnet.solve.results.Equilibrium` (``timing`` None). ``model`` (active
    terms) and ``solver`` are static. ``step``: None for a static equilibrium; for an implicit time step,
    its past and masses (:class:`jaxnet.solve.dynamics.TimeStep`), which add the force of inertia, the
    water's acceleration and the drag on relative velocities to the same iteration.

    :func:`jaxnet.solve.statics.solve` drives the same iteration from the host instead
    (:func:`jaxnet.solve.statics.host_loop`): its compiled pieces are smaller and cacheable on disk. This
    form is for callers who need the solve inside a traced function (the dynamic step loop, the
    differentiable equilibrium), and it is what the tests lower to see which terms a scene compiles.

    Its shape: one ``while_loop`` whose every pass evaluates the residual once, at the start point first,
    then at the line search's trial points; when a line search ends (or at the start) the tangent is
    assembled and factorised for the next direction (a ``lax.cond``). So the program holds the evaluation
    and the tangent once each: the start, the trials and the final force share them (compiling them twice
    would double the program), and the last accepted evaluation gives the returned force.
    """
    n_nodes = scene.nodes.position.shape[0]
    load = kernel.loads(scene, model, step)
    free = pattern.free
    springs = kernel.springs(scene, pattern, model)

    def status_of(it, f, e, floor):
        nodal_f = kernel.nodal_norm(f, pattern, n_nodes)
        excess = jnp.max(nodal_f - jnp.maximum(solver.tol, kernel.nodal_norm(floor, pattern, n_nodes)))
        return jnp.max(nodal_f), status(it, jnp.max(nodal_f), e, solver, jnp, excess)

    def solve(entries, rhs):
        return linalg.solve(entries, rhs, pattern.indptr, pattern.indices)

    def matvec(data, v):
        return linalg.matvec(data, pattern.rows, pattern.indices, v)

    def nodal(v):
        return kernel.nodal_norm(v, pattern, n_nodes)

    def new_direction_at(x, f, e_stored, f_nc, s, mu):
        X = assemble.positions(x, scene, pattern)
        e = kernel.merit(e_stored, X, load + f_nc)
        data = kernel.tangent(x, s, 1.0, scene, pattern, model, solver.stiffness, step)
        work = jnp.sum((load + f_nc) * X)
        dx, slope, predicted, usable, roundoff, res_now = direction(f, data, springs, mu, e, work, solver, solve,
                                                                    matvec, nodal, jnp)
        return dx, slope, predicted, usable, e, roundoff, res_now, roundoff_floor(data, pattern.rows, pattern.indices, x)

    zero_free = jnp.zeros_like(x0)
    zero = jnp.zeros_like(load)
    # placeholders of the right types for the accepted iterate and its direction, filled by the first pass
    s0 = kernel.placeholders(
        jax.eval_shape(lambda: kernel.evaluate(x0, zero, load, 1.0, scene, pattern, model, step)[4]))
    f64 = jnp.asarray(0.0)
    carry0 = dict(
        x=x0, f=zero_free, force=zero, e_stored=f64, f_nc=zero, s=s0, mu=jnp.asarray(solver.damping),
        it=jnp.asarray(0), st=jnp.asarray(RUNNING), hist=jnp.full(solver.max_iter + 1, jnp.nan),
        dx=zero_free, slope=f64, predicted=f64, usable=jnp.asarray(False), e=f64, roundoff=f64, res_now=f64,
        floor=zero_free, k=jnp.asarray(0), alpha=jnp.asarray(1.0), started=jnp.asarray(False))

    def cond(c):
        return c["st"] == RUNNING

    def body(c):
        started, usable = c["started"], c["usable"]
        alpha = jnp.where(c["k"] == 0, 1.0, 0.5 * c["alpha"])
        # the start point first; an unusable direction is judged without a trial (its pass re-evaluates x)
        x_try = c["x"] + jnp.where(started & usable, alpha, 0.0) * c["dx"]
        e_try, force_try, nc_try, m_try, s_try = kernel.evaluate(x_try, jnp.where(started, c["f_nc"], zero), load,
                                                                 1.0, scene, pattern, model, step, c["s"])
        f_try = force_try.ravel()[free]
        done = usable & accepts(m_try, f_try, c["e"], alpha, c["slope"], c["roundoff"], c["res_now"], jnp)
        trials = jnp.where(usable, c["k"] + 1, 0)
        ends = ~started | done | ~usable | (trials >= solver.line_search)  # this pass ends an iteration
        accepted = ~started | done
        keep = lambda new, old: jnp.where(accepted, new, old)  # noqa: E731
        x, f, force = keep(x_try, c["x"]), keep(f_try, c["f"]), keep(force_try, c["force"])
        e_stored, f_nc = keep(e_try, c["e_stored"]), keep(nc_try, c["f_nc"])
        s = jax.tree.map(keep, s_try, c["s"])
        it = jnp.where(started & ends, c["it"] + 1, c["it"])
        res, st = status_of(it, f, jnp.where(started, jnp.where(done, m_try, c["e"]), e_try), c["floor"])
        mu = next_damping(c["mu"], done, trials, c["e"], m_try, c["predicted"],
                          res / jnp.maximum(c["hist"][c["it"]], 1e-300), solver, jnp)
        mu = jnp.where(started & ends, mu, c["mu"])
        st = jnp.where(started & (st == RUNNING) & ~done & (c["mu"] >= solver.max_damping), STALLED, st)
        st = jnp.where(ends, st, RUNNING)
        hist = jnp.where(ends, c["hist"].at[it].set(res), c["hist"])
        if solver.verbose:
            jax.lax.cond(started & ends, lambda: jax.debug.callback(
                progress, it, res, c["mu"], jnp.where(done, alpha, 0.0), ordered=False), lambda: None)

        def new_direction(_):
            return new_direction_at(x, f, e_stored, f_nc, s, mu)

        def same_direction(_):
            return c["dx"], c["slope"], c["predicted"], usable, c["e"], c["roundoff"], c["res_now"], c["floor"]

        dx, slope, predicted, usable_next, e, roundoff, res_now, floor = jax.lax.cond(
            ends & (st == RUNNING), new_direction, same_direction, None)
        return dict(x=x, f=f, force=force, e_stored=e_stored, f_nc=f_nc, s=s, mu=mu, it=it, st=st, hist=hist,
                    dx=dx, slope=slope, predicted=predicted, usable=usable_next, e=e, roundoff=roundoff,
                    res_now=res_now, floor=floor, k=jnp.where(ends, 0, trials), alpha=alpha, started=jnp.asarray(True))

    c = jax.lax.while_loop(cond, body, carry0)
    X = assemble.positions(c["x"], scene, pattern)
    nodal_f = kernel.nodal_norm(c["f"], pattern, n_nodes)
    return Equilibrium(
        x=X,
        force=c["force"],
        residual_N=jnp.max(nodal_f),
        iterations=c["it"],
        status=c["st"],
        worst_node=jnp.argmax(nodal_f),
        history=c["hist"],
        energy=kernel.merit(c["e_stored"], X, load + c["f_nc"]),
    )


#: :func:`newton_loop` compiled as a program of its own (``model`` and ``solver`` static): for callers
#: outside a trace (the tests lower it to see which terms a scene compiles)
newton_loop_jit = programs.jit(newton_loop, static_argnames=("model", "solver"))
