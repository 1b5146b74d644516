"""Batches of designs: the equilibria of many designs in one program, on one device or sharded over
several, with a figure of each and its gradient.

A design study solves the same net for many values of its parameters (a sweep of mesh sides, the
candidates of a population, the corners of a tolerance box). The designs share everything the compiled
program depends on (the topology, the active terms, the tangent's sparsity: one
:class:`~jaxnet.solve.implicit.Structure`), so one program serves them all:

* :func:`solve_batch` runs :func:`jaxnet.solve.implicit.equilibrium` over a leading batch axis of θ on one
  device, batched with ``jax.vmap`` (``method="vmap"``, the default) or one design after the other inside
  the program with ``jax.lax.map`` (``method="map"``);
* :func:`solve_sharded` splits the batch axis over the devices of a :class:`jax.sharding.Mesh`
  (``jax.shard_map``, the inputs placed by :class:`~jax.sharding.NamedSharding`): each device runs the same
  program on its share, and the results come back sharded along the batch axis.

θ is a pytree (a :class:`~jaxnet.design.space.DesignSpace`'s dict of families, or whatever a scene function
takes) whose every leaf has the batch as its leading axis. With a ``figure`` (a callable on an
:class:`jaxnet.design.objectives.Outcome`, e.g. any :mod:`~jaxnet.design.objectives` figure) each design's
figure and its gradient with respect to its θ (reverse mode: one adjoint solve per design, by the implicit
function theorem) come with the positions.

**What runs where.** A differentiable equilibrium is a damped Newton iteration (one ``lax.while_loop``,
:func:`jaxnet.solve.newton.newton_loop`) whose linear solves leave the device. The element assembly
(forces, the sparse tangent's entries), the residual norms, the line search and the step logic are XLA code
and run on the device(s) holding the designs. Each factorisation of the tangent K, and each sensitivity
solve with K or K^T, is a ``jax.pure_callback``: XLA calls Python from one of its CPU client's threads
(never the main one), JAX copies the operands onto CPU device 0 and the callback factorises them with
SuperLU (scipy) on the host (:mod:`jaxnet.linalg`), then the solution goes back to the device.

* *vmap on one device.* The batched while loop runs until the batch's slowest design has converged, and
  under vmap the loop's ``lax.cond`` (factorise only when a line search ends) becomes a select that takes
  both branches: every pass of the loop assembles and factorises the tangent of every design, converged
  ones included, one callback after the other (``vmap_method="sequential"``): designs of 4 to 13 Newton
  iterations make the batch factorise several times what they need, where ``method="map"`` factorises
  exactly what each design needs and is as fast as a Python loop of single solves; even where the
  callbacks are a small part (a small panel), vmap is the slower (``benchmarks/design_batch.py`` times
  both). Until the Newton loop tells the host which designs need a factorisation (a flag to the
  callback), prefer ``method="map"``.
* *sharded over several devices.* Each device runs its own loop over its own designs (it stops at its own
  slowest) and makes its own callbacks, from its own thread, so the callbacks of different devices run on
  the host at the same time. With emulated CPU devices on a host of few cores (``benchmarks/design_batch.py``)
  the factorisations of ``method="map"`` overlap, but each takes longer than alone, the cores and Python's
  GIL being shared: sharded can be slower than one device (``validation/REPORT.md``). With ``method="vmap"`` sharding
  helps because it cuts the batched waste (each device stops at its own slowest design). Emulated devices
  add no cores: sharding can only pay where the host has cores to spare for the concurrent callbacks.
* *a deadlock to avoid.* XLA's CPU client runs the programs of all CPU devices, and their callbacks, on
  max(cores, CPU devices) threads (:func:`xla_cpu_threads`). A mesh of as many emulated devices as those
  threads can hang: each XLA thread is then inside a callback, waiting to read its operands (which JAX put on
  CPU device 0) as numpy arrays, and no thread is left to complete those copies; a mesh of one device fewer
  leaves a thread for them. So
  :func:`design_mesh` leaves CPU device 0 out when the devices are as many as those threads, and
  :func:`solve_sharded` refuses a mesh of that many CPU devices.
* *threads.* The host solves of different devices run in different threads at once, so
  :mod:`jaxnet.linalg` must not share a factorisation between threads (one solver per structure *and*
  thread).
* *on a GPU* (not measured). The same program runs on the GPU; every callback stops the GPU's
  stream, copies the tangent's entries (nnz floats) and the right-hand side to the host, factorises on the
  CPU and copies the solution back. So a GPU speeds up the assembly and the line search, not the
  factorisations, half of a Newton iteration's time at 362 nodes on the CPU and more on larger nets:
  expect a batch on one GPU to take about as long as on the CPU, plus a round trip per factorisation, and, with
  ``method="vmap"``, the same factorisation of every design at every pass. Sharding over several GPUs
  overlaps their host solves as above, within the host's cores and GIL.

**Convergence.** Every design starts from ``x0`` (one (N, 3) start for all, or one per design) and must
converge within ``solver.max_iter`` pure Newton steps (:data:`jaxnet.solve.options.DIFFERENTIABLE`): a
design far from its start may not. With ``throw=True`` the designs that did not converge are named (index,
reason, residual, worst node) in an :class:`~jaxnet.solve.implicit.ImplicitError` once the batch is back;
with ``throw=False`` the batch is returned and its ``status`` says which designs to trust.

Bad input (leaves with different batch sizes, a scalar leaf, a start of the wrong shape, an invalid
design of a :class:`~jaxnet.design.space.DesignSpace`, an unknown method, a mesh without the design axis)
raises ValueError naming the leaf, the design or the option before anything is compiled.

Units: positions in m, residuals in N, the figure in its own unit and its gradient in that unit per unit
of each θ entry.
"""

