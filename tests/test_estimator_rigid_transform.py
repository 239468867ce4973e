"""Eq. 9 rigid-transform fit (closed-form 2D Procrustes) and the shift-to-displacement gain calibration."""

import json

import numpy as np
import pytest

from controller.estimation.calibration import EstimatorCalibration, PositionSource, calibrate_gain
from controller.estimation.estimator import BumpLayout
from controller.estimation.rigid_transform import FrameStatus, fit_rigid_transform

REFERENCE = BumpLayout.grid(spacing=12.0).centre_array        # 3 x 3 bumps, centroid at the origin [mm]


def transformed(reference, rotation, translation):
    """R(theta) r + t for angles (t,) and translations (t, 2): positions (t, k, 2)."""
    cos, sin = np.cos(rotation)[:, None], np.sin(rotation)[:, None]
    x, y = reference[None, :, 0], reference[None, :, 1]
    return np.stack([cos * x - sin * y, sin * x + cos * y], axis=-1) + translation[:, None, :]


def test_known_transforms_are_recovered_to_round_off():
    rng = np.random.default_rng(0)
    rotation = rng.uniform(-np.pi + 0.01, np.pi - 0.01, 50)    # atan2 covers the full circle
    translation = rng.uniform(-2.0, 2.0, (50, 2))
    fit = fit_rigid_transform(REFERENCE, transformed(REFERENCE, rotation, translation))
    # Positions ~ 17 mm carry round-off ~ 17 eps; theta's lever arm is 12 sqrt(6) mm.
    np.testing.assert_allclose(fit.rotation, rotation, atol=1e3 * np.finfo(float).eps)
    np.testing.assert_allclose(fit.translation, translation, atol=1e4 * np.finfo(float).eps)
    assert np.all(fit.valid) and fit.residual_rms.max() < 1e4 * np.finfo(float).eps


def test_any_two_bumps_in_contact_determine_the_transform():
    used = np.zeros((1, 9), dtype=bool)
    used[0, [2, 7]] = True
    current = transformed(REFERENCE, np.array([0.05]), np.array([[0.3, -0.2]]))
    current[0, ~used[0]] = 99.0                                # bumps out of contact carry anything
    fit = fit_rigid_transform(REFERENCE, current, used)
    assert fit.rotation[0] == pytest.approx(0.05, abs=1e-14) and fit.bump_count[0] == 2
    np.testing.assert_allclose(fit.translation[0], [0.3, -0.2], atol=1e-13)


def test_noise_spread_matches_the_least_squares_covariance():
    rng = np.random.default_rng(1)
    frames, sigma = 4000, 0.01                                 # mm, i.i.d. per coordinate
    truth_rotation, truth_translation = 0.03, np.array([0.2, -0.1])
    current = transformed(REFERENCE, np.full(frames, truth_rotation), np.tile(truth_translation, (frames, 1)))
    fit = fit_rigid_transform(REFERENCE, current + rng.normal(0.0, sigma, current.shape))
    # Linearised least squares with the reference centroid at the origin:
    # std(theta) = sigma / sqrt(sum |r_i - r_m|^2), std(t) = sigma / sqrt(N).
    rotation_std = sigma / np.sqrt(np.sum(REFERENCE**2))
    translation_std = sigma / np.sqrt(len(REFERENCE))
    # 4-sigma bounds on the sample std (relative 1/sqrt(2 frames)) and sample mean (std/sqrt(frames)).
    spread = 4.0 / np.sqrt(2.0 * frames)
    assert fit.rotation.std() / rotation_std == pytest.approx(1.0, abs=spread)
    np.testing.assert_allclose(fit.translation.std(axis=0) / translation_std, 1.0, atol=spread)
    assert abs(fit.rotation.mean() - truth_rotation) < 4.0 * rotation_std / np.sqrt(frames)
    assert np.all(np.abs(fit.translation.mean(axis=0) - truth_translation) < 4.0 * translation_std / np.sqrt(frames))
    # Residual: 2N data, 3 parameters -> E[rms^2] = sigma^2 (2N - 3) / N.
    assert np.mean(fit.residual_rms**2) / sigma**2 == pytest.approx((2 * 9 - 3) / 9, rel=0.05)


