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

__all__ = ["array_margin", "fingertip_need", "slip_signature", "low_pass_frame"]

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
def fingertip_need(centres, force, ratio, contact, rotational, slip_centre, full_search, warm_step):
    """F / lambda*(mu = 1) [N] of the more loaded fingertip (the module docstring's demand at mu = 1); without
    rotational detection |F_t| of that fingertip. ``slip_centre`` (2, 2) [mm] holds each fingertip's last slip
    centre (inf: none): a full search when ``full_search`` or none, else a warm start near it (updated in place)."""
    count = centres.shape[0]
    finger, largest = 0, -1.0
    for f in range(2):
        total = 0.0
        for i in range(count):
            total += force[f, i] * math.hypot(ratio[f, i, 0], ratio[f, i, 1])
        if total > largest:
            finger, largest = f, total
    used = np.empty(count)
    load = np.zeros(2)
    torque = 0.0
    for i in range(count):
        used[i] = force[finger, i] if contact[finger, i] else 0.0
        q_x, q_y = force[finger, i] * ratio[finger, i, 0], force[finger, i] * ratio[finger, i, 1]
        load[0] += q_x
        load[1] += q_y
        torque += centres[i, 0] * q_y - centres[i, 1] * q_x
    if not rotational:
        return math.hypot(load[0], load[1])
    if full_search or not math.isfinite(slip_centre[finger, 0]):
        margin, centre_x, centre_y = array_margin(centres, used, load, torque, 1.0)
    else:
        margin, centre_x, centre_y = array_margin(centres, used, load, torque, 1.0, slip_centre[finger, 0],
                                                  slip_centre[finger, 1], warm_step, 8)
    slip_centre[finger, 0], slip_centre[finger, 1] = centre_x, centre_y
    return used.sum() / margin if margin > 0.0 else math.inf


@njit_cached
def slip_signature(force, ratio, contact, force_then, ratios_then, judged, plateau, second_frame, hold_ratio,
                   total_drop, force_drop, stick_exponent, loaded_share, force_share, noise):
    """The slip watch's tests on one frame (the module docstring).

    Returns signature (2, k + 1) bool (per bump, and the grasp's total in [0, k]), the total ratio (a sliding
    fingertip's |sum q| / sum P), the largest ratio of the bearing bumps and |rho_i| (2, k). ``plateau`` (|total
    load| [N], sum P [N]) is set on the first call (negative: unset); bumps are judged only when ``judged``, against
    the frame ``watch_frames`` ago (force_then, ratios_then); a bump's ratio must stay below the slip bound by
    ``noise`` (2, k) [-] too (a margin over its estimate's noise)."""
    count = force.shape[1]
    signature = np.zeros((2, count + 1), dtype=np.bool_)
    ratios = np.empty((2, count))
    total_x = total_y = total_force = total_ratio = bearing = 0.0
    mean_force = np.zeros(2)
    largest = np.zeros(2)
    for f in range(2):
        tip_x = tip_y = finger_force = 0.0
        contacts = 0
        for i in range(count):
            ratios[f, i] = math.hypot(ratio[f, i, 0], ratio[f, i, 1])
            tip_x += force[f, i] * ratio[f, i, 0]
            tip_y += force[f, i] * ratio[f, i, 1]
            finger_force += force[f, i]
            if contact[f, i]:
                contacts += 1
                largest[f] = max(largest[f], ratios[f, i])
        total_x += tip_x if f == 0 else second_frame[0] * tip_x
        total_y += tip_y if f == 0 else second_frame[1] * tip_y
        total_force += finger_force
        mean_force[f] = finger_force / max(contacts, 1)
        if finger_force > 0.0:
            total_ratio = max(total_ratio, math.hypot(tip_x, tip_y) / finger_force)
    for f in range(2):
        for i in range(count):
            if contact[f, i] and force[f, i] >= force_share * mean_force[f]:
                bearing = max(bearing, ratios[f, i])
    total_load = math.hypot(total_x, total_y)
    if plateau[0] < 0.0:
        plateau[0], plateau[1] = total_load, total_force
    signature[0, count] = (plateau[0] > 0.0 and total_load <= (1.0 - total_drop) * plateau[0]
                           and total_force <= (1.0 - total_drop) * plateau[1] and total_ratio > hold_ratio)
    if judged:
        for f in range(2):
            for i in range(count):
                if not (contact[f, i] and ratios_then[f, i] > 0.0 and force_then[f, i] > 0.0
                        and ratios[f, i] > hold_ratio and ratios[f, i] >= loaded_share * largest[f]
                        and force[f, i] >= force_share * mean_force[f]):
                    continue
                fallen = force[f, i] / force_then[f, i]
                signature[f, i] = fallen <= 1.0 - force_drop and \
                    ratios[f, i] + noise[f, i] <= ratios_then[f, i] * fallen ** (-stick_exponent)
    return signature, total_ratio, bearing, ratios


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
