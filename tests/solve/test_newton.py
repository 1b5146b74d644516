"""The damped static Newton (method="damped"): convergence from the flat stress-free start, its rate and its failures."""

import numpy as np
import pytest

import jaxnet as jn
import jaxnet.figures  # noqa: F401
from jaxnet.net import Twine
from jaxnet.scenes.panel import framed_panel, hanging_panel
from panels import SMOOTH  # tests/panels.py


def balance(scene, eq):
    """Total reaction + total load: zero at equilibrium, whatever the shape (N, [x, y, z])."""
    return eq.reaction(scene).sum(axis=0) + np.asarray(jn.figures.total_load(scene))


def test_flat_start_of_a_2000_node_panel_with_slack_twines_converges_in_20_iterations():
    # A horizontal panel held along its border, sagging under its weight and a 20 kg sinker: the flat,
    # stress-free start has no out-of-plane stiffness at all, and the twines have EA_c = 0.
    scene = framed_panel(meshes=80, step=0.06, sinker_kg=20.0).scene
    assert scene.n_nodes >= 2000 and not np.any(np.asarray(scene.netting.ea_compression))
    eq = jn.solve_static(scene, method="damped", tol=1e-3, max_iter=20)
    assert eq.converged and float(eq.residual_N) <= 1e-3
    assert float(np.asarray(eq.x)[:, 2].min()) < -0.1  # it really sagged (about 0.23 m)
    np.testing.assert_allclose(balance(scene, eq), 0.0, atol=scene.n_nodes * 1e-3)


def test_flat_start_of_the_2000_node_hanging_panel_with_stiff_twines_converges_in_20_iterations():
    scene = hanging_panel(meshes=80, step=0.06, **SMOOTH).scene
    assert scene.n_nodes >= 2000
    eq = jn.solve_static(scene, method="damped", tol=1e-3, max_iter=20)
    assert eq.converged
    np.testing.assert_allclose(balance(scene, eq), 0.0, atol=scene.n_nodes * 1e-3)


def test_badly_crumpled_start_reaches_the_same_equilibrium():
    # With EA_c = 0 the energy is convex in the positions and this equilibrium (all twines taut) is
    # unique: from a crumpled start (every free node moved at random by up to three twine lengths,
    # many triangles turned inside out) Newton must find the flat start's answer.
    scene = framed_panel(meshes=20, step=0.08, sinker_kg=2.0).scene
    flat = jn.solve_static(scene, method="damped", tol=1e-8)
    rng = np.random.default_rng(0)
    x0 = np.asarray(scene.nodes.position) + rng.uniform(-0.075, 0.075, (scene.n_nodes, 3))
    crumpled = jn.solve_static(scene, method="damped", x0=x0, tol=1e-8)
    np.testing.assert_allclose(np.asarray(crumpled.x), np.asarray(flat.x), atol=1e-7)


def test_slack_curtain_converges_even_though_slowly():
    # The hanging curtain with slack twines has a degenerate equilibrium (gathered, slack sides): Newton
    # converges linearly there, but it must converge, and balance the weight.
    slack = Twine(l0=0.025, ea=2000.0, diameter=1.5e-3, ea_compression=0.0)
    scene = hanging_panel(meshes=40, step=0.1, twine=slack).scene
    eq = jn.solve_static(scene, method="damped", tol=1e-3, max_iter=500)
    assert eq.converged
    np.testing.assert_allclose(balance(scene, eq), 0.0, atol=scene.n_nodes * 1e-3)


def test_quadratic_convergence_near_the_solution():
    scene = framed_panel(meshes=20, step=0.08, sinker_kg=2.0).scene
    eq = jn.solve_static(scene, method="damped", tol=1e-9, max_iter=60)
    hist = np.asarray(eq.history)
    hist = hist[np.isfinite(hist)]
    r1, r2 = hist[-2:]
    scale = float(np.abs(np.asarray(jn.figures.total_load(scene))).max())  # N
    # quadratic: r2 <= C r1² / scale with a modest C; a linearly converging solver has r2 / r1 ~ 0.1-0.5,
    # which fails this by orders of magnitude once r1 is small.
    assert r1 < 1e-3 * scale and r2 <= 100.0 * r1 * r1 / scale, hist


