"""Objectives and constraints of a net design, made of figures (:mod:`jaxnet.design.objectives`), and bounds on
its parameters.

  * :func:`weighted`: a weighted sum of named figures;
  * :class:`Constraint`: lower <= figure <= upper, with its violation and its exterior penalty;
  * :func:`penalised`: objective + weight × Σ penalties (the exterior penalty method);
  * :class:`Bounds`: box bounds on a pytree of design parameters, with projection and violation.

Each is a figure again (a callable of an :class:`~jaxnet.design.objectives.Outcome`) or, for the bounds, a
function of θ; all are pytrees whose numbers may be traced. Bad settings raise ValueError naming them.
"""

from __future__ import annotations

from typing import Any, Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet.design.objectives import Figure, Outcome, finite_number


class Weighted(Figure):
    """Σ weight × figure; see :func:`weighted`."""

    figures: dict
    weights: dict

    def __call__(self, o: Outcome):
        return sum(self.weights[k] * self.figures[k](o) for k in sorted(self.figures))

    def parts(self, o: Outcome) -> dict:
        """Each named figure's value (unweighted), for reports and histories."""
        return {k: self.figures[k](o) for k in sorted(self.figures)}


def weighted(**parts) -> Weighted:
    """A weighted sum of named figures: ``weighted(drag=(1.0, drag()), cost=(0.1, material(2.5)))``; a bare
    figure has weight 1. Weights are leaves (traceable); mind the units (N + kg: the weight converts)."""
    if not parts:
        raise ValueError("weighted: give at least one figure")
    figures, weights = {}, {}
    for name, part in parts.items():
        w, f = part if isinstance(part, tuple) else (1.0, part)
        if not callable(f):
            raise ValueError(f"weighted: {name} is not a figure (a callable of an Outcome): {f!r}")
        figures[name], weights[name] = f, finite_number(w, f"weighted: weight of {name}")
    return Weighted(figures, weights)


class Constraint(Figure):
    """lower ≤ figure ≤ upper (None: that side is free); called, it gives its penalty.

    figure: any figure; lower, upper: bounds in the figure's units; scale: a typical size of a violation,
    in the same units, making penalties of different units comparable (1 by default).
    """

    figure: Callable
    lower: float | None = None
    upper: float | None = None
    scale: float = 1.0

    def __check_init__(self):
        if not callable(self.figure):
            raise ValueError(f"Constraint: figure is not a callable of an Outcome: {self.figure!r}")
        if self.lower is None and self.upper is None:
            raise ValueError("Constraint: give lower, upper or both")
        lo = None if self.lower is None else finite_number(self.lower, "Constraint: lower")
        hi = None if self.upper is None else finite_number(self.upper, "Constraint: upper")
        if isinstance(lo, float) and isinstance(hi, float) and lo > hi:
            raise ValueError(f"Constraint: lower {lo} > upper {hi}")
        finite_number(self.scale, "Constraint: scale", positive=True)

    def value(self, o: Outcome):
        return self.figure(o)

    def violation(self, o: Outcome):
        """How far outside [lower, upper] the figure is (its units, >= 0; 0 when satisfied)."""
        v = self.figure(o)
        out = jnp.zeros_like(v)
        if self.lower is not None:
            out = out + jnp.maximum(self.lower - v, 0.0)
        if self.upper is not None:
            out = out + jnp.maximum(v - self.upper, 0.0)
        return out

    def penalty(self, o: Outcome):
        """Exterior quadratic penalty (violation / scale)², dimensionless: 0 inside, C¹ at the bounds."""
        return (self.violation(o) / self.scale) ** 2

    def __call__(self, o: Outcome):
        return self.penalty(o)


class Penalised(Figure):
    """objective + weight × Σ penalties; see :func:`penalised`."""

    objective: Callable
    constraints: tuple
    weight: float

    def __call__(self, o: Outcome):
        return self.objective(o) + self.weight * sum(c.penalty(o) for c in self.constraints)

    def violation(self, o: Outcome):
        """Σ violation / scale over the constraints (dimensionless, 0 when all are met), for histories."""
        return sum(c.violation(o) / c.scale for c in self.constraints)


def penalised(objective, constraints, weight=1.0) -> Penalised:
    """The exterior penalty method: objective(o) + weight × Σ_c (violation_c / scale_c)². Raise ``weight``
    over an optimisation to drive the violations to 0 (the minimiser of a fixed weight violates by O(1/weight))."""
    constraints = tuple(constraints) if not isinstance(constraints, Constraint) else (constraints,)
    bad = [c for c in constraints if not isinstance(c, Constraint)]
    if bad:
        raise ValueError(f"penalised: constraints must be Constraint objects, got {bad[0]!r}")
    if not callable(objective):
        raise ValueError(f"penalised: objective is not a figure: {objective!r}")
    return Penalised(objective, constraints, finite_number(weight, "penalised: weight", nonnegative=True))


