"""Cable bending (jaxnet.terms.cable_bending): FEMNET's law, its derivatives, the builder's joints, and FEMNET's
6flexion/c1 (a ring of four stiff cables) against its stored equilibrium."""

import math
import pathlib

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jaxnet.closed_form.cable_bending import joint_stiffness
from jaxnet.io import femnet
from jaxnet.net import Net, Rope
from jaxnet.scene import Environment, SceneError
from jaxnet.solve.options import Newton
from jaxnet.solve.statics import solve
from jaxnet.terms.cable_bending import joint_energy, joint_moment

# FEMNET's 6flexion/c1 (.don and .sta), copied with FEMNET's licence (tests/data/femnet-corpus/LICENSE)
C1 = pathlib.Path(__file__).resolve().parents[1] / "data" / "femnet-corpus" / "6flexion" / "c1.don"


def _joint(alpha, a=0.7, b=1.3, tilt=0.3):
    """Nodes of a joint with bars of lengths a, b turning by alpha, in a plane tilted out of xy."""
    d1 = np.array([1.0, 0.0, 0.0])
    d2 = np.array([math.cos(alpha), math.sin(alpha) * math.cos(tilt), math.sin(alpha) * math.sin(tilt)])
    x1 = np.array([0.2, -0.1, 0.4])
    return jnp.asarray(np.stack([x1 - a * d1, x1, x1 + b * d2]))


def _circumradius(x):
    """Radius (m) of the circle through three points."""
    x = np.asarray(x)
    p, q, r = (np.linalg.norm(x[i] - x[j]) for i, j in ((0, 1), (1, 2), (0, 2)))
    area = 0.5 * np.linalg.norm(np.cross(x[1] - x[0], x[2] - x[0]))
    return p * q * r / (4.0 * area)


def _femnet_forces(x, ei, beta):
    """FEMNET's nodal forces on a joint (pliage_barre_pardiso2_3.c for beta = 0, pliage_barre_pardiso4.c
    otherwise), transcribed from the law stated in jaxnet.terms.cable_bending's docstring: forces M/a, M/b
    across the bars, M = 2 EI sin(alpha - beta) / c with c on the current bar lengths."""
    x = np.asarray(x)
    u, v = x[1] - x[0], x[2] - x[1]
    a, b = np.linalg.norm(u), np.linalg.norm(v)
    ps = u @ v
    alpha = math.acos(ps / (a * b))
    c = math.sqrt(a * a + b * b + 2 * a * b * math.cos(alpha - beta))
    scale = 2 * ei / c * math.sin(alpha - beta) / math.sin(alpha)
    f1 = scale * (u * ps / (a**3 * b) - v / (a * b))
    f3 = scale * (-v * ps / (a * b**3) + u / (a * b))
    return np.stack([f1, -f1 - f3, f3])


# -- the law ------------------------------------------------------------------------------------------------


def test_energy_and_moment_of_a_bent_joint():
    # E = 2 EI (a + b - c) / (a b) exactly; for a small turn it is the discrete beam's EI phi² / (a + b)
    ei, a, b = 3.0, 0.7, 1.3
    for alpha in (0.01, 0.4, 1.7):
        x = _joint(alpha, a, b)
        c = math.sqrt(a * a + b * b + 2 * a * b * math.cos(alpha))
        assert float(joint_energy(x, jnp.array([a, b]), ei, 0.0)) == pytest.approx(2 * ei * (a + b - c) / (a * b), rel=1e-12)
        # FEMNET's couple: EI / R, R the radius of the circle through the three nodes (bars at rest length)
        assert float(joint_moment(x, jnp.array([a, b]), ei, 0.0)) == pytest.approx(ei / _circumradius(x), rel=1e-10)
    small = 1e-3
    e = float(joint_energy(_joint(small, a, b), jnp.array([a, b]), ei, 0.0))
    assert e == pytest.approx(ei * small**2 / (a + b), rel=1e-6)
    # a neutral angle: no energy at the neutral turn, and the energy of the turn measured from it
    x = _joint(0.9, a, b)
    assert abs(float(joint_energy(x, jnp.array([a, b]), ei, 0.9))) < 1e-14
    c = math.sqrt(a * a + b * b + 2 * a * b * math.cos(0.9 - 0.5))
    assert float(joint_energy(x, jnp.array([a, b]), ei, 0.5)) == pytest.approx(2 * ei * (a + b - c) / (a * b), rel=1e-12)


