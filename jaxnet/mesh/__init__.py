"""Meshing of netting panels (twine-coordinate space triangulation)."""

from .panel import PanelError, PanelMesh, mesh_panel, side_divisions

__all__ = ["PanelError", "PanelMesh", "mesh_panel", "side_divisions"]
