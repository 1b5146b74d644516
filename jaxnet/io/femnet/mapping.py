"""The mapping of a parsed ``.don`` file (:class:`~.grammar.DonFile`) onto jaxnet: its twines, ropes,
surroundings and node types, built with the :class:`~jaxnet.net.Net` builder by :func:`read_don` (jaxnet meshes
the panels), and the pieces :func:`~.mdg.read_mdg` shares on FEMNET's own mesh. The conventions are the
package's docstring's.
"""

from __future__ import annotations

import contextlib
import dataclasses
import math
import re

import equinox as eqx
import numpy as np

from jaxnet import geometry
from jaxnet.water import waves as waves_lib
from jaxnet.io.femnet.grammar import INPUTS, DonCable, DonFile, DonPanel, twine_coordinates
from jaxnet.io.femnet.links import MERGE_TOLERANCE, JoinPlan, all_panels, at_joined_positions, plan_joins
from jaxnet.io.femnet.parse import parse_don
from jaxnet.io.femnet.reader import Value
from jaxnet.io.femnet.twines import numerical_twines
from jaxnet.net import CableRef, HexTwine, Net, Rope, Twine
from jaxnet.scene import Environment, PanelCatches, SceneError
from jaxnet.case import Case, TimeSettings
from jaxnet.solve.options import TIME_STEP, Implicit, Newton
from jaxnet.terms import knot

#: FEMNET's default water density (kg/m³, phobos ``chargement_don.c``: RHO = 1025)
WATER_DENSITY = 1025.0
#: the acceleration of gravity (m/s²), FEMNET's
GRAVITY = 9.81


def twine_of(p: DonPanel, case: DonFile, femnet_laws: bool) -> Twine:
    """The panel's netting material; with ``femnet_laws``, with FEMNET's laws where they differ from the book
    (``docs/errata.md``, "Where FEMNET differs"): its knot contact (``fermeture2``), and, in a case with a
    catch, its netting drag (``trainee_fil``)."""
    m = {k: v.value for k, v in p.material.items()}
    twine = Twine(l0=m["l0"], ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"],
                  cd_normal=m["cd"], tangential_ratio=m["f"], opening_stiffness=m["opening"], knot_size=m["knot"])
    twine = dataclasses.replace(twine, tarp_cd=_tarp_cd(case, p), drag_model=_drag_law(case))
    if not femnet_laws:
        return twine
    return dataclasses.replace(
        twine, knot_form="femnet", knot_stiffness=float(knot.femnet_knot_stiffness(m["l0"], m["knot"], m["ea"])),
        drag_model="femnet-catch" if _femnet_catch_drag(case) else twine.drag_model)


#: FEMNET's netting drag laws (``input drag_forces_type N``) -> jaxnet's drag models (jaxnet.terms.drag's
#: docstring): its 3 (drop pressure) and 4 (Aarnes) are calls commented out in its code, so no drag
FEMNET_DRAG_LAWS = {1: "twines", 2: "zhan", 3: "none", 4: "none"}


def _drag_law(case: DonFile) -> str:
    """The drag model of the case's diamond netting, by its ``input drag_forces_type`` (1, Morison, without one).
    A law of the case, kept with the book's laws too; with FEMNET's, a case with a catch takes its catch drag
    instead, as FEMNET does whatever the law (:func:`twine_of`)."""
    law = case.inputs.get("drag_forces_type")
    return FEMNET_DRAG_LAWS[1 if law is None else int(law.value)]


def _femnet_catch_drag(case: DonFile) -> bool:
    """Whether FEMNET loads this case's netting with its drag of cases with a catch (``unix.c``: a catch
    volume above its accuracy, in a current) rather than its twine drag (``filethydro4_sta``)."""
    return ((case.catch["catch_volume"].value > case.catch["catch_accuracy"].value or bool(_tarps(case)))
            and case.ocean["current_speed"].value > 0)


def _tarps(case: DonFile) -> dict:
    """{0-based diamond panel index: its ``input tarp PANEL`` line's Value} (a SceneError ``file:LINE:`` for a
    line naming no diamond panel)."""
    out = {}
    for key, v in case.inputs.items():
        if key.startswith("tarp "):
            k = int(v.value) - 1
            if not 0 <= k < len(case.panels):
                raise SceneError(f"{case.path}:{v.line}: 'input tarp {k + 1}': panel {k + 1} does not exist (diamond "
                                 f"panels: 1 to {len(case.panels)})")
            out[k] = v
    return out


def meshing_lattices(case: DonFile) -> dict:
    """{0-based diamond panel index: (NU, NV)} from the ``input Meshing_UV PANEL NU NV`` lines (meshes along the U
    and V diagonals between nodes: ``Net.panel(lattice=...)``; phobos ``chargement_don.c`` sets ``pas_U``, ``pas_V``
    and ``maillage.c`` then meshes the panel with ``maillage_interne4``), for the panels of meshing type 2, the only
    ones FEMNET meshes so (the parser warns of the others). A SceneError ``file:LINE:`` for a line naming no
    diamond panel."""
    out = {}
    for key, v in case.inputs.items():
        if key.startswith("meshing_uv "):
            k = int(v.value[0]) - 1
            if not 0 <= k < len(case.panels):
                raise SceneError(f"{case.path}:{v.line}: 'input Meshing_UV {k + 1}': panel {k + 1} does not exist "
                                 f"(diamond panels: 1 to {len(case.panels)})")
            if case.panels[k].material["mesh_type"].value == 2:
                out[k] = (float(v.value[1]), float(v.value[2]))
    return out


def _tarp_cd(case: DonFile, p: DonPanel) -> float:
    """The tarp pressure coefficient of diamond panel ``p`` (:attr:`Twine.tarp_cd`): the catch's Cd ("Drag
    coefficient on this volume") for a panel named by ``input tarp``, as FEMNET's ``pression_prise3`` pushes its
    tarps with the catch's pressure (:mod:`jaxnet.terms.tarp`), else 0."""
    tarps = _tarps(case)
    k = next((k for k, q in enumerate(case.panels) if q is p), None)
    return float(case.catch["catch_cd"].value) if k in tarps else 0.0


def _hextwine(p: DonPanel) -> HexTwine:
    """A hexagonal panel's netting material: FEMNET's three twine families l, m, n (one diameter, see
    :func:`_hexagonal_diameter`)."""
    m = p.material
    l0 = np.array([v.value for v in m["l0"]])
    d = np.array([v.value for v in m["diameter"]])
    return HexTwine(l0=tuple(l0.tolist()), ea=tuple(v.value for v in m["ea"]), diameter=_hexagonal_diameter(l0, d),
                    ea_compression=tuple(v.value for v in m["eac"]), density=m["density"].value)


def _hexagonal_diameter(l0, d):
    """jaxnet's hexagonal netting has one twine diameter, used only for the twines' weight (it has no drag
    model): the one with the weight of FEMNET's three families, pi/4 sum d_i² l0_i = pi/4 D² sum l0_i (m)."""
    d, l0 = np.asarray(d, dtype=float), np.asarray(l0, dtype=float)
    scale = d.max()  # scaled, so that no square overflows for any finite diameters
    return float(scale * np.sqrt(np.sum((d / scale) ** 2 * l0) / np.sum(l0))) if scale > 0 else 0.0


def rope_of(c: DonCable) -> Rope:
    """A cable's rope material (its unstretched length l0 is the cable's rest length, given with the cable)."""
    m = {k: v.value for k, v in c.material.items()}
    return Rope(ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"], cd_normal=m["cd"],
                tangential_ratio=m["f"], bending_stiffness=m.get("ei", 0.0))


