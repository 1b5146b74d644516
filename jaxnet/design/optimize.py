"""Gradient-based optimisation of a net design with optax, through the differentiable equilibrium.

The loop. Each iteration solves the equilibrium of the current design θ (warm-started at the last one: a few
Newton steps), evaluates the objective on it and its gradient by the adjoint (one more sparse solve:
:mod:`jaxnet.design.gradient`), and takes an optax step. Its compiled programs (the static solver's, the
residual's and the objective's reverse mode, the design map's) are compiled once per design space and
objective, and kept between processes where a compilation cache directory is set. An optimiser with a line
search (``optax.lbfgs``) evaluates trial designs inside its own jitted update: those go through
:func:`jaxnet.solve.implicit.equilibrium`, the same equilibrium in one traced program.

What is optimised. Either θ itself (``start`` a partial θ: the families and entries to vary, every corner
of every cut given a coordinate of its own), or a *reduced design vector* z (``design``, a map z -> partial θ,
jnp code: every wall alike, a taper, a few shape parameters; :mod:`jaxnet.design.reduced` has ready-made
ones): the gradient in z is the chain rule through the map, which ``jax`` differentiates with the rest.
A few numbers that mean something to the designer move the design coherently, where hundreds of corner
coordinates each moved by the optimiser's own step scatter the cut by fractions of a mesh.

Scaling. The optimiser works on w = (p - p₀)/s, p the parameters (θ or z) and s their unit, since optax's
steps (Adam's in particular: its first step is the learning rate in every coordinate) are in the units of
what they optimise. For θ, whose entries span orders of magnitude (corner twine coordinates in tens of
twines, a twine diameter in millimetres, EA in kilonewtons), s is one twine for the cut's corners (corner 0
held: only differences of twine coordinates matter) and |θ₀| (a relative change) for everything else
(:func:`default_scale`). For z, s is 1 unless ``scale`` says otherwise: z is the caller's own
parametrisation, in units the caller chose (meshes, a factor, metres), and one of its numbers may move many
entries of θ at once (the eight walls of a cage), so θ's units say nothing of how far a step of z goes.

Robustness. A step to a design whose equilibrium does not converge (a cut that folds the net, a twine made
too thin to carry the load) is not taken: the step is halved, up to ``backtracks`` times, and the loop stops
with that reason if no half of it converges. The optimiser's state is kept from before the rejected step.
Bounds (:class:`jaxnet.design.constraints.Bounds`, on θ or on z: on what ``start`` is) are enforced by
projection after each step.

The end. The continuous optimum's cut is generally not on whole meshes: the result also holds the design
rounded to whole meshes (:meth:`jaxnet.design.space.DesignSpace.rounded`: legal cutting rates on every side),
re-solved, with its objective and constraint violation, so the design one can actually cut is reported. An
optimum on a constraint (no more twine than ...) has no room for the nearest whole meshes when they round a
corner outward: then the cut with those corners taken one mesh in is solved too, and kept when it violates
the constraints less.
``print(result)`` gives the account as tables (:func:`jaxnet.design.report.result_table`), and its designs
print as tables too (:class:`jaxnet.design.report.Design`).

History. Every iteration appends a line to ``out/history.jsonl`` (objective, constraint violation, gradient
norm, step, Newton iterations, wall time, and z with a design map) as it goes, and ``out/design.json`` holds
the final and rounded designs: a run that is stopped loses nothing it has done.
"""

from __future__ import annotations

import dataclasses
import json
import math
import pathlib
import time
from typing import Any, Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax

from jaxnet.design import constraints as constraints_lib, gradient as gradient_lib, objectives as objectives_lib, report
from jaxnet.design.report import Design
from jaxnet.solve import implicit, programs, results, statics
from jaxnet.solve.options import DIFFERENTIABLE, Newton

#: how optimize computes each step's gradient (its ``adjoint`` argument)
ADJOINTS = ("host", "traced")

