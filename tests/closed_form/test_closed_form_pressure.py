"""Closed-form stiffness of the catch pressure (4.246-4.264) and of inertia (4.265-4.271) vs autodiff, and
the errata of 4.246-4.271 and 4.277 (each printed form transcribed as ``book_4_xxx`` and evaluated)."""

import inspect
import itertools
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.closed_form import inertia as cf_inertia
from jaxnet.closed_form import pressure as cf_pressure
from jaxnet.terms import gravity, inertia, pressure
from elements import random_triangles, relative_difference  # tests/elements.py

P = 2590.175  # ½ 1025 · 1.4 · 1.9² Pa (FEMNET's c2)
TOL = 1e-10


def autodiff_stiffness(x, p, front, axis, sign):
    return -jax.jacfwd(pressure.catch_pressure)(x, p, front, axis, sign).reshape(9, 9)


both_stiffness = jax.jit(jax.vmap(lambda x, p, f, a, s: (autodiff_stiffness(x, p, f, a, s),
                                                         cf_pressure.catch_pressure_stiffness(x, p, f, a, s))))
force = jax.jit(pressure.catch_pressure)
weights = jax.jit(pressure.clipped_shape_integrals)
BATCH = 128  # every batch is padded to this size, so that both_stiffness compiles once (compiling dominates)


def pad(a, n=BATCH):
    a = np.asarray(a)
    return np.concatenate([a, np.repeat(a[:1], n - len(a), axis=0)])


def one_stiffness(x, p, front, axis, sign):
    """(autodiff, closed form) (9, 9) of one element, through the batched both_stiffness."""
    auto, closed = both_stiffness(pad([x]), np.full(BATCH, p), pad([front]), pad([axis]), np.full(BATCH, sign))
    return np.asarray(auto[0]), np.asarray(closed[0])
both_weight_jacobians = jax.jit(jax.vmap(lambda h: (jax.jacfwd(pressure.clipped_shape_integrals)(h),
                                                    cf_pressure.clipped_shape_integrals_jacobian(h))))


def assert_agree(k_auto, k_closed):
    """Per element: relative difference <= TOL, or both exactly zero; and everything finite."""
    k_auto, k_closed = np.asarray(k_auto), np.asarray(k_closed)
    assert np.all(np.isfinite(k_auto)) and np.all(np.isfinite(k_closed))
    for a, c in zip(k_auto, k_closed):
        if np.max(np.abs(a)) == 0.0:
            assert np.max(np.abs(c)) == 0.0
        else:
            assert relative_difference(c, a) <= TOL


def test_closed_form_modules_use_no_autodiff():
    pattern = re.compile(r"\b(grad|jacfwd|jacrev|hessian|jvp|vjp|linearize)\b|^import jax\s*$|^from jax import", re.M)
    for module in (cf_pressure, cf_inertia):
        assert pattern.search(inspect.getsource(module)) is None, module.__name__


# --------------------------------------------------------------------------------------------------
# ∂w/∂h of the clipped shape integrals
# --------------------------------------------------------------------------------------------------


def test_weight_jacobian_on_random_heights_and_every_sign_pattern():
    rng = np.random.default_rng(5)
    generic = rng.normal(size=(200, 3))
    # all 27 patterns of (-, 0, +), 0 exactly: the boundaries where "0 counts as ahead" decides the piece
    patterns = np.array(list(itertools.product((-1.0, 0.0, 1.0), repeat=3)))
    boundary = np.concatenate([patterns * rng.uniform(0.2, 2.0, size=(27, 3)) for _ in range(4)])
    h = np.concatenate([generic, boundary])
    auto, closed = both_weight_jacobians(h)
    assert_agree(auto, closed)
    # the pieces are all hit: jacobians with a non-zero entry on exactly the cut patterns
    behind = (h > 0).sum(axis=1)
    nonzero = np.abs(np.asarray(closed)).max(axis=(1, 2)) > 0
    assert np.all(~nonzero[(behind == 0) | (behind == 3)])
    cut = (behind == 1) | ((behind == 2) & (h.min(axis=1) < 0))
    assert np.all(nonzero[cut])
    # and the closed form is the derivative: central differences on a generic cut element
    k = int(np.flatnonzero(cut[:200])[0])
    eps = 1e-6
    fd = np.stack([(weights(h[k] + eps * e) - weights(h[k] - eps * e)) / (2 * eps) for e in np.eye(3)], axis=1)
    np.testing.assert_allclose(closed[k], fd, rtol=1e-8, atol=1e-9)


