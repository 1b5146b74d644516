"""Built-in scenes: nets a user recognises, ready to solve (``jaxnet run --scene NAME``), each a
:class:`~jaxnet.case.Case` made by a function of its main dimensions. :mod:`jaxnet.catalogue` lists them by name
for the command line.
"""

from jaxnet.catalogue import BUILT_IN, DEFAULT, DYNAMIC, DYNAMIC_DEFAULT, BuiltIn
from jaxnet.scenes.cage import cage_in_waves, fish_cage
from jaxnet.scenes.codend import codend
from jaxnet.scenes.panel import framed_panel, hanging_panel

__all__ = ["BUILT_IN", "DEFAULT", "DYNAMIC", "DYNAMIC_DEFAULT", "BuiltIn", "cage_in_waves", "fish_cage", "codend",
           "framed_panel", "hanging_panel"]
