"""Sparse direct solves on an accelerator against the host's, on the static solver's own tangents.

    python benchmarks/device_factorisation.py [--tangents DIR] [--matrices NAME ...] [--solvers NAME ...]
                                                    [--repeats 3] [--target 4] [--limit 120]
    python benchmarks/device_factorisation.py --export-iterates DIR [--tangents DIR] [--matrices ...]
    python benchmarks/device_factorisation.py --iterates DIR [--corpus DIR] [--tangents DIR] [--build-only]

The tangents are those ``benchmarks/factorisation.py`` computes and keeps (its ``--tangents`` directory,
by default ``jaxnet-tangents`` in the system's temporary directory): run it first, on any machine. The
matrices of 10^5 nodes weigh 60-75 MB each; their Newton iterates (the free coordinates, a few MB) rebuild
them exactly: ``--export-iterates DIR`` writes the iterates of the kept tangents to ``DIR``, and
``--iterates DIR`` on the accelerator's machine rebuilds each tangent there with jaxnet
(:func:`factorisation.tangent_at`, on JAX's default device: an assembly on the accelerator) into
``--tangents`` before measuring (``--build-only``: only that). The trawl's tangents read FEMNET's case from
``--corpus`` (default: ``../shared/femnet-corpus``). On each tangent, side by side:

* ``host``: the factorisation the static solver makes on the host (:class:`jaxnet.linalg.PardisoSolver` where
  MKL is installed, else :class:`jaxnet.linalg.HostSolver`, SuperLU), its first factorisation and solve
  (analysis included) and the median of ``--repeats`` more;
* ``jax spsolve``: :func:`jax.experimental.sparse.linalg.spsolve` on JAX's default device (cuSOLVER's sparse
  QR with reordering on a CUDA device; on the CPU, scipy's ``spsolve`` through a host callback);
* ``cupy spsolve``: :func:`cupyx.scipy.sparse.linalg.spsolve` where CuPy imports (cuSOLVER on the GPU);
* ``cuDSS``: NVIDIA's sparse direct solver (:class:`nvmath.sparse.advanced.DirectSolver` of
  ``nvmath-python`` on CuPy arrays, the ``nvidia-cudss`` library), general LU with its defaults: analysis
  (``plan``) once, then factorisation and solve (the analysis time is in the note), as jaxnet's Newton uses it
  on a GPU (:class:`jaxnet.linalg.CudssSolver`, which also checks and refines each solution on the host).

For each: the time of the first call (analysis, factorisation and solve) and the median of the next
``--repeats`` (analysis reused where the solver separates it; fewer repeats where they would take over
``--target`` seconds, one at least; device work synchronised),
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


def timed(call, repeats, target=float("inf")):
    """(result, first call's time, median of up to ``repeats`` more) (s): fewer where they would take over
    ``target`` seconds, one at least."""
    t = time.perf_counter()
    out = call()
    first = time.perf_counter() - t
    times = []
    for _ in range(max(1, min(repeats, int(target / max(first, 1e-9))))):
        t = time.perf_counter()
        out = call()
        times.append(time.perf_counter() - t)
    return out, first, statistics.median(times) if times else float("nan")


def host(data, indices, indptr, b):
    from jaxnet import linalg
    from jaxnet.linalg import pardiso

    solver = (linalg.PardisoSolver if pardiso.available() else linalg.HostSolver)(indptr, indices)
    name = type(solver).__name__
    return f"host ({name})", lambda: solver.solve(data, b)[0]


def jax_spsolve(data, indices, indptr, b):
    import jax
    import jax.numpy as jnp
    from jax.experimental.sparse.linalg import spsolve

    # cuSOLVER's sparse QR takes 32-bit indices (with 64-bit ones jax 0.11.2 on CUDA refuses the call:
    # "Failed to decode all FFI handler operands")
    args = [jnp.asarray(v) for v in (data, indices.astype(np.int32), indptr.astype(np.int32), b)]
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


def cudss(data, indices, indptr, b):
    import cupy
    import cupyx.scipy.sparse as csp
    from nvmath.sparse.advanced import DirectSolver

    n = indptr.shape[0] - 1
    a = csp.csr_matrix((cupy.asarray(data), cupy.asarray(indices.astype(np.int32)),
                        cupy.asarray(indptr.astype(np.int32))), shape=(n, n))
    rhs = cupy.asarray(b)
    solver = DirectSolver(a, rhs)
    state = {}

    def call():
        if not state:  # the analysis, once per pattern (as the Newton would keep it)
            t = time.perf_counter()
            solver.plan()
            cupy.cuda.Device().synchronize()
            state["plan_s"] = time.perf_counter() - t
        solver.factorize()
        x = solver.solve()
        cupy.cuda.Device().synchronize()
        return cupy.asnumpy(x)

    call.note = lambda: f"analysis {state.get('plan_s', float('nan')):.3g} s"
    return "cuDSS (nvmath)", call


SOLVERS = (host, jax_spsolve, cupy_spsolve, cudss)


def export_iterates(tangents, names, out):
    """Write the Newton iterate ``x`` of each kept tangent to ``out``/NAME.npz (what rebuilds it)."""
    out.mkdir(parents=True, exist_ok=True)
    for path in sorted(tangents.glob("*.npz")):
        if names and path.stem not in names:
            continue
        z = np.load(path)
        if "x" not in z:
            raise SystemExit(f"{path} holds no iterate: recompute it with factorisation.py --regenerate")
        np.savez(out / path.name, x=z["x"])
        print(f"{path.stem}: {z['x'].size} unknowns -> {out / path.name}")


def build_from_iterates(iterates, corpus, tangents, names):
    """Rebuild each tangent of ``iterates`` (files NAME.npz holding ``x``) into ``tangents``/NAME.npz."""
    import jax

    import factorisation

    factorisation.TRAWL = corpus / factorisation.TRAWL.relative_to(factorisation.ROOT.parent / "shared"
                                                                     / "femnet-corpus")
    tangents.mkdir(parents=True, exist_ok=True)
    for path in sorted(iterates.glob("*.npz")):
        if names and path.stem not in names:
            continue
        _, kind, arg, _, mu = factorisation.MATRICES[path.stem]
        t = time.perf_counter()
        case = factorisation.make_case(kind, arg)
        tangent = factorisation.tangent_at(case, np.load(path)["x"], mu)
        np.savez(tangents / path.name, **tangent)
        print(f"{path.stem}: {case.scene.n_nodes} nodes, tangent rebuilt on {jax.default_backend()} in "
              f"{time.perf_counter() - t:.1f} s", flush=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tangents", type=pathlib.Path, default=DEFAULT_TANGENTS)
    parser.add_argument("--matrices", nargs="*", help="tangent names (files NAME.npz); default all")
    parser.add_argument("--solvers", nargs="*", choices=[f.__name__ for f in SOLVERS],
                        help="default: all")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--target", type=float, default=4.0,
                        help="seconds of repeated calls per pair: fewer repeats (one at least) beyond")
    parser.add_argument("--limit", type=float, default=120.0, help="seconds a device solve may take")
    parser.add_argument("--export-iterates", type=pathlib.Path, metavar="DIR",
                        help="write the kept tangents' iterates to DIR and stop")
    parser.add_argument("--iterates", type=pathlib.Path, metavar="DIR",
                        help="rebuild the tangents from the iterates in DIR first")
    parser.add_argument("--corpus", type=pathlib.Path,
                        default=pathlib.Path(__file__).resolve().parents[2] / "shared" / "femnet-corpus")
    parser.add_argument("--build-only", action="store_true", help="with --iterates: rebuild, then stop")
    args = parser.parse_args(argv)
    import jaxnet  # noqa: F401  (float64 on)

    if args.export_iterates:
        export_iterates(args.tangents, args.matrices, args.export_iterates)
        return
    if args.iterates:
        build_from_iterates(args.iterates, args.corpus, args.tangents, args.matrices)
        if args.build_only:
            return
    solvers = [f for f in SOLVERS if not args.solvers or f.__name__ in args.solvers]
    paths = sorted(args.tangents.glob("*.npz"), key=lambda p: np.load(p)["indptr"].shape[0])
    if args.matrices:
        paths = [p for p in paths if p.stem in args.matrices]
    if not paths:
        raise SystemExit(f"no tangents in {args.tangents}: run benchmarks/factorisation.py first")
    signal.signal(signal.SIGALRM, _alarm)
    print("| tangent | n | nnz | solver | first s | median s | backward error | note |")
    print("|---|---|---|---|---|---|---|---|")
    for path in paths:
        z = np.load(path)
        data, indices, indptr, b = z["data"], z["indices"], z["indptr"], z["rhs"]
        n = indptr.shape[0] - 1
        a = sp.csr_matrix((data, indices, indptr), shape=(n, n))
        for make in solvers:
            label, note = make.__name__, ""
            try:
                label, call = make(data, indices, indptr, b)
                signal.alarm(int(np.ceil(args.limit)))
                x, first, median = timed(call, args.repeats, args.target)
                signal.alarm(0)
                cells = f"{first:.4g} | {median:.4g} | {backward_error(a, x, b):.1e}"
                note = call.note() if hasattr(call, "note") else ""
            except TooLong:
                cells, note = "- | - | -", f"over {args.limit:g} s"
            except Exception as error:  # noqa: BLE001 -- a solver that cannot run here is reported, not fatal
                signal.alarm(0)
                cells, note = "- | - | -", f"{type(error).__name__}: {str(error).splitlines()[0][:100]}"
            print(f"| {path.stem} | {n} | {a.nnz} | {label} | {cells} | {note} |", flush=True)


if __name__ == "__main__":
    main()
