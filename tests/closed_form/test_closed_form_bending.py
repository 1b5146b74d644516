"""Closed-form bending stiffness (jaxnet.closed_form.bending) against autodiff, and the errata of 4.220-4.245.

The reference is ``jax.jacfwd(jax.grad(bending.hinge_energy))``, what the assembly takes (itself the terms
module's own closed form, attached by custom JVPs), and finite differences of the energy (independent of
both). The book's printed equations are
transcribed as ``book_4_2xx`` and evaluated on random well-conditioned hinges; results in
/work/exp5/errata_bending.md.

Book vertices 1, 2, 3, 4 are the hinge nodes p, q, a, b (x[2], x[3], x[0], x[1]): book triangles 134 and
243 are jaxnet's (a, b, p) and (b, a, q) up to a cyclic shift.
"""

import ast
import inspect

import jax
import jax.numpy as jnp
import numpy as np

import jaxnet  # noqa: F401  (float64)
from elements import L0, positions, random_twine_pair, relative_difference
from jaxnet import geometry
from jaxnet.closed_form import bending as closed
from jaxnet.terms import bending

EI = 2e-4  # N m²


# ---------------------------------------------------------------- random hinges


def rotation(axis, angle):
    """Rodrigues rotation matrix about ``axis`` by ``angle`` (rad)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def fold(x, angle):
    """Rotate node q about the side a -> b by ``angle`` (rad, right hand): the fold angle grows by it."""
    x = np.array(x, float)
    x[3] = x[0] + rotation(x[1] - x[0], angle) @ (x[3] - x[0])
    return x


def det(uv):
    """d (4.7) of a triangle's (3, 2) twine coordinates, in numpy (the generator calls it often)."""
    (u1, v1), (u2, v2), (u3, v3) = np.asarray(uv, float)
    return (u2 - u1) * (v3 - v1) - (u3 - u1) * (v2 - v1)


def random_hinge_coordinates(rng, clockwise, same_side=False):
    """(4, 2) twine coordinates of [a, b, p, q]: triangles (a, b, p) and (b, a, q) of 2 < |d| < 30 twines²,
    sides no shorter than a third of the longest, both families crossing a-b (|du|, |dv| > 0.5); p and q on
    opposite sides of a-b (d_a d_b > 0; ``same_side``: on the same side, d_a d_b < 0); d_a < 0 if clockwise."""
    while True:
        uv = rng.uniform(-4.0, 4.0, size=(4, 2))
        d1, d2 = det(uv[[0, 1, 2]]), det(uv[[1, 0, 3]])
        shapes = [np.linalg.norm(t - t[[1, 2, 0]], axis=1) for t in (uv[[0, 1, 2]], uv[[1, 0, 3]])]
        if (min(abs(d1), abs(d2)) > 2.0 and max(abs(d1), abs(d2)) < 30.0 and (d1 * d2 < 0) == same_side
                and all(s.min() > s.max() / 3.0 for s in shapes) and np.abs(uv[1] - uv[0]).min() > 0.5):
            break
    # swapping U and V mirrors the twine plane: d changes sign
    return uv[:, ::-1].copy() if (d1 < 0) != clockwise else uv


def random_hinges(n, seed, fold_deg=(5.0, 120.0)):
    """n well-conditioned hinges: x (n, 4, 3) m, uv (n, 4, 2), fold angles (n,) rad; half clockwise.

    A flat net of twine vectors stretched 0-5 % at a half opening angle of 15-75° (tests/elements.py),
    every node moved by 1 % of l0 (so that Ua != Ub: a generic hinge), q folded about a-b by a random
    angle of +-fold_deg, the whole turned and moved at random.
    """
    rng = np.random.default_rng(seed)
    xs, uvs, folds = [], [], []
    for k in range(n):
        uv = random_hinge_coordinates(rng, clockwise=bool(k % 2))
        U, V = random_twine_pair(rng, stretch=(0.0, 0.05))
        x = positions(uv, U, V, np.zeros(3)) + 0.01 * L0 * rng.normal(size=(4, 3))
        angle = rng.choice([-1.0, 1.0]) * np.radians(rng.uniform(*fold_deg))
        x = fold(x, angle) @ rotation(rng.normal(size=3), rng.uniform(0, np.pi)).T + rng.normal(size=3)
        xs.append(x), uvs.append(uv), folds.append(angle)
    return np.array(xs), np.array(uvs), np.array(folds)


