"""Calibration of the reduced fingertip model (``ReducedParameters``) from FEM load paths of the same design.

Inputs are ``PathSamples`` of FEM paths: a press path at several normal forces, shear paths (plate shift along x)
at the calibration normal force and at a second one, and a twist path (plate angle) at the calibration force.
Each parameter is fitted with scipy (``least_squares``, ``lsq_linear``) on the quantity it governs, in the order
that lets the later fits use the earlier values:

normal_stiffness k_n
    total plate approach against P_i = P / k of a centred plate, d = (P_i / k_n)^(2/3). The approach includes the
    settlement of the base layer and of the bump stem under it (linear in P_i); the model has no separate term for
    it, and its only use of k_n is the depth-to-force law of a tilted plate (``normal_split``), which is the total
    approach of each bump. So k_n is the *effective* stiffness of the whole column; the report gives the split of a
    two-term fit d = (P_i / k_h)^(2/3) + c_s P_i as a diagnostic (``settlement_compliance``).
radius_coefficient c_a
    per-bump contact radius sqrt(A_i / pi) (points grouped by their nearest bump) against c_a P_i^(1/3), with the
    bump's own FEM normal force P_i.
tangential_modulus G*
    array tangential force against plate shift, through the model itself (per-bump Mindlin laws summed), all
    shear paths together.
torsional_modulus G_t
    per-bump torque about the bump's own axis against the plate twist, through the model (Lubkin laws, each bump
    sheared by theta z x r_i as well). The array torque about its centre is not used: it is ~99 % the moment
    r_i x Q_i of the bumps' shear forces (G*), so it hardly depends on G_t; the report gives its residual.
kernel_spread s
    second moment of the base pressure in each bump's cell of the sensor plane. The kernel p ~ 1 - r^2 / w^2 has
    <r^2> = w^2 / 3 with w^2 = a^2 + s^2; that gives the starting value, and the fit then matches the model's own
    cell moments (``base_pressure`` cut into the same cells), because the FEM's base pressure is wide (w ~ 8 mm
    on this design, more than half a pitch): neighbouring kernels overlap and the cells truncate them.
cop_gain g, moment_arm h
    per-bump CoP shift of the base pressure against the pressed state, Delta c = g delta_i + h Q_i / P_i (FEM
    delta_i, Q_i, P_i; shear and twist paths), by bounded linear least squares (g >= 1e-6, h >= 0): the model's
    law for its kernel centre. At one normal force Q_i / P_i grows monotonically with delta_i and the two terms are
    nearly collinear; the shear path at a second force separates them. The diagnostics hold the unbounded fit, the
    standard errors, and how the model's own sensor cells follow the FEM with these numbers (a kernel wider than
    half a pitch spills into the neighbours' cells, so its cell CoP lags its centre and saturates).
damping_time
    a quasi-static FEM path cannot see the gel's viscosity: the closed-form default is kept.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from fem.validation import check_positive

from ._bumps import bump_response, normal_split
from ._design import ArrayFingertipDesign, ReducedParameters
from ._model import BaseGrid, ReducedFingertip
from ._samples import PathSamples, cell_moments

__all__ = ["FitResult", "Calibration", "calibrate", "fit_normal_stiffness", "fit_radius_coefficient",
           "fit_tangential_modulus", "fit_torsional_modulus", "fit_kernel_spread", "fit_cop", "kernel_grid"]

MIN_COP_GAIN = 1e-6            # ReducedParameters needs cop_gain > 0; the bound stands for "no such term"
KERNEL_GRID_SPACING = 0.5      # mm, the model's default base grid (the closed loop's sensor images)


@dataclass(frozen=True)
class FitResult:
    """One fitted parameter: value, closed-form value, residual statistics of the quantity it was fitted on.

    residual_unit says what a residual is (e.g. "relative depth", "N / (mu P)"); samples counts the residuals.
    """

    parameter: str
    value: float
    closed_form: float
    samples: int
    rms_residual: float
    max_residual: float
    residual_unit: str
    note: str = ""

    def to_dict(self) -> dict:
        return dataclasses.asdict(self)


@dataclass(frozen=True, eq=False)
class Calibration:
    """Fitted parameters of ``design``, the fit of each (``fits``) and further numbers (``diagnostics``)."""

    design: ArrayFingertipDesign
    parameters: ReducedParameters
    fits: tuple[FitResult, ...]
    diagnostics: dict = field(default_factory=dict)

    def fit(self, parameter: str) -> FitResult:
        """The FitResult of one parameter name (KeyError if there is none)."""
        for result in self.fits:
            if result.parameter == parameter:
                return result
        raise KeyError(parameter)


def _result(name, value, closed_form, residual, unit, note="") -> FitResult:
    residual = np.asarray(residual, dtype=float).ravel()
    if not np.all(np.isfinite(residual)):
        raise ValueError(f"fit of {name}: non-finite residuals (bad FEM samples?)")
    return FitResult(name, float(value), float(closed_form), int(residual.size),
                     float(np.sqrt(np.mean(residual**2))), float(np.abs(residual).max()), unit, note)


def _pressed(samples: Sequence[PathSamples]):
    """Normal force (m,), depth (m,), per-bump FEM forces (m, k), radii (m, k), second moments (m, k) of presses."""
    samples = list(samples)
    if not samples or not any(s.pressed.any() for s in samples):
        raise ValueError("press samples: need at least one press increment")
    pick = [(s, s.pressed) for s in samples]
    return (np.concatenate([s.normal_force[m] for s, m in pick]), np.concatenate([s.depth[m] for s, m in pick]),
            np.concatenate([s.bump_normal_force[m] for s, m in pick]),
            np.concatenate([s.bump_contact_radius[m] for s, m in pick]),
            np.concatenate([s.base_second_moment[m] for s, m in pick]))


def fit_normal_stiffness(press: Sequence[PathSamples], design: ArrayFingertipDesign):
    """k_n [N/mm^1.5] from the plate approach d against P / k (relative residual in d); and the settlement split."""
    from scipy.optimize import least_squares

    force, depth, *_ = _pressed(press)
    if np.unique(np.round(force, 9)).size < 2:
        raise ValueError(f"press samples: need at least two distinct normal forces, got {np.unique(force)} N")
    bump_force = force / design.bump_count

    def relative(log_stiffness):
        return (bump_force / math.exp(log_stiffness[0])) ** (2.0 / 3.0) / depth - 1.0

    start = math.log(float(np.median(bump_force / depth**1.5)))
    fitted = least_squares(relative, [start], x_scale=1.0, xtol=1e-12, ftol=1e-12)
    # diagnostic: Hertz part plus a linear settlement c_s P_i (c_s >= 0)
    two = least_squares(lambda x: ((bump_force / math.exp(x[0])) ** (2.0 / 3.0) + x[1] * bump_force) / depth - 1.0,
                        [fitted.x[0], 0.0], bounds=([-np.inf, 0.0], [np.inf, np.inf]), xtol=1e-12, ftol=1e-12)
    middle = float(np.median(bump_force))
    share = two.x[1] * middle / ((middle / math.exp(two.x[0])) ** (2.0 / 3.0) + two.x[1] * middle)
    exponent = float(np.polyfit(np.log(bump_force), np.log(depth), 1)[0])          # d ~ P_i^e; Hertz: 2/3
    diagnostics = {"approach_exponent": exponent,
                   "hertz_stiffness_two_term": math.exp(two.x[0]), "settlement_compliance": float(two.x[1]),
                   "settlement_share_at_median_force": float(share),
                   "two_term_rms_relative_depth": float(np.sqrt(np.mean(two.fun**2)))}
    closed = ReducedParameters.from_design(design).normal_stiffness
    note = (f"effective (includes base settlement); d ~ P_i^{exponent:.3f} (Hertz 0.667); two-term fit: Hertz "
            f"k = {math.exp(two.x[0]):.4g} N/mm^1.5, settlement {two.x[1]:.3g} mm/N = {100 * share:.0f} % of the "
            f"approach at P_i = {middle:.3g} N")
    return _result("normal_stiffness", math.exp(fitted.x[0]), closed, fitted.fun, "relative depth", note), diagnostics


def fit_radius_coefficient(press: Sequence[PathSamples], design: ArrayFingertipDesign) -> FitResult:
    """c_a [mm/N^(1/3)] from per-bump contact radii a_i against the bumps' FEM normal forces (relative residual)."""
    from scipy.optimize import least_squares

    _, _, bump_force, radius, _ = _pressed(press)
    touching = (bump_force > 0.0) & (radius > 0.0)
    bump_force, radius = bump_force[touching], radius[touching]
    if bump_force.size == 0:
        raise ValueError("press samples: no bump in contact")
    fitted = least_squares(lambda x: math.exp(x[0]) * np.cbrt(bump_force) / radius - 1.0,
                           [math.log(float(np.median(radius / np.cbrt(bump_force))))], xtol=1e-12, ftol=1e-12)
    return _result("radius_coefficient", math.exp(fitted.x[0]),
                   ReducedParameters.from_design(design).radius_coefficient, fitted.fun, "relative contact radius",
                   "per-bump radius sqrt(A_i / pi) from nodal tributary areas (quantised by the mesh)")


