"""How many Newton steps an interior method on the tension form takes, with the rods' unknowns eliminated rod by
rod so that each step's linear system is the node-sparse one jaxnet factorises today: the question a solver of
this kind (issue 45) must answer before it is built into jaxnet's statics.

    python validation/interior_point.py [--steps 0.1 0.05 0.025] [--method primal-dual|barrier] [--sigma S]
                                        [--shrink 0.1] [--verbose]

The net is the cone program of :mod:`cone_reference` (tension-only twines and bars, constant loads, still water):
minimise sum_r w_r s_r² - f·x subject to |U_r(x)| <= l0_r + s_r. Two methods, each compared with Clarabel's answer
(:func:`cone_reference.solve_cone`) by jaxnet's own residual and potential energy:

* ``primal-dual`` (:func:`primal_dual_solve`): each rod's tension and gap are unknowns, their product relaxed to
  mu (Mehrotra's predictor-corrector, or a fixed fraction ``--sigma`` of the mean product); the Newton step's
  rod unknowns are eliminated into today's tangent with an effective axial stiffness.
* ``barrier`` (:func:`barrier_solve`): the primal log-barrier path following. Each cone gets the barrier
  -mu log((l0_r + s_r)² - |U_r|²) (its degree is 2), and for a decreasing sequence of mu the barrier problem is
  minimised by Newton's method (Boyd and Vandenberghe, Convex Optimization, 2004, 11.3): each step eliminates the
  rod's stretch s_r from its own 4 x 4 block (a Schur complement on its 1 x 1 s-block), which leaves a 3 x 3
  stiffness on U_r, assembled on its nodes as a twine's stiffness is. A step is cut to stay inside every cone
  (fraction to the boundary, 0.99) and backtracked on the barrier objective (Armijo); mu is multiplied by
  ``--shrink`` once the Newton decrement of the barrier problem is below mu / 4, from mu0 = the largest nodal
  load x the mean rest length; the run stops when the gap 2 m mu (m cones) is below 1e-10 J and the largest
  out-of-balance force is below 1e-6 N.

validation/REPORT.md has what each measured.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

try:  # run as a script (validation/ on the path) or imported from the repository root
    from cone_reference import balance, check_convex, rods, solve_cone, wall_in_still_water
except ImportError:
    from validation.cone_reference import balance, check_convex, rods, solve_cone, wall_in_still_water


class RodSystem:
    """What both methods share: a tension-only ``scene`` in still water as its rods (:func:`cone_reference.rods`:
    coefficients c (m, k), rest lengths l0, weights w), its constant loads f (3N,) (N), start positions x0 (3N,)
    (m) and free coordinates, and the node-sparse assembly of a per-rod 3 x 3 stiffness on its twine vector U."""

    def __init__(self, scene):
        from jaxnet import assemble, model as model_lib

        model = model_lib.active_terms(scene)
        check_convex(scene, model)
        self.f = np.asarray(assemble.loads(scene, model), dtype=float).ravel()
        self.x0 = np.asarray(scene.nodes.position, dtype=float).ravel().copy()
        self.free = np.flatnonzero(~np.asarray(scene.nodes.fixed, dtype=bool).ravel())
        self.c, nodes, self.l0, self.w = rods(scene)
        self.m, k = self.c.shape
        self.dof = 3 * nodes[:, :, None] + np.arange(3)                  # (m, k, 3) global coordinates of each rod
        # the sparsity of the node stiffness: every pair of a rod's coordinates, on the free ones only
        rows = np.broadcast_to(self.dof.reshape(self.m, -1)[:, :, None], (self.m, 3 * k, 3 * k)).ravel()
        cols = np.broadcast_to(self.dof.reshape(self.m, -1)[:, None, :], (self.m, 3 * k, 3 * k)).ravel()
        position = np.full(self.x0.size, -1)
        position[self.free] = np.arange(self.free.size)
        self._keep = (position[rows] >= 0) & (position[cols] >= 0)
        self._rows, self._cols = position[rows[self._keep]], position[cols[self._keep]]

    def twine_vectors(self, x):
        """(m, 3) each rod's twine vector U at positions x (3N,) (m)."""
        return np.einsum("rj,rjc->rc", self.c, x[self.dof])

    def on_nodes(self, per_rod):
        """(3N,) the rods' (m, 3) vectors along their U taken onto their nodes (a force on U to nodal forces)."""
        out = np.zeros_like(self.x0)
        np.add.at(out, self.dof.reshape(-1), (self.c[:, :, None] * per_rod[:, None, :]).reshape(-1))
        return out

    def stiffness(self, K_U):
        """The (free, free) CSC node matrix of per-rod (m, 3, 3) stiffnesses on U."""
        size = 3 * self.c.shape[1]
        blocks = np.einsum("rj,rk,rab->rjakb", self.c, self.c, K_U).reshape(self.m, size, size)
        return sp.csc_matrix((blocks.ravel()[self._keep], (self._rows, self._cols)),
                             shape=(self.free.size, self.free.size))


