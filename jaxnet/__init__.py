"""jaxnet: a differentiable simulator of fishing nets and aquaculture netting on JAX.

Implements D. Priour's triangular finite element for netting (the FEMNET model). float64 is switched on by
the package: netting tangents span EA/l0 against tiny geometric stiffness, which float32 cannot hold.

The names a user needs first are here: describe a net (:class:`Net`, :class:`Twine`, :class:`Rope`, ...) or
read one (:func:`read_don`, :func:`read_mdg`, :func:`read_scene`, the built-in :mod:`jaxnet.scenes`), each
giving a :class:`Case`; solve it (:func:`solve_static`, :func:`simulate`, the run layer :mod:`jaxnet.run`) into
an :class:`Equilibrium` or a :class:`Trajectory`. The subpackages hold the rest, layer by layer
(``docs/architecture.md``): :mod:`jaxnet.water` (current, waves, loads in time), :mod:`jaxnet.scene` (the
arrays and their checks), :mod:`jaxnet.terms` (the physics), :mod:`jaxnet.model` (active terms, assembly),
:mod:`jaxnet.linalg` (factorisations), :mod:`jaxnet.solve` (solvers, kernel, options), :mod:`jaxnet.design`
(gradients of equilibria), :mod:`jaxnet.io` (readers and writers).

Importing the package loads neither JAX nor any of its modules: each public name is imported when it is first
used (PEP 562), so that ``jaxnet --version``, ``jaxnet --help`` and a run's first line come at once, and a run
imports only what it uses. float64 is switched on as JAX is imported (:class:`_Float64OnImport`), or at once
when JAX was imported before jaxnet.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys

from jaxnet.version import __version__  # noqa: F401  (the installed package's version)


class _Float64OnImport(importlib.abc.MetaPathFinder):
    """Switches JAX's float64 on (``jax_enable_x64``) as soon as ``jax`` has been imported, whoever imports it
    first (a jaxnet module, equinox, the user): JAX fixes the precision of the arrays it makes from then on.

    It finds ``jax`` as the import system would without it, and wraps that loader's ``exec_module`` so that the
    setting follows the package's own initialisation; then it takes itself off ``sys.meta_path``. An environment
    variable (``JAX_ENABLE_X64``) would do the same but leak into every process started from this one."""

    def find_spec(self, name, path=None, target=None):
        if name != "jax":
            return None
        sys.meta_path.remove(self)
        spec = importlib.util.find_spec("jax")
        if spec is None or spec.loader is None:
            return spec
        execute = spec.loader.exec_module

        def exec_module(module):
            execute(module)
            module.config.update("jax_enable_x64", True)

        spec.loader.exec_module = exec_module
        return spec


if "jax" in sys.modules:
    sys.modules["jax"].config.update("jax_enable_x64", True)
elif not any(isinstance(finder, _Float64OnImport) for finder in sys.meta_path):
    sys.meta_path.insert(0, _Float64OnImport())

#: modules that moved into the folders of their layer, by their former name: importable under it for one
#: release (the same module object, with a DeprecationWarning), through :class:`_MovedModules`
MOVED = {
    "jaxnet.current": "jaxnet.water.current", "jaxnet.waves": "jaxnet.water.waves",
    "jaxnet.spectra": "jaxnet.water.spectra", "jaxnet.forcing": "jaxnet.water.forcing",
    "jaxnet.pardiso": "jaxnet.linalg.pardiso", "jaxnet.cudss": "jaxnet.linalg.cudss",
    "jaxnet.assemble": "jaxnet.model.assemble", "jaxnet.catch": "jaxnet.model.catch",
    "jaxnet.checks": "jaxnet.scene.checks",
}


class _MovedModules(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds a module by its former name (:data:`MOVED`) and gives the module under its new name: one object
    under both names, so that state and patches are shared."""

    def find_spec(self, name, path=None, target=None):
        if name not in MOVED:
            return None
        return importlib.util.spec_from_loader(name, self)

    def create_module(self, spec):
        import warnings

        warnings.warn(f"{spec.name} moved to {MOVED[spec.name]}; the old name goes in the next release",
                      DeprecationWarning, stacklevel=3)
        return importlib.import_module(MOVED[spec.name])

    def exec_module(self, module):
        pass


if not any(isinstance(finder, _MovedModules) for finder in sys.meta_path):
    sys.meta_path.append(_MovedModules())

#: public name -> the module that defines it (its attribute of the same name, or of the name after ':')
_PUBLIC = {
    "Case": "jaxnet.case", "TimeSettings": "jaxnet.case",
    "Loading": "jaxnet.water.forcing",
    "read_don": "jaxnet.io.femnet", "read_mdg": "jaxnet.io.femnet",
    "read_scene": "jaxnet.io.scene_file:read",
    "Net": "jaxnet.net", "Twine": "jaxnet.net", "Rope": "jaxnet.net", "HexTwine": "jaxnet.net",
    "NumericalTwines": "jaxnet.net",
    "Bars": "jaxnet.scene", "Environment": "jaxnet.scene", "Netting": "jaxnet.scene", "Nodes": "jaxnet.scene",
    "Scene": "jaxnet.scene", "SceneError": "jaxnet.scene",
    "validate": "jaxnet.scene.checks",
    "Newton": "jaxnet.solve.options", "Implicit": "jaxnet.solve.options",
    "Equilibrium": "jaxnet.solve.results", "SolveError": "jaxnet.solve.results",
    "solve_static": "jaxnet.run",
    "Trajectory": "jaxnet.solve.dynamics", "DynamicsError": "jaxnet.solve.dynamics",
    "simulate": "jaxnet.run",
}

__all__ = [
    "Case", "TimeSettings", "Loading", "read_don", "read_mdg", "read_scene", "scenes",
    "Net", "Twine", "Rope", "HexTwine", "NumericalTwines",
    "Bars", "Environment", "Netting", "Nodes", "Scene", "SceneError", "validate",
    "Newton", "Implicit", "Equilibrium", "SolveError", "solve_static", "Trajectory", "DynamicsError", "simulate",
]


def __getattr__(name):
    """A public name (:data:`_PUBLIC`) or a subpackage (``jaxnet.solve``, ``jaxnet.scenes``...), imported on first
    use and kept in the package's namespace."""
    if name in _PUBLIC:
        module, _, attribute = _PUBLIC[name].partition(":")
        value = getattr(importlib.import_module(module), attribute or name)
    elif importlib.util.find_spec(f"{__name__}.{name}") is not None:
        value = importlib.import_module(f"{__name__}.{name}")
    else:
        raise AttributeError(f"module 'jaxnet' has no attribute '{name}'")
    globals()[name] = value
    return value


def __dir__():
    return sorted(set(globals()) | set(_PUBLIC) | {"scenes"})
