"""How a physical term is declared, and the registry derived from the declarations.

Each module of :mod:`jaxnet.terms` declares its terms once, at its end: ``register(Term(...))`` with

* ``name``: how the term is named in results, programs and messages;
* ``family``: the element family it acts on (:data:`FAMILIES`: one row of the family per element);
* ``kind``: :data:`ENERGY` (conservative: an element energy in J, forces its negative gradient, stiffness
  its Hessian), :data:`LOAD` (a nodal force in N independent of the positions: evaluated once per solve,
  no stiffness) or :data:`FORCE` (a non-conservative element force in N: drag, catch pressure; stiffness
  minus its Jacobian);
* ``element``: the per-element physics function, ``element(x, **args)`` for an energy (J), ``element(**args)``
  for a load ((k, 3) N), ``element(x, state, **args)`` for a force ((k, 3) N), x the (k, 3) vertex positions
  (m) and ``state`` the term's global state (below) or None;
* ``arguments``: how one row ``p`` of the family becomes those keyword arguments, ``arguments(p, env,
  **options) -> dict`` (``env`` the scene's :class:`~jaxnet.scene.Environment`, ``options`` the term's static
  options for the scene): written once, shared by the element and its closed-form stiffness;
* ``active``: when the term is present, ``active(scene, dynamic) -> dict | None``: its static options for
  this scene (hashable values), or None when its parameters are absent or zero. Decided from the scene's
  concrete values before anything is traced, so a weightless net compiles no weight;
* ``group``: the :class:`Group` of the result's force breakdown its force is summed into (None for the
  net's internal forces, which sum to zero);
* ``closed_form``: optionally, its hand-derived stiffness (:class:`ClosedForm`), a function with the
  element's signature returning the (3k, 3k) element matrix K = -dF/dx (N/m), vertex-major;
* ``elastic``: an energy of the net's own elasticity (twines, bars, mesh opening, knots, bending), which the
  static solver's stiffness continuation scales; ``moving``: a force that depends on the element's velocity
  relative to the water (drag): in dynamics its ``options`` hold ``moving=True`` and its element and closed
  form take the vertices' velocities ``velocity`` ((k, 3) m/s; the closed form also ``time_step``, s);
  ``state``: for a force, ``state(x, scene, previous) -> pytree``, a global quantity of the positions
  x (N, 3) computed once per evaluation and handed to its elements (the catch front); ``previous`` is its
  value at nearby positions, a start for its solution, or None. Terms sharing a state function share its
  value. Like a closed form it may be named ``"module:name"``: the catch front is solved by
  :mod:`jaxnet.model.catch`, which is built on the catch pressure's element functions;
* ``rods``: for an elastic energy that is a sum of tension-only rods (:class:`Rods`), their lengths, rest lengths
  and axial stiffnesses: the tension form the primal-dual static solver gives unknowns of their own
  (:mod:`jaxnet.solve.interior`).

The registry (:func:`registered`) holds the terms module by module in the order of the package's table of
contents (:data:`jaxnet.terms.CONTENTS`), each module's terms in the order it declares them: the order in
which a family's terms are summed. The closed-form registry, the result groups and the lists of
hydrodynamic and drag terms are all derived from it, so adding a term is adding its module (and, for a
closed form, its module of :mod:`jaxnet.closed_form`); a term declared elsewhere (a user's, a test's) is
registered the same way and :func:`unregister` removes it.
"""

from __future__ import annotations

import dataclasses
import functools
import importlib
import inspect
import itertools
import pkgutil
import threading
from typing import Callable

import numpy as np

#: element families, as fields of :class:`jaxnet.scene.Scene` ("nodes": every node is its own element)
FAMILIES = ("netting", "bars", "hexagonal", "hinges", "cable_joints", "nodes")
#: kinds of terms (module docstring)
ENERGY, LOAD, FORCE = "energy", "load", "force"
KINDS = (ENERGY, LOAD, FORCE)


