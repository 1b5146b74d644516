"""The hexagonal-mesh element (book eqs 4.76-4.113): knot equilibrium, energy, forces and exact stiffness."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from elements import random_twine_coordinates  # tests/elements.py

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.terms import hexagonal as hx

L0 = np.array([0.020, 0.022, 0.025])  # unstretched lengths of the l, m, n twines (m)
EA = np.full(3, 1500.0)  # traction stiffness of each family (N)
EA_C = np.full(3, 300.0)  # compression stiffness (N), when the twines can push


def _report(x, uv, l0, ea, eac):
    """Everything the tests read of one element, in one compiled function per compression option."""
    grad = jax.grad(hx.hexagonal_energy)
    U, V, _ = geometry.twine_vectors(x, uv)
    return {
        "energy": hx.hexagonal_energy(x, uv, l0, ea, eac),
        "force": -grad(x, uv, l0, ea, eac),
        "stiffness": jax.jacfwd(grad)(x, uv, l0, ea, eac).reshape(9, 9),  # K = -dF/dx (as 4.46)
        "tensions": hx.hexagonal_tensions(x, uv, l0, ea, eac),
        "twines": hx.hexagonal_twines(x, uv, l0, ea, eac),
        "theta": hx.knot_equilibrium(U, V, l0, ea, eac),
    }


report = jax.jit(_report)


@jax.jit
def batch_energy_force(xs, uv, l0, ea, eac):
    """Energy and forces of the same element at a batch of vertex positions (for finite differences)."""
    def one(x):
        return hx.hexagonal_energy(x, uv, l0, ea, eac), -jax.grad(hx.hexagonal_energy)(x, uv, l0, ea, eac)

    return jax.vmap(one)(xs)


def rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def random_rotation(rng):
    return rotation(rng.normal(size=3), rng.uniform(0, 2 * np.pi))


def element_from_mesh(rng, U, V, uv, origin=None):
    """Vertex positions of a triangle with twine coordinates uv in a netting of base mesh sides U, V."""
    origin = rng.normal(size=3) if origin is None else origin
    return jnp.asarray(origin + uv[:, :1] * U + uv[:, 1:] * V)


def random_uv(rng, clockwise):
    # well-conditioned (tests/elements.py: 2 < |d| < 40, no side under a third of the longest): drawn anywhere in
    # [-4, 4]², a sliver (|d| = 0.03) had a stiffness of 7e6 N/m varying over its width, and central differences of
    # step 1e-6 m missed it by 8e-6 (truncation, h² over the square of that width)
    return jnp.asarray(random_twine_coordinates(rng, clockwise))


def random_mesh(rng, spread=0.3):
    """Base mesh sides of a stretched, sheared honeycomb: the regular one (twine 0.027 m) distorted."""
    a = 0.027
    l, m, n = (a * np.array([np.cos(t), np.sin(t), 0.0]) for t in np.deg2rad([90.0, 210.0, 330.0]))
    U, V = 2 * n - m - l, l - m
    A = np.eye(3) + spread * rng.uniform(-1, 1, size=(3, 3))
    R = random_rotation(rng)
    return R @ A @ U, R @ A @ V


def random_element(rng, clockwise=False, spread=0.3):
    U, V = random_mesh(rng, spread)
    uv = random_uv(rng, clockwise)
    return element_from_mesh(rng, U, V, uv), uv


def strains(x, uv):
    """Strains of the l, m, n twines at knot equilibrium, without then with compression stiffness: (6,)."""
    return np.concatenate([np.linalg.norm(report(x, uv, L0, EA, eac)["twines"], axis=1) / L0 - 1 for eac in (None, EA_C)])


def taut_element(rng, clockwise=False):
    """:func:`random_element` with a twine taut at the knot. Without compression stiffness, an element whose three
    twines are all slack (2 % of the draws) carries nothing: its forces and stiffness are zero to roundoff, and
    checks relative to their size compare roundoff (test_slack_element_without_compression_stiffness_is_inert_and_finite
    is about that element)."""
    while True:
        x, uv = random_element(rng, clockwise)
        if np.any(strains(x, uv)[:3] > 0.0):
            return x, uv


# -- geometry and counts -------------------------------------------------------------------------------


def test_regular_honeycomb_counts_its_twines(rng):
    # a regular honeycomb of twine a has one l, one m and one n twine per (3 sqrt3 / 2) a²: a triangle of
    # surface S holds S / that of each family, which must be |d| (text after 4.82), and |d|/2 base meshes
    a = 0.02
    l, m, n = (a * np.array([np.cos(t), np.sin(t), 0.0]) for t in np.deg2rad([90.0, 210.0, 330.0]))
    U, V = 2 * n - m - l, l - m  # 4.83-4.84
    for clockwise in (False, True):
        uv = random_uv(rng, clockwise)
        x = element_from_mesh(rng, U, V, uv)
        d = geometry.twine_determinant(uv)
        per_family = geometry.surface(x) / (1.5 * np.sqrt(3) * a**2)
        np.testing.assert_allclose(hx.family_twine_count(d), per_family, rtol=1e-12)
        np.testing.assert_allclose(hx.base_mesh_count(d) * np.linalg.norm(np.cross(U, V)), geometry.surface(x), rtol=1e-12)
        np.testing.assert_allclose(hx.hexagonal_knot_count(d), 2 * per_family, rtol=1e-12)


def test_book_479_prints_minus_v(rng):
    # 4.79 prints V = (U3-U1)/d 12 - (U2-U1)/d 13; solving 4.76-4.77 gives the opposite (as 4.4 has it)
    U, V = random_mesh(rng)
    uv = random_uv(rng, False)
    x = element_from_mesh(rng, U, V, uv)
    Ui, d = uv[:, 0], geometry.twine_determinant(uv)
    printed = (Ui[2] - Ui[0]) / d * (x[1] - x[0]) - (Ui[1] - Ui[0]) / d * (x[2] - x[0])
    np.testing.assert_allclose(geometry.twine_vectors(x, uv)[1], V, rtol=1e-10)
    np.testing.assert_allclose(printed, -V, rtol=1e-10)


# -- knot equilibrium: hand solutions ------------------------------------------------------------------


def test_regular_honeycomb_has_equal_tensions_at_120_degrees(rng):
    # twines of length a at 120 degrees: the knot is at the centroid of its neighbours (theta = 1/3, 1/3),
    # every twine carries EA (a - l0)/l0 and E = |d| * 3 * EA l0 eps² / 2. Scalar l0 and EA here.
    a, l0, ea = 0.021, 0.02, 1500.0
    R = random_rotation(rng)
    l, m, n = (R @ (a * np.array([np.cos(t), np.sin(t), 0.0])) for t in np.deg2rad([90.0, 210.0, 330.0]))
    U, V = 2 * n - m - l, l - m
    for clockwise in (False, True):
        uv = random_uv(rng, clockwise)
        out = report(element_from_mesh(rng, U, V, uv), uv, l0, ea, None)
        np.testing.assert_allclose(out["theta"], hx.REGULAR_KNOT, atol=1e-13)
        np.testing.assert_allclose(out["tensions"], np.full(3, ea * 0.05), rtol=1e-11)
        np.testing.assert_allclose(out["twines"], np.stack([l, m, n]), atol=1e-14)
        d = abs(float(geometry.twine_determinant(uv)))
        np.testing.assert_allclose(out["energy"], d * 3 * 0.5 * ea * l0 * 0.05**2, rtol=1e-11)


def test_uniaxial_stretch_matches_the_hand_solution_with_families_unlike(rng):
    # mirror-symmetric knot: l = (-p, q), m = (-p, -q), n = (r, 0). Equilibrium along x: T_n = 2 T_l p/|l|;
    # choosing p, q fixes T_l, hence T_n and r = l0_n (1 + T_n/EA_n); then U = (2(p+r), 0), V = (0, 2q) and
    # the knot weights are t = p/(p+r), s = (1-t)/2. The n family has its own l0 and EA.
    l0 = np.array([0.020, 0.020, 0.025])
    ea = np.array([1500.0, 1500.0, 2500.0])
    p, q = 0.008, 0.019
    length = np.hypot(p, q)
    t_l = 1500.0 * (length - 0.02) / 0.02
    t_n = 2 * t_l * p / length
    r = 0.025 * (1 + t_n / 2500.0)
    R = random_rotation(rng)
    U, V = R @ np.array([2 * (p + r), 0.0, 0.0]), R @ np.array([0.0, 2 * q, 0.0])
    t = p / (p + r)
    uv = random_uv(rng, True)
    out = report(element_from_mesh(rng, U, V, uv), uv, l0, ea, None)
    np.testing.assert_allclose(out["theta"], [(1 - t) / 2, t], rtol=1e-12)
    np.testing.assert_allclose(out["tensions"], [t_l, t_l, t_n], rtol=1e-10)
    np.testing.assert_allclose(out["twines"], np.array([[-p, q, 0], [-p, -q, 0], [r, 0, 0]]) @ R.T, atol=1e-14)


def test_a_slack_twine_leaves_the_other_two_in_line(rng):
    # U short, V long: n (= U/2 from the midpoint of l-m) is slack, so l and m pull in line with the knot at
    # the middle of P_l P_m: theta = (1/2, 0), T_l = T_m = EA (|V|/2 - l0)/l0, T_n = 0, with no compression
    U, V = np.array([0.02, 0.0, 0.0]), np.array([0.0, 0.05, 0.0])
    l0 = np.full(3, 0.02)
    uv = random_uv(rng, False)
    x = element_from_mesh(rng, U, V, uv)
    out = report(x, uv, l0, EA, None)
    np.testing.assert_allclose(out["theta"], [0.5, 0.0], atol=1e-13)
    np.testing.assert_allclose(out["tensions"], [375.0, 375.0, 0.0], rtol=1e-12, atol=1e-12)
    # and the stiffness there (n slack, l and m taut) is still exact
    check_stiffness_by_finite_differences(x, uv, l0, None, out["stiffness"])


def test_book_489_holds_at_the_knot_and_490_needs_its_radicands_fixed(rng):
    # 4.89-4.90 (element turned into XOY, unknown m): sum of EA_i/l0_i (|i| - l0_i) i/|i| with l = m + V and
    # n = m + (U+V)/2. At the solved knot 4.89 vanishes; 4.90 as printed has (m_y+V_y)² + (m_y+V_y)²,
    # m_y² + m_y², ... under its roots, and only the x² + y² radicands make it vanish.
    # 4.89-4.90 balance three twines all in tension (EA/l0 (|i| - l0) each). Flattening the mesh into XOY
    # shortens its twines, slackening one in about half of the draws (the model's slack twine carries nothing,
    # not the book's compression): drawn again until all three are taut at the knot
    while True:
        U, V = random_mesh(rng)
        U, V = U * [1, 1, 0], V * [1, 1, 0]  # in the XOY plane
        uv = random_uv(rng, False)
        out = report(element_from_mesh(rng, U, V, uv), uv, L0, EA, None)
        if np.all(np.linalg.norm(out["twines"], axis=1) / L0 - 1 > 1e-3):
            break
    mx, my = out["twines"][1, :2]
    W = (U + V) / 2
    vectors = [(mx + V[0], my + V[1]), (mx, my), (mx + W[0], my + W[1])]
    ea, l0 = np.asarray(EA), np.asarray(L0)

    def term(i, component, root):
        return vectors[i][component] / np.hypot(*vectors[i]) * ea[i] / l0[i] * (root - l0[i])

    eq_489 = sum(term(i, 0, np.hypot(*vectors[i])) for i in range(3))
    eq_490 = sum(term(i, 1, np.hypot(*vectors[i])) for i in range(3))
    printed_490 = sum(term(i, 1, np.sqrt(2) * abs(vectors[i][1])) for i in range(3))
    scale = np.abs(out["tensions"]).sum()
    assert abs(eq_489) < 1e-11 * scale and abs(eq_490) < 1e-11 * scale
    assert abs(printed_490) > 1e-3 * scale


def test_book_newton_matrix_4101_is_minus_the_jacobian(rng):
    # 4.99 F(m) = sum EA/l0² (|i| - l0) i (approximate balance 4.95-4.96); 4.102-4.104 print
    # D11 = -[EA/l0² (|l| - l0 + l_x²/|l|) + ...]: that is -dF/dm, so 4.101 "F' = D" should read F' = -D
    # (4.105, h = D^-1 F, is then the Newton step of 4.97). 4.105's second component prints D22 F2 where
    # the inverse of D has D11 F2.
    U, V = random_mesh(rng)
    U, V = U[:2], V[:2]
    W = (U + V) / 2
    ea, l0 = np.asarray(EA), np.asarray(L0)

    def F(m):
        twines = jnp.stack([m + V, m, m + W])
        return jnp.sum((ea / l0**2 * (jnp.linalg.norm(twines, axis=1) - l0))[:, None] * twines, axis=0)

    m = -(U + V) / 4 + 0.002 * rng.normal(size=2)  # a knot near its place
    twines = np.stack([m + V, m, m + W])
    lengths = np.linalg.norm(twines, axis=1)
    c = ea / l0**2
    D11 = -np.sum(c * (lengths - l0 + twines[:, 0] ** 2 / lengths))
    D12 = -np.sum(c * twines[:, 0] * twines[:, 1] / lengths)
    D22 = -np.sum(c * (lengths - l0 + twines[:, 1] ** 2 / lengths))
    D = np.array([[D11, D12], [D12, D22]])
    np.testing.assert_allclose(D, -jax.jacfwd(F)(jnp.asarray(m)), rtol=1e-12)
    F1, F2 = np.asarray(F(jnp.asarray(m)))
    det = D22 * D11 - D12 * D12
    h = np.linalg.solve(D, [F1, F2])
    np.testing.assert_allclose((D22 * F1 - D12 * F2) / det, h[0], rtol=1e-12)
    assert abs((D22 * F2 - D12 * F1) / det - h[1]) > 1e-6 * np.abs(h).max()
    np.testing.assert_allclose((D11 * F2 - D12 * F1) / det, h[1], rtol=1e-12)


# -- forces --------------------------------------------------------------------------------------------


def coordinate_steps(h):
    """The 9 steps of size h on one vertex coordinate each, then their opposites: (18, 3, 3)."""
    steps = h * np.eye(9).reshape(9, 3, 3)
    return np.concatenate([steps, -steps])


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize("ea_c", [None, EA_C])
def test_force_is_minus_gradient_of_energy(clockwise, ea_c, rng):
    for _ in range(3):
        x, uv = random_element(rng, clockwise) if ea_c is not None else taut_element(rng, clockwise)
        h = 1e-7
        e, _ = batch_energy_force(x + coordinate_steps(h), uv, L0, EA, ea_c)
        fd = -(e[:9] - e[9:]) / (2 * h)
        force = report(x, uv, L0, EA, ea_c)["force"].ravel()
        np.testing.assert_allclose(force, fd, rtol=1e-6, atol=1e-7 * np.abs(fd).max())


@pytest.mark.parametrize("clockwise", [False, True])
def test_forces_are_the_book_4113_up_to_the_sign_of_d(clockwise, rng):
    # 4.106-4.113: F_U = T_l - T_m, F_V = -T_n (tension vectors along l, m, n away from the knot),
    # T_ij = (U_j - U_i) F_U + (V_j - V_i) F_V, F_1 = (T_12 + T_31)/2 ...; for d < 0 the sign flips
    for _ in range(3):
        x, uv = random_element(rng, clockwise)
        out = report(x, uv, L0, EA, EA_C)
        twines = out["twines"]
        tl, tm, tn = out["tensions"][:, None] * twines / jnp.linalg.norm(twines, axis=1)[:, None]
        f_u, f_v = tl - tm, -tn
        Ui, Vi = uv[:, 0], uv[:, 1]
        side = {(i, j): (Ui[j] - Ui[i]) * f_u + (Vi[j] - Vi[i]) * f_v for i, j in ((0, 1), (1, 2), (2, 0))}
        book = jnp.stack([
            (side[0, 1] + side[2, 0]) / 2,
            (side[1, 2] + side[0, 1]) / 2,
            (side[2, 0] + side[1, 2]) / 2,
        ])
        d = geometry.twine_determinant(uv)
        np.testing.assert_allclose(out["force"], jnp.sign(d) * book, rtol=1e-9, atol=1e-9 * np.abs(book).max())


def test_rigid_motions_give_no_force(rng):
    x, uv = taut_element(rng)
    out = report(x, uv, L0, EA, None)
    F, K = out["force"], out["stiffness"]
    R, c = random_rotation(rng), rng.normal(size=3)
    moved = report(x @ R.T + c, uv, L0, EA, None)
    np.testing.assert_allclose(moved["energy"], out["energy"], rtol=1e-12)
    np.testing.assert_allclose(moved["force"], F @ R.T, atol=1e-10 * np.abs(F).max())
    # the element is in equilibrium as a whole: no resultant force, no resultant moment
    np.testing.assert_allclose(F.sum(axis=0), 0.0, atol=1e-11 * np.abs(F).max())
    np.testing.assert_allclose(jnp.cross(x, F).sum(axis=0), 0.0, atol=1e-11 * np.abs(F).max())
    # tangent: a translation changes no force; a rotation omega turns them, K (omega ^ x) = -omega ^ F
    np.testing.assert_allclose(K @ np.tile(c, 3), 0.0, atol=1e-10 * np.abs(K).max())
    omega = rng.normal(size=3)
    np.testing.assert_allclose(K @ np.cross(omega, x).ravel(), -np.cross(omega, F).ravel(), rtol=1e-8, atol=1e-8 * np.abs(F).max())


# -- stiffness -----------------------------------------------------------------------------------------


def check_stiffness_by_finite_differences(x, uv, l0, ea_c, K):
    h = 1e-6
    _, f = batch_energy_force(x + coordinate_steps(h), uv, l0, EA, ea_c)
    f = np.asarray(f).reshape(18, 9)
    fd = -(f[:9] - f[9:]).T / (2 * h)  # K = -dF/dx, column j from a step on coordinate j
    np.testing.assert_allclose(K, fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
    np.testing.assert_allclose(K, K.T, atol=1e-9 * np.abs(K).max())


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize("ea_c", [None, EA_C])
def test_jacfwd_stiffness_equals_finite_differences_of_forces(clockwise, ea_c, rng):
    checked = 0
    while checked < 3:
        x, uv = random_element(rng, clockwise)
        if np.any(np.abs(strains(x, uv)) < 1e-3):  # a twine at its rest length is a kink of the energy
            continue
        check_stiffness_by_finite_differences(x, uv, L0, ea_c, report(x, uv, L0, EA, ea_c)["stiffness"])
        checked += 1


@jax.jit
def schur_stiffness(x, uv, theta):
    """E_xx - E_x,theta H^-1 E_theta,x of the element energy written with a free knot theta."""

    def free_knot(y, th):
        U, V, d = geometry.twine_vectors(y.reshape(3, 3), uv)
        return hx.family_twine_count(d) * hx.knot_energy(th, U, V, L0, EA)

    Kxx = jax.hessian(free_knot, argnums=0)(x.ravel(), theta)
    Kxt = jax.jacfwd(jax.grad(free_knot, argnums=0), argnums=1)(x.ravel(), theta)
    Ktt = jax.hessian(free_knot, argnums=1)(x.ravel(), theta)
    return Kxx - Kxt @ jnp.linalg.solve(Ktt, Kxt.T), Kxx


def test_stiffness_includes_the_knot_motion(rng):
    # exact stiffness = frozen-knot stiffness minus E_x,theta H^-1 E_theta,x (the knot follows the vertices);
    # the correction is not small: the frozen-knot stiffness, which the book's forces suggest, is wrong
    x, uv = random_element(rng, spread=0.4)
    while np.any(strains(x, uv) < 1e-3):  # all taut: the knot is then unique
        x, uv = random_element(rng, spread=0.4)
    out = report(x, uv, L0, EA, None)
    schur, frozen = schur_stiffness(x, uv, out["theta"])
    K = out["stiffness"]
    np.testing.assert_allclose(K, schur, rtol=1e-9, atol=1e-9 * np.abs(K).max())
    assert np.abs(K - frozen).max() > 1e-2 * np.abs(K).max()


def test_energy_is_differentiable_in_the_twine_parameters(rng):
    # design sensitivities: d E / d l0 and d E / d EA through the knot solve, against finite differences
    x, uv = random_element(rng)
    grads = jax.jit(jax.grad(hx.hexagonal_energy, argnums=(2, 3)))(x, uv, L0, EA, EA_C)
    for arg, g, h in ((2, grads[0], 1e-9), (3, grads[1], 1e-4)):
        fd = []
        for i in range(3):
            plus, minus = [L0.copy(), EA.copy()], [L0.copy(), EA.copy()]
            plus[arg - 2][i] += h
            minus[arg - 2][i] -= h
            fd.append((report(x, uv, *plus, EA_C)["energy"] - report(x, uv, *minus, EA_C)["energy"]) / (2 * h))
        np.testing.assert_allclose(g, fd, rtol=1e-6)


# -- the knot solve ------------------------------------------------------------------------------------

PROBES = 1e-4 * np.array([[1, 0], [-1, 0], [0, 1], [0, -1], [1, 1], [-1, -1], [1, -1], [-1, 1]])


@jax.jit
def knot_report(U, V, eac):
    theta = hx.knot_equilibrium(U, V, L0, EA, eac)
    lengths = jnp.linalg.norm(hx.knot_twines(theta, U, V), axis=1)
    return (
        hx.knot_force(theta, U, V, L0, EA, eac),
        jnp.sum(jnp.abs(EA * (lengths / L0 - 1))),
        hx.knot_energy(theta, U, V, L0, EA, eac),
        hx.knot_energy(theta + PROBES, U, V, L0, EA, eac),
    )


@pytest.mark.parametrize("ea_c", [None, EA_C])
def test_knot_solve_converges_on_strongly_distorted_elements(ea_c, rng):
    # meshes sheared to a few degrees, stretched 3x or crushed to a tenth, in 3-D: the knot is in
    # equilibrium (4.88, resultant at the round-off of the tensions) and at a minimum of the twines' energy
    for _ in range(16):
        angle = rng.uniform(np.deg2rad(3), np.deg2rad(177))
        R = random_rotation(rng)
        U = R @ (rng.uniform(0.005, 0.15) * np.array([1.0, 0.0, 0.0]))
        V = R @ (rng.uniform(0.005, 0.15) * np.array([np.cos(angle), np.sin(angle), 0.0]))
        resultant, scale, f0, probes = knot_report(jnp.asarray(U), jnp.asarray(V), ea_c)
        assert np.linalg.norm(resultant) <= 1e-11 * scale
        assert np.all(probes >= f0 - 1e-14 * abs(f0))


# -- slack and degenerate elements ---------------------------------------------------------------------


def test_slack_element_without_compression_stiffness_is_inert_and_finite(rng):
    # a net crushed below the rest length of every twine: no energy, no force, no stiffness, no NaN;
    # a zero compression stiffness given as numbers behaves the same
    U, V = random_mesh(rng, spread=0.0)
    uv = random_uv(rng, False)
    x = element_from_mesh(rng, 0.4 * U, 0.4 * V, uv)
    for eac in (None, np.zeros(3)):
        out = report(x, uv, L0, EA, eac)
        assert float(out["energy"]) == 0.0
        assert np.all(np.asarray(out["force"]) == 0.0)
        assert np.all(np.asarray(out["stiffness"]) == 0.0)


@pytest.mark.parametrize("ea_c", [None, EA_C])
def test_degenerate_elements_give_no_nan(ea_c, rng):
    # a closed base mesh (U parallel to V), and an element collapsed to a point
    uv = random_uv(rng, False)
    U = np.array([0.05, 0.01, 0.0])
    for x in (element_from_mesh(rng, U, 0.7 * U, uv), jnp.zeros((3, 3))):
        for value in report(x, uv, L0, EA, ea_c).values():
            assert np.all(np.isfinite(np.asarray(value)))
