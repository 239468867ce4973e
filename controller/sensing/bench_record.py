"""What a sensor bench hands over: the loads it applied (known, from its own gauges) and the readings it saw."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BenchRecord"]


@dataclass(frozen=True, eq=False)
class BenchRecord:
    """One bench state: a flat plate pressed on the fingertip with ``total_force`` [N] and, by force control, the
    ``tangential_force`` (2,) [N] and ``torque`` [N mm] about the array centre, or, by displacement control, the
    plate's ``shift`` (2,) [mm] and ``angle`` [rad]; ``readings`` (ny, nx) [N] the mean of ``frames`` frames.
    ``kind`` names the series ("rest", "press", "shear", "twist", "shift", ...)."""

    kind: str
    total_force: float
    readings: np.ndarray
    frames: int
    tangential_force: tuple[float, float] = (0.0, 0.0)
    torque: float = 0.0
    shift: tuple[float, float] = (0.0, 0.0)
    angle: float = 0.0
    force_controlled: bool = True

    def __post_init__(self):
        readings = np.asarray(self.readings, dtype=float)
        if readings.ndim != 2 or not np.all(np.isfinite(readings)):
            raise ValueError(f"bench record {self.kind!r}: readings must be a finite (ny, nx) frame")
        object.__setattr__(self, "readings", readings)
