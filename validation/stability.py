"""Stability suite: the solvers on stiff and extreme cases, each from a flat and from a perturbed start.

Why. A net solver is trusted when it either converges or says why it stopped, whatever the net: twines
from 10 N to 10¹⁰ N of stiffness, twines free to go slack, currents from still water to 5 m/s, meshes drawn
nearly closed or fully open, sliver triangles, knots in contact, a cod-end from empty to full, time steps
from 10 µs to 10 s, nets of 10⁵ nodes. This section runs a catalogue of such cases (:func:`catalogue`) and
reports, per run, whether it converged, in how many Newton iterations, why it stopped, its worst residual
and where, its wall time, and whether anything non-finite appeared (which must never happen).

Each case runs twice: from its *flat* start (the stress-free drawing of the net, as FEMNET's cases start)
and from a *perturbed* one: every free coordinate of the flat start displaced by a normally distributed
random amount of standard deviation :data:`PERTURBATION` times the elements' size at the start (the
median of their shortest sides; seeded, :data:`SEED`): a crumpled, over-stretched start, triangles turned
inside out, that the flat one never is.

A case's *expected* outcome is "converged" unless it genuinely has no equilibrium or is refused as input;
then the named stop is the right answer and the case says which (its note says why). Every statics run
uses ``jaxnet.solve_static`` with ``throw=False`` (its ``Equilibrium.reason``), every dynamics run
``jaxnet.solve.dynamics.simulate`` (its ``DynamicsError`` message when a step fails below the smallest
step); a scene refused by validation records its ``SceneError``.

The catalogue is a list of :class:`CatalogueCase`; ``case.build(size)`` returns the :class:`Problem` at a size:
``"test"`` (the unit tests: seconds), ``"quick"`` (``--quick``: nets of about 10⁴ nodes at most) or
``"full"`` (10⁵ nodes). :func:`run_case` runs one case from one start and returns its record (a dict);
``tests/validation/test_stability.py`` runs a subset of the catalogue at the test size.
"""

from __future__ import annotations

import dataclasses
import math
import pathlib
import time
from typing import Callable

import numpy as np

TITLE = "Stability suite: stiff and extreme cases"

#: the perturbed start: each free coordinate displaced by N(0, σ²), σ = PERTURBATION × element size
PERTURBATION = 0.25
#: seed of the perturbed starts
SEED = 8
#: the Newton iterations every statics run may take (the library's default is 500): enough to tell a slow
#: convergence (nets with slack or wrinkled regions converge linearly) from none
MAX_ITERATIONS = 2000
#: the starts each case runs from
STARTS = ("flat", "perturbed")
#: where FEMNET's worked cases are kept
FEMNET_DATA = pathlib.Path(__file__).resolve().parent.parent / "tests" / "data" / "femnet"
#: the named outcome of a run that reaches its equilibrium (statics) or its end time (dynamics)
CONVERGED = "converged"
DONE = "reached the end time"
#: the prefix of the recorded reason of a scene refused by validation
REFUSED = "SceneError"


# -- the catalogue ------------------------------------------------------------------------------------------


@dataclasses.dataclass(frozen=True)
class Dynamic:
    """A dynamics run: ``simulate(scene, end_time, solver, loading)``, one record at the end."""

    solver: object  # jaxnet.solve.dynamics.Implicit
    end_time: float
    loading: object | None = None  # jaxnet.solve.dynamics.Loading


@dataclasses.dataclass(frozen=True)
class Problem:
    """What one case solves: a scene, the static Newton options (None: the defaults), or a dynamics run."""

    scene: object
    newton: object | None = None
    dynamic: Dynamic | None = None


@dataclasses.dataclass(frozen=True)
class CatalogueCase:
    """One case of the catalogue.

    name: unique identifier. family: the issue's family it covers (:data:`FAMILIES`). build: size ->
    :class:`Problem` (sizes ``"test"``, ``"quick"``, ``"full"``). expect: the outcomes accepted (a reason
    is accepted when it starts with one of them). note: what the case is, and why its outcome is right.
    full_only: run in the full study only.
    """

    name: str
    family: str
    build: Callable[[str], Problem]
    note: str
    expect: tuple = (CONVERGED,)
    full_only: bool = False


def _size(size, test, quick, full):
    return {"test": test, "quick": quick, "full": full}[size]


def _drawn(scene, stretch):
    """The scene with its start positions scaled per axis by ``stretch`` (3,) about the origin: the same
    netting drawn with another cut aspect (every start position an affine image of the twine coordinates
    stays one)."""
    import equinox as eqx

    position = np.asarray(scene.nodes.position) * np.asarray(stretch, dtype=float)
    return eqx.tree_at(lambda s: s.nodes.position, scene, position)


def _twine(ea=2000.0, ea_compression=0.0, l0=0.025, **more):
    from jaxnet.net import Twine

    return Twine(l0=l0, ea=ea, diameter=1.5e-3, ea_compression=ea_compression, **more)


