"""The book's implicit time stepping (4.265-4.276): exact discrete solutions, the scheme's energy identity,
settling to the static equilibrium, resume, retries, stiff twines, and the step's tangent."""

import numpy as np
import jax
import jax.numpy as jnp
import pytest

import jaxnet  # noqa: F401  (float64)
from jaxnet import model as model_lib, run
from jaxnet.model import assemble
from jaxnet.scene import Bars, Environment, Nodes, Scene
from jaxnet.solve import dynamics, kernel, statics
from jaxnet.solve.options import Newton

TIGHT = Newton(tol=1e-9, max_iter=30, damping=1e-12, stall_window=None)


def spring_mass(m=2.0, L=1.0, ea=800.0, delta=0.01, drag_area=None, current=0.0, gravity=0.0, free_axes="x"):
    """A body of mass m on a bar of rest length L, the bar's far end held at the origin. The bar is
    massless (density ~0) and the water adds no mass, so k = EA/L and ω = sqrt(k/m) exactly."""
    pos = np.array([[0.0, 0.0, 0.0], [L + delta, 0.0, 0.0]])
    fixed = np.array([[True] * 3, [a not in free_axes for a in "xyz"]])
    nodes = Nodes(position=pos, fixed=fixed, mass=np.array([0.0, m]), volume=np.zeros(2), force=np.zeros((2, 3)),
                  drag_area=None if drag_area is None else np.array([0.0, drag_area]))
    bars = Bars(ends=np.array([[0, 1]]), rest_length=np.array([L]), ea_traction=np.array([ea]),
                ea_compression=np.array([ea]), diameter=np.array([1e-3]), density=np.array([1e-9]), cable=np.array([0]))
    env = Environment(gravity=gravity, added_mass_coefficient=0.0, current_speed=current)
    return Scene(nodes=nodes, bars=bars, environment=env)


def recurrence(x0, omega, h, n):
    """The book scheme's exact discrete solution of x'' = -ω² x from rest: (x_{k+1} - 2 x_k + x_{k-1})/h² =
    -ω² x_{k+1}, with x_{-1} = x_0 (start at rest: v_0 = (x_0 - x_{-1})/h = 0)."""
    out = [x0, x0 / (1 + (omega * h) ** 2)]
    for _ in range(n - 1):
        out.append((2 * out[-1] - out[-2]) / (1 + (omega * h) ** 2))
    return np.array(out)


