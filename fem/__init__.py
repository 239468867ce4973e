"""Gel geometry, tetrahedral meshes, linear-elastic operators and sparse solver backends (no friction here)."""

from fem.geometry import ArrayGeometry, BlockGeometry, CapGeometry, FlatCapGeometry, GelGeometry
from fem.cache_dir import CacheWarning
from fem.mesh_cache import MeshCache, default_cache_dir
from fem.tetmesh import GelMesh, MeshQualityError, TetMeshSpec, mesh_gel, tetrahedralize, write_mesh_vtu
from fem.validation import check_choice, check_finite_array, check_positive, check_range

__all__ = ["check_choice", "check_finite_array", "check_positive", "check_range",
           "ArrayGeometry", "BlockGeometry", "CapGeometry", "FlatCapGeometry", "GelGeometry",
           "MeshCache", "default_cache_dir", "CacheWarning",
           "GelMesh", "MeshQualityError", "TetMeshSpec", "mesh_gel", "tetrahedralize", "write_mesh_vtu"]
