"""Parametric gel geometries in mm (docs/design.md, sec. 4: top at z = 0, bonded base at z = -height), each validated,
with closed-form volume and contact-side area, and a checked watertight triangle surface for meshing."""

from fem.geometry.array import ArrayGeometry
from fem.geometry.caps import BlockGeometry, CapGeometry, FlatCapGeometry

GelGeometry = BlockGeometry | CapGeometry | FlatCapGeometry | ArrayGeometry

__all__ = ["ArrayGeometry", "BlockGeometry", "CapGeometry", "FlatCapGeometry", "GelGeometry"]
