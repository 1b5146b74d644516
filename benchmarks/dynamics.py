"""Error against run time of jaxnet's dynamics: the book's implicit scheme and the diffrax reference.

    python benchmarks/dynamics.py [--sizes 1.6 1.0 0.5 0.3 0.16] [--cage-end 3.0] [--no-cage]
                                       [--cage-reference-end 1.0] [--plot FILE.png] [--breakdown]

1. Pendulum (a 1.5 kg mass on an elastic bar, EA = 2e4 N, released horizontal under gravity): the mass's
   position at t = 1 s, against diffrax's Kvaerno5 at rtol 1e-10 (the reference solution). Rows: the book
   scheme at Δt = 20 ms ... 0.625 ms; the reference integrator at rtol 1e-4 ... 1e-8. Error (m), wall time
   (s, compiled: the second run), steps, Newton iterations per step, and the observed order; a plot of
   error against wall time (``--plot``).
2. The cage in waves (``jaxnet.scenes.cage_in_waves(step=1.6)``, 339 unknowns: the size of FEMNET's dynamic
   cage benchmark), from its static equilibrium: the peak vertical reaction on the collar (the largest in
   magnitude after t = 0, where a record holds no inertia) and the volume held at the end, for Δt = 40 ... 5 ms against Δt = 2.5 ms (the finest run: the book scheme converges at
   first order, so its own fine run is the reference for the coarse ones), with wall time, steps per second
   and Newton iterations per step; then, at Δt = 10 ms, the cost per step with each stiffness path.
   Then its work-precision against an independent reference (``--cage-reference-end``, default 1 s): the
   same two outputs by the book scheme at Δt = 40 ... 2.5 ms and by diffrax's Kvaerno5 at rtol 1e-3 ...
   1e-5, against Kvaerno5 at rtol 1e-6 (records every 50 ms; the reactions of the reference come from the
   equations of motion at its saved states, the held nodes' inertia taken with the prescribed motion's exact
   acceleration), error against wall time, and the plot's second panel.
3. Cost against size: steps per second and Newton iterations per step of the cage in waves meshed finer
   and finer (``--sizes``, meshing steps in m: 137 to 10361 nodes), after compilation, with the compile time
   and the static solve that gives the start.
4. Where a step's time goes (``--breakdown``): on the same cage at Δt = 10 ms, the pieces of a Newton
   iteration timed alone, compiled (the evaluation of the residual, the tangent on each path and term by
   term, the sparse solve through the host callback and on the host alone), and the fixed cost of a step
   (the cage at its equilibrium in calm water: Newton converges at its start point, 0 iterations).

Timings are medians of 3 repeats; on a shared machine they vary up to ~1.5x between runs.

FEMNET's dynamic solver (same scheme, C): about 55 Newton iterations per step and 732 s of wall time for 68 s
of a 351-DOF cage in waves at Δt = 0.01 s (6800 steps: 108 ms per step) on this kind of machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

import numpy as np

import jaxnet  # noqa: F401
from jaxnet.scene import Bars, Environment, Nodes, Scene
from jaxnet.solve import dynamics, kernel, reference, statics
from jaxnet.solve.options import Newton

NEWTON = Newton(tol=1e-9, max_iter=30, damping=1e-12, stall_window=None)


def pendulum(m=1.5, L=1.0, ea=2e4):
    nodes = Nodes(position=np.array([[0.0, 0.0, 0.0], [L, 0.0, 0.0]]), fixed=np.array([[True] * 3, [False, True, False]]),
                  mass=np.array([0.0, m]), volume=np.zeros(2), force=np.zeros((2, 3)))
    bars = Bars(ends=np.array([[0, 1]]), rest_length=np.array([L]), ea_traction=np.array([ea]),
                ea_compression=np.array([ea]), diameter=np.array([1e-3]), density=np.array([1e-9]), cable=np.array([0]))
    return Scene(nodes=nodes, bars=bars, environment=Environment(gravity=9.81, added_mass_coefficient=0.0))


def timed(run, compile_first=True):
    if compile_first:
        run()
    t0 = time.perf_counter()
    out = run()
    return out, time.perf_counter() - t0


def plot(pendulum_rows, path, cage_rows=None):
    """Work-precision plot: error against wall time, one line per method; the pendulum, and the cage in
    waves when ``cage_rows`` (method, wall time, relative error of the peak collar reaction) are given."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [(pendulum_rows, "Pendulum", "error of the position at t = 1 s (m)")]
    if cage_rows:
        panels.append((cage_rows, "Cage in waves (339 unknowns)", "relative error of the peak collar reaction"))
    fig, axes = plt.subplots(1, len(panels), figsize=(6 * len(panels), 4), squeeze=False)
    for ax, (rows_all, title, ylabel) in zip(axes[0], panels):
        for method, marker in (("book scheme", "o-"), ("Kvaerno5 (diffrax)", "s-")):
            rows = [(w, e) for m, w, e in rows_all if m == method and e > 0]
            ax.loglog([w for w, _ in rows], [e for _, e in rows], marker, label=method)
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel(ylabel)
        ax.set_title(f"{title}: error against run time")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"\nwrote {path}")


