"""Built-in scenes: nets a user recognises, ready to solve (``jaxnet run --scene NAME``), each a
:class:`~jaxnet.case.Case` made by a function of its main dimensions."""

from jaxnet.scenes.cage import cage_in_waves, fish_cage
from jaxnet.scenes.codend import codend
from jaxnet.scenes.panel import framed_panel, hanging_panel

#: name -> (function returning the Case, one-line description)
BUILT_IN = {
    "cage": (fish_cage, "cylindrical fish cage (floating collar, bottom, sinkers) in a 0.5 m/s current"),
    "codend": (codend, "trawl cod-end (quarter model) holding 0.2 m³ of catch at 1.5 m/s"),
    "hanging": (hanging_panel, "square panel hanging from a top rope with a sinker bar, still water"),
    "framed": (framed_panel, "horizontal panel held along its border, sagging under a sinker"),
}
DEFAULT = "cage"


def _cage_waves():
    # meshed coarsely (339 unknowns): the size of FEMNET's dynamic cage benchmark (351 unknowns)
    return cage_in_waves(step=1.6)


#: scenes that run in time (``jaxnet run --dynamic --scene NAME``; their Case has time settings): name ->
#: (function returning the Case, one-line description)
DYNAMIC = {
    "cage_waves": (_cage_waves, "the cage in 2 m, 6 s regular waves and a 0.2 m/s current, its collar heaving; 12 s"),
}
DYNAMIC_DEFAULT = "cage_waves"
