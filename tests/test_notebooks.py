"""The notebooks run top to bottom, on a small size, and say what they claim.

Each notebook's code cells are executed in order in one namespace (as a kernel would), with
``JAXNET_NOTEBOOK_SMALL=1`` (the notebooks' switch to small sizes) and matplotlib's non-interactive backend;
no Jupyter kernel is needed. The namespace is then checked for the numbers the notebook shows.
"""

from __future__ import annotations

import json
import pathlib

import matplotlib
import numpy as np
import pytest

NOTEBOOKS = pathlib.Path(__file__).parents[1] / "notebooks"


def run_notebook(name, monkeypatch):
    matplotlib.use("Agg")
    monkeypatch.setenv("JAXNET_NOTEBOOK_SMALL", "1")
    cells = json.loads((NOTEBOOKS / name).read_text())["cells"]
    namespace = {"__name__": "__main__"}
    for k, cell in enumerate(cells):
        if cell["cell_type"] == "code":
            source = "".join(cell["source"])
            exec(compile(source, f"{name}[cell {k}]", "exec"), namespace)  # noqa: S102
    import matplotlib.pyplot as plt

    plt.close("all")
    return namespace


def test_hand_vs_autodiff(monkeypatch):
    ns = run_notebook("hand_vs_autodiff.ipynb", monkeypatch)
    # one element and the whole net: the two paths agree to rounding
    assert ns["difference"].max() <= 1e-10 * np.abs(np.asarray(ns["K_autodiff"])).max()
    assert ns["gap"] <= 1e-10
    # the erratum shown: 4.58 as printed is the true derivative times |U|
    np.testing.assert_allclose(ns["printed"] / ns["true"], ns["U_len"], rtol=1e-6)
    # the cost table has both paths for every term it timed
    assert all(np.isfinite(v).all() and min(v) > 0 for v in ns["run"].values())


def test_design_panel_cuts(monkeypatch):
    import re

    ns = run_notebook("design_panel_cuts.ipynb", monkeypatch)
    result, history, ref, opt, best = ns["result"], ns["history"], ns["ref"], ns["opt"], ns["best"]
    top, walls = ns["top"], ns["walls"]
    # the history: one row per iteration, the start included (all of them unless the gradient fell below
    # optimize's tolerance first), every figure finite
    n = len(result.history)
    if result.reason == ns["optimize"].MAX_STEPS:
        assert n == ns["steps"] + 1
    else:
        assert result.reason == ns["optimize"].CONVERGED and 2 <= n <= ns["steps"] + 1
    np.testing.assert_array_equal(history["step"], np.arange(n))
    for key in ("objective", "violation", "gradient_norm"):
        assert history[key].shape == (n,) and np.isfinite(history[key]).all()
    # the objective -V/V_ref + penalty starts at -1 (on the twine limit) and falls by more than 0.05, i.e.
    # 5 % more volume (measured: -1.084), L-BFGS converging (gradient down by 1e-4 at least; measured 2e-6)
    assert history["objective"][0] == pytest.approx(-1.0, abs=1e-12)
    assert history["objective"][-1] < -1.05
    assert history["gradient_norm"][-1] < 1e-4 * history["gradient_norm"][0]
    # the continuous optimum, re-solved: > 5 % more volume (measured 8.4 %), its twine within the penalty's
    # overshoot of the limit (1e-4 relative; measured 6e-6)
    assert opt["volume"] > 1.05 * ref["volume"]
    assert abs(opt["twine"] / ref["twine"] - 1) < 1e-4
    # the whole-mesh design, re-solved: feasible (violation 0), > 4 % more volume (measured 7.5 %); its twine by
    # the figure (sum of |d| l0 over the triangles) equals 4 l0 per mesh counted on the cut
    assert best["violation"] <= 1e-9 and best["twine"] <= ref["twine"] * (1 + 1e-12)
    assert best["volume"] > 1.04 * ref["volume"]
    counted = float(sum(ns["space"].twine_length(best["theta"]).values()))
    assert best["twine"] == pytest.approx(counted, rel=1e-12)
    # whole meshes: every corner of every panel moved from the reference cut by whole meshes (integer du, dv);
    # the walls, drawn on whole meshes from corner 0, have whole sides
    from jaxnet.design import cut

    reference = ns["space"].initial()["cut"]
    for panel, corners in best["theta"]["cut"].items():
        moved = np.asarray(cut.twine_to_mesh(np.asarray(corners) - np.asarray(reference[panel])))
        np.testing.assert_allclose(moved, np.rint(moved), rtol=0, atol=1e-9)
    for side in best["report"][walls[0]]:
        assert side.whole and side.du == round(side.du) and side.dv == round(side.dv)
    # all walls alike; tapered: the top kept, a narrower foot, the same cut on both sides: k = (top - foot)/2
    # meshes off each side over `depth` meshes is (depth - k) points and 2k bars
    cuts = [tuple(str(s) for s in best["report"][w]) for w in walls]
    assert all(c == cuts[0] for c in cuts)
    top_side, right, foot, left = best["report"][walls[0]]
    assert top_side.meshes == top and foot.meshes == best["foot"] < top
    k = (top - best["foot"]) // 2
    assert right.rate == left.rate and re.fullmatch(r"\d+N\d+B", right.rate)
    assert right.steps == {"N": best["depth"] - k, "T": 0, "B": 2 * k} and right.meshes == best["depth"]
    # the bottom slices' rim has the foot's meshes (they are sewn together)
    assert all(best["report"][b][2].meshes == best["foot"] for b in ns["bottoms"])