def _framed(size, twine=None, sinker_kg=5.0, opening=math.pi / 4):
    """:func:`jaxnet.scenes.framed_panel` (held along its border, sagging under its weight and a sinker),
    drawn with meshes of half opening angle ``opening`` (rad; π/4 square): x across the meshes, y along."""
    from jaxnet.scenes import framed_panel

    meshes = _size(size, 10, 40, 100)
    scene = framed_panel(meshes=meshes, step=_size(size, 0.1, 0.07, 0.05), twine=twine or _twine(),
                         sinker_kg=sinker_kg).scene
    scale = math.sqrt(2.0)
    return _drawn(scene, (scale * math.sin(opening), scale * math.cos(opening), 1.0))


def _hanging(size, twine=None, current=0.0, direction=(0.0, 1.0, 0.0), sinker_kg_per_m=1.0, meshes=None, step=None):
    """:func:`jaxnet.scenes.hanging_panel` (a curtain in the x-z plane from a headline, a sinker bar along its
    bottom) in a current of ``current`` m/s along ``direction`` (default normal to the curtain)."""
    from jaxnet.scene import Environment
    from jaxnet.scenes import hanging_panel

    meshes = meshes or _size(size, 10, 20, 40)
    step = step or _size(size, 0.1, 0.1, 0.05)
    kw = {} if twine is None else {"twine": twine}
    net = hanging_panel(meshes=meshes, step=step, sinker_kg_per_m=sinker_kg_per_m, **kw).net
    if current:
        net.environment = Environment(current_speed=current, current_direction=np.asarray(direction, dtype=float))
    return net.build()


def _static(build):
    return lambda size: Problem(build(size))


def _ea_cases():
    cases = []
    for ea in (1e1, 1e2, 1e4, 1e6, 1e8, 1e10):
        cases.append(CatalogueCase(
            f"framed EA {ea:.0e} N", "EA", _static(lambda size, ea=ea: _framed(size, _twine(ea=ea))),
            f"the framed panel (slack twines, EA_c = 0) under its weight and a 5 kg sinker, EA = {ea:g} N"))
    for ea in (1e1, 1e10):
        cases.append(CatalogueCase(
            f"curtain EA {ea:.0e} N", "EA",
            _static(lambda size, ea=ea: _hanging(size, _twine(ea=ea, ea_compression=ea))),
            f"the hanging curtain, twines EA = EA_c = {ea:g} N (headline 5e4 N, sinker bar 1e5 N)"))
    return cases


def _slack_cases():
    def loose_frame(size, load=True):
        # the panel's border drawn at 70 % of its width: every twine starts slack
        twine = _twine() if load else _twine(density=1025.0)  # neutrally buoyant: no load at all
        scene = _framed(size, twine, sinker_kg=5.0 if load else 0.0)
        return _drawn(scene, (0.7, 0.7, 1.0))

    def slack_everything(size):
        # the slack curtain, its sinker bar also unable to resist compression
        import equinox as eqx

        scene = _hanging(size, _twine())
        return eqx.tree_at(lambda s: s.bars.ea_compression, scene, np.zeros_like(scene.bars.ea_compression))

    return [
        CatalogueCase("loose frame", "slack", _static(loose_frame),
             "the framed panel on a frame 70 % of its size: every twine slack at the start; weight and sinker "
             "pull it down until the twines carry them"),
        CatalogueCase("loose frame, no load", "slack", _static(lambda size: loose_frame(size, load=False)),
             "the same, neutrally buoyant and without sinker: every twine stays slack; the equilibrium is the "
             "whole set of slack shapes (the flat start is one, the perturbed start must find one)"),
        CatalogueCase("slack curtain", "slack", _static(lambda size: _hanging(size, _twine())),
             "the hanging curtain with twines of EA_c = 0: its free sides gather into slack regions"),
        CatalogueCase("slack curtain and sinker bar", "slack", _static(slack_everything),
             "the same with a sinker bar of EA_c = 0: nothing in the net resists compression"),
    ]


def _current_cases():
    u_twine = (1.0 / math.sqrt(2.0), 0.0, 1.0 / math.sqrt(2.0))  # the curtain's U twines (U = u + v)
    cases = [CatalogueCase("still water", "current", _static(lambda size: _hanging(size)),
                  "the hanging curtain, no current: the reference of the family")]
    for speed in (0.01, 0.1, 0.5, 1.0, 2.0, 5.0):
        cases.append(CatalogueCase(f"current {speed:g} m/s normal", "current",
                          _static(lambda size, s=speed: _hanging(size, current=s)),
                          f"the hanging curtain in a {speed:g} m/s current normal to it"))
    for speed in (0.01, 1.0, 5.0):
        cases.append(CatalogueCase(f"current {speed:g} m/s along a twine", "current",
                          _static(lambda size, s=speed: _hanging(size, current=s, direction=u_twine)),
                          f"the curtain in a {speed:g} m/s current along its U twines (in its plane, 45° up)"))
    cases.append(CatalogueCase("current 1 m/s along the headline", "current",
                      _static(lambda size: _hanging(size, current=1.0, direction=(1.0, 0.0, 0.0))),
                      "the curtain in a 1 m/s current in its plane, along the headline"))
    return cases


