"""Bad input sweep: malformed nets, scenes, solver options, scene files and FEMNET ``.don`` files, and the error
each gets.

Why. A user's mistake (a misspelt key, a NaN pasted into a table, a panel drawn with its corners on one line, a
line of a ``.don`` file with a value missing) must stop with an error that says what is wrong and where: the
panel, cable, node, triangle or parameter, and for a ``.don`` file its ``file:LINE``. It must stop *before*
anything is compiled (seconds to minutes for a large net) wherever the input can be judged without solving,
and never as a bare numpy or JAX exception, a NaN result or a hang.

:data:`CASES` is the catalogue: one :class:`BadInput` per kind of mistake, with how to make it (``attempt``,
given a scratch folder), the exception type expected and a regular expression the message must match, which
names the culprit (the line numbers of ``.don`` cases are found in FEMNET's case files, not typed). Both this
report section and ``tests/validation/test_bad_input_sweep.py`` run it. :func:`attempt` runs one case with the solver's
compiled programs replaced by tripwires (:func:`solver_compilation_watched`), so that a case also records
whether the solver was about to be compiled when the error came.

Two kinds of entries are not plain refusals: ``solve=True`` marks input that is valid as a scene and can only be
judged by solving it (none at present: a netting of zero stiffness, a mechanism that a solve reported as a step
that lowers no energy, is now refused where its material is made); ``pending`` names the library file whose
check is still missing (the test expects such a case to fail until that check is added, and then to pass).

A scene file's error names the file and the line of its culprit (``scene.toml:7: ...``): the cases find that line
in the text they write (:func:`_scene_at`), as the ``.don`` cases find theirs in FEMNET's files.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import pathlib
import re
import tempfile
import time
from typing import Callable

import numpy as np

TITLE = "Bad input: malformed scenes and .don files"

#: FEMNET's worked cases and the small synthetic ones beside them (tests/data/femnet)
FEMNET_DATA = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "femnet"
#: the table shows this many characters of each message
MESSAGE_CHARS = 160


@dataclasses.dataclass(frozen=True)
class BadInput:
    """One kind of malformed input.

    kind: unique short name. level: where the input enters (``net``: the :class:`~jaxnet.net.Net` builder;
    ``scene``: a scene edited by hand and given to ``jaxnet.solve_static``; ``solver``, ``dynamics``, ``waves``: their
    options; ``scene file``; ``.don``). input: the mistake, in a few words. attempt: folder -> anything; makes
    and uses the bad input (files in ``folder``) and is expected to raise. error: the exception type expected.
    culprit: a regular expression the message must match (``re.search``): it names the culprit.
    solve: the input is a valid scene, judged by solving it (compilation expected).
    pending: the library file whose check this kind still lacks (the case fails until it is added).
    """

    kind: str
    level: str
    input: str
    attempt: Callable[[pathlib.Path], object]
    error: type
    culprit: str
    solve: bool = False
    pending: str | None = None


@dataclasses.dataclass(frozen=True)
class Outcome:
    """What one attempt gave: the exception raised (None if none), the solver programs it was about to compile
    (names; empty if none) and its wall time (s)."""

    raised: BaseException | None
    compiled: tuple
    seconds: float

    @property
    def message(self):
        return "" if self.raised is None else str(self.raised)

    def names_culprit(self, case: BadInput) -> bool:
        return self.raised is not None and re.search(case.culprit, self.message) is not None

    def as_expected(self, case: BadInput) -> bool:
        """The expected type, a message naming the culprit, and no compilation unless the case needs a solve."""
        return (isinstance(self.raised, case.error) and self.names_culprit(case)
                and (case.solve or not self.compiled))


# -- the solver's compilation, watched ------------------------------------------------------------------------


class SolverCompiled(AssertionError):
    """Raised by a tripwire: the solver was about to compile a program."""


#: (module, attribute) of every entry point that compiles a solver program
#: (the static solve compiles its evaluation and tangent inside ``compile_pieces`` only)
_ENTRY_POINTS = (("jaxnet.solve.statics", "compile_pieces"), ("jaxnet.solve.newton", "newton_loop_jit"),
                 ("jaxnet.solve.dynamics", "out_of_balance_jit"), ("jaxnet.solve.dynamics", "advance_jit"),
                 ("jaxnet.solve.implicit", "root_jit"))


class _Tripwire:
    """Stands for a compiled entry point: records that it was reached, then raises (``forbid``) or goes on."""

    def __init__(self, name, original, reached, forbid):
        self._name, self._original, self._reached, self._forbid = name, original, reached, forbid

    def _hit(self):
        self._reached.append(self._name)
        if self._forbid:
            raise SolverCompiled(f"the solver was about to compile {self._name} before the bad input was caught")

    def __call__(self, *args, **kwargs):
        self._hit()
        return self._original(*args, **kwargs)

    def lower(self, *args, **kwargs):
        self._hit()
        return self._original.lower(*args, **kwargs)

    def __getattr__(self, name):  # anything else of a jitted function (not a compilation)
        return getattr(self._original, name)


@contextlib.contextmanager
def solver_compilation_watched(forbid=True):
    """Replace the solver's compiled entry points (statics, dynamics, implicit) by tripwires for the duration;
    yields the list of the names reached. ``forbid``: a tripwire raises :class:`SolverCompiled` instead of
    compiling."""
    import importlib

    reached, saved = [], []
    try:
        for module_name, attribute in _ENTRY_POINTS:
            module = importlib.import_module(module_name)
            original = getattr(module, attribute)
            saved.append((module, attribute, original))
            setattr(module, attribute, _Tripwire(f"{module_name.rsplit('.', 1)[1]}.{attribute}", original, reached,
                                                 forbid))
        yield reached
    finally:
        for module, attribute, original in saved:
            setattr(module, attribute, original)


def attempt(case: BadInput, folder: pathlib.Path) -> Outcome:
    """Run one case in ``folder`` (created), the solver's compilation forbidden unless the case needs a solve."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    raised = None
    t0 = time.perf_counter()
    with solver_compilation_watched(forbid=not case.solve) as reached:
        try:
            case.attempt(folder)
        except Exception as error:  # noqa: BLE001 -- what was raised is the measurement
            raised = error
    return Outcome(raised, tuple(reached), time.perf_counter() - t0)


# -- nets and scenes to damage ----------------------------------------------------------------------------------


def _twine(**changes):
    from jaxnet.net import Twine

    return Twine(**{**dict(l0=0.02, ea=1000.0, diameter=1e-3), **changes})


def _rope(**changes):
    from jaxnet.net import Rope

    return Rope(**{**dict(ea=1e4, diameter=0.01), **changes})


def _hex_twine(**changes):
    from jaxnet.net import HexTwine

    return HexTwine(**{**dict(l0=0.02, ea=1000.0, diameter=1e-3), **changes})


#: a 1 m x 1 m square panel of 20 x 20 meshes in the plane y = 0: x, y, z (m), U, V (twines)
SQUARE = ((0, 0, 0, 0, 0), (1, 0, 0, 20, -20), (1, 0, 1, 40, 0), (0, 0, 1, 20, 20))


def _net(corners=SQUARE, twine=None, step=0.1, fix=True, environment=None):
    """(net, panel): the square panel 'wall' (about 50 nodes), held along its top side (side 2) unless not ``fix``;
    ``twine``: its material, or a function making it (a material that refuses itself when made)."""
    from jaxnet.net import Net

    net = Net(environment)
    twine = twine() if callable(twine) else twine
    panel = net.panel("wall", corners, twine or _twine(), step)
    if fix:
        net.fix(panel.side(2))
    return net, panel