def environment_of(case: DonFile) -> Environment:
    """The surroundings: FEMNET's water and current, its water plane z = 0, and its sea bed (``fond.c``): the
    limits' penalty stiffness, its law exactly (no band), and its friction coefficient, the "wearing coefficient
    on the bottom": in statics FEMNET applies it only with ``input moving_bottom`` (``bottom_moving``; a still
    bottom exerts none), in time on every node that presses on the bed (``fond_dyn.c``).

    The water plane. FEMNET's statics float node boxes (``flotteur2.c``) and bars (``flotteurelement2.c``: their
    wetted length) by their part under z = 0, and keep diamond netting buoyant wherever it is
    (``flotteursurf3.c``; its static loop does not call ``flotteursurf4.c``, the surface-aware one). jaxnet's
    scenes from FEMNET have their free surface there too (``surface_level`` 0) and the same split
    (``floating=("bars", "nodes")``): boxes float as boxes (:func:`jaxnet.terms.surface.box_fraction_integral`,
    FEMNET's law), bars by jaxnet's profile (:mod:`jaxnet.terms.surface`: each end as a horizontal cylinder of
    the bar's diameter, which differs from the wetted length only within a diameter of the surface; a bar lying
    at z = 0 exactly is half immersed, FEMNET's wholly). Under the surface the loads are the constant immersed
    weights, as before."""
    angle = math.radians(case.ocean["current_direction"].value)
    rho = case.inputs["water_density"].value if "water_density" in case.inputs else WATER_DENSITY
    friction = case.ocean["bottom_friction"].value
    waves = None
    if case.ocean["wave_height"].value > 0:
        # regular waves on FEMNET's surface z = 0 (felt in dynamics only), linear or, with 'input wave_model 2'
        # or 3, Stokes second order or third order in deep water (FEMNET's default is Airy); a depth of 0 is
        # deep water
        heading = math.radians(case.ocean["wave_direction"].value)
        depth = case.ocean["depth"].value
        model = int(case.inputs["wave_model"].value) if "wave_model" in case.inputs else 1
        theory = {1: waves_lib.Airy, 2: waves_lib.Stokes2, 3: waves_lib.Stokes3}[model]
        waves = theory(case.ocean["wave_height"].value, case.ocean["wave_period"].value,
                               direction=(math.cos(heading), math.sin(heading), 0.0),
                               depth=depth if depth > 0 else float("inf"), surface_level=0.0, gravity=GRAVITY)
    return Environment(gravity=GRAVITY, water_density=float(rho), up=np.array([0.0, 0.0, 1.0]),
                       current_speed=case.ocean["current_speed"].value,
                       current_direction=np.array([math.cos(angle), math.sin(angle), 0.0]),
                       bottom_stiffness=float(case.ocean["bottom_stiffness"].value), bottom_friction=float(friction),
                       bottom_band=0.0, waves=waves, surface_level=0.0, floating=("bars", "nodes"),
                       bottom_moving="moving_bottom" in case.inputs)


def symmetry_share(case: DonFile, node_type):
    """(N,) the share of its type's loads that each node carries in the modelled part of a symmetric net: 1/2 per
    symmetry plane the node lies on (its type's "Symmetry X,Y,Z" flags), 1 elsewhere.

    FEMNET's manual (its "Symmetry" section) defines a node type's mass, added mass, box ("Length") and external
    force for the whole structure: a node on a symmetry plane is shared by the modelled half and its mirror, so
    the half carries half of them (a quarter on two planes). Its statics do so by doubling, at such a node, the
    netting's and the bars' forces in the plane (``symetrie2.c``: ``wasurf`` and ``waelem`` times 2, the node's own
    loads ``wanoeud`` not), which gives the same equilibrium as halving the node's loads, as here. Measured on
    the bottom seines s1-s3 (FEMNET's equilibrium holds 5000 N at their two type-5 nodes of 10000 N along x)."""
    return np.array([0.5 ** sum(int(bool(s.value)) for s in case.types[t].symmetry) for t in node_type])


def node_type_fields(case: DonFile, position, node_type):
    """The nodes' box bodies, float volumes and limits from their types: {Nodes field: array}, a field absent when
    no node has a body (a float, a limit), so that its term is not compiled. FEMNET drags and floats the immersed
    part of a box under its surface z = 0, and so do jaxnet's scenes from FEMNET (their free surface is z = 0,
    :func:`environment_of`); ``info["boxes"]``: the nodes with a box and the height of its top above them. A box
    on a symmetry plane is the whole structure's (:func:`symmetry_share`): its volume and its drag coefficients
    (its drag is linear in them) are scaled by the node's share, its lengths, which set where it meets the
    surface, are kept."""
    types = [case.types[t] for t in node_type]
    share = symmetry_share(case, node_type)
    fields = {}
    volume = share * np.array([nt.box_volume for nt in types])
    if volume.any():
        # a box with a volume floats: FEMNET's buoyancy rho g L_x L_y h (flotteur2.c), h its immersed height under
        # the surface z = 0: the node's volume V = |L_x L_y L_z|, floated as a box by the surface term (the box's
        # height is drag_length's z)
        fields["volume"] = volume
    if any(nt.has_body for nt in types):
        length = np.array([[v.value for v in nt.length] if nt.has_body else [0.0] * 3 for nt in types])
        cd = share[:, None] * np.array([[v.value for v in nt.drag_coefficient] if nt.has_body else [0.0] * 3
                                        for nt in types])
        fields.update(drag_length=length, drag_coefficient=cd)
    if any(nt.has_limit for nt in types):
        fields["limit"] = np.array([[v.value if s.value else 0.0 for v, s in zip(nt.limit, nt.sense)] for nt in types])
        fields["limit_sense"] = np.array([[s.value for s in nt.sense] for nt in types], dtype=np.int32)
    return fields


def _solver(case: DonFile) -> Newton:
    """FEMNET's numerics as jaxnet's Newton options (the threshold as tol: see the package's docstring,
    "Convergence"), with the damped method: FEMNET's cases start from flat drawings far from their shape (trawls,
    seines, a gill net), where the damped method's stiffness continuation does better than the primal-dual method,
    which solves only 10 of FEMNET's 87 read cases within its budget (validation/REPORT.md, the robustness set's
    FEMNET family); ``jaxnet run CASE.don --method primal-dual`` chooses it."""
    n = case.numeric
    return Newton(tol=n["threshold"].value, max_iter=int(n["max_iter"].value), max_step=n["max_step"].value,
                  method="damped")


def check_types(case: DonFile):
    """Every node type a part names (its corners, sides, internal nodes, cable ends) must be described."""
    used = []
    for kind, k, p, name in all_panels(case):
        used += [(t, f"{name} corner {c + 1}") for c, t in enumerate(p.corner_type)]
        used += [(t, f"{name} side {c + 1}") for c, t in enumerate(p.side_type)]
        used += [(p.material["inner_type"], f"{name} internal nodes")]
    used += [(t, f"cable {k + 1} end {e + 1}") for k, c in enumerate(case.cables) for e, t in enumerate(c.end_type)]
    used += [(c.material["inner_type"], f"cable {k + 1} internal nodes") for k, c in enumerate(case.cables)]
    for t, what in used:
        if t.value not in case.types:
            raise SceneError(f"{case.path}:{t.line}: {what}: node type {t.value} is not described (types: "
                             f"{sorted(case.types)})")


#: FEMNET's drag coefficient of its spherical floats (manual: "the drag coefficient of sphere is expected to be 0.6")
SPHERE_CD = 0.6


