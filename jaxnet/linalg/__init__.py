"""Sparse linear algebra of the tangent stiffness: CSR matrix-vector products in JAX, direct solves on the host.

The tangent of a net is sparse, often nearly singular (slack twines, a flat membrane has no out-of-plane
stiffness) and badly conditioned (EA/l0 against small geometric stiffness): Krylov methods with cheap
preconditioners do not converge on it (``docs/solvers.md``), so it is factorised on the
host: by oneMKL's PARDISO where MKL is installed (:class:`PardisoSolver`, :mod:`jaxnet.linalg.pardiso` says why),
else by SuperLU (scipy, :class:`HostSolver`), which is also PARDISO's fallback; where JAX computes on a GPU, by
cuDSS on the device (:class:`CudssSolver`, :mod:`jaxnet.linalg.cudss`); :func:`direct_solver` picks
(:func:`solver_choice`). Jitted code calls them through ``jax.pure_callback``, on a Python thread of this module's
(:func:`on_solver_thread`: SuperLU's memory is freed only there). What follows is SuperLU's. The structure
(indptr, indices) is passed as arguments, so one compiled program serves every scene of the same shape. The
minimum-degree ordering on A^T + A suits the structurally symmetric pattern of finite elements (about
half the fill of COLAMD on these matrices).

Pivoting. The tangents are structurally symmetric and their values nearly so (drag makes them slightly
nonsymmetric), but their diagonal can be tiny or zero at slack twines and closed meshes. A threshold of 0.1
(SuperLU's "take the diagonal unless it is below 0.1 x its column's largest entry") pivots off the
diagonal in hundreds of columns of the later Newton tangents, and each such pivot breaks the symmetric
ordering: the factor grows several times beyond the ordering's prediction, and the factorisation slows
as much. So the regular factorisation prefers the diagonal much more strongly
(:data:`PIVOT_THRESHOLD` = 1e-3: no off-diagonal pivot in any tangent of the FEMNET cases, so the fill
stays the ordering's; as fast as 0, which would also accept pivots that are tiny but not zero). Its
multipliers are bounded by 1/threshold instead of partial pivoting's 1, so entries can grow more during
the elimination. What makes that safe is a check of every solution's normwise backward error
``|b - A x|_inf / (|A|_inf |x|_inf + |b|_inf)`` (one sparse mat-vec; ~1e-16 for a stable solve, whatever
the conditioning): above :data:`TOLERANCE` the solution is refined (x += A^-1 r with the same factor, up
to :data:`REFINEMENTS` times), and if it still fails, or the factorisation breaks down, the matrix is
refactorised with partial pivoting (threshold 1, COLAMD column ordering, which bounds the fill whatever
the row interchanges; the symmetric ordering with partial pivoting fills several times more and is as
much slower)
and counted in :attr:`HostSolver.fallbacks`. A zero diagonal entry alone causes no fallback: SuperLU never
takes a zero pivot, it takes the column's largest entry instead.
"""

from __future__ import annotations

import concurrent.futures
import dataclasses
import functools
import hashlib
import os
import threading

import jax
import jax.numpy as jnp
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from jaxnet.linalg import pardiso
from jaxnet.memo import Memo

#: A diagonal entry is the pivot of its column when it is at least this fraction of the column's largest
#: entry (after the updates of the earlier columns); otherwise that largest entry is. Dimensionless.
PIVOT_THRESHOLD = 1e-3
#: Largest accepted normwise backward error of a solution (dimensionless; double precision's unit
#: roundoff is 1.1e-16, a stable factorisation gives ~1e-16 on the FEMNET tangents).
TOLERANCE = 1e-12
#: Steps of iterative refinement tried before refactorising with partial pivoting.
REFINEMENTS = 2
#: SuperLU's panel size (columns updated together): 1 is faster than scipy's default on the FEMNET
#: tangents (their supernodes are small; ``docs/investigations.md``); it changes neither the pivots
#: nor the fill.
PANEL_SIZE = 1
#: SuperLU's relaxed-supernode size (subtrees of the elimination tree of at most this many columns are
#: merged into one supernode). SuperLU's default, 10, is slower on the FEMNET tangents and on the cage,
#: and several times slower on the cage meshed finely, at the same fill; 1, 2 and 3 are alike on all of
#: them (``docs/investigations.md``).
RELAX = 2


