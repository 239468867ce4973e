"""Compiled sensing of the closed loop: base-pressure kernels -> sensor cells, per-bump force and CoP, rigid fit.

The same computations as ``ReducedFingertip.base_pressure`` sampled by ``controller.sensor.sample`` (paraboloid
kernels normalised on the grid, integrated exactly over the cells by the cell-force operator), as
``controller.estimator.bump_positions`` (force and centre of pressure per bump region above a noise gate) and as
``controller.rigid_transform.fit_rigid_transform`` (2D Procrustes), for one fingertip frame at a time: the closed
loop reads 2 fingertips at 100 Hz, where the vectorised library functions spend milliseconds in array set-up per
frame. The tests check both against the library functions. A kernel only visits the grid points under its support,
and the cell operator is stored by grid point (CSC) so each point scatters into its few cells.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def kernel_readings(readings, x0, y0, spacing, nx, ny, centre_x, centre_y, width, force, indptr, indices, weights):
    """Cell readings [N] (n_cells,) of sum_i P_i K((x - c_i) / w_i) / (h^2 sum_grid K), K(r) = max(1 - r^2, 0).

    Grid: x0 + i h, y0 + j h (i < nx, j < ny), point j nx + i; (indptr, indices, weights): the cell-force operator
    in CSC form (column = grid point). Bumps with P_i <= 0 add nothing.
    """
    readings[:] = 0.0
    for bump in range(force.size):
        if not force[bump] > 0.0:
            continue
        cx, cy, w = centre_x[bump], centre_y[bump], width[bump]
        low_x = max(int(math.ceil((cx - w - x0) / spacing)), 0)
        high_x = min(int(math.floor((cx + w - x0) / spacing)), nx - 1)
        low_y = max(int(math.ceil((cy - w - y0) / spacing)), 0)
        high_y = min(int(math.floor((cy + w - y0) / spacing)), ny - 1)
        size = max(high_x - low_x + 1, 0) * max(high_y - low_y + 1, 0)
        values, points = np.empty(size), np.empty(size, dtype=np.int64)
        used, total = 0, 0.0
        for j in range(low_y, high_y + 1):
            dy = (y0 + j * spacing - cy) / w
            for i in range(low_x, high_x + 1):
                dx = (x0 + i * spacing - cx) / w
                value = 1.0 - dx * dx - dy * dy
                if value > 0.0:
                    values[used], points[used] = value, j * nx + i
                    used += 1
                    total += value
        if not total > 0.0:
            continue
        scale = force[bump] / (total * spacing * spacing)
        for n in range(used):
            point = points[n]
            for entry in range(indptr[point], indptr[point + 1]):
                readings[indices[entry]] += weights[entry] * scale * values[n]


@njit(cache=True)
def bump_forces_and_cops(readings, region, node_x, node_y, floor, centres, force, cop):
    """Per-bump force [N] (k,) and CoP [mm] (k, 2) of one frame (n_nodes,): readings above ``floor`` summed over
    each bump's nodes (``region[n]`` = bump of node n, -1 for none); a bump with no force gets its centre."""
    force[:] = 0.0
    cop[:] = 0.0
    for node in range(readings.size):
        bump = region[node]
        value = readings[node]
        if bump < 0 or not value > floor:
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


@njit(cache=True)
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


@njit(cache=True)
def reference_at(force, table_force, table_cop, reference):
    """Unsheared CoP (k, 2) [mm] of each bump interpolated in log force on the bench table (n,) / (n, k, 2)."""
    last = table_force.size - 1
    for bump in range(force.size):
        value = math.log(max(force[bump], table_force[0]))
        if value >= math.log(table_force[last]):
            lower, weight = last - 1, 1.0
        else:
            lower = 0
            while math.log(table_force[lower + 1]) <= value:
                lower += 1
            weight = (value - math.log(table_force[lower])) / (math.log(table_force[lower + 1])
                                                                 - math.log(table_force[lower]))
        for axis in range(2):
            reference[bump, axis] = ((1.0 - weight) * table_cop[lower, bump, axis]
                                     + weight * table_cop[lower + 1, bump, axis])


