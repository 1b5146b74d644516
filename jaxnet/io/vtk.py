"""VTK output (.vtu) of a net for ParaView: its shape, what holds it, the forces on its nodes, its tensions.

:func:`write_vtu` writes the netting triangles and the cable bars at positions x with, as data on them:

point data (one row per node)
  ``displacement_m`` (N, 3) m: x minus the drawn start shape (``scene.nodes.position``).
  ``fixed_x``, ``fixed_y``, ``fixed_z`` (N,) int8: 1 where the node is held along that axis.
  ``node_type`` (N,) int32: :data:`NODE_TYPES` (0 free, 1 held along some axis, 2 held only across the
    symmetry planes it lies on: a node on a mirror plane of a quarter model, free in the whole net).
  ``mass_kg`` (N,) kg: the lumped mass attached (sinkers, floats).
  one (N, 3) array per result group (:func:`jaxnet.terms.term.groups`: ``drag_netting_N``, ``catch_N``,
    ``weight_and_buoyancy_N``, ``bottom_N``...), N: the force its terms exert on each node
    (:func:`jaxnet.figures.nodal_forces_by_group`), zero for a group none of whose terms is active.
  ``reaction_N`` (N, 3) N: the reactions at the held coordinates, zero on the free ones
    (:func:`jaxnet.figures.nodal_reactions`). At an equilibrium the groups and the reactions, summed over the
    nodes, balance: the internal terms (twines, bending), in no group, sum to zero over the net.
  ``residual_N`` (N, 3) N, when given: the out-of-balance force of a solve that failed, on the free coordinates
    (zero on the held ones, where the out-of-balance force is the reaction).

cell data (one row per triangle, then per bar; NaN, or -1 for an id, where a quantity does not apply)
  ``twine_tension_U_N``, ``twine_tension_V_N`` N: the tensions of the U and V twines of a diamond triangle.
  ``mesh_opening_angle_deg`` deg: the angle between its U and V twines (90 for square meshes).
  ``twine_tension_l_N``, ``twine_tension_m_N``, ``twine_tension_n_N`` N: the tensions of the three twine
    families of a hexagonal triangle (only for scenes with hexagonal netting).
  ``bar_tension_N`` N: the tension of a cable bar.
  ``panel_id`` int32: the panel of a triangle (-1 on bars); ``cable_id`` int32: the cable of a bar (-1 on
    triangles).

field data (the legend)
  ``panel K: NAME`` and ``cable K: NAME``, int32 (1,) holding K: the name of panel id and cable id K.
  ``node_type K: MEANING``, int32 (1,) holding K: the codes of ``node_type``.
  ``mirror_copies`` int32 (1,): how many copies of the modelled part make the whole net (1 for a whole net,
    4 for a quarter model).
  ``symmetry_planes`` float64 (P, 2), only for a model with mirror planes: one row per plane, its axis (0 x,
    1 y, 2 z) and its position (m) along that axis (components named so).

Why the names are the names of field arrays: VTK keeps strings in String arrays, but meshio (which reads these
files in the tests and in users' scripts) refuses a String array anywhere in a .vtu, and meshio writes no field
data at all, so this module writes the XML itself; an array named ``panel 3: belly`` holding 3 is shown by
ParaView's spreadsheet view (Attribute: Field Data) and is read by every VTK and meshio reader.

For a model with symmetry planes, :func:`write_vtu` also writes the whole net beside it (``NAME_whole.vtu``):
the copies of :func:`jaxnet.scene.mirrored`, one after the other, their vector point data (every (N, 3) array)
mirrored with :func:`jaxnet.scene.mirror_signs`, the rest repeated, and the point data ``mirror_copy`` (int32,
0 for the modelled part). A node on a plane is drawn once per copy (the copies are not merged, so every
array's sum over the file is the whole net's, each copy bringing its share), and the triangles of the copies
mirrored an odd number of times are written with two vertices swapped, so that their normals keep pointing to
the same side of the netting as the modelled part's.

Units are SI (m, N, kg) but for the angle, in degrees; a quantity's unit is in its name.
"""

from __future__ import annotations

import base64
import pathlib
import xml.sax.saxutils
import zlib

import numpy as np

from jaxnet import scene as scene_lib
from jaxnet.figures import net_figures, nodal_forces_by_group, nodal_reactions

