"""Static equilibrium by a primal-dual interior-point Newton on the tension form of the tension-only rods.

Why. A twine or a bar without compression stiffness stores (k/2) max(0, L - l0)² (L its length, l0 its rest
length, k = n EA / l0 its axial stiffness): convex in its twine vector, which is linear in the node positions
(book 4.3-4.7), but with a kink where it goes slack. Newton on that energy (:mod:`jaxnet.solve.newton`) meets two
barriers: rods that carry little and must turn (a step that turns a rod by θ stretches it by L θ²/2, which the
energy line search lets through only for θ below about 2 √(T / EA)), and the slack meshes of a hanging net, whose
energy is flat over every arrangement of them (a degenerate minimum, where Newton converges linearly). In still
water such a net is a second-order cone program, which interior-point methods solve in tens of iterations nearly
independently of its size (Lobo, Vandenberghe, Boyd and Lebret, Linear Algebra Appl. 284, 1998;
``validation/cone_reference.py`` solves it with Clarabel).

The tension form. Each rod r (the terms that declare :class:`jaxnet.terms.term.Rods`: the U and V twines of each
diamond triangle, each bar, where no compression stiffness is given) gets its tension T_r >= 0 and its gap
g_r >= 0 (how far it is from taut) as unknowns beside the free coordinates x, with

    F(x) - sum_r T_r grad L_r(x) = 0                 (balance: F the other terms' out-of-balance force),
    L_r(x) - l0_r - T_r / k_r + g_r = 0              (the rod's law: taut, T = k (L - l0); slack, the gap g),
    T_r g_r = mu                                     (complementarity, relaxed by the barrier parameter mu).

Newton's step eliminates dT_r and dg_r rod by rod: dT_r = c_r (grad L_r . dx + rho_r) with
c_r = k_r T_r / (T_r + k_r g_r) and rho_r = r_r + (target_r - T_r g_r) / T_r (r_r the law's residual), which
leaves on the nodes

    (K_F + sum_r [T_r hess L_r + c_r grad L_r grad L_r^T]) dx = F - sum_r T_r grad L_r - sum_r c_r rho_r grad L_r,

the tangent of today's Newton with each rod's axial stiffness k replaced by c (between k, taut, and 0, slack) and
its geometric stiffness taken at its tension T > 0: the same sparsity, the same factorisations (PARDISO, SuperLU,
cuDSS), no barrier Hessian. K_F is the other terms' tangent (drag, mesh opening, knots, bending, the catch, the sea
bed, weight at the surface, rods with a compression stiffness, a time step's inertia), assembled as today.

mu is driven by Mehrotra's predictor-corrector (SIAM J. Optim. 2, 1992): a predictor towards T g = 0 on the same
factorisation sets mu = (the mean T g it would leave / the mean now)³ x the mean now and gives the corrector its
second-order term dT dg. The primal unknowns (x, g) and the tensions T then step apart, each as far as its own
boundary T > 0 or g > 0 lets it (fraction to the boundary, :data:`BOUNDARY`; and the nodes no farther than
``Newton.max_step``, FEMNET's displacement limit); where the rod's law leaves its gap more room than the step
gives, the gap takes it (a slack reset: g = max(g, l0 + T / k - L)).

Globalisation, for what the cone program does not hold (drag, the catch, the sea bed: not convex, or not
conservative), and for nets that are mechanisms at their start (a flat panel in a current along it):

* a trial is accepted when its merit (:func:`merit`: the balance and the rods' laws, as forces) is no larger than
  the largest of the last :data:`MEMORY` iterates' (a non-monotone line search), else halved, at most
  ``Newton.line_search`` times; when no trial is accepted the iterate stays and the step is refused;
* the damped method's metric steadies the step where it comes out far too long: (K + lambda S) with S the spring
  network (:mod:`jaxnet.solve.spring_network`), lambda a fictitious prestrain, zero at the start, raised after a
  refused or cut step and lowered after a full one (:data:`LOWER`, :data:`RAISE`, :data:`REFUSED`, :data:`SHORT`);
* the method has at most :data:`BUDGET` iterations: a net it has not solved by then is solved by the damped
  method from the start (:func:`jaxnet.solve.statics.host_loop`), which is how every net the damped method
  solves is still solved, to its answer.

Convergence is judged as the damped method judges it: on the out-of-balance force of the net itself, the rods'
tensions taken from their lengths, k max(0, L - l0), at every node below ``Newton.tol`` (or the roundoff floor of
that node, :func:`jaxnet.solve.newton.roundoff_floor`). So where both methods converge they answer the same
equations; where the equilibria form a flat set (slack meshes free to lie anywhere in a range) they may land at
different points of it, both balanced.

The iteration starts with T_r = max(k_r (L_r - l0_r), T_s) and g_r = max(l0_r - L_r, l0_r / 100), T_s the largest
out-of-balance force at the start (N): every rod strictly inside, taut ones near their tension.

Where it is used. ``Newton(method="primal-dual")``, the static solve's default (:data:`jaxnet.solve.options.STATIC`),
but not for FEMNET's cases, whose reader asks for the damped method (:mod:`jaxnet.io.femnet.mapping` says why);
an implicit time step keeps the damped method (:data:`jaxnet.solve.options.TIME_STEP`: a step starts next to its
answer, where the damped method takes a few iterations and an interior method, which must centre its tensions
again, several times more; docs/investigations.md measures both), as does the jittable iteration
(:func:`jaxnet.solve.newton.newton_loop`). The gradients of an equilibrium (:mod:`jaxnet.solve.implicit`,
:mod:`jaxnet.solve.adjoint_statics`) are taken at the converged point, whichever method found it.

Units: m, N, J, N/m.
"""

