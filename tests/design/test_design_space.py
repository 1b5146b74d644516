"""The design space (jaxnet.design.space, jaxnet.design.cut): θ -> Scene, exact at the reference design,
differentiable, and what a netting maker reads of a cut.

Closed forms used here (derived in jaxnet.design.cut's docstring): mesh coordinates u = (U - V)/2, v = (U + V)/2;
a trapezoid of n1 meshes at the top, n2 at the bottom and m deep holds (n1 + n2) m / 2 meshes, i.e.
Σ|d| l0 = 4 l0 (n1 + n2) m / 2 = 2 l0 m (n1 + n2) metres of twine (|d|/2 twines of each direction per
triangle, eq. 4.25-4.26; |d|/4 meshes, eq. 4.24); a side (dU, dV) has a stretched length (|dU| + |dV|) l0.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.flatten_util import ravel_pytree

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.design import cut
from jaxnet.design.space import DesignSpace
from jaxnet.net import Nearest, Net, Rope, Twine
from jaxnet.scene import Environment
from jaxnet.scenes.cage import fish_cage
from jaxnet.scenes.codend import codend
from jaxnet.scenes.panel import framed_panel, hanging_panel

L0 = 0.05
TRAPEZOID = (6, 4, 4)  # meshes at the top, at the bottom, deep


def rig(twine=None):
    """A tapered panel with every family: hung from two bridles (free cables) to fixed points, a headline
    and a footrope sewn along it, a float, two sinkers, knots (default contact stiffness) and twine bending
    (hinges), in a current. ``twine``: another netting material (e.g. without knots and bending, which
    cost compile time where they are not the point)."""
    twine = twine or Twine(l0=L0, ea=1000.0, diameter=2e-3, ea_compression=100.0, knot_size=4e-3, bending_stiffness=1e-6)
    net = Net(environment=Environment(current_speed=0.3))
    width = L0 * np.sqrt(2.0)  # a square mesh across and deep (m)
    uv = np.asarray(cut.trapezoid(*TRAPEZOID))
    mesh = np.asarray(cut.twine_to_mesh(uv))
    corners = [(u * width, 0.0, -v * width, U, V) for (u, v), (U, V) in zip(mesh, uv)]
    p = net.panel("trap", corners, twine, step=0.1)
    rope = Rope(ea=2e4, diameter=6e-3)
    net.cable("headline", along=p.side(0), rope=rope)
    net.cable("footrope", along=p.side(2), rope=Rope(ea=2e4, diameter=8e-3, density=3000.0))
    top = TRAPEZOID[0] * width
    net.cable("bridle a", start=(-0.1, 0.0, 0.3), end=p.corner(0), rope=rope, n_bars=2)
    net.cable("bridle b", start=(top + 0.1, 0.0, 0.3), end=p.corner(1), rope=rope, n_bars=2, length=0.4)
    net.fix((-0.1, 0.0, 0.3))
    net.fix((top + 0.1, 0.0, 0.3))
    net.float(p.corner(0), 2.0, mass=0.05)
    net.sinker(p.corner(2), 0.3)
    net.sinker(p.nearest(0.5 * top, 0.0, -0.2), 0.1)
    return net


@pytest.fixture(scope="module")
def rig_space():
    return DesignSpace(rig())


@pytest.fixture(scope="module")
def panel_space():
    return DesignSpace(hanging_panel(meshes=6, step=0.1))


@pytest.fixture(scope="module")
def cage_space():
    return DesignSpace(fish_cage(radius=2.0, depth=1.5, sides=5, l0=0.1, step=0.6))


def design_leaves(scene):
    """Every float array of a scene that a design parameter moves, flattened into one vector."""
    parts = [scene.nodes.position, scene.nodes.mass, scene.nodes.volume]
    if scene.netting is not None:
        n = scene.netting
        parts += [n.uv, n.l0, n.ea_traction, n.ea_compression, n.diameter]
        parts += [] if n.knot_stiffness is None else [n.knot_stiffness]
    if scene.hinges is not None:
        parts += [scene.hinges.uv, scene.hinges.l0]
    if scene.bars is not None:
        parts += [scene.bars.rest_length]
    return jnp.concatenate([jnp.ravel(jnp.asarray(p, float)) for p in parts])


def assert_same_scene(a, b, tol=1e-12):
    """Same tree, same dtypes kinds and shapes, floats equal to tol (relative to 1 + |b|), others equal."""
    la, ta = jax.tree_util.tree_flatten_with_path(a)
    lb, tb = jax.tree_util.tree_flatten_with_path(b)
    assert ta == tb
    for (path, x), (_, y) in zip(la, lb):
        x, y = np.asarray(x), np.asarray(y)
        where = jax.tree_util.keystr(path)
        assert x.shape == y.shape, where
        assert x.dtype.kind == y.dtype.kind, where
        if x.dtype.kind == "f":
            np.testing.assert_array_less(np.abs(x - y), tol * (1.0 + np.abs(y)) + 1e-300, err_msg=where)
        else:
            np.testing.assert_array_equal(x, y, err_msg=where)


# -- the reference design ----------------------------------------------------------------------------------


@pytest.mark.parametrize("make", [lambda: fish_cage(radius=2.0, depth=1.5, sides=5, l0=0.1, step=0.6).net,
                                  lambda: codend(meshes_around=16, meshes_along=8, step=0.2).net,
                                  lambda: hanging_panel(meshes=6, step=0.1).net, rig],
                         ids=["cage", "codend", "hanging_panel", "rig"])
def test_initial_design_is_the_built_net(make):
    net = make()
    space = DesignSpace(net)
    assert_same_scene(jax.jit(space.scene)(space.initial()), net.build())


def test_families_of_the_rig(rig_space):
    theta = rig_space.initial()
    assert {k: sorted(v) for k, v in theta.items()} == {
        "cut": ["trap"], "mesh_side": ["trap"], "twine_diameter": ["trap"], "ea": ["trap"],
        "hanging_ratio": ["footrope", "headline"], "sinker_mass": ["trap corner 2", "trap near (0.212132, 0, -0.2)"],
        "buoyancy": ["trap corner 0"], "cable_length": ["bridle a", "bridle b"]}
    # the headline is sewn along the top, 6 meshes: stretched 12 l0, rope at its start length (square meshes)
    np.testing.assert_allclose(float(theta["hanging_ratio"]["headline"]), 6 * L0 * np.sqrt(2) / (12 * L0), rtol=1e-14)
    np.testing.assert_allclose(float(theta["cable_length"]["bridle b"]), 0.4, rtol=1e-14)


# -- derivatives ---------------------------------------------------------------------------------------------


def test_jacobian_matches_central_differences_for_every_family(rig_space):
    """jax.jacfwd of every moved float of the scene with respect to every entry of θ, against central
    differences of step 1e-4 |θ_i| (every map is at most quadratic in one parameter: l0² in the default knot
    stiffness; the differences are then exact but for rounding): agree to 1e-7 of the column's size."""
    flat, unravel = ravel_pytree(rig_space.initial())
    f = jax.jit(lambda x: design_leaves(rig_space.scene(unravel(x))))
    jac = np.asarray(jax.jit(jax.jacfwd(lambda x: design_leaves(rig_space.scene(unravel(x)))))(flat))
    x0 = np.asarray(flat)
    h = 1e-4 * np.maximum(np.abs(x0), 1e-3)
    fd = np.stack([(np.asarray(f(x0 + h[i] * e)) - np.asarray(f(x0 - h[i] * e))) / (2 * h[i])
                   for i, e in enumerate(np.eye(x0.size))], axis=1)
    paths = jax.tree_util.tree_flatten_with_path(rig_space.initial())[0]
    labels = [f"{jax.tree_util.keystr(p)}[{k}]" for p, leaf in paths for k in range(np.size(leaf))]
    for i, label in enumerate(labels):
        scale = max(np.max(np.abs(fd[:, i])), 1e-300)
        assert np.max(np.abs(fd[:, i])) > 0, f"{label}: moves nothing"
        assert np.max(np.abs(jac[:, i] - fd[:, i])) <= 1e-7 * scale, label


