"""Pictures of a net (jaxnet.io.plot): every twine line has the colour of its own twine's tension under the colour
bar, whose top is the largest twine tension; views at equal scale covering the whole (mirrored) net, or the
netting where cables reach far beyond it; what holds the net (fixings, holds in some axes, floats, sinkers) with
its values; axes named in words for a current along no coordinate axis; the current's arrow, the catch front, and
the picture of a run at its largest reaction without curves of what is zero throughout.

The cod-end is the small quarter model codend(meshes_around=8, meshes_along=4) (11 nodes, 10 triangles, 2 bars,
two symmetry planes: 4 copies) at its start positions: no solve, the tensions are given where their values
matter.
"""

import importlib

import matplotlib

matplotlib.use("Agg")

import equinox as eqx
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.colors import LogNorm, Normalize
from matplotlib.path import Path

import jaxnet  # noqa: F401  (float64)
from jaxnet import figures, geometry, scene as scene_lib
from jaxnet.io import plot
from jaxnet.net import Net, Rope, Twine


@pytest.fixture(scope="module")
def codend():
    return importlib.import_module("jaxnet.scenes.codend").codend(meshes_around=8, meshes_along=4).scene


@pytest.fixture
def tensions(codend):
    """Twine (E, 2) and bar (B,) tensions (N), distinct per element and per family (the start shape's are all
    zero); the U and V tensions of a triangle differ, so that their mean is no twine's tension."""
    rng = np.random.default_rng(3)
    e, b = codend.netting.vertices.shape[0], codend.bars.ends.shape[0]
    return rng.uniform(0.5, 40.0, (e, 2)), rng.uniform(100.0, 900.0, b)


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def x0(scene):
    return np.asarray(scene.nodes.position, dtype=float)


def artist(ax, gid):
    """The one artist named ``gid`` on ``ax`` (collections, lines, texts, patches, artists)."""
    found = [a for a in ax.get_children() if a.get_gid() == gid]
    assert len(found) == 1, f"{gid!r}: {len(found)} artists"
    return found[0]


def artists(ax, gid):
    return [a for a in ax.get_children() if a.get_gid() == gid]


def views(fig):
    """(3D view, view along the current, side view) of :func:`plot.net_figure`, by their labels."""
    by_label = {ax.get_label(): ax for ax in fig.axes}
    return by_label[plot.VIEW_3D], by_label[plot.VIEW_ALONG], by_label[plot.VIEW_SIDE]


def colour_bar(fig, label):
    found = [ax for ax in fig.axes if ax.get_label() == "<colorbar>" and ax.get_ylabel() == label]
    assert len(found) == 1
    return found[0]


