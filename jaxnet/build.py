"""Building a :class:`~jaxnet.net.Net` into a :class:`~jaxnet.scene.Scene`: mesh every panel, join panels, seams and
cables into one set of nodes, and lay out the element families, what is attached to the nodes, the catch and the
environment as arrays (:meth:`jaxnet.net.Net.build` calls :func:`scene_of`).

The joining rules are the net's (:mod:`jaxnet.net`, module docstring). What the build made of the description
(each panel's mesh, the nodes of panels, cables, fixings and attachments) is returned beside the scene as a
:class:`~jaxnet.net.Layout`, which the design spaces (:mod:`jaxnet.design.space`) read.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.materials import HexTwine, bar_columns, netting_rows
from jaxnet.mesh.hinges import netting_hinges
from jaxnet.mesh.joining import NodeJoiner
from jaxnet.mesh.panel import lattice_divisions, mesh_panel
from jaxnet.mesh.polygon import PanelError, side_divisions
from jaxnet.mesh.twines import mesh_twines, numerical_twine_rope
from jaxnet.net import CableEnd, CableNodes, CableRef, Corner, Layout, Nearest, PanelRef, Side, describe_reference
from jaxnet.scene import Bars, CableJoints, Netting, Nodes, Scene, SceneError, on_symmetry_planes


def scene_of(net) -> tuple[Scene, Layout]:
    """Mesh every panel of ``net`` (:class:`~jaxnet.net.Net`), join panels, seams and cables, and lay out what
    is attached: (the :class:`Scene`, validated; the :class:`~jaxnet.net.Layout` of what was made of the
    description)."""
    if not net.panels and not net.cables:
        raise SceneError("the net has no panel and no cable")
    divisions = _side_divisions(net)
    builder = NodeJoiner(net.merge_tolerance)
    meshes = {}
    for p in net.panels.values():
        try:
            if p.twines is not None:
                m = mesh_twines(p.corners[:, 3:5], p.corners[:, 0:3], p.twines, divisions=divisions[p.name],
                                name=p.name)
            else:
                m = mesh_panel(p.corners[:, 3:5], p.corners[:, 0:3], p.step, _mesh_length(p.twine), divisions=divisions[p.name], name=p.name,
                               lattice=p.lattice)
        except PanelError as err:
            raise SceneError(str(err)) from err
        offset = builder.add_nodes(m.xyz)
        meshes[p.name] = (m, offset[0])
        builder.mergeable(offset[m.corner_nodes])
    for a, b in net.seams:
        ia = _side_nodes(net, meshes, a)
        ib = _side_nodes(net, meshes, b)
        xa, xb = builder.position(ia), builder.position(ib)
        same = np.linalg.norm(xa[0] - xb[0]) + np.linalg.norm(xa[-1] - xb[-1])
        flipped = np.linalg.norm(xa[0] - xb[-1]) + np.linalg.norm(xa[-1] - xb[0])
        builder.merge_pairs(ia, ib if same <= flipped else ib[::-1])
    cable_nodes = {}
    for c in net.cables.values():
        cable_nodes[c.name] = _cable_nodes(net, builder, meshes, c)
        builder.mergeable(cable_nodes[c.name][[0, -1]])
    builder.merge_close()
    ids = builder.resolve()
    n = int(ids.max()) + 1
    position = np.zeros((n, 3))
    count = np.zeros(n)
    np.add.at(position, ids, builder.xyz)
    np.add.at(count, ids, 1)
    position /= count[:, None]

    hexagonal = _hexagonal(net, meshes, ids)
    netting = _netting(net, meshes, ids)
    bars = _bars(net, cable_nodes, ids, position, meshes)
    cable_joints = _joints(net, bars)
    environment = _normalised(net.environment)
    catch, enclosure = _catch_and_enclosure(net, environment)
    if netting is not None and (catch is not None or enclosure is not None):
        center = (catch or enclosure).center
        netting = dataclasses.replace(netting, outward=_outward(position, np.asarray(netting.vertices), center,
                                                                np.asarray(netting.uv), np.asarray(netting.panel)))
    panel_catches = _panel_catches_of(net, environment)
    if netting is not None and panel_catches is not None and netting.outward is None:
        netting = dataclasses.replace(netting, outward=_panel_catch_outward(net, netting, position, panel_catches))
    fixed = np.zeros((n, 3), dtype=bool)
    mass, volume, force = np.zeros(n), np.zeros(n), np.zeros((n, 3))
    drag_area, size = np.zeros(n), np.zeros(n)
    lookup = lambda ref: np.unique(ids[_nodes_of(net, ref, meshes, cable_nodes, builder)])  # noqa: E731
    for ref, axes in net.fixings:
        fixed[lookup(ref)] |= np.array(axes)
    fixed |= on_symmetry_planes(position, [(axis, at) for axis, at, hold in net.symmetry_planes if hold])
    for ref, m, v, f, a, h in net.attachments:
        nodes = lookup(ref)
        mass[nodes] += m / nodes.size
        volume[nodes] += v / nodes.size
        force[nodes] += f / nodes.size
        drag_area[nodes] += a / nodes.size
        size[nodes] = np.maximum(size[nodes], h)
    # node types (FEMNET's): each node takes the body and the limits of the last call naming it; the
    # fields stay None without any call, so that their terms are not compiled
    drag_length = drag_coefficient = limit = limit_sense = None
    if net.bodies:
        drag_length, drag_coefficient = np.zeros((n, 3)), np.zeros((n, 3))
        for ref, length, cd in net.bodies:
            nodes = lookup(ref)
            drag_length[nodes], drag_coefficient[nodes] = length, cd
    if net.limits:
        limit, limit_sense = np.zeros((n, 3)), np.zeros((n, 3), dtype=np.int32)
        for ref, value, sense in net.limits:
            nodes = lookup(ref)
            limit[nodes], limit_sense[nodes] = value, sense
    scene = Scene(
        nodes=Nodes(position=position, fixed=fixed, mass=mass, volume=volume, force=force,
                    drag_area=drag_area, size=size, drag_length=drag_length, drag_coefficient=drag_coefficient,
                    limit=limit, limit_sense=limit_sense),
        netting=netting,
        bars=bars,
        hinges=netting_hinges(netting),
        cable_joints=cable_joints,
        hexagonal=hexagonal,
        catch=catch,
        enclosure=enclosure,
        panel_catches=panel_catches,
        environment=environment,
        panel_names=tuple(net.panels),
        cable_names=tuple(net.cables) + tuple(f"{p.name} twines" for p in _twine_panels(net)),
        symmetry_planes=tuple((axis, at) for axis, at, _ in net.symmetry_planes),
    )
    from jaxnet.scene.checks import validate

    validate(scene)
    layout = Layout(
        meshes={name: m for name, (m, _) in meshes.items()},
        twines={p.name: p.twine for p in net.panels.values()},
        panel_nodes={name: ids[offset + np.arange(len(m.uv))] for name, (m, offset) in meshes.items()},
        cable_nodes={name: ids[nodes] for name, nodes in cable_nodes.items()},
        cable_sides={c.name: c.along for c in net.cables.values() if c.along is not None},
        fixed=tuple((ref, lookup(ref), axes) for ref, axes in net.fixings),
        attached=tuple(lookup(ref) for ref, *_ in net.attachments),
        attached_where=tuple(ref for ref, *_ in net.attachments),
        sinkers=tuple(net.sinkers),
        floats=tuple(net.floats),
    )
    return scene, layout


def _catch_and_enclosure(net, environment):
    from jaxnet.scene import Catch, Enclosure

    catch = enclosure = None
    if net.main_catch is not None:
        spec = dict(net.main_catch)
        if spec["axis"] is None and spec["density"] > 0:
            spec["axis"] = -np.asarray(environment.up, dtype=float)  # a gravity catch fills the bag from below
        if spec["axis"] is None:
            if not environment.current_speed > 0:
                raise SceneError("catch: give its axis, or a current (the axis defaults to its direction)")
            spec["axis"] = np.asarray(environment.current_direction, dtype=float)
        catch = Catch(**spec)
    if net.enclosure is not None:
        enclosure = Enclosure(**net.enclosure)
    return catch, enclosure

def _panel_catches_of(net, environment):
    from jaxnet.scene import PanelCatches

    if not net.panel_catches:
        return None
    cd, symmetry, axis = net.panel_catch_options
    if axis is None:
        if not environment.current_speed > 0:
            raise SceneError("panel_catch: give its axis, or a current (the axis defaults to its direction)")
        axis = np.asarray(environment.current_direction, dtype=float)
    index = {name: k for k, name in enumerate(net.panels)}
    panel_catch = np.full(len(net.panels), -1, dtype=np.int32)
    for k, (_, names, _) in enumerate(net.panel_catches):
        panel_catch[[index[n] for n in names]] = k
    return PanelCatches(volume=np.array([v for v, _, _ in net.panel_catches]), panel_catch=panel_catch,
                        drag_coefficient=cd, axis=axis, symmetry=symmetry)

def _panel_catch_outward(net, netting, position, panel_catches):
    """``Netting.outward`` for panel catches alone: the triangles of each catch's panels oriented away from
    its centre (:meth:`panel_catch`), panel by panel (:func:`_outward`); +1 elsewhere."""
    vertices, uv, panel = np.asarray(netting.vertices), np.asarray(netting.uv), np.asarray(netting.panel)
    holder = np.asarray(panel_catches.panel_catch)[panel]
    out = np.ones(len(vertices))
    for k, (_, _, center) in enumerate(net.panel_catches):
        rows = np.flatnonzero(holder == k)
        if rows.size:
            if center is None:
                center = position[np.unique(vertices[rows])].mean(axis=0)
            out[rows] = _outward(position, vertices[rows], center, uv[rows], panel[rows])
    return out

def _side_divisions(net):
    """Number of segments of every panel side; seams and sewn cables make sides agree."""
    div = {}
    for p in net.panels.values():
        if p.twines is not None:
            # a side of numerical twines has the nodes where they cross it, and those of a cable of a given
            # number of bars sewn along it (mesh_twines' divisions; 0: none)
            div[p.name] = np.zeros(len(p.corners), dtype=int)
            continue
        try:
            if p.lattice is not None:
                div[p.name] = np.array(lattice_divisions(p.corners[:, 3:5], p.lattice), dtype=int)
                continue
            div[p.name] = np.array(side_divisions(p.corners[:, 3:5], p.step, _mesh_length(p.twine)), dtype=int)
        except PanelError as err:
            # the mesher names the function, not the panel, in what it finds wrong here
            message = str(err).removeprefix("panel 'side_divisions': ").removeprefix("panel 'lattice_divisions': ")
            raise SceneError(f"panel '{p.name}': {message}") from err
    sides = [s for seam in net.seams for s in seam]
    for s in sides:
        _check_side(net, s, "seam")
        if net.panels[s.panel].twines is not None:
            raise SceneError(f"seam: panel '{s.panel}' is meshed as numerical twines: sew a cable along its "
                             f"side {s.index} instead (its twines end on the rope)")
    sewn = {c.along for c in net.cables.values() if c.along is not None}
    for p in _twine_panels(net):
        for k in range(len(p.corners)):
            if Side(p.name, k) not in sewn:
                raise SceneError(f"panel '{p.name}': side {k} has no cable sewn along it: a panel of numerical "
                                 "twines must be surrounded by ropes (their twines end on them), as in FEMNET")
    # Sides joined by seams (possibly in chains) form groups that all take the largest division.
    parent = {}

    def find(s):
        while parent.setdefault(s, s) != s:
            s = parent[s]
        return s

    for a, b in net.seams:
        parent[find(a)] = find(b)
    forced = {}
    for c in net.cables.values():
        if c.along is not None:
            _check_side(net, c.along, f"cable '{c.name}'")
            if c.n_bars is not None:
                forced[c.along] = int(c.n_bars)
    groups = {}
    for s in set(sides) | set(forced):
        groups.setdefault(find(s), []).append(s)
    for members in groups.values():
        want = [forced[s] for s in members if s in forced]
        value = max(want) if want else max(div[s.panel][s.index] for s in members)
        for s in members:
            div[s.panel][s.index] = value
    return div

def _check_side(net, side, what):
    if not isinstance(side, Side):
        raise SceneError(f"{what}: expected a panel side (panel.side(k)), got {side!r}")
    p = net.panel_named(side.panel, what)
    if not 0 <= side.index < len(p.corners):
        raise SceneError(f"{what}: panel '{side.panel}' has no side {side.index} (it has {len(p.corners)})")

def _side_nodes(net, meshes, side):
    _check_side(net, side, "side")
    m, offset = meshes[side.panel]
    return offset + m.side_nodes[side.index]

def _cable_nodes(net, builder, meshes, c):
    """Builder indices of the nodes of cable c, in order from start to end."""
    if c.along is not None:
        return _side_nodes(net, meshes, c.along)
    ends = []
    for k, ref in enumerate((c.start, c.end)):
        ends.append(_point(net, builder, meshes, ref, f"cable '{c.name}' {'start' if k == 0 else 'end'}"))
    (ia, xa), (ib, xb) = ends
    length = c.length if c.length is not None else float(np.linalg.norm(xb - xa))
    if length <= 0:
        raise SceneError(f"cable '{c.name}': both ends at the same point and no length given")
    nb = c.n_bars or 1
    t = np.linspace(0.0, 1.0, nb + 1)[1:-1, None]
    inner = builder.add_nodes(xa + t * (xb - xa))
    head = [ia] if ia is not None else list(builder.add_nodes(xa[None]))
    tail = [ib] if ib is not None else list(builder.add_nodes(xb[None]))
    return np.concatenate([head, inner, tail]).astype(np.int64)

def _point(net, builder, meshes, ref, what):
    """(builder index or None, position) of a cable end given as a reference or a point."""
    if isinstance(ref, Corner):
        p = net.panel_named(ref.panel, what)
        if not 0 <= ref.index < len(p.corners):
            raise SceneError(f"{what}: panel '{ref.panel}' has no corner {ref.index} (it has {len(p.corners)})")
        m, offset = meshes[ref.panel]
        i = offset + m.corner_nodes[ref.index]
        return i, builder.xyz[i]
    if isinstance(ref, (CableEnd, CableNodes, Side, PanelRef, CableRef)):
        raise SceneError(f"{what}: a cable end may be a panel corner or a point (x, y, z), got "
                         f"{describe_reference(ref)}")
    xyz = np.asarray(ref, dtype=float)
    if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
        raise SceneError(f"{what}: expected a panel corner or a finite point (x, y, z), got "
                         f"{describe_reference(ref)}")
    return None, xyz

def _nodes_of(net, ref, meshes, cable_nodes, builder):
    """Builder indices of the nodes a fixing/attachment reference designates."""
    what = f"reference {describe_reference(ref)}"
    if isinstance(ref, Corner):
        return np.array([_point(net, builder, meshes, ref, what)[0]])
    if isinstance(ref, Side):
        _check_side(net, ref, what)
        return _side_nodes(net, meshes, ref)
    if isinstance(ref, Nearest):
        net.panel_named(ref.panel, what)
        m, offset = meshes[ref.panel]
        xyz = np.asarray(ref.point, dtype=float)
        if not np.all(np.isfinite(xyz)):
            raise SceneError(f"{what}: the point must be finite")
        return np.array([offset + int(np.argmin(np.linalg.norm(m.xyz - xyz, axis=1)))])
    if isinstance(ref, PanelRef):
        net.panel_named(ref.name, what)
        m, offset = meshes[ref.name]
        return offset + np.arange(len(m.uv))
    if isinstance(ref, (CableEnd, CableNodes, CableRef)):
        name = ref.cable if not isinstance(ref, CableRef) else ref.name
        if name not in cable_nodes:
            raise SceneError(f"{what}: no cable named '{name}' (cables: {sorted(cable_nodes)})")
        nodes = cable_nodes[name]
        if isinstance(ref, CableEnd):
            return nodes[[0 if ref.end == 0 else -1]]
        return nodes
    xyz = np.asarray(ref, dtype=float)
    if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
        raise SceneError(f"{what}: not a panel corner/side, a cable (end) or a point (x, y, z)")
    dist = np.linalg.norm(builder.xyz - xyz, axis=1)
    hit = np.flatnonzero(dist <= net.merge_tolerance)
    if hit.size == 0:
        raise SceneError(f"no node at point {xyz.tolist()} (nearest is {dist.min():.4g} m away)")
    return hit

def _netting(net, meshes, ids):
    rows = {k: [] for k in ("vertices", "uv", "panel")}
    twines = []
    for p, e in _panel_triangles(net, meshes, ids, rows,
                                      lambda p: not isinstance(p.twine, HexTwine) and p.twines is None):
        twines.append(p.twine)
    if not rows["vertices"]:
        return None
    # the rows of the k-th diamond panel take the k-th diamond material (panel indices count all panels)
    material = np.concatenate([np.full(len(r), k) for k, r in enumerate(rows["panel"])])
    return Netting(**{k: np.concatenate(v) for k, v in rows.items()}, **netting_rows(twines, material))

def _panel_triangles(net, meshes, ids, rows, keep):
    """For each kept panel, append its triangles' vertices, twine coordinates and panel index to
    ``rows`` and yield (panel, number of triangles) for the caller's material columns."""
    for k, p in enumerate(net.panels.values()):
        if not keep(p):
            continue
        m, offset = meshes[p.name]
        tri = m.triangles
        rows["vertices"].append(ids[offset + tri])
        rows["uv"].append(m.uv[tri])
        rows["panel"].append(np.full(len(tri), k))
        yield p, len(tri)

