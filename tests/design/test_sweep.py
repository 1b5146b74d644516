"""Design sweeps on a cluster (jaxnet.design.sweep), on a real local Dask cluster of two worker processes.

The net is the hanging panel of 8 x 8 meshes (51 nodes, still water), meshed by the recipe on each worker.
Six named designs: four valid ones (mesh side, twine diameter, a moved cut corner, the headline's hanging
ratio), one refused by DesignSpace.check (a negative mesh side) and one whose equilibrium does not converge
(a mesh side of 40 mm, 1.6 times the drawing's, which takes 73 pure Newton steps from the reference
equilibrium, given 20 here). The figures are the smooth largest tension (N) and the deployed netting area
(m²).

What could be wrong and is checked: a worker's reused state (design space, start, compiled programs) giving
a design anything but its own equilibrium, or the rows being mixed up between designs (each figure against a
single-process solve of the same design from the same start, 1e-9 relative); a failure stopping the sweep
or losing its reason; a row not written as it arrived; the work not spread over the two workers; a resumed
sweep solving again what the file holds (the tasks the scheduler ran are counted); bad input reaching the
cluster (a stand-in for the cluster that fails the test is put in place) instead of a ValueError naming it.
"""

import concurrent.futures
import dataclasses
import json

import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.design import objectives
from jaxnet.design import sweep as sw
from jaxnet.design.space import DesignSpace
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import adjoint_statics, results, statics
from jaxnet.solve.options import DIFFERENTIABLE

from distributed import get_task_stream
from panels import SMOOTH  # tests/panels.py

RECIPE = (hanging_panel, {"meshes": 8, "step": 0.05, **SMOOTH})
#: 20 pure Newton steps at most: the 40 mm design needs 73
SOLVER = dataclasses.replace(DIFFERENTIABLE, max_iter=20)
FIGURES = {"tension": objectives.max_tension(), "area": objectives.netting_area(deployed=True)}
GOOD = {
    "l0 24 mm": {"mesh_side": {"netting": 0.024}},
    "l0 23 mm thick": {"mesh_side": {"netting": 0.023}, "twine_diameter": {"netting": 2e-3}},
    "cut": None,  # corner 1 moved along U (set in designs())
    "headline E 0.6": {"hanging_ratio": {"headline": 0.6}},
}
INVALID, DIVERGING = "negative l0", "l0 40 mm"


def designs(space):
    out = dict(GOOD)
    cut = np.array(space.initial()["cut"]["netting"])
    cut[1, 0] -= 0.05
    out["cut"] = {"cut": {"netting": cut}}
    out[INVALID] = {"mesh_side": {"netting": -0.01}}
    out[DIVERGING] = {"mesh_side": {"netting": 0.04}}
    return out


@pytest.fixture(scope="module")
def space():
    return DesignSpace(hanging_panel(**RECIPE[1]))


@pytest.fixture(scope="module")
def client():
    """A local cluster of two worker processes, one thread each, made as sweep() makes its own."""
    client, to_close = sw._connect(None, 2)
    client.wait_for_workers(2)
    yield client
    for thing in to_close:
        thing.close()


def single_process(space):
    """{design: (figures, iterations)} of the good designs, solved in this process from the reference
    equilibrium."""
    adjoint = adjoint_statics.Adjoint(space.reference, SOLVER)
    start = adjoint.solve(space.reference, statics.solve(space.reference).x).x
    out = {}
    for name, theta in designs(space).items():
        if name in GOOD:
            scene = space.scene(theta)
            eq = adjoint.solve(scene, start)
            assert int(eq.status) == results.CONVERGED
            outcome = objectives.Outcome(eq.x, scene, adjoint.model)
            out[name] = ({k: float(f(outcome)) for k, f in FIGURES.items()}, int(eq.iterations))
    return out


def test_sweep_on_two_workers(client, space, tmp_path):
    out = tmp_path / "sweep"
    given = designs(space)
    # the sweep from a thread of this process while it solves the designs itself: its compilations use the
    # core the workers' leave idle
    with get_task_stream(client) as first_tasks, concurrent.futures.ThreadPoolExecutor(1) as pool:
        swept = pool.submit(sw.sweep, RECIPE, given, FIGURES, address=client, out=out, solver=SOLVER, progress=False,
                            cache=tmp_path / "cache")
        alone = single_process(space)
        table = swept.result()
    assert [row["design"] for row in table] == list(given)

    # (a) every good design's figures are those of its own single-process solve
    for row in table.done:
        figures, iterations = alone[row["design"]]
        for name, value in figures.items():
            assert row[name] == pytest.approx(value, rel=1e-9, abs=0.0), (row["design"], name)
        assert row["iterations"] == iterations
        assert row["residual_N"] <= SOLVER.tol
    # (b) the two failures are rows with their reasons, and the others were done
    assert sorted(row["design"] for row in table.done) == sorted(GOOD)
    failed = {row["design"]: row for row in table.failed}
    assert sorted(failed) == [DIVERGING, INVALID]
    assert "mesh_side['netting']" in failed[INVALID]["reason"] and "must be > 0" in failed[INVALID]["reason"]
    assert failed[DIVERGING]["reason"].startswith("SolveError: maximum number of iterations")
    assert failed[DIVERGING]["iterations"] == SOLVER.max_iter
    assert all(failed[d]["tension"] is None for d in failed)
    # (c) one row a design in the file, as returned (its θ entries included)
    written = [json.loads(line) for line in (out / sw.ROWS_FILE).read_text().splitlines()]
    assert sorted(row["design"] for row in written) == sorted(given)
    assert {row["design"]: row for row in written} == {row["design"]: row for row in table}
    cut_row = next(row for row in written if row["design"] == "cut")
    np.testing.assert_array_equal(cut_row["cut[netting]"], given["cut"]["cut"]["netting"])
    # (d) both worker processes solved designs, each its first task building its workspace once
    assert len(first_tasks.data) == len(given)
    workers = {row["worker"] for row in table}
    assert workers == set(client.scheduler_info()["workers"]) and len(workers) == 2
    assert all(n == 1 for n in client.nthreads().values())
    for worker in workers:
        built = [row["setup_s"] > 0 for row in table if row["worker"] == worker]
        assert built.count(True) == 1, worker

    # (e) resumed with one more design, by the scheduler's address: only that one is solved
    more = {**given, "l0 24.5 mm": {"mesh_side": {"netting": 0.0245}}}
    before = (out / sw.ROWS_FILE).read_text()
    with get_task_stream(client) as resumed_tasks:
        again = sw.sweep(RECIPE, more, FIGURES, address=client.scheduler.address, out=out, solver=SOLVER,
                         progress=False, cache=tmp_path / "cache")
    assert len(resumed_tasks.data) == 1 and again.solved == 1
    after = (out / sw.ROWS_FILE).read_text()
    assert after.startswith(before) and len(after.splitlines()) == len(more)
    assert again.rows[:len(given)] == table.rows
    assert again.rows[-1]["status"] == "done" and again.rows[-1]["setup_s"] == 0.0  # workspace reused


