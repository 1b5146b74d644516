"""`jaxnet run`: the default scene and a scene file, with result.json, VTK and PNG written."""

import json
import pathlib
import subprocess
import sys

import meshio
import numpy as np
import pytest

from jaxnet import cli


def test_default_scene_is_a_cage_in_current(tmp_path, capsys):
    assert cli.main(["run", "--out", str(tmp_path), "--no-cache"]) == 0
    printed = capsys.readouterr().out
    assert "newton" in printed and "converged in" in printed and "cage" in printed
    result = json.loads((tmp_path / "result.json").read_text())
    for key in ("converged", "iterations", "residual_N", "n_nodes", "n_elements", "n_dof", "reaction_N", "wall_s",
                "compile_s", "forces_N", "enclosed_volume_m3"):
        assert key in result
    assert result["converged"] and result["residual_N"] <= 1e-3
    forces = result["forces_N"]
    # balance of the whole net: the moorings hold what drag, weight and buoyancy put on it
    total = np.sum([forces[k] for k in forces], axis=0) + np.asarray(result["reaction_N"])
    np.testing.assert_allclose(total, 0.0, atol=result["n_nodes"] * 1e-3)
    assert forces["drag_netting_N"][0] > 0 and forces["drag_cables_N"][0] > 0  # the current flows along +x
    # the cage keeps part of its 8-sided start volume (8 · ½ R² sin 45° · depth)
    start = 8 * 0.5 * 5.0**2 * np.sin(np.pi / 4) * 5.0
    assert 0.3 * start < result["enclosed_volume_m3"] < start
    mesh = meshio.read(tmp_path / "net.vtu")
    assert len(mesh.points) == result["n_nodes"]
    tu, tv = mesh.cell_data["twine_tension_U_N"][0], mesh.cell_data["twine_tension_V_N"][0]
    assert len(tu) == result["n_triangles"]
    np.testing.assert_allclose(max(tu.max(), tv.max()), result["max_twine_tension_N"], rtol=1e-12)
    assert (tmp_path / "net.png").stat().st_size > 10_000


def test_hanging_scene_reaction_carries_the_weight(tmp_path):
    assert cli.main(["run", "--scene", "hanging", "--out", str(tmp_path), "--quiet", "--no-cache"]) == 0
    result = json.loads((tmp_path / "result.json").read_text())
    # the fixings carry the whole immersed weight (within the residual left on the free nodes)
    assert abs(result["reaction_N"][2] + result["load_N"][2]) <= result["n_nodes"] * 1e-3
    assert result["load_N"][2] < 0
    np.testing.assert_allclose(result["forces_N"]["weight_and_buoyancy_N"], result["load_N"], rtol=1e-12)


