"""FEMNET's own mesh (``.mdg``, written by its mesher) read into a :class:`~jaxnet.scene.Scene`, with the
materials and node types of its ``.don`` case, so that the physics of FEMNET and jaxnet can be compared
without mesh differences (see the package's docstring).
"""

from __future__ import annotations

import dataclasses
import math
import pathlib

import numpy as np

from jaxnet.io.femnet.grammar import twine_coordinates
from jaxnet.io.femnet.mapping import gauge_of, result
from jaxnet.io.femnet.materials import rope_of, twine_of
from jaxnet.io.femnet.surroundings import (catch_of, check_types, environment_of, femnet_panel_catch_sides,
                                           gravity_catch_density, node_type_fields, panel_catches_of, spheres_folded,
                                           symmetry_planes, symmetry_share, with_added_masses)
from jaxnet.io.femnet.parse import parse_don
from jaxnet.io.femnet.twines import mdg_twine_bars, numerical_twines
from jaxnet.materials import bar_rows, netting_rows
from jaxnet.build import outward
from jaxnet.scene.checks import validate
from jaxnet.scene import Bars, Catch, Netting, Nodes, Scene, SceneError


def read_mdg(path, don=None, femnet_laws=True):
    """FEMNET's mesh ``path`` (.mdg) as a :class:`~jaxnet.case.Case` (its scene read whole: no ``net``), with
    the materials, node types and numerics of the ``.don`` case ``don`` (default: the same name with ``.don``).

    The scene's nodes are the ``.mdg``'s, in its order (so the ``.sta``'s positions compare node by node);
    its triangles carry the ``.mdg``'s corner (U, V) turned into twine coordinates (U + V, V - U), and the
    material of the panel named in the triangle's line; its bars the rest length (pro2 - pro1) × L of
    their cable. Solver options, time settings and ``info`` as :func:`~.mapping.read_don`'s.
    """
    path = pathlib.Path(path)
    don = pathlib.Path(don) if don is not None else path.with_suffix(".don")
    case = parse_don(don)
    if femnet_laws:
        case = spheres_folded(case)   # FEMNET's spheres are folded into their cables' materials
    check_types(case)
    if not path.exists():
        raise SceneError(f"FEMNET mesh {path} does not exist")
    mdg = MdgText(path)
    where = mdg.where
    n_nodes, at = mdg.count_after("nombre de noeuds")
    node_rows = mdg.rows("description des noeuds", n_nodes, 7, at)
    n_bars, at = mdg.count_after("nombre d'elements")
    bar_lines = mdg.rows("description des elements", n_bars, 6, at)
    n_tri, at = mdg.count_after("nombre de surfaces")
    tri_rows = mdg.rows("description des surfaces", n_tri, 11, at)
    for header in ("nombre de coulisses", "nombre de surfaces hexagonales"):
        n, at = mdg.count_after(header)
        if n:
            raise SceneError(f"{where}:{at + 1}: '{header}' {n}: not supported")
    position = np.array([r[1:4] for r in node_rows])
    node_type = [int(r[5]) for r in node_rows]
    for r in node_rows:
        if int(r[5]) not in case.types:
            raise SceneError(f"{where}:{r[-1]}: node {int(r[0])} has type {int(r[5])}, not described in {don}")
    env = environment_of(case)
    planes = symmetry_planes(case, position, node_type)
    fixed = np.array([[case.types[t].fixed[a].value or case.types[t].symmetry[a].value for a in range(3)]
                      for t in node_type], dtype=bool)
    # a net its node types leave free along an axis: held there at its gauge node, as on jaxnet's own mesh
    warnings = []
    gauge = gauge_of(case, position, fixed.any(axis=0), warnings)
    if gauge is not None:
        fixed[gauge[0], ["xyz".index(a) for a in gauge[1]]] = True
    share = symmetry_share(case, node_type)
    mass = share * np.array([case.types[t].mass[0] for t in node_type])
    force = share[:, None] * np.array([case.types[t].force for t in node_type], dtype=float)
    fields = node_type_fields(case, position, node_type)
    nodes = Nodes(position=position, fixed=fixed, mass=mass, volume=fields.pop("volume", np.zeros(n_nodes)), force=force,
                  drag_area=np.zeros(n_nodes), size=np.zeros(n_nodes), **fields)

    def node_index(value, line):
        i = int(value) - 1
        if value != int(value) or not 0 <= i < n_nodes:
            raise SceneError(f"{where}:{line}: node number {value!r} outside 1..{n_nodes}")
        return i

    netting = _netting(case, tri_rows, node_index, where, don, femnet_laws) if n_tri else None
    bars, twine_names = _bars(case, bar_lines, node_index, where, don, femnet_laws)
    netting_nodes = np.unique(netting.vertices) if netting is not None else np.arange(n_nodes)
    density = gravity_catch_density(case, env)
    catch_spec = catch_of(case, position, netting_nodes, planes, env, density)
    catch = None
    if catch_spec is not None:
        volume, cd, copies, center, axis = catch_spec
        catch = Catch(volume=volume, drag_coefficient=cd, axis=axis, center=center, symmetry=copies, density=density)
        netting = dataclasses.replace(netting, outward=outward(position, np.asarray(netting.vertices), center,
                                                               np.asarray(netting.uv), np.asarray(netting.panel)))
    scene = Scene(nodes=nodes, netting=netting, bars=bars, environment=env, catch=catch,
                  panel_catches=panel_catches_of(case, planes, len(case.panels)),
                  panel_names=tuple(f"panel {k + 1}" for k in range(len(case.panels))),
                  # the mirror planes its .don declares, as on jaxnet's own mesh: the whole net's figures and files
                  symmetry_planes=tuple((axis, at) for axis, at in sorted(planes.items())),
                  cable_names=tuple(f"cable {k + 1}" for k in range(len(case.cables))) + twine_names)
    scene = with_added_masses(case, femnet_panel_catch_sides(scene), node_type, share)
    validate(scene)
    out = result(case, scene, None, planes, catch_spec, femnet_laws, label=f"FEMNET case {don} on FEMNET's mesh {path}",
                  node_type=node_type, warnings=warnings)
    if gauge is not None:
        out.info["gauge"] = {"node": gauge[0], "axes": gauge[1]}
    # FEMNET's global nodes are the first nodes of its .mdg, in order (its text outputs name nodes by them)
    out.info["global_nodes"] = list(range(scene.n_nodes))
    return out


