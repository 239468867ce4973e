"""The capacitive node's read-out as one compiled kernel: the law of ``controller.sensing.capacitive``.

``CapacitiveNode.read`` calls it for frames from Python, and the closed loop's plant calls it inside its compiled
frame loop; one source, so the two cannot drift apart. numba, because the loop reads 2 x 143 nodes at 100 Hz inside
compiled code, where a return to numpy per frame would cost more than the arithmetic.
"""

from __future__ import annotations

import math

import numpy as np
from fem.compiled import njit_cached

__all__ = ["read_frame", "capacitance_changes", "pressures", "NODE_LAW_SIZE", "node_law"]

# the node law's constants in one vector: capacitance per area [pF/mm^2], E_d [MPa], eps_max [-], nonlinear (0/1),
# crosstalk [-], converter step [pF] (0: none), converter bits
(L_CAPACITANCE, L_MODULUS, L_MAX_STRAIN, L_NONLINEAR, L_CROSSTALK, L_ADC_STEP, L_ADC_BITS, NODE_LAW_SIZE) = range(8)


def node_law(node) -> np.ndarray:
    """The constant vector (NODE_LAW_SIZE,) ``read_frame`` takes for a ``CapacitiveNode``."""
    law = np.zeros(NODE_LAW_SIZE)
    law[L_CAPACITANCE], law[L_MODULUS], law[L_MAX_STRAIN] = (node.capacitance_per_area, node.dielectric_modulus,
                                                              node.max_strain)
    law[L_NONLINEAR], law[L_CROSSTALK] = float(node.nonlinear), node.crosstalk
    law[L_ADC_STEP], law[L_ADC_BITS] = node.adc_step, node.adc_bits
    return law


@njit_cached
def _change(pressure, law, pad_area):
    """Capacitance change dC [pF] of a pad at mean pressure [MPa] (the docstring's steps 2-3)."""
    linear = pressure / law[L_MODULUS]
    base = law[L_CAPACITANCE] * pad_area
    if law[L_NONLINEAR] == 0.0:
        return base * linear
    limit = law[L_MAX_STRAIN]
    strain = limit * -math.expm1(-max(linear, 0.0) / limit) if pressure >= 0.0 else linear
    return base * strain / (1.0 - strain)


@njit_cached
def _pressure(change, law, pad_area):
    """The firmware's inverse of ``_change`` [MPa]; a saturated node reads the pressure at 1 - 1e-9 of eps_max."""
    relative = change / (law[L_CAPACITANCE] * pad_area)
    if law[L_NONLINEAR] == 0.0:
        return relative * law[L_MODULUS]
    strain = relative / (1.0 + max(relative, -1.0 + 1e-12))
    if strain < 0.0:
        return strain * law[L_MODULUS]
    limit = law[L_MAX_STRAIN]
    return -limit * law[L_MODULUS] * math.log1p(-min(strain, limit * (1.0 - 1e-9)) / limit)


@njit_cached
def read_frame(pad_force, pad_area, law, gain, offset, noise, change, out):
    """One frame of node readings [N] (ny, nx) into ``out`` from pad forces (ny, nx) [N]: dC of each pad times its
    ``gain`` [-], plus ``crosstalk`` of its four neighbours' dC, plus its ``offset`` and ``noise`` [pF], through the
    converter (rounded to its step, clipped to its range) and the firmware's nominal inverse; ``change`` (ny, nx)
    is work space."""
    rows, cols = pad_force.shape
    for j in range(rows):
        for i in range(cols):
            change[j, i] = gain[j, i] * _change(pad_force[j, i] / pad_area, law, pad_area)
    crosstalk, step = law[L_CROSSTALK], law[L_ADC_STEP]
    half = 2.0 ** (law[L_ADC_BITS] - 1.0)
    for j in range(rows):
        for i in range(cols):
            value = change[j, i]
            if crosstalk > 0.0:
                neighbours = 0.0
                if j > 0:
                    neighbours += change[j - 1, i]
                if j < rows - 1:
                    neighbours += change[j + 1, i]
                if i > 0:
                    neighbours += change[j, i - 1]
                if i < cols - 1:
                    neighbours += change[j, i + 1]
                value += crosstalk * neighbours
            value += offset[j, i] + noise[j, i]
            if step > 0.0:
                value = min(max(np.round(value / step), -half), half - 1.0) * step
            out[j, i] = _pressure(value, law, pad_area) * pad_area


@njit_cached
def capacitance_changes(pressure, law, pad_area, out):
    """dC [pF] of pads at mean pressures [MPa] (flat arrays), into ``out``."""
    for index in range(pressure.size):
        out[index] = _change(pressure[index], law, pad_area)


@njit_cached
def pressures(change, law, pad_area, out):
    """The firmware's pressures [MPa] of capacitance changes [pF] (flat arrays), into ``out``."""
    for index in range(change.size):
        out[index] = _pressure(change[index], law, pad_area)
