"""Pictures of a net (matplotlib), as a gear designer reads them.

The netting triangles are coloured by their twine tension (the mean of the U and V twines', N) and the cables
by their bar tension (N), each on its own colour scale with a colour bar: twines and ropes differ by orders of
magnitude, and one scale would leave the netting a single colour. The pictures are drawn at equal scale (the
same metres per unit on every axis: a cod-end's opening is read off its length), show the current as an arrow
with its speed, and the catch's front across the net with the netting behind it (that carries the catch's
pressure) hatched. A model with symmetry planes (a cod-end's quarter) is drawn mirrored to the whole net, the
tensions repeated in every copy; its nodes held only across a plane they lie on are what makes the model
symmetric, not fixings, and are not marked as fixed. Fixed nodes are small hollow circles, so that they do not
hide the net.

:func:`save_png` writes one figure of three views of an equilibrium (:func:`net_figure`): 3D, the side view
(the plane of the current and the vertical) and the view along the current; :func:`plot_net` draws the 3D view
on an axis of one's own (notebooks). :func:`save_run_png` writes the picture of a run in time
(:func:`run_figure`): the total reaction and the largest tensions against time, and the side view of the net
when the reaction is largest.

Directions: ``along`` is the current's direction (x without a current) made square to ``up``; ``across`` =
``up`` × ``along``, so that the view along the current is seen from downstream with ``across`` to the right
(for a current along x and up along z: the side view is the x–z plane, the view along the current the y–z
plane).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from jaxnet import scene as scene_lib

#: matplotlib colour map of the twine tension of the netting triangles
TWINE_COLOURS = "viridis"
#: matplotlib colour map of the bar (cable) tension, a second scale: ropes carry orders of magnitude more
BAR_COLOURS = "copper"
#: labels of the colour bars (their unit is the newton)
TWINE_LABEL = "twine tension (N)"
BAR_LABEL = "bar tension (N)"
#: labels of the artists the pictures draw, by which they can be found on an axis (``get_label``)
NETTING, HEXAGONAL, CABLES, FIXED, MASSES, CURRENT, FRONT, BEHIND = (
    "netting", "hexagonal netting", "cables", "fixed nodes", "lumped masses", "current", "catch front",
    "behind the catch front")

_EDGE = (0.0, 0.0, 0.0, 0.15)          # edges of the uncoloured (hexagonal) triangles
_BEHIND_EDGE = (0.0, 0.0, 0.0, 0.4)    # edges (3D) and hatching (2D) of the triangles behind the catch front
_FRONT_COLOUR = "magenta"


# -- what is drawn -----------------------------------------------------------------------------------------------

def held_nodes(scene) -> np.ndarray:
    """(N,) bool: the nodes drawn as fixed, those held along some axis other than the normal of a symmetry plane
    they lie on (:func:`jaxnet.scene.on_symmetry_planes`, the test of :meth:`jaxnet.net.Net.symmetry_plane`). A
    node held only across its plane is free in the whole net: the hold is what makes the modelled part
    symmetric."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool)
    return (fixed & ~scene_lib.on_symmetry_planes(scene.nodes.position, scene.symmetry_planes)).any(axis=1)


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


def _tension_scale(values):
    """Normalize from the smallest to the largest tension (N); a scale 1 N wide from the smallest where they
    are all equal to a millionth of a newton (a net at rest, whose tensions are rounding noise), since a colour
    bar needs a span and a span of 1e-10 N would only colour the noise."""
    from matplotlib.colors import Normalize

    values = np.asarray(values, dtype=float)
    lo, hi = (float(values.min()), float(values.max())) if values.size else (0.0, 0.0)
    return Normalize(vmin=lo, vmax=hi if hi - lo > 1e-6 else lo + 1.0)


class _Net(NamedTuple):
    """A net ready to draw, the whole of it (every mirrored copy, copy after copy as :func:`jaxnet.scene.
    mirrored` gives them, the model first)."""

    points: np.ndarray          # (copies, N, 3) m
    triangles: np.ndarray       # (copies * E, 3, 3) m, the netting triangles' corners
    twine: np.ndarray           # (copies * E,) mean twine tension (N)
    twine_scale: object         # Normalize of the twine tensions
    behind: np.ndarray          # (copies * E,) bool: triangles behind the catch front
    hexagonal: np.ndarray       # (copies * H, 3, 3) m
    bars: np.ndarray            # (copies * B, 2, 3) m
    bar: np.ndarray             # (copies * B,) bar tension (N)
    bar_scale: object           # Normalize of the bar tensions
    front: np.ndarray           # (copies * K, 2, 3) m: the segments where the front plane cuts the netting
    fixed: np.ndarray           # (F, 3) m: fixed nodes of all copies, each point once
    masses: np.ndarray          # (M, 3) m: nodes with a lumped mass, each point once
    speed: float                # current speed (m/s), 0 for none
    current: np.ndarray         # (3,) unit current direction