def _built(change=None, **net_options):
    """An attempt: the square panel, changed by ``change(net, panel)``, built (validated)."""
    def run(folder):
        net, panel = _net(**net_options)
        if change is not None:
            change(net, panel)
        return net.build()
    return run


def _corners(k, column, value):
    """The square's corners with corner ``k``'s ``column`` (x y z U V) set to ``value``."""
    rows = [list(c) for c in SQUARE]
    rows[k][column] = value
    return rows


def _scene():
    """The square panel with a headline sewn along its top side: a scene with netting and bars."""
    net, panel = _net()
    net.cable("headline", along=panel.side(2), rope=_rope())
    return net.build()


def _edited(part, index=None, **values):
    """An attempt: jaxnet.solve_static on the scene of :func:`_scene` with fields of ``part`` (nodes, netting, bars,
    environment) replaced; a value that is a function gets the old array (a copy) and returns the new one;
    ``index``: the entry of the old array to set instead (``values`` then hold one field and its entry's value)."""
    def run(folder):
        import jaxnet as jn

        scene = _scene()
        family = getattr(scene, part)
        changes = {}
        for name, value in values.items():
            if index is not None:
                array = np.array(getattr(family, name))
                array[index] = value
                value = array
            elif callable(value):
                value = value(np.array(getattr(family, name)))
            changes[name] = value
        return jn.solve_static(dataclasses.replace(scene, **{part: dataclasses.replace(family, **changes)}))
    return run


def _solved(scene_of, **options):
    def run(folder):
        import jaxnet as jn

        return jn.solve_static(scene_of(), **options)
    return run


def small_scene(ea=100.0, sinker_kg=0.0):
    """A valid scene of 15 nodes: a 0.2 m square panel of twines of stiffness ``ea`` (N) held along its top side,
    with a sinker of ``sinker_kg`` at its corner 0 (none for 0)."""
    from jaxnet.net import Net

    net = Net()
    panel = net.panel("wall", [(0, 0, 0, 0, 0), (0.2, 0, 0, 4, -4), (0.2, 0, 0.2, 8, 0), (0, 0, 0.2, 4, 4)],
                      _twine(l0=0.025, ea=ea), 0.05)
    net.fix(panel.side(2))
    if sinker_kg:
        net.sinker(panel.corner(0), sinker_kg)
    return net.build()


def _start_of_wrong_shape(folder):
    import jaxnet as jn

    scene = small_scene()
    return jn.solve_static(scene, x0=np.asarray(scene.nodes.position)[:-1])


def _simulated(end_time=1.0, loading=None, **options):
    def run(folder):
        from jaxnet.solve import dynamics

        return dynamics.simulate(small_scene(), end_time, loading=loading, **options)
    return run


def _towed_free_node():
    from jaxnet.water import forcing
    from jaxnet.solve import dynamics

    towing = forcing.Towing(velocity=(1.0, 0.0, 0.0))
    return dynamics.Loading(motions=(forcing.PrescribedMotion(np.array([0]), towing),))


def _calling(make):
    """An attempt that only calls ``make()`` (options objects that check themselves)."""
    return lambda folder: make()


# -- scene files ------------------------------------------------------------------------------------------------


#: a valid scene file: the square panel held along its top side
SCENE_DOC = {
    "twines": {"pa": {"l0": 0.02, "ea": 1000.0, "diameter": 0.001}},
    "panels": [{"name": "wall", "corners": [list(c) for c in SQUARE], "twine": "pa", "step": 0.1}],
    "fix": [{"at": {"panel": "wall", "side": 2}}],
}


#: :data:`SCENE_DOC` as a hand-written TOML file, its material a named table
SCENE_TOML = """# the square panel held along its top side
[environment]
current_speed = 0.5   # m/s

[twines."wall 0"]
l0 = 0.02
ea = 1000.0
diameter = 0.001

[[panels]]
name = "wall"
corners = [[0, 0, 0, 0, 0], [1, 0, 0, 20, -20], [1, 0, 1, 40, 0], [0, 0, 1, 20, 20]]
twine = "wall 0"
step = 0.1

[[fix]]
at = {panel = "wall", side = 2}
"""


def _scene_text(change=None, text=None):
    """The text of a scene file: :data:`SCENE_DOC` changed in place by ``change(doc)`` as JSON, one key a line, or
    ``text`` as written."""
    if text is not None:
        return text
    doc = json.loads(json.dumps(SCENE_DOC))
    if change is not None:
        change(doc)
    return json.dumps(doc, indent=2)


def _scene_file(change=None, text=None, name="scene.json"):
    """An attempt: read (and build) the scene file ``name`` of :func:`_scene_text`."""
    def run(folder):
        from jaxnet.io import scene_file

        path = folder / name
        path.write_text(_scene_text(change, text))
        return scene_file.read(path)
    return run


def _scene_at(needle, change=None, text=None, name="scene.json"):
    """The regex prefix ``NAME:LINE: `` of the line of :func:`_scene_text` holding ``needle``: where the reader
    must point."""
    written = _scene_text(change, text)
    return rf"{re.escape(name)}:{written[:written.index(needle)].count(chr(10)) + 1}: "


def _set(path, value):
    """A change of a scene document: the entry at ``path`` (keys and indices) set to ``value``."""
    def change(doc):
        *head, last = path
        for key in head:
            doc = doc[key]
        doc[last] = value
    return change


def _drop(path):
    def change(doc):
        *head, last = path
        for key in head:
            doc = doc[key]
        del doc[last]
    return change


# -- .don files -------------------------------------------------------------------------------------------------


def _don_text(case):
    return (FEMNET_DATA / f"{case}.don").read_text()


def _line(case, needle, after=None):
    """The line (1-based) of FEMNET case ``case`` holding ``needle`` (the first at or after the line holding
    ``after``): where the reader must point."""
    text = _don_text(case)
    start = text.index(after) if after is not None else 0
    return text[:text.index(needle, start)].count("\n") + 1


def _don(case, *edits, keep_lines=None, name=None):
    """An attempt: FEMNET case ``case`` with ``edits`` ((old, new) text replacements, each of text found once)
    read by :func:`jaxnet.io.femnet.read_don` as ``name`` (default the case's own name); ``keep_lines``: only
    the first lines (a truncated file)."""
    def run(folder):
        from jaxnet.io import femnet

        text = _don_text(case)
        for old, new in edits:
            if text.count(old) != 1:
                raise RuntimeError(f"bad-input catalogue: {old!r} is not found exactly once in {case}.don")
            text = text.replace(old, new)
        if keep_lines is not None:
            text = "\n".join(text.split("\n")[:keep_lines])
        path = folder / f"{name or case}.don"
        path.write_text(text)
        return femnet.read_don(path)
    return run


def _at(case, needle, after=None):
    """The regex prefix ``case.don:LINE: `` of the line holding ``needle``."""
    return rf"{re.escape(case)}\.don:{_line(case, needle, after)}: "


