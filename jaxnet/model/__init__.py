"""Which physical terms a scene uses, decided from its concrete values before anything is traced.

The terms are declared once each, in their modules of :mod:`jaxnet.terms` (:mod:`jaxnet.terms.term` says
how). For a given scene, :func:`active_terms` keeps the registered terms whose parameters are present and
non-zero and fixes their static options (e.g. whether any twine has a compression stiffness), so the
residual traced for that scene contains only those terms: a weightless net compiles no weight, a net with
EA_c = 0 everywhere no compressive branch. :mod:`jaxnet.model.assemble` wraps each term's element function in a
``jax.named_scope`` of its name, so what was compiled can be read back from the lowered program (the tests
do).

Statics and dynamics. In statics the net is at rest and the water's velocity is the current's, taken at
the element's centroid. In dynamics (``active_terms(scene, dynamic=True)``) the drag terms are *moving*
(:attr:`jaxnet.terms.term.Term.moving`): they are present wherever their coefficients are, even in still
water (a net moving through still water is dragged), and each vertex takes its share of the element's drag
with the velocity of the water *relative to that vertex* (book 4.272-4.276): the current at the vertex and
at the environment's time, plus the waves' orbital velocity there (``Environment.waves``), minus the
vertex's velocity, which the dynamic solver gives the element (``velocity``, (k, 3) m/s).

The tangent's two paths. A term's stiffness is autodiff's (``jax.jacfwd`` of its element, the reference) or,
where the term declares one that covers its options, its hand-derived closed form (:mod:`jaxnet.closed_form`):
:meth:`ActiveTerm.has_closed_form` and :func:`stiffness_paths` say which.
"""

from __future__ import annotations

import dataclasses

from jaxnet.terms.term import ENERGY, FORCE, LOAD, Term, registered

#: the two ways of computing the tangent stiffness
STIFFNESS_PATHS = ("autodiff", "closed_form")


@dataclasses.dataclass(frozen=True)
class ActiveTerm:
    """A registered term with its static options for one scene (hashable: a jit static argument). Its
    methods evaluate the term on one element: ``x`` the (k, 3) vertex positions (m), ``p`` the element's row
    of its family, ``env`` the scene's environment."""

    term: Term
    options: tuple

    @property
    def name(self):
        return self.term.name

    def kwargs(self):
        """The static options as a dict."""
        return dict(self.options)

    @property
    def moving_now(self):
        """True for a drag in a time step: it takes the vertices' velocities (and its closed form Δt)."""
        return self.term.moving and bool(self.kwargs().get("moving"))

    def arguments(self, p, env):
        return self.term.arguments(p, env, **self.kwargs())

    def energy(self, x, p, env):
        """The element energy (J) of an energy term."""
        return self.term.element(x, **self.arguments(p, env))

    def load(self, p, env):
        """The (k, 3) vertex loads (N) of a load term."""
        return self.term.element(**self.arguments(p, env))

    def force(self, x, p, env, state, velocity=None):
        """The (k, 3) vertex forces (N) of a force term; ``state`` its global state (or None), ``velocity``
        the vertices' velocities (m/s) in a time step (moving terms only)."""
        extra = {"velocity": velocity} if self.moving_now else {}
        return self.term.element(x, state, **self.arguments(p, env), **extra)

    def has_closed_form(self, with_velocities=False) -> bool:
        """Whether the term's stiffness has a closed form for its options. ``with_velocities``: the caller hands
        the closed forms the vertices' velocities and the time step (the tangent of an implicit step); a moving
        drag depends on them (c_i = w(x_i) - (x_i - x_i^n)/Δt, book 4.272-4.276), so without them it keeps its
        autodiff stiffness."""
        closed = self.term.closed_form
        if closed is None or (self.moving_now and not with_velocities):
            return False
        return closed.covers is None or bool(closed.covers(self.kwargs()))

    def has_rods(self) -> bool:
        """Whether the term is, with its options, a sum of tension-only rods (:class:`jaxnet.terms.term.Rods`)."""
        rods = self.term.rods
        return rods is not None and (rods.covers is None or bool(rods.covers(self.kwargs())))

    def rods(self, x, p, env):
        """The element's rods: (length (r,) m, rest length (r,) m, axial stiffness (r,) N/m)."""
        return self.term.rods.form(x, **self.arguments(p, env))

    def stiffness(self, x, p, env, state=None, velocity=None, time_step=None):
        """The (3k, 3k) closed-form element matrix K = -dF/dx (N/m), vertex-major; for a force term ``state``
        is held fixed, and a moving drag takes ``velocity`` (m/s) and ``time_step`` (s)."""
        function = self.term.closed_form.function()
        if self.term.kind == ENERGY:
            return function(x, **self.arguments(p, env))
        extra = {"velocity": velocity, "time_step": time_step} if self.moving_now else {}
        return function(x, state, **self.arguments(p, env), **extra)


def active_terms(scene, dynamic=False) -> tuple[ActiveTerm, ...]:
    """The terms this scene uses, with their static options, in registry order; ``dynamic``: for a time
    step (the drag terms then act on the velocity relative to the water, see the module docstring)."""
    active = []
    for term in registered():
        options = term.active(scene, dynamic)
        if options is not None:
            active.append(ActiveTerm(term, tuple(sorted(options.items()))))
    return tuple(active)


def stiffness_paths(terms, stiffness="closed_form", with_velocities=False) -> dict:
    """Per active term with a stiffness (energies and forces), the path its stiffness takes: ``"closed_form"``
    or ``"autodiff"``, for a solver run with ``stiffness`` (``with_velocities``: in a time step, see
    :meth:`ActiveTerm.has_closed_form`)."""
    if stiffness not in STIFFNESS_PATHS:
        raise ValueError(f"stiffness must be one of {STIFFNESS_PATHS}, not {stiffness!r}")
    return {t.name: ("closed_form" if stiffness == "closed_form" and t.has_closed_form(with_velocities) else "autodiff")
            for t in terms if t.term.kind in (ENERGY, FORCE)}


__all__ = ["ActiveTerm", "ENERGY", "FORCE", "LOAD", "STIFFNESS_PATHS", "active_terms", "registered", "stiffness_paths"]
