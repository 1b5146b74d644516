"""A netting panel's polygon in twine coordinates, checked before meshing: finite corners, no two at one place,
an area (not all corners on a line), no crossing sides, a usable meshing step, and the number of segments of
each side (:func:`side_divisions`). :mod:`jaxnet.mesh.panel` meshes what passes; the design's cuts
(:mod:`jaxnet.design`) check their polygons with :func:`check_polygon`.
"""

from __future__ import annotations

import math

import numpy as np

#: relative tolerance of the geometric predicates (times the squared scale of the corners)
REL_EPS = 1e-12


class PanelError(ValueError):
    """Invalid panel description (or a panel that could not be meshed).

    The message names the panel and the culprit (corner, side or parameter).
    """


def panel_error(name, msg):
    """A :class:`PanelError` naming the panel."""
    return PanelError(f"panel {name!r}: {msg}")


def _positive_scalar(value, what, name):
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise panel_error(name, f"{what} must be a positive number, got {value!r}") from None
    if isinstance(value, (bool, np.bool_)) or not math.isfinite(v) or v <= 0.0:
        raise panel_error(name, f"{what} must be a positive finite number, got {what}={value!r}")
    return v


def _corner_array(corners, ncols, labels, what, name, ncorners=None):
    try:
        arr = np.asarray(corners, dtype=np.float64)
    except (TypeError, ValueError):
        raise panel_error(name, f"{what} must be a numeric array of shape (C, {ncols})") from None
    if arr.ndim != 2 or arr.shape[1] != ncols:
        raise panel_error(name, f"{what} must have shape (C, {ncols}), got shape {arr.shape}")
    if ncorners is None and arr.shape[0] < 3:
        raise panel_error(name, f"a panel needs at least 3 corners, got {arr.shape[0]}")
    if ncorners is not None and arr.shape[0] != ncorners:
        raise panel_error(name, f"{what} has {arr.shape[0]} corners but corners_uv has {ncorners}")
    bad = np.argwhere(~np.isfinite(arr))
    if bad.size:
        k, c = bad[0]
        raise panel_error(name, f"corner {k} has a non-finite {labels[c]} coordinate "
                         f"({what}[{k}, {c}] = {arr[k, c]})")
    return arr


def _orient_sign(a, b, c, eps):
    """Sign (-1, 0, 1) of the orientation of (a, b, c), arrays (..., 2)."""
    cr = (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])
    return np.where(np.abs(cr) <= eps, 0, np.sign(cr)).astype(np.int64)


def _on_segment(p, q, r):
    """For collinear p, q, r: is r within the bounding box of segment pq."""
    return ((np.minimum(p[..., 0], q[..., 0]) <= r[..., 0]) & (r[..., 0] <= np.maximum(p[..., 0], q[..., 0]))
            & (np.minimum(p[..., 1], q[..., 1]) <= r[..., 1]) & (r[..., 1] <= np.maximum(p[..., 1], q[..., 1])))


def _check_simple(uv, eps, name):
    """Raise if two sides of the closed polygon ``uv`` intersect illegally."""
    C = len(uv)
    a, b = uv, np.roll(uv, -1, axis=0)
    # adjacent sides k, k+1 share corner k+1; they may not fold back on each other
    e0 = b - a
    e1 = np.roll(e0, -1, axis=0)
    cr = e0[:, 0] * e1[:, 1] - e0[:, 1] * e1[:, 0]
    dt = (e0 * e1).sum(axis=1)
    fold = np.nonzero((np.abs(cr) <= eps) & (dt < 0))[0]
    if fold.size:
        k = int(fold[0])
        raise panel_error(name, f"sides {k} and {(k + 1) % C} overlap (the polygon folds back at "
                         f"corner {(k + 1) % C}; self-intersecting polygon)")
    if C < 4:
        return
    i, j = np.triu_indices(C, k=2)
    keep = ~((i == 0) & (j == C - 1))          # sides 0 and C-1 are adjacent
    i, j = i[keep], j[keep]
    p1, p2, q1, q2 = a[i], b[i], a[j], b[j]
    o1 = _orient_sign(p1, p2, q1, eps)
    o2 = _orient_sign(p1, p2, q2, eps)
    o3 = _orient_sign(q1, q2, p1, eps)
    o4 = _orient_sign(q1, q2, p2, eps)
    hit = (o1 * o2 < 0) & (o3 * o4 < 0)
    hit |= (o1 == 0) & _on_segment(p1, p2, q1)
    hit |= (o2 == 0) & _on_segment(p1, p2, q2)
    hit |= (o3 == 0) & _on_segment(q1, q2, p1)
    hit |= (o4 == 0) & _on_segment(q1, q2, p2)
    if hit.any():
        m = int(np.nonzero(hit)[0][0])
        raise panel_error(name, f"sides {i[m]} and {j[m]} cross (self-intersecting polygon; side k "
                         f"runs from corner k to corner k+1)")