def test_spring_follows_the_schemes_exact_discrete_solution():
    m, ea, L, delta = 2.0, 800.0, 1.0, 0.01
    omega = np.sqrt(ea / L / m)
    h = 2 * np.pi / omega / 25
    tr = dynamics.simulate(spring_mass(m, L, ea, delta), 40 * h, dynamics.Implicit(time_step=h, newton=TIGHT))
    x = tr.positions[:, 1, 0] - L
    np.testing.assert_allclose(tr.times, h * np.arange(41), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(x, recurrence(delta, omega, h, 40), rtol=0, atol=1e-10 * delta)
    assert tr.mean_iterations == 1.0  # a linear problem: one Newton step per time step


def test_spring_period_and_damping_converge_at_the_schemes_order():
    """Period of the discrete oscillation 2π h / atan(ω h) (the scheme's eigenvalues (1 ± iωh)/(1 + ω²h²)):
    its error falls at second order as Δt halves; the numerical damping rate ln(1 + ω²h²)/(2h) ~ ω²h/2 at
    first order. The damping is measured on I_n = x_n² - p x_n x_{n-1} + q x_{n-1}², which the scheme's
    recurrence x_{n+1} = p x_n - q x_{n-1} multiplies by q = |eigenvalue|² at every step."""
    m, ea, L, delta = 2.0, 800.0, 1.0, 0.01
    omega = np.sqrt(ea / L / m)
    period = 2 * np.pi / omega
    period_errors, damping_rates = [], []
    for n in (20, 40, 80):
        h = period / n
        tr = dynamics.simulate(spring_mass(m, L, ea, delta), 3 * period, dynamics.Implicit(time_step=h, newton=TIGHT))
        x = tr.positions[:, 1, 0] - L
        s = np.sign(x)
        up = np.flatnonzero((s[:-1] < 0) & (s[1:] >= 0))
        crossings = tr.times[up] - x[up] * h / (x[up + 1] - x[up])
        measured = np.mean(np.diff(crossings))
        assert measured == pytest.approx(2 * np.pi * h / np.arctan(omega * h), rel=1e-3)
        period_errors.append(measured / period - 1)
        a = (omega * h) ** 2
        p, q = 2 / (1 + a), 1 / (1 + a)
        invariant = x[1:] ** 2 - p * x[1:] * x[:-1] + q * x[:-1] ** 2
        rate = -np.log(invariant[-1] / invariant[0]) / (2 * (tr.times[-1] - tr.times[1]))
        assert rate == pytest.approx(np.log(1 + a) / (2 * h), rel=1e-6)
        damping_rates.append(rate)
    ratios = np.array(period_errors[:-1]) / np.array(period_errors[1:])
    np.testing.assert_allclose(ratios, 4.0, rtol=0.05)
    rate_ratios = np.array(damping_rates[:-1]) / np.array(damping_rates[1:])
    assert np.all((rate_ratios > 1.8) & (rate_ratios < 2.0))


def _potential(scene, model, x):
    load = assemble.loads(scene, model)
    return float(assemble.energy(jnp.asarray(x), scene, model) - jnp.sum(load * x))


def test_energy_changes_exactly_as_the_scheme_dissipates():
    """Backward differences dissipate, per step, ½ m |v_{n+1} - v_n|² plus the Bregman gap of the potential
    D(x_n, x_{n+1}) = V(x_n) - V(x_{n+1}) - ∇V(x_{n+1}).(x_n - x_{n+1}): an identity of the scheme, checked
    on a swinging elastic pendulum (gravity, large angle, nonlinear)."""
    m, L = 1.5, 1.0
    scene = spring_mass(m=m, L=L, ea=2e4, delta=0.0, gravity=9.81, free_axes="xz")
    h = 0.01
    tr = dynamics.simulate(scene, 0.6, dynamics.Implicit(time_step=h, newton=TIGHT))
    model = model_lib.active_terms(scene, dynamic=True)
    x, v = tr.positions, tr.velocities
    V = np.array([_potential(scene, model, xi) for xi in x])
    grad = np.array([np.asarray(jax.grad(lambda y: assemble.energy(y, scene, model))(jnp.asarray(xi))) for xi in x])
    grad -= np.asarray(assemble.loads(scene, model))
    E = 0.5 * m * np.sum(v[:, 1] ** 2, axis=1) + V
    dv = v[1:, 1] - v[:-1, 1]
    bregman = V[:-1] - V[1:] - np.sum(grad[1:] * (x[:-1] - x[1:]), axis=(1, 2))
    predicted = -0.5 * m * np.sum(dv**2, axis=1) - bregman
    assert np.all(np.diff(E) < 0)  # it swings 45 cm down: real dissipation, not rounding
    np.testing.assert_allclose(np.diff(E), predicted, rtol=0, atol=1e-7 * abs(E[0] - E[-1]) + 1e-9)


def test_current_settles_to_the_static_equilibrium():
    """A body held by a spring in a current, starting at rest: the dynamic run settles on the statics
    solver's equilibrium (drag on the relative velocity is what damps it)."""
    scene = spring_mass(m=3.0, ea=500.0, delta=0.0, drag_area=0.2, current=1.0)
    eq = statics.solve(scene, tol=1e-9)
    tr = dynamics.simulate(scene, 20.0, dynamics.Implicit(time_step=0.05, newton=TIGHT), record_every=1.0)
    drag = 0.5 * 1025.0 * 0.2 * 1.0**2
    assert float(eq.x[1, 0]) == pytest.approx(1.0 + drag / 500.0, rel=1e-9)
    assert tr.positions[-1, 1, 0] == pytest.approx(float(eq.x[1, 0]), abs=1e-7)
    assert abs(tr.velocities[-1, 1, 0]) < 1e-6
    # the reaction at the held end (node 0; node 1 is held across the bar) carries the drag, and so does the bar
    np.testing.assert_array_equal(tr.reaction_nodes, [0, 1])
    assert tr.figures["reaction_N"][-1][0, 0] == pytest.approx(-drag, rel=1e-6)
    assert tr.figures["reaction_total_N"][-1][0] == pytest.approx(-drag, rel=1e-6)
    assert tr.figures["max_bar_tension_N"][-1] == pytest.approx(drag, rel=1e-6)
    assert "max_twine_tension_N" not in tr.figures  # no netting
    np.testing.assert_allclose(tr.figures["drag_nodes_N"][-1], [drag, 0, 0], rtol=1e-6)


def test_resumed_run_equals_an_uninterrupted_one(tmp_path):
    scene = spring_mass(m=2.0, ea=800.0, delta=0.02, drag_area=0.05, current=0.5)
    opts = dynamics.Implicit(time_step=0.01, newton=TIGHT)
    whole = run.simulate(scene, 0.5, opts, record_every=0.05, out=tmp_path / "whole", progress=False, vtk=False)
    run.simulate(scene, 0.25, opts, record_every=0.05, out=tmp_path / "part", progress=False, vtk=False)
    resumed = run.simulate(scene, 0.5, opts, record_every=0.05, out=tmp_path / "part", resume=True, progress=False,
                           vtk=False)
    from jaxnet.io import timeseries

    a, b = timeseries.read_series(tmp_path / "whole"), timeseries.read_series(tmp_path / "part")
    assert len(a["time"]) == len(b["time"]) == 11
    np.testing.assert_allclose(b["time"], a["time"], rtol=1e-14)
    np.testing.assert_array_equal(b["position"], a["position"])
    np.testing.assert_array_equal(b["velocity"], a["velocity"])
    assert int(resumed.state.steps) == int(whole.state.steps) == 50


def test_failed_steps_are_retried_smaller_and_reported():
    """Newton allowed 2 iterations: the big steps of a swinging pendulum fail, are halved until they pass."""
    scene = spring_mass(m=1.0, ea=1e4, delta=0.0, gravity=9.81, free_axes="xz")
    newton = Newton(tol=1e-9, max_iter=2, damping=1e-12, stall_window=None)
    tr = dynamics.simulate(scene, 0.4, dynamics.Implicit(time_step=0.05, newton=newton), record_every=0.05)
    assert int(tr.state.retries) > 0
    assert tr.figures["time_step_s"].min() < 0.05
    assert tr.times[-1] == pytest.approx(0.4, abs=1e-14)
    assert np.all(np.isfinite(tr.positions))
    with pytest.raises(dynamics.DynamicsError, match=r"node 1"):
        dynamics.simulate(scene, 0.4, dynamics.Implicit(time_step=0.05, min_time_step=0.05,
                                                        newton=Newton(tol=1e-9, max_iter=1, damping=1e-12,
                                                                              stall_window=None)))


def test_a_failed_run_returns_its_records_when_asked_not_to_throw():
    """``throw=False``: the run stops where a step fails below the smallest step and returns what it
    recorded, its status saying why (as the error would have)."""
    scene = spring_mass(m=1.0, ea=1e4, delta=0.0, gravity=9.81, free_axes="xz")
    solver = dynamics.Implicit(time_step=0.05, min_time_step=0.05,
                               newton=Newton(tol=1e-9, max_iter=1, damping=1e-12, stall_window=None))
    with pytest.raises(dynamics.DynamicsError) as raised:
        dynamics.simulate(scene, 0.4, solver, record_every=0.05)
    run = dynamics.simulate(scene, 0.4, solver, record_every=0.05, throw=False)
    assert run.status == dynamics.STEP_FAILED and run.reason == dynamics.REASONS[dynamics.STEP_FAILED]
    assert float(run.state.t) == float(raised.value.state.t) < 0.4
    assert run.times[-1] <= float(run.state.t) and np.all(np.isfinite(run.positions))
    assert run.timing.wall_s >= run.timing.compile_s > 0.0


@pytest.mark.parametrize("h", [1e-4, 1e-2, 1.0])
def test_stiff_twines_stay_stable_at_any_step(h):
    """EA = 1e9 N on 1 kg (ω = 3e4 rad/s: ωΔt from 3 to 3e4): the scheme is L-stable, the amplitude never
    grows and is damped by (1 + ω²h²)^(-1/2) per step."""
    m, ea, delta = 1.0, 1e9, 1e-6
    omega = np.sqrt(ea / m)
    tr = dynamics.simulate(spring_mass(m=m, ea=ea, delta=delta), 10 * h,
                           dynamics.Implicit(time_step=h, newton=Newton(tol=1e-6, max_iter=30, damping=1e-12,
                                                                                stall_window=None)))
    x = tr.positions[:, 1, 0] - 1.0
    assert np.all(np.isfinite(x))
    np.testing.assert_allclose(x, recurrence(delta, omega, h, 10), rtol=0, atol=1e-6 / ea + 1e-15)


def _small_net():
    from jaxnet.scenes.panel import hanging_panel

    net = hanging_panel(meshes=6, step=0.05).net
    net.environment = Environment(current_speed=0.7, current_direction=np.array([1.0, 0.2, 0.0]))
    return net.build()


def test_the_steps_tangent_is_the_derivative_of_its_residual():
    """Inertia (M + M_a)/Δt² and the drag's damping (1/Δt) ∂F/∂v in the tangent: against central
    differences of the step's out-of-balance force, with the net moving through a current."""
    scene = _small_net()
    model = model_lib.active_terms(scene, dynamic=True)
    pattern = assemble.build_pattern(scene, model)
    mass, water = (jnp.asarray(a) for a in dynamics.lumped_masses(scene))
    rng = np.random.default_rng(0)
    x_prev = jnp.asarray(scene.nodes.position) + 0.01 * rng.normal(size=scene.nodes.position.shape)
    v_prev = jnp.asarray(0.3 * rng.normal(size=x_prev.shape))
    h = 0.02
    step = dynamics.TimeStep(x_prev, v_prev, jnp.asarray(h), mass, jnp.zeros_like(x_prev))
    free = np.asarray(pattern.free)
    x = (x_prev + h * v_prev + 1e-3 * rng.normal(size=x_prev.shape)).ravel()[free]
    state = assemble.states(assemble.positions(jnp.asarray(x), scene, pattern), scene, model)
    load = assemble.loads(scene, model)

    @jax.jit
    def residual(y):
        return kernel.evaluate(y, jnp.zeros_like(load), load, 1.0, scene, pattern, model, step)[1].ravel()[free]

    # one compiled program, as the solver runs it
    data = jax.jit(lambda y: kernel.tangent(y, state, 1.0, scene, pattern, model, "autodiff", step))(jnp.asarray(x))
    import scipy.sparse as sp

    K = sp.csr_matrix((np.asarray(data), np.asarray(pattern.indices), np.asarray(pattern.indptr))).toarray()
    eps = 1e-6
    cols = rng.choice(len(x), min(12, len(x)), replace=False)
    for j in cols:
        e = np.zeros(len(x))
        e[j] = eps
        fd = -(np.asarray(residual(jnp.asarray(x + e))) - np.asarray(residual(jnp.asarray(x - e)))) / (2 * eps)
        np.testing.assert_allclose(K[:, j], fd, rtol=1e-6, atol=1e-6 * np.abs(fd).max())
    # the inertia alone is (M + M_a)/Δt² on the diagonal (4.271): jax.hessian of the inertia energy agrees
    H = jax.jit(jax.hessian(step.inertia_energy))(x_prev)
    np.testing.assert_allclose(np.asarray(H).reshape(x_prev.size, -1), np.diag(np.asarray(mass).ravel()) / h**2,
                               rtol=1e-12, atol=1e-9)


def test_drag_at_rest_is_the_static_drag():
    """Each vertex's share computed with its own relative velocity (4.272) equals the statics' drag for a
    uniform current and a net at rest."""
    scene = _small_net()
    static, moving = model_lib.active_terms(scene), model_lib.active_terms(scene, dynamic=True)
    x = jnp.asarray(scene.nodes.position)
    pick = lambda model: tuple(t for t in model if t.name in ("netting_drag", "bar_drag"))  # noqa: E731
    f_static = assemble.forces(x, scene, pick(static))
    f_moving = assemble.forces(x, scene, pick(moving), None, assemble.Motion(x, jnp.asarray(0.1)))
    np.testing.assert_allclose(np.asarray(f_moving), np.asarray(f_static), rtol=1e-12, atol=1e-14)
    # and moving with the water cancels it
    c = scene.environment.current_speed * scene.environment.current_direction / np.linalg.norm(scene.environment.current_direction)
    f_carried = assemble.forces(x, scene, pick(moving), None, assemble.Motion(x - 0.1 * c, jnp.asarray(0.1)))
    np.testing.assert_allclose(np.asarray(f_carried), 0.0, atol=1e-12)


def test_lumped_masses_sum_to_the_nets_mass():
    scene = _small_net()
    mass, water = dynamics.lumped_masses(scene)
    net, bars, env = scene.netting, scene.bars, scene.environment
    uv = np.asarray(net.uv)
    d = (uv[:, 1, 0] - uv[:, 0, 0]) * (uv[:, 2, 1] - uv[:, 0, 1]) - (uv[:, 2, 0] - uv[:, 0, 0]) * (uv[:, 1, 1] - uv[:, 0, 1])
    v_net = np.sum(np.abs(d) * np.pi * net.diameter**2 / 4 * net.l0)
    v_bar = np.sum(np.pi * bars.diameter**2 / 4 * bars.rest_length)
    m_net = np.sum(np.abs(d) * np.pi * net.diameter**2 / 4 * net.l0 * net.density)
    m_bar = np.sum(np.pi * bars.diameter**2 / 4 * bars.rest_length * bars.density)
    ca, rho = env.added_mass_coefficient, env.water_density
    expected = m_net + m_bar + np.sum(scene.nodes.mass) + ca * rho * (v_net + v_bar)
    np.testing.assert_allclose(mass.sum(axis=0), expected, rtol=1e-12)
    np.testing.assert_allclose(water.sum(axis=0), (ca + 1) * rho * (v_net + v_bar) + rho * np.sum(scene.nodes.volume),
                               rtol=1e-12)


def test_towing_through_still_water_is_the_current_seen_from_the_net():
    """Galilean invariance: a net towed at speed U through still water (its top held and moved by a prescribed
    motion, reaching U after a smooth ramp) settles, seen from the towing point, on the static shape of the
    same net held in a current U."""
    from jaxnet.water import forcing
    from jaxnet.scenes.panel import hanging_panel

    speed = 0.4
    net = hanging_panel(meshes=4, step=0.1).net
    net.environment = Environment(current_speed=speed, current_direction=np.array([1.0, 0.0, 0.0]))
    in_current = net.build()
    eq = statics.solve(in_current, tol=1e-8)
    net.environment = Environment()
    still = net.build()
    held = np.flatnonzero(np.asarray(still.nodes.fixed).all(axis=1))
    towing = forcing.Towing(velocity=(-speed, 0.0, 0.0), ramp=2.0)
    loading = dynamics.Loading(motions=(forcing.PrescribedMotion(held, towing),))
    start = statics.solve(still, tol=1e-8)
    end = 40.0
    newton = Newton(tol=1e-6, max_iter=30, damping=1e-12, stall_window=None)
    tr = dynamics.simulate(still, end, dynamics.Implicit(time_step=0.05, newton=newton), loading, record_every=5.0,
                           x0=np.asarray(start.x))
    seen = tr.positions[-1] - np.asarray(towing(end))
    np.testing.assert_allclose(seen, np.asarray(eq.x), atol=2e-4)
    np.testing.assert_allclose(tr.velocities[-1], np.tile([-speed, 0.0, 0.0], (still.n_nodes, 1)), atol=1e-4)


def test_an_accelerating_current_pushes_by_the_waters_inertia():
    """A body (mass M, volume V, added mass M_a along x, no drag) in a current whose speed rises at a steady
    rate a: the water's inertia (M_a + ρV) a (4.265's γ_h terms) accelerates it at (M_a + ρV)/(M + M_a) a, and
    the scheme from rest puts it at A h² n(n+1)/2 after n steps (its exact response to a constant force)."""
    from jaxnet.water import forcing

    M, V, Ma, rate = 4.0, 2e-3, 1.5, 0.3
    # held by a bar of negligible stiffness and size (validation wants every node held by something)
    nodes = Nodes(position=np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 0.0]]), fixed=np.array([[True] * 3, [False, True, True]]),
                  mass=np.array([0.0, M]), volume=np.array([0.0, V]), force=np.zeros((2, 3)),
                  added_mass=np.array([[0.0] * 3, [Ma, 0.0, 0.0]]))
    bars = Bars(ends=np.array([[0, 1]]), rest_length=np.array([1.0]), ea_traction=np.array([1e-9]),
                ea_compression=np.array([1e-9]), diameter=np.array([1e-9]), density=np.array([1e-9]), cable=np.array([0]))
    scene = Scene(nodes=nodes, bars=bars, environment=Environment(gravity=0.0, current_direction=np.array([1.0, 0.0, 0.0])))
    loading = dynamics.Loading(current_speed=forcing.Ramp(0.0, 10 * rate, 0.0, 10.0, smooth=False))
    h, n = 0.05, 40
    tr = dynamics.simulate(scene, n * h, dynamics.Implicit(time_step=h, newton=TIGHT), loading)
    A = (Ma + 1025.0 * V) / (M + Ma) * rate
    k = np.arange(n + 1)
    np.testing.assert_allclose(tr.positions[:, 1, 0], A * h**2 * k * (k + 1) / 2, rtol=1e-8, atol=1e-14)


