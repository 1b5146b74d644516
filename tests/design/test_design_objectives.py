"""Design objectives and constraints (jaxnet.design.objectives): each figure against an independent value
(a conservation law or a closed form), its gradients in the positions and in the scene's float leaves
against central finite differences or closed forms, and the penalty, bounds and batching machinery.

Scenes: a hanging panel of 4 x 4 meshes blown by a current (twines, ropes, weight, drag), the fish cage
meshed at 2 m as drawn (an octagonal prism: volumes in closed form), a cod-end of 8 x 6 meshes holding a
small catch, a hexagonal-mesh panel of 3 x 3 base meshes as drawn. Every figure is evaluated by one jitted
function of (figure, outcome), and differentiated by one jitted gradient with respect to the whole outcome
(positions and every float leaf of the scene): a figure type compiles about twice per scene. Finite
differences are central, in float64; tolerances stated where used.
"""

import dataclasses

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import figures
from jaxnet.design import constraints as cs, objectives as ob
from jaxnet.net import HexTwine, Net, Twine
from jaxnet.scene import Environment
from jaxnet.scenes import codend, fish_cage, hanging_panel
from jaxnet.solve import statics

#: a figure's value; the figure is an argument (its settings are leaves), the outcome's scene too
evaluate = eqx.filter_jit(lambda figure, o: figure(o))
#: its gradient with respect to every float leaf of the outcome: the positions and the scene's parameters
gradient = eqx.filter_jit(eqx.filter_grad(lambda o, figure: figure(o)))

PANEL_MESHES, PANEL_L0 = 4, 0.025


@pytest.fixture(scope="module")
def panel():
    """The hanging panel blown by a 1 m/s current across it, solved to 1e-9 N."""
    net = hanging_panel(meshes=PANEL_MESHES, l0=PANEL_L0, step=0.05).net
    net.environment = Environment(current_speed=1.0, current_direction=np.array([1.0, 1.0, 0.0]))
    scene = net.build()
    eq = statics.solve(scene, tol=1e-9)
    return scene, eq, ob.outcome(eq, scene)


@pytest.fixture(scope="module")
def cage():
    """The fish cage as drawn (not solved): an octagonal prism 5 m in radius and depth, with a flat bottom."""
    scene = fish_cage(step=2.0).scene
    return scene, ob.outcome(scene.nodes.position, scene)


@pytest.fixture(scope="module")
def cod_end():
    """The built-in cod-end, 8 x 6 meshes, its twine without knots (a program half the size to compile);
    the net holds ~0.01 m³ at equilibrium: a catch of 0.004 m³ puts the catch front inside it."""
    twine = Twine(l0=0.06, ea=1e5, diameter=4e-3, density=1025.0)
    scene = codend(meshes_around=8, meshes_along=6, step=0.12, catch_m3=0.004, twine=twine).scene
    eq = statics.solve(scene, tol=1e-9)
    return scene, eq, ob.outcome(eq, scene)


def replace(scene, family, **leaves):
    return dataclasses.replace(scene, **{family: dataclasses.replace(getattr(scene, family), **leaves)})


def moved(o, x):
    return ob.Outcome(jnp.asarray(x), o.scene, o.model)


def unit_direction(shape, seed):
    v = np.random.default_rng(seed).normal(size=shape)
    return jnp.asarray(v / np.linalg.norm(v))


def check_position_gradient(figure, o, seed, h, rtol):
    """The gradient of ``figure`` along a random unit direction v of the positions against the central
    difference (f(x + h v) - f(x - h v)) / 2h; returns the whole gradient (an Outcome of derivatives)."""
    v = unit_direction(o.x.shape, seed)
    g = gradient(o, figure)
    fd = (evaluate(figure, moved(o, o.x + h * v)) - evaluate(figure, moved(o, o.x - h * v))) / (2 * h)
    assert np.all(np.isfinite(np.asarray(g.x)))
    np.testing.assert_allclose(float(jnp.sum(g.x * v)), float(fd), rtol=rtol)
    return g


# -- drag: the reactions balance the water's force ------------------------------------------------


