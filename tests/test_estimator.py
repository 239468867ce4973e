"""Slip estimator: CoP and peak of known fields, end-to-end shifts and rotation, flags for degenerate frames."""

import numpy as np
import pytest

from contact.theory import stick_ratio_from_rotation, stick_ratio_from_shear_displacement
from controller.estimation.calibration import EstimatorCalibration, PositionSource
from controller.estimation.estimator import (BumpLayout, BumpReference, EstimatorSettings, bump_positions,
                                             estimate_slip, rotational_stick_ratio, translational_stick_ratio)
from controller.estimation.rigid_transform import FrameStatus
from controller.sensing.sensor import PressureField, SensorArray, sample

PAPER_ARRAY = SensorArray()                                   # 11 x 13 nodes at 3 mm
LAYOUT = BumpLayout.grid(spacing=12.0)                         # 3 x 3 bumps, regions = Voronoi cells
FIELD_SPACING = 0.25                                           # mm, grid of the tabulated test fields


def translated_field(profile, shift, half_width=25.0):
    """profile(X, Y) [MPa] translated by ``shift`` [mm], tabulated on a grid translated with it, so the
    piecewise-linear field is exactly the translated one and only the sensor sampling differs."""
    x = np.arange(-half_width, half_width + 0.5 * FIELD_SPACING, FIELD_SPACING)
    return PressureField.from_function(lambda X, Y: profile(X - shift[0], Y - shift[1]), x + shift[0], x + shift[1])


def unsheared_reference(profile, array, layout):
    """Reference positions from the untranslated field."""
    return BumpReference.from_readings(sample(translated_field(profile, (0.0, 0.0)), array), array, layout)


def gaussian(width):
    return lambda X, Y: 0.02 * np.exp(-(X**2 + Y**2) / (2.0 * width**2))


def hertz_bumps(centres, radius):
    """Hertz pressure p0 sqrt(1 - r^2/a^2) under every bump (compact: radius a [mm])."""
    def profile(X, Y):
        r2 = (X[None] - centres[:, 0, None, None]) ** 2 + (Y[None] - centres[:, 1, None, None]) ** 2
        return 0.05 * np.sqrt(np.maximum(1.0 - r2 / radius**2, 0.0)).sum(axis=0)
    return profile


def test_cop_of_a_shifted_gaussian_moves_by_the_shift():
    single = BumpLayout([(0.0, 0.0)])                          # one region: the whole array
    reference = unsheared_reference(gaussian(3.0), PAPER_ARRAY, single)
    for shift in [(0.37, -0.81), (1.2, 0.5), (-1.4, 1.49)]:
        estimate = estimate_slip(sample(translated_field(gaussian(3.0), shift), PAPER_ARRAY), PAPER_ARRAY, single,
                                 reference)
        # The cell (box) filter has zeros at every multiple of 1/pitch, so sampling aliases the CoP only through
        # the field's spectrum there: exp(-2 pi^2 w^2 / pitch^2) ~ 3e-9 for w = pitch. What remains is the tail
        # beyond the footprint edge (16.5 mm ~ 5 w): measured 4e-6 mm.
        np.testing.assert_allclose(estimate.cop_shift[0, 0], shift, atol=1e-5)


def test_cop_shift_by_whole_pitches_is_exact_and_gives_a_pure_translation():
    array = SensorArray(node_counts=(15, 15))                  # margin: shifted bumps stay inside the footprint
    profile = hertz_bumps(LAYOUT.centre_array, radius=2.0)
    reference = unsheared_reference(profile, array, LAYOUT)
    estimate = estimate_slip(sample(translated_field(profile, (3.0, 3.0)), array), array, LAYOUT, reference)
    # Shifting field and cells by one pitch maps every clipped piece onto itself (cell-local coordinates), and
    # each field stays inside its own region, so only round-off separates the shifts.
    np.testing.assert_allclose(estimate.cop_shift[0], 3.0, atol=1e-12)
    np.testing.assert_allclose(estimate.peak_shift[0], 3.0, atol=1e-12)
    assert estimate.transform.valid[0] and abs(estimate.transform.rotation[0]) < 1e-13
    np.testing.assert_allclose(estimate.transform.translation[0], 3.0, atol=1e-12)


