"""Describe a net the way a designer does, and build it into a :class:`~jaxnet.scene.Scene`.

A :class:`Net` holds panels (polygons whose corners have start positions x, y, z and twine coordinates
U, V — as FEMNET's ``.don`` files describe them), cables, seams and what is attached to nodes::

    twine = Twine(l0=0.02, ea=1000.0, diameter=0.002)
    net = Net()
    p = net.panel("wall", corners=[(0, 0, 0, 0, 0), (1, 0, 0, 25, -25), (1, 0, 1, 50, 0), (0, 0, 1, 25, 25)],
                  twine=twine, step=0.1)
    net.cable("headline", along=p.side(2), rope=Rope(ea=5e4, diameter=0.008))
    net.fix(p.side(2))
    scene = net.build()

Joining rules (decided in :meth:`Net.build`):
  * Panel corners and cable ends at the same start position (within ``merge_tolerance``) are one node.
  * ``net.seam(a.side(i), b.side(j))`` makes two panel borders share their nodes: both sides are divided
    into the same number of segments (the larger of their defaults), also when the two panels have
    different mesh counts along the seam (50 meshes joined to 45, book Fig. 4.5): each panel keeps its
    own twine coordinates at the shared nodes. The direction is matched from the start positions.
  * ``net.cable(..., along=p.side(k))`` sews a rope along a border: one bar per border segment, rest
    length of each bar its share of the rope length (by default the border's start length).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.mesh.panel import PanelError, mesh_panel, side_divisions
from jaxnet.scene import Bars, Environment, Netting, Nodes, Scene, SceneError


@dataclasses.dataclass(frozen=True)
class Twine:
    """Netting material. l0: unstretched twine length = mesh side (m); ea: traction stiffness (N);
    ea_compression: compression stiffness (N, 0 = twines go slack); diameter: twine (hydrodynamic)
    diameter (m); density: volumic mass (kg/m³, 1140 = polyamide)."""

    l0: float
    ea: float
    diameter: float
    ea_compression: float = 0.0
    density: float = 1140.0


@dataclasses.dataclass(frozen=True)
class Rope:
    """Cable material: ea, ea_compression (N), diameter (m), density (kg/m³)."""

    ea: float
    diameter: float
    ea_compression: float = 0.0
    density: float = 1140.0


# -- references to places in a net that is not built yet ------------------------------------------


@dataclasses.dataclass(frozen=True)
class Corner:
    """Corner ``index`` of a panel."""

    panel: str
    index: int


@dataclasses.dataclass(frozen=True)
class Side:
    """Side ``index`` of a panel: from corner ``index`` to corner ``index + 1`` (cyclic)."""

    panel: str
    index: int


@dataclasses.dataclass(frozen=True)
class Nearest:
    """The node of a panel nearest to a point (x, y, z) of the start geometry (m)."""

    panel: str
    point: tuple


@dataclasses.dataclass(frozen=True)
class CableEnd:
    """End 0 (start) or 1 (end) of a cable."""

    cable: str
    end: int


@dataclasses.dataclass(frozen=True)
class CableNodes:
    """All nodes of a cable."""

    cable: str


@dataclasses.dataclass(frozen=True)
class PanelRef:
    name: str

    def corner(self, k):
        return Corner(self.name, int(k))

    def side(self, k):
        return Side(self.name, int(k))

    def nearest(self, x, y, z):
        """The panel's node nearest to the start position (x, y, z) (m), e.g. for a sinker at its centre."""
        return Nearest(self.name, (float(x), float(y), float(z)))


@dataclasses.dataclass(frozen=True)
class CableRef:
    name: str

    @property
    def start(self):
        return CableEnd(self.name, 0)

    @property
    def end(self):
        return CableEnd(self.name, 1)

    @property
    def nodes(self):
        return CableNodes(self.name)


@dataclasses.dataclass
class _Panel:
    name: str
    corners: np.ndarray  # (C, 5): x y z U V
    twine: Twine
    step: float


