"""Calibration of the reduced fingertip model (``ReducedParameters``) from FEM load paths of the same design.

Inputs are ``PathSamples`` of FEM paths: a press path at several normal forces, plate-shift paths along x and y at
several normal forces (some into full sliding), and plate-twist paths (one after a shift). Each parameter is fitted
with scipy ``least_squares`` on the quantity it governs, in the order that lets the later fits use the earlier
values:

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
kernel_width sigma, couple_arm h_0, couple_arm_slope kappa (displacement_gain g)
    the base pressure (``_base``): per-bump CoP shift of the sensor-plane pressure in the bumps' Voronoi cells
    against the pressed state, model (fed with the FEM's own bump loads and displacements) against FEM, over every
    shear and twist increment (``fit_base_pressure``). The paths tell them apart: normal forces from 1 to 6 N (the
    arm falls with P_i: h_0 against kappa), sliding increments (the displacement grows at a constant load: g), both
    axes and twist (sigma, the edge mirrors). g is held at 0 for a small-strain FEM (its contact loads act on the
    undeformed bump tops, and the FEM's CoP stays put while a bump slides); the free fit is kept as a diagnostic.
couple_arm_limit h_inf
    not fitted: H / 2 (the paths' bump forces stay far from it).
damping_time
    a quasi-static FEM path cannot see the gel's viscosity: the closed-form default is kept.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from ._base import BaseGrid
from ._bumps import bump_response, normal_split
from ._design import ArrayFingertipDesign, ReducedParameters
from ._model import ReducedFingertip
from ._samples import PathSamples, model_cells

__all__ = ["FitResult", "Calibration", "calibrate", "fit_normal_stiffness", "fit_radius_coefficient",
           "fit_tangential_modulus", "fit_torsional_modulus", "fit_base_pressure", "kernel_grid", "COP_FIELDS"]

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


def fit_torsional_modulus(twist: Sequence[PathSamples], design: ArrayFingertipDesign,
                          parameters: ReducedParameters):
    """G_t [MPa] from per-bump own-axis torques against the plate twist through the model (N mm / (mu P_i a_i)).

    Every twist increment of the paths (a twist after a shift too: the model shears each bump by t + theta z x r_i).
    """
    from scipy.optimize import least_squares

    picks = [(path, _tangential(path, "twist")) for path in twist]
    scales = [path.friction * path.bump_normal_force[mask] * np.maximum(path.bump_contact_radius[mask], 1e-12)
              for path, mask in picks]

    def residual(log_modulus):
        trial = dataclasses.replace(parameters, torsional_modulus=math.exp(log_modulus[0]))
        return np.concatenate([((_model_loads(path, mask, design, trial)[1].torque - path.bump_torque[mask])
                                / scale).ravel() for (path, mask), scale in zip(picks, scales)])

    fitted = least_squares(residual, [math.log(parameters.torsional_modulus)], xtol=1e-12, ftol=1e-12,
                           diff_step=1e-6)
    modulus = math.exp(fitted.x[0])
    trial = dataclasses.replace(parameters, torsional_modulus=modulus)
    relative = np.concatenate([(_model_loads(path, mask, design, trial)[3] - path.torque[mask])
                               / np.abs(path.torque[mask]) for path, mask in picks])
    share = max(float(np.abs(path.bump_torque[mask]).sum(axis=1).max() / np.abs(path.torque[mask]).max())
                for path, mask in picks)
    diagnostics = {"array_torque_relative_error": relative.tolist(), "bump_torque_share": share}
    note = (f"array torque about the centre with this G_t: {100 * np.abs(relative).max():.1f} % max error; the "
            f"bumps' own torques are {100 * share:.1f} % of it")
    return _result("torsional_modulus", modulus, ReducedParameters.from_design(design).torsional_modulus,
                   fitted.fun, "N mm / (mu P_i a_i)", note), diagnostics


def kernel_grid(design: ArrayFingertipDesign, spacing: float = KERNEL_GRID_SPACING) -> BaseGrid:
    """The model's base grid [mm] of ``design`` for the kernel fits (``ReducedFingertip.base_grid``)."""
    return ReducedFingertip(design).base_grid(spacing)


