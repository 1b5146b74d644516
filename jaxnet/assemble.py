"""Global assembly: total energy, out-of-balance force and sparse tangent stiffness of a scene.

Per element family, the active energy terms are summed into one element energy, evaluated on the gathered
vertex positions and vmapped over the elements. The force is minus the gradient of the total energy plus
the constant loads; the tangent is the per-element Hessian (``jax.jacfwd`` over ``jax.grad``), vmapped,
scattered by ``segment_sum`` into the entries of a CSR matrix over the free coordinates. The CSR
structure and the slot of every element-matrix entry are computed once per scene in numpy
(:func:`build_pattern`) and passed to the jitted functions as arguments — never closed over, so XLA does
not constant-fold large index arrays. No dense global matrix is ever formed.

Sign convention: ``force`` is the out-of-balance force on the nodes (N), zero at equilibrium;
``tangent`` is K = -d force / dx (book eq. 4.46), symmetric for conservative terms.
"""

from __future__ import annotations

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet.model import ActiveTerm

#: vertices per element of each family
ARITY = {"netting": 3, "bars": 2}


def connectivity(scene, family):
    """(E, k) node indices of the elements of a family."""
    f = getattr(scene, family)
    return f.vertices if family == "netting" else f.ends


class Pattern(eqx.Module):
    """Sparse structure of the tangent over the free coordinates (arrays; built once per scene).

    free: (n,) flat indices (3 * node + axis) of the free coordinates.
    slots: per family with stiffness, (E, (3k)²) position of each element-matrix entry in the CSR data,
      ``nnz`` for entries that touch a fixed coordinate (dropped).
    diagonal: (n,) position of the diagonal entries in the CSR data.
    indptr, indices, rows: CSR structure and the row of each entry (for products).
    """

    free: jax.Array
    slots: dict
    diagonal: jax.Array
    indptr: jax.Array
    indices: jax.Array
    rows: jax.Array

    @property
    def n(self):
        return self.free.shape[0]

    @property
    def nnz(self):
        return self.indices.shape[0]


def stiff_families(model):
    return tuple(sorted({t.term.family for t in model if t.term.kind == "energy"}))


def build_pattern(scene, model) -> Pattern:
    """CSR structure of the tangent and element slot maps, in numpy, once per scene."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool).ravel()
    free = np.flatnonzero(~fixed)
    n = free.size
    dof_map = np.full(fixed.size, -1, dtype=np.int64)
    dof_map[free] = np.arange(n)
    keys_per_family = {}
    all_keys = [np.arange(n, dtype=np.int64) * (n + 1)]  # the diagonal is always present
    for family in stiff_families(model):
        conn = np.asarray(connectivity(scene, family), dtype=np.int64)
        dofs = (3 * conn[:, :, None] + np.arange(3)).reshape(conn.shape[0], -1)
        fd = dof_map[dofs]
        r = np.broadcast_to(fd[:, :, None], fd.shape + fd.shape[-1:])
        c = np.broadcast_to(fd[:, None, :], fd.shape + fd.shape[-1:])
        keys = np.where((r >= 0) & (c >= 0), r * n + c, -1).reshape(conn.shape[0], -1)
        keys_per_family[family] = keys
        all_keys.append(keys[keys >= 0])
    unique = np.unique(np.concatenate(all_keys))
    nnz = unique.size
    rows = unique // n
    indices = (unique % n).astype(np.int32 if nnz < 2**31 else np.int64)
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=n), out=indptr[1:])
    slots = {}
    for family, keys in keys_per_family.items():
        s = np.searchsorted(unique, keys)
        slots[family] = np.where(keys >= 0, s, nnz).astype(np.int64)
    diagonal = np.searchsorted(unique, np.arange(n, dtype=np.int64) * (n + 1))
    return Pattern(
        free=jnp.asarray(free),
        slots={k: jnp.asarray(v) for k, v in slots.items()},
        diagonal=jnp.asarray(diagonal),
        indptr=jnp.asarray(indptr),
        indices=jnp.asarray(indices),
        rows=jnp.asarray(rows),
    )


def positions(x_free, scene, pattern):
    """(N, 3) positions: the free coordinates from ``x_free``, the fixed ones from the scene."""
    x0 = jnp.asarray(scene.nodes.position).ravel()
    return x0.at[pattern.free].set(x_free).reshape(-1, 3)


def _family_energy(model, family):
    terms = [t for t in model if t.term.family == family and t.term.kind == "energy"]

    def energy(x, p, env):
        total = 0.0
        for t in terms:
            with jax.named_scope(t.name):
                total = total + t.term.element(x, p, env, **t.kwargs())
        return total

    return energy


def energy(x, scene, model: tuple[ActiveTerm, ...]):
    """Total stored energy (J) of all energy terms at positions x (N, 3)."""
    total = 0.0
    for family in stiff_families(model):
        conn = connectivity(scene, family)
        fam = getattr(scene, family)
        e = jax.vmap(_family_energy(model, family), in_axes=(0, 0, None))(x[conn], fam, scene.environment)
        total = total + jnp.sum(e)
    return total


def loads(scene, model):
    """(N, 3) constant nodal loads (N) of all load terms: weight, buoyancy, external forces."""
    n = scene.n_nodes
    f = jnp.zeros((n, 3))
    for t in model:
        if t.term.kind != "load":
            continue
        with jax.named_scope(t.name):
            family = t.term.family
            fam = scene.nodes if family == "nodes" else getattr(scene, family)
            per_elem = jax.vmap(lambda p: t.term.element(p, scene.environment, **t.kwargs()))(fam)
            conn = jnp.arange(n)[:, None] if family == "nodes" else connectivity(scene, family)
            f = f.at[conn.ravel()].add(per_elem.reshape(-1, 3))
    return f


def potential(x, scene, model, load):
    """Total potential energy (J): stored energy minus the work of the constant loads."""
    return energy(x, scene, model) - jnp.sum(load * x)


def nodal_force(x, scene, model, load):
    """(N, 3) out-of-balance force on every node (N), including reactions' share at fixed coordinates."""
    return load - jax.grad(energy)(x, scene, model)


def scatter_hessians(x, scene, pattern, element_energies):
    """CSR entries (nnz,) of the sum of per-element Hessians of ``element_energies[family](x, p, env)``.

    Each element energy is differentiated twice (``jax.jacfwd`` of ``jax.grad``) on its own vertices,
    vmapped over the family, and its entries are summed into the pattern's slots (entries on fixed
    coordinates are dropped).
    """
    data = jnp.zeros(pattern.nnz + 1)
    for family, element in element_energies.items():
        conn = connectivity(scene, family)
        fam = getattr(scene, family)
        k = conn.shape[1]

        def hess(xe, p, element=element, k=k):
            flat = lambda v: element(v.reshape(k, 3), p, scene.environment)  # noqa: E731
            return jax.jacfwd(jax.grad(flat))(xe.ravel())

        blocks = jax.vmap(hess)(x[conn], fam)
        data = data + jax.ops.segment_sum(blocks.reshape(-1), pattern.slots[family].reshape(-1), pattern.nnz + 1)
    return data[:-1]


def tangent(x, scene, model, pattern):
    """CSR entries (nnz,) of the tangent K = -d force / dx over the free coordinates."""
    return scatter_hessians(x, scene, pattern, {f: _family_energy(model, f) for f in stiff_families(model)})
