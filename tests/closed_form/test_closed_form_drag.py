"""Closed-form drag stiffness (jaxnet.closed_form.drag) against jax.jacfwd of the drag forces, and the
book's printed drag equations 4.114-4.210 and 4.272-4.276 transcribed and evaluated (errata).

The current may vary with depth: the solver evaluates it at the element's centroid inside the
differentiated function (``jaxnet.terms.drag.water_velocity``); the harness below composes the two the same
way, with a 3-point profile, so that jacfwd sees dc/dz.
"""

import ast
import inspect

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from elements import central_differences, random_triangles, relative_difference

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.water import current
from jaxnet.closed_form import drag as closed
from jaxnet.terms import drag

L0, D, CN, CT, RHO = 0.05, 0.0012, 1.2, 0.15, 1025.0
F_RATIO = CT / CN  # the book's f
#: 3-point profile: factor 1 at 0 m, 0.6 at 5 m, 0.2 at 20 m depth; surface at z = 2 m
PROFILE_DEPTH, PROFILE_FACTOR, SURFACE = jnp.array([0.0, 5.0, 20.0]), jnp.array([1.0, 0.6, 0.2]), 2.0
UP = jnp.array([0.2, -0.3, 0.9]) / np.linalg.norm([0.2, -0.3, 0.9])
TOL = 1e-10
N = 120


def water(z, speed, direction):
    return current.current_velocity(z, speed, direction, PROFILE_DEPTH, PROFILE_FACTOR, SURFACE)


def slope(z, speed, direction):
    return closed.current_slope(z, speed, direction, PROFILE_DEPTH, PROFILE_FACTOR, SURFACE)


def netting_force(model):
    f = {"netting": drag.netting_drag, "femnet_catch": drag.netting_drag_femnet_catch}[model]
    return lambda x, uv, c: f(x, uv, L0, D, CN, CT, c, RHO)


def netting_closed(model):
    f = {"netting": closed.netting_drag_stiffness, "femnet_catch": closed.netting_drag_femnet_catch_stiffness}[model]
    return lambda x, uv, c, s=None, up=None: f(x, uv, L0, D, CN, CT, c, RHO, s, up)


def bar_force(x, c):
    return drag.bar_drag(x, 3.0 * L0, D, CN, CT, c, RHO)


def node_force(x, c):
    return drag.node_drag(0.07, c, RHO)[None, :]


def per_element_relative(k, ref):
    k, ref = np.asarray(k), np.asarray(ref)
    axes = tuple(range(1, ref.ndim))
    return np.max(np.abs(k - ref), axis=axes) / np.max(np.abs(ref), axis=axes)


def random_currents(n, seed):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(n, 3))
    return jnp.asarray(v / np.linalg.norm(v, axis=1)[:, None] * rng.uniform(0.2, 2.0, size=(n, 1)))


def random_elements(n, seed, depth=(-25.0, 3.0)):
    """Random well-conditioned triangles (half clockwise) placed at heights spanning the profile: above
    the surface, on each segment and below its last point."""
    x, uv = random_triangles(n, seed)
    rng = np.random.default_rng(seed + 1)
    x = x + (rng.uniform(*depth, size=n)[:, None] * np.asarray(UP))[:, None, :]
    return jnp.asarray(x), jnp.asarray(uv)


# ---------------------------------------------------------------------------------------------------
# one twine: the compact form of 4.136-4.210


def twine_args(axis, c):
    return (axis, L0, D, CN, CT, c, RHO)


def twine_total(axis, c):
    n, t = drag.twine_drag(*twine_args(axis, c))
    return n + t


@jax.jit
@jax.vmap
def twine_jacobians(w, c):
    """(autodiff ∂/∂axis, ∂/∂c), (closed ∂/∂axis, ∂/∂c) of one twine's drag."""
    auto = (jax.jacfwd(twine_total, 0)(w, c), jax.jacfwd(twine_total, 1)(w, c))
    return auto, closed.twine_drag_jacobians(*twine_args(w, c))


#: exact along (c_n = 0), against, across (c_t = 0), still water, zero axis, zero axis in still water
SINGULAR_W = np.array([[0.0625, 0.0, 0.0]] * 4 + [[0.0, 0.0, 0.0]] * 2)
SINGULAR_C = np.array([[1.5, 0.0, 0.0], [-0.75, 0.0, 0.0], [0.0, 1.25, -0.5], [0.0, 0.0, 0.0], [0.3, -1.1, 0.4], [0.0, 0.0, 0.0]])


def test_twine_drag_jacobians_equal_jacfwd():
    rng = np.random.default_rng(3)
    w = np.concatenate([rng.normal(size=(N, 3)) * L0, SINGULAR_W])
    c = np.concatenate([np.asarray(random_currents(N, 4)), SINGULAR_C])
    (ja, jc), (ka, kc) = (tuple(np.asarray(m) for m in pair) for pair in twine_jacobians(jnp.asarray(w), jnp.asarray(c)))
    assert per_element_relative(ka[:N], ja[:N]).max() <= TOL
    assert per_element_relative(kc[:N], jc[:N]).max() <= TOL
    # singular directions: |v| v has derivative 0 at v = 0, so the vanishing part contributes nothing;
    # finite and equal to jacfwd's values, which are checked against hand values here
    ka, kc, ja, jc = ka[N:], kc[N:], ja[N:], jc[N:]
    assert np.isfinite(ka).all() and np.isfinite(kc).all()
    scale = 0.5 * RHO * D * L0 * CN * 2.0
    np.testing.assert_allclose(ka, ja, rtol=0, atol=TOL * scale / L0)
    np.testing.assert_allclose(kc, jc, rtol=0, atol=TOL * scale)
    k_n, k_t = 0.5 * RHO * D * L0 * CN, 0.5 * RHO * D * L0 * CT
    # along: only the tangential part, c = c_t, ∂(|v| v)/∂v = |c| (I + ê ê^T): ∂/∂c = 2 K_t |c| ê ê^T, and
    # turning the twine turns its drag with it, ∂/∂W = K_t |c| (c.ê)(I - ê ê^T)/|W|
    np.testing.assert_allclose(kc[0], np.diag([2 * k_t * 1.5, 0.0, 0.0]), atol=1e-15)
    np.testing.assert_allclose(ka[0], k_t * 1.5 * 1.5 / 0.0625 * np.diag([0.0, 1.0, 1.0]), rtol=1e-13, atol=1e-15)
    # across: only the normal part, c = c_n: ∂/∂W = -K_n |c| (I + ĉ ĉ^T) ê c^T/|W|
    c = SINGULAR_C[2]
    expected = -k_n * np.linalg.norm(c) * (np.eye(3) + np.outer(c, c) / (c @ c)) @ np.outer([1.0, 0.0, 0.0], c) / 0.0625
    np.testing.assert_allclose(ka[2], expected, rtol=1e-13, atol=1e-15)
    # still water: nothing; zero axis: all of c normal, no axis dependence
    for k in (3, 5):
        np.testing.assert_array_equal(ka[k], 0.0)
        np.testing.assert_array_equal(kc[k], 0.0)
    np.testing.assert_array_equal(ka[4], 0.0)
    c = SINGULAR_C[4]
    np.testing.assert_allclose(kc[4], k_n * (np.linalg.norm(c) * np.eye(3) + np.outer(c, c) / np.linalg.norm(c)), rtol=1e-13)


