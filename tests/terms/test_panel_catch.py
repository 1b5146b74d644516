"""Catches held by chosen panels (jaxnet.terms.panel_catch, jaxnet.model.catch.panel_catch_state, Net.panel_catch, FEMNET's
``input catch2_volume``): one catch on a whole cod-end is the main catch, two catches fill their own panels, the
stiffness is the force's Jacobian, the readers map FEMNET's lines and give FEMNET's catch drag on its own mesh,
result.json reports each catch, the equilibrium's derivative is right, and bad input is refused by name."""

from __future__ import annotations

import dataclasses
import pathlib

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet as jn
from jaxnet import geometry, model
from jaxnet.model import assemble, catch
from jaxnet.closed_form import pressure as pressure_closed
from jaxnet.io import femnet
from jaxnet.net import Net, Rope, Twine
from jaxnet.scene import Environment, PanelCatches, SceneError
from jaxnet.terms import panel_catch

DATA = pathlib.Path(__file__).resolve().parents[1] / "data"
AXIS = np.array([1.0, 0.0, 0.0])
CURRENT = 1.5
TWINE = Twine(l0=0.06, ea=1e5, diameter=4e-3, density=1025.0)


def quarter_codend(net, name, y0=0.0, twine=TWINE, meshes_around=20, meshes_along=10, opening=0.1, l0=0.06):
    """A quarter cod-end panel (as :func:`jaxnet.scenes.codend`) whose axis runs along x at y = y0, z = 0: held at
    its front, on its two symmetry planes, its rear border gathered by a cod line."""
    quarter = meshes_around // 4
    length = meshes_along * 2 * l0 * np.cos(opening)
    radius = meshes_around * 2 * l0 * np.sin(opening) / (2 * np.pi)
    n, m = quarter, meshes_along
    corners = [(0.0, y0, radius, 0, 0), (0.0, y0 + radius, 0.0, n, -n), (length, y0 + radius, 0.0, n + m, m - n),
               (length, y0, radius, m, m)]
    p = net.panel(name, corners, twine, 0.12)
    net.fix(p.side(0))
    net.fix(p.side(3), axes="y")
    net.fix(p.side(1), axes="z")
    net.cable(f"{name} cod line", along=p.side(2), rope=Rope(ea=5e4, diameter=0.01, density=1025.0), length=0.01)
    return p


def codend_net():
    return Net(Environment(current_speed=CURRENT, current_direction=AXIS))


_forces = jax.jit(assemble.forces, static_argnames=("model",))


def term_force(scene, x, name):
    only = tuple(t for t in model.active_terms(scene) if t.name == name)
    assert len(only) == 1
    return np.asarray(_forces(jnp.asarray(x), scene, model=only))


def test_one_panel_catch_on_the_whole_codend_is_the_main_catch():
    """The same cod-end (a quarter model) holding 0.01 m³ as its main catch and as one panel catch, both centred on
    its axis: the builder orients its netting alike, the fronts are one and the nodal pressure forces the same, at a
    shape where the front cuts the netting."""
    a = codend_net()
    quarter_codend(a, "cod-end")
    a.catch(0.01, drag_coefficient=1.4, symmetry=4.0, center=(0.0, 0.0, 0.0))
    main = a.build()
    b = codend_net()
    quarter_codend(b, "cod-end")
    b.panel_catch(0.01, ["cod-end"], drag_coefficient=1.4, symmetry=4.0, center=(0.0, 0.0, 0.0))
    panels = b.build()
    np.testing.assert_array_equal(np.asarray(main.netting.outward), np.asarray(panels.netting.outward))
    x = bulged(main)
    front = catch.catch_state(x, main)["front"]
    state = catch.panel_catch_state(x, panels)
    assert float(state["fronts"][0]) == pytest.approx(float(front), abs=1e-9)
    assert float(np.asarray(x)[:, 0].min()) < float(front) < float(np.asarray(x)[:, 0].max())
    f_main, f_panel = term_force(main, x, "catch_pressure"), term_force(panels, x, "panel_catch_pressure")
    assert np.abs(f_main).max() > 1.0
    np.testing.assert_allclose(f_panel, f_main, rtol=1e-12, atol=1e-9)


