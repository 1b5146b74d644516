"""The closed-form stiffness in the solver: the switch, the global tangent, the same equilibrium.

``Newton(stiffness="closed_form")`` assembles the hand-derived element matrices of :mod:`jaxnet.closed_form`
for the terms that have one and autodiff for the others. Checked here: the switch and its errors, that the
closed-form package is independent of JAX's automatic differentiation, that the assembled global tangents
of the two paths agree to rounding on a scene with every closed-form term, and that both paths solve
scenes to the same equilibrium. The element-level comparisons, term by term, are in the
``tests/test_closed_form_<term>.py`` files.
"""

from __future__ import annotations

import ast
import pathlib
import re

import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet as jn
from jaxnet import model
from jaxnet.model import assemble
from jaxnet.net import Twine
from jaxnet.scenes.codend import codend
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import newton, programs, results, statics

CLOSED_FORM = pathlib.Path(jn.__file__).parent / "closed_form"
#: the tangent, compiled (op by op, its vmaps would compile dozens of small programs) with the XLA options of
#: the solver's own programs (:func:`jaxnet.solve.programs.jit`), which compile it faster
TANGENT = programs.jit(assemble.tangent, static_argnames=("model", "stiffness"))
#: the force terms' states (the catch front), compiled likewise
STATES = programs.jit(assemble.states, static_argnames="model")
AUTODIFF = re.compile(r"grad|jacfwd|jacrev|hessian|jvp|vjp|linearize|value_and_grad|custom_jvp|custom_vjp")


def test_closed_form_modules_never_call_autodiff():
    """The hand path is independent: no module of jaxnet/closed_form calls or imports an autodiff transformation
    (docstrings may name ``jax.jacfwd``, to say what is matched; the code may not use it)."""
    sources = sorted(CLOSED_FORM.glob("*.py"))
    assert len(sources) >= 8
    for path in sources:
        used = []
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id == "jax" \
                    and AUTODIFF.fullmatch(node.attr):
                used.append(node.attr)  # jax.grad, jax.jacfwd, ...
            elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("jax"):
                used += [a.name for a in node.names if AUTODIFF.fullmatch(a.name)]
        assert not used, (path.name, used)


def test_unknown_stiffness_path_is_refused_before_compiling():
    with pytest.raises(ValueError, match="stiffness must be one of"):
        jn.Newton(stiffness="hand")
    scene = hanging_panel(meshes=4, step=0.05).scene
    m = model.active_terms(scene)
    with pytest.raises(ValueError, match="stiffness must be one of"):
        assemble.tangent(jnp.asarray(scene.nodes.position), scene, m, assemble.build_pattern(scene, m),
                         stiffness="Closed-Form")


def every_term_codend():
    """A small cod-end with every term the book gives a stiffness for (the codend's own plus mesh opening,
    compression, bending), slightly perturbed from its start so that no element sits on a kink."""
    twine = Twine(l0=0.06, ea=1e5, ea_compression=1e3, diameter=4e-3, density=1025.0, knot_size=0.01,
                  opening_stiffness=0.05, bending_stiffness=1e-4)
    scene = codend(meshes_around=8, meshes_along=6, step=0.12, twine=twine).scene
    rng = np.random.default_rng(3)
    x = np.asarray(scene.nodes.position) + 2e-3 * rng.normal(size=scene.nodes.position.shape)
    return scene, jnp.asarray(x)


def test_paths_name_each_term():
    scene, _ = every_term_codend()
    m = model.active_terms(scene)
    paths = model.stiffness_paths(m)
    assert set(paths) == {t.name for t in m if t.term.kind in ("energy", "force")}
    assert set(paths) >= {"netting_tension", "bar_tension", "mesh_opening", "knot_contact", "twine_bending",
                          "netting_drag", "bar_drag", "catch_pressure"}
    assert set(paths.values()) == {"closed_form"}
    assert set(model.stiffness_paths(m, "autodiff").values()) == {"autodiff"}


def test_a_term_without_closed_form_keeps_autodiff():
    """The screen drag models have no stiffness in the book: with them the netting drag stays on autodiff,
    and the mixed tangent is still the autodiff one."""
    twine = Twine(l0=0.06, ea=1e5, diameter=4e-3, density=1025.0, drag_model="loland")
    scene = codend(meshes_around=8, meshes_along=4, step=0.12, twine=twine).scene
    m = model.active_terms(scene)
    assert model.stiffness_paths(m)["netting_drag"] == "autodiff"
    assert model.stiffness_paths(m)["netting_tension"] == "closed_form"
    x = jnp.asarray(scene.nodes.position) + 1e-3
    pattern = assemble.build_pattern(scene, m)
    k = {path: np.asarray(TANGENT(x, scene, pattern=pattern, model=m, stiffness=path)) for path in assemble.STIFFNESS_PATHS}
    assert np.max(np.abs(k["closed_form"] - k["autodiff"])) <= 1e-10 * np.max(np.abs(k["autodiff"]))


