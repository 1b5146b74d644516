"""Benchmark of design sweeps on a cluster (jaxnet.design.sweep): one process against a local Dask cluster,
cold and warm.

    python benchmarks/design_sweep.py [--scene cage|cage:STEP|panel] [--designs 24] [--workers 2]

The same N designs are solved (each from the reference design's equilibrium, by
:func:`jaxnet.design.sweep.solve_design`, the figures the drag and the netting's deployed area):

* ``one process, cold`` / ``warm``: in a fresh Python process, one design after the other, with an empty
  compilation cache directory / with the one the cold run filled;
* ``cluster, cold`` / ``warm``: :func:`jaxnet.design.sweep.sweep` on a new local cluster of ``--workers``
  worker processes (one thread each), with an empty cache directory / the one the cold cluster filled.

Printed per run: the wall time of the whole run (a cluster's including its start and close, a process's its
imports), of the cluster's start alone, per design (the whole run over N), the first task of each worker
(which builds its workspace: the net, the reference equilibrium, the compiled programs) and the mean of the
later tasks, these two also in CPU time (the worker process's, all threads: the work done, which a loaded
machine does not inflate as it does the wall time); the compiled programs the run added to the cache
directory (a warm run adding some compiled them again) and the JAX persistent-cache hits counted in the
worker processes.

The scene: ``cage``, the fish cage meshed at 1.6 m (:func:`jaxnet.scenes.fish_cage`, 137 nodes, current
0.5 m/s), the designs scaling every panel's mesh side by 0.985-1.015 and the twine diameter by 0.8-1.2;
``cage:STEP``, the cage meshed at STEP m (465 nodes at 0.8 m); ``panel``, the hanging panel of 8 x 8 meshes
(51 nodes, still water; its twines resisting compression as traction and its sinker bar hinged, the smooth
equilibrium that the design studies' jitted Newton reaches quadratically), mesh side 23-25 mm. The machine's cores and load average are printed: on a shared
machine the columns are comparable only within one run.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import subprocess
import sys
import tempfile
import time

SCENES = {"cage": ("jaxnet.scenes", "fish_cage", {"step": 1.6}),
          "panel": ("jaxnet.scenes.panel", "hanging_panel", {"meshes": 8, "step": 0.05})}


def _recipe(scene):
    """(function, keyword arguments) of a scene name, ``cage`` or ``panel``, or ``cage:STEP`` (the cage meshed
    at STEP m)."""
    import importlib

    from jaxnet.net import Twine

    scene, _, step = scene.partition(":")
    module, name, kwargs = SCENES[scene]
    if scene == "panel":
        kwargs = {**kwargs, "twine": Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=2000.0),
                  "sinker_bending_stiffness": 0.0}
    return getattr(importlib.import_module(module), name), {**kwargs, **({"step": float(step)} if step else {})}


def _designs(scene, n):
    """N θ dicts of the scene."""
    import numpy as np

    from jaxnet.design import sweep

    space = sweep.Recipe.of(_recipe(scene)).build()
    initial = space.initial()
    cage = scene.startswith("cage")
    scale = np.linspace(0.985, 1.015, n) if cage else np.linspace(0.92, 1.0, n)
    thick = np.linspace(0.8, 1.2, n)
    out = []
    for s, t in zip(scale, thick):
        theta = {"mesh_side": {p: float(initial["mesh_side"][p]) * s for p in space.panels}}
        if cage:
            theta["twine_diameter"] = {p: float(initial["twine_diameter"][p]) * t for p in space.panels}
        out.append(theta)
    return out


def _figures():
    from jaxnet.design import objectives

    return {"drag": objectives.drag(), "area": objectives.netting_area(deployed=True)}


def _programs(cache):
    """Files in a cache directory (JAX's entries and jaxnet's programs)."""
    return sum(1 for p in pathlib.Path(cache).rglob("*") if p.is_file()) if pathlib.Path(cache).exists() else 0


def _count_hits():
    """In a worker: count JAX's persistent-cache hits from now on (the count kept on the ``sys`` module: this
    function reaches the workers by value, without a module of its own to keep it in)."""
    import jax

    sys.jaxnet_cache_hits = [0]
    jax.monitoring.register_event_listener(
        lambda event, **_: sys.jaxnet_cache_hits.__setitem__(0, sys.jaxnet_cache_hits[0]
                                                             + (event == "/jax/compilation_cache/cache_hits")))


def _hits():
    return sys.jaxnet_cache_hits[0]


def one_process(scene, n, cache):
    """In this (fresh) process: solve the designs one after the other; print the rows as JSON."""
    start = time.perf_counter()
    import jax

    if cache:
        jax.config.update("jax_compilation_cache_dir", cache)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.2)
    _count_hits()
    from jaxnet.design import sweep
    from jaxnet.solve.options import DIFFERENTIABLE

    recipe, figures = sweep.Recipe.of(_recipe(scene)), _figures()
    rows = [sweep.solve_design(recipe, DIFFERENTIABLE, None, figures, k, theta)
            for k, theta in enumerate(_designs(scene, n))]
    print(json.dumps({"rows": rows, "wall_s": time.perf_counter() - start, "hits": _hits()}))


def _in_process(scene, n, cache):
    command = [sys.executable, __file__, "--scene", scene, "--designs", str(n), "--one-process", cache]
    done = subprocess.run(command, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _on_cluster(scene, n, workers, cache):
    from distributed import Client, LocalCluster

    from jaxnet.design import sweep

    designs = _designs(scene, n)
    start = time.perf_counter()
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    client = Client(cluster)
    client.wait_for_workers(workers)
    started = time.perf_counter() - start
    client.run(_count_hits)
    table = sweep.sweep(_recipe(scene), designs, _figures(), address=client, progress=False, cache=cache)
    hits = sum(client.run(_hits).values())
    client.close()
    cluster.close()
    return {"rows": table.rows, "wall_s": time.perf_counter() - start, "start_s": started, "hits": hits}


def _line(label, n, run, added):
    rows = run["rows"]
    first = [r for r in rows if r["setup_s"]]
    later = [r for r in rows if not r["setup_s"]]
    failed = sum(r["status"] != "done" for r in rows)
    firsts = " ".join(f"{r['wall_s']:.1f} ({r['cpu_s']:.1f})" for r in first)
    start = f"{run['start_s']:.1f}" if "start_s" in run else "-"
    wall = sum(r["wall_s"] for r in later) / len(later) if later else float("nan")
    cpu = sum(r["cpu_s"] for r in later) / len(later) if later else float("nan")
    print(f"{label:18s} {run['wall_s']:7.1f} {start:>6s} {run['wall_s'] / n:11.2f} {firsts:>24s} "
          f"{f'{1e3 * wall:.0f} ({1e3 * cpu:.0f})':>15s} {sum(r['iterations'] or 0 for r in rows) / n:7.1f} "
          f"{added:6d} {run['hits']:5d} {failed:6d}")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="cage", help="cage (meshed at 1.6 m), cage:STEP (meshed at STEP m) or panel")
    parser.add_argument("--designs", type=int, default=24)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--one-process", default=None, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.one_process is not None:
        return one_process(args.scene, args.designs, args.one_process)
    function, kwargs = _recipe(args.scene)
    name = function.__name__
    print(f"{name}({', '.join(f'{k}={v!r}' for k, v in kwargs.items())}), {args.designs} designs; {args.workers} "
          f"workers; {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the start")
    print(f"{'run':18s} {'wall s':>7s} {'start':>6s} {'wall/design':>11s} {'first tasks s (cpu)':>24s} "
          f"{'later ms (cpu)':>15s} {'Newton':>7s} {'cached':>6s} {'hits':>5s} {'failed':>6s}")
    with tempfile.TemporaryDirectory() as process_cache, tempfile.TemporaryDirectory() as cluster_cache:
        for label, cache in (("one process, cold", process_cache), ("one process, warm", process_cache)):
            before = _programs(cache)
            run = _in_process(args.scene, args.designs, cache)
            _line(label, args.designs, run, _programs(cache) - before)
        for label in ("cluster, cold", "cluster, warm"):
            before = _programs(cluster_cache)
            run = _on_cluster(args.scene, args.designs, args.workers, cluster_cache)
            _line(label, args.designs, run, _programs(cluster_cache) - before)
    print(f"load average {os.getloadavg()[0]:.1f} at the end. Columns: wall, the whole run (s); start, the "
          "cluster's start (s); wall/design, wall / N (s); first tasks, each worker's (process's) first task, wall "
          "and CPU time (s); later, the mean of the other tasks, wall and CPU time (ms); Newton, the mean "
          "iterations; cached, files the run added to "
          "the cache directory; hits, JAX persistent-cache hits in the workers")


if __name__ == "__main__":
    main()
