"""Batches of designs (jaxnet.design.batch): vmapped on one device, sharded over several.

The scene is the small hanging panel (4 meshes, 15 nodes, no current), whose equilibrium Newton reaches
from the drawing in a few iterations, so every design of a batch starts near it (one start per design).
The batch varies families of every shape: the mesh side (a scalar per design), the panel's cut ((4, 2)
twine coordinates) and the twine diameter. The figure is the mean depth of the nodes (m).

What could be wrong and is checked: the batched while loop (designs converging at different iterations,
the converged ones carried along) and the sequential host callbacks must give each design exactly its own
solve, as a loop of separate solves does, gradients included; the gradients must be those of the batched
figure (central differences of the batch itself); the sharded batch, run in a subprocess with emulated CPU
devices (``XLA_FLAGS`` must be set before jax starts, and this process has started it with one), must
equal the vmapped one and come back split over 4 devices, four designs each, whose host callbacks then
run at the same time (which is how jaxnet.linalg's solver cache, shared between threads, was found to give
wrong factors); and a malformed batch must be refused by name before anything compiles.
"""

import json
import os
import subprocess
import sys
import textwrap

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.design import batch, objectives
from jaxnet.design.space import DesignSpace
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import implicit
from jaxnet.solve.options import Newton
from panels import SMOOTH  # tests/panels.py

#: converged far below options.DIFFERENTIABLE's 1e-8 N, for the differences of the figure
NEWTON = Newton(tol=1e-10, max_iter=100, damping=1e-6, stall_window=None, line_search=30)
B = 16  # four designs a device when sharded: their host callbacks then overlap (a race once found there)


def depth(outcome):
    """Mean height z of the nodes (m; negative below the headline)."""
    return jnp.mean(outcome.x[:, 2])


def designs(space):
    """B designs: mesh side 23-24.5 mm, the cut's corner 1 moved along U by -0.05..0.05 twines, twine diameter
    1-2 mm. The mesh side stays below the drawn 25 mm: there the headline, held between the two fixed corners
    at the hanging ratio of the drawing, is exactly at its rest length, and above it slack (the derivative
    in l0 jumps by 6 % across that kink)."""
    cut = np.asarray(space.initial()["cut"]["netting"])
    move = np.zeros((B, 4, 2))
    move[:, 1, 0] = np.linspace(-0.05, 0.05, B)
    return {"mesh_side": {"netting": np.linspace(0.023, 0.0245, B)},
            "cut": {"netting": cut + move},
            "twine_diameter": {"netting": np.linspace(1e-3, 2e-3, B)}}


def starts(space):
    """(B, N, 3) start positions (m): the drawing lifted by 0 to 20 mm (in its plane: out of it, pure Newton has
    no stiffness to come back), more for the later designs, which then take 5 to 8 Newton iterations."""
    flat = np.asarray(space.reference.nodes.position)
    return flat + np.linspace(0.0, 0.02, B)[:, None, None] * np.array([0.0, 0.0, 1.0])


@pytest.fixture(scope="module")
def panel():
    space = DesignSpace(hanging_panel(meshes=4, step=0.05, **SMOOTH))
    return space, implicit.structure_of(space.reference), np.asarray(space.reference.nodes.position)


@pytest.fixture(scope="module")
def vmapped(panel):
    space, structure, x0 = panel
    return batch.solve_batch(space, designs(space), structure, starts(space), solver=NEWTON, figure=depth)