def test_global_tangents_agree():
    """The assembled CSR tangents of the two paths, every term of the cod-end at a perturbed shape."""
    scene, x = every_term_codend()
    m = model.active_terms(scene)
    pattern = assemble.build_pattern(scene, m)
    state = STATES(x, scene, m)
    # the elastic scale as an array: one compilation per path serves both scales
    k = {path: np.asarray(TANGENT(x, scene, pattern=pattern, state=state, elastic_scale=jnp.asarray(1.0), model=m,
                                  stiffness=path))
         for path in assemble.STIFFNESS_PATHS}
    scale = np.max(np.abs(k["autodiff"]))
    assert scale > 0
    assert np.max(np.abs(k["closed_form"] - k["autodiff"])) <= 1e-10 * scale
    # and with the elastic energies scaled (the stiffness continuation's softened nets)
    soft = {path: np.asarray(TANGENT(x, scene, pattern=pattern, state=state, elastic_scale=jnp.asarray(0.1), model=m,
                                     stiffness=path))
            for path in assemble.STIFFNESS_PATHS}
    assert np.max(np.abs(soft["closed_form"] - soft["autodiff"])) <= 1e-10 * scale
    assert np.max(np.abs(soft["autodiff"] - k["autodiff"])) > 1e-3 * scale


