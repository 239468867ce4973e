"""Capacitive node model: pads smaller than the cells, the pressure-capacitance curve, crosstalk, noise, converter."""

import dataclasses

import numpy as np
import pytest

from controller.sensing.capacitive import CapacitiveNode
from controller.sensing.sensor import PressureField, SensorArray, capacitive_array, sample

EPS = np.finfo(float).eps
NODE = CapacitiveNode()


def rotated_linear_field(pressure_at, spacing=0.7, angle=0.3, half_width=30.0):
    """A linear pressure field on a rotated 0.7 mm grid overhanging the arrays below: exact for the clipping."""
    x = np.arange(-half_width, half_width, spacing)
    grid = PressureField.from_grid(x, x, np.zeros((x.size, x.size)))
    rotation = np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])
    positions = grid.positions @ rotation.T
    return PressureField(positions, grid.triangles, pressure_at(positions[:, 0], positions[:, 1]))


@pytest.mark.parametrize("fill", [1.0, 0.5, 1.0 / 9.0])
def test_pad_integral_of_a_uniform_pressure_is_the_cell_force_times_the_fill(fill):
    pressure = 0.004                                                    # MPa
    array = SensorArray(pitch=3.0, node_counts=(11, 13), fill_factor=fill)
    readings = sample(rotated_linear_field(lambda x, y: np.full_like(x, pressure)), array)[0]
    # exact clipping of a field linear on each triangle: ~1e3 pieces per pad, each with relative error eps
    np.testing.assert_allclose(readings, pressure * array.cell_area * fill, rtol=1e3 * EPS)


def test_node_model_returns_the_pad_force_of_a_uniform_pressure():
    # nonlinear curve and converter on, noise and crosstalk off: the firmware inverts the nominal curve exactly,
    # so a uniform pressure reads force x fill up to the converter's rounding, half a step in dC per node
    node = dataclasses.replace(NODE, noise_floor=0.0, crosstalk=0.0)
    array = capacitive_array(pitch=3.0, node_counts=(11, 13), node=node)
    pressure = 0.004
    readings = sample(rotated_linear_field(lambda x, y: np.full_like(x, pressure)), array)[0]
    cell_force = pressure * array.cell_area
    slope = node.capacitance_per_area * array.pad_area / node.dielectric_modulus * 1.1    # dC/dp bound near 4 kPa
    half_step = 0.5 * node.adc_step / slope * array.pad_area                              # [N]
    np.testing.assert_allclose(readings, cell_force * array.fill_factor, atol=half_step)


def test_pads_read_their_centre_value_of_a_linear_field():
    array = SensorArray(pitch=3.0, node_counts=(11, 13), fill_factor=0.25)
    field = rotated_linear_field(lambda x, y: 0.05 + 0.001 * x - 0.002 * y)
    nodes = array.node_positions
    expected = (0.05 + 0.001 * nodes[..., 0] - 0.002 * nodes[..., 1]) * array.pad_area
    np.testing.assert_allclose(sample(field, array)[0], expected, rtol=1e3 * EPS)


def test_ideal_node_is_the_pad_integral():
    array = capacitive_array(pitch=1.0, node_counts=(20, 20), node=CapacitiveNode.ideal())
    field = rotated_linear_field(lambda x, y: 0.01 + 1e-4 * x)
    plain = dataclasses.replace(array, node=None)
    # linear curve inverted by the firmware: the pad force back to round-off of a few multiplications
    np.testing.assert_allclose(sample(field, array), sample(field, plain), rtol=1e-12)


def test_curve_is_linear_at_small_pressure_and_saturates():
    area = 4.0
    small = 1e-6                                                        # MPa
    base = NODE.capacitance_per_area * area
    assert NODE.capacitance_change(small, area) == pytest.approx(base * small / NODE.dielectric_modulus, rel=1e-5)
    # eps -> eps_max: dC -> C_0 eps_max / (1 - eps_max)
    limit = base * NODE.max_strain / (1.0 - NODE.max_strain)
    assert NODE.capacitance_change(100.0, area) == pytest.approx(limit, rel=1e-12)
    pressures = np.array([-0.01, 0.0, 0.001, 0.05, 0.2])
    back = NODE.pressure_from_capacitance(NODE.capacitance_change(pressures, area), area)
    np.testing.assert_allclose(back, pressures, rtol=1e-9, atol=1e-15)
    # sensitivity falls with pressure (saturation) though the plate law alone would raise it
    slopes = np.diff(NODE.capacitance_change(np.array([0.0, 0.01, 0.1, 0.11]), area))
    assert slopes[2] / 0.01 < slopes[0] / 0.01


def test_crosstalk_reaches_the_four_neighbours_only():
    node = CapacitiveNode(nonlinear=False, crosstalk=0.03, noise_floor=0.0, adc_bits=0)
    forces = np.zeros((1, 5, 5))
    forces[0, 2, 2] = 0.01
    readings = node.read(forces, 2.0)
    # linear curve: crosstalk adds 3 % of the loaded node's dC to each neighbour, read back as 3 % of its force
    expected = np.zeros((1, 5, 5))
    expected[0, 2, 2] = 0.01
    expected[0, [1, 3, 2, 2], [2, 2, 1, 3]] = 0.03 * 0.01
    np.testing.assert_allclose(readings, expected, atol=1e-15)


def test_noise_floor_as_a_force_matches_the_readings_spread():
    node = CapacitiveNode(nonlinear=False, crosstalk=0.0, adc_bits=0)
    readings = node.read(np.zeros((400, 10, 10)), 1.0, rng=1)
    # 40 000 samples: the sample standard deviation is within 3 / sqrt(2 * 40000) = 1.1 % of the true one
    assert readings.std() == pytest.approx(node.force_noise(), rel=0.011)


def test_converter_rounds_and_saturates():
    node = CapacitiveNode(nonlinear=False, crosstalk=0.0, noise_floor=0.0, adc_bits=8, adc_range=0.1)
    area = 1.0
    pressures = np.array([[[1e-4, 2.2e-3, 1.0]]])                      # the last one beyond the range
    readings = node.read(pressures * area, area)
    change = node.capacitance_change(readings / area, area)
    codes = change / node.adc_step
    np.testing.assert_allclose(codes, np.round(codes), atol=1e-9)
    assert codes.max() == 2**7 - 1                                      # clipped at the converter's top code


@pytest.mark.parametrize("field, value, match", [
    ("max_strain", 1.0, "max_strain=1.0 outside"),
    ("crosstalk", 0.3, "crosstalk=0.3 outside"),
    ("noise_floor", -1e-3, "noise_floor=-0.001 outside"),
    ("adc_bits", 2, "adc_bits=2 must be 0"),
    ("nonlinear", "yes", "nonlinear='yes' must be True or False"),
])
def test_bad_node_parameters_are_refused(field, value, match):
    with pytest.raises(ValueError, match=match):
        dataclasses.replace(NODE, **{field: value})


def test_bad_fill_factor_is_refused():
    with pytest.raises(ValueError, match="fill_factor=0.0 outside"):
        SensorArray(fill_factor=0.0)
    with pytest.raises(ValueError, match="pad_gap=3.0 outside"):
        capacitive_array(pitch=3.0, pad_gap=3.0)