def water_force_by_balance(scene, eq, direction):
    """What the water must exert on the net along ``direction`` (N), from the solve's balance: the sum over
    nodes of reactions + loads + water forces is the sum of the residuals at the free coordinates (the
    twines' and knots' forces are internal and sum to zero)."""
    free_residual = np.where(np.asarray(scene.nodes.fixed), 0.0, np.asarray(eq.force)).sum(axis=0)
    balance = free_residual - eq.reaction(scene).sum(axis=0) - figures.total_load(scene)
    return float(balance @ (np.asarray(direction) / np.linalg.norm(direction)))


def test_panel_drag_balances_the_reactions_and_weight_along_every_axis(panel):
    scene, eq, o = panel
    current = scene.environment.current_direction
    along = float(evaluate(ob.drag(direction=current), o))
    assert along > 1.0
    np.testing.assert_allclose(along, water_force_by_balance(scene, eq, current), rtol=1e-9)
    for axis in np.eye(3) * 2.0:  # any length: normalised; along z the reactions also carry the weight
        value = float(evaluate(ob.drag(direction=axis), o))
        np.testing.assert_allclose(value, water_force_by_balance(scene, eq, axis), rtol=1e-9, atol=1e-12)


def test_cod_end_drag_with_catch_balances_the_reactions(cod_end):
    scene, eq, o = cod_end
    total = float(evaluate(ob.drag(), o))  # along the current (the default), the catch's pressure included
    assert total > 1.0
    np.testing.assert_allclose(total, water_force_by_balance(scene, eq, scene.environment.current_direction), rtol=1e-9)


def test_catch_diameter_is_femnets_figure_and_its_gradient(cod_end):
    """The catch diameter against result.json's (figures.catch_report, another program) and against its
    definition: twice the largest distance from the axis, across it, of the netting nodes behind the front."""
    scene, eq, o = cod_end
    value = float(evaluate(ob.catch_diameter(), o))
    report = figures.catch_report(scene, np.asarray(eq.x))
    assert value == pytest.approx(report["diameter_m"], rel=1e-12)
    x = np.asarray(eq.x)
    c = scene.catch
    axis = np.asarray(c.axis) / np.linalg.norm(c.axis)
    netting = np.unique(np.asarray(scene.netting.vertices))
    behind = netting[x[netting] @ axis >= report["front_m"]]
    e1 = np.cross([0.0, 0.0, 1.0], axis)  # FEMNET's transverse axes: horizontal, then axis ^ horizontal
    e1 /= np.linalg.norm(e1)
    across = np.abs((x[behind] - np.asarray(c.center)) @ np.stack([e1, np.cross(axis, e1)]).T)
    assert value == pytest.approx(2.0 * across.max(), rel=1e-9)
    assert value > 0.0
    # a maximum over nodes (a ring of them ties on this symmetric cod-end): its gradient is the farthest node's,
    # 2 along its transverse direction, of unit length times 2
    g = np.asarray(gradient(o, ob.catch_diameter()).x)
    moved_nodes = np.flatnonzero(np.linalg.norm(g, axis=1) > 0)
    assert len(moved_nodes) == 1 and moved_nodes[0] in behind
    assert np.linalg.norm(g[moved_nodes[0]]) == pytest.approx(2.0, rel=1e-12)
    assert abs(float(g[moved_nodes[0]] @ axis)) < 1e-12
    with pytest.raises(ValueError, match="catch_diameter: the scene has no catch"):
        evaluate(ob.catch_diameter(), ob.outcome(fish_cage(step=2.0).scene.nodes.position, fish_cage(step=2.0).scene))


def test_drag_gradients_in_positions_and_twine_diameter(panel):
    scene, _, o = panel
    figure = ob.drag(direction=scene.environment.current_direction)
    g = check_position_gradient(figure, o, seed=0, h=1e-6, rtol=1e-7)
    # twine diameter D: the twines' drag is linear in D (projected area D l0), the ropes' does not depend
    # on it, so D·∂drag/∂D = drag(D) - drag(0), the netting's own drag (less than the total: ropes drag too)
    d = scene.netting.diameter
    by_gradient = float(np.sum(np.asarray(g.scene.netting.diameter) * d))
    without = float(evaluate(figure, ob.Outcome(o.x, replace(scene, "netting", diameter=0.0 * d), o.model)))
    total = float(evaluate(figure, o))
    np.testing.assert_allclose(by_gradient, total - without, rtol=1e-10)
    assert 0.0 < by_gradient < total


