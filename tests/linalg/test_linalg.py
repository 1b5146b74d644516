"""HostSolver (jaxnet.linalg): sparse direct solves with diagonal-preferring pivots, a backward-error check,
iterative refinement and a fallback to partial pivoting. Checked against numpy's dense solve on matrices
with the pattern of a net's tangent (3x3 blocks on a small triangulated sheet)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
import scipy.sparse as sp

from jaxnet import linalg


def sheet(nx=5, ny=4):
    """Positions (N, 3) and edges (E, 2) of a flat triangulated nx x ny grid (each square split in two)."""
    ids = np.arange(nx * ny).reshape(ny, nx)
    edges = np.concatenate([np.stack([ids[:, :-1].ravel(), ids[:, 1:].ravel()], 1),
                            np.stack([ids[:-1, :].ravel(), ids[1:, :].ravel()], 1),
                            np.stack([ids[:-1, :-1].ravel(), ids[1:, 1:].ravel()], 1)])
    y, x = np.divmod(np.arange(nx * ny), nx)
    return np.stack([x, y, np.zeros_like(x)], 1).astype(float), edges


def block_mask(n_nodes, edges):
    """Dof pattern (3 dof per node): a full 3x3 block for each node and each pair of nodes of an edge."""
    adj = np.eye(n_nodes, dtype=bool)
    adj[edges[:, 0], edges[:, 1]] = adj[edges[:, 1], edges[:, 0]] = True
    return np.kron(adj, np.ones((3, 3), dtype=bool))


def csr(mask, dense):
    """CSR structure of ``mask`` (zeros kept as stored entries) and the values of ``dense`` on it."""
    m = sp.csr_matrix(mask.astype(float))
    m.sort_indices()
    rows = np.repeat(np.arange(mask.shape[0]), np.diff(m.indptr))
    return m.indptr, m.indices, dense[rows, m.indices]


def random_on(mask, rng, shift=6.0):
    """Nonsymmetric random values on ``mask`` plus ``shift`` on the diagonal (well conditioned)."""
    return np.where(mask, rng.standard_normal(mask.shape), 0.0) + shift * np.eye(mask.shape[0])


def net_tangent(rng, mu=1e-8, drag=1e-5):
    """A net-like tangent K + mu S: twines as axial springs on a flat sheet (no out-of-plane stiffness, a
    third of them slack), S their spring network (EA/l0 I blocks), one row of nodes held by stiff anchors,
    and a small nonsymmetric 'drag' part. Nearly singular for small mu."""
    x, edges = sheet()
    n_nodes = len(x)
    K = np.zeros((3 * n_nodes, 3 * n_nodes))
    S = np.zeros_like(K)
    for a, b in edges:
        e = (x[b] - x[a]) / np.linalg.norm(x[b] - x[a])
        k = rng.uniform(1e3, 1e4)
        for block, value in ((K, k * rng.integers(0, 2) * np.outer(e, e)), (S, k * np.eye(3))):
            for i, j, sign in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
                block[3 * i:3 * i + 3, 3 * j:3 * j + 3] += sign * value
    anchors = np.repeat(3 * np.arange(5), 3) + np.tile(np.arange(3), 5)
    K[anchors, anchors] += 1e6
    mask = block_mask(n_nodes, edges)
    return mask, K + mu * S + drag * np.where(mask, rng.standard_normal(mask.shape), 0.0)


def backward_error(A, x, b):
    return np.abs(A @ x - b).max() / (np.abs(A).sum(1).max() * np.abs(x).max() + np.abs(b).max())


def test_random_block_systems_match_the_dense_solve():
    rng = np.random.default_rng(0)
    x, edges = sheet()
    mask = block_mask(len(x), edges)
    for _ in range(3):
        A = random_on(mask, rng)
        indptr, indices, data = csr(mask, A)
        b = rng.standard_normal(A.shape[0])
        xs, ok = linalg.HostSolver(indptr, indices).solve(data, b)
        assert ok
        np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-12 * np.abs(xs).max())


def test_the_ordering_is_computed_once_and_reused_for_new_values():
    rng = np.random.default_rng(1)
    x, edges = sheet()
    mask = block_mask(len(x), edges)
    A1, A2 = random_on(mask, rng), random_on(mask, rng)
    indptr, indices, data1 = csr(mask, A1)
    data2 = csr(mask, A2)[2]
    solver = linalg.HostSolver(indptr, indices)
    b = rng.standard_normal(A1.shape[0])
    x1, ok1 = solver.solve(data1, b)
    order = solver.order
    assert order is not None and sorted(order) == list(range(A1.shape[0]))
    x2, ok2 = solver.solve(data2, b)
    assert ok1 and ok2 and solver.order is order and solver.factorizations == 2 and solver.fallbacks == 0
    np.testing.assert_allclose(x2, np.linalg.solve(A2, b), rtol=0, atol=1e-12 * np.abs(x2).max())
    # the factor of the second matrix, not the first, is stored and applied
    np.testing.assert_allclose(solver.apply(A2 @ x1), x1, rtol=0, atol=1e-12 * np.abs(x1).max())



def test_a_second_solver_of_the_same_structure_takes_the_first_ones_ordering():
    # a warm solve (a new HostSolver on a structure already factorised) skips the ordering step: it takes
    # the same permutation, with its own permuted matrix, and solves as accurately
    rng = np.random.default_rng(11)
    x, edges = sheet(6, 5)
    mask = block_mask(len(x), edges)
    A1, A2 = random_on(mask, rng), random_on(mask, rng)
    indptr, indices, data1 = csr(mask, A1)
    data2 = csr(mask, A2)[2]
    b = rng.standard_normal(A1.shape[0])
    first = linalg.HostSolver(indptr, indices)
    assert first.solve(data1, b)[1]
    second = linalg.HostSolver(indptr.copy(), indices.copy())  # equal arrays, not the same objects
    x2, ok = second.solve(data2, b)
    assert ok and second.order is first.order and second._permuted is not first._permuted
    np.testing.assert_allclose(x2, np.linalg.solve(A2, b), rtol=0, atol=1e-12 * np.abs(x2).max())
    # the first solver's factor is untouched by the second's factorisation
    np.testing.assert_allclose(first.apply(b), np.linalg.solve(A1, b), rtol=0, atol=1e-11 * np.abs(first.apply(b)).max())
    # another structure gets its own ordering
    other = block_mask(len(x), edges[:-3])
    other_indptr, other_indices, other_data = csr(other, random_on(other, rng))
    third = linalg.HostSolver(other_indptr, other_indices)
    assert third.solve(other_data, b)[1] and third.order is not first.order

def test_a_nearly_singular_net_tangent_is_solved_backward_stably():
    rng = np.random.default_rng(2)
    mask, A = net_tangent(rng)
    cond = np.linalg.cond(A)
    assert cond > 1e10  # the slack, flat sheet: only mu S holds it out of plane
    indptr, indices, data = csr(mask, A)
    solver = linalg.HostSolver(indptr, indices)
    for _ in range(2):  # the second matrix goes through the stored ordering
        b = rng.standard_normal(A.shape[0])
        xs, ok = solver.solve(data, b)
        assert ok and backward_error(A, xs, b) < 1e-14 and solver.backward_error < 1e-14
        # forward error within what the conditioning allows
        np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-15 * cond * np.abs(xs).max())


def kkt(rng, eps):
    """Saddle-point matrix [[H, B], [B^T, -eps I]] (H: random on a sheet's pattern, each constraint on
    two dofs of one node), its (2,2) block stored though zero for eps = 0."""
    x, edges = sheet(4, 3)
    H = random_on(block_mask(len(x), edges), rng)
    n, m = H.shape[0], 4
    B = np.zeros((n, m))
    for j in range(m):
        B[[6 * j, 6 * j + 1], j] = rng.standard_normal(2)
    A = np.block([[H, B], [B.T, -eps * np.eye(m)]])
    mask = (A != 0) | np.eye(n + m, dtype=bool)
    return mask | mask.T, A


def test_a_zero_diagonal_block_is_pivoted_off_the_diagonal_and_solved_accurately():
    rng = np.random.default_rng(3)
    mask, A = kkt(rng, eps=0.0)
    indptr, indices, data = csr(mask, A)
    b = rng.standard_normal(A.shape[0])
    solver = linalg.HostSolver(indptr, indices)
    xs, ok = solver.solve(data, b)
    assert ok and backward_error(A, xs, b) < 1e-14
    np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-11 * np.abs(xs).max())


def test_moderate_pivot_growth_is_mended_by_iterative_refinement():
    # A 1e-10 diagonal taken as a pivot (no threshold): the first solution's backward error is ~1e-9,
    # one refinement step with the same factor brings it to roundoff, no refactorisation.
    rng = np.random.default_rng(4)
    mask, A = kkt(rng, eps=1e-10)
    indptr, indices, data = csr(mask, A)
    solver = linalg.HostSolver(indptr, indices, pivot_threshold=0.0)
    b = rng.standard_normal(A.shape[0])
    xs, ok = solver.solve(data, b)
    assert ok and solver.refinements == 1 and solver.fallbacks == 0
    assert backward_error(A, xs, b) < 1e-14
    np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-9 * np.abs(xs).max())


def test_tiny_diagonal_pivots_are_caught_by_the_check_and_refactorised_with_partial_pivoting():
    # Without a threshold a 1e-30 diagonal is taken as a pivot: growth 1e30, an inaccurate solution that
    # refinement cannot mend; the check sends it to partial pivoting, and each such matrix is counted.
    rng = np.random.default_rng(4)
    mask, A = kkt(rng, eps=1e-30)
    indptr, indices, data = csr(mask, A)
    solver = linalg.HostSolver(indptr, indices, pivot_threshold=0.0)
    for count in (1, 2):
        b = rng.standard_normal(A.shape[0])
        xs, ok = solver.solve(data, b)
        assert ok and solver.fallbacks == count and solver.refinements == 2 * count
        assert backward_error(A, xs, b) < 1e-14
        np.testing.assert_allclose(xs, np.linalg.solve(A, b), rtol=0, atol=1e-11 * np.abs(xs).max())
    # the default threshold rejects such pivots in the first factorisation: no fallback needed
    default = linalg.HostSolver(indptr, indices)
    xs, ok = default.solve(data, b)
    assert ok and default.fallbacks == 0 and backward_error(A, xs, b) < 1e-14


def test_singular_or_non_finite_matrices_give_ok_false_and_no_nan():
    rng = np.random.default_rng(5)
    x, edges = sheet()
    mask = block_mask(len(x), edges)
    A = random_on(mask, rng)
    A[7, :] = A[:, 7] = 0.0  # a dof with no stiffness at all: exactly singular
    indptr, indices, data = csr(mask, A)
    b = rng.standard_normal(A.shape[0])
    solver = linalg.HostSolver(indptr, indices)
    xs, ok = solver.solve(data, b)
    assert not ok and np.all(xs == 0) and not solver.ok
    assert np.all(solver.apply(b) == 0)  # no factor kept
    assert solver.fallbacks == 1  # partial pivoting was tried too
    bad = data.copy()
    bad[3] = np.nan
    xs, ok = solver.solve(bad, b)
    assert not ok and np.all(xs == 0) and solver.fallbacks == 1  # not factorised at all
    # a node with no stiffness in any direction, after a regular matrix (through the stored ordering)
    assert solver.solve(csr(mask, random_on(mask, rng))[2], b)[1] and solver.order is not None
    A = random_on(mask, rng)
    A[9:12, :] = A[:, 9:12] = 0.0
    xs, ok = solver.solve(csr(mask, A)[2], b)
    assert not ok and np.all(xs == 0) and solver.fallbacks == 2


def test_several_right_hand_sides_equal_column_by_column_solves():
    rng = np.random.default_rng(6)
    mask, A = net_tangent(rng, mu=1e-3)
    indptr, indices, data = csr(mask, A)
    solver = linalg.HostSolver(indptr, indices)
    assert solver.factorize(2 * data) and solver.factorize(data)  # the second in the stored ordering
    B = rng.standard_normal((A.shape[0], 4))
    X = solver.apply(B)
    assert X.shape == B.shape and solver.ok
    for j in range(B.shape[1]):
        np.testing.assert_allclose(X[:, j], solver.apply(B[:, j]), rtol=0, atol=1e-13 * np.abs(X).max())
    np.testing.assert_allclose(X, np.linalg.solve(A, B), rtol=0, atol=1e-9 * np.abs(X).max())
    assert solver.apply(B[:, :1]).shape == (A.shape[0], 1)


def test_the_jitted_solve_calls_the_same_solver():
    rng = np.random.default_rng(7)
    x, edges = sheet()
    mask = block_mask(len(x), edges)
    A = random_on(mask, rng)
    indptr, indices, data = csr(mask, A)
    b = rng.standard_normal(A.shape[0])
    xs, ok = jax.jit(linalg.solve)(jnp.asarray(data), jnp.asarray(b), jnp.asarray(indptr), jnp.asarray(indices))
    assert bool(ok)
    np.testing.assert_allclose(np.asarray(xs), np.linalg.solve(A, b), rtol=0, atol=1e-12 * np.abs(xs).max())
    xs, ok = jax.jit(linalg.solve)(jnp.zeros_like(data), jnp.asarray(b), jnp.asarray(indptr), jnp.asarray(indices))
    assert not bool(ok) and np.all(np.asarray(xs) == 0)


def test_the_jitted_solve_packs_every_argument_kind_and_keeps_structures_apart():
    """solve() hands the host one packed array: int32 and int64 structures, several right-hand sides, the
    transposed system and a vmapped batch all come back right, and two structures solved in turn (the
    host's last-solver shortcut) each get their own factorisation."""
    rng = np.random.default_rng(8)
    x, edges = sheet()
    # the second system: the same sheet with its nodes renumbered, so both structures have the same sizes
    # and differ only in their column indices
    renumber = rng.permutation(len(x))
    systems = []
    for e in (edges, renumber[edges]):
        mask = block_mask(len(x), e)
        A = random_on(mask, rng)
        systems.append((A,) + csr(mask, A))
    assert systems[0][1].shape == systems[1][1].shape and systems[0][2].shape == systems[1][2].shape
    assert not np.array_equal(systems[0][2], systems[1][2])
    solve = jax.jit(linalg.solve, static_argnames=("transpose",))
    for _ in range(2):
        for (A, indptr, indices, data), itype in zip(systems, (jnp.int32, jnp.int64)):
            B = rng.standard_normal((A.shape[0], 3))
            args = (jnp.asarray(data), jnp.asarray(B), jnp.asarray(indptr, itype), jnp.asarray(indices, itype))
            X, ok = solve(*args)
            assert bool(ok)
            np.testing.assert_allclose(np.asarray(X), np.linalg.solve(A, B), rtol=0, atol=1e-12 * np.abs(X).max())
            Xt, ok = solve(*args, transpose=True)
            np.testing.assert_allclose(np.asarray(Xt), np.linalg.solve(A.T, B), rtol=0, atol=1e-12 * np.abs(Xt).max())
    # a batch of matrices on one structure (vmap: one host call per member)
    A, indptr, indices, data = systems[0]
    scales = jnp.asarray([1.0, 2.0, -3.0])
    b = rng.standard_normal(A.shape[0])
    xs, oks = jax.vmap(lambda s: linalg.solve(s * jnp.asarray(data), jnp.asarray(b), jnp.asarray(indptr),
                                              jnp.asarray(indices)))(scales)
    assert np.all(np.asarray(oks))
    for s, xv in zip(np.asarray(scales), np.asarray(xs)):
        np.testing.assert_allclose(xv, np.linalg.solve(s * A, b), rtol=0, atol=1e-12 * np.abs(xv).max())


def _resident_bytes():
    with open("/proc/self/status") as status:
        return next(int(line.split()[1]) * 1024 for line in status if line.startswith("VmRSS"))


def test_factors_made_in_callbacks_are_freed_whatever_thread_state_calls_back():
    """XLA calls back from threads Python did not make, with a new thread state at every call, and scipy's
    SuperLU frees a factor's memory only from the thread state that allocated it: factorised directly in
    such calls, every factor kept until the next call leaked (the size of L and U per call). Emulated here
    with threads made by the C library (pthread_create through ctypes, as XLA's are), each calling the
    callback's host function once: memory must not grow with the number of calls, and the solutions must
    stay right."""
    import ctypes

    m = 120  # a 5-point Laplacian on a 120 x 120 grid: its factor takes 7 MB
    lap = sp.diags([-1.0, -1.0, 4.001, -1.0, -1.0], [-m, -1, 0, 1, m], shape=(m * m, m * m)).tocsr()
    n = lap.shape[0]
    b = np.linspace(-1.0, 1.0, n)
    packed = np.concatenate([lap.data, b, lap.indptr.astype(float), lap.indices.astype(float)])
    results = []

    def callback(_):
        results.append(linalg._host_solve_packed(packed, lap.nnz, (n,)))
        return 0

    entry = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p)(callback)
    libc = ctypes.CDLL(None)

    def foreign_call():
        thread = ctypes.c_ulong()
        assert libc.pthread_create(ctypes.byref(thread), None, entry, None) == 0
        assert libc.pthread_join(thread, None) == 0

    for _ in range(2):  # the solver, its ordering and the worker thread exist after these
        foreign_call()
    before = _resident_bytes()
    calls = 30
    for _ in range(calls):
        foreign_call()
    growth = _resident_bytes() - before
    factor_bytes = max(s.factor_entries for s in linalg._SOLVERS.values() if s.n == n) * 12
    assert factor_bytes > 5e6
    # leaking, memory grew by about one factor per call (measured: 196 MB for 30 calls)
    assert growth < 0.1 * calls * factor_bytes, (growth, factor_bytes)
    assert len(results) == calls + 2
    for x, ok in results:
        assert bool(ok)
        np.testing.assert_allclose(lap @ x, b, atol=1e-10)