def test_failed_solve_names_the_reason_and_the_node():
    scene = hanging_panel(meshes=20, step=0.08).scene
    with pytest.raises(jn.SolveError, match=r"after 2 iterations: maximum number of iterations reached; largest residual .* N at node \d+"):
        jn.solve_static(scene, method="damped", max_iter=2)
    eq = jn.solve_static(scene, method="damped", max_iter=2, throw=False)
    assert not eq.converged and eq.reason == "maximum number of iterations reached"
    assert np.all(np.isfinite(np.asarray(eq.x)))
    worst = int(eq.worst_node)
    free = ~np.asarray(scene.nodes.fixed)
    nodal = np.linalg.norm(np.where(free, np.asarray(eq.force), 0.0), axis=1)
    assert nodal[worst] == pytest.approx(float(eq.residual_N))


def test_host_factorisation_with_its_ordering_reused_solves_changing_nonsymmetric_matrices():
    # One sparsity, several matrices (the tangents of a Newton solve): the ordering computed at the first
    # factorisation serves the later ones, whose values and pivots differ. A zero diagonal entry makes
    # the later matrices need an off-diagonal pivot.
    import scipy.sparse as sp

    from jaxnet import linalg

    rng = np.random.default_rng(3)
    n = 300
    a = sp.random(n, n, density=0.02, random_state=4) + sp.eye(n)
    pattern = (a + a.T).tocsr()
    pattern.sort_indices()
    solver = linalg.HostSolver(pattern.indptr, pattern.indices)
    b = rng.normal(size=n)
    for k in range(4):
        data = rng.normal(size=pattern.nnz) + (pattern.indices == np.repeat(np.arange(n), np.diff(pattern.indptr))) * 4.0
        if k == 3:
            data[pattern.indptr[5] + np.flatnonzero(pattern.indices[pattern.indptr[5]:pattern.indptr[6]] == 5)] = 0.0
        x, ok = solver.solve(data, b)
        A = sp.csr_matrix((data, pattern.indices, pattern.indptr), shape=(n, n))
        assert ok and np.abs(A @ x - b).max() <= 1e-10 * np.abs(b).max() * np.abs(data).max() * n
        np.testing.assert_allclose(x, sp.linalg.spsolve(A.tocsc(), b), rtol=1e-8, atol=1e-10)


def test_host_loop_and_jitted_loop_are_the_same_iteration():
    # solve() drives the Newton from the host; newton_loop is the same iteration as one jitted program.
    # Same rules, same arithmetic: same iterates up to roundoff.
    from jaxnet import model as model_lib
    from jaxnet.model import assemble
    from jaxnet.solve import newton

    scene = framed_panel(meshes=12, step=0.1, sinker_kg=2.0).scene
    host = jn.solve_static(scene, method="damped", tol=1e-8)
    model = model_lib.active_terms(scene)
    pattern = assemble.build_pattern(scene, model)
    start = np.asarray(scene.nodes.position).ravel()[np.asarray(pattern.free)]
    jitted = newton.newton_loop_jit(start, scene, pattern, model=model, solver=jn.Newton(tol=1e-8))
    assert int(jitted.iterations) == int(host.iterations) and bool(jitted.converged)
    np.testing.assert_allclose(np.asarray(jitted.x), np.asarray(host.x), atol=1e-9)
    np.testing.assert_allclose(np.asarray(jitted.force), np.asarray(host.force), atol=1e-6)



def test_the_pattern_is_kept_for_the_same_net_and_rebuilt_for_another():
    # build_pattern is kept by a digest of the fixed coordinates and the connectivity: an equal scene (a
    # warm solve, another load) gets the same pattern; another fixing gets its own, with one node fewer free
    import dataclasses

    import jax

    from jaxnet import model as model_lib
    from jaxnet.model import assemble

    net = framed_panel(meshes=12, step=0.1, sinker_kg=2.0).net
    scene, again = net.build(), net.build()
    model = model_lib.active_terms(scene)
    first = assemble.build_pattern(scene, model)
    assert assemble.build_pattern(again, model) is first
    fixed = np.asarray(scene.nodes.fixed).copy()
    node = int(np.flatnonzero(~fixed.all(axis=1))[0])
    freed = int((~fixed[node]).sum())
    fixed[node] = True
    held = dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, fixed=fixed))
    other = assemble.build_pattern(held, model)
    assert other is not first and other.n == first.n - freed > 0
    fresh = assemble.pattern_of(held, assemble.stiff_families(model), fixed.ravel())
    assert all(np.array_equal(np.asarray(a), np.asarray(b))
               for a, b in zip(jax.tree.leaves(other), jax.tree.leaves(fresh)))

