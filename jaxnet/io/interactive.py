"""A 3D view of a net to turn with the mouse in a notebook (plotly): netting coloured by twine tension (each
triangle by the larger of its U and V twines' tensions, so that the colour bar's top is the largest twine
tension), cables by bar tension, the fixed nodes marked, the whole net drawn for a model with symmetry planes.

Why plotly: its figures are HTML and JavaScript that Jupyter (and any browser) shows without a server behind
them, and its wheel is about 10 MB of pure Python; PyVista's static-HTML export needs VTK (a 140 MB wheel) and
trame. The view is for looking; the figures to read numbers off are in :mod:`jaxnet.io.plot` and ParaView's
files in :mod:`jaxnet.io.vtk`.

plotly is an optional dependency (``pip install -e ".[notebooks]"``); importing this module does not need it,
:func:`view` does and says so. A figure's ``write_html`` embeds plotly.js (plotly's default); the notebooks'
saved outputs load it from plotly's CDN (``notebooks/execute.py``: kilobytes per view instead of megabytes), and
JupyterLab draws them from plotly's JSON without it. The page of a run that opens offline is net.html
(:mod:`jaxnet.io.page`).
"""

from __future__ import annotations

import numpy as np

from jaxnet import figures
from jaxnet.scene import mirrored

#: the title of the netting's colour bar
TWINE_LABEL = "twine tension, larger of U and V (N)"


def _plotly():
    try:
        import plotly.graph_objects as go
    except ImportError as err:  # the extra was not installed
        raise ImportError("jaxnet.io.interactive.view needs plotly: pip install plotly (or the 'notebooks' "
                          "extra: pip install -e \".[notebooks]\")") from err
    return go


def view(scene, x, twine_tension=None, bar_tension=None, title=None, whole=True):
    """A plotly Figure of the net at positions x (N, 3) (m).

    Args:
      scene: the :class:`~jaxnet.scene.Scene`.
      x: node positions (N, 3), m.
      twine_tension: (E, 2) tensions (N) of the U and V twines of every triangle; default
        :func:`jaxnet.figures.twine_tensions` at x. A triangle is coloured by the larger of the two.
      bar_tension: (B,) tensions (N) of the cable bars; default :func:`jaxnet.figures.bar_tensions` at x.
      title: the figure's title.
      whole: draw the whole net of a model with symmetry planes (every mirrored copy), else the model only.
    Returns:
      a ``plotly.graph_objects.Figure``: one Mesh3d of the triangles (cell intensity the larger of the U and V
      twine tensions, its colour bar in N), one Scatter3d of the cables (coloured by bar tension), one of the fixed nodes;
      equal scales on the three axes.
    """
    go = _plotly()
    x = np.asarray(x, dtype=float)
    copies = mirrored(scene, x) if whole else x[None]
    traces = []
    if scene.netting is not None:
        tw = figures.twine_tensions(scene, x) if twine_tension is None else np.asarray(twine_tension, dtype=float)
        tri = np.asarray(scene.netting.vertices)
        n = x.shape[0]
        points = copies.reshape(-1, 3)
        faces = np.concatenate([tri + c * n for c in range(len(copies))])
        intensity = np.tile(tw.max(axis=1), len(copies))
        traces.append(go.Mesh3d(x=points[:, 0], y=points[:, 1], z=points[:, 2], i=faces[:, 0], j=faces[:, 1],
                                k=faces[:, 2], intensity=intensity, intensitymode="cell", colorscale="Viridis",
                                colorbar={"title": {"text": TWINE_LABEL}}, flatshading=True, name="netting",
                                hovertemplate="larger twine tension %{intensity:.3g} N<extra></extra>"))
    if scene.bars is not None:
        bt = figures.bar_tensions(scene, x) if bar_tension is None else np.asarray(bar_tension, dtype=float)
        ends = np.asarray(scene.bars.ends)
        # one polyline of segments separated by gaps (NaN), each end coloured by its bar's tension
        segments = np.concatenate([c[ends] for c in copies])                     # (copies * B, 2, 3)
        gap = np.full((len(segments), 1, 3), np.nan)
        path = np.concatenate([segments, gap], axis=1).reshape(-1, 3)
        colour = np.repeat(np.tile(bt, len(copies)), 3)
        traces.append(go.Scatter3d(x=path[:, 0], y=path[:, 1], z=path[:, 2], mode="lines", name="cables",
                                   line={"color": colour, "colorscale": "Reds", "width": 5},
                                   hovertemplate="bar tension %{line.color:.3g} N<extra></extra>"))
    fixed = np.asarray(scene.nodes.fixed).all(axis=1)
    if fixed.any():
        held = x[fixed]
        traces.append(go.Scatter3d(x=held[:, 0], y=held[:, 1], z=held[:, 2], mode="markers", name="fixed nodes",
                                   marker={"size": 2, "color": "black"}))
    fig = go.Figure(traces)
    fig.update_layout(title=title, scene={"aspectmode": "data", "xaxis_title": "x (m)", "yaxis_title": "y (m)",
                                          "zaxis_title": "z (m)"},
                      margin={"l": 0, "r": 0, "t": 30 if title else 0, "b": 0})
    return fig
