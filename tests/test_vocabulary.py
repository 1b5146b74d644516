"""One word for each thing, everywhere a user reads: the package's docstrings and messages, the README, docs/ and the
notebooks. Each retired spelling below names the word that replaced it; a new page or docstring that brings one back
fails here."""

import pathlib
import re
import warnings

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]

#: retired spelling (a regular expression) -> the word used instead, and why
RETIRED = {
    r"\bfloat_\(|Net\.float_\b": "Net.float (a float on a headline is a float, no trailing underscore)",
    r"\btop rope\b": "headline (the rope a net hangs from)",
    r"designer's mesh counts": "twine coordinates (U, V): counted in twines along the two twine directions",
}

#: where a user reads jaxnet's words
PAGES = sorted([ROOT / "README.md", *(ROOT / "docs").glob("*.md"), *(ROOT / "notebooks").glob("*.ipynb"),
                *(ROOT / "jaxnet").rglob("*.py")])


@pytest.mark.parametrize("pattern", sorted(RETIRED))
def test_a_retired_spelling_is_nowhere(pattern):
    found = [f"{page.relative_to(ROOT)}:{n}" for page in PAGES
             for n, line in enumerate(page.read_text(encoding="utf-8").splitlines(), 1)
             if re.search(pattern, line) and "former name" not in line and "float_ is now" not in line
             and "def float_" not in line]
    assert not found, f"{RETIRED[pattern]}: {found}"


def test_the_former_name_of_float_still_works_and_warns():
    from jaxnet.net import Net, PanelRef, Twine

    net, old = Net(), Net()
    corners = [(0, 0, 0, 0, 0), (1, 0, 0, 5, -5), (1, 0, 1, 10, 0), (0, 0, 1, 5, 5)]
    for n in (net, old):
        n.panel("p", corners, Twine(l0=0.1, ea=100.0, diameter=1e-3), step=0.5)
        n.fix(PanelRef("p").side(0))

    net.float(PanelRef("p").corner(2), 20.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        old.float_(PanelRef("p").corner(2), 20.0)
    assert any(issubclass(w.category, DeprecationWarning) and "Net.float" in str(w.message) for w in caught)
    a, b = net.build().nodes, old.build().nodes
    assert (a.volume == b.volume).all() and float(a.volume.sum()) > 0
    # 20 N of buoyancy net of its own weight: the volume that displaces 20 N of water
    g, rho = float(net.environment.gravity), float(net.environment.water_density)
    assert abs(float(a.volume.sum()) - 20.0 / (g * rho)) < 1e-15