# -- volume -----------------------------------------------------------------------------------------


def test_volume_of_the_octagonal_cage_and_its_affine_images(cage):
    scene, start = cage
    sides, radius, depth = 8, 5.0, 5.0
    prism = 0.5 * sides * radius**2 * np.sin(2 * np.pi / sides) * depth  # the start shape, by hand
    np.testing.assert_allclose(float(evaluate(ob.volume(), start)), prism, rtol=1e-12)
    # stretching x, y by a and z by b scales every volume by a² b
    a, b = 1.3, 0.7
    np.testing.assert_allclose(float(evaluate(ob.volume(), moved(start, start.x * jnp.array([a, a, b])))),
                               a * a * b * prism, rtol=1e-12)
    # d/da of V(a x, a y, z) at a = 1 is 2 V: the gradient along the radial stretch
    g = gradient(start, ob.volume())
    np.testing.assert_allclose(float(jnp.sum(g.x[:, :2] * start.x[:, :2])), 2 * prism, rtol=1e-12)
    # a plane of one's own: half way down, the prism below it holds half the wall's volume
    lower = ob.volume(center=(0.0, 0.0, -2.5), axis=(0.0, 0.0, -3.0))
    np.testing.assert_allclose(float(evaluate(lower, start)), prism / 2, rtol=1e-12)


def test_volume_gradient_with_elements_cut_by_the_plane(cage):
    scene, start = cage
    # the collar lies in the plane: shaken by 5 cm, some of its elements are cut by it
    shaken = moved(start, start.x + 0.05 * jnp.asarray(np.random.default_rng(1).normal(size=start.x.shape)))
    check_position_gradient(ob.volume(), shaken, seed=2, h=1e-6, rtol=1e-7)


def test_cod_end_volume_and_mouth_opening(cod_end):
    scene, _, o = cod_end
    c = scene.catch
    whole = float(evaluate(ob.volume(), o))  # behind the catch's plane, the whole cod-end (× symmetry)
    quarter = float(evaluate(ob.volume(center=c.center, axis=c.axis), o))
    np.testing.assert_allclose(whole, c.symmetry * quarter, rtol=1e-14)
    assert whole > c.volume  # it holds its catch
    x = np.asarray(o.x)
    mouth = np.flatnonzero(np.abs(x[:, 0]) < 1e-12)  # the front, fixed on the plane x = 0
    mouth = mouth[np.argsort(np.arctan2(x[mouth, 2], x[mouth, 1]))]
    # the quarter mouth is the straight side from (0, 0, r) to (0, r, 0): a right triangle with the axis
    radius = 8 * 2 * 0.06 * np.sin(0.1) / (2 * np.pi)
    figure = ob.opening(mouth, center=(0.0, 0.0, 0.0), symmetry=4)  # projected along the current, x
    np.testing.assert_allclose(float(evaluate(figure, o)), 2 * radius**2, rtol=1e-9)


# -- opening and shape ------------------------------------------------------------------------------


def test_opening_of_a_tilted_regular_polygon(panel):
    scene, _, o = panel
    k, radius, tilt = 7, 0.3, 0.4
    angle = 2 * np.pi * np.arange(k) / k
    # a regular k-gon of the given radius, in a plane tilted by `tilt` about y
    ring = radius * np.stack([np.cos(angle) * np.cos(tilt), np.sin(angle), np.cos(angle) * np.sin(tilt)], 1)
    centre = np.array([1.0, -2.0, 0.5])
    x = np.asarray(o.x).copy()
    x[:k] = ring + centre
    area = 0.5 * k * radius**2 * np.sin(2 * np.pi / k) * np.cos(tilt)  # projected on the horizontal
    up = (0.0, 0.0, 1.0)
    for order in (range(k), range(k)[::-1]):  # either orientation
        np.testing.assert_allclose(float(evaluate(ob.opening(order, axis=up), moved(o, x))), area, rtol=1e-12)
    # d area / d radius = 2 area / radius: the gradient along the ring's scaling about its centre
    g = gradient(moved(o, x), ob.opening(range(k), axis=up))
    np.testing.assert_allclose(float(np.sum(np.asarray(g.x[:k]) * ring)) / radius, 2 * area / radius, rtol=1e-12)
    # an arc closed through a centre: a quarter of a regular 4m-gon, four times
    m = 3
    quarter = np.pi / 2 * np.arange(m + 1) / m
    x[: m + 1] = 0.2 * np.stack([np.cos(quarter), np.sin(quarter), np.zeros(m + 1)], 1) + np.array([1.0, 1.0, 7.0])
    arc = ob.opening(range(m + 1), axis=up, center=(1.0, 1.0, -3.0), symmetry=4)
    np.testing.assert_allclose(float(evaluate(arc, moved(o, x))), 0.5 * 4 * m * 0.2**2 * np.sin(2 * np.pi / (4 * m)),
                               rtol=1e-12)


