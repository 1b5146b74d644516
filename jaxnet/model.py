"""Which physical terms a scene uses, decided from its concrete values before anything is traced.

A term is registered once in :data:`TERMS` (one line per term). For a given scene, :func:`active_terms`
keeps the terms whose parameters are present and non-zero and fixes their static options (e.g. whether
any twine has a compression stiffness), so the residual traced for that scene contains only those terms:
a weightless net compiles no weight, a net with EA_c = 0 everywhere no compressive branch. Each term's
element function is wrapped in a ``jax.named_scope`` of its name, so what was compiled can be read back
from the lowered program (the tests do).

Kinds of terms:
  * ``"energy"``: conservative, element energy (J) of the element's vertex positions; forces are its
    negative gradient, stiffness its Hessian (``jax.jacfwd`` of ``jax.grad``).
  * ``"load"``: a nodal force (N) independent of positions (weight of an immersed net, external forces):
    evaluated once per solve, no stiffness.
  * ``"force"``: a non-conservative element force (drag, catch pressure): ``(k, 3)`` nodal forces (N) of
    the element's vertex positions; stiffness minus its ``jax.jacfwd``. A force term may need a global
    ``state`` of the whole net (the catch front), computed once per evaluation.

Statics and dynamics. In statics the net is at rest and the water's velocity is the current's, taken at
the element's centroid. In dynamics (``active_terms(scene, dynamic=True)``) the drag terms are *moving*
(:attr:`Term.moving`): they are present wherever their coefficients are, even in still water (a net
moving through still water is dragged), and each vertex takes its share of the element's drag with the
velocity of the water *relative to that vertex* (book 4.272-4.276): the current at the vertex and at the
environment's time, plus the waves' orbital velocity there (``Environment.waves``), minus the vertex's
velocity, which the dynamic solver gives the element (``velocity``, (k, 3) m/s).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet import catch as catch_lib, current, geometry, scene as scene_lib
from jaxnet.terms import bending, bottom, cable, drag, gravity, hexagonal, knot, opening, pressure, screen, surface, tension


@dataclasses.dataclass(frozen=True)
class Term:
    """A physical term acting on one element family ("netting", "bars" or "nodes").

    element: for an energy, ``element(x, p, env, **options) -> J`` with x the (k, 3) vertex positions and
      p one row of the family; for a load, ``element(p, env, **options) -> (k, 3)`` forces in N; for a
      force, ``element(x, p, env, state, **options) -> (k, 3)`` forces in N.
    options: ``options(scene) -> dict | None``, the static choices for this scene, None if inactive.
    state: for a force term, optional ``state(x, scene, previous=None)``: a global quantity of positions x
      (N, 3), solved for; ``previous``, its value at nearby positions (the solver's last iterate), only a
      start for that solution (the same answer, sooner), or None.
    elastic: for an energy, True if it is the net's own elastic energy (twines, bars, mesh opening, knots,
      bending), which the static solver's stiffness continuation scales; False for the potentials of
      loads (weight and buoyancy at the surface) and of the surroundings (the sea bed).
    moving: for a force, True if it depends on the element's velocity relative to the water (drag): its
      ``options(scene, dynamic)`` takes the dynamic flag, and in dynamics its element takes the vertex
      velocities as the keyword ``velocity`` ((k, 3) m/s).
    """

    name: str
    family: str
    kind: str
    element: Callable
    options: Callable
    state: Callable | None = None
    elastic: bool = False
    moving: bool = False


# -- element adapters: map a family row onto the term functions ------------------------------------


def _netting_tension(x, p, env, compression):
    return tension.netting_energy(x, p.uv, p.l0, p.ea_traction, p.ea_compression if compression else None)


def _bar_tension(x, p, env, compression):
    return cable.bar_energy(x, p.rest_length, p.ea_traction, p.ea_compression if compression else None)


def _hexagonal_tension(x, p, env, compression):
    return hexagonal.hexagonal_energy(x, p.uv, p.l0, p.ea_traction, p.ea_compression if compression else None)


def _hexagonal_weight(p, env):
    # |d| twines of each family l, m, n (text after 4.82): the analogue of 4.277, one third per vertex
    d = geometry.twine_determinant(p.uv)
    w = jnp.abs(d) * jnp.pi * p.diameter**2 / 4.0 * jnp.sum(p.l0) * (p.density - env.water_density) * env.gravity
    return jnp.broadcast_to(-(w / 3.0) * env.up, (3, 3))


def _opening(x, p, env):
    return opening.opening_energy(x, p.uv, p.opening_stiffness, p.rest_angle)


#: knot contact laws (``Netting.knot_form`` codes)
KNOT_FORMS = {0: "book", 1: "femnet"}


def _knot_contact(x, p, env, forms):
    total = 0.0
    for code in forms:
        e = knot.knot_contact_energy(x, p.uv, p.l0, p.knot_size, p.knot_stiffness, form=KNOT_FORMS[code])
        total = total + (e if len(forms) == 1 else jnp.where(p.knot_form == code, e, 0.0))
    return total


def _twine_bending(x, p, env):
    return bending.hinge_energy(x, p.uv, p.l0, p.stiffness)


def _netting_weight(p, env):
    return gravity.netting_weight(p.uv, p.l0, p.diameter, p.density, env.water_density, env.gravity, env.up)


def _bar_weight(p, env):
    return gravity.bar_weight(p.rest_length, p.diameter, p.density, env.water_density, env.gravity, env.up)


def _node_weight(p, env):
    return gravity.node_weight(p.mass, p.volume, env.water_density, env.gravity, env.up)[None, :]


def _node_force(p, env):
    return p.force[None, :]


# near the free surface, weight and buoyancy depend on the height: energies (jaxnet.terms.surface)
def _netting_gravity(x, p, env):
    return surface.netting_gravity_energy(x, p.uv, p.l0, p.diameter, p.density, env.water_density, env.gravity, env.up,
                                          env.surface_level)


def _bar_gravity(x, p, env):
    return surface.bar_gravity_energy(x, p.rest_length, p.diameter, p.density, env.water_density, env.gravity, env.up,
                                      env.surface_level)


def _node_gravity(x, p, env):
    # a body given no size is taken as the sphere of its volume (1 mm at least) for its waterline band
    sphere = jnp.cbrt(6.0 * p.volume / jnp.pi)
    size = jnp.maximum(jnp.where(p.size > 0, p.size, sphere), 1e-3)
    return surface.node_gravity_energy(x[0], p.mass, p.volume, size, env.water_density, env.gravity, env.up,
                                       env.surface_level)


def _water_velocity(x, env):
    """Current (m/s) at the centroid of an element's vertices x (k, 3), inside the differentiated function
    so that the stiffness sees how the current varies with depth."""
    z = jnp.dot(geometry.centroid(x), env.up)
    return current.current_velocity(z, env.current_speed, env.current_direction, env.profile_depth,
                                    env.profile_factor, env.surface_level)


def water_velocity_at(points, env, waves):
    """Velocity (..., 3) in m/s of the water at ``points`` (..., 3) and at the environment's time: the
    current at each point's depth, plus the waves' orbital velocity when ``waves`` (static) is True."""
    z = points @ env.up
    c = current.current_velocity(z, env.current_speed, env.current_direction, env.profile_depth,
                                 env.profile_factor, env.surface_level)
    if waves:
        c = c + env.waves.velocity(points, env.time)
    return c


def _per_vertex(force, x, env, velocity, waves):
    """Dynamics (book 4.272-4.276): vertex i of an element takes its share of the element's drag computed
    with the water's velocity relative to vertex i. ``force(c) -> (k, 3)`` is the element's drag shared
    over its k vertices for a uniform relative velocity c; row i of force(c_i) is vertex i's share."""
    relative = water_velocity_at(x, env, waves) - velocity
    # one batched evaluation (not k unrolled copies: a third of the program to compile)
    shares = jax.vmap(force)(relative)  # (k, k, 3): [i] the shares of all vertices for vertex i's velocity
    return shares[jnp.arange(x.shape[0]), jnp.arange(x.shape[0])]


