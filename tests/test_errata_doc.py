"""docs/errata.md stays true to the tests: every test it cites exists, and it covers the whole chapter."""

import pathlib
import re

ROOT = pathlib.Path(__file__).parents[1]
DOC = (ROOT / "docs" / "errata.md").read_text()


def test_every_cited_test_exists():
    cited = set(re.findall(r"`(?:tests/[\w/]+\.py::)?(test_\w+)", DOC))
    assert len(cited) > 50
    defined = set(re.findall(r"def (test_\w+)", "\n".join(p.read_text() for p in (ROOT / "tests").rglob("*.py"))))
    # a citation may abbreviate a long name with "..." (its prefix, ending in "_")
    missing = [c for c in cited if c not in defined and not (c.endswith("_") and any(d.startswith(c) for d in defined))]
    assert not missing, missing


def test_every_part_of_the_chapter_has_its_section():
    sections = re.findall(r"^## (4\.\d+)-(4\.\d+)", DOC, flags=re.M)
    covered = sorted((int(a.split(".")[1]), int(b.split(".")[1])) for a, b in sections)
    # contiguous from 4.1 to 4.271 (4.272-4.280 are in the drag, opening and pressure sections' titles)
    assert covered[0][0] == 1
    for (_, end), (start, _) in zip(covered, covered[1:]):
        assert start == end + 1, (end, start)
    for eq in ("4.272-4.276", "4.277", "4.278-4.280"):
        assert re.search(rf"^## .*{re.escape(eq)}", DOC, flags=re.M), eq
