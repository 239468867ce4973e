"""Closed-form contact plant of one Hertz fingertip (hemisphere) under a tangential force and a moment.

The single-hemisphere plant the grasp controller is tested against without MuJoCo (contact.reduced models the 3x3
array fingertip of the closed loop and shares its Lubkin table).

Model (contact.theory, docs/theory.md, secs. 4.4 and 6.3), rigid object on an elastic hemisphere (R, E, nu):
    contact radius  a(P) from Hertz with E* = E / (1 - nu^2),
    shear displacement u_x = Mindlin shift: 3 mu P (2 - nu) / (16 G a) [1 - (1 - Q/(mu P))^(2/3)]  [mm],
    twist angle theta = Lubkin twist at torque T                                                  [rad],
each mode on its own (the combined partial-slip problem is not in the theory; its gross-slip limit is tighter than
either mode alone). Gross slip: Q >= mu P or T >= (3 pi / 16) mu P a; the plant then latches ``slipped`` and reports
``SLIP_DISPLACEMENT_FACTOR`` times the reference scale of the mode, which keeps growing load ratios visible to the
controller without an infinite value.

The Lubkin twist is tabulated once in dimensionless form (``contact.reduced.normalized_lubkin_twist``, shared with
the reduced array model): ``lubkin_twist`` costs milliseconds per call, too slow for a 1 kHz loop over seconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from contact.reduced import normalized_lubkin_torque, normalized_lubkin_twist
from contact.reduced._bumps import _TORQUE_RATIOS
from contact.theory import effective_modulus, hertz, mindlin_shift, shear_modulus

SLIP_TORQUE_RATIO = 3.0 * math.pi / 16.0          # full-slip torque / (mu P a), Lubkin
SLIP_DISPLACEMENT_FACTOR = 3.0                     # reported displacement in gross slip / slip scale [-]

__all__ = ["SLIP_TORQUE_RATIO", "HertzFingertip", "ClosedFormContactPlant", "normalized_lubkin_twist",
           "normalized_lubkin_torque", "slip_factors"]


@dataclass(frozen=True)
class HertzFingertip:
    """Urethane-gel hemisphere and the (unknown to the controller) friction; the bump-contact threshold.

    radius [mm], youngs_modulus [MPa], poissons_ratio [-], friction_coefficient [-],
    second_contact_force [N]: normal force at which the estimator sees a second bump contact (the object is not
    exactly parallel to the array, so the bumps touch one after the other).
    """

    radius: float = 8.0
    youngs_modulus: float = 0.5
    poissons_ratio: float = 0.45
    friction_coefficient: float = 0.8
    second_contact_force: float = 0.3

    @property
    def effective_modulus(self) -> float:
        return float(effective_modulus(self.youngs_modulus, self.poissons_ratio))

    @property
    def shear_modulus(self) -> float:
        return float(shear_modulus(self.youngs_modulus, self.poissons_ratio))

    def contact_radius(self, normal_force):
        """Hertz contact radius a [mm] at P [N]."""
        return hertz(normal_force, self.radius, self.effective_modulus).contact_radius

    def translational_scale(self, normal_force, friction_coefficient=None):
        """Gross-slip shift delta_slip = 3 mu P (2 - nu) / (16 G a) [mm]."""
        mu = self.friction_coefficient if friction_coefficient is None else friction_coefficient
        return 3.0 * mu * normal_force * (2.0 - self.poissons_ratio) / (
            16.0 * self.shear_modulus * self.contact_radius(normal_force))

    def rotational_scale(self, normal_force, friction_coefficient=None):
        """Twist scale mu P / (G a^2) [rad]: theta = scale * normalized_lubkin_twist(T / (mu P a))."""
        mu = self.friction_coefficient if friction_coefficient is None else friction_coefficient
        return mu * normal_force / (self.shear_modulus * self.contact_radius(normal_force) ** 2)

    def minimum_normal_force(self, tangential_force, torque):
        """Least P [N] with Q < mu P and T < (3 pi/16) mu P a(P) (each mode alone; a ~ P^(1/3) from Hertz)."""
        mu = self.friction_coefficient
        radius_per_force = float(self.contact_radius(1.0))                     # a(P) = a(1 N) P^(1/3)
        rotational = (torque / (SLIP_TORQUE_RATIO * mu * radius_per_force)) ** 0.75
        return max(tangential_force / mu, rotational)

    def references(self, load_ratio, torque_ratio, friction_coefficient, reference_force=1.0):
        """Shear targets (u_x [mm], theta [rad]) at ``reference_force`` that put the contact at Q/(mu P) =
        load_ratio and T/(mu P a) = torque_ratio for the friction ``friction_coefficient`` (a design value)."""
        u_x = self.translational_scale(reference_force, friction_coefficient) * (
            1.0 - (1.0 - load_ratio) ** (2.0 / 3.0))
        theta = self.rotational_scale(reference_force, friction_coefficient) * normalized_lubkin_twist(torque_ratio)
        return float(u_x), float(theta)


def slip_factors(load_ratio, torque_ratio):
    """Logarithmic slopes x h'(x)/h(x) (Mindlin, h = 1 - (1 - x)^(2/3)) and y f'(y)/f(y) (Lubkin twist f) [-]."""
    mindlin = load_ratio * (2.0 / 3.0) * (1.0 - load_ratio) ** (-1.0 / 3.0) / (1.0 - (1.0 - load_ratio) ** (2.0 / 3.0))
    step = 1e-4 * torque_ratio                                       # central difference on the interpolated curve
    twist = np.log(normalized_lubkin_twist(np.array([torque_ratio - step, torque_ratio + step])))
    slope = twist[1] - twist[0]
    return float(mindlin), float(slope / (np.log(torque_ratio + step) - np.log(torque_ratio - step)))


class ClosedFormContactPlant:
    """What the estimator would report for the fingertip under the loads Q(t) [N], T(t) [N mm] at normal force P.

    ``sense(time, normal_force) -> (u_x [mm], theta [rad], contact_count)``; ``slipped`` latches gross slip per mode.
    """

    def __init__(self, fingertip: HertzFingertip, tangential_force, torque):
        self.fingertip = fingertip
        self.tangential_force = tangential_force           # callable time [s] -> Q [N]
        self.torque = torque                               # callable time [s] -> T [N mm]
        self.slipped = {"translational": False, "rotational": False}

    def sense(self, time: float, normal_force: float):
        tip = self.fingertip
        if normal_force <= 0.0:
            return 0.0, 0.0, 0
        count = 2 if normal_force >= tip.second_contact_force else 1
        mu = tip.friction_coefficient
        a = float(tip.contact_radius(normal_force))
        q, t = self.tangential_force(time), self.torque(time)
        if q >= mu * normal_force:
            self.slipped["translational"] = True
            u_x = SLIP_DISPLACEMENT_FACTOR * tip.translational_scale(normal_force)
        else:
            u_x = float(mindlin_shift(q, normal_force, mu, a, tip.shear_modulus, tip.poissons_ratio))
        torque_ratio = t / (mu * normal_force * a)
        if torque_ratio >= SLIP_TORQUE_RATIO:
            self.slipped["rotational"] = True
            torque_ratio = _TORQUE_RATIOS[-1]
        theta = tip.rotational_scale(normal_force) * float(normalized_lubkin_twist(torque_ratio))
        return u_x, theta, count
