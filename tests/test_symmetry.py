"""Symmetry planes: a model that is part of a symmetric net (a cod-end's quarter), declared once
(:meth:`jaxnet.net.Net.symmetry_plane`, :attr:`jaxnet.scene.Scene.symmetry_planes`), and the mirror images
the writers draw and the whole-net figures use."""

import importlib
import pathlib

import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.net import Net, Twine
from jaxnet.scene import SceneError, mirror_copies, mirror_signs, mirrored

codend = importlib.import_module("jaxnet.scenes.codend")
CORPUS = pathlib.Path(__file__).resolve().parent / "data" / "femnet-corpus"  # FEMNET's cases, their licence there


def half_panel(**plane):
    """A 1 m square panel in the plane x = 0, from y = 0 to 1, z = -1 to 0, held along its top."""
    net = Net()
    p = net.panel("half", [(0.0, 0.0, -1.0, 0, 0), (0.0, 1.0, -1.0, 5, -5), (0.0, 1.0, 0.0, 10, 0),
                           (0.0, 0.0, 0.0, 5, 5)], Twine(l0=0.1, ea=1000.0, diameter=1e-3), 0.25)
    net.fix(p.side(2))
    if plane:
        net.symmetry_plane(**plane)
    return net.build()


def test_a_plane_holds_exactly_the_nodes_on_it_across_it():
    scene = half_panel(axis="y", at=0.0)
    assert scene.symmetry_planes == ((1, 0.0),)
    x, fixed = np.asarray(scene.nodes.position), np.asarray(scene.nodes.fixed)
    plain = np.asarray(half_panel().nodes.fixed)
    on = np.abs(x[:, 1]) < 1e-12
    assert on.sum() >= 3
    np.testing.assert_array_equal(fixed[:, 1], plain[:, 1] | on)  # held along y on the plane, nowhere else
    np.testing.assert_array_equal(fixed[:, [0, 2]], plain[:, [0, 2]])
    kept = half_panel(axis="y", at=0.0, hold=False)
    np.testing.assert_array_equal(np.asarray(kept.nodes.fixed), plain)
    assert kept.symmetry_planes == ((1, 0.0),)


def test_bad_planes_are_named():
    net = Net()
    with pytest.raises(SceneError, match=r"symmetry_plane: axis must be 'x', 'y' or 'z', got 'w'"):
        net.symmetry_plane("w")
    with pytest.raises(SceneError, match=r"symmetry_plane: 'at' must be a finite position \(m\), got nan"):
        net.symmetry_plane("x", float("nan"))
    net.symmetry_plane("z", -1.0)
    with pytest.raises(SceneError, match="already has a symmetry plane across z"):
        net.symmetry_plane("z", 0.0)


def test_images_and_signs_of_a_quarter_model():
    """Two planes make four copies: the points reflected in y = 0, then both in z = -2; a force keeps its x and
    flips its y in the copies mirrored in y, its z in those mirrored in z, so the whole net's force is 4 F_x
    along x and nothing across the planes."""
    scene = half_panel(axis="y", at=0.0)
    scene = type(scene)(**{**{f: getattr(scene, f) for f in scene.__dataclass_fields__},
                           "symmetry_planes": ((1, 0.0), (2, -2.0))})
    assert mirror_copies(scene) == 4
    p = np.array([[1.0, 2.0, 3.0]])
    images = mirrored(scene, p)[:, 0]
    np.testing.assert_array_equal(images, [[1, 2, 3], [1, -2, 3], [1, 2, -7], [1, -2, -7]])
    signs = mirror_signs(scene)
    force = np.array([5.0, 1.0, -2.0])
    np.testing.assert_array_equal((signs * force).sum(axis=0), [20.0, 0.0, 0.0])


def test_the_cod_end_and_femnet_quarter_models_declare_their_planes():
    assert codend.codend(meshes_around=8, meshes_along=4).scene.symmetry_planes == ((1, 0.0), (2, 0.0))
    from jaxnet.io import femnet

    case = femnet.read_don(CORPUS / "14tarp" / "c2.don")
    assert case.scene.symmetry_planes == ((1, 0.0), (2, -10.0)) and case.info["symmetry_axes"] == ["y", "z"]
    # every node FEMNET holds by a symmetry plane lies on it
    x = np.asarray(case.scene.nodes.position)
    for axis, at in case.scene.symmetry_planes:
        on = np.abs(x[:, axis] - at) < 1e-9
        assert on.sum() >= 3 and np.asarray(case.scene.nodes.fixed)[on, axis].all()
