"""Multi-rate closed loop: one 1 kHz Grasp Force Control step, then N 8 kHz Acceleration Control steps."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from controller.control.acceleration_control import AccelerationController
from controller.plant.actuator import ActuatorPlant
from controller.control.grasp_force_control import GraspForceController
from controller.control.references import GraspPhase

__all__ = ["LoopSample", "MultiRateRunner", "rate_ratio"]


def rate_ratio(fast_rate_hz: float, slow_rate_hz: float) -> int:
    """N = fast / slow as an int if it is a whole number >= 1 (to 1e-9 relative), else raise ValueError."""
    ratio = float(fast_rate_hz) / float(slow_rate_hz)
    whole = round(ratio)
    if whole < 1 or abs(ratio - whole) > 1e-9 * ratio:
        raise ValueError(f"acceleration rate {fast_rate_hz!r} Hz is not an integer multiple (>= 1) "
                         f"of the grasp-force rate {slow_rate_hz!r} Hz (ratio {ratio!r})")
    return int(whole)


@dataclass(frozen=True)
class LoopSample:
    """State after one slow step: time [s], force command [N], contact force [N], torque [N mm],
    shear displacement u_x [mm] and twist angle theta [rad] that the grasp controller saw."""

    time: float
    force_command: float
    contact_force: float
    torque: float
    shear_displacement: float
    twist_angle: float


class MultiRateRunner:
    """Steps the grasp controller once and the acceleration controller and plant ``steps_per_grasp_step`` times.

    Parameters
    ----------
    grasp : GraspForceController -- slow loop (its ``sample_rate_hz``).
    acceleration : AccelerationController -- fast loop (an integer multiple of the slow rate).
    plant : ActuatorPlant -- actuator and fingertip contact; its contact force is the measured force.
    sense : callable -- ``sense(time, contact_force) -> (u_x [mm], theta [rad], contact_count)``: the estimator
        output the grasp controller sees (in tests, a closed-form contact model; later the sensor and estimator).
    """

    def __init__(self, grasp: GraspForceController, acceleration: AccelerationController, plant: ActuatorPlant,
                 sense: Callable[[float, float], tuple[float, float, int]]):
        self.grasp = grasp
        self.acceleration = acceleration
        self.plant = plant
        self.sense = sense
        self.steps_per_grasp_step = rate_ratio(acceleration.parameters.sample_rate_hz,
                                               grasp.parameters.sample_rate_hz)
        self.fast_period = acceleration.sample_period
        self.time = 0.0                                                   # [s]

    def step(self, phase: GraspPhase, external_torque: float = 0.0) -> LoopSample:
        """Advance by one slow period (1 ms) in ``phase``, with ``external_torque`` [N mm] on the actuator."""
        shear_displacement, twist_angle, contact_count = self.sense(self.time, self.plant.contact_force)
        command = self.grasp.step(shear_displacement, twist_angle, contact_count, phase)
        for _ in range(self.steps_per_grasp_step):
            torque = self.acceleration.step(command, self.plant.contact_force, self.plant.angle)
            self.plant.step(torque, self.fast_period, external_torque)
        self.time += self.steps_per_grasp_step * self.fast_period
        return LoopSample(self.time, command, self.plant.contact_force, torque, shear_displacement, twist_angle)
