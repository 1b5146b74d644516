"""The built-in hanging panel with a smooth equilibrium, for the tests of solver machinery.

:func:`jaxnet.scenes.panel.hanging_panel` is built with slack twines (EA_c = 0) and a lead sinker bar that
bends: its equilibrium is degenerate (gathered, slack netting), which the primal-dual method solves in a few
tens of iterations but the damped Newton iteration, the one traced programs run (``newton.newton_loop``, the
design batches, the implicit equilibrium), reaches only linearly. Tests of that machinery (a jitted loop against
the host loop, gradients against differences of re-solved equilibria at 1e-10 N, sweeps) use the panel this
module's keywords make: twines that resist compression as they resist traction and a hinged sinker bar, whose
equilibrium is smooth and reached quadratically.
"""

from jaxnet.net import Twine

#: keyword arguments of ``hanging_panel`` (at its default mesh side l0 = 0.025 m) for the smooth panel
SMOOTH = {"twine": Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=2000.0),
          "sinker_bending_stiffness": 0.0}
