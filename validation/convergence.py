"""Error against run time, statics: closed forms, the solver's tolerance, and refinement series.

Three kinds of error are measured, because a user pays for each in a different currency:

1. **The solver's**: on nets whose exact answer the discretisation holds exactly (a uniformly stretched
   panel, the balance of a hanging panel, of a hexagonal-mesh panel), the only error left is the Newton
   tolerance's. Swept from 1e-1 N to 1e-10 N, it shows what each digit costs in run time.
2. **The discretisation's, where a closed form exists**: a held panel in a current (Morison drag per twine,
   exact at every meshing step: the element counts its twines exactly, 4.114-4.117) and a pressurised tube
   (twines at arctan √2 to its axis, approached as the triangles shrink).
3. **The discretisation's on real nets**: a framed panel sagging under its weight, the fish cage in a current
   and the cod-end with its catch, the meshing step halved repeatedly; the error of each reported figure is
   taken against the finest run, and the observed order from three successive runs (Richardson):
   p = log2(|f(2h) - f(h)| / |f(h) - f(h/2)|).

Times: ``compile s`` is JAX's compilation of the scene's program (paid once per scene shape and set of terms,
and kept on disk by ``jaxnet run``); ``run s`` is the solve itself (assembly, factorisations, line search).
"""

from __future__ import annotations

import math
import time

import numpy as np

TITLE = "Error against run time: statics"


def _solve(scene, warm=False, **options):
    """Solve and time it; a failed solve is reported, not raised (the table says so). ``warm``: solve once
    before, untimed, so that the time measured is the solve's alone (no compilation, no first-call costs)."""
    import jaxnet as jn

    if warm:
        jn.solve_static(scene, throw=False, **options)
    t0 = time.perf_counter()
    eq = jn.solve_static(scene, throw=False, **options)
    timing = eq.timing
    wall = time.perf_counter() - t0
    return eq, {"iterations": int(eq.iterations), "converged": eq.converged, "residual N": float(eq.residual_N),
                "compile s": timing.compile_s, "run s": wall - timing.compile_s}


def _progress(*parts):
    print("  [convergence]", *parts, flush=True)


# -- 1. the solver's error ------------------------------------------------------------------------------------------
def tolerance_sweep(quick):
    """Rows: case, tolerance, error, iterations, run time, for three nets whose exact answer the mesh holds."""
    tolerances = [10.0**-k for k in (range(1, 11) if not quick else (1, 3, 5, 7, 9))]
    sizes = (1,) if quick else (1, 2)  # the full study repeats the sweep on nets twice as many meshes across
    rows = []
    for size in sizes:
        rows += _sweep_one(size, tolerances)
    return rows


def _sweep_one(size, tolerances):
    """The sweep on the three nets, ``size`` times as many meshes across as the smallest."""
    from jaxnet import figures
    from jaxnet.scenes import textbook
    from jaxnet.scenes.panel import hanging_panel

    rows = []

    # a uniformly stretched panel, started from a perturbed interior: error = largest node distance (m)
    scene, _, _ = textbook.biaxial_panel(12 * size, 8 * size, 0.3, 0.01, step=0.05)
    exact = np.asarray(scene.nodes.position)
    free = ~np.asarray(scene.nodes.fixed).all(axis=1)
    start = exact.copy()
    start[free] += np.random.default_rng(1).normal(scale=0.002, size=(free.sum(), 3))
    for tol in tolerances:
        eq, t = _solve(scene, warm=tol == tolerances[0], x0=start, tol=tol)
        rows.append({"case": "biaxial panel: node positions (m)", "DOF": scene.n_dof, "tol N": tol,
                     "error": float(np.abs(np.asarray(eq.x) - exact).max()), **t})
        _progress("biaxial", tol, rows[-1]["error"])

    # a curtain hanging from its headline: error = |vertical reaction - immersed weight| / weight
    scene = hanging_panel(meshes=20 * size, step=0.08).scene
    weight = -float(figures.total_load(scene)[2])
    for tol in tolerances:
        eq, t = _solve(scene, warm=tol == tolerances[0], tol=tol, max_iter=300)
        rows.append({"case": "hanging panel: reaction / immersed weight - 1", "DOF": scene.n_dof, "tol N": tol,
                     "error": abs(float(eq.reaction(scene).sum(axis=0)[2]) / weight - 1), **t})
        _progress("hanging", tol, rows[-1]["error"])

    # a hexagonal-mesh panel under a pull: error = |reaction - (pull + weight)| / (pull + weight)
    scene, exact_reaction = textbook.hexagonal_hanging_panel(meshes=8 * size)
    for tol in tolerances:
        eq, t = _solve(scene, warm=tol == tolerances[0], tol=tol)
        error = np.abs(eq.reaction(scene).sum(axis=0) - exact_reaction).max() / np.abs(exact_reaction).max()
        rows.append({"case": "hexagonal panel: reaction (relative)", "DOF": scene.n_dof, "tol N": tol,
                     "error": float(error), **t})
        _progress("hexagonal", tol, rows[-1]["error"])
    return rows