#: ``node_type`` codes -> meaning (also in each file's field data)
NODE_TYPES = {0: "free", 1: "held along some axis", 2: "held only across the symmetry planes it lies on"}

#: VTK cell types
_TRIANGLE, _LINE = 5, 3

#: the bytes of one compressed block, and zlib's level: the fastest, as a run in time writes a file at every
#: record; the default level compresses these arrays only a little better (the ids, flags and zeros compress
#: well at any level, the float64 positions and forces barely at any)
_BLOCK, _LEVEL = 1 << 15, 1

#: numpy dtype -> VTK XML data type, the dtypes this module writes
_VTK_TYPES = {"f8": "Float64", "i1": "Int8", "i4": "Int32", "i8": "Int64", "u1": "UInt8"}


def write_vtu(path, scene, x, residual=None, *, forces=True, point_data=None, write_whole=True, figures=None,
              force=None):
    """Write the net at positions x (N, 3) m to ``path`` (.vtu), with the data of the module docstring; for a
    model with symmetry planes also the whole net to ``NAME_whole.vtu`` beside it (``write_whole``). Returns
    the list of the paths written.

    residual: (N, 3) the out-of-balance force (N) of a failed solve (its ``Equilibrium.force``), written as
      ``residual_N`` on the free coordinates; None for none.
    forces: write the nodal forces by group and the reactions (one compiled program of the scene's terms, the
      one :func:`jaxnet.figures.forces_by_term` runs); their static balance is that of an equilibrium, not of
      an instant of a dynamic run (where inertia joins it), so the time series leave them out.
    point_data: more point data, name -> (N,) or (N, 3) array (the time series' velocities); an (N, 3) float
      array is a vector (mirrored as one in the whole net).
    figures: the :class:`jaxnet.figures.NetFigures` at x when already computed (a run hands the same to every
      output), else computed here: the tensions, opening angles and nodal forces by group come from it.
    force: (N, 3) the out-of-balance force (N) of every node at x, a solve's own (``Equilibrium.force``), whose
      held coordinates give the reactions; None: the sum of every term's nodal forces at x
      (:func:`jaxnet.figures.nodal_reactions`).
    """
    path = pathlib.Path(path)
    x = np.asarray(x, dtype=float)
    figures = net_figures(scene, x, forces=forces) if figures is None else figures
    cells, cell_data = _cells(scene, figures)
    points = _point_data(scene, x, residual, forces, point_data, figures, force)
    field = _field_data(scene)
    _write(path, x, cells, points, cell_data, field)
    written = [path]
    if write_whole and scene.symmetry_planes:
        whole = path.with_name(f"{path.stem}_whole{path.suffix}")
        _write(whole, *_whole(scene, x, cells, points, cell_data), field)
        written.append(whole)
    return written


def node_types(scene) -> np.ndarray:
    """(N,) int32 :data:`NODE_TYPES` code of every node: 0 free, 1 held along some axis, 2 held only along the
    normals of symmetry planes it lies on (:func:`jaxnet.scene.on_symmetry_planes`, by which
    :meth:`jaxnet.net.Net.symmetry_plane` holds them) at its start position."""
    fixed = np.asarray(scene.nodes.fixed, dtype=bool)
    across = scene_lib.on_symmetry_planes(scene.nodes.position, scene.symmetry_planes)
    held = fixed.any(axis=1)
    only_across = held & ~(fixed & ~across).any(axis=1)
    return np.where(only_across, 2, np.where(held, 1, 0)).astype(np.int32)


# -- the data -----------------------------------------------------------------------------------------------


