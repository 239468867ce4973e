"""Compiled kernels of the incipient-slip controller (``controller.control.incipient_slip``): the slip margin of an
array of Coulomb point contacts, a fingertip's grip demand, the slip signature of one sensor frame and the frame's
low-pass.

numba, because they run once per sensor frame on a few dozen bumps inside the closed loop, where numpy's per-call
overhead is larger than the arithmetic (a direction search over slip centres is not a vector operation).
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

__all__ = ["array_margin", "fingertip_need", "slip_signature", "low_pass_frame", "carried_wrench", "trend_spread",
           "dominant_component", "tip_normal_force"]

# a held grasp's carried load still moves with its grip: the estimator's own error (its kernel and arm are not the
# plant's) and the bumps' own elasticity, whose tangential stiffness follows the grip, make it fall by about 0.25-0.6
# of a falling grip over the probe (measured in the closed loop); a grasp sliding as a whole loses it as fast as the
# grip (its friction is mu P): a load that fell by at least this share of the grip's fall slid
GROSS_SHARE = 0.8

@njit_cached
def array_margin(centres, bump_force, load, torque, friction, start_x=0.0, start_y=0.0, first_step=-1.0,
                 levels=14):
    """Slip margin lambda* [-] of an array of Coulomb point contacts, and the rotation centre (x, y) [mm] of its
    slip: the factor by which the tangential load (2,) [N] and the moment ``torque`` [N mm] about the centres'
    origin may grow before the array slides as a whole.

    Any sliding motion is a rotation about a centre c (a translation as c -> infinity); Coulomb bumps at r_i with
    normal forces P_i then dissipate mu sum P_i |r_i - c| per unit spin against the load's power |T - c x F|, so
    lambda* = min( mu sum P_i / |F|, min_c mu sum P_i |r_i - c| / |T - c x F| ) (maximum dissipation; the array's
    limit set as in ``contact.reduced``, without the bumps' own torsion, which adds about 1 % here). The centre is
    searched on a 5 x 5 grid of spacing ``first_step`` (default: the array's reach) around (start_x, start_y),
    refined ``levels`` times around the best point (14 levels: to 1e-4 of the reach). inf without load.
    """
    total = friction * bump_force.sum()
    force_norm = math.hypot(load[0], load[1])
    best, best_x, best_y = (total / force_norm if force_norm > 0.0 else math.inf), math.inf, math.inf
    step = first_step
    if step <= 0.0:
        for i in range(bump_force.size):
            step = max(step, math.hypot(centres[i, 0], centres[i, 1]))
        step = max(step, 1.0)
    centre_x, centre_y = start_x, start_y
    for _ in range(levels):                                          # the grid spans +-2 steps: halving is safe
        level, level_x, level_y = math.inf, centre_x, centre_y
        for a in range(-2, 3):
            for b in range(-2, 3):
                cx, cy = centre_x + a * step, centre_y + b * step
                power = abs(torque - (cx * load[1] - cy * load[0]))
                if not power > 0.0:
                    continue
                dissipation = 0.0
                for i in range(bump_force.size):        # sqrt, not hypot: 4x faster, no overflow at mm scales
                    dx, dy = centres[i, 0] - cx, centres[i, 1] - cy
                    dissipation += bump_force[i] * math.sqrt(dx * dx + dy * dy)
                value = friction * dissipation / power
                if value < level:
                    level, level_x, level_y = value, cx, cy
        if level < best:
            best, best_x, best_y = level, level_x, level_y
        centre_x, centre_y = level_x, level_y
        step *= 0.5
    return best, best_x, best_y


@njit_cached
def _utilisation(centres, force, ratio, contact, finger, rotational, slip_centre, full_search, warm_step):
    """1 / lambda*(mu = 1) [-] of fingertip ``finger``: the share of its friction capacity at mu = 1 its load uses
    (module docstring of incipient_slip); without rotational detection |sum q| / sum P. Scale-free: the bump
    forces' common scale cancels. Updates the fingertip's slip centre (warm starts)."""
    count = centres.shape[0]
    used = np.empty(count)
    load = np.zeros(2)
    torque = 0.0
    for i in range(count):
        used[i] = force[finger, i] if contact[finger, i] else 0.0
        q_x, q_y = used[i] * ratio[finger, i, 0], used[i] * ratio[finger, i, 1]
        load[0] += q_x
        load[1] += q_y
        torque += centres[i, 0] * q_y - centres[i, 1] * q_x
    total = used.sum()
    if total <= 0.0:
        return 0.0
    if not rotational:
        return math.hypot(load[0], load[1]) / total
    if full_search or not math.isfinite(slip_centre[finger, 0]):
        margin, centre_x, centre_y = array_margin(centres, used, load, torque, 1.0)
    else:
        margin, centre_x, centre_y = array_margin(centres, used, load, torque, 1.0, slip_centre[finger, 0],
                                                  slip_centre[finger, 1], warm_step, 8)
    slip_centre[finger, 0], slip_centre[finger, 1] = centre_x, centre_y
    return 1.0 / margin if margin > 0.0 else math.inf


@njit_cached
def fingertip_need(centres, force, ratio, contact, rotational, slip_centre, full_search, warm_step):
    """The demand of the module docstring per unit grip: nu = 1 / lambda*(mu = 1) [-] of the more used fingertip,
    so that the grip F / (s lambda*(mu_hat)) = F nu / (s mu_hat) holds the array at s of its limit, and that
    fingertip's index (-1: neither is used; its ``tip_normal_force`` is the F of the readings). ``slip_centre``
    (2, 2) [mm] holds each fingertip's last slip centre (inf: none): a full search when ``full_search`` or none, else
    a warm start near it."""
    largest, used = 0.0, -1
    for f in range(2):
        value = _utilisation(centres, force, ratio, contact, f, rotational, slip_centre, full_search, warm_step)
        if value > largest:
            largest, used = value, f
    return largest, used


@njit_cached
def tip_normal_force(force, contact, tip):
    """Fingertip ``tip``'s sensed normal force [N]: its bump forces (2, k) [N] summed over the bumps in contact."""
    total = 0.0
    for i in range(force.shape[1]):
        total += force[tip, i] if contact[tip, i] else 0.0
    return total


@njit_cached
def carried_wrench(force, ratio, contact, centres, second_frame):
    """What the grasp carries, from both fingertips' bump forces (2, k) [N] and load ratios (2, k, 2) [-]: the
    total tangential force |sum q| [N], the total moment |sum r x q| [N mm] about the arrays' centres (the second
    fingertip's axes turned into the first's: a mirrored frame reverses its moments) and the total normal force
    sum P [N]; only bumps in ``contact``."""
    total_x = total_y = moment = normal = 0.0
    mirror = second_frame[0] * second_frame[1]
    for f in range(2):
        tip_x = tip_y = tip_moment = 0.0
        for i in range(force.shape[1]):
            if not contact[f, i]:
                continue
            q_x, q_y = force[f, i] * ratio[f, i, 0], force[f, i] * ratio[f, i, 1]
            tip_x += q_x
            tip_y += q_y
            tip_moment += centres[i, 0] * q_y - centres[i, 1] * q_x
            normal += force[f, i]
        total_x += tip_x if f == 0 else second_frame[0] * tip_x
        total_y += tip_y if f == 0 else second_frame[1] * tip_y
        moment += tip_moment if f == 0 else mirror * tip_moment
    return math.hypot(total_x, total_y), abs(moment), normal


@njit_cached
def slip_signature(force, ratio, fast_force, fast_ratio, contact, centres, force_then, ratios_then, judged,
                   watch_total, reference, carried, second_frame, hold_ratio, total_drop, force_drop, stick_exponent,
                   loaded_share, force_share, noise, wrench_noise, reach, use_now, use_then, use_noise, use_mode,
                   use_level, stall_rise, stall_fraction):
    """The slip watch's tests on one frame (the module docstring).

    Returns signature (2, k + 1) bool (per bump, and the grasp's gross slip in [0, k]), the total ratio (a sliding
    fingertip's |sum q| / sum P), the largest ratio of the bearing bumps, |rho_i| (2, k) and, per fingertip (2,), the
    largest |rho_i| in contact and the mean bump force [N] (``watched``'s references).

    Bumps (slowly filtered ``force``, ``ratio``) are judged only when ``judged``, against the frame ``watch_frames`` ago
    (force_then, ratios_then): a bump whose force fell by ``force_drop`` while its ratio rose less than a stuck bump's
    (P^-``stick_exponent``, with a margin ``noise`` (2, k) [-]: its estimate's noise, or its swing) slides. Gross slip
    (slow signals, below the object's swing in the fingers; when ``watch_total``): the carried load's dominant component
    - the total force F or the moment T / ``reach`` - and the normal force fell below ``reference`` (the largest F, T /
    reach and sum P [N] of the last frames; negative: none yet) by ``total_drop`` and by the margin ``wrench_noise`` [N]
    (noise, or swing): held, the grasp carries a constant load whatever its grip; sliding, its friction falls as fast as
    the grip (a short window: the estimator's own error of the load drifts with the grip far slower). ``carried`` (3,)
    receives this frame's (F, T / reach, sum P). The array as a whole (slowly filtered), in [1, k]: its utilisation nu
    and normal force ``use_now`` (2,) against ``use_then`` (2,) of the frame ``watch_frames`` ago. ``use_mode`` 1 (a
    probe): the same test as a bump's with the margin ``use_noise`` [-] (noise, or swing) - a grasp that slides as a
    whole keeps nu = mu while its grip falls, held its nu rises like 1 / P. ``use_mode`` 2 (a lift): the grip holds nu
    at ``use_level``; nu stalled (moved less than ``stall_rise`` over the window) below ``stall_fraction`` of it while
    the grip sank, or anywhere while the grip rose by ``force_drop``, is a load that follows the grip: the bumps slide
    at a friction the prior does not cover (held, nu rises to the level as the weight comes off the table - the grip
    grows with it - and then stays there at a grip that no longer grows)."""
    count = force.shape[1]
    signature = np.zeros((2, count + 1), dtype=np.bool_)
    ratios = np.empty((2, count))
    total_ratio = bearing = 0.0
    mean_force = np.zeros(2)
    largest = np.zeros(2)
    for f in range(2):
        tip_x = tip_y = finger_force = 0.0
        contacts = 0
        for i in range(count):
            ratios[f, i] = math.hypot(ratio[f, i, 0], ratio[f, i, 1])
            tip_x += fast_force[f, i] * fast_ratio[f, i, 0]
            tip_y += fast_force[f, i] * fast_ratio[f, i, 1]
            finger_force += fast_force[f, i]
            if contact[f, i]:
                contacts += 1
                largest[f] = max(largest[f], ratios[f, i])
        mean_force[f] = force[f].sum() / max(contacts, 1)
        if finger_force > 0.0:
            total_ratio = max(total_ratio, math.hypot(tip_x, tip_y) / finger_force)
    for f in range(2):
        for i in range(count):
            if contact[f, i] and force[f, i] >= force_share * mean_force[f]:
                bearing = max(bearing, ratios[f, i])
    load, moment, normal = carried_wrench(force, ratio, contact, centres, second_frame)
    # the component of the carried load that dominates: its force or its moment over the array's reach (with a
    # moment, the bumps' forces also carry an internal, grip-dependent part; the moment is the object's own)
    carried[0], carried[1], carried[2] = load, moment / reach, normal
    if watch_total and reference[2] > 0.0:
        component = dominant_component(reference)
        now, then = carried[component], reference[component]
        load_fall, grip_fall = 1.0 - now / then if then > 0.0 else 0.0, 1.0 - normal / reference[2]
        # fell by the threshold, and at least GROSS_SHARE as fast as the grip
        signature[0, count] = (then > 0.0 and now <= then - max(total_drop * then, wrench_noise)
                               and grip_fall >= total_drop and load_fall >= GROSS_SHARE * grip_fall
                               and total_ratio > hold_ratio)
    if use_mode == 1 and use_then[0] > 0.0 and use_then[1] > 0.0 and use_now[0] > hold_ratio:
        fallen = use_now[1] / use_then[1]
        signature[1, count] = fallen <= 1.0 - force_drop and \
            use_now[0] + use_noise <= use_then[0] * fallen ** (-stick_exponent)
    elif use_mode == 2 and use_then[0] > 0.0 and use_then[1] > 0.0:
        # a regulated lift keeps nu at its level; nu stuck away from it for a window - below it while the grip sank,
        # or above it while the grip rose and could not pull it down - is a load held by friction alone: sliding
        stalled = abs(use_now[0] / use_then[0] - 1.0) + use_noise / use_now[0] <= stall_rise
        grew = use_now[1] > (1.0 + force_drop) * use_then[1]
        signature[1, count] = stalled and ((0.3 * use_level < use_now[0] < stall_fraction * use_level) or grew)
    if judged:
        for f in range(2):
            for i in range(count):
                if not (watched(contact[f, i], ratios[f, i], force[f, i], largest[f], mean_force[f], loaded_share,
                                force_share)
                        and ratios_then[f, i] > 0.0 and force_then[f, i] > 0.0 and ratios[f, i] > hold_ratio):
                    continue
                fallen = force[f, i] / force_then[f, i]
                signature[f, i] = fallen <= 1.0 - force_drop and \
                    ratios[f, i] + noise[f, i] <= ratios_then[f, i] * fallen ** (-stick_exponent)
    return signature, total_ratio, bearing, ratios, largest, mean_force


@njit_cached(inline="always")
def dominant_component(reference):
    """Which of the carried wrench's references (F, T / reach, ...) the gross test watches: the larger of the two."""
    return 1 if reference[1] > reference[0] else 0


@njit_cached
def trend_spread(values, written, skip=0):
    """The rms spread of a ring buffer's values about their least-squares line (same unit): what moves a signal over
    the window besides its trend (noise, and the object's swing in the fingers). Over the min(written, len) last
    values less the newest ``skip``; 0 for fewer than three."""
    size = values.shape[0]
    count = min(written, size) - skip
    if count < 3:
        return 0.0
    start = written - skip - count
    middle = 0.5 * (count - 1)
    mean = slope = spread = squares = 0.0
    for j in range(count):
        mean += values[(start + j) % size]
    mean /= count
    for j in range(count):
        slope += (j - middle) * (values[(start + j) % size] - mean)
        squares += (j - middle) ** 2
    slope /= squares
    for j in range(count):
        spread += (values[(start + j) % size] - mean - slope * (j - middle)) ** 2
    return math.sqrt(spread / count)


@njit_cached(inline="always")
def watched(in_contact, ratio, force, largest, mean_force, loaded_share, force_share):
    """Is a bump one the slip watch judges: in contact, its |rho_i| at least ``loaded_share`` of its fingertip's
    largest and its force at least ``force_share`` of the fingertip's mean (``slip_signature``'s references)."""
    return in_contact and ratio >= loaded_share * largest and force >= force_share * mean_force


@njit_cached
def low_pass_frame(gain, force, ratio, contact, previous_force, previous_ratio, output_force, output_ratio,
                   restart):
    """One step of the first-order Tustin low-pass y_k = b (x_k + x_{k-1}) + (1 - 2 b) y_{k-1} (``filters``) on the
    bumps' forces and ratios, zero off contact, in place; ``restart`` sets input and output to the sample."""
    for f in range(force.shape[0]):
        for i in range(force.shape[1]):
            new = force[f, i] if contact[f, i] else 0.0
            if restart:
                output_force[f, i] = new
            else:
                output_force[f, i] = gain * (new + previous_force[f, i]) + (1.0 - 2.0 * gain) * output_force[f, i]
            previous_force[f, i] = new
            for axis in range(2):
                new = ratio[f, i, axis] if contact[f, i] else 0.0
                if restart:
                    output_ratio[f, i, axis] = new
                else:
                    output_ratio[f, i, axis] = gain * (new + previous_ratio[f, i, axis]) + \
                        (1.0 - 2.0 * gain) * output_ratio[f, i, axis]
                previous_ratio[f, i, axis] = new