#: stop reasons
CONVERGED, MAX_STEPS, SOLVE_FAILED = "gradient below tolerance", "maximum number of steps", "equilibrium failed"
#: how the cut was rounded (:attr:`DesignResult.rounding`)
NEAREST, INWARD = report.NEAREST, report.INWARD


@dataclasses.dataclass(repr=False)
class DesignResult:
    """An optimisation's outcome; ``print(result)`` shows it as tables (:func:`jaxnet.design.report.result_table`).

    theta: the optimised design, the best iterate: a :class:`~jaxnet.design.report.Design` of the families
    and entries that were optimised (``design(z)`` with a design map), in θ's units. value: its objective.
    x: (N, 3) its equilibrium (m). history: one dict per iteration (see the module docstring). reason: why
    the loop stopped. step: the iteration of the best iterate. start: the start design (the same entries as
    theta). z, z_start: the best and the start design vectors with a design map (None without).
    rounded: the whole design (every family) with its cut on whole meshes (None without a cut),
    rounded_value, rounded_violation: its objective and constraint violation, rounded_x its equilibrium,
    cut_report: per panel, its sides' meshes and cutting rates (:class:`jaxnet.design.cut.SideCut`), rounding:
    how the cut was made whole (:data:`NEAREST`, or :data:`INWARD` where the nearest whole meshes violate the
    constraints more than the optimum and the corners rounded outward taken one mesh in violate them less).
    """

    theta: dict
    value: float
    x: np.ndarray
    history: list
    reason: str
    step: int = 0
    start: dict | None = None
    z: Any = None
    z_start: Any = None
    rounded: dict | None = None
    rounded_value: float | None = None
    rounded_violation: float | None = None
    rounded_x: np.ndarray | None = None
    cut_report: dict | None = None
    rounding: str | None = None

    def __str__(self):
        return report.result_table(self)

    __repr__ = __str__

    def _repr_pretty_(self, printer, cycle):  # IPython and Jupyter's text output
        printer.text(str(self))


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


def _numpy_design(theta) -> Design:
    """θ as a :class:`Design` of numpy arrays, its families and entries in θ's order (the space's panel order,
    or the map's), where ``jax.tree.map`` would sort them."""
    return Design({family: {k: np.asarray(v) for k, v in entries.items()} if isinstance(entries, dict)
                   else np.asarray(entries) for family, entries in theta.items()})


def _json(tree):
    return jax.tree.map(lambda a: np.asarray(a).tolist(), tree)


def _where(path):
    """``start['foot']``, ``start[1]``: a leaf of the start named as the caller wrote it."""
    return "start" + jax.tree_util.keystr(path)