def test_twine_lines_are_coloured_by_their_own_tension_under_the_colour_bar(codend, tensions):
    twine, bar = tensions
    assert np.all(twine[:, 0] != twine[:, 1])
    fig = plot.net_figure(codend, x0(codend), "cod-end", twine_tension=twine, bar_tension=bar)
    ax3, along, side = views(fig)
    # the bar's top is the largest twine tension (result.json's), not the largest mean of a triangle's two
    top = twine.max()
    assert twine.mean(axis=1).max() < top
    cax = colour_bar(fig, plot.TWINE_LABEL)
    assert cax.get_yscale() == "log"
    np.testing.assert_allclose(cax.get_ylim()[1], top, rtol=1e-12)
    # its bottom: the 5th percentile of the tensions within 3 decades (here all of them), at least a decade down
    np.testing.assert_allclose(cax.get_ylim()[0], min(np.percentile(twine, 5.0), top / 10), rtol=1e-12)
    bax = colour_bar(fig, plot.BAR_LABEL)
    np.testing.assert_allclose(bax.get_ylim(), (bar.min(), bar.max()), rtol=1e-12)

    # every drawn triangle's U and V lines have the colours of its own U and V tensions, in every copy
    scale = LogNorm(*cax.get_ylim())
    colours = matplotlib.colormaps[plot.TWINE_COLOURS](scale(twine))                      # (E, 2, 4)
    points = scene_lib.mirrored(codend, x0(codend))
    copies, tri = points.shape[0], np.asarray(codend.netting.vertices)
    for ax in (ax3, along, side):
        netting = artist(ax, plot.NETTING)
        assert isinstance(netting, plot.NettingArtist)
        assert len(netting.order) == copies * len(tri) == 40
        np.testing.assert_allclose(netting.colours, colours[netting.order % len(tri)], atol=1e-12)
    # the lines lie along their triangle's twines (in the side view's x-z plane), inside the triangle
    netting = artist(side, plot.NETTING)
    for k, i in enumerate(netting.order):
        c, e = divmod(int(i), len(tri))
        corners = points[c][tri[e]]
        U, V, _ = geometry.twine_vectors(corners, np.asarray(codend.netting.uv)[e])
        centroid = corners.mean(axis=0)[[0, 2]]
        for f, twine_vector in enumerate((np.asarray(U)[[0, 2]], np.asarray(V)[[0, 2]])):
            a, b = netting.twines[k, f]
            np.testing.assert_allclose((a + b) / 2, centroid, atol=1e-12)
            if np.linalg.norm(twine_vector) > 1e-9 and np.linalg.norm(b - a) > 1e-9:
                (p, q), (r, t) = b - a, twine_vector
                assert abs(p * t - q * r) < 1e-9 * np.linalg.norm(b - a) * np.linalg.norm(twine_vector)
            drawn = Path(netting.triangles[k])
            assert drawn.contains_point(a, radius=1e-9) or np.allclose(a, centroid)

    # the cables: the bar colour map under the bar colour bar's scale, repeated in every copy
    cables = artist(side, plot.CABLES)
    bar_rgba = matplotlib.colormaps[plot.BAR_COLOURS](Normalize(bar.min(), bar.max())(bar))
    np.testing.assert_allclose(cables.get_color(), np.tile(bar_rgba, (copies, 1)), atol=1e-12)
    np.testing.assert_allclose([s[:, 0] for s in cables.get_segments()],
                               points[:, np.asarray(codend.bars.ends)].reshape(-1, 2, 3)[:, :, 0], atol=1e-12)
    # the picture says what the colours are
    assert any("U and V twines of every triangle drawn apart" in t.get_text() and "log scale" in t.get_text()
               for t in fig.texts)


def test_the_colour_bar_top_is_the_largest_twine_tension_of_the_positions(codend):
    x = x0(codend).copy()
    x[:, 0] *= 1.0 + x[:, 0] / x[:, 0].max()          # stretched more toward the rear: different tensions
    twine, bar = figures.twine_tensions(codend, x), figures.bar_tensions(codend, x)
    assert np.ptp(twine) > 1.0 and np.ptp(bar) == 0.0   # the two bars of the cod line pull alike
    fig = plot.net_figure(codend, x)
    assert colour_bar(fig, plot.TWINE_LABEL).get_ylim()[1] == pytest.approx(twine.max(), rel=1e-12)
    # equal tensions: a scale 1 N wide from theirs
    np.testing.assert_allclose(colour_bar(fig, plot.BAR_LABEL).get_ylim(), (bar[0], bar[0] + 1.0), rtol=1e-12)
    # a net at rest: no tension to scale by, a linear scale 1 N wide
    rest = plot.net_figure(codend, x0(codend), twine_tension=np.zeros((10, 2)), bar_tension=np.zeros(2))
    np.testing.assert_allclose(colour_bar(rest, plot.TWINE_LABEL).get_ylim(), (0.0, 1.0))


def test_the_twine_scale_spends_its_colours_on_the_tensions_carried():
    rng = np.random.default_rng(11)
    slack_and_loaded = np.concatenate([np.zeros(300), rng.uniform(0.2, 50.0, 700), [120.0]])
    scale = plot.twine_scale(slack_and_loaded)
    within = slack_and_loaded[slack_and_loaded > 0.12]
    assert scale.vmax == 120.0 and scale.vmin == pytest.approx(np.percentile(within, 5.0), rel=1e-12)
    alike = rng.uniform(20.0, 25.0, 1000)              # all loaded alike: still a decade of colours
    assert plot.twine_scale(alike).vmin == pytest.approx(alike.max() / 10.0, rel=1e-12)
    assert plot.twine_scale(np.full(10, 1e-9)).vmax == 1.0