@dataclasses.dataclass
class _Cable:
    name: str
    start: object
    end: object
    rope: Rope
    length: float | None
    n_bars: int | None
    along: Side | None


class Net:
    """A net under construction: panels, cables, seams, fixings and attachments. See the module docstring.

    merge_tolerance: corners and cable ends closer than this (m) at the start are one node.
    """

    def __init__(self, environment: Environment | None = None, merge_tolerance: float = 1e-6):
        self.environment = environment or Environment()
        self.merge_tolerance = merge_tolerance
        self._panels: dict[str, _Panel] = {}
        self._cables: dict[str, _Cable] = {}
        self._seams: list[tuple[Side, Side]] = []
        self._fixed: list[tuple[object, tuple[bool, bool, bool]]] = []
        self._attached: list[tuple[object, float, float, np.ndarray]] = []

    # -- description ------------------------------------------------------------------------------

    def panel(self, name, corners, twine: Twine, step: float) -> PanelRef:
        """Add a diamond-mesh panel. corners: (C, 5) rows x, y, z (m), U, V (twines); step: meshing step (m)."""
        if name in self._panels or name in self._cables:
            raise SceneError(f"panel '{name}': the name is already used")
        corners = np.asarray(corners, dtype=float)
        if corners.ndim != 2 or corners.shape[1] != 5:
            raise SceneError(f"panel '{name}': corners must be rows of x y z U V, got shape {corners.shape}")
        _check_material(twine, f"panel '{name}'", ("l0", "ea", "ea_compression", "diameter", "density"), positive=("l0",))
        self._panels[name] = _Panel(name, corners, twine, float(step))
        return PanelRef(name)

    def cable(self, name, start=None, end=None, rope: Rope | None = None, n_bars: int | None = None,
              length: float | None = None, along: Side | None = None) -> CableRef:
        """Add a cable of ``n_bars`` bars between ``start`` and ``end`` (references or (x, y, z) points), or
        sewn ``along`` a panel side. length: unstretched length (m), default the start distance."""
        if name in self._panels or name in self._cables:
            raise SceneError(f"cable '{name}': the name is already used")
        if rope is None:
            raise SceneError(f"cable '{name}': no rope material given")
        _check_material(rope, f"cable '{name}'", ("ea", "ea_compression", "diameter", "density"))
        if along is None and (start is None or end is None):
            raise SceneError(f"cable '{name}': give both ends (start=, end=) or a panel side (along=)")
        if n_bars is not None and (int(n_bars) != n_bars or n_bars < 1):
            raise SceneError(f"cable '{name}': number of bars must be a positive integer, got {n_bars!r}")
        if length is not None and not (np.isfinite(length) and length > 0):
            raise SceneError(f"cable '{name}': length must be > 0, got {length!r}")
        self._cables[name] = _Cable(name, start, end, rope, length, n_bars, along)
        return CableRef(name)

    def seam(self, a: Side, b: Side):
        """Sew panel side ``a`` to panel side ``b``: they share their border nodes."""
        self._seams.append((a, b))

    def fix(self, where, axes="xyz"):
        """Hold the node(s) at ``where`` (a reference or (x, y, z) point) along ``axes`` (e.g. "xyz", "z")."""
        bad = set(axes) - set("xyz")
        if bad:
            raise SceneError(f"fix: unknown axes {sorted(bad)} (use x, y, z)")
        self._fixed.append((where, tuple(a in axes for a in "xyz")))

    def attach(self, where, mass=0.0, volume=0.0, force=(0.0, 0.0, 0.0)):
        """Attach a lumped mass (kg) displacing ``volume`` (m³) and/or an external force (N) to the
        node(s) at ``where``; on several nodes (a side, a cable) the amounts are shared equally."""
        self._attached.append((where, float(mass), float(volume), np.asarray(force, dtype=float)))

    def sinker(self, where, mass, density=11340.0):
        """A sinker of ``mass`` kg of a material of ``density`` (kg/m³, lead by default)."""
        self.attach(where, mass=mass, volume=mass / density)

    def float_(self, where, buoyancy_N, mass=0.0):
        """A float pulling up with ``buoyancy_N`` newtons net of its own weight (+ optional mass, kg)."""
        g, rho = self.environment.gravity, self.environment.water_density
        self.attach(where, mass=mass, volume=(buoyancy_N / g + mass) / rho)

    # -- building ---------------------------------------------------------------------------------

    def build(self) -> Scene:
        """Mesh every panel, join panels and cables, and return the :class:`Scene` (validated)."""
        if not self._panels and not self._cables:
            raise SceneError("the net has no panel and no cable")
        divisions = self._side_divisions()
        builder = _Builder(self.merge_tolerance)
        meshes = {}
        for p in self._panels.values():
            try:
                m = mesh_panel(p.corners[:, 3:5], p.corners[:, 0:3], p.step, p.twine.l0, divisions=divisions[p.name], name=p.name)
            except PanelError as err:
                raise SceneError(str(err)) from err
            offset = builder.add_nodes(m.xyz)
            meshes[p.name] = (m, offset[0])
            builder.mergeable(offset[m.corner_nodes])
        for a, b in self._seams:
            ia = self._side_nodes(meshes, a)
            ib = self._side_nodes(meshes, b)
            xa, xb = builder.position(ia), builder.position(ib)
            same = np.linalg.norm(xa[0] - xb[0]) + np.linalg.norm(xa[-1] - xb[-1])
            flipped = np.linalg.norm(xa[0] - xb[-1]) + np.linalg.norm(xa[-1] - xb[0])
            builder.merge_pairs(ia, ib if same <= flipped else ib[::-1])
        cable_nodes = {}
        for c in self._cables.values():
            cable_nodes[c.name] = self._cable_nodes(builder, meshes, c)
            builder.mergeable(cable_nodes[c.name][[0, -1]])
        builder.merge_close()
        ids = builder.resolve()
        n = int(ids.max()) + 1
        position = np.zeros((n, 3))
        count = np.zeros(n)
        np.add.at(position, ids, builder.xyz)
        np.add.at(count, ids, 1)
        position /= count[:, None]

        netting = self._netting(meshes, ids)
        bars = self._bars(cable_nodes, ids, position)
        fixed = np.zeros((n, 3), dtype=bool)
        mass, volume, force = np.zeros(n), np.zeros(n), np.zeros((n, 3))
        lookup = lambda ref: np.unique(ids[self._nodes_of(ref, meshes, cable_nodes, builder)])  # noqa: E731
        for ref, axes in self._fixed:
            fixed[lookup(ref)] |= np.array(axes)
        for ref, m, v, f in self._attached:
            nodes = lookup(ref)
            mass[nodes] += m / nodes.size
            volume[nodes] += v / nodes.size
            force[nodes] += f / nodes.size
        scene = Scene(
            nodes=Nodes(position=position, fixed=fixed, mass=mass, volume=volume, force=force),
            netting=netting,
            bars=bars,
            environment=self.environment,
            panel_names=tuple(self._panels),
            cable_names=tuple(self._cables),
        )
        from jaxnet.scene import validate

        validate(scene)
        return scene

    # -- helpers of build -------------------------------------------------------------------------

    def _panel(self, name, what):
        if name not in self._panels:
            raise SceneError(f"{what}: no panel named '{name}' (panels: {sorted(self._panels)})")
        return self._panels[name]

    def _side_divisions(self):
        """Number of segments of every panel side; seams and sewn cables make sides agree."""
        div = {}
        for p in self._panels.values():
            try:
                div[p.name] = np.array(side_divisions(p.corners[:, 3:5], p.step, p.twine.l0), dtype=int)
            except PanelError as err:
                raise SceneError(str(err)) from err
        sides = [s for seam in self._seams for s in seam]
        for s in sides:
            self._check_side(s, "seam")
        # Sides joined by seams (possibly in chains) form groups that all take the largest division.
        parent = {}

        def find(s):
            while parent.setdefault(s, s) != s:
                s = parent[s]
            return s

        for a, b in self._seams:
            parent[find(a)] = find(b)
        forced = {}
        for c in self._cables.values():
            if c.along is not None:
                self._check_side(c.along, f"cable '{c.name}'")
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

    def _check_side(self, side, what):
        if not isinstance(side, Side):
            raise SceneError(f"{what}: expected a panel side (panel.side(k)), got {side!r}")
        p = self._panel(side.panel, what)
        if not 0 <= side.index < len(p.corners):
            raise SceneError(f"{what}: panel '{side.panel}' has no side {side.index} (it has {len(p.corners)})")

    def _side_nodes(self, meshes, side):
        self._check_side(side, "side")
        m, offset = meshes[side.panel]
        return offset + m.side_nodes[side.index]

    def _cable_nodes(self, builder, meshes, c):
        """Builder indices of the nodes of cable c, in order from start to end."""
        if c.along is not None:
            return self._side_nodes(meshes, c.along)
        ends = []
        for k, ref in enumerate((c.start, c.end)):
            ends.append(self._point(builder, meshes, ref, f"cable '{c.name}' {'start' if k == 0 else 'end'}"))
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

    def _point(self, builder, meshes, ref, what):
        """(builder index or None, position) of a cable end given as a reference or a point."""
        if isinstance(ref, Corner):
            p = self._panel(ref.panel, what)
            if not 0 <= ref.index < len(p.corners):
                raise SceneError(f"{what}: panel '{ref.panel}' has no corner {ref.index} (it has {len(p.corners)})")
            m, offset = meshes[ref.panel]
            i = offset + m.corner_nodes[ref.index]
            return i, builder.xyz[i]
        if isinstance(ref, (CableEnd, CableNodes, Side, PanelRef, CableRef)):
            raise SceneError(f"{what}: a cable end may be a panel corner or a point (x, y, z), got {ref!r}")
        xyz = np.asarray(ref, dtype=float)
        if xyz.shape != (3,) or not np.all(np.isfinite(xyz)):
            raise SceneError(f"{what}: expected a panel corner or a finite point (x, y, z), got {ref!r}")
        return None, xyz

    def _nodes_of(self, ref, meshes, cable_nodes, builder):
        """Builder indices of the nodes a fixing/attachment reference designates."""
        what = f"reference {ref!r}"
        if isinstance(ref, Corner):
            return np.array([self._point(builder, meshes, ref, what)[0]])
        if isinstance(ref, Side):
            return self._side_nodes(meshes, ref)
        if isinstance(ref, Nearest):
            self._panel(ref.panel, what)
            m, offset = meshes[ref.panel]
            xyz = np.asarray(ref.point, dtype=float)
            if not np.all(np.isfinite(xyz)):
                raise SceneError(f"{what}: the point must be finite")
            return np.array([offset + int(np.argmin(np.linalg.norm(m.xyz - xyz, axis=1)))])
        if isinstance(ref, PanelRef):
            self._panel(ref.name, what)
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
        hit = np.flatnonzero(dist <= self.merge_tolerance)
        if hit.size == 0:
            raise SceneError(f"no node at point {xyz.tolist()} (nearest is {dist.min():.4g} m away)")
        return hit

    def _netting(self, meshes, ids):
        if not meshes:
            return None
        rows = {k: [] for k in ("vertices", "uv", "l0", "ea_traction", "ea_compression", "diameter", "density", "panel")}
        for k, p in enumerate(self._panels.values()):
            m, offset = meshes[p.name]
            tri = m.triangles
            e = len(tri)
            rows["vertices"].append(ids[offset + tri])
            rows["uv"].append(m.uv[tri])
            for key, value in (("l0", p.twine.l0), ("ea_traction", p.twine.ea), ("ea_compression", p.twine.ea_compression),
                               ("diameter", p.twine.diameter), ("density", p.twine.density)):
                rows[key].append(np.full(e, float(value)))
            rows["panel"].append(np.full(e, k))
        return Netting(**{k: np.concatenate(v) for k, v in rows.items()})

    def _bars(self, cable_nodes, ids, position):
        if not cable_nodes:
            return None
        rows = {k: [] for k in ("ends", "rest_length", "ea_traction", "ea_compression", "diameter", "density", "cable")}
        for k, c in enumerate(self._cables.values()):
            nodes = ids[cable_nodes[c.name]]
            ends = np.stack([nodes[:-1], nodes[1:]], axis=1)
            seg = np.linalg.norm(position[ends[:, 1]] - position[ends[:, 0]], axis=1)
            total = c.length if c.length is not None else seg.sum()
            # each bar takes its share of the rope by its start length (equal shares if all are zero)
            share = seg / seg.sum() if seg.sum() > 0 else np.full(len(seg), 1.0 / len(seg))
            rows["ends"].append(ends)
            rows["rest_length"].append(total * share)
            for key, value in (("ea_traction", c.rope.ea), ("ea_compression", c.rope.ea_compression),
                               ("diameter", c.rope.diameter), ("density", c.rope.density)):
                rows[key].append(np.full(len(ends), float(value)))
            rows["cable"].append(np.full(len(ends), k))
        return Bars(**{k: np.concatenate(v) for k, v in rows.items()})