# -- bounds on design parameters -----------------------------------------------------------------


def _one_for_all(bound):
    """None or a single number: the same bound for every leaf of θ."""
    return bound is None or isinstance(bound, (int, float, np.number)) or (
        isinstance(bound, (np.ndarray, jax.Array)) and bound.ndim == 0)


class Bounds(eqx.Module):
    """Box bounds on a pytree θ of design parameters (e.g. the design of :mod:`jaxnet.design.space`).

    lower, upper: None (unbounded), a number (the same for every leaf of θ), or a pytree of θ's structure
    whose leaves are None (that leaf unbounded), numbers or arrays broadcastable to the leaf; where θ has a
    dict, the bound's dict may leave keys out (unbounded) or give one number for a whole subtree, e.g.
    ``Bounds(lower={"twine": {"diameter": 1e-3}}, upper=1e6)`` for θ = {"cut": ..., "twine": {...}}.
    """

    lower: Any = None
    upper: Any = None

    def __check_init__(self):
        for name in ("lower", "upper"):
            for path, leaf in jax.tree_util.tree_flatten_with_path(getattr(self, name))[0]:
                if not isinstance(leaf, jax.core.Tracer) and np.any(np.isnan(np.asarray(leaf, dtype=float))):
                    raise ValueError(f"Bounds: {name}{jax.tree_util.keystr(path)} is NaN")

    def _pairs(self, theta):
        """Per leaf of θ: (path name, leaf, lower or None, upper or None), checked."""
        paths_leaves, treedef = jax.tree_util.tree_flatten_with_path(theta)

        def complete(bound, part, name, path=""):
            """The bound spread over θ's subtree ``part``: a number or None for all of its leaves, dicts key by key."""
            if _one_for_all(bound):
                return jax.tree.map(lambda _: bound, part)
            if isinstance(bound, dict) and isinstance(part, dict):
                extra = sorted(set(bound) - set(part), key=str)
                if extra:
                    raise ValueError(f"Bounds: {name}{path}{extra} are not design parameters (θ{path} has "
                                     f"{sorted(part, key=str)})")
                return {k: complete(bound.get(k), v, name, f"{path}[{k!r}]") for k, v in part.items()}
            return bound

        def per_leaf(bound, name):
            try:
                return treedef.flatten_up_to(complete(bound, theta, name))
            except (ValueError, TypeError) as e:
                if str(e).startswith("Bounds:"):
                    raise
                raise ValueError(f"Bounds: {name} does not match the structure of the design parameters: {e}") from None

        out = []
        for (path, leaf), lo, hi in zip(paths_leaves, per_leaf(self.lower, "lower"), per_leaf(self.upper, "upper")):
            where = jax.tree_util.keystr(path) or "θ"
            for b, side in ((lo, "lower"), (hi, "upper")):
                if b is not None:
                    try:
                        np.broadcast_shapes(np.shape(b), np.shape(leaf))
                    except ValueError:
                        raise ValueError(f"Bounds: {side} bound of {where} has shape {np.shape(b)}, the parameter "
                                         f"{np.shape(leaf)}") from None
            concrete = not any(isinstance(b, jax.core.Tracer) for b in (lo, hi))
            if lo is not None and hi is not None and concrete and np.any(np.asarray(lo) > np.asarray(hi)):
                raise ValueError(f"Bounds: lower > upper for {where}")
            out.append((where, leaf, lo, hi))
        return out, treedef

    def project(self, theta):
        """θ clipped into the box, leaf by leaf (the projection of projected-gradient methods)."""
        pairs, treedef = self._pairs(theta)
        leaves = []
        for _, leaf, lo, hi in pairs:
            v = jnp.asarray(leaf)
            if lo is not None:
                v = jnp.maximum(v, lo)
            if hi is not None:
                v = jnp.minimum(v, hi)
            leaves.append(v)
        return jax.tree.unflatten(treedef, leaves)

    def violation(self, theta):
        """Σ over all entries of θ of the distance outside the box (θ's units, >= 0; 0 inside)."""
        total = 0.0
        for _, leaf, lo, hi in self._pairs(theta)[0]:
            v = jnp.asarray(leaf)
            if lo is not None:
                total = total + jnp.sum(jnp.maximum(lo - v, 0.0))
            if hi is not None:
                total = total + jnp.sum(jnp.maximum(v - hi, 0.0))
        return jnp.asarray(total)
