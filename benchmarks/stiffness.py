"""Closed-form against autodiff stiffness: compile time, run time and memory, per term and in total.

    python benchmarks/stiffness.py [--elements 1000 10000 100000] [--repeats 7] [--json FILE]

For each size the built-in cod-end (:func:`jaxnet.scenes.codend.codend`) is meshed to about that many
triangles, with a twine that switches on every term the book gives a stiffness for: twine tension (with a
compression stiffness), mesh opening, knot contact, out-of-plane bending (hinges), twine drag, and the
catch pressure; its cod line adds bar tension and drag. At its start shape, slightly perturbed (so that
no element sits on a kink), for every term with a closed form (declared by the term, :mod:`jaxnet.closed_form`):

* **element**: the (3k, 3k) element matrices of all the term's elements, vmapped and jitted, by the closed
  form and by autodiff (``jax.jacfwd`` of ``jax.grad`` for energies, ``jax.jacfwd`` for forces: the
  solver's path). For energies also the other ways autodiff can form a Hessian: ``jax.hessian``
  (forward over reverse), ``jax.jacrev`` of ``jax.grad`` (reverse over reverse), to show whether the
  mode matters;
* **assembled**: ``assemble.tangent`` with that term alone, both paths: the CSR entries of the global
  tangent (gather, element matrices, scatter into the slots; no dense matrix);
* and the assembled tangent of all the terms together.

Per case: compile time (trace + lower + XLA compile of a fresh function, s), run time (median of
``--repeats`` calls, ms), temporary memory of the compiled program (XLA's ``memory_analysis``, MB), and
the ratio autodiff / closed form. Nothing is asserted; the machine is whatever runs this (its load
average is printed): read ratios measured side by side in one run, not absolute figures.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time

import jax
import jax.numpy as jnp
import numpy as np

import jaxnet  # noqa: F401  (float64)
from jaxnet import model as model_lib
from jaxnet.model import assemble
from jaxnet.net import Twine
from jaxnet.scenes.codend import codend


def scene_of_size(triangles):
    """The cod-end with every stiffness term on, meshed to about ``triangles`` netting elements."""
    twine = Twine(l0=0.06, ea=1e5, ea_compression=1e3, diameter=4e-3, density=1025.0, knot_size=0.01,
                  opening_stiffness=0.05, bending_stiffness=1e-4)
    # the quarter has (around/4) x along meshes, two triangles per mesh at step = one mesh diagonal
    along = max(8, int(round(np.sqrt(triangles / 2.0))))
    around = 4 * max(2, int(round(along / 2.0)))
    scale = 1.0
    for _ in range(8):
        scene = codend(meshes_around=around, meshes_along=along, step=0.12 * scale, twine=twine).scene
        n = scene.netting.vertices.shape[0]
        if 0.7 * triangles <= n <= 1.4 * triangles:
            break
        scale *= np.sqrt(n / triangles)
    return scene


def timed(fn, args, repeats):
    """(compile s, median run ms, temporary MB) of a fresh jitted ``fn`` on ``args``."""
    t0 = time.perf_counter()
    compiled = jax.jit(fn).lower(*args).compile()
    compile_s = time.perf_counter() - t0
    jax.block_until_ready(compiled(*args))
    runs = []
    for _ in range(repeats):
        t = time.perf_counter()
        jax.block_until_ready(compiled(*args))
        runs.append(time.perf_counter() - t)
    memory = compiled.memory_analysis()
    temp = memory.temp_size_in_bytes / 1e6 if memory is not None else float("nan")
    return compile_s, 1e3 * statistics.median(runs), temp


def element_functions(term, scene, state, all_modes=True):
    """name -> function of (xe (E, k, 3), rows) giving the (E, 3k, 3k) element matrices of one term
    (``all_modes``: also the Hessians by ``jax.hessian`` and ``jax.jacrev(jax.grad)``)."""
    env, family = scene.environment, term.term.family
    k = assemble.connectivity(scene, family).shape[1]
    out = {}
    if term.term.kind == "energy":
        flat = lambda v, p: term.energy(v.reshape(k, 3), p, env)  # noqa: E731
        modes = {"jacfwd(grad)": lambda f: jax.jacfwd(jax.grad(f)),
                 "hessian": jax.hessian,
                 "jacrev(grad)": lambda f: jax.jacrev(jax.grad(f))}
        for name, mode in (modes if all_modes else dict(list(modes.items())[:1])).items():
            out[name] = (lambda mode: lambda xe, p: jax.vmap(
                lambda v, q: mode(lambda w: flat(w, q))(v.ravel()))(xe, p))(mode)
    else:
        flat = lambda v, p: term.force(v.reshape(k, 3), p, env, state.get(term.name)).ravel()  # noqa: E731
        out["jacfwd"] = lambda xe, p: jax.vmap(lambda v, q: -jax.jacfwd(lambda w: flat(w, q))(v.ravel()))(xe, p)
    out["closed form"] = lambda xe, p: jax.vmap(lambda v, q: term.stiffness(v, q, env, state.get(term.name)))(xe, p)
    return out


def measure(triangles, repeats, all_modes=True, only=None, elements=True):
    """Rows of the tables for a cod-end of about ``triangles`` triangles, and the terms with no closed form.

    ``only``: names of the terms to time (None: all with a closed form); ``elements``: also time the element
    matrices alone (not only the assembled tangents)."""
    scene = scene_of_size(triangles)
    model = model_lib.active_terms(scene)
    rng = np.random.default_rng(0)
    x = jnp.asarray(np.asarray(scene.nodes.position) + 1e-4 * rng.normal(size=scene.nodes.position.shape))
    state = assemble.states(x, scene, model)
    rows = []
    covered = [t for t in model if t.has_closed_form() and (only is None or t.name in only)]
    for term in covered:
        family = term.term.family
        conn = assemble.connectivity(scene, family)
        xe, fam = x[conn], getattr(scene, family)
        fns = element_functions(term, scene, state, all_modes) if elements else {}
        for name, fn in fns.items():
            rows.append(dict(elements=int(scene.netting.vertices.shape[0]), term=term.name, level="element",
                             method=name, count=int(conn.shape[0]), **dict(zip(("compile_s", "run_ms", "temp_mb"),
                                                                              timed(fn, (xe, fam), repeats)))))
        only = (term,)
        pattern = assemble.build_pattern(scene, only)
        for path in assemble.STIFFNESS_PATHS:
            fn = lambda x, pattern, path=path, only=only: assemble.tangent(x, scene, only, pattern, state, 1.0, path)  # noqa: E731
            rows.append(dict(elements=int(scene.netting.vertices.shape[0]), term=term.name, level="assembled",
                             method=path, count=int(conn.shape[0]), **dict(zip(("compile_s", "run_ms", "temp_mb"),
                                                                               timed(fn, (x, pattern), repeats)))))
    pattern = assemble.build_pattern(scene, model)
    for path in assemble.STIFFNESS_PATHS:
        fn = lambda x, pattern, path=path: assemble.tangent(x, scene, model, pattern, state, 1.0, path)  # noqa: E731
        rows.append(dict(elements=int(scene.netting.vertices.shape[0]), term="all terms", level="assembled",
                         method=path, count=int(scene.netting.vertices.shape[0]),
                         **dict(zip(("compile_s", "run_ms", "temp_mb"), timed(fn, (x, pattern), repeats)))))
    uncovered = [t.name for t in model if t.term.kind in ("energy", "force") and not t.has_closed_form()]
    return rows, uncovered


def table(rows):
    """Markdown table: per (size, term, level), every method with its ratio to the closed form."""
    lines = ["| triangles | term | level | method | elements | compile s | run ms | temp MB | run / closed form | compile / closed form |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    groups = {}
    for r in rows:
        groups.setdefault((r["elements"], r["term"], r["level"]), []).append(r)
    for (size, term, level), group in groups.items():
        ref = next(r for r in group if r["method"] in ("closed form", "closed_form"))
        for r in group:
            lines.append(f"| {size} | {term} | {level} | {r['method']} | {r['count']} | {r['compile_s']:.2f} | "
                         f"{r['run_ms']:.3f} | {r['temp_mb']:.1f} | {r['run_ms'] / ref['run_ms']:.2f} | "
                         f"{r['compile_s'] / ref['compile_s']:.2f} |")
    return "\n".join(lines)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--elements", type=int, nargs="+", default=[1000, 10000, 100000])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--json", default=None, help="also write the rows to this JSON file")
    args = parser.parse_args(argv)
    print(f"# stiffness cost: closed form vs autodiff ({platform.node()}, {os.cpu_count()} cores, jax {jax.__version__}, "
          f"load {os.getloadavg()[0]:.2f})\n")
    rows = []
    for n in args.elements:
        r, uncovered = measure(n, args.repeats)
        rows += r
        print(table(r), flush=True)
        print(f"\nterms of this scene without a closed form (autodiff in both paths): {uncovered or 'none'}\n")
    print(f"load average at the end: {os.getloadavg()[0]:.2f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
