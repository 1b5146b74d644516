"""PardisoSolver (jaxnet.linalg, jaxnet.linalg.pardiso): the same checks as SuperLU's HostSolver (tests/linalg/test_linalg.py)
on the same matrices: solutions against numpy's dense solve, transposed solves on one factor, several
right-hand sides, a nearly singular net tangent solved backward stably, a zero diagonal block, singular and
non-finite matrices refused without NaN; and which solver jaxnet picks.

MKL is a dependency of jaxnet on x86-64 (pyproject.toml): there PARDISO must be found, and these tests run.
Elsewhere MKL does not exist and jaxnet factorises with SuperLU alone; the PARDISO tests then have nothing to
test and say so.
"""

import platform

import numpy as np
import pytest

from jaxnet import linalg
from jaxnet.linalg import pardiso
from test_linalg import backward_error, block_mask, csr, kkt, net_tangent, random_on, sheet

needs_mkl = pytest.mark.skipif(platform.machine() not in ("x86_64", "AMD64") and pardiso.library() is None,
                               reason="MKL exists on x86-64 only: SuperLU alone factorises here")


def test_mkl_is_found_wherever_it_is_a_dependency():
    if platform.machine() in ("x86_64", "AMD64"):
        assert pardiso.library() is not None


@needs_mkl
def test_random_block_systems_and_their_transposes_match_the_dense_solve():
    rng = np.random.default_rng(1)
    x, edges = sheet()
    mask = block_mask(len(x), edges)
    A = random_on(mask, rng)
    indptr, indices, data = csr(mask, A)
    solver = linalg.PardisoSolver(indptr, indices)
    b = rng.standard_normal(A.shape[0])
    xs, ok = solver.solve(data, b)
    assert ok and solver.fallbacks == 0 and solver.factor_entries > len(data) // 2
    np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-12 * np.abs(xs).max())
    xt, ok = solver.solve(data, b, transpose=True, reuse=True)
    assert ok and solver.factorizations == 1  # the transposed solve on the same factor
    np.testing.assert_allclose(xt, np.linalg.solve(A.T, b), rtol=0, atol=1e-12 * np.abs(xt).max())


@needs_mkl
def test_a_nearly_singular_net_tangent_is_solved_backward_stably():
    rng = np.random.default_rng(2)
    mask, A = net_tangent(rng)
    cond = np.linalg.cond(A)
    assert cond > 1e10
    indptr, indices, data = csr(mask, A)
    solver = linalg.PardisoSolver(indptr, indices)
    for _ in range(2):  # the second matrix reuses the analysis
        b = rng.standard_normal(A.shape[0])
        xs, ok = solver.solve(data, b)
        assert ok and backward_error(A, xs, b) < 1e-14 and solver.backward_error < 1e-14
        np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-15 * cond * np.abs(xs).max())


@needs_mkl
def test_a_zero_diagonal_block_is_solved_accurately_by_the_fallback():
    # PARDISO perturbs the zero pivots of the saddle point instead of exchanging rows: the matrix is then
    # factorised again by SuperLU with partial pivoting, and solved accurately
    rng = np.random.default_rng(3)
    mask, A = kkt(rng, eps=0.0)
    indptr, indices, data = csr(mask, A)
    b = rng.standard_normal(A.shape[0])
    solver = linalg.PardisoSolver(indptr, indices)
    xs, ok = solver.solve(data, b)
    assert ok and solver.fallbacks == 1 and backward_error(A, xs, b) < 1e-14
    np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-11 * np.abs(xs).max())


@needs_mkl
def test_singular_or_non_finite_matrices_give_ok_false_and_no_nan():
    rng = np.random.default_rng(5)
    x, edges = sheet()
    mask = block_mask(len(x), edges)
    A = random_on(mask, rng)
    A[7, :] = A[:, 7] = 0.0  # a dof with no stiffness at all: exactly singular
    indptr, indices, data = csr(mask, A)
    b = rng.standard_normal(A.shape[0])
    solver = linalg.PardisoSolver(indptr, indices)
    xs, ok = solver.solve(data, b)
    assert not ok and np.all(xs == 0) and not solver.ok
    assert solver.fallbacks == 1  # PARDISO perturbed the zero pivot: partial pivoting refused the matrix
    bad = data.copy()
    bad[3] = np.nan
    xs, ok = solver.solve(bad, b)
    assert not ok and np.all(xs == 0)
    good = csr(mask, random_on(mask, rng))[2]  # a regular matrix afterwards is solved again
    xs, ok = solver.solve(good, b)
    assert ok and np.all(np.isfinite(xs))


@needs_mkl
def test_several_right_hand_sides_equal_column_by_column_solves():
    rng = np.random.default_rng(6)
    mask, A = net_tangent(rng, mu=1e-3)
    indptr, indices, data = csr(mask, A)
    solver = linalg.PardisoSolver(indptr, indices)
    assert solver.factorize(2 * data) and solver.factorize(data)
    B = rng.standard_normal((A.shape[0], 4))
    X = solver.apply(B)
    assert X.shape == B.shape and solver.ok
    for j in range(B.shape[1]):
        # PARDISO solves several columns with other kernels than one: the same to rounding, not to the bit
        np.testing.assert_allclose(X[:, j], solver.apply(B[:, j]), rtol=0, atol=1e-11 * np.abs(X).max())
    np.testing.assert_allclose(X, np.linalg.solve(A, B), rtol=0, atol=1e-9 * np.abs(X).max())