def test_closed_form_stiffness_gives_the_same_answer(tmp_path):
    results = {}
    for path in ("autodiff", "closed_form"):
        out = tmp_path / path
        assert cli.main(["run", "--scene", "hanging", "--out", str(out), "--quiet", "--no-cache", "--stiffness", path]) == 0
        results[path] = json.loads((out / "result.json").read_text())
    a, c = results["autodiff"], results["closed_form"]
    np.testing.assert_allclose(c["reaction_N"], a["reaction_N"], rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(c["bounding_box_m"], a["bounding_box_m"], rtol=1e-9, atol=1e-9)


def wall_scene(w=0.5):
    """A scene file: a weightless square wall held on three sides, pulled down by 2 N along the fourth."""
    return {
        "environment": {"gravity": 0.0},
        "twines": {"pa": {"l0": 0.02, "ea": 1000.0, "diameter": 0.001}},
        "panels": [{"name": "wall", "step": 0.1, "twine": "pa",
                    "corners": [[0, 0, 0, 0, 0], [w, 0, 0, 10, -10], [w, 0, w, 20, 0], [0, 0, w, 10, 10]]}],
        "fix": [{"at": {"panel": "wall", "side": 2}}, {"at": {"panel": "wall", "side": 1}}, {"at": {"panel": "wall", "side": 3}}],
        "attach": [{"at": {"panel": "wall", "side": 0}, "force": [0, 0, -2.0]}],
    }


def test_scene_file_and_bad_scene_file(tmp_path, capsys):
    doc = wall_scene()
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet", "--no-cache"]) == 0
    result = json.loads((tmp_path / "out" / "result.json").read_text())
    np.testing.assert_allclose(result["reaction_N"], [0, 0, 2.0], atol=result["n_nodes"] * 1e-3)
    doc["panels"][0]["stepp"] = 1
    path.write_text(json.dumps(doc))
    assert cli.main(["run", str(path), "--out", str(tmp_path / "bad"), "--no-cache"]) == 2
    assert "unknown key(s) ['stepp']" in capsys.readouterr().err


def test_compiled_programs_are_kept_on_disk_and_reused(tmp_path):
    """The solver's compiled programs (evaluation, tangent, scatter, spring network, loads, and the primal-dual
    method's rod programs with their own scatter and spring metric) and the one of the result's figures (tensions, opening angles, forces by term: :func:`jaxnet.figures.net_figures`) are kept on
    disk whole
    (:mod:`jaxnet.solve.programs`): a second process solving the same scene loads them, compiles nothing
    (no new program, none rewritten, no new entry in JAX's own cache) and gives the same answer; a damaged
    program file is compiled again and replaced, never trusted. Run in subprocesses: the cache is
    process-wide JAX configuration."""
    cache = tmp_path / "cache"
    programs = cache / "jaxnet-programs"

    def run(out):
        cmd = [sys.executable, "-m", "jaxnet.cli", "run", "--scene", "hanging", "--quiet", "--cache", str(cache),
               "--out", str(tmp_path / out)]
        subprocess.run(cmd, check=True, capture_output=True)
        return (json.loads((tmp_path / out / "result.json").read_text()),
                {p.name: p.stat().st_mtime_ns for p in programs.iterdir()}, set(p.name for p in cache.iterdir()))

    first, kept, entries = run("a")
    assert sorted(name.split("-")[0] for name in kept) == [
        "evaluate", "loads", "net_figures", "rod_blocks", "rod_measure", "rod_pull", "rod_rate", "scatter", "scatter",
        "springs", "springs", "tangent"]
    second, kept_after, entries_after = run("b")
    assert kept_after == kept and entries_after == entries  # loaded: nothing compiled, nothing written
    assert second["iterations"] == first["iterations"]
    # to rounding of the largest component (a component that is zero to rounding may differ in its own digits
    # where sums run in another order: a GPU's reductions)
    np.testing.assert_allclose(second["reaction_N"], first["reaction_N"], rtol=1e-12,
                               atol=1e-12 * np.abs(first["reaction_N"]).max())
    damaged = next(name for name in kept if name.startswith("tangent-"))
    (programs / damaged).write_bytes(b"not a program")
    third, kept_third, _ = run("c")
    assert set(kept_third) == set(kept) and kept_third[damaged] != kept[damaged]  # compiled again, replaced
    assert third["iterations"] == first["iterations"]
    np.testing.assert_allclose(third["reaction_N"], first["reaction_N"], rtol=1e-12)


def test_a_dynamic_run_keeps_its_programs_and_a_resumed_run_loads_them(tmp_path):
    """A run in time keeps its step's programs on disk (the step's setup, its evaluation and tangent, as the
    static solver's): resumed in a fresh process, it loads them and compiles nothing (no program written, no
    new entry in JAX's own cache), and its records go on as one run's."""
    from jaxnet.io import timeseries

    path = tmp_path / "scene.json"
    path.write_text(json.dumps(wall_scene()))
    cache, out = tmp_path / "cache", tmp_path / "dyn"
    programs = cache / "jaxnet-programs"

    def run(*extra):
        cmd = [sys.executable, "-m", "jaxnet.cli", "run", str(path), "--dynamic", "--dt", "0.01", "--record", "0.05",
               "--quiet", "--cache", str(cache), "--out", str(out), *extra]
        subprocess.run(cmd, check=True, capture_output=True)
        return {p.name: p.stat().st_mtime_ns for p in programs.iterdir()}, set(p.name for p in cache.iterdir())

    kept, entries = run("--end", "0.1")
    assert {"step_setup", "evaluate", "tangent", "scatter", "springs", "loads"} <= {n.split("-")[0] for n in kept}
    kept_after, entries_after = run("--end", "0.2", "--resume")
    assert kept_after == kept and entries_after == entries  # loaded: nothing compiled, nothing written
    np.testing.assert_allclose(timeseries.read_series(out)["time"], [0.0, 0.05, 0.1, 0.15, 0.2], atol=1e-12)


def test_dynamic_run_of_a_net_at_rest_stays_at_rest_and_resumes(tmp_path):
    """`jaxnet run SCENE --dynamic`: started at its static equilibrium under constant loads, a net stays there
    (reactions constant, no motion); a stopped run resumed with a later end time continues its records."""
    doc = wall_scene()
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(doc))
    out = tmp_path / "dyn"
    args = ["run", str(path), "--dynamic", "--dt", "0.01", "--record", "0.05", "--out", str(out), "--quiet", "--no-cache"]
    assert cli.main(args + ["--end", "0.1"]) == 0
    assert cli.main(args + ["--end", "0.2", "--resume"]) == 0
    from jaxnet.io import timeseries

    series = timeseries.read_series(out)
    np.testing.assert_allclose(series["time"], [0.0, 0.05, 0.1, 0.15, 0.2], atol=1e-12)
    assert np.abs(series["position"] - series["position"][:1]).max() < 1e-6
    np.testing.assert_allclose(series["reaction_total_N"], np.tile([0.0, 0.0, 2.0], (5, 1)), atol=5e-3)
    assert (out / "series.pvd").exists() and (out / "series.npz").exists() and (out / "run.png").exists()


