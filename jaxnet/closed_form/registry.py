"""Which terms have a closed-form stiffness, and the element functions that give it (one line per term).

``Newton(stiffness="closed_form")`` (and ``assemble.tangent(..., stiffness="closed_form")``) assembles,
for every active term listed in :data:`STIFFNESS` whose options it covers, the term's hand-derived
element matrix; the other terms (those the chapter gives no stiffness for: hexagonal meshes, weight and
buoyancy at the free surface, the sea bed, FEMNET's node boxes, the screen drag models) keep their
autodiff stiffness. Each term's matrix comes from exactly one path; :func:`paths` says which.

An element stiffness function has the signature of the term's element function (:class:`jaxnet.model.Term`)
and returns the (3k, 3k) element matrix K = -dF/dx (N/m), vertex-major (entry (3 i + m, 3 j + n):
coordinate m of vertex i, n of vertex j): ``(x, p, env, **options)`` for an energy (its Hessian),
``(x, p, env, state, **options)`` for a force (minus its Jacobian, the global state held fixed). In a time
step a moving drag (book 4.272-4.276: each vertex's share with the water's velocity relative to that vertex)
also takes the keywords ``velocity`` ((k, 3) vertex velocities, m/s) and ``time_step`` (Δt, s): its matrix
then holds the damping -(1/Δt) ∂F/∂c as well (:func:`covered`'s ``with_velocities``).
"""

from __future__ import annotations

import dataclasses
from typing import Callable

import jax.numpy as jnp

from jaxnet import geometry, model
from jaxnet.closed_form import bending, drag, knot, opening, pressure, tension
from jaxnet.terms import pressure as catch_load


@dataclasses.dataclass(frozen=True)
class ClosedForm:
    """The closed-form stiffness of one registered term.

    stiffness: the element stiffness function (module docstring).
    covers: ``covers(options) -> bool``, False for options the closed form does not cover (those elements'
      term then keeps its autodiff stiffness); None covers every option.
    """

    stiffness: Callable
    covers: Callable | None = None


def _netting_tension(x, p, env, compression):
    return tension.netting_stiffness(x, p.uv, p.l0, p.ea_traction, p.ea_compression if compression else None)


def _bar_tension(x, p, env, compression):
    return tension.bar_stiffness(x, p.rest_length, p.ea_traction, p.ea_compression if compression else None)


def _opening(x, p, env):
    return opening.opening_stiffness(x, p.uv, p.opening_stiffness, p.rest_angle)


def _knot_contact(x, p, env, forms):
    total = 0.0
    for code in forms:
        k = knot.knot_contact_stiffness(x, p.uv, p.l0, p.knot_size, p.knot_stiffness, form=model.KNOT_FORMS[code])
        total = total + (k if len(forms) == 1 else jnp.where(p.knot_form == code, k, 0.0))
    return total


def _twine_bending(x, p, env):
    return bending.hinge_stiffness(x, p.uv, p.l0, p.stiffness)


def _catch_pressure(x, p, env, state):
    return pressure.catch_pressure_stiffness(x, state["pressure"], state["front"], state["axis"], p.outward)


def _water(x, env):
    """The current at the centroid of the element's vertices x (k, 3), as the force terms see it
    (:func:`jaxnet.model._water_velocity`), and its slope dc/dz there (m/s per m of height); the slope is
    None for a uniform current (a profile of fewer than 2 points: known from the shapes, when tracing)."""
    if env.profile_depth.shape[0] < 2:
        return model._water_velocity(x, env), None
    z = jnp.dot(geometry.centroid(x), env.up)
    slope = drag.current_slope(z, env.current_speed, env.current_direction, env.profile_depth, env.profile_factor,
                               env.surface_level)
    return model._water_velocity(x, env), slope


def _water_at_vertices(x, env, waves):
    """In a time step, the water's velocity w (k, 3) at each vertex x (k, 3) as the moving drag sees it
    (:func:`jaxnet.model.water_velocity_at`: the current at the vertex's depth, plus the waves' orbital
    velocity when ``waves``) and its gradient ∂w/∂x (k, 3, 3) there (1/s): dc/dz up^T, plus the waves'."""
    w = model.water_velocity_at(x, env, waves)
    slope = drag.current_slope(x @ env.up, env.current_speed, env.current_direction, env.profile_depth,
                               env.profile_factor, env.surface_level)
    gradient = slope[:, :, None] * env.up[None, None, :]
    if waves:
        gradient = gradient + env.waves.velocity_gradient(x, env.time)
    return w, gradient


#: closed forms of the netting drag models made of twine drags (``Netting.drag_model`` codes): at rest in a
#: current, and moving (a time step: relative velocity per vertex)
_NETTING_DRAG = {0: drag.netting_drag_stiffness, 3: drag.netting_drag_femnet_catch_stiffness}
_MOVING_NETTING_DRAG = {0: drag.moving_netting_drag_stiffness, 3: drag.moving_netting_drag_femnet_catch_stiffness}


