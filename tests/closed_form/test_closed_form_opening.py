"""Closed-form stiffness of the mesh opening (4.211-4.219) and of knot contact (4.278-4.280) vs autodiff,
and the errata of those equations (printed forms transcribed as ``book_4_xxx``; /work/exp5/errata_opening.md).

Every comparison runs through two jitted, vmapped programs (one per module), always called with the
same batch size so that each compiles once: the autodiff Hessians (``jax.jacfwd(jax.jacrev(.))`` of the
energies of jaxnet.terms) and the closed forms (jaxnet.closed_form) of the same elements side by side.
"""

import ast
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jaxnet  # noqa: F401  (float64)
from elements import L0, random_triangles, relative_difference
from jaxnet import geometry
from jaxnet.closed_form import knot as closed_knot
from jaxnet.closed_form import opening as closed_opening
from jaxnet.terms import knot, opening

BATCH = 128
TOL = 1e-10
KNOT, EA = 0.01, 2.0e5  # m, N: α_min = arcsin(0.1) = 5.74°, FEMNET's α_c = atan(0.1) = 5.71°
ONE_MESH = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])  # d = 4; x = (0, 2U, 2V) gives U, V exactly


def batched(element_program):
    """A jitted program over BATCH elements (lax.map: compiles twice as fast as vmap here), called with every
    argument padded to BATCH rows (so one compilation serves all tests) and its result trimmed."""
    program = jax.jit(lambda *args: jax.lax.map(lambda one: element_program(*one), args))

    def call(*args):
        n = len(args[0])
        assert n <= BATCH
        padded = [np.concatenate([a, np.repeat(a[-1:], BATCH - n, axis=0)]) for a in map(np.asarray, args)]
        return jax.tree.map(lambda o: np.asarray(o)[:n], program(*padded))
    return call


def value_gradient_hessian(f, y):
    """f(y) (k,), its Jacobian (k, 9) and Hessians (k, 9, 9) by autodiff, traced once."""
    g = jax.jacrev(f)
    hessian, gradient = jax.jacfwd(lambda z: (g(z), g(z)), has_aux=True)(y)
    return f(y), gradient, hessian


def _opening_autodiff(x, uv, h, rest):
    def scalars(y):
        y = y.reshape(3, 3)
        return jnp.stack([opening.half_angle(y, uv)[0], opening.opening_energy(y, uv, h, rest)])

    value, gradient, hessian = value_gradient_hessian(scalars, x.ravel())
    return dict(alpha=value[0], energy=value[1], ad_dalpha=gradient[0], ad_force=-gradient[1], ad_ddalpha=hessian[0],
                ad_k=hessian[1])


def _opening_closed(x, uv, h, rest):
    alpha, d_alpha, dd_alpha, d, valid = closed_opening.half_angle_derivatives(x, uv)
    return dict(alpha_cf=alpha, dalpha=d_alpha, ddalpha=dd_alpha, d=d, valid=valid,
                k=closed_opening.opening_stiffness(x, uv, h, rest))


# two programs rather than one: XLA compiles them in less than half the time of their union
_opening_runs = batched(_opening_autodiff), batched(_opening_closed)


def run_opening(x, uv, h, rest):
    return {key: value for run in _opening_runs for key, value in run(x, uv, h, rest).items()}


# the option combinations of knot_contact_energy compared: (name, options); band and H are traced arguments
KNOT_OPTIONS = ("book, band α_min/10, both diagonals, H of 4.280", "book, band α_min/10, α -> 0 only, H of 4.280",
                "book, band b, both diagonals, H of 4.280", "book, band b, α -> 0 only, H given",
                "femnet, both diagonals, H of FEMNET", "femnet, α -> 0 only, H given")


def knot_options(band, h):
    return [dict(), dict(both_diagonals=False), dict(band=band), dict(band=band, both_diagonals=False, stiffness=h),
            dict(form="femnet"), dict(form="femnet", both_diagonals=False, stiffness=h)]


