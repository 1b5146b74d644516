"""Dynamics: the book's implicit time stepping (eqs 4.265-4.276), each step solved by the static Newton iteration.

The scheme. At the new time t + Δt the positions x are the unknown; the velocity and the acceleration are
backward differences (4.266-4.268, with the signs corrected: ``docs/errata.md``),

    v = (x - x_n)/Δt,        γ = (v - v_n)/Δt = (x - x_n - Δt v_n)/Δt²,

x_n, v_n the positions and velocity at t (for a constant step γ is 4.268's (x - 2 x_n + x_{n-1})/Δt²). The
step solves "sum of forces = 0" at t + Δt: the static out-of-balance force (twines, bars, weight, ...), the
drag on the velocity of the water relative to each vertex (4.272-4.276: current and waves at the vertex,
minus v), and the force of inertia 4.265,

    F_i = M_a (γ_h - γ) + ρ V γ_h - M γ = -(M + M_a) γ + (M_a + ρ V) γ_h,

per node and axis, with the masses lumped at the nodes (:func:`jaxnet.solve.masses.lumped_masses`: a third of each triangle's
netting per vertex as the book says, half of each bar per end, the nodes' own bodies). Its first part is
minus the gradient of ½ (M + M_a)/Δt² |x - x_n - Δt v_n|² (:func:`jaxnet.terms.inertia.inertia_energy`), so
the step is the static problem with that energy added: :func:`jaxnet.solve.newton.newton_loop` solves it
unchanged (the same damped Newton, energy line search and stop reasons), its tangent gaining the inertia
(M + M_a)/Δt² on the diagonal (4.271) and the drag's damping (1/Δt) ∂F/∂v (autodiff of the drag with v
formed inside, or the drag's closed form given v: :mod:`jaxnet.closed_form.drag`). The water's acceleration
γ_h (the current's time derivative, the waves' local acceleration) is taken at the start of the step, at the
nodes' positions x_n: a load during the step.

Why this scheme is stable. Backward differences are the first-order backward differentiation formula
(implicit Euler on positions and velocities): A-stable and L-stable, so stiff twines (EA up to 1e9 N) do not
limit Δt; the price is numerical damping of oscillations with periods not well above Δt (an oscillator of
frequency ω loses amplitude as (1 + (ω Δt)²)^(-1/2) per step, and its period lengthens by O(ω Δt)), and
first-order accuracy: the error is proportional to Δt. :mod:`jaxnet.solve.reference` integrates the same
equations with an error-controlled higher-order method to measure it.

Robustness. Each step starts Newton from the constant-velocity prediction x_n + Δt v_n. A step whose
Newton does not converge is retried with half the step (counted in ``retries``, reported); the step grows
back (doubling, up to ``time_step``) after each success that took Newton at most a third of its allowed
iterations, and is kept after a harder one: doubling a step that barely passed fails the next attempt, a
whole Newton solve lost every other step (the stability suite's stiff curtain, EA = 1e10 N, in a current
switched on, Δt = 10 s, counts the failed attempts: ``validation/stability.py``). Below ``min_time_step``
the run stops: :class:`DynamicsError` naming the time, the node with the largest residual and Newton's
reason, or with ``throw=False`` the run so far, its state's ``status`` STEP_FAILED. Nothing non-finite is
accepted (Newton's NON_FINITE status is a failure).

The loop. :func:`integrate` advances a run (checked first: :func:`plan`) one record interval at a time and
hands each record to an observer as it is taken; :func:`simulate` does both. Writing the records
(:mod:`jaxnet.io.timeseries`: time series and VTK), progress and resuming a stopped run from its last record are
the run layer's (:func:`jaxnet.run.simulate`). Two drivers take the same steps (:attr:`jaxnet.solve.options.Implicit.loop`): the host
(:class:`Stepper`: a compiled :func:`step_setup` per step, then the static solver's host Newton loop given the
step, whose programs are kept on disk, so that the next run and a resumed one load them); or one jitted
program per interval (:func:`advance`: ``lax.while_loop`` over steps, Newton's ``lax.while_loop`` inside, the
factorisation a host callback, which keeps it from the disk: compiled by every process, cheaper per step).
By default a run of many steps takes the compiled loop, a shorter one the host's
(:data:`jaxnet.solve.options.AUTO_COMPILED_STEPS`); ``benchmarks/dynamics_loops.py`` measures both.

Loading in time (:class:`Loading`): a current whose speed follows a history (:mod:`jaxnet.water.forcing`),
waves (``Environment.waves``, :mod:`jaxnet.water.waves`: regular, Stokes, an irregular sea), and prescribed motions
of nodes (a towing speed or speed table, the heave of a collar): those nodes are held (fixed in the scene) at
start + displacement(t); winches (:class:`jaxnet.water.forcing.Winch`) set their cables' rest lengths at t, the
lumped masses following them at every step. A run grows the waves and the motions in over its start ramp
(:func:`with_start_ramp`: one wave period by default), so that it leaves its static start without a shock.

Units: m, s, kg, N.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple
import time as _time

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import linalg, model as model_lib, scene as scene_lib
from jaxnet.model import assemble, catch as catch_lib
from jaxnet.scene import checks
from jaxnet.water import forcing
from jaxnet.water.forcing import Loading  # simulate's argument, offered here as dynamics.Loading too
from jaxnet.solve import newton, options as options_lib, programs, results, statics
from jaxnet.solve.masses import lumped_masses
from jaxnet.solve.options import Implicit, Newton
from jaxnet.solve.results import Timing
from jaxnet.terms import cable, drag, inertia, tension, term as term_lib

__all__ = ["Implicit", "Loading", "TimeStep", "State", "Trajectory", "DynamicsError", "lumped_masses", "scene_at",
           "water_acceleration", "out_of_balance", "prescribed_velocity", "check_loading", "with_start_ramp", "advance",
           "simulate", "out_of_balance_jit", "advance_jit", "step_setup", "Stepper", "chosen_loop", "record_figures",
           "RUNNING", "DONE", "STEP_FAILED", "REASONS"]

#: stop reasons of a dynamic run (``State.status``, ``Trajectory.status``)
RUNNING, DONE, STEP_FAILED = 0, 1, 2
REASONS = {RUNNING: "running", DONE: "done", STEP_FAILED: "a step failed below the smallest time step"}


class DynamicsError(RuntimeError):
    """A dynamic run could not go on; ``.state`` holds the last accepted state."""

    def __init__(self, message, state):
        super().__init__(message)
        self.state = state


class TimeStep(eqx.Module):
    """The past and the masses of one implicit step, handed to the static Newton iteration
    (:func:`jaxnet.solve.newton.newton_loop`'s ``step``).

    x_previous, velocity: (N, 3) positions (m) and velocities (m/s) at the start of the step.
    time_step: Δt (s). mass: (N, 3) M + M_a per node and axis (kg). water_load: (N, 3) (M_a + ρV) γ_h (N).
    """

    x_previous: jax.Array
    velocity: jax.Array
    time_step: jax.Array
    mass: jax.Array
    water_load: jax.Array

    @property
    def motion(self):
        return assemble.Motion(self.x_previous, self.time_step)

    def inertia_energy(self, x):
        return inertia.inertia_energy(x, self.x_previous, self.velocity, self.time_step, self.mass)

    def inertia_stiffness(self):
        """(N, 3) the diagonal (M + M_a)/Δt² (N/m) of the inertia's stiffness (4.271)."""
        return self.mass / self.time_step**2


class State(eqx.Module):
    """The state of a run between steps (pytree, the loop's carry).

    x, v: (N, 3) positions (m) and velocities (m/s) at time t (s). next_step: the Δt the next step tries (s).
    last_step: the Δt of the last accepted step (s). force: (N, 3) the last step's out-of-balance force (N);
    at fixed coordinates minus the reactions (inertia of the fixed nodes included). steps, iterations,
    retries: accepted steps, Newton iterations (of accepted and failed steps) and retried steps so far.
    status: RUNNING / DONE / STEP_FAILED. newton_status, worst_node, residual_N: of the last Newton solve.
    """

    x: jax.Array
    v: jax.Array
    t: jax.Array
    next_step: jax.Array
    last_step: jax.Array
    force: jax.Array
    steps: jax.Array
    iterations: jax.Array
    retries: jax.Array
    status: jax.Array
    newton_status: jax.Array
    worst_node: jax.Array
    residual_N: jax.Array

    def arrays(self):
        """The state as numpy arrays by field name: what a resumed run starts from, exactly (a checkpoint)."""
        return {f.name: np.asarray(getattr(self, f.name)) for f in dataclasses.fields(self)}

    @classmethod
    def from_arrays(cls, arrays):
        """The state of a checkpoint (:meth:`arrays`)."""
        return cls(**{f.name: jnp.asarray(arrays[f.name]) for f in dataclasses.fields(cls)})

    @classmethod
    def start(cls, x, v, t, solver: Implicit, force=None):
        # strongly typed leaves (numpy scalars, not Python ones): the loop's output has these exact types,
        # so the next call of the compiled loop reuses it instead of compiling again for weak types
        x = jnp.asarray(x, dtype=np.float64)
        i = jnp.asarray(np.int64(0))
        f = jnp.zeros_like(x) if force is None else jnp.asarray(force, dtype=np.float64)
        return cls(x=x, v=jnp.asarray(v, dtype=np.float64), t=jnp.asarray(np.float64(t)),
                   next_step=jnp.asarray(np.float64(solver.time_step)), last_step=jnp.asarray(np.float64(solver.time_step)),
                   force=f, steps=i, iterations=i, retries=i, status=jnp.asarray(np.int64(RUNNING)),
                   newton_status=jnp.asarray(np.int64(results.CONVERGED)), worst_node=i,
                   residual_N=jnp.asarray(np.float64(0.0)))


# -- the surroundings at a time ------------------------------------------------------------------------


def _ramped_motion(motion, ramp):
    """``motion`` with ``ramp`` (s) as its own ramp where it is a Towing or Harmonic without one (recursively
    through sums); any other motion as it is."""
    if isinstance(motion, forcing.Sum):
        return forcing.Sum(*(_ramped_motion(part, ramp) for part in motion.parts))
    if isinstance(motion, (forcing.Towing, forcing.Harmonic)) and not float(motion.ramp) > 0.0:
        return eqx.tree_at(lambda m: m.ramp, motion, jnp.asarray(ramp, dtype=float))
    return motion


def with_start_ramp(scene, loading: Loading):
    """(scene, loading, ramp in s): the scene's waves and the loading's motions given the run's start ramp
    (:attr:`jaxnet.water.forcing.Loading.ramp`, its default resolved: one period of the waves, 0 without). What
    :func:`simulate` runs; applying it twice changes nothing more. Raises SceneError for waves that have no
    ``ramp`` to set when a ramp is asked for."""
    waves = scene.environment.waves
    ramp = loading.ramp
    if ramp is None:
        ramp = float(waves.characteristic_period) if waves is not None and hasattr(waves, "characteristic_period") \
            else 0.0
    ramp = float(ramp)
    if not (np.isfinite(ramp) and ramp >= 0.0):
        raise ValueError(f"Loading: ramp must be finite and >= 0 (s), got {loading.ramp!r}")
    if ramp > 0.0:
        if waves is not None:
            if not hasattr(waves, "ramp"):
                raise scene_lib.SceneError(f"the waves ({type(waves).__name__}) have no ramp to grow them in over "
                                           f"{ramp:g} s: give them one, or run with Loading(ramp=0)")
            scene = eqx.tree_at(lambda s: s.environment.waves.ramp, scene, jnp.asarray(ramp, dtype=float))
        motions = tuple(eqx.tree_at(lambda p: p.motion, m, _ramped_motion(m.motion, ramp)) for m in loading.motions)
        loading = eqx.tree_at(lambda ld: ld.motions, loading, motions)
    loading = eqx.tree_at(lambda ld: ld.ramp, loading, ramp, is_leaf=lambda v: v is None)
    return scene, loading, ramp


def scene_at(scene, loading: Loading, t, surface_at=None):
    """The scene at time t: the environment's time and current speed, the prescribed nodes moved, the winches'
    bars at their rest lengths. ``surface_at``: in waves, the positions (N, 3) (m) at which the free surface's
    elevation is taken (a step's start; :attr:`jaxnet.scene.Environment.surface_elevation`): buoyancy and the
    wetted drags then follow the wave's surface, the elevation η(x_i, t) over each node held through the step as
    FEMNET's ``dyna`` holds it (taken once per step, at the step's start positions and its end time, so that the
    step's forces keep an energy: η moved with the node would give every immersed body a horizontal force ρgV∇η
    that linear theory puts in the water's acceleration, already in the inertia). None: the mean level."""
    env = scene.environment
    speed = env.current_speed if loading.current_speed is None else loading.current_speed(t)
    env = eqx.tree_at(lambda e: (e.time, e.current_speed), env, (t, speed))
    if surface_at is not None and env.waves is not None:
        elevation = env.waves.elevation(jnp.asarray(surface_at, dtype=float), t)
        env = eqx.tree_at(lambda e: e.surface_elevation, env, elevation, is_leaf=lambda leaf: leaf is None)
    position = jnp.asarray(scene.nodes.position)
    for prescribed in loading.motions:
        nodes = jnp.asarray(prescribed.nodes)
        position = position.at[nodes].set(jnp.asarray(scene.nodes.position)[nodes] + prescribed.displacement(t))
    out = eqx.tree_at(lambda s: (s.environment, s.nodes.position), scene, (env, position))
    if loading.winches:
        rest = jnp.asarray(scene.bars.rest_length, dtype=float)
        for winch in loading.winches:
            rest = winch.rest_lengths(rest, t)
        out = eqx.tree_at(lambda s: s.bars.rest_length, out, rest)
    return out


def water_acceleration(points, scene_t, loading: Loading, waves: bool):
    """(..., 3) acceleration (m/s²) of the water at ``points`` at the scene's time: the current's
    d(speed)/dt along its direction and profile, plus the waves' local acceleration."""
    env = scene_t.environment
    accel = jnp.zeros_like(points)
    if loading.current_speed is not None:
        rate = jax.jacfwd(loading.current_speed)(env.time)
        per_speed = drag.water_velocity_at(points, eqx.tree_at(lambda e: e.current_speed, env, 1.0), False)
        accel = accel + rate * per_speed
    if waves:
        accel = accel + env.waves.acceleration(points, env.time)
    return accel


def out_of_balance(x, v, t, scene, masses, loading: Loading, model):
    """(N, 3) force (N) on every node at positions x (m), velocities v (m/s) and time t (s), the net's own
    inertia -(M + M_a) a left out: the loads, the water's inertia (M_a + ρV) γ_h, minus the gradient of the
    stored energy, and the force terms with the drag on the water's velocity relative to v. The equations
    of motion are (M + M_a) a = out_of_balance(x, v, t) at the free coordinates: what
    :mod:`jaxnet.solve.reference` integrates, and what the implicit step balances with a = γ. In waves the free
    surface is the wave's elevation over the nodes at x (:func:`scene_at`)."""
    scene_t = scene_at(scene, loading, t, surface_at=x)
    waves = scene.environment.waves is not None
    f = assemble.loads(scene_t, model) - jax.grad(assemble.energy)(x, scene_t, model)
    if waves or loading.current_speed is not None:
        f = f + jnp.asarray(masses[1]) * water_acceleration(x, scene_t, loading, waves)
    if any(t.term.kind == "force" for t in model):
        # a unit "step" from x - v: the force terms see the velocity v itself
        f = f + assemble.forces(x, scene_t, model, None, assemble.Motion(x - v, jnp.asarray(1.0)))
    return f


#: :func:`out_of_balance` compiled (``model`` static): the start force of a run
out_of_balance_jit = programs.jit(out_of_balance, static_argnames=("model",))


def prescribed_velocity(scene, loading: Loading, t):
    """(N, 3) velocity (m/s) of every node held by a prescribed motion at time t (zero elsewhere)."""
    return jax.jacfwd(lambda s: scene_at(scene, loading, s).nodes.position)(jnp.asarray(t, dtype=float))


# -- the step loop -----------------------------------------------------------------------------------


def step_setup(x, v, h, t_new, scene, masses, loading: Loading):
    """(the scene at ``t_new``, the :class:`TimeStep`) of the implicit step from positions x and velocities v
    (N, 3) at t_new - h to t_new (s): the surroundings at t_new (:func:`scene_at`; in waves, the free surface's
    elevation over the nodes at x), the masses (``masses``,
    :func:`lumped_masses`; with winches, those of the scene at t_new: a winch moves cable into or out of the
    water), and the water's inertia (M_a + ρV) γ_h at the positions x."""
    mass, water_mass = (jnp.asarray(m) for m in masses)
    scene_t = scene_at(scene, loading, t_new, surface_at=x)
    if loading.winches:
        mass, water_mass = lumped_masses(scene_t, jnp)
    waves = scene.environment.waves is not None
    if waves or loading.current_speed is not None:
        load = water_mass * water_acceleration(x, scene_t, loading, waves)
    else:
        load = jnp.zeros_like(x)
    return scene_t, TimeStep(x, v, h, mass, load)


def _step_setup_leaves(x, v, h, t_new, scene, masses, loading):
    # the program returns leaves only: a program kept on disk keeps its output's structure, and an equinox
    # module's does not survive that; the caller puts them back in their tree
    return jax.tree.leaves(step_setup(x, v, h, t_new, scene, masses, loading))


_step_setup_jit = programs.jit(_step_setup_leaves)


def _easy_iterations(solver: Newton):
    """The most Newton iterations of a step after which the next step may double: a third of the allowed."""
    return max(1, solver.max_iter // 3)


def advance(state: State, t_end, scene, pattern, masses, loading: Loading, time_step, min_time_step, model,
            solver: Newton) -> State:
    """Steps from ``state`` until time ``t_end`` (the last step adjusted to land on it) or a step failing
    below ``min_time_step`` (s). ``time_step``: the step taken when Newton converges (s). Jittable; ``model``
    (the dynamic active terms, ``active_terms(scene, dynamic=True)``) and ``solver`` (each step's options)
    are static, the steps are not (a study over Δt compiles once). ``masses``: :func:`lumped_masses`."""
    free = pattern.free
    end = jnp.asarray(t_end, dtype=float)
    state = eqx.tree_at(lambda s: s.status, state, jnp.asarray(np.int64(RUNNING)))

    def cond(s):
        return (s.status == RUNNING) & (s.t < end)

    def body(s):
        # the step that would end within 1 % of t_end lands on it exactly: no sliver of a step is left
        # (a step of 1e-14 s would scale the inertia by 1/Δt² = 1e28 and drown the step in rounding)
        remaining = end - s.t
        land = remaining <= 1.01 * s.next_step
        h = jnp.where(land, remaining, s.next_step)
        t_new = jnp.where(land, end, s.t + h)
        scene_t, step = step_setup(s.x, s.v, h, t_new, scene, masses, loading)
        # Newton starts from the constant-velocity prediction: carrying the last step's backward-difference
        # acceleration over as well takes more Newton iterations per step on the cage in waves
        x_guess = (s.x + h * s.v).ravel()[free]
        eq = newton.newton_loop(x_guess, scene_t, pattern, model, solver, step)
        ok = eq.status == results.CONVERGED
        failed = ~ok & (0.5 * h < min_time_step)
        pick = lambda a, b: jnp.where(ok, a, b)  # noqa: E731
        new = State(
            x=pick(eq.x, s.x),
            v=pick((eq.x - s.x) / h, s.v),
            t=pick(t_new, s.t),
            # a step that took Newton many iterations is near the largest that passes: keep it (doubling it
            # would fail and cost a whole failed Newton solve, every other step); an easy one doubles
            next_step=pick(jnp.where(eq.iterations <= _easy_iterations(solver),
                                     jnp.minimum(time_step, 2.0 * s.next_step), s.next_step), 0.5 * h),
            last_step=pick(h, s.last_step),
            force=pick(eq.force, s.force),
            steps=s.steps + ok,
            iterations=s.iterations + eq.iterations,
            retries=s.retries + ~ok,
            status=jnp.where(failed, STEP_FAILED, RUNNING),
            newton_status=eq.status,
            worst_node=eq.worst_node,
            residual_N=eq.residual_N,
        )
        return jax.tree.map(lambda a, b: jax.lax.convert_element_type(a, b.dtype), new, s)

    out = jax.lax.while_loop(cond, body, state)
    out = eqx.tree_at(lambda s: s.status, out, jnp.where(out.status == RUNNING, DONE, out.status))
    return jax.tree.map(lambda a, b: jax.lax.convert_element_type(a, b.dtype), out, state)


#: :func:`advance` compiled (``model``, ``solver`` static): what :func:`simulate` calls once per record
advance_jit = programs.jit(advance, static_argnames=("model", "solver"))


class Stepper:
    """:func:`advance`'s steps driven from the host: what :func:`simulate` runs. Each step calls the compiled
    :func:`step_setup` once, then the static solver's host Newton loop (:func:`jaxnet.solve.statics.host_loop`
    given the step: the same iteration as :func:`advance`'s jitted ``newton_loop``, from the same prediction,
    with the same step control). Its programs (the step's setup, the evaluation and tangent of a time step,
    compiled once per run for the scene's shape) hold no host callback, so they are kept on disk like the static
    solver's (:mod:`jaxnet.solve.programs`, when a compilation cache directory is set: the command line sets
    one): the next run of a scene of the same shape, and a resumed run, load them instead of compiling them.
    The jitted :func:`advance` holds the factorisation as a host callback, which no executable kept on disk
    may hold.

    scene, pattern, masses, loading, model: as :func:`advance`'s; ``solver``: its :class:`Implicit` options.
    """

    def __init__(self, scene, pattern, masses, loading: Loading, model, solver: Implicit):
        self.scene, self.pattern, self.masses, self.loading = jax.device_put((scene, pattern, masses, loading))
        self.model, self.solver = model, solver
        self.free = np.asarray(pattern.free)
        self._setup = self._tree = self._pieces = None

    def _setup_of(self, x, v, h, t_new):
        args = (x, v, np.float64(h), np.float64(t_new), self.scene, self.masses, self.loading)
        if self._setup is None:
            self._tree = jax.tree.structure(jax.eval_shape(step_setup, *args))
            self._setup = programs.obtain("step_setup", _step_setup_jit, args)
        return jax.tree.unflatten(self._tree, self._setup(*args))

    def advance(self, state: State, t_end) -> State:
        """:func:`advance` from ``state`` to ``t_end`` (s): the same steps, step control and stop reasons."""
        options, newton_options = self.solver, self.solver.newton
        x, v = np.asarray(state.x, dtype=float), np.asarray(state.v, dtype=float)
        t, next_step, last_step = float(state.t), float(state.next_step), float(state.last_step)
        force = state.force
        steps, iterations, retries = int(state.steps), int(state.iterations), int(state.retries)
        status, newton_status = RUNNING, int(state.newton_status)
        worst_node, residual = int(state.worst_node), float(state.residual_N)
        end = float(t_end)
        while status == RUNNING and t < end:
            # the step that would end within 1 % of t_end lands on it exactly (advance says why)
            remaining = end - t
            land = remaining <= 1.01 * next_step
            h = remaining if land else next_step
            t_new = end if land else t + h
            scene_t, step = self._setup_of(x, v, h, t_new)
            x_guess = (x + h * v).ravel()[self.free]
            if self._pieces is None:
                self._pieces = statics.compile_pieces(x_guess, scene_t, self.pattern, self.model,
                                                      newton_options.stiffness, step, newton_options.method)
            eq = statics.host_loop(x_guess, scene_t, self.pattern, self.model, newton_options, self._pieces, step)
            ok = int(eq.status) == results.CONVERGED
            its = int(eq.iterations)
            if ok:
                x_new = np.asarray(eq.x)
                x, v, t = x_new, (x_new - x) / h, t_new
                next_step = min(options.time_step, 2.0 * next_step) if its <= _easy_iterations(newton_options) \
                    else next_step
                last_step, force, steps = h, eq.force, steps + 1
            else:
                next_step, retries = 0.5 * h, retries + 1
                if 0.5 * h < options.min_time_step:
                    status = STEP_FAILED
            iterations += its
            newton_status, worst_node, residual = int(eq.status), int(eq.worst_node), float(eq.residual_N)
        f64, i64 = np.float64, np.int64
        return State(x=jnp.asarray(x), v=jnp.asarray(v), t=jnp.asarray(f64(t)), next_step=jnp.asarray(f64(next_step)),
                     last_step=jnp.asarray(f64(last_step)), force=jnp.asarray(force, dtype=np.float64),
                     steps=jnp.asarray(i64(steps)), iterations=jnp.asarray(i64(iterations)),
                     retries=jnp.asarray(i64(retries)), status=jnp.asarray(i64(DONE if status == RUNNING else status)),
                     newton_status=jnp.asarray(i64(newton_status)), worst_node=jnp.asarray(i64(worst_node)),
                     residual_N=jnp.asarray(f64(residual)))


# -- what a record holds ---------------------------------------------------------------------------------

def _totals(state: State, scene, loading, model):
    """(3,) total drag (N) of each drag group (:func:`jaxnet.terms.term.drag_groups`) at the state (relative
    velocities included), the volume held (m³) when the scene has an enclosure, and the largest twine and bar
    tensions (N; of one twine, not of the mesh's bundle of them); one compiled program per run."""
    motion = assemble.Motion(state.x - state.last_step * state.v, state.last_step)
    scene_t = scene_at(scene, loading, state.t, surface_at=motion.x_previous)
    out = {}
    for group, names in term_lib.drag_groups().items():
        terms = tuple(t for t in model if t.name in names)
        if terms:
            out[group] = jnp.sum(assemble.forces(state.x, scene_t, terms, None, motion), axis=0)
    e = scene.enclosure
    if e is not None and scene.netting is not None:
        out["volume_m3"] = catch_lib.enclosed_volume(state.x, scene.netting.vertices, jnp.dot(e.center, e.axis), e.axis,
                                                     sign=scene.netting.outward)
    net, bars = scene.netting, scene.bars
    if net is not None:
        tu, tv = jax.vmap(tension.netting_tensions)(state.x[net.vertices], net.uv, net.l0, net.ea_traction,
                                                    net.ea_compression)
        out["max_twine_tension_N"] = jnp.maximum(jnp.max(tu), jnp.max(tv))
    if bars is not None:
        bars = scene_t.bars
        bar_tension = jax.vmap(cable.bar_tension)(state.x[bars.ends], bars.rest_length, bars.ea_traction,
                                                  bars.ea_compression)
        out["max_bar_tension_N"] = jnp.max(bar_tension)
        if loading.winches:
            out["winch_tension_N"] = jnp.stack([bar_tension[w.drum_bar] for w in loading.winches])
            out["winch_hauled_m"] = jnp.stack([w.hauled(state.t) for w in loading.winches])
    return out


_totals_jit = programs.jit(_totals, static_argnames=("model",))


def record_figures(state: State, scene, loading, model, fixed_nodes):
    """The figures of one record (numpy): reactions at the fixed nodes (F, 3) (N; the nodes ``fixed_nodes``, in
    that order) and their total (3,) in N, drag totals (3,) in N per group, the volume held (m³) for an
    enclosure, the largest twine and bar tensions (N), the run's counters."""
    force = np.asarray(state.force)
    fixed = np.asarray(scene.nodes.fixed)
    reaction = np.where(fixed, -force, 0.0)
    figures = {"reaction_N": reaction[fixed_nodes], "reaction_total_N": reaction.sum(axis=0)}
    # a program of the solver's (kept on disk, JAX's own cache left alone), so that a resumed run loads it as it
    # loads the steps' programs, whatever its compilation took
    totals = programs.obtain("record_totals", _totals_jit, (state, scene, loading), {"model": model})
    figures.update({k: np.asarray(v) for k, v in totals(state, scene, loading).items()})
    figures.update(steps=np.asarray(int(state.steps)), newton_iterations=np.asarray(int(state.iterations)),
                   retries=np.asarray(int(state.retries)), time_step_s=np.asarray(float(state.last_step)))
    return figures


# -- the run -------------------------------------------------------------------------------------------


@dataclasses.dataclass
class Trajectory:
    """A run: ``times`` (R,) (s), ``positions`` (R, N, 3) (m), ``velocities`` (R, N, 3) (m/s) of its records,
    ``figures`` name -> (R, ...), the last :class:`State` (its ``status`` DONE, or STEP_FAILED for a run that
    stopped, ``throw=False``: the records then end at the last one before the failure), and its
    :class:`~jaxnet.solve.results.Timing` (``compile_s``: the first record interval, which compiles), and the
    time (s) over which its waves and motions grew in (:attr:`jaxnet.water.forcing.Loading.ramp`); ``reaction_nodes``
    (F,): the node indices of the rows of ``figures["reaction_N"]`` (the nodes held on some axis); ``loop``: the
    loop that drove its steps, "host" or "compiled" (:func:`chosen_loop`)."""

    times: np.ndarray
    positions: np.ndarray
    velocities: np.ndarray
    figures: dict
    state: State
    timing: Timing
    start_ramp_s: float = 0.0
    reaction_nodes: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    loop: str = "host"

    @property
    def status(self):
        """The run's stop reason (:data:`REASONS`): DONE, or STEP_FAILED."""
        return int(self.state.status)

    @property
    def reason(self):
        return REASONS[self.status]

    @property
    def steps(self):
        return int(self.state.steps)

    @property
    def mean_iterations(self):
        """Newton iterations per accepted step."""
        return int(self.state.iterations) / max(int(self.state.steps), 1)


def check_loading(scene, loading: Loading):
    """Raise :class:`jaxnet.scene.SceneError` naming the motion and node when a prescribed motion moves a node
    outside the scene or one not fixed on every axis (a prescribed node must be held), and naming the winch
    and bar when a winch takes a bar outside the scene or one another winch takes."""
    fixed = np.asarray(scene.nodes.fixed)
    for k, prescribed in enumerate(loading.motions):
        nodes = np.asarray(prescribed.nodes)
        if nodes.size and (nodes.min() < 0 or nodes.max() >= scene.n_nodes):
            raise scene_lib.SceneError(f"prescribed motion {k}: node index outside 0..{scene.n_nodes - 1}")
        loose = nodes[~fixed[nodes].all(axis=1)]
        if loose.size:
            raise scene_lib.SceneError(f"prescribed motion {k}: node {int(loose[0])} is not fixed on every axis; "
                                       "a prescribed node must be held (fixed) in the scene")
    n_bars = 0 if scene.bars is None else len(np.asarray(scene.bars.rest_length))
    taken = {}
    for k, winch in enumerate(loading.winches):
        bars = np.asarray(winch.bars)
        if bars.max() >= n_bars:
            raise scene_lib.SceneError(f"winch {k}: bar index {int(bars.max())} outside the scene's {n_bars} bars")
        for b in bars.tolist():
            if b in taken:
                raise scene_lib.SceneError(f"winches {taken[b]} and {k} both take bar {b}: a bar has one winch")
            taken[b] = k


class Plan(NamedTuple):
    """A run in time, checked and ready (:func:`plan`): the scene and loading with the start ramp applied
    (:func:`with_start_ramp`), the options, the end time and the record interval (s), the ramp (s), and the
    nodes held on some axis, whose reactions the records hold (``reaction_nodes``, (F,))."""

    scene: scene_lib.Scene
    loading: Loading
    solver: Implicit
    end_time: float
    record_every: float
    ramp_s: float
    reaction_nodes: np.ndarray


def plan(scene, end_time, solver: Implicit | None = None, loading: Loading | None = None, record_every=None) -> Plan:
    """Checks a run of ``scene`` to ``end_time`` (s) before anything is compiled (the scene for dynamics, the
    loading against it, the times) and gives its :class:`Plan`. ``solver`` defaults to ``Implicit()``,
    ``loading`` to none, ``record_every`` (s) to every step."""
    if end_time is None:
        raise ValueError("simulate: give end_time (s): the case has no time settings, or none with an end time")
    solver = solver or Implicit()
    loading = loading or Loading()
    checks.validate(scene, dynamic=True)
    scene, loading, ramp = with_start_ramp(scene, loading)
    linalg.solver_choice()  # a sparse solver asked for that cannot run here: said before anything compiles
    check_loading(scene, loading)
    if not (np.isfinite(end_time) and end_time > 0):
        raise ValueError(f"simulate: end_time must be finite and > 0, got {end_time!r}")
    record_every = solver.time_step if record_every is None else float(record_every)
    if not (np.isfinite(record_every) and record_every > 0):
        raise ValueError(f"simulate: record_every must be finite and > 0, got {record_every!r}")
    held = np.flatnonzero(np.asarray(scene.nodes.fixed).any(axis=1))
    return Plan(scene=scene, loading=loading, solver=solver, end_time=float(end_time), record_every=record_every,
                ramp_s=ramp, reaction_nodes=held)


def simulate(scene, end_time, solver: Implicit | None = None, loading: Loading | None = None, record_every=None,
             x0=None, v0=None, observer=None, throw: bool = True) -> Trajectory:
    """Runs ``scene`` from time 0 to ``end_time`` (s): :func:`integrate` of its :func:`plan`. Records are kept in
    memory; writing them, progress and resuming are the run layer's (:func:`jaxnet.run.simulate`).

    Args:
      scene: a :class:`jaxnet.scene.Scene` (validated here, before anything is compiled).
      end_time: the time to reach (s).
      solver: :class:`Implicit` options. loading: :class:`Loading` (histories, prescribed motions).
      record_every: the interval between records (s); default: every step.
      x0, v0: (N, 3) start positions and velocities (default: the scene's positions, at rest).
      observer: called as ``observer(state, figures)`` with each record as it is taken (:func:`integrate`).
      throw: raise :class:`DynamicsError` when a step fails below the smallest step; with ``throw=False``
        the run stops there and returns its records so far, ``Trajectory.status`` STEP_FAILED (its state
        names the time reached, Newton's status, the worst node and its residual).
    Returns:
      a :class:`Trajectory`, its ``timing`` the compile and wall times (s).
    """
    return integrate(plan(scene, end_time, solver, loading, record_every), x0=x0, v0=v0, observer=observer,
                     throw=throw)


def integrate(run: Plan, x0=None, v0=None, start: State | None = None, observer=None, throw: bool = True
              ) -> Trajectory:
    """Advances a planned run (:func:`plan`) one record interval at a time to its end.

    Args:
      run: the :class:`Plan`.
      x0, v0: (N, 3) start positions (m) and velocities (m/s) at time 0 (default: the scene's, at rest).
      start: a :class:`State` to continue from instead (a stopped run's last record: :meth:`State.from_arrays`);
        records then go on at the same times as the whole run's.
      observer: called as ``observer(state, figures)`` at each record (the start's too when the run starts at
        time 0), ``figures`` the record's figures by name (:func:`record_figures`): where a writer or a
        progress bar takes them as they come.
      throw: as :func:`simulate`'s.
    """
    scene, loading, solver, end_time = run.scene, run.loading, run.solver, run.end_time
    model = model_lib.active_terms(scene, dynamic=True)
    pattern = assemble.build_pattern(scene, model)
    masses = tuple(jnp.asarray(m) for m in lumped_masses(scene, np))
    # The jitted calls below take these trees at every record: their numpy leaves would be copied to the
    # device at each call, a cost on every record (every step by default).
    scene_arg, pattern, loading_arg = jax.tree.map(lambda a: jnp.asarray(a) if isinstance(a, np.ndarray) else a,
                                                   (scene, pattern, loading))
    if start is None:
        x_start = np.asarray(scene_at(scene, loading, 0.0).nodes.position if x0 is None else x0, dtype=float)
        v_start = np.zeros_like(x_start) if v0 is None else np.asarray(v0, dtype=float)
        # the force at the start: the net's own inertia unknown there, the rest (reactions at t = 0) is
        force0 = out_of_balance_jit(jnp.asarray(x_start), jnp.asarray(v_start), 0.0, scene, masses, loading,
                                    model=model)
        start = State.start(x_start, v_start, 0.0, solver, force0)
    state = start
    times, positions, velocities, figures = [], [], [], {}

    def keep(s):
        fig = record_figures(s, scene_arg, loading_arg, model, run.reaction_nodes)
        times.append(float(s.t))
        positions.append(np.asarray(s.x))
        velocities.append(np.asarray(s.v))
        for k, v in fig.items():
            figures.setdefault(k, []).append(v)
        if observer is not None:
            observer(s, fig)

    t0 = _time.perf_counter()
    compile_s = 0.0
    if float(state.t) == 0.0:
        keep(state)
    # record times k * record_every, the same whichever record a run resumes from (so is each step)
    record_every = run.record_every
    targets = np.minimum(record_every * np.arange(1, int(np.ceil(end_time / record_every - 1e-9)) + 1), end_time)
    targets = targets[targets > float(state.t) + 1e-9 * record_every]
    loop = chosen_loop(solver, end_time - float(state.t))
    stepper = Stepper(scene, pattern, masses, loading, model, solver) if loop == "host" else None
    for k, target in enumerate(targets):
        t_call = _time.perf_counter()
        if stepper is not None:
            state = stepper.advance(state, float(target))
        else:
            state = advance_jit(state, float(target), scene_arg, pattern, masses, loading_arg,
                                solver.time_step, solver.min_time_step, model=model, solver=solver.newton)
            jax.block_until_ready(state)
        if k == 0:
            compile_s = _time.perf_counter() - t_call  # the first call compiles (and runs one interval)
        if int(state.status) == STEP_FAILED:
            if not throw:
                break
            node = int(state.worst_node)
            raise DynamicsError(
                f"dynamic step failed at t = {float(state.t):.6g} s: Newton "
                f"({results.REASONS[int(state.newton_status)]}) with the step halved down to "
                f"{solver.min_time_step:g} s; largest residual {float(state.residual_N):.4g} N at node {node}",
                state)
        keep(state)
    return Trajectory(times=np.asarray(times), positions=np.asarray(positions), velocities=np.asarray(velocities),
                      figures={k: np.asarray(v) for k, v in figures.items()}, state=state,
                      timing=Timing(compile_s=compile_s, wall_s=_time.perf_counter() - t0), start_ramp_s=run.ramp_s,
                      reaction_nodes=run.reaction_nodes, loop=loop)


def chosen_loop(solver: Implicit, duration):
    """The loop that drives a run of ``duration`` (s) still to go (:attr:`Implicit.loop`): "host" or
    "compiled", "auto" resolved by the number of steps left (:data:`jaxnet.solve.options.AUTO_COMPILED_STEPS`)."""
    if solver.loop != "auto":
        return solver.loop
    return "compiled" if duration / solver.time_step > options_lib.AUTO_COMPILED_STEPS else "host"
