"""Sensor array model, slip estimator, grasp-force control and actuator control with a disturbance observer."""

from .acceleration_control import AccelerationControlParameters, AccelerationController, DisturbanceObserver
from .actuator import ActuatorParameters, ActuatorPlant, contact_force
from .filters import FirstOrderLowPass, sample_period
from .grasp_force_control import GraspForceController, GraspForceParameters
from .multirate import LoopSample, MultiRateRunner, rate_ratio
from .references import GraspPhase, ReferenceGenerator, ReferenceParameters
from .calibration import EstimatorCalibration, PositionSource, calibrate_gain
from .estimator import (BumpLayout, BumpReference, EstimatorSettings, SlipEstimate, bump_positions, estimate_slip,
                        rotational_stick_ratio, translational_stick_ratio)
from .rigid_transform import FrameStatus, RigidTransformTrace, fit_rigid_transform
from .capacitive import CapacitiveNode
from .sensor import (Interpolation, PressureField, SensorArray, capacitive_array, cell_force_operator,
                     resample_time_series, sample)

__all__ = [
    "AccelerationControlParameters",
    "AccelerationController",
    "ActuatorParameters",
    "ActuatorPlant",
    "DisturbanceObserver",
    "FirstOrderLowPass",
    "GraspForceController",
    "GraspForceParameters",
    "GraspPhase",
    "LoopSample",
    "MultiRateRunner",
    "ReferenceGenerator",
    "ReferenceParameters",
    "contact_force",
    "rate_ratio",
    "sample_period",
    "EstimatorCalibration",
    "PositionSource",
    "calibrate_gain",
    "BumpLayout",
    "BumpReference",
    "EstimatorSettings",
    "SlipEstimate",
    "bump_positions",
    "estimate_slip",
    "rotational_stick_ratio",
    "translational_stick_ratio",
    "FrameStatus",
    "RigidTransformTrace",
    "fit_rigid_transform",
    "Interpolation",
    "PressureField",
    "SensorArray",
    "CapacitiveNode",
    "capacitive_array",
    "cell_force_operator",
    "resample_time_series",
    "sample",
]