@pytest.mark.parametrize("beta", [0.0, 0.35, 1.2])
def test_forces_are_femnets_at_rest_length(beta):
    # with the bars at their rest length, -grad E is FEMNET's force law (any plane, any turn, any neutral angle)
    rng = np.random.default_rng(1)
    ei = 7.0
    for _ in range(4):
        x = rng.normal(size=(3, 3))
        rest = jnp.array([np.linalg.norm(x[1] - x[0]), np.linalg.norm(x[2] - x[1])])
        forces = -jax.grad(joint_energy)(jnp.asarray(x), rest, ei, beta)
        expected = _femnet_forces(x, ei, beta)
        np.testing.assert_allclose(np.asarray(forces), expected, rtol=1e-10, atol=1e-12 * np.abs(expected).max())
        # normal to the bars, self-equilibrated in force and in moment
        f = np.asarray(forces)
        assert abs(f[0] @ (x[1] - x[0])) < 1e-12 * np.abs(f).max() and abs(f[2] @ (x[2] - x[1])) < 1e-12 * np.abs(f).max()
        assert np.abs(f.sum(axis=0)).max() < 1e-12 * np.abs(f).max()
        assert np.abs(np.cross(x, f).sum(axis=0)).max() < 1e-11 * np.abs(f).max()


# -- derivatives ----------------------------------------------------------------------------------------------


@pytest.mark.parametrize("beta", [0.0, 0.8])
def test_gradient_and_closed_form_stiffness_against_finite_differences(beta):
    rng = np.random.default_rng(2)
    x = rng.normal(size=(3, 3))
    rest, ei, h = jnp.array([0.9, 1.1]), 2.0, 1e-6
    energy = lambda y: joint_energy(jnp.asarray(y).reshape(3, 3), rest, ei, beta)  # noqa: E731
    grad = jax.grad(energy)
    g = np.asarray(grad(x.ravel()))
    fd = np.array([(energy(x.ravel() + h * e) - energy(x.ravel() - h * e)) / (2 * h) for e in np.eye(9)])
    np.testing.assert_allclose(g, fd, rtol=1e-7, atol=1e-9 * np.abs(g).max())
    k = np.asarray(joint_stiffness(jnp.asarray(x), rest, ei, beta))
    fd_k = np.array([(np.asarray(grad(x.ravel() + h * e)) - np.asarray(grad(x.ravel() - h * e))) / (2 * h) for e in np.eye(9)])
    np.testing.assert_allclose(k, fd_k, rtol=1e-6, atol=1e-7 * np.abs(k).max())


@pytest.mark.parametrize("beta", [0.0, 0.3, 2.5])
def test_closed_form_is_the_autodiff_hessian(beta):
    rng = np.random.default_rng(3)
    for _ in range(5):
        x = jnp.asarray(rng.normal(size=(3, 3)))
        rest, ei = jnp.asarray(rng.uniform(0.5, 2.0, size=2)), 4.0
        h = jax.jacfwd(jax.grad(lambda y: joint_energy(y.reshape(3, 3), rest, ei, beta)))(x.ravel())
        k = joint_stiffness(x, rest, ei, beta)
        assert float(jnp.abs(k - h).max()) < 1e-12 * float(jnp.abs(h).max())
        assert float(jnp.abs(k - k.T).max()) < 1e-12 * float(jnp.abs(k).max())


