"""The lift's test of the incipient-slip law (``controller.control.incipient_slip``, whose docstring states it): a
step up of the grip, held for a window, whose verdict tells a held load (its utilisation falls like 1 / P) from one
that follows the grip (bumps sliding at mu) - compiled, on the law's state arrays (``_slip_state``).
"""

from __future__ import annotations

import math

from fem.compiled import njit_cached

from ._slip_state import (LIFT, MINIMUM_FRICTION, P_CONFIRM_FRAMES, P_FORCE_DROP, P_LIFT_SAFETY, P_MAXIMUM_FORCE,
                          P_STALL_RISE, SATURATED, X_COMMAND, X_FRICTION, X_LIFT_FRAMES, X_LIFT_GRIP, X_LIFT_HELD,
                          X_LIFT_HOLD, X_LIFT_SIZED, X_LIFT_STEP, X_LIFT_TEST, X_LIFT_UNJUDGED, X_LIFT_USE, X_PHASE,
                          X_PROBING, _first_max, _first_min, _force_scale)

# the lift's test (``_lift_test``): a step up of the grip by this fraction, held for a watch window. Half: a held
# load's nu then falls by log(1.5) = 0.41, and the verdict halfway (0.2) clears the noise margin at the contact
# minimum (0.09-0.12 of nu for the traced bottle at 0.5-0.9 N, docs/design.md sec. 12)
LIFT_STEP = 0.5
# the step where a blind probe asks for the test (``_lift_step``): as large as its verdict needs over nu's noise, at
# least this (a rise the verdict can see: twice force_drop, with room), at most LIFT_STEP - the grip there can be far
# above the contact minimum (blind eclairs at 7 N: a step of half took 3 tuning eclairs past their crush force)
LIFT_STEP_LEAST = 0.15
# ... and a grip that grew by this fraction over the window while nu sat at the lift's level or above: sliding just
# above the level, the load follows the grip and the demand asks only mu / level more (tuning draws: 0.2 and 0.3
# alike, 0.5 one drop more)
LIFT_GROWTH = 0.3
# the lift test's states; ASKED: a probe that could not rely on its bump test did not start, and asked for the test
LIFT_UNTRIED, LIFT_STEPPED, LIFT_DONE, LIFT_ASKED = 0.0, 1.0, 2.0, 3.0


@njit_cached
def _load_follows_grip(parameters, now_use, now_grip, then_use, then_grip):
    """Did the carried load follow the grip, from the utilisation nu and the grip now and at a reference: 1 if the
    grip grew and nu did not fall with it (sliding: the load follows the grip and nu stays), 0 if nu fell with it
    (held: the load stays and nu falls like 1 / P), judged halfway between with no margin towards 'held' (a sliding
    array whose read nu moved with the grip was called held inside a margin); -1 if the grip did not grow by twice
    force_drop (no verdict). The lift test's step and the test that an array still slides after a slip."""
    if not (then_use > 0.0 and then_grip > 0.0 and now_use > 0.0 and now_grip > 0.0):
        return -1
    rise = math.log(now_grip / then_grip)
    if rise < math.log(1.0 + 2.0 * parameters[P_FORCE_DROP]):
        return -1
    return 1 if math.log(now_use / then_use) > -0.5 * rise else 0


@njit_cached(inline="always")
def _lift_step(use, use_noise):
    """The grip factor [-] of the lift test a blind probe asks for: a held load's nu falls by log(factor) = six of
    nu's noise margins, so the verdict halfway clears three; within 1 + LIFT_STEP_LEAST ... 1 + LIFT_STEP."""
    return _first_max(_first_min(math.exp(6.0 * use_noise / use), 1.0 + LIFT_STEP), 1.0 + LIFT_STEP_LEAST)