@needs_mkl
def test_the_same_matrix_gives_the_same_bits():
    # a solve does not depend on what was solved before (SuperLU's first factorisation of a structure orders
    # itself and the later ones take the stored permutation: their last bits differ)
    rng = np.random.default_rng(8)
    mask, A = net_tangent(rng, mu=1e-3)
    indptr, indices, data = csr(mask, A)
    b = rng.standard_normal(A.shape[0])
    solver = linalg.PardisoSolver(indptr, indices)
    first, _ = solver.solve(data, b)
    solver.solve(2 * data, b)
    again, _ = solver.solve(data, b)
    fresh, _ = linalg.PardisoSolver(indptr, indices).solve(data, b)
    assert np.array_equal(first, again) and np.array_equal(first, fresh)


def test_the_choice_of_solver(monkeypatch):
    x, edges = sheet()
    indptr, indices, _ = csr(block_mask(len(x), edges), np.zeros((3 * len(x),) * 2))
    monkeypatch.setenv(pardiso.CHOICE, "superlu")
    assert type(linalg.direct_solver(indptr, indices)) is linalg.HostSolver
    monkeypatch.delenv(pardiso.CHOICE)
    expected = linalg.PardisoSolver if pardiso.library() is not None else linalg.HostSolver
    assert type(linalg.direct_solver(indptr, indices)) is expected


@needs_mkl
def test_a_solve_does_not_depend_on_the_solves_before_it():
    # the first static solve of a scene in a process and the next ones give the same bits (with SuperLU they
    # did not: the first factorisation of a structure orders itself, the later ones take the stored
    # permutation, and a slow, chaotic convergence amplified the last bits into other iteration counts)
    import jaxnet as jn
    from jaxnet.net import Twine
    from jaxnet.scenes.panel import hanging_panel

    scene = hanging_panel(meshes=8, step=0.05, twine=Twine(l0=0.025, ea=2000.0, diameter=1.5e-3,
                                                           ea_compression=0.0)).scene
    first = jn.solve_static(scene, max_iter=40, throw=False)
    second = jn.solve_static(scene, max_iter=40, throw=False)
    assert int(first.iterations) == int(second.iterations) > 5
    assert np.array_equal(np.asarray(first.x), np.asarray(second.x))


@needs_mkl
def test_a_cage_solved_twice_gives_the_same_bits():
    """PARDISO's multithreaded factorisation in MKL's reproducible mode (pardiso.CNR): two solves of the default
    cage in a current (1161 nodes, a tangent large enough for MKL's threads) give the same positions to the last
    bit and the same iterations. Without the mode they differed by about 1e-13 m, and on the 10⁴-node cage by two
    iterations."""
    import os

    import jaxnet as jn
    from jaxnet.scenes import fish_cage

    scene = fish_cage(step=0.5, current=0.5).scene
    first = jn.solve_static(scene, throw=False)
    second = jn.solve_static(scene, throw=False)
    assert os.environ.get(pardiso.CNR[0]) is not None  # set when jaxnet loaded MKL, or by the user
    assert int(first.iterations) == int(second.iterations) > 20
    assert np.array_equal(np.asarray(first.x), np.asarray(second.x))


@needs_mkl
# the singular chain's steps are as large as float64 holds: their norms overflow, as the test means them to
@pytest.mark.filterwarnings("ignore:overflow encountered:RuntimeWarning",
                            "ignore:invalid value encountered:RuntimeWarning")
def test_a_static_solve_counts_its_fallbacks():
    """Timing.fallbacks: a hanging chain whose last node is held by a bar of a stiffness 1e-300 N (below rounding
    beside the other bar's 1000 N: a coordinate whose tangent is singular in float64; a stiffness of exactly 0 is
    refused as bad input) has every factorisation redone by SuperLU; the same chain with a stiff last bar has
    none."""
    import jaxnet as jn
    from jaxnet.scene import Bars, Nodes, Scene

    def chain(ea_last):
        nodes = Nodes(position=np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 0.0, -2.0]]),
                      fixed=np.array([[True] * 3, [False] * 3, [False] * 3]), mass=np.array([0.0, 1.0, 0.5]),
                      volume=np.zeros(3), force=np.zeros((3, 3)))
        bars = Bars(ends=np.array([[0, 1], [1, 2]]), rest_length=np.ones(2), ea_traction=np.array([1000.0, ea_last]),
                    ea_compression=np.zeros(2), diameter=np.zeros(2), density=np.zeros(2), cable=np.array([0, 1]))
        return Scene(nodes=nodes, bars=bars)

    singular = jn.solve_static(chain(1e-300), throw=False, max_iter=5).timing
    assert singular.factorisations >= 1 and singular.fallbacks == singular.factorisations
    held = jn.solve_static(chain(1000.0), throw=False, max_iter=50)
    assert held.converged and held.timing.fallbacks == 0