def _cells(scene, figures):
    """[(VTK cell type, (E, k) node indices)] of the diamond triangles, the hexagonal ones and the bars, in that
    order, and the cell data over all of them, name -> (cells,) array (``figures``: the net's
    :class:`~jaxnet.figures.NetFigures`)."""
    blocks, rows = [], []  # rows: per block, the arrays it has
    net, hexagonal, bars = scene.netting, scene.hexagonal, scene.bars
    if net is not None:
        tw = figures.twine_tension
        blocks.append((_TRIANGLE, np.asarray(net.vertices)))
        rows.append({"twine_tension_U_N": tw[:, 0], "twine_tension_V_N": tw[:, 1],
                     "mesh_opening_angle_deg": np.degrees(figures.opening_angle),
                     "panel_id": np.asarray(net.panel)})
    if hexagonal is not None:
        tw = figures.hexagonal_tension
        blocks.append((_TRIANGLE, np.asarray(hexagonal.vertices)))
        rows.append({"twine_tension_l_N": tw[:, 0], "twine_tension_m_N": tw[:, 1], "twine_tension_n_N": tw[:, 2],
                     "panel_id": np.asarray(hexagonal.panel)})
    if bars is not None:
        blocks.append((_LINE, np.asarray(bars.ends)))
        rows.append({"bar_tension_N": figures.bar_tension, "cable_id": np.asarray(bars.cable)})
    names = ["twine_tension_U_N", "twine_tension_V_N", "mesh_opening_angle_deg"]
    if hexagonal is not None:
        names += ["twine_tension_l_N", "twine_tension_m_N", "twine_tension_n_N"]
    names += ["bar_tension_N", "panel_id", "cable_id"]
    data = {}
    for name in names:
        ids = name.endswith("_id")
        parts = [np.asarray(row[name], dtype=np.int32 if ids else float) if name in row else
                 np.full(len(conn), -1 if ids else np.nan, dtype=np.int32 if ids else float)
                 for (_, conn), row in zip(blocks, rows)]
        data[name] = np.concatenate(parts) if parts else np.zeros(0, dtype=np.int32 if ids else float)
    return blocks, data


def _point_data(scene, x, residual, forces, extra, figures, force):
    nodes = scene.nodes
    fixed = np.asarray(nodes.fixed, dtype=bool)
    out = {"displacement_m": x - np.asarray(nodes.position, dtype=float)}
    for axis, name in enumerate("xyz"):
        out[f"fixed_{name}"] = fixed[:, axis].astype(np.int8)
    out["node_type"] = node_types(scene)
    out["mass_kg"] = np.asarray(nodes.mass, dtype=float)
    if forces:
        out.update(nodal_forces_by_group(scene, x, figures.nodal_forces))
        out["reaction_N"] = (nodal_reactions(scene, x) if force is None else
                             np.where(fixed, -np.asarray(force, dtype=float), 0.0))
    if residual is not None:
        out["residual_N"] = np.where(fixed, 0.0, np.asarray(residual, dtype=float))
    for name, values in (extra or {}).items():
        values = np.asarray(values)
        if values.shape[:1] != (scene.n_nodes,):
            raise ValueError(f"point data {name!r}: one row per node ({scene.n_nodes}) needed, "
                             f"got shape {values.shape}")
        out[name] = values
    return out


def _field_data(scene):
    """name -> (values, component names or None): the legend of the module docstring."""
    out = {}
    for kind, names in (("panel", scene.panel_names), ("cable", scene.cable_names)):
        for k, name in enumerate(names):
            out[f"{kind} {k}: {name}"] = (np.array([k], dtype=np.int32), None)
    for code, meaning in NODE_TYPES.items():
        out[f"node_type {code}: {meaning}"] = (np.array([code], dtype=np.int32), None)
    out["mirror_copies"] = (np.array([scene_lib.mirror_copies(scene)], dtype=np.int32), None)
    if scene.symmetry_planes:
        planes = np.array([(axis, at) for axis, at in scene.symmetry_planes], dtype=float)
        out["symmetry_planes"] = (planes, ("axis (0 x, 1 y, 2 z)", "position_m"))
    return out


def _whole(scene, x, cells, points, cell_data):
    """(points, cells, point data, cell data) of the whole net: the mirrored copies of the modelled part
    (module docstring)."""
    copies = scene_lib.mirrored(scene, x)
    signs = scene_lib.mirror_signs(scene)
    n, count = len(x), len(copies)
    whole_cells = []
    for kind, conn in cells:
        parts = []
        for c in range(count):
            flipped = conn[:, [0, 2, 1]] if kind == _TRIANGLE and np.prod(signs[c]) < 0 else conn
            parts.append(flipped + c * n)
        whole_cells.append((kind, np.concatenate(parts)))
    # the cells are grouped by kind, copy after copy within each: repeat each kind's rows of the cell data
    whole_cell_data = {}
    for name, values in cell_data.items():
        start, parts = 0, []
        for _, conn in cells:
            parts += [values[start:start + len(conn)]] * count
            start += len(conn)
        whole_cell_data[name] = np.concatenate(parts) if parts else values
    whole_points = {}
    for name, values in points.items():
        if values.ndim == 2 and values.shape[1] == 3 and values.dtype.kind == "f":
            whole_points[name] = np.concatenate([values * signs[c] for c in range(count)])
        else:
            whole_points[name] = np.concatenate([values] * count)
    whole_points["mirror_copy"] = np.repeat(np.arange(count, dtype=np.int32), n)
    return copies.reshape(-1, 3), whole_cells, whole_points, whole_cell_data


