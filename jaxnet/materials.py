"""Materials of a net as a designer gives them, and the one map from a material to its family's rows.

:class:`Twine` (diamond-mesh netting), :class:`HexTwine` (hexagonal-mesh netting) and :class:`Rope` (cables)
are what :class:`~jaxnet.net.Net` takes per panel and per cable. :func:`netting_columns` and
:func:`bar_columns` say which value each per-element parameter of the scene (:class:`~jaxnet.scene.Netting`,
:class:`~jaxnet.scene.Bars`) takes for a material: the builder (:meth:`jaxnet.net.Net.build`) and the readers
that fill a family themselves (FEMNET's ``.mdg`` mesh) both use them, so the map is written once.

Units: m, N, kg/m³; drag coefficients dimensionless; stiffnesses of the mesh opening and knots in N·m/rad,
of bending in N·m².

A material checks its stiffnesses when it is made (:class:`MaterialError`, a :class:`~jaxnet.scene.SceneError`
naming the material, the parameter and its value): a traction stiffness EA must be > 0 (twines or a rope without
it hold nothing: the net is a mechanism, which a solve would only report as a step that lowers no energy); a
compression, opening, knot or bending stiffness must be >= 0 (0: none, a twine that goes slack in compression,
meshes that open freely, ...). :func:`check` checks all its parameters (lengths, diameters, coefficients, the
names of its laws): what :meth:`~jaxnet.net.Net.panel` and :meth:`~jaxnet.net.Net.cable` ask of the material
they are given, and a scene file of each material table it reads.
"""

from __future__ import annotations

import dataclasses
import difflib

import jax
import numpy as np

from jaxnet.scene import SceneError
from jaxnet.terms import knot
from jaxnet.terms.drag import NETTING_DRAG_MODELS

#: how the current loads netting (``Twine.drag_model``) -> code in ``Netting.drag_model``
DRAG_MODELS = {model.name: code for code, model in enumerate(NETTING_DRAG_MODELS)}
#: knot contact law (``Twine.knot_form``) -> code in ``Netting.knot_form``
KNOT_FORMS = {form: code for code, form in enumerate(knot.FORMS)}
#: Young's modulus of lead (Pa): handbooks give 14-17 GPa for cast lead; the value of sinker bars here
LEAD_YOUNG_MODULUS = 16e9


def rod_bending_stiffness(diameter, young_modulus=LEAD_YOUNG_MODULUS):
    """Flexural stiffness EI (N·m²) of a solid round rod of ``diameter`` (m): E pi d⁴ / 64, E in Pa (lead's by
    default): the ``bending_stiffness`` of a :class:`Rope` that is a bar (a 10 mm lead rod: 7.85 N·m²)."""
    return float(young_modulus) * np.pi * float(diameter) ** 4 / 64.0


