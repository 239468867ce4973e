"""The estimator's own model of the fingertip's sensor, fitted on a bench: what it believes, not what the plant is.

Model (the form of ``contact.reduced``'s base pressure, with parameters of its own): bump i's base pressure is a
Gaussian bell of width sigma carrying P_i, mirrored at the base layer's edges, plus the pressure couple M_i =
h(P_i) Q_i of its overturning moment, h(P) = h_inf + (h_0 - h_inf) / (1 + kappa P / (h_0 - h_inf)); the array
reads it through its pads, times one overall gain. So the readings are linear in theta = (P_i, M_i,x, M_i,y):
r = A theta + offset, A (n_nodes, 3k) the sensor's response to each (``sensor_operator``).

Fit (``fit_sensor_belief``), as the paper's bench does it (Fig. 8): known flat-plate presses and shears of the
fingertip, readings averaged over frames, and the estimator's assumption that a centred flat plate loads the k bumps
alike (P_i = F / k, Q_i = Q / k). scipy ``least_squares`` on the readings' residual gives sigma, h_0, kappa and the
gain; h_inf is the design's H / 2 (the bench forces stay far from it). The node offsets and the noise come from
readings at rest (``rest_calibration``), on the bench and again before each grasp (the baselines drift).

The plant that made the readings is never seen: only BenchRecords (loads the rig applied, readings it saw).
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, replace

import numpy as np

from controller.sensing import PressureField, SensorArray, cell_force_operator

from .estimator import BumpLayout

__all__ = ["SensorBelief", "fit_sensor_belief", "sensor_operator", "rest_calibration", "belief_tip",
           "GRID_SPACING"]

GRID_SPACING = 1.0          # mm, the grid the model's base pressure is evaluated on (kernel width >= 3 mm)
LINEARITY_TOLERANCE = 1e-9  # relative: A theta against the sampled base pressure of a loaded state


def belief_tip(design, kernel_width: float, couple_arm: float, couple_arm_slope: float, couple_arm_limit: float):
    """A ReducedFingertip that carries the belief's base-pressure parameters (its bump laws are the closed forms of
    the nominal design and are not used by the sensor model)."""
    from contact.reduced import ReducedFingertip, ReducedParameters

    parameters = replace(ReducedParameters.from_design(design), kernel_width=kernel_width, couple_arm=couple_arm,
                         couple_arm_slope=couple_arm_slope, couple_arm_limit=couple_arm_limit,
                         displacement_gain=0.0, source="bench")
    return ReducedFingertip(design, parameters)


@functools.lru_cache(maxsize=8)
def _cells(design_json: str, array: SensorArray):
    """The pad-force operator (n_nodes, n_grid) of the model's base grid, and the grid (one per design and array)."""
    from contact.reduced import ArrayFingertipDesign
    from contact.reduced._base import base_grid

    grid = base_grid(ArrayFingertipDesign.from_dict(json.loads(design_json)), GRID_SPACING)
    field = PressureField.from_grid(grid.x, grid.y, np.zeros((len(grid.y), len(grid.x))))
    return cell_force_operator(field.positions, field.triangles, array), grid


def sensor_operator(tip, array: SensorArray, layout: BumpLayout):
    """The model's response A (n_nodes, 3k) [N per N, N per N mm] to each bump's normal force and couple components,
    its pseudo-inverse (3k, n_nodes) and the bump of each node (n_nodes,) for the CoP regions.

    Columns: the base pressure of a unit bump force, and of a unit couple along x and y (P_i = 0, Q_i = e / h(0)),
    each through the pads (``cell_force_operator``). Raises ValueError if the base pressure is not linear in
    (P_i, M_i) (a loaded state's sampled pressure differs from A theta)."""
    count = len(tip.centres)
    cells, grid = _cells(json.dumps(tip.design.to_dict(), sort_keys=True), array)
    zeros = np.zeros((count, 2))
    arm = float(tip.parameters.couple_arm_at(0.0))
    columns = []
    for kind in range(3):
        for bump in range(count):
            force, tangential = np.zeros(count), zeros.copy()
            if kind == 0:
                force[bump] = 1.0
            else:
                tangential[bump, kind - 1] = 1.0 / arm
            columns.append(cells @ tip.base_pressure(grid, force, np.zeros(count), zeros, tangential).ravel())
    operator = np.stack(columns, axis=1)                                                     # (n_nodes, 3k)
    force = np.linspace(0.4, 1.2, count)
    tangential = np.column_stack([np.linspace(-0.2, 0.3, count), np.linspace(0.25, -0.1, count)])
    sampled = cells @ tip.base_pressure(grid, force, np.zeros(count), zeros, tangential).ravel()
    couple = tip.couple(force, zeros, tangential)
    predicted = operator @ np.concatenate([force, couple[:, 0], couple[:, 1]])
    if np.abs(predicted - sampled).max() > LINEARITY_TOLERANCE * np.abs(sampled).max():
        raise ValueError("the model's base pressure is not linear in the bumps' forces and couples")
    regions = layout.regions(array).reshape(count, -1)                                       # (k, n_nodes)
    region = np.where(regions.any(axis=0), np.argmax(regions, axis=0), -1)
    return operator, np.linalg.pinv(operator), region.astype(np.int64)


def rest_calibration(readings) -> tuple[np.ndarray, float]:
    """Offsets (..., n_nodes) [N] and the pooled rms noise [N] of readings at rest (frames, ..., n_nodes)."""
    readings = np.asarray(readings, dtype=float)
    if readings.ndim < 2 or len(readings) < 2:
        raise ValueError("rest calibration needs at least two frames")
    offset = readings.mean(axis=0)
    return offset, float(np.sqrt(((readings - offset) ** 2).mean() * len(readings) / (len(readings) - 1)))