from __future__ import annotations

import concurrent.futures
import time

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import linalg
from jaxnet.model import assemble
from jaxnet.solve import kernel, newton, programs
from jaxnet.solve.options import Newton
from jaxnet.solve.results import CONVERGED, MAX_ITERATIONS, NON_FINITE, RUNNING, STALLED, Equilibrium, Timing

#: the fraction of the way to the boundary T = 0 or g = 0 a step may go
BOUNDARY = 0.995
#: a trial step is accepted when its merit is at most the largest of the last MEMORY iterates' (a non-monotone
#: line search: Grippo, Lampariello and Lucidi, SIAM J. Numer. Anal. 23, 1986): the path of an interior method is
#: not monotone in the balance, and a monotone search stalls on slack nets in a current
MEMORY = 5
#: the Levenberg-Marquardt damping's factors: divided by LOWER after a full step, multiplied by RAISE after a step
#: the merit cut or the boundary cut below SHORT (a direction far too long: a near-mechanism), by REFUSED when no
#: trial is accepted (the iterate is kept and the tangent refactorised)
LOWER, RAISE, REFUSED, SHORT = 3.0, 2.0, 10.0, 0.1
#: the damping a refusal raises from when it is below it (dimensionless prestrain)
REFUSED_FROM = 1e-9
#: the method stops (MAX_ITERATIONS) after BUDGET iterations, or SHARE x ``max_iter`` if fewer: the damped method
#: then solves the net from the start (:func:`jaxnet.solve.statics.host_loop`). On the robustness set
#: (``validation/robustness.py``), run without a budget, the method converged within 100 iterations in 4 cases of 5
#: where it converged at all (validation/REPORT.md): a net it has not solved by then is better left to the damped
#: method
BUDGET, SHARE = 100, 0.5


def suits(model) -> bool:
    """Whether the primal-dual method solves a net of these active terms: one with tension-only rods
    (:func:`split`) and without a catch (a force term with a global state, the catch front, other than the drag's,
    which only reads where a catch's front is). The catch's pressure gives a cod-end more than one balanced shape
    (one turned inside out balances too); the method's merit, the out-of-balance force, does not tell a stable one
    from an unstable one, and on jaxnet's small cod-ends it converged to the inverted one where the damped method,
    which descends the energy, finds the cod-end filled (docs/investigations.md); a net with a catch is left to the
    damped method."""
    rods, rest = split(model)
    return bool(rods) and not any(t.term.kind == "force" and t.term.state is not None and not t.term.moving
                                  for t in rest)


