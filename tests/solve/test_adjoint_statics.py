"""The host-driven adjoint (jaxnet.solve.adjoint_statics): the gradient of a figure of the static equilibrium
in every float array of the scene, against jax.grad through the traced implicit equilibrium and against
differences of re-solved equilibria; and its programs compiled in one process, loaded by the next.

The scene is small (a hanging panel of 4 meshes in a current, 15 nodes). The design-level gradient (through a
DesignSpace) is tested on the cage and the trawl (tests/design/test_design_optimize.py, tests/design/test_design_trawl.py),
the refinement where K is not exact (a catch) in tests/terms/test_panel_catch.py."""

import json
import os
import subprocess
import sys

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.scene import Environment
from jaxnet.scenes.panel import hanging_panel
from jaxnet.solve import adjoint_statics, implicit, programs, results, statics
from jaxnet.solve.options import Newton
from panels import SMOOTH  # tests/panels.py

NEWTON = Newton(tol=1e-10, max_iter=100, damping=1e-6, stall_window=None, line_search=30)


class Deflection(eqx.Module):
    """The mean downstream (y) position of the nodes (m), and the largest as aux."""

    def __call__(self, x, scene):
        return jnp.mean(x[:, 1]), jnp.max(x[:, 1])


def panel_in_current():
    net = hanging_panel(meshes=4, step=0.05, **SMOOTH).net
    net.environment = Environment(current_speed=0.4, current_direction=np.array([0.0, 1.0, 0.0]))
    # the current speed as an array: a float array of the scene, so a gradient in it (a Python number is not)
    scene = eqx.tree_at(lambda s: s.environment.current_speed, net.build(), jnp.asarray(0.4))
    return scene, np.asarray(statics.solve(scene, tol=1e-9).x)


#: the scene's arrays the differences move (a random direction each): the design families and the current
MOVED = {"netting.uv": lambda s: s.netting.uv, "netting.l0": lambda s: s.netting.l0,
         "netting.ea_traction": lambda s: s.netting.ea_traction, "netting.diameter": lambda s: s.netting.diameter,
         "environment.current_speed": lambda s: s.environment.current_speed}


def test_the_host_gradient_is_jax_grads_and_the_differences_of_solves():
    """Every float array's gradient equals jax.grad through implicit.equilibrium (the same derivative by the
    traced path) to 1e-9 of the largest entry; along a random direction of the moved arrays, central
    differences of re-solved equilibria (fourth order) agree to 1e-6. The adjoint solve's residual is at roundoff."""
    scene, x0 = panel_in_current()
    adjoint = adjoint_statics.Adjoint(scene, NEWTON)
    figure = Deflection()
    result = adjoint.value_and_grad(figure, scene, x0)
    assert int(result.equilibrium.status) == results.CONVERGED
    assert result.adjoint_residual < 1e-8  # K the exact Jacobian: its transposed solve at roundoff (x its condition)
    params, rest = eqx.partition(scene, eqx.is_inexact_array)
    structure = implicit.structure_of(scene)

    def traced(p):
        s = eqx.combine(p, rest)
        return figure(implicit.equilibrium(s, structure, x0=x0, solver=NEWTON).x, s)[0]

    value, expected = jax.value_and_grad(traced)(params)
    assert result.value == pytest.approx(float(value), rel=1e-12)
    assert float(result.aux) == pytest.approx(float(np.max(np.asarray(result.equilibrium.x)[:, 1])), rel=1e-12)
    for got, want in zip(jax.tree.leaves(result.grad), jax.tree.leaves(expected)):
        scale = max(float(np.abs(want).max(initial=0.0)), 1e-30)
        np.testing.assert_allclose(np.asarray(got), np.asarray(want), rtol=0, atol=1e-9 * scale)

    rng = np.random.default_rng(1)
    # each array moved in proportion to its size; the twine coordinates by hundredths of a twine (a random
    # move of every vertex's own coordinates bends the function strongly: the differences' error is then h²)
    direction = {name: rng.normal(size=np.shape(field(scene))) * (
        0.01 if name == "netting.uv" else np.abs(np.asarray(field(scene))).mean()) for name, field in MOVED.items()}

    def moved(h):
        s = scene
        for name, field in MOVED.items():
            s = eqx.tree_at(field, s, jnp.asarray(field(s)) + h * direction[name])
        return adjoint.value(figure, s, x0)[0]

    gradient_of = {name: field(result.grad) for name, field in MOVED.items()}
    directional = sum(float(np.sum(np.asarray(gradient_of[n]) * direction[n])) for n in MOVED)
    h = 1e-4  # fourth-order central differences
    differences = (8 * (moved(h) - moved(-h)) - (moved(2 * h) - moved(-2 * h))) / (12 * h)
    assert abs(directional) > 1e-3  # the direction does move the net
    assert directional == pytest.approx(differences, rel=1e-6)