def barrier_solve(scene, shrink=0.1, max_newton=500, force_tol=1e-6, verbose=False):
    """The equilibrium of a tension-only ``scene`` in still water by the barrier method of the module docstring.
    Returns (x (N, 3), Newton steps, stages of mu, wall s)."""
    t_start = time.perf_counter()
    system = RodSystem(scene)
    f, x, free, l0, w, m = system.f, system.x0, system.free, system.l0, system.w, system.m
    twine_vectors = system.twine_vectors
    U = twine_vectors(x)
    s = np.linalg.norm(U, axis=1) - l0 + 0.1 * l0                        # strictly inside every cone
    mu = float(np.abs(f).max() * l0.mean())

    def objective(x, s, mu):
        U = twine_vectors(x)
        t = l0 + s
        D = t**2 - np.einsum("rc,rc->r", U, U)
        if np.any(D <= 0.0) or np.any(t <= 0.0):
            return np.inf
        return float(np.sum(w * s**2) - f @ x - mu * np.sum(np.log(D)))

    def residual(x):
        U = twine_vectors(x)
        length = np.linalg.norm(U, axis=1)
        tension = 2.0 * w * np.maximum(length - l0, 0.0)                   # the n twines' force together (N)
        along = tension[:, None] * U / np.maximum(length, 1e-300)[:, None]
        return float(np.abs((f - system.on_nodes(along))[free]).max())

    steps = stages = 0
    scale = float(np.abs(f).sum() * l0.mean())                            # an energy scale (J)
    while steps < max_newton:
        U = twine_vectors(x)
        t = l0 + s
        D = t**2 - np.einsum("rc,rc->r", U, U)
        # the rod's barrier -log D: gradient and Hessian in (t, U)
        phi_t, phi_U = -2.0 * t / D, 2.0 * U / D[:, None]
        phi_tt = -2.0 / D + 4.0 * t**2 / D**2
        phi_tU = -4.0 * t[:, None] * U / D[:, None] ** 2
        phi_UU = 2.0 * np.eye(3) / D[:, None, None] + 4.0 * U[:, :, None] * U[:, None, :] / D[:, None, None] ** 2
        g_s, g_U = 2.0 * w * s + mu * phi_t, mu * phi_U
        H_ss, H_sU, H_UU = 2.0 * w + mu * phi_tt, mu * phi_tU, mu * phi_UU
        # eliminate s: the reduced stiffness and gradient on U
        K_U = H_UU - H_sU[:, :, None] * H_sU[:, None, :] / H_ss[:, None, None]
        g_red = g_U - H_sU * (g_s / H_ss)[:, None]
        gradient = system.on_nodes(g_red) - f
        K = system.stiffness(K_U)
        dx = np.zeros_like(x)
        dx[free] = spla.spsolve(K, -gradient[free])
        dU = twine_vectors(dx)
        ds = -(g_s + np.einsum("rc,rc->r", H_sU, dU)) / H_ss
        decrement = float(-(gradient[free] @ dx[free]) - g_s @ ds)       # the Newton decrement squared
        steps += 1
        if decrement < 0.25 * mu or decrement < 1e-14 * scale:   # near the centre: lambda² of (E / mu + barrier) < 1/4
            if 2.0 * m * mu < 1e-10 and residual(x) < force_tol:
                break
            mu *= shrink
            stages += 1
            continue
        # fraction to the boundary: the largest step that keeps every cone strictly inside, times 0.99: the
        # first positive root of (t + a ds)² - |U + a dU|², a quadratic in a, and of t + a ds
        qa = ds**2 - np.einsum("rc,rc->r", dU, dU)
        qb = 2.0 * (t * ds - np.einsum("rc,rc->r", U, dU))
        alpha_max = np.full(m, np.inf)
        linear = np.abs(qa) < 1e-300
        alpha_max[linear & (qb < 0)] = -D[linear & (qb < 0)] / qb[linear & (qb < 0)]
        disc = qb**2 - 4.0 * qa * D
        quad = ~linear & (disc >= 0.0)
        roots = np.stack([(-qb[quad] - np.sqrt(disc[quad])) / (2.0 * qa[quad]),
                          (-qb[quad] + np.sqrt(disc[quad])) / (2.0 * qa[quad])])
        roots[roots <= 0.0] = np.inf
        alpha_max[quad] = roots.min(axis=0)
        behind = ds < 0.0
        alpha_max[behind] = np.minimum(alpha_max[behind], -t[behind] / ds[behind])
        alpha = min(1.0, 0.99 * float(alpha_max.min()))
        base = objective(x, s, mu)
        while objective(x + alpha * dx, s + alpha * ds, mu) > base - 1e-4 * alpha * decrement and alpha > 1e-12:
            alpha *= 0.5
        x, s = x + alpha * dx, s + alpha * ds
        if verbose:
            print(f"  {steps:4d} mu {mu:.2e} decrement {decrement:.2e} step {alpha:.3f} residual {residual(x):.2e}")
    return x.reshape(-1, 3), steps, stages, time.perf_counter() - t_start