@dataclass(frozen=True, eq=False)
class _CopData:
    """FEM increments of the CoP fit: bump loads and displacements (m, k[, 2]) of the shear and twist increments and
    of the pressed states they start from, the FEM's CoP shifts, and each increment's largest shift (m,) [mm]."""

    bump_force: np.ndarray
    tangential_force: np.ndarray
    displacement: np.ndarray
    pressed_force: np.ndarray
    pressed_tangential_force: np.ndarray     # a press leaves Q_i ~ 1 % of P_i (friction against the bulge)
    cop_shift: np.ndarray
    scale: np.ndarray
    normal_force: np.ndarray                  # (m,) the path's total normal force [N]

    @classmethod
    def of(cls, paths: Sequence[PathSamples], design: ArrayFingertipDesign) -> "_CopData":
        paths = [path for path in paths if (~path.pressed).any()]
        if not paths:
            raise ValueError("CoP fit: need shear or twist increments")
        pick = [(path, ~path.pressed) for path in paths]

        def stack(values):
            return np.concatenate([values(p)[m] for p, m in pick])

        shift = stack(lambda p: p.cop_shift)                                                # (m, k, 2)
        scale = np.linalg.norm(shift, axis=2).max(axis=1)
        if np.any(scale <= 0.0):
            raise ValueError("CoP fit: a shear or twist increment whose base CoP did not move")
        return cls(stack(lambda p: p.bump_normal_force), stack(lambda p: p.bump_tangential_force),
                   stack(lambda p: p.bump_displacement(design.bump_centres)),
                   stack(lambda p: p.bump_normal_force[p.reference]),
                   stack(lambda p: p.bump_tangential_force[p.reference]), shift, scale,
                   stack(lambda p: p.normal_force))

    def residual(self, tip, grid) -> np.ndarray:
        """(model cell CoP shift - FEM) / the increment's largest FEM shift (m, k, 2) [-], FEM bump loads in."""
        moved = model_cells(tip, grid, self.bump_force, self.displacement, self.tangential_force)[1]
        still = model_cells(tip, grid, self.pressed_force, np.zeros_like(self.displacement),
                            self.pressed_tangential_force)[1]
        return (moved - still - self.cop_shift) / self.scale[:, None, None]


COP_FIELDS = ("kernel_width", "couple_arm", "couple_arm_slope", "displacement_gain")
SMALL_STRAIN_GAIN = 0.0         # g of a small-strain FEM: its contact loads act on the undeformed bump tops


def _fit_cop(data: _CopData, design, parameters, grid, fields):
    """least_squares of the CoP residual over ``fields`` (a prefix of COP_FIELDS); fit, standard errors, correlation."""
    from scipy.optimize import least_squares

    def model(values):
        return ReducedFingertip(design, dataclasses.replace(parameters, **dict(zip(fields, values))))

    bounds = {"kernel_width": (0.05 * design.pitch, design.pitch),
              "couple_arm": (parameters.couple_arm_limit * 1.001, 3.0 * design.bump_height),
              "couple_arm_slope": (0.0, 100.0), "displacement_gain": (-2.0, 2.0)}
    low, high = np.array([bounds[f] for f in fields]).T
    start = np.clip([getattr(parameters, f) for f in fields], low, high)
    scale = [0.1 if f == "displacement_gain" else 1.0 for f in fields]
    # dogbox: the trust-region-reflective default creeps along a bound (kappa = 0) and stops on its gtol
    fitted = least_squares(lambda values: data.residual(model(values), grid).ravel(), start, bounds=(low, high),
                           method="dogbox", x_scale=scale, diff_step=1e-4, xtol=1e-10, ftol=1e-10, gtol=1e-10)
    variance = float(fitted.fun @ fitted.fun) / max(fitted.fun.size - len(fields), 1)
    covariance = variance * np.linalg.pinv(fitted.jac.T @ fitted.jac)
    error = np.sqrt(np.diag(covariance))
    outer = np.outer(error, error)
    correlation = np.divide(covariance, outer, out=np.zeros_like(covariance), where=outer > 0.0)  # exact data: 0
    return fitted, error, correlation, model(fitted.x)


