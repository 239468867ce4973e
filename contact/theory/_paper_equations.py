"""The paper's eqs. 7, 8 and 10-14 (shear displacement <-> grasp force <-> stick ratio), as printed and corrected.

Units: forces [N], moduli [MPa], lengths and displacements [mm], torque [N mm], C_n [mm^(1-n)].
u_x is the tangential shift of the fingertip, u_theta = a theta the rotational shear displacement at the
contact edge. docs/theory.md, sec. 7 lists every finding; each function's docstring says what was corrected.
"""

from __future__ import annotations

import math

import numpy as np

from ._checks import as_output, check_choice, checked, checked_modulus
from ._mdr import mdr_scale
from ._numerics import solve_monotone
from ._torsion import _lubkin_twist, lubkin_twist

__all__ = [
    "contact_radius_from_force", "shear_displacement_translational", "shear_displacement_translational_exact",
    "shear_displacement_rotational", "shear_displacement_rotational_exact", "stick_ratio_from_shear_displacement",
    "stick_ratio_from_shear_displacement_paper", "stick_ratio_from_rotation", "stick_ratio_from_rotation_paper",
]

_PAPER_MODELS = ("corrected", "as_printed")


def contact_radius_from_force(P, E_star, C_n, n=2):
    """Contact radius a = [(n+1) P / (2n E* kappa_n C_n)]^(1/(n+1)) [mm] of a power-law profile (paper eq. 10).

    Eq. 10 is correct as printed: it is eq. 1 inverted (dimensions: [N / (MPa mm^(1-n))]^(1/(n+1)) = mm).
    Hertz: n = 2, C_2 = 1/(2R) gives a = (3 P R / (4 E*))^(1/3).
    """
    P, E_star, C_n, n = _check_power_law(P, E_star, C_n, n)
    return as_output(((n + 1.0) * P / (2.0 * n * E_star * mdr_scale(n) * C_n)) ** (1.0 / (n + 1.0)))


def shear_displacement_translational(Q, P, E_star, G_star, C_n, n=2, model="corrected"):
    """Shear displacement u_x [mm] of the paper's linear law, eq. 12 (full-stick stiffness, no partial slip).

    "corrected": u_x = Q / (2 G* a), the inversion of eq. 11 (Q = 2 G* u_x a). "as_printed": u_x = Q / (G* a),
    eq. 12 as printed, which lost the factor 2 of eq. 11 (both are dimensionally a length, so only
    re-deriving from eq. 11 shows it). a from eq. 10. This is the initial slope only; the true
    displacement is larger in partial slip (``shear_displacement_translational_exact``).
    """
    check_choice("model", model, _PAPER_MODELS)
    a = contact_radius_from_force(P, E_star, C_n, n)
    Q = checked("Q", Q, 0.0, math.inf, "N")
    G_star = checked_modulus("G_star", G_star)
    return as_output(Q / ((2.0 if model == "corrected" else 1.0) * G_star * a))


def shear_displacement_translational_exact(Q, P, mu, E_star, G_star, C_n, n=2):
    """Exact (MDR / Cattaneo-Mindlin) shear displacement u_x [mm] of a power-law contact under Q at constant P.

    u_x = mu (E*/G*) [d(a) - d(c)] = mu (E*/G*) d [1 - (1 - Q/(mu P))^(n/(n+1))], d = kappa_n C_n a^n
    (docs/theory.md, sec. 4.4). For n = 2 this is Mindlin's 3 mu P/(4 G* a) [1 - (1 - Q/(mu P))^(2/3)].
    """
    depth, mu, E_star, G_star, n, P = _indentation(P, mu, E_star, G_star, C_n, n)
    load_ratio = checked("Q/(mu P)", np.asarray(Q, dtype=float) / (mu * P), 0.0, 1.0)
    return as_output(mu * E_star / G_star * depth * (1.0 - (1.0 - load_ratio) ** (n / (n + 1.0))))


