"""The error-controlled reference integrator (diffrax): closed forms (a mass on a spring, an elastic
pendulum against scipy), its convergence with the tolerance, the book scheme's first-order error measured
against it, a small net in a current, the sparse stage Jacobian, and its errors.

The spring and the pendulum are one node on a bar under gravity, free in x and z: the same terms and the
same number of states, so they share one compiled program (compiling dominates this file's runtime)."""

import functools

import numpy as np
import jax
import jax.numpy as jnp
import equinox as eqx
import pytest
from scipy.integrate import solve_ivp

import jaxnet  # noqa: F401  (float64)
from jaxnet import model as model_lib
from jaxnet.water import forcing
from jaxnet.scene import Bars, Environment, Nodes, Scene
from jaxnet.solve import dynamics, reference, statics
from jaxnet.solve.options import Newton
from panels import SMOOTH  # tests/panels.py

G = 9.81
SAVES = 41  # every spring/pendulum run saves this many times: one compiled program for all


def body_on_bar(position, m=2.0, L=1.0, ea=800.0):
    """A body of mass m at ``position`` on a bar of rest length L held at the origin, free in x and z,
    under gravity along -z. The bar is thin (1 µm) and nearly weightless, so its mass, weight and buoyancy
    (< 1e-11 N) are negligible: the stiffness is k = EA/L, the load m g."""
    pos = np.array([[0.0, 0.0, 0.0], position], dtype=float)
    fixed = np.array([[True, True, True], [False, True, False]])
    nodes = Nodes(position=pos, fixed=fixed, mass=np.array([0.0, m]), volume=np.zeros(2), force=np.zeros((2, 3)))
    bars = Bars(ends=np.array([[0, 1]]), rest_length=np.array([L]), ea_traction=np.array([ea]),
                ea_compression=np.array([ea]), diameter=np.array([1e-6]), density=np.array([1e-9]), cable=np.array([0]))
    return Scene(nodes=nodes, bars=bars, environment=Environment(gravity=G, added_mass_coefficient=0.0))


def vertical_spring(m=2.0, L=1.0, ea=800.0, delta=0.01):
    """The body hanging at its static stretch m g/k plus ``delta`` below it, at rest: it oscillates along z
    as z(t) = -(L + m g/k) - delta cos(ω t), ω = sqrt(k/m). Returns (scene, ω, the closed form of z)."""
    k = ea / L
    omega = np.sqrt(k / m)
    centre = -(L + m * G / k)
    scene = body_on_bar([0.0, 0.0, centre - delta], m, L, ea)
    return scene, omega, lambda t: centre - delta * np.cos(omega * t)


def test_spring_matches_its_closed_form_and_converges_with_the_tolerance():
    scene, omega, exact = vertical_spring()
    period = 2 * np.pi / omega
    ts = np.linspace(0.0, 2 * period, SAVES)
    errors, steps = [], []
    tolerances = (1e-7, 1e-8, 1e-9, 1e-10)
    for rtol in tolerances:
        tr = reference.reference(scene, ts[-1], saveat=ts, rtol=rtol, atol=1e-3 * rtol)
        assert tr.linear_solver == "sparse" and tr.solver == "Kvaerno5"
        np.testing.assert_allclose(tr.times, ts)
        np.testing.assert_allclose(tr.positions[:, 0], 0.0)  # the held end, filled in
        np.testing.assert_allclose(tr.positions[:, 1, 0:2], 0.0, atol=1e-13)  # no sideways motion
        z = tr.positions[:, 1, 2]
        errors.append(np.abs(z - exact(ts)).max())
        # the velocity too: dz/dt = delta ω sin(ω t)
        np.testing.assert_allclose(tr.velocities[:, 1, 2], 0.01 * omega * np.sin(omega * ts), rtol=0,
                                   atol=20 * rtol)
        steps.append(tr.steps_accepted)
    # |z| ~ 1 m, so rtol is the local error allowed (m); the global error stays below it over two periods and
    # falls nearly in proportion (measured 11, 8.4, 7.8 per decade). (Looser tolerances are capped by the
    # steps landing on the 41 save times: at rtol >= 1e-5 the error stays 1.8e-7.)
    errors = np.array(errors)
    assert np.all(errors < np.array(tolerances))
    assert np.all(errors[:-1] / errors[1:] > 5)
    assert np.all(np.diff(steps) > 0)