def _opening_cases():
    H = 0.01  # N·m/rad: a twine's opening moment H Δα / l0 ~ 0.3 N, the order of the sinker's tension
    cases = []
    for label, angle in (("nearly closed", 0.05), ("square", math.pi / 4), ("fully open", 1.5)):
        cases.append(CatalogueCase(
            f"cut {label}", "opening",
            _static(lambda size, a=angle: _framed(size, _twine(opening_stiffness=H), opening=a)),
            f"the framed panel cut with meshes of half angle {angle:.3g} rad, opening stiffness {H} N·m/rad, "
            f"rest angle π/4"))
    for label, rest in (("nearly closed", 0.05), ("fully open", math.pi / 2)):
        cases.append(CatalogueCase(
            f"rest angle {label}", "opening",
            _static(lambda size, r=rest: _framed(size, _twine(opening_stiffness=H, rest_angle=r))),
            f"the square-cut framed panel whose meshes rest at half angle {rest:.3g} rad ({H} N·m/rad)"))
    cases.append(CatalogueCase(
        "curtain with opening stiffness", "opening",
        _static(lambda size: _hanging(size, _twine(opening_stiffness=H))),
        f"the slack curtain (EA_c = 0) with opening stiffness {H} N·m/rad holding its meshes open"))
    return cases


def _sliver_cases():
    def strip(size, current=0.0):
        # a strip of netting 10 000 twines long and 1 wide, meshed 1000 twines a triangle: 20 triangles of
        # aspect ratio 1e3 in twine coordinates (longest edge² / twice the area); square meshes (U along x,
        # V along y), hanging between its two short ends
        from jaxnet.net import Net
        from jaxnet.scene import Environment

        l0, n = 2e-3, 10_000
        net = Net(Environment(current_speed=current, current_direction=np.array([0.0, 1.0, 0.0])))
        corners = [(0, 0, 0, 0, 0), (n * l0, 0, 0, n, 0), (n * l0, l0, 0, n, 1), (0, l0, 0, 0, 1)]
        p = net.panel("strip", corners, _twine(l0=l0), step=1000 * l0)
        net.fix(p.side(1))
        net.fix(p.side(3))
        return net.build()

    def fan(size):
        # triangles (0,0) (1000,0) (500,1) in twine coordinates, one panel each, sharing corners: a fan of
        # slivers around a free hub, each of aspect ratio 1e3, the rim held
        from jaxnet.net import Net

        l0 = 1e-3
        net = Net()
        k = 6
        for i in range(k):
            a, b = 2 * math.pi * i / k, 2 * math.pi * (i + 1) / k
            r = 1000 * l0 / (2 * math.sin(math.pi / k))
            corners = [(r * math.cos(a), r * math.sin(a), 0, 0, 0), (r * math.cos(b), r * math.sin(b), 0, 1000, 0),
                       (0, 0, 0.0, 500, 1)]
            p = net.panel(f"sliver {i}", corners, _twine(l0=l0), step=1.0)
            net.fix(p.corner(0))
            net.fix(p.corner(1))
        return net.build()

    return [
        CatalogueCase("sliver strip", "sliver", _static(strip),
             "a strip 10 000 × 1 twines meshed into 20 triangles of aspect ratio 1e3 in twine coordinates, "
             "hanging between its ends"),
        CatalogueCase("sliver strip in a current", "sliver", _static(lambda size: strip(size, 1.0)),
             "the same in a 1 m/s current across it"),
        CatalogueCase("sliver fan", "sliver", _static(fan),
             "six triangles (0,0) (1000,0) (500,1) in twine coordinates (aspect 1e3) around a free hub, "
             "their rims held, drawn flat: the twines across each sliver (one twine length from rim to hub in "
             "twine coordinates) are drawn 866 times their length, the hub held by six enormous tensions in "
             "balance"),
    ]


def _knot_cases():
    l0 = 0.025

    def closed_frame(size):
        # contact from 2 arcsin(knot / 2 l0) = 0.6 rad (half angle 0.3 rad), the frame holding the meshes at
        # a half angle of 0.1 rad: every mesh is pushed closed against its knots
        knot = 2 * l0 * math.sin(0.3)
        return _framed(size, _twine(knot_size=knot), opening=0.1)

    def pulled(size):
        # a panel held along its top and pulled down along its bottom: its meshes close until the knots touch
        from jaxnet.net import Net

        meshes = _size(size, 10, 20, 40)
        w = meshes * l0 * math.sqrt(2.0)
        net = Net()
        corners = [(0, 0, -w, 0, 0), (w, 0, -w, meshes, -meshes), (w, 0, 0, 2 * meshes, 0), (0, 0, 0, meshes, meshes)]
        p = net.panel("netting", corners, _twine(knot_size=0.01), step=_size(size, 0.1, 0.07, 0.05))
        net.fix(p.side(2))
        net.attach(p.side(0), force=(0.0, 0.0, -50.0))
        return net.build()

    return [
        CatalogueCase("knots: frame pushes meshes closed", "knot", _static(closed_frame),
             "the framed panel drawn with meshes at half angle 0.1 rad, knots touching below 0.3 rad"),
        CatalogueCase("knots: pulled panel", "knot", _static(pulled),
             "a panel held along its top, 50 N pulling its bottom side: meshes close onto 1 cm knots"),
    ]