@pytest.mark.parametrize("beta", [0.0, 0.6])
def test_a_straight_cable_has_finite_derivatives(beta):
    # exactly straight: no NaN anywhere; for beta = 0 no force, and the transverse stiffness of the middle node
    # is the discrete beam's 4 EI / l³ (E = EI (2 w / l)² / (2 l) for a deflection w of the middle node)
    ei, l = 5.0, 0.25
    x = jnp.array([[0.0, 0.0, 0.0], [l, 0.0, 0.0], [2 * l, 0.0, 0.0]])
    rest = jnp.array([l, l])
    energy = lambda y: joint_energy(y.reshape(3, 3), rest, ei, beta)  # noqa: E731
    g = jax.grad(energy)(x.ravel())
    h = jax.jacfwd(jax.grad(energy))(x.ravel())
    k = joint_stiffness(x, rest, ei, beta)
    assert bool(jnp.all(jnp.isfinite(g))) and bool(jnp.all(jnp.isfinite(h))) and bool(jnp.all(jnp.isfinite(k)))
    assert float(jnp.abs(k - h).max()) <= 1e-12 * float(jnp.abs(h).max())
    if beta == 0.0:
        assert float(jnp.abs(g).max()) == 0.0
        assert float(h[4, 4]) == pytest.approx(4 * ei / l**3, rel=1e-12)
        assert float(h[3, 3]) == 0.0   # nothing along the cable
    else:
        # straight but neutral at 0.6 rad: the energy of the whole neutral turn
        c = math.sqrt(2 * l * l + 2 * l * l * math.cos(beta))
        assert float(energy(x.ravel())) == pytest.approx(2 * ei * (2 * l - c) / (l * l), rel=1e-12)


# -- the builder ----------------------------------------------------------------------------------------------


def _cantilever(n_bars, length=1.0, ei=50.0, load=0.1):
    """A straight stiff cable along x, clamped by holding its first bar, a small tip load along y (N)."""
    net = Net(Environment(gravity=0.0))   # weightless: the tip load alone
    rope = Rope(ea=1e4, ea_compression=1e4, diameter=0.01, density=0.0, bending_stiffness=ei)
    net.cable("beam", start=(0.0, 0.0, 0.0), end=(length, 0.0, 0.0), rope=rope, n_bars=n_bars)
    net.fix((0.0, 0.0, 0.0))
    net.fix((length / n_bars, 0.0, 0.0))
    net.fix((length, 0.0, 0.0), axes="z")
    net.attach((length, 0.0, 0.0), force=(0.0, load, 0.0))
    return net.build()


def test_cantilever_deflection_tends_to_the_beam_formula():
    # the first bar is held: a cantilever of N = n - 1 bars of length l, L = N l. Its joints carry
    # EI phi² / (2 l) each (equal bars), so joint k from the clamp turns by P (N - k + 1) l² / EI and the tip
    # deflects P l³ sum_{m=1..N} m² / EI = P l³ N (N+1) (2N+1) / (6 EI): the beam's P L³ / (3 EI) times
    # (1 + 1/N) (1 + 1/(2N)), exact for the discrete beam up to the geometric nonlinearity of the small load
    # (tip slope 2e-3: relative O(1e-6)); the bars (EA = 1e4 N) stretch by 1e-8. tol 1e-6 N: the tip, of
    # stiffness 3 EI / L³ = 150 N/m, is then within 1e-8 m (the energy line search resolves no finer here).
    ei, load, length = 50.0, 0.1, 1.0
    ratios = []
    for n_bars in (6, 21):
        scene = _cantilever(n_bars, length, ei, load)
        assert len(scene.cable_joints.vertices) == n_bars - 1
        eq = solve(scene, Newton(tol=1e-6))
        start = np.asarray(scene.nodes.position)
        tip = np.asarray(eq.x)[np.argmin(np.linalg.norm(start - [length, 0.0, 0.0], axis=1))]
        l, big_n = length / n_bars, n_bars - 1
        discrete = load * l**3 * big_n * (big_n + 1) * (2 * big_n + 1) / (6 * ei)
        assert tip[1] == pytest.approx(discrete, rel=1e-4)
        beam = load * (big_n * l) ** 3 / (3 * ei)
        ratios.append(tip[1] / beam)
    assert ratios[0] == pytest.approx((1 + 1 / 5) * (1 + 1 / 10), rel=1e-4)
    assert 1.0 < ratios[1] < 1.08 and ratios[1] < ratios[0]


