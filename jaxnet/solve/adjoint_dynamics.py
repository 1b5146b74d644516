"""Gradients through the implicit dynamics: the derivative of a time-integrated figure (the mean or the peak
of a mooring force over a wave period, the volume a cage keeps) with respect to the design.

The run. The book's scheme (:mod:`jaxnet.solve.dynamics`, eqs 4.265-4.271) at a *fixed* step h: from
(x_n, v_n) at t_n, the positions x_{n+1} at t_{n+1} = t_0 + (n + 1) h are the root of the step's
out-of-balance force (the static one at t_{n+1}, the drag on the velocity (x - x_n)/h relative to the
water, the inertia -(M + M_a)(x - x_n - h v_n)/h², the water's inertia (M_a + ρV) γ_h), and
v_{n+1} = (x_{n+1} - x_n)/h. Each step is :func:`jaxnet.solve.implicit.equilibrium` with the step's
:class:`~jaxnet.solve.dynamics.TimeStep`, so its derivative is that of the root by the implicit function
theorem: one sparse solve with the step's tangent K_n per direction in forward mode, one with K_n^T per
step in reverse mode (the adjoint recurrence runs backwards over the steps), never an unrolled Newton
iteration. The masses M + M_a and M_a + ρV are :func:`lumped_masses` (in JAX: differentiable in the twine
diameter, the mesh side, a sinker's mass, ...).

Why a fixed step, and no retries. :func:`jaxnet.solve.dynamics.simulate` halves a step whose Newton fails
and grows it back; the accepted steps then depend on the design discontinuously (a design a hair away can
take another sequence of steps), and the figure with them: no derivative. Here every design takes the same
n steps, the figure is a smooth function of the design, and a step whose Newton does not converge *raises*
(``implicit.equilibrium``'s ``throw``: :class:`~jaxnet.solve.implicit.ImplicitError` outside a trace, an
equinox runtime error inside one) instead of being retried: choose h where :func:`~jaxnet.solve.dynamics.simulate`
takes no retries (its ``Trajectory.state.retries``), and a ``solver`` with enough iterations. The forward
run equals ``simulate`` at the same step (tested, 1e-8 m), apart from the Newton tolerance: the derivative
is only as good as each root, so the default is :data:`jaxnet.solve.options.DIFFERENTIABLE`, not the
dynamics' :data:`jaxnet.solve.options.TIME_STEP`.

Memory: checkpointing. Reverse mode needs, for step n, what its adjoint solve and the transposed
linearisation of its residual need (x_n, v_n, the tangent's entries, the elements' intermediate values):
kept for every step, that grows as n. The steps run as a ``lax.scan`` over *segments* of ``segment`` steps
(default ⌈√n⌉), each segment an inner ``lax.scan`` under ``jax.checkpoint``: the forward pass stores only
the state (x, v) at each segment's start, and the reverse pass re-runs one segment at a time (its Newton
solves again) to rebuild that segment's per-step values. Memory is then ⌈n/segment⌉ states plus one
segment's per-step values, O(√n) at the default (plus the figure's own (n, ...) series, a scalar per
step for :func:`integrate`), for two Newton solves per step instead of one. XLA's memory analysis of the
compiled ``jax.grad`` of the mean mooring force (temporary bytes, on a small hanging panel and on a
two-node spring) shows it: each 4× the steps doubles the checkpointed run's growth, and quadruples the
plain scan's. ``segment=n_steps`` gives the plain scan (one Newton solve
per step; memory O(n)). Each step's adjoint solve factorises that step's K_n^T once (on the host).

Figures. A per-step figure is a function of an :class:`Instant` (the net at the end of one step: time,
positions, velocities, out-of-balance force, the scene at that time, the step that led there) returning
any pytree of arrays:
:func:`reactions`, :func:`mooring_force` (the resultant of the reactions at fixed nodes: minus the
out-of-balance force there, the inertia of the step included), :func:`drag` (by the groups of
:func:`jaxnet.terms.term.drag_groups`), :func:`enclosed_volume`. :func:`series` gives the figure at
every step (n, ...); :func:`integrate` reduces it to a scalar with :func:`mean` or :func:`smooth_peak`
(log-sum-exp: a differentiable maximum, within a stated bound of the true one).

A design study (checked by hand on ``scenes.panel.hanging_panel(meshes=4)`` in a current ramp: the
gradients agreed with fourth-order differences of the whole run to 5e-10 and 1e-8)::

    space = DesignSpace(net)
    reference = space.scene(space.initial())
    structure = implicit.structure_of(reference, dynamic=True)
    x_rest = implicit.solve(reference).x            # start at rest at the static equilibrium

    def peak_pull(d, ratio):                        # twine diameter (m), hanging ratio of the sinker bar
        theta = {"twine_diameter": {"netting": d}, "hanging_ratio": {"sinker bar": ratio}}
        return integrate(mooring_force, space.scene(theta), structure, loading, time_step=0.05, n_steps=10,
                         x0=x_rest, reduce=functools.partial(smooth_peak, width=0.01))

    value, gradient = programs.jit(jax.value_and_grad(peak_pull, argnums=(0, 1)))(d, ratio)

Units: m, s, kg, N.
"""

