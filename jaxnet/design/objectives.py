"""The figures of a net design: differentiable scalars of an equilibrium (drag, volume, opening, tension, material).

Gradient-based design needs scalars of an equilibrium x*(θ) whose gradients flow both into the
positions x (and from there, by the implicit function theorem of :mod:`jaxnet.solve.implicit`, into θ) and
directly into the scene's float leaves (twine diameter, l0, EA, ...). A *figure* here is a small equinox
Module called on an :class:`Outcome` (the positions, the scene, its active terms) and returning a scalar;
being a pytree, a figure's own settings (a target shape, a direction) are leaves too, and figures nest into
weighted sums, constraints and penalised objectives that are figures again. Every figure is a pure jnp
function of the outcome: jit-able, vmap-able over a batch of positions or scenes, with finite gradients
everywhere (safe norms and double-``where`` at the degenerate points, stated figure by figure).

Nothing physical is recomputed here: drag forces come from :func:`jaxnet.model.assemble.forces` restricted to
the model's drag terms, tensions from :mod:`jaxnet.terms.tension`, :mod:`jaxnet.terms.cable` and
:mod:`jaxnet.terms.hexagonal`, volumes from :func:`jaxnet.model.catch.enclosed_volume`, twine counts from
:mod:`jaxnet.geometry` (|d| twines per triangle, eqs 4.25-4.26), so a figure agrees with the solver's
own physics by construction.

Figures (factories return the Modules; units in each docstring):
  * :func:`drag` (N), :func:`volume` (m³), :func:`opening` (m²), :func:`shape_distance` (m or m²),
    :func:`height` (m: a headline over the ground or the footrope), :func:`spread` (m: door or wing-end
    spread, the swept width), :func:`ratio` (drag per swept width, N/m), :func:`catch_diameter` (m),
    :func:`max_tension` (N, a smooth upper bound of the largest tension), :func:`twine_length` (m),
    :func:`material` (kg, or a cost), :func:`netting_area` (m²);

Figures combine into objectives and constraints in :mod:`jaxnet.design.constraints` (weighted sums,
constraints with their penalties, box bounds on the design parameters).

Bad settings raise ValueError naming the parameter when the figure is made, or, for what needs the scene
(node indices, a missing enclosure), when it is first called, i.e. while tracing, before any compilation.
"""

from __future__ import annotations

import math
from typing import Any

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import geometry, model as model_lib
from jaxnet.model import assemble, catch as catch_lib
from jaxnet.scene import mirror_copies
from jaxnet.terms import cable, hexagonal, tension, term as term_lib

#: element families that carry tensions (and material): diamond netting, hexagonal netting, cable bars
TENSION_FAMILIES = ("netting", "hexagonal", "bars")


class Outcome(eqx.Module):
    """What an objective sees: an equilibrium and the design it belongs to.

    x: (N, 3) equilibrium node positions (m).
    scene: the design's :class:`jaxnet.scene.Scene`; its float leaves may be tracers (design gradients).
    model: the active terms (static), :func:`jaxnet.model.active_terms` of a *concrete* reference scene
      (``implicit.structure_of(scene).model``); it decides which drag terms exist, not their values.
    """

    x: jax.Array
    scene: Any
    model: tuple = eqx.field(static=True)


def outcome(x, scene, model=None) -> Outcome:
    """An :class:`Outcome` of positions ``x`` ((N, 3) m, or anything with an ``.x``, e.g. a
    :class:`jaxnet.solve.results.Equilibrium`) of ``scene``. ``model``: the active terms; None to read them
    from ``scene``, which must then be concrete (pass the model when the scene's leaves are traced)."""
    x = jnp.asarray(getattr(x, "x", x))
    if x.ndim != 2 or x.shape[-1] != 3:
        raise ValueError(f"outcome: x must be (N, 3) node positions, got shape {x.shape}")
    if x.shape[0] != scene.n_nodes:
        raise ValueError(f"outcome: x has {x.shape[0]} nodes, the scene {scene.n_nodes}")
    return Outcome(x, scene, model_lib.active_terms(scene) if model is None else tuple(model))


class Figure(eqx.Module):
    """A scalar figure of an :class:`Outcome`: ``figure(outcome) -> ()``."""

    def __call__(self, outcome: Outcome) -> jax.Array:
        raise NotImplementedError