def test_views_are_at_equal_scale_and_cover_the_whole_mirrored_net(codend, tensions):
    fig = plot.net_figure(codend, x0(codend), twine_tension=tensions[0], bar_tension=tensions[1])
    fig.canvas.draw()
    ax3, along, side = views(fig)
    whole = scene_lib.mirrored(codend, x0(codend)).reshape(-1, 3)
    lo, hi = whole.min(axis=0), whole.max(axis=0)
    # the quarter lies at y, z >= 0: the whole net spans y and z symmetric about the planes y = 0, z = 0
    assert x0(codend)[:, 1:].min() >= 0.0 and hi[1] > 0.0
    np.testing.assert_allclose(lo[1:], -hi[1:], atol=1e-15)
    for ax, (i, j) in ((side, (0, 2)), (along, (1, 2))):
        assert ax.get_aspect() == 1.0
        pixels = ax.transData.transform([[0.0, 0.0], [1.0, 1.0]])
        dx, dy = pixels[1] - pixels[0]
        assert dx == pytest.approx(dy, rel=1e-9)           # one metre is as long across as up
        (x_lo, x_hi), (y_lo, y_hi) = ax.get_xlim(), ax.get_ylim()
        assert x_lo <= lo[i] and x_hi >= hi[i] and y_lo <= lo[j] and y_hi >= hi[j]
    # the 3D view: an oblique projection at equal scale too, covering every copy
    right, vertical, toward = plot.oblique_directions(codend)
    np.testing.assert_allclose([right @ vertical, right @ toward, vertical @ toward], 0.0, atol=1e-15)
    seen = whole @ np.stack([right, vertical]).T
    pixels = ax3.transData.transform([[0.0, 0.0], [1.0, 1.0]])
    assert (pixels[1] - pixels[0])[0] == pytest.approx((pixels[1] - pixels[0])[1], rel=1e-9)
    (x_lo, x_hi), (y_lo, y_hi) = ax3.get_xlim(), ax3.get_ylim()
    assert x_lo <= seen[:, 0].min() and x_hi >= seen[:, 0].max() and y_lo <= seen[:, 1].min() <= y_hi


def test_fixed_nodes_are_the_front_not_the_symmetry_planes(codend):
    fixed = np.asarray(codend.nodes.fixed)
    held = plot.held_nodes(codend)
    np.testing.assert_array_equal(held, fixed.all(axis=1))
    assert held.sum() == 3 and fixed.any(axis=1).sum() == 9
    fig = plot.net_figure(codend, x0(codend), twine_tension=np.ones((10, 2)), bar_tension=np.ones(2))
    ax3, along, side = views(fig)
    front = scene_lib.mirrored(codend, x0(codend))[:, held].reshape(-1, 3)
    distinct = np.unique(np.round(front, 12), axis=0)
    assert len(distinct) == 8                              # the whole cod-end's front ring, each node once
    markers = artist(side, plot.FIXED)
    offsets = markers.get_offsets()
    assert len(offsets) == len(distinct)
    np.testing.assert_allclose(offsets[:, 0], 0.0, atol=1e-15)   # all at the front, x = 0
    np.testing.assert_allclose(np.sort(offsets[:, 1]), np.sort(distinct[:, 2]), atol=1e-12)
    assert len(markers.get_facecolor()) == 0 and len(markers.get_edgecolor()) > 0   # hollow: rings only
    assert np.all(markers.get_sizes() <= 10.0)                                      # small
    assert markers.get_label() == "fixed (held in x, y, z)"
    assert len(artist(along, plot.FIXED).get_offsets()) == len(distinct)
    assert not artists(side, plot.HELD)                       # the symmetry planes' holds are no fixings