def test_design_trawl(monkeypatch, tmp_path):
    """The trawl study on FEMNET's b1 (small: one Adam step in each optimisation): its figures are what they say,
    the optimiser's history starts at the drawn trawl's figure, and the design written as .don and re-meshed by
    jaxnet gives the design space's figures within the re-meshing's difference."""
    # the notebook writes its runs and the designed .don under $TMPDIR/jaxnet-design-trawl: this test's own folder,
    # not the /tmp one that another run (or another user's) shares and leaves behind
    monkeypatch.setenv("TMPDIR", str(tmp_path))
    ns = run_notebook("design_trawl.ipynb", monkeypatch)
    before, after, trimmed, checked = ns["before"], ns["after"], ns["trimmed_figures"], ns["checked"]
    assert after["twine"] == pytest.approx(trimmed["twine"], rel=1e-12)  # trimming ropes leaves the netting
    # drag per swept width: the whole trawl's drag over twice the door's distance to the plane y = 0
    x = np.asarray(ns["reference"].x)
    assert before["spread"] == pytest.approx(2 * abs(x[ns["door"], 1]), rel=1e-14)
    assert before["per_width"] == pytest.approx(before["drag"] / before["spread"], rel=1e-14)
    # FEMNET's printed half door spread of b1 (26.28 m) within 2 % (measured 26.63 m)
    assert before["spread"] / 2 == pytest.approx(26.28, rel=0.02)
    # the penalised objective starts at the drawn figure: every constraint holds there (its own values)
    assert ns["result"].history[0]["objective"] == pytest.approx(before["per_width"], rel=1e-12)
    assert ns["result"].history[0]["violation"] <= 1e-9
    assert ns["trim"].value <= ns["trim"].history[0]["objective"] + 1e-12
    # the rounded cut moved every corner by whole meshes from the drawn one
    from jaxnet.design import cut

    drawn = ns["space"].initial()["cut"]
    for panel, corners in ns["rounded"]["cut"].items():
        moved = np.asarray(cut.twine_to_mesh(np.asarray(corners) - np.asarray(drawn[panel])))
        np.testing.assert_allclose(moved, np.rint(moved), rtol=0, atol=1e-9)
    # re-read from its .don and re-meshed: within 2 % of the design space's figures (the frozen mesh)
    for key in ("per_width", "drag", "spread", "height"):
        assert checked[key] == pytest.approx(trimmed[key], rel=0.02), key
    assert checked["twine"] == pytest.approx(trimmed["twine"], rel=1e-9)  # the same cut: the same twine