def test_rows_file_cut_short(tmp_path):
    """A sweep stopped while writing leaves a partial last line: it is cut off and that design solved again."""
    path = tmp_path / sw.ROWS_FILE
    rows = [{"design": 0, "status": "done"}, {"design": 1, "status": "failed"}]
    path.write_text("".join(json.dumps(r) + "\n" for r in rows) + '{"design": 2, "sta')
    assert sw._read_rows(path) == rows
    assert path.read_text() == "".join(json.dumps(r) + "\n" for r in rows)


@pytest.fixture
def no_cluster(monkeypatch):
    """sweep() fails the test if it gets as far as connecting to a cluster."""
    def refuse(*_):
        raise AssertionError("sweep() reached the cluster with bad input")

    monkeypatch.setattr(sw, "_connect", refuse)


def _local():
    """A recipe function that is not at the top level of a module."""
    return lambda: hanging_panel(meshes=2)


def _not_a_net(meshes=2):
    return {"meshes": meshes}


@pytest.mark.parametrize("recipe, designs_, figures, match", [
    (RECIPE, [], FIGURES, "no designs"),
    (RECIPE, {}, FIGURES, "no designs"),
    (RECIPE, {"a": {}}, {}, "non-empty dict"),
    (RECIPE, {"a": {}}, {"tension": 3.0}, "figure 'tension' is not callable"),
    (RECIPE, {"a": {}}, {"status": objectives.max_tension()}, "figure name 'status'"),
    (_local(), {"a": {}}, FIGURES, "top level of a module"),
    ((_not_a_net, {"meshes": 3}), {"a": {}}, FIGURES, r"recipe .*_not_a_net\(meshes=3\) does not build"),
    ((hanging_panel, {"mesh": 3}), {"a": {}}, FIGURES, r"recipe .*hanging_panel\(mesh=3\) does not build"),
    ("case.txt", {"a": {}}, FIGURES, "not a FEMNET case"),
    ("nowhere/case.don", {"a": {}}, FIGURES, "no such FEMNET case"),
    (42, {"a": {}}, FIGURES, "the recipe must be"),
    (RECIPE, [{}, {}, {"mesh_sides": {"netting": 0.02}}], FIGURES, "design 2: .*unknown family 'mesh_sides'"),
    (RECIPE, {"wide": {"mesh_side": {"net": 0.02}}}, FIGURES, r"design 'wide': mesh_side: no entry 'net'"),
    (RECIPE, {"wide": {"cut": {"netting": np.zeros(3)}}}, FIGURES, r"design 'wide': cut\['netting'\]: expected shape"),
    (RECIPE, {"wide": {"mesh_side": {"netting": "big"}}}, FIGURES, r"design 'wide': mesh_side\['netting'\] is not"),
])
def test_bad_input_before_any_worker(no_cluster, recipe, designs_, figures, match):
    with pytest.raises(ValueError, match=match):
        sw.sweep(recipe, designs_, figures, progress=False, cache=None)


def test_bad_worker_count(no_cluster):
    with pytest.raises(ValueError, match="n_workers must be a positive integer"):
        sw.sweep(RECIPE, {"a": {}}, FIGURES, n_workers=0, progress=False, cache=None)


def test_resume_refuses_another_design(no_cluster, tmp_path):
    """A file holding design 'a' with another θ is not taken for it."""
    row = {"design": "a", "mesh_side[netting]": 0.02, "tension": 1.0, "status": "done",
           "recipe": sw.Recipe.of(RECIPE).label}
    (tmp_path / sw.ROWS_FILE).write_text(json.dumps(row) + "\n")
    with pytest.raises(ValueError, match="design 'a' in the sweep file has another θ"):
        sw.sweep(RECIPE, {"a": {"mesh_side": {"netting": 0.021}}}, {"tension": objectives.max_tension()},
                 out=tmp_path, progress=False, cache=None)