def split(model):
    """(rods, rest): the active terms that are sums of tension-only rods (:meth:`jaxnet.model.ActiveTerm.has_rods`)
    and all the others, in model order."""
    rods = tuple(t for t in model if t.has_rods())
    return rods, tuple(t for t in model if t not in rods)


# -- the rods, vmapped over their families (pure, jittable; ``rods`` the rod terms, static) ----------------


def _rod_rows(rods, scene):
    """Per rod term: (term, family rows, connectivity)."""
    return [(t, getattr(scene, t.term.family), assemble.connectivity(scene, t.term.family)) for t in rods]


def lengths(X, scene, rods):
    """(L, l0, k): each rod's length (m), rest length (m) and axial stiffness (N/m) at positions X (N, 3), (m,)
    each, the rod terms in order, each term's elements in order, each element's rods in order."""
    env = scene.environment
    out = [jax.vmap(lambda xe, p, t=t: t.rods(xe, p, env))(X[conn], rows) for t, rows, conn in _rod_rows(rods, scene)]
    return tuple(jnp.concatenate([o[i].reshape(-1) for o in out]) for i in range(3))


def measure(x, T, scene, pattern, rods):
    """At free coordinates x (m) with rod tensions T (m,) (N): (L, l0, k, pull, pull_true, energy): the rods'
    lengths, rest lengths and stiffnesses; the nodal forces (N, 3) (N) the tensions T exert, sum_r T_r grad L_r, and
    those the rods' own tensions k max(0, L - l0) exert (the net's, which convergence is judged on); the rods' own
    elastic energy (J)."""
    X = assemble.positions(x, scene, pattern)
    L, l0, k = lengths(X, scene, rods)
    own = k * jnp.maximum(L - l0, 0.0)

    def weighted(X, w):
        return jnp.sum(w * lengths(X, scene, rods)[0])

    pull = jax.grad(weighted)(X, T)
    pull_true = jax.grad(weighted)(X, own)
    return L, l0, k, pull, pull_true, 0.5 * jnp.sum(k * jnp.maximum(L - l0, 0.0) ** 2)


def pull(x, w, scene, pattern, rods):
    """(N, 3) the nodal forces sum_r w_r grad L_r (N) of rod weights w (m,) (N) at free coordinates x."""
    X = assemble.positions(x, scene, pattern)
    return jax.grad(lambda X: jnp.sum(w * lengths(X, scene, rods)[0]))(X)


def stretch_rate(x, dx, scene, pattern, rods):
    """(m,) grad L_r . dx: each rod's change of length (m) along the free-coordinate step dx (m), at x."""
    full = lambda v: lengths(assemble.positions(v, scene, pattern), scene, rods)[0]  # noqa: E731
    return jax.jvp(full, (x,), (dx,))[1]


def blocks(x, T, c, scene, pattern, rods):
    """{family: (E, 3k, 3k)} the rods' element matrices (N/m) in the eliminated Newton system:
    sum_r T_r hess L_r + c_r grad L_r grad L_r^T over each element's rods (T (m,) tensions, N; c (m,) effective
    axial stiffnesses, N/m)."""
    X = assemble.positions(x, scene, pattern)
    env = scene.environment
    out, start = {}, 0
    for t, rows, conn in _rod_rows(rods, scene):
        n_elements, k = conn.shape
        first_row = jax.tree.map(lambda a: a[0], rows)
        r = jax.eval_shape(lambda xe, p, t=t: t.rods(xe, p, env)[0], X[conn][0], first_row).shape[0]
        size = n_elements * r
        Te, ce = T[start:start + size].reshape(n_elements, r), c[start:start + size].reshape(n_elements, r)
        start += size

        def element(xe, p, Te, ce, t=t, k=k):
            flat = lambda v: t.rods(v.reshape(k, 3), p, env)[0]  # noqa: E731
            G = jax.jacfwd(flat)(xe.ravel())                      # (r, 3k)
            H = jax.hessian(flat)(xe.ravel())                     # (r, 3k, 3k)
            return jnp.einsum("r,rab->ab", Te, H) + jnp.einsum("r,ra,rb->ab", ce, G, G)

        block = jax.vmap(element)(X[conn], rows, Te, ce)
        family = t.term.family
        out[family] = out[family] + block if family in out else block
    return out