def _knot_autodiff(x, uv, l0, knot_size, band, h):
    options = knot_options(band, h)

    def energies(y):
        return jnp.stack([knot.knot_contact_energy(y.reshape(3, 3), uv, l0, knot_size, ea=EA, **o) for o in options])

    _, gradient, hessian = value_gradient_hessian(energies, x.ravel())
    return dict(ad_k=hessian, ad_force=-gradient)


def _knot_closed(x, uv, l0, knot_size, band, h):
    k = jnp.stack([closed_knot.knot_contact_stiffness(x, uv, l0, knot_size, ea=EA, **o) for o in knot_options(band, h)])
    alpha = opening.half_angle(x, uv)[0]
    alpha_min, alpha_c = knot.contact_half_angle(l0, knot_size), knot.femnet_contact_half_angle(l0, knot_size)
    # closing beyond contact, computed as the energy computes it (the branch tests are on these)
    closing = jnp.stack([alpha_min - alpha, alpha - (0.5 * jnp.pi - alpha_min),
                         alpha_c - alpha, alpha - (0.5 * jnp.pi - alpha_c)])
    return dict(k=k, alpha=alpha, closing=closing)


_knot_runs = batched(_knot_autodiff), batched(_knot_closed)


def run_knot(x, uv, l0=L0, knot_size=KNOT, band=0.0, h=1.0):
    n = len(x)
    args = (x, uv) + tuple(np.broadcast_to(v, (n,)).astype(float) for v in (l0, knot_size, band, h))
    return {key: value for run in _knot_runs for key, value in run(*args).items()}


def assert_matches(k, reference, tol=TOL):
    """Per element: max |k - ref| <= tol max |ref|; elements where ref is exactly 0 must give exactly 0.
    Returns the number of elements with a non-zero reference."""
    k, reference = np.asarray(k), np.asarray(reference)
    assert np.isfinite(k).all() and np.isfinite(reference).all()
    nonzero = 0
    for a, b in zip(k.reshape(len(k), -1), reference.reshape(len(k), -1)):
        if np.abs(b).max() == 0.0:
            assert np.abs(a).max() == 0.0
        else:
            nonzero += 1
            assert relative_difference(a, b) <= tol, relative_difference(a, b)
    return nonzero


def triangles_at(alpha, n, seed):
    """n random well-shaped triangles (half clockwise) at the half opening angle alpha (rad)."""
    return random_triangles(n, seed, half_angle_deg=(np.degrees(alpha),) * 2)


def knot_zone_triangles(n_per_zone=24, seed=70):
    """Triangles at half angles spread over every contact zone: deep contact and band on both closures,
    and the free range between (out of contact for every form)."""
    zones = [(0.5, 5.0), (5.2, 5.7), (6.0, 84.0), (84.3, 84.8), (85.0, 89.5)]  # degrees
    parts = [random_triangles(n_per_zone, seed + i, half_angle_deg=z) for i, z in enumerate(zones)]
    return np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts])


# ---------------------------------------------------------------------------------------------- opening


def test_closed_form_uses_no_automatic_differentiation():
    # an independent derivation: only jax.numpy and jaxnet are imported, and no JAX transformation is named
    for module in (closed_opening, closed_knot):
        tree = ast.parse(pathlib.Path(module.__file__).read_text())
        modules = {a.name for n in ast.walk(tree) if isinstance(n, ast.Import) for a in n.names}
        modules |= {n.module for n in ast.walk(tree) if isinstance(n, ast.ImportFrom)}
        assert all(m in ("__future__", "jax.numpy") or m.split(".")[0] == "jaxnet" for m in modules), modules
        attributes = {n.attr for n in ast.walk(tree) if isinstance(n, ast.Attribute)}
        assert not attributes & {"grad", "jacfwd", "jacrev", "hessian", "jvp", "vjp", "linearize", "value_and_grad"}


