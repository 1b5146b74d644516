"""Gradients of time-integrated figures through the implicit dynamics (jaxnet.solve.adjoint_dynamics).

Two scenes and few programs (compiling the Newton iteration dominates this file):

* a body on a spring (two nodes, one bar along x): the scheme's recurrence is linear and solved in closed
  form, x_k - L = δ (1 + a)^(-k/2) cos(k atan √a), a = (EA/L) h²/m, so the run, a figure of it and their
  derivatives in m, EA and h are exact numbers: reverse mode (jax.grad) at 16 and 64 steps, forward mode
  (jax.jacfwd) of the whole trajectory at 18 steps (a partial last segment). The compiled gradients also
  give the memory test.
* a panel of 4 x 4 meshes hanging from two corners, with a sinker at each bottom corner, in a current
  ramping up: the run against ``dynamics.simulate``, and reverse-mode gradients of two figures (the mean
  and the smooth peak of the mooring force) with respect to the twine diameter, the twine EA, the sinkers'
  mass and the current, against fourth-order central differences of the whole run (step 1e-3 relative,
  every step converged to 1e-10 N: see tests/solve/test_implicit.py for why these settings).
"""

import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import pytest
from jax.extend import core as jax_core

import jaxnet  # noqa: F401  (float64)
from jaxnet.water import forcing
from jaxnet.net import Net, Twine
from jaxnet.scene import Bars, Environment, Nodes, Scene
from jaxnet.solve import adjoint_dynamics as ad, dynamics, implicit
from jaxnet.solve.options import Newton

NEWTON = Newton(tol=1e-10, max_iter=50, damping=1e-12, stall_window=None, line_search=30)


# -- the body on a spring: closed forms --------------------------------------------------------------------

M, EA, L, DELTA = 2.0, 800.0, 1.0, 0.01
H = 2 * np.pi / np.sqrt(EA / L / M) / 25  # 25 steps a period
PULL_X = functools.partial(ad.mooring_force, nodes=[0], direction=[1.0, 0.0, 0.0])


def spring(m=M, ea=EA):
    """A body of mass m (kg) on a bar of rest length L and stiffness EA (N) along x, the bar's far end held at
    the origin, the body held across x, released at rest from L + δ; no gravity, no water (massless bar,
    no drag, no added mass): the equation of motion is m x'' = -(EA/L)(x - L) exactly. m and EA may be traced."""
    nodes = Nodes(position=np.array([[0.0, 0.0, 0.0], [L + DELTA, 0.0, 0.0]]),
                  fixed=np.array([[True, True, True], [False, True, True]]), mass=np.array([0.0, M]),
                  volume=np.zeros(2), force=np.zeros((2, 3)))
    bars = Bars(ends=np.array([[0, 1]]), rest_length=np.array([L]), ea_traction=np.array([EA]),
                ea_compression=np.array([EA]), diameter=np.array([1e-3]), density=np.array([1e-9]),
                cable=np.array([0]))
    scene = Scene(nodes=nodes, bars=bars, environment=Environment(gravity=0.0, added_mass_coefficient=0.0))
    if m is M and ea is EA:
        return scene
    return eqx.tree_at(lambda s: (s.nodes.mass, s.bars.ea_traction, s.bars.ea_compression), scene,
                       (jnp.stack([jnp.zeros(()), m]), jnp.reshape(ea, (1,)), jnp.reshape(ea, (1,))))


@functools.lru_cache(maxsize=None)
def spring_structure():
    with jax.ensure_compile_time_eval():  # concrete even when first asked for inside a trace
        return implicit.structure_of(spring(), dynamic=True)


def discrete_solution(m, ea, h, n):
    """The scheme's exact discrete solution (x_k - L)/δ = g_k(a), k = 0 .. n, a = (EA/L) h²/m; dg_k/da; and
    da/d(m, EA, h).

    The recurrence (x_{k+1} - 2 x_k + x_{k-1})/h² = -(EA/(L m)) (x_{k+1} - L) has the characteristic roots
    (1 ± i√a)/(1 + a) = (1 + a)^(-1/2) e^(±iφ), φ = atan √a; from rest (x_{-1} = x_0) its solution is
    g_k = (1 + a)^(-k/2) cos kφ, and dφ/da = 1/(2 √a (1 + a))."""
    k = np.arange(n + 1)
    a = ea / L * h**2 / m
    phi = np.arctan(np.sqrt(a))
    g = (1 + a) ** (-k / 2) * np.cos(k * phi)
    dg = -(k / 2) * (1 + a) ** (-k / 2 - 1) * np.cos(k * phi) - (1 + a) ** (-k / 2) * np.sin(k * phi) * k / (
        2 * (1 + a) * np.sqrt(a))
    return g, dg, np.array([-a / m, a / ea, 2 * a / h])


