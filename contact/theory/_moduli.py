"""Effective elastic moduli of two bodies in contact: normal E*, MDR tangential G*, and the shear modulus G [MPa]."""

from __future__ import annotations

import math

from ._checks import as_output, checked, checked_modulus

__all__ = ["effective_modulus", "tangential_modulus", "shear_modulus"]

_POISSON = dict(low=-1.0, high=0.5, low_open=True)      # 0.5 (incompressible) is allowed in these formulas


def effective_modulus(E1, nu1, E2=math.inf, nu2=0.0):
    """Effective normal modulus E* [MPa]: 1/E* = (1 - nu1^2)/E1 + (1 - nu2^2)/E2 (docs/theory.md sec. 1.3, paper eq. 1).

    Parameters
    ----------
    E1, E2 : float or array -- Young's moduli [MPa]; ``E2 = inf`` (default) is a rigid counter-body.
    nu1, nu2 : float or array -- Poisson's ratios [-], in (-1, 0.5].
    """
    E1 = checked_modulus("E1", E1)
    E2 = checked_modulus("E2", E2, allow_infinite=True)
    nu1 = checked("nu1", nu1, **_POISSON)
    nu2 = checked("nu2", nu2, **_POISSON)
    return as_output(1.0 / ((1.0 - nu1**2) / E1 + (1.0 - nu2**2) / E2))


def tangential_modulus(G1, nu1, G2=math.inf, nu2=0.0):
    """MDR tangential modulus G* [MPa]: 1/G* = (2 - nu1)/(4 G1) + (2 - nu2)/(4 G2) (docs/theory.md, sec. 1.3).

    Rigid body on one elastic body: G* = 4 G/(2 - nu). The paper uses G* without defining it; this is the
    value for which the 1D spring model reproduces the Cattaneo-Mindlin shift exactly.

    Parameters
    ----------
    G1, G2 : float or array -- shear moduli [MPa]; ``G2 = inf`` (default) is a rigid counter-body.
    nu1, nu2 : float or array -- Poisson's ratios [-], in (-1, 0.5].
    """
    G1 = checked_modulus("G1", G1)
    G2 = checked_modulus("G2", G2, allow_infinite=True)
    nu1 = checked("nu1", nu1, **_POISSON)
    nu2 = checked("nu2", nu2, **_POISSON)
    return as_output(1.0 / ((2.0 - nu1) / (4.0 * G1) + (2.0 - nu2) / (4.0 * G2)))


def shear_modulus(E, nu):
    """Shear modulus G = E / (2 (1 + nu)) [MPa] of an isotropic material, E [MPa], nu [-] in (-1, 0.5]."""
    E = checked_modulus("E", E)
    nu = checked("nu", nu, **_POISSON)
    return as_output(E / (2.0 * (1.0 + nu)))