def bulged(scene):
    """The drawn cod-ends (tubes of radius 0.038 m along x) swollen in their middle to 7 times their radius, their
    ends as drawn: a bag the front cuts (the drawn tube holds nothing: its netting is parallel to the axis)."""
    x = np.asarray(scene.nodes.position).copy()
    length = x[:, 0].max()
    axis_y = np.where(x[:, 1] > 1.5, 3.0, 0.0)  # the second cod-end's axis is at y = 3 m
    swell = 1.0 + 6.0 * np.sin(np.pi * x[:, 0] / length)
    x[:, 1] = axis_y + (x[:, 1] - axis_y) * swell
    x[:, 2] *= swell
    return jnp.asarray(x)


def two_codends(volume_a, volume_b):
    net = codend_net()
    quarter_codend(net, "port", y0=0.0)
    quarter_codend(net, "starboard", y0=3.0)
    net.panel_catch(volume_a, ["port"], drag_coefficient=1.4, symmetry=4.0, center=(0.0, 0.0, 0.0))
    net.panel_catch(volume_b, ["starboard"], drag_coefficient=1.4, symmetry=4.0, center=(0.0, 3.0, 0.0))
    return net.build()


def test_two_catches_fill_their_own_panels():
    """Two cod-ends side by side, 0.01 and 0.03 m³: each front encloses its own volume among its own panel's
    triangles, the larger catch's front lies further upstream, and the pressure on one cod-end does not change
    with the other's volume."""
    scene = two_codends(0.01, 0.03)
    x = bulged(scene)
    state = catch.panel_catch_state(x, scene)
    holder = np.asarray(scene.panel_catches.panel_catch)[np.asarray(scene.netting.panel)]
    for k, volume in enumerate((0.01, 0.03)):
        sign = np.where(holder == k, np.asarray(scene.netting.outward), 0.0)
        enclosed = catch.enclosed_volume(x, scene.netting.vertices, state["fronts"][k], AXIS, 4.0, sign)
        assert float(enclosed) == pytest.approx(volume, rel=1e-8)
    assert float(state["fronts"][1]) < float(state["fronts"][0])
    other = two_codends(0.01, 0.02)
    port = np.unique(np.asarray(scene.netting.vertices)[holder == 0])
    starboard = np.unique(np.asarray(scene.netting.vertices)[holder == 1])
    f, g = term_force(scene, x, "panel_catch_pressure"), term_force(other, x, "panel_catch_pressure")
    np.testing.assert_allclose(g[port], f[port], rtol=1e-12, atol=1e-12)
    assert np.abs(g[starboard] - f[starboard]).max() > 1.0


@pytest.mark.parametrize("panel", [0, 1, 2])
def test_stiffness_is_minus_the_jacobian_of_the_force(panel):
    """The closed-form stiffness of a triangle cut by its catch's front is -dF/dx (autodiff), the front held; a
    triangle of a panel holding no catch has neither force nor stiffness."""
    rng = np.random.default_rng(panel)
    x = jnp.asarray(rng.normal(size=(3, 3)))
    state = {"fronts": jnp.array([float(np.median(x[:, 0])), 5.0]), "pressure": jnp.asarray(2590.0),
             "axis": jnp.asarray(AXIS), "catch_of_panel": jnp.array([0, 1, -1])}
    force = panel_catch.panel_catch_pressure(x, state, 1.0, panel)
    jac = jax.jacfwd(lambda y: panel_catch.panel_catch_pressure(y, state, 1.0, panel).reshape(-1))(x).reshape(9, 9)
    stiffness = pressure_closed.panel_catch_pressure_stiffness(x, state, 1.0, panel)
    np.testing.assert_allclose(np.asarray(stiffness), -np.asarray(jac), rtol=1e-10, atol=1e-8)
    if panel == 2:
        assert np.abs(np.asarray(force)).max() == 0.0 and np.abs(np.asarray(stiffness)).max() == 0.0
    elif panel == 0:
        assert np.abs(np.asarray(force)).max() > 0.0


