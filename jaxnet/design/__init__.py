"""Design of nets by gradients: what a gear designer changes, what is measured, and the optimisation.

- :mod:`jaxnet.design.cut`: panel cuts in the trade's terms (meshes per side, cutting rates, rounding to
  whole meshes).
- :mod:`jaxnet.design.space`: :class:`~jaxnet.design.space.DesignSpace`, the differentiable map from design
  parameters θ (cut, mesh side, twine diameter, EA, hanging ratio, sinkers, floats, cable lengths) to a scene
  of fixed topology.
- :mod:`jaxnet.design.objectives`: figures of an equilibrium (drag, volume, opening, shape, tension,
  material) and constraints, composable.
- :mod:`jaxnet.design.gradient`: an objective's value and gradient in θ at equilibrium by the host-driven
  adjoint (:mod:`jaxnet.solve.adjoint_statics`), its programs kept between processes.
- :mod:`jaxnet.design.optimize`: optax optimisation of a design, through the differentiable equilibrium
  (:mod:`jaxnet.design.gradient`; :mod:`jaxnet.solve.implicit` for an optimiser's line search).
- :mod:`jaxnet.design.reduced`: design vectors, maps from a few numbers (symmetries, tapers, a panel's size)
  to θ, which ``optimize`` optimises through.
- :mod:`jaxnet.design.report`: designs and optimisation results printed as short tables of cuts and values.
- :mod:`jaxnet.design.sweep`: sweeps of many designs on the worker processes of a Dask cluster, local or remote,
  rows written as they arrive.
- :mod:`jaxnet.design.batch`: batches of designs in one program on one process's devices (vmap, shard_map).
"""
