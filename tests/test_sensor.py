"""Sensor array model: exact cell integration, read-out chain (offset, noise, quantization), resampling, inputs."""

import numpy as np
import pytest
from scipy.spatial import Delaunay

from controller.sensing.sensor import (Interpolation, PressureField, SensorArray, cell_force_operator,
                                       resample_time_series, sample)

PAPER_ARRAY = SensorArray()                       # 11 x 13 nodes at 3 mm, footprint 33 x 39 mm
EPS = np.finfo(float).eps


def random_field(seed=0, frames=3, half_width=15.0, nodes=300):
    """Scattered Delaunay triangulation inside the paper array's footprint, random nodal pressures [MPa]."""
    rng = np.random.default_rng(seed)
    positions = rng.uniform(-half_width, half_width, (nodes, 2))
    return PressureField(positions, Delaunay(positions).simplices, rng.uniform(0.0, 0.1, (frames, nodes)))


def test_total_force_is_conserved_to_round_off():
    field = random_field()
    readings = sample(field, PAPER_ARRAY)
    # Exact clipping: the pieces tile each triangle; ~1e3 pieces each summed with relative error eps.
    np.testing.assert_allclose(readings.sum(axis=(1, 2)), field.total_force(), rtol=1e3 * EPS)


def test_each_cell_of_a_linear_field_reads_its_centre_value_times_area():
    # The mean of a linear field over a square is its value at the centre: a per-cell check of the clipping
    # on a mesh (0.7 mm, rotated) that is not aligned with the cells and overhangs the footprint.
    x = np.arange(-30.0, 30.0, 0.7)
    rotation = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    grid = PressureField.from_grid(x, x, np.zeros((x.size, x.size)))
    positions = grid.positions @ rotation.T
    pressure = 0.05 + 0.001 * positions[:, 0] - 0.002 * positions[:, 1]
    readings = sample(PressureField(positions, grid.triangles, pressure), PAPER_ARRAY)[0]
    nodes = PAPER_ARRAY.node_positions
    expected = (0.05 + 0.001 * nodes[..., 0] - 0.002 * nodes[..., 1]) * PAPER_ARRAY.cell_area
    np.testing.assert_allclose(readings, expected, rtol=1e3 * EPS, atol=1e3 * EPS * 0.05 * PAPER_ARRAY.cell_area)