# -- checks (on concrete settings, before anything is traced) ---------------------------------------


def _vector(value, what, unit=False):
    """A concrete (3,) float vector, finite, and non-zero if ``unit`` (then normalised)."""
    v = np.asarray(value, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{what} must be 3 finite numbers, got {value!r}")
    if unit:
        n = float(np.linalg.norm(v))
        if n == 0.0:
            raise ValueError(f"{what} must not be the zero vector")
        v = v / n
    return v


def _node_indices(nodes, what, at_least):
    """Node indices as a tuple of ints: a static setting (the figure's shape), so they can be checked
    against the scene whenever the figure is traced."""
    idx = np.asarray(nodes)
    if idx.ndim != 1 or idx.size < at_least or not (idx.size == 0 or np.issubdtype(idx.dtype, np.integer)):
        raise ValueError(f"{what} must be a 1-D sequence of at least {at_least} node indices, got {nodes!r}")
    if np.any(idx < 0):
        raise ValueError(f"{what}: negative node index {int(idx[idx < 0][0])}")
    return tuple(int(i) for i in idx)


def _nodes_of(idx, x, what):
    """The (M,) index array of static node indices, checked against the N nodes of x."""
    if max(idx) >= x.shape[0]:
        raise ValueError(f"{what}: node index {max(idx)} outside 0..{x.shape[0] - 1}")
    return np.asarray(idx)


def finite_number(value, what, positive=False, nonnegative=False):
    """A concrete finite float, or a ValueError naming ``what`` (a tracer passes unchecked: it was checked when
    the figure was made)."""
    if isinstance(value, jax.core.Tracer):
        return value
    v = float(value)
    if not math.isfinite(v) or (positive and v <= 0.0) or (nonnegative and v < 0.0):
        kind = " positive" if positive else " non-negative" if nonnegative else ""
        raise ValueError(f"{what} must be a finite{kind} number, got {value!r}")
    return v


def _unit(v):
    """v / |v| with a finite derivative (a zero vector gives zero)."""
    n = geometry.safe_norm(v)
    return v * jnp.where(n > 0.0, 1.0 / jnp.where(n > 0.0, n, 1.0), 0.0)


def _safe_sqrt(s):
    """sqrt with derivative 0 at 0 (instead of inf): the figure has a kink (a cone) there."""
    positive = s > 0.0
    return jnp.where(positive, jnp.sqrt(jnp.where(positive, s, 1.0)), 0.0)


# -- hydrodynamics -------------------------------------------------------------------------------------


class Drag(Figure):
    """Total hydrodynamic force on the net along a direction (N); see :func:`drag`."""

    direction: jax.Array | None
    terms: tuple = eqx.field(static=True)
    whole_net: bool = eqx.field(static=True, default=False)

    def __call__(self, o: Outcome):
        copies = mirror_copies(o.scene) if self.whole_net else 1
        chosen = tuple(t for t in o.model if t.name in self.terms)
        if any(dict(t.options).get("moving") for t in chosen):
            raise ValueError("drag: the model is a dynamic one (active_terms(scene, dynamic=True)); drag is a figure "
                             "of a static equilibrium: pass the static model")
        if not chosen:  # still water, or none of the chosen terms in this scene
            return jnp.zeros((), o.x.dtype)
        total = jnp.sum(assemble.forces(o.x, o.scene, chosen), axis=0)
        d = o.scene.environment.current_direction if self.direction is None else self.direction
        return copies * jnp.dot(total, _unit(jnp.asarray(d, o.x.dtype)))


def drag(direction=None, terms=None, whole_net=False) -> Drag:
    """Hydrodynamic drag (N): the sum over all nodes of the forces of the drag terms, along ``direction``.

    direction: (3,) any non-zero length; None: the scene's current direction (the towing resistance of a
      trawl, the current load of a cage, positive downstream).
    terms: names of the force terms counted (default :func:`jaxnet.terms.term.hydrodynamic_terms`: twine, bar
      and node drag and the catch's pressure; ``("netting_drag",)`` for the netting alone); terms absent from the model
      count zero. The force of the modelled part (a quarter model gives a quarter of the cod-end's drag),
      which is what the model's reactions balance; with ``whole_net``, that of the whole net, the part's times
      its mirror copies (:func:`jaxnet.scene.mirror_copies`: 2 for a half trawl; ``direction`` should then lie in
      the symmetry planes, as the current of a symmetric model does, for the copies' drags to add up).
    Differentiated through everything the forces depend on, the catch front's position included (implicit
    function theorem, :func:`jaxnet.model.catch.catch_front`). Smooth, except with a catch: C¹ where the front
    sweeps a node, a kink where an edge lies in the front plane (:mod:`jaxnet.terms.pressure`) and where the
    net just holds the catch (the front jumps to the mouth); gradients finite throughout.
    """
    force_terms = {t.name for t in term_lib.registered() if t.kind == term_lib.FORCE}
    terms = term_lib.hydrodynamic_terms() if terms is None else tuple(terms)
    unknown = [t for t in terms if t not in force_terms]
    if unknown or not terms:
        raise ValueError(f"drag: terms must be force terms among {sorted(force_terms)}, got {unknown or terms!r}")
    return Drag(None if direction is None else jnp.asarray(_vector(direction, "drag: direction", unit=True)), terms,
                bool(whole_net))


# -- shape -----------------------------------------------------------------------------------------


class Volume(Figure):
    """Volume held by the net behind a plane (m³); see :func:`volume`."""

    center: jax.Array | None
    axis: jax.Array | None

    def __call__(self, o: Outcome):
        scene, net = o.scene, o.scene.netting
        if net is None or net.outward is None:
            raise ValueError("volume: the scene has no netting with an outward side (Net.enclose or Net.catch "
                             "sets it)")
        symmetry = 1.0
        if self.center is not None:
            center, axis = self.center, self.axis
        elif scene.enclosure is not None:
            center, axis = scene.enclosure.center, scene.enclosure.axis
        elif scene.catch is not None:
            center, axis, symmetry = scene.catch.center, scene.catch.axis, scene.catch.symmetry
        else:
            raise ValueError("volume: the scene has neither an enclosure nor a catch; give center and axis")
        axis = _unit(jnp.asarray(axis, o.x.dtype))
        front = jnp.dot(jnp.asarray(center, o.x.dtype), axis)
        return catch_lib.enclosed_volume(o.x, net.vertices, front, axis, symmetry, sign=net.outward)


def volume(center=None, axis=None) -> Volume:
    """Volume (m³) enclosed by the netting behind the plane through ``center`` (3,) normal to ``axis`` (3,),
    the axis pointing into the net (:func:`jaxnet.model.catch.enclosed_volume`, divergence theorem).

    Default plane: the scene's enclosure (a cage's collar plane), else its catch's (the opening of a cod-end,
    then the whole cod-end: × ``Catch.symmetry``). The netting must close the volume with the plane (and
    with symmetry planes containing the axis), its outward side given by ``Netting.outward``.
    C¹ in the positions (its gradient is the consistent load pattern of a unit pressure behind the plane,
    :mod:`jaxnet.terms.pressure`, continuous); that gradient has a kink where an edge of the netting lies in
    the plane (a cage's collar at rest): finite everywhere.
    """
    if (center is None) != (axis is None):
        raise ValueError("volume: give both center and axis, or neither (the scene's enclosure or catch)")
    if center is None:
        return Volume(None, None)
    return Volume(jnp.asarray(_vector(center, "volume: center")), jnp.asarray(_vector(axis, "volume: axis", unit=True)))


class Opening(Figure):
    """Area of a ring of nodes projected on the plane normal to an axis (m²); see :func:`opening`."""

    nodes: tuple = eqx.field(static=True)
    axis: jax.Array | None
    center: jax.Array | None
    symmetry: float

    def __call__(self, o: Outcome):
        axis = o.scene.environment.current_direction if self.axis is None else self.axis
        axis = _unit(jnp.asarray(axis, o.x.dtype))
        p = o.x[_nodes_of(self.nodes, o.x, "opening: nodes")]
        if self.center is None:  # a closed ring: wrap around, about its mean (any origin gives the same)
            q = p - jnp.mean(p, axis=0)
            pairs = jnp.cross(q, jnp.roll(q, -1, axis=0))
        else:  # an open arc, closed through the centre (a fan)
            q = p - jnp.asarray(self.center, o.x.dtype)
            pairs = jnp.cross(q[:-1], q[1:])
        # shoelace in 3-D: the projected area is half the axial component of sum q_i ^ q_{i+1};
        # |.| makes it independent of the ring's orientation (a kink only at zero area)
        return self.symmetry * 0.5 * jnp.abs(jnp.sum(pairs @ axis))


def opening(nodes, axis=None, center=None, symmetry=1.0) -> Opening:
    """Opening area (m²) of a ring of nodes (the mouth of a trawl, a cod-end's section), projected on the
    plane normal to ``axis`` (shoelace formula).

    nodes: node indices in order around the ring (closed: the last joins the first), or, with ``center``,
      along an arc closed through ``center`` (3,) (m): e.g. a quarter model's mouth, from one symmetry
      plane to the other, with center a point of the axis.
    axis: (3,) the normal of the projection plane; None: the scene's current direction.
    symmetry: copies of the modelled part in the whole opening (4 for a quarter model).
    Smooth, except at zero area (|.|: a kink, gradient finite).
    """
    idx = _node_indices(nodes, "opening: nodes", 2 if center is not None else 3)
    axis = None if axis is None else jnp.asarray(_vector(axis, "opening: axis", unit=True))
    center = None if center is None else jnp.asarray(_vector(center, "opening: center"))
    return Opening(idx, axis, center, finite_number(symmetry, "opening: symmetry", positive=True))


class ShapeDistance(Figure):
    """RMS (or mean square) distance of nodes to a target shape; see :func:`shape_distance`."""

    target: jax.Array
    nodes: tuple | None = eqx.field(static=True)
    weights: jax.Array | None
    squared: bool = eqx.field(static=True)

    def __call__(self, o: Outcome):
        p = o.x if self.nodes is None else o.x[_nodes_of(self.nodes, o.x, "shape_distance: nodes")]
        if p.shape != self.target.shape:
            raise ValueError(f"shape_distance: target has shape {self.target.shape}, the selected nodes {p.shape}")
        d2 = jnp.sum((p - self.target) ** 2, axis=-1)
        mean = jnp.mean(d2) if self.weights is None else jnp.sum(self.weights * d2) / jnp.sum(self.weights)
        return mean if self.squared else _safe_sqrt(mean)


def shape_distance(target, nodes=None, weights=None, squared=False) -> ShapeDistance:
    """Root-mean-square distance (m) of the nodes to a target shape: sqrt(Σ w_i |x_i - t_i|² / Σ w_i).

    target: (M, 3) target positions (m) of the nodes ``nodes`` (M indices), or of all N nodes (nodes=None).
    weights: (M,) non-negative weights, not all zero; None: equal.
    squared: return the weighted mean square distance (m²) instead: smooth everywhere, while the RMS has a
      kink (a cone) at the target itself, where its gradient is taken as 0.
    """
    target = np.asarray(target, dtype=float)
    if target.ndim != 2 or target.shape[1] != 3 or not np.all(np.isfinite(target)):
        raise ValueError(f"shape_distance: target must be (M, 3) finite positions, got shape {target.shape}")
    idx = None
    if nodes is not None:
        idx = _node_indices(nodes, "shape_distance: nodes", 1)
        if len(idx) != target.shape[0]:
            raise ValueError(f"shape_distance: {len(idx)} nodes but {target.shape[0]} target positions")
    w = None
    if weights is not None:
        w = np.asarray(weights, dtype=float)
        if w.shape != target.shape[:1] or not np.all(np.isfinite(w)) or np.any(w < 0) or not np.any(w > 0):
            raise ValueError(f"shape_distance: weights must be {target.shape[0]} finite non-negative numbers, "
                             f"not all zero")
        w = jnp.asarray(w)
    return ShapeDistance(jnp.asarray(target), idx, w, bool(squared))


class CatchDiameter(Figure):
    """The catch's largest diameter (m); see :func:`catch_diameter`."""

    def __call__(self, o: Outcome):
        scene = o.scene
        c = scene.catch
        if c is None or scene.netting is None:
            raise ValueError("catch_diameter: the scene has no catch (Net.catch)")
        state = catch_lib.catch_state(o.x, scene)
        summary = catch_lib.catch_summary(o.x, scene.netting.vertices, c.axis, state["front"], symmetry=c.symmetry,
                                          sign=scene.netting.outward, center=c.center,
                                          up=scene.environment.up)
        return summary.diameter


def catch_diameter() -> CatchDiameter:
    """The catch's largest diameter (m): twice the largest distance from the cod-end's axis, along either
    transverse direction, of the netting nodes on or behind the catch front (FEMNET's "maximal catch
    diameter", :func:`jaxnet.model.catch.catch_summary`; result.json's ``catch.diameter_m``). The front moves with
    the net (:func:`jaxnet.model.catch.catch_front`, differentiated through). A maximum over nodes: its gradient is
    that of the node farthest out, with a kink where two are."""
    return CatchDiameter()


# -- the gear's geometry: heights, spreads, ratios -------------------------------------------------------------

#: axis names of the figures' ``axis`` arguments
AXES = {"x": 0, "y": 1, "z": 2, 0: 0, 1: 1, 2: 2}


def _axis(axis, what):
    if axis not in AXES or isinstance(axis, bool):
        raise ValueError(f"{what}: axis must be one of 'x', 'y', 'z' (or 0, 1, 2), got {axis!r}")
    return AXES[axis]


class Height(Figure):
    """A node's coordinate along an axis above a reference (m); see :func:`height`."""

    node: int = eqx.field(static=True)
    axis: int = eqx.field(static=True)
    above: int | None = eqx.field(static=True)
    level: float | None

    def __call__(self, o: Outcome):
        node = int(_nodes_of((self.node,) + (() if self.above is None else (self.above,)), o.x, "height: node")[0])
        if self.above is not None:
            return o.x[node, self.axis] - o.x[self.above, self.axis]
        if self.level is not None:
            return o.x[node, self.axis] - self.level
        nodes = o.scene.nodes
        message = (f"height: node {node} has no sea bed under it along axis {'xyz'[self.axis]} (no floor among its "
                   "limits, Nodes.limit_sense): give above= a node or level= a height")
        value = o.x[node, self.axis] - (0.0 if nodes.limit is None else nodes.limit[node, self.axis])
        if isinstance(nodes.limit_sense, jax.core.Tracer):
            # the scene's node types are an argument of the compiled program (jaxnet.solve.adjoint_statics):
            # checked when it runs, before the value is used
            return eqx.error_if(value, nodes.limit_sense[node, self.axis] != 1, message)
        sense = None if nodes.limit_sense is None else int(np.asarray(nodes.limit_sense)[node, self.axis])
        if sense != 1:
            raise ValueError(message)
        return value


def height(node, axis="z", above=None, level=None) -> Height:
    """Height (m) of ``node`` along ``axis`` above a reference: another node ``above`` (a headline above the
    footrope: the vertical opening of a trawl's mouth), a ``level`` (m), or, with neither, the sea bed under the
    node (its floor limit along the axis, FEMNET's "Limits" of its node type: the headline height of a bottom
    trawl over the ground). Linear in the positions: smooth."""
    node = _node_indices([node], "height: node", 1)[0]
    above = None if above is None else _node_indices([above], "height: above", 1)[0]
    if above is not None and level is not None:
        raise ValueError("height: give above (a node) or level (m), not both")
    level = None if level is None else finite_number(level, "height: level")
    return Height(node, _axis(axis, "height"), above, level)


class Spread(Figure):
    """Distance across an axis between a node and its mirror image, or another node (m); see :func:`spread`."""

    node: int = eqx.field(static=True)
    axis: int = eqx.field(static=True)
    other: int | None = eqx.field(static=True)

    def __call__(self, o: Outcome):
        nodes = (self.node,) + (() if self.other is None else (self.other,))
        _nodes_of(nodes, o.x, "spread: node")
        if self.other is not None:
            return jnp.abs(o.x[self.node, self.axis] - o.x[self.other, self.axis])
        planes = [at for axis, at in o.scene.symmetry_planes if axis == self.axis]
        if not planes:
            raise ValueError(f"spread: the scene has no symmetry plane across {'xyz'[self.axis]} "
                             f"(planes: {o.scene.symmetry_planes}); give other= the opposite node")
        return 2.0 * jnp.abs(o.x[self.node, self.axis] - planes[0])


def spread(node, axis="y", other=None) -> Spread:
    """Spread (m) of a net across ``axis``: the distance along it between ``node`` and its image in the scene's
    symmetry plane across that axis (:attr:`jaxnet.scene.Scene.symmetry_planes`), i.e. twice the node's distance
    to the plane: the door spread of a half trawl from a door's node, its wing-end spread from a wing end;
    or, with ``other``, between the two nodes (a whole net's two doors). The swept width of a trawl is its door
    spread. Smooth except where the node crosses the plane (|.|: a kink)."""
    node = _node_indices([node], "spread: node", 1)[0]
    other = None if other is None else _node_indices([other], "spread: other", 1)[0]
    return Spread(node, _axis(axis, "spread"), other)


class Ratio(Figure):
    """numerator / denominator of two figures; see :func:`ratio`."""

    numerator: Figure
    denominator: Figure

    def __call__(self, o: Outcome):
        den = self.denominator(o)
        return self.numerator(o) / jnp.where(den != 0.0, den, jnp.nan)


def ratio(numerator, denominator) -> Ratio:
    """A figure divided by another, in their units' ratio: the drag per swept width of a trawl (N/m),
    ``ratio(drag(whole_net=True), spread(door))``, or per mouth area (N/m²) with :func:`opening`. NaN where
    the denominator is 0 (the optimiser then rejects the step, as for a failed equilibrium)."""
    for name, f in (("numerator", numerator), ("denominator", denominator)):
        if not callable(f):
            raise ValueError(f"ratio: the {name} is not a figure (a callable of an Outcome): {f!r}")
    return Ratio(numerator, denominator)


# -- tensions ------------------------------------------------------------------------------------


def tensions(o: Outcome, families=TENSION_FAMILIES) -> jax.Array:
    """All twine and bar tensions (N, positive in traction) of an outcome, one flat array: per diamond
    triangle Tu and Tv (4.30-4.31), per hexagonal triangle T_l, T_m, T_n (4.85-4.87), per bar its tension;
    families absent from the scene are skipped. Slack twines (EA_c = 0) carry 0, with a kink at the slack
    point (finite one-sided gradient)."""
    scene, x, parts = o.scene, o.x, []
    if "netting" in families and scene.netting is not None:
        n = scene.netting
        tu, tv = jax.vmap(tension.netting_tensions)(x[n.vertices], n.uv, n.l0, n.ea_traction, n.ea_compression)
        parts += [tu, tv]
    if "hexagonal" in families and scene.hexagonal is not None:
        h = scene.hexagonal
        parts.append(jnp.ravel(jnp.stack(jax.vmap(hexagonal.hexagonal_tensions)(
            x[h.vertices], h.uv, h.l0, h.ea_traction, h.ea_compression))))
    if "bars" in families and scene.bars is not None:
        b = scene.bars
        parts.append(jax.vmap(cable.bar_tension)(x[b.ends], b.rest_length, b.ea_traction, b.ea_compression))
    if not parts:
        raise ValueError(f"tensions: the scene has none of the families {tuple(families)} (no twines, no bars)")
    return jnp.concatenate([jnp.ravel(p) for p in parts])


class MaxTension(Figure):
    """Smooth maximum of the tensions (N); see :func:`max_tension`."""

    softness: float
    families: tuple = eqx.field(static=True)

    def __call__(self, o: Outcome):
        t = tensions(o, self.families)
        return self.softness * jax.nn.logsumexp(t / self.softness)

    def excess_bound(self, o: Outcome):
        """Largest possible excess (N) of the figure over the true maximum tension: softness × log(n)."""
        return self.softness * jnp.log(tensions(o, self.families).size)


def max_tension(softness=1.0, families=TENSION_FAMILIES) -> MaxTension:
    """Smooth maximum (N) of the twine and bar tensions, by log-sum-exp with softness τ (N):

        M = τ log Σ_i exp(T_i / τ),     max T ≤ M ≤ max T + τ log n,

    n the number of tensions (:func:`tensions`: 2 per diamond triangle, 3 per hexagonal one, 1 per bar).
    M is an *upper* bound of the true maximum, so ``Constraint(max_tension(τ), upper=T_break)`` is
    conservative; its gradient is the softmax-weighted gradient of the tensions (finite everywhere: at ties
    and at slack twines, where each tension has a kink). Smaller τ: closer to the max, stiffer gradient.
    families: which of :data:`TENSION_FAMILIES` to include (those present in the scene).
    """
    families = tuple(families)
    unknown = [f for f in families if f not in TENSION_FAMILIES]
    if unknown or not families:
        raise ValueError(f"max_tension: families must be among {TENSION_FAMILIES}, got {unknown or families!r}")
    return MaxTension(finite_number(softness, "max_tension: softness", positive=True), families)


# -- material --------------------------------------------------------------------------------------


def _twines(scene, families):
    """(count, length (m), diameter (m), density (kg/m³)) per element of each family present: a diamond
    triangle holds |d| twines of length l0 (|d|/2 U and |d|/2 V twines, 4.25-4.26), a hexagonal one |d| of
    each family (after 4.82: length the sum of the three l0), a bar one of its rest length. The same counts as
    the weight (4.277)."""
    out = []
    if "netting" in families and scene.netting is not None:
        n = scene.netting
        out.append((jnp.abs(geometry.twine_determinant(n.uv)), n.l0, n.diameter, n.density))
    if "hexagonal" in families and scene.hexagonal is not None:
        h = scene.hexagonal
        out.append((jnp.abs(geometry.twine_determinant(h.uv)), jnp.sum(h.l0, axis=-1), h.diameter, h.density))
    if "bars" in families and scene.bars is not None:
        b = scene.bars
        out.append((1.0, jnp.asarray(b.rest_length), b.diameter, b.density))
    return out


class Material(Figure):
    """Twine length (m), mass (kg) or cost of the material; see :func:`material` and :func:`twine_length`."""

    what: str = eqx.field(static=True)  # "length" or "mass"
    price_per_kg: float | None
    families: tuple = eqx.field(static=True)

    def __call__(self, o: Outcome):
        total = jnp.zeros((), o.x.dtype)
        for count, length, diameter, density in _twines(o.scene, self.families):
            per = count * length if self.what == "length" else geometry.twine_volume(count, length, diameter) * density
            total = total + jnp.sum(per)
        return total if self.price_per_kg is None else self.price_per_kg * total


def _material_families(families, what):
    families = tuple(families)
    unknown = [f for f in families if f not in TENSION_FAMILIES]
    if unknown or not families:
        raise ValueError(f"{what}: families must be among {TENSION_FAMILIES}, got {unknown or families!r}")
    return families


def twine_length(families=("netting", "hexagonal")) -> Material:
    """Total unstretched twine length (m) of the netting: Σ_triangles |d| l0 (|d| twines of length l0 per
    diamond triangle; Σ|d| Σ l0 for hexagonal netting); with "bars" in ``families``, plus the ropes' rest
    lengths. A function of the design (twine coordinates, l0), not of the positions: exact, smooth."""
    return Material("length", None, _material_families(families, "twine_length"))


def material(price_per_kg=None, families=("netting", "hexagonal")) -> Material:
    """Mass (kg) of the netting's twine, Σ |d| l0 π D²/4 ρ (the dry mass behind the weight of 4.277); with
    ``price_per_kg`` (currency/kg), its cost. ``families``: add "bars" to count the ropes (rest length ×
    π D²/4 × ρ). Smooth in the design (D, ρ, l0, twine coordinates); independent of the positions."""
    price = None if price_per_kg is None else finite_number(price_per_kg, "material: price_per_kg")
    return Material("mass", price, _material_families(families, "material"))


class NettingArea(Figure):
    """Area of the diamond netting (m²); see :func:`netting_area`."""

    deployed: bool = eqx.field(static=True)

    def __call__(self, o: Outcome):
        net = o.scene.netting
        if o.scene.hexagonal is not None:
            raise ValueError("netting_area: hexagonal netting has no square-mesh area; use twine_length or material")
        if net is None:
            return jnp.zeros((), o.x.dtype)
        if self.deployed:
            return jnp.sum(jax.vmap(geometry.surface)(o.x[net.vertices]))
        # |d|/2 mesh rhombi per triangle (twine-coordinate area), each l0² when square
        return jnp.sum(jnp.abs(geometry.twine_determinant(net.uv)) * net.l0**2 / 2.0)


def netting_area(deployed=False) -> NettingArea:
    """Area (m²) of the diamond netting: with ``deployed=False`` its nominal area, that of its meshes opened
    square, Σ |d| l0²/2 (|d|/2 rhombi of side l0 per triangle; for a panel of n × n meshes of side l0,
    2 n² l0²): a measure of the netting bought, independent of the shape; with ``deployed=True`` the
    surface of the netting at the positions, Σ |12 ^ 13|/2 (4.18).
    """
    return NettingArea(bool(deployed))
