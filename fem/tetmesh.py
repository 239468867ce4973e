"""Graded tetrahedral meshes of the gel geometries: gmsh (OpenCASCADE solid, Delaunay, one thread) with an
analytic sizing field for caps and arrays, the structured bisection mesher for the flat pad; cleaned up (positive
orientation, exact base and top planes), checked for quality and cached on disk.

Same geometry, same spec and same mesher versions give the same mesh, node for node, on every run: gmsh's Delaunay
and optimisers are deterministic on one thread (its configuration files and environment are not read), and the
bisection mesher is plain numpy. fTetWild (pytetwild), used before, was not: it shuffles the input triangles with a
``std::random_device`` seed (``sort_input_faces``) and runs its optimiser on TBB threads, so the same cap gave
1838, 1660 and 1765 nodes in three runs.

Sizing (edge length [mm]) at a point x, the smallest of: ``size_contact + grading * d_contact(x)``, d_contact the
distance to the ball of radius ``contact_radius`` about each first-contact point (bump top, apex, pad centre);
``size_base + grading * (z + height)`` near the sensor plane; and ``size_far``.
"""

from __future__ import annotations

import dataclasses
import importlib
import os
import threading
import time
from dataclasses import dataclass

import numpy as np

from fem.geometry import BlockGeometry
from fem.mesh import MeshQuality, graded_block_mesh, mesh_quality, positively_oriented, quiet_skfem
from fem.mesh_cache import MeshCache, cache_key
from fem.validation import check_positive, check_range

__all__ = ["GelMesh", "MeshQualityError", "MesherUnavailable", "TetMeshSpec", "mesh_gel", "tetrahedralize", "write_mesh_vtu"]

MESHER_REVISION = 2          # bump when the meshing or clean-up algorithm changes: old cache entries then miss
# 1: fTetWild (pytetwild); 2: gmsh, one thread, OpenCASCADE solids from the exact profile


class MeshQualityError(RuntimeError):
    """A mesh failed the quality check (too small a dihedral angle, or a tet of zero volume)."""


