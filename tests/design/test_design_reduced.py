"""Reduced design vectors (jaxnet.design.reduced) and the account of an optimisation (jaxnet.design.report).

A small panel (4 x 4 meshes, the rig of tests/design/test_design_optimize.py) hangs in a current. The design vector
z = {"size": (across, along) factors of the panel's cut, "diameter": its twine diameter (m)} maps to θ by the
ready-made maps. The maps are checked against their definitions, their derivatives against the chain rule
through the full θ and against central differences, an optimisation on z recovers a target design whose cut
is one mesh wider (its rounded cut is the target's), its account prints as tables whose numbers are the cut
report's, and bad input is refused before anything compiles, naming the culprit."""

import functools
import re

import jax
import jax.numpy as jnp
import numpy as np
import optax
import pytest

import jaxnet  # noqa: F401
from jaxnet.design import constraints, cut, objectives, optimize, reduced, report, space as space_lib
from jaxnet.scene import Environment
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import implicit

STEPS = 12
#: the target: one mesh wider (5 across instead of 4), the same depth, a twine 10 % thicker
TARGET = {"size": np.array([1.25, 1.0]), "diameter": np.asarray(1.1 * 1.5e-3)}
#: the least diameter the optimiser may take (a bound on z, m); unbounded it dips to 1.36 mm on the way
LEAST_DIAMETER = 1.45e-3


@functools.lru_cache(maxsize=1)
def problem():
    net = hanging_panel(meshes=4, step=0.05).net
    net.environment = Environment(current_speed=0.4, current_direction=np.array([0.0, 1.0, 0.0]))
    space = space_lib.DesignSpace(net)
    design = reduced.combine(size=reduced.scale_cut(space, ["netting"]),
                             diameter=reduced.one_value("twine_diameter", ["netting"]))
    z0 = {"size": np.array([1.0, 1.0]), "diameter": np.asarray(float(space.initial()["twine_diameter"]["netting"]))}
    target_x = np.asarray(implicit.solve(space.scene(design(TARGET))).x)
    return space, design, z0, target_x


def test_the_maps_are_what_they_say():
    space, design, z0, _ = problem()
    reference = np.asarray(space.initial()["cut"]["netting"])
    scale = reduced.scale_cut(space, ["netting"])
    np.testing.assert_array_equal(np.asarray(scale(1.0)["cut"]["netting"]), reference)
    # 1.25 across, 1 along: 5 meshes across, 4 deep, corner 0 where it was; rates AT and AN
    wider = np.asarray(scale(jnp.array([1.25, 1.0]))["cut"]["netting"])
    np.testing.assert_allclose(wider, [[0, 0], [5, -5], [9, -1], [4, 4]], atol=1e-14)
    assert [(s.meshes, s.rate) for s in cut.describe_sides(wider)] == [(5, "AT"), (4, "AN"), (5, "AT"), (4, "AN")]
    # twice as large both ways: four times the meshes
    assert float(cut.panel_meshes(scale(2.0)["cut"]["netting"])) == pytest.approx(4 * 16.0, rel=1e-14)
    # a taper from 0.6 to 0.8 along the two ropes, one value for both: linear, endpoints exact
    ropes = ["headline", "sinker bar"]
    tapered = reduced.taper("hanging_ratio", ropes)(jnp.array([0.6, 0.8]))["hanging_ratio"]
    assert {k: float(v) for k, v in tapered.items()} == {"headline": 0.6, "sinker bar": 0.8}
    three = reduced.taper("mesh_side", ["a", "b", "c"])(jnp.array([1.0, 2.0]))["mesh_side"]
    assert float(three["b"]) == 1.5
    assert reduced.one_value("hanging_ratio", ropes)(0.7) == {"hanging_ratio": {"headline": 0.7, "sinker bar": 0.7}}
    theta = design(z0)
    assert set(theta) == {"cut", "twine_diameter"} and float(theta["twine_diameter"]["netting"]) == 1.5e-3
    assert reduced.coordinate_names(z0) == ["diameter", "size[0]", "size[1]"]
    assert reduced.coordinate_names(jnp.zeros(2)) == ["z[0]", "z[1]"]


