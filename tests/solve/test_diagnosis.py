"""What a failed static solve says about the net (jaxnet.solve.diagnosis): hinged struts in compression, bars that
carry little.

A chain of two cable bars between two held ends, drawn shorter than the bars: both are in compression by an
exact strain. With a compression stiffness, the free joint between them makes a strut that buckles; a rope
without one (ea_compression=0) goes slack and is no strut; a stretched chain, a joint held on every axis, or a
joint that bends with a stiffness (a bar, Rope(bending_stiffness=EI)) is none either. Two links of 1 cm drawn a
tenth of a micrometre longer than at rest carry little (strain 1e-5); slack, or drawn 2 µm longer (2e-4), they are
not such bars.
"""

import numpy as np
import pytest

import jaxnet as jn
from jaxnet.scene import Bars, CableJoints, Environment, Nodes, Scene
from jaxnet.solve import diagnosis


def chain(span=1.9, ea_compression=1e4, joint_fixed=False, load=0.0, bending=None):
    """Two bars of rest length 1 m from (0, 0, 0) to (span, 0, 0), the joint drawn at the middle; ``load``
    (N) pushes the joint sideways (along y); ``bending``: the joint's flexural stiffness EI (N·m²), None for a
    hinge."""
    pos = np.array([[0.0, 0.0, 0.0], [span / 2, 0.0, 0.0], [span, 0.0, 0.0]])
    fixed = np.array([[True] * 3, [joint_fixed] * 3, [True] * 3])
    force = np.zeros((3, 3))
    force[1, 1] = load
    nodes = Nodes(position=pos, fixed=fixed, mass=np.zeros(3), volume=np.zeros(3), force=force)
    bars = Bars(ends=np.array([[0, 1], [1, 2]]), rest_length=np.ones(2), ea_traction=np.full(2, 1e4),
                ea_compression=np.full(2, ea_compression), diameter=np.full(2, 1e-3), density=np.full(2, 1e-9),
                cable=np.zeros(2, dtype=int))
    joints = None if bending is None else CableJoints(
        vertices=np.array([[0, 1, 2]]), rest_length=np.ones((1, 2)), stiffness=np.array([bending]),
        rest_angle=np.zeros(1), cable=np.zeros((1, 2), dtype=int))
    return Scene(nodes=nodes, bars=bars, environment=Environment(gravity=0.0), cable_names=("strut",),
                 cable_joints=joints)


def test_a_compressed_chain_with_compression_stiffness_is_a_strut():
    scene = chain(span=1.9)
    (name, count, strain, joint), = diagnosis.compressed_struts(scene, scene.nodes.position)
    assert (name, count, joint) == ("strut", 2, 1)
    assert strain == pytest.approx(0.05, rel=1e-12)  # each bar 0.95 m for 1 m at rest


@pytest.mark.parametrize("options, span", [({"ea_compression": 0.0}, 1.9), ({}, 2.1), ({"joint_fixed": True}, 1.9),
                                           ({"bending": 10.0}, 1.9)],
                         ids=["slack rope", "stretched", "joint held", "joint bends"])
def test_no_strut(options, span):
    scene = chain(span=span, **options)
    assert diagnosis.compressed_struts(scene, scene.nodes.position) == []


def test_a_failed_solve_names_the_strut_and_what_to_try():
    # the joint pushed sideways: the compressed straight chain has a negative sideways stiffness, so the first
    # damped step is no descent and the solve stops where it started, on the strut
    scene = chain(span=1.9, load=1.0)
    with pytest.raises(jn.SolveError) as failure:
        jn.solve_static(scene, max_iter=1)
    assert diagnosis.compressed_struts(scene, failure.value.equilibrium.x)
    assert "cable 'strut' has 2 bars in compression" in str(failure.value)
    assert "ea_compression=0" in str(failure.value) and "bending_stiffness" in str(failure.value)


def test_a_jointless_strut_is_named_but_a_bending_joint_of_zero_stiffness_is_still_a_hinge():
    scene = chain(span=1.9, bending=0.0)
    (name, count, _, joint), = diagnosis.compressed_struts(scene, scene.nodes.position)
    assert (name, count, joint) == ("strut", 2, 1)


