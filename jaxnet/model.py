"""Which physical terms a scene uses, decided from its concrete values before anything is traced.

A term is registered once in :data:`TERMS` (one line per term). For a given scene, :func:`active_terms`
keeps the terms whose parameters are present and non-zero and fixes their static options (e.g. whether
any twine has a compression stiffness), so the residual traced for that scene contains only those terms:
a weightless net compiles no weight, a net with EA_c = 0 everywhere no compressive branch. Each term's
element function is wrapped in a ``jax.named_scope`` of its name, so what was compiled can be read back
from the lowered program (the tests do).

Kinds of terms:
  * ``"energy"``: conservative, element energy (J) of the element's vertex positions; forces are its
    negative gradient, stiffness its Hessian (``jax.jacfwd`` of ``jax.grad``).
  * ``"load"``: a nodal force (N) independent of positions (weight of an immersed net, external forces):
    evaluated once per solve, no stiffness.
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import numpy as np

from jaxnet.terms import cable, gravity, tension


@dataclasses.dataclass(frozen=True)
class Term:
    """A physical term acting on one element family ("netting", "bars" or "nodes").

    element: for an energy, ``element(x, p, env, **options) -> J`` with x the (k, 3) vertex positions and
      p one row of the family; for a load, ``element(p, env, **options) -> (k, 3)`` forces in N.
    options: ``options(scene) -> dict | None``, the static choices for this scene, None if inactive.
    """

    name: str
    family: str
    kind: str
    element: Callable
    options: Callable


# -- element adapters: map a family row onto the term functions ------------------------------------


def _netting_tension(x, p, env, compression):
    return tension.netting_energy(x, p.uv, p.l0, p.ea_traction, p.ea_compression if compression else None)


def _bar_tension(x, p, env, compression):
    return cable.bar_energy(x, p.rest_length, p.ea_traction, p.ea_compression if compression else None)


def _netting_weight(p, env):
    return gravity.netting_weight(p.uv, p.l0, p.diameter, p.density, env.water_density, env.gravity, env.up)


def _bar_weight(p, env):
    return gravity.bar_weight(p.rest_length, p.diameter, p.density, env.water_density, env.gravity, env.up)


def _node_weight(p, env):
    return gravity.node_weight(p.mass, p.volume, env.water_density, env.gravity, env.up)[None, :]


def _node_force(p, env):
    return p.force[None, :]


# -- activity: which parameters make a term present ----------------------------------------------


def _any(a):
    return bool(np.any(np.asarray(a) != 0))


def _tension_options(family):
    def options(scene):
        f = getattr(scene, family)
        if f is None or not _any(f.ea_traction) and not _any(f.ea_compression):
            return None
        return {"compression": _any(f.ea_compression)}

    return options


def _weight_options(family, volume):
    def options(scene):
        f = getattr(scene, family)
        env = scene.environment
        if f is None or env.gravity == 0:
            return None
        net_density = np.asarray(f.density) - env.water_density
        if not _any(np.asarray(volume(f)) * net_density):
            return None
        return {}

    return options


def _node_weight_options(scene):
    n = scene.nodes
    if scene.environment.gravity == 0 or not _any(np.asarray(n.mass) - scene.environment.water_density * np.asarray(n.volume)):
        return None
    return {}


def _node_force_options(scene):
    return {} if _any(scene.nodes.force) else None


#: The registry: one line per physical term.
TERMS = (
    Term("netting_tension", "netting", "energy", _netting_tension, _tension_options("netting")),
    Term("bar_tension", "bars", "energy", _bar_tension, _tension_options("bars")),
    Term("netting_weight", "netting", "load", _netting_weight, _weight_options("netting", lambda f: f.diameter)),
    Term("bar_weight", "bars", "load", _bar_weight, _weight_options("bars", lambda f: f.diameter)),
    Term("node_weight", "nodes", "load", _node_weight, _node_weight_options),
    Term("node_force", "nodes", "load", _node_force, _node_force_options),
)


@dataclasses.dataclass(frozen=True)
class ActiveTerm:
    """A term with its static options for one scene (hashable: a jit static argument)."""

    term: Term
    options: tuple

    @property
    def name(self):
        return self.term.name

    def kwargs(self):
        return dict(self.options)


def active_terms(scene) -> tuple[ActiveTerm, ...]:
    """The terms this scene uses, with their static options, in registry order."""
    active = []
    for term in TERMS:
        opts = term.options(scene)
        if opts is not None:
            active.append(ActiveTerm(term, tuple(sorted(opts.items()))))
    return tuple(active)
