"""Acceleration Control block (paper Fig. 7, 8 kHz): force control through a target impedance and a DOB.

Law, at sample k (T = 1/f_s; q joint angle [rad], F measured contact force [N], F_ref commanded force [N]):

    v_k       = (q_k - q_{k-1}) / T                                   backward-difference velocity [rad/s]
    a_ref,k   = (r (F_ref - F_k) - D_a v_k) / I_a                     target impedance [rad/s^2]
    tau_k     = clip(J_n a_ref,k + d_hat_k, -tau_max, tau_max)        torque command [N mm]
    d_hat_k   = LPF[ (tau_{k-1} + tau_{k-2}) / 2 - J_n (q_k - 2 q_{k-1} + q_{k-2}) / T^2 ]     DOB [N mm]

With a perfect DOB the actuator obeys J_n q'' = J_n a_ref, i.e. the target dynamics

    I_a q'' + D_a q' = r (F_ref - F),

an inertia I_a driven by the force error: in free space it closes at v = r F_ref / D_a, in contact with the
stiffness k_c it settles at F = F_ref with w_n = r sqrt(k_c / I_a) and zeta = D_a / (2 I_a w_n). The DOB estimates
everything that is not the nominal inertia - friction, load torque, the inertia error (J - J_n) q'', an external
torque - through the first-order low-pass filter of cut-off g, and the feed-forward cancels it: the residual
disturbance is (1 - Q(z)) d with Q(1) = 1, so a constant disturbance leaves no steady-state force error
(final-value theorem), while an uncancelled torque d would leave e = I_a d / (J_n r). The DOB also cancels
the load torque r F, so the loop relies on it: without the DOB the force loop gain J_n r / I_a is far too low.

Force feedback. F_k is either a force sensor's reading (``ForceFeedback.SENSOR``) or the observer's own estimate
F_hat = d_hat / r (``ForceFeedback.OBSERVER``, a reaction-force observer): the DOB sees the load torque r F among
the disturbances, so a gripper without a force sensor reads its grip from the actuator side. What else the DOB sees
- the finger's damping and the error of the nominal inertia while the finger moves - is then read as force: the
estimate is exact at rest and lags by the DOB's filter.

The averaged torque in the DOB is exact for the zero-order-held nominal plant: for J_n q'' = tau held over each
period, q_k - 2 q_{k-1} + q_{k-2} = T^2 (tau_{k-1} + tau_{k-2}) / (2 J_n), so the raw estimate is zero without
disturbance. The DOB is fed the saturated (applied) torque, so the estimate does not wind up at the torque limit.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_positive, check_range

from .filters import FirstOrderLowPass, sample_period

__all__ = ["AccelerationControlParameters", "DisturbanceObserver", "AccelerationController", "ForceFeedback"]


class ForceFeedback(str, enum.Enum):
    """Where the force loop's F comes from (module docstring)."""

    SENSOR = "sensor"          # a force sensor on the finger: the measured contact force
    OBSERVER = "observer"      # the reaction-force observer d_hat / r: the actuator side alone


@dataclass(frozen=True)
class AccelerationControlParameters:
    """Gains and rate of the Acceleration Control block (defaults: w_n = 2 pi 30 Hz, zeta = 1 at k_c = 10 N/mm).

    Attributes
    ----------
    nominal_inertia : float -- J_n, the actuator inertia the DOB assumes [N mm s^2], > 0.
    target_inertia : float -- I_a, the inertia of the target impedance [N mm s^2], > 0.
    target_damping : float -- D_a, the damping of the target impedance [N mm s/rad], > 0.
    dob_cutoff_hz : float -- cut-off g / (2 pi) of the DOB low-pass filter [Hz], 0 < g/(2 pi) < f_s/2.
    sample_rate_hz : float -- loop rate f_s [Hz], > 0 (8 kHz in the paper).
    arm_radius : float -- nominal fingertip travel per joint angle r [mm/rad], > 0.
    torque_limit : float -- torque command limit tau_max [N mm], > 0.
    force_feedback : ForceFeedback -- the force sensor's reading, or the observer's estimate d_hat / r.
    """

    nominal_inertia: float = 0.1
    target_inertia: float = 0.7
    target_damping: float = 264.0
    dob_cutoff_hz: float = 200.0
    sample_rate_hz: float = 8000.0
    arm_radius: float = 50.0
    torque_limit: float = 500.0
    force_feedback: ForceFeedback = ForceFeedback.SENSOR

    def __post_init__(self):
        try:
            object.__setattr__(self, "force_feedback", ForceFeedback(self.force_feedback))
        except ValueError:
            raise ValueError(f"force_feedback={self.force_feedback!r} is not one of "
                             f"{[item.value for item in ForceFeedback]}") from None
        check_positive("nominal_inertia", self.nominal_inertia, "N mm s^2")
        check_positive("target_inertia", self.target_inertia, "N mm s^2")
        check_positive("target_damping", self.target_damping, "N mm s/rad")
        check_positive("sample_rate_hz", self.sample_rate_hz, "Hz")
        check_range("dob_cutoff_hz", self.dob_cutoff_hz, 0.0, 0.5 * self.sample_rate_hz, "Hz", True, True)
        check_positive("arm_radius", self.arm_radius, "mm")
        check_positive("torque_limit", self.torque_limit, "N mm")

    def force_error_per_residual_torque(self) -> float:
        """Static force error per unit residual (uncancelled) torque, I_a / (J_n r) [N per N mm].

        A torque d_res the DOB has not (yet) cancelled enters J_n q'' = J_n a_ref - d_res, i.e. the target
        dynamics as I_a q'' + D_a q' + r F = r F_ref - (I_a / J_n) d_res: at rest F_ref - F = I_a d_res / (J_n r).
        """
        return self.target_inertia / (self.nominal_inertia * self.arm_radius)

    def natural_frequency(self, contact_stiffness: float) -> float:
        """Target-impedance natural frequency w_n = r sqrt(k_c / I_a) [rad/s] on a contact stiffness k_c [N/mm]."""
        return self.arm_radius * math.sqrt(check_positive("contact_stiffness", contact_stiffness, "N/mm")
                                           / self.target_inertia)