# nr_netting.don's lines that the cases damage (as written in FEMNET's file)
_CORNER_2 = "2    0.000000    0.730000    -1.000000    80.000000    0.000000    2    2"
_CORNER_4 = "4    1.695000    -0.735000    -1.000000    0.000000    120.000000    2    2"
_EA = "Traction stiffness (N):\t\t\t6000.000000"
_L0 = "Unstretched length (m):\t\t\t0.022000"
_CABLE_3 = "Kt: 50000.000000  Kc: 0.000000  L: 1.97  Vm"
_CABLE_5 = "D:0.022500  Cd: 1.200000  f: 0.080000  Nb: 57"
_TYPE_1_MASS = "Mass X,Y,Z (kg):        0.000000  0.000000  0.000000\nAdded mass X,Y,Z (kg):        0.000000  0.000000  0.000000\nLength X,Y,Z (m):        0.000000  0.000000  0.000000\nDrag coefficient X,Y,Z:        1.200000  1.200000  1.200000\nExternal forces X,Y,Z (N):    0.000000  0.000000  0.000000\nDisplacement X,Y,Z:        1  1  1"  # noqa: E501
_TYPE_2_BOX = "Length X,Y,Z (m):        0.000000  0.000000  0.000000\nDrag coefficient X,Y,Z:        1.200000  1.200000  1.200000\nExternal forces X,Y,Z (N):    0.000000  0.000000  0.000000\nDisplacement X,Y,Z:        0 0 0"  # noqa: E501
_C2_CORNERS = ("4\t0.000000\t0.270468\t-10.000000\t0.000000\t-25.000000",
               "3\t5.765000\t0.270468\t-10.000000\t50.000000\t-25.000000")


# -- the catalogue ----------------------------------------------------------------------------------------------