#: bytes of the block :func:`keep_factor_memory` allocates and frees once per process (0: none, the heap
#: left as glibc starts; ``docs/investigations.md`` compares the two)
MALLOC_PRIMER = 16 << 20
_PRIMED = []


def keep_factor_memory():
    """Let the C heap keep the memory of SuperLU's factors between factorisations (once per process).

    Why. Each factorisation allocates its L and U afresh (a few MB on the FEMNET cases) and frees them at
    the next. glibc's malloc serves blocks above its mmap threshold (128 kB at start) by mmap, returns them
    to the system on free, and every page of the next factor is then faulted in again. glibc raises that
    threshold (and the trim threshold, to twice it) to the size of any mmapped block freed, up to 32 MB:
    freeing one 16 MB block makes the later factors come from the heap and stay there: a factorisation
    then takes fewer page faults and less time (``docs/investigations.md``). Elsewhere
    than glibc this is one allocation and its release, nothing more. The process may keep up to 32 MB more
    heap. Called by every :class:`HostSolver`.
    """
    if not _PRIMED:
        _PRIMED.append(True)
        np.empty(MALLOC_PRIMER, dtype=np.uint8)  # from malloc (numpy's large arrays), freed at once


def matvec(data, rows, indices, v):
    """y = A v for a CSR matrix given by its entries ``data``, their rows and column ``indices``."""
    return jax.ops.segment_sum(data * v[indices], rows, num_segments=v.shape[0], indices_are_sorted=True)


#: solvers of the structures seen by :func:`solve`'s callback ((structure digest, thread) -> HostSolver; at
#: most 64 structures x threads): a jitted loop of Newton solves (dynamics: thousands of time steps) then
#: computes each structure's ordering once.
_SOLVERS = Memo(64)


#: the solver each thread used last: a Newton loop solves on one structure over and over, and comparing it
#: (a memcmp) is far cheaper than digesting it, a cost on every solve of a time step
_LAST = threading.local()


def _structure_digest(indptr, indices):
    """A digest of a CSR structure (indptr, indices): the key of the per-structure caches."""
    return hashlib.blake2b(np.ascontiguousarray(indptr).tobytes() + np.ascontiguousarray(indices).tobytes(),
                           digest_size=16).digest()


#: the fill-reducing ordering of each structure factorised so far, with the permuted structure it gives
#: (structure digest -> :class:`_Ordering`, at most 64): the ordering depends on the structure only, so a
#: second solve of a scene of the same shape (another load, another start: a warm solve) skips SuperLU's
#: ordering step and the permutation's set-up, the larger part of a first factorisation
#: (``benchmarks/femnet_cases.py`` times cold and warm solves)
_ORDERINGS = Memo(64)


def _host_solver(indptr, indices):
    indptr, indices = np.asarray(indptr), np.asarray(indices)
    last = getattr(_LAST, "solver", None)
    if (last is not None and last.indptr.shape == indptr.shape and last.indices.shape == indices.shape
            and np.array_equal(last.indices, indices) and np.array_equal(last.indptr, indptr)):
        return last
    _LAST.solver = solver = _lookup_solver(indptr, indices)
    return solver


def _lookup_solver(indptr, indices):
    # one solver per structure and thread: the callbacks of a program sharded over several devices run in
    # several of XLA's threads at once, and a solver holds its last factor (not to be shared mid-solve)
    key = (_structure_digest(indptr, indices), threading.get_ident())
    return _SOLVERS.get_or_make(key, lambda: direct_solver(indptr, indices))