# ---------------------------------------------------------------------------------------------------
# netting, both models, uniform and sheared current: one batch per model (random elements, then the hard
# cases), evaluated once by one jitted function (compiling is what takes time here)


def exact_element(clockwise, collapse_u=False):
    """A triangle with U exactly along x and V exactly along y (powers of two: every product exact), at
    about 4 m below z = 0 along UP."""
    uv = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])
    if clockwise:
        uv = uv[[0, 2, 1]]
    U = np.zeros(3) if collapse_u else np.array([0.0625, 0.0, 0.0])
    V = np.array([0.0, 0.0625, 0.0])
    x = uv[:, :1] * U + uv[:, 1:] * V + np.round(-4.0 * np.asarray(UP) * 2**20) / 2**20
    return x, uv


#: hard cases: (element options, current direction); U = x̂, V = ŷ, panel normal ẑ; each both orientations
HARD = {
    "along_u": ({}, [1.0, 0.0, 0.0]),
    "against_u": ({}, [-1.0, 0.0, 0.0]),
    "normal_to_u_along_v": ({}, [0.0, 1.0, 0.0]),
    "normal_to_u_not_v": ({}, [0.0, 0.5, 0.75]),
    "normal_to_panel": ({}, [0.0, 0.0, 1.0]),
    "still_water": ({}, [0.0, 0.0, 0.0]),
    "collapsed_u": ({"collapse_u": True}, [0.5, 0.25, 0.5]),
    "collapsed_u_along_v": ({"collapse_u": True}, [0.0, 1.0, 0.0]),
}
ZERO_OF_PROFILE = jnp.array([1.0, 0.0, 0.5])  # the current vanishes at 5 m depth, with a slope there


def netting_batch():
    """x (n, 3, 3), uv (n, 3, 2), speed (n,), direction (n, 3), profile factors (n, 3) and case names."""
    x, uv = random_elements(N, 21)
    c = random_currents(N, 22)
    xs, uvs, names = list(np.asarray(x)), list(np.asarray(uv)), ["random"] * N
    speeds, directions = list(np.linalg.norm(c, axis=1)), list(np.asarray(c))
    for clockwise in (False, True):
        for name, (options, direction) in HARD.items():
            xe, uve = exact_element(clockwise, **options)
            xs.append(xe), uvs.append(uve), names.append(name), speeds.append(1.25), directions.append(direction)
    # still water at a zero of the profile: a flat element whose centroid is exactly 5 m deep along UP
    xe, uve = exact_element(False)
    xs.append(xe - np.mean(xe, axis=0) + (SURFACE - 5.0) * np.asarray(UP))
    uvs.append(uve), names.append("zero_of_profile"), speeds.append(1.3), directions.append([1.0, 0.2, 0.0])
    factors = np.tile(np.asarray(PROFILE_FACTOR), (len(xs), 1))
    factors[-1] = ZERO_OF_PROFILE
    return (jnp.asarray(np.array(xs)), jnp.asarray(np.array(uvs)), jnp.asarray(np.array(speeds)),
            jnp.asarray(np.array(directions, float)), jnp.asarray(factors), np.array(names))


def _netting_stiffnesses(model):
    force, hand = netting_force(model), netting_closed(model)

    def one(x, uv, speed, direction, factors):
        def c_at(y):
            z = jnp.dot(geometry.centroid(y), UP)
            return current.current_velocity(z, speed, direction, PROFILE_DEPTH, factors, SURFACE)

        z = jnp.dot(geometry.centroid(x), UP)
        c = c_at(x)
        s = closed.current_slope(z, speed, direction, PROFILE_DEPTH, factors, SURFACE)
        return {
            "uniform_auto": -jax.jacfwd(force)(x, uv, c).reshape(9, 9),
            "uniform_closed": hand(x, uv, c),
            "sheared_auto": -jax.jacfwd(lambda y: force(y, uv, c_at(y)))(x).reshape(9, 9),
            "sheared_closed": hand(x, uv, c, s, UP),
            "slope": s,
            "c": c,
        }

    return jax.jit(jax.vmap(one))


_NETTING_CACHE = {}


def netting_results(model):
    if model not in _NETTING_CACHE:
        x, uv, speed, direction, factors, names = netting_batch()
        r = {k: np.asarray(v) for k, v in _netting_stiffnesses(model)(x, uv, speed, direction, factors).items()}
        _NETTING_CACHE[model] = r, names
    return _NETTING_CACHE[model]


@pytest.mark.parametrize("model", ["netting", "femnet_catch"])
@pytest.mark.parametrize("current_kind", ["uniform", "sheared"])
def test_netting_stiffness_equals_jacfwd_on_random_elements(model, current_kind):
    r, names = netting_results(model)
    random = names == "random"
    err = per_element_relative(r[current_kind + "_closed"][random], r[current_kind + "_auto"][random])
    assert err.max() <= TOL


@pytest.mark.parametrize("model", ["netting", "femnet_catch"])
def test_netting_stiffness_with_force_gives_the_terms_drag(model):
    """``with_force=True`` (the shielded drag's tangent uses it instead of the force function) returns the
    same stiffness and the term's own per-vertex drag, on random elements and on the singular ones."""
    x, uv, speed, direction, factors, names = netting_batch()
    c = jax.vmap(lambda x, s, d, fa: current.current_velocity(jnp.dot(geometry.centroid(x), UP), s, d, PROFILE_DEPTH,
                                                            fa, SURFACE))(x, speed, direction, factors)
    f = {"netting": closed.netting_drag_stiffness, "femnet_catch": closed.netting_drag_femnet_catch_stiffness}[model]
    k, forces = jax.vmap(lambda x, uv, c: f(x, uv, L0, D, CN, CT, c, RHO, with_force=True))(x, uv, c)
    expected = jax.vmap(netting_force(model))(x, uv, c)
    scale = np.abs(np.asarray(expected)).max()
    assert scale > 0.0
    np.testing.assert_allclose(forces, expected, rtol=1e-12, atol=1e-14 * scale)
    np.testing.assert_array_equal(k, jax.vmap(netting_closed(model))(x, uv, c))