def test_the_cage_in_waves_starts_from_its_static_equilibrium_without_a_shock(tmp_path):
    """Issue 26's start-up shock: the built-in cage in 2 m, 6 s waves with its collar heaving. By default
    the waves and the heave grow in over one wave period (C² envelope), so the reactions leave the static
    equilibrium smoothly (with no ramp the first second strayed 14 kN from it: docs/investigations.md, "The start
    of a dynamic run")."""
    import json

    from jaxnet.scenes import cage_in_waves

    case = cage_in_waves(step=1.6)
    scene, loading, ramp = dynamics.with_start_ramp(case.scene, case.time.loading)
    assert ramp == 6.0 and float(scene.environment.waves.ramp) == 6.0
    assert float(loading.motions[0].motion.ramp) == 6.0
    again = dynamics.with_start_ramp(scene, loading)  # applying it twice changes nothing
    assert again[2] == 6.0 and float(again[1].motions[0].motion.ramp) == 6.0
    eq = statics.solve(dynamics.scene_at(scene, loading, 0.0), case.solver)
    static = np.asarray(eq.reaction(scene)).sum(axis=0)
    # to the end of the ramp and half a period at full height: the heave's crest (6 s) and trough (9 s)
    run = jaxnet.run.simulate(scene, 9.0, case.time.solver, loading, record_every=0.25, x0=np.asarray(eq.x),
                              out=tmp_path, vtk=False, progress=False)
    total = run.figures["reaction_total_N"]
    times = run.times
    np.testing.assert_allclose(total[0], static, rtol=1e-6, atol=1e-6 * np.abs(static).max())
    # the swing of the vertical reaction once the waves are at full height, from the crest to the trough (6-9 s;
    # the swing over a whole period is no smaller, so both bounds below are no looser than over 6-12 s), and
    # how far the first second strays from the static reaction: a small part of it (measured: 0.28 kN of 12.1 kN)
    full = total[times >= 6.0, 2]
    swing = full.max() - full.min()
    first = np.abs(total[times <= 1.0, 2] - static[2]).max()
    assert swing > 1e4
    assert first < 0.15 * swing
    assert run.start_ramp_s == 6.0
    index = json.loads((tmp_path / "series.json").read_text())["run"]
    assert index["start_ramp_s"] == 6.0 and index["reaction_nodes"] == run.reaction_nodes.tolist()
    assert len(run.reaction_nodes) == run.figures["reaction_N"].shape[1]


