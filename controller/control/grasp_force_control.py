"""Grasp Force Control block (paper Fig. 7, 1 kHz): grasp force from translational and rotational shear displacement.

Inputs per step: the estimated shear displacement u_x [mm] (translation of the contact), the twist angle theta
[rad] (rotation of the contact, paper eq. 9; not the arc length a theta, which would need a), the number of bump
contacts the estimator sees, and the grasp phase. Output: the grasp-force command F [N]. The controller knows
neither mu, nor the object's mass, nor the tangential force or moment.

Law (after the minimum contact force F_min is set), for each channel i in (x, theta), with u_f the low-pass
filtered displacements, u_ref,i(F) from the reference generator and p_i its inversion exponent:

    F_i <- clip(F_i + gamma F (min(|u_f,i| / u_ref,i(F), r_max)^p_i - 1), 0, F_max - F_min),   gamma = lambda T
    F   <- min(F_min + F_x + F_theta, F_max)

Derivation. At a constant load the full-stick laws (paper eqs. 10, 12, 14) give |u_i| / u_ref,i(F) = (F*_i / F)^(1/p_i),
F*_i the force that puts channel i on its reference, so the increment is gamma (F*_i - F): an integral law whose
closed loop is the first-order F_{k+1} = F_k + gamma (F* - F_k), time constant 1/lambda, whatever the operating
point (a plain integral law on u - u_ref would have a gain ~ 1/F). In partial slip |u| grows faster than the
full-stick law as F falls, which raises the loop gain by the logarithmic slope of the Mindlin/Lubkin curves (1.5 at
Q/(mu P) = 0.85, 2.8 at T/(mu P a) = 0.5); ``ReferenceParameters`` divides p_i by that slip factor at the design
point, so the gain is lambda there and lower at any higher friction. lambda T << 1 keeps the discrete loop far from
its limit gamma < 2. The delays in the loop - the filter (1/(2 pi f_c) = 5 ms at 30 Hz) and the force loop (its
slowest mode, 16 ms) - add up to tau_d = 21 ms; with lambda = 30 rad/s the loop L(s) = lambda e^(-s tau_d) / s keeps
a phase margin of 90 deg - lambda tau_d = 53 deg. A faster lambda cuts the lag behind a growing load (ln F lags by
(d ln F*/dt) / lambda), which is what limits how fast an object may be lifted from F_min.
The components are integrators clamped at zero and summed (the paper sums the two grasp forces): the channel that
needs more force settles on its reference while the other one drains to zero, so the sum is the larger requirement,
not twice it. A channel drains only while no channel asks for more force: otherwise, when the moment takes over
from the tangential load, the translational share would drain as fast as the rotational one builds and the sum
would lag.
The low-pass filter (cut-off well above lambda / (2 pi)) suppresses estimator noise.

Minimum contact force: in GRASP the command ramps from the approach force until two bump contacts are reported
(the shear displacement needs two contacts, paper sec. IV); the command at that moment becomes F_min.

Release (hand-over, placing): on entering RELEASE the filtered displacements u_0 and the force F_hold are latched.
The same detection - the change of each displacement from its latched value, relative to it - now lowers the force
(the increase and decrease are switched, paper sec. V):

    F <- max(F - lambda_r F_hold d T, 0),   d = min(1, max_i |u_f,i - u_0,i| / max(|u_0,i|, s u_ref,i(F_hold))),

d = 1 if no channel carried load at the latch (|u_0,i| < s u_ref,i: the object already rests on the table). A
human who takes the weight (or pulls) changes u and the gripper opens in proportion, with no minimum force; if
nobody takes the object, u does not change and the grip is held.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_positive, check_range

from .filters import FirstOrderLowPass, sample_period
from .references import GraspPhase, ReferenceGenerator, ReferenceParameters

__all__ = ["GraspForceParameters", "GraspForceController"]


@dataclass(frozen=True)
class GraspForceParameters:
    """Rates and gains of the Grasp Force Control block.

    Attributes
    ----------
    sample_rate_hz : float -- loop rate f_s [Hz] (1 kHz in the paper), > 0.
    filter_cutoff_hz : float -- cut-off of the shear-displacement low-pass filter [Hz], in (0, f_s/2).
    loop_rate : float -- lambda, the closed-loop rate of the force law in full stick [rad/s]; lambda / f_s <= 0.1.
    release_rate : float -- lambda_r, fraction of the hold force removed per second at full detection [1/s], > 0.
    approach_force : float -- force command in APPROACH and start of the GRASP ramp [N], > 0.
    ramp_rate : float -- force ramp in GRASP until two contacts are seen [N/s], > 0.
    maximum_force : float -- force limit F_max [N], > approach_force.
    ratio_limit : float -- r_max, cap on |u| / u_ref per step (bounds the step on outliers) [-], > 1.
    release_threshold : float -- s, loaded-channel threshold at the release latch, fraction of u_ref [-], (0, 1].
    rotational_slip_detection : bool -- False drops the rotational channel (paper Fig. 10b comparison).
    """

    sample_rate_hz: float = 1000.0
    filter_cutoff_hz: float = 30.0
    loop_rate: float = 30.0
    release_rate: float = 2.0
    approach_force: float = 0.05
    ramp_rate: float = 2.0
    maximum_force: float = 20.0
    ratio_limit: float = 3.0
    release_threshold: float = 0.2
    rotational_slip_detection: bool = True

    def __post_init__(self):
        check_positive("sample_rate_hz", self.sample_rate_hz, "Hz")
        check_range("filter_cutoff_hz", self.filter_cutoff_hz, 0.0, 0.5 * self.sample_rate_hz, "Hz", True, True)
        check_range("loop_rate", self.loop_rate, 0.0, 0.1 * self.sample_rate_hz, "rad/s", low_open=True)
        check_positive("release_rate", self.release_rate, "1/s")
        check_positive("approach_force", self.approach_force, "N")
        check_positive("ramp_rate", self.ramp_rate, "N/s")
        check_range("maximum_force", self.maximum_force, self.approach_force, math.inf, "N", True, True)
        check_range("ratio_limit", self.ratio_limit, 1.0, math.inf, low_open=True, high_open=True)
        check_range("release_threshold", self.release_threshold, 0.0, 1.0, low_open=True)


class GraspForceController:
    """Grasp Force Control block: ``step(u_x, theta, contact_count, phase)`` -> grasp-force command [N].

    State: ``command`` [N], ``minimum_force`` [N] (None until two contacts were seen), ``components`` (F_x, F_theta)
    [N], the filter, and the release latch.

    Parameters
    ----------
    parameters : GraspForceParameters
    references : ReferenceParameters
    """

    def __init__(self, parameters: GraspForceParameters, references: ReferenceParameters):
        self.parameters = parameters
        self.generator = ReferenceGenerator(references)
        self.exponents = np.array(references.inversion_exponents)                       # (p_x, p_theta)
        self.sample_period = sample_period(parameters.sample_rate_hz)
        self.filter = FirstOrderLowPass(parameters.filter_cutoff_hz, parameters.sample_rate_hz, np.zeros(2))
        self.command = parameters.approach_force
        self.minimum_force = None
        self.components = np.zeros(2)
        self._release_latch = None                                                      # (u_0, scale, F_hold)

    def step(self, shear_displacement: float, twist_angle: float, contact_count: int, phase: GraspPhase) -> float:
        """One 1 kHz step: u_x [mm], theta [rad], number of bump contacts, phase -> force command [N]."""
        phase = GraspPhase(phase)
        filtered = self.filter.step([shear_displacement, twist_angle])
        if phase is not GraspPhase.RELEASE:
            self._release_latch = None
        if phase is GraspPhase.APPROACH:
            self.command = self.parameters.approach_force
            self._latch_minimum(contact_count)
        elif phase is GraspPhase.RELEASE:
            self._release(filtered)
        elif self.minimum_force is None:
            if not self._latch_minimum(contact_count):
                self.command = min(self.command + self.parameters.ramp_rate * self.sample_period,
                                   self.parameters.maximum_force)
        else:
            self._regulate(filtered, self.generator.references(phase, self.command))
        return self.command

    def _latch_minimum(self, contact_count: int) -> bool:
        """Set F_min to the current command the first time two contacts are seen; True once it is set."""
        if self.minimum_force is None and contact_count >= 2:
            self.minimum_force = self.command
            self.components = np.zeros(2)
        return self.minimum_force is not None

    def _regulate(self, filtered: np.ndarray, references) -> None:
        """The grasp law of the module docstring (scalar arithmetic: it runs at 1 kHz)."""
        p = self.parameters
        gamma = p.loop_rate * self.sample_period
        changes = []
        for value, reference, exponent in zip(filtered.tolist(), references, self.exponents.tolist()):
            ratio = min(abs(value) / reference, p.ratio_limit)
            changes.append(gamma * self.command * (ratio**exponent - 1.0))
        if not p.rotational_slip_detection:
            changes[1] = 0.0                            # the channel is off: it neither adds force nor blocks draining
        if changes[0] > 0.0 or changes[1] > 0.0:
            changes = [max(change, 0.0) for change in changes]   # no channel drains while another asks for more force
        upper = p.maximum_force - self.minimum_force
        components = [min(max(float(component) + change, 0.0), upper)
                      for component, change in zip(self.components, changes)]
        self.components = np.array(components)
        self.command = min(self.minimum_force + components[0] + components[1], p.maximum_force)

    def _release(self, filtered: np.ndarray) -> None:
        """The release law of the module docstring (no minimum force)."""
        p = self.parameters
        if self._release_latch is None:
            scale = p.release_threshold * np.asarray(self.generator.references(GraspPhase.HOLD, self.command))
            if not p.rotational_slip_detection:
                scale[1] = math.inf                                                     # channel ignored
            self._release_latch = (filtered.copy(), scale, self.command)
        latched, scale, hold_force = self._release_latch
        loaded = np.abs(latched) >= scale
        if loaded.any():
            change = np.abs(filtered - latched)[loaded] / np.abs(latched)[loaded]
            detection = min(1.0, float(change.max()))
        else:
            detection = 1.0
        self.command = max(self.command - p.release_rate * hold_force * detection * self.sample_period, 0.0)
