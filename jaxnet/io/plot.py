"""Pictures of a net (matplotlib), as a gear designer reads them (docs/pictures.md).

The netting is drawn as its twines: through every triangle, one line along its U twines and one along its V
twines, each coloured by its own family's tension (N) and the thicker the larger the tension, on the netting's
surface drawn grey. The two families of one triangle carry different tensions, and neighbouring triangles
differ by orders of magnitude where twines go slack (in the default cage a third of the triangles carry less
than 0.1 N in both families, and neighbours differ by a median factor of about 100): one colour per triangle,
the mean of its two families, drew a checkerboard under a colour bar whose top was half the largest twine
tension. Drawn apart, every line has the colour of a tension some twine carries, the colour bar's top is the
largest twine tension (result.json's ``max_twine_tension_N``), and the lines show the way the load runs. The
twine scale is logarithmic (:func:`twine_scale`): tensions span orders of magnitude, and on a linear scale
everything but the few most loaded triangles took the bottom colour. Cables are coloured by their bar tension on
a linear scale of their own (ropes carry orders of magnitude more than twines).

What holds the net is marked (:func:`marks`): nodes fixed in x, y and z (hollow red circles), nodes held along
some axes only (hollow diamonds, one legend entry per set of axes: "held in x, y only" for a collar moored
horizontally), floats (their net buoyancy, N) and sinkers and other lumped masses (their mass, kg), their values
in the legend and, where a net has at most :data:`LABELLED` of a kind that differ, beside the marks. A model
with symmetry planes (a cod-end's quarter) is drawn mirrored to the whole net, the tensions repeated in every
copy; its nodes held only across a plane they lie on are what makes the model symmetric, not fixings, and are
not marked (:func:`held_axes`).

:func:`save_png` writes one figure of an equilibrium (:func:`net_figure`): a 3D view, the view along the
current and the side view (the plane of the current and the vertical), all at equal scale (a cod-end's opening
is read off its length), with the current's arrow and speed and the catch's front across the net, the netting
behind it (that carries the catch's pressure) hatched. Where cables or bridles reach far beyond the netting (it
fills less than :data:`ZOOM_BELOW` of the whole's area: a mooring, a trawl's warps), the three views show the
netting and a fourth, small view the whole, the zoomed region boxed. :func:`plot_net` draws the net on a 3D
axis of one's own (notebooks). :func:`save_run_png` writes the picture of a run in time (:func:`run_figure`).

Cost: the figure's views are 2D projections on plain axes in a fixed layout, the 3D view an oblique projection
with a scale bar and the coordinate axes' directions, and each view's netting is one artist drawn by one call
of the renderer (:class:`NettingArtist`). mplot3d's axes (their three axes of tick labels), the constrained
layout's measuring of every text, a second drawing for a tight bounding box and a collection's path per
triangle took most of the time of a picture, more than a small net's solve.

Directions: ``along`` is the current's direction (x without a current) made square to ``up``; ``across`` =
``up`` × ``along``, so that the view along the current is seen from downstream with ``across`` to the right
(for a current along x and up along z: the side view is the x–z plane, the view along the current the y–z
plane). A current along no coordinate axis gives axes named "along the current" and "across the current", its
heading given in the side view's title in degrees from one horizontal coordinate axis toward the other
(:func:`heading`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from matplotlib.artist import Artist

from jaxnet import scene as scene_lib

#: matplotlib colour map of the twines' tension: pale for slack twines, dark for the most loaded, on the grey
#: netting surface
TWINE_COLOURS = "magma_r"
#: matplotlib colour map of the bar (cable) tension, a second scale: ropes carry orders of magnitude more
BAR_COLOURS = "winter"
#: labels of the colour bars (their unit is the newton)
TWINE_LABEL = "twine tension (N)"
BAR_LABEL = "bar tension (N)"
#: decades of the twine colour scale at most, below the largest twine tension
TWINE_DECADES = 3
#: the twine colour scale's bottom: this percentile of the tensions of the twines within its decades
TWINE_FLOOR_PERCENTILE = 5.0
#: a kind of mark (floats, sinkers) has its values written beside the marks where a net has at most this many
LABELLED = 12
#: the netting gets views of its own where it fills less than this fraction of the whole's area in the side view
#: and in the view along the current (cables, bridles, a mooring beyond it)
ZOOM_BELOW = 0.1
#: names (``get_gid``) of the artists the pictures draw, by which they can be found on an axis
NETTING, HEXAGONAL, CABLES, FIXED, HELD, FLOATS, SINKERS, CURRENT, FRONT, BEHIND, ZOOMED = (
    "netting", "hexagonal netting", "cables", "fixed nodes", "held nodes", "floats", "sinkers", "current",
    "catch front", "behind the catch front", "zoomed region")
#: labels (``get_label``) of the views of :func:`net_figure`
VIEW_3D, VIEW_ALONG, VIEW_SIDE, VIEW_WHOLE = "3D view", "view along the current", "side view", "whole"

_DPI = 100
_SURFACE = 0.80                        # grey level of the netting surface facing away (brighter facing the viewer)
_EDGE = (0.0, 0.0, 0.0, 0.15)          # edges of the hexagonal triangles
_BEHIND_EDGE = (0.0, 0.0, 0.0, 0.4)    # hatching of the triangles behind the catch front
_FRONT_COLOUR = "magenta"
_HELD_COLOURS = ("darkorange", "purple", "teal", "olive", "brown", "navy")


# -- what is drawn -----------------------------------------------------------------------------------------------

def held_axes(scene) -> np.ndarray:
    """(N, 3) bool: the axes along which each node is drawn as held: those it is fixed along, less the normal of
    a symmetry plane it lies on (:func:`jaxnet.scene.on_symmetry_planes`, the test of :meth:`jaxnet.net.Net.
    symmetry_plane`): a node held only across its plane is free in the whole net, the hold is what makes the
    modelled part symmetric. A node on a plane fixed along every axis, and along some other than the plane's
    normal, is drawn fixed along every axis: the scene does not say whether a fixing or the plane holds it
    across the plane, and a fixed ring (a cod-end's front) is fixed whole."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool)
    held = fixed & ~scene_lib.on_symmetry_planes(scene.nodes.position, scene.symmetry_planes)
    whole = fixed.all(axis=1) & held.any(axis=1)
    return np.where(whole[:, None], True, held)


def held_nodes(scene) -> np.ndarray:
    """(N,) bool: the nodes drawn as held along some axis (:func:`held_axes`)."""
    return held_axes(scene).any(axis=1)


def floats_and_sinkers(scene):
    """((N,) bool floats, (N,) net buoyancy (N), (N,) bool sinkers, (N,) mass (kg)). A float is a node whose
    attached volume's buoyancy exceeds its mass's weight (its net buoyancy ρ g V - m g > 0: the buoyancy of
    :meth:`jaxnet.net.Net.float`); a sinker, any other node with a lumped mass (lead, a weight, a catch
    bag's mass), drawn by its mass as sinkers are specified."""
    env, nodes = scene.environment, scene.nodes
    mass = np.asarray(nodes.mass, dtype=float)
    lift = float(env.water_density) * float(env.gravity) * np.asarray(nodes.volume, dtype=float) \
        - mass * float(env.gravity)
    floats = lift > 0.0
    return floats, lift, (mass > 0.0) & ~floats, mass


def view_directions(scene):
    """(along, across, up): unit vectors of the pictures. ``along``: the current's direction made square to
    ``up`` (x when the scene has no current, or a current along the vertical: then the coordinate axis least
    along ``up``); ``across`` = ``up`` × ``along``. The side view shows (along, up), the view along the current
    (across, up), seen from downstream."""
    env = scene.environment
    up = np.asarray(env.up, dtype=float)
    up = up / np.linalg.norm(up)
    d = np.asarray(env.current_direction, dtype=float)
    if not (float(env.current_speed) > 0.0 and np.linalg.norm(d) > 0.0):
        d = np.array([1.0, 0.0, 0.0])
    along = d - np.dot(d, up) * up
    if np.linalg.norm(along) < 1e-9 * np.linalg.norm(d):
        d = np.eye(3)[int(np.argmin(np.abs(up)))]
        along = d - np.dot(d, up) * up
    along = along / np.linalg.norm(along)
    return along, np.cross(up, along), up


def oblique_directions(scene, elevation=25.0, azimuth=35.0):
    """(right, vertical, toward): the picture plane's unit vectors of the 3D view and the direction it is seen
    along (into the picture). The viewer stands ``elevation`` degrees above the horizontal, turned ``azimuth``
    degrees from the side view's viewpoint (on the side of -across) toward upstream, so that a net's mouth,
    facing the current, is seen; ``vertical`` is ``up`` as seen."""
    along, across, up = view_directions(scene)
    el, az = np.radians(elevation), np.radians(azimuth)
    out = np.cos(el) * (-np.cos(az) * across - np.sin(az) * along) + np.sin(el) * up   # toward the viewer
    right = np.cross(up, out)
    right = right / np.linalg.norm(right)
    return right, np.cross(out, right), -out


def twine_scale(values):
    """The colour scale of twine tensions (N): logarithmic, its top the largest tension, its bottom the
    :data:`TWINE_FLOOR_PERCENTILE` th percentile of the tensions within :data:`TWINE_DECADES` decades of it,
    but at least one decade below it; tensions below (slack twines too) clipped to the bottom. The percentile
    spends the colours on the tensions the twines carry: the default cage's loaded twines span nearly three
    decades, a cod-end's one (its bottom a thousandth of the largest would leave all of them one dark colour).
    Linear and 1 N wide from 0 where no twine carries a millionth of a newton (a net at rest, whose tensions
    are rounding noise)."""
    from matplotlib.colors import LogNorm, Normalize

    values = np.asarray(values, dtype=float).ravel()
    top = float(values.max()) if values.size else 0.0
    if top > 1e-6:
        deepest = top * 10.0 ** -TWINE_DECADES
        floor = float(np.percentile(values[values > deepest], TWINE_FLOOR_PERCENTILE))
        return LogNorm(vmin=min(max(floor, deepest), top / 10.0), vmax=top, clip=True)
    return Normalize(vmin=0.0, vmax=1.0, clip=True)


def bar_scale(values):
    """The colour scale of bar tensions (N): Normalize from the smallest to the largest tension (N); a scale 1 N
    wide from the smallest where they are all equal to a millionth of a newton (a net at rest, whose tensions
    are rounding noise), since a colour bar needs a span and a span of 1e-10 N would only colour the noise."""
    from matplotlib.colors import Normalize

    values = np.asarray(values, dtype=float)
    lo, hi = (float(values.min()), float(values.max())) if values.size else (0.0, 0.0)
    return Normalize(vmin=lo, vmax=hi if hi - lo > 1e-6 else lo + 1.0)


def twine_lines(x, vertices, uv, shrink=0.8):
    """(E, 2, 2, 3) m: the lines that draw the U and V twines of each triangle (vertices (E, 3) at positions x
    (N, 3), twine coordinates uv (E, 3, 2)): through the triangle's centroid along its twine vector (the
    position's derivative along that twine coordinate, :func:`jaxnet.geometry.twine_vectors`), centred on it,
    ``shrink`` of the longest such line that stays inside the triangle, so that neighbouring triangles' lines
    do not touch."""
    corners = np.asarray(x, dtype=float)[vertices]                        # (E, 3, 3)
    uv = np.asarray(uv, dtype=float)
    # barycentric coordinates are affine in (u, v): lambda = inv([[u], [v], [1]]) @ (u, v, 1)
    frame = np.stack([uv[..., 0], uv[..., 1], np.ones(uv.shape[:2])], axis=1)   # (E, 3, 3)
    with np.errstate(all="ignore"):
        inverse = np.linalg.inv(frame)
    inverse = np.where(np.isfinite(inverse), inverse, 0.0)
    centroid = corners.mean(axis=1)
    lines = []
    for family in (0, 1):
        gradient = inverse[:, :, family]                                  # (E, 3): d lambda / d u (or v)
        twine = np.einsum("ei,eik->ek", gradient, corners)                # (E, 3): the twine vector (m)
        with np.errstate(divide="ignore"):
            reach = np.min(np.where(gradient != 0.0, 1.0 / (3.0 * np.abs(gradient)), np.inf), axis=1)
        half = shrink * np.where(np.isfinite(reach), reach, 0.0)[:, None] * twine
        lines.append(np.stack([centroid - half, centroid + half], axis=1))
    return np.stack(lines, axis=1)


class Mark(NamedTuple):
    """Nodes marked alike: what holds the net (fixings, holds in some axes, floats, sinkers)."""

    gid: str                    # FIXED, HELD, FLOATS or SINKERS
    label: str                  # the legend's words, values included
    points: np.ndarray          # (K, 3) m, each point once
    texts: tuple                # (K,) the value written beside each mark, or () for none
    style: dict                 # matplotlib scatter keywords


class _Net(NamedTuple):
    """A net ready to draw, the whole of it (every mirrored copy, copy after copy as :func:`jaxnet.scene.
    mirrored` gives them, the model first)."""

    points: np.ndarray          # (copies, N, 3) m
    triangles: np.ndarray       # (copies * E, 3, 3) m, the netting triangles' corners
    twines: np.ndarray          # (copies * E, 2, 2, 3) m, the lines of their U and V twines (:func:`twine_lines`)
    twine: np.ndarray           # (copies * E, 2) U and V twine tensions (N)
    twine_scale: object         # the twine colour scale (:func:`twine_scale`)
    behind: np.ndarray          # (copies * E,) bool: triangles behind the catch front
    hexagonal: np.ndarray       # (copies * H, 3, 3) m
    bars: np.ndarray            # (copies * B, 2, 3) m
    bar: np.ndarray             # (copies * B,) bar tension (N)
    bar_scale: object           # Normalize of the bar tensions
    front: np.ndarray           # (copies * K, 2, 3) m: the segments where the front plane cuts the netting
    marks: tuple                # of Mark
    speed: float                # current speed (m/s), 0 for none
    current: np.ndarray         # (3,) unit current direction
    zoom: object                # (lo, hi) (3,) m: the netting's box where it gets views of its own, else None


def _distinct(points, values=None):
    """The points (K, 3) with those that coincide (to 1e-9 m: a node on a symmetry plane is its own image) kept
    once, and their values (K,) when given."""
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    if len(points) == 0:
        return points, (np.zeros(0) if values is None else np.asarray(values)[:0])
    _, first = np.unique(np.round(points / 1e-9).astype(np.int64), axis=0, return_index=True)
    first = np.sort(first)
    return points[first], (None if values is None else np.asarray(values)[first])


def front_cut(x, vertices, axis, front):
    """(K, 2, 3) m: the segments where the plane {y·axis = front} cuts the triangles ``vertices`` at positions x:
    each triangle with vertices on both sides gives one, between the points where its two crossing edges meet
    the plane."""
    corners = x[vertices]                                   # (E, 3, 3)
    h = corners @ axis - front                              # heights behind the front (m)
    behind = h > 0
    segments = []
    for c, hh, b in zip(corners, h, behind):
        if b.all() or not b.any():
            continue
        cut = [c[i] + (c[j] - c[i]) * hh[i] / (hh[i] - hh[j])
               for i, j in ((0, 1), (1, 2), (2, 0)) if b[i] != b[j]]
        segments.append(cut)
    return np.asarray(segments, dtype=float).reshape(-1, 2, 3)


def _amounts(values, unit, kind, kinds):
    """Legend words of ``values`` (K,) of a kind of mark: "8 sinkers, 20 kg each", "3 floats, 5–20 N"."""
    n = len(values)
    lo, hi = float(np.min(values)), float(np.max(values))
    name = kind if n == 1 else kinds
    if hi - lo <= 1e-9 * max(abs(hi), 1e-300):
        return f"{n} {name}, {hi:.3g} {unit}" + (" each" if n > 1 else "")
    return f"{n} {name}, {lo:.3g}–{hi:.3g} {unit}"


def marks(scene, points):
    """The :class:`Mark` of what holds the net (fixed nodes, then nodes held in some axes, floats, sinkers), at
    the mirrored positions ``points`` (copies, N, 3) m, each point once."""
    found = []
    held = held_axes(scene)
    full = held.all(axis=1)
    at, _ = _distinct(points[:, full])
    if len(at):
        found.append(Mark(FIXED, "fixed (held in x, y, z)", at, (),
                           dict(s=6, facecolors="none", edgecolors="red", linewidths=0.6)))
    partial = held.any(axis=1) & ~full
    sets = sorted({tuple(row) for row in held[partial]}, key=lambda row: (-sum(row), row[::-1]))
    for k, axes in enumerate(sets):
        rows = partial & (held == np.asarray(axes)).all(axis=1)
        at, _ = _distinct(points[:, rows])
        names = ", ".join(a for a, h in zip("xyz", axes) if h)
        found.append(Mark(HELD, f"held in {names} only", at, (),
                           dict(s=8, marker="D", facecolors="none", edgecolors=_HELD_COLOURS[k % len(_HELD_COLOURS)],
                                linewidths=0.6)))
    floats, lift, sinkers, mass = floats_and_sinkers(scene)
    copies = points.shape[0]
    for gid, rows, values, unit, kind, style in (
            (FLOATS, floats, lift, "N", "float", dict(s=28, marker="^", facecolors="gold", edgecolors="k",
                                                      linewidths=0.6)),
            (SINKERS, sinkers, mass, "kg", "sinker", dict(s=28, marker="v", facecolors="0.25", edgecolors="k",
                                                          linewidths=0.6))):
        if not rows.any():
            continue
        at, value = _distinct(points[:, rows], np.tile(values[rows], copies))
        alike = np.ptp(value) <= 1e-9 * np.abs(value).max()      # then the legend says the value
        texts = tuple(f"{v:.3g} {unit}" for v in value) if len(at) <= LABELLED and not alike else ()
        what = "net buoyancy" if gid == FLOATS else "mass"
        found.append(Mark(gid, f"{_amounts(value, unit, kind, kind + 's')} ({what})", at, texts, style))
    return tuple(found)


def _zoom(scene, points, netting_points):
    """The netting's box (lo, hi) (3,) m where the rectangle around it fills less than :data:`ZOOM_BELOW` of the
    whole's in the side view and in the view along the current (positions (K, 3) m, the whole's and the
    netting's), else None. By areas, not lengths: a trawl's wings make its netting long and thin, a third of
    the length of its warps and a thirtieth of the picture."""
    if len(netting_points) == 0:
        return None
    along, across, up = view_directions(scene)
    fractions = []
    for plane in (np.stack([along, up]), np.stack([across, up])):
        net, whole = np.ptp(netting_points @ plane.T, axis=0), np.ptp(points @ plane.T, axis=0)
        fractions.append(float(np.prod(net)) / max(float(np.prod(whole)), 1e-300))
    if max(fractions) >= ZOOM_BELOW:
        return None
    return netting_points.min(axis=0), netting_points.max(axis=0)


def _prepare(scene, x, twine_tension=None, bar_tension=None, catch_front=None):
    """The :class:`_Net` of ``scene`` at positions x (N, 3): tensions from :mod:`jaxnet.figures` when not given."""
    from jaxnet import figures

    x = np.asarray(x, dtype=float)
    points = scene_lib.mirrored(scene, x)
    copies = points.shape[0]

    def whole(rows):   # (copies * E, k, 3) corners of the elements ``rows`` (E, k) in every copy
        return points[:, rows].reshape(-1, rows.shape[1], 3) if rows.size else np.zeros((0, rows.shape[1], 3))

    net, bars, env = scene.netting, scene.bars, scene.environment
    vertices = np.zeros((0, 3), dtype=np.int64) if net is None else np.asarray(net.vertices)
    ends = np.zeros((0, 2), dtype=np.int64) if bars is None else np.asarray(bars.ends)
    hexagonal = np.zeros((0, 3), dtype=np.int64) if scene.hexagonal is None else np.asarray(scene.hexagonal.vertices)
    if twine_tension is None:
        twine_tension = figures.twine_tensions(scene, x)
    if bar_tension is None:
        bar_tension = figures.bar_tensions(scene, x)
    twine = np.asarray(twine_tension, dtype=float).reshape(len(vertices), 2)
    bar = np.asarray(bar_tension, dtype=float).reshape(len(ends))
    lines = np.zeros((0, 2, 2, 3))
    if len(vertices):
        lines = twine_lines(x, vertices, net.uv)
        lines = scene_lib.mirrored(scene, lines.reshape(-1, 3)).reshape(-1, 2, 2, 3)
    behind = np.zeros(len(vertices), dtype=bool)
    front = np.zeros((0, 2, 3))
    if scene.catch is not None and catch_front is not None and len(vertices):
        axis = np.asarray(scene.catch.axis, dtype=float)
        behind = ((x[vertices] @ axis) > float(catch_front)).any(axis=1)
        cut = front_cut(x, vertices, axis, float(catch_front))
        front = scene_lib.mirrored(scene, cut.reshape(-1, 3)).reshape(-1, 2, 3)
    in_netting = np.unique(np.concatenate([vertices.ravel(), hexagonal.ravel()]))
    return _Net(points=points, triangles=whole(vertices), twines=lines, twine=np.tile(twine, (copies, 1)),
                twine_scale=twine_scale(twine), behind=np.tile(behind, copies), hexagonal=whole(hexagonal),
                bars=whole(ends), bar=np.tile(bar, copies), bar_scale=bar_scale(bar), front=front,
                marks=marks(scene, points), speed=float(env.current_speed),
                current=np.asarray(env.current_direction, dtype=float),
                zoom=_zoom(scene, points.reshape(-1, 3), points[:, in_netting].reshape(-1, 3)))


def _colours(name, scale, values):
    """RGBA (K, 4) of ``values`` under the colour map ``name`` and the norm ``scale``."""
    import matplotlib

    return matplotlib.colormaps[name](scale(np.asarray(values, dtype=float)))


def _axis_name(direction):
    """'x', '-y', ... for a direction along a coordinate axis, else None."""
    k = int(np.argmax(np.abs(direction)))
    if abs(abs(direction[k]) - 1.0) < 1e-9:
        return ("-" if direction[k] < 0 else "") + "xyz"[k]
    return None


def heading(along, up):
    """The horizontal direction ``along`` (unit, square to ``up``) in words: "20° from x toward y", the angle
    from the first horizontal coordinate axis toward the second (those other than ``up``'s, in the right-handed
    order x, y, z); "x" where it runs along a coordinate axis."""
    name = _axis_name(along)
    if name is not None:
        return name
    k = int(np.argmax(np.abs(up)))
    a, b = (k + 1) % 3, (k + 2) % 3
    if np.sign(up[k]) < 0:
        a, b = b, a
    angle = float(np.degrees(np.arctan2(along[b], along[a])))
    return f"{angle:.0f}° from {'xyz'[a]} toward {'xyz'[b]}"


# -- the views ---------------------------------------------------------------------------------------------------

def _twine_widths(scale, values):
    """Widths (pixels at the figure's dpi) of the lines of twines of tensions ``values`` (N): 0.7 for the
    slack, 2 for the largest."""
    return 0.7 + 1.3 * np.clip(np.ma.filled(scale(np.asarray(values, dtype=float)), 0.0), 0.0, 1.0)


def _netting_colours(d: _Net, toward, order):
    """Colours of the netting seen along ``toward``, its triangles in ``order``: (T, 4) the surface's grey
    (brighter where it faces the viewer: the shape reads as a shaded surface) and (T, 2, 4) the U and V
    twines'."""
    tri = d.triangles[order]
    normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    with np.errstate(invalid="ignore", divide="ignore"):
        facing = np.nan_to_num(np.abs(normal @ toward) / np.linalg.norm(normal, axis=1))
    grey = _SURFACE + (0.97 - _SURFACE) * facing
    surface = np.stack([grey, grey, grey, np.ones(len(tri))], axis=1)
    twines = _colours(TWINE_COLOURS, d.twine_scale, d.twine[order].ravel()).reshape(len(tri), 2, 4)
    return surface, twines


class NettingArtist(Artist):
    """The netting of one view, drawn far to near in one call of the renderer (its Gouraud-shaded triangles,
    one colour per triangle): each netting triangle, then its U and V twine lines as thin quadrilaterals (two
    triangles each) over it, so that a nearer triangle hides the twines behind it. One call for all: a
    collection of as many paths drew each as a path of its own, several times slower.

    triangles: (T, 3, 2) the netting triangles in the picture plane (m), far to near; twines: (T, 2, 2, 2) the
    ends of their U and V lines; widths: (T, 2) the lines' widths (m in the picture plane); surface: (T, 4) the
    triangles' colours; colours: (T, 2, 4) the lines'; order: (T,) the index of each drawn triangle among the
    whole net's (:class:`_Net`'s ``triangles``)."""

    def __init__(self, triangles, twines, widths, surface, colours, order, **kwargs):
        super().__init__()
        self.triangles, self.twines, self.widths = triangles, twines, widths
        self.surface, self.colours, self.order = surface, colours, order
        self.set(**kwargs)

    def flat_triangles(self):
        """((5 T, 3, 2) m, (5 T, 4)): the triangles the renderer draws, in order, and their colours."""
        a, b = self.twines[:, :, 0], self.twines[:, :, 1]                    # (T, 2, 2)
        along = b - a
        length = np.linalg.norm(along, axis=-1, keepdims=True)
        side = np.stack([-along[..., 1], along[..., 0]], axis=-1) / np.where(length > 0, length, 1.0)
        side = side * (self.widths[..., None] / 2)
        quads = np.stack([np.stack([a + side, b + side, b - side], axis=2),
                          np.stack([a + side, b - side, a - side], axis=2)], axis=2)   # (T, 2, 2, 3, 2)
        t = len(self.triangles)
        shapes = np.concatenate([self.triangles[:, None], quads.reshape(t, 4, 3, 2)], axis=1).reshape(-1, 3, 2)
        colours = np.concatenate([self.surface[:, None], np.repeat(self.colours, 2, axis=1)], axis=1).reshape(-1, 4)
        return shapes, colours

    def get_datalim(self, transData):
        from matplotlib.transforms import Bbox

        return Bbox.from_extents(*self.triangles.reshape(-1, 2).min(axis=0), *self.triangles.reshape(-1, 2).max(axis=0))

    def draw(self, renderer):
        if not self.get_visible() or not len(self.triangles):
            return
        shapes, colours = self.flat_triangles()
        renderer.open_group("netting", gid=self.get_gid())
        gc = renderer.new_gc()
        self._set_gc_clip(gc)
        renderer.draw_gouraud_triangles(gc, shapes, np.repeat(colours[:, None], 3, axis=1),
                                        self.axes.transData.frozen())
        gc.restore()
        renderer.close_group("netting")
        self.stale = False


def _fit(ax, lo, hi, pad=0.05):
    """Limits of the 2D axis ``ax`` showing the region (lo, hi) (2,) (m) and a margin ``pad`` of its extent, at
    equal scale in the axis's box (grown along the direction the box leaves room in); returns the pixels per
    metre at the figure's dpi."""
    fig = ax.figure
    box = ax.get_position()
    width, height = box.width * fig.get_figwidth() * fig.dpi, box.height * fig.get_figheight() * fig.dpi
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    margin = pad * max(float((hi - lo).max()), 1e-9)
    lo, hi = lo - margin, hi + margin
    span = hi - lo
    metres = max(span[0] / width, span[1] / height)                  # per pixel
    mid, half = (lo + hi) / 2, np.array([width, height]) * metres / 2
    ax.set_xlim(mid[0] - half[0], mid[0] + half[0])
    ax.set_ylim(mid[1] - half[1], mid[1] + half[1])
    ax.set_aspect("equal", adjustable="box")
    return 1.0 / metres


def _corners(box):
    """(8, 3) the corners of the box (lo, hi) (3,) (m)."""
    lo, hi = box
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1) for k in (0, 1)])


