"""Tetrahedral meshing of the gel geometries: orientation, exact base and top planes, volume, quality report and
rejection, the on-disk cache (a second call must not re-mesh), VTU export. Meshes are kept small (a few seconds)."""

import os

import meshio
import numpy as np
import pytest

import fem.tetmesh as tetmesh
from fem.geometry import ArrayGeometry, BlockGeometry, FlatCapGeometry
from fem.cache_dir import CacheWarning
from fem.mesh_cache import CACHE_ENV_VAR, MeshCache, cache_key, default_cache_dir
from fem.tetmesh import MeshQualityError, TetMeshSpec, mesh_gel, tetrahedralize, write_mesh_vtu

ROUND_OFF = 1e-9     # mm: snapped coordinates are set exactly; sums over a few thousand faces stay far below this

BUMP = ArrayGeometry(rows=1, cols=1, bump_radius=4.0, base_width=12.0, base_depth=12.0, base_thickness=2.0)
BUMP_SPEC = TetMeshSpec(size_contact=0.6, size_far=3.0, contact_radius=1.0, size_base=1.5)


def _volumes(mesh):
    corners = mesh.p[:, mesh.t].transpose(2, 1, 0)                   # (n_tets, 4, 3)
    return np.linalg.det(corners[:, 1:] - corners[:, :1]) / 6.0


def _boundary_faces(mesh):
    return mesh.p[:, mesh.facets[:, mesh.boundary_facets()]].transpose(2, 1, 0)   # (n_faces, 3, 3)


def _face_areas(corners):
    return 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)


@pytest.fixture(scope="module")
def cache_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("mesh-cache")


@pytest.fixture(scope="module")
def bump_mesh(cache_dir):
    return mesh_gel(BUMP, BUMP_SPEC, cache_dir)


def test_tets_are_positively_oriented(bump_mesh):
    assert np.all(_volumes(bump_mesh.mesh) > 0.0)


def test_tet_volume_is_inscribed_in_the_exact_volume(bump_mesh):
    # every boundary node lies on the exact (convex) bump or on a plane, so the mesh is inscribed: its volume is
    # below the closed form, by at most the sagitta of each curved face, L^2 / (2 r) with L its longest edge
    faces = _boundary_faces(bump_mesh.mesh)
    curved = ~np.any(np.all(faces == faces[:, :1], axis=1), axis=1)          # not on an axis-aligned plane
    longest = np.linalg.norm(faces - np.roll(faces, 1, axis=1), axis=2).max(axis=1)
    sagitta_volume = (_face_areas(faces[curved]) * longest[curved] ** 2 / (2.0 * BUMP.bump_radius)).sum()
    deficit = BUMP.volume - _volumes(bump_mesh.mesh).sum()
    assert -ROUND_OFF <= deficit <= sagitta_volume


def test_meshing_twice_gives_the_same_mesh(bump_mesh, tmp_path):
    # gmsh on one thread is deterministic: a fresh cache gives the same mesh, node for node (fTetWild did not)
    again = mesh_gel(BUMP, BUMP_SPEC, tmp_path)
    assert not again.from_cache and again.key == bump_mesh.key
    np.testing.assert_array_equal(again.mesh.p, bump_mesh.mesh.p)
    np.testing.assert_array_equal(again.mesh.t, bump_mesh.mesh.t)


def test_meshing_off_the_main_thread_gives_the_same_mesh(bump_mesh, tmp_path):
    # dask workers mesh in threads, where gmsh must not install its SIGINT handler (Python refuses it there)
    import threading

    meshed = []
    worker = threading.Thread(target=lambda: meshed.append(mesh_gel(BUMP, BUMP_SPEC, tmp_path)))
    worker.start()
    worker.join()
    assert meshed and not meshed[0].from_cache
    np.testing.assert_array_equal(meshed[0].mesh.p, bump_mesh.mesh.p)


