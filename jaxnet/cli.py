"""Command line: ``jaxnet run [SCENE] [--scene NAME [--set KEY=VALUE ...]] [--mesh CASE.mdg] [--out DIR]``,
``jaxnet export --scene NAME [--set ...] [--force] FILE`` (a built-in scene written as a scene file to edit),
``jaxnet show DIR`` (a run's pictures drawn again without solving), ``jaxnet --version``.

With no SCENE, solves a built-in scene (``--scene``, default ``cage``: a fish cage in a current; see
``jaxnet run --help`` for the list). SCENE may be a jaxnet scene file (.json, .toml) or a FEMNET case
(.don, :mod:`jaxnet.io.femnet`); for a FEMNET case ``--mesh CASE.mdg`` solves on FEMNET's own mesh instead
of jaxnet's, and ``--start CASE.sta`` (with ``--mesh``) starts it from FEMNET's stored node positions (its
equilibrium, or an earlier case's, as FEMNET's ``phobos`` and ``dyna`` start theirs); result.json gets a "femnet"
section with FEMNET's summary figures (drag on netting, cables and catch, total force on the fixings, catch
thickness and diameter). A FEMNET case uses FEMNET's own laws where they differ from the book's
(``docs/errata.md``), so that it gives FEMNET's answers; ``--jaxnet-laws`` solves it with jaxnet's.

Writes, in this order, the answer first: DIR/command.json (the command, for ``jaxnet show``), DIR/result.json (the
figures, ``docs/result.md``), DIR/net.vtu (ParaView: tensions, displacement, nodal forces by group, reactions;
DIR/net_whole.vtu beside it for a model with symmetry planes), then the pictures, DIR/net.png and DIR/net.html
(``docs/pictures.md``; ``--no-pictures`` leaves them out). Prints one line per Newton iteration under a legend,
and a summary (the balance of the forces on the net, the weight and buoyancy by what carries them, the largest
tensions). ``--set`` changes a built-in scene's numbers (its function's keyword arguments); the run's label is
made from the numbers it ran with. Exit status (:data:`OK`, :data:`FAILED`, :data:`BAD_INPUT`, :data:`STOPPED`):
0 on convergence, 1 on a failed solve (its last state still written, net.vtu with its residual), 2 on bad input,
130 when stopped by Ctrl-C. Bad input is one line naming the culprit, never a traceback, and is found before
anything is compiled where it can be: an option that would not apply (``--end`` without ``--dynamic``, FEMNET's
options with a scene file, ``--scene`` with a file), a path in the way (``--out`` under a file, an existing file
to export without ``--force``), a file that does not exist; a file that cannot be written during the run (a full
disk) is named too.

``--dynamic`` runs the scene in time instead (:mod:`jaxnet.solve.dynamics`, the book's implicit scheme):
from its static equilibrium (computed first), to ``--end`` seconds with steps of ``--dt`` seconds, a record
every ``--record`` seconds written to DIR as it goes (series.json + raw/ arrays, series.npz at the end,
series.pvd + net_NNNNN.vtu for ParaView, checkpoint.npz; ``--resume`` continues a stopped run from its last
record; run.png at the end: the reactions and largest tensions against time), its progress a bar on a terminal
and plain lines in a log (:mod:`jaxnet.io.progress`). A FEMNET case takes its own time settings, towing tables,
winches and numerics (its threshold, iterations and displacement limit, for the static start and for every time
step); ``--tol``, ``--max-iter``, ``--stiffness`` and ``--method`` apply to both as in a static run. The built-in
``cage_waves`` (the default with ``--dynamic``) is the cage in regular waves, its collar heaving.

Compiled programs are kept on disk (in ``--cache DIR``, default ``$XDG_CACHE_HOME/jaxnet`` or
``~/.cache/jaxnet``: the static solver's programs whole, :mod:`jaxnet.solve.programs`, the others in JAX's
persistent compilation cache; ``--no-cache`` to switch both off; a ``JAX_COMPILATION_CACHE_DIR`` set by the
user wins): a second run of a case of the same shape and terms — another current speed, another catch, the
same case again — loads them instead of tracing and compiling, most of a first run's time
(``benchmarks/whole_process.py`` times whole runs cold and with them). The program of the outputs' figures is
obtained in a thread of its own while the solver iterates.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import json
import os
import pathlib
import sys

# The command line imports what a command needs when it needs it: parsing the arguments, ``--help`` and
# ``--version`` import neither JAX nor the physics (``jaxnet/__init__.py`` loads its names on first use).

#: exit statuses: converged (or done), a failed solve, bad input (a file, a key, an option, a path), stopped by Ctrl-C
OK, FAILED, BAD_INPUT, STOPPED = 0, 1, 2, 130


class CommandError(ValueError):
    """A command line that cannot run as given: an option that does not apply, a path that cannot be written,
    a file that would be overwritten. Printed as ``jaxnet: bad input: ...``, exit status 2, before anything is
    solved."""


#: JAX's settings of its persistent compilation cache that a run changes (:func:`_compilation_cache`)
_CACHE_SETTINGS = ("jax_compilation_cache_dir", "jax_persistent_cache_min_compile_time_secs")


@contextlib.contextmanager
def _compilation_cache(directory):
    """JAX's persistent compilation cache in ``directory`` for the time of a run (the solver's pieces hold no host
    callback, so they can be cached; None: none), unless the user already chose one; JAX's settings are put back
    as they were after it, so that a run started from Python (a notebook, a test) leaves the process as it
    found it."""
    if directory is None or os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        yield
        return
    import jax

    before = {name: getattr(jax.config, name) for name in _CACHE_SETTINGS}
    jax.config.update("jax_compilation_cache_dir", str(directory))
    # the default (1 s) would leave out the smaller pieces of a small scene
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)
    try:
        yield
    finally:
        for name, value in before.items():
            jax.config.update(name, value)


def _reason(err: OSError) -> str:
    """An operating-system error in words, without its path (the message names the path itself)."""
    if not err.errno:
        return str(err)
    return err.strerror or os.strerror(err.errno)


def writable_directory(path, option) -> pathlib.Path:
    """The directory ``path`` (given by ``option``, e.g. ``--out``), created with its parents if it does not exist,
    checked to take new files; a :class:`CommandError` naming the option, the path and what is in the way (a file
    where a directory should be, no permission, a read-only or full disk) otherwise."""
    problem = directory_problem(path)
    if problem is not None:
        raise CommandError(f"{option} {path}: {problem}")
    return pathlib.Path(path)


def directory_problem(path) -> str | None:
    """Create the directory ``path`` (and its parents) if need be and check that it takes new files: None if it
    does, else what is in the way, in words."""
    directory = pathlib.Path(path)
    blocking = next((p for p in [directory, *directory.parents] if p.exists() and not p.is_dir()), None)
    if blocking is not None:
        return f"{blocking} is a file, not a directory"
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        return f"cannot create it ({_reason(err)})"
    probe = directory / f".jaxnet-write-test-{os.getpid()}"
    try:
        probe.write_bytes(b"")
        probe.unlink()
    except OSError as err:
        return f"cannot write in it ({_reason(err)})"
    return None


def _existing_file(path, what) -> str:
    """``path`` if it is a file; a :class:`CommandError` naming ``what`` it should be otherwise."""
    p = pathlib.Path(path)
    if not p.exists():
        raise CommandError(f"{what} {path} does not exist")
    if p.is_dir():
        raise CommandError(f"{what} {path} is a directory, not a file")
    return str(path)


def case_of(args, dynamic):
    """The case the command names (a built-in scene, a scene file, a FEMNET case on jaxnet's or FEMNET's mesh,
    started from a FEMNET .sta) and its label: a built-in scene's from its own numbers (``--set`` included)."""
    import dataclasses

    from jaxnet.catalogue import BUILT_IN, DYNAMIC, DYNAMIC_DEFAULT

    settings = getattr(args, "set", None) or []
    if args.scene is None:
        catalogue = DYNAMIC if dynamic else BUILT_IN
        name = args.builtin or (DYNAMIC_DEFAULT if dynamic else None)
        if name is None:
            from jaxnet.catalogue import DEFAULT

            name = DEFAULT
        if name not in catalogue:
            raise CommandError(f"--scene {name} is a static scene: run it without --dynamic, or run one of the scenes "
                               f"in time: {', '.join(catalogue)}" if dynamic else
                               f"--scene {name} is a dynamic scene: run it with --dynamic")
        make = catalogue[name].make()
        changes = built_in_arguments(make, name, settings)
        case = make(**changes)
        kind = "built-in dynamic scene" if dynamic else "built-in scene"
        # its label from the numbers it was built with; and what --set changed, said again
        said = "; " + ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in changes.items()) \
            if changes else ""
        return case, f"{kind} '{name}': {case.label}{said}"
    if str(args.scene).endswith(".don"):
        from jaxnet.io import femnet

        laws = not args.jaxnet_laws
        case = (femnet.read_mdg(args.mesh, args.scene, femnet_laws=laws) if args.mesh is not None
                else femnet.read_don(args.scene, femnet_laws=laws, refine=1.0 if args.refine is None else args.refine))
        if args.start is not None:
            case = femnet.started_from_sta(case, args.start)
            case = dataclasses.replace(case, label=f"{case.label}, started from {args.start}")
        return case, case.label
    from jaxnet.io import scene_file

    case = scene_file.read(args.scene)
    return case, case.label


