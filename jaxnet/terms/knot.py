"""Contact between knots: meshes cannot close below the angle at which knots touch (eqs 4.278-4.280).

Contact angle. In a mesh with knots A (origin), B = A + U, D = A + V, the knots B and D close in on
each other as the mesh closes: |U - V| = 2 l sin α with l = |U| = |V| the mesh side and α the *half*
opening angle of :mod:`jaxnet.terms.opening` (the angle between U and V is 2α). Knots of size k
(centre to surface k/2 each) touch when |U - V| = k, at the half angle

    α_min = arcsin(k / (2 l)),

whose *full* angle 2 α_min = 2 arcsin(k / (2 l)) is 4.278. The book then compares 4.278 with "α" and
computes forces "as in 4.3.4", where α is the half angle (4.211): taken literally that puts contact at
twice the right half angle. Here the half angle is used throughout, as in opening.py. The mesh side is
the unstretched twine length l0, as the book suggests, so α_min is a constant of the element.

The other diagonal. A mesh also closes the other way, α → π/2 (U → -V): then knots A and C = A + U + V
close in, |U + V| = 2 l cos α, and touch at α = π/2 - α_min. The book treats only α < α_min, but which
diagonal closes at α → 0 is only a choice of sign of the V twine coordinate (V → -V maps α to π/2 - α),
so a contact on one side only would make the physics depend on that labelling. Both closures are in
contact by default (``both_diagonals=True``); the free range is α_min < α < π/2 - α_min.

The energy. 4.279 puts the couple C = H (α - α_min) per knot below α_min and none above; with the
virtual work of 4.3.4 (see opening.py: 2 C ∂α per knot, |d|/2 knots) that is the gradient of
(|d|/2) H s² with s = α_min - α > 0, a one-sided quadratic penalty. Its stiffness jumps from 0 to
|d| H (∂α ⊗ ∂α) at onset, so a Newton step computed on one side of onset is wrong on the other and
active sets flip back and forth (chatter). Here the penalty is instead

    E = (|d|/2) H g(s),   g(s) = 0                       s <= 0   (more open than α_min)
                          g(s) = s³ / (3 b)              0 < s < b
                          g(s) = (s - b/2)² + b²/12      s >= b,

a C² function: the couple per knot, C = -H g'(s)/2, grows as -H s²/(2b) inside a band of width b
below α_min, then as 4.279 with the full stiffness dC/dα = H; dC/dα rises linearly from 0 to H across
the band. What it costs, exactly: beyond the band the couple is 4.279's with contact at α_min - b/2
(it differs from 4.279 by at most H b / 2 anywhere), and the energy lies between the one-sided penalties
with contact at α_min and at α_min - b: (s - b)₊² <= g(s) <= s₊². The default band b = α_min / 10 moves
the effective contact by b/2 = 5 % of α_min (a knot 5 % smaller), well inside the uncertainty on knot
sizes, while spreading the stiffness rise over an angle that a Newton step resolves. ``band=0`` gives the plain one-sided penalty.

Stiffness. H is "not well known"; by default the book's 4.280, H = l0² EA / (100 k) (N·m/rad), with
EA the twine traction stiffness.

Units: positions, l0 and knot size in m, EA in N, H in N·m/rad, angles in rad, energy in J.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.opening import half_angle

DEFAULT_BAND_FRACTION = 0.1


def contact_half_angle(l0, knot_size):
    """Half opening angle at which knots touch, α_min = arcsin(k / (2 l0)) (rad); half of 4.278.

    Knots as large as the mesh (k >= 2 l0) forbid any closing: α_min = π/2. k = 0 gives α_min = 0.
    """
    ratio = knot_size / (2.0 * l0)
    possible = ratio < 1.0
    # double where: arcsin has an infinite derivative at 1
    return jnp.where(possible, jnp.arcsin(jnp.where(possible, ratio, 0.0)), 0.5 * jnp.pi)


def default_knot_stiffness(l0, knot_size, ea):
    """Knot contact stiffness of eq. 4.280, H = l0² EA / (100 k) (N·m/rad); 0 for k = 0 (no knots).

    Args:
      l0: mesh side, the unstretched twine length (m). knot_size: k (m). ea: twine traction stiffness EA (N).
    """
    has_knot = knot_size > 0.0
    return jnp.where(has_knot, l0**2 * ea / (100.0 * jnp.where(has_knot, knot_size, 1.0)), 0.0)


def contact_penalty(s, band):
    """The C² one-sided penalty g(s) (rad²) of the module docstring: 0 for s <= 0, ~ s² deep in contact.

    Args:
      s: closing beyond contact, α_min - α (rad).
      band: width b >= 0 (rad) of the band over which the stiffness rises; 0 gives s₊².
    """
    b = jnp.where(band > 0.0, band, 1.0)  # the cubic branch is never selected when band = 0
    ramp = s**3 / (3.0 * b)
    full = (s - 0.5 * band) ** 2 + band**2 / 12.0
    return jnp.where(s <= 0.0, 0.0, jnp.where(s < band, ramp, full))


def knot_contact_energy(x, uv, l0, knot_size, stiffness=None, *, ea=None, band=None, both_diagonals=True):
    """Energy (J) of the knot contacts of one diamond-mesh triangle: (|d|/2) H g(α_min - α).

    Zero while the meshes are more open than α_min (half angle, :func:`contact_half_angle`); below it,
    a couple per knot whose stiffness rises continuously to H over ``band`` (module docstring). With
    ``both_diagonals`` also (|d|/2) H g(α - (π/2 - α_min)) for the closure along the other diagonal.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
      l0: mesh side, the unstretched twine length (m).
      knot_size: knot size k (m); 0 for knotless netting (no contact).
      stiffness: contact stiffness H (N·m/rad) per knot per radian of half angle; None for 4.280,
        which then needs ``ea``.
      ea: twine traction stiffness EA (N), used only by the default stiffness.
      band: width (rad) of the stiffness ramp below α_min; None for α_min / 10; 0 for the plain
        one-sided penalty of 4.279 (stiffness jump at onset).
      both_diagonals: also resist closing towards α = π/2 (the book has only α -> 0); a Python bool.
    """
    if stiffness is None:
        if ea is None:
            raise ValueError("knot_contact_energy: the default stiffness (eq. 4.280) needs ea, the twine EA (N)")
        stiffness = default_knot_stiffness(l0, knot_size, ea)
    alpha_min = contact_half_angle(l0, knot_size)
    if band is None:
        band = DEFAULT_BAND_FRACTION * alpha_min
    alpha, d, valid = half_angle(x, uv)
    penalty = contact_penalty(alpha_min - alpha, band)
    if both_diagonals:
        penalty = penalty + contact_penalty(alpha - (0.5 * jnp.pi - alpha_min), band)
    energy = geometry.knot_count(d) * stiffness * penalty
    return jnp.where(valid, energy, 0.0)