def _dynamic_don(tmp_path):
    """FEMNET's nr_netting made a dynamic case: a time step of 0.05 s, records every 0.1 s to 1 s."""
    text = (pathlib.Path(__file__).parent / "data" / "femnet" / "nr_netting.don").read_text()
    for label, value in (("Dynamic: Time step (s):", "0.05"), ("Dynamic: Record time step (s):", "0.1"),
                         ("Dynamic: End time of record and calculation (s):", "1.0")):
        head, rest = text.split(label, 1)
        old = rest.split()[0]
        text = head + label + rest.replace(old, value, 1)
    path = tmp_path / "nr_netting_dynamic.don"
    path.write_text(text)
    return path


def test_a_dynamic_run_takes_the_case_numerics_and_the_solver_flags(tmp_path):
    """`jaxnet run CASE.don --dynamic`: each time step's Newton takes FEMNET's threshold, iterations and
    displacement limit from the file, and --tol, --max-iter and --stiffness replace them as in a static run."""
    from jaxnet.solve.options import TIME_STEP

    path = _dynamic_don(tmp_path)
    args = cli.argument_parser().parse_args(["run", str(path), "--dynamic"])
    case, _ = cli.case_of(args, dynamic=True)
    settings, implicit = cli.time_stepping(case, args)
    assert (settings.end_time, settings.record_every, implicit.time_step) == (1.0, 0.1, 0.05)
    newton = implicit.newton
    assert (newton.tol, newton.max_iter, newton.max_step) == (0.001, 10000, 10.0)  # the file's numerics
    assert (newton.damping, newton.line_search, newton.stall_window) == (TIME_STEP.damping, TIME_STEP.line_search, None)
    flags = ["--tol", "2e-4", "--max-iter", "7", "--stiffness", "autodiff", "--dt", "0.02"]
    args = cli.argument_parser().parse_args(["run", str(path), "--dynamic", *flags])
    _, implicit = cli.time_stepping(case, args)
    newton = implicit.newton
    assert (newton.tol, newton.max_iter, newton.stiffness, newton.max_step) == (2e-4, 7, "autodiff", 10.0)
    assert implicit.time_step == 0.02


