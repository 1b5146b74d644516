"""Command line: ``jaxnet run [SCENE] [--scene NAME [--set KEY=VALUE ...]] [--mesh CASE.mdg] [--out DIR]``,
``jaxnet export --scene NAME [--set ...] FILE`` (a built-in scene written as a scene file to edit), ``jaxnet show
DIR`` (a run's pictures drawn again without solving), ``jaxnet --version``.

With no SCENE, solves a built-in scene (``--scene``, default ``cage``: a fish cage in a current; see
``jaxnet run --help`` for the list). SCENE may be a jaxnet scene file (.json, .toml) or a FEMNET case
(.don, :mod:`jaxnet.io.femnet`); for a FEMNET case ``--mesh CASE.mdg`` solves on FEMNET's own mesh instead
of jaxnet's, and ``--start CASE.sta`` (with ``--mesh``) starts it from FEMNET's stored node positions (its
equilibrium, or an earlier case's, as FEMNET's ``phobos`` and ``dyna`` start theirs); result.json gets a "femnet"
section with FEMNET's summary figures (drag on netting, cables and catch, total force on the fixings, catch
thickness and diameter). A FEMNET case uses FEMNET's own
laws where they differ from the book's (``docs/errata.md``), so that it gives FEMNET's answers;
``--jaxnet-laws`` solves it with jaxnet's.
Writes DIR/result.json (the figures, ``docs/result.md``), DIR/net.vtu (ParaView: tensions, displacement, nodal
forces by group, reactions; DIR/net_whole.vtu beside it for a model with symmetry planes), DIR/net.png (the
pictures) and DIR/command.json (the command, for ``jaxnet show``), prints one line per Newton iteration and a
short summary. ``--set`` changes a built-in scene's numbers (its function's keyword arguments). Exit status 0
on convergence, 1 on a failed solve (its last state still written, net.vtu with its residual), 2 on bad input.

``--dynamic`` runs the scene in time instead (:mod:`jaxnet.solve.dynamics`, the book's implicit scheme):
from its static equilibrium (computed first), to ``--end`` seconds with steps of ``--dt`` seconds, a record
every ``--record`` seconds written to DIR as it goes (series.json + raw/ arrays, series.npz at the end,
series.pvd + net_NNNNN.vtu for ParaView, checkpoint.npz; ``--resume`` continues a stopped run from its last
record; run.png at the end: the reactions and largest tensions against time), with a progress bar. A FEMNET case takes its own time settings, towing tables, winches and numerics
(its threshold, iterations and displacement limit, for the static start and for every time step); ``--tol``,
``--max-iter`` and ``--stiffness`` apply to both as in a static run. The built-in ``cage_waves`` (the default with ``--dynamic``) is
the cage in regular waves, its collar heaving.

Compiled programs are kept on disk (in ``--cache DIR``, default ``$XDG_CACHE_HOME/jaxnet`` or
``~/.cache/jaxnet``: the static solver's programs whole, :mod:`jaxnet.solve.programs`, the others in JAX's
persistent compilation cache; ``--no-cache`` to switch both off; a ``JAX_COMPILATION_CACHE_DIR`` set by the
user wins): a second run of a case of the same shape and terms — another current speed, another catch, the
same case again — loads them instead of tracing and compiling, most of a first run's time
(``validation/femnet_cases.py`` times cold runs with and without them).
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import sys


def _use_compilation_cache(directory):
    """Turn on JAX's persistent compilation cache in ``directory`` (the solver's pieces hold no host
    callback, so they can be cached), unless the user already chose one."""
    import jax

    if os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return
    jax.config.update("jax_compilation_cache_dir", str(directory))
    # the default (1 s) would leave out the smaller pieces of a small scene
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)


def _case(args, dynamic):
    """The case the command names (a built-in scene, a scene file, a FEMNET case on jaxnet's or FEMNET's mesh,
    started from a FEMNET .sta)."""
    import dataclasses

    from jaxnet.io import femnet, scene_file
    from jaxnet.scene import SceneError
    from jaxnet.scenes import BUILT_IN, DYNAMIC, DYNAMIC_DEFAULT

    if args.mesh is not None and (args.scene is None or not str(args.scene).endswith(".don")):
        raise SceneError("--mesh (FEMNET's .mdg mesh) goes with a FEMNET case CASE.don")
    if args.refine is not None and (args.scene is None or not str(args.scene).endswith(".don") or args.mesh):
        raise SceneError("--refine (a mesh finer than the file's) goes with a FEMNET case CASE.don meshed by jaxnet "
                         "(not with --mesh)")
    settings = getattr(args, "set", None) or []
    if settings and args.scene is not None:
        raise SceneError("--set changes a built-in scene's arguments (--scene NAME); a scene file or a FEMNET case "
                         "is changed by editing it (jaxnet export --scene NAME FILE writes a built-in to a file)")
    if args.scene is None:
        if dynamic:
            name = args.builtin if args.builtin in DYNAMIC else DYNAMIC_DEFAULT
            make, description = DYNAMIC[name]
        else:
            if args.builtin not in BUILT_IN:
                raise SceneError(f"the built-in scene '{args.builtin}' is a dynamic one: run it with --dynamic")
            name = args.builtin
            make, description = BUILT_IN[name]
        changes = built_in_arguments(make, name, settings)
        said = "; " + ", ".join(f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in changes.items()) \
            if changes else ""
        kind = "built-in dynamic scene" if dynamic else "built-in scene"
        return make(**changes), f"{kind} '{name}': {description}{said}"
    if args.start is not None and args.mesh is None:
        raise SceneError("--start (FEMNET's node positions, a .sta) goes with --mesh: they are numbered on its mesh")
    if str(args.scene).endswith(".don"):
        laws = not args.jaxnet_laws
        case = (femnet.read_mdg(args.mesh, args.scene, femnet_laws=laws) if args.mesh is not None
                else femnet.read_don(args.scene, femnet_laws=laws, refine=1.0 if args.refine is None else args.refine))
        if args.start is not None:
            case = femnet.started_from_sta(case, args.start)
            case = dataclasses.replace(case, label=f"{case.label}, started from {args.start}")
        return case, case.label
    case = scene_file.read(args.scene)
    return case, case.label




def built_in_arguments(make, name, settings):
    """The keyword arguments ``--set KEY=VALUE ...`` give the function ``make`` of the built-in scene ``name``:
    each KEY one of its number or integer parameters (its defaults say which), VALUE read as that type. Raises
    SceneError naming an unknown key (with the known ones) or a value of the wrong kind, before anything is built."""
    import inspect

    from jaxnet.scene import SceneError

    parameters = {p.name: p for p in inspect.signature(make).parameters.values()
                  if isinstance(p.default, (int, float)) and not isinstance(p.default, bool)}
    out = {}
    for item in settings:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or not key:
            raise SceneError(f"--set {item!r}: expected KEY=VALUE, e.g. --set current=0.8")
        if key not in parameters:
            raise SceneError(f"--set {key}: the built-in scene '{name}' has no such number; it has: "
                             f"{', '.join(f'{k} (default {p.default!r})' for k, p in parameters.items())}")
        kind = type(parameters[key].default)
        try:
            value = kind(text) if kind is float else int(text)
        except ValueError:
            raise SceneError(f"--set {key}={text}: expected {'an integer' if kind is int else 'a number'}") from None
        out[key] = value
    return out


def _overrides(args):
    """The Newton options the command line sets (``--tol``, ``--max-iter``, ``--stiffness``): for the static solve,
    and in a run in time for its start and for every time step."""
    return {k: v for k, v in (("tol", args.tol), ("max_iter", args.max_iter), ("stiffness", args.stiffness))
            if v is not None}


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


def _run(args):
    import dataclasses

    if not args.no_cache:
        _use_compilation_cache(args.cache)
    if args.dynamic:
        return _run_dynamic(args)
    import jax

    from jaxnet import figures, linalg
    from jaxnet.io import femnet, plot, vtk
    from jaxnet.solve.statics import SolveError, solve

    case, label = _case(args, dynamic=False)
    scene = case.scene
    print(f"jaxnet: {label}")
    print(f"  {scene.n_nodes} nodes, {scene.n_elements} elements, {scene.n_dof} unknowns")
    for line in case.info.get("warnings", []):       # a FEMNET case read as FEMNET would, with a difference said
        print(f"  note: {line}")
    if case.info.get("dynamic_only"):
        print(f"  left out of this static run (FEMNET's dynamics only): {', '.join(case.info['dynamic_only'])}")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    _record_command(out, args)
    failed = None
    try:
        eq = solve(case, verbose=not args.quiet, **_overrides(args))
    except SolveError as err:
        failed, eq = err, err.equilibrium
    # what the solve ran with: the case's options with the command line's (solve() above took the same)
    used = dataclasses.replace(case.solver, verbose=not args.quiet, **_overrides(args))
    result = figures.summary(scene, eq, case=case, source=None if args.scene is None else str(args.scene), solver=used)
    if "symmetry_axes" in case.info:  # a FEMNET case: its own figures, and what the reader decided
        result["femnet"] = femnet.femnet_figures(scene, eq, case.info["symmetry_axes"], case.info.get("fixity"))
        result["femnet"]["printed"] = femnet.text_output_figures(scene, eq, case.info)
        result["femnet_case"] = case.info
    (out / "result.json").write_text(json.dumps(result, indent=2))
    # a failed solve's file holds its residual, where the net is out of balance
    written = [out / "result.json", *vtk.write_vtu(out / "net.vtu", scene, eq.x,
                                                  residual=None if failed is None else eq.force)]
    plot.save_png(out / "net.png", scene, eq.x, title=label, catch_front=result.get("catch", {}).get("front_m"))
    written.append(out / "net.png")

    def shown(value):  # -0.0 + 0.0 is 0.0: no "-0" printed
        return f"{value + 0.0:.4g}"

    def vector(values):
        return "[" + ", ".join(shown(v) for v in values) + "] N"

    whole = result["whole_net"]
    print(f"  {'converged' if result['converged'] else 'NOT converged: ' + result['reason']} in {result['iterations']} "
          f"iterations, residual {result['residual_N']:.3g} N")
    if eq.timing is not None:
        print(f"  wall {eq.timing.wall_s:.2f} s (compile {eq.timing.compile_s:.2f} s; JAX on {jax.default_backend()}, "
              f"tangents factorised by {linalg.solver_choice()})")
    part = f" (the model: {result['modelled_part']})" if whole["copies"] > 1 else ""
    print(f"  reaction at fixed nodes {vector(result['reaction_N'])}, load {vector(result['load_N'])}{part}")
    if whole["copies"] > 1:
        catch = f", catch drag {shown(result['catch']['drag_whole_net_N'])} N" if "catch" in result else ""
        print(f"  whole net ({whole['copies']} mirrored copies): reaction {vector(whole['reaction_N'])}, load "
              f"{vector(whole['load_N'])}{catch}")
    tensions = ([f"max twine tension {shown(result['max_twine_tension_N'])} N"] if result["n_triangles"] else []) + (
        [f"max bar tension {shown(result['max_bar_tension_N'])} N"] if result["n_bars"] else [])
    if tensions:
        print("  " + ", ".join(tensions))
    for figure in result.get("femnet", {}).get("printed", []):   # FEMNET's text outputs, as it prints them
        if figure["value"] is not None:
            print(f"  {figure['comment']}: {figure['value']:.6g} {figure['unit']}")
    print(f"  wrote {', '.join(str(p) for p in written)}")
    if failed is not None:
        print(f"jaxnet: {failed}", file=sys.stderr)
        return 1
    return 0


def _stopped(out, argv):
    """What a dynamic run stopped by Ctrl-C says: where its records end, and the command that continues it
    (exit status 130, the shell's for an interrupt)."""
    import shlex

    from jaxnet.io import timeseries

    point = timeseries.resume_point(out)
    where = f"its records in {out} end at t = {point[0].time:g} s" if point else f"no record in {out} yet"
    again = [a for a in argv if a != "--resume"] + ["--resume"]
    print(f"jaxnet: stopped (Ctrl-C); {where}. Continue with: jaxnet {shlex.join(again)}", file=sys.stderr)
    return 130


def _run_dynamic(args):
    import numpy as np

    import equinox as eqx

    from jaxnet.scene import SceneError
    from jaxnet.solve import dynamics
    from jaxnet.solve.statics import solve

    case, label = _case(args, dynamic=True)
    overrides = _overrides(args)
    settings, implicit = time_stepping(case, args)
    end_time = args.end if args.end is not None else settings.end_time
    record_every = args.record if args.record is not None else settings.record_every
    if end_time is None:
        raise SceneError("--dynamic: give the end time (--end, s); the scene has none")
    scene = case.scene
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
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
        run = dynamics.simulate(scene, end_time, implicit, loading, record_every=record_every, out=out,
                                resume=args.resume, x0=x0, progress=not args.quiet)
    except dynamics.DynamicsError as err:
        print(f"jaxnet: {err}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return _stopped(out, args.argv)
    print(f"  {run.steps} steps, {run.mean_iterations:.2f} Newton iterations per step, {int(run.state.retries)} "
          f"retried; wall {run.timing.wall_s:.2f} s (first interval with compilation {run.timing.compile_s:.2f} s; "
          f"{run.loop} loop)")
    from jaxnet.io import plot

    plot.save_run_png(out / "run.png", scene, run.times, run.positions, run.figures, title=label)
    print(f"  wrote {out / 'series.npz'}, {out / 'series.pvd'}, {out / 'run.png'}")
    return 0


def argument_parser() -> argparse.ArgumentParser:
    """The command line's parser (``jaxnet run ...``)."""
    from jaxnet.scenes import BUILT_IN, DEFAULT, DYNAMIC
    from jaxnet.solve.options import Implicit

    import jaxnet

    parser = argparse.ArgumentParser(
        prog="jaxnet", description="Fishing nets and aquaculture netting in a current and in waves: static "
        "equilibrium and motion in time (D. Priour's triangular netting element, FEMNET's model) on JAX. "
        "Reads jaxnet scene files and FEMNET cases (.don).")
    parser.add_argument("--version", action="version", version=f"jaxnet {jaxnet.__version__}")
    sub = parser.add_subparsers(dest="command", required=True)
    listing = "; ".join(f"{name}: {text}" for name, (_, text) in BUILT_IN.items())
    run = sub.add_parser("run", help="solve a scene (a built-in scene if no file is given)",
                         description=f"Built-in scenes ({DEFAULT} by default): {listing}.")
    run.add_argument("scene", nargs="?", help="scene file (.json or .toml) or FEMNET case (.don)")
    run.add_argument("--mesh", help="with a FEMNET case: solve on FEMNET's mesh (CASE.mdg) instead of jaxnet's")
    run.add_argument("--start", help="with --mesh: start from FEMNET's node positions in this .sta, held nodes too "
                     "(its equilibrium on that mesh, where its dyna starts; or an earlier case's, as its phobos does)")
    run.add_argument("--refine", type=float, help="with a FEMNET case: mesh it this many times finer than its file "
                                                  "says (nodes grow about as its square; for mesh convergence)")
    run.add_argument("--scene", dest="builtin", choices=sorted(set(BUILT_IN) | set(DYNAMIC)), default=DEFAULT,
                     help=f"built-in scene to solve when no file is given (default: {DEFAULT})")
    run.add_argument("--set", action="append", metavar="KEY=VALUE",
                     help="change a number of the built-in scene (repeatable), e.g. --set current=0.8 --set step=0.3; "
                          "an unknown KEY lists the scene's")
    run.add_argument("--out", default="jaxnet-out", help="output directory (default: jaxnet-out)")
    run.add_argument("--tol", type=float, help="convergence threshold on the largest nodal force (N)")
    run.add_argument("--max-iter", type=int, dest="max_iter", help="maximum Newton iterations")
    run.add_argument("--quiet", action="store_true", help="no per-iteration progress lines")
    run.add_argument("--stiffness", choices=("autodiff", "closed_form"),
                     help="the tangent's path: closed_form (the default: the book's hand-derived stiffness where a "
                          "term has one; docs/errata.md) or autodiff (jax.jacfwd of every term, the reference); the "
                          "same matrix either way")
    run.add_argument("--jaxnet-laws", action="store_true", dest="jaxnet_laws",
                     help="with a FEMNET case: jaxnet's own laws (the book's, corrected) where FEMNET's differ (knot "
                          "contact, netting drag with a catch: docs/errata.md), instead of FEMNET's")
    run.add_argument("--dynamic", action="store_true",
                     help="run in time (implicit dynamics) from the static equilibrium; built-in default: cage_waves")
    run.add_argument("--end", type=float, help="with --dynamic: end time (s)")
    run.add_argument("--dt", type=float,
                     help=f"with --dynamic: time step (s), default {Implicit.time_step:g} or the case's")
    run.add_argument("--loop", choices=("auto", "host", "compiled"),
                     help="with --dynamic: who drives the steps (jaxnet.solve.options.Implicit.loop): host (its "
                     "programs kept on disk, reused by the next run and --resume), compiled (one program, compiled "
                     "by every run, cheaper per step), or auto (default: compiled for a run of many steps)")
    run.add_argument("--record", type=float, help="with --dynamic: time between records (s), default every step")
    run.add_argument("--resume", action="store_true", help="with --dynamic: continue the run in --out from its last record")
    export = sub.add_parser("export", help="write a built-in scene as a scene file to edit",
                            description="Write a built-in scene (its numbers changed by --set) as a scene file "
                                        "(.toml or .json) to edit and run with jaxnet run FILE.")
    export.add_argument("path", help="the scene file to write (.toml or .json)")
    export.add_argument("--scene", dest="builtin", choices=sorted(set(BUILT_IN) | set(DYNAMIC)), default=DEFAULT,
                        help=f"the built-in scene (default: {DEFAULT})")
    export.add_argument("--set", action="append", metavar="KEY=VALUE",
                        help="change a number of the built-in scene first (repeatable), as jaxnet run --set")
    show = sub.add_parser("show", help="redraw the pictures of a run without solving",
                          description="Draw the pictures of a run again from the files it wrote in DIR "
                                      "(result.json and net.vtu of a static run, the records of a run in time).")
    show.add_argument("directory", help="the run's output directory (jaxnet run --out DIR)")
    default_cache = pathlib.Path(os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache") / "jaxnet"
    run.add_argument("--cache", default=str(default_cache),
                     help=f"directory of compiled programs kept between runs (default: {default_cache})")
    run.add_argument("--no-cache", action="store_true", dest="no_cache", help="compile everything afresh, keep nothing")
    return parser


def _export(args):
    """``jaxnet export --scene NAME [--set KEY=VALUE ...] FILE``: a built-in scene (its numbers changed by ``--set``)
    written as a scene file (.toml or .json) to edit and run (:func:`jaxnet.io.scene_file.write`)."""
    from jaxnet.io import scene_file
    from jaxnet.scene import SceneError
    from jaxnet.scenes import BUILT_IN, DYNAMIC

    scenes = {**BUILT_IN, **DYNAMIC}
    if args.builtin not in scenes:
        raise SceneError(f"export: no built-in scene '{args.builtin}' (there are: {', '.join(scenes)})")
    make, description = scenes[args.builtin]
    case = make(**built_in_arguments(make, args.builtin, args.set or []))
    path = scene_file.write(args.path, case)
    print(f"jaxnet: wrote the built-in scene '{args.builtin}' ({description}) to {path}; run it with: "
          f"jaxnet run {path}")
    if case.time is not None:
        print("  its time settings (end, steps, records, prescribed motions) are not in the file: give them to "
              "jaxnet run --dynamic (--end, --dt, --record)")
    return 0


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
    from jaxnet.scene import SceneError

    directory = pathlib.Path(args.directory)
    recorded = directory / COMMAND
    if not recorded.exists():
        raise SceneError(f"show: {directory} holds no {COMMAND}: it is not the output directory of a jaxnet run "
                         f"(jaxnet run --out DIR), or of one older than the command")
    command = json.loads(recorded.read_text())
    ran = argument_parser().parse_args(command["argv"])
    ran.argv = command["argv"]
    for name in ("scene", "mesh", "start"):  # files named relative to where the run was started
        value = getattr(ran, name, None)
        if value is not None and not pathlib.Path(value).is_absolute():
            setattr(ran, name, str(pathlib.Path(command["cwd"]) / value))
    case, label = _case(ran, dynamic=ran.dynamic)
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
            raise SceneError(f"show: {directory / 'net.vtu'} holds {x.shape[0]} nodes but {label} has "
                             f"{scene.n_nodes}: the scene changed since the run")
        cells = {k: np.concatenate(v) for k, v in mesh.cell_data.items()}
        triangles = 0 if scene.netting is None else scene.netting.vertices.shape[0]
        tensions = {}
        if triangles and "twine_tension_U_N" in cells:
            tensions["twine_tension"] = np.stack([cells["twine_tension_U_N"][:triangles],
                                                  cells["twine_tension_V_N"][:triangles]], axis=1)
        if scene.bars is not None and "bar_tension_N" in cells:
            tensions["bar_tension"] = cells["bar_tension_N"][-scene.bars.ends.shape[0]:]
        result = json.loads((directory / "result.json").read_text()) if (directory / "result.json").exists() else {}
        path = directory / "net.png"
        plot.save_png(path, scene, x, title=label, catch_front=result.get("catch", {}).get("front_m"), **tensions)
        written.append(path)
    print(f"jaxnet: drew {', '.join(str(p) for p in written)} from the run in {directory} ({label})")
    return 0


def main(argv=None):
    from jaxnet.scene import SceneError

    args = argument_parser().parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)  # what a stopped run's hint repeats

    try:
        return {"run": _run, "export": _export, "show": _show}[args.command](args)
    except SceneError as err:
        print(f"jaxnet: bad input: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
