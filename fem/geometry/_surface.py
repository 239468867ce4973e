"""Solid modelling for the gel geometries: boxes, revolved profiles, boolean union, checked triangle surfaces."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["arc_points", "box_solid", "revolved_solid", "union_surface"]


def arc_points(center_r: float, center_z: float, radius: float, angle_start: float, angle_end: float,
               segments: int) -> np.ndarray:
    """Points (m, 2) in the (rho, z) half-plane on a circular arc, angle measured from +rho toward +z [rad].

    The number of chords follows the circumferential resolution: ``segments`` chords per full turn, at least one.
    """
    count = max(1, math.ceil(abs(angle_end - angle_start) * segments / (2.0 * math.pi)))
    angles = np.linspace(angle_start, angle_end, count + 1)
    return np.column_stack([center_r + radius * np.cos(angles), center_z + radius * np.sin(angles)])


def box_solid(width: float, depth: float, z_low: float, z_high: float):
    """manifold3d solid [-width/2, width/2] x [-depth/2, depth/2] x [z_low, z_high] (mm)."""
    from manifold3d import Manifold

    return Manifold.cube((width, depth, z_high - z_low), center=True).translate((0.0, 0.0, 0.5 * (z_low + z_high)))


def revolved_solid(profile: np.ndarray, z_floor: float, center_xy, segments: int):
    """Solid of revolution about the vertical axis through ``center_xy``.

    Parameters
    ----------
    profile : ndarray (m, 2)
        (rho, z) [mm] of the top surface from the axis (rho = 0) outward to the rim; rho increasing.
    z_floor : float
        The solid is closed below at this height [mm] (inside the base block, so the union overlaps).
    center_xy : (2,) floats
        Axis position [mm].
    segments : int
        Chords per full turn.
    """
    from manifold3d import CrossSection, Manifold

    rim_rho = profile[-1, 0]
    outline = np.vstack([[[0.0, z_floor], [rim_rho, z_floor]], profile[::-1]])   # counter-clockwise in (rho, z)
    solid = Manifold.revolve(CrossSection([outline]), circular_segments=segments)
    return solid.translate((float(center_xy[0]), float(center_xy[1]), 0.0))


def union_surface(solids):
    """Boolean union of manifold3d solids as a checked trimesh.Trimesh (watertight, outward normals).

    Raises
    ------
    RuntimeError
        If the merged surface is not watertight, not consistently wound or encloses a non-positive volume.
    """
    import trimesh
    from manifold3d import Manifold

    solid = Manifold.batch_boolean(list(solids), _union_op()) if len(solids) > 1 else solids[0]
    mesh_data = solid.to_mesh()
    surface = trimesh.Trimesh(np.asarray(mesh_data.vert_properties)[:, :3], np.asarray(mesh_data.tri_verts),
                              process=False)
    # the union leaves zero-area slivers with coincident vertex copies where a rim lies on the base plane:
    # merge the copies, then drop the faces that collapsed
    surface.merge_vertices()
    surface.update_faces(surface.nondegenerate_faces())
    surface.update_faces(surface.unique_faces())
    surface.remove_unreferenced_vertices()
    if not surface.is_watertight:
        raise RuntimeError("gel surface is not watertight after the boolean union")
    if not surface.is_winding_consistent:
        raise RuntimeError("gel surface has inconsistent triangle winding")
    if not surface.volume > 0.0:
        raise RuntimeError(f"gel surface encloses volume {surface.volume} mm^3 <= 0: normals point inward")
    return surface


def _union_op():
    from manifold3d import OpType

    return OpType.Add