def codend_capacity(meshes_around, meshes_along, l0):
    """The most a tube of that netting can hold (m³): π r² L with r = meshes_around 2 l0 sin α / 2π and
    L = meshes_along 2 l0 cos α, at its best mesh opening (sin² α = 2/3). A cod-end closed by its cod line
    holds less; the catch cases are fractions of this."""
    sin, cos = math.sqrt(2.0 / 3.0), math.sqrt(1.0 / 3.0)
    r = meshes_around * 2 * l0 * sin / (2 * math.pi)
    return math.pi * r * r * meshes_along * 2 * l0 * cos


def _catch_cases():
    from jaxnet.scenes import codend

    def build(size, fraction):
        around, along = _size(size, (24, 12), (60, 30), (100, 50))
        return codend(meshes_around=around, meshes_along=along, step=_size(size, 0.3, 0.15, 0.12),
                      catch_m3=fraction * codend_capacity(around, along, 0.06)).scene

    cases = []
    for label, fraction in (("tiny", 1e-5), ("small", 1e-2), ("c2's", 0.03), ("half", 0.5), ("overfull", 2.0)):
        cases.append(CatalogueCase(f"catch {label}", "catch", lambda size, f=fraction: Problem(build(size, f)),
                          f"the built-in cod-end (quarter model, 1.5 m/s, knots 1 cm) holding {fraction:g} of "
                          "the most its netting could hold as a tube" + (" (more than it can: the catch front "
                          "stops at its opening)" if fraction > 1 else "")))
    return cases


def _time_step_cases():
    from jaxnet.solve import dynamics

    def build(size, dt, ea=None):
        twine = None if ea is None else _twine(ea=ea, ea_compression=ea)
        scene = _hanging(size, twine, current=0.5, meshes=_size(size, 6, 10, 20), step=0.1)
        return Problem(scene, dynamic=Dynamic(dynamics.Implicit(time_step=dt, min_time_step=min(dt, 1e-7)), 3 * dt))

    cases = [CatalogueCase(f"time step {dt:g} s", "time step", lambda size, dt=dt: build(size, dt),
                  f"dynamics: the curtain, a 0.5 m/s current switched on at t = 0, three implicit steps of {dt:g} s")
             for dt in (1e-5, 1e-3, 1e-1, 1.0, 10.0)]
    cases += [CatalogueCase(f"time step {dt:g} s, EA 1e10 N", "time step", lambda size, dt=dt: build(size, dt, 1e10),
                   f"the same with twines of EA = EA_c = 1e10 N (periods of microseconds), steps of {dt:g} s")
              for dt in (1e-5, 10.0)]
    return cases


def _size_cases():
    def framed(size):
        from jaxnet.scenes import framed_panel

        n = _size(size, 1000, 10_000, 100_000)
        width = 100 * 0.025 * math.sqrt(2.0)
        # the mesher's lattice holds about 1.15 nodes per step² (benchmarks/statics.py)
        return framed_panel(meshes=100, step=width / math.sqrt(n / 1.15), twine=_twine()).scene

    return [CatalogueCase("large framed panel", "size", _static(framed),
                 "the framed panel (100 × 100 meshes, slack twines, 5 kg sinker) of 10⁴ nodes (quick) or 10⁵ "
                 "(full: about 8 minutes for its two runs on 2 cores)")]


def _hexagonal_cases():
    from jaxnet.net import HexTwine, Net

    def panel(size, framed, ea=1000.0):
        a, meshes = 0.02, _size(size, 8, 20, 40)
        w = meshes * 3 * a  # a base mesh is 3 twine lengths along U
        net = Net()
        if framed:
            corners = [(0, 0, 0, 0, 0), (w, 0, 0, meshes, 0), (w, w, 0, meshes, meshes), (0, w, 0, 0, meshes)]
        else:
            corners = [(0, 0, -w, 0, 0), (w, 0, -w, meshes, 0), (w, 0, 0, meshes, meshes), (0, 0, 0, 0, meshes)]
        twine = HexTwine(l0=(a, a, 1.2 * a), ea=ea, diameter=1e-3)
        p = net.panel("hex", corners, twine, step=_size(size, 0.1, 0.05, 0.05))
        if framed:
            for k in range(4):
                net.fix(p.side(k))
            net.sinker(p.nearest(w / 2, w / 2, 0.0), 2.0)
        else:
            net.fix(p.side(2))
            net.attach(p.side(0), force=(0.0, 0.0, -5.0))
        return net.build()

    return [
        CatalogueCase("hexagonal curtain", "hexagonal", _static(lambda size: panel(size, False)),
             "a hexagonal-mesh panel (l, m, n = 2, 2, 2.4 cm) hanging from its top, 5 N along its bottom"),
        CatalogueCase("hexagonal framed", "hexagonal", _static(lambda size: panel(size, True)),
             "a horizontal hexagonal-mesh panel held along its border, a 2 kg sinker at its centre"),
        CatalogueCase("hexagonal framed EA 1e10 N", "hexagonal", _static(lambda size: panel(size, True, 1e10)),
             "the same with twines of EA = 1e10 N"),
    ]


