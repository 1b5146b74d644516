"""Knot contact (eqs 4.278-4.280): contact angle, zero above it, 4.280 stiffness below, C² onset, Newton."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.terms import knot, opening

RNG = np.random.default_rng(4278)
STEP = np.eye(9)
ONE_MESH = jnp.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])  # d = 4: one mesh, two knots
L0, KNOT, EA = 0.05, 0.006, 2000.0  # m, m, N
H_BOOK = L0**2 * EA / (100.0 * KNOT)  # eq. 4.280, N·m/rad
ALPHA_MIN = np.arcsin(KNOT / (2 * L0))  # half angle at which the knots B = A + U and D = A + V touch
BAND = float(0.1 * ALPHA_MIN)  # the documented default (a Python float, like 0.0: one compiled evaluate)


def lattice_positions(uv, alpha, side=L0, twist=None):
    """Vertices of a net of twine vectors of length ``side`` at half angle ``alpha`` either side of x (eq. 4.16)."""
    U = side * np.array([np.cos(alpha), np.sin(alpha), 0.0])
    V = side * np.array([np.cos(alpha), -np.sin(alpha), 0.0])
    uv = np.asarray(uv)
    x = uv[:, 0:1] * U + uv[:, 1:2] * V
    return x if twist is None else x @ np.asarray(twist).T


def random_rotation():
    q, r = np.linalg.qr(RNG.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


H_OPEN, ALPHA0 = 0.2, np.pi / 4  # opening stiffness (N·m/rad) and rest half angle, for the Newton test


def _energy(x, uv, band, h_open):
    x = x.reshape(3, 3)
    return knot.knot_contact_energy(x, uv, L0, KNOT, ea=EA, band=band) + opening.opening_energy(x, uv, h_open, ALPHA0)


# one compiled program for energy, forces and stiffness of knot contact (+ mesh opening when h_open > 0);
# band and h_open are traced, so the plain penalty (band 0) and the Newton test reuse it
@jax.jit
def _evaluate(x, uv, band, h_open):
    args = (x, uv, band, h_open)
    return _energy(*args), -jax.grad(_energy)(*args), jax.jacfwd(jax.grad(_energy))(*args)


def evaluate(x, uv, band, h_open=0.0):
    return _evaluate(np.asarray(x, float), np.asarray(uv, float), float(band), float(h_open))


def along_path(alpha, band=BAND, uv=ONE_MESH, twist=None):
    """Energy of a lattice element at half angle alpha (twine length L0)."""
    return float(evaluate(lattice_positions(uv, alpha, L0, twist).ravel(), uv, band)[0])


def test_contact_angle_is_where_neighbouring_knots_touch():
    # at α_min the knots at the ends of U and V, |U - V| apart, are one knot size apart
    alpha_min = float(knot.contact_half_angle(L0, KNOT))
    np.testing.assert_allclose(alpha_min, ALPHA_MIN, rtol=1e-14)
    U = L0 * np.array([np.cos(alpha_min), np.sin(alpha_min), 0.0])
    V = L0 * np.array([np.cos(alpha_min), -np.sin(alpha_min), 0.0])
    np.testing.assert_allclose(np.linalg.norm(U - V), KNOT, rtol=1e-13)
    # 4.278 is the *full* angle between the twines: twice the half angle compared with α
    np.testing.assert_allclose(2 * np.arcsin(KNOT / (2 * L0)), 2 * alpha_min, rtol=1e-14)
    assert float(knot.contact_half_angle(L0, 0.0)) == 0.0
    assert float(knot.contact_half_angle(L0, 3 * L0)) == np.pi / 2  # knots larger than the mesh
    np.testing.assert_allclose(knot.default_knot_stiffness(L0, KNOT, EA), H_BOOK, rtol=1e-14)


def test_no_contact_while_more_open_than_the_contact_angle():
    for alpha in (ALPHA_MIN + 1e-9, 0.3, np.pi / 4, 1.2, np.pi / 2 - ALPHA_MIN - 1e-9):
        for band in (BAND, 0.0):
            x = lattice_positions(ONE_MESH, alpha, L0, random_rotation()).ravel()
            e, f, K = evaluate(x, ONE_MESH, band)
            assert float(e) == 0.0 and float(jnp.abs(f).max()) == 0.0 and float(jnp.abs(K).max()) == 0.0
    # the book's one-sided contact: nothing even at the other closure
    x = lattice_positions(ONE_MESH, np.pi / 2 - 0.01)
    one_sided = jax.jit(lambda y: knot.knot_contact_energy(y, ONE_MESH, L0, KNOT, ea=EA, both_diagonals=False))
    assert float(one_sided(x)) == 0.0
    assert float(evaluate(x.ravel(), ONE_MESH, BAND)[0]) > 0.0


def test_default_band_and_stiffness_are_the_documented_ones():
    x = lattice_positions(ONE_MESH, 0.8 * ALPHA_MIN)
    defaults = jax.jit(lambda y: knot.knot_contact_energy(y, ONE_MESH, L0, KNOT, ea=EA))
    explicit = jax.jit(lambda y: knot.knot_contact_energy(y, ONE_MESH, L0, KNOT, H_BOOK, band=BAND))
    np.testing.assert_allclose(defaults(x), evaluate(x.ravel(), ONE_MESH, BAND)[0], rtol=1e-14)
    np.testing.assert_allclose(explicit(x), evaluate(x.ravel(), ONE_MESH, BAND)[0], rtol=1e-14)
    with pytest.raises(ValueError, match="ea"):
        knot.knot_contact_energy(x, ONE_MESH, L0, KNOT)


@pytest.mark.parametrize("depth", [0.2, 0.6])
def test_below_the_band_the_couple_is_4279_with_the_4280_stiffness(depth):
    # per knot the couple C does work 2 C dα (opening.py), |d|/2 knots: C = (dE/dα) / |d|.
    # Below the band, C = H (α - α_min + b/2) (4.279 with the contact moved by b/2), dC/dα = H of 4.280
    alpha = ALPHA_MIN - BAND - depth * (ALPHA_MIN - BAND)
    twist = random_rotation()
    h = 1e-6
    e_minus, e0, e_plus = (along_path(alpha + s, twist=twist) for s in (-h, 0.0, h))
    couple = (e_plus - e_minus) / (2 * h) / 4.0
    np.testing.assert_allclose(couple, H_BOOK * (alpha - ALPHA_MIN + BAND / 2), rtol=1e-7)
    np.testing.assert_allclose((e_plus - 2 * e0 + e_minus) / h**2 / 4.0, H_BOOK, rtol=1e-4)
    # the plain penalty (band 0) is exactly 4.279: C = H (α - α_min)
    e_minus, e_plus = (along_path(alpha + s, band=0.0, twist=twist) for s in (-h, h))
    np.testing.assert_allclose((e_plus - e_minus) / (2 * h) / 4.0, H_BOOK * (alpha - ALPHA_MIN), rtol=1e-7)


def test_stiffness_is_continuous_at_onset_and_at_the_end_of_the_band():
    # d²E/dα² along the closing path by finite differences of the energy: with the C² ramp it goes
    # continuously from 0 (above α_min) to |d| H (below the band); the plain penalty jumps by |d| H
    h = 1e-7

    def curvature(alpha, band):
        return (along_path(alpha + h, band) - 2 * along_path(alpha, band) + along_path(alpha - h, band)) / h**2

    full = 4.0 * H_BOOK
    for eps in (BAND / 10, BAND / 100):
        assert curvature(ALPHA_MIN + eps, BAND) == 0.0
        np.testing.assert_allclose(curvature(ALPHA_MIN - eps, BAND), full * eps / BAND, rtol=1e-3)  # -> 0
        np.testing.assert_allclose(curvature(ALPHA_MIN - BAND + eps, BAND), full * (1 - eps / BAND), rtol=1e-3)
        np.testing.assert_allclose(curvature(ALPHA_MIN - BAND - eps, BAND), full, rtol=1e-3)
        np.testing.assert_allclose(curvature(ALPHA_MIN - eps, 0.0), full, rtol=1e-3)  # plain: the jump
    # the same with the jacfwd stiffness of the vertices, in 3D: above α_min K = 0; at α_min - ε the
    # ramp's K is (ε/b) times the plain penalty's (K = (|d|/2) H [g'' ∇α ∇α^T - g' ∇∇α] with g'' = 2ε/b
    # against 2, g' = ε²/b against 2ε), which tends to 4 H ∇α ∇α^T as ε -> 0: a jump
    twist = random_rotation()
    K_plain = {}
    for eps in (BAND / 10, BAND / 1000):
        above = lattice_positions(ONE_MESH, ALPHA_MIN + eps, L0, twist).ravel()
        assert float(np.abs(evaluate(above, ONE_MESH, BAND)[2]).max()) == 0.0
        below = lattice_positions(ONE_MESH, ALPHA_MIN - eps, L0, twist).ravel()
        K_ramp, K_plain[eps] = (np.asarray(evaluate(below, ONE_MESH, b)[2]) for b in (BAND, 0.0))
        scale = eps / BAND * np.abs(K_plain[eps]).max()
        np.testing.assert_allclose(K_ramp, eps / BAND * K_plain[eps], atol=0.05 * scale)
    small, large = K_plain[BAND / 1000], K_plain[BAND / 10]
    np.testing.assert_allclose(small, large, atol=0.1 * np.abs(large).max())


penalty_and_derivatives = jax.jit(jax.vmap(
    lambda s, b: (knot.contact_penalty(s, b), jax.grad(knot.contact_penalty)(s, b),
                  jax.grad(jax.grad(knot.contact_penalty))(s, b)), (0, None)))


def test_penalty_bounds_and_smoothness():
    b = 0.01
    s = np.linspace(-0.02, 0.05, 141)
    g, dg, _ = (np.asarray(a) for a in penalty_and_derivatives(s, b))
    # sandwiched between the one-sided penalties with contact at α_min and at α_min - b
    assert np.all(g <= np.maximum(s, 0) ** 2 + 1e-18) and np.all(g >= np.maximum(s - b, 0) ** 2 - 1e-18)
    assert np.all(np.abs(dg - 2 * np.maximum(s, 0)) <= b * (1 + 1e-12))  # couple off 4.279 by <= H b / 2
    # C²: g'' continuous where the pieces meet (0 and b), half-way up the ramp at the middle of the band
    _, _, d2g = penalty_and_derivatives(np.array([-1e-9, 1e-9, b - 1e-9, b + 1e-9, 0.5 * b]), b)
    np.testing.assert_allclose(d2g, [0.0, 0.0, 2.0, 2.0, 1.0], atol=1e-6)


@pytest.mark.parametrize("clockwise", [False, True])
def test_forces_and_stiffness_in_contact_by_finite_differences(clockwise):
    for _ in range(4):
        uv = RNG.uniform(-4, 4, size=(3, 2))
        if (geometry.twine_determinant(uv) < 0) != clockwise:
            uv = uv[[0, 2, 1]]
        # a nearly closed net (deep in contact, or in the band), rotated, twines stretched unequally
        alpha = RNG.uniform(ALPHA_MIN - 3 * BAND, ALPHA_MIN - 0.2 * BAND)
        x = lattice_positions(uv, alpha, L0, random_rotation()) * RNG.uniform(0.9, 1.1, size=3)
        x = x.ravel() + RNG.normal(size=9) * 1e-4
        assert float(opening.half_angle(x.reshape(3, 3), uv)[0]) < ALPHA_MIN
        e, f, K = evaluate(x, uv, BAND)
        h = 1e-8
        fd = -np.array([(evaluate(x + h * STEP[i], uv, BAND)[0] - evaluate(x - h * STEP[i], uv, BAND)[0]) / (2 * h)
                        for i in range(9)])
        np.testing.assert_allclose(f, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
        fdK = -np.stack([(evaluate(x + h * STEP[i], uv, BAND)[1] - evaluate(x - h * STEP[i], uv, BAND)[1]) / (2 * h)
                         for i in range(9)], axis=1)
        np.testing.assert_allclose(K, fdK, rtol=1e-4, atol=1e-5 * np.abs(fdK).max())
        np.testing.assert_allclose(K, K.T, atol=1e-10 * np.abs(K).max())


def test_both_closures_are_symmetric_and_degenerate_meshes_are_finite():
    # relabelling V -> -V maps α to π/2 - α: the contact must not depend on it
    for alpha in (0.5 * ALPHA_MIN, ALPHA_MIN - 0.5 * BAND):
        np.testing.assert_allclose(along_path(np.pi / 2 - alpha), along_path(alpha), rtol=1e-9)
    closed = [lattice_positions(ONE_MESH, a).ravel() for a in (0.0, np.pi / 2)]
    closed += [np.zeros(9), np.array([0.0, 0, 0, 0.1, 0, 0, 0.1, 0, 0])]
    for x in closed:
        e, f, K = evaluate(x, ONE_MESH, BAND)
        assert np.isfinite(float(e)) and np.isfinite(np.asarray(f)).all() and np.isfinite(np.asarray(K)).all()
    # knotless netting: no contact at all, and no NaN from 4.280's division by the knot size
    knotless = jax.jit(jax.value_and_grad(lambda y: knot.knot_contact_energy(y, ONE_MESH, L0, 0.0, ea=EA)))
    e, f = knotless(jnp.asarray(closed[0]).reshape(3, 3))
    assert float(e) == 0.0 and np.isfinite(np.asarray(f)).all()


def newton_model(a, load):
    """Residual dΠ/dα and tangent d²Π/dα² of one mesh at half angle a, squeezed by ``load`` N.

    Π = E(x(a)) + load |2U - 2V|, with x(a) = (0, 2U, 2V), |U| = |V| = L0: the chain rule on the element's
    forces F = -∇E and jacfwd stiffness K, as the assembled Newton uses them.
    """
    c, s = np.cos(a), np.sin(a)
    x = 2 * L0 * np.array([0, 0, 0, c, s, 0, c, -s, 0])
    dx = 2 * L0 * np.array([0, 0, 0, -s, c, 0, -s, -c, 0])
    ddx = 2 * L0 * np.array([0, 0, 0, -c, -s, 0, -c, s, 0])
    _, f, K = (np.asarray(v) for v in evaluate(x, ONE_MESH, BAND, H_OPEN))
    return -f @ dx + load * 4 * L0 * c, dx @ K @ dx - f @ ddx - load * 4 * L0 * s


@pytest.mark.parametrize("load", [5.0, 3.3])
def test_damped_newton_crosses_onset_without_chatter(load):
    # one mesh held open by the opening stiffness, squeezed by two forces of ``load`` N pulling its side
    # knots 2U and 2V together (potential load |2U - 2V| = 4 load L0 sin α). Newton on α with steps
    # capped (0.1 rad, and at most half the way to closure) must enter contact and converge there
    # without leaving it, the residual falling quadratically; one load ends in the ramp band. The
    # equilibrium is checked against the closed form
    #   4 H_o (α - α0) - 4 H (α_min - α - b/2) + 4 load L0 cos α = 0     (below the band),
    #   4 H_o (α - α0) - 4 H (α_min - α)² / (2 b) + 4 load L0 cos α = 0  (in the band).
    alpha, history = ALPHA0, []
    for _ in range(30):
        r, k = newton_model(alpha, load)
        history.append((alpha, abs(r)))
        if abs(r) < 1e-13:
            break
        alpha += float(np.clip(-r / k, -min(0.1, alpha / 2), 0.1))
    alphas, residuals = np.array(history).T
    assert residuals[-1] < 1e-13 and len(history) < 20
    inside = np.flatnonzero(alphas < ALPHA_MIN)
    assert inside.size and np.all(alphas[inside[0]:] < ALPHA_MIN)  # entered contact and stayed: no chatter
    in_contact = residuals[inside[0]:]
    assert np.all(np.diff(in_contact) < 0)  # once in contact the residual falls at every step
    for before, after in zip(in_contact[:-1], in_contact[1:]):
        assert after <= 10 * before**2 or after < 1e-14  # quadratically (residual in J/rad, of order 1)
    s = ALPHA_MIN - alphas[-1]
    contact = -4 * H_BOOK * (s - BAND / 2) if s >= BAND else -4 * H_BOOK * s**2 / (2 * BAND)
    balance = 4 * H_OPEN * (alphas[-1] - ALPHA0) + contact + 4 * load * L0 * np.cos(alphas[-1])
    np.testing.assert_allclose(balance, 0.0, atol=1e-12)
    assert (s >= BAND) == (load == 5.0)  # the two loads end below the band and inside it