def _sphere_lines(case: DonFile):
    """The case's ``sphere_element`` and ``sphere_element2`` lines: (cable index, count, diameter (m), net buoyancy of
    one sphere (N), the length (m) FEMNET spreads them over or None for the cable's, line), checked as FEMNET does."""
    out = []
    for name, values, line in case.commands:
        if name not in ("sphere_element", "sphere_element2"):
            continue
        k, count, diameter, buoyancy = int(values[0]), values[1], values[2], values[3]
        if k > len(case.cables):
            raise SceneError(f"{case.path}:{line}: 'input {name} {k}': there is no cable {k} (the case has "
                             f"{len(case.cables)})")
        limit = environment_of(case).water_density * GRAVITY * math.pi * diameter ** 3 / 6.0
        if buoyancy > limit:
            raise SceneError(f"{case.path}:{line}: 'input {name}': a sphere of {diameter!r} m cannot float {buoyancy!r} "
                             f"N (its volume holds at most {limit:.6g} N; FEMNET stops there too)")
        out.append((k - 1, count, diameter, buoyancy, values[4] if name == "sphere_element2" else None, line))
    return out


def spheres(case: DonFile, net: Net):
    """jaxnet's laws for ``input sphere_element CABLE COUNT D B`` (``femnet_laws=False``): COUNT spheres of diameter D
    (m), each pulling up with B newtons net of its weight, on the cable's nodes: floats of COUNT B newtons and a
    drag area COUNT 0.6 pi D²/4 shared equally by the nodes (each carries COUNT / (bars + 1) spheres), a sphere's
    drag acting along the flow whatever the cable's direction."""
    for k, count, diameter, buoyancy, _, _ in _sphere_lines(case):
        net.float(CableRef(f"cable {k + 1}").nodes, buoyancy_N=count * buoyancy,
                   drag_area=count * SPHERE_CD * math.pi * diameter ** 2 / 4.0)


def spheres_folded(case: DonFile) -> DonFile:
    """FEMNET's laws for spheres (``chargement_don.c``): the spheres are folded into their cable, whose diameter,
    volumic mass and normal Cd become those of the cable and its spheres together over a length L (the cable's
    unstretched length; ``sphere_element2``'s fifth value):

        V = L pi D_c²/4 + n pi D³/6,  M = V_c rho_c + n (rho pi D³/6 - B/g),  D_c' = sqrt(4 V / (L pi)),
        rho_c' = M / V,  Cd' = (n 0.6 pi D²/4 + L D_c Cd) / (L D_c').

    The cable's net buoyancy grows by n B exactly; the spheres' drag becomes a cross-flow drag of the cable."""
    lines = _sphere_lines(case)
    if not lines:
        return case
    cables = list(case.cables)
    rho = environment_of(case).water_density
    for k, count, diameter, buoyancy, length, line in lines:
        m = dict(cables[k].material)
        L = m["l0"].value if length is None else length
        d, density, cd = m["diameter"].value, m["density"].value, m["cd"].value
        sphere_volume = math.pi * diameter ** 3 / 6.0
        volume = L * math.pi * d * d / 4.0 + count * sphere_volume
        mass = L * math.pi * d * d / 4.0 * density + count * (sphere_volume * rho - buoyancy / GRAVITY)
        folded = math.sqrt(4.0 * volume / (L * math.pi))
        m["diameter"] = Value(folded, line)
        m["density"] = Value(mass / volume, line)
        m["cd"] = Value((count * SPHERE_CD * math.pi * diameter ** 2 / 4.0 + L * d * cd) / (L * folded), line)
        cables[k] = dataclasses.replace(cables[k], material=m)
    return dataclasses.replace(case, cables=cables)


def translated(case: DonFile) -> DonFile:
    """``input add_{x,y,z}_{ele,pan} D FIRST LAST``: cables (ele) or panels (pan) FIRST to LAST moved by D (m) along
    the axis before they are meshed and joined (the manual: "in case cables/bars are translated in the design")."""
    moves = [(name, values, line) for name, values, line in case.commands if name.startswith("add_")]
    if not moves:
        return case
    panels = [dataclasses.replace(p, corners=p.corners.copy()) for p in case.panels]
    cables = [dataclasses.replace(c, ends=c.ends.copy()) for c in case.cables]
    for name, (distance, first, last), line in moves:
        axis, parts = "xyz".index(name[4]), panels if name.endswith("pan") else cables
        if last > len(parts):
            raise SceneError(f"{case.path}:{line}: 'input {name}': there is no {'panel' if parts is panels else 'cable'} "
                             f"{int(last)} (the case has {len(parts)})")
        for part in parts[int(first) - 1:int(last)]:
            (part.corners if parts is panels else part.ends)[:, axis] += distance
    return dataclasses.replace(case, panels=panels, cables=cables)


#: FEMNET's windows of ``input type_noeud_XYZ_SUPINF MODE BOUNDS... TYPE`` (its manual's index): per mode, the
#: (axis, sense) of each bound in order: sense +1 "coordinate > bound", -1 "coordinate < bound"
WINDOWS = {1: ((0, 1),), 2: ((0, -1),), 3: ((1, 1),), 4: ((1, -1),), 5: ((2, 1),), 6: ((2, -1),),
           7: ((0, 1), (0, -1)), 8: ((1, 1), (1, -1)), 9: ((2, 1), (2, -1)),
           10: ((0, 1), (0, -1), (1, 1), (1, -1)), 11: ((1, 1), (1, -1), (2, 1), (2, -1)),
           12: ((2, 1), (2, -1), (0, 1), (0, -1)),
           13: ((0, 1), (0, -1), (1, 1), (1, -1), (2, 1), (2, -1))}


def retyped(case: DonFile, position, node_type):
    """``input type_noeud_XYZ_SUPINF``: the nodes whose start position lies strictly inside the command's window take
    its type (FEMNET applies it to its mesh's nodes, in the commands' order)."""
    node_type = list(node_type)
    for name, values, line in case.commands:
        if name != "type_noeud_xyz_supinf":
            continue
        mode, bounds, new = int(values[0]), values[1:-1], int(values[-1])
        if new not in case.types:
            raise SceneError(f"{case.path}:{line}: 'input type_noeud_XYZ_SUPINF': node type {new} is not described "
                             f"(types: {sorted(case.types)})")
        inside = np.ones(len(position), bool)
        for (axis, sense), bound in zip(WINDOWS[mode], bounds):
            inside &= sense * (np.asarray(position)[:, axis] - bound) > 0
        for i in np.flatnonzero(inside):
            node_type[i] = new
    return node_type


def _check_supported(case: DonFile):
    """What a case may read but jaxnet cannot model: said with the line that asks for it."""
    speed = case.ocean["current_speed"]
    if case.hexagonal and speed.value > 0:
        raise SceneError(f"{case.path}:{speed.line}: current speed {speed.value!r} m/s with hexagonal panels (hexagonal "
                         f"panel 1 at line {case.hexagonal[0].line}): jaxnet has no drag model for hexagonal netting yet")


def symmetry_planes(case: DonFile, position, node_type):
    """Symmetry planes used by the nodes: {axis: plane coordinate}; a plane must be flat at the start."""
    planes = {}
    for axis in range(3):
        on = [i for i, t in enumerate(node_type) if case.types[t].symmetry[axis].value]
        if not on:
            continue
        coords = position[on, axis]
        if np.ptp(coords) > 1e-6 * max(1.0, np.abs(coords).max()):
            t = node_type[on[int(np.argmax(np.abs(coords - coords[0])))]]
            raise SceneError(f"{case.path}:{case.types[t].line}: node type {t} puts nodes on a symmetry plane normal to "
                             f"{'XYZ'[axis]}, but they start at different {'xyz'[axis]} ({coords.min():.6g} to "
                             f"{coords.max():.6g} m)")
        planes[axis] = float(coords.mean())
    return planes