def test_shape_distance_values_and_gradients(panel):
    scene, _, o = panel
    x = np.asarray(o.x)
    np.testing.assert_allclose(float(evaluate(ob.shape_distance(x + np.array([0.03, -0.04, 0.0])), o)), 0.05,
                               rtol=1e-12)
    # two nodes, weighted: sqrt((w0 a² + w1 b²) / (w0 + w1))
    target = x[[2, 5]] + np.array([[0.1, 0.0, 0.0], [0.0, 0.0, 0.3]])
    figure = ob.shape_distance(target, nodes=[2, 5], weights=[3.0, 1.0])
    np.testing.assert_allclose(float(evaluate(figure, o)), np.sqrt((3 * 0.01 + 0.09) / 4), rtol=1e-12)
    squared = ob.shape_distance(target, nodes=[2, 5], weights=[3.0, 1.0], squared=True)
    np.testing.assert_allclose(float(evaluate(squared, o)), (3 * 0.01 + 0.09) / 4, rtol=1e-12)
    check_position_gradient(figure, o, seed=3, h=1e-6, rtol=1e-8)
    # at the target itself the RMS has a cone: value 0, gradient finite (taken as 0)
    on_target = x.copy()
    on_target[[2, 5]] = target
    assert float(evaluate(figure, moved(o, on_target))) == 0.0
    assert np.all(np.asarray(gradient(moved(o, on_target), figure).x) == 0.0)


# -- tensions -------------------------------------------------------------------------------------


def test_smooth_max_tension_is_within_its_bound_of_the_true_max(panel):
    scene, eq, o = panel
    twines = figures.twine_tensions(scene, eq.x).ravel()
    true = np.concatenate([twines, figures.bar_tensions(scene, eq.x)])
    n = 2 * scene.netting.vertices.shape[0] + scene.bars.ends.shape[0]
    assert true.size == n
    rounding = 1e-12 * true.max()  # (T / τ) τ is T to rounding
    for softness in (1.0, 1e-3):
        figure = ob.max_tension(softness)
        m = float(evaluate(figure, o))
        assert true.max() - rounding <= m <= true.max() + softness * np.log(n)
        np.testing.assert_allclose(float(figure.excess_bound(o)), softness * np.log(n), rtol=1e-14)
        # the log-sum-exp itself, by numpy
        np.testing.assert_allclose(m, true.max() + softness * np.log(np.sum(np.exp((true - true.max()) / softness))),
                                   rtol=1e-11)
    # twines only: the ropes are left out
    m = float(evaluate(ob.max_tension(1e-3, families=("netting",)), o))
    assert twines.max() - rounding <= m <= twines.max() + 1e-3 * np.log(twines.size)
    assert twines.max() < true.max() - 1.0  # the headline pulls harder than any twine: it was left out


def test_max_tension_gradients_in_positions_and_stiffness(panel):
    scene, _, o = panel
    softness = 1.0
    figure = ob.max_tension(softness, families=("netting",))
    # positions: h = 3e-8 m (stiff twines, EA/l0 = 8e4 N/m: the truncation error grows as (EA/l0)³ h²/τ²)
    g = check_position_gradient(figure, o, seed=4, h=3e-8, rtol=1e-6)
    # EA at fixed positions: T_i ∝ EA where the twine is in traction, so EA·∂M/∂EA = Σ softmax_i T_i [T_i > 0]
    t = figures.twine_tensions(scene, o.x).T.ravel()  # (Tu of every triangle, then Tv), as the figure
    w = np.exp((t - t.max()) / softness)
    expected = np.sum(w / w.sum() * np.where(t > 0, t, 0.0))
    by_gradient = float(np.sum(np.asarray(g.scene.netting.ea_traction) * scene.netting.ea_traction))
    np.testing.assert_allclose(by_gradient, expected, rtol=1e-10)


