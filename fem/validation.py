"""Input checks shared by every package: a bad value raises ValueError naming the parameter, its value and what is
allowed. Types are strict: a bool or a string is not a number, a number is not a bool (TOML files carry types, and
``frictionless_press = "no"`` must not read as true). ``check_all`` runs several checks and reports every problem at
once (``InputErrors``); string options are ``Choice`` enums, converted where they enter (``parse_choice``).
"""

from __future__ import annotations

import math
import numbers
from enum import Enum
from typing import Callable, Iterable

import numpy as np

__all__ = ["check_range", "check_positive", "check_finite_array", "check_choice", "check_number", "check_integer",
           "check_bool", "check_all", "InputErrors", "Choice", "parse_choice", "describe"]


class InputErrors(ValueError):
    """One or more bad inputs; ``problems`` lists one message per problem (the text joins them, one per line)."""

    def __init__(self, problems: Iterable[str]):
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))

    @staticmethod
    def problems_of(error: ValueError) -> list[str]:
        """The problems of any ValueError: an InputErrors' list, or the one message of another."""
        return list(error.problems) if isinstance(error, InputErrors) else [str(error)]


def check_all(*checks: Callable[[], object]) -> None:
    """Run every check (a callable raising ValueError) and raise one InputErrors with all their problems."""
    problems: list[str] = []
    for check in checks:
        try:
            check()
        except ValueError as error:
            problems.extend(InputErrors.problems_of(error))
    if problems:
        raise InputErrors(problems)


def describe(value) -> str:
    """``value!r`` with its kind when that is what is wrong: '"1.0" (a string)', 'True (a bool)'."""
    kinds = {bool: "a bool", str: "a string", type(None): "nothing", list: "a list", tuple: "a list", dict: "a table"}
    kind = next((text for cls, text in kinds.items() if isinstance(value, cls)), None)
    if isinstance(value, (bool, np.bool_)):
        kind = "a bool"
    return f"{value!r} ({kind})" if kind else repr(value)


def check_number(name: str, value, unit: str = "") -> float:
    """Return ``float(value)`` for a real number (int, float or numpy number, not a bool); else raise ValueError."""
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value[()]
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ValueError(f"{name}={describe(value)} is not a number{f' [{unit}]' if unit else ''}")
    return float(value)


def check_range(
    name: str,
    value: float,
    low: float,
    high: float,
    unit: str = "",
    low_open: bool = False,
    high_open: bool = False,
) -> float:
    """Return ``float(value)`` if it is a finite number inside [low, high] (open ends as asked), else raise
    ValueError."""
    number = check_number(name, value, unit)
    inside = (number > low if low_open else number >= low) and (number < high if high_open else number <= high)
    if not (inside and math.isfinite(number)):
        lo, hi = "(" if low_open else "[", ")" if high_open else "]"
        raise ValueError(f"{name}={value!r} outside allowed range {lo}{low}, {high}{hi} {unit}".rstrip())
    return number


def check_positive(name: str, value: float, unit: str = "") -> float:
    """Return ``float(value)`` if it is finite and > 0, else raise ValueError."""
    return check_range(name, value, 0.0, math.inf, unit, low_open=True, high_open=True)


def check_integer(name: str, value, low: int, high: int) -> int:
    """Return ``int(value)`` for an integer (int or numpy integer, not a bool, not 1.5 or 2.0) in [low, high]."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Integral):
        raise ValueError(f"{name}={describe(value)} is not an integer (allowed: {low} to {high})")
    if not low <= value <= high:
        raise ValueError(f"{name}={value!r} outside allowed range [{low}, {high}] (an integer)")
    return int(value)


def check_bool(name: str, value) -> bool:
    """Return ``value`` if it is a bool (true/false in TOML), else raise ValueError: no "no", 0 or 1."""
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}={describe(value)} is not a bool: write true or false")
    return bool(value)


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


class Choice(str, Enum):
    """A string option: compares equal to its text, prints as its text, and is written to JSON as its text."""

    def __str__(self) -> str:
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

    @classmethod
    def values(cls) -> list[str]:
        return [member.value for member in cls]


def parse_choice(name: str, value, choices: type[Choice]) -> Choice:
    """The member of ``choices`` whose text is ``value`` (a member passes through), else ValueError listing them."""
    if isinstance(value, choices):
        return value
    if isinstance(value, str):
        for member in choices:
            if member.value == value:
                return member
    shown = repr(value) if isinstance(value, str) else describe(value)
    raise ValueError(f"{name}={shown} is not one of {choices.values()}")