@dataclasses.dataclass(frozen=True)
class Group:
    """A group of a result's force breakdown: the total force (N, over all nodes) of the terms declaring it.

    name: its key in ``result.json`` (with its unit). hydrodynamic: the water's force on the net (drag,
    catch pressure): what the towing resistance of a gear and the current load of a cage sum.
    """

    name: str
    hydrodynamic: bool = False


#: the result groups of jaxnet's own terms
DRAG_NETTING = Group("drag_netting_N", hydrodynamic=True)
DRAG_CABLES = Group("drag_cables_N", hydrodynamic=True)
DRAG_NODES = Group("drag_nodes_N", hydrodynamic=True)
CATCH = Group("catch_N", hydrodynamic=True)
WEIGHT = Group("weight_and_buoyancy_N")
EXTERNAL = Group("external_N")
BOTTOM = Group("bottom_N")


def resolve(function: Callable | str) -> Callable:
    """``function`` itself, or the function a ``"module:name"`` string names (imported on first use)."""
    if callable(function):
        return function
    module, _, name = function.partition(":")
    return getattr(importlib.import_module(module), name)


@dataclasses.dataclass(frozen=True)
class ClosedForm:
    """A term's hand-derived stiffness.

    stiffness: the function (module docstring), or ``"module:name"`` naming it: the terms' modules do not
      import :mod:`jaxnet.closed_form`, whose functions are an independent derivation (and use theirs).
    covers: ``covers(options) -> bool``, False for static options the closed form does not cover (the term
      then keeps its autodiff stiffness); None: every option.
    """

    stiffness: Callable | str
    covers: Callable | None = None

    def function(self) -> Callable:
        """The stiffness function (imported on first use when named by a string)."""
        return resolve(self.stiffness)


@dataclasses.dataclass(frozen=True)
class Rods:
    """A term's energy written as tension-only rods: E = sum_r (k_r / 2) max(0, L_r - l0_r)², each rod r of an
    element a straight twine (or the n parallel twines a twine vector stands for) of length L_r(x).

    form: ``form(x, **args) -> (length (r,), rest_length (r,), stiffness (r,))``, the element's signature: each
      rod's length L_r (m), rest length l0_r (m) and axial stiffness k_r = n_r EA_r / l0_r (N/m, n_r its number of
      twines), so that its tension is k_r max(0, L_r - l0_r) (N).
    covers: ``covers(options) -> bool``: False for static options where the energy is not of that form (a
      compression stiffness); None: every option.

    The primal-dual solver (:mod:`jaxnet.solve.interior`) gives each rod its tension and its gap as unknowns
    instead of differentiating the energy's kink; the test of the terms checks that the form sums to the
    element's energy."""

    form: Callable
    covers: Callable | None = None


@dataclasses.dataclass(frozen=True)
class Term:
    """One physical term, declared once (module docstring)."""

    name: str
    family: str
    kind: str
    element: Callable
    arguments: Callable
    active: Callable
    group: Group | None = None
    closed_form: ClosedForm | None = None
    elastic: bool = False
    moving: bool = False
    state: Callable | str | None = None
    rods: Rods | None = None

    def __post_init__(self):
        if self.family not in FAMILIES:
            raise ValueError(f"term {self.name!r}: family must be one of {FAMILIES}, got {self.family!r}")
        if self.kind not in KINDS:
            raise ValueError(f"term {self.name!r}: kind must be one of {KINDS}, got {self.kind!r}")
        if self.state is not None and self.kind != FORCE:
            raise ValueError(f"term {self.name!r}: only a force term has a state")
        if self.closed_form is not None and self.kind == LOAD:
            raise ValueError(f"term {self.name!r}: a load has no stiffness, so no closed form")
        if self.rods is not None and self.kind != ENERGY:
            raise ValueError(f"term {self.name!r}: only an energy is a sum of rods")


