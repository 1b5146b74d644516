"""Every registered term, in whole scenes: traced exactly when the scene asks for it, and doing its job.

Part 1 (tracing). For each registered term (:func:`jaxnet.terms.term.registered`) a small scene is lowered twice through the
Newton program (``newton.newton_loop_jit.lower``, no compilation): once with the term's parameters present
and non-zero, once with them absent or zero. The term's ``jax.named_scope`` must be in the first program
and not in the second, and the two programs must differ by that term only. Names are read from the
*name stacks* of the lowered program's locations (``jit(newton_loop)/vmap(netting_drag)/twine_drag/mul``),
not from the raw text: with ``debug_info`` the text also holds the Python call sites, and a bar's drag
calls ``jaxnet.terms.drag.twine_drag``, so the substring "twine_drag" is in every scene with cable drag,
whatever the netting's drag model.

Part 2 (end to end). Each term is then checked through the whole package (builder, scene, registry,
assembly, Newton, figures) against a number that could be wrong: a closed form at the start shape, a
balance of the solved net, a draft, an angle. Two solved scenes carry most terms: curtains in a current
(tensions, weights, an external force, the three netting drag models, rope and body drag) and pieces in
still water with a free surface (mesh opening, knot contact, a stretched panel, a floating pipe, a float,
a hanging rope, netting under and above the water). Twine bending and hexagonal tension are checked at a
given shape: a Newton program with either compiles ~10 s longer (tests/scenes/test_hexagonal_panel.py solves a
hexagonal panel). The catch pressure's solved check is the pressurised tube (tests/scenes/test_pressurised_tube.py);
here its resultant on a closed cod-end is checked at a given shape.

Scenes are a few dozen to ~150 nodes so that tracing and compiling stay short.
"""

from __future__ import annotations

import dataclasses
import re

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.optimize import brentq

import jaxnet as jn
from jaxnet import figures, geometry, model
from jaxnet.model import assemble
from jaxnet.net import HexTwine, Net, Rope, Twine
from jaxnet.scene import Environment
from jaxnet.terms import bending, drag as drag_term, opening, screen, term as term_lib
from traced import NAMED_LOCATION, lowered_text  # tests/traced.py

RHO = 1025.0  # sea water (kg/m³), the Environment default
G = 9.81
TERM_NAMES = tuple(t.name for t in term_lib.registered())
DRAG_SCOPES = tuple(m.scope for m in drag_term.NETTING_DRAG_MODELS)  # twine_drag, loland_screen, ...
SCOPES = frozenset(TERM_NAMES + DRAG_SCOPES)

# ----------------------------------------------------------------------------------------------------
# Part 1: which terms a scene traces
# ----------------------------------------------------------------------------------------------------

# named locations of the MLIR text: loc("NAME"(...)); file locations are loc("FILE":line:col)
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_traced_cache: dict = {}


def traced_scopes(scene, dynamic=False):
    """Term and drag-model scopes in the name stacks of the scene's lowered Newton program (``dynamic``: a time
    step's)."""
    key = (model.active_terms(scene, dynamic=dynamic), jax.tree.structure(scene),
           tuple(np.shape(a) for a in jax.tree.leaves(scene)), dynamic)
    if key not in _traced_cache:  # the program depends on these only; the parameter values are arguments
        words = set()
        for name in NAMED_LOCATION.findall(lowered_text(scene, dynamic)):
            if "/" in name:  # a name stack (scopes and transforms), not a Python call site
                words.update(_IDENTIFIER.findall(name))
        _traced_cache[key] = frozenset(words & SCOPES)
    return _traced_cache[key]


N_MESHES, L0 = 3, 0.05
WIDTH = N_MESHES * L0 * np.sqrt(2.0)  # a square mesh of side l0 is l0 sqrt 2 across
#: neutrally buoyant twine (no weight), still water (no drag): the base scene traces the tension only
BASE_TWINE = Twine(l0=L0, ea=1000.0, diameter=2e-3, density=RHO)
NEUTRAL_ROPE = Rope(ea=1e4, diameter=0.01, density=RHO)


def curtain(net, name, y0, twine, step=0.1):
    """A square panel of N_MESHES meshes in the plane x = 0, hanging from its fixed top side (z = 0)."""
    n, w = N_MESHES, WIDTH
    corners = [(0.0, y0, -w, 0, 0), (0.0, y0 + w, -w, n, -n), (0.0, y0 + w, 0.0, 2 * n, 0), (0.0, y0, 0.0, n, n)]
    p = net.panel(name, corners, twine, step)
    net.fix(p.side(2))
    return p


HEX_MESHES, HEX_TWINE = 2, 0.02  # base meshes a side, twine length (m): a base mesh is 3 x sqrt 3 twines


def hexagonal_curtain(net, name, y0, hex_twine):
    """A hexagonal panel of HEX_MESHES x HEX_MESHES regular base meshes (U along z, V along y) in the plane
    x = 0, hanging from its fixed top side."""
    n, a = HEX_MESHES, HEX_TWINE
    h, w = n * 3 * a, n * np.sqrt(3.0) * a
    corners = [(0.0, y0, -h, 0, 0), (0.0, y0, 0.0, n, 0), (0.0, y0 + w, 0.0, n, n), (0.0, y0 + w, -h, 0, n)]
    p = net.panel(name, corners, hex_twine, 0.05)
    net.fix(p.side(1))
    return p


def small_scene(twine=BASE_TWINE, rope=None, current=0.0, surface=float("nan"), mass=0.0, volume=0.0,
                force=(0.0, 0.0, 0.0), drag_area=0.0, catch=False, second_twine=None, hexagonal=None, catch_density=0.0,
                panel_catch=False):
    """The base scene with one knob turned: a curtain of 3 x 3 meshes (~25 nodes), optionally a rope
    along its foot, a body at its lower corner, a catch, a current along x, a free surface, a second
    curtain of another netting, a hexagonal-mesh curtain of 2 x 2 base meshes; ``catch_density`` > 0 makes the catch a
    gravity catch; ``panel_catch``: the curtain holds a panel catch of its own."""
    net = Net(Environment(current_speed=current, surface_level=surface))
    p = curtain(net, "netting", 0.0, twine)
    if second_twine is not None:
        curtain(net, "second", 1.0, second_twine)
    if hexagonal is not None:
        hexagonal_curtain(net, "hexagonal", 2.0, hexagonal)
    if rope is not None:
        net.cable("foot rope", along=p.side(0), rope=rope)
    net.attach(p.corner(0), mass=mass, volume=volume, force=force, drag_area=drag_area)
    if catch:
        net.catch(1.0, center=(-1.0, 0.0, -0.5 * WIDTH), density=catch_density)
    if panel_catch:
        net.panel_catch(1.0, ["netting"], center=(-1.0, 0.0, -0.5 * WIDTH))
    return net.build()