def test_max_tension_of_slack_netting_has_finite_gradients(panel):
    scene, _, o = panel
    slack = ob.Outcome(o.x, replace(scene, "netting", ea_compression=np.zeros_like(scene.netting.ea_compression)),
                       o.model)
    figure = ob.max_tension(0.5, families=("netting",))
    # every twine 10 % shorter than its rest length: all slack, all tensions 0, so M = τ log n exactly
    shrunk = moved(slack, 0.9 * jnp.asarray(scene.nodes.position))
    np.testing.assert_allclose(float(evaluate(figure, shrunk)), 0.5 * np.log(2 * scene.netting.vertices.shape[0]),
                               rtol=1e-14)
    assert np.all(np.asarray(gradient(shrunk, figure).x) == 0.0)
    # at the stress-free start every twine sits on its slack kink: still finite
    assert np.all(np.isfinite(np.asarray(gradient(moved(slack, scene.nodes.position), figure).x)))


# -- material -------------------------------------------------------------------------------------


def test_panel_material_against_its_mesh_count(panel):
    scene, _, o = panel
    n, l0 = PANEL_MESHES, PANEL_L0
    d, rho = float(scene.netting.diameter[0]), float(scene.netting.density[0])
    # n x n square meshes of side l0 fill a square of side W = n l0 √2; a square lattice of spacing l0
    # has 2/l0 metres of line per m², so W² · 2 / l0 = 4 n² l0 of twine
    length = 4 * n**2 * l0
    width = n * l0 * np.sqrt(2.0)
    np.testing.assert_allclose(float(evaluate(ob.twine_length(), o)), length, rtol=1e-12)
    mass = length * np.pi * d**2 / 4 * rho
    np.testing.assert_allclose(float(evaluate(ob.material(), o)), mass, rtol=1e-12)
    np.testing.assert_allclose(float(evaluate(ob.material(price_per_kg=7.5), o)), 7.5 * mass, rtol=1e-12)
    # with the ropes: the headline and the sinker bar, each a side W long
    np.testing.assert_allclose(float(evaluate(ob.twine_length(families=("netting", "bars")), o)), length + 2 * width,
                               rtol=1e-12)
    np.testing.assert_allclose(float(evaluate(ob.netting_area(), o)), width**2, rtol=1e-12)
    start = moved(o, scene.nodes.position)  # drawn flat with square meshes
    np.testing.assert_allclose(float(evaluate(ob.netting_area(deployed=True), start)), width**2, rtol=1e-12)
    # mass ∝ D²: D·∂mass/∂D = 2 mass; and the mass does not depend on the positions
    g = gradient(o, ob.material())
    np.testing.assert_allclose(float(np.sum(np.asarray(g.scene.netting.diameter) * scene.netting.diameter)), 2 * mass,
                               rtol=1e-12)
    assert np.all(np.asarray(g.x) == 0.0)


def test_hexagonal_netting_material():
    # a panel of 3 x 3 base meshes, each holding 2 twines of each family l, m, n (lengths a, a, 1.2 a)
    meshes, a = 3, 0.02
    net = Net()
    w = meshes * 3 * a
    corners = [(0, 0, -w, 0, 0), (w, 0, -w, meshes, 0), (w, 0, 0, meshes, meshes), (0, 0, 0, 0, meshes)]
    twine = HexTwine(l0=(a, a, 1.2 * a), ea=1000.0, diameter=1e-3)
    panel = net.panel("hex", corners, twine, step=0.05)
    net.fix(panel.side(2))
    scene = net.build()
    o = ob.outcome(scene.nodes.position, scene)
    length = meshes**2 * 2 * (a + a + 1.2 * a)
    np.testing.assert_allclose(float(evaluate(ob.twine_length(), o)), length, rtol=1e-12)
    np.testing.assert_allclose(float(evaluate(ob.material(), o)), length * np.pi * 1e-6 / 4 * 1140.0, rtol=1e-12)
    with pytest.raises(ValueError, match="netting_area: hexagonal"):
        ob.netting_area()(o)