def _catalogue():
    import jaxnet as jn
    from jaxnet.water import waves
    from jaxnet.net import Side
    from jaxnet.scene import Catch, SceneError
    from jaxnet.solve import dynamics
    from jaxnet.solve.options import Newton

    E = SceneError
    net, scene, solver, dyn, wav, sfile, don = "net", "scene", "solver", "dynamics", "waves", "scene file", ".don"
    nr = "nr_netting"
    cases = [
        # -- the Net builder: panels ----------------------------------------------------------------------------
        BadInput("collinear U/V contour", net, "corners (U, V) (0, 0), (10, 10), (20, 20)",
                 _built(corners=[(0, 0, 0, 0, 0), (1, 0, 0, 10, 10), (2, 0, 0, 20, 20)]), E,
                 r"panel 'wall': .*collinear"),
        BadInput("corners share their twine coordinates", net, "corners 1 and 2 at different places, same (U, V)",
                 _built(corners=[(0, 0, 0, 0, 0), (1, 0, 0, 20, -20), (1, 0, 1, 20, -20), (0, 0, 1, 20, 20)]), E,
                 r"panel 'wall': corners 1 and 2 have the same twine coordinates"),
        BadInput("self-intersecting panel", net, "bow-tie contour",
                 _built(corners=[(0, 0, 0, 0, 0), (1, 0, 1, 20, 20), (1, 0, 0, 20, 0), (0, 0, 1, 0, 20)], fix=False), E,
                 r"panel 'wall': sides \d and \d cross"),
        BadInput("NaN corner position", net, "corner 2: y = NaN", _built(corners=_corners(2, 1, float("nan"))), E,
                 r"panel 'wall': corner 2 has a non-finite y"),
        BadInput("infinite twine coordinate", net, "corner 1: U = inf", _built(corners=_corners(1, 3, float("inf"))), E,
                 r"panel 'wall': corner 1 has a non-finite U"),
        BadInput("too few corners", net, "two corners", _built(corners=SQUARE[:2]), E,
                 r"panel 'wall': a panel needs at least 3 corners, got 2"),
        BadInput("wrong-shape corners", net, "rows of 4 numbers", _built(corners=[c[:4] for c in SQUARE]), E,
                 r"panel 'wall': corners must be rows of x y z U V, got shape \(4, 4\)"),
        BadInput("meshing step <= 0", net, "step = 0", _built(step=0.0), E,
                 r"panel 'wall': step must be a positive finite number"),
        BadInput("meshing step absurdly fine", net, "step = 1 µm (1e11 nodes)", _built(step=1e-6), E,
                 r"panel 'wall': step=1e-06 m .*nodes \(limit \d+\)"),
        BadInput("negative twine EA", net, "Twine(ea=-5)", _built(twine=lambda: _twine(ea=-5.0)), E,
                 r"^Twine: ea must be > 0, got -5\.0 \(traction stiffness EA, N\)"),
        BadInput("zero twine EA (a mechanism)", net, "Twine(ea=0) + 1 kg sinker",
                 _built(lambda n, p: n.sinker(p.corner(0), 1.0), twine=lambda: _twine(ea=0.0)), E,
                 r"^Twine: ea must be > 0, got 0\.0 \(traction stiffness EA, N\)"),
        BadInput("negative opening stiffness", net, "Twine(opening_stiffness=-0.1)",
                 _built(twine=lambda: _twine(opening_stiffness=-0.1)), E,
                 r"^Twine: opening_stiffness must be >= 0, got -0\.1 \(mesh opening stiffness"),
        BadInput("zero hexagonal EA of a family", net, "HexTwine(ea=(1000, 0, 1000))",
                 _calling(lambda: _hex_twine(ea=(1000.0, 0.0, 1000.0))), E,
                 r"^HexTwine: ea must be > 0 per twine family \(l, m, n\), got \[1000\.0, 0\.0, 1000\.0\]"),
        BadInput("twine l0 <= 0", net, "Twine(l0=0)", _built(twine=_twine(l0=0.0)), E,
                 r"panel 'wall': l0 must be > 0, got 0"),
        BadInput("negative twine diameter", net, "Twine(diameter=-1 mm)", _built(twine=_twine(diameter=-1e-3)), E,
                 r"panel 'wall': diameter must be >= 0, got -0.001"),
        BadInput("negative Cd", net, "Twine(cd_normal=-1)", _built(twine=_twine(cd_normal=-1.0)), E,
                 r"panel 'wall': cd_normal must be >= 0, got -1"),
        BadInput("NaN parameter", net, "Twine(density=NaN)", _built(twine=_twine(density=float("nan"))), E,
                 r"panel 'wall': density must be >= 0, got nan"),
        BadInput("rest angle out of range", net, "Twine(rest_angle=2 rad)", _built(twine=_twine(rest_angle=2.0)), E,
                 r"panel 'wall': rest_angle .* got 2\.0"),
        BadInput("misspelt drag model", net, "Twine(drag_model='loeland')",
                 _built(twine=_twine(drag_model="loeland")), E,
                 r"panel 'wall': drag_model must be one of .* got 'loeland'"),
        BadInput("duplicate panel name", net, "two panels 'wall'",
                 _built(lambda n, p: n.panel("wall", SQUARE, _twine(), 0.1)), E,
                 r"panel 'wall': the name is already used"),
        # -- the Net builder: cables, seams ----------------------------------------------------------------------
        BadInput("negative cable stiffness", net, "Rope(ea_compression=-1)",
                 _built(lambda n, p: n.cable("rope", along=p.side(2), rope=_rope(ea_compression=-1.0))), E,
                 r"^Rope: ea_compression must be >= 0, got -1\.0 \(compression stiffness"),
        BadInput("zero cable EA", net, "Rope(ea=0)",
                 _built(lambda n, p: n.cable("rope", along=p.side(2), rope=_rope(ea=0.0))), E,
                 r"^Rope: ea must be > 0, got 0\.0 \(traction stiffness EA, N\)"),
        BadInput("zero-length cable", net, "both ends on corner 0, no length",
                 _built(lambda n, p: n.cable("bridle", start=p.corner(0), end=p.corner(0), rope=_rope())), E,
                 r"cable 'bridle': both ends at the same point and no length given"),
        BadInput("cable with 0 bars", net, "n_bars=0",
                 _built(lambda n, p: n.cable("bridle", start=p.corner(0), end=(0, 0, -1), rope=_rope(), n_bars=0)), E,
                 r"cable 'bridle': number of bars must be a positive integer, got 0"),
        BadInput("negative cable length", net, "length=-1",
                 _built(lambda n, p: n.cable("bridle", start=p.corner(0), end=(0, 0, -1), rope=_rope(), length=-1.0)),
                 E, r"cable 'bridle': length must be > 0, got -1"),
        BadInput("cable end on a missing corner", net, "start=corner 7 of a 4-corner panel",
                 _built(lambda n, p: n.cable("bridle", start=p.corner(7), end=(0, 0, 2), rope=_rope())), E,
                 r"cable 'bridle' start: panel 'wall' has no corner 7"),
        BadInput("NaN cable end", net, "end=(0, 0, NaN)",
                 _built(lambda n, p: n.cable("bridle", start=p.corner(0), end=(0, 0, float("nan")), rope=_rope())), E,
                 r"cable 'bridle' end: expected a panel corner or a finite point"),
        BadInput("seam of a side to itself", net, "seam(side 0, side 0)",
                 _built(lambda n, p: n.seam(p.side(0), p.side(0))), E,
                 r"seam: side 0 of panel 'wall' is sewn to itself"),
        BadInput("seam to a missing side", net, "seam(side 0, side 9)",
                 _built(lambda n, p: n.seam(p.side(0), p.side(9))), E, r"seam: panel 'wall' has no side 9"),
        BadInput("seam to a corner", net, "seam(side 0, corner 1)",
                 _built(lambda n, p: n.seam(p.side(0), p.corner(1))), E,
                 r"seam: expected a panel side .*Corner\(panel='wall', index=1\)"),
        # -- the Net builder: fixings, loads, catch, environment ------------------------------------------------
        BadInput("fixing a missing side", net, "fix(side 9)", _built(lambda n, p: n.fix(p.side(9))), E,
                 r"panel 'wall' has no side 9"),
        BadInput("fixing a missing panel", net, "fix(Side('roof', 0))", _built(lambda n, p: n.fix(Side("roof", 0))), E,
                 r"no panel named 'roof'"),
        BadInput("fixing a point with no node", net, "fix((5, 5, 5))", _built(lambda n, p: n.fix((5.0, 5.0, 5.0))), E,
                 r"no node at point \[5\.0, 5\.0, 5\.0\]"),
        BadInput("fixing along an unknown axis", net, "fix(axes='xyw')",
                 _built(lambda n, p: n.fix(p.side(2), axes="xyw")), E, r"fix: unknown axes \['w'\]"),
        BadInput("nothing fixed (free-floating net)", net, "no fix", _built(fix=False), E, r"no node is fixed"),
        BadInput("held along z only (a mechanism)", net, "fix(axes='z') only",
                 _built(lambda n, p: n.fix(p.side(2), axes="z"), fix=False), E, r"no node is fixed along x"),
        BadInput("loose piece of net", net, "second panel attached to nothing",
                 _built(lambda n, p: n.panel("loose", [(3, 0, 0, 0, 0), (4, 0, 0, 20, -20), (4, 0, 1, 40, 0),
                                                      (3, 0, 1, 20, 20)], _twine(), 0.2)), E,
                 r"nodes \[[\d, ]+\]\.* \(\d+ nodes\) form a piece of net connected to no fixed node"),
        BadInput("negative mass", net, "attach(mass=-3 kg)", _built(lambda n, p: n.attach(p.corner(0), mass=-3.0)), E,
                 r"node 0: mass must be >= 0, got .*-3\.0"),
        BadInput("negative displaced volume", net, "attach(volume=-1 m³)",
                 _built(lambda n, p: n.attach(p.corner(0), volume=-1.0)), E,
                 r"node 0: displaced volume must be >= 0, got .*-1\.0"),
        BadInput("negative body width", net, "body(length=(-0.1, 0.1, 0.1))",
                 _built(lambda n, p: n.body(p.corner(0), (-0.1, 0.1, 0.1), (1.0, 1.0, 1.0))), E,
                 r"body: length along x and y must be >= 0"),
        BadInput("catch volume <= 0", net, "catch(0 m³)", _built(lambda n, p: n.catch(0.0, axis=(1, 0, 0))), E,
                 r"catch: volume must be > 0.*got 0\.0"),
        BadInput("NaN catch volume", net, "catch(NaN)", _built(lambda n, p: n.catch(float("nan"), axis=(1, 0, 0))), E,
                 r"catch: volume must be > 0.*got nan"),
        BadInput("catch without an axis", net, "catch(0.1 m³), no axis, no current",
                 _built(lambda n, p: n.catch(0.1)), E, r"catch: give its axis, or a current"),
        BadInput("NaN current speed", net, "Environment(current_speed=NaN)",
                 _built(environment=jn.Environment(current_speed=float("nan"))), E,
                 r"environment: current_speed must be finite and >= 0, got nan"),
        BadInput("negative current speed", net, "Environment(current_speed=-1)",
                 _built(environment=jn.Environment(current_speed=-1.0)), E,
                 r"environment: current_speed must be finite and >= 0, got -1"),
        BadInput("zero current direction", net, "current_direction=(0, 0, 0) at 1 m/s",
                 _built(environment=jn.Environment(current_speed=1.0, current_direction=np.zeros(3))), E,
                 r"environment: current_direction must be a non-zero vector"),
        BadInput("current profile not increasing", net, "profile_depth=(5, 2)",
                 _built(environment=jn.Environment(current_speed=1.0, profile_depth=np.array([5.0, 2.0]),
                                                   profile_factor=np.array([1.0, 0.5]))), E,
                 r"environment: the current profile needs .*strictly increasing depths"),
        BadInput("sea bed without stiffness", net, "limit(z >= -2) with bottom_stiffness 0",
                 _built(lambda n, p: n.limit(p.corner(0), (0.0, 0.0, -2.0), (0, 0, 1))), E,
                 r"node 0: a limit along z needs environment bottom_stiffness > 0"),
        BadInput("hexagonal netting in a current", net, "HexTwine panel, current 0.5 m/s",
                 _hexagonal_in_current, E, r"hexagonal triangle 0 \(hex\): hexagonal netting has no drag model"),
        # -- scenes edited by hand, given to jaxnet.solve_static ------------------------------------------------
        BadInput("triangle with collinear twine coordinates", scene, "triangle 7: (U, V) = (0,0), (1,1), (2,2)",
                 _edited("netting", 7, uv=[[0, 0], [1, 1], [2, 2]]), E,
                 r"triangle 7 \(wall\): collinear twine coordinates"),
        BadInput("infinite node position", scene, "node 5: z = inf", _edited("nodes", (5, 2), position=np.inf), E,
                 r"node 5: position is not finite \(inf\)"),
        BadInput("negative triangle EA", scene, "triangle 3: EA = -1", _edited("netting", 3, ea_traction=-1.0), E,
                 r"triangle 3 \(wall\): traction stiffness EA must be > 0, got -1"),
        BadInput("zero triangle EA", scene, "triangle 3: EA = 0", _edited("netting", 3, ea_traction=0.0), E,
                 r"triangle 3 \(wall\): traction stiffness EA must be > 0, got 0\.0"),
        BadInput("zero bar EA", scene, "bar 2: EA = 0", _edited("bars", 2, ea_traction=0.0), E,
                 r"bar 2 \(headline\): traction stiffness EA must be > 0, got 0\.0"),
        BadInput("infinite triangle EA", scene, "triangle 3: EA = inf", _edited("netting", 3, ea_traction=np.inf), E,
                 r"triangle 3 \(wall\): traction stiffness EA must be finite, got inf"),
        BadInput("NaN triangle Cd", scene, "triangle 4: Cd = NaN", _edited("netting", 4, cd_normal=np.nan), E,
                 r"triangle 4 \(wall\): cd normal must be >= 0, got .*nan"),
        BadInput("bar of zero rest length", scene, "bar 2: rest length 0", _edited("bars", 2, rest_length=0.0), E,
                 r"bar 2 \(headline\): unstretched length must be > 0, got .*0\.0"),
        BadInput("node twice in a triangle", scene, "triangle 2: vertices (a, a, c)",
                 _edited("netting", vertices=lambda v: np.where(np.arange(len(v))[:, None] == 2, v[:, [0, 0, 2]], v)),
                 E, r"triangle 2 \(wall\): a node appears twice among its vertices"),
        BadInput("vertex index out of range", scene, "triangle 4: vertex 10⁶",
                 _edited("netting", (4, 1), vertices=10**6), E, r"triangle 4 \(wall\): vertex index outside 0\.\.\d+"),
        BadInput("bar end out of range", scene, "bar 1: end -1", _edited("bars", (1, 0), ends=-1), E,
                 r"bar 1 \(headline\): end node index outside 0\.\.\d+"),
        BadInput("wrong-length node array", scene, "mass of N - 1 nodes", _edited("nodes", mass=lambda m: m[:-1]), E,
                 r"nodes: mass must have shape \(\d+,\), got \(\d+,\)"),
        BadInput("wrong-shape fixity", scene, "fixed of shape (N,)", _edited("nodes", fixed=lambda f: f.any(axis=1)),
                 E, r"nodes: fixed must have shape \(\d+, 3\), got \(\d+,\)"),
        BadInput("wrong-length element parameter", scene, "l0 of E - 1 triangles",
                 _edited("netting", l0=lambda l0: l0[:-1]), E, r"netting: l0 must have shape \(\d+,\), got \(\d+,\)"),
        BadInput("wrong-shape twine coordinates", scene, "uv of shape (E, 3, 3)",
                 _edited("netting", uv=lambda uv: np.concatenate([uv, uv[..., :1]], axis=-1)), E,
                 r"netting: uv must have shape \(\d+, 3, 2\), got \(\d+, 3, 3\)"),
        BadInput("NaN current direction", scene, "current_direction=(NaN, 0, 0) at 1 m/s",
                 _edited("environment", current_speed=1.0, current_direction=np.array([np.nan, 0.0, 0.0])), E,
                 r"environment: current_direction must be 3 finite numbers"),
        BadInput("2-D vertical", scene, "up=(0, 1)", _edited("environment", up=np.array([0.0, 1.0])), E,
                 r"environment: 'up' must be 3 finite numbers"),
        BadInput("infinite surface level", scene, "surface_level=inf",
                 _edited("environment", surface_level=np.inf), E, r"environment: surface_level must be a finite"),
        BadInput("a family that cannot float", scene, "floating=('twines',)",
                 _edited("environment", surface_level=0.0, floating=("twines",)), E,
                 r"environment: floating names the families that feel the free surface"),
        BadInput("waves that are not waves", scene, "waves='big'", _edited("environment", waves="big"), E,
                 r"environment: waves must be None or waves"),
        BadInput("NaN catch in a scene", scene, "Catch(volume=NaN)",
                 lambda folder: jn.solve_static(dataclasses.replace(_scene(), catch=Catch(
                     volume=float("nan"), drag_coefficient=1.4, axis=np.array([1.0, 0.0, 0.0]), center=np.zeros(3)))),
                 E, r"catch: volume must be finite and > 0"),
        # -- solver options ---------------------------------------------------------------------------------------
        BadInput("misspelt stiffness path", solver, "Newton(stiffness='closedform')",
                 _calling(lambda: Newton(stiffness="closedform")), ValueError,
                 r"Newton: stiffness must be one of .*not 'closedform'"),
        BadInput("misspelt Newton option", solver, "solve(scene, tolerance=1e-3)",
                 _solved(small_scene, tolerance=1e-3), TypeError, r"unexpected keyword argument 'tolerance'"),
        BadInput("Newton tolerance <= 0", solver, "solve(scene, tol=0)", _solved(small_scene, tol=0.0), ValueError,
                 r"\btol\b.*> 0"),
        BadInput("Newton max_iter 0", solver, "solve(scene, max_iter=0)", _solved(small_scene, max_iter=0), ValueError,
                 r"max_iter.*>= 1"),
        BadInput("start positions of the wrong shape", solver, "solve(scene, x0=N - 1 rows)",
                 _start_of_wrong_shape, ValueError,
                 r"x0.*\(\d+, 3\)"),
        # -- dynamics, waves --------------------------------------------------------------------------------------
        BadInput("time step <= 0", dyn, "Implicit(time_step=0)", _calling(lambda: dynamics.Implicit(time_step=0.0)),
                 ValueError, r"Implicit: time_step must be finite and > 0, got 0\.0"),
        BadInput("NaN time step", dyn, "Implicit(time_step=NaN)",
                 _calling(lambda: dynamics.Implicit(time_step=float("nan"))), ValueError,
                 r"Implicit: time_step must be finite and > 0, got nan"),
        BadInput("smallest step above the step", dyn, "Implicit(time_step=0.01, min_time_step=0.1)",
                 _calling(lambda: dynamics.Implicit(time_step=0.01, min_time_step=0.1)), ValueError,
                 r"Implicit: min_time_step \(0\.1\) exceeds time_step \(0\.01\)"),
        BadInput("end time <= 0", dyn, "simulate(end_time=-1)", _simulated(-1.0), ValueError,
                 r"simulate: end_time must be finite and > 0, got -1\.0"),
        BadInput("record interval 0", dyn, "simulate(record_every=0)", _simulated(record_every=0.0), ValueError,
                 r"simulate: record_every must be finite and > 0, got 0\.0"),
        BadInput("prescribed motion of a free node", dyn, "Towing node 0 (not fixed)",
                 lambda folder: _simulated(loading=_towed_free_node())(folder), E,
                 r"prescribed motion 0: node 0 is not fixed on every axis"),
        BadInput("wave period <= 0", wav, "Airy(period=0)", _calling(lambda: waves.Airy(1.0, 0.0)), ValueError,
                 r"Airy: period must be > 0, got 0\.0"),
        BadInput("water depth <= 0", wav, "Airy(depth=0)", _calling(lambda: waves.Airy(1.0, 5.0, depth=0.0)),
                 ValueError, r"Airy: depth must be > 0"),
        BadInput("NaN wave height", wav, "Airy(height=NaN)", _calling(lambda: waves.Airy(float("nan"), 5.0)),
                 ValueError, r"Airy: height is NaN"),
        BadInput("vertical wave direction", wav, "Airy(direction=(0, 0, 1))",
                 _calling(lambda: waves.Airy(1.0, 5.0, direction=(0.0, 0.0, 1.0))), ValueError,
                 r"Airy: direction must have a horizontal component"),
        # -- scene files ------------------------------------------------------------------------------------------
        BadInput("unknown key", sfile, "panels[0].mesh_size", _scene_file(_set(("panels", 0, "mesh_size"), 3)), E,
                 _scene_at('"mesh_size"', _set(("panels", 0, "mesh_size"), 3))
                 + r"panels\[0\]: unknown key\(s\) \['mesh_size'\] \(allowed: "),
        BadInput("misspelt key: the nearest one", sfile, "panels[0].stepp", _scene_file(_set(("panels", 0, "stepp"), 3)),
                 E, _scene_at('"stepp"', _set(("panels", 0, "stepp"), 3))
                 + r"panels\[0\]: unknown key\(s\) \['stepp'\]: did you mean step\?"),
        BadInput("unknown top-level key", sfile, "'currents': {}", _scene_file(_set(("currents",), {})), E,
                 _scene_at('"currents"', _set(("currents",), {})) + r"scene: unknown key\(s\) \['currents'\]"),
        BadInput("misspelt material key", sfile, "twines.pa.EA", _scene_file(_set(("twines", "pa", "EA"), 5)), E,
                 _scene_at('"EA"', _set(("twines", "pa", "EA"), 5))
                 + r"twines\.pa: unknown key\(s\) \['EA'\]: did you mean ea\?"),
        BadInput("wrong type: a word for a number", sfile, "twines.pa.l0 = 'abc'",
                 _scene_file(_set(("twines", "pa", "l0"), "abc")), E,
                 _scene_at('"l0"', _set(("twines", "pa", "l0"), "abc")) + r"twines\.pa\.l0: expected a number, got 'abc'"),
        BadInput("misspelt key in a TOML file", sfile, "environment.curent_speed",
                 _scene_file(text=SCENE_TOML.replace("current_speed", "curent_speed"), name="scene.toml"), E,
                 _scene_at("curent_speed", text=SCENE_TOML.replace("current_speed", "curent_speed"), name="scene.toml")
                 + r"environment: unknown key\(s\) \['curent_speed'\]: did you mean current_speed\?"),
        BadInput("zero EA in a material table", sfile, '[twines."wall 0"] ea = 0.0',
                 _scene_file(text=SCENE_TOML.replace("ea = 1000.0", "ea = 0.0"), name="scene.toml"), E,
                 _scene_at("ea = 0.0", text=SCENE_TOML.replace("ea = 1000.0", "ea = 0.0"), name="scene.toml")
                 + r'twines\."wall 0": ea must be > 0, got 0\.0 \(traction stiffness EA, N\)$'),
        BadInput("negative diameter in a material table", sfile, '[twines."wall 0"] diameter = -0.001',
                 _scene_file(text=SCENE_TOML.replace("diameter = 0.001", "diameter = -0.001"), name="scene.toml"), E,
                 _scene_at("diameter = -", text=SCENE_TOML.replace("diameter = 0.001", "diameter = -0.001"),
                           name="scene.toml") + r'twines\."wall 0": diameter must be >= 0, got -0\.001$'),
        BadInput("panel error at its line", sfile, "panels[0].step = -0.1",
                 _scene_file(_set(("panels", 0, "step"), -0.1)), E,
                 _scene_at('"step"', _set(("panels", 0, "step"), -0.1)) + r"panel 'wall': step must be a positive"),
        BadInput("wrong type: a word for corners", sfile, "panels[0].corners = 'square'",
                 _scene_file(_set(("panels", 0, "corners"), "square")), E,
                 r"panels\[0\]\.corners: expected rows of 5 numbers"),
        BadInput("wrong type: a word for a corner index", sfile, "fix[0].at.corner = 'top'",
                 _scene_file(_set(("fix", 0, "at"), {"panel": "wall", "corner": "top"})), E,
                 r"fix\[0\]\.at\.corner: expected an integer, got 'top'"),
        BadInput("wrong type: a word for the current", sfile, "environment.current_speed = 'fast'",
                 _scene_file(_set(("environment",), {"current_speed": "fast"})), E,
                 r"environment\.current_speed: expected a number, got 'fast'"),
        BadInput("wrong type: a word for a list", sfile, "fix = 'top'", _scene_file(_set(("fix",), "top")), E,
                 r"fix\[0\]: expected a table/object, got str"),
        BadInput("missing required key", sfile, "panels[0] without twine", _scene_file(_drop(("panels", 0, "twine"))),
                 E, r"panels\[0\]: give its material as twine \(diamond meshes\) or hex_twine \(hexagonal\)"),
        BadInput("missing material key", sfile, "twines.pa without ea", _scene_file(_drop(("twines", "pa", "ea"))), E,
                 r"twines\.pa: missing key\(s\) \['ea'\]"),
        BadInput("unknown material name", sfile, "panels[0].twine = 'pb'",
                 _scene_file(_set(("panels", 0, "twine"), "pb")), E,
                 r"panels\[0\]\.twine: no material named 'pb'"),
        BadInput("solver tolerance <= 0", sfile, "solver.tol = 0", _scene_file(_set(("solver",), {"tol": 0})), E,
                 _scene_at('"tol"', _set(("solver",), {"tol": 0})) + r"solver\.tol: must be > 0, got 0"),
        BadInput("solver iterations not an integer", sfile, "solver.max_iter = 2.5",
                 _scene_file(_set(("solver",), {"max_iter": 2.5})), E,
                 r"solver\.max_iter: expected an integer, got 2\.5"),
        BadInput("misspelt solver stiffness", sfile, "solver.stiffness = 'hand'",
                 _scene_file(_set(("solver",), {"stiffness": "hand"})), E,
                 r"solver: Newton: stiffness must be one of .*not 'hand'"),
        BadInput("wrong type: a word for the catch", sfile, "catch.volume = 'lots'",
                 _scene_file(_set(("catch",), {"volume": "lots"})), E, r"catch\.volume: expected a number, got 'lots'"),
        BadInput("JSON syntax error", sfile, "'{\"twines\": '", _scene_file(text='{"twines": '), E,
                 r"scene\.json:1: cannot parse"),
        BadInput("TOML syntax error", sfile, "'[twines' on line 2",
                 _scene_file(text="# a scene\n[twines\nl0 = 1\n", name="scene.toml"), E, r"scene\.toml:2: cannot parse"),
        BadInput("unknown scene file type", sfile, "scene.yaml", _scene_file(text="twines: {}", name="scene.yaml"), E,
                 r"scene\.yaml: unknown scene file type '\.yaml'"),
        BadInput("missing scene file", sfile, "a path that does not exist",
                 _read_missing("none.json"), E,
                 r"scene file .*none\.json does not exist"),
        # -- FEMNET .don files ------------------------------------------------------------------------------------
        BadInput("empty file", don, "no text", _don(nr, keep_lines=0, name="empty"), E,
                 r"empty\.don:1: the file ends before the field 'design in the plane normal to axis'"),
        BadInput("truncated file", don, "cut after line 60", _don(nr, keep_lines=60), E,
                 rf"{nr}\.don:\d+: the file ends before the value of 'cable 6 end 1 number' \(truncated file\?\)"),
        BadInput("misspelt keyword", don, "'Unstreched length (m)'",
                 _don(nr, (_L0, _L0.replace("Unstretched", "Unstreched"))), E,
                 _at(nr, _L0) + r"expected the field 'panel 1: unstretched length', found the label 'Unstreched"),
        BadInput("missing panel", don, "'panels number: 2', one panel written",
                 _don(nr, ("panels number: 1", "panels number: 2")), E,
                 _at(nr, "hexagonal panels number") + r"expected the field 'panel 2'"),
        BadInput("collinear U/V contour", don, "c2 panel 1: corners 3, 4 moved onto the line V = 0",
                 _don("c2", (_C2_CORNERS[0], "4\t0.000000\t0.270468\t-10.000000\t150.000000\t0.000000"),
                      (_C2_CORNERS[1], "3\t5.765000\t0.270468\t-10.000000\t100.000000\t0.000000")), E,
                 _at("c2", "1\t0.000000\t0.000000") + r"panel 1: the \(U, V\) contour of its corners is collinear"),
        BadInput("zero-length cable", don, "cable 3: 'L: 0'",
                 _don(nr, (_CABLE_3, _CABLE_3.replace("L: 1.97", "L: 0"))), E,
                 _at(nr, _CABLE_3) + r"'cable 3: unstretched length' must be > 0, got 0\.0"),
        BadInput("negative stiffness", don, "panel 1: EA = -6000", _don(nr, (_EA, _EA.replace("6000", "-6000"))), E,
                 _at(nr, _EA) + r"'panel 1: traction stiffness' must be > 0, got -6000"),
        BadInput("zero stiffness", don, "panel 1: EA = 0", _don(nr, (_EA, _EA.replace("6000", "0"))), E,
                 _at(nr, _EA) + r"'panel 1: traction stiffness' must be > 0, got 0\.0"),
        BadInput("zero cable stiffness", don, "cable 3: 'Kt: 0'", _don(nr, (_CABLE_3, _CABLE_3.replace("50000", "0"))),
                 E, _at(nr, _CABLE_3) + r"'cable 3: traction stiffness' must be > 0, got 0\.0"),
        BadInput("NaN value", don, "panel 1: l0 = nan", _don(nr, (_L0, _L0.replace("0.022000", "nan"))), E,
                 _at(nr, _L0) + r"'panel 1: unstretched length': 'nan' is not a finite number"),
        BadInput("a value missing on a line", don, "corner 2 line: 7 values of 8",
                 _don(nr, (_CORNER_2, _CORNER_2.rsplit(maxsplit=1)[0])), E,
                 _at(nr, _CORNER_2) + r"panel 1 corner 2: expected 8 values on its line .*found 7"),
        BadInput("a value too many on a line", don, "corner 4 line: 9 values of 8",
                 _don(nr, (_CORNER_4, _CORNER_4 + "    7")), E,
                 _at(nr, _CORNER_4) + r"unexpected value '7' after 'panel 1 corner 4 following side type'"),
        BadInput("two values for one field", don, "'Traction stiffness (N): 6000 7000'",
                 _don(nr, (_EA, _EA + " 7000")), E,
                 _at(nr, _EA) + r"unexpected value '7000' after 'panel 1: traction stiffness'"),
        BadInput("two values for X, Y, Z", don, "node type 1: 'Mass X,Y,Z (kg): 0 0'",
                 _don(nr, (_TYPE_1_MASS, _TYPE_1_MASS.replace("0.000000  0.000000  0.000000", "0.000000  0.000000",
                                                               1))), E,
                 _at(nr, "Mass X,Y,Z") + r"'node type 1: mass Z': missing: the line ends after 'node type 1: mass Y'"),
        BadInput("node type out of range", don, "corner 2 of node type 3 (2 types)",
                 _don(nr, (_CORNER_2, _CORNER_2.rsplit(maxsplit=2)[0] + "    3    2")), E,
                 _at(nr, _CORNER_2) + r"panel 1 corner 2: node type 3 is not described \(types: \[1, 2\]\)"),
        BadInput("meshing order names a missing panel", don, "'pa: 2' in the meshing order",
                 _don(nr, ("el:     5 pa:    1", "el:     5 pa:    2")), E,
                 _at(nr, "el:     5 pa:    1") + r"meshing order: 'pa: 2' is not a panel of the case"),
        BadInput("link to a missing panel", don, "links_cable: 'pa: 3' (2 panels)",
                 _don("links_cable", ("pa: 2\tnd: 4", "pa: 3\tnd: 4")), E,
                 _at("links_cable", "pa: 2\tnd: 4") + r"link 1 point 2: there is no panel 3 \(the case has 2\)"),
        BadInput("link to a missing corner", don, "links_cable: 'pa: 2 nd: 5' (4 corners)",
                 _don("links_cable", ("pa: 2\tnd: 4", "pa: 2\tnd: 5")), E,
                 _at("links_cable", "pa: 2\tnd: 4") + r"link 1 point 2: panel 2 has no corner 5 \(it has 4\)"),
        BadInput("cable with 0 bars", don, "cable 5: 'Nb: 0'",
                 _don(nr, (_CABLE_5, _CABLE_5.replace("Nb: 57", "Nb: 0"))), E,
                 _at(nr, _CABLE_5) + r"'cable 5: number of bars' must be an integer >= 1, got 0"),
        BadInput("convergence threshold 0", don, "'Convergence threshold (N): 0'",
                 _don(nr, ("Convergence threshold (N):                0.00100000",
                           "Convergence threshold (N):                0")), E,
                 _at(nr, "Convergence threshold") + r"'convergence threshold' must be > 0, got 0\.0"),
        BadInput("no iteration allowed", don, "'Maximal number of iterations: 0'",
                 _don(nr, ("Maximal number of iterations:                10000", "Maximal number of iterations:   0")),
                 E, _at(nr, "Maximal number of iterations") + r"'maximal number of iterations' must be an integer"),
        BadInput("dynamic time step 0", don, "end time 30 s, time step 0",
                 _don(nr, ("Dynamic: Time step (s):                    0.100000", "Dynamic: Time step (s):   0"),
                      ("Dynamic: End time of record and calculation (s):    0.000000",
                       "Dynamic: End time of record and calculation (s):    30.0")), E,
                 _at(nr, "Dynamic: Time step") + r"dynamic time step 0\.0 s: a dynamic case \(end time 30\.0 s\)"),
        BadInput("wave period 0", don, "waves of 1.5 m, period 0",
                 _don(nr, ("Wave period (s):                    10.000000", "Wave period (s):   0"),
                      ("Wave height (m):                    0.000000", "Wave height (m):    1.5")), E,
                 _at(nr, "Wave period") + r"wave period 0\.0 s: waves of height 1\.5 m need a period > 0"),
        BadInput("no fixed node type", don, "type 1 'Displacement X,Y,Z: 0 0 0'",
                 _don(nr, (_TYPE_1_MASS, _TYPE_1_MASS.replace("Displacement X,Y,Z:        1  1  1",
                                                              "Displacement X,Y,Z:        0  0  0"))), E,
                 _at(nr, "No du type :            1") + r"the net with its node types: no node is fixed"),
        BadInput("unsupported: sliding cables", don, "'Sliding cables number: 1'",
                 _don(nr, ("Sliding cables number: 0", "Sliding cables number: 1")), E,
                 _at(nr, "Sliding cables number") + r"sliding cables number 1: sliding cables are not supported"),
        BadInput("unsupported: twines as bars", don, "panel 1: 'Meshing type: 3'",
                 _don(nr, ("Meshing type:\t\t\t\t2", "Meshing type:\t\t\t\t3")), E,
                 _at(nr, "Meshing type") + r"panel 1: meshing type 3 \(twines as bar elements\) is not supported"),
        BadInput("unsupported: input spheric_limit", don, "'input spheric_limit 0 0 0 5 1e5 1e5'",
                 _don(nr, ("input water_density 1000", "input water_density 1000\ninput spheric_limit 0 0 0 5 1e5 1e5")),
                 E, rf"{re.escape(nr)}\.don:{_line(nr, 'input water_density') + 1}: "
                 + r"'input spheric_limit': a spherical limit: a FEMNET feature jaxnet does not model yet"),
        BadInput("design plane axis 4", don, "'design in the plane normal to axis: 4'",
                 _don(nr, ("design in the plane normal to axis: 3", "design in the plane normal to axis: 4")), E,
                 _at(nr, "design in the plane") + r"design in the plane normal to axis 4: an axis is 1, 2 or 3"),
        BadInput("unsupported: input command", don, "'input wind_speed 10'",
                 _don(nr, ("input water_density 1000", "input wind_speed 10")), E,
                 _at(nr, "input water_density") + r"'input wind_speed': unknown input command, not supported"),
        BadInput("unsupported: hexagonal netting in a current", don, "hexagonal.don at 0.5 m/s",
                 _don("hexagonal", ("Current speed (m/s):                    0.000000",
                                    "Current speed (m/s):                    0.5")), E,
                 _at("hexagonal", "Current speed") + r"current speed 0\.5 m/s with hexagonal panels"),
        BadInput("missing .don file", don, "a path that does not exist",
                 _read_missing("none.don"), E,
                 r"FEMNET case .*none\.don does not exist"),
    ]
    kinds = [c.kind + " @ " + c.level for c in cases]
    assert len(set(kinds)) == len(kinds), "bad-input catalogue: a kind is listed twice"
    return tuple(cases)