@dataclass(frozen=True, eq=False)
class SensorBelief:
    """The estimator's sensor model (module docstring): kernel_width sigma [mm], couple_arm h_0 [mm],
    couple_arm_slope kappa [mm/N], couple_arm_limit h_inf [mm], gain [-]; the operator A (n, 3k) (gain included),
    its pseudo-inverse and the node regions; the bench offsets (n,) [N] and noise [N]; fit residuals."""

    design: object
    array: SensorArray
    layout: BumpLayout
    kernel_width: float
    couple_arm: float
    couple_arm_slope: float
    couple_arm_limit: float
    gain: float
    operator: np.ndarray
    inverse: np.ndarray
    region: np.ndarray
    bench_offset: np.ndarray
    bench_noise: float
    fit: dict

    @property
    def couple_law(self) -> np.ndarray:
        """(h_0, kappa, h_inf, g = 0): the compiled estimator's form of h(P)."""
        return np.array([self.couple_arm, self.couple_arm_slope, self.couple_arm_limit, 0.0])

    def couple_arm_at(self, force):
        force = np.maximum(np.asarray(force, dtype=float), 0.0)
        if self.couple_arm_slope == 0.0:
            return np.full(force.shape, self.couple_arm)
        excess = self.couple_arm - self.couple_arm_limit
        return self.couple_arm_limit + excess / (1.0 + (self.couple_arm_slope / excess) * force)

    def bump_loads(self, readings, offset, threshold: float):
        """Per-bump normal force (m, k) [N], load ratio (m, k, 2) [-] and loaded (m, k) of readings (m, n):
        theta = A^+ (r - offset), rho_i = M_i / (h(P_i) P_i), 0 where P_i <= ``threshold``."""
        theta = (np.asarray(readings, dtype=float) - offset) @ self.inverse.T
        count = len(self.layout.centres)
        normal, couple = theta[:, :count], np.stack([theta[:, count:2 * count], theta[:, 2 * count:]], axis=-1)
        loaded = normal > threshold
        safe = np.where(loaded, normal, 1.0)
        ratio = np.where(loaded[..., None], couple / (self.couple_arm_at(safe) * safe)[..., None], 0.0)
        return normal, ratio, loaded


def _theta(record, count: int, centres, arm_law) -> np.ndarray:
    """The bench's belief of a record's per-bump loads: equal shares of the plate's force and tangential load; a
    torque shared in proportion to each bump's distance from the centre, perpendicular to it."""
    force = np.full(count, record.total_force / count)
    tangential = np.tile(np.asarray(record.tangential_force, dtype=float) / count, (count, 1))
    if record.torque:
        perpendicular = np.column_stack([-centres[:, 1], centres[:, 0]])
        tangential = tangential + record.torque * perpendicular / (centres**2).sum()
    couple = arm_law(force)[:, None] * tangential
    return np.concatenate([force, couple[:, 0], couple[:, 1]])


def fit_sensor_belief(records, design, array: SensorArray, layout: BumpLayout) -> SensorBelief:
    """The sensor model fitted to force-controlled bench records (module docstring); 'rest' records give the
    offsets and the noise (at least two frames' worth: their per-record noise is the spread of the rest records)."""
    from scipy.optimize import least_squares

    rest = [r for r in records if r.kind == "rest"]
    loaded = [r for r in records if r.kind != "rest" and r.force_controlled]
    if len(rest) < 2 or len(loaded) < 3:
        raise ValueError(f"a sensor fit needs >= 2 rest and >= 3 loaded force-controlled records, got "
                         f"{len(rest)} and {len(loaded)}")
    offset = np.mean([r.readings.ravel() for r in rest], axis=0)
    noise = float(np.std([r.readings.ravel() for r in rest], axis=0, ddof=1).mean() * math.sqrt(rest[0].frames))
    measured = np.stack([r.readings.ravel() - offset for r in loaded])                  # (m, n)
    count, limit = len(layout.centres), 0.5 * design.bump_height
    centres = np.asarray(layout.centre_array)

    def model(values):
        width, arm, slope, gain = math.exp(values[0]), values[1], max(values[2], 0.0), values[3]
        tip = belief_tip(design, width, max(arm, limit + 1e-6), slope, limit)
        operator = sensor_operator(tip, array, layout)[0]
        theta = np.stack([_theta(r, count, centres, tip.parameters.couple_arm_at) for r in loaded])
        return gain * theta @ operator.T

    def residual(values):
        return ((model(values) - measured) / np.abs(measured).max()).ravel()

    start = [math.log(0.5 * design.bump_radius), design.bump_height, 0.0, 1.0]
    solution = least_squares(residual, start, x_scale=[0.1, 1.0, 0.5, 0.1],
                             bounds=([math.log(0.5), limit + 1e-3, 0.0, 0.2], [math.log(20.0), 5 * limit, 20.0, 5.0]))
    width, arm, slope, gain = math.exp(solution.x[0]), float(solution.x[1]), float(solution.x[2]), float(solution.x[3])
    tip = belief_tip(design, width, arm, slope, limit)
    operator, _, region = sensor_operator(tip, array, layout)
    operator = gain * operator
    misfit = model(solution.x) - measured
    fit = {"records": len(loaded), "rms_residual_n": float(np.sqrt(np.mean(misfit**2))),
           "relative_residual": float(np.linalg.norm(misfit) / np.linalg.norm(measured)),
           "cost": float(solution.cost), "evaluations": int(solution.nfev)}
    return SensorBelief(design, array, layout, width, arm, slope, limit, gain, operator, np.linalg.pinv(operator),
                        region, offset, noise, fit)
