"""Command line: ``jaxnet run [SCENE] [--scene NAME] [--mesh CASE.mdg] [--out DIR]``.

With no SCENE, solves a built-in scene (``--scene``, default ``cage``: a fish cage in a current; see
``jaxnet run --help`` for the list). SCENE may be a jaxnet scene file (.json, .toml) or a FEMNET case
(.don, :mod:`jaxnet.io.femnet`); for a FEMNET case ``--mesh CASE.mdg`` solves on FEMNET's own mesh instead
of jaxnet's, and result.json gets a "femnet" section with FEMNET's summary figures (drag on netting,
cables and catch, total force on the fixings, catch thickness and diameter). A FEMNET case uses FEMNET's own
laws where they differ from the book's (``docs/errata.md``), so that it gives FEMNET's answers;
``--jaxnet-laws`` solves it with jaxnet's.
Writes DIR/result.json (figures, see README), DIR/net.vtu (ParaView) and DIR/net.png, prints one line
per Newton iteration and a short summary. Exit status 0 on convergence, 1 on a failed solve, 2 on bad input.

Compiled programs are kept on disk (JAX's persistent compilation cache, in ``--cache DIR``, default
``$XDG_CACHE_HOME/jaxnet`` or ``~/.cache/jaxnet``; ``--no-cache`` to switch it off; a
``JAX_COMPILATION_CACHE_DIR`` set by the user wins): a second run of a case of the same shape and terms —
another current speed, another catch, the same case again — loads them instead of compiling (FEMNET's
c2: about 10 s of compilation becomes about 1 s).
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


def _run(args):
    if not args.no_cache:
        _use_compilation_cache(args.cache)
    from jaxnet import figures
    from jaxnet.io import plot, scene_file, vtk
    from jaxnet.scenes import BUILT_IN
    from jaxnet.solve.statics import Newton, SolveError, solve

    from jaxnet.io import femnet
    from jaxnet.scene import SceneError

    femnet_info = None
    if args.mesh is not None and (args.scene is None or not str(args.scene).endswith(".don")):
        raise SceneError("--mesh (FEMNET's .mdg mesh) goes with a FEMNET case CASE.don")
    if args.scene is None:
        make, description = BUILT_IN[args.builtin]
        net, solver = make(), Newton()
        label = f"built-in scene '{args.builtin}': {description}"
        scene = net.build()
    elif str(args.scene).endswith(".don"):
        if args.mesh is not None:
            scene, solver, femnet_info = femnet.read_mdg(args.mesh, args.scene, femnet_laws=not args.jaxnet_laws)
            label = f"FEMNET case {args.scene} on FEMNET's mesh {args.mesh}"
        else:
            net, solver, femnet_info = femnet.read_don(args.scene, femnet_laws=not args.jaxnet_laws)
            scene = net.build()
            label = f"FEMNET case {args.scene}"
    else:
        net, solver = scene_file.read(args.scene)
        label = str(args.scene)
        scene = net.build()
    overrides = {k: v for k, v in (("tol", args.tol), ("max_iter", args.max_iter), ("stiffness", args.stiffness))
                 if v is not None}
    print(f"jaxnet: {label}")
    print(f"  {scene.n_nodes} nodes, {scene.n_elements} elements, {scene.n_dof} unknowns")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    failed = None
    try:
        eq, timing = solve(scene, solver, verbose=not args.quiet, **overrides)
    except SolveError as err:
        failed, eq, timing = err, err.equilibrium, None
    result = figures.summary(scene, eq, timing)
    if femnet_info is not None:
        result["femnet"] = femnet.femnet_figures(scene, eq, femnet_info["symmetry_axes"])
        result["femnet_case"] = femnet_info
    (out / "result.json").write_text(json.dumps(result, indent=2))
    vtk.write_vtu(out / "net.vtu", scene, eq.x)
    plot.save_png(out / "net.png", scene, eq.x, title=label)
    r = result["reaction_N"]
    print(f"  {'converged' if result['converged'] else 'NOT converged: ' + result['reason']} in {result['iterations']} "
          f"iterations, residual {result['residual_N']:.3g} N")
    if timing is not None:
        print(f"  wall {timing.wall_s:.2f} s (compile {timing.compile_s:.2f} s)")
    print(f"  reaction at fixed nodes [{r[0]:.4g}, {r[1]:.4g}, {r[2]:.4g}] N, max twine tension "
          f"{result['max_twine_tension_N']:.4g} N, max bar tension {result['max_bar_tension_N']:.4g} N")
    print(f"  wrote {out / 'result.json'}, {out / 'net.vtu'}, {out / 'net.png'}")
    if failed is not None:
        print(f"jaxnet: {failed}", file=sys.stderr)
        return 1
    return 0


def main(argv=None):
    from jaxnet.scenes import BUILT_IN, DEFAULT

    parser = argparse.ArgumentParser(prog="jaxnet", description="Static equilibrium of nets (Priour's netting element) on JAX.")
    sub = parser.add_subparsers(dest="command", required=True)
    listing = "; ".join(f"{name}: {text}" for name, (_, text) in BUILT_IN.items())
    run = sub.add_parser("run", help="solve a scene (a built-in scene if no file is given)",
                         description=f"Built-in scenes ({DEFAULT} by default): {listing}.")
    run.add_argument("scene", nargs="?", help="scene file (.json or .toml) or FEMNET case (.don)")
    run.add_argument("--mesh", help="with a FEMNET case: solve on FEMNET's mesh (CASE.mdg) instead of jaxnet's")
    run.add_argument("--scene", dest="builtin", choices=sorted(BUILT_IN), default=DEFAULT,
                     help=f"built-in scene to solve when no file is given (default: {DEFAULT})")
    run.add_argument("--out", default="jaxnet-out", help="output directory (default: jaxnet-out)")
    run.add_argument("--tol", type=float, help="convergence threshold on the largest nodal force (N)")
    run.add_argument("--max-iter", type=int, dest="max_iter", help="maximum Newton iterations")
    run.add_argument("--quiet", action="store_true", help="no per-iteration progress lines")
    run.add_argument("--stiffness", choices=("autodiff", "closed_form"),
                     help="the tangent's path: autodiff (jax.jacfwd of every term) or closed_form (the book's "
                          "hand-derived stiffness where a term has one; docs/errata.md); the same matrix either way")
    run.add_argument("--jaxnet-laws", action="store_true", dest="jaxnet_laws",
                     help="with a FEMNET case: jaxnet's own laws (the book's, corrected) where FEMNET's differ (knot "
                          "contact, netting drag with a catch: docs/errata.md), instead of FEMNET's")
    default_cache = pathlib.Path(os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache") / "jaxnet"
    run.add_argument("--cache", default=str(default_cache),
                     help=f"directory of compiled programs kept between runs (default: {default_cache})")
    run.add_argument("--no-cache", action="store_true", dest="no_cache", help="compile everything afresh, keep nothing")
    args = parser.parse_args(argv)
    from jaxnet.scene import SceneError

    try:
        return _run(args)
    except SceneError as err:
        print(f"jaxnet: bad input: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
