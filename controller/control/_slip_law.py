"""The incipient-slip law (``controller.control.incipient_slip``, whose docstring states it) as compiled kernels on
the controller's state arrays: ``observe_frame`` at each sensor frame, ``control_step`` at each control step (the
arrays' slots are ``_slip_state``'s, the lift's test is ``_lift_test``'s).

This is the one source of the law: ``IncipientSlipController`` is a thin Python wrapper that owns the arrays and
calls these kernels, and the closed loop's fused frame loop (``controller.closed_loop._fused``) calls the same
kernels on the same arrays without returning to Python. numba, because the law runs per frame on a few dozen bumps
inside the closed loop, where Python's per-call overhead is larger than the arithmetic.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

from ._lift_test import (LIFT_UNTRIED, LIFT_STEPPED, LIFT_DONE, LIFT_ASKED, _load_follows_grip, _lift_test)
from ._slip_kernels import (dominant_component, fingertip_need, low_pass_frame, slip_signature, tip_normal_force,
                            trend_spread, watched)
from ._slip_state import (APPROACH, ARRAY_SLIP, AT_MINIMUM, BUMP_SLIP, FAST, FAST_PREVIOUS, GROSS_SLIP, HOLD, LIFT,
                          MINIMUM_FRICTION, NO_SLIP, PLACE, P_APPROACH_FORCE, P_CONFIRM_FRAMES, P_FAST_GAIN,
                          P_FORCE_DROP, P_FORCE_SHARE, P_FULL_SEARCH_EVERY, P_GROSS_FRAMES, P_LIFT_SAFETY,
                          P_LOADED_SHARE, P_LOOP_RATE, P_MAXIMUM_FORCE, P_MAXIMUM_FRICTION, P_NOISE_MARGIN, P_PERIOD,
                          P_PROBE_DELAY, P_PROBE_RATE, P_RAMP_RATE, P_REACH, P_RELEASE_LOOP_RATE, P_RELEASE_RATE,
                          P_ROTATIONAL, P_SAFETY, P_SCALE_GAIN, P_SLIDE_FRAMES, P_SLOW_GAIN, P_STALL_FRACTION,
                          P_STALL_RISE, P_STICK_EXPONENT, P_SWING_MARGIN, P_TOTAL_DROP, P_WARM_STEP, P_WATCH_TIME,
                          RATIO_NOISE, RELEASE, SATURATED, SLOW, SLOW_PREVIOUS, X_CARRY_SLIP, X_CARRY_TIME, X_COMMAND,
                          X_COMMAND_MEAN, X_CONTACTS, X_FRAMES, X_FRICTION, X_GRIP, X_HISTORY, X_LIFT_HOLD,
                          X_LIFT_SIZED, X_LIFT_TEST, X_LIFT_USE, X_MINIMUM, X_NEED, X_PHASE, X_PLACE_FORCE, X_PROBED,
                          X_PROBE_BEGUN, X_PROBING, X_RELEASE_FORCE, X_RELEASE_NEED, X_RELEASING, X_SENSED,
                          X_SENSED_MEAN, X_SENSED_SLOW, X_SLIDING, X_SLID_GRIP, X_SLID_HELD, X_SLID_USE, X_SLIP_SEEN,
                          X_STARTED, X_TIME, X_TIP_MEAN_0, X_TIP_SLOW_0, X_USE_SLOW, X_VISIBLE, X_WATCHING, _ema,
                          _first_max, _first_min, _force_scale, _tip_grip)

__all__ = ["observe_frame", "control_step"]

# the probe starts only where some fingertip has this many bumps its test can see slide (``_visible_bumps``): the bump
# test confirms a slip at two bumps of one fingertip
BLIND_BELOW = 2


@njit_cached
def _start_watch(scalars, plateau, streak, total):
    """(Re)start the watch: no plateau (the total is watched when ``total``), no history, no streaks."""
    plateau[0] = plateau[1] = -1.0                 # (unused) and the frame the total's watch began at
    plateau[2] = 1.0 if total else 0.0
    scalars[X_HISTORY] = 0.0
    streak[:] = 0


@njit_cached
def _target(parameters, scalars):
    """The grip [N] that holds the array at the safety fraction of its slip limit at mu_hat: the grip of the
    readings times their utilisation nu = 1 / lambda*(1) over s mu_hat, both slowly filtered (the object swings in
    the compliant fingers at a few Hz; a demand that followed the swing would drive it)."""
    probing_or_seen = scalars[X_SLIP_SEEN] > 0.0 or scalars[X_PROBING] > 0.0
    fraction = parameters[P_SAFETY] if probing_or_seen else parameters[P_LIFT_SAFETY]
    grip, use = scalars[X_GRIP], _first_min(scalars[X_USE_SLOW], 1e6)
    # after a slip in the lift, an array that still slides (observe_frame) is at its limit, nu = mu_hat whatever it
    # reads: grow from the command, which the slowly filtered grip lags (the lag halved the growth while the
    # object slid)
    if (scalars[X_PHASE] == LIFT and scalars[X_SLIP_SEEN] > 0.0 and scalars[X_PROBING] == 0.0
            and scalars[X_SLIDING] > 0.0):
        grip, use = _first_max(grip, scalars[X_COMMAND]), _first_max(use, scalars[X_FRICTION])
    return grip * use / (fraction * scalars[X_FRICTION])


@njit_cached
def observe_frame(bump_force, load_ratio, in_contact, ratio_noise, parameters, centres, second_frame, scalars,
                  contact, signals, ratios, plateau, history_force, history_ratios, history_use, streak, slip_centre):
    """Take a sensor frame on the state arrays: bump forces (2, k) [N], load ratios (2, k, 2) [-],
    in contact (2, k) bool, ratio noise (2, k) [-]. Returns what the slip watch saw (NO_SLIP, or the kind of slip:
    the event is (scalars[X_TIME], scalars[X_FRICTION]))."""
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
    use, used = fingertip_need(centres, signals[FAST], ratios[FAST], contact, parameters[P_ROTATIONAL] > 0.0,
                               slip_centre, full, parameters[P_WARM_STEP])
    # each fingertip's sensed normal force; the more used one's is the F of the readings
    tips = (tip_normal_force(signals[FAST], contact, 0), tip_normal_force(signals[FAST], contact, 1))
    sensed = tips[used] if used >= 0 else 0.0
    scalars[X_NEED], scalars[X_SENSED] = use, sensed
    # the scale both fingertips share: the command against the more used fingertip's sensed force over a second (the
    # estimator's scale error; a lag of the grip behind its command averages out). The lift test reads the command in
    # it, and the grip falls back to it while no fingertip is used
    if sensed > 0.0:
        scalars[X_COMMAND_MEAN] = _ema(scalars[X_COMMAND_MEAN], scalars[X_COMMAND], parameters[P_SCALE_GAIN])
        scalars[X_SENSED_MEAN] = _ema(scalars[X_SENSED_MEAN], sensed, parameters[P_SCALE_GAIN])
    scalars[X_USE_SLOW] = _ema(scalars[X_USE_SLOW], use, parameters[P_SLOW_GAIN])
    scalars[X_SENSED_SLOW] = _ema(scalars[X_SENSED_SLOW], sensed, parameters[P_SLOW_GAIN])
    # each fingertip's sensed force over a second and slowly filtered: both carry one grip, but each reads it with
    # its own error (up to 1.7x apart on a curved object), so the grip is read off the more used one in its own scale;
    # one scale for both jumped when the more used fingertip changed and the grip sank while the object slid
    # (docs/design.md sec. 12)
    for f in range(2):
        if tips[f] > 0.0:
            scalars[X_TIP_MEAN_0 + f] = _ema(scalars[X_TIP_MEAN_0 + f], tips[f], parameters[P_SCALE_GAIN])
            scalars[X_TIP_SLOW_0 + f] = _ema(scalars[X_TIP_SLOW_0 + f], tips[f], parameters[P_SLOW_GAIN])
    # the slowly filtered grip: a fast one would feed the object's own swing in the fingers back into the demand
    if used >= 0 and scalars[X_TIP_MEAN_0 + used] > 0.0:
        scalars[X_GRIP] = _tip_grip(scalars, used)
    else:
        scalars[X_GRIP] = scalars[X_SENSED_SLOW] * _force_scale(scalars)
    if scalars[X_WATCHING] == 0.0:
        return NO_SLIP
    # the slip watch (module docstring of incipient_slip: per-bump ratios against their forces, the total load)
    frames = history_force.shape[0]
    seen = scalars[X_SLIP_SEEN] > 0.0
    # once the friction is known and the grip holds, only loads above the hold level count as slip; while probing,
    # every load does (the probe's mu_hat may be past the true friction)
    hold_ratio = parameters[P_SAFETY] * scalars[X_FRICTION] if seen and scalars[X_PROBING] == 0.0 else 0.0
    written = int(scalars[X_HISTORY])
    # while probing, once the window lies in the probe (before it the grip followed the load: no test can tell a load
    # that fell from a grasp that slid); after a slip, the total above the hold level
    probed = scalars[X_PROBING] > 0.0 and scalars[X_PROBED] >= parameters[P_WATCH_TIME]
    judged = parameters[P_ROTATIONAL] > 0.0 and probed and written >= frames
    watch_total = (parameters[P_TOTAL_DROP] < 1.0 and plateau[2] > 0.0
                   and (probed or (seen and scalars[X_PROBING] == 0.0)))
    oldest = written % frames
    # a bump's ratio against its value a window ago, both through the slow filter (variance times its gain b):
    # the difference has sqrt(2 b) of the raw noise; the margin is NOISE_MARGIN of that
    noise = parameters[P_NOISE_MARGIN] * math.sqrt(2.0 * parameters[P_SLOW_GAIN]) * signals[RATIO_NOISE]
    wrench_noise = 0.0                       # the carried wrench's noise, from each bump's: sqrt(sum (P_i s_i)^2)
    for f in range(2):
        for i in range(count):
            if contact[f, i]:
                wrench_noise += (signals[FAST, f, i] * signals[RATIO_NOISE, f, i]) ** 2
    wrench_noise = parameters[P_NOISE_MARGIN] * math.sqrt(wrench_noise)
    use_now = np.array([scalars[X_USE_SLOW], scalars[X_SENSED_SLOW]])
    use_then = history_use[oldest, :2] if written >= frames else np.zeros(2)
    fast_now = np.array([scalars[X_NEED], scalars[X_SENSED]])
    if seen and scalars[X_PHASE] == LIFT and scalars[X_PROBING] == 0.0:
        # does the array still slide after the slip? Over the last SLIDE_FRAMES frames of the fast signals (the slow
        # ones lag a grip growing several-fold a second by a tenth of a second) or since the slip for the first of
        # them; where the grip grew too little for a verdict there, over the window of the slow ones (a slow slide);
        # else while it reads its friction. Its read nu may sit below the mu_hat its slip set (an estimator whose
        # scale error changes with the force)
        back = int(parameters[P_SLIDE_FRAMES])
        if written >= back:
            row = (written - back) % frames
            then_use, then_grip = history_use[row, 5], history_use[row, 6]
        else:
            then_use, then_grip = scalars[X_SLID_USE], scalars[X_SLID_GRIP]
        verdict = _load_follows_grip(parameters, fast_now[0], fast_now[1], then_use, then_grip)
        if verdict == 0:
            scalars[X_SLID_HELD] = written
        # the slow window only once it lies after the fast one's last 'held' (across it, it would read the slide
        # before as sliding now)
        if verdict < 0 and written >= frames and written - scalars[X_SLID_HELD] >= frames:
            verdict = _load_follows_grip(parameters, use_now[0], use_now[1], use_then[0], use_then[1])
        slides = verdict > 0 if verdict >= 0 else scalars[X_USE_SLOW] >= scalars[X_FRICTION]
        scalars[X_SLIDING] = 1.0 if slides else 0.0
    # the carried wrench's reference: its largest value (and the grip's) over the last GROSS_FRAMES frames
    window = int(parameters[P_GROSS_FRAMES])
    reference = np.full(3, -1.0)
    if written >= window:
        for back in range(1, window + 1):
            row = (written - back) % frames
            for column in range(3):
                reference[column] = max(reference[column], history_use[row, 2 + column])
    carried = np.zeros(3)
    # the utilisation's noise: the per-bump noise pooled, through the slow filter (variance times its gain b) and the
    # window's difference (twice that): sqrt(2 b) of the raw margin
    use_noise = math.sqrt(2.0 * parameters[P_SLOW_GAIN]) * wrench_noise / max(sensed, 1e-9)
    # the tests' margins (a bump's ratio, the carried load, the array's nu): the noise's, or, with a swing margin and
    # once the window lies in the probe, that many times the signal's rms spread about its trend over the window
    # where that is larger (a held object rocks in the compliant fingers and its loads swing with it; docs/design.md
    # sec. 12). A bump's spread leaves out the newest frames of its history, the confirmation's and one: the onset of
    # its slide bends them, and a margin that grew with it saw the slide later, the array by then sliding as a whole
    # and read low. The carried load's and nu's keep them (left out of the gross test's too, the swing's fall passed it)
    watch_noise, gross_noise, array_noise = noise, wrench_noise, use_noise
    swing_margin = parameters[P_SWING_MARGIN]
    if probed and swing_margin > 0.0:
        watch_noise = noise.copy()
        skip = int(parameters[P_CONFIRM_FRAMES]) + 1
        for f in range(2):
            for i in range(count):
                if contact[f, i]:
                    spread = trend_spread(history_ratios[:, f, i], written, skip)
                    watch_noise[f, i] = _first_max(watch_noise[f, i], swing_margin * spread)
        gross_noise = _first_max(wrench_noise, swing_margin * trend_spread(
            history_use[:, 2 + dominant_component(reference)], written))
        array_noise = _first_max(use_noise, swing_margin * trend_spread(history_use[:, 0], written))
    # the array as a whole: against the probe's falling grip, or, in the lift, a load-driven grip (above the
    # minimum force) whose load stopped growing below what it carries; not with the grip pinned at the actuator's
    # limit (a load still coming on then keeps nu where it is, held or not: the test cannot tell them apart)
    at_minimum = scalars[X_COMMAND] <= AT_MINIMUM * scalars[X_MINIMUM]        # False while no minimum is latched
    lifting = (scalars[X_PHASE] == LIFT and scalars[X_COMMAND] > AT_MINIMUM * scalars[X_MINIMUM] and not seen
               and scalars[X_COMMAND] < SATURATED * parameters[P_MAXIMUM_FORCE])
    use_mode = 1 if probed else (2 if lifting and parameters[P_STALL_FRACTION] > 0.0 else 0)
    signature, total_ratio, bearing, magnitudes, largest, mean_force = slip_signature(
        signals[SLOW], ratios[SLOW], signals[FAST], ratios[FAST], contact, centres, history_force[oldest],
        history_ratios[oldest], judged, watch_total, reference, carried, second_frame, hold_ratio,
        parameters[P_TOTAL_DROP],
        parameters[P_FORCE_DROP], parameters[P_STICK_EXPONENT], parameters[P_LOADED_SHARE],
        parameters[P_FORCE_SHARE], watch_noise, gross_noise, parameters[P_REACH], use_now, use_then, array_noise,
        use_mode,
        parameters[P_LIFT_SAFETY] * scalars[X_FRICTION],
        parameters[P_STALL_RISE], parameters[P_STALL_FRACTION])
    if scalars[X_PROBE_BEGUN] == 0.0:                 # read once, when the probe begins (_carry_step)
        scalars[X_VISIBLE] = _visible_bumps(parameters, signals[SLOW], magnitudes, contact, noise, largest, mean_force)
    if not seen and (scalars[X_PHASE] == LIFT or scalars[X_LIFT_TEST] == LIFT_STEPPED
                     or scalars[X_LIFT_TEST] == LIFT_ASKED):
        # nu's spread over the window (largest less smallest, this frame's included), for a test yet to start
        low = high = use_now[0]
        if scalars[X_LIFT_TEST] == LIFT_UNTRIED:
            for back in range(1, min(written, frames) + 1):
                value = history_use[(written - back) % frames, 0]
                low, high = _first_min(low, value), _first_max(high, value)
        _lift_test(parameters, scalars, signature, count, use_now, use_then, use_noise, high - low,
                   written >= frames, frames, at_minimum)
    history_force[oldest] = signals[SLOW]
    history_ratios[oldest] = magnitudes
    history_use[oldest, :2] = use_now
    history_use[oldest, 2:5] = carried
    history_use[oldest, 5:7] = fast_now
    scalars[X_HISTORY] = written + 1
    confirm = parameters[P_CONFIRM_FRAMES]
    finger, index, measured = 0, -1, 0.0
    for f in range(2):
        for i in range(count + 1):
            streak[f, i] = streak[f, i] + 1 if signature[f, i] else 0
    # a bump slip counts when two bumps of one fingertip show it: an array starts to slide at more than one bump
    # (the outer ones in a pair under a moment, all under a force), while noise flags bumps one at a time. It reads
    # the ratio two of them reach, the second largest: each sits at mu, each reading carries the estimator's error
    # for its bump, and the largest over-reads mu (docs/design.md sec. 12). Bumps that carry no load to speak of
    # measure nothing; the array's tests below still run. Where both fingertips show one (rare), the larger reading
    # measures (the smaller changed no tuning outcome, tried with each fingertip's smallest reading)
    for f in range(2):
        flagged, first, second = 0, 0.0, 0.0
        for i in range(count):
            if streak[f, i] >= confirm:
                flagged += 1
                value = magnitudes[f, i]
                if value > first:
                    first, second = value, first
                elif value > second:
                    second = value
        if flagged >= 2 and second >= MINIMUM_FRICTION and second > measured:
            finger, index, measured = f, 0, second
    if index < 0:
        # the array slides as a whole: at its limit, lambda*(mu) = 1, so its utilisation nu = 1 / lambda*(1) is mu
        # (any mode, translation or rotation: the bumps' largest ratio overshoots it under a moment)
        if streak[0, count] >= confirm:                             # the grasp slid as a whole, its load fell
            finger, index, measured = 0, count, scalars[X_NEED]
        elif streak[1, count] >= confirm:                           # the array's utilisation stayed at mu
            finger, index, measured = 1, count, scalars[X_NEED]
            # confirmed while a lift test holds a sized step: that test began where nu sat at the level, and nu now,
            # confirm frames into the verdict, may already fall as the grip catches the object (read low, the catch
            # that followed crushed an eclair on a tuning draw)
            if scalars[X_LIFT_TEST] == LIFT_STEPPED and scalars[X_LIFT_SIZED] > 0.0:
                measured = _first_max(measured, scalars[X_LIFT_USE])
        else:
            return NO_SLIP
    if not measured >= MINIMUM_FRICTION:     # no load to speak of (or none at all): not a friction measurement
        streak[finger, index] = 0
        return NO_SLIP
    scalars[X_FRICTION] = _first_min(scalars[X_FRICTION], measured) if seen else measured
    scalars[X_SLIP_SEEN], scalars[X_PROBING] = 1.0, 0.0
    scalars[X_LIFT_TEST] = LIFT_DONE                  # a slip seen ends the lift's test (and its hold on the grip)
    scalars[X_CARRY_SLIP] = 1.0
    scalars[X_SLID_USE], scalars[X_SLID_GRIP], scalars[X_SLIDING], scalars[X_SLID_HELD] = \
        fast_now[0], fast_now[1], 1.0, -frames
    # step up at once, by at least twice the safety margin: a grasp that slid carried less than its load while
    # sliding, so the demand read off its loads is short of what holds it, and what slides has gathered momentum
    step_up = _first_max(_first_max(scalars[X_COMMAND], _target(parameters, scalars)),
                         scalars[X_COMMAND] / parameters[P_SAFETY] ** 2)
    scalars[X_COMMAND] = _first_min(step_up, parameters[P_MAXIMUM_FORCE])
    _start_watch(scalars, plateau, streak, True)
    return BUMP_SLIP if index < count else (GROSS_SLIP if finger == 0 else ARRAY_SLIP)


@njit_cached
def _visible_bumps(parameters, force, magnitudes, contact, noise, largest, mean_force):
    """The most bumps of one fingertip that the probe's bump test can be relied on to see slide: of the bumps it
    watches (``watched``, on ``slip_signature``'s references ``largest`` and ``mean_force``), those whose noise margin
    lies below the gap the probe opens over a window between a stuck bump's ratio and a sliding one's
    (|rho_i| (exp(stick_exponent probe_rate window) - 1): noise over |rho_i| is that of the bump's tangential load,
    which the falling grip does not change while the loads stay where they are)."""
    gap = math.exp(parameters[P_STICK_EXPONENT] * parameters[P_PROBE_RATE] * parameters[P_WATCH_TIME]) - 1.0
    best = 0
    for f in range(2):
        visible = 0
        for i in range(force.shape[1]):
            if (watched(contact[f, i], magnitudes[f, i], force[f, i], largest[f], mean_force[f],
                        parameters[P_LOADED_SHARE], parameters[P_FORCE_SHARE])
                    and noise[f, i] <= gap * magnitudes[f, i]):
                visible += 1
        best = max(best, visible)
    return best


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
    if phase != scalars[X_PHASE]:
        carrying = scalars[X_PHASE] == LIFT and phase == HOLD      # the watch and the probe go on through both
        scalars[X_PHASE] = phase
        if not carrying:
            scalars[X_CARRY_TIME] = scalars[X_PROBING] = scalars[X_PROBE_BEGUN] = 0.0
            scalars[X_LIFT_TEST] = LIFT_UNTRIED
            # the lift is watched from its start (a friction below the prior slides it), the total from the probe
            scalars[X_WATCHING] = 1.0 if phase == LIFT else 0.0
            _start_watch(scalars, plateau, streak, False)
        if phase == PLACE:
            scalars[X_PLACE_FORCE] = scalars[X_COMMAND]
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
        if phase == LIFT or phase == HOLD:
            _carry_step(parameters, scalars, plateau, streak, period)
        target = _first_max(_target(parameters, scalars), scalars[X_MINIMUM])
        if scalars[X_LIFT_TEST] == LIFT_STEPPED:                         # the lift's test holds its step
            target = _first_max(target, scalars[X_LIFT_HOLD])
        if phase == PLACE:
            # placing never asks more than holding did: the table takes the load. A load that grows now is the
            # table's push on an object that slid down in the grasp and met it early - the fingers slide along it
            # and carry mu of any grip - not a load to hold (chased, it drove the grip to the actuator's limit)
            target = _first_min(target, scalars[X_PLACE_FORCE])
        target = _first_min(target, parameters[P_MAXIMUM_FORCE])
        rate = parameters[P_LOOP_RATE] if target > scalars[X_COMMAND] else parameters[P_RELEASE_LOOP_RATE]
        scalars[X_COMMAND] += rate * period * (target - scalars[X_COMMAND])
    return scalars[X_COMMAND]


@njit_cached
def _carry_step(parameters, scalars, plateau, streak, period):
    """While the object is carried (lift, then hold): watch the total one window before the probe delay (counted
    from the lift's start: the weight is long off the table and the lift's load is steady to 0.5 %); probe (raise
    mu_hat) until a slip is seen."""
    scalars[X_CARRY_TIME] += period
    if plateau[2] == 0.0 and scalars[X_CARRY_TIME] >= parameters[P_PROBE_DELAY] - parameters[P_WATCH_TIME]:
        scalars[X_WATCHING] = plateau[2] = 1.0
    if scalars[X_CARRY_TIME] < parameters[P_PROBE_DELAY]:
        return
    if scalars[X_PROBE_BEGUN] == 0.0:
        scalars[X_PROBE_BEGUN] = 1.0
        # a probe whose bump test cannot be relied on to see a bump slide does not start (without rotational detection
        # the bump test is not used: that probe watches the total alone)
        blind = parameters[P_ROTATIONAL] > 0.0 and scalars[X_VISIBLE] < BLIND_BELOW
        scalars[X_PROBING] = 0.0 if scalars[X_CARRY_SLIP] > 0.0 or blind else 1.0
        # the grip a blind probe leaves where the lift left it is tested once instead, if no lift test ran: a grasp
        # sliding at a friction read at the lift's level looks, to nu and to the demand, like one held there
        if blind and scalars[X_CARRY_SLIP] == 0.0 and scalars[X_LIFT_TEST] == LIFT_UNTRIED:
            scalars[X_LIFT_TEST] = LIFT_ASKED
        if scalars[X_PROBING] > 0.0:        # the probe's margin is the hold's: mu_hat starts where the grip is
            scalars[X_FRICTION] *= parameters[P_LIFT_SAFETY] / parameters[P_SAFETY]
            scalars[X_PROBED] = 0.0
    # the probe waits while a lift test holds its step: mu_hat raised under a grip held up would drop it at once,
    # unwatched, to the demand at an unchecked mu_hat when the test ends
    if scalars[X_PROBING] > 0.0 and scalars[X_LIFT_TEST] != LIFT_STEPPED:
        scalars[X_PROBED] += period
        scalars[X_FRICTION] = _first_min(scalars[X_FRICTION] * math.exp(parameters[P_PROBE_RATE] * period),
                                         parameters[P_MAXIMUM_FRICTION])
