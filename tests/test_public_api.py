"""The public namespace imports as documented: the subpackages are not shadowed, the top-level names are
the library's own objects, and every name the README's code imports exists."""

from __future__ import annotations

import ast
import importlib
import importlib.util
import pathlib
import re
import pytest

import jaxnet

README = pathlib.Path(__file__).parents[1] / "README.md"


def test_the_solve_subpackage_is_not_shadowed():
    import jaxnet.run as run
    import jaxnet.solve.dynamics  # noqa: F401  (failed while jaxnet.solve was bound to a function)

    assert jaxnet.solve is importlib.import_module("jaxnet.solve")
    assert jaxnet.simulate is run.simulate and jaxnet.solve_static is run.solve_static


def test_every_public_name_resolves():
    from jaxnet.case import Case
    from jaxnet.io import femnet
    from jaxnet.net import Net, Twine
    from jaxnet.solve.options import Newton

    missing = [name for name in jaxnet.__all__ if not hasattr(jaxnet, name)]
    assert not missing
    assert (jaxnet.Case, jaxnet.Net, jaxnet.Twine, jaxnet.Newton, jaxnet.read_don) == (Case, Net, Twine, Newton,
                                                                                       femnet.read_don)


DOCS = sorted((README.parent / "docs").glob("*.md"))


def _python_blocks(path):
    return re.findall(r"```python\n(.*?)```", path.read_text(), flags=re.S)


def _readme_code():
    return "\n".join(_python_blocks(README))


@pytest.mark.parametrize("path", DOCS, ids=lambda p: p.name)
def test_what_the_docs_import_exists(path):
    """The Python of every page of docs/ parses, and what it imports from jaxnet exists."""
    for block in _python_blocks(path):
        for node in ast.walk(ast.parse(block)):
            if isinstance(node, ast.ImportFrom) and node.module.startswith("jaxnet"):
                module = importlib.import_module(node.module)
                for alias in node.names:
                    assert hasattr(module, alias.name) or importlib.util.find_spec(f"{node.module}.{alias.name}"), \
                        f"{path.name}: from {node.module} import {alias.name}"


def test_the_readmes_example_runs_and_balances(tmp_path, monkeypatch, capsys):
    """The README's first example, run as it is written: the wall converges, and the reaction of its fixings
    balances the forces of the groups it prints (N); the current goes through the wall, not along it, so it
    pushes the wall downstream, and the sinker bar, a rod, keeps the foot as wide as the wall was drawn."""
    import numpy as np

    monkeypatch.chdir(tmp_path)
    namespace = {}
    exec(_python_blocks(README)[0], namespace)
    eq, scene = namespace["eq"], namespace["scene"]
    assert eq.converged
    forces = namespace["figures"].summary(scene, eq)["forces_N"]
    total = np.asarray(eq.reaction(scene)).sum(axis=0) + np.sum([np.asarray(f) for f in forces.values()], axis=0)
    assert np.abs(total).max() < 1e-6 * np.abs(np.asarray(forces["weight_and_buoyancy_N"])).max()
    assert forces["drag_netting_N"][0] > 0  # the current pushes the wall downstream
    w = namespace["w"]
    x = np.asarray(eq.x)
    foot = np.asarray(scene.bars.ends)[np.asarray(scene.bars.cable) == scene.cable_names.index("sinker bar")]
    foot = np.unique(foot)
    # through the wall: the foot swings downstream by a good part of the wall's height (edge-on it would not move)
    assert x[foot, 0].mean() > 0.2 * w
    # the sinker bar keeps the foot as wide as the wall was drawn, to 1 % (the rod bows a little in the current);
    # netting whose foot is free closes its meshes there and gathers it to a small fraction of that
    width = np.ptp(x[foot, 1])
    assert abs(width - w) < 1e-2 * w
    assert (tmp_path / "wall.png").exists() and (tmp_path / "wall.vtu").exists()


def test_what_the_readme_imports_exists():
    tree = ast.parse(_readme_code())
    imported = 0
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module.startswith("jaxnet"):
            module = importlib.import_module(node.module)
            for alias in node.names:
                assert hasattr(module, alias.name) or importlib.util.find_spec(f"{node.module}.{alias.name}"), \
                    f"README: from {node.module} import {alias.name}"
                imported += 1
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("jaxnet"):
                    importlib.import_module(alias.name)
                    imported += 1
    # jn.NAME as the README uses it (import jaxnet as jn)
    used = set(re.findall(r"\bjn\.([A-Za-z_]+)", _readme_code()))
    assert used and not [name for name in used if not hasattr(jaxnet, name)]
    assert imported >= 5