def check_options(args):
    """Refuse what the command line asks that would not apply (a :class:`CommandError` naming the option and
    what it goes with), before anything is read or compiled: options of a run in time without ``--dynamic``,
    options of a FEMNET case without one, a built-in's ``--set`` or ``--scene`` with a file, ``--cache`` with
    ``--no-cache``; and the input files that do not exist."""
    def given(*names):
        return [f"--{n.replace('_', '-')}" for n in names if getattr(args, n, None) not in (None, False)]

    if not args.dynamic:
        stray = given("end", "dt", "loop", "record", "resume")
        if stray:
            raise CommandError(f"{', '.join(stray)} {'applies' if len(stray) == 1 else 'apply'} to a run in time: "
                               "add --dynamic, or leave "
                               f"{'it' if len(stray) == 1 else 'them'} out for a static solve")
    don = args.scene is not None and str(args.scene).endswith(".don")
    if not don:
        stray = given("mesh", "start", "refine", "jaxnet_laws")
        if stray:
            raise CommandError(f"{', '.join(stray)} {'goes' if len(stray) == 1 else 'go'} with a FEMNET case "
                               f"(jaxnet run CASE.don {' '.join(stray)} ...)")
    if args.mesh is not None and args.refine is not None:
        raise CommandError("--refine (a mesh finer than the file's) is for jaxnet's mesh of a FEMNET case, not with "
                           "--mesh (FEMNET's own mesh)")
    if args.start is not None and args.mesh is None:
        raise CommandError("--start (FEMNET's node positions, a .sta) goes with --mesh: they are numbered on its mesh")
    if args.scene is not None:
        if args.set:
            raise CommandError("--set changes a built-in scene's numbers (--scene NAME); a scene file or a FEMNET case "
                               "is changed by editing it (jaxnet export --scene NAME FILE writes a built-in to a file)")
        if args.builtin is not None:
            raise CommandError(f"--scene {args.builtin} (a built-in scene) and the file {args.scene}: give one of them")
        _existing_file(args.scene, "the scene file" if not don else "the FEMNET case")
        for option in ("mesh", "start"):
            if getattr(args, option) is not None:
                _existing_file(getattr(args, option), f"--{option}")
        if pathlib.Path(args.scene).suffix not in (".don", ".toml", ".json"):
            raise CommandError(f"{args.scene}: a scene file is .toml or .json, a FEMNET case .don")
    if args.no_cache and args.cache is not None:
        raise CommandError("--cache DIR and --no-cache: give one of them")