def rigid_pendulum_angle(theta0, length, ts):
    """θ(t) of the rigid pendulum θ'' = -(g/L) sin θ from rest at θ0 (scipy, rtol 1e-12)."""
    sol = solve_ivp(lambda t, y: [y[1], -G / length * np.sin(y[0])], (0, ts[-1]), [theta0, 0.0], t_eval=ts,
                    method="DOP853", rtol=1e-12, atol=1e-14)
    return sol.y[0]


def test_pendulum_against_scipy():
    """A body on a stiff bar (k = 1e5 N/m, radial ω = 224 rad/s vs the swing's 3.1 rad/s) swinging from
    0.5 rad: (1) the same ODE, (x, z)'' = -k/m (r - L) r̂ - g ẑ, solved by scipy at rtol 1e-12 agrees with
    the reference to its tolerance; (2) the rigid pendulum agrees to the bar's stretch: the bar is longer by
    ε L, ε = m g/(k L) = 9.8e-5, slowing the swing by ε/2 in frequency, a drift of θ0 ω t ε/2 in angle."""
    m, L, ea, theta0 = 2.0, 1.0, 1e5, 0.5
    k = ea / L
    r0 = L + m * G * np.cos(theta0) / k  # the bar at its radial equilibrium at rest: the stiff mode is quiet
    start = np.array([r0 * np.sin(theta0), 0.0, -r0 * np.cos(theta0)])
    scene = body_on_bar(start, m, L, ea)
    ts = np.linspace(0.0, 2.0, SAVES)
    tr = reference.reference(scene, ts[-1], saveat=ts, rtol=1e-8, atol=1e-11)

    def elastic(t, y):
        r = y[:2]
        n = np.linalg.norm(r)
        return np.concatenate([y[2:], -k / m * (n - L) * r / n - np.array([0.0, G])])

    exact = solve_ivp(elastic, (0, ts[-1]), [start[0], start[2], 0.0, 0.0], t_eval=ts, method="DOP853",
                      rtol=1e-12, atol=1e-14)
    xz = tr.positions[:, 1][:, [0, 2]]
    # measured 9e-10 m and 1.3e-7 m/s (the velocities carry the radial vibration at 224 rad/s)
    np.testing.assert_allclose(xz, exact.y[:2].T, rtol=0, atol=1e-8)
    np.testing.assert_allclose(tr.velocities[:, 1][:, [0, 2]], exact.y[2:].T, rtol=0, atol=1e-6)
    theta = np.arctan2(xz[:, 0], -xz[:, 1])
    eps = m * G / (k * L)
    drift = theta0 * np.sqrt(G / L) * ts[-1] * eps / 2
    rigid = rigid_pendulum_angle(theta0, L, ts)
    # measured 3.21e-4 rad for a predicted 3.07e-4: the stretch is seen, far above the reference's error
    assert 0.5 * drift < np.abs(theta - rigid).max() < 2 * drift