from __future__ import annotations

import math
from typing import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import model as model_lib
from jaxnet.model import assemble, catch as catch_lib
from jaxnet.solve import dynamics, implicit, kernel, masses as masses_lib
from jaxnet.solve.options import Implicit, Newton
from jaxnet.terms import term as term_lib

__all__ = ["Instant", "lumped_masses", "step_force", "implicit_step", "series", "trajectory", "integrate", "mean",
           "smooth_peak", "reactions", "mooring_force", "drag", "enclosed_volume"]


# -- masses --------------------------------------------------------------------------------------------


def lumped_masses(scene):
    """Per node and axis, (M + M_a, M_a + ρV) in kg, (N, 3) each: :func:`jaxnet.solve.masses.lumped_masses`
    in JAX, so that the inertia follows a design (twine diameter, mesh side, twine coordinates, a sinker's
    mass and volume, the water density)."""
    return masses_lib.lumped_masses(scene, jnp)


# -- one step ------------------------------------------------------------------------------------------


class Instant(eqx.Module):
    """The net at the end of one implicit step: what a per-step figure reads (pytree; traced in a run).

    t: the time (s). x, v: (N, 3) positions (m) and velocities (m/s). force: (N, 3) the step's out-of-balance
    force (N) at x: zero at the free coordinates (to the solve's tolerance), minus the reactions at the
    fixed ones (:func:`step_force`; computed once per step for all the figures that read it, and dropped
    from the compiled program when none does). scene: the scene at t (:func:`jaxnet.solve.dynamics.scene_at`:
    the current's speed and the prescribed nodes' positions at t). step: the
    :class:`~jaxnet.solve.dynamics.TimeStep` that led here (x_n, v_n, h, masses, the water's load).
    structure: the dynamic :class:`~jaxnet.solve.implicit.Structure`.
    """

    t: jax.Array
    x: jax.Array
    v: jax.Array
    force: jax.Array
    scene: object
    step: dynamics.TimeStep
    structure: implicit.Structure


def step_force(x, scene_t, structure, step):
    """(N, 3) the out-of-balance force (N) of an implicit step at positions x (m), fixed coordinates included:
    the Newton iteration's own evaluation (``dynamics.State.force``): the loads, the water's inertia, minus
    the gradient of the stored and inertia energies, plus the drag on the velocities relative to the water.
    At fixed coordinates it is minus the reactions, the inertia of the held nodes included."""
    pattern = structure.pattern
    return kernel.force(x.ravel()[pattern.free], scene_t, pattern, structure.model, step)


def _moving_water(scene, loading):
    return scene.environment.waves is not None or loading.current_speed is not None


