"""Gradient-based optimisation of a net design with optax, through the differentiable equilibrium.

The loop. Each iteration solves the equilibrium of the current design θ (:func:`jaxnet.solve.implicit.equilibrium`,
warm-started at the last one: a few Newton steps), evaluates the objective on it and its gradient by the
adjoint (one more sparse solve), and takes an optax step. The value-and-gradient is one jitted program,
compiled once; the design and the warm start are its arguments.

Scaling. Design parameters span orders of magnitude (corner twine coordinates in tens of twines, a twine
diameter in millimetres, EA in kilonewtons), and optax's steps (Adam's in particular) are in the units of
what they optimise. So the optimiser works on z = (θ - θ₀)/s, s one twine for the cut's corners (corner 0 held:
only differences of twine coordinates matter) and |θ₀| (a relative change) for everything else, unless
``scale`` says otherwise.

Robustness. A step to a design whose equilibrium does not converge (a cut that folds the net, a twine made
too thin to carry the load) is not taken: the step is halved, up to ``backtracks`` times, and the loop stops
with that reason if no half of it converges. The optimiser's state is kept from before the rejected step.
Bounds (:class:`jaxnet.design.constraints.Bounds`) are enforced by projection after each step.

The end. The continuous optimum's cut is generally not on whole meshes: the result also holds the design
rounded to whole meshes (:meth:`jaxnet.design.space.DesignSpace.rounded`: legal cutting rates on every side),
re-solved, with its objective and constraint violation, so the design one can actually cut is reported.

History. Every iteration appends a line to ``out/history.jsonl`` (objective, constraint violation, gradient
norm, step, Newton iterations, wall time) as it goes, and ``out/design.json`` holds the final and rounded
designs: a run that is stopped loses nothing it has done.
"""

from __future__ import annotations

import dataclasses
import json
import pathlib
import time

import jax
import jax.numpy as jnp
import numpy as np
import optax

from jaxnet.design import constraints as constraints_lib, objectives as objectives_lib
from jaxnet.solve import implicit, programs, results, statics
from jaxnet.solve.options import DIFFERENTIABLE, Newton

#: stop reasons
CONVERGED, MAX_STEPS, SOLVE_FAILED = "gradient below tolerance", "maximum number of steps", "equilibrium failed"


@dataclasses.dataclass
class DesignResult:
    """An optimisation's outcome.

    theta: the optimised design, the best iterate (the families and entries that were optimised; θ's
    units). value: its objective. x: (N, 3) its equilibrium (m). history: one dict per iteration (see the module docstring).
    reason: why the loop stopped. rounded: the design with its cut on whole meshes (None without a cut),
    rounded_value, rounded_violation: its objective and constraint violation, rounded_x its equilibrium,
    cut_report: per panel, its sides' meshes and cutting rates (:class:`jaxnet.design.cut.SideCut`).
    """

    theta: dict
    value: float
    x: np.ndarray
    history: list
    reason: str
    rounded: dict | None = None
    rounded_value: float | None = None
    rounded_violation: float | None = None
    rounded_x: np.ndarray | None = None
    cut_report: dict | None = None


def default_scale(theta):
    """The optimiser's unit for each leaf of θ: one twine for a cut's corners, |θ₀| (a relative change)
    for any other parameter (1 where θ₀ is 0).

    A cut's corner 0 gets 0: it stays where it is. Only differences of twine coordinates mean anything (the
    netting is the same wherever its origin is), so moving every corner together changes nothing and the
    gradient along that direction is only rounding; an optimiser that normalises its steps (Adam) would turn
    that rounding into full steps and let the cut drift."""
    def unit(path, leaf):
        if path and getattr(path[0], "key", None) == "cut":
            return jnp.ones_like(jnp.asarray(leaf, dtype=float)).at[0].set(0.0)
        a = jnp.abs(jnp.asarray(leaf, dtype=float))
        return jnp.where(a > 0, a, 1.0)

    return jax.tree_util.tree_map_with_path(unit, theta)


def _violation(objective, outcome):
    return objective.violation(outcome) if hasattr(objective, "violation") else jnp.asarray(0.0)


def _json(tree):
    return jax.tree.map(lambda a: np.asarray(a).tolist(), tree)