def test_a_pendulum_towed_by_a_speed_table_trails_at_the_drag_angle():
    """FEMNET's towing speed table (forcing.SpeedTable): the top of a pendulum (a 10 kg body on a 1 m bar, drag
    area 0.05 m²) towed through still water, its speed rising linearly from 0 to 1 m/s over 5 s then held,
    settles at the angle where drag and weight balance, tan θ = ½ρ CdA V² / (m g); the top's path is the table's
    integral, V (t - 2.5 s) after the rise."""
    from jaxnet.water import forcing

    m, cda, speed = 10.0, 0.05, 1.0
    scene = spring_mass(m=m, L=1.0, ea=1e6, delta=0.0, drag_area=cda, gravity=9.81, free_axes="xyz")
    # hanging under its top: the bar along -z
    position = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0]])
    import equinox as eqx

    scene = eqx.tree_at(lambda s: s.nodes.position, scene, position)
    table = forcing.SpeedTable([0.0, 5.0, 60.0], [[0.0, 0.0, 0.0], [speed, 0.0, 0.0], [speed, 0.0, 0.0]])
    loading = dynamics.Loading(motions=(forcing.PrescribedMotion(np.array([0]), table),))
    newton = Newton(tol=1e-8, max_iter=30, damping=1e-12, stall_window=None)
    tr = dynamics.simulate(scene, 40.0, dynamics.Implicit(time_step=0.05, newton=newton), loading, record_every=10.0)
    top, body = tr.positions[-1]
    assert top[0] == pytest.approx(speed * (40.0 - 2.5), rel=1e-12)
    drag, weight = 0.5 * 1025.0 * cda * speed**2, m * 9.81
    angle = np.arctan2(top[0] - body[0], top[2] - body[2])
    assert angle == pytest.approx(np.arctan(drag / weight), abs=1e-4)
    np.testing.assert_allclose(tr.velocities[-1, 1], [speed, 0.0, 0.0], atol=1e-5)


