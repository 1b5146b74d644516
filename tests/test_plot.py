"""Pictures of a net (jaxnet.io.plot): colours are the tensions under the colour bar's scale, views at equal scale
covering the whole (mirrored) net, fixed nodes without the symmetry planes' holds, the current's arrow along the
current, the catch front where it is, and the picture of a run at its largest reaction.

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
from matplotlib.colors import Normalize

import jaxnet  # noqa: F401  (float64)
from jaxnet import figures, scene as scene_lib
from jaxnet.io import plot


@pytest.fixture(scope="module")
def codend():
    return importlib.import_module("jaxnet.scenes.codend").codend(meshes_around=8, meshes_along=4).scene


@pytest.fixture(scope="module")
def tensions(codend):
    """Twine (E, 2) and bar (B,) tensions (N), distinct per element: the start shape's are all zero."""
    rng = np.random.default_rng(3)
    e, b = codend.netting.vertices.shape[0], codend.bars.ends.shape[0]
    return rng.uniform(0.5, 40.0, (e, 2)), rng.uniform(100.0, 900.0, b)


@pytest.fixture(autouse=True)
def close_figures():
    yield
    plt.close("all")


def x0(scene):
    return np.asarray(scene.nodes.position, dtype=float)


def artist(ax, label):
    """The one artist labelled ``label`` on ``ax`` (collections, lines, texts)."""
    found = [a for a in ax.collections + ax.lines + ax.texts if a.get_label() == label]
    assert len(found) == 1, f"{label!r}: {len(found)} artists"
    return found[0]


def views(fig):
    """(3D axis, view along the current, side view) of :func:`plot.net_figure`."""
    ax3, along, side = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert ax3.name == "3d" and along.name == "rectilinear" and side.name == "rectilinear"
    return ax3, along, side


def colour_bar(fig, label):
    found = [ax for ax in fig.axes if ax.get_label() == "<colorbar>" and ax.get_ylabel() == label]
    assert len(found) == 1
    return found[0]


def test_netting_and_cables_are_coloured_by_their_tensions_under_the_colour_bars(codend, tensions):
    twine, bar = tensions
    fig = plot.net_figure(codend, x0(codend), "cod-end", twine_tension=twine, bar_tension=bar)
    ax3, along, side = views(fig)
    mean = twine.mean(axis=1)
    cax = colour_bar(fig, "twine tension (N)")
    np.testing.assert_allclose(cax.get_ylim(), (mean.min(), mean.max()), rtol=1e-12)
    bax = colour_bar(fig, "bar tension (N)")
    np.testing.assert_allclose(bax.get_ylim(), (bar.min(), bar.max()), rtol=1e-12)

    # each drawn triangle of the side view (x, z) has the colour of its triangle's tension, in every copy
    expected = matplotlib.colormaps[plot.TWINE_COLOURS](Normalize(mean.min(), mean.max())(mean))
    points = scene_lib.mirrored(codend, x0(codend))
    copies, tri = points.shape[0], np.asarray(codend.netting.vertices)
    colour_of = {}
    for c in range(copies):
        for k, t in enumerate(tri):
            key = tuple(np.round(points[c][t][:, [0, 2]], 12).ravel())
            colour_of.setdefault(key, set()).add(tuple(expected[k]))
    netting = artist(side, plot.NETTING)
    paths, faces = netting.get_paths(), netting.get_facecolor()
    assert len(paths) == len(faces) == copies * len(tri) == 40
    for path, face in zip(paths, faces):
        key = tuple(np.round(path.vertices[:3], 12).ravel())
        assert len(colour_of[key]) == 1                  # the mirrored copies repeat the tensions
        np.testing.assert_allclose(face, next(iter(colour_of[key])), atol=1e-12)

    # the cables: the bar colour map under the bar colour bar's scale, repeated in every copy
    cables = artist(side, plot.CABLES)
    bar_rgba = matplotlib.colormaps[plot.BAR_COLOURS](Normalize(bar.min(), bar.max())(bar))
    np.testing.assert_allclose(cables.get_color(), np.tile(bar_rgba, (copies, 1)), atol=1e-12)
    np.testing.assert_allclose([s[:, 0] for s in cables.get_segments()],
                               points[:, np.asarray(codend.bars.ends)].reshape(-1, 2, 3)[:, :, 0], atol=1e-12)
    # every copy's triangles in every view
    assert len(artist(along, plot.NETTING).get_paths()) == copies * len(tri)
    assert len(artist(ax3, plot.NETTING).get_facecolor()) == copies * len(tri)