_REGISTRY: dict[str, tuple[str, int, Term]] = {}  # name -> (declaring module, registration count, term)
_LOCK = threading.Lock()
_COUNT = itertools.count()


def register(term: Term) -> Term:
    """Add ``term`` to the registry and return it. A term of the same name declared again by the same module
    replaces it (a module imported again); by another module, it is an error."""
    declarer = inspect.currentframe().f_back.f_globals.get("__name__", "?")
    with _LOCK:
        if term.name in _REGISTRY and _REGISTRY[term.name][0] != declarer:
            raise ValueError(f"a term named {term.name!r} is already registered (by {_REGISTRY[term.name][0]})")
        _REGISTRY[term.name] = (declarer, next(_COUNT), term)
    return term


def unregister(name: str) -> None:
    """Remove the term ``name`` from the registry (a term a test or a study declared for a while)."""
    with _LOCK:
        _REGISTRY.pop(name, None)


@functools.cache
def _own_modules() -> tuple[str, ...]:
    """The modules of :mod:`jaxnet.terms` in registry order (:data:`jaxnet.terms.CONTENTS`, then the others by
    name), each imported: importing a module registers its terms."""
    package = importlib.import_module("jaxnet.terms")
    listed = tuple(package.CONTENTS)
    others = sorted(m.name for m in pkgutil.iter_modules(package.__path__) if m.name not in listed and m.name != "term")
    names = tuple(f"jaxnet.terms.{name}" for name in listed + tuple(others))
    for name in names:
        importlib.import_module(name)
    return names


def registered() -> tuple[Term, ...]:
    """Every registered term, in registry order: jaxnet's own (always there) module by module in the order of
    :data:`jaxnet.terms.CONTENTS`, each module's in the order it declares them; then the others (a user's, a
    test's) in the order registered. The order does not depend on which modules happened to be imported first."""
    modules = {name: k for k, name in enumerate(_own_modules())}
    with _LOCK:
        entries = list(_REGISTRY.values())

    def rank(entry):
        declarer, count, _ = entry
        return (modules[declarer], count) if declarer in modules else (len(modules), count)

    return tuple(term for _, _, term in sorted(entries, key=rank))


def groups(select=None) -> dict[str, tuple[str, ...]]:
    """Each result group of the registered terms, by name -> the names of its terms, in registry order.
    ``select(group, term) -> bool``: only the terms it accepts (and the groups left with any)."""
    out: dict[str, tuple[str, ...]] = {}
    for term in registered():
        if term.group is not None and (select is None or select(term.group, term)):
            out[term.group.name] = out.get(term.group.name, ()) + (term.name,)
    return out


def drag_groups() -> dict[str, tuple[str, ...]]:
    """The groups of the drag terms (the water's forces on a moving net's relative velocity, not the sea bed's
    friction): what a dynamic run records."""
    return groups(lambda group, term: term.moving and group.hydrodynamic)


def hydrodynamic_terms() -> tuple[str, ...]:
    """The names of the terms through which the water acts on the net (drag, the catch's pressure): their sum is
    the towing resistance of a trawl, the current load of a cage."""
    return tuple(name for names in groups(lambda group, term: group.hydrodynamic).values() for name in names)


# -- helpers of the terms' activity rules -----------------------------------------------------------


def any_nonzero(values) -> bool:
    """Whether any of ``values`` (an array or None) is non-zero: a parameter that makes its term present."""
    return values is not None and bool(np.any(np.asarray(values) != 0))


def has_current(scene) -> bool:
    return scene.environment.current_speed > 0


def flowing(scene, dynamic) -> bool:
    """Does water move relative to the net? In statics where there is a current; in dynamics always (the net
    moves, the current may start later, the waves move the water)."""
    return dynamic or has_current(scene)


def moving_options(scene, dynamic) -> dict:
    """Static options of a moving (drag) term: per-vertex relative velocities in dynamics, and waves."""
    return {"moving": True, "waves": scene.environment.waves is not None} if dynamic else {}
