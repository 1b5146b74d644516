"""Which terms have a closed-form stiffness, and the element functions that give it (one line per term).

``Newton(stiffness="closed_form")`` (and ``assemble.tangent(..., stiffness="closed_form")``) assembles,
for every active term listed in :data:`STIFFNESS` whose options it covers, the term's hand-derived
element matrix; the other terms (those the chapter gives no stiffness for: hexagonal meshes, weight and
buoyancy at the free surface, the sea bed, FEMNET's node boxes, the screen drag models) keep their
autodiff stiffness. Each term's matrix comes from exactly one path; :func:`paths` says which.

An element stiffness function has the signature of the term's element function (:class:`jaxnet.model.Term`)
and returns the (3k, 3k) element matrix K = -dF/dx (N/m), vertex-major (entry (3 i + m, 3 j + n):
coordinate m of vertex i, n of vertex j): ``(x, p, env, **options)`` for an energy (its Hessian),
``(x, p, env, state, **options)`` for a force (minus its Jacobian, the global state held fixed).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

from jaxnet.closed_form import pressure, tension


@dataclasses.dataclass(frozen=True)
class ClosedForm:
    """The closed-form stiffness of one registered term.

    stiffness: the element stiffness function (module docstring).
    covers: ``covers(options) -> bool``, False for options the closed form does not cover (those elements'
      term then keeps its autodiff stiffness); None covers every option.
    """

    stiffness: Callable
    covers: Callable | None = None


def _netting_tension(x, p, env, compression):
    return tension.netting_stiffness(x, p.uv, p.l0, p.ea_traction, p.ea_compression if compression else None)


def _bar_tension(x, p, env, compression):
    return tension.bar_stiffness(x, p.rest_length, p.ea_traction, p.ea_compression if compression else None)


def _catch_pressure(x, p, env, state):
    return pressure.catch_pressure_stiffness(x, state["pressure"], state["front"], state["axis"], p.outward)


#: term name (:data:`jaxnet.model.TERMS`) -> its closed-form stiffness
STIFFNESS = {
    "netting_tension": ClosedForm(_netting_tension),
    "bar_tension": ClosedForm(_bar_tension),
    "catch_pressure": ClosedForm(_catch_pressure),
}


def covered(active_term) -> bool:
    """True if this active term (:class:`jaxnet.model.ActiveTerm`) has a closed-form stiffness for its options."""
    entry = STIFFNESS.get(active_term.name)
    return entry is not None and (entry.covers is None or entry.covers(active_term.kwargs()))


def paths(model, stiffness="closed_form") -> dict:
    """Per active term with a stiffness (energies and forces), the path its stiffness takes:
    ``"closed_form"`` or ``"autodiff"``, for a solver run with ``stiffness``."""
    return {t.name: ("closed_form" if stiffness == "closed_form" and covered(t) else "autodiff")
            for t in model if t.term.kind in ("energy", "force")}
