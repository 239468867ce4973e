"""The plant's sensor per frame, compiled: both fingertips' bump states -> pad forces (the FEM response surface of
``contact.reduced.base_response``, as pad-force tables) -> node readings (``controller.sensing._node_kernel``).

numba, because the closed loop reads 2 x 143 nodes of 9 bumps at 100 Hz inside its compiled frame loop.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

from controller.sensing._node_kernel import read_frame

__all__ = ["pad_forces", "plant_readings"]


@njit_cached
def _level(levels, force):
    """Lower index and upper weight of ``force`` [N] between ``levels`` in log force (the end levels beyond)."""
    last = levels.size - 1
    if last == 0 or force <= levels[0]:
        return 0, 0.0
    if force >= levels[last]:
        return last - 1, 1.0
    lower = 0
    while levels[lower + 1] <= force:
        lower += 1
    return lower, (math.log(force) - math.log(levels[lower])) / (math.log(levels[lower + 1]) - math.log(levels[lower]))


@njit_cached
def pad_forces(states, normal_levels, normal, shear_levels, shear, spin, out):
    """Pad forces (n,) [N] into ``out`` of one fingertip's bump states (k, 4): P_i, Q_i,x, Q_i,y [N], S_i [N mm];
    tables normal (k, L, n), shear (k, M, 2, n), spin (k, n) [N per N, N per N mm]."""
    out[:] = 0.0
    for bump in range(states.shape[0]):
        force = max(states[bump, 0], 0.0)
        if force == 0.0:
            continue
        lower, weight = _level(normal_levels, force)
        upper = min(lower + 1, normal_levels.size - 1)
        s_lower, s_weight = _level(shear_levels, force)
        s_upper = min(s_lower + 1, shear_levels.size - 1)
        q_x, q_y, torque = states[bump, 1], states[bump, 2], states[bump, 3]
        for node in range(out.size):
            value = force * ((1.0 - weight) * normal[bump, lower, node] + weight * normal[bump, upper, node])
            value += q_x * ((1.0 - s_weight) * shear[bump, s_lower, 0, node] + s_weight * shear[bump, s_upper, 0, node])
            value += q_y * ((1.0 - s_weight) * shear[bump, s_lower, 1, node] + s_weight * shear[bump, s_upper, 1, node])
            out[node] += value + torque * spin[bump, node]


@njit_cached
def plant_readings(states, normal_levels, normal, shear_levels, shear, spin, pad_area, law, gain, offset, drift,
                   noise_floor, time, noise, pads, change, readings):
    """Readings (2, ny, nx) [N] of both fingertips into ``readings``: bump states (2, k, 4), the tables, the node
    law (``node_law``) with each array's gain, offset [pF] and drift [pF/s] (2, ny, nx) at ``time`` [s], and
    standard-normal ``noise`` (2, ny, nx) times ``noise_floor`` [pF]; ``pads``, ``change`` (ny, nx) work space."""
    rows, cols = pads.shape
    baseline = np.empty((rows, cols))
    scaled = np.empty((rows, cols))
    for f in range(2):
        pad_forces(states[f], normal_levels, normal, shear_levels, shear, spin, pads.reshape(-1))
        for j in range(rows):
            for i in range(cols):
                baseline[j, i] = offset[f, j, i] + time * drift[f, j, i]
                scaled[j, i] = noise_floor * noise[f, j, i]
        read_frame(pads, pad_area, law, gain[f], baseline, scaled, change, readings[f])
