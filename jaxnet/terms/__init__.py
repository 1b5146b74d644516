"""The physical terms of the netting model (book chapter 4), one module per term or per kind of term.

Each module holds the term's physics (pure functions of one element's vertex positions) and, at its end, the
term's declaration (:mod:`jaxnet.terms.term` says what a declaration holds). The table of contents:

  tension     twine tension of diamond-mesh netting (4.30-4.45)
  cable       tension of cable bars
  gravity     weight and buoyancy of fully immersed netting, bars and node bodies (4.277)
  surface     weight and buoyancy near a free surface
  applied     forces applied to nodes
  hexagonal   hexagonal-mesh netting: tension (4.76-4.113) and weight
  opening     mesh opening stiffness (4.211-4.219)
  knot        knot contact (4.278-4.280)
  bending     twine bending across hinges (4.220-4.245)
  cable_bending  bending of cables at their joints and of welded cables (FEMNET's EI_flexion_cable)
  drag        hydrodynamic drag of netting, bars and node bodies (4.114-4.135; moving nets 4.272-4.276)
  screen      screen models of netting drag (used by ``drag``)
  bottom      sea-bed contact and friction
  pressure    the catch's pressure behind its front (4.246-4.264)
  panel_catch catches held by chosen panels, each behind its own front (FEMNET's catch2_volume)
  gravity_catch  the weight of a catch out of the water: hydrostatic pressure below its level (FEMNET)
  tarp        the current's pressure on an impermeable panel, in place of its twines' drag (FEMNET)
  inertia     inertia of a moving net (4.265-4.271; used by the dynamic solver)

:data:`CONTENTS` is that order: the registry's, in which the terms of a family are summed (floating-point
sums depend on their order in the last bits, so an existing term keeps its place). A new module needs no
entry: modules not listed come after, by name.
"""

#: the modules of the package in registry order (module docstring)
CONTENTS = ("tension", "cable", "gravity", "surface", "applied", "hexagonal", "opening", "knot", "bending", "drag",
            "screen", "bottom", "pressure", "inertia", "cable_bending", "gravity_catch", "tarp", "panel_catch")