# -- composition, constraints, bounds -------------------------------------------------------------


def test_weighted_constraints_and_penalty(panel):
    scene, _, o = panel
    area = float(evaluate(ob.netting_area(), o))
    mass = float(evaluate(ob.material(), o))
    both = cs.weighted(area=(2.0, ob.netting_area()), mass=ob.material())
    np.testing.assert_allclose(float(evaluate(both, o)), 2 * area + mass, rtol=1e-12)
    np.testing.assert_allclose([float(v) for v in both.parts(o).values()], [area, mass], rtol=1e-12)

    above = cs.Constraint(ob.netting_area(), upper=area / 4, scale=area / 10)
    below = cs.Constraint(ob.netting_area(), lower=area * 2)
    inside = cs.Constraint(ob.netting_area(), lower=0.0, upper=area * 2)
    np.testing.assert_allclose(float(above.violation(o)), 0.75 * area, rtol=1e-12)
    np.testing.assert_allclose(float(above.penalty(o)), 7.5**2, rtol=1e-12)
    np.testing.assert_allclose(float(below.violation(o)), area, rtol=1e-12)
    assert float(inside.violation(o)) == 0.0 and float(inside.penalty(o)) == 0.0
    objective = cs.penalised(ob.material(), [above, below, inside], weight=3.0)
    np.testing.assert_allclose(float(evaluate(objective, o)), mass + 3.0 * (7.5**2 + area**2), rtol=1e-12)
    np.testing.assert_allclose(float(objective.violation(o)), 7.5 + area, rtol=1e-12)

    # a penalty of the positions: gradient vs central differences (the exterior penalty is C¹)
    x = np.asarray(o.x)
    near = cs.Constraint(ob.shape_distance(x[:3] + 0.01, nodes=[0, 1, 2]), upper=0.005)
    assert float(near.violation(o)) > 0.01
    check_position_gradient(cs.penalised(ob.shape_distance(x + 0.02, squared=True), near, weight=10.0), o, seed=5,
                            h=1e-6, rtol=1e-7)


def test_bounds_projection_and_violation():
    theta = {"cut": np.array([-1.0, 0.5, 3.0]), "diameter": 2e-3, "ea": np.array([[100.0, 5000.0]])}
    box = cs.Bounds(lower={"cut": 0.0, "diameter": 1e-3, "ea": None},
                    upper={"cut": np.array([1.0, 1.0, 2.0]), "diameter": None, "ea": 1000.0})
    projected = box.project(theta)
    np.testing.assert_array_equal(projected["cut"], [0.0, 0.5, 2.0])
    assert float(projected["diameter"]) == 2e-3
    np.testing.assert_array_equal(projected["ea"], [[100.0, 1000.0]])
    np.testing.assert_allclose(float(box.violation(theta)), 1.0 + 1.0 + 4000.0, rtol=1e-15)
    assert float(box.violation(projected)) == 0.0
    # jit, and a (sub)gradient: -1 below a lower bound, +1 above an upper one, 0 inside
    g = jax.jit(jax.grad(box.violation))(theta)
    np.testing.assert_array_equal(g["cut"], [-1.0, 0.0, 1.0])
    np.testing.assert_array_equal(g["ea"], [[0.0, 1.0]])
    # one number for every leaf
    np.testing.assert_array_equal(cs.Bounds(lower=0.0).project(theta)["cut"], [0.0, 0.5, 3.0])
    # a partial bound: the keys left out are unbounded; nested dicts, as a design space's θ
    nested = {"twine": {"diameter": np.array([5e-4, 2e-3]), "l0": 0.02}, "cut": np.array([-1.0, 3.0])}
    partial = cs.Bounds(lower={"twine": {"diameter": 1e-3}}, upper={"cut": 2.0})
    np.testing.assert_array_equal(partial.project(nested)["twine"]["diameter"], [1e-3, 2e-3])
    np.testing.assert_array_equal(partial.project(nested)["cut"], [-1.0, 2.0])
    np.testing.assert_allclose(float(partial.violation(nested)), 5e-4 + 1.0, rtol=1e-15)
    with pytest.raises(ValueError, match=r"Bounds: lower\['twine'\]\['mesh'\] are not design parameters"):
        cs.Bounds(lower={"twine": {"mesh": 1.0}}).project(nested)
    with pytest.raises(ValueError, match="structure"):
        cs.Bounds(lower=[0.0, 1.0]).project(theta)
    with pytest.raises(ValueError, match=r"lower > upper for \['cut'\]"):
        cs.Bounds(lower={"cut": 2.5, "diameter": 0.0, "ea": 0.0},
                  upper={"cut": 1.0, "diameter": 1.0, "ea": 1.0}).project(theta)
    with pytest.raises(ValueError, match=r"upper bound of \['cut'\] has shape \(2,\)"):
        cs.Bounds(upper={"cut": np.ones(2), "diameter": None, "ea": None}).project(theta)
    with pytest.raises(ValueError, match=r"Bounds: lower\['ea'\] is NaN"):
        cs.Bounds(lower={"cut": 0.0, "diameter": 0.0, "ea": np.array([np.nan])})