# -- 2. closed forms with a discretisation ------------------------------------------------------------------------
def held_panel_drag(quick):
    """Rows: the drag of a held panel normal to the current against the closed form, at several steps."""
    from jaxnet.scenes import textbook

    rows = []
    steps = (0.2, 0.1, 0.05) if quick else (0.4, 0.2, 0.1, 0.05, 0.025)
    for step in steps:
        scene, exact = textbook.panel_in_current(meshes=17, step=step, angle=np.pi / 2, speed=0.5)
        eq, t = _solve(scene)
        drag = -float(eq.reaction(scene).sum(axis=0)[0])
        rows.append({"step m": step, "nodes": scene.n_nodes, "triangles": scene.n_elements, "drag N": drag,
                     "exact N": exact, "error": abs(drag / exact - 1), **t})
        _progress("held panel", step, rows[-1]["error"])
    return rows


def tube(quick):
    """Rows: the mean twine angle in the middle third of the pressurised tube against arctan √2, per step."""
    from jaxnet.scenes import textbook

    rows = []
    l0 = 0.05
    for step in ((2 * l0, l0) if quick else (2 * l0, l0, l0 / 2)):
        scene = textbook.pressurised_tube(np.radians(textbook.TUBE_ANGLE_DEG), step=step, l0=l0)
        eq, t = _solve(scene, tol=1e-8, max_iter=300)
        x = np.asarray(eq.x)
        middle = textbook.tube_middle_third(scene, x)
        _, u_angle, v_angle = textbook.tube_twine_angles(scene, x)
        mean = 0.5 * (u_angle[middle].mean() + v_angle[middle].mean())
        rows.append({"step m": step, "step / l0": step / l0, "DOF": scene.n_dof, "angle deg": mean,
                     "exact deg": textbook.TUBE_ANGLE_DEG, "error deg": abs(mean - textbook.TUBE_ANGLE_DEG), **t})
        _progress("tube", step, rows[-1]["error deg"])
    return rows


# -- 3. refinement series ---------------------------------------------------------------------------------------------
def _framed(step):
    from jaxnet.scenes.panel import framed_panel

    # under its weight alone: a point sinker would put a logarithmic singularity under the measured sag
    return framed_panel(meshes=40, step=step, sinker_kg=0.0).scene


def _cage(step):
    from jaxnet.scenes import fish_cage

    return fish_cage(step=step).scene


def _codend(step):
    from jaxnet.scenes import codend

    return codend(step=step).scene


def _figures_framed(scene, eq):
    x = np.asarray(eq.x)
    from jaxnet import figures

    return {"sag m": -float(x[:, 2].min()), "max tension N": float(figures.twine_tensions(scene, x).max())}


def _figures_cage(scene, eq):
    from jaxnet import figures

    forces = figures.force_breakdown(scene, eq.x)
    return {"drag N": float(forces["drag_netting_N"][0]), "volume m3": float(figures.enclosed_volume(scene, eq.x)),
            "depth m": -float(np.asarray(eq.x)[:, 2].min())}


def _figures_codend(scene, eq):
    from jaxnet import figures

    report = figures.catch_report(scene, eq.x)
    return {"total drag N": float(-eq.reaction(scene).sum(axis=0)[0]), "catch thickness m": report["thickness_m"],
            "max diameter m": report["diameter_m"]}


#: name -> (scene of a meshing step, figures of a result, steps quick, steps full, solver options)
SERIES = {
    "framed panel under its weight": (_framed, _figures_framed, (0.4, 0.2, 0.1), (0.4, 0.2, 0.1, 0.05, 0.025),
                                    {"tol": 1e-8, "max_iter": 300}),
    "fish cage in 0.5 m/s": (_cage, _figures_cage, (3.2, 1.6, 0.8), (3.2, 1.6, 0.8, 0.4, 0.2),
                             {"tol": 1e-6, "max_iter": 500}),
    "cod-end with 0.2 m3 of catch": (_codend, _figures_codend, (0.48, 0.24, 0.12), (0.48, 0.24, 0.12, 0.06, 0.03),
                                     {"tol": 1e-6, "max_iter": 500}),
}


