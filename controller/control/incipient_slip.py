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

on the more used fingertip (the larger nu = 1 / lambda*(1)), F that fingertip's sensed normal force in the force
loop's scale by its own factor (the command over its sensed force, each averaged over ``SCALE_TIME``): both fingertips
carry one grip, but each estimator reads it with its own error, and a factor shared by the two jumped when the more
used fingertip changed (docs/design.md sec. 12). Without rotational detection only the translational part is used,
F_need = |F_t| / (s mu_hat): blind to the moment. The command tracks F_need with rate lambda (faster upwards),
never below the minimum contact force F_min.

Friction estimate: probe and watch. Before any slip was seen mu_hat is ``prior_friction``, the lowest friction the
gripper is designed for, with a wider margin (``lift_safety_fraction``: the load grows in the lift faster than the grip
follows). From ``probe_delay`` after the lift's start (through the rest of the lift and the hold) the law probes: it
raises mu_hat by ``probe_rate`` per second (the grip falls the same way) while it watches how each loaded bump's load
ratio answers its falling normal force over the last ``watch_frames`` frames. A stuck bump keeps its load (equilibrium
fixes it; its share moves with its stiffness, ~ P_i^(1/3), when the normal forces redistribute), so its ratio rises at
least like P_i^-(2/3); a bump on its friction limit keeps |rho_i| = mu while P_i falls: when P_i has fallen by
``force_drop`` over the window and |rho_i| plus its noise margin rose less than P_i^-``stick_exponent`` (just under the
stuck bound 2/3, so that the gap between the two, ~8 % of |rho_i| over a 25-frame window of the probe, clears the noise
margin), for ``confirm_frames`` frames, that bump slides. Once two bumps of one fingertip slide, the ratio |rho_i| that
two of them reach (the second largest) is the friction coefficient of this object measured in hand: each sliding bump
sits at mu, but each reading carries the estimator's own error for that bump (its model is not the plant's), and the
largest of several readings over-reads mu - a hold whose margin that eats lets the object creep. mu_hat takes it, the
probe ends and the grip steps up at once to the demand at s mu_hat. Under a moment the bumps far from the array's slip
centre slide first while the others hold (incipient rotational slip). Under pure weight all slide together, which shows
sooner in the total tangential load of both fingertips (in one frame): equilibrium keeps it constant while the object
holds, and a fall by ``total_drop`` together with the normal force is the grasp sliding as a whole (at its limit the
array's utilisation nu is mu: mu_hat takes it). After the probe the total load is still watched: a gross slip seen later
(the load grew, or mu_hat was too high) lowers mu_hat and steps the grip up again. Each test's margin is its signal's
noise (the sensor's rest calibration); with ``swing_margin``, once the probe's window lies in the probe, it is at least
that many times the signal's rms spread about its trend over the window (a bump's without its newest frames, the
confirmation's and one, which the onset of its slide bends): a held object rocks in the compliant fingers and its loads
swing with it by several per cent, which the tests read as a load that fell with the grip - a friction read low. Off by
default: it reads the friction closer and grips less, but waits longer for a slip that looks like a swing, and fewer
objects are held (docs/design.md sec. 12). Single bumps are judged only while the grip is probed down: at a held grip a
bump's force changes only as the normal forces redistribute, not as the controller asks. A probe whose bump test cannot
be relied on to see a bump slide does not start: over a window the probe opens a gap of |rho_i| (exp(``stick_exponent``
``probe_rate`` window) - 1) between a stuck bump's ratio and a sliding one's; where neither fingertip has two watched
bumps whose noise margin lies below that gap (a light object: small tangential loads per bump against the sensor's
noise), a sliding bump is flagged only if its read ratio happens to fall as the loads shift, and where it was not, the
probe ran on through incipient slip until the grasp slid as a whole. The grip then stays where the lift left it, at
mu_hat = ``prior_friction`` with the lift's margin: more grip, the friction not measured (docs/design.md, sec. 12).
Where no lift test ran, that grip is tested once, as the lift's test does (below), with a step sized to the
utilisation's noise: a grasp sliding at a friction the sensor reads at the lift's level asks, like a held one, for the
grip it has. Without rotational detection the bump test is not used; that probe starts as before and watches the total
alone.

Lift test (once per lift, before any slip was seen). Below the lift's level (mu_hat x ``lift_safety_fraction``) sliding
bumps carry only mu of the grip, so the demand never asks for more and the grip stays where it is - at the contact
minimum, where the utilisation's noise is several times the lift's stall threshold and its stall test cannot see. Where
that test is blind (its noise margin more than twice ``STALL_RISE``) or does not judge at all (a grip at the contact
minimum: on a quiet array the margin is narrow there, and an object sliding at that grip was watched by neither test), a
utilisation that has sat below the level for a window, neither rising nor falling, is tested: the grip steps up by half
(``_lift_test.LIFT_STEP``) and is held there for a window. Held, the load stays and nu falls like 1 / P; sliding, the
load follows the grip and nu stays: halfway between is the verdict (no margin towards 'held', docs/design.md sec. 12).
Sliding marks the array's slip (mu_hat = nu, the grip steps up as after any slip); held lets the grip back to its
demand. A step the sensed grip does not follow (at the contact minimum the estimated force resolves it poorly) gives no
verdict, and no verdict is not 'held': after a whole window without one the grip steps up again (up to the actuator's
limit, where the test ends; the probe waits while a test holds its step). The step is the safe direction. Just above the
level the same blindness hides a slide the other way: bumps that slide at a friction a little above the level keep nu at
mu, so the demand asks only mu / level more than the grip and the grip creeps up while the object slides (a bottle at mu
0.32 slid 35 mm in the lift). A grip that grew by ``_lift_test.LIFT_GROWTH`` over the window while nu sat still at the
level or above is tested the same way (its reference grip is the command in the sensed scale: the slowly filtered grip
lags a growing one, and the lag would pass for a rise) - wherever it is seen, not only where the stall test is blind: nu
'still' within the larger of its noise margin and twice ``STALL_RISE`` of nu (a margin between one and two STALL_RISE
leaves the stall test nothing to pass, yet did not count as blind), and where the stall test could have judged, with a
step sized to nu's noise as for an asked test (half took light eclairs whose moment was still coming on past their crush
force). A slip confirmed while such a step is held (this test's or an asked test's) reads the larger of nu at the step
and nu at the verdict: the test began where nu sat at the level, and a few frames into the verdict nu already falls as
the grip catches. After a slip seen in the lift, while the array still slides, the demand grows from the command at nu =
mu_hat rather than from the slowly filtered grip at the nu it reads: that filter keeps the object's swing out of the
demand, but it lags a grip that must grow several-fold, and an array that slides is at its limit whatever it reads (an
estimator whose scale error changes with the force reads it below the mu_hat its slip set). It still slides while its nu
does not fall with the growing grip - halfway between held and sliding, as the lift's test - over the last
``SLIDE_WINDOW`` of the fast signals, or, where the grip grew too little there for a verdict, over the window of the
slow ones once that lies after the fast test's last 'held'; with no verdict, while nu reads at least mu_hat.

A lift's grip pinned at the actuator's limit (``maximum_force``) is not judged by the lift's stall test: a load still
coming on keeps nu where it is at a grip that cannot follow, held or sliding alike. The probe, later, finds the
friction.

Placing and releasing: in PLACE the demand falls as the table takes the load, and never rises above the hold's
command (an object that slid down in the grasp meets the table early, and the fingers that slide along it as the arm
goes on down carry mu of any grip: a load that follows the grip, not one to hold); in RELEASE the force falls at
``release_rate`` of the hold force per second in proportion to how far the load has left the fingertips (at once if
none was carried), as the displacement-target law does (``GraspForceController``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_positive, check_range

from ._slip_kernels import array_margin
from ._slip_law import control_step, observe_frame
from ._slip_state import (PHASE_CODES, P_APPROACH_FORCE, P_CONFIRM_FRAMES, P_FAST_GAIN, P_FORCE_DROP, P_FORCE_SHARE,
                          P_FULL_SEARCH_EVERY, P_GROSS_FRAMES, P_LIFT_SAFETY, P_LOADED_SHARE, P_LOOP_RATE,
                          P_MAXIMUM_FORCE, P_MAXIMUM_FRICTION, P_NOISE_MARGIN, P_PERIOD, P_PRIOR_FRICTION,
                          P_PROBE_DELAY, P_PROBE_RATE, P_RAMP_RATE, P_REACH, P_RELEASE_LOOP_RATE, P_RELEASE_RATE,
                          P_ROTATIONAL, P_SAFETY, P_SCALE_GAIN, P_SIZE, P_SLIDE_FRAMES, P_SLOW_GAIN, P_STALL_FRACTION,
                          P_STALL_RISE, P_STICK_EXPONENT, P_SWING_MARGIN, P_TOTAL_DROP, P_WARM_STEP, P_WATCH_TIME,
                          SLIP_KINDS, X_COMMAND, X_FRICTION, X_MINIMUM, X_NEED, X_PROBING, X_SIZE, X_SLIP_SEEN, X_TIME)
from .filters import sample_period, tustin_gain
from .references import GraspPhase

FULL_SEARCH_EVERY = 10              # frames between full searches of the array's slip centre (warm starts between)
# a bump's ratio must rise less than a stuck bump's by this many standard deviations of the compared difference
# (two slowly filtered values); two bumps of a fingertip must show it (``_slip_law``), which keeps noise out
NOISE_MARGIN = 2.5
SCALE_TIME = 1.0                    # s: the sensed force is put in the force loop's scale over this time
# s: after a slip in the lift, the look-back of the test that the array still slides (tuning draws: 0.05 and 0.03 s
# held 6 and 2 fewer of 100 low-friction eclairs, their grip growing on past the slide's end)
SLIDE_WINDOW = 0.02
GROSS_WINDOW = 0.1                  # s: a load that fell within this time, as fast as the grip, slid
STALL_RISE = 0.02                   # a lift's utilisation that rose less than this over the window has stalled
STALL_FRACTION = 0.8                # ... below this share of the lift's level: the bumps slide below the prior

__all__ = ["IncipientSlipParameters", "IncipientSlipController", "array_margin", "law_parameters"]


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
    probe_delay : float -- time from the lift's start before the probe starts (the weight is off the table) [s], >= 0.
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
    swing_margin : float -- while probing, each slip test's margin is at least this many times its signal's rms
        spread about its trend over the window [-], >= 0; 0 (the default): the sensor's noise alone. 3 keeps a held
        object's swing in the fingers from passing for slip, at a cost in objects held (docs/design.md sec. 12).
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
    probe_rate: float = 0.3
    probe_delay: float = 1.2
    total_drop: float = 0.015
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
    swing_margin: float = 0.0

    def __post_init__(self):
        check_positive("sample_rate_hz", self.sample_rate_hz, "Hz")
        check_range("frame_rate_hz", self.frame_rate_hz, 0.0, self.sample_rate_hz, "Hz", low_open=True)
        for name, value in (("filter_cutoff_hz", self.filter_cutoff_hz), ("watch_cutoff_hz", self.watch_cutoff_hz)):
            check_range(name, value, 0.0, 0.5 * self.frame_rate_hz, "Hz", True, True)
        check_range("loop_rate", self.loop_rate, 0.0, 0.1 * self.sample_rate_hz, "rad/s", low_open=True)
        check_range("release_loop_rate", self.release_loop_rate, 0.0, self.loop_rate, "rad/s", low_open=True)
        for name, value in (("safety_fraction", self.safety_fraction), ("force_drop", self.force_drop),
                            ("lift_safety_fraction", self.lift_safety_fraction), ("total_drop", self.total_drop),
                            ("stick_exponent", self.stick_exponent)):
            check_range(name, value, 0.0, 1.0, low_open=True, high_open=True)
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
        check_range("swing_margin", self.swing_margin, 0.0, math.inf, high_open=True)
        if not isinstance(self.rotational_slip_detection, bool):
            raise ValueError(f"rotational_slip_detection={self.rotational_slip_detection!r} must be True or False")


class IncipientSlipController:
    """The law of the module docstring: ``observe(bump_force, load_ratio, in_contact, ratio_noise)`` at each sensor
    frame, ``step(phase)`` at the control rate -> grasp-force command [N].

    A thin wrapper: the state lives in a few arrays (``arrays()``) and the law is the compiled kernels of
    ``_slip_law`` (``observe_frame``, ``control_step``), which the closed loop's fused frame loop calls on the same
    arrays. Read-outs: ``command`` [N], ``minimum_force`` [N] (None until two contacts), ``friction_estimate``
    mu_hat [-], ``probing`` / ``slip_seen``, ``need`` [N] (F / lambda*(mu = 1) of the more used fingertip: the
    grip at which it would slide at mu = 1), ``time`` [s] and ``slip_events`` ((time [s], mu_hat, kind) per
    detection; kind 'bump', 'gross' or 'array').

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
        if self.centres.ndim != 2 or self.centres.shape[1] != 2 or not len(self.centres):
            raise ValueError(f"centres must have shape (k, 2) with k >= 1, got {self.centres.shape}")
        self.second_frame = np.ascontiguousarray(second_frame, dtype=float)
        if self.second_frame.shape != (2,) or not np.all(np.abs(self.second_frame) == 1.0):
            raise ValueError(f"second_frame={second_frame!r} must be two signs (+-1, +-1)")
        self.period = sample_period(parameters.sample_rate_hz)
        self.law = law_parameters(parameters, self.centres)
        count = len(self.centres)
        self.scalars = np.zeros(X_SIZE)
        self.scalars[X_COMMAND], self.scalars[X_MINIMUM] = parameters.approach_force, math.nan
        self.scalars[X_FRICTION] = parameters.prior_friction
        self.contact = np.zeros((2, count), dtype=np.bool_)
        self.signals = np.zeros((5, 2, count))            # fast and slow filters with their previous inputs, noise
        self.ratios = np.zeros((4, 2, count, 2))          # the same for the load ratios
        self.plateau = np.array([-1.0, -1.0, 0.0])        # (wrench, sum P) when the watch began (-1: not yet), watched
        self.history_force = np.zeros((parameters.watch_frames, 2, count))
        self.history_ratios = np.zeros((parameters.watch_frames, 2, count))
        # the array's utilisation and sensed force, the carried force, moment / reach and sensed force (all slow),
        # the utilisation and sensed force through the fast filter
        self.history_use = np.zeros((parameters.watch_frames, 7))
        self.streak = np.zeros((2, count + 1), dtype=np.int64)     # frames each bump / the total has slid
        self.slip_centre = np.full((2, 2), math.inf)      # each fingertip's last slip centre [mm] (warm starts)
        self.slip_events: list[tuple[float, float]] = []

    def arrays(self) -> tuple:
        """The state arrays, in the order ``observe_frame`` takes them after the frame's inputs."""
        return (self.law, self.centres, self.second_frame, self.scalars, self.contact, self.signals, self.ratios,
                self.plateau, self.history_force, self.history_ratios, self.history_use, self.streak, self.slip_centre)

    def observe(self, bump_force, load_ratio, in_contact, ratio_noise=None) -> None:
        """Take a sensor frame: bump forces (2, k) [N], load-ratio estimates (2, k, 2) [-], in-contact (2, k), and
        the standard deviation of each ratio estimate (2, k) [-] if the sensor gives it (None: noise-free)."""
        noise = np.zeros(self.contact.shape) if ratio_noise is None else ratio_noise
        kind = observe_frame(np.ascontiguousarray(bump_force, dtype=float),
                             np.ascontiguousarray(load_ratio, dtype=float),
                             np.ascontiguousarray(in_contact, dtype=np.bool_),
                             np.ascontiguousarray(noise, dtype=float), *self.arrays())
        if kind:
            self.slip_events.append((self.time, self.friction_estimate, SLIP_KINDS[kind]))

    def step(self, phase: GraspPhase) -> float:
        """One control step in ``phase`` -> grasp-force command [N]."""
        return control_step(self.law, self.scalars, self.plateau, self.streak, PHASE_CODES[GraspPhase(phase)])

    @property
    def command(self) -> float:
        return float(self.scalars[X_COMMAND])

    @command.setter
    def command(self, value: float) -> None:
        self.scalars[X_COMMAND] = value

    @property
    def minimum_force(self) -> float | None:
        value = float(self.scalars[X_MINIMUM])
        return None if math.isnan(value) else value

    @minimum_force.setter
    def minimum_force(self, value: float | None) -> None:
        self.scalars[X_MINIMUM] = math.nan if value is None else value

    @property
    def friction_estimate(self) -> float:
        return float(self.scalars[X_FRICTION])

    @property
    def need(self) -> float:
        return float(self.scalars[X_NEED])

    @property
    def probing(self) -> bool:
        return bool(self.scalars[X_PROBING])

    @property
    def slip_seen(self) -> bool:
        return bool(self.scalars[X_SLIP_SEEN])

    @property
    def time(self) -> float:
        return float(self.scalars[X_TIME])


def law_parameters(parameters: IncipientSlipParameters, centres) -> np.ndarray:
    """The parameter vector (P_SIZE,) the compiled law reads (``_slip_law``'s P_* slots)."""
    values = np.zeros(P_SIZE)
    reach = float(np.hypot(centres[:, 0], centres[:, 1]).max())
    for slot, value in ((P_PERIOD, sample_period(parameters.sample_rate_hz)),
                        (P_FAST_GAIN, tustin_gain(parameters.filter_cutoff_hz, parameters.frame_rate_hz)),
                        (P_SLOW_GAIN, tustin_gain(parameters.watch_cutoff_hz, parameters.frame_rate_hz)),
                        (P_APPROACH_FORCE, parameters.approach_force), (P_RAMP_RATE, parameters.ramp_rate),
                        (P_MAXIMUM_FORCE, parameters.maximum_force), (P_LOOP_RATE, parameters.loop_rate),
                        (P_RELEASE_LOOP_RATE, parameters.release_loop_rate), (P_SAFETY, parameters.safety_fraction),
                        (P_LIFT_SAFETY, parameters.lift_safety_fraction),
                        (P_PRIOR_FRICTION, parameters.prior_friction),
                        (P_MAXIMUM_FRICTION, parameters.maximum_friction), (P_PROBE_RATE, parameters.probe_rate),
                        (P_PROBE_DELAY, parameters.probe_delay), (P_TOTAL_DROP, parameters.total_drop),
                        (P_WATCH_TIME, parameters.watch_frames / parameters.frame_rate_hz),
                        (P_FORCE_DROP, parameters.force_drop), (P_STICK_EXPONENT, parameters.stick_exponent),
                        (P_CONFIRM_FRAMES, parameters.confirm_frames), (P_LOADED_SHARE, parameters.loaded_share),
                        (P_FORCE_SHARE, parameters.force_share), (P_RELEASE_RATE, parameters.release_rate),
                        (P_ROTATIONAL, float(parameters.rotational_slip_detection)),
                        (P_NOISE_MARGIN, NOISE_MARGIN), (P_FULL_SEARCH_EVERY, FULL_SEARCH_EVERY),
                        (P_WARM_STEP, 0.1 * reach), (P_REACH, max(reach, 1.0)),
                        (P_SCALE_GAIN, 1.0 - math.exp(-1.0 / (SCALE_TIME * parameters.frame_rate_hz))),
                        (P_STALL_RISE, STALL_RISE), (P_STALL_FRACTION, STALL_FRACTION),
                        (P_GROSS_FRAMES, min(max(round(GROSS_WINDOW * parameters.frame_rate_hz), 2),
                                             parameters.watch_frames)),
                        (P_SLIDE_FRAMES, min(max(round(SLIDE_WINDOW * parameters.frame_rate_hz), 2),
                                             parameters.watch_frames)),
                        (P_SWING_MARGIN, parameters.swing_margin)):
        values[slot] = value
    return values