def twine(**changes):
    return dataclasses.replace(BASE_TWINE, **changes)


def rope(**changes):
    return dataclasses.replace(NEUTRAL_ROPE, **changes)


def hex_twine(**changes):
    return HexTwine(**{**dict(l0=HEX_TWINE, ea=1000.0, diameter=1e-3, density=RHO), **changes})


def without_tension(scene, family):
    """The scene with the traction and compression stiffnesses of ``family`` ("netting", "bars", "hexagonal")
    zero: a scene no builder makes (a material of zero EA is refused), for the registry to drop the tension term."""
    f = getattr(scene, family)
    zero = np.zeros_like(np.asarray(f.ea_traction))
    return dataclasses.replace(scene, **{family: dataclasses.replace(f, ea_traction=zero, ea_compression=zero)})


def node_types(scene, environment=None, **fields):
    """The scene with FEMNET's per-node fields (one (3,) row for every node) and environment changes."""
    n = scene.n_nodes
    nodes = dataclasses.replace(scene.nodes, **{k: np.tile(np.asarray(v), (n, 1)) for k, v in fields.items()})
    return dataclasses.replace(scene, nodes=nodes, environment=dataclasses.replace(scene.environment, **(environment or {})))


BOX = dict(drag_length=(0.1, 0.1, 0.2), drag_coefficient=(1.0, 1.0, 1.0))  # a body at every node
SEA_BED = dict(limit=(0.0, 0.0, -10.0), limit_sense=(0, 0, 1))  # a floor 10 m down under every node
SINKER = dict(mass=1.0, volume=1.0 / 11340.0)  # 1 kg of lead
#: per term: (scene with its parameters present and non-zero, the same scene with them zero or absent)
ON_OFF = {
    "netting_tension": (lambda: small_scene(), lambda: without_tension(small_scene(), "netting")),
    "bar_tension": (lambda: small_scene(rope=rope()), lambda: without_tension(small_scene(rope=rope()), "bars")),
    "netting_weight": (lambda: small_scene(twine(density=1140.0)), lambda: small_scene()),
    "bar_weight": (lambda: small_scene(rope=rope(density=1140.0)), lambda: small_scene(rope=rope())),
    "node_weight": (lambda: small_scene(**SINKER), lambda: small_scene()),
    "node_force": (lambda: small_scene(force=(0.0, 0.0, -1.0)), lambda: small_scene()),
    "mesh_opening": (lambda: small_scene(twine(opening_stiffness=0.01)), lambda: small_scene()),
    "knot_contact": (lambda: small_scene(twine(knot_size=0.01)), lambda: small_scene()),
    "twine_bending": (lambda: small_scene(twine(bending_stiffness=1e-4)), lambda: small_scene()),
    "cable_bending": (lambda: small_scene(rope=rope(bending_stiffness=1.0)), lambda: small_scene(rope=rope())),
    "netting_drag": (lambda: small_scene(current=0.5), lambda: small_scene()),
    "bar_drag": (lambda: small_scene(twine(cd_normal=0.0), rope=rope(), current=0.5),
                 lambda: small_scene(twine(cd_normal=0.0), rope=rope(cd_normal=0.0), current=0.5)),
    "node_drag": (lambda: small_scene(twine(cd_normal=0.0), current=0.5, drag_area=0.01),
                  lambda: small_scene(twine(cd_normal=0.0), current=0.5)),
    "node_box_drag": (lambda: node_types(small_scene(twine(cd_normal=0.0), current=0.5), **BOX),
                      lambda: node_types(small_scene(twine(cd_normal=0.0), current=0.5), **dict(BOX, drag_coefficient=(0, 0, 0)))),
    "bottom_contact": (lambda: node_types(small_scene(), {"bottom_stiffness": 1e6}, **SEA_BED),
                       lambda: node_types(small_scene(), {"bottom_stiffness": 1e6}, **dict(SEA_BED, limit_sense=(0, 0, 0)))),
    "bottom_friction": (lambda: node_types(small_scene(twine(cd_normal=0.0), current=0.5),
                                           {"bottom_stiffness": 1e6, "bottom_friction": 0.5}, **SEA_BED),
                        lambda: node_types(small_scene(twine(cd_normal=0.0), current=0.5), {"bottom_stiffness": 1e6}, **SEA_BED)),
    # in time only: a still bed rubs the nodes moving over it
    "bed_friction": (lambda: node_types(small_scene(), {"bottom_stiffness": 1e6, "bottom_friction": 0.5,
                                                        "bottom_moving": False}, **SEA_BED),
                     lambda: node_types(small_scene(), {"bottom_stiffness": 1e6, "bottom_moving": False}, **SEA_BED)),
    "catch_pressure": (lambda: small_scene(twine(cd_normal=0.0), current=0.5, catch=True),
                       lambda: small_scene(twine(cd_normal=0.0), current=0.5)),
    "panel_catch_pressure": (lambda: small_scene(twine(cd_normal=0.0), current=0.5, panel_catch=True),
                             lambda: small_scene(twine(cd_normal=0.0), current=0.5)),
    "tarp_pressure": (lambda: small_scene(twine(cd_normal=0.0, tarp_cd=1.0), current=0.5),
                      lambda: small_scene(twine(cd_normal=0.0), current=0.5)),
    "gravity_catch": (lambda: small_scene(catch=True, catch_density=1000.0), lambda: small_scene()),
    # with a free surface (1 m above everything) even neutral netting weighs where it emerges: only a
    # family without volume (diameter 0, no body) has no gravity energy
    "netting_gravity_at_surface": (lambda: small_scene(surface=1.0),
                                   lambda: small_scene(twine(diameter=0.0), surface=1.0)),
    "bar_gravity_at_surface": (lambda: small_scene(twine(diameter=0.0), rope=rope(), surface=1.0),
                               lambda: small_scene(twine(diameter=0.0), rope=rope(diameter=0.0), surface=1.0)),
    "node_gravity_at_surface": (lambda: small_scene(twine(diameter=0.0), surface=1.0, **SINKER),
                                lambda: small_scene(twine(diameter=0.0), surface=1.0)),
    "hexagonal_tension": (lambda: small_scene(hexagonal=hex_twine()),
                          lambda: without_tension(small_scene(hexagonal=hex_twine()), "hexagonal")),
    "hexagonal_weight": (lambda: small_scene(hexagonal=hex_twine(density=1140.0)),
                         lambda: small_scene(hexagonal=hex_twine())),
    "hexagonal_gravity_at_surface": (lambda: small_scene(twine(diameter=0.0), hexagonal=hex_twine(), surface=1.0),
                                     lambda: small_scene(twine(diameter=0.0), hexagonal=hex_twine(diameter=0.0),
                                                         surface=1.0)),
}
#: the terms only a time step has (their pairs are traced in a time step)
IN_TIME_ONLY = {"bed_friction"}