def test_a_dynamic_run_of_a_scene_file_takes_the_solver_flags(tmp_path):
    from jaxnet.solve.options import TIME_STEP

    path = tmp_path / "scene.json"
    path.write_text(json.dumps(wall_scene()))
    args = cli.argument_parser().parse_args(["run", str(path), "--dynamic", "--tol", "5e-5", "--max-iter", "12"])
    case, _ = cli.case_of(args, dynamic=True)
    settings, implicit = cli.time_stepping(case, args)
    assert settings.end_time is None  # a scene file has no end time: --end must say
    assert (implicit.newton.tol, implicit.newton.max_iter) == (5e-5, 12)
    assert implicit.newton.damping == TIME_STEP.damping and implicit.time_step == 0.01


def test_a_dynamic_run_stopped_by_ctrl_c_says_how_to_resume_and_resumes(tmp_path, monkeypatch, capsys):
    """Ctrl-C during `jaxnet run --dynamic`: the records written so far are kept, a one-line hint gives the
    command that continues the run (exit status 130), and that command finishes it as one run would."""
    from jaxnet.io import timeseries
    from jaxnet.solve import dynamics

    path = tmp_path / "scene.json"
    path.write_text(json.dumps(wall_scene()))
    out = tmp_path / "dyn"
    args = ["run", str(path), "--dynamic", "--dt", "0.01", "--record", "0.05", "--end", "0.2", "--out", str(out),
            "--quiet", "--no-cache"]
    advance, calls = dynamics.Stepper.advance, []

    def interrupted(self, *a, **k):
        calls.append(1)
        if len(calls) == 3:  # during the third record interval
            raise KeyboardInterrupt
        return advance(self, *a, **k)

    monkeypatch.setattr(dynamics.Stepper, "advance", interrupted)
    assert cli.main(args) == 130
    err = capsys.readouterr().err
    assert "its records in" in err and "end at t = 0.1 s" in err
    hint = err.split("Continue with: jaxnet ")[1].strip()
    assert hint.endswith("--resume") and str(out) in hint
    assert len(timeseries.read_series(out)["time"]) == 3  # t = 0, 0.05, 0.1
    monkeypatch.setattr(dynamics.Stepper, "advance", advance)
    import shlex

    assert cli.main(shlex.split(hint)) == 0
    np.testing.assert_allclose(timeseries.read_series(out)["time"], [0.0, 0.05, 0.1, 0.15, 0.2], atol=1e-12)


