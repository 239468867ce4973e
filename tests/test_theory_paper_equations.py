"""Paper eqs. 7, 8, 10-14: corrected forms against independent routes, as-printed forms against their defects."""

import numpy as np
import pytest

from contact.theory import (
    contact_radius_from_force, effective_modulus, hertz, mdr_normal_force, mindlin_shift, power_law,
    shear_displacement_rotational, shear_displacement_rotational_exact, shear_displacement_translational,
    shear_displacement_translational_exact, shear_modulus, stick_ratio_from_rotation,
    stick_ratio_from_rotation_paper, stick_ratio_from_shear_displacement, stick_ratio_from_shear_displacement_paper,
    stick_ratio_torsion, stick_ratio_translational, tangential_modulus,
)

E, NU, MU, R, P = 1.0, 0.45, 0.5, 10.0, 0.2         # MPa, -, -, mm, N (HCM-1 benchmark)
G = shear_modulus(E, NU)
E_STAR, G_STAR = effective_modulus(E, NU), tangential_modulus(G, NU)
C2 = 1.0 / (2.0 * R)
A = hertz(P, R, E_STAR).contact_radius
ROUND_OFF = 1e-13                                  # closed forms of a few operations each


def test_eq10_is_hertz_for_a_sphere_and_inverts_the_mdr_force_for_other_orders():
    assert contact_radius_from_force(P, E_STAR, C2, 2) == pytest.approx(A, rel=ROUND_OFF)
    for n, coefficient in ((1, 0.1), (3, 0.02), (8, 0.5)):
        a = contact_radius_from_force(P, E_STAR, coefficient, n)
        # Gauss quadrature of the MDR force, ~1e-14 relative
        assert mdr_normal_force(power_law(n, coefficient), a, E_STAR) == pytest.approx(P, rel=1e-12)


def test_eq12_corrected_is_the_initial_slope_of_the_exact_displacement_and_as_printed_is_twice_it():
    Q = 1e-7 * MU * P
    exact = shear_displacement_translational_exact(Q, P, MU, E_STAR, G_STAR, C2, 2)
    corrected = shear_displacement_translational(Q, P, E_STAR, G_STAR, C2, 2)
    assert corrected == pytest.approx(exact, rel=1e-7)              # O(Q/(mu P)) curvature of the exact law
    assert shear_displacement_translational(Q, P, E_STAR, G_STAR, C2, 2, model="as_printed") == pytest.approx(
        2.0 * corrected, rel=ROUND_OFF)


def test_exact_translational_displacement_is_mindlin_for_a_sphere():
    Q = np.linspace(0.0, MU * P, 7)
    np.testing.assert_allclose(shear_displacement_translational_exact(Q, P, MU, E_STAR, G_STAR, C2, 2),
                               mindlin_shift(Q, P, MU, A, G, NU), rtol=ROUND_OFF, atol=1e-18)


@pytest.mark.parametrize("n, coefficient", [(1, 0.1), (2, C2), (3, 0.02), (8, 0.5)])
def test_exact_eq7_replacement_returns_eq3_for_the_exact_displacement(n, coefficient):
    load_ratio = np.linspace(0.0, 1.0, 11)
    u_x = shear_displacement_translational_exact(load_ratio * MU * P, P, MU, E_STAR, G_STAR, coefficient, n)
    # powers 1/n of 1 - G* u/(mu E* d): round-off amplified near full slip, (1e-16)^(1/(n+1)) at x = 1 ends exactly
    np.testing.assert_allclose(stick_ratio_from_shear_displacement(u_x, P, MU, E_STAR, G_STAR, coefficient, n),
                               stick_ratio_translational(load_ratio, n), atol=1e-7)


def test_eq7_corrected_reproduces_eq3_with_its_own_linear_law():
    load_ratio = np.linspace(0.0, 1.0, 11)
    u_linear = shear_displacement_translational(load_ratio * MU * P, P, E_STAR, G_STAR, C2, 2)
    np.testing.assert_allclose(stick_ratio_from_shear_displacement_paper(u_linear, P, MU, E_STAR, G_STAR, C2, 2),
                               stick_ratio_translational(load_ratio, 2), atol=1e-7)


def _paper_in_other_units(function, u):
    """Evaluate a paper stick-ratio formula in m and mN instead of mm and N (stress unit mN/m^2 follows)."""
    length, force = 1e-3, 1e3                    # new units per old unit: 1 mm = 1e-3 m, 1 N = 1e3 mN
    stress = force / length**2
    return function(u * length, P * force, MU, E_STAR * stress, G_STAR * stress, C2 / length)


@pytest.mark.parametrize("function", [stick_ratio_from_shear_displacement_paper, stick_ratio_from_rotation_paper])
def test_corrected_eq7_eq8_are_unit_independent_and_as_printed_are_not(function):
    u = 0.2 * shear_displacement_translational(MU * P, P, E_STAR, G_STAR, C2, 2)
    in_mm = function(u, P, MU, E_STAR, G_STAR, C2)
    assert _paper_in_other_units(function, u) == pytest.approx(in_mm, rel=1e-12)   # dimensionless: unit-free
    # eq. 7 as printed: Psi u_x is a length; eq. 8 as printed: Phi u_theta carries N^(-1/3)
    printed = lambda *args: function(*args, model="as_printed")
    assert abs(_paper_in_other_units(printed, u) - printed(u, P, MU, E_STAR, G_STAR, C2)) > 0.01


def test_eq14_inverts_eq13_and_exact_rotation_has_the_full_stick_stiffness():
    T = 1e-6 * MU * P * A
    u_paper = shear_displacement_rotational(T, P, E_STAR, G_STAR, C2, 2)
    assert T == pytest.approx(2.0 / 3.0 * G_STAR * u_paper * A**2, rel=ROUND_OFF)     # eq. 13
    u_exact = shear_displacement_rotational_exact(T, P, MU, A, G)
    assert u_exact == pytest.approx(3.0 * T / (16.0 * G * A**2), rel=1e-5)            # O(T/T_slip) partial slip
    # the paper's stiffness is 1/(2(2 - nu)) of the exact one (docs/theory.md, sec. 6.2)
    assert u_exact / u_paper == pytest.approx(1.0 / (2.0 * (2.0 - NU)), rel=1e-5)


def test_eq8_corrected_reproduces_eq6_corrected_with_eq14():
    t = np.linspace(0.0, 0.375, 9)
    u_theta = shear_displacement_rotational(t * MU * P * A, P, E_STAR, G_STAR, C2, 2)
    np.testing.assert_allclose(stick_ratio_from_rotation_paper(u_theta, P, MU, E_STAR, G_STAR, C2),
                               stick_ratio_torsion(t, "paper"), atol=1e-7)    # sqrt-steep at full slip


def test_exact_eq8_replacement_inverts_the_lubkin_twist():
    t = np.array([0.0, 0.1, 0.3, 0.5, 0.58])
    u_theta = shear_displacement_rotational_exact(t * MU * P * A, P, MU, A, G)
    # root finder to 4 eps; the twist is steep in c only near c = 0, outside this grid
    np.testing.assert_allclose(stick_ratio_from_rotation(u_theta, P, MU, A, G), stick_ratio_torsion(t), atol=1e-9)
    assert 0.0 < stick_ratio_from_rotation(1e3, P, MU, A, G) < 1e-6        # huge twists: tiny stick zone
