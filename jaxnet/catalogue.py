"""The built-in scenes by name (``jaxnet run --scene NAME``): what each is and the function that makes it, named by
its module, so that the command line lists and checks them (``--help``, ``--scene``) without importing them, nor
JAX. The functions themselves are in :mod:`jaxnet.scenes`.
"""

from __future__ import annotations

import importlib
from typing import NamedTuple


class BuiltIn(NamedTuple):
    """A built-in scene: the function that makes its :class:`~jaxnet.case.Case` (``module:function``) and what it
    is at its default numbers, in a line (the command line's list; a run's own label comes from its numbers,
    :attr:`jaxnet.case.Case.label`)."""

    function: str
    description: str

    def make(self):
        """The scene's function (imported now), whose keyword arguments are the numbers ``--set`` changes."""
        module, _, name = self.function.partition(":")
        return getattr(importlib.import_module(module), name)


#: name -> the built-in static scenes
BUILT_IN = {
    "cage": BuiltIn("jaxnet.scenes.cage:fish_cage",
                    "cylindrical fish cage (floating collar, bottom, sinkers) in a 0.5 m/s current"),
    "codend": BuiltIn("jaxnet.scenes.codend:codend",
                      "trawl cod-end (quarter model) holding 0.2 m³ of catch at 1.5 m/s"),
    "hanging": BuiltIn("jaxnet.scenes.panel:hanging_panel",
                       "square panel hanging from a headline with a sinker bar, still water"),
    "framed": BuiltIn("jaxnet.scenes.panel:framed_panel",
                      "horizontal panel held along its border, sagging under a sinker"),
}
DEFAULT = "cage"

#: scenes that run in time (``jaxnet run --dynamic --scene NAME``; their Case has time settings)
DYNAMIC = {
    "cage_waves": BuiltIn("jaxnet.scenes.cage:cage_in_waves_coarse",
                          "the cage in 2 m, 6 s regular waves and a 0.2 m/s current, its collar heaving; 12 s"),
}
DYNAMIC_DEFAULT = "cage_waves"
