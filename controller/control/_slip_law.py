"""The incipient-slip law (``controller.control.incipient_slip``, whose docstring states it) as compiled kernels on
the controller's state arrays: ``observe_frame`` at each sensor frame, ``control_step`` at each control step.

This is the one source of the law: ``IncipientSlipController`` is a thin Python wrapper that owns the arrays and
calls these kernels, and the closed loop's fused frame loop (``controller.closed_loop._fused``) calls the same
kernels on the same arrays without returning to Python. numba, because the law runs per frame on a few dozen bumps
inside the closed loop, where Python's per-call overhead is larger than the arithmetic.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

from ._slip_kernels import fingertip_need, low_pass_frame, slip_signature
from .references import GraspPhase

__all__ = ["observe_frame", "control_step", "PHASE_CODES"]

PHASE_CODES = {phase: code for code, phase in enumerate(GraspPhase)}     # GraspPhase -> int for compiled code
APPROACH, GRASP, LIFT, HOLD, PLACE, RELEASE = (PHASE_CODES[phase] for phase in GraspPhase)

# --- scalar state slots ---------------------------------------------------------------------------------------
(X_COMMAND, X_MINIMUM, X_FRICTION, X_PROBING, X_SLIP_SEEN, X_NEED, X_TIME, X_STARTED, X_CONTACTS, X_WATCHING,
 X_PROBE_BEGUN, X_HOLD_TIME, X_RELEASING, X_RELEASE_NEED, X_RELEASE_FORCE, X_FRAMES, X_HISTORY, X_SIZE) = range(18)
# --- parameter slots --------------------------------------------------------------------------------------------
(P_PERIOD, P_FAST_GAIN, P_SLOW_GAIN, P_APPROACH_FORCE, P_RAMP_RATE, P_MAXIMUM_FORCE, P_LOOP_RATE,
 P_RELEASE_LOOP_RATE, P_SAFETY, P_LIFT_SAFETY, P_PRIOR_FRICTION, P_MAXIMUM_FRICTION, P_PROBE_RATE, P_PROBE_DELAY,
 P_TOTAL_DROP, P_WATCH_TIME, P_FORCE_DROP, P_STICK_EXPONENT, P_CONFIRM_FRAMES, P_LOADED_SHARE, P_FORCE_SHARE,
 P_RELEASE_RATE, P_ROTATIONAL, P_NOISE_MARGIN, P_FULL_SEARCH_EVERY, P_WARM_STEP, P_SIZE) = range(27)
# --- rows of the per-bump signals (5, 2, k) and of the ratio signals (4, 2, k, 2) -------------------------------
FAST, FAST_PREVIOUS, SLOW, SLOW_PREVIOUS, RATIO_NOISE = range(5)


@njit_cached(inline="always")
def _first_min(a, b):
    """min(a, b) that keeps a unless b is strictly smaller (a NaN b keeps a)."""
    return b if b < a else a


@njit_cached(inline="always")
def _first_max(a, b):
    """max(a, b) that keeps a unless b is strictly larger (a NaN b keeps a)."""
    return b if b > a else a


@njit_cached
def _start_watch(scalars, plateau, streak):
    plateau[0] = plateau[1] = -1.0
    scalars[X_HISTORY] = 0.0
    streak[:] = 0


@njit_cached
def _target(parameters, scalars):
    probing_or_seen = scalars[X_SLIP_SEEN] > 0.0 or scalars[X_PROBING] > 0.0
    fraction = parameters[P_SAFETY] if probing_or_seen else parameters[P_LIFT_SAFETY]
    return scalars[X_NEED] / (fraction * scalars[X_FRICTION])


@njit_cached
def observe_frame(bump_force, load_ratio, in_contact, ratio_noise, parameters, centres, second_frame, scalars,
                  contact, signals, ratios, plateau, history_force, history_ratios, streak, slip_centre):
    """Take a sensor frame on the state arrays: bump forces (2, k) [N], load ratios (2, k, 2) [-],
    in contact (2, k) bool, ratio noise (2, k) [-]. True when the slip watch saw a slip (the event is
    (scalars[X_TIME], scalars[X_FRICTION]))."""
    count = centres.shape[0]
    signals[RATIO_NOISE] = ratio_noise
    restart = scalars[X_STARTED] == 0.0
    contacts = 0
    for f in range(2):
        touching = 0
        for i in range(count):
            if in_contact[f, i] and not contact[f, i]:
                restart = True
            contact[f, i] = in_contact[f, i]
            touching += 1 if in_contact[f, i] else 0
        contacts = max(contacts, touching)
    scalars[X_STARTED], scalars[X_CONTACTS] = 1.0, contacts
    low_pass_frame(parameters[P_FAST_GAIN], bump_force, load_ratio, contact, signals[FAST_PREVIOUS],
                   ratios[FAST_PREVIOUS], signals[FAST], ratios[FAST], restart)
    low_pass_frame(parameters[P_SLOW_GAIN], signals[FAST], ratios[FAST], contact, signals[SLOW_PREVIOUS],
                   ratios[SLOW_PREVIOUS], signals[SLOW], ratios[SLOW], restart)
    scalars[X_FRAMES] += 1.0
    full = int(scalars[X_FRAMES]) % int(parameters[P_FULL_SEARCH_EVERY]) == 0
    scalars[X_NEED] = fingertip_need(centres, signals[FAST], ratios[FAST], contact, parameters[P_ROTATIONAL] > 0.0,
                                     slip_centre, full, parameters[P_WARM_STEP])
    if scalars[X_WATCHING] == 0.0:
        return False
    # the slip watch (module docstring of incipient_slip: per-bump ratios against their forces, the total load)
    frames = history_force.shape[0]
    seen = scalars[X_SLIP_SEEN] > 0.0
    hold_ratio = parameters[P_SAFETY] * scalars[X_FRICTION] if seen else 0.0
    written = int(scalars[X_HISTORY])
    judged = parameters[P_ROTATIONAL] > 0.0 and scalars[X_PROBING] > 0.0 and written >= frames
    oldest = written % frames
    noise = parameters[P_NOISE_MARGIN] * signals[RATIO_NOISE]
    signature, total_ratio, bearing, magnitudes = slip_signature(
        signals[SLOW], ratios[SLOW], contact, history_force[oldest], history_ratios[oldest], judged, plateau,
        second_frame, hold_ratio, parameters[P_TOTAL_DROP], parameters[P_FORCE_DROP], parameters[P_STICK_EXPONENT],
        parameters[P_LOADED_SHARE], parameters[P_FORCE_SHARE], noise)
    history_force[oldest] = signals[SLOW]
    history_ratios[oldest] = magnitudes
    scalars[X_HISTORY] = written + 1
    longest, finger, index = -1, 0, 0
    for f in range(2):
        for i in range(count + 1):
            streak[f, i] = streak[f, i] + 1 if signature[f, i] else 0
            if streak[f, i] > longest:                                  # the first largest, as np.argmax
                longest, finger, index = streak[f, i], f, i
    if longest < parameters[P_CONFIRM_FRAMES]:
        return False
    measured = _first_max(total_ratio, bearing) if index == count else magnitudes[finger, index]
    scalars[X_FRICTION] = _first_min(scalars[X_FRICTION], measured) if seen else measured
    scalars[X_SLIP_SEEN], scalars[X_PROBING] = 1.0, 0.0
    step_up = _first_min(_first_max(scalars[X_COMMAND], _target(parameters, scalars)), parameters[P_MAXIMUM_FORCE])
    scalars[X_COMMAND] = step_up
    _start_watch(scalars, plateau, streak)
    return True


@njit_cached
def _latch_minimum(scalars):
    if math.isnan(scalars[X_MINIMUM]) and scalars[X_CONTACTS] >= 2:
        scalars[X_MINIMUM] = scalars[X_COMMAND]
    return not math.isnan(scalars[X_MINIMUM])


@njit_cached
def control_step(parameters, scalars, plateau, streak, phase):
    """One control step on the state arrays, ``phase`` a ``PHASE_CODES`` value -> command [N]."""
    period = parameters[P_PERIOD]
    scalars[X_TIME] += period
    if phase != RELEASE:
        scalars[X_RELEASING] = 0.0
    if phase != HOLD and scalars[X_HOLD_TIME] > 0.0:
        scalars[X_HOLD_TIME] = scalars[X_PROBING] = scalars[X_WATCHING] = scalars[X_PROBE_BEGUN] = 0.0
        _start_watch(scalars, plateau, streak)
    if phase == APPROACH:
        scalars[X_COMMAND] = parameters[P_APPROACH_FORCE]
        _latch_minimum(scalars)
    elif phase == RELEASE:
        if scalars[X_RELEASING] == 0.0:
            scalars[X_RELEASING], scalars[X_RELEASE_NEED], scalars[X_RELEASE_FORCE] = 1.0, scalars[X_NEED], \
                scalars[X_COMMAND]
        need_start = scalars[X_RELEASE_NEED]
        change = 1.0 if need_start <= 0.0 else _first_min(1.0, abs(scalars[X_NEED] - need_start) / need_start)
        scalars[X_COMMAND] = _first_max(scalars[X_COMMAND] - parameters[P_RELEASE_RATE] * scalars[X_RELEASE_FORCE]
                                        * change * period, 0.0)
    elif math.isnan(scalars[X_MINIMUM]):
        if not _latch_minimum(scalars):
            scalars[X_COMMAND] = _first_min(scalars[X_COMMAND] + parameters[P_RAMP_RATE] * period,
                                            parameters[P_MAXIMUM_FORCE])
    else:
        if phase == HOLD:
            _hold_step(parameters, scalars, period)
        target = _first_min(_first_max(_target(parameters, scalars), scalars[X_MINIMUM]), parameters[P_MAXIMUM_FORCE])
        rate = parameters[P_LOOP_RATE] if target > scalars[X_COMMAND] else parameters[P_RELEASE_LOOP_RATE]
        scalars[X_COMMAND] += rate * period * (target - scalars[X_COMMAND])
    return scalars[X_COMMAND]


@njit_cached
def _hold_step(parameters, scalars, period):
    """Start the watch one window before the probe delay; probe (raise mu_hat) until a slip is seen."""
    scalars[X_HOLD_TIME] += period
    if scalars[X_WATCHING] == 0.0 and scalars[X_HOLD_TIME] >= parameters[P_PROBE_DELAY] - parameters[P_WATCH_TIME]:
        scalars[X_WATCHING] = 1.0
    if scalars[X_HOLD_TIME] < parameters[P_PROBE_DELAY]:
        return
    if scalars[X_PROBE_BEGUN] == 0.0:
        scalars[X_PROBE_BEGUN] = 1.0
        scalars[X_PROBING] = 0.0 if scalars[X_SLIP_SEEN] > 0.0 else 1.0
    if scalars[X_PROBING] > 0.0:
        scalars[X_FRICTION] = _first_min(scalars[X_FRICTION] * math.exp(parameters[P_PROBE_RATE] * period),
                                         parameters[P_MAXIMUM_FRICTION])
