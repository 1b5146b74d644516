"""Time series of dynamic runs (jaxnet.io.timeseries): read back bit for bit, survive a kill, resume exactly."""

import io
import json
import os
import pathlib
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import figures as figures_lib
from jaxnet.io import timeseries as ts
from jaxnet.io.progress import Progress
from jaxnet.scene import Bars, Netting, Nodes, Scene


def tiny_scene():
    """Two netting triangles (a square of side 0.1 m in the x-z plane) and a bar hanging below: 5 nodes."""
    pos = np.array([[0.0, 0, 0], [0.1, 0, 0], [0.1, 0, -0.1], [0.0, 0, -0.1], [0.05, 0, -0.3]])
    fixed = np.zeros((5, 3), bool)
    fixed[:2] = True
    nodes = Nodes(position=pos, fixed=fixed, mass=np.full(5, 0.01), volume=np.zeros(5), force=np.zeros((5, 3)))
    netting = Netting(vertices=np.array([[0, 1, 2], [0, 2, 3]]),
                      uv=np.array([[[0.0, 0], [2, -2], [4, 0]], [[0.0, 0], [4, 0], [2, 2]]]),
                      l0=np.full(2, 0.03), ea_traction=np.full(2, 2000.0), ea_compression=np.zeros(2),
                      diameter=np.full(2, 1.5e-3), density=np.full(2, 1140.0), panel=np.zeros(2, int))
    bars = Bars(ends=np.array([[2, 4]]), rest_length=np.array([0.2]), ea_traction=np.array([1e4]),
                ea_compression=np.array([0.0]), diameter=np.array([0.008]), density=np.array([1140.0]),
                cable=np.array([0]))
    return Scene(nodes=nodes, netting=netting, bars=bars, panel_names=("square",), cable_names=("pendant",))


def record(k, n=5):
    """Record k of a made-up run (a swinging net); irrational values so that any rounding shows."""
    t = 0.05 * k + np.pi * 1e-3
    rng = np.random.default_rng(k)
    pos = tiny_scene().nodes.position + 0.01 * np.sin(2.3 * t) * np.array([1.0, 0.3, 0.1])
    vel = rng.standard_normal((n, 3)) / 3.0
    figs = {"reaction_N": rng.standard_normal((n, 3)), "drag_netting_N": rng.standard_normal(3),
            "volume_m3": float(np.exp(-t)), "newton_iterations": 3 + k % 4, "time_step_s": 0.05 / 7}
    ckpt = {"previous_position": pos - 0.05 * vel, "time_step_s": np.asarray(0.05 / 7), "k": np.asarray(k)}
    return ts.Record(time=t, step=7 * k, position=pos, velocity=vel, figures=figs), ckpt


def assert_record_equal(a, b):
    assert a.time == b.time and a.step == b.step
    assert np.array_equal(a.position, b.position) and np.array_equal(a.velocity, b.velocity)
    assert set(a.figures) == set(b.figures)
    for name in a.figures:
        assert np.array_equal(a.figures[name], b.figures[name]), name
        assert type(a.figures[name]) is type(b.figures[name]), name  # an iteration count stays an int


def reference_series(n_records):
    """What the series of records 0..n_records-1 must read as."""
    recs = [record(k)[0] for k in range(n_records)]
    out = {"time": np.array([r.time for r in recs]), "step": np.array([r.step for r in recs]),
           "position": np.stack([r.position for r in recs]), "velocity": np.stack([r.velocity for r in recs])}
    for name in recs[0].figures:
        out[name] = np.stack([np.asarray(r.figures[name]) for r in recs])
    return out


def assert_series_equal(got, want):
    assert set(got) == set(want)
    for name in want:
        assert got[name].shape == want[name].shape, name
        assert np.array_equal(got[name], want[name]), name


def write_run(out, ks, vtk=False, resume=False, close=True):
    w = ts.SeriesWriter(out, tiny_scene(), vtk=vtk, resume=resume)
    for k in ks:
        w.write(*record(k))
    if close:
        w.close()
    return w