class MesherUnavailable(RuntimeError):
    """gmsh cannot be loaded (not installed, or its shared library misses a system library)."""


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
    segments : int
        Samples per full turn of arc along the gel's profile; the solid of revolution is a spline through them
        (at 1024 it is within 1e-8 mm of the exact profile on the shipped geometries) and the contact side is then
        projected onto the exact surface.
    min_dihedral_deg : float
        Meshes with a smaller dihedral angle [deg] are rejected.
    """

    size_contact: float
    size_far: float
    contact_radius: float
    size_base: float | None = None
    grading: float = 0.5
    segments: int = 1024
    min_dihedral_deg: float = 1.0

    def __post_init__(self):
        check_positive("size_contact", self.size_contact, "mm")
        check_range("size_far", self.size_far, self.size_contact, np.inf, "mm (at least size_contact)",
                    high_open=True)
        check_range("contact_radius", self.contact_radius, 0.0, np.inf, "mm", high_open=True)
        if self.size_base is not None:
            check_range("size_base", self.size_base, 0.0, self.size_far, "mm (at most size_far)", low_open=True)
        check_positive("grading", self.grading)
        check_range("segments", self.segments, 64, 8192)
        check_range("min_dihedral_deg", self.min_dihedral_deg, 0.0, 70.0, "deg")

    @property
    def snap_tolerance(self) -> float:
        """Distance [mm] within which a boundary node is snapped onto a box plane or the exact contact side: far
        above the spline's and round-off's error, far below an element (1e-3 size_contact)."""
        return 1e-3 * self.size_contact


@dataclass(frozen=True)
class _SizingField:
    """Target edge length over the gel's bounding box, shaped as ``fem.mesh.BlockMeshSpec`` so that
    ``graded_block_mesh`` meshes the box with it (the flat pad), and written as a gmsh formula for the others."""

    width: float
    depth: float
    thickness: float
    size_contact: float
    size_far: float
    size_base: float
    contact_radius: float
    grading: float
    centers: tuple                  # ((x, y), ...) first-contact points, at z = 0
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
        return self.edge_length(points)

    def gmsh_formula(self) -> str:
        """``edge_length`` as a gmsh MathEval expression (numbers by repr, so exactly the same field)."""
        distance = [f"Sqrt((x - ({x!r}))^2 + (y - ({y!r}))^2 + z^2)" for x, y in self.centers]
        nearest = distance[0]
        for term in distance[1:]:
            nearest = f"Min({nearest}, {term})"
        contact = f"{self.size_contact!r} + {self.grading!r} * Max({nearest} - {self.contact_radius!r}, 0)"
        base = f"{self.size_base!r} + {self.grading!r} * (z + {self.thickness!r})"
        return f"Min(Min({contact}, {base}), {self.size_far!r})"


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


def _sizing(geometry, spec: TetMeshSpec) -> _SizingField:
    width, depth = _footprint(geometry)
    centers = tuple(map(tuple, np.asarray(geometry.contact_centers(), dtype=float).tolist()))
    return _SizingField(width, depth, geometry.height, spec.size_contact, spec.size_far,
                        spec.size_base if spec.size_base is not None else spec.size_far, spec.contact_radius,
                        spec.grading, centers)


GMSH_OPTIONS = {
    "General.Terminal": 0,
    # one thread everywhere: gmsh's Delaunay and optimisers are then deterministic
    "General.NumThreads": 1, "Mesh.MaxNumThreads1D": 1, "Mesh.MaxNumThreads2D": 1, "Mesh.MaxNumThreads3D": 1,
    # the sizing field alone sets the element size (not the CAD points, curvature or boundary)
    "Mesh.MeshSizeExtendFromBoundary": 0, "Mesh.MeshSizeFromPoints": 0, "Mesh.MeshSizeFromCurvature": 0,
    "Mesh.Algorithm3D": 1,                    # Delaunay
    # gmsh's and Netgen's optimisers: min dihedral 21.7 instead of 13.7 deg on the Fig. 4 cap at h = 0.4 mm
    "Mesh.Optimize": 1, "Mesh.OptimizeNetgen": 1,
}                                             # part of the mesh cache key: a change re-meshes
_GMSH_LOCK = threading.Lock()     # gmsh is one global state per process: one mesh at a time


def _gmsh():
    """The gmsh module, or MesherUnavailable saying what to install."""
    try:
        import gmsh

        gmsh.isInitialized()             # fails here when libgmsh could not be loaded
    except (ImportError, OSError, AttributeError) as error:
        raise MesherUnavailable(
            f"gmsh could not be loaded ({error}); it meshes caps and arrays: pip install gmsh, and on Debian/Ubuntu "
            f"the system libraries its wheel links: apt-get install libglu1-mesa libxcursor1 libxft2 libxinerama1"
        ) from None
    return gmsh


def _versions() -> dict:
    from importlib.metadata import version

    return {name: version(name) for name in ("gmsh", "scikit-fem")}


def _even_profile(points: np.ndarray) -> np.ndarray:
    """The profile (m, 2) with every chord longer than the median split evenly, so that a spline through it does
    not overshoot where a straight piece (the flat of a flat cap: one chord) meets a finely sampled arc."""
    lengths = np.hypot(*np.diff(points, axis=0).T)
    step = float(np.median(lengths))
    pieces = [points[:1]]
    for start, end, length in zip(points[:-1], points[1:], lengths):
        count = max(1, int(np.ceil(length / step - 1e-9)))
        pieces.append(start + np.outer(np.arange(1, count + 1) / count, end - start))
    return np.vstack(pieces)


def _revolved_profiles(geometry, segments: int):
    """(rho, z) profile points [mm] from the axis to the rim, the axis positions (k, 2) and the base top z [mm]."""
    profile = _even_profile(geometry._profile_points(segments))
    if hasattr(geometry, "bump_centers"):
        return profile, np.asarray(geometry.bump_centers, float), -geometry.bump_radius
    return profile, np.zeros((1, 2)), -geometry.cap_height


def _not_interruptible_off_main_thread(gmsh) -> dict:
    """gmsh.initialize installs a SIGINT handler, which Python allows only in the main thread: a dask worker's
    thread (design and scene sweeps) must ask it not to (``interruptible``, in the gmsh versions that have it)."""
    import inspect

    if threading.current_thread() is threading.main_thread() \
            or "interruptible" not in inspect.signature(gmsh.initialize).parameters:
        return {}
    return {"interruptible": False}


def _gmsh_mesh(geometry, spec: TetMeshSpec) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (n, 3) and tets (m, 4) [mm] of a cap or array: the base box fused with one solid of revolution per
    bump (a spline through the profile, revolved about the bump axis), meshed with the sizing field on one thread."""
    gmsh = _gmsh()
    profile, axes, base_top = _revolved_profiles(geometry, spec.segments)
    width, depth = _footprint(geometry)
    floor = base_top - 0.5 * geometry.base_thickness          # the revolved solids reach into the base
    with _GMSH_LOCK:
        gmsh.initialize(["-noenv"], readConfigFiles=False, **_not_interruptible_off_main_thread(gmsh))
        try:
            for name, value in GMSH_OPTIONS.items():
                gmsh.option.setNumber(name, value)
            occ = gmsh.model.occ
            box = occ.addBox(-width / 2, -depth / 2, -geometry.height, width, depth, geometry.height + base_top)
            solids = []
            for cx, cy in axes:
                points = [occ.addPoint(cx + rho, cy, z) for rho, z in profile]
                rim, axis = occ.addPoint(cx + profile[-1, 0], cy, floor), occ.addPoint(cx, cy, floor)
                curves = [occ.addSpline(points), occ.addLine(points[-1], rim), occ.addLine(rim, axis),
                          occ.addLine(axis, points[0])]
                face = occ.addPlaneSurface([occ.addCurveLoop(curves)])
                solids += [tag for tag in occ.revolve([(2, face)], cx, cy, 0.0, 0.0, 0.0, 1.0, 2.0 * np.pi)
                           if tag[0] == 3]
            occ.fuse([(3, box)], solids)
            occ.synchronize()
            field = gmsh.model.mesh.field.add("MathEval")
            gmsh.model.mesh.field.setString(field, "F", _sizing(geometry, spec).gmsh_formula())
            gmsh.model.mesh.field.setAsBackgroundMesh(field)
            gmsh.model.mesh.generate(3)
            tags, coordinates, _ = gmsh.model.mesh.getNodes()
            element_types, _, element_nodes = gmsh.model.mesh.getElements(3)
        finally:
            gmsh.finalize()
    tet_nodes = element_nodes[list(element_types).index(4)]      # gmsh type 4: 4-node tetrahedron
    index = np.zeros(int(tags.max()) + 1, dtype=np.int64)
    index[tags.astype(np.int64)] = np.arange(tags.size)
    return coordinates.reshape(-1, 3), index[tet_nodes.astype(np.int64).reshape(-1, 4)]