#: netting drag models (``Netting.drag_model`` codes), each a function of (x, p, c, rho) -> (3, 3) N
NETTING_DRAG = {
    0: ("twine_drag", lambda x, p, c, rho: drag.netting_drag(x, p.uv, p.l0, p.diameter, p.cd_normal,
                                                             p.tangential_ratio * p.cd_normal, c, rho)),
    1: ("loland_screen", lambda x, p, c, rho: screen.loland_force(x, p.uv, p.l0, p.diameter, c, rho)),
    2: ("kristiansen_faltinsen_screen", lambda x, p, c, rho: screen.kristiansen_faltinsen_force(x, p.uv, p.l0, p.diameter, c, rho)),
    # FEMNET's drag of netting ahead of a catch (trainee_front -> trainee_fil): the twine drag along the
    # current, the U twines' cross-flow part turned onto the V twines' (drag.netting_drag_femnet_catch)
    3: ("femnet_catch_drag", lambda x, p, c, rho: drag.netting_drag_femnet_catch(
        x, p.uv, p.l0, p.diameter, p.cd_normal, p.tangential_ratio * p.cd_normal, c, rho)),
}

#: the netting drag models made of twine drags (Cd, f): present only where some Cd is not zero
TWINE_DRAG_MODELS = (0, 3)


