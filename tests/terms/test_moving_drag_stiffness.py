"""The closed-form drag stiffness of a moving net (an implicit time step, book 4.272-4.276), against autodiff
and finite differences, and the waves' velocity gradient it needs.

In a time step each vertex i of a drag element takes its share of the element's drag computed with the water's
velocity relative to it, c_i = w(x_i) - (x_i - x_i^n)/Δt (:func:`jaxnet.terms.drag.per_vertex`), w the current at
the vertex's depth plus the waves' orbital velocity. The reference is ``jax.jacfwd`` of the term's own element
force with the velocity formed inside the differentiated function (what the autodiff path of
:func:`jaxnet.model.assemble.scatter_hessians` does); the closed form (:mod:`jaxnet.closed_form.drag`, as the term
declares it) takes the velocities and Δt. Cases: random states, still water, vertices
moving with the water (c_i = 0 with the water moving), water along a twine (c_n = 0), a catch front across the
netting (the shielding), both netting drag models made of twine drags.
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from elements import central_differences

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry, model as model_lib
from jaxnet.model import assemble
from jaxnet.water import waves
from jaxnet.terms import drag as drag_term
from jaxnet.net import Net, Rope, Twine
from jaxnet.scene import Environment
from jaxnet.solve import dynamics
from jaxnet.solve.options import Newton

TOL = 1e-10  # closed form against jacfwd, per element, relative to the element's largest entry
DT = 0.02  # s


def scene_in_waves():
    """A small panel in waves and a current falling with depth, with a rope along its top (bars) and two bodies
    with a drag area at its foot (node drag); held at its top corners."""
    airy = waves.Airy(1.6, 4.0, direction=(1.0, 0.4, 0.0), depth=6.0)
    env = Environment(current_speed=0.5, current_direction=np.array([1.0, 0.3, -0.1]),
                      profile_depth=np.array([0.0, 1.0, 3.0]), profile_factor=np.array([1.0, 0.6, 0.2]),
                      surface_level=0.0)
    env = eqx.tree_at(lambda e: e.waves, env, airy, is_leaf=lambda v: v is None)
    net = Net(environment=env)
    twine = Twine(l0=0.05, ea=2000.0, diameter=2e-3, cd_normal=1.2, tangential_ratio=0.1)
    panel = net.panel("netting", [(0.0, 0.0, -3.5, 0, 0), (1.5, 0.0, -3.5, 15, -15), (1.5, 0.0, -0.5, 45, 15),
                                  (0.0, 0.0, -0.5, 30, 30)], twine, 0.5)
    net.cable("headline", along=panel.side(2), rope=Rope(ea=5e4, diameter=8e-3))
    net.attach(panel.corner(0), mass=2.0, drag_area=0.05)
    net.attach(panel.corner(1), mass=2.0, drag_area=0.05)
    net.fix(panel.corner(2))
    net.fix(panel.corner(3))
    return net.build()


SCENE = scene_in_waves()
MODEL = model_lib.active_terms(SCENE, dynamic=True)
TERMS = {t.name: t for t in MODEL}


def test_the_scene_has_every_moving_drag_with_a_closed_form():
    assert {"netting_drag", "bar_drag", "node_drag"} <= set(TERMS)
    for name in ("netting_drag", "bar_drag", "node_drag"):
        assert TERMS[name].kwargs()["moving"] and TERMS[name].kwargs()["waves"]
    # a time step's tangent hands the velocities over: closed forms; without them the moving drags keep autodiff
    with_v = model_lib.stiffness_paths(MODEL, with_velocities=True)
    without = model_lib.stiffness_paths(MODEL)
    for name in ("netting_drag", "bar_drag", "node_drag"):
        assert with_v[name] == "closed_form" and without[name] == "autodiff"
    assert model_lib.stiffness_paths(MODEL, "autodiff", with_velocities=True)["netting_drag"] == "autodiff"


@jax.jit
def wave_gradients(airy, x, t):
    auto = jax.vmap(jax.jacfwd(lambda p: airy.velocity(p, t)))(x)
    return airy.velocity_gradient(x, t), auto


@pytest.mark.parametrize("depth", [6.0, float("inf")])
def test_wave_velocity_gradient_equals_jacfwd(depth):
    surface = 0.5
    airy = waves.Airy(1.6, 4.0, direction=(1.0, 0.4, 0.0), depth=depth, phase=0.3, surface_level=surface,
                      up=(0.1, 0.0, 1.0))
    up = np.asarray(airy.up)
    rng = np.random.default_rng(1)
    x = rng.uniform(-8.0, 8.0, size=(200, 3))
    # points on the mean surface and on the bed (where velocity's clamps start: their own derivative), beyond
    for k, z in enumerate([0.0, -6.0, 2.0, -9.0]):
        x[k] += (z + surface - x[k] @ up) * up
    closed, auto = (np.asarray(a) for a in wave_gradients(airy, jnp.asarray(x), 1.3))
    scale = np.abs(auto).max()
    assert scale > 0.1
    np.testing.assert_allclose(closed, auto, rtol=0, atol=1e-13 * scale)
    # above the surface (and below the bed) the velocity is held constant along the vertical
    z = x @ up - surface
    outside = (z > 1e-9) | (z < -depth - 1e-9)
    assert outside.sum() >= 20
    assert np.abs(closed[outside] @ up).max() <= 1e-13 * scale
    # still water: zero, and no NaN
    calm, _ = wave_gradients(waves.Airy(0.0, 4.0, depth=depth), jnp.asarray(x), 1.3)
    np.testing.assert_array_equal(np.asarray(calm), 0.0)


def element_rows(family, scene=SCENE):
    conn = np.asarray(assemble.connectivity(scene, family))
    rows = scene.nodes if family == "nodes" else getattr(scene, family)
    return conn, rows


@functools.partial(jax.jit, static_argnames=("term",))
def element_stiffness(term, env, x, p, xp, state=None, levels=None):
    """(closed form, -jacfwd) of one moving drag term on elements x (E, k, 3) with previous positions xp;
    ``levels``: the free surface's height over each vertex (E, k) (a time step in waves), None for the mean
    level."""
    if levels is not None:
        env = eqx.tree_at(lambda e: e.surface_elevation, env, jnp.zeros(1), is_leaf=lambda v: v is None)
    else:
        levels = jnp.zeros((x.shape[0], 0))

    def one(x, p, xp, level):
        local = assemble.element_environment(env, level)

        def force(v):
            v = v.reshape(x.shape)
            return term.force(v, p, local, state, velocity=(v - xp) / DT).ravel()

        auto = -jax.jacfwd(force)(x.ravel())
        return term.stiffness(x, p, local, state, velocity=(x - xp) / DT, time_step=DT), auto

    return jax.vmap(one)(x, p, xp, levels)


@jax.jit
def water_at(x, env):
    """(..., 3) the water's velocity (m/s) at points x: the current at their depth and the waves'."""
    return drag_term.water_velocity_at(x, env, True)


def states(family, seed):
    """Random element states: positions perturbed from the scene's (m), previous positions a step of random
    velocities (up to ~1.5 m/s) back."""
    conn, rows = element_rows(family)
    rng = np.random.default_rng(seed)
    x = np.asarray(SCENE.nodes.position)[conn] + 0.05 * rng.normal(size=conn.shape + (3,))
    xp = x - DT * rng.uniform(-1.5, 1.5, size=x.shape)
    return x, xp, rows


def per_element_relative(k, ref):
    return np.max(np.abs(k - ref), axis=(1, 2)) / np.max(np.abs(ref), axis=(1, 2))


def netting_with_a_front(x, rows):
    """The netting drag term with both models made of twine drags (FEMNET's catch variant, model 3, on every
    other element beside the twine drag, model 0) and the shielding of the netting behind a catch front across
    the panel (at the median height of the vertices: some elements cut, some wholly behind), with the rows and
    the front's state: the plain term's elements are among them (model 0, ahead of the front)."""
    term = TERMS["netting_drag"]
    both = model_lib.ActiveTerm(term.term, tuple(sorted({**term.kwargs(), "models": (0, 3), "shielded": True}.items())))
    rows = eqx.tree_at(lambda r: r.drag_model, rows, jnp.asarray(np.where(np.arange(x.shape[0]) % 2 == 0, 0, 3)))
    axis = np.array([0.0, 0.0, -1.0])
    front = np.median(x @ axis)
    state = {"front": jnp.asarray(front), "axis": jnp.asarray(axis), "pressure": jnp.asarray(100.0)}
    return both, rows, state


def compare(closed, auto):
    """Element by element to :data:`TOL`; elements without drag (behind the front) zero on both paths.
    Returns the count of elements without drag."""
    closed, auto = np.asarray(closed), np.asarray(auto)
    assert np.all(np.isfinite(closed))
    none = np.abs(auto).max(axis=(1, 2)) == 0.0
    np.testing.assert_array_equal(closed[none], 0.0)
    assert per_element_relative(closed[~none], auto[~none]).max() <= TOL
    return none.sum()


def wave_surface_levels(family, x, rows, seed):
    """(E, k) heights (m) of a wave's surface over the vertices x (E, k, 3) ((E,) for the nodes, as
    :func:`jaxnet.model.assemble.surface_levels` gives them), each within its element's immersion band of the vertex
    (1.2 bands wide): the wetted shares on their ramp and corners, each vertex its own."""
    if family == "nodes":
        band = drag_term.surface.node_band(rows.size, rows.volume)[:, None]
    else:
        band = drag_term.surface.immersion_band(rows.diameter)[:, None]
    u = np.random.default_rng(seed).uniform(-0.6, 0.6, size=x.shape[:2])
    levels = jnp.asarray(x[..., 2] + u * band)
    return levels[:, 0] if family == "nodes" else levels  # a node is its own element: one height


@pytest.mark.parametrize("surface", ["mean level", "waves"])
@pytest.mark.parametrize("name, family", [("netting_drag", "netting"), ("bar_drag", "bars"), ("node_drag", "nodes")])
def test_moving_drag_stiffness_equals_jacfwd(name, family, surface):
    """With the mean level the elements lie deep; with a wave's surface over each vertex (a time step in waves,
    :func:`jaxnet.model.assemble.element_environment`) each is partly wetted, and its wetted shares' slopes enter."""
    term, env = TERMS[name], SCENE.environment
    env = eqx.tree_at(lambda e: e.time, env, 0.7)
    x, xp, rows = states(family, seed=3)
    state = None
    if family == "netting":
        term, rows, state = netting_with_a_front(x, rows)
        heights = x @ np.asarray(state["axis"])
        assert ((heights.min(axis=1) < state["front"]) & (heights.max(axis=1) > state["front"])).sum() >= 3
    if family == "nodes":
        keep = np.flatnonzero(np.asarray(rows.drag_area) > 0)
        x, xp, rows = x[keep], xp[keep], jax.tree.map(lambda a: a[keep], rows)
    levels = wave_surface_levels(family, x, rows, seed=4) if surface == "waves" else None
    closed, auto = element_stiffness(term, env, jnp.asarray(x), rows, jnp.asarray(xp), state, levels)
    hidden = compare(closed, auto)
    if levels is not None:
        # the wave's surface changes the stiffness: the shares and their slopes are not those of deep water
        deep = element_stiffness(term, env, jnp.asarray(x), rows, jnp.asarray(xp), state)[1]
        assert per_element_relative(np.asarray(auto)[~(np.abs(auto).max(axis=(1, 2)) == 0)],
                                    np.asarray(deep)[~(np.abs(auto).max(axis=(1, 2)) == 0)]).min() > 0.01
    assert 3 <= hidden <= x.shape[0] - 5 if family == "netting" else hidden == 0
    # the vertex's own velocity enters: the damping -(1/Δt) dF/dc dominates the diagonal blocks here
    assert np.abs(np.asarray(auto)).max() > 10.0