_measure_jit = programs.jit(measure, static_argnames=("rods",))
_pull_jit = programs.jit(pull, static_argnames=("rods",))
_rate_jit = programs.jit(stretch_rate, static_argnames=("rods",))
_blocks_jit = programs.jit(blocks, static_argnames=("rods",))
_scatter_jit = programs.jit(assemble.scatter_stiffnesses)
_springs_jit = programs.jit(kernel.springs, static_argnames=("model",))


def count(scene, rods):
    """The number of rods of ``scene`` (their tension and gap unknowns)."""
    X = jax.ShapeDtypeStruct(scene.nodes.position.shape, jnp.float64)
    return int(jax.eval_shape(lambda X: lengths(X, scene, rods)[0], X).shape[0])


def compile_pieces(start, scene, pattern, model, stiffness="closed_form", step=None):
    """The programs of :func:`host_loop`: the other terms' (:func:`jaxnet.solve.statics.damped_pieces` of the
    model less its rods), the rods' (measure, pull, stretch rate, element matrices and their sum into the pattern)
    and the spring network of the whole model (the damping's metric, as an array under "metric"), from memory,
    disk or compiled (:mod:`jaxnet.solve.programs`)."""
    from jaxnet.solve import statics  # the other terms' programs are the damped Newton's own

    rods, rest = split(model)
    m = count(scene, rods)
    vector = np.zeros(m)
    static = {"rods": rods}
    jobs = {"rod_measure": (_measure_jit, (start, vector, scene, pattern), static),
            "rod_pull": (_pull_jit, (start, vector, scene, pattern), static),
            "rod_rate": (_rate_jit, (start, start, scene, pattern), static),
            "rod_blocks": (_blocks_jit, (start, vector, vector, scene, pattern), static),
            "metric": (_springs_jit, (scene, pattern), {"model": model})}
    # the rods' programs compile in threads while the other terms' are traced and compiled (XLA's compilation
    # releases the GIL)
    with concurrent.futures.ThreadPoolExecutor(len(jobs)) as pool:
        futures = {name: pool.submit(programs.obtain, name if name != "metric" else "springs", *job)
                   for name, job in jobs.items()}
        pieces = statics.damped_pieces(start, scene, pattern, rest, stiffness, step)
        pieces.update({name: future.result() for name, future in futures.items()})
    placeholder = jax.tree.map(lambda b: np.zeros(b.shape, b.dtype), pieces["rod_blocks"].out_info)
    pieces["rod_scatter"] = programs.obtain("scatter", _scatter_jit, (placeholder, pattern))
    pieces["metric"] = np.asarray(pieces["metric"](scene, pattern))
    pieces["rods"] = m
    return pieces


#: what the columns of the verbose lines mean, printed once above them
LEGEND = ("  (primal-dual: one line per Newton iteration. residual: the largest out-of-balance force on a node (N), "
          "converged below tol; damping: the fictitious prestrain that steadies a step where the net is a "
          "mechanism; step: the fraction of the step taken, 0 when refused; mean T g: the rods' complementarity, "
          "driven to 0)")


def merit(R, law):
    """The merit (N²) of an iterate: its squared out-of-balance force R (N, free coordinates) plus its rods' laws
    measured as forces, k (L - l0 - T / k + g) (N)."""
    return float(R @ R + law @ law)


def to_boundary(value, change):
    """The largest a in (0, 1] with value + a change >= 0 (value > 0), over every entry."""
    shrinking = change < 0.0
    if not shrinking.any():
        return 1.0
    return min(1.0, float(np.min(-value[shrinking] / change[shrinking])))