def test_records_read_back_bit_exactly_from_append_only_raw_files(tmp_path):
    r, n = 6, 5
    write_run(tmp_path, range(r))
    want = reference_series(r)
    got = ts.read_series(tmp_path)
    assert_series_equal(got, want)
    assert got["step"].dtype == np.int64 and got["newton_iterations"].dtype == np.int64
    with np.load(tmp_path / "series.npz") as z:
        assert_series_equal({k: z[k] for k in z.files}, want)
    # one fixed-size record per write, nothing rewritten: R * N * 3 float64 positions, R * 3 drag values
    assert (tmp_path / "raw" / "position.bin").stat().st_size == r * n * 3 * 8
    assert (tmp_path / "raw" / "figure.drag_netting_N.bin").stat().st_size == r * 3 * 8
    index = json.loads((tmp_path / "series.json").read_text())
    assert index["records"] == r and index["scene"]["n_nodes"] == n and index["scene"]["n_elements"] == 3
    rec, ckpt = ts.resume_point(tmp_path)
    assert_record_equal(rec, record(r - 1)[0])
    assert set(ckpt) == {"previous_position", "time_step_s", "k"} and int(ckpt["k"]) == r - 1


def test_killed_run_keeps_complete_records_and_resumes_to_the_uninterrupted_series(tmp_path):
    full, killed = tmp_path / "full", tmp_path / "killed"
    write_run(full, range(8), vtk=True)
    w = write_run(killed, range(5), vtk=True, close=False)  # never closed: killed
    # the 6th record was being written: part of its positions reached the raw file, and a temporary .vtu
    with open(killed / "raw" / "position.bin", "ab") as f:
        f.write(record(5)[0].position.tobytes()[:37])
    (killed / "net_00005.partial.vtu").write_bytes(b"<VTKFile")
    assert not (killed / "series.npz").exists()
    assert_series_equal(ts.read_series(killed), reference_series(5))
    rec, ckpt = ts.resume_point(killed)
    assert_record_equal(rec, record(4)[0])
    want_ckpt = record(4)[1]
    assert all(np.array_equal(ckpt[name], want_ckpt[name]) for name in want_ckpt)
    del w
    w = ts.SeriesWriter(killed, tiny_scene(), vtk=True, resume=True)
    assert_record_equal(w.resumed[0], record(4)[0])
    for k in range(5, 8):
        w.write(*record(k))
    w.close()
    with np.load(killed / "series.npz") as a, np.load(full / "series.npz") as b:
        assert sorted(a.files) == sorted(b.files)
        for name in b.files:
            assert np.array_equal(a[name], b[name]), name
    # the ParaView collection kept the first run's entries
    assert (killed / "series.pvd").read_text() == (full / "series.pvd").read_text()
    assert not list(killed.glob("*.partial*"))


def test_killed_between_checkpoint_and_index_rolls_the_index_forward(tmp_path):
    write_run(tmp_path, range(5), close=False)
    index_of_5 = (tmp_path / "series.json").read_bytes()
    w = write_run(tmp_path, [], resume=True, close=False)
    w.write(*record(5))
    # killed after the checkpoint of record 5 was replaced, before the index counting it was
    (tmp_path / "series.json").write_bytes(index_of_5)
    assert len(ts.read_series(tmp_path)["time"]) == 5
    rec, ckpt = ts.resume_point(tmp_path)
    assert_record_equal(rec, record(5)[0])
    assert int(ckpt["k"]) == 5
    write_run(tmp_path, [6, 7], resume=True)
    assert_series_equal(ts.read_series(tmp_path), reference_series(8))


CHILD = """
import sys
sys.path.insert(0, {tests!r})
from test_timeseries import record, tiny_scene
from jaxnet.io import timeseries as ts
w = ts.SeriesWriter({out!r}, tiny_scene(), vtk=False)
for k in range(100000):
    w.write(*record(k))
"""


def test_sigkill_at_any_moment_leaves_a_consistent_resumable_series(tmp_path):
    out = tmp_path / "run"
    env = dict(os.environ, JAX_PLATFORMS="cpu")
    child = subprocess.Popen([sys.executable, "-c", CHILD.format(tests=str(pathlib.Path(__file__).parent), out=str(out))],
                             env=env)
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            try:
                if json.loads((out / "series.json").read_text())["records"] >= 30:
                    break
            except (FileNotFoundError, json.JSONDecodeError, KeyError):
                pass
            assert child.poll() is None, "the writing process died"
            time.sleep(0.01)
        os.kill(child.pid, signal.SIGKILL)
    finally:
        child.wait()
    series = ts.read_series(out)
    r = len(series["time"])
    assert r >= 30
    assert_series_equal(series, reference_series(r))
    rec, _ = ts.resume_point(out)
    c = rec.step // 7 + 1
    assert c in (r, r + 1)  # the checkpoint is at most one record ahead of the index
    write_run(out, range(c, c + 2), resume=True)
    assert_series_equal(ts.read_series(out), reference_series(c + 2))


