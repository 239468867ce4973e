"""Input checks shared by every package: a bad value raises ValueError naming the parameter, value and allowed range."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["check_range", "check_positive", "check_finite_array", "check_choice"]


def check_range(
    name: str,
    value: float,
    low: float,
    high: float,
    unit: str = "",
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Return ``float(value)`` if it is finite and inside [low, high] (open ends as asked), else raise ValueError."""
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name}={value!r} is not a number") from None
    inside = (number > low if low_open else number >= low) and (number < high if high_open else number <= high)
    if not (inside and math.isfinite(number)):
        lo, hi = "(" if low_open else "[", ")" if high_open else "]"
        raise ValueError(f"{name}={value!r} outside allowed range {lo}{low}, {high}{hi} {unit}".rstrip())
    return number


def check_positive(name: str, value: float, unit: str = "") -> float:
    """Return ``float(value)`` if it is finite and > 0, else raise ValueError."""
    return check_range(name, value, 0.0, math.inf, unit, low_open=True, high_open=True)


def check_finite_array(name: str, values, low: float = -math.inf, high: float = math.inf) -> np.ndarray:
    """Return ``values`` as a float array if every entry is finite and inside [low, high], else raise ValueError."""
    array = np.asarray(values, dtype=float)
    bad = ~np.isfinite(array) | (array < low) | (array > high)
    if np.any(bad):
        first = array.flat[int(np.flatnonzero(bad.ravel())[0])]
        raise ValueError(
            f"{name} has {int(bad.sum())} value(s) that are NaN, infinite or outside [{low}, {high}] (first: {first!r})"
        )
    return array


def check_choice(name: str, value, allowed) -> object:
    """Return ``value`` if it is one of ``allowed``, else raise ValueError listing the choices."""
    if value not in allowed:
        raise ValueError(f"{name}={value!r} is not one of {sorted(map(str, allowed))}")
    return value