@pytest.mark.parametrize("model", ["netting", "femnet_catch"])
def test_netting_depth_term_equals_jacfwd(model):
    # the depth term alone (sheared minus uniform at the same c): a wrong dc/dz term shows here at full
    # size, not diluted by the rest of the stiffness
    r, names = netting_results(model)
    random = names == "random"
    depth_a = (r["sheared_auto"] - r["uniform_auto"])[random]
    depth_c = (r["sheared_closed"] - r["uniform_closed"])[random]
    moving = np.abs(r["slope"][random]).max(axis=1) > 0
    assert moving.sum() > N // 2  # most elements sit on a sloping segment of the profile
    assert (~moving).sum() > 5  # some above the surface or below the last point: no depth term
    assert per_element_relative(depth_c[moving], depth_a[moving]).max() <= 1e-8
    np.testing.assert_array_equal(depth_c[~moving], 0.0)
    assert np.abs(depth_a[~moving]).max() <= 1e-14 * np.abs(r["uniform_auto"][random]).max()


@pytest.mark.parametrize("model", ["netting", "femnet_catch"])
@pytest.mark.parametrize("current_kind", ["uniform", "sheared"])
def test_netting_stiffness_hard_cases(model, current_kind):
    # exact singular directions, both orientations: the closed form is finite and equal to jacfwd's value
    # (the derivative of |v| v is 0 at v = 0; FEMNET's unit vectors across the flow are 0 where undefined;
    # a collapsed twine has no direction and no axis term)
    r, names = netting_results(model)
    hard = names != "random"
    ka, kc = r[current_kind + "_auto"][hard], r[current_kind + "_closed"][hard]
    assert np.isfinite(kc).all() and np.isfinite(ka).all()
    scale = 0.5 * RHO * D * L0 * CN * 1.25 * 2 / 0.0625  # N/m of one twine across the flow
    assert np.max(np.abs(kc - ka)) <= TOL * scale
    still = names[hard] == "still_water"
    # c = 0 is the kink of |c| c: zero derivative, exactly
    np.testing.assert_array_equal(kc[still], 0.0)
    np.testing.assert_array_equal(ka[still], 0.0)
    # also where the profile has a slope: the factor is 0 there up to the rounding of the centroid's height
    # (|c| ~ 1e-16 m/s), and so is the stiffness, in both paths
    zero = names[hard] == "zero_of_profile"
    assert np.abs(kc[zero]).max() <= 1e-12 * scale and np.abs(ka[zero]).max() <= 1e-12 * scale
    still = still | zero
    assert (np.abs(kc[~still]).max(axis=(1, 2)) > 1e-3 * scale).all()
    assert np.abs(r["slope"][names == "zero_of_profile"]).max() > 0.05


@pytest.mark.parametrize("model", ["netting", "femnet_catch"])
def test_sheared_closed_form_equals_finite_differences(model):
    # independent of autodiff: -dF/dx by central differences of the composed force, on a counter-clockwise
    # and a clockwise element of the batch that sit on a sloping segment of the profile
    r, names = netting_results(model)
    x, uv, speed, direction, _, _ = netting_batch()
    force = netting_force(model)
    composed = jax.jit(lambda y, uv, speed, direction: force(y, uv, water(jnp.dot(geometry.centroid(y), UP), speed, direction)))
    moving = np.flatnonzero((names == "random") & (np.abs(r["slope"]).max(axis=1) > 0))
    for k in moving[:2]:
        fd = -central_differences(lambda y: composed(jnp.asarray(y), uv[k], speed[k], direction[k]), x[k], 1e-6)
        assert relative_difference(r["sheared_closed"][k], fd) < 1e-7


# ---------------------------------------------------------------------------------------------------
# bars and nodes


def bar_closed(x, c, s=None, up=None):
    return closed.bar_drag_stiffness(x, 3.0 * L0, D, CN, CT, c, RHO, s, up)


def bar_batch():
    """Random bars at heights spanning the profile, then hard cases: along, across, against, still, zero length."""
    rng = np.random.default_rng(41)
    start = rng.normal(size=(N, 3)) + rng.uniform(-25.0, 3.0, size=(N, 1)) * np.asarray(UP)
    x = list(np.stack([start, start + rng.normal(size=(N, 3)) * 0.2], axis=1))
    c = list(np.asarray(random_currents(N, 42)))
    ends = np.array([[0.0, 0.0, -4.0], [0.125, 0.0, -4.0]])
    x += [ends] * 4 + [np.stack([ends[0], ends[0]])]
    c += [[1.0, 0.0, 0.0], [0.0, 0.5, 0.25], [-0.5, 0.0, 0.0], [0.0, 0.0, 0.0], [0.5, 0.25, 0.0]]
    c = np.array(c, float)
    return jnp.asarray(np.array(x)), jnp.asarray(np.linalg.norm(c, axis=1)), jnp.asarray(c)


@jax.jit
@jax.vmap
def _bar_and_node_stiffnesses(x, speed, direction):
    z = jnp.dot(geometry.centroid(x), UP)
    c, s = water(z, speed, direction), slope(z, speed, direction)
    node = x[:1]
    zn = jnp.dot(node[0], UP)
    return {
        "bar_uniform_auto": -jax.jacfwd(bar_force)(x, c).reshape(6, 6),
        "bar_uniform_closed": bar_closed(x, c),
        "bar_sheared_auto": -jax.jacfwd(lambda y: bar_force(y, water(jnp.dot(geometry.centroid(y), UP), speed, direction)))(x).reshape(6, 6),
        "bar_sheared_closed": bar_closed(x, c, s, UP),
        "node_auto": -jax.jacfwd(lambda y: node_force(y, water(jnp.dot(y[0], UP), speed, direction)))(node).reshape(3, 3),
        "node_closed": closed.node_drag_stiffness(0.07, water(zn, speed, direction), RHO, slope(zn, speed, direction),
                                                  UP),
    }


_BAR_CACHE = []


def bar_results():
    if not _BAR_CACHE:
        _BAR_CACHE.append({k: np.asarray(v) for k, v in _bar_and_node_stiffnesses(*bar_batch()).items()})
    return _BAR_CACHE[0]


@pytest.mark.parametrize("current_kind", ["uniform", "sheared"])
def test_bar_stiffness_equals_jacfwd(current_kind):
    r = bar_results()
    ka, kc = r[f"bar_{current_kind}_auto"], r[f"bar_{current_kind}_closed"]
    assert per_element_relative(kc[:N], ka[:N]).max() <= TOL
    # hard cases: finite, equal to jacfwd; still water: 0; a bar of zero length: no axis term
    scale = 0.5 * RHO * D * 3 * L0 * CN * 2 / 0.125
    assert np.isfinite(kc).all()
    assert np.max(np.abs(kc[N:] - ka[N:])) <= TOL * scale
    np.testing.assert_array_equal(kc[N + 3], 0.0)
    if current_kind == "uniform":
        np.testing.assert_array_equal(kc[N + 4], 0.0)