def test_stiffness_continuation_stages_rise_geometrically_to_the_net_as_it_is():
    from jaxnet.solve import newton

    stages = newton.stiffness_stages(jn.Newton(soft_start=1e-2, stiffening=10**0.5))
    np.testing.assert_allclose(stages, [1e-2, 10**-1.5, 1e-1, 10**-0.5, 1.0], rtol=1e-12)
    assert newton.stiffness_stages(jn.Newton(stall_window=None)) == [1.0]


def test_stall_is_a_residual_that_stopped_halving():
    from jaxnet.solve import newton

    steady = 100.0 * 0.3 ** np.arange(12)  # converging: never stalled
    bouncing = np.array([300.0, 900, 250, 700, 400, 800, 600, 500, 900, 300])  # best of the last 5 = 300
    assert not any(newton.stalled(steady[:k], 5) for k in range(1, 13))
    assert newton.stalled(bouncing, 5)
    assert not newton.stalled(bouncing[:9], 5)  # too short to judge
    assert newton.stalled(bouncing[:1], 0) and not newton.stalled(bouncing, None)


def test_stiffness_continuation_changes_the_path_not_the_equilibrium(capsys):
    # The continuation solves softer nets first; its last stage is the net as it is, so it must land on
    # plain Newton's equilibrium (unique here: EA_c = 0 makes the energy convex, all twines taut).
    scene = framed_panel(meshes=16, step=0.08, sinker_kg=2.0).scene
    plain = jn.solve_static(scene, method="damped", tol=1e-8, stall_window=None)
    softened = jn.solve_static(scene, method="damped", tol=1e-8, stall_window=0, verbose=True)
    printed = capsys.readouterr().out
    assert [line.split()[-1] for line in printed.splitlines() if line.startswith("  stiffness x")] == ["0.01", "0.0316", "0.1", "0.316", "1"]
    assert softened.converged and int(softened.iterations) > int(plain.iterations)
    np.testing.assert_allclose(np.asarray(softened.x), np.asarray(plain.x), atol=1e-7)


def test_a_solve_with_a_catch_compiles_its_evaluation_and_tangent_once(caplog):
    # The tangent is compiled (while the evaluation compiles) before the loop, with placeholders for
    # the catch front state; the loop must then reuse it. A weakly typed leaf in the evaluation's state
    # (from a Python scalar) once made it compile a second time at the first iteration: seconds, cold.
    import jax

    from jaxnet.scenes.codend import codend
    from jaxnet.solve import programs

    scene = codend(meshes_around=8, meshes_along=6, catch_m3=0.01).scene
    jax.clear_caches()
    programs.clear()
    # the once-per-process probe of which XLA options the compiler takes (a one-line program): done before the
    # count, which would otherwise see it or not by whether an earlier test of this process compiled anything
    programs.compiler_options()
    was_logging = jax.config.jax_log_compiles  # put back as it was (JAX_LOG_COMPILES may have set it)
    jax.config.update("jax_log_compiles", True)  # globally: the pieces compile in worker threads
    try:
        with caplog.at_level("WARNING"):
            eq = jn.solve_static(scene)
    finally:
        jax.config.update("jax_log_compiles", was_logging)
    compiled = [r.getMessage().split(" with ")[0] for r in caplog.records if r.getMessage().startswith("Compiling jit(")]
    assert eq.converged
    # the evaluation (from the last states: _evaluate_from), the tangent: its element matrices, their sum
    once = ("_evaluate_from", "_tangent_from", "scatter_stiffnesses")
    assert all(compiled.count(f"Compiling jit({name})") == 1 for name in once), sorted(set(compiled))
    # and nothing else but the spring network and the loads: no JAX operation run one by one on the way (jax
    # 0.10 compiles a program for each: jnp.asarray of a numpy array, a comparison, a placeholder's zeros;
    # 0.2-1 s of a first solve of FEMNET's c2, one of them stalled behind the big compilations)
    assert set(compiled) == {f"Compiling jit({name})" for name in once + ("springs", "loads")}, sorted(set(compiled))
    # the result's figures likewise: one program of the net's figures (tensions, opening angles, the forces of
    # the external terms: jaxnet.figures.net_figures) and one of the catch, not an operation at a time
    caplog.clear()
    jax.config.update("jax_log_compiles", True)
    try:
        with caplog.at_level("WARNING"):
            summary = jn.figures.summary(scene, eq)
    finally:
        jax.config.update("jax_log_compiles", was_logging)
    compiled = [r.getMessage().split(" with ")[0] for r in caplog.records if r.getMessage().startswith("Compiling")]
    assert sorted(compiled) == [f"Compiling jit({name})" for name in ("_catch", "_net_figures")]
    catch_report = summary["catch"]
    assert catch_report["holds_the_volume"] and catch_report["volume_whole_net_m3"] == pytest.approx(0.01, rel=1e-9)