from __future__ import annotations

import functools
import os
from typing import Any, Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

from jaxnet.design import objectives
from jaxnet.design.space import DesignSpace
from jaxnet.solve import implicit
from jaxnet.solve.options import DIFFERENTIABLE, Newton
from jaxnet.solve.results import CONVERGED, REASONS

__all__ = ["AXIS", "METHODS", "Batch", "batch_size", "design_mesh", "solve_batch", "solve_sharded",
           "xla_cpu_threads"]

#: the name of the batch axis of a design mesh (:func:`design_mesh`)
AXIS = "designs"

#: how a device goes through its designs: ``"vmap"``, all at once (one batched Newton loop), or ``"map"``,
#: one after the other inside one program (``jax.lax.map``: a loop compiled once, no batching)
METHODS = {"vmap": "jax.vmap", "map": "jax.lax.map"}


class Batch(eqx.Module):
    """The equilibria of a batch of B designs (leading axis B on every field).

    x: (B, N, 3) equilibrium node positions (m).
    status: (B,) the solve's stop reason (:data:`jaxnet.solve.results.REASONS`; CONVERGED is the only
      trustworthy one). residual_N: (B,) largest out-of-balance force (N). iterations: (B,) Newton
      iterations. worst_node: (B,) node of the largest residual.
    value: (B,) the figure of each design (its unit), or None without a figure.
    gradient: d value / d θ, θ's pytree with a leading B on every leaf, or None (no figure, or
      ``gradient=False``).
    """

    x: jax.Array
    status: jax.Array
    residual_N: jax.Array
    iterations: jax.Array
    worst_node: jax.Array
    value: Any = None
    gradient: Any = None

    @property
    def converged(self) -> np.ndarray:
        """(B,) bool, on the host: the designs whose solve converged."""
        return np.asarray(self.status) == CONVERGED


# -- checks, before anything is compiled -------------------------------------------------------------------

def batch_size(thetas) -> int:
    """The number of designs B in the batch ``thetas`` (every leaf of shape (B, ...)). Raises ValueError
    naming the leaf (its path in the pytree) when a leaf has no leading axis or a leading size other than
    the first leaf's."""
    leaves = jax.tree_util.tree_leaves_with_path(thetas)
    if not leaves:
        raise ValueError("design batch: θ holds no arrays, so it has no batch axis (give each parameter that "
                         "varies as an array of shape (B, ...), one row per design)")
    first, size = None, None
    for path, leaf in leaves:
        name = jax.tree_util.keystr(path) or "θ"
        shape = np.shape(leaf)
        if len(shape) == 0:
            raise ValueError(f"design batch: leaf {name} is a scalar; every leaf needs a leading batch axis "
                             "(shape (B, ...), one entry per design)")
        if first is None:
            first, size = name, shape[0]
        elif shape[0] != size:
            raise ValueError(f"design batch: leaf {name} holds {shape[0]} designs along its leading axis, but "
                             f"leaf {first} holds {size}: every leaf of θ needs the same batch size")
    if size == 0:
        raise ValueError(f"design batch: leaf {first} holds no design (batch size 0)")
    return size


