"""Stick ratio under tangential load: eq. 3 against Ciavarella-Jager with MDR quadrature, flat + curved end points."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from contact.theory import flat_curved, power_law, stick_ratio_profile, stick_ratio_translational

LOAD_RATIOS = np.linspace(0.0, 1.0, 41)
# The quadrature is exact to ~1e-14 (Gauss with s^2 substitution) and the root finder stops at 4 eps, but the
# inversion amplifies force errors by dc/dP ~ 1/(1 - Q/(mu P)) near full slip: 1e-10 covers the grid above.
ROOT_ATOL = 1e-10


@pytest.mark.parametrize("n", [1, 2, 3, 4, 5, 6, 7, 8])
def test_ciavarella_jager_with_mdr_quadrature_reproduces_eq3(n):
    numerical = stick_ratio_profile(LOAD_RATIOS, power_law(n, coefficient=0.2), contact_radius=1.3)
    np.testing.assert_allclose(numerical, stick_ratio_translational(LOAD_RATIOS, n), atol=ROOT_ATOL)


def test_plain_callable_profile_with_numerical_slope_reproduces_hertz():
    load_ratios = np.linspace(0.0, 0.9, 10)
    numerical = stick_ratio_profile(load_ratios, lambda r: r**2 / 20.0, contact_radius=1.06)
    # 4th-order central difference of a quadratic: only round-off eps f/step ~ 1e-13 per slope value
    np.testing.assert_allclose(numerical, (1.0 - load_ratios) ** (1.0 / 3.0), atol=1e-9)


def test_flat_limit_of_eq3_is_all_stick_until_gross_slip():
    assert stick_ratio_translational(0.999, math.inf) == 1.0
    assert stick_ratio_translational(1.0, math.inf) == 0.0
    # the power law approaches it: c/a = (1 - x)^(1/(n+1)) -> 1 for large n
    assert stick_ratio_translational(0.9, 1e6) == pytest.approx(1.0, abs=1e-5)   # ln(10)/1e6 = 2.3e-6


@pytest.mark.parametrize("n", [1.0, 2.0, 8.0, math.inf])
def test_eq3_end_points(n):
    assert stick_ratio_translational(0.0, n) == 1.0
    assert stick_ratio_translational(1.0, n) == 0.0


@pytest.mark.parametrize("reading", ["rounded_punch", "mdr_1d"])
@pytest.mark.parametrize("b_over_a", [0.25, 0.5, 0.75, 0.9])
def test_flat_curved_starts_at_one_falls_to_b_over_a_then_drops_to_zero(reading, b_over_a):
    profile = flat_curved(b_over_a, reading=reading, contact_radius=2.0)
    ends = stick_ratio_profile([0.0, 1.0 - 1e-12, 1.0], profile, contact_radius=2.0)
    assert ends[0] == 1.0
    # P(c) ~ (c - b)^(5/2) (rounded punch) or (c - b)^2 (mdr_1d): 1e-12 of the force is < 1e-4 in c/a
    assert ends[1] == pytest.approx(b_over_a, abs=1e-4)
    assert ends[2] == 0.0


@pytest.mark.parametrize("reading", ["rounded_punch", "mdr_1d"])
def test_flat_curved_quadrature_matches_closed_form_force_curve(reading):
    profile = flat_curved(0.5, reading=reading)
    np.testing.assert_allclose(stick_ratio_profile(LOAD_RATIOS, profile),
                               stick_ratio_profile(LOAD_RATIOS, profile, method="closed_form"), atol=ROOT_ATOL)


def test_mdr_1d_reading_sticks_more_than_rounded_punch():
    # docs/theory.md, sec. 5.2: the second reading is 0.003-0.03 higher in c/a, same end point
    load_ratios = np.linspace(0.05, 0.95, 10)
    for b_over_a in (0.25, 0.5, 0.75):
        gap = (stick_ratio_profile(load_ratios, flat_curved(b_over_a, reading="mdr_1d"))
               - stick_ratio_profile(load_ratios, flat_curved(b_over_a)))
        assert np.all(gap > 0.0)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(x1=st.floats(0.0, 1.0), x2=st.floats(0.0, 1.0), n=st.floats(0.1, 50.0))
def test_eq3_is_bounded_and_decreasing_in_load(x1, x2, n):
    low, high = sorted((x1, x2))
    c_low, c_high = stick_ratio_translational(low, n), stick_ratio_translational(high, n)
    assert 0.0 <= c_high <= c_low <= 1.0


@settings(max_examples=30, deadline=None, derandomize=True)
@given(x=st.floats(0.0, 0.999), n1=st.floats(0.1, 20.0), n2=st.floats(0.1, 20.0))
def test_eq3_increases_with_profile_order(x, n1, n2):
    low, high = sorted((n1, n2))
    assert stick_ratio_translational(x, low) <= stick_ratio_translational(x, high)


@settings(max_examples=20, deadline=None, derandomize=True)
@given(b_over_a=st.floats(0.0, 0.95), x=st.lists(st.floats(0.0, 0.999), min_size=2, max_size=6))
def test_flat_curved_stick_ratio_is_monotone_between_b_over_a_and_one(b_over_a, x):
    load_ratios = np.sort(np.array(x))
    stick = stick_ratio_profile(load_ratios, flat_curved(b_over_a), method="closed_form")
    assert np.all(np.diff(stick) <= 1e-12)                           # round-off of the root finder
    assert np.all((stick >= b_over_a - 1e-12) & (stick <= 1.0))
