"""Compiled estimators of the closed loop (the belief side): per-bump loads read back with the estimator's own sensor
model (``read_loads``), and the paper's estimator - per-bump force and CoP, reference, rigid fit.

The latter are the same computations as ``controller.estimation.estimator.bump_positions`` (force and centre of
pressure per bump region above a noise gate), the bench's reference table and
``controller.estimation.rigid_transform.fit_rigid_transform`` (2D Procrustes), for one frame of two fingertips: the
closed loop reads them at 100 Hz, where the vectorised library functions spend milliseconds in array set-up per frame.
The tests check them against the library functions.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached


@njit_cached
def bump_forces_and_cops(readings, region, node_x, node_y, floor, pool, centres, force, cop):
    """Per-bump force [N] (k,) and CoP [mm] (k, 2) of one frame (n_nodes,): readings of open gates summed over each
    bump's nodes (``region[n]`` = bump of node n, -1 for none); a bump with no force gets its centre. A node's gate
    is open when the sum over its pool (``pool[n]``: the m x m nodes around it, -1 off the array) exceeds
    ``floor`` x sqrt(the pool's nodes on the array) (``controller.estimation.gated_weights``)."""
    force[:] = 0.0
    cop[:] = 0.0
    side = math.sqrt(pool.shape[1])
    for node in range(readings.size):
        bump = region[node]
        if bump < 0:
            continue
        value = readings[node]
        if side == 1.0:
            pooled, members = value, 1.0
        else:
            pooled = members = 0.0
            for member in pool[node]:
                if member >= 0:
                    pooled += readings[member]
                    members += 1.0
        if not pooled > floor * math.sqrt(members):
            continue
        force[bump] += value
        cop[bump, 0] += value * node_x[node]
        cop[bump, 1] += value * node_y[node]
    for bump in range(force.size):
        if force[bump] > 0.0:
            cop[bump, 0] /= force[bump]
            cop[bump, 1] /= force[bump]
        else:
            cop[bump, 0], cop[bump, 1] = centres[bump, 0], centres[bump, 1]


@njit_cached
def rigid_fit(reference, current, used):
    """Least-squares rotation [rad] and translation [mm] mapping ``reference`` (k, 2) onto ``current`` (k, 2) over
    the ``used`` bumps: (count, rotation, t_x, t_y); zeros when fewer than two bumps are used."""
    count = 0
    reference_x = reference_y = current_x = current_y = 0.0
    for i in range(used.size):
        if used[i]:
            count += 1
            reference_x += reference[i, 0]
            reference_y += reference[i, 1]
            current_x += current[i, 0]
            current_y += current[i, 1]
    if count < 2:
        return count, 0.0, 0.0, 0.0
    reference_x, reference_y, current_x, current_y = (reference_x / count, reference_y / count, current_x / count,
                                                      current_y / count)
    cross = dot = 0.0
    for i in range(used.size):
        if used[i]:
            ax, ay = reference[i, 0] - reference_x, reference[i, 1] - reference_y
            bx, by = current[i, 0] - current_x, current[i, 1] - current_y
            cross += ax * by - ay * bx
            dot += ax * bx + ay * by
    rotation = math.atan2(cross, dot)
    cos, sin = math.cos(rotation), math.sin(rotation)
    return (count, rotation, current_x - (cos * reference_x - sin * reference_y),
            current_y - (sin * reference_x + cos * reference_y))


@njit_cached
def reference_at(force, table_force, table_cop, reference):
    """Unsheared CoP (k, 2) [mm] of each bump interpolated in log force on the bench table (n,) / (n, k, 2)."""
    last = table_force.size - 1
    logarithm = np.empty(table_force.size)                   # the table's log forces, once per call
    for entry in range(table_force.size):
        logarithm[entry] = math.log(table_force[entry])
    for bump in range(force.size):
        value = math.log(max(force[bump], table_force[0]))
        if value >= logarithm[last]:
            lower, weight = last - 1, 1.0
        else:
            lower = 0
            while logarithm[lower + 1] <= value:
                lower += 1
            weight = (value - logarithm[lower]) / (logarithm[lower + 1] - logarithm[lower])
        for axis in range(2):
            reference[bump, axis] = ((1.0 - weight) * table_cop[lower, bump, axis]
                                     + weight * table_cop[lower + 1, bump, axis])


@njit_cached
def estimate_frame(readings, region, node_x, node_y, node_floor, pool, threshold, centres, table_force, table_cop,
                   cop_gain_to_shear, force, shift, fit):
    """The paper's estimator on one frame of both fingertips' readings (2, n_nodes) [N]: per-bump force (2, k)
    [N] and CoP shift (2, k, 2) [mm] against the unsheared reference at the bump's force (0 where the force is at
    most ``threshold``), and fit (2, 4) = (bumps used, rotation [rad], t_x, t_y [mm]) of the eq. 9 fit of
    u_i = g shift_i (``SensingChain.sense``)."""
    count = centres.shape[0]
    cop = np.empty((count, 2))
    reference = np.empty((count, 2))
    current = np.empty((count, 2))
    used = np.empty(count, dtype=np.bool_)
    for f in range(2):
        bump_forces_and_cops(readings[f], region, node_x, node_y, node_floor, pool, centres, force[f], cop)
        reference_at(force[f], table_force, table_cop, reference)
        for i in range(count):
            used[i] = force[f, i] > threshold
            for axis in range(2):
                shift[f, i, axis] = cop[i, axis] - reference[i, axis] if used[i] else 0.0
                current[i, axis] = reference[i, axis] + cop_gain_to_shear * shift[f, i, axis]
        number, rotation, t_x, t_y = rigid_fit(reference, current, used)
        fit[f, 0], fit[f, 1], fit[f, 2], fit[f, 3] = number, rotation, t_x, t_y


@njit_cached
def couple_arm(bump_force, arm, slope, limit):
    """h(P) [mm] of ``ReducedParameters.couple_arm_at``: limit + (arm - limit) / (1 + slope P / (arm - limit))."""
    if slope == 0.0:
        return arm
    excess = arm - limit
    return limit + excess / (1.0 + (slope / excess) * max(bump_force, 0.0))


@njit_cached
def load_ratio_noise(load_force, threshold, couple_law, noise_std, couple_noise, out):
    """Noise (2, k) [-] of each bump's load ratio into ``out``: the node noise ``noise_std`` [N] (measured at rest)
    read back through the couple, noise_std c_i / (h(P_i) P_i) for a loaded bump (P_i > ``threshold``), 0 else."""
    for f in range(load_force.shape[0]):
        for i in range(load_force.shape[1]):
            value = load_force[f, i]
            if value > threshold:
                out[f, i] = noise_std * couple_noise[i] / (couple_arm(value, couple_law[0], couple_law[1],
                                                                      couple_law[2]) * value)
            else:
                out[f, i] = 0.0


@njit_cached
def read_loads(readings, offset, couple_law, inverse, threshold, couple_force, couple_table, corrected, load_force,
               load_ratio):
    """The per-bump loads of both fingertips' readings (2, n) [N] (``SensingChain.sense``): ``corrected`` = readings
    less the tared ``offset`` (2, n); theta = A^+ corrected with the estimator's model (inverse (3k, n)); the couple
    an unsheared bump shows at its force (the bench's presses: ``couple_force`` (m,) [N], ``couple_table`` (m, k, 2)
    [N mm], interpolated in log force) taken off; load_force (2, k) [N] and load_ratio (2, k, 2) [-] = M / (h(P) P),
    0 where the force is at most ``threshold``; couple_law = (h_0, kappa, h_inf, g) of the estimator's arm h(P)."""
    count = load_force.shape[1]
    theta = np.empty(3 * count)
    zero = np.empty((count, 2))
    for f in range(2):
        for node in range(readings.shape[1]):
            corrected[f, node] = readings[f, node] - offset[f, node]
        for j in range(3 * count):
            value = 0.0
            for node in range(readings.shape[1]):
                value += inverse[j, node] * corrected[f, node]
            theta[j] = value
        for i in range(count):
            load_force[f, i] = theta[i]
        reference_at(load_force[f], couple_force, couple_table, zero)
        for i in range(count):
            force = theta[i]
            if force > threshold:
                scale = 1.0 / (couple_arm(force, couple_law[0], couple_law[1], couple_law[2]) * force)
                load_ratio[f, i, 0] = (theta[count + i] - zero[i, 0]) * scale
                load_ratio[f, i, 1] = (theta[2 * count + i] - zero[i, 1]) * scale
            else:
                load_ratio[f, i, 0] = load_ratio[f, i, 1] = 0.0


@njit_cached
def sense_frame(readings, offset, couple_law, inverse, threshold, couple_force, couple_table, region, node_x, node_y,
                node_floor, pool, centres, table_force, table_cop, cop_gain_to_shear, corrected, load_force,
                load_ratio, force, shift, fit):
    """One sensor frame of both fingertips' readings (2, n) [N]: ``read_loads`` then ``estimate_frame`` on the tared
    readings; returns the paper's inputs (u_x [mm], theta [rad], bumps in contact on the fingertip that sees more),
    the larger of the two fingertips."""
    read_loads(readings, offset, couple_law, inverse, threshold, couple_force, couple_table, corrected, load_force,
               load_ratio)
    estimate_frame(corrected, region, node_x, node_y, node_floor, pool, threshold, centres, table_force, table_cop,
                   cop_gain_to_shear, force, shift, fit)
    translation = rotation = 0.0
    contacts = 0
    for f in range(2):
        count = 0
        for i in range(force.shape[1]):
            if force[f, i] > threshold:
                count += 1
        contacts = max(contacts, count)
        if fit[f, 0] >= 2:
            translation = max(translation, math.hypot(fit[f, 2], fit[f, 3]))
            rotation = max(rotation, abs(fit[f, 1]))
    return translation, rotation, contacts
