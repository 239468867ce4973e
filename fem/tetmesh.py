"""Graded tetrahedral meshes of the gel geometries: fTetWild (pytetwild) with a background sizing field, a
structured bisection mesh for the flat pad, cleaned up (positive orientation, exact base and top planes), checked
for quality and cached on disk.

Sizing (edge length [mm]) at a point x, the smallest of: ``size_contact + grading * d_contact(x)``, d_contact the
distance to the ball of radius ``contact_radius`` about each first-contact point (bump top, apex, pad centre);
``size_base + grading * (z + height)`` near the sensor plane; and ``size_far``.
"""

from __future__ import annotations

import dataclasses
import importlib
import os
import tempfile
import time
from dataclasses import dataclass

import numpy as np

from fem.geometry import BlockGeometry
from fem.mesh import MeshQuality, graded_block_mesh, mesh_quality, quiet_skfem
from fem.mesh_cache import MeshCache, cache_key
from fem.validation import check_positive, check_range

__all__ = ["GelMesh", "MeshQualityError", "TetMeshSpec", "mesh_gel", "tetrahedralize", "write_mesh_vtu"]

MESHER_REVISION = 1          # bump when the meshing or clean-up algorithm changes: old cache entries then miss


class MeshQualityError(RuntimeError):
    """A mesh failed the quality check (too small a dihedral angle, or a tet of zero volume)."""


@dataclass(frozen=True)
class TetMeshSpec:
    """Mesh parameters [mm]; see the module docstring for the sizing field.

    Parameters
    ----------
    size_contact : float
        Edge length within ``contact_radius`` of each first-contact point [mm].
    size_far : float
        Largest edge length [mm].
    contact_radius : float
        Radius of the fine ball about each first-contact point [mm] (>= 0).
    size_base : float or None
        Edge length on the sensor plane z = -height [mm]; None means ``size_far``.
    grading : float
        Growth of the edge length with distance from the fine regions [mm per mm].
    envelope : float or None
        fTetWild's envelope [mm]: its boundary stays within this distance of the input surface; the contact side is
        then projected onto the exact surface. None means min(size_contact / 4, 0.05 mm). Smaller is much slower.
    segments : int
        Chords per full turn when tessellating curved surfaces.
    min_dihedral_deg : float
        Meshes with a smaller dihedral angle [deg] are rejected.
    """

    size_contact: float
    size_far: float
    contact_radius: float
    size_base: float | None = None
    grading: float = 0.5
    envelope: float | None = None
    segments: int = 64
    min_dihedral_deg: float = 1.0

    def __post_init__(self):
        check_positive("size_contact", self.size_contact, "mm")
        check_range("size_far", self.size_far, self.size_contact, np.inf, "mm (at least size_contact)",
                    high_open=True)
        check_range("contact_radius", self.contact_radius, 0.0, np.inf, "mm", high_open=True)
        if self.size_base is not None:
            check_range("size_base", self.size_base, 0.0, self.size_far, "mm (at most size_far)", low_open=True)
        check_positive("grading", self.grading)
        if self.envelope is not None:
            check_range("envelope", self.envelope, 0.0, self.size_contact, "mm (at most size_contact)",
                        low_open=True)
        check_range("segments", self.segments, 16, 1024)
        check_range("min_dihedral_deg", self.min_dihedral_deg, 0.0, 70.0, "deg")

    @property
    def envelope_mm(self) -> float:
        return self.envelope if self.envelope is not None else min(self.size_contact / 4.0, 0.05)


@dataclass(frozen=True)
class _SizingField:
    """Target edge length over the gel's bounding box, shaped as ``fem.mesh.BlockMeshSpec`` so that
    ``graded_block_mesh`` meshes the box with it (the flat pad itself, or the background mesh for fTetWild)."""

    width: float
    depth: float
    thickness: float
    size_contact: float
    size_far: float
    size_base: float
    contact_radius: float
    grading: float
    centers: tuple                  # ((x, y), ...) first-contact points, at z = 0
    scale: float = 1.0              # a background mesh may be coarser than the field it carries
    half: bool = False              # read by graded_block_mesh: always the whole gel here

    def edge_length(self, points: np.ndarray) -> np.ndarray:
        """Wanted edge length [mm] at points (3, n)."""
        centers = np.asarray(self.centers, dtype=float)                                  # (k, 2)
        offsets = points[:2, :, None] - centers.T[:, None, :]                           # (2, n, k)
        distance = np.sqrt((offsets**2).sum(axis=0) + points[2, :, None] ** 2).min(axis=1)
        contact = self.size_contact + self.grading * np.maximum(distance - self.contact_radius, 0.0)
        base = self.size_base + self.grading * (points[2] + self.thickness)
        return np.minimum(np.minimum(contact, base), self.size_far)

    def target_size(self, points: np.ndarray) -> np.ndarray:
        return self.scale * self.edge_length(points)


