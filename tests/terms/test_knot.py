"""Knot contact (eqs 4.278-4.280): contact angle, zero above it, 4.280 stiffness below, C² onset, Newton;
and FEMNET's form (atan contact angle, H / 5, couple 2 H cos α (α - α_c)), by hand and by finite differences."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.terms import knot, opening

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


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
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


def test_no_contact_while_more_open_than_the_contact_angle(rng):
    for alpha in (ALPHA_MIN + 1e-9, 0.3, np.pi / 4, 1.2, np.pi / 2 - ALPHA_MIN - 1e-9):
        for band in (BAND, 0.0):
            x = lattice_positions(ONE_MESH, alpha, L0, random_rotation(rng)).ravel()
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
def test_below_the_band_the_couple_is_4279_with_the_4280_stiffness(depth, rng):
    # per knot the couple C does work 2 C dα (opening.py), |d|/2 knots: C = (dE/dα) / |d|.
    # Below the band, C = H (α - α_min + b/2) (4.279 with the contact moved by b/2), dC/dα = H of 4.280
    alpha = ALPHA_MIN - BAND - depth * (ALPHA_MIN - BAND)
    twist = random_rotation(rng)
    h = 1e-6
    e_minus, e0, e_plus = (along_path(alpha + s, twist=twist) for s in (-h, 0.0, h))
    couple = (e_plus - e_minus) / (2 * h) / 4.0
    np.testing.assert_allclose(couple, H_BOOK * (alpha - ALPHA_MIN + BAND / 2), rtol=1e-7)
    np.testing.assert_allclose((e_plus - 2 * e0 + e_minus) / h**2 / 4.0, H_BOOK, rtol=1e-4)
    # the plain penalty (band 0) is exactly 4.279: C = H (α - α_min)
    e_minus, e_plus = (along_path(alpha + s, band=0.0, twist=twist) for s in (-h, h))
    np.testing.assert_allclose((e_plus - e_minus) / (2 * h) / 4.0, H_BOOK * (alpha - ALPHA_MIN), rtol=1e-7)


def test_stiffness_is_continuous_at_onset_and_at_the_end_of_the_band(rng):
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
    twist = random_rotation(rng)
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
def test_forces_and_stiffness_in_contact_by_finite_differences(clockwise, rng):
    for _ in range(4):
        # a nearly closed net (deep in contact, or in the band), rotated, twines stretched unequally; the
        # unequal stretch moves the half angle, so draws that leave the contact are drawn again (the test's own
        # generator: the same draws whichever tests ran before)
        for _ in range(100):
            uv = rng.uniform(-4, 4, size=(3, 2))
            if (geometry.twine_determinant(uv) < 0) != clockwise:
                uv = uv[[0, 2, 1]]
            alpha = rng.uniform(ALPHA_MIN - 3 * BAND, ALPHA_MIN - 0.2 * BAND)
            x = lattice_positions(uv, alpha, L0, random_rotation(rng)) * rng.uniform(0.9, 1.1, size=3)
            x = x.ravel() + rng.normal(size=9) * 1e-4
            if float(opening.half_angle(x.reshape(3, 3), uv)[0]) < ALPHA_MIN:
                break
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


# -- FEMNET's form (form="femnet"): its contact angle, stiffness and force, as fermeture2.c computes them --

H_FEMNET = L0**2 * EA / (500.0 * KNOT)  # FEMNET: l0² EA / (1000 k/2), N·m/rad
ALPHA_C = np.arctan(KNOT / (2 * L0))  # FEMNET's contact half angle (atan, not arcsin)
ONE_TWINE = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])  # d = 1: x = (A, A + U, A + V)


def _femnet_energy(x, uv):
    return knot.knot_contact_energy(x.reshape(3, 3), uv, L0, KNOT, ea=EA, form="femnet")


@jax.jit
def _femnet_evaluate(x, uv):
    """Energy, forces -∇E, jacfwd stiffness of the femnet form, and FEMNET's own force, flat (9,)."""
    own = knot.femnet_contact_force(x.reshape(3, 3), uv, L0, KNOT, ea=EA).ravel()
    return _femnet_energy(x, uv), -jax.grad(_femnet_energy)(x, uv), jax.jacfwd(jax.grad(_femnet_energy))(x, uv), own


