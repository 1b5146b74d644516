"""Closed-form (hand-derived) tangent stiffness: the book's derivations, term by term, corrected.

The other tangent is autodiff (:mod:`jaxnet.model.assemble`: ``jax.jacfwd`` of the element energies and forces
of :mod:`jaxnet.terms`), the reference. This package is the solvers' default path (``Newton(stiffness=
"closed_form")``, cheaper: :class:`jaxnet.solve.options.Newton`): for every term where the chapter
derives a stiffness, the same matrix K = -dF/dx (4.46) written out by hand, in the book's structure
(twine-vector derivatives, then the chain rule to the vertices) but with its errata corrected
(``docs/errata.md``). No module here calls JAX's automatic differentiation: the two paths are
independent, so that comparing them tests both.

One module per term, named as in :mod:`jaxnet.terms`; :mod:`jaxnet.closed_form.chain` holds the chain
rule from twine vectors to vertices they all share. A term names its closed form in its declaration
(:class:`jaxnet.terms.term.ClosedForm`): a function here with the term's element signature, returning its
element matrix; :meth:`jaxnet.model.ActiveTerm.has_closed_form` says where it applies.
"""