def _cache_directory(args):
    """The directory of compiled programs this run keeps (``--cache``, else the default), or None: ``--no-cache``,
    or the default directory that cannot be written (a read-only home: said, and the run goes on without it).
    A ``--cache`` given that cannot be written is a :class:`CommandError`."""
    if args.no_cache:
        return None
    if args.cache is not None:
        return writable_directory(args.cache, "--cache")
    try:
        return writable_directory(default_cache(), "the cache of compiled programs")
    except CommandError as err:
        print(f"jaxnet: note: {err}; compiling without it (--cache DIR to choose another)", file=sys.stderr)
        return None


def default_cache() -> pathlib.Path:
    """Where compiled programs are kept by default: ``$XDG_CACHE_HOME/jaxnet``, else ``~/.cache/jaxnet``."""
    return pathlib.Path(os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache") / "jaxnet"


def built_in_arguments(make, name, settings):
    """The keyword arguments ``--set KEY=VALUE ...`` give the function ``make`` of the built-in scene ``name``:
    each KEY one of its number or integer parameters (its defaults say which), VALUE read as that type. Raises
    a :class:`CommandError` naming an unknown key (with the known ones) or a value of the wrong kind, before
    anything is built."""
    import inspect

    parameters = {p.name: p for p in inspect.signature(make).parameters.values()
                  if isinstance(p.default, (int, float)) and not isinstance(p.default, bool)}
    out = {}
    for item in settings:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise CommandError(f"--set {item!r}: expected KEY=VALUE, e.g. --set current=0.8")
        if key not in parameters:
            raise CommandError(f"--set {key}: the built-in scene '{name}' has no such number; it has: "
                               f"{', '.join(f'{k} (default {p.default!r})' for k, p in parameters.items())}")
        kind = type(parameters[key].default)
        try:
            value = kind(text) if kind is float else int(text)
        except ValueError:
            raise CommandError(f"--set {key}={text}: expected {'an integer' if kind is int else 'a number'}") from None
        out[key] = value
    return out


def _overrides(args):
    """The Newton options the command line sets (``--tol``, ``--max-iter``, ``--stiffness``, ``--method``): for the
    static solve, and in a run in time for its start and for every time step."""
    return {k: v for k, v in (("tol", args.tol), ("max_iter", args.max_iter), ("stiffness", args.stiffness),
                              ("method", args.method)) if v is not None}


def time_stepping(case, args):
    """(time settings, implicit options) of a run in time of ``case`` as the command line asks: the case's own
    time settings (a FEMNET case's, a dynamic built-in's) or the defaults, its time step replaced by ``--dt``,
    and each step's Newton its own (a FEMNET case's already holds the file's threshold, iterations and
    displacement limit) with the command line's solver flags (``--tol``, ``--max-iter``, ``--stiffness``)."""
    import dataclasses

    from jaxnet.case import TimeSettings

    settings = case.time or TimeSettings()
    implicit = settings.solver
    if args.dt is not None:
        implicit = dataclasses.replace(implicit, time_step=args.dt, min_time_step=min(implicit.min_time_step, args.dt))
    if args.loop is not None:
        implicit = dataclasses.replace(implicit, loop=args.loop)
    implicit = dataclasses.replace(implicit, newton=dataclasses.replace(implicit.newton, **_overrides(args)))
    return settings, implicit


def _shown(value, scale=0.0):
    """A force component as the console prints it: 4 significant digits, 0 where it is rounding beside ``scale``
    (below 1e-12 of it: the forces of the balance it is printed with), and -0.0 + 0.0 is 0.0: no "-0"."""
    return f"{(value if abs(value) > 1e-12 * scale else 0.0) + 0.0:.4g}"


def _vector(values, scale=0.0):
    return "[" + ", ".join(_shown(v, scale) for v in values) + "] N"


def _size(*vectors):
    """The largest component of the vectors (N): the scale below which a printed component is rounding."""
    return max((abs(v) for vector in vectors for v in vector), default=0.0)


def carrier_groups(carriers):
    """result.json's weight and buoyancy by carrier (name -> [x, y, z] N) as the console gives them: the cables
    of one name numbered (``collar 0`` ... ``collar 7``, a FEMNET case's ``cable 1`` ...) summed as one line
    (``collar (8 cables)``), the other carriers as they are."""
    import re

    groups, members = {}, {}
    for name, force in carriers.items():
        stem = re.sub(r" \d+$", "", name)
        key = stem if stem != name else name
        groups[key] = [a + b for a, b in zip(groups.get(key, [0.0, 0.0, 0.0]), force)]
        members[key] = members.get(key, 0) + 1
    return {(f"{key} ({members[key]} cables)" if members[key] > 1 else
             next(n for n in carriers if n == key or re.sub(r" \d+$", "", n) == key)): force
            for key, force in groups.items()}


def print_summary(result, where=None):
    """The console's summary of a static run's ``result`` (:func:`jaxnet.figures.summary`, with a FEMNET case's
    sections): how the solve ended, the balance of the forces on the net (the fixings', the weight and other
    loads', the water's), its whole net where the model has symmetry planes, the largest tensions, the weight
    and buoyancy by what carries them, FEMNET's text outputs."""
    whole = result["whole_net"] if "whole_net" in result else None
    print(f"  {'converged' if result['converged'] else 'NOT converged: ' + result['reason']} in {result['iterations']} "
          f"iterations, residual {result['residual_N']:.3g} N")
    if "wall_s" in result:
        print(f"  wall {result['wall_s']:.2f} s (compile {result['compile_s']:.2f} s{'; ' + where if where else ''})")
    part = f" (the model: {result['modelled_part']})" if whole is not None else ""
    scale = _size(result["reaction_N"], result["load_N"], result["water_N"])
    print(f"  reaction of the fixings {_vector(result['reaction_N'], scale)}; weight, buoyancy and other loads "
          f"{_vector(result['load_N'], scale)}; the water's forces {_vector(result['water_N'], scale)}{part}")
    if whole is not None:
        catch = f", catch drag {_shown(result['catch']['drag_whole_net_N'])} N" if "catch" in result else ""
        scale = _size(whole["reaction_N"], whole["load_N"], whole["water_N"])
        print(f"  whole net ({whole['copies']} mirrored copies): reaction {_vector(whole['reaction_N'], scale)}, "
              f"weight, buoyancy and other loads {_vector(whole['load_N'], scale)}, the water's forces "
              f"{_vector(whole['water_N'], scale)}{catch}")
    carriers = carrier_groups(result.get("weight_and_buoyancy_by_carrier_N", {}))
    if carriers:
        up = result["inputs"]["environment"]["up"]
        print("  weight (-) and buoyancy (+) along up: " + ", ".join(
            f"{name} {_shown(sum(a * b for a, b in zip(force, up)))} N" for name, force in carriers.items()))
    tensions = ([f"max twine tension {_shown(result['max_twine_tension_N'])} N"] if result["n_triangles"] else []) + (
        [f"max bar tension {_shown(result['max_bar_tension_N'])} N"] if result["n_bars"] else [])
    if tensions:
        print("  " + ", ".join(tensions))
    for figure in result.get("femnet", {}).get("printed", []):   # FEMNET's text outputs, as it prints them
        if figure["kind"] == "heading":      # a distance from a node to itself: FEMNET's way of printing a title
            print(f"  {figure['comment']}")
        elif figure["value"] is not None:
            print(f"  {figure['comment']}: {figure['value']:.6g} {figure['unit']}")


def _run(args):
    """``jaxnet run``: the options checked and the output directory made before anything is read or compiled,
    then a static run or a run in time, with the cache of compiled programs on for its duration."""
    check_options(args)
    out = writable_directory(args.out, "--out")
    with _compilation_cache(_cache_directory(args)):
        return _run_dynamic(args, out) if args.dynamic else _run_static(args, out)


def _run_static(args, out):
    import dataclasses
    import time

    case, label = case_of(args, dynamic=False)
    scene = case.scene
    print(f"jaxnet: {label}")
    print(f"  {scene.n_nodes} nodes, {scene.n_elements} elements, {scene.n_dof} unknowns")
    for line in case.info.get("warnings", []):       # a FEMNET case read as FEMNET would, with a difference said
        print(f"  note: {line}")
    if case.info.get("dynamic_only"):
        print(f"  left out of this static run (FEMNET's dynamics only): {', '.join(case.info['dynamic_only'])}")
    _record_command(out, args)
    from jaxnet import figures
    from jaxnet.io import vtk
    from jaxnet.run import solve_static
    from jaxnet.solve.results import SolveError

    failed = None
    # what the outputs need is made ready while the solver iterates (the figures' program compiles in XLA beside
    # the Newton loop's host work; the pictures' modules import), then waited for after the solve
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=1) as pool:
        figures_program = pool.submit(_prepare_outputs, scene, not args.no_pictures)
        try:
            eq = solve_static(case, verbose=not args.quiet, **_overrides(args))
        except SolveError as err:
            failed, eq = err, err.equilibrium
        figures_program.exception()   # done (an error there is raised again, and named, by net_figures below)
    # what the solve ran with: the case's options with the command line's (solve_static() above took the same)
    used = dataclasses.replace(case.solver, verbose=not args.quiet, **_overrides(args))
    t = time.perf_counter()
    source = args.scene if args.scene is not None else f"built-in scene '{args.builtin or _default_scene()}'"
    net = figures.net_figures(scene, eq.x)   # one program's figures, for every output below
    result = figures.summary(scene, eq, case=case, source=str(source), solver=used, figures=net)
    if "symmetry_axes" in case.info:  # a FEMNET case: its own figures, and what the reader decided
        from jaxnet.io import femnet

        result["femnet"] = femnet.femnet_figures(scene, eq, case.info["symmetry_axes"], case.info.get("fixity"),
                                                 groups=result["forces_N"])
        result["femnet"]["printed"] = femnet.text_output_figures(scene, eq, case.info)
        result["femnet_case"] = case.info
    # the answer first: result.json, then ParaView's files, then the pictures (skipped by --no-pictures)
    (out / "result.json").write_text(json.dumps(result, indent=2))
    written = [out / "result.json", *vtk.write_vtu(out / "net.vtu", scene, eq.x, figures=net, force=eq.force,
                                                  residual=None if failed is None else eq.force)]
    outputs_s = time.perf_counter() - t
    print_summary(result, where=_where_it_ran() if eq.timing is not None else None)
    if not args.no_pictures:
        t = time.perf_counter()
        written += _pictures(out, scene, eq.x, result, label, net)
        outputs_s += time.perf_counter() - t
    print(f"  wrote {', '.join(str(p) for p in written)} (in {outputs_s:.2f} s)")
    if failed is not None:
        print(f"jaxnet: {failed}", file=sys.stderr)
        return FAILED
    return OK