def _draw_view(ax, d: _Net, right, vertical, toward, box=None):
    """The net projected on the plane (right, vertical) (unit vectors, m along each) on the 2D axis ``ax``, seen
    looking along ``toward`` (= vertical × right): the far side drawn first, so that the near side covers it.
    box: (lo, hi) (3,) m, the region to show (the netting's, zoomed), else the whole net; the current's arrow
    beside it. Returns the shown region's corners (2,) (2D, m)."""
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path

    basis = np.stack([right, vertical])

    def flat(points):
        return np.asarray(points) @ basis.T

    shown = flat(d.points.reshape(-1, 3) if box is None else _corners(box))
    lo, hi = shown.min(axis=0), shown.max(axis=0)
    extent = float((hi - lo).max()) or 1.0
    region = [lo, hi]
    arrow = None
    if d.speed > 0:
        flow = flat(d.current / np.linalg.norm(d.current))
        if np.linalg.norm(flow) > 1e-6:
            flow = flow / np.linalg.norm(flow)
            tip = (lo + hi) / 2 - flow * (0.5 * float(np.abs(flow) @ (hi - lo)) + 0.05 * extent)
            arrow = (tip - 0.25 * extent * flow, tip)
        else:
            arrow = (np.array([lo[0] - 0.1 * extent, hi[1]]),)
        region += list(arrow)
    region = np.asarray(region)
    per_metre = _fit(ax, region.min(axis=0), region.max(axis=0))

    if len(d.triangles):
        order = np.argsort(-(d.triangles.mean(axis=1) @ toward), kind="stable")
        surface, colours = _netting_colours(d, toward, order)
        widths = _twine_widths(d.twine_scale, d.twine[order]) / per_metre
        ax.add_artist(NettingArtist(flat(d.triangles[order]), flat(d.twines[order]), widths, surface, colours, order,
                                    gid=NETTING, zorder=1))
        if d.behind.any():   # one hatched path of all the triangles behind the front
            ax.add_patch(PathPatch(Path.make_compound_path_from_polys(flat(d.triangles[d.behind])), fill=False,
                                   edgecolor=_BEHIND_EDGE, hatch="///", linewidth=0.0, gid=BEHIND, label=BEHIND,
                                   zorder=2))
    if len(d.hexagonal):
        order = np.argsort(-(d.hexagonal.mean(axis=1) @ toward), kind="stable")
        ax.add_collection(PolyCollection(flat(d.hexagonal[order]), facecolors=(0.6, 0.6, 0.6, 0.6), edgecolors=_EDGE,
                                         linewidths=0.3, gid=HEXAGONAL, zorder=1), autolim=False)
    if len(d.bars):
        ax.add_collection(LineCollection(flat(d.bars), colors=_colours(BAR_COLOURS, d.bar_scale, d.bar),
                                         linewidths=2.0, gid=CABLES, zorder=3), autolim=False)
    if len(d.front):
        ax.add_collection(LineCollection(flat(d.front), colors=_FRONT_COLOUR, linewidths=1.5, gid=FRONT, label=FRONT,
                                         zorder=4), autolim=False)
    written = []
    for mark in d.marks:
        at = flat(mark.points)
        ax.scatter(*at.T, gid=mark.gid, label=mark.label, zorder=5, **mark.style)
        for point, text in zip(at, mark.texts):   # none where another is written within 20 pixels
            if np.all((lo <= point) & (point <= hi)) and all(
                    np.linalg.norm(point - p) * per_metre > 20.0 for p in written):
                written.append(point)
                ax.annotate(text, point, xytext=(3, 3), textcoords="offset points", fontsize=6, zorder=6)
    if arrow is not None:
        text = f"current {d.speed:g} m/s"
        if len(arrow) == 2:
            ax.annotate(text, xy=arrow[1], xytext=arrow[0], color="tab:blue", fontsize=8, ha="center", va="bottom",
                        arrowprops=dict(arrowstyle="-|>", color="tab:blue", lw=1.5), gid=CURRENT, label=CURRENT,
                        zorder=6)
        else:   # the current runs square to the picture: ⊙ coming out of it, ⊗ going in
            at = arrow[0]
            toward_viewer = float(np.dot(d.current, toward)) < 0
            ax.plot(*at, marker="o", markersize=12, markerfacecolor="none", markeredgecolor="tab:blue", ls="none",
                    gid=CURRENT, label=CURRENT, zorder=6)
            ax.plot(*at, marker="." if toward_viewer else "x", markersize=8 if toward_viewer else 6, color="tab:blue",
                    ls="none", zorder=6)
            ax.annotate(f"{text}, {'toward the viewer' if toward_viewer else 'into the picture'}", xy=at,
                        xytext=(0, -10), textcoords="offset points", color="tab:blue", fontsize=8, ha="left",
                        va="top")
    return lo, hi