@dataclass(frozen=True)
class GelMesh:
    """A checked mesh and its report: ``mesh`` (skfem.MeshTet), ``quality``, meshing ``seconds`` (of the run that
    made it), ``from_cache`` and the cache ``key``."""

    mesh: object
    quality: MeshQuality
    seconds: float
    from_cache: bool
    key: str


def _footprint(geometry) -> tuple[float, float]:
    return (getattr(geometry, "width", None) or geometry.base_width,
            getattr(geometry, "depth", None) or geometry.base_depth)


def _sizing(geometry, spec: TetMeshSpec, scale: float = 1.0) -> _SizingField:
    width, depth = _footprint(geometry)
    centers = tuple(map(tuple, np.asarray(geometry.contact_centers(), dtype=float).tolist()))
    return _SizingField(width, depth, geometry.height, spec.size_contact, spec.size_far,
                        spec.size_base if spec.size_base is not None else spec.size_far, spec.contact_radius,
                        spec.grading, centers, scale)


def _pytetwild():
    """pytetwild's compiled wrapper (``tetrahedralize_mesh``); pytetwild imports PyVista, a core dependency for it."""
    import pytetwild

    return pytetwild.PyfTetWildWrapper


def _versions() -> dict:
    from importlib.metadata import version

    return {name: version(name) for name in ("pytetwild", "manifold3d", "scikit-fem")}


def _run_mesher(geometry, spec: TetMeshSpec) -> tuple[np.ndarray, np.ndarray]:
    """Raw nodes (n, 3) and tets (m, 4) [mm] of the gel, before clean-up."""
    if isinstance(geometry, BlockGeometry):
        mesh = graded_block_mesh(_sizing(geometry, spec))
        return mesh.p.T, mesh.t.T
    surface = geometry.surface(spec.segments)
    background = graded_block_mesh(_sizing(geometry, spec, scale=2.0))
    diagonal = float(np.linalg.norm(surface.bounds[1] - surface.bounds[0]))
    wrapper = _pytetwild()
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="tetwild-") as folder:
        os.chdir(folder)                            # fTetWild writes __tracked_surface.stl into the cwd
        try:
            nodes, tets = wrapper.tetrahedralize_mesh(
                np.ascontiguousarray(surface.vertices, dtype=np.float64),
                np.ascontiguousarray(surface.faces, dtype=np.uint32),
                True, False, 0.05, spec.size_far, spec.envelope_mm / diagonal, 10.0, False, 0, 80, 6, True, False,
                False, np.ascontiguousarray(background.p.T, dtype=np.float64),
                np.ascontiguousarray(background.t.T, dtype=np.int32),
                np.ascontiguousarray(_sizing(geometry, spec).edge_length(background.p), dtype=np.float64))
        finally:
            os.chdir(cwd)
    return np.asarray(nodes, dtype=float), np.asarray(tets, dtype=np.int64)


def _boundary_nodes(tets: np.ndarray) -> np.ndarray:
    faces = np.sort(np.concatenate([tets[:, [1, 2, 3]], tets[:, [0, 2, 3]], tets[:, [0, 1, 3]], tets[:, [0, 1, 2]]]),
                    axis=1)
    unique, counts = np.unique(faces, axis=0, return_counts=True)
    return np.unique(unique[counts == 1])