def fit_base_pressure(paths: Sequence[PathSamples], press: Sequence[PathSamples], design: ArrayFingertipDesign,
                      parameters: ReducedParameters, displacement_gain: float | None = SMALL_STRAIN_GAIN):
    """sigma [mm], h_0 [mm], kappa [mm/N] (and g [-]) from the per-bump base CoP shifts of shear and twist paths.

    The model's base pressure with the FEM's own bump loads (P_i, Q_i, delta_i per increment, and Q_i of the pressed
    state each starts from) is cut into the same Voronoi cells as the FEM's sensor plane, and its cell CoP shifts
    from the pressed state are fitted to the FEM's (``least_squares``, residual over the increment's largest FEM
    shift, the held-out error measure). h_inf stays at its closed-form H / 2 (the arm of a column whose top cannot
    turn: the FEM's forces do not reach it). Told apart by: several normal forces (h_0 against kappa: the arm falls
    with P_i), sliding increments (the displacement grows at a constant load: g), both axes and twist (sigma and the
    edge mirrors).

    ``displacement_gain``: g is held at this value (default 0: in a small-strain FEM the contact loads act on the
    undeformed bump tops, so its base pressure cannot depend on the displacement; the sliding paths confirm it)
    or fitted with the others (None). Either way the diagnostics hold the free four-parameter fit with its standard
    errors and correlations, the correlation of the old regressors (delta_i against Q_i / P_i) over these paths,
    and the kernel width the press cells' second moments alone would give.
    """
    from scipy.optimize import least_squares

    data = _CopData.of(paths, design)
    forces = np.unique(np.round(data.normal_force, 6))
    if forces.size < 2:
        raise ValueError(f"CoP fit: the shear and twist paths all press with {forces[0]:g} N; need paths at two or "
                         f"more normal forces to tell the couple arm from its fall with the bump force")
    grid = kernel_grid(design)
    free, free_error, correlation, free_tip = _fit_cop(data, design, parameters, grid, COP_FIELDS)
    if displacement_gain is None:
        fitted, error, tip = free, free_error, free_tip
    else:
        held = dataclasses.replace(parameters, displacement_gain=displacement_gain)
        fitted, error, _, tip = _fit_cop(data, design, held, grid, COP_FIELDS[:3])
    ratio = data.tangential_force / np.where(data.bump_force > 0.0, data.bump_force, np.inf)[..., None]
    regressors = np.corrcoef(data.displacement.ravel(), ratio.ravel())[0, 1]
    _, _, bump_force, _, second = _pressed(press)
    zeros = np.zeros(bump_force.shape + (2,))

    def spread(width):                        # the press cells' second moments, relative to the FEM's
        trial = ReducedFingertip(design, dataclasses.replace(tip.parameters, kernel_width=width[0]))
        return (np.sqrt(model_cells(trial, grid, bump_force, zeros, zeros)[2] / second) - 1.0).ravel()

    width_from_press = least_squares(spread, [tip.parameters.kernel_width], bounds=([0.05 * design.pitch],
                                     [design.pitch]), diff_step=1e-4).x[0]
    diagnostics = {"base_pressure_free_fit": dict(zip(COP_FIELDS, free.x.tolist())),
                   "base_pressure_free_fit_standard_error": dict(zip(COP_FIELDS, free_error.tolist())),
                   "base_pressure_free_fit_correlation": {
                       f"{a}/{b}": float(correlation[i, j]) for i, a in enumerate(COP_FIELDS)
                       for j, b in enumerate(COP_FIELDS) if i < j},
                   "base_pressure_free_fit_rms": float(np.sqrt(np.mean(free.fun**2))),
                   "cop_old_regressor_correlation": float(regressors),
                   "cop_fit_increments": int(data.scale.size), "cop_fit_normal_forces": forces.tolist(),
                   "kernel_width_from_press_spread": float(width_from_press)}
    closed = ReducedParameters.from_design(design)
    unit = "CoP shift / the increment's largest FEM shift"
    notes = {"kernel_width": f"Gaussian sigma, bell and couple alike; the press cells' second moments alone give "
                             f"{width_from_press:.3g} mm",
             "couple_arm": f"H = R + t = {design.bump_height:.4g} mm; arm at P_i = 1 N: "
                           f"{tip.parameters.couple_arm_at(1.0):.3g} mm",
             "couple_arm_slope": f"arm falls towards h_inf = {parameters.couple_arm_limit:.4g} mm as P_i grows"}
    results = [_result(name, fitted.x[i], getattr(closed, name), fitted.fun, unit,
                       f"{notes[name]}; standard error {error[i]:.2g}") for i, name in enumerate(COP_FIELDS[:3])]
    rms = float(np.sqrt(np.mean(fitted.fun**2)))
    free_note = (f"free fit g = {free.x[3]:.3g} +- {free_error[3]:.2g}, correlated {correlation[2, 3]:.2f} with "
                 f"kappa (rms {diagnostics['base_pressure_free_fit_rms']:.4g} against {rms:.4g}); old regressors "
                 f"delta_i and Q_i / P_i correlate at {regressors:.3f} over these paths")
    if displacement_gain is None:
        results.append(_result("displacement_gain", fitted.x[3], closed.displacement_gain, fitted.fun, unit,
                               f"fitted; standard error {error[3]:.2g}; {free_note}"))
    else:
        results.append(_result("displacement_gain", displacement_gain, closed.displacement_gain, fitted.fun, unit,
                               f"held at {displacement_gain:g} (small-strain FEM: contact loads on the undeformed "
                               f"bump tops); {free_note}"))
    return results, diagnostics