def test_moving_netting_drag_degenerate_cases():
    """Still water (nothing moves: K = 0), vertices moving with the water (c_i = 0 with the water's velocity and
    its gradient not zero: K = 0), and the water along a twine at each vertex (c_n = 0 for U)."""
    env = eqx.tree_at(lambda e: e.time, SCENE.environment, 0.7)
    x, xp, rows = states("netting", seed=5)
    term, rows, state = netting_with_a_front(x, rows)
    x = jnp.asarray(x)
    still_env = eqx.tree_at(lambda e: (e.current_speed, e.waves.height), env, replace_fn=lambda v: v * 0)
    closed, auto = element_stiffness(term, still_env, x, rows, x, state)
    np.testing.assert_array_equal(np.asarray(closed), 0.0)
    np.testing.assert_array_equal(np.asarray(auto), 0.0)
    carried = x - DT * water_at(x, env)
    closed, auto = element_stiffness(term, env, x, rows, carried, state)
    assert np.abs(np.asarray(auto)).max() <= 1e-12 and np.abs(np.asarray(closed)).max() <= 1e-12
    # along U: c_i = s_i U (s_i of both signs)
    U = np.asarray(jax.jit(jax.vmap(lambda x, uv: geometry.twine_vectors(x, uv)[0]))(x, rows.uv))
    s = np.random.default_rng(6).uniform(-20.0, 20.0, size=(x.shape[0], 3))
    along = x - DT * (water_at(x, env) - s[:, :, None] * U[:, None, :])
    closed, auto = element_stiffness(term, env, x, rows, jnp.asarray(along), state)
    assert np.abs(np.asarray(auto)).max() > 1.0
    compare(closed, auto)