def _label_axes(ax, right, vertical, names):
    """Axis labels of a view: the coordinate's name where a direction runs along a coordinate axis ("x (m)"),
    else the direction's words (``names``: (right's, vertical's))."""
    ax.set_xlabel(f"{_axis_name(right) or names[0]} (m)", fontsize=8)
    ax.set_ylabel(f"{_axis_name(vertical) or names[1]} (m), up" if names[1] == "up" else
                  f"{_axis_name(vertical) or names[1]} (m)", fontsize=8)
    ax.tick_params(labelsize=7)


def _zoom_note(d: _Net):
    return ", zoomed on the netting" if d.zoom is not None else ""


def _side_view(ax, d: _Net, scene, title=None, box=None):
    """The side view: the plane (along, up) of the current and the vertical, seen from the side of -across."""
    along, across, up = view_directions(scene)
    _draw_view(ax, d, along, up, across, box)
    current = "along the current" if d.speed > 0 else "along x"
    _label_axes(ax, along, up, (current, "up"))
    if title is None:
        title = f"{VIEW_SIDE} ({_axis_name(along) or 'along the current'}–{_axis_name(up) or 'up'})"
        if d.speed > 0 and _axis_name(along) is None:
            title += f", the current heading {heading(along, up)}"
        title += "" if box is None else _zoom_note(d)
    ax.set_title(title, fontsize=9)
    ax.set_label(VIEW_SIDE)


