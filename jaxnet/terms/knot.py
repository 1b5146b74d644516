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

FEMNET's form (``form="femnet"``). FEMNET, the author's program of this model (routine ``fermeture2``
of ``unix_2004/fermeture2.c``, called once per Newton iteration after the twine tension ``etirement5``
and the mesh opening stiffness ``flexion2``, with which it shares nothing but the geometry) computes a
different contact. Read from its source, in this module's notation (α the half angle, d of 4.7, which
is FEMNET's ``deno``, "the number of twines in the triangle"):

* contact half angle α_c = atan(k / (2 l0)) with l0 the unstretched twine length, not arcsin (its
  display program draws contact with the same atan). For k = 10 mm, l0 = 57.65 mm that is 0.08651 rad
  against 0.08684: the difference is negligible, both are k / (2 l0) to first order;
* contact on both diagonals: α < α_c (rest angle α_c) and α > π/2 - α_c (rest angle π/2 - α_c), no band;
* H = l0² EA / (1000 (k / 2)) = l0² EA / (500 k), five times smaller than 4.280 (the source first sets
  l0² EA / (100 (k / 2)) and overwrites it);
* the vertex forces of 4.216-4.218 *as printed*: F_i = d H (α - α_0) ∂c/∂x_i / (2 sin α), c = U.V/(|U||V|)
  = cos 2α. 4.218 has sin α where the derivative of α = ½ acos c has -sin 2α (opening.py's erratum), so
  this "∂α/∂x_i" is ∂c/∂x_i / (2 sin α) = -2 cos α ∂α/∂x_i, and FEMNET's force is

      F_i = -2 cos α d H (α - α_0) ∂α/∂x_i,

  restoring (for d > 0) thanks to that sign, but with a factor 2 cos α: about 2 at the α -> 0 closure and
  about 2 sin α_c at the α -> π/2 one (0.17 for c2 below). FEMNET's stiffness (k_elem = -∂F/∂x) is the exact Jacobian of that
  force, so the program is consistent with it.

The force is f(α) ∂α/∂x_i with a coefficient that depends on α only, so it *is* conservative (for d > 0):
it is minus the gradient of

    E = (|d| / 2) H φ(α),   φ(α) = 4 [(α - α_0) sin α + cos α - cos α_0],   dφ/dα = 4 (α - α_0) cos α,

taken where the contact is on (φ >= 0 on [0, π/2], zero with zero slope at α_0: a C¹ one-sided penalty
like ``band=0``). In terms of 4.279: a couple per knot C = 2 H cos α (α - α_0) instead of H (α - α_0).
FEMNET multiplies by the signed d, so on a clockwise triangle (d < 0) its contact would push the
meshes closed. All 1243 triangles of the cod-end case c2 have d > 0 (whether FEMNET's mesher always
orients them so was not checked); here |d| is used, equal to FEMNET wherever d > 0. :func:`femnet_contact_force` gives FEMNET's
force literally (signed d, the printed 4.218, its clamp of sin α at α = 1e-5) for comparison.

Evidence that this is FEMNET's contact: on FEMNET's cod-end case c2 (knot 10 mm, l0 57.65 mm, EA 2e5 N;
264 of its 1243 triangles closed beyond π/2 - α_c, at the narrow front and at the gathered end), the
largest out-of-balance force of jaxnet at FEMNET's own equilibrium falls from 410 N with the book form
(its default stiffness, no cos α factor) to 0.8 N with this one, the remainder being netting drag.

Units: positions, l0 and knot size in m, EA in N, H in N·m/rad, angles in rad, energy in J.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import geometry
from jaxnet.terms.opening import half_angle
from jaxnet.terms.term import ENERGY, ClosedForm, Term, any_nonzero, register

DEFAULT_BAND_FRACTION = 0.1
FORMS = ("book", "femnet")
_FEMNET_MIN_ANGLE = 1e-5  # FEMNET's "seuil": below this half angle it divides by sin(1e-5)


def _namespace(*values):
    """numpy for plain numbers and numpy arrays (a ``.don`` reader's material constants: no JAX program
    compiled for three scalar operations), jax.numpy for JAX arrays and tracers."""
    return jnp if any(isinstance(v, jax.Array) for v in values) else np


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
    xp = _namespace(l0, knot_size, ea)
    has_knot = knot_size > 0.0
    return xp.where(has_knot, l0**2 * ea / (100.0 * xp.where(has_knot, knot_size, 1.0)), 0.0)


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


def femnet_contact_half_angle(l0, knot_size):
    """FEMNET's contact half angle α_c = atan(k / (2 l0)) (rad); 0 for k = 0, -> π/2 for huge knots.

    Args:
      l0: unstretched twine length (m). knot_size: k (m).
    """
    return jnp.arctan(knot_size / (2.0 * l0))


def femnet_knot_stiffness(l0, knot_size, ea):
    """FEMNET's contact stiffness H = l0² EA / (1000 k / 2) = l0² EA / (500 k) (N·m/rad); 0 for k = 0.

    A fifth of the book's 4.280 (:func:`default_knot_stiffness`).
    Args:
      l0: unstretched twine length (m). knot_size: k (m). ea: twine traction stiffness EA (N).
    """
    xp = _namespace(l0, knot_size, ea)
    has_knot = knot_size > 0.0
    return xp.where(has_knot, l0**2 * ea / (500.0 * xp.where(has_knot, knot_size, 1.0)), 0.0)


def femnet_penalty(alpha, contact_angle):
    """φ(α) = 4 [(α - α_0) sin α + cos α - cos α_0] (rad², dimensionless), FEMNET's contact per knot / (H/2).

    dφ/dα = 4 (α - α_0) cos α: the couple per knot is C = 2 H cos α (α - α_0) (module docstring). φ >= 0 on
    [0, π/2] with its minimum 0 at α_0; the caller keeps it only on the contact side.
    Args:
      alpha: half opening angle (rad). contact_angle: α_0, the half angle where contact starts (rad).
    """
    return 4.0 * ((alpha - contact_angle) * jnp.sin(alpha) + jnp.cos(alpha) - jnp.cos(contact_angle))


def contact_options(form, band, stiffness, ea, l0, knot_size, caller):
    """Check a knot contact's options (:func:`knot_contact_energy`'s, also those of its closed-form stiffness)
    and resolve the default stiffness: returns (femnet, H) with femnet True for FEMNET's form and H in N·m/rad.
    ``caller`` names the function in the error messages."""
    if form not in FORMS:
        raise ValueError(f"{caller}: form must be one of {FORMS}, not {form!r}")
    femnet = form == "femnet"
    if femnet and band is not None:
        raise ValueError(f"{caller}: FEMNET's contact has no band; leave band=None with form='femnet'")
    if stiffness is None:
        if ea is None:
            raise ValueError(f"{caller}: the default stiffness (eq. 4.280 or FEMNET's) needs ea, the twine EA (N)")
        stiffness = (femnet_knot_stiffness if femnet else default_knot_stiffness)(l0, knot_size, ea)
    return femnet, stiffness


def knot_contact_energy(x, uv, l0, knot_size, stiffness=None, *, ea=None, band=None, both_diagonals=True,
                        form="book"):
    """Energy (J) of the knot contacts of one diamond-mesh triangle.

    ``form="book"`` (default): (|d|/2) H g(α_min - α), zero while the meshes are more open than α_min
    (half angle, :func:`contact_half_angle`); below it, a couple per knot whose stiffness rises
    continuously to H over ``band`` (module docstring). With ``both_diagonals`` also
    (|d|/2) H g(α - (π/2 - α_min)) for the closure along the other diagonal.

    ``form="femnet"``: FEMNET's contact, (|d|/2) H φ(α) (:func:`femnet_penalty`) below
    α_c = atan(k / (2 l0)) and, with ``both_diagonals``, above π/2 - α_c; no band.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
      l0: mesh side, the unstretched twine length (m).
      knot_size: knot size k (m); 0 for knotless netting (no contact).
      stiffness: contact stiffness H (N·m/rad) per knot per radian of half angle; None for the form's
        default (4.280 for "book", :func:`femnet_knot_stiffness` for "femnet"), which then needs ``ea``.
      ea: twine traction stiffness EA (N), used only by the default stiffness.
      band: "book" only: width (rad) of the stiffness ramp below α_min; None for α_min / 10; 0 for the
        plain one-sided penalty of 4.279 (stiffness jump at onset). Must be None for "femnet".
      both_diagonals: also resist closing towards α = π/2 (the book has only α -> 0; FEMNET has both);
        a Python bool.
      form: "book" or "femnet", a Python str.
    """
    femnet, stiffness = contact_options(form, band, stiffness, ea, l0, knot_size, "knot_contact_energy")
    alpha, d, valid = half_angle(x, uv)
    if femnet:
        contact = femnet_contact_half_angle(l0, knot_size)
        other = 0.5 * jnp.pi - contact
        penalty = jnp.where(alpha < contact, femnet_penalty(alpha, contact), 0.0)
        if both_diagonals:
            penalty = penalty + jnp.where(alpha > other, femnet_penalty(alpha, other), 0.0)
    else:
        alpha_min = contact_half_angle(l0, knot_size)
        if band is None:
            band = DEFAULT_BAND_FRACTION * alpha_min
        penalty = contact_penalty(alpha_min - alpha, band)
        if both_diagonals:
            penalty = penalty + contact_penalty(alpha - (0.5 * jnp.pi - alpha_min), band)
    energy = geometry.knot_count(d) * stiffness * penalty
    return jnp.where(valid, energy, 0.0)


def femnet_contact_force(x, uv, l0, knot_size, stiffness=None, *, ea=None):
    """FEMNET's knot contact forces on the three vertices (N, (3, 3)), computed its way, for comparison.

    F_i = d H (α - α_0) ∂c/∂x_i / (2 sin α), c = U.V / (|U||V|), with the *signed* d of 4.7, α_0 = α_c
    where α < α_c and π/2 - α_c where α > π/2 - α_c, 0 elsewhere, sin α clamped below at α = 1e-5 as
    FEMNET does. Equal to -∇ of ``knot_contact_energy(..., form="femnet")`` when d > 0, to +∇ when d < 0
    (module docstring). Not meant for the solver: it is not differentiable at onset as an energy's
    gradient is, and it has no safeguard for collapsed twines.
    Args: as :func:`knot_contact_energy`; ``stiffness`` None for :func:`femnet_knot_stiffness` (needs ``ea``).
    """
    if stiffness is None:
        if ea is None:
            raise ValueError("femnet_contact_force: FEMNET's default stiffness needs ea, the twine EA (N)")
        stiffness = femnet_knot_stiffness(l0, knot_size, ea)

    def cosine(y):
        U, V, _ = geometry.twine_vectors(y, uv)
        return jnp.dot(U, V) / (geometry.safe_norm(U) * geometry.safe_norm(V))

    alpha, d, _ = half_angle(x, uv)
    contact = femnet_contact_half_angle(l0, knot_size)
    other = 0.5 * jnp.pi - contact
    rest = jnp.where(alpha > other, other, contact)  # FEMNET tests the π/2 side last: it wins if both hold
    active = (alpha < contact) | (alpha > other)
    slope = jax.grad(cosine)(x) / (2.0 * jnp.sin(jnp.maximum(alpha, _FEMNET_MIN_ANGLE)))
    return jnp.where(active, d * stiffness * (alpha - rest), 0.0) * slope


# -- the term --------------------------------------------------------------------------------------


def per_form(contact, forms, knot_form):
    """The contact of the laws ``forms`` (codes: indices into :data:`FORMS`) present in a scene, each kept
    where the triangle's ``knot_form`` code is its own: ``contact(form name)`` summed over the forms (a
    single form is not masked). Shared by the energy and its closed-form stiffness."""
    total = 0.0
    for code in forms:
        value = contact(FORMS[code])
        total = total + (value if len(forms) == 1 else jnp.where(knot_form == code, value, 0.0))
    return total


def knot_contact(x, uv, l0, knot_size, stiffness, knot_form, forms):
    """Energy (J) of the knot contacts of one triangle under its law (``knot_form``: a code of :data:`FORMS`;
    ``forms``: the codes present in the scene, static); :func:`knot_contact_energy` of each."""
    return per_form(lambda form: knot_contact_energy(x, uv, l0, knot_size, stiffness, form=form), forms, knot_form)


def _arguments(p, env, forms):
    return {"uv": p.uv, "l0": p.l0, "knot_size": p.knot_size, "stiffness": p.knot_stiffness,
            "knot_form": p.knot_form, "forms": forms}


def _active(scene, dynamic):
    net = scene.netting
    if net is None or not any_nonzero(net.knot_size):
        return None
    codes = np.zeros(1, int) if net.knot_form is None else np.asarray(net.knot_form)
    return {"forms": tuple(sorted(set(codes.tolist())))}


KNOT_CONTACT = register(Term(
    name="knot_contact", family="netting", kind=ENERGY, element=knot_contact, arguments=_arguments, active=_active,
    elastic=True, closed_form=ClosedForm("jaxnet.closed_form.knot:knot_contact_stiffness_per_form")))