def test_a_panel_catch_solves_as_the_main_catch_without_netting_drag():
    """Without netting drag (the main catch shields the netting behind its front, a panel catch does not) the
    cod-end holding 0.05 m³ as a panel catch reaches the main catch's equilibrium."""
    results = []
    for kind in ("main", "panel"):
        net = codend_net()
        quarter_codend(net, "cod-end", twine=dataclasses.replace(TWINE, cd_normal=0.0))
        if kind == "main":
            net.catch(0.05, drag_coefficient=1.4, symmetry=4.0, center=(0.0, 0.0, 0.0))
        else:
            net.panel_catch(0.05, ["cod-end"], drag_coefficient=1.4, symmetry=4.0, center=(0.0, 0.0, 0.0))
        eq = jn.solve_static(net.build(), tol=1e-6, max_iter=400)
        assert eq.converged
        results.append(np.asarray(eq.x))
    np.testing.assert_allclose(results[1], results[0], atol=1e-6)


def test_builder_and_checks_refuse_bad_panel_catches():
    net = codend_net()
    quarter_codend(net, "port")
    with pytest.raises(SceneError, match="no panel named 'aft'"):
        net.panel_catch(0.1, ["aft"])
    with pytest.raises(SceneError, match="volume must be finite and > 0"):
        net.panel_catch(0.0, ["port"])
    net.panel_catch(0.1, ["port"])
    with pytest.raises(SceneError, match="panel 'port' already holds a catch"):
        net.panel_catch(0.1, ["port"])
    scene = net.build()
    wrong = dataclasses.replace(scene, panel_catches=dataclasses.replace(scene.panel_catches,
                                                                         panel_catch=np.array([1], dtype=np.int32)))
    with pytest.raises(SceneError, match="panel 0 holds catch 1, not among the 1 catches"):
        jn.validate(wrong)
    empty = dataclasses.replace(scene, panel_catches=PanelCatches(volume=np.array([0.1, 0.2]),
                                                                  panel_catch=np.array([0], dtype=np.int32),
                                                                  drag_coefficient=1.4, axis=AXIS))
    with pytest.raises(SceneError, match="catch 1 is held by no netting panel"):
        jn.validate(empty)


C2 = DATA / "femnet" / "c2.don"


def test_femnet_catch2_volume_lines_become_panel_catches(tmp_path):
    """``input catch2_volume V N P1..PN`` on FEMNET's cod-end c2 (a quarter model: its planes make 4 copies), its
    main catch removed: one panel catch of 4 V on panel 1 with the main catch's Cd, fronts along x, and the
    panel's triangles on FEMNET's side, -sign(d) (the catch on the U ^ V side). A panel the case does not have,
    or a line whose count does not match its panels, is refused at its line."""
    text = C2.read_text()
    parsed = femnet.parse_don(C2)
    volume_line = parsed.catch["catch_volume"].line
    lines = text.rstrip("\n").split("\n")
    assert lines[volume_line - 1].split()[-1] == "0.2"
    lines[volume_line - 1] = lines[volume_line - 1][:-len("0.2")] + "0.0"
    base = "\n".join(lines)
    good = tmp_path / "c2.don"
    good.write_text(base + "\ninput catch2_volume 0.2 1 1\n")
    case = femnet.read_don(good)
    scene = case.scene
    assert scene.catch is None
    pc = scene.panel_catches
    np.testing.assert_allclose(pc.volume, [0.8])
    assert pc.symmetry == 4.0 and pc.drag_coefficient == parsed.catch["catch_cd"].value
    np.testing.assert_allclose(pc.axis, AXIS)
    np.testing.assert_array_equal(pc.panel_catch, [0])
    sides = -np.sign(np.asarray(geometry.twine_determinant(np.asarray(scene.netting.uv))))
    np.testing.assert_array_equal(np.asarray(scene.netting.outward), sides)
    assert "panel_catch_pressure" in [t.name for t in model.active_terms(scene)]
    n = len(lines) + 1
    for tail, message in (("input catch2_volume 0.2 1 7", f"bad.don:{n}: 'input catch2_volume 0.2': panel 7 does not exist"),
                          ("input catch2_volume 0.2 2 1", "the number of panels must be a whole number >= 1 followed by")):
        bad = tmp_path / "bad.don"
        bad.write_text(base + "\n" + tail + "\n")
        with pytest.raises(SceneError, match=message):
            femnet.read_don(bad)