class MdgText:
    """The text of a FEMNET mesh file (.mdg), read section by section: FEMNET's French headers ("nombre de noeuds",
    "description des noeuds", ...), the count on the line after a "nombre de" header, and rows of numbers. A
    :class:`~jaxnet.scene.SceneError` names the file and the line (``where``: the file)."""

    def __init__(self, path):
        self.lines = pathlib.Path(path).read_text(errors="replace").split("\n")
        self.where = str(path)

    def section(self, header, start=0):
        """The index of the line that starts with ``header`` (case and spacing aside), from line ``start`` on."""
        for i in range(start, len(self.lines)):
            if " ".join(self.lines[i].lower().split()).startswith(header):
                return i
        raise SceneError(f"{self.where}: no '{header}' section (truncated file?)")

    def count_after(self, header):
        """(the count on the line after ``header``, the index of that line)."""
        i = self.section(header)
        try:
            return int(self.lines[i + 1].split()[0]), i + 1
        except (IndexError, ValueError):
            raise SceneError(f"{self.where}:{i + 2}: expected the count of '{header}'") from None

    def rows(self, header, count, width, after):
        """``count`` rows of at least ``width`` finite numbers after the ``header`` found from line ``after``, blank
        lines skipped; each row ends with its line number (1-based)."""
        lines, where = self.lines, self.where
        i = self.section(header, after) + 1
        out = []
        while len(out) < count:
            if i >= len(lines):
                raise SceneError(f"{where}:{i}: the file ends inside '{header}' ({len(out)} of {count} rows; truncated?)")
            words = lines[i].split()
            if words:
                try:
                    values = [float(w) for w in words]
                except ValueError:
                    raise SceneError(f"{where}:{i + 1}: '{header}': expected numbers, found {lines[i].strip()!r}") from None
                if len(values) < width or not all(math.isfinite(v) for v in values):
                    raise SceneError(f"{where}:{i + 1}: '{header}': expected {width} finite numbers, found {lines[i].strip()!r}")
                out.append(values + [i + 1])
            i += 1
        return out