def _hexagonal(net, meshes, ids):
    from jaxnet.scene import HexagonalNetting

    rows = {k: [] for k in ("vertices", "uv", "l0", "ea_traction", "ea_compression", "diameter", "density", "panel")}
    for p, e in _panel_triangles(net, meshes, ids, rows, lambda p: isinstance(p.twine, HexTwine)):
        for key, field in (("l0", "l0"), ("ea_traction", "ea"), ("ea_compression", "ea_compression")):
            rows[key].append(np.broadcast_to(p.twine.per_family(field), (e, 3)))
        rows["diameter"].append(np.full(e, float(p.twine.diameter)))
        rows["density"].append(np.full(e, float(p.twine.density)))
    if not rows["vertices"]:
        return None
    return HexagonalNetting(**{key: np.concatenate(v) for key, v in rows.items()})

def _twine_panels(net):
    """The panels meshed as numerical twines, in the net's order."""
    return [p for p in net.panels.values() if p.twines is not None]

def _bars(net, cable_nodes, ids, position, meshes=None):
    """The cables' bars (a cable's rest length shared by its bars' start lengths), then those of each panel of
    numerical twines (rest length l0 times the twines a bar spans, cable index after the net's cables)."""
    twine_panels = _twine_panels(net)
    if not cable_nodes and not twine_panels:
        return None
    rows = {k: [] for k in ("ends", "rest_length", "ea_traction", "ea_compression", "diameter", "density", "cable",
                            "cd_normal", "tangential_ratio")}
    for k, c in enumerate(net.cables.values()):
        nodes = ids[cable_nodes[c.name]]
        ends = np.stack([nodes[:-1], nodes[1:]], axis=1)
        seg = np.linalg.norm(position[ends[:, 1]] - position[ends[:, 0]], axis=1)
        total = c.length if c.length is not None else seg.sum()
        # each bar takes its share of the rope by its start length (equal shares if all are zero)
        share = seg / seg.sum() if seg.sum() > 0 else np.full(len(seg), 1.0 / len(seg))
        rows["ends"].append(ends)
        rows["rest_length"].append(total * share)
        for key, value in bar_columns(c.rope).items():
            rows[key].append(np.full(len(ends), value))
        rows["cable"].append(np.full(len(ends), k))
    for j, p in enumerate(twine_panels):
        m, offset = meshes[p.name]
        ends = ids[offset + m.bars]
        rows["ends"].append(ends)
        rows["rest_length"].append(p.twine.l0 * np.asarray(m.twines))
        for key, value in bar_columns(numerical_twine_rope(p.twine, p.twines)).items():
            rows[key].append(np.full(len(ends), value))
        rows["cable"].append(np.full(len(ends), len(net.cables) + j))
    return Bars(**{k: np.concatenate(v) for k, v in rows.items()})

