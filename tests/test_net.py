"""The description of a net (jaxnet.net) and what its build made of it (jaxnet.build): references in words, the
description's lists, the layout of the built scene. Seams and symmetry planes have their own test files."""

import numpy as np
import pytest

from jaxnet.net import CableEnd, Corner, Nearest, Net, Rope, Side, Twine, describe_reference
from jaxnet.scene import SceneError


def wall(net=None):
    """A square panel of 10 x 10 meshes (l0 2.5 cm) hanging from a headline held at both ends, with a sinker."""
    net = net or Net()
    n, width = 10, 10 * 0.025 * np.sqrt(2.0)
    corners = [(0.0, 0.0, -width, 0, 0), (width, 0.0, -width, n, -n), (width, 0.0, 0.0, 2 * n, 0), (0.0, 0.0, 0.0, n, n)]
    panel = net.panel("wall", corners, Twine(l0=0.025, ea=2000.0, diameter=1.5e-3), step=0.1)
    net.cable("headline", along=panel.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    net.fix(panel.corner(2))
    net.fix(panel.corner(3))
    net.sinker(panel.corner(0), 0.5)
    return net, panel


@pytest.mark.parametrize("ref, message, name", [
    (Corner("wall", 7), "corner 7 of panel 'wall'", "wall corner 7"),
    (Side("wall", 2), "side 2 of panel 'wall'", "wall side 2"),
    (Nearest("wall", (1.0, 0.0, -2.0)), "the node of panel 'wall' nearest (1.0, 0.0, -2.0)", "wall near (1, 0, -2)"),
    (CableEnd("rope", 0), "end 0 of cable 'rope'", "rope start"),
    (CableEnd("rope", 1), "end 1 of cable 'rope'", "rope end"),
    ((1.0, 0.0, -2.5), "the point (1.0, 0.0, -2.5)", "(1, 0, -2.5)"),
])
def test_a_reference_in_words_for_messages_and_as_a_name(ref, message, name):
    assert describe_reference(ref) == message
    assert describe_reference(ref, short=True) == name


def test_the_description_is_kept_as_given_and_the_build_says_what_it_made():
    net, panel = wall()
    assert list(net.panels) == ["wall"] and list(net.cables) == ["headline"]
    assert [ref for ref, _ in net.fixings] == [panel.corner(2), panel.corner(3)]
    assert net.layout is None  # nothing built yet
    scene = net.build()
    layout = net.layout
    assert scene.panel_names == ("wall",) and scene.cable_names == ("headline",)
    # the two held corners are the scene's only fixed nodes, held on every axis
    held = np.flatnonzero(np.asarray(scene.nodes.fixed).all(axis=1))
    np.testing.assert_array_equal(np.sort(np.concatenate([nodes for _, nodes, _ in layout.fixed])), held)
    # the headline's nodes are the panel's top side, and the sinker's mass sits on corner 0
    top = layout.panel_nodes["wall"][layout.meshes["wall"].side_nodes[2]]
    assert set(layout.cable_nodes["headline"].tolist()) == set(top.tolist())
    corner0 = layout.attached[0]
    assert np.asarray(scene.nodes.mass)[corner0].sum() == pytest.approx(0.5)
    assert np.asarray(scene.nodes.mass).sum() == pytest.approx(0.5)


def test_a_reference_to_a_missing_panel_is_named():
    net, _ = wall()
    net.fix(Corner("roof", 0))
    with pytest.raises(SceneError, match=r"no panel named 'roof' \(panels: \['wall'\]\)"):
        net.build()