def _distinct(points):
    """The points (K, 3) with those that coincide (to 1e-9 m: a node on a symmetry plane is its own image) kept
    once."""
    if len(points) == 0:
        return points.reshape(0, 3)
    _, first = np.unique(np.round(points / 1e-9).astype(np.int64), axis=0, return_index=True)
    return points[np.sort(first)]


def _front_cut(x, vertices, axis, front):
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
    twine = np.asarray(twine_tension, dtype=float).reshape(len(vertices), 2).mean(axis=1)
    bar = np.asarray(bar_tension, dtype=float).reshape(len(ends))
    behind = np.zeros(len(vertices), dtype=bool)
    front = np.zeros((0, 2, 3))
    if scene.catch is not None and catch_front is not None and len(vertices):
        axis = np.asarray(scene.catch.axis, dtype=float)
        behind = ((x[vertices] @ axis) > float(catch_front)).any(axis=1)
        cut = _front_cut(x, vertices, axis, float(catch_front))
        front = scene_lib.mirrored(scene, cut.reshape(-1, 3)).reshape(-1, 2, 3)
    held = held_nodes(scene)
    lumped = np.asarray(scene.nodes.mass) > 0
    return _Net(points=points, triangles=whole(vertices), twine=np.tile(twine, copies),
                twine_scale=_tension_scale(twine), behind=np.tile(behind, copies), hexagonal=whole(hexagonal),
                bars=whole(ends), bar=np.tile(bar, copies), bar_scale=_tension_scale(bar), front=front,
                fixed=_distinct(points[:, held].reshape(-1, 3)), masses=_distinct(points[:, lumped].reshape(-1, 3)),
                speed=float(env.current_speed), current=np.asarray(env.current_direction, dtype=float))


def _colours(name, scale, values):
    """RGBA (K, 4) of ``values`` under the colour map ``name`` and the Normalize ``scale``."""
    import matplotlib

    return matplotlib.colormaps[name](scale(values))


def _axis_name(direction):
    """'x', '-y', ... for a direction along a coordinate axis, else its components."""
    k = int(np.argmax(np.abs(direction)))
    if abs(abs(direction[k]) - 1.0) < 1e-9:
        return ("-" if direction[k] < 0 else "") + "xyz"[k]
    return "(" + ", ".join(f"{c:.2f}" for c in direction) + ")"


# -- the 3D view -------------------------------------------------------------------------------------------------

def _draw_3d(ax, d: _Net, up):
    """The net on the 3D axis ``ax``, its spans equal (a cube around the net and the current's arrow)."""
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    if len(d.triangles):
        rgba = _colours(TWINE_COLOURS, d.twine_scale, d.twine)
        edges = np.where(d.behind[:, None], np.asarray(_BEHIND_EDGE), rgba)
        ax.add_collection3d(Poly3DCollection(d.triangles, facecolors=rgba, edgecolors=edges, linewidths=0.3,
                                             label=NETTING))
    if len(d.hexagonal):
        ax.add_collection3d(Poly3DCollection(d.hexagonal, facecolors=(0.6, 0.6, 0.6, 0.6), edgecolors=_EDGE,
                                             linewidths=0.3, label=HEXAGONAL))
    if len(d.bars):
        ax.add_collection3d(Line3DCollection(d.bars, colors=_colours(BAR_COLOURS, d.bar_scale, d.bar), linewidths=2.0,
                                             label=CABLES))
    if len(d.front):
        ax.add_collection3d(Line3DCollection(d.front, colors=_FRONT_COLOUR, linewidths=1.5, label=FRONT))
    if len(d.fixed):
        ax.scatter(*d.fixed.T, s=6, facecolors="none", edgecolors="red", linewidths=0.6, depthshade=False,
                   label=FIXED)
    if len(d.masses):
        ax.scatter(*d.masses.T, s=6, marker="s", facecolors="none", edgecolors="k", linewidths=0.6, depthshade=False,
                   label=MASSES)
    x = d.points.reshape(-1, 3)
    lo, hi = x.min(axis=0), x.max(axis=0)
    extent = float((hi - lo).max()) or 1.0
    shown = [lo, hi]
    if d.speed > 0:
        direction = d.current / np.linalg.norm(d.current)
        centre = (lo + hi) / 2
        tip = centre - direction * (0.5 * float(np.abs(direction) @ (hi - lo)) + 0.05 * extent)
        tail = tip - 0.25 * extent * direction
        ax.quiver(*tail, *(tip - tail), color="tab:blue", linewidth=1.5, arrow_length_ratio=0.3, label=CURRENT)
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