def _bending_cases():
    def shelf(size, ei, knot=0.005):
        # a horizontal panel held along one side only, a lead line along the opposite one: it folds down
        # about the held side, bending resisting
        from jaxnet.net import Net

        meshes, l0 = _size(size, 10, 20, 40), 0.025
        w = meshes * l0 * math.sqrt(2.0)
        net = Net()
        corners = [(0, 0, 0, 0, 0), (w, 0, 0, meshes, -meshes), (w, w, 0, 2 * meshes, 0), (0, w, 0, meshes, meshes)]
        p = net.panel("shelf", corners, _twine(bending_stiffness=ei, knot_size=knot), step=_size(size, 0.1, 0.07, 0.05))
        net.fix(p.side(3))
        net.sinker(p.side(1), 1.0)
        return net.build()

    return [
        CatalogueCase("bending, framed", "bending", _static(lambda size: _framed(size, _twine(bending_stiffness=1e-4))),
             "the framed panel with twine bending EI = 1e-4 N·m²"),
        CatalogueCase("bending shelf, soft", "bending", _static(lambda size: shelf(size, 1e-5)),
             "a horizontal panel held along one side, a 1 kg lead line along the opposite side, EI = 1e-5 "
             "N·m², knots of 5 mm (its meshes close near the held side, down to the knots)"),
        CatalogueCase("bending shelf, stiff", "bending", _static(lambda size: shelf(size, 1e-1)),
             "the same with EI = 0.1 N·m²"),
        CatalogueCase("bending shelf, no knots", "bending", _static(lambda size: shelf(size, 1e-1, knot=0.0)),
             "the stiff shelf without knots: meshes may close completely, and a triangle of a closed mesh has "
             "no area, no normal and so no fold angle; the bending energy is continuous there but not "
             "differentiable (the out-of-plane turn of a twine lying along the hinge), which a Newton "
             "iteration cannot resolve: see the section's findings"),
    ]


def _femnet_cases():
    from jaxnet.io import femnet

    def build(name):
        def problem(size):
            loaded = femnet.read_don(FEMNET_DATA / f"{name}.don")
            return Problem(loaded.scene, newton=loaded.solver)
        return problem

    notes = {
        "nr_netting": "FEMNET's panel held by ropes, a sinker bar, in a 0.6 m/s current (its numerics)",
        "c2": "FEMNET's quarter cod-end with 0.2 m³ of catch at 1.9 m/s (its numerics)",
        "hexagonal": "a hexagonal panel hanging from its top side, 0.5 N per bottom node",
        "links_cable": "two panels of 10 and 8 meshes sewn on one border and a lead cable; slack twines",
        "links_hub": "a square of netting written as four triangular panels around a free hub",
        "links_hub_single": "the same net as one panel",
    }
    return [CatalogueCase(f"FEMNET {name}", "FEMNET", build(name), note) for name, note in notes.items()]


def _fixing_cases():
    from jaxnet.net import Net

    def one_corner(size):
        # a panel held at one corner only, in a current: it must swing about that corner to stream and hang
        from jaxnet.scene import Environment

        meshes, l0 = _size(size, 10, 20, 40), 0.025
        w = meshes * l0 * math.sqrt(2.0)
        net = Net(Environment(current_speed=0.5))
        corners = [(0, 0, 0, 0, 0), (w, 0, 0, meshes, -meshes), (w, w, 0, 2 * meshes, 0), (0, w, 0, meshes, meshes)]
        p = net.panel("flag", corners, _twine(), step=_size(size, 0.1, 0.05, 0.05))
        net.fix(p.corner(0))
        return net.build()

    def unheld(size):
        net = Net()
        net.panel("loose", [(0, 0, 0, 0, 0), (1, 0, 0, 20, -20), (1, 1, 0, 40, 0), (0, 1, 0, 20, 20)], _twine(), 0.2)
        return net.build()

    return [
        CatalogueCase("held at one corner", "fixing", _static(one_corner),
             "a panel held at a single node, in a 0.5 m/s current: it must swing through 90° about that node"),
        CatalogueCase("held nowhere", "fixing", _static(unheld),
             "a panel with no fixing has no equilibrium (it drifts as a rigid body): refused before solving",
             expect=(REFUSED,)),
    ]


def catalogue():
    """Every case of the suite, family by family (a list of :class:`CatalogueCase`)."""
    return (_ea_cases() + _slack_cases() + _current_cases() + _opening_cases() + _sliver_cases() + _knot_cases()
            + _catch_cases() + _time_step_cases() + _size_cases() + _hexagonal_cases() + _bending_cases()
            + _femnet_cases() + _fixing_cases())


#: the families the issue names, in report order
FAMILIES = ("EA", "slack", "current", "opening", "sliver", "knot", "catch", "time step", "size", "hexagonal",
            "bending", "FEMNET", "fixing")


# -- running a case ------------------------------------------------------------------------------------------