def femnet_evaluate(x, uv):
    return [np.asarray(a) for a in _femnet_evaluate(np.asarray(x, float).ravel(), np.asarray(uv, float))]


def test_femnet_contact_angle_and_stiffness(rng):
    np.testing.assert_allclose(knot.femnet_contact_half_angle(L0, KNOT), np.arctan(0.06), rtol=1e-15)
    np.testing.assert_allclose(knot.femnet_knot_stiffness(L0, KNOT, EA), 5.0 / 3.0, rtol=1e-14)  # 0.05² 2000 / 3
    np.testing.assert_allclose(knot.femnet_knot_stiffness(L0, KNOT, EA), H_BOOK / 5, rtol=1e-14)
    assert float(knot.femnet_knot_stiffness(L0, 0.0, EA)) == 0.0
    # onset exactly at atan(k / 2 l0) and at π/2 minus it, and only there: between atan (0.059928) and
    # arcsin (0.060036) the book form is in contact, FEMNET's is not
    assert ALPHA_C < ALPHA_MIN
    for alpha, touching in ((ALPHA_C + 1e-9, False), (ALPHA_C - 1e-6, True), (0.5 * (ALPHA_C + ALPHA_MIN), False),
                            (np.pi / 2 - ALPHA_C - 1e-9, False), (np.pi / 2 - ALPHA_C + 1e-6, True), (np.pi / 4, False)):
        e = femnet_evaluate(lattice_positions(ONE_MESH, alpha, L0, random_rotation(rng)), ONE_MESH)[0]
        assert (float(e) > 0.0) == touching, alpha
    assert along_path(0.5 * (ALPHA_C + ALPHA_MIN), band=0.0) > 0.0