def test_too_few_bumps_or_nan_give_flags_and_zeros():
    current = np.repeat(REFERENCE[None], 4, axis=0)
    used = np.ones((4, 9), dtype=bool)
    used[0] = False                                            # no contact
    used[1, 1:] = False                                        # one bump
    current[2, 4] = np.nan                                     # NaN on a used bump
    current[3, 4] = np.nan                                     # NaN on an unused bump is ignored
    used[3, 4] = False
    fit = fit_rigid_transform(REFERENCE, current, used)
    assert list(fit.status) == [FrameStatus.NO_CONTACT, FrameStatus.ONE_BUMP, FrameStatus.NOT_FINITE, FrameStatus.OK]
    assert np.all(np.isfinite(fit.rotation)) and np.all(np.isfinite(fit.translation))
    assert np.all(fit.rotation[:3] == 0.0) and np.all(fit.translation[:3] == 0.0)


def test_gain_calibration_exact_noisy_and_json_roundtrip():
    rng = np.random.default_rng(2)
    shift = rng.uniform(-0.5, 0.5, (200, 9, 2))
    exact = calibrate_gain(shift, 1.7 * shift)
    assert exact.gain == pytest.approx(1.7, rel=1e-14) and exact.r_squared == pytest.approx(1.0, abs=1e-14)
    assert exact.sample_count == 3600
    sigma = 0.02
    noisy = calibrate_gain(shift, 1.7 * shift + rng.normal(0.0, sigma, shift.shape), PositionSource.PEAK)
    # Least squares through the origin: std(gain) = sigma / sqrt(sum s^2); 4-sigma bound.
    assert abs(noisy.gain - 1.7) < 4.0 * sigma / np.sqrt(np.sum(shift**2))
    assert 0.9 < noisy.r_squared < 1.0
    restored = EstimatorCalibration.from_dict(json.loads(json.dumps(noisy.to_dict())))
    assert restored == noisy and restored.position is PositionSource.PEAK


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="reference must be a finite"):
        fit_rigid_transform(np.zeros((3, 3)), np.zeros((1, 3, 2)))
    with pytest.raises(ValueError, match="current must have shape"):
        fit_rigid_transform(REFERENCE, np.zeros((1, 8, 2)))
    with pytest.raises(ValueError, match="used must have shape"):
        fit_rigid_transform(REFERENCE, np.zeros((1, 9, 2)), np.ones((2, 9), dtype=bool))
    with pytest.raises(ValueError, match="differs from position_shift"):
        calibrate_gain(np.ones(3), np.ones(4))
    with pytest.raises(ValueError, match="position_shift has 1 value"):
        calibrate_gain([1.0, np.nan], [1.0, 2.0])
    with pytest.raises(ValueError, match="at least 2 samples"):
        calibrate_gain([1.0], [1.0])
    with pytest.raises(ValueError, match="all zero"):
        calibrate_gain([0.0, 0.0], [1.0, 2.0])
    with pytest.raises(ValueError, match="constant"):
        calibrate_gain([1.0, 2.0], [1.0, 1.0])
    with pytest.raises(ValueError, match="gain .* <= 0"):
        calibrate_gain([1.0, 2.0], [-1.0, -2.0])
    with pytest.raises(ValueError, match="gain=0"):
        EstimatorCalibration(gain=0.0)
    with pytest.raises(ValueError, match="r_squared"):
        EstimatorCalibration(r_squared=1.5)
    with pytest.raises(ValueError, match="is not a valid PositionSource"):
        EstimatorCalibration(position="centroid")
    with pytest.raises(ValueError, match="unknown EstimatorCalibration keys"):
        EstimatorCalibration.from_dict({"gain": 1.0, "offset": 0.0})