def test_jacobian_of_the_cage_collar_mounting(cage_space):
    """The same check on the cage's fixed-node mounting: the collar's positions and pipes move with E, with the
    cut of a wall (its top's meshes) and with its mesh side; the map is linear in each, so central differences
    of step 1e-4 |θ_i| agree to 1e-7 of the column's size."""
    theta = cage_space.initial()
    name, = theta["hanging_ratio"]
    subset = {"hanging_ratio": theta["hanging_ratio"], "cut": {"wall 0": theta["cut"]["wall 0"]},
              "mesh_side": {"wall 0": theta["mesh_side"]["wall 0"]}}
    flat, unravel = ravel_pytree(subset)
    f = jax.jit(lambda x: design_leaves(cage_space.scene(unravel(x))))
    jac = np.asarray(jax.jacfwd(f)(flat))
    x0 = np.asarray(flat)
    h = 1e-4 * np.maximum(np.abs(x0), 1e-3)
    fd = np.stack([(np.asarray(f(x0 + h[i] * e)) - np.asarray(f(x0 - h[i] * e))) / (2 * h[i])
                   for i, e in enumerate(np.eye(x0.size))], axis=1)
    scale = np.max(np.abs(fd), axis=0)
    assert np.all(scale > 0)
    assert np.all(np.max(np.abs(jac - fd), axis=0) <= 1e-7 * scale)
    # d(collar node x, y)/dE = its (x, y) / E_ref: the collar is scaled about the axis by E / E_ref
    column = int(np.flatnonzero(ravel_pytree(jax.tree_util.tree_map(jnp.zeros_like, subset)
                                             | {"hanging_ratio": {name: 1.0}})[0])[0])
    corner = int(cage_space.net.layout.panel_nodes["wall 0"][0])
    xy = np.asarray(cage_space.reference.nodes.position)[corner, :2]
    np.testing.assert_allclose(jac[[3 * corner, 3 * corner + 1], column], xy / float(theta["hanging_ratio"][name]),
                               rtol=1e-10, atol=1e-12)