def test_quickstart(monkeypatch):
    import jaxnet as jn

    ns = run_notebook("quickstart.ipynb", monkeypatch)
    scene, eq, forces, n, twine = ns["scene"], ns["eq"], ns["forces"], ns["n"], ns["twine"]
    tol = jn.Newton().tol
    assert eq.converged and float(eq.residual_N) <= tol
    # the net as a whole: the twines' forces cancel, so reactions + external forces = the sum of the free
    # nodes' residuals, each below the tolerance (measured: 4e-9 N against loads of 6 N)
    assert np.abs(ns["balance"]).max() <= scene.n_nodes * tol
    # immersed weight, closed form: n² meshes of 4 l0 of twine each, and the two ropes along the panel's
    # width (headline polyamide 1140 kg/m³, sinker bar lead 11340 kg/m³) in sea water
    g, rho, w = 9.81, 1025.0, n * twine.l0 * np.sqrt(2.0)
    section = lambda d: np.pi * d**2 / 4  # noqa: E731
    weight = g * (4 * n**2 * twine.l0 * section(twine.diameter) * (twine.density - rho)
                  + w * section(8e-3) * (1140.0 - rho) + w * section(0.01) * (11340.0 - rho))
    np.testing.assert_allclose(forces["weight_and_buoyancy_N"], [0.0, 0.0, -weight], rtol=1e-9, atol=1e-9)
    # the two ropes lie nearly straight across the flow: Morison drag ½ ρ Cd D L U² of both, within the 5 %
    # their bow downstream takes off (measured: 1 % less, 2.5 % at full size)
    U, cd = 0.3, 1.2
    straight = 0.5 * rho * cd * (8e-3 + 0.01) * w * U**2
    assert 0.95 * straight <= forces["drag_cables_N"][1] <= straight
    # the drag and the weight swing the panel back: tilted downstream, its foot still below the headline
    assert 0.0 < ns["angle"] < 90.0


def test_fish_cage_in_current(monkeypatch):
    import jaxnet as jn
    from jaxnet.terms import drag

    ns = run_notebook("fish_cage_in_current.ipynb", monkeypatch)
    rows, table, exponent = ns["rows"], ns["table"], ns["exponent"]
    tol = jn.Newton().tol
    assert [row["speed"] for row in rows] == ns["speeds"] and rows[0]["speed"] == 0.0
    for row in rows:
        scene, _ = ns["shapes"][row["speed"]]
        # the whole net in equilibrium: reactions (the collar held in x and y) + drag + weight and buoyancy
        # vanish to within the free nodes' residuals
        assert row["balance"] <= scene.n_nodes * tol
    # the collar is held in plan, so its drag is a rigid body's, Morison's on each bar, times the part of it in
    # the water: each end's half of ½ ρ D l0 U² (Cn sin³α + Ct |cos α|³) along x (α the bar's angle to the
    # current) weighed by its wetted depth, about clip(1/2 - z/D, 0, 1) of the pipe's diameter D (its corners
    # rounded: jaxnet.terms.drag.wetted_shares, checked against the ramp in test_drag.py). Its exponent then
    # differs from 2 by how the draught changes with the speed; the netting gives way, so its drag grows no
    # faster than U² and faster than U (measured 1.99 on the small, stiff cage, 1.55-1.93 at full size)
    rho = 1025.0
    for row in rows[1:]:
        scene, x = ns["shapes"][row["speed"]]
        bars = scene.bars
        a, b = np.asarray(bars.ends).T
        axis = x[b] - x[a]
        cos = axis[:, 0] / np.linalg.norm(axis, axis=1)
        sin = np.sqrt(1.0 - cos**2)
        d, cn = np.asarray(bars.diameter), np.asarray(bars.cd_normal)
        ct = cn * np.asarray(bars.tangential_ratio)
        wet = np.asarray(drag.wetted_shares(x, d[0], scene.environment))
        morison = 0.5 * rho * d * np.asarray(bars.rest_length) * row["speed"] ** 2 * (cn * sin**3 + ct * np.abs(cos) ** 3)
        expected = np.sum(morison * 0.5 * (wet[a] + wet[b]))
        assert 0.0 < wet[a].mean() < 1.0  # the pipe floats partly out of the water
        np.testing.assert_allclose(row["drag_collar"], expected, rtol=1e-9)
    assert np.all(exponent["drag_netting"] >= 1.0) and np.all(exponent["drag_netting"] <= 2.0 + 5e-3)
    assert np.all(exponent["drag"] <= 2.0 + 5e-3)
    # the stronger the current, the less volume the net keeps
    assert np.all(np.diff(table["volume"]) < 0.0)