def test_a_node_held_in_some_axes_is_marked_apart_with_its_axes(codend):
    fixed = np.asarray(codend.nodes.fixed).copy()
    fixed[10] = (True, True, False)                        # off both planes: a hold, not a symmetry's
    held_xy = eqx.tree_at(lambda s: s.nodes.fixed, codend, fixed)
    np.testing.assert_array_equal(plot.held_axes(held_xy)[10], [True, True, False])
    _, _, side = views(plot.net_figure(held_xy, x0(held_xy), twine_tension=np.ones((10, 2)),
                                       bar_tension=np.ones(2)))
    partial = artist(side, plot.HELD)
    assert partial.get_label() == "held in x, y only"
    at = scene_lib.mirrored(held_xy, x0(held_xy))[:, 10][:, [0, 2]]
    drawn = np.asarray(partial.get_offsets())
    assert len(drawn) == 4 and all(np.any(np.all(np.isclose(drawn, p, atol=1e-12), axis=1)) for p in at)
    full = artist(side, plot.FIXED).get_offsets()
    assert not np.any(np.all(np.isclose(full[:, None], at[None], atol=1e-12), axis=2))   # not as fixed
    assert partial.get_paths()[0] != artist(side, plot.FIXED).get_paths()[0]          # another marker
    ax3 = views(plot.net_figure(held_xy, x0(held_xy), twine_tension=np.ones((10, 2)), bar_tension=np.ones(2)))[0]
    legend = [t.get_text() for t in ax3.get_legend().get_texts()]
    assert "held in x, y only" in legend and "fixed (held in x, y, z)" in legend


def test_the_cage_collar_is_held_in_x_and_y_and_its_sinkers_are_drawn_with_their_mass():
    scene = importlib.import_module("jaxnet.scenes.cage").fish_cage().scene
    e, b = scene.netting.vertices.shape[0], scene.bars.ends.shape[0]
    fig = plot.net_figure(scene, x0(scene), twine_tension=np.ones((e, 2)), bar_tension=np.ones(b))
    ax3, along, side = views(fig)
    collar = artist(side, plot.HELD)
    assert collar.get_label() == "held in x, y only" and not artists(side, plot.FIXED)
    sinkers = artist(side, plot.SINKERS)
    assert sinkers.get_label() == "8 sinkers, 20 kg each (mass)"
    np.testing.assert_allclose(np.asarray(sinkers.get_offsets())[:, 1], -5.0, atol=1e-9)   # at the wall's foot
    legend = [t.get_text() for t in ax3.get_legend().get_texts()]
    assert legend == ["held in x, y only", "8 sinkers, 20 kg each (mass)"]


def test_floats_and_sinkers_are_drawn_with_their_buoyancy_and_mass(codend):
    env = codend.environment
    volume, mass = np.zeros(11), np.zeros(11)
    volume[10] = 20.0 / (env.water_density * env.gravity)            # a float of 20 N, off both planes
    mass[7], volume[7] = 3.0, 3.0 / 11340.0                          # a 3 kg lead sinker
    weighted = eqx.tree_at(lambda s: (s.nodes.volume, s.nodes.mass), codend, (volume, mass))
    floats, lift, sinkers, kg = plot.floats_and_sinkers(weighted)
    assert np.flatnonzero(floats).tolist() == [10] and np.flatnonzero(sinkers).tolist() == [7]
    assert lift[10] == pytest.approx(20.0, rel=1e-12) and kg[7] == 3.0
    _, along, side = views(plot.net_figure(weighted, x0(weighted), twine_tension=np.ones((10, 2)),
                                           bar_tension=np.ones(2)))
    assert artist(side, plot.FLOATS).get_label() == "4 floats, 20 N each (net buoyancy)"
    assert artist(side, plot.SINKERS).get_label() == "4 sinkers, 3 kg each (mass)"
    assert len(artist(along, plot.FLOATS).get_offsets()) == 4                # every copy's
    # floats of different buoyancy: each value written beside its float (at most LABELLED of them)
    volume[7], mass[7] = 5.0 / (env.water_density * env.gravity), 0.0
    two = eqx.tree_at(lambda s: (s.nodes.volume, s.nodes.mass), codend, (volume, mass))
    _, _, side = views(plot.net_figure(two, x0(two), twine_tension=np.ones((10, 2)), bar_tension=np.ones(2)))
    assert artist(side, plot.FLOATS).get_label() == "8 floats, 5–20 N (net buoyancy)"
    written = {t.get_text() for t in side.texts}
    assert {"5 N", "20 N"} <= written