def test_twine_length_of_a_trapezoid_and_its_gradient(rig_space):
    """Σ|d| l0 over the panel's triangles = 2 l0 m (n1 + n2) for trapezoid cuts (n1, n2, m) and mesh sides
    l0, at and away from the reference; its derivative in n1 is 2 l0 m."""

    @jax.jit
    def twine_length(counts, l0):
        theta = {"cut": {"trap": cut.trapezoid(*counts)}, "mesh_side": {"trap": l0}}
        scene = rig_space.scene(theta)
        total = jnp.sum(jnp.abs(geometry.twine_determinant(scene.netting.uv)) * scene.netting.l0)
        return total, rig_space.twine_length(theta)["trap"]

    for counts, l0 in [(TRAPEZOID, L0), ((6.5, 3.6, 4.7), 0.043)]:
        n1, n2, m = counts
        np.testing.assert_allclose(twine_length(jnp.array(counts, float), l0), 2 * l0 * m * (n1 + n2), rtol=1e-12)
    grad = jax.jit(jax.grad(lambda counts, l0: twine_length(counts, l0)[0]))(jnp.array([6.5, 3.6, 4.7]), 0.043)
    np.testing.assert_allclose(np.asarray(grad), [2 * 0.043 * 4.7] * 2 + [2 * 0.043 * (6.5 + 3.6)], rtol=1e-12)


