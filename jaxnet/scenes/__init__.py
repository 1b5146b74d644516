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


def _cage_waves(wave_height: float = 2.0, wave_period: float = 6.0, water_depth: float = 50.0, current: float = 0.2,
                end_time: float = 12.0, time_step: float = 0.01, record_every: float = 0.1, radius: float = 5.0,
                depth: float = 5.0, step: float = 1.6):
    """:func:`cage_in_waves` meshed coarsely by default (339 unknowns: the size of FEMNET's dynamic cage benchmark,
    351 unknowns); its numbers are those ``jaxnet run --dynamic --set`` may change."""
    return cage_in_waves(wave_height=wave_height, wave_period=wave_period, water_depth=water_depth, current=current,
                         end_time=end_time, time_step=time_step, record_every=record_every, radius=radius, depth=depth,
                         step=step)


#: scenes that run in time (``jaxnet run --dynamic --scene NAME``; their Case has time settings): name ->
#: (function returning the Case, one-line description)
DYNAMIC = {
    "cage_waves": (_cage_waves, "the cage in 2 m, 6 s regular waves and a 0.2 m/s current, its collar heaving; 12 s"),
}
DYNAMIC_DEFAULT = "cage_waves"
