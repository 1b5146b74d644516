"""jaxnet: a differentiable simulator of fishing nets and aquaculture netting on JAX.

Implements D. Priour's triangular finite element for netting (the FEMNET model). float64 is switched on
here, on import: netting tangents span EA/l0 against tiny geometric stiffness, which float32 cannot hold.
"""

import jax

jax.config.update("jax_enable_x64", True)

from jaxnet.checks import validate  # noqa: E402
from jaxnet.scene import Bars, Environment, Netting, Nodes, Scene, SceneError  # noqa: E402
from jaxnet.solve.options import Newton  # noqa: E402
from jaxnet.solve.results import Equilibrium, SolveError  # noqa: E402
from jaxnet.solve.statics import solve  # noqa: E402

__all__ = [
    "Bars", "Environment", "Netting", "Nodes", "Scene", "SceneError", "validate",
    "Equilibrium", "Newton", "SolveError", "solve",
]