@dataclasses.dataclass(frozen=True)
class Twine:
    """Netting material.

    l0: unstretched twine length = mesh side (m); ea: traction stiffness (N); ea_compression: compression
    stiffness (N, 0 = twines go slack); diameter: twine (hydrodynamic) diameter (m); density: volumic mass
    (kg/m³, 1140 = polyamide).
    cd_normal, tangential_ratio: twine drag: normal coefficient Cd and f, the tangential drag as a fraction
      of Cd (eqs 4.114-4.115; FEMNET's usual 1.2 and 0.08); drag_model: "twines" (drag on every twine, the book), "loland" or
      "kristiansen-faltinsen" (screen models of aquaculture engineering), "femnet-catch" (FEMNET's twine
      drag of cases with a catch, which misdirects the U twines' cross-flow drag: to reproduce FEMNET only),
      "zhan" (Zhan et al.'s twine drag with the netting's solidity, its own coefficients: Cd and f unused;
      FEMNET's drag_forces_type 2) or "none" (the current does not load the netting: what FEMNET's
      drag_forces_type 3 and 4 do; :mod:`jaxnet.terms.drag`).
    opening_stiffness: mesh opening stiffness H (N·m/rad, eqs 4.211-4.219); rest_angle: the half opening
      angle α0 (rad) at which the mesh is unstressed in flexion (π/4: square meshes).
    knot_size: knot size (m, eq. 4.278: meshes cannot close below the angle it sets; 0 for none);
      knot_stiffness: contact stiffness (N·m/rad), None for the default of eq. 4.280; knot_form: "book"
      (4.278-4.280) or "femnet" (FEMNET's law, :mod:`jaxnet.terms.knot`; give it FEMNET's stiffness).
    bending_stiffness: flexural stiffness EI of one twine (N·m², eqs 4.220-4.245; 0 for none).
    tarp_cd: pressure coefficient C of a tarp (dimensionless): 0 (the default) for netting the water flows
      through; > 0 makes the panel impermeable (FEMNET's ``input tarp``): the current pushes it with the
      pressure C ½ρ|c|² on its whole surface, towards -(U ^ V), instead of the drag of its twines
      (:mod:`jaxnet.terms.tarp`). Only with the twine drag models ("twines", "femnet-catch").
    """

    l0: float
    ea: float
    diameter: float
    ea_compression: float = 0.0
    density: float = 1140.0
    cd_normal: float = 1.2
    tangential_ratio: float = 0.08
    drag_model: str = "twines"
    opening_stiffness: float = 0.0
    rest_angle: float = float(np.pi / 4)
    knot_size: float = 0.0
    knot_stiffness: float | None = None
    knot_form: str = "book"
    bending_stiffness: float = 0.0
    tarp_cd: float = 0.0

    def __post_init__(self):
        _check_stiffnesses(self)


@dataclasses.dataclass(frozen=True)
class Rope:
    """Cable material: ea, ea_compression (N), diameter (m), density (kg/m³); Morison drag coefficients
    cd_normal and tangential_ratio f (tangential drag f x Cd; FEMNET's usual 1.2 and 0.08).

    bending_stiffness: flexural stiffness EI (N·m²) of the cable: a cable with EI > 0 resists the turn of its
      direction at every joint between two of its bars, straight at rest (FEMNET's ``EI_flexion_cable``;
      :mod:`jaxnet.terms.cable_bending`); 0 (the default) for a rope whose joints are free hinges. A polyamide
      rod 0.2 m in diameter has about 3e5 N·m², an 18 mm steel bar about 1e3 N·m².
    """

    ea: float
    diameter: float
    ea_compression: float = 0.0
    density: float = 1140.0
    cd_normal: float = 1.2
    tangential_ratio: float = 0.08
    bending_stiffness: float = 0.0

    def __post_init__(self):
        _check_stiffnesses(self)


@dataclasses.dataclass(frozen=True)
class HexTwine:
    """Hexagonal-mesh netting material (book eqs 4.76-4.113): three twine families l, m, n.

    l0, ea, ea_compression: per family (l, m, n), or one value for all three: unstretched twine length (m),
    traction and compression stiffness (N). diameter (m) and density (kg/m³) of the twines. Twine
    coordinates of a hexagonal panel count *base meshes* (see :mod:`jaxnet.terms.hexagonal`).
    """

    l0: float | tuple
    ea: float | tuple
    diameter: float
    ea_compression: float | tuple = 0.0
    density: float = 1140.0

    def __post_init__(self):
        _check_stiffnesses(self)

    def per_family(self, name):
        value = np.broadcast_to(np.asarray(getattr(self, name), dtype=float), (3,))
        return value

    @property
    def base_mesh_side(self):
        """|U| of the regular base mesh (m): 3 twine lengths; sets how finely a panel is meshed."""
        return 3.0 * float(np.mean(self.per_family("l0")))


