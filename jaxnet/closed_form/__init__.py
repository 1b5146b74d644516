"""Closed-form (hand-derived) tangent stiffness: the book's derivations, term by term, corrected.

The other tangent is autodiff (:mod:`jaxnet.assemble`: ``jax.jacfwd`` of the element energies and forces
of :mod:`jaxnet.terms`), the reference. This package is the solvers' default path (``Newton(stiffness=
"closed_form")``, cheaper: :class:`jaxnet.solve.statics.Newton`): for every term where the chapter
derives a stiffness, the same matrix K = -dF/dx (4.46) written out by hand, in the book's structure
(twine-vector derivatives, then the chain rule to the vertices) but with its errata corrected
(``docs/errata.md``). No module here calls JAX's automatic differentiation: the two paths are
independent, so that comparing them tests both.

One module per term, named as in :mod:`jaxnet.terms`; :mod:`jaxnet.closed_form.chain` holds the chain
rule from twine vectors to vertices they all share; :mod:`jaxnet.closed_form.registry` maps the
registered terms of :data:`jaxnet.model.TERMS` onto these functions, for
``Newton(stiffness="closed_form")``.
"""