def element_size(scene):
    """The scale of the elements at the start (m): the median over elements of each one's shortest side
    (triangles: the shortest of the three; bars: the length). The shortest side, so that a sliver's
    perturbation is a fraction of its thickness, not of its length."""
    x = np.asarray(scene.nodes.position, dtype=float)
    sizes = []
    for family in (scene.netting, scene.hexagonal):
        if family is not None:
            tri = np.asarray(family.vertices)
            sides = [np.linalg.norm(x[tri[:, a]] - x[tri[:, b]], axis=1) for a, b in ((0, 1), (1, 2), (2, 0))]
            sizes.append(np.min(sides, axis=0))
    if scene.bars is not None:
        ends = np.asarray(scene.bars.ends)
        sizes.append(np.linalg.norm(x[ends[:, 0]] - x[ends[:, 1]], axis=1))
    return float(np.median(np.concatenate(sizes)))


def perturbed_start(scene, seed=SEED, size=PERTURBATION):
    """(N, 3) start positions (m): the scene's, every free coordinate displaced by N(0, σ²), σ = ``size`` ×
    :func:`element_size`; and σ (m)."""
    sigma = size * element_size(scene)
    rng = np.random.default_rng(seed)
    x = np.asarray(scene.nodes.position, dtype=float)
    free = ~np.asarray(scene.nodes.fixed, dtype=bool)
    return np.where(free, x + rng.normal(0.0, sigma, x.shape), x), sigma


def shape_figures(scene, x):
    """What the net looks like at positions x (N, 3) (m), to explain an outcome: ``closed``, the smallest
    sine of the angle between a diamond-mesh triangle's two twine vectors (0: a mesh shut completely, its
    triangle without area); ``sharp_folds``, the sides shared by two triangles of one panel folded beyond
    90° (a crumpled net). None where the scene has no diamond netting."""
    import jax
    import jax.numpy as jnp

    from jaxnet import geometry
    from jaxnet.mesh.hinges import find_hinges
    from jaxnet.terms import bending

    net = scene.netting
    if net is None or not np.all(np.isfinite(x)):
        return dict(closed=None, sharp_folds=None)
    tri = np.asarray(net.vertices)
    U, V, _ = jax.vmap(geometry.twine_vectors)(jnp.asarray(x[tri]), jnp.asarray(net.uv))
    U, V = np.asarray(U), np.asarray(V)
    sine = np.linalg.norm(np.cross(U, V), axis=1) / np.maximum(
        np.linalg.norm(U, axis=1) * np.linalg.norm(V, axis=1), 1e-300)
    _, hinge_nodes = find_hinges(tri, np.asarray(net.panel))
    folds = np.asarray(jax.vmap(bending.fold_angle)(jnp.asarray(x[hinge_nodes]))) if len(hinge_nodes) else np.zeros(0)
    return dict(closed=float(sine.min()), sharp_folds=int(np.sum(np.abs(folds) > np.pi / 2)))


def _finite(*arrays):
    return all(np.all(np.isfinite(np.asarray(a, dtype=float))) for a in arrays)


def newton_options(problem: Problem):
    """The Newton options a statics case runs with: its own (FEMNET's cases: theirs) or the defaults, with
    at least :data:`MAX_ITERATIONS` iterations."""
    from jaxnet.solve.options import Newton

    newton = problem.newton or Newton()
    return dataclasses.replace(newton, max_iter=max(newton.max_iter, MAX_ITERATIONS))


def _solve_static(problem: Problem, x0):
    import jaxnet as jn

    newton = newton_options(problem)
    eq = jn.solve_static(problem.scene, newton, x0=x0, throw=False)
    it = int(eq.iterations)
    history = np.asarray(eq.history)[: it + 1]
    return dict(converged=eq.converged, reason=eq.reason, iterations=it, residual_N=float(eq.residual_N),
                tol=newton.tol, worst_node=int(eq.worst_node), compile_s=eq.timing.compile_s,
                history=history.tolist(), nan=not _finite(eq.x, eq.force, history, eq.energy)), np.asarray(eq.x)


def _solve_dynamic(problem: Problem, x0):
    from jaxnet.solve import dynamics

    d = problem.dynamic
    try:
        run = dynamics.simulate(problem.scene, d.end_time, d.solver, d.loading, record_every=d.end_time, x0=x0)
        state, reason, compile_s = run.state, DONE, run.timing.compile_s
        arrays = [run.positions, run.velocities] + [np.asarray(v, dtype=float) for v in run.figures.values()]
    except dynamics.DynamicsError as error:
        state, reason, compile_s, arrays = error.state, f"DynamicsError: {error}", None, []
    return dict(converged=reason == DONE, reason=reason, iterations=int(state.iterations),
                residual_N=float(state.residual_N), tol=d.solver.newton.tol, worst_node=int(state.worst_node),
                compile_s=compile_s, steps=int(state.steps), retries=int(state.retries), history=[],
                nan=not _finite(state.x, state.v, state.force, state.residual_N, *arrays)), np.asarray(state.x)