def test_triangle_orientation_and_frame_stacking_do_not_change_readings():
    field = random_field(seed=1)
    flipped = PressureField(field.positions, field.triangles[:, ::-1], field.pressure)
    one_by_one = np.concatenate([sample(PressureField(field.positions, field.triangles, p), PAPER_ARRAY)
                                 for p in field.frames])
    np.testing.assert_allclose(sample(flipped, PAPER_ARRAY), sample(field, PAPER_ARRAY), rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(one_by_one, sample(field, PAPER_ARRAY), rtol=1e-13, atol=1e-15)


def test_force_outside_the_footprint_is_not_seen():
    x = np.linspace(-40.0, 40.0, 41)
    uniform = PressureField.from_grid(x, x, np.full((41, 41), 0.02))
    readings = sample(uniform, PAPER_ARRAY)[0]
    np.testing.assert_allclose(readings, 0.02 * PAPER_ARRAY.cell_area, rtol=1e3 * EPS)
    assert uniform.total_force()[0] == pytest.approx(0.02 * 80.0**2, rel=1e3 * EPS)


def test_precomputed_operator_gives_the_same_readings():
    field = random_field(seed=2)
    operator = cell_force_operator(field.positions, field.triangles, PAPER_ARRAY)
    np.testing.assert_array_equal(sample(field, PAPER_ARRAY, operator=operator), sample(field, PAPER_ARRAY))


def test_grid_and_function_constructors_agree():
    x, y = np.linspace(-10.0, 10.0, 21), np.linspace(-8.0, 8.0, 17)
    function = lambda X, Y: 0.01 * np.exp(-(X**2 + Y**2) / 8.0)                                    # noqa: E731
    grid_x, grid_y = np.meshgrid(x, y)
    from_grid = PressureField.from_grid(x, y, np.stack([function(grid_x, grid_y)] * 2))
    from_function = PressureField.from_function(function, x, y)
    assert from_grid.frames.shape == (2, 21 * 17) and from_function.frames.shape == (1, 21 * 17)
    np.testing.assert_array_equal(from_grid.frames[1], from_function.pressure)
    # Nodal hat functions on a uniform grid integrate to h^2 (h^2/4 corners, h^2/2 edges): the trapezoidal rule.
    trapezoid = np.trapezoid(np.trapezoid(function(grid_x, grid_y), x, axis=1), y)
    assert from_function.total_force()[0] == pytest.approx(trapezoid, rel=1e3 * EPS)


def test_offset_noise_and_quantization_are_seeded_and_have_their_statistics():
    field = random_field(seed=3, frames=200)
    clean = sample(field, PAPER_ARRAY)
    noisy_array = SensorArray(noise_std=0.01, offset=0.05)
    noisy = sample(field, noisy_array, rng=7)
    np.testing.assert_array_equal(noisy, sample(field, noisy_array, rng=np.random.default_rng(7)))
    error = (noisy - clean - 0.05).ravel()                        # 200 x 143 = 28600 samples
    # 4-sigma bounds of the sample mean (sigma / sqrt(N)) and sample std (sigma / sqrt(2N)).
    assert abs(error.mean()) < 4.0 * 0.01 / np.sqrt(error.size)
    assert abs(error.std() / 0.01 - 1.0) < 4.0 / np.sqrt(2.0 * error.size)
    step = 0.004
    quantized = sample(field, SensorArray(quantization_step=step, offset=0.05))
    np.testing.assert_allclose(quantized / step, np.round(quantized / step), atol=1e-9)
    assert np.max(np.abs(quantized - clean - 0.05)) <= 0.5 * step * (1.0 + 1e-12)


def test_resampling_to_the_sensor_rate():
    times = np.arange(1001) * 1e-3                                # 1 kHz for 1 s; 1.0 is 1000 * 1e-3 with round-off
    values = np.stack([2.0 * times + 1.0, -times], axis=1)        # (T, 2), linear in time
    sample_times, linear = resample_time_series(times, values, 100.0)
    assert sample_times.size == 101 and sample_times[-1] == pytest.approx(1.0)
    np.testing.assert_allclose(linear[:, 0], 2.0 * sample_times + 1.0, rtol=1e-12)
    shifted_times, held = resample_time_series(times, values, 100.0, Interpolation.HOLD, start_time=0.0025)
    assert shifted_times.size == 100
    np.testing.assert_allclose(held[:, 1], -np.floor(shifted_times * 1e3 + 1e-6) * 1e-3, atol=1e-12)


def test_bad_inputs_are_named():
    positions, triangles = np.zeros((3, 2)), np.array([[0, 1, 2]])
    with pytest.raises(ValueError, match="positions must have shape"):
        PressureField(np.zeros((3, 3)), triangles, np.zeros(3))
    with pytest.raises(ValueError, match="triangles index nodes outside"):
        PressureField(positions, np.array([[0, 1, 3]]), np.zeros(3))
    with pytest.raises(ValueError, match="integer array"):
        PressureField(positions, triangles.astype(float), np.zeros(3))
    with pytest.raises(ValueError, match="pressure must have shape"):
        PressureField(positions, triangles, np.zeros(4))
    with pytest.raises(ValueError, match="pressure has 1 value"):
        PressureField(positions, triangles, [0.0, np.nan, 0.0])
    with pytest.raises(ValueError, match="x must be a strictly increasing"):
        PressureField.from_grid([0.0, 0.0, 1.0], [0.0, 1.0], np.zeros((2, 3)))
    with pytest.raises(ValueError, match="grid pressure must have shape"):
        PressureField.from_grid([0.0, 1.0], [0.0, 1.0], np.zeros((3, 2)))
    with pytest.raises(ValueError, match="pitch=0"):
        SensorArray(pitch=0.0)
    with pytest.raises(ValueError, match="node_counts"):
        SensorArray(node_counts=(11, 0))
    with pytest.raises(ValueError, match="noise_std"):
        SensorArray(noise_std=-1.0)
    with pytest.raises(ValueError, match="quantization_step"):
        SensorArray(quantization_step=-0.1)
    with pytest.raises(ValueError, match="sample_rate_hz"):
        SensorArray(sample_rate_hz=0.0)
    with pytest.raises(ValueError, match="operator shape"):
        sample(random_field(), PAPER_ARRAY, operator=cell_force_operator(positions, triangles, PAPER_ARRAY))
    with pytest.raises(ValueError, match="times must be a strictly increasing"):
        resample_time_series([0.0, 0.0], [1.0, 2.0], 100.0)
    with pytest.raises(ValueError, match="values must have 2 samples"):
        resample_time_series([0.0, 1.0], [1.0, 2.0, 3.0], 100.0)
    with pytest.raises(ValueError, match="start_time"):
        resample_time_series([0.0, 1.0], [1.0, 2.0], 100.0, start_time=2.0)
    with pytest.raises(ValueError, match="is not a valid Interpolation"):
        resample_time_series([0.0, 1.0], [1.0, 2.0], 100.0, "cubic")