def implicit_step(x, v, t_new, time_step, scene, structure, loading, masses,
                  solver: Newton | None = None) -> Instant:
    """One step of the book's scheme from (x, v) (N, 3) (m, m/s) to time ``t_new`` (s) with step
    ``time_step`` h (s), differentiable in everything (the root by the implicit function theorem).

    The same step as :func:`jaxnet.solve.dynamics.advance`'s: Newton from the constant-velocity prediction
    x + h v, the water's acceleration at x and t_new. ``masses``: :func:`lumped_masses` of ``scene``;
    ``structure``: dynamic (``implicit.structure_of(scene, dynamic=True)``). Raises (or, traced, errors at
    run time) when Newton does not converge: no retry. ``solver``: the step's Newton options (default
    :data:`jaxnet.solve.options.DIFFERENTIABLE`). Returns the :class:`Instant` at t_new."""
    loading = loading or dynamics.Loading()
    mass, water_mass = masses
    scene_t = dynamics.scene_at(scene, loading, t_new, surface_at=x)
    if _moving_water(scene, loading):
        waves = scene.environment.waves is not None
        load = water_mass * dynamics.water_acceleration(x, scene_t, loading, waves)
    else:
        load = jnp.zeros_like(x)
    step = dynamics.TimeStep(x, v, time_step, mass, load)
    x_new = implicit.equilibrium(scene_t, structure, x0=x + time_step * v, solver=solver, step=step).x
    return Instant(t=t_new, x=x_new, v=(x_new - x) / time_step, force=step_force(x_new, scene_t, structure, step),
                   scene=scene_t, step=step, structure=structure)


# -- the run ---------------------------------------------------------------------------------------------


def _is_concrete(tree):
    return not any(isinstance(leaf, jax.core.Tracer) for leaf in jax.tree_util.tree_leaves(tree))


def _check(scene, structure, loading, time_step, n_steps, segment, x0, v0, start_time):
    """ValueError naming the culprit, before anything is traced (the values that are concrete)."""
    if isinstance(n_steps, bool) or not isinstance(n_steps, (int, np.integer)) or n_steps < 1:
        raise ValueError(f"n_steps must be an int >= 1, got {n_steps!r}")
    if segment is not None and (isinstance(segment, bool) or not isinstance(segment, (int, np.integer))
                                or segment < 1):
        raise ValueError(f"segment must be None or an int >= 1, got {segment!r}")
    for name, value, positive in (("time_step", time_step, True), ("start_time", start_time, False)):
        if _is_concrete(value):
            a = np.asarray(value, dtype=float)
            if a.shape != () or not np.isfinite(a) or (positive and not a > 0):
                raise ValueError(f"{name} must be a finite scalar{' > 0' if positive else ''} (s), got {value!r}")
    if not isinstance(structure, implicit.Structure):
        raise ValueError(f"structure must be a jaxnet.solve.implicit.Structure, got {type(structure).__name__}")
    if any(t.term.moving and not t.kwargs().get("moving") for t in structure.model):
        raise ValueError("structure is a static one (its drag does not see the velocities): build it with "
                         "implicit.structure_of(scene, dynamic=True)")
    shape = tuple(np.shape(scene.nodes.position))
    for name, value in (("x0", x0), ("v0", v0)):
        if value is not None and tuple(np.shape(value)) != shape:
            raise ValueError(f"{name} must have the shape of the scene's positions {shape}, got {np.shape(value)}")
    if loading.winches:
        raise ValueError("winches (Loading.winches) are not differentiated here: its masses are the start's, where a "
                         "winch's cable changes length; run them with dynamics.simulate")
    if _is_concrete((scene.nodes.fixed, [motion.nodes for motion in loading.motions])):
        dynamics.check_loading(scene, loading)
    if _is_concrete(scene):
        # a structure may hold more terms than this design needs (a family's reference), never fewer
        missing = [t.name for t in model_lib.active_terms(scene, dynamic=True) if t not in structure.model]
        if missing:
            raise ValueError(f"structure lacks the dynamic terms {missing} of this scene: build it with "
                             "implicit.structure_of(reference, dynamic=True)")


