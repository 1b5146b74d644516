"""jaxnet: a differentiable simulator of fishing nets and aquaculture netting on JAX.

Implements D. Priour's triangular finite element for netting (the FEMNET model). float64 is switched on
here, on import: netting tangents span EA/l0 against tiny geometric stiffness, which float32 cannot hold.

The names a user needs first are here: describe a net (:class:`Net`, :class:`Twine`, :class:`Rope`, ...) or
read one (:func:`read_don`, :func:`read_mdg`, :func:`read_scene`, the built-in :mod:`jaxnet.scenes`), each
giving a :class:`Case`; solve it (:func:`solve_static`, :func:`simulate`) into an :class:`Equilibrium` or a
:class:`Trajectory`. The subpackages hold the rest: :mod:`jaxnet.solve` (drivers, kernel, options),
:mod:`jaxnet.terms` (the physics), :mod:`jaxnet.design` (gradients of equilibria), :mod:`jaxnet.io` (readers
and writers).
"""

from importlib import metadata as _metadata

import jax

jax.config.update("jax_enable_x64", True)

try:
    #: the installed package's version (``pyproject.toml``), as ``jaxnet --version`` and result.json give it
    __version__ = _metadata.version("jaxnet")
except _metadata.PackageNotFoundError:  # run from a source tree that was not installed
    __version__ = "0+unknown"

from jaxnet import scenes  # noqa: E402
from jaxnet.case import Case, TimeSettings  # noqa: E402
from jaxnet.checks import validate  # noqa: E402
from jaxnet.forcing import Loading  # noqa: E402
from jaxnet.io.femnet import read_don, read_mdg  # noqa: E402
from jaxnet.io.scene_file import read as read_scene  # noqa: E402
from jaxnet.net import HexTwine, Net, NumericalTwines, Rope, Twine  # noqa: E402
from jaxnet.scene import Bars, Environment, Netting, Nodes, Scene, SceneError  # noqa: E402
from jaxnet.solve.dynamics import DynamicsError, Trajectory, simulate  # noqa: E402
from jaxnet.solve.options import Implicit, Newton  # noqa: E402
from jaxnet.solve.results import Equilibrium, SolveError  # noqa: E402
from jaxnet.solve.statics import solve as solve_static  # noqa: E402

__all__ = [
    "Case", "TimeSettings", "Loading", "read_don", "read_mdg", "read_scene", "scenes",
    "Net", "Twine", "Rope", "HexTwine", "NumericalTwines",
    "Bars", "Environment", "Netting", "Nodes", "Scene", "SceneError", "validate",
    "Newton", "Implicit", "Equilibrium", "SolveError", "solve_static", "Trajectory", "DynamicsError", "simulate",
]
