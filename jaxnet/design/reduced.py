"""Reduced design vectors: a few numbers z mapped to the design parameters θ of a net.

A net has hundreds of design parameters (every corner of every panel's cut, a diameter and an EA per
panel, ...), but a designer varies a few: every wall alike (a symmetry), a twine diameter tapering from the
mouth to the cod-end, the depth of a panel in meshes. :func:`jaxnet.design.optimize.optimize` takes such a map,
``design=lambda z: θ``, and optimises z; the map is jnp code, differentiated through, returning a partial θ
(the families and entries it sets; the rest stay at the reference, as :meth:`DesignSpace.complete
<jaxnet.design.space.DesignSpace.complete>` fills them).

The ready-made maps here are factories: each takes the names it acts on, checks them when it is made (a
ValueError naming the family or the entry), and returns a function of its own small vector:

  * :func:`one_value`: one value for several entries of a family (all walls cut alike, one diameter);
  * :func:`taper`: a linear taper of a family along a sequence of entries (z = its first and last values);
  * :func:`scale_cut`: a panel's reference cut scaled about its corner 0, in meshes across and along;
  * :func:`merge`: partial θs put together (each entry set once); :func:`combine`: named maps on the named
    parts of z (a dict), merged.

A map of one's own is a few jnp lines on top of these (and of :func:`jaxnet.design.cut.trapezoid`), e.g. every
wall a trapezoid of z = (meshes at the foot, meshes deep) with the bottom slices following the foot::

    walls_cut = reduced.one_value("cut", walls)
    bottoms_scaled = reduced.scale_cut(space, bottoms)
    def tapered(z):
        return reduced.merge(walls_cut(cut.trapezoid(top, z[0], z[1])), bottoms_scaled(z[0] / top))
"""

from __future__ import annotations

from typing import Callable

import jax
import jax.numpy as jnp
import numpy as np

from jaxnet.design import cut as cut_lib
from jaxnet.design.space import FAMILIES

__all__ = ["one_value", "taper", "scale_cut", "merge", "combine", "coordinate_names"]


def _family(family):
    if family not in FAMILIES:
        raise ValueError(f"unknown design family {family!r} (families: {sorted(FAMILIES)})")
    return family


def _entries(entries, what, at_least=1):
    """The entries as a tuple of distinct names, at least ``at_least`` of them."""
    if isinstance(entries, str):
        entries = (entries,)
    names = tuple(entries)
    if len(names) < at_least:
        raise ValueError(f"{what}: give at least {at_least} entr{'y' if at_least == 1 else 'ies'}, got {names!r}")
    repeated = sorted({n for n in names if names.count(n) > 1})
    if repeated:
        raise ValueError(f"{what}: entries named more than once: {repeated}")
    return names


def one_value(family: str, entries) -> Callable:
    """z -> {family: {entry: z for every entry}}: one value shared by several entries of a family.

    family: a design family (``"cut"``, ``"twine_diameter"``, ...); entries: their names (panels, sinkers...).
    z has the shape of one entry (a scalar; (C, 2) twine coordinates for a cut: all the panels then cut alike)
    and its units. The names are checked against the space when the map is used (:meth:`DesignSpace.check
    <jaxnet.design.space.DesignSpace.check>`: an unknown entry is named there).
    """
    family = _family(family)
    names = _entries(entries, f"one_value({family!r})")

    def design(z):
        return {family: {name: z for name in names}}

    return design


def taper(family: str, entries) -> Callable:
    """z -> {family: {entries[k]: (1 - t_k) z[0] + t_k z[1]}}, t_k = k / (n - 1): a family varying linearly along
    a sequence of n >= 2 entries, from z[0] at the first to z[1] at the last (a twine diameter from the mouth
    of a trawl to its cod-end, the mesh side along a sequence of panels).

    z: (2, ...) the first and last values, each of an entry's shape, in the family's units. Linear in z.
    """
    family = _family(family)
    names = _entries(entries, f"taper({family!r})", at_least=2)
    t = np.linspace(0.0, 1.0, len(names))

    def design(z):
        z = jnp.asarray(z)
        if z.shape[:1] != (2,):
            raise ValueError(f"taper({family!r}): z must hold the first and the last value (shape (2, ...)), got "
                             f"shape {z.shape}")
        return {family: {name: (1.0 - t[k]) * z[0] + t[k] * z[1] for k, name in enumerate(names)}}

    return design