def gravity_catch_density(case: DonFile, env: Environment) -> float:
    """The density (kg/m³) of the case's gravity catch (``input catch_gravity RHO_C``; :mod:`jaxnet.terms.gravity_catch`),
    0 without one. FEMNET's statics (``unix.c``) give a gravity-catch case no netting drag at all (neither its twine
    drag nor the drag ahead of a catch): jaxnet does not reproduce that, so a gravity catch in a current is refused
    at its line."""
    if "catch_gravity" not in case.inputs:
        return 0.0
    line = case.inputs["catch_gravity"]
    if env.current_speed > 0 and case.catch["catch_volume"].value > 0:
        raise SceneError(f"{case.path}:{line.line}: 'input catch_gravity' with a current of {env.current_speed!r} m/s: "
                         "FEMNET then gives the netting no drag, which jaxnet does not reproduce (a gravity catch is "
                         "for a bag out of the water)")
    return float(line.value)


def catch_of(case: DonFile, position, netting_nodes, planes, env: Environment, density: float = 0.0):
    """(volume of the whole cod-end, Cd, copies, center, axis) of the catch, or None without one. ``density`` > 0:
    a gravity catch (:func:`gravity_catch_density`), whose axis is the vertical downward (FEMNET's
    ``changement_variable_catch``) and which needs no current."""
    volume = case.catch["catch_volume"].value
    if volume <= 0:
        return None
    if not env.current_speed > 0 and not density > 0:
        raise SceneError(f"{case.path}:{case.catch['catch_volume'].line}: a catch needs a current (its axis is the "
                         "current's direction)")
    copies = 2.0 ** len(planes)
    axis = -np.asarray(env.up, dtype=float) if density > 0 else np.asarray(env.current_direction, dtype=float)
    pts = position[netting_nodes]
    center = pts.mean(axis=0)
    for a, c in planes.items():
        center[a] = c
    # the opening: the most upstream netting node's abscissa along the axis
    center = center + (pts @ axis).min() * axis - (center @ axis) * axis
    return volume * copies, case.catch["catch_cd"].value, copies, center, axis


#: the axis along which FEMNET advances the fronts of its panel catches: x (``catch2_volume.c`` places each front
#: among the x coordinates of its panels' vertices, whatever the current's direction)
CATCH2_AXIS = (1.0, 0.0, 0.0)


def catch2_volumes(case: DonFile, planes):
    """The case's ``input catch2_volume V N P1 .. PN`` lines as [(the whole net's volume V x 2 per symmetry plane (m³),
    the 0-based diamond panels, the line)] (FEMNET compares its panels' volume with V as it is: V is the modelled
    part's). SceneError at the line naming a panel the case does not have, or one already holding a catch."""
    if "catch2_volume" not in case.inputs:
        return []
    copies, out, held = 2.0 ** len(planes), [], {}
    for occurrence in case.inputs["catch2_volume"].value:
        volume, panels = occurrence.values[0], [int(v) for v in occurrence.values[2:]]
        where = f"{case.path}:{occurrence.line}: 'input catch2_volume {volume:g}'"
        for k in panels:
            if k > len(case.panels):
                raise SceneError(f"{where}: panel {k} does not exist (diamond panels: 1..{len(case.panels)})")
            if k in held:
                raise SceneError(f"{where}: panel {k} already holds the catch of line {held[k]} (a panel holds at most one)")
            held[k] = occurrence.line
        out.append((volume * copies, [k - 1 for k in panels], occurrence.line))
    return out


def panel_catches(case: DonFile, net: Net, planes):
    """Each ``input catch2_volume`` line (:func:`catch2_volumes`) as a panel catch of the net (:meth:`Net.panel_catch`):
    the main catch's Cd (FEMNET's ``Prise.cd``), as many copies as the symmetry planes make, fronts along x
    (:data:`CATCH2_AXIS`)."""
    for volume, panels, _ in catch2_volumes(case, planes):
        net.panel_catch(volume, [f"panel {k + 1}" for k in panels], drag_coefficient=case.catch["catch_cd"].value,
                        symmetry=2.0 ** len(planes), axis=CATCH2_AXIS)


def panel_catches_of(case: DonFile, planes, n_panels):
    """The case's panel catches as a :class:`~jaxnet.scene.PanelCatches` over ``n_panels`` panels (as
    :func:`panel_catches` gives the Net), or None without any: for a scene built without a Net (FEMNET's mesh)."""
    volumes = catch2_volumes(case, planes)
    if not volumes:
        return None
    panel_catch = np.full(n_panels, -1, dtype=np.int32)
    for k, (_, panels, _) in enumerate(volumes):
        panel_catch[panels] = k
    return PanelCatches(volume=np.array([v for v, _, _ in volumes]), panel_catch=panel_catch,
                        drag_coefficient=float(case.catch["catch_cd"].value), axis=np.array(CATCH2_AXIS),
                        symmetry=2.0 ** len(planes))


def femnet_panel_catch_sides(scene):
    """The scene with the triangles of its panel catches oriented as FEMNET orients them: from the twine
    coordinates alone, not from the drawn shape (FEMNET's cases draw their cod-ends flat, in the design plane,
    where no side of a panel is outward). FEMNET's catch pressure is -p (12 ^ 13)/6 and 12 ^ 13 = d U ^ V (4.7), so
    the catch lies on the U ^ V side of every panel: ``Netting.outward`` = -sign(d), d the triangle's twine
    determinant in jaxnet's vertex order (:mod:`jaxnet.terms.pressure`, "Orientation")."""
    pc, netting = scene.panel_catches, scene.netting
    if pc is None or netting is None:
        return scene
    held = np.asarray(pc.panel_catch)[np.asarray(netting.panel)] >= 0
    sides = -np.sign(np.asarray(geometry.twine_determinant(np.asarray(netting.uv))))
    others = np.ones(held.shape) if netting.outward is None else np.asarray(netting.outward)
    outward = np.where(held, sides, others)
    return dataclasses.replace(scene, netting=dataclasses.replace(netting, outward=outward))


def _describe(case: DonFile, env: Environment, plan: JoinPlan, femnet_laws: bool = True, refine: float = 1.0) -> Net:
    """The panels and cables of the (joined) case on a new Net, sewn as ``plan`` says, meshed ``refine`` times
    finer than the file says (:func:`read_don`)."""
    net = Net(environment=env, merge_tolerance=MERGE_TOLERANCE)
    case = _with_cable_bending(case)
    twines = numerical_twines(case, femnet_laws)
    lattices = meshing_lattices(case)
    for kind, k, p, name in all_panels(case):
        step = p.material["step"].value / refine
        if kind == "pa":
            corners = np.concatenate([p.corners[:, :3], twine_coordinates(p.corners[:, 3:5])], axis=1)
            lattice, numerical = lattices.get(k), twines.get(k)
            if lattice is not None:
                lattice = (lattice[0] / refine, lattice[1] / refine)
            if numerical is not None:
                numerical = dataclasses.replace(numerical, bars=_finer(numerical.bars, refine))
            net.panel(name, corners, twine_of(p, case, femnet_laws), step, twines=numerical, lattice=lattice)
        else:
            # hexagonal: FEMNET's (U, V) count base meshes, as jaxnet's (see the package's docstring)
            net.panel(name, p.corners, _hextwine(p), step)
    for a, b in plan.seams:
        net.seam(a, b)
    for k, c in enumerate(case.cables):
        name, length = f"cable {k + 1}", c.material["l0"].value
        if k in plan.along:
            side, n_bars = plan.along[k]
            net.cable(name, along=side, rope=rope_of(c), length=length,
                      n_bars=None if n_bars is None else _finer(n_bars, refine))
        else:
            net.cable(name, start=tuple(c.ends[0]), end=tuple(c.ends[1]), rope=rope_of(c), length=length,
                      n_bars=_finer(plan.n_bars[k], refine))
    _weld_cables(case, net)
    return net


