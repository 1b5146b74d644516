"""Textbook scenes: nets whose answer is known in closed form (the tests and the validation report use them).

Each function builds a small net and states the exact answer beside it, derived in its docstring:

- :func:`biaxial_panel`: a panel stretched uniformly, every border held (twine tension EA·strain everywhere;
  the edge forces follow from counting the twines that cross each edge);
- :func:`panel_in_current`: a panel held in a uniform current at an angle (Morison drag per twine: every
  twine of the panel sees the same flow, so the total is the count of twines times one twine's drag);
- :func:`pressurised_tube`: a closed diamond-mesh tube loaded by the catch pressure, whose twines settle at
  arctan √2 to its axis;
- :func:`hexagonal_hanging_panel`: a hexagonal-mesh panel hanging under its weight and a pull (the fixings
  carry the pull plus the immersed weight of the twines).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.net import HexTwine, Net, Rope, Twine
from jaxnet.scene import Environment

#: the tube's twines settle at this angle to its axis (degrees): tan² β = N_hoop / N_axial = 2
TUBE_ANGLE_DEG = float(np.degrees(np.arctan(np.sqrt(2.0))))


def biaxial_panel(nx: int, ny: int, theta: float, strain: float, step: float, l0: float = 0.02,
                  ea: float = 1000.0):
    """A panel of ``nx`` x ``ny`` meshes stretched uniformly, all borders held, weightless.

    The twines have length l0 (1 + strain) at the half angle ``theta`` (rad) from the vertical (mesh
    coordinates u across = x, v up = z). The nodes are drawn at that uniform state, which is the equilibrium:
    every twine carries T = EA strain, and 2 twines per mesh row cross a vertical line, so the right edge
    carries 2 ny T sin θ along x and the top edge 2 nx T cos θ along z.

    Returns (scene, across, up): across and up are one mesh's width and height (m).
    """
    length = l0 * (1 + strain)
    across, up = 2 * length * np.sin(theta), 2 * length * np.cos(theta)  # one mesh is (U - V, U + V)
    corners = [(0, 0, 0, 0, 0), (nx * across, 0, 0, nx, -nx), (nx * across, 0, ny * up, nx + ny, ny - nx),
               (0, 0, ny * up, ny, ny)]
    net = Net(environment=Environment(gravity=0.0))
    panel = net.panel("panel", corners, Twine(l0=l0, ea=ea, diameter=1e-3), step)
    for k in range(4):
        net.fix(panel.side(k))
    return net.build(), across, up


def panel_in_current(meshes: int, step: float, angle: float, speed: float = 1.0, l0: float = 0.029,
                     diameter: float = 2.8e-3, cd_normal: float = 1.2, tangential_ratio: float = 0.0,
                     water_density: float = 1025.0):
    """A square panel of open square meshes, ``meshes`` diagonals a side, every node held, in a uniform current.

    The panel lies in the plane spanned by z and (cos angle, sin angle, 0); the current runs along x, so
    ``angle`` = 0 puts the panel in the flow's direction and π/2 normal to it (rad). Morison drag per twine
    (4.114-4.117): a twine of unstretched length l0 at the angle ψ to the current takes
    ½ ρ Cd_n d l0 U² sin² ψ normally (plus f times that with cos² ψ tangentially). With the panel normal to
    the flow every twine is normal to it: the drag is (number of twines) ½ ρ Cd_n d l0 U². The panel is
    ``meshes`` mesh diagonals across and high; its diamonds interleave, so it holds 2 meshes² meshes of
    2 twines each. Returns (scene, exact drag along x in N with the panel normal to the flow).
    """
    width = meshes * l0 * np.sqrt(2.0)
    direction = np.array([np.cos(angle), np.sin(angle), 0.0])
    up = np.array([0.0, 0.0, 1.0])
    corners = [(*(a * direction + b * up), u, v) for a, b, u, v in
               [(0.0, 0.0, 0, 0), (width, 0.0, meshes, -meshes), (width, width, 2 * meshes, 0), (0.0, width, meshes, meshes)]]
    env = Environment(gravity=0.0, water_density=water_density, current_speed=speed,
                      current_direction=np.array([1.0, 0.0, 0.0]))
    net = Net(environment=env)
    twine = Twine(l0=l0, ea=1000.0, diameter=diameter, cd_normal=cd_normal, tangential_ratio=tangential_ratio)
    net.fix(net.panel("panel", corners, twine, step))
    normal_drag = 4 * meshes**2 * 0.5 * water_density * cd_normal * diameter * l0 * speed**2
    return net.build(), normal_drag


def pressurised_tube(start_angle: float, step: float | None = None, around: int = 16, along: int = 32,
                     l0: float = 0.05, ea: float = 1000.0, speed: float = 1.0, catch_cd: float = 1.4,
                     cod_line: float = 1e-3, water_density: float = 1025.0):
    """A closed diamond-mesh tube under the catch pressure p = ½ ρ Cd v²; its twines settle at arctan √2.

    Why arctan √2: in uniform diamond netting whose two twine families make the angle β with the axis and
    carry the same tension T, N_axial = T cos β / (l sin β) and N_hoop = T sin β / (l cos β) (membrane
    forces: the twines crossing a cut across and along the axis), so N_axial / N_hoop = cot² β. A long tube
    closed at both ends has N_hoop = p R and N_axial = p R / 2, hence tan² β = 2, whatever the strain.

    A quarter model (symmetry planes y = 0 and z = 0) of a tube of ``around`` meshes around and ``along``
    meshes along, axis x. The front ring is held; the rear is gathered onto the axis by a ``cod_line`` (m)
    rope, which closes it. The catch is larger than the net can hold, so its front sits at the ring and the
    whole net is loaded. Weightless (neutral) netting, no drag. Every node is laid at the start on the
    cylinder whose meshes make ``start_angle`` (rad) with the axis, the last 3 meshes closing onto the rope.
    ``step`` (m) is the meshing step (default l0: triangles of about one twine).
    """
    n, m = around // 4, along
    radius = around * l0 * np.sin(start_angle) / np.pi  # M meshes of width 2 l0 sin(angle) around
    length = along * 2 * l0 * np.cos(start_angle)
    net = Net(Environment(current_speed=speed, current_direction=np.array([1.0, 0.0, 0.0]),
                          water_density=water_density))
    twine = Twine(l0=l0, ea=ea, diameter=2e-3, density=water_density, cd_normal=0.0)
    # mesh coordinates: u around (from the plane y = 0 to the plane z = 0), v along; U = u + v, V = v - u
    panel = net.panel("tube", [(0, 0, radius, 0, 0), (0, radius, 0, n, -n), (length, radius, 0, n + m, m - n),
                               (length, 0, radius, m, m)], twine, step=l0 if step is None else step)
    net.fix(panel.side(0))  # the front ring
    net.fix(panel.side(3), axes="y")  # on the symmetry plane y = 0
    net.fix(panel.side(1), axes="z")  # on the symmetry plane z = 0
    net.cable("cod line", along=panel.side(2), length=cod_line,
              rope=Rope(ea=5e4, diameter=0.01, density=water_density, cd_normal=0.0))
    net.catch(100.0, drag_coefficient=catch_cd, symmetry=4.0, center=(0.0, 0.0, 0.0))  # far more than it holds
    scene = net.build()
    # the builder draws the corners' straight chords: lay every node on the cylinder (fixed ones included,
    # so that the ring is round)
    tri, uv = np.asarray(scene.netting.vertices), np.asarray(scene.netting.uv)
    node_uv = np.zeros((scene.n_nodes, 2))
    node_uv[tri.ravel()] = uv.reshape(-1, 2)
    u, v = (node_uv[:, 0] - node_uv[:, 1]) / 2, (node_uv[:, 0] + node_uv[:, 1]) / 2
    phi = u / n * np.pi / 2
    closing = np.clip((v - (m - 3)) / 3, 0.0, 1.0)
    r = np.maximum(radius * np.sqrt(1.0 - closing**2), cod_line * 2 / np.pi)
    x = np.stack([v * 2 * l0 * np.cos(start_angle), r * np.sin(phi), r * np.cos(phi)], axis=1)
    return dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, position=x))


def tube_twine_angles(scene, x):
    """Per triangle of a tube: centroid abscissa (m) and the angles (degrees) of its U and V twines to x."""
    import jax

    from jaxnet import geometry

    netting = scene.netting
    xe = np.asarray(x)[np.asarray(netting.vertices)]
    U, V, _ = jax.vmap(geometry.twine_vectors)(xe, np.asarray(netting.uv))

    def angle(w):
        w = np.asarray(w)
        return np.degrees(np.arccos(np.abs(w[:, 0]) / np.linalg.norm(w, axis=1)))

    return xe[:, :, 0].mean(axis=1), angle(U), angle(V)


def tube_middle_third(scene, x):
    """The triangles of the tube's middle third along its axis, away from the ring and the closure, whose
    end effects decay over ~0.3 R (boolean mask over triangles)."""
    centroid, _, _ = tube_twine_angles(scene, x)
    length = np.asarray(x)[:, 0].max() - np.asarray(x)[:, 0].min()
    return (centroid > length / 3) & (centroid < 2 * length / 3)


def hexagonal_hanging_panel(meshes: int = 8, a: float = 0.02, pull: float = 5.0, step: float = 0.1):
    """A hexagonal-mesh panel (twines a, a, 1.2 a; EA 1000 N; polyamide 1 mm) hanging from its top side,
    ``pull`` (N, in total) hanging from its bottom side. The fixings carry pull + the immersed weight of the
    twines: |d| twines of each family per triangle (text after 4.82). Returns (scene, exact reaction (3,) N).
    """
    net = Net()
    w = meshes * 3 * a  # a base mesh is 3 twine lengths along U
    corners = [(0, 0, -w, 0, 0), (w, 0, -w, meshes, 0), (w, 0, 0, meshes, meshes), (0, 0, 0, 0, meshes)]
    lengths = (a, a, 1.2 * a)
    panel = net.panel("hex", corners, HexTwine(l0=lengths, ea=1000.0, diameter=1e-3), step=step)
    net.fix(panel.side(2))
    net.attach(panel.side(0), force=(0.0, 0.0, -pull))
    scene = net.build()
    uv = np.asarray(scene.hexagonal.uv)
    d = (uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1]) - (uv[:, 2, 0] - uv[:, 0, 0]) * (uv[:, 1, 1] - uv[:, 0, 1])
    hexagonal, env = scene.hexagonal, scene.environment
    weight = np.sum(np.abs(d) * np.pi * np.asarray(hexagonal.diameter) ** 2 / 4 * sum(lengths)
                    * (np.asarray(hexagonal.density) - env.water_density) * env.gravity)
    return scene, np.array([0.0, 0.0, pull + weight])
