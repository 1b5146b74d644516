"""Scene files' errors name the file, the line and the key path of the culprit (README, "Scene files"), with the
nearest key for a misspelt one; a material's error names its table, not a panel that uses it; a stiffness of 0
or below is bad input (exit status 2 from the command line), refused before anything is built.

The files are those ``jaxnet export`` writes (:func:`jaxnet.io.scene_export.write`) and hand-written ones. The
messages start with the file's path, a temporary folder's: the tests take that prefix off (the folder's name holds
the test's name) and check the line against the text they wrote.
"""

import json
import re

import numpy as np
import pytest

from jaxnet import cli
from jaxnet.io import scene_export, scene_file
from jaxnet.net import Net, Rope, Twine
from jaxnet.scene import SceneError

#: a square panel of 20 x 20 meshes held along its top side, in a current, with a headline
SQUARE = [(0, 0, 0, 0, 0), (1, 0, 0, 20, -20), (1, 0, 1, 40, 0), (0, 0, 1, 20, 20)]


def _net():
    import jaxnet as jn

    net = Net(jn.Environment(current_speed=0.5))
    wall = net.panel("wall 0", SQUARE, Twine(l0=0.02, ea=1000.0, diameter=1e-3), 0.1)
    net.cable("headline", along=wall.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    net.fix(wall.side(2))
    return net


def _written(tmp_path, suffix, old=None, new=None):
    """(path, text): the net of :func:`_net` written by ``jaxnet export``'s writer, ``old`` replaced by ``new``
    (found once)."""
    path = tmp_path / f"scene{suffix}"
    scene_export.write(path, _net())
    text = path.read_text()
    if old is not None:
        assert text.count(old) == 1, old
        text = text.replace(old, new)
        path.write_text(text)
    return path, text


def _located(path, error):
    """(line, the rest of the message) of a scene file's SceneError "PATH:LINE: ...", the path taken off."""
    message = str(error)
    assert message.startswith(f"{path}:"), message
    found = re.match(r":(\d+): (.*)$", message.removeprefix(str(path)), re.S)
    assert found, message
    return int(found.group(1)), found.group(2)


def _line(text, needle):
    return text[:text.index(needle)].count("\n") + 1


@pytest.mark.parametrize("suffix, old, new", [(".toml", "current_speed = 0.5", "curent_speed = 0.5"),
                                              (".json", '"current_speed": 0.5', '"curent_speed": 0.5')])
def test_a_misspelt_key_names_its_line_and_the_nearest_key(tmp_path, suffix, old, new):
    path, text = _written(tmp_path, suffix, old, new)
    with pytest.raises(SceneError) as err:
        scene_file.read(path)
    line, rest = _located(path, err.value)
    assert line == _line(text, "curent_speed") > 1
    assert rest.startswith("environment: unknown key(s) ['curent_speed']: did you mean current_speed? (allowed: [")


def test_a_material_tables_error_names_the_table_and_its_line_not_the_panel(tmp_path):
    path, text = _written(tmp_path, ".toml", "diameter = 0.001", "diameter = -0.001")
    assert '[twines."wall 0"]' in text and 'twine = "wall 0"' in text   # the table a panel names
    with pytest.raises(SceneError) as err:
        scene_file.read(path)
    line, rest = _located(path, err.value)
    assert line == _line(text, "diameter = -0.001")
    assert rest == 'twines."wall 0": diameter must be >= 0, got -0.001'
    # the panel's own entry gets the panel's errors, at its key
    path, text = _written(tmp_path, ".toml", "step = 0.1", "step = -0.1")
    with pytest.raises(SceneError) as err:
        scene_file.read(path)
    line, rest = _located(path, err.value)
    assert (line, rest) == (_line(text, "step = -0.1"), "panel 'wall 0': step must be a positive finite number, "
                                                        "got step=-0.1")


@pytest.mark.parametrize("table, old", [("twines.\"wall 0\"", "ea = 1000.0"), ("ropes.headline", "ea = 50000.0")])
def test_zero_traction_stiffness_is_named_at_its_line(tmp_path, table, old):
    path, text = _written(tmp_path, ".toml", old, "ea = 0.0")
    with pytest.raises(SceneError) as err:
        scene_file.read(path)
    line, rest = _located(path, err.value)
    assert line == _line(text, "ea = 0.0")
    assert rest == f"{table}: ea must be > 0, got 0.0 (traction stiffness EA, N)"


def test_zero_stiffness_is_bad_input_on_the_command_line(tmp_path, capsys):
    """``jaxnet run`` of a file whose twine has EA = 0: exit status 2, the message naming the file's line, the
    material and EA, and nothing solved (no result written)."""
    path, text = _written(tmp_path, ".toml", "ea = 1000.0", "ea = 0.0")
    out = tmp_path / "out"
    assert cli.main(["run", str(path), "--out", str(out), "--no-cache", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert f':{_line(text, "ea = 0.0")}: twines."wall 0": ea must be > 0, got 0.0 (traction stiffness EA, N)' in err
    assert "bad input" in err and not (out / "result.json").exists()
    # a compression stiffness of 0 is a twine that goes slack: accepted
    path, _ = _written(tmp_path, ".toml")
    assert "ea_compression = 0.0" in path.read_text()
    assert scene_file.read(path).scene.n_nodes > 4


def test_hand_written_toml_errors_find_their_lines(tmp_path):
    """Comments, a multi-line array, quoted and dotted keys, inline tables, arrays of tables: each error is at the
    line of its key."""
    text = """# a hand-written scene: "quotes" and [brackets] in a comment
environment.current_speed = 0.5   # dotted key

[twines.'wall 0']
l0 = 0.02
"ea" = 1000.0
diameter = 0.001

[[panels]]
name = "wall"
corners = [
    [0, 0, 0, 0, 0],   # corner 0
    [1, 0, 0, 20, -20],
    [1, 0, 1, 40, 0],
    [0, 0, 1, 20, 20],
]
twine = 'wall 0'
step = 0.1

[[panels]]
name = "roof"
corners = [[0, 0, 1, 0, 0], [1, 0, 1, 20, -20], [1, 0, 2, 40, 0], [0, 0, 2, 20, 20]]
twine = {l0 = 0.02, ea = 1000.0, diameter = 0.001}
step = 0.1

[[fix]]
at = {panel = "roof", side = 2}

[[fix]]
at = {panel = "wall", side = 9}
"""
    path = tmp_path / "hand.toml"
    cases = [
        # (old, new, the needle of the line, the message)
        ("[1, 0, 1, 40, 0],", "[1, 0, 1, 40],", "[1, 0, 1, 40],", "panels[0].corners: expected rows of 5 numbers"),
        ("twine = {l0 = 0.02, ea = 1000.0", "twine = {l0 = 0.02, ea = -1.0", "twine = {",
         "panels[1].twine: ea must be > 0, got -1.0 (traction stiffness EA, N)"),
        ("twine = {l0 = 0.02,", "twine = {l0 = 0.02, EA = 5,", "twine = {",
         "panels[1].twine: unknown key(s) ['EA']: did you mean ea?"),
        ("twine = 'wall 0'", "twine = 'wal 0'", "twine = 'wal 0'",
         "panels[0].twine: no material named 'wal 0': did you mean 'wall 0'?"),
        ('"ea" = 1000.0', '"ea" = -5.0', '"ea" = -5.0', 'twines."wall 0": ea must be > 0, got -5.0'),
        ("environment.current_speed", "environment.curent_speed", "environment.curent",
         "environment: unknown key(s) ['curent_speed']: did you mean current_speed?"),
        # an error of the built net that names a reference is at the line of the reference
        (None, None, "side = 9}", "reference side 9 of panel 'wall': panel 'wall' has no side 9 (it has 4)"),
    ]
    for old, new, needle, message in cases:
        written = text if old is None else text.replace(old, new)
        assert written.count(needle) == 1, needle
        path.write_text(written)
        with pytest.raises(SceneError) as err:
            scene_file.read(path)
        line, rest = _located(path, err.value)
        assert (line, rest[:len(message)]) == (_line(written, needle), message), str(err.value)
    # a syntax error names the line too
    path.write_text(text.replace("[[fix]]\nat = {panel = \"roof\"", "[[fix]\nat = {panel = \"roof\""))
    with pytest.raises(SceneError) as err:
        scene_file.read(path)
    line, rest = _located(path, err.value)
    assert line == _line(text, '[[fix]]\nat = {panel = "roof"') and rest.startswith("cannot parse: ")


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_every_key_of_an_exported_file_is_found_at_its_line(tmp_path, suffix):
    """Every key of a written built-in scene (materials, panels, cables, references, sinkers, ...) is located at
    the line that holds it: what a key's error reports."""
    from jaxnet.scenes import fish_cage

    path = tmp_path / f"cage{suffix}"
    scene_export.write(path, fish_cage())
    text = path.read_text()
    doc = scene_file.parse_text(text, suffix)
    lines = text.split("\n")

    def keys(value, where):
        if isinstance(value, dict):
            for k, v in value.items():
                yield where + (k,)
                yield from keys(v, where + (k,))
        elif isinstance(value, list):
            for i, v in enumerate(value):
                yield from keys(v, where + (i,))

    checked = 0
    for where in keys(doc, ()):
        line = scene_file._line(text, suffix, where)
        key = where[-1]
        spelled = f'"{key}"' if suffix == ".json" or not re.fullmatch(r"[A-Za-z0-9_-]+", key) else key
        # a table written as a [header] holds its key there; a key of a table holds it at its own line
        assert spelled in lines[line - 1], (where, line, lines[line - 1])
        checked += 1
    assert checked > 300   # every material parameter, panel, cable, reference, sinker of the cage


def test_a_scene_built_by_hand_with_a_zero_stiffness_row_is_refused_naming_the_element():
    import jaxnet as jn

    scene = _net().build()
    ea = np.asarray(scene.netting.ea_traction).copy()
    ea[5] = 0.0
    bad = jn.Scene(nodes=scene.nodes, netting=scene.netting.__class__(**{**scene.netting.__dict__, "ea_traction": ea}),
                   bars=scene.bars, panel_names=scene.panel_names, cable_names=scene.cable_names)
    with pytest.raises(SceneError, match=r"^triangle 5 \(wall 0\): traction stiffness EA must be > 0, got 0\.0$"):
        jn.validate(bad)


def test_json_duplicate_and_nested_paths_are_named_in_the_files_notation(tmp_path):
    """Key paths are written as the file's keys: a name with a blank quoted (``twines."wall 0"``), an index in
    brackets."""
    path, text = _written(tmp_path, ".json", '"along": {', '"along": {"sid": 2, ')
    with pytest.raises(SceneError) as err:
        scene_file.read(path)
    line, rest = _located(path, err.value)
    assert line == _line(text, '"sid"')
    assert rest.startswith("cables[0].along: unknown key(s) ['sid']: did you mean side?")
    assert json.loads(text)["cables"][0]["along"]["sid"] == 2
