"""NVIDIA's cuDSS sparse direct solver on a GPU: the factorisations of the static solver's tangents where JAX
computes on a CUDA device.

Why. On a GPU the tangent's assembly runs on the device while PARDISO or SuperLU factorise on the host's few
cores, and at 10^4-10^5 nodes the factorisation is what an iteration costs. cuDSS factorises the same tangents
on the device, faster than SuperLU on the host from 10^4 unknowns, with backward errors at rounding, its time
growing more slowly with the unknowns (the cage's and a trawl's Newton tangents, and whole solves:
``benchmarks/device_factorisation.py``; the figures in the section "cuDSS on a GPU" of
``validation/REPORT.md``).

How. Through ``nvmath-python`` (NVIDIA's Python interface to its math libraries;
``pip install -e ".[gpu]"``: nvmath-python with the ``nvidia-cudss`` library, and CuPy) on CuPy arrays:
one :class:`nvmath.sparse.advanced.DirectSolver` per structure, its analysis (reordering, symbolic
factorisation) made at the first factorisation and kept, the values of each later tangent written into the
same device arrays and factorised again. cuDSS solves with A only: A^T x = b (the adjoints of the implicit
differentiation) is solved with a second factor, of A^T, made when first asked for each matrix.
:class:`jaxnet.linalg.CudssSolver` puts it behind the interface of the host solvers: every solution's
backward error is checked on the host, refined, and the factorisation handed to SuperLU with partial pivoting
when it stays inaccurate or cuDSS fails.

Availability. :func:`available` is True where JAX's default backend is a GPU and nvmath-python with cuDSS
imports. ``JAXNET_SPARSE_SOLVER`` (:data:`jaxnet.linalg.pardiso.CHOICE`) chooses otherwise: ``cudss`` asks for it
(an error says why where it cannot run), ``pardiso`` or ``superlu`` keep the factorisations on the host.

Memory. JAX takes 75 % of the GPU's memory at its start by default; cuDSS's factors and CuPy's arrays need
their own, outside JAX's pool. Where a solve runs out of device memory (a fallback to SuperLU, counted in
``Timing.fallbacks``), start Python with ``XLA_PYTHON_CLIENT_PREALLOCATE=false`` (or a smaller
``XLA_PYTHON_CLIENT_MEM_FRACTION``).
"""

from __future__ import annotations

import importlib

import numpy as np

_MODULES = []  # [(cupy, DirectSolver) or the reason they are not there], once per process


def require():
    """(cupy, nvmath's DirectSolver), the modules cuDSS is reached through, or a RuntimeError saying why they
    cannot be used here."""
    if not _MODULES:
        try:
            import cupy
            from nvmath.sparse.advanced import DirectSolver

            importlib.import_module("cupyx.scipy.sparse")  # the CSR operand's module

            cupy.cuda.runtime.getDeviceCount()
            _MODULES.append((cupy, DirectSolver))
        except Exception as error:  # noqa: BLE001 -- any failure to import or to reach a device means: not here
            _MODULES.append(f"{type(error).__name__}: {error}")
    found = _MODULES[0]
    if isinstance(found, str):
        raise RuntimeError("cuDSS cannot be used here: nvmath-python with cuDSS and CuPy on a CUDA device are "
                           f"needed (pip install 'nvmath-python[cu13]' cupy-cuda13x) -- {found}")
    return found


def available():
    """Whether the static solver can factorise with cuDSS here: JAX computes on a GPU, and nvmath-python
    (with the cuDSS library) and CuPy import and see a device."""
    import jax

    if jax.default_backend() != "gpu":
        return False
    try:
        require()
    except RuntimeError:
        return False
    return True