def undistorted_hinge(uv, angle, half_angle=np.radians(35.0), l0=L0):
    """An unstretched rhombic net in the plane z = 0 (|U| = |V| = l0), q folded by ``angle``: Ua = Ub before
    the fold, so the book's alpha has no in-plane kink."""
    U = l0 * np.array([np.cos(half_angle), np.sin(half_angle), 0.0])
    V = l0 * np.array([np.cos(half_angle), -np.sin(half_angle), 0.0])
    return fold(positions(np.asarray(uv), U, V, np.zeros(3)), angle)


# ---------------------------------------------------------------- the two paths


def _reference(x, uv):
    e = lambda y: bending.hinge_energy(y, uv, L0, EI)
    return jax.grad(e)(x).reshape(12), jax.jacfwd(jax.grad(e))(x).reshape(12, 12)


def _closed(x, uv):
    return closed.hinge_gradient(x, uv, L0, EI), closed.hinge_stiffness(x, uv, L0, EI)


CHUNK = 8  # hinges per call: every batch is cut and padded to this size, so that each path compiles once
_reference_chunk = jax.jit(jax.vmap(_reference))
_closed_chunk = jax.jit(jax.vmap(_closed))


def _evaluate(chunk_fn, x, uv):
    x, uv = np.asarray(x, float), np.asarray(uv, float)
    n = len(x)
    pad = -n % CHUNK
    x, uv = np.concatenate([x, np.repeat(x[:1], pad, 0)]), np.concatenate([uv, np.repeat(uv[:1], pad, 0)])
    outs = [chunk_fn(x[i:i + CHUNK], uv[i:i + CHUNK]) for i in range(0, len(x), CHUNK)]
    return tuple(np.concatenate([o[k] for o in outs])[:n] for k in range(2))


def reference(x, uv):
    """(gradient (n, 12), stiffness (n, 12, 12)) of jax.grad / jax.jacfwd(jax.grad(hinge_energy))."""
    return _evaluate(_reference_chunk, x, uv)


def closed_form(x, uv):
    """(hinge_gradient (n, 12), hinge_stiffness (n, 12, 12))."""
    return _evaluate(_closed_chunk, x, uv)


_energy = jax.jit(lambda x, uv: bending.hinge_energy(x, uv, L0, EI))


def per_hinge(a, b):
    return np.array([relative_difference(a[i], b[i]) for i in range(len(a))])


def fd_gradient(x, uv, h=1e-7):
    """Central differences of the energy (J/m), (12,)."""
    x = np.asarray(x, float)
    steps = h * np.eye(12).reshape(12, 4, 3)
    return np.array([(_energy(x + d, uv) - _energy(x - d, uv)) / (2 * h) for d in steps])


def fd_stiffness(x, uv, h=1e-7):
    """Central differences of the closed-form gradient (N/m), (12, 12)."""
    x = np.asarray(x, float)
    steps = h * np.eye(12).reshape(12, 4, 3)
    g = closed_form(np.concatenate([x + steps, x - steps]), np.tile(uv, (24, 1, 1)))[0]
    return ((g[:12] - g[12:]) / (2 * h)).T


# ---------------------------------------------------------------- closed form vs autodiff


def test_closed_form_uses_no_automatic_differentiation():
    tree = ast.parse(inspect.getsource(closed))
    names = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}  # jax.grad, jnp.x, ...
    forbidden = {"grad", "jacfwd", "jacrev", "hessian", "jvp", "vjp", "linearize", "custom_jvp", "value_and_grad"}
    assert not names & forbidden
    modules = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
    modules |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
    assert modules == {"__future__", "jax.numpy", "numpy", "jaxnet"}  # nothing from jaxnet.terms


def test_stiffness_and_gradient_equal_autodiff_on_random_hinges():
    x, uv, folds = random_hinges(120, seed=1)
    # the generator makes what it says: folds of 5-120° (theta moved a little by the 1 % distortion), both
    # orientations
    theta = np.asarray(jax.vmap(bending.fold_angle)(jnp.asarray(x)))
    np.testing.assert_allclose(theta, folds, atol=0.1)
    d = np.array([det(u[:3]) for u in uv])
    assert np.sum(d < 0) == 60
    g_ref, k_ref = reference(x, uv)
    g, k = closed_form(x, uv)
    assert per_hinge(g, g_ref).max() < 1e-10
    assert per_hinge(k, k_ref).max() < 1e-10
    # and, independently of the module's own closed-form derivatives (custom JVPs), finite differences of
    # the energy and of the gradient on a few
    for i in range(0, 120, 30):
        assert relative_difference(g[i], fd_gradient(x[i], uv[i])) < 1e-6
        assert relative_difference(k[i], fd_stiffness(x[i], uv[i])) < 1e-6


