"""Cables (ropes, bars): straight elastic bars between two nodes.

A cable of unstretched length L is discretised into n bars of rest length L/n. Each bar stores the elastic
energy of :func:`jaxnet.terms.tension.elastic_energy` (separate traction and compression stiffness, N).
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.terms.tension import elastic_energy, tension, tension_activity, tension_only
from jaxnet.terms.term import ENERGY, ClosedForm, Rods, Term, register


def bar_energy(x, rest_length, ea_traction, ea_compression=None):
    """Elastic energy (J) of one bar. x: (2, 3) end positions (m); rest_length (m); EA (N)."""
    return elastic_energy(geometry.safe_norm(x[1] - x[0]), rest_length, ea_traction, ea_compression)


def bar_tension(x, rest_length, ea_traction, ea_compression=None):
    """Tension (N, positive in traction) of one bar, for output."""
    return tension(geometry.safe_norm(x[1] - x[0]), rest_length, ea_traction, ea_compression)


def bar_rods(x, rest_length, ea_traction, ea_compression=None):
    """The bar as one rod (:class:`jaxnet.terms.term.Rods`): length |x1 - x0|, its rest length, stiffness EA / L0
    (N/m)."""
    return (geometry.safe_norm(x[1] - x[0])[None], jnp.reshape(rest_length, (1,)),
            jnp.reshape(ea_traction / rest_length, (1,)))


def _arguments(p, env, compression):
    return {"rest_length": p.rest_length, "ea_traction": p.ea_traction,
            "ea_compression": p.ea_compression if compression else None}


BAR_TENSION = register(Term(
    name="bar_tension", family="bars", kind=ENERGY, element=bar_energy, arguments=_arguments,
    active=tension_activity("bars"), elastic=True, closed_form=ClosedForm("jaxnet.closed_form.tension:bar_stiffness"),
    rods=Rods(bar_rods, tension_only)))