def run_case(case: CatalogueCase, start: str, size: str):
    """Build ``case`` at ``size`` and run it from ``start`` ("flat" or "perturbed"): its record (a dict:
    case, family, start, nodes, dof, sigma_m (the perturbation, m), converged, reason, expected (bool: the
    outcome is one the case accepts), iterations, residual_N, tol, worst_node, wall_s (build and solve),
    compile_s, nan, history (the residual after each Newton iteration, N; statics), steps and retries
    (dynamics), closed and sharp_folds (:func:`shape_figures` at the end))."""
    from jaxnet.scene import SceneError

    record = dict(case=case.name, family=case.family, start=start)
    t0 = time.perf_counter()
    try:
        problem = case.build(size)
    except SceneError as error:
        record.update(converged=False, reason=f"{REFUSED}: {error}", iterations=0, residual_N=None, tol=None,
                      worst_node=None, compile_s=None, history=[], nan=False, nodes=None, dof=None, sigma_m=None,
                      closed=None, sharp_folds=None)
    else:
        scene = problem.scene
        x0, sigma = (None, 0.0) if start == "flat" else perturbed_start(scene)
        record.update(nodes=scene.n_nodes, dof=scene.n_dof, sigma_m=sigma)
        outcome, x = (_solve_dynamic if problem.dynamic else _solve_static)(problem, x0)
        record.update(outcome, wall_s=time.perf_counter() - t0)
        record.update(shape_figures(scene, x))
    record.setdefault("wall_s", time.perf_counter() - t0)
    record["expected"] = accepted(case, record)
    return record


def accepted(case: CatalogueCase, record):
    """True when the run's outcome is one the case accepts and nothing non-finite appeared: it converged
    (statics) or reached its end time (dynamics) where the case expects that, or stopped with a reason
    the case names."""
    if record["nan"]:
        return False
    if record["converged"]:
        return CONVERGED in case.expect
    return any(record["reason"].startswith(e) for e in case.expect if e != CONVERGED)


# -- the report section ----------------------------------------------------------------------------------------

COLUMNS = ("case", "start", "nodes", "converged", "iterations", "reason", "residual_N", "worst_node", "wall_s",
           "nan", "closed", "sharp_folds", "expected")


def _row(record):
    row = {k: record.get(k) for k in COLUMNS}
    reason = record["reason"]
    row["reason"] = reason if len(reason) <= 90 else reason[:87] + "..."
    if record.get("retries"):
        row["reason"] += f" ({record['steps']} steps, {record['retries']} retried)"
    return row


def _plot(records):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(12, 8.5))
    names = list(dict.fromkeys(r["case"] for r in records))
    for k, start in enumerate(STARTS):
        rows = {r["case"]: r for r in records if r["start"] == start}
        its = [max(rows[n]["iterations"], 0.8) if n in rows else 0 for n in names]
        colours = ["tab:blue" if n in rows and rows[n]["converged"] else "tab:red" for n in names]
        top.bar(np.arange(len(names)) + (k - 0.5) * 0.4, its, width=0.4, color=colours,
                alpha=1.0 if start == "flat" else 0.55, label=f"{start} start")
    top.set_yscale("log")
    top.set_xticks(np.arange(len(names)))
    top.set_xticklabels(names, rotation=90, fontsize=6)
    top.set_ylabel("Newton iterations")
    top.set_title("Iterations per case (left bar flat start, right bar perturbed; red: did not converge)")
    hardest = sorted((r for r in records if len(r["history"]) > 1), key=lambda r: -r["iterations"])[:8]
    for r in hardest:
        h = np.asarray(r["history"], dtype=float)
        bottom.semilogy(np.arange(len(h)), np.maximum(h, 1e-16), label=f"{r['case']} ({r['start']})")
    bottom.set_xlabel("Newton iteration")
    bottom.set_ylabel("largest nodal residual (N)")
    bottom.set_title("Residual histories of the statics runs that took the most iterations")
    bottom.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.tight_layout()
    return fig


#: what the suite found, by class of outcome (prose: the numbers are in the tables above it)
FINDINGS = """\
How to read the slow and failed runs. Three classes explain every run above a few tens of iterations.

1. *Degenerate equilibria converge linearly.* Nets with slack regions (twines with EA_c = 0 and no
   tension: the loose frame, the slack curtains, FEMNET's `links_cable`) or with regions in compression
   that wrinkle out of their plane (many of the curtain's twines, with EA_c = EA, are in compression under
   its own weight: in still water it stays in its plane by symmetry, any current or perturbation makes it
   wrinkle) have an energy that is flat, or a kink, in some directions at the solution. Newton
   converges there linearly, in hundreds of iterations (`jaxnet/solve/newton.py`, "Known limit"); the
   residual histories of the plot are of this kind. A crumpled start (the perturbed runs) makes most of
   these nets visit such states on the way, hence the perturbed runs' larger counts. They converge: the
   iteration cap here is larger than the library's default (500), to tell slow convergence from none.
2. *Slivers.* A triangle of aspect ratio 1e3 in twine coordinates represents as many twines across its
   short side as along its long one: its stiffness across is 1e6 times its stiffness along (the aspect
   ratio squared). A strip one such triangle wide is a ladder of near-rigid rungs on soft rails, free to
   twist; Newton steps that rotate the rungs stretch them, and the solve crawls (linear convergence). No
   NaN, no breakdown: the strip converges in hundreds of iterations, or stops at the iteration cap with its
   residual still falling.
3. *Bending where a triangle has no area.* The bending energy (jaxnet/terms/bending.py) is continuous
   but not differentiable where a triangle of a hinge loses its area (a mesh shut completely, or a slack
   twine vector shrunk to nothing): its fold angle is undefined there. Knots keep meshes from shutting
   (the shelves with 5 mm knots converge from their flat start); without knots, or from a crumpled start
   where slack twines collapse triangles, the Newton iteration reaches such a point and no step decreases
   the energy: it stops with that named reason, the residual finite. The fix belongs to the model (smoothing the
   out-of-plane turn of a twine that lies along the hinge, in the energy and in its closed-form stiffness
   together), not to the solver.

Compression-stiff twines from a crumpled start (the curtain with EA = EA_c = 1e10 N, perturbed) fold:
`sharp_folds` counts the sides of a panel folded beyond 90° at the end. Such a net's equilibria are folded
sheets of near-inextensible twines, the hardest case here. `closed` is the smallest sine of the angle
between a triangle's twines at the end (0: a mesh shut).
"""