@pytest.mark.parametrize("case", ["current", "retries"])
def test_the_host_loop_takes_the_compiled_loops_steps(case):
    """``Implicit(loop="host")`` (the default: the steps driven from Python, each Newton the static solver's host
    loop) and ``loop="compiled"`` (one program per record interval) take the same steps: a body settling in a
    current, and a swinging pendulum whose big steps fail and are halved. The same times, step counts, retries
    and Newton iterations; positions to rounding (tests/solve/test_winch.py: the same with a winch)."""
    newton = TIGHT
    if case == "current":
        scene, end, h = spring_mass(m=3.0, ea=500.0, delta=0.0, drag_area=0.2, current=1.0), 2.0, 0.05
    else:
        scene, end, h = spring_mass(m=1.0, ea=1e4, delta=0.0, gravity=9.81, free_axes="xz"), 0.4, 0.05
        newton = Newton(tol=1e-9, max_iter=2, damping=1e-12, stall_window=None)
    host, compiled = same_run_both_loops(scene, end, h, newton)
    if case == "retries":
        assert int(host.state.retries) > 0
    with pytest.raises(ValueError, match="loop must be one of"):
        dynamics.Implicit(loop="python")
    # "auto" (the default): the compiled loop past AUTO_COMPILED_STEPS steps still to take, the host's below
    from jaxnet.solve.options import AUTO_COMPILED_STEPS

    auto = dynamics.Implicit(time_step=0.01)
    assert auto.loop == "auto"
    assert dynamics.chosen_loop(auto, 0.01 * AUTO_COMPILED_STEPS) == "host"
    assert dynamics.chosen_loop(auto, 0.01 * (AUTO_COMPILED_STEPS + 1)) == "compiled"
    assert dynamics.chosen_loop(dynamics.Implicit(time_step=0.01, loop="host"), 1e3) == "host"