def test_scene_file_panel_catches(tmp_path):
    """A scene file's ``panel_catches`` entries are :meth:`Net.panel_catch` calls; an unknown key is refused by name."""
    import json

    doc = {"environment": {"current_speed": 1.0},
           "twines": {"pa": {"l0": 0.05, "ea": 2000.0, "diameter": 0.002}},
           "panels": [{"name": "bag", "corners": [[0, 0, 0, 0, 0], [0, 1, 0, 10, -10], [1, 1, 0, 20, 0], [1, 0, 0, 10, 10]],
                       "twine": "pa", "step": 0.25}],
           "fix": [{"at": {"panel": "bag", "side": 0}}],
           "panel_catches": [{"volume": 0.2, "panels": ["bag"], "drag_coefficient": 1.2, "center": [0.5, 0.5, -1.0]}]}
    path = tmp_path / "bag.json"
    path.write_text(json.dumps(doc))
    pc = jn.read_scene(path).scene.panel_catches
    np.testing.assert_allclose(pc.volume, [0.2])
    assert pc.drag_coefficient == 1.2
    np.testing.assert_array_equal(pc.panel_catch, [0])
    doc["panel_catches"][0]["colour"] = "red"
    path.write_text(json.dumps(doc))
    with pytest.raises(SceneError, match=r"panel_catches\[0\]: unknown key\(s\) \['colour'\]"):
        jn.read_scene(path)


AVRIL_4 = DATA / "femnet-corpus" / "15grid" / "avril_4"


def test_femnets_panel_catches_at_femnets_equilibrium_give_its_catch_drag():
    """15grid/avril_4 (two catches of 2 m³ in the two cod-ends of a grid trawl) on FEMNET's own mesh at its stored
    equilibrium (avril_4.mdg, .sta): the pressure of jaxnet's panel catches pushes the net along x by FEMNET's
    printed "catch drag" (7574 N, to the unit it prints), and its netting drag is FEMNET's "surface drag" (6269 N)."""
    from jaxnet import figures

    case = femnet.read_mdg(AVRIL_4.with_suffix(".mdg"), AVRIL_4.with_suffix(".don"))
    scene = case.scene
    np.testing.assert_allclose(scene.panel_catches.volume, [2.0, 2.0])
    pos, _, _, summary = femnet.read_sta(AVRIL_4.with_suffix(".sta"), scene.n_nodes, scene.bars.ends.shape[0],
                                         scene.netting.vertices.shape[0])
    assert summary["catch drag (N)"][0] == 7574.0 and summary["surface drag (N)"][0] == 6269.0
    forces = figures.force_breakdown(scene, pos)
    assert forces["catch_N"][0] == pytest.approx(7574.0, abs=1.0)
    assert forces["drag_netting_N"][0] == pytest.approx(6269.0, abs=1.0)
    state = catch.panel_catch_state(jnp.asarray(pos), scene)
    holder = np.asarray(scene.panel_catches.panel_catch)[np.asarray(scene.netting.panel)]
    for k in range(2):
        sign = np.where(holder == k, np.asarray(scene.netting.outward), 0.0)
        enclosed = catch.enclosed_volume(jnp.asarray(pos), scene.netting.vertices, state["fronts"][k], AXIS, 1.0, sign)
        assert float(enclosed) == pytest.approx(2.0, rel=1e-8)