def scale_cut(space, panels, reference=None) -> Callable:
    """s -> {"cut": {panel: corners scaled about corner 0}}: panels keep the shape of their reference cut and
    change their size in meshes.

    s: a scalar (the same factor across and along) or (2,) the factors in meshes across (u, the T-direction)
    and along (v, the N-direction), dimensionless: the corners' mesh coordinates from corner 0 are multiplied
    by them (corner 0 stays; only differences of twine coordinates matter). A bottom slice scaled by
    foot / top has ``foot`` meshes along the rim it shares with a wall of that foot.
    space: the :class:`~jaxnet.design.space.DesignSpace` (its reference cuts), or None with ``reference``;
    panels: names of its diamond-mesh panels; reference: {panel: (C, 2) corners} to scale instead of the
    space's reference cut.
    """
    names = _entries(panels, "scale_cut")
    cuts = space.initial()["cut"] if reference is None else reference
    unknown = [p for p in names if p not in cuts]
    if unknown:
        raise ValueError(f"scale_cut: no panel {unknown[0]!r} (panels: {sorted(cuts)})")
    corners = {p: np.asarray(cuts[p], dtype=float) for p in names}
    for p, c in corners.items():
        if c.ndim != 2 or c.shape[1] != 2 or not np.all(np.isfinite(c)):
            raise ValueError(f"scale_cut: the cut of panel {p!r} must be (C, 2) finite twine coordinates")
    # mesh coordinates (u, v) of each corner from corner 0: what the factors multiply
    meshes = {p: np.asarray(cut_lib.twine_to_mesh(c - c[0])) for p, c in corners.items()}

    def design(s):
        s = jnp.asarray(s)
        if s.shape not in ((), (2,)):
            raise ValueError(f"scale_cut: s must be one factor or two (across, along), got shape {s.shape}")
        return {"cut": {p: corners[p][0] + cut_lib.mesh_to_twine(meshes[p] * s) for p in names}}

    return design


def merge(*thetas) -> dict:
    """The union of partial designs {family: {entry: value}}; an entry set by two of them is a ValueError (two
    maps fighting over one parameter: the second would silently win)."""
    out = {}
    for theta in thetas:
        if not isinstance(theta, dict):
            raise ValueError(f"merge: expected partial designs (dicts of families), got {type(theta).__name__}")
        for family, entries in theta.items():
            if not isinstance(entries, dict):
                raise ValueError(f"merge: {family}: expected a dict {{name: value}}, got {type(entries).__name__}")
            target = out.setdefault(family, {})
            twice = sorted(set(target) & set(entries))
            if twice:
                raise ValueError(f"merge: {family}[{twice[0]!r}] is set by two maps")
            target.update(entries)
    return out


def combine(**maps) -> Callable:
    """z -> merge(map(z[name]) for each named map): one design from maps of the named parts of z, a dict
    {name: value}; ``combine(foot=..., diameter=reduced.one_value("twine_diameter", panels))``. The names are
    what :func:`jaxnet.design.optimize.optimize` reports z by."""
    if not maps:
        raise ValueError("combine: give at least one map, as name=map")
    bad = [name for name, m in maps.items() if not callable(m)]
    if bad:
        raise ValueError(f"combine: {bad[0]} is not a map (a function of its part of z)")

    def design(z):
        if not isinstance(z, dict) or set(z) != set(maps):
            raise ValueError(f"combine: z must be a dict with the parts {sorted(maps)}, got "
                             f"{sorted(z) if isinstance(z, dict) else type(z).__name__}")
        return merge(*(m(z[name]) for name, m in maps.items()))

    return design


def coordinate_names(z) -> list:
    """Names of the numbers of a design vector z (a pytree), in ``jax.tree.leaves`` order, one per number:
    ``z[0]`` for an array, ``foot`` and ``diameter[1]`` for a dict's entries; for reports and histories."""
    out = []
    for path, leaf in jax.tree_util.tree_flatten_with_path(z)[0]:
        base = ".".join(str(getattr(k, "key", getattr(k, "idx", k))) for k in path) or "z"
        if np.ndim(leaf) == 0:
            out.append(base)
        else:
            out += [f"{base}[{', '.join(map(str, i))}]" for i in np.ndindex(np.shape(leaf))]
    return out