def same_run_both_loops(scene, end, h, newton, loading=None):
    """Runs ``scene`` with either loop and asserts they took the same steps; (host run, compiled run)."""
    runs = {loop: dynamics.simulate(scene, end, dynamics.Implicit(time_step=h, newton=newton, loop=loop), loading,
                                    record_every=end / 4) for loop in ("host", "compiled")}
    host, compiled = runs["host"], runs["compiled"]
    np.testing.assert_array_equal(host.times, compiled.times)
    assert host.steps == compiled.steps and int(host.state.retries) == int(compiled.state.retries)
    assert int(host.state.iterations) == int(compiled.state.iterations)
    scale = np.abs(compiled.positions).max()
    np.testing.assert_allclose(host.positions, compiled.positions, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(host.velocities, compiled.velocities, rtol=0,
                               atol=1e-9 * max(np.abs(compiled.velocities).max(), 1e-3))
    return host, compiled


def test_a_net_that_nothing_holds_moves_freely_in_time():
    """In time the masses hold a net that no node fixes (a static solve refuses it): a bar with two 2 kg ends,
    each pushed by 3 N along x, translates as one body; the scheme's velocity gains h F/m a step exactly, so
    x_n = x_0 + h² (F/m) n (n + 1)/2."""
    import equinox as eqx

    scene = spring_mass(m=2.0, ea=1e4, delta=0.0, free_axes="xyz")
    scene = eqx.tree_at(lambda s: (s.nodes.fixed, s.nodes.mass, s.nodes.force), scene,
                        (np.zeros((2, 3), bool), np.array([2.0, 2.0]), np.array([[3.0, 0, 0], [3.0, 0, 0]])))
    with pytest.raises(Exception, match="no node is fixed"):
        statics.solve(scene)
    h, n = 0.1, 10
    tr = dynamics.simulate(scene, n * h, dynamics.Implicit(time_step=h, newton=TIGHT))
    shift = h**2 * 1.5 * np.arange(n + 1) * (np.arange(n + 1) + 1) / 2
    np.testing.assert_allclose(tr.positions[:, :, 0] - tr.positions[0, :, 0], np.stack([shift, shift], axis=1),
                               rtol=1e-9, atol=1e-12)
    assert tr.reaction_nodes.size == 0


def float_in_waves(mass=400.0, side=1.0, height=1.0, wave_height=0.2, period=8.0):
    """A box float (FEMNET's node body: ``side`` × ``side`` × ``height`` m, above its node) held along x and y at
    the origin, free to heave in deep-water Airy waves, and a horizontal bar of diameter 0.5 m lying on the mean
    surface a quarter of a wavelength long; the float's link to a fixed node is slack and weightless. The float
    rests with its bottom at -mass / (ρ side²)."""
    from jaxnet.water import waves

    rho, airy = 1025.0, waves.Airy(height=wave_height, period=period, depth=float("inf"))
    quarter = float(airy.wavelength) / 4.0
    bottom = -mass / (rho * side**2)
    pos = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, bottom], [0.0, 5.0, 0.0], [quarter, 5.0, 0.0]])
    fixed = np.array([[True] * 3, [True, True, False], [True] * 3, [True] * 3])
    length = np.zeros((4, 3))
    length[1] = (side, side, height)
    nodes = Nodes(position=pos, fixed=fixed, mass=np.array([0.0, mass, 0.0, 0.0]),
                  volume=np.array([0.0, side**2 * height, 0.0, 0.0]), force=np.zeros((4, 3)), drag_length=length,
                  drag_coefficient=np.zeros((4, 3)))
    bars = Bars(ends=np.array([[0, 1], [2, 3]]), rest_length=np.array([5.0, quarter]), ea_traction=np.array([1.0, 1e3]),
                ea_compression=np.zeros(2), diameter=np.array([0.0, 0.5]), density=np.zeros(2), cable=np.array([0, 1]))
    env = Environment(water_density=rho, surface_level=0.0, waves=airy, added_mass_coefficient=0.0)
    return Scene(nodes=nodes, bars=bars, environment=env)