def shear_displacement_rotational(T, P, E_star, G_star, C_n, n=2):
    """Rotational shear displacement u_theta = 3 T / (2 G* a^2) [mm] of the paper's model (eq. 14, a from eq. 10).

    Eq. 14 inverts eq. 13 correctly, but eq. 13, T = (2/3) G* a^2 u_theta, integrates a 1D spring row
    (int_-a^a ... r dr) for a 2D torque: its stiffness T/theta = (2/3) G* a^3 is 1/(2(2 - nu)) of the exact
    16 G a^3/3 (25-33 %), and it has no partial slip (docs/theory.md, sec. 6.2). See
    ``shear_displacement_rotational_exact``.
    """
    a = contact_radius_from_force(P, E_star, C_n, n)
    T = checked("T", T, 0.0, math.inf, "N mm")
    G_star = checked_modulus("G_star", G_star)
    return as_output(3.0 * T / (2.0 * G_star * a**2))


def shear_displacement_rotational_exact(T, P, mu, a, G):
    """Exact rotational shear displacement u_theta = a theta [mm] of a Hertz contact under torque T [N mm].

    theta from Lubkin's partial-slip solution (``lubkin_twist``, docs/theory.md, sec. 6.3); full-stick slope
    u_theta = 3 T / (16 G a^2). G is the shear modulus of the elastic body [MPa] (two bodies: 1/(1/G1 + 1/G2)).
    """
    return as_output(checked("a", a, 0.0, math.inf, "mm", low_open=True) * np.asarray(lubkin_twist(T, P, mu, a, G)))


def stick_ratio_from_shear_displacement(u_x, P, mu, E_star, G_star, C_n, n=2):
    """Stick ratio c/a [-] from the measured shear displacement u_x [mm]: exact replacement of paper eq. 7.

    c/a = [1 - G* u_x / (mu E* d)]^(1/n), d = kappa_n C_n a^n the indentation depth (MDR, docs/theory.md, sec. 4.4);
    Hertz: c/a = sqrt(1 - G* u_x/(mu E* d)). Displacements at or beyond the gross-slip value mu E* d / G*
    give 0 (the contact slides). Eq. 7 itself uses the linear law of eq. 11 in partial slip; see
    ``stick_ratio_from_shear_displacement_paper``.
    """
    depth, mu, E_star, G_star, n, _ = _indentation(P, mu, E_star, G_star, C_n, n)
    u_x = checked("u_x", u_x, 0.0, math.inf, "mm")
    return as_output(np.maximum(1.0 - G_star * u_x / (mu * E_star * depth), 0.0) ** (1.0 / n))


def stick_ratio_from_shear_displacement_paper(u_x, P, mu, E_star, G_star, C_n, n=2, model="corrected"):
    """Stick ratio c/a [-] from u_x [mm] by paper eq. 7, c/a = (1 - Psi u_x)^(1/(n+1)), clipped at 0 (slides).

    "as_printed": Psi = pi G* [(n+1) F_N / (2n E* C_n lambda_n)]^(2/(n+1)) / (mu F_N) = pi G* a^2/(mu F_N) is
    dimensionless, so Psi u_x is a length and the result changes with the length unit (here mm).
    "corrected": Psi = 2 G* a / (mu F_N) [1/mm] (eq. 3 combined with eq. 11: exponent 1/(n+1) on a and factor 2
    instead of pi). Both still assume the linear law of eq. 11 in partial slip, which underestimates the
    displacement (by 1.5x at gross slip) and so overestimates c/a for a given Q; feeding it an exact
    displacement gives c/a too low (docs/theory.md, sec. 7.1).
    """
    check_choice("model", model, _PAPER_MODELS)
    P, E_star, C_n, n = _check_power_law(P, E_star, C_n, n)
    mu = checked("mu", mu, 0.0, math.inf, low_open=True)
    G_star = checked_modulus("G_star", G_star)
    u_x = checked("u_x", u_x, 0.0, math.inf, "mm")
    a = contact_radius_from_force(P, E_star, C_n, n)
    psi = (2.0 * G_star * a if model == "corrected" else math.pi * G_star * a**2) / (mu * P)
    return as_output(np.maximum(1.0 - psi * u_x, 0.0) ** (1.0 / (n + 1.0)))