def test_opening_matches_autodiff_on_random_elements():
    x, uv = random_triangles(120, seed=211)
    rng = np.random.default_rng(212)
    h, rest = rng.uniform(0.1, 2.0, 120), rng.uniform(0.05, 1.5, 120)
    out = run_opening(x, uv, h, rest)
    assert (out["d"] < 0).sum() == 60 and out["valid"].all()
    np.testing.assert_allclose(out["alpha_cf"], out["alpha"], rtol=0, atol=0)  # the same value function
    assert assert_matches(out["dalpha"], out["ad_dalpha"]) == 120
    assert assert_matches(out["ddalpha"], out["ad_ddalpha"]) == 120
    assert assert_matches(out["k"], out["ad_k"]) == 120
    # the closed form is the Hessian of E: symmetric, and rigid motions are free (K t = 0 for a translation)
    np.testing.assert_allclose(out["k"], np.swapaxes(out["k"], 1, 2), atol=1e-12 * np.abs(out["k"]).max())
    translation = np.tile(np.eye(3), (3, 1))
    assert np.abs(out["k"] @ translation).max() < 1e-12 * np.abs(out["k"]).max()


def test_gradient_of_the_half_angle_is_the_corrected_4218_in_twine_space():
    # ∂α/∂U ⟂ U of length 1/(2|U|) (turning U by ε closes the mesh by ε/2), pointing away from V
    x, uv = random_triangles(3, seed=5)
    for xi, uvi in zip(x, uv):
        U, V, _ = geometry.twine_vectors(xi, uvi)
        alpha, g_u, g_v, *_ = closed_opening.twine_angle_derivatives(U, V)
        np.testing.assert_allclose(np.dot(g_u, U), 0.0, atol=1e-14)
        np.testing.assert_allclose(np.linalg.norm(g_u), 1 / (2 * np.linalg.norm(U)), rtol=1e-13)
        np.testing.assert_allclose(np.linalg.norm(g_v), 1 / (2 * np.linalg.norm(V)), rtol=1e-13)
        assert np.dot(g_u, V) < 0 and np.dot(g_v, U) < 0


@pytest.mark.parametrize("alpha", [1e-3, np.pi / 2 - 1e-3, np.pi / 4, np.pi / 4 + 1e-9, np.pi / 4 - 1e-9])
def test_opening_nearly_closed_and_nearly_square(alpha):
    x, uv = triangles_at(alpha, 16, seed=7)
    out = run_opening(x, uv, np.full(16, 0.8), np.full(16, 0.55))
    np.testing.assert_allclose(out["alpha"], alpha, rtol=1e-9)
    assert (out["d"] < 0).sum() == 8
    assert assert_matches(out["k"], out["ad_k"]) == 16
    assert assert_matches(out["ddalpha"], out["ad_ddalpha"]) == 16


@pytest.mark.parametrize("alpha", [1e-5, 1e-7, np.pi / 2 - 1e-7])
def test_opening_very_nearly_closed_agrees_to_its_conditioning(alpha):
    # both paths compute n = U ^ V with a relative error ~ ε / sin 2α (cancellation in the cross product of
    # nearly parallel vectors), and K's largest entries are ∝ 1/|n|: they agree to ~1e-16 / min(α, π/2 - α)
    x, uv = triangles_at(alpha, 16, seed=8)
    out = run_opening(x, uv, np.full(16, 0.8), np.full(16, 0.55))
    gap = min(alpha, np.pi / 2 - alpha)
    assert np.abs(out["k"]).max() > 10.0 / gap  # N/m; the cone: K ∝ 1/sin 2α
    assert assert_matches(out["k"], out["ad_k"], tol=1e-14 / gap) == 16


def exactly_closed(direction, factor):
    """ONE_MESH positions with V = factor U exactly (U along ``direction``, 5 cm)."""
    U = L0 * np.asarray(direction, float)
    return np.stack([np.zeros(3), 2 * U, 2 * factor * U]), ONE_MESH


