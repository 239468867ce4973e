"""Moduli, Hertz, Mindlin and MDR closed forms against independent quadratures (scipy.integrate.quad)."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from contact.theory import (
    effective_modulus, flat_curved, hertz, mdr_modified_profile, mdr_normal_force, mdr_scale, mindlin_shift,
    power_law, shear_modulus, stick_ratio_translational, tangential_modulus,
)

# quad reaches ~1e-12 relative on these smooth or algebraic-weight integrands; 1e-9 leaves room for cancellation.
QUAD_RTOL = 1e-9


def _abel(integrand, x, start=0.0):
    """int_start^x integrand(r) / sqrt(x^2 - r^2) dr with QUADPACK's algebraic end weight (x - r)^(-1/2)."""
    if x <= start:
        return 0.0
    value, _ = quad(lambda r: integrand(r) / math.sqrt(x + r), start, x, weight="alg", wvar=(0.0, -0.5),
                    epsabs=0.0, epsrel=1e-13, limit=200)
    return value


def _abel_modified_profile(slope, x, start=0.0):
    """g(x) = x int_0^x f'(r) / sqrt(x^2 - r^2) dr; ``start`` skips a flat part where f' = 0."""
    return x * _abel(slope, x, start)


def _mdr_force(slope, a, start=0.0):
    """P(a)/E* = 2 int_0^a r^2 f'(r) / sqrt(a^2 - r^2) dr (Sneddon's form: a different integral from the code's)."""
    return 2.0 * _abel(lambda r: r * r * slope(r), a, start)


def test_moduli_reduce_to_one_body_and_add_as_compliances():
    E, nu = 2.0, 0.3
    G = shear_modulus(E, nu)
    assert G == pytest.approx(E / 2.6, rel=1e-15)          # exact arithmetic up to round-off
    assert effective_modulus(E, nu) == pytest.approx(2.0 * G / (1.0 - nu), rel=1e-14)
    assert tangential_modulus(G, nu) == pytest.approx(4.0 * G / (2.0 - nu), rel=1e-14)
    # two identical bodies are twice as compliant as one against a rigid body
    assert effective_modulus(E, nu, E, nu) == pytest.approx(effective_modulus(E, nu) / 2.0, rel=1e-14)
    assert tangential_modulus(G, nu, G, nu) == pytest.approx(tangential_modulus(G, nu) / 2.0, rel=1e-14)
    np.testing.assert_allclose(effective_modulus(np.array([1.0, 2.0]), 0.0), [1.0, 2.0], rtol=1e-15)


@pytest.mark.parametrize("P, R, E_star", [(0.2, 10.0, 1.2539), (5.0, 3.0, 40.0)])
def test_hertz_force_is_integral_of_pressure_and_indentation_is_mdr_depth(P, R, E_star):
    contact = hertz(P, R, E_star)
    a, p0 = contact.contact_radius, contact.peak_pressure
    force, _ = quad(lambda r: 2.0 * math.pi * r * p0 * math.sqrt(1.0 - (r / a) ** 2), 0.0, a, epsrel=1e-13)
    assert force == pytest.approx(P, rel=QUAD_RTOL)
    assert contact.indentation == pytest.approx(_abel_modified_profile(lambda r: r / R, a), rel=QUAD_RTOL)
    assert E_star * _mdr_force(lambda r: r / R, a) == pytest.approx(P, rel=QUAD_RTOL)


def test_hertz_zero_force_gives_zero_contact():
    contact = hertz(0.0, 10.0, 1.0)
    assert (contact.contact_radius, contact.peak_pressure, contact.indentation) == (0.0, 0.0, 0.0)


@pytest.mark.parametrize("n", [0.5, 1.0, 2.0, 3.0, 4.0, 8.0])
def test_mdr_scale_is_the_abel_integral_of_a_power_law(n):
    # kappa_n = g(1) for f(r) = r^n, computed here by QUADPACK with the algebraic end weight
    assert mdr_scale(n) == pytest.approx(_abel_modified_profile(lambda r: n * r ** (n - 1.0), 1.0), rel=QUAD_RTOL)


def test_mdr_scale_special_values():
    # Gamma-function values: kappa_1 = pi/2, kappa_2 = 2, kappa_4 = 8/3, kappa_8 = 128/35 (round-off only)
    np.testing.assert_allclose(mdr_scale([1, 2, 4, 8]), [math.pi / 2, 2.0, 8.0 / 3.0, 128.0 / 35.0], rtol=1e-13)
    assert mdr_scale(math.inf) == math.inf