def optimize(space, objective, theta, optimizer=None, steps=50, bounds=None, scale=None, solver: Newton | None = None,
             gtol=1e-6, backtracks=6, out=None, progress=True, x0=None, round_cut=True) -> DesignResult:
    """Minimise ``objective`` over the design parameters ``theta`` of ``space``.

    Args:
      space: a :class:`jaxnet.design.space.DesignSpace`.
      objective: a figure (:mod:`jaxnet.design.objectives`): Outcome -> scalar, e.g. ``constraints.penalised(volume...)``;
        a figure with a ``violation`` (a penalised objective) reports it in the history.
      theta: the starting design: the families and entries to optimise (a subset of ``space.initial()``);
        the others stay at the reference.
      optimizer: an optax GradientTransformation (default ``optax.adam(0.05)`` on the scaled parameters);
        one that needs the value and a value function (``optax.lbfgs()``) gets them.
      steps: the most iterations. gtol: stop when the largest gradient component (scaled) is below it.
      bounds: :class:`jaxnet.design.constraints.Bounds` on θ (its units), enforced by projection.
      scale: the optimiser's unit per leaf of θ (default :func:`default_scale`).
      solver: the equilibrium solves' options (default :data:`jaxnet.solve.options.DIFFERENTIABLE`).
      backtracks: halvings of a step whose equilibrium does not converge before the loop stops.
      out: a directory for ``history.jsonl`` and ``design.json`` (written as the run goes); None for none.
      progress: a tqdm bar with the objective and the gradient norm.
      x0: (N, 3) start of the first solve; default: the static solver's equilibrium of the start design.
      round_cut: also solve and report the design rounded to whole meshes.
    Returns:
      a :class:`DesignResult`.
    """
    theta0 = jax.tree.map(lambda a: jnp.asarray(a, dtype=float), theta)
    space.check(theta0)
    scale = default_scale(theta0) if scale is None else jax.tree.map(jnp.asarray, scale)
    structure = implicit.structure_of(space.reference)
    model = structure.model
    optimizer = optimizer or optax.adam(0.05)
    solver = solver or DIFFERENTIABLE
    bounds = bounds or constraints_lib.Bounds()
    out = None if out is None else pathlib.Path(out)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / "history.jsonl").write_text("")

    def design(z):
        return jax.tree.map(lambda t0, s, zz: t0 + s * zz, theta0, scale, z)

    def loss(z, start):
        scene = space.scene(design(z))
        eq = implicit.equilibrium(scene, structure, x0=start, solver=solver, throw=False)
        o = objectives_lib.Outcome(eq.x, scene, model)
        return objective(o), (eq.x, eq.status, eq.iterations, _violation(objective, o))

    value_and_grad = programs.jit(jax.value_and_grad(loss, has_aux=True))
    extra = isinstance(optimizer, optax.GradientTransformationExtraArgs)
    # an optimiser with a line search (L-BFGS) calls the value function inside its update: one compiled update,
    # the warm start an argument (a fresh closure per step would recompile the line search every step)
    extra_update = programs.jit(lambda g, state, z, value, start: optimizer.update(
        g, state, z, value=value, grad=g, value_fn=lambda zz: loss(zz, start)[0]))

    def evaluate(z, start):
        (value, (x, status, iterations, violation)), g = value_and_grad(z, start)
        ok = int(status) == results.CONVERGED and bool(jnp.isfinite(value))
        return ok, float(value), g, np.asarray(x), int(iterations), float(violation)

    t_start = time.perf_counter()
    if x0 is None:
        first = implicit.solve(space.scene(theta0), solver=solver, structure=structure)
        x0 = np.asarray(first.x)
    z = jax.tree.map(jnp.zeros_like, theta0)
    ok, value, g, x, iterations, violation = evaluate(z, x0)
    if not ok:
        raise implicit.ImplicitError("optimize: the equilibrium of the start design does not converge")
    state = optimizer.init(z)
    history, reason = [], MAX_STEPS
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=steps, desc="design", unit="step")
    best = (value, z, x)
    for k in range(steps + 1):
        g_norm = float(max(jnp.max(jnp.abs(leaf)) for leaf in jax.tree.leaves(g)))
        row = dict(step=k, objective=value, violation=violation + float(bounds.violation(design(z))),
                   gradient_norm=g_norm, newton_iterations=iterations, wall_s=time.perf_counter() - t_start)
        history.append(row)
        if out is not None:
            with open(out / "history.jsonl", "a") as f:
                f.write(json.dumps(row) + "\n")
        if bar is not None:
            bar.set_postfix(objective=f"{value:.6g}", gradient=f"{g_norm:.3g}")
            bar.update(1 if k else 0)
        if g_norm < gtol:
            reason = CONVERGED
            break
        if k == steps:
            break
        if extra:
            updates, new_state = extra_update(g, state, z, value, x)
        else:
            updates, new_state = optimizer.update(g, state, z)
        for _ in range(backtracks + 1):
            z_new = optax.apply_updates(z, updates)
            # bounds in θ's units, then back to the optimiser's
            z_new = jax.tree.map(lambda t, t0, s: jnp.where(s > 0, (t - t0) / jnp.where(s > 0, s, 1.0), 0.0),
                                 bounds.project(design(z_new)), theta0, scale)
            trial = evaluate(z_new, x)
            if trial[0]:
                break
            updates = jax.tree.map(lambda u: 0.5 * u, updates)
        else:
            reason = SOLVE_FAILED
            break
        z, state = z_new, new_state
        _, value, g, x, iterations, violation = trial
        if value < best[0]:
            best = (value, z, x)
    if bar is not None:
        bar.close()
    # the best design seen: optimisers without a line search (Adam) need not end on their best iterate
    value, z, x = best
    best = design(z)
    result = DesignResult(theta=jax.tree.map(np.asarray, best), value=value, x=x, history=history, reason=reason)
    if round_cut and "cut" in theta0:
        rounded, report = space.rounded(best)
        scene = space.scene(rounded)
        eq = implicit.equilibrium(scene, structure, x0=x, solver=solver, throw=False)
        if int(eq.status) != results.CONVERGED:
            first = statics.solve(scene)
            eq = implicit.equilibrium(scene, structure, x0=first.x, solver=solver)
        o = objectives_lib.Outcome(eq.x, scene, model)
        result.rounded = jax.tree.map(np.asarray, rounded)
        result.rounded_value = float(objective(o))
        optimised = {family: {k: rounded[family][k] for k in entries} for family, entries in theta0.items()}
        result.rounded_violation = float(_violation(objective, o)) + float(bounds.violation(optimised))
        result.rounded_x = np.asarray(eq.x)
        result.cut_report = report
    if out is not None:
        (out / "design.json").write_text(json.dumps(dict(
            reason=reason, objective=value, theta=_json(result.theta),
            rounded=None if result.rounded is None else _json(result.rounded),
            rounded_objective=result.rounded_value, rounded_violation=result.rounded_violation,
            cut_report=None if result.cut_report is None else {p: [str(s) for s in sides] for p, sides in
                                                                result.cut_report.items()}), indent=1))
    return result