def test_vmapped_batch_equals_the_loop(panel, vmapped):
    """Each design of the vmapped batch (positions, figure, gradient of the figure in every θ entry) equals its
    own solve, one at a time, to 1e-12 m and 1e-9 of the largest gradient entry (the batched program rounds
    differently: 6e-17 m and 3e-14 measured)."""
    space, structure, x0 = panel
    thetas = designs(space)

    def figure(theta, x0):
        scene = space.scene(theta)
        eq = implicit.equilibrium(scene, structure, x0=x0, solver=NEWTON)
        return depth(objectives.Outcome(eq.x, scene, structure.model)), eq.x

    one = jax.jit(jax.value_and_grad(figure, has_aux=True))
    assert vmapped.converged.all() and vmapped.x.shape == (B, space.reference.n_nodes, 3)
    for b in range(B):
        (value, x), grad = one(jax.tree_util.tree_map(lambda a: a[b], thetas), starts(space)[b])
        np.testing.assert_allclose(np.asarray(vmapped.x[b]), np.asarray(x), rtol=0, atol=1e-12)
        np.testing.assert_allclose(float(vmapped.value[b]), float(value), rtol=1e-12)
        jax.tree_util.tree_map_with_path(
            lambda path, got, want: np.testing.assert_allclose(
                np.asarray(got[b]), np.asarray(want), rtol=0, atol=1e-9 * np.abs(want).max(),
                err_msg=f"design {b}, {jax.tree_util.keystr(path)}"), vmapped.gradient, grad)
    # the designs do differ, and in their number of Newton iterations (the batched loop waits for the last)
    assert np.ptp(np.asarray(vmapped.value)) > 1e-3
    assert np.ptp(np.asarray(vmapped.iterations)) > 0


def test_batched_gradient_is_that_of_the_batched_figure(panel, vmapped):
    """d depth / d l0 of every design against fourth-order central differences of the batch itself (the same
    compiled program, every design moved at once), step 1e-3 of l0, to 1e-7 relative. A longer mesh side
    lowers the panel: its width held by the fixed corners (w = 25√2 mm a mesh, as drawn), each of the four
    meshes in its height opens by d(2 sqrt(l0² - w²/4))/dl0 = 2.8 (at 25 mm) to 3.1 (at 23 mm), so the height
    grows 11-12.5 times as fast as l0 and the mean node sinks about half as fast, less what the twines'
    stretch takes: -4.5 to -4.8 measured."""
    space, structure, x0 = panel
    thetas = designs(space)
    h = 1e-3 * 0.025

    def values(shift):
        moved = dict(thetas, mesh_side={"netting": thetas["mesh_side"]["netting"] + shift})
        return np.asarray(batch.solve_batch(space, moved, structure, starts(space), solver=NEWTON, figure=depth).value)

    fd = (8 * (values(h) - values(-h)) - (values(2 * h) - values(-2 * h))) / (12 * h)
    grad = np.asarray(vmapped.gradient["mesh_side"]["netting"])
    np.testing.assert_allclose(grad, fd, rtol=1e-7)
    assert np.all((grad < -3.0) & (grad > -6.3))


SHARDED = textwrap.dedent("""
    import os, sys, json
    import numpy as np
    import jax
    import jaxnet
    from jaxnet.design import batch
    from jaxnet.design.space import DesignSpace
    from jaxnet.scenes.panel import hanging_panel
    from jaxnet.solve import implicit
    here = os.path.dirname(sys.argv[2])
    sys.path[:0] = [here, os.path.dirname(here)]  # this module, and the tests' helpers
    from test_design_batch import NEWTON, SMOOTH, depth, designs, starts

    assert jax.device_count() == 5, jax.devices()
    space = DesignSpace(hanging_panel(meshes=4, step=0.05, **SMOOTH))
    structure = implicit.structure_of(space.reference)
    results, layouts = {}, {}
    for method in ("vmap", "map"):
        out = batch.solve_sharded(space, designs(space), structure, starts(space), solver=NEWTON, figure=depth,
                                  gradient=False, method=method, mesh=batch.design_mesh(jax.devices()[1:]))
        assert out.gradient is None
        results.update({f"x {method}": np.asarray(out.x), f"value {method}": np.asarray(out.value)})
        layouts[method] = dict(
            spec=list(out.x.sharding.spec), mesh=dict(out.x.sharding.mesh.shape),
            fully_replicated=out.x.sharding.is_fully_replicated,
            shards=sorted((s.device.id, s.index[0].start, s.data.shape[0]) for s in out.x.addressable_shards))
    np.savez(sys.argv[1], **results)
    print(json.dumps(layouts))
""")