def test_stiffness_is_symmetric_and_knows_rigid_motions():
    # E is invariant under rigid motions: K annihilates translations, and an infinitesimal rotation w ^ x
    # gives K (w ^ x) = w ^ g node by node (differentiate g(x) . (w ^ x) = 0), g the gradient
    x, uv, _ = random_hinges(6, seed=2)
    g, k = closed_form(x, uv)
    rng = np.random.default_rng(3)
    for i in range(len(x)):
        scale = np.abs(k[i]).max()
        np.testing.assert_allclose(k[i], k[i].T, rtol=0, atol=1e-13 * scale)
        t = rng.normal(size=3)
        np.testing.assert_allclose(k[i] @ np.tile(t, 4), 0.0, atol=1e-13 * scale * L0)
        w = rng.normal(size=3)
        lhs = k[i] @ np.cross(w, x[i]).ravel()
        np.testing.assert_allclose(lhs, np.cross(w, np.asarray(g[i]).reshape(4, 3)).ravel(),
                                   rtol=0, atol=1e-11 * np.abs(lhs).max())
        assert np.abs(lhs).max() > 1e-3 * scale * L0  # the hinge is loaded: a real check


# ---------------------------------------------------------------- hard cases


def test_nearly_flat_and_flat_hinges():
    # theta = 1e-4 and exactly 0: regular (theta² is smooth there); E = F = 0 when flat and
    # K = 2 sum_f w_f sigma_f dtheta dtheta^T. Lifting q by t along the plane's normal turns the fold by
    # t / h_q (h_q: distance of q from the line a-b): K_qq along the normal is 2 sum_f w_f sigma_f / h_q².
    x, uv, _ = random_hinges(4, seed=4)
    rng = np.random.default_rng(5)
    for i in range(4):
        flat = undistorted_hinge(uv[i], 0.0) + 0.01 * L0 * rng.normal(size=(4, 3)) * [1, 1, 0]  # z = 0
        for angle in (1e-4, 0.0):
            y = fold(flat, angle)
            g_ref, k_ref = reference(y[None], uv[i][None])
            g, k = closed_form(y[None], uv[i][None])
            assert relative_difference(k, k_ref) < 1e-10
            assert relative_difference(k[0], fd_stiffness(y, uv[i])) < 1e-6
            if angle:
                assert relative_difference(g, g_ref) < 1e-10
        assert np.abs(g).max() == 0.0
        e = flat[1] - flat[0]
        h_q = np.linalg.norm(np.cross(e, flat[3] - flat[0])) / np.linalg.norm(e)
        tri1, tri2 = flat[[0, 1, 2]], flat[[1, 0, 3]]
        Ua, Va, da = (np.asarray(t) for t in geometry.twine_vectors(tri1, uv[i][[0, 1, 2]]))
        Ub, Vb, db = (np.asarray(t) for t in geometry.twine_vectors(tri2, uv[i][[1, 0, 3]]))
        sin_phi = lambda f: np.linalg.norm(np.cross(f, e)) / (np.linalg.norm(f) * np.linalg.norm(e))
        n_u, n_v = abs(uv[i][1, 1] - uv[i][0, 1]), abs(uv[i][1, 0] - uv[i][0, 0])
        w = 2 * EI / (L0 * (abs(da) + abs(db)))
        total = w * (n_u**2 * sin_phi(Ua) * sin_phi(Ub) + n_v**2 * sin_phi(Va) * sin_phi(Vb))
        np.testing.assert_allclose(k[0][11, 11], 2 * total / h_q**2, rtol=1e-12)
        eig = np.linalg.eigvalsh(np.asarray(k[0]))
        assert np.sum(np.abs(eig) > 1e-10 * eig.max()) == 1  # rank one


def test_fold_close_to_half_a_turn():
    # theta = +-(pi - 1e-3), pi - 1e-6: regular (atan2 is smooth up to its cut at pi, where theta² jumps);
    # finite differences of the gradient agree where their steps (1e-7 m) do not reach the cut
    _, uv, _ = random_hinges(3, seed=6)
    for i, angle in enumerate((np.pi - 1e-3, -(np.pi - 1e-3), np.pi - 1e-6)):
        y = undistorted_hinge(uv[i], angle)
        np.testing.assert_allclose(float(bending.fold_angle(jnp.asarray(y))), angle, rtol=1e-12)
        g_ref, k_ref = reference(y[None], uv[i][None])
        g, k = closed_form(y[None], uv[i][None])
        assert relative_difference(g, g_ref) < 1e-10 and relative_difference(k, k_ref) < 1e-10
        if abs(angle) < np.pi - 1e-4:
            assert relative_difference(k[0], fd_stiffness(y, uv[i])) < 1e-6