def _as_float(thetas):
    """θ with every leaf a float64 array (the gradient needs floats; a list of numbers is fine as input)."""
    return jax.tree_util.tree_map(lambda a: jnp.asarray(a, dtype=float), thetas)


def _start(x0, n_nodes, size):
    """(x0 as a float array, whether it holds one start per design); ValueError on a wrong shape."""
    x0 = jnp.asarray(x0, dtype=float)
    if x0.shape == (n_nodes, 3):
        return x0, False
    if x0.shape == (size, n_nodes, 3):
        return x0, True
    raise ValueError(f"design batch: x0 must be one start (N, 3) = ({n_nodes}, 3) for every design or one per "
                     f"design (B, N, 3) = ({size}, {n_nodes}, 3), got shape {x0.shape}")


def _design(thetas, b):
    """Design ``b`` of the batch, as concrete host arrays."""
    return jax.tree_util.tree_map(lambda a: np.asarray(a[b]), thetas)


def _resolve(space_or_scene_fn, thetas, structure, x0):
    """(scene function, structure, float θ, x0, x0 batched?, B), every input checked: the leading sizes;
    for a DesignSpace each design in turn (:meth:`DesignSpace.check`, the error prefixed by its index)."""
    size = batch_size(thetas)
    thetas = _as_float(thetas)
    if isinstance(space_or_scene_fn, DesignSpace):
        space = space_or_scene_fn
        for b in range(size):
            try:
                space.check(_design(thetas, b))
            except ValueError as err:
                raise ValueError(f"design {b} of the batch: {err}") from err
        scene_fn, n_nodes = space.scene, space.reference.n_nodes
        structure = structure if structure is not None else implicit.structure_of(space.reference)
    elif callable(space_or_scene_fn):
        if structure is None:
            raise ValueError("design batch: a scene function needs the Structure of its reference scene "
                             "(jaxnet.solve.implicit.structure_of(reference))")
        scene_fn = space_or_scene_fn
        # the shapes of the first design's scene (traced, not computed)
        n_nodes = jax.eval_shape(scene_fn, jax.tree_util.tree_map(lambda a: a[0], thetas)).nodes.position.shape[0]
    else:
        raise ValueError("design batch: expected a DesignSpace or a function θ -> Scene, got "
                         f"{type(space_or_scene_fn).__name__}")
    x0, batched = _start(x0, n_nodes, size)
    return scene_fn, structure, thetas, x0, batched, size


# -- one design, then many ------------------------------------------------------------------------------

def _one_design(scene_fn, structure, solver, figure, gradient, theta, x0) -> Batch:
    """The equilibrium of one design θ (and its figure, and the figure's gradient in θ), as a Batch of
    unbatched fields: what vmap or lax.map runs over the designs."""
    def solved(theta):
        scene = scene_fn(theta)
        eq = implicit.equilibrium(scene, structure, x0=x0, solver=solver, throw=False)
        return eq, scene

    def figure_of(theta):
        eq, scene = solved(theta)
        return figure(objectives.Outcome(eq.x, scene, structure.model)), eq

    value = grad = None
    if figure is None:
        eq, _ = solved(theta)
    elif gradient:
        (value, eq), grad = jax.value_and_grad(figure_of, has_aux=True)(theta)
    else:
        value, eq = figure_of(theta)
    return Batch(x=eq.x, status=eq.status, residual_N=eq.residual_N, iterations=eq.iterations,
                 worst_node=eq.worst_node, value=value, gradient=grad)


def _batched(scene_fn, structure, solver, figure, gradient, method, x0_batched, thetas, x0) -> Batch:
    """Every design of the batch, by ``jax.vmap`` or ``jax.lax.map`` (see :data:`METHODS`)."""
    one = functools.partial(_one_design, scene_fn, structure, solver, figure, gradient)
    if method == "vmap":
        return jax.vmap(one, in_axes=(0, 0 if x0_batched else None))(thetas, x0)
    if x0_batched:
        return jax.lax.map(lambda design: one(*design), (thetas, x0))
    return jax.lax.map(lambda theta: one(theta, x0), thetas)


# one program per (scene function, terms, Newton options, figure's static part, gradient?, method, batch
# shapes): a sweep or an optimisation calling again with new θ reuses it
_batched_jit = eqx.filter_jit(_batched)


