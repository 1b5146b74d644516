"""Sweeps and batches of designs beyond one process: hundreds of equilibria on a cluster of workers.

A parameter sweep, the candidates of a population or the corners of a tolerance box are many independent
solves of one net. :mod:`jaxnet.design.batch` runs them in one program on one process's devices
(``vmap``/``lax.map``/``shard_map``); :func:`sweep` spreads them over the worker processes of a cluster,
on one machine or many, one design a task:

* **the engine** is Dask's distributed scheduler (``distributed``): a :class:`distributed.LocalCluster` of
  worker processes (one thread each) by default, started and closed by :func:`sweep`, or any running
  cluster by its scheduler's address (``dask scheduler`` and ``dask worker tcp://HOST:8786`` on the
  machines) or an existing :class:`distributed.Client`. Chosen over Ray (``docs/investigations.md``
  has the figures of both): Dask is pure
  Python and small to install, its local cluster starts several times faster, and its larger per-task
  overhead is nothing next to a solve; its workers are plain processes running Python functions, which
  suits JAX (each worker its own XLA client, no object store between them). It is an optional dependency:
  ``pip install "jaxnet[cluster]"``.
* **the recipe** says how a worker builds the :class:`~jaxnet.design.space.DesignSpace` (:class:`Recipe`: a
  module-level function and its keyword arguments, e.g. ``(jaxnet.scenes.fish_cage, {"step": 1.6})``, or a
  FEMNET ``.don`` path, read by :func:`jaxnet.io.femnet.read_don`). A small description is sent with every
  task rather than the built net: pickling a scene and its structure to every worker would cost more than
  building them once there.
* **each worker keeps its work** per recipe and solver (:class:`Workspace`, in a dict of the worker
  process): the design space, its :class:`~jaxnet.solve.adjoint_statics.Adjoint` (the active terms, the
  tangent's pattern, the solver's programs), the reference
  design's equilibrium (the start of every design's solve: each result depends on its design only, never
  on which worker solved it or in what order) and the compiled programs (the Newton loop, the scene map,
  the figures), so that only a worker's first task compiles.
* **compiled programs across processes.** With ``cache`` (default: JAX's compilation cache directory if
  set, else the directory ``jaxnet run`` uses), each worker turns on JAX's persistent compilation cache
  there and :mod:`jaxnet.solve.programs` keeps the static solver's programs in it: a worker then loads what
  an earlier worker or sweep compiled. Each design is solved by the static solver's host loop with the
  differentiable solve's options (:meth:`jaxnet.solve.adjoint_statics.Adjoint.solve`), whose programs hold no
  host callback, so nothing of a design's solve is compiled again by a later worker (the first-task times of
  ``benchmarks/design_sweep.py``, cold and warm, show what each part costs).
* **results as they arrive.** Each design's row (its θ entries, each figure, Newton iterations, residual,
  status, wall time, worker) is appended to ``out/sweep.jsonl`` as its task completes (one JSON object a
  line) and gathered in a :class:`SweepTable`, returned at the end in the designs' order. A design that
  fails (θ refused by :meth:`DesignSpace.check`, an equilibrium that did not converge, anything raised,
  a worker lost) is a row of status ``"failed"`` with its reason, and the sweep goes on. With ``resume``,
  the designs already in ``out/sweep.jsonl`` are not solved again.

Bad input (no designs, a figure that is not callable, a recipe that cannot be built, a θ naming an unknown
family or entry or of a wrong shape) raises ValueError naming it before any worker starts: the client builds
the design space once to check every θ against it (the mesher only; nothing is compiled on the client).

Units: θ in its families' units (:data:`jaxnet.design.space.FAMILIES`), figures in their own, residuals in
N, times in s.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import pathlib
import pickle
import threading
import time
from typing import Any, Callable

import equinox as eqx
import numpy as np

from jaxnet.design import objectives
from jaxnet.design.space import DesignSpace
from jaxnet.solve import adjoint_statics, statics
from jaxnet.solve.options import DIFFERENTIABLE, Newton
from jaxnet.solve.results import CONVERGED, REASONS

__all__ = ["ROWS_FILE", "STATUSES", "Recipe", "SweepTable", "Workspace", "sweep", "solve_design"]

#: the file of a sweep's rows in its ``out`` directory, one JSON object a line, appended as results arrive
ROWS_FILE = "sweep.jsonl"

#: a row's status: the design was solved (its figures are its equilibrium's), or it failed (``reason`` says why)
STATUSES = ("done", "failed")

#: columns of a row besides the design's θ entries and its figures
_COLUMNS = ("design", "iterations", "residual_N", "status", "reason", "wall_s", "cpu_s", "setup_s", "worker",
            "recipe")


# -- the recipe: how a worker builds the design space ------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class Recipe:
    """How to build a :class:`~jaxnet.design.space.DesignSpace`: ``function(**kwargs)`` returns a
    :class:`~jaxnet.net.Net`, a :class:`~jaxnet.case.Case` built from one, or a DesignSpace.

    function: a module-level callable (sent to the workers by reference: importable there by its qualified
      name, or defined in the client's ``__main__``, which Dask sends by value). kwargs: its keyword
      arguments, as sorted (name, value) pairs (picklable: sent with every task).
    Make one with :meth:`of`.
    """

    function: Callable
    kwargs: tuple = ()

    @classmethod
    def of(cls, recipe) -> "Recipe":
        """The Recipe of ``recipe``: a Recipe; ``(function, {name: value})``; a function taking no argument;
        or the path of a FEMNET ``.don`` case (read by :func:`jaxnet.io.femnet.read_don`: the path must be the
        same on the workers, e.g. a shared file system). ValueError naming what is wrong otherwise."""
        if isinstance(recipe, Recipe):
            return recipe
        if isinstance(recipe, (str, os.PathLike)):
            path = pathlib.Path(recipe).expanduser().resolve()
            if path.suffix.lower() != ".don":
                raise ValueError(f"sweep: recipe {str(recipe)!r} is a path but not a FEMNET case (.don)")
            if not path.is_file():
                raise ValueError(f"sweep: recipe {str(recipe)!r}: no such FEMNET case")
            from jaxnet.io.femnet import read_don

            return cls(read_don, (("path", str(path)),))
        if isinstance(recipe, tuple) and len(recipe) == 2 and isinstance(recipe[1], dict):
            function, kwargs = recipe
        elif callable(recipe):
            function, kwargs = recipe, {}
        else:
            raise ValueError("sweep: the recipe must be (function, {keyword: value}), a function, or a FEMNET .don "
                             f"path, got {type(recipe).__name__}")
        if not callable(function):
            raise ValueError(f"sweep: the recipe's function is not callable ({type(function).__name__})")
        if not all(isinstance(k, str) for k in kwargs):
            raise ValueError(f"sweep: the recipe's keywords must be names (str), got {sorted(map(repr, kwargs))}")
        made = cls(function, tuple(sorted(kwargs.items())))
        made._picklable()
        return made

    @property
    def label(self) -> str:
        """``module.function(name=value, ...)``: the recipe as a row of a sweep names it."""
        name = f"{getattr(self.function, '__module__', '?')}.{getattr(self.function, '__qualname__', '?')}"
        return f"{name}({', '.join(f'{k}={v!r}' for k, v in self.kwargs)})"

    @property
    def key(self) -> str:
        """A digest of the function's name and the pickled arguments: a worker's key for what it built."""
        import cloudpickle

        name = (getattr(self.function, "__module__", "?"), getattr(self.function, "__qualname__", "?"))
        return hashlib.blake2b(cloudpickle.dumps((name, self.kwargs)), digest_size=16).hexdigest()

    def _picklable(self):
        """ValueError unless the function goes to the workers by reference (or by value from ``__main__``) and
        the arguments pickle."""
        import cloudpickle

        if getattr(self.function, "__module__", None) != "__main__":
            try:
                pickle.dumps(self.function)
            except Exception as err:  # noqa: BLE001 -- a lambda, a local function, a bound method of a local object
                raise ValueError(f"sweep: the recipe's function {self.label} must be defined at the top level of a "
                                 f"module (the workers import it by name): {err}") from err
        try:
            cloudpickle.dumps(self.kwargs)
        except Exception as err:  # noqa: BLE001
            raise ValueError(f"sweep: the arguments of recipe {self.label} cannot be sent to the workers: "
                             f"{err}") from err

    def build(self) -> DesignSpace:
        """The design space (the net meshed and built: numpy, nothing compiled). ValueError naming the recipe
        if the function raises or returns something that is not a net."""
        try:
            made = self.function(**dict(self.kwargs))
            return made if isinstance(made, DesignSpace) else DesignSpace(made)
        except Exception as err:  # noqa: BLE001 -- whatever the recipe raises, the user needs its name
            raise ValueError(f"sweep: recipe {self.label} does not build a design space: "
                             f"{type(err).__name__}: {err}") from err


# -- a worker's side: what it keeps between tasks -----------------------------------------------------------

@dataclasses.dataclass
class Workspace:
    """What a worker process keeps for one recipe and solver, built at its first task and reused by every
    later one: the design ``space``, its ``adjoint`` (:class:`~jaxnet.solve.adjoint_statics.Adjoint`: the
    terms, the tangent's pattern, the solver's programs), ``start`` (the reference design's
    equilibrium, (N, 3) m: every design's start) and ``setup_s``, the time it took to build (s). ``error``:
    the reason the build failed (the reference did not converge...), then given as every design's reason."""

    space: DesignSpace | None = None
    adjoint: adjoint_statics.Adjoint | None = None
    start: Any = None
    setup_s: float = 0.0
    error: str | None = None


_WORKSPACES: dict = {}  # (recipe key, solver) -> Workspace, in each worker process
_BUILDING = threading.Lock()  # one build at a time (a worker of several threads builds each recipe once)
_CACHE_SET: list = []  # the persistent cache directory this process was given (once)


def _use_cache(directory):
    """Turn on JAX's persistent compilation cache (and with it :mod:`jaxnet.solve.programs`'s) in ``directory``
    in this process, unless one is configured already (``JAX_COMPILATION_CACHE_DIR``, the user's own). It
    takes effect if this process has compiled nothing yet (JAX reads the setting at its first compilation);
    jaxnet's own programs follow it in any case."""
    import jax

    if directory is None or _CACHE_SET or jax.config.jax_compilation_cache_dir:
        return
    jax.config.update("jax_compilation_cache_dir", str(directory))
    # the default (1 s) would leave out most pieces of a small net, as for `jaxnet run`
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)
    _CACHE_SET.append(str(directory))


def _workspace(recipe: Recipe, solver: Newton, cache) -> Workspace:
    """This process's :class:`Workspace` of ``recipe`` and ``solver``, built if it has none."""
    key = (recipe.key, solver)
    with _BUILDING:
        found = _WORKSPACES.get(key)
        if found is not None:
            return found
        _use_cache(cache)
        start = time.perf_counter()
        made = Workspace()
        try:
            made.space = recipe.build()
            made.adjoint = adjoint_statics.Adjoint(made.space.reference, solver)
            # the reference's equilibrium, robustly from the drawing (the static solver's stiffness
            # continuation), polished with the sweep's options: every design then starts there
            rough = statics.solve(made.space.reference)
            polished = made.adjoint.solve(made.space.reference, rough.x)
            if int(polished.status) != CONVERGED:
                raise RuntimeError(f"{REASONS.get(int(polished.status))} after {int(polished.iterations)} "
                                   f"iterations polishing it to {solver.tol:g} N (largest residual "
                                   f"{float(polished.residual_N):.4g} N at node {int(polished.worst_node)})")
            made.start = polished.x
        except Exception as err:  # noqa: BLE001 -- every design of this recipe fails with this reason
            made.error = f"the reference design of {recipe.label} was not solved: {type(err).__name__}: {err}"
        made.setup_s = time.perf_counter() - start
        _WORKSPACES[key] = made
        return made


@eqx.filter_jit
def _figure_values(figures, x, scene, model):
    """{name: figure of the outcome}: one compiled program for all the figures (per figure set and net)."""
    outcome = objectives.Outcome(x, scene, model)
    return {name: figure(outcome) for name, figure in figures.items()}


def _worker_name():
    """The address of the Dask worker running this task (its process id outside a worker)."""
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return f"pid {os.getpid()}"


def solve_design(recipe: Recipe, solver: Newton, cache, figures: dict, design, theta: dict) -> dict:
    """One design's row (what a worker runs; also callable in-process): the equilibrium of design ``theta``
    of ``recipe``'s design space from the reference equilibrium, by
    :meth:`jaxnet.solve.adjoint_statics.Adjoint.solve` with ``solver``, and each of ``figures`` there. Never raises:
    a design that fails is a row of status ``"failed"`` with its reason."""
    start, cpu = time.perf_counter(), time.process_time()
    row = {"design": design, **_theta_columns(theta), **{name: None for name in figures},
           "iterations": None, "residual_N": None, "status": "failed", "reason": None, "setup_s": 0.0}
    try:
        had = (recipe.key, solver) in _WORKSPACES
        work = _workspace(recipe, solver, cache)
        row["setup_s"] = 0.0 if had else work.setup_s
        if work.error is not None:
            row["reason"] = work.error
        else:
            scene = work.space.scene(theta)  # checked first (DesignSpace.check): ValueError naming the entry
            eq = work.adjoint.solve(scene, work.start)
            row["iterations"], row["residual_N"] = int(eq.iterations), float(eq.residual_N)
            status = int(eq.status)
            if status == CONVERGED:
                values = _figure_values(figures, eq.x, scene, work.adjoint.model)
                row.update({name: float(v) for name, v in values.items()})
                row["status"] = "done"
            else:
                row["reason"] = (f"SolveError: {REASONS.get(status, status)} after {int(eq.iterations)} "
                                 f"iterations; largest residual {float(eq.residual_N):.4g} N at node "
                                 f"{int(eq.worst_node)} (tolerance {solver.tol:g} N)")
    except Exception as err:  # noqa: BLE001 -- a failed design is a row, the sweep goes on
        row["reason"] = f"{type(err).__name__}: {err}"
    row["wall_s"] = time.perf_counter() - start
    row["cpu_s"] = time.process_time() - cpu
    row["worker"] = _worker_name()
    row["recipe"] = recipe.label
    return row


# -- the client's side --------------------------------------------------------------------------------------

def _theta_columns(theta) -> dict:
    """θ as row columns ``"family[entry]"``: a number, or nested lists (a cut's corners)."""
    out = {}
    for family, entries in theta.items():
        for name, value in entries.items():
            value = np.asarray(value, dtype=float)
            out[f"{family}[{name}]"] = float(value) if value.ndim == 0 else value.tolist()
    return out


def _designs(designs) -> list:
    """[(key, θ)]: keys 0.. for a list, the names for a dict. ValueError for none or a malformed one."""
    if isinstance(designs, dict):
        items = list(designs.items())
        bad = [k for k, _ in items if not isinstance(k, str) or not k]
        if bad:
            raise ValueError(f"sweep: design names must be non-empty strings, got {bad[0]!r}")
    elif isinstance(designs, (list, tuple)):
        items = list(enumerate(designs))
    else:
        raise ValueError(f"sweep: designs must be a list of θ dicts or a dict {{name: θ}}, "
                         f"got {type(designs).__name__}")
    if not items:
        raise ValueError("sweep: no designs to solve (designs is empty)")
    return items


def _checked_theta(space: DesignSpace, key, theta) -> dict:
    """θ as given (the families and entries it names) as float numpy arrays, its names and shapes checked
    against the design space (:meth:`DesignSpace.complete`); ValueError naming the design otherwise. Its
    values are checked on the worker (an invalid design is a failed row, not an error of the sweep)."""
    try:
        space.complete(theta)
    except ValueError as err:
        raise ValueError(f"sweep: design {key!r}: {err}") from err
    out = {}
    for family, entries in theta.items():
        out[family] = {}
        for name, value in entries.items():
            try:
                out[family][name] = np.asarray(value, dtype=float)
            except (ValueError, TypeError) as err:
                raise ValueError(f"sweep: design {key!r}: {family}[{name!r}] is not a number ({value!r})") from err
    return out


def _figures(figures) -> dict:
    if not isinstance(figures, dict) or not figures:
        raise ValueError("sweep: figures must be a non-empty dict {name: figure}, e.g. {'drag': objectives.drag()}")
    for name, figure in figures.items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"sweep: figure names must be non-empty strings, got {name!r}")
        if name in _COLUMNS or "[" in name:
            raise ValueError(f"sweep: figure name {name!r} is taken by a column of the rows ({', '.join(_COLUMNS)}) "
                             "or looks like a θ entry (family[entry])")
        if not callable(figure):
            raise ValueError(f"sweep: figure {name!r} is not callable (a figure of jaxnet.design.objectives, called on "
                             f"an Outcome), got {type(figure).__name__}")
    return dict(figures)