def test_nearly_collapsed_side_and_triangle():
    # a-b shrunk to 1e-6 of its length, p 1e-6 of its distance from the side: regular but stiff; the two
    # paths agree, and K grows as 1/|e|² (theta turns by O(1) for displacements of O(|e|)) and 1/h_p
    uv = np.array([[0.0, 0.0], [1.4, 2.0], [-1.5, 1.2], [2.2, 0.5]])
    x = undistorted_hinge(uv, 0.5)
    cases = []
    for eps in (1e-3, 1e-6):
        side, tri = x.copy(), x.copy()
        side[1] = x[0] + eps * (x[1] - x[0])
        tri[2] = x[0] + 0.5 * (x[1] - x[0]) + eps * (x[2] - x[0])
        cases += [side, tri]
    g_ref, k_ref = reference(np.array(cases), np.tile(uv, (4, 1, 1)))
    g, k = closed_form(np.array(cases), np.tile(uv, (4, 1, 1)))
    assert per_hinge(k, k_ref).max() < 1e-10 and per_hinge(g, g_ref).max() < 1e-10
    size = np.abs(k).max(axis=(1, 2))
    np.testing.assert_allclose(size[2] / size[0], 1e6, rtol=1e-2)  # side: 1/eps²
    np.testing.assert_allclose(size[3] / size[1], 1e3, rtol=1e-2)  # triangle: 1/eps


def test_side_crossed_by_one_family_and_triangles_of_opposite_orientation():
    # a-b along a V twine (du = 0): no V twine crosses it, N_V = 0 (the book's 4.229-4.230 would divide by
    # it for that family); sigma_V and its derivatives are then exactly 0
    one_family = np.array([[0.0, 0.0], [0.0, 2.0], [-2.0, 1.3], [1.7, 0.4]])
    # p and q on the same side of a-b in twine coordinates: d_a d_b < 0
    opposite = random_hinge_coordinates(np.random.default_rng(7), clockwise=False, same_side=True)
    assert det(one_family[[0, 1, 2]]) * det(one_family[[1, 0, 3]]) > 0
    assert det(opposite[[0, 1, 2]]) * det(opposite[[1, 0, 3]]) < 0
    rng = np.random.default_rng(8)
    for uv in (one_family, opposite):
        y = undistorted_hinge(uv, 0.7) + 0.01 * L0 * rng.normal(size=(4, 3))
        g_ref, k_ref = reference(y[None], uv[None])
        g, k = closed_form(y[None], uv[None])
        assert relative_difference(g, g_ref) < 1e-10 and relative_difference(k, k_ref) < 1e-10
        assert relative_difference(k[0], fd_stiffness(y, uv)) < 1e-6 and np.abs(k).max() > 0
    @jax.jit
    def sines(x, uv):
        rows, d_a, d_b, n_u, n_v = closed._twine_rows(uv)
        z = closed._invariant_derivatives(x, rows)[0]
        return n_v, closed._sines_of_invariants(z, d_a, d_b, n_u, n_v)

    n_v, (sigma, d_sigma, h_sigma) = sines(undistorted_hinge(one_family, 0.7), one_family)
    assert float(n_v) == 0.0 and float(sigma[0]) > 0.1
    assert float(jnp.abs(sigma[1])) + float(jnp.abs(d_sigma[1]).max()) + float(jnp.abs(h_sigma[1]).max()) == 0.0


def test_collapsed_side_and_triangles_give_zero_like_the_energy():
    # a = b: theta has no limit (E is discontinuous there); p on a, or on the line a-b: n1 = 0, theta
    # undefined. The energy's guards hold everything at 0; so does the closed form (finite, not a limit).
    uv = np.array([[0.0, 0.0], [1.4, 2.0], [-1.5, 1.2], [2.2, 0.5]])
    x = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.03, 0.05, 0.0], [0.06, -0.04, 0.02]])
    cases = [x.copy() for _ in range(4)]
    cases[0][1] = cases[0][0]  # collapsed side
    cases[1][2] = cases[1][0]  # p on a
    cases[2][2] = [0.05, 0.0, 0.0]  # p on the side a-b
    cases[3][:] = 0.0  # the whole hinge at one point
    xs, uvs = np.array(cases), np.tile(uv, (4, 1, 1))
    g_ref, k_ref = reference(xs, uvs)
    g, k = closed_form(xs, uvs)
    assert np.all(np.isfinite(g)) and np.all(np.isfinite(k))
    assert np.abs(g).max() == 0.0 and np.abs(k).max() == 0.0
    assert np.abs(g_ref).max() == 0.0 and np.abs(k_ref).max() == 0.0


