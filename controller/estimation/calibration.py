"""Gain from the sensor's position shift (CoP or peak) to the bump's shear displacement, fitted once on FEM data.

The CoP of a bump's sensor readings moves less than the bump's contact (the base spreads the load), so the estimator
scales the shift by a gain fitted on FEM runs of the same fingertip design, u = gain * shift, and stores it with the
design. The estimator itself never sees the true displacement.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from enum import Enum

import numpy as np

from fem.validation import check_finite_array, check_positive, check_range

__all__ = ["EstimatorCalibration", "PositionSource", "calibrate_gain"]


class PositionSource(Enum):
    """Which per-bump position the estimator tracks (paper sec. IV-A)."""

    COP = "cop"    # centre of pressure of the bump's readings (robust to noise)
    PEAK = "peak"  # maximum-pressure point, sub-node by a parabolic fit


@dataclass(frozen=True)
class EstimatorCalibration:
    """Shift-to-displacement gain of one fingertip design, stored with it (JSON via ``to_dict``/``from_dict``).

    Parameters
    ----------
    gain : float -- shear displacement per position shift [-] (mm/mm), > 0; 1 means uncalibrated.
    position : PositionSource -- the position the gain was fitted for.
    r_squared : float or None -- coefficient of determination of the fit [-] (<= 1), None if not fitted.
    sample_count : int -- number of scalar samples (displacement components) in the fit, >= 0.
    """

    gain: float = 1.0
    position: PositionSource = PositionSource.COP
    r_squared: float | None = None
    sample_count: int = 0

    def __post_init__(self):
        check_positive("gain", self.gain)
        object.__setattr__(self, "position", PositionSource(self.position))
        if self.r_squared is not None:
            check_range("r_squared", self.r_squared, -math.inf, 1.0)
        if int(self.sample_count) != self.sample_count or self.sample_count < 0:
            raise ValueError(f"sample_count={self.sample_count!r} must be an integer >= 0")

    def to_dict(self) -> dict:
        """Plain JSON-ready dict (the enum as its string value)."""
        return {**asdict(self), "position": self.position.value}

    @classmethod
    def from_dict(cls, data: dict) -> "EstimatorCalibration":
        """Inverse of ``to_dict``; unknown keys raise ValueError."""
        unknown = set(data) - {"gain", "position", "r_squared", "sample_count"}
        if unknown:
            raise ValueError(f"unknown EstimatorCalibration keys {sorted(unknown)}")
        return cls(**data)


def calibrate_gain(position_shift, true_displacement,
                   position: PositionSource = PositionSource.COP) -> EstimatorCalibration:
    """Least-squares gain through the origin, u = g s, from position shifts s and true displacements u [mm].

    g = sum(s u) / sum(s^2) over every component of the (same-shaped) arrays, e.g. (t, k, 2) per bump and frame.
    R^2 = 1 - sum (u - g s)^2 / sum (u - mean u)^2 is the centred coefficient of determination, so it can be
    negative when a line through the origin fits worse than the mean (a sign that an offset is missing).

    Raises ValueError for shapes that differ, non-finite values, fewer than two samples, all-zero shifts or a
    constant true displacement (R^2 undefined).
    """
    shift = check_finite_array("position_shift", position_shift).ravel()
    truth = check_finite_array("true_displacement", true_displacement)
    if truth.shape != np.shape(position_shift):
        raise ValueError(f"true_displacement shape {truth.shape} differs from position_shift "
                         f"{np.shape(position_shift)}")
    truth = truth.ravel()
    if shift.size < 2:
        raise ValueError(f"calibration needs at least 2 samples, got {shift.size}")
    shift_power = float(shift @ shift)
    if shift_power == 0.0:
        raise ValueError("position_shift is all zero: the gain is undetermined")
    spread = float(np.sum((truth - truth.mean()) ** 2))
    if spread == 0.0:
        raise ValueError("true_displacement is constant: R^2 is undefined; load the calibration runs differently")
    gain = float(shift @ truth) / shift_power
    if gain <= 0.0:
        raise ValueError(f"fitted gain {gain!r} <= 0: the shift moves against the displacement (check the sign)")
    residual = float(np.sum((truth - gain * shift) ** 2))
    return EstimatorCalibration(gain, position, 1.0 - residual / spread, int(shift.size))