@njit_cached
def _lift_test(parameters, scalars, signature, count, use_now, use_then, use_noise, use_spread, full, frames,
               at_minimum):
    """The lift's test of a load that does not come on (once per lift): the grip's utilisation nu has sat below the
    lift's level for a window, neither rising nor falling (a load that eases after the lift's acceleration lowers
    nu while the grip lags: that is not it) - the grip is above what the load asks, which a held load
    corrects within the loop's time (nu ~ 1 / P rises to the level as the grip sinks), but bumps that slide carry
    mu of any grip and keep nu = mu. The grip steps up by LIFT_STEP and is held there for a window: held, the load
    stays and nu falls like 1 / P; sliding, the load follows the grip and nu stays. Halfway between is the verdict,
    and either must hold for confirm_frames frames in a row: sliding marks the array's slip
    (signature[1, count]: mu_hat becomes nu), held lets the grip go back to its demand. Not while the probe runs (it
    lowers the grip on purpose); a test still running when the lift ends is judged on into the hold. The same test
    runs when nu has sat still at the level or above while the grip grew by LIFT_GROWTH over the window: bumps that
    slide at a friction just above the level keep nu = mu and the demand creeps up with the grip. The test of a load
    below the level starts only where the lift's stall test cannot see: blind in its noise, or not judging at all
    because the grip is at the contact minimum (``at_minimum``: the stall test judges only a load-driven grip). The
    test of a creeping grip starts wherever one is seen, nu still within the larger of its noise margin and twice
    STALL_RISE of nu (a margin between one and two STALL_RISE leaves the stall test nothing to pass, yet does not make
    it blind); where the stall test is neither blind nor idle at the minimum, with a step sized to nu's noise
    (``_lift_step``) instead of one of half. It also starts, whatever nu does, where a probe that could not rely on
    its bump test did not start (LIFT_ASKED, ``_carry_step``): nu read at the level is a held load's or one sliding at
    a friction read there, and only the step tells them apart - a step sized to nu's noise there too. A slip confirmed
    while a sized step is held reads the larger of nu at the step (X_LIFT_USE) and nu then (``_slip_law``;
    X_LIFT_SIZED marks the test): the test began where nu sat at the level. A step the sensed grip does not follow by
    twice force_drop gives no verdict, which is not 'held': after a whole window without one the grip steps up again
    by the same factor, up to the actuator's limit, where the test ends (nothing is left to step)."""
    level = parameters[P_LIFT_SAFETY] * scalars[X_FRICTION]
    if scalars[X_LIFT_TEST] == LIFT_UNTRIED or scalars[X_LIFT_TEST] == LIFT_ASKED:
        still = abs(use_now[0] - use_then[0]) <= use_noise
        below = max(use_now[0], use_then[0]) + use_noise < level
        # nu 'still' for a creeping grip: within its noise margin, and never within less than twice the rise the
        # stall test allows (a sliding array's read nu wobbles with the estimator's error as its loads shift)
        still_band = _first_max(use_noise, 2.0 * parameters[P_STALL_RISE] * use_now[0])
        creeping = (use_now[0] >= level - use_noise and use_spread <= still_band
                    and abs(use_now[0] - use_then[0]) <= still_band
                    and use_now[1] >= (1.0 + LIFT_GROWTH) * use_then[1])
        # below the level, only where the lift's own stall test cannot see: its noise margin more than twice the
        # rise it allows, or it does not judge at all - the grip at the contact minimum (a quiet array's margin is
        # small there, and an object sliding at that grip was seen by neither test)
        stall_cannot_see = use_noise > 2.0 * parameters[P_STALL_RISE] * use_now[0] or at_minimum
        readable = use_now[1] > 0.0 and full and MINIMUM_FRICTION < use_now[0]
        asked = scalars[X_LIFT_TEST] == LIFT_ASKED
        unseen = (scalars[X_PHASE] == LIFT and scalars[X_PROBING] == 0.0 and MINIMUM_FRICTION < use_then[0]
                  and ((stall_cannot_see and still and below) or creeping))
        if readable and (asked or unseen):
            # a step of half where the stall test is blind or idle; sized to nu's noise where it could see, as for an
            # asked test: half took light, moment-loaded eclairs whose moment was still coming on past their crush
            # force (docs/design.md sec. 12)
            sized = asked or (creeping and not stall_cannot_see)
            scalars[X_LIFT_STEP] = _lift_step(use_now[0], use_noise) if sized else 1.0 + LIFT_STEP
            scalars[X_LIFT_SIZED] = 1.0 if sized else 0.0
            scalars[X_LIFT_TEST], scalars[X_LIFT_FRAMES], scalars[X_LIFT_HELD] = LIFT_STEPPED, 0.0, 0.0
            scalars[X_LIFT_UNJUDGED] = 0.0
            # the step's reference grip: the command in the sensed scale, which the slowly filtered grip lags when
            # the grip was growing (the lag would pass for part of the step's rise)
            scalars[X_LIFT_USE] = use_now[0]
            scalars[X_LIFT_GRIP] = _first_max(use_now[1], scalars[X_COMMAND] / _force_scale(scalars))
            scalars[X_LIFT_HOLD] = _first_min(scalars[X_COMMAND] * scalars[X_LIFT_STEP], parameters[P_MAXIMUM_FORCE])
            scalars[X_COMMAND] = scalars[X_LIFT_HOLD]
    elif scalars[X_LIFT_TEST] == LIFT_STEPPED:
        scalars[X_LIFT_FRAMES] += 1.0
        if scalars[X_LIFT_FRAMES] >= frames:            # judged each frame until held, or the slip is confirmed
            verdict = _load_follows_grip(parameters, use_now[0], use_now[1], scalars[X_LIFT_USE], scalars[X_LIFT_GRIP])
            if verdict > 0:
                signature[1, count] = True
                scalars[X_LIFT_HELD] = scalars[X_LIFT_UNJUDGED] = 0.0
            elif verdict == 0:
                scalars[X_LIFT_UNJUDGED] = 0.0
                scalars[X_LIFT_HELD] += 1.0
                if scalars[X_LIFT_HELD] >= parameters[P_CONFIRM_FRAMES]:
                    scalars[X_LIFT_TEST] = LIFT_DONE
            else:
                # no verdict: the sensed grip did not follow the step (at the contact minimum the estimated force
                # resolves it poorly). Not seen is not held: after a whole window without one the grip steps up
                # again - unless it is at the actuator's limit, where nothing is left to step and the test ends
                scalars[X_LIFT_HELD] = 0.0
                scalars[X_LIFT_UNJUDGED] += 1.0
                if scalars[X_LIFT_UNJUDGED] >= frames:
                    scalars[X_LIFT_UNJUDGED] = 0.0
                    if scalars[X_LIFT_HOLD] >= SATURATED * parameters[P_MAXIMUM_FORCE]:
                        scalars[X_LIFT_TEST] = LIFT_DONE
                    else:
                        scalars[X_LIFT_HOLD] = _first_min(scalars[X_LIFT_HOLD] * scalars[X_LIFT_STEP],
                                                          parameters[P_MAXIMUM_FORCE])
                        scalars[X_COMMAND] = _first_max(scalars[X_COMMAND], scalars[X_LIFT_HOLD])
