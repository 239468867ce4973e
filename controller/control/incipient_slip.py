"""Incipient-slip grasp control: hold the array a margin below the friction limit that the sensor itself finds.

Inputs per sensor frame (``observe``, 100 Hz), for each fingertip and bump i in contact: the estimated bump force
P_i [N] and load-ratio vector rho_i ~ Q_i / P_i [-] (what the FEM-calibrated fingertip's base pressure carries: the
bump's overturning couple; ``controller.closed_loop`` sensing). Output per control step (``step``, 1 kHz): the grasp
force command [N]. The controller never sees the friction coefficient, the object's mass or moment, or which bumps
slide: it learns what it needs from how the signals answer its own force.

Demand. The bumps' tangential loads q_i = P_i rho_i add up to the load the fingertip carries, a force F_t and a
moment T about the array centre. With a friction estimate mu_hat the array slides as a whole when (F_t, T) reaches
the limit set of its bumps (``array_margin``: Coulomb point contacts, the array's combined force-torque limit, as
``contact.reduced`` computes it); its margin lambda* grows in proportion to the grip (the bump forces scale with
it, the load does not), so the grip that leaves the margin 1 / s is

    F_need = F / (s lambda*(mu_hat)),

on the more loaded fingertip. Without rotational detection only the translational part is used,
F_need = |F_t| / (s mu_hat): blind to the moment. The command tracks F_need with rate lambda (faster upwards),
never below the minimum contact force F_min.

Friction estimate: probe and watch. Before any slip was seen mu_hat is ``prior_friction``, the lowest friction the
gripper is designed for, with a wider margin (``lift_safety_fraction``: the load grows in the lift faster than the
grip follows). In HOLD the reference generator probes: it raises mu_hat by ``probe_rate`` per second (the grip falls
the same way) while it watches how each loaded bump's load ratio answers its falling normal force over the last
``watch_frames`` frames. A stuck bump keeps its load (equilibrium fixes it; its share moves with its stiffness,
~ P_i^(1/3), when the normal forces redistribute), so its ratio rises at least like P_i^-(2/3); a bump on its
friction limit keeps |rho_i| = mu while P_i falls: when P_i has fallen by ``force_drop`` over the window and
|rho_i| plus its noise margin rose less than P_i^-``stick_exponent`` (just under the stuck bound 2/3, so that
the gap between the two, ~8 % of |rho_i| over a 25-frame window of the probe, clears the noise margin), for
``confirm_frames`` frames, that bump slides. Its ratio |rho_i|
is then the friction coefficient of this object measured in hand: mu_hat takes it, the probe ends and the grip
steps up at once to the demand at s mu_hat. Under a moment the bumps far from the array's slip centre slide first
while the others hold (incipient rotational slip). Under pure weight all slide together, which shows sooner in the
total tangential load of both fingertips (in one frame): equilibrium keeps it constant while the object holds, and a
fall by ``total_drop`` together with the normal force is the grasp sliding as a whole (its most loaded bumps are
then on their limit: mu_hat is their ratio). After the probe the total load is still watched: a gross slip seen
later (the load grew, or mu_hat was too high) lowers mu_hat and steps the grip up again. Single bumps are judged
only while the grip is probed down: at a held grip a bump's force changes only as the normal forces redistribute,
not as the controller asks.

Placing and releasing: in PLACE the demand falls as the table takes the load; in RELEASE the force falls at
``release_rate`` of the hold force per second in proportion to how far the load has left the fingertips (at once if
none was carried), as the displacement-target law does (``GraspForceController``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_positive, check_range

from ._slip_kernels import array_margin, fingertip_need, low_pass_frame, slip_signature
from .filters import sample_period, tustin_gain
from .references import GraspPhase

FULL_SEARCH_EVERY = 10              # frames between full searches of the array's slip centre (warm starts between)
# a bump's ratio must rise less than a stuck bump's by this many of its estimate's standard deviations (raw, per frame;
# the slow watch filter and the window's difference leave about 0.6 of it): 3 x 0.6 ~ 2 sigma of the compared values,
# the largest of some 18 bumps over a few frames
NOISE_MARGIN = 3.0

__all__ = ["IncipientSlipParameters", "IncipientSlipController", "array_margin"]


@dataclass(frozen=True)
class IncipientSlipParameters:
    """Rates, margins, probe and slip watch of the incipient-slip controller.

    Attributes
    ----------
    sample_rate_hz : float -- control rate [Hz] (1 kHz in the paper).
    frame_rate_hz : float -- sensor frame rate [Hz] (``observe`` calls), <= sample_rate_hz.
    filter_cutoff_hz : float -- low-pass cut-off on the per-bump signals for the demand [Hz], < frame_rate_hz / 2.
    watch_cutoff_hz : float -- low-pass cut-off on the signals the slip watch compares [Hz] (slower: the watch
        looks at many bumps, so their noise must stay well below ``force_drop``).
    loop_rate, release_loop_rate : float -- rate at which the command follows a rising / falling demand [rad/s].
    safety_fraction : float -- s: the grip holds the array's load at s of its slip limit at mu_hat [-], (0, 1).
    lift_safety_fraction : float -- the same before a slip was seen, with mu_hat the prior [-], (0, 1).
    prior_friction : float -- friction estimate before a slip was seen (lowest expected) [-], > 0.
    maximum_friction : float -- highest friction the probe believes (it stops there) [-], > prior_friction.
    probe_rate : float -- relative rise of the friction estimate per second while probing [1/s], > 0.
    probe_delay : float -- time in HOLD before the probe starts (the lift's signals settle) [s], >= 0.
    total_drop : float -- fall of a fingertip's total tangential load and normal force from where the watch began
        that means gross slip [-], (0, 1).
    watch_frames : int -- window over which a bump's ratio is compared with its normal force [frames], >= 2.
    force_drop : float -- fall of a bump's normal force over the window before its ratio is judged [-], (0, 1).
    stick_exponent : float -- a stuck bump's ratio rises at least like P_i^-(1 - 1/3) as P_i falls (its load
        is fixed; its share moves like P_i^(1/3) at most); a bump whose ratio rose less than P_i^-this over the
        window slides [-], (0, 1). Just under 2/3: at 0.3 a sliding bump's flat ratio sat only ~2 % of |rho_i|
        below the bound over 15 frames, less than the noise margin, and a rotation went unseen until the object
        turned out of the grasp (Table I: 1 drop and 3 crushes in 90 trials, none with 0.6 over 25 frames).
    confirm_frames : int -- consecutive frames the slip signature must last, >= 1.
    loaded_share : float -- bumps carrying at least this share of the largest load are watched [-], (0, 1].
    force_share : float -- and at least this share of the mean bump force [-], [0, 1].
    approach_force, ramp_rate, maximum_force : float -- as in ``GraspForceParameters`` [N], [N/s], [N].
    release_rate : float -- fraction of the hold force removed per second in RELEASE [1/s].
    rotational_slip_detection : bool -- False: only the translational load is used and watched.
    """

    sample_rate_hz: float = 1000.0
    frame_rate_hz: float = 100.0
    filter_cutoff_hz: float = 15.0
    watch_cutoff_hz: float = 5.0
    loop_rate: float = 40.0
    release_loop_rate: float = 10.0
    safety_fraction: float = 0.85
    lift_safety_fraction: float = 0.7
    prior_friction: float = 0.4
    maximum_friction: float = 2.0
    probe_rate: float = 0.5
    probe_delay: float = 0.5
    total_drop: float = 0.03
    watch_frames: int = 25
    force_drop: float = 0.04
    stick_exponent: float = 0.6
    confirm_frames: int = 3
    loaded_share: float = 0.5
    force_share: float = 0.25
    approach_force: float = 0.5
    ramp_rate: float = 2.0
    maximum_force: float = 30.0
    release_rate: float = 2.0
    rotational_slip_detection: bool = True

    def __post_init__(self):
        check_positive("sample_rate_hz", self.sample_rate_hz, "Hz")
        check_range("frame_rate_hz", self.frame_rate_hz, 0.0, self.sample_rate_hz, "Hz", low_open=True)
        for name in ("filter_cutoff_hz", "watch_cutoff_hz"):
            check_range(name, getattr(self, name), 0.0, 0.5 * self.frame_rate_hz, "Hz", True, True)
        check_range("loop_rate", self.loop_rate, 0.0, 0.1 * self.sample_rate_hz, "rad/s", low_open=True)
        check_range("release_loop_rate", self.release_loop_rate, 0.0, self.loop_rate, "rad/s", low_open=True)
        for name in ("safety_fraction", "lift_safety_fraction", "force_drop", "total_drop", "stick_exponent"):
            check_range(name, getattr(self, name), 0.0, 1.0, low_open=True, high_open=True)
        check_positive("prior_friction", self.prior_friction)
        check_range("maximum_friction", self.maximum_friction, self.prior_friction, math.inf, low_open=True,
                    high_open=True)
        check_positive("probe_rate", self.probe_rate, "1/s")
        check_range("probe_delay", self.probe_delay, 0.0, math.inf, "s", high_open=True)
        if isinstance(self.confirm_frames, bool) or not isinstance(self.confirm_frames, int) or \
                self.confirm_frames < 1:
            raise ValueError(f"confirm_frames={self.confirm_frames!r} must be an integer >= 1")
        if isinstance(self.watch_frames, bool) or not isinstance(self.watch_frames, int) or self.watch_frames < 2:
            raise ValueError(f"watch_frames={self.watch_frames!r} must be an integer >= 2")
        check_range("loaded_share", self.loaded_share, 0.0, 1.0, low_open=True)
        check_range("force_share", self.force_share, 0.0, 1.0)
        check_positive("approach_force", self.approach_force, "N")
        check_positive("ramp_rate", self.ramp_rate, "N/s")
        check_range("maximum_force", self.maximum_force, self.approach_force, math.inf, "N", True, True)
        check_positive("release_rate", self.release_rate, "1/s")
        if not isinstance(self.rotational_slip_detection, bool):
            raise ValueError(f"rotational_slip_detection={self.rotational_slip_detection!r} must be True or False")


class _History:
    """Ring buffer of the slip watch: bump forces and |rho_i| (watch_frames, 2, k) and how many were written."""

    def __init__(self, frames: int, count: int):
        self.force, self.ratios, self.count = np.zeros((frames, 2, count)), np.zeros((frames, 2, count)), 0


class _Filtered:
    """Low-passed bump forces (2, k) [N] and load ratios (2, k, 2) [-] with their previous inputs."""

    def __init__(self, gain: float, count: int):
        self.gain = gain
        self.force, self.previous_force = np.zeros((2, count)), np.zeros((2, count))
        self.ratio, self.previous_ratio = np.zeros((2, count, 2)), np.zeros((2, count, 2))


class IncipientSlipController:
    """The law of the module docstring: ``observe(bump_force, load_ratio, in_contact)`` at each sensor frame,
    ``step(phase)`` at the control rate -> grasp-force command [N].

    State: ``command`` [N], ``minimum_force`` [N] (None until two contacts), ``friction_estimate`` mu_hat [-],
    ``probing`` / ``slip_seen`` flags, ``need`` [N] (F / lambda*(mu = 1) of the more loaded fingertip: the grip
    at which it would slide at mu = 1), ``slip_events`` ((time [s], mu_hat) at each detection).

    Parameters
    ----------
    parameters : IncipientSlipParameters
    centres : (k, 2) float -- bump centres on the sensor plane [mm] (the fingertip design; the same for both).
    second_frame : (2,) float -- signs that turn the second fingertip's sensor axes (x, y) into the first's: the
        gripper's geometry; (1, -1) for two fingertips facing each other with a common x axis.
    """

    def __init__(self, parameters: IncipientSlipParameters, centres, second_frame=(1.0, -1.0)):
        self.parameters = parameters
        self.centres = np.ascontiguousarray(centres, dtype=float)
        self.second_frame = np.asarray(second_frame, dtype=float)
        if self.second_frame.shape != (2,) or not np.all(np.abs(self.second_frame) == 1.0):
            raise ValueError(f"second_frame={second_frame!r} must be two signs (+-1, +-1)")
        self.period = sample_period(parameters.sample_rate_hz)
        self.command = parameters.approach_force
        self.minimum_force = None
        self.friction_estimate = parameters.prior_friction
        self.probing = False
        self.slip_seen = False
        self.need = 0.0
        self.time = 0.0
        self.slip_events = []
        count = len(self.centres)
        self._signals = _Filtered(tustin_gain(parameters.filter_cutoff_hz, parameters.frame_rate_hz), count)
        self._watched = _Filtered(tustin_gain(parameters.watch_cutoff_hz, parameters.frame_rate_hz), count)
        self._started = False
        self._contact = np.zeros((2, len(self.centres)), dtype=bool)
        self._contacts = 0                                 # bumps in contact on the fingertip that sees more
        self._ratio_noise = np.zeros((2, len(self.centres)))
        self._plateau = np.full(2, -1.0)                 # (|total load|, sum P) when the watch began (-1: not yet)
        self._history = _History(parameters.watch_frames, len(self.centres))     # (P_i, |rho_i|) of the last frames
        self._watching = False
        self._probe_begun = False
        self._streak = np.zeros((2, len(self.centres) + 1), dtype=int)      # frames each bump / total has slid
        self._hold_time = 0.0
        self._release = None
        self._frames = 0
        self._slip_centre = np.full((2, 2), math.inf)     # each fingertip's last slip centre [mm] (warm starts)
        self._reach = float(np.hypot(self.centres[:, 0], self.centres[:, 1]).max())

    # --- sensor frames (100 Hz) ---------------------------------------------------------------------------
    def observe(self, bump_force, load_ratio, in_contact, ratio_noise=None) -> None:
        """Take a sensor frame: bump forces (2, k) [N], load-ratio estimates (2, k, 2) [-], in-contact (2, k), and
        the standard deviation of each ratio estimate (2, k) [-] if the sensor gives it (None: noise-free)."""
        self._ratio_noise = np.zeros(self._contact.shape) if ratio_noise is None else \
            np.asarray(ratio_noise, dtype=float)
        contact = np.asarray(in_contact, dtype=np.bool_)
        fast, slow = self._signals, self._watched
        restart = not self._started or bool(np.any(contact & ~self._contact))   # a new contact: start afresh
        self._started, self._contact = True, contact
        self._contacts = int(contact.sum(axis=1).max())
        low_pass_frame(fast.gain, np.asarray(bump_force, dtype=float), np.asarray(load_ratio, dtype=float), contact,
                       fast.previous_force, fast.previous_ratio, fast.force, fast.ratio, restart)
        low_pass_frame(slow.gain, fast.force, fast.ratio, contact, slow.previous_force, slow.previous_ratio,
                       slow.force, slow.ratio, restart)
        self._frames += 1
        full = self._frames % FULL_SEARCH_EVERY == 0
        self.need = fingertip_need(self.centres, fast.force, fast.ratio, contact,
                                   self.parameters.rotational_slip_detection, self._slip_centre, full,
                                   0.1 * self._reach)
        if self._watching:
            self._watch(slow.force, slow.ratio, contact)

    def _watch(self, force, ratio, contact) -> None:
        """The slip watch of the module docstring, on the slowly filtered signals (``slip_signature``)."""
        p = self.parameters
        hold_ratio = p.safety_fraction * self.friction_estimate if self.slip_seen else 0.0
        history = self._history
        filled = history.count >= history.force.shape[0]
        judged = p.rotational_slip_detection and self.probing and filled
        oldest = history.count % history.force.shape[0]                 # the slot the newest frame will take
        signature, total_ratio, bearing, ratios = slip_signature(
            force, ratio, contact, history.force[oldest], history.ratios[oldest], judged, self._plateau,
            self.second_frame, hold_ratio, p.total_drop, p.force_drop, p.stick_exponent, p.loaded_share,
            p.force_share, NOISE_MARGIN * self._ratio_noise)
        history.force[oldest], history.ratios[oldest] = force, ratios
        history.count += 1
        self._streak = np.where(signature, self._streak + 1, 0)
        if self._streak.max() < p.confirm_frames:
            return
        f, index = np.unravel_index(int(np.argmax(self._streak)), self._streak.shape)
        # the grasp slid as a whole: its most loaded bumps are on their limit (under a moment the translational
        # ratio is lower: a rotation); a single bump: its own ratio
        measured = max(total_ratio, bearing) if index == len(self.centres) else float(ratios[f, index])
        self.friction_estimate = min(self.friction_estimate, measured) if self.slip_seen else measured
        self.slip_seen, self.probing = True, False
        self.slip_events.append((self.time, self.friction_estimate))
        self.command = min(max(self.command, self._target()), p.maximum_force)                # step up now
        self._start_watch()

    def _start_watch(self) -> None:
        """(Re)start the watch: no plateau, no history, no streaks."""
        self._plateau[:] = -1.0
        self._history.count = 0
        self._streak[:] = 0

    # --- control steps (1 kHz) ----------------------------------------------------------------------------
    def _target(self) -> float:
        p = self.parameters
        fraction = p.safety_fraction if (self.slip_seen or self.probing) else p.lift_safety_fraction
        return self.need / (fraction * self.friction_estimate)

    def step(self, phase: GraspPhase) -> float:
        """One control step in ``phase`` -> grasp-force command [N]."""
        p = self.parameters
        self.time += self.period
        if not isinstance(phase, GraspPhase):
            phase = GraspPhase(phase)
        if phase is not GraspPhase.RELEASE:
            self._release = None
        if phase is not GraspPhase.HOLD and self._hold_time > 0.0:
            self._hold_time, self.probing, self._watching, self._probe_begun = 0.0, False, False, False
            self._start_watch()
        contacts = self._contacts
        if phase is GraspPhase.APPROACH:
            self.command = p.approach_force
            self._latch_minimum(contacts)
        elif phase is GraspPhase.RELEASE:
            self._release_step()
        elif self.minimum_force is None:
            if not self._latch_minimum(contacts):
                self.command = min(self.command + p.ramp_rate * self.period, p.maximum_force)
        else:
            if phase is GraspPhase.HOLD:
                self._hold_step()
            target = min(max(self._target(), self.minimum_force), p.maximum_force)
            rate = p.loop_rate if target > self.command else p.release_loop_rate
            self.command += rate * self.period * (target - self.command)
        return self.command

    def _hold_step(self) -> None:
        """Start the watch one window before the probe delay; probe (raise mu_hat) until a slip is seen."""
        p = self.parameters
        self._hold_time += self.period
        # the watch starts one window before the probe, so that its window is full when the grip begins to fall
        # (else the first window of the probe, 0.25 s and 13 % of mu_hat, goes by unwatched)
        if not self._watching and self._hold_time >= p.probe_delay - p.watch_frames / p.frame_rate_hz:
            self._watching = True
        if self._hold_time < p.probe_delay:
            return
        if not self._probe_begun:
            self._probe_begun, self.probing = True, not self.slip_seen
        if self.probing:
            self.friction_estimate = min(self.friction_estimate * math.exp(p.probe_rate * self.period),
                                         p.maximum_friction)

    def _latch_minimum(self, contacts: int) -> bool:
        if self.minimum_force is None and contacts >= 2:
            self.minimum_force = self.command
        return self.minimum_force is not None

    def _release_step(self) -> None:
        """Lower the force once the tangential load leaves the fingertips (or at once if none was carried)."""
        p = self.parameters
        if self._release is None:
            self._release = (self.need, self.command)
        need_start, hold_force = self._release
        change = 1.0 if need_start <= 0.0 else min(1.0, abs(self.need - need_start) / need_start)
        self.command = max(self.command - p.release_rate * hold_force * change * self.period, 0.0)