def test_book_scheme_error_is_first_order_against_the_reference():
    """Backward differences damp the spring's amplitude by (1 + ω²Δt²)^(-1/2) per step, by exp(-ω²Δt t/2)
    after time t: an error delta (1 - exp(-ω²Δt t/2)) ~ delta ω²Δt t/2, proportional to Δt while that
    exponent is small (0.12 after one period at 160 steps a period). Against a tight reference the error
    halves with Δt (ratio 2 - ω²Δt t/4: 1.89, 1.94 here)."""
    scene, omega, exact = vertical_spring()
    period = 2 * np.pi / omega
    ts = np.linspace(0.0, period, SAVES)
    ref = reference.reference(scene, ts[-1], saveat=ts, rtol=1e-10, atol=1e-13)
    assert np.abs(ref.positions[:, 1, 2] - exact(ts)).max() < 1e-9
    newton = Newton(tol=1e-9, max_iter=30, damping=1e-12, stall_window=None)
    errors = []
    for n in (160, 320, 640):
        book = dynamics.simulate(scene, ts[-1], dynamics.Implicit(time_step=period / n, newton=newton),
                                 record_every=ts[1])
        np.testing.assert_allclose(book.times, ts, rtol=0, atol=1e-12)
        errors.append(np.abs(book.positions[:, 1, 2] - ref.positions[:, 1, 2]).max())
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 2 - omega**2 * (period / np.array([320, 640])) * period / 4, rtol=0.03)
    # the damping predicts its size (the period's lengthening, O(Δt²), adds little)
    assert errors[-1] == pytest.approx(0.01 * (1 - np.exp(-omega**2 * (period / 640) * period / 2)), rel=0.1)


def test_stiff_spring_is_resolved():
    """EA = 1e9 N on 2 kg (ω = 2.2e4 rad/s, the stiff end of twines and ropes): ten periods of the free
    oscillation, resolved by the error control (the L-stable method does not damp what it resolves)."""
    scene, omega, exact = vertical_spring(ea=1e9, delta=1e-6)
    ts = np.linspace(0.0, 10 * 2 * np.pi / omega, SAVES)
    tr = reference.reference(scene, ts[-1], saveat=ts, rtol=1e-8, atol=1e-12)
    # measured 2e-12 m: the amplitude 1e-6 m kept to 1e-3 of itself (implicit Euler at the same steps would
    # have damped it away)
    np.testing.assert_allclose(tr.positions[:, 1, 2], exact(ts), rtol=0, atol=1e-9)
    assert tr.steps_accepted > 10 * 10  # it does resolve the oscillation, > 10 steps a period


@functools.lru_cache(maxsize=1)
def _net_in_a_current(meshes=4):
    """The hanging panel (15 nodes, 78 states at meshes=4) at rest at its still-water equilibrium, a current of
    0.7 m/s rising over 0.1 s (half-cosine ramp: the drag comes on smoothly)."""
    from jaxnet.scenes.panel import hanging_panel

    net = hanging_panel(meshes=meshes, step=0.05, **SMOOTH).net
    net.environment = Environment(current_speed=0.0, current_direction=np.array([1.0, 0.2, 0.0]))
    rest = statics.solve(net.build(), tol=1e-10)
    net.environment = Environment(current_speed=0.7, current_direction=np.array([1.0, 0.2, 0.0]))
    scene = eqx.tree_at(lambda s: s.nodes.position, net.build(), np.asarray(rest.x))
    return scene, dynamics.Loading(current_speed=forcing.Ramp(0.0, 0.7, 0.0, 0.1))


