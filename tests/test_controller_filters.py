"""First-order low-pass filters: cut-off of the shear-displacement filter (1 kHz) and of the DOB filter (8 kHz)."""

import math

import numpy as np
import pytest

from controller import (AccelerationControlParameters, AccelerationController, FirstOrderLowPass,
                        GraspForceController, GraspForceParameters, ReferenceParameters)

# Tustin with pre-warping puts |H| = 1/sqrt(2) exactly at f_c; what is left is rounding in tan, exp and a few
# products of O(1) numbers: a few ulp, so 1e3 eps is a generous bound.
ROUNDING = 1e3 * np.finfo(float).eps


def _impulse_response_magnitude(lowpass, frequency_hz, length):
    """|DTFT| of the impulse response of ``lowpass.step`` (the code, not the formula), truncated at ``length``."""
    response = np.array([lowpass.step(1.0 if k == 0 else 0.0) for k in range(length)])
    phase = np.exp(-2j * math.pi * frequency_hz * lowpass.sample_period * np.arange(length))
    return abs(np.dot(response, phase)), abs(response[-1])


@pytest.mark.parametrize("cutoff_hz, rate_hz", [(30.0, 1000.0), (200.0, 8000.0), (400.0, 1000.0)])
def test_frequency_response_is_one_over_sqrt2_at_cutoff(cutoff_hz, rate_hz):
    lowpass = FirstOrderLowPass(cutoff_hz, rate_hz)
    assert abs(lowpass.frequency_response(cutoff_hz)) == pytest.approx(1.0 / math.sqrt(2.0), abs=ROUNDING)
    assert abs(lowpass.frequency_response(0.0)) == pytest.approx(1.0, abs=ROUNDING)
    assert abs(lowpass.frequency_response(0.5 * rate_hz)) == pytest.approx(0.0, abs=ROUNDING)
    # The impulse response decays geometrically (pole 1 - 2b); truncating it after N samples changes the DTFT by
    # at most |h_N| / (1 - pole) <= |h_N| * (its time constant in samples + 1), bounded below by 1e-12 at N chosen.
    length = int(60 * rate_hz / (2 * math.pi * cutoff_hz)) + 50
    magnitude, tail = _impulse_response_magnitude(FirstOrderLowPass(cutoff_hz, rate_hz), cutoff_hz, length)
    assert tail < 1e-14
    assert magnitude == pytest.approx(1.0 / math.sqrt(2.0), abs=1e-12)


def test_controllers_use_their_stated_cutoffs():
    grasp = GraspForceController(GraspForceParameters(filter_cutoff_hz=30.0), ReferenceParameters())
    observer = AccelerationController(AccelerationControlParameters(dob_cutoff_hz=200.0)).observer.filter
    for lowpass, cutoff in ((grasp.filter, 30.0), (observer, 200.0)):
        assert abs(lowpass.frequency_response(cutoff)) == pytest.approx(1.0 / math.sqrt(2.0), abs=ROUNDING)


def test_filter_is_vectorised_and_starts_at_rest():
    lowpass = FirstOrderLowPass(30.0, 1000.0, initial=np.array([1.0, -2.0]))
    np.testing.assert_allclose(lowpass.step([1.0, -2.0]), [1.0, -2.0], atol=ROUNDING)


@pytest.mark.parametrize("cutoff_hz, rate_hz, match", [
    (0.0, 1000.0, "cutoff_hz=0.0 outside"),
    (500.0, 1000.0, "cutoff_hz=500.0 outside"),
    (10.0, 0.0, "sample_rate_hz=0.0 outside"),
])
def test_invalid_filter_settings_raise(cutoff_hz, rate_hz, match):
    with pytest.raises(ValueError, match=match):
        FirstOrderLowPass(cutoff_hz, rate_hz)
