"""The design space of a net: what a gear designer changes, as a differentiable map θ -> Scene.

:class:`DesignSpace` builds a :class:`~jaxnet.net.Net` once (numpy, the mesher) and records where every
part of the description landed in the scene (``Net.layout``). The *topology* is then frozen — the same
nodes, triangles, hinges and bars — and :meth:`DesignSpace.scene` maps design parameters θ to the
scene's float arrays with jnp, so that ``jax.grad``, ``jacfwd``, ``jit`` and ``vmap`` go through it (and,
with :mod:`jaxnet.solve.implicit`, through the equilibrium). θ is a nested dict of float arrays, one entry
per family and per panel, rope, sinker or float (:meth:`DesignSpace.initial` gives all of them at the
reference design):

  ``cut``            {panel: (C, 2)}  twine coordinates (U, V) of the panel's corners (twines). Each triangle's
                     ``Netting.uv`` is ``weights @ corners`` (the mesher's weights of the reference polygon:
                     linear along the sides, mean value coordinates inside), a linear map, exact at the reference
                     and reproducing any affine map of the corners exactly. Meshes, cutting rates and rounding
                     to whole meshes: :mod:`jaxnet.design.cut`.
  ``mesh_side``      {panel: ()}  l0, the unstretched bar length (m).
  ``twine_diameter`` {panel: ()}  (m), for weight, buoyancy and drag (panels of diameter 0 are left out).
  ``ea``             {panel: ()}  traction stiffness EA of a twine (N); the compression stiffness keeps its
                     ratio to it (0 stays 0). Panels of EA 0 are left out.
  ``hanging_ratio``  {mounting: ()}  E (dimensionless), see below.
  ``sinker_mass``    {sinker: ()}  per :meth:`Net.sinker <jaxnet.net.Net.sinker>` call (kg): its mass and its
                     displaced volume (mass / density of the lead) both follow.
  ``buoyancy``       {float: ()}  per :meth:`Net.float <jaxnet.net.Net.float>` call (N, net of its own
                     weight): its displaced volume follows.
  ``cable_length``   {cable: ()}  total rest length (m) of a cable not mounted on netting; its bars keep
                     their shares of the rope.

Sinkers and floats are named after where they hang ("wall 3 corner 3", "netting near (0.5, 0, -1)",
"bridle end"; a second one at the same place gets " #2").

**Hanging ratio.** E = mounted length / stretched length of the netting border, the stretched length
being (|dU| + |dV|) l0 per side (every bar drawn along the border; 2 l0 per mesh, :func:`cut.stretched_length`).
It is defined where a border of netting is *mounted*:

  * on a rope sewn along it (``net.cable(..., along=p.side(k))``): the rope's rest length is E × the side's
    stretched length. The headline and the sinker bar of :func:`~jaxnet.scenes.panel.hanging_panel`, the cod
    line of :func:`~jaxnet.scenes.codend.codend`. The mounting is named after the rope.
  * on fixed nodes: panel sides held by ``net.fix(p.side(k), ...)``, joined into one border where they share
    nodes, held in every direction across the axis of the net's catch or enclosure (all three axes when the
    net has neither) and lying in one plane across that axis. The border's nodes are scaled about the axis
    (about their centroid without one), so that the mounted length (the polyline through them) is E × the
    summed stretched length of its sides; ropes sewn along those sides follow the same E (each keeping its
    own ratio to it). The floating collar of :func:`~jaxnet.scenes.cage.fish_cage` (one border of all the
    wall tops, with the collar pipes) and the front of the cod-end (fixed to the trawl). Named after its
    first side ("wall 0 side 0"). The cod-end's sides on its symmetry planes, held along one axis only, are
    not mountings.

E is the independent parameter: with E fixed, a cut with more meshes along a mounted border makes a longer
rope and a wider collar. For a fixed mounted length M instead, set E = M / :meth:`stretched_length`.
Where the border has a side of pure bars (an AB side, dU or dV = 0) the stretched length has a kink.

**What stays as built.** Start positions of free nodes (``weights @ corners_xyz`` of the reference: the
equilibrium does not depend on them), fixed nodes other than mountings, the netting's outward side, the
catch and the environment, every other material constant (Cd, density, opening and bending stiffness, knot
size) and hexagonal panels (no family varies them). A knot contact stiffness left to its default
(eq. 4.280, l0² EA / (100 knot size)) follows l0 and EA.

**Terms and validity.** Which terms the model compiles is read once from concrete values
(:func:`jaxnet.model.active_terms`): compute it from :attr:`DesignSpace.reference`. A parameter never
switches a term on or off silently: a term of the reference stays compiled at any θ (a sinker taken to 0 kg
keeps the node-weight term, which then weighs nothing), and :meth:`DesignSpace.check` refuses a θ whose
scene would need a term the reference does not have (e.g. a sinker made heavy in a net whose reference
sinker weighs nothing and nothing else on the nodes does). :meth:`DesignSpace.scene` calls
:meth:`~DesignSpace.check` on every entry of θ that is concrete (not a tracer), so errors are raised before
anything is compiled, naming the family, the entry and the corner.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import model
from jaxnet.case import Case
from jaxnet.design import cut as cut_lib
from jaxnet.net import HexTwine, Net, Side, describe_reference
from jaxnet.scene import Scene
from jaxnet.solve import programs

__all__ = ["FAMILIES", "Mounting", "DesignSpace"]

#: design parameter families: name -> (unit, what)
FAMILIES = {
    "cut": ("twines", "twine coordinates (U, V) of the panel's corners"),
    "mesh_side": ("m", "mesh side (bar length) l0"),
    "twine_diameter": ("m", "twine diameter"),
    "ea": ("N", "twine traction stiffness EA"),
    "hanging_ratio": ("", "hanging ratio E = mounted / stretched length"),
    "sinker_mass": ("kg", "sinker mass"),
    "buoyancy": ("N", "float buoyancy (net of its weight)"),
    "cable_length": ("m", "cable rest length"),
}


@dataclasses.dataclass(frozen=True)
class Mounting:
    """A border of netting mounted at a hanging ratio (see the module docstring).

    name: the key in θ["hanging_ratio"]; sides: the panel sides of the border; cables: the ropes sewn along
    them (their rest lengths follow E); fixed: whether the border's nodes are held (and scaled with E);
    mounted_length, stretched_length: at the reference (m).
    """

    name: str
    sides: tuple
    cables: tuple
    fixed: bool
    mounted_length: float
    stretched_length: float

    @property
    def hanging_ratio(self):
        """E at the reference design."""
        return self.mounted_length / self.stretched_length


def _unique_names(labels):
    """Labels made unique by appending " #2", " #3"... to repeats."""
    seen, out = {}, []
    for label in labels:
        seen[label] = seen.get(label, 0) + 1
        out.append(label if seen[label] == 1 else f"{label} #{seen[label]}")
    return out


def _fixed_borders(scene, layout, panels):
    """Borders of netting mounted on fixed nodes: [(sides, scene nodes, offsets (n, 3) m, mounted length m)].

    A border is a set of fixed panel sides (of ``panels``) sharing nodes, each held in every direction across
    the axis of the net's catch or enclosure (all three without one) and, with an axis, all its nodes in one
    plane across it. The offsets are the nodes' positions from the axis, across it (from their centroid
    without an axis): what scaling the border moves. The mounted length is the polyline through each side's
    nodes, summed.
    """
    holder = scene.catch if scene.catch is not None else scene.enclosure
    axis = None if holder is None else np.asarray(holder.axis, float)
    position = np.asarray(scene.nodes.position)
    across = np.eye(3) if axis is None else np.eye(3) - np.outer(axis, axis)
    needed = np.ones(3, bool) if axis is None else np.abs(axis) < 1.0 - 1e-12

    def side_nodes(side):
        return layout.panel_nodes[side.panel][layout.meshes[side.panel].side_nodes[side.index]]

    held = []  # (side, nodes), each side once
    for ref, _, axes in layout.fixed:
        if (isinstance(ref, Side) and ref.panel in panels and np.all(np.asarray(axes)[needed])
                and all(ref != s for s, _ in held)):
            held.append((ref, side_nodes(ref)))
    group = list(range(len(held)))  # union-find of sides sharing a node

    def root(i):
        while group[i] != i:
            i = group[i]
        return i

    for i in range(len(held)):
        for j in range(i):
            if np.intersect1d(held[i][1], held[j][1]).size:
                group[root(i)] = root(j)
    borders = []
    for r in dict.fromkeys(root(i) for i in range(len(held))):
        members = [held[i] for i in range(len(held)) if root(i) == r]
        nodes = np.unique(np.concatenate([n for _, n in members]))
        centre = position[nodes].mean(axis=0) if axis is None else np.asarray(holder.center, float)
        offset = (position[nodes] - centre) @ across.T
        if axis is not None:  # across the axis, or scaling about the axis would not scale its length
            height = (position[nodes] - centre) @ axis
            if np.ptp(height) > 1e-9 * max(float(np.max(np.abs(offset))), 1e-300):
                continue
        mounted = sum(float(np.sum(np.linalg.norm(np.diff(position[n], axis=0), axis=1))) for _, n in members)
        borders.append(([s for s, _ in members], nodes, offset, mounted))
    return borders


def _is_concrete(value):
    return not isinstance(value, jax.core.Tracer)


class DesignSpace:
    """The design parameters of a net and the differentiable map from them to its scene.

    net: the :class:`~jaxnet.net.Net` (built once here, numpy), or a :class:`~jaxnet.case.Case` built from one
    (its ``net``). Attributes: ``reference`` (the built :class:`~jaxnet.scene.Scene`), ``panels`` (names of
    the diamond-mesh panels, in order), ``mountings`` (name -> :class:`Mounting`), ``sinkers``, ``floats``,
    ``cables`` (names of the free cables).
    """

    def __init__(self, net: Net | Case):
        if isinstance(net, Case):
            if net.net is None:
                raise ValueError(f"DesignSpace: the case ({net.label or 'unnamed'}) was not built from a Net "
                                 "description (a scene read whole, such as FEMNET's .mdg mesh): nothing to vary")
            net = net.net
        if not isinstance(net, Net):
            raise ValueError(f"DesignSpace: expected a Net or a Case, got {type(net).__name__}")
        self.net = net
        self.reference = scene = net.build()
        layout = net.layout
        self.panels = tuple(name for name in scene.panel_names if not isinstance(layout.twines[name], HexTwine))
        self._twines = {name: layout.twines[name] for name in self.panels}
        self._netting_maps(scene, layout)
        self._hinge_maps(scene)
        self._mounting_maps(scene, layout)
        self._cable_maps(scene, layout)
        self._attachment_maps(scene, layout)
        self._initial = self._reference_theta(layout)
        # the stretched lengths of the mounted sides at the reference, by the same jnp function as scene()
        self._side_stretched_ref = np.asarray(self._side_stretched(self._initial))
        self._active = self._term_keys(scene)
        # plain jax.jit: it runs inside the caller's traced functions, where XLA refuses options
        self._moved = jax.jit(self._moved_arrays)
        self._pullback = programs.jit(self._vjp_moved)
        self._moved_fields = None

    # -- the maps, recorded once -------------------------------------------------------------------

    def _netting_maps(self, scene, layout):
        """Per netting row: its panel's slot, and the weights of its vertices on its panel's corners."""
        self._corners = {}
        if scene.netting is None:
            return
        panel_of_row = np.asarray(scene.netting.panel)
        vertices = np.asarray(scene.netting.vertices)
        n_rows = len(panel_of_row)
        c_max = max(len(layout.meshes[p].corner_nodes) for p in self.panels)
        self._row_slot = np.zeros(n_rows, dtype=np.int64)
        self._uv_weights = np.zeros((n_rows, 3, c_max))
        self._uv_corners = np.zeros((n_rows, c_max), dtype=np.int64)
        self._panel_rows = {}
        offset = 0
        for slot, name in enumerate(self.panels):
            m = layout.meshes[name]
            rows = np.flatnonzero(panel_of_row == scene.panel_names.index(name))
            # Net.build writes a panel's triangles in the mesher's order
            assert np.array_equal(vertices[rows], layout.panel_nodes[name][m.triangles]), name
            c = len(m.corner_nodes)
            self._row_slot[rows] = slot
            self._uv_weights[rows, :, :c] = m.weights[m.triangles]
            self._uv_corners[rows] = offset
            self._uv_corners[rows, :c] = offset + np.arange(c)
            self._panel_rows[name] = rows
            self._corners[name] = np.array(m.uv[:c])  # corner rows of the weights are unit rows
            offset += c
        self._uv_ref = np.asarray(scene.netting.uv)
        twines = [self._twines[p] for p in self.panels]
        self._l0_ref = np.array([t.l0 for t in twines], dtype=float)
        self._ea_ref = np.array([t.ea for t in twines], dtype=float)
        self._diameter_ref = np.array([t.diameter for t in twines], dtype=float)
        # knot contact stiffness left to its default (eq. 4.280) follows l0 and EA
        self._knot_default = np.array([t.knot_stiffness is None and t.knot_size > 0 for t in twines])[self._row_slot]
        self._knot_size = np.array([t.knot_size for t in twines], dtype=float)[self._row_slot]

    def _hinge_maps(self, scene):
        """Each hinge node's (triangle, vertex slot) whose twine coordinates it takes
        (:func:`jaxnet.mesh.hinges.hinge_rows`), and each hinge's first triangle."""
        if scene.hinges is None:
            return
        from jaxnet.mesh.hinges import hinge_rows

        self._hinge_tri, self._hinge_slot, _, _ = hinge_rows(scene.netting)
        self._hinge_first = self._hinge_tri[:, 0]

    def _mounting_maps(self, scene, layout):
        """Mountings: borders on fixed nodes (with the ropes sewn along them), then ropes sewn alone."""
        self._mounting_specs = {}  # name -> (sides, cables, fixed, mounted length m, indices in _mounted_sides)
        self._mounted_sides = []  # (panel, side index) whose stretched length θ sets
        self._mounting_of_cable = {}  # cable -> (mounting name, index of its side in _mounted_sides)
        fixed_nodes, fixed_group, fixed_offset = [], [], []
        for sides, nodes, offset, mounted in _fixed_borders(scene, layout, self.panels):
            name = describe_reference(sides[0], short=True)
            side_index = list(range(len(self._mounted_sides), len(self._mounted_sides) + len(sides)))
            self._mounted_sides += [(s.panel, s.index) for s in sides]
            cables = tuple(c for c, s in layout.cable_sides.items() if s in sides)
            for c in cables:
                self._mounting_of_cable[c] = (name, side_index[sides.index(layout.cable_sides[c])])
            fixed_group.append(np.full(len(nodes), len(self._mounting_specs)))
            self._mounting_specs[name] = (tuple(sides), cables, True, mounted, side_index)
            fixed_nodes.append(nodes)
            fixed_offset.append(offset)
        for c, s in layout.cable_sides.items():
            if c in self._mounting_of_cable or s.panel not in self.panels:
                continue
            name = c if c not in self._mounting_specs else f"{c} (rope)"
            self._mounting_of_cable[c] = (name, len(self._mounted_sides))
            rows = np.asarray(scene.bars.cable) == scene.cable_names.index(c)
            length = float(np.sum(np.asarray(scene.bars.rest_length)[rows]))
            self._mounting_specs[name] = ((s,), (c,), False, length, [len(self._mounted_sides)])
            self._mounted_sides.append((s.panel, s.index))
        self._fixed_nodes = np.concatenate(fixed_nodes) if fixed_nodes else np.zeros(0, np.int64)
        self._fixed_group = np.concatenate(fixed_group) if fixed_group else np.zeros(0, np.int64)
        self._fixed_offset = np.concatenate(fixed_offset) if fixed_offset else np.zeros((0, 3))
        # (mountings, mounted sides): which sides make each border
        self._border_sides = np.zeros((len(self._mounting_specs), len(self._mounted_sides)))
        for k, (*_, side_index) in enumerate(self._mounting_specs.values()):
            self._border_sides[k, side_index] = 1.0

    def _cable_maps(self, scene, layout):
        """Per cable: its bars and its reference rest length; the free cables are those not mounted."""
        self.cables = ()
        if scene.bars is None:
            return
        cable_of_bar = np.asarray(scene.bars.cable)
        rest = np.asarray(scene.bars.rest_length)
        self._bar_cable = cable_of_bar
        self._cable_length_ref = np.array([rest[cable_of_bar == k].sum() for k in range(len(scene.cable_names))])
        self.cables = tuple(c for c in scene.cable_names if c not in self._mounting_of_cable)

    def _attachment_maps(self, scene, layout):
        """Sinkers and floats: the nodes sharing each one's mass and volume (as Net.build shares them)."""
        where = layout.attached_where

        def shares(calls):
            nodes = [layout.attached[i] for i in calls]
            node = np.concatenate(nodes) if nodes else np.zeros(0, np.int64)
            call = np.concatenate([np.full(len(n), k) for k, n in enumerate(nodes)]) if nodes else np.zeros(0, np.int64)
            share = np.concatenate([np.full(len(n), 1.0 / len(n)) for n in nodes]) if nodes else np.zeros(0)
            return node, call, share

        self.sinkers = tuple(_unique_names([describe_reference(where[i], short=True) for i, _, _ in layout.sinkers]))
        self._sinker_mass_ref = np.array([m for _, m, _ in layout.sinkers], dtype=float)
        self._sinker_density = np.array([d for _, _, d in layout.sinkers], dtype=float)
        self._sinker_shares = shares([i for i, _, _ in layout.sinkers])
        self.floats = tuple(_unique_names([describe_reference(where[i], short=True) for i, *_ in layout.floats]))
        self._buoyancy_ref = np.array([b for _, b, _, _, _ in layout.floats], dtype=float)
        self._float_gravity_rho = np.array([g * rho for _, _, g, rho, _ in layout.floats], dtype=float)
        # a float's volume (B / g + own mass) / rho must stay >= 0: B >= -its own weight
        self._float_least = np.array([-m * g for _, _, g, _, m in layout.floats], dtype=float)
        self._float_shares = shares([i for i, *_ in layout.floats])

    def _reference_theta(self, layout):
        """θ at the reference design, every family, every entry (jnp float64 arrays)."""
        f = lambda v: jnp.asarray(v, dtype=float)  # noqa: E731
        theta = {
            "cut": {p: f(self._corners[p]) for p in self.panels},
            "mesh_side": {p: f(self._twines[p].l0) for p in self.panels},
            "twine_diameter": {p: f(self._twines[p].diameter) for p in self.panels if self._twines[p].diameter > 0},
            "ea": {p: f(self._twines[p].ea) for p in self.panels if self._twines[p].ea > 0},
            "hanging_ratio": {},
            "sinker_mass": {s: f(m) for s, m in zip(self.sinkers, self._sinker_mass_ref)},
            "buoyancy": {s: f(b) for s, b in zip(self.floats, self._buoyancy_ref)},
            "cable_length": {c: f(self._cable_length_ref[self.reference.cable_names.index(c)]) for c in self.cables},
        }
        # stretched lengths at the reference (for the reference E): the same formula as scene()
        stretched = self._border_sides @ np.asarray(self._side_stretched(theta))
        self.mountings = {}
        for k, (name, (sides, cables, fixed, mounted, _)) in enumerate(self._mounting_specs.items()):
            self.mountings[name] = Mounting(name, sides, cables, fixed, mounted, float(stretched[k]))
            theta["hanging_ratio"][name] = f(mounted / float(stretched[k]))
        self._hanging_ref = np.array([float(theta["hanging_ratio"][n]) for n in self.mountings])
        return theta

    # -- θ -------------------------------------------------------------------------------------------

    def initial(self) -> dict:
        """θ at the reference design: {family: {entry: array}} with every family and entry (see the module
        docstring for keys, shapes and units)."""
        return jax.tree_util.tree_map(lambda v: v, self._initial)

    def complete(self, theta) -> dict:
        """θ with the reference value for every family and entry it does not hold. Raises ValueError for an
        unknown family or entry, a non-dict family or an entry of the wrong shape."""
        if not isinstance(theta, dict):
            raise ValueError(f"design parameters: expected a dict of families {sorted(FAMILIES)}, "
                             f"got {type(theta).__name__}")
        full = {family: dict(entries) for family, entries in self._initial.items()}
        for family, entries in theta.items():
            if family not in FAMILIES:
                raise ValueError(f"design parameters: unknown family {family!r} (families: {sorted(FAMILIES)})")
            if not isinstance(entries, dict):
                raise ValueError(f"{family}: expected a dict {{name: value}}, got {type(entries).__name__}")
            for name, value in entries.items():
                if name not in full[family]:
                    raise ValueError(self._unknown_entry(family, name))
                # kept as given: inside a trace jnp.asarray would make a concrete value a tracer, unchecked
                want = np.shape(full[family][name])
                if np.shape(value) != want:
                    raise ValueError(f"{family}[{name!r}]: expected shape {want}, got {np.shape(value)}")
                full[family][name] = value
        return full

    def _unknown_entry(self, family, name):
        if family == "cable_length" and name in self._mounting_of_cable:
            mounting = self._mounting_of_cable[name][0]
            return (f"cable_length[{name!r}]: this rope is sewn along netting; its length is set by "
                    f"hanging_ratio[{mounting!r}]")
        known = sorted(self._initial[family])
        return f"{family}: no entry {name!r} (entries: {known})"

    def check(self, theta) -> None:
        """Raise ValueError naming the family, entry (panel, mounting, sinker...) and corner if θ is not a valid
        design: non-finite values; l0, diameter, EA, cable lengths or hanging ratios not > 0; sinker masses
        < 0; a float left with a negative volume; a cut whose polygon is degenerate or self-intersecting, or
        that turns a triangle of the reference mesh over; or a design needing a model term the reference
        does not have (see the module docstring). Entries that are tracers, or the reference's own values,
        are not looked at."""
        self._checked(self.complete(theta))

    def _checked(self, full):
        """:meth:`check` of a complete θ; the concrete scene it built to compare the terms, or None."""
        # the reference's own values are valid (Net.build validated them): only new concrete values are checked
        concrete = {f: {k: np.asarray(v, dtype=float) for k, v in e.items()
                        if _is_concrete(v) and v is not self._initial[f][k]} for f, e in full.items()}
        for family, entries in concrete.items():
            for name, value in entries.items():
                bad = np.argwhere(~np.isfinite(value))
                if bad.size:
                    where = f" at corner {int(bad[0][0])}" if family == "cut" else ""
                    raise ValueError(f"{family}[{name!r}]: non-finite value{where} ({value.tolist()})")
        positive = {"mesh_side": "the mesh side l0 (m)", "twine_diameter": "the twine diameter (m)",
                    "ea": "the twine stiffness EA (N)", "cable_length": "the cable length (m)",
                    "hanging_ratio": "the hanging ratio"}
        for family, what in positive.items():
            for name, value in concrete[family].items():
                if not value > 0:
                    raise ValueError(f"{family}[{name!r}]: {what} must be > 0, got {float(value)!r}")
        for name, value in concrete["sinker_mass"].items():
            if not value >= 0:
                raise ValueError(f"sinker_mass[{name!r}]: a sinker's mass (kg) must be >= 0, got {float(value)!r}")
        for k, name in enumerate(self.floats):
            if name in concrete["buoyancy"]:
                least = self._float_least[k]
                if not concrete["buoyancy"][name] >= least:
                    raise ValueError(f"buoyancy[{name!r}]: {float(concrete['buoyancy'][name])!r} N leaves the float a "
                                     f"negative volume (buoyancy must be >= -its own weight = {least:g} N)")
        for name, corners in concrete["cut"].items():
            self._check_cut(name, corners)
        changed = any(concrete.values())
        if changed and all(_is_concrete(v) for v in jax.tree_util.tree_leaves(full)):
            scene = self._concrete_scene(full)
            needed = self._term_keys(scene) - self._active
            if needed:
                raise ValueError(
                    f"design parameters: this design needs model terms the reference design does not have "
                    f"({', '.join(sorted(n for n, _ in needed))}); the terms are chosen once from space.reference, so "
                    "build the net with a non-zero value of the parameter that makes them (e.g. a sinker's mass)")
            return scene
        return None

    def _concrete_scene(self, full):
        """The scene of a concrete complete θ as concrete arrays, also while a jit is tracing (when every jnp
        operation, even on constants, is staged: then evaluated one by one, slower but rare)."""
        if isinstance(jnp.zeros(()), jax.core.Tracer):
            with jax.ensure_compile_time_eval():
                return self._scene(full)
        return self._scene(full)

    def _check_cut(self, name, corners):
        from jaxnet.mesh.polygon import PanelError, check_polygon

        try:
            check_polygon(corners, name)
        except PanelError as err:
            raise ValueError(f"cut[{name!r}]: {err}") from err
        rows = self._panel_rows[name]
        uv = np.einsum("evc,cd->evd", self._uv_weights[rows][:, :, :len(corners)], corners)
        d_new = np.asarray(_determinant(uv))
        d_ref = np.asarray(_determinant(self._uv_ref[rows]))
        flipped = np.flatnonzero(d_new * np.sign(d_ref) <= 1e-9 * np.abs(d_ref))
        if flipped.size:
            moved = np.linalg.norm(corners - np.asarray(self._initial["cut"][name]), axis=1)
            raise ValueError(
                f"cut[{name!r}]: triangle {int(rows[flipped[0]])} of the reference mesh turns over (its twine "
                f"determinant d goes from {d_ref[flipped[0]]:.3g} to {d_new[flipped[0]]:.3g}): the corners moved too "
                f"far from the reference cut (most at corner {int(np.argmax(moved))}, by {moved.max():.3g} twines); "
                "build the design space from a net drawn nearer this cut")

    @staticmethod
    def _term_keys(scene):
        return {(t.name, t.options) for t in model.active_terms(scene)}

    # -- θ -> scene ------------------------------------------------------------------------------------

    def scene(self, theta) -> Scene:
        """The :class:`~jaxnet.scene.Scene` of design θ (a dict holding any subset of the families and
        entries of :meth:`initial`; the rest at the reference). Differentiable in every float of θ;
        jit-able and vmap-able. Concrete entries are checked first (:meth:`check`)."""
        full = self.complete(theta)
        if any(_is_concrete(v) for v in jax.tree_util.tree_leaves(full)):
            scene = self._checked(full)
            if scene is not None:  # built concrete by the check (the same function): not built twice
                return scene
        return self._scene(full)

    def pullback(self, theta, cotangent) -> dict:
        """The gradient in θ of a function of the scene, given its gradient in the scene's float arrays: the
        vector-Jacobian product of :meth:`scene` at θ (complete or not; the result is complete).

        ``cotangent``: a pytree shaped as ``eqx.partition(scene, eqx.is_inexact_array)[0]`` (the scene's float
        arrays, e.g. :attr:`jaxnet.solve.adjoint_statics.Gradient.grad`); its arrays that θ does not move
        (the current, the catch) are not used. One compiled program per design space (the design map's
        reverse mode)."""
        t = jax.tree_util.tree_map(lambda v: jnp.asarray(v, float), self.complete(theta))
        if self._moved_fields is None:  # which arrays θ moves: traced once (the structure, not the values)
            self._moved_fields = {name: tuple(fields) for name, fields in jax.eval_shape(self._moved_arrays, t).items()}
        bar = {name: {field: jnp.asarray(getattr(getattr(cotangent, name), field)) for field in fields}
               for name, fields in self._moved_fields.items()}
        return self._pullback(t, bar)

    def _vjp_moved(self, t, bar):
        return jax.vjp(self._moved_arrays, t)[1](bar)[0]

    def _family_vector(self, t, family, reference):
        """(P,) values of a per-panel family in panel order (the reference where a panel is left out)."""
        return jnp.stack([jnp.asarray(t[family][p], float) if p in t[family] else jnp.asarray(reference[k], float)
                          for k, p in enumerate(self.panels)]) if self.panels else jnp.zeros(0)

    def _side_ends(self):
        """Each mounted side's first and last corner in the panels' corners put end to end (``self.panels``'
        order), and its panel's slot: the gathers of :meth:`_side_stretched`."""
        first, count = {}, 0
        for p in self.panels:
            first[p], count = count, count + len(self._corners[p])
        start = [first[p] + k for p, k in self._mounted_sides]
        end = [first[p] + (k + 1) % len(self._corners[p]) for p, k in self._mounted_sides]
        slot = [self.panels.index(p) for p, _ in self._mounted_sides]
        return tuple(np.asarray(a, dtype=np.int64) for a in (start, end, slot))

    def _side_stretched(self, t):
        """(S,) stretched length (m) of each mounted side: (|dU| + |dV|) l0, one gather for all of them (a loop
        over the sides would trace, and differentiate, one small program per side)."""
        if not self._mounted_sides:
            return jnp.zeros(0)
        start, end, slot = self._side_ends()
        corners = jnp.concatenate([jnp.asarray(t["cut"][p], float) for p in self.panels])
        l0 = jnp.stack([jnp.asarray(t["mesh_side"][p], float) for p in self.panels])
        return cut_lib.stretched_length(corners[end] - corners[start], l0[slot])

    def _scene(self, t):
        """The scene of a complete θ (no checks): the reference with the moved arrays put in."""
        moved = self._moved(jax.tree_util.tree_map(lambda v: jnp.asarray(v, float), t))
        ref = self.reference
        parts = {}
        for name in ("nodes", "netting", "hinges", "bars"):
            if name in moved:
                parts[name] = dataclasses.replace(getattr(ref, name), **moved[name])
        return dataclasses.replace(ref, **parts)

    def _moved_arrays(self, t):
        """{family of the scene: {field: array}}: every float array of the scene that θ moves (jitted once per
        design space in ``_moved``: one compiled program instead of dozens of small eager ones)."""
        ref = self.reference
        netting, nodes = ref.netting, ref.nodes
        out = {}
        if netting is not None and self.panels:
            corners = jnp.concatenate([t["cut"][p] for p in self.panels])
            uv = jnp.einsum("evc,ecd->evd", self._uv_weights, corners[self._uv_corners])
            l0 = self._family_vector(t, "mesh_side", self._l0_ref)
            ea = self._family_vector(t, "ea", self._ea_ref)
            ratio = jnp.where(self._ea_ref > 0, ea / np.where(self._ea_ref > 0, self._ea_ref, 1.0), 1.0)
            diameter = self._family_vector(t, "twine_diameter", self._diameter_ref)
            slot = self._row_slot
            l0_row, ea_row = l0[slot], ea[slot]
            out["netting"] = dict(uv=uv, l0=l0_row, ea_traction=ea_row, diameter=diameter[slot],
                                  ea_compression=jnp.asarray(netting.ea_compression) * ratio[slot])
            if netting.knot_stiffness is not None and self._knot_default.any():
                size = np.where(self._knot_default, self._knot_size, 1.0)  # no 0/0 where the default is not used
                out["netting"]["knot_stiffness"] = jnp.where(self._knot_default, l0_row**2 * ea_row / (100.0 * size),
                                                             jnp.asarray(netting.knot_stiffness))
            if ref.hinges is not None:
                out["hinges"] = dict(uv=uv[self._hinge_tri, self._hinge_slot], l0=l0_row[self._hinge_first])
        position = jnp.asarray(nodes.position)
        names = list(self.mountings)
        if names:
            hanging = jnp.stack([t["hanging_ratio"][n] for n in names]) / self._hanging_ref
            stretched = self._side_stretched(t)
            side_factor = stretched / self._side_stretched_ref
            border = hanging * (self._border_sides @ stretched) / (self._border_sides @ self._side_stretched_ref)
            if self._fixed_nodes.size:
                scale = border[self._fixed_group] - 1.0
                position = position.at[self._fixed_nodes].add(scale[:, None] * self._fixed_offset)
        if ref.bars is not None:
            factor = []
            for k, c in enumerate(ref.cable_names):
                if c in self._mounting_of_cable:
                    mounting, side = self._mounting_of_cable[c]
                    factor.append(hanging[names.index(mounting)] * side_factor[side])
                else:
                    factor.append(t["cable_length"][c] / self._cable_length_ref[k])
            out["bars"] = dict(rest_length=jnp.asarray(ref.bars.rest_length) * jnp.stack(factor)[self._bar_cable])
        mass, volume = jnp.asarray(nodes.mass), jnp.asarray(nodes.volume)
        if self.sinkers:
            node, call, share = self._sinker_shares
            dm = jnp.stack([t["sinker_mass"][s] for s in self.sinkers]) - self._sinker_mass_ref
            mass = mass.at[node].add(share * dm[call])
            volume = volume.at[node].add(share * (dm / self._sinker_density)[call])
        if self.floats:
            node, call, share = self._float_shares
            db = jnp.stack([t["buoyancy"][s] for s in self.floats]) - self._buoyancy_ref
            volume = volume.at[node].add(share * (db / self._float_gravity_rho)[call])
        out["nodes"] = dict(position=position, mass=mass, volume=volume)
        return out

    # -- what a designer reads ------------------------------------------------------------------------

    def stretched_length(self, theta) -> dict:
        """{mounting: stretched length (m) of its border} at design θ (differentiable)."""
        full = self.complete(theta)
        if not self.mountings:
            return {}
        per_border = self._border_sides @ self._side_stretched(full)
        return {name: per_border[k] for k, name in enumerate(self.mountings)}

    def mounted_length(self, theta) -> dict:
        """{mounting: mounted length (m)} = E × stretched length, at design θ (differentiable)."""
        full = self.complete(theta)
        stretched = self.stretched_length(full)
        return {name: jnp.asarray(full["hanging_ratio"][name], float) * s for name, s in stretched.items()}

    def twine_length(self, theta) -> dict:
        """{panel: total twine length (m)} at design θ: 4 l0 per mesh, the panel's meshes being its area in
        (U, V) / 2 (:func:`cut.panel_meshes`); equal to Σ |d| l0 over its triangles. Differentiable."""
        full = self.complete(theta)
        return {p: 4.0 * jnp.asarray(full["mesh_side"][p], float) * cut_lib.panel_meshes(full["cut"][p])
                for p in self.panels}

    def rounded(self, theta, step="mesh"):
        """(θ with every cut rounded to whole meshes, report): :func:`cut.round_cut` on each panel, ``step``
        "mesh" (whole meshes) or "twine" (whole twines: bar cuts too). Each corner's *change from the
        reference cut* is rounded: the reference comes back as it is, even where it was drawn on fractions of a
        mesh (FEMNET's files often put corners on half meshes), and a design differs from it by whole meshes (or
        twines); a reference on whole meshes from corner 0, as the built-in nets', gives the same as rounding from
        corner 0. report: {panel: tuple of :class:`cut.SideCut`}. θ is completed with the reference values,
        checked, and returned whole."""
        full = self.complete(theta)
        out = {family: dict(entries) for family, entries in full.items()}
        report = {}
        for p in self.panels:
            corners, sides = cut_lib.round_cut(np.asarray(full["cut"][p], dtype=float), name=p,
                                               reference=self._corners[p], step=step)
            out["cut"][p] = jnp.asarray(corners)
            report[p] = sides
        self.check(out)
        return out, report

    def describe(self, theta=None) -> str:
        """A readable account of design θ (default: the reference): each panel's meshes, twine length and its
        sides (meshes along, cutting rate; ≈ for a side not on whole meshes), then every other value with
        its unit."""
        full = self.complete(self._initial if theta is None else theta)
        lines = []
        twine = self.twine_length(full)
        for p in self.panels:
            corners = np.asarray(full["cut"][p], dtype=float)
            meshes = float(cut_lib.panel_meshes(corners))
            lines.append(f"panel {p!r}: {meshes:.6g} meshes, {float(twine[p]):.6g} m of twine")
            for k in range(len(corners)):
                d = corners[(k + 1) % len(corners)] - corners[k]
                du, dv = 0.5 * (d[0] - d[1]), 0.5 * (d[0] + d[1])
                whole = np.all(np.abs(d - np.rint(d)) <= 1e-6) and np.any(np.rint(d) != 0)
                rate = cut_lib.cutting_rate(*np.rint(d)) if np.any(np.rint(d) != 0) else "-"
                lines.append(f"  side {k}: {float(cut_lib.side_meshes(d)):.6g} meshes, {'' if whole else '≈'}{rate} "
                             f"(du {du:+.6g}, dv {dv:+.6g} meshes)")
        for family in ("mesh_side", "twine_diameter", "ea", "sinker_mass", "buoyancy", "cable_length"):
            unit = FAMILIES[family][0]
            for name, value in full[family].items():
                lines.append(f"{family}[{name!r}] = {float(value):.6g} {unit}")
        stretched, mounted = self.stretched_length(full), self.mounted_length(full)
        for name, m in self.mountings.items():
            e = float(full["hanging_ratio"][name])
            ropes = ", ".join(m.cables)
            held = ("fixed nodes" + (f" and ropes {ropes}" if m.cables else "")) if m.fixed else f"rope {ropes}"
            lines.append(f"hanging_ratio[{name!r}] = {e:.6g} (mounted {float(mounted[name]):.6g} m on {held}, stretched "
                         f"{float(stretched[name]):.6g} m{'; more than fully stretched' if e > 1 else ''})")
        return "\n".join(lines)


def _determinant(uv):
    """Twine determinant d (4.7) of rows of (3, 2) twine coordinates (numpy)."""
    from jaxnet.geometry import twine_determinant

    return twine_determinant(np.asarray(uv))