def _along_view(ax, d: _Net, scene, box=None):
    """The view along the current: the plane (across, up), seen from downstream (from +along)."""
    along, across, up = view_directions(scene)
    _draw_view(ax, d, across, up, -along, box)
    name = "along the current" if d.speed > 0 else f"along {_axis_name(along) or 'x'}"
    seen = "downstream" if d.speed > 0 else f"beyond the net along {_axis_name(along) or 'x'}"
    _label_axes(ax, across, up, ("across the current" if d.speed > 0 else "across", "up"))
    plane = f"{_axis_name(across) or 'across the current'}–{_axis_name(up) or 'up'}"
    ax.set_title(f"view {name} ({plane}), seen from {seen}"
                 f"{'' if box is None else _zoom_note(d)}", fontsize=9)
    ax.set_label(VIEW_ALONG)


def _nice(length):
    """The round length (1, 2 or 5 × 10^k) at most ``length``."""
    k = np.floor(np.log10(length))
    return max(m * 10.0 ** k for m in (1.0, 2.0, 5.0) if m * 10.0 ** k <= length)


def _oblique_view(ax, d: _Net, scene, box=None):
    """The 3D view: an oblique projection (:func:`oblique_directions`), no ticks (its picture plane's
    coordinates are no coordinates of the net's), a scale bar and the coordinate axes' directions."""
    right, vertical, toward = oblique_directions(scene)
    lo, hi = _draw_view(ax, d, right, vertical, toward, box)
    ax.set_xticks([])
    ax.set_yticks([])
    bar = _nice(0.25 * max(float((hi - lo).max()), 1e-9))
    fraction = bar / float(np.ptp(ax.get_xlim()))   # the scale bar, in the axis's lower left corner
    ax.plot([0.04, 0.04 + fraction], [0.04, 0.04], color="k", lw=2.0, solid_capstyle="butt", transform=ax.transAxes)
    ax.annotate(f"{bar:g} m", (0.04 + fraction / 2, 0.04), xytext=(0, 3), textcoords="offset points",
                xycoords="axes fraction", ha="center", fontsize=7)
    origin = (0.93, 0.1)     # the coordinate axes' directions, in the axis's corner
    for k, name in enumerate("xyz"):
        arm = np.eye(3)[k] @ np.stack([right, vertical]).T * 0.06
        ax.annotate("", xy=(origin[0] + arm[0], origin[1] + arm[1]), xytext=origin, xycoords="axes fraction",
                    arrowprops=dict(arrowstyle="-|>", color="0.3", lw=0.8))
        ax.annotate(name, (origin[0] + 1.3 * arm[0], origin[1] + 1.3 * arm[1]), xycoords="axes fraction",
                    ha="center", va="center", fontsize=7, color="0.3")
    ax.set_title(f"{VIEW_3D}{'' if box is None else _zoom_note(d)}", fontsize=9)
    ax.set_label(VIEW_3D)