def _netting_drag(x, p, env, state, models, shielded, moving=False, waves=False, velocity=None):
    total = jnp.zeros((3, 3))
    for code in models:
        name, force = NETTING_DRAG[code]
        with jax.named_scope(name):
            if moving:
                f = _per_vertex(lambda c: force(x, p, c, env.water_density), x, env, velocity, waves)
            else:
                f = force(x, p, _water_velocity(x, env), env.water_density)
        total = total + (f if len(models) == 1 else jnp.where(p.drag_model == code, f, 0.0))
    if shielded:
        # netting behind the catch front is backed by fish: the water does not flow through it, and the
        # catch pressure (catch_pressure) replaces its drag, as in FEMNET. The part of the triangle ahead
        # of the front keeps its drag, spread as the consistent load of that part (continuous as the front
        # sweeps the element).
        behind = pressure.clipped_shape_integrals(pressure.front_heights(x, state["front"], state["axis"]))
        total = total * (1.0 - 3.0 * behind)[:, None]
    return total


def _bar_drag(x, p, env, state, moving=False, waves=False, velocity=None):
    def force(c):
        return drag.bar_drag(x, p.rest_length, p.diameter, p.cd_normal, p.tangential_ratio * p.cd_normal, c,
                             env.water_density)

    return _per_vertex(force, x, env, velocity, waves) if moving else force(_water_velocity(x, env))


def _node_water_velocity(x, env, moving, waves, velocity):
    return water_velocity_at(x[0], env, waves) - velocity[0] if moving else _water_velocity(x, env)


def _node_drag(x, p, env, state, moving=False, waves=False, velocity=None):
    c = _node_water_velocity(x, env, moving, waves, velocity)
    return drag.node_drag(p.drag_area, c, env.water_density)[None, :]


def _node_box_drag(x, p, env, state, floating, moving=False, waves=False, velocity=None):
    c = _node_water_velocity(x, env, moving, waves, velocity)
    # only with a free surface can a body be partly immersed; without one it is wholly under water
    f = drag.box_immersed_fraction(jnp.dot(x[0], env.up), p.drag_length[2], env.surface_level) if floating else 1.0
    return drag.box_drag(p.drag_length, p.drag_coefficient, c, env.water_density, f)[None, :]


def _bottom_contact(x, p, env):
    return bottom.contact_energy(x[0], p.limit, p.limit_sense, env.bottom_stiffness, env.bottom_band)


def _bottom_friction(x, p, env, state, axis, floor):
    t = bottom.sliding_direction(env.current_direction, axis)
    return bottom.friction_force(x[0], p.limit, p.limit_sense, env.bottom_stiffness, env.bottom_band,
                                 env.bottom_friction, t, axis, floor)[None, :]


def _catch_state(x, scene, previous=None):
    """The catch front (abscissa along the axis, m) for positions x, with the pressure and axis (None without a
    catch). The state of the catch pressure and of the netting drag (the shielding of the netting behind the
    front): the same function, so that :func:`jaxnet.assemble.states` solves for the front once.
    ``previous``: this state at the solver's last iterate, whose front starts the search (the front moves
    little from one iterate to the next: FEMNET's c2 takes 4-5 passes over its elements instead of 8)."""
    c, env = scene.catch, scene.environment
    if c is None:
        return None
    guess = None if previous is None else previous["front"]
    front = catch_lib.catch_front(x, scene.netting.vertices, c.axis, c.volume, c.symmetry, sign=scene.netting.outward,
                                  guess=guess)
    p = pressure.dynamic_pressure(env.water_density, c.drag_coefficient, env.current_speed)
    return {"front": front.position, "pressure": p, "axis": c.axis}