def _netting_drag(x, p, env, state, models, shielded, moving=False, waves=False, velocity=None, time_step=None):
    rho = env.water_density
    if moving:
        # in a time step (model._per_vertex): vertex i takes its share of the drag at the water's velocity
        # relative to it, c_i
        w, gradient = _water_at_vertices(x, env, waves)
        relative = w - velocity
    else:
        c, slope = _water(x, env)
    stiffness, force = 0.0, 0.0
    for code in models:
        drag_force = model.NETTING_DRAG[code][1]
        if moving:
            k = _MOVING_NETTING_DRAG[code](x, p.uv, p.l0, p.diameter, p.cd_normal, p.tangential_ratio * p.cd_normal,
                                           relative, gradient, time_step, rho)
            f = jnp.stack([drag_force(x, p, relative[i], rho)[i] for i in range(3)]) if shielded else 0.0
        else:
            # the shielding's product rule needs the drag itself: from the closed form's own intermediate values
            k = _NETTING_DRAG[code](x, p.uv, p.l0, p.diameter, p.cd_normal, p.tangential_ratio * p.cd_normal, c, rho,
                                    slope, env.up, with_force=shielded)
            k, f = k if shielded else (k, 0.0)
        if len(models) > 1:
            k, f = jnp.where(p.drag_model == code, k, 0.0), jnp.where(p.drag_model == code, f, 0.0)
        stiffness, force = stiffness + k, force + f
    if shielded:
        # the netting behind the catch front keeps the factor 1 - 3 w_i(h) of its drag (model._netting_drag),
        # w the clipped shape integrals of the heights h_j = x_j . axis - s: product rule, the front fixed
        h = catch_load.front_heights(x, state["front"], state["axis"])
        keep = 1.0 - 3.0 * catch_load.clipped_shape_integrals(h)
        dw = pressure.clipped_shape_integrals_jacobian(h)  # (i, j): dw_i/dh_j
        # d(1 - 3 w_i)/dx_j = -3 dw_i/dh_j axis: K_i,j = keep_i K_i,j + 3 f_i (dw_i/dh_j axis)^T
        correction = 3.0 * force[:, :, None, None] * (dw[:, None, :, None] * state["axis"][None, None, None, :])
        stiffness = keep.repeat(3)[:, None] * stiffness + correction.reshape(9, 9)
    return stiffness


def _bar_drag(x, p, env, state, moving=False, waves=False, velocity=None, time_step=None):
    cd_tangential = p.tangential_ratio * p.cd_normal
    if moving:
        w, gradient = _water_at_vertices(x, env, waves)
        return drag.moving_bar_drag_stiffness(x, p.rest_length, p.diameter, p.cd_normal, cd_tangential, w - velocity,
                                              gradient, time_step, env.water_density)
    c, slope = _water(x, env)
    return drag.bar_drag_stiffness(x, p.rest_length, p.diameter, p.cd_normal, cd_tangential, c, env.water_density,
                                   slope, env.up)


def _node_drag(x, p, env, state, moving=False, waves=False, velocity=None, time_step=None):
    if moving:
        w, gradient = _water_at_vertices(x, env, waves)
        return drag.moving_node_drag_stiffness(p.drag_area, w[0] - velocity[0], gradient[0], time_step,
                                               env.water_density)
    c, slope = _water(x, env)
    return drag.node_drag_stiffness(p.drag_area, c, env.water_density, slope, env.up)


#: term name (:data:`jaxnet.model.TERMS`) -> its closed-form stiffness
STIFFNESS = {
    "netting_tension": ClosedForm(_netting_tension),
    "bar_tension": ClosedForm(_bar_tension),
    "mesh_opening": ClosedForm(_opening),
    "knot_contact": ClosedForm(_knot_contact),
    "twine_bending": ClosedForm(_twine_bending),
    "netting_drag": ClosedForm(_netting_drag, covers=lambda options: set(options["models"]) <= set(_NETTING_DRAG)),
    "bar_drag": ClosedForm(_bar_drag),
    "node_drag": ClosedForm(_node_drag),
    "catch_pressure": ClosedForm(_catch_pressure),
}


def covered(active_term, with_velocities=False) -> bool:
    """True if this active term (:class:`jaxnet.model.ActiveTerm`) has a closed-form stiffness for its options.

    with_velocities: the caller hands the closed forms the vertices' velocities and the time step (the
    tangent of an implicit step, :func:`jaxnet.assemble.tangent` with a ``Motion``). A moving drag (a
    dynamic scene's) depends on them (c_i = w(x_i) - (x_i - x_i^n)/Δt, book 4.272-4.276): without them it
    keeps its autodiff stiffness.
    """
    entry = STIFFNESS.get(active_term.name)
    options = active_term.kwargs()
    if options.get("moving") and not with_velocities:
        return False
    return entry is not None and (entry.covers is None or entry.covers(options))


def paths(terms, stiffness="closed_form", with_velocities=False) -> dict:
    """Per active term with a stiffness (energies and forces), the path its stiffness takes:
    ``"closed_form"`` or ``"autodiff"``, for a solver run with ``stiffness`` (``with_velocities``: in a time
    step, see :func:`covered`)."""
    return {t.name: ("closed_form" if stiffness == "closed_form" and covered(t, with_velocities) else "autodiff")
            for t in terms if t.term.kind in ("energy", "force")}