def _finer(count: int, refine: float) -> int:
    """A number of bars ``refine`` times larger (rounded up; the file's own count at ``refine`` 1)."""
    return int(count) if refine == 1.0 else max(1, int(math.ceil(count * refine - 1e-9)))


def _with_cable_bending(case: DonFile) -> DonFile:
    """The case with each cable's ``input EI_flexion_cable K EI`` (N·m²) in its material (key "ei", which
    :func:`rope_of` makes the rope's bending stiffness); a later line for the same cable replaces an earlier
    one, as in FEMNET. SceneError at the line naming a cable the case does not have."""
    if "ei_flexion_cable" not in case.inputs:
        return case
    cables = [dataclasses.replace(c, material=dict(c.material)) for c in case.cables]
    for occurrence in case.inputs["ei_flexion_cable"].value:
        k, ei = int(occurrence.values[0]), occurrence.values[1]
        if k > len(cables):
            raise SceneError(f"{case.path}:{occurrence.line}: 'input EI_flexion_cable {k}': no cable {k} (the case has "
                             f"{len(cables)} cable(s))")
        cables[k - 1].material["ei"] = Value(ei, occurrence.line)
    return dataclasses.replace(case, cables=cables)


def _weld_cables(case: DonFile, net: Net):
    """Each ``input link_flexion_elem2 A B angle`` as a joint between cables A and B (:meth:`Net.cable_joint`): the
    neutral angle the file's (degrees, 180 when aligned), the stiffness the smaller of the two cables' EI
    (FEMNET's ``pliage_barre_pardiso4.c``). The two cables must share an end (their ends are at FEMNET's joined
    positions here); SceneError at the line otherwise."""
    if "link_flexion_elem2" not in case.inputs:
        return
    for occurrence in case.inputs["link_flexion_elem2"].value:
        a, b, angle = int(occurrence.values[0]), int(occurrence.values[1]), occurrence.values[2]
        where = f"{case.path}:{occurrence.line}: 'input link_flexion_elem2 {a} {b}'"
        for k in (a, b):
            if k > len(case.cables):
                raise SceneError(f"{where}: no cable {k} (the case has {len(case.cables)} cable(s))")
        ends_a, ends_b = case.cables[a - 1].ends, case.cables[b - 1].ends
        gap = np.linalg.norm(ends_a[:, None, :] - ends_b[None, :, :], axis=-1).min()
        if gap > MERGE_TOLERANCE:
            raise SceneError(f"{where}: the cables have no end in common (their nearest ends are {gap:.6g} m apart)")
        net.cable_joint(f"cable {a}", f"cable {b}", math.radians(angle))


@contextlib.contextmanager
def _located(case: DonFile, what: str):
    """Name the file and the line of the part it names in a SceneError from jaxnet's Net (describing or
    building the net)."""
    try:
        yield
    except SceneError as err:
        if str(err).startswith(f"{case.path}:"):
            raise
        raise SceneError(f"{case.path}:{_culprit_line(case, str(err))}: {what}: {err}") from None


def _culprit_line(case: DonFile, message: str) -> int:
    """The line of the panel or cable a message names; else of the first node type (fixings, loads)."""
    m = re.search(r"(hexagonal panel|panel|cable) (\d+)", message)
    if m:
        parts = {"hexagonal panel": case.hexagonal, "panel": case.panels, "cable": case.cables}[m.group(1)]
        k = int(m.group(2)) - 1
        if 0 <= k < len(parts):
            return parts[k].line
    return min((t.line for t in case.types.values()), default=1)


def read_don(path, femnet_laws=True, refine=1.0):
    """Read FEMNET's ``.don`` case ``path`` into jaxnet.

    ``femnet_laws``: use FEMNET's own laws where they differ from the book (knot contact; netting drag in a
    case with a catch; ``docs/errata.md``), so that jaxnet gives FEMNET's answers (the default); False for
    jaxnet's own physics (the book's laws, corrected).

    ``refine``: mesh the case this many times finer than its file says (> 0; 1, the default, is FEMNET's
    mesh): every panel's meshing step and ``Meshing_UV`` lattice divided by it, the bars of every cable and
    of every numerical twine's period multiplied by it (rounded up). Nodes grow about as ``refine²``. For
    studies of mesh convergence (is FEMNET's mesh fine enough for a figure?) and of cost against size on
    real gear (``benchmarks/statics.py --scene trawl``). Node types go where the file puts them, on the
    finer mesh: a type's mass, force and body are per node, as in FEMNET, so where a side or a panel's interior
    has a loaded type, the finer mesh's more nodes carry more of it in all (as FEMNET's own mesh of a finer step
    would); corners and cable ends keep theirs.

    Returns:
      a :class:`~jaxnet.case.Case`: its ``net`` the :class:`~jaxnet.net.Net` (jaxnet meshes it) and ``scene``
      the built scene; ``solver`` the :class:`~jaxnet.solve.options.Newton` options (tol = FEMNET's threshold
      in N, max_iter, max_step = FEMNET's displacement limit in m); for a dynamic case (an end time > 0) its
      ``time`` settings (:func:`time_settings`); ``info`` a dict of what the reader decided (symmetry planes
      and copies, FEMNET's solver settings, the inputs and outputs, the depth, the joined points, seams and
      sewn cables, the added masses per node type, the sea bed and the node bodies read, ``refine``).
    Raises:
      SceneError naming the file and line (see the package's docstring).
    """
    try:
        finite = bool(np.isfinite(refine) and refine > 0) and not isinstance(refine, bool)
    except TypeError:
        finite = False
    if not finite:
        raise SceneError(f"{path}: refine (how many times finer than the file's mesh) must be a number > 0, got "
                         f"{refine!r}")
    refine = float(refine)
    case = translated(parse_don(path))
    if femnet_laws:
        case = spheres_folded(case)
    check_types(case)
    _check_supported(case)
    env = environment_of(case)
    plan = plan_joins(case)
    case = at_joined_positions(case, plan)
    # a first build, held at every corner and cable end, tells where jaxnet's mesher put the nodes: their
    # FEMNET types (and so the fixings and loads of the real net) follow from where they were created
    with _located(case, "meshing the case"):
        probe = _describe(case, env, plan, femnet_laws, refine)
        for kind, k, p, name in all_panels(case):
            for xyz in p.corners[:, :3]:
                probe.fix(tuple(xyz))
        for c in case.cables:
            for xyz in c.ends:
                probe.fix(tuple(xyz))
        scene = probe.build()
        net = _describe(case, env, plan, femnet_laws, refine)
    warnings = list(plan.warnings)
    node_type = _node_types(case, scene, warnings)
    position = np.asarray(scene.nodes.position)
    node_type = retyped(case, position, node_type)
    planes = symmetry_planes(case, position, node_type)
    for axis, at in sorted(planes.items()):
        net.symmetry_plane("xyz"[axis], at, hold=False)  # its nodes are held by their node types below
    held = np.zeros(3, bool)
    for i, t in enumerate(node_type):
        nt = case.types[t]
        axes = "".join(a for j, a in enumerate("xyz") if nt.fixed[j].value or nt.symmetry[j].value)
        held |= [a in axes for a in "xyz"]
        if axes:
            net.fix(tuple(position[i]), axes)
    gauge = gauge_of(case, position, held, warnings)
    if gauge is not None:
        net.fix(tuple(position[gauge[0]]), gauge[1])
    fields = node_type_fields(case, position, node_type)
    volume = fields.pop("volume", np.zeros(len(position)))
    share = symmetry_share(case, node_type)
    for i, t in enumerate(node_type):
        nt = case.types[t]
        if nt.mass[0] > 0 or any(nt.force) or volume[i] > 0:
            net.attach(tuple(position[i]), mass=share[i] * nt.mass[0], force=tuple(share[i] * np.asarray(nt.force)),
                       volume=volume[i])
    for i, t in enumerate(node_type):
        if "drag_length" in fields and case.types[t].has_body:
            net.body(tuple(position[i]), fields["drag_length"][i], fields["drag_coefficient"][i])
        if "limit" in fields and case.types[t].has_limit:
            net.limit(tuple(position[i]), fields["limit"][i], fields["limit_sense"][i])
    if not femnet_laws:
        spheres(case, net)
    netting_nodes = np.unique(np.asarray(scene.netting.vertices)) if scene.netting is not None else np.arange(len(position))
    density = gravity_catch_density(case, env)
    catch = catch_of(case, position, netting_nodes, planes, env, density)
    panel_catches(case, net, planes)
    with _located(case, "the net with its node types"):
        if catch is not None:
            volume, cd, copies, center, axis = catch
            net.catch(volume, drag_coefficient=cd, symmetry=copies, center=tuple(center), axis=tuple(axis),
                      density=density)
        scene = femnet_panel_catch_sides(net.build())
    scene = with_added_masses(case, scene, node_type, share)
    finer = "" if refine == 1.0 else f", meshed {refine:g} times finer than its file"
    out = result(case, scene, net, planes, catch, femnet_laws, plan, label=f"FEMNET case {case.path}{finer}",
                 warnings=warnings, node_type=node_type)
    out.info["global_nodes"] = _global_nodes(plan, np.asarray(scene.nodes.position))
    out.info["refine"] = refine  # the mesh, this many times finer than the file's
    if gauge is not None:
        out.info["gauge"] = {"node": gauge[0], "axes": gauge[1]}
    return out


