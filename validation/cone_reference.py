"""A net in still water as a second-order cone program, solved by Clarabel: an independent check of jaxnet's statics.

    python validation/cone_reference.py [--steps 0.1 0.05 0.025]

Priour's twine vectors are linear in the node positions (:func:`jaxnet.geometry.twine_coefficients`: U = a·x,
V = b·x; a bar's is the difference of its ends), and the energy of a rod that carries no compression,
(EA / 2 l0) max(0, |U| - l0)², is convex in U. With weight and buoyancy (constant loads away from the surface) and
fixed coordinates (equalities), the static equilibrium of such a net is the minimum of a convex program, which a
second-order cone program states with one slack s_r per rod:

    minimise  sum_r w_r s_r² - f·x   subject to  |U_r(x)| <= l0_r + s_r   (a cone of dimension 4 per rod),

w_r = n_r EA_r / (2 l0_r), n_r the rod's number of twines (|d|/2 for each family of a diamond triangle, book eqs
4.25-4.26; 1 for a bar). At the minimum s_r = max(0, |U_r| - l0_r), so its value is jaxnet's potential energy
(:func:`jaxnet.model.assemble.potential`) less the work of the loads on the fixed coordinates, and the cone's multiplier
is the rod's tension. Interior-point methods solve such programs in tens of iterations nearly independently of
their size (Lobo, Vandenberghe, Boyd and Lebret, "Applications of second-order cone programming", Linear Algebra
Appl. 284, 1998). Clarabel (Goulart and Chen, 2024) is one, used here through its own Python interface.

Only what is convex is written: the tension of tension-only twines and bars, and constant loads. A scene with any
other active term (drag, mesh opening, knots, bending, a catch, the sea bed, a free surface) or with a compression
stiffness is refused by name. Where the equilibria form a flat set (slack meshes that may lie anywhere in a
range), the two solvers may land at different points of it: both balance, and their potential energies (the
program's minimum) agree.

The script compares jaxnet's Newton with Clarabel on a wall of netting hanging in still water from a headline,
with a lead sinker along its foot (40 x 40 meshes, tension-only twines), meshed at three steps: iterations and
times of each, the largest out-of-balance force of each answer by jaxnet's own residual, the difference of their
energies and of their positions.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

#: the terms a cone program holds: the tension of rods without compression stiffness, and constant loads
CONVEX_ENERGIES = ("netting_tension", "bar_tension")


@dataclasses.dataclass(frozen=True)
class ConeSolution:
    """Clarabel's answer. x: (N, 3) node positions (m), the fixed coordinates as the scene holds them;
    tension: (R,) tension of each rod (N, the cones' multipliers), the netting's U then V twine of each triangle,
    then the bars; potential: the program's minimum plus the loads' work on the fixed coordinates (J): jaxnet's
    potential energy at x; iterations, status (Clarabel's words), wall_s (s)."""

    x: np.ndarray
    tension: np.ndarray
    potential: float
    iterations: int
    status: str
    wall_s: float


def rods(scene):
    """The rods of ``scene`` as (coefficients (R, k), nodes (R, k), rest length (R,), weight w (R,)): the twine
    vector of rod r is sum_j coefficients[r, j] x[nodes[r, j]] (k = 3 for a twine of a triangle, padded for a
    bar, whose ends take -1 and +1)."""
    import jax

    from jaxnet import geometry

    parts = []
    net, bars = scene.netting, scene.bars
    if net is not None:
        uv = np.asarray(net.uv, dtype=float)
        a, b, d = (np.asarray(v) for v in jax.vmap(geometry.twine_coefficients)(uv))
        vertices = np.asarray(net.vertices)
        count = np.abs(d) / 2.0
        stiff = count * np.asarray(net.ea_traction, dtype=float) / (2.0 * np.asarray(net.l0, dtype=float))
        for coefficients in (a, b):
            parts.append((coefficients, vertices, np.asarray(net.l0, dtype=float), stiff))
    if bars is not None:
        ends = np.asarray(bars.ends)
        rest = np.asarray(bars.rest_length, dtype=float)
        coefficients = np.tile([-1.0, 1.0, 0.0], (len(ends), 1))
        nodes = np.column_stack([ends, ends[:, 0]])
        parts.append((coefficients, nodes, rest, np.asarray(bars.ea_traction, dtype=float) / (2.0 * rest)))
    return tuple(np.concatenate([p[i] for p in parts]) for i in range(4))


def check_convex(scene, model):
    """Refuse (ValueError naming it) a term or a material that the cone program cannot hold."""
    for t in model:
        if t.term.kind != "load" and t.name not in CONVEX_ENERGIES:
            raise ValueError(f"the cone program holds the twines' and bars' tension and constant loads only: "
                             f"the scene's term '{t.name}' is not one of them")
    for family in ("netting", "bars"):
        rows = getattr(scene, family)
        if rows is not None and np.any(np.asarray(rows.ea_compression) != 0.0):
            raise ValueError(f"the cone program holds rods without compression stiffness: some of the scene's "
                             f"{family} have ea_compression > 0")


def solve_cone(scene, tol=1e-9, max_iter=200) -> ConeSolution:
    """The equilibrium of ``scene`` (a net in still water, tension-only) as Clarabel's minimum of the cone program
    of the module docstring; ``tol``: Clarabel's gap and feasibility tolerances."""
    import clarabel
    import scipy.sparse as sp

    from jaxnet import model as model_lib
    from jaxnet.model import assemble

    model = model_lib.active_terms(scene)
    check_convex(scene, model)
    load = np.asarray(assemble.loads(scene, model), dtype=float).ravel()
    x0 = np.asarray(scene.nodes.position, dtype=float).ravel()
    fixed = np.asarray(scene.nodes.fixed, dtype=bool).ravel()
    free = np.flatnonzero(~fixed)
    column = np.full(x0.size, -1)
    column[free] = np.arange(free.size)
    coefficients, nodes, rest, stiff = rods(scene)
    n_rods, n_free = len(rest), free.size
    # rows of rod r: 4 r (l0 + s_r), 4 r + 1 + c (component c of its twine vector); b - A z in the cone
    rows, cols, vals = [], [], []
    b = np.zeros(4 * n_rods)
    b[0::4] = rest
    rows.append(4 * np.arange(n_rods))
    cols.append(n_free + np.arange(n_rods))
    vals.append(-np.ones(n_rods))
    for j in range(coefficients.shape[1]):
        for c in range(3):
            dof = 3 * nodes[:, j] + c
            row = 4 * np.arange(n_rods) + 1 + c
            held = column[dof] < 0
            np.add.at(b, row[held], coefficients[held, j] * x0[dof[held]])
            keep = ~held & (coefficients[:, j] != 0.0)
            rows.append(row[keep])
            cols.append(column[dof[keep]])
            vals.append(-coefficients[keep, j])
    A = sp.csc_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                      shape=(4 * n_rods, n_free + n_rods))
    P = sp.csc_matrix((2.0 * stiff, (n_free + np.arange(n_rods), n_free + np.arange(n_rods))),
                      shape=(n_free + n_rods,) * 2)
    q = np.concatenate([-load[free], np.zeros(n_rods)])
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    settings.max_iter = max_iter
    settings.tol_gap_abs = settings.tol_gap_rel = settings.tol_feas = tol
    solver = clarabel.DefaultSolver(P, q, A, b, [clarabel.SecondOrderConeT(4)] * n_rods, settings)
    t = time.perf_counter()
    answer = solver.solve()
    wall = time.perf_counter() - t
    z = np.asarray(answer.x)
    x = x0.copy()
    x[free] = z[:n_free]
    multipliers = np.asarray(answer.z).reshape(n_rods, 4)
    return ConeSolution(x=x.reshape(-1, 3), tension=multipliers[:, 0],
                        potential=float(answer.obj_val) - float(load[fixed] @ x0[fixed]),
                        iterations=int(answer.iterations), status=str(answer.status), wall_s=wall)


def balance(scene, x):
    """jaxnet's largest out-of-balance force on a free coordinate (N) and its potential energy (J) at x."""
    import jax.numpy as jnp

    from jaxnet import model as model_lib
    from jaxnet.model import assemble

    model = model_lib.active_terms(scene)
    load = assemble.loads(scene, model)
    x = jnp.asarray(x)
    force = np.asarray(assemble.nodal_force(x, scene, model, load))
    free = ~np.asarray(scene.nodes.fixed, dtype=bool)
    return float(np.abs(force[free]).max()), float(assemble.potential(x, scene, model, load))


def wall_in_still_water(step, meshes=40, l0=0.025, sinker_kg=2.0):
    """A wall of ``meshes`` x ``meshes`` square meshes (mesh side l0, m; tension-only polyamide twine) hanging in
    still water from a headline held at both ends, ``sinker_kg`` of lead spread along its foot; meshed at ``step``
    (m)."""
    import jaxnet as jn
    from jaxnet.net import Net, Rope, Twine

    net = Net(jn.Environment(current_speed=0.0))
    w = meshes * l0 * np.sqrt(2.0)
    wall = net.panel("wall", [(0, 0, -w, 0, 0), (0, w, -w, meshes, -meshes), (0, w, 0, 2 * meshes, 0),
                              (0, 0, 0, meshes, meshes)], Twine(l0=l0, ea=2000.0, diameter=1.5e-3), step=step)
    net.cable("headline", along=wall.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    net.sinker(wall.side(0), mass=sinker_kg)
    net.fix(wall.corner(2))
    net.fix(wall.corner(3))
    return net.build()


def main():
    import jaxnet as jn

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=float, nargs="*", default=[0.1, 0.05, 0.025])
    parser.add_argument("--max-iter", type=int, default=3000, help="jaxnet's Newton iterations at most")
    parser.add_argument("--methods", nargs="*", default=["primal-dual", "damped"],
                        help="jaxnet's static methods to run (default both, side by side)")
    args = parser.parse_args()
    header = (f"{'step m':>7s} {'nodes':>6s} | {'jaxnet method':>13s} {'its':>5s} {'wall s':>7s} {'residual N':>10s} | "
              f"{'Clarabel its':>12s} {'wall s':>7s} {'residual N':>10s} {'status':>8s} | {'energy diff J':>13s} "
              f"{'max |dx| m':>10s}")
    print("A wall in still water (40 x 40 meshes, tension-only twines, 2 kg of lead along its foot): jaxnet's "
          "static methods against Clarabel\n")
    print(header)
    print("-" * len(header))
    for step in args.steps:
        scene = wall_in_still_water(step)
        cone = solve_cone(scene)
        cone_residual, cone_energy = balance(scene, cone.x)
        for method in args.methods:
            t = time.perf_counter()
            eq = jn.solve_static(scene, max_iter=args.max_iter, method=method, throw=False)
            ours_wall = time.perf_counter() - t
            ours_residual, ours_energy = balance(scene, eq.x)
            print(f"{step:7.3f} {scene.n_nodes:6d} | {method:>13s} {int(eq.iterations):5d} {ours_wall:7.2f} "
                  f"{ours_residual:10.2e} | {cone.iterations:12d} {cone.wall_s:7.2f} {cone_residual:10.2e} "
                  f"{cone.status:>8s} | {ours_energy - cone_energy:13.2e} {np.abs(np.asarray(eq.x) - cone.x).max():10.2e}")
    print("\njaxnet's wall time includes its compilation; residual: the largest out-of-balance force on a free "
          "coordinate, by jaxnet's residual at each answer; energy diff: jaxnet's potential energy at its answer "
          "less at Clarabel's.")


if __name__ == "__main__":
    main()
