"""Closed-form twine tension stiffness against autodiff, and the book's printed equations 4.30-4.113.

Part 1: :mod:`jaxnet.closed_form.tension` (``netting_stiffness``, ``bar_stiffness``, ``rod_stiffness``) is an
independent hand derivation of K = -dF/dx (4.46); here it is compared with ``jax.jacfwd(jax.grad(.))`` of
the energies of :mod:`jaxnet.terms.tension` and :mod:`jaxnet.terms.cable` on random well-conditioned
elements (``tests/elements.py``) and on the hard cases (clockwise triangles, a twine exactly at its rest
length, a collapsed twine, very stretched twines, EA = 1e9 N), and checked for symmetry and rigid motions.

Part 2 (errata): every equation of 4.30-4.113 whose printed form can be evaluated is transcribed as
``book_4_NN`` and compared, on a seeded random element, with the mathematics (autodiff, the exact knot
solve of :mod:`jaxnet.terms.hexagonal`, or an identity); each test asserts agreement or the size of the
documented disagreement (the rows of docs/errata.md for 4.30-4.113).

Conventions: forces are the forces ON the vertices (-grad E), K = -dF/dx, vertex-major (9, 9) layout
(entry (3 i + m, 3 j + n)), SI units (m, N).
"""

import functools

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from elements import L0, positions, random_triangles, random_twine_pair, relative_difference
from jaxnet import geometry
from jaxnet.closed_form import tension as closed
from jaxnet.terms import cable, tension
from jaxnet.terms import hexagonal as hx

EA = 1500.0  # twine traction stiffness (N)
EA_C = 300.0  # compression stiffness (N), when the twines can push
OPTIONS = [None, EA_C]
TOLERANCE = 1e-10  # closed form vs autodiff: max |difference| / max |autodiff entry|, per element


# -- the two paths, vmapped and jitted once per compression option ----------------------------------


BATCH = 192  # every batch is padded to this size: one compilation per compression option


@functools.cache
def _netting_pair(ea_c):
    def one(x, uv, l0, ea):
        auto = jax.jacfwd(jax.grad(tension.netting_energy))(x, uv, l0, ea, ea_c).reshape(9, 9)
        return auto, closed.netting_stiffness(x, uv, l0, ea, ea_c)

    return jax.jit(jax.vmap(one, in_axes=(0, 0, None, None)))


def netting_pair(ea_c):
    """(autodiff K, closed-form K), each (n, 9, 9), for batches x (n, 3, 3), uv (n, 3, 2); l0, ea scalars."""

    def run(x, uv, l0, ea):
        n = len(x)
        pad = np.arange(BATCH) % n
        auto, hand = _netting_pair(ea_c)(np.asarray(x)[pad], np.asarray(uv)[pad], float(l0), float(ea))
        return np.asarray(auto)[:n], np.asarray(hand)[:n]

    return run


@functools.cache
def bar_pair(ea_c):
    def one(x, rest, ea):
        auto = jax.jacfwd(jax.grad(cable.bar_energy))(x, rest, ea, ea_c).reshape(6, 6)
        return auto, closed.bar_stiffness(x, rest, ea, ea_c)

    return jax.jit(jax.vmap(one, in_axes=(0, 0, None)))


rod_stiffness = jax.jit(closed.rod_stiffness, static_argnames="ea_compression")


def assert_paths_agree(auto, hand, tolerance=TOLERANCE):
    """Per element: relative difference <= tolerance; where autodiff is exactly 0 the closed form is too.

    Returns the number of elements whose autodiff matrix is exactly zero (skipped from the ratio).
    """
    auto, hand = np.asarray(auto), np.asarray(hand)
    assert np.all(np.isfinite(hand))
    zero = 0
    for k, (a, h) in enumerate(zip(auto, hand)):
        if np.all(a == 0.0):
            zero += 1
            assert np.all(h == 0.0), f"element {k}: autodiff is exactly 0, closed form is not"
        else:
            assert relative_difference(h, a) <= tolerance, f"element {k}: {relative_difference(h, a):.2e}"
    return zero


def sides(uv):
    return uv[:, 0], uv[:, 1]


@functools.cache
def _force(ea_c):
    return jax.jit(lambda x, uv, l0, ea: -jax.grad(tension.netting_energy)(x, uv, l0, ea, ea_c))


def true_force(x, uv, l0, ea, ea_c=None):
    """Force on the vertices (N), (3, 3): -grad of the element energy."""
    return np.asarray(_force(ea_c)(jnp.asarray(x), jnp.asarray(uv), float(l0), float(ea)))


# -- part 1: closed form vs autodiff ------------------------------------------------------------------


@pytest.mark.parametrize("ea_c", OPTIONS)
def test_netting_stiffness_equals_autodiff_on_random_triangles(ea_c):
    # 128 triangles (half clockwise) stretched -5 % .. +20 %, and 64 half-slack ones (-10 % .. +10 %):
    # without compression stiffness some of those have both families slack, K exactly 0 on both paths
    x, uv = random_triangles(128, seed=11)
    xs, uvs = random_triangles(64, seed=12, stretch=(-0.1, 0.1))
    x, uv = np.concatenate([x, xs]), np.concatenate([uv, uvs])
    assert np.sum(geometry.twine_determinant(uv) < 0) == 96
    zero = assert_paths_agree(*netting_pair(ea_c)(x, uv, L0, EA))
    if ea_c is None:
        assert 0 < zero < 40  # the slack branch is exercised, and most elements are not slack
    else:
        assert zero == 0


