"""Sensing chain of the closed loop: reduced model -> base pressure -> sensor -> estimators, and its bench.

The reduced fingertip's base pressure is linear in each bump's normal force P_i and pressure couple M_i
(``ReducedFingertip.base_pressure``: a bell carrying P_i and the couple of its overturning moment), so the paper's
11 x 13 node array reads r = A theta, theta = (P_i, M_i,x, M_i,y) of the k bumps and A (n_nodes, 3k) the sensor's
response to each, built once per design (``sensor_operator``, checked against sampling the base pressure). Every
frame (100 Hz) the bump states become readings with noise, and two estimators read them:

* the paper's (eq. 9): per-bump CoP shifts against the unsheared reference at each bump's force, calibrated to
  shear displacements u_i = g s_i, and their rigid transform, whose translation u_x and rotation theta drive the
  displacement-target law (``GraspForceController``);
* the per-bump load: theta_hat = A^+ r, the least-squares bump forces and couples (the sensor model inverted, a
  calibrated deconvolution), and the load ratio rho_i = M_i / (h(P_i) P_i) ~ Q_i / P_i with h the couple arm of
  the design, which the incipient-slip controller reads. It separates neighbouring bumps that the CoP regions mix
  and is linear in the load up to the friction limit, along both axes.

The bench (noise-free, like the FEM bench of Fig. 9) works on the reduced model without any object: the reference
CoPs against the bump force, the scalar CoP gain and the displacement-law targets. Its fingertip states do not
depend on the trial and are kept per fingertip design; only the estimator's noise gate changes with a trial's noise.
"""

from __future__ import annotations

import functools
import json
import math
from dataclasses import dataclass, replace

import numpy as np

from contact.reduced import ReducedFingertip, bump_response
from controller.estimation.calibration import EstimatorCalibration, calibrate_gain
from controller.estimation.estimator import BumpLayout, BumpReference, EstimatorSettings, bump_positions, estimate_slip
from controller.control.references import GraspPhase, ReferenceGenerator, ReferenceParameters
from controller.sensing.sensor import PressureField, SensorArray, cell_force_operator

from . import _sensing_kernel as S
from ._trial import GRID_SPACING, TargetDesign

BENCH_FRICTION = 1.0                   # -, friction of the bench states (their load ratios are read off them)


