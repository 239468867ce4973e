"""Shared pieces of the FEM shear studies (Figs. 3 and 4): a rigid plate pressed on a gel, then sheared along x."""

from __future__ import annotations

import numpy as np

from contact.scene import BodySpec, ContactSpec, GelSpec, Load, LoadKind, Material, MeshSettings, Scene

MU = 0.5
NU = 0.45            # urethane-like gel; beta/mu = 0.18 and the press is frictionless (docs/theory.md, sec. 8.3)
E = 1.0              # MPa; stick ratios do not depend on E


def plate_shear_scene(name: str, gel: GelSpec, normal_force: float, load_ratios, size_contact: float,
                      size_far: float = 3.0, fine_radius: float | None = None) -> Scene:
    """A rigid plate pressed on the gel with ``normal_force`` [N] (frictionless), then sheared along +x by force
    control to Q/(mu P) = each of ``load_ratios``."""
    return Scene(name=name, gel=gel, material=Material(E, NU), body=BodySpec("plane"),
                 contact=ContactSpec(friction_coefficient=MU, frictionless_press=True),
                 mesh=MeshSettings(size_contact=size_contact, size_far=size_far, fine_radius=fine_radius),
                 loads=(Load(LoadKind.PRESS, "force", (normal_force,)),
                        Load(LoadKind.SHEAR, "force", tuple(float(r * MU * normal_force) for r in load_ratios))))


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