def test_every_registered_term_has_an_on_off_pair():
    assert set(ON_OFF) == set(TERM_NAMES)


@pytest.mark.parametrize("name", TERM_NAMES)
def test_term_is_traced_exactly_when_its_parameters_are_present(name):
    on_scene, off_scene = (make() for make in ON_OFF[name])
    dynamic = name in IN_TIME_ONLY
    on, off = traced_scopes(on_scene, dynamic), traced_scopes(off_scene, dynamic)
    assert name in on and name not in off
    terms = lambda s: s & set(TERM_NAMES)  # noqa: E731
    assert terms(on) - terms(off) == {name} and terms(off) <= terms(on)
    # what was traced is what the registry decided, from the parameter values alone
    for scene, traced in ((on_scene, on), (off_scene, off)):
        assert terms(traced) == {t.name for t in model.active_terms(scene, dynamic=dynamic)}
    if dynamic:
        assert name not in {t.name for t in model.active_terms(on_scene)}  # statics never have it
    if name == "twine_bending":
        assert on_scene.hinges is not None and off_scene.hinges is None  # no EI: no hinges at all


def test_a_free_surface_replaces_every_weight_load_by_its_energy():
    heavy = dict(twine=twine(density=1140.0), rope=rope(density=1140.0), **SINKER)
    immersed, floating = traced_scopes(small_scene(**heavy)), traced_scopes(small_scene(surface=1.0, **heavy))
    weights = {"netting_weight", "bar_weight", "node_weight"}
    energies = {w.replace("_weight", "_gravity_at_surface") for w in weights}
    assert weights <= immersed and not energies & immersed
    assert energies <= floating and not weights & floating


@pytest.mark.parametrize("drag_model, scope", [("twines", "twine_drag"), ("loland", "loland_screen"),
                                               ("kristiansen-faltinsen", "kristiansen_faltinsen_screen")])
def test_drag_model_traces_its_own_scope_only(drag_model, scope):
    # a rope with drag: its call of drag.twine_drag must not be mistaken for the netting's twine drag
    scopes = traced_scopes(small_scene(twine(drag_model=drag_model), rope=rope(), current=0.5))
    assert {"netting_drag", "bar_drag"} <= scopes
    assert scopes & set(DRAG_SCOPES) == {scope}


def test_mixed_drag_models_trace_both_and_still_water_none():
    mixed = traced_scopes(small_scene(current=0.5, second_twine=twine(drag_model="loland")))
    assert {"netting_drag", "twine_drag", "loland_screen"} <= mixed
    assert "kristiansen_faltinsen_screen" not in mixed
    still = traced_scopes(small_scene(rope=rope(), drag_area=0.01, second_twine=twine(drag_model="loland")))
    assert not still & ({"netting_drag", "bar_drag", "node_drag"} | set(DRAG_SCOPES))


# ----------------------------------------------------------------------------------------------------
# Part 2: end to end
# ----------------------------------------------------------------------------------------------------


def immersed_fraction(t):
    """Immersed fraction of a horizontal cylinder whose axis is t radii above the water plane."""
    t = np.clip(t, -1.0, 1.0)
    return (np.arccos(t) - t * np.sqrt(1.0 - t * t)) / np.pi


def panel_nodes(scene, panel, family="netting"):
    fam = getattr(scene, family)
    k = scene.panel_names.index(panel)
    return np.unique(np.asarray(fam.vertices)[np.asarray(fam.panel) == k])


def cable_nodes(scene, cable):
    bars = scene.bars
    return np.unique(np.asarray(bars.ends)[np.asarray(bars.cable) == scene.cable_names.index(cable)])


_forces = jax.jit(assemble.forces, static_argnames=("model",))
_term_forces = jax.jit(assemble.term_forces, static_argnames=("model",))


def term_force(scene, x, name):
    """(N, 3) nodal forces (N) of the one force term ``name`` of the scene at positions x (jitted: the
    first eager evaluation of a scene's terms costs seconds)."""
    only = tuple(t for t in model.active_terms(scene) if t.name == name)
    assert len(only) == 1
    return np.asarray(_forces(np.asarray(x), scene, model=only))


# -- curtains in a current: tension, weights, external force, the three netting drags, rope and body drag

CURRENT = 0.5  # m/s along x
Q = 0.5 * RHO * CURRENT**2  # dynamic pressure (Pa)
D_TWINE, LEAD = 2e-3, 11340.0
CURTAIN_MESHES = 4
DRAG_MODELS = ("twines", "loland", "kristiansen-faltinsen")
BODY_DRAG_AREA = 0.02  # Cd A (m²) of the sinker
HEADLINE = Rope(ea=5e4, diameter=8e-3, density=1140.0, cd_normal=1.2)
SINKER_BAR = Rope(ea=1e5, ea_compression=1e5, diameter=0.01, density=LEAD, cd_normal=1.2)
PULL = (0.0, 0.3, -1.0)  # external force (N)


