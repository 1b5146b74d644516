"""Sparse direct solves on an accelerator against the host's, on the static solver's own tangents.

    python validation/bench_device_factorisation.py [--tangents DIR] [--matrices NAME ...] [--repeats 3]
                                                    [--limit 120]

The tangents are those ``validation/bench_factorisation.py`` computes and keeps (its ``--tangents`` directory,
by default ``jaxnet-tangents`` in the system's temporary directory): run it first, on any machine, and bring
the ``.npz`` files along. On each tangent, side by side:

* ``host``: the factorisation the static solver makes (:func:`jaxnet.linalg.direct_solver`: PARDISO where MKL
  is installed, else SuperLU), its first factorisation and solve (analysis included) and the median of
  ``--repeats`` more;
* ``jax spsolve``: :func:`jax.experimental.sparse.linalg.spsolve` on JAX's default device (cuSOLVER's sparse
  QR with reordering on a CUDA device; on the CPU, scipy's ``spsolve`` through a host callback);
* ``cupy spsolve``: :func:`cupyx.scipy.sparse.linalg.spsolve` where CuPy imports (cuSOLVER on the GPU).

For each: the time of the first call and the median of the next ``--repeats`` (device work synchronised),
and the normwise backward error ``|b - A x|_inf / (|A|_inf |x|_inf + |b|_inf)`` of its solution, computed on
the host the same way for all (a solution above ~1e-12 is not usable by the Newton iteration). A device
solve that takes longer than ``--limit`` seconds is abandoned and reported. Nothing is asserted: it is the
measurement a choice of a device-side factorisation would rest on.
"""

from __future__ import annotations

import argparse
import pathlib
import signal
import statistics
import tempfile
import time

import numpy as np
import scipy.sparse as sp

DEFAULT_TANGENTS = pathlib.Path(tempfile.gettempdir()) / "jaxnet-tangents"


class TooLong(Exception):
    pass


def _alarm(*_):
    raise TooLong()


def backward_error(a, x, b):
    r = b - a @ x
    scale = abs(a).sum(axis=1).max() * np.abs(x).max() + np.abs(b).max()
    return float(np.abs(r).max() / scale) if scale > 0 else float("nan")


def timed(call, repeats):
    """(result, first call's time, median of ``repeats`` more) (s)."""
    t = time.perf_counter()
    out = call()
    first = time.perf_counter() - t
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        out = call()
        times.append(time.perf_counter() - t)
    return out, first, statistics.median(times) if times else float("nan")


def host(data, indices, indptr, b):
    from jaxnet import linalg

    solver = linalg.direct_solver(indptr, indices)
    name = type(solver).__name__
    return f"host ({name})", lambda: solver.solve(data, b)[0]


def jax_spsolve(data, indices, indptr, b):
    import jax
    import jax.numpy as jnp
    from jax.experimental.sparse.linalg import spsolve

    args = [jnp.asarray(v) for v in (data, indices, indptr, b)]
    return f"jax spsolve ({jax.default_backend()})", lambda: np.asarray(
        spsolve(*args, tol=0.0, reorder=1).block_until_ready())


def cupy_spsolve(data, indices, indptr, b):
    import cupy
    import cupyx.scipy.sparse as csp
    import cupyx.scipy.sparse.linalg as cspl

    n = indptr.shape[0] - 1
    a = csp.csr_matrix((cupy.asarray(data), cupy.asarray(indices), cupy.asarray(indptr)), shape=(n, n))
    rhs = cupy.asarray(b)

    def call():
        x = cspl.spsolve(a, rhs)
        cupy.cuda.Device().synchronize()
        return cupy.asnumpy(x)

    return "cupy spsolve", call


SOLVERS = (host, jax_spsolve, cupy_spsolve)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tangents", type=pathlib.Path, default=DEFAULT_TANGENTS)
    parser.add_argument("--matrices", nargs="*", help="tangent names (files NAME.npz); default all")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--limit", type=float, default=120.0, help="seconds a device solve may take")
    args = parser.parse_args(argv)
    import jaxnet  # noqa: F401  (float64 on)

    paths = sorted(args.tangents.glob("*.npz"), key=lambda p: np.load(p)["indptr"].shape[0])
    if args.matrices:
        paths = [p for p in paths if p.stem in args.matrices]
    if not paths:
        raise SystemExit(f"no tangents in {args.tangents}: run validation/bench_factorisation.py first")
    signal.signal(signal.SIGALRM, _alarm)
    print("| tangent | n | nnz | solver | first s | median s | backward error | note |")
    print("|---|---|---|---|---|---|---|---|")
    for path in paths:
        z = np.load(path)
        data, indices, indptr, b = z["data"], z["indices"], z["indptr"], z["rhs"]
        n = indptr.shape[0] - 1
        a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
        for make in SOLVERS:
            label, note = make.__name__, ""
            try:
                label, call = make(data, indices, indptr, b)
                signal.alarm(int(np.ceil(args.limit)))
                x, first, median = timed(call, args.repeats)
                signal.alarm(0)
                cells = f"{first:.4g} | {median:.4g} | {backward_error(a, x, b):.1e}"
            except TooLong:
                cells, note = "- | - | -", f"over {args.limit:g} s"
            except Exception as error:  # noqa: BLE001 -- a solver that cannot run here is reported, not fatal
                signal.alarm(0)
                cells, note = "- | - | -", f"{type(error).__name__}: {str(error).splitlines()[0][:100]}"
            print(f"| {path.stem} | {n} | {a.nnz} | {label} | {cells} | {note} |", flush=True)


if __name__ == "__main__":
    main()