def _check_tag(tag: str) -> str:
    if not isinstance(tag, str) or not tag or not all(c.isalnum() or c in "._-" for c in tag):
        raise ValueError(f"tag={tag!r} must be a non-empty string of letters, digits, '.', '_' or '-'")
    return tag


def calibrate(design: ArrayFingertipDesign, press: Sequence[PathSamples], shear: Sequence[PathSamples],
              twist: Sequence[PathSamples], tag: str,
              displacement_gain: float | None = SMALL_STRAIN_GAIN) -> Calibration:
    """Fit the ReducedParameters fields but damping_time and couple_arm_limit to FEM samples of ``design``.

    press: paths whose press increments span several normal forces [N]; shear: shear paths (force or displacement
    control) along x and y at several normal forces, some into full sliding; twist: twist paths (possibly after a
    shear). Module docstring for what each fit reads. ``displacement_gain``: held at this value (default 0, the
    small-strain FEM's) or fitted (None; ``fit_base_pressure``). The parameters carry ``source="fem:<tag>"``.
    """
    tag = _check_tag(tag)
    press, shear, twist = list(press), list(shear), list(twist)
    if not shear or not twist:
        raise ValueError(f"calibrate: need at least one shear and one twist path, got {len(shear)} and {len(twist)}")
    frictions = {s.friction for s in (*press, *shear, *twist)}
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
    pressure, more = fit_base_pressure([*shear, *twist], press, design, parameters, displacement_gain)
    diagnostics.update(more)
    parameters = dataclasses.replace(parameters, **{fit.parameter: fit.value for fit in pressure})
    limit = FitResult("couple_arm_limit", parameters.couple_arm_limit, closed.couple_arm_limit, 0, 0.0, 0.0, "mm",
                      "not fitted: H / 2, the arm of a bump column whose top cannot turn (reached at bump forces "
                      "beyond the FEM paths)")
    damping = FitResult("damping_time", parameters.damping_time, closed.damping_time, 0, 0.0, 0.0, "-",
                        "not fitted: quasi-static FEM paths carry no rate; closed-form default kept")
    return Calibration(design, parameters, (stiffness, radius, tangential, torsional, *pressure, limit, damping),
                       diagnostics)
