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
    # whole meshes: every side of every panel whole steps (integer du, dv from corner 0)
    for sides in best["report"].values():
        for side in sides:
            assert side.du == round(side.du) and side.dv == round(side.dv)
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


def test_every_notebook_has_a_test():
    tested = {"hand_vs_autodiff.ipynb", "design_panel_cuts.ipynb"}
    assert {p.name for p in NOTEBOOKS.glob("*.ipynb")} == tested