def test_opening_at_the_exactly_closed_mesh_is_zero_as_autodiff():
    # U ^ V = 0 exactly: autodiff takes d|U ^ V| = 0 (safe_norm), so ∂α = ∂²α = 0 and K = 0; the closed form
    # returns the same zeros (the one-sided limits, ∝ 1/|U ^ V|, are unbounded: a kink, no derivative)
    cases = [exactly_closed(e, f) for e in np.eye(3) for f in (1.0, 2.0, -1.0, -0.5)]
    x, uv = np.array([c[0] for c in cases]), np.array([c[1] for c in cases])
    out = run_opening(x, uv, np.full(len(x), 0.8), np.full(len(x), 0.55))
    np.testing.assert_array_equal(out["alpha_cf"], np.repeat([[0.0, 0.0, np.pi / 2, np.pi / 2]], 3, 0).ravel())
    for key in ("dalpha", "ddalpha", "k", "ad_k", "ad_force"):
        assert np.abs(out[key]).max() == 0.0
    np.testing.assert_allclose(out["energy"], 2 * 0.8 * (out["alpha"] - 0.55) ** 2, rtol=1e-14)
    # closed to rounding only (a generic direction: the cross product keeps ~1e-20 m²): both paths follow the
    # cone, K ~ 1e18 N/m, and still agree
    x, uv = exactly_closed([0.6, 0.8, 0.0], 1.0)
    out = run_opening(x[None], uv[None], [0.8], [0.55])
    assert np.abs(out["k"]).max() > 1e15
    assert assert_matches(out["k"], out["ad_k"]) == 1


def test_opening_of_a_collapsed_twine_is_zero_and_finite():
    V = L0 * np.array([0.0, 1.0, 0.0])
    cases = [np.stack([np.zeros(3), np.zeros(3), 2 * V]),  # U = 0
             np.stack([np.zeros(3), 2 * V, np.zeros(3)]),  # V = 0
             np.zeros((3, 3))]
    out = run_opening(np.array(cases), np.repeat(ONE_MESH[None], 3, 0), np.full(3, 0.8), np.full(3, 0.55))
    assert not out["valid"].any()
    for key in ("alpha_cf", "dalpha", "ddalpha", "k", "ad_k", "energy"):
        assert np.isfinite(out[key]).all() and np.abs(out[key]).max() == 0.0


# ------------------------------------------------------------------------------------------ knot contact


def test_knot_contact_matches_autodiff_for_every_option_on_random_elements():
    x, uv = knot_zone_triangles()
    for band in (0.0, 0.004):  # the plain one-sided penalty of 4.279, and a band of 0.23°
        out = run_knot(x, uv, band=band, h=3.0)
        for j, name in enumerate(KNOT_OPTIONS):
            in_contact = assert_matches(out["k"][:, j], out["ad_k"][:, j])
            assert in_contact == (96 if "both" in name else 48), name  # 2 or 4 of the 5 zones
    # the options differ: a check that would pass with any of them swapped would be weak
    assert relative_difference(out["k"][:24, 0], out["k"][:24, 2]) > 1e-3
    assert relative_difference(out["k"][:24, 0], out["k"][:24, 4]) > 1e-3


def test_knot_contact_refuses_what_the_energy_refuses():
    x, uv = random_triangles(1, seed=3)
    for options in (dict(), dict(ea=EA, form="femnet", band=0.0), dict(ea=EA, form="neither")):
        with pytest.raises(ValueError):
            closed_knot.knot_contact_stiffness(x[0], uv[0], L0, KNOT, **options)
        with pytest.raises(ValueError):
            knot.knot_contact_energy(x[0], uv[0], L0, KNOT, **options)


@pytest.mark.parametrize("alpha", [1e-3, np.pi / 2 - 1e-3])
def test_knot_contact_nearly_closed(alpha):
    x, uv = triangles_at(alpha, 16, seed=9)
    out = run_knot(x, uv)
    for j, name in enumerate(KNOT_OPTIONS):
        expected = 16 if (alpha < 1 or "both" in name) else 0
        assert assert_matches(out["k"][:, j], out["ad_k"][:, j]) == expected, name


