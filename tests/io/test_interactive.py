"""The notebooks' 3D view (plotly): what it draws is the net, its colours the tensions, its scales equal."""

import importlib

import numpy as np

import jaxnet  # noqa: F401  (float64)
from jaxnet import figures
from jaxnet.io import interactive

codend = importlib.import_module("jaxnet.scenes.codend")


def test_the_view_draws_the_whole_net_coloured_by_tension():
    scene = codend.codend(meshes_around=8, meshes_along=4).scene
    x = np.asarray(scene.nodes.position) * np.array([1.5, 1.3, 1.3])  # its twines stretched
    fig = interactive.view(scene, x, title="cod-end")
    mesh, cables, fixed = fig.data
    tri = np.asarray(scene.netting.vertices)
    n, copies = scene.n_nodes, 4
    assert len(mesh.i) == copies * len(tri)
    np.testing.assert_array_equal(mesh.i[len(tri):2 * len(tri)], tri[:, 0] + n)  # the second copy's faces
    tw = figures.twine_tensions(scene, x)
    np.testing.assert_allclose(mesh.intensity, np.tile(tw.max(axis=1), copies))   # the larger of U and V
    assert np.any(tw[:, 0] != tw[:, 1]) and np.max(mesh.intensity) == tw.max() > 0     # the bar's top: the largest
    assert mesh.colorbar.title.text == "twine tension, larger of U and V (N)"
    # the copies mirror the model in y = 0 and z = 0: the drawn points span both sides symmetrically
    points = np.stack([mesh.x, mesh.y, mesh.z], axis=1)
    np.testing.assert_allclose(points[:, 1].min(), -points[:, 1].max())
    np.testing.assert_allclose(points[:, 2].min(), -points[:, 2].max())
    bt = figures.bar_tensions(scene, x)
    np.testing.assert_allclose(np.asarray(cables.line.color)[::3], np.tile(bt, copies))
    assert len(fixed.x) == int(np.asarray(scene.nodes.fixed).all(axis=1).sum())
    assert fig.layout.scene.aspectmode == "data" and fig.layout.title.text == "cod-end"
    only = interactive.view(scene, x, whole=False)
    assert len(only.data[0].i) == len(tri)