def _legend(ax):
    """The legend of the marks (fixed nodes, lumped masses, current, catch front): the colours of the netting and
    cables are read on their colour bars."""
    marks = (FIXED, MASSES, CURRENT, FRONT)
    shown = [(h, label) for h, label in zip(*ax.get_legend_handles_labels()) if label in marks]
    if shown:
        ax.legend(*zip(*shown), loc="upper left", fontsize=7)


def _colour_bars(fig, axes, d: _Net):
    """The colour bars of the tensions drawn (twine, then bar), beside ``axes``."""
    from matplotlib.cm import ScalarMappable

    bars = []
    if len(d.triangles):
        bars.append(fig.colorbar(ScalarMappable(d.twine_scale, TWINE_COLOURS), ax=axes, label=TWINE_LABEL,
                                 shrink=0.8))
    if len(d.bars):
        bars.append(fig.colorbar(ScalarMappable(d.bar_scale, BAR_COLOURS), ax=axes, label=BAR_LABEL, shrink=0.8))
    for bar in bars:   # a tension read as 57858.2 N, not as 0.2 above an offset of 5.7858e4
        bar.ax.yaxis.get_major_formatter().set_useOffset(False)
    return bars


def plot_net(scene, x, ax=None, title=None, *, twine_tension=None, bar_tension=None, catch_front=None,
             colorbar=True):
    """Draw the net at positions x (N, 3) (m) on a 3D matplotlib axis (created if None); returns the axis.

    twine_tension: (E, 2) U and V twine tensions (N) of the netting triangles, bar_tension: (B,) bar tensions
    (N); by default :func:`jaxnet.figures.twine_tensions` and :func:`jaxnet.figures.bar_tensions` at x.
    catch_front: the catch front's position (m) along ``scene.catch.axis`` (result.json's ``catch.front_m``),
    drawn where the scene has a catch. colorbar: add the tensions' colour bars beside the axis.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig = plt.figure(figsize=(8, 6))
        ax = fig.add_subplot(projection="3d")
    d = _prepare(scene, x, twine_tension, bar_tension, catch_front)
    _draw_3d(ax, d, view_directions(scene)[2])
    if colorbar:
        _colour_bars(ax.figure, ax, d)
    if title:
        ax.set_title(title)
    _legend(ax)
    return ax


# -- the 2D views ------------------------------------------------------------------------------------------------

def _draw_2d(ax, d: _Net, right, vertical, toward, description):
    """The net projected on the plane (right, vertical) (unit vectors, m along each) on the 2D axis ``ax``, seen
    looking along ``toward`` (= vertical × right): the far side drawn first, so that the near side covers it."""
    from matplotlib.collections import LineCollection, PolyCollection

    basis = np.stack([right, vertical])

    def flat(corners):
        return corners @ basis.T

    if len(d.triangles):
        order = np.argsort(-(d.triangles.mean(axis=1) @ toward), kind="stable")
        rgba = _colours(TWINE_COLOURS, d.twine_scale, d.twine)
        ax.add_collection(PolyCollection(flat(d.triangles[order]), facecolors=rgba[order], edgecolors=rgba[order],
                                         linewidths=0.3, label=NETTING, zorder=1))
        if d.behind.any():
            ax.add_collection(PolyCollection(flat(d.triangles[d.behind]), facecolors="none", edgecolors=_BEHIND_EDGE,
                                             hatch="///", linewidths=0.0, label=BEHIND, zorder=2))
    if len(d.hexagonal):
        ax.add_collection(PolyCollection(flat(d.hexagonal), facecolors=(0.6, 0.6, 0.6, 0.6), edgecolors=_EDGE,
                                         linewidths=0.3, label=HEXAGONAL, zorder=1))
    if len(d.bars):
        ax.add_collection(LineCollection(flat(d.bars), colors=_colours(BAR_COLOURS, d.bar_scale, d.bar),
                                         linewidths=2.0, label=CABLES, zorder=3))
    if len(d.front):
        ax.add_collection(LineCollection(flat(d.front), colors=_FRONT_COLOUR, linewidths=1.5, label=FRONT, zorder=4))
    if len(d.fixed):
        ax.scatter(*flat(d.fixed).T, s=6, facecolors="none", edgecolors="red", linewidths=0.6, label=FIXED, zorder=5)
    if len(d.masses):
        ax.scatter(*flat(d.masses).T, s=6, marker="s", facecolors="none", edgecolors="k", linewidths=0.6,
                   label=MASSES, zorder=5)
    net = flat(d.points.reshape(-1, 3))
    lo, hi = net.min(axis=0), net.max(axis=0)
    extent = float((hi - lo).max()) or 1.0
    shown = [lo, hi]
    if d.speed > 0:
        flow = flat(d.current / np.linalg.norm(d.current))
        text = f"current {d.speed:g} m/s"
        if np.linalg.norm(flow) > 1e-6:
            flow = flow / np.linalg.norm(flow)
            tip = (lo + hi) / 2 - flow * (0.5 * float(np.abs(flow) @ (hi - lo)) + 0.05 * extent)
            tail = tip - 0.25 * extent * flow
            ax.annotate(text, xy=tip, xytext=tail, color="tab:blue", fontsize=8, ha="center", va="bottom",
                        arrowprops=dict(arrowstyle="-|>", color="tab:blue", lw=1.5), label=CURRENT, zorder=6)
            shown += [tail, tip]
        else:   # the current runs square to the picture: ⊙ coming out of it, ⊗ going in
            toward_viewer = float(np.dot(d.current, toward)) < 0
            at = np.array([lo[0] - 0.1 * extent, hi[1]])
            ax.plot(*at, marker="o", markersize=12, markerfacecolor="none", markeredgecolor="tab:blue", ls="none",
                    label=CURRENT, zorder=6)
            ax.plot(*at, marker="." if toward_viewer else "x", markersize=8 if toward_viewer else 6, color="tab:blue",
                    ls="none", zorder=6)
            ax.annotate(f"{text}, {'toward the viewer' if toward_viewer else 'into the picture'}", xy=at,
                        xytext=(0, 9), textcoords="offset points", color="tab:blue", fontsize=8, ha="left")
            shown += [at]
    ax.update_datalim(np.asarray(shown))
    ax.margins(0.05)
    ax.autoscale_view()
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"{_axis_name(right)} (m){description[0]}")
    ax.set_ylabel(f"{_axis_name(vertical)} (m), up")
    ax.set_title(description[1], fontsize=10)


def _side_view(ax, d: _Net, scene, title=None):
    """The side view: the plane (along, up) of the current and the vertical, seen from the side of -across."""
    along, across, up = view_directions(scene)
    current = ", along the current" if d.speed > 0 else ""
    _draw_2d(ax, d, along, up, across,
             (current, title or f"side view ({_axis_name(along)}–{_axis_name(up)})"))


def _along_view(ax, d: _Net, scene):
    """The view along the current: the plane (across, up), seen from downstream (from +along)."""
    along, across, up = view_directions(scene)
    name = "along the current" if d.speed > 0 else f"along {_axis_name(along)}"
    seen = "downstream" if d.speed > 0 else f"beyond the net along {_axis_name(along)}"
    _draw_2d(ax, d, across, up, -along,
             ("", f"view {name} ({_axis_name(across)}–{_axis_name(up)}), seen from {seen}"))


# -- figures -----------------------------------------------------------------------------------------------------

def net_figure(scene, x, title=None, *, twine_tension=None, bar_tension=None, catch_front=None):
    """The figure of the net at positions x (N, 3) (m): the 3D view and the view along the current above, the
    side view below, the tensions' colour bars on the right (arguments as :func:`plot_net`'s)."""
    import matplotlib.pyplot as plt

    d = _prepare(scene, x, twine_tension, bar_tension, catch_front)
    fig = plt.figure(figsize=(13, 10), layout="constrained")
    fig.get_layout_engine().set(wspace=0.08)  # room for the 3D view's tick labels, which the layout does not see
    grid = fig.add_gridspec(2, 2, height_ratios=(1.2, 1.0))
    ax3 = fig.add_subplot(grid[0, 0], projection="3d")
    front = fig.add_subplot(grid[0, 1])
    side = fig.add_subplot(grid[1, :])
    _draw_3d(ax3, d, view_directions(scene)[2])
    ax3.set_title("3D view", fontsize=10)
    _along_view(front, d, scene)
    _side_view(side, d, scene)
    _colour_bars(fig, [ax3, front, side], d)
    _legend(ax3)
    if title:
        fig.suptitle(title)
    return fig


def save_png(path, scene, x, title=None, *, twine_tension=None, bar_tension=None, catch_front=None):
    """Write the PNG picture of :func:`net_figure` of the net at positions x (N, 3) (m) to ``path``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig = net_figure(scene, x, title, twine_tension=twine_tension, bar_tension=bar_tension, catch_front=catch_front)
    fig.savefig(str(path), dpi=120, bbox_inches="tight")
    plt.close(fig)


