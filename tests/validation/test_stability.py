"""The stability suite (validation/stability.py) on a subset of its catalogue, at the test size.

Each run must converge to its tolerance (the largest nodal residual it reports is at most the tolerance,
and nothing non-finite appeared in positions, forces, residual history or energy), or stop with the named
reason its case expects; and the catalogue must cover every family the issue names, with at least 40 cases.
"""

import numpy as np
import pytest

from validation import stability

CASES = {case.name: case for case in stability.catalogue()}

#: (case, start): one or two of the cheapest cases of several families, from both starts where the start
#: matters (the perturbed start crumples the net: twines overstretched, triangles turned inside out)
SUBSET = [
    ("framed EA 1e+01 N", "flat"),
    ("framed EA 1e+10 N", "flat"),
    ("framed EA 1e+10 N", "perturbed"),
    ("loose frame, no load", "perturbed"),
    ("current 5 m/s normal", "flat"),
    ("cut nearly closed", "perturbed"),
    ("sliver fan", "perturbed"),
    ("knots: frame pushes meshes closed", "perturbed"),
    ("time step 1e-05 s", "flat"),
    ("time step 10 s", "perturbed"),
    ("FEMNET links_hub", "perturbed"),
    ("held nowhere", "flat"),
]


@pytest.mark.parametrize("name,start", SUBSET)
def test_case_converges_or_stops_with_its_named_reason(name, start):
    case = CASES[name]
    record = stability.run_case(case, start, "test")
    assert not record["nan"], record["reason"]
    if stability.CONVERGED in case.expect:
        assert record["converged"], (record["reason"], record["residual_N"])
        assert record["residual_N"] <= record["tol"]
        if record["history"]:  # statics: the residual history ends where the solve stopped
            assert record["history"][-1] == pytest.approx(record["residual_N"])
            assert record["iterations"] == len(record["history"]) - 1
        else:  # dynamics: three steps of the asked size (none retried at 1e-5 s)
            assert record["steps"] >= 3
    else:
        assert not record["converged"]
        assert any(record["reason"].startswith(e) for e in case.expect), record["reason"]
    assert record["expected"]


def test_the_perturbed_start_moves_every_free_coordinate_and_no_fixed_one():
    problem = CASES["framed EA 1e+01 N"].build("test")
    scene = problem.scene
    x, sigma = stability.perturbed_start(scene)
    x0 = np.asarray(scene.nodes.position)
    fixed = np.asarray(scene.nodes.fixed)
    assert sigma == pytest.approx(stability.PERTURBATION * stability.element_size(scene))
    assert np.all(x[fixed] == x0[fixed]) and np.all(x[~fixed] != x0[~fixed])
    # the displacements are the stated normal distribution: their RMS is sigma (a few tens of samples)
    assert np.sqrt(np.mean((x - x0)[~fixed] ** 2)) == pytest.approx(sigma, rel=0.25)
    again, _ = stability.perturbed_start(scene)
    assert np.array_equal(x, again)  # seeded


def test_the_catalogue_covers_every_family_with_at_least_40_cases():
    cases = stability.catalogue()
    assert len(cases) >= 40
    assert len({c.name for c in cases}) == len(cases)
    assert {c.family for c in cases} == set(stability.FAMILIES)
    # the ranges: EA from 1e1 to 1e10 N, currents from 0.01 to 5 m/s, time steps from 1e-5 to 10 s
    names = " ".join(c.name for c in cases)
    for needle in ("EA 1e+01", "EA 1e+10", "0.01 m/s", "5 m/s", "still water", "along a twine", "normal",
                   "time step 1e-05 s", "time step 10 s"):
        assert needle in names, needle
    # nets of 1e5 nodes in the full study, of 1e4 in the quick one (their meshes: building the full one takes
    # seconds, solving it minutes)
    large = next(c for c in cases if c.family == "size")
    assert not large.full_only and 9_000 <= large.build("quick").scene.n_nodes <= 12_000
    assert 95_000 <= large.build("full").scene.n_nodes <= 120_000


def test_sliver_triangles_have_an_aspect_ratio_of_1e3_in_twine_coordinates():
    for name in ("sliver strip", "sliver fan"):
        scene = CASES[name].build("test").scene
        uv = np.asarray(scene.netting.uv)
        sides = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 1], uv[:, 0] - uv[:, 2]], axis=1)
        longest = np.linalg.norm(sides, axis=2).max(axis=1)
        area2 = np.abs(sides[:, 0, 0] * sides[:, 2, 1] - sides[:, 0, 1] * sides[:, 2, 0])
        np.testing.assert_allclose(longest**2 / area2, 1000.0, rtol=0.01)


def test_codend_capacity_is_the_largest_tube_of_its_netting():
    # pi r² L with r = n 2 l0 sin(a) / 2 pi, L = m 2 l0 cos(a): maximal where tan² a = 2
    a = np.linspace(0.01, np.pi / 2 - 0.01, 20001)
    n, m, l0 = 100, 50, 0.06
    volume = np.pi * (n * 2 * l0 * np.sin(a) / (2 * np.pi)) ** 2 * m * 2 * l0 * np.cos(a)
    assert stability.codend_capacity(n, m, l0) == pytest.approx(volume.max(), rel=1e-6)


def test_a_continuation_out_of_iterations_is_not_thrown_away():
    # The curtain in a 1 m/s current along its twines, from the crumpled start, with the library's default
    # 500 iterations: the stiffness continuation starts, runs out of its half of the iterations a stage short
    # of the end, and plain Newton must go on from where it got to (it failed when it went back to the
    # crumpled start: 500 iterations, 24 N left).
    import jaxnet as jn

    scene = CASES["current 1 m/s along a twine"].build("test").scene
    x0, _ = stability.perturbed_start(scene)
    eq = jn.solve_static(scene, x0=x0, throw=False)
    assert eq.converged and float(eq.residual_N) <= 1e-3
    assert np.all(np.isfinite(np.asarray(eq.x)))


def test_a_stiff_net_in_large_time_steps_does_not_fail_every_other_step():
    # Twines of 1e10 N, a current switched on, steps of 10 s: Newton needs many iterations per step and the
    # step is halved until it passes. Doubling it after every success made every other attempt fail
    # (retries = steps); the step now grows only after an easy step.
    record = stability.run_case(CASES["time step 10 s, EA 1e10 N"], "flat", "test")
    assert record["converged"] and not record["nan"]
    assert 0 < record["retries"] < 0.5 * record["steps"]
