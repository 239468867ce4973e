"""The estimator side of the closed loop: readings in, what the controller may know out (the belief of
docs/design.md, sec. 9; the readings themselves come from the plant, ``controller.plant``).

Everything here was fitted on the estimator's bench (``_bench``: a nominal build, never the trial's) or measured at
rest before the grasp (``SensingChain.tare``: each array's node offsets and the node noise, which set the noise
gates). Every frame (100 Hz) two estimators read the tared readings:

* the per-bump load: theta_hat = A^+ r with A the estimator's own sensor model (``SensorBelief``: Gaussian bells and
  pressure couples fitted on the bench), the bump forces and couples read back, and the load ratio
  rho_i = M_i / (h(P_i) P_i) ~ Q_i / P_i, which the incipient-slip controller reads, with its noise from the noise
  measured at rest;
* the paper's (eq. 9): per-bump CoP shifts against the unsheared reference at each bump's force (a table of bench
  presses), calibrated to shear displacements u_i = g s_i on bench shifts, and their rigid transform, whose
  translation u_x and rotation theta drive the displacement-target law (``GraspForceController``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from controller.control.references import GraspPhase, ReferenceGenerator, ReferenceParameters
from controller.estimation import (BumpReference, EstimatorCalibration, EstimatorSettings, bump_positions,
                                   calibrate_gain, estimate_slip, gate_pool_for)
from controller.estimation.sensor_model import rest_calibration

from . import _sensing_kernel as S
from ._bench import DESIGN_STEP, REFERENCE_FORCE, SMALL_SHIFTS, EstimatorBench, design_pairs, estimator_bench
from ._trial import TargetDesign

__all__ = ["SensorFrame", "SensingChain", "NOISE_GATE", "CONTACT_GATE", "MINIMUM_CONTACT_THRESHOLD"]

NOISE_GATE = 3.0                  # node readings below this many noise sigmas count as zero (CoP regions)
CONTACT_GATE = 10.0               # a bump below this many node sigmas of force is not in contact
MINIMUM_CONTACT_THRESHOLD = 0.02  # N: and never below this


def pool_nodes(shape: tuple, side: int) -> np.ndarray:
    """(ny * nx, side**2) flat indices of the side x side nodes around each node of an array of ``shape``
    (ny, nx), -1 where the square leaves the array: the compiled gate's pools (``EstimatorSettings.gate_pool``)."""
    ny, nx = shape
    half = side // 2
    j, i = np.divmod(np.arange(ny * nx), nx)
    dj, di = (offset.ravel() for offset in np.mgrid[-half:half + 1, -half:half + 1])
    rows, cols = j[:, None] + dj, i[:, None] + di
    inside = (rows >= 0) & (rows < ny) & (cols >= 0) & (cols < nx)
    return np.ascontiguousarray(np.where(inside, rows * nx + cols, -1), dtype=np.int64)


@dataclass(frozen=True, eq=False)
class SensorFrame:
    """What the estimator reports for both fingertips (index 0 left, 1 right) at one sensor frame.

    The paper's estimator: bump_force (2, k) [N] (readings summed over each bump's nodes); in_contact (2, k) bool;
    cop_shift (2, k, 2) [mm] against the unsheared reference; translation (2, 2) [mm] and rotation (2,) [rad] of
    the eq. 9 fit of u_i = g s_i; fitted (2,) bool (two bumps or more); what the displacement-target law sees,
    the larger of the two fingertips: shear_displacement u_x [mm], twist_angle theta [rad], contact_count. The
    per-bump load: normal_force (2, k) [N] and load_ratio (2, k, 2) [-] (A^+ r; 0 where normal_force is at most
    the contact threshold), loaded (2, k) bool, and ratio_noise (2, k) [-], the standard deviation the measured
    node noise gives each ratio (the larger of its two components).
    """

    bump_force: np.ndarray
    in_contact: np.ndarray
    cop_shift: np.ndarray
    translation: np.ndarray
    rotation: np.ndarray
    fitted: np.ndarray
    shear_displacement: float
    twist_angle: float
    contact_count: int
    normal_force: np.ndarray
    load_ratio: np.ndarray
    loaded: np.ndarray
    ratio_noise: np.ndarray


