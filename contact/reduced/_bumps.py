"""Per-bump laws of the reduced model: normal split, Hertz radius, Mindlin shear, Lubkin twist, combined friction limit.

All functions are vectorised over leading axes (..., k) of k bumps and take mm, N, MPa, N mm, rad.

Combined load on one bump. A bump under a tangential force Q and a torque T about its normal slides as a whole when
(Q, T) reaches its limit surface; for a circular Hertz contact the limit surface is close to the ellipse
(Q / (mu P))^2 + (T / T_slip)^2 = 1 with T_slip = (3 pi / 16) mu P a (Howe and Cutkosky 1996, "Practical
force-motion models for sliding manipulation", IJRR 15: the ellipsoid fits the exact limit surface of a circular
patch within a few per cent). Each mode follows its own partial-slip law (Mindlin, Lubkin, docs/theory.md,
secs. 4.4 and 6.3, exact each on its own) up to the flow point of the ellipse, the point whose normal is along
(mu P |delta|, T_slip |phi|): the loads of maximum dissipation for slip increments parallel to the displacement and
twist (for a monotonic load from rest, the rigid sliding twist). Each share is capped at its flow-point value, so
the law is continuous, reduces to Mindlin alone and Lubkin alone, and a bump that slides in both (sliding) carries
exactly its share of the array's limit set (``_model``); a bump whose torque share is capped but whose
translation still sticks has its stick annulus slipping in torsion only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from fem.compiled import njit_cached

from contact.theory import LUBKIN_SLIP_TORQUE_RATIO, lubkin_torque_twist

from ._design import ReducedParameters

__all__ = ["BumpResponse", "bump_response", "normal_split", "normalized_lubkin_twist", "normalized_lubkin_torque",
           "lubkin_stick_ratio", "mindlin_load_ratio", "mindlin_displacement_ratio", "full_stick_stiffness", "bump_law"]

# Lubkin's twist, tabulated once in dimensionless form theta G a^2 / (mu P) against T / (mu P a), parametric in c/a
# (contact.theory.lubkin_torque_twist costs milliseconds per call; a table serves a 1 kHz loop). 460 stick ratios,
# dense near full slip: the linear interpolation error of the smooth curve is below 1e-4.
_STICK_RATIOS = np.concatenate([np.linspace(1.0, 0.05, 400), np.geomspace(0.05, 1e-4, 60)[1:]])
_TORQUE_RATIOS, _TWISTS = lubkin_torque_twist(_STICK_RATIOS, 1.0, 1.0, 1.0, 1.0)   # increasing in both


def normalized_lubkin_twist(torque_ratio):
    """theta G a^2 / (mu P) [-] at T / (mu P a) in [0, 3 pi / 16) (interpolated Lubkin curve; float or array)."""
    return np.interp(torque_ratio, _TORQUE_RATIOS, _TWISTS)


def normalized_lubkin_torque(twist):
    """Inverse of ``normalized_lubkin_twist``: T / (mu P a) at theta G a^2 / (mu P) [-] (the last value beyond)."""
    return np.interp(twist, _TWISTS, _TORQUE_RATIOS)


def lubkin_stick_ratio(torque_ratio):
    """Stick ratio c/a [-] of the Lubkin contact at T / (mu P a) (0 at and beyond 3 pi / 16)."""
    ratio = np.interp(torque_ratio, _TORQUE_RATIOS, _STICK_RATIOS)
    return np.where(np.asarray(torque_ratio) >= _TORQUE_RATIOS[-1], 0.0, ratio)


def mindlin_load_ratio(displacement_ratio):
    """Q / (mu P) = 1 - (1 - delta / delta_s)^(3/2) [-] at delta / delta_s (1 from 1 on: gross slip)."""
    return 1.0 - (1.0 - np.minimum(displacement_ratio, 1.0)) ** 1.5


def mindlin_displacement_ratio(load_ratio):
    """Inverse of ``mindlin_load_ratio``: delta / delta_s = 1 - (1 - Q / (mu P))^(2/3) [-]."""
    return 1.0 - (1.0 - np.minimum(load_ratio, 1.0)) ** (2.0 / 3.0)


def normal_split(normal_force, centres, parameters: ReducedParameters, tilt=(0.0, 0.0), iterations: int = 60):
    """Per-bump normal forces (..., k) [N] of a flat object pressing with ``normal_force`` (...,) [N].

    The object face approaches bump i by d_i = d_0 + tilt . r_i (tilt: gradient of the approach [mm/mm], i.e. the
    small face tilt angles about y and -x [rad]); P_i = k_n max(d_i, 0)^(3/2) and d_0 solves sum P_i = P
    (bisection, ``iterations`` halvings of a bracket of width ~ (P / k_n)^(2/3) + tilt span: 60 reach round-off).
    Without a tilt the split is exactly P / k.
    """
    force = np.asarray(normal_force, dtype=float)
    centres = np.asarray(centres, dtype=float)
    tilt = np.asarray(tilt, dtype=float)
    offset = centres @ tilt                                                          # (k,) [mm]
    if not np.any(offset):
        return np.broadcast_to(force[..., None] / len(centres), force.shape + (len(centres),)).copy()
    k_n = parameters.normal_stiffness
    low = np.full(force.shape, -offset.max())
    high = (np.maximum(force, 0.0) / k_n) ** (2.0 / 3.0) - offset.min()
    for _ in range(iterations):
        middle = 0.5 * (low + high)
        total = k_n * np.sum(np.maximum(middle[..., None] + offset, 0.0) ** 1.5, axis=-1)
        below = total < force
        low, high = np.where(below, middle, low), np.where(below, high, middle)
    return k_n * np.maximum(0.5 * (low + high)[..., None] + offset, 0.0) ** 1.5


@dataclass(frozen=True, eq=False)
class BumpResponse:
    """Loads and state of k bumps (arrays (..., k) or (..., k, 2)).

    contact_radius [mm]; tangential_force (..., k, 2) [N] (on the bump, along its shear displacement); torque [N mm]
    (about the bump normal, along its twist); load_ratio Q / (mu P) and torque_ratio T / (mu P a) [-];
    stick_ratio_translational, stick_ratio_rotational c/a [-]; sliding (bool): the bump is on its combined limit;
    limit_displacement (..., k, 2) [mm], limit_twist [rad]: the displacement and twist that carry the returned loads
    (equal to the inputs unless sliding: the elastic part left after the bump slid).
    """

    contact_radius: np.ndarray
    tangential_force: np.ndarray
    torque: np.ndarray
    load_ratio: np.ndarray
    torque_ratio: np.ndarray
    stick_ratio_translational: np.ndarray
    stick_ratio_rotational: np.ndarray
    sliding: np.ndarray
    limit_displacement: np.ndarray
    limit_twist: np.ndarray


def bump_response(normal_force, shear_displacement, twist, friction, parameters: ReducedParameters) -> BumpResponse:
    """Loads of bumps pressed with P_i (..., k) [N], sheared by delta_i (..., k, 2) [mm], twisted by phi_i (..., k) [rad].

    Mindlin: Q = mu P [1 - (1 - |delta| / delta_s)^(3/2)], delta_s = 3 mu P / (4 G* a); Lubkin:
    T = mu P a g(|phi| G_t a^2 / (mu P)), g the inverse normalised Lubkin twist; combined limit: the ellipse of the
    module docstring. A bump with P_i = 0 carries nothing. ``friction`` mu (> 0) may be a scalar or broadcast.
    Evaluated bump by bump by the compiled ``bump_law`` (the same law the closed loop steps with).
    """
    force = np.asarray(normal_force, dtype=float)
    displacement = np.asarray(shear_displacement, dtype=float)
    twist = np.asarray(twist, dtype=float)
    shape = np.broadcast_shapes(force.shape, displacement.shape[:-1], twist.shape, np.shape(friction))
    flat = [np.ascontiguousarray(np.broadcast_to(value, shape), dtype=float).ravel()
            for value in (force, displacement[..., 0], displacement[..., 1], twist, friction)]
    out = _bump_laws(*flat, parameters.radius_coefficient, parameters.tangential_modulus,
                     parameters.torsional_modulus)                                          # (10, n)
    sliding = out[7].astype(bool).reshape(shape)
    pair = lambda row: np.stack([out[row], out[row + 1]], axis=-1).reshape(shape + (2,))     # noqa: E731
    return BumpResponse(
        contact_radius=out[0].reshape(shape), tangential_force=pair(1), torque=out[3].reshape(shape),
        load_ratio=out[4].reshape(shape), torque_ratio=out[5].reshape(shape),
        stick_ratio_translational=out[6].reshape(shape), stick_ratio_rotational=out[10].reshape(shape),
        sliding=sliding, limit_displacement=pair(8), limit_twist=out[11].reshape(shape))


@njit_cached(inline="always")
def _interpolate(value, grid, values):
    """np.interp(value, grid, values) for an increasing grid, by bisection (numba's np.interp scans linearly)."""
    if value <= grid[0]:
        return values[0]
    last = grid.size - 1
    if value >= grid[last]:
        return values[last]
    low, high = 0, last
    while high - low > 1:
        middle = (low + high) // 2
        if grid[middle] <= value:
            low = middle
        else:
            high = middle
    weight = (value - grid[low]) / (grid[high] - grid[low])
    return values[low] + weight * (values[high] - values[low])


@njit_cached
def bump_law(force, shear_x, shear_y, twist, friction, radius_coefficient, tangential_modulus, torsional_modulus):
    """One bump: the law of ``bump_response`` for scalars (compiled; the closed loop calls it at every step).

    Returns (contact_radius [mm], Q_x, Q_y [N], torque [N mm], load_ratio, torque_ratio, stick_ratio_translational,
    sliding (0/1), elastic_x, elastic_y [mm], stick_ratio_rotational, elastic_twist [rad]), the elastic part being
    ``limit_displacement`` / ``limit_twist`` of ``BumpResponse``.
    """
    if not force > 0.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0
    radius = radius_coefficient * np.cbrt(force)
    limit_force = friction * force                                                   # mu P [N]
    slip_displacement = 3.0 * limit_force / (4.0 * tangential_modulus * radius)
    magnitude = math.hypot(shear_x, shear_y)
    load_ratio = 1.0 - (1.0 - min(magnitude / slip_displacement, 1.0)) ** 1.5        # Mindlin
    twist_scale = limit_force / (torsional_modulus * radius * radius)                # mu P / (G a^2) [rad]
    spin = abs(twist)
    torque_ratio = _interpolate(spin / twist_scale, _TWISTS, _TORQUE_RATIOS)           # Lubkin
    spin_limit = LUBKIN_SLIP_TORQUE_RATIO * limit_force * radius                      # T_slip [N mm]
    demand = math.hypot(limit_force * magnitude, spin_limit * spin)                   # flow point on the ellipse
    if not demand > 0.0:
        demand = 1.0
    flow_load = limit_force * magnitude / demand if magnitude > 0.0 else 0.0
    flow_torque = spin_limit * spin / demand if twist != 0.0 else 1.0
    sliding = load_ratio >= flow_load and torque_ratio >= LUBKIN_SLIP_TORQUE_RATIO * flow_torque
    load_ratio = min(load_ratio, flow_load)
    torque_ratio = min(torque_ratio, LUBKIN_SLIP_TORQUE_RATIO * flow_torque)
    unit_x, unit_y = (shear_x / magnitude, shear_y / magnitude) if magnitude > 0.0 else (shear_x, shear_y)
    sign = 1.0 if twist > 0.0 else (-1.0 if twist < 0.0 else 0.0)
    if sliding:
        elastic = slip_displacement * (1.0 - (1.0 - min(load_ratio, 1.0)) ** (2.0 / 3.0))
        elastic_twist = sign * twist_scale * _interpolate(torque_ratio, _TORQUE_RATIOS, _TWISTS)
        stick_translational = stick_rotational = 0.0
    else:
        elastic, elastic_twist = magnitude, twist
        stick_translational = np.cbrt(1.0 - load_ratio)
        stick_rotational = 0.0 if torque_ratio >= _TORQUE_RATIOS[-1] else _interpolate(torque_ratio, _TORQUE_RATIOS,
                                                                                        _STICK_RATIOS)
    tangential = limit_force * load_ratio
    return (radius, tangential * unit_x, tangential * unit_y, sign * limit_force * radius * torque_ratio, load_ratio,
            torque_ratio, stick_translational, 1.0 if sliding else 0.0, elastic * unit_x, elastic * unit_y,
            stick_rotational, elastic_twist)


@njit_cached
def _bump_laws(force, shear_x, shear_y, twist, friction, radius_coefficient, tangential_modulus, torsional_modulus):
    """``bump_law`` over flat arrays (n,): rows (12, n) in its return order."""
    out = np.zeros((12, force.size))
    for i in range(force.size):
        row = bump_law(force[i], shear_x[i], shear_y[i], twist[i], friction[i], radius_coefficient,
                       tangential_modulus, torsional_modulus)
        for j in range(12):
            out[j, i] = row[j]
    return out


def full_stick_stiffness(normal_force, parameters: ReducedParameters):
    """Initial tangential 2 G* a [N/mm] and torsional 16 G_t a^3 / 3 [N mm/rad] stiffness of bumps at P_i [N]."""
    radius = parameters.radius_coefficient * np.cbrt(np.maximum(np.asarray(normal_force, dtype=float), 0.0))
    return 2.0 * parameters.tangential_modulus * radius, 16.0 * parameters.torsional_modulus * radius**3 / 3.0

