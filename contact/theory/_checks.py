"""Input checks for the closed-form theory: scalars and arrays, ValueError naming the argument and its range."""

from __future__ import annotations

import math

import numpy as np

from fem.validation import check_choice, check_finite_array, check_range

__all__ = ["checked", "checked_modulus", "check_choice", "as_output"]


def checked(name, value, low=-math.inf, high=math.inf, unit="", low_open=False, high_open=False):
    """Return ``value`` as float (scalar) or float array if finite and inside the range, else raise ValueError."""
    array = _float_array(name, value)
    low_open, high_open = low_open or math.isinf(low), high_open or math.isinf(high)    # (0, inf), not (0, inf]
    if array.ndim == 0:
        return check_range(name, float(array), low, high, unit, low_open, high_open)
    check_finite_array(name, array, low, high)
    for end, is_open in ((low, low_open), (high, high_open)):
        if is_open and np.any(array == end):
            lo, hi = "(" if low_open else "[", ")" if high_open else "]"
            raise ValueError(f"{name} has value(s) equal to {end}; allowed range {lo}{low}, {high}{hi} {unit}".rstrip())
    return array


def checked_modulus(name, value, unit="MPa", allow_infinite=False):
    """Return an elastic modulus [MPa] checked > 0 and finite (or ``inf`` = rigid body, if allowed), else ValueError."""
    array = _float_array(name, value)
    rigid = np.isposinf(array) if allow_infinite else np.zeros(array.shape, dtype=bool)
    if array.ndim == 0:
        return math.inf if rigid else checked(name, value, 0.0, math.inf, unit, low_open=True)
    checked(name, array[~rigid], 0.0, math.inf, unit, low_open=True)
    return array


def _float_array(name, value):
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}={value!r} is not a number or an array of numbers") from None


def as_output(value):
    """Return a Python float for a 0-d result and the array otherwise."""
    array = np.asarray(value, dtype=float)
    return float(array) if array.ndim == 0 else array