def stick_ratio_from_rotation(u_theta, P, mu, a, G):
    """Stick ratio c/a [-] from the rotational shear displacement u_theta = a theta [mm]: exact replacement of eq. 8.

    Inverts Lubkin's twist theta(c) = 3 mu P/(4 pi G a^2) [K(k') - E(k')] (docs/theory.md, sec. 6.3) for c by a
    bracketing root finder; theta(c) grows without bound as c -> 0, so every u_theta >= 0 has a c/a in (0, 1].
    """
    P = checked("P", P, 0.0, math.inf, "N", low_open=True)
    mu = checked("mu", mu, 0.0, math.inf, low_open=True)
    a = checked("a", a, 0.0, math.inf, "mm", low_open=True)
    G = checked_modulus("G", G)
    twist = np.asarray(checked("u_theta", u_theta, 0.0, math.inf, "mm"), dtype=float) / a
    smallest = 1e-12                 # c/a floor: twists beyond theta(1e-12) ~ 2 mu P/(G a^2) ln(4e12) report it
    largest_twist = _lubkin_twist(np.float64(smallest), P, mu, a, G)
    k = solve_monotone(lambda k_, theta: _lubkin_twist(k_, P, mu, a, G) - theta, smallest, 1.0,
                       args=(np.minimum(twist, largest_twist),), what="stick ratio from rotation")
    return as_output(k)


def stick_ratio_from_rotation_paper(u_theta, P, mu, E_star, G_star, C_2, model="corrected"):
    """Stick ratio c/a [-] from u_theta [mm] by paper eq. 8, c/a = sqrt(sqrt(4 - Phi u_theta) - 1), 0 when it slides.

    "as_printed": Phi = 16 G* (3/(4 E* C_2 lambda_2))^(1/3) / (3 mu F_N): F_N is missing inside the cube root,
    so Phi u_theta carries N^(-1/3) and is not dimensionless. "corrected": Phi = 16 G* a / (3 mu F_N) with
    a = (3 F_N/(4 E* C_2 lambda_2))^(1/3) (eq. 6 corrected combined with eq. 13). Both inherit the 1D torsion
    model's errors (full slip at 3/8 instead of 3 pi/16 mu P a, stiffness 25-33 % of the exact one).
    """
    check_choice("model", model, _PAPER_MODELS)
    P, E_star, C_2, _ = _check_power_law(P, E_star, C_2, 2)
    mu = checked("mu", mu, 0.0, math.inf, low_open=True)
    G_star = checked_modulus("G_star", G_star)
    u_theta = checked("u_theta", u_theta, 0.0, math.inf, "mm")
    length = contact_radius_from_force(P, E_star, C_2, 2) if model == "corrected" else (
        3.0 / (4.0 * E_star * C_2 * mdr_scale(2))) ** (1.0 / 3.0)
    phi = 16.0 * G_star * length / (3.0 * mu * P)
    inner = np.sqrt(np.maximum(4.0 - phi * u_theta, 0.0)) - 1.0
    return as_output(np.sqrt(np.maximum(inner, 0.0)))


def _check_power_law(P, E_star, C_n, n):
    return (checked("P", P, 0.0, math.inf, "N"), checked_modulus("E_star", E_star),
            checked("C_n", C_n, 0.0, math.inf, "mm^(1-n)", low_open=True),
            checked("n", n, 0.0, math.inf, low_open=True))


def _indentation(P, mu, E_star, G_star, C_n, n):
    """Checked inputs and the indentation depth d = kappa_n C_n a^n [mm] (a from eq. 10), P > 0 here."""
    P = checked("P", P, 0.0, math.inf, "N", low_open=True)
    mu = checked("mu", mu, 0.0, math.inf, low_open=True)
    G_star = checked_modulus("G_star", G_star)
    a = contact_radius_from_force(P, E_star, C_n, n)
    n = checked("n", n, 0.0, math.inf, low_open=True)
    return mdr_scale(n) * C_n * a**n, mu, checked_modulus("E_star", E_star), G_star, n, P
