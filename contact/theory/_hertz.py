"""Hertz contact of a sphere on a half-space, and the Cattaneo-Mindlin tangential shift [mm, N, MPa]."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ._checks import as_output, checked, checked_modulus

__all__ = ["HertzContact", "hertz", "mindlin_shift"]


@dataclass(frozen=True)
class HertzContact:
    """Frictionless sphere-on-half-space contact state (floats, or arrays shaped like the inputs).

    Attributes
    ----------
    contact_radius : float or array -- a = (3 P R / (4 E*))^(1/3) [mm]
    peak_pressure : float or array -- p0 = 3 P / (2 pi a^2) [MPa]
    indentation : float or array -- d = a^2 / R [mm]
    """

    contact_radius: float
    peak_pressure: float
    indentation: float


def hertz(P, R, E_star):
    """Hertz contact radius [mm], peak pressure [MPa] and indentation [mm] for normal force P [N].

    Parameters
    ----------
    P : float or array -- normal force [N], >= 0 (P = 0 gives a closed contact of zero size).
    R : float or array -- effective radius of curvature [mm], > 0.
    E_star : float or array -- effective modulus [MPa], > 0 (see ``effective_modulus``).

    Returns
    -------
    HertzContact
        Johnson (1985) sec. 4.2; docs/theory.md, secs. 2 and 3.2 (MDR with n = 2, C_2 = 1/(2R)).
    """
    P = checked("P", P, 0.0, math.inf, "N")
    R = checked("R", R, 0.0, math.inf, "mm", low_open=True)
    E_star = checked_modulus("E_star", E_star)
    radius = np.cbrt(3.0 * P * R / (4.0 * E_star))
    with np.errstate(invalid="ignore", divide="ignore"):
        pressure = np.where(radius > 0.0, 3.0 * P / (2.0 * math.pi * np.where(radius > 0.0, radius, 1.0) ** 2), 0.0)
    return HertzContact(as_output(radius), as_output(pressure), as_output(radius**2 / R))


def mindlin_shift(Q, P, mu, a, G, nu):
    """Tangential shift [mm] of a rigid sphere on an elastic half-space under Q at constant P (partial slip).

    delta = 3 mu P (2 - nu) / (16 G a) [1 - (1 - Q/(mu P))^(2/3)]   (Mindlin 1949; Johnson 1985 sec. 7.2;
    docs/theory.md, sec. 4.4). Initial stiffness dQ/d delta = 8 G a / (2 - nu); gross slip at Q = mu P.

    Parameters
    ----------
    Q : float or array -- tangential force [N], 0 <= Q <= mu P.
    P : float or array -- normal force [N], > 0.
    mu : float or array -- friction coefficient [-], > 0.
    a : float or array -- contact radius [mm], > 0.
    G : float or array -- shear modulus of the elastic body [MPa], > 0.
    nu : float or array -- Poisson's ratio of the elastic body [-], in (-1, 0.5].
    """
    P = checked("P", P, 0.0, math.inf, "N", low_open=True)
    mu = checked("mu", mu, 0.0, math.inf, low_open=True)
    a = checked("a", a, 0.0, math.inf, "mm", low_open=True)
    G = checked_modulus("G", G)
    nu = checked("nu", nu, -1.0, 0.5, low_open=True)
    load_ratio = checked("Q/(mu P)", np.asarray(Q, dtype=float) / (mu * P), 0.0, 1.0)
    return as_output(3.0 * mu * P * (2.0 - nu) / (16.0 * G * a) * (1.0 - (1.0 - load_ratio) ** (2.0 / 3.0)))
