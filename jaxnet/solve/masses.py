"""The masses of a net lumped at its nodes (4.265): its inertia M + M_a and the water's inertia coefficient
M_a + ρV, per node and axis.

What the implicit time stepping (:mod:`jaxnet.solve.dynamics`), its adjoint
(:mod:`jaxnet.solve.adjoint_dynamics`) and the reference integration (:mod:`jaxnet.solve.reference`) put
on each node: a third of each triangle's netting per vertex as the book says, half of each bar per end,
the nodes' own bodies.

Units: kg, m³.
"""

from __future__ import annotations

import jax
import numpy as np

from jaxnet import geometry
from jaxnet.solve import programs
from jaxnet.terms import inertia


# jitted for the host: op by op, their vmaps would dispatch (and, at the first call, compile) each primitive
# apart, a cost on every simulate
_HOST_VMAPS = {f: programs.jit(jax.vmap(f)) for f in (inertia.netting_vertex_mass, geometry.twine_determinant)}


def _per_element(function, xp, *args):
    """``function`` over the elements (vmapped): inline where traced (jnp), a compiled program on the host
    (numpy, the result as numpy)."""
    if xp is np:
        return jax.tree.map(np.asarray, _HOST_VMAPS[function](*args))
    return jax.vmap(function)(*args)


def _scatter_add(total, index, values, xp):
    """``total`` with ``values`` added at ``index`` (repeated indices accumulate, in order)."""
    if xp is np:
        total = total.copy()
        np.add.at(total, index, values)
        return total
    return total.at[index].add(values)


def lumped_masses(scene, xp=np):
    """Per node and axis, (M + M_a, M_a + ρV): the inertia (kg) and the water's inertia coefficient (kg),
    (N, 3) each.

    M: a third of each triangle's netting per vertex (4.265; twine volume of the weight 4.277, diamond and
    hexagonal), half of each bar per end, plus the nodes' own masses. V: the same volumes, plus the nodes'
    displaced volumes. M_a: ``Environment.added_mass_coefficient`` × ρ × the volume of twines and bars, plus
    the nodes' ``added_mass`` (per axis).

    ``xp``: numpy (the default) computes on the host, for a run (:func:`simulate`, the reference's
    :func:`jaxnet.solve.reference.free_masses`); jax.numpy computes in JAX, traceable and differentiable in
    the design (twine diameter, mesh side, twine coordinates, a sinker's mass and volume, the water
    density: :mod:`jaxnet.solve.adjoint_dynamics`). Why not JAX for both: compiled, XLA fuses the products
    and sums into fused multiply-adds, and the host's masses would change in their last bits.
    """
    env = scene.environment
    n = scene.n_nodes
    rho, ca = xp.asarray(env.water_density, dtype=float), xp.asarray(env.added_mass_coefficient, dtype=float)
    mass, volume = xp.zeros(n), xp.zeros(n)

    def spread(total, ends, per_element):
        ends = xp.asarray(ends)
        return _scatter_add(total, ends.ravel(), xp.repeat(per_element, ends.shape[1]), xp)

    net = scene.netting
    if net is not None:
        m, v = _per_element(inertia.netting_vertex_mass, xp, xp.asarray(net.uv), xp.asarray(net.l0),
                            xp.asarray(net.diameter), xp.asarray(net.density))
        mass, volume = spread(mass, net.vertices, m), spread(volume, net.vertices, v)
    hexa = scene.hexagonal
    if hexa is not None:
        d = xp.abs(_per_element(geometry.twine_determinant, xp, xp.asarray(hexa.uv)))
        v = geometry.twine_volume(d, xp.sum(xp.asarray(hexa.l0), axis=1), xp.asarray(hexa.diameter)) / 3.0
        mass, volume = spread(mass, hexa.vertices, xp.asarray(hexa.density) * v), spread(volume, hexa.vertices, v)
    bars = scene.bars
    if bars is not None:
        v = geometry.twine_volume(1.0, xp.asarray(bars.rest_length), xp.asarray(bars.diameter)) / 2.0
        mass, volume = spread(mass, bars.ends, xp.asarray(bars.density) * v), spread(volume, bars.ends, v)
    nodes = scene.nodes
    added = xp.broadcast_to((ca * rho * volume)[:, None], (n, 3))
    if nodes.added_mass is not None:
        added = added + xp.asarray(nodes.added_mass, dtype=float)
    mass = mass + xp.asarray(nodes.mass, dtype=float)
    volume = volume + xp.asarray(nodes.volume, dtype=float)
    return mass[:, None] + added, added + (rho * volume)[:, None]