def test_stiffness_continuation_softens_the_net_not_its_weight_and_buoyancy():
    # The continuation scales the net's elastic energies only: scaling the potential of weight and
    # buoyancy at the free surface too would sink the cage's floats in the soft stages (the default cage
    # then stalled, no step decreasing the energy).
    from jaxnet import model as model_lib
    from jaxnet.model import assemble
    from jaxnet.scenes.cage import fish_cage

    scene = fish_cage(step=1.0).scene
    terms = model_lib.active_terms(scene)
    elastic = tuple(t for t in terms if t.term.kind == "energy" and t.term.elastic)
    others = tuple(t for t in terms if t.term.kind == "energy" and not t.term.elastic)
    assert [t.name for t in elastic] == ["netting_tension", "bar_tension"] and len(others) == 3
    rng = np.random.default_rng(1)
    x = np.asarray(scene.nodes.position) + rng.uniform(-0.05, 0.05, (scene.n_nodes, 3))
    e_elastic, e_others = float(assemble.energy(x, scene, elastic)), float(assemble.energy(x, scene, others))
    assert abs(e_elastic) > 1.0 and abs(e_others) > 1.0
    assert float(assemble.energy(x, scene, terms, 0.01)) == pytest.approx(0.01 * e_elastic + e_others, rel=1e-12)


def test_a_continuation_that_cannot_finish_gives_way_to_plain_newton(capsys):
    # The continuation gets half the iterations left when it starts; if its stages do not reach the net
    # as it is by then (or a softened net stalls), plain Newton resumes from where the continuation began,
    # so a misjudged start of the continuation costs iterations, never the solve.
    scene = framed_panel(meshes=16, step=0.08, sinker_kg=2.0).scene
    plain = jn.solve_static(scene, method="damped", tol=1e-8, stall_window=None)
    n = int(plain.iterations)
    rescued = jn.solve_static(scene, method="damped", tol=1e-8, stall_window=0, max_iter=2 * n + 2, verbose=True)
    assert "stiffness continuation abandoned" in capsys.readouterr().out
    assert rescued.converged and int(rescued.iterations) == (2 * n + 2) // 2 + n
    np.testing.assert_allclose(np.asarray(rescued.x), np.asarray(plain.x), atol=1e-7)


def test_the_continuation_starts_only_on_over_stretched_iterates():
    # stalled AND the twines pulling far harder than the loads (balancing scale << 1)
    from jaxnet.solve import newton

    applied = np.array([1.0, -2.0, 0.5])
    assert newton.balancing_scale(applied, 0.0 * applied) == pytest.approx(1.0)  # balanced by the net
    assert newton.balancing_scale(applied, applied - 1e4 * applied) == pytest.approx(1e-4)
    bouncing = np.array([300.0, 900, 250, 700, 400, 800, 600, 500, 900, 300])
    opts = jn.Newton(stall_window=5, soften_below=1e-3)
    assert newton.overstretched(bouncing, [1e-4] * 10, opts)
    assert not newton.overstretched(bouncing, [1e-4] * 5 + [0.05] * 5, opts)  # stalls, carrying its loads
    assert not newton.overstretched(100.0 * 0.3 ** np.arange(10), [1e-4] * 10, opts)  # converging