def host_solve(data, rhs, indptr, indices, transpose=False, reuse=False):
    """What :func:`solve`'s host callback computes, on the host (numpy): x solving A x = rhs (A^T x = rhs if
    ``transpose``) for the CSR matrix (data, indices, indptr), and ok (a numpy bool), by this thread's
    :class:`HostSolver` of the structure (its ordering kept between calls)."""
    x, ok = _host_solver(indptr, indices).solve(data, rhs, transpose, reuse)
    return x, np.asarray(ok)


#: the Python threads that run the callbacks' host solves: (process, calling thread) -> a one-thread executor
_WORKERS = Memo(None)


def on_solver_thread(function, *args, **kwargs):
    """``function(*args, **kwargs)`` run on a thread that Python made (one per calling thread, the same for
    every call from it); its result, or its exception raised here.

    Why. XLA runs a host callback on a thread of its own, and Python gives such a thread a new thread
    state at every call. scipy's SuperLU records the memory it allocates with the thread state of the call
    that allocates it, and frees memory only if the thread state of the call that frees it recorded it
    (scipy's ``_superlu_utils.c``, a record per thread). A :class:`HostSolver` keeps its last factor until
    the next factorisation, so the factor made in one callback was dropped in the next, under another thread
    state, and never freed: the size of L and U lost per factorisation, so that a dynamic run or a diffrax
    reference grew without bound (``tests/linalg/test_linalg.py`` checks that the memory does not grow with the
    calls). A thread Python made keeps one thread state,
    so every factor is freed where it was made. One such thread per calling thread: the callbacks of
    several devices (``jaxnet.design.batch``) still solve at the same time, and the per-thread solvers
    (:data:`_SOLVERS`, :data:`_LAST`) stay apart.
    """
    # by process too: a forked child inherits the table but not the threads (it would wait forever)
    caller = (os.getpid(), threading.get_ident())
    worker = _WORKERS.get_or_make(
        caller, lambda: concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="jaxnet-superlu"))
    return worker.submit(function, *args, **kwargs).result()


def _host_solve_packed(packed, nnz, rhs_shape, transpose=False, reuse=False):
    """:func:`host_solve` of the arguments :func:`solve` packed into one array, on the calling thread's
    solver thread (:func:`on_solver_thread`)."""
    return on_solver_thread(_unpack_and_solve, np.asarray(packed), nnz, rhs_shape, transpose, reuse)


def _unpack_and_solve(packed, nnz, rhs_shape, transpose=False, reuse=False):
    m = int(np.prod(rhs_shape))
    n = rhs_shape[0]
    structure = packed[nnz + m:].astype(np.int64)
    return host_solve(packed[:nnz], packed[nnz:nnz + m].reshape(rhs_shape), structure[:n + 1], structure[n + 1:],
                       transpose, reuse)


def solve(data, rhs, indptr, indices, transpose=False, reuse=False):
    """Solve A x = rhs (A^T x = rhs if ``transpose``) for the CSR matrix (data, indices, indptr). Returns
    (x, ok); ok False if singular. ``reuse`` (a Python bool): consecutive solves with the same ``data`` share
    one factorisation (:meth:`HostSolver.solve`): the sensitivity solves of an equilibrium."""
    out = (jax.ShapeDtypeStruct(rhs.shape, rhs.dtype), jax.ShapeDtypeStruct((), jnp.bool_))
    host = functools.partial(_host_solve_packed, nnz=data.shape[0], rhs_shape=tuple(rhs.shape), transpose=transpose,
                             reuse=reuse)
    # One argument, not four: the callback hands each argument to the host through its own device_put, a
    # large part of a small solve's cost (``benchmarks/dynamics.py --breakdown`` times the solve through
    # the callback). The structure travels as float64 values, exact below 2**53.
    packed = jnp.concatenate([data.astype(jnp.float64), rhs.astype(jnp.float64).ravel(),
                              indptr.astype(jnp.float64), indices.astype(jnp.float64)])
    return jax.pure_callback(host, out, packed, vmap_method="sequential")


def host_matvec(data, indptr, indices, v):
    """y = A v on the host (numpy) for the CSR matrix (data, indices, indptr)."""
    n = v.shape[0]
    return sp.csr_matrix((data, indices, indptr), shape=(n, n)) @ v