def _read_missing(name):
    """An attempt: read a file that does not exist (a scene file, or a .don case, by its suffix)."""
    def run(folder):
        from jaxnet.io import femnet, scene_file

        path = folder / name
        return femnet.read_don(path) if path.suffix == ".don" else scene_file.read(path)
    return run


def _hexagonal_in_current(folder):
    import jaxnet as jn
    from jaxnet.net import HexTwine, Net

    net = Net(jn.Environment(current_speed=0.5))
    panel = net.panel("hex", [(0, 0, -0.5, 0, 0), (0, 0, 0, 5, 0), (0, 0.5, 0, 5, 5), (0, 0.5, -0.5, 0, 5)],
                      HexTwine(l0=0.02, ea=1000.0, diameter=1e-3), 0.1)
    net.fix(panel.side(1))
    return net.build()


CASES = _catalogue()


# -- accepted by design -----------------------------------------------------------------------------------------


def _accepted_by_design():
    """Inputs that look wrong but are meant (README, docs): measured to be accepted, with what happens."""
    import jax.numpy as jnp

    from jaxnet.model import catch as catch_lib
    from jaxnet.net import Net
    from jaxnet.scenes import codend

    rows = []
    scene = codend(catch_m3=1000.0).scene
    c = scene.catch
    front = catch_lib.catch_front(jnp.asarray(scene.nodes.position), jnp.asarray(scene.netting.vertices),
                                  jnp.asarray(c.axis), c.volume, c.symmetry, jnp.asarray(scene.netting.outward))
    rows.append({"kind": "catch larger than the net", "input": "codend(catch_m3=1000)",
                 "what happens": "built; the front sits at the opening, the whole net carries the pressure "
                                 "(FEMNET's behaviour; result.json reports catch.holds_the_volume)",
                 "nodes": scene.n_nodes, "catch held at the start shape": bool(front.holds)})
    net = Net()
    twine = _twine()
    a = net.panel("a", SQUARE, twine, 0.1)
    b = net.panel("b", [(0, 0, 1, 0, 0), (1, 0, 1, 18, -18), (1, 0, 2, 36, 0), (0, 0, 2, 18, 18)], twine, 0.1)
    net.seam(a.side(2), b.side(0))
    net.fix(b.side(2))
    scene = net.build()
    rows.append({"kind": "seam between sides of different mesh counts", "input": "20 meshes sewn to 18",
                 "what happens": "built: both sides take the larger division, each panel keeps its own twine "
                                 "coordinates (README, Seams)", "nodes": scene.n_nodes,
                 "catch held at the start shape": None})
    return rows


