"""Stick ratio c/a under a tangential force at constant normal force: MDR eq. 3 and Ciavarella-Jager for any profile."""

from __future__ import annotations

import math

import numpy as np

from ._checks import as_output, check_choice, checked
from ._mdr import _force_per_modulus
from ._numerics import solve_monotone
from ._profiles import as_profile

__all__ = ["stick_ratio_translational", "stick_ratio_profile"]


def stick_ratio_translational(load_ratio, n=2):
    """Stick ratio c/a = (1 - Q/(mu P))^(1/(n+1)) [-] for a power-law profile C r^n (paper eq. 3).

    Exact in 3D for beta = 0 (docs/theory.md, sec. 4.2). ``n = inf`` is the flat-punch limit: c/a = 1 for every
    load ratio below 1 and 0 at 1 (the whole contact slides at once).

    Parameters
    ----------
    load_ratio : float or array -- Q/(mu P) [-], in [0, 1].
    n : float -- profile order [-], > 0 (inf allowed).
    """
    x = checked("load_ratio", load_ratio, 0.0, 1.0)
    if not (isinstance(n, (int, float)) and math.isinf(n) and n > 0):
        n = checked("n", n, 0.0, math.inf, low_open=True)
        return as_output((1.0 - x) ** (1.0 / (n + 1.0)))
    return as_output(np.where(x < 1.0, 1.0, 0.0))


def stick_ratio_profile(load_ratio, profile, contact_radius=1.0, method="quadrature"):
    """Stick ratio c/a [-] of any axisymmetric profile by Ciavarella-Jager: P(c) = P(a) (1 - Q/(mu P)).

    P(rho) is the frictionless force-radius curve from MDR, P(rho)/E* = 2 int_0^rho (g(rho) - g(x)) dx with
    g(x) = x int_0^(pi/2) f'(x sin phi) dphi (docs/theory.md, secs. 3.1 and 5.1), solved for c in [flat_radius, a] by a
    bracketing root finder. At Q = mu P the whole contact slides and the result is 0 (for a profile with a
    flat face the stick ratio drops there from b/a to 0).

    Parameters
    ----------
    load_ratio : float or array -- Q/(mu P) [-], in [0, 1].
    profile : AxisymmetricProfile or callable -- initial gap f(r) [mm]; a plain callable gets a numerical slope.
    contact_radius : float -- a [mm], > 0 (for ``flat_curved`` the a its b/a refers to).
    method : str -- "quadrature" (MDR quadrature of f, any profile) or "closed_form" (the profile's
        ``force_per_modulus``, where known).
    """
    x = checked("load_ratio", load_ratio, 0.0, 1.0)
    profile = as_profile(profile)
    a = checked("contact_radius", contact_radius, 0.0, math.inf, "mm", low_open=True)
    check_choice("method", method, ("quadrature", "closed_form"))
    if method == "closed_form":
        if profile.force_per_modulus is None:
            raise ValueError(f"method='closed_form' but profile {profile.name!r} has no closed-form force curve")
        force = lambda rho: np.asarray(profile.force_per_modulus(rho), dtype=float)
    else:
        force = lambda rho: _force_per_modulus(profile, rho)
    if not profile.flat_radius < a:
        raise ValueError(f"contact_radius={a!r} must exceed the flat radius {profile.flat_radius!r} mm of the profile")
    full = force(a)
    target = np.asarray(x, dtype=float).ravel()
    sliding = target >= 1.0
    radius = solve_monotone(lambda rho, share: force(rho) / full - share, profile.flat_radius, a,
                            args=(1.0 - np.where(sliding, 0.0, target),), what="stick radius")
    return as_output(np.where(sliding, 0.0, radius / a).reshape(np.shape(x)))
