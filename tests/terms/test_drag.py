"""Hydrodynamic drag (book 4.114-4.135) on twines, bars and nodes, and the current profile."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from elements import central_differences  # tests/elements.py

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.water import current
from jaxnet.terms import drag


L0, D, CN, CT, RHO = 0.02, 0.0012, 1.2, 0.1, 1025.0
#: ½ ρ Cn D l0 and ½ ρ Ct D l0: drag of one twine per (m/s)² normal to and along it
KN, KT = 0.5 * RHO * CN * D * L0, 0.5 * RHO * CT * D * L0


def netting(x, uv, c):
    return drag.netting_drag(x, uv, L0, D, CN, CT, c, RHO)


netting_jit = jax.jit(netting)
netting_parts = jax.jit(lambda x, uv, c: drag.netting_drag_parts(x, uv, L0, D, CN, CT, c, RHO))
jac_x = jax.jit(jax.jacfwd(netting, argnums=0))
jac_c = jax.jit(jax.jacfwd(netting, argnums=2))


def random_element(rng, clockwise=False):
    """A random triangle: twine coordinates (d of the requested sign) and positions around 5 cm."""
    uv = rng.uniform(-5, 5, size=(3, 2))
    if (geometry.twine_determinant(uv) < 0) != clockwise:
        uv = uv[[0, 2, 1]]
    return jnp.asarray(rng.normal(size=(3, 3)) * 0.05), jnp.asarray(uv)


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return jnp.asarray(q * np.linalg.det(q))  # proper rotation


def diamond_panel(nu=4, nv=3, stretch=1.05, half_angle=0.6):
    """Flat panel in z = 0 covering [0, nu] x [0, nv] in twine coordinates, every other triangle clockwise.

    The twines are stretched (|U| = |V| = stretch * l0) so that using |U| instead of l0 would show.
    """
    Uvec = stretch * L0 * np.array([np.cos(half_angle), np.sin(half_angle), 0.0])
    Vvec = stretch * L0 * np.array([np.cos(half_angle), -np.sin(half_angle), 0.0])
    uvs, xs = [], []
    for i in range(nu):
        for j in range(nv):
            corners = np.array([[i, j], [i + 1, j], [i + 1, j + 1], [i, j + 1]], float)
            for k, tri in enumerate(([0, 1, 2], [0, 2, 3])):
                t = corners[tri]
                if (i + j + k) % 2:
                    t = t[[0, 2, 1]]
                uvs.append(t)
                xs.append(t[:, :1] * Uvec + t[:, 1:] * Vvec)
    return jnp.asarray(np.array(xs)), jnp.asarray(np.array(uvs))


@pytest.mark.parametrize("rotated", [False, True])
def test_flat_panel_normal_to_the_current(rotated, rng):
    # every twine is normal to c: total drag = (number of twines) ½ ρ Cd D l0 c² along c, nothing tangential
    x, uv = diamond_panel()
    d = jax.vmap(geometry.twine_determinant)(uv)
    assert (d < 0).any() and (d > 0).any()
    n_twines = 2 * 4 * 3  # U twines = V twines = twine-coordinate area
    np.testing.assert_allclose(jnp.abs(d).sum(), n_twines)
    c = jnp.array([0.0, 0.0, -0.8])
    if rotated:
        R = random_rotation(rng)
        x, c = x @ R.T, R @ c
    f = jax.vmap(netting_jit, in_axes=(0, 0, None))(x, uv, c)
    total = f.sum(axis=(0, 1))
    np.testing.assert_allclose(total, n_twines * KN * 0.8**2 * c / 0.8, rtol=1e-12, atol=1e-17)
    # each vertex of each element takes one third of its element's drag, all along c
    across = f - (f @ c)[..., None] * c / 0.64
    assert np.abs(across).max() < 1e-15
    parts = jax.vmap(netting_parts, in_axes=(0, 0, None))(x, uv, c)
    assert np.abs(parts["u_tangential"]).max() < 1e-18 and np.abs(parts["v_tangential"]).max() < 1e-18
    np.testing.assert_allclose(parts["u_normal"] + parts["v_normal"], 3 * f[:, 0], rtol=1e-13)
    for jac in (jac_x, jac_c):
        assert np.isfinite(jax.vmap(jac, in_axes=(0, 0, None))(x, uv, c)).all()


def test_drag_uses_unstretched_twine_length(rng):
    # book text after 4.117: the area is D l0 whatever the stretch; only U's direction matters
    x, uv = random_element(rng)
    c = jnp.asarray(rng.normal(size=3))
    np.testing.assert_allclose(netting_jit(1.7 * x, uv, c), netting_jit(x, uv, c), rtol=1e-12)


def axis_element(clockwise):
    """Element whose U twine is exactly along x (U = 12, V = 13 exactly, |d| = 1)."""
    uv = jnp.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    if clockwise:
        uv = uv[jnp.array([0, 2, 1])]
    U, V = jnp.array([0.021, 0.0, 0.0]), jnp.array([0.004, 0.017, 0.007])
    origin = jnp.array([0.3, -0.2, -1.5])
    x = origin + uv[:, :1] * U + uv[:, 1:] * V
    U_, V_, d = geometry.twine_vectors(x, uv)
    assert (U_[1], U_[2]) == (0.0, 0.0)
    return x, uv, U, V


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize(
    "case",
    ["along_u", "against_u", "normal_to_u", "normal_to_panel", "still_water"],
)
def test_degenerate_directions_are_smooth(case, clockwise):
    # the printed directions 4.116-4.117 are 0/0 here; force and stiffness must be finite and equal to
    # the limit from either side (direction perturbed by +-1e-7)
    x, uv, U, V = axis_element(clockwise)
    speed = 1.3
    directions = {
        "along_u": U / jnp.linalg.norm(U),
        "against_u": -U / jnp.linalg.norm(U),
        "normal_to_u": jnp.array([0.0, 0.0, 1.0]),
        "normal_to_panel": jnp.cross(U, V) / jnp.linalg.norm(jnp.cross(U, V)),
        "still_water": jnp.zeros(3),
    }
    c0 = speed * directions[case]
    wobble = jnp.array([0.3, -0.8, 0.52])
    f0, jx0, jc0 = netting_jit(x, uv, c0), jac_x(x, uv, c0), jac_c(x, uv, c0)
    for a in (f0, jx0, jc0):
        assert np.isfinite(a).all()
    scale_f, scale_j = (KN + KT) * speed**2, (KN + KT) * speed
    for sign in (1.0, -1.0):
        c = c0 + sign * 1e-7 * speed * wobble
        np.testing.assert_allclose(netting_jit(x, uv, c), f0, atol=1e-6 * scale_f, rtol=0)
        np.testing.assert_allclose(jac_x(x, uv, c), jx0, atol=1e-5 * scale_j / 0.02, rtol=0)
        np.testing.assert_allclose(jac_c(x, uv, c), jc0, atol=1e-5 * scale_j, rtol=0)
    parts = netting_parts(x, uv, c0)
    if case in ("along_u", "against_u"):
        # all of the U twines' drag is tangential: Ct-drag along c, |d|/2 = 1/2 twine
        np.testing.assert_allclose(parts["u_normal"], 0.0, atol=1e-30)
        np.testing.assert_allclose(parts["u_tangential"], 0.5 * KT * speed * c0, rtol=1e-13)
    if case == "normal_to_u":
        np.testing.assert_allclose(parts["u_tangential"], 0.0, atol=1e-30)
        np.testing.assert_allclose(parts["u_normal"], 0.5 * KN * speed * c0, rtol=1e-13)
    if case == "still_water":
        np.testing.assert_array_equal(f0, 0.0)
        np.testing.assert_array_equal(jx0, 0.0)
        np.testing.assert_array_equal(jc0, 0.0)


def test_collapsed_element_is_finite():
    # a triangle shrunk to a point has no twine direction: all the velocity counts as normal, no NaN
    x = jnp.ones((3, 3)) * 0.4
    uv = jnp.array([[0.0, 0.0], [2.0, 0.0], [0.0, 3.0]])
    c = jnp.array([0.2, -0.5, 0.1])
    expected = 2 * 3.0 * KN * jnp.linalg.norm(c) * c  # |d| = 6: 3 U and 3 V twines
    np.testing.assert_allclose(netting_jit(x, uv, c).sum(0), expected, rtol=1e-13)
    assert np.isfinite(jac_x(x, uv, c)).all() and np.isfinite(jac_c(x, uv, c)).all()


@pytest.mark.parametrize("clockwise", [False, True])
def test_stiffness_equals_finite_differences(clockwise, rng):
    for _ in range(6):
        x, uv = random_element(rng, clockwise)
        c = jnp.asarray(rng.normal(size=3))
        jx = np.asarray(jac_x(x, uv, c)).reshape(9, 9)
        fd = central_differences(lambda y: netting_jit(y.reshape(3, 3), uv, c).ravel(), x.ravel(), 1e-7)
        np.testing.assert_allclose(jx, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
        jc = np.asarray(jac_c(x, uv, c)).reshape(9, 3)
        fdc = central_differences(lambda w: netting_jit(x, uv, w).ravel(), c, 1e-6)
        np.testing.assert_allclose(jc, fdc, rtol=1e-6, atol=1e-8 * np.abs(fdc).max())


def book_directions(U, c):
    """Unit directions of the normal and tangential drag as printed, 4.116-4.117 (non-degenerate cases)."""
    E = jnp.cross(U, jnp.cross(c, U))
    T = jnp.cross(E, jnp.cross(c, E))
    return E / jnp.linalg.norm(E), T / jnp.linalg.norm(T)


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize("alpha_deg", [17.0, 60.0, 110.0, 163.0])
def test_twine_at_an_angle_matches_book_4114_4117(alpha_deg, clockwise, rng):
    # U twines at angle alpha to c: |F| = ½ρ Cd D l0 (|c| sin a)² |d|/2, |T| = f ½ρ Cd D l0 (|c| cos a)² |d|/2
    # (Ct = f Cd), directions 4.116-4.117; the V twines alike with beta
    R = random_rotation(rng)
    uv = jnp.array([[0.0, 0.0], [3.0, 0.0], [0.0, 2.0]])
    if clockwise:
        uv = uv[jnp.array([0, 2, 1])]
    n = abs(float(geometry.twine_determinant(uv))) / 2
    assert n == 3.0
    U = R @ jnp.array([0.022, 0.0, 0.0])
    V = R @ jnp.array([0.01, 0.015, 0.004])
    x = jnp.array([0.1, 0.2, -3.0]) + uv[:, :1] * U + uv[:, 1:] * V
    a = np.radians(alpha_deg)
    speed = 0.9
    c = speed * (R @ jnp.array([np.cos(a), np.sin(a) * 0.6, np.sin(a) * 0.8]))
    parts = netting_parts(x, uv, c)
    f = netting_jit(x, uv, c)
    total = jnp.zeros(3)
    for name, twine in (("u", U), ("v", V)):
        cos_a = jnp.dot(c, twine) / (speed * jnp.linalg.norm(twine))  # 4.132 / 4.135
        assert 1e-3 < abs(float(cos_a)) < 0.999  # neither along nor across c: the book's forms are defined
        sin_a = jnp.sqrt(1 - cos_a**2)
        normal, tangential = parts[name + "_normal"], parts[name + "_tangential"]
        np.testing.assert_allclose(jnp.linalg.norm(normal), KN * (speed * sin_a) ** 2 * n, rtol=1e-12)
        np.testing.assert_allclose(jnp.linalg.norm(tangential), KT * (speed * cos_a) ** 2 * n, rtol=1e-12)
        e_normal, e_tangential = book_directions(twine, c)
        np.testing.assert_allclose(normal / jnp.linalg.norm(normal), e_normal, atol=1e-12)
        np.testing.assert_allclose(tangential / jnp.linalg.norm(tangential), e_tangential, atol=1e-12)
        total = total + normal + tangential
    np.testing.assert_allclose(f, jnp.broadcast_to(total / 3, (3, 3)), rtol=1e-13)


def bar(x, rest, c):
    return drag.bar_drag(x, rest, D, CN, CT, c, RHO)


bar_jit = jax.jit(bar)


@pytest.mark.parametrize("alpha_deg", [0.0, 35.0, 90.0, 140.0])
def test_bar_drag_closed_form(alpha_deg):
    # Morison on a cylinder of rest length L0: ½ρ Cn D L0 (c sin a)² across, ½ρ Ct D L0 (c cos a)² along,
    # half per end; the current length of the bar does not enter
    a = np.radians(alpha_deg)
    rest, speed = 2.5, 1.4
    axis = jnp.array([np.cos(a), np.sin(a), 0.0])
    c = speed * jnp.array([1.0, 0.0, 0.0])
    for stretch in (1.0, 1.08):
        x = jnp.stack([jnp.array([1.0, 2.0, -4.0]), jnp.array([1.0, 2.0, -4.0]) + stretch * rest * axis])
        f = bar_jit(x, rest, c)
        np.testing.assert_array_equal(f[0], f[1])
        k = 0.5 * RHO * D * rest * speed**2
        normal_dir = np.array([1.0, 0.0, 0.0]) - np.cos(a) * np.asarray(axis)
        normal_dir = normal_dir / (np.linalg.norm(normal_dir) or 1.0)
        expected = CN * k * np.sin(a) ** 2 * normal_dir + CT * k * np.cos(a) * abs(np.cos(a)) * np.asarray(axis)
        np.testing.assert_allclose(2 * f[0], expected, rtol=1e-12, atol=1e-15)


def test_bar_stiffness_equals_finite_differences(rng):
    jx = jax.jit(jax.jacfwd(bar, argnums=0))
    jc = jax.jit(jax.jacfwd(bar, argnums=2))
    for _ in range(6):
        x, c, rest = jnp.asarray(rng.normal(size=(2, 3))), jnp.asarray(rng.normal(size=3)), 0.7
        fd = central_differences(lambda y: bar_jit(y.reshape(2, 3), rest, c).ravel(), x.ravel(), 1e-7)
        got = np.asarray(jx(x, rest, c)).reshape(6, 6)
        np.testing.assert_allclose(got, fd, rtol=1e-5, atol=1e-7 * np.abs(fd).max())
        fdc = central_differences(lambda w: bar_jit(x, rest, w).ravel(), c, 1e-6)
        got = np.asarray(jc(x, rest, c)).reshape(6, 3)
        np.testing.assert_allclose(got, fdc, rtol=1e-6, atol=1e-8 * np.abs(fdc).max())
    # along the bar and in still water the stiffness is finite
    x = jnp.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    for c in (jnp.array([0.5, 0.0, 0.0]), jnp.array([0.0, 0.5, 0.0]), jnp.zeros(3)):
        assert np.isfinite(jx(x, 1.0, c)).all() and np.isfinite(jc(x, 1.0, c)).all()


def test_node_drag_closed_form():
    cda = 0.35  # Cd A (m²)
    c = jnp.array([0.6, -0.8, 0.0]) * 1.5
    np.testing.assert_allclose(drag.node_drag(cda, c, RHO), 0.5 * RHO * cda * 1.5 * c, rtol=1e-14)
    # d(|c| c)/dc = |c| I + c c^T / |c|, and 0 in still water
    jac = jax.jacfwd(drag.node_drag, argnums=1)
    expected = 0.5 * RHO * cda * (1.5 * np.eye(3) + np.outer(c, c) / 1.5)
    np.testing.assert_allclose(jac(cda, c, RHO), expected, rtol=1e-13)
    np.testing.assert_array_equal(jac(cda, jnp.zeros(3), RHO), 0.0)
    np.testing.assert_array_equal(drag.node_drag(cda, jnp.zeros(3), RHO), 0.0)


def test_rotating_element_and_current_rotates_the_forces(rng):
    for clockwise in (False, True):
        for _ in range(3):
            x, uv = random_element(rng, clockwise)
            c = jnp.asarray(rng.normal(size=3))
            R = random_rotation(rng)
            shift = jnp.asarray(rng.normal(size=3))
            moved = netting_jit(x @ R.T + shift, uv, R @ c)
            np.testing.assert_allclose(moved, netting_jit(x, uv, c) @ R.T, rtol=1e-11, atol=1e-16)
            moved = bar_jit(x[:2] @ R.T + shift, 0.3, R @ c)
            np.testing.assert_allclose(moved, bar_jit(x[:2], 0.3, c) @ R.T, rtol=1e-11, atol=1e-16)


PROFILE_DEPTH = jnp.array([0.0, 10.0, 30.0])
PROFILE_FACTOR = jnp.array([1.0, 0.8, 0.2])


def sheared(z, surface=0.0, speed=1.2, direction=jnp.array([3.0, 4.0, 0.0])):
    return current.current_velocity(z, speed, direction, PROFILE_DEPTH, PROFILE_FACTOR, surface)


sheared_jit, sheared_dz = jax.jit(sheared), jax.jit(jax.jacfwd(sheared))


@pytest.mark.parametrize(
    "depth, factor, slope",  # slope: d factor / d depth (1/m)
    [
        (-2.0, 1.0, 0.0),  # above the surface: first point's factor
        (0.0, 1.0, -0.02),
        (4.0, 0.92, -0.02),
        (10.0, 0.8, -0.03),  # interior point: deeper segment's slope
        (25.0, 0.35, -0.03),
        (30.0, 0.2, -0.03),
        (55.0, 0.2, 0.0),  # below the last point: constant
    ],
)
def test_current_profile(depth, factor, slope):
    speed, surface = 1.2, 2.5
    z = surface - depth
    unit = np.array([0.6, 0.8, 0.0])
    np.testing.assert_allclose(sheared_jit(z, surface), speed * factor * unit, rtol=1e-13, atol=1e-15)
    # z up: d c / dz = - d c / d depth
    np.testing.assert_allclose(sheared_dz(z, surface), -speed * slope * unit, rtol=1e-13, atol=1e-15)


def test_current_without_profile_and_with_one_point():
    south = jnp.array([0.0, -2.0, 0.0])  # not unit: normalised inside
    empty = jnp.zeros((0,))
    uniform = jax.jit(lambda z: current.current_velocity(z, 0.7, south, empty, empty))
    scaled = jax.jit(lambda z: current.current_velocity(z, 0.7, south, jnp.array([5.0]), jnp.array([0.5])))
    for z in (3.0, -40.0):
        np.testing.assert_allclose(uniform(z), [0.0, -0.7, 0.0], rtol=1e-15)
        np.testing.assert_allclose(scaled(z), [0.0, -0.35, 0.0], rtol=1e-15)
        assert float(jnp.abs(jax.jacfwd(uniform)(z)).max()) == 0.0
    # vectorised in z
    east = jnp.array([1.0, 0.0, 0.0])
    got = sheared_jit(jnp.array([0.0, -5.0, -20.0]), 0.0, 1.0, east)
    np.testing.assert_allclose(got[:, 0], [1.0, 0.9, 0.5], rtol=1e-14)
    # a scene without free surface (surface_level NaN) measures depth from z = 0, and stays finite
    got = sheared_jit(jnp.array([-5.0, -20.0]), jnp.nan, 1.0, east)
    np.testing.assert_allclose(got[:, 0], [0.9, 0.5], rtol=1e-14)
    np.testing.assert_allclose(sheared_dz(-5.0, jnp.nan, 1.0, east)[0], 0.02, rtol=1e-14)


def test_drag_in_a_sheared_current_sees_dc_dz(rng):
    # with the current evaluated at the element's centroid inside the differentiated function, the stiffness
    # includes d c/d z: compare with finite differences of the composed force
    x, uv = random_element(rng)
    x = x + jnp.array([0.0, 0.0, -5.0])
    force = jax.jit(lambda y: netting(y, uv, sheared(geometry.centroid(y)[2])))
    jx = np.asarray(jax.jit(jax.jacfwd(force))(x)).reshape(9, 9)
    fd = central_differences(lambda y: force(y.reshape(3, 3)).ravel(), x.ravel(), 1e-7)
    np.testing.assert_allclose(jx, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
    # the difference from a uniform current of the same local velocity is (dF/dc)(dc/dz)(dz_centroid/dz_j)
    z = geometry.centroid(x)[2]
    uniform = np.asarray(jac_x(x, uv, sheared_jit(z))).reshape(9, 9)
    shear = np.asarray(jac_c(x, uv, sheared_jit(z))).reshape(9, 3) @ np.asarray(sheared_dz(z)) / 3.0
    assert np.abs(shear).max() > 1e-4 * np.abs(uniform).max()
    expected = uniform.copy()
    expected[:, 2::3] += shear[:, None]
    np.testing.assert_allclose(jx, expected, rtol=1e-12, atol=1e-14)


# ----------------------------------------------------------------------------------------------------
# FEMNET's drag of netting ahead of a catch (trainee_fil): netting_drag_femnet_catch, model code 3


def femnet_catch(x, uv, c):
    return drag.netting_drag_femnet_catch(x, uv, L0, D, CN, CT, c, RHO)


femnet_catch_jit = jax.jit(femnet_catch)
femnet_jac_x = jax.jit(jax.jacfwd(femnet_catch, argnums=0))
femnet_jac_c = jax.jit(jax.jacfwd(femnet_catch, argnums=2))


def twine_pair_element(U, V, clockwise=False):
    """Element whose U and V twine vectors are exactly U and V, |d| = 1 (half a U and half a V twine)."""
    uv = jnp.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    if clockwise:  # d = -1: vertex 2 is then at V, vertex 3 at U; same twine vectors
        uv = uv[jnp.array([0, 2, 1])]
    x = jnp.array([0.1, 0.2, -3.0]) + uv[:, :1] * U + uv[:, 1:] * V
    U_, V_, d = geometry.twine_vectors(x, uv)
    np.testing.assert_allclose(U_, U, atol=1e-15)
    np.testing.assert_allclose(V_, V, atol=1e-15)
    assert abs(d) == 1.0 and (d < 0) == clockwise
    return x, uv


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize("a_deg, b_deg, v_upstream", [(30.0, 50.0, False), (30.0, 50.0, True), (70.0, 20.0, True)])
def test_femnet_catch_closed_form(a_deg, b_deg, v_upstream, clockwise):
    # c = |c| x; U = l (cos a, sin a, 0) in the xy plane (ê_U = y), V = l (±cos b, 0, sin b) in the xz
    # plane (ê_V = z). Per twine (k = |c|²): along x  K_n sin³ + K_t cos³ for each twine; across, U gives
    # k cos a sin a (K_t cos a - K_n sin a) along ê_U, V gives ±k cos b sin b (K_t cos b - K_n sin b)
    # along ê_V (+ downstream V, - upstream V). FEMNET sends U's part along ê_V: F_y = 0.
    a, b, speed, l = np.radians(a_deg), np.radians(b_deg), 1.7, 0.03
    sv = -1.0 if v_upstream else 1.0
    U = l * jnp.array([np.cos(a), np.sin(a), 0.0])
    V = l * jnp.array([sv * np.cos(b), 0.0, np.sin(b)])
    x, uv = twine_pair_element(U, V, clockwise)
    c = jnp.array([speed, 0.0, 0.0])
    k = speed**2
    along = k * (KN * (np.sin(a)**3 + np.sin(b)**3) + KT * (np.cos(a)**3 + np.cos(b)**3))
    across_u = k * np.cos(a) * np.sin(a) * (KT * np.cos(a) - KN * np.sin(a))
    across_v = sv * k * np.cos(b) * np.sin(b) * (KT * np.cos(b) - KN * np.sin(b))
    per_vertex = 0.5 / 3.0  # |d|/2 twines of each kind, one third per vertex
    f = np.asarray(femnet_catch_jit(x, uv, c))
    np.testing.assert_allclose(f, np.broadcast_to(per_vertex * np.array([along, 0.0, across_u + across_v]), (3, 3)),
                               rtol=1e-12, atol=1e-15 * k * KN)
    # the exact twine drag has the same x part but U's cross part along y where it belongs
    exact = np.asarray(netting_jit(x, uv, c))
    np.testing.assert_allclose(exact, np.broadcast_to(per_vertex * np.array([along, across_u, across_v]), (3, 3)),
                               rtol=1e-12, atol=1e-15 * k * KN)
    assert abs(across_u) > 1e-3 * along  # so that the two forms do differ


def test_femnet_catch_cod_end_twines_lose_the_cross_flow():
    # a cod-end panel at 25° to the current, meshed along its axis as FEMNET does (u = U + V, v = V - U):
    # U runs downstream, V upstream, each at 35° to the axis. FEMNET's form keeps only the drag along c;
    # the exact form has the panel's lift (along the normal's component across c), of the same order
    tilt, half = np.radians(25.0), np.radians(35.0)
    axis = np.array([np.cos(tilt), 0.0, np.sin(tilt)])  # in the panel, the panel's normal in the xz plane
    around = np.array([0.0, 1.0, 0.0])
    l = 0.05
    U = jnp.asarray(l * (np.cos(half) * axis + np.sin(half) * around))
    V = jnp.asarray(l * (-np.cos(half) * axis + np.sin(half) * around))
    x, uv = twine_pair_element(U, V)
    c = jnp.array([1.9, 0.0, 0.0])
    f, exact = np.asarray(femnet_catch_jit(x, uv, c)).sum(0), np.asarray(netting_jit(x, uv, c)).sum(0)
    np.testing.assert_allclose(f[0], exact[0], rtol=1e-13)
    np.testing.assert_allclose(f[1:], 0.0, atol=1e-14 * f[0])
    assert np.abs(exact[1]) < 1e-14 * exact[0] and abs(exact[2]) > 0.1 * exact[0]


def test_femnet_catch_along_the_current_and_frame(rng):
    # random elements and currents: the part along c is the exact drag's; only the cross part differs, by U's cross
    # part turned from ê_U onto ê_V (the docstring's form: (F_U.ê_U)(ê_V - ê_U), a third per vertex); the form is
    # a vector function of the element and c (turning both turns the force)
    differs = 0
    for clockwise in (False, True):
        for _ in range(4):
            x, uv = random_element(rng, clockwise)
            c = jnp.asarray(rng.normal(size=3))
            f, exact = femnet_catch_jit(x, uv, c), netting_jit(x, uv, c)
            np.testing.assert_allclose(f @ c, exact @ c, rtol=1e-12, atol=1e-14 * np.abs(exact).max())
            U, V, _ = geometry.twine_vectors(x, uv)
            parts = netting_parts(x, uv, c)
            e_c = np.asarray(c) / np.linalg.norm(c)
            across = [np.asarray(w) - (np.asarray(w) @ e_c) * e_c for w in (U, V)]
            e_u, e_v = (a / np.linalg.norm(a) for a in across)
            moved = np.asarray(parts["u_normal"] + parts["u_tangential"]) @ e_u * (e_v - e_u) / 3.0
            np.testing.assert_allclose(f - exact, np.broadcast_to(moved, (3, 3)), atol=1e-12 * np.abs(exact).max())
            differs += np.abs(f - exact).max() > 1e-3 * np.abs(exact).max()
            R = random_rotation(rng)
            np.testing.assert_allclose(femnet_catch_jit(x @ R.T, uv, R @ c), f @ R.T, rtol=1e-11,
                                       atol=1e-13 * np.abs(f).max())
    # and the forms do differ: that difference vanishes only as U turns normal to c (or along it) or ê_V turns onto
    # ê_U, below 1e-3 of the drag on 1.5 % of random draws (400 drawn): most of the 8, not every one, differ
    assert differs >= 4


@pytest.mark.parametrize("clockwise", [False, True])
def test_femnet_catch_stiffness_equals_finite_differences(clockwise, rng):
    for _ in range(4):
        x, uv = random_element(rng, clockwise)
        c = jnp.asarray(rng.normal(size=3))
        jx = np.asarray(femnet_jac_x(x, uv, c)).reshape(9, 9)
        fd = central_differences(lambda y: femnet_catch_jit(y.reshape(3, 3), uv, c).ravel(), x.ravel(), 1e-7)
        np.testing.assert_allclose(jx, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
        jc = np.asarray(femnet_jac_c(x, uv, c)).reshape(9, 3)
        fdc = central_differences(lambda w: femnet_catch_jit(x, uv, w).ravel(), c, 1e-6)
        np.testing.assert_allclose(jc, fdc, rtol=1e-6, atol=1e-8 * np.abs(fdc).max())


@pytest.mark.parametrize("case", ["u_along_c", "v_along_c", "v_against_c", "still_water", "collapsed"])
def test_femnet_catch_degenerate_cases_are_finite(case):
    l, speed = 0.04, 1.1
    U, V = l * jnp.array([0.6, 0.8, 0.0]), l * jnp.array([0.6, 0.0, 0.8])
    c = speed * jnp.array([1.0, 0.0, 0.0])
    if case == "u_along_c":
        U = l * jnp.array([1.0, 0.0, 0.0])
    if case in ("v_along_c", "v_against_c"):
        V = l * jnp.array([1.0 if case == "v_along_c" else -1.0, 0.0, 0.0])
    if case == "still_water":
        c = jnp.zeros(3)
    x, uv = twine_pair_element(U, V)
    if case == "collapsed":
        x = jnp.ones((3, 3)) * 0.4
    f, jx, jc = femnet_catch_jit(x, uv, c), femnet_jac_x(x, uv, c), femnet_jac_c(x, uv, c)
    for a in (f, jx, jc):
        assert np.isfinite(a).all()
    exact = netting_jit(x, uv, c)
    if case in ("u_along_c", "collapsed", "still_water"):
        # U's drag has no cross part (or there is no drag): the two forms agree
        np.testing.assert_allclose(f, exact, rtol=1e-13, atol=1e-30)
    if case in ("v_along_c", "v_against_c"):
        # ê_V has no direction: U's cross part is dropped, its part along c kept. U at cos a = 0.6 to c:
        # along c, K_n sin³a + K_t cos³a per twine; V all tangential, K_t; |d|/2 = 1/2 twine of each
        expected = 0.5 * speed**2 * (KT + KN * 0.8**3 + KT * 0.6**3) * jnp.array([1.0, 0.0, 0.0])
        np.testing.assert_allclose(f.sum(0), expected, rtol=1e-12, atol=1e-16)
    if case == "still_water":
        np.testing.assert_array_equal(jx, 0.0)
        np.testing.assert_array_equal(jc, 0.0)


def test_model_code_3_is_femnet_catch(rng):
    # the term passes code 3 Ct = f Cd, as the twine drag (code 0)
    from types import SimpleNamespace

    from jaxnet.terms import drag as drag_term

    x, uv = random_element(rng)
    c = jnp.asarray(rng.normal(size=3))
    p = SimpleNamespace(uv=uv, l0=L0, diameter=D, cd_normal=CN, tangential_ratio=CT / CN, drag_model=3)
    model = drag_term.NETTING_DRAG_MODELS[3]
    assert model.scope == "femnet_catch_drag" and model.twines
    a = drag_term.NETTING_DRAG.arguments(p, SimpleNamespace(water_density=RHO), models=(3,), shielded=False)
    force = model.force(x, a["uv"], a["l0"], a["diameter"], a["cd_normal"], a["cd_tangential"], c, RHO)
    np.testing.assert_allclose(force, femnet_catch_jit(x, uv, c), rtol=1e-13)


# -- at a free surface: the water drags only what is in it ----------------------------------------------------


def _surface_env(level=0.3):
    from jaxnet.scene import Environment

    return Environment(current_speed=1.2, current_direction=np.array([1.0, 0.0, 0.0]), surface_level=level)


@pytest.mark.parametrize("h_over_d", [-3.0, -0.5, -0.2, 0.0, 0.35, 0.5, 2.0])
def test_a_horizontal_bar_at_the_surface_is_dragged_by_its_immersed_part(h_over_d):
    # A horizontal pipe (a collar) across the current, its axis h above the water plane: each end's half of the
    # drag is that of the area it shows the flow under water, its wetted depth D/2 - h over D: all of it from
    # h = -3D/4 down, exactly half with its axis on the surface, none from h = 3D/4 up; the ramp's corners
    # rounded over D/4 on either side of h = ∓D/2 by the parabolas tangent to both sides (1 - e/4 and e/4 at
    # the corners, e = 1/4; (0.35 - 0.75)² = 0.16 at h = 0.35 D).
    env, diameter, rest = _surface_env(), 0.25, 3.0
    h = h_over_d * diameter
    x = jnp.array([[0.0, 0.0, 0.3 + h], [0.0, rest, 0.3 + h]])
    deep = drag.bar_drag_on_element(x - jnp.array([0.0, 0.0, 5.0]), None, rest, diameter, 1.0, 0.1, env)
    wet = drag.bar_drag_on_element(x, None, rest, diameter, 1.0, 0.1, env, wetted=True)
    share = {-3.0: 1.0, -0.5: 1.0 - 1.0 / 16.0, -0.2: 0.7, 0.0: 0.5, 0.35: 0.16, 0.5: 1.0 / 16.0, 2.0: 0.0}[h_over_d]
    np.testing.assert_allclose(wet, share * np.asarray(deep), rtol=1e-14, atol=1e-14 * float(np.abs(deep).max()))
    assert float(np.abs(deep).max()) > 1.0  # ½ ρ Cd D L c² / 2 = 138 N at each end


def test_the_wetted_share_is_smooth_and_keeps_the_ramps_integral():
    # C¹ (its slope, the closed form's, is the derivative of the share and continuous across the corners), within
    # e/4 of the ramp clip(1/2 - h/D, 0, 1), and of the same integral over the heights (the corners' differences
    # cancel): the drag of a body summed over the heights of its axis is the ramp's
    env, band = _surface_env(0.0), 0.1
    h = np.linspace(-0.1, 0.1, 40001)
    x = jnp.asarray(np.stack([np.zeros_like(h), np.zeros_like(h), h], axis=1))
    share, slope = np.asarray(drag.wetted_shares(x, band, env)), np.asarray(drag.wetted_shares_slope(x, band, env))
    ramp = np.clip(0.5 - h / band, 0.0, 1.0)
    assert np.abs(share - ramp).max() == pytest.approx(drag.WETTED_ROUNDING / 4.0, rel=1e-6)
    np.testing.assert_allclose(np.trapezoid(share - ramp, h), 0.0, atol=1e-10)
    np.testing.assert_allclose(np.gradient(share, h)[1:-1], slope[1:-1], atol=1e-4 / band)
    assert np.abs(np.diff(slope)).max() < 1e-3 / band  # no jump anywhere


def test_netting_and_bodies_at_the_surface_keep_the_drag_of_their_immersed_vertices(rng):
    # a triangle with a vertex deep, one on the water plane and one high above it: its vertices keep 1, 1/2 and 0
    # of their thirds; a float of size 0.1 m on the plane half its drag
    env = _surface_env()
    x, uv = random_element(rng)
    x = x.at[:, 2].set(jnp.array([-1.0, 0.3, 1.5]))
    args = dict(uv=uv, l0=L0, diameter=D, cd_normal=jnp.asarray(CN), cd_tangential=jnp.asarray(CT),
                drag_model=jnp.asarray(0), env=env, models=(0,), shielded=False)
    dry = drag.netting_drag_on_element(x, None, **args)
    wet = drag.netting_drag_on_element(x, None, **args, wetted=True)
    np.testing.assert_allclose(wet, np.asarray(dry) * np.array([1.0, 0.5, 0.0])[:, None], rtol=1e-14, atol=1e-18)
    assert float(np.abs(dry).min()) > 0.0
    node = jnp.array([[2.0, 1.0, 0.3]])
    body = drag.node_drag_on_element(node, None, 0.02, env)
    np.testing.assert_allclose(drag.node_drag_on_element(node, None, 0.02, env, wetted=True, band=0.1),
                               0.5 * np.asarray(body), rtol=1e-14)


def test_the_wetted_bar_drag_stiffness_is_its_derivative_across_the_surface(rng):
    # ends inside the pipe's band, where the share changes with height: autodiff and the closed form's product
    # rule against central differences of the force
    from jaxnet.closed_form.drag_elements import bar_drag_on_element_stiffness

    env, diameter, rest = _surface_env(), 0.25, 2.0
    force = jax.jit(lambda y: drag.bar_drag_on_element(y, None, rest, diameter, 1.0, 0.1, env, wetted=True))
    for _ in range(4):
        x = jnp.array([[0.0, 0.0, 0.3], [0.3, 1.9, 0.3]]) + jnp.asarray(rng.uniform(-0.1, 0.1, size=(2, 3)))
        fd = central_differences(lambda y: force(y.reshape(2, 3)).ravel(), x.ravel(), 1e-6)
        auto = np.asarray(jax.jacfwd(force)(x)).reshape(6, 6)
        closed = np.asarray(bar_drag_on_element_stiffness(x, None, rest, diameter, 1.0, 0.1, env, wetted=True))
        np.testing.assert_allclose(auto, fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())
        np.testing.assert_allclose(-closed, auto, rtol=1e-12, atol=1e-12 * np.abs(fd).max())
        # the height's share is part of it: a column along z that the dry drag does not have
        dry = np.asarray(jax.jacfwd(lambda y: drag.bar_drag_on_element(y, None, rest, diameter, 1.0, 0.1, env))(x))
        assert np.abs(auto - dry.reshape(6, 6)).max() > 1e-3 * np.abs(auto).max()


@pytest.mark.parametrize("models", [(0,), (0, 3)])
def test_the_wetted_netting_stiffness_behind_a_catch_front_is_its_derivative(models, rng):
    # both product rules at once: a triangle cut by a catch front (its part behind it shielded) with two vertices
    # inside the twines' band at the surface; the closed form (the drag from its own intermediate values) against
    # autodiff, and autodiff against central differences
    from jaxnet.closed_form.drag_elements import netting_drag_on_element_stiffness
    from jaxnet.terms import pressure

    env = _surface_env(0.3)
    x, uv = random_element(rng)
    x = x.at[:, 2].set(jnp.array([0.3 + 3e-4, 0.3 - 4e-4, 0.28]))
    axis = jnp.array([1.0, 0.0, 0.0])
    state = {"front": jnp.median(x @ axis), "axis": axis}
    args = dict(uv=uv, l0=L0, diameter=D, cd_normal=jnp.asarray(CN), cd_tangential=jnp.asarray(CT),
                drag_model=jnp.asarray(models[-1]), env=env, models=models, shielded=True, wetted=True)
    force = jax.jit(lambda y: drag.netting_drag_on_element(y, state, **args))
    auto = np.asarray(jax.jacfwd(force)(x)).reshape(9, 9)
    closed = np.asarray(netting_drag_on_element_stiffness(x, state, **args))
    # Richardson-extrapolated, 2 D(h/2) - D(h): moving the vertex on the front along the axis, the shielded share is
    # C1 with a jump of its second derivative (as the catch pressure, tests/terms/test_pressure.py), which leaves an
    # error h/4 times that jump in D(h): over the tolerance on 1 random element in 40, gone once extrapolated
    force_of = lambda y: force(y.reshape(3, 3)).ravel()  # noqa: E731
    fd = 2 * central_differences(force_of, x.ravel(), 5e-9) - central_differences(force_of, x.ravel(), 1e-8)
    np.testing.assert_allclose(auto, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
    np.testing.assert_allclose(-closed, auto, rtol=1e-10, atol=1e-12 * np.abs(auto).max())
    # the wetted shares and the front both act: vertices 0 and 1 in the band, partly wet; the front through the
    # median vertex, part of the triangle behind it. (Not "vertex 0 keeps less drag than vertex 2": true of the
    # shares, not of the force when vertex 2 is the one behind the front, as for some random elements.)
    shares = np.asarray(drag.wetted_shares(x, D, env))
    behind = np.asarray(pressure.clipped_shape_integrals(pressure.front_heights(x, state["front"], axis)))
    assert np.all((0.0 < shares[:2]) & (shares[:2] < 1.0)) and shares[2] == 1.0 and 0.0 < behind.sum() < 1.0
    assert np.abs(np.asarray(force(x))).max() > 0.0