def _prepare_outputs(scene, pictures):
    """Obtain the program of the outputs' figures (:func:`jaxnet.figures.prepare_figures`) and, for ``pictures``,
    import the modules that draw them (matplotlib's import is a good part of a picture's time)."""
    from jaxnet import figures

    figures.prepare_figures(scene)
    if pictures:
        from jaxnet.io import page, plot  # noqa: F401


def _where_it_ran():
    """Where the solve ran, in words: JAX's backend and the sparse factorisation of its tangents."""
    import jax

    from jaxnet import linalg

    return f"JAX on {jax.default_backend()}, tangents factorised by {linalg.solver_choice()}"


def _default_scene():
    from jaxnet.catalogue import DEFAULT

    return DEFAULT


def _pictures(out, scene, x, result, label, net=None):
    """Draw a static run's pictures in ``out``: net.png and the page net.html (``net``: the
    :class:`jaxnet.figures.NetFigures` at x, whose tensions they colour by). Returns the files written."""
    from jaxnet.io import plot

    tensions = {} if net is None else {"twine_tension": net.twine_tension, "bar_tension": net.bar_tension}
    front = result.get("catch", {}).get("front_m")
    plot.save_png(out / "net.png", scene, x, title=label, catch_front=front, **tensions)
    from jaxnet.io import page

    page.write_html(out / "net.html", scene, x, result=result, title=label, **tensions)
    return [out / "net.png", out / "net.html"]