def test_knot_contact_at_the_exactly_closed_mesh_and_collapsed_twine():
    cases = [exactly_closed(e, f) for e in np.eye(3) for f in (1.0, -1.0)]
    cases.append((np.stack([np.zeros(3), np.zeros(3), [0, 0.1, 0]]), ONE_MESH))  # U = 0
    x, uv = np.array([c[0] for c in cases]), np.array([c[1] for c in cases])
    out = run_knot(x, uv)
    # deep in contact, but ∂α = ∂²α = 0 there (autodiff's safe_norm, the closed form's choice): K = 0
    assert np.abs(out["k"]).max() == 0.0 and np.abs(out["ad_k"]).max() == 0.0


def onset_search(alpha, side, form):
    """(l0, knot size) candidates around those putting contact at exactly alpha, on the α -> 0 side
    (side 0) or the α -> π/2 side (side 1): contact half angle = alpha resp. π/2 - alpha."""
    target = alpha if side == 0 else np.pi / 2 - alpha
    ratio = np.sin(target) if form == "book" else np.tan(target)
    # near π/2 one ulp of the contact angle is ~20 ulps of α_min = π/2 - target: coarser steps of k
    step = 1.1e-16 if side == 0 else 2e-15
    l0 = L0 * (1 + 2.2e-16 * np.repeat(np.arange(8), 16))
    size = 2 * l0 * ratio * (1 + step * np.tile(np.arange(-8, 8), 8))
    return l0, size


@pytest.mark.parametrize("side", [0, 1])
@pytest.mark.parametrize("form", ["book", "femnet"])
def test_knot_contact_exactly_at_onset(form, side):
    # contact sizes chosen so that the closing beyond contact is exactly 0 for one element: the energy is then
    # on its "no contact" branch (s <= 0; α < α_c false), and so is the closed form: K = 0. One step further
    # the plain penalty (band 0) and FEMNET's jump to their full stiffness, and both paths jump together.
    alpha = np.radians(4.0 if side == 0 else 86.0)
    x, uv = triangles_at(alpha, 1, seed=11 + side)
    l0, size = onset_search(alpha, side, form)
    out = run_knot(np.repeat(x, len(l0), 0), np.repeat(uv, len(l0), 0), l0, size, band=0.0)
    closing = out["closing"][:, side + (2 if form == "femnet" else 0)]
    at_onset, inside = closing == 0.0, closing > 0.0
    assert at_onset.any() and inside.any()
    columns = [2, 3, 0, 1] if form == "book" else [4, 5]  # band 0 first: its stiffness jumps at onset
    columns = [c for c in columns if side == 0 or c in (0, 2, 4)]  # one-diagonal options see no π/2 closure
    for j in columns:
        assert np.abs(out["k"][at_onset, j]).max() == 0.0 and np.abs(out["ad_k"][at_onset, j]).max() == 0.0
        assert assert_matches(out["k"][inside, j], out["ad_k"][inside, j]) == inside.sum()
    jump = out["k"][inside, columns[0]]
    assert np.abs(jump).max() > 1e3  # N/m: the full stiffness |d| H φ''(α_0) ∂α ⊗ ∂α right after onset


@pytest.mark.parametrize("side", [0, 1])
def test_knot_contact_exactly_at_the_band_edge(side):
    # band b = the closing s itself: s < b is false, the energy takes its s >= b branch; g', g'' are continuous
    # there (g'(b) = b, g''(b) = 2 on both branches), and the closed form takes the same branch
    alpha = np.radians(5.0 if side == 0 else 85.0)
    x, uv = triangles_at(alpha, 8, seed=13 + side)
    s = run_knot(x, uv)["closing"][:, side]
    assert (s > 0).all()
    out = run_knot(x, uv, band=s)
    for j in ([2, 3] if side == 0 else [2]):
        assert assert_matches(out["k"][:, j], out["ad_k"][:, j]) == 8
    # and just inside the band (b a little larger than s) the ramp branch agrees with the edge
    inner = run_knot(x, uv, band=s * (1 + 1e-9))
    assert relative_difference(inner["k"][:, 2], out["k"][:, 2]) < 1e-6