def test_sub_pitch_hertz_shifts_and_a_rotation_through_the_paper_array():
    profile = hertz_bumps(LAYOUT.centre_array, radius=2.5)
    reference = unsheared_reference(profile, PAPER_ARRAY, LAYOUT)
    shifts = [(0.5, 0.2), (1.0, 0.7), (0.75, 0.0), (1.2, -0.4)]
    readings = np.concatenate([sample(translated_field(profile, s), PAPER_ARRAY) for s in shifts])
    estimate = estimate_slip(readings, PAPER_ARRAY, LAYOUT, reference)
    cop_error = np.abs(estimate.cop_shift - np.array(shifts)[:, None, :]).max()
    # A 5 mm wide Hertz patch on a 3 mm pitch: the CoP aliases (paper Fig. 6); measured 0.074 mm. A pure shift
    # moves every bump alike, so the fitted rotation stays at round-off.
    assert cop_error < 0.08
    assert np.all(estimate.transform.valid) and np.abs(estimate.transform.rotation).max() < 1e-12
    twist = 0.03
    rotation = np.array([[np.cos(twist), -np.sin(twist)], [np.sin(twist), np.cos(twist)]])
    rotated = sample(translated_field(hertz_bumps(LAYOUT.centre_array @ rotation.T, 2.5), (0, 0)), PAPER_ARRAY)
    transform = estimate_slip(rotated, PAPER_ARRAY, LAYOUT, reference).transform
    # Outer bumps move by twist * 12-17 mm = 0.36-0.51 mm, each with up to ~0.08 mm aliasing error; theta's
    # lever is sqrt(sum |r_i|^2) = 12 sqrt(6) mm, so |d theta| <~ 0.08 / (12 sqrt(6) / sqrt(8)) ~ 8e-3 rad.
    assert abs(transform.rotation[0] - twist) < 8e-3 and transform.residual_rms[0] < 0.08


def test_peak_fit_is_exact_for_a_quadratic_and_does_not_refine_across_the_edge():
    nodes = PAPER_ARRAY.node_positions
    peak = np.array([1.1, -0.7])
    readings = 10.0 - (nodes[..., 0] - peak[0]) ** 2 - 2.0 * (nodes[..., 1] - peak[1]) ** 2
    _, _, peaks = bump_positions(readings, PAPER_ARRAY, BumpLayout([(0.0, 0.0)]))
    np.testing.assert_allclose(peaks[0, 0], peak, atol=1e-12)
    edge = 10.0 - (nodes[..., 0] - 16.0) ** 2 - (nodes[..., 1] - peak[1]) ** 2      # peak beyond the last column
    _, _, peaks = bump_positions(edge, PAPER_ARRAY, BumpLayout([(0.0, 0.0)]))
    np.testing.assert_allclose(peaks[0, 0], [PAPER_ARRAY.node_x[-1], peak[1]], atol=1e-12)


def test_region_radius_restricts_the_voronoi_cell():
    voronoi = LAYOUT.regions(PAPER_ARRAY)
    disks = BumpLayout(LAYOUT.centres, region_radius=4.5).regions(PAPER_ARRAY)
    assert voronoi.sum(axis=0).max() == 1 and voronoi.sum() == 11 * 13          # a partition of the nodes
    assert np.all(disks <= voronoi) and disks.sum(axis=(1, 2)).tolist() == [9] * 9


def test_gain_and_position_source_scale_the_shift():
    profile = hertz_bumps(LAYOUT.centre_array, radius=2.5)
    reference = unsheared_reference(profile, PAPER_ARRAY, LAYOUT)
    readings = sample(translated_field(profile, (0.6, -0.3)), PAPER_ARRAY)
    plain = estimate_slip(readings, PAPER_ARRAY, LAYOUT, reference)
    cop = estimate_slip(readings, PAPER_ARRAY, LAYOUT, reference, EstimatorCalibration(gain=1.8))
    peak = estimate_slip(readings, PAPER_ARRAY, LAYOUT, reference, EstimatorCalibration(0.5, PositionSource.PEAK))
    np.testing.assert_allclose(cop.shear_displacement, 1.8 * plain.cop_shift, rtol=1e-15)
    np.testing.assert_allclose(peak.shear_displacement, 0.5 * plain.peak_shift, rtol=1e-15)
    np.testing.assert_allclose(cop.transform.translation, 1.8 * plain.transform.translation, rtol=1e-12)