def test_cache_key_changes_with_the_mesher(monkeypatch, tmp_path):
    before = mesh_gel(BlockGeometry(4.0, 4.0, 2.0), TetMeshSpec(0.5, 1.0, 0.5), tmp_path).key
    monkeypatch.setattr(tetmesh, "MESHER_REVISION", tetmesh.MESHER_REVISION + 1)
    after_revision = mesh_gel(BlockGeometry(4.0, 4.0, 2.0), TetMeshSpec(0.5, 1.0, 0.5), tmp_path)
    monkeypatch.setattr(tetmesh, "_versions", lambda: {"gmsh": "0.0"})
    after_version = mesh_gel(BlockGeometry(4.0, 4.0, 2.0), TetMeshSpec(0.5, 1.0, 0.5), tmp_path)
    assert len({before, after_revision.key, after_version.key}) == 3 and not after_version.from_cache


def test_base_plane_is_exact_and_complete(bump_mesh):
    faces = _boundary_faces(bump_mesh.mesh)
    on_base = np.all(faces[:, :, 2] == -BUMP.height, axis=1)
    assert _face_areas(faces[on_base]).sum() == pytest.approx(BUMP.base_width * BUMP.base_depth, abs=ROUND_OFF)
    assert bump_mesh.mesh.p[2].min() == -BUMP.height


def test_top_point_is_at_zero_on_the_bump_axis(bump_mesh):
    nodes = bump_mesh.mesh.p
    assert nodes[2].max() == 0.0
    top = np.flatnonzero(nodes[2] == 0.0)
    assert np.hypot(nodes[0, top], nodes[1, top]).min() <= BUMP_SPEC.size_contact


def test_contact_side_nodes_lie_on_the_exact_surface(bump_mesh):
    nodes = bump_mesh.mesh.p
    boundary = bump_mesh.mesh.boundary_nodes()
    upper = (np.hypot(nodes[0, boundary], nodes[1, boundary]) < 2.0) & (nodes[2, boundary] > -1.0)
    near_top = boundary[upper]                                    # the bump's top, slope < 0.6: projected
    exact = BUMP.top_surface_height(nodes[:2, near_top].T)
    # only the one lifted apex node may be off, by the sag rho^2 / (2 r) over which it was lifted, rho <= h
    off = np.abs(nodes[2, near_top] - exact)
    assert np.sort(off)[-2] <= ROUND_OFF
    assert off.max() <= BUMP_SPEC.size_contact**2 / (2.0 * BUMP.bump_radius) + ROUND_OFF


def test_fine_near_contact_coarse_far(bump_mesh):
    mesh = bump_mesh.mesh
    lengths = np.linalg.norm(mesh.p[:, mesh.t[0]] - mesh.p[:, mesh.t[1]], axis=0)
    centroids = mesh.p[:, mesh.t].mean(axis=1)
    near = np.linalg.norm(centroids, axis=0) < BUMP_SPEC.contact_radius
    assert np.median(lengths[near]) < 1.5 * BUMP_SPEC.size_contact     # gmsh meets its sizes within about 1.5x
    assert np.median(lengths[~near]) > 1.5 * np.median(lengths[near])


def test_quality_is_reported(bump_mesh):
    quality = bump_mesh.quality
    assert quality.n_tets == bump_mesh.mesh.t.shape[1] and quality.n_nodes == bump_mesh.mesh.p.shape[1]
    assert quality.min_dihedral_deg > BUMP_SPEC.min_dihedral_deg
    assert 0.0 < quality.min_radius_ratio <= 1.0


def test_bad_mesh_is_rejected(cache_dir, bump_mesh):
    strict = TetMeshSpec(**{**BUMP_SPEC.__dict__, "min_dihedral_deg": 60.0})   # same mesh, read from the cache
    with pytest.raises(MeshQualityError, match="min dihedral angle .* below min_dihedral_deg=60.0"):
        mesh_gel(BUMP, strict, cache_dir)


def test_second_call_reads_the_cache(cache_dir, bump_mesh, monkeypatch):
    def no_meshing(*args):
        raise AssertionError("re-meshed a cached geometry")

    monkeypatch.setattr(tetmesh, "_run_mesher", no_meshing)
    again = mesh_gel(BUMP, BUMP_SPEC, cache_dir)
    assert again.from_cache and again.key == bump_mesh.key
    np.testing.assert_array_equal(again.mesh.p, bump_mesh.mesh.p)
    np.testing.assert_array_equal(again.mesh.t, bump_mesh.mesh.t)