def _whole_view(ax, d: _Net, scene):
    """The side view of the whole (cables included), the region the zoomed views show boxed."""
    from matplotlib.patches import Rectangle

    along, across, up = view_directions(scene)
    _draw_view(ax, d, along, up, across)
    corners = _corners(d.zoom) @ np.stack([along, up]).T
    a, b = corners.min(axis=0), corners.max(axis=0)
    ax.add_patch(Rectangle(a, *(b - a), fill=False, ls="--", lw=0.8, ec="0.3", gid=ZOOMED, zorder=7))
    _label_axes(ax, along, up, ("along the current" if d.speed > 0 else "along x", "up"))
    ax.set_title("the whole, side view (the netting boxed)", fontsize=9)
    ax.set_label(VIEW_WHOLE)


def _legend(ax, axes_for_handles):
    """The legend of the marks (what holds the net, current, catch front) of ``axes_for_handles``'s artists, on
    ``ax``: the colours of the netting and cables are read on their colour bars."""
    shown, seen = [], set()
    for artist in axes_for_handles.collections:
        label = artist.get_label()
        if artist.get_gid() in (FIXED, HELD, FLOATS, SINKERS, FRONT) and label not in seen:
            seen.add(label)
            shown.append((artist, label))
    if shown:
        ax.legend(*zip(*shown), loc="upper left", fontsize=7, framealpha=0.85)