def test_a_dynamic_run_of_a_case_with_a_winch_pays_out_its_cable(tmp_path, capsys):
    """FEMNET's purse seine p1 pays out its purse line by a winch (``input hauling_cable4 1 ... -15.4 -15.4``):
    `jaxnet run p1.don --dynamic` says what the winch does and records the length paid out, the table's
    integral."""
    from jaxnet.io import timeseries

    p1 = pathlib.Path(__file__).resolve().parent / "data" / "femnet-corpus" / "12purse_seine" / "p1.don"
    out = tmp_path / "p1"
    assert cli.main(["run", str(p1), "--dynamic", "--end", "0.3", "--quiet", "--no-cache", "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "winch 0: pays out 2002 m of 100 bars between 0 and 130 s (drum at bar 0)" in printed
    series = timeseries.read_series(out)
    np.testing.assert_allclose(series["time"], [0.0, 0.1, 0.2, 0.3], atol=1e-12)
    np.testing.assert_allclose(series["winch_hauled_m"][:, 0], -15.4 * series["time"], rtol=1e-12, atol=1e-12)
    assert np.all(np.isfinite(series["winch_tension_N"]))


def test_a_run_starts_from_femnets_stored_equilibrium(tmp_path, capsys):
    """``--start CASE.sta`` on FEMNET's mesh: the seine s4_libre, which no load holds any more (many equilibria
    on the sea bed, held along x at jaxnet's gauge node only), starts where FEMNET's .sta has it, laid out over
    2 km, where its drawn shape would fold it up; its winch then hauls cable 14 in (from 10 s, at 1 m/s: its table),
    its gauge free in time. Without --mesh, and with a .sta too short for the mesh, --start is refused naming the
    file and line."""
    from jaxnet.io import femnet, timeseries

    folder = pathlib.Path(__file__).resolve().parent / "data" / "femnet-corpus" / "11bottom_seine"
    don, mdg, sta = (folder / f"s4_libre.{ext}" for ext in ("don", "mdg", "sta"))
    out = tmp_path / "s4"
    args = ["run", str(don), "--mesh", str(mdg), "--start", str(sta), "--dynamic", "--end", "12", "--record", "6",
            "--quiet", "--no-cache", "--out", str(out)]
    assert cli.main(args) == 0
    series = timeseries.read_series(out)
    stored = femnet.sta_positions(sta, series["position"].shape[1])
    assert np.ptp(stored[:, 0]) > 2000.0
    # jaxnet's equilibrium from FEMNET's: the seine stays laid out where FEMNET has it, to 1 % of its 2 km (its
    # drawn shape lies 2.2 km away)
    assert np.abs(series["position"][0] - stored).max() < 0.01 * np.ptp(stored[:, 0])
    np.testing.assert_allclose(series["winch_hauled_m"][:, 0], [0.0, 0.0, 2.0], atol=1e-12)
    # the gauge that held the seine along x for its static start is free in time: no reaction there
    gauge = femnet.read_mdg(mdg, don).info["gauge"]
    assert f"its gauge node {gauge['node']} (x), held for the static start, is free in time" in capsys.readouterr().out
    held = json.loads((out / "series.json").read_text())["run"]["reaction_nodes"]
    assert held and gauge["node"] not in held
    assert cli.main(["run", str(don), "--start", str(sta), "--quiet", "--no-cache", "--out", str(out)]) == 2
    assert "--start (FEMNET's node positions, a .sta) goes with --mesh" in capsys.readouterr().err
    short = tmp_path / "short.sta"
    short.write_text("\n".join(sta.read_text().splitlines()[:40]))
    assert cli.main(["run", str(don), "--mesh", str(mdg), "--start", str(short), "--quiet", "--no-cache",
                     "--out", str(out)]) == 2
    assert f"{short}:41: expected node 41's number and x y z" in capsys.readouterr().err


def test_version_and_built_in_numbers_set_on_the_command_line(tmp_path, capsys):
    """``--version`` says the installed version; ``--set KEY=VALUE`` changes a built-in scene's numbers (the scene
    is the builder's with them), and names an unknown key with the ones it has, or a value of the wrong kind."""
    import jaxnet
    from jaxnet.scenes import hanging_panel

    with pytest.raises(SystemExit) as stop:
        cli.main(["--version"])
    assert stop.value.code == 0 and capsys.readouterr().out.strip() == f"jaxnet {jaxnet.__version__}"
    out = tmp_path / "small"
    assert cli.main(["run", "--scene", "hanging", "--set", "meshes=8", "--set", "step=0.05", "--out", str(out),
                     "--quiet", "--no-cache"]) == 0
    assert "meshes=8, step=0.05" in capsys.readouterr().out
    result = json.loads((out / "result.json").read_text())
    expected = hanging_panel(meshes=8, step=0.05).scene
    assert result["n_nodes"] == expected.n_nodes != hanging_panel().scene.n_nodes
    assert cli.main(["run", "--scene", "hanging", "--set", "mesh=8", "--out", str(out), "--no-cache"]) == 2
    err = capsys.readouterr().err
    assert "--set mesh: the built-in scene 'hanging' has no such number; it has: meshes (default 40)" in err
    assert cli.main(["run", "--scene", "hanging", "--set", "meshes=eight", "--out", str(out), "--no-cache"]) == 2
    assert "--set meshes=eight: expected an integer" in capsys.readouterr().err
    path = tmp_path / "panel.json"
    path.write_text("{}")
    assert cli.main(["run", str(path), "--set", "step=1", "--out", str(out), "--no-cache"]) == 2
    assert "--set changes a built-in scene's numbers" in capsys.readouterr().err


def test_export_writes_a_built_in_scene_that_runs_as_a_file(tmp_path, capsys):
    """``jaxnet export --scene NAME [--set ...] FILE`` writes the built-in, its numbers changed, as a scene file;
    ``jaxnet run FILE`` then solves the same net as ``jaxnet run --scene NAME --set ...``."""
    path = tmp_path / "panel.toml"
    assert cli.main(["export", "--scene", "hanging", "--set", "meshes=8", "--set", "step=0.05", str(path)]) == 0
    assert f"run it with: jaxnet run {path}" in capsys.readouterr().out
    runs = {}
    for name, argv in (("file", [str(path)]), ("built-in", ["--scene", "hanging", "--set", "meshes=8",
                                                            "--set", "step=0.05"])):
        out = tmp_path / name
        assert cli.main(["run", *argv, "--out", str(out), "--quiet", "--no-cache"]) == 0
        runs[name] = json.loads((out / "result.json").read_text())
    assert runs["file"]["n_nodes"] == runs["built-in"]["n_nodes"]
    np.testing.assert_allclose(runs["file"]["reaction_N"], runs["built-in"]["reaction_N"], rtol=1e-9, atol=1e-12)
    assert cli.main(["export", "--scene", "hanging", "--set", "mesh=8", str(tmp_path / "x.toml")]) == 2
    assert "has no such number" in capsys.readouterr().err and not (tmp_path / "x.toml").exists()


def test_show_redraws_the_pictures_of_a_run_without_solving(tmp_path, capsys, monkeypatch):
    """``jaxnet show DIR`` draws net.png (a static run) or run.png (a run in time) again from what the run wrote and
    the command it recorded (DIR/command.json), the net read again from its source: no solve (the solvers are
    made to fail here), and a directory that is no run's is named."""
    from jaxnet.io import plot
    from jaxnet.solve import statics

    static, dynamic = tmp_path / "static", tmp_path / "dynamic"
    built_in = ["--scene", "hanging", "--set", "meshes=8", "--set", "step=0.05"]
    assert cli.main(["run", *built_in, "--out", str(static), "--quiet", "--no-cache"]) == 0
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(wall_scene()))
    monkeypatch.chdir(tmp_path)  # the file named relative to where the run started
    assert cli.main(["run", "scene.json", "--dynamic", "--dt", "0.01", "--end", "0.03", "--out", str(dynamic),
                     "--quiet", "--no-cache"]) == 0
    (static / "net.png").unlink()
    (dynamic / "run.png").unlink()
    drawn = {}
    monkeypatch.setattr(plot, "save_png", lambda p, scene, x, **kw: drawn.update(png=(p, scene, x, kw)))
    monkeypatch.setattr(plot, "save_run_png", lambda p, scene, t, x, f, **kw: drawn.update(run=(p, t, x, f)))
    monkeypatch.setattr(statics, "solve", lambda *a, **k: pytest.fail("show must not solve"))
    monkeypatch.chdir(pathlib.Path("/"))
    assert cli.main(["show", str(static)]) == 0
    p, scene, x, kw = drawn["png"]
    result = json.loads((static / "result.json").read_text())
    assert p == static / "net.png" and scene.n_nodes == result["n_nodes"]
    np.testing.assert_allclose(np.asarray(kw["twine_tension"]).max(), result["max_twine_tension_N"], rtol=1e-12)
    assert cli.main(["show", str(dynamic)]) == 0
    p, t, positions, figures_ = drawn["run"]
    np.testing.assert_allclose(t, [0.0, 0.01, 0.02, 0.03], atol=1e-12)
    assert positions.shape[0] == 4 and "reaction_total_N" in figures_
    assert cli.main(["show", str(tmp_path)]) == 2
    assert "holds no command.json: it is not the output directory of a jaxnet run" in capsys.readouterr().err


def test_a_label_says_the_numbers_the_scene_was_built_with(tmp_path, capsys):
    """A built-in scene's label (the run's first line, its pictures' title, the exported file's description) is
    made from the numbers it was built with, ``--set`` included, not from its defaults."""
    path = tmp_path / "c08.toml"
    assert cli.main(["export", "--scene", "cage", "--set", "current=0.8", str(path)]) == 0
    printed = capsys.readouterr().out
    assert "in a 0.8 m/s current" in printed and "0.5 m/s" not in printed
    assert "in a 0.8 m/s current" in path.read_text() and "0.5 m/s" not in path.read_text()
    out = tmp_path / "small"
    assert cli.main(["run", "--scene", "hanging", "--set", "meshes=8", "--set", "step=0.05", "--out", str(out),
                     "--quiet", "--no-cache", "--no-pictures"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first.startswith("jaxnet: built-in scene 'hanging': square panel of 8 x 8 meshes"), first
    assert json.loads((out / "result.json").read_text())["inputs"]["label"].startswith("square panel of 8 x 8 meshes")


def test_a_femnet_case_on_its_own_mesh_keeps_its_symmetry_planes(tmp_path, capsys):
    """FEMNET's cod-end c2 is a quarter (symmetry planes y = 0 and z = -10 m in its .don): read on FEMNET's own mesh
    (``--mesh c2.mdg``) it is the same quarter as on jaxnet's, so that the whole net's figures, its ParaView file and
    its mirrored pictures are those of the whole cod-end."""
    from jaxnet.io import femnet

    data = pathlib.Path(__file__).parent / "data" / "femnet"
    don, mdg = data / "c2.don", data / "c2.mdg"
    planes = femnet.read_don(don).scene.symmetry_planes
    assert planes == ((1, 0.0), (2, -10.0)) == femnet.read_mdg(mdg, don).scene.symmetry_planes
    out = tmp_path / "c2"
    assert cli.main(["run", str(don), "--mesh", str(mdg), "--out", str(out), "--quiet", "--no-cache",
                     "--no-pictures"]) == 0
    printed = capsys.readouterr().out
    result = json.loads((out / "result.json").read_text())
    assert result["modelled_part"].startswith("a quarter of the net") and result["whole_net"]["copies"] == 4
    assert "whole net (4 mirrored copies)" in printed
    np.testing.assert_allclose(result["whole_net"]["reaction_N"][0], 4 * result["reaction_N"][0], rtol=1e-12)
    assert result["whole_net"]["reaction_N"][1:] == [0.0, 0.0]
    whole = meshio.read(out / "net_whole.vtu")
    assert len(whole.points) == 4 * result["n_nodes"]


def test_paths_that_cannot_be_used_are_named_without_a_traceback(tmp_path, capsys, monkeypatch):
    """A path in the way is bad input (exit status 2), named, before anything is solved: an output directory under
    a file, a --cache under a file, an exported file under a file, a scene file that does not exist; a disk that
    fills while a run writes names the file. Ctrl-C during a static solve stops it with status 130."""
    from jaxnet.io import vtk
    from jaxnet.solve import statics

    a_file = tmp_path / "a_file"
    a_file.write_text("")
    small = ["--scene", "hanging", "--set", "meshes=4", "--set", "step=0.05", "--quiet", "--no-pictures"]
    cases = [
        (["run", *small, "--no-cache", "--out", str(a_file / "sub")], f"--out {a_file / 'sub'}: {a_file} is a file"),
        (["run", *small, "--no-cache", "--out", str(a_file)], f"--out {a_file}: {a_file} is a file, not a directory"),
        (["run", *small, "--cache", str(a_file / "c"), "--out", str(tmp_path / "o")], f"{a_file} is a file"),
        (["export", "--scene", "cage", str(a_file / "x.toml")],
         f"cannot write {a_file / 'x.toml'}: {a_file} is a file, not a directory"),
        (["export", "--scene", "cage", str(tmp_path / "x.txt")], "a scene file is .toml or .json"),
        (["run", str(tmp_path / "missing.toml"), "--no-cache", "--out", str(tmp_path / "o")],
         f"the scene file {tmp_path / 'missing.toml'} does not exist"),
    ]
    monkeypatch.setattr(statics, "solve", lambda *a, **k: pytest.fail("nothing is solved on bad input"))
    for argv, message in cases:
        assert cli.main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.startswith("jaxnet: bad input: ") and message in err and "Traceback" not in err, (argv, err)
    monkeypatch.undo()

    def full(path, *a, **k):
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(vtk, "write_vtu", full)
    out = tmp_path / "full"
    assert cli.main(["run", *small, "--no-cache", "--out", str(out)]) == 2
    assert f"jaxnet: bad input: cannot use {out / 'net.vtu'}: disk full" in capsys.readouterr().err
    assert (out / "result.json").exists()   # the answer was written before

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(statics, "solve", interrupted)
    assert cli.main(["run", *small, "--no-cache", "--out", str(out)]) == 130
    assert "jaxnet: stopped (Ctrl-C)" in capsys.readouterr().err


def test_export_keeps_an_existing_file_unless_forced(tmp_path, capsys):
    path = tmp_path / "cage.toml"
    path.write_text("# mine\n")
    assert cli.main(["export", "--scene", "cage", str(path)]) == 2
    assert f"{path} exists: give another name, or --force to overwrite it" in capsys.readouterr().err
    assert path.read_text() == "# mine\n"
    assert cli.main(["export", "--scene", "cage", "--set", "current=0.7", "--force", str(path)]) == 0
    assert "0.7 m/s" in path.read_text()


def test_options_that_do_not_apply_are_refused_before_anything_runs(tmp_path, capsys, monkeypatch):
    """An option that would be ignored is bad input naming it and what it goes with, before anything is built or
    solved: options of a run in time without --dynamic, FEMNET's options with a scene file, a built-in's --scene with
    a file, a static built-in run in time, --cache with --no-cache."""
    from jaxnet.solve import statics

    monkeypatch.setattr(statics, "solve", lambda *a, **k: pytest.fail("nothing is solved on bad input"))
    scene = tmp_path / "wall.json"
    scene.write_text(json.dumps(wall_scene()))
    out = ["--out", str(tmp_path / "o")]
    cases = [
        (["run", "--end", "2"], "--end applies to a run in time: add --dynamic"),
        (["run", "--dt", "0.1", "--resume"], "--dt, --resume apply to a run in time"),
        (["run", str(scene), "--jaxnet-laws"], "--jaxnet-laws goes with a FEMNET case"),
        (["run", str(scene), "--mesh", "x.mdg"], "--mesh goes with a FEMNET case"),
        (["run", str(scene), "--scene", "hanging"], "--scene hanging (a built-in scene) and the file"),
        (["run", "--scene", "cage", "--dynamic"], "--scene cage is a static scene"),
        (["run", "--scene", "cage_waves"], "--scene cage_waves is a dynamic scene: run it with --dynamic"),
        (["run", "--cache", str(tmp_path / "c"), "--no-cache"], "--cache DIR and --no-cache: give one of them"),
    ]
    for argv, message in cases:
        assert cli.main(argv + out) == 2, argv
        err = capsys.readouterr().err
        assert message in err, (argv, err)
    assert not (tmp_path / "o" / "result.json").exists()


def test_help_and_version_import_no_jax_and_the_iterations_have_a_legend(tmp_path, capsys):
    """``jaxnet --version`` and ``jaxnet run --help`` answer without importing JAX or the physics (a fresh process
    is asked what it imported); a run prints once what the columns of its iteration lines are, each method's."""
    probe = ("import sys\nfrom jaxnet import cli\nfor argv in (['--version'], ['run', '--help']):\n"
             "    try:\n        cli.main(argv)\n    except SystemExit:\n        pass\n"
             "print('IMPORTED', sorted(m for m in sys.modules if m == 'jax' or m.startswith(('jax.', 'jaxnet.'))))\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True)
    imported = done.stdout.rsplit("IMPORTED", 1)[1]
    assert "'jax'" not in imported and "jaxnet.scene'" not in imported and "jaxnet.cli" in imported, imported
    assert "Built-in scenes (cage by default)" in done.stdout and "jaxnet " in done.stdout
    for method, columns in (("primal-dual", ("residual:", "damping:", "step:", "mean T g:")),
                            ("damped", ("residual:", "damping:", "step:", "stiffness x"))):
        assert cli.main(["run", "--scene", "hanging", "--set", "meshes=4", "--set", "step=0.05", "--no-cache",
                         "--method", method, "--no-pictures", "--out", str(tmp_path / method)]) == 0
        printed = capsys.readouterr().out
        legend = [line for line in printed.splitlines() if "one line per Newton iteration" in line]
        assert len(legend) == 1 and legend[0].lstrip().startswith(f"({method}:"), legend
        assert all(w in legend[0] for w in columns), (method, legend[0])
        assert printed.index(legend[0]) < printed.index("  newton    1")