def _netting(case, tri_rows, node_index, where, don, femnet_laws):
    """The :class:`~jaxnet.scene.Netting` of the .mdg's triangles: their nodes, their corners' (U, V) as twine
    coordinates, and the twine of the panel each names."""
    vertices = np.array([[node_index(v, r[-1]) for v in r[1:4]] for r in tri_rows])
    uv = twine_coordinates(np.array([r[4:10] for r in tri_rows]).reshape(-1, 3, 2))
    panel = np.array([int(r[10]) - 1 for r in tri_rows])
    for r, p in zip(tri_rows, panel):
        if not 0 <= p < len(case.panels):
            raise SceneError(f"{where}:{r[-1]}: triangle {int(r[0])} belongs to panel {p + 1}, not in {don}")
    twines = [twine_of(p, case, femnet_laws) for p in case.panels]
    return Netting(vertices=vertices, uv=uv, panel=panel, **netting_rows(twines, panel))


def _bars(case, bar_lines, node_index, where, don, femnet_laws):
    """The :class:`~jaxnet.scene.Bars` of the .mdg's elements: the cables' bars (rest length (pro2 - pro1) × L of
    their cable) and, after them, the numerical twines' (type -PANEL); with the twines' cable names:
    (bars or None, names)."""
    bars = None
    # FEMNET's numerical twines (input netting2ropes): bars of type -PANEL, kept apart (jaxnet.io.femnet.twines)
    twines = numerical_twines(case, femnet_laws)
    twine_lines = [r for r in bar_lines if r[5] < 0]
    bar_lines = [r for r in bar_lines if r[5] >= 0]
    n_bars = len(bar_lines)
    twine_bars, twine_names = mdg_twine_bars(case, twines, twine_lines, node_index, where, femnet_laws)
    if n_bars:
        ends = np.array([[node_index(v, r[-1]) for v in r[1:3]] for r in bar_lines])
        cable = np.array([int(r[5]) - 1 for r in bar_lines])
        for r, c in zip(bar_lines, cable):
            if not 0 <= c < len(case.cables):
                raise SceneError(f"{where}:{r[-1]}: bar {int(r[0])} belongs to cable {c + 1}, not in {don}")
        portion = np.array([r[4] - r[3] for r in bar_lines])
        bad = np.flatnonzero(~(portion > 0))
        if bad.size:
            r = bar_lines[int(bad[0])]
            raise SceneError(f"{where}:{r[-1]}: bar {int(r[0])}: its share of the cable (pro2 - pro1 = "
                             f"{portion[bad[0]]!r}) must be > 0")
        ropes = [rope_of(c) for c in case.cables]
        rest = portion * np.array([case.cables[c].material["l0"].value for c in cable])
        bars = Bars(ends=ends, rest_length=rest, cable=cable, **bar_rows(ropes, cable))
    if twine_bars is not None:
        bars = twine_bars if bars is None else Bars(**{f: np.concatenate([getattr(bars, f), getattr(twine_bars, f)])
                                                       for f in ("ends", "rest_length", "ea_traction", "ea_compression",
                                                                 "diameter", "density", "cable", "cd_normal",
                                                                 "tangential_ratio")})
    return bars, twine_names