# ---------------------------------------------------------------- the book's equations 4.220-4.245


def book_positions(x):
    """Book vertices 1, 2, 3, 4 = p, q, a, b: their positions."""
    return x[2], x[3], x[0], x[1]


def book_coordinates(uv):
    """(U1, U2, U3, U4), (V1, V2, V3, V4): twine coordinates of book vertices 1-4 = p, q, a, b."""
    return (uv[2, 0], uv[3, 0], uv[0, 0], uv[1, 0]), (uv[2, 1], uv[3, 1], uv[0, 1], uv[1, 1])


def book_4_227(uv):
    (u1, u2, u3, u4), (v1, v2, v3, v4) = book_coordinates(uv)
    return (u3 - u1) * (v4 - v1) - (u4 - u1) * (v3 - v1)


def book_4_228(uv):
    (u1, u2, u3, u4), (v1, v2, v3, v4) = book_coordinates(uv)
    return (u4 - u2) * (v3 - v2) - (u3 - u2) * (v4 - v2)


def book_4_221(x, uv):
    (x1, x2, x3, x4), (_, (v1, v2, v3, v4)) = book_positions(x), book_coordinates(uv)
    da = book_4_227(uv)
    return (v4 - v1) / da * (x3 - x1) - (v3 - v1) / da * (x4 - x1)  # 13 = x3 - x1 (4.225)


def book_4_222(x, uv):
    (x1, x2, x3, x4), ((u1, u2, u3, u4), _) = book_positions(x), book_coordinates(uv)
    da = book_4_227(uv)
    return (u4 - u1) / da * (x3 - x1) - (u3 - u1) / da * (x4 - x1)


def book_4_223(x, uv):
    (x1, x2, x3, x4), (_, (v1, v2, v3, v4)) = book_positions(x), book_coordinates(uv)
    db = book_4_228(uv)
    return (v3 - v2) / db * (x4 - x2) - (v4 - v2) / db * (x3 - x2)  # 24 = x4 - x2 (4.226)


def book_4_224(x, uv):
    (x1, x2, x3, x4), ((u1, u2, u3, u4), _) = book_positions(x), book_coordinates(uv)
    db = book_4_228(uv)
    return (u3 - u2) / db * (x4 - x2) - (u4 - u2) / db * (x3 - x2)


def book_4_229_4_230(uv):
    """(n_a, n_b) as printed: d / (2 |V3 - V4|) (signed d)."""
    _, (v1, v2, v3, v4) = book_coordinates(uv)
    return book_4_227(uv) / (2 * abs(v3 - v4)), book_4_228(uv) / (2 * abs(v3 - v4))


def book_4_231_to_4_236(x, uv, counts=None):
    """rho (m) of the U twine: circumradius of the chords n_a Ua, n_b Ub by Heron (4.231-4.236); Ua, Ub by
    the right 4.221, 4.223; ``counts`` (n_a, n_b), default the printed 4.229-4.230."""
    n_a, n_b = book_4_229_4_230(uv) if counts is None else counts
    Ua, Ub = book_4_221(x, uv), book_4_223(x, uv)
    A, B, C = jnp.linalg.norm(n_a * Ua), jnp.linalg.norm(n_b * Ub), jnp.linalg.norm(n_a * Ua + n_b * Ub)
    p = (A + B + C) / 2
    S = jnp.sqrt(p * (p - A) * (p - B) * (p - C))
    return A * B * C / (4 * S)


def book_4_240(x, uv):
    """alpha (rad): the angle between Ua and Ub, cos(alpha) = Ua . Ub / (|Ua| |Ub|)."""
    Ua, Ub = book_4_221(x, uv), book_4_223(x, uv)
    return jnp.arccos(Ua @ Ub / (jnp.linalg.norm(Ua) * jnp.linalg.norm(Ub)))