def with_added_masses(case: DonFile, scene, node_type, share):
    """``scene`` with FEMNET's added masses (``Nodes.added_mass``, kg per axis): each node's type's "Added mass
    X,Y,Z", shared over the symmetry planes as its mass is (``share``: FEMNET's manual gives the masses of the
    whole structure). They act in dynamics only (``lectureDo4.c``: "n'intervient qu'en dynamique"); a case
    with none is returned as it is."""
    added = np.array([share[i] * np.asarray(case.types[t].added_mass, dtype=float) for i, t in enumerate(node_type)])
    if not added.any():
        return scene
    return eqx.tree_at(lambda s: s.nodes.added_mass, scene, added, is_leaf=lambda v: v is None)


def _global_nodes(plan: JoinPlan, position):
    """The scene's node of each of FEMNET's global nodes (the joined points, numbered as FEMNET numbers them: its
    text outputs name nodes by these numbers): [node index] for global node 1, 2, ..."""
    out = []
    for point in plan.global_nodes:
        d = np.linalg.norm(position - point, axis=1)
        out.append(int(np.argmin(d)))
    return out


def gauge_of(case: DonFile, position, held, warnings):
    """A net that no node holds along some axis (but along another) is free to translate along it: FEMNET's solver
    finds one of its equilibria (its added diagonal stiffness holds it), which exist when the loads along that axis
    balance. jaxnet holds the node nearest the net's centre along those axes instead (the gauge: its reaction is
    the loads' imbalance, zero at an equilibrium of the free net) and says so. (node, axes) or None."""
    if held.all() or not held.any():
        return None
    axes = "".join(a for a, h in zip("xyz", held) if not h)
    node = int(np.argmin(np.linalg.norm(position - position.mean(axis=0), axis=1)))
    warnings.append(f"{case.path}: no node type holds the net along {axes}: FEMNET's net is free to translate along it; "
                    f"jaxnet holds node {node} at {np.round(position[node], 6).tolist()} along {axes} (its reaction is "
                    "zero at an equilibrium of the free net)")
    return node, axes


def released_gauge(case: Case):
    """The scene of ``case`` (read by :func:`read_don` or :func:`~.mdg.read_mdg`) with its gauge node
    (:func:`gauge_of`, ``info["gauge"]``) free again, for a run in time: there the nodes' masses hold a net that
    no node type holds along an axis, and the loads along it need not balance (FEMNET's ``dyna`` has no gauge:
    s4_traction's seine, pulled by 7 kN along x, slides). The case's scene as it is without a gauge."""
    gauge = case.info.get("gauge")
    if gauge is None:
        return case.scene
    fixed = np.array(case.scene.nodes.fixed, dtype=bool)
    fixed[int(gauge["node"]), ["xyz".index(a) for a in gauge["axes"]]] = False
    return eqx.tree_at(lambda s: s.nodes.fixed, case.scene, fixed)


def result(case: DonFile, scene, net, planes, catch, femnet_laws, plan: JoinPlan | None = None, label="",
           warnings=(), node_type=None) -> Case:
    """What :func:`read_don` and :func:`~.mdg.read_mdg` return: the :class:`~jaxnet.case.Case` of ``scene``
    (built from ``net``, or read whole: None), with the Newton options of the case's numerics, its time settings
    (:func:`time_settings`) and ``info``, what the reader decided (:func:`_info`) and whether FEMNET's laws were
    used. ``planes``: the symmetry planes {axis: coordinate}; ``catch``: :func:`catch_of`'s tuple or None;
    ``plan``: the joins (None on FEMNET's mesh, which has its own)."""
    solver = _solver(case)
    info = {**_info(case, planes, catch, plan), "femnet_laws": bool(femnet_laws), "warnings": case.warnings + list(warnings)}
    if node_type is not None:
        # the coordinates FEMNET holds by a node type's "Displacement" and not on a symmetry plane: its "forces
        # along X Y and Z axes" sum the reactions there (femnet_figures; FEMNET's effortstructur.c skips a
        # coordinate whose type has its "Symmetry" set even where "Displacement" also holds it)
        info["fixity"] = [[int(i), j] for i, t in enumerate(node_type) for j in range(3)
                          if case.types[t].fixed[j].value and not case.types[t].symmetry[j].value]
        # FEMNET's node boxes (floats, bodies with drag): the nodes that have one and the height of its top above
        # them (m), for the reports (which boxes rest at the surface z = 0)
        info["boxes"] = {int(i): max(case.types[t].length[2].value, 0.0) for i, t in enumerate(node_type)
                         if case.types[t].box_volume > 0 or case.types[t].has_body}
    time = time_settings(case, solver, node_type, scene, info["warnings"])
    return Case(scene=scene, solver=solver, time=time, net=net, label=label, info=info)


TOWING = "speed_type_node2"