@eqx.filter_jit
def _sharded_jit(scene_fn, structure, solver, figure, gradient, method, x0_batched, mesh, thetas, x0) -> Batch:
    # the arrays of the structure and the figure go in as replicated arguments, their static parts by closure
    structure_arrays, structure_static = eqx.partition(structure, eqx.is_array)
    figure_arrays, figure_static = eqx.partition(figure, eqx.is_array)

    def shard(thetas, x0, structure_arrays, figure_arrays):
        return _batched(scene_fn, eqx.combine(structure_arrays, structure_static), solver,
                        eqx.combine(figure_arrays, figure_static), gradient, method, x0_batched, thetas, x0)

    designs, everywhere = PartitionSpec(AXIS), PartitionSpec()
    # check_vma=False: the host callbacks inside carry no varying-across-devices annotation
    run = jax.shard_map(shard, mesh=mesh, in_specs=(designs, designs if x0_batched else everywhere, everywhere,
                                                    everywhere), out_specs=designs, check_vma=False)
    return run(thetas, x0, structure_arrays, figure_arrays)


def _method(method):
    """``method``, checked against :data:`METHODS`."""
    if method not in METHODS:
        raise ValueError(f"design batch: method must be one of {sorted(METHODS)}, got {method!r}")
    return method


def _checked(batch: Batch, size: int, solver: Newton, throw: bool) -> Batch:
    """The batch, or (``throw``) an ImplicitError naming every design whose solve did not converge."""
    if not throw:
        return batch
    status = np.asarray(batch.status)
    failed = np.flatnonzero(status != CONVERGED)
    if failed.size:
        residual, iterations, worst = (np.asarray(a) for a in (batch.residual_N, batch.iterations, batch.worst_node))
        lines = [f"design {b}: {REASONS[int(status[b])]} after {int(iterations[b])} iterations, largest "
                 f"residual {float(residual[b]):.4g} N at node {int(worst[b])}" for b in failed[:10]]
        more = f"; and {failed.size - 10} more" if failed.size > 10 else ""
        raise implicit.ImplicitError(
            f"design batch: {failed.size} of {size} designs did not converge (tolerance {solver.tol:g} N): "
            + "; ".join(lines) + more + ". Start them nearer their answers (x0, one per design) or run with "
            "throw=False and read status")
    return batch


def solve_batch(space_or_scene_fn: DesignSpace | Callable, thetas, structure: implicit.Structure | None, x0,
                solver: Newton | None = None, figure: Callable | None = None, gradient: bool = True,
                throw: bool = True, method: str = "vmap") -> Batch:
    """The equilibria of a batch of designs in one program on one device (the default device).

    Args:
      space_or_scene_fn: a :class:`~jaxnet.design.space.DesignSpace` (θ a dict of its families, any subset,
        the rest at the reference; every design checked by :meth:`DesignSpace.check` first), or any
        differentiable function θ -> :class:`~jaxnet.scene.Scene` of fixed topology.
      thetas: θ with a leading batch axis B on every leaf (e.g. ``{"mesh_side": {"netting": (B,) m}}``).
      structure: the :class:`~jaxnet.solve.implicit.Structure` of the reference scene; None for a DesignSpace
        (computed from ``space.reference``: pass it when calling repeatedly, it is a host computation).
      x0: (N, 3) start positions of every design, or (B, N, 3) one per design (m); not differentiated.
      solver: the forward solve's options (default :data:`jaxnet.solve.options.DIFFERENTIABLE`).
      figure: None, or a scalar figure of an :class:`jaxnet.design.objectives.Outcome` (positions, scene,
        terms), e.g. ``objectives.drag()``.
      gradient: with a figure, also its gradient with respect to each design's θ (reverse mode).
      throw: raise :class:`~jaxnet.solve.implicit.ImplicitError` naming the designs that did not converge.
      method: ``"vmap"``, the designs batched (one batched Newton loop), or ``"map"``, one after the other
        (``jax.lax.map``); the same results to rounding. ``"map"`` is the faster wherever the host
        factorisations matter (the module docstring says why).
    Returns:
      a :class:`Batch` (positions, solve status, figure values and gradients, leading axis B).
    """
    scene_fn, structure, thetas, x0, x0_batched, size = _resolve(space_or_scene_fn, thetas, structure, x0)
    solver = solver or DIFFERENTIABLE
    batch = _batched_jit(scene_fn, structure, solver, figure, gradient, _method(method), x0_batched, thetas, x0)
    return _checked(batch, size, solver, throw)