def _read_rows(path: pathlib.Path) -> list:
    """The rows of a sweep file; a last line cut short (a sweep stopped while writing) is dropped from the
    file."""
    if not path.exists():
        return []
    text = path.read_text()
    lines = text.split("\n")
    if lines and lines[-1] != "":  # the last write did not finish: cut it off, it is solved again
        complete = text[:len(text) - len(lines[-1])]
        path.write_text(complete)
        lines = complete.split("\n")
    rows = []
    for number, line in enumerate(lines, 1):
        if line.strip():
            try:
                rows.append(json.loads(line))
            except json.JSONDecodeError as err:
                raise ValueError(f"sweep: {path} line {number} is not a row ({err}); move the file away or "
                                 "run with resume=False") from err
    return rows


def _resumed(rows, items, columns, figures, recipe) -> dict:
    """{design key: row} of the designs of ``items`` already in the file, each checked to be the same design
    (θ, figures, recipe); ValueError naming the first that differs."""
    wanted = dict(items)
    done = {}
    for row in rows:
        key = row.get("design")
        if key not in wanted:
            continue
        theirs = {k: v for k, v in row.items() if "[" in k}
        if theirs != columns[key]:
            raise ValueError(f"sweep: design {key!r} in the sweep file has another θ ({theirs}) than the one given "
                             f"({columns[key]}); give another out directory or resume=False")
        if row.get("recipe") != recipe.label or any(name not in row for name in figures):
            raise ValueError(f"sweep: design {key!r} in the sweep file is of recipe {row.get('recipe')} with other "
                             f"figures; give another out directory or resume=False")
        done[key] = row
    return done