def _tangential(samples: PathSamples, kind: str) -> np.ndarray:
    mask = samples.load_kind == kind
    if not mask.any():
        raise ValueError(f"case {samples.case!r} has no {kind} increment")
    return mask


def _model_loads(samples: PathSamples, mask, design, parameters):
    """Model bump response at the FEM increments ``mask`` (displacement control from the pressed state)."""
    centres = design.bump_centres
    bump_force = normal_split(samples.normal_force[mask], centres, parameters)             # (m, k)
    displacement = samples.bump_displacement(centres)[mask]                                # (m, k, 2)
    twist = (samples.angle - samples.angle[samples.reference])[mask]
    response = bump_response(bump_force, displacement, np.repeat(twist[:, None], len(centres), axis=1),
                             samples.friction, parameters)
    tip = ReducedFingertip(design, parameters)
    force, torque = tip.wrench(response)
    return bump_force, response, force, torque


def fit_tangential_modulus(shear: Sequence[PathSamples], design: ArrayFingertipDesign, parameters: ReducedParameters):
    """G* [MPa] from the array tangential force against plate shift through the model (residual in N / (mu P)).

    All shear paths together: at several normal forces this also tests the a_i ~ P_i^(1/3) scaling of 2 G* a_i.
    """
    from scipy.optimize import least_squares

    picks = [(path, _tangential(path, "shear")) for path in shear]

    def residual(log_modulus):
        trial = dataclasses.replace(parameters, tangential_modulus=math.exp(log_modulus[0]))
        return np.concatenate([((_model_loads(path, mask, design, trial)[2] - path.tangential_force[mask])
                                / (path.friction * path.normal_force[mask][:, None])).ravel()
                               for path, mask in picks])

    fitted = least_squares(residual, [math.log(parameters.tangential_modulus)], xtol=1e-12, ftol=1e-12,
                           diff_step=1e-6)
    return _result("tangential_modulus", math.exp(fitted.x[0]),
                   ReducedParameters.from_design(design).tangential_modulus, fitted.fun, "N / (mu P)",
                   "effective: bump bending and base shear included")