def xla_cpu_threads() -> int:
    """The threads of XLA's CPU client, which run every CPU device's programs and their host callbacks:
    max(schedulable cores, CPU devices) (``GetTfrtCpuClient``: ``max(DefaultThreadPoolSize(), device
    count)``)."""
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(cores, len(jax.devices("cpu")))


def design_mesh(devices=None) -> Mesh:
    """A one-axis :class:`jax.sharding.Mesh` (axis :data:`AXIS`) over ``devices``. Default: all devices of
    the default backend, except that on CPU, when the devices are as many as XLA's threads
    (:func:`xla_cpu_threads`, as with emulated devices on few cores), device 0 is left out: a sharded solve
    needs a thread to spare (see the module docstring)."""
    if devices is None:
        devices = jax.devices()
        if devices[0].platform == "cpu" and len(devices) > 1 and len(devices) >= xla_cpu_threads():
            devices = devices[1:]
    devices = list(devices)
    if not devices:
        raise ValueError("design_mesh: no devices given")
    return Mesh(np.asarray(devices), (AXIS,))


def _check_mesh(mesh):
    """ValueError for a mesh that can deadlock: as many CPU devices as XLA's CPU threads (several)."""
    if AXIS not in mesh.axis_names:
        raise ValueError(f"solve_sharded: the mesh needs an axis named {AXIS!r} (design_mesh() makes one), "
                         f"it has {mesh.axis_names}")
    cpus = sum(d.platform == "cpu" for d in mesh.devices.flat)
    if cpus > 1 and cpus >= xla_cpu_threads():
        raise ValueError(
            f"solve_sharded: a mesh of {cpus} CPU devices on a host where XLA runs {xla_cpu_threads()} threads "
            "(max(cores, CPU devices)) can deadlock: every device may wait in a host callback for a copy that "
            f"needs a free thread. Use at most {xla_cpu_threads() - 1} of them (design_mesh() leaves device 0 out)")


def _padded(tree, size, total):
    """Every leaf of ``tree`` padded along its leading axis from ``size`` to ``total`` rows by repeating its
    last row (a design solved again: its results are dropped)."""
    if total == size:
        return tree
    return jax.tree_util.tree_map(lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], total - size, axis=0)]), tree)


def solve_sharded(space_or_scene_fn: DesignSpace | Callable, thetas, structure: implicit.Structure | None, x0,
                  solver: Newton | None = None, figure: Callable | None = None, gradient: bool = True,
                  throw: bool = True, method: str = "vmap", mesh: Mesh | None = None) -> Batch:
    """:func:`solve_batch` with the batch split over the devices of ``mesh`` (default :func:`design_mesh`):
    each device solves its B / D designs (batched or mapped, by ``method``), at the same time as the
    others. The results are sharded along the batch axis the same way (``NamedSharding(mesh,
    P("designs"))``). A mesh of as many CPU devices as XLA's CPU threads is refused (ValueError): it can
    deadlock (module docstring).

    B need not be a multiple of the D devices: the batch is padded with copies of its last design, solved
    and dropped (the returned arrays are then the first B rows, no longer evenly sharded). Arguments and
    result as :func:`solve_batch`; ``mesh``: a :class:`jax.sharding.Mesh` with an axis named :data:`AXIS`.
    """
    mesh = mesh or design_mesh()
    _check_mesh(mesh)
    scene_fn, structure, thetas, x0, x0_batched, size = _resolve(space_or_scene_fn, thetas, structure, x0)
    solver = solver or DIFFERENTIABLE
    devices = mesh.shape[AXIS]
    total = -(-size // devices) * devices
    thetas = _padded(thetas, size, total)
    if x0_batched:
        x0 = _padded(x0, size, total)
    designs, everywhere = NamedSharding(mesh, PartitionSpec(AXIS)), NamedSharding(mesh, PartitionSpec())
    thetas = jax.device_put(thetas, designs)
    x0 = jax.device_put(x0, designs if x0_batched else everywhere)
    structure = jax.device_put(structure, everywhere)
    batch = _sharded_jit(scene_fn, structure, solver, figure, gradient, _method(method), x0_batched, mesh, thetas, x0)
    if total != size:
        batch = jax.tree_util.tree_map(lambda a: a[:size], batch)
    return _checked(batch, size, solver, throw)