@dataclass(frozen=True, eq=False)
class SensorFrame:
    """What the estimator reports for both fingertips (index 0 left, 1 right) at one sensor frame.

    The paper's estimator: bump_force (2, k) [N] (readings summed over each bump's nodes); in_contact (2, k) bool;
    cop_shift (2, k, 2) [mm] against the unsheared reference; translation (2, 2) [mm] and rotation (2,) [rad] of
    the eq. 9 fit of u_i = g s_i; fitted (2,) bool (two bumps or more); what the displacement-target law sees,
    the larger of the two fingertips: shear_displacement u_x [mm], twist_angle theta [rad], contact_count. The
    per-bump load: normal_force (2, k) [N] and load_ratio (2, k, 2) [-] (A^+ r; 0 where normal_force is at most
    the contact threshold), loaded (2, k) bool, and ratio_noise (2, k) [-], the standard deviation the sensor
    noise gives each ratio (the larger of its two components).
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
    """Reduced model -> base pressure -> sensor (noise) -> estimator for both fingertips (100 Hz), and its bench.

    The displacement-law targets (``design_references``): u_x,ref is what the chain reports when every bump carries
    Q_i / (mu_low P_i) = ``design.load_ratio``, theta_ref when the array carries ``design.torque_ratio`` of its slip
    torque, at the reference force, for the lowest friction expected (``design.friction_coefficient``); how each target scales
    with the force and the loop-gain slip factors are read off the bench too (a signal that follows the shear
    displacement grows like F^(2/3) at a fixed load ratio, one dominated by the overturning moment h Q / P stays
    constant: exponent 0).
    """

    REFERENCE_FORCE = 5.0              # N, bench force for calibration and targets (mid-range of the holds)

    def __init__(self, tip: ReducedFingertip, noise: float = 0.0, rng=None, design: TargetDesign | None = None):
        self.tip, self.rng = tip, rng
        self.design = TargetDesign() if design is None else design
        self.grid = tip.base_grid(GRID_SPACING)
        self.array = SensorArray(noise_std=noise)
        self.layout = BumpLayout.grid((tip.design.cols, tip.design.rows), tip.design.pitch)
        # noise gate at 3 sigma: without it the noise of the empty cells in a bump's region dominates |t| and |theta|
        # at low force (a biased magnitude the controller regulates instead of the shear); the gate in turn biases
        # the CoP of a bump's rim in a force-dependent way, which the bench below sees as well
        self.settings = EstimatorSettings(contact_threshold=max(0.02, 10.0 * noise), node_floor=3.0 * noise)
        self.operator, self._inverse, self._region = sensor_operator(tip, self.array, self.layout)
        count = len(tip.centres)
        # standard deviation of each bump's couple estimate per unit node noise [N mm per N]: A^+ rows' norms
        self._couple_noise = np.sqrt((self._inverse[count:] ** 2).sum(axis=1)).reshape(2, count).max(axis=0)
        node = self.array.node_positions.reshape(-1, 2)
        self._node_x, self._node_y = node[:, 0].copy(), node[:, 1].copy()
        self._centres = self.layout.centre_array
        p = tip.parameters
        self._couple_law = np.array([p.couple_arm, p.couple_arm_slope, p.couple_arm_limit, p.displacement_gain])
        self._bench = _bench_states(tip)
        self.reference_table = self._reference_table()
        self.calibration = self._calibrate()

    # --- readings ---------------------------------------------------------------------------------------------
    def readings(self, bump_force, radius, shear, tangential, noisy: bool = True) -> np.ndarray:
        """Sensor readings (ny, nx) [N] of one fingertip's bump states (k,) / (k, 2) (noise unless ``noisy``).

        ``radius`` is accepted for the bump-state signature; the base pressure does not depend on it."""
        flat = self._noiseless(np.asarray(bump_force, dtype=float)[None], np.asarray(shear, dtype=float)[None],
                               np.asarray(tangential, dtype=float)[None])[0]
        return self._read_out(flat, noisy).reshape(self.array.shape)

    def _noiseless(self, bump_force, shear, tangential) -> np.ndarray:
        """A theta for bump states (m, k), (m, k, 2), (m, k, 2): readings (m, n_nodes) [N] before the read-out."""
        couple = self.tip.couple(bump_force, shear, tangential)                          # (m, k, 2) [N mm]
        theta = np.concatenate([bump_force, couple[..., 0], couple[..., 1]], axis=-1)    # (m, 3k)
        return theta @ self.operator.T

    def _read_out(self, readings, noisy: bool) -> np.ndarray:
        """Offset, noise (unless ``noisy`` is False) and quantization of readings (..., n_nodes) [N]."""
        readings = readings + self.array.offset
        if noisy and self.array.noise_std > 0.0:
            readings = readings + self.rng.normal(0.0, self.array.noise_std, readings.shape)
        if self.array.quantization_step > 0.0:
            readings = np.round(readings / self.array.quantization_step) * self.array.quantization_step
        return readings

    def _state_readings(self, states) -> np.ndarray:
        """Noise-free readings (t, ny, nx) of bench states (dicts of per-bump arrays)."""
        return np.stack([self.readings(s["normal_force"], s["contact_radius"], s["shear_displacement"],
                                       s["tangential_force"], noisy=False) for s in states])

    # --- one frame --------------------------------------------------------------------------------------------
    def sense(self, bridge) -> SensorFrame:
        """Both estimators' view of the two fingertips at the bridge's current state (one sensor frame)."""
        count, nodes = len(self._centres), self._node_x.size
        noise = self.frame_noise(1)[0]
        readings, normal, ratio = np.empty((2, nodes)), np.empty((2, count)), np.empty((2, count, 2))
        force, shift, fit = np.empty((2, count)), np.empty((2, count, 2)), np.empty((2, 4))
        table_force, table_cop = self.reference_table
        threshold = self.settings.contact_threshold
        u_x, theta, contacts = S.sense_frame(
            bridge.normal_force, bridge.shear_displacement, bridge.tangential_force, noise, self._couple_law,
            self.operator, self._inverse, self.array.offset, self.array.quantization_step, threshold, self._region,
            self._node_x, self._node_y, self.settings.node_floor, self._centres, table_force, table_cop,
            self.calibration.gain, readings, normal, ratio, force, shift, fit)
        fitted = fit[:, 0] >= 2
        loaded = normal > threshold
        ratio_noise = np.empty((2, count))
        S.load_ratio_noise(normal, threshold, self._couple_law, float(self.array.noise_std), self._couple_noise,
                           ratio_noise)
        return SensorFrame(force, force > threshold, shift, fit[:, 2:], np.where(fitted, fit[:, 1], 0.0), fitted,
                           u_x, theta, contacts, normal, ratio, loaded, ratio_noise)

    def frame_noise(self, frames: int) -> np.ndarray:
        """Node noise (frames, 2, n_nodes) [N] of the next ``frames`` sensor frames of both fingertips, drawn in
        frame order (the same numbers as one frame at a time); zeros without noise."""
        shape = (frames, 2, self._node_x.size)
        return self.rng.normal(0.0, self.array.noise_std, shape) if self.array.noise_std > 0.0 else np.zeros(shape)

    def compiled_inputs(self) -> tuple:
        """The chain's constants in the order the compiled frame (``_fused._frame_loads``) takes them."""
        return (self._couple_law, self.operator, self._inverse, float(self.array.offset),
                float(self.array.quantization_step), float(self.settings.contact_threshold), self._region,
                self._node_x, self._node_y, float(self.settings.node_floor), self._centres, *self.reference_table,
                float(self.calibration.gain), float(self.array.noise_std), self._couple_noise)

    def bump_loads(self, readings):
        """Per-bump normal force (m, k) [N], load ratio (m, k, 2) [-] and loaded (m, k) bool of readings
        (m, n_nodes): theta = A^+ (r - offset), rho_i = M_i / (h(P_i) P_i) (module docstring)."""
        theta = (np.asarray(readings) - self.array.offset) @ self._inverse.T                # (m, 3k)
        count = len(self._centres)
        normal, couple = theta[:, :count], np.stack([theta[:, count:2 * count], theta[:, 2 * count:]], axis=-1)
        loaded = normal > self.settings.contact_threshold
        safe = np.where(loaded, normal, 1.0)
        arm = self.tip.parameters.couple_arm_at(safe)
        ratio = np.where(loaded[..., None], couple / (arm * safe)[..., None], 0.0)
        return normal, ratio, loaded

    # --- bench ------------------------------------------------------------------------------------------------
    def _reference_table(self):
        """Unsheared bench CoPs per bump against the bump's measured force: (forces (n,) [N], cop (n, k, 2) [mm]).

        The CoP of an unsheared bump is not its centre and moves with the force (the kernel widens, the rim falls
        under the noise gate, the outer kernels leave the sensor): a single reference taken at first touch turns
        every later change of grip force into a spurious shear. The bench tabulates it (a sensor calibration of the
        design, not of the object), and ``sense`` interpolates each bump's reference at its own measured force.
        """
        frames = self._state_readings(self._bench["unsheared"])
        force, cop, _ = bump_positions(frames, self.array, self.layout, self.settings)     # (n, k), (n, k, 2)
        seen = force.min(axis=1) > 0.0                                                     # every bump above the gate
        return np.ascontiguousarray(force[seen].mean(axis=1)), np.ascontiguousarray(cop[seen])

    def _estimate(self, states):
        """Noise-free estimate of bench states against the first one (the paper's estimator, ``estimate_slip``)."""
        frames = self._state_readings(states)
        reference = BumpReference.from_readings(frames[:1], self.array, self.layout, self.settings)
        return estimate_slip(frames, self.array, self.layout, reference,
                             getattr(self, "calibration", EstimatorCalibration()), self.settings)

    def _calibrate(self) -> EstimatorCalibration:
        """CoP gain on small rigid shifts (0, 0.01, 0.02 mm along x, nearly full stick) at the bench force."""
        estimate = self._estimate(self._bench["small_shifts"])
        truth = np.zeros_like(estimate.cop_shift)
        truth[:, :, 0] = np.asarray(SMALL_SHIFTS)[:, None]
        return calibrate_gain(estimate.cop_shift[1:], truth[1:])

    def _design_signal(self, state_pair):
        """(|t|, |theta|) the chain reports for a (reference, loaded) pair of bench states."""
        estimate = self._estimate(state_pair)
        return (float(np.linalg.norm(estimate.transform.translation[1])), abs(float(estimate.transform.rotation[1])))

    def design_references(self) -> ReferenceParameters:
        """Targets, force scaling and slip factors of the displacement-target law from the bench (class docstring)."""
        design, force, step = self.design, self.REFERENCE_FORCE, DESIGN_STEP
        pairs = _design_states(self.tip, design.friction_coefficient, design.load_ratio, design.torque_ratio, force)
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