def test_a_failed_solve_without_struts_claims_none():
    scene = chain(span=1.9, load=1.0, ea_compression=0.0)  # a slack rope: nothing holds the joint
    with pytest.raises(jn.SolveError) as failure:
        jn.solve_static(scene, max_iter=1)
    assert "compression" not in str(failure.value)


def test_a_solve_stopped_while_converging_is_told_to_take_more_iterations():
    """The built-in framed panel stopped by a cap of 4 iterations of the damped method, its residual falling
    quadratically: the error says
    by how much it fell over its last quarter (one iteration) and to give it more iterations; given them, it
    converges. The same record with a flat history (a residual that did not halve) gets no such hint."""
    import dataclasses

    from jaxnet.scenes import framed_panel

    case = framed_panel()
    with pytest.raises(jn.SolveError) as failure:
        jn.solve_static(case, max_iter=4, method="damped")
    eq = failure.value.equilibrium
    k, before, last = diagnosis.still_falling(eq)
    history = np.asarray(eq.history)
    assert k == 1 and before == history[3] and last == history[4] and last * 2.0 <= before
    message = str(failure.value)
    assert "the residual was still falling when the iteration cap stopped it" in message
    assert "over its last 1 iteration(s)" in message and "max_iter" in message
    assert jn.solve_static(case).converged
    flat = dataclasses.replace(eq, history=np.where(np.isfinite(history), history[4], np.nan))
    # a failure that shows nothing particular still says what to try
    assert diagnosis.still_falling(flat) is None and diagnosis.hints(case.scene, flat) == [diagnosis.GENERAL_HINT]


def links(off=1e-7):
    """Two links of 0.01 m and EA 1.6e6 N between held ends, each drawn ``off`` (m) longer than at rest (strain
    off / 0.01), the joint pulled sideways by 0.1 N: FEMNET's short links that carry little (1pelagic_trawl/toto1's,
    docs/investigations.md)."""
    pos = np.array([[0.0, 0.0, 0.0], [0.01 + off, 0.0, 0.0], [0.02 + 2 * off, 0.0, 0.0]])
    force = np.zeros((3, 3))
    force[1, 1] = 0.1
    nodes = Nodes(position=pos, fixed=np.array([[True] * 3, [False] * 3, [True] * 3]), mass=np.zeros(3),
                  volume=np.zeros(3), force=force)
    bars = Bars(ends=np.array([[0, 1], [1, 2]]), rest_length=np.full(2, 0.01), ea_traction=np.full(2, 1.6e6),
                ea_compression=np.ones(2), diameter=np.full(2, 1e-3), density=np.full(2, 1e-9),
                cable=np.zeros(2, dtype=int))
    return Scene(nodes=nodes, bars=bars, environment=Environment(gravity=0.0), cable_names=("link",))


def test_bars_that_carry_little_are_found_with_their_strain():
    scene = links()
    found = diagnosis.barely_taut_bars(scene, scene.nodes.position, 1)
    assert [f[:4] for f in found] == [(0, "link", 0.01, 1.6e6), (1, "link", 0.01, 1.6e6)]
    assert [f[4] for f in found] == pytest.approx([1e-5, 1e-5], rel=1e-6)
    assert [f[0] for f in diagnosis.barely_taut_bars(scene, scene.nodes.position, 0)] == [0]  # a held end: its bar


@pytest.mark.parametrize("off", [-1e-7, 2e-6], ids=["slack", "stretched by 2e-4"])
def test_no_bar_that_carries_little(off):
    scene = links(off=off)
    assert diagnosis.barely_taut_bars(scene, scene.nodes.position, 1) == []


def test_a_failed_solve_names_the_bar_that_carries_little_and_what_to_try():
    # one damped step turns the links by 3e-5 rad: they stay stretched by 1e-5
    scene = links()
    with pytest.raises(jn.SolveError) as failure:
        jn.solve_static(scene, max_iter=1)
    message = str(failure.value)
    assert int(failure.value.equilibrium.worst_node) == 1
    assert ("node 1 hangs on bar 0 of cable 'link' (and 1 other bar(s) there) (rest length 0.01 m, EA 1.6e+06 N) "
            "stretched by only 1e-05") in message
    assert "more than about 0.0045 rad" in message and "a lower EA" in message