@dataclasses.dataclass(frozen=True)
class _Ordering:
    """A fill-reducing symmetric permutation of one CSR structure (:class:`HostSolver`): ``order`` (the
    unknowns in elimination order), ``slot`` (entry k of the permuted A^T, in CSC order, is CSR entry
    slot[k] of A) and the permuted A^T's CSC ``indices`` and ``indptr`` (int32, SuperLU's). Read-only once
    made: solvers of one structure share it."""

    order: np.ndarray
    slot: np.ndarray
    indices: np.ndarray
    indptr: np.ndarray


class HostSolver:
    """Repeated direct solves A x = b on the host for matrices of one fixed sparsity (a Newton solve's
    tangents). The fill-reducing ordering (minimum degree on A^T + A) is computed once per structure, at the
    first factorisation (and kept for later solvers of the same structure, :data:`_ORDERINGS`), and every
    later matrix is permuted symmetrically by it and factorised in that order (SuperLU without its own
    ordering step, a large part of a factorisation). Pivots are
    taken on the diagonal where they are not too small and every solution is checked; see the module
    docstring for why and for the fallback to partial pivoting.

    Use ``factorize(data)`` then ``apply(rhs)`` (several times if needed), or ``solve(data, rhs)``.

    Args:
      indptr, indices: the CSR structure of A (numpy), n = len(indptr) - 1 unknowns.
      pivot_threshold, tolerance, refinements: see :data:`PIVOT_THRESHOLD`, :data:`TOLERANCE`,
        :data:`REFINEMENTS`.

    Attributes (for reports):
      ok: False when the last factorisation or solve failed (singular or non-finite); True otherwise.
      factorizations: matrices factorised so far (fallbacks not counted twice).
      fallbacks: factorisations redone with partial pivoting (the diagonal-preferring one broke down or
        gave an inaccurate solution).
      refinements: iterative-refinement steps taken, over all solves.
      backward_error: the largest normwise backward error of the last ``apply``'s columns.
    """

    def __init__(self, indptr, indices, pivot_threshold=PIVOT_THRESHOLD, tolerance=TOLERANCE,
                 refinements=REFINEMENTS):
        keep_factor_memory()
        self.indptr, self.indices = np.asarray(indptr), np.asarray(indices)
        self.n = self.indptr.shape[0] - 1
        self.pivot_threshold, self.tolerance, self.max_refinements = pivot_threshold, tolerance, refinements
        self._rows = np.repeat(np.arange(self.n), np.diff(self.indptr))
        # Starts of the non-empty rows: np.add.reduceat over them sums each row (|A|_inf at half the cost
        # of a weighted bincount).
        self._row_starts = self.indptr[:-1][np.diff(self.indptr) > 0]
        # A itself for the residuals; its values are replaced at each factorisation (no re-validation).
        nnz = self.indices.shape[0]
        self._a = sp.csr_matrix((np.zeros(nnz), self.indices, self.indptr), shape=(self.n, self.n))
        self.order = None  # fill-reducing symmetric permutation, set by the first successful factorisation
        self._lu, self._perm, self._pivoted = None, None, False
        self.ok = False
        self.factorizations = self.fallbacks = self.refinements = 0
        self.backward_error = float("nan")

    @property
    def factor_entries(self):
        """Entries of the kept factor, L's and U's together (its fill), or 0 without one."""
        return 0 if self._lu is None else int(self._lu.L.nnz + self._lu.U.nnz)

    # -- factorisation ----------------------------------------------------------------------------------

    def factorize(self, data):
        """Factorise A given by its CSR entries ``data`` on the fixed structure and keep the factor.
        Returns False (and keeps no factor) if ``data`` is not finite or A is singular."""
        data = np.array(data, dtype=float)  # a copy: the residual checks of later solves read it
        self._a.data = data
        self._lu, self._pivoted = None, False
        self.ok = bool(np.all(np.isfinite(data)))
        if not self.ok:
            return False
        self.factorizations += 1
        self._norm = float(np.add.reduceat(np.abs(data), self._row_starts).max(initial=0.0))
        try:
            self._factor_diagonal(data)
        except RuntimeError:  # no nonzero pivot left in some column: let partial pivoting decide
            return self._factor_pivoted()
        return True

    def _factor_diagonal(self, data):
        """Factorisation preferring diagonal pivots, in the stored order (computed here the first time, or
        taken from the orderings of the structures seen before, :data:`_ORDERINGS`)."""
        n = self.n
        options = {"SymmetricMode": True}  # rows eliminated in the columns' order: diagonal pivots
        if self.order is None:
            key = _structure_digest(self.indptr, self.indices)
            known = _ORDERINGS.get(key)
            if known is None:
                # CSR of A read as CSC is A^T: factorise A^T and solve with trans="T" (no conversion).
                at = sp.csc_matrix((data, self.indices, self.indptr), shape=(n, n))
                self._lu = spla.splu(at, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=self.pivot_threshold,
                                     panel_size=PANEL_SIZE, relax=RELAX, options=options)
                self._perm = None
                # perm_c maps a column to its place (after SuperLU's postorder of the elimination tree): the
                # symmetric permutation that reproduces the ordering takes rows and columns in its inverse's
                # order.
                known = _ORDERINGS.put(key, self._ordering(np.argsort(self._lu.perm_c)))
                self._use(known)
                return
            self._use(known)
        at = self._permuted
        np.take(data, self._slot, out=at.data)  # in place: no new matrix to validate
        self._lu = spla.splu(at, permc_spec="NATURAL", diag_pivot_thresh=self.pivot_threshold,
                             panel_size=PANEL_SIZE, relax=RELAX, options=options)
        self._perm = self.order

    def _ordering(self, order):
        """The :class:`_Ordering` of ``order`` on this structure: the CSC structure of the permuted A^T and
        the map from A's CSR entries to its entries, so that a matrix is permuted by one gather."""
        rank = np.empty_like(order)
        rank[order] = np.arange(self.n)
        # Entry k of the CSR of A is entry (indices[k], rows[k]) of A^T, moved to (rank[.], rank[.]).
        new_row, new_col = rank[self.indices], rank[self._rows]
        slot = np.lexsort((new_row, new_col))  # by column, rows ascending within each column
        indptr = np.concatenate([[0], np.cumsum(np.bincount(new_col, minlength=self.n))])
        # int32 indices, SuperLU's: splu would copy wider ones at every call.
        return _Ordering(order, slot, new_row[slot].astype(np.intc), indptr.astype(np.intc))

    def _use(self, ordering):
        """Factorise in ``ordering`` from now on (the permuted matrix of this solver's own, its values
        overwritten at each factorisation)."""
        self.order, self._slot = ordering.order, ordering.slot
        self._permuted = sp.csc_matrix((np.zeros(self._slot.shape[0]), ordering.indices, ordering.indptr),
                                       shape=(self.n, self.n))

    def _factor_pivoted(self):
        """Refactorise the stored matrix with partial pivoting (the robust, slower fallback)."""
        self.fallbacks += 1
        self._pivoted, self._perm = True, None
        at = sp.csc_matrix((self._a.data, self.indices, self.indptr), shape=(self.n, self.n))
        try:
            # COLAMD orders the columns for any row interchanges; the symmetric ordering fills far more.
            self._lu = spla.splu(at, permc_spec="COLAMD", diag_pivot_thresh=1.0)
        except RuntimeError:  # exactly singular
            self._lu, self.ok = None, False
        return self.ok

    # -- solves -----------------------------------------------------------------------------------------

    def apply(self, rhs, transpose=False):
        """x solving A x = rhs (A^T x = rhs if ``transpose``) with the stored factor; ``rhs`` of shape (n,)
        or (n, k) (k right-hand sides, each checked and refined on its own). Switches to a partially
        pivoted factor (kept for later calls) if a column stays inaccurate. Returns zeros, never NaN, and
        sets ``ok`` False when there is no usable factor or the solution is not finite."""
        b = np.asarray(rhs, dtype=float)
        if self._lu is None:
            self.ok = False
            return np.zeros_like(b)
        x, error = self._refined(b, transpose)
        if not np.all(error <= self.tolerance) and not self._pivoted and self._factor_pivoted():
            x, error = self._refined(b, transpose)
        if self._lu is None or not np.all(np.isfinite(x)):
            self._lu, self.ok = None, False
            return np.zeros_like(b)
        self.backward_error = float(np.max(error, initial=0.0))
        return x

    def solve(self, data, rhs, transpose=False, reuse=False):
        """x solving A x = rhs (A^T x = rhs if ``transpose``) for the CSR entries ``data``; (x, ok) with ok
        False (x zeros) if singular. ``reuse``: if ``data`` is the matrix factorised last, solve with the
        kept factor (the sensitivities of an equilibrium: one system, many right-hand sides, either side)."""
        data = np.asarray(data, dtype=float)
        same = (reuse and self._lu is not None and self._a.data.shape == data.shape
                and np.array_equal(self._a.data, data))
        if not same and not self.factorize(data):
            return np.zeros_like(np.asarray(rhs, dtype=float)), False
        x = self.apply(rhs, transpose)
        return x, self.ok

    def _refined(self, b, transpose=False):
        """Solution of A x = b (A^T x = b if ``transpose``) and its backward error per column, after up to
        ``max_refinements`` steps of iterative refinement on the columns above the tolerance (needed after
        large pivot growth)."""
        x = self._lu_solve(b, transpose)
        error, r = self._backward_error(x, b, transpose)
        for _ in range(self.max_refinements):
            if np.all(error <= self.tolerance) or not np.all(np.isfinite(x)):
                break
            self.refinements += 1
            x = x + self._lu_solve(r, transpose)
            error, r = self._backward_error(x, b, transpose)
        return x, error

    def _lu_solve(self, b, transpose=False):
        """A^-1 b (A^-T b if ``transpose``) with the stored factor (of A^T, in the stored order when
        ``_perm`` is set: a symmetric permutation, so the transposed system takes the same one)."""
        trans = "N" if transpose else "T"
        if self._perm is None:
            return self._lu.solve(b, trans=trans)
        x = np.empty_like(b)
        x[self._perm] = self._lu.solve(b[self._perm], trans=trans)
        return x

    def _backward_error(self, x, b, transpose=False):
        """Normwise backward error |b - A x|_inf / (|A|_inf |x|_inf + |b|_inf) of each column (NaN if x is
        not finite) and the residual b - A x (A^T in place of A if ``transpose``)."""
        if transpose:
            r = b - self._a.T @ x
            norm = float(np.max(np.asarray(abs(self._a).sum(axis=0)), initial=0.0))  # |A^T|_inf = |A|_1
        else:
            r, norm = b - self._a @ x, self._norm
        scale = norm * np.max(np.abs(x), axis=0, initial=0.0) + np.max(np.abs(b), axis=0, initial=0.0)
        return np.max(np.abs(r), axis=0, initial=0.0) / np.where(scale > 0, scale, 1.0), r


