"""The sea current: velocity of the water as a function of position (an environment concept).

Used by the drag terms (:mod:`jaxnet.terms.drag`) in statics, and by dynamics for the relative velocity
(current minus node velocity). The book takes one uniform current vector c (4.124, "generally c_z is
null"); FEMNET also accepts a profile with depth (of speed and direction). Here only the speed varies
with depth, the direction is fixed:

    c(z) = speed * factor(depth) * direction / |direction|,        depth = surface_level - z,

with ``factor`` piecewise linear in depth through the points (profile_depth[i], profile_factor[i]) and
constant beyond the first and last points. No profile points (P = 0) means a uniform current
(factor 1); one point (P = 1) scales the uniform current by that factor.

Conventions: z is the height along the vertical ``up`` (m; the caller projects positions on ``up``), the
free surface is at z = ``surface_level``, so depth is positive below it. A NaN ``surface_level`` (a scene
without free surface, :class:`jaxnet.scene.Environment`'s default) measures depths from z = 0, so that a
profile still means something and nothing turns NaN. The profile depths must be strictly increasing
(m); speeds in m/s. Points above the surface get the factor of the first profile point (whether an
emerged part feels any drag is a matter for the free surface, not for the current).

Why piecewise linear, evaluated with a clamp and an explicit segment: the drag's tangent stiffness sees
dc/dz, so the factor must be differentiable in z with the slope of the segment at hand, zero beyond the
ends (where the factor is constant), and never NaN. At an interior profile point the derivative is that
of the deeper segment; at the first and last points, that of the adjoining segment.
"""

from __future__ import annotations

import jax.numpy as jnp

from jaxnet import geometry


def profile_factor_at(depth, profile_depth, profile_factor):
    """Dimensionless factor of the current at ``depth`` (m, positive downward), piecewise linear.

    Args:
      depth: scalar or array of depths (m).
      profile_depth: (P,) strictly increasing depths (m) of the profile points.
      profile_factor: (P,) factor at those depths (dimensionless).
    Returns:
      factor with the shape of ``depth``: 1 if P = 0, profile_factor[0] if P = 1, otherwise linear
      interpolation, constant beyond the first and last points.
    """
    depth = jnp.asarray(depth, dtype=float)
    profile_depth = jnp.asarray(profile_depth, dtype=float)
    profile_factor = jnp.asarray(profile_factor, dtype=float)
    points = profile_depth.shape[0]  # static: the branches below are on shapes, not on traced values
    if points == 0:
        return jnp.ones_like(depth)
    if points == 1:
        return jnp.broadcast_to(profile_factor[0], depth.shape)
    first, last = profile_depth[0], profile_depth[-1]
    # clamp with where (not clip): inside, the derivative is exactly 1, beyond the ends exactly 0
    clamped = jnp.where(depth < first, first, jnp.where(depth > last, last, depth))
    segment = jnp.clip(jnp.searchsorted(profile_depth, clamped, side="right") - 1, 0, points - 2)
    d0, d1 = profile_depth[segment], profile_depth[segment + 1]
    f0, f1 = profile_factor[segment], profile_factor[segment + 1]
    return f0 + (clamped - d0) * ((f1 - f0) / (d1 - d0))


def current_velocity(z, speed, direction, profile_depth, profile_factor, surface_level=0.0):
    """Velocity (3,) of the current in m/s at height ``z`` (m, z up).

    Args:
      z: height of the point (m); depth below the surface is ``surface_level - z``.
      speed: speed of the current where the factor is 1 (m/s).
      direction: (3,) direction of the current, any non-zero length (normalised here; a zero vector
        gives no current rather than NaN).
      profile_depth: (P,) strictly increasing depths (m) of the profile points, P >= 0.
      profile_factor: (P,) dimensionless factors at those depths.
      surface_level: height of the free surface (m); NaN (no free surface) is taken as 0.
    Returns:
      (3,) current velocity (m/s); (..., 3) if z is an array.
    """
    direction = jnp.asarray(direction, dtype=float)
    length = geometry.safe_norm(direction)
    unit = direction * jnp.where(length > 0.0, 1.0 / jnp.where(length > 0.0, length, 1.0), 0.0)
    surface_level = jnp.asarray(surface_level, dtype=float)
    surface_level = jnp.where(jnp.isnan(surface_level), 0.0, surface_level)
    factor = profile_factor_at(surface_level - jnp.asarray(z, dtype=float), profile_depth, profile_factor)
    return (speed * factor)[..., None] * unit
