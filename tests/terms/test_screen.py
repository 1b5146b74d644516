"""Screen models of the hydrodynamic force on netting (jaxnet.terms.screen): coefficients, forces, stiffness."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import geometry
from jaxnet.terms import screen

RHO = 1025.0
L0, DIAMETER = 0.02, 0.0016  # D / l0 = 0.08: Sn = 0.16 / sin(opening) for twines at l0

# Both models as jitted functions of (x, uv, c); "kf" uses the Reynolds-dependent cylinder drag.
MODELS = {
    "loland": jax.jit(lambda x, uv, c: screen.loland_force(x, uv, L0, DIAMETER, c, RHO)),
    "loland1991": jax.jit(
        lambda x, uv, c: screen.loland_force(x, uv, L0, DIAMETER, c, RHO, coefficients=screen.LOLAND_1991)
    ),
    "kf": jax.jit(lambda x, uv, c: screen.kristiansen_faltinsen_force(x, uv, L0, DIAMETER, c, RHO)),
}
JACOBIANS = {name: jax.jit(jax.jacfwd(f)) for name, f in MODELS.items()}
SOLIDITY = jax.jit(screen.solidity)
EFFECTIVE_SOLIDITY = jax.jit(screen.effective_solidity)


def rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def netting(U, V, uv, origin=(0.0, 0.0, 0.0)):
    """Vertex positions of a triangle of netting with twine vectors U, V: x_i = origin + U_i U + V_i V (4.16)."""
    uv = jnp.asarray(uv, dtype=float)
    return jnp.asarray(origin) + uv[:, :1] * jnp.asarray(U) + uv[:, 1:] * jnp.asarray(V), uv


def random_element(rng, clockwise=False):
    """A triangle of netting with random orientation, twines near l0, opening 50-130°, random twine coordinates."""
    frame = rotation(rng)
    opening = math.radians(rng.uniform(50, 130))
    lu, lv = L0 * rng.uniform(0.97, 1.03, size=2)
    U = lu * frame[0]
    V = lv * (math.cos(opening) * frame[0] + math.sin(opening) * frame[1])
    uv = rng.uniform(-6, 6, size=(3, 2))
    while abs(float(geometry.twine_determinant(jnp.asarray(uv)))) < 5.0:
        uv = rng.uniform(-6, 6, size=(3, 2))
    if (float(geometry.twine_determinant(jnp.asarray(uv))) < 0) != clockwise:
        uv = uv[[0, 2, 1]]
    return netting(U, V, uv, origin=rng.normal(size=3) * 0.1)


def random_current(rng):
    return jnp.asarray(rng.normal(size=3)) * 0.6


def square_panel(normal_rotation=np.eye(3), scale=1.0):
    """Unstretched square-mesh triangle (Sn = 2 D / l0 = 0.16) in the plane normal to R e_x."""
    U = normal_rotation @ np.array([0.0, 1.0, 1.0]) * L0 * scale / math.sqrt(2)
    V = normal_rotation @ np.array([0.0, -1.0, 1.0]) * L0 * scale / math.sqrt(2)
    return netting(U, V, [[0.0, 0.0], [12.0, 0.0], [0.0, 9.0]])


# ------------------------------------------------------------------------------------------------ coefficients


@pytest.mark.parametrize(
    "coefficients, sn, theta_deg, cd, cl",
    [
        # 0.04 + (-0.04 + 0.2 - 1.24*0.04 + 13.7*0.008) cos 0 = 0.26; lift 0 at theta = 0
        (screen.AARSNES_1990, 0.2, 0.0, 0.26, 0.0),
        # slope 0.22, cos 30° = 0.8660254; lift amplitude 0.114 - 0.1416 + 0.0808 = 0.0532, sin 60°
        (screen.AARSNES_1990, 0.2, 30.0, 0.04 + 0.22 * 0.8660254038, 0.0532 * 0.8660254038),
        # slope -0.04 + 0.3 - 0.1116 + 0.3699 = 0.5183, cos 60° = 0.5; lift 0.171 - 0.3186 + 0.2727 = 0.1251
        (screen.AARSNES_1990, 0.3, 60.0, 0.299150, 0.1251 * 0.8660254038),
        (screen.AARSNES_1990, 0.3, 90.0, 0.04, 0.0),
        # Løland (1991) set: slope -0.04 + 0.0825 + 0.40875 - 0.07625 = 0.375; lift -0.0125 + 0.14375 - 0.0275
        (screen.LOLAND_1991, 0.25, 45.0, 0.04 + 0.375 * 0.7071067812, 0.10375),
    ],
)
def test_loland_coefficients_by_hand(coefficients, sn, theta_deg, cd, cl):
    got_cd, got_cl = screen.loland_coefficients(sn, math.radians(theta_deg), coefficients)
    np.testing.assert_allclose([got_cd, got_cl], [cd, cl], rtol=1e-9, atol=1e-12)


def test_kristiansen_faltinsen_coefficients_by_hand():
    # Sn = 0.2, Cd_cyl = 1.2: Cd(0) = 1.2*0.2*1.8/(2*0.64) = 0.3375; Cn* = 0.24/1.28 = 0.1875;
    # Ct = pi*0.1875/8.1875 = 0.0719448699; Cl(45°) = (0.16875 - 0.0719448699)/sqrt 2 = 0.0684515639
    sn, cyl = 0.2, 1.2
    np.testing.assert_allclose(screen.kristiansen_faltinsen_normal_drag(sn, cyl), 0.3375, rtol=1e-12)
    np.testing.assert_allclose(screen.kristiansen_faltinsen_lift_45(sn, cyl), 0.0684515639, rtol=1e-9)
    cd0, cl45 = 0.3375, 0.0684515639
    for theta_deg in (0.0, 30.0, 45.0, 72.0, 90.0):
        t = math.radians(theta_deg)
        # the published Fourier form, in angles (the module evaluates polynomials in cos theta instead)
        cd = cd0 * (0.9 * math.cos(t) + 0.1 * math.cos(3 * t))
        cl = cl45 * (1.0 * math.sin(2 * t) + 0.1 * math.sin(4 * t))
        got = screen.kristiansen_faltinsen_coefficients(sn, t, cyl)
        np.testing.assert_allclose(got, [cd, cl], rtol=1e-9, atol=1e-12)
    # 30° by hand: 0.3375 (0.9*0.8660254 + 0) = 0.2630552164; 0.0684515639 * 1.1 * 0.8660254 = 0.0652088726
    np.testing.assert_allclose(
        screen.kristiansen_faltinsen_coefficients(sn, math.radians(30.0), cyl), [0.2630552164, 0.0652088726], rtol=1e-9
    )


def test_cylinder_drag_fit_and_its_clamp():
    # sum_k c_k 3^k = 1.00523 (Re = 1e3), sum_k c_k 2^k = 1.36087 (Re = 100), evaluated in exact arithmetic
    np.testing.assert_allclose(screen.cylinder_drag_coefficient(1e3), 1.00523, rtol=1e-9)
    np.testing.assert_allclose(screen.cylinder_drag_coefficient(1e2), 1.36087, rtol=1e-9)
    lo, hi = screen.CYLINDER_DRAG_LOG10_RE_RANGE
    np.testing.assert_allclose(screen.cylinder_drag_coefficient(1.0), screen.cylinder_drag_coefficient(10**lo))
    np.testing.assert_allclose(screen.cylinder_drag_coefficient(1e7), screen.cylinder_drag_coefficient(10**hi))
    # still water: finite value and derivative
    value, slope = jax.value_and_grad(screen.cylinder_drag_coefficient)(0.0)
    assert np.isfinite(value) and float(slope) == 0.0
    # 0.5 m/s, D = 2 mm, Sn = 0.2, nu = 1e-6: 0.5*0.002/(1e-6*0.8) = 1250
    np.testing.assert_allclose(screen.twine_reynolds_number(0.5, 0.002, 0.2, 1e-6), 1250.0, rtol=1e-12)


def test_velocity_reduction_factor():
    # Løland: r = 1 - 0.46 Cd; Cd(0) at Sn = 0.2 is 0.26 -> 0.8804; floored at 0
    np.testing.assert_allclose(screen.velocity_reduction_factor(0.26), 0.8804, rtol=1e-12)
    cd0, _ = screen.loland_coefficients(0.2, 0.0)
    np.testing.assert_allclose(screen.velocity_reduction_factor(cd0), 0.8804, rtol=1e-12)
    assert float(screen.velocity_reduction_factor(3.0)) == 0.0


# ------------------------------------------------------------------------------------------------ solidity


@pytest.mark.parametrize("clockwise", [False, True])
def test_solidity_of_a_deformed_mesh(clockwise):
    # Sn = |d| D l0 / S = 2 D l0 / (|U| |V| sin(opening)); 2 D / l0 for unstretched square meshes
    for opening_deg, stretch in ((90.0, 1.0), (60.0, 1.02), (25.0, 0.98)):
        b = math.radians(opening_deg)
        U = np.array([1.0, 0.0, 0.0]) * L0 * stretch
        V = np.array([math.cos(b), math.sin(b), 0.0]) * L0
        uv = [[0.0, 0.0], [7.0, 1.0], [2.0, 5.0]] if not clockwise else [[0.0, 0.0], [2.0, 5.0], [7.0, 1.0]]
        x, uv = netting(U, V, uv)
        expected = 2 * DIAMETER * L0 / (L0 * stretch * L0 * math.sin(b))
        np.testing.assert_allclose(SOLIDITY(x, uv, L0, DIAMETER), expected, rtol=1e-12)
    x, uv = square_panel()
    np.testing.assert_allclose(SOLIDITY(x, uv, L0, DIAMETER), 2 * DIAMETER / L0, rtol=1e-12)


def test_effective_solidity_is_exact_when_open_and_capped_when_closing():
    x, uv = square_panel()
    np.testing.assert_allclose(EFFECTIVE_SOLIDITY(x, uv, L0, DIAMETER), 0.16, rtol=1e-12)
    # closing meshes: geometric Sn = 0.16 / sin(opening) grows without bound; the capped one stays < 0.5
    previous = 0.0
    for opening_deg in (60.0, 30.0, 15.0, 5.0, 1.0, 0.01):
        b = math.radians(opening_deg)
        x, uv = netting([L0, 0, 0], [L0 * math.cos(b), L0 * math.sin(b), 0], [[0, 0], [5, 0], [0, 5]])
        sn = float(EFFECTIVE_SOLIDITY(x, uv, L0, DIAMETER))
        assert previous <= sn <= 0.5
        previous = sn
    assert previous > 0.499
    # fully collapsed element: finite cap and finite derivative
    x = jnp.zeros((3, 3))
    uv = jnp.array([[0.0, 0.0], [5.0, 0.0], [0.0, 5.0]])
    sn, grad = jax.value_and_grad(lambda y: screen.effective_solidity(y, uv, L0, DIAMETER))(x)
    np.testing.assert_allclose(sn, 0.5, rtol=1e-12)
    assert np.all(np.isfinite(grad))


# ------------------------------------------------------------------------------------------------ forces


@pytest.mark.parametrize("model", ["loland", "loland1991", "kf"])
def test_panel_normal_to_the_flow_has_drag_and_no_lift(model, rng):
    # F = 1/2 rho A Cd(0) |c|² along c, one third per vertex; any sign of c relative to the normal
    R = rotation(rng)
    x, uv = square_panel(R)
    area = float(geometry.surface(x))
    sn = 2 * DIAMETER / L0
    for speed in (0.7, -1.3):
        c = jnp.asarray(R[:, 0] * speed)
        if model == "kf":
            cyl = screen.cylinder_drag_coefficient(abs(speed) * DIAMETER / (1.05e-6 * (1 - sn)))
            cd0 = cyl * sn * (2 - sn) / (2 * (1 - sn) ** 2)
        else:
            p = screen.AARSNES_1990 if model == "loland" else screen.LOLAND_1991
            cd0 = 0.04 + (-0.04 + p.drag[0] * sn + p.drag[1] * sn**2 + p.drag[2] * sn**3)
        force = MODELS[model](x, uv, c)
        expected = 0.5 * RHO * area * cd0 * abs(speed) * c
        np.testing.assert_allclose(force.sum(axis=0), expected, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(force, jnp.broadcast_to(expected / 3, (3, 3)), rtol=1e-10, atol=1e-14)


def test_kristiansen_faltinsen_constant_cylinder_drag_normal_panel():
    # Cd_cyl = 1.2 given: Cd(0) = 1.2*0.16*1.84/(2*0.84²) = 0.2503401361
    x, uv = square_panel()
    c = jnp.array([0.9, 0.0, 0.0])
    force = screen.kristiansen_faltinsen_force(x, uv, L0, DIAMETER, c, RHO, cylinder_drag=1.2)
    area = float(geometry.surface(x))
    np.testing.assert_allclose(force.sum(axis=0), [0.5 * RHO * area * 0.2503401361 * 0.81, 0, 0], rtol=1e-9)


@pytest.mark.parametrize("model", ["loland", "kf"])
def test_lift_at_45_degrees_leans_towards_the_downstream_normal(model):
    # panel normal (1, 1, 0)/sqrt 2, flow +x: drag along +x, lift along +y (the downstream normal's side),
    # magnitudes 1/2 rho A |c|² Cd(45°) and 1/2 rho A |c|² Cl(45°); the same for the panel flipped over
    R = np.array([[1.0, -1.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, math.sqrt(2)]]) / math.sqrt(2)  # e_x -> (1,1,0)/√2
    speed = 0.8
    c = jnp.array([speed, 0.0, 0.0])
    sn = 2 * DIAMETER / L0
    if model == "loland":
        cd = 0.04 + (-0.04 + sn - 1.24 * sn**2 + 13.7 * sn**3) / math.sqrt(2)
        cl = 0.57 * sn - 3.54 * sn**2 + 10.1 * sn**3
    else:
        cyl = float(screen.cylinder_drag_coefficient(speed * DIAMETER / (1.05e-6 * (1 - sn))))
        cd0 = cyl * sn * (2 - sn) / (2 * (1 - sn) ** 2)
        cn = cyl * sn / (2 * (1 - sn) ** 2)
        cl45 = (cd0 / 2 - math.pi * cn / (8 + cn)) / math.sqrt(2)
        cd, cl = cd0 * (0.9 - 0.1) / math.sqrt(2), cl45  # cos 45° = -cos 135°; sin 90° = 1, sin 180° = 0
    assert cl > 0
    for flip in (False, True):
        x, uv = square_panel(R)
        if flip:
            x, uv = x[jnp.array([0, 2, 1])], uv[jnp.array([0, 2, 1])]
        area = float(geometry.surface(x))
        total = MODELS[model](x, uv, c).sum(axis=0)
        q = 0.5 * RHO * area * speed**2
        np.testing.assert_allclose(total, [q * cd, q * cl, 0.0], rtol=1e-10, atol=1e-14)


@pytest.mark.parametrize("model", ["loland", "loland1991", "kf"])
def test_force_equals_the_angle_form_on_random_elements(model, rng):
    # independent evaluation of (S1): theta = arccos |n.c|/|c|, e_lift from the downstream normal (as in
    # Cheng et al. 2020), coefficients from the angle formulas, exact |cos| (kink_width=0)
    kwargs = dict(kink_width=0.0)
    for _ in range(6):
        x, uv = random_element(rng, clockwise=bool(rng.integers(2)))
        c = random_current(rng)
        a = np.cross(x[1] - x[0], x[2] - x[0]) / 2
        area, n = np.linalg.norm(a), a / np.linalg.norm(a)
        speed = np.linalg.norm(c)
        n_down = n if n @ c >= 0 else -n
        theta = math.acos(min(1.0, n_down @ c / speed))
        lift_dir = np.cross(np.cross(c, n_down), c)
        lift_dir /= np.linalg.norm(lift_dir)
        sn = float(SOLIDITY(x, uv, L0, DIAMETER))
        if model == "kf":
            cyl = screen.cylinder_drag_coefficient(speed * DIAMETER / (1.05e-6 * (1 - sn)))
            cd, cl = screen.kristiansen_faltinsen_coefficients(sn, theta, cyl)
            force = screen.kristiansen_faltinsen_force(x, uv, L0, DIAMETER, c, RHO, **kwargs)
        else:
            p = screen.AARSNES_1990 if model == "loland" else screen.LOLAND_1991
            cd, cl = screen.loland_coefficients(sn, theta, p)
            force = screen.loland_force(x, uv, L0, DIAMETER, c, RHO, coefficients=p, **kwargs)
        expected = 0.5 * RHO * area * speed**2 * (cd * c / speed + cl * lift_dir)
        np.testing.assert_allclose(force.sum(axis=0), expected, rtol=1e-9, atol=1e-12 * np.abs(expected).max())


@pytest.mark.parametrize("model", ["loland", "kf"])
def test_flipping_the_vertex_order_gives_the_same_force(model, rng):
    for _ in range(5):
        x, uv = random_element(rng)
        c = random_current(rng)
        flipped = jnp.array([0, 2, 1])
        assert float(geometry.twine_determinant(uv)) * float(geometry.twine_determinant(uv[flipped])) < 0
        f = MODELS[model](x, uv, c)
        g = MODELS[model](x[flipped], uv[flipped], c)
        np.testing.assert_allclose(g, f[flipped], rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("model", ["loland", "kf"])
def test_rotating_element_and_current_together_rotates_the_force(model, rng):
    for _ in range(5):
        x, uv = random_element(rng, clockwise=bool(rng.integers(2)))
        c = random_current(rng)
        R = jnp.asarray(rotation(rng))
        f = MODELS[model](x, uv, c)
        g = MODELS[model](x @ R.T, uv, R @ c)
        np.testing.assert_allclose(g, f @ R.T, rtol=1e-10, atol=1e-12 * float(jnp.abs(f).max()))


# ------------------------------------------------------------------------------------------------ stiffness


def central_differences(f, x, uv, c, h=1e-7):
    cols = []
    for i in range(9):
        e = jnp.zeros(9).at[i].set(h).reshape(3, 3)
        cols.append(((f(x + e, uv, c) - f(x - e, uv, c)) / (2 * h)).ravel())
    return np.stack(cols, axis=1)


#: central differences' step (m) per model. K&F's force carries the roundoff of its cylinder drag, a degree-7
#: polynomial in log10 Re evaluated with cancellation (condition number 3e4 at Re ~ 1.5e3), which the differences
#: divide by h: at 1e-7 their error reached 2.4e-6 of the stiffness's largest entry (the tolerance: 1e-6) on some
#: draws; at 1e-6, roundoff and truncation (h² over the square of the kink's scale, 1e-2 of cos theta) together
#: 1.5e-7 at most (150 random elements, 40 rotated panels at theta 0 and 90°). Løland's has no such roundoff: 1e-7.
STEPS = {"loland": 1e-7, "loland1991": 1e-7, "kf": 1e-6}


def assert_jacobian_matches(model, x, uv, c):
    J = np.asarray(JACOBIANS[model](x, uv, c)).reshape(9, 9)
    assert np.all(np.isfinite(J))
    fd = central_differences(MODELS[model], x, uv, c, STEPS[model])
    scale = max(np.abs(fd).max(), 1e-12)
    np.testing.assert_allclose(J, fd, rtol=1e-5, atol=1e-6 * scale)
    return J


@pytest.mark.parametrize("model", ["loland", "loland1991", "kf"])
@pytest.mark.parametrize("clockwise", [False, True])
def test_jacfwd_matches_central_differences_on_random_elements(model, clockwise, rng):
    for _ in range(4):
        x, uv = random_element(rng, clockwise)
        assert_jacobian_matches(model, x, uv, random_current(rng))


@pytest.mark.parametrize("model", ["loland", "kf"])
def test_degenerate_inflows_have_finite_smooth_stiffness(model, rng):
    R = rotation(rng)
    x, uv = square_panel(R)
    normal, in_plane = R[:, 0], R[:, 1] + 0.5 * R[:, 2]
    for clockwise in (False, True):
        xs, uvs = (x[jnp.array([0, 2, 1])], uv[jnp.array([0, 2, 1])]) if clockwise else (x, uv)
        # theta = 0 (e_lift is 0/0 there, Cl = 0): no lift, smooth
        f = MODELS[model](xs, uvs, jnp.asarray(0.8 * normal))
        np.testing.assert_allclose(f.sum(axis=0) - (f.sum(axis=0) @ normal) * normal, 0.0, atol=1e-15)
        assert_jacobian_matches(model, xs, uvs, jnp.asarray(0.8 * normal))
        # theta = 90° (flow in the panel plane): Løland's skin drag 0.04 only, K&F's drag vanishes
        c = jnp.asarray(0.8 * in_plane)
        f = MODELS[model](xs, uvs, c).sum(axis=0)
        area = float(geometry.surface(xs))
        expected = 0.5 * RHO * area * 0.04 * float(jnp.linalg.norm(c)) * c if model == "loland" else 0.0 * c
        np.testing.assert_allclose(f, expected, atol=1e-14)
        assert_jacobian_matches(model, xs, uvs, c)
        # still water: no force, zero stiffness
        f = MODELS[model](xs, uvs, jnp.zeros(3))
        J = JACOBIANS[model](xs, uvs, jnp.zeros(3))
        assert np.all(f == 0.0) and np.all(np.isfinite(J)) and float(jnp.abs(J).max()) == 0.0
    # collapsed element (all vertices together): no force, finite stiffness
    x0 = jnp.zeros((3, 3))
    assert np.all(MODELS[model](x0, uv, jnp.asarray(normal)) == 0.0)
    assert np.all(np.isfinite(JACOBIANS[model](x0, uv, jnp.asarray(normal))))


def test_kink_width_makes_the_stiffness_continuous_across_the_panel_plane():
    # |cos theta| has a kink at 90°: with kink_width=0 the stiffness jumps between theta = 90° -/+ 0.01°,
    # with the default rounding it does not; away from 90° both agree to rounding error
    x, uv = square_panel()
    delta = math.radians(0.01)

    jacobians = {
        width: jax.jit(jax.jacfwd(lambda y, c, w=width: screen.loland_force(y, uv, L0, DIAMETER, c, RHO, kink_width=w)))
        for width in (1e-2, 0.0)
    }

    def jac(theta, width):
        c = jnp.array([math.cos(theta), math.sin(theta), 0.0])
        return np.asarray(jacobians[width](x, c)).reshape(9, 9)

    scale = np.abs(jac(math.pi / 2 - 0.3, 1e-2)).max()
    smooth_jump = np.abs(jac(math.pi / 2 - delta, 1e-2) - jac(math.pi / 2 + delta, 1e-2)).max()
    exact_jump = np.abs(jac(math.pi / 2 - delta, 0.0) - jac(math.pi / 2 + delta, 0.0)).max()
    assert smooth_jump < 0.05 * exact_jump
    assert exact_jump > 0.1 * scale
    c = jnp.array([0.6, 0.3, -0.2])
    exact = screen.loland_force(x, uv, L0, DIAMETER, c, RHO, kink_width=0.0)
    np.testing.assert_allclose(screen.loland_force(x, uv, L0, DIAMETER, c, RHO), exact, rtol=1e-13)
