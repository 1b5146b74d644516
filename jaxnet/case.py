"""A case: what to solve, with how to solve it, read from any description.

Every way of describing a net gives a :class:`Case`: the built-in scenes (:mod:`jaxnet.scenes`), scene
files (:func:`jaxnet.io.scene_file.read`), FEMNET's ``.don`` cases and ``.mdg`` meshes
(:func:`jaxnet.io.femnet.read_don`, :func:`jaxnet.io.femnet.read_mdg`). It holds

* ``scene``: the :class:`~jaxnet.scene.Scene` (built and validated);
* ``solver``: the static solve's options (:class:`~jaxnet.solve.options.Newton`: the description's own, e.g.
  FEMNET's threshold, iterations and displacement limit, else the defaults);
* ``time``: for a case that runs in time, its :class:`TimeSettings` (end, records, the time stepping's
  options and the loading in time), else None;
* ``net``: the :class:`~jaxnet.net.Net` it was built from, when it was (its ``layout`` maps the description to
  the scene: design spaces use it); None for a scene read whole (FEMNET's own mesh);
* ``label``: one line saying what it is; ``info``: what the reader decided, for the record (FEMNET's symmetry
  planes, links, sewn sides, ...; empty for the others).

A case is plain data (frozen): :meth:`with_solver` gives one with other solver options. Its ``net`` is the
builder's own mutable object: changing it does not change ``scene``; build it again for a new scene.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.water.forcing import Loading
from jaxnet.scene import Scene, SceneError
from jaxnet.solve.options import Implicit, Newton


@dataclasses.dataclass(frozen=True)
class TimeSettings:
    """How a case runs in time (:func:`jaxnet.solve.dynamics.simulate`).

    end_time: the time to reach (s), None when the description gives none (a caller must then say).
    record_every: the interval between records (s); None: every step.
    solver: the implicit time stepping's options (:class:`~jaxnet.solve.options.Implicit`: Δt, and each
      step's Newton).
    loading: what changes with time besides the net (:class:`~jaxnet.water.forcing.Loading`: a current's history,
      prescribed motions).
    """

    end_time: float | None = None
    record_every: float | None = None
    solver: Implicit = dataclasses.field(default_factory=Implicit)
    loading: Loading = dataclasses.field(default_factory=Loading)

    def __post_init__(self):
        for name in ("end_time", "record_every"):
            value = getattr(self, name)
            if value is not None and not (np.isfinite(value) and value > 0):
                raise SceneError(f"time settings: {name} must be finite and > 0 (s), got {value!r}")


@dataclasses.dataclass(frozen=True)
class Case:
    """What to solve (module docstring)."""

    scene: Scene
    solver: Newton = dataclasses.field(default_factory=Newton)
    time: TimeSettings | None = None
    net: object | None = None
    label: str = ""
    info: dict = dataclasses.field(default_factory=dict)

    def __post_init__(self):
        if not isinstance(self.scene, Scene):
            raise TypeError(f"Case: scene must be a jaxnet.scene.Scene, got {type(self.scene).__name__}")
        if not isinstance(self.solver, Newton):
            raise TypeError(f"Case: solver must be jaxnet.solve.options.Newton, got {type(self.solver).__name__}")

    def with_solver(self, **options) -> Case:
        """The case with its static solver's options changed (``Newton`` fields by keyword)."""
        return dataclasses.replace(self, solver=dataclasses.replace(self.solver, **options))


def from_net(net, solver: Newton | None = None, time: TimeSettings | None = None, label: str = "",
             info: dict | None = None) -> Case:
    """The case of a :class:`~jaxnet.net.Net` description: built here (meshed, joined, validated)."""
    return Case(scene=net.build(), solver=solver or Newton(), time=time, net=net, label=label, info=dict(info or {}))