def _catch_pressure(x, p, env, state):
    return pressure.catch_pressure(x, state["pressure"], state["front"], state["axis"], p.outward)


# -- activity: which parameters make a term present ----------------------------------------------


def _any(a):
    return bool(np.any(np.asarray(a) != 0))


def _tension_options(family):
    def options(scene):
        f = getattr(scene, family)
        if f is None or not _any(f.ea_traction) and not _any(f.ea_compression):
            return None
        return {"compression": _any(f.ea_compression)}

    return options


def _floating(scene):
    return bool(np.isfinite(scene.environment.surface_level))


def _weight_options(family, volume, at_surface=False):
    """Weight of a family: a constant load when fully immersed, an energy of the heights with a free surface
    (``at_surface=None``: always the constant load, for families without a free-surface form)."""

    def options(scene):
        f = getattr(scene, family)
        env = scene.environment
        if f is None or env.gravity == 0 or (at_surface is not None and _floating(scene) != at_surface):
            return None
        net_density = np.asarray(f.density) - env.water_density
        if at_surface:  # above the surface even a neutrally buoyant net weighs
            net_density = np.asarray(f.density) + np.abs(net_density)
        if not _any(np.asarray(volume(f)) * net_density):
            return None
        return {}

    return options


def _node_weight_options(scene):
    n = scene.nodes
    if scene.environment.gravity == 0 or _floating(scene):
        return None
    if not _any(np.asarray(n.mass) - scene.environment.water_density * np.asarray(n.volume)):
        return None
    return {}


def _node_gravity_options(scene):
    n = scene.nodes
    if scene.environment.gravity == 0 or not _floating(scene) or not (_any(n.mass) or _any(n.volume)):
        return None
    return {}


def _node_force_options(scene):
    return {} if _any(scene.nodes.force) else None


def _netting_parameter_options(name):
    def options(scene):
        net = scene.netting
        value = None if net is None else getattr(net, name)
        return {} if value is not None and _any(value) else None

    return options


def _knot_options(scene):
    net = scene.netting
    if net is None or net.knot_size is None or not _any(net.knot_size):
        return None
    codes = np.zeros(1, int) if net.knot_form is None else np.asarray(net.knot_form)
    return {"forms": tuple(sorted(set(codes.tolist())))}


def _hinge_options(scene):
    return {} if scene.hinges is not None and _any(scene.hinges.stiffness) else None


def _catch_options(scene):
    if scene.catch is None or scene.netting is None or not _current(scene) or scene.catch.drag_coefficient == 0:
        return None
    return {}


def _current(scene):
    return scene.environment.current_speed > 0


def _flow(scene, dynamic):
    """Does water move relative to the net? In statics where there is a current; in dynamics always (the
    net moves, the current may start later, the waves move the water)."""
    return dynamic or _current(scene)


def _moving(scene, dynamic):
    """Static options of a moving (drag) term: per-vertex relative velocities in dynamics, and waves."""
    return {"moving": True, "waves": scene.environment.waves is not None} if dynamic else {}


def _netting_drag_options(scene, dynamic=False):
    net = scene.netting
    if net is None or not _flow(scene, dynamic) or net.drag_model is None:
        return None
    codes = np.asarray(net.drag_model)
    has_cd = (np.asarray(net.cd_normal) != 0) if net.cd_normal is not None else np.zeros(codes.shape, bool)
    screens = set(codes[~np.isin(codes, TWINE_DRAG_MODELS)].tolist())
    twines = {m for m in TWINE_DRAG_MODELS if np.any((codes == m) & has_cd)}
    models = tuple(sorted(screens | twines))
    if not models:
        return None
    return {"models": models, "shielded": scene.catch is not None, **_moving(scene, dynamic)}


def _bar_drag_options(scene, dynamic=False):
    bars = scene.bars
    if bars is None or not _flow(scene, dynamic) or bars.cd_normal is None or not _any(bars.cd_normal):
        return None
    return _moving(scene, dynamic)


def _node_drag_options(scene, dynamic=False):
    n = scene.nodes
    return _moving(scene, dynamic) if _flow(scene, dynamic) and n.drag_area is not None and _any(n.drag_area) else None