def test_the_sparse_solver_is_chosen_by_the_environment_and_refused_by_name(monkeypatch):
    """``JAXNET_SPARSE_SOLVER`` names the factorisation (superlu, pardiso, cudss); unset, cuDSS on a GPU where it
    is installed, else PARDISO where MKL is, else SuperLU. A name it does not know, or a solver that cannot run
    here, is refused with the variable, the value and what to do -- before anything compiles, by the static,
    dynamic and differentiable solves."""
    import jaxnet as jn
    from jaxnet.linalg import cudss, pardiso
    from jaxnet.scenes.panel import hanging_panel
    from jaxnet.solve import dynamics, implicit

    indptr, indices = np.array([0, 1]), np.array([0])
    monkeypatch.setenv("JAXNET_SPARSE_SOLVER", "superlu")
    assert linalg.solver_choice() == "superlu" and type(linalg.direct_solver(indptr, indices)) is linalg.HostSolver
    monkeypatch.delenv("JAXNET_SPARSE_SOLVER")
    default = "cudss" if cudss.available() else ("pardiso" if pardiso.library() is not None else "superlu")
    assert linalg.solver_choice() == default
    monkeypatch.setenv("JAXNET_SPARSE_SOLVER", "MUMPS")
    with pytest.raises(ValueError, match="JAXNET_SPARSE_SOLVER='mumps': expected cudss, pardiso or superlu"):
        linalg.solver_choice()
    scene = hanging_panel(meshes=4, step=0.1).scene
    for entry in (lambda: jn.solve_static(scene), lambda: dynamics.simulate(scene, end_time=0.1),
                  lambda: implicit.structure_of(scene)):  # statics, dynamics, the differentiable equilibrium
        with pytest.raises(ValueError, match="JAXNET_SPARSE_SOLVER"):
            entry()
    monkeypatch.setenv("JAXNET_SPARSE_SOLVER", "cudss")
    try:
        cudss.require()
    except RuntimeError:  # no GPU with cuDSS here (CI): asked for, it is refused with the reason and the install
        with pytest.raises(ValueError, match=r"JAXNET_SPARSE_SOLVER=cudss: cuDSS cannot be used here.*pip install"):
            linalg.solver_choice()
    else:
        assert type(linalg.direct_solver(indptr, indices)) is linalg.CudssSolver


