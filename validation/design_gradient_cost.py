"""What a design gradient costs against one forward solve (issue 7: the gradient should cost ≤ 2x a solve).

For each scene: the equilibrium of a design θ₁ near the reference θ₀ (each twine diameter and EA 2 % up, as in
one optimisation step), warm-started at θ₀'s equilibrium — the forward solve an optimisation iteration makes
— and the same solve with the gradient of a scalar figure of it (the net's drag, or its volume) with respect
to every design parameter of the space (jax.value_and_grad: the adjoint, one sparse solve with K^T plus the
vector-Jacobian product of the residual in θ). Both are jitted programs, timed after compilation (median of
``REPEATS``), so the table compares run times; the compile times are printed too.

    python validation/design_gradient_cost.py [--quick]

Columns: nodes, unknowns, design parameters, Newton iterations of the forward solve, forward (ms), forward +
gradient (ms), gradient alone (ms, the difference), gradient / forward.
"""

from __future__ import annotations

import argparse
import statistics
import time

import jax
import numpy as np

import jaxnet  # noqa: F401
from jaxnet.design import objectives, space as space_lib
from jaxnet.net import Twine
from jaxnet.scene import Environment
from jaxnet.scenes import cage, panel
from jaxnet.solve import implicit

REPEATS = 5


def scenes(quick):
    def curtain(meshes, step):
        # twines that resist compression and a hinged sinker bar: the smooth equilibrium of the design studies
        stiff = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=2000.0)
        net = panel.hanging_panel(meshes=meshes, step=step, twine=stiff, sinker_bending_stiffness=0.0).net
        net.environment = Environment(current_speed=0.4, current_direction=np.array([0.0, 1.0, 0.0]))
        return net

    out = [("hanging panel 10 meshes", curtain(10, 0.05), objectives.drag()),
           ("cage, step 1.6 m", cage.fish_cage(step=1.6), objectives.volume())]
    if not quick:
        out += [("hanging panel 40 meshes", curtain(40, 0.1), objectives.drag()),
                ("cage, step 0.8 m", cage.fish_cage(step=0.8), objectives.volume()),
                ("cage, step 0.5 m (default)", cage.fish_cage(), objectives.volume())]
    return out


def timed(f, *args):
    times = []
    for _ in range(REPEATS):
        t = time.perf_counter()
        jax.block_until_ready(f(*args))
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main(quick=False):
    print("| scene | nodes | unknowns | design parameters | Newton it. | forward (ms) | forward + gradient (ms) "
          "| gradient (ms) | gradient / forward | compile fwd, fwd+grad (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for name, net, figure in scenes(quick):
        space = space_lib.DesignSpace(net)
        structure = implicit.structure_of(space.reference)
        theta0 = space.initial()
        x0 = implicit.solve(space.reference, structure=structure).x
        # one optimisation step away: every diameter and EA 2 % up
        theta1 = dict(theta0, twine_diameter={k: 1.02 * v for k, v in theta0["twine_diameter"].items()},
                      ea={k: 1.02 * v for k, v in theta0["ea"].items()})
        n_params = sum(np.size(leaf) for leaf in jax.tree.leaves(theta1))

        def solve(theta, start):
            scene = space.scene(theta)
            eq = implicit.equilibrium(scene, structure, x0=start)
            return figure(objectives.Outcome(eq.x, scene, structure.model)), eq.iterations

        forward = jax.jit(solve)
        both = jax.jit(jax.value_and_grad(solve, has_aux=True))
        t = time.perf_counter()
        _, iterations = jax.block_until_ready(forward(theta1, x0))
        compile_forward = time.perf_counter() - t
        t = time.perf_counter()
        jax.block_until_ready(both(theta1, x0))
        compile_both = time.perf_counter() - t
        t_forward, t_both = timed(forward, theta1, x0), timed(both, theta1, x0)
        print(f"| {name} | {space.reference.n_nodes} | {space.reference.n_dof} | {n_params} | {int(iterations)} | "
              f"{1e3 * t_forward:.1f} | {1e3 * t_both:.1f} | {1e3 * (t_both - t_forward):.1f} | "
              f"{(t_both - t_forward) / t_forward:.2f} | {compile_forward:.1f}, {compile_both:.1f} |", flush=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="the two small scenes only")
    main(parser.parse_args().quick)