def test_node_stiffness_equals_jacfwd():
    r = bar_results()
    ka, kc = r["node_auto"][:N], r["node_closed"][:N]
    moving = np.abs(ka).max(axis=(1, 2)) > 0
    assert moving.sum() > N // 2
    assert per_element_relative(kc[moving], ka[moving]).max() <= TOL
    np.testing.assert_array_equal(kc[~moving], 0.0)
    # uniform current: a body's drag does not depend on where it is
    c = jnp.array([0.3, -0.2, 0.1])
    np.testing.assert_array_equal(closed.node_drag_stiffness(0.07, c, RHO, None), 0.0)
    # default vertical is +z: K = -½ ρ CdA (|c| I + c c^T/|c|) s ẑ^T
    s = jnp.array([0.1, -0.2, 0.0])
    expected = -0.5 * RHO * 0.07 * (np.linalg.norm(c) * np.eye(3) + np.outer(c, c) / np.linalg.norm(c)) @ np.outer(s, [0, 0, 1.0])
    np.testing.assert_allclose(closed.node_drag_stiffness(0.07, c, RHO, s), expected, rtol=1e-14, atol=1e-18)


# ---------------------------------------------------------------------------------------------------
# dc/dz of the profile


_profile_jacobian = jax.jit(jax.vmap(jax.jacfwd(
    lambda z, direction, surface: current.current_velocity(z, 1.4, direction, PROFILE_DEPTH, PROFILE_FACTOR, surface)),
    in_axes=(0, None, None)))


@pytest.mark.parametrize("surface", [SURFACE, float("nan")])
def test_current_slope_equals_jacfwd_of_the_profile(surface):
    s0 = 0.0 if np.isnan(surface) else surface
    direction = jnp.array([0.6, -0.3, 0.2])
    points = [s0 - d for d in (0.0, 5.0, 20.0)]  # each profile point exactly, and just off it
    zs = jnp.array(points + [p + e for p in points for e in (1e-9, -1e-9)] + [s0 + 4.0, s0 - 30.0, s0 - 2.5, s0 - 11.0])
    ref = _profile_jacobian(zs, direction, jnp.asarray(surface))
    got = closed.current_slope(zs, 1.4, direction, PROFILE_DEPTH, PROFILE_FACTOR, surface)
    np.testing.assert_array_equal(got, ref)
    unit = np.asarray(direction) / np.linalg.norm(direction)
    # the interior point (5 m) takes the deeper segment's slope; the last point the last segment's
    np.testing.assert_allclose(got[1], 1.4 * (0.4 / 15.0) * unit, rtol=1e-14)
    np.testing.assert_allclose(got[2], 1.4 * (0.4 / 15.0) * unit, rtol=1e-14)
    np.testing.assert_allclose(got[0], 1.4 * (0.4 / 5.0) * unit, rtol=1e-14)
    np.testing.assert_array_equal(got[-4:-2], 0.0)  # above the surface, below the last point


def test_current_slope_without_a_profile_or_with_one_point():
    for depth, factor in (([], []), ([3.0], [0.5])):
        got = closed.current_slope(jnp.array([-1.0, 4.0]), 1.0, jnp.array([1.0, 0.0, 0.0]), jnp.array(depth),
                                   jnp.array(factor), 0.0)
        np.testing.assert_array_equal(got, 0.0)
    # a zero direction: no current, no slope, no NaN
    got = closed.current_slope(-2.5, 1.0, jnp.zeros(3), PROFILE_DEPTH, PROFILE_FACTOR, 0.0)
    np.testing.assert_array_equal(got, 0.0)


def test_closed_form_module_uses_no_automatic_differentiation():
    # the code (not the docstrings, which name jacfwd as the reference) imports only jax.numpy and jaxnet
    # modules and calls no JAX transformation
    tree = ast.parse(inspect.getsource(closed))
    imported = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
    imported |= {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
    assert imported <= {"jax.numpy", "__future__", "jaxnet", "jaxnet.closed_form"}
    names = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)}
    names |= {node.id for node in ast.walk(tree) if isinstance(node, ast.Name)}
    assert not names & {"grad", "jacfwd", "jacrev", "hessian", "jvp", "vjp", "linearize", "jax"}


# ===================================================================================================
# Errata: the printed equations 4.114-4.210 and 4.272-4.276, transcribed as printed (numpy), evaluated on
# random well-conditioned elements (one counter-clockwise, one clockwise) and compared with the truth.


def book_4_125_4_126(x, uv):
    d = book_4_129(uv)
    s12, s13 = x[1] - x[0], x[2] - x[0]
    (U1, V1), (U2, V2), (U3, V3) = uv
    return (V3 - V1) / d * s12 - (V2 - V1) / d * s13, (U2 - U1) / d * s13 - (U3 - U1) / d * s12


def book_4_129(uv):
    (U1, V1), (U2, V2), (U3, V3) = uv
    return (U2 - U1) * (V3 - V1) - (U3 - U1) * (V2 - V1)


def book_4_131(x, uv):
    (U1, V1), (U2, V2), (U3, V3) = uv
    d = book_4_129(uv)
    return np.array([((V3 - V1) * (x[1, k] - x[0, k]) - (V2 - V1) * (x[2, k] - x[0, k])) / d for k in range(3)])


def book_4_134(x, uv):
    (U1, V1), (U2, V2), (U3, V3) = uv
    d = book_4_129(uv)
    return np.array([((U2 - U1) * (x[2, k] - x[0, k]) - (U3 - U1) * (x[1, k] - x[0, k])) / d for k in range(3)])


def book_4_132(c, U):
    return c @ U / (np.linalg.norm(c) * np.linalg.norm(U))


def book_4_114(c, U, d):
    sin = np.sqrt(1.0 - book_4_132(c, U) ** 2)  # α in [0, π]
    return 0.5 * RHO * CN * D * L0 * (np.linalg.norm(c) * sin) ** 2 * d / 2


def book_4_115(c, U, d):
    return F_RATIO * 0.5 * RHO * CN * D * L0 * (np.linalg.norm(c) * book_4_132(c, U)) ** 2 * d / 2


def book_4_116(c, U):
    e = np.cross(U, np.cross(c, U))
    return e / np.linalg.norm(e)


def book_4_117(F, c):
    e = np.cross(F, np.cross(c, F))
    return e / np.linalg.norm(e)


def book_4_136_to_4_141(c, U, d):
    """F = |F| E/|E| componentwise (4.137-4.139), E = U ^ (c ^ U) (4.140)."""
    E = np.cross(U, np.cross(c, U))
    return book_4_114(c, U, d) * E / np.linalg.norm(E)