def fit_torsional_modulus(twist: PathSamples, design: ArrayFingertipDesign, parameters: ReducedParameters):
    """G_t [MPa] from per-bump own-axis torques against the plate twist through the model (N mm / (mu P_i a_i))."""
    from scipy.optimize import least_squares

    mask = _tangential(twist, "twist")
    scale = twist.friction * twist.bump_normal_force[mask] * np.maximum(twist.bump_contact_radius[mask], 1e-12)

    def model(modulus):
        trial = dataclasses.replace(parameters, torsional_modulus=modulus)
        return _model_loads(twist, mask, design, trial)

    def residual(log_modulus):
        return ((model(math.exp(log_modulus[0]))[1].torque - twist.bump_torque[mask]) / scale).ravel()

    fitted = least_squares(residual, [math.log(parameters.torsional_modulus)], xtol=1e-12, ftol=1e-12,
                           diff_step=1e-6)
    modulus = math.exp(fitted.x[0])
    array_torque = model(modulus)[3]
    relative = (array_torque - twist.torque[mask]) / np.abs(twist.torque[mask])
    diagnostics = {"array_torque_relative_error": relative.tolist(),
                   "bump_torque_share": float(np.abs(twist.bump_torque[mask]).sum(axis=1).max()
                                              / np.abs(twist.torque[mask]).max())}
    note = (f"array torque about the centre with this G_t: {100 * np.abs(relative).max():.1f} % max error; the "
            f"bumps' own torques are {100 * diagnostics['bump_torque_share']:.1f} % of it")
    return _result("torsional_modulus", modulus, ReducedParameters.from_design(design).torsional_modulus,
                   fitted.fun, "N mm / (mu P_i a_i)", note), diagnostics


