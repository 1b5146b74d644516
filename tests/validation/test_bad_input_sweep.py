"""The bad-input sweep (validation/bad_input.py): every kind of malformed input in the catalogue gets the exception
expected, with a message naming the culprit (the panel, cable, node, triangle or parameter; for a .don file its
file:LINE), raised before the solver compiles anything.

The catalogue is the one the report's section runs. A case marked ``pending`` names the library file whose
check is still missing: it is expected to fail (strictly: once the check is added the test says so, and the
mark must go). A case judged by solving (``solve=True``: a valid scene; none at present) must compile and stop
with a named reason.
"""

import pytest

import jaxnet as jn
from validation.bad_input import CASES, SolverCompiled, attempt, small_scene, solver_compilation_watched


def _param(case):
    marks = [pytest.mark.xfail(strict=True, reason=f"check missing in {case.pending}")] if case.pending else []
    return pytest.param(case, id=f"{case.level}: {case.kind}", marks=marks)


@pytest.mark.parametrize("case", [_param(c) for c in CASES])
def test_bad_input_gets_a_named_error_before_compilation(case, tmp_path):
    outcome = attempt(case, tmp_path)
    assert isinstance(outcome.raised, case.error), f"{type(outcome.raised).__name__}: {outcome.message}"
    assert outcome.names_culprit(case), f"{outcome.message!r} does not match {case.culprit!r}"
    if case.solve:
        assert outcome.compiled, "a case judged by solving did not reach the solver"
    else:
        assert not outcome.compiled, f"the solver was about to compile {outcome.compiled}"


def test_the_catalogue_holds_at_least_30_distinct_kinds():
    kinds = {case.kind for case in CASES}
    assert len(kinds) >= 30, sorted(kinds)
    assert {".don", "scene file", "net", "scene", "solver"} <= {case.level for case in CASES}


def test_the_tripwires_stop_a_real_solve_before_it_compiles():
    # the 'before compilation' verdict can fail: a valid scene reaches the solver's compiled entry points
    scene = small_scene()
    with solver_compilation_watched() as reached, pytest.raises(SolverCompiled):
        jn.solve_static(scene)
    assert reached == ["statics.compile_pieces"]
