"""Built-in scenes: nets a user recognises, ready to solve (``jaxnet run --scene NAME``)."""

from jaxnet.scenes.cage import fish_cage
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