def test_codend_with_catch(monkeypatch):
    import jax

    import jaxnet as jn
    from jaxnet.model import catch as catch_lib

    ns = run_notebook("codend_with_catch.ipynb", monkeypatch)
    rows, tol = ns["rows"], jn.Newton().tol
    assert [row["requested"] for row in rows] == ns["volumes"]
    # the cross-section A(s) at many abscissae s: one compiled program for every volume (the same mesh)
    sections = jax.jit(jax.vmap(catch_lib.front_area, in_axes=(None, None, 0, None, None, None)))
    for row in rows:
        scene, x = ns["shapes"][row["requested"]]
        tri, c, env = scene.netting.vertices, scene.catch, scene.environment
        sign = scene.netting.outward
        assert row["holds_the_volume"]
        # the front encloses the requested catch (whole cod-end): as the report's divergence-theorem sum,
        # and as the integral of the cross-section A(s) from the front to the rear of the net (-dV/ds = A;
        # A is piecewise quadratic in s, so 4000 trapezoids are within 1e-6; measured 7e-9)
        assert row["volume_m3"] == pytest.approx(row["requested"], rel=1e-8)
        s = np.linspace(row["front_m"], np.max(x[np.asarray(tri)] @ np.asarray(c.axis)), 4001)
        area = np.asarray(sections(x, tri, s, c.axis, c.symmetry, sign))
        assert np.trapezoid(area, s) == pytest.approx(row["requested"], rel=1e-6)
        # the axial push of the catch's pressure forces on the netting behind the front is p × the front's
        # cross-section (the divergence theorem on the closed catch), with p = ½ ρ Cd U² (4.246); the section
        # at the front is the first of A(s) above (s[0] is the front)
        p = 0.5 * float(env.water_density) * float(c.drag_coefficient) * float(env.current_speed) ** 2
        assert s[0] == row["front_m"]
        front_area = float(area[0])
        assert row["catch_force"] == pytest.approx(p * front_area, rel=1e-9)
        assert row["drag_N"] == pytest.approx(p * front_area, rel=1e-9)
        # the net in equilibrium as a whole: reactions + drag + catch pressure
        assert row["balance"] <= scene.n_nodes * tol
    # a larger catch reaches further forward, is thicker and wider, and pulls harder
    by_volume = sorted(rows, key=lambda r: r["requested"])
    for key in ("thickness_m", "diameter_m", "drag_N", "towing"):
        assert np.all(np.diff([r[key] for r in by_volume]) > 0), key
    assert np.all(np.diff([r["front_m"] for r in by_volume]) < 0)