def moored_panel(cable_m):
    """A hanging panel 1.4 m wide, its top corners held, moored from a bottom corner by a cable ``cable_m`` long
    (m) to an anchor held upstream; a current along (0.94, 0.34, 0)."""
    net = Net()
    twine = Twine(l0=0.1, ea=2000.0, diameter=1.5e-3, density=1140.0)
    w = 10 * 0.1 * np.sqrt(2.0)
    panel = net.panel("netting", [(0, 0, -w, 0, 0), (w, 0, -w, 10, -10), (w, 0, 0, 20, 0), (0, 0, 0, 10, 10)],
                      twine, 0.35)
    net.fix(panel.corner(2))
    net.fix(panel.corner(3))
    if cable_m:
        net.cable("mooring", start=panel.corner(0), end=(-cable_m, 0.0, -w), rope=Rope(ea=1e5, diameter=0.01),
                  n_bars=4)
        net.fix((-cable_m, 0.0, -w))
    scene = net.build()
    return eqx.tree_at(lambda s: (s.environment.current_speed, s.environment.current_direction), scene,
                       (1.0, np.array([0.94, 0.34, 0.0]) / np.hypot(0.94, 0.34)))


def test_cables_far_beyond_the_netting_get_views_zoomed_on_the_netting():
    scene = moored_panel(50.0)
    x = x0(scene)
    fig = plot.net_figure(scene, x, twine_tension=np.ones((scene.netting.vertices.shape[0], 2)))
    ax3, along, side = views(fig)
    netting = np.unique(np.asarray(scene.netting.vertices))
    lo, hi = x[netting].min(axis=0), x[netting].max(axis=0)
    along_x, across, up = plot.view_directions(scene)
    for ax, plane in ((side, (along_x, up)), (along, (across, up))):
        corners = np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]] for i in (0, 1) for j in (0, 1)
                            for k in (0, 1)]) @ np.stack(plane).T
        (x_lo, x_hi), (y_lo, y_hi) = ax.get_xlim(), ax.get_ylim()
        assert x_lo <= corners[:, 0].min() and corners[:, 0].max() <= x_hi        # the netting is in view
        assert y_lo <= corners[:, 1].min() and corners[:, 1].max() <= y_hi
        assert x_hi - x_lo < 0.2 * 50.0                                            # the cable is not
        assert "zoomed on the netting" in ax.get_title()
    whole = next(ax for ax in fig.axes if ax.get_label() == plot.VIEW_WHOLE)
    assert np.ptp(whole.get_xlim()) > 50.0 * 0.94 and artist(whole, plot.ZOOMED) is not None
    # the same panel without its mooring: one side view of everything
    alone = plot.net_figure(moored_panel(0.0), x0(moored_panel(0.0)),
                            twine_tension=np.ones((scene.netting.vertices.shape[0], 2)))
    assert plot.VIEW_WHOLE not in [ax.get_label() for ax in alone.axes]
    assert "zoomed" not in views(alone)[2].get_title()


def test_a_current_along_no_axis_names_the_axes_in_words_with_its_heading():
    scene = moored_panel(0.0)
    fig = plot.net_figure(scene, x0(scene), twine_tension=np.ones((scene.netting.vertices.shape[0], 2)))
    _, along, side = views(fig)
    labels = [side.get_xlabel(), side.get_ylabel(), along.get_xlabel(), along.get_ylabel()]
    assert labels == ["along the current (m)", "z (m), up", "across the current (m)", "z (m), up"]
    assert not any("(0.9" in label or "0.34" in label for label in labels)
    assert "the current heading 20° from x toward y" in side.get_title()     # atan2(0.34, 0.94) = 19.9°
    assert plot.heading(np.array([0.0, -1.0, 0.0]), np.array([0.0, 0.0, 1.0])) == "-y"