def book_4_142(amp, amp_prime, E, E_prime, norm_E_prime):
    """F'_x = |F|' E_x/|E| + |F| (E'_x |E| - E_x |E|')/|E|² (vectorised over x, y, z)."""
    n = np.linalg.norm(E)
    return amp_prime * E / n + amp * (E_prime * n - E * norm_E_prime) / n**2


def book_4_143_to_4_145(amp, amp_prime, E, E_prime):
    n = np.linalg.norm(E)
    return amp_prime * E / n + amp / n**2 * (E_prime * n - E / n * (E @ E_prime))


def book_4_146(U, U_prime, c):
    return np.cross(U_prime, np.cross(c, U)) + np.cross(U, np.cross(c, U_prime))


def book_4_147_to_4_153(U, U_prime, c):
    return 2 * (U_prime @ U) * c - (U_prime @ c) * U - (U @ c) * U_prime


def book_4_154(c, d, sin2_prime):
    return 0.5 * RHO * CN * D * L0 * (c @ c) * sin2_prime * d / 2


def book_4_155(c, U, d, alpha_prime):
    cos = book_4_132(c, U)
    return d / 2 * RHO * CN * D * L0 * (c @ c) * cos * np.sqrt(1 - cos**2) * alpha_prime


def book_4_156(cos, cos_prime):
    return -1.0 / np.sqrt(1 - cos**2) * cos_prime


def book_4_157(c, U, unit_prime):
    return -1.0 / np.sqrt(1 - book_4_132(c, U) ** 2) * (c / np.linalg.norm(c) @ unit_prime)


def book_4_158(U, U_prime, norm_prime):
    n = np.linalg.norm(U)
    return (U_prime * n - U * norm_prime) / n**2


def book_4_159(c, U, U_prime, norm_prime):
    n = np.linalg.norm(U)
    return -1.0 / np.sqrt(1 - book_4_132(c, U) ** 2) * ((c / np.linalg.norm(c)) @ ((U_prime * n - U * norm_prime) / n**2))


def book_4_160(c, U, U_prime, norm_prime):
    n, sin = np.linalg.norm(U), np.sqrt(1 - book_4_132(c, U) ** 2)
    return -1.0 / (n**2 * np.linalg.norm(c) * sin) * (n * (c @ U_prime) - (c @ U) * norm_prime)


def book_4_162_to_4_176(uv):
    """(9, 3): ∂U/∂(x1, y1, z1, x2, ..., z3), rows in the vertex-major order."""
    (U1, V1), (U2, V2), (U3, V3) = uv
    d = book_4_129(uv)
    coef = [(V2 - V3) / d, (V3 - V1) / d, (V1 - V2) / d]
    return np.concatenate([k * np.eye(3) for k in coef])


def book_4_177(U, U_prime):
    return U @ U_prime / np.linalg.norm(U)


def book_4_178_to_4_186(U, uv):
    (U1, V1), (U2, V2), (U3, V3) = uv
    d, n = book_4_129(uv), np.linalg.norm(U)
    return np.concatenate([U * k / (d * n) for k in (V2 - V3, V3 - V1, V1 - V2)])


def book_4_187_to_4_195(c, U, uv):
    (U1, V1), (U2, V2), (U3, V3) = uv
    d, n, nc = book_4_129(uv), np.linalg.norm(U), np.linalg.norm(c)
    root = np.sqrt(1 - (c @ U / (nc * n)) ** 2)
    bracket = c * n - U / n * (c @ U)
    return np.concatenate([k / (d * n**2 * nc * root) * bracket for k in (V3 - V2, V1 - V3, V2 - V1)])


def book_4_197(c, U):
    E = np.cross(U, np.cross(c, U))
    e = np.cross(E, np.cross(c, E))
    return e / np.linalg.norm(e)


def book_4_198(c, U):
    e = ((U @ U) * (c @ c) - (U @ c) ** 2) * (U @ c) * U
    return e / np.linalg.norm(e)


def book_4_199(c, U):
    n, nc, cos = np.linalg.norm(U), np.linalg.norm(c), book_4_132(c, U)
    e = (n**2 * nc**2 - (n * nc * cos) ** 2) * n * nc * cos * U
    return e / np.linalg.norm(e)


def book_4_200_to_4_203(c, U, d):
    cos = book_4_132(c, U)
    return book_4_115(c, U, d) * cos * U / (abs(cos) * np.linalg.norm(U))


def book_4_204(amp, amp_prime, cos, U, cosU_prime, abscos_normU_prime):
    """T'_x = |T|' cos U_x/(|cos||U|) + |T| ((cos U_x)' |cos||U| - cos U_x (|cos||U|)')/(|cos||U|)²."""
    q = abs(cos) * np.linalg.norm(U)
    return amp_prime * cos * U / q + amp * (cosU_prime * q - cos * U * abscos_normU_prime) / q**2


def book_4_205(amp, amp_prime, cos, alpha_prime, U, U_prime):
    n, sin = np.linalg.norm(U), np.sqrt(1 - cos**2)
    q = abs(cos) * n
    bracket = abs(cos) * (U @ U_prime) / n - cos / abs(cos) * sin * alpha_prime * n
    return amp_prime * cos * U / q + amp / q * (cos * U_prime - sin * alpha_prime * U) - amp * cos * U / q**2 * bracket


def book_4_206_to_4_208(amp, amp_prime, T, cos, alpha_prime, U, U_prime):
    n, sin = np.linalg.norm(U), np.sqrt(1 - cos**2)
    q = abs(cos) * n
    bracket = abs(cos) * (U @ U_prime) / n - cos / abs(cos) * sin * alpha_prime * n
    return amp_prime * T / amp + amp / q * (cos * U_prime - sin * alpha_prime * U) - T / q * bracket


def book_4_209(c, d, cos2_prime):
    return F_RATIO * 0.5 * RHO * CN * D * L0 * (c @ c) * cos2_prime * d / 2


def book_4_210(c, U, d, alpha_prime):
    cos = book_4_132(c, U)
    return -d / 2 * F_RATIO * RHO * CN * D * L0 * (c @ c) * cos * np.sqrt(1 - cos**2) * alpha_prime


def book_4_272(c_i, U, d):
    return d / 6 * 0.5 * RHO * CN * D * L0 * (np.linalg.norm(c_i) * np.sqrt(1 - book_4_274(c_i, U) ** 2)) ** 2


def book_4_273(c_i, U, d):
    return d / 6 * F_RATIO * 0.5 * RHO * CN * D * L0 * (np.linalg.norm(c_i) * book_4_274(c_i, U)) ** 2


def book_4_274(c_i, U):
    return c_i @ U / (np.linalg.norm(c_i) * np.linalg.norm(U))