@pytest.fixture(scope="module")
def curtains():
    """Three curtains side by side across a current, one per netting drag model, each hanging from a
    headline held at both ends and weighted by a lead rope along its foot; a sinker with a drag area and
    an external force at the first curtain's lower corners. Solved."""
    net = Net(Environment(current_speed=CURRENT, current_direction=np.array([1.0, 0.0, 0.0])))
    n = CURTAIN_MESHES
    w = n * L0 * np.sqrt(2.0)
    refs = {}
    for k, drag_model in enumerate(DRAG_MODELS):
        tw = Twine(l0=L0, ea=2000.0, ea_compression=2000.0, diameter=D_TWINE, density=1140.0, cd_normal=1.2,
                   tangential_ratio=0.08, drag_model=drag_model)
        y0 = 1.0 * k
        p = net.panel(drag_model, [(0, y0, -w, 0, 0), (0, y0 + w, -w, n, -n), (0, y0 + w, 0, 2 * n, 0), (0, y0, 0, n, n)],
                      tw, step=0.05)
        net.cable(f"headline {k}", along=p.side(2), rope=HEADLINE)
        net.cable(f"sinker bar {k}", along=p.side(0), rope=SINKER_BAR)
        net.fix(p.corner(2))
        net.fix(p.corner(3))
        refs[drag_model] = p
    net.sinker(refs["twines"].corner(0), 0.5)
    net.attach(refs["twines"].corner(0), drag_area=BODY_DRAG_AREA)
    net.attach(refs["twines"].corner(1), force=PULL)
    scene = net.build()
    eq = jn.solve_static(scene, tol=1e-8)
    return scene, eq


def test_curtains_use_every_current_term(curtains):
    scene, eq = curtains
    assert eq.converged
    assert {t.name for t in model.active_terms(scene)} == {
        "netting_tension", "bar_tension", "netting_weight", "bar_weight", "node_weight", "node_force",
        "netting_drag", "bar_drag", "node_drag"}


def test_netting_drag_at_the_start_is_the_closed_form_of_each_model(curtains):
    # At the start every panel is flat, unstretched and normal to the current.
    scene, _ = curtains
    drag = term_force(scene, scene.nodes.position, "netting_drag")
    n = CURTAIN_MESHES
    area = 2 * n * n * L0**2  # (n l0 sqrt 2)², openings included
    solidity = 2 * D_TWINE / L0  # twine area over panel area, unstretched square meshes
    # twine drag: every twine normal to the current, each ½ rho Cd D l0 c² (4.114). A square of n mesh
    # diagonals a side holds 2 n² meshes (side l0, area l0²), so 4 n² twines (two per mesh); the scene
    # counts |d| twines per triangle (|d|/2 U, |d|/2 V)
    twines = 4 * n * n
    net = scene.netting
    d = np.abs(np.asarray(geometry.twine_determinant(np.asarray(net.uv))))
    assert d[np.asarray(net.panel) == scene.panel_names.index("twines")].sum() == twines
    expected = {"twines": twines * Q * 1.2 * D_TWINE * L0}
    # Løland (Aarsnes et al. 1990 fit) at theta = 0: Cd = 0.04 + (-0.04 + Sn - 1.24 Sn² + 13.7 Sn³)
    expected["loland"] = Q * area * (0.04 + (-0.04 + solidity - 1.24 * solidity**2 + 13.7 * solidity**3))
    # Kristiansen-Faltinsen at theta = 0: Cd = Cd_cyl(Re) Sn (2 - Sn) / (2 (1 - Sn)²) (a1 + a3 = 1), Re of
    # the flow through the openings (the smooth-cylinder fit is data: taken from the module)
    reynolds = CURRENT * D_TWINE / (1.05e-6 * (1.0 - solidity))
    cd_cylinder = float(screen.cylinder_drag_coefficient(reynolds))
    assert 0.95 < cd_cylinder < 1.1  # a smooth cylinder near Re = 1000
    expected["kristiansen-faltinsen"] = Q * area * cd_cylinder * solidity * (2 - solidity) / (2 * (1 - solidity) ** 2)
    for drag_model in DRAG_MODELS:
        total = drag[panel_nodes(scene, drag_model)].sum(axis=0)
        np.testing.assert_allclose(total, [expected[drag_model], 0.0, 0.0], rtol=1e-9, atol=1e-12)