def refinement(name, quick):
    """Rows per step: DOF, iterations, times, each figure, its error against the finest run and the observed
    order (Richardson, from this step and the two finer ones)."""
    build, measure, steps_quick, steps_full, options = SERIES[name]
    rows = []
    for step in (steps_quick if quick else steps_full):
        scene = build(step)
        eq, t = _solve(scene, **options)
        values = measure(scene, eq)
        figures_ = list(values)
        rows.append({"step m": step, "nodes": scene.n_nodes, "DOF": scene.n_dof, **t, **values})
        _progress(name, step, {k: rows[-1][k] for k in ("iterations", "run s")})
    finest = rows[-1]
    for k, row in enumerate(rows):
        for f in figures_:
            row[f"{f} error"] = abs(row[f] / finest[f] - 1) if k < len(rows) - 1 else None
            if k + 2 < len(rows):
                a, b = row[f] - rows[k + 1][f], rows[k + 1][f] - rows[k + 2][f]
                row[f"{f} order"] = math.log2(abs(a / b)) if a and b else None
            else:
                row[f"{f} order"] = None
    return rows, figures_


# -- the section ----------------------------------------------------------------------------------------------------
def _plot(sweep, series):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(12, 4.5))
    for case in dict.fromkeys(r["case"] for r in sweep):
        rows = [r for r in sweep if r["case"] == case and r["error"] > 0]
        left.loglog([r["run s"] for r in rows], [r["error"] for r in rows], "o-", label=case)
    left.set_xlabel("run time (s, compile excluded)")
    left.set_ylabel("error")
    left.set_title("solver: Newton tolerance 1e-1 ... 1e-10 N")
    left.legend(fontsize=7)
    for name, (rows, figures_) in series.items():
        for f in figures_:
            pts = [(r["DOF"], r[f"{f} error"]) for r in rows if r[f"{f} error"]]
            if pts:
                right.loglog(*zip(*pts), "o-", label=f"{name}: {f}")
    right.set_xlabel("unknowns (DOF)")
    right.set_ylabel("relative error against the finest mesh")
    right.set_title("discretisation: meshing step halved")
    right.legend(fontsize=6)
    fig.tight_layout()
    return fig


def run(report, quick):
    report.text(__doc__.split("\n", 2)[2])
    report.heading("1. The solver's error: Newton tolerance against run time")
    report.text("Each net's exact answer is held by its mesh, so the error is the tolerance's alone. Each net is "
                "solved once before its sweep (compiling it), so that the run times are the solves' alone.")
    sweep = tolerance_sweep(quick)
    report.table(sweep, ["case", "DOF", "tol N", "iterations", "residual N", "error", "run s", "converged"])
    report.record("convergence_tolerance", sweep)

    report.heading("2. Closed forms under refinement")
    drag = held_panel_drag(quick)
    report.text("A held panel normal to a 0.5 m/s current (17 x 17 mesh diagonals, half-mesh 29 mm, twine 2.8 mm, "
                "Cd_n = 1.2): the drag is exact at every step, down to rounding, because each element carries "
                "its exact count of twines (4.114-4.117).")
    report.table(drag, ["step m", "nodes", "triangles", "drag N", "exact N", "error", "run s", "compile s"])
    tube_rows = tube(quick)
    report.text("The pressurised tube (16 meshes around, 32 along, EA 1000 N): the mean angle of the twines to the "
                "axis in the middle third against arctan √2 = 54.7356°. What is left at fine steps is the ring's "
                "and the closure's end effects and the facets' sag, not the element.")
    report.table(tube_rows, ["step m", "step / l0", "DOF", "iterations", "angle deg", "exact deg", "error deg",
                             "run s", "compile s"])
    report.record("convergence_closed_forms", {"held_panel": drag, "tube": tube_rows})

    report.heading("3. Refinement series: error against unknowns and run time")
    series = {}
    for name in SERIES:
        rows, figures_ = refinement(name, quick)
        series[name] = (rows, figures_)
        report.text(f"**{name}** (error: relative to the finest run; order: observed, from three successive runs)")
        columns = ["step m", "nodes", "DOF", "iterations", "run s", "compile s"]
        for f in figures_:
            columns += [f, f"{f} error", f"{f} order"]
        report.table(rows, columns)
        report.record(f"convergence_{name.split()[0]}_{name.split()[1]}", rows)
    report.figure(_plot(sweep, series), "convergence_statics",
                  "Left: error against run time as the Newton tolerance tightens. Right: error of each figure "
                  "against the finest mesh, against the number of unknowns.")