def host_loop(start, scene, pattern, model, solver: Newton, pieces=None, step=None):
    """The primal-dual iteration of the module docstring from free coordinates ``start`` (m), driven from the
    host: each iteration assembles the tangent once, factorises it once and solves twice (predictor and
    corrector). Same arguments and result as :func:`jaxnet.solve.statics.host_loop` (``step``: an implicit time
    step's past and masses, whose inertia joins the other terms); the stiffness continuation of the damped
    Newton has no part here."""
    from jaxnet.solve import statics  # the host loops' shared parts (statics imports this module)

    t_start = time.perf_counter()
    rods, rest = split(model)
    if pieces is None or "rod_measure" not in pieces:
        pieces = compile_pieces(np.asarray(start, dtype=float), scene, pattern, model, solver.stiffness, step)
    evaluate, tangent, scatter = pieces["evaluate"], pieces["tangent"], pieces["scatter"]
    n_nodes = scene.n_nodes
    free = np.asarray(pattern.free)
    indptr, indices = np.asarray(pattern.indptr), np.asarray(pattern.indices)
    factor = linalg.direct_solver(indptr, indices)
    spent = dict(assembly_s=0.0, factorisation_s=0.0, evaluation_s=0.0, factorisations=0, evaluations=0)
    on_host = any(isinstance(leaf, np.ndarray) for leaf in jax.tree.leaves((scene, pattern)))
    scene_d, pattern_d = jax.device_put((scene, pattern)) if on_host else (scene, pattern)
    load_device, inertia, diagonal = statics.step_loads(pieces["loads"](scene_d), pattern, step)
    load = np.asarray(load_device)
    host = statics.FreeCoordinates(scene, pattern)
    nodal, positions = host.nodal, host.positions

    def run(x, T, previous):
        """Everything at (x, T): the other terms' evaluation and the rods' measure."""
        t = time.perf_counter()
        e, force, f_nc, _, state = evaluate(x, np.zeros_like(load), load_device, 1.0, scene_d, pattern_d, previous,
                                            step)
        measured = pieces["rod_measure"](x, T, scene_d, pattern_d)
        (e, force, f_nc), (L, l0, k, pull_T, pull_own, e_rods) = jax.device_get(((e, force, f_nc), measured))
        spent["evaluation_s"] += time.perf_counter() - t
        spent["evaluations"] += 1
        return dict(e=float(e) + float(e_rods), force=force, f_nc=f_nc, state=state, L=L, l0=l0, k=k,
                    R=(force - pull_T).ravel()[free], own=(force - pull_own))

    x = np.asarray(start, dtype=float)
    unknown = pieces.get("states")
    at = run(x, np.zeros(pieces["rods"]), unknown)
    L, l0, k = at["L"], at["l0"], at["k"]
    scale_T = max(float(np.max(np.abs(at["own"].ravel()[free]), initial=0.0)), solver.tol)
    T = np.maximum(k * (L - l0), scale_T)
    g = np.maximum(l0 - L, 0.01 * l0)
    at = run(x, T, unknown)
    if solver.verbose:
        print(LEGEND)
    hist = np.full(solver.max_iter + 1, np.nan)
    it, st = 0, RUNNING
    lam = solver.min_damping  # none to start with: raised where steps come out short or are refused
    springs = pieces["metric"]
    merits = [merit(at["R"], k * (at["L"] - l0 - T / k + g))]
    floor = np.zeros(n_nodes)
    while True:
        own_free = at["own"].ravel()[free]
        nodal_own = nodal(own_free)
        res = nodal_own.max(initial=0.0)
        hist[it] = res
        law = at["L"] - l0 - T / k + g
        gap = float(np.mean(T * g))
        if solver.verbose and it > 0:
            print(f"  newton {it:4d}  residual {res:11.4e} N  damping {lam:8.1e}  step {alpha if accepted else 0.0:6.3f}"
                  f"  mean T g {gap:8.1e} N m")
        if not (np.isfinite(res) and np.isfinite(at["e"]) and np.all(np.isfinite(T)) and np.all(np.isfinite(g))):
            st = NON_FINITE
        elif np.max(nodal_own - np.maximum(solver.tol, floor), initial=-1.0) <= 0.0:
            st = CONVERGED
        elif it >= min(BUDGET, max(SHARE * solver.max_iter, 1)):
            st = MAX_ITERATIONS
        if st != RUNNING:
            break
        c = k * T / (T + k * g)
        t = time.perf_counter()
        rest_blocks = tangent(x, at["state"], 1.0, scene_d, pattern_d, step)
        rod_blocks = pieces["rod_blocks"](x, T, c, scene_d, pattern_d)
        data = np.asarray(scatter(rest_blocks, pattern_d)) + np.asarray(pieces["rod_scatter"](rod_blocks, pattern_d))
        if inertia is not None:
            data[diagonal] += inertia
        spent["assembly_s"] += time.perf_counter() - t
        floor = nodal(newton.ROUNDOFF_FACTOR * np.finfo(float).eps * linalg.host_matvec(np.abs(data), indptr, indices,
                                                                                          np.abs(x)))
        t = time.perf_counter()
        ok = factor.factorize(data + lam * springs)
        spent["factorisation_s"] += time.perf_counter() - t
        spent["factorisations"] += 1
        if not ok:
            st = NON_FINITE
            break
        R = at["R"]

        def direction(target):
            """(dx, dT, dg) of the Newton step towards T g = target (per rod, N m)."""
            rho = law + (target - T * g) / T
            rhs = R - np.asarray(pieces["rod_pull"](x, c * rho, scene_d, pattern_d)).ravel()[free]
            t = time.perf_counter()
            dx = factor.apply(rhs)
            spent["factorisation_s"] += time.perf_counter() - t
            dT = c * (np.asarray(pieces["rod_rate"](x, dx, scene_d, pattern_d)) + rho)
            return dx, dT, (target - T * g - g * dT) / T

        dx_a, dT_a, dg_a = direction(np.zeros_like(T))
        a = min(to_boundary(T, dT_a), to_boundary(g, dg_a))
        centring = (float(np.mean((T + a * dT_a) * (g + a * dg_a))) / gap) ** 3
        target = centring * gap - dT_a * dg_a
        dx, dT, dg = direction(target)
        if not factor.ok:
            st = NON_FINITE
            break
        # the primal unknowns (x, g) and the tensions T step apart, each as far as its own boundary lets it
        biggest = float(np.max(nodal(dx), initial=0.0))
        alpha = min(1.0, BOUNDARY * to_boundary(g, dg), solver.max_step / max(biggest, 1e-300))
        beta = min(1.0, BOUNDARY * to_boundary(T, dT))
        reference = max(merits[-MEMORY:])
        trials, accepted = 0, False
        while trials <= solver.line_search:
            x_try, T_try = x + alpha * dx, T + beta * dT
            trial = run(x_try, T_try, at["state"])
            # where the rod's law leaves its gap more room than the step gives, the gap takes it (a slack reset)
            g_try = np.maximum(g + alpha * dg, l0 + T_try / k - trial["L"])
            trials += 1
            after = merit(trial["R"], k * (trial["L"] - l0 - T_try / k + g_try))
            if np.isfinite(after) and after <= reference:
                accepted = True
                break
            alpha, beta = 0.5 * alpha, 0.5 * beta
        if not accepted:
            lam = min(REFUSED * max(lam, REFUSED_FROM), solver.max_damping)
            it += 1
            if lam >= solver.max_damping:
                st = STALLED
                break
            continue
        # a full step lowers the damping; a step cut by the merit, or one the boundary cut short because the
        # direction was far too long (a near-mechanism), raises it
        lam = max(lam / LOWER if trials == 1 and alpha >= SHORT else lam * RAISE, solver.min_damping)
        merits.append(after)
        x, T, g, at = x_try, T_try, g_try, trial
        it += 1
    X = positions(x)
    nodal_f = nodal(at["own"].ravel()[free])
    return Equilibrium(
        **jax.device_put(dict(x=X, force=at["own"], residual_N=nodal_f.max(initial=0.0), iterations=np.int64(it),
                              status=np.int64(st), worst_node=np.int64(np.argmax(nodal_f)), history=hist,
                              energy=np.float64(at["e"] - float(np.sum((load + at["f_nc"]) * X))))),
        timing=Timing(compile_s=0.0, wall_s=time.perf_counter() - t_start, fallbacks=int(factor.fallbacks), **spent),
    )