@pytest.mark.parametrize("n", [1.0, 2.0, 3.0, 4.0, 8.0])
def test_power_law_closed_forms_match_quadrature(n):
    profile = power_law(n, coefficient=0.3)
    radii = np.array([0.2, 1.0, 1.7])
    expected_g = [_abel_modified_profile(profile.slope, r) for r in radii]
    expected_force = [_mdr_force(profile.slope, r) for r in radii]
    np.testing.assert_allclose(profile.modified_profile(radii), expected_g, rtol=QUAD_RTOL)
    np.testing.assert_allclose(profile.force_per_modulus(radii), expected_force, rtol=QUAD_RTOL)
    # the package's own Gauss route (s^2 substitution) agrees to the same level
    np.testing.assert_allclose(mdr_modified_profile(profile, radii), expected_g, rtol=QUAD_RTOL)
    np.testing.assert_allclose(mdr_normal_force(profile, radii, E_star=2.0), 2.0 * np.array(expected_force),
                               rtol=QUAD_RTOL)


@pytest.mark.parametrize("reading", ["rounded_punch", "mdr_1d"])
@pytest.mark.parametrize("b_over_a", [0.0, 0.25, 0.5, 0.9])
def test_flat_curved_closed_forms_match_quadrature(reading, b_over_a):
    profile = flat_curved(b_over_a, reading=reading, curvature_radius=2.0)
    radii = np.array([b_over_a + 0.05, 0.5 * (1.0 + b_over_a), 1.0])
    # start the quadrature at the kink r = b (f' = 0 inside), so QUADPACK sees a smooth integrand
    expected_g = [_abel_modified_profile(profile.slope, r, start=b_over_a) for r in radii]
    expected_force = [_mdr_force(profile.slope, r, start=b_over_a) for r in radii]
    # the profile is zero out to b, so the absolute scale of the tolerance is g(1) ~ 0.1-0.5 mm
    np.testing.assert_allclose(profile.modified_profile(radii), expected_g, rtol=QUAD_RTOL, atol=1e-12)
    np.testing.assert_allclose(profile.force_per_modulus(radii), expected_force, rtol=QUAD_RTOL, atol=1e-12)
    np.testing.assert_allclose(mdr_normal_force(profile, radii), expected_force, rtol=QUAD_RTOL, atol=1e-12)


def test_flat_curved_mdr_1d_gap_is_inverse_transform_of_its_1d_profile():
    # f(r) = (2/pi) int_0^r g(x)/sqrt(r^2 - x^2) dx with g = (x - b)^2 / R: independent of the closed-form gap
    b, R = 0.4, 1.0
    profile = flat_curved(b, reading="mdr_1d", curvature_radius=R)
    for r in (0.3, 0.6, 1.0):
        value, _ = quad(lambda x: max(x - b, 0.0) ** 2 / R / math.sqrt(r + x), 0.0, r, weight="alg",
                        wvar=(0.0, -0.5), epsrel=1e-13)
        assert profile(r) == pytest.approx(2.0 / math.pi * value, rel=QUAD_RTOL, abs=1e-15)


def test_flat_curved_readings_reduce_to_the_sphere():
    sphere = power_law(2.0, coefficient=0.5)        # f = r^2 / 2 = r^2/(2R) with R = 1
    radii = np.linspace(0.0, 1.5, 7)
    for reading in ("rounded_punch", "mdr_1d"):
        # round-off only: the formulas coincide algebraically at b = 0
        np.testing.assert_allclose(flat_curved(0.0, reading=reading)(radii), sphere(radii), rtol=1e-14, atol=1e-16)


@pytest.mark.parametrize("nu", [0.0, 0.3, 0.45, 0.5])
def test_mindlin_shift_initial_stiffness_and_mdr_route(nu):
    P, mu, R, G = 0.2, 0.5, 10.0, 0.35
    E_star, G_star = 2.0 * G / (1.0 - nu), 4.0 * G / (2.0 - nu)
    contact = hertz(P, R, E_star)
    a = contact.contact_radius
    small = 1e-7 * mu * P
    # forward difference: relative error ~ (1/6) Q/(mu P) = 2e-8 (the curve's second-order term)
    assert small / mindlin_shift(small, P, mu, a, G, nu) == pytest.approx(8.0 * G * a / (2.0 - nu), rel=1e-7)
    # MDR route: u_x = mu (E*/G*) [d(a) - d(c)], d(rho) = rho^2 / R, c from eq. 3 (independent of the 2/3 power)
    load_ratio = np.array([0.0, 0.3, 0.7, 1.0])
    c = a * stick_ratio_translational(load_ratio, 2)
    np.testing.assert_allclose(mindlin_shift(load_ratio * mu * P, P, mu, a, G, nu),
                               mu * E_star / G_star * (a**2 - c**2) / R, rtol=1e-13, atol=1e-18)