def _book_fractions(x, uv):
    Ua, Ub = book_4_221(x, uv), book_4_223(x, uv)
    dot, la, lb, s = Ua @ Ub, jnp.linalg.norm(Ua), jnp.linalg.norm(Ub), jnp.sin(book_4_240(x, uv))
    ga = (dot * Ua - Ub * la**2) / (la**3 * lb * s)  # the first fraction of 4.241 (over d_a)
    gb = (dot * Ub - Ua * lb**2) / (lb**3 * la * s)  # that of 4.242 (over d_b)
    return ga, gb


def book_4_241(x, uv):
    _, (v1, v2, v3, v4) = book_coordinates(uv)
    return (v3 - v4) * _book_fractions(x, uv)[0] / book_4_227(uv)


def book_4_242(x, uv):
    _, (v1, v2, v3, v4) = book_coordinates(uv)
    return (v4 - v3) * _book_fractions(x, uv)[1] / book_4_228(uv)


def book_4_243_first_line(x, uv):
    """4.243 up to where the print becomes garbled (its first two terms)."""
    _, (v1, v2, v3, v4) = book_coordinates(uv)
    ga, gb = _book_fractions(x, uv)
    return (v4 - v1) * ga / book_4_227(uv) + (v2 - v4) * gb / book_4_228(uv)


def corrected_4_244(x, uv):
    """d(alpha)/dx4, missing from the print: the chain rule through Ua (dUa/dx4 = (V1 - V3)/d_a) and Ub
    (dUb/dx4 = (V3 - V2)/d_b)."""
    _, (v1, v2, v3, v4) = book_coordinates(uv)
    ga, gb = _book_fractions(x, uv)
    return (v1 - v3) * ga / book_4_227(uv) + (v3 - v2) * gb / book_4_228(uv)


def book_alpha_gradient(x, uv):
    """(4, 3) d(alpha)/dx on our nodes [a, b, p, q] = book [3, 4, 1, 2], from 4.241-4.243 and 4.244."""
    return jnp.stack([book_4_243_first_line(x, uv), corrected_4_244(x, uv), book_4_241(x, uv), book_4_242(x, uv)])


def book_4_239(x, uv):
    """(4, 3) U-twine bending forces as printed: F = EI/rho d(alpha)/dx (V3 - V4)."""
    _, (v1, v2, v3, v4) = book_coordinates(uv)
    return EI / book_4_231_to_4_236(x, uv) * book_alpha_gradient(x, uv) * (v3 - v4)


def corrected_4_239(x, uv):
    """The restoring force with the count |V3 - V4|: F = -|V3 - V4| EI/rho d(alpha)/dx."""
    _, (v1, v2, v3, v4) = book_coordinates(uv)
    return -abs(v3 - v4) * EI / book_4_231_to_4_236(x, uv) * book_alpha_gradient(x, uv)


def true_twine_vectors(x, uv):
    """(Ua, Va, d_a), (Ub, Vb, d_b) of jaxnet's triangles (a, b, p), (b, a, q) (geometry, 4.3-4.7)."""
    return (geometry.twine_vectors(x[jnp.array([0, 1, 2])], uv[jnp.array([0, 1, 2])]),
            geometry.twine_vectors(x[jnp.array([1, 0, 3])], uv[jnp.array([1, 0, 3])]))


def test_book_4221_to_4228_twine_vectors_and_determinants():
    x, uv, _ = random_hinges(2, seed=10)  # one counter-clockwise, one clockwise
    for xi, uvi in zip(jnp.asarray(x), jnp.asarray(uv)):
        (Ua, Va, da), (Ub, Vb, db) = true_twine_vectors(xi, uvi)
        np.testing.assert_allclose(book_4_227(uvi), da, rtol=1e-14)  # d of 134 = d of (a, b, p)
        np.testing.assert_allclose(book_4_228(uvi), db, rtol=1e-14)
        assert relative_difference(book_4_221(xi, uvi), Ua) < 1e-12
        assert relative_difference(book_4_223(xi, uvi), Ub) < 1e-12
        # 4.222 and 4.224 print -Va and -Vb: relative error 2
        np.testing.assert_allclose(relative_difference(book_4_222(xi, uvi), Va), 2.0, rtol=1e-12)
        np.testing.assert_allclose(relative_difference(book_4_224(xi, uvi), Vb), 2.0, rtol=1e-12)
        assert relative_difference(book_4_222(xi, uvi), -Va) < 1e-12
        assert relative_difference(book_4_224(xi, uvi), -Vb) < 1e-12


