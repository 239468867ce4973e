"""Graded tetrahedral meshes of a gel block, refined by longest-edge bisection where contact can occur."""

from __future__ import annotations

import logging
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from fem.validation import check_positive, check_range

__all__ = ["BlockMeshSpec", "graded_block_mesh", "mesh_quality", "MeshQuality", "quiet_skfem", "size_cells",
           "positively_oriented",
           "BISECTION_TETS_PER_CELL", "GMSH_TETS_PER_CELL", "NODES_PER_TET"]

_TET_EDGES = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])


@dataclass(frozen=True)
class BlockMeshSpec:
    """A block x in [-width/2, width/2], y in [-depth/2, depth/2], z in [-thickness, 0], graded toward a disc on top.

    Element edges are at most ``size_contact`` [mm] inside the cylinder of radius ``fine_radius`` [mm] about
    ``fine_center`` down to ``fine_depth`` [mm] below the top, and grow by ``grading`` [mm per mm] away from it,
    up to ``size_far`` [mm].
    """

    width: float = 40.0
    depth: float = 40.0
    thickness: float = 20.0
    size_contact: float = 0.15
    size_far: float = 4.0
    fine_radius: float = 1.5
    fine_depth: float = 0.2
    fine_center: tuple[float, float] = (0.0, 0.0)
    grading: float = 0.5
    half: bool = False          # keep only y >= 0 (a mirror-symmetric half model about the plane y = 0)

    def __post_init__(self):
        for name in ("width", "depth", "thickness", "size_contact", "size_far", "grading"):
            check_positive(name, getattr(self, name), "" if name == "grading" else "mm")
        check_range("fine_radius", self.fine_radius, 0.0, np.inf, "mm", high_open=True)
        check_range("fine_depth", self.fine_depth, 0.0, self.thickness, "mm")
        if self.size_contact > self.size_far:
            raise ValueError(f"size_contact={self.size_contact} mm must not exceed size_far={self.size_far} mm")
        smallest_side = min(self.width, self.depth, self.thickness)
        if self.size_contact > smallest_side / 2:
            raise ValueError(f"size_contact={self.size_contact} mm is more than half the smallest block side "
                             f"({smallest_side} mm)")

    def target_size(self, points: np.ndarray) -> np.ndarray:
        """Wanted longest edge [mm] at points (3, n)."""
        radial = np.hypot(points[0] - self.fine_center[0], points[1] - self.fine_center[1])
        below = -points[2]
        distance = np.hypot(np.maximum(radial - self.fine_radius, 0.0), np.maximum(below - self.fine_depth, 0.0))
        return np.minimum(self.size_contact + self.grading * distance, self.size_far)


def _longest_edges(mesh) -> np.ndarray:
    corners = mesh.p[:, mesh.t]                                          # (3, 4, n_tets)
    edge_vectors = corners[:, _TET_EDGES[:, 0]] - corners[:, _TET_EDGES[:, 1]]   # (3, 6, n_tets)
    return np.sqrt((edge_vectors**2).sum(axis=0)).max(axis=0)           # (n_tets,)


@contextmanager
def quiet_skfem():
    """Silence skfem's 'Transforming over 1000 vertices to C_CONTIGUOUS' notices (harmless, one per refinement)."""
    logger = logging.getLogger("skfem.mesh.mesh")
    level = logger.level
    logger.setLevel(logging.ERROR)
    try:
        yield
    finally:
        logger.setLevel(level)


def graded_block_mesh(spec: BlockMeshSpec, max_rounds: int = 80):
    """Tetrahedral mesh (skfem.MeshTet) of the block, refined until every tet meets ``spec.target_size``.

    Starts from a tensor grid at ``size_far`` and bisects marked tets along their longest edge (skfem's
    adaptive refinement), which keeps element shape bounded while grading over a factor of 40 in size.
    """
    from skfem import MeshTet

    def axis(length, low):
        cells = max(2, int(np.ceil(length / spec.size_far)))
        return np.linspace(low, low + length, cells + 1)

    y_axis = axis(spec.depth / 2, 0.0) if spec.half else axis(spec.depth, -spec.depth / 2)
    mesh = MeshTet.init_tensor(axis(spec.width, -spec.width / 2), y_axis,
                               axis(spec.thickness, -spec.thickness))
    with quiet_skfem():
        for _ in range(max_rounds):
            # the smallest target over an element's corners and centroid: a large element that reaches into the
            # fine zone is refined even when its centroid lies outside it
            corners = mesh.p[:, mesh.t]                                          # (3, 4, n_tets)
            wanted = np.minimum(spec.target_size(corners.mean(axis=1)),
                                spec.target_size(corners.reshape(3, -1)).reshape(4, -1).min(axis=0))
            marked = np.flatnonzero(_longest_edges(mesh) > wanted * (1 + 1e-9))
            if marked.size == 0:
                return mesh
            mesh = mesh.refined(marked)
    raise RuntimeError(f"graded_block_mesh: refinement did not finish in {max_rounds} rounds "
                       f"(size_contact={spec.size_contact} mm)")


@dataclass(frozen=True)
class MeshQuality:
    """Shape measures of a tet mesh: smallest dihedral angle [deg] and smallest radius ratio 3 r_in / r_circ."""

    min_dihedral_deg: float
    min_radius_ratio: float
    n_tets: int
    n_nodes: int