def book_4_275(c_i, U):
    n = np.linalg.norm(U)
    return np.cross(U / n, np.cross(c_i, U) / (np.linalg.norm(c_i) * n))


def book_4_276(F_unit, c_i, U):
    return np.cross(F_unit, np.cross(c_i, U) / (np.linalg.norm(c_i) * np.linalg.norm(U)))


# ---- book stiffness of the U twines, assembled from the printed pieces, per vertex coordinate (9 columns)


def book_normal_derivative(x, uv, c, count_d, form=book_4_143_to_4_145):
    """(3, 9) ∂F/∂x of the U twines' normal drag: 4.143-4.145 (or 4.142, with |E|' = E.E'/|E|) with E'
    (4.147), |F|' (4.155), α' (4.187-4.195), U' (4.162-4.176). ``count_d`` is the d of the printed d/2
    (4.114, 4.155)."""
    U = book_4_131(x, uv)
    E = np.cross(U, np.cross(c, U))
    amp = book_4_114(c, U, count_d)
    dU, dalpha = book_4_162_to_4_176(uv), book_4_187_to_4_195(c, U, uv)
    cols = []
    for j in range(9):
        amp_prime = book_4_155(c, U, count_d, dalpha[j])
        E_prime = book_4_147_to_4_153(U, dU[j], c)
        if form is book_4_142:
            cols.append(book_4_142(amp, amp_prime, E, E_prime, E @ E_prime / np.linalg.norm(E)))
        else:
            cols.append(book_4_143_to_4_145(amp, amp_prime, E, E_prime))
    return np.stack(cols, axis=1)


def book_tangential_derivative(x, uv, c, count_d, form=book_4_206_to_4_208):
    """(3, 9) ∂T/∂x of the U twines' tangential drag: 4.206-4.208 (or 4.205) with |T|' (4.210), α'
    (4.187-4.195), U' (4.162-4.176)."""
    U = book_4_131(x, uv)
    cos = book_4_132(c, U)
    amp, T = book_4_115(c, U, count_d), book_4_200_to_4_203(c, U, count_d)
    dU, dalpha = book_4_162_to_4_176(uv), book_4_187_to_4_195(c, U, uv)
    cols = []
    for j in range(9):
        amp_prime = book_4_210(c, U, count_d, dalpha[j])
        if form is book_4_205:
            cols.append(book_4_205(amp, amp_prime, cos, dalpha[j], U, dU[j]))
        elif form is book_4_204:
            # the inner derivatives of the quotient rule: (cos α U)' and (|cos α| |U|)'
            cos_prime = -np.sqrt(1 - cos**2) * dalpha[j]
            norm_prime = book_4_177(U, dU[j])
            cos_u_prime = cos_prime * U + cos * dU[j]
            q_prime = np.sign(cos) * cos_prime * np.linalg.norm(U) + abs(cos) * norm_prime
            cols.append(book_4_204(amp, amp_prime, cos, U, cos_u_prime, q_prime))
        else:
            cols.append(book_4_206_to_4_208(amp, amp_prime, T, cos, dalpha[j], U, dU[j]))
    return np.stack(cols, axis=1)


def _parts(x, uv, c):
    return drag.netting_drag_parts(x, uv, L0, D, CN, CT, c, RHO)


_parts_jac = jax.jit(jax.jacfwd(_parts))
_parts_jit = jax.jit(_parts)


def _alpha(x, uv, c):
    U, _, _ = geometry.twine_vectors(x, uv)
    return jnp.arccos(jnp.dot(c, U) / (jnp.linalg.norm(c) * jnp.linalg.norm(U)))


_alpha_jac = jax.jit(jax.jacfwd(_alpha))


def errata_elements():
    """One counter-clockwise (d > 0) and one clockwise (d < 0) random well-conditioned element, with a
    current at a general angle to both twines."""
    x, uv = random_triangles(2, 7)
    c = np.array([0.9, -0.35, 0.4])
    return [(np.asarray(x[k]), np.asarray(uv[k]), c) for k in range(2)]


def relative_error(printed, true):
    return float(np.max(np.abs(np.asarray(printed) - np.asarray(true))) / np.max(np.abs(np.asarray(true))))


def test_book_geometry_4_125_to_4_135_is_right():
    for x, uv, c in errata_elements():
        U, V, d = (np.asarray(a) for a in geometry.twine_vectors(jnp.asarray(x), jnp.asarray(uv)))
        assert book_4_129(uv) == pytest.approx(float(d), rel=1e-14)
        Ub, Vb = book_4_125_4_126(x, uv)
        assert relative_error(Ub, U) < 1e-13 and relative_error(Vb, V) < 1e-13
        assert relative_error(book_4_131(x, uv), U) < 1e-13 and relative_error(book_4_134(x, uv), V) < 1e-13
        alpha = float(_alpha(jnp.asarray(x), jnp.asarray(uv), jnp.asarray(c)))
        assert np.arccos(book_4_132(c, U)) == pytest.approx(alpha, rel=1e-13)


def test_book_amplitudes_4_114_4_115_have_the_sign_of_d():
    # right for d > 0; for d < 0 the printed d/2 makes the amplitude negative: printed = -true exactly
    for x, uv, c in errata_elements():
        U, _, d = geometry.twine_vectors(jnp.asarray(x), jnp.asarray(uv))
        U, d = np.asarray(U), float(d)
        parts = _parts_jit(jnp.asarray(x), jnp.asarray(uv), jnp.asarray(c))
        true_f, true_t = np.linalg.norm(parts["u_normal"]), np.linalg.norm(parts["u_tangential"])
        np.testing.assert_allclose(book_4_114(c, U, d), np.sign(d) * true_f, rtol=1e-13)
        np.testing.assert_allclose(book_4_115(c, U, d), np.sign(d) * true_t, rtol=1e-13)
        if d < 0:
            assert relative_error(book_4_114(c, U, d), true_f) == pytest.approx(2.0, rel=1e-12)


def test_book_directions_4_116_4_117_4_136_and_4_196_to_4_203():
    # right wherever defined (singular points: test_book_stiffness_singular_points)
    for x, uv, c in errata_elements():
        U, _, d = geometry.twine_vectors(jnp.asarray(x), jnp.asarray(uv))
        U, d = np.asarray(U), float(d)
        p = {k: np.asarray(v) for k, v in _parts_jit(jnp.asarray(x), jnp.asarray(uv), jnp.asarray(c)).items()}
        n_hat, t_hat = p["u_normal"] / np.linalg.norm(p["u_normal"]), p["u_tangential"] / np.linalg.norm(p["u_tangential"])
        assert relative_error(book_4_116(c, U), n_hat) < 1e-13
        assert relative_error(book_4_117(p["u_normal"], c), t_hat) < 1e-13
        for direction in (book_4_197, book_4_198, book_4_199):
            assert relative_error(direction(c, U), t_hat) < 1e-12
        # 4.136-4.141 and 4.200-4.203: the force vectors, with the sign of d (4.114-4.115)
        assert relative_error(book_4_136_to_4_141(c, U, d), np.sign(d) * p["u_normal"]) < 1e-13
        assert relative_error(book_4_200_to_4_203(c, U, d), np.sign(d) * p["u_tangential"]) < 1e-13