def check_polygon(corners_uv, name):
    """The mesher's own checks of a panel's polygon in twine coordinates ``corners_uv`` (C, 2): finite corners,
    no two at one place, an area, no crossing sides. Raises :class:`PanelError` naming the panel ``name`` and the
    corner or side; returns nothing (the meshing step and l0 do not matter to these checks)."""
    validate_panel(corners_uv, None, 1.0, 1.0, None, name)


def validate_panel(corners_uv, corners_xyz, step, l0, divisions, name):
    """The checked panel: (corners_uv (C, 2), corners_xyz (C, 3) or None, h (twines), side lengths (C,) (twines),
    signed area (twines²), scale of the corners (twines), divisions (C,)), or a :class:`PanelError` naming the
    panel and the culprit."""
    uv = _corner_array(corners_uv, 2, ("U", "V"), "corners_uv", name)
    C = uv.shape[0]
    xyz = None
    if corners_xyz is not None:
        xyz = _corner_array(corners_xyz, 3, ("x", "y", "z"), "corners_xyz", name, ncorners=C)
    step = _positive_scalar(step, "step", name)
    l0 = _positive_scalar(l0, "l0", name)
    h = step / l0
    if not math.isfinite(h) or h <= 0.0:
        raise panel_error(name, f"step/l0 = {step}/{l0} is not a usable mesh size")

    nxt = np.roll(uv, -1, axis=0)
    seg = np.hypot(*(nxt - uv).T)
    scale = float(np.max(np.abs(uv - uv.mean(axis=0)))) or 1.0
    dup = np.nonzero(seg <= 1e-12 * scale)[0]
    if dup.size:
        k = int(dup[0])
        raise panel_error(name, f"corners {k} and {(k + 1) % C} have the same twine coordinates "
                         f"({uv[k, 0]:g}, {uv[k, 1]:g}) (side {k} has zero length)")
    eps = REL_EPS * scale * scale
    # all corners on one line -> zero area
    c0 = uv - uv[0]
    rel = c0 / scale
    if np.linalg.matrix_rank(rel, tol=1e-9) < 2:
        raise panel_error(name, "the polygon has zero area in twine space (all corners are collinear, d = 0)")
    _check_simple(uv, eps, name)
    area = 0.5 * float(np.sum(uv[:, 0] * nxt[:, 1] - nxt[:, 0] * uv[:, 1]))
    if abs(area) <= 1e-9 * scale * scale:
        raise panel_error(name, f"the polygon has zero area in twine space (signed area {area:g}, d = 0)")

    if divisions is None:
        div = _default_divisions(seg, h)
    else:
        div = _check_divisions(divisions, C, name)
    return uv, xyz, h, seg, area, scale, div


def _check_divisions(divisions, C, name):
    try:
        raw = np.asarray(divisions)
    except Exception:                      # pragma: no cover - exotic input
        raise panel_error(name, f"divisions must be a sequence of {C} positive integers") from None
    if raw.ndim != 1 or raw.shape[0] != C:
        raise panel_error(name, f"divisions must have one entry per side ({C}), got shape {raw.shape}")
    if raw.dtype == np.bool_ or not (np.issubdtype(raw.dtype, np.integer)
                                     or np.issubdtype(raw.dtype, np.floating)):
        raise panel_error(name, f"divisions must be positive integers, got dtype {raw.dtype}")
    for k, v in enumerate(raw.tolist()):
        if isinstance(v, float) and (not math.isfinite(v) or v != int(v)):
            raise panel_error(name, f"divisions[{k}] (side {k}) must be a positive integer, got {v!r}")
        if int(v) < 1:
            raise panel_error(name, f"divisions[{k}] (side {k}) must be a positive integer, got {v!r}")
    return np.asarray([int(v) for v in raw.tolist()], dtype=np.int64)