def _stopped(out, argv):
    """What a dynamic run stopped by Ctrl-C says: where its records end, and the command that continues it
    (exit status 130, the shell's for an interrupt)."""
    import shlex

    from jaxnet.io import timeseries

    point = timeseries.resume_point(out)
    where = f"its records in {out} end at t = {point[0].time:g} s" if point else f"no record in {out} yet"
    again = [a for a in argv if a != "--resume"] + ["--resume"]
    print(f"jaxnet: stopped (Ctrl-C); {where}. Continue with: jaxnet {shlex.join(again)}", file=sys.stderr)
    return STOPPED


def _run_dynamic(args, out):
    import numpy as np

    import equinox as eqx

    from jaxnet import run as run_lib
    from jaxnet.solve import dynamics
    from jaxnet.solve.statics import solve

    case, label = case_of(args, dynamic=True)
    overrides = _overrides(args)
    settings, implicit = time_stepping(case, args)
    end_time = args.end if args.end is not None else settings.end_time
    record_every = args.record if args.record is not None else settings.record_every
    if end_time is None:
        raise CommandError("--dynamic: give the end time (--end, s); the scene has none")
    scene = case.scene
    _record_command(out, args)
    print(f"jaxnet: {label}")
    print(f"  {scene.n_nodes} nodes, {scene.n_elements} elements, {scene.n_dof} unknowns; dynamics to "
          f"{end_time:g} s, step {implicit.time_step:g} s")
    scene, loading, ramp = dynamics.with_start_ramp(scene, settings.loading)
    if ramp > 0:
        print(f"  the waves and the prescribed motions grow in over the first {ramp:g} s")
    for k, winch in enumerate(loading.winches):
        times = np.asarray(winch.table.times)
        total = float(winch.hauled(times[-1]))
        print(f"  winch {k}: {'hauls in' if total >= 0 else 'pays out'} {abs(total):g} m of {len(winch.bars)} bars "
              f"between {times[0]:g} and {times[-1]:g} s (drum at bar {winch.drum_bar})")
    x0 = None
    if not args.resume:
        eq = solve(dynamics.scene_at(scene, loading, 0.0), case.solver, verbose=False, throw=False, **overrides)
        print(f"  start: static equilibrium {'converged' if eq.converged else 'NOT converged (' + eq.reason + ')'}"
              f" in {int(eq.iterations)} iterations")
        x0 = np.asarray(eq.x)
    if "gauge" in case.info:  # a FEMNET net held only at jaxnet's gauge for its static start: free in time
        from jaxnet.io import femnet

        scene = eqx.tree_at(lambda s: s.nodes.fixed, scene, femnet.released_gauge(case).nodes.fixed)
        print(f"  its gauge node {case.info['gauge']['node']} ({case.info['gauge']['axes']}), held for the static "
              "start, is free in time")
    try:
        run = run_lib.simulate(scene, end_time, implicit, loading, record_every=record_every, out=out,
                               resume=args.resume, x0=x0, progress=not args.quiet)
    except dynamics.DynamicsError as err:
        print(f"jaxnet: {err}", file=sys.stderr)
        return FAILED
    except KeyboardInterrupt:
        return _stopped(out, args.argv)
    print(f"  {run.steps} steps, {run.mean_iterations:.2f} Newton iterations per step, {int(run.state.retries)} "
          f"retried; wall {run.timing.wall_s:.2f} s (first interval with compilation {run.timing.compile_s:.2f} s; "
          f"{run.loop} loop)")
    written = [out / "series.npz", out / "series.pvd"]
    if not args.no_pictures:
        from jaxnet.io import plot

        plot.save_run_png(out / "run.png", scene, run.times, run.positions, run.figures, title=label)
        written.append(out / "run.png")
    print(f"  wrote {', '.join(str(p) for p in written)}")
    return OK