@jax.jit
def true_pieces(x, uv, c):
    """The true derivatives (jacfwd) of the quantities the book differentiates, per vertex coordinate (9 columns)."""
    def twine_u(y):
        return geometry.twine_vectors(y, uv)[0]

    def per_column(f):
        j = jax.jacfwd(f)(x)
        return j.reshape(-1, 9)

    return {
        "dU": per_column(twine_u).T,
        "dnorm": per_column(lambda y: jnp.linalg.norm(twine_u(y))[None]).ravel(),
        "dE": per_column(lambda y: jnp.cross(twine_u(y), jnp.cross(c, twine_u(y)))),
        "dalpha": per_column(lambda y: _alpha(y, uv, c)[None]).ravel(),
        "dcos": per_column(lambda y: jnp.cos(_alpha(y, uv, c))[None]).ravel(),
        "dunit": per_column(lambda y: twine_u(y) / jnp.linalg.norm(twine_u(y))),
        "dsin2": per_column(lambda y: jnp.sin(_alpha(y, uv, c))[None] ** 2).ravel(),
        "dcos2": per_column(lambda y: jnp.cos(_alpha(y, uv, c))[None] ** 2).ravel(),
        "damp": per_column(lambda y: jnp.linalg.norm(_parts(y, uv, c)["u_normal"])[None]).ravel(),
        "damp_t": per_column(lambda y: jnp.linalg.norm(_parts(y, uv, c)["u_tangential"])[None]).ravel(),
    }


def test_book_derivative_pieces_4_146_to_4_195_are_right():
    # E' (4.146-4.153), α' in all its printed forms (4.156-4.160, 4.187-4.195), U' (4.162-4.176),
    # |U|' (4.177-4.186), |F|' (4.154-4.155 up to the sign of d): each column against jacfwd
    for x, uv, c in errata_elements():
        xj, uvj, cj = jnp.asarray(x), jnp.asarray(uv), jnp.asarray(c)
        U, _, d = geometry.twine_vectors(xj, uvj)
        U, d = np.asarray(U), float(d)
        t = {k: np.asarray(v) for k, v in true_pieces(xj, uvj, cj).items()}
        dU = book_4_162_to_4_176(uv)
        assert relative_error(dU, t["dU"]) < 1e-13
        assert relative_error(book_4_178_to_4_186(U, uv), t["dnorm"]) < 1e-13
        assert relative_error([book_4_177(U, dU[j]) for j in range(9)], t["dnorm"]) < 1e-13
        assert relative_error(book_4_187_to_4_195(c, U, uv), t["dalpha"]) < 1e-12
        dnorm = book_4_178_to_4_186(U, uv)
        for j in range(9):
            scale = np.abs(t["dE"]).max()
            assert np.max(np.abs(book_4_146(U, dU[j], c) - t["dE"][:, j])) < 1e-13 * scale
            assert np.max(np.abs(book_4_147_to_4_153(U, dU[j], c) - t["dE"][:, j])) < 1e-13 * scale
            assert np.max(np.abs(book_4_158(U, dU[j], dnorm[j]) - t["dunit"][:, j])) < 1e-13 * np.abs(t["dunit"]).max()
            a_scale = np.abs(t["dalpha"]).max()
            assert abs(book_4_156(book_4_132(c, U), t["dcos"][j]) - t["dalpha"][j]) < 1e-12 * a_scale
            assert abs(book_4_157(c, U, t["dunit"][:, j]) - t["dalpha"][j]) < 1e-12 * a_scale
            assert abs(book_4_159(c, U, dU[j], dnorm[j]) - t["dalpha"][j]) < 1e-12 * a_scale
            assert abs(book_4_160(c, U, dU[j], dnorm[j]) - t["dalpha"][j]) < 1e-12 * a_scale
            s = np.sign(d)
            f_scale, t_scale = np.abs(t["damp"]).max(), np.abs(t["damp_t"]).max()
            assert abs(book_4_154(c, d, t["dsin2"][j]) - s * t["damp"][j]) < 1e-12 * f_scale
            assert abs(book_4_155(c, U, d, t["dalpha"][j]) - s * t["damp"][j]) < 1e-12 * f_scale
            assert abs(book_4_209(c, d, t["dcos2"][j]) - s * t["damp_t"][j]) < 1e-12 * t_scale
            assert abs(book_4_210(c, U, d, t["dalpha"][j]) - s * t["damp_t"][j]) < 1e-12 * t_scale


@pytest.mark.parametrize("twine", ["U", "V"])
def test_book_stiffness_4_142_to_4_210_is_right_up_to_the_sign_of_d(twine):
    # the whole printed chain (4.143-4.145 with 4.147, 4.155, 4.187-4.195, 4.162-4.176 for the normal drag;
    # 4.205 and 4.206-4.208 with 4.210 for the tangential drag) reproduces ∂F/∂x for d > 0 and gives exactly
    # its opposite for d < 0 (printed d/2 for the count |d|/2). The V twines (4.3.3.5, "V and β in place of
    # U and α") are read as the same formulas with the twine coordinates swapped (U_i <-> V_i, hence d -> -d
    # in the derivatives of V, 4.162-4.195), the count staying d/2 of 4.129.
    for x, uv, c in errata_elements():
        xj, uvj, cj = jnp.asarray(x), jnp.asarray(uv), jnp.asarray(c)
        d = book_4_129(uv)
        jac = {k: np.asarray(v).reshape(3, 9) for k, v in _parts_jac(xj, uvj, cj).items()}
        uv_book = uv if twine == "U" else uv[:, ::-1]
        key = "u" if twine == "U" else "v"
        normal = book_normal_derivative(x, uv_book, c, d)
        tangential = book_tangential_derivative(x, uv_book, c, d)
        tangential_205 = book_tangential_derivative(x, uv_book, c, d, form=book_4_205)
        tangential_204 = book_tangential_derivative(x, uv_book, c, d, form=book_4_204)
        normal_142 = book_normal_derivative(x, uv_book, c, d, form=book_4_142)
        s = np.sign(d)
        assert relative_error(normal, s * jac[key + "_normal"]) < 1e-10
        assert relative_error(normal_142, s * jac[key + "_normal"]) < 1e-10
        assert relative_error(tangential_204, s * jac[key + "_tangential"]) < 1e-10
        assert relative_error(tangential, s * jac[key + "_tangential"]) < 1e-10
        assert relative_error(tangential_205, s * jac[key + "_tangential"]) < 1e-10
        # and so the element stiffness: -(1/3) of the four twine derivatives on every vertex, against the
        # closed form; the printed one is off by a factor -1 for clockwise elements
        if twine == "U":
            other_n = book_normal_derivative(x, uv[:, ::-1], c, d)
            other_t = book_tangential_derivative(x, uv[:, ::-1], c, d)
            total = normal + tangential + other_n + other_t
            k_book = np.tile(-total / 3.0, (3, 1))
            k_closed = np.asarray(closed.netting_drag_stiffness(xj, uvj, L0, D, CN, CT, cj, RHO))
            err = relative_error(k_book, k_closed)
            if d > 0:
                assert err < 1e-10
            else:
                assert err == pytest.approx(2.0, rel=1e-10)
                assert relative_error(-k_book, k_closed) < 1e-10