def _run(figure, scene, structure, loading, time_step, n_steps, x0, v0, start_time, solver, segment):
    """(x, v) at the end and the figure at every step (n_steps, ...), by checkpointed segments."""
    loading = loading or dynamics.Loading()
    _check(scene, structure, loading, time_step, n_steps, segment, x0, v0, start_time)
    segment = min(segment or math.isqrt(n_steps - 1) + 1, n_steps)  # ⌈√n⌉
    segments = -(-n_steps // segment)
    h = jnp.asarray(time_step, dtype=float)
    t0 = jnp.asarray(start_time, dtype=float)
    x = jnp.asarray(dynamics.scene_at(scene, loading, t0).nodes.position if x0 is None else x0, dtype=float)
    v = jnp.zeros_like(x) if v0 is None else jnp.asarray(v0, dtype=float)
    masses = lumped_masses(scene)

    def advance(carry, k):
        x, v = carry
        # t_k from the step's index, not accumulated: the same times as simulate's records k h
        now = implicit_step(x, v, t0 + (k + 1) * h, h, scene, structure, loading, masses, solver)
        return (now.x, now.v), figure(now)

    if segments * segment != n_steps:
        # a last, partial segment: its surplus steps are skipped (one traced step either way; the index
        # is not batched, so under vmap this stays a branch and the surplus steps never run)
        shapes = jax.eval_shape(advance, (x, v), jnp.asarray(0))[1]
        full = advance

        def advance(carry, k):
            return jax.lax.cond(k < n_steps, full, lambda c, _: (c, jax.tree.map(
                lambda s: jnp.zeros(s.shape, s.dtype), shapes)), carry, k)

    @jax.checkpoint
    def run_segment(carry, first):
        return jax.lax.scan(advance, carry, first + jnp.arange(segment))

    (x, v), values = jax.lax.scan(run_segment, (x, v), segment * jnp.arange(segments))
    values = jax.tree.map(lambda a: a.reshape((segments * segment,) + a.shape[2:])[:n_steps], values)
    return x, v, values


def series(figure: Callable, scene, structure, loading=None, time_step=Implicit.time_step, n_steps=100, x0=None,
           v0=None, start_time=0.0, solver: Newton | None = None, segment: int | None = None):
    """The per-step figure over a run of ``n_steps`` fixed steps, differentiable (jax.grad, jacfwd, jit, vmap)
    with respect to every float leaf of ``scene``, ``loading``, ``x0``, ``v0`` and ``time_step``.

    Args:
      figure: Instant -> pytree of arrays (e.g. :func:`mooring_force`), evaluated at the end of every step.
      scene: a :class:`jaxnet.scene.Scene` (traced or not, e.g. ``DesignSpace.scene(theta)``).
      structure: ``implicit.structure_of(reference, dynamic=True)`` of a scene of the same shapes.
      loading: :class:`jaxnet.solve.dynamics.Loading` (the current's history, prescribed motions).
      time_step: h (s), fixed (no retries: see the module docstring). n_steps: the number of steps (static).
      x0, v0: (N, 3) positions (m) and velocities (m/s) at ``start_time`` (s); default the scene's
        positions there (prescribed nodes moved), at rest.
      solver: each step's Newton options; default :data:`jaxnet.solve.options.DIFFERENTIABLE`.
      segment: steps per checkpointed segment (default ⌈√n_steps⌉; ``n_steps``: no checkpointing).
    Returns:
      the figure's pytree, each leaf stacked over the steps (n_steps, ...): the values at
      t_k = start_time + k h, k = 1 .. n_steps.
    """
    return _run(figure, scene, structure, loading, time_step, n_steps, x0, v0, start_time, solver, segment)[2]


def trajectory(scene, structure, loading=None, time_step=Implicit.time_step, n_steps=100, x0=None, v0=None,
               start_time=0.0, solver: Newton | None = None, segment: int | None = None):
    """(xs, vs): positions (m) and velocities (m/s) (n_steps + 1, N, 3) at t_k = start_time + k h, k = 0 ..
    n_steps, the start included; arguments as :func:`series`. For looking at and for short runs: a figure
    of the whole history keeps every state in reverse mode, where :func:`series` of a scalar figure does not."""
    loading = loading or dynamics.Loading()
    x, v, (xs, vs) = _run(lambda now: (now.x, now.v), scene, structure, loading, time_step, n_steps, x0, v0,
                          start_time, solver, segment)
    first_x = jnp.asarray(dynamics.scene_at(scene, loading, jnp.asarray(start_time, dtype=float)).nodes.position
                          if x0 is None else x0, dtype=float)
    first_v = jnp.zeros_like(first_x) if v0 is None else jnp.asarray(v0, dtype=float)
    return jnp.concatenate([first_x[None], xs]), jnp.concatenate([first_v[None], vs])


def mean(values):
    """The mean over the steps (axis 0) of a per-step series: its time average over the run (the right-
    rectangle rule on the steps' ends: ∫ f dt / (n h) to first order, the scheme's own order)."""
    return jnp.mean(values, axis=0)


def smooth_peak(values, width):
    """A differentiable maximum over the steps (axis 0): width × log Σ_k exp(f_k / width) (log-sum-exp).

    Bound: max_k f_k <= smooth_peak <= max_k f_k + width × ln(n_steps), the upper bound reached when all
    the steps are equal, the lower approached when one step stands more than a few widths above the rest.
    ``width`` (the figure's unit, e.g. N) trades smoothness for tightness: small, the gradient is that of
    the largest step alone (and jumps between steps as the design moves); large, several steps near the
    peak share it. Its gradient weights each step's by softmax(f / width)."""
    if _is_concrete(width) and not (np.ndim(width) == 0 and np.isfinite(width) and width > 0):
        raise ValueError(f"smooth_peak: width must be a finite scalar > 0 (the figure's unit), got {width!r}")
    return width * jax.nn.logsumexp(jnp.asarray(values) / width, axis=0)


def integrate(figure: Callable, scene, structure, loading=None, time_step=Implicit.time_step, n_steps=100, x0=None,
              v0=None, start_time=0.0, solver: Newton | None = None, segment: int | None = None,
              reduce: Callable = mean):
    """``reduce`` (default :func:`mean`; e.g. ``functools.partial(smooth_peak, width=10.0)``) of the per-step
    ``figure`` over the run: a time-integrated figure, its gradient by ``jax.grad`` costing one adjoint
    solve per step and O(√n_steps) states of memory (module docstring). Arguments as :func:`series`."""
    return reduce(series(figure, scene, structure, loading, time_step, n_steps, x0, v0, start_time, solver,
                         segment))


# -- per-step figures ------------------------------------------------------------------------------------


def reactions(now: Instant):
    """(N, 3) the force (N) the supports exert on each node at its fixed coordinates (zero elsewhere): minus
    the step's out-of-balance force there, so the inertia of the held nodes and of their share of the net
    is in it (what ``simulate`` records as ``reaction_N``)."""
    return jnp.where(jnp.asarray(now.scene.nodes.fixed), -now.force, 0.0)


def _safe_norm(a):
    """|a| with a zero (not NaN) gradient at a = 0."""
    squared = jnp.sum(a * a)
    positive = squared > 0.0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, squared, 1.0)), 0.0)