class SensingChain:
    """Readings (2, n_nodes) -> both estimators for both fingertips (100 Hz), from the bench and the rest frames.

    Parameters
    ----------
    bench : EstimatorBench, optional -- the estimator's bench (default: the FEM plane's, ``estimator_bench()``).
    design : TargetDesign, optional -- what the displacement-target law's references are designed for.
    """

    def __init__(self, bench: EstimatorBench | None = None, design: TargetDesign | None = None):
        self.bench = estimator_bench() if bench is None else bench
        self.design = TargetDesign() if design is None else design
        belief = self.bench.belief
        self.belief, self.array, self.layout = belief, belief.array, belief.layout
        self.operator, self._inverse, self._region = belief.operator, belief.inverse, belief.region
        count = len(self.layout.centres)
        # standard deviation of each bump's couple estimate per unit node noise [N mm per N]: A^+ rows' norms
        self._couple_noise = np.sqrt((self._inverse[count:] ** 2).sum(axis=1)).reshape(2, count).max(axis=0)
        node = self.array.node_positions.reshape(-1, 2)
        self._node_x, self._node_y = node[:, 0].copy(), node[:, 1].copy()
        self._centres = self.layout.centre_array
        self._couple_law = belief.couple_law
        self._gate_pool = gate_pool_for(self.array.pitch)
        self._pool_nodes = pool_nodes(self.array.shape, self._gate_pool)
        self.tare(None)

    # --- rest calibration -------------------------------------------------------------------------------------
    def tare(self, rest) -> None:
        """Offsets (2, n_nodes) [N] and node noise [N] from readings at rest (frames, 2, n_nodes) (None: the
        bench's), then the noise gates and the paper's estimator's tables for them."""
        if rest is None:
            self.offset = np.tile(self.bench.offset, (2, 1))
            self.noise = self.belief.bench_noise
        else:
            self.offset, self.noise = rest_calibration(rest)
        self.offset = np.ascontiguousarray(self.offset)
        self.settings = EstimatorSettings(contact_threshold=max(MINIMUM_CONTACT_THRESHOLD, CONTACT_GATE * self.noise),
                                          node_floor=NOISE_GATE * self.noise, gate_pool=self._gate_pool)
        self.reference_table = self._reference_table()
        self.couple_table = self._couple_table()
        self.calibration = self._calibrate()

    # --- one frame --------------------------------------------------------------------------------------------
    def sense(self, readings) -> SensorFrame:
        """Both estimators' view of the two fingertips' readings (2, n_nodes) [N] (one sensor frame)."""
        count, nodes = len(self._centres), self._node_x.size
        readings = np.ascontiguousarray(np.asarray(readings, dtype=float).reshape(2, nodes))
        corrected, normal, ratio = np.empty((2, nodes)), np.empty((2, count)), np.empty((2, count, 2))
        force, shift, fit = np.empty((2, count)), np.empty((2, count, 2)), np.empty((2, 4))
        u_x, theta, contacts = S.sense_frame(readings, *self.compiled_inputs()[:-2], corrected, normal, ratio,
                                             force, shift, fit)
        threshold = self.settings.contact_threshold
        fitted = fit[:, 0] >= 2
        ratio_noise = np.empty((2, count))
        S.load_ratio_noise(normal, threshold, self._couple_law, float(self.noise), self._couple_noise, ratio_noise)
        return SensorFrame(force, force > threshold, shift, fit[:, 2:], np.where(fitted, fit[:, 1], 0.0), fitted,
                           u_x, theta, contacts, normal, ratio, normal > threshold, ratio_noise)

    def compiled_inputs(self) -> tuple:
        """The chain's constants in the order ``_sensing_kernel.sense_frame`` takes them after the readings, then the
        noise and the couples' noise factors (``load_ratio_noise``)."""
        table_force, table_cop = self.reference_table
        couple_force, couple_table = self.couple_table
        return (self.offset, self._couple_law, self._inverse, float(self.settings.contact_threshold), couple_force,
                couple_table, self._region, self._node_x, self._node_y, float(self.settings.node_floor),
                self._pool_nodes, self._centres, table_force, table_cop, float(self.calibration.gain),
                float(self.noise), self._couple_noise)

    def bump_loads(self, readings, finger: int = 0):
        """Per-bump normal force (m, k) [N], load ratio (m, k, 2) [-] and loaded (m, k) of one fingertip's readings
        (m, n_nodes): theta = A^+ (r - offset), rho_i = (M_i - M_0,i(P_i)) / (h(P_i) P_i), M_0 the unsheared couple
        (``sense``'s arithmetic, frame by frame)."""
        readings = np.atleast_2d(readings)
        normal, ratio = np.empty((len(readings), len(self._centres))), np.empty((len(readings), len(self._centres), 2))
        for index, frame in enumerate(readings):
            both = np.ascontiguousarray(np.stack([frame, frame]))
            loads, ratios = np.empty((2, len(self._centres))), np.empty((2, len(self._centres), 2))
            offset = np.ascontiguousarray(np.stack([self.offset[finger]] * 2))
            S.read_loads(both, offset, self._couple_law, self._inverse, float(self.settings.contact_threshold),
                         *self.couple_table, np.empty_like(both), loads, ratios)
            normal[index], ratio[index] = loads[0], ratios[0]
        return normal, ratio, normal > self.settings.contact_threshold

    # --- the paper's estimator's tables, from the bench ---------------------------------------------------------
    def _tared(self, readings) -> np.ndarray:
        """Bench readings (m, n_nodes) less the bench's offsets, as frames (m, ny, nx)."""
        return (np.asarray(readings) - self.bench.offset).reshape((-1,) + self.array.shape)

    def _reference_table(self):
        """Unsheared bench CoPs per bump against the bump's measured force: (forces (n,) [N], cop (n, k, 2) [mm]).

        The CoP of an unsheared bump is not its centre and moves with the force (the kernel widens, the rim falls
        under the noise gate, the outer kernels leave the sensor): a single reference taken at first touch turns
        every later change of grip force into a spurious shear. The bench tabulates it (a calibration of the
        fingertip, not of the object), and ``sense`` interpolates each bump's reference at its measured force.
        """
        force, cop, _ = bump_positions(self._tared(self.bench.reference_readings), self.array, self.layout,
                                       self.settings)
        seen = force.min(axis=1) > 0.0                                                     # every bump above the gate
        return np.ascontiguousarray(force[seen].mean(axis=1)), np.ascontiguousarray(cop[seen])

    def _couple_table(self):
        """The couple each bump shows unsheared, against its force: (forces (n,) [N], couples (n, k, 2) [N mm]) from
        the bench's presses. The estimator's model is not the fingertip's: an unsheared bump's force leaks into its
        own and its neighbours' couples, in proportion to the grip, and would read as a load that falls as the
        grip does. Taken off every frame (``_sensing_kernel.read_loads``), like the CoP table of the paper's
        estimator."""
        theta = (np.asarray(self.bench.reference_readings) - self.bench.offset) @ self._inverse.T      # (n, 3k)
        count = len(self._centres)
        force = theta[:, :count]
        couple = np.stack([theta[:, count:2 * count], theta[:, 2 * count:]], axis=-1)            # (n, k, 2)
        seen = force.min(axis=1) > self.settings.contact_threshold
        return np.ascontiguousarray(force[seen].mean(axis=1)), np.ascontiguousarray(couple[seen])

    def _estimate(self, readings):
        """The paper's estimator on bench readings (m, n_nodes) against the first of them."""
        frames = self._tared(readings)
        reference = BumpReference.from_readings(frames[:1], self.array, self.layout, self.settings)
        return estimate_slip(frames, self.array, self.layout, reference,
                             getattr(self, "calibration", EstimatorCalibration()), self.settings)

    def _calibrate(self) -> EstimatorCalibration:
        """CoP gain on the bench's small rigid shifts (0, 0.01, 0.02 mm along x, nearly full stick)."""
        estimate = self._estimate(self.bench.shift_readings)
        truth = np.zeros_like(estimate.cop_shift)
        truth[:, :, 0] = np.asarray(SMALL_SHIFTS)[:, None]
        return calibrate_gain(estimate.cop_shift[1:], truth[1:])

    def _design_signal(self, readings):
        """(|t|, |theta|) the chain reports for a bench pair (unloaded, loaded) of readings (2, n_nodes)."""
        estimate = self._estimate(readings)
        return (float(np.linalg.norm(estimate.transform.translation[1])), abs(float(estimate.transform.rotation[1])))

    def design_references(self) -> ReferenceParameters:
        """Targets of the displacement-target law from bench pairs: u_x,ref is what the chain reports when every
        bump carries Q_i / (mu_low P_i) = ``design.load_ratio``, theta_ref when the array carries
        ``design.torque_ratio`` of its slip torque, at REFERENCE_FORCE on a plate of the lowest friction expected
        (``design.friction_coefficient``); how each target scales with the force and the loop-gain slip factors
        (a signal that follows the shear displacement grows like F^(2/3) at a fixed load ratio, one dominated by the
        overturning moment h Q / P stays constant: exponent 0)."""
        design, force, step = self.design, REFERENCE_FORCE, DESIGN_STEP
        pairs = design_pairs(self.bench.plane, design.friction_coefficient, design.load_ratio, design.torque_ratio,
                             force, self.bench.rig)
        u_ref = self._design_signal(pairs["translation", 1.0])[0]
        theta_ref = self._design_signal(pairs["twist", 1.0])[1]
        growth = (math.log(self._design_signal(pairs["translation", 4.0])[0] / u_ref) / math.log(4.0),
                  math.log(self._design_signal(pairs["twist", 4.0])[1] / theta_ref) / math.log(4.0))
        references = ReferenceParameters(u_ref, theta_ref, force, scale_with_force=True,
                                         translational_force_exponent=min(max(growth[0], 0.0), 2.0),
                                         rotational_force_exponent=min(max(growth[1], 0.0), 2.0))
        # |u| / u_ref(F) ~ F^(-e) at a constant load: e from a +-1 % force change at the design load
        span = math.log((1 + step) / (1 - step))
        ratios = []
        generator = ReferenceGenerator(references)
        for channel, kind in enumerate(("translation_at_constant_load", "twist_at_constant_load")):
            values = [self._design_signal(pairs[kind, scale])[channel]
                      / generator.references(GraspPhase.HOLD, force * scale)[channel] for scale in (1 - step, 1 + step)]
            ratios.append(math.log(values[0] / values[1]) / span)
        p_x, p_theta = references.inversion_exponents                  # full-stick law of a single hemisphere
        return replace(references, translational_slip_factor=max(p_x * ratios[0], 1.0),
                       rotational_slip_factor=max(p_theta * ratios[1], 1.0))
