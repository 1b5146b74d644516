"""The closed-form stiffness in the solver: the switch, the global tangent, the same equilibrium.

``Newton(stiffness="closed_form")`` assembles the hand-derived element matrices of :mod:`jaxnet.closed_form`
for the terms that have one and autodiff for the others. Checked here: the switch and its errors, that the
closed-form package is independent of JAX's automatic differentiation, that the assembled global tangents
of the two paths agree to rounding on a scene with every closed-form term, and that both paths solve
scenes to the same equilibrium. The element-level comparisons, term by term, are in the
``tests/test_closed_form_<term>.py`` files.
"""

from __future__ import annotations

import pathlib
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet as jn
from jaxnet import assemble, model
from jaxnet.closed_form import registry
from jaxnet.net import Twine
from jaxnet.scenes.codend import codend
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import statics

CLOSED_FORM = pathlib.Path(jn.__file__).parent / "closed_form"
AUTODIFF = re.compile(r"\b(grad|jacfwd|jacrev|hessian|jvp|vjp|linearize|value_and_grad)\b")


def test_closed_form_modules_never_call_autodiff():
    """The hand path is independent: no module of jaxnet/closed_form names an autodiff transformation."""
    sources = sorted(CLOSED_FORM.glob("*.py"))
    assert len(sources) >= 3
    for path in sources:
        code = "\n".join(line.split("#")[0] for line in path.read_text().splitlines())
        # docstrings may name jax.jacfwd (to say what is matched); calls may not
        calls = [m.group(0) for m in re.finditer(r"jax\.\w+\s*\(|\b(grad|jacfwd|jacrev|hessian|jvp|vjp)\s*\(", code)]
        assert not [c for c in calls if AUTODIFF.search(c)], (path.name, calls)


def test_unknown_stiffness_path_is_refused_before_compiling():
    with pytest.raises(ValueError, match="stiffness must be one of"):
        jn.Newton(stiffness="hand")
    scene = hanging_panel(meshes=4, step=0.05).build()
    m = model.active_terms(scene)
    with pytest.raises(ValueError, match="stiffness must be one of"):
        assemble.tangent(jnp.asarray(scene.nodes.position), scene, m, assemble.build_pattern(scene, m),
                         stiffness="Closed-Form")


def every_term_codend():
    """A small cod-end with every term the book gives a stiffness for (the codend's own plus mesh opening,
    compression, bending), slightly perturbed from its start so that no element sits on a kink."""
    twine = Twine(l0=0.06, ea=1e5, ea_compression=1e3, diameter=4e-3, density=1025.0, knot_size=0.01,
                  opening_stiffness=0.05, bending_stiffness=1e-4)
    scene = codend(meshes_around=8, meshes_along=6, step=0.12, twine=twine).build()
    rng = np.random.default_rng(3)
    x = np.asarray(scene.nodes.position) + 2e-3 * rng.normal(size=scene.nodes.position.shape)
    return scene, jnp.asarray(x)


def test_paths_name_each_term():
    scene, _ = every_term_codend()
    m = model.active_terms(scene)
    paths = registry.paths(m)
    assert set(paths) == {t.name for t in m if t.term.kind in ("energy", "force")}
    assert set(paths) >= {"netting_tension", "bar_tension", "mesh_opening", "knot_contact", "twine_bending",
                          "netting_drag", "bar_drag", "catch_pressure"}
    assert set(paths.values()) == {"closed_form"}
    assert set(registry.paths(m, "autodiff").values()) == {"autodiff"}


def test_a_term_without_closed_form_keeps_autodiff():
    """The screen drag models have no stiffness in the book: with them the netting drag stays on autodiff,
    and the mixed tangent is still the autodiff one."""
    twine = Twine(l0=0.06, ea=1e5, diameter=4e-3, density=1025.0, drag_model="loland")
    scene = codend(meshes_around=8, meshes_along=4, step=0.12, twine=twine).build()
    m = model.active_terms(scene)
    assert registry.paths(m)["netting_drag"] == "autodiff"
    assert registry.paths(m)["netting_tension"] == "closed_form"
    x = jnp.asarray(scene.nodes.position) + 1e-3
    pattern = assemble.build_pattern(scene, m)
    k = {path: np.asarray(assemble.tangent(x, scene, m, pattern, None, 1.0, path)) for path in assemble.STIFFNESS_PATHS}
    assert np.max(np.abs(k["closed_form"] - k["autodiff"])) <= 1e-10 * np.max(np.abs(k["autodiff"]))


def test_global_tangents_agree():
    """The assembled CSR tangents of the two paths, every term of the cod-end at a perturbed shape."""
    scene, x = every_term_codend()
    m = model.active_terms(scene)
    pattern = assemble.build_pattern(scene, m)
    state = assemble.states(x, scene, m)
    k = {path: np.asarray(jax.jit(lambda x, pattern, path=path: assemble.tangent(x, scene, m, pattern, state, 1.0, path))(x, pattern))
         for path in assemble.STIFFNESS_PATHS}
    scale = np.max(np.abs(k["autodiff"]))
    assert scale > 0
    assert np.max(np.abs(k["closed_form"] - k["autodiff"])) <= 1e-10 * scale
    # and with the elastic energies scaled (the stiffness continuation's softened nets)
    soft = {path: np.asarray(assemble.tangent(x, scene, m, pattern, state, 0.1, path)) for path in assemble.STIFFNESS_PATHS}
    assert np.max(np.abs(soft["closed_form"] - soft["autodiff"])) <= 1e-10 * scale
    assert np.max(np.abs(soft["autodiff"] - k["autodiff"])) > 1e-3 * scale


@pytest.mark.parametrize("name", ["hanging", "codend"])
def test_both_paths_reach_the_same_equilibrium(name):
    if name == "hanging":
        scene = hanging_panel(meshes=6, step=0.05).build()
    else:
        scene = codend(meshes_around=8, meshes_along=6, step=0.12).build()
    eq = {path: statics.solve(scene, jn.Newton(stiffness=path))[0] for path in assemble.STIFFNESS_PATHS}
    a, c = eq["autodiff"], eq["closed_form"]
    assert a.converged and c.converged
    size = np.ptp(np.asarray(a.x), axis=0).max()
    # both converge to tol (1e-3 N); their positions differ by what that residual allows
    assert np.max(np.abs(np.asarray(a.x) - np.asarray(c.x))) < 1e-6 * size