def test_tensions_default_to_the_figures_of_the_positions(codend):
    x = x0(codend).copy()
    x[:, 0] *= 1.0 + x[:, 0] / x[:, 0].max()          # stretched more toward the rear: different tensions
    twine, bar = figures.twine_tensions(codend, x), figures.bar_tensions(codend, x)
    assert np.ptp(twine.mean(axis=1)) > 1.0 and np.ptp(bar) == 0.0   # the two bars of the cod line pull alike
    fig = plot.net_figure(codend, x)
    np.testing.assert_allclose(colour_bar(fig, "twine tension (N)").get_ylim(),
                               (twine.mean(axis=1).min(), twine.mean(axis=1).max()), rtol=1e-12)
    # equal tensions: a scale 1 N wide from theirs
    np.testing.assert_allclose(colour_bar(fig, "bar tension (N)").get_ylim(), (bar[0], bar[0] + 1.0), rtol=1e-12)


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
    spans = [np.ptp(lim) for lim in (ax3.get_xlim(), ax3.get_ylim(), ax3.get_zlim())]
    np.testing.assert_allclose(spans, spans[0], rtol=1e-9)
    assert spans[0] >= (hi - lo).max()


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
    assert len(artist(along, plot.FIXED).get_offsets()) == len(distinct)


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
    assert not [t for t in along.texts if t.get_label() == plot.CURRENT]
    assert artist(along, plot.CURRENT).get_xydata().shape == (1, 2)
    # no current: the views fall back to x, and nothing marks a current
    still = eqx.tree_at(lambda s: (s.environment.current_speed, s.environment.current_direction), codend,
                        (0.0, np.array([0.0, 1.0, 0.0])))
    np.testing.assert_allclose(plot.view_directions(still)[0], [1.0, 0.0, 0.0])
    _, along, side = views(plot.net_figure(still, x0(still), twine_tension=np.ones((10, 2)), bar_tension=np.ones(2)))
    assert not [a for ax in (along, side) for a in ax.lines + ax.texts if a.get_label() == plot.CURRENT]


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
    assert len(artist(side, plot.BEHIND).get_paths()) == 4 * behind.sum()
    assert artist(side, plot.BEHIND).get_hatch()
    ring = np.asarray(artist(along, plot.FRONT).get_segments())   # seen along the axis: the front's ring
    np.testing.assert_allclose(np.abs(ring).max(axis=(0, 1)), np.abs(z).max(), rtol=1e-9)
    # without its position the front is not drawn
    _, along, side = views(plot.net_figure(codend, x, twine_tension=np.ones((10, 2)), bar_tension=np.ones(2)))
    assert not [a for a in side.collections if a.get_label() in (plot.FRONT, plot.BEHIND)]


def test_plot_net_draws_every_copy_on_the_given_axis(codend, tensions):
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    assert plot.plot_net(codend, x0(codend), ax=ax, title="quarter", twine_tension=tensions[0],
                         bar_tension=tensions[1]) is ax
    fig.canvas.draw()
    assert len(artist(ax, plot.NETTING).get_facecolor()) == 4 * 10
    assert len(artist(ax, plot.CABLES).get_segments()) == 4 * 2
    assert ax.get_title() == "quarter"
    assert colour_bar(fig, "twine tension (N)") is not None


def test_save_png_writes_a_picture_called_as_the_command_line_does(codend, tensions, tmp_path):
    plot.save_png(tmp_path / "net.png", codend, x0(codend), "cod-end", catch_front=0.25)
    assert (tmp_path / "net.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert not plt.get_fignums()                           # the figure is closed


def synthetic_run(scene):
    """Records of a made-up run: 7 records, the net moved 0.1 m downstream per record, the total reaction
    largest in magnitude at record 4 (not at the largest component's record)."""
    times = np.linspace(0.0, 0.6, 7)
    positions = np.stack([x0(scene) + [0.1 * k, 0.0, 0.0] for k in range(7)])
    reaction = np.array([[10.0, 0, 0], [-20, 5, 0], [30, 0, 0], [0, 0, -5], [25, 25, 10], [31, 0, 0], [0, 1, 0]])
    assert np.argmax(np.abs(reaction).max(axis=1)) == 5 and np.argmax(np.linalg.norm(reaction, axis=1)) == 4
    return times, positions, {"reaction_total_N": reaction, "max_twine_tension_N": np.arange(7.0) ** 2,
                              "max_bar_tension_N": 100.0 + np.arange(7.0), "steps": np.arange(7)}


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
    drawn = np.concatenate([p.vertices[:3] for p in artist(side, plot.NETTING).get_paths()])
    at = scene_lib.mirrored(codend, positions[4]).reshape(-1, 3)
    np.testing.assert_allclose([drawn[:, 0].min(), drawn[:, 0].max()], [at[:, 0].min(), at[:, 0].max()], atol=1e-12)
    marks = [line for ax in (forces, tensions) for line in ax.lines if line.get_label().startswith("_")]
    assert any(np.allclose(line.get_xdata(), times[4]) for line in marks)   # the snapshot's time on the curves
    plot.save_run_png(tmp_path / "run.png", codend, times, positions, series, title="a run")
    assert (tmp_path / "run.png").read_bytes()[:4] == b"\x89PNG"