def argument_parser() -> argparse.ArgumentParser:
    """The command line's parser (``jaxnet run ...``). Building it imports neither JAX nor the physics."""
    from jaxnet.catalogue import BUILT_IN, DEFAULT, DYNAMIC, DYNAMIC_DEFAULT

    import jaxnet

    parser = argparse.ArgumentParser(
        prog="jaxnet", description="Fishing nets and aquaculture netting in a current and in waves: static "
        "equilibrium and motion in time (D. Priour's triangular netting element, FEMNET's model) on JAX. "
        "Reads jaxnet scene files and FEMNET cases (.don).")
    parser.add_argument("--version", action="version", version=f"jaxnet {jaxnet.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    listing = "; ".join(f"{name}: {b.description}" for name, b in BUILT_IN.items())
    moving = "; ".join(f"{name}: {b.description}" for name, b in DYNAMIC.items())
    run = sub.add_parser("run", help="solve a scene (a built-in scene if no file is given)",
                         description=f"Built-in scenes ({DEFAULT} by default): {listing}. In time (--dynamic, "
                                     f"{DYNAMIC_DEFAULT} by default): {moving}. Exit status 0 converged, 1 a failed "
                                     "solve (its last state written), 2 bad input, 130 stopped by Ctrl-C.")
    run.add_argument("scene", nargs="?", help="scene file (.json or .toml) or FEMNET case (.don)")
    run.add_argument("--mesh", help="with a FEMNET case: solve on FEMNET's mesh (CASE.mdg) instead of jaxnet's")
    run.add_argument("--start", help="with --mesh: start from FEMNET's node positions in this .sta, held nodes too "
                     "(its equilibrium on that mesh, where its dyna starts; or an earlier case's, as its phobos does)")
    run.add_argument("--refine", type=float, help="with a FEMNET case: mesh it this many times finer than its file "
                                                  "says (nodes grow about as its square; for mesh convergence)")
    run.add_argument("--scene", dest="builtin", choices=sorted(set(BUILT_IN) | set(DYNAMIC)),
                     help=f"built-in scene to solve when no file is given (default: {DEFAULT}; with --dynamic "
                          f"{DYNAMIC_DEFAULT})")
    run.add_argument("--set", action="append", metavar="KEY=VALUE",
                     help="change a number of the built-in scene (repeatable), e.g. --set current=0.8 --set step=0.3; "
                          "an unknown KEY lists the scene's")
    run.add_argument("--out", default="jaxnet-out", help="output directory (default: jaxnet-out)")
    run.add_argument("--tol", type=float, help="convergence threshold on the largest nodal force (N)")
    run.add_argument("--max-iter", type=int, dest="max_iter", help="maximum Newton iterations")
    run.add_argument("--quiet", action="store_true", help="no per-iteration progress lines")
    run.add_argument("--no-pictures", action="store_true", dest="no_pictures",
                     help="write the answer only (result.json, ParaView's files), no net.png, net.html or run.png: "
                          "for batch work (jaxnet show DIR draws them later)")
    run.add_argument("--stiffness", choices=("autodiff", "closed_form"),
                     help="the tangent's path: closed_form (the default: the book's hand-derived stiffness where a "
                          "term has one; docs/errata.md) or autodiff (jax.jacfwd of every term, the reference); the "
                          "same matrix either way")
    # jaxnet.solve.options.METHODS, written here so that the command line starts without importing the solver
    run.add_argument("--method", choices=("damped", "primal-dual"),
                     help="the static iteration: damped (Newton on the energy, damped, with a stiffness continuation) "
                          "or primal-dual (an interior-point Newton with each tension-only twine's and bar's tension "
                          "as an unknown); default the library's")
    run.add_argument("--jaxnet-laws", action="store_true", dest="jaxnet_laws",
                     help="with a FEMNET case: jaxnet's own laws (the book's, corrected) where FEMNET's differ (knot "
                          "contact, netting drag with a catch: docs/errata.md), instead of FEMNET's")
    run.add_argument("--dynamic", action="store_true",
                     help="run in time (implicit dynamics) from the static equilibrium; built-in default: "
                          f"{DYNAMIC_DEFAULT}")
    run.add_argument("--end", type=float, help="with --dynamic: end time (s)")
    run.add_argument("--dt", type=float, help="with --dynamic: time step (s), default the case's, else "
                                              "jaxnet.Implicit's")
    run.add_argument("--loop", choices=("auto", "host", "compiled"),
                     help="with --dynamic: who drives the steps (jaxnet.solve.options.Implicit.loop): host (its "
                     "programs kept on disk, reused by the next run and --resume), compiled (one program, compiled "
                     "by every run, cheaper per step), or auto (default: compiled for a run of many steps)")
    run.add_argument("--record", type=float, help="with --dynamic: time between records (s), default every step")
    run.add_argument("--resume", action="store_true", help="with --dynamic: continue the run in --out from its last record")
    run.add_argument("--cache", help=f"directory of compiled programs kept between runs (default: "
                                     f"$XDG_CACHE_HOME/jaxnet or ~/.cache/jaxnet)")
    run.add_argument("--no-cache", action="store_true", dest="no_cache", help="compile everything afresh, keep nothing")
    export = sub.add_parser("export", help="write a built-in scene as a scene file to edit",
                            description="Write a built-in scene (its numbers changed by --set) as a scene file "
                                        "(.toml or .json) to edit and run with jaxnet run FILE.")
    export.add_argument("path", help="the scene file to write (.toml or .json)")
    export.add_argument("--scene", dest="builtin", choices=sorted(set(BUILT_IN) | set(DYNAMIC)), default=DEFAULT,
                        help=f"the built-in scene (default: {DEFAULT})")
    export.add_argument("--set", action="append", metavar="KEY=VALUE",
                        help="change a number of the built-in scene first (repeatable), as jaxnet run --set")
    export.add_argument("--force", action="store_true", help="overwrite the file if it exists")
    show = sub.add_parser("show", help="redraw the pictures of a run without solving",
                          description="Draw the pictures of a run again from the files it wrote in DIR "
                                      "(result.json and net.vtu of a static run, the records of a run in time).")
    show.add_argument("directory", help="the run's output directory (jaxnet run --out DIR)")
    return parser


def _export(args):
    """``jaxnet export --scene NAME [--set KEY=VALUE ...] [--force] FILE``: a built-in scene (its numbers changed by
    ``--set``) written as a scene file (.toml or .json) to edit and run (:func:`jaxnet.io.scene_export.write`); an
    existing FILE is kept unless ``--force``."""
    from jaxnet.catalogue import BUILT_IN, DYNAMIC

    scenes = {**BUILT_IN, **DYNAMIC}
    path = pathlib.Path(args.path)
    if path.suffix not in (".toml", ".json"):
        raise CommandError(f"{path}: a scene file is .toml or .json")
    if path.is_dir():
        raise CommandError(f"{path} is a directory; give the scene file's name (e.g. {path / 'scene.toml'})")
    if path.exists() and not args.force:
        raise CommandError(f"{path} exists: give another name, or --force to overwrite it")
    problem = directory_problem(path.parent)
    if problem is not None:
        raise CommandError(f"cannot write {path}: {problem}")
    make = scenes[args.builtin].make()
    case = make(**built_in_arguments(make, args.builtin, args.set or []))
    from jaxnet.io import scene_export

    written = scene_export.write(path, case)
    print(f"jaxnet: wrote the built-in scene '{args.builtin}' ({case.label}) to {written}; run it with: "
          f"jaxnet run {written}")
    if case.time is not None:
        print("  its time settings (end, steps, records, prescribed motions) are not in the file: give them to "
              "jaxnet run --dynamic (--end, --dt, --record)")
    return OK


#: the file in a run's directory that says what ran: the command line and where it ran from (``jaxnet show``)
COMMAND = "command.json"


def _record_command(out, args):
    """Write DIR/command.json: the run's command line and working directory, from which ``jaxnet show`` rebuilds
    the net to draw it again (a file's name is read relative to that directory)."""
    import jaxnet

    (out / COMMAND).write_text(json.dumps({"argv": args.argv, "cwd": os.getcwd(),
                                           "jaxnet_version": jaxnet.__version__}, indent=1))


def _show(args):
    """``jaxnet show DIR``: the pictures of a run in DIR drawn again, without solving: the net rebuilt from the
    command that ran (DIR/command.json: its scene file, FEMNET case or built-in scene, read again), the positions
    and tensions from what the run wrote (net.vtu and result.json; a run in time's records)."""
    import numpy as np

    from jaxnet.io import plot, timeseries

    directory = pathlib.Path(args.directory)
    if not directory.is_dir():
        raise CommandError(f"show: {directory} is not a directory (the output directory of jaxnet run --out DIR)")
    recorded = directory / COMMAND
    if not recorded.exists():
        raise CommandError(f"show: {directory} holds no {COMMAND}: it is not the output directory of a jaxnet run "
                           f"(jaxnet run --out DIR), or of one older than the command")
    try:
        command = json.loads(recorded.read_text())
        argv = list(command["argv"])
    except (json.JSONDecodeError, KeyError, TypeError) as err:
        raise CommandError(f"show: {recorded} is not the record of a run's command ({err})") from None
    ran = argument_parser().parse_args(argv)
    ran.argv = argv
    for name in ("scene", "mesh", "start"):  # files named relative to where the run was started
        value = getattr(ran, name, None)
        if value is not None and not pathlib.Path(value).is_absolute():
            setattr(ran, name, str(pathlib.Path(command["cwd"]) / value))
    case, label = case_of(ran, dynamic=ran.dynamic)
    scene = case.scene
    written = []
    if ran.dynamic:
        series = timeseries.read_series(directory)
        figures_ = {k: v for k, v in series.items() if k not in ("time", "step", "position", "velocity")}
        path = directory / "run.png"
        plot.save_run_png(path, scene, series["time"], series["position"], figures_, title=label)
        written.append(path)
    else:
        import meshio

        mesh = meshio.read(directory / "net.vtu")
        x = np.asarray(mesh.points, dtype=float)
        if x.shape != (scene.n_nodes, 3):
            raise CommandError(f"show: {directory / 'net.vtu'} holds {x.shape[0]} nodes but {label} has "
                               f"{scene.n_nodes}: the scene changed since the run")
        cells = {k: np.concatenate(v) for k, v in mesh.cell_data.items()}
        triangles = 0 if scene.netting is None else scene.netting.vertices.shape[0]
        tensions = {}
        if triangles and "twine_tension_U_N" in cells:
            tensions["twine_tension"] = np.stack([cells["twine_tension_U_N"][:triangles],
                                                  cells["twine_tension_V_N"][:triangles]], axis=1)
        if scene.bars is not None and "bar_tension_N" in cells:
            tensions["bar_tension"] = cells["bar_tension_N"][-scene.bars.ends.shape[0]:]
        try:
            result = json.loads((directory / "result.json").read_text()) if (directory / "result.json").exists() else {}
        except json.JSONDecodeError as err:
            raise CommandError(f"show: {directory / 'result.json'} is not JSON ({err}): the run's answer is "
                               "damaged") from None
        path = directory / "net.png"
        plot.save_png(path, scene, x, title=label, catch_front=result.get("catch", {}).get("front_m"), **tensions)
        written.append(path)
        if result:
            from jaxnet.io import page

            page.write_html(directory / "net.html", scene, x, result=result, title=label, **tensions)
            written.append(directory / "net.html")
    print(f"jaxnet: drew {', '.join(str(p) for p in written)} from the run in {directory} ({label})")
    return OK


def _bad_input_error(err) -> bool:
    """Whether ``err`` is the physics' bad-input error (:class:`jaxnet.scene.SceneError`), without importing the
    physics to ask: where it was never imported, nothing raised one."""
    scene = sys.modules.get("jaxnet.scene")
    return scene is not None and isinstance(err, scene.SceneError)


def main(argv=None):
    """Run the command line ``argv`` (default ``sys.argv[1:]``); returns the exit status (:data:`OK`,
    :data:`FAILED`, :data:`BAD_INPUT`, :data:`STOPPED`). A user's mistake (a bad file, key or option, a path that
    cannot be read or written) is one line naming it, never a traceback."""
    args = argument_parser().parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # what a stopped run's hint repeats
    try:
        return {"run": _run, "export": _export, "show": _show}[args.command](args)
    except CommandError as err:
        print(f"jaxnet: bad input: {err}", file=sys.stderr)
        return BAD_INPUT
    except KeyboardInterrupt:
        print("jaxnet: stopped (Ctrl-C)", file=sys.stderr)
        return STOPPED
    except OSError as err:
        # a file that could not be read or written while running: named, with the system's reason
        where = f" {err.filename}" if err.filename else ""
        what = "disk full" if err.errno == errno.ENOSPC else _reason(err)
        print(f"jaxnet: bad input: cannot use{where}: {what}", file=sys.stderr)
        return BAD_INPUT
    except Exception as err:
        if _bad_input_error(err):
            print(f"jaxnet: bad input: {err}", file=sys.stderr)
            return BAD_INPUT
        raise


if __name__ == "__main__":
    sys.exit(main())