def test_affine_cut_moves_every_twine_coordinate_by_that_map(rig_space):
    """Corners moved by an affine map A uv + b (A of positive determinant) move every triangle's and hinge's
    twine coordinates by the same map (the mesher's weights reproduce affine functions)."""
    a, b = np.array([[1.2, 0.3], [-0.1, 0.9]]), np.array([2.5, -1.0])
    ref = rig_space.reference
    corners = np.asarray(rig_space.initial()["cut"]["trap"])
    scene = rig_space.scene({"cut": {"trap": corners @ a.T + b}})
    np.testing.assert_allclose(np.asarray(scene.netting.uv), np.asarray(ref.netting.uv) @ a.T + b, rtol=0, atol=1e-12)
    np.testing.assert_allclose(np.asarray(scene.hinges.uv), np.asarray(ref.hinges.uv) @ a.T + b, rtol=0, atol=1e-12)


def test_vmap_over_designs_equals_one_by_one(panel_space):
    base = panel_space.initial()
    corners = base["cut"]["netting"]
    batch = {"cut": {"netting": jnp.stack([corners * s for s in (1.0, 1.1, 0.9)])},
             "mesh_side": {"netting": jnp.array([0.025, 0.03, 0.02])},
             "hanging_ratio": {"headline": jnp.array([0.7, 0.6, 0.8])}}
    one = jax.jit(lambda t: design_leaves(panel_space.scene(t)))
    out = jax.jit(jax.vmap(one))(batch)
    for k in range(3):
        np.testing.assert_allclose(np.asarray(out[k]), np.asarray(one(jax.tree_util.tree_map(lambda v: v[k], batch))),
                                   rtol=1e-14, atol=0)
    assert not np.allclose(out[1], out[2])


# -- materials and gear parameters against a net rebuilt with them ----------------------------------------------


def test_materials_equal_the_net_rebuilt_with_them():
    """EA (compression following), diameter and mesh side given to θ give the scene of the same net built
    with that twine (the step scaled with l0, so that the mesh is the same in twine coordinates): every array
    but the free start positions, ropes included (sewn at the reference hanging ratio). The twines resist
    compression (EA_c = EA), so that EA_c's following EA is seen."""
    stiff = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=2000.0)
    space = DesignSpace(hanging_panel(meshes=6, step=0.1, twine=stiff))
    twine = Twine(l0=0.03, ea=3000.0, diameter=2e-3, density=1140.0, ea_compression=3000.0)
    rebuilt = hanging_panel(meshes=6, step=0.12, l0=0.03, twine=twine).scene
    scene = space.scene({"mesh_side": {"netting": 0.03}, "ea": {"netting": 3000.0},
                               "twine_diameter": {"netting": 2e-3}})
    assert_same_scene(scene.netting, rebuilt.netting)
    assert_same_scene(scene.bars, rebuilt.bars)


def test_sinker_mass_equals_the_net_rebuilt_with_it(cage_space):
    theta = {"sinker_mass": {name: 25.0 for name in cage_space.initial()["sinker_mass"]}}
    rebuilt = fish_cage(radius=2.0, depth=1.5, sides=5, l0=0.1, step=0.6, sinker_kg=25.0).scene
    assert_same_scene(cage_space.scene(theta).nodes, rebuilt.nodes)


