"""Invalid input raises ValueError naming the argument: one test per rule."""

import math

import numpy as np
import pytest

from contact.theory import (
    effective_modulus, flat_curved, hertz, lubkin_twist, mdr_scale, mindlin_shift, power_law,
    stick_ratio_from_shear_displacement, stick_ratio_profile, stick_ratio_torsion, stick_ratio_translational,
)


def test_load_ratio_above_one():
    with pytest.raises(ValueError, match=r"load_ratio=1\.2 outside allowed range \[0\.0, 1\.0\]"):
        stick_ratio_translational(1.2)


def test_negative_load_ratio_in_an_array():
    with pytest.raises(ValueError, match=r"load_ratio has 1 value\(s\).*first: .*-0\.1"):
        stick_ratio_profile(np.array([0.2, -0.1]), power_law(2))


def test_torque_ratio_outside_unit_interval():
    with pytest.raises(ValueError, match="torque_ratio"):
        stick_ratio_torsion(1.5)


def test_non_positive_order():
    with pytest.raises(ValueError, match=r"n=0\.0 outside allowed range \(0\.0, inf\)"):
        stick_ratio_translational(0.5, n=0)
    with pytest.raises(ValueError, match="n=-1"):
        mdr_scale(-1.0)


def test_negative_force():
    with pytest.raises(ValueError, match=r"P=-0\.2"):
        hertz(-0.2, 10.0, 1.0)


def test_negative_or_zero_modulus():
    with pytest.raises(ValueError, match=r"E_star=-1\.0"):
        hertz(0.2, 10.0, -1.0)
    with pytest.raises(ValueError, match=r"E1=0\.0"):
        effective_modulus(0.0, 0.3)


def test_nan_is_refused():
    with pytest.raises(ValueError, match="load_ratio=nan"):
        stick_ratio_translational(math.nan)
    with pytest.raises(ValueError, match="u_x has 1 value"):
        stick_ratio_from_shear_displacement(np.array([0.01, np.nan]), 0.2, 0.5, 1.25, 0.89, 0.05)


def test_tangential_force_beyond_friction_limit():
    with pytest.raises(ValueError, match=r"Q/\(mu P\)=1\.49"):
        mindlin_shift(0.15, 0.2, 0.5, 1.0, 0.35, 0.45)


def test_twist_at_full_slip_is_refused():
    with pytest.raises(ValueError, match="torque=.*full slip at 3 pi/16"):
        lubkin_twist(3 * math.pi / 16 * 0.5 * 0.2 * 1.0, 0.2, 0.5, 1.0, 0.35)


def test_unknown_model_and_reading():
    with pytest.raises(ValueError, match="model='paper_eq6'"):
        stick_ratio_torsion(0.1, model="paper_eq6")
    with pytest.raises(ValueError, match="reading='3d'"):
        flat_curved(0.5, reading="3d")


def test_lubkin_is_hertz_only():
    with pytest.raises(ValueError, match=r"n=3\.0 not allowed for model='lubkin'"):
        stick_ratio_torsion(0.1, model="lubkin", n=3)


def test_surface_ratio_must_leave_a_curved_rim():
    with pytest.raises(ValueError, match=r"b_over_a=1\.0 outside allowed range \[0\.0, 1\.0\)"):
        flat_curved(1.0)


def test_profile_must_be_callable():
    with pytest.raises(ValueError, match="profile=3"):
        stick_ratio_profile(0.5, 3)
