"""Benchmark of batches of designs (jaxnet.design.batch): vmapped on one device, one by one, sharded.

    python benchmarks/design_batch.py [--sizes 1 4 16] [--meshes 4] [--devices 4] [--repeats 3] [--gradient]

The scene is the hanging panel of ``--meshes`` meshes (jaxnet.scenes.panel, no current, meshing step 0.05 m:
15 nodes at 4 meshes; its twines resisting compression as traction and its sinker bar hinged, the smooth
equilibrium that the jitted Newton reaches quadratically), every design starting from the flat drawing. A batch of B designs sweeps the mesh
side (24-26 mm) and the twine diameter (1-2 mm). For each B, printed: the wall time of

* ``vmap``, ``map``: :func:`jaxnet.design.batch.solve_batch`, the B designs in one program on one CPU device,
  batched (``method="vmap"``) or one after the other (``method="map"``, ``jax.lax.map``);
* ``loop``: the B designs one after the other through one jitted single-design equilibrium, from Python;
* ``sharded vmap``, ``sharded map``: :func:`jaxnet.design.batch.solve_sharded` over ``--devices`` emulated
  CPU devices, each device batching or mapping over its share, in a
  subprocess started with ``XLA_FLAGS=--xla_force_host_platform_device_count=D+1`` (jax reads it once, at
  start): the mesh takes devices 1..D, leaving XLA's CPU client the thread to spare that a sharded solve
  needs (:func:`jaxnet.design.batch.design_mesh`);

warm (the best of ``--repeats`` runs after a first, compiling one, whose time is printed apart) and per
design, with the Newton iterations (largest and total over the batch). ``--gradient`` adds a figure (the
mean node depth) and its gradient in θ to every solve. The machine's cores and load average are printed:
on a shared machine the columns are comparable only within one run.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time


def _setup(meshes, gradient):
    import jax.numpy as jnp
    import numpy as np

    import jaxnet  # noqa: F401  (float64)
    from jaxnet.design.space import DesignSpace
    from jaxnet.net import Twine
    from jaxnet.scenes.panel import hanging_panel
    from jaxnet.solve import implicit

    stiff = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=2000.0)
    space = DesignSpace(hanging_panel(meshes=meshes, step=0.05, twine=stiff, sinker_bending_stiffness=0.0))
    structure = implicit.structure_of(space.reference)
    x0 = np.asarray(space.reference.nodes.position)
    figure = (lambda outcome: jnp.mean(outcome.x[:, 2])) if gradient else None
    return space, structure, x0, figure


def _designs(size):
    import numpy as np

    return {"mesh_side": {"netting": np.linspace(0.024, 0.026, size)},
            "twine_diameter": {"netting": np.linspace(1e-3, 2e-3, size)}}


def _timed(run, repeats):
    """(first call's wall time s, best of ``repeats`` later calls s, the last result)."""
    import jax

    t0 = time.perf_counter()
    out = jax.block_until_ready(run())
    cold = time.perf_counter() - t0
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = jax.block_until_ready(run())
        best = min(best, time.perf_counter() - t0)
    return cold, best, out


def _iterations(out):
    import numpy as np

    it = np.asarray(out.iterations)
    return int(it.max()), int(it.sum())


def one_device(sizes, meshes, repeats, gradient):
    """{B: {"vmap": ..., "map": ..., "loop": ...}} timings on one CPU device."""
    import jax
    import numpy as np

    from jaxnet.design import batch, objectives
    from jaxnet.solve import implicit

    space, structure, x0, figure = _setup(meshes, gradient)

    def solved(theta):
        scene = space.scene(theta)
        eq = implicit.equilibrium(scene, structure, x0=x0)
        return (0.0 if figure is None else figure(objectives.Outcome(eq.x, scene, structure.model))), eq

    def single(theta):  # what solve_batch computes for one design, without vmap
        if figure is None:
            return solved(theta)[1].x
        return jax.value_and_grad(solved, has_aux=True)(theta)

    single = jax.jit(single)
    rows = {}
    for size in sizes:
        thetas = _designs(size)
        row = rows[size] = {}
        for method in batch.METHODS:
            cold, warm, out = _timed(lambda: batch.solve_batch(space, thetas, structure, x0, figure=figure,
                                                               method=method), repeats)
            row[method] = dict(cold=cold, warm=warm, iterations=_iterations(out))
        designs = [jax.tree_util.tree_map(lambda a: np.asarray(a[b]), thetas) for b in range(size)]
        cold, warm, _ = _timed(lambda: [single(d) for d in designs], repeats)
        row["loop"] = dict(cold=cold, warm=warm)
    return rows, space.reference.n_nodes


def sharded(sizes, meshes, repeats, gradient):
    """{B: {"sharded vmap": ..., "sharded map": ...}} timings over the (emulated) devices of this process but
    the first."""
    import jax

    from jaxnet.design import batch

    space, structure, x0, figure = _setup(meshes, gradient)
    mesh = batch.design_mesh(jax.devices()[1:])
    rows = {}
    for size in sizes:
        thetas = _designs(size)
        row = rows[size] = {}
        for method in batch.METHODS:
            cold, warm, out = _timed(lambda: batch.solve_sharded(space, thetas, structure, x0, figure=figure,
                                                                 method=method, mesh=mesh), repeats)
            row[f"sharded {method}"] = dict(cold=cold, warm=warm)
    return rows, mesh.size


COLUMNS = ("vmap", "map", "loop", "sharded vmap", "sharded map")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 4, 16])
    parser.add_argument("--meshes", type=int, default=4)
    parser.add_argument("--devices", type=int, default=4)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--gradient", action="store_true")
    parser.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:  # the sharded half, in its own process with D + 1 emulated devices
        rows, devices = sharded(args.sizes, args.meshes, args.repeats, args.gradient)
        print(json.dumps(dict(rows=rows, devices=devices)))
        return
    env = dict(os.environ, XLA_FLAGS=f"--xla_force_host_platform_device_count={args.devices + 1}", JAX_PLATFORMS="cpu")
    command = [sys.executable, __file__, "--worker", "--meshes", str(args.meshes), "--repeats", str(args.repeats),
               "--sizes", *map(str, args.sizes)] + (["--gradient"] if args.gradient else [])
    os.environ["JAX_PLATFORMS"] = "cpu"  # the one-device half on the CPU too, whatever else the machine has
    rows, nodes = one_device(args.sizes, args.meshes, args.repeats, args.gradient)
    worker = subprocess.run(command, env=env, capture_output=True, text=True, check=True)
    shard = json.loads(worker.stdout.strip().splitlines()[-1])
    for size in args.sizes:
        rows[size].update(shard["rows"][str(size)])
    import jax

    print(f"hanging panel, {args.meshes} meshes, {nodes} nodes; {'figure + gradient' if args.gradient else 'positions'}"
          f"; jax {jax.__version__}; {len(os.sched_getaffinity(0))} cores, load average {os.getloadavg()[0]:.1f}; "
          f"sharded over {shard['devices']} emulated CPU devices")
    width = 14
    print(f"{'B':>3} {'Newton it.':>10} | " + " ".join(f"{c:>{width}}" for c in COLUMNS)
          + " | compile s: " + " ".join(f"{c:>12}" for c in COLUMNS))
    for size in args.sizes:
        row = rows[size]
        iterations = "{}/{}".format(*row["vmap"]["iterations"])
        cells = " ".join(f"{row[c]['warm']:>7.3f} ({1e3 * row[c]['warm'] / size:>4.0f})" for c in COLUMNS)
        cold = " ".join(f"{row[c]['cold']:>12.1f}" for c in COLUMNS)
        print(f"{size:>3} {iterations:>10} | {cells} |            {cold}")
    print("warm wall time s (ms per design), best of the repeats; Newton it. = largest / total over the batch; "
          "compile s = the first call, compilation included (the loop compiles once for all B; a batch of the "
          "same padded size reuses the sharded program)")


if __name__ == "__main__":
    main()
