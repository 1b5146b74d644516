"""Sparse linear algebra of the tangent stiffness: CSR matrix-vector products in JAX, direct solves on the host.

The tangent of a net is sparse, often nearly singular (slack twines, a flat membrane has no out-of-plane
stiffness) and badly conditioned (EA/l0 against small geometric stiffness): Krylov methods with cheap
preconditioners do not converge on it (measured: ../shared/notes/solvers.md), so it is factorised by
SuperLU (scipy), called from inside jitted code through ``jax.pure_callback``. The structure (indptr,
indices) is passed as arguments, so one compiled program serves every scene of the same shape. The
minimum-degree ordering on A^T + A suits the structurally symmetric pattern of finite elements (about
half the fill of COLAMD on these matrices).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def matvec(data, rows, indices, v):
    """y = A v for a CSR matrix given by its entries ``data``, their rows and column ``indices``."""
    return jax.ops.segment_sum(data * v[indices], rows, num_segments=v.shape[0], indices_are_sorted=True)


def _host_solve(data, rhs, indptr, indices):
    n = rhs.shape[0]
    # CSR of A read as CSC is A^T: factorise A^T and solve with trans="T", which avoids a conversion.
    at = sp.csc_matrix((np.asarray(data), np.asarray(indices), np.asarray(indptr)), shape=(n, n))
    try:
        lu = spla.splu(at, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1, options={"SymmetricMode": True})
        x = lu.solve(np.asarray(rhs), trans="T")
    except RuntimeError:  # exactly singular factor
        return np.zeros(n), np.asarray(False)
    ok = bool(np.all(np.isfinite(x)))
    return (x if ok else np.zeros(n)), np.asarray(ok)


def solve(data, rhs, indptr, indices):
    """Solve A x = rhs for the CSR matrix (data, indices, indptr). Returns (x, ok); ok False if singular."""
    out = (jax.ShapeDtypeStruct(rhs.shape, rhs.dtype), jax.ShapeDtypeStruct((), jnp.bool_))
    return jax.pure_callback(_host_solve, out, data, rhs, indptr, indices, vmap_method="sequential")


def host_matvec(data, indptr, indices, v):
    """y = A v on the host (numpy) for the CSR matrix (data, indices, indptr)."""
    n = v.shape[0]
    return sp.csr_matrix((data, indices, indptr), shape=(n, n)) @ v


class HostSolver:
    """Repeated direct solves A x = b on the host for matrices of one fixed sparsity (a Newton solve's
    tangents): the fill-reducing ordering is computed once, at the first factorisation, and every later
    matrix is permuted symmetrically by it and factorised in that order (SuperLU without its own
    ordering step: 20-50 % of a factorisation on the FEMNET cases).

    indptr, indices: the CSR structure of A (numpy).
    """

    def __init__(self, indptr, indices):
        self.indptr, self.indices = np.asarray(indptr), np.asarray(indices)
        self.n = self.indptr.shape[0] - 1
        self.order = None

    def _prepare(self, at):
        lu = spla.splu(at, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.1, options={"SymmetricMode": True})
        # perm_c maps a column to its place: the symmetric permutation that reproduces SuperLU's ordering
        # takes rows and columns in the order of its inverse.
        self.order = np.argsort(lu.perm_c)
        nnz = self.indices.shape[0]
        slot = sp.csc_matrix((np.arange(1.0, nnz + 1), self.indices, self.indptr), shape=(self.n, self.n))
        permuted = slot[self.order][:, self.order].tocsc()
        permuted.sort_indices()
        self.slot_map = permuted.data.astype(np.int64) - 1
        self.p_indices, self.p_indptr = permuted.indices, permuted.indptr
        return lu

    def solve(self, data, rhs):
        """x solving A x = rhs for the CSR entries ``data``; (x, ok) with ok False if singular."""
        data, rhs = np.asarray(data), np.asarray(rhs)
        try:
            if self.order is None:
                # CSR of A read as CSC is A^T: factorise A^T and solve with trans="T" (no conversion).
                lu = self._prepare(sp.csc_matrix((data, self.indices, self.indptr), shape=(self.n, self.n)))
                x = lu.solve(rhs, trans="T")
            else:
                at = sp.csc_matrix((data[self.slot_map], self.p_indices, self.p_indptr), shape=(self.n, self.n))
                lu = spla.splu(at, permc_spec="NATURAL", diag_pivot_thresh=0.1, options={"SymmetricMode": True})
                x = np.empty_like(rhs)
                x[self.order] = lu.solve(rhs[self.order], trans="T")
        except RuntimeError:  # exactly singular factor
            return np.zeros(self.n), False
        ok = bool(np.all(np.isfinite(x)))
        return (x if ok else np.zeros(self.n)), ok