def _default_cache():
    """JAX's compilation cache directory if set, else the one ``jaxnet run`` uses."""
    import jax

    configured = jax.config.jax_compilation_cache_dir or os.environ.get("JAX_COMPILATION_CACHE_DIR")
    if configured:
        return str(configured)
    return str(pathlib.Path(os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache") / "jaxnet")


class SweepTable:
    """The rows of a sweep, one a design in the order the designs were given (dicts: ``design``, each
    ``family[entry]`` of its θ, each figure, ``iterations``, ``residual_N`` (N), ``status``, ``reason``,
    ``wall_s`` (the task's time on its worker, s), ``cpu_s`` (the worker process's CPU time during the task,
    all its threads: on a loaded machine, the work done), ``setup_s`` (of it, building the worker's
    :class:`Workspace`: 0 but for a worker's first task), ``worker``, ``recipe``). ``figures``: the figure
    names; ``solved``: how many designs this call sent to the workers (the others were resumed from the
    file). ``str(table)`` is a printable table."""

    def __init__(self, rows, figures, solved):
        self.rows, self.figures, self.solved = list(rows), tuple(figures), int(solved)

    def __len__(self):
        return len(self.rows)

    def __iter__(self):
        return iter(self.rows)

    def __getitem__(self, index):
        return self.rows[index]

    def column(self, name) -> list:
        """The values of column ``name``, one a row."""
        return [row.get(name) for row in self.rows]

    @property
    def done(self) -> list:
        """The rows of the designs solved."""
        return [row for row in self.rows if row["status"] == "done"]

    @property
    def failed(self) -> list:
        """The rows of the designs that failed (``reason`` says why)."""
        return [row for row in self.rows if row["status"] != "done"]

    def __str__(self):
        def cell(value):
            if value is None:
                return "-"
            if isinstance(value, list):
                return f"({'x'.join(str(n) for n in np.shape(value))})"
            if isinstance(value, float):
                return f"{value:.6g}"
            return str(value)

        thetas = [k for k in (self.rows[0] if self.rows else {}) if "[" in k]
        columns = ["design", *thetas, *self.figures, "iterations", "residual_N", "status", "wall_s", "worker"]
        cells = [[cell(row.get(c)) for c in columns] for row in self.rows]
        widths = [max([len(c)] + [len(r[i]) for r in cells]) for i, c in enumerate(columns)]
        lines = ["  ".join(c.rjust(w) for c, w in zip(columns, widths))]
        lines += ["  ".join(c.rjust(w) for c, w in zip(r, widths)) for r in cells]
        lines += [f"design {row['design']!r} failed: {row['reason']}" for row in self.failed]
        return "\n".join(lines)

    def __repr__(self):
        return f"SweepTable({len(self.rows)} designs, {len(self.done)} done, {len(self.failed)} failed)"


def _require_distributed():
    """ImportError saying how to install Dask's distributed scheduler, if it is not installed."""
    import importlib.util

    if importlib.util.find_spec("distributed") is None:
        raise ImportError('jaxnet.design.sweep runs on Dask\'s distributed scheduler: pip install "jaxnet[cluster]" '
                          '(or pip install "dask[distributed]")')


def _connect(address, n_workers):
    """(client, what to close at the end): the given Client (nothing closed), a Client of the scheduler at
    ``address`` (the client closed, not the cluster), or a new local cluster (both closed)."""
    from distributed import Client, LocalCluster

    if isinstance(address, Client):
        return address, []
    if address is not None:
        client = Client(address)
        return client, [client]
    # one thread a worker: a solve's factorisations and XLA's own threads use the core; processes, not
    # threads, so each worker has its own interpreter (no GIL shared between solves) and its own XLA client
    cluster = LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    return client, [client, cluster]


def sweep(recipe, designs, figures: dict, *, address=None, n_workers: int = 2, out=None,
          solver: Newton | None = None, resume: bool = True, progress: bool = True, cache=True) -> SweepTable:
    """Solve every design of ``designs`` on a cluster's workers and measure ``figures`` at each equilibrium.

    Args:
      recipe: how each worker builds the design space (:meth:`Recipe.of`): ``(function, {keyword: value})``
        with a module-level function returning a Net or Case (e.g. ``(jaxnet.scenes.fish_cage, {"step":
        1.6})``), a function of no argument, a :class:`Recipe`, or a FEMNET ``.don`` path.
      designs: a list of θ (dicts of families, any subset of :meth:`DesignSpace.initial`'s, the rest at the
        reference: :meth:`DesignSpace.complete`), keyed 0, 1, ... in the rows, or a dict {name: θ}.
      figures: {name: figure}: scalars of an :class:`jaxnet.design.objectives.Outcome`, e.g.
        ``{"drag": objectives.drag(), "volume": objectives.volume()}`` (picklable: jaxnet's figures are).
      address: None for a local cluster of ``n_workers`` worker processes (one thread each), started here
        and closed at the end; a scheduler's address (``"tcp://host:8786"``) or a
        :class:`distributed.Client` to use a running cluster (left running).
      out: a directory for ``sweep.jsonl`` (:data:`ROWS_FILE`), the rows appended as they arrive; None to
        keep them in memory only.
      solver: the Newton options of every design's solve (default
        :data:`jaxnet.solve.options.DIFFERENTIABLE`), each started from the reference design's equilibrium.
      resume: leave out the designs that ``out/sweep.jsonl`` already holds (their rows, done or failed, are
        read back; ValueError if one has another θ, recipe or figures); False starts the file afresh. To solve
        a failed design again, delete its line.
      progress: a progress bar (tqdm) of the designs solved.
      cache: a directory where each worker keeps its compiled programs between processes (JAX's persistent
        compilation cache and :mod:`jaxnet.solve.programs`, on the worker's machine); True (default) for JAX's
        compilation cache directory if set, else ``$XDG_CACHE_HOME/jaxnet`` (as ``jaxnet run``); None or False
        for none. A worker that already has a cache directory keeps its own.
    Returns:
      a :class:`SweepTable` of every design's row, in the designs' order.

    Bad input raises ValueError naming it before any worker starts (module docstring).
    """
    _require_distributed()
    items = _designs(designs)
    figures = _figures(figures)
    if solver is None:
        solver = DIFFERENTIABLE
    if not isinstance(solver, Newton):
        raise ValueError(f"sweep: solver must be jaxnet.solve.options.Newton options, got {type(solver).__name__}")
    if address is None and (not isinstance(n_workers, int) or isinstance(n_workers, bool) or n_workers < 1):
        raise ValueError(f"sweep: n_workers must be a positive integer, got {n_workers!r}")
    recipe = Recipe.of(recipe)
    space = recipe.build()
    items = [(key, _checked_theta(space, key, theta)) for key, theta in items]
    columns = {key: _theta_columns(theta) for key, theta in items}
    cache = _default_cache() if cache is True else (None if cache is False or cache is None else str(cache))

    path = None
    rows = {}
    if out is not None:
        directory = pathlib.Path(out)
        directory.mkdir(parents=True, exist_ok=True)
        path = directory / ROWS_FILE
        if resume:
            rows = _resumed(_read_rows(path), items, columns, figures, recipe)
        else:
            path.write_text("")
    todo = [(key, theta) for key, theta in items if key not in rows]
    if todo:
        rows.update(_run(recipe, solver, cache, figures, todo, address, n_workers, path, progress))
    return SweepTable([rows[key] for key, _ in items], figures, len(todo))


def _run(recipe, solver, cache, figures, todo, address, n_workers, path, progress) -> dict:
    """{design key: row} of the designs ``todo``, solved on the cluster, each row appended to ``path`` as it
    arrives."""
    from distributed import as_completed
    from tqdm.auto import tqdm

    client, to_close = _connect(address, n_workers)
    rows = {}
    try:
        futures = {}
        for key, theta in todo:
            future = client.submit(solve_design, recipe, solver, cache, figures, key, theta, pure=False,
                                   key=f"jaxnet-design-{key}-{os.urandom(4).hex()}")
            futures[future] = (key, theta)
        bar = tqdm(total=len(todo), desc="designs", unit="design", disable=not progress)
        failed = 0
        with open(path, "a") if path is not None else _Nowhere() as file:
            for future in as_completed(futures):
                key, theta = futures[future]
                try:
                    row = future.result()
                except Exception as err:  # noqa: BLE001 -- a lost worker, a task that could not be sent: a failed row
                    row = {"design": key, **_theta_columns(theta), **{name: None for name in figures},
                           "iterations": None, "residual_N": None, "status": "failed",
                           "reason": f"{type(err).__name__}: {err}", "wall_s": None, "cpu_s": None, "setup_s": None,
                           "worker": None, "recipe": recipe.label}
                row = _ordered(row, figures)
                rows[key] = row
                file.write(json.dumps(row, allow_nan=True) + "\n")
                file.flush()
                failed += row["status"] != "done"
                bar.set_postfix_str(f"{failed} failed", refresh=False)
                bar.update(1)
        bar.close()
    finally:
        for thing in to_close:
            thing.close()
    return rows


def _ordered(row, figures) -> dict:
    """The row's columns in a fixed order: design, θ, figures, then the solve's."""
    thetas = [k for k in row if "[" in k]
    names = ["design", *thetas, *figures, "iterations", "residual_N", "status", "reason", "wall_s", "cpu_s",
             "setup_s", "worker", "recipe"]
    out = {name: row.get(name) for name in names}
    for name in ("residual_N", *figures):  # JSON has no NaN: a non-finite figure is written as null
        if isinstance(out[name], float) and not math.isfinite(out[name]):
            out[name] = None
    return out


class _Nowhere:
    """A file that keeps nothing (a sweep without ``out``)."""

    def __enter__(self):
        return self

    def __exit__(self, *_):
        return False

    def write(self, _):
        pass

    def flush(self):
        pass