def _joints(net, bars):
    """The bending joints of the stiff cables and of the welded pairs (:class:`CableJoints`), or None."""
    if bars is None:
        return None
    ends, rest, cable_of = np.asarray(bars.ends), np.asarray(bars.rest_length), np.asarray(bars.cable)
    names = list(net.cables)
    rows = []   # (first bar, second bar, joint node, EI, neutral turning angle)
    for k, c in enumerate(net.cables.values()):
        ei = float(c.rope.bending_stiffness)
        own = np.flatnonzero(cable_of == k)   # the cable's bars, from its start to its end
        if ei <= 0:
            continue
        rows += [(i, j, ends[i, 1], ei, 0.0) for i, j in zip(own[:-1], own[1:])]
        if len(own) > 2 and ends[own[-1], 1] == ends[own[0], 0]:   # a closed cable bends where it closes too
            rows.append((own[-1], own[0], ends[own[0], 0], ei, 0.0))
    for a, b, angle, stiffness in net.cable_joints:
        ka, kb = names.index(a), names.index(b)
        ei = stiffness if stiffness is not None else min(net.cables[a].rope.bending_stiffness,
                                                         net.cables[b].rope.bending_stiffness)
        bars_a, bars_b = np.flatnonzero(cable_of == ka), np.flatnonzero(cable_of == kb)
        shared = np.intersect1d(ends[bars_a], ends[bars_b])
        if shared.size == 0:
            raise SceneError(f"cable joint '{a}'-'{b}': the cables share no node (a joint needs an end of one "
                             "on a node of the other)")
        for node in shared:
            for i in bars_a[np.any(ends[bars_a] == node, axis=1)]:
                for j in bars_b[np.any(ends[bars_b] == node, axis=1)]:
                    rows.append((i, j, node, float(ei), float(np.pi) - angle))
    if not rows:
        return None
    first, second, node, ei, beta = (np.array(col) for col in zip(*rows))
    far = lambda bar: np.where(ends[bar, 0] == node, ends[bar, 1], ends[bar, 0])  # noqa: E731
    return CableJoints(vertices=np.stack([far(first), node, far(second)], axis=1).astype(np.int64),
                       rest_length=np.stack([rest[first], rest[second]], axis=1),
                       stiffness=ei.astype(float), rest_angle=beta.astype(float),
                       cable=np.stack([cable_of[first], cable_of[second]], axis=1))