def test_the_transposed_structure_gathers_a_transpose_from_the_entries():
    """cuDSS solves with A only: the adjoints' A^T is factorised from A's entries gathered into A^T's CSR
    structure (:func:`jaxnet.linalg.cudss.transposed_structure`), explicit zeros and empty rows included."""
    from jaxnet.linalg import cudss

    rng = np.random.default_rng(3)
    a = sp.random(40, 40, density=0.15, random_state=4, format="csr") + sp.eye(40, format="csr")
    a = a.tolil()
    a[5, :] = 0.0  # an empty row (no entries) becomes an empty column
    a = a.tocsr()
    a.eliminate_zeros()
    a.data[::5] = 0.0  # explicit zeros stay entries of the pattern
    a.sort_indices()
    slot, indptr_t, indices_t = cudss.transposed_structure(a.indptr, a.indices)
    assert slot.shape == a.data.shape and np.array_equal(np.sort(slot), np.arange(a.nnz))
    for _ in range(2):  # any entries of A, on the same structure
        data = rng.normal(size=a.nnz)
        at = sp.csr_matrix((data[slot], indices_t, indptr_t), shape=a.shape)
        np.testing.assert_array_equal(at.toarray(), sp.csr_matrix((data, a.indices, a.indptr), shape=a.shape).T.toarray())