def kernel_grid(design: ArrayFingertipDesign, spacing: float = KERNEL_GRID_SPACING) -> BaseGrid:
    """Fixed base grid [mm] for the kernel fits: wide enough for s up to two pitches and the largest CoP shift."""
    check_positive("spacing", spacing, "mm")
    half = design.half_extent + 2.5 * design.pitch
    axis = np.arange(-math.ceil(half / spacing), math.ceil(half / spacing) + 1) * spacing
    return BaseGrid(axis, axis.copy())


def _model_cells(tip, grid, bump_force, displacement, tangential_force):
    """Cell force (m, k), CoP (m, k, 2), second moment (m, k) of the model's base pressure for m bump states."""
    radius = tip.parameters.radius_coefficient * np.cbrt(np.maximum(bump_force, 0.0))
    nodal = np.stack([tip.base_pressure(grid, force, a, delta, q).ravel() for force, a, delta, q
                      in zip(bump_force, radius, displacement, tangential_force)]) * grid.spacing**2
    return cell_moments(grid.points, nodal, tip.centres)


def fit_kernel_spread(press: Sequence[PathSamples], design: ArrayFingertipDesign, parameters: ReducedParameters):
    """s [mm] from the cell second moments of the FEM base pressure under a press (relative residual)."""
    from scipy.optimize import least_squares

    _, _, bump_force, _, second = _pressed(press)
    radius = parameters.radius_coefficient * np.cbrt(bump_force)
    start = float(np.sqrt(max(np.mean(3.0 * second - radius**2), 1e-6)))     # <r^2> = w^2 / 3, w^2 = a^2 + s^2
    grid = kernel_grid(design)
    zeros = np.zeros(bump_force.shape + (2,))

    def residual(spread):
        tip = ReducedFingertip(design, dataclasses.replace(parameters, kernel_spread=spread[0]))
        return (_model_cells(tip, grid, bump_force, zeros, zeros)[2] / second - 1.0).ravel()

    fitted = least_squares(residual, [start], bounds=([1e-3], [2.0 * design.pitch]), method="dogbox", xtol=1e-12,
                           ftol=1e-12, gtol=1e-12)
    note = (f"analytic <r^2> = (a^2 + s^2) / 3 gives s = {start:.4g} mm; fitted on the model's own cells "
            f"(overlapping kernels, truncated by the cells)")
    return (_result("kernel_spread", fitted.x[0], ReducedParameters.from_design(design).kernel_spread, fitted.fun,
                    "relative second moment", note), {"kernel_spread_analytic": start})