class _LibrarySolver(HostSolver):
    """:class:`HostSolver` whose regular factorisations a library makes instead of SuperLU (its factor object:
    ``factor(data)``, ``solve(b, transpose)``, ``entries``; :meth:`make_factor`): the same interface, the same
    check of every solution's backward error (on the host), the same iterative refinement, and the same
    fallback, to SuperLU with partial pivoting (counted in ``fallbacks``), when a solution stays inaccurate or
    the library fails (a RuntimeError, from it or from :meth:`check_factor`). The structure is analysed
    (ordered) at the first factorisation; ``order`` is None: the library keeps its ordering to itself."""

    def __init__(self, indptr, indices, tolerance=TOLERANCE, refinements=REFINEMENTS):
        super().__init__(indptr, indices, tolerance=tolerance, refinements=refinements)
        self._library = self.make_factor(self.indptr, self.indices)

    def make_factor(self, indptr, indices):
        """The library's factor object for this structure."""
        raise NotImplementedError

    def check_factor(self, factor):
        """Raise RuntimeError where the library's last factor must not be used (the fallback decides)."""

    @property
    def factor_entries(self):
        if self._lu is None:
            return 0
        return super().factor_entries if self._pivoted else self._library.entries

    def _factor_diagonal(self, data):
        # a RuntimeError (the library failed, or its factor is refused) sends HostSolver.factorize to the fallback
        self._library.factor(data)
        self.check_factor(self._library)
        self._lu, self._perm = self._library, None

    def _lu_solve(self, b, transpose=False):
        if self._pivoted:
            return super()._lu_solve(b, transpose)
        return self._library.solve(b, transpose)