@njit(cache=True)
def kernel_geometry(bump_force, radius, shear, tangential, centres, kernel_spread, cop_gain, moment_arm, max_shift,
                    centre_x, centre_y, width):
    """Kernel centres [mm] and widths [mm] of ``ReducedFingertip.base_pressure`` for one fingertip (same law):
    w_i = sqrt(a_i^2 + s^2), c_i = r_i + g delta_i + h Q_i / P_i, the shift capped at ``max_shift``."""
    for i in range(bump_force.size):
        width[i] = math.sqrt(radius[i] * radius[i] + kernel_spread * kernel_spread)
        safe = bump_force[i] if bump_force[i] > 0.0 else 1.0
        shift_x = cop_gain * shear[i, 0] + moment_arm * tangential[i, 0] / safe
        shift_y = cop_gain * shear[i, 1] + moment_arm * tangential[i, 1] / safe
        length = math.hypot(shift_x, shift_y)
        scale = min(1.0, max_shift / length) if length > 0.0 else 1.0
        centre_x[i] = centres[i, 0] + scale * shift_x
        centre_y[i] = centres[i, 1] + scale * shift_y


@njit(cache=True)
def sense_frame(normal, radius, shear, tangential, noise, model, grid, indptr, indices, weights, region, node_x,
                node_y, centres, table_force, table_cop, cop_gain_to_shear, force, shift, fit):
    """One sensor frame of both fingertips, the compiled form of ``SensingChain.sense``.

    Inputs per fingertip f (2, k, ...): bump normal force [N], contact radius [mm], elastic shear [mm], tangential
    force [N]; noise (2, n_nodes) [N] added to the readings. ``model`` = (kernel_spread, cop_gain, moment_arm,
    max_shift, offset, quantization_step, node_floor, contact_threshold); ``grid`` = (x0, y0, spacing, nx, ny).
    Outputs: force (2, k) [N], shift (2, k, 2) [mm] (0 where not in contact), fit (2, 4) = (bumps used, rotation [rad], t_x, t_y [mm]) of the eq. 9 fit of u_i = g shift_i.
    """
    count = centres.shape[0]
    centre_x, centre_y, width = np.empty(count), np.empty(count), np.empty(count)
    readings = np.empty(node_x.size)
    cop = np.empty((count, 2))
    reference = np.empty((count, 2))
    current = np.empty((count, 2))
    used = np.empty(count, dtype=np.bool_)
    for f in range(2):
        kernel_geometry(normal[f], radius[f], shear[f], tangential[f], centres, model[0], model[1], model[2],
                        model[3], centre_x, centre_y, width)
        kernel_readings(readings, grid[0], grid[1], grid[2], int(grid[3]), int(grid[4]), centre_x, centre_y, width,
                        normal[f], indptr, indices, weights)
        for node in range(readings.size):
            value = readings[node] + model[4] + noise[f, node]
            if model[5] > 0.0:
                value = np.round(value / model[5]) * model[5]
            readings[node] = value
        bump_forces_and_cops(readings, region, node_x, node_y, model[6], centres, force[f], cop)
        reference_at(force[f], table_force, table_cop, reference)
        for i in range(count):
            used[i] = force[f, i] > model[7]
            for axis in range(2):
                shift[f, i, axis] = cop[i, axis] - reference[i, axis] if used[i] else 0.0
                current[i, axis] = reference[i, axis] + cop_gain_to_shear * shift[f, i, axis]
        number, rotation, t_x, t_y = rigid_fit(reference, current, used)
        fit[f, 0], fit[f, 1], fit[f, 2], fit[f, 3] = number, rotation, t_x, t_y