def mean_pull_closed_form(m, ea, h, n):
    """The mean over steps 1 .. n of the support's pull along x, -(EA/L)(x_k - L), and its derivatives in
    (m, EA, h)."""
    g, dg, da = discrete_solution(m, ea, h, n)
    f = -ea / L * DELTA * g[1:].mean()
    return f, -ea / L * DELTA * dg[1:].mean() * da + np.array([0.0, f / ea, 0.0])


def spring_figure(p, n, segment=None):
    """The mean pull on the support along x over n steps of h, as a function of p = (m, EA, h)."""
    return ad.integrate(PULL_X, spring(p[0], p[1]), spring_structure(), time_step=p[2], n_steps=n, solver=NEWTON,
                        segment=segment)


@functools.lru_cache(maxsize=None)
def spring_gradient(n):
    """The compiled value and gradient (reverse mode) of :func:`spring_figure` at n steps, ⌈√n⌉ a segment."""
    return jax.jit(jax.value_and_grad(spring_figure), static_argnums=1).lower(jnp.array([M, EA, H]), n).compile()


@pytest.mark.parametrize("n", [16, 64])
def test_spring_figure_and_its_adjoint_gradient_are_the_closed_forms(n):
    value, gradient = spring_gradient(n)(jnp.array([M, EA, H]))
    f, df = mean_pull_closed_form(M, EA, H, n)
    assert abs(float(value) - f) <= 1e-10 * abs(f)
    # a linear problem: each step is one Newton step and one exact solve; the adjoint is exact to rounding
    np.testing.assert_allclose(np.asarray(gradient), df, rtol=1e-9)
    assert np.all(np.abs(df) > 1e-3 * np.abs(f) / np.array([M, EA, H]))  # every parameter matters


def test_trajectories_of_a_batch_of_designs_and_their_forward_derivatives_are_the_closed_forms():
    """vmap over two designs of the whole trajectory and of d x_k/d(m, EA, h) at every step by forward mode
    (jacfwd): each design's own closed form."""
    n = 18  # ⌈√18⌉ = 5 a segment, 4 segments: the last two steps of the last segment are skipped

    def run(p):
        xs, vs = ad.trajectory(spring(p[0], p[1]), spring_structure(), None, p[2], n, solver=NEWTON)
        return xs[:, 1, 0], (xs, vs)

    designs = np.array([[M, EA, H], [1.5 * M, 0.8 * EA, 1.2 * H]])
    derivatives, (xs, vs) = jax.jit(jax.vmap(jax.jacfwd(run, has_aux=True)))(designs)
    assert xs.shape == vs.shape == (2, n + 1, 2, 3)
    for design, derivative, x, v in zip(designs, derivatives, xs, vs):
        g, dg, da = discrete_solution(*design, n)
        np.testing.assert_allclose(np.asarray(x[:, 1, 0]) - L, DELTA * g, rtol=0, atol=1e-12 * DELTA)
        np.testing.assert_allclose(np.asarray(v[1:, 1, 0]), DELTA * np.diff(g) / design[2], rtol=0,
                                   atol=1e-10 * DELTA / design[2])
        assert float(v[0, 1, 0]) == 0.0
        exact = DELTA * dg[:, None] * da[None, :]
        scale = np.abs(exact).max(axis=0)  # per parameter: their units differ
        np.testing.assert_allclose(np.asarray(derivative) / scale, exact / scale, rtol=0, atol=1e-9)