# --------------------------------------------------------------------------------------------------
# Element stiffness on random well-conditioned triangles
# --------------------------------------------------------------------------------------------------


def random_elements(n=BATCH, seed=3):
    """x (n, 3, 3), axis (n, 3), sign (n,), with both signs and both vertex orders (a quarter each)."""
    x, _ = random_triangles(n, seed)
    k = np.arange(n)
    x = np.where(((k // 2) % 2 == 1)[:, None, None], x[:, [0, 2, 1]], x)
    rng = np.random.default_rng(seed + 1)
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    sign = np.where(k % 2 == 0, 1.0, -1.0)
    return x, axis, sign, rng


@pytest.mark.parametrize("behind", [3, 0, 1, 2])
def test_stiffness_matches_autodiff_on_random_elements(behind):
    x, axis, sign, rng = random_elements()
    h = np.sort(np.einsum("nij,nj->ni", x, axis), axis=1)
    frac = rng.uniform(0.05, 0.95, size=len(x))
    front = {3: h[:, 0] - 0.01, 0: h[:, 2] + 0.01,
             1: h[:, 1] + frac * (h[:, 2] - h[:, 1]), 2: h[:, 0] + frac * (h[:, 1] - h[:, 0])}[behind]
    heights = np.asarray(jax.vmap(pressure.front_heights)(x, front, axis))
    assert np.all((heights > 0).sum(axis=1) == behind)
    pressures = P * rng.uniform(0.5, 2.0, size=len(x))
    auto, closed = both_stiffness(x, pressures, front, axis, sign)
    assert_agree(auto, closed)
    if behind == 0:
        assert np.max(np.abs(np.asarray(closed))) == 0.0
    else:
        assert np.min(np.abs(np.asarray(closed)).max(axis=(1, 2))) > 0.0


def test_stiffness_equals_finite_differences_on_a_cut_triangle():
    x, axis, _, _ = random_elements(seed=11)
    x, axis = x[0], axis[0]
    h = np.sort(x @ axis)
    front = 0.5 * (h[0] + h[1])  # two behind
    eps = 1e-7
    fd = np.zeros((9, 9))
    for k in range(9):
        e = np.zeros(9)
        e[k] = eps
        e = e.reshape(3, 3)
        df = force(x + e, P, front, axis, -1.0) - force(x - e, P, front, axis, -1.0)
        fd[:, k] = -np.asarray(df).ravel() / (2 * eps)
    assert relative_difference(one_stiffness(x, P, front, axis, -1.0)[1], fd) < 1e-7


def hard_cases():
    """(name, x, front, axis) on the boundaries of the pieces and for degenerate triangles."""
    rng = np.random.default_rng(17)
    ez = np.array([0.0, 0.0, 1.0])
    cases = []
    for k in range(3):
        x = rng.normal(size=(3, 3)) * 0.1
        others = [j for j in range(3) if j != k]
        x[others[0], 2], x[others[1], 2] = x[k, 2] + 0.05, x[k, 2] - 0.07  # one on each side
        cases.append((f"vertex {k} on the front, one behind", x, x[k, 2], ez))
        cases.append((f"vertex {k} on the front, axis reversed", x, -x[k, 2], -ez))
        y = x.copy()
        y[others[1], 2] = x[k, 2] + 0.02  # the two others behind
        cases.append((f"vertex {k} on the front, two behind", y, y[k, 2], ez))
        z = x.copy()
        z[others[0], 2] = x[k, 2]  # the front through vertices k and others[0]
        cases.append(("front through two vertices, third ahead", z, z[k, 2], ez))
        cases.append(("front through two vertices, third behind", z, -z[k, 2], -ez))
    x = rng.normal(size=(3, 3)) * 0.1
    collinear = np.array([x[0], x[1], x[0] + 0.4 * (x[1] - x[0])])
    cases.append(("zero-area (collinear), cut", collinear, float(np.median(collinear[:, 2])) + 1e-3, ez))
    point = np.tile(x[0], (3, 1))
    cases.append(("zero-area (one point), behind", point, x[0, 2] - 0.1, ez))
    cases.append(("zero-area (one point), on the front", point, x[0, 2], ez))
    flat = x.copy()
    flat[:, 2] = 0.3
    cases.append(("flat triangle in the front plane", flat, 0.3, ez))
    return cases


def test_stiffness_on_hard_cases():
    cases = hard_cases()
    x = np.array([c[1] for c in cases])
    front = np.array([c[2] for c in cases])
    axis = np.array([c[3] for c in cases])
    heights = np.asarray(jax.vmap(pressure.front_heights)(x, front, axis))
    # the cases really lie on the boundaries: at least one height exactly 0 (but the cut collinear one)
    assert np.sum(np.any(heights == 0.0, axis=1)) == len(cases) - 2
    n = len(cases)
    for sign in (1.0, -1.0):
        auto, closed = both_stiffness(pad(x), np.full(BATCH, P), pad(front), pad(axis), np.full(BATCH, sign))
        assert_agree(auto[:n], closed[:n])
    closed = np.asarray(closed)[:n]
    names = [c[0] for c in cases]
    # a point triangle: n = 0 and ∂n/∂x = 0, no stiffness; nothing behind a flat triangle in the front plane
    assert np.max(np.abs(closed[names.index("zero-area (one point), behind")])) == 0.0
    assert np.max(np.abs(closed[names.index("flat triangle in the front plane")])) == 0.0
    # a collinear triangle has n = 0 but ∂n/∂x != 0: a finite, non-zero stiffness
    assert np.max(np.abs(closed[names.index("zero-area (collinear), cut")])) > 0.0


# --------------------------------------------------------------------------------------------------
# Inertia
# --------------------------------------------------------------------------------------------------

inertia_jac = jax.jit(jax.vmap(lambda *a: -jax.jacfwd(inertia.inertia_force)(*a)))
inertia_closed = jax.jit(jax.vmap(cf_inertia.inertia_stiffness))


@pytest.mark.parametrize("per_axis", [False, True])
def test_inertia_stiffness_matches_autodiff(per_axis):
    rng = np.random.default_rng(23)
    n = 120
    x, x1, x2 = (rng.normal(size=(n, 3)) for _ in range(3))
    dt = rng.uniform(0.01, 1.0, size=n)
    mass = rng.uniform(0.0, 2.0, size=n)
    added = rng.uniform(0.0, 2.0, size=(n, 3) if per_axis else n)
    volume, rho = rng.uniform(0.0, 1e-3, size=n), np.full(n, 1025.0)
    gamma_h = rng.normal(size=(n, 3))
    args = (x, x1, x2, dt, mass, added, volume, rho, gamma_h)
    auto, closed = inertia_jac(*args), inertia_closed(*args)
    assert_agree(auto, closed)
    expect = (mass[:, None] + (added if per_axis else added[:, None])) / dt[:, None] ** 2
    np.testing.assert_allclose(np.diagonal(np.asarray(closed), axis1=1, axis2=2), np.broadcast_to(expect, (n, 3)),
                               rtol=1e-14)


def test_inertia_force_of_a_uniform_acceleration():
    # x(t) = x0 + v0 t + ½ g t²: the second backward difference is exact, γ = g
    g, v0, x0, dt = np.array([0.3, -1.2, 0.5]), np.array([1.0, 2.0, -0.5]), np.array([0.1, 0.2, 0.3]), 0.2
    path = lambda t: x0 + v0 * t + 0.5 * g * t**2
    t = 1.3
    M, Ma, V, rho, gh = 0.8, 0.5, 2e-4, 1025.0, np.array([0.0, 0.4, -0.1])
    f = inertia.inertia_force(path(t), path(t - dt), path(t - 2 * dt), dt, M, Ma, V, rho, gh)
    np.testing.assert_allclose(f, Ma * (gh - g) + rho * V * gh - M * g, rtol=1e-12, atol=1e-12)
    # moving with the water (γ = γ_h) the added mass exerts nothing: F = (rho V - M) γ_h
    f = inertia.inertia_force(path(t), path(t - dt), path(t - 2 * dt), dt, M, Ma, V, rho, g)
    np.testing.assert_allclose(f, (rho * V - M) * g, rtol=1e-12)


def test_netting_vertex_mass_weighs_the_books_4277():
    uv = np.array([[0.0, 0.0], [3.0, 1.0], [1.0, 4.0]])
    l0, D, rho_n, rho, g, up = 0.05, 2e-3, 1140.0, 1025.0, 9.81, np.array([0.0, 0.0, 1.0])
    for order in ([0, 1, 2], [0, 2, 1]):
        mass, volume = inertia.netting_vertex_mass(uv[order], l0, D, rho_n)
        weight = gravity.netting_weight(uv[order], l0, D, rho_n, rho, g, up)
        np.testing.assert_allclose(weight[:, 2], -(mass - rho * volume) * g, rtol=1e-14)
        np.testing.assert_allclose(3 * volume, 11.0 * np.pi * D**2 / 4 * l0, rtol=1e-14)  # |d| = 11


# --------------------------------------------------------------------------------------------------
# Errata: printed forms 4.246-4.271 and 4.277
# --------------------------------------------------------------------------------------------------


def book_4_246(rho, cd, v):
    return 0.5 * rho * cd * v**2


def book_4_247_249(x, p):
    x1, x2, x3 = x
    f = np.cross(x2 - x1, x3 - x1) / 2 * p / 3
    return np.stack([f, f, f])


def book_4_250(x):
    """Printed 12: four rows, the fourth "x3 - x1"."""
    (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = x
    return np.array([x2 - x1, y2 - y1, z2 - z1, x3 - x1])


def book_4_251_rows_2_3(x):
    """Printed 13: first row "x3 x1" (no operator), then y3 - y1, z3 - z1."""
    (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = x
    return np.array([y3 - y1, z3 - z1])


def book_4_252_254(x, p):
    (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = x
    return p / 6 * np.array([(y2 - y1) * (z3 - z1) - (z2 - z1) * (y3 - y1),
                             (z2 - z1) * (x3 - x1) - (x2 - x1) * (z3 - z1),
                             (x2 - x1) * (y3 - y1) - (y2 - y1) * (x3 - x1)])


def book_4_255(x, dx, p):
    """F1' = (12' ^ 13 + 12 ^ 13') p/6 along a variation dx (3, 3) of the positions."""
    x1, x2, x3 = x
    d1, d2, d3 = dx
    return (np.cross(d2 - d1, x3 - x1) + np.cross(x2 - x1, d3 - d1)) * p / 6


def book_4_256_264(x, p):
    """(3, 3, 3) [j, n, m]: ∂F1_m/∂(coordinate n of vertex j) as printed."""
    (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = x
    return p / 6 * np.array([
        [[0, z3 - z2, y2 - y3], [z2 - z3, 0, x3 - x2], [y3 - y2, x2 - x3, 0]],    # 4.256-4.258
        [[0, z1 - z3, y3 - y1], [z3 - z1, 0, x1 - x3], [y1 - y3, x3 - x1, 0]],    # 4.259-4.261
        [[0, z2 - z1, y1 - y2], [z1 - z2, 0, x2 - x1], [y2 - y1, x1 - x2, 0]],    # 4.262-4.264
    ])


def book_4_265(Ma, gamma_h, gamma, rho, V, M):
    return Ma * (gamma_h - gamma) + rho * V * gamma_h - M * gamma


def book_4_266(x, x1, dt):
    return (x1 - x) / dt


def book_4_267(v1, v, dt):
    return (v1 - v) / dt


def book_4_268(x, x1, x2, dt):
    return (x2 - 2 * x1 + x) / dt**2


def book_4_271(M, Ma, dt):
    return (M + Ma) / dt**2


def book_4_277(d, D, l0, rho_netting, rho, g):
    return d * np.pi * D**2 / 4 * l0 * (rho_netting - rho) * g


def one_element(seed=29):
    x, uv = random_triangles(2, seed)
    return np.asarray(x[0]), np.asarray(uv[0]), np.asarray(x[1]), np.asarray(uv[1])


def test_book_4246_is_the_dynamic_pressure():
    assert float(pressure.dynamic_pressure(1025.0, 1.4, 1.9)) == pytest.approx(book_4_246(1025.0, 1.4, 1.9), rel=1e-15)


def test_book_4247_to_4254_are_the_force_of_a_triangle_wholly_behind():
    x, _, _, _ = one_element()
    axis = np.array([0.6, 0.0, 0.8])
    front = float(np.min(x @ axis)) - 0.1
    f = np.asarray(force(x, P, front, axis, 1.0))
    assert relative_difference(book_4_247_249(x, P), f) < 1e-14
    assert relative_difference(np.tile(book_4_252_254(x, P), (3, 1)), f) < 1e-14
    # convention: the printed force pushes along 12 ^ 13; a triangle whose 12 ^ 13 points into the catch
    # (sign = -1, FEMNET's vertex order) gets minus it: relative difference 2
    assert relative_difference(book_4_247_249(x, P), force(x, P, front, axis, -1.0)) == pytest.approx(2.0)
    # on a triangle cut by the front (one vertex behind) 4.247 loads the whole surface; the load is the
    # fraction behind, h_a² / ((h_a - h_b)(h_a - h_c)) of it (similar triangles)
    heights = np.sort(x @ axis)[::-1]
    cut_front = 0.5 * (heights[0] + heights[1])
    h = heights - cut_front
    cut = np.asarray(force(x, P, cut_front, axis, 1.0))
    fraction = h[0] ** 2 / ((h[0] - h[1]) * (h[0] - h[2]))
    book = book_4_247_249(x, P)
    assert np.linalg.norm(cut.sum(0)) / np.linalg.norm(book.sum(0)) == pytest.approx(fraction, rel=1e-12)
    assert relative_difference(book, cut) > 1.0


def test_book_4250_4251_are_garbled_and_4252_uses_the_side_vectors():
    x, _, _, _ = one_element()
    printed = book_4_250(x)
    assert printed.shape == (4,)  # not a 3-vector
    # its first three rows are 12 and its fourth is the first row of 13 (x3 - x1), misplaced
    np.testing.assert_array_equal(printed[:3], x[1] - x[0])
    assert printed[3] == x[2, 0] - x[0, 0]
    side13 = np.concatenate([[printed[3]], book_4_251_rows_2_3(x)])
    np.testing.assert_array_equal(side13, x[2] - x[0])
    assert relative_difference(np.cross(printed[:3], side13) * P / 6, book_4_252_254(x, P)) < 1e-14


def test_book_4255_is_the_derivative_of_the_cross_product():
    x, _, _, _ = one_element()
    dx = np.random.default_rng(31).normal(size=(3, 3))
    axis = np.array([0.0, 1.0, 0.0])
    front = float(np.min(x @ axis)) - 0.1
    k_auto, k_closed = one_stiffness(x, P, front, axis, 1.0)
    jvp, auto = -k_closed @ dx.ravel(), (-k_auto @ dx.ravel()).reshape(3, 3)
    for i in range(3):
        assert relative_difference(book_4_255(x, dx, P), jvp.reshape(3, 3)[i]) < 1e-13
        assert relative_difference(book_4_255(x, dx, P), auto[i]) < 1e-13


def test_book_4256_to_4264_are_minus_the_stiffness_of_a_triangle_wholly_behind():
    x, _, x_b, _ = one_element()
    axis = np.array([0.0, 0.0, 1.0])
    front = float(np.min(x[:, 2])) - 0.1
    printed = book_4_256_264(x, P)  # [j, n, m]
    k_auto, k_closed = one_stiffness(x, P, front, axis, 1.0)
    k, auto = k_closed.reshape(3, 3, 3, 3), -k_auto.reshape(3, 3, 3, 3)  # [i, m, j, n]
    for i in range(3):  # "the derivatives of F1, F2 and F3 are identical"
        assert relative_difference(-k[i].transpose(1, 2, 0), printed) < 1e-13
        assert relative_difference(auto[i].transpose(1, 2, 0), printed) < 1e-13
    # on a triangle cut by the front (which the book does not treat) they are not the derivative
    h = np.sort(x_b[:, 2])
    k_cut = one_stiffness(x_b, P, 0.5 * (h[0] + h[1]), axis, 1.0)[1].reshape(3, 3, 3, 3)
    assert relative_difference(-k_cut[0].transpose(1, 2, 0), book_4_256_264(x_b, P)) > 0.1


def test_book_4265_is_the_inertia_force():
    rng = np.random.default_rng(37)
    x, x1, x2, gh = (rng.normal(size=3) for _ in range(4))
    dt, M, Ma, V, rho = 0.1, 0.7, 0.4, 3e-4, 1025.0
    gamma = (x - 2 * x1 + x2) / dt**2
    f = inertia.inertia_force(x, x1, x2, dt, M, Ma, V, rho, gh)
    assert relative_difference(f, book_4_265(Ma, gh, gamma, rho, V, M)) < 1e-14


def test_book_4266_4267_have_the_wrong_sign_and_4268_is_right():
    dt, t = 0.05, 2.0
    c, g, j = np.array([1.0, -2.0, 0.5]), np.array([0.3, 0.1, -0.4]), np.array([0.6, -0.2, 0.1])
    path = lambda s: c * s + 0.5 * g * s**2 + j * s**3 / 6
    x, x1, x2 = path(t), path(t - dt), path(t - 2 * dt)
    velocity = (x - x1) / dt  # backward difference at t (the velocity is c + g t + j t²/2 + O(dt))
    # 4.266 (x: position at t, x1: at t - dt) is minus the backward difference: relative error 2
    assert relative_difference(book_4_266(x, x1, dt), velocity) == pytest.approx(2.0, rel=1e-12)
    # 4.267 with the velocities at t and t - dt is minus the acceleration: relative error 2
    velocity1 = (x1 - x2) / dt
    gamma = (velocity - velocity1) / dt
    assert relative_difference(book_4_267(velocity1, velocity, dt), gamma) == pytest.approx(2.0, rel=1e-12)
    # the two signs cancel: 4.267 of the printed 4.266 velocities is 4.268, which is right
    printed = book_4_267(book_4_266(x1, x2, dt), book_4_266(x, x1, dt), dt)
    assert relative_difference(printed, book_4_268(x, x1, x2, dt)) < 1e-12
    # 4.268: the second backward difference, γ = x'' - dt x''' exactly on a cubic (first order)
    np.testing.assert_allclose(book_4_268(x, x1, x2, dt), g + j * t - dt * j, rtol=1e-9)
    np.testing.assert_allclose(inertia.vertex_acceleration(x, x1, x2, dt), book_4_268(x, x1, x2, dt), rtol=1e-14)


def test_book_4269_to_4271_are_the_inertia_stiffness():
    rng = np.random.default_rng(41)
    x, x1, x2, gh = (rng.normal(size=3) for _ in range(4))
    dt, M, Ma, V, rho = 0.07, 0.7, 0.4, 3e-4, 1025.0
    minus_f_prime = -np.asarray(jax.jacfwd(inertia.inertia_force)(x, x1, x2, dt, M, Ma, V, rho, gh))  # 4.269
    dgamma = np.asarray(jax.jacfwd(inertia.vertex_acceleration)(x, x1, x2, dt))
    assert relative_difference((M + Ma) * dgamma, minus_f_prime) < 1e-14  # 4.270
    assert relative_difference(book_4_271(M, Ma, dt) * np.eye(3), minus_f_prime) < 1e-14  # 4.271 (times I)
    assert relative_difference(cf_inertia.inertia_stiffness(x, x1, x2, dt, M, Ma, V, rho, gh), minus_f_prime) < 1e-14


def test_book_4277_needs_the_absolute_value_of_d():
    _, uv, _, _ = one_element()
    l0, D, rho_n, rho, g, up = 0.05, 2e-3, 1140.0, 1025.0, 9.81, np.array([0.0, 0.0, 1.0])
    for order in ([0, 1, 2], [0, 2, 1]):
        d = float(geometry.twine_determinant(uv[order]))
        weight = np.asarray(gravity.netting_weight(uv[order], l0, D, rho_n, rho, g, up)).sum(axis=0)
        printed = book_4_277(d, D, l0, rho_n, rho, g)
        # F_z is the magnitude of the (downward) weight: the z component is -|F_z|
        if d > 0:
            assert relative_difference(-printed, weight[2]) < 1e-14
        else:  # a clockwise element: the printed weight is negative, the element would float
            assert relative_difference(-printed, weight[2]) == pytest.approx(2.0, rel=1e-14)