class Factor:
    """cuDSS's factorisations of the matrices of one CSR structure (indptr, indices; n unknowns), on the GPU:
    ``factor(data)`` for each matrix (the analysis made at the first call and kept), then ``solve(b,
    transpose)`` with its factor, b of shape (n,) or (n, k). Raises RuntimeError when cuDSS fails (out of
    device memory, a singular matrix it cannot factorise)."""

    def __init__(self, indptr, indices):
        self._cupy, self._direct_solver = require()
        self.indptr, self.indices = np.asarray(indptr), np.asarray(indices)
        self.n = self.indptr.shape[0] - 1
        self._forward = self._transposed = None
        self._data = None  # the last matrix's entries (host), for the factor of A^T when it is asked for
        self._transposed_current = False
        self._t_slot = None  # where A^T's entries come from in A's (transposed_structure), made when first needed

    @property
    def entries(self):
        """Entries of the last factor (L's and U's), as cuDSS reports them; 0 before the first."""
        if self._forward is None or self._forward.info is None:
            return 0
        try:
            return int(self._forward.info.lu_nnz)
        except Exception:  # noqa: BLE001 -- a report only
            return 0

    def factor(self, data):
        self._data = np.asarray(data, dtype=float)
        self._transposed_current = False
        if self._forward is None:
            self._forward = _OnDevice(self._cupy, self._direct_solver, self.indptr, self.indices, self.n)
        self._forward.factor(self._data)

    def solve(self, b, transpose=False):
        if not transpose:
            return self._forward.solve(b)
        if self._transposed is None:  # the first transposed solve: the Newton never asks for one, the adjoints do
            self._t_slot, indptr_t, indices_t = transposed_structure(self.indptr, self.indices)
            self._transposed = _OnDevice(self._cupy, self._direct_solver, indptr_t, indices_t, self.n)
        if not self._transposed_current:
            self._transposed.factor(self._data[self._t_slot])
            self._transposed_current = True
        return self._transposed.solve(b)


def transposed_structure(indptr, indices):
    """The CSR structure of A^T for the CSR structure (indptr, indices) of a square A, and where its entries
    come from: (slot, indptr_t, indices_t) such that A^T is the CSR matrix (data[slot], indices_t, indptr_t)
    for any entries ``data`` of A (one gather per matrix)."""
    import scipy.sparse as sp

    n = np.asarray(indptr).shape[0] - 1
    # entries numbered from 1: a conversion may drop an explicit 0
    numbered = sp.csr_matrix((np.arange(1, np.asarray(indices).shape[0] + 1, dtype=float), indices, indptr),
                             shape=(n, n))
    at = numbered.T.tocsr()
    at.sort_indices()
    return at.data.astype(np.int64) - 1, at.indptr, at.indices


class _OnDevice:
    """One nvmath DirectSolver on device arrays that each matrix and right-hand side overwrite."""

    def __init__(self, cupy, direct_solver, indptr, indices, n):
        import cupyx.scipy.sparse as csp

        self._cupy = cupy
        self._values = cupy.zeros(indices.shape[0], dtype=cupy.float64)
        self._rhs = cupy.zeros(n, dtype=cupy.float64)
        a = csp.csr_matrix((self._values, cupy.asarray(indices.astype(np.int32)),
                            cupy.asarray(indptr.astype(np.int32))), shape=(n, n))
        self._values = a.data  # the matrix's own array (CuPy may have copied it)
        self.solver = direct_solver(a, self._rhs)
        self._planned = False
        self.info = None  # what the last factorisation reported (nvmath's DirectSolverFactorizationInfo)

    def factor(self, data):
        try:
            self._values.set(np.ascontiguousarray(data))
            if not self._planned:
                self.solver.plan()
                self._planned = True
            self.info = self.solver.factorize()
        except Exception as error:  # noqa: BLE001 -- cuDSS's and CuPy's errors: the caller falls back
            raise RuntimeError(f"cuDSS factorisation failed: {type(error).__name__}: {error}") from error

    def solve(self, b):
        b = np.asarray(b, dtype=float)
        columns = b.reshape(b.shape[0], -1)
        x = np.empty_like(columns)
        try:
            for k in range(columns.shape[1]):
                self._rhs.set(np.ascontiguousarray(columns[:, k]))
                x[:, k] = self._cupy.asnumpy(self.solver.solve())
        except Exception as error:  # noqa: BLE001
            raise RuntimeError(f"cuDSS solve failed: {type(error).__name__}: {error}") from error
        return x.reshape(b.shape)
