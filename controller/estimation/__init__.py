"""Estimation: per-bump forces and centres of pressure, the eq. 9 rigid transform, the gain calibration and the FEM
bench of Figs. 6 and 9 (``bench``); may import controller.sensing."""

from .calibration import EstimatorCalibration, PositionSource, calibrate_gain
from .estimator import (GATE_POOL_WIDTH, BumpLayout, BumpReference, EstimatorSettings, SlipEstimate, bump_positions,
                        estimate_slip, gate_pool_for, gated_weights, rotational_stick_ratio, translational_stick_ratio)
from .rigid_transform import FrameStatus, RigidTransformTrace, fit_rigid_transform

__all__ = ["EstimatorCalibration", "PositionSource", "calibrate_gain", "BumpLayout", "BumpReference",
           "EstimatorSettings", "SlipEstimate", "bump_positions", "estimate_slip", "rotational_stick_ratio",
           "translational_stick_ratio", "GATE_POOL_WIDTH", "gate_pool_for", "gated_weights", "FrameStatus",
           "RigidTransformTrace", "fit_rigid_transform"]
