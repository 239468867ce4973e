"""Plant model of a torque-controlled gripper actuator pressing a fingertip on an object [mm, N, N mm, s, rad].

Model (one finger of a parallel gripper; the object is held still by the other finger, so it is a fixed wall here):

    J q'' = tau_sat - b q' - tau_c sign(q') - r F(q) - tau_ext,      tau_sat = clip(tau, -tau_max, tau_max),
    F(q) = k_c max(r q, 0),

q the joint angle [rad] measured from first touch (q < 0: open), r the arm radius [mm] turning the joint angle
into fingertip travel r q [mm] and the contact force F [N] into the load torque r F [N mm], k_c the contact
stiffness of the fingertip [N/mm] (a linear spring: force = stiffness * penetration; a Hertz fingertip has the
tangent stiffness 2 E* a(F), which the loop design must cover), tau_ext an external disturbance torque [N mm].

Integration: semi-implicit (symplectic) Euler on ``substeps`` sub-steps per call with time-stepping Coulomb
friction: the friction impulse is at most tau_c h, and if it can stop the joint within the sub-step the joint
sticks (q' = 0). This models stiction (|net torque| <= tau_c holds the joint) without a velocity dead band.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_positive, check_range

__all__ = ["ActuatorParameters", "ActuatorPlant", "contact_force"]


@dataclass(frozen=True)
class ActuatorParameters:
    """Physical gripper actuator and fingertip contact (the plant; the controller only knows nominal values).

    Attributes
    ----------
    inertia : float -- joint inertia J [N mm s^2] (1 kg m^2 = 1e3 N mm s^2), > 0.
    viscous_friction : float -- viscous coefficient b [N mm s/rad], >= 0.
    coulomb_friction : float -- Coulomb (and static) friction torque tau_c [N mm], >= 0.
    torque_limit : float -- saturation torque tau_max [N mm], > 0.
    arm_radius : float -- fingertip travel per joint angle r [mm/rad], > 0.
    contact_stiffness : float -- fingertip contact stiffness k_c [N/mm], > 0.
    """

    inertia: float = 0.1
    viscous_friction: float = 1.0
    coulomb_friction: float = 0.0
    torque_limit: float = 500.0
    arm_radius: float = 50.0
    contact_stiffness: float = 10.0

    def __post_init__(self):
        check_positive("inertia", self.inertia, "N mm s^2")
        check_range("viscous_friction", self.viscous_friction, 0.0, math.inf, "N mm s/rad", high_open=True)
        check_range("coulomb_friction", self.coulomb_friction, 0.0, math.inf, "N mm", high_open=True)
        check_positive("torque_limit", self.torque_limit, "N mm")
        check_positive("arm_radius", self.arm_radius, "mm")
        check_positive("contact_stiffness", self.contact_stiffness, "N/mm")


def contact_force(angle, parameters: ActuatorParameters):
    """Contact force F = k_c max(r q, 0) [N] at joint angle ``angle`` q [rad] (float or array)."""
    return parameters.contact_stiffness * np.maximum(parameters.arm_radius * np.asarray(angle, dtype=float), 0.0)


class ActuatorPlant:
    """State (joint angle q [rad], velocity q' [rad/s]) of the actuator model above, advanced by ``step``.

    Parameters
    ----------
    parameters : ActuatorParameters
    angle, velocity : float -- initial state [rad], [rad/s].
    substeps : int -- integration sub-steps per ``step`` call (>= 1).
    """

    def __init__(self, parameters: ActuatorParameters, angle: float = 0.0, velocity: float = 0.0, substeps: int = 4):
        self.parameters = parameters
        self.angle = float(angle)
        self.velocity = float(velocity)
        self.substeps = int(check_range("substeps", substeps, 1, math.inf, high_open=True))

    @property
    def contact_force(self) -> float:
        """Current contact force F(q) [N]."""
        return float(contact_force(self.angle, self.parameters))

    def step(self, torque: float, duration: float, external_torque: float = 0.0) -> float:
        """Hold ``torque`` [N mm] (saturated) for ``duration`` [s] against ``external_torque`` [N mm].

        Returns the contact force [N] at the end of the interval.
        """
        p = self.parameters
        applied = min(max(float(torque), -p.torque_limit), p.torque_limit)
        h = check_positive("duration", duration, "s") / self.substeps
        for _ in range(self.substeps):
            load = p.arm_radius * p.contact_stiffness * max(p.arm_radius * self.angle, 0.0)   # r F [N mm]
            free = self.velocity + h * (applied - load - external_torque) / p.inertia          # no friction [rad/s]
            stop = h * p.coulomb_friction / p.inertia                                          # |friction dv| max
            free = 0.0 if abs(free) <= stop else free - math.copysign(stop, free)
            self.velocity = free / (1.0 + h * p.viscous_friction / p.inertia)                 # implicit viscous
            self.angle += h * self.velocity
        return self.contact_force
