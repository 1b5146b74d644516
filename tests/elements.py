"""Random well-conditioned netting elements, shared by the closed-form vs autodiff stiffness tests.

"Well conditioned": the twine coordinates span a triangle of |d| between 2 and 40 twines² with no
side shorter than a third of the longest, the twines are stretched by -5 % to +20 % of l0 = 0.05 m, and the
half opening angle is between 15° and 75° (away from the closed meshes where the opening and knot
terms have their singular points, which the tests probe separately). Half of the triangles are clockwise
(d < 0).
"""

import jax.numpy as jnp
import numpy as np

L0 = 0.05  # m


def random_twine_coordinates(rng, clockwise):
    """(3, 2) twine coordinates of a reasonably shaped triangle, with d < 0 if ``clockwise``."""
    while True:
        uv = rng.uniform(-6.0, 6.0, size=(3, 2))
        d = (uv[1, 0] - uv[0, 0]) * (uv[2, 1] - uv[0, 1]) - (uv[2, 0] - uv[0, 0]) * (uv[1, 1] - uv[0, 1])
        sides = np.linalg.norm(uv - uv[[1, 2, 0]], axis=1)
        if 2.0 < abs(d) < 40.0 and sides.min() > sides.max() / 3.0:
            return uv[[0, 2, 1]] if (d < 0) != clockwise else uv


def random_twine_pair(rng, l0=L0, stretch=(-0.05, 0.2), half_angle_deg=(15.0, 75.0)):
    """Twine vectors U, V (3,) m of lengths l0 (1 + stretch) at a half opening angle in the given range."""
    frame, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    alpha = np.radians(rng.uniform(*half_angle_deg))
    lu, lv = l0 * (1.0 + rng.uniform(*stretch, size=2))
    # the bisector along frame[0]: U and V at ±alpha from it, in the plane (frame[0], frame[1])
    U = lu * (np.cos(alpha) * frame[0] + np.sin(alpha) * frame[1])
    V = lv * (np.cos(alpha) * frame[0] - np.sin(alpha) * frame[1])
    return U, V


def positions(uv, U, V, origin):
    """(3, 3) vertex positions whose twine vectors are U, V (eqs 4.1-4.2): x_i = origin + ΔU_i U + ΔV_i V."""
    du, dv = uv[:, 0] - uv[0, 0], uv[:, 1] - uv[0, 1]
    return origin + du[:, None] * U[None, :] + dv[:, None] * V[None, :]


def random_triangles(n, seed=0, **pair):
    """n well-conditioned triangles: x (n, 3, 3) m and uv (n, 3, 2) twines, half of them clockwise.

    ``pair``: options of :func:`random_twine_pair` (l0, stretch, half_angle_deg).
    """
    rng = np.random.default_rng(seed)
    xs, uvs = [], []
    for k in range(n):
        uv = random_twine_coordinates(rng, clockwise=bool(k % 2))
        U, V = random_twine_pair(rng, **pair)
        xs.append(positions(uv, U, V, rng.normal(size=3)))
        uvs.append(uv)
    return np.array(xs), np.array(uvs)


def relative_difference(k, reference):
    """max |k - reference| / max |reference| (both arrays of any shape)."""
    return float(np.max(np.abs(np.asarray(k) - np.asarray(reference))) / np.max(np.abs(np.asarray(reference))))


def central_differences(f, a, h):
    """Jacobian of f at a by central differences of step h: (f(a).size, a.size); f is called on jnp arrays of
    a's shape."""
    a = np.asarray(a, float)
    cols = []
    for i in range(a.size):
        e = np.zeros(a.size)
        e[i] = h
        e = e.reshape(a.shape)
        cols.append((np.asarray(f(jnp.asarray(a + e))) - np.asarray(f(jnp.asarray(a - e)))).ravel() / (2 * h))
    return np.stack(cols, axis=-1)
