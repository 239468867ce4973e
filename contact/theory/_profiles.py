"""Named axisymmetric gap profiles f(r) for MDR / Ciavarella-Jager: power law C r^n and the paper's flat + curved cap.

Every profile is a callable f(r) [mm] (initial gap between the flat counter-body and the fingertip at radius
r [mm]) that also carries its slope f'(r), the radii where f' has a kink, and, where known, the closed-form
MDR profile g(x) [mm] and the force-radius curve P(a)/E* [mm^2] (docs/theory.md, secs. 3 and 5).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from ._checks import check_choice, checked
from ._mdr import mdr_scale

__all__ = ["AxisymmetricProfile", "FLAT_CURVED_READINGS", "power_law", "flat_curved", "as_profile"]

FLAT_CURVED_READINGS = ("rounded_punch", "mdr_1d")


@dataclass(frozen=True)
class AxisymmetricProfile:
    """Axisymmetric initial gap f(r) [mm], r [mm], with what MDR needs; call it as ``profile(r)``.

    Attributes
    ----------
    name : str -- label, e.g. "power_law_n2".
    gap : callable -- f(r) [mm], f(0) = 0, vectorized over r >= 0.
    slope : callable -- f'(r) [-], vectorized.
    breakpoints : tuple of float -- radii [mm] where f' is not smooth (quadrature splits there).
    flat_radius : float -- f = 0 for r < flat_radius [mm]; a stick zone never shrinks below it.
    modified_profile : callable or None -- closed-form MDR profile g(x) [mm], if known.
    force_per_modulus : callable or None -- closed-form P(a)/E* [mm^2] for contact radius a [mm], if known.
    """

    name: str
    gap: Callable
    slope: Callable
    breakpoints: tuple = ()
    flat_radius: float = 0.0
    modified_profile: Optional[Callable] = None
    force_per_modulus: Optional[Callable] = None

    def __call__(self, r):
        """Initial gap f(r) [mm] at radius r [mm]."""
        return self.gap(np.asarray(r, dtype=float))


def power_law(n, coefficient=1.0):
    """Power-law profile f(r) = C r^n [mm] (paper Fig. 2a; n = 2, C = 1/(2R) is a sphere of radius R).

    Closed forms (docs/theory.md, sec. 3.2): g(x) = kappa_n C x^n, P(a)/E* = 2n/(n+1) kappa_n C a^(n+1).

    Parameters
    ----------
    n : float -- order [-], finite and > 0 (the flat punch n = inf has no finite gap; see
        ``stick_ratio_translational``).
    coefficient : float -- C [mm^(1-n)], > 0.
    """
    n = checked("n", n, 0.0, math.inf, low_open=True)
    C = checked("coefficient", coefficient, 0.0, math.inf, low_open=True)
    kappa = mdr_scale(n)
    return AxisymmetricProfile(
        name=f"power_law_n{n:g}",
        gap=lambda r: C * np.abs(r) ** n,
        slope=lambda r: n * C * np.abs(r) ** (n - 1.0),
        modified_profile=lambda x: kappa * C * np.abs(x) ** n,
        force_per_modulus=lambda a: 2.0 * n / (n + 1.0) * kappa * C * np.asarray(a, dtype=float) ** (n + 1.0),
    )


def flat_curved(b_over_a, reading="rounded_punch", contact_radius=1.0, curvature_radius=1.0):
    """The paper's flat + curved cap (Fig. 3): flat for r < b = (b/a) a, curved beyond [mm].

    Two readings (docs/theory.md, sec. 5.2; the paper does not say which it used). The stick ratio depends only on
    b/a, not on the curvature radius.

    * ``"rounded_punch"`` (default, the 3D reading): f = (r - b)^2 / (2 R) for r > b, 0 inside, so
      g(x) = (x/R)[sqrt(x^2 - b^2) - b arccos(b/x)] and
      P(a)/E* = [sqrt(a^2 - b^2)(4a^2 - b^2) - 3 a^2 b arccos(b/a)] / (3R) (Ciavarella, Hills & Monno 1998).
    * ``"mdr_1d"``: the 1D MDR profile itself is flat + parabolic, g(x) = (x - b)^2 / R for x > b, so
      P(a)/E* = (2/(3R)) (a - b)^2 (2a + b); the 3D gap is its inverse MDR transform
      f(r) = (2/(pi R)) [(r^2/2 + b^2) arccos(b/r) - (3/2) b sqrt(r^2 - b^2)], slope
      f'(r) = (2/(pi R)) [r arccos(b/r) - b sqrt(r^2 - b^2)/r].

    Both reduce to the sphere r^2/(2R) for b = 0.

    Parameters
    ----------
    b_over_a : float -- surface ratio b/a [-], in [0, 1).
    reading : str -- "rounded_punch" or "mdr_1d".
    contact_radius : float -- a [mm] the ratio refers to (pass the same a to ``stick_ratio_profile``).
    curvature_radius : float -- R [mm] of the curved part.
    """
    ratio = checked("b_over_a", b_over_a, 0.0, 1.0, high_open=True)
    check_choice("reading", reading, FLAT_CURVED_READINGS)
    a = checked("contact_radius", contact_radius, 0.0, math.inf, "mm", low_open=True)
    R = checked("curvature_radius", curvature_radius, 0.0, math.inf, "mm", low_open=True)
    b = ratio * a
    outside = _outside(b)                       # (r -> r clipped to >= b, sqrt(r^2 - b^2), arccos(b/r))
    if reading == "rounded_punch":
        gap = lambda r: (np.maximum(np.abs(r), b) - b) ** 2 / (2.0 * R)
        slope = lambda r: (np.maximum(np.abs(r), b) - b) / R

        def modified(x):
            x, root, angle = outside(x)
            return x / R * (root - b * angle)

        def force(a_):
            a_, root, angle = outside(a_)
            return (root * (4.0 * a_**2 - b**2) - 3.0 * a_**2 * b * angle) / (3.0 * R)
    else:
        def gap(r):
            r, root, angle = outside(r)
            return 2.0 / (math.pi * R) * ((r**2 / 2.0 + b**2) * angle - 1.5 * b * root)

        def slope(r):
            r, root, angle = outside(r)
            return 2.0 / (math.pi * R) * (r * angle - b * root / np.maximum(r, np.finfo(float).tiny))

        modified = lambda x: (np.maximum(np.abs(x), b) - b) ** 2 / R
        force = lambda a_: 2.0 / (3.0 * R) * (np.maximum(a_, b) - b) ** 2 * (2.0 * np.maximum(a_, b) + b)
    return AxisymmetricProfile(
        name=f"flat_curved_{reading}_b{ratio:g}", gap=gap, slope=slope, breakpoints=(b,) if b > 0 else (),
        flat_radius=b, modified_profile=modified, force_per_modulus=force,
    )


def _outside(b):
    """Helper for profiles flat inside r < b: returns r -> (max(|r|, b), sqrt(r^2 - b^2), arccos(b/r)), 0 inside."""

    def parts(r):
        r = np.maximum(np.abs(np.asarray(r, dtype=float)), b)
        safe = np.where(r > 0.0, r, 1.0)
        return r, np.sqrt(np.maximum(r**2 - b**2, 0.0)), np.arccos(np.clip(b / safe, -1.0, 1.0))

    return parts


def as_profile(profile):
    """Return ``profile`` if it is an AxisymmetricProfile; wrap a plain callable f(r) [mm] with a numerical slope."""
    if isinstance(profile, AxisymmetricProfile):
        return profile
    if not callable(profile):
        raise ValueError(f"profile={profile!r} is neither an AxisymmetricProfile nor a callable f(r)")

    def slope(r, step=1e-4):
        # 4th-order central difference on the even extension f(|r|); error ~ step^4 f^(5) for smooth f.
        f = lambda s: np.asarray(profile(np.abs(s)), dtype=float)
        return (f(r - 2 * step) - 8 * f(r - step) + 8 * f(r + step) - f(r + 2 * step)) / (12.0 * step)

    return AxisymmetricProfile(name=getattr(profile, "__name__", "custom"), gap=profile, slope=slope)