def primal_dual_solve(scene, sigma=None, max_newton=300, force_tol=1e-6, verbose=False):
    """The same equilibrium by a primal-dual interior method on the tension form: each rod's tension T_r >= 0 and
    gap g_r >= 0 (how far it is from taut) are unknowns beside x, with

        sum_r T_r grad L_r(x) = f,   L_r(x) - l0_r - T_r / k_r + g_r = 0,   T_r g_r = mu,

    L_r = |U_r| its length and k_r = 2 w_r its axial stiffness (N/m). Newton's step eliminates dT_r and dg_r rod by
    rod: dT_r = c_r (grad L_r . dx + rho_r), c_r = k_r T_r / (T_r + k_r g_r), which leaves on the nodes

        sum_r (T_r hess L_r + c_r grad L_r grad L_r^T) dx = -(sum_r T_r grad L_r - f) - sum_r c_r rho_r grad L_r,

    today's tangent with each rod's axial stiffness k_r replaced by c_r, between k_r (taut: g_r -> 0) and 0 (slack:
    T_r -> 0): the same sparsity and no barrier Hessian to blow up. mu: with ``sigma`` None, Mehrotra's
    predictor-corrector (Mehrotra, SIAM J. Optim. 2, 1992): a predictor step towards mu = 0 on the same
    factorisation, sigma = (the mean T g it would leave / the mean now)³ and its second-order term dT dg in the
    corrector; else mu = sigma x the mean T_r g_r at each step. A step is cut by the fraction to the boundary
    (0.995) of T and g, without line search. Returns (x (N, 3), Newton steps, wall s)."""
    t_start = time.perf_counter()
    system = RodSystem(scene)
    f, x, free, l0, m = system.f, system.x0, system.free, system.l0, system.m
    k_axial = 2.0 * system.w
    on_nodes = system.on_nodes

    def geometry_of(x):
        U = system.twine_vectors(x)
        L = np.linalg.norm(U, axis=1)
        return U, L, U / L[:, None]

    U, L, unit = geometry_of(x)
    scale_T = float(np.abs(f).max())
    T = np.maximum(k_axial * (L - l0), scale_T)
    g = np.maximum(l0 - L, 0.01 * l0)
    steps = 0
    while steps < max_newton:
        R1 = on_nodes(T[:, None] * unit) - f
        r2 = L - l0 - T / k_axial + g
        gap = float(np.mean(T * g))
        force = float(np.abs(R1[free]).max())
        if verbose:
            print(f"  {steps:4d} force {force:.2e} N  length {np.abs(r2).max():.2e} m  mean T g {gap:.2e}")
        if force < force_tol and np.abs(r2).max() < 1e-12 and gap < 1e-14:
            break
        cr = k_axial * T / (T + k_axial * g)
        # the rod's stiffness on its twine vector: T hess L + c unit unit^T, hess L = (I - unit unit^T) / L
        K_U = (T / L)[:, None, None] * (np.eye(3) - unit[:, :, None] * unit[:, None, :]) \
            + cr[:, None, None] * unit[:, :, None] * unit[:, None, :]
        K = spla.splu(system.stiffness(K_U))

        def direction(target):
            """The Newton direction (dx, dT, dg) towards T g = target (per rod, N m)."""
            rho = r2 + (target - T * g) / T
            dx = np.zeros_like(x)
            dx[free] = K.solve((-R1 - on_nodes((cr * rho)[:, None] * unit))[free])
            dT = cr * (np.einsum("rc,rc->r", unit, system.twine_vectors(dx)) + rho)
            return dx, dT, (target - T * g - g * dT) / T

        def step_to_boundary(dT, dg):
            alpha = 1.0
            for value, change in ((T, dT), (g, dg)):
                shrinking = change < 0.0
                if shrinking.any():
                    alpha = min(alpha, float(np.min(-value[shrinking] / change[shrinking])))
            return alpha

        if sigma is None:
            # predictor: towards T g = 0; its reach sets sigma = (mean T g it would leave / now)³, and its
            # second-order term dT dg corrects the complementarity of the step taken
            _, dT_a, dg_a = direction(np.zeros(m))
            a = step_to_boundary(dT_a, dg_a)
            centring = (float(np.mean((T + a * dT_a) * (g + a * dg_a))) / gap) ** 3
            dx, dT, dg = direction(centring * gap - dT_a * dg_a)
        else:
            dx, dT, dg = direction(np.full(m, sigma * gap))
        alpha = min(1.0, 0.995 * step_to_boundary(dT, dg))
        x, T, g = x + alpha * dx, T + alpha * dT, g + alpha * dg
        U, L, unit = geometry_of(x)
        steps += 1
    return x.reshape(-1, 3), steps, time.perf_counter() - t_start


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=float, nargs="*", default=[0.1, 0.05, 0.025])
    parser.add_argument("--method", choices=("primal-dual", "barrier"), default="primal-dual")
    parser.add_argument("--shrink", type=float, default=0.1, help="barrier: mu's factor per stage")
    parser.add_argument("--sigma", type=float, help="primal-dual: mu = sigma x the mean T g at every step, instead "
                                                    "of Mehrotra's predictor-corrector")
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args()
    header = (f"{'step m':>7s} {'nodes':>6s} | {'Newton steps':>12s} {'wall s':>7s} {'residual N':>10s} | "
              f"{'Clarabel its':>12s} {'residual N':>10s} | {'energy diff J':>13s} {'max |dx| m':>10s}")
    centring = "Mehrotra's predictor-corrector" if args.sigma is None else f"mu = {args.sigma:g} x mean T g"
    how = (f"a primal-dual method on the tension form ({centring})" if args.method == "primal-dual"
           else f"a primal barrier method (mu x {args.shrink:g} per stage)")
    print(f"The wall of cone_reference.py in still water: {how}, against Clarabel\n")
    print(header)
    print("-" * len(header))
    for step in args.steps:
        scene = wall_in_still_water(step)
        if args.method == "primal-dual":
            x, steps, wall = primal_dual_solve(scene, sigma=args.sigma, verbose=args.verbose)
        else:
            x, steps, _, wall = barrier_solve(scene, shrink=args.shrink, verbose=args.verbose)
        cone = solve_cone(scene)
        ours_residual, ours_energy = balance(scene, x)
        cone_residual, cone_energy = balance(scene, cone.x)
        print(f"{step:7.3f} {scene.n_nodes:6d} | {steps:12d} {wall:7.2f} {ours_residual:10.2e} | "
              f"{cone.iterations:12d} {cone_residual:10.2e} | {ours_energy - cone_energy:13.2e} "
              f"{np.abs(x - cone.x).max():10.2e}")
    print("\nresidual: the largest out-of-balance force on a free coordinate by jaxnet's residual at each answer; "
          "energy diff: jaxnet's potential energy at this answer less at Clarabel's; wall: the method's own "
          "time (NumPy and SciPy's SuperLU)")


if __name__ == "__main__":
    main()
