"""Closed-form stiffness of twine tension (book eqs 4.46-4.75) and of cable bars.

K = -∂F/∂x (4.46) of the tension forces 4.43-4.45, i.e. the Hessian of the energy of
:mod:`jaxnet.terms.tension`, E = (|d|/2) [φ(|U|) + φ(|V|)], written without autodiff.

One twine. For a rod of current vector W (length L = |W|, direction ê = W/L) and tension T(L) (4.30-4.31),

    ∂²φ(|W|)/∂W² = (dT/dL) ê ê^T + (T / L) (I - ê ê^T),

an axial stiffness dT/dL = EA/l0 (the traction or the compression EA, 0 on a slack branch) and a
geometric stiffness T/L across the rod. The book's 4.47-4.57 are these same two parts, per pair of vertex
coordinates: its 4.47 is the (x1, x1) entry, (V3-V2)²/4 · d · [EA/l0 · U_x²/|U|² + T/|U| · (1 - U_x²/|U|²)]
in this notation, once 4.47-4.49's 1/n0 is read as 1/l0 and 4.58-4.75's missing division by |U| is put
back (docs/errata.md). The chain rule from U and V to the vertices (the (V3-V2)/d factors of 4.58-4.75)
is :mod:`jaxnet.closed_form.chain`.

Kink: at a twine exactly at its rest length without compression stiffness the Hessian does not exist (one-
sided values EA/l0 and 0 along the twine); the value returned is the autodiff path's, EA/(4 l0).

Singular point: a twine of zero length has no direction; its stiffness is taken as 0 there, as the
autodiff path's ``safe_norm`` gives. With a compression stiffness T/L grows like -EA/L as L -> 0: the
element is then collapsing, and the value is returned as it is (finite for L > 0).

Units: positions and lengths in m, EA in N, stiffness in N/m.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.closed_form import chain


def rod_stiffness(w, rest_length, ea_traction, ea_compression=None):
    """(3, 3) Hessian (N/m) of the elastic energy of one rod (:func:`jaxnet.terms.tension.elastic_energy`)
    with respect to its vector w (m): axial EA/L0 ê ê^T plus geometric T/L (I - ê ê^T).

    Args:
      w: (3,) the rod's vector, end minus start (m).
      rest_length: L0 (m). ea_traction, ea_compression: EA (N); ``ea_compression=None`` for a rod that goes
        slack in compression (no stiffness, no tension when L < L0; at L = L0 exactly, EA/(4 L0) along the
        rod, as the autodiff path gives).
    """
    length = geometry.safe_norm(w)
    has = length > 0.0
    inv = jnp.where(has, 1.0 / jnp.where(has, length, 1.0), 0.0)
    e = w * inv
    strain = (length - rest_length) / rest_length
    if ea_compression is None:
        # At eps = 0 exactly (the kink of EA l0 max(eps, 0)²/2) the autodiff path differentiates max with
        # the tie split in halves, twice: its axial stiffness there is (1/2)² EA/l0. Same value here, so
        # the two paths agree on a twine exactly at its rest length (T = 0 there: no geometric part).
        ea = jnp.where(strain > 0.0, ea_traction, jnp.where(strain == 0.0, 0.25 * ea_traction, 0.0))
    else:
        ea = jnp.where(strain > 0.0, ea_traction, ea_compression)
    tension = ea * strain
    axial = ea / rest_length
    across = tension * inv
    outer = e[:, None] * e[None, :]
    return jnp.where(has, axial * outer + across * (jnp.eye(3) - outer), 0.0)


def netting_stiffness(x, uv, l0, ea_traction, ea_compression=None):
    """(9, 9) tension stiffness K = -∂F/∂x (N/m) of one diamond-mesh triangle (4.46-4.75, corrected).

    Args: as :func:`jaxnet.terms.tension.netting_energy` (x (3, 3) m, uv (3, 2) twines, l0 m, EA N).
    Vertex-major layout (entry (3 i + m, 3 j + n): coordinate m of vertex i, n of vertex j).
    """
    a, b, d = geometry.twine_coefficients(uv)
    U, V = a @ x, b @ x
    count = geometry.twine_count(d)
    k_u = count * rod_stiffness(U, l0, ea_traction, ea_compression)
    k_v = count * rod_stiffness(V, l0, ea_traction, ea_compression)
    return chain.vertex_block(a, b, k_u, None, None, k_v)


def bar_stiffness(x, rest_length, ea_traction, ea_compression=None):
    """(6, 6) stiffness (N/m) of one cable bar between its ends x (2, 3) (m): ±k of the rod x1 - x0.

    Args: as :func:`jaxnet.terms.cable.bar_energy`.
    """
    k = rod_stiffness(x[1] - x[0], rest_length, ea_traction, ea_compression)
    return jnp.block([[k, -k], [-k, k]])
