"""Panels joined along a seam, also with different mesh counts along it (book Figs 4.3 and 4.5)."""

import numpy as np

import jaxnet as jn
from jaxnet.net import Net, Rope, Twine


def two_panels(upper_meshes=50, lower_meshes=45, high=20, l0=0.02, step=0.08):
    """An upper panel of 50 meshes across sewn to a lower one of 45 across on the same 1 m border,
    hanging from a rope and weighted by a sinker bar; square meshes where the widths allow."""
    width = upper_meshes * l0 * np.sqrt(2)
    h = high * l0 * np.sqrt(2)
    n, m, k = upper_meshes, lower_meshes, high
    upper = [(0, 0, -h, 0, 0), (width, 0, -h, n, -n), (width, 0, 0, n + k, k - n), (0, 0, 0, k, k)]
    lower = [(0, 0, -2 * h, 0, 0), (width, 0, -2 * h, m, -m), (width, 0, -h, m + k, k - m), (0, 0, -h, k, k)]
    net = Net()
    twine = Twine(l0=l0, ea=2000.0, diameter=1.5e-3, ea_compression=20.0)
    a = net.panel("upper", upper, twine, step)
    b = net.panel("lower", lower, twine, step)
    net.seam(a.side(0), b.side(2))
    net.cable("headline", along=a.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    net.cable("sinker", along=b.side(0), rope=Rope(ea=1e5, diameter=0.012, density=11340.0))
    net.fix(a.corner(2))
    net.fix(a.corner(3))
    return net.build(), a, b


def test_seam_of_50_and_45_meshes_shares_nodes_and_is_in_equilibrium():
    scene, _, _ = two_panels()
    tri = np.asarray(scene.netting.vertices)
    panel = np.asarray(scene.netting.panel)
    upper_nodes = np.unique(tri[panel == 0])
    lower_nodes = np.unique(tri[panel == 1])
    seam = np.intersect1d(upper_nodes, lower_nodes)
    # the shared border: every seam node belongs to both panels, at least the two corners and more
    assert seam.size >= 3
    z = scene.nodes.position[seam, 2]
    np.testing.assert_allclose(z, z[0], atol=1e-12)  # all on the seam line
    # at a seam node the two panels have different twine coordinates: 50 vs 45 meshes on one border
    uv = np.asarray(scene.netting.uv)
    corner = seam[np.argmax(scene.nodes.position[seam, 0])]
    u_up = {tuple(uv[e][list(tri[e]).index(corner)]) for e in np.flatnonzero((panel == 0) & (tri == corner).any(axis=1))}
    u_lo = {tuple(uv[e][list(tri[e]).index(corner)]) for e in np.flatnonzero((panel == 1) & (tri == corner).any(axis=1))}
    assert u_up == {(50.0, -50.0)} and u_lo == {(65.0, -25.0)}
    eq = jn.solve_static(scene, tol=1e-6, max_iter=200)
    force = np.linalg.norm(np.asarray(eq.force)[seam], axis=1)
    assert force.max() <= 1e-6
    # the seam carries the weight of the lower panel and sinker: the vertical pull across it is positive
    assert eq.reaction(scene).sum(axis=0)[2] > 0