def test_changed_parameters_miss_the_cache(tmp_path, monkeypatch):
    calls = []
    real = tetmesh._run_mesher
    monkeypatch.setattr(tetmesh, "_run_mesher", lambda *args: calls.append(args) or real(*args))
    block = BlockGeometry(width=4.0, depth=4.0, thickness=2.0)
    for size_far in (1.0, 1.0, 2.0, 2.0):
        tetrahedralize(block, 0.5, size_far, 0.5, cache_dir=tmp_path)
    assert len(calls) == 2
    assert not [name for name in os.listdir(tmp_path) if name.endswith(".tmp")]      # atomic writes left no debris


def test_block_uses_the_structured_mesher_exactly(tmp_path):
    block = BlockGeometry(width=6.0, depth=4.0, thickness=2.0)
    mesh = tetrahedralize(block, 0.4, 1.0, 1.0, cache_dir=tmp_path)
    volumes = _volumes(mesh)
    assert np.all(volumes > 0.0)
    assert volumes.sum() == pytest.approx(block.volume, abs=ROUND_OFF)
    assert mesh.p[2].max() == 0.0 and mesh.p[2].min() == -2.0


def test_flat_face_stays_flat(tmp_path):
    punch = FlatCapGeometry(width=10.0, depth=10.0, base_thickness=2.0, cap_radius=3.0, flat_radius=2.0,
                            edge_radius=2.0)
    mesh = tetrahedralize(punch, 0.5, 2.0, 2.0, cache_dir=tmp_path / "cache")
    boundary = mesh.boundary_nodes()
    upper = (np.hypot(mesh.p[0, boundary], mesh.p[1, boundary]) < 0.9 * punch.flat_radius) & (mesh.p[2, boundary] > -1)
    on_flat = boundary[upper]
    assert on_flat.size > 3 and np.all(mesh.p[2, on_flat] == 0.0)
    assert sorted(path.name for path in tmp_path.iterdir()) == ["cache"]     # the mesher left no files behind


def test_vtu_round_trip(bump_mesh, tmp_path):
    path = tmp_path / "gel.vtu"
    write_mesh_vtu(bump_mesh.mesh, path)
    back = meshio.read(path)
    np.testing.assert_allclose(back.points, bump_mesh.mesh.p.T)
    np.testing.assert_array_equal(back.cells_dict["tetra"], bump_mesh.mesh.t.T)


def test_cache_folder_and_corrupt_files(tmp_path, monkeypatch):
    monkeypatch.setenv(CACHE_ENV_VAR, str(tmp_path / "here"))
    assert default_cache_dir() == tmp_path / "here"
    monkeypatch.delenv(CACHE_ENV_VAR)
    assert default_cache_dir().name == "fingertip-contact"
    cache = MeshCache(tmp_path)
    key = cache_key({"a": 1.0})
    assert key != cache_key({"a": 1.0 + 1e-12}) and cache.load(key) is None
    cache.path(key).write_bytes(b"not an npz")
    with pytest.warns(CacheWarning, match="damaged cache entry .*mesh-"):
        assert cache.load(key) is None                                 # unreadable: re-mesh instead of failing
    cache.save(key, np.zeros((3, 4)), np.arange(4).reshape(4, 1), {"seconds": 1.5})
    nodes, tets = cache.load(key)
    assert nodes.shape == (3, 4) and tets.shape == (4, 1) and cache.metadata(key)["seconds"] == 1.5


BAD_SPECS = [
    (dict(size_contact=0.0), "size_contact=0.0"),
    (dict(size_far=0.5), "size_far=0.5.*at least size_contact"),
    (dict(contact_radius=-1.0), "contact_radius=-1.0"),
    (dict(size_base=5.0), "size_base=5.0.*at most size_far"),
    (dict(grading=0.0), "grading=0.0"),
    (dict(segments=8), "segments=8"),
    (dict(min_dihedral_deg=80.0), "min_dihedral_deg=80.0"),
]


@pytest.mark.parametrize("changes, message", BAD_SPECS, ids=[next(iter(c)) for c, _ in BAD_SPECS])
def test_bad_mesh_parameters_raise_naming_them(changes, message):
    with pytest.raises(ValueError, match=message):
        TetMeshSpec(**{**dict(size_contact=1.0, size_far=3.0, contact_radius=1.0), **changes})
