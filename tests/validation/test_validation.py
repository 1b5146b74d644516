"""The validation report's machinery, and the textbook scenes its closed forms rest on."""

from __future__ import annotations

import numpy as np
import pytest

import jaxnet as jn
from jaxnet.scenes import textbook
from validation import report as report_lib


def test_tables_are_written_from_rows_and_sections_survive_a_partial_run(tmp_path):
    path = tmp_path / "REPORT.md"
    header = {"date": "today", "host": "here", "jaxnet revision": "abc1234"}
    first = report_lib.Report(path, header=header)
    first.start("Alpha", ["Alpha", "Beta"])
    first.table([{"a": 1, "b": 0.5, "c": None, "d": True, "e": 1.23456e-7, "f": "x|y"}])
    first.start("Beta")
    first.text("beta body")
    text = path.read_text()
    assert "| a | b | c | d | e | f |" in text
    assert "| 1 | 0.5 | - | yes | 1.235e-07 | x\\|y |" in text
    assert text.index("## Alpha") < text.index("## Beta")
    assert text.count("at `abc1234` on here") == 2  # each section dated with the commit it measured
    # a second run that refreshes Beta only keeps Alpha's table as it was
    second = report_lib.Report(path, header={**header, "jaxnet revision": "def5678"})
    second.start("Beta", ["Alpha", "Beta"])
    second.text("new beta")
    text = path.read_text()
    assert "| 1 | 0.5 | - | yes | 1.235e-07 | x\\|y |" in text
    assert "new beta" in text and "beta body" not in text
    assert text.count("## Alpha") == 1 and text.count("## Beta") == 1
    assert text.count("at `abc1234`") == 1 and text.count("at `def5678`") == 1  # Alpha keeps its commit


def test_unknown_section_is_refused(capsys):
    from validation.__main__ import main

    with pytest.raises(SystemExit):
        main(["--only", "nonsense"])
    assert "nonsense" in capsys.readouterr().err


@pytest.mark.parametrize("angle_deg", [90.0, 50.0, 20.0])
def test_held_panel_in_a_current_has_the_morison_drag_of_its_twines(angle_deg):
    # the panel's twines run at 45° in its plane: (direction ± z)/√2, so every twine makes the same angle ψ
    # with the current (x): cos ψ = cos(angle) / √2. Morison normal drag K |c_n| c_n with |c_n| = U sin ψ has
    # the component K U² sin³ ψ along the current and, across it (y), -K U² sin ψ cos ψ (t · y) summed over
    # the two families, whose t · y = sin(angle)/√2 alike.
    angle = np.radians(angle_deg)
    scene, normal = textbook.panel_in_current(meshes=6, step=0.05, angle=angle, speed=0.7)
    eq = jn.solve_static(scene)
    force = -eq.reaction(scene).sum(axis=0)  # the current's force on the net
    cos_psi = np.cos(angle) / np.sqrt(2.0)
    sin_psi = np.sqrt(1.0 - cos_psi**2)
    np.testing.assert_allclose(force[0], normal * sin_psi**3, rtol=1e-12)
    np.testing.assert_allclose(force[1], -normal * sin_psi * cos_psi * np.sin(angle) / np.sqrt(2.0), rtol=1e-12,
                               atol=1e-14 * normal)
    assert abs(force[2]) < 1e-12 * normal