def fit_cop(paths: Sequence[PathSamples], design: ArrayFingertipDesign, parameters: ReducedParameters):
    """cop_gain g [-], moment_arm h [mm]: bounded linear least squares of Delta c_i = g delta_i + h Q_i / P_i [mm].

    The kernel centre is taken for the cell's CoP (the model's law); the diagnostics say how well the model's own
    cells (``base_pressure`` cut like the FEM's) then follow the FEM, and which (g, h) would fit them best. At a
    single normal force Q_i / P_i is a monotone function of delta_i and the two terms cannot be told apart: the
    correlation of the regressors and the standard errors of g and h are reported; paths at two normal forces
    separate them (at a fixed delta, Q_i / P_i ~ P_i^(-2/3) while the displacement term does not change).
    """
    from scipy.optimize import least_squares, lsq_linear

    centres = design.bump_centres
    paths = [path for path in paths if (~path.pressed).any()]
    if not paths:
        raise ValueError("CoP fit: need shear or twist increments")
    pick = [(path, ~path.pressed) for path in paths]
    shift = np.concatenate([p.cop_shift[m] for p, m in pick])                               # (m, k, 2)
    displacement = np.concatenate([p.bump_displacement(centres)[m] for p, m in pick])       # (m, k, 2)
    force = np.concatenate([p.bump_normal_force[m] for p, m in pick])                       # (m, k)
    tangential = np.concatenate([p.bump_tangential_force[m] for p, m in pick])              # (m, k, 2)
    reference = np.concatenate([p.bump_normal_force[p.reference[m]] for p, m in pick])      # pressed state
    ratio = tangential / np.where(force > 0.0, force, np.inf)[..., None]                    # Q_i / P_i
    matrix = np.column_stack([displacement.ravel(), ratio.ravel()])                         # (2 m k, 2)
    target = shift.ravel()
    free = np.linalg.lstsq(matrix, target, rcond=None)[0]
    linear = lsq_linear(matrix, target, bounds=([MIN_COP_GAIN, 0.0], [np.inf, np.inf]), method="bvls")
    gain, arm = linear.x
    variance = float(linear.fun @ linear.fun) / max(target.size - 2, 1)
    standard_error = np.sqrt(np.diag(variance * np.linalg.inv(matrix.T @ matrix)))
    correlation = float(np.corrcoef(matrix.T)[0, 1])
    grid = kernel_grid(design)
    zeros = np.zeros_like(displacement)

    def through_model(gain_arm):
        tip = ReducedFingertip(design, dataclasses.replace(parameters, cop_gain=gain_arm[0], moment_arm=gain_arm[1]))
        moved = _model_cells(tip, grid, force, displacement, tangential)[1]
        still = _model_cells(tip, grid, reference, zeros, zeros)[1]
        return (moved - still - shift).ravel()

    # dogbox: the trust-region-reflective default creeps along a bound and stops on its gtol
    best = least_squares(through_model, np.maximum(linear.x, [MIN_COP_GAIN, 0.0]), bounds=([MIN_COP_GAIN, 0.0],
                         [np.inf, np.inf]), method="dogbox", xtol=1e-12, ftol=1e-12, gtol=1e-12)
    rms = {"fem": float(np.sqrt(np.mean(target**2))), "linear": float(np.sqrt(np.mean(linear.fun**2))),
           "from_gain": float(np.sqrt(np.mean((gain * displacement) ** 2))),
           "from_moment_arm": float(np.sqrt(np.mean((arm * ratio) ** 2))),
           "model_cells": float(np.sqrt(np.mean(through_model(linear.x) ** 2))),
           "model_cells_best": float(np.sqrt(np.mean(best.fun**2)))}
    diagnostics = {"cop_unbounded": {"cop_gain": float(free[0]), "moment_arm": float(free[1])},
                   "cop_standard_error": {"cop_gain": float(standard_error[0]),
                                          "moment_arm": float(standard_error[1])},
                   "cop_regressor_correlation": correlation, "cop_rms": rms,
                   "cop_model_cells_best": {"cop_gain": float(best.x[0]), "moment_arm": float(best.x[1])}}
    closed = ReducedParameters.from_design(design)
    note = (f"FEM CoP shift rms {rms['fem']:.3g} mm, fit rms {rms['linear']:.3g} mm; g delta carries "
            f"{rms['from_gain']:.3g} mm, h Q/P {rms['from_moment_arm']:.3g} mm; delta and Q/P correlate at "
            f"{correlation:.3f} (standard errors g {standard_error[0]:.2g}, h {standard_error[1]:.2g} mm); "
            f"through the model's own sensor cells rms {rms['model_cells']:.3g} mm (best there: g = {best.x[0]:.3g}, "
            f"h = {best.x[1]:.3g} mm, rms {rms['model_cells_best']:.3g} mm)")
    return (_result("cop_gain", gain, closed.cop_gain, linear.fun, "mm (CoP shift)", note),
            _result("moment_arm", arm, closed.moment_arm, linear.fun, "mm (CoP shift)", "fitted with cop_gain"),
            diagnostics)