def test_equilibrium_derivative_in_the_catch_volume():
    """d(equilibrium)/d(volume) of a cod-end holding a panel catch, by the implicit function theorem (its tangent
    holds the front fixed, so the sensitivity solve is refined against the exact Jacobian), against central
    differences of full solves."""
    from jaxnet.solve import implicit, programs
    from jaxnet.solve.options import DIFFERENTIABLE

    net = codend_net()
    quarter_codend(net, "cod-end")
    net.panel_catch(0.05, ["cod-end"], drag_coefficient=1.4, symmetry=4.0, center=(0.0, 0.0, 0.0))
    scene = net.build()
    first = jn.solve_static(scene, tol=1e-9, max_iter=400)
    structure = implicit.structure_of(scene)
    assert not structure.exact_tangent
    x0 = np.asarray(first.x)
    solver = dataclasses.replace(DIFFERENTIABLE, max_iter=400)

    def rear(volume):
        s = dataclasses.replace(scene, panel_catches=dataclasses.replace(scene.panel_catches,
                                                                         volume=jnp.reshape(volume, (1,))))
        x = implicit.equilibrium(s, structure, x0=x0, solver=solver).x
        return jnp.max(x[:, 0])  # how far the cod-end reaches downstream (m)

    # one compiled program (with the XLA options of jaxnet's own programs) gives the reach and its derivative;
    # the differences' full solves are its values at the neighbouring volumes (the same Newton solve, to the
    # same tolerance, from the same start)
    reach_and_grad = programs.jit(jax.value_and_grad(rear))
    grad = float(reach_and_grad(jnp.asarray(0.05))[1])
    h = 1e-3
    fd = (float(reach_and_grad(jnp.asarray(0.05 + h))[0]) - float(reach_and_grad(jnp.asarray(0.05 - h))[0])) / (2 * h)
    assert abs(grad) > 1e-3
    assert grad == pytest.approx(fd, rel=1e-3)
    # the host-driven adjoint (jaxnet.solve.adjoint_statics), its transposed solve refined the same way
    from jaxnet.solve import adjoint_statics

    class Reach(eqx.Module):
        def __call__(self, x, scene):
            return jnp.max(x[:, 0])

    host = adjoint_statics.Adjoint(scene, solver).value_and_grad(Reach(), scene, x0)
    assert host.adjoint_residual < 1e-11
    assert float(host.grad.panel_catches.volume[0]) == pytest.approx(grad, rel=1e-7)


def test_result_reports_each_panel_catch():
    """result.json's ``panel_catches``: at the solved equilibrium of two cod-ends holding 0.01 and 0.03 m³, each entry
    names its panel and holds its volume, and each catch's whole-net drag (p × its front's section) is the
    axial force of its pressure on its own cod-end (the netting with the front and the symmetry planes closes the
    catch), four times the modelled quarter's."""
    from jaxnet import figures

    scene = two_codends(0.01, 0.03)
    eq = jn.solve_static(scene, max_iter=500)
    report = figures.summary(scene, eq)["panel_catches"]
    assert [r["panels"] for r in report] == [["port"], ["starboard"]]
    holder = np.asarray(scene.panel_catches.panel_catch)[np.asarray(scene.netting.panel)]
    force = term_force(scene, np.asarray(eq.x), "panel_catch_pressure")
    for k, (r, volume) in enumerate(zip(report, (0.01, 0.03))):
        assert r["holds_the_volume"] and r["volume_whole_net_m3"] == pytest.approx(volume, rel=1e-8)
        nodes = np.unique(np.asarray(scene.netting.vertices)[holder == k])
        assert r["drag_whole_net_N"] == pytest.approx(4.0 * force[nodes, 0].sum(), rel=1e-6)
        assert r["drag_N"] == pytest.approx(force[nodes, 0].sum(), rel=1e-6)  # the modelled quarter's
    assert report[1]["drag_whole_net_N"] > report[0]["drag_whole_net_N"] > 0.0
