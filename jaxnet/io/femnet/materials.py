"""FEMNET's materials in jaxnet's terms: a ``.don`` panel's twine (:func:`twine_of`: stiffness, diameter, drag law,
knots, a tarp's pressure coefficient), a hexagonal panel's twine, a cable's rope, and the lattices some panels are
meshed on. The conventions are the package's docstring's (:mod:`jaxnet.io.femnet`)."""

from __future__ import annotations

import dataclasses

import numpy as np

from jaxnet.io.femnet.grammar import DonCable, DonFile, DonPanel
from jaxnet.net import HexTwine, Rope, Twine
from jaxnet.scene import SceneError
from jaxnet.terms import knot


def twine_of(p: DonPanel, case: DonFile, femnet_laws: bool) -> Twine:
    """The panel's netting material; with ``femnet_laws``, with FEMNET's laws where they differ from the book
    (``docs/errata.md``, "Where FEMNET differs"): its knot contact (``fermeture2``), and, in a case with a
    catch, its netting drag (``trainee_fil``)."""
    m = {k: v.value for k, v in p.material.items()}
    twine = Twine(l0=m["l0"], ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"],
                  cd_normal=m["cd"], tangential_ratio=m["f"], opening_stiffness=m["opening"], knot_size=m["knot"])
    twine = dataclasses.replace(twine, tarp_cd=tarp_cd(case, p), drag_model=drag_law(case))
    if not femnet_laws:
        return twine
    return dataclasses.replace(
        twine, knot_form="femnet", knot_stiffness=float(knot.femnet_knot_stiffness(m["l0"], m["knot"], m["ea"])),
        drag_model="femnet-catch" if femnet_catch_drag(case) else twine.drag_model)


#: FEMNET's netting drag laws (``input drag_forces_type N``) -> jaxnet's drag models (jaxnet.terms.drag's
#: docstring): its 3 (drop pressure) and 4 (Aarnes) are calls commented out in its code, so no drag
FEMNET_DRAG_LAWS = {1: "twines", 2: "zhan", 3: "none", 4: "none"}


def drag_law(case: DonFile) -> str:
    """The drag model of the case's diamond netting, by its ``input drag_forces_type`` (1, Morison, without one).
    A law of the case, kept with the book's laws too; with FEMNET's, a case with a catch takes its catch drag
    instead, as FEMNET does whatever the law (:func:`twine_of`)."""
    law = case.inputs.get("drag_forces_type")
    return FEMNET_DRAG_LAWS[1 if law is None else int(law.value)]


def femnet_catch_drag(case: DonFile) -> bool:
    """Whether FEMNET loads this case's netting with its drag of cases with a catch (``unix.c``: a catch
    volume above its accuracy, in a current) rather than its twine drag (``filethydro4_sta``)."""
    return ((case.catch["catch_volume"].value > case.catch["catch_accuracy"].value or bool(tarp_panels(case)))
            and case.ocean["current_speed"].value > 0)


def tarp_panels(case: DonFile) -> dict:
    """{0-based diamond panel index: its ``input tarp PANEL`` line's Value} (a SceneError ``file:LINE:`` for a
    line naming no diamond panel)."""
    out = {}
    for key, v in case.inputs.items():
        if key.startswith("tarp "):
            k = int(v.value) - 1
            if not 0 <= k < len(case.panels):
                raise SceneError(f"{case.path}:{v.line}: 'input tarp {k + 1}': panel {k + 1} does not exist (diamond "
                                 f"panels: 1 to {len(case.panels)})")
            out[k] = v
    return out


def meshing_lattices(case: DonFile) -> dict:
    """{0-based diamond panel index: (NU, NV)} from the ``input Meshing_UV PANEL NU NV`` lines (meshes along the U
    and V diagonals between nodes: ``Net.panel(lattice=...)``; phobos ``chargement_don.c`` sets ``pas_U``, ``pas_V``
    and ``maillage.c`` then meshes the panel with ``maillage_interne4``), for the panels of meshing type 2, the only
    ones FEMNET meshes so (the parser warns of the others). A SceneError ``file:LINE:`` for a line naming no
    diamond panel."""
    out = {}
    for key, v in case.inputs.items():
        if key.startswith("meshing_uv "):
            k = int(v.value[0]) - 1
            if not 0 <= k < len(case.panels):
                raise SceneError(f"{case.path}:{v.line}: 'input Meshing_UV {k + 1}': panel {k + 1} does not exist "
                                 f"(diamond panels: 1 to {len(case.panels)})")
            if case.panels[k].material["mesh_type"].value == 2:
                out[k] = (float(v.value[1]), float(v.value[2]))
    return out


def tarp_cd(case: DonFile, p: DonPanel) -> float:
    """The tarp pressure coefficient of diamond panel ``p`` (:attr:`Twine.tarp_cd`): the catch's Cd ("Drag
    coefficient on this volume") for a panel named by ``input tarp``, as FEMNET's ``pression_prise3`` pushes its
    tarps with the catch's pressure (:mod:`jaxnet.terms.tarp`), else 0."""
    tarps = tarp_panels(case)
    k = next((k for k, q in enumerate(case.panels) if q is p), None)
    return float(case.catch["catch_cd"].value) if k in tarps else 0.0


def hextwine(p: DonPanel) -> HexTwine:
    """A hexagonal panel's netting material: FEMNET's three twine families l, m, n (one diameter, see
    :func:`hexagonal_diameter`)."""
    m = p.material
    l0 = np.array([v.value for v in m["l0"]])
    d = np.array([v.value for v in m["diameter"]])
    return HexTwine(l0=tuple(l0.tolist()), ea=tuple(v.value for v in m["ea"]), diameter=hexagonal_diameter(l0, d),
                    ea_compression=tuple(v.value for v in m["eac"]), density=m["density"].value)


def hexagonal_diameter(l0, d):
    """jaxnet's hexagonal netting has one twine diameter, used only for the twines' weight (it has no drag
    model): the one with the weight of FEMNET's three families, pi/4 sum d_i² l0_i = pi/4 D² sum l0_i (m)."""
    d, l0 = np.asarray(d, dtype=float), np.asarray(l0, dtype=float)
    scale = d.max()  # scaled, so that no square overflows for any finite diameters
    return float(scale * np.sqrt(np.sum((d / scale) ** 2 * l0) / np.sum(l0))) if scale > 0 else 0.0


def rope_of(c: DonCable) -> Rope:
    """A cable's rope material (its unstretched length l0 is the cable's rest length, given with the cable)."""
    m = {k: v.value for k, v in c.material.items()}
    return Rope(ea=m["ea"], diameter=m["diameter"], ea_compression=m["eac"], density=m["density"], cd_normal=m["cd"],
                tangential_ratio=m["f"], bending_stiffness=m.get("ei", 0.0))
