"""Where the static solver's iterations go: the path from the drawn shape, or the neighbourhood of the answer?

    python validation/newton_locality.py [--currents 0 0.5] [--kicks 1e-4 1e-3 1e-2] [--step 0.5] [--seed 0]

The built-in cage (:func:`jaxnet.scenes.fish_cage`, 1161 nodes at ``--step`` 0.5 m) takes about a hundred
Newton iterations from its drawn cylinder. Newton converges quadratically near a regular root, so if the
iterations were spent on the way from the drawn shape (large rotations, a long mechanism path), a start near the
answer would need a handful. This script solves each case from its drawn shape to 1e-8 N, then again from
that equilibrium with every free node moved by a random displacement of ``--kicks`` metres (normal, per
coordinate), to jaxnet's tolerance (1e-3 N), and prints the iterations and how far the second answer lies from
the first. It does the same for

* the physical twine (no compression stiffness) and a linear one (EA_c = EA: no slack kink);
* nested iteration: the cage solved at twice the meshing step, its equilibrium carried to the fine mesh by
  the twine coordinates of each panel (barycentric in the coarse triangle holding the fine node's (U, V);
  along each cable by the node's place in it), and the fine mesh solved from there.

A start a millimetre from the answer taking as many iterations as the drawn start says that the cost is local:
nearly singular directions (slack bottom netting, free mesh opening) where the quadratic model holds only very
close to the answer, not the globalisation's path. Nothing is asserted.

Units: m, N.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

#: the tolerances (N): the reference equilibrium's, and the re-solves' (jaxnet's)
TOL_REFERENCE, TOL_N = 1e-8, 1e-3


def cage(step, current, linear):
    """The built-in cage, its twines physical (its own) or ``linear`` (compression stiffness = EA)."""
    import dataclasses

    from jaxnet.scenes import fish_cage
    from jaxnet.scenes.cage import netting_twine

    twine = netting_twine()
    return fish_cage(step=step, current=current,
                     twine=dataclasses.replace(twine, ea_compression=twine.ea) if linear else None)


def prolongation(coarse, x_coarse, fine):
    """(N_fine, 3) start positions of the ``fine`` case from the equilibrium ``x_coarse`` of the ``coarse`` one
    (both built from a Net of the same panels and cables): each fine panel node at the barycentric interpolation
    of the coarse triangle of its panel that holds its twine coordinates (the nearest where none holds them),
    each node of a cable only at its fraction of the cable's nodes."""
    from scipy.spatial import cKDTree

    lc, lf = coarse.net.layout, fine.net.layout
    n = fine.scene.n_nodes
    total, count = np.zeros((n, 3)), np.zeros(n)
    for name, mesh in lf.meshes.items():
        coarse_mesh, nodes_c, nodes_f = lc.meshes[name], lc.panel_nodes[name], lf.panel_nodes[name]
        tri, p, q = coarse_mesh.triangles, coarse_mesh.uv, mesh.uv
        a, b, c = p[tri[:, 0]], p[tri[:, 1]], p[tri[:, 2]]
        det = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (c[:, 0] - a[:, 0]) * (b[:, 1] - a[:, 1])
        _, near = cKDTree((a + b + c) / 3.0).query(q, k=min(12, len(tri)))
        best, weights, worst = np.zeros(len(q), int), np.zeros((len(q), 3)), np.full(len(q), -np.inf)
        for t in near.T:
            l1 = ((q[:, 0] - a[t, 0]) * (c[t, 1] - a[t, 1]) - (c[t, 0] - a[t, 0]) * (q[:, 1] - a[t, 1])) / det[t]
            l2 = ((b[t, 0] - a[t, 0]) * (q[:, 1] - a[t, 1]) - (q[:, 0] - a[t, 0]) * (b[t, 1] - a[t, 1])) / det[t]
            w = np.stack([1.0 - l1 - l2, l1, l2], axis=1)
            inside = w.min(axis=1)
            better = inside > worst
            worst[better], best[better], weights[better] = inside[better], t[better], w[better]
        np.add.at(total, nodes_f, np.einsum("qk,qkd->qd", weights, x_coarse[nodes_c[tri[best]]]))
        np.add.at(count, nodes_f, 1.0)
    x = np.asarray(fine.scene.nodes.position, dtype=float).copy()
    held = count > 0
    x[held] = total[held] / count[held, None]
    for name, nodes_f in lf.cable_nodes.items():
        nodes_c = lc.cable_nodes[name]
        along_f, along_c = np.linspace(0.0, 1.0, len(nodes_f)), np.linspace(0.0, 1.0, len(nodes_c))
        alone = ~held[nodes_f]
        for d in range(3):
            x[nodes_f[alone], d] = np.interp(along_f, along_c, x_coarse[nodes_c, d])[alone]
    return x


def solve(case, x0=None, tol=TOL_N):
    import jaxnet as jn

    t = time.perf_counter()
    eq = jn.solve_static(case, x0=x0, throw=False, tol=tol, max_iter=1000)
    return eq, time.perf_counter() - t


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--currents", type=float, nargs="*", default=[0.0, 0.5], help="current speeds (m/s)")
    parser.add_argument("--kicks", type=float, nargs="*", default=[1e-4, 1e-3, 1e-2], help="random moves (m)")
    parser.add_argument("--step", type=float, default=0.5, help="the cage's meshing step (m)")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    print(f"fish cage, meshing step {args.step:g} m; iterations to {TOL_N:g} N from the drawn shape, and from its "
          f"equilibrium ({TOL_REFERENCE:g} N) moved at random\n")
    print("| current m/s | twine | start | iterations | converged | distance to the first answer m | s |")
    print("|---|---|---|---|---|---|---|")
    for current in args.currents:
        for linear in (False, True):
            twine = "linear, EA_c = EA" if linear else "physical, EA_c = 0"
            case = cage(args.step, current, linear)
            drawn, seconds = solve(case)
            print(f"| {current:g} | {twine} | drawn | {int(drawn.iterations)} | {bool(drawn.converged)} | | "
                  f"{seconds:.1f} |", flush=True)
            reference, _ = solve(case, x0=np.asarray(drawn.x), tol=TOL_REFERENCE)
            x = np.asarray(reference.x)
            free = ~np.asarray(case.scene.nodes.fixed)
            for kick in args.kicks:
                eq, seconds = solve(case, x0=x + kick * rng.standard_normal(x.shape) * free)
                print(f"| {current:g} | {twine} | equilibrium + {kick:g} m | {int(eq.iterations)} | "
                      f"{bool(eq.converged)} | {np.abs(np.asarray(eq.x) - x).max():.2g} | {seconds:.1f} |", flush=True)
        coarse = cage(2.0 * args.step, current, False)
        coarse_eq, coarse_s = solve(coarse)
        fine = cage(args.step, current, False)
        eq, seconds = solve(fine, x0=prolongation(coarse, np.asarray(coarse_eq.x), fine))
        print(f"| {current:g} | physical, EA_c = 0 | the cage at step {2.0 * args.step:g} m solved "
              f"({int(coarse_eq.iterations)} it, {coarse_s:.1f} s), carried over | {int(eq.iterations)} | "
              f"{bool(eq.converged)} | | {seconds:.1f} |", flush=True)


if __name__ == "__main__":
    main()