def test_current_arrow_is_along_the_current_with_its_speed(codend):
    direction = np.array([0.8, 0.0, -0.6])                 # downstream and down
    tilted = eqx.tree_at(lambda s: s.environment.current_direction, codend, direction)
    fig = plot.net_figure(tilted, x0(tilted), twine_tension=np.ones((10, 2)), bar_tension=np.ones(2))
    _, along, side = views(fig)
    for ax, drawn in ((side, direction[[0, 2]]), (along, direction[[1, 2]])):
        arrow = artist(ax, plot.CURRENT)
        assert "1.5 m/s" in arrow.get_text()
        shaft = np.asarray(arrow.xy) - np.asarray(arrow.xyann)
        np.testing.assert_allclose(shaft / np.linalg.norm(shaft), drawn / np.linalg.norm(drawn), atol=1e-12)
    along_x, across, up = plot.view_directions(tilted)
    np.testing.assert_allclose(along_x, [1.0, 0.0, 0.0], atol=1e-15)
    np.testing.assert_allclose(across, [0.0, 1.0, 0.0], atol=1e-15)
    # a current along x is square to the view along it: marked there, not drawn as an arrow
    fig = plot.net_figure(codend, x0(codend), twine_tension=np.ones((10, 2)), bar_tension=np.ones(2))
    _, along, _ = views(fig)
    assert not [t for t in along.texts if t.get_gid() == plot.CURRENT]
    assert artist(along, plot.CURRENT).get_xydata().shape == (1, 2)
    # no current: the views fall back to x, and nothing marks a current
    still = eqx.tree_at(lambda s: (s.environment.current_speed, s.environment.current_direction), codend,
                        (0.0, np.array([0.0, 1.0, 0.0])))
    np.testing.assert_allclose(plot.view_directions(still)[0], [1.0, 0.0, 0.0])
    _, along, side = views(plot.net_figure(still, x0(still), twine_tension=np.ones((10, 2)), bar_tension=np.ones(2)))
    assert not artists(along, plot.CURRENT) and not artists(side, plot.CURRENT)


def test_catch_front_is_drawn_where_it_is_and_the_netting_behind_marked(codend):
    front = 0.25                                           # m along the cod-end's axis (x), mid-length
    np.testing.assert_allclose(codend.catch.axis, [1.0, 0.0, 0.0])
    x = x0(codend)
    fig = plot.net_figure(codend, x, twine_tension=np.ones((10, 2)), bar_tension=np.ones(2), catch_front=front)
    _, along, side = views(fig)
    cut = np.asarray(artist(side, plot.FRONT).get_segments())
    assert len(cut) > 0
    np.testing.assert_allclose(cut[:, :, 0], front, atol=1e-12)
    z = cut[:, :, 1]
    assert z.max() > 0.0 and z.min() == pytest.approx(-z.max(), abs=1e-15)   # across the whole net
    tri = np.asarray(codend.netting.vertices)
    behind = (x[tri][:, :, 0] > front).any(axis=1)
    assert 0 < behind.sum() < len(tri)
    hatched = artist(side, plot.BEHIND)
    assert np.sum(hatched.get_path().codes == Path.MOVETO) == 4 * behind.sum()   # one polygon a triangle
    assert hatched.get_hatch()
    ring = np.asarray(artist(along, plot.FRONT).get_segments())   # seen along the axis: the front's ring
    np.testing.assert_allclose(np.abs(ring).max(axis=(0, 1)), np.abs(z).max(), rtol=1e-9)
    # without its position the front is not drawn
    _, along, side = views(plot.net_figure(codend, x, twine_tension=np.ones((10, 2)), bar_tension=np.ones(2)))
    assert not artists(side, plot.FRONT) and not artists(side, plot.BEHIND)