def towing_of(case: DonFile, node_type) -> tuple:
    """The prescribed motions of FEMNET's ``input speed_type_node2 TYPE K`` and its table (times, then the speeds
    along x, y and z at them): the nodes of TYPE moved by a :class:`jaxnet.water.forcing.SpeedTable`, as FEMNET's
    ``dyna`` moves them (``mvb``: the interpolated speed within the table's times, standing still outside). A
    case without it, or read without node types, has none. FEMNET holds the towed coordinates while it moves
    them; jaxnet holds its prescribed nodes throughout, so the type must hold them on every axis: a
    SceneError naming the line says so otherwise."""
    from jaxnet.water import forcing

    if TOWING not in case.inputs or node_type is None:
        return ()
    line = case.inputs[TOWING]
    values = np.asarray(line.value, dtype=float)
    t, k = int(values[0]), int(values[1])
    table = values[2:].reshape(4, k)
    if t not in case.types:
        raise SceneError(f"{case.path}:{line.line}: 'input {TOWING}': node type {t} is not described")
    if not all(bool(f.value) for f in case.types[t].fixed):
        raise SceneError(f"{case.path}:{line.line}: 'input {TOWING}': the nodes of type {t} are towed but not held on "
                         "every axis (its 'Displacement X,Y,Z' 1 1 1): jaxnet moves only held nodes")
    nodes = np.array([i for i, typ in enumerate(node_type) if typ == t], dtype=np.int64)
    if nodes.size == 0:
        return ()
    try:
        table_motion = forcing.SpeedTable(table[0], table[1:].T)
    except ValueError as err:
        raise SceneError(f"{case.path}:{line.line}: 'input {TOWING}': {err}") from None
    return (forcing.PrescribedMotion(nodes, table_motion),)


WINCHES = ("hauling_cable4", "hauling_cable6")


def cable_in_order(case: DonFile, scene, k: int, where: str) -> np.ndarray:
    """The bar indices of FEMNET's cable ``k`` (0-based) in the scene, in their order from its extremity 1 to its
    extremity 2 (the chain of its bars walked from the end nearest the .don's extremity 1). SceneError, naming
    ``where``, for a cable whose bars do not make one open chain."""
    bars = np.asarray(scene.bars.cable) if scene.bars is not None else np.zeros(0, dtype=int)
    mine = np.flatnonzero(bars == k)
    if mine.size == 0:
        raise SceneError(f"{where}: cable {k + 1} has no bars in the scene")
    ends = np.asarray(scene.bars.ends)[mine]
    touching = {}
    for b, (i, j) in enumerate(ends.tolist()):
        touching.setdefault(i, []).append(b)
        touching.setdefault(j, []).append(b)
    tips = [n for n, at in touching.items() if len(at) == 1]
    if len(tips) != 2 or any(len(at) > 2 for at in touching.values()):
        raise SceneError(f"{where}: the bars of cable {k + 1} do not make one open chain: a winch needs its ends")
    position = np.asarray(scene.nodes.position)
    start = min(tips, key=lambda n: float(np.linalg.norm(position[n] - case.cables[k].ends[0])))
    order, node, seen = [], start, set()
    while True:
        step = [b for b in touching[node] if b not in seen]
        if not step:
            break
        b = step[0]
        seen.add(b)
        order.append(int(mine[b]))
        i, j = ends[b]
        node = j if i == node else i
    if len(order) != mine.size:
        raise SceneError(f"{where}: the bars of cable {k + 1} do not make one open chain: a winch needs its ends")
    return np.array(order, dtype=np.int64)


def winches_of(case: DonFile, scene, warnings: list) -> tuple:
    """The winches (:class:`jaxnet.water.forcing.Winch`) of FEMNET's ``input hauling_cable4 CABLE MIN MAX K`` and its
    table (the times, the hauling speeds in m/s, > 0 hauling in, < 0 paying out, the extremity hauled from), as
    FEMNET's ``dyna`` applies them (``hauling_cable``/``find_bar``): hauling in shortens the cable's bars from the
    extremity given, each down to MIN; paying out lengthens them from the other extremity, each up to MAX (the
    drum is at the extremity given). The drum's bar is the one at that extremity. A table whose speed changes
    sign, or whose extremity changes, is refused naming its line (FEMNET then changes the bar it starts from;
    jaxnet's winch takes its bars in one order). ``hauling_cable6`` (in the corpus, not in FEMNET's manual) is
    read as ``hauling_cable4``, which has the same line, with a warning."""
    from jaxnet.water import forcing

    out = []
    for name, values, line in case.commands:
        if name not in WINCHES:
            continue
        where = f"{case.path}:{line}: 'input {name}'"
        values = np.asarray(values, dtype=float)
        cable, k = int(values[0]), int(values[3])
        shortest, longest = values[1], values[2]
        times, speeds, extremity = values[4:].reshape(3, k)
        if not 1 <= cable <= len(case.cables):
            raise SceneError(f"{where}: cable {cable} is not described (the case has {len(case.cables)})")
        used = extremity[:-1] if k > 1 else extremity
        if not (set(used.tolist()) <= {1.0, 2.0}) or len(set(used.tolist())) != 1:
            raise SceneError(f"{where}: the extremity hauled from must be 1 or 2, the same in every row but the "
                             f"last (jaxnet's winch takes its bars in one order), got {extremity.tolist()}")
        if (speeds > 0).any() and (speeds < 0).any():
            raise SceneError(f"{where}: the speeds must all haul in (>= 0) or all pay out (<= 0), got "
                             f"{speeds.tolist()} (jaxnet's winch takes its bars in one order)")
        order = cable_in_order(case, scene, cable - 1, where)
        at_drum = order if extremity[0] == 1.0 else order[::-1]
        paying_out = (speeds < 0).any()
        try:
            winch = forcing.Winch(at_drum[::-1] if paying_out else at_drum, drum_bar=int(at_drum[0]), times=times,
                                  speeds=speeds, shortest=shortest, longest=longest)
        except ValueError as err:
            raise SceneError(f"{where}: {err}") from None
        if name == "hauling_cable6":
            warnings.append(f"{where}: not in FEMNET's manual; read as 'input hauling_cable4', which has the same line")
        out.append(winch)
    return tuple(out)


def time_settings(case: DonFile, solver: Newton, node_type=None, scene=None, warnings=None) -> TimeSettings | None:
    """FEMNET's dynamic settings as a run in time, None for a static case (end time 0): to the end of its
    records, a record every "record time step", steps of its "time step", each step's Newton the time steps'
    own (:data:`jaxnet.solve.options.TIME_STEP`) with the case's threshold, iterations and displacement limit
    (``solver``, FEMNET's numerics: its dynamics iterates each step to the same criterion). FEMNET's
    "beginning time of record" is kept in ``info`` only: jaxnet records from the start. Its towing speeds
    (:func:`towing_of`, given the scene's ``node_type``) are the loading's motions, its winches
    (:func:`winches_of`, given the ``scene``; their warnings appended to ``warnings``) the loading's winches."""
    n = case.numeric
    if not n["record_end"].value > 0:
        return None
    from jaxnet.water.forcing import Loading

    newton = dataclasses.replace(TIME_STEP, tol=solver.tol, max_iter=solver.max_iter, max_step=solver.max_step)
    return TimeSettings(end_time=n["record_end"].value, record_every=n["record_dt"].value,
                        solver=Implicit(time_step=n["dt"].value, newton=newton),
                        loading=Loading(motions=towing_of(case, node_type),
                                        winches=() if scene is None else winches_of(
                                            case, scene, [] if warnings is None else warnings)))


