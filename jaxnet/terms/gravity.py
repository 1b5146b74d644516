"""Weight and buoyancy (book eq. 4.277) of netting (diamond and hexagonal), cable bars and lumped node masses.

Immersed weight acts along -``up`` (the unit vertical, z by default). For one netting triangle it is
(4.277), with |d| the number of U plus V twine vectors of the element:

    W = |d| (pi D² / 4) l0 (rho_netting - rho_water) g        (N),

the twine length taken as the unstretched l0 as in the book; for a hexagonal triangle, |d| twines of each
family l, m, n (text after 4.82), l0 their summed lengths. W is split one third per vertex; a bar's
weight (pi D²/4) L0 (rho_bar - rho_water) g is split one half per end; a node of mass m (kg) and
displaced volume Vol (m³) weighs (m - rho_water Vol) g. A negative weight is buoyancy (floats).

These loads do not depend on the positions of a fully immersed net, so they enter the residual as a
constant vector and contribute nothing to the tangent stiffness (the book notes the exception of a net
crossing the free surface, which is a separate term: :mod:`jaxnet.terms.surface`).
"""

from __future__ import annotations

import jax.numpy as jnp

import numpy as np

from jaxnet import geometry
from jaxnet.scene import feels_surface
from jaxnet.terms.term import LOAD, WEIGHT, Term, any_nonzero, register


def netting_weight(uv, l0, diameter, density, water_density, g, up):
    """Per-vertex immersed weight (3, 3) in N of one triangle: one third of eq. 4.277 on each vertex."""
    d = geometry.twine_determinant(uv)
    w = geometry.twine_volume(jnp.abs(d), l0, diameter) * (density - water_density) * g
    return jnp.broadcast_to(-(w / 3.0) * up, (3, 3))


def bar_weight(rest_length, diameter, density, water_density, g, up):
    """Per-end immersed weight (2, 3) in N of one cable bar, half on each end."""
    w = geometry.twine_volume(1.0, rest_length, diameter) * (density - water_density) * g
    return jnp.broadcast_to(-(w / 2.0) * up, (2, 3))


def hexagonal_weight(uv, l0, diameter, density, water_density, g, up):
    """Per-vertex immersed weight (3, 3) in N of one hexagonal-mesh triangle (l0: the (3,) twine lengths of
    the families l, m, n), one third on each vertex."""
    d = geometry.twine_determinant(uv)
    w = geometry.twine_volume(jnp.abs(d), jnp.sum(l0), diameter) * (density - water_density) * g
    return jnp.broadcast_to(-(w / 3.0) * up, (3, 3))


def node_weight(mass, volume, water_density, g, up):
    """Immersed weight (3,) in N of a lumped node mass (kg) displacing ``volume`` (m³)."""
    return -((mass - water_density * volume) * g) * up


# -- the terms -------------------------------------------------------------------------------------


def weight_activity(family, at_surface):
    """The activity rule of a family's weight and buoyancy: present where gravity and the net density of some
    element are not zero. ``at_surface``: False for the constant load of a fully immersed net (no free
    surface, or one the family does not feel: ``Environment.floating``), True for the energy of the heights
    near a free surface (:mod:`jaxnet.terms.surface`), None for the constant load whatever the surface."""

    def active(scene, dynamic):
        f = getattr(scene, family)
        env = scene.environment
        if f is None or env.gravity == 0 or (at_surface is not None and feels_surface(scene, family) != at_surface):
            return None
        net_density = np.asarray(f.density) - env.water_density
        if at_surface:  # above the surface even a neutrally buoyant net weighs
            net_density = np.asarray(f.density) + np.abs(net_density)
        if not any_nonzero(np.asarray(f.diameter) * net_density):
            return None
        return {}

    return active


def netting_arguments(p, env):
    """The arguments of :func:`netting_weight` (and :func:`hexagonal_weight`) for a netting row ``p``."""
    return {"uv": p.uv, "l0": p.l0, "diameter": p.diameter, "density": p.density, "water_density": env.water_density,
            "g": env.gravity, "up": env.up}


def _bar_arguments(p, env):
    return {"rest_length": p.rest_length, "diameter": p.diameter, "density": p.density,
            "water_density": env.water_density, "g": env.gravity, "up": env.up}


def _node_arguments(p, env):
    return {"mass": p.mass, "volume": p.volume, "water_density": env.water_density, "g": env.gravity, "up": env.up}


def _node_weight_activity(scene, dynamic):
    n = scene.nodes
    if scene.environment.gravity == 0 or feels_surface(scene, "nodes"):
        return None
    if not any_nonzero(np.asarray(n.mass) - scene.environment.water_density * np.asarray(n.volume)):
        return None
    return {}


def _node_weight(mass, volume, water_density, g, up):
    return node_weight(mass, volume, water_density, g, up)[None, :]


NETTING_WEIGHT = register(Term(
    name="netting_weight", family="netting", kind=LOAD, element=netting_weight, arguments=netting_arguments,
    active=weight_activity("netting", at_surface=False), group=WEIGHT))
BAR_WEIGHT = register(Term(
    name="bar_weight", family="bars", kind=LOAD, element=bar_weight, arguments=_bar_arguments,
    active=weight_activity("bars", at_surface=False), group=WEIGHT))
NODE_WEIGHT = register(Term(
    name="node_weight", family="nodes", kind=LOAD, element=_node_weight, arguments=_node_arguments,
    active=_node_weight_activity, group=WEIGHT))
