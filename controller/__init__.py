"""The chain from the sensor to the grasp, in rooms that follow the data (each imports only the rooms before it):

    sensing       pressure array, capacitive node, sampling of a base pressure       (imports no other room)
    estimation    per-bump CoP and forces, eq. 9 rigid transform, calibration, FEM bench       (sensing)
    control       grasp-force laws, references, filters, acceleration control with DOB    (sensing, estimation)
    plant         what makes the data: the actuator, a closed-form Hertz fingertip      (sensing; never estimation
                  or control)
    closed_loop   the MuJoCo grasp and the multi-rate runner: plant and control joined      (all of the above)
    design        fingertip designs through FEM -> sensing -> estimation, one row per design       (all of the above)

The names below are re-exported for convenience; ``docs/design.md``, sec. 2 draws the rooms and the data's path.
"""

import importlib as _importlib
import sys as _sys

from .control import (AccelerationControlParameters, AccelerationController, DisturbanceObserver, FirstOrderLowPass,
                      GraspForceController, GraspForceParameters, GraspPhase, ReferenceGenerator, ReferenceParameters,
                      sample_period)
from .estimation import (BumpLayout, BumpReference, EstimatorCalibration, EstimatorSettings, FrameStatus,
                         PositionSource, RigidTransformTrace, SlipEstimate, bump_positions, calibrate_gain,
                         estimate_slip, fit_rigid_transform, rotational_stick_ratio, translational_stick_ratio)
from .plant import ActuatorParameters, ActuatorPlant, contact_force
from .sensing import (CapacitiveNode, Interpolation, PressureField, SensorArray, capacitive_array, cell_force_operator,
                      resample_time_series, sample)
from .closed_loop._multirate import LoopSample, MultiRateRunner, rate_ratio

# The module paths from before the rooms (``from controller.estimator import ...``) stay importable: each former
# module is the room's module under its old name too (one module object, so isinstance and monkeypatching agree).
FORMER_MODULES = {
    "sensor": "sensing.sensor", "capacitive": "sensing.capacitive",
    "estimator": "estimation.estimator", "rigid_transform": "estimation.rigid_transform",
    "calibration": "estimation.calibration", "bench": "estimation.bench",
    "filters": "control.filters", "references": "control.references",
    "grasp_force_control": "control.grasp_force_control", "incipient_slip": "control.incipient_slip",
    "acceleration_control": "control.acceleration_control",
    "actuator": "plant.actuator", "hertz_plant": "plant.hertz_plant", "multirate": "closed_loop._multirate",
}
for _former, _room_module in FORMER_MODULES.items():
    _sys.modules[f"{__name__}.{_former}"] = _importlib.import_module(f"{__name__}.{_room_module}")

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