# -- the file -----------------------------------------------------------------------------------------------


def _data_array(name, values, components=None, tuples=False):
    """One <DataArray> in VTK's inline binary format, compressed: the values (little-endian) cut in blocks of
    :data:`_BLOCK` bytes, each compressed by zlib; base64 of the UInt64 header (block count, block size, size
    of the last block, compressed size of each) followed by base64 of the compressed blocks."""
    values = np.asarray(values)
    code = values.dtype.kind + str(values.dtype.itemsize)
    if code not in _VTK_TYPES:
        values = values.astype(float if values.dtype.kind == "f" else np.int64)
        code = values.dtype.kind + str(values.dtype.itemsize)
    values = np.ascontiguousarray(values, dtype=values.dtype.newbyteorder("<"))
    attributes = f'type="{_VTK_TYPES[code]}" Name={xml.sax.saxutils.quoteattr(name)}'
    if values.ndim == 2:
        attributes += f' NumberOfComponents="{values.shape[1]}"'
    for k, component in enumerate(components or ()):
        attributes += f" ComponentName{k}={xml.sax.saxutils.quoteattr(component)}"
    if tuples:
        attributes += f' NumberOfTuples="{len(values)}"'
    raw = values.tobytes()
    blocks = [zlib.compress(raw[k:k + _BLOCK], _LEVEL) for k in range(0, len(raw), _BLOCK)]
    last = len(raw) - _BLOCK * (len(blocks) - 1) if blocks else 0
    header = np.array([len(blocks), _BLOCK, last, *map(len, blocks)], dtype="<u8")
    payload = base64.b64encode(header.tobytes()).decode() + base64.b64encode(b"".join(blocks)).decode()
    return f'<DataArray {attributes} format="binary">{payload}</DataArray>\n'


def _write(path, points, cells, point_data, cell_data, field_data):
    """Write an UnstructuredGrid .vtu (VTK XML, version 1.0: 64-bit headers; zlib-compressed arrays)."""
    n_cells = sum(len(conn) for _, conn in cells)
    if cells:
        connectivity = np.concatenate([np.asarray(conn, dtype=np.int64).ravel() for _, conn in cells])
        offsets = np.cumsum(np.concatenate([np.full(len(conn), conn.shape[1], dtype=np.int64) for _, conn in cells]))
        types = np.concatenate([np.full(len(conn), kind, dtype=np.uint8) for kind, conn in cells])
    else:
        connectivity = offsets = np.zeros(0, dtype=np.int64)
        types = np.zeros(0, dtype=np.uint8)
    parts = ['<?xml version="1.0"?>\n',
             '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64" '
             'compressor="vtkZLibDataCompressor">\n',
             "<UnstructuredGrid>\n<FieldData>\n"]
    parts += [_data_array(name, values, components, tuples=True) for name, (values, components) in field_data.items()]
    parts += ["</FieldData>\n", f'<Piece NumberOfPoints="{len(points)}" NumberOfCells="{n_cells}">\n',
              "<Points>\n", _data_array("Points", np.asarray(points, dtype=float)), "</Points>\n",
              "<Cells>\n", _data_array("connectivity", connectivity), _data_array("offsets", offsets),
              _data_array("types", types), "</Cells>\n", "<PointData>\n"]
    parts += [_data_array(name, values) for name, values in point_data.items()]
    parts += ["</PointData>\n<CellData>\n"]
    parts += [_data_array(name, values) for name, values in cell_data.items()]
    parts += ["</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n"]
    with open(path, "w", encoding="utf-8") as f:
        f.writelines(parts)
