"""Meshing of netting panels: the panel's polygon and its checks (:mod:`~jaxnet.mesh.polygon`), its triangulation
in twine-coordinate space (:mod:`~jaxnet.mesh.panel`) or its numerical twines (bars, :mod:`~jaxnet.mesh.twines`), the joining of nodes (:mod:`~jaxnet.mesh.joining`) and the
bending hinges of a netting (:mod:`~jaxnet.mesh.hinges`)."""

from .panel import PanelMesh, lattice_coordinates, lattice_divisions, mesh_panel
from .polygon import PanelError, side_divisions
from .twines import NumericalTwines, TwineMesh, mesh_twines

__all__ = ["NumericalTwines", "PanelError", "PanelMesh", "TwineMesh", "lattice_coordinates", "lattice_divisions", "mesh_panel", "mesh_twines", "side_divisions"]