def test_the_reduced_gradient_is_the_chain_rule_through_theta():
    """d F(design(z)) / dz by jax.grad equals Σ ∂F/∂θ · dθ/dz (jax.jvp of the map, the full θ gradient) and
    central differences, F the drag of the scene at fixed positions plus its ropes' mounted lengths: every
    entry the map sets (the cut, the diameter, the ropes' E) matters."""
    space, _, _, target_x = problem()
    structure = implicit.structure_of(space.reference)
    x = jnp.asarray(target_x)
    drag = objectives.drag()

    def f(theta):
        ropes = sum(space.mounted_length(theta).values())
        return drag(objectives.Outcome(x, space.scene(theta), structure.model)) + 0.1 * ropes

    design = reduced.combine(size=reduced.scale_cut(space, ["netting"]),
                             diameter=reduced.one_value("twine_diameter", ["netting"]),
                             ropes=reduced.taper("hanging_ratio", ["headline", "sinker bar"]))
    z = {"size": jnp.array([1.1, 0.95]), "diameter": jnp.asarray(1.6e-3), "ropes": jnp.array([0.72, 0.69])}
    reduced_f = jax.jit(lambda zz: f(design(zz)))
    g = jax.jit(jax.grad(lambda zz: f(design(zz))))(z)
    g_theta = jax.jit(jax.grad(f))(design(z))
    unit = {"size": 1.0, "diameter": 1e-3, "ropes": 1.0}  # a step of each coordinate in its own units
    for part, leaf in z.items():
        for i in np.ndindex(np.shape(leaf)):
            e = jax.tree.map(jnp.zeros_like, z)
            e[part] = e[part].at[i].set(1.0)
            _, d_theta = jax.jvp(design, (z,), (e,))
            chain = sum(jnp.vdot(a, b) for a, b in zip(jax.tree.leaves(g_theta), jax.tree.leaves(d_theta)))
            np.testing.assert_allclose(float(g[part][i]), float(chain), rtol=1e-12, atol=1e-14 * abs(float(chain)))
            h = 1e-4 * unit[part]
            shifted = [reduced_f({**z, part: z[part].at[i].add(s * h)}) for s in (1, -1, 2, -2)]
            central = (8 * (shifted[0] - shifted[1]) - (shifted[2] - shifted[3])) / (12 * h)
            np.testing.assert_allclose(float(g[part][i]), float(central), rtol=1e-7)


@pytest.fixture(scope="module")
def optimised(tmp_path_factory):
    space, design, z0, target_x = problem()
    out = tmp_path_factory.mktemp("reduced")
    # the cut in meshes-factors (a step of 0.05 is a fifth of a mesh here), the diameter in millimetres
    result = optimize.optimize(space, objectives.shape_distance(target_x), z0, design=design,
                               optimizer=optax.adam(0.05), steps=STEPS, scale={"size": 1.0, "diameter": 1e-3},
                               bounds=constraints.Bounds(lower={"diameter": LEAST_DIAMETER}), out=out, progress=False)
    return result, out


def test_an_optimisation_on_z_recovers_the_target(optimised):
    result, out = optimised
    space, design, z0, _ = problem()
    h = result.history
    # the objective (RMS distance to the target shape, m) falls by 80 % at least
    assert len(h) == STEPS + 1 and result.reason == optimize.MAX_STEPS
    assert result.value < 0.2 * h[0]["objective"]
    # the history: z at the start, the best row is the result's, z within its bound at every step
    flat = lambda tree: [float(v) for leaf in jax.tree.leaves(tree) for v in np.ravel(leaf)]  # noqa: E731
    assert h[0]["z"] == flat(z0) and h[0]["violation"] == 0.0
    assert min(r["objective"] for r in h) == result.value == h[result.step]["objective"]
    assert h[result.step]["z"] == flat(result.z)
    assert all(r["z"][0] >= LEAST_DIAMETER - 1e-18 for r in h)
    # θ is the map of z, the start's too
    for family, entries in design(result.z).items():
        for name, value in entries.items():
            np.testing.assert_array_equal(np.asarray(result.theta[family][name]), np.asarray(value))
    np.testing.assert_array_equal(result.start["cut"]["netting"], space.initial()["cut"]["netting"])
    # rounded to whole meshes, the cut is the target's: 5 meshes across
    np.testing.assert_array_equal(np.asarray(result.rounded["cut"]["netting"]), [[0, 0], [5, -5], [9, -1], [4, 4]])
    target_sides = cut.describe_sides(design(TARGET)["cut"]["netting"])
    assert [str(s) for s in result.cut_report["netting"]] == [str(s) for s in target_sides]
    assert result.rounded_value < 0.2 * h[0]["objective"]
    assert (out / "design.json").exists() and len((out / "history.jsonl").read_text().splitlines()) == STEPS + 1