def positively_oriented(nodes: np.ndarray, tets: np.ndarray) -> np.ndarray:
    """Tets (m, 4) with two corners swapped where the volume is negative (VTK's and the quality measures'
    convention; a mesher or a reflection may give either orientation); ``tets`` is not modified."""
    corners = nodes[tets]                                                    # (m, 4, 3)
    negative = np.linalg.det(corners[:, 1:] - corners[:, :1]) < 0.0
    tets = tets.copy()
    tets[negative] = tets[negative][:, [0, 2, 1, 3]]
    return tets


def mesh_quality(nodes: np.ndarray, tets: np.ndarray) -> MeshQuality:
    """Smallest dihedral angle and radius ratio over the tets (nodes (3, n), tets (4, n_tets))."""
    x = nodes[:, tets].transpose(2, 1, 0)                               # (n_tets, 4, 3)
    faces = np.array([[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]])
    a, b, c = (x[:, faces[:, k], :] for k in range(3))                  # (n_tets, 4, 3) each
    normals = np.cross(b - a, c - a)                                    # (n_tets, 4, 3)
    inward = np.einsum("eki,eki->ek", normals, x - a) > 0.0             # face k is opposite vertex k
    normals[inward] *= -1.0                                             # all outward
    areas = 0.5 * np.linalg.norm(normals, axis=2)                       # (n_tets, 4)
    unit = normals / np.linalg.norm(normals, axis=2, keepdims=True)
    pairs = np.array([[0, 1], [0, 2], [0, 3], [1, 2], [1, 3], [2, 3]])
    cosines = np.einsum("eki,eki->ek", unit[:, pairs[:, 0]], unit[:, pairs[:, 1]])
    dihedral = 180.0 - np.degrees(np.arccos(np.clip(cosines, -1.0, 1.0)))
    volume = np.abs(np.linalg.det(x[:, 1:, :] - x[:, :1, :])) / 6.0
    inradius = 3.0 * volume / areas.sum(axis=1)
    # circumradius from the standard formula |a|^2 (b x c) + ... over 12 V, edges from vertex 0
    e1, e2, e3 = (x[:, k, :] - x[:, 0, :] for k in (1, 2, 3))
    numerator = (np.einsum("ei,ei->e", e1, e1)[:, None] * np.cross(e2, e3)
                 + np.einsum("ei,ei->e", e2, e2)[:, None] * np.cross(e3, e1)
                 + np.einsum("ei,ei->e", e3, e3)[:, None] * np.cross(e1, e2))
    circumradius = np.linalg.norm(numerator, axis=1) / (12.0 * volume)
    return MeshQuality(float(dihedral.min()), float((3.0 * inradius / circumradius).min()),
                       int(tets.shape[1]), int(nodes.shape[1]))



# tets per h^3 of volume (h the target edge length), measured with size_cells(): graded bisection 24-35 under a
# sphere (HCM-1's block at h = 0.35 ... 0.1 mm with the fine zone a/2 deep, the stability study's block, P1 and P2)
# and 47-66 under a plane pressing a whole block top (h = 0.5 and 0.35 mm; a fine zone 0.2 mm deep and as wide as the
# block: bisection cannot grade as fast as the target below it), gmsh 0.65-0.75 x 6 on the Fig. 4 cap and the 3x3
# array. The bisection value is the old upper end: 1.4-2.1x too many tets under a sphere, 0.76-1.07 of them under a
# plane (the memory model in contact.limits carries a margin of 1.5 for that)
BISECTION_TETS_PER_CELL = 50.0
GMSH_TETS_PER_CELL = 4.5
NODES_PER_TET = 0.2          # 3.9-5.4 tets per node on the same meshes


def size_cells(target_size, centers, width: float, depth: float, height: float, smallest: float) -> float:
    """Integral of 1 / h^3 over the gel [-], h = ``target_size`` (points (3, n) -> edge length [mm]): tets ~ a
    mesher's constant times this. Without meshing, each first-contact point (``centers``, (k, 2) [mm] on z = 0)
    takes an equal share of the footprint as a cylinder, integrated on rings and layers graded from ``smallest``
    [mm] up, so that a fine zone of any size is resolved. Good to a factor of about 2: enough to refuse a mesh that
    cannot fit the machine before making it."""
    centers = np.asarray(centers, dtype=float).reshape(-1, 2)
    radius = np.sqrt(width * depth / (np.pi * len(centers)))
    # 100 graded samples each way: within 0.3 % of 400 on the 3x3 array, HCM-1 and the Fig. 4 cap, 25x faster
    r = np.concatenate([[0.0], np.geomspace(smallest / 20.0, radius, 100)])
    z = np.concatenate([[0.0], np.geomspace(smallest / 20.0, height, 100)])
    r_mid, z_mid = 0.5 * (r[1:] + r[:-1]), 0.5 * (z[1:] + z[:-1])
    ring_volume = np.pi * np.diff(r**2)[:, None] * np.diff(z)[None, :]                  # (n_r, n_z)
    rr, zz = np.meshgrid(r_mid, z_mid, indexing="ij")
    total = 0.0
    for cx, cy in centers:
        points = np.stack([cx + rr.ravel(), np.full(rr.size, cy), -zz.ravel()])
        size = np.asarray(target_size(points), dtype=float).reshape(rr.shape)
        total += float((ring_volume / size**3).sum())
    return total
