"""The incipient-slip law's compiled state (``controller.control._slip_law``): the slots of its scalar state and
parameter arrays, the rows of its per-bump signals, the phase codes, what a frame can see, and the small helpers every
kernel of the law shares. Plain numbers and inlined functions: the law's kernels index its arrays by these names.
"""

from __future__ import annotations

from fem.compiled import njit_cached

from .references import GraspPhase

__all__ = ["PHASE_CODES", "SLIP_KINDS"]

PHASE_CODES = {phase: code for code, phase in enumerate(GraspPhase)}     # GraspPhase -> int for compiled code
APPROACH, GRASP, LIFT, HOLD, PLACE, RELEASE = (PHASE_CODES[phase] for phase in GraspPhase)

# --- scalar state slots ---------------------------------------------------------------------------------------
(X_COMMAND, X_MINIMUM, X_FRICTION, X_PROBING, X_SLIP_SEEN, X_NEED, X_TIME, X_STARTED, X_CONTACTS, X_WATCHING,
 X_PROBE_BEGUN, X_CARRY_TIME, X_RELEASING, X_RELEASE_NEED, X_RELEASE_FORCE, X_FRAMES, X_HISTORY, X_PHASE, X_GRIP,
 X_CARRY_SLIP, X_SENSED, X_COMMAND_MEAN, X_SENSED_MEAN, X_USE_SLOW, X_SENSED_SLOW, X_PROBED, X_LIFT_TEST,
 X_LIFT_FRAMES, X_LIFT_USE, X_LIFT_GRIP, X_LIFT_HOLD, X_LIFT_HELD, X_SLID_USE, X_SLID_GRIP, X_SLIDING,
 X_SLID_HELD, X_PLACE_FORCE, X_VISIBLE, X_LIFT_STEP, X_LIFT_UNJUDGED, X_LIFT_SIZED, X_TIP_MEAN_0, X_TIP_MEAN_1,
 X_TIP_SLOW_0, X_TIP_SLOW_1, X_SIZE) = range(46)
# --- parameter slots --------------------------------------------------------------------------------------------
(P_PERIOD, P_FAST_GAIN, P_SLOW_GAIN, P_APPROACH_FORCE, P_RAMP_RATE, P_MAXIMUM_FORCE, P_LOOP_RATE,
 P_RELEASE_LOOP_RATE, P_SAFETY, P_LIFT_SAFETY, P_PRIOR_FRICTION, P_MAXIMUM_FRICTION, P_PROBE_RATE, P_PROBE_DELAY,
 P_TOTAL_DROP, P_WATCH_TIME, P_FORCE_DROP, P_STICK_EXPONENT, P_CONFIRM_FRAMES, P_LOADED_SHARE, P_FORCE_SHARE,
 P_RELEASE_RATE, P_ROTATIONAL, P_NOISE_MARGIN, P_FULL_SEARCH_EVERY, P_WARM_STEP, P_REACH, P_SCALE_GAIN,
 P_STALL_RISE, P_STALL_FRACTION, P_GROSS_FRAMES, P_SLIDE_FRAMES, P_SWING_MARGIN, P_SIZE) = range(34)
# --- rows of the per-bump signals (5, 2, k) and of the ratio signals (4, 2, k, 2) -------------------------------
FAST, FAST_PREVIOUS, SLOW, SLOW_PREVIOUS, RATIO_NOISE = range(5)
SATURATED = 0.98                 # a command this close to the actuator's limit is pinned there, not regulated
AT_MINIMUM = 1.05                # a command within this factor of the contact minimum sits there (not load-driven)
MINIMUM_FRICTION = 0.05          # a slip measured at a lower ratio carried no load: it is not counted
# what ``observe_frame`` saw: nothing, a single bump sliding, the grasp's carried load falling with its grip (gross
# slip), the array's utilisation staying put while its grip fell (the array sliding as a whole)
NO_SLIP, BUMP_SLIP, GROSS_SLIP, ARRAY_SLIP = range(4)
SLIP_KINDS = {BUMP_SLIP: "bump", GROSS_SLIP: "gross", ARRAY_SLIP: "array"}


@njit_cached(inline="always")
def _first_min(a, b):
    """min(a, b) that keeps a unless b is strictly smaller (a NaN b keeps a)."""
    return b if b < a else a


@njit_cached(inline="always")
def _first_max(a, b):
    """max(a, b) that keeps a unless b is strictly larger (a NaN b keeps a)."""
    return b if b > a else a


@njit_cached(inline="always")
def _scale_against(scalars, sensed_mean):
    """The force loop's scale over a sensed force [-]: the command's mean over a second against ``sensed_mean`` [N],
    that force's mean over the same time (1 without one), within 0.5-2."""
    scale = scalars[X_COMMAND_MEAN] / sensed_mean if sensed_mean > 0.0 else 1.0
    return _first_min(_first_max(scale, 0.5), 2.0)


@njit_cached(inline="always")
def _force_scale(scalars):
    """The force loop's scale over the more used fingertip's sensed force [-] (the estimator's scale error; a lag of
    the grip behind its command averages out)."""
    return _scale_against(scalars, scalars[X_SENSED_MEAN])


@njit_cached(inline="always")
def _tip_grip(scalars, tip):
    """The grip [N] read off fingertip ``tip`` alone: its slowly filtered sensed normal force by its own scale (its
    sensed force averaged over the frames it touches, from its first)."""
    return scalars[X_TIP_SLOW_0 + tip] * _scale_against(scalars, scalars[X_TIP_MEAN_0 + tip])


@njit_cached(inline="always")
def _ema(value, target, gain):
    return target if value == 0.0 else value + gain * (target - value)
