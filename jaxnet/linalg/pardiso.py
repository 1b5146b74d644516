"""oneMKL PARDISO, called through ctypes: the sparse direct factorisation of the tangents where MKL is installed.

What it is. PARDISO (Schenk and Gärtner; the version in Intel's oneMKL) factorises a sparse matrix with a
nested-dissection ordering (METIS) and a supernodal, multithreaded LU. jaxnet calls it for real
nonsymmetric matrices (``mtype`` 11: the tangents are structurally symmetric and nearly symmetric in value,
drag making them slightly nonsymmetric) with MKL's defaults except: indices from zero; no maximum weighted
matching (``iparm[12] = 0``, "iparm(13)" in MKL's one-based numbering), which on these tangents doubles the
fill and leaves solutions inaccurate (backward errors 1e-7 to 1e-3); no refinement of its own (jaxnet checks
and refines); no matrix check. Pivots too small are perturbed (MKL's default for ``mtype`` 11, 1e-13
relative) instead of exchanged, so the factor keeps the ordering's fill whatever the pivots: what makes it
fast on the cage's tangents, where SuperLU's threshold pivoting leaves the symmetric ordering and fills
several times more. A perturbed factor is of a nearby matrix: :class:`jaxnet.linalg.PardisoSolver` hands
such a matrix to SuperLU with partial pivoting, and checks and refines every solution, as it does SuperLU's.
It runs in oneMKL's reproducible mode (:data:`CNR`), so that one scene gives one answer to the last bit.

Why it. Measured side by side on the static solver's own tangents (``benchmarks/factorisation.py``):
against SuperLU with a minimum-degree ordering, PARDISO factorises as fast on FEMNET's cod-end (10³ nodes)
and faster on the cage from 10⁴ to 10⁵ nodes, with less fill (the figures: ``validation/REPORT.md``);
SuperLU with METIS's ordering, UMFPACK, KLU and MUMPS are slower than PARDISO at every size there, and the
symmetric factorisations (CHOLMOD, LDLᵀ) give inaccurate solutions once drag makes the tangent
nonsymmetric. PARDISO solves with A or with Aᵀ on one factor (``iparm[11]``), which the implicit function
theorem and the adjoints need.

Availability. MKL comes as the ``mkl`` wheel on x86-64 (``pyproject.toml``); :func:`available` looks for its
``mkl_rt`` library where pip puts it (the environment's or the user's ``lib``), then where the system's
loader finds it. Where it is absent (other processors) jaxnet factorises with SuperLU alone.
``JAXNET_SPARSE_SOLVER=superlu`` in the environment makes jaxnet use SuperLU even where MKL is installed (to
compare the two); ``cudss`` asks for NVIDIA's cuDSS on a GPU (:mod:`jaxnet.linalg.cudss`;
:func:`jaxnet.linalg.solver_choice` says which applies).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import glob
import os
import site
import sys
import sysconfig

import numpy as np

#: the environment variable that chooses the sparse direct solver (:func:`jaxnet.linalg.solver_choice`):
#: "superlu" for SuperLU even where MKL is installed, "pardiso" for PARDISO, "cudss" for cuDSS on a GPU; unset
#: for cuDSS where JAX computes on a GPU and it is installed, else PARDISO where MKL is, else SuperLU
CHOICE = "JAXNET_SPARSE_SOLVER"

#: PARDISO's matrix type: real and nonsymmetric
REAL_NONSYMMETRIC = 11

#: oneMKL's conditional numerical reproducibility (CNR) mode, for bitwise reproducible factors from run to run
#: on one machine: PARDISO's threads otherwise sum in an order that varies, and a Newton iteration sensitive to
#: rounding (the 10⁴-node cage) then gave one scene two iteration counts. "AUTO": the code branch MKL chooses
#: for this processor, kept for the whole run. Set through MKL's own environment variable, which MKL reads at
#: its first call; a value the user gave is left as it is. Its cost: ``docs/investigations.md``,
#: "PARDISO's reproducible mode".
CNR = ("MKL_CBWR", "AUTO")

_LIBRARY = []  # [library or None], once per process


def library():
    """The loaded ``mkl_rt`` library (ctypes), or None where MKL is not installed."""
    if not _LIBRARY:
        found = None
        # the mkl wheel puts its libraries in the data directory of the scheme pip installed it with: the
        # environment's (a venv, the system) or the user's (pip install --user)
        roots = dict.fromkeys([sys.prefix, sysconfig.get_paths()["data"], site.getuserbase()])
        candidates = [path for root in roots
                      for path in sorted(glob.glob(os.path.join(root, "lib", "libmkl_rt.so*")), reverse=True)]
        candidates += [name for name in (ctypes.util.find_library("mkl_rt"),) if name]
        os.environ.setdefault(*CNR)  # before MKL's first call (CNR)
        for path in candidates:
            try:
                found = ctypes.CDLL(path)
                found.pardiso.restype = None
                break
            except (OSError, AttributeError):
                found = None
        _LIBRARY.append(found)
    return _LIBRARY[0]


def available():
    """Whether the static solver factorises with PARDISO: MKL is installed and not declined by
    ``JAXNET_SPARSE_SOLVER=superlu``."""
    return os.environ.get(CHOICE, "").lower() != "superlu" and library() is not None


def _address(array):
    return array.ctypes.data_as(ctypes.c_void_p)


class Factor:
    """One PARDISO handle for the matrices of one CSR structure: ``analyse`` once (ordering and symbolic
    factorisation), then ``factor(data)`` for each matrix and ``solve(b, transpose)`` with the last factor.
    Its memory is released when the object is (``release``). Raises RuntimeError with PARDISO's error code
    when a phase fails (singular, out of memory)."""

    def __init__(self, indptr, indices):
        self._lib = library()
        if self._lib is None:
            raise RuntimeError("PARDISO: MKL's mkl_rt library is not installed")
        self.n = int(np.asarray(indptr).shape[0] - 1)
        self._ia = np.ascontiguousarray(indptr, dtype=np.int32)
        self._ja = np.ascontiguousarray(indices, dtype=np.int32)
        self._data = np.zeros(self._ja.shape[0])
        self._pt = np.zeros(64, dtype=np.int64)  # PARDISO's internal handle
        self.iparm = np.zeros(64, dtype=np.int32)
        self._lib.pardisoinit(_address(self._pt), ctypes.byref(ctypes.c_int32(REAL_NONSYMMETRIC)), _address(self.iparm))
        self.iparm[34] = 1  # indices from zero
        self.iparm[12] = 0  # no maximum weighted matching (module docstring)
        self.iparm[26] = 0  # no check of the structure: it is the tangent's pattern, sorted
        # no refinement steps of PARDISO's own: every solution is checked and refined if need be by
        # jaxnet.linalg (two steps by default, each a solve and a product, whether needed or not)
        self.iparm[7] = 0
        self.iparm[17] = -1  # report the factor's entries in iparm[17]
        self._analysed = False

    def _call(self, phase, b=None, x=None, nrhs=1):
        error = ctypes.c_int32(0)
        one = ctypes.c_int32(1)
        none = np.zeros(1)
        self._lib.pardiso(_address(self._pt), ctypes.byref(one), ctypes.byref(one),
                          ctypes.byref(ctypes.c_int32(REAL_NONSYMMETRIC)), ctypes.byref(ctypes.c_int32(phase)),
                          ctypes.byref(ctypes.c_int32(self.n)), _address(self._data), _address(self._ia),
                          _address(self._ja), None, ctypes.byref(ctypes.c_int32(nrhs)), _address(self.iparm),
                          ctypes.byref(ctypes.c_int32(0)), _address(none if b is None else b),
                          _address(none if x is None else x), ctypes.byref(error))
        if error.value != 0:
            raise RuntimeError(f"PARDISO phase {phase}: error {error.value}")

    def factor(self, data):
        """Factorise the matrix of CSR entries ``data`` (analysing the structure first, the first time)."""
        self._data[:] = data
        if not self._analysed:
            self._call(11)
            self._analysed = True
        self._call(22)

    def solve(self, b, transpose=False):
        """A^-1 b (A^-T b if ``transpose``) with the last factor; b of shape (n,) or (n, k)."""
        b = np.asarray(b, dtype=float)
        rhs = np.array(b.reshape(self.n, -1), order="F")  # PARDISO takes the columns one after the other
        x = np.zeros_like(rhs, order="F")
        self.iparm[11] = 2 if transpose else 0
        self._call(33, rhs, x, nrhs=rhs.shape[1])
        return x.reshape(b.shape)

    @property
    def entries(self):
        """Entries of the last factor, L's and U's together."""
        return int(self.iparm[17])

    @property
    def perturbed_pivots(self):
        """Pivots of the last factorisation that were perturbed for being too small."""
        return int(self.iparm[13])

    def release(self):
        """Free PARDISO's memory for this structure (its factor and analysis)."""
        if self._analysed and self._lib is not None:
            try:
                self._call(-1)
            except RuntimeError:
                pass
            self._analysed = False

    def __del__(self):
        try:
            self.release()
        except Exception:  # noqa: BLE001 -- at interpreter shutdown numpy and ctypes may be gone already
            pass