def _check_tag(tag: str) -> str:
    if not isinstance(tag, str) or not tag or not all(c.isalnum() or c in "._-" for c in tag):
        raise ValueError(f"tag={tag!r} must be a non-empty string of letters, digits, '.', '_' or '-'")
    return tag


def calibrate(design: ArrayFingertipDesign, press: Sequence[PathSamples], shear: Sequence[PathSamples],
              twist: PathSamples, tag: str) -> Calibration:
    """Fit every ReducedParameters field but damping_time to FEM samples of ``design`` (module docstring).

    press: paths whose press increments span several normal forces [N]; shear: plate-shift paths (displacement
    control), at two normal forces to tell cop_gain from moment_arm; twist: a plate-twist path (displacement
    control). The parameters carry ``source="fem:<tag>"``.
    """
    tag = _check_tag(tag)
    press, shear = list(press), list(shear)
    if not shear:
        raise ValueError("calibrate: need at least one shear path")
    frictions = {s.friction for s in (*press, *shear, twist)}
    if len(frictions) != 1:
        raise ValueError(f"the FEM paths use different friction coefficients {sorted(frictions)}; need one mu")
    closed = ReducedParameters.from_design(design)
    stiffness, diagnostics = fit_normal_stiffness(press, design)
    radius = fit_radius_coefficient(press, design)
    parameters = dataclasses.replace(closed, normal_stiffness=stiffness.value, radius_coefficient=radius.value,
                                     source=f"fem:{tag}")
    tangential = fit_tangential_modulus(shear, design, parameters)
    parameters = dataclasses.replace(parameters, tangential_modulus=tangential.value)
    torsional, more = fit_torsional_modulus(twist, design, parameters)
    diagnostics.update(more)
    parameters = dataclasses.replace(parameters, torsional_modulus=torsional.value)
    spread, more = fit_kernel_spread(press, design, parameters)
    diagnostics.update(more)
    parameters = dataclasses.replace(parameters, kernel_spread=spread.value)
    gain, arm, more = fit_cop([*shear, twist], design, parameters)
    diagnostics.update(more)
    parameters = dataclasses.replace(parameters, cop_gain=gain.value, moment_arm=arm.value)
    damping = FitResult("damping_time", parameters.damping_time, closed.damping_time, 0, 0.0, 0.0, "-",
                        "not fitted: quasi-static FEM paths carry no rate; closed-form default kept")
    return Calibration(design, parameters, (stiffness, radius, tangential, torsional, spread, gain, arm, damping),
                       diagnostics)
