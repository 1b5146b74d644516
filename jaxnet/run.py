"""Runs of a case: the layer between a description and the solvers.

The solvers (:mod:`jaxnet.solve`) take a :class:`~jaxnet.scene.Scene`, options and a start, and hand each
iteration's or record's state to an optional observer; they know nothing of cases, files or terminals. What a
run of a :class:`~jaxnet.case.Case` needs besides is here: its scene and its own options unpacked (a FEMNET
case's Newton settings, its time settings), the records written as they come (:mod:`jaxnet.io.timeseries`:
series, VTK, a checkpoint), a progress bar (:mod:`jaxnet.io.progress`), and a stopped run resumed from its last
record. The command line, the notebooks and ``jaxnet.solve_static`` / ``jaxnet.simulate`` call these functions.
"""

from __future__ import annotations

import pathlib

import numpy as np

from jaxnet.case import Case
from jaxnet.water.forcing import Loading
from jaxnet.solve import dynamics, statics
from jaxnet.solve.options import Implicit, Newton
from jaxnet.solve.results import Equilibrium


def solve_static(case, solver: Newton | None = None, x0=None, throw: bool = True, **options) -> Equilibrium:
    """Static equilibrium of a :class:`~jaxnet.case.Case` (with its own solver options unless ``solver`` is
    given) or of a :class:`~jaxnet.scene.Scene`: :func:`jaxnet.solve.statics.solve`, whose arguments these are.

    Args:
      case: the case or scene.
      solver: :class:`~jaxnet.solve.options.Newton` options (default: the case's, else
        :data:`jaxnet.solve.options.STATIC`); keyword ``options`` override its fields.
      x0: optional (N, 3) start positions (m).
      throw: raise :class:`~jaxnet.solve.results.SolveError` when the solve does not converge.
    """
    scene = case
    if isinstance(case, Case):
        scene, solver = case.scene, solver or case.solver
    return statics.solve(scene, solver, x0=x0, throw=throw, **options)


def simulate(case, end_time=None, solver: Implicit | None = None, loading: Loading | None = None, record_every=None,
             out=None, resume=False, x0=None, v0=None, progress=True, vtk=True, throw: bool = True
             ) -> dynamics.Trajectory:
    """Runs a case in time, from time 0 (or from the last record of ``out`` when ``resume``) to ``end_time`` (s).

    Args:
      case: a :class:`~jaxnet.case.Case` (its scene, and from its time settings the end time, options, loading
        and record interval not given here) or a :class:`~jaxnet.scene.Scene`.
      end_time: the time to reach (s).
      solver: :class:`~jaxnet.solve.options.Implicit` options. loading: :class:`~jaxnet.water.forcing.Loading`.
      record_every: the interval between records (s); default: every step.
      out: a directory to write the records to as the run goes (:mod:`jaxnet.io.timeseries`: raw series,
        ``series.npz`` at the end, ``checkpoint.npz``, VTK ``series.pvd`` when ``vtk``); None keeps them in
        memory only.
      resume: continue the run in ``out`` from its last record (same scene and options).
      x0, v0: (N, 3) start positions (m) and velocities (m/s) (default: the scene's positions, at rest).
      progress: show a progress bar (simulated time, steps per second, Newton iterations per step).
      throw: raise :class:`~jaxnet.solve.dynamics.DynamicsError` when a step fails below the smallest step;
        with ``throw=False`` the run stops there and returns its records so far.
    Returns:
      the :class:`~jaxnet.solve.dynamics.Trajectory` (every record, also those written to ``out``).
    """
    from jaxnet.io import timeseries
    from jaxnet.io.progress import Progress

    scene = case
    if isinstance(case, Case):
        settings, scene = case.time, case.scene
        if settings is not None:
            end_time = settings.end_time if end_time is None else end_time
            solver, loading = solver or settings.solver, loading or settings.loading
            record_every = settings.record_every if record_every is None else record_every
    plan = dynamics.plan(scene, end_time, solver, loading, record_every)
    writer, start = None, None
    if out is not None:
        writer = timeseries.SeriesWriter(pathlib.Path(out), plan.scene, vtk=vtk, resume=resume,
                                         run={"start_ramp_s": plan.ramp_s,
                                              "reaction_nodes": plan.reaction_nodes.tolist()})
        if resume and writer.resumed is not None:
            start = dynamics.State.from_arrays(writer.resumed[1])
    begin = (0.0, 0, 0) if start is None else (float(start.t), int(start.steps), int(start.iterations))
    bar = Progress(begin[0], plan.end_time, disable=not progress, steps0=begin[1])
    iterations = [begin[2]]

    def observe(state, figures):
        if writer is not None:
            writer.write(timeseries.Record(time=float(state.t), step=int(state.steps), position=np.asarray(state.x),
                                           velocity=np.asarray(state.v), figures=figures), state.arrays())
        if int(state.steps) > begin[1] or float(state.t) > begin[0]:
            bar.update(float(state.t), int(state.steps), int(state.iterations) - iterations[0])
            iterations[0] = int(state.iterations)

    try:
        with bar:
            return dynamics.integrate(plan, x0=x0, v0=v0, start=start, observer=observe, throw=throw)
    finally:
        if writer is not None:
            writer.close()