def twine_note(scale):
    """The words on the picture saying what the netting's colours are, under the twine colour ``scale``
    (:func:`twine_scale`)."""
    from matplotlib.colors import LogNorm

    if isinstance(scale, LogNorm):
        return (f"netting: the U and V twines of every triangle drawn apart, each coloured by its tension "
                f"(log scale, largest {scale.vmax:.4g} N; below {scale.vmin:.3g} N, slack twines too, in the "
                f"palest colour)")
    return "netting: the U and V twines of every triangle drawn apart; no twine under tension"


def twine_ticks(scale):
    """The ticks (N) of the twine colour bar under ``scale`` (:func:`twine_scale`): on a log scale its decades
    (1, 2 and 5 in each where it spans less than two), the largest tension at the top."""
    from matplotlib.colors import LogNorm

    lo, hi = float(scale.vmin), float(scale.vmax)
    if not isinstance(scale, LogNorm):
        return [lo + f * (hi - lo) for f in (0.0, 0.25, 0.5, 0.75, 1.0)]
    steps = (1.0,) if hi / lo >= 100.0 else (1.0, 2.0, 5.0)
    return [m * 10.0 ** k for k in range(int(np.floor(np.log10(lo))), int(np.ceil(np.log10(hi))) + 1)
            for m in steps if lo <= m * 10.0 ** k < hi / 1.6] + [hi]