@pytest.mark.parametrize("ea_c", OPTIONS)
def test_netting_stiffness_equals_autodiff_when_very_stretched_and_very_stiff(ea_c):
    # twines at 2 to 4 times their rest length (geometric part T/L as large as the axial one), EA = 1e9 N
    x, uv = random_triangles(32, seed=13, stretch=(1.0, 3.0))
    for ea in (EA, 1e9):
        assert assert_paths_agree(*netting_pair(ea_c)(x, uv, L0, ea)) == 0


@pytest.mark.parametrize("ea_c", OPTIONS)
def test_bar_stiffness_equals_autodiff(ea_c):
    rng = np.random.default_rng(14)
    n = 100
    rest = rng.uniform(0.1, 2.0, size=n)
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    stretch = np.concatenate([rng.uniform(1.0, 1.5, n // 2), rng.uniform(0.5, 1.0, n - n // 2)])  # half compressed
    start = rng.normal(size=(n, 3))
    x = np.stack([start, start + (rest * stretch)[:, None] * direction], axis=1)
    zero = assert_paths_agree(*bar_pair(ea_c)(x, rest, 2.0e5))
    assert zero == (n - n // 2 if ea_c is None else 0)  # a compressed bar without EA_c is slack


@pytest.mark.parametrize("ea_c", OPTIONS)
def test_rod_stiffness_is_axial_plus_geometric(ea_c):
    # independent numpy form: EA/L0 e e^T (EA of the branch, 0 when slack) + T/L (I - e e^T), T = EA eps
    rng = np.random.default_rng(15)
    for stretch in (1.3, 1.02, 0.97, 0.4):
        w = rng.normal(size=3)
        rest = np.linalg.norm(w) / stretch
        length = np.linalg.norm(w)
        e = w / length
        eps = length / rest - 1.0
        ea = EA if eps > 0 else (0.0 if ea_c is None else ea_c)
        expected = ea / rest * np.outer(e, e) + ea * eps / length * (np.eye(3) - np.outer(e, e))
        k = np.asarray(rod_stiffness(jnp.asarray(w), rest, EA, ea_compression=ea_c))
        np.testing.assert_allclose(k, expected, rtol=1e-13, atol=1e-13 * EA / rest)
        if ea_c is None and eps < 0:
            assert np.all(k == 0.0)
        else:
            # and it is the Jacobian of the rod's force T e (central differences)
            def force(v):
                L = np.linalg.norm(v)
                s = L / rest - 1.0
                return (EA if s > 0 else (0.0 if ea_c is None else ea_c)) * s * v / L

            h = 1e-7 * length
            fd = np.stack([(force(w + h * u) - force(w - h * u)) / (2 * h) for u in np.eye(3)], axis=1)
            np.testing.assert_allclose(k, fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())


def test_clockwise_triangle_is_the_counter_clockwise_one_relabelled():
    # d < 0: swapping vertices 2 and 3 turns a counter-clockwise triangle into a clockwise one with the same
    # twines, so K must be the same matrix with its vertex blocks permuted (no sign of d anywhere)
    x, uv = random_triangles(16, seed=16)
    ccw = geometry.twine_determinant(uv) > 0
    x, uv = x[ccw], uv[ccw]
    swap = [0, 2, 1]
    _, k = netting_pair(EA_C)(x, uv, L0, EA)
    auto_cw, k_cw = netting_pair(EA_C)(x[:, swap], uv[:, swap], L0, EA)
    assert np.all(geometry.twine_determinant(uv[:, swap]) < 0)
    perm = np.concatenate([3 * i + np.arange(3) for i in swap])
    np.testing.assert_allclose(k_cw, np.asarray(k)[:, perm][:, :, perm], rtol=0, atol=1e-12 * np.abs(k).max())
    assert_paths_agree(auto_cw, k_cw)


def rest_length_element():
    """A triangle whose U twine is x2 - x1 and V twine x3 - x1 (uv = (0,0), (1,0), (0,1): d = 1), both of
    length exactly L0 in floating point (sqrt(fl(L0²)) = L0), so eps = 0 exactly."""
    x = np.array([[0.0, 0.0, 0.0], [L0, 0.0, 0.0], [0.0, L0, 0.0]])
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    return x, uv


@pytest.mark.parametrize("ea_c", OPTIONS)
def test_twine_exactly_at_rest_length(ea_c):
    # The kink of the energy at eps = 0. Without compression stiffness phi = EA l0 max(eps, 0)²/2 and JAX
    # differentiates max at a tie as half of each side: the autodiff Hessian there is (1/2)² EA/l0 along the
    # twine (neither one-sided value, 0 or EA/l0). The closed form returns the same choice; with a compression
    # stiffness the tie goes to the compressive branch (strain > 0 is False): EA_c/l0 on both paths.
    x, uv = rest_length_element()
    U, V, d = geometry.twine_vectors(jnp.asarray(x), jnp.asarray(uv))
    assert float(jnp.linalg.norm(U)) == L0 and float(jnp.linalg.norm(V)) == L0
    auto, k = (np.asarray(m[0]) for m in netting_pair(ea_c)(x[None], uv[None], L0, EA))
    axial = (0.25 * EA if ea_c is None else ea_c) / L0
    a, b, _ = (np.asarray(c) for c in geometry.twine_coefficients(jnp.asarray(uv)))
    ex, ey = np.diag([1.0, 0, 0]), np.diag([0, 1.0, 0])  # U along x, V along y; no tension, no geometric part
    expected = 0.5 * axial * (np.kron(np.outer(a, a), ex) + np.kron(np.outer(b, b), ey))  # |d|/2 = 1/2
    np.testing.assert_allclose(auto, expected, rtol=1e-14, atol=0)
    np.testing.assert_allclose(k, expected, rtol=1e-14, atol=0)


@pytest.mark.parametrize("ea_c", OPTIONS)
def test_collapsed_twine_and_collapsed_element(ea_c):
    # U = 0 exactly (the U twines collapsed: no direction) with V stretched, for d > 0 and d < 0: safe_norm
    # gives the U family a zero derivative, so both paths keep the V family's stiffness only, |d|/2 b b^T k_V;
    # an element collapsed to a point: K = 0 exactly. (U = 0 needs exact arithmetic: uv = (0,0), (2,0), (0,3)
    # makes U = (x2 - x1)/2, and x2 = x1. A twine of round-off length, |U| ~ 1e-17 m, is the singular point
    # of the module docstring: with a compression stiffness T/|U| ~ -EA_c/|U| is then ~1e19 N/m on both
    # paths, finite, with a direction that is round-off.)
    rng = np.random.default_rng(17)
    xs, uvs = [], []
    for swap in ([0, 1, 2], [0, 2, 1]):
        _, V = random_twine_pair(rng, stretch=(0.05, 0.2))
        x1 = rng.normal(size=3)
        xs.append(np.array([x1, x1, x1 + 3 * V])[swap])
        uvs.append(np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 3.0]])[swap])
    xs.append(np.zeros((3, 3)))
    uvs.append(uvs[0])
    xs, uvs = np.array(xs), np.array(uvs)
    assert np.sign(geometry.twine_determinant(uvs)).tolist() == [1, -1, 1]
    auto, k = netting_pair(ea_c)(xs, uvs, L0, EA)
    assert np.all(np.isfinite(np.asarray(auto)))
    assert assert_paths_agree(auto, k) == 1 and np.all(np.asarray(k[-1]) == 0.0)
    for xk, uvk, kk in zip(xs[:2], uvs[:2], np.asarray(k[:2])):
        a, b, d = (np.asarray(c) for c in geometry.twine_coefficients(jnp.asarray(uvk)))
        assert np.all(a @ xk == 0.0)
        k_v = np.asarray(rod_stiffness(jnp.asarray(b @ xk), L0, EA, ea_compression=ea_c))
        expected = abs(d) / 2 * np.kron(np.outer(b, b), k_v)
        np.testing.assert_allclose(kk, expected, rtol=1e-13, atol=1e-13 * np.abs(kk).max())


@pytest.mark.parametrize("ea_c", OPTIONS)
def test_stiffness_is_symmetric_and_rigid_motions_give_the_right_response(ea_c):
    # K = K^T (conservative); K t = 0 for a translation t; for an infinitesimal rotation omega the forces
    # turn with the element, K (omega ^ x) = -omega ^ F (F = -grad E: d F = omega ^ F under x -> x + omega ^ x)
    rng = np.random.default_rng(19)
    x, uv = random_triangles(12, seed=20)
    _, k = netting_pair(ea_c)(x, uv, L0, EA)
    for xk, uvk, kk in zip(x, uv, np.asarray(k)):
        scale = np.abs(kk).max()
        np.testing.assert_allclose(kk, kk.T, rtol=0, atol=1e-14 * scale)
        np.testing.assert_allclose(kk @ np.tile(rng.normal(size=3), 3), 0.0, atol=1e-12 * scale)
        omega = rng.normal(size=3)
        f = true_force(xk, uvk, L0, EA, ea_c)
        np.testing.assert_allclose(kk @ np.cross(omega, xk).ravel(), -np.cross(omega, f).ravel(),
                                   rtol=0, atol=1e-10 * np.abs(f).max())
        assert np.abs(f).max() > 1e-3 * scale * np.abs(xk).max()  # the rotation test is not a stress-free one


def test_stress_free_element_does_not_resist_infinitesimal_rotations():
    # twines at their rest length (to round-off): F ~ 0 and K (omega ^ x) = 0 while K itself is EA/l0-sized
    rng = np.random.default_rng(21)
    x, uv = random_triangles(8, seed=22, stretch=(0.0, 0.0))
    _, k = netting_pair(EA_C)(x, uv, L0, EA_C)  # EA = EA_c: the rounding side of eps = 0 does not matter
    for xk, kk in zip(x, np.asarray(k)):
        omega = rng.normal(size=3)
        assert np.abs(kk).max() > 0.1 * EA_C / L0
        np.testing.assert_allclose(kk @ np.cross(omega, xk).ravel(), 0.0,
                                   atol=1e-12 * np.abs(kk).max() * np.abs(xk).max())


# -- part 2: the printed equations 4.30-4.75 (diamond mesh) ---------------------------------------------


def traction_element(seed, clockwise):
    """One seeded well-conditioned triangle with both twine families in traction (+2 % .. +20 %)."""
    x, uv = random_triangles(2, seed=seed, stretch=(0.02, 0.2))
    k = 1 if clockwise else 0
    assert (geometry.twine_determinant(uv[k]) < 0) == clockwise
    return x[k], uv[k]


def twine_state(x, uv, l0, ea):
    U, V, d = (np.asarray(v) for v in geometry.twine_vectors(jnp.asarray(x), jnp.asarray(uv)))
    lu, lv = np.linalg.norm(U), np.linalg.norm(V)
    return U, V, float(d), lu, lv, book_4_30(lu, l0, ea), book_4_30(lv, l0, ea)


def book_4_30(length, l0, ea):
    """4.30-4.31: T = EA (|U| - l0) / l0 (N)."""
    return ea * (length - l0) / l0


def book_4_34_to_4_42(x, uv, l0, ea, grad_length_u, grad_length_v):
    """4.34-4.42 as printed: F_ti = (T_u d|U|/dti + T_v d|V|/dti) d/2, given the derivatives of |U|, |V|
    (3, 3). Returns (3, 3)."""
    U, V, d, lu, lv, tu, tv = twine_state(x, uv, l0, ea)
    return (tu * grad_length_u + tv * grad_length_v) * d / 2


def book_4_43_to_4_45(x, uv, l0, ea):
    """4.43-4.45 as printed: F_i = (V_j - V_k) T_u U/(2|U|) + (U_k - U_j) T_v V/(2|V|). Returns (3, 3)."""
    U, V, d, lu, lv, tu, tv = twine_state(x, uv, l0, ea)
    Ui, Vi = sides(uv)
    cu = np.array([Vi[2] - Vi[1], Vi[0] - Vi[2], Vi[1] - Vi[0]])
    cv = np.array([Ui[1] - Ui[2], Ui[2] - Ui[0], Ui[0] - Ui[1]])
    return cu[:, None] * tu * U / (2 * lu) + cv[:, None] * tv * V / (2 * lv)


def book_4_50_to_4_57(uv):
    """4.50-4.57 as printed: dU_w/dt and dV_w/dt, (3, 9) each (row w, column t = 3 i + coordinate)."""
    Ui, Vi = sides(uv)
    d = float(geometry.twine_determinant(jnp.asarray(uv)))
    cu = np.array([Vi[1] - Vi[2], Vi[2] - Vi[0], Vi[0] - Vi[1]]) / d  # 4.50, 4.51, 4.52
    cv = np.array([Ui[2] - Ui[1], Ui[0] - Ui[2], Ui[1] - Ui[0]]) / d  # 4.54, 4.55, 4.56
    # 4.53, 4.57: a component of U (V) does not depend on the other coordinates of the vertices
    return np.kron(cu[None, :], np.eye(3)), np.kron(cv[None, :], np.eye(3))


def book_4_58_to_4_75(x, uv):
    """4.58-4.75 as printed: d|U|/dt and d|V|/dt, (9,) each (t = x1, y1, z1, x2, ..., z3)."""
    Ui, Vi = sides(uv)
    d = float(geometry.twine_determinant(jnp.asarray(uv)))
    s12, s13 = x[1] - x[0], x[2] - x[0]
    bracket_u = s12 * (Vi[2] - Vi[0]) - s13 * (Vi[1] - Vi[0])  # per coordinate w = x, y, z
    bracket_v = s12 * (Ui[2] - Ui[0]) - s13 * (Ui[1] - Ui[0])
    cu = np.array([Vi[1] - Vi[2], Vi[2] - Vi[0], Vi[0] - Vi[1]])  # 4.58-4.60 (x), 4.61-4.63 (y), 4.64-4.66 (z)
    cv = np.array([Ui[1] - Ui[2], Ui[2] - Ui[0], Ui[0] - Ui[1]])  # 4.67-4.75
    return (np.outer(cu, bracket_u) / d**2).ravel(), (np.outer(cv, bracket_v) / d**2).ravel()


def book_4_47_to_4_49(x, uv, l0, ea, n0, du, dv, dlu, dlv):
    """4.47-4.49 as printed: dF_wi/dt (9, 9) (row 3 i + w, column t), with the unstretched length written n0
    and the derivatives dU_w/dt, dV_w/dt (3, 9) and d|U|/dt, d|V|/dt (9,) supplied."""
    U, V, d, lu, lv, tu, tv = twine_state(x, uv, l0, ea)
    Ui, Vi = sides(uv)
    cu = np.array([Vi[2] - Vi[1], Vi[0] - Vi[2], Vi[1] - Vi[0]])
    cv = np.array([Ui[1] - Ui[2], Ui[2] - Ui[0], Ui[0] - Ui[1]])
    part_u = du * (1 / n0 - 1 / lu) + np.outer(U, dlu) / lu**2  # (w, t)
    part_v = dv * (1 / n0 - 1 / lv) + np.outer(V, dlv) / lv**2
    dF = ea * cu[:, None, None] / 2 * part_u[None] + ea * cv[:, None, None] / 2 * part_v[None]
    return dF.reshape(9, 9)


@jax.jit
def _twine_derivatives(x, uv):
    def vectors(y):
        U, V, _ = geometry.twine_vectors(y, uv)
        return jnp.stack([U, V])

    def lengths(y):
        return jnp.linalg.norm(vectors(y), axis=1)

    return jax.jacfwd(lengths)(x), jax.jacfwd(vectors)(x)


def length_gradients(x, uv):
    """True d|U|/dx, d|V|/dx (3, 3) by autodiff."""
    g = np.asarray(_twine_derivatives(jnp.asarray(x), jnp.asarray(uv))[0])
    return g[0], g[1]


def twine_jacobians(x, uv):
    """True dU_w/dt, dV_w/dt (3, 9) by autodiff."""
    j = np.asarray(_twine_derivatives(jnp.asarray(x), jnp.asarray(uv))[1]).reshape(2, 3, 9)
    return j[0], j[1]


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_434_to_442_give_minus_sign_d_times_the_force(clockwise):
    # 4.32-4.33 equate the work of F with the work of the twines, so 4.34-4.42 give the load that holds the
    # twines (+sign(d) grad E), not the force of the twines on the vertices that 4.43-4.45 then print
    # (-grad E for d > 0). With the true d|U|/dt: printed = -sign(d) F. Relative error 2 for d > 0; for
    # d < 0 the two errors (sign convention, d instead of |d|) cancel.
    x, uv = traction_element(31, clockwise)
    gu, gv = length_gradients(x, uv)
    printed = book_4_34_to_4_42(x, uv, L0, EA, gu, gv)
    force = true_force(x, uv, L0, EA)
    d = float(geometry.twine_determinant(jnp.asarray(uv)))
    np.testing.assert_allclose(printed, -np.sign(d) * force, rtol=1e-12, atol=1e-12 * np.abs(force).max())
    expected_error = 0.0 if clockwise else 2.0
    np.testing.assert_allclose(relative_difference(printed, force), expected_error, atol=1e-12)


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_443_to_445_are_the_force_for_positive_d_only(clockwise):
    x, uv = traction_element(32, clockwise)
    printed = book_4_43_to_4_45(x, uv, L0, EA)
    force = true_force(x, uv, L0, EA)
    expected_error = 2.0 if clockwise else 0.0  # printed = sign(d) F
    np.testing.assert_allclose(relative_difference(printed, force), expected_error, atol=1e-12)


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_450_to_457_are_right(clockwise):
    x, uv = traction_element(33, clockwise)
    du, dv = book_4_50_to_4_57(uv)
    tu, tv = twine_jacobians(x, uv)
    assert relative_difference(du, tu) < 1e-14 and relative_difference(dv, tv) < 1e-14


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_458_to_475_are_the_length_derivatives_times_the_length(clockwise):
    # the bracket over d is U_w (-V_w for 4.67-4.75, whose factor (U2-U3) = -d dV/dx1 compensates), so each
    # printed entry is |U| (|V|) times the true d|U|/dt: dimensionally metres instead of a pure number. In SI
    # units, on this element (|U|, |V| ~ 0.055 m) the relative error is 1 - |U| ~ 0.95.
    x, uv = traction_element(34, clockwise)
    dlu, dlv = book_4_58_to_4_75(x, uv)
    gu, gv = length_gradients(x, uv)
    U, V, d, lu, lv, *_ = twine_state(x, uv, L0, EA)
    np.testing.assert_allclose(dlu, lu * gu.ravel(), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(dlv, lv * gv.ravel(), rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(relative_difference(dlu, gu.ravel()), 1 - lu, rtol=1e-10)
    np.testing.assert_allclose(relative_difference(dlv, gv.ravel()), 1 - lv, rtol=1e-10)
    assert 0.9 < 1 - max(lu, lv) < 1 - min(lu, lv) < 0.96


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_447_to_449_with_l0_and_true_length_derivatives_are_the_stiffness(clockwise):
    # read 1/n0 as 1/l0 and d|U|/dt as U_t/|U| (4.58-4.75 divided by |U|): 4.47-4.49 are then dF/dt of
    # 4.43-4.45, i.e. -K for d > 0 and +K for d < 0 (4.43-4.45 carry sign(d)); the closed form agrees
    x, uv = traction_element(35, clockwise)
    du, dv = book_4_50_to_4_57(uv)
    gu, gv = length_gradients(x, uv)
    dF = book_4_47_to_4_49(x, uv, L0, EA, L0, du, dv, gu.ravel(), gv.ravel())
    auto, hand = (k[0] for k in netting_pair(None)(x[None], uv[None], L0, EA))
    d = float(geometry.twine_determinant(jnp.asarray(uv)))
    assert relative_difference(-np.sign(d) * dF, auto) < 1e-12
    assert relative_difference(hand, auto) < 1e-12


def test_book_stiffness_as_printed_misses_most_of_the_axial_part():
    # 4.47 with 4.50-4.57 and 4.58-4.75 exactly as printed (n0 read as l0, d > 0): the axial term
    # d|U|/dt U_w/|U|² is multiplied by |U| (in m). On this element the printed K is off by 91 % of its
    # largest entry; dividing 4.58-4.75 by |U|, |V| removes the whole error.
    x, uv = traction_element(36, clockwise=False)
    du, dv = book_4_50_to_4_57(uv)
    dlu, dlv = book_4_58_to_4_75(x, uv)
    U, V, d, lu, lv, *_ = twine_state(x, uv, L0, EA)
    printed = -book_4_47_to_4_49(x, uv, L0, EA, L0, du, dv, dlu, dlv)
    fixed = -book_4_47_to_4_49(x, uv, L0, EA, L0, du, dv, dlu / lu, dlv / lv)
    auto = netting_pair(None)(x[None], uv[None], L0, EA)[0][0]
    assert relative_difference(fixed, auto) < 1e-12
    error = relative_difference(printed, auto)
    assert 0.88 < error < 0.94, error


# -- part 2: the printed equations 4.76-4.113 (hexagonal mesh) ------------------------------------------

HEX_L0 = np.array([0.020, 0.022, 0.025])  # unstretched lengths of the l, m, n twines (m)
HEX_EA = np.full(3, 1500.0)


def hexagonal_mesh(rng, plane=False, spread=0.05):
    """Base mesh sides U, V (m) of a honeycomb whose l, m, n twines (at 90°, 210°, 330°) are stretched by
    2 % .. 8 % (4.83-4.84), then distorted by up to ``spread`` and rotated; in the XOY plane if ``plane``
    (the frame of 4.89-4.105)."""
    lengths = HEX_L0 * (1.0 + rng.uniform(0.02, 0.08, size=3))
    l, m, n = (r * np.array([np.cos(t), np.sin(t), 0.0]) for r, t in zip(lengths, np.deg2rad([90.0, 210.0, 330.0])))
    A = np.eye(3) + spread * rng.uniform(-1, 1, size=(3, 3))
    if plane:
        A[2], A[:, 2] = [0, 0, 1.0], [0, 0, 1.0]
        angle = rng.uniform(0, 2 * np.pi)
        c, s = np.cos(angle), np.sin(angle)
        R = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    else:
        R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    return R @ A @ (2 * n - m - l), R @ A @ (l - m)


def hexagonal_element(seed, clockwise=False, plane=False):
    rng = np.random.default_rng(seed)
    U, V = hexagonal_mesh(rng, plane)
    x, uv = random_triangles(2, seed=seed)
    uv = uv[1 if clockwise else 0]
    return positions(uv, U, V, rng.normal(size=3)), uv, U, V


@functools.cache
def hexagonal_report():
    def one(x, uv):
        args = (HEX_L0, HEX_EA, None)
        U, V, _ = geometry.twine_vectors(x, uv)
        dU, dV = jax.grad(hx.equilibrium_knot_energy, argnums=(0, 1))(U, V, *args)
        return {
            "force": -jax.grad(hx.hexagonal_energy)(x, uv, *args),
            "twines": hx.hexagonal_twines(x, uv, *args),
            "tensions": hx.hexagonal_tensions(x, uv, *args),
            "dE_dU": dU,
            "dE_dV": dV,
        }

    return jax.jit(one)


def book_4_79(x, uv):
    """4.79 as printed: V = (U3 - U1)/d 12 - (U2 - U1)/d 13."""
    Ui, _ = sides(uv)
    d = float(geometry.twine_determinant(jnp.asarray(uv)))
    return (Ui[2] - Ui[0]) / d * (x[1] - x[0]) - (Ui[1] - Ui[0]) / d * (x[2] - x[0])


def book_4_78(x, uv):
    """4.78 as printed: U = (V3 - V1)/d 12 - (V2 - V1)/d 13 (= 4.3)."""
    _, Vi = sides(uv)
    d = float(geometry.twine_determinant(jnp.asarray(uv)))
    return (Vi[2] - Vi[0]) / d * (x[1] - x[0]) - (Vi[1] - Vi[0]) / d * (x[2] - x[0])


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_478_is_right_and_479_is_minus_v(clockwise):
    x, uv, U, V = hexagonal_element(41, clockwise)
    assert relative_difference(book_4_78(x, uv), U) < 1e-12
    np.testing.assert_allclose(relative_difference(book_4_79(x, uv), V), 2.0, atol=1e-12)  # printed = -V


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_483_to_488_hold_at_the_solved_knot(clockwise):
    # 4.83 U = -m + 2n - l, 4.84 V = l - m (twines from the knot), 4.85-4.87 |T_i| = EA_i (|i| - i0)/i0,
    # 4.88 T_l + T_m + T_n = 0 (an element with all twines in traction)
    x, uv, U, V = hexagonal_element(42, clockwise)
    out = hexagonal_report()(x, uv)
    l, m, n = np.asarray(out["twines"])
    assert relative_difference(-m + 2 * n - l, U) < 1e-12 and relative_difference(l - m, V) < 1e-12
    lengths = np.linalg.norm([l, m, n], axis=1)
    assert np.all(lengths > HEX_L0)
    np.testing.assert_allclose(out["tensions"], HEX_EA * (lengths - HEX_L0) / HEX_L0, rtol=1e-12)
    vectors = np.asarray(out["tensions"])[:, None] * np.array([l, m, n]) / lengths[:, None]
    assert np.linalg.norm(vectors.sum(axis=0)) < 1e-11 * np.abs(out["tensions"]).sum()


def planar_knot(seed):
    """An element in the XOY plane and its exact knot: 2-D U, V, m (m) and the tensions (N)."""
    x, uv, U, V = hexagonal_element(seed, plane=True)
    out = hexagonal_report()(x, uv)
    twines = np.asarray(out["twines"])
    assert np.abs(twines[:, 2]).max() < 1e-15 and np.all(np.asarray(out["tensions"]) > 0)
    return U[:2], V[:2], twines[1, :2], np.asarray(out["tensions"])


def book_4_89_4_90(m, U, V, radicands="exact"):
    """4.89 and 4.90 (N), unknown m = (m_x, m_y); ``radicands="printed"`` takes 4.90's printed radicands
    (m_y + V_y)² + (m_y + V_y)², m_y² + m_y², (m_y + W_y)² + (m_y + W_y)² under the brackets' roots."""
    W = (U + V) / 2
    vectors = [m + V, m, m + W]  # l, m, n (4.83-4.84)
    f = np.zeros(2)
    for i, r in enumerate(vectors):
        length = np.hypot(*r)
        stretched = np.sqrt(2) * abs(r[1]) if radicands == "printed" else length
        f += r / length * HEX_EA[i] / HEX_L0[i] * (np.array([length, stretched]) - HEX_L0[i])
    return f


def book_4_93_4_94(m, U, V):
    """4.93-4.94 written out (approximation 4.91-4.92 applied to the three twines)."""
    Wx, Wy = (U + V) / 2
    mx, my = m
    (ea_l, ea_m, ea_n), (l0, m0, n0) = HEX_EA, HEX_L0
    rl, rm, rn = np.hypot(mx + V[0], my + V[1]), np.hypot(mx, my), np.hypot(mx + Wx, my + Wy)
    return np.array([
        (mx + V[0]) * ea_l / l0**2 * (rl - l0) + mx * ea_m / m0**2 * (rm - m0) + (mx + Wx) * ea_n / n0**2 * (rn - n0),
        (my + V[1]) * ea_l / l0**2 * (rl - l0) + my * ea_m / m0**2 * (rm - m0) + (my + Wy) * ea_n / n0**2 * (rn - n0),
    ])


def book_4_99(m, U, V):
    """4.95-4.96 = 4.99: F = sum EA_i/i0² (|i| - i0) i, i = l, m, n."""
    twines = np.array([m + V, m, m + (U + V) / 2])
    lengths = np.linalg.norm(twines, axis=1)
    return np.sum((HEX_EA / HEX_L0**2 * (lengths - HEX_L0))[:, None] * twines, axis=0)


def book_4_102_to_4_104(m, U, V):
    """D11, D12 = D21, D22 as printed (the '1' of 4.102-4.104 read as |l|)."""
    twines = np.array([m + V, m, m + (U + V) / 2])
    lengths = np.linalg.norm(twines, axis=1)
    c = HEX_EA / HEX_L0**2
    D11 = -np.sum(c * (lengths - HEX_L0 + twines[:, 0] ** 2 / lengths))
    D12 = -np.sum(c * twines[:, 0] * twines[:, 1] / lengths)
    D22 = -np.sum(c * (lengths - HEX_L0 + twines[:, 1] ** 2 / lengths))
    return D11, D12, D12, D22


def book_4_105(D, F, printed=True):
    """4.105: h = ((D22 F1 - D12 F2)/det, (D22 F2 - D21 F1)/det) as printed; D11 F2 in h2 if not."""
    D11, D12, D21, D22 = D
    det = D22 * D11 - D12 * D21
    return np.array([(D22 * F[0] - D12 * F[1]) / det, ((D22 if printed else D11) * F[1] - D21 * F[0]) / det])


def test_book_490_radicands_leave_a_large_residual_at_the_knot():
    # at the exact knot 4.89 and the corrected 4.90 vanish; 4.90 with its printed radicands leaves a residual
    # of 10 times the largest tension on this element (strains 4 %): a radicand sqrt(2) |m_y| instead of |m|
    # is off by O(l0), not O(eps l0)
    U, V, m, tensions = planar_knot(43)
    exact = book_4_89_4_90(m, U, V)
    printed = book_4_89_4_90(m, U, V, radicands="printed")
    assert np.abs(exact).max() < 1e-11 * tensions.max()
    np.testing.assert_allclose(printed[0], exact[0], rtol=0, atol=1e-15)  # 4.89 is not affected
    assert 5.0 < abs(printed[1]) / tensions.max() < 15.0, abs(printed[1]) / tensions.max()


def test_book_491_to_4105_approximate_knot_and_newton_step():
    # 4.93-4.94 = 4.95-4.96 = 4.99 (identity); 4.102-4.104 are -dF/dm (4.101 should read F' = -D); solving
    # 4.99 = 0 by Newton with h = D^-1 F (4.105 with h2's D22 corrected to D11) gives the approximate knot,
    # which differs from the exact one (4.89-4.90) by the approximation 4.91-4.92 (twines weighted by
    # 1 + eps_i): on this element (strains 5 % .. 6 %) the knot moves by 2.5e-4 |m| and the tensions change
    # by 0.36 % of the largest.
    U, V, m_exact, tensions = planar_knot(44)
    rng = np.random.default_rng(45)
    probe = m_exact + 0.002 * rng.normal(size=2)
    np.testing.assert_allclose(book_4_93_4_94(probe, U, V), book_4_99(probe, U, V), rtol=1e-13)
    # 4.101: F' = -D
    h = 1e-7
    jac = np.stack([(book_4_99(probe + h * e, U, V) - book_4_99(probe - h * e, U, V)) / (2 * h) for e in np.eye(2)], axis=1)
    D11, D12, D21, D22 = book_4_102_to_4_104(probe, U, V)
    np.testing.assert_allclose(np.array([[D11, D12], [D21, D22]]), -jac, rtol=1e-6)
    # 4.97 with 4.101 as printed (F' = D): h = -D^-1 F is minus the Newton step, so |F| grows
    F = book_4_99(probe, U, V)
    newton = book_4_105((D11, D12, D21, D22), F, printed=False)
    np.testing.assert_allclose(newton, -np.linalg.solve(jac, F), rtol=1e-6)
    assert np.linalg.norm(book_4_99(probe - newton, U, V)) > np.linalg.norm(F)
    # 4.105's printed h2 (D22 F2 where D11 F2 belongs): error size on this probe, relative to |h|
    h2_error = abs(book_4_105((D11, D12, D21, D22), F)[1] - newton[1]) / np.linalg.norm(newton)
    assert 0.03 < h2_error < 0.1, h2_error
    # iterated, the printed 4.105 still reaches the root (h = 0 only where F = 0) but linearly, not
    # quadratically: after 3 steps from the regular knot its residual is 8e-5 of the start, Newton's 5e-15
    start = -(V + (U + V) / 2) / 3  # the regular knot
    for printed, bound in ((True, lambda r, r0: r > 1e-5 * r0), (False, lambda r, r0: r < 1e-12 * r0)):
        m = start
        for _ in range(3):
            m = m + book_4_105(book_4_102_to_4_104(m, U, V), book_4_99(m, U, V), printed=printed)
        assert bound(np.abs(book_4_99(m, U, V)).max(), np.abs(book_4_99(start, U, V)).max())
    # iterate the corrected Newton step to the approximate knot
    m = start
    for _ in range(30):
        m = m + book_4_105(book_4_102_to_4_104(m, U, V), book_4_99(m, U, V), printed=False)
    assert np.abs(book_4_99(m, U, V)).max() < 1e-9 * tensions.max() / HEX_L0.min()
    shift = np.linalg.norm(m - m_exact) / np.linalg.norm(m_exact)
    twines = np.array([m + V, m, m + (U + V) / 2])
    approx_tensions = HEX_EA * (np.linalg.norm(twines, axis=1) - HEX_L0) / HEX_L0
    tension_error = np.abs(approx_tensions - tensions).max() / tensions.max()
    assert 1e-4 < shift < 1e-3 and 1e-3 < tension_error < 1e-2, (shift, tension_error)


@pytest.mark.parametrize("clockwise", [False, True])
def test_book_4106_4107_are_the_energy_derivatives_and_4113_has_the_sign_of_d(clockwise):
    # with e the energy of one l, m and n twine at knot equilibrium (envelope theorem): F_U = T_l - T_m =
    # 2 de/dV and F_V = -T_n = -2 de/dU (4.106-4.107: the forces across one base-mesh side along U, along V);
    # 4.108-4.113 then give sign(d) times the force on the vertices: relative error 2 for d < 0
    x, uv, U, V = hexagonal_element(46, clockwise)
    out = hexagonal_report()(x, uv)
    twines = np.asarray(out["twines"])
    t_l, t_m, t_n = np.asarray(out["tensions"])[:, None] * twines / np.linalg.norm(twines, axis=1)[:, None]
    f_u, f_v = t_l - t_m, -t_n  # 4.106, 4.107
    scale = np.abs(out["tensions"]).max()
    np.testing.assert_allclose(f_u, 2 * np.asarray(out["dE_dV"]), rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(f_v, -2 * np.asarray(out["dE_dU"]), rtol=0, atol=1e-10 * scale)
    Ui, Vi = sides(uv)
    side = {(i, j): (Ui[j] - Ui[i]) * f_u + (Vi[j] - Vi[i]) * f_v for i, j in ((0, 1), (1, 2), (2, 0))}  # 4.108-4.110
    np.testing.assert_allclose(side[0, 1] + side[1, 2] + side[2, 0], 0.0, atol=1e-12 * scale)
    printed = np.array([side[0, 1] + side[2, 0], side[1, 2] + side[0, 1], side[2, 0] + side[1, 2]]) / 2  # 4.111-4.113
    np.testing.assert_allclose(relative_difference(printed, out["force"]), 2.0 if clockwise else 0.0, atol=1e-9)