def test_float_buoyancy_and_cable_length(rig_space):
    """A float's displaced volume grows by ΔB / (ρ g) on its node; a free cable's bars keep their shares of a new
    total length."""
    ref = rig_space.reference
    theta = {"buoyancy": {"trap corner 0": 7.0}, "cable_length": {"bridle b": 0.55}}
    scene = rig_space.scene(theta)
    dv = np.asarray(scene.nodes.volume) - np.asarray(ref.nodes.volume)
    assert np.count_nonzero(dv) == 1
    np.testing.assert_allclose(dv.sum(), 5.0 / (1025.0 * 9.81), rtol=1e-12)
    bridle = np.asarray(ref.bars.cable) == ref.cable_names.index("bridle b")
    rest = np.asarray(scene.bars.rest_length)
    np.testing.assert_allclose(rest[bridle].sum(), 0.55, rtol=1e-14)
    np.testing.assert_allclose(rest[bridle] / np.asarray(ref.bars.rest_length)[bridle], 0.55 / 0.4, rtol=1e-14)
    # the others as they were, to rounding (bit for bit on the CPU; a GPU's arithmetic moved them by one ulp)
    np.testing.assert_allclose(rest[~bridle], np.asarray(ref.bars.rest_length)[~bridle], rtol=1e-15)


# -- hanging ratio ---------------------------------------------------------------------------------------------


def test_hanging_ratio_of_a_sewn_rope(panel_space):
    """Rope rest length = E × (|dU| + |dV|) l0 of its side, whatever the cut and l0."""
    corners = np.asarray(panel_space.initial()["cut"]["netting"]).copy()
    corners[3] += (-1.0, 1.0)  # the top side (corner 2 -> 3) one mesh longer
    theta = {"cut": {"netting": corners}, "mesh_side": {"netting": 0.02}, "hanging_ratio": {"headline": 0.6}}
    scene = panel_space.scene(theta)
    d = corners[3] - corners[2]
    headline = np.asarray(scene.bars.cable) == scene.cable_names.index("headline")
    stretched = (abs(d[0]) + abs(d[1])) * 0.02
    np.testing.assert_allclose(stretched, 7 * 2 * 0.02, rtol=1e-14)  # 7 meshes of 2 l0
    np.testing.assert_allclose(np.asarray(scene.bars.rest_length)[headline].sum(), 0.6 * stretched, rtol=1e-13)
    np.testing.assert_allclose(float(panel_space.stretched_length(theta)["headline"]), stretched, rtol=1e-14)


def test_hanging_ratio_of_the_cage_collar(cage_space):
    """The collar (fixed in x, y) is scaled about the cage's axis: its polyline is E × the wall tops' stretched
    length (5 walls of n meshes, 2 n l0 each), it stays at z = 0, and the collar pipes' rest length follows."""
    ref = cage_space.reference
    (name, mounting), = cage_space.mountings.items()
    assert mounting.fixed and len(mounting.sides) == 5 and len(mounting.cables) == 5
    around = cage_space.initial()["cut"]["wall 0"][1, 0]  # (n, -n): n meshes across
    stretched = 5 * 2 * float(around) * 0.1
    np.testing.assert_allclose(mounting.stretched_length, stretched, rtol=1e-14)
    scene = cage_space.scene({"hanging_ratio": {name: 0.6}})
    x = np.asarray(scene.nodes.position)
    layout = cage_space.net.layout
    mounted = 0.0
    for side in mounting.sides:
        nodes = layout.panel_nodes[side.panel][layout.meshes[side.panel].side_nodes[side.index]]
        mounted += np.linalg.norm(np.diff(x[nodes], axis=0), axis=1).sum()
        np.testing.assert_array_equal(x[nodes, 2], 0.0)
    np.testing.assert_allclose(mounted, 0.6 * stretched, rtol=1e-13)
    collar = np.isin(np.asarray(ref.bars.cable), [ref.cable_names.index(c) for c in mounting.cables])
    np.testing.assert_allclose(np.asarray(scene.bars.rest_length)[collar].sum(), 0.6 * stretched, rtol=1e-13)
    moved = np.flatnonzero(np.any(x != np.asarray(ref.nodes.position), axis=1))
    assert np.asarray(ref.nodes.fixed)[moved][:, :2].all()  # only the collar moved


# -- the netting maker's terms ------------------------------------------------------------------------------