def test_figures_vmap_over_a_batch_of_positions_and_designs(panel):
    scene, _, o = panel
    drag, tension, shape = ob.drag(direction=scene.environment.current_direction), ob.max_tension(0.5), \
        ob.shape_distance(np.asarray(o.x))
    objective = cs.weighted(drag=drag, tension=(0.1, tension), shape=(10.0, shape))
    xs = o.x[None] + 0.01 * jnp.asarray(np.random.default_rng(6).normal(size=(3,) + o.x.shape))
    scales = jnp.array([0.5, 1.0, 2.0])  # twine diameters D·s

    def outcome(x, s):
        return ob.Outcome(x, replace(scene, "netting", diameter=scene.netting.diameter * s), o.model)

    values = jax.jit(jax.vmap(lambda x, s: objective(outcome(x, s))))(xs, scales)
    singly = [float(evaluate(drag, outcome(x, s)) + 0.1 * evaluate(tension, outcome(x, s))
                    + 10.0 * evaluate(shape, outcome(x, s))) for x, s in zip(xs, np.asarray(scales))]
    np.testing.assert_allclose(np.asarray(values), singly, rtol=1e-12)
    assert len(set(np.round(singly, 6))) == 3


def test_bad_settings_name_the_culprit(panel):
    scene, _, o = panel
    with pytest.raises(ValueError, match="drag: terms"):
        ob.drag(terms=("netting_tension",))
    with pytest.raises(ValueError, match="drag: direction"):
        ob.drag(direction=(0.0, 0.0, 0.0))
    with pytest.raises(ValueError, match=r"opening: nodes: node index 99 outside 0\.\.14"):
        ob.opening([0, 1, 99], axis=(0, 0, 1))(o)
    with pytest.raises(ValueError, match="opening: nodes must be"):
        ob.opening([0, 1], axis=(0, 0, 1))
    with pytest.raises(ValueError, match="shape_distance: 2 nodes but 3 target"):
        ob.shape_distance(np.zeros((3, 3)), nodes=[0, 1])
    with pytest.raises(ValueError, match="max_tension: softness"):
        ob.max_tension(0.0)
    with pytest.raises(ValueError, match="neither an enclosure nor a catch"):
        outward = np.ones(scene.netting.vertices.shape[0])
        ob.volume()(ob.Outcome(o.x, replace(scene, "netting", outward=outward), o.model))
    with pytest.raises(ValueError, match="Constraint: lower 2.0 > upper 1.0"):
        cs.Constraint(ob.material(), lower=2.0, upper=1.0)
    with pytest.raises(ValueError, match="Constraint: give lower"):
        cs.Constraint(ob.material())
    with pytest.raises(ValueError, match="outcome: x has 3 nodes"):
        ob.outcome(np.zeros((3, 3)), scene)
    with pytest.raises(ValueError, match="weighted: mass is not a figure"):
        cs.weighted(mass=(1.0, "material"))