SMALL_SHIFTS = (0.0, 0.01, 0.02)        # mm along x at the bench force: the scalar CoP gain
DESIGN_STEP = 0.01                      # +-1 % force change for the displacement law's slip factors


def _tip_key(tip: ReducedFingertip) -> str:
    return json.dumps(tip.to_dict(), sort_keys=True)


_OPERATORS: dict = {}
LINEARITY_TOLERANCE = 1e-9        # relative: A theta against the sampled base pressure of a loaded state


def sensor_operator(tip: ReducedFingertip, array: SensorArray, layout: BumpLayout):
    """The sensor's response A (n_nodes, 3k) [N per N, N per N mm] to each bump's normal force and couple
    components, its pseudo-inverse (3k, n_nodes) and the bump of each node (n_nodes,) for the CoP regions; cached per
    design, parameters and array geometry.

    Columns: the base pressure of a unit bump force, and of a unit couple along x and y (a bump with P_i = 0 and
    Q_i = e / h(0)), each integrated over the cells (``cell_force_operator``). Raises ValueError if the base pressure
    is not linear in (P_i, M_i) (a state's sampled pressure differs from A theta).
    """
    key = (_tip_key(tip), array.pitch, array.node_counts, array.centre, layout)
    if key not in _OPERATORS:
        count = len(tip.centres)
        grid = tip.base_grid(GRID_SPACING)
        field = PressureField.from_grid(grid.x, grid.y, np.zeros((len(grid.y), len(grid.x))))
        cells = cell_force_operator(field.positions, field.triangles, array)
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
                pressure = tip.base_pressure(grid, force, np.zeros(count), zeros, tangential)
                columns.append(cells @ pressure.ravel())
        operator = np.stack(columns, axis=1)                                                 # (n_nodes, 3k)
        state = tip.load_state(6.0, (1.0, -1.5), 12.0, 1.0)
        sampled = cells @ tip.state_pressure(grid, state).ravel()
        couple = tip.couple(state.normal_force, state.shear_displacement, state.bump_tangential_force)
        predicted = operator @ np.concatenate([state.normal_force, couple[:, 0], couple[:, 1]])
        if np.abs(predicted - sampled).max() > LINEARITY_TOLERANCE * np.abs(sampled).max():
            raise ValueError("the fingertip's base pressure is not linear in the bumps' forces and couples; "
                             "the sensing chain needs ReducedFingertip.base_pressure of that form")
        regions = layout.regions(array).reshape(count, -1)                                   # (k, n_nodes)
        region = np.where(regions.any(axis=0), np.argmax(regions, axis=0), -1)
        _OPERATORS[key] = (operator, np.linalg.pinv(operator), region.astype(np.int64))
    return _OPERATORS[key]


