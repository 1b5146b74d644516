"""Pictures of a net (matplotlib): netting triangles shaded, cables as lines, fixed nodes marked."""

from __future__ import annotations

import numpy as np


def plot_net(scene, x, ax=None, title=None):
    """Draw the net at positions x (N, 3) on a 3D matplotlib axis (created if None); returns the axis."""
    import matplotlib.pyplot as plt
    from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

    x = np.asarray(x)
    if ax is None:
        fig = plt.figure(figsize=(7, 6))
        ax = fig.add_subplot(projection="3d")
    if scene.netting is not None:
        tri = np.asarray(scene.netting.vertices)
        ax.add_collection3d(Poly3DCollection(x[tri], facecolor=(0.2, 0.5, 0.8, 0.35), edgecolor=(0.1, 0.3, 0.6, 0.5), linewidth=0.2))
    if scene.bars is not None:
        ends = np.asarray(scene.bars.ends)
        ax.add_collection3d(Line3DCollection(x[ends], colors="k", linewidths=1.5))
    fixed = np.asarray(scene.nodes.fixed).any(axis=1)
    ax.scatter(*x[fixed].T, color="red", s=12, depthshade=False, label="fixed")
    sinkers = np.asarray(scene.nodes.mass) > 0
    if sinkers.any():
        ax.scatter(*x[sinkers].T, color="k", s=8, depthshade=False, label="lumped mass")
    lo, hi = x.min(axis=0), x.max(axis=0)
    mid, half = (lo + hi) / 2, max((hi - lo).max() / 2, 1e-9)
    ax.set_xlim(mid[0] - half, mid[0] + half)
    ax.set_ylim(mid[1] - half, mid[1] + half)
    ax.set_zlim(mid[2] - half, mid[2] + half)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_zlabel("z (m)")
    if title:
        ax.set_title(title)
    ax.legend(loc="upper right", fontsize=7)
    return ax


def save_png(path, scene, x, title=None):
    """Write a PNG picture of the net at positions x to ``path``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    ax = plot_net(scene, x, title=title)
    ax.figure.savefig(str(path), dpi=120, bbox_inches="tight")
    plt.close(ax.figure)