def test_pvd_lists_every_vtu_with_its_time_and_the_vtu_holds_the_state(tmp_path):
    scene = tiny_scene()
    write_run(tmp_path, range(3), vtk=True)
    root = ET.parse(tmp_path / "series.pvd").getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    datasets = root.find("Collection").findall("DataSet")
    assert [d.get("file") for d in datasets] == ["net_00000.vtu", "net_00001.vtu", "net_00002.vtu"]
    assert [float(d.get("timestep")) for d in datasets] == [record(k)[0].time for k in range(3)]
    rec = record(2)[0]
    mesh = meshio.read(tmp_path / "net_00002.vtu")
    assert np.array_equal(mesh.points, rec.position)
    assert np.array_equal(mesh.point_data["velocity_m_s"], rec.velocity)
    tw = figures_lib.twine_tensions(scene, rec.position)
    np.testing.assert_allclose(mesh.cell_data["twine_tension_U_N"][0], tw[:, 0], rtol=1e-12)
    np.testing.assert_allclose(mesh.cell_data["bar_tension_N"][1], figures_lib.bar_tensions(scene, rec.position), rtol=1e-12)


def test_records_that_do_not_fit_the_series_raise_naming_the_culprit_and_write_nothing(tmp_path):
    w = write_run(tmp_path, [0], close=False)
    rec, ckpt = record(1)
    bad_shape = ts.Record(rec.time, rec.step, rec.position, rec.velocity, {**rec.figures, "reaction_N": np.zeros((4, 3))})
    with pytest.raises(ts.SeriesError, match=r"figure 'reaction_N' has shape \(4, 3\), the first record's was \(5, 3\)"):
        w.write(bad_shape, ckpt)
    missing = ts.Record(rec.time, rec.step, rec.position, rec.velocity, {k: v for k, v in rec.figures.items() if k != "volume_m3"})
    with pytest.raises(ts.SeriesError, match="figure 'volume_m3' is missing"):
        w.write(missing, ckpt)
    fractional = ts.Record(rec.time, rec.step, rec.position, rec.velocity, {**rec.figures, "newton_iterations": 3.5})
    with pytest.raises(ts.SeriesError, match="figure 'newton_iterations' is an integer"):
        w.write(fractional, ckpt)
    earlier = ts.Record(0.0, 0, rec.position, rec.velocity, rec.figures)
    with pytest.raises(ts.SeriesError, match="does not come after"):
        w.write(earlier, ckpt)
    assert (tmp_path / "raw" / "position.bin").stat().st_size == 1 * 5 * 3 * 8
    w.write(rec, ckpt)
    w.close()
    assert_series_equal(ts.read_series(tmp_path), reference_series(2))


def test_resume_refuses_the_series_of_another_scene(tmp_path):
    write_run(tmp_path, range(2))
    scene = tiny_scene()
    other = Scene(nodes=scene.nodes, netting=scene.netting)
    with pytest.raises(ts.SeriesError, match="3 elements"):
        ts.SeriesWriter(tmp_path, other, vtk=False, resume=True)


def test_progress_shows_time_step_rate_and_mean_newton_iterations():
    out = io.StringIO()
    with Progress(0.0, 2.0, file=out, mininterval=0, steps0=10) as bar:
        for step, (t, its) in enumerate([(0.5, 3), (1.0, 5), (1.5, 6)], start=11):
            bar.update(t, step, its)
        assert bar.newton_per_step == 14 / 3
        assert bar.steps_per_second > 0
    text = out.getvalue()
    assert "t = 1.5/2 s" in text and "4.67 Newton it./step" in text and "steps/s" in text
    # a run resumed at 6 s of 12: the bar is the whole run's, starting at 6 s (half done)
    resumed = io.StringIO()
    with Progress(6.0, 12.0, file=resumed, mininterval=0, steps0=600) as bar:
        bar.update(9.0, 900, 1200)
    assert "t = 9/12 s" in resumed.getvalue() and " 75%" in resumed.getvalue()
    quiet = Progress(0.0, 1.0, disable=True, file=out)
    quiet.update(0.5, 2, 7)
    quiet.close()
    assert quiet.newton_per_step == 3.5 and out.getvalue() == text