@pytest.mark.parametrize("alpha", [0.04, np.pi / 2 - 0.04])
def test_femnet_force_on_one_twine_pair_by_hand(alpha):
    # d = 1, U = l (cos α, sin α, 0), V = l (cos α, -sin α, 0), x = (0, U, V). FEMNET's force is
    # F_i = d H (α - α_0) (∂c/∂x_i) / (2 sin α), c = cos 2α. Moving the tip of U by δ along
    # e = (-sin α, cos α, 0) turns U away from V by δ / l: 2α grows by δ / l, c = cos 2α by
    # -sin(2α) δ / l, so F_2 = -d H (α - α_0) (sin 2α / (2 l sin α)) e = -H (α - α_0) cos α e / l,
    # F_3 its mirror image, F_1 = -F_2 - F_3. (The printed 4.216 with the true ∂α/∂x_2 = e / (2 l)
    # would give H (α - α_0) e / (2 l): FEMNET's is 2 cos α times that.)
    rest = ALPHA_C if alpha < np.pi / 4 else np.pi / 2 - ALPHA_C
    s, c = np.sin(alpha), np.cos(alpha)
    x = np.array([[0.0, 0.0, 0.0], [L0 * c, L0 * s, 0.0], [L0 * c, -L0 * s, 0.0]])
    coefficient = -H_FEMNET * (alpha - rest) * c / L0
    f2, f3 = coefficient * np.array([-s, c, 0.0]), coefficient * np.array([-s, -c, 0.0])
    expected = np.concatenate([-(f2 + f3), f2, f3])
    e, force, _, own = femnet_evaluate(x, ONE_TWINE)
    np.testing.assert_allclose(own, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
    np.testing.assert_allclose(force, expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())
    # the numbers (H = 5/3 N·m/rad, α_c = atan 0.06): 0.6637 N at the tip of U at α = 0.04, opening the
    # mesh; at the other closure the same depth gives tan(0.04) = 4 % of it, closing it back from U = -V
    magnitude = {0.04: 0.663740, np.pi / 2 - 0.04: 0.0265638}[alpha]
    np.testing.assert_allclose(np.linalg.norm(force[3:6]), magnitude, rtol=1e-5)
    np.testing.assert_allclose(np.sign(force[4]), 1.0 if alpha < np.pi / 4 else -1.0)
    # the energy itself: (|d|/2) H φ(α), φ = 4 [(α - α_0) sin α + cos α - cos α_0]
    np.testing.assert_allclose(e, 0.5 * H_FEMNET * 4 * ((alpha - rest) * s + c - np.cos(rest)), rtol=1e-7)


@pytest.mark.parametrize("closure", ["alpha to 0", "alpha to pi/2"])
def test_femnet_couple_per_knot_along_the_closing_path(closure, rng):
    # per knot the couple does work 2 C dα, |d|/2 knots: C = (dE/dα) / |d| = 2 H cos α (α - α_0)
    twist = random_rotation(rng)
    h = 1e-6
    depth = (0.3, 0.9) if closure == "alpha to 0" else (-0.3, -0.9)
    rest = ALPHA_C if closure == "alpha to 0" else np.pi / 2 - ALPHA_C
    for fraction in depth:
        alpha = rest - fraction * ALPHA_C
        e = [float(femnet_evaluate(lattice_positions(ONE_MESH, alpha + t, L0, twist), ONE_MESH)[0]) for t in (-h, h)]
        couple = (e[1] - e[0]) / (2 * h) / 4.0
        np.testing.assert_allclose(couple, 2 * H_FEMNET * np.cos(alpha) * (alpha - rest), rtol=1e-6)


@pytest.mark.parametrize("clockwise", [False, True])
def test_femnet_forces_and_stiffness_by_finite_differences(clockwise, rng):
    for closure in (0.0, np.pi / 2):
        uv = rng.uniform(-4, 4, size=(3, 2))
        if (geometry.twine_determinant(uv) < 0) != clockwise:
            uv = uv[[0, 2, 1]]
        depth = rng.uniform(0.2, 0.9) * ALPHA_C
        alpha = ALPHA_C - depth if closure == 0.0 else np.pi / 2 - ALPHA_C + depth
        x = lattice_positions(uv, alpha, L0, random_rotation(rng)) * rng.uniform(0.95, 1.05, size=3)
        x = x.ravel() + rng.normal(size=9) * 1e-5
        e, f, K, own = femnet_evaluate(x, uv)
        assert float(e) > 0.0
        h = 1e-8
        fd = -np.array([(femnet_evaluate(x + h * STEP[i], uv)[0] - femnet_evaluate(x - h * STEP[i], uv)[0]) / (2 * h)
                        for i in range(9)])
        np.testing.assert_allclose(f, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())
        fdK = -np.stack([(femnet_evaluate(x + h * STEP[i], uv)[1] - femnet_evaluate(x - h * STEP[i], uv)[1]) / (2 * h)
                         for i in range(9)], axis=1)
        np.testing.assert_allclose(K, fdK, rtol=1e-4, atol=1e-5 * np.abs(fdK).max())
        np.testing.assert_allclose(K, K.T, atol=1e-10 * np.abs(K).max())
        # FEMNET's own force is -∇E on its (d > 0) triangles; it carries the signed d, so on a
        # clockwise triangle it is +∇E: it would push the mesh further closed
        sign = -1.0 if clockwise else 1.0
        np.testing.assert_allclose(own, sign * f, rtol=1e-9, atol=1e-12 * np.abs(f).max())


def test_femnet_form_options_and_degenerate_meshes():
    x = lattice_positions(ONE_MESH, 0.5 * ALPHA_C)
    explicit = jax.jit(lambda y: knot.knot_contact_energy(y, ONE_MESH, L0, KNOT, H_FEMNET, form="femnet"))
    np.testing.assert_allclose(explicit(x), femnet_evaluate(x, ONE_MESH)[0], rtol=1e-14)
    # FEMNET has contact on both diagonals; both_diagonals=False keeps only the α -> 0 one
    near_half_pi = lattice_positions(ONE_MESH, np.pi / 2 - 0.5 * ALPHA_C)
    one_sided = jax.jit(lambda y: knot.knot_contact_energy(y, ONE_MESH, L0, KNOT, ea=EA, form="femnet",
                                                           both_diagonals=False))
    assert float(one_sided(near_half_pi)) == 0.0 and float(femnet_evaluate(near_half_pi, ONE_MESH)[0]) > 0.0
    with pytest.raises(ValueError, match="band"):
        knot.knot_contact_energy(x, ONE_MESH, L0, KNOT, ea=EA, band=0.01, form="femnet")
    with pytest.raises(ValueError, match="form"):
        knot.knot_contact_energy(x, ONE_MESH, L0, KNOT, ea=EA, form="FEMNET")
    with pytest.raises(ValueError, match="ea"):
        knot.knot_contact_energy(x, ONE_MESH, L0, KNOT, form="femnet")
    closed = [lattice_positions(ONE_MESH, a).ravel() for a in (0.0, np.pi / 2)]
    closed += [np.zeros(9), np.array([0.0, 0, 0, 0.1, 0, 0, 0.1, 0, 0])]
    for y in closed:
        e, f, K, _ = femnet_evaluate(y, ONE_MESH)
        assert np.isfinite(e) and np.isfinite(f).all() and np.isfinite(K).all()
    # fully closed (α = 0): φ(0) = 4 (1 - cos α_c), |d|/2 = 2 knots
    np.testing.assert_allclose(femnet_evaluate(closed[0], ONE_MESH)[0], 2 * H_FEMNET * 4 * (1 - np.cos(ALPHA_C)),
                               rtol=1e-12)


def test_scene_knot_form_codes_select_the_law_per_triangle():
    # Netting.knot_form: 0 the book's law, 1 FEMNET's; a scene mixing both sums each triangle's own law.
    import dataclasses

    from jaxnet import model
    from jaxnet.model import assemble
    from jaxnet.net import Net, Twine

    net = Net()
    p = net.panel("p", [(0, 0, 0, 0, 0), (0.3, 0, 0, 10, -10), (0.3, 0, 0.3, 20, 0), (0, 0, 0.3, 10, 10)],
                  Twine(l0=0.02, ea=1000.0, diameter=1e-3, knot_size=0.008), 0.1)
    net.fix(p.side(2))
    scene = net.build()
    rng = np.random.default_rng(5)
    # squeeze the panel along z so that its meshes close past the contact angle
    x = np.asarray(scene.nodes.position) * np.array([1.0, 1.0, 0.15]) + rng.normal(0, 1e-3, (scene.n_nodes, 3))
    e_count = scene.netting.vertices.shape[0]
    codes = np.arange(e_count) % 2
    mixed = dataclasses.replace(scene, netting=dataclasses.replace(scene.netting, knot_form=codes))
    terms = tuple(t for t in model.active_terms(mixed) if t.name == "knot_contact")
    assert terms[0].kwargs()["forms"] == (0, 1)
    total = float(assemble.energy(jnp.asarray(x), mixed, terms))
    net_ = scene.netting
    expected = 0.0
    for e in range(e_count):
        form = "femnet" if codes[e] else "book"
        expected += float(knot.knot_contact_energy(jnp.asarray(x[np.asarray(net_.vertices[e])]), net_.uv[e], net_.l0[e],
                                                   net_.knot_size[e], net_.knot_stiffness[e], form=form))
    assert expected > 0
    np.testing.assert_allclose(total, expected, rtol=1e-12)