@pytest.mark.parametrize("d_uv, rate", [((3, 1), "1N2B"), ((1, 1), "AN"), ((1, 0), "AB"), ((0, -4), "AB"),
                                        ((1, -1), "AT"), ((-5, -5), "AN"), ((6, 2), "1N2B"), ((30, 50), "3N2B"),
                                        ((3, -1), "1T2B"), ((-4, 2), "1T1B"), ((2, 7), "2N5B")])
def test_cutting_rates(d_uv, rate):
    assert cut.cutting_rate(*d_uv) == rate


def test_a_tapered_panel_as_the_netting_maker_reads_it():
    """100 meshes at the top, 80 at the bottom, 40 deep: the tapered sides lose 10 meshes over 40, i.e. 20 bars
    and 30 points, 3N2B; the panel holds (100 + 80) × 40 / 2 meshes."""
    corners = cut.trapezoid(100, 80, 40)
    sides = cut.describe_sides(corners)
    assert [(s.meshes, s.rate) for s in sides] == [(100, "AT"), (40, "3N2B"), (80, "AT"), (40, "3N2B")]
    assert sides[1].steps == {"N": 30, "T": 0, "B": 20}
    assert float(cut.panel_meshes(corners)) == 3600.0
    np.testing.assert_allclose(np.asarray(cut.twine_to_mesh(corners))[2], [90, 40])


def test_round_cut_recovers_a_perturbed_cut():
    exact = np.asarray(cut.trapezoid(100, 80, 40)) + np.array([3.0, -1.0])
    noisy = exact + np.random.default_rng(0).uniform(-0.2, 0.2, exact.shape)
    rounded, sides = cut.round_cut(noisy, name="belly")
    np.testing.assert_array_equal(rounded[0], noisy[0])  # corner 0 stays
    np.testing.assert_allclose(rounded - rounded[0], exact - exact[0], rtol=0, atol=1e-12)
    assert [s.rate for s in sides] == ["AT", "3N2B", "AT", "3N2B"]
    with pytest.raises(ValueError, match="panel 'sliver'.*corners 1 and 2"):
        cut.round_cut([(0.0, 0.0), (3.0, 1.0), (3.2, 1.3)], name="sliver")
    with pytest.raises(ValueError, match="not a whole number"):
        cut.cutting_rate(1.5, 0.0)


def test_rounded_design(rig_space):
    corners = np.asarray(rig_space.initial()["cut"]["trap"])
    noisy = corners + np.random.default_rng(1).uniform(-0.2, 0.2, corners.shape)
    theta, report = rig_space.rounded({"cut": {"trap": noisy}, "mesh_side": {"trap": 0.06}})
    # each corner's change from the reference rounds to whole meshes: less than half a mesh is none
    np.testing.assert_allclose(np.asarray(theta["cut"]["trap"]), corners, atol=1e-12)
    assert float(theta["mesh_side"]["trap"]) == 0.06
    assert [(s.meshes, s.rate) for s in report["trap"]] == [(6, "AT"), (4, "3N2B"), (4, "AT"), (4, "3N2B")]
    text = rig_space.describe(theta)
    assert "side 1: 4 meshes, 3N2B" in text and "mesh_side['trap'] = 0.06 m" in text