def test_book_stiffness_singular_points():
    # 4.143 divides by |E| = |U|² |c| sin α and 4.156-4.160, 4.187-4.195 by sin α: 0/0 with the water along
    # the twine; 4.200-4.208 divide by |cos α|: 0/0 across it. The true stiffness is finite there (the
    # derivative of |v| v at v = 0 is 0) and the closed form gives it, equal to jacfwd.
    r, names = netting_results("netting")
    first = {name: int(np.flatnonzero(names == name)[0]) for name in ("along_u", "normal_to_panel")}
    x, uv, _, _, _, _ = netting_batch()
    k = first["along_u"]
    x, uv = np.asarray(x[k]), np.asarray(uv[k])  # counter-clockwise, U along x, V along y
    U = book_4_131(x, uv)
    d = book_4_129(uv)
    along, across = r["c"][first["along_u"]], r["c"][first["normal_to_panel"]]
    assert along[1] == along[2] == 0.0 and across[0] == across[1] == 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        assert np.isnan(book_4_116(along, U)).all()
        assert not np.isfinite(book_normal_derivative(x, uv, along, d)).all()
        assert not np.isfinite(book_4_187_to_4_195(along, U, uv)).all()
        assert not np.isfinite(book_tangential_derivative(x, uv, across, d)).all()
        assert np.isnan(book_4_200_to_4_203(across, U, d)).all()
    for k in first.values():
        k_closed, k_auto = r["uniform_closed"][k], r["uniform_auto"][k]
        assert np.isfinite(k_closed).all() and np.abs(k_auto).max() > 0
        assert np.max(np.abs(k_closed - k_auto)) <= TOL * np.abs(k_auto).max()


def test_book_normal_stiffness_loses_precision_near_the_twine_direction():
    # with sin α taken from cos α (4.114, 4.155, 4.160, 4.187: sqrt(1 - (c.U/|c||U|)²)) the printed forms
    # lose about eps/α² of relative accuracy as the water comes along the twine; the compact form, built on
    # c_n = c - c_t, does not (it agrees with jacfwd of the force to 1e-10 at α = 1e-6)
    x, uv, _ = errata_elements()[0]
    d = book_4_129(uv)
    U = book_4_131(x, uv)
    u_hat = U / np.linalg.norm(U)
    normal = np.cross(u_hat, [0.3, 0.7, -0.2])
    normal /= np.linalg.norm(normal)
    errors = []
    for alpha in (1e-2, 1e-6):
        c = 1.2 * (np.cos(alpha) * u_hat + np.sin(alpha) * normal)
        xj, uvj, cj = jnp.asarray(x), jnp.asarray(uv), jnp.asarray(c)
        jac = {k: np.asarray(v).reshape(3, 9) for k, v in _parts_jac(xj, uvj, cj).items()}
        errors.append(relative_error(book_normal_derivative(x, uv, c, d), jac["u_normal"]))
        k_auto = -np.tile(sum(jac.values()) / 3.0, (3, 1))
        k_closed = np.asarray(closed.netting_drag_stiffness(xj, uvj, L0, D, CN, CT, cj, RHO))
        assert relative_error(k_closed, k_auto) <= TOL
    assert errors[0] < 1e-10
    assert 1e-6 < errors[1] < 1e-3


def test_book_dynamic_drag_4_272_to_4_276():
    # per vertex, one third of the static drag of the U twines, with the relative velocity c_i
    x, uv, c = errata_elements()[1]  # clockwise: d < 0
    U, _, d = geometry.twine_vectors(jnp.asarray(x), jnp.asarray(uv))
    U, d = np.asarray(U), float(d)
    assert d < 0
    n_true, t_true = (np.asarray(f) * abs(d) / 6 for f in drag.twine_drag(jnp.asarray(U), L0, D, CN, CT, jnp.asarray(c), RHO))
    # 4.272-4.273: d/6 for |d|/6: the printed amplitudes are the true ones times sign(d) = -1
    np.testing.assert_allclose(book_4_272(c, U, d), -np.linalg.norm(n_true), rtol=1e-13)
    np.testing.assert_allclose(book_4_273(c, U, d), -np.linalg.norm(t_true), rtol=1e-13)
    for theta in (0.3, 2.5):
        # a current at angle θ to U in the plane of U and a normal
        u_hat = U / np.linalg.norm(U)
        normal = np.cross(u_hat, [0.3, 0.7, -0.2])
        normal /= np.linalg.norm(normal)
        ci = 1.1 * (np.cos(theta) * u_hat + np.sin(theta) * normal)
        assert np.arccos(book_4_274(ci, U)) == pytest.approx(theta, rel=1e-13)
        # 4.275: right direction, but of length sin θ, not a unit vector
        f_hat = book_4_275(ci, U)
        np.testing.assert_allclose(f_hat, np.sin(theta) * normal, atol=1e-15)
        assert relative_error(f_hat, normal) == pytest.approx(1 - np.sin(theta), rel=1e-12)
        # 4.276 with the true unit F̂: -sin θ û whatever the sign of c.U; true: sign(cos θ) û
        t_hat = book_4_276(normal, ci, U)
        np.testing.assert_allclose(t_hat, -np.sin(theta) * u_hat, atol=1e-15)
        # and with 4.275's F̂ as printed: -sin² θ û
        np.testing.assert_allclose(book_4_276(f_hat, ci, U), -np.sin(theta) ** 2 * u_hat, atol=1e-15)
        true_t_hat = np.sign(np.cos(theta)) * u_hat
        expected_error = 1 + np.sin(theta) if np.cos(theta) > 0 else 1 - np.sin(theta)
        assert relative_error(t_hat, true_t_hat) == pytest.approx(expected_error, rel=1e-12)