def _check_material(material, what, fields, positive=()):
    for f in fields:
        v = getattr(material, f)
        if not np.isfinite(v) or v < 0 or (f in positive and v == 0):
            raise SceneError(f"{what}: {f} must be {'> 0' if f in positive else '>= 0'}, got {v!r}")


class _Builder:
    """Nodes before merging: positions, merge pairs (union-find), resolution into global ids."""

    def __init__(self, tolerance):
        self.tolerance = tolerance
        self.chunks = []
        self.n = 0
        self.pairs = []
        self.candidates = []

    @property
    def xyz(self):
        return np.concatenate(self.chunks) if self.chunks else np.zeros((0, 3))

    def add_nodes(self, xyz):
        xyz = np.asarray(xyz, dtype=float).reshape(-1, 3)
        self.chunks.append(xyz)
        idx = np.arange(self.n, self.n + len(xyz))
        self.n += len(xyz)
        return idx

    def position(self, idx):
        return self.xyz[idx]

    def merge_pairs(self, a, b):
        self.pairs.append(np.stack([np.asarray(a), np.asarray(b)], axis=1))

    def mergeable(self, idx):
        """Mark nodes (panel corners, cable ends) that merge with any other such node at the same point."""
        self.candidates.append(np.asarray(idx, dtype=np.int64))

    def merge_close(self):
        """Merge corners and cable ends that start at the same point. Other nodes never merge by position:
        panels drawn overlapping (the upper and lower panels of a cod-end) must stay apart."""
        from scipy.spatial import cKDTree

        if not self.candidates:
            return
        cand = np.unique(np.concatenate(self.candidates))
        pairs = cKDTree(self.xyz[cand]).query_pairs(self.tolerance, output_type="ndarray")
        if len(pairs):
            self.pairs.append(cand[pairs])

    def resolve(self):
        import scipy.sparse as sp
        from scipy.sparse.csgraph import connected_components

        pairs = np.concatenate(self.pairs) if self.pairs else np.zeros((0, 2), dtype=int)
        g = sp.coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(self.n, self.n))
        _, label = connected_components(g, directed=False)
        # renumber in order of first appearance so that node numbers follow the description
        _, first = np.unique(label, return_index=True)
        order = np.argsort(first)
        rank = np.empty_like(order)
        rank[order] = np.arange(len(order))
        return rank[label]
