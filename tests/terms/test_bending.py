"""Twine bending across hinges (book eqs 4.220-4.245) and the hinges of a mesh."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.mesh.hinges import find_hinges
from jaxnet.terms import bending

L0, EI = 0.02, 2e-4  # m, N m²



@jax.jit
def _energy_force_stiffness(x, uv):
    """One compiled program for the three (compiling the hinge Hessian takes seconds): x (12,) m."""
    e = lambda y: bending.hinge_energy(y.reshape(4, 3), uv, L0, EI)
    f = lambda y: -jax.grad(e)(y)
    return e(x), f(x), -jax.jacfwd(f)(x)  # K = -dF/dx (4.245)


def energy(x, uv):
    return _energy_force_stiffness(x, uv)[0]


def force(x, uv):
    return _energy_force_stiffness(x, uv)[1]


def stiffness(x, uv):
    return _energy_force_stiffness(x, uv)[2]


fold_angle = jax.jit(bending.fold_angle)
couples = jax.jit(lambda x, uv: bending.hinge_couples(x, uv, L0, EI))


def rotation(axis, angle):
    """Rodrigues rotation matrix about ``axis`` by ``angle`` (rad)."""
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def net_plane(uv, half_angle=np.radians(35.0), l0=L0):
    """Positions of nodes of an unstretched flat net in the plane z = 0: x = u U + v V, |U| = |V| = l0."""
    U = l0 * np.array([np.cos(half_angle), np.sin(half_angle), 0.0])
    V = l0 * np.array([np.cos(half_angle), -np.sin(half_angle), 0.0])
    return uv[:, :1] * U + uv[:, 1:] * V


def fold(x, theta):
    """Rotate node q (index 3) about the shared side a->b by theta: a pure fold of the hinge."""
    x = np.array(x, float)
    x[3] = x[0] + rotation(x[1] - x[0], theta) @ (x[3] - x[0])
    return x


def random_hinge(rng, clockwise=False):
    """Random hinge: p and q on either side of a-b in twine coordinates, positions a distorted folded net."""
    while True:
        uv = rng.uniform(-4, 4, size=(4, 2))
        d1 = geometry.twine_determinant(uv[[0, 1, 2]])
        d2 = geometry.twine_determinant(uv[[1, 0, 3]])
        if min(abs(d1), abs(d2)) > 2.0 and d1 * d2 > 0 and abs(uv[1] - uv[0]).min() > 0.5:
            break
    if (d1 < 0) != clockwise:
        uv = uv[:, ::-1].copy()  # swapping U and V mirrors the twine plane: d changes sign
    theta = rng.choice([-1, 1]) * rng.uniform(0.2, 1.0)
    x = fold(net_plane(uv), theta) * (1.0 + 0.1 * rng.normal(size=(4, 3)))  # folded, stretched, sheared
    return jnp.asarray(x.ravel()), jnp.asarray(uv)


def flattened_hinge(rng, clockwise=False):
    """A random hinge flattened onto z = 0: flat, distorted in its plane. Drawn again where flattening put q on p's
    side of a-b (1 draw in 130): that folds the hinge over by pi instead."""
    while True:
        x, uv = random_hinge(rng, clockwise)
        x = x.reshape(4, 3).at[:, 2].set(0.0).ravel()
        if abs(float(fold_angle(x.reshape(4, 3)))) < np.pi / 2:
            return x, uv


def fd_gradient(f, x, h):
    return np.array([(f(x.at[i].add(h)) - f(x.at[i].add(-h))) / (2 * h) for i in range(x.size)])


# ---------------------------------------------------------------- the bending term

def test_flat_panel_has_no_bending_force_and_the_finite_fold_stiffness(rng):
    # A flat hinge, however distorted in its plane (Ua != Ub: the book's alpha is not 0 there), stores no
    # energy and pulls nothing; its stiffness is finite and is 2 k grad(theta) grad(theta)^T.
    for clockwise in (False, True):
        for _ in range(4):
            x, uv = flattened_hinge(rng, clockwise)
            assert float(energy(x, uv)) == 0.0
            assert float(jnp.abs(force(x, uv)).max()) == 0.0
            K = stiffness(x, uv)
            assert np.all(np.isfinite(K))
            # only out-of-plane (z) displacements are stiff at the flat state
            z = np.arange(2, 12, 3)
            np.testing.assert_allclose(np.delete(np.delete(K, z, 0), z, 1), 0.0, atol=1e-12 * np.abs(K).max())
            assert np.linalg.eigvalsh(K).min() > -1e-9 * np.abs(K).max()  # positive semi-definite, rank one
            assert np.sum(np.linalg.eigvalsh(K) > 1e-9 * np.abs(K).max()) == 1


def test_flat_stiffness_closed_form_for_twines_crossing_at_right_angles():
    # uv: a = (0,0), b = (0,2), p = (-2,1), q = (2,1); U along x, V along y, |U| = |V| = l0. The side is a
    # V line: N_U = 2 U twines cross it at right angles, no V twine. Each chord n l0 with n = 4/(2*2) = 1,
    # so E = 2 * EI theta² / (2 l0) (4.229-4.234, small angle). Lifting p by w out of the plane folds by
    # theta = w / h, h = 2 l0 (p's distance to the side): K_zz(p) = 2 EI / (l0 h²).
    uv = jnp.array([[0.0, 0.0], [0.0, 2.0], [-2.0, 1.0], [2.0, 1.0]])
    x = jnp.asarray(np.asarray(uv) @ np.array([[L0, 0, 0], [0, L0, 0]]))
    K = stiffness(x.ravel(), uv)
    np.testing.assert_allclose(K[8, 8], 2 * EI / (L0 * (2 * L0) ** 2), rtol=1e-12)


def book_couple_perpendicular(theta):
    """EI/rho with rho from 4.231-4.236 (Heron) for the right-angle hinge above, folded by theta."""
    A = B = 1.0 * L0  # n_a |Ua|, n_b |Ub|
    C = np.linalg.norm(np.array([L0, 0, 0]) + rotation([0, 1, 0], theta) @ np.array([L0, 0, 0]))
    p = (A + B + C) / 2
    S = np.sqrt(p * (p - A) * (p - B) * (p - C))
    return EI / (A * B * C / (4 * S))


@pytest.mark.parametrize("theta", [0.05, -0.1])
def test_small_fold_gives_the_books_couple_on_each_twine(theta):
    # Right-angle hinge folded by theta (alpha = theta for twines normal to the side): the moment about the
    # side is N_U * EI/rho (4.238-4.239), so p (distance h = 2 l0 from the side) feels N_U EI / (rho h)
    # along its out-of-plane direction. The book's rho is exact at any fold: agreement to O(theta²).
    uv = jnp.array([[0.0, 0.0], [0.0, 2.0], [-2.0, 1.0], [2.0, 1.0]])
    x = fold(np.asarray(uv) @ np.array([[L0, 0, 0], [0, L0, 0]]), theta)
    f = np.asarray(force(jnp.asarray(x.ravel()), uv)).reshape(4, 3)
    moment = 2 * book_couple_perpendicular(abs(theta))
    np.testing.assert_allclose(np.linalg.norm(f[2]), moment / (2 * L0), rtol=theta**2 / 10)
    np.testing.assert_allclose(np.linalg.norm(f[3]), moment / (2 * L0), rtol=theta**2 / 10)
    # restoring: q is pushed back towards the plane z = 0 of triangle 1, and p out of it to the other side
    # (rotating triangle 1 with q would flatten the hinge too)
    assert f[3, 2] * x[3, 2] < 0 and f[2, 2] * x[3, 2] < 0
    cu, cv = couples(jnp.asarray(x), uv)
    np.testing.assert_allclose(cu, moment / 2, rtol=theta**2 / 10)
    assert float(cv) == 0.0


def book_twine_vectors(x, uv):
    """(Ua, Va, d_a), (Ub, Vb, d_b) of triangles 134 and 243 by eqs 4.221-4.228, in numpy.

    Book vertices 1, 2, 3, 4 are our p, q, a, b. 4.222 and 4.224 are printed with the wrong sign (they
    give -Va, -Vb); written here as solving 4.1-4.2 gives them.
    """
    (x3, x4, x1, x2), (u3, u4, u1, u2) = x, uv[:, 0]
    v3, v4, v1, v2 = uv[:, 1]
    da = (u3 - u1) * (v4 - v1) - (u4 - u1) * (v3 - v1)
    db = (u4 - u2) * (v3 - v2) - (u3 - u2) * (v4 - v2)
    Ua = ((v4 - v1) * (x3 - x1) - (v3 - v1) * (x4 - x1)) / da
    Va = ((u3 - u1) * (x4 - x1) - (u4 - u1) * (x3 - x1)) / da
    Ub = ((v3 - v2) * (x4 - x2) - (v4 - v2) * (x3 - x2)) / db
    Vb = ((u4 - u2) * (x3 - x2) - (u3 - u2) * (x4 - x2)) / db
    return (Ua, Va, da), (Ub, Vb, db)


def angle(a, b):
    return np.arctan2(np.linalg.norm(np.cross(a, b)), np.dot(a, b))


def book_forces(x, uv):
    """Vertex forces of the book, -sum_f N_f EI/rho_f d(alpha_f)/dx (4.220-4.240), in numpy.

    alpha_f is the angle between the twine vectors of the two triangles (4.240), its derivative taken by
    central differences; rho_f from the chords n Ua, n Ub by Heron (4.229-4.236); the count
    N_U = |V3 - V4|, N_V = |U3 - U4|, and the restoring sign (printed: +(V3 - V4), see the errata).
    """
    x, uv = np.asarray(x, float), np.asarray(uv, float)
    f = np.zeros((4, 3))
    for fam in (0, 1):
        n_twines = abs(uv[1, 1 - fam] - uv[0, 1 - fam])

        def alpha(y):
            (Ua, Va, _), (Ub, Vb, _) = book_twine_vectors(y, uv)
            return angle(Ua, Ub) if fam == 0 else angle(Va, Vb)

        tri_a, tri_b = book_twine_vectors(x, uv)
        a, b, da, db = tri_a[fam], tri_b[fam], tri_a[2], tri_b[2]
        na, nb = abs(da) / (2 * n_twines), abs(db) / (2 * n_twines)  # 4.229-4.230
        A, B, C = np.linalg.norm(na * a), np.linalg.norm(nb * b), np.linalg.norm(na * a + nb * b)
        p = (A + B + C) / 2
        rho = A * B * C / (4 * np.sqrt(p * (p - A) * (p - B) * (p - C)))
        h = 1e-7
        grad = np.zeros((4, 3))
        for i in range(4):
            for k in range(3):
                step = np.zeros((4, 3))
                step[i, k] = h
                grad[i, k] = (alpha(x + step) - alpha(x - step)) / (2 * h)
        f -= n_twines * EI / rho * grad
    return f


def test_all_twelve_forces_agree_with_the_book_to_second_order_in_the_fold():
    # Oblique side crossed by 2 U and 1.4 V twines of a rhombic (35° half-angle) unstretched net, folded:
    # the book's forces (in- and out-of-plane components) and -grad E agree to O(theta²): halving theta
    # quarters the relative difference.
    uv = jnp.array([[0.0, 0.0], [1.4, 2.0], [-1.5, 1.2], [2.2, 0.5]])
    errors = []
    for theta in (0.02, 0.01):
        x = fold(net_plane(np.asarray(uv)), theta)
        ours = np.asarray(force(jnp.asarray(x.ravel()), uv)).reshape(4, 3)
        book = book_forces(x, uv)
        errors.append(np.abs(ours - book).max() / np.abs(book).max())
    assert errors[0] < 1e-4
    np.testing.assert_allclose(errors[0] / errors[1], 4.0, rtol=0.02)


def test_book_angle_derivatives_241_to_244(rng):
    # 4.241-4.242 as printed, and 4.243-4.244 (printed garbled / missing) as the chain rule gives them,
    # against central differences of alpha (4.240). With G_a = d(alpha)/d(Ua), G_b = d(alpha)/d(Ub):
    # d/dx1 = (V3-V4)/d_a G_a, d/dx2 = (V4-V3)/d_b G_b, d/dx3 = (V4-V1)/d_a G_a + (V2-V4)/d_b G_b,
    # d/dx4 = (V1-V3)/d_a G_a + (V3-V2)/d_b G_b (book vertices 1, 2, 3, 4 = our p, q, a, b).
    uv = np.array([[0.0, 0.0], [1.4, 2.0], [-1.5, 1.2], [2.2, 0.5]])
    x = fold(net_plane(uv), 0.3) * (1 + 0.05 * rng.normal(size=(4, 3)))
    v3, v4, v1, v2 = uv[:, 1]
    (Ua, _, da), (Ub, _, db) = book_twine_vectors(x, uv)
    alpha = angle(Ua, Ub)
    dot, na, nb = Ua @ Ub, np.linalg.norm(Ua), np.linalg.norm(Ub)
    Ga = (dot * Ua - na**2 * Ub) / (na**3 * nb * np.sin(alpha))
    Gb = (dot * Ub - nb**2 * Ua) / (nb**3 * na * np.sin(alpha))
    book = {2: (v3 - v4) / da * Ga, 3: (v4 - v3) / db * Gb,
            0: (v4 - v1) / da * Ga + (v2 - v4) / db * Gb, 1: (v1 - v3) / da * Ga + (v3 - v2) / db * Gb}
    h = 1e-7
    for node, g in book.items():
        for k in range(3):
            step = np.zeros((4, 3))
            step[node, k] = h
            fd = (angle(*[t[0] for t in book_twine_vectors(x + step, uv)])
                  - angle(*[t[0] for t in book_twine_vectors(x - step, uv)])) / (2 * h)
            np.testing.assert_allclose(g[k], fd, rtol=1e-6, atol=1e-8 * np.abs(Ga).max() / abs(da))


def test_book_angle_is_the_in_plane_kink_plus_the_fold(rng):
    # The decomposition the energy rests on: 4 sin²(alpha/2) = 4 sin²((phi_a - phi_b)/2)
    # + sin(phi_a) sin(phi_b) 4 sin²(theta/2), for any positions (distorted, folded, d < 0).
    for clockwise in (False, True):
        for _ in range(5):
            x, uv = random_hinge(rng, clockwise)
            theta = float(fold_angle(x.reshape(4, 3)))
            x = np.asarray(x).reshape(4, 3)
            e = x[1] - x[0]
            (Ua, Va, _), (Ub, Vb, _) = book_twine_vectors(x, np.asarray(uv))
            for a, b in ((Ua, Ub), (Va, Vb)):
                alpha, pa, pb = angle(a, b), angle(a, e), angle(b, e)
                lhs = 4 * np.sin(alpha / 2) ** 2
                rhs = 4 * np.sin((pa - pb) / 2) ** 2 + np.sin(pa) * np.sin(pb) * 4 * np.sin(theta / 2) ** 2
                np.testing.assert_allclose(lhs, rhs, rtol=1e-10)


def test_fold_angle_sign_and_magnitude():
    uv = np.array([[0.0, 0.0], [0.0, 2.0], [-2.0, 1.0], [2.0, 1.0]])
    x = uv @ np.array([[L0, 0, 0], [0, L0, 0]])
    for theta in (0.3, -1.2, 2.9):
        np.testing.assert_allclose(fold_angle(jnp.asarray(fold(x, theta))), theta, rtol=1e-12)


@pytest.mark.parametrize("clockwise", [False, True])
def test_force_is_minus_gradient_and_stiffness_is_its_jacobian(clockwise, rng):
    for _ in range(4):
        x, uv = random_hinge(rng, clockwise)
        assert abs(float(fold_angle(x.reshape(4, 3)))) > 0.05  # a real fold, not near flat
        f = force(x, uv)
        fd = -fd_gradient(lambda y: energy(y, uv), x, 1e-7)
        np.testing.assert_allclose(f, fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
        K = stiffness(x, uv)
        fdK = -np.stack([(force(x.at[i].add(1e-7), uv) - force(x.at[i].add(-1e-7), uv)) / 2e-7
                         for i in range(12)], axis=1)
        np.testing.assert_allclose(K, fdK, rtol=1e-5, atol=1e-6 * np.abs(fdK).max())
        np.testing.assert_allclose(K, K.T, atol=1e-10 * np.abs(K).max())


def test_stiffness_at_the_flat_state_matches_finite_differences(rng):
    # the flat state is where 4.241-4.242 divide by sin(alpha) = 0; here the tangent is finite and exact
    x, uv = flattened_hinge(rng)
    K = stiffness(x, uv)
    fdK = -np.stack([(force(x.at[i].add(1e-7), uv) - force(x.at[i].add(-1e-7), uv)) / 2e-7
                     for i in range(12)], axis=1)
    np.testing.assert_allclose(K, fdK, rtol=1e-5, atol=1e-6 * np.abs(fdK).max())


def test_rigid_motions_produce_no_force(rng):
    for clockwise in (False, True):
        x, uv = random_hinge(rng, clockwise)
        y = x.reshape(4, 3)
        f = np.asarray(force(x, uv)).reshape(4, 3)
        assert np.abs(f).max() > 0
        # invariance: the energy of a translated and rotated hinge is the same, its forces rotate with it
        R = rotation(rng.normal(size=3), 1.1)
        moved = jnp.asarray(np.asarray(y) @ R.T + rng.normal(size=3))
        np.testing.assert_allclose(energy(moved.ravel(), uv), energy(x, uv), rtol=1e-12)
        np.testing.assert_allclose(np.asarray(force(moved.ravel(), uv)).reshape(4, 3), f @ R.T,
                                   atol=1e-10 * np.abs(f).max())
        # so no net force nor net moment on the hinge (virtual translations and rotations do no work)
        np.testing.assert_allclose(f.sum(0), 0.0, atol=1e-12 * np.abs(f).max())
        np.testing.assert_allclose(np.cross(np.asarray(y), f).sum(0), 0.0, atol=1e-12 * np.abs(f).max() * L0)
        # and the stiffness does not resist a translation
        K = np.asarray(stiffness(x, uv))
        np.testing.assert_allclose(K @ np.tile(rng.normal(size=3), 4), 0.0, atol=1e-10 * np.abs(K).max())


def test_degenerate_hinges_stay_finite():
    uv = jnp.array([[0.0, 0.0], [1.0, 2.0], [-1.5, 1.2], [2.2, 0.5]])
    x = jnp.asarray(fold(net_plane(np.asarray(uv)), 0.3))
    cases = {
        "collapsed side": x.at[1].set(x[0]),
        "flat triangle": x.at[2].set(0.5 * (x[0] + x[1])),
        "all nodes at one point": jnp.zeros((4, 3)),
        "p on a": x.at[2].set(x[0]),
        "q on b": x.at[3].set(x[1]),
    }
    for name, y in cases.items():
        for out in (energy(y.ravel(), uv), force(y.ravel(), uv), stiffness(y.ravel(), uv)):
            assert np.all(np.isfinite(np.asarray(out))), name
    # a side along a twine family: that family does not cross it and contributes nothing (N_V = 0 here)
    uv_u = jnp.array([[0.0, 0.0], [0.0, 2.0], [-2.0, 1.0], [2.0, 1.0]])
    y = jnp.asarray(fold(net_plane(np.asarray(uv_u)), 0.2))
    cu, cv = couples(y, uv_u)
    assert float(cv) == 0.0 and float(cu) > 0.0
    assert np.all(np.isfinite(np.asarray(stiffness(y.ravel(), uv_u))))


def reference_energy(x, uv):
    """The hinge energy (J) transcribed plainly from its definition, for autodiff: x (12,) m.

    theta = atan2((n1 ^ n2) . e / |e|, n1 . n2); sin(phi) = |F ^ e| / (|F| |e|) for each twine vector F of
    each triangle (geometry.twine_vectors on the positions). Valid away from collapsed hinges, for sides
    crossed by both families.
    """
    x = x.reshape(4, 3)
    e = x[1] - x[0]
    n1, n2 = jnp.cross(e, x[2] - x[0]), jnp.cross(-e, x[3] - x[1])
    theta = jnp.arctan2(jnp.cross(n1, n2) @ e / jnp.sqrt(e @ e), n1 @ n2)
    swap = lambda a: jnp.stack([a[1], a[0], a[3]])
    Ua, Va, da = geometry.twine_vectors(x[:3], uv[:3])
    Ub, Vb, db = geometry.twine_vectors(swap(x), swap(uv))

    def sin_phi(f):
        c = jnp.cross(f, e)
        return jnp.sqrt((c @ c) / ((f @ f) * (e @ e)))

    n_u, n_v = jnp.abs(uv[1, 1] - uv[0, 1]), jnp.abs(uv[1, 0] - uv[0, 0])
    total = n_u**2 * sin_phi(Ua) * sin_phi(Ub) + n_v**2 * sin_phi(Va) * sin_phi(Vb)
    return 2.0 * EI * theta**2 * total / (L0 * (jnp.abs(da) + jnp.abs(db)))


@jax.jit
def reference_energy_force_stiffness(x, uv):
    f = lambda y: -jax.grad(reference_energy)(y, uv)
    return reference_energy(x, uv), f(x), -jax.jacfwd(f)(x)


def flat_hinge(rng, clockwise):
    """A flat hinge distorted in its plane (Ua != Ub): an affine image of the net, q then moved away from
    the side a-b (so that it cannot cross it: theta stays 0, not pi)."""
    _, uv = random_hinge(rng, clockwise)
    x = net_plane(np.asarray(uv)) @ np.diag([1.0 + 0.2 * rng.uniform(), 1.0 - 0.2 * rng.uniform(), 1.0])
    side = (x[1] - x[0]) / np.linalg.norm(x[1] - x[0])
    away = x[3] - x[0] - np.dot(x[3] - x[0], side) * side
    x[3] += 0.1 * L0 * (side + away / np.linalg.norm(away))
    return jnp.asarray(x.ravel()), uv


def test_closed_form_stiffness_is_autodiff_of_the_formula(rng):
    # The assembly's stiffness, jax.jacfwd(jax.grad(hinge_energy)) vmapped over hinges, comes from the
    # module's closed-form derivatives (custom JVP rules); it and the forces must be autodiff's of the
    # plainly written formula, to roundoff: random folded, stretched and sheared hinges (both
    # orientations), flat ones, folds near +-pi.
    hinges = [random_hinge(rng, clockwise) for clockwise in (False, True) for _ in range(2)]
    flat = [flat_hinge(rng, clockwise) for clockwise in (False, True)]
    near_pi = [(jnp.asarray(fold(np.asarray(x).reshape(4, 3), t)).ravel(), uv)
               for (x, uv), t in zip(flat, (3.0, -3.1))]
    hinges += flat + near_pi
    x, uv = jnp.stack([h[0] for h in hinges]), jnp.stack([h[1] for h in hinges])
    thetas = jax.vmap(bending.fold_angle)(x.reshape(-1, 4, 3))
    np.testing.assert_allclose(thetas[-4:], [0.0, 0.0, 3.0, -3.1], atol=1e-12)
    ours = jax.jit(jax.vmap(_energy_force_stiffness))(x, uv)
    for i, (xi, uvi) in enumerate(hinges):
        for a, b in zip(ours, reference_energy_force_stiffness(xi, uvi)):
            a, b = np.asarray(a[i]), np.asarray(b)
            assert np.all(np.isfinite(a))
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-10 * np.abs(b).max())
    assert float(ours[0][4]) == 0.0 and float(ours[0][6]) > 0.0  # flat: no energy; folded: some


def test_derivatives_in_twine_coordinates_length_and_stiffness(rng):
    # Not taken by the solver (the closed forms are in x only; these fall back on autodiff), but the
    # simulator is differentiable in its parameters: dE/d(uv, l0, EI) against central differences.
    x, uv = random_hinge(rng)
    params = (uv, jnp.asarray(L0), jnp.asarray(EI))
    e = jax.jit(lambda uv, l0, ei: bending.hinge_energy(x.reshape(4, 3), uv, l0, ei))
    grads = jax.jit(jax.grad(lambda *p: e(*p), argnums=(0, 1, 2)))(*params)
    np.testing.assert_allclose(grads[2], e(*params) / EI, rtol=1e-12)  # E is linear in EI
    np.testing.assert_allclose(grads[1], -e(*params) / L0, rtol=1e-12)  # and goes as 1/l0
    h = 1e-6
    fd = np.array([(e(uv.at[i, j].add(h), *params[1:]) - e(uv.at[i, j].add(-h), *params[1:])) / (2 * h)
                   for i in range(4) for j in range(2)]).reshape(4, 2)
    np.testing.assert_allclose(grads[0], fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
    assert np.abs(fd).max() > 0


# ---------------------------------------------------------------- the hinges of a mesh

def grid_triangles(nx, ny):
    """nx by ny squares of a node grid (node k = i + (nx + 1) j), each cut along a diagonal, CCW triangles."""
    i, j = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    n0 = (i + (nx + 1) * j).ravel()
    n1, n2, n3 = n0 + 1, n0 + nx + 2, n0 + nx + 1
    tri = np.concatenate([np.stack([n0, n1, n2], 1), np.stack([n0, n2, n3], 1)])
    return tri, np.concatenate([i.ravel(), i.ravel()])


def test_hinges_of_a_structured_mesh_are_its_interior_sides(rng):
    nx, ny = 4, 3
    tri, _ = grid_triangles(nx, ny)
    pairs, nodes = find_hinges(tri)
    # sides: 3E/2 counted twice inside, once on the border (2 (nx + ny) of them)
    assert len(pairs) == (3 * len(tri) - 2 * (nx + ny)) // 2 == 29
    assert pairs.shape == (29, 2) and nodes.shape == (29, 4)
    assert np.all(pairs[:, 0] < pairs[:, 1])
    for (t1, t2), (a, b, p, q) in zip(pairs, nodes):
        assert {a, b, p} == set(tri[t1]) and {a, b, q} == set(tri[t2]) and p != q
        # (a, b, p) has triangle 1's own orientation: it is a cyclic shift of its vertex list
        k = list(tri[t1]).index(a)
        assert tri[t1][(k + 1) % 3] == b
    # deterministic, and independent of the order the triangles are listed in (as a set of hinges)
    again = find_hinges(tri)
    assert np.array_equal(again[0], pairs) and np.array_equal(again[1], nodes)
    perm = rng.permutation(len(tri))
    _, nodes_perm = find_hinges(tri[perm])
    key = lambda n: {(min(a, b), max(a, b), frozenset((p, q))) for a, b, p, q in n}
    assert key(nodes_perm.tolist()) == key(nodes.tolist())


def test_hinges_skip_sides_between_panels():
    nx, ny = 4, 3
    tri, column = grid_triangles(nx, ny)
    panel = (column >= 2).astype(int)  # columns 0-1 and 2-3: a seam of ny sides on the line i = 2
    pairs, nodes = find_hinges(tri, panel)
    assert len(pairs) == 29 - ny
    assert np.all(panel[pairs[:, 0]] == panel[pairs[:, 1]])
    # a third panel on a seam side (nodes 2-7): three panels meet there, which is a seam, not an error
    extra = np.array([[2, 7, 99]])
    pairs3, _ = find_hinges(np.concatenate([tri, extra]), np.append(panel, 7))
    assert len(pairs3) == len(pairs)


def test_non_manifold_side_is_refused_with_its_nodes():
    tri, _ = grid_triangles(2, 2)
    bad = np.concatenate([tri, [[5, 4, 99]]])  # side 4-5 already borders two triangles
    with pytest.raises(ValueError, match=r"nodes 4, 5\) is shared by 3 triangles"):
        find_hinges(bad)
    with pytest.raises(ValueError, match="repeated node"):
        find_hinges([[0, 1, 1]])
    with pytest.raises(ValueError, match="same nodes"):
        find_hinges([[0, 1, 2], [2, 1, 0]])
    with pytest.raises(ValueError, match="shape"):
        find_hinges([[0, 1, 2, 3]])


def test_hinge_energy_on_a_mesh_folded_along_a_row_of_sides():
    # A 2x1 grid (uv = node grid, U along x) folded by theta about the line x = 1: the only stiff hinge is
    # the vertical side between the squares, crossed by one U twine at right angles with chords
    # n = |d|/(2 N) = 1/2 on each side: E = EI theta² / (A + B) = EI theta² / l0.
    tri, _ = grid_triangles(2, 1)
    uv = np.array([[i, j] for j in range(2) for i in range(3)], float)
    x = np.c_[uv * L0, np.zeros(6)]
    theta = 0.2
    right, R, axis_point = x[:, 0] > L0 * 1.5, rotation([0, 1, 0], theta), np.array([L0, 0.0, 0.0])
    x[right] = (x[right] - axis_point) @ R.T + axis_point
    _, nodes = find_hinges(tri)
    total = sum(float(energy(jnp.asarray(x[n].ravel()), jnp.asarray(uv[n]))) for n in nodes)
    np.testing.assert_allclose(total, EI * theta**2 / L0, rtol=1e-12)
