"""net.html (jaxnet.io.page) in a real browser: Chromium, headless, its network shut off (every host unresolvable,
every connection sent to a closed proxy), opens the page of a small solved cod-end and must draw the whole net
(every mirrored copy's triangles) with no script error and no console message.

Chromium is required, not optional: a page is only tested by a browser running it, and a skipped test would
let a broken page through. Without it the tests fail and say how to install it (Debian: ``apt-get install -y
--no-install-recommends chromium``; any other binary by ``JAXNET_CHROMIUM=/path/to/chrome``).

What the test reads back: Chromium's ``--dump-dom`` writes the document after its load, in which the page set
``data-triangles`` (the triangles drawn) and, for any error, ``data-errors`` on its ``<html>`` element; with
``--enable-logging=stderr`` Chromium writes every console message of the page (uncaught errors included, and
those thrown before the page's own error handler exists) as a ``CONSOLE`` line on its standard error.
"""

import html.parser
import importlib
import json
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

import jaxnet
from jaxnet import figures
from jaxnet.io import page

INSTALL = ("tests/io/test_page.py opens net.html in a real browser and needs Chromium; none was found (looked for "
           "$JAXNET_CHROMIUM, chromium, chromium-browser, google-chrome on PATH). On Debian or Ubuntu, as root: "
           "apt-get install -y --no-install-recommends chromium")


def chromium():
    for name in (os.environ.get("JAXNET_CHROMIUM"), "chromium", "chromium-browser", "google-chrome",
                 "google-chrome-stable"):
        found = name and shutil.which(name)
        if found:
            return found
    pytest.fail(INSTALL, pytrace=False)


class _Root(html.parser.HTMLParser):
    """The attributes of a document's ``<html>`` element."""

    def __init__(self):
        super().__init__()
        self.attributes = None

    def handle_starttag(self, tag, attrs):
        if tag == "html" and self.attributes is None:
            self.attributes = dict(attrs)


def open_offline(path, profile):
    """Open ``path`` in headless Chromium with no network; returns (the ``<html>`` element's attributes after
    load, the document, the page's console lines). ``profile``: an empty directory for Chromium's profile."""
    command = [chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
               "--disable-background-networking", "--disable-component-update", "--disable-sync",
               "--disable-extensions", f"--user-data-dir={profile}",
               # the network shut off: no name resolves, every connection goes to a closed port
               "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9", "--proxy-bypass-list=<-loopback>",
               "--enable-logging=stderr", "--v=0", "--window-size=1200,800", "--virtual-time-budget=5000",
               "--dump-dom", path.resolve().as_uri()]
    done = subprocess.run(command, capture_output=True, text=True, timeout=180)
    assert done.returncode == 0, f"chromium exited with {done.returncode}: {done.stderr[-2000:]}"
    parser = _Root()
    parser.feed(done.stdout)
    assert parser.attributes is not None, f"no document came back: {done.stdout[:500]!r} {done.stderr[-2000:]}"
    console = [line for line in done.stderr.splitlines() if ":CONSOLE" in line]
    return parser.attributes, done.stdout, console


@pytest.fixture(scope="module")
def solved():
    """A small cod-end quarter (10 triangles, 2 symmetry planes: 4 copies) solved, and its figures."""
    chromium()   # said first: without it the tests cannot run
    case = importlib.import_module("jaxnet.scenes.codend").codend(meshes_around=8, meshes_along=4)
    eq = jaxnet.solve_static(case)
    assert eq.converged
    return case.scene, np.asarray(eq.x), figures.summary(case.scene, eq, case=case)


def test_the_page_draws_the_whole_net_offline_without_errors(solved, tmp_path):
    scene, x, result = solved
    path = page.write_html(tmp_path / "net.html", scene, x, result=result, title="cod-end <quarter>")
    text = path.read_text()
    # one file: nothing it loads from elsewhere
    assert not re.search(r"""(src|href)\s*=\s*["']?\s*(https?:)?//""", text, re.I)
    assert not re.search(r"url\(\s*['\"]?(https?:)?//", text, re.I)
    root, document, console = open_offline(path, tmp_path / "profile")
    assert "data-errors" not in root, root["data-errors"]
    assert console == []
    copies, triangles = 4, scene.netting.vertices.shape[0]
    assert int(root["data-triangles"]) == copies * triangles == 40
    # the figures beside the net: the largest twine tension, as the colour scale's top and in the table
    largest = float(figures.twine_tensions(scene, x).max())
    assert result["max_twine_tension_N"] == pytest.approx(largest, rel=1e-12)
    assert re.search(rf"<th[^>]*>max_twine_tension_N</th><td>{largest:.4g}</td>", document)
    data = json.loads(re.search(r'<script type="application/json" id="net-data">(.*?)</script>', text, re.S)
                      .group(1))
    assert data["twineScale"]["hi"] == pytest.approx(largest, rel=1e-12)
    # the catch front where result.json puts it: a ring across the whole net, at front_m along the axis (x)
    front = np.reshape(data["front"], (-1, 3))
    assert len(front) > 0 and np.ptp(front[:, 1]) > 0 and np.ptp(front[:, 2]) > 0
    np.testing.assert_allclose(front[:, 0], result["catch"]["front_m"], atol=1e-6 * np.ptp(x))
    assert "cod-end &lt;quarter&gt;" in document                  # the title, escaped
    assert "fixed (held in x, y, z)" in document                   # what holds the net, in the legend


def test_a_broken_page_is_caught(solved, tmp_path):
    """The checks above fail on a page whose script fails: an error while drawing is written into the page, and
    a script that does not even parse shows on the console (before the page's handlers exist)."""
    scene, x, result = solved
    good = page.write_html(tmp_path / "net.html", scene, x, result=result).read_text()
    assert good.count("safe(draw);\n})();") == 1
    failing = tmp_path / "failing.html"
    failing.write_text(good.replace("safe(draw);\n})();", "safe(() => undefinedFunction());\n})();"))
    root, _, _ = open_offline(failing, tmp_path / "profile-1")
    assert "undefinedFunction" in root.get("data-errors", "") and "data-triangles" not in root
    unparsed = tmp_path / "unparsed.html"
    unparsed.write_text(good.replace('"use strict";', '"use strict"; (((', 1))
    root, _, console = open_offline(unparsed, tmp_path / "profile-2")
    assert "data-triangles" not in root and any("SyntaxError" in line for line in console)
