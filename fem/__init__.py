"""Gel geometry, tetrahedral meshes, linear-elastic operators and sparse solver backends (no friction here)."""

from fem.validation import check_choice, check_finite_array, check_positive, check_range

__all__ = ["check_choice", "check_finite_array", "check_positive", "check_range"]