def _clean(geometry, spec: TetMeshSpec, nodes: np.ndarray, tets: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positive orientation, boundary nodes snapped to the box planes and projected onto the exact contact side,
    the highest node at each first-contact point lifted to z = 0; unreferenced nodes dropped."""
    used, tets = np.unique(tets, return_inverse=True)
    tets = tets.reshape(-1, 4)
    nodes = nodes[used].copy()
    tolerance = spec.envelope_mm
    width, depth = _footprint(geometry)
    boundary = _boundary_nodes(tets)
    x, y, z = nodes[boundary].T
    planes = ((0, width / 2), (0, -width / 2), (1, depth / 2), (1, -depth / 2), (2, -geometry.height))
    on_box = np.zeros(boundary.size, dtype=bool)
    for axis, level in planes:
        near = np.abs(nodes[boundary, axis] - level) <= tolerance
        nodes[boundary[near], axis] = level
        on_box |= near
    top = boundary[~on_box]
    exact = geometry.top_surface_height(nodes[top, :2])
    close = np.abs(nodes[top, 2] - exact) <= 1.5 * tolerance   # steep walls keep fTetWild's (within envelope) place
    nodes[top[close], 2] = exact[close]
    for center in np.asarray(geometry.contact_centers(), dtype=float):
        nearby = top[np.hypot(*(nodes[top, :2] - center).T) <= max(spec.contact_radius, spec.size_contact)]
        if nearby.size == 0 or nodes[nearby, 2].max() < -tolerance:
            raise MeshQualityError(f"no mesh node within {tolerance} mm of the top at contact point {center} mm")
        nodes[nearby[np.argmax(nodes[nearby, 2])], 2] = 0.0
    corners = nodes[tets]                                                    # (m, 4, 3)
    negative = np.linalg.det(corners[:, 1:] - corners[:, :1]) < 0.0
    tets[negative] = tets[negative][:, [0, 2, 1, 3]]
    return nodes, tets


def _check_quality(nodes: np.ndarray, tets: np.ndarray, spec: TetMeshSpec) -> MeshQuality:
    corners = nodes[tets]
    volumes = np.linalg.det(corners[:, 1:] - corners[:, :1]) / 6.0
    floor = 1e-9 * spec.size_contact**3                    # far below any tet the sizing field asks for
    if np.any(volumes <= floor):
        raise MeshQualityError(f"{int((volumes <= floor).sum())} tets with volume <= {floor:g} mm^3 after clean-up")
    quality = mesh_quality(nodes.T, tets.T)
    if quality.min_dihedral_deg < spec.min_dihedral_deg:
        raise MeshQualityError(f"min dihedral angle {quality.min_dihedral_deg:.3g} deg is below min_dihedral_deg="
                               f"{spec.min_dihedral_deg} deg ({quality})")
    return quality


def mesh_gel(geometry, spec: TetMeshSpec, cache_dir=None, use_cache: bool = True) -> GelMesh:
    """Checked, cached tetrahedral mesh of ``geometry`` (a fem.geometry dataclass) with ``spec``.

    The base plane is exactly z = -height (nodes snapped), the top point of each bump exactly z = 0, tets positively
    oriented. The cache (``fem.mesh_cache.MeshCache``, folder ``cache_dir`` or FINGERTIP_CACHE or
    ~/.cache/fingertip-contact) is keyed by the geometry, ``spec`` and the mesher versions.

    Raises
    ------
    MeshQualityError
        If a tet has (near) zero volume or the smallest dihedral angle is below ``spec.min_dihedral_deg``.
    """
    from skfem import MeshTet

    mesh_parameters = dataclasses.asdict(spec)
    del mesh_parameters["min_dihedral_deg"]        # the acceptance threshold does not change the mesh
    payload = {"geometry": type(geometry).__name__, "geometry_parameters": dataclasses.asdict(geometry),
               "spec": mesh_parameters, "versions": _versions(), "revision": MESHER_REVISION}
    key = cache_key(payload)
    cache = MeshCache(cache_dir)
    stored = cache.load(key) if use_cache else None
    if stored is not None:
        nodes, tets = stored[0].T, stored[1].T
        quality = _check_quality(nodes, tets, spec)
        with quiet_skfem():
            mesh = MeshTet(nodes.T, tets.T)
        return GelMesh(mesh, quality, float(cache.metadata(key).get("seconds", 0.0)), True, key)
    start = time.perf_counter()
    nodes, tets = _clean(geometry, spec, *_run_mesher(geometry, spec))
    seconds = time.perf_counter() - start
    quality = _check_quality(nodes, tets, spec)
    if use_cache:
        cache.save(key, nodes.T, tets.T, dict(payload, seconds=seconds, quality=dataclasses.asdict(quality)))
    with quiet_skfem():
        mesh = MeshTet(nodes.T, tets.T)
    return GelMesh(mesh, quality, seconds, False, key)


def tetrahedralize(geometry, size_contact: float, size_far: float, contact_radius: float, cache_dir=None,
                   **options):
    """skfem.MeshTet of ``geometry``, graded from ``size_contact`` [mm] within ``contact_radius`` [mm] of each
    first-contact point to ``size_far`` [mm]; ``options`` are the other ``TetMeshSpec`` fields (size_base, grading,
    envelope, segments, min_dihedral_deg). Cached on disk; see ``mesh_gel`` for the guarantees and the report."""
    spec = TetMeshSpec(size_contact, size_far, contact_radius, **options)
    return mesh_gel(geometry, spec, cache_dir).mesh


def write_mesh_vtu(mesh, path) -> None:
    """Write a skfem.MeshTet as a VTU file (ParaView) via meshio; point/cell data can be added with meshio later."""
    meshio = importlib.import_module("meshio")
    meshio.write(os.fspath(path), meshio.Mesh(mesh.p.T, [("tetra", mesh.t.T)]), file_format="vtu")
