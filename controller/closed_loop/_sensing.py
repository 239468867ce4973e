"""Sensing chain of the closed loop: reduced model -> base pressure -> sensor -> estimator, and its bench."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from contact.reduced import ReducedFingertip
from controller.calibration import EstimatorCalibration, calibrate_gain
from controller.estimator import BumpLayout, BumpReference, EstimatorSettings, bump_positions, estimate_slip
from controller.references import GraspPhase, ReferenceGenerator, ReferenceParameters
from controller.sensor import PressureField, SensorArray, cell_force_operator, sample

from ._bridge import ContactBridge
from ._trial import GRID_SPACING, TargetDesign


class SensingChain:
    """Reduced model -> base pressure -> sensor (noise) -> estimator for both fingertips (100 Hz), and its bench.

    The bench (noise-free, like the FEM bench of Fig. 9) calibrates the CoP gain on small shifts and sets the
    controller's targets: u_x,ref is what the chain reports when every bump carries Q_i / (mu_low P_i) =
    ``design.load_ratio``, theta_ref when the array carries ``design.torque_ratio`` of its slip torque, at the
    reference force, for the lowest friction expected (``design.friction``). How each target scales with the force
    (``ReferenceParameters`` force exponents) is read off the bench too: a signal that follows the shear displacement
    grows like F^(2/3) at a fixed load ratio, one dominated by the overturning moment h Q / P stays constant
    (exponent 0, a fixed target; negative growths are clipped to 0). The
    controller's inversion exponents (its loop gain) are matched to the chain's measured slopes through the slip
    factors.
    """

    REFERENCE_FORCE = 5.0              # N, bench force for calibration and targets (mid-range of the holds)

    def __init__(self, tip: ReducedFingertip, noise: float = 0.0, rng=None, design: TargetDesign = TargetDesign()):
        self.tip, self.rng, self.design = tip, rng, design
        self.grid = tip.base_grid(GRID_SPACING)
        self.array = SensorArray(noise_std=noise)
        self.layout = BumpLayout.grid((tip.design.cols, tip.design.rows), tip.design.pitch)
        # noise gate at 3 sigma: without it the noise of the empty cells in a bump's region dominates |t| and |theta|
        # at low force (a biased magnitude the controller regulates instead of the shear); the gate in turn biases
        # the CoP of a bump's rim in a force-dependent way, which the bench below sees as well
        self.settings = EstimatorSettings(contact_threshold=max(0.02, 10.0 * noise), node_floor=3.0 * noise)
        self.operator = _operator(tip, self.array)
        self.reference_table = self._reference_table()
        self.calibration = self._calibrate()

    def _readings(self, bump_force, radius, shear, tangential, noisy=True):
        pressure = self.tip.base_pressure(self.grid, bump_force, radius, shear, tangential)
        field = PressureField.from_grid(self.grid.x, self.grid.y, pressure)
        array = self.array if noisy else replace(self.array, noise_std=0.0)
        return sample(field, array, self.rng if noisy else None, self.operator)[0]

    def _bench(self, states):
        """Noise-free readings (t, ny, nx) of reduced-model states and the estimate against the first one."""
        frames = np.stack([self._readings(s.normal_force, s.contact_radius, s.shear_displacement,
                                          s.bump_tangential_force, False) for s in states])
        reference = BumpReference.from_readings(frames[:1], self.array, self.layout, self.settings)
        return estimate_slip(frames, self.array, self.layout, reference,
                             getattr(self, "calibration", EstimatorCalibration()), self.settings)

    def _calibrate(self) -> EstimatorCalibration:
        """CoP gain on small rigid shifts (0, 0.01, 0.02 mm along x, nearly full stick) at the bench force."""
        shifts = (0.0, 0.01, 0.02)
        states = [self.tip.displacement_state(self.REFERENCE_FORCE, (shift, 0.0), 0.0, 1.0) for shift in shifts]
        estimate = self._bench(states)
        truth = np.zeros_like(estimate.cop_shift)
        truth[:, :, 0] = np.asarray(shifts)[:, None]
        return calibrate_gain(estimate.cop_shift[1:], truth[1:])

    def _design_signal(self, force, load_ratio, torque_ratio):
        """(|t|, |theta|) the chain reports at a load ratio (x) or torque ratio (slip torque share) at force P."""
        friction = self.design.friction
        bump_force = np.full(len(self.tip.centres), force / len(self.tip.centres))
        radius = self.tip.parameters.radius_coefficient * np.cbrt(bump_force)
        slip_torque = self.tip.slip_margin(bump_force, radius, friction, (0.0, 0.0), 1.0)[0]
        state = self.tip.load_state(force, (load_ratio * friction * force, 0.0), torque_ratio * slip_torque, friction)
        estimate = self._bench([self.tip.displacement_state(force, (0.0, 0.0), 0.0, friction), state])
        return (float(np.linalg.norm(estimate.transform.translation[1])), abs(float(estimate.transform.rotation[1])))

    def design_references(self) -> ReferenceParameters:
        """Targets, force scaling and slip factors from the bench (class docstring)."""
        force, x, y, step = self.REFERENCE_FORCE, self.design.load_ratio, self.design.torque_ratio, 0.01
        u_ref = self._design_signal(force, x, 0.0)[0]
        theta_ref = self._design_signal(force, 0.0, y)[1]
        # how the signals grow with the force at the design ratios (a hemisphere: u ~ F^(2/3), theta ~ F^(1/3); the
        # array's twist signal ~ F^(2/3) too, its bumps translate; a load-ratio signal, as the FEM-calibrated CoP,
        # does not grow: exponent 0, a fixed target), each channel scaled with its own exponent
        growth = (math.log(self._design_signal(4.0 * force, x, 0.0)[0] / u_ref) / math.log(4.0),
                  math.log(self._design_signal(4.0 * force, 0.0, y)[1] / theta_ref) / math.log(4.0))
        references = ReferenceParameters(u_ref, theta_ref, force, scale_with_force=True,
                                         translational_force_exponent=min(max(growth[0], 0.0), 2.0),
                                         rotational_force_exponent=min(max(growth[1], 0.0), 2.0))
        # |u| / u_ref(F) ~ F^(-e) at a constant load: e from a +-1 % force change at the design load
        span = math.log((1 + step) / (1 - step))
        ratios = []
        for channel, (load, torque) in enumerate(((x, 0.0), (0.0, y))):
            generator = ReferenceGenerator(references)
            values = [self._design_signal(force * scale, load / scale, torque / scale)[channel]
                      / generator.references(GraspPhase.HOLD, force * scale)[channel] for scale in (1 - step, 1 + step)]
            ratios.append(math.log(values[0] / values[1]) / span)
        p_x, p_theta = references.inversion_exponents                  # full-stick law of a single hemisphere
        return replace(references, translational_slip_factor=max(p_x * ratios[0], 1.0),
                       rotational_slip_factor=max(p_theta * ratios[1], 1.0))

    def _reference_table(self):
        """Unsheared bench CoPs per bump against the bump's measured force: (forces (n,) [N], cop (n, k, 2) [mm]).

        The CoP of an unsheared bump is not its centre and moves with the force (the kernel widens, the rim falls
        under the noise gate, the outer kernels leave the sensor): a single reference taken at first touch turns
        every later change of grip force into a spurious shear. The bench tabulates it (a sensor calibration of the
        design, not of the object), and ``sense`` interpolates each bump's reference at its own measured force.
        """
        totals = np.geomspace(0.1, 60.0, 40)                                              # N per fingertip
        states = [self.tip.displacement_state(total, (0.0, 0.0), 0.0, 1.0) for total in totals]
        frames = np.stack([self._readings(s.normal_force, s.contact_radius, s.shear_displacement,
                                          s.bump_tangential_force, False) for s in states])
        force, cop, _ = bump_positions(frames, self.array, self.layout, self.settings)     # (n, k), (n, k, 2)
        seen = force.min(axis=1) > 0.0                                                     # every bump above the gate
        return force[seen].mean(axis=1), cop[seen]

    def _reference_at(self, bump_force):
        """BumpReference interpolated at the measured bump forces (k,) [N] (log-force, clamped at the ends)."""
        forces, cop = self.reference_table
        position = np.interp(np.log(np.maximum(bump_force, forces[0])), np.log(forces), np.arange(len(forces)))
        lower = np.minimum(position.astype(int), len(forces) - 2)
        weight = (position - lower)[:, None]
        index = np.arange(len(bump_force))
        reference = (1.0 - weight) * cop[lower, index] + weight * cop[lower + 1, index]      # (k, 2)
        return BumpReference(reference, reference.copy(), bump_force > self.settings.contact_threshold)

    def sense(self, bridge: ContactBridge):
        """(u_x [mm], theta [rad], contact_count) seen by the controller: the larger of the two fingertips."""
        u_x, theta, count = 0.0, 0.0, 0
        for f in range(2):
            readings = self._readings(bridge.normal_force[f], bridge.contact_radius[f], bridge.shear_displacement[f],
                                      bridge.tangential_force[f])
            bump_force = bump_positions(readings, self.array, self.layout, self.settings)[0][0]
            estimate = estimate_slip(readings, self.array, self.layout, self._reference_at(bump_force),
                                     self.calibration, self.settings)
            count = max(count, int(estimate.in_contact[0].sum()))
            if estimate.transform.valid[0]:
                u_x = max(u_x, float(np.linalg.norm(estimate.transform.translation[0])))
                theta = max(theta, abs(float(estimate.transform.rotation[0])))
        return u_x, theta, count


_OPERATORS = {}


def _operator(tip: ReducedFingertip, array: SensorArray):
    """Cell-force operator of the reduced model's base grid (cached per design, parameters and array geometry)."""
    key = (repr(tip.to_dict()), array.pitch, array.node_counts, array.centre)
    if key not in _OPERATORS:
        grid = tip.base_grid(GRID_SPACING)
        field = PressureField.from_grid(grid.x, grid.y, np.zeros((len(grid.y), len(grid.x))))
        _OPERATORS[key] = cell_force_operator(field.positions, field.triangles, array)
    return _OPERATORS[key]
