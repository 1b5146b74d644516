"""Direct sparse factorisations side by side on the static solver's real Newton tangents.

    python benchmarks/factorisation.py [--sizes 1e3 1e4 3e4 1e5] [--matrices NAME ...] [--solvers NAME ...]
        [--repeats 5] [--target 4] [--budget 40] [--tangents DIR] [--regenerate] [--json FILE] [--list]

(``--list`` names the tangents and the solvers; the defaults measure every tangent with every solver but the
few of :data:`EXTRA` (``--solvers all`` adds them), ~15 minutes on 2 cores once the tangents exist.)

What it measures. The matrices are Newton tangents K + mu S of static solves, on the tangent's CSR pattern
(what :func:`jaxnet.solve.statics.host_loop` factorises): the FEMNET cod-end ``c2`` and panel
``nr_netting`` (small stand-ins for a trawl, ~1e3 nodes), the fish cage (:func:`jaxnet.scenes.cage.fish_cage`)
at four meshing steps (~1e3, 1e4, 3e4, 1e5 nodes), the framed panel
(:func:`jaxnet.scenes.panel.framed_panel`, 100 meshes a side) at ~1e4, 3e4 and 1e5 nodes, and FEMNET's pelagic
trawl ``1pelagic_trawl/s3`` of the corpus meshed 2, 5, 9 and 15 times finer than its file
(``read_don(refine=...)``: ~1.5e3, 1e4, 3e4, 1e5 nodes). Each scene gives
an early iterate (5 Newton iterations, mu = 1e-3); the FEMNET cases, the cage up to 3e4 nodes and the trawl up
to 1e4 also a late one (the solve's end, or 60 iterations, mu = 1e-8).
At 1e5 nodes a solve of 60 iterations takes too long
(~17 s a factorisation at 3e4 nodes already, late in the solve), so only the early iterate is taken there;
the panel converges in 7 iterations, to a tangent alike to its early one, so only that is taken. The
right-hand side is the residual of the same iterate. The tangents are computed once (a static solve of
each scene, ~10 minutes in all) and kept in ``--tangents`` (default ``jaxnet-tangents`` in the system's
temporary directory, outside the repository); later runs only load them.

Each solver runs in a fresh Python process of its own over the tangents, smallest first, with
``OMP_NUM_THREADS``, ``MKL_NUM_THREADS`` and ``OPENBLAS_NUM_THREADS`` set to its thread count (1 unless its
name ends in ``/2t``); the libraries' per-pattern caches are emptied before each tangent. On each: the
analysis (ordering, symbolic factorisation) where the solver separates it, the first factorisation
(analysis included), then up to ``--repeats`` numerical factorisations of the same values with the analysis
reused (fewer where they would take over ``--target`` seconds: 3 at least, 2 where the first alone took
longer), each followed by one solve (medians of factorisation, factorisation + solve, and solve), the fill
(entries of L and U, of L and D for LDL^T, of L for LL^T), the peak resident memory above that at the start
of the analysis (sampled every 2 ms, the C heap trimmed first; MB), and the normwise backward error
``|b - A x|_inf / (|A|_inf |x|_inf + |b|_inf)`` of a solve and of a transpose solve (A^T x = b, what the
adjoint of the implicit differentiation needs), computed here the same way for every solver. Solvers of
the symmetric part (A + A^T)/2 (CHOLMOD, QDLDL, MUMPS's LDL^T) solve the wrong matrix by ||A - A^T||; their
solve is refined against A (x += F^-1 (b - A x), at most 20 steps, until the backward error is below 1e-14),
its time included and the steps counted in the table; the notes give the backward error before refinement.

Solvers (each skipped, with the reason printed, if its package does not import):
  - ``HostSolver``: :class:`jaxnet.linalg.HostSolver`, the library's SuperLU solver (where MKL is absent, and
    PARDISO's fallback): MMD on A^T + A once, diagonal pivots preferred at threshold 1e-3, backward-error
    check and refinement, fallback to partial pivoting. The library factorises with PARDISO where MKL is
    installed (:class:`jaxnet.linalg.PardisoSolver`, the configuration of ``PARDISO-11nm`` here, without
    PARDISO's own refinement steps).
  - ``SuperLU+METIS(dof)``, ``SuperLU+METIS(node)``: the same HostSolver with its ordering replaced by
    METIS's nested dissection (pymetis) of the unknowns' graph, or of the nodes' graph (weighted by their
    free coordinates) expanded node by node; SuperLU then runs with permc_spec NATURAL.
  - ``SuperLU-COLAMD-pp``: HostSolver's fallback (COLAMD, partial pivoting), the analysis not reusable.
  - ``PARDISO-11``, ``PARDISO-11nm``, ``PARDISO-1`` (``/2t``: 2 threads): oneMKL PARDISO (the library
    library jaxnet loads, :func:`jaxnet.linalg.pardiso.library`, called through ctypes here so that phases 11, 22
    and 33 are timed apart): real
    nonsymmetric with MKL's defaults (mtype 11: scaling and weighted matching), the same without the
    matching (iparm(13) = 0), and structurally symmetric (mtype 1); METIS ordering, pivots perturbed
    rather than exchanged, up to 2 refinement steps inside the solve (MKL's defaults).
  - ``UMFPACK``, ``KLU``: SuiteSparse through kvxopt (its own UMFPACK 5.7 and KLU, symbolic analysis reused).
  - ``KLU(sparsax)``: KLU through sparsax's XLA FFI (what a JAX-native solve would run; analysis cached by
    pattern).
  - ``MUMPS``, ``MUMPS-LDLt(sym)``: MUMPS 5.5 (Debian's libmumps-dev, through pymumps, which builds against
    it) unsymmetric (sym=0) and general symmetric LDL^T on the symmetric part (sym=2); ordering chosen by
    MUMPS (ICNTL(7)=7: Debian's build has neither METIS nor SCOTCH, so AMF or PORD).
  - ``CHOLMOD-LDLt(sym)``, ``CHOLMOD-LLt(sym)``: CHOLMOD through scikit-sparse on the symmetric part,
    simplicial LDL^T and supernodal LL^T (the latter fails where the part is not positive definite).
  - ``QDLDL(sym)``: QDLDL (AMD, LDL^T without pivoting) on the symmetric part.

Noise. Another process may share the two cores: compare solvers only as ratios within one run (the table
gives fill and time relative to HostSolver on the same matrix) and rerun before relying on a number. A
solver whose predicted time on a tangent (its time on the last tangent of the same kind, early or late,
scaled by (n / n_last)^1.5) exceeds ``--budget`` seconds is skipped there (HostSolver, the reference, never
is); a process that gives no result for 4 x budget + 30 s is killed, and the next tangents go on in a new one.

The output: a Markdown table (rows: matrix x solver), the relative nonsymmetry ||A - A^T||_F / ||A||_F of
each tangent, and the growth exponent p of factorisation time ~ n^p (least squares on log-log) of each
solver, over the cage's early tangents and over all the tangents. Nothing is asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np
import scipy.sparse as sp

ROOT = pathlib.Path(__file__).resolve().parents[1]
DATA = ROOT / "tests" / "data" / "femnet"
TANGENTS = pathlib.Path(tempfile.gettempdir()) / "jaxnet-tangents"
REFINE_TO, MAX_REFINE = 1e-14, 20
#: pymetis.nested_dissection returns (perm, iperm): which one lists the vertices in elimination order
PERM_IS_ORDER = True

#: the tangents: name -> (size group, scene kind, scene argument, Newton iterations (None: to the end), mu)
MATRICES = {
    "c2-it5": ("1e3", "femnet", "c2", 5, 1e-3),
    "c2-end": ("1e3", "femnet", "c2", None, 1e-8),
    "nr_netting-end": ("1e3", "femnet", "nr_netting", None, 1e-8),
    "cage0.5-it5": ("1e3", "cage", 0.5, 5, 1e-3),
    "cage0.5-it60": ("1e3", "cage", 0.5, 60, 1e-8),
    "cage0.17-it5": ("1e4", "cage", 0.17, 5, 1e-3),
    "cage0.17-it60": ("1e4", "cage", 0.17, 60, 1e-8),
    "panel0.035-it5": ("1e4", "panel", 0.035, 5, 1e-3),
    "cage0.1-it5": ("3e4", "cage", 0.1, 5, 1e-3),
    "cage0.1-it60": ("3e4", "cage", 0.1, 60, 1e-8),
    "panel0.025-it5": ("3e4", "panel", 0.025, 5, 1e-3),
    "cage0.053-it5": ("1e5", "cage", 0.053, 5, 1e-3),
    "panel0.0125-it5": ("1e5", "panel", 0.0125, 5, 1e-3),
    "trawl-s3x2-it5": ("1e3", "trawl", 2.0, 5, 1e-3),
    "trawl-s3x2-it60": ("1e3", "trawl", 2.0, 60, 1e-8),
    "trawl-s3x5-it5": ("1e4", "trawl", 5.0, 5, 1e-3),
    "trawl-s3x5-it60": ("1e4", "trawl", 5.0, 60, 1e-8),
    "trawl-s3x9-it5": ("3e4", "trawl", 9.0, 5, 1e-3),
    "trawl-s3x15-it5": ("1e5", "trawl", 15.0, 5, 1e-3),
}
#: the trawl of the ``trawl`` tangents: FEMNET's pelagic trawl s3 (424 nodes on its own mesh), meshed finer
TRAWL = ROOT.parent / "shared" / "femnet-corpus" / "1pelagic_trawl" / "s3.don"


# -- the tangents -------------------------------------------------------------------------------------------

def make_case(kind, arg):
    if kind == "femnet":
        from jaxnet.io import femnet
        return femnet.read_don(DATA / f"{arg}.don")
    if kind == "cage":
        from jaxnet.scenes.cage import fish_cage
        return fish_cage(step=arg)
    if kind == "trawl":
        from jaxnet.io import femnet
        return femnet.read_don(TRAWL, refine=arg)
    from jaxnet.scenes.panel import framed_panel
    return framed_panel(meshes=100, step=arg)


def iterate(name):
    """The scene of ``name`` solved for its Newton iterations: (case, free coordinates of the iterate, the
    iterations done, converged, solve time in s)."""
    import jaxnet as jn
    from jaxnet.model import assemble
    from jaxnet import model as model_lib

    _, kind, arg, iterations, _ = MATRICES[name]
    case = make_case(kind, arg)
    pattern = assemble.build_pattern(case.scene, model_lib.active_terms(case.scene))
    t = time.perf_counter()
    options = {} if iterations is None else {"max_iter": iterations}
    eq = jn.solve_static(case, throw=False, **options)
    solve_s = time.perf_counter() - t
    x = np.asarray(eq.x).ravel()[np.asarray(pattern.free)]
    return case, x, int(eq.iterations), bool(eq.converged), solve_s


def tangent_at(case, x, mu):
    """The tangent K + mu S of ``case``'s scene at the free coordinates ``x`` on the tangent's CSR pattern, and
    the residual there: dict of data, indptr, indices, rhs, free, n_nodes (what the solver factorises at
    that iterate)."""
    import jax

    from jaxnet.model import assemble
    from jaxnet import model as model_lib
    from jaxnet.solve import statics

    scene = case.scene
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    free = np.asarray(pattern.free)
    pieces = statics.compile_pieces(x, scene, pattern, model, "closed_form")
    sd, pd = jax.device_put((scene, pattern))
    state = statics._unknown_states(scene, pattern, model)
    _, force, _, _, state = pieces["evaluate"](x, np.zeros(scene.nodes.position.shape), pieces["loads"](sd), 1.0,
                                               sd, pd, state)
    data = np.asarray(pieces["scatter"](pieces["tangent"](x, state, 1.0, sd, pd), pd))
    springs = np.asarray(pieces["springs"](sd, pd))
    return dict(data=data + mu * springs, indptr=np.asarray(pattern.indptr), indices=np.asarray(pattern.indices),
                rhs=np.asarray(force).ravel()[free], free=free, n_nodes=scene.n_nodes)


def make_tangent(name, path):
    """Solve the scene of ``name`` for its iterations and save its tangent K + mu S (CSR on the pattern),
    the residual there, the free coordinates and the iterate ``x`` itself to ``path`` (npz). The iterate
    alone rebuilds the same tangent elsewhere (:func:`tangent_at`: what a machine too far to send the
    matrices to does)."""
    mu = MATRICES[name][4]
    case, x, iterations, converged, solve_s = iterate(name)
    tangent = tangent_at(case, x, mu)
    np.savez(path, **tangent, x=x, iterations=iterations, converged=converged, mu=mu, solve_s=solve_s)
    print(f"  {name}: {case.scene.n_nodes} nodes, {x.size} unknowns, {iterations} iterations "
          f"(converged {converged}), solved in {solve_s:.0f} s", flush=True)


def load(path):
    z = np.load(path)
    a = sp.csr_matrix((z["data"], z["indices"], z["indptr"]))
    meta = {k: z[k].item() for k in ("n_nodes", "iterations", "converged", "mu", "solve_s")}
    return a, z["rhs"], z["free"], meta


# -- measures -----------------------------------------------------------------------------------------------

def backward_error(a, x, b, transpose=False, norm=None):
    """|b - A x|_inf / (|A|_inf |x|_inf + |b|_inf) (A^T for ``transpose``; ``norm``: |A|_inf if known)."""
    m = a.T.tocsr() if transpose else a
    r = b - m @ x
    norm = float(abs(m).sum(axis=1).max()) if norm is None else norm
    scale = norm * np.abs(x).max() + np.abs(b).max()
    return float(np.abs(r).max() / scale) if np.all(np.isfinite(x)) else float("nan")


def transpose_slots(a):
    """s with A^T's entries, in A's CSR order, equal to a.data[s] (A structurally symmetric)."""
    n = a.shape[0]
    rows = np.repeat(np.arange(n), np.diff(a.indptr))
    key_t = a.indices.astype(np.int64) * n + rows  # entry (r, c) of A is entry (c, r) of A^T
    key = rows.astype(np.int64) * n + a.indices
    order = np.argsort(key)
    pos = np.searchsorted(key[order], key_t)
    if not np.array_equal(key[order][np.minimum(pos, key.size - 1)], key_t):
        raise ValueError("the pattern is not structurally symmetric")
    return order[pos]


def rss_mb():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


# -- the solvers ----------------------------------------------------------------------------------------------
# Each adapter: __init__(a, free) (imports and set-up, untimed); analyse() (symbolic analysis, timed; may do
# nothing); factor(data) (numerical factorisation of the CSR values on the fixed pattern, the analysis
# reused); solve(b, transpose) ; fill() ; info() (extra facts). Class attributes: transpose (supported),
# reuse (the symbolic analysis reused across matrices of the pattern), threads.


class HostSolverAdapter:
    transpose, reuse, threads, symmetric_part = True, True, 1, False
    note = "library: SuperLU MMD(A^T+A), diag pivots 1e-3, checked"

    def __init__(self, a, free):
        from jaxnet import linalg
        self.linalg, self.a = linalg, a
        self.s = linalg.HostSolver(a.indptr, a.indices)

    def analyse(self):
        pass  # SuperLU orders inside the first factorisation (MMD_AT_PLUS_A), kept for the later ones

    def factor(self, data):
        if not self.s.factorize(data):
            raise RuntimeError("HostSolver.factorize failed")

    def solve(self, b, transpose=False):
        return self.s.apply(b, transpose)

    def fill(self):
        return self.s.factor_entries

    def info(self):
        lu = self.s._lu  # rows taken off the diagonal by the last factorisation (SymmetricMode: perm_r = perm_c)
        return {"fallbacks": self.s.fallbacks, "refinements": self.s.refinements,
                "offdiag_pivots": None if lu is None else int(np.sum(lu.perm_r != lu.perm_c))}


class MetisAdapter(HostSolverAdapter):
    by_node = False
    note = "HostSolver with METIS ND order, SuperLU NATURAL"

    def __init__(self, a, free):
        super().__init__(a, free)
        import pymetis
        self.pymetis, self.free = pymetis, free

    def analyse(self):
        a = self.a
        n = a.shape[0]
        if self.by_node:
            node = self.free // 3
            nodes, dof_node = np.unique(node, return_inverse=True)
            g = sp.csr_matrix((np.ones(a.nnz), dof_node[a.indices], a.indptr), shape=(n, nodes.size))
            g = (sp.csr_matrix((np.ones(n), (dof_node, np.arange(n))), shape=(nodes.size, n)) @ g).tocsr()
            weights = np.bincount(dof_node)
        else:
            g, weights = a, None
        g = sp.csr_matrix((np.ones(g.nnz), g.indices, g.indptr), shape=g.shape)
        g = (g + g.T).tocsr()
        g.setdiag(0)
        g.eliminate_zeros()
        g.sort_indices()
        graph = self.pymetis.CSRAdjacency(adj_starts=g.indptr, adjacent=g.indices)
        perm, iperm = self.pymetis.nested_dissection(graph, vweights=weights)
        elimination = np.asarray(perm if PERM_IS_ORDER else iperm)  # vertices in elimination order
        if self.by_node:  # the nodes in METIS's order, each node's coordinates together
            rank = np.empty_like(elimination)
            rank[elimination] = np.arange(elimination.size)
            elimination = np.lexsort((np.arange(n), rank[dof_node]))
        self.s._use(self.s._ordering(elimination))


class MetisNodeAdapter(MetisAdapter):
    by_node = True
    note = "HostSolver with METIS ND order of the node graph"


class ColamdAdapter(HostSolverAdapter):
    reuse = False
    note = "HostSolver's fallback: COLAMD, partial pivoting"

    def __init__(self, a, free):
        import scipy.sparse.linalg as spla
        self.spla, self.a = spla, a

    def factor(self, data):
        at = sp.csc_matrix((data, self.a.indices, self.a.indptr), shape=self.a.shape)
        self.lu = self.spla.splu(at, permc_spec="COLAMD", diag_pivot_thresh=1.0)

    def solve(self, b, transpose=False):
        return self.lu.solve(b, trans="N" if transpose else "T")

    def fill(self):
        return int(self.lu.L.nnz + self.lu.U.nnz)

    def info(self):
        return {}


class PardisoAdapter:
    transpose, reuse, symmetric_part = True, True, False
    mtype, threads = 11, 1
    iparm_set = {}  # iparm (1-based) -> value, over pardisoinit's defaults

    @property
    def note(self):
        if self.mtype == 1:
            return "MKL PARDISO structurally symmetric"
        return "MKL PARDISO real nonsym, " + ("scaling, no matching" if self.iparm_set.get(13) == 0
                                              else "defaults (scaling + weighted matching)")

    def __init__(self, a, free):
        import ctypes

        from jaxnet.linalg import pardiso
        self.ct = ctypes
        lib = pardiso.library()
        if lib is None:
            raise ImportError("MKL's mkl_rt library is not installed")
        self.pardiso = lib.pardiso
        self.pardiso.restype = None
        self.n = a.shape[0]
        self.ia = a.indptr.astype(np.int32)
        self.ja = a.indices.astype(np.int32)
        self.pt = np.zeros(64, dtype=np.int64)
        self.iparm = np.zeros(64, dtype=np.int32)
        self.data = np.zeros(a.nnz)
        lib.pardisoinit(self._p(self.pt), self.ct.byref(self.ct.c_int32(self.mtype)), self._p(self.iparm))
        self.iparm[34] = 1  # zero-based indices
        self.iparm[17] = -1  # report the factor's entries
        self.iparm[26] = 0  # no matrix check
        for i, v in self.iparm_set.items():
            self.iparm[i - 1] = v
        self.mkl_threads = int(lib.MKL_Get_Max_Threads())

    def _p(self, arr):
        return arr.ctypes.data_as(self.ct.c_void_p)

    def _call(self, phase, b=None, x=None):
        ct = self.ct
        error = ct.c_int32(0)
        one = ct.c_int32(1)
        nrhs = ct.c_int32(1)
        dummy = np.zeros(1)
        self.pardiso(self._p(self.pt), ct.byref(one), ct.byref(one), ct.byref(ct.c_int32(self.mtype)),
                     ct.byref(ct.c_int32(phase)), ct.byref(ct.c_int32(self.n)), self._p(self.data), self._p(self.ia),
                     self._p(self.ja), None, ct.byref(nrhs), self._p(self.iparm), ct.byref(ct.c_int32(0)),
                     self._p(dummy if b is None else b), self._p(dummy if x is None else x), ct.byref(error))
        if error.value != 0:
            raise RuntimeError(f"PARDISO phase {phase}: error {error.value}")

    def analyse(self):
        self._call(11)

    def factor(self, data):
        self.data[:] = data
        self._call(22)

    def solve(self, b, transpose=False):
        b = np.ascontiguousarray(b, dtype=float)
        x = np.zeros_like(b)
        self.iparm[11] = 2 if transpose else 0
        self._call(33, b, x)
        return x

    def fill(self):
        return int(self.iparm[17])

    def info(self):
        return {"mkl_threads": self.mkl_threads, "perturbed_pivots": int(self.iparm[13]),
                "pardiso_peak_MB": round(max(int(self.iparm[14]), int(self.iparm[15]) + int(self.iparm[16])) / 1024, 1),
                "refinement_steps": int(self.iparm[6])}


class _Kvx:
    transpose, reuse, threads, symmetric_part = True, True, 1, False

    def __init__(self, a, free):
        import kvxopt
        self.kvx = kvxopt
        self.a = a
        # A's CSR entry numbers in CSC order: the slots that gather CSR values into kvxopt's CSC
        self.slot = sp.csr_matrix((np.arange(a.nnz) + 1, a.indices, a.indptr), shape=a.shape).tocsc()
        self.slot.sort_indices()
        coo = self.slot.tocoo()
        self.slot = (self.slot.data - 1).astype(np.int64)
        self.K = kvxopt.spmatrix(kvxopt.matrix(a.data[self.slot]), coo.row.tolist(), coo.col.tolist(), a.shape)

    def _set(self, data):
        self.K.V = self.kvx.matrix(data[self.slot])

    def info(self):
        return {}


class UmfpackAdapter(_Kvx):
    note = "UMFPACK 5.7 (kvxopt)"

    def analyse(self):
        from kvxopt import umfpack
        self.umf = umfpack
        self.Fs = umfpack.symbolic(self.K)

    def factor(self, data):
        self._set(data)
        self.Fn = self.umf.numeric(self.K, self.Fs)

    def solve(self, b, transpose=False):
        x = self.kvx.matrix(np.array(b, dtype=float))
        self.umf.solve(self.K, self.Fn, x, trans="T" if transpose else "N")
        return np.array(x).ravel()

    def fill(self):
        L, U, *_ = self.umf.get_numeric(self.K, self.Fn)
        return int(len(L) + len(U))


class KluAdapter(_Kvx):
    note = "KLU (kvxopt)"

    def analyse(self):
        from kvxopt import klu
        self.klu = klu
        self.Fs = klu.symbolic(self.K)

    def factor(self, data):
        self._set(data)
        self.Fn = self.klu.numeric(self.K, self.Fs)

    def solve(self, b, transpose=False):
        x = self.kvx.matrix(np.array(b, dtype=float))
        self.klu.solve(self.K, self.Fs, self.Fn, x, trans="T" if transpose else "N")
        return np.array(x).ravel()

    def fill(self):
        parts = self.klu.get_numeric(self.K, self.Fs, self.Fn)
        return int(len(parts[0]) + len(parts[1]) + len(parts[5]))  # L, U and the off-diagonal blocks F


class SparsaxKluAdapter:
    transpose, reuse, threads, symmetric_part = True, True, 1, False
    note = "KLU through sparsax (XLA FFI, JAX-native)"

    def __init__(self, a, free):
        import jax
        jax.config.update("jax_enable_x64", True)
        import jax.numpy as jnp
        import sparsax
        self.sx, self.jnp = sparsax, jnp
        rows = np.repeat(np.arange(a.shape[0]), np.diff(a.indptr))
        self.ai, self.aj, self.n = jnp.asarray(rows, jnp.int32), jnp.asarray(a.indices, jnp.int32), a.shape[0]

    def analyse(self):
        pass  # cached by pattern inside the first factorisation

    def factor(self, data):
        # sparsax keeps the factors of the values it has seen (keyed by a hash of them): each call factorises
        # data times another power of 2 (exact, the same pivots), and the solve scales x back
        self.k = getattr(self, "k", -1) + 1
        self.scale = 2.0 ** (self.k % 64 - 32)
        self.token = self.sx.lu_factor(self.ai, self.aj, self.jnp.asarray(data * self.scale), self.n)
        self.token.block_until_ready()

    def solve(self, b, transpose=False):
        return self.scale * np.asarray(self.sx.lu_solve_factor(self.token, self.jnp.asarray(b), trans=transpose))

    def fill(self):
        return None

    def info(self):
        return {}


class _SymPart:
    """Factorises (A + A^T)/2; solve() refines against A."""
    symmetric_part = True

    def _sym_setup(self, a):
        self.a, self.at = a, a.T.tocsr()
        self.norms = (float(abs(a).sum(axis=1).max()), float(abs(a).sum(axis=0).max()))
        self.tslot = transpose_slots(a)
        self.steps = []

    def sym_values(self, data):
        return 0.5 * (data + data[self.tslot])

    def solve(self, b, transpose=False):
        m = self.at if transpose else self.a  # the matrix the worker factorises, A itself
        x = self.raw_solve(b)
        steps = 0
        while steps < MAX_REFINE and backward_error(m, x, b, norm=self.norms[transpose]) > REFINE_TO:
            x = x + self.raw_solve(b - m @ x)
            steps += 1
        self.steps.append(steps)
        return x

    def info(self):
        return {"refinement_steps_max": max(self.steps, default=0),
                "raw_backward_error": getattr(self, "raw_error", None)}


class CholmodAdapter(_SymPart):
    transpose, reuse, threads = True, True, 1
    mode = "simplicial"

    @property
    def note(self):
        return f"CHOLMOD {'LDL^T simplicial' if self.mode == 'simplicial' else 'LL^T supernodal'} on (A+A^T)/2"

    def __init__(self, a, free):
        from sksparse import cholmod
        self.ch = cholmod
        self._sym_setup(a)
        c = sp.csr_matrix((np.arange(a.nnz, dtype=float) + 1, a.indices, a.indptr), shape=a.shape)
        cu = sp.triu(c, format="csc")
        cu.sort_indices()
        self.uslot = (cu.data - 1).astype(np.int64)
        self.upper = cu

    def _matrix(self, data):
        m = self.upper.copy()
        m.data = self.sym_values(data)[self.uslot]
        return m + sp.triu(m, k=1).T

    def analyse(self):
        self.f = self.ch.analyze(self._matrix(self.a.data).tocsc(), mode=self.mode)

    def factor(self, data):
        self.f.cholesky_inplace(self._matrix(data).tocsc())

    def raw_solve(self, b):
        return self.f.solve_A(b)

    def fill(self):
        return int(self.f.L().nnz)


class CholmodLLtAdapter(CholmodAdapter):
    mode = "supernodal"


class QdldlAdapter(_SymPart):
    transpose, reuse, threads = True, True, 1
    note = "QDLDL (AMD, LDL^T, no pivoting) on (A+A^T)/2"

    def __init__(self, a, free):
        import qdldl
        self.q = qdldl
        self._sym_setup(a)
        c = sp.csr_matrix((np.arange(a.nnz, dtype=float) + 1, a.indices, a.indptr), shape=a.shape)
        cu = sp.triu(c, format="csc")
        cu.sort_indices()
        self.uslot = (cu.data - 1).astype(np.int64)
        self.upper = cu

    def _matrix(self, data):
        m = self.upper.copy()
        m.data = self.sym_values(data)[self.uslot]
        return m

    def analyse(self):
        pass  # QDLDL's AMD and elimination tree are computed by the constructor, with the first factorisation

    def factor(self, data):
        if getattr(self, "solver", None) is None:
            self.solver = self.q.Solver(self._matrix(data), upper=True)
        else:
            self.solver.update(self._matrix(data), upper=True)

    def raw_solve(self, b):
        return self.solver.solve(b)

    def fill(self):
        L, D, p = self.solver.factors()
        return int(L.nnz + L.shape[0])  # L's off-diagonal entries and D


class MumpsAdapter:
    transpose, reuse, threads, symmetric_part = True, True, 1, False
    sym, ordering = 0, 7  # ICNTL(7): 7 MUMPS's choice, 5 METIS
    note = "MUMPS 5.5 unsymmetric (Debian, pymumps)"

    def __init__(self, a, free):
        import mumps
        self.a = a
        self.ctx = mumps.DMumpsContext(sym=self.sym, par=1)
        self.ctx.set_silent()
        rows = np.repeat(np.arange(a.shape[0]), np.diff(a.indptr))
        if self.sym:
            keep = rows >= a.indices  # lower triangle
        else:
            keep = np.ones(a.nnz, bool)
        self.keep = np.flatnonzero(keep)
        self.irn = (rows[keep] + 1).astype(np.int32)
        self.jcn = (a.indices[keep] + 1).astype(np.int32)
        self.vals = np.ascontiguousarray(a.data[keep], dtype=float)
        self.ctx.set_shape(a.shape[0])
        self.ctx.set_centralized_assembled(self.irn, self.jcn, self.vals)
        self.ctx.set_icntl(7, self.ordering)

    def values(self, data):
        return data[self.keep]

    def analyse(self):
        self.ctx.run(job=1)
        self._check("analysis")

    def _check(self, what):
        if self.ctx.get_infog(1) < 0:
            raise RuntimeError(f"MUMPS {what}: INFOG(1) = {self.ctx.get_infog(1)}, INFOG(2) = {self.ctx.get_infog(2)}")

    def factor(self, data):
        self.vals[:] = self.values(data)
        self.ctx.run(job=2)
        self._check("factorisation")

    def raw_solve(self, b, transpose=False):
        x = np.array(b, dtype=float)
        self.ctx.set_rhs(x)
        self.ctx.set_icntl(9, 0 if transpose else 1)
        self.ctx.run(job=3)
        self._check("solve")
        return x

    def solve(self, b, transpose=False):
        return self.raw_solve(b, transpose)

    def fill(self):
        f = self.ctx.get_infog(29)
        return int(f) if f >= 0 else int(-f * 1e6)

    def info(self):
        out = {"mumps_peak_MB": int(self.ctx.get_infog(21)),
               "ordering": {0: "AMD", 2: "AMF", 3: "SCOTCH", 4: "PORD", 5: "METIS", 6: "QAMD"}.get(
                   int(self.ctx.get_infog(7)), int(self.ctx.get_infog(7)))}
        self.ctx.destroy()  # the last call of the worker
        return out


class MumpsSymAdapter(_SymPart, MumpsAdapter):
    sym = 2
    note = "MUMPS 5.5 LDL^T (sym=2) on (A+A^T)/2"

    def __init__(self, a, free):
        MumpsAdapter.__init__(self, a, free)
        self._sym_setup(a)

    def values(self, data):
        return self.sym_values(data)[self.keep]

    def raw_solve(self, b):
        return MumpsAdapter.raw_solve(self, b, False)

    def solve(self, b, transpose=False):
        return _SymPart.solve(self, b, transpose)

    def info(self):
        return {**MumpsAdapter.info(self), **_SymPart.info(self)}


#: the solvers a run measures unless told (``--solvers all``: every one of :data:`SOLVERS`); the others repeat
#: what these show (METIS on the unknowns' graph, PARDISO mtype 11 without matching on 2 threads, KLU through
#: sparsax, QDLDL) and would take the run past ~15 minutes
EXTRA = ("SuperLU+METIS(dof)", "PARDISO-11nm/2t", "KLU(sparsax)", "QDLDL(sym)")


def _variant(base, **kw):
    return type(base.__name__, (base,), kw)


SOLVERS = {
    "HostSolver": HostSolverAdapter,
    "SuperLU+METIS(dof)": MetisAdapter,
    "SuperLU+METIS(node)": MetisNodeAdapter,
    "SuperLU-COLAMD-pp": ColamdAdapter,
    "PARDISO-11": PardisoAdapter,
    "PARDISO-11nm": _variant(PardisoAdapter, iparm_set={13: 0}),
    "PARDISO-11nm/2t": _variant(PardisoAdapter, iparm_set={13: 0}, threads=2),
    "PARDISO-1": _variant(PardisoAdapter, mtype=1),
    "PARDISO-1/2t": _variant(PardisoAdapter, mtype=1, threads=2),
    "UMFPACK": UmfpackAdapter,
    "KLU": KluAdapter,
    "KLU(sparsax)": SparsaxKluAdapter,
    "MUMPS": MumpsAdapter,
    "MUMPS-LDLt(sym)": MumpsSymAdapter,
    "CHOLMOD-LDLt(sym)": CholmodAdapter,
    "CHOLMOD-LLt(sym)": CholmodLLtAdapter,
    "QDLDL(sym)": QdldlAdapter,
}


# -- one solver on the matrices, in its own process -----------------------------------------------------------

class PeakRss:
    """The largest resident set size (MB) of this process while the ``with`` block runs, sampled every
    2 ms by a thread, less the size at its start (the C heap trimmed first, so that memory freed by the
    previous matrix's solver does not hide this one's)."""

    def __enter__(self):
        import ctypes
        import gc
        import threading
        gc.collect()
        try:
            ctypes.CDLL("libc.so.6").malloc_trim(0)
        except (OSError, AttributeError):
            pass
        self.base = self.peak = rss_mb()
        self.stop = threading.Event()
        self.thread = threading.Thread(target=self._sample, daemon=True)
        self.thread.start()
        return self

    def _sample(self):
        while not self.stop.wait(0.002):
            self.peak = max(self.peak, rss_mb())

    def __exit__(self, *exc):
        self.stop.set()
        self.thread.join()
        self.peak = max(self.peak, rss_mb())
        self.mb = self.peak - self.base


def forget_caches():
    """Empty the per-pattern caches of the libraries (the cage's two tangents share a pattern)."""
    if "jaxnet.linalg" in sys.modules:
        sys.modules["jaxnet.linalg"]._ORDERINGS.clear()
        sys.modules["jaxnet.linalg"]._SOLVERS.clear()
    if "sparsax" in sys.modules:
        sys.modules["sparsax"].clear_cache()


def measure(path, solver_name, repeats, target_s):
    """One solver on one tangent (see the module docstring): a dict of the measures."""
    a, b, free, _ = load(path)
    data = a.data.copy()
    out = {"solver": solver_name}
    forget_caches()
    t = time.perf_counter()
    s = SOLVERS[solver_name](a, free)
    out["setup_s"] = time.perf_counter() - t
    with PeakRss() as peak:
        t = time.perf_counter()
        s.analyse()
        out["analysis_s"] = time.perf_counter() - t
        s.factor(data)
        out["first_s"] = time.perf_counter() - t
        # ``repeats`` factorisations, fewer where they would take over target_s: 3 at least, 2 where the first
        # alone took longer than target_s
        count = max(2 if out["first_s"] > target_s else 3, min(repeats, int(target_s / max(out["first_s"], 1e-9))))
        factor_s, total_s, solve_s = [], [], []
        for _ in range(count):
            t0 = time.perf_counter()
            s.factor(data)
            t1 = time.perf_counter()
            x = s.solve(b)
            t2 = time.perf_counter()
            factor_s.append(t1 - t0)
            solve_s.append(t2 - t1)
            total_s.append(t2 - t0)
    out["repeats"] = count
    out["factor_s"] = statistics.median(factor_s)
    out["solve_s"] = statistics.median(solve_s)
    out["total_s"] = statistics.median(total_s)
    out["peak_MB"] = peak.mb
    out["berr"] = backward_error(a, x, b)
    if getattr(s, "symmetric_part", False):
        s.raw_error = backward_error(a, s.raw_solve(b), b)
    try:
        xt = s.solve(b, transpose=True)
        out["berr_t"] = backward_error(a, xt, b, transpose=True)
    except Exception as e:  # noqa: BLE001
        out["berr_t"], out["transpose_error"] = float("nan"), repr(e)
    out["fill"] = s.fill()
    out["info"] = s.info()
    out["transpose"], out["reuse"], out["threads"] = s.transpose, s.reuse, s.threads
    out["note"] = s.note
    return out


def worker(solver_name, paths, repeats, budget, target_s):
    """Measure one solver on each tangent in turn (ascending size), printing one RESULT line each. A tangent
    whose predicted time (that of the last tangent of the same kind, early or late iterate, scaled by
    (n / n_last)^1.5) exceeds ``budget`` is skipped, except for HostSolver (the reference)."""
    last = {}
    for path in paths:
        n = int(np.load(path)["indptr"].size - 1)
        kind = "early" if path.stem.endswith("it5") else "late"
        known = last.get(kind) or last.get("early" if kind == "late" else "late")
        if known is not None and solver_name != "HostSolver":
            predicted = known[1] * (n / known[0]) ** 1.5
            if predicted > budget:
                out = {"solver": solver_name, "error": f"skipped (predicted {predicted:.0f} s)"}
                print("RESULT " + json.dumps({"path": str(path), **out}), flush=True)
                continue
        t = time.perf_counter()
        try:
            out = measure(path, solver_name, repeats, target_s)
            last[kind] = (n, time.perf_counter() - t)
        except Exception as e:  # noqa: BLE001
            out = {"solver": solver_name, "error": f"{type(e).__name__}: {e}"[:200]}
        out["wall_s"] = time.perf_counter() - t
        print("RESULT " + json.dumps({"path": str(path), **out}, default=str), flush=True)


def run_solver(solver_name, paths, args):
    """Run :func:`worker` in a fresh process with the solver's thread count; a crashed or hung process
    (no result for ``4 x budget`` s) costs its tangent, and the rest are measured in a new process.
    Yields each tangent's result."""
    import selectors

    threads = str(SOLVERS[solver_name].threads)
    env = dict(os.environ, OMP_NUM_THREADS=threads, MKL_NUM_THREADS=threads, OPENBLAS_NUM_THREADS=threads,
               JAX_PLATFORMS="cpu", PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    todo = list(paths)
    while todo:
        cmd = [sys.executable, "-W", "ignore", __file__, "--worker", solver_name, *map(str, todo),
               "--repeats", str(args.repeats), "--budget", str(args.budget), "--target", str(args.target)]
        p = subprocess.Popen(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        sel = selectors.DefaultSelector()
        sel.register(p.stdout, selectors.EVENT_READ)
        deadline = time.perf_counter() + 4 * args.budget + 30
        failed = None
        while todo:
            if not sel.select(timeout=max(0.0, deadline - time.perf_counter())):
                p.kill()
                failed = f"killed after {4 * args.budget + 30:.0f} s without a result"
                break
            line = p.stdout.readline()
            if not line:  # the process ended
                p.wait()
                failed = f"process died (exit {p.returncode}): " + (p.stderr.read().strip().splitlines()
                                                                    or ["?"])[-1][:160]
                break
            if line.startswith("RESULT "):
                out = json.loads(line[len("RESULT "):])
                path = pathlib.Path(out.pop("path"))
                todo.remove(path)
                deadline = time.perf_counter() + 4 * args.budget + 30
                yield path, out
        p.stdout.close()
        p.stderr.close()
        p.wait()
        if failed and todo:
            yield todo.pop(0), {"solver": solver_name, "error": failed}


# -- the report ---------------------------------------------------------------------------------------------

def fmt(v, spec=".3g"):
    if v is None or (isinstance(v, float) and not np.isfinite(v)):
        return "-"
    return format(v, spec)


def slope(points):
    """Least-squares slope of log(t) against log(n), or None with fewer than 2 distinct n."""
    if len({n for n, _ in points}) < 2:
        return None
    x, y = np.log([n for n, _ in points]), np.log([t for _, t in points])
    return float(np.polyfit(x, y, 1)[0])


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", nargs="+", default=["1e3", "1e4", "3e4", "1e5"],
                        help="size groups of the tangents (1e3 1e4 3e4 1e5)")
    parser.add_argument("--matrices", nargs="+", help="tangents by name (overrides --sizes)")
    parser.add_argument("--solvers", nargs="+", default=[k for k in SOLVERS if k not in EXTRA],
                        help="solvers by name, or all (default: all but " + ", ".join(EXTRA) + ")")
    parser.add_argument("--repeats", type=int, default=5, help="most factorisations timed per pair (median)")
    parser.add_argument("--target", type=float, default=4.0,
                        help="seconds of timed factorisations per pair: fewer repeats (3 at least) beyond")
    parser.add_argument("--budget", type=float, default=40.0,
                        help="a pair predicted to take longer (seconds) is skipped")
    parser.add_argument("--tangents", type=pathlib.Path, default=TANGENTS, help="where the tangents are kept")
    parser.add_argument("--regenerate", action="store_true", help="recompute the tangents")
    parser.add_argument("--json", type=pathlib.Path, help="also write the raw results here")
    parser.add_argument("--list", action="store_true", help="list the tangents and solvers and stop")
    parser.add_argument("--worker", nargs="+", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)

    if args.worker:
        worker(args.worker[0], [pathlib.Path(p) for p in args.worker[1:]], args.repeats, args.budget, args.target)
        return
    if args.list:
        print("tangents:", ", ".join(f"{k} ({v[0]})" for k, v in MATRICES.items()))
        print("solvers:", ", ".join(SOLVERS), "(by default all but", ", ".join(EXTRA) + ")")
        return
    names = args.matrices or [k for k, v in MATRICES.items() if v[0] in args.sizes]
    if args.solvers == ["all"]:
        args.solvers = list(SOLVERS)
    unknown = [s for s in args.solvers if s not in SOLVERS] + [k for k in names if k not in MATRICES]
    if unknown:
        parser.error(f"unknown {unknown}; solvers: {list(SOLVERS)}; tangents: {list(MATRICES)}")
    args.tangents.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    missing = [k for k in names if args.regenerate or not (args.tangents / f"{k}.npz").exists()]
    if missing:
        print(f"computing {len(missing)} tangents into {args.tangents} (once)", flush=True)
        for k in missing:
            make_tangent(k, args.tangents / f"{k}.npz")
    t_bench = time.perf_counter()

    facts, paths = {}, {}
    for k in names:
        paths[k] = args.tangents / f"{k}.npz"
        a, _, _, meta = load(paths[k])
        nonsym = float(sp.linalg.norm(a - a.T) / sp.linalg.norm(a))
        facts[k] = dict(meta, n=a.shape[0], nnz=a.nnz, nonsym=nonsym)
    names.sort(key=lambda k: (facts[k]["n"], k))
    by_path = {paths[k]: k for k in names}
    results = {}
    for name in args.solvers:
        t = time.perf_counter()
        print(f"{name}:", flush=True)
        for path, out in run_solver(name, [paths[k] for k in names], args):
            k = by_path[path]
            out["matrix"] = k
            results[(k, name)] = out
            if "error" in out:
                print(f"  {k:16s} {out['error']}", flush=True)
            else:
                print(f"  {k:16s} first {out['first_s']:.3g} s, factor+solve {out['total_s']:.3g} s "
                      f"(x{out['repeats']}), fill {out['fill']}, berr {out['berr']:.1e} / {out['berr_t']:.1e}",
                      flush=True)
        print(f"  ({time.perf_counter() - t:.0f} s)", flush=True)
    rows = [results[(k, name)] for k in names for name in args.solvers if (k, name) in results]
    report(rows, {k: facts[k] for k in names}, args)
    print(f"\n(tangents: {t_bench - t_start:.0f} s; benchmark: {time.perf_counter() - t_bench:.0f} s)")
    if args.json:
        args.json.write_text(json.dumps({"facts": facts, "rows": rows}, indent=1, default=str))


def report(rows, facts, args):
    ref = {r["matrix"]: r for r in rows if r["solver"] == "HostSolver" and "error" not in r}
    print("\n## Tangents\n")
    print("| matrix | nodes | n | nnz | Newton its (converged) | mu | ‖A−Aᵀ‖_F/‖A‖_F |")
    print("|---|---|---|---|---|---|---|")
    for k, f in facts.items():
        print(f"| {k} | {f['n_nodes']} | {f['n']} | {f['nnz']} | {f['iterations']} ({f['converged']}) | "
              f"{f['mu']:g} | {f['nonsym']:.2e} |")
    print(f"\n## Factorisations (repeats {args.repeats}, medians; ratios against HostSolver on the same matrix)\n")
    print("| matrix | n | solver | thr | analysis s | first fact. s | fact. s | fact.+solve s | solve s | reps | "
          "time / Host | fill nnz(L+U) | fill / Host | peak MB | berr | berr Aᵀ | refine | transpose | reuse | "
          "notes |")
    print("|" + "---|" * 20)
    for r in rows:
        n = facts[r["matrix"]]["n"]
        if "error" in r:
            print(f"| {r['matrix']} | {n} | {r['solver']} |" + " |" * 16 + f" {r['error']} |")
            continue
        h = ref.get(r["matrix"])
        ratio_t = r["total_s"] / h["total_s"] if h else None
        ratio_f = r["fill"] / h["fill"] if (h and r["fill"]) else None
        info = r.get("info", {})
        refine = info.get("refinement_steps_max", info.get("refinements", info.get("refinement_steps", "")))
        skip = ("refinement_steps_max", "refinements", "refinement_steps")
        notes = [r["note"]] + [f"{k} {fmt(v, '.1e' if 'error' in k else '.3g') if isinstance(v, float) else v}"
                               for k, v in info.items() if k not in skip]
        print(f"| {r['matrix']} | {n} | {r['solver']} | {r['threads']} | {fmt(r['analysis_s'])} | "
              f"{fmt(r['first_s'])} | {fmt(r['factor_s'])} | {fmt(r['total_s'])} | {fmt(r['solve_s'])} | "
              f"{r['repeats']} | {fmt(ratio_t, '.2f')} | {fmt(r['fill'], 'd') if r['fill'] else '-'} | "
              f"{fmt(ratio_f, '.2f')} | {fmt(r['peak_MB'], '.0f')} | {fmt(r['berr'], '.1e')} | "
              f"{fmt(r['berr_t'], '.1e')} | {refine} | {'yes' if r['transpose'] else 'no'} | "
              f"{'yes' if r['reuse'] else 'no'} | {'; '.join(notes)} |")
    print("\n## Growth of the factorisation time (fact.+solve, median) with n: exponent p of t ~ n^p\n")
    print("| solver | p, cage early tangents | p, all tangents | points |")
    print("|---|---|---|---|")
    for name in args.solvers:
        ok = [r for r in rows if r["solver"] == name and "error" not in r]
        cage = [(facts[r["matrix"]]["n"], r["total_s"]) for r in ok if r["matrix"].startswith("cage")
                and r["matrix"].endswith("it5")]
        every = [(facts[r["matrix"]]["n"], r["total_s"]) for r in ok]
        print(f"| {name} | {fmt(slope(cage), '.2f')} | {fmt(slope(every), '.2f')} | {len(cage)} / {len(every)} |")


if __name__ == "__main__":
    if "--worker" not in sys.argv:
        sys.path.insert(0, str(ROOT))
    main()
