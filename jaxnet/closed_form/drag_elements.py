"""Element stiffnesses of the drag terms of :mod:`jaxnet.terms.drag`: what the terms declare as their closed forms.

Each function takes the arguments of its term's element function (:func:`jaxnet.terms.drag.netting_drag_on_element`
and the others) and returns the element matrix K = -∂F/∂x (N/m), vertex-major, from the closed forms of
:mod:`jaxnet.closed_form.drag`: the water's velocity where the term takes it (the current at the centroid in
statics, with its slope over depth; the relative velocity at each vertex in a time step, with the gradient of
the water's velocity there and the damping of the vertex's own), the netting's drag model per triangle, and
the shielding of the netting behind a catch front (the front held fixed, as :mod:`jaxnet.model.assemble` says), and
at a free surface the wetted share of each vertex's drag (:func:`wetted_stiffness`). No automatic
differentiation here either.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry
from jaxnet.closed_form.drag import (bar_drag_stiffness, current_slope, moving_bar_drag_stiffness,
                                     moving_netting_drag_femnet_catch_stiffness, moving_netting_drag_stiffness,
                                     moving_netting_drag_zhan_stiffness, moving_node_drag_stiffness,
                                     netting_drag_femnet_catch_stiffness, netting_drag_stiffness,
                                     netting_drag_zhan_stiffness, node_drag_stiffness)
from jaxnet.closed_form.pressure import clipped_shape_integrals_jacobian
from jaxnet.terms import drag as drag_term, pressure as pressure_term, surface as surface_term


def wetted_stiffness(stiffness, force, x, band, env):
    """The stiffness of the wetted drag w_i(h_i) F_i (:func:`jaxnet.terms.drag.wetted_shares`) from that of the
    drag F: ``stiffness`` (3k, 3k) = -∂F/∂x (N/m, with its damping in a time step: w does not depend on the
    velocities), ``force`` (k, 3) = F (N), x (k, 3) the vertices, ``band`` (m) their bodies' height. Product
    rule, w_i depending on vertex i's height h_i = x_i·up - s only:

        K^w_ij = w_i K_ij - δ_ij F_i (w_i' up)^T,      w_i' = dw_i/dh_i (1/m)."""
    k = x.shape[0]
    w, slope = drag_term.wetted_shares(x, band, env), drag_term.wetted_shares_slope(x, band, env)
    own = jnp.einsum("ij,ia,i,b->iajb", jnp.eye(k), force, slope, env.up).reshape(3 * k, 3 * k)
    return w.repeat(3)[:, None] * stiffness - own


def water_at_centroid(x, env):
    """The current at the centroid of the element's vertices x (k, 3), as the static drag sees it
    (:func:`jaxnet.terms.drag.water_velocity`), and its slope dc/dz there (m/s per m of height); the slope is
    None for a uniform current (a profile of fewer than 2 points: known from the shapes, when tracing)."""
    if env.profile_depth.shape[0] < 2:
        return drag_term.water_velocity(x, env), None
    z = jnp.dot(geometry.centroid(x), env.up)
    slope = current_slope(z, env.current_speed, env.current_direction, env.profile_depth, env.profile_factor,
                          env.surface_level)
    return drag_term.water_velocity(x, env), slope


def _water_at_vertices(x, env, waves):
    """In a time step, the water's velocity w (k, 3) at each vertex x (k, 3) as the moving drag sees it
    (:func:`jaxnet.terms.drag.water_velocity_at`: the current at the vertex's depth, plus the waves' orbital
    velocity when ``waves``) and its gradient ∂w/∂x (k, 3, 3) there (1/s): dc/dz up^T, plus the waves'."""
    w = drag_term.water_velocity_at(x, env, waves)
    slope = current_slope(x @ env.up, env.current_speed, env.current_direction, env.profile_depth,
                          env.profile_factor, env.surface_level)
    gradient = slope[:, :, None] * env.up[None, None, :]
    if waves:
        gradient = gradient + env.waves.velocity_gradient(x, env.time)
    return w, gradient


#: closed forms of the netting drag models made of twine drags (their codes in
#: :data:`jaxnet.terms.drag.NETTING_DRAG_MODELS`): at rest in a current, and moving (a time step)
_ZHAN = {"normal": drag_term.ZHAN_NORMAL, "tangential": drag_term.ZHAN_TANGENTIAL}
_NETTING = {0: netting_drag_stiffness, 3: netting_drag_femnet_catch_stiffness,
            4: lambda *args, **kwargs: netting_drag_zhan_stiffness(*args, **kwargs, **_ZHAN)}
_MOVING_NETTING = {0: moving_netting_drag_stiffness, 3: moving_netting_drag_femnet_catch_stiffness,
                   4: lambda *args: moving_netting_drag_zhan_stiffness(*args, **_ZHAN)}


def netting_drag_on_element_stiffness(x, state, uv, l0, diameter, cd_normal, cd_tangential, drag_model, env, models,
                                      shielded, moving=False, waves=False, velocity=None, time_step=None,
                                      selective=False, wetted=False):
    """(9, 9) stiffness (N/m) of :func:`jaxnet.terms.drag.netting_drag_on_element` (same arguments; in a time
    step also ``time_step`` Δt, s: the matrix then holds the damping -(1/Δt) ∂F/∂c), the catch front held
    fixed. Only the twine drag models (codes 0, 3 and 4, Zhan's) have one."""
    rho = env.water_density
    if moving:
        # vertex i takes its share of the drag at the water's velocity relative to it, c_i
        w, gradient = _water_at_vertices(x, env, waves)
        relative = w - velocity
    else:
        c, slope = water_at_centroid(x, env)
    # the product rules of the shielding and of the wetted share need the drag itself
    needs_force = shielded or wetted
    stiffness, force = 0.0, 0.0
    for code in models:
        drag_force = drag_term.NETTING_DRAG_MODELS[code].force
        if moving:
            k = _MOVING_NETTING[code](x, uv, l0, diameter, cd_normal, cd_tangential, relative, gradient, time_step, rho)
            f = (jnp.stack([drag_force(x, uv, l0, diameter, cd_normal, cd_tangential, relative[i], rho)[i]
                            for i in range(3)]) if needs_force else 0.0)
        else:
            # from the closed form's own intermediate values
            k = _NETTING[code](x, uv, l0, diameter, cd_normal, cd_tangential, c, rho, slope, env.up,
                               with_force=needs_force)
            k, f = k if needs_force else (k, 0.0)
        if len(models) > 1 or selective:
            k, f = jnp.where(drag_model == code, k, 0.0), jnp.where(drag_model == code, f, 0.0)
        stiffness, force = stiffness + k, force + f
    if shielded:
        # the netting behind the catch front keeps the factor 1 - 3 w_i(h) of its drag, w the clipped shape
        # integrals of the heights h_j = x_j . axis - s: product rule, the front fixed
        h = pressure_term.front_heights(x, state["front"], state["axis"])
        keep = 1.0 - 3.0 * pressure_term.clipped_shape_integrals(h)
        dw = clipped_shape_integrals_jacobian(h)  # (i, j): dw_i/dh_j
        # d(1 - 3 w_i)/dx_j = -3 dw_i/dh_j axis: K_i,j = keep_i K_i,j + 3 f_i (dw_i/dh_j axis)^T
        correction = 3.0 * force[:, :, None, None] * (dw[:, None, :, None] * state["axis"][None, None, None, :])
        stiffness = keep.repeat(3)[:, None] * stiffness + correction.reshape(9, 9)
        force = keep[:, None] * force
    if wetted:
        stiffness = wetted_stiffness(stiffness, force, x, surface_term.immersion_band(diameter), env)
    return stiffness


def bar_drag_on_element_stiffness(x, state, rest_length, diameter, cd_normal, cd_tangential, env, moving=False,
                                  waves=False, velocity=None, time_step=None, wetted=False):
    """(6, 6) stiffness (N/m) of :func:`jaxnet.terms.drag.bar_drag_on_element` (same arguments, and Δt)."""
    if moving:
        w, gradient = _water_at_vertices(x, env, waves)
        stiffness = moving_bar_drag_stiffness(x, rest_length, diameter, cd_normal, cd_tangential, w - velocity,
                                              gradient, time_step, env.water_density)
    else:
        c, slope = water_at_centroid(x, env)
        stiffness = bar_drag_stiffness(x, rest_length, diameter, cd_normal, cd_tangential, c, env.water_density, slope,
                                       env.up)
    if wetted:
        drag = drag_term.bar_drag_on_element(x, state, rest_length, diameter, cd_normal, cd_tangential, env, moving,
                                             waves, velocity)
        stiffness = wetted_stiffness(stiffness, drag, x, surface_term.immersion_band(diameter), env)
    return stiffness


def node_drag_on_element_stiffness(x, state, drag_area, env, moving=False, waves=False, velocity=None,
                                   time_step=None, wetted=False, band=None):
    """(3, 3) stiffness (N/m) of :func:`jaxnet.terms.drag.node_drag_on_element` (same arguments, and Δt)."""
    if moving:
        w, gradient = _water_at_vertices(x, env, waves)
        stiffness = moving_node_drag_stiffness(drag_area, w[0] - velocity[0], gradient[0], time_step,
                                               env.water_density)
    else:
        c, slope = water_at_centroid(x, env)
        stiffness = node_drag_stiffness(drag_area, c, env.water_density, slope, env.up)
    if wetted:
        drag = drag_term.node_drag_on_element(x, state, drag_area, env, moving, waves, velocity)
        stiffness = wetted_stiffness(stiffness, drag, x, band, env)
    return stiffness