def test_rounding_keeps_a_cut_drawn_on_half_meshes():
    """FEMNET's files put corners on half meshes: rounding the change from the drawn cut keeps the drawing, and
    moves a corner by whole meshes (or whole twines) from it."""
    drawn = np.asarray(cut.mesh_to_twine(np.array([[0.0, 0.0], [58.5, 0.0], [69.0, 54.0], [0.0, 58.5]])))
    same, _ = cut.round_cut(drawn + 0.3, name="wing", reference=drawn)
    np.testing.assert_array_equal(same, drawn + np.rint(np.asarray(cut.twine_to_mesh(np.full(2, 0.3)))))
    change = np.array([[0.0, 0.0], [1.3, -0.2], [0.0, 2.6], [-0.4, 0.45]])  # (u, v) meshes
    moved, sides = cut.round_cut(drawn + np.asarray(cut.mesh_to_twine(change)), name="wing", reference=drawn)
    np.testing.assert_allclose(np.asarray(cut.twine_to_mesh(moved - drawn)), [[0, 0], [1, 0], [0, 3], [0, 0]],
                               atol=1e-12)
    assert sides[0].meshes == 59.5  # 58.5 meshes drawn along side 0, one more
    by_twine, _ = cut.round_cut(drawn + np.array([[0.2, 0.0], [1.6, -0.2], [0.0, 0.0], [0.0, 0.0]]), name="wing",
                                reference=drawn, step="twine")
    np.testing.assert_allclose(by_twine - drawn, [[0, 0], [2, 0], [0, 0], [0, 0]], atol=1e-12)
    with pytest.raises(ValueError, match="step must be one of"):
        cut.round_cut(drawn, name="wing", step="knot")


# -- bad designs ------------------------------------------------------------------------------------------------


def test_bad_designs_are_named(panel_space):
    corners = np.asarray(panel_space.initial()["cut"]["netting"])
    space = panel_space
    cases = [
        ({"mesh_size": {}}, "unknown family 'mesh_size'"),
        ({"cut": {"net": corners}}, r"cut: no entry 'net'"),
        ({"cut": {"netting": corners[:3]}}, r"cut\['netting'\]: expected shape \(4, 2\)"),
        ({"cut": {"netting": np.where(np.arange(8).reshape(4, 2) == 5, np.nan, corners)}},
         r"cut\['netting'\].*corner 2"),
        ({"cut": {"netting": corners[[0, 2, 1, 3]]}}, r"cut\['netting'\].*cross"),
        ({"cut": {"netting": corners[[0, 1, 1, 3]]}}, r"cut\['netting'\].*corners 1 and 2"),
        ({"cut": {"netting": np.array([corners[0], corners[1], 0.8 * corners[0] + 0.2 * corners[2], corners[3]])}},
         r"cut\['netting'\]: triangle \d+ of the reference mesh turns over"),
        ({"mesh_side": {"netting": -0.01}}, r"mesh_side\['netting'\].*> 0"),
        ({"ea": {"netting": 0.0}}, r"ea\['netting'\].*> 0"),
        ({"hanging_ratio": {"headline": 0.0}}, r"hanging_ratio\['headline'\].*> 0"),
        ({"cable_length": {"headline": 0.3}}, r"cable_length\['headline'\].*hanging_ratio\['headline'\]"),
    ]
    for theta, message in cases:
        with pytest.raises(ValueError, match=message):
            space.scene(theta)
    # a concrete value closed over by a jitted function is checked while tracing, before compiling
    with pytest.raises(ValueError, match=r"mesh_side\['netting'\].*> 0"):
        jax.jit(lambda x: space.scene({"mesh_side": {"netting": -0.01}, "ea": {"netting": x}}).netting.l0)(1000.0)


def test_a_design_never_switches_a_term_on_silently():
    net = framed_panel(meshes=4, step=0.1, sinker_kg=0.0).net
    # a sinker of 0 kg at the reference: no node weight is compiled for it
    net.sinker(Nearest("netting", (0.07, 0.07, 0.0)), 0.0)
    space = DesignSpace(net)
    name, = space.initial()["sinker_mass"]
    with pytest.raises(ValueError, match=r"model terms the reference design does not have \(node_weight\)"):
        space.scene({"sinker_mass": {name: 2.0}})
    heavy = DesignSpace(framed_panel(meshes=4, step=0.1, sinker_kg=3.0))
    name, = heavy.initial()["sinker_mass"]
    scene = heavy.scene({"sinker_mass": {name: 0.0}})  # the term stays, weighing nothing
    np.testing.assert_array_equal(np.asarray(scene.nodes.mass), 0.0)
