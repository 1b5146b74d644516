"""How a ``.don`` file's parts are joined (see the package's docstring, "Links"): FEMNET's links, its automatic
links and points at one place made one node at the mean of their start positions (``numerotation.c``), panel
sides sewn to panel sides or to cables (``maillage_panneau*.c``), planned before jaxnet's
:class:`~jaxnet.net.Net` meshes the parts.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.io.femnet.grammar import PART_NAMES, DonFile
from jaxnet.net import Side
from jaxnet.scene import SceneError


def all_panels(case: DonFile):
    """Every panel of the case as (kind, index, panel, jaxnet name), diamond panels first: the order in which
    :func:`~.mapping.read_don` adds them to the Net, so the position is the ``panel`` index in the scene."""
    return ([("pa", k, p, f"panel {k + 1}") for k, p in enumerate(case.panels)]
            + [("ha", k, p, f"hexagonal panel {k + 1}") for k, p in enumerate(case.hexagonal)])


#: corners and cable ends closer than this (m) at the start are one node (jaxnet's Net joins them)
MERGE_TOLERANCE = 1e-6
#: how far (m) a point at the place of another that no link joins it to starts from it (at most 1 % of its side)
APART = 1e-3


@dataclasses.dataclass
class JoinPlan:
    """How the case's parts are joined (see the package's docstring, "Links"): start positions after joining,
    panel sides sewn together, cables sewn along panel sides, the bars of the other cables."""

    corners: dict        # (kind, index) -> (C, 3) start positions of a panel's corners (m)
    ends: list           # per cable: (2, 3) start positions of its ends (m)
    seams: list          # [(Side, Side)]
    along: dict          # cable index -> (Side, number of bars or None: the side's division)
    n_bars: list         # per cable: number of bars when it is not sewn along a side
    joined: list         # [[point names]]: the points made one node, groups of two or more
    warnings: list = dataclasses.field(default_factory=list)   # points at one place kept apart (file:LINE: ...)
    global_nodes: list = dataclasses.field(default_factory=list)  # FEMNET's global node k+1: its start (3,) (m)


def _point_names(case: DonFile):
    """Every panel corner and cable end: [((kind, index, corner), name, line)]."""
    out = []
    for kind, k, p, name in all_panels(case):
        out += [((kind, k, c), f"{name} corner {c + 1}", p.corner_type[c].line) for c in range(len(p.corners))]
    for k, c in enumerate(case.cables):
        out += [(("el", k, e), f"cable {k + 1} end {e + 1}", c.end_type[e].line) for e in range(2)]
    return out


def plan_joins(case: DonFile) -> JoinPlan:
    """Join the case's parts as FEMNET's mesher does (phobos ``chargement_don.c``, ``maillage*.c``,
    ``numerotation.c``):

    * the points of a link, those closer than ``input link`` d (FEMNET's automatic links) and those at one
      place (jaxnet joins them anyway) are one node, which starts at the mean of their start positions;
    * a panel side whose two corners are joined to the two corners of another panel's side, or to the two
      ends of a cable, is sewn to it; the division of a sewn side is that of the part meshed first when it
      is a cable (its number of bars); otherwise jaxnet's (the largest default of the sewn sides);
    * cables joined at both ends to the ends of another cable would share its nodes: only when that one has
      a single bar (then they are parallel bars), otherwise refused.
    """
    points = _point_names(case)
    index = {key: i for i, (key, _, _) in enumerate(points)}
    xyz = np.array([(_panel_of(case, key).corners[key[2], :3] if key[0] != "el" else case.cables[key[1]].ends[key[2]])
                    for key, _, _ in points], dtype=float).reshape(-1, 3)
    parent = list(range(len(points)))

    def find(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    owner = {}
    for link in case.links:
        ids = [index[m[:3]] for m in link.members]
        for m, i in zip(link.members, ids):
            if i in owner:
                raise SceneError(f"{case.path}:{m[3]}: {points[i][1]} is already in the link of line {owner[i]}: a point "
                                 "belongs to one link (list all the points that are one node in that link)")
            owner[i] = link.line
        for i in ids[1:]:
            parent[find(i)] = find(ids[0])
    radius = MERGE_TOLERANCE
    if "link" in case.inputs:
        radius = max(radius, float(case.inputs["link"].value))
    if len(xyz) > 1:
        from scipy.spatial import cKDTree

        for i, j in cKDTree(xyz).query_pairs(radius):
            parent[find(i)] = find(j)
    group = [find(i) for i in range(len(points))]
    members = {}
    for i, g in enumerate(group):
        members.setdefault(g, []).append(i)
    for ids in members.values():
        seen = {}
        for i in ids:
            part = points[i][0][:2]
            if part in seen:
                a, b = points[seen[part]], points[i]
                raise SceneError(f"{case.path}:{b[2]}: {a[1]} and {b[1]} are joined (by a link, or closer than the "
                                 f"automatic link distance {radius:g} m): a panel or cable cannot be joined to itself")
            seen[part] = i
    # FEMNET's joined node starts at the mean of the joined points (numerotation.c); moving them there before
    # meshing makes jaxnet's Net join them by position, and the sides to sew end at the same two points
    moved = xyz.copy()
    for ids in members.values():
        moved[ids] = xyz[ids].mean(axis=0)
    reps = list(members)
    warnings = []
    if len(reps) > 1:
        from scipy.spatial import cKDTree

        # points at one place that no link joins are two nodes in FEMNET; jaxnet's Net joins points at one place,
        # so the later one (with its group) starts APART metres away along its own side (a panel corner towards
        # the next corner, a cable end towards the other end): the start shape only, not the equilibrium
        for a_rep, b_rep in sorted(cKDTree(moved[reps]).query_pairs(MERGE_TOLERANCE)):
            i, j = reps[a_rep], reps[b_rep]
            key = points[j][0]
            if key[0] == "el":
                toward = xyz[index[("el", key[1], 1 - key[2])]]
            else:
                n = len(_panel_of(case, key).corners)
                toward = xyz[index[(key[0], key[1], (key[2] + 1) % n)]]
            direction = toward - moved[j]
            length = float(np.linalg.norm(direction))
            if length == 0.0:
                raise SceneError(f"{case.path}:{points[j][2]}: {points[j][1]} is not joined to {points[i][1]} but starts "
                                 "at the same place, and its part has no length to move it along")
            moved[members[j]] += direction / length * min(APART, 0.01 * length)
            warnings.append(f"{case.path}:{points[j][2]}: {points[j][1]} is not joined to {points[i][1]} but starts at "
                            f"the same place: two nodes, as in FEMNET; it starts {min(APART, 0.01 * length):.3g} m away "
                            "along its own side (jaxnet's Net would join points at one place)")
    # sides and cables by the pair of nodes at their ends
    rank = {item: i for i, item in enumerate(case.order)}
    ends = {}
    for kind, k, p, name in all_panels(case):
        n = len(p.corners)
        for s in range(n):
            pair = frozenset((group[index[(kind, k, s)]], group[index[(kind, k, (s + 1) % n)]]))
            ends.setdefault(pair, []).append((rank.get((kind, k + 1), 0), kind, k, s))
    for k in range(len(case.cables)):
        pair = frozenset((group[index[("el", k, 0)]], group[index[("el", k, 1)]]))
        ends.setdefault(pair, []).append((rank.get(("el", k + 1), 0), "el", k, None))
    seams, along = [], {}
    n_bars = [c.material["n_bars"].value for c in case.cables]
    for items in ends.values():
        if len(items) < 2:
            continue
        items.sort()
        sides = [it for it in items if it[1] != "el"]
        cables = [it for it in items if it[1] == "el"]
        if sides:
            base = sides[0]
            side = Side(f"{PART_NAMES[base[1]]} {base[2] + 1}", base[3])
            seams += [(side, Side(f"{PART_NAMES[it[1]]} {it[2] + 1}", it[3])) for it in sides[1:]]
            for it in cables:
                # meshed before every side: its bars divide them; after: it follows the side's division
                along[it[2]] = (side, n_bars[it[2]] if it is cables[0] and it[0] < base[0] else None)
        else:
            first = cables[0][2]
            for it in cables[1:]:
                k = it[2]
                if n_bars[first] > 1:
                    raise SceneError(f"{case.path}:{case.cables[k].line}: cable {k + 1} is joined at both ends to the ends "
                                     f"of cable {first + 1}, meshed before it with {n_bars[first]} bars: FEMNET threads "
                                     "it on that cable's nodes, which jaxnet cannot do (a cable is sewn along a panel "
                                     "side only)")
                n_bars[k] = 1  # FEMNET gives it the single bar of the cable it lies on
    corners = {}
    for kind, k, p, name in all_panels(case):
        corners[(kind, k)] = moved[[index[(kind, k, c)] for c in range(len(p.corners))]]
    cable_ends = [moved[[index[("el", k, 0)], index[("el", k, 1)]]] for k in range(len(case.cables))]
    joined = [[points[i][1] for i in ids] for ids in members.values() if len(ids) > 1]
    # FEMNET's global nodes (numerotation.c; the first nodes of its .mdg): the joined points numbered in the order
    # their first point comes (panel corners, then hexagonal panels', then cable ends)
    first = {}
    for i, g in enumerate(group):
        first.setdefault(g, i)
    global_nodes = [moved[i] for i in sorted(first.values())]
    return JoinPlan(corners, cable_ends, seams, along, n_bars, joined, warnings, global_nodes)


def _panel_of(case: DonFile, key):
    return (case.panels if key[0] == "pa" else case.hexagonal)[key[1]]


def at_joined_positions(case: DonFile, plan: JoinPlan) -> DonFile:
    """The case with its corners and cable ends at their joined start positions."""
    def panel(p, xyz):
        corners = p.corners.copy()
        corners[:, :3] = xyz
        return dataclasses.replace(p, corners=corners)

    return dataclasses.replace(
        case,
        panels=[panel(p, plan.corners[("pa", k)]) for k, p in enumerate(case.panels)],
        hexagonal=[panel(p, plan.corners[("ha", k)]) for k, p in enumerate(case.hexagonal)],
        cables=[dataclasses.replace(c, ends=plan.ends[k]) for k, c in enumerate(case.cables)])
