"""The robustness set (validation/robustness.py) at its test size: its records are consistent with themselves.

A handful of tiny cases are run once; every record must say what its solve did without contradiction
(factorisations at least the iterations, the parts of the wall time below it, converged exactly when the
residual is within the tolerance), the JSON lines must hold one record per case and ``resume`` must skip
them; a ``.don`` file the reader refuses is listed as "does not read", not as a solver failure. No timed
assertions: the times are only checked against each other.
"""

import json
import math

from jaxnet.solve.options import TOL_N, Newton
from validation import robustness


def test_test_size_is_a_handful_of_tiny_cases():
    cases = robustness.cases("test")
    assert 3 <= len(cases) <= 6
    assert len({c.name for c in cases}) == len(cases)


def test_the_test_size_runs_with_consistent_records(tmp_path, monkeypatch):
    # one test (one run of the cases) for every check, so that pytest-xdist does not run them on two workers
    out = tmp_path / "records.json"
    cases = robustness.cases("test")
    lines = []
    records = robustness.run_cases(cases, out=out, echo=lines.append)
    check_records(cases, records)
    check_table_and_summary(cases, records, lines)
    check_json_lines_and_resume(cases, out, monkeypatch)


def check_records(cases, records):
    assert [r["case"] for r in records] == [c.name for c in cases]
    for r in records:
        assert r["read"] and not r["nan"], r
        assert r["nodes"] > 0 and r["dof"] > 0
        assert r["tol"] == TOL_N and r["max_iter"] == robustness.MAX_ITERATIONS
        assert 0 < r["iterations"] <= robustness.MAX_ITERATIONS
        assert r["converged"] == (r["residual_N"] <= r["tol"]), r
        assert r["converged"] == (r["reason"] == robustness.CONVERGED)
        assert r["factorisations"] >= r["iterations"]
        assert r["evaluations"] >= r["iterations"]
        parts = r["compile_s"] + r["assembly_s"] + r["factorisation_s"] + r["evaluation_s"]
        assert all(r[k] >= 0 for k in ("compile_s", "assembly_s", "factorisation_s", "evaluation_s"))
        assert parts <= r["wall_s"] and r["other_s"] >= 0
        assert math.isclose(r["other_s"], r["wall_s"] - parts, rel_tol=1e-9, abs_tol=1e-12)
        assert math.isclose(r["factorisation_each_s"], r["factorisation_s"] / r["factorisations"], rel_tol=1e-9)
        assert r["peak_MB"] > 0 and r["peak_source"]
        assert r["expected"] is True


def check_table_and_summary(cases, records, lines):
    assert lines[0].startswith("| case |") and len(lines) == 1 + len(cases)
    assert all(line.count("|") == len(robustness.COLUMNS) + 1 for line in lines[1:])
    rows = {row["family"]: row for row in robustness.summary(records)}
    assert rows["all"]["cases"] == len(records) and rows["all"]["not read"] == 0
    assert rows["all"]["converged"] == sum(r["converged"] for r in records)
    its = [r["iterations"] for r in records if r["converged"]]
    assert rows["all"]["max it"] == max(its)
    assert rows["all"]["> 25 it"] == sum(i > 25 for i in its)


def check_json_lines_and_resume(cases, out, monkeypatch):
    kept = robustness.read_records(out)
    assert [r["case"] for r in kept] == [c.name for c in cases]
    assert all(json.loads(json.dumps(r)) == r for r in kept)

    def must_not_run(case):
        raise AssertionError(f"{case.name} was run again")

    monkeypatch.setattr(robustness, "run_case", must_not_run)
    again = robustness.run_cases(cases, out=out, resume=True, echo=lambda line: None)
    assert [r["case"] for r in again] == [c.name for c in cases]
    assert len(robustness.read_records(out)) == len(cases)


def test_a_file_the_reader_refuses_is_not_a_solver_failure(tmp_path):
    (tmp_path / "broken.don").write_text("this is not a FEMNET case\n")
    cases = robustness.femnet_cases("quick", dirs=[tmp_path])
    assert len(cases) == 1
    record = robustness.run_case(cases[0])
    assert record["read"] is False and not record["converged"]
    assert record["reason"].startswith(robustness.NOT_READ + ": ")
    row = robustness.summary([record])[0]
    assert row["cases"] == 0 and row["not read"] == 1
    assert robustness.not_read([record])[0]["case"] == cases[0].name
    assert robustness.failures([record]) == []


def test_every_run_has_the_tolerance_and_the_cap():
    own = Newton(tol=1e-9, max_iter=10_000, max_step=0.1)  # a FEMNET case's numerics
    newton = robustness.newton_options(robustness.Setup(scene=None, newton=own))
    assert (newton.tol, newton.max_iter, newton.max_step) == (TOL_N, robustness.MAX_ITERATIONS, 0.1)
    assert robustness.newton_options(robustness.Setup(scene=None)).max_iter == robustness.MAX_ITERATIONS


def test_the_sizes_hold_the_issue_s_cases():
    quick, full = robustness.cases("quick"), robustness.cases("full")
    for cases in (quick, full):
        assert len({c.name for c in cases}) == len(cases)
    families = {c.family for c in full}
    assert families >= {"readme", "hanging", "framed", "cage", "codend", "femnet", "stability"}
    panels = [c for c in full if c.family in robustness.PANELS]
    # per family: 3 sizes x 2 (sinker or not) x (still + 4 speeds x 4 angles)
    assert len(panels) == 3 * 3 * 2 * 17
    assert sum(c.family == "cage" for c in full) == 4 * 3
    assert sum(c.family == "codend" for c in full) == 4
    assert not any("n10000" in c.name for c in quick)
    assert sum(c.family == "cage" for c in quick) == 3


def test_compare_names_a_case_that_now_fails():
    before = dict(case="a", family="readme", nodes=10, read=True, converged=True, reason="converged", iterations=12,
                  wall_s=1.0, build_s=0.1, expected=True)
    after = dict(before, converged=False, reason="maximum number of iterations reached", iterations=500,
                 expected=False)
    text = robustness.compare([before], [after])
    assert "NOW FAILS" in text and "| a |" in text


def test_only_picks_whole_words_side_by_side():
    """``--only`` matches whole words of the case names: a size or a speed does not pick its multiples."""
    names = [c.name for c in robustness.cases("quick") if c.family in ("readme", "hanging")]
    picked = [n for n in names if robustness.matches(n, "readme n100")]
    assert picked and all(n.startswith("readme n100 ") for n in picked)
    assert not any(robustness.matches(n, "readme n100") for n in names if "n1000" in n)
    assert {n for n in names if robustness.matches(n, "1m/s")} == {n for n in names if " 1m/s " in n} != set()
    assert not robustness.matches("readme n100 0.1m/s 30deg sinker", "1m/s")
    assert all(robustness.matches(n, "") for n in names)
    assert not robustness.matches("readme n100 still sinker", "sinker still")  # in the name's order only