def test_bad_input_is_named_before_anything_is_compiled():
    scene, structure = spring(), spring_structure()
    with pytest.raises(ValueError, match="n_steps must be an int >= 1, got 0"):
        ad.series(PULL_X, scene, structure, time_step=H, n_steps=0)
    with pytest.raises(ValueError, match="time_step must be a finite scalar > 0"):
        ad.series(PULL_X, scene, structure, time_step=-H, n_steps=4)
    with pytest.raises(ValueError, match="segment must be None or an int >= 1"):
        ad.series(PULL_X, scene, structure, time_step=H, n_steps=4, segment=0)
    with pytest.raises(ValueError, match=r"x0 must have the shape of the scene's positions \(2, 3\)"):
        ad.series(PULL_X, scene, structure, time_step=H, n_steps=4, x0=np.zeros((3, 3)))
    panel_scene, loading, _ = panel()
    with pytest.raises(ValueError, match="dynamic=True"):
        ad.series(PULL_X, panel_scene, implicit.structure_of(panel_scene), loading, H, 4)
    held_free = dynamics.Loading(motions=(forcing.PrescribedMotion(np.array([1]), forcing.Towing((1.0, 0, 0))),))
    with pytest.raises(ValueError, match="prescribed motion 0: node 1 is not fixed on every axis"):
        ad.series(PULL_X, scene, structure, held_free, H, 4)
    with pytest.raises(ValueError, match="no enclosure"):
        ad.enclosed_volume(ad.Instant(t=0.0, x=scene.nodes.position, v=np.zeros((2, 3)), force=np.zeros((2, 3)),
                                      scene=scene, step=None,
                                      structure=structure))


# -- memory of the reverse pass ----------------------------------------------------------------------------


def _sub_jaxprs(params):
    for value in params.values():
        for item in value if isinstance(value, (tuple, list)) else (value,):
            if isinstance(item, jax_core.ClosedJaxpr):
                yield item.jaxpr
            elif isinstance(item, jax_core.Jaxpr):
                yield item


def stacked_bytes(jaxpr):
    """Bytes of every value a scan stacks over its iterations (its ``ys``), nested scans counted once (their
    buffer is reused at each outer iteration): what a reverse pass keeps of its forward pass."""
    total = 0
    for eqn in jaxpr.eqns:
        if eqn.primitive.name == "scan":
            total += sum(v.aval.size * v.aval.dtype.itemsize for v in eqn.outvars[eqn.params["num_carry"]:])
        total += sum(stacked_bytes(sub) for sub in _sub_jaxprs(eqn.params))
    return total


def test_reverse_pass_memory_grows_as_the_square_root_of_the_steps():
    """The values the gradient's program stacks (traced at 16, 64, 256 steps: 4× the steps each): a plain
    scan (one segment) grows 4× as much each time, the checkpointed one (⌈√n⌉ a segment) ~2×. And XLA's
    temporary memory of the compiled checkpointed gradients grows from 16 to 64 steps by less than
    2 r (√64 - √16), r the bytes a plain scan stacks per step: one segment's steps (√n r) plus the states
    at √n segment starts (less than √n r)."""
    p = jnp.array([M, EA, H])
    stored = {}
    for n in (16, 64, 256):
        for segment in (None, n):
            jaxpr = jax.make_jaxpr(jax.grad(spring_figure), static_argnums=(1, 2))(p, n, segment)
            stored[n, segment] = stacked_bytes(jaxpr.jaxpr)
    plain = np.array([stored[n, n] for n in (16, 64, 256)])
    checkpointed = np.array([stored[n, None] for n in (16, 64, 256)])
    assert np.diff(plain)[1] / np.diff(plain)[0] == pytest.approx(4.0, rel=1e-3)
    growth = np.diff(checkpointed)[1] / np.diff(checkpointed)[0]
    assert 1.8 < growth < 2.5  # √n: 2; the figure's own (n,) series adds a little
    assert checkpointed[2] < plain[2] / 8
    per_step = np.diff(plain)[0] / 48
    temp = [spring_gradient(n).memory_analysis().temp_size_in_bytes for n in (16, 64)]
    assert 0 < temp[1] - temp[0] < 2 * per_step * (8 - 4)


# -- a hanging panel in a current ramp -----------------------------------------------------------------------

STEPS, STEP = 9, 0.05  # 3 segments of 3 steps
PARAMETERS = ("twine diameter", "twine EA", "sinker mass", "current")
PEAK_WIDTH = 0.01  # N: the smooth peak is within 0.01 ln 9 = 0.022 N above the largest step's force