def test_dynamics_in_waves(monkeypatch):
    from scipy.optimize import brentq

    ns = run_notebook("dynamics_in_waves.ipynb", monkeypatch)
    run, t, start, static = ns["run"], ns["t"], ns["start"], ns["static"]
    H, T, depth, ramp, collar = ns["H"], ns["T"], ns["depth"], ns["ramp"], ns["collar"]
    g, omega = 9.81, 2 * np.pi / ns["T"]
    assert t[0] == 0.0 and t[-1] == pytest.approx(ns["end"]) and int(run.figures["retries"][-1]) == 0
    # the collar follows the surface at the cage's centre, η = H/2 cos ωt, grown in over the run's start ramp by
    # the C² envelope s³ (10 - 15 s + 6 s²), s = t/R (jaxnet.water.forcing.envelope)
    assert ramp == pytest.approx(T)
    s = np.minimum(t / ramp, 1.0)
    envelope = s**3 * (10 - 15 * s + 6 * s**2)
    heave = run.positions[:, collar, 2] - start[collar, 2]
    expected = np.broadcast_to((0.5 * H * envelope * np.cos(omega * t))[:, None], heave.shape)
    np.testing.assert_allclose(heave, expected, atol=1e-9)
    # the wave's elevation at each node plotted: Airy's H/2 cos(k x - ωt), k from ω² = g k tanh(k h)
    k = brentq(lambda k_: g * k_ * np.tanh(k_ * depth) - omega**2, 1e-8, 100.0, xtol=1e-15)
    for name, i in ns["nodes"].items():
        np.testing.assert_allclose(ns["elevation"][name], 0.5 * H * envelope * np.cos(k * start[i, 0] - omega * t),
                                   atol=1e-9)
    # mean loads over the last whole period against the static ones. Along the current: drag grows as
    # u|u| of the water's velocity relative to the net, and adding a zero-mean oscillation w to a current U
    # raises its mean (U² + w² while |w| < U, 2 U |w| beyond) without passing U² + mean w²: for a net held
    # still, 1 < mean / static < 1 + (a ω coth kh)² / (2 U²), a the wave's amplitude (measured: 4.9)
    last = ns["means"][-1]
    U = float(ns["scene"].environment.current_speed)
    orbital = 0.5 * H * omega / np.tanh(k * depth)
    assert static["reaction"][0] < 0.0
    assert 1.0 < last["reaction"][0] / static["reaction"][0] < 1.0 + orbital**2 / (2 * U**2)
    # vertically: the weights are constant, the buoyancy of the collar heaving through the mean surface is
    # symmetric about its half-immersed rest, and the inertia of a periodic motion averages out over a
    # period: the mean is the static reaction to within a few % of the swing (measured 0.8 %)
    late = t >= last["window"][0]
    swing = np.ptp(run.figures["reaction_total_N"][late, 2])
    assert abs(last["reaction"][2] - static["reaction"][2]) < 0.03 * swing
    # the volume below the rest plane z = 0 (recorded) and below the heaving collar (the notebook's): with
    # the collar at z_c <= 0 and the whole net below it, they differ by the water column above the collar,
    # -z_c times the area of the collar's ring (the shoelace formula on its nodes), exactly
    ring = start[collar, :2]
    ring = ring[np.argsort(np.arctan2(ring[:, 1], ring[:, 0]))]
    ring_area = 0.5 * abs(np.dot(ring[:, 0], np.roll(ring[:, 1], -1)) - np.dot(ring[:, 1], np.roll(ring[:, 0], -1)))
    z_c = ns["collar_z"]
    below = (z_c <= 0.0) & (run.positions[:, :, 2].max(axis=1) <= z_c + 1e-12)
    assert below.sum() >= len(t) // 4
    np.testing.assert_allclose((run.figures["volume_m3"] - ns["held"])[below], -ring_area * z_c[below], rtol=1e-9,
                               atol=1e-9 * ring_area)


def test_every_notebook_has_a_test():
    tested = {"hand_vs_autodiff.ipynb", "design_panel_cuts.ipynb", "quickstart.ipynb", "fish_cage_in_current.ipynb",
              "codend_with_catch.ipynb", "dynamics_in_waves.ipynb", "design_trawl.ipynb"}
    assert {p.name for p in NOTEBOOKS.glob("*.ipynb")} == tested


@pytest.mark.parametrize("path", sorted(NOTEBOOKS.glob("*.ipynb")), ids=lambda p: p.name)
def test_saved_notebooks_show_the_full_size_and_a_3d_view(path):
    """What GitHub and Jupyter show is a full-size run (``notebooks/execute.py`` records the size it ran), every code
    cell with its outputs where it prints or draws, and at least one 3D view to turn (plotly's HTML)."""
    notebook = json.loads(path.read_text())
    assert notebook["metadata"].get("jaxnet", {}).get("size") == "full"
    code = [c for c in notebook["cells"] if c["cell_type"] == "code"]
    assert all(c["execution_count"] is not None for c in code)
    views = [o for c in code for o in c["outputs"] if "text/html" in o.get("data", {})
             and "plotly" in "".join(o["data"]["text/html"])]
    assert views and all("application/vnd.plotly.v1+json" in o["data"] for o in views)
    pictures = sum("image/png" in o.get("data", {}) for c in code for o in c["outputs"])
    assert pictures >= 1
