"""Torsion: the paper's eqs. 4-6 against eq. 5 as printed, and Lubkin's solution against traction quadrature."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.special import ellipe

from contact.theory import (
    LUBKIN_SLIP_TORQUE_RATIO, full_slip_torque_ratio, lubkin_torque_twist, lubkin_twist, stick_ratio_torsion,
    torsion_torque_ratio,
)

P, MU, A, G = 0.2, 0.5, 1.06, 0.35          # N, -, mm, MPa (the HCM-1 benchmark scale)
QUAD_RTOL = 1e-8                            # nested QUADPACK with epsrel 1e-11 each, log-type integrands


def _eq5_residual(k, t, n):
    """Paper eq. 5 exactly as printed (n != 1)."""
    return (k ** (n + 2) + (n + 2) / (2 * (n - 1)) * k**2 - 3 * n / (2 * (n - 1))
            + t * 3 * n * (n + 2) / (n**2 - 1))


@pytest.mark.parametrize("n", [2.0, 3.0, 4.0, 8.0])
def test_paper_model_solves_eq5(n):
    slip = (n + 1) / (2 * (n + 2))
    t = np.linspace(0.0, slip, 9)[1:-1]
    k = stick_ratio_torsion(t, "paper", n=n)
    # eq. 5 terms are O(1) to O(10); the root is found to 4 eps, so the residual is round-off
    np.testing.assert_allclose(_eq5_residual(k, t, n), 0.0, atol=1e-12)


def test_eq6_corrected_is_the_nested_root_and_as_printed_is_its_square():
    t = np.linspace(0.0, 0.375, 16)
    corrected = stick_ratio_torsion(t, "paper")
    np.testing.assert_allclose(corrected, np.sqrt(np.sqrt(4.0 - 8.0 * t) - 1.0), rtol=1e-15, atol=1e-15)
    np.testing.assert_allclose(stick_ratio_torsion(t, "paper_as_printed"), corrected**2, atol=1e-14)
    # general-n root finder at n = 2 agrees with the closed form (4 eps root tolerance, sqrt-steep near slip)
    np.testing.assert_allclose(stick_ratio_torsion(t[:-1], "paper", n=2.0 + 1e-12), corrected[:-1], atol=1e-7)


@pytest.mark.parametrize("model, n", [("lubkin", 2), ("paper", 1), ("paper", 2), ("paper", 8), ("paper_as_printed", 2)])
def test_torsion_end_points(model, n):
    slip = full_slip_torque_ratio(model, n)
    assert stick_ratio_torsion(0.0, model, n) == 1.0
    assert stick_ratio_torsion(min(slip + 1e-9, 1.0), model, n) == 0.0
    assert torsion_torque_ratio(0.0, model, n) == pytest.approx(slip, rel=1e-13)    # quadrature at c = 0
    assert torsion_torque_ratio(1.0, model, n) == pytest.approx(0.0, abs=1e-15)


def test_full_slip_torques():
    assert full_slip_torque_ratio("paper", 2) == 0.375
    assert full_slip_torque_ratio("lubkin") == 3 * math.pi / 16 == LUBKIN_SLIP_TORQUE_RATIO
    # docs/theory.md, sec. 6.2: the 1D model's full-slip torque is 2/pi of the exact one for every profile
    ratio = full_slip_torque_ratio("paper", 2) / full_slip_torque_ratio("lubkin")
    assert ratio == pytest.approx(2 / math.pi, rel=1e-15)


def test_lubkin_torque_tends_to_full_slip_as_stick_zone_vanishes():
    torque, twist = lubkin_torque_twist(1e-6, P, MU, A, G)
    # T(c) - T(0) = O((c/a)^2 ln(c/a)) ~ 1e-11 for c/a = 1e-6
    assert torque / (MU * P * A) == pytest.approx(3 * math.pi / 16, abs=1e-9)
    assert twist > 10 * lubkin_torque_twist(0.5, P, MU, A, G)[1]      # logarithmic growth of the twist


def test_lubkin_full_stick_stiffness():
    stick_ratio = 1.0 - 1e-7
    torque, twist = lubkin_torque_twist(stick_ratio, P, MU, A, G)
    # T/theta = 16 G a^3/3 (1 + O(m)), m = 1 - (c/a)^2 = 2e-7
    assert torque / twist == pytest.approx(16.0 * G * A**3 / 3.0, rel=1e-6)
    small = 1e-6 * MU * P * A
    assert small / lubkin_twist(small, P, MU, A, G) == pytest.approx(16.0 * G * A**3 / 3.0, rel=1e-5)


def _w(t, c):
    """Superposition density w(t) = (2 mu p0/pi) E(k_t)/t, k_t = sqrt(1 - t^2/a^2), for c < t < a.

    docs/theory.md, sec. 6.3.
    """
    p0 = 3.0 * P / (2.0 * math.pi * A**2)
    return 2.0 * MU * p0 / math.pi * ellipe(1.0 - (t / A) ** 2) / t


def _traction(r, c):
    """q(r) = r int_max(r,c)^a w(t) / sqrt(t^2 - r^2) dt by QUADPACK (end weight (t - r)^(-1/2) when r > c)."""
    if r >= c:
        value, _ = quad(lambda t: _w(t, c) / math.sqrt(t + r), r, A, weight="alg", wvar=(-0.5, 0.0), epsrel=1e-11)
    else:
        value, _ = quad(lambda t: _w(t, c) / math.sqrt(t * t - r * r), c, A, epsrel=1e-11)
    return r * value


@pytest.mark.parametrize("stick_ratio", [0.2, 0.6, 0.9])
def test_lubkin_torque_is_the_moment_of_the_traction(stick_ratio):
    c = stick_ratio * A
    torque, _ = quad(lambda r: 2.0 * math.pi * r * r * _traction(r, c), 0.0, A, points=[c], epsrel=1e-10)
    assert lubkin_torque_twist(stick_ratio, P, MU, A, G)[0] == pytest.approx(torque, rel=QUAD_RTOL)


def test_lubkin_traction_is_on_the_friction_limit_in_the_slip_annulus_and_below_it_inside():
    c = 0.5 * A
    p0 = 3.0 * P / (2.0 * math.pi * A**2)
    limit = lambda r: MU * p0 * math.sqrt(1.0 - (r / A) ** 2)
    for r in (0.6 * A, 0.8 * A, 0.95 * A):
        assert _traction(r, c) == pytest.approx(limit(r), rel=QUAD_RTOL)
    for r in (0.1 * A, 0.3 * A, 0.45 * A):
        assert _traction(r, c) < limit(r)


@pytest.mark.parametrize("stick_ratio", [0.1, 0.5, 0.95])
def test_lubkin_twist_is_the_sum_of_disc_rotations(stick_ratio):
    # a disc of radius t with density w dt rotates by pi w dt / (4 G): theta = (pi / (4 G)) int_c^a w dt
    c = stick_ratio * A
    value, _ = quad(lambda t: _w(t, c), c, A, epsrel=1e-12)
    assert lubkin_torque_twist(stick_ratio, P, MU, A, G)[1] == pytest.approx(math.pi / (4.0 * G) * value, rel=1e-10)


def test_lubkin_twist_inverts_the_parametric_curve():
    stick_ratios = np.array([0.1, 0.4, 0.7, 0.99])
    torque, twist = lubkin_torque_twist(stick_ratios, P, MU, A, G)
    # root finder to 4 eps in c/a; dtheta/dc is bounded away from c = 0
    np.testing.assert_allclose(lubkin_twist(torque, P, MU, A, G), twist, rtol=1e-9)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(t1=st.floats(0.0, 1.0), t2=st.floats(0.0, 1.0))
def test_torsion_models_are_monotone_and_ordered(t1, t2):
    low, high = sorted((t1, t2))
    for model in ("lubkin", "paper", "paper_as_printed"):
        assert 0.0 <= stick_ratio_torsion(high, model) <= stick_ratio_torsion(low, model) <= 1.0
    # the exact solution always sticks more than the 1D model, which sticks more than eq. 6 as printed
    lubkin, paper, printed = (stick_ratio_torsion(low, m) for m in ("lubkin", "paper", "paper_as_printed"))
    assert lubkin >= paper >= printed
