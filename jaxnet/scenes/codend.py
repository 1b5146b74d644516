"""Built-in scene: a trawl cod-end holding a catch, in the current (``jaxnet run --scene codend``).

A quarter model, as FEMNET's case ``c2``: the cod-end is a tube of ``meshes_around`` meshes around and
``meshes_along`` meshes along its axis (x, downstream), cut by the two symmetry planes y = 0 and z = 0.
The modelled quarter is one panel, drawn (like FEMNET's) as a narrow strip of nearly closed meshes; its
border on the plane y = 0 is held in y, the one on z = 0 in z, the front (the join to the trawl) is fixed,
and the rear is closed by the cod line, a short rope sewn along the rear border that gathers it onto the
axis. The catch fills the rear of the cod-end with ``catch_m3`` cubic metres; its pressure ½ρCd v² acts
on the netting behind the catch front.
"""

from __future__ import annotations

import numpy as np

from jaxnet.case import Case, from_net
from jaxnet.net import Net, Rope, Twine
from jaxnet.scene import Environment


def codend(meshes_around: int = 100, meshes_along: int = 50, l0: float = 0.06, step: float = 0.12,
           opening: float = 0.1, current: float = 1.5, catch_m3: float = 0.2, catch_cd: float = 1.4,
           twine: Twine | None = None) -> Case:
    """The cod-end (see module docstring), as a :class:`~jaxnet.case.Case` (its ``net`` the description).

    meshes_around (a multiple of 4), meshes_along: mesh counts of the whole cod-end; l0: mesh side (m);
    step: meshing step (m); opening: half opening angle of the meshes at the start (rad, nearly closed);
    current: towing speed (m/s); catch_m3: catch volume of the whole cod-end (m³); catch_cd: its Cd.
    """
    if meshes_around % 4:
        raise ValueError(f"meshes_around must be a multiple of 4 (quarter model), got {meshes_around}")
    # neutrally buoyant netting (as in FEMNET's c2): a quarter model is exact only if the loads share the
    # symmetry of both planes, and weight does not
    twine = twine or Twine(l0=l0, ea=1e5, diameter=4e-3, density=1025.0, knot_size=0.01)
    env = Environment(current_speed=current, current_direction=np.array([1.0, 0.0, 0.0]))
    net = Net(environment=env)
    quarter = meshes_around // 4
    length = meshes_along * 2 * l0 * np.cos(opening)
    radius = meshes_around * 2 * l0 * np.sin(opening) / (2 * np.pi)
    # mesh coordinates: u around (from the plane y = 0 to the plane z = 0), v along; U = u + v, V = v - u
    n, m = quarter, meshes_along
    corners = [(0.0, 0.0, radius, 0, 0), (0.0, radius, 0.0, n, -n), (length, radius, 0.0, n + m, m - n),
               (length, 0.0, radius, m, m)]
    p = net.panel("cod-end", corners, twine, step)
    net.fix(p.side(0))              # the front, sewn to the trawl
    net.symmetry_plane("y", 0.0)    # side 3 lies on it, held along y
    net.symmetry_plane("z", 0.0)    # side 1 lies on it, held along z
    # the cod line gathers the rear border onto the axis: a short rope, as in FEMNET's c2
    net.cable("cod line", along=p.side(2), rope=Rope(ea=5e4, diameter=0.01, density=1025.0), length=0.01)
    net.catch(catch_m3, drag_coefficient=catch_cd, symmetry=4.0, center=(0.0, 0.0, 0.0))
    return from_net(net, label=f"trawl cod-end (quarter model) holding {catch_m3:g} m³ of catch at {current:g} m/s")
