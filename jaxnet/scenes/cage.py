"""Built-in scene (the default of ``jaxnet run``): a cylindrical fish-farm cage in a uniform current.

The net: a vertical cylinder of ``sides`` flat wall panels (each ``meshes_around`` meshes across and
``meshes_deep`` deep, square meshes at the start) sewn side to side, closed by a flat bottom of ``sides``
triangular panels meeting at the centre. Its top border hangs from the floating collar, an HDPE pipe
(a ring cable at the surface, half immersed at rest): the collar floats on the free surface (its
buoyancy and waterplane stiffness come from the free-surface term) and is moored horizontally at every
node (a real collar is a stiff ring held by a mooring grid: without bending stiffness in the bars, a
moored ring of pin-jointed bars would fold, so its horizontal position is held). A sinker hangs at the
foot of every seam of the wall. The current flows along x.

The result reports the drag on the netting, the cables and the sinkers, and the volume the net keeps
below the collar plane (m³).

:func:`cage_in_waves` is the same cage in regular waves, for dynamics (``jaxnet run --scene cage_waves``):
the netting feels the waves' orbital velocity and acceleration (drag on the relative velocity, inertia of
the water), and the collar heaves with the waves. The collar is taken as a rigid ring moored in place that
follows the surface's heave at the cage's centre (a prescribed motion): a ring of pin-jointed bars has
no bending stiffness to float as a body, and the free-surface buoyancy of this version of jaxnet sees the
mean surface, not the waves' (``docs``: left for later).
"""

from __future__ import annotations

import inspect

import equinox as eqx
import numpy as np

from jaxnet.water import forcing, waves
from jaxnet.case import Case, TimeSettings, from_net
from jaxnet.net import Net, PanelRef, Rope, Twine
from jaxnet.scene import Environment
from jaxnet.solve.options import Implicit


def fish_cage(radius: float = 5.0, depth: float = 5.0, sides: int = 8, l0: float = 0.05, step: float = 0.5,
              current: float = 0.5, sinker_kg: float = 20.0, twine: Twine | None = None) -> Case:
    """The cage (see module docstring), as a :class:`~jaxnet.case.Case` (its ``net`` the description).

    radius, depth: of the cylinder at the start (m); sides: number of wall panels (and bottom slices);
    l0: mesh side (m); step: meshing step (m); current: speed along x (m/s); sinker_kg: lead at the foot
    of each wall seam (kg); twine: netting material (default: polyamide 2.5 mm, EA 5000 N, Cd 1.2).
    """
    net = _describe(radius, depth, sides, l0, step, current, sinker_kg, twine)
    return from_net(net, label=f"cylindrical fish cage (floating collar, bottom, sinkers) in a {current:g} m/s current")


def netting_twine(l0: float = 0.05) -> Twine:
    """The cage's netting material by default: polyamide twine 2.5 mm across, EA 5000 N, Cd 1.2, f 0.08, mesh
    side ``l0`` (m), no compression stiffness."""
    return Twine(l0=l0, ea=5000.0, diameter=2.5e-3, density=1140.0, cd_normal=1.2, tangential_ratio=0.08)


def _describe(radius, depth, sides, l0, step, current, sinker_kg, twine) -> Net:
    """The cage's description (:func:`fish_cage`'s arguments)."""
    twine = twine or netting_twine(l0)
    env = Environment(current_speed=current, current_direction=np.array([1.0, 0.0, 0.0]), surface_level=0.0)
    net = Net(environment=env)
    mesh_width = l0 * np.sqrt(2.0)  # a square mesh is l0 * sqrt(2) across and high
    angles = 2 * np.pi * np.arange(sides + 1) / sides
    rim = np.stack([radius * np.cos(angles), radius * np.sin(angles)], axis=1)
    chord = np.linalg.norm(rim[1] - rim[0])
    around = max(1, int(round(chord / mesh_width)))
    deep = max(1, int(round(depth / mesh_width)))
    apothem = radius * np.cos(np.pi / sides)
    rows = max(1, int(round(apothem / mesh_width)))
    walls, bottoms = [], []
    for k in range(sides):
        (xa, ya), (xb, yb) = rim[k], rim[k + 1]
        # mesh coordinates (u across, v down) -> twine coordinates U = u + v, V = v - u
        corners = [(xa, ya, 0.0, 0, 0), (xb, yb, 0.0, around, -around),
                   (xb, yb, -depth, around + deep, deep - around), (xa, ya, -depth, deep, deep)]
        walls.append(net.panel(f"wall {k}", corners, twine, step))
        # bottom slice: outer edge along u (the wall's foot), apex at the centre `rows` meshes inward
        u_apex, v_apex = 0.5 * around, rows
        corners = [(xa, ya, -depth, 0, 0), (0.0, 0.0, -depth, u_apex + v_apex, v_apex - u_apex),
                   (xb, yb, -depth, around, -around)]
        bottoms.append(net.panel(f"bottom {k}", corners, twine, step))
    for k in range(sides):
        nxt = (k + 1) % sides
        net.seam(walls[k].side(1), walls[nxt].side(3))      # wall to wall
        net.seam(walls[k].side(2), bottoms[k].side(2))      # wall foot to its bottom slice (rim to rim)
        net.seam(bottoms[k].side(1), bottoms[nxt].side(0))  # slice to slice (centre to rim)
    # HDPE collar pipe, 250 mm across, 15 mm wall: 10.5 kg/m, i.e. 214 kg/m³ over its outer section
    pipe = Rope(ea=2e6, diameter=0.25, density=214.0, ea_compression=2e6)
    for k in range(sides):
        net.cable(f"collar {k}", along=walls[k].side(0), rope=pipe)
    for k in range(sides):
        net.fix(walls[k].side(0), axes="xy")  # moored collar: see the module docstring
        net.sinker(walls[k].corner(3), sinker_kg)
    net.enclose(center=(0.0, 0.0, 0.0), axis=(0.0, 0.0, -1.0))  # the volume held below the collar
    return net