def _colour_bars(fig, d: _Net, twine_rect, bar_rect):
    """The colour bars of the tensions drawn (twine, bar) on new axes at the figure's rectangles."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm

    bars = []
    if len(d.triangles):
        cax = fig.add_axes(twine_rect, label="<colorbar>")
        log = isinstance(d.twine_scale, LogNorm)
        bar = fig.colorbar(ScalarMappable(d.twine_scale, TWINE_COLOURS), cax=cax, label=TWINE_LABEL,
                           extend="min" if log else "neither")
        if log:
            ticks = twine_ticks(d.twine_scale)
            bar.set_ticks(ticks, labels=[f"{t:.4g}" for t in ticks])
            bar.minorticks_off()
        bars.append(bar)
    if len(d.bars):
        cax = fig.add_axes(bar_rect, label="<colorbar>")
        bar = fig.colorbar(ScalarMappable(d.bar_scale, BAR_COLOURS), cax=cax, label=BAR_LABEL)
        bar.ax.yaxis.get_major_formatter().set_useOffset(False)   # 57858.2 N, not 0.2 above an offset of 5.7858e4
        bars.append(bar)
    for bar in bars:
        bar.ax.tick_params(labelsize=7)
        bar.ax.yaxis.label.set_fontsize(8)
    return bars


def _figure(size):
    """A figure on matplotlib's Agg canvas, outside pyplot (nothing to close, no GUI backend)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=_DPI)
    FigureCanvasAgg(fig)
    return fig


# -- figures -----------------------------------------------------------------------------------------------------

def net_figure(scene, x, title=None, *, twine_tension=None, bar_tension=None, catch_front=None):
    """The figure of the net at positions x (N, 3) (m): the 3D view and the view along the current above, the
    side view below (beside it the whole, where the netting is zoomed on), the tensions' colour bars on the
    right (arguments as :func:`plot_net`'s). A matplotlib Figure on the Agg canvas, not pyplot's."""
    d = _prepare(scene, x, twine_tension, bar_tension, catch_front)
    fig = _figure((12.0, 9.0))
    ax3 = fig.add_axes((0.03, 0.50, 0.43, 0.40))
    along = fig.add_axes((0.53, 0.50, 0.33, 0.40))
    if d.zoom is None:
        side = fig.add_axes((0.06, 0.06, 0.80, 0.36))
    else:
        side = fig.add_axes((0.06, 0.06, 0.50, 0.36))
        _whole_view(fig.add_axes((0.62, 0.06, 0.24, 0.36)), d, scene)
    _oblique_view(ax3, d, scene, d.zoom)
    _along_view(along, d, scene, d.zoom)
    _side_view(side, d, scene, box=d.zoom)
    _colour_bars(fig, d, (0.90, 0.50, 0.012, 0.40), (0.90, 0.06, 0.012, 0.36))
    _legend(ax3, ax3)
    if title:
        fig.suptitle(title, y=0.985, fontsize=12)
    if len(d.triangles):
        fig.text(0.5, 0.945, twine_note(d.twine_scale), ha="center", fontsize=8)
    return fig


def save_png(path, scene, x, title=None, *, twine_tension=None, bar_tension=None, catch_front=None):
    """Write the PNG picture of :func:`net_figure` of the net at positions x (N, 3) (m) to ``path``."""
    fig = net_figure(scene, x, title, twine_tension=twine_tension, bar_tension=bar_tension, catch_front=catch_front)
    fig.savefig(str(path), dpi=_DPI)


def plot_net(scene, x, ax=None, title=None, *, twine_tension=None, bar_tension=None, catch_front=None,
             colorbar=True):
    """Draw the net at positions x (N, 3) (m) on a 3D matplotlib axis (created with pyplot if None); returns the
    axis. Drawn as :func:`net_figure` draws it: the twines by their tensions on the grey netting, cables by
    theirs, what holds the net, the current, the catch front.

    twine_tension: (E, 2) U and V twine tensions (N) of the netting triangles, bar_tension: (B,) bar tensions
    (N); by default :func:`jaxnet.figures.twine_tensions` and :func:`jaxnet.figures.bar_tensions` at x.
    catch_front: the catch front's position (m) along ``scene.catch.axis`` (result.json's ``catch.front_m``),
    drawn where the scene has a catch. colorbar: add the tensions' colour bars beside the axis.
    """
    from matplotlib.cm import ScalarMappable
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    if ax is None:
        import matplotlib.pyplot as plt

        ax = plt.figure(figsize=(8, 6)).add_subplot(projection="3d")
    d = _prepare(scene, x, twine_tension, bar_tension, catch_front)
    up = view_directions(scene)[2]
    if len(d.triangles):
        t = len(d.triangles)
        lines = np.concatenate([d.twines, d.twines.mean(axis=2, keepdims=True)], axis=2)   # (T, 2, 3, 3)
        items = np.concatenate([d.triangles[:, None], lines], axis=1).reshape(-1, 3, 3)
        grey = np.tile([0.85, 0.85, 0.85, 1.0], (t, 1))
        colour = _colours(TWINE_COLOURS, d.twine_scale, d.twine.ravel()).reshape(t, 2, 4)
        faces = np.concatenate([grey[:, None], np.zeros((t, 2, 4))], axis=1).reshape(-1, 4)
        edges = np.concatenate([grey[:, None], colour], axis=1).reshape(-1, 4)
        widths = np.concatenate([np.full((t, 1), 0.3), _twine_widths(d.twine_scale, d.twine.ravel()).reshape(t, 2)],
                                axis=1).ravel()
        netting = Poly3DCollection(items, facecolors=faces, edgecolors=edges, linewidths=widths, gid=NETTING)
        # a triangle's twine lines are as deep as the triangle (their midpoints at its centroid): sorted a hair
        # nearer, so that mplot3d's depth sort (not stable) draws them after it, not under it (its depth function
        # is private to matplotlib: where it is absent, the plain sort)
        nearer = np.tile([0.0, -1e-9, -1e-9], t)
        if hasattr(netting, "_zsortfunc"):
            netting._zsortfunc = lambda z, axis=-1: np.mean(z, axis=axis) + nearer
        ax.add_collection3d(netting)
    if len(d.hexagonal):
        ax.add_collection3d(Poly3DCollection(d.hexagonal, facecolors=(0.6, 0.6, 0.6, 0.6), edgecolors=_EDGE,
                                             linewidths=0.3, gid=HEXAGONAL))
    if len(d.bars):
        ax.add_collection3d(Line3DCollection(d.bars, colors=_colours(BAR_COLOURS, d.bar_scale, d.bar), linewidths=2.0,
                                             gid=CABLES))
    if len(d.front):
        ax.add_collection3d(Line3DCollection(d.front, colors=_FRONT_COLOUR, linewidths=1.5, gid=FRONT, label=FRONT))
    for mark in d.marks:
        ax.scatter(*mark.points.T, depthshade=False, gid=mark.gid, label=mark.label, **mark.style)
        if mark.texts:
            for point, text in zip(mark.points, mark.texts):
                ax.text(*point, f" {text}", fontsize=6)
    points = d.points.reshape(-1, 3)
    lo, hi = points.min(axis=0), points.max(axis=0)
    extent = float((hi - lo).max()) or 1.0
    shown = [lo, hi]
    if d.speed > 0:
        direction = d.current / np.linalg.norm(d.current)
        centre = (lo + hi) / 2
        tip = centre - direction * (0.5 * float(np.abs(direction) @ (hi - lo)) + 0.05 * extent)
        tail = tip - 0.25 * extent * direction
        ax.quiver(*tail, *(tip - tail), color="tab:blue", linewidth=1.5, arrow_length_ratio=0.3, gid=CURRENT)
        ax.text(*tail, f"{d.speed:g} m/s", color="tab:blue", fontsize=8)
        shown += [tail, tip]
    shown = np.asarray(shown)
    lo, hi = shown.min(axis=0), shown.max(axis=0)
    mid, half = (lo + hi) / 2, max(float((hi - lo).max()) / 2, 1e-9)
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_box_aspect((1.0, 1.0, 1.0))
    k = int(np.argmax(np.abs(up)))
    if abs(abs(up[k]) - 1.0) < 1e-9:
        ax.view_init(vertical_axis="xyz"[k])
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    if colorbar:
        fig = ax.figure
        if len(d.triangles):
            fig.colorbar(ScalarMappable(d.twine_scale, TWINE_COLOURS), ax=ax, label=TWINE_LABEL, shrink=0.8)
        if len(d.bars):
            fig.colorbar(ScalarMappable(d.bar_scale, BAR_COLOURS), ax=ax, label=BAR_LABEL, shrink=0.8)
    if title:
        ax.set_title(title)
    _legend(ax, ax)
    return ax