def _rows(text, header):
    """The rows of the table under the line starting with ``header``, split on runs of 2+ spaces."""
    lines = text.splitlines()
    start = next(k for k, line in enumerate(lines) if line.startswith(header))
    rows = []
    for line in lines[start + 1:]:
        if not line.strip():
            break
        rows.append(re.split(r" {2,}", line.strip()))
    return rows


def test_the_account_prints_as_tables_of_the_cut_report(optimised):
    result, _ = optimised
    space, design, z0, _ = problem()
    text = str(result)
    assert max(map(len, text.splitlines())) < report.WIDTH
    assert repr(result) == text
    assert text.startswith(f"stopped: {optimize.MAX_STEPS} after {STEPS} steps (best: step {result.step}); "
                           f"{sum(r['newton_iterations'] for r in result.history)} Newton iterations")
    objective = _rows(text, "stopped:")[1]
    assert objective[0] == "objective" and [float(v) for v in objective[1:]] == pytest.approx(
        [result.history[0]["objective"], result.value, result.rounded_value], rel=1e-6)
    z = {row[0]: [float(v) for v in row[1:]] for row in _rows(text, "design vector")}
    assert z == {"diameter": pytest.approx([1.5e-3, float(result.z["diameter"])], rel=1e-5),
                 "size[0]": pytest.approx([1.0, float(result.z["size"][0])], rel=1e-5),
                 "size[1]": pytest.approx([1.0, float(result.z["size"][1])], rel=1e-5)}
    # the cut: start and rounded columns are describe_sides' meshes and rates; the optimised one is real
    rows = _rows(text, "panel")
    start = cut.describe_sides(space.initial()["cut"]["netting"])
    assert [r[-3] for r in rows] == [f"{s.meshes:g} {s.rate}" for s in start]
    assert [r[-1] for r in rows] == [f"{s.meshes:g} {s.rate}" for s in result.cut_report["netting"]]
    optimised_sides = np.abs(np.diff(np.vstack([result.theta["cut"]["netting"], result.theta["cut"]["netting"][:1]]),
                                     axis=0)).sum(axis=1) / 2
    assert [float(r[-2].split()[0]) for r in rows] == pytest.approx(optimised_sides, abs=5e-3)
    # the parameter that changed: the diameter, start -> optimised -> rounded (the cut's rounding leaves it)
    (diameter,) = _rows(text, "parameter")
    assert diameter[0] == "twine_diameter[netting]" and diameter[-1] == "m"
    assert [float(v) for v in diameter[1:4]] == pytest.approx([1.5e-3, float(result.z["diameter"])] * 1
                                                               + [float(result.z["diameter"])], rel=1e-5)


def test_a_design_prints_as_a_table_and_is_still_theta(optimised):
    result, _ = optimised
    space, *_ = problem()
    rounded = result.rounded
    assert isinstance(rounded, report.Design) and isinstance(rounded, dict)
    text = repr(rounded)
    assert max(map(len, text.splitlines())) < report.WIDTH and len(text.splitlines()) < 15
    rows = _rows(text, "panel")
    assert [(float(r[-4]), r[-3]) for r in rows] == [(s.meshes, s.rate) for s in result.cut_report["netting"]]
    values = {r[0]: r[1] for r in _rows(text, "parameter")}
    assert float(values["mesh_side[netting]"]) == 0.025 and float(values["hanging_ratio[headline, sinker bar]"]) \
        == pytest.approx(float(rounded["hanging_ratio"]["headline"]), rel=1e-6)
    # a pytree of θ's leaves and a θ the space takes
    doubled = jax.tree.map(lambda a: 2 * a, rounded)
    assert isinstance(doubled, report.Design)
    assert float(doubled["mesh_side"]["netting"]) == 0.05
    assert len(jax.tree.leaves(rounded)) == len(jax.tree.leaves(dict(rounded)))
    scene = space.scene(rounded)
    np.testing.assert_array_equal(np.asarray(scene.netting.uv), np.asarray(space.scene(dict(rounded)).netting.uv))
    # eight alike panels read as one block
    assert report.group_name([f"wall {k}" for k in range(8)]) == "wall 0..7"
    assert report.group_name(["wall 0 corner 3", "wall 2 corner 3", "wall 3 corner 3"]) == "wall 0,2..3 corner 3"


