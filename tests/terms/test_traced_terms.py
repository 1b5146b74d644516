"""A scene compiles only the terms it uses: the ones left out are absent from the lowered program."""

import dataclasses

import numpy as np

import jaxnet as jn
import jaxnet.net  # noqa: F401
from jaxnet.net import Rope
from jaxnet.scenes.panel import framed_panel, hanging_panel
from traced import lowered_text  # tests/traced.py


def test_weightless_net_compiles_no_weight():
    net = hanging_panel(meshes=6, step=0.1).net
    heavy = lowered_text(net.build())
    assert "netting_weight" in heavy and "bar_weight" in heavy
    net.environment = jn.Environment(gravity=0.0)
    net.attach(jn.net.Corner("netting", 0), force=(0.0, 0.0, -1.0))
    light = lowered_text(net.build())
    for term in ("netting_weight", "bar_weight", "node_weight"):
        assert term not in light
    assert "netting_tension" in light and "bar_tension" in light and "node_force" in light


def test_pushing_twines_are_traced_only_when_some_can_push():
    slack = jn.net.Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=0.0)
    scene = framed_panel(meshes=6, step=0.1, twine=slack).scene
    assert scene.bars is None
    assert "compressive_branch" not in lowered_text(scene)
    net = dataclasses.replace(scene.netting, ea_compression=np.full_like(np.asarray(scene.netting.ea_compression), 5.0))
    assert "compressive_branch" in lowered_text(dataclasses.replace(scene, netting=net))


def test_nodes_only_scene_without_netting_compiles_no_netting():
    from jaxnet.net import Net

    net = Net()
    net.cable("rope", start=(0, 0, 0), end=(1, 0, 0), rope=Rope(ea=1e4, diameter=0.01, density=2000.0), n_bars=4)
    net.fix((0, 0, 0))
    net.fix((1, 0, 0))
    text = lowered_text(net.build())
    assert "bar_tension" in text and "bar_weight" in text
    assert "netting_tension" not in text and "netting_weight" not in text