def test_moving_drag_stiffness_equals_finite_differences():
    """The closed form against central differences of the element force itself (no autodiff anywhere)."""
    env = eqx.tree_at(lambda e: e.time, SCENE.environment, 0.7)
    for name, family in (("netting_drag", "netting"), ("bar_drag", "bars")):
        term = TERMS[name]
        force = jax.jit(lambda v, p, xp, term=term: term.force(v, p, env, None, velocity=(v - xp) / DT))
        closed = jax.jit(lambda v, p, xp, term=term: term.stiffness(v, p, env, None, velocity=(v - xp) / DT,
                                                                    time_step=DT))
        x, xp, rows = states(family, seed=11)
        for e in range(2):
            p = jax.tree.map(lambda a: a[e], rows)
            fd = -central_differences(lambda v: force(v, p, xp[e]), x[e], 1e-6)
            k = np.asarray(closed(jnp.asarray(x[e]), p, jnp.asarray(xp[e])))
            assert np.abs(k - fd).max() <= 1e-6 * np.abs(fd).max()


def panel_in_waves():
    """The panel of :func:`scene_in_waves` alone, held along its top (a smaller program to compile twice)."""
    net = Net(environment=SCENE.environment)
    twine = Twine(l0=0.05, ea=2000.0, diameter=2e-3, cd_normal=1.2, tangential_ratio=0.1)
    panel = net.panel("netting", [(0.0, 0.0, -3.5, 0, 0), (1.5, 0.0, -3.5, 15, -15), (1.5, 0.0, -0.5, 45, 15),
                                  (0.0, 0.0, -0.5, 30, 30)], twine, 0.5)
    net.fix(panel.side(2))
    return net.build()


def test_both_paths_follow_the_same_trajectory():
    """Half a second of the panel in waves from rest, each stiffness path (the drag's tangent by autodiff, or by
    its closed form): the same positions to rounding, in the same number of Newton iterations."""
    scene = panel_in_waves()
    runs = {}
    for path in assemble.STIFFNESS_PATHS:
        newton = Newton(tol=1e-6, max_iter=30, damping=1e-12, stall_window=None, stiffness=path)
        runs[path] = dynamics.simulate(scene, 0.5, dynamics.Implicit(time_step=0.05, newton=newton), record_every=0.25)
    a, c = runs["autodiff"], runs["closed_form"]
    assert np.abs(a.positions[-1] - a.positions[0]).max() > 0.5  # the net swings
    np.testing.assert_allclose(c.positions, a.positions, rtol=0, atol=1e-9)
    assert int(c.state.iterations) == int(a.state.iterations)