def test_sharded_batch_equals_the_vmapped_one(vmapped, tmp_path):
    """The batch sharded over 4 emulated CPU devices (a subprocess), each device batching (vmap) or mapping
    (lax.map) over its share, equals the vmapped one to 1e-9 relative (positions and figure; not the
    gradients, whose programs would double the subprocess's compile time: each shard runs the same function
    as solve_batch), and its positions are split by design over the 4 devices: four designs each, none
    replicated. The subprocess has 5 devices and leaves device 0 out of the mesh: XLA's CPU client runs the
    devices' programs on max(cores, devices) threads, and a mesh of all of them can deadlock (see
    jaxnet.design.batch)."""
    # the jaxnet this process tests (a checkout's, where the installed one is another's), not from the cwd
    root = os.path.dirname(os.path.dirname(os.path.abspath(jaxnet.__file__)))
    env = dict(os.environ, XLA_FLAGS="--xla_force_host_platform_device_count=5", JAX_PLATFORMS="cpu",
               PYTHONPATH=os.pathsep.join([root] + [p for p in [os.environ.get("PYTHONPATH")] if p]))
    result = tmp_path / "sharded.npz"
    run = subprocess.run([sys.executable, "-c", SHARDED, str(result), __file__], env=env, capture_output=True,
                         text=True, timeout=300, cwd=tmp_path)
    assert run.returncode == 0, run.stderr[-4000:]
    layouts = json.loads(run.stdout.strip().splitlines()[-1])
    sharded = np.load(result)
    for method, layout in layouts.items():
        assert layout["mesh"] == {"designs": 4} and not layout["fully_replicated"], method
        assert layout["spec"][0] == "designs" and not any(layout["spec"][1:]), method  # split by design, nodes whole
        assert layout["shards"] == [[d + 1, 4 * d, 4] for d in range(4)], method  # device d + 1: designs 4d to 4d + 3
        for name, want in [("x", vmapped.x), ("value", vmapped.value)]:
            want = np.asarray(want)
            np.testing.assert_allclose(sharded[f"{name} {method}"], want, rtol=0, atol=1e-9 * np.abs(want).max(),
                                       err_msg=f"{name}, sharded {method}")


def test_a_malformed_batch_is_refused_by_name(panel):
    """Inconsistent leading sizes, a leaf without a batch axis, a start of the wrong shape, an invalid design and
    an unknown method are each refused with a ValueError naming the leaf, the shape, the design or the method,
    before anything compiles."""
    space, structure, x0 = panel
    thetas = designs(space)
    short = dict(thetas, cut={"netting": thetas["cut"]["netting"][:3]})
    with pytest.raises(ValueError, match=r"leaf \['mesh_side'\]\['netting'\] holds 16 designs .* "
                                         r"leaf \['cut'\]\['netting'\] holds 3"):
        batch.solve_batch(space, short, structure, x0)
    assert batch.batch_size(thetas) == B
    with pytest.raises(ValueError, match=r"leaf \['mesh_side'\]\['netting'\] is a scalar"):
        batch.solve_batch(space, {"mesh_side": {"netting": 0.025}}, structure, x0)
    with pytest.raises(ValueError, match=r"x0 must be .* \(15, 3\) .* \(16, 15, 3\), got shape \(3, 15, 3\)"):
        batch.solve_batch(space, thetas, structure, np.stack([x0] * 3))
    bad = dict(thetas, mesh_side={"netting": np.where(np.arange(B) == 2, -0.025, 0.025)})
    with pytest.raises(ValueError, match=r"design 2 of the batch: mesh_side\['netting'\]: .* must be > 0"):
        batch.solve_sharded(space, bad, structure, x0)
    with pytest.raises(ValueError, match=r"method must be one of \['map', 'vmap'\], got 'pmap'"):
        batch.solve_batch(space, thetas, structure, x0, method="pmap")
    with pytest.raises(ValueError, match=r"a scene function needs the Structure of its reference scene"):
        batch.solve_batch(space.scene, thetas, None, x0)