def test_a_solve_that_does_not_converge_gives_no_gradient_and_says_why():
    """Two Newton iterations from the panel drawn flat do not reach 1e-10 N: no gradient (None), the value NaN,
    and the equilibrium's status and residual say where the solve stopped."""
    scene, _ = panel_in_current()
    adjoint = adjoint_statics.Adjoint(scene, Newton(tol=1e-10, max_iter=2, stall_window=None))
    result = adjoint.value_and_grad(Deflection(), scene)
    assert result.grad is None and np.isnan(result.value)
    assert int(result.equilibrium.status) == results.MAX_ITERATIONS
    assert float(result.equilibrium.residual_N) > 1e-10


def test_a_scene_of_another_net_is_refused_before_anything_compiles():
    """The adjoint's pattern and programs are its reference's: a scene with other nodes is a ValueError that says
    so, raised before any program is traced."""
    scene, _ = panel_in_current()
    other = hanging_panel(meshes=3, step=0.05).net.build()
    with pytest.raises(ValueError, match=r"not of the reference's family.*\(15 nodes\)"):
        adjoint_statics.Adjoint(scene).solve(other)


_SCRIPT = r"""
import json, os, sys
import jax
events = {"hits": 0, "misses": 0}
def listen(event, **_):
    if event == "/jax/compilation_cache/cache_hits": events["hits"] += 1
    if event == "/jax/compilation_cache/cache_misses": events["misses"] += 1
jax.monitoring.register_event_listener(listen)
sys.path[:0] = [sys.argv[1], os.path.dirname(sys.argv[1])]  # this module, and the tests' helpers
import test_adjoint_statics as t
from jaxnet.solve import adjoint_statics, programs
scene, x0 = t.panel_in_current()
programs.clear()
before = dict(events)
result = adjoint_statics.Adjoint(scene, t.NEWTON).value_and_grad(t.Deflection(), scene, x0)
print("RESULT " + json.dumps({"value": result.value, "grad": [float(jax.numpy.sum(abs(g))) for g in
      jax.tree.leaves(result.grad)], "misses": events["misses"] - before["misses"]}))
"""


def _process(cache):
    env = dict(os.environ, JAX_COMPILATION_CACHE_DIR=str(cache), JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS="0",
               JAX_PERSISTENT_CACHE_MIN_ENTRY_SIZE_BYTES="0")
    done = subprocess.run([sys.executable, "-c", _SCRIPT, os.path.dirname(__file__)], env=env, capture_output=True,
                          text=True, check=False, timeout=600)
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    assert lines, done.stderr[-3000:]
    return json.loads(lines[0][len("RESULT "):])


def test_the_gradients_programs_are_compiled_once_and_loaded_by_the_next_process(tmp_path):
    """With a compilation cache directory, a first process compiles the gradient's programs (the static solver's
    and the residual's reverse mode kept whole by jaxnet, the figure's by JAX's cache); a second process compiles
    nothing (no miss of JAX's cache after the scene is built), loads the residual's reverse mode without
    rewriting it, and computes the same gradient."""
    first = _process(tmp_path)
    kept = sorted((tmp_path / programs.SUBDIRECTORY).glob("residual_vjp-*.jaxexe"))
    assert len(kept) == 1 and first["misses"] > 0
    stamp = kept[0].stat().st_mtime_ns
    second = _process(tmp_path)
    assert second["misses"] == 0
    assert kept[0].stat().st_mtime_ns == stamp
    assert second["value"] == first["value"]
    np.testing.assert_allclose(second["grad"], first["grad"], rtol=1e-13, atol=0)
