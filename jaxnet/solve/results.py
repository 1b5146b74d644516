"""What a Newton solve returns: the :class:`Equilibrium`, its stop reasons, its timing, and its error.

One result per kind of solve: a static solve (:func:`jaxnet.solve.statics.solve`), the jittable iteration
(:func:`jaxnet.solve.newton.newton_loop`) and the differentiable equilibrium
(:func:`jaxnet.solve.implicit.equilibrium`) all return an :class:`Equilibrium`; a dynamic run returns a
:class:`jaxnet.solve.dynamics.Trajectory`. Each says how it stopped by a status code (an int, also inside
traced code) that :data:`REASONS` names, and carries its :class:`Timing` where the host timed it.

Units: m, N, J, s.
"""

from __future__ import annotations

import dataclasses

import equinox as eqx
import jax
import numpy as np

#: stop reasons of a Newton solve (``Equilibrium.status``), ints: compared and selected inside traced code
RUNNING, CONVERGED, MAX_ITERATIONS, NON_FINITE, STALLED = 0, 1, 2, 3, 4
REASONS = {
    CONVERGED: "converged",
    MAX_ITERATIONS: "maximum number of iterations reached",
    NON_FINITE: "non-finite force or energy (NaN/inf)",
    STALLED: "no step decreases the energy even with maximal damping (singular or inconsistent problem)",
    RUNNING: "running",
}


@dataclasses.dataclass(frozen=True)
class Timing:
    """Wall times of a solve on the host (s), and what its iterations did. Frozen (hashable): a static field
    of the results that hold it.

    compile_s: obtaining the compiled programs (~0 when a program compiled for a scene of the same shape and
      terms is reused; for a dynamic run, the first record interval, which compiles and runs).
    wall_s: the whole call, compilation included.
    The static solve's host loop (:func:`jaxnet.solve.statics.host_loop`) also splits its own time, where
    the others leave these at 0:
    assembly_s: computing the tangents (element matrices on the device and their sum into the pattern).
    factorisation_s: factorising and solving with them on the host (:func:`jaxnet.linalg.direct_solver`:
      ordering, factors, the triangular solves and their accuracy checks).
    evaluation_s: evaluating the residual (once per line-search trial, and at the start).
    factorisations, evaluations: how many of each the solve made.
    fallbacks: factorisations redone by SuperLU with partial pivoting (:class:`jaxnet.linalg.HostSolver`'s
      ``fallbacks``: the first factor of a nearly singular tangent perturbed a pivot or left a solution
      inaccurate); each costs several times a PARDISO factorisation at 10⁵ nodes.
    The rest of ``wall_s`` less ``compile_s`` is the loop's own bookkeeping on the host.
    """

    compile_s: float
    wall_s: float
    assembly_s: float = 0.0
    factorisation_s: float = 0.0
    evaluation_s: float = 0.0
    factorisations: int = 0
    evaluations: int = 0
    fallbacks: int = 0

    @property
    def factorisation_each_s(self):
        """The mean time of one factorisation and its solve (s); NaN where the solve made none."""
        return self.factorisation_s / self.factorisations if self.factorisations else float("nan")


class Equilibrium(eqx.Module):
    """Result of a static solve (or of one implicit time step's Newton iteration).

    x: (N, 3) node positions (m). force: (N, 3) out-of-balance force (N); at fixed coordinates it is
    minus the reaction. residual_N: largest nodal out-of-balance force on free coordinates (N).
    iterations: Newton iterations. status: stop reason code (see :data:`REASONS`). worst_node: node with
    the largest residual. history: (max_iter + 1,) residual at each iteration (NaN after the last).
    energy: the potential energy (J) at x, the non-conservative forces frozen there.
    timing: the host's :class:`Timing` of the solve (:func:`jaxnet.solve.statics.solve`), None where it
    was not timed (a traced solve).
    """

    x: jax.Array
    force: jax.Array
    residual_N: jax.Array
    iterations: jax.Array
    status: jax.Array
    worst_node: jax.Array
    history: jax.Array
    energy: jax.Array
    timing: Timing | None = eqx.field(static=True, default=None)

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


class SolveError(RuntimeError):
    """A static solve failed; ``.equilibrium`` holds the last state reached."""

    def __init__(self, message, equilibrium):
        super().__init__(message)
        self.equilibrium = equilibrium