def cage_in_waves(wave_height: float = 2.0, wave_period: float = 6.0, water_depth: float = 50.0,
                  current: float = 0.2, ramp: float | None = None, end_time: float = 12.0, time_step: float = 0.01,
                  record_every: float = 0.1, **cage) -> Case:
    """The cage of :func:`fish_cage` (its keyword arguments ``cage``) in regular waves along x, for dynamics.

    wave_height H (m, crest to trough), wave_period T (s), water_depth (m): linear (Airy) waves
    (:class:`jaxnet.water.waves.Airy`); current (m/s) along x; ramp: time (s) over which the waves and the collar's
    heave grow together from still water to their full height (:attr:`jaxnet.water.forcing.Loading.ramp`; None:
    one wave period), so that the run starts from the static equilibrium without a shock. A
    :class:`~jaxnet.case.Case` whose time settings run it to ``end_time`` (s) with steps of ``time_step`` (s), a
    record every ``record_every`` (s), the collar's heave its :class:`~jaxnet.water.forcing.Loading`.
    """
    options = {k: v.default for k, v in inspect.signature(fish_cage).parameters.items() if k != "current"}
    unknown = set(cage) - set(options)
    if unknown:
        raise TypeError(f"cage_in_waves: unknown cage arguments {sorted(unknown)} (those of fish_cage: {sorted(options)})")
    options = {**options, **cage}
    net = _describe(current=current, **options)
    env = net.environment
    net.environment = eqx.tree_at(lambda e: e.waves, env, waves.Airy(wave_height, wave_period, direction=(1.0, 0.0, 0.0),
                                                                     depth=water_depth, surface_level=env.surface_level),
                                  is_leaf=lambda v: v is None)
    for k in range(options["sides"]):
        net.fix(PanelRef(f"wall {k}").side(0), axes="z")  # the collar follows the heave: held, then moved
    scene = net.build()
    collar = np.flatnonzero(np.asarray(scene.nodes.fixed).all(axis=1))
    # the heave of the surface at the centre: η = H/2 cos(-ωt) = H/2 sin(ωt + π/2)
    heave = forcing.Harmonic(amplitude=(0.0, 0.0, 0.5 * wave_height), period=wave_period, phase=np.pi / 2)
    loading = forcing.Loading(motions=(forcing.PrescribedMotion(collar, heave),), ramp=ramp)
    time = TimeSettings(end_time=end_time, record_every=record_every, solver=Implicit(time_step=time_step),
                        loading=loading)
    return Case(scene=scene, time=time, net=net,
                label=f"the cage in {wave_height:g} m, {wave_period:g} s regular waves and a {current:g} m/s current, its "
                      f"collar heaving; {end_time:g} s")


def cage_in_waves_coarse(wave_height: float = 2.0, wave_period: float = 6.0, water_depth: float = 50.0,
                         current: float = 0.2, end_time: float = 12.0, time_step: float = 0.01, record_every: float = 0.1,
                         radius: float = 5.0, depth: float = 5.0, step: float = 1.6) -> Case:
    """:func:`cage_in_waves` meshed coarsely by default (339 unknowns: the size of FEMNET's dynamic cage benchmark,
    351 unknowns), the built-in ``cage_waves`` of ``jaxnet run --dynamic``; its keyword arguments are the numbers
    ``--set`` may change."""
    return cage_in_waves(wave_height=wave_height, wave_period=wave_period, water_depth=water_depth, current=current,
                         end_time=end_time, time_step=time_step, record_every=record_every, radius=radius, depth=depth,
                         step=step)