def _info(case: DonFile, planes, catch, plan: JoinPlan | None = None):
    """The dict ``info`` of :func:`read_don` (see there), JSON-compatible (the CLI writes it into result.json)."""
    along = {} if plan is None else plan.along
    differences = []
    if any(p.material["opening"].value > 0 for p in case.panels):
        differences.append("mesh opening stiffness: the book's law (FEMNET's flexion2 applies 4.218 as printed: its "
                           "couple is 2 H cos(a) (a - a0)); docs/errata.md")
    return {
        "laws_differing_from_femnet": differences,
        "source": case.path,
        "symmetry_axes": ["xyz"[a] for a in sorted(planes)],
        "symmetry_planes_m": {"xyz"[a]: c for a, c in planes.items()},
        "copies": 2 ** len(planes),
        "catch_volume_modelled_m3": case.catch["catch_volume"].value,
        "catch_volume_whole_m3": None if catch is None else catch[0],
        "femnet_threshold_N": case.numeric["threshold"].value,
        "femnet_criterion": "mean nodal residual norm (jaxnet: largest nodal residual, same threshold)",
        "femnet_max_iterations": int(case.numeric["max_iter"].value),
        "displacement_limit_m": case.numeric["max_step"].value,
        "depth_m": case.ocean["depth"].value,
        "water_density": environment_of(case).water_density,
        "inputs": {k: v.value for k, v in case.inputs.items()},
        "outputs": list(case.outputs),
        # FEMNET's commands that act in its dynamics only, left out of a static run (the winches)
        "dynamic_only": [f"input {name} (line {line})" for name, values, line in case.commands
                         if INPUTS[name].use == "dynamic"],
        # commands FEMNET itself does nothing with
        "ignored": [f"input {name} (line {line})" for name, values, line in case.commands if INPUTS[name].use == "ignored"],
        "design_plane_axis": case.orientation,
        "text_outputs": [dataclasses.asdict(t) for t in case.text_outputs],
        "cables_sewn_along_sides": {f"cable {k + 1}": f"{side.panel} side {side.index + 1}"
                                    for k, (side, _) in sorted(along.items())},
        "seams": [] if plan is None else [f"{a.panel} side {a.index + 1} = {b.panel} side {b.index + 1}"
                                          for a, b in plan.seams],
        "joined": [] if plan is None else plan.joined,
        # FEMNET's added mass acts in dynamics only (lectureDo4.c): read, kept here, without effect in statics
        "added_mass": {t: list(nt.added_mass) for t, nt in sorted(case.types.items())},
        # FEMNET's dynamic settings (None for a static case): what `jaxnet run CASE.don --dynamic` uses
        "dynamic": None if not case.numeric["record_end"].value > 0 else {
            "time_step_s": case.numeric["dt"].value, "record_every_s": case.numeric["record_dt"].value,
            "record_start_s": case.numeric["record_start"].value, "end_time_s": case.numeric["record_end"].value},
        "sea_bed": {"stiffness_N_per_m": case.ocean["bottom_stiffness"].value,
                    "moving_bottom": "moving_bottom" in case.inputs,
                    "friction": environment_of(case).bottom_friction,
                    "limits": {t: {"limit_m": [v.value for v in nt.limit], "sense": [v.value for v in nt.sense]}
                               for t, nt in sorted(case.types.items()) if nt.has_limit}},
        "node_bodies": {t: {"length_m": [v.value for v in nt.length],
                            "drag_coefficient": [v.value for v in nt.drag_coefficient]}
                        for t, nt in sorted(case.types.items()) if nt.has_body},
        "hexagonal_twine_diameter_m": {f"hexagonal panel {k + 1}": _hexagonal_diameter(
            [v.value for v in p.material["l0"]], [v.value for v in p.material["diameter"]])
            for k, p in enumerate(case.hexagonal)},
    }


def _on_segment(points, a, b, tol):
    """(N,) True where a point lies strictly inside segment a-b (m)."""
    ab = b - a
    t = (points - a) @ ab / max(ab @ ab, 1e-300)
    d = np.linalg.norm(points - a - t[:, None] * ab, axis=1)
    return (d <= tol) & (t > 1e-9) & (t < 1 - 1e-9)


def _twine_nodes(scene, name):
    """The nodes of the numerical twines of panel ``name`` (the bars of its cable "<name> twines"), or none."""
    label = f"{name} twines"
    if scene.bars is None or label not in scene.cable_names:
        return np.zeros(0, dtype=np.int64)
    return np.unique(np.asarray(scene.bars.ends)[np.asarray(scene.bars.cable) == scene.cable_names.index(label)])


def _node_types(case: DonFile, scene, warnings=None):
    """Node type of every scene node, from where it was created (see the package's docstring). Points joined into one
    node with different types of the same rank (two corners, two cable ends): FEMNET warns and keeps one; here the
    first met (panels before cables, in the file's order) is kept and the conflict appended to ``warnings``."""
    pos = np.asarray(scene.nodes.position)
    n = len(pos)
    tol = 1e-7 * max(1.0, float(np.abs(pos).max()))
    # (priority, type, what): a corner's own type wins over a side's or an element's internal type
    claims = [dict() for _ in range(n)]

    def claim(nodes, priority, t, what):
        for i in np.atleast_1d(nodes):
            have = claims[i].get(priority)
            if have is not None and have[0].value != t.value:
                message = (f"{case.path}:{t.line}: node at {pos[i].round(6).tolist()} is given type {t.value} "
                           f"({what}) and type {have[0].value} ({have[1]}, line {have[0].line}): type "
                           f"{have[0].value} kept")
                if warnings is None:
                    raise SceneError(message.removesuffix(f": type {have[0].value} kept"))
                warnings.append(message)
                continue
            claims[i][priority] = (t, what)

    def at(point):
        return np.flatnonzero(np.linalg.norm(pos - point, axis=1) <= tol)

    nettings = [f for f in (scene.netting, scene.hexagonal) if f is not None]
    panel_of = np.concatenate([np.asarray(f.panel) for f in nettings]) if nettings else np.zeros(0, int)
    tri = np.concatenate([np.asarray(f.vertices) for f in nettings]) if nettings else np.zeros((0, 3), int)
    for j, (kind, k, p, name) in enumerate(all_panels(case)):
        nodes = np.union1d(np.unique(tri[panel_of == j]), _twine_nodes(scene, name))
        claim(nodes, 0, p.material["inner_type"], f"{name} internal nodes")
        C = len(p.corners)
        for c in range(C):
            a, b = p.corners[c, :3], p.corners[(c + 1) % C, :3]
            claim(nodes[_on_segment(pos[nodes], a, b, tol)], 1, p.side_type[c], f"{name} side {c + 1}")
            claim(at(a), 2, p.corner_type[c], f"{name} corner {c + 1}")
    if scene.bars is not None:
        ends, cable_of = np.asarray(scene.bars.ends), np.asarray(scene.bars.cable)
        for k, c in enumerate(case.cables):
            nodes = np.unique(ends[cable_of == k])
            inner = nodes[[not (np.linalg.norm(pos[i] - c.ends[0]) <= tol or np.linalg.norm(pos[i] - c.ends[1]) <= tol)
                           for i in nodes]]
            claim(inner, 1, c.material["inner_type"], f"cable {k + 1} internal nodes")
            for e in range(2):
                claim(at(c.ends[e]), 2, c.end_type[e], f"cable {k + 1} end {e + 1}")
    out = []
    for i in range(n):
        if not claims[i]:
            raise SceneError(f"{case.path}:{_culprit_line(case, '')}: node {i} at {pos[i].tolist()} belongs to no "
                             "panel or cable")
        out.append(claims[i][max(claims[i])][0].value)
    return out