def knot_stiffness(twine: Twine) -> float:
    """Knot contact stiffness (N·m/rad) of the triangles of a diamond-mesh panel of material ``twine``:
    ``twine.knot_stiffness`` when given, else the default of eq. 4.280
    (:func:`jaxnet.terms.knot.default_knot_stiffness`), 0 without knots (knot_size 0)."""
    if twine.knot_stiffness is not None:
        return float(twine.knot_stiffness)
    return float(knot.default_knot_stiffness(float(twine.l0), float(twine.knot_size), float(twine.ea)))


def netting_columns(twine: Twine) -> dict:
    """The :class:`~jaxnet.scene.Netting` parameters of every triangle of a panel of material ``twine``
    ({field: value}): the one map from a builder's material to the scene's per-triangle rows, used by
    :meth:`Net.build` and by readers that fill a ``Netting`` themselves (FEMNET's ``.mdg`` mesh)."""
    return {"l0": float(twine.l0), "ea_traction": float(twine.ea), "ea_compression": float(twine.ea_compression),
            "diameter": float(twine.diameter), "density": float(twine.density), "cd_normal": float(twine.cd_normal),
            "tangential_ratio": float(twine.tangential_ratio), "opening_stiffness": float(twine.opening_stiffness),
            "rest_angle": float(twine.rest_angle), "knot_size": float(twine.knot_size),
            "bending_stiffness": float(twine.bending_stiffness), "knot_stiffness": knot_stiffness(twine),
            "knot_form": KNOT_FORMS[twine.knot_form], "drag_model": DRAG_MODELS[twine.drag_model],
            "tarp_cd": float(twine.tarp_cd)}


def netting_rows(twines, material) -> dict:
    """{Netting field: (E,) array} of triangles whose material is ``twines[material[e]]`` (``material``: (E,)
    indices into the sequence ``twines``): :func:`netting_columns` row by row."""
    columns = [netting_columns(t) for t in twines]
    material = np.asarray(material, dtype=np.int64)
    return {k: np.array([c[k] for c in columns])[material] for k in columns[0]}


def bar_columns(rope: Rope) -> dict:
    """The :class:`~jaxnet.scene.Bars` parameters of every bar of a cable of material ``rope`` ({field: value})."""
    return {"ea_traction": float(rope.ea), "ea_compression": float(rope.ea_compression),
            "diameter": float(rope.diameter), "density": float(rope.density), "cd_normal": float(rope.cd_normal),
            "tangential_ratio": float(rope.tangential_ratio)}


def bar_rows(ropes, material) -> dict:
    """{Bars field: (B,) array} of bars whose material is ``ropes[material[b]]``: :func:`bar_columns` row by row."""
    columns = [bar_columns(r) for r in ropes]
    material = np.asarray(material, dtype=np.int64)
    return {k: np.array([c[k] for c in columns])[material] for k in columns[0]}


class MaterialError(SceneError):
    """A parameter of a material out of its range. ``parameter``: the field's name ("ea"); ``problem``: what is
    wrong, in words that start with the parameter ("ea must be > 0, got 0.0 (traction stiffness EA, N)"), for a
    caller to say whose material it is (a panel, a scene file's table); the message names the material's class."""

    def __init__(self, material, parameter, problem):
        super().__init__(f"{type(material).__name__}: {problem}")
        self.parameter, self.problem = parameter, problem


#: a material's stiffnesses: (field, > 0 required, what it is). A traction stiffness of 0 leaves the twines or the
#: rope holding nothing; the others may be 0 (none)
STIFFNESSES = (("ea", True, "traction stiffness EA, N"),
               ("ea_compression", False, "compression stiffness, N; 0: slack in compression"),
               ("opening_stiffness", False, "mesh opening stiffness, N·m/rad"),
               ("knot_stiffness", False, "knot contact stiffness, N·m/rad"),
               ("bending_stiffness", False, "flexural stiffness EI, N·m²"))
#: the other numbers of a material, finite and >= 0 (l0 > 0)
_AMOUNTS = ("l0", "diameter", "density", "cd_normal", "tangential_ratio", "knot_size", "tarp_cd")


