"""Closed-form stiffness of cable bending at a joint (:mod:`jaxnet.terms.cable_bending`), written by hand.

The energy of a joint is a function of one scalar, s = cos(α - β) = cos β C + sin β S with C = cos α and
S = sin α >= 0 of the angle between the bars u = x1 - x0 and v = x2 - x1:

    E = g(s) = 2 EI (a + b - c) / (a b),   c = sqrt(a² + b² + 2 a b s),
    g'(s) = -2 EI / c,                     g''(s) = 2 EI a b / c³.

Through C alone (S = sqrt(1 - C²), dS/dC = -C/S): E = h(C) with

    h'(C)  = g'(s) (cos β - sin β C / S),
    h''(C) = g''(s) (cos β - sin β C / S)² - g'(s) sin β / S³,

and K = h'(C) ∇²C + h''(C) ∇C ∇C^T. With û = u/|u|, v̂ = v/|v|, the derivatives of C on (u, v) are

    ∂C/∂u = (v̂ - C û)/|u|,     ∂C/∂v = (û - C v̂)/|v|,
    ∂²C/∂u² = (3 C ûû^T - ûv̂^T - v̂û^T - C I) / |u|²,    ∂²C/∂v² = the same with u and v exchanged,
    ∂²C/∂u∂v = (I - ûû^T - v̂v̂^T + C ûv̂^T) / (|u| |v|)   (rows along u, columns along v),

and the chain rule to the nodes is ∂/∂x0 = -∂/∂u, ∂/∂x1 = ∂/∂u - ∂/∂v, ∂/∂x2 = ∂/∂v (u, v linear in x).

Singular point. With β ≠ 0, S = 0 (the bars aligned or folded) is a cone point of E (its docstring); there
∇C = 0 and the terms in sin β / S are dropped, which is what the energy's guard (``safe_norm`` of u ^ v, whose
derivatives there are 0) gives the autodiff path: the two paths agree there too. A collapsed bar (|u| or |v|
= 0) has stiffness 0, as in the energy. S is taken as |u ^ v| / (|u| |v|) (not sqrt(1 - C²), which loses
precision at small angles).

Units: positions and lengths in m, EI in N·m², stiffness in N/m.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np

from jaxnet import geometry
from jaxnet.terms.cable_bending import chord

# (u, v) = _TO_EDGES @ x for x the (9,) node coordinates, vertex-major: u = x1 - x0, v = x2 - x1
_I3 = np.eye(3)
_TO_EDGES = np.block([[-_I3, _I3, 0.0 * _I3], [0.0 * _I3, -_I3, _I3]])


def joint_stiffness(x, rest_length, ei, rest_angle):
    """(9, 9) stiffness K = ∂²E/∂x² (N/m) of one cable joint, vertex-major (module docstring).

    Args: as :func:`jaxnet.terms.cable_bending.joint_energy` (x (3, 3) m, rest_length (2,) m, EI N·m², β rad).
    """
    a, b = rest_length[0], rest_length[1]
    u, v = x[1] - x[0], x[2] - x[1]
    lu, lv = geometry.safe_norm(u), geometry.safe_norm(v)
    ok = (lu > 0.0) & (lv > 0.0)
    lu_, lv_ = jnp.where(ok, lu, 1.0), jnp.where(ok, lv, 1.0)
    uh, vh = u / lu_, v / lv_
    C = jnp.dot(uh, vh)
    S = geometry.safe_norm(jnp.cross(uh, vh))
    cb, sb = jnp.cos(rest_angle), jnp.sin(rest_angle)
    s = cb * C + sb * S
    c = chord(s, a, b)
    g1 = -2.0 * ei / c
    g2 = 2.0 * ei * a * b / c**3
    bent = S > 0.0
    S_ = jnp.where(bent, S, 1.0)
    slope = cb - jnp.where(bent, sb * C / S_, 0.0)
    h1 = g1 * slope
    h2 = g2 * slope**2 - jnp.where(bent, g1 * sb / S_**3, 0.0)

    grad = jnp.concatenate([(vh - C * uh) / lu_, (uh - C * vh) / lv_])
    uu = (3.0 * C * jnp.outer(uh, uh) - jnp.outer(uh, vh) - jnp.outer(vh, uh) - C * _I3) / lu_**2
    vv = (3.0 * C * jnp.outer(vh, vh) - jnp.outer(vh, uh) - jnp.outer(uh, vh) - C * _I3) / lv_**2
    uv = (_I3 - jnp.outer(uh, uh) - jnp.outer(vh, vh) + C * jnp.outer(uh, vh)) / (lu_ * lv_)
    hessian_c = jnp.block([[uu, uv], [uv.T, vv]])
    k_edges = h1 * hessian_c + h2 * jnp.outer(grad, grad)
    k = _TO_EDGES.T @ k_edges @ _TO_EDGES
    return jnp.where(ok, k, 0.0)