def largest_reaction_record(figures) -> int:
    """Index of the record of a run whose total reaction (``figures["reaction_total_N"]``, (R, 3) N) is largest in
    magnitude; the last record when the run holds none."""
    reaction = figures.get("reaction_total_N")
    if reaction is None or len(reaction) == 0:
        return -1
    return int(np.argmax(np.linalg.norm(np.asarray(reaction, dtype=float), axis=1)))


def run_figure(scene, times, positions, figures, title=None):
    """The figure of a run in time: the total reaction on the fixed nodes (its x, y, z components and magnitude,
    N) against time (s), the largest twine and bar tensions (N) against time (the bars' on an axis of their own,
    on the right), and the side view of the net at the record of the largest reaction (the time it is at in its
    title, and marked on the curves).

    times: (R,) s; positions: (R, N, 3) m; figures: name -> (R, ...) as :attr:`jaxnet.solve.dynamics.Trajectory.
    figures` (``reaction_total_N``, ``max_twine_tension_N``, ``max_bar_tension_N``: those present are drawn).
    """
    import matplotlib.pyplot as plt

    times = np.asarray(times, dtype=float)
    positions = np.asarray(positions, dtype=float)
    k = largest_reaction_record(figures) % len(times)
    fig = plt.figure(figsize=(13, 10), layout="constrained")
    grid = fig.add_gridspec(2, 2, height_ratios=(1.0, 1.2))
    forces, tensions, side = fig.add_subplot(grid[0, 0]), fig.add_subplot(grid[0, 1]), fig.add_subplot(grid[1, :])
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
    twine, bar = figures.get("max_twine_tension_N"), figures.get("max_bar_tension_N")
    lines = []
    if twine is not None:
        lines += tensions.plot(times, np.asarray(twine, dtype=float), color="tab:green", label="largest twine tension")
        tensions.set_ylabel("largest twine tension (N)", color="tab:green")
    if bar is not None:
        bars = tensions.twinx() if twine is not None else tensions
        lines += bars.plot(times, np.asarray(bar, dtype=float), color="tab:purple", label="largest bar tension")
        bars.set_ylabel("largest bar tension (N)", color="tab:purple")
    if lines:
        tensions.legend(lines, [line.get_label() for line in lines], fontsize=8)
    tensions.set_xlabel("time (s)")
    tensions.set_title("largest tensions", fontsize=10)
    for ax in (forces, tensions):
        ax.axvline(times[k], color="0.5", ls=":", lw=1.0)
    d = _prepare(scene, positions[k])
    what = "largest total reaction" if reaction is not None else "last record"
    _side_view(side, d, scene, f"side view at t = {times[k]:.6g} s ({what})")
    _colour_bars(fig, [side], d)
    if title:
        fig.suptitle(title)
    return fig


def save_run_png(path, scene, times, positions, figures, title=None):
    """Write the PNG picture of :func:`run_figure` of a run (times (R,) s, positions (R, N, 3) m, figures as
    :attr:`jaxnet.solve.dynamics.Trajectory.figures`) to ``path``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig = run_figure(scene, times, positions, figures, title)
    fig.savefig(str(path), dpi=120, bbox_inches="tight")
    plt.close(fig)