def mooring_force(now: Instant, nodes=None, direction=None):
    """The resultant (N) of the reactions at ``nodes`` (default: every node with a fixed coordinate): its
    magnitude, or its component along ``direction`` (3,) (normalised here) when given. The load on a
    mooring (or the towing force, for a towed net) at the end of the step."""
    r = reactions(now)
    if nodes is not None:
        r = r[jnp.asarray(nodes)]
    total = jnp.sum(r, axis=0)
    if direction is None:
        return _safe_norm(total)
    d = jnp.asarray(direction, dtype=float)
    return jnp.dot(total, d / jnp.linalg.norm(d))


def drag(now: Instant, group=None):
    """(3,) the total drag (N) of a drag group (:func:`jaxnet.terms.term.drag_groups`: ``"drag_netting_N"``,
    ``"drag_cables_N"``, ``"drag_nodes_N"``), or of every drag term (``group=None``), on the velocities of
    the step relative to the water."""
    drag_groups = term_lib.drag_groups()
    if group is not None and group not in drag_groups:
        raise ValueError(f"drag: group must be one of {tuple(drag_groups)} or None, got {group!r}")
    names = sum(drag_groups.values(), ()) if group is None else drag_groups[group]
    terms = tuple(t for t in now.structure.model if t.name in names)
    if not terms:
        return jnp.zeros(3)
    return jnp.sum(assemble.forces(now.x, now.scene, terms, None, now.step.motion), axis=0)


def enclosed_volume(now: Instant):
    """The volume (m³) the net holds behind its enclosure's plane (``net.enclose``), as ``simulate`` records."""
    scene = now.scene
    e = scene.enclosure
    if e is None or scene.netting is None:
        raise ValueError("enclosed_volume: the scene has no enclosure (net.enclose) or no netting")
    return catch_lib.enclosed_volume(now.x, scene.netting.vertices, jnp.dot(jnp.asarray(e.center), jnp.asarray(e.axis)),
                                     jnp.asarray(e.axis), sign=scene.netting.outward)
