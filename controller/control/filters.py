"""First-order discrete low-pass filter (Tustin with pre-warping) for shear displacements and the DOB."""

from __future__ import annotations

import math

import numpy as np

from fem.validation import check_positive, check_range

__all__ = ["FirstOrderLowPass", "sample_period", "tustin_gain"]


def sample_period(sample_rate_hz: float, name: str = "sample_rate_hz") -> float:
    """Sample period T = 1 / f_s [s] of a loop running at ``sample_rate_hz`` [Hz] (> 0, checked)."""
    return 1.0 / check_positive(name, sample_rate_hz, "Hz")


def tustin_gain(cutoff_hz: float, sample_rate_hz: float) -> float:
    """Gain b [-] of the first-order Tustin low-pass y_k = b (x_k + x_{k-1}) + (1 - 2 b) y_{k-1}, cut-off pre-warped
    (w_a = 2 / T tan(pi f_c T) [rad/s])."""
    period = sample_period(sample_rate_hz)
    warped = 2.0 / period * math.tan(math.pi * cutoff_hz * period)
    return warped * period / (2.0 + warped * period)


class FirstOrderLowPass:
    """Discrete first-order low-pass filter H(s) = w_a / (s + w_a), Tustin-discretised with pre-warping.

    With w_a = (2/T) tan(w_c T / 2) and s -> (2/T) (z - 1)/(z + 1) the discrete response is

        H(e^{jwT}) = w_a / (w_a + j (2/T) tan(wT/2)),

    so |H| = 1/sqrt(2) exactly at the cut-off w = w_c (pre-warping), H(1) = 1 (unit DC gain) and H(-1) = 0
    (a zero at the Nyquist frequency, which suppresses sample-to-sample noise). Difference equation:

        y_k = b (x_k + x_{k-1}) + (1 - 2 b) y_{k-1},   b = w_a T / (2 + w_a T).

    The filter is vectorised: the state has the shape of the first input (or of ``initial``).

    Parameters
    ----------
    cutoff_hz : float -- cut-off frequency f_c [Hz], 0 < f_c < f_s / 2.
    sample_rate_hz : float -- sample rate f_s [Hz], > 0.
    initial : float or array -- initial input and output (steady state) [unit of the signal].
    """

    def __init__(self, cutoff_hz: float, sample_rate_hz: float, initial=0.0):
        self.sample_period = sample_period(sample_rate_hz)
        self.cutoff_hz = check_range("cutoff_hz", cutoff_hz, 0.0, 0.5 * sample_rate_hz, "Hz", True, True)
        self._gain = tustin_gain(self.cutoff_hz, sample_rate_hz)                                     # b [-]
        self.reset(initial)

    def reset(self, value=0.0) -> None:
        """Set the filter to the steady state ``value`` (input = output = value)."""
        self.previous_input = np.array(value, dtype=float)
        self.output = np.array(value, dtype=float)

    def step(self, value):
        """Filter one sample ``value`` (float or array) and return the output (same shape)."""
        value = np.asarray(value, dtype=float)
        self.output = self._gain * (value + self.previous_input) + (1.0 - 2.0 * self._gain) * self.output
        self.previous_input = value
        return self.output.copy() if self.output.ndim else float(self.output)

    def frequency_response(self, frequency_hz):
        """Complex response H(e^{j 2 pi f T}) of the difference equation at ``frequency_hz`` [Hz] (array)."""
        z = np.exp(2j * math.pi * np.asarray(frequency_hz, dtype=float) * self.sample_period)
        return self._gain * (1.0 + 1.0 / z) / (1.0 - (1.0 - 2.0 * self._gain) / z)
