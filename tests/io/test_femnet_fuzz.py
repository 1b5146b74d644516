"""Fuzzing jaxnet.io.femnet's .don reader: damaged FEMNET cases are read or refused, never crash it.

Each example takes one of FEMNET's two worked cases (or one of the small synthetic cases beside them, which
use links, seams and hexagonal netting) and damages its text once or twice, as a careless edit would: a
line deleted, the file cut short, a number replaced by NaN, inf, -1, 0, a huge value or a word, two lines
swapped, a line duplicated, a label misspelt. The reader must then either read the case, and the net it
returns must build into a scene that :func:`jaxnet.scene.checks.validate` accepts, or raise ``SceneError`` whose
message names the file and a line (``file.don:LINE: ...``). Any other exception is a bug of the reader.
Nothing is solved. The examples are derandomized (the same every run) so that the test cannot flicker.
"""

import json
import pathlib
import re

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from jaxnet.io import femnet
from jaxnet.scene.checks import validate
from jaxnet.scene import SceneError

DATA = pathlib.Path(__file__).parents[1] / "data" / "femnet"
CASES = {name: (DATA / f"{name}.don").read_text() for name in
         ("nr_netting", "c2", "links_hub", "links_cable", "hexagonal")}
NUMBER = re.compile(r"(?<![\w.])[-+]?\d+\.?\d*(?:[eE][-+]?\d+)?(?![\w.])")
REPLACEMENTS = ("nan", "NaN", "inf", "-inf", "-1", "0", "0.0", "1e300", "-1e300", "1e30", "1e-300", "99999",
                "2.5", "abc", "1_000", "0x10", "", "7")
SETTINGS = settings(max_examples=1000, deadline=None, derandomize=True, database=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


def _misspell(draw, text):
    labels = [m for m in re.finditer(r"[A-Za-z][^:\n]*:", text)]
    m = draw(st.sampled_from(labels))
    at = draw(st.integers(m.start(), m.end() - 2))
    how = draw(st.sampled_from(["drop", "x", "double"]))
    letter = {"drop": "", "x": "x", "double": text[at] * 2}[how]
    return text[:at] + letter + text[at + 1:]


@st.composite
def damaged(draw):
    name = draw(st.sampled_from(sorted(CASES)))
    text = CASES[name]
    done = []
    for _ in range(draw(st.integers(1, 2))):
        lines = text.split("\n")
        kind = draw(st.sampled_from(["delete", "truncate", "number", "number", "number", "swap", "duplicate",
                                     "misspell"]))
        if kind == "delete":
            del lines[draw(st.integers(0, len(lines) - 1))]
            text = "\n".join(lines)
        elif kind == "truncate":
            text = text[:draw(st.integers(0, len(text)))]
        elif kind == "number":
            numbers = list(NUMBER.finditer(text))
            if not numbers:
                continue
            m = draw(st.sampled_from(numbers))
            text = text[:m.start()] + draw(st.sampled_from(REPLACEMENTS)) + text[m.end():]
        elif kind == "swap":
            i, j = draw(st.integers(0, len(lines) - 1)), draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
        elif kind == "duplicate":
            i = draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i])
            text = "\n".join(lines)
        else:
            if ":" not in text:
                continue
            text = _misspell(draw, text)
        done.append(kind)
    return name, text, done


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


@SETTINGS
@given(case=damaged())
def test_damaged_cases_are_read_or_refused_with_file_and_line(workdir, case):
    name, text, done = case
    path = workdir / f"{name}.don"
    path.write_text(text)
    try:
        loaded = femnet.read_don(path)
    except SceneError as err:
        message = str(err)
        assert f"{name}.don:" in message and re.search(r"\.don:\d+:", message), (done, message)
        return
    scene, solver, info = loaded.scene, loaded.solver, loaded.info
    validate(scene)
    json.dumps(info)  # the CLI writes it into result.json
    assert solver.tol > 0 and solver.max_iter >= 1


def test_the_undamaged_cases_are_read():
    # the fuzzing starts from cases that read: the damage, not the case, is what is refused
    for name in CASES:
        validate(femnet.read_don(DATA / f"{name}.don").scene)