def _values(value):
    """A material's number, or its numbers per twine family, as a 1-D float array; None for a traced value (a
    material made inside a JAX transformation is checked by the scene's own checks instead)."""
    if any(isinstance(v, jax.core.Tracer) for v in jax.tree_util.tree_leaves(value)):
        return None
    try:
        return np.atleast_1d(np.asarray(value, dtype=float)).ravel()
    except (TypeError, ValueError):
        return np.array([np.nan])


def _check_range(material, name, positive, what=""):
    """MaterialError unless the field ``name`` of ``material`` is finite and >= 0 (> 0 if ``positive``), per twine
    family where it has one value per family."""
    value = getattr(material, name)
    values = _values(value)
    if values is None or (np.all(np.isfinite(values)) and np.all(values > 0 if positive else values >= 0)):
        return
    several = isinstance(value, (tuple, list, np.ndarray)) and np.size(value) > 1
    family = " per twine family (l, m, n)" if several else ""
    shown = values.tolist() if family else (value.item() if isinstance(value, np.generic) else value)
    raise MaterialError(material, name, f"{name} must be {'> 0' if positive else '>= 0'}{family}, got {shown!r}"
                                        + (f" ({what})" if what else ""))


def _check_stiffnesses(material):
    """What a material checks when it is made: its stiffnesses (:data:`STIFFNESSES`), those it has."""
    names = {f.name for f in dataclasses.fields(material)}
    for name, positive, what in STIFFNESSES:
        if name in names and not (name == "knot_stiffness" and material.knot_stiffness is None):
            _check_range(material, name, positive, what)


def check(material):
    """:class:`MaterialError` naming the first parameter of ``material`` (a :class:`Twine`, :class:`HexTwine` or
    :class:`Rope`) out of its range: its stiffnesses (:data:`STIFFNESSES`), its unstretched length (> 0), its
    diameter, density and drag coefficients, knot size and tarp coefficient (finite, >= 0); a twine's drag model
    and knot law among those there are, its rest angle in (0, pi/2] rad, and a tarp only with a drag model of
    twines (a screen model has no twines whose drag the tarp's pressure replaces)."""
    if not isinstance(material, (Twine, HexTwine, Rope)):
        raise SceneError(f"expected a jaxnet material (Twine, HexTwine or Rope), got {material!r}")
    _check_stiffnesses(material)
    names = {f.name for f in dataclasses.fields(material)}
    for name in _AMOUNTS:
        if name in names:
            _check_range(material, name, name == "l0")
    if not isinstance(material, Twine):
        return
    for name, names in (("drag_model", DRAG_MODELS), ("knot_form", KNOT_FORMS)):
        value = getattr(material, name)
        if value not in names:
            raise MaterialError(material, name, f"{name} must be one of {sorted(names)}, got {value!r}"
                                                f"{_nearest(value, names)}")
    angle = _values(material.rest_angle)
    if angle is not None and not (0.0 < angle[0] <= np.pi / 2):
        raise MaterialError(material, "rest_angle", "rest_angle (half opening angle, rad) must be in (0, pi/2], got "
                                                    f"{material.rest_angle!r}")
    if material.tarp_cd > 0 and not NETTING_DRAG_MODELS[DRAG_MODELS[material.drag_model]].twines:
        raise MaterialError(material, "drag_model", f"a tarp (tarp_cd {material.tarp_cd!r}) replaces the drag of its "
                                                    f"twines; drag_model {material.drag_model!r} is a screen model "
                                                    "(use 'twines' or 'femnet-catch')")


def _nearest(word, names):
    """The hint ``" (did you mean 'NAME'?)"`` for the name of ``names`` nearest a misspelt ``word``, or ""."""
    close = difflib.get_close_matches(str(word), list(names), n=1) if isinstance(word, str) else []
    return f" (did you mean {close[0]!r}?)" if close else ""