def test_rope_and_body_drag_at_the_start_are_their_closed_forms(curtains):
    scene, _ = curtains
    x = scene.nodes.position
    # every rope lies along y, normal to the current: ½ rho Cd D L c², L its unstretched length
    width = CURTAIN_MESHES * L0 * np.sqrt(2.0)
    ropes = 3 * Q * 1.2 * width * (HEADLINE.diameter + SINKER_BAR.diameter)
    np.testing.assert_allclose(term_force(scene, x, "bar_drag").sum(axis=0), [ropes, 0, 0], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(term_force(scene, x, "node_drag").sum(axis=0), [Q * BODY_DRAG_AREA, 0, 0], rtol=1e-12)


def test_curtains_balance_and_the_reaction_carries_every_drag_and_weight(curtains):
    scene, eq = curtains
    x = np.asarray(eq.x)
    breakdown = figures.force_breakdown(scene, x)
    reaction = eq.reaction(scene).sum(axis=0)
    free_nodes = np.count_nonzero(~np.asarray(scene.nodes.fixed).all(axis=1))
    np.testing.assert_allclose(reaction + sum(breakdown.values()), 0.0, atol=free_nodes * 1e-8)
    # the body's drag does not depend on where it is in a uniform current; the reaction takes it
    np.testing.assert_allclose(breakdown["drag_nodes_N"], [Q * BODY_DRAG_AREA, 0, 0], rtol=1e-12)
    drag = breakdown["drag_netting_N"] + breakdown["drag_cables_N"] + breakdown["drag_nodes_N"]
    np.testing.assert_allclose(reaction[0], -drag[0], atol=free_nodes * 1e-8)
    # the curtains swung downstream, took the current at an angle, and their drag fell below the start's
    start = term_force(scene, scene.nodes.position, "netting_drag").sum(axis=0)
    assert x[:, 0].max() > 0.05 and 0.5 * start[0] < breakdown["drag_netting_N"][0] < start[0]
    # weights are constant loads: immersed volume x (rho_material - rho_water) g
    n = CURTAIN_MESHES
    width = n * L0 * np.sqrt(2.0)
    netting = 3 * 4 * n * n * L0 * np.pi * D_TWINE**2 / 4 * (1140.0 - RHO)
    ropes = 3 * width * np.pi / 4 * (HEADLINE.diameter**2 * (1140.0 - RHO) + SINKER_BAR.diameter**2 * (LEAD - RHO))
    sinker = 0.5 * (1 - RHO / LEAD)
    np.testing.assert_allclose(breakdown["weight_and_buoyancy_N"], [0, 0, -(netting + ropes + sinker) * G], rtol=1e-12)
    np.testing.assert_allclose(breakdown["external_N"], PULL, rtol=1e-12)


# -- still water with a free surface: mesh opening, knots, stretched netting, floats

H = 1.0  # mesh opening stiffness (N m/rad)
REST_A, REST_B = np.radians(30.0), np.radians(5.0)
CONTACT = np.radians(20.0)  # knot contact half angle of panel B
STRETCH, STRETCH_EA = 1.2, 1000.0
PIPE_D, PIPE_FILL = 0.2, 0.25  # pipe diameter (m), its density as a fraction of the water's
FLOAT_MASS, FLOAT_VOLUME, FLOAT_SIZE = 8.0, 0.02, 0.3
MOORING = Rope(ea=100.0, diameter=1e-3, density=RHO, cd_normal=0.0)
MOORING_LENGTH = 3.0
HANGER = Rope(ea=1000.0, diameter=5e-3, density=RHO, cd_normal=0.0)
HANGER_SINKER = 1.0  # kg of lead
FLAT_MESHES = 4


def square_panel(net, name, origin, twine_, meshes, scale=1.0, step=0.05):
    """A horizontal square panel of ``meshes`` mesh diagonals a side (u along x, v along y) at ``origin``,
    drawn ``scale`` times its unstretched size (square meshes)."""
    x0, y0, z0 = origin
    n, w = meshes, meshes * twine_.l0 * np.sqrt(2.0) * scale
    corners = [(x0, y0, z0, 0, 0), (x0 + w, y0, z0, n, -n), (x0 + w, y0 + w, z0, 2 * n, 0), (x0, y0 + w, z0, n, n)]
    return net.panel(name, corners, twine_, step)


@pytest.fixture(scope="module")
def still():
    """Pieces that do not touch, in still water with a free surface at z = 0, solved together.

    A, B: free square panels of 4 x 4 meshes 1 m under water, every node held in z, one corner held and
      the next one held in y (no rigid motion left). A has a mesh opening stiffness H with rest half angle
      30°; B the same H with rest 5° and knots that touch at 20° (contact stiffness H). Their twines resist
      compression, so they stay l0 long.
    S: a square panel held along its border at 1.2 times its unstretched size.
    pipe: a horizontal pipe of a quarter of the water's density held only horizontally; float: a float on
      a slack mooring line; hanger: a 1 m rope hanging from a held point with 1 kg of lead at its end;
      wet and dry: panels held at top and foot, under water and in the air.
    The pieces under water are neutrally buoyant (none of them feels its weight) except the wet panel and
    the lead.
    """
    net = Net(Environment(surface_level=0.0))
    neutral = Twine(l0=L0, ea=1e4, ea_compression=1e4, diameter=1e-3, density=RHO, opening_stiffness=H)
    for name, y0, tw in (("A", 0.0, dataclasses.replace(neutral, rest_angle=float(REST_A))),
                         ("B", 1.0, dataclasses.replace(neutral, rest_angle=float(REST_B),
                                                        knot_size=2 * L0 * np.sin(CONTACT), knot_stiffness=H))):
        p = square_panel(net, name, (0.0, y0, -1.0), tw, FLAT_MESHES)
        net.fix(p, axes="z")
        net.fix(p.corner(0))
        net.fix(p.corner(1), axes="y")
    s = square_panel(net, "S", (0.0, 3.0, -1.0), Twine(l0=L0, ea=STRETCH_EA, diameter=1e-3, density=RHO), FLAT_MESHES,
                     STRETCH)
    for k in range(4):
        net.fix(s.side(k))
    # a pipe and a float, each at its own draft
    pipe = net.cable("pipe", start=(0, 5, 0), end=(2, 5, 0), n_bars=4,
                     rope=Rope(ea=1e6, ea_compression=1e6, diameter=PIPE_D, density=PIPE_FILL * RHO))
    net.fix(pipe.nodes, axes="xy")
    line = net.cable("mooring", start=(4, 5, 0), end=(5, 5, -1), rope=MOORING, length=MOORING_LENGTH)
    net.fix(line.start, axes="xy")
    net.fix(line.end)
    net.attach(line.start, mass=FLOAT_MASS, volume=FLOAT_VOLUME, size=FLOAT_SIZE)
    # a rope hanging from a held point with a lead sinker at its end
    hanger = net.cable("hanger", start=(8, 0, -0.5), end=(8, 0, -1.5), n_bars=2, rope=HANGER)
    net.fix(hanger.start)
    net.sinker(hanger.end, HANGER_SINKER)
    heavy = Twine(l0=L0, ea=1000.0, ea_compression=1000.0, diameter=D_TWINE, density=1140.0)
    n, w = 3, 3 * L0 * np.sqrt(2.0)
    for name, top in (("wet", -1.0), ("dry", 2.0)):
        corners = [(6, 0, top - w, 0, 0), (6, w, top - w, n, -n), (6, w, top, 2 * n, 0), (6, 0, top, n, n)]
        p = net.panel(name, corners, heavy, step=0.1)
        net.fix(p.side(0))
        net.fix(p.side(2))
    scene = net.build()
    # start S's interior shaken by up to half a twine: the equilibrium must not depend on it
    rng = np.random.default_rng(1)
    x0 = np.array(scene.nodes.position)
    inner = panel_nodes(scene, "S")
    x0[inner] += rng.uniform(-0.5 * L0, 0.5 * L0, (inner.size, 3))
    eq = jn.solve_static(scene, x0=x0, tol=1e-9)
    return scene, eq


def half_angles(scene, x, panel):
    net = scene.netting
    mine = np.asarray(net.panel) == scene.panel_names.index(panel)
    alpha, _, _ = jax.vmap(opening.half_angle)(np.asarray(x)[np.asarray(net.vertices)[mine]], np.asarray(net.uv)[mine])
    return np.asarray(alpha)


def test_still_scene_uses_opening_knots_and_the_surface_energies(still):
    scene, eq = still
    assert eq.converged
    assert {t.name for t in model.active_terms(scene)} == {
        "netting_tension", "bar_tension", "mesh_opening", "knot_contact",
        "netting_gravity_at_surface", "bar_gravity_at_surface", "node_gravity_at_surface"}


def test_free_panel_opens_its_meshes_to_the_rest_angle(still):
    # from square meshes (45°) the free panel relaxes to its rest half angle: its corner 1 (4 mesh
    # diagonals along u) ends 4 x 2 l0 sin(alpha) from corner 0
    scene, eq = still
    np.testing.assert_allclose(half_angles(scene, eq.x, "A"), REST_A, atol=1e-9)
    corners = np.asarray(eq.x)[panel_nodes(scene, "A")[:2]]
    np.testing.assert_allclose(corners[1] - corners[0], [FLAT_MESHES * 2 * L0 * np.sin(REST_A), 0, 0], atol=1e-9)


def test_knots_stop_the_closing_meshes_where_contact_balances_opening(still):
    # Rest 5° but knots touch at 20°. Per knot, opening H (a - a0)² and contact H g(a_min - a), g the C²
    # penalty of band b = a_min/10, g(s) = (s - b/2)² + b²/12 beyond the band: the energy is least where
    # H (a - a0) = H (a_min - b/2 - a), i.e. a = (a0 + a_min - b/2) / 2 = 12°, 8° deep (beyond the band).
    scene, eq = still
    band = CONTACT / 10
    expected = (REST_B + CONTACT - band / 2) / 2
    assert CONTACT - expected > band and np.degrees(expected) == pytest.approx(12.0)
    np.testing.assert_allclose(half_angles(scene, eq.x, "B"), expected, atol=1e-9)


def test_stretched_panel_has_uniform_tension_and_the_virial_of_its_reactions(still):
    # Held at 1.2 times its size, every twine has the strain 0.2 at equilibrium, whatever the start of the
    # interior. Virial: at equilibrium sum over held nodes of x . R = sum over twines of T L (the internal
    # forces are -dE/dx, E a function of twine lengths, which are homogeneous of degree 1 in x).
    scene, eq = still
    n, tension = FLAT_MESHES, STRETCH_EA * (STRETCH - 1.0)
    net, x = scene.netting, np.asarray(eq.x)
    mine = np.asarray(net.panel) == scene.panel_names.index("S")
    np.testing.assert_allclose(figures.twine_tensions(scene, x)[mine], tension, rtol=1e-8)
    nodes = panel_nodes(scene, "S")
    virial = np.sum(x[nodes] * eq.reaction(scene)[nodes])
    np.testing.assert_allclose(virial, 4 * n * n * tension * STRETCH * L0, rtol=1e-8)  # 4 n² twines


def test_hanging_rope_carries_the_sinker_and_stretches_by_its_tension(still):
    scene, eq = still
    weight = HANGER_SINKER * (1.0 - RHO / LEAD) * G  # the rope itself is neutral
    hanger = np.asarray(scene.bars.cable) == scene.cable_names.index("hanger")
    np.testing.assert_allclose(figures.bar_tensions(scene, eq.x)[hanger], weight, rtol=1e-9)
    end = np.asarray(eq.x)[cable_nodes(scene, "hanger")].min(axis=0)  # the lowest node
    np.testing.assert_allclose(end, [8.0, 0.0, -1.5 - weight * 1.0 / HANGER.ea], atol=1e-9)  # L T / EA


def test_pipe_floats_where_its_immersed_fraction_is_its_density_ratio(still):
    # a horizontal circular pipe of density 0.25 rho: immersed fraction 0.25, its axis t D/2 above the water
    scene, eq = still
    t = brentq(lambda t: immersed_fraction(t) - PIPE_FILL, -1.0, 1.0)
    np.testing.assert_allclose(np.asarray(eq.x)[cable_nodes(scene, "pipe"), 2], t * PIPE_D / 2, atol=1e-9)
    assert 0.03 < t * PIPE_D / 2 < 0.05  # floats high, as a quarter-full pipe does


def test_float_settles_at_the_draft_where_buoyancy_is_its_weight(still):
    # weight m g, plus the emerged half of the (slack) mooring line, = rho g V f(2 h / size)
    scene, eq = still
    node = int(np.asarray(scene.bars.ends)[np.asarray(scene.bars.cable) == scene.cable_names.index("mooring")][0, 0])
    line = RHO * np.pi * MOORING.diameter**2 / 4 * MOORING_LENGTH / 2
    t = brentq(lambda t: RHO * FLOAT_VOLUME * immersed_fraction(t) - FLOAT_MASS - line, -1.0, 1.0)
    height = float(np.asarray(eq.x)[node, 2])
    np.testing.assert_allclose(height, t * FLOAT_SIZE / 2, atol=1e-9)
    assert height > MOORING.diameter  # the line's end is in the air, as the expected value assumes


def test_netting_weighs_immersed_under_water_and_in_full_in_the_air(still):
    scene, eq = still
    volume = 4 * 3 * 3 * L0 * np.pi * D_TWINE**2 / 4  # 4 n² twines
    reaction = eq.reaction(scene)
    np.testing.assert_allclose(reaction[panel_nodes(scene, "wet")].sum(axis=0), [0, 0, volume * (1140.0 - RHO) * G],
                               rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(reaction[panel_nodes(scene, "dry")].sum(axis=0), [0, 0, volume * 1140.0 * G],
                               rtol=1e-9, atol=1e-12)


def test_hexagonal_netting_weighs_its_three_twine_families():
    # M x M regular base meshes, each 2 l, 2 m and 2 n twines of length a: 6 M² twines
    scene = small_scene(hexagonal=hex_twine(density=1140.0))
    only = tuple(t for t in model.active_terms(scene) if t.name == "hexagonal_weight")
    load = np.asarray(assemble.loads(scene, only))
    volume = 6 * HEX_MESHES**2 * HEX_TWINE * np.pi * 1e-3**2 / 4
    np.testing.assert_allclose(load.sum(axis=0), [0, 0, -volume * (1140.0 - RHO) * G], rtol=1e-12)
    assert np.all(load[panel_nodes(scene, "netting")] == 0.0)  # only on the hexagonal panel's nodes


def test_stretched_hexagonal_panel_has_uniform_tension_and_the_virial_of_its_forces():
    # A regular honeycomb drawn at 1.2 times the size of its twines (a given shape: a Newton solve with the
    # hexagonal element compiles for ~10 s more; tests/scenes/test_hexagonal_panel.py solves one). Every twine of
    # the three families is at strain 0.2: the interior knots are in balance, and the virial of the
    # tension forces is minus the sum of T L over the 6 M² twines (2 M² per family), T = 0.2 EA.
    m, a = HEX_MESHES, HEX_TWINE * STRETCH
    net = Net(Environment(gravity=0.0))
    p = net.panel("honeycomb", [(0, 0, 0, 0, 0), (m * 3 * a, 0, 0, m, 0), (m * 3 * a, m * np.sqrt(3) * a, 0, m, m),
                                (0, m * np.sqrt(3) * a, 0, 0, m)], hex_twine(ea=STRETCH_EA), 0.05)
    net.fix(p.side(0))
    scene = net.build()
    x = np.asarray(scene.nodes.position)
    tension = STRETCH_EA * (STRETCH - 1.0)
    force = np.asarray(_term_forces(x, scene, model=model.active_terms(scene))["hexagonal_tension"])
    border = np.zeros(scene.n_nodes, dtype=bool)
    lo, hi = x.min(axis=0), x.max(axis=0)
    border[(np.abs(x[:, :2] - lo[:2]) < 1e-12).any(axis=1) | (np.abs(x[:, :2] - hi[:2]) < 1e-12).any(axis=1)] = True
    assert np.count_nonzero(~border) > 0
    np.testing.assert_allclose(force[~border], 0.0, atol=1e-9 * tension)
    np.testing.assert_allclose(np.sum(x * force), -6 * m * m * tension * a, rtol=1e-12)


# -- twine bending, at a given fold (a Newton solve with bending compiles for ~10 s more)


def test_folded_twines_resist_with_their_bending_stiffness():
    # Two triangles of N x N = 2 x 2 twines (twines along x and y) folded about their shared diagonal by
    # theta. The book's discrete twine (4.229-4.236): each of the 2 N twines crossing the fold (at 45°)
    # turns by a = theta sin 45° over two chords of N l0 / 2 (|d|/(2 N) twine vectors each side); couple
    # EI/rho with rho = (A + B)/(2 a), i.e. energy EI a²/(A + B) per twine: E = 2 N EI theta²/(2 N l0)
    # = EI theta² / l0. Virtual work: turning the folded corner about the diagonal at the lever
    # r = N l0 / sqrt 2, the bending force on it does -dE/dtheta = -2 EI theta / l0 per radian.
    n, ei = 2, 1e-4
    side = n * L0
    net = Net(Environment(gravity=0.0))
    net.panel("C", [(0, 0, 0, 0, 0), (side, 0, 0, n, 0), (side, side, 0, n, n), (0, side, 0, 0, n)],
              Twine(l0=L0, ea=1e4, diameter=1e-3, bending_stiffness=ei), step=0.2)
    net.fix((0.0, 0.0, 0.0))
    scene = net.build()
    assert scene.netting.vertices.shape[0] == 2 and np.asarray(scene.hinges.vertices).shape == (1, 4)
    a, b, p, q = np.asarray(scene.hinges.vertices)[0]
    x = np.array(scene.nodes.position)
    axis = (x[b] - x[a]) / np.linalg.norm(x[b] - x[a])
    foot = x[a] + np.dot(x[q] - x[a], axis) * axis
    out = x[q] - foot
    lever = np.linalg.norm(out)
    assert lever == pytest.approx(side / np.sqrt(2.0))
    bend = tuple(t for t in model.active_terms(scene) if t.name == "twine_bending")
    for theta in (0.2, 1.0):
        x[q] = foot + np.cos(theta) * out + np.sin(theta) * lever * np.array([0.0, 0.0, 1.0])
        assert abs(float(bending.fold_angle(x[[a, b, p, q]]))) == pytest.approx(theta, rel=1e-12)
        force = np.asarray(_term_forces(x, scene, model=bend)["twine_bending"])
        turn = -np.sin(theta) * out + np.cos(theta) * lever * np.array([0.0, 0.0, 1.0])  # dq/dtheta
        np.testing.assert_allclose(force[q] @ turn, -2 * ei * theta / L0, rtol=1e-9)
        np.testing.assert_allclose(force.sum(axis=0), 0.0, atol=1e-12)  # internal
        np.testing.assert_allclose(np.cross(x, force).sum(axis=0), 0.0, atol=1e-12)


# -- the catch pressure on a closed cod-end (a given shape: the solved check is the pressurised tube)

CATCH_P = 0.5 * RHO * 1.4 * 1.0**2  # ½ rho Cd v², Cd 1.4 at 1 m/s (Pa)


def closed_codend(volume):
    """A quarter cod-end (axis x, symmetry planes y = 0 and z = 0) of 8 meshes around and 6 along, laid on a
    cylinder of radius 0.1 m whose last 2 meshes close onto the axis (a dome): with its front opening, a
    closed net. The front ring (x = 0) is held."""
    n, m, l0, radius = 2, 6, 0.05, 0.1
    length = m * 2 * l0 * np.cos(np.radians(55.0))
    net = Net(Environment(current_speed=1.0))
    corners = [(0, 0, radius, 0, 0), (0, radius, 0, n, -n), (length, radius, 0, n + m, m - n), (length, 0, radius, m, m)]
    p = net.panel("cod-end", corners, Twine(l0=l0, ea=1e3, diameter=2e-3, density=RHO, cd_normal=0.0), 0.05)
    net.fix(p.side(0))
    net.fix(p.side(3), axes="y")
    net.fix(p.side(1), axes="z")
    net.catch(volume, drag_coefficient=1.4, symmetry=4.0, center=(0.0, 0.0, 0.0))
    scene = net.build()
    tri, uv = np.asarray(scene.netting.vertices), np.asarray(scene.netting.uv)
    node_uv = np.zeros((scene.n_nodes, 2))
    node_uv[tri.ravel()] = uv.reshape(-1, 2)
    u, v = (node_uv[:, 0] - node_uv[:, 1]) / 2, (node_uv[:, 0] + node_uv[:, 1]) / 2
    phi = u / n * np.pi / 2
    r = radius * np.sqrt(1.0 - np.clip((v - (m - 2)) / 2, 0.0, 1.0) ** 2)
    x = np.stack([v / m * length, r * np.sin(phi), r * np.cos(phi)], axis=1)
    return dataclasses.replace(scene, nodes=dataclasses.replace(scene.nodes, position=x))


def profile_area(points, axis):
    """Area (m²) between the x axis and the polyline of ``points`` (sorted by x) in the plane of x and ``axis``."""
    points = points[np.argsort(points[:, 0], kind="stable")]
    return np.trapezoid(points[:, axis], points[:, 0])


def test_catch_pressure_resultant_is_the_pressure_on_the_faces_that_close_the_catch():
    # More catch than the net holds: the front is at the ring and the whole net is loaded. The net, the
    # ring's disk and the two symmetry planes close the catch, and the pressure on a closed surface sums
    # to zero: the net's resultant is p times the disk along x and p times the net's profile in each
    # symmetry plane across (those faces carry the pressure of the other quarters).
    over = closed_codend(volume=10.0)
    x = np.asarray(over.nodes.position)
    assert [t.name for t in model.active_terms(over)] == ["netting_tension", "catch_pressure"]
    report = figures.catch_report(over, x)
    assert not report["holds_the_volume"] and report["front_m"] == pytest.approx(0.0, abs=1e-12)
    ring = x[np.asarray(over.nodes.fixed).all(axis=1)]
    ring = ring[np.argsort(np.arctan2(ring[:, 1], ring[:, 2]))]
    disk = 0.5 * abs(np.sum(ring[:-1, 1] * ring[1:, 2] - ring[:-1, 2] * ring[1:, 1]))  # fan from the axis
    in_y0, in_z0 = profile_area(x[np.abs(x[:, 1]) < 1e-12], 2), profile_area(x[np.abs(x[:, 2]) < 1e-12], 1)
    catch = term_force(over, x, "catch_pressure").sum(axis=0)
    np.testing.assert_allclose(catch, CATCH_P * np.array([disk, in_y0, in_z0]), rtol=1e-9)
    # the disk is the ring's polygon (k sides on the 0.1 m circle), the two profiles are mirror images
    k = len(ring) - 1
    assert disk == pytest.approx(k / 2 * 0.1**2 * np.sin(np.pi / (2 * k)), rel=1e-12)
    assert in_y0 == pytest.approx(in_z0, rel=1e-12)
    # a catch the net holds: the front is inside the net and the resultant along x is p times the front's
    # section, which the catch report gives (as the catch drag) for the whole cod-end, 4 quarters
    held = closed_codend(volume=0.5 * report["volume_m3"])
    report = figures.catch_report(held, x)
    assert report["holds_the_volume"] and report["volume_m3"] == pytest.approx(float(held.catch.volume), rel=1e-9)
    assert 0.0 < report["front_m"] < x[:, 0].max()
    catch = term_force(held, x, "catch_pressure").sum(axis=0)
    np.testing.assert_allclose(catch[0], report["drag_N"] / 4, rtol=1e-9)
    # the front cuts the cylindrical part, whose section is about the ring's polygon
    assert report["drag_N"] / 4 == pytest.approx(CATCH_P * disk, rel=0.05)


def test_catch_shields_the_netting_behind_its_front_from_drag():
    # the adapter of the netting drag: ahead of the front the twine drag, behind it none (the catch pressure
    # replaces it), in between the consistent load of the part ahead, continuous as the front sweeps through
    from jaxnet.scene import Environment
    from jaxnet.terms import drag

    env = Environment(current_speed=1.0, current_direction=np.array([1.0, 0.0, 0.0]))
    x = jnp.array([[0.0, 0.0, 0.0], [0.0, 0.1, 0.0], [0.05, 0.0, 0.1]])
    uv = jnp.array([[0.0, 0.0], [4.0, -4.0], [4.0, 4.0]])

    class Row:  # one netting row
        pass

    p = Row()
    p.uv, p.l0, p.diameter, p.cd_normal, p.tangential_ratio, p.drag_model = uv, 0.025, 2e-3, 1.2, 0.08, 0
    plain = drag.netting_drag(x, uv, 0.025, 2e-3, 1.2, 0.08 * 1.2, jnp.array([1.0, 0.0, 0.0]), env.water_density)

    def shielded(front):
        state = {"front": jnp.asarray(front), "axis": jnp.array([1.0, 0.0, 0.0])}
        arguments = drag_term.NETTING_DRAG.arguments(p, env, models=(0,), shielded=True)
        return np.asarray(drag_term.netting_drag_on_element(x, state, **arguments))

    np.testing.assert_allclose(shielded(1.0), plain, rtol=1e-12)   # front downstream of the triangle
    np.testing.assert_allclose(shielded(-1.0), 0.0, atol=1e-15)    # triangle wholly behind the front
    partial = shielded(0.025).sum(axis=0)[0] / np.asarray(plain).sum(axis=0)[0]
    # the part ahead of the plane x = 0.025 is the corner beyond it: 1 - (1/2)^2 of the surface
    assert partial == pytest.approx(1.0 - 0.25, rel=1e-12)
    # continuity as the front reaches the vertex at x = 0.05
    np.testing.assert_allclose(shielded(0.05 - 1e-9), shielded(0.05 + 1e-9), atol=1e-9 * abs(float(plain[0, 0])))
