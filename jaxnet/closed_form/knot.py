"""Closed-form stiffness of the contact between knots (book eqs 4.278-4.280, corrected).

The book computes the contact forces and stiffness "as in 4.3.4" (the mesh opening, 4.216-4.219) with
the couple 4.279 in place of 4.212. :mod:`jaxnet.terms.knot` writes the contact as an energy of the
half opening angle α alone, E = (|d|/2) H P(α), so its Hessian has the structure of the opening's
(:mod:`jaxnet.closed_form.opening`):

    K = (|d|/2) H [P''(α) ∂α ⊗ ∂α + P'(α) ∂²α]          (N/m),

with ∂α, ∂²α the closed forms of the corrected 4.218 and its derivative, and P', P'' written here by
hand for the two forms of :func:`jaxnet.terms.knot.knot_contact_energy`:

* ``form="book"``: P(α) = g(α_min - α) [+ g(α - (π/2 - α_min)) with ``both_diagonals``], g the C²
  band penalty of :func:`jaxnet.terms.knot.contact_penalty`:

      g'(s)  = 0,            g''(s) = 0           s <= 0
      g'(s)  = s² / b,       g''(s) = 2 s / b     0 < s < b
      g'(s)  = 2 s - b,      g''(s) = 2           s >= b,

  so P' = -g'(α_min - α) [+ g'(α - π/2 + α_min)] and P'' = g''(α_min - α) [+ g''(α - π/2 + α_min)].
  With ``band=0`` the middle branch is empty: g = s₊², whose g'' jumps from 0 to 2 at onset (4.279).
* ``form="femnet"``: P(α) = φ(α; α_c) below α_c [+ φ(α; π/2 - α_c) above π/2 - α_c], with
  φ = 4 [(α - α_0) sin α + cos α - cos α_0] (:func:`jaxnet.terms.knot.femnet_penalty`):

      φ'(α) = 4 (α - α_0) cos α,     φ''(α) = 4 [cos α - (α - α_0) sin α].

  φ'' = 4 cos α_0 > 0 at α_0: the stiffness jumps at onset, as in FEMNET.

Branches are chosen with the same comparisons as the energy (``s <= 0``, ``s < b``; ``α < α_c``,
``α > π/2 - α_c``), so exactly at onset and at the band edge K is the derivative of the branch that the
autodiff path differentiates there (the one-sided derivative on the side that includes the point).

Singular points: those of ∂α and ∂²α (:mod:`jaxnet.closed_form.opening`): at the exactly closed mesh
both are 0, so K = 0 there (the autodiff value, from ``safe_norm``'s zero derivative), although a mesh
that close is deep in contact and K grows like 1/|U ^ V| on approach; a collapsed twine gives K = 0.

Units: positions, l0 and knot size in m, EA in N, H in N·m/rad, angles in rad, K in N/m.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet.closed_form.opening import angle_energy_hessian
from jaxnet.terms import knot


def penalty_slope(s, band):
    """g'(s) (rad) of the band penalty :func:`jaxnet.terms.knot.contact_penalty`; s = closing beyond contact (rad)."""
    b = jnp.where(band > 0.0, band, 1.0)  # the ramp is never selected when band = 0
    return jnp.where(s <= 0.0, 0.0, jnp.where(s < band, s**2 / b, 2.0 * s - band))


def penalty_curvature(s, band):
    """g''(s) (dimensionless) of the band penalty: rises linearly from 0 to 2 across the band, 2 beyond."""
    b = jnp.where(band > 0.0, band, 1.0)
    return jnp.where(s <= 0.0, 0.0, jnp.where(s < band, 2.0 * s / b, 2.0))


def femnet_penalty_slope(alpha, contact_angle):
    """φ'(α) = 4 (α - α_0) cos α (rad) of :func:`jaxnet.terms.knot.femnet_penalty`; α, α_0 in rad."""
    return 4.0 * (alpha - contact_angle) * jnp.cos(alpha)


def femnet_penalty_curvature(alpha, contact_angle):
    """φ''(α) = 4 [cos α - (α - α_0) sin α] (dimensionless) of :func:`jaxnet.terms.knot.femnet_penalty`."""
    return 4.0 * (jnp.cos(alpha) - (alpha - contact_angle) * jnp.sin(alpha))


def knot_contact_stiffness(x, uv, l0, knot_size, stiffness=None, *, ea=None, band=None, both_diagonals=True,
                           form="book"):
    """(9, 9) knot contact stiffness K = -∂F/∂x (N/m) of one diamond-mesh triangle (4.278-4.280 with 4.219).

    The Hessian of :func:`jaxnet.terms.knot.knot_contact_energy` called with the same arguments,
    vertex-major (entry (3 i + m, 3 j + n): coordinate m of vertex i, n of vertex j); 0 out of contact.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
      l0: mesh side, the unstretched twine length (m).
      knot_size: knot size k (m); 0 for knotless netting.
      stiffness: contact stiffness H (N·m/rad); None for the form's default (4.280, or FEMNET's l0² EA/(500 k)),
        which needs ``ea``.
      ea: twine traction stiffness EA (N), for the default stiffness only.
      band: "book" only: width of the stiffness ramp (rad); None for α_min / 10, 0 for the one-sided
        penalty of 4.279. Must be None for "femnet".
      both_diagonals: also resist the closure towards α = π/2 (a Python bool).
      form: "book" or "femnet" (a Python str).
    """
    femnet, stiffness = knot.contact_options(form, band, stiffness, ea, l0, knot_size, "knot_contact_stiffness")

    if femnet:
        contact = knot.femnet_contact_half_angle(l0, knot_size)
        other = 0.5 * jnp.pi - contact

        def slope(alpha):
            p = jnp.where(alpha < contact, femnet_penalty_slope(alpha, contact), 0.0)
            if both_diagonals:
                p = p + jnp.where(alpha > other, femnet_penalty_slope(alpha, other), 0.0)
            return stiffness * p

        def curvature(alpha):
            p = jnp.where(alpha < contact, femnet_penalty_curvature(alpha, contact), 0.0)
            if both_diagonals:
                p = p + jnp.where(alpha > other, femnet_penalty_curvature(alpha, other), 0.0)
            return stiffness * p
    else:
        alpha_min = knot.contact_half_angle(l0, knot_size)
        if band is None:
            band = knot.DEFAULT_BAND_FRACTION * alpha_min
        other = 0.5 * jnp.pi - alpha_min

        # s = α_min - α closes the α -> 0 side (ds/dα = -1), s = α - (π/2 - α_min) the other (ds/dα = +1)
        def slope(alpha):
            p = -penalty_slope(alpha_min - alpha, band)
            if both_diagonals:
                p = p + penalty_slope(alpha - other, band)
            return stiffness * p

        def curvature(alpha):
            p = penalty_curvature(alpha_min - alpha, band)
            if both_diagonals:
                p = p + penalty_curvature(alpha - other, band)
            return stiffness * p

    return angle_energy_hessian(x, uv, slope, curvature)


def knot_contact_stiffness_per_form(x, uv, l0, knot_size, stiffness, knot_form, forms):
    """(9, 9) stiffness (N/m) of :func:`jaxnet.terms.knot.knot_contact` (same arguments): each triangle under
    its own contact law, :func:`knot_contact_stiffness` of each law present."""
    return knot.per_form(lambda form: knot_contact_stiffness(x, uv, l0, knot_size, stiffness, form=form), forms,
                         knot_form)