def test_book_4229_to_4236_counts_and_radius():
    x, uv, _ = random_hinges(2, seed=11)
    for k, (xi, uvi) in enumerate(zip(jnp.asarray(x), jnp.asarray(uv))):
        (Ua, _, da), (Ub, _, db) = true_twine_vectors(xi, uvi)
        n_u = abs(float(uvi[1, 1] - uvi[0, 1]))
        counts = abs(da) / (2 * n_u), abs(db) / (2 * n_u)  # |d|/2 U twine vectors over N_U twines (4.25)
        printed = book_4_229_4_230(uvi)
        # 4.229-4.230 use the signed d: negative counts on clockwise triangles (k = 1) ...
        np.testing.assert_allclose(printed, np.sign(da) * np.array(counts), rtol=1e-14)
        assert (printed[0] < 0) == bool(k % 2)
        # ... immaterial for rho as both triangles have the sign of d (n_a Ua + n_b Ub changes sign only)
        rho = book_4_231_to_4_236(xi, uvi, counts)
        np.testing.assert_allclose(book_4_231_to_4_236(xi, uvi), rho, rtol=1e-12)
        # 4.234-4.236 (Heron) is the circumradius: rho = C / (2 sin(angle opposite C)) = C / (2 sin(alpha))
        alpha = book_4_240(xi, uvi)
        chord = np.linalg.norm(counts[0] * Ua + counts[1] * Ub)
        np.testing.assert_allclose(rho, chord / (2 * np.sin(alpha)), rtol=1e-10)


def test_book_radius_is_the_small_turn_radius_to_second_order():
    # jaxnet's couple is EI/rho with rho = (A + B) / (2 alpha_out), A + B on unstretched chords: on a pure
    # fold of an unstretched undistorted net, the book's Heron rho agrees to O(theta²)
    uv = jnp.array([[0.0, 0.0], [1.4, 2.0], [-1.5, 1.2], [2.2, 0.5]])
    errors = []
    for angle in (0.02, 0.01):
        x = jnp.asarray(undistorted_hinge(uv, angle))
        cu, _ = bending.hinge_couples(x, uv, L0, EI)
        errors.append(abs(float(EI / book_4_231_to_4_236(x, uv) / cu) - 1.0))
    assert errors[0] < 1e-4
    np.testing.assert_allclose(errors[0] / errors[1], 4.0, rtol=0.01)


def test_book_4240_angle_is_the_in_plane_kink_plus_the_fold():
    # 4 sin²(alpha/2) = 4 sin²((phi_a - phi_b)/2) + sin(phi_a) sin(phi_b) 4 sin²(theta/2) (to roundoff); on a
    # random hinge the book's alpha and jaxnet's alpha_out = |theta| sqrt(sin phi_a sin phi_b) differ by the kink
    x, uv, _ = random_hinges(4, seed=12)
    differences = []
    for xi, uvi in zip(jnp.asarray(x), jnp.asarray(uv)):
        e = xi[1] - xi[0]
        angle = lambda a, b: np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b))
        (Ua, _, _), (Ub, _, _) = true_twine_vectors(xi, uvi)
        alpha, pa, pb = float(book_4_240(xi, uvi)), angle(Ua, e), angle(Ub, e)
        theta = float(bending.fold_angle(xi))
        lhs = 4 * np.sin(alpha / 2) ** 2
        rhs = 4 * np.sin((pa - pb) / 2) ** 2 + np.sin(pa) * np.sin(pb) * 4 * np.sin(theta / 2) ** 2
        np.testing.assert_allclose(lhs, rhs, rtol=1e-10)
        alpha_out = abs(theta) * np.sqrt(np.sin(pa) * np.sin(pb))
        differences.append(abs(alpha - alpha_out) / alpha)
    assert min(differences) > 5e-4  # 0.1 % to 8 % on these four


def test_book_4241_to_4244_angle_derivatives():
    # 4.241, 4.242 and the first line of 4.243 as printed, 4.244 as the chain rule gives it, against
    # autodiff of 4.240; they sum to 0 (a translation does not turn the twine)
    x, uv, _ = random_hinges(2, seed=13)
    for xi, uvi in zip(jnp.asarray(x), jnp.asarray(uv)):
        exact = jax.jit(jax.grad(book_4_240))(xi, uvi)
        book = jax.jit(book_alpha_gradient)(xi, uvi)
        assert relative_difference(book, exact) < 1e-10
        np.testing.assert_allclose(book.sum(axis=0), 0.0, atol=1e-12 * np.abs(book).max())