@functools.lru_cache(maxsize=None)
def panel():
    """A panel of 4 x 4 square meshes (15 nodes) hanging from its top corners, a 0.1 kg lead sinker at each
    bottom corner, at rest in a current of 0.2 m/s across it (along y), which then ramps up to 0.4 m/s over
    0.3 s; the dynamic structure. (Not ``scenes.panel.hanging_panel``: its headline and sinker bar add the bar
    terms, which would double the compile time of this file.)

    The rest state is the end of 20 implicit steps of 0.5 s in the steady current from the panel as drawn
    (stress-free): the scheme is L-stable, the net settles (velocities 1e-11 m/s), and this run compiles
    the program that ``dynamics.simulate`` runs again in :func:`test_run_is_simulate_at_the_same_step`.
    Measured, why so: from the drawn panel the sinkers fall 4 cm in the first steps, and a step's Newton
    lands on another root for a design 2e-3 away (no derivative there); from rest in still water the steps
    take 8-50 Newton iterations (the drag's damping vanishes with the relative velocity, leaving the mesh's
    soft modes to the netting's small inertia); from rest in a current, 4-6."""
    twine = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, density=1140.0, ea_compression=2000.0)
    n, width = 4, 4 * 0.025 * np.sqrt(2.0)
    net = Net(environment=Environment(current_speed=0.4, current_direction=np.array([0.0, 1.0, 0.0])))
    netting = net.panel("netting", [(0.0, 0.0, -width, 0, 0), (width, 0.0, -width, n, -n),
                                    (width, 0.0, 0.0, 2 * n, 0), (0.0, 0.0, 0.0, n, n)], twine, 0.05)
    net.fix(netting.corner(2))
    net.fix(netting.corner(3))
    net.sinker(netting.corner(0), 0.1)
    net.sinker(netting.corner(1), 0.1)
    drawn = net.build()
    still = dynamics.Loading(current_speed=forcing.Ramp(0.2, 0.2, 0.0, 0.3))
    settling = dynamics.simulate(drawn, 10.0, dynamics.Implicit(time_step=0.5, newton=NEWTON), still)
    assert np.abs(settling.velocities[-1]).max() < 1e-9
    scene = eqx.tree_at(lambda s: s.nodes.position, drawn, settling.positions[-1])
    loading = dynamics.Loading(current_speed=forcing.Ramp(0.2, 0.4, 0.0, 0.3))
    return scene, loading, implicit.structure_of(scene, dynamic=True)


def designed(theta):
    """The panel and its loading with each of :data:`PARAMETERS` multiplied by (1 + theta[k]) (a sinker's
    displaced volume follows its mass, as in ``DesignSpace``)."""
    scene, loading, _ = panel()
    scale = 1.0 + theta
    scene = eqx.tree_at(lambda s: (s.netting.diameter, s.netting.ea_traction, s.nodes.mass, s.nodes.volume), scene,
                        (jnp.asarray(scene.netting.diameter) * scale[0],
                         jnp.asarray(scene.netting.ea_traction) * scale[1],
                         jnp.asarray(scene.nodes.mass) * scale[2], jnp.asarray(scene.nodes.volume) * scale[2]))
    loading = eqx.tree_at(lambda g: g.current_speed.end_value, loading, loading.current_speed.end_value * scale[3])
    return scene, loading


def panel_run(theta):
    """The figures (2,): the mean pull of the current on the moorings (along y, N) and the smooth peak of the
    mooring force's magnitude (N); and what the steps recorded."""
    scene, loading = designed(theta)
    record = ad.series(lambda now: dict(x=now.x, v=now.v, reactions=ad.reactions(now),
                                        pull=ad.mooring_force(now, direction=[0.0, 1.0, 0.0]),
                                        magnitude=ad.mooring_force(now)),
                       scene, panel()[2], loading, STEP, STEPS, solver=NEWTON)
    return jnp.stack([ad.mean(record["pull"]), ad.smooth_peak(record["magnitude"], PEAK_WIDTH)]), record


@functools.lru_cache(maxsize=None)
def panel_adjoint():
    """θ -> (figures, their Jacobian by reverse mode (one adjoint pass per figure), the record): one program."""

    panel()  # concrete, before the trace

    def adjoint(theta):
        figures, pullback, record = jax.vjp(panel_run, theta, has_aux=True)
        return figures, jax.vmap(pullback)(jnp.eye(2))[0], record

    return jax.jit(adjoint)