def test_rounding_inward_takes_back_the_corners_rounded_outward():
    """optimize's fallback rounding (used when the nearest whole meshes violate a constraint the optimum met):
    a cut 4.6 meshes across and 3.7 deep rounds to 5 x 4 at the nearest, and to 4 x 3 with the corners that
    rounded outward taken a mesh in; a cut that rounded inward already (5.04 x 4) is left to the nearest."""
    space, *_ = problem()
    scale = reduced.scale_cut(space, ["netting"])
    theta = scale(jnp.array([1.15, 0.925]))
    nearest, _ = space.rounded(theta)
    np.testing.assert_array_equal(np.asarray(nearest["cut"]["netting"]), [[0, 0], [5, -5], [9, -1], [4, 4]])
    inward, sides = optimize._rounded_inward(space, theta, nearest)
    np.testing.assert_array_equal(np.asarray(inward["cut"]["netting"]), [[0, 0], [4, -4], [7, -1], [3, 3]])
    assert [(s.meshes, s.rate) for s in sides["netting"]] == [(4, "AT"), (3, "AN"), (4, "AT"), (3, "AN")]
    assert float(inward["twine_diameter"]["netting"]) == float(nearest["twine_diameter"]["netting"])
    already = scale(jnp.array([1.26, 1.0]))
    assert optimize._rounded_inward(space, already, space.rounded(already)[0]) is None


def test_bad_input_is_refused_before_compiling():
    space, design, z0, _ = problem()
    objective = objectives.drag()

    def refused(match, start=z0, **kw):
        with pytest.raises(ValueError, match=match):
            optimize.optimize(space, objective, start, design=kw.pop("design", design), progress=False, **kw)

    # design(z0) not a valid θ: the space's message, naming the entry
    refused(r"design\(start\) is not a valid design: cut\['netting'\]", {**z0, "size": np.array([0.0, 1.0])})
    refused(r"design\(start\) is not a valid design: twine_diameter\['netting'\]: the twine diameter \(m\) must be > 0",
            {**z0, "diameter": np.asarray(-1e-3)})
    unknown = reduced.combine(size=reduced.scale_cut(space, ["netting"]),
                              diameter=reduced.one_value("twine_diameter", ["nope"]))
    refused(r"twine_diameter: no entry 'nope'", design=unknown)
    # z0 not finite, not numbers
    refused(r"start\['size'\] is not finite at index \(1,\)", {**z0, "size": np.array([1.0, np.inf])})
    refused(r"start\['diameter'\] is not a number", {**z0, "diameter": "thick"})
    # a map that is numpy code, one that returns no design, one that is no function
    refused(r"jnp code", design=lambda z: {"twine_diameter": {"netting": np.asarray(z["diameter"]) * 1.0}})
    refused(r"must return a design", design=lambda z: z["size"])
    refused(r"design\(start\) failed: KeyError: 'width'", design=lambda z: {"cut": {"netting": z["width"]}})
    refused(r"design must be a function", design=3.0)
    # scale and bounds not shaped like z; a map's own check
    refused(r"scale of start\['size'\] has shape \(3,\)", scale={"size": np.ones(3), "diameter": 1e-3})
    refused(r"scale does not match", scale={"size": 1.0})
    refused(r"Bounds: lower\['width'\]", bounds=constraints.Bounds(lower={"width": 1.0}))
    refused(r"steps must be", steps=-1)
    with pytest.raises(ValueError, match=r"merge: cut\['netting'\] is set by two maps"):
        reduced.merge(reduced.scale_cut(space, ["netting"])(1.0),
                      reduced.one_value("cut", ["netting"])(jnp.zeros((4, 2))))
    with pytest.raises(ValueError, match=r"taper\('mesh_side'\): give at least 2"):
        reduced.taper("mesh_side", ["netting"])
    with pytest.raises(ValueError, match=r"scale_cut: no panel 'wall'"):
        reduced.scale_cut(space, ["wall"])
    with pytest.raises(ValueError, match=r"unknown design family 'diameter'"):
        reduced.one_value("diameter", ["netting"])
