"""Bending of stiff cables at their joints: FEMNET's ``EI_flexion_cable`` and ``link_flexion_elem2``.

A cable with a flexural stiffness EI (N·m²: a rigid bar, a float line, the twines of a stiff netting modelled
as cables) resists the turn of its direction where two of its bars meet; two cables welded at a node
(``link_flexion_elem2 A B angle``) resist the change of the angle between them. Each such joint is a row of
:class:`~jaxnet.scene.CableJoints`: nodes (x0, x1, x2), bars u = x1 - x0 and v = x2 - x1 of unstretched
lengths a and b, stiffness EI and neutral turning angle β.

FEMNET's law (read in its C source, dpriour/femnet: ``unix_2004/pliage_barre_pardiso2_3.c`` for the joints
inside a cable, neutral angle 0; ``pliage_barre_pardiso4.c`` (``toto4``) for the joints between linked
cables; the commands read in ``unix_2004/chargement_don.c``)
------------------------------------------------------------------------------------------------------------
α = acos(u·v / (|u| |v|)) is the turning angle at the joint (0: the bars aligned, pi: folded back). The
couple is the bending moment of a beam bent to the circle through the joint's three points,

    M = EI / R,    R = c / (2 sin(α - β)),    c = |u + Rot_β(v)| = sqrt(|u|² + |v|² + 2 |u| |v| cos(α - β)),

R the radius of the circle circumscribing the triangle of the two bars, the second turned back by the neutral
angle (``Rayon*sin(alpha) = c/2`` in the source). The couple acts as a pair of forces across the bars:
M/|u| on x0 normal to u, M/|v| on x2 normal to v, in the plane of the bars and towards straightening them
(towards α = β), and minus their sum on x1: FEMNET's F1 = 2 EI/c (u (u·v)/(|u|³|v|) - v/(|u||v|))
sin(α-β)/sin α and its F3, F2 = -(F1 + F3). No force acts along the bars.

``EI_flexion_cable K EI`` gives every bar of cable K the stiffness EI; a joint between two bars of one cable
has neutral angle β = 0 and that EI (``pliage_barre_pardiso2_3``). ``link_flexion_elem2 A B γ`` adds a joint
between each bar of cable A and each bar of cable B that share a node, with β = pi - γ (the file's γ is the
angle *between* the cables: 180° when aligned, 90° square; ``chargement_don.c`` stores 180 - γ) and the
stiffness of the less stiff of the two cables (``toto4`` computes the mean of the two EI and then overwrites it
with their minimum; the manual says "the mean value": the code's minimum is what FEMNET does).

What is computed here, and why
------------------------------
An energy, so that forces are ``-jax.grad`` and the stiffness its Hessian, as every elastic term of jaxnet.
FEMNET's couple is the derivative in α of

    E(α) = 2 EI (a + b - c(α - β)) / (a b),      c(φ) = sqrt(a² + b² + 2 a b cos φ),

(dE/dα = 2 EI sin(α - β) / c = EI / R) when the chord c is taken on the bars' lengths a, b. jaxnet takes a and b
as the bars' *unstretched* lengths (material lengths, as discrete elastic rods do): E then depends on the
bars' directions only, its forces are exactly normal to the bars (the virtual work of stretching a bar is
zero), and they are FEMNET's forces wherever the bars are at their rest length; a stretched bar changes the
couple by its strain only (FEMNET's c is on the stretched bars, which makes its forces non-conservative:
their curl is of the order of the strain). For a small angle E = EI (α - β)² / (a + b) (1 + O(α²)): the
discrete beam's EI κ² ℓ / 2 with curvature κ = 2 (α - β)/(a + b) over the length ℓ = (a + b)/2 a joint
stands for; with equal bars, E = EI (α-β)²/(2a) and M = 2 EI sin((α-β)/2) / a.

Smoothness. E is written with cos(α - β) = cos α cos β + sin α sin β, cos α = u·v/(|u||v|) and sin α =
|u ^ v|/(|u||v|): no acos. Inside a cable (β = 0) E is a smooth function of cos α, finite with its
gradient and Hessian at a straight cable (where they vanish, resp. are EI/(a+b) times the usual
curvature operator). With β ≠ 0 the straight state α = 0 is a cone point of E (a joint that must bend
chooses a plane to bend in; FEMNET then picks an arbitrary normal): |u ^ v| is taken by
:func:`jaxnet.geometry.safe_norm`, whose derivative there is 0, so forces and stiffness stay finite. Folded
right back (α - β = pi) with a = b, c = 0 and the couple is infinite: the guard below holds c² above
(1e-12 a b)² so that nothing is NaN, which only a collapsed joint reaches.

Units: positions and lengths in m, EI in N·m², angles in rad, energy in J.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.term import ENERGY, ClosedForm, Term, any_nonzero, register

#: relative floor of the chord c (times sqrt(a b)): only a joint folded right back with equal bars reaches it
CHORD_FLOOR = 1e-12


def bend_cosine(x, rest_angle):
    """cos(α - β) of one joint: x (3, 3) its nodes (m), β = ``rest_angle`` (rad); α the angle between the bars
    x1 - x0 and x2 - x1 (0 when aligned). Finite with its derivatives everywhere but at a collapsed bar."""
    u, v = x[1] - x[0], x[2] - x[1]
    lengths = geometry.safe_norm(u) * geometry.safe_norm(v)
    ok = lengths > 0.0
    inv = jnp.where(ok, 1.0 / jnp.where(ok, lengths, 1.0), 0.0)
    cos_a = jnp.dot(u, v) * inv
    sin_a = geometry.safe_norm(jnp.cross(u, v)) * inv
    return cos_a * jnp.cos(rest_angle) + sin_a * jnp.sin(rest_angle)


def chord(cosine, a, b):
    """c = sqrt(a² + b² + 2 a b cos φ) (m): the distance between the far ends of bars of lengths a, b (m) at
    turning angle φ, held above ``CHORD_FLOOR`` sqrt(a b)."""
    c2 = a * a + b * b + 2.0 * a * b * cosine
    return jnp.sqrt(jnp.maximum(c2, (CHORD_FLOOR**2) * a * b))


def joint_energy(x, rest_length, ei, rest_angle):
    """Bending energy (J) of one cable joint: E = 2 EI (a + b - c) / (a b) (module docstring).

    Args:
      x: (3, 3) positions (m) of the far end of the first bar, the joint node, the far end of the second bar.
      rest_length: (2,) unstretched lengths a, b (m) of the two bars.
      ei: flexural stiffness EI (N·m²).
      rest_angle: neutral turning angle β (rad): 0 for a cable straight at rest.
    """
    a, b = rest_length[0], rest_length[1]
    c = chord(bend_cosine(x, rest_angle), a, b)
    return 2.0 * ei * (a + b - c) / (a * b)


def joint_moment(x, rest_length, ei, rest_angle):
    """The bending moment M = dE/dα = 2 EI sin(α - β) / c (N·m, >= 0) of one joint, for output: FEMNET's
    EI / R, R the radius of the circle through the joint's points (module docstring)."""
    a, b = rest_length[0], rest_length[1]
    cosine = bend_cosine(x, rest_angle)
    sine = jnp.sqrt(jnp.maximum(1.0 - cosine * cosine, 0.0))
    return 2.0 * ei * sine / chord(cosine, a, b)


def _active(scene, dynamic):
    joints = scene.cable_joints
    return {} if joints is not None and any_nonzero(joints.stiffness) else None


CABLE_BENDING = register(Term(
    name="cable_bending", family="cable_joints", kind=ENERGY, element=joint_energy,
    arguments=lambda p, env: {"rest_length": p.rest_length, "ei": p.stiffness, "rest_angle": p.rest_angle},
    active=_active, elastic=True, closed_form=ClosedForm("jaxnet.closed_form.cable_bending:joint_stiffness")))