def test_degenerate_frames_are_flagged_not_nan():
    profile = hertz_bumps(LAYOUT.centre_array[:1], radius=2.5)                 # only bump 0 pressed
    one_bump = sample(translated_field(profile, (0.2, 0.0)), PAPER_ARRAY)[0]
    two_bumps = sample(translated_field(hertz_bumps(LAYOUT.centre_array[:2], 2.5), (0.2, 0.0)), PAPER_ARRAY)[0]
    broken = two_bumps.copy()
    broken[3, 4] = np.nan
    readings = np.stack([np.zeros(PAPER_ARRAY.shape), one_bump, broken, two_bumps])
    estimate = estimate_slip(readings, PAPER_ARRAY, LAYOUT)
    assert list(estimate.transform.status) == [FrameStatus.NO_CONTACT, FrameStatus.ONE_BUMP,
                                               FrameStatus.NOT_FINITE, FrameStatus.OK]
    assert estimate.transform.valid.tolist() == [False, False, False, True]
    assert estimate.in_contact.sum(axis=1).tolist() == [0, 1, 0, 2]
    for value in (estimate.bump_force, estimate.cop, estimate.peak, estimate.shear_displacement,
                  estimate.transform.rotation, estimate.transform.translation, estimate.transform.residual_rms):
        assert np.all(np.isfinite(value))
    assert estimate.transform.rotation[:3].tolist() == [0.0] * 3
    assert estimate.shear_displacement[1, 0, 0] > 0.0               # the single bump still reports its shift
    empty = estimate_slip(np.zeros((0,) + PAPER_ARRAY.shape), PAPER_ARRAY, LAYOUT)
    assert empty.shear_displacement.shape == (0, 9, 2) and empty.transform.valid.shape == (0,)


def test_stick_ratio_wrappers_reuse_contact_theory():
    displacement = np.array([[0.003, 0.004], [0.0, 0.01]])      # |u| = 0.005, 0.01 mm
    force = np.array([1.0, 2.0])
    expected = stick_ratio_from_shear_displacement(np.array([0.005, 0.01]), force, 0.5, 1.2, 0.5, 0.05, 2)
    np.testing.assert_allclose(translational_stick_ratio(displacement, force, 0.5, 1.2, 0.5, 0.05), expected,
                               rtol=1e-15)
    twist, radius = np.array([-0.01, 0.02]), np.array([1.0, 1.3])
    scaled = rotational_stick_ratio(twist, force, 0.5, radius, 0.33)
    # Lubkin's twist scales as mu P / (G a^2): the normalised call equals the direct one to the root-finder tolerance.
    direct = [stick_ratio_from_rotation(abs(t) * a, p, 0.5, a, 0.33) for t, p, a in zip(twist, force, radius)]
    np.testing.assert_allclose(scaled, direct, rtol=1e-9)


def test_bad_inputs_are_named():
    with pytest.raises(ValueError, match="readings must have shape"):
        estimate_slip(np.zeros((13, 12)), PAPER_ARRAY, LAYOUT)
    with pytest.raises(ValueError, match="reference positions must have shape"):
        estimate_slip(np.zeros((13, 11)), PAPER_ARRAY, LAYOUT, BumpReference.from_layout(BumpLayout([(0, 0)])))
    with pytest.raises(ValueError, match="has no sensor node"):
        BumpLayout([(0.0, 0.0), (40.0, 0.0)]).regions(PAPER_ARRAY)
    with pytest.raises(ValueError, match="centres must be distinct"):
        BumpLayout([(0.0, 0.0), (0.0, 0.0)])
    with pytest.raises(ValueError, match="centres must have shape"):
        BumpLayout([0.0, 1.0])
    with pytest.raises(ValueError, match="region_radius"):
        BumpLayout([(0.0, 0.0)], region_radius=0.0)
    with pytest.raises(ValueError, match="contact_threshold"):
        EstimatorSettings(contact_threshold=-0.1)
    with pytest.raises(ValueError, match="readings must be finite here"):
        bump_positions(np.full((13, 11), np.nan), PAPER_ARRAY, LAYOUT)
    with pytest.raises(ValueError, match="normal_force must be > 0"):
        translational_stick_ratio(np.zeros((1, 2)), [0.0], 0.5, 1.2, 0.5, 0.05)
    with pytest.raises(ValueError, match="shear_displacement must have shape"):
        translational_stick_ratio(np.zeros(3), [1.0], 0.5, 1.2, 0.5, 0.05)
    with pytest.raises(ValueError, match="contact_radius must be > 0"):
        rotational_stick_ratio([0.01], [1.0], 0.5, [0.0], 0.33)