# ------------------------------------------------------------------------------------------------ errata
# Transcriptions of the printed equations. u_i, v_i are the twine-coordinate factors of 4.43-4.45
# (v_1 = V3 - V2, u_1 = U2 - U3, cyclic), d is that of 4.7 unless said otherwise.


def factors(uv):
    (U1, V1), (U2, V2), (U3, V3) = np.asarray(uv)
    return np.array([U2 - U3, U3 - U1, U1 - U2]), np.array([V3 - V2, V1 - V3, V2 - V1])


def book_4_211(U, V):
    return 0.5 * np.arccos(np.dot(U, V) / (np.linalg.norm(U) * np.linalg.norm(V)))


def book_4_212(h, alpha, rest):
    """(C_u, C_v)."""
    return h * (alpha - rest), -h * (alpha - rest)


def book_4_214(d, c_u, c_v, d_alpha):
    return d / 2 * (c_u * d_alpha + c_v * d_alpha)


def book_4_215(uv):
    (U1, V1), (U2, V2), (U3, V3) = np.asarray(uv)
    return (U2 - U1) * (V1 - V3) - (U3 - U1) * (V1 - V2)


def book_4_217(h, alpha, rest, d, d_alpha):
    """F_wi = H (α - α0) d ∂α/∂w_i (4.216 is its x_1 component, with C_u = H (α - α0))."""
    return h * (alpha - rest) * d * d_alpha


def book_4_218(x, uv, sine=np.sin, printed_signs=True, u_convention=1.0):
    """(3, 3) ∂α/∂w_i of 4.218. As printed: ``sine=np.sin`` of α, ``printed_signs`` ('- U_w u_i' and
    '- V_w (U.V) u_i / |V|²'); ``u_convention=-1`` reads u_i with the opposite sign (u_1 = U3 - U2)."""
    U, V, d = geometry.twine_vectors(np.asarray(x), np.asarray(uv))
    U, V = np.asarray(U), np.asarray(V)
    alpha = book_4_211(U, V)
    u, v = factors(uv)
    u, v = u_convention * u[:, None], v[:, None]
    c, p, q = np.dot(U, V), np.dot(U, U), np.dot(V, V)
    numerator = V * v + (-1.0 if printed_signs else 1.0) * U * u - U * c * v / p - V * c * u / q
    return numerator / (2 * float(d) * sine(alpha) * np.sqrt(p * q))


def book_4_278(knot_size, mesh_side):
    return 2 * np.arcsin(knot_size / (2 * mesh_side))


def book_4_279(h, alpha, alpha_min):
    return np.where(alpha <= alpha_min, h * (alpha - alpha_min), 0.0)


def book_4_280(mesh_side, ea, knot_size):
    return mesh_side**2 * ea / (100 * knot_size)


H, REST = 0.8, 0.55


@pytest.fixture(scope="module")
def element():
    """A random well-conditioned element of each orientation, with autodiff and closed-form values."""
    x, uv = random_triangles(2, seed=4219)
    return x, uv, run_opening(x, uv, np.full(2, H), np.full(2, REST))


def test_4211_is_the_half_angle_and_loses_its_digits_at_closure(element):
    x, uv, out = element
    for i in range(2):
        U, V, _ = geometry.twine_vectors(x[i], uv[i])
        np.testing.assert_allclose(book_4_211(np.asarray(U), np.asarray(V)), out["alpha"][i], rtol=1e-12)
    # singular point: at α = 1e-9 cos 2α rounds to 1 and the acos form returns 0 (the atan2 form is exact)
    U, V = np.array([1.0, 0, 0]), np.array([np.cos(2e-9), np.sin(2e-9), 0])
    assert book_4_211(U, V) == 0.0
    np.testing.assert_allclose(float(geometry.half_opening_angle(U, V)), 1e-9, rtol=1e-15)


