"""Twine tension in diamond-mesh netting (book eqs 4.30-4.45), as a per-element elastic energy.

The book derives the vertex forces (4.43-4.45) by virtual work from the twine tensions
T = EA (|U| - l0) / l0 (4.30-4.31). Those forces are exactly minus the gradient of the energy

    E = (|d| / 2) [ phi(|U|) + phi(|V|) ],      phi(L) = EA l0 eps² / 2,  eps = (L - l0) / l0,

because dphi/dL = T and |d|/2 is the number of U (and of V) twines in the element (4.25-4.26). Writing
the energy instead of the forces makes the element conservative by construction, gives the forces by
``jax.grad`` and the tangent stiffness (4.46-4.75) by ``jax.jacfwd``; using |d| instead of d makes
clockwise triangles (d < 0) correct, which the printed forces 4.43-4.45 are not: for d < 0 they carry
the wrong sign (their factors V3 - V2 etc. come from dividing d/2 by d).

As in FEMNET, traction and compression have separate stiffnesses. With ``ea_compression=None`` (a net
whose twines all have compression stiffness 0) the compressive branch is not even traced: a slack twine
then carries nothing.
"""

from __future__ import annotations

import jax
import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.term import ENERGY, ClosedForm, Rods, Term, any_nonzero, register


def elastic_energy(length, rest_length, ea_traction, ea_compression=None):
    """Elastic energy (J) of one straight elastic rod: EA L0 eps² / 2 with eps = (L - L0) / L0.

    Shared by twines and cable bars. Its derivative in ``length`` is the tension EA eps (N), with EA the
    traction stiffness when eps > 0 and the compression stiffness otherwise.

    Args:
      length: current length L (m).
      rest_length: unstretched length L0 (m), > 0.
      ea_traction: traction stiffness EA (N).
      ea_compression: compression stiffness (N), or None for a rod that cannot be compressed (slack).
    """
    strain = (length - rest_length) / rest_length
    if ea_compression is None:
        return 0.5 * ea_traction * rest_length * jnp.maximum(strain, 0.0) ** 2
    with jax.named_scope("compressive_branch"):  # traced only when some rod has a compression stiffness
        ea = jnp.where(strain > 0.0, ea_traction, ea_compression)
    return 0.5 * ea * rest_length * strain**2


def tension(length, rest_length, ea_traction, ea_compression=None):
    """Tension (N, positive in traction) of one rod, T = EA (L - L0) / L0 (eqs 4.30-4.31)."""
    strain = (length - rest_length) / rest_length
    if ea_compression is None:
        return ea_traction * jnp.maximum(strain, 0.0)
    return jnp.where(strain > 0.0, ea_traction, ea_compression) * strain


def netting_energy(x, uv, l0, ea_traction, ea_compression=None):
    """Elastic energy (J) of the twines of one diamond-mesh triangle.

    Args:
      x: (3, 3) vertex positions (m).
      uv: (3, 2) twine coordinates of the vertices (twines).
      l0: unstretched length of one twine (mesh side) (m).
      ea_traction, ea_compression: twine stiffnesses (N); see :func:`elastic_energy`.
    """
    U, V, d = geometry.twine_vectors(x, uv)
    per_family = geometry.twine_count(d)
    return per_family * (
        elastic_energy(geometry.safe_norm(U), l0, ea_traction, ea_compression)
        + elastic_energy(geometry.safe_norm(V), l0, ea_traction, ea_compression)
    )


def netting_tensions(x, uv, l0, ea_traction, ea_compression=None):
    """Tensions (Tu, Tv) in N of the U and V twines of one triangle (eqs 4.30-4.31), for output."""
    U, V, _ = geometry.twine_vectors(x, uv)
    return (
        tension(geometry.safe_norm(U), l0, ea_traction, ea_compression),
        tension(geometry.safe_norm(V), l0, ea_traction, ea_compression),
    )


def netting_rods(x, uv, l0, ea_traction, ea_compression=None):
    """The triangle's twines as two rods (:class:`jaxnet.terms.term.Rods`): its U and its V twines, each family
    the |d|/2 parallel twines of one twine vector (4.25-4.26), so of length |U| (|V|), rest length l0 and axial
    stiffness |d|/2 EA / l0 (N/m). Their energies sum to :func:`netting_energy` without compression."""
    U, V, d = geometry.twine_vectors(x, uv)
    k = geometry.twine_count(d) * ea_traction / l0
    return jnp.stack([geometry.safe_norm(U), geometry.safe_norm(V)]), jnp.stack([l0, l0]), jnp.stack([k, k])


def tension_only(options):
    """Whether a tension term's options leave it tension-only (no compression stiffness): its rods then cover it."""
    return not options.get("compression")


def tension_activity(family):
    """The activity rule of a family's twine or bar tension: present where any stiffness is not zero, with the
    compressive branch traced only where some element has a compression stiffness (option ``compression``)."""

    def active(scene, dynamic):
        f = getattr(scene, family)
        if f is None or not any_nonzero(f.ea_traction) and not any_nonzero(f.ea_compression):
            return None
        return {"compression": any_nonzero(f.ea_compression)}

    return active


def _arguments(p, env, compression):
    return {"uv": p.uv, "l0": p.l0, "ea_traction": p.ea_traction,
            "ea_compression": p.ea_compression if compression else None}


NETTING_TENSION = register(Term(
    name="netting_tension", family="netting", kind=ENERGY, element=netting_energy, arguments=_arguments,
    active=tension_activity("netting"), elastic=True,
    closed_form=ClosedForm("jaxnet.closed_form.tension:netting_stiffness"),
    rods=Rods(netting_rods, tension_only)))