class PardisoSolver(_LibrarySolver):
    """The tangents factorised by oneMKL's PARDISO (:mod:`jaxnet.linalg.pardiso`) on the host, behind
    :class:`HostSolver`'s checks and fallback (:class:`_LibrarySolver`); a factor with a perturbed pivot (the
    matrix singular or nearly so) is handed to the fallback too."""

    def make_factor(self, indptr, indices):
        return pardiso.Factor(indptr, indices)

    def check_factor(self, factor):
        if factor.perturbed_pivots:
            # A perturbed pivot factorises a nearby matrix: of a singular one, a solution far too large whose
            # backward error is nevertheless small. Partial pivoting decides instead (SuperLU's exact zero
            # pivots refuse a singular matrix). The Newton tangents, damped, perturb none.
            raise RuntimeError("PARDISO perturbed a pivot")


class CudssSolver(_LibrarySolver):
    """The tangents factorised by NVIDIA's cuDSS on the GPU (:mod:`jaxnet.linalg.cudss`), behind :class:`HostSolver`'s
    checks and fallback (:class:`_LibrarySolver`)."""

    def make_factor(self, indptr, indices):
        from jaxnet.linalg import cudss

        return cudss.Factor(indptr, indices)


def solver_choice():
    """The sparse direct solver :func:`direct_solver` makes: ``"cudss"``, ``"pardiso"`` or ``"superlu"``.
    ``JAXNET_SPARSE_SOLVER`` (:data:`jaxnet.linalg.pardiso.CHOICE`) names one; unset (or empty), cuDSS where JAX
    computes on a GPU and it is installed (:func:`jaxnet.linalg.cudss.available`), else PARDISO where MKL is
    installed, else SuperLU. A name that is not one of these three, or ``cudss`` or ``pardiso`` where it
    cannot run, is a ValueError that says why."""
    from jaxnet.linalg import cudss

    asked = os.environ.get(pardiso.CHOICE, "").strip().lower()
    if asked == "":
        if cudss.available():
            return "cudss"
        return "pardiso" if pardiso.available() else "superlu"
    if asked == "cudss":
        try:
            cudss.require()
        except RuntimeError as error:
            raise ValueError(f"{pardiso.CHOICE}=cudss: {error}") from None
        return asked
    if asked == "pardiso" and not pardiso.available():
        raise ValueError(f"{pardiso.CHOICE}=pardiso: MKL's mkl_rt library is not installed "
                         "(pip install mkl, x86-64 only); unset the variable for the default solver")
    if asked not in ("pardiso", "superlu"):
        raise ValueError(f"{pardiso.CHOICE}={asked!r}: expected cudss, pardiso or superlu (or unset: cuDSS on a "
                         "GPU where it is installed, else PARDISO where MKL is, else SuperLU)")
    return asked


def direct_solver(indptr, indices):
    """The sparse direct solver of the tangents of one structure, as :func:`solver_choice` says: a
    :class:`CudssSolver`, a :class:`PardisoSolver` or a :class:`HostSolver` (SuperLU). All have the same
    interface."""
    return {"cudss": CudssSolver, "pardiso": PardisoSolver, "superlu": HostSolver}[solver_choice()](indptr, indices)