def test_run_is_simulate_at_the_same_step():
    scene, loading, _ = panel()
    reference = dynamics.simulate(scene, STEPS * STEP, dynamics.Implicit(time_step=STEP, newton=NEWTON), loading)
    assert int(reference.state.retries) == 0 and reference.steps == STEPS
    for ours, theirs in zip(jax.jit(ad.lumped_masses)(scene), dynamics.lumped_masses(scene)):
        np.testing.assert_allclose(np.asarray(ours), theirs, rtol=1e-14, atol=0)
    figures, _, record = panel_adjoint()(np.zeros(len(PARAMETERS)))
    assert np.abs(reference.positions[-1] - reference.positions[0]).max() > 1e-3  # the net does move
    np.testing.assert_allclose(np.asarray(record["x"]), reference.positions[1:], rtol=0, atol=1e-8)
    np.testing.assert_allclose(np.asarray(record["v"]), reference.velocities[1:], rtol=0, atol=1e-8 / STEP)
    fixed = np.flatnonzero(np.asarray(scene.nodes.fixed).any(axis=1))
    np.testing.assert_allclose(np.asarray(record["reactions"])[:, fixed], reference.figures["reaction_N"][1:], rtol=0,
                               atol=1e-8 * np.abs(reference.figures["reaction_N"]).max())
    # the drag of the last step, as simulate records it (its own small program, the instant built inside it: the
    # adjoint's is big enough)
    def last_drag(record):
        last = jax.tree.map(lambda a: a[-1], record)
        scene_t = dynamics.scene_at(scene, loading, STEPS * STEP)
        masses = ad.lumped_masses(scene)
        water = masses[1] * dynamics.water_acceleration(record["x"][-2], scene_t, loading, False)
        step = dynamics.TimeStep(record["x"][-2], record["v"][-2], jnp.asarray(STEP), masses[0], water)
        now = ad.Instant(t=STEPS * STEP, x=last["x"], v=last["v"], force=-last["reactions"], scene=scene_t, step=step,
                         structure=panel()[2])
        return ad.drag(now)

    np.testing.assert_allclose(np.asarray(jax.jit(last_drag)(record)), reference.figures["drag_netting_N"][-1],
                               rtol=1e-9)
    total = reference.figures["reaction_total_N"][1:]
    np.testing.assert_allclose(np.asarray(record["pull"]), total[:, 1], rtol=1e-9)
    np.testing.assert_allclose(np.asarray(record["magnitude"]), np.linalg.norm(total, axis=1), rtol=1e-9)
    assert float(figures[0]) == pytest.approx(total[:, 1].mean(), rel=1e-9)
    largest = np.linalg.norm(total, axis=1).max()
    assert largest <= float(figures[1]) <= largest + PEAK_WIDTH * np.log(STEPS)


def central_differences(f, theta, h=1e-3):
    """Fourth-order central differences of f at theta, a column per parameter."""
    cols = []
    for k in range(theta.size):
        e = np.zeros_like(theta)
        e[k] = h
        cols.append((8 * (f(theta + e) - f(theta - e)) - (f(theta + 2 * e) - f(theta - 2 * e))) / (12 * h))
    return np.stack(cols, axis=-1)


def test_adjoint_gradients_match_differences_of_the_whole_run():
    """d(mean pull, smooth peak)/d(twine diameter, EA, sinker mass, current) by the adjoint (one transposed
    solve per step and figure, backwards over the run) against differences of the whole run, to 1e-6."""
    adjoint = panel_adjoint()
    theta = np.zeros(len(PARAMETERS))
    jacobian = np.asarray(adjoint(theta)[1])
    fd = central_differences(lambda t: np.asarray(adjoint(t)[0]), theta)
    for i, figure in enumerate(("mean pull", "smooth peak")):
        scale = np.abs(fd[i]).max()
        np.testing.assert_allclose(jacobian[i], fd[i], rtol=0, atol=1e-6 * scale, err_msg=figure)
        for k, name in enumerate(PARAMETERS):
            assert abs(fd[i, k]) > 1e-4 * scale, (figure, name)  # every parameter moves every figure
