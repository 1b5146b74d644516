"""Design on a FEMNET trawl: the gear's figures (spread, height, ratios), the design written back as a ``.don``
file, and a design gradient through the trawl's equilibrium against finite differences.

The trawl is FEMNET's worked case ``3bottom_trawl/b1`` (a half bottom trawl with doors, read from its ``.don``).
"""

from __future__ import annotations

import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxnet.design import cut, gradient, objectives
from jaxnet.design.space import DesignSpace
from jaxnet.io import femnet
from jaxnet.solve import implicit, statics

CORPUS = pathlib.Path(__file__).parents[3] / "shared" / "femnet-corpus"
B1 = CORPUS / "3bottom_trawl" / "b1.don"


@pytest.fixture(scope="module")
def trawl():
    case = femnet.read_don(B1)
    return case, DesignSpace(case)


# -- the gear's figures --------------------------------------------------------------------------------------


def test_gear_figures_against_their_definitions(trawl):
    """Spread, height and the drag per swept width at arbitrary positions, against their definitions; the
    ratio's gradient against central differences."""
    case, space = trawl
    scene = space.reference
    model = implicit.structure_of(scene).model
    rng = np.random.default_rng(3)
    x = np.asarray(scene.nodes.position) + rng.normal(0.0, 0.5, (scene.n_nodes, 3))
    door, headline = femnet.global_node(case, 56), femnet.global_node(case, 8)
    per_width = objectives.ratio(objectives.drag(whole_net=True), objectives.spread(door))
    figures = dict(spread=objectives.spread(door), across=objectives.spread(door, other=headline),
                   height=objectives.height(headline), above=objectives.height(headline, above=door),
                   level=objectives.height(headline, level=-50.0), half=objectives.drag(),
                   whole=objectives.drag(whole_net=True), per_width=per_width)
    values = jax.jit(lambda xx: {k: f(objectives.Outcome(xx, scene, model)) for k, f in figures.items()})(
        jnp.asarray(x))
    v = {k: float(a) for k, a in values.items()}
    assert scene.symmetry_planes == ((1, 0.0),)  # the half trawl's plane y = 0
    assert v["spread"] == pytest.approx(2.0 * abs(x[door, 1]), rel=1e-14)
    assert v["across"] == pytest.approx(abs(x[door, 1] - x[headline, 1]), rel=1e-14)
    bed = float(np.asarray(scene.nodes.limit)[headline, 2])
    assert bed == -56.0  # the case's "Limits Z" of the headline's node type: the sea bed 56 m down
    assert v["height"] == pytest.approx(x[headline, 2] + 56.0, rel=1e-14)
    assert v["above"] == pytest.approx(x[headline, 2] - x[door, 2], rel=1e-14)
    assert v["level"] == pytest.approx(x[headline, 2] + 50.0, rel=1e-14)
    assert v["whole"] == pytest.approx(2.0 * v["half"], rel=1e-14)
    assert v["per_width"] == pytest.approx(v["whole"] / (2.0 * abs(x[door, 1])), rel=1e-13)

    @jax.jit
    def f(xx):
        return per_width(objectives.Outcome(xx, scene, model))

    g = np.asarray(jax.jit(jax.grad(f))(jnp.asarray(x)))
    d = rng.normal(size=x.shape)
    h = 1e-5
    fd = (float(f(jnp.asarray(x + h * d))) - float(f(jnp.asarray(x - h * d)))) / (2 * h)
    assert np.sum(g * d) == pytest.approx(fd, rel=1e-6)


def test_gear_figures_name_bad_settings(trawl):
    case, space = trawl
    o = objectives.Outcome(jnp.asarray(space.reference.nodes.position), space.reference,
                           implicit.structure_of(space.reference).model)
    with pytest.raises(ValueError, match="no symmetry plane across x"):
        objectives.spread(0, axis="x")(o)
    with pytest.raises(ValueError, match="axis must be one of"):
        objectives.height(0, axis="up")
    with pytest.raises(ValueError, match="give above .* or level"):
        objectives.height(0, above=1, level=0.0)
    with pytest.raises(ValueError, match="node index 100000 outside"):
        objectives.height(100000)(o)
    free = int(np.flatnonzero(np.asarray(space.reference.nodes.limit_sense)[:, 2] != 1)[0])
    with pytest.raises(ValueError, match=f"node {free} has no sea bed under it"):
        objectives.height(free)(o)
    with pytest.raises(ValueError, match="the denominator is not a figure"):
        objectives.ratio(objectives.drag(), 3.0)
    with pytest.raises(ValueError, match="global node 0: the case has global nodes 1 to"):
        femnet.global_node(case, 0)


# -- the design as a .don file ------------------------------------------------------------------------------


def test_the_drawn_design_writes_the_file_unchanged(trawl, tmp_path):
    _, space = trawl
    written = femnet.write_design(B1, space, {}, tmp_path / "same.don")
    assert written.read_text() == B1.read_text(errors="replace")


