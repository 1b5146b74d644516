"""Catch pressure (4.246-4.264), the catch front and the enclosed volume (jaxnet.terms.pressure, jaxnet.model.catch)."""

import jax
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet.model import catch
from jaxnet.terms import pressure

AXIS = np.array([1.0, 0.0, 0.0])
P = 2590.175  # ½ 1025 · 1.4 · 1.9², Pa

force = jax.jit(pressure.catch_pressure)
force_jac = jax.jit(jax.jacfwd(pressure.catch_pressure))
force_dfront = jax.jit(jax.jacfwd(pressure.catch_pressure, argnums=2))


def random_triangle(rng):
    return rng.normal(size=(3, 3))


# --------------------------------------------------------------------------------------------------
# One triangle
# --------------------------------------------------------------------------------------------------


def test_dynamic_pressure():
    # 4.246 with FEMNET's c2: rho 1025, Cd 1.4, v 1.9 m/s
    assert float(pressure.dynamic_pressure(1025.0, 1.4, 1.9)) == pytest.approx(2590.175, rel=1e-12)


def test_whole_triangle_gets_a_third_of_p_S_n_per_vertex(rng):
    x = random_triangle(rng)
    front = float(np.min(x[:, 0])) - 1.0  # the whole triangle behind the front
    f = force(x, P, front, AXIS, 1.0)
    (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = np.asarray(x)
    f1 = P / 6.0 * np.array([(y2 - y1) * (z3 - z1) - (z2 - z1) * (y3 - y1),   # 4.252
                             (z2 - z1) * (x3 - x1) - (x2 - x1) * (z3 - z1),   # 4.253
                             (x2 - x1) * (y3 - y1) - (y2 - y1) * (x3 - x1)])  # 4.254
    np.testing.assert_allclose(f, np.tile(f1, (3, 1)), rtol=1e-13)
    np.testing.assert_allclose(np.linalg.norm(f.sum(0)), P * 0.5 * np.linalg.norm(np.cross(x[1] - x[0], x[2] - x[0])),
                               rtol=1e-13)
    np.testing.assert_allclose(force(x, P, front, AXIS, -1.0), -f, rtol=1e-15)
    # a front point instead of an abscissa
    np.testing.assert_allclose(force(x, P, front * AXIS + np.array([0.0, 3.0, -2.0]), AXIS, 1.0), f, rtol=1e-15)


def test_stiffness_of_a_whole_triangle_is_the_books(rng):
    # 4.256-4.264: dF1/dx_j = p/6 (e ^ 23, e ^ 31, e ^ 12)-type vectors, the same for F2 and F3
    x = random_triangle(rng)
    K = force_jac(x, P, -10.0, AXIS, 1.0)  # (3 vertices, 3 comps, 3 vertices, 3 comps)
    (x1, y1, z1), (x2, y2, z2), (x3, y3, z3) = np.asarray(x)
    book = {  # (vertex j, coordinate) -> dF1/d(that coordinate)
        (0, 0): [0, z3 - z2, y2 - y3], (0, 1): [z2 - z3, 0, x3 - x2], (0, 2): [y3 - y2, x2 - x3, 0],
        (1, 0): [0, z1 - z3, y3 - y1], (1, 1): [z3 - z1, 0, x1 - x3], (1, 2): [y1 - y3, x3 - x1, 0],
        (2, 0): [0, z2 - z1, y1 - y2], (2, 1): [z1 - z2, 0, x2 - x1], (2, 2): [y2 - y1, x1 - x2, 0],
    }
    for (j, c), column in book.items():
        for i in range(3):
            np.testing.assert_allclose(K[i, :, j, c], P / 6.0 * np.array(column), rtol=1e-12, atol=1e-9)


@pytest.mark.parametrize("s", [0.0, 0.3, 0.75, 0.999])
def test_cut_triangle_closed_form(s):
    # triangle (0,0,0), (1,0,0), (0,1,0), axis x: behind = {x > s}; N2 = x, N3 = y, N1 = 1 - x - y and
    # ∫ x = 1/6 - s²/2 + s³/3, ∫ y = (1-s)³/6, ∫ 1 = (1-s)²/2 over {x > s} (one vertex behind)
    x = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    i2, i3, i = 1 / 6 - s**2 / 2 + s**3 / 3, (1 - s) ** 3 / 6, (1 - s) ** 2 / 2
    expect = P * np.outer([i - i2 - i3, i2, i3], [0.0, 0.0, 1.0])
    np.testing.assert_allclose(force(x, P, s, AXIS, 1.0), expect, rtol=1e-12, atol=1e-12)
    # the complement (two vertices behind: axis -x, front at -s) takes the rest of the full 1/6 each
    rest = P * np.outer([1 / 6, 1 / 6, 1 / 6], [0, 0, 1]) - expect
    np.testing.assert_allclose(force(x, P, -s, -AXIS, 1.0), rest, rtol=1e-12, atol=1e-12)


def test_forces_are_continuous_when_the_front_crosses_a_vertex(rng):
    eps = 1e-9
    for _ in range(5):
        x = random_triangle(rng)
        for v in range(3):
            sv = float(x[v, 0])
            before, after = force(x, P, sv - eps, AXIS, 1.0), force(x, P, sv + eps, AXIS, 1.0)
            # the jump is the load of a sliver of width eps: O(eps), not a third of an element
            assert np.max(np.abs(after - before)) < 1e3 * P * eps
            # and the tangent too (no chatter): C1 across a vertex
            ka, kb = force_jac(x, P, sv - eps, AXIS, 1.0), force_jac(x, P, sv + eps, AXIS, 1.0)
            np.testing.assert_allclose(ka, kb, atol=1e-4 * P)


def fd_jacobian(f, x, step=1e-6, one_sided=None):
    """Central differences (or forward ones along +/- one_sided per coordinate) of f at x (3, 3)."""
    cols = []
    for k in range(9):
        e = np.zeros(9)
        e[k] = step
        e = e.reshape(3, 3)
        if one_sided is None:
            cols.append((f(x + e) - f(x - e)) / (2 * step))
        else:
            d = float(one_sided.reshape(-1)[k]) or 1.0
            cols.append((f(x + d * e) - f(x)) / (d * step))
    return np.stack(cols, axis=-1).reshape(3, 3, 3, 3)


@pytest.mark.parametrize("case", ["one_behind", "two_behind", "vertex_on_front", "edge_on_front"])
def test_jacfwd_matches_finite_differences(case, rng):
    x = random_triangle(rng)
    order = np.argsort(x[:, 0])
    xs = [float(v) for v in x[order, 0]]
    one_sided = None
    if case == "one_behind":
        front = 0.5 * (xs[1] + xs[2])
    elif case == "two_behind":
        front = 0.5 * (xs[0] + xs[1])
    elif case == "vertex_on_front":
        front = xs[1]  # C1 there: central differences converge, Richardson-extrapolated below
    else:
        x[order[1], 0] = xs[0]  # the edge between the two most upstream vertices lies on the front
        front = xs[0]
        # h = 0 counts as ahead: differentiate toward ahead (-x) for the vertices on the front
        one_sided = np.zeros((3, 3))
        one_sided[order[:2], 0] = -1.0
    f = lambda y: force(y, P, front, AXIS, 1.0)  # noqa: E731
    K = force_jac(x, P, front, AXIS, 1.0)
    assert np.all(np.isfinite(K))
    step = 1e-7 if one_sided is None else 1e-8
    tol = 1e-6 if one_sided is None else 1e-5
    fd = fd_jacobian(f, x, step, one_sided)
    if case == "vertex_on_front":
        # moving the vertex on the front along the axis, the force is C1 but its second derivative jumps (the part
        # cut off grows as h² / (the vertex's axial gaps to the other two)): central differences err by h/4 times
        # that jump, over 1e-6 P on 1 random triangle in 9, up to 6e-5 P; 2 D(h/2) - D(h) removes that term
        # (1.6e-8 P at most over 300 triangles)
        fd = 2 * fd_jacobian(f, x, step / 2) - fd
    np.testing.assert_allclose(K, fd, atol=tol * P)
    # derivative with respect to the front position: the force falls as the front moves back
    dfront = force_dfront(x, P, front, AXIS, 1.0)
    if one_sided is None:
        # central differences, Richardson-extrapolated (2 D(h/2) - D(h)): with a vertex on the front the force is
        # C1 in the front's position but its second derivative jumps there, which leaves an error h/4 times that
        # jump in D(h), up to 1.6 at h = 1e-6 on some random triangles; the extrapolation removes that term
        # (3.6e-5 at most over 300 triangles)
        def central(h):
            return (force(x, P, front + h, AXIS, 1.0) - force(x, P, front - h, AXIS, 1.0)) / (2 * h)

        fd = 2 * central(5e-7) - central(1e-6)
        np.testing.assert_allclose(dfront, fd, atol=1e-6 * P)


def test_triangle_in_the_front_plane_is_finite():
    x = np.array([[2.0, 0.0, 0.0], [2.0, 1.0, 0.0], [2.0, 0.0, 1.0]])
    for sign in (1.0, -1.0):
        f, K = force(x, P, 2.0, AXIS, sign), force_jac(x, P, 2.0, AXIS, sign)
        assert np.all(np.asarray(f) == 0.0) and np.all(np.isfinite(K))
    g = jax.jit(jax.grad(pressure.catch_volume))(x, 2.0, AXIS)
    assert np.all(np.isfinite(g))


# --------------------------------------------------------------------------------------------------
# Meshes: cones and a closed cylinder along x, triangles ordered so that 12 ^ 13 points outward
# --------------------------------------------------------------------------------------------------


def ring_net(n, radii, xs, quarter=False, rear_centre=None, front_cap=False):
    """Rings of n sectors (a quarter: angles 0..pi/2 only, for a model with symmetry planes y = 0 and
    z = 0) at abscissae xs with radii, closed at the rear by a fan onto ``rear_centre`` (3,) and, if
    ``front_cap``, at the front by a fan onto the axis. Returns numpy (x (N, 3), triangles (E, 3))."""
    sectors = n // 4 if quarter else n
    per_ring = sectors + 1 if quarter else n
    theta = 2 * np.pi * np.arange(per_ring) / n
    x = np.concatenate([np.stack([np.full(per_ring, xk), rk * np.cos(theta), rk * np.sin(theta)], 1)
                        for xk, rk in zip(xs, radii)])
    tri = []
    for k in range(len(xs) - 1):
        for j in range(sectors):
            a, b = k * per_ring + j, k * per_ring + (j + 1) % per_ring
            tri += [[a, b, b + per_ring], [a, b + per_ring, a + per_ring]]  # e_theta ^ e_x = e_r: outward
    fans = [(len(xs) - 1, np.asarray(rear_centre), False)]
    if front_cap:
        fans.append((0, np.array([xs[0], 0.0, 0.0]), True))
    for k, centre, flip in fans:
        c = len(x)
        x = np.concatenate([x, centre[None]])
        for j in range(sectors):
            a, b = k * per_ring + j, k * per_ring + (j + 1) % per_ring
            tri.append([a, c, b] if flip else [a, b, c])
    return x, np.array(tri)


def cone(n, rings, radius, length, quarter=False):
    """Cone open at x = 0 (radius ``radius``), apex at x = length (the rear); rings at length k/rings."""
    xs = np.linspace(0.0, length, rings + 1)[:-1]
    return ring_net(n, radius * (1 - xs / length), xs, quarter, rear_centre=[length, 0.0, 0.0])


def polygon_area(n, r):
    """Area of the regular n-gon of circumradius r: the cross-section of the meshed cone or cylinder."""
    return 0.5 * n * r**2 * np.sin(2 * np.pi / n)


N_SECTORS, RADIUS, LENGTH, RINGS = 16, 0.8, 2.0, 8
CONE = cone(N_SECTORS, RINGS, RADIUS, LENGTH)
QUARTER_CONE = cone(N_SECTORS, RINGS, RADIUS, LENGTH, quarter=True)
CYLINDER = ring_net(N_SECTORS, np.full(RINGS + 1, 0.6), np.linspace(0.0, 2.5, RINGS + 1),
                    rear_centre=[2.5, 0.0, 0.0], front_cap=True)
# a generic net: its own generator (drawn once, at import), so nothing module-level is left to draw from
NOISY_CONE = (CONE[0] + np.random.default_rng(20261121).normal(size=CONE[0].shape) * 0.01, CONE[1])

volume = jax.jit(catch.enclosed_volume)
volume_ds = jax.jit(jax.grad(catch.enclosed_volume, argnums=2))
volume_dx = jax.jit(jax.grad(catch.enclosed_volume))
section = jax.jit(catch.front_area)
forces = jax.jit(catch.catch_forces)
front = jax.jit(catch.catch_front)
summary = jax.jit(catch.catch_summary)
NO_GUESS = float("nan")


def test_test_meshes_are_outward():
    # the triangles' 12 ^ 13 points away from a point inside each convex net
    for (x, tri), inside in ((CONE, [0.5, 0, 0]), (QUARTER_CONE, [0.5, 0.1, 0.1]), (CYLINDER, [1.2, 0, 0])):
        xe = np.asarray(x)[np.asarray(tri)]
        A = 0.5 * np.cross(xe[:, 1] - xe[:, 0], xe[:, 2] - xe[:, 0])
        assert np.all(np.sum(A * (xe.mean(axis=1) - np.array(inside)), axis=1) > 0.0)


def test_orientation_sign_pushes_outward_of_a_closed_net():
    x, tri = CYLINDER
    F = forces(x, tri, P, -1.0, AXIS, 1.0)
    # every node is pushed away from the middle of the (convex, closed) net
    assert np.all(np.sum(np.asarray(F) * (np.asarray(x) - np.array([1.25, 0.0, 0.0])), axis=1) > 0.0)
    # inward vertex order with sign -1 (FEMNET's convention) is the same load
    np.testing.assert_allclose(forces(x, tri[:, [0, 2, 1]], P, -1.0, AXIS, -1.0), F, atol=1e-9)


# --------------------------------------------------------------------------------------------------
# Volume, front, summary
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("quarter", [False, True])
def test_cone_volume_front_area_and_front(quarter):
    x, tri = QUARTER_CONE if quarter else CONE
    symmetry = 4.0 if quarter else 1.0
    for s in (0.1, 0.77, 1.0, 1.9):  # 1.0 is on a ring of nodes
        A = polygon_area(N_SECTORS, RADIUS * (LENGTH - s) / LENGTH)
        np.testing.assert_allclose(volume(x, tri, s, AXIS, symmetry, 1.0), A * (LENGTH - s) / 3.0, rtol=1e-12)
        np.testing.assert_allclose(section(x, tri, s, AXIS, symmetry), A, rtol=1e-12)
        np.testing.assert_allclose(-volume_ds(x, tri, s, AXIS, symmetry), A, rtol=1e-12)  # dV/ds = -A
    # the front that holds 0.1 m³ of catch: (L - s)³ = 3 V L² / A(0)
    target = 0.1
    exact = LENGTH - (3.0 * target * LENGTH**2 / polygon_area(N_SECTORS, RADIUS)) ** (1.0 / 3.0)
    res = front(x, tri, AXIS, target, symmetry, 1.0, NO_GUESS)
    assert bool(res.holds) and bool(res.converged)
    np.testing.assert_allclose(res.position, exact, rtol=1e-10)
    np.testing.assert_allclose(res.volume, target, rtol=1e-10)


def test_cylinder_volume_and_orientation_sign():
    x, tri = CYLINDER
    A = polygon_area(N_SECTORS, 0.6)
    outward = np.ones(tri.shape[0])  # one sign per triangle
    for s in (-1.0, 0.4, 1.25, 2.4):  # upstream of the whole closed net: its volume
        np.testing.assert_allclose(volume(x, tri, s, AXIS, 1.0, outward), A * (2.5 - max(s, 0.0)), rtol=1e-12)
    # inward-ordered triangles need sign = -1 for the same volume, also when only some are inward
    np.testing.assert_allclose(volume(x, tri[:, [1, 0, 2]], 0.4, AXIS, 1.0, -outward), A * 2.1, rtol=1e-12)
    flip = np.arange(tri.shape[0]) % 3 == 0
    mixed = np.where(flip[:, None], np.asarray(tri)[:, [1, 0, 2]], tri)
    np.testing.assert_allclose(volume(x, mixed, 0.4, AXIS, 1.0, np.where(flip, -1.0, 1.0)), A * 2.1, rtol=1e-12)
    # orientation matters: all-inward triangles with the outward sign give minus the volume
    np.testing.assert_allclose(volume(x, tri[:, [1, 0, 2]], 0.4, AXIS, 1.0, outward), -A * 2.1, rtol=1e-12)


def test_closed_net_under_pressure_has_no_resultant():
    x, tri = CYLINDER
    F = forces(x, tri, P, -1.0, AXIS, 1.0)  # front upstream of the whole net
    np.testing.assert_allclose(F.sum(0), 0.0, atol=1e-10 * P)
    assert np.max(np.abs(F)) > 10.0
    # cut by the front: the netting behind it is pushed back by p times the front's section (catch drag)
    for s in (0.3, 1.25, 2.0):
        total = forces(x, tri, P, s, AXIS, 1.0).sum(0)
        np.testing.assert_allclose(total, P * polygon_area(N_SECTORS, 0.6) * np.array([1.0, 0.0, 0.0]),
                                   atol=1e-10 * P)


def test_forces_are_p_times_the_volume_gradient():
    # a closed catch: the consistent pressure load is conservative, F = p dV/dx at a fixed front
    x, tri = NOISY_CONE
    for s in (0.2, 0.83):
        np.testing.assert_allclose(forces(x, tri, P, s, AXIS, 1.0), P * volume_dx(x, tri, s, AXIS),
                                   atol=1e-10 * P)


def test_assembled_tangent_is_finite_with_a_ring_of_nodes_on_the_front(rng):
    # front at x = 1.0, the abscissa of a ring: vertices and whole edges lie in the front plane
    x, tri = CONE
    dx = rng.normal(size=x.shape)
    f, df = jax.jit(lambda y, d: jax.jvp(lambda z: catch.catch_forces(z, tri, P, 1.0, AXIS, 1.0), (y,), (d,)))(x, dx)
    assert np.all(np.isfinite(f)) and np.all(np.isfinite(df)) and np.max(np.abs(df)) > 0.0
    # the forces are continuous across it
    near = forces(x, tri, P, 1.0 + 1e-10, AXIS, 1.0)
    np.testing.assert_allclose(near, f, atol=1e-6)


def test_front_when_the_net_cannot_hold_the_catch():
    x, tri = CONE
    full = polygon_area(N_SECTORS, RADIUS) * LENGTH / 3.0
    res = front(x, tri, AXIS, 1.5 * full, 1.0, 1.0, NO_GUESS)
    assert not bool(res.holds)
    assert float(res.position) == 0.0  # the most upstream node
    np.testing.assert_allclose(res.volume, full, rtol=1e-12)
    empty = front(x, tri, AXIS, 0.0, 1.0, 1.0, NO_GUESS)
    assert bool(empty.holds) and float(empty.position) == LENGTH
    # a warm start converges to the same front
    res = front(x, tri, AXIS, 0.3 * full, 1.0, 1.0, 1.9)
    assert bool(res.converged)
    np.testing.assert_allclose(volume(x, tri, float(res.position), AXIS, 1.0, 1.0), 0.3 * full, rtol=1e-10)


def test_a_front_started_near_its_solution_takes_fewer_passes(rng):
    # the solver's evaluations start the front from the last iterate's (jaxnet.model.catch.catch_state): the same front,
    # to the tolerance, in fewer passes over the elements than from the middle of the net
    x, tri = NOISY_CONE
    full = float(volume(x, tri, 0.0, AXIS, 1.0, 1.0))
    cold = front(x, tri, AXIS, 0.4 * full, 1.0, 1.0, NO_GUESS)
    moved = x + 1e-3 * rng.normal(size=x.shape)  # the next iterate
    again = front(moved, tri, AXIS, 0.4 * full, 1.0, 1.0, NO_GUESS)
    warm = front(moved, tri, AXIS, 0.4 * full, 1.0, 1.0, float(cold.position))
    assert bool(again.converged) and bool(warm.converged)
    np.testing.assert_allclose(warm.position, again.position, rtol=0, atol=1e-9 * LENGTH)
    assert int(warm.passes) <= 4 < int(again.passes), (int(warm.passes), int(again.passes))


def test_front_position_derivative(rng):
    x, tri = NOISY_CONE
    position = lambda y, v: catch.catch_front(y, tri, AXIS, v).position  # noqa: E731
    pos_and_grads = jax.jit(jax.value_and_grad(position, argnums=(0, 1)))
    target = 0.1
    s, (g_x, g_v) = pos_and_grads(x, target)
    # d s / d volume = -1 / front area
    np.testing.assert_allclose(g_v, -1.0 / section(x, tri, float(s), AXIS, 1.0), rtol=1e-9)
    # d s / d x (reverse mode through the implicit jvp) along a random direction, by central differences
    dx = rng.normal(size=x.shape)
    fd = (pos_and_grads(x + 1e-6 * dx, target)[0] - pos_and_grads(x - 1e-6 * dx, target)[0]) / 2e-6
    np.testing.assert_allclose(np.sum(g_x * dx), fd, rtol=1e-6)


def test_catch_summary_of_a_cone():
    x, tri = QUARTER_CONE
    s = 0.9
    out = summary(x, tri, AXIS, s, P, 4.0, 1.0, np.zeros(3))  # pressure, symmetry, sign, center
    A = polygon_area(N_SECTORS, RADIUS * (LENGTH - s) / LENGTH)
    np.testing.assert_allclose(out.volume, A * (LENGTH - s) / 3.0, rtol=1e-12)
    np.testing.assert_allclose(out.front_area, A, rtol=1e-12)
    np.testing.assert_allclose(out.drag, P * A, rtol=1e-12)
    np.testing.assert_allclose(out.thickness, LENGTH - s, rtol=1e-12)
    # the widest nodes on or behind the front: the first ring behind it (rings every 0.25 m: x = 1.0)
    np.testing.assert_allclose(out.diameter, 2 * RADIUS * (1 - 1.0 / LENGTH), rtol=1e-12)
    # a whole cone, shifted off the origin, without a centre: half the extent of those nodes
    x, tri = CONE
    whole = summary(x + np.array([0.0, 3.0, -1.0]), tri, AXIS, s, P, 1.0, 1.0, None)
    np.testing.assert_allclose(whole.diameter, 2 * RADIUS * (1 - 1.0 / LENGTH), rtol=1e-12)
    np.testing.assert_allclose(whole.volume, out.volume, rtol=1e-12)
