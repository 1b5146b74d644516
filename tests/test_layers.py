"""The package's layers, read from its imports: data flows one way (``docs/architecture.md``).

Every module of ``jaxnet`` belongs to one layer, by the longest prefix of its dotted name in :data:`LAYERS`;
a module may import modules of its own layer and of the layers below it, never of a layer above. The imports
are read from the sources (every ``import`` and ``from ... import`` statement, those inside functions too):
a lazy import is an arrow all the same.
"""

import ast
import pathlib
import warnings

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parent.parent / "jaxnet"

#: the layers from the bottom up, each with the module prefixes that make it (``docs/architecture.md``)
LAYERS = [
    ("foundation", ["jaxnet.geometry", "jaxnet.memo", "jaxnet.version"]),
    ("water", ["jaxnet.water"]),
    ("scene", ["jaxnet.scene"]),
    ("physics", ["jaxnet.terms", "jaxnet.closed_form"]),
    ("model", ["jaxnet.model", "jaxnet.scene.checks"]),
    ("sparse linear algebra", ["jaxnet.linalg"]),
    ("solvers", ["jaxnet.solve"]),
    ("description", ["jaxnet.materials", "jaxnet.mesh", "jaxnet.net", "jaxnet.build", "jaxnet.case", "jaxnet.catalogue",
                     "jaxnet.scenes", "jaxnet.io.scene_file", "jaxnet.io.femnet.grammar", "jaxnet.io.femnet.links",
                     "jaxnet.io.femnet.mapping", "jaxnet.io.femnet.materials", "jaxnet.io.femnet.surroundings",
                     "jaxnet.io.femnet.motion", "jaxnet.io.femnet.mdg", "jaxnet.io.femnet.parse",
                     "jaxnet.io.femnet.reader", "jaxnet.io.femnet.twines", "jaxnet.io.femnet.writer"]),
    ("results", ["jaxnet.figures", "jaxnet.io", "jaxnet.io.femnet.results"]),
    ("facades", ["jaxnet.io.femnet"]),  # the FEMNET package's public names: its readers and its results
    ("run", ["jaxnet.run"]),
    ("design", ["jaxnet.design"]),
    ("interface", ["jaxnet", "jaxnet.cli"]),
]
LEVEL = {prefix: level for level, (_, prefixes) in enumerate(LAYERS) for prefix in prefixes}


def module_name(path):
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def layer_of(name):
    """The level of a module: that of the longest prefix of its name in :data:`LAYERS`."""
    parts = name.split(".")
    for k in range(len(parts), 0, -1):
        prefix = ".".join(parts[:k])
        if prefix in LEVEL:
            return LEVEL[prefix]
    raise KeyError(name)


def imported(path, name):
    """The jaxnet modules (or packages) that the module at ``path`` imports, with their line numbers."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "jaxnet":
                    yield alias.name, node.lineno
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[:len(package.split(".")) - node.level + 1] + ([base] if base else []))
            if base.split(".")[0] != "jaxnet":
                continue
            for alias in node.names:  # a name imported from a package may be a module of it
                candidate = f"{base}.{alias.name}"
                is_module = (PACKAGE.parent / candidate.replace(".", "/")).with_suffix(".py").exists() or \
                    (PACKAGE.parent / candidate.replace(".", "/") / "__init__.py").exists()
                yield (candidate if is_module else base), node.lineno


MODULES = sorted(PACKAGE.rglob("*.py"))


def test_every_module_has_a_layer():
    names = [module_name(p) for p in MODULES]
    assert len(names) > 90
    for name in names:
        layer_of(name)


def test_no_import_points_up_the_layers():
    upward = []
    for path in MODULES:
        name = module_name(path)
        for target, line in imported(path, name):
            if target == "jaxnet" and name == "jaxnet":
                continue
            if layer_of(target) > layer_of(name):
                upward.append(f"{path.relative_to(PACKAGE.parent)}:{line}: {LAYERS[layer_of(name)][0]} "
                              f"{name} imports {LAYERS[layer_of(target)][0]} {target}")
    assert not upward, "\n".join(upward)


def test_the_check_sees_an_upward_import():
    """The rule has teeth: a solver that imported the description (as statics once imported the Case) and a
    relative import of the run layer are both found."""
    source = "from jaxnet.case import Case\nfrom .. import run\n"
    path = PACKAGE / "solve" / "statics.py"
    name = module_name(path)
    targets = {t for t, _ in imported_source(source, path, name)}
    assert targets == {"jaxnet.case", "jaxnet.run"}
    assert all(layer_of(t) > layer_of(name) for t in targets)


def imported_source(source, path, name):
    class Fake:
        def __init__(self, text, real):
            self.text, self.name = text, real.name

        def read_text(self):
            return self.text

    return imported(Fake(source, path), name)


@pytest.mark.parametrize("old, new", [("jaxnet.forcing", "jaxnet.water.forcing"),
                                      ("jaxnet.checks", "jaxnet.scene.checks"),
                                      ("jaxnet.assemble", "jaxnet.model.assemble")])
def test_a_moved_module_is_importable_by_its_former_name_for_one_release(old, new):
    import importlib
    import sys

    import jaxnet

    assert jaxnet.MOVED[old] == new
    sys.modules.pop(old, None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        module = importlib.import_module(old)
    assert module is importlib.import_module(new)
    assert any(issubclass(w.category, DeprecationWarning) and new in str(w.message) for w in caught)