def _run_mesher(geometry, spec: TetMeshSpec) -> tuple[np.ndarray, np.ndarray]:
    """Raw nodes (n, 3) and tets (m, 4) [mm] of the gel, before clean-up."""
    if isinstance(geometry, BlockGeometry):
        mesh = graded_block_mesh(_sizing(geometry, spec))
        return mesh.p.T, mesh.t.T
    return _gmsh_mesh(geometry, spec)


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
    tolerance = spec.snap_tolerance
    width, depth = _footprint(geometry)
    boundary = _boundary_nodes(tets)
    planes = ((0, width / 2), (0, -width / 2), (1, depth / 2), (1, -depth / 2), (2, -geometry.height))
    on_box = np.zeros(boundary.size, dtype=bool)
    for axis, level in planes:
        near = np.abs(nodes[boundary, axis] - level) <= tolerance
        nodes[boundary[near], axis] = level
        on_box |= near
    top = boundary[~on_box]
    exact = geometry.top_surface_height(nodes[top, :2])
    close = np.abs(nodes[top, 2] - exact) <= tolerance        # nodes of the contact side (not of steep side walls)
    nodes[top[close], 2] = exact[close]
    for center in np.asarray(geometry.contact_centers(), dtype=float):
        nearby = top[np.hypot(*(nodes[top, :2] - center).T) <= max(spec.contact_radius, spec.size_contact)]
        if nearby.size == 0 or nodes[nearby, 2].max() < -tolerance:
            raise MeshQualityError(f"no mesh node within {tolerance} mm of the top at contact point {center} mm")
        nodes[nearby[np.argmax(nodes[nearby, 2])], 2] = 0.0
    return nodes, positively_oriented(nodes, tets)


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
               "spec": mesh_parameters, "versions": _versions(), "revision": MESHER_REVISION,
               "mesher_options": {} if isinstance(geometry, BlockGeometry) else GMSH_OPTIONS}
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
        try:
            cache.save(key, nodes.T, tets.T, dict(payload, seconds=seconds, quality=dataclasses.asdict(quality)))
        except OSError as error:                   # a full disk costs the cache entry, never the mesh
            import warnings

            from fem.cache_dir import CacheWarning

            warnings.warn(f"mesh not cached in {str(cache.directory)!r} ({error.strerror or error})", CacheWarning,
                          stacklevel=2)
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