def _displacement_states(tip: ReducedFingertip, total_force: float, translations, rotations) -> list[dict]:
    """Bench states of a rigid object displacement (translation (n, 2) [mm], rotation (n,) [rad]) at a total
    normal force [N] shared equally by the bumps (a flat object, no tilt), on a surface of BENCH_FRICTION."""
    translations, rotations = np.atleast_2d(translations), np.atleast_1d(rotations)
    bump_force = np.full((len(rotations), len(tip.centres)), total_force / len(tip.centres))
    shear = tip.bump_shear(translations, rotations)
    response = bump_response(bump_force, shear, np.broadcast_to(rotations[:, None], bump_force.shape),
                             BENCH_FRICTION, tip.parameters)
    return [dict(normal_force=bump_force[n], contact_radius=response.contact_radius[n],
                 shear_displacement=response.limit_displacement[n], tangential_force=response.tangential_force[n])
            for n in range(len(rotations))]


_BENCH: dict = {}


def _bench_states(tip: ReducedFingertip) -> dict:
    """Noise-free bench states of a fingertip design (cached): 'unsheared' at 40 forces (the reference table) and
    'small_shifts' (the scalar gain)."""
    key = _tip_key(tip)
    if key not in _BENCH:
        unsheared = [_displacement_states(tip, total, (0.0, 0.0), 0.0)[0] for total in np.geomspace(0.1, 60.0, 40)]
        small = _displacement_states(tip, SensingChain.REFERENCE_FORCE, [(shift, 0.0) for shift in SMALL_SHIFTS],
                                     np.zeros(len(SMALL_SHIFTS)))
        _BENCH[key] = dict(unsheared=unsheared, small_shifts=small)
    return _BENCH[key]


