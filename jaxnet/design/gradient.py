"""The value and gradient of a design objective at equilibrium, in θ, by the host-driven adjoint.

    J(θ) = objective(outcome(x*(θ), scene(θ))),     dJ/dθ = (∂J/∂scene + λᵀ ∂F/∂scene) · d scene/dθ

with Kᵀλ = ∂J/∂x at the equilibrium x* (:mod:`jaxnet.solve.adjoint_statics`) and the design map's reverse mode
(:meth:`jaxnet.design.space.DesignSpace.pullback`). Every piece is a compiled program without host callbacks:
the static solver's, the residual's reverse mode, the objective's and the design map's. So they are compiled
once per design space and objective in a process and, with a compilation cache directory set (``jaxnet run``
sets one; :func:`jaxnet.design.sweep.sweep` gives its workers one), loaded by the next process instead of
compiled again. This is what :func:`jaxnet.design.optimize.optimize` calls at each step.

``jax.grad`` of a function of :func:`jaxnet.solve.implicit.equilibrium` gives the same derivative, inside a
caller's ``jit``/``vmap`` and for any function of the equilibrium; its program holds the sparse solve's host
callbacks, which no persistent cache keeps. ``benchmarks/design.py`` compiles and runs both.

Units: the objective's, per unit of each entry of θ (:data:`jaxnet.design.space.FAMILIES`).
"""

from __future__ import annotations

import dataclasses
import weakref
from typing import Any

import equinox as eqx
import jax.numpy as jnp
import numpy as np

from jaxnet.design import objectives as objectives_lib
from jaxnet.solve import adjoint_statics
from jaxnet.solve.options import Newton
from jaxnet.solve.results import CONVERGED, REASONS

__all__ = ["Evaluation", "Sensitivity", "value_and_grad", "violation"]


def violation(objective, outcome):
    """The constraint violation of ``objective`` at ``outcome`` (0 for an objective without constraints:
    :class:`jaxnet.design.constraints.Penalised` has them)."""
    return objective.violation(outcome) if hasattr(objective, "violation") else jnp.asarray(0.0)


class _OnPositions(eqx.Module):
    """A design objective as a figure of (positions, scene) for :class:`jaxnet.solve.adjoint_statics.Adjoint`:
    J, and the constraint violation beside it."""

    objective: Any
    model: tuple = eqx.field(static=True)

    def __call__(self, x, scene):
        outcome = objectives_lib.Outcome(x, scene, self.model)
        return self.objective(outcome), violation(self.objective, outcome)


@dataclasses.dataclass(frozen=True)
class Evaluation:
    """A design evaluated at its equilibrium.

    value: the objective J (NaN when the equilibrium did not converge). violation: its constraints' violation.
    grad: dJ/dθ shaped as the θ given (its families and entries), or None (a value only, or no equilibrium).
    x: (N, 3) equilibrium positions (m). status, reason, iterations, residual_N, worst_node: the forward
    solve's (:mod:`jaxnet.solve.results`). adjoint_residual: the adjoint solve's relative residual.
    """

    value: float
    violation: float
    grad: dict | None
    x: np.ndarray
    status: int
    iterations: int
    residual_N: float
    worst_node: int
    adjoint_residual: float = 0.0

    @property
    def converged(self) -> bool:
        return self.status == CONVERGED

    @property
    def reason(self) -> str:
        return REASONS[self.status]


_ADJOINTS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()  # design space -> {solver: Adjoint}


class Sensitivity:
    """The objective's value and gradient over a design space (one per space and objective; its compiled
    programs shared by every instance of the same space, objective structure and solver).

    Args:
      space: a :class:`~jaxnet.design.space.DesignSpace`.
      objective: a figure of :mod:`jaxnet.design.objectives` (or a constrained objective of
        :mod:`jaxnet.design.constraints`): a pytree called on an :class:`~jaxnet.design.objectives.Outcome`.
      solver: the forward solve's options; default :data:`jaxnet.solve.options.DIFFERENTIABLE`.
    """

    def __init__(self, space, objective, solver: Newton | None = None):
        self.space, self.objective = space, objective
        by_solver = _ADJOINTS.setdefault(space, {})
        if solver not in by_solver:
            by_solver[solver] = adjoint_statics.Adjoint(space.reference, solver)
        self.adjoint = by_solver[solver]
        self._figure = _OnPositions(objective, self.adjoint.model)

    def value(self, theta, x0=None) -> Evaluation:
        """The objective at the equilibrium of design θ (checked first), solved from ``x0`` ((N, 3) m; default
        the reference's positions: start near the answer, e.g. the last design's equilibrium)."""
        value, extra, eq = self.adjoint.value(self._figure, self.space.scene(theta), x0)
        return self._evaluation(value, extra, None, eq)

    def value_and_grad(self, theta, x0=None) -> Evaluation:
        """The objective and its gradient in θ (shaped as the θ given) at the equilibrium of design θ, solved
        from ``x0``. Where the equilibrium does not converge, ``value`` is NaN and ``grad`` None."""
        result = self.adjoint.value_and_grad(self._figure, self.space.scene(theta), x0)
        if result.grad is None:
            return self._evaluation(result.value, None, None, result.equilibrium)
        full = self.space.pullback(theta, result.grad)
        grad = {family: {k: full[family][k] for k in entries} for family, entries in theta.items()}
        return self._evaluation(result.value, result.aux, grad, result.equilibrium, result.adjoint_residual)

    @staticmethod
    def _evaluation(value, extra, grad, eq, adjoint_residual=0.0):
        return Evaluation(value=float(value), violation=float("nan") if extra is None else float(extra), grad=grad,
                          x=np.asarray(eq.x), status=int(eq.status), iterations=int(eq.iterations),
                          residual_N=float(eq.residual_N), worst_node=int(eq.worst_node),
                          adjoint_residual=adjoint_residual)


def value_and_grad(space, objective, theta, x0=None, solver: Newton | None = None) -> Evaluation:
    """The objective and its gradient in θ at the equilibrium of design θ: :meth:`Sensitivity.value_and_grad`."""
    return Sensitivity(space, objective, solver).value_and_grad(theta, x0)