# -- the report section -----------------------------------------------------------------------------------------


def _row(number, case: BadInput, outcome: Outcome, folder: pathlib.Path):
    message = outcome.message.replace(str(folder) + "/", "")
    return {
        "#": number,
        "kind": case.kind,
        "input": case.input,
        "exception": "none" if outcome.raised is None else type(outcome.raised).__name__,
        "message": message[:MESSAGE_CHARS] + ("…" if len(message) > MESSAGE_CHARS else ""),
        "names the culprit": outcome.names_culprit(case),
        "before compilation": not outcome.compiled,
        "time (ms)": 1e3 * outcome.seconds,
        "as expected": outcome.as_expected(case),
        "pending": case.pending,
    }


def run(report, quick: bool) -> None:
    """Run every case of :data:`CASES` (the same in quick and full mode: each takes milliseconds, the solved
    ones seconds) and tabulate what each got, per level."""
    report.text(
        "Each row is one kind of malformed input (the catalogue `validation.bad_input.CASES`, also run by "
        "`tests/validation/test_bad_input_sweep.py`). *exception* and *message* are what jaxnet raised; *names the culprit* "
        "is whether the message matches the case's regular expression, which names the panel, cable, node, "
        "triangle or parameter at fault (for a `.don` file: `file:LINE` of the culprit line, found in FEMNET's "
        "case file); *before compilation* is whether the error came before the solver compiled anything (the "
        "solver's compiled entry points are replaced by tripwires during each case). *as expected* is all "
        "three, with the expected exception type. A case marked *pending* still lacks its check in the library "
        "file named (outside this section's reach). A scene file's message starts with the file and the line of "
        "the culprit (`scene.toml:7: ...`), found in the text each case writes.")
    levels = list(dict.fromkeys(c.level for c in CASES))
    names = {"net": "The Net builder (panels, cables, seams, fixings, loads, environment)",
             "scene": "Scenes edited by hand, given to jaxnet.solve_static",
             "solver": "Solver options", "dynamics": "Dynamics options", "waves": "Waves",
             "scene file": "Scene files (JSON, TOML)", ".don": "FEMNET .don files"}
    records, number = [], 0
    with tempfile.TemporaryDirectory(prefix="jaxnet-bad-input-") as scratch:
        for level in levels:
            rows = []
            for case in (c for c in CASES if c.level == level):
                number += 1
                folder = pathlib.Path(scratch) / str(number)
                outcome = attempt(case, folder)
                row = _row(number, case, outcome, folder)
                rows.append(row)
                records.append({**row, "level": level, "culprit regex": case.culprit, "message": outcome.message,
                                "expected": case.error.__name__, "solved": case.solve})
                print(f"[bad_input] {number:3d} {level:10s} {case.kind:45s} {row['exception']:14s} "
                      f"culprit={'yes' if row['names the culprit'] else 'NO'} "
                      f"compiled={'yes' if outcome.compiled else 'no'} {row['time (ms)']:.0f} ms", flush=True)
            report.heading(names.get(level, level))
            report.table(rows, columns=["#", "kind", "input", "exception", "message", "names the culprit",
                                        "before compilation", "time (ms)", "as expected", "pending"],
                         formats={"time (ms)": ".1f"})
            report.record("bad_input", records)
    kinds = len({c.kind for c in CASES})
    good = sum(r["as expected"] for r in records)
    pending = [r for r in records if r["pending"]]
    report.heading("Summary")
    report.table([{"cases": len(records), "distinct kinds": kinds, "as expected": good,
                   "pending (check missing in the library)": len(pending),
                   "named the culprit": sum(r["names the culprit"] for r in records),
                   "raised before compilation": sum(r["before compilation"] for r in records)}])
    if pending:
        report.text("Pending checks (not in this section's files): "
                    + "; ".join(f"#{r['#']} {r['kind']} -> {r['pending']}" for r in pending) + ".")
    report.heading("Accepted by design")
    report.text("Inputs that look malformed but are meant, measured to be accepted here. A catch larger than "
                "the net can hold is how a whole net is put under the catch pressure (the textbook pressurised tube "
                "of `jaxnet.scenes.textbook` relies on it); seams join sides of different mesh counts by design (book "
                "Fig. 4.5), so no seam is refused for its length. Waves and dynamic settings in a `.don` file are "
                "read (they go to `Environment.waves` and `info['dynamic']`), so the `.don` rows above refuse the "
                "features that are not modelled instead (sliding cables, twines as bars, a spherical limit, ...).")
    report.table(_accepted_by_design())