def test_in_waves_buoyancy_is_that_of_the_volume_under_the_waves_surface():
    """In a time step the free surface is the wave's: a box float's buoyancy is ρ g × its volume under the
    elevation η over its node, the bar's ends float each by its own η (a quarter wavelength apart), and without
    the positions at which to take η the surface is the mean level. Closed forms: the box's immersed volume
    side² (η - z_bottom); the cylinder's immersed fraction at each end."""
    from jaxnet.terms import surface

    scene = float_in_waves()
    model = model_lib.active_terms(scene, dynamic=True)
    x = jnp.asarray(scene.nodes.position)
    rho, g, t = 1025.0, 9.81, 7.0
    eta = np.asarray(scene.environment.waves.elevation(x, t))
    assert eta[1] > 0.05 and eta[3] < -0.05  # the float under a crest, the bar's far end over a trough
    weight = -400.0 * g
    for surface_at, level in ((x, eta), (None, np.zeros(4))):
        scene_t = dynamics.scene_at(scene, dynamics.Loading(), t, surface_at=surface_at)
        f = assemble.term_forces(x, scene_t, model)
        box = f["node_gravity_at_surface"][1, 2]
        np.testing.assert_allclose(box, weight + rho * g * (level[1] - x[1, 2]), rtol=1e-12)
        bar_volume = np.pi * 0.5**2 / 4 * float(scene.bars.rest_length[1])
        fraction = np.asarray(surface.immersed_fraction(-jnp.asarray(level[2:]), 0.5))
        np.testing.assert_allclose(f["bar_gravity_at_surface"][2:, 2], rho * g * bar_volume / 2 * fraction, rtol=1e-12)
    # under the mean level (the last pass) the two ends float alike: they differ by the wave's surface only
    assert abs(fraction[0] - fraction[1]) < 1e-15