def _parameters(start):
    """The start as a pytree of float64 arrays, each checked finite (a ValueError naming the leaf); a
    :class:`Design` becomes a plain dict (the structure bounds and scales are written in)."""
    if isinstance(start, Design):
        start = dict(start)
    leaves, treedef = jax.tree_util.tree_flatten_with_path(start)
    if not leaves:
        raise ValueError("optimize: start holds no numbers to optimise")
    out = []
    for path, leaf in leaves:
        try:
            a = np.asarray(leaf, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(f"optimize: {_where(path)} is not a number or an array of numbers: {leaf!r}") from None
        bad = np.argwhere(~np.isfinite(a))
        if bad.size:
            at = f" at index {tuple(int(i) for i in bad[0])}" if a.ndim else ""
            raise ValueError(f"optimize: {_where(path)} is not finite{at} ({a.tolist()})")
        out.append(jnp.asarray(a))
    return jax.tree.unflatten(treedef, out)


def _scale(scale, p0, default):
    """The optimiser's unit per leaf of the parameters, checked: finite, >= 0 (0 holds a coordinate), shaped
    like (or broadcastable to) its leaf."""
    if scale is None:
        return default(p0)
    leaves, treedef = jax.tree_util.tree_flatten_with_path(p0)
    try:
        units = treedef.flatten_up_to(scale)
    except (ValueError, TypeError) as e:
        raise ValueError(f"optimize: scale does not match the structure of start: {e}") from None
    out = []
    for (path, leaf), unit in zip(leaves, units):
        u = np.asarray(unit, dtype=float)
        try:
            np.broadcast_to(u, leaf.shape)
        except ValueError:
            raise ValueError(f"optimize: the scale of {_where(path)} has shape {u.shape}, the parameter "
                             f"{leaf.shape}") from None
        if not np.all(np.isfinite(u)) or np.any(u < 0):
            raise ValueError(f"optimize: the scale of {_where(path)} must be finite and >= 0, got {u.tolist()}")
        out.append(jnp.broadcast_to(jnp.asarray(u), leaf.shape))
    return jax.tree.unflatten(treedef, out)


def _design_map(design, p0, space):
    """θ at the start, ``design(z0)``, checked: the map is traceable jnp code returning a partial θ that the
    space accepts (its ValueError, naming the family and the entry, prefixed with what was called)."""
    if not callable(design):
        raise ValueError(f"optimize: design must be a function z -> θ, got {type(design).__name__}")
    try:
        theta = design(p0)
    except (ValueError, TypeError, KeyError, IndexError) as err:
        raise ValueError(f"optimize: design(start) failed: {type(err).__name__}: {err}") from err
    if not isinstance(theta, dict):
        raise ValueError(f"optimize: design(start) must return a design θ (a dict of families), got "
                         f"{type(theta).__name__}")
    try:
        space.check(theta)
    except ValueError as err:
        raise ValueError(f"optimize: design(start) is not a valid design: {err}") from err
    try:  # traced once, not compiled: numpy code (no gradient) is refused here
        jax.eval_shape(design, p0)
    except jax.errors.ConcretizationTypeError as err:
        raise ValueError(f"optimize: design must be jnp code of z (it is differentiated): {err}") from None
    except jax.errors.TracerArrayConversionError as err:
        raise ValueError(f"optimize: design must be jnp code of z (it is differentiated), not numpy: {err}") from None
    return theta


def _rounded_inward(space, theta, nearest):
    """(θ, cut report) of ``nearest`` (θ rounded to the nearest whole meshes, :meth:`DesignSpace.rounded`) with
    every corner that rounded outward, away from corner 0 along u or v, moved one mesh back in: a cut on
    whole meshes no larger than the optimised one along u and v from corner 0; None when that changes nothing
    or makes a panel the space refuses (a degenerate polygon)."""
    from jaxnet.design import cut as cut_lib

    full = space.complete(theta)
    out = {family: dict(entries) for family, entries in nearest.items()}
    report, moved = {}, False
    for p in space.panels:
        whole = np.asarray(nearest["cut"][p], dtype=float)
        real = np.asarray(full["cut"][p], dtype=float)
        m_whole = np.asarray(cut_lib.twine_to_mesh(whole - whole[0]))
        m_real = np.asarray(cut_lib.twine_to_mesh(real - whole[0]))
        outward = np.abs(m_whole) > np.abs(m_real) + 1e-9
        outward[0] = False  # corner 0 is where the meshes are counted from
        if outward.any():
            moved = True
            m_whole = m_whole - np.where(outward, np.sign(m_whole), 0.0)
            whole = whole[0] + np.asarray(cut_lib.mesh_to_twine(m_whole))
        out["cut"][p] = jnp.asarray(whole)
        report[p] = cut_lib.describe_sides(whole)
    if not moved:
        return None
    try:
        space.check(out)
    except ValueError:
        return None
    return out, report


def optimize(space, objective, start, *, design: Callable | None = None, optimizer=None, steps=50, bounds=None,
             scale=None, solver: Newton | None = None, gtol=1e-6, backtracks=6, out=None, progress=True, x0=None,
             round_cut=True, adjoint="host") -> DesignResult:
    """Minimise ``objective`` over the design parameters of ``space``: θ itself, or a design vector z.

    Args:
      space: a :class:`jaxnet.design.space.DesignSpace`.
      objective: a figure (:mod:`jaxnet.design.objectives`): Outcome -> scalar, e.g.
        ``constraints.penalised(volume...)``; a figure with a ``violation`` (a penalised objective) reports it
        in the history.
      start: without ``design``, the starting design θ: the families and entries to optimise (a subset of
        ``space.initial()``), the others staying at the reference. With ``design``, the starting design vector
        z0: an array or a pytree (a dict of named parts) of floats.
      design: a map z -> θ (a partial θ, as :meth:`DesignSpace.complete
        <jaxnet.design.space.DesignSpace.complete>` takes it), jnp code: it is traced and differentiated
        (:mod:`jaxnet.design.reduced` has ready-made ones). None: θ is optimised directly.
      optimizer: an optax GradientTransformation (default ``optax.adam(0.05)`` on the scaled parameters);
        one that needs the value and a value function (``optax.lbfgs()``) gets them.
      steps: the most iterations. gtol: stop when the largest gradient component (scaled) is below it.
      bounds: :class:`jaxnet.design.constraints.Bounds` on what ``start`` is (θ in its units, or z), enforced by
        projection.
      scale: the optimiser's unit per leaf of ``start`` (default: :func:`default_scale` for θ, 1 for z; see the
        module docstring); 0 holds a coordinate.
      solver: the equilibrium solves' options (default :data:`jaxnet.solve.options.DIFFERENTIABLE`).
      backtracks: halvings of a step whose equilibrium does not converge before the loop stops.
      out: a directory for ``history.jsonl`` and ``design.json`` (written as the run goes); None for none.
      progress: a tqdm bar with the objective and the gradient norm.
      x0: (N, 3) start of the first solve; default: the static solver's equilibrium of the start design.
      round_cut: also solve and report the design rounded to whole meshes.
      adjoint: how each step's value and gradient are computed, the same numbers either way. ``"host"``
        (:mod:`jaxnet.design.gradient`): the static solver's Newton loop and the adjoint's pieces driven from
        Python, compiled in less time and kept between processes (a compilation cache directory set), each
        step some milliseconds of dispatch slower. ``"traced"``: ``jax.value_and_grad`` of one jitted program
        around :func:`jaxnet.solve.implicit.equilibrium`, its steps faster and its compilation longer, in every
        process (its host callbacks keep it out of any cache): for runs of hundreds of steps.
        ``benchmarks/design.py`` times both.
    Returns:
      a :class:`DesignResult`.
    Raises:
      ValueError before anything is compiled, naming the culprit: a start that is not finite numbers, a design
      map that fails, does not return a valid θ (the space's message: the family, the entry, the corner) or is
      not jnp code, a scale or bounds not shaped like the start, steps or backtracks < 0.
    """
    _check_options(steps, backtracks, gtol, adjoint)
    p0 = _parameters(start)
    if design is None:
        to_theta = lambda p: p  # noqa: E731
        space.check(p0)
        theta_start = p0
        scale = _scale(scale, p0, default_scale)
    else:
        to_theta = design
        theta_start = _design_map(design, p0, space)
        scale = _scale(scale, p0, lambda p: jax.tree.map(jnp.ones_like, p))
    bounds = bounds or constraints_lib.Bounds()
    bounds.violation(p0)  # a bound not shaped like the start: its ValueError, now
    structure = implicit.structure_of(space.reference)
    model = structure.model
    optimizer = optimizer or optax.adam(0.05)
    solver = solver or DIFFERENTIABLE
    out = None if out is None else pathlib.Path(out)
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        (out / "history.jsonl").write_text("")

    def parameters(w):
        """The parameters (θ or z) of the optimiser's variables w = (p - p₀) / s."""
        return jax.tree.map(lambda a0, s, ww: a0 + s * ww, p0, scale, w)

    def loss(w, x_start):
        """The objective through the traced equilibrium (jaxnet.solve.implicit), and (x, status, iterations,
        violation)."""
        scene = space.scene(to_theta(parameters(w)))
        eq = implicit.equilibrium(scene, structure, x0=x_start, solver=solver, throw=False)
        o = objectives_lib.Outcome(eq.x, scene, model)
        return objective(o), (eq.x, eq.status, eq.iterations, gradient_lib.violation(objective, o))

    sensitivity = gradient_lib.Sensitivity(space, objective, solver)
    # the gradient in w from the gradient in θ: the reverse mode of w -> θ (the scale, and the design map)
    chain = programs.jit(lambda w, g: jax.vjp(lambda ww: to_theta(parameters(ww)), w)[1](g)[0])
    extra = isinstance(optimizer, optax.GradientTransformationExtraArgs)
    # an optimiser with a line search (L-BFGS) calls the value function inside its update: one compiled update,
    # the warm start an argument (a fresh closure per step would recompile the line search every step); that
    # value function is the jitted differentiable equilibrium (jaxnet.solve.implicit), the host-driven one
    # being no JAX function
    extra_update = programs.jit(lambda g, state, w, value, x_start: optimizer.update(
        g, state, w, value=value, grad=g, value_fn=lambda ww: loss(ww, x_start)[0]))
    traced = programs.jit(jax.value_and_grad(loss, has_aux=True))

    def evaluate(w, x_start):
        if adjoint == "traced":
            (value, (x, status, iterations, violation)), g = traced(w, x_start)
            ok = int(status) == results.CONVERGED and bool(jnp.isfinite(value))
            return ok, float(value), g, np.asarray(x), int(iterations), float(violation)
        theta = to_theta(parameters(w))
        e = sensitivity.value_and_grad(theta, x_start)
        ok = e.converged and math.isfinite(e.value)
        if not ok:
            return False, e.value, None, e.x, e.iterations, e.violation
        g_theta = jax.tree.map(lambda t, g: jnp.asarray(g, dtype=jnp.result_type(t)).reshape(jnp.shape(t)), theta,
                               e.grad)
        return True, e.value, chain(w, g_theta), e.x, e.iterations, e.violation

    def flat(tree):
        return [float(v) for leaf in jax.tree.leaves(tree) for v in np.ravel(leaf)]

    t_start = time.perf_counter()
    if x0 is None:  # the static solver's continuation from the flat net, polished by the first evaluation
        x0 = np.asarray(statics.solve(space.scene(theta_start)).x)
    w = jax.tree.map(jnp.zeros_like, p0)
    ok, value, g, x, iterations, violation = evaluate(w, x0)
    if not ok:
        raise implicit.ImplicitError("optimize: the equilibrium of the start design does not converge")
    state = optimizer.init(w)
    history, reason = [], MAX_STEPS
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(total=steps, desc="design", unit="step")
    best = (value, w, x, 0)
    for k in range(steps + 1):
        g_norm = float(max(jnp.max(jnp.abs(leaf)) for leaf in jax.tree.leaves(g)))
        p = parameters(w)
        row = dict(step=k, objective=value, violation=violation + float(bounds.violation(p)),
                   gradient_norm=g_norm, newton_iterations=iterations, wall_s=time.perf_counter() - t_start)
        if design is not None:
            row["z"] = flat(p)
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
            updates, new_state = extra_update(g, state, w, value, x)
        else:
            updates, new_state = optimizer.update(g, state, w)
        for _ in range(backtracks + 1):
            w_new = optax.apply_updates(w, updates)
            # bounds in the parameters' units, then back to the optimiser's
            w_new = jax.tree.map(lambda a, a0, s: jnp.where(s > 0, (a - a0) / jnp.where(s > 0, s, 1.0), 0.0),
                                 bounds.project(parameters(w_new)), p0, scale)
            trial = evaluate(w_new, x)
            if trial[0]:
                break
            updates = jax.tree.map(lambda u: 0.5 * u, updates)
        else:
            reason = SOLVE_FAILED
            break
        w, state = w_new, new_state
        _, value, g, x, iterations, violation = trial
        if value < best[0]:
            best = (value, w, x, k + 1)
    if bar is not None:
        bar.close()
    # the best design seen: optimisers without a line search (Adam) need not end on their best iterate
    value, w, x, step = best
    p = jax.tree.map(np.asarray, parameters(w))
    theta = to_theta(parameters(w))
    result = DesignResult(theta=_numpy_design(theta), value=value, x=x, history=history, reason=reason, step=step,
                          start=_numpy_design(theta_start))
    if design is not None:
        result.z, result.z_start = p, jax.tree.map(np.asarray, p0)
    if round_cut and "cut" in theta_start:
        optimised = None if design is not None else p0  # the bounds are on θ: a rounded θ is measured against them
        rounded, figures, result.rounding, result.cut_report = _rounded_cut(
            space, sensitivity, theta, x, bounds, optimised, history[step]["violation"])
        result.rounded = _numpy_design(rounded)
        result.rounded_value, result.rounded_violation, result.rounded_x = figures
    if out is not None:
        _write_design(out / "design.json", result)
    return result


def _check_options(steps, backtracks, gtol, adjoint):
    """ValueError naming the option of :func:`optimize` out of its range, before anything is compiled."""
    if not (isinstance(steps, (int, np.integer)) and steps >= 0):
        raise ValueError(f"optimize: steps must be a whole number >= 0, got {steps!r}")
    if not (isinstance(backtracks, (int, np.integer)) and backtracks >= 0):
        raise ValueError(f"optimize: backtracks must be a whole number >= 0, got {backtracks!r}")
    if not math.isfinite(float(gtol)) or gtol < 0:
        raise ValueError(f"optimize: gtol must be a finite number >= 0, got {gtol!r}")
    if adjoint not in ADJOINTS:
        raise ValueError(f"optimize: adjoint must be one of {ADJOINTS}, got {adjoint!r}")


def _rounded_cut(space, sensitivity, theta, x, bounds, optimised, violation):
    """The optimum ``theta`` cut to whole meshes and re-solved from its equilibrium ``x``: (rounded θ, (objective,
    constraint violation, positions), rounding, cut report). The nearest whole meshes first; where they violate
    the constraints more than the optimum did (``violation``: they need more netting than it had room for), the cut
    with the corners that rounded outward taken one mesh in, if that does better. ``optimised``: the optimised
    families and entries of θ, whose ``bounds`` a rounded θ is measured against (None: the bounds are on a design
    vector z, which a rounded θ does not have)."""
    def solved(rounded):
        """(objective, constraint violation, equilibrium) of a rounded design, re-solved."""
        e = sensitivity.value(rounded, x)
        if not e.converged:  # the static solver's continuation, from the optimum's shape
            e = sensitivity.value(rounded, statics.solve(space.scene(rounded), x0=x).x)
        if not e.converged:
            raise implicit.ImplicitError(f"optimize: the rounded design's equilibrium: {e.reason} after "
                                         f"{e.iterations} iterations ({e.residual_N:.3g} N at node {e.worst_node})")
        excess = e.violation
        if optimised is not None:
            excess += float(bounds.violation({family: {k: rounded[family][k] for k in entries}
                                              for family, entries in optimised.items()}))
        return e.value, excess, e.x

    rounded, cut_report = space.rounded(theta)
    figures, rounding = solved(rounded), NEAREST
    if figures[1] > violation + 1e-12:
        inward = _rounded_inward(space, theta, rounded)
        try:
            inward_figures = None if inward is None else solved(inward[0])
        except (implicit.ImplicitError, results.SolveError):
            inward_figures = None  # a candidate whose equilibrium fails is not the design to cut
        if inward_figures is not None and inward_figures[1] < figures[1]:
            (rounded, cut_report), figures, rounding = inward, inward_figures, INWARD
    return rounded, figures, rounding, cut_report


def _write_design(path, result):
    """``design.json``: the run's end (reason, objective, step), its design θ (and z), and its cut to whole
    meshes with how it was rounded."""
    path.write_text(json.dumps(dict(
        reason=result.reason, objective=result.value, step=result.step, theta=_json(result.theta),
        z=None if result.z is None else _json(result.z),
        rounded=None if result.rounded is None else _json(result.rounded),
        rounded_objective=result.rounded_value, rounded_violation=result.rounded_violation,
        rounding=result.rounding,
        cut_report=None if result.cut_report is None else {p: [str(s) for s in sides] for p, sides in
                                                            result.cut_report.items()}), indent=1))
