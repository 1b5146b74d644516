"""Meshing of netting panels: the panel's polygon and its checks (:mod:`~jaxnet.mesh.polygon`), its triangulation
in twine-coordinate space (:mod:`~jaxnet.mesh.panel`), the joining of nodes (:mod:`~jaxnet.mesh.joining`) and the
bending hinges of a netting (:mod:`~jaxnet.mesh.hinges`)."""

from .panel import PanelMesh, mesh_panel
from .polygon import PanelError, side_divisions

__all__ = ["PanelError", "PanelMesh", "mesh_panel", "side_divisions"]