def test_a_float_heaves_with_the_waves_surface_as_the_schemes_steady_response():
    """A box float held along x and y heaves in 8 s Airy waves. Its equation, with the surface the wave's:
    M z'' = -K (z - η) + c γ_z, K = ρ g side² its waterplane stiffness, c = ρV the water's inertia on it, and
    γ_z = -ω² e^{k z} η the water's vertical acceleration at its bottom. The book's scheme,
    M (z_{n+1} - 2 z_n + z_{n-1})/h² = F_{n+1}, answers η = Re(A e^{iωt}) in steady state with
    Z = (K - c ω² e^{k z_b}) A / (K + M (1 - e^{-iωh})²/h²) (its exact discrete response; the free motion it
    starts with decays by 1/sqrt(1 + ω_n² h²) a step). Under the mean level the float would heave by c's part
    alone: -0.06 A."""
    scene = float_in_waves()
    h, period, a = 0.1, 8.0, 0.1
    tr = dynamics.simulate(scene, 64.0, dynamics.Implicit(time_step=h, newton=TIGHT))
    mass, water = dynamics.lumped_masses(scene)
    M, c = float(mass[1, 2]), float(water[1, 2])
    omega = 2 * np.pi / period
    k, K = omega**2 / 9.81, 1025.0 * 9.81
    z_b = float(scene.nodes.position[1, 2])
    expected = (K - c * omega**2 * np.exp(k * z_b)) * a / (K + M * (1 - np.exp(-1j * omega * h)) ** 2 / h**2)
    late = tr.times >= 64.0 - 2 * period - 1e-9
    t, z = tr.times[late], tr.positions[late, 1, 2]
    basis = np.stack([np.ones_like(t), np.cos(omega * t), -np.sin(omega * t)], axis=1)
    mean, re, im = np.linalg.lstsq(basis, z, rcond=None)[0]
    # measured: 3.4e-6 relative (the free motion's remains and the e^{kz} of the moving bottom); under the mean
    # level the fit is -0.0063 m, 107 % off
    assert abs(complex(re, im) - expected) < 1e-4 * abs(expected)
    assert abs(expected) > 0.9 * a
    assert abs(mean - z_b) < 1e-3 * a
