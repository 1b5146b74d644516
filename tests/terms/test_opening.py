"""Mesh opening stiffness (in-plane twine flexion, eqs 4.211-4.219): energy, forces, stiffness, limits."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from elements import random_twine_coordinates  # tests/elements.py

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.terms import opening

STEP = np.eye(9)
H, ALPHA0 = 0.8, 0.55  # N·m/rad, rad (half angle)
ONE_MESH = jnp.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])  # d = 4: one mesh, two knots


def lattice_positions(uv, alpha, side=0.05, twist=None):
    """Vertices of a net of twine vectors of length ``side`` at half angle ``alpha`` on either side of x.

    Built from the lattice (OP = U_P U + V_P V, eq. 4.16), independently of geometry.twine_vectors.
    ``twist`` rotates the whole net rigidly (3x3 matrix).
    """
    U = side * np.array([np.cos(alpha), np.sin(alpha), 0.0])
    V = side * np.array([np.cos(alpha), -np.sin(alpha), 0.0])
    uv = np.asarray(uv)
    x = uv[:, 0:1] * U + uv[:, 1:2] * V
    return jnp.asarray(x if twist is None else x @ np.asarray(twist).T)


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return jnp.asarray(q * np.sign(np.diag(r)))


def random_element(rng, clockwise):
    # well-conditioned twine coordinates (tests/elements.py: 2 < |d| < 40, no side under a third of the longest):
    # drawn anywhere in [-4, 4]², a sliver (|d| = 1e-3) times a nearly closed mesh (alpha = 0.005°) rounded 4.218
    # and autodiff's dalpha/dx 4e-8 apart, roundoff growing as 1 / (|d| sin 2 alpha)
    uv = random_twine_coordinates(rng, clockwise)
    x = rng.normal(size=(3, 3)) * 0.05
    return jnp.asarray(x), jnp.asarray(uv)


def _energy(x, uv):
    return opening.opening_energy(x.reshape(3, 3), uv, H, ALPHA0)


# one compiled program for energy, forces (-grad) and stiffness (jacfwd of grad, 4.219): x is (9,)
evaluate = jax.jit(lambda x, uv: (_energy(x, uv), -jax.grad(_energy)(x, uv), jax.jacfwd(jax.grad(_energy))(x, uv)))


def energy(x, uv):
    return evaluate(x, uv)[0]


def force(x, uv):
    return evaluate(x, uv)[1]


def stiffness(x, uv):
    return evaluate(x, uv)[2]


half_angle = jax.jit(lambda x, uv: opening.half_angle(x, uv)[0])
grad_alpha = jax.jit(jax.grad(lambda x, uv: opening.half_angle(x, uv)[0]))


@pytest.mark.parametrize("delta", [0.3, -0.2, 0.01])
def test_one_mesh_opened_by_delta_stores_2_H_delta_squared(delta, rng):
    # one mesh = 2 knots; at each the couple H(α - α0) turns U by dα and V by -dα: work 2 H (α - α0) dα,
    # i.e. H δα² per knot once opened by δα, 2 H δα² for the mesh, whatever its orientation and side
    for side in (0.02, 0.07):
        x = lattice_positions(ONE_MESH, ALPHA0 + delta, side, random_rotation(rng))
        np.testing.assert_allclose(energy(x.ravel(), ONE_MESH), 2.0 * H * delta**2, rtol=1e-11)


@pytest.mark.parametrize("clockwise", [False, True])
def test_many_mesh_element_stores_H_delta_squared_per_knot(clockwise, rng):
    # book example of Figs 4.6/4.8: d = 38, 9.5 meshes, 19 knots: 19 H δα²
    uv = jnp.array([[0.0, 0.0], [2.0, -5.0], [6.0, 4.0]])
    if clockwise:
        uv = uv[jnp.array([0, 2, 1])]
    delta = -0.17
    x = lattice_positions(uv, ALPHA0 + delta, 0.03, random_rotation(rng))
    np.testing.assert_allclose(energy(x.ravel(), uv), 19.0 * H * delta**2, rtol=1e-11)


def test_rest_angle_is_a_minimum_with_the_derived_curvature(rng):
    # at α0 the forces vanish; along the opening path E = 2 H (α - α0)², so d²E/dα² = 4 H
    rotation = random_rotation(rng)
    x0 = lattice_positions(ONE_MESH, ALPHA0, twist=rotation).ravel()
    f0 = force(x0, ONE_MESH)
    assert float(jnp.abs(f0).max()) < 1e-12
    path = lambda a: energy(lattice_positions(ONE_MESH, a, twist=rotation).ravel(), ONE_MESH)
    h = 1e-4
    curvature = (path(ALPHA0 + h) - 2 * path(ALPHA0) + path(ALPHA0 - h)) / h**2
    np.testing.assert_allclose(curvature, 4.0 * H, rtol=1e-6)
    # stiffness at rest: |d| H (dα/dx)(dα/dx)^T, positive semi-definite of rank one
    K = stiffness(x0, ONE_MESH)
    grad_alpha_x0 = grad_alpha(x0.reshape(3, 3), ONE_MESH).ravel()
    np.testing.assert_allclose(K, 4.0 * H * jnp.outer(grad_alpha_x0, grad_alpha_x0), atol=1e-9 * jnp.abs(K).max())
    eigenvalues = np.linalg.eigvalsh(np.asarray(K))
    assert eigenvalues.min() > -1e-9 * eigenvalues.max() and eigenvalues.max() > 0


def test_half_angle_is_half_the_acos_of_4211(rng):
    for _ in range(10):
        x, uv = random_element(rng, clockwise=bool(rng.integers(2)))
        U, V, _ = geometry.twine_vectors(np.asarray(x), np.asarray(uv))
        book = 0.5 * np.arccos(np.dot(U, V) / (np.linalg.norm(U) * np.linalg.norm(V)))
        np.testing.assert_allclose(half_angle(x, uv), book, rtol=1e-10)
    x = lattice_positions(ONE_MESH, np.pi / 4)
    np.testing.assert_allclose(half_angle(x, ONE_MESH), np.pi / 4, rtol=1e-14)  # square meshes
    couple = jax.jit(opening.opening_couple)(lattice_positions(ONE_MESH, 0.7), ONE_MESH, H, ALPHA0)
    np.testing.assert_allclose(couple, H * (0.7 - ALPHA0), rtol=1e-12)



def _plain_half_angle(U, V):
    """The half angle without its hand-written derivative: autodiff differentiates through the cross product."""
    return 0.5 * jnp.arctan2(geometry.safe_norm(jnp.cross(U, V)), jnp.dot(U, V))


def test_half_angle_derivatives_by_hand_are_autodiffs_and_finite_differences():
    # geometry.half_opening_angle carries its own JVP (dot products, no sliced cross product): its gradient
    # and Hessian are the autodiff ones of the plain formula, and central differences of the angle
    gradient = jax.jit(jax.grad(lambda w: geometry.half_opening_angle(w[:3], w[3:])))
    plain_gradient = jax.jit(jax.grad(lambda w: _plain_half_angle(w[:3], w[3:])))
    hessian = jax.jit(jax.jacfwd(jax.grad(lambda w: geometry.half_opening_angle(w[:3], w[3:]))))
    plain_hessian = jax.jit(jax.jacfwd(jax.grad(lambda w: _plain_half_angle(w[:3], w[3:]))))
    angle = jax.jit(lambda w: geometry.half_opening_angle(w[:3], w[3:]))
    rng = np.random.default_rng(4212)  # its own draws: the same elements whichever tests ran before in the process
    for scale in (1.0, 1e-3):  # also nearly closed meshes (U, V nearly parallel)
        for _ in range(5):
            U = rng.normal(size=3)
            w = np.concatenate([U, 2.0 * U + scale * rng.normal(size=3)])
            g = np.asarray(gradient(w))
            # both formulas round within the gap between U and V: their difference grows as 1/scale
            np.testing.assert_allclose(g, plain_gradient(w), rtol=1e-12, atol=1e-14 * np.abs(g).max() / scale)
            np.testing.assert_allclose(hessian(w), plain_hessian(w), rtol=1e-10,
                                       atol=1e-12 * np.abs(hessian(w)).max() / scale)
            h = 1e-5 * scale * np.linalg.norm(w)  # the angle varies over the gap between U and V
            fd = [(angle(w + h * e) - angle(w - h * e)) / (2 * h) for e in np.eye(6)]
            np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-8 * np.abs(g).max())
    # exactly closed and exactly opened flat (U, V parallel, antiparallel): the angle's derivative is taken as 0
    for other in (2.0, -2.0):
        w = np.concatenate([[1.0, 2.0, 3.0], other * np.array([1.0, 2.0, 3.0])])
        np.testing.assert_array_equal(gradient(w), plain_gradient(w))
        assert np.all(np.isfinite(hessian(w)))
    # and the gradient holds no pad (the transpose of a slice), which XLA ran once per slice, each time
    # recomputing the knot contact's derivative before it
    U, V = rng.normal(size=3), rng.normal(size=3)
    assert " pad[" not in str(jax.make_jaxpr(jax.grad(geometry.half_opening_angle, argnums=(0, 1)))(U, V))
    assert " pad[" in str(jax.make_jaxpr(jax.grad(_plain_half_angle, argnums=(0, 1)))(U, V))

@pytest.mark.parametrize("closed", ["U+V", "U-V"])
def test_closed_meshes_have_finite_energy_forces_and_stiffness(closed, rng):
    # α -> 0 (U parallel to V) and α -> π/2 (U antiparallel to V): E = 2 H α0² resp. 2 H (π/2 - α0)²
    limit = 0.0 if closed == "U+V" else jnp.pi / 2
    expected = 2.0 * H * (limit - ALPHA0) ** 2
    side = 0.05
    exact = jnp.array([[0.0, 0.0, 0.0], [2 * side, 0.0, 0.0], [(1 if closed == "U+V" else -1) * 2 * side, 0.0, 0.0]])
    rotation = random_rotation(rng)
    configurations = [exact, lattice_positions(ONE_MESH, limit, side, rotation)]
    # and nearly closed (either side of closure, in a rotated plane): the kink is steep but finite
    configurations += [lattice_positions(ONE_MESH, limit + s, side, rotation) for s in (1e-7, -1e-7)]
    for x in configurations:
        x = x.ravel()
        e, f, K = energy(x, ONE_MESH), force(x, ONE_MESH), stiffness(x, ONE_MESH)
        assert np.isfinite(np.asarray(f)).all() and np.isfinite(np.asarray(K)).all()
        np.testing.assert_allclose(e, expected, rtol=1e-6)
    # at the exactly closed mesh the forces are those of the chosen subgradient: zero
    assert float(jnp.abs(force(exact.ravel(), ONE_MESH)).max()) == 0.0


def test_nearly_closed_mesh_pulls_open_with_the_book_couple():
    # in plane near closure: vertex 3 = 2V at angle -α; moving it by dy turns V by dy/|2V|, so α by
    # -dy/(2|2V|), and F_y = -dE/dy = 4 H (α - α0) / (2 |2V|): finite, opening the mesh (towards -y)
    alpha, side = 1e-6, 0.05
    positions = lattice_positions(ONE_MESH, alpha, side)
    f = force(positions.ravel(), ONE_MESH).reshape(3, 3)
    np.testing.assert_allclose(f[2, 1], 4.0 * H * (alpha - ALPHA0) / (2 * 2 * side), rtol=1e-6)
    np.testing.assert_allclose(jnp.cross(positions, f).sum(0), 0.0, atol=1e-12)  # internal: no moment


def test_collapsed_element_carries_nothing_and_stays_finite():
    for x in (jnp.zeros(9), jnp.array([0.0, 0, 0, 0.1, 0, 0, 0, 0, 0])):
        assert float(energy(x, ONE_MESH)) == 0.0
        assert np.isfinite(np.asarray(stiffness(x, ONE_MESH))).all()


@pytest.mark.parametrize("clockwise", [False, True])
def test_force_is_minus_gradient_by_finite_differences(clockwise, rng):
    for _ in range(6):
        x, uv = random_element(rng, clockwise)
        x = np.asarray(x).ravel()
        h = 1e-7
        fd = -np.array([(energy(x + h * STEP[i], uv) - energy(x - h * STEP[i], uv)) / (2 * h) for i in range(9)])
        f = force(x, uv)
        np.testing.assert_allclose(f, fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())
        # internal forces: no resultant, no moment (the energy is invariant under rigid motions)
        np.testing.assert_allclose(f.reshape(3, 3).sum(0), 0.0, atol=1e-10 * np.abs(f).max())
        np.testing.assert_allclose(jnp.cross(x.reshape(3, 3), f.reshape(3, 3)).sum(0), 0.0,
                                   atol=1e-10 * np.abs(f).max())


@pytest.mark.parametrize("clockwise", [False, True])
def test_jacfwd_stiffness_equals_finite_differences_of_forces(clockwise, rng):
    for _ in range(6):
        x, uv = random_element(rng, clockwise)
        x = np.asarray(x).ravel()
        K = stiffness(x, uv)  # -dF/dx (4.219)
        h = 1e-7
        fd = -np.stack([(force(x + h * STEP[i], uv) - force(x - h * STEP[i], uv)) / (2 * h) for i in range(9)], axis=1)
        np.testing.assert_allclose(K, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
        np.testing.assert_allclose(K, K.T, atol=1e-10 * np.abs(K).max())


CORRECT_U_SIGNS = (1.0, -1.0)


def book_dalpha(x, uv, sin_of, u_signs=CORRECT_U_SIGNS):
    """Eq. 4.218 with u_i, v_i the twine-coordinate factors of 4.43-4.45 (v_1 = V3 - V2, u_1 = U2 - U3).

    ``u_signs`` are the signs of the U_w u_i and V_w (U.V) u_i / |V|² terms: (+1, -1) is correct, the
    printed form has (-1, -1). ``sin_of`` is the argument of the sine: 2α (correct) or α (printed).
    """
    x, uv = np.asarray(x), np.asarray(uv)
    U, V, d = geometry.twine_vectors(x, uv)
    alpha = 0.5 * np.arctan2(np.linalg.norm(np.cross(U, V)), np.dot(U, V))
    Ui, Vi = uv[:, 0], uv[:, 1]
    v = np.array([Vi[2] - Vi[1], Vi[0] - Vi[2], Vi[1] - Vi[0]])[:, None]
    u = np.array([Ui[1] - Ui[2], Ui[2] - Ui[0], Ui[0] - Ui[1]])[:, None]
    uv_dot, nu2, nv2 = np.dot(U, V), np.dot(U, U), np.dot(V, V)
    numerator = V * v + u_signs[0] * U * u - U * uv_dot * v / nu2 + u_signs[1] * V * uv_dot * u / nv2
    return numerator / (2 * d * np.sin(sin_of(alpha)) * np.sqrt(nu2 * nv2))


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_4217_4218_once_corrected(clockwise, rng):
    # F_wi = -H (α - α0) |d| dα/dw_i with the corrected 4.218
    for _ in range(6):
        x, uv = random_element(rng, clockwise)
        d = geometry.twine_determinant(np.asarray(uv))
        exact = grad_alpha(x, uv)
        corrected = book_dalpha(x, uv, lambda a: 2 * a)
        np.testing.assert_allclose(corrected, exact, rtol=1e-9, atol=1e-12 * np.abs(exact).max())
        alpha = half_angle(x, uv)
        np.testing.assert_allclose(force(x.ravel(), uv).reshape(3, 3), -H * (alpha - ALPHA0) * abs(d) * corrected,
                                   rtol=1e-9, atol=1e-12)
        # the printed sin(α), and the printed signs of the u_i terms whichever the sign of u_i, are wrong
        wrong = [book_dalpha(x, uv, lambda a: a)]
        wrong += [book_dalpha(x, uv, lambda a: 2 * a, signs) for signs in ((-1.0, -1.0), (1.0, 1.0))]
        for w in wrong:
            assert np.abs(w - exact).max() > 1e-3 * np.abs(exact).max()


def test_book_4215_is_minus_the_determinant_of_47(rng):
    for _ in range(5):
        _, uv = random_element(rng, clockwise=False)
        (U1, V1), (U2, V2), (U3, V3) = np.asarray(uv)
        printed = (U2 - U1) * (V1 - V3) - (U3 - U1) * (V1 - V2)
        np.testing.assert_allclose(printed, -geometry.twine_determinant(uv), rtol=1e-13)
