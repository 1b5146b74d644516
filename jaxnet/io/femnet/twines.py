"""FEMNET's numerical twines (``input netting2ropes``) read into jaxnet's :class:`~jaxnet.mesh.twines.NumericalTwines`.

FEMNET's line ``input netting2ropes PANEL PERIOD GAP_U GAP_V ACCURACY BARS`` (phobos ``chargement_don.c``; the
manual's "Numerical twines", e.g. ``input netting2ropes 4 10 0.0 0.5 3 2``) meshes diamond panel PANEL as
numerical twines (its meshing type becomes 4, ``maillage.c`` -> ``meshing_netting_2_ropes3.c``) instead of
triangles:

* PERIOD (integer): "the period of twines (numerical twines are 10 times larger than actual twines)": the
  numerical twines are PERIOD twines apart, each stands for PERIOD real twines;
* GAP_U, GAP_V: the positions of the numerical U and V twines relatively to the period (fractions of it);
* ACCURACY: "nodes closer than 3 meshes are merged" (in twines);
* BARS (integer): "the number of bar elements inside a full numerical twine".

FEMNET's solver (``lectureDo4.c``, bars of type -PANEL in the ``.mdg``) gives these bars the panel's material
scaled by PERIOD: traction and compression stiffness times PERIOD, hydrodynamic diameter, normal Cd and
tangential f times sqrt(PERIOD), rest length l0 PERIOD / BARS (:func:`~jaxnet.mesh.twines.numerical_twine_rope`;
with FEMNET's laws the tangential f too). Its mesher (``meshing_netting_2_ropes2.c``) requires a rope along every
side ("the panel must be surrounded by ropes") and puts the twines' border nodes on those ropes, with the ropes'
"type of internal nodes"; the nodes inside take the panel's. A rope meshed before the panel ("Meshing order")
keeps its nodes, and the border nodes are inserted among them (``bar_creation_per_element_around_panel``).

One difference is not reproduced: FEMNET's insertion into such a rope keeps the rope's original bars (those
whose end it moves are shortened) *and* adds a new bar between each pair of consecutive nodes (its search for
the bar to reuse forgets a match found before the last bar), so that rope is doubled in its ``.mdg`` (FEMNET's
``0simple/nr_*`` cases: the sinker rope, cable 5, has 57 + 60 bars), with twice its weight, drag and stiffness.
jaxnet's rope is single; ``tests/mesh/test_numerical_twines.py`` measures what the second copy adds to FEMNET's answer.
"""

from __future__ import annotations

from jaxnet.io.femnet.grammar import DonFile
from jaxnet.mesh.twines import NumericalTwines
from jaxnet.scene import SceneError

#: how :attr:`DonFile.inputs` keeps the line of panel k (1-based): "netting2ropes k"
INPUT = "netting2ropes"


def numerical_twines(case: DonFile, femnet_laws: bool = True) -> dict:
    """{0-based diamond panel index: :class:`NumericalTwines`} of the case's ``input netting2ropes`` lines, with
    FEMNET's tangential drag (``femnet_tangential``) when ``femnet_laws``. Raises a SceneError ``file:LINE:`` for
    a line naming no diamond panel, and for a panel of meshing type 4 (FEMNET's numerical twines) without one."""
    out = {}
    for key, v in case.inputs.items():
        if not key.startswith(INPUT + " "):
            continue
        panel, period, gap_u, gap_v, accuracy, bars = v.value
        k = int(panel) - 1
        if not 0 <= k < len(case.panels):
            raise SceneError(f"{case.path}:{v.line}: 'input {INPUT}': panel {int(panel)} does not exist (diamond "
                             f"panels: 1 to {len(case.panels)})")
        out[k] = NumericalTwines(period=float(period), bars=int(bars), offset_u=float(gap_u), offset_v=float(gap_v),
                                 accuracy=float(accuracy), femnet_tangential=bool(femnet_laws))
    for k, p in enumerate(case.panels):
        t = p.material["mesh_type"]
        if t.value == 4 and k not in out:
            raise SceneError(f"{case.path}:{t.line}: panel {k + 1}: meshing type 4 (numerical twines) needs its "
                             f"parameters: add 'input {INPUT} {k + 1} PERIOD GAP_U GAP_V ACCURACY BARS'")
    return out


def mdg_twine_bars(case: DonFile, twines: dict, rows, node_index, where, femnet_laws=True):
    """(:class:`~jaxnet.scene.Bars` or None, their cable names) of the numerical twines' bars of FEMNET's ``.mdg``:
    ``rows`` its bar lines of type -PANEL ([number, end 1, end 2, pro 1, pro 2, type, line]). Each takes the
    material of :func:`~jaxnet.mesh.twines.numerical_twine_rope` and, as FEMNET's solver gives it (``lectureDo4.c``),
    the rest length l0 PERIOD / BARS, whatever the mesher wrote; the bars of panel k are those of a cable
    "panel k twines", numbered after the case's cables in the order of the panels."""
    import numpy as np

    from jaxnet.io.femnet.materials import twine_of
    from jaxnet.materials import bar_columns
    from jaxnet.mesh.twines import numerical_twine_rope
    from jaxnet.scene import Bars

    if not rows:
        return None, ()
    panels = sorted({-int(r[5]) for r in rows})
    for r in rows:
        if -int(r[5]) - 1 not in twines:
            raise SceneError(f"{where}:{r[-1]}: bar {int(r[0])} of type {int(r[5])} is a numerical twine of panel "
                             f"{-int(r[5])}, which has no 'input {INPUT}' in {case.path}")
    columns = {}
    for p in panels:
        twine, layout = twine_of(case.panels[p - 1], case, femnet_laws), twines[p - 1]
        columns[p] = {**bar_columns(numerical_twine_rope(twine, layout)),
                      "rest_length": twine.l0 * layout.period / layout.bars,
                      "cable": len(case.cables) + panels.index(p)}
    fields = ("rest_length", "ea_traction", "ea_compression", "diameter", "density", "cable", "cd_normal",
              "tangential_ratio")
    out = {f: np.array([columns[-int(r[5])][f] for r in rows]) for f in fields}
    out["cable"] = out["cable"].astype(np.int64)
    ends = np.array([[node_index(v, r[-1]) for v in r[1:3]] for r in rows])
    return Bars(ends=ends, **out), tuple(f"panel {p} twines" for p in panels)