def test_two_welded_cables_straighten_to_their_neutral_angle():
    # cable a held by its first bar along x; cable b starts at a's end, drawn at 120° to it. Welded at 180°
    # (aligned) and with nothing else acting (weightless), b swings into line with a: its end at (2, 0, 0).
    rope = Rope(ea=1e6, ea_compression=1e6, diameter=0.01, density=0.0, bending_stiffness=10.0)
    net = Net(Environment(gravity=0.0))
    a = net.cable("a", start=(0.0, 0.0, 0.0), end=(1.0, 0.0, 0.0), rope=rope, n_bars=2)
    end_b = (1.0 + math.cos(math.pi / 3), math.sin(math.pi / 3), 0.0)
    b = net.cable("b", start=(1.0, 0.0, 0.0), end=end_b, rope=rope, n_bars=2)
    net.cable_joint(a, b, neutral_angle=math.pi)
    net.fix((0.0, 0.0, 0.0))
    net.fix((0.5, 0.0, 0.0))
    net.fix(end_b, axes="z")
    scene = net.build()
    joints = scene.cable_joints
    assert len(joints.vertices) == 3   # one inside each cable, one between them
    between = np.flatnonzero(joints.cable[:, 0] != joints.cable[:, 1])
    assert joints.rest_angle[between].tolist() == [0.0]
    eq = solve(scene, Newton(tol=1e-8))
    x = np.asarray(eq.x)
    far = np.argmin(np.linalg.norm(np.asarray(scene.nodes.position) - end_b, axis=1))
    np.testing.assert_allclose(x[far], [2.0, 0.0, 0.0], atol=1e-8)
    # welded at the drawn 120° instead: the drawn shape is the neutral one, the weld stores no energy there
    net = Net()
    a = net.cable("a", start=(0.0, 0.0, 0.0), end=(1.0, 0.0, 0.0), rope=rope, n_bars=2)
    b = net.cable("b", start=(1.0, 0.0, 0.0), end=end_b, rope=rope, n_bars=2)
    net.cable_joint(a, b, neutral_angle=2 * math.pi / 3)
    net.fix((0.0, 0.0, 0.0))
    joints = net.build().cable_joints
    weld = int(np.flatnonzero(joints.cable[:, 0] != joints.cable[:, 1])[0])
    assert joints.rest_angle[weld] == pytest.approx(math.pi / 3, rel=1e-15)
    x0 = np.asarray(scene.nodes.position)[np.asarray(joints.vertices)[weld]]
    assert abs(float(joint_energy(jnp.asarray(x0), jnp.asarray(joints.rest_length[weld]), 10.0,
                                  float(joints.rest_angle[weld])))) < 1e-12


def test_builder_refuses_bad_joints():
    rope = Rope(ea=1e6, diameter=0.01, bending_stiffness=1.0)
    net = Net()
    net.cable("a", start=(0.0, 0.0, 0.0), end=(1.0, 0.0, 0.0), rope=rope, n_bars=2)
    net.cable("b", start=(2.0, 0.0, 0.0), end=(3.0, 0.0, 0.0), rope=rope, n_bars=2)
    with pytest.raises(SceneError, match="no cable named 'c'"):
        net.cable_joint("a", "c")
    with pytest.raises(SceneError, match=r"neutral_angle must be in \[0, pi\]"):
        net.cable_joint("a", "b", neutral_angle=4.0)
    with pytest.raises(SceneError, match="bending_stiffness must be >= 0"):
        net.cable("c", start=(0.0, 1.0, 0.0), end=(1.0, 1.0, 0.0), rope=Rope(ea=1.0, diameter=0.01, bending_stiffness=-1.0))
    net.cable_joint("a", "b")
    net.fix((0.0, 0.0, 0.0))
    net.fix((2.0, 0.0, 0.0))
    with pytest.raises(SceneError, match="cable joint 'a'-'b': the cables share no node"):
        net.build()


# -- FEMNET's reader and its case 6flexion/c1 -----------------------------------------------------------------


