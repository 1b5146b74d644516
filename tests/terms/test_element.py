"""The diamond-mesh element: geometry (4.1-4.29), tension energy, forces and stiffness (4.30-4.75)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.terms import tension



def random_element(rng, clockwise=False):
    """A well-conditioned random triangle: twine coordinates and positions near a stretched net."""
    uv = rng.uniform(-5, 5, size=(3, 2))
    d = geometry.twine_determinant(uv)
    if (d < 0) != clockwise:
        uv = uv[[0, 2, 1]]
    x = rng.normal(size=(3, 3)) * 0.05
    return jnp.asarray(x), jnp.asarray(uv)


@pytest.mark.parametrize("clockwise", [False, True])
def test_twine_vectors_rebuild_the_sides(clockwise, rng):
    # eqs 4.1-4.2: 12 = dU12 U + dV12 V, 13 = dU13 U + dV13 V, whatever the sign of d
    for _ in range(20):
        x, uv = random_element(rng, clockwise)
        U, V, d = geometry.twine_vectors(x, uv)
        assert (d < 0) == clockwise
        for j in (1, 2):
            side = (uv[j, 0] - uv[0, 0]) * U + (uv[j, 1] - uv[0, 1]) * V
            np.testing.assert_allclose(side, x[j] - x[0], rtol=1e-12, atol=1e-14)


def test_counts_of_the_book_example():
    # Figs 4.6/4.8: d = 38 gives 9.5 meshes; U and V twines and knots are d/2 = 19
    # (the book prints 18 for these: erratum recorded in docs/errata.md)
    uv = jnp.array([[0.0, 0.0], [2.0, -5.0], [6.0, 4.0]])
    d = geometry.twine_determinant(uv)
    assert float(d) == 38.0
    assert float(geometry.mesh_count(d)) == 9.5
    assert float(geometry.twine_count(d)) == 19.0
    assert float(geometry.knot_count(d)) == 19.0
    assert float(geometry.twine_count(-d)) == 19.0


def test_mesh_surface_times_mesh_count_is_the_surface(rng):
    # 4.28-4.29: S = Ms * nb_m on any triangle
    for _ in range(20):
        x, uv = random_element(rng, clockwise=bool(rng.integers(2)))
        U, V, d = geometry.twine_vectors(x, uv)
        np.testing.assert_allclose(geometry.mesh_surface(U, V) * geometry.mesh_count(d), geometry.surface(x), rtol=1e-11)


def element_energy(ea_c):
    return jax.jit(lambda x, uv: tension.netting_energy(x.reshape(3, 3), uv, 0.02, 1500.0, ea_c))


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize("ea_c", [None, 300.0])
def test_force_is_minus_gradient_of_energy(clockwise, ea_c, rng):
    energy = element_energy(ea_c)
    for _ in range(10):
        x, uv = random_element(rng, clockwise)
        x = x.ravel()
        g = jax.grad(energy)(x, uv)
        h = 1e-7
        fd = np.array([(energy(x.at[i].add(h), uv) - energy(x.at[i].add(-h), uv)) / (2 * h) for i in range(9)])
        np.testing.assert_allclose(g, fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())


@pytest.mark.parametrize("clockwise", [False, True])
def test_forces_agree_with_book_443_up_to_the_sign_of_d(clockwise, rng):
    # eqs 4.43-4.45 give the force on each vertex for d > 0; for d < 0 the printed form has the wrong sign
    l0, ea = 0.02, 1500.0
    for _ in range(10):
        x, uv = random_element(rng, clockwise)
        U, V, d = geometry.twine_vectors(x, uv)
        tu = ea * (jnp.linalg.norm(U) - l0) / l0
        tv = ea * (jnp.linalg.norm(V) - l0) / l0
        Ui, Vi = uv[:, 0], uv[:, 1]
        u_hat, v_hat = U / (2 * jnp.linalg.norm(U)), V / (2 * jnp.linalg.norm(V))
        book = jnp.stack([
            (Vi[2] - Vi[1]) * tu * u_hat + (Ui[1] - Ui[2]) * tv * v_hat,
            (Vi[0] - Vi[2]) * tu * u_hat + (Ui[2] - Ui[0]) * tv * v_hat,
            (Vi[1] - Vi[0]) * tu * u_hat + (Ui[0] - Ui[1]) * tv * v_hat,
        ])
        force = -jax.grad(lambda y: tension.netting_energy(y, uv, l0, ea, ea))(x)
        np.testing.assert_allclose(force, jnp.sign(d) * book, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize("ea_c", [None, 300.0])
def test_jacfwd_stiffness_equals_finite_differences_of_forces(clockwise, ea_c, rng):
    energy = element_energy(ea_c)
    force = jax.jit(lambda x, uv: -jax.grad(energy)(x, uv))
    for _ in range(10):
        x, uv = random_element(rng, clockwise)
        x = x.ravel()
        K = -jax.jacfwd(force)(x, uv)  # K = -dF/dx (eq. 4.46)
        h = 1e-7
        fd = -np.stack([(force(x.at[i].add(h), uv) - force(x.at[i].add(-h), uv)) / (2 * h) for i in range(9)], axis=1)
        np.testing.assert_allclose(K, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
        np.testing.assert_allclose(K, K.T, atol=1e-9 * np.abs(K).max())  # conservative: symmetric


def test_slack_twine_carries_nothing_without_compression_stiffness():
    # a twine shorter than l0 with EA_c = 0 stores no energy and pulls nothing; with EA_c it pushes
    assert float(tension.elastic_energy(0.015, 0.02, 1000.0, None)) == 0.0
    assert float(tension.tension(0.015, 0.02, 1000.0, None)) == 0.0
    np.testing.assert_allclose(tension.tension(0.015, 0.02, 1000.0, 400.0), 400.0 * (-0.25))
    np.testing.assert_allclose(tension.tension(0.025, 0.02, 1000.0, 400.0), 1000.0 * 0.25)


def test_book_458_misses_a_division_by_the_twine_length(rng):
    # eq. 4.58 prints d|U|/dx1 = (V2-V3)/d² [(x2-x1)(V3-V1) - (x3-x1)(V2-V1)]; the bracket over d is U_x, so
    # the derivative of |U| needs a further 1/|U| (as 4.178 has it). Same for 4.59-4.75. docs/errata.md
    for _ in range(10):
        x, uv = random_element(rng, clockwise=bool(rng.integers(2)))
        U, V, d = geometry.twine_vectors(x, uv)
        V1, V2, V3 = uv[:, 1]
        bracket = (x[1, 0] - x[0, 0]) * (V3 - V1) - (x[2, 0] - x[0, 0]) * (V2 - V1)
        printed = (V2 - V3) / d**2 * bracket
        exact = jax.grad(lambda y: jnp.linalg.norm(geometry.twine_vectors(y, uv)[0]))(x)[0, 0]
        np.testing.assert_allclose(printed / jnp.linalg.norm(U), exact, rtol=1e-10)
        assert abs(printed - exact) > 1e-3 * abs(exact)