class DisturbanceObserver:
    """Disturbance observer d_hat = LPF[(tau_{k-1} + tau_{k-2})/2 - J_n * second difference of q / T^2] [N mm].

    Parameters
    ----------
    nominal_inertia : float -- J_n [N mm s^2].
    cutoff_hz : float -- DOB low-pass cut-off [Hz].
    sample_rate_hz : float -- rate [Hz].
    angle : float -- joint angle at rest at the start [rad] (fills the difference history).
    """

    def __init__(self, nominal_inertia: float, cutoff_hz: float, sample_rate_hz: float, angle: float = 0.0):
        self.nominal_inertia = check_positive("nominal_inertia", nominal_inertia, "N mm s^2")
        self.sample_period = sample_period(sample_rate_hz)
        self.filter = FirstOrderLowPass(cutoff_hz, sample_rate_hz)
        self.angles = np.full(2, float(angle))          # q_{k-1}, q_{k-2} [rad]
        self.torques = np.zeros(2)                      # applied tau_{k-1}, tau_{k-2} [N mm]
        self.estimate = 0.0                             # d_hat [N mm]

    def step(self, angle: float) -> float:
        """Update with the new angle q_k [rad]; return d_hat_k [N mm]. Call ``record`` with tau_k afterwards."""
        second_difference = angle - 2.0 * self.angles[0] + self.angles[1]
        raw = 0.5 * self.torques.sum() - self.nominal_inertia * second_difference / self.sample_period**2
        self.angles = np.array([angle, self.angles[0]])
        self.estimate = self.filter.step(raw)
        return self.estimate

    def record(self, applied_torque: float) -> None:
        """Store the torque tau_k [N mm] applied over the coming period."""
        self.torques = np.array([applied_torque, self.torques[0]])


class AccelerationController:
    """Acceleration Control block: ``step(force_command, measured_force, angle)`` -> torque command [N mm].

    Parameters
    ----------
    parameters : AccelerationControlParameters
    angle : float -- joint angle at rest at the start [rad].
    use_dob : bool -- False drops the DOB feed-forward (for comparisons; the estimate is still computed).
    """

    def __init__(self, parameters: AccelerationControlParameters, angle: float = 0.0, use_dob: bool = True):
        self.parameters = parameters
        self.use_dob = bool(use_dob)
        self.sample_period = sample_period(parameters.sample_rate_hz)
        self.observer = DisturbanceObserver(parameters.nominal_inertia, parameters.dob_cutoff_hz,
                                            parameters.sample_rate_hz, angle)
        self.velocity = 0.0                              # v_k [rad/s]
        self.torque = 0.0                                # tau_k [N mm]

    def step(self, force_command: float, measured_force: float, angle: float) -> float:
        """One 8 kHz step: F_ref [N], measured F [N] (a force sensor's; not read with ``ForceFeedback.OBSERVER``),
        joint angle q [rad] -> saturated torque command [N mm]."""
        p = self.parameters
        self.velocity = (angle - self.observer.angles[0]) / self.sample_period
        disturbance = self.observer.step(angle)
        force = disturbance / p.arm_radius if p.force_feedback is ForceFeedback.OBSERVER else measured_force
        acceleration_reference = (p.arm_radius * (force_command - force)
                                  - p.target_damping * self.velocity) / p.target_inertia
        torque = p.nominal_inertia * acceleration_reference + (disturbance if self.use_dob else 0.0)
        self.torque = min(max(torque, -p.torque_limit), p.torque_limit)
        self.observer.record(self.torque)
        return self.torque