def test_c1_reads_its_stiff_cables_and_welds():
    scene = femnet.read_don(C1).scene
    joints = scene.cable_joints
    # 4 cables of 11 bars: 10 joints inside each, and the 4 welds where they meet (180°: aligned at rest)
    assert len(joints.vertices) == 44
    assert np.all(np.asarray(joints.stiffness) == 300000.0) and np.all(np.asarray(joints.rest_angle) == 0.0)
    welds = np.flatnonzero(joints.cable[:, 0] != joints.cable[:, 1])
    assert sorted(map(tuple, np.sort(joints.cable[welds], axis=1).tolist())) == [(0, 1), (0, 3), (1, 2), (2, 3)]
    np.testing.assert_allclose(np.asarray(joints.rest_length), 1.5708 / 11, rtol=1e-12)


def _edited(tmp_path, old, new):
    text = C1.read_text()
    assert old in text
    path = tmp_path / "c1.don"
    path.write_text(text.replace(old, new))
    line = text[: text.index(old)].count("\n") + 1
    return path, line


@pytest.mark.parametrize("old, new, message", [
    ("input EI_flexion_cable 4   300000", "input EI_flexion_cable 9   300000", "no cable 9 .the case has 4 cable"),
    ("input EI_flexion_cable 4   300000", "input EI_flexion_cable 4   -3", "EI must be >= 0"),
    ("input EI_flexion_cable 4   300000", "input EI_flexion_cable 2.5 300000", "whole number >= 1"),
    ("input link_flexion_elem2 4 1 180.0", "input link_flexion_elem2 4 1 190.0", r"must be in \[0, 180\] degrees"),
    ("input link_flexion_elem2 4 1 180.0", "input link_flexion_elem2 4 4 180.0", "cable 4 is linked to itself"),
    ("input link_flexion_elem2 4 1 180.0", "input link_flexion_elem2 4 7 180.0", "no cable 7"),
    ("input link_flexion_elem2 4 1 180.0", "input link_flexion_elem2 2 4 180.0", "the cables have no end in common"),
])
def test_c1_bad_bending_commands_name_their_line(tmp_path, old, new, message):
    path, line = _edited(tmp_path, old, new)
    with pytest.raises(SceneError, match=rf"c1.don:{line}: .*{message}"):
        femnet.read_don(path)


def test_c1_equilibrium_is_femnets_ring():
    # Four stiff cables (EI = 3e5 N·m², EA = 3e6 N, l0 = 1.5708 m in 11 bars each) drawn as a square of side
    # sqrt(2) m (compressed), welded aligned at its corners, which slide along the axes. The bending joints push
    # the corners out; by symmetry the equilibrium is the regular 44-gon. FEMNET's forces (and jaxnet's) are
    # normal to the bars, so a uniform dilation of the ring does no work against them: the bars end at their
    # rest length, the radius is l0 / (2 sin(pi/44)) whatever EI, and FEMNET's .sta prints all strains 0.
    case = femnet.read_don(C1)
    eq = solve(case.scene, case.solver)
    assert eq.converged
    x = np.asarray(eq.x)
    radius = (1.5708 / 11) / (2 * math.sin(math.pi / 44))
    r = np.hypot(x[:, 0], x[:, 1])
    np.testing.assert_allclose(r, radius, rtol=0, atol=1e-10)
    np.testing.assert_allclose(x[:, 2], 1.0, atol=1e-12)
    # FEMNET's stored equilibrium (44 nodes, printed with 9 decimals): every FEMNET node has a jaxnet node within
    # 2e-7 m, FEMNET's own convergence error (its mirror nodes 9 and 10 differ from each other's mirror image by
    # 1.2e-7 m). The radius FEMNET prints is 1.000852502 m.
    sta = femnet.read_sta(C1.with_suffix(".sta"), 44, 44, 0)
    femnet_pos, femnet_strain = sta[0], sta[1]
    nearest = np.linalg.norm(femnet_pos[:, None, :] - x[None, :, :], axis=-1).min(axis=1)
    assert nearest.max() < 2e-7
    assert np.abs(femnet_strain).max() == 0.0
    assert np.hypot(*femnet_pos[0, :2]) == pytest.approx(radius, abs=1e-9)