def _node_box_drag_options(scene, dynamic=False):
    n = scene.nodes
    if not _flow(scene, dynamic) or n.drag_length is None or n.drag_coefficient is None:
        return None
    length, cd = np.abs(np.asarray(n.drag_length, dtype=float)), np.asarray(n.drag_coefficient, dtype=float)
    # Cd times the area of each face (the vertical one counts when it has any size)
    faces = np.stack([length[:, 1] * length[:, 2], length[:, 0] * length[:, 2], length[:, 0] * length[:, 1]], axis=1)
    return {"floating": _floating(scene), **_moving(scene, dynamic)} if _any(cd * faces) else None


def _limits(scene):
    n = scene.nodes
    return n.limit is not None and n.limit_sense is not None and _any(n.limit_sense)


def _bottom_contact_options(scene):
    return {} if _limits(scene) and scene.environment.bottom_stiffness > 0 else None


def _bottom_friction_options(scene):
    env = scene.environment
    if _bottom_contact_options(scene) is None or not env.bottom_friction > 0 or not _current(scene):
        return None
    where = scene_lib.bottom_axis(env)
    if where is None:
        return None  # validate() names the problem
    axis, floor = where
    on_floor = np.any(np.asarray(scene.nodes.limit_sense)[:, axis] == floor)
    sliding = np.any(np.delete(np.asarray(env.current_direction, dtype=float), axis) != 0)
    return {"axis": axis, "floor": floor} if on_floor and sliding else None


#: The registry: one line per physical term.
TERMS = (
    Term("netting_tension", "netting", "energy", _netting_tension, _tension_options("netting"), elastic=True),
    Term("bar_tension", "bars", "energy", _bar_tension, _tension_options("bars"), elastic=True),
    Term("netting_weight", "netting", "load", _netting_weight, _weight_options("netting", lambda f: f.diameter)),
    Term("bar_weight", "bars", "load", _bar_weight, _weight_options("bars", lambda f: f.diameter)),
    Term("node_weight", "nodes", "load", _node_weight, _node_weight_options),
    Term("netting_gravity_at_surface", "netting", "energy", _netting_gravity,
         _weight_options("netting", lambda f: f.diameter, at_surface=True)),
    Term("bar_gravity_at_surface", "bars", "energy", _bar_gravity, _weight_options("bars", lambda f: f.diameter, at_surface=True)),
    Term("node_gravity_at_surface", "nodes", "energy", _node_gravity, _node_gravity_options),
    Term("node_force", "nodes", "load", _node_force, _node_force_options),
    Term("hexagonal_tension", "hexagonal", "energy", _hexagonal_tension, _tension_options("hexagonal"), elastic=True),
    Term("hexagonal_weight", "hexagonal", "load", _hexagonal_weight, _weight_options("hexagonal", lambda f: f.diameter, at_surface=None)),
    Term("mesh_opening", "netting", "energy", _opening, _netting_parameter_options("opening_stiffness"), elastic=True),
    Term("knot_contact", "netting", "energy", _knot_contact, _knot_options, elastic=True),
    Term("twine_bending", "hinges", "energy", _twine_bending, _hinge_options, elastic=True),
    Term("netting_drag", "netting", "force", _netting_drag, _netting_drag_options, state=_catch_state, moving=True),
    Term("bar_drag", "bars", "force", _bar_drag, _bar_drag_options, moving=True),
    Term("node_drag", "nodes", "force", _node_drag, _node_drag_options, moving=True),
    Term("node_box_drag", "nodes", "force", _node_box_drag, _node_box_drag_options, moving=True),
    Term("bottom_contact", "nodes", "energy", _bottom_contact, _bottom_contact_options),
    Term("bottom_friction", "nodes", "force", _bottom_friction, _bottom_friction_options),
    Term("catch_pressure", "netting", "force", _catch_pressure, _catch_options, state=_catch_state),
)


@dataclasses.dataclass(frozen=True)
class ActiveTerm:
    """A term with its static options for one scene (hashable: a jit static argument)."""

    term: Term
    options: tuple

    @property
    def name(self):
        return self.term.name

    def kwargs(self):
        return dict(self.options)


def active_terms(scene, dynamic=False) -> tuple[ActiveTerm, ...]:
    """The terms this scene uses, with their static options, in registry order; ``dynamic``: for a time
    step (the drag terms then act on the velocity relative to the water, see the module docstring)."""
    active = []
    for term in TERMS:
        opts = term.options(scene, dynamic) if term.moving else term.options(scene)
        if opts is not None:
            active.append(ActiveTerm(term, tuple(sorted(opts.items()))))
    return tuple(active)