def _mesh_length(twine):
    """Length (m) of one unit of twine coordinates, which sets the size of the triangles in the mesher."""
    return twine.base_mesh_side if isinstance(twine, HexTwine) else twine.l0


def outward(position, triangles, center, uv=None, panel=None) -> np.ndarray:
    """(E,) ``Netting.outward`` of triangles ``triangles`` (E, 3) (node indices into ``position`` (N, 3), m):
    +1 where the triangle's 12 ^ 13 points away from ``center`` (a point on the axis of the net, m), -1
    otherwise; with the triangles' twine coordinates ``uv`` (E, 3, 2) and ``panel`` (E,), decided panel by panel
    (:func:`_outward`). This is how :meth:`Net.build` orients netting for a catch or an enclosure (the catch pushes
    outwards); public for readers that build the :class:`~jaxnet.scene.Netting` themselves."""
    return _outward(np.asarray(position, dtype=float), np.asarray(triangles), np.asarray(center, dtype=float),
                    None if uv is None else np.asarray(uv, dtype=float), None if panel is None else np.asarray(panel))


def _outward(position, triangles, center, uv=None, panel=None):
    """(E,) +1 where a triangle's 12 ^ 13 points away from ``center`` (out of the net), -1 otherwise.

    Triangle by triangle, from the start shape, unless the twine coordinates ``uv`` (E, 3, 2) and the ``panel``
    (E,) of the triangles are given: then panel by panel. On a panel, 12 ^ 13 = d U ^ V (d the sign of the
    triangle's twine determinant, U ^ V the side of the netting, continuous over the panel), so a panel has one
    outward side and each triangle's orientation is the panel's times d. The panel's side is its triangles'
    majority vote (ties: the outward side of d > 0): a drawn shape that is not the net's (a bag drawn open, a
    panel folded across a corner, as FEMNET's 13gravity_catch/g1) misleads the test of some triangles, not of
    most of a panel."""
    x = position[triangles]
    normal = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])
    away = x.mean(axis=1) - center
    geometric = np.where(np.einsum("ij,ij->i", normal, away) >= 0.0, 1.0, -1.0)
    if uv is None or panel is None:
        return geometric
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    d = np.where(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0] >= 0.0, 1.0, -1.0)
    votes = np.zeros(int(panel.max()) + 1 if panel.size else 0)
    np.add.at(votes, panel, geometric * d)
    return np.where(votes[panel] >= 0.0, 1.0, -1.0) * d


def _normalised(env):
    """The environment with a unit current direction (a zero vector is an error when there is a current)."""
    direction = np.asarray(env.current_direction, dtype=float)
    norm = np.linalg.norm(direction)
    if env.current_speed and not norm > 0:
        raise SceneError(f"environment: current_direction must be a non-zero vector, got {direction.tolist()}")
    if norm > 0:
        env = dataclasses.replace(env, current_direction=direction / norm)
    return env
