"""Catches held by chosen panels: FEMNET's ``input catch2_volume``, several catches in one net.

A trawl with twin cod-ends, or a grid section whose compartments each collect fish, holds several catches at
once. Each catch k (:class:`jaxnet.scene.PanelCatches`) fills the netting of its own panels from the rear: its
front is the plane {y · a = s_k} normal to the catches' axis a (downstream) placed so that the netting of its
panels behind it encloses its volume (:func:`jaxnet.model.catch.panel_catch_state`: :func:`jaxnet.model.catch.catch_front`
on those triangles only, as FEMNET's ``catch2_volume.c`` places each front on the triangles of its listed
panels). That netting carries the catch pressure p = ½ ρ Cd v² (4.246) behind the front, with the consistent
nodal load of :func:`jaxnet.terms.pressure.catch_pressure` (the same law as the scene's main catch, which
FEMNET's ``pres_pris_elem3`` applies to the listed panels). Unlike the main catch, a panel catch leaves the
drag of its netting as it is, as FEMNET's stored answer with panel catches has it (its current statics drop all
netting drag from such a case: :mod:`jaxnet.io.femnet`).

The element: a triangle of a panel holding catch k takes k's front; a triangle of another panel carries
nothing. Its stiffness is the main catch's with that front held fixed
(:func:`jaxnet.closed_form.pressure.panel_catch_pressure_stiffness`).

Units: positions in m, pressure in Pa, forces in N.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet.terms.pressure import catch_pressure, off_tarps
from jaxnet.terms.term import CATCH, FORCE, ClosedForm, Term, register


def panel_catch_pressure(x, state, sign, panel):
    """(3, 3) nodal forces (N) of the panel catches' pressure on one triangle of panel ``panel``: the pressure
    of the catch its panel holds, behind that catch's front (``state``: :func:`jaxnet.model.catch.panel_catch_state`),
    or zero where the panel holds none. ``sign``: the triangle's orientation (+1 where 12 ^ 13 points out of the
    cod-end, :func:`jaxnet.terms.pressure.catch_pressure`)."""
    k = state["catch_of_panel"][panel]
    front = state["fronts"][jnp.maximum(k, 0)]
    force = catch_pressure(x, state["pressure"], front, state["axis"], sign)
    return jnp.where(k >= 0, force, 0.0)


def _active(scene, dynamic):
    c = scene.panel_catches
    if c is None or scene.netting is None or not scene.environment.current_speed > 0 or c.drag_coefficient == 0:
        return None
    return {}


def _arguments(p, env):
    # as the main catch's: a tarp takes the current's pressure on its whole surface by its own term
    return {"sign": off_tarps(p, p.outward), "panel": p.panel}


PANEL_CATCH_PRESSURE = register(Term(
    name="panel_catch_pressure", family="netting", kind=FORCE, element=panel_catch_pressure,
    arguments=_arguments, active=_active, group=CATCH, state="jaxnet.model.catch:panel_catch_state",
    closed_form=ClosedForm("jaxnet.closed_form.pressure:panel_catch_pressure_stiffness")))