def _not_converged(records):
    """Rows for the runs that did not converge, and what the net looked like where they stopped."""
    return [{k: r.get(k) for k in ("case", "start", "reason", "iterations", "residual_N", "worst_node", "closed",
                                   "sharp_folds", "expected")} for r in records if not r["converged"]]


def run(report, quick: bool) -> None:
    size = "quick" if quick else "full"
    cases = [c for c in catalogue() if not (quick and c.full_only)]
    report.text(
        f"{len(cases)} cases in {len(FAMILIES)} families, each run from its flat stress-free start and from a "
        f"perturbed one (every free coordinate displaced by a normal random amount of standard deviation "
        f"σ = {PERTURBATION} × the elements' size at the start, the median of their shortest sides; seed "
        f"{SEED}). Statics: `jaxnet.solve_static` with its default options (FEMNET's cases: their own numerics) but "
        f"up to {MAX_ITERATIONS} Newton iterations, `throw=False`; dynamics: "
        "`dynamics.simulate` with `Implicit(time_step=...)`. Per run: converged (statics: the largest nodal "
        "residual at most the tolerance; dynamics: the end time reached), Newton iterations (dynamics: over "
        "all steps, failed ones included; the reason then says how many steps were retried with half the "
        "step), the stop reason, the worst residual (N; dynamics: of the last step's Newton) and its node, the "
        "wall time (s, compilation included: a case whose scene has the shape and terms of an earlier one "
        "reuses its programs), whether anything non-finite appeared in positions, velocities, forces, "
        "residual history or energy (it must never), and two figures of the final shape (`closed`, "
        "`sharp_folds`: see the findings below). *expected* says whether the outcome is the one the case "
        "accepts: convergence, except where the case's note says why a named stop is the right answer."
        + (" **Quick mode**: smaller nets (the largest about 10⁴ nodes; the full study runs 10⁵-node nets)."
           if quick else ""))
    records = []
    for family in FAMILIES:
        members = [c for c in cases if c.family == family]
        if not members:
            continue
        report.heading(f"{family}")
        rows = []
        for case in members:
            for start in STARTS:
                r = run_case(case, start, size)
                records.append(r)
                rows.append(_row(r))
                print(f"[stability] {case.name:42s} {start:9s} {r['reason'][:40]:40s} it {r['iterations']:5d} "
                      f"res {r['residual_N'] if r['residual_N'] is not None else float('nan'):9.2e} "
                      f"{r['wall_s']:7.1f} s{'  NaN!' if r['nan'] else ''}{'' if r['expected'] else '  UNEXPECTED'}",
                      flush=True)
        report.text("\n".join(f"- **{c.name}**: {c.note}" + ("" if c.expect == (CONVERGED,) else
                                 f" (expected: {', '.join(c.expect)})") for c in members))
        report.table(rows, columns=COLUMNS, formats={"residual_N": ".2e", "wall_s": ".2f", "closed": ".3g"})
    report.record("stability", records)
    summary = {
        "cases": len(cases),
        "runs": len(records),
        "converged": sum(r["converged"] for r in records),
        "named stops": sum(not r["converged"] for r in records),
        "unexpected outcomes": sum(not r["expected"] for r in records),
        "NaN/inf (must be 0)": sum(r["nan"] for r in records),
        "runs over 100 iterations": sum(r["iterations"] > 100 for r in records),
        "most iterations": max(r["iterations"] for r in records),
        "total wall s": sum(r["wall_s"] for r in records),
    }
    report.heading("Summary")
    report.table([summary], formats={"total wall s": ".1f"})
    stopped = _not_converged(records)
    if stopped:
        report.table(stopped, formats={"residual_N": ".2e", "closed": ".3g"},
                     caption="The runs that did not converge, and the shape they stopped in")
    report.figure(_plot(records), "stability_iterations", "Newton iterations per case and residual histories of the "
                  "hardest runs")
    report.heading("Findings")
    report.text(FINDINGS)
