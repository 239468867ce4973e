"""Method of dimensionality reduction (MDR): scaling factor kappa_n, modified profile g(x) and force P(a) by quadrature.

Popov & Hess, Method of Dimensionality Reduction in Contact Mechanics and Friction (2015); docs/theory.md, sec. 3.
The quadrature routes here take any axisymmetric profile (an ``AxisymmetricProfile`` or anything with
``slope(r)`` and ``breakpoints``) and serve as the independent check of every closed form.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import gammaln

from ._checks import as_output, checked
from ._numerics import piecewise_gauss

__all__ = ["mdr_scale", "mdr_modified_profile", "mdr_normal_force"]


def mdr_scale(n):
    """MDR scaling factor kappa_n = sqrt(pi) Gamma(n/2 + 1) / Gamma(n/2 + 1/2) [-] (the paper's lambda_n).

    For f(r) = C r^n the modified 1D profile is g(x) = kappa_n C |x|^n: kappa_1 = pi/2, kappa_2 = 2,
    kappa_4 = 8/3. ``n`` > 0; ``n = inf`` returns inf (flat punch limit).
    """
    n = np.asarray(n, dtype=float)
    finite = checked("n", np.where(np.isposinf(n), 1.0, n), 0.0, math.inf, low_open=True)
    kappa = math.sqrt(math.pi) * np.exp(gammaln(finite / 2.0 + 1.0) - gammaln(finite / 2.0 + 0.5))
    return as_output(np.where(np.isposinf(n), math.inf, kappa))


def mdr_modified_profile(profile, x):
    """MDR modified profile g(x) = x int_0^x f'(r) / sqrt(x^2 - r^2) dr [mm] by quadrature, x >= 0 [mm].

    The inverse-square-root singularity is removed by r = x sin(phi): g(x) = x int_0^(pi/2) f'(x sin phi) dphi;
    the phi range is split where x sin(phi) crosses a breakpoint of the profile (a kink of f').
    """
    x = checked("x", x, 0.0, math.inf, "mm")
    return as_output(_modified_profile(profile, np.asarray(x, dtype=float)))


def mdr_normal_force(profile, contact_radius, E_star=1.0):
    """Frictionless normal force P(a) = 2 E* int_0^a (g(a) - g(x)) dx [N] by MDR quadrature (docs/theory.md, sec. 3.1).

    Parameters
    ----------
    profile : AxisymmetricProfile -- initial gap f(r) [mm] (with ``slope`` and ``breakpoints``).
    contact_radius : float or array -- a [mm], >= 0.
    E_star : float -- effective modulus [MPa], > 0; the default 1 gives P/E* [mm^2].
    """
    contact_radius = checked("contact_radius", contact_radius, 0.0, math.inf, "mm")
    E_star = checked("E_star", E_star, 0.0, math.inf, "MPa", low_open=True)
    return as_output(E_star * _force_per_modulus(profile, np.asarray(contact_radius, dtype=float)))


def _modified_profile(profile, x):
    """g(x) [mm] for x (...,) >= 0 by Gauss quadrature in phi (no validation)."""
    x = np.asarray(x, dtype=float)
    safe = np.where(x > 0.0, x, 1.0)
    kinks = [np.arcsin(np.clip(b / safe, 0.0, 1.0)) for b in sorted(profile.breakpoints) if b > 0.0]
    phi, weight = piecewise_gauss(np.stack(np.broadcast_arrays(0.0, *kinks, math.pi / 2), axis=-1))
    radius = safe[..., None] * np.sin(phi)                                # (..., K*N)
    return np.where(x > 0.0, x * np.sum(weight * profile.slope(radius), axis=-1), 0.0)


def _force_per_modulus(profile, contact_radius):
    """P(a)/E* = 2 (a g(a) - int_0^a g dx) [mm^2] for a (...,) by nested quadrature (no validation)."""
    a = np.asarray(contact_radius, dtype=float)
    kinks = [np.minimum(b, a) for b in sorted(profile.breakpoints) if b > 0.0]
    points, weight = piecewise_gauss(np.stack(np.broadcast_arrays(0.0, *kinks, a), axis=-1))
    integral = np.sum(weight * _modified_profile(profile, points), axis=-1)
    return 2.0 * (a * _modified_profile(profile, a) - integral)
