"""Reduced model of one array fingertip: array state for a load or a rigid displacement, slip limit, base pressure.

The object is a rigid flat face. A rigid displacement of the object relative to the fingertip - translation t (2,)
[mm] and rotation theta [rad] about the array centre, in the sensor plane - shears bump i at r_i by
delta_i = t + theta z x r_i and twists it by theta; each bump answers with its own laws (``_bumps``). The array
carries the tangential force F = sum Q_i and the torque T = sum (r_i x Q_i + T_i) about its centre.

Gross slip of the whole contact (combined criterion). The bumps' friction limits bound the wrench (F, T) the array
can carry: bump i contributes any (Q_i, T_i) inside its ellipse (``_bumps``), so the array's limit set is their
Minkowski sum mapped to the centre. By maximum dissipation its support function for a sliding twist
xi = (v, omega) (velocity of the centre [mm/s], spin [rad/s]) is

    h(xi) = sum_i sqrt( (mu P_i |v + omega z x r_i|)^2 + (T_slip,i omega)^2 ),     T_slip,i = (3 pi/16) mu P_i a_i,

and the load (F, T) is carried iff F.v + T omega <= h(xi) for every xi. The slip margin
lambda* = min_xi h(xi) / (F.v + T omega) is the factor by which the load may grow before the contact slides
(lambda* <= 1: gross slip). Translation alone gives mu P / |F| (gross slip at mu P); torque alone gives
sum mu P_i |r_i| plus the bumps' own torsion; in between the torque the array can carry falls with the tangential
load. On an anisotropic surface (friction mu (1 + e) along the sensor's x and mu (1 - e) along y, the plant's
``friction_anisotropy``) a bump's force set is that ellipse scaled by P_i, and mu |u| above becomes
mu sqrt(((1 + e) u_x)^2 + ((1 - e) u_y)^2); the bumps' own spin limit keeps mu (the plant's spin limit takes the
friction along each bump's shear, between the two; the bumps' torsion carries about 1 % of an array's torque). The
minimising twist tells the mode: its instantaneous centre |v| / |omega| inside the array (within the
farthest bump) is a rotational slip, outside it a translational slip.

The base pressure that the sensor reads is ``_base``'s: per bump a mirrored Gaussian bell and the pressure
couple of its overturning moment.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from contact.theory import LUBKIN_SLIP_TORQUE_RATIO
from fem.validation import check_finite_array, check_positive, check_range

from ._base import BaseGrid, BaseKernel, base_grid
from ._bumps import BumpResponse, bump_response, normal_split
from ._design import ArrayFingertipDesign, ReducedParameters
from ._store import load_calibration

__all__ = ["ContactState", "ReducedFingertip", "SlipMode", "BaseGrid", "load_calibrated"]

_DIRECTIONS = 4000                   # Fibonacci points on the twist sphere for the coarse search of lambda*
NON_SMOOTH_TOLERANCE = 1e-3         # accepted residual / (mu P) where Newton stalls at a bump's slip onset
GROSS_SLIP_REPORT = 0.99             # a load beyond the limit is reported at this fraction of lambda* times it


class SlipMode:
    """Names of the gross-slip modes (plain strings, as written to the CSV outputs)."""

    NONE = "none"
    TRANSLATION = "translation"
    ROTATION = "rotation"


@dataclass(frozen=True, eq=False)
class ContactState:
    """State of the array contact.

    normal_force (k,) [N], contact_radius (k,) [mm], shear_displacement (k, 2) [mm], twist (k,) [rad] per bump;
    bump_tangential_force (k, 2) [N], bump_torque (k,) [N mm]; stick_ratio_translational / _rotational (k,) [-];
    sliding (k,) bool; translation (2,) [mm] and rotation [rad] of the object; tangential_force (2,) [N] and
    torque [N mm] about the array centre; slip_margin lambda* [-]; gross_slip (bool); slip_mode (SlipMode).
    """

    normal_force: np.ndarray
    contact_radius: np.ndarray
    shear_displacement: np.ndarray
    twist: np.ndarray
    bump_tangential_force: np.ndarray
    bump_torque: np.ndarray
    stick_ratio_translational: np.ndarray
    stick_ratio_rotational: np.ndarray
    sliding: np.ndarray
    translation: np.ndarray
    rotation: float
    tangential_force: np.ndarray
    torque: float
    slip_margin: float
    gross_slip: bool
    slip_mode: str


def _fibonacci_sphere(count: int) -> np.ndarray:
    index = np.arange(count) + 0.5
    polar = np.arccos(1.0 - 2.0 * index / count)
    azimuth = math.pi * (1.0 + math.sqrt(5.0)) * index
    return np.stack([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)], axis=1)


class ReducedFingertip:
    """Reduced model of one array fingertip (design + parameters); every method in mm, N, N mm, rad.

    Parameters
    ----------
    design : ArrayFingertipDesign, optional -- default the paper's 3x3 fingertip (``ArrayFingertipDesign()``).
    parameters : ReducedParameters, optional -- default ``ReducedParameters.from_design(design)`` (closed form).
    """

    def __init__(self, design: ArrayFingertipDesign | None = None, parameters: ReducedParameters | None = None):
        design = ArrayFingertipDesign() if design is None else design
        self.design = design
        self.parameters = ReducedParameters.from_design(design) if parameters is None else parameters
        self.centres = design.bump_centres                                             # (k, 2) [mm]
        self.length = float(design.pitch)                                              # twist-sphere scale [mm]
        self._directions = _fibonacci_sphere(_DIRECTIONS)
        self._kernel_cache = {}                                                        # id(grid) -> BaseKernel

    # --- round trip ---------------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """{"design": ..., "parameters": ...} (JSON-ready): the parameters are stored with the design."""
        return {"design": self.design.to_dict(), "parameters": self.parameters.to_dict()}

    @classmethod
    def from_dict(cls, data: dict) -> "ReducedFingertip":
        return cls(ArrayFingertipDesign.from_dict(data["design"]), ReducedParameters.from_dict(data["parameters"]))

    @classmethod
    def calibrated(cls, path=None, design: ArrayFingertipDesign | None = None) -> "ReducedFingertip":
        """FEM-calibrated model from a calibration file (default: the packaged 3x3 fingertip; ``_store``).

        With ``design`` given, the file's design must equal it (ValueError naming the fields that differ).
        """
        stored = load_calibration(path, design)
        return cls(stored.design, stored.parameters)

    # --- states -------------------------------------------------------------------------------------------
    def bump_shear(self, translation, rotation) -> np.ndarray:
        """Bump shear displacements delta_i = t + theta z x r_i (..., k, 2) [mm] of a rigid object motion."""
        translation = np.asarray(translation, dtype=float)
        rotation = np.asarray(rotation, dtype=float)
        perpendicular = np.stack([-self.centres[:, 1], self.centres[:, 0]], axis=1)     # z x r_i (k, 2)
        return translation[..., None, :] + rotation[..., None, None] * perpendicular

    def wrench(self, response: BumpResponse):
        """Array tangential force (..., 2) [N] and torque (...,) [N mm] about the centre from bump loads."""
        force = response.tangential_force
        moment = self.centres[:, 0] * force[..., 1] - self.centres[:, 1] * force[..., 0]
        return force.sum(axis=-2), (moment + response.torque).sum(axis=-1)

    def displacement_state(self, normal_force, translation, rotation, friction, tilt=(0.0, 0.0)) -> ContactState:
        """State for a rigid object displacement t (2,) [mm], theta [rad] at total normal force P [N]."""
        bump_force = normal_split(check_positive("normal_force", normal_force, "N"), self.centres, self.parameters,
                                  tilt)
        translation = check_finite_array("translation", translation)
        response = bump_response(bump_force, self.bump_shear(translation, rotation), np.full(len(self.centres),
                                 float(rotation)), check_positive("friction", friction), self.parameters)
        force, torque = self.wrench(response)
        if np.all(response.sliding):
            margin, mode = 1.0, self._mode_of_motion(translation, float(rotation))
        else:
            margin, mode = self.slip_margin(bump_force, response.contact_radius, friction, force, float(torque))
        return self._state(bump_force, response, translation, float(rotation), force, float(torque), margin, mode)

    def load_state(self, normal_force, tangential_force, torque, friction, tilt=(0.0, 0.0),
                   tolerance: float = 1e-10, max_iterations: int = 100) -> ContactState:
        """State carrying the tangential force F (2,) [N] and torque T [N mm] about the array centre at P [N].

        If the load is beyond the slip limit (lambda* <= 1) the state is gross slip: the displacements reported are
        those just before the slip onset (the load scaled to 0.99 lambda* F, 0.99 lambda* T) and ``gross_slip`` is True.
        Otherwise (t, theta) solve sum Q_i = F, sum r_i x Q_i + T_i = T by a damped Newton method (finite-difference
        Jacobian of the 3 unknowns, backtracking). A bump's loads turn onto the flow direction when it starts to
        slide (``_bumps``), a small kink in the map where Newton may stall: a residual below 1e-3 mu P is then
        accepted; above it the method raises RuntimeError with the residual history.
        """
        friction = check_positive("friction", friction)
        bump_force = normal_split(check_positive("normal_force", normal_force, "N"), self.centres, self.parameters,
                                  tilt)
        load = np.append(check_finite_array("tangential_force", tangential_force), float(torque))
        radius = self.parameters.radius_coefficient * np.cbrt(bump_force)
        margin, mode = self.slip_margin(bump_force, radius, friction, load[:2], load[2])
        gross = margin <= 1.0
        target = load * (min(margin, 1.0) * GROSS_SLIP_REPORT if gross else 1.0)
        unknown = self._solve(bump_force, friction, target, tolerance, max_iterations)
        response = bump_response(bump_force, self.bump_shear(unknown[:2], unknown[2]),
                                 np.full(len(self.centres), unknown[2]), friction, self.parameters)
        force, carried = self.wrench(response)
        return self._state(bump_force, response, unknown[:2], float(unknown[2]), force, float(carried), margin,
                           mode if gross else SlipMode.NONE, gross)

    def _solve(self, bump_force, friction, target, tolerance, max_iterations) -> np.ndarray:
        scale = np.array([1.0, 1.0, 1.0 / self.length])                              # torque residual in N

        def residual(unknowns):                                                       # (m, 3) -> (m, 3)
            response = bump_response(bump_force, self.bump_shear(unknowns[:, :2], unknowns[:, 2]),
                                     np.repeat(unknowns[:, 2:3], len(self.centres), axis=1), friction, self.parameters)
            force, torque = self.wrench(response)
            return (np.column_stack([force, torque]) - target) * scale

        tangential, torsional = (s.sum() for s in _stiffness_terms(bump_force, self.parameters, self.centres))
        unknown = target / np.array([tangential, tangential, torsional])             # full-stick guess
        current = residual(unknown[None])[0]
        history = [float(np.linalg.norm(current))]
        limit = friction * bump_force.sum()
        step_size = 1e-7 * max(1.0, float(np.abs(unknown).max()))
        for _ in range(max_iterations):
            if history[-1] <= tolerance * limit:
                return unknown
            probes = unknown + np.vstack([np.zeros(3), step_size * np.eye(3)])
            values = residual(probes)
            jacobian = (values[1:] - values[0]).T / step_size
            step = np.linalg.lstsq(jacobian, -current, rcond=None)[0]
            for damping in 0.5 ** np.arange(30):
                trial = unknown + damping * step
                trial_residual = residual(trial[None])[0]
                if np.linalg.norm(trial_residual) < history[-1]:
                    break
            unknown, current = trial, trial_residual
            history.append(float(np.linalg.norm(current)))
        if history[-1] <= NON_SMOOTH_TOLERANCE * limit:
            return unknown
        raise RuntimeError(f"load_state did not converge in {max_iterations} Newton steps; residual history [N]: "
                           f"{history[:3]} ... {history[-3:]}")

    def _state(self, bump_force, response, translation, rotation, force, torque, margin, mode, gross=None):
        gross = bool(margin <= 1.0) if gross is None else bool(gross)
        return ContactState(
            normal_force=bump_force, contact_radius=response.contact_radius,
            shear_displacement=self.bump_shear(translation, rotation), twist=np.full(len(self.centres), rotation),
            bump_tangential_force=response.tangential_force, bump_torque=response.torque,
            stick_ratio_translational=response.stick_ratio_translational,
            stick_ratio_rotational=response.stick_ratio_rotational, sliding=response.sliding,
            translation=np.asarray(translation, dtype=float), rotation=rotation, tangential_force=force,
            torque=torque, slip_margin=float(margin), gross_slip=gross, slip_mode=mode if gross else SlipMode.NONE)

    # --- slip limit ---------------------------------------------------------------------------------------
    def support(self, bump_force, contact_radius, friction, twists, anisotropy: float = 0.0) -> np.ndarray:
        """Support function h(xi) (m,) [N mm/s] of the array's limit set for twists (m, 3) = (v_x, v_y, omega);
        ``anisotropy`` e: friction mu (1 + e) along the sensor's x, mu (1 - e) along y (module docstring)."""
        twists = np.asarray(twists, dtype=float)
        velocity = self.bump_shear(twists[:, :2], twists[:, 2])                      # (m, k, 2) bump slip velocity
        velocity = velocity * np.array([1.0 + anisotropy, 1.0 - anisotropy])         # the ellipse's support
        limit = friction * np.asarray(bump_force)
        spin = LUBKIN_SLIP_TORQUE_RATIO * limit * np.asarray(contact_radius)
        return np.sqrt((limit * np.linalg.norm(velocity, axis=-1)) ** 2 + (spin * twists[:, 2:3]) ** 2).sum(axis=1)

    def slip_margin(self, bump_force, contact_radius, friction, tangential_force, torque, anisotropy: float = 0.0):
        """lambda* = min_xi h(xi) / (F.v + T omega) [-] and the slip mode of the minimising twist (module docstring).

        Coarse search over 4000 twist directions, refined by Nelder-Mead on the sphere (relative accuracy ~1e-6).
        No load gives (inf, "none").
        """
        from scipy.optimize import minimize

        # |e| < 1: at 1 the ellipse's minor axis, and the friction along it, vanishes
        check_range("anisotropy", anisotropy, -1.0, 1.0, low_open=True, high_open=True)
        load = np.append(np.asarray(tangential_force, dtype=float), float(torque))
        scale = np.array([1.0, 1.0, 1.0 / self.length])                              # omega L on the sphere
        if not np.any(load):
            return math.inf, SlipMode.NONE

        def ratio(twists):
            twists = np.atleast_2d(twists) * scale
            power = twists @ load
            value = (self.support(bump_force, contact_radius, friction, twists, anisotropy)
                     / np.where(power > 0, power, 1.0))
            return np.where(power > 0, value, np.inf)

        coarse = ratio(self._directions)
        best = self._directions[np.argmin(coarse)]
        refined = minimize(lambda x: float(ratio(x / np.linalg.norm(x))[0]), best, method="Nelder-Mead",
                           options=dict(xatol=1e-8, fatol=1e-10 * coarse.min(), maxiter=400))
        twist = refined.x / np.linalg.norm(refined.x) * scale
        margin = min(float(refined.fun), float(coarse.min()))
        return margin, self._mode_of_motion(twist[:2], twist[2])

    def _mode_of_motion(self, velocity, spin) -> str:
        """Rotation if the instantaneous centre |v| / |omega| lies within the farthest bump, else translation."""
        reach = float(np.linalg.norm(self.centres, axis=1).max())
        if spin != 0.0 and np.linalg.norm(velocity) < reach * abs(spin):
            return SlipMode.ROTATION
        return SlipMode.TRANSLATION

    def minimum_normal_force(self, tangential_force, torque, friction, tilt=(0.0, 0.0), tolerance=1e-4,
                             anisotropy: float = 0.0) -> float:
        """Least total normal force P [N] at which the load is carried (lambda* = 1), to a relative ``tolerance``;
        ``anisotropy`` as in ``support``."""
        from scipy.optimize import brentq

        def margin(force):
            bump_force = normal_split(force, self.centres, self.parameters, tilt)
            radius = self.parameters.radius_coefficient * np.cbrt(bump_force)
            return self.slip_margin(bump_force, radius, friction, tangential_force, torque, anisotropy)[0]

        def carried(force):
            return margin(force) > 1.0

        def log_margin(log_force):
            return math.log(margin(math.exp(log_force)))

        low, high = 1e-3, 1.0
        while carried(low):
            low *= 0.1
        while not carried(high):
            high *= 2.0
        # lambda*(P) rises smoothly with P: Brent's method on log lambda* needs about 6 margins where bisection to
        # the same tolerance needed 14; the root's upper end is returned, so the force found carries the load
        root = brentq(log_margin, math.log(low), math.log(high), xtol=0.5 * tolerance, rtol=1e-12)
        return min(high, math.exp(root + 0.5 * tolerance))

    # --- base pressure ------------------------------------------------------------------------------------
    def base_grid(self, spacing: float = 0.5) -> BaseGrid:
        """Square grid [mm] of the given spacing over the base layer, one node past its edges (zero there)."""
        return base_grid(self.design, spacing)

    def couple(self, bump_force, shear_displacement, tangential_force=None) -> np.ndarray:
        """Pressure couple M_i = h(P_i) Q_i + g P_i delta_i (..., k, 2) [N mm] on the sensor plane (``_design``).

        bump_force P_i (..., k) [N], shear_displacement delta_i (..., k, 2) [mm], tangential_force Q_i (..., k, 2)
        [N] (None: no load term). The centre of bump i's own pressure moves by M_i / P_i.
        """
        p = self.parameters
        force = np.asarray(bump_force, dtype=float)
        if tangential_force is None:
            return p.displacement_gain * force[..., None] * np.asarray(shear_displacement, dtype=float)
        moment = p.couple_arm_at(force)[..., None] * tangential_force
        if p.displacement_gain != 0.0:
            moment = moment + p.displacement_gain * force[..., None] * shear_displacement
        return moment

    def base_pressure(self, grid: BaseGrid, bump_force, contact_radius, shear_displacement,
                      tangential_force=None) -> np.ndarray:
        """Pressure (ny, nx) [MPa] on the sensor plane: sum over bumps of P_i G(x - r_i) - M_i . (grad G)(x - r_i).

        G is the Gaussian of standard deviation ``kernel_width`` mirrored at the base layer's edges and zero beyond
        them (``_base``), M_i = ``couple(bump_force, shear_displacement, tangential_force)``. Each bump's bell
        carries P_i (k,) [N] and its couple has the first moment M_i [N mm] on the grid (trapezoid weights, so the
        piecewise-linear field of ``PressureField.from_grid`` carries sum P_i exactly); a bump with P_i = Q_i = 0
        adds nothing. ``contact_radius`` (k,) [mm] is checked for its shape only: the base field does not depend on
        it. The grid must reach past the footprint (``base_grid``); its kernel factors are cached per grid object,
        so a call costs one (ny, 3k) x (3k, nx) product.
        """
        count = len(self.centres)
        bump_force = np.asarray(bump_force, dtype=float)
        shear_displacement = np.asarray(shear_displacement, dtype=float)
        for name, value, shape in (("bump_force", bump_force, (count,)),
                                   ("contact_radius", np.asarray(contact_radius), (count,)),
                                   ("shear_displacement", shear_displacement, (count, 2)),
                                   ("tangential_force", tangential_force, (count, 2))):
            if value is not None and np.shape(value) != shape:
                raise ValueError(f"{name} has shape {np.shape(value)}, expected {shape} ({count} bumps)")
        kernel = self._kernel_cache.get(id(grid))
        if kernel is None or kernel.grid is not grid:
            kernel = BaseKernel(self.design, self.parameters.kernel_width, grid)
            if len(self._kernel_cache) >= 8:
                self._kernel_cache.pop(next(iter(self._kernel_cache)))
            self._kernel_cache[id(grid)] = kernel
        return kernel.pressure(bump_force, self.couple(bump_force, shear_displacement, tangential_force))

    def state_pressure(self, grid: BaseGrid, state: ContactState) -> np.ndarray:
        """``base_pressure`` of a ContactState (ny, nx) [MPa]."""
        return self.base_pressure(grid, state.normal_force, state.contact_radius, state.shear_displacement,
                                  state.bump_tangential_force)


def load_calibrated(path=None, design: ArrayFingertipDesign | None = None) -> "ReducedFingertip":
    """ReducedFingertip with FEM-calibrated parameters (default: the packaged file of the paper's 3x3 fingertip)."""
    return ReducedFingertip.calibrated(path, design)


def _stiffness_terms(bump_force, parameters, centres):
    """Full-stick tangential stiffness per bump (k,) [N/mm] and its torsional share k_i r_i^2 + k_t,i [N mm/rad]."""
    from ._bumps import full_stick_stiffness

    tangential, torsional = full_stick_stiffness(bump_force, parameters)
    return tangential, tangential * np.sum(centres**2, axis=1) + torsional
