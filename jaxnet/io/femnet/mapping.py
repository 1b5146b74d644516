"""A parsed ``.don`` file (:class:`~.grammar.DonFile`) made into a :class:`~jaxnet.case.Case`: :func:`read_don`
describes the net with the :class:`~jaxnet.net.Net` builder (jaxnet meshes the panels), from its materials
(:mod:`.materials`), its surroundings, node types and catches (:mod:`.surroundings`) and what moves in time
(:mod:`.motion`); :func:`result` assembles the case, which :func:`~.mdg.read_mdg` shares on FEMNET's own mesh.
The conventions are the package's docstring's.
"""

from __future__ import annotations

import dataclasses
import math

import equinox as eqx
import numpy as np

from jaxnet.case import Case
from jaxnet.io.femnet.grammar import INPUTS, DonFile, twine_coordinates
from jaxnet.io.femnet.links import MERGE_TOLERANCE, JoinPlan, all_panels, at_joined_positions, plan_joins
from jaxnet.io.femnet.materials import hexagonal_diameter, hextwine, meshing_lattices, rope_of, twine_of
from jaxnet.io.femnet.motion import time_settings
from jaxnet.io.femnet.parse import parse_don
from jaxnet.io.femnet.reader import Value
from jaxnet.io.femnet.surroundings import (catch_of, check_types, environment_of, femnet_panel_catch_sides,
                                           gravity_catch_density, located, node_type_fields, node_types,
                                           panel_catches, retyped, spheres, spheres_folded, symmetry_planes,
                                           symmetry_share, translated, with_added_masses)
from jaxnet.io.femnet.twines import numerical_twines
from jaxnet.net import Net
from jaxnet.scene import Environment, SceneError
from jaxnet.solve.options import Newton


def _solver(case: DonFile) -> Newton:
    """FEMNET's numerics as jaxnet's Newton options (the threshold as tol: see the package's docstring,
    "Convergence"), with the damped method: FEMNET's cases start from flat drawings far from their shape (trawls,
    seines, a gill net), where the damped method's stiffness continuation does better than the primal-dual method,
    which solves only 10 of FEMNET's 87 read cases within its budget (validation/REPORT.md, the robustness set's
    FEMNET family); ``jaxnet run CASE.don --method primal-dual`` chooses it."""
    n = case.numeric
    return Newton(tol=n["threshold"].value, max_iter=int(n["max_iter"].value), max_step=n["max_step"].value,
                  method="damped")


def _check_supported(case: DonFile):
    """What a case may read but jaxnet cannot model: said with the line that asks for it."""
    speed = case.ocean["current_speed"]
    if case.hexagonal and speed.value > 0:
        raise SceneError(f"{case.path}:{speed.line}: current speed {speed.value!r} m/s with hexagonal panels (hexagonal "
                         f"panel 1 at line {case.hexagonal[0].line}): jaxnet has no drag model for hexagonal netting yet")


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
            net.panel(name, p.corners, hextwine(p), step)
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
    with located(case, "meshing the case"):
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
    node_type = node_types(case, scene, warnings)
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
    with located(case, "the net with its node types"):
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
        "hexagonal_twine_diameter_m": {f"hexagonal panel {k + 1}": hexagonal_diameter(
            [v.value for v in p.material["l0"]], [v.value for v in p.material["diameter"]])
            for k, p in enumerate(case.hexagonal)},
    }
