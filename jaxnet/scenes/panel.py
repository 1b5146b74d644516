"""Built-in scene: a square diamond-mesh panel hanging from a top rope, with a sinker bar along its bottom.

The panel is ``meshes`` meshes across and high (mesh coordinates u across, v up; twine coordinates
U = u + v, V = v - u, book eqs 4.12-4.13), drawn with square meshes (half opening angle 45°), in the
vertical x-z plane. The headline is sewn along the top border and held at both ends; the sinker bar (a
heavy rope) is sewn along the bottom border. Polyamide netting in sea water, no current.

The default twine has a compression stiffness equal to its traction stiffness. Real twines go slack
(EA_c = 0, FEMNET's usual setting), but jaxnet's Newton does not yet converge robustly from a flat start on
nets with slack regions (open work, see the notes of issue 2); pass ``twine=`` to choose.
"""

from __future__ import annotations

import numpy as np

from jaxnet.net import Net, Rope, Twine


def hanging_panel(meshes: int = 40, l0: float = 0.025, step: float = 0.1, twine: Twine | None = None,
                  sinker_kg_per_m: float = 1.0) -> Net:
    """The default scene (see module docstring). l0: mesh side (m); step: meshing step (m);
    sinker_kg_per_m: mass of the sinker bar per metre (kg/m, lead)."""
    twine = twine or Twine(l0=l0, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=2000.0)
    width = meshes * l0 * np.sqrt(2.0)  # a square mesh of side l0 is l0*sqrt(2) across
    n = meshes
    corners = [  # x, y, z, U, V  (u, v) = (0, 0), (n, 0), (n, n), (0, n)
        (0.0, 0.0, -width, 0.0, 0.0),
        (width, 0.0, -width, n, -n),
        (width, 0.0, 0.0, 2 * n, 0.0),
        (0.0, 0.0, 0.0, n, n),
    ]
    net = Net()
    panel = net.panel("netting", corners, twine, step)
    net.cable("headline", along=panel.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    # lead rope: diameter from the mass per metre (kg/m = density * pi D²/4)
    lead = 11340.0
    diameter = float(np.sqrt(4.0 * sinker_kg_per_m / (np.pi * lead)))
    net.cable("sinker bar", along=panel.side(0), rope=Rope(ea=1e5, diameter=diameter, density=lead))
    net.fix(panel.corner(2))
    net.fix(panel.corner(3))
    return net
