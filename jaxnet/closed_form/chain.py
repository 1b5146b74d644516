"""From twine-vector space to vertex space: the chain rule every netting closed form ends with.

The twine vectors of a triangle are linear in its vertex positions, U = Σ a_i x_i and V = Σ b_i x_i
(:func:`jaxnet.geometry.twine_coefficients`, eqs 4.3-4.4). A quantity of the element that depends on x
only through U and V therefore has

    ∂/∂x_i = a_i ∂/∂U + b_i ∂/∂V,
    ∂²/∂x_i∂x_j = a_i a_j H_UU + a_i b_j H_UV + b_i a_j H_VU + b_i b_j H_VV,

with H_PQ the (3, 3) blocks of second derivatives in twine space. The book writes this chain rule out
term by term (4.47-4.75: 81 entries, each with its own (V3 - V2)/d factor); here it is done once.

Vertex-major layout: entry (3 i + m, 3 j + n) of a (9, 9) block couples coordinate m of vertex i with
coordinate n of vertex j, as ``x.ravel()`` of (3, 3) positions orders them (the assembly's order).
"""

from __future__ import annotations

import jax.numpy as jnp


def vertex_gradient(a, b, g_u, g_v):
    """(3, 3) derivatives on the vertices (row i: ∂/∂x_i) of derivatives g_u = ∂/∂U, g_v = ∂/∂V (3,)."""
    return a[:, None] * g_u[None, :] + b[:, None] * g_v[None, :]


def vertex_block(a, b, h_uu, h_uv, h_vu, h_vv):
    """(9, 9) second derivatives on the vertices from the (3, 3) twine-space blocks H_UU ... H_VV.

    ``h_uv`` is ∂²/∂U∂V (rows along U, columns along V); any block may be None (zero).
    """
    total = jnp.zeros((3, 3, 3, 3))
    for ci, cj, h in ((a, a, h_uu), (a, b, h_uv), (b, a, h_vu), (b, b, h_vv)):
        if h is not None:
            total = total + ci[:, None, None, None] * cj[None, None, :, None] * h[None, :, None, :]
    return total.reshape(9, 9)