def test_4212_4214_virtual_work_needs_the_v_twine_to_turn_the_other_way(element):
    x, uv, out = element
    rng = np.random.default_rng(0)
    for i in range(2):
        d = out["d"][i]
        c_u, c_v = book_4_212(H, out["alpha"][i], REST)
        assert c_v == -c_u
        move = rng.normal(size=9)
        d_alpha = out["dalpha"][i] @ move
        true_work = -out["ad_force"][i] @ move  # dE = -F.δx with F on the vertices
        assert abs(true_work) > 1e-6 * np.abs(out["ad_force"][i]).max()
        assert book_4_214(d, c_u, c_v, d_alpha) == 0.0  # printed: no work at all (error 100 %)
        np.testing.assert_allclose(abs(d) / 2 * (c_u - c_v) * d_alpha, true_work, rtol=1e-10)


def test_4215_is_minus_the_d_of_47(element):
    _, uv, out = element
    for i in range(2):
        np.testing.assert_allclose(book_4_215(uv[i]), -out["d"][i], rtol=1e-14)


def test_4216_4217_force_sign_and_orientation(element):
    # F on the vertices = -∇E = -H (α - α0) |d| ∂α/∂w_i. The printed +H (α - α0) d ∂α/∂w_i is its opposite with
    # the d of 4.7 for d > 0; with 4.215's d (= -d) it is right for d > 0 and opposite for d < 0
    _, uv, out = element
    assert out["d"][0] > 0 > out["d"][1]
    for i in range(2):
        d, alpha = out["d"][i], out["alpha"][i]
        true = out["ad_force"][i]
        np.testing.assert_allclose(-H * (alpha - REST) * abs(d) * out["dalpha"][i], true, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(book_4_217(H, alpha, REST, d, out["dalpha"][i]), -np.sign(d) * true, rtol=1e-10)
        np.testing.assert_allclose(book_4_217(H, alpha, REST, book_4_215(uv[i]), out["dalpha"][i]),
                                   np.sign(d) * true, rtol=1e-10)


def test_4218_printed_has_sin_alpha_and_a_wrong_sign(element):
    x, uv, out = element
    double = lambda a: np.sin(2 * a)  # noqa: E731
    for i in range(2):
        true = out["dalpha"][i].reshape(3, 3)
        scale = np.abs(true).max()
        np.testing.assert_allclose(book_4_218(x[i], uv[i], double, printed_signs=False), true, atol=1e-10 * scale)
        assert np.abs(book_4_218(x[i], uv[i]) - true).max() > 0.3 * scale  # the printed form: O(1) error
        # sin α for sin 2α alone: exactly 2 cos α times the derivative
        np.testing.assert_allclose(book_4_218(x[i], uv[i], np.sin, printed_signs=False),
                                   2 * np.cos(out["alpha"][i]) * true, atol=1e-10 * scale)
        # the signs alone, with either sign convention for u_i (the two u_i terms need opposite signs): with u_i
        # of 4.43 the U_w u_i term is wrong, an O(1) error; with -u_i the (U.V) u_i term is, an error ∝ cos 2α
        U, V, d = (np.asarray(t) for t in geometry.twine_vectors(x[i], uv[i]))
        u = factors(uv[i])[0][:, None]
        denominator = 2 * d * np.sin(2 * out["alpha"][i]) * np.linalg.norm(U) * np.linalg.norm(V)
        error_u = book_4_218(x[i], uv[i], double) - true
        np.testing.assert_allclose(error_u, -2 * U * u / denominator, atol=1e-10 * scale)
        assert np.abs(error_u).max() > 0.3 * scale
        error_minus_u = book_4_218(x[i], uv[i], double, u_convention=-1.0) - true
        np.testing.assert_allclose(error_minus_u, 2 * V * np.dot(U, V) * u / (np.dot(V, V) * denominator),
                                   atol=1e-10 * scale)
        assert np.abs(error_minus_u).max() > 1e-3 * scale


def test_4219_is_minus_the_jacobian_of_the_corrected_forces(element):
    # K = -∂F/∂x, by central differences of the autodiff forces, equals the closed form; the printed forces
    # (4.217 with 4.215's d and the printed 4.218, FEMNET's flexion2) have another, unsymmetric, Jacobian
    x, uv, out = element
    h = 1e-7
    steps = np.concatenate([np.eye(9), -np.eye(9)]) * h
    for i in range(2):
        moved = x[i].ravel() + steps
        shifted = run_opening(moved.reshape(-1, 3, 3), np.repeat(uv[i:i + 1], 18, 0), np.full(18, H), np.full(18, REST))
        fd = -(shifted["ad_force"][:9] - shifted["ad_force"][9:]).T / (2 * h)
        assert relative_difference(out["k"][i], fd) < 1e-6

        def printed_force(y):
            U, V, _ = geometry.twine_vectors(y.reshape(3, 3), uv[i])
            alpha = book_4_211(np.asarray(U), np.asarray(V))
            return book_4_217(H, alpha, REST, book_4_215(uv[i]), book_4_218(y.reshape(3, 3), uv[i])).ravel()

        pairs = zip(moved[:9], moved[9:])
        k_printed = -np.stack([(printed_force(y) - printed_force(z)) / (2 * h) for y, z in pairs], 1)
        assert relative_difference(k_printed, out["k"][i]) > 0.1
        assert relative_difference(k_printed, k_printed.T) > 1e-2


def test_4278_is_the_full_angle_where_knots_touch():
    # knots at the ends of U and V touch when |U - V| = 2 l0 sin α = k: α = arcsin(k / (2 l0)), half of 4.278
    alpha = float(knot.contact_half_angle(L0, KNOT))
    U = L0 * np.array([np.cos(alpha), np.sin(alpha), 0.0])
    V = L0 * np.array([np.cos(alpha), -np.sin(alpha), 0.0])
    np.testing.assert_allclose(np.linalg.norm(U - V), KNOT, rtol=1e-14)
    np.testing.assert_allclose(float(geometry.half_opening_angle(U, V)), alpha, rtol=1e-14)
    np.testing.assert_allclose(book_4_278(KNOT, L0), 2 * alpha, rtol=1e-15)  # error: factor 2


def test_4279_couple_per_knot_with_the_half_contact_angle():
    # with band 0 the energy's couple per knot, C = -F.∂α / (|d| |∂α|²) (F = -|d| C ∂α, as 4.217), is 4.279
    # with α_min the half angle; the printed 4.278 in 4.279 puts it at 2 α_min (couple H α_min too large)
    x, uv = random_triangles(4, seed=4279, half_angle_deg=(1.0, 5.0))
    out = run_knot(x, uv, band=0.0)
    opened = run_opening(x, uv, np.full(4, H), np.full(4, REST))
    h = float(knot.default_knot_stiffness(L0, KNOT, EA))
    alpha_min = float(knot.contact_half_angle(L0, KNOT))
    for i in range(4):
        g = opened["dalpha"][i]
        couple = -out["ad_force"][i, 2] @ g / (abs(opened["d"][i]) * g @ g)
        np.testing.assert_allclose(couple, book_4_279(h, out["alpha"][i], alpha_min), rtol=1e-10)
        printed = book_4_279(h, out["alpha"][i], book_4_278(KNOT, L0))
        np.testing.assert_allclose(printed - couple, -h * alpha_min, rtol=1e-10)
        # the default band moves the effective contact by b/2 deep in contact (a jaxnet choice, not the book's)
        couple_band = -out["ad_force"][i, 0] @ g / (abs(opened["d"][i]) * g @ g)
        np.testing.assert_allclose(couple_band, book_4_279(h, out["alpha"][i], alpha_min - 0.05 * alpha_min),
                                   rtol=1e-10)


def test_4280_default_stiffness():
    np.testing.assert_allclose(knot.default_knot_stiffness(L0, KNOT, EA), book_4_280(L0, EA, KNOT), rtol=1e-15)
    assert float(knot.default_knot_stiffness(L0, 0.0, EA)) == 0.0  # k = 0: no knots, not a division by 0
