"""Built-in scenes: nets a user recognises, ready to solve (``jaxnet run --scene NAME``)."""

from jaxnet.scenes.cage import cage_in_waves, fish_cage
from jaxnet.scenes.codend import codend
from jaxnet.scenes.panel import framed_panel, hanging_panel

#: name -> (function returning a Net, one-line description)
BUILT_IN = {
    "cage": (fish_cage, "cylindrical fish cage (floating collar, bottom, sinkers) in a 0.5 m/s current"),
    "codend": (codend, "trawl cod-end (quarter model) holding 0.2 m³ of catch at 1.5 m/s"),
    "hanging": (hanging_panel, "square panel hanging from a top rope with a sinker bar, still water"),
    "framed": (framed_panel, "horizontal panel held along its border, sagging under a sinker"),
}
DEFAULT = "cage"


def _cage_waves():
    # meshed coarsely (339 unknowns): the size of FEMNET's dynamic cage benchmark (351 unknowns)
    scene, loading = cage_in_waves(step=1.6)
    return scene, loading, {"time_step": 0.01, "end_time": 12.0, "record_every": 0.1}


#: dynamic scenes (``jaxnet run --dynamic --scene NAME``): name -> (function returning (scene, loading, time
#: settings), one-line description)
DYNAMIC = {
    "cage_waves": (_cage_waves, "the cage in 2 m, 6 s regular waves and a 0.2 m/s current, its collar heaving; 12 s"),
}
DYNAMIC_DEFAULT = "cage_waves"
