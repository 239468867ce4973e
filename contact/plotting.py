"""Plots of a contact result: the top view of the contact state (open / stick / slip) on the gel's upper surface."""

from __future__ import annotations

import numpy as np

__all__ = ["state_map", "state_legend"]


def state_map(axis, result, increment, title: str, half_width: float | None = None) -> None:
    """Top view of the contact state on the gel's upper surface (open / stick / slip), mirrored for a half model.

    Each surface triangle takes the median state of its three points.
    """
    from matplotlib.colors import ListedColormap

    top = result.model.top
    status = np.zeros(top.areas.size)
    status[result.candidates] = increment.status
    faces = np.median(status[top.triangles], axis=1).round()
    xy, triangles = top.positions[:, :2], top.triangles
    if result.mesh_info.get("half_model"):
        triangles = np.concatenate([triangles, triangles + len(xy)])
        xy = np.concatenate([xy, xy * [1.0, -1.0]])
        faces = np.concatenate([faces, faces])
    colours = ListedColormap(["#d9d9d9", "#2b8cbe", "#e34a33"])
    axis.tripcolor(xy[:, 0], xy[:, 1], triangles, facecolors=faces, cmap=colours, vmin=-0.5, vmax=2.5)
    axis.set_aspect("equal")
    axis.set_title(title, fontsize=9)
    axis.set_xticks([])
    axis.set_yticks([])
    if half_width:
        axis.set_xlim(-half_width, half_width)
        axis.set_ylim(-half_width, half_width)


def state_legend(fig) -> None:
    """One legend for the state maps: open, stick, slip."""
    from matplotlib.patches import Patch

    fig.legend(handles=[Patch(color="#d9d9d9", label="open"), Patch(color="#2b8cbe", label="stick"),
                        Patch(color="#e34a33", label="slip")], loc="lower center", ncol=3, frameon=False)