def pendulum_table(end=1.0):
    scene = pendulum()
    exact = reference.reference(scene, end, saveat=[0.0, end], rtol=1e-10, atol=1e-12).positions[-1, 1]
    print(f"\n## Pendulum: position of the mass at t = {end} s (reference: Kvaerno5, rtol 1e-10)\n")
    print("| method | setting | error (m) | order | wall (s) | steps | Newton it./step |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    last = None
    for n in (50, 100, 200, 400, 800, 1600):
        h = end / n
        tr, wall = timed(lambda: dynamics.simulate(scene, end, dynamics.Implicit(time_step=h, newton=NEWTON),
                                                   record_every=end))
        err = float(np.linalg.norm(tr.positions[-1, 1] - exact))
        order = "" if last is None else f"{np.log2(last / err):.2f}"
        last = err
        rows.append(("book scheme", wall, err))
        print(f"| book scheme | Δt = {h * 1e3:.3g} ms | {err:.3e} | {order} | {wall:.3f} | {tr.steps} | {tr.mean_iterations:.2f} |")
    for rtol in (1e-4, 1e-6, 1e-8):
        ref, wall = timed(lambda: reference.reference(scene, end, saveat=[0.0, end], rtol=rtol, atol=rtol * 1e-2))
        err = float(np.linalg.norm(ref.positions[-1, 1] - exact))
        rows.append(("Kvaerno5 (diffrax)", wall, err))
        print(f"| Kvaerno5 (diffrax) | rtol = {rtol:g} | {err:.3e} | | {wall:.3f} | {ref.steps_accepted} (+{ref.steps_rejected} rejected) | |")
    return rows


def cage_and_loading(step):
    """(scene, loading) of the cage in waves (:func:`jaxnet.scenes.cage_in_waves`) meshed at ``step`` (m)."""
    from jaxnet import scenes

    case = scenes.cage_in_waves(step=step)
    return case.scene, case.time.loading


def cage_table(end):
    scene, loading = cage_and_loading(1.6)
    eq = statics.solve(scene)
    x0 = np.asarray(eq.x)
    print(f"\n## Cage in waves ({scene.n_nodes} nodes, {scene.n_dof} unknowns): 0 to {end} s from the static "
          "equilibrium; against the book scheme at Δt = 2.5 ms\n")
    runs = {}
    for h in (0.04, 0.02, 0.01, 0.005, 0.0025):
        opts = dynamics.Implicit(time_step=h)
        tr, wall = timed(lambda: dynamics.simulate(scene, end, opts, loading, record_every=0.05, x0=x0))
        runs[h] = (tr, wall)
    fine = runs[0.0025][0]
    peak_ref = peak(fine.figures["reaction_total_N"][:, 2])
    volume_ref = fine.figures["volume_m3"][-1]
    print("| Δt (ms) | peak collar reaction (N, largest in magnitude after t = 0) | its error | volume at end (m³) | "
          "its error | wall (s) | steps/s | Newton it./step |")
    print("|---|---|---|---|---|---|---|---|")
    for h, (tr, wall) in runs.items():
        top = peak(tr.figures["reaction_total_N"][:, 2])
        vol = tr.figures["volume_m3"][-1]
        print(f"| {h * 1e3:g} | {top:.1f} | {abs(top - peak_ref) / abs(peak_ref):.2e} | {vol:.3f} | "
              f"{abs(vol - volume_ref) / volume_ref:.2e} | {wall:.2f} | {tr.steps / wall:.1f} | {tr.mean_iterations:.2f} |")
    print("\nAt Δt = 10 ms, per step (the same run, each stiffness path, 5 runs each, alternating; FEMNET: 108 ms "
          "and 55 iterations per step). On a shared machine a run can take 1.5x another: the median and the "
          "fastest run are both given.\n")
    print("| stiffness | ms per step, median | fastest | Newton it./step | vs FEMNET (median) |")
    print("|---|---|---|---|---|")
    paths = ("closed_form", "autodiff")
    options = {path: dynamics.Implicit(time_step=0.01, newton=dataclasses.replace(dynamics.Implicit().newton,
                                                                                  stiffness=path)) for path in paths}
    per_step, iterations = {path: [] for path in paths}, {}
    for _ in range(5):
        for path in paths:
            tr, wall = timed(lambda: dynamics.simulate(scene, end, options[path], loading, record_every=0.05, x0=x0), compile_first=not per_step[path])
            per_step[path].append(wall / tr.steps)
            iterations[path] = tr.mean_iterations
    for path in paths:
        median = float(np.median(per_step[path]))
        print(f"| {path} | {median * 1e3:.1f} | {min(per_step[path]) * 1e3:.1f} | {iterations[path]:.2f} | "
              f"{0.108 / median:.1f}x |")
    return runs


def reference_figures(scene, loading, ref):
    """The collar's total vertical reaction (N) at each saved time of a reference run, and the volume held
    (m³) at the last: the same figures as a book-scheme record. The reactions are minus the out-of-balance
    force at the fixed coordinates, the held nodes' own inertia -(M + M_a) a included, with a the prescribed
    motion's exact acceleration (the book scheme takes its backward difference: first-order close)."""
    import jax
    import jax.numpy as jnp

    from jaxnet import model as model_lib
    from jaxnet.model import catch as catch_lib

    model = model_lib.active_terms(scene, dynamic=True)
    masses = tuple(jnp.asarray(m) for m in dynamics.lumped_masses(scene))
    fixed = np.asarray(scene.nodes.fixed)

    def position(t):
        return dynamics.scene_at(scene, loading, t).nodes.position

    acceleration = jax.jit(jax.jacfwd(jax.jacfwd(position)))
    force = jax.jit(dynamics.out_of_balance, static_argnames=("model",))
    reaction_z = []
    for t, x, v in zip(ref.times, ref.positions, ref.velocities):
        f = np.asarray(force(jnp.asarray(x), jnp.asarray(v), float(t), scene, masses, loading, model=model))
        f = f - np.asarray(masses[0]) * np.asarray(acceleration(jnp.asarray(float(t))))
        reaction_z.append(float(np.where(fixed, -f, 0.0)[:, 2].sum()))
    e = scene.enclosure
    volume = float(catch_lib.enclosed_volume(jnp.asarray(ref.positions[-1]), scene.netting.vertices,
                                             jnp.dot(e.center, e.axis), e.axis, sign=scene.netting.outward))
    return np.asarray(reaction_z), volume


def peak(reaction_z):
    """The reaction (N) of largest magnitude among the records after t = 0 (at t = 0 a book-scheme record has
    no inertia in it: the acceleration there is unknown)."""
    later = np.asarray(reaction_z)[1:]
    return float(later[np.argmax(np.abs(later))])


def cage_reference_table(end, reference_rtol=1e-6):
    """Work-precision of the book scheme and of Kvaerno5 on the cage in waves, against Kvaerno5 at
    ``reference_rtol`` over [0, end] (module docstring, item 2). Returns the rows (method, wall, error)."""
    scene, loading = cage_and_loading(1.6)
    x0 = np.asarray(statics.solve(scene).x)
    record = 0.05
    saveat = np.linspace(0.0, end, int(round(end / record)) + 1)

    def run_reference(rtol):
        return reference.reference(scene, end, loading, saveat=saveat, rtol=rtol, atol=rtol * 1e-2, x0=x0)

    t0 = time.perf_counter()
    exact = run_reference(reference_rtol)
    wall_exact = time.perf_counter() - t0
    reaction_exact, volume_exact = reference_figures(scene, loading, exact)
    peak_exact = peak(reaction_exact)
    print(f"\n## Cage in waves ({scene.n_dof} unknowns), 0 to {end:g} s from the static equilibrium: against "
          f"Kvaerno5 at rtol {reference_rtol:g} ({exact.steps_accepted} steps, +{exact.steps_rejected} rejected, "
          f"{wall_exact:.0f} s with its compilation)\n")
    print(f"Peak collar reaction (z, the largest in magnitude after t = 0) of the reference {peak_exact:.2f} N, "
          f"volume held at {end:g} s {volume_exact:.4f} m³. Wall times after compilation (the book scheme: a second "
          "run; Kvaerno5: its run less its compile time). The reference's own error is of the order of its "
          "tolerance: errors below about 10 x rtol of the reference are not resolved.\n")
    print("| method | setting | peak reaction error | volume error | wall (s) | steps | Newton it./step |")
    print("|---|---|---|---|---|---|---|")
    rows = []
    for h in (0.04, 0.02, 0.01, 0.005, 0.0025):
        opts = dynamics.Implicit(time_step=h)
        tr, wall = timed(lambda: dynamics.simulate(scene, end, opts, loading, record_every=record, x0=x0))
        err = abs(peak(tr.figures["reaction_total_N"][:, 2]) - peak_exact) / abs(peak_exact)
        verr = abs(tr.figures["volume_m3"][-1] - volume_exact) / volume_exact
        rows.append(("book scheme", wall, err))
        print(f"| book scheme | Δt = {h * 1e3:g} ms | {err:.2e} | {verr:.2e} | {wall:.2f} | {tr.steps} | "
              f"{tr.mean_iterations:.2f} |")
    for rtol in (1e-3, 1e-4, 1e-5):
        ref = run_reference(rtol)
        wall = ref.timing.wall_s - ref.timing.compile_s
        reaction, volume = reference_figures(scene, loading, ref)
        err = abs(peak(reaction) - peak_exact) / abs(peak_exact)
        rows.append(("Kvaerno5 (diffrax)", wall, err))
        print(f"| Kvaerno5 (diffrax) | rtol = {rtol:g} | {err:.2e} | {abs(volume - volume_exact) / volume_exact:.2e} | "
              f"{wall:.2f} | {ref.steps_accepted} (+{ref.steps_rejected} rejected) | |")
    return rows


def size_table(steps):
    """Steps per second against size (module docstring, item 3): 0.5 s of the cage in waves from its static
    equilibrium, 0.1 s from 3000 nodes on (a step there takes a large part of a second)."""
    print("\n## Cost against size: the cage in waves, Δt = 10 ms, from the static equilibrium\n")
    print("| meshing step (m) | nodes | unknowns | static solve (s) | compile + first 2 steps (s) | simulated (s) | "
          "steps/s | ms per step | Newton it./step |")
    print("|---|---|---|---|---|---|---|---|---|")
    for step in steps:
        scene, loading = cage_and_loading(step)
        t0 = time.perf_counter()
        eq = statics.solve(scene)
        static_s = time.perf_counter() - t0
        x0 = np.asarray(eq.x)
        opts = dynamics.Implicit(time_step=0.01)
        end = 0.5 if scene.n_nodes < 3000 else 0.1
        t0 = time.perf_counter()
        dynamics.simulate(scene, 0.02, opts, loading, record_every=0.02, x0=x0)
        first = time.perf_counter() - t0
        t0 = time.perf_counter()
        tr = dynamics.simulate(scene, end, opts, loading, record_every=end, x0=x0)
        wall = time.perf_counter() - t0
        print(f"| {step:g} | {scene.n_nodes} | {scene.n_dof} | {static_s:.1f} | {first:.1f} | {end:g} | "
              f"{tr.steps / wall:.1f} | {wall / tr.steps * 1e3:.1f} | {tr.mean_iterations:.2f} |", flush=True)


def _median_ms(run, calls=100, repeats=3):
    """Median over ``repeats`` of the mean time (ms) of ``calls`` calls of ``run`` (compiled by a first call)."""
    import jax

    jax.block_until_ready(run())
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(calls):
            out = run()
        jax.block_until_ready(out)
        times.append((time.perf_counter() - t0) / calls * 1e3)
    return float(np.median(times))


def time_step_problem(mesh_step, run_time, time_step=0.01):
    """The next time step of the cage in waves meshed at ``mesh_step`` (m), ``run_time`` (s) into a run from its
    static equilibrium: (scene, loading, model, pattern, scene at the step's end, its
    :class:`~jaxnet.solve.dynamics.TimeStep`, the free coordinates Newton starts from, the loads (N)), what the
    step's Newton iteration evaluates and differentiates."""
    import jax.numpy as jnp

    from jaxnet import model as model_lib
    from jaxnet.model import assemble

    scene, loading = cage_and_loading(mesh_step)
    x_eq = np.asarray(statics.solve(scene).x)
    model = model_lib.active_terms(scene, dynamic=True)
    pattern = assemble.build_pattern(scene, model)
    masses = tuple(jnp.asarray(m) for m in dynamics.lumped_masses(scene))
    state = dynamics.simulate(scene, run_time, dynamics.Implicit(time_step=time_step), loading, record_every=run_time,
                              x0=x_eq).state
    scene_t = dynamics.scene_at(scene, loading, state.t + time_step)
    water_load = masses[1] * dynamics.water_acceleration(state.x, scene_t, loading, True)
    step = dynamics.TimeStep(state.x, state.v, jnp.asarray(time_step), masses[0], water_load)
    x = (state.x + time_step * state.v).ravel()[pattern.free]
    return scene, loading, model, pattern, scene_t, step, x, assemble.loads(scene_t, model) + water_load


def breakdown():
    """The pieces of a time step of the cage in waves, each timed alone (module docstring, item 4)."""
    import equinox as eqx
    import jax
    import jax.numpy as jnp

    from jaxnet import linalg
    from jaxnet.model import assemble

    scene, loading, model, pattern, scene_t, step, x, load = time_step_problem(1.6, 0.5)
    h = float(step.time_step)
    evaluate = jax.jit(kernel.evaluate, static_argnames=("model",))
    zero = jnp.zeros_like(step.x_previous)
    _, force, _, _, forces_state = evaluate(x, zero, load, 1.0, scene_t, pattern, model=model, step=step)
    rows = [("evaluation (energy, its gradient, drag forces)", _median_ms(
        lambda: evaluate(x, zero, load, 1.0, scene_t, pattern, model=model, step=step)))]
    tangent = jax.jit(kernel.tangent, static_argnames=("model", "stiffness"))
    for path in assemble.STIFFNESS_PATHS:
        rows.append((f"tangent, {path}", _median_ms(
            lambda: tangent(x, forces_state, 1.0, scene_t, pattern, model=model, stiffness=path, step=step))))
        X = assemble.positions(x, scene_t, pattern)
        for term in model:
            if term.term.kind in ("energy", "force"):
                one = jax.jit(lambda X, term=term, path=path: assemble.tangent(
                    X, scene_t, (term,), pattern, forces_state, 1.0, path, step.motion))
                rows.append((f"    {term.name}", _median_ms(lambda: one(X))))
    data = tangent(x, forces_state, 1.0, scene_t, pattern, model=model, stiffness="closed_form", step=step)
    f = force.ravel()[pattern.free]
    solve = jax.jit(linalg.solve)
    rows.append(("sparse solve through the host callback", _median_ms(lambda: solve(data, f, pattern.indptr,
                                                                                    pattern.indices))))
    host = linalg.HostSolver(np.asarray(pattern.indptr), np.asarray(pattern.indices))
    data_np, f_np = np.asarray(data), np.asarray(f)
    rows.append(("    of which on the host (SuperLU, checks)", _median_ms(lambda: host.solve(data_np, f_np)[0])))
    # the fixed cost of a step: the cage at its equilibrium in calm water, Newton converging at its start
    calm = eqx.tree_at(lambda s: s.environment.waves.height, scene, jnp.asarray(0.0))
    x_calm = np.asarray(statics.solve(calm, tol=1e-7).x)
    opts = dynamics.Implicit(time_step=h)
    _, wall = timed(lambda: dynamics.simulate(calm, 1.0, opts, None, record_every=0.05, x0=x_calm))
    rows.append(("a step without Newton iterations (1 evaluation, records every 5 steps)", wall / 100 * 1e3))
    print("\n## Where a step's time goes: the cage in waves, Δt = 10 ms, pieces timed alone (compiled)\n")
    print("| piece | ms |")
    print("|---|---|")
    for name, ms in rows:
        print(f"| {name} | {ms:.3f} |")
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=float, nargs="*", default=[1.6, 1.0, 0.5, 0.3, 0.16])
    parser.add_argument("--cage-end", type=float, default=3.0)
    parser.add_argument("--no-cage", action="store_true")
    parser.add_argument("--cage-reference-end", type=float, default=1.0,
                        help="length (s) of the cage's work-precision against Kvaerno5; 0 skips it")
    parser.add_argument("--plot", default="validation/dynamics_work_precision.png")
    parser.add_argument("--breakdown", action="store_true", help="only the cost breakdown of a step (item 4)")
    args = parser.parse_args()
    if args.breakdown:
        breakdown()
        return
    pendulum_rows = pendulum_table()
    cage_rows = None
    if not args.no_cage:
        cage_table(args.cage_end)
        if args.cage_reference_end > 0:
            cage_rows = cage_reference_table(args.cage_reference_end)
    plot(pendulum_rows, args.plot, cage_rows)
    if args.sizes:
        size_table(args.sizes)


if __name__ == "__main__":
    main()
