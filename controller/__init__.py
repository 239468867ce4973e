"""Sensor array model, slip estimator, grasp-force control and actuator control with a disturbance observer."""

from .acceleration_control import AccelerationControlParameters, AccelerationController, DisturbanceObserver
from .actuator import ActuatorParameters, ActuatorPlant, contact_force
from .filters import FirstOrderLowPass, sample_period
from .grasp_force_control import GraspForceController, GraspForceParameters
from .multirate import LoopSample, MultiRateRunner, rate_ratio
from .references import GraspPhase, ReferenceGenerator, ReferenceParameters

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
]
