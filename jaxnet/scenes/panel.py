"""Built-in scenes: square diamond-mesh panels under weight, from a flat, stress-free start.

:func:`hanging_panel` (``jaxnet run --scene hanging``): a panel hanging from a headline, with a sinker
bar along its bottom. :func:`framed_panel`: a horizontal panel held along its four sides, sagging under its
own weight and a sinker at its centre (the benchmark and Newton-test scene: its start has no out-of-plane
stiffness at all, and with slack twines its equilibrium is still well posed).

Hanging panel.

The panel is ``meshes`` meshes across and high (mesh coordinates u across, v up; twine coordinates
U = u + v, V = v - u, book eqs 4.12-4.13), drawn with square meshes (half opening angle 45°), in the
vertical x-z plane. The headline is sewn along the top border and held at both ends; the sinker bar (a
heavy rope) is sewn along the bottom border. Polyamide netting in sea water, no current.

The sinker bar resists compression (EA_c = EA) and bends like the lead rod it is (EI of its diameter by
:func:`jaxnet.materials.rod_bending_stiffness`, unless ``sinker_bending_stiffness`` says otherwise): a chain
of hinged struts pushed together buckles (folds), and the netting, whose twines go slack and gather, pushes
the bar's ends together. The twine is polyamide netting that goes slack (EA_c = 0, FEMNET's usual setting;
pass ``twine=`` to choose): the free sides of the curtain gather, their meshes close and large regions of
netting carry no tension. That equilibrium is degenerate (the energy is flat over every arrangement of the
slack netting); the primal-dual static method (:mod:`jaxnet.solve.interior`) treats each twine's tension and
slack as unknowns and converges on it in a few tens of iterations, where the damped method, which meets the
slack kink twine by twine, converges only linearly (``docs/solvers.md``).
"""

from __future__ import annotations

import numpy as np

from jaxnet.case import Case, from_net
from jaxnet.materials import rod_bending_stiffness
from jaxnet.net import Net, Rope, Twine


def hanging_panel(meshes: int = 40, l0: float = 0.025, step: float = 0.1, twine: Twine | None = None,
                  sinker_kg_per_m: float = 1.0, sinker_bending_stiffness: float | None = None) -> Case:
    """The hanging panel (see module docstring), as a :class:`~jaxnet.case.Case` (its ``net`` the
    description). l0: mesh side (m); step: meshing step (m); sinker_kg_per_m: mass of the sinker bar per metre
    (kg/m, lead); sinker_bending_stiffness: its flexural stiffness EI (N·m²), by default a lead rod's
    (:func:`jaxnet.materials.rod_bending_stiffness` of its diameter); 0 makes it a chain of hinges, which
    buckles if the netting pushes its ends together (:mod:`jaxnet.solve.diagnosis`). twine: by default
    polyamide (EA = 2000 N, EA_c = 0, diameter 1.5 mm)."""
    twine = twine or Twine(l0=l0, ea=2000.0, diameter=1.5e-3, density=1140.0)
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
    if sinker_bending_stiffness is None:
        sinker_bending_stiffness = rod_bending_stiffness(diameter)
    net.cable("sinker bar", along=panel.side(0), rope=Rope(ea=1e5, diameter=diameter, density=lead, ea_compression=1e5,
                                                           bending_stiffness=sinker_bending_stiffness))
    net.fix(panel.corner(2))
    net.fix(panel.corner(3))
    return from_net(net, label=f"square panel of {meshes} x {meshes} meshes hanging from a headline with a sinker "
                               "bar, still water")


def framed_panel(meshes: int = 40, l0: float = 0.025, step: float = 0.1, twine: Twine | None = None,
                 sinker_kg: float = 5.0) -> Case:
    """A horizontal square panel held along its four sides, sagging under its weight and a central sinker.

    ``meshes`` meshes a side, square meshes (half opening angle 45°) in the plane z = 0, all border nodes
    fixed; the twine (default: polyamide, EA = 2000 N, EA_c = 0) is stress-free at the start, which is
    flat: the tangent there has no out-of-plane stiffness at all. ``sinker_kg``: lead sinker (kg) at the
    node nearest the centre. l0: mesh side (m); step: meshing step (m). A :class:`~jaxnet.case.Case`.
    """
    twine = twine or Twine(l0=l0, ea=2000.0, diameter=1.5e-3, density=1140.0)
    width = meshes * l0 * np.sqrt(2.0)
    n = meshes
    corners = [(0.0, 0.0, 0.0, 0.0, 0.0), (width, 0.0, 0.0, n, -n), (width, width, 0.0, 2 * n, 0.0), (0.0, width, 0.0, n, n)]
    net = Net()
    panel = net.panel("netting", corners, twine, step)
    for k in range(4):
        net.fix(panel.side(k))
    if sinker_kg:
        net.sinker(panel.nearest(0.5 * width, 0.5 * width, 0.0), sinker_kg)
    return from_net(net, label=f"horizontal panel of {meshes} x {meshes} meshes held along its border, sagging under "
                               f"a {sinker_kg:g} kg sinker")
