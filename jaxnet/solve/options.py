"""The solvers' options and every default of them, written once.

:class:`Newton` configures the damped Newton iteration (:mod:`jaxnet.solve.newton`) wherever it runs: the
static solve (:func:`jaxnet.solve.statics.solve`), each implicit time step (:class:`Implicit`,
:mod:`jaxnet.solve.dynamics`) and the differentiable equilibrium (:mod:`jaxnet.solve.implicit`). These
differ in what they need from it, hence three presets:

* :data:`STATIC`: the static solve from a drawn (often flat, stress-free) net: the primal-dual method, the
  damped one with its stiffness continuation where it stops short, converged to FEMNET's threshold :data:`TOL_N`.
* :data:`TIME_STEP`: one implicit time step: the inertia (M + M_a)/Δt² on the tangent's diagonal makes it
  regular, and the step starts at the constant-velocity prediction, close to its answer: the damped method,
  nearly undamped, no continuation, few iterations (a step that needs more is better halved).
* :data:`DIFFERENTIABLE`: the forward solve of a differentiable equilibrium: pure Newton steps near the
  root (no continuation: it is the jittable iteration), converged far below :data:`TOL_N`, because the
  derivative by the implicit function theorem is only as good as the root.

Both option classes are frozen dataclasses, hashable: part of the identity of a compiled program
(:mod:`jaxnet.solve.programs`), so each is checked here, before anything compiles.

Units: N, m, s; damping dimensionless.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.model import STIFFNESS_PATHS

#: the static iterations (:attr:`Newton.method`): ``"damped"``, the damped Newton on the energy
#: (:mod:`jaxnet.solve.newton`); ``"primal-dual"``, the interior-point Newton on the tension form of the tension-only
#: rods (:mod:`jaxnet.solve.interior`)
METHODS = ("damped", "primal-dual")

#: FEMNET's convergence threshold (N): the largest nodal out-of-balance force over the free coordinates
#: at which a static solve or a time step has converged (:attr:`Newton.tol`'s default)
TOL_N = 1e-3


@dataclasses.dataclass(frozen=True)
class Newton:
    """Options of the damped Newton iteration (hashable: part of the compiled program's identity).

    tol: convergence threshold on the largest nodal out-of-balance force (N).
    max_iter: maximum number of Newton iterations (factorisations).
    max_step: largest displacement of any node in one iteration (m); inf for none.
    damping: initial damping mu, the fictitious prestrain of the spring-network metric (dimensionless).
    min_damping, max_damping: bounds of mu.
    line_search: maximum number of step halvings per iteration.
    stall_window: the stiffness continuation starts when the best residual of the last ``stall_window``
      iterations is not half the best before them (0: from the first iteration; None: never).
    soften_below: ... and the iterates' twines pull far harder than the loads: the elastic scale that best
      balances the loads there (:func:`jaxnet.solve.newton.balancing_scale`, median over the window) is
      below this.
    soft_start: the first stage's factor on the elastic energies (dimensionless, in (0, 1)).
    stiffening: the factor between consecutive stages (> 1).
    stage_rtol: a stage ends when the residual is this fraction of the residual it started with (or the
      tolerance ``tol``); the last stage (the net as it is) ends at ``tol``.
    stiffness: the tangent's path, ``"closed_form"`` (the default: the hand-derived stiffness of
      :mod:`jaxnet.closed_form` where a term has one, autodiff for the others) or ``"autodiff"``
      (``jax.jacfwd`` of every term). Both are the same matrix to rounding (tested per element and on whole
      solves), and the answer does not depend on it: the residual is always the energies' gradient and the
      forces themselves, only the steps towards it are the tangent's. The closed forms are the default
      because they are cheaper to compile and to run (``benchmarks/femnet_cases.py`` times whole solves
      with either, ``benchmarks/stiffness.py`` the element matrices).
    verbose: print one line per iteration.
    method: the static iteration, one of :data:`METHODS`: ``"primal-dual"`` (the default: the tension and gap of
      every tension-only twine and bar as unknowns, an interior-point Newton, :mod:`jaxnet.solve.interior`; where
      it has not converged after its budget, the damped method from the start; a scene without such rods, or
      with a catch, is solved by the damped method: :func:`jaxnet.solve.interior.suits`) or ``"damped"``
      (Levenberg-Marquardt damping, the energy line search and the stiffness continuation,
      :mod:`jaxnet.solve.newton`). The damping and continuation fields are the damped method's; ``tol``,
      ``max_iter`` (each method's own), ``line_search`` and ``max_step`` serve both.

    The jittable iteration (:func:`jaxnet.solve.newton.newton_loop`: time steps, the differentiable
    equilibrium) is the damped one whatever ``method`` says, without the stiffness continuation: there the
    continuation's fields are unused.
    """

    tol: float = TOL_N
    max_iter: int = 500
    max_step: float = float("inf")
    damping: float = 1e-3
    min_damping: float = 1e-12
    max_damping: float = 1e8
    line_search: int = 30
    stall_window: int | None = 5
    soften_below: float = 1e-3
    soft_start: float = 1e-2
    stiffening: float = 10**0.5
    stage_rtol: float = 1e-2
    stiffness: str = "closed_form"
    verbose: bool = False
    method: str = "primal-dual"

    def __post_init__(self):
        if self.method not in METHODS:
            raise ValueError(f"Newton: method must be one of {METHODS}, not {self.method!r}")
        if self.stiffness not in STIFFNESS_PATHS:
            raise ValueError(f"Newton: stiffness must be one of {STIFFNESS_PATHS}, not {self.stiffness!r}")
        # refused here, before anything compiles: tol <= 0 would run to max_iter and report a failure that is
        # the caller's, max_iter 0 would compile a solve that cannot take a step
        if not (np.isfinite(self.tol) and self.tol > 0):
            raise ValueError(f"Newton: tol (N) must be finite and > 0, got {self.tol!r}")
        if isinstance(self.max_iter, bool) or int(self.max_iter) != self.max_iter or self.max_iter < 1:
            raise ValueError(f"Newton: max_iter must be an integer >= 1, got {self.max_iter!r}")
        if not self.max_step > 0:
            raise ValueError(f"Newton: max_step (m) must be > 0 (inf for no limit), got {self.max_step!r}")
        if self.line_search < 0:
            raise ValueError(f"Newton: line_search (halvings) must be >= 0, got {self.line_search!r}")
        if not (0 < self.min_damping <= self.damping <= self.max_damping):
            raise ValueError(f"Newton: damping must lie in [min_damping, max_damping] with min_damping > 0, got "
                             f"{self.min_damping!r} <= {self.damping!r} <= {self.max_damping!r}")


#: the static solve's options (:func:`jaxnet.solve.statics.solve`): the class defaults
STATIC = Newton()

#: each implicit time step's Newton (:attr:`Implicit.newton`'s default): nearly undamped (inertia makes the
#: step's tangent regular), without the static continuation, at most 30 iterations (a step that needs more
#: is halved, :mod:`jaxnet.solve.dynamics`), and with the hand-derived stiffness where a term has one (the
#: class default, chosen for time steps as much as for statics): a time step is a few iterations, so the
#: tangent is a large part of its cost, and the moving drag's autodiff tangent (jacfwd through the drag
#: computed once per vertex) most of it; the drag, which depends on the velocities here, takes its closed
#: form where the assembly hands it the vertices' velocities (:meth:`jaxnet.model.ActiveTerm.has_closed_form`).
#: ``benchmarks/dynamics.py`` measures both paths.
TIME_STEP = Newton(tol=TOL_N, max_iter=30, damping=1e-12, stall_window=None, line_search=20, method="damped")

#: the differentiable equilibrium's forward solve (:func:`jaxnet.solve.implicit.equilibrium`, the design
#: studies, :mod:`jaxnet.solve.adjoint_dynamics`): pure Newton steps near the root, converged to 1e-8 N
DIFFERENTIABLE = Newton(tol=1e-8, max_iter=200, damping=1e-6, stall_window=None, line_search=30, method="damped")


#: who drives a run's time steps (:attr:`Implicit.loop`)
LOOPS = ("auto", "host", "compiled")

#: ``loop="auto"`` takes the compiled loop for a run of more steps than this still to take: the host loop's
#: extra cost a step then outweighs the compiled loop's compilation in every process (both measured by
#: ``benchmarks/dynamics_loops.py`` on the cage in waves and the seine s4: ``validation/REPORT.md``)
AUTO_COMPILED_STEPS = 1500


@dataclasses.dataclass(frozen=True)
class Implicit:
    """Options of the implicit time stepping (hashable). Only ``newton`` is part of the compiled program's
    identity: the steps are arguments, so a study over Δt compiles once.

    time_step: Δt (s), the step the run takes when Newton converges.
    min_time_step: the smallest step a failed step may be retried with (s); below it the run stops.
    newton: the options of each step's Newton iteration (:class:`Newton`); default :data:`TIME_STEP`.
    loop: who drives the steps, the same steps either way. ``"host"``: Python, each step's Newton the static
      solver's host loop (:class:`jaxnet.solve.dynamics.Stepper`): its programs are kept on disk, so the next
      run of a scene of that shape and a resumed run load them instead of compiling; each step costs a few
      milliseconds more (Python and dispatch). ``"compiled"``: one program runs the steps of a record interval
      (:func:`jaxnet.solve.dynamics.advance`), with the factorisation as a host callback, which no program kept
      on disk may hold: compiled again by every process (seconds), cheaper per step. ``"auto"`` (default): the
      compiled loop for a run of more than :data:`AUTO_COMPILED_STEPS` steps still to take, where the host's
      cost per step outweighs a compilation, the host loop otherwise (``validation/REPORT.md``,
      "benchmarks/dynamics_loops.py", measures both).
    """

    time_step: float = 0.01
    min_time_step: float = 1e-7
    newton: Newton = TIME_STEP
    loop: str = "auto"

    def __post_init__(self):
        if self.loop not in LOOPS:
            raise ValueError(f"Implicit: loop must be one of {LOOPS}, got {self.loop!r}")
        for name in ("time_step", "min_time_step"):
            value = getattr(self, name)
            if not (np.isfinite(value) and value > 0):
                raise ValueError(f"Implicit: {name} must be finite and > 0, got {value!r}")
        if self.min_time_step > self.time_step:
            raise ValueError(f"Implicit: min_time_step ({self.min_time_step}) exceeds time_step ({self.time_step})")