@functools.lru_cache(maxsize=16)
def _cached_design_states(key: str, friction: float, load_ratio: float, torque_ratio: float, force: float):
    tip = ReducedFingertip.from_dict(json.loads(key))
    count = len(tip.centres)

    def pair(total, load, torque):
        bump_force = np.full(count, total / count)
        radius = tip.parameters.radius_coefficient * np.cbrt(bump_force)
        slip_torque = tip.slip_margin(bump_force, radius, friction, (0.0, 0.0), 1.0)[0]
        loaded = tip.load_state(total, (load * friction * total, 0.0), torque * slip_torque, friction)
        rest = tip.displacement_state(total, (0.0, 0.0), 0.0, friction)
        return [_as_bench(rest), _as_bench(loaded)]

    pairs = {("translation", 1.0): pair(force, load_ratio, 0.0), ("twist", 1.0): pair(force, 0.0, torque_ratio),
             ("translation", 4.0): pair(4.0 * force, load_ratio, 0.0), ("twist", 4.0): pair(4.0 * force, 0.0,
                                                                                           torque_ratio)}
    for scale in (1 - DESIGN_STEP, 1 + DESIGN_STEP):
        pairs["translation_at_constant_load", scale] = pair(force * scale, load_ratio / scale, 0.0)
        pairs["twist_at_constant_load", scale] = pair(force * scale, 0.0, torque_ratio / scale)
    return pairs


def _design_states(tip: ReducedFingertip, friction, load_ratio, torque_ratio, force) -> dict:
    """Bench state pairs (unloaded, loaded) of the displacement-law design (``SensingChain.design_references``),
    cached per design: they need the array's slip limit and a Newton solve each."""
    return _cached_design_states(_tip_key(tip), float(friction), float(load_ratio), float(torque_ratio), float(force))


def _as_bench(state) -> dict:
    return dict(normal_force=state.normal_force, contact_radius=state.contact_radius,
                shear_displacement=state.shear_displacement, tangential_force=state.bump_tangential_force)