def test_a_design_written_as_don_reads_back_as_that_design(trawl, tmp_path):
    """Corners moved by whole meshes, a twine, a mesh side, a free rope and a rope sewn along netting (its
    hanging ratio): the written file, read again, is that design."""
    _, space = trawl
    theta = space.initial()
    corners = np.asarray(theta["cut"]["panel 3"]).copy()
    corners[2] += np.asarray(cut.mesh_to_twine(np.array([1.0, -2.0])))  # one mesh wider, two less deep
    rope = space.initial()["cable_length"]
    free = sorted(rope)[0]
    mounting = next(n for n, m in space.mountings.items() if not m.fixed)
    design = {"cut": {"panel 3": corners}, "twine_diameter": {"panel 5": 0.0035}, "mesh_side": {"panel 7": 0.055},
              "cable_length": {free: float(rope[free]) * 1.05},
              "hanging_ratio": {mounting: float(theta["hanging_ratio"][mounting]) * 0.98}}
    written = femnet.write_design(B1, space, design, tmp_path / "designed.don")
    again = DesignSpace(femnet.read_don(written))
    back = again.initial()
    np.testing.assert_allclose(np.asarray(back["cut"]["panel 3"]), corners, rtol=0, atol=1e-9)
    for p in space.panels:
        if p != "panel 3":
            np.testing.assert_array_equal(np.asarray(back["cut"][p]), np.asarray(theta["cut"][p]))
    assert float(back["twine_diameter"]["panel 5"]) == 0.0035
    assert float(back["mesh_side"]["panel 7"]) == 0.055
    assert float(back["cable_length"][free]) == pytest.approx(float(rope[free]) * 1.05, rel=1e-9)
    assert float(back["hanging_ratio"][mounting]) == pytest.approx(design["hanging_ratio"][mounting], rel=1e-9)
    changed = [a != b for a, b in zip(B1.read_text(errors="replace").split("\n"), written.read_text().split("\n"))]
    # a corner line, three material lines and two ropes' lengths: nothing else is touched
    assert sum(changed) == 6


def test_a_design_of_another_case_is_refused(trawl, tmp_path):
    _, space = trawl
    with pytest.raises(ValueError, match="write_design: 'panel .*"):
        femnet.write_design(CORPUS / "1pelagic_trawl" / "s2.don", space, {}, tmp_path / "x.don")
    assert not (tmp_path / "x.don").exists()


# -- the design gradient through the trawl's equilibrium ---------------------------------------------------------


def _kinked(space):
    """Panels with a side of pure bars (dU or dV = 0) mounted on a rope: the rope's length follows the side's
    stretched length (|dU| + |dV|) l0, which has a kink there (the design space's docstring)."""
    cuts = space.initial()["cut"]
    out = set()
    for mounting in space.mountings.values():
        for side in mounting.sides:
            c = np.asarray(cuts[side.panel])
            if np.any(c[(side.index + 1) % len(c)] - c[side.index] == 0.0):
                out.add(side.panel)
    return out


def test_drag_per_swept_width_gradient_through_the_trawl_equilibrium(trawl):
    """d(drag per swept width)/d(cut) by the host-driven adjoint (what optimize calls) against central
    differences of re-solved equilibria, along a random direction of the corners of the panels without a kink
    (b1's panels 1 and 13 have ropes along sides of pure bars). The trawl's warp (EA 27 MN in short bars, 280 m
    from the origin) puts the residual's roundoff at 1e-6 to 1e-4 N, above the differentiable solve's 1e-8 N:
    the solve stops at its roundoff floor (newton.roundoff_floor). Along this direction the gradient has a
    kink between 1e-4 and 1e-3 twines (measured: the directional derivative -3.34 at +1e-4 twines, -6.47 at
    +1e-3; a node of the sea-bed contact or a twine at its slack length switching): the differences are taken
    inside it, and the step halved gives the same difference (the function is smooth there)."""
    case, space = trawl
    x0 = statics.solve(space.reference).x
    door = femnet.global_node(case, 56)
    per_width = objectives.ratio(objectives.drag(whole_net=True), objectives.spread(door))
    cuts = space.initial()["cut"]
    sensitivity = gradient.Sensitivity(space, per_width)
    e = sensitivity.value_and_grad({"cut": cuts}, x0)
    rng = np.random.default_rng(0)
    kinked = _kinked(space)
    assert kinked == {"panel 1", "panel 13"}
    d = {p: np.vstack([np.zeros((1, 2)), rng.normal(size=(len(c) - 1, 2))]) * (p not in kinked)
         for p, c in cuts.items()}

    def difference(h):  # twines
        plus = sensitivity.value({"cut": {p: c + h * d[p] for p, c in cuts.items()}}, x0).value
        minus = sensitivity.value({"cut": {p: c - h * d[p] for p, c in cuts.items()}}, x0).value
        return (plus - minus) / (2 * h)

    directional = sum(float(jnp.sum(e.grad["cut"][p] * d[p])) for p in cuts)
    assert e.value == pytest.approx(561.14, rel=1e-4)  # jaxnet's drag per swept width of b1 (N/m)
    assert e.adjoint_residual < 1e-9
    halved = difference(5e-5)
    assert difference(1e-4) == pytest.approx(halved, rel=1e-5)
    assert directional == pytest.approx(halved, rel=1e-5)
    # the height above a sea bed the node does not have: in the host path's compiled figure (its node types an
    # argument), an error naming the node when it runs, not a number
    free = int(np.flatnonzero(np.asarray(space.reference.nodes.limit_sense)[:, 2] != 1)[0])
    with pytest.raises(RuntimeError, match=f"node {free} has no sea bed under it"):
        gradient.Sensitivity(space, objectives.height(free)).value({"cut": cuts}, e.x)