def largest_reaction_record(figures) -> int:
    """Index of the record of a run whose total reaction (``figures["reaction_total_N"]``, (R, 3) N) is largest in
    magnitude; the last record when the run holds none."""
    reaction = figures.get("reaction_total_N")
    if reaction is None or len(reaction) == 0:
        return -1
    return int(np.argmax(np.linalg.norm(np.asarray(reaction, dtype=float), axis=1)))


def _carried(series):
    """``series`` as an array, or None where it is absent or zero throughout (no bar under tension: a net
    without cables records zeros, which would draw an empty curve)."""
    if series is None:
        return None
    series = np.asarray(series, dtype=float)
    return series if series.size and np.any(series != 0.0) else None


def run_figure(scene, times, positions, figures, title=None):
    """The figure of a run in time: the total reaction on the fixed nodes (its x, y, z components and magnitude,
    N) against time (s), the largest twine and bar tensions (N) against time (the bars' on an axis of their own,
    on the right; a tension zero throughout is not drawn), and the side view of the net at the record of the
    largest reaction (the time it is at in its title, and marked on the curves). A matplotlib Figure on the Agg
    canvas, not pyplot's.

    times: (R,) s; positions: (R, N, 3) m; figures: name -> (R, ...) as :attr:`jaxnet.solve.dynamics.Trajectory.
    figures` (``reaction_total_N``, ``max_twine_tension_N``, ``max_bar_tension_N``: those present are drawn).
    """
    times = np.asarray(times, dtype=float)
    positions = np.asarray(positions, dtype=float)
    k = largest_reaction_record(figures) % len(times)
    fig = _figure((12.0, 9.0))
    forces = fig.add_axes((0.07, 0.56, 0.36, 0.36))
    tensions = fig.add_axes((0.53, 0.56, 0.32, 0.36))
    side = fig.add_axes((0.07, 0.06, 0.72, 0.40))
    reaction = figures.get("reaction_total_N")
    if reaction is not None:
        reaction = np.asarray(reaction, dtype=float)
        for c, name in enumerate("xyz"):
            forces.plot(times, reaction[:, c], lw=1.0, label=f"R{name}")
        forces.plot(times, np.linalg.norm(reaction, axis=1), "k", lw=1.8, label="|R|")
        forces.legend(fontsize=8)
    forces.set_xlabel("time (s)")
    forces.set_ylabel("total reaction (N)")
    forces.set_title("total reaction on the fixed nodes", fontsize=10)
    twine, bar = _carried(figures.get("max_twine_tension_N")), _carried(figures.get("max_bar_tension_N"))
    lines = []
    if twine is not None:
        lines += tensions.plot(times, twine, color="tab:green", label="largest twine tension")
        tensions.set_ylabel("largest twine tension (N)", color="tab:green")
    if bar is not None:
        bars = tensions.twinx() if twine is not None else tensions
        lines += bars.plot(times, bar, color="tab:purple", label="largest bar tension")
        bars.set_ylabel("largest bar tension (N)", color="tab:purple")
    if lines:
        tensions.legend(lines, [line.get_label() for line in lines], fontsize=8)
    else:
        tensions.text(0.5, 0.5, "no twine or bar under tension", ha="center", va="center",
                      transform=tensions.transAxes)
    tensions.set_xlabel("time (s)")
    tensions.set_title("largest tensions", fontsize=10)
    for ax in (forces, tensions):
        ax.axvline(times[k], color="0.5", ls=":", lw=1.0)
    d = _prepare(scene, positions[k])
    what = "largest total reaction" if reaction is not None else "last record"
    _side_view(side, d, scene, f"side view at t = {times[k]:.6g} s ({what})")
    _colour_bars(fig, d, (0.82, 0.06, 0.012, 0.40), (0.905, 0.06, 0.012, 0.40) if len(d.triangles) else
                 (0.82, 0.06, 0.012, 0.40))
    _legend(side, side)
    if title:
        fig.suptitle(title, y=0.985, fontsize=12)
    if len(d.triangles):
        fig.text(0.5, 0.955, twine_note(d.twine_scale), ha="center", fontsize=8)
    return fig


def save_run_png(path, scene, times, positions, figures, title=None):
    """Write the PNG picture of :func:`run_figure` of a run (times (R,) s, positions (R, N, 3) m, figures as
    :attr:`jaxnet.solve.dynamics.Trajectory.figures`) to ``path``."""
    run_figure(scene, times, positions, figures, title).savefig(str(path), dpi=_DPI)