def _default_divisions(seg_len, h):
    # the small relative slack keeps e.g. a 10-twine side with h = 1 at 10 segments
    n = np.ceil(seg_len / h * (1.0 - 1e-12))
    return np.maximum(n, 1).astype(np.int64)


def side_divisions(corners_uv, step, l0) -> np.ndarray:
    """Default number of segments of each side of a panel.

    Parameters
    ----------
    corners_uv : array_like, shape (C, 2)
        Twine coordinates of the corners (twines).
    step : float
        Meshing step (m).
    l0 : float
        Unstretched twine length (m per twine).

    Returns
    -------
    np.ndarray, shape (C,), int64
        ``ceil(|side| / h)`` (at least 1) for each side ``k`` (from corner
        ``k`` to corner ``(k + 1) % C``), where ``|side|`` is the side length
        in twines and ``h = step / l0`` (twines).
    """
    uv = _corner_array(corners_uv, 2, ("U", "V"), "corners_uv", "side_divisions")
    step = _positive_scalar(step, "step", "side_divisions")
    l0 = _positive_scalar(l0, "l0", "side_divisions")
    seg = np.hypot(*(np.roll(uv, -1, axis=0) - uv).T)
    return _default_divisions(seg, step / l0)


# -- points against a polygon (vectorised, in chunks of CHUNK points) ---------------------------------------

#: points handled at once by the polygon kernels (bounds their (points, corners) temporaries)
CHUNK = 100_000


def inside(points, poly):
    """Crossing-number point-in-polygon test, points (m, 2) -> bool (m,)."""
    out = np.zeros(len(points), dtype=bool)
    x0, y0 = poly[:, 0], poly[:, 1]
    x1, y1 = np.roll(x0, -1), np.roll(y0, -1)
    dy = y1 - y0
    safe_dy = np.where(dy == 0.0, 1.0, dy)
    for s in range(0, len(points), CHUNK):
        x = points[s:s + CHUNK, 0:1]
        y = points[s:s + CHUNK, 1:2]
        straddle = (y0 > y) != (y1 > y)
        xint = x0 + (y - y0) * (x1 - x0) / safe_dy
        out[s:s + CHUNK] = (np.count_nonzero(straddle & (x < xint), axis=1) % 2) == 1
    return out


def distance_to_boundary(points, poly):
    """Distance of points (m, 2) to the closed polygon boundary (m,)."""
    a = poly
    e = np.roll(poly, -1, axis=0) - poly
    ee = (e * e).sum(axis=1)
    out = np.empty(len(points))
    for s in range(0, len(points), CHUNK):
        p = points[s:s + CHUNK]
        ap = p[:, None, :] - a[None, :, :]
        t = np.clip((ap * e[None]).sum(axis=2) / ee[None], 0.0, 1.0)
        q = ap - t[:, :, None] * e[None]
        out[s:s + CHUNK] = np.sqrt(np.min((q * q).sum(axis=2), axis=1))
    return out


def mean_value_coordinates(points, poly):
    """Mean value coordinates (Floater) of points (m, 2) w.r.t. polygon (C, 2).

    Valid for points strictly inside a simple polygon (convex or not, either
    orientation); points must not lie on the boundary.  Returns (m, C), rows
    summing to 1, with ``w @ poly == points`` up to rounding.
    """
    C = len(poly)
    out = np.empty((len(points), C))
    for s in range(0, len(points), CHUNK):
        p = points[s:s + CHUNK]
        d = poly[None, :, :] - p[:, None, :]            # (m, C, 2)
        r = np.hypot(d[..., 0], d[..., 1])
        d1 = np.roll(d, -1, axis=1)
        r1 = np.roll(r, -1, axis=1)
        cross = d[..., 0] * d1[..., 1] - d[..., 1] * d1[..., 0]
        dot = (d * d1).sum(axis=2)
        # tan(alpha_k / 2), signed, alpha_k the angle from d_k to d_{k+1}; the
        # two equivalent forms avoid cancellation near alpha = 0 and alpha = pi
        rr = r * r1
        with np.errstate(divide="ignore", invalid="ignore"):
            tan_half = np.where(dot >= 0.0, cross / (rr + dot), (rr - dot) / cross)
        w = (np.roll(tan_half, 1, axis=1) + tan_half) / r
        out[s:s + CHUNK] = w / w.sum(axis=1, keepdims=True)
    return out