def panel_with_bodies(profile=True, surface_level=float("nan")):
    """A panel in a current (its speed falling with depth if ``profile``), with bodies (node drag) and a rope
    along its top side at z = 0 (a free surface at ``surface_level``, m, if finite)."""
    from jaxnet.net import Net, Rope
    from jaxnet.scene import Environment

    depth, factor = (np.array([0.0, 0.5, 2.0]), np.array([1.0, 0.7, 0.2])) if profile else (np.zeros(0), np.zeros(0))
    net = Net(environment=Environment(current_speed=1.0, current_direction=np.array([1.0, 0.3, 0.0]),
                                      profile_depth=depth, profile_factor=factor, surface_level=surface_level))
    twine = Twine(l0=0.05, ea=2000.0, diameter=2e-3, ea_compression=500.0)
    panel = net.panel("netting", [(0.0, 0.0, -1.0, 0, 0), (1.0, 0.0, -1.0, 10, -10), (1.0, 0.0, 0.0, 20, 0),
                                  (0.0, 0.0, 0.0, 10, 10)], twine, 0.2)
    net.cable("headline", along=panel.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    net.attach(panel.corner(0), mass=2.0, drag_area=0.05)
    net.attach(panel.corner(1), mass=2.0, drag_area=0.05)
    net.attach(panel.corner(2), drag_area=0.02, volume=1e-3, size=0.1)  # a float on the headline
    net.fix(panel.side(2))
    return net.build()


def test_global_tangents_agree_in_a_current_varying_with_depth():
    """The drag stiffness includes dc/dz of the current profile (the book's 4.157 takes c constant) on both
    paths, for the netting, the rope and the bodies at nodes."""
    tangents = {}
    for profile in (True, False):
        scene = panel_with_bodies(profile)
        m = model.active_terms(scene)
        paths = model.stiffness_paths(m)
        assert paths["node_drag"] == paths["bar_drag"] == paths["netting_drag"] == "closed_form"
        rng = np.random.default_rng(5)
        x = jnp.asarray(np.asarray(scene.nodes.position) + 0.02 * rng.normal(size=scene.nodes.position.shape))
        pattern = assemble.build_pattern(scene, m)
        # both paths with the profile; without it, the closed form only, to which the profile is compared below
        tangents[profile] = {path: np.asarray(TANGENT(x, scene, pattern=pattern, model=m, stiffness=path))
                             for path in (assemble.STIFFNESS_PATHS if profile else ("closed_form",))}
    k = tangents[True]
    scale = np.max(np.abs(k["autodiff"]))
    assert np.max(np.abs(k["closed_form"] - k["autodiff"])) <= 1e-10 * scale
    # the profile does change the tangent here (speed and slope), so the agreement above is not vacuous
    assert np.max(np.abs(tangents[False]["closed_form"] - k["closed_form"])) > 1e-8 * scale


def test_global_tangents_agree_at_a_free_surface():
    """At a free surface the drags load only the immersed part of each vertex's share (``wetted``): the product
    rule of the closed forms against autodiff, the surface put through a row of free netting nodes, those and the
    headline's float within their immersion bands (2 mm and 0.1 m)."""
    dry = panel_with_bodies(profile=True)
    x0 = np.asarray(dry.nodes.position)
    free = ~np.asarray(dry.nodes.fixed).any(axis=1)
    level = float(x0[free, 2][np.argmin(np.abs(x0[free, 2] + 0.4))])  # a row of free nodes, 0.4 m down
    scene = panel_with_bodies(profile=True, surface_level=level)
    m = model.active_terms(scene)
    options = {t.name: t.kwargs() for t in m}
    assert all(options[name].get("wetted") for name in ("netting_drag", "bar_drag", "node_drag"))
    assert model.stiffness_paths(m)["bar_drag"] == "closed_form"
    rng = np.random.default_rng(7)
    near = np.abs(x0[:, 2] - level) < 1e-2
    x = jnp.asarray(x0 + np.where(near[:, None], 5e-4, 2e-2) * rng.normal(size=x0.shape))
    inside = free & (np.abs(np.asarray(x)[:, 2] - level) < 1e-3)
    assert inside.sum() >= 2  # free vertices inside the twines' band, where the share has a slope
    pattern = assemble.build_pattern(scene, m)
    k = {path: np.asarray(TANGENT(x, scene, pattern=pattern, model=m, stiffness=path))
         for path in assemble.STIFFNESS_PATHS}
    scale = np.max(np.abs(k["autodiff"]))
    assert np.max(np.abs(k["closed_form"] - k["autodiff"])) <= 1e-10 * scale
    # the surface does change the tangent (not a vacuous agreement): the same scene without it
    m_dry = model.active_terms(dry)
    k_dry = np.asarray(TANGENT(x, dry, pattern=assemble.build_pattern(dry, m_dry), model=m_dry, stiffness="autodiff"))
    assert np.max(np.abs(k_dry - k["autodiff"])) > 1e-6 * scale


@pytest.mark.parametrize("name", ["hanging", "codend"])
def test_both_paths_reach_the_same_equilibrium(name):
    if name == "hanging":
        scene = hanging_panel(meshes=6, step=0.05).scene
    else:
        scene = codend(meshes_around=8, meshes_along=6, step=0.12).scene
    eq = {path: statics.solve(scene, jn.Newton(stiffness=path)) for path in assemble.STIFFNESS_PATHS}
    a, c = eq["autodiff"], eq["closed_form"]
    assert a.converged and c.converged
    size = np.ptp(np.asarray(a.x), axis=0).max()
    # both converge to tol (1e-3 N); their positions differ by what that residual allows
    assert np.max(np.abs(np.asarray(a.x) - np.asarray(c.x))) < 1e-6 * size


def test_jitted_newton_loop_runs_on_the_closed_form():
    """The one-program Newton (``newton.newton_loop``, for traced callers) takes the switch too, and is the
    same iteration as the host loop."""
    scene = hanging_panel(meshes=6, step=0.05).scene
    solver = jn.Newton(stiffness="closed_form", stall_window=None, method="damped")
    host = statics.solve(scene, solver)
    m = model.active_terms(scene)
    pattern = assemble.build_pattern(scene, m)
    x0 = jnp.asarray(np.asarray(scene.nodes.position).ravel()[np.asarray(pattern.free)])
    jitted = newton.newton_loop_jit(x0, scene, pattern, model=m, solver=solver)
    assert int(jitted.status) == results.CONVERGED
    assert int(jitted.iterations) == int(host.iterations)
    np.testing.assert_allclose(np.asarray(jitted.x), np.asarray(host.x), atol=1e-9)


def test_jitted_newton_loop_threads_the_catch_front_as_the_host_loop():
    """With a catch, each evaluation starts its front from the last accepted iterate's (``previous``): the
    one-program loop carries that state as the host loop does, from NaN placeholders (no front yet), and
    the two reach the same equilibrium in the same iterations, the front holding the catch's volume."""
    from jaxnet.model import catch

    scene = codend(meshes_around=8, meshes_along=6, catch_m3=0.01).scene
    solver = jn.Newton(stall_window=None)
    host = statics.solve(scene, solver)
    m = model.active_terms(scene)
    pattern = assemble.build_pattern(scene, m)
    x0 = jnp.asarray(np.asarray(scene.nodes.position).ravel()[np.asarray(pattern.free)])
    jitted = newton.newton_loop_jit(x0, scene, pattern, model=m, solver=solver)
    assert host.converged and int(jitted.status) == results.CONVERGED
    assert int(jitted.iterations) == int(host.iterations)
    np.testing.assert_allclose(np.asarray(jitted.x), np.asarray(host.x), atol=1e-9)
    c = scene.catch
    front = catch.catch_front(host.x, scene.netting.vertices, c.axis, c.volume, c.symmetry, sign=scene.netting.outward)
    assert bool(front.holds) and float(front.volume) == pytest.approx(float(c.volume), rel=1e-9)
