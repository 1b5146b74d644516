"""VTK output (.vtu, via meshio) of a net: triangles and cable bars, with tensions as cell data.

ParaView opens the file directly. Quantities not defined for a cell type (a twine tension on a bar) are NaN.
"""

from __future__ import annotations

import meshio
import numpy as np

from jaxnet import figures


def write_vtu(path, scene, x):
    """Write the net at positions x (N, 3) to ``path`` (.vtu). Cell data in N, point data in N and 0/1."""
    x = np.asarray(x)
    cells, data = [], {"twine_tension_U_N": [], "twine_tension_V_N": [], "bar_tension_N": []}
    if scene.netting is not None:
        tw = figures.twine_tensions(scene, x)
        cells.append(("triangle", np.asarray(scene.netting.vertices)))
        data["twine_tension_U_N"].append(tw[:, 0])
        data["twine_tension_V_N"].append(tw[:, 1])
        data["bar_tension_N"].append(np.full(len(tw), np.nan))
    if scene.bars is not None:
        bt = figures.bar_tensions(scene, x)
        cells.append(("line", np.asarray(scene.bars.ends)))
        data["twine_tension_U_N"].append(np.full(len(bt), np.nan))
        data["twine_tension_V_N"].append(np.full(len(bt), np.nan))
        data["bar_tension_N"].append(bt)
    point_data = {"fixed": np.asarray(scene.nodes.fixed).any(axis=1).astype(np.int8), "mass_kg": np.asarray(scene.nodes.mass)}
    meshio.write(str(path), meshio.Mesh(x, cells, point_data=point_data, cell_data=data))