def test_book_4239_sign_depends_on_the_labelling():
    # The printed force (EI/rho) d(alpha)/dx (V3 - V4) does positive work on alpha (it bends the twine
    # further) when V3 > V4; relabelling the same hinge (a <-> b, p <-> q: V3 <-> V4) flips it. The
    # restoring force is -|V3 - V4| (EI/rho) d(alpha)/dx: the printed one is off by a relative 2 or 0.
    x, uv, _ = random_hinges(1, seed=14)
    x, uv = jnp.asarray(x[0]), jnp.asarray(uv[0])
    swap = jnp.array([1, 0, 3, 2])
    for xi, uvi in ((x, uv), (x[swap], uv[swap])):
        printed, right = book_4_239(xi, uvi), corrected_4_239(xi, uvi)
        work = float(jnp.sum(printed * book_alpha_gradient(xi, uvi)))
        v3_minus_v4 = float(uvi[0, 1] - uvi[1, 1])
        if v3_minus_v4 > 0:
            assert work > 0
            np.testing.assert_allclose(relative_difference(printed, right), 2.0, rtol=1e-12)
        else:
            assert work < 0
            assert relative_difference(printed, right) < 1e-14
    np.testing.assert_allclose(book_4_239(x[swap], uv[swap]), -book_4_239(x, uv)[swap], rtol=1e-10)


def _fd_jacobian(f, x, h=1e-8):
    """(12, 12) central differences of f: (4, 3) -> (4, 3)."""
    steps = h * np.eye(12).reshape(12, 4, 3)
    return np.stack([(np.asarray(f(x + d)) - np.asarray(f(x - d))).ravel() / (2 * h) for d in steps], axis=1)


@jax.jit
def book_forces(x, uv):
    """Both families' corrected book forces (4, 3) N: the V family is the U family of the mirrored
    coordinates (U <-> V)."""
    return corrected_4_239(x, uv) + corrected_4_239(x, uv[:, ::-1])


@jax.jit
def kink_gradients(x, uv):
    """(2, 4, 3) d(kappa_f)/dx, kappa_f = phi_af - phi_bf the in-plane kink of family f (U, V)."""
    def kink(y, coordinates):
        (Ua, _, _), (Ub, _, _) = true_twine_vectors(y, coordinates)
        e = y[1] - y[0]
        angle = lambda a, b: jnp.arctan2(jnp.linalg.norm(jnp.cross(a, b)), a @ b)
        return angle(Ua, e) - angle(Ub, e)
    return jnp.stack([jax.grad(kink)(x, uv), jax.grad(kink)(x, uv[:, ::-1])])


def test_book_4239_forces_and_4245_stiffness_against_jaxnets():
    # On a pure fold (theta = 2e-3) of an unstretched undistorted net, the corrected book forces (both
    # families) equal -grad E to O(theta²); the book's stiffness K_book = -d F_book / dx (4.245) is jaxnet's
    # plus the stiffness of the in-plane kink, sum_f N_f 2 EI / (A_f + B_f) dkappa_f dkappa_f^T
    # (kappa_f = phi_af - phi_bf, 0 at a pure fold), to O(theta). Away from it K_book is not symmetric:
    # the book's forces are not conservative (1/rho depends on the chords as well as on alpha).
    uv = np.array([[0.0, 0.0], [1.4, 2.0], [-1.5, 1.2], [2.2, 0.5]])
    x = undistorted_hinge(uv, 2e-3)
    g, k = (a[0] for a in closed_form(x[None], uv[None]))
    np.testing.assert_allclose(np.asarray(book_forces(x, uv)).ravel(), -g, rtol=0, atol=1e-5 * np.abs(g).max())
    k_book = -_fd_jacobian(lambda y: book_forces(y, uv), x)
    d_a, d_b = det(uv[[0, 1, 2]]), det(uv[[1, 0, 3]])
    k_kink = np.zeros((12, 12))
    for n, dk in zip(np.abs(uv[1] - uv[0])[::-1], np.asarray(kink_gradients(x, uv))):  # N_U = |dv|, N_V = |du|
        k_kink += n * 2 * EI / ((abs(d_a) + abs(d_b)) * L0 / (2 * n)) * np.outer(dk.ravel(), dk.ravel())
    assert relative_difference(k_book, k) > 0.1  # the kink's stiffness is not small
    assert relative_difference(k_book, k + k_kink) < 1e-3  # 3e-4: the O(theta) rest is K_book's asymmetry
    # a random (stretched, sheared, folded) hinge: the book's tangent is not symmetric
    y, uv_r, _ = random_hinges(1, seed=15)
    k_r = -_fd_jacobian(lambda z: book_forces(z, uv_r[0]), y[0])
    assert relative_difference(k_r, k_r.T) > 1e-3