def test_small_net_in_a_current_agrees_with_the_book_scheme():
    """The reference (rtol = atol = 1e-5: its error ~1e-5 m) and the book scheme at Δt = 1 ms and 0.5 ms over
    0.1 s, the net moving ~1 cm. The book's error at 0.5 ms is a few 1e-4 m: below 3 % of the motion. It is
    the scheme's O(Δt) error: Richardson's extrapolation 2 x(Δt/2) - x(Δt), which cancels a first-order
    error, is several times closer to the reference than x(Δt/2) itself."""
    scene, loading = _net_in_a_current()
    end = 0.1
    ts = np.linspace(0.0, end, 6)
    ref = reference.reference(scene, end, loading=loading, saveat=ts, rtol=1e-5, atol=1e-5)
    assert np.all(np.isfinite(ref.positions)) and np.all(np.isfinite(ref.velocities))
    fixed = np.asarray(scene.nodes.fixed)
    np.testing.assert_array_equal(ref.positions[:, fixed], np.broadcast_to(scene.nodes.position[fixed], (6, fixed.sum())))
    motion = np.abs(ref.positions[-1] - ref.positions[0]).max()
    assert motion > 5e-3  # the current does move the net
    runs = {}
    for h in (1e-3, 5e-4):
        book = dynamics.simulate(scene, end, dynamics.Implicit(time_step=h), loading=loading, record_every=ts[1])
        runs[h] = book.positions
    error = np.abs(runs[5e-4] - ref.positions).max()
    assert error < 0.03 * motion
    extrapolated = np.abs(2 * runs[5e-4] - runs[1e-3] - ref.positions).max()
    assert extrapolated < error / 3


def test_sparse_stage_jacobian_equals_the_dense_one():
    """The stage Jacobian I - c ∂f/∂y of a net moving through a current (drag on the relative velocity
    couples the velocities of an element's vertices), from one JVP per colour, equals jax.jacfwd's."""
    scene, _ = _net_in_a_current()
    model = model_lib.active_terms(scene, dynamic=True)
    free_index, masses = reference.free_masses(scene)
    masses = tuple(jnp.asarray(m) for m in masses)
    pattern = reference.stage_pattern(scene, model)
    n = free_index.size
    assert pattern.n_colours < 2 * n  # fewer products than columns
    rng = np.random.default_rng(1)
    x = np.asarray(scene.nodes.position) + 0.01 * rng.normal(size=scene.nodes.position.shape)
    y = jnp.asarray(np.concatenate([x.ravel()[free_index], 0.3 * rng.normal(size=n)]))
    c = 3e-3

    def stage(z):
        xs = reference._full(z[:n], jnp.asarray(scene.nodes.position), jnp.asarray(free_index))
        vs = reference._full(z[n:], jnp.zeros_like(xs), jnp.asarray(free_index))
        a = dynamics.out_of_balance(xs, vs, 0.0, scene, masses, dynamics.Loading(), model).ravel()[free_index]
        return z - c * jnp.concatenate([z[n:], a / masses[0].ravel()[free_index]])

    dense = np.asarray(jax.jit(jax.jacfwd(stage))(y))
    entries = jax.jit(lambda y: reference.coloured_entries(lambda v: jax.jvp(stage, (y,), (v,))[1], pattern,
                                                           pattern.n_colours))(y)
    rows, cols = np.asarray(pattern.rows), np.asarray(pattern.indices)
    sparse = np.zeros_like(dense)
    sparse[rows, cols] = np.asarray(entries)
    assert np.abs(dense[sparse == 0]).max() == 0.0  # nothing outside the pattern
    np.testing.assert_allclose(sparse, dense, rtol=1e-12, atol=1e-9 * np.abs(dense).max())


def test_failures_raise_clear_errors():
    scene, _, _ = vertical_spring()
    with pytest.raises(reference.ReferenceError, match=r"failed at t = .* after 5 accepted .*maximum number of solver steps"):
        reference.reference(scene, 1.0, solver="Tsit5", max_steps=5)
    massless = eqx.tree_at(lambda s: (s.nodes.mass, s.bars.density), scene, (np.zeros(2), np.zeros(1)))
    with pytest.raises(ValueError, match=r"node 1 is free along x but has no inertia"):
        reference.reference(massless, 1.0)
    x0 = np.asarray(scene.nodes.position).copy()
    x0[1, 2] = np.nan
    with pytest.raises(ValueError, match=r"x0 is not finite at node 1, z"):
        reference.reference(scene, 1.0, x0=x0)
    with pytest.raises(ValueError, match=r"unknown solver"):
        reference.reference(scene, 1.0, solver="Euler")
