"""Partial-slip torsion of a circular contact: the paper's 1D model (eqs. 4-6) and the exact Hertz solution (Lubkin).

Torque ratio t = T/(mu P a) [-], stick ratio k = c/a [-]. docs/theory.md, sec. 6: the paper's 1D spring model
reaches full slip at t = (n+1)/(2(n+2)) (3/8 for n = 2), the exact Hertz contact at t = 3 pi/16 (Lubkin 1951;
Johnson 1985 sec. 7.4), and eq. 6 as printed gives (c/a)^2 instead of c/a.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ellipe, elliprd

from ._checks import as_output, check_choice, checked
from ._numerics import piecewise_gauss, solve_monotone

__all__ = [
    "TORSION_MODELS", "LUBKIN_SLIP_TORQUE_RATIO", "full_slip_torque_ratio", "torsion_torque_ratio",
    "stick_ratio_torsion",
    "lubkin_twist", "lubkin_torque_twist",
]

TORSION_MODELS = ("lubkin", "paper", "paper_as_printed")
LUBKIN_SLIP_TORQUE_RATIO = 3.0 * math.pi / 16.0


def full_slip_torque_ratio(model="lubkin", n=2):
    """Torque ratio T/(mu P a) [-] at which the whole contact slides: 3 pi/16 (Lubkin), (n+1)/(2(n+2)) (paper)."""
    n = _check_model(model, n)
    return LUBKIN_SLIP_TORQUE_RATIO if model == "lubkin" else (n + 1.0) / (2.0 * (n + 2.0))


def torsion_torque_ratio(stick_ratio, model="lubkin", n=2):
    """Torque ratio T/(mu P a) [-] that gives the stick ratio c/a [-] in [0, 1] (the inverse of stick_ratio_torsion).

    * "lubkin": T(c) = (4 mu P a / pi) int_0^k' x sqrt(1 - x^2) E(x) dx, k' = sqrt(1 - c^2/a^2), E with modulus x
      (docs/theory.md, sec. 6.3), by Gauss quadrature after x = sin(psi).
    * "paper": eq. 4, t = -(n+1)/(6n) k^2 - 2(n^2-1)/(6n(n+2)) k^(n+2) + (n+1)/(2(n+2)), valid for any n > 0.
    * "paper_as_printed": eq. 6 as printed inverted, k = sqrt(4 - 8t) - 1, so t = (4 - (k+1)^2)/8 (n = 2).
    """
    k = checked("stick_ratio", stick_ratio, 0.0, 1.0)
    n = _check_model(model, n)
    return as_output(_torque_ratio(np.asarray(k, dtype=float), model, n))


def stick_ratio_torsion(torque_ratio, model="lubkin", n=2):
    """Stick ratio c/a [-] under a torque T about the contact normal at constant P, t = T/(mu P a) in [0, 1].

    Torques at or beyond the model's full-slip torque (``full_slip_torque_ratio``) give 0: the contact slides.

    Parameters
    ----------
    torque_ratio : float or array -- T/(mu P a) [-], in [0, 1].
    model : str
        "lubkin" -- exact partial-slip torsion of a Hertz contact (n = 2 only), T(c) of docs/theory.md, sec. 6.3
        inverted by a bracketing root finder; full slip at 3 pi/16 = 0.589.
        "paper" -- paper eq. 5 (eq. 4 solved for c/a; any n > 0, root finding); for n = 2 the closed form
        c/a = sqrt(sqrt(4 - 8t) - 1), i.e. eq. 6 corrected with the outer square root (eq. 6 as printed is
        (c/a)^2: with k = c/a, eq. 5 for n = 2 reads (k^2 + 1)^2 = 4 - 8t). Full slip at (n+1)/(2(n+2)).
        "paper_as_printed" -- eq. 6 exactly as printed, c/a = sqrt(4 - 8t) - 1 (n = 2), for comparison.
    n : float -- profile order of the paper's model [-], > 0; must be 2 for "lubkin" and "paper_as_printed".
    """
    t = checked("torque_ratio", torque_ratio, 0.0, 1.0)
    n = _check_model(model, n)
    t = np.asarray(t, dtype=float)
    slides = t >= _torque_ratio(np.zeros(()), model, n)        # numerical T(c = 0), equal to the full-slip value
    share = np.where(slides, 0.0, t)
    if model == "paper_as_printed":
        k = np.sqrt(4.0 - 8.0 * share) - 1.0
    elif model == "paper" and n == 2.0:
        k = np.sqrt(np.sqrt(4.0 - 8.0 * share) - 1.0)
    else:
        k = solve_monotone(lambda k_, t_: _torque_ratio(k_, model, n) - t_, 0.0, 1.0, args=(share,),
                           what=f"stick ratio ({model} torsion)")
    return as_output(np.where(slides, 0.0, np.clip(k, 0.0, 1.0)))


def lubkin_twist(torque, P, mu, a, G):
    """Twist angle theta [rad] of a rigid sphere on an elastic half-space under torque T [N mm], partial slip.

    theta(c) = 3 mu P / (4 pi G a^2) [K(k') - E(k')], k' = sqrt(1 - c^2/a^2), c from ``stick_ratio_torsion``
    (docs/theory.md, sec. 6.3; Lubkin 1951, Deresiewicz 1954). Two elastic bodies: pass G = 1/(1/G1 + 1/G2).
    Full stick limit theta = 3 T / (16 G a^3).

    Parameters
    ----------
    torque : float or array -- T [N mm], 0 <= T < 3 pi/16 mu P a (at full slip the twist is unbounded).
    P : float -- normal force [N], > 0.   mu : float -- friction coefficient [-], > 0.
    a : float -- contact radius [mm], > 0.   G : float -- shear modulus [MPa], > 0.
    """
    P, mu, a, G = _check_body(P, mu, a, G)
    t = checked("torque", np.asarray(torque, dtype=float) / (mu * P * a), 0.0, LUBKIN_SLIP_TORQUE_RATIO,
                "(as T/(mu P a); full slip at 3 pi/16)", high_open=True)
    k = stick_ratio_torsion(t, "lubkin")
    if np.any(np.asarray(k) <= 0.0):
        raise ValueError(f"torque={torque!r} is at full slip (T/(mu P a) numerically 3 pi/16): twist unbounded")
    return as_output(_lubkin_twist(np.asarray(k), P, mu, a, G))


def lubkin_torque_twist(stick_ratio, P, mu, a, G):
    """Torque T [N mm] and twist theta [rad] of the exact Hertz torsion at stick ratio c/a in (0, 1] (parametric)."""
    P, mu, a, G = _check_body(P, mu, a, G)
    k = np.asarray(checked("stick_ratio", stick_ratio, 0.0, 1.0, low_open=True), dtype=float)
    return (as_output(mu * P * a * _torque_ratio(k, "lubkin", 2.0)), as_output(_lubkin_twist(k, P, mu, a, G)))


def _check_model(model, n):
    check_choice("model", model, TORSION_MODELS)
    n = checked("n", n, 0.0, math.inf, low_open=True)
    if model != "paper" and n != 2.0:
        raise ValueError(f"n={n!r} not allowed for model={model!r}: it is defined for the Hertz case n = 2 only")
    return n


def _check_body(P, mu, a, G):
    return (checked("P", P, 0.0, math.inf, "N", low_open=True), checked("mu", mu, 0.0, math.inf, low_open=True),
            checked("a", a, 0.0, math.inf, "mm", low_open=True), checked("G", G, 0.0, math.inf, "MPa", low_open=True))


def _torque_ratio(k, model, n):
    """T/(mu P a) at stick ratio k (...,) for one model (no validation)."""
    k = np.asarray(k, dtype=float)
    if model == "paper":
        # eq. 4 regrouped so that it vanishes exactly at k = 1 (no round-off sign flip near zero torque)
        return (n + 1.0) / (6.0 * n * (n + 2.0)) * ((n + 2.0) * (1.0 - k**2) + 2.0 * (n - 1.0) * (1.0 - k ** (n + 2.0)))
    if model == "paper_as_printed":
        return (4.0 - (k + 1.0) ** 2) / 8.0
    # x = sin(psi): int_0^k' x sqrt(1-x^2) E(x) dx = int_0^arccos(k) sin(psi) cos(psi)^2 E(sin^2 psi) dpsi
    psi, weight = piecewise_gauss(np.stack(np.broadcast_arrays(0.0, np.arccos(np.clip(k, 0.0, 1.0))), axis=-1))
    integrand = np.sin(psi) * np.cos(psi) ** 2 * ellipe(np.sin(psi) ** 2)      # ellipe takes m = modulus^2
    return 4.0 / math.pi * np.sum(weight * integrand, axis=-1)


def _lubkin_twist(k, P, mu, a, G):
    """theta = 3 mu P/(4 pi G a^2) (K - E)(m), m = 1 - k^2, with K - E = (m/3) R_D(0, 1 - m, 1) (no cancellation)."""
    m = 1.0 - k**2
    return mu * P / (4.0 * math.pi * G * a**2) * m * elliprd(0.0, k**2, 1.0)
