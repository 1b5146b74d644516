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


def test_every_notebook_has_a_test():
    tested = {"hand_vs_autodiff.ipynb"}
    assert {p.name for p in NOTEBOOKS.glob("*.ipynb")} == tested
