"""The surroundings of a FEMNET case in jaxnet's terms: the water and its current, waves and sea bed
(:func:`environment_of`), the node types (fixings, limits, bodies, added masses), the symmetry planes, the spheres
of floats, and the catches (the main catch, the panel catches). The conventions are the package's docstring's
(:mod:`jaxnet.io.femnet`); a message about the file names its line (:func:`located`)."""

from __future__ import annotations

import contextlib
import dataclasses
import math
import re

import equinox as eqx
import numpy as np

from jaxnet import geometry
from jaxnet.io.femnet.grammar import DonFile
from jaxnet.io.femnet.links import all_panels
from jaxnet.io.femnet.reader import Value
from jaxnet.net import CableRef, Net
from jaxnet.scene import Environment, PanelCatches, SceneError
from jaxnet.water import waves as waves_lib


#: FEMNET's default water density (kg/m³, phobos ``chargement_don.c``: RHO = 1025)
WATER_DENSITY = 1025.0


#: the acceleration of gravity (m/s²), FEMNET's
GRAVITY = 9.81


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


def sphere_lines(case: DonFile):
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
    for k, count, diameter, buoyancy, _, _ in sphere_lines(case):
        net.float(CableRef(f"cable {k + 1}").nodes, buoyancy_N=count * buoyancy,
                   drag_area=count * SPHERE_CD * math.pi * diameter ** 2 / 4.0)


def spheres_folded(case: DonFile) -> DonFile:
    """FEMNET's laws for spheres (``chargement_don.c``): the spheres are folded into their cable, whose diameter,
    volumic mass and normal Cd become those of the cable and its spheres together over a length L (the cable's
    unstretched length; ``sphere_element2``'s fifth value):

        V = L pi D_c²/4 + n pi D³/6,  M = V_c rho_c + n (rho pi D³/6 - B/g),  D_c' = sqrt(4 V / (L pi)),
        rho_c' = M / V,  Cd' = (n 0.6 pi D²/4 + L D_c Cd) / (L D_c').

    The cable's net buoyancy grows by n B exactly; the spheres' drag becomes a cross-flow drag of the cable."""
    lines = sphere_lines(case)
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


@contextlib.contextmanager
def located(case: DonFile, what: str):
    """Name the file and the line of the part it names in a SceneError from jaxnet's Net (describing or
    building the net)."""
    try:
        yield
    except SceneError as err:
        if str(err).startswith(f"{case.path}:"):
            raise
        raise SceneError(f"{case.path}:{culprit_line(case, str(err))}: {what}: {err}") from None


def culprit_line(case: DonFile, message: str) -> int:
    """The line of the panel or cable a message names; else of the first node type (fixings, loads)."""
    m = re.search(r"(hexagonal panel|panel|cable) (\d+)", message)
    if m:
        parts = {"hexagonal panel": case.hexagonal, "panel": case.panels, "cable": case.cables}[m.group(1)]
        k = int(m.group(2)) - 1
        if 0 <= k < len(parts):
            return parts[k].line
    return min((t.line for t in case.types.values()), default=1)


def with_added_masses(case: DonFile, scene, node_type, share):
    """``scene`` with FEMNET's added masses (``Nodes.added_mass``, kg per axis): each node's type's "Added mass
    X,Y,Z", shared over the symmetry planes as its mass is (``share``: FEMNET's manual gives the masses of the
    whole structure). They act in dynamics only (``lectureDo4.c``: "n'intervient qu'en dynamique"); a case
    with none is returned as it is."""
    added = np.array([share[i] * np.asarray(case.types[t].added_mass, dtype=float) for i, t in enumerate(node_type)])
    if not added.any():
        return scene
    return eqx.tree_at(lambda s: s.nodes.added_mass, scene, added, is_leaf=lambda v: v is None)


def on_segment(points, a, b, tol):
    """(N,) True where a point lies strictly inside segment a-b (m)."""
    ab = b - a
    t = (points - a) @ ab / max(ab @ ab, 1e-300)
    d = np.linalg.norm(points - a - t[:, None] * ab, axis=1)
    return (d <= tol) & (t > 1e-9) & (t < 1 - 1e-9)


def twine_nodes(scene, name):
    """The nodes of the numerical twines of panel ``name`` (the bars of its cable "<name> twines"), or none."""
    label = f"{name} twines"
    if scene.bars is None or label not in scene.cable_names:
        return np.zeros(0, dtype=np.int64)
    return np.unique(np.asarray(scene.bars.ends)[np.asarray(scene.bars.cable) == scene.cable_names.index(label)])


def node_types(case: DonFile, scene, warnings=None):
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
        nodes = np.union1d(np.unique(tri[panel_of == j]), twine_nodes(scene, name))
        claim(nodes, 0, p.material["inner_type"], f"{name} internal nodes")
        C = len(p.corners)
        for c in range(C):
            a, b = p.corners[c, :3], p.corners[(c + 1) % C, :3]
            claim(nodes[on_segment(pos[nodes], a, b, tol)], 1, p.side_type[c], f"{name} side {c + 1}")
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
            raise SceneError(f"{case.path}:{culprit_line(case, '')}: node {i} at {pos[i].tolist()} belongs to no "
                             "panel or cable")
        out.append(claims[i][max(claims[i])][0].value)
    return out