def test_plot_net_draws_every_copy_on_the_given_axis(codend, tensions):
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    assert plot.plot_net(codend, x0(codend), ax=ax, title="quarter", twine_tension=tensions[0],
                         bar_tension=tensions[1]) is ax
    fig.canvas.draw()
    assert len(artist(ax, plot.NETTING).get_facecolor()) == 4 * 10 * 3     # each triangle, its U and V lines
    assert len(artist(ax, plot.CABLES).get_segments()) == 4 * 2
    assert ax.get_title() == "quarter"
    assert colour_bar(fig, plot.TWINE_LABEL).get_ylim()[1] == pytest.approx(tensions[0].max(), rel=1e-12)


def test_save_png_writes_a_picture_called_as_the_command_line_does(codend, tmp_path):
    plot.save_png(tmp_path / "net.png", codend, x0(codend), "cod-end", catch_front=0.25)
    assert (tmp_path / "net.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not plt.get_fignums()                           # no pyplot figure left open


def synthetic_run(scene, bar_tension=None):
    """Records of a made-up run: 7 records, the net moved 0.1 m downstream per record, the total reaction
    largest in magnitude at record 4 (not at the largest component's record)."""
    times = np.linspace(0.0, 0.6, 7)
    positions = np.stack([x0(scene) + [0.1 * k, 0.0, 0.0] for k in range(7)])
    reaction = np.array([[10.0, 0, 0], [-20, 5, 0], [30, 0, 0], [0, 0, -5], [25, 25, 10], [31, 0, 0], [0, 1, 0]])
    assert np.argmax(np.abs(reaction).max(axis=1)) == 5 and np.argmax(np.linalg.norm(reaction, axis=1)) == 4
    return times, positions, {"reaction_total_N": reaction, "max_twine_tension_N": np.arange(7.0) ** 2,
                              "max_bar_tension_N": 100.0 + np.arange(7.0) if bar_tension is None else bar_tension,
                              "steps": np.arange(7)}


def test_run_figure_plots_the_series_and_the_net_at_the_largest_reaction(codend, tmp_path):
    times, positions, series = synthetic_run(codend)
    assert plot.largest_reaction_record(series) == 4
    fig = plot.run_figure(codend, times, positions, series, "a run")
    forces, tensions, side = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"][:3]
    by_label = {line.get_label(): line for line in forces.lines}
    reaction = series["reaction_total_N"]
    for c, name in enumerate("xyz"):
        np.testing.assert_array_equal(by_label[f"R{name}"].get_xdata(), times)
        np.testing.assert_array_equal(by_label[f"R{name}"].get_ydata(), reaction[:, c])
    np.testing.assert_allclose(by_label["|R|"].get_ydata(), np.linalg.norm(reaction, axis=1), rtol=1e-15)
    lines = {line.get_label(): line for ax in fig.axes for line in ax.lines}
    np.testing.assert_array_equal(lines["largest twine tension"].get_ydata(), series["max_twine_tension_N"])
    np.testing.assert_array_equal(lines["largest bar tension"].get_ydata(), series["max_bar_tension_N"])
    assert "t = 0.4 s" in side.get_title()
    drawn = artist(side, plot.NETTING).triangles.reshape(-1, 2)
    at = scene_lib.mirrored(codend, positions[4]).reshape(-1, 3)
    np.testing.assert_allclose([drawn[:, 0].min(), drawn[:, 0].max()], [at[:, 0].min(), at[:, 0].max()], atol=1e-12)
    marks = [line for ax in (forces, tensions) for line in ax.lines if line.get_label().startswith("_")]
    assert any(np.allclose(line.get_xdata(), times[4]) for line in marks)   # the snapshot's time on the curves
    plot.save_run_png(tmp_path / "run.png", codend, times, positions, series, title="a run")
    assert (tmp_path / "run.png").read_bytes()[:4] == b"\x89PNG"


def test_a_tension_zero_throughout_is_no_curve(codend):
    times, positions, series = synthetic_run(codend, bar_tension=np.zeros(7))   # no bar under tension
    fig = plot.run_figure(codend, times, positions, series)
    labels = [line.get_label() for ax in fig.axes for line in ax.lines]
    assert "largest twine tension" in labels and "largest bar tension" not in labels
    assert not [ax for ax in fig.axes if ax.get_ylabel() == "largest bar tension (N)"]
