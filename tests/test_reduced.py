"""Reduced array-fingertip model (contact.reduced) against the closed-form theory it is built from (contact.theory).

With an untilted flat object every bump carries P / k, so each per-bump law must reproduce its single-contact
formula exactly (to the solver tolerance), and the array laws follow from statics alone.
"""

import dataclasses
import json
import math

import numpy as np
import pytest

from contact.reduced import (ArrayFingertipDesign, BaseGrid, ReducedFingertip, ReducedParameters, SlipMode,
                             bump_response, normal_split)
from contact.theory import effective_modulus, hertz, lubkin_twist, mindlin_shift, shear_modulus
from controller.sensing.sensor import PressureField

DESIGN = ArrayFingertipDesign()
TIP = ReducedFingertip(DESIGN)
SINGLE = ReducedFingertip(ArrayFingertipDesign(rows=1, cols=1))
E_STAR = effective_modulus(DESIGN.youngs_modulus, DESIGN.poissons_ratio)
G = shear_modulus(DESIGN.youngs_modulus, DESIGN.poissons_ratio)
MU, P = 0.8, 4.5
# load_state converges to 1e-10 mu P in the residual; the Lubkin table interpolates to 1e-4 (_bumps).
SOLVER = 1e-8
TABLE = 1e-4


def test_bump_contact_radius_is_hertz():
    state = TIP.load_state(P, (0.0, 0.0), 0.0, MU)
    assert state.normal_force == pytest.approx(np.full(9, P / 9), rel=1e-14)
    expected = hertz(P / 9, DESIGN.bump_radius, E_STAR).contact_radius
    assert state.contact_radius == pytest.approx(np.full(9, expected), rel=1e-12)


@pytest.mark.parametrize("load_ratio", [0.2, 0.6, 0.9])
def test_translation_is_mindlin_shift_of_each_bump(load_ratio):
    q = load_ratio * MU * P
    state = TIP.load_state(P, (q * 0.6, q * 0.8), 0.0, MU)
    a = hertz(P / 9, DESIGN.bump_radius, E_STAR).contact_radius
    expected = mindlin_shift(q / 9, P / 9, MU, a, G, DESIGN.poissons_ratio)
    assert np.linalg.norm(state.translation) == pytest.approx(expected, rel=SOLVER)
    assert state.rotation == pytest.approx(0.0, abs=1e-12)
    assert state.stick_ratio_translational == pytest.approx(np.full(9, (1 - load_ratio) ** (1 / 3)), rel=SOLVER)
    assert not state.gross_slip and state.slip_mode == SlipMode.NONE


def test_gross_slip_at_mu_p():
    bump_force = np.full(9, P / 9)
    radius = TIP.parameters.radius_coefficient * np.cbrt(bump_force)
    margin, mode = TIP.slip_margin(bump_force, radius, MU, (MU * P, 0.0), 0.0)
    assert margin == pytest.approx(1.0, rel=1e-6)           # Nelder-Mead on the twist sphere, 1e-8 in angle
    assert mode == SlipMode.TRANSLATION
    assert not TIP.load_state(P, (0.99 * MU * P, 0.0), 0.0, MU).gross_slip
    beyond = TIP.load_state(P, (1.01 * MU * P, 0.0), 0.0, MU)
    assert beyond.gross_slip and beyond.slip_mode == SlipMode.TRANSLATION


def test_single_bump_twist_is_lubkin():
    torque = 0.4 * MU * P * hertz(P, DESIGN.bump_radius, E_STAR).contact_radius
    state = SINGLE.load_state(P, (0.0, 0.0), torque, MU)
    a = float(state.contact_radius[0])
    assert state.rotation == pytest.approx(lubkin_twist(torque, P, MU, a, G), rel=TABLE)
    assert SINGLE.load_state(P, (0.0, 0.0), 1.01 * 3 * math.pi / 16 * MU * P * a, MU).gross_slip


def test_array_torque_limit_is_bumps_friction_about_the_centre():
    # pure torque: every bump slides around the centre, mu P_i |r_i| plus the bumps' own spin limit in quadrature
    bump_force = np.full(9, P / 9)
    radius = TIP.parameters.radius_coefficient * np.cbrt(bump_force)
    lever = np.linalg.norm(TIP.centres, axis=1)
    spin = 3 * math.pi / 16 * MU * bump_force * radius
    limit = np.sum(np.hypot(MU * bump_force * lever, spin))
    margin, mode = TIP.slip_margin(bump_force, radius, MU, (0.0, 0.0), limit)
    assert margin == pytest.approx(1.0, rel=1e-6) and mode == SlipMode.ROTATION
    # combined: with a tangential load the array carries less torque
    with_load = TIP.slip_margin(bump_force, radius, MU, (0.5 * MU * P, 0.0), limit)[0]
    assert with_load < margin


@pytest.mark.parametrize("tangential, torque", [((0.5, 0.0), 0.0), ((0.0, 0.3), 25.0), ((0.0, 0.0), 40.0)])
def test_minimum_normal_force_is_where_the_margin_crosses_one(tangential, torque):
    # the force found carries the load and 1e-4 less does not (the tolerance asked for), whatever the mode
    tolerance = 1e-4
    force = TIP.minimum_normal_force(tangential, torque, MU, tolerance=tolerance)

    def margin(total):
        bump_force = np.full(9, total / 9)
        radius = TIP.parameters.radius_coefficient * np.cbrt(bump_force)
        return TIP.slip_margin(bump_force, radius, MU, tangential, torque)[0]

    assert margin(force) >= 1.0 > margin(force * (1.0 - 2 * tolerance))


@pytest.mark.parametrize("anisotropy", [0.1, -0.2])
def test_an_anisotropic_surface_carries_a_translation_at_the_friction_along_it(anisotropy):
    # friction mu (1 + e) along x and mu (1 - e) along y (the plant's elliptic limit): a pure translation along an
    # axis is the isotropic limit at that axis's friction, exactly (every bump slides along it; 1e-4 is the
    # search's tolerance); a twist of the array slides its bumps every way, so its limit lies between the two
    tolerance = 1e-4
    along_y = TIP.minimum_normal_force((0.0, 0.5), 0.0, MU, tolerance=tolerance, anisotropy=anisotropy)
    along_x = TIP.minimum_normal_force((0.5, 0.0), 0.0, MU, tolerance=tolerance, anisotropy=anisotropy)
    assert along_y == pytest.approx(TIP.minimum_normal_force((0.0, 0.5), 0.0, MU * (1 - anisotropy)), rel=2e-4)
    assert along_x == pytest.approx(TIP.minimum_normal_force((0.5, 0.0), 0.0, MU * (1 + anisotropy)), rel=2e-4)
    twisted = TIP.minimum_normal_force((0.0, 0.0), 40.0, MU, anisotropy=anisotropy)
    low, high = sorted(TIP.minimum_normal_force((0.0, 0.0), 40.0, MU * (1 + sign * anisotropy)) for sign in (1, -1))
    assert low < twisted < high


def test_base_pressure_carries_the_normal_force():
    state = TIP.load_state(P, (1.0, 0.5), 20.0, MU, tilt=(0.01, -0.005))
    grid = TIP.base_grid()
    field = PressureField.from_grid(grid.x, grid.y, TIP.state_pressure(grid, state))
    # the kernels stay off the grid border: exact up to round-off of ~1e4 nodes
    assert field.total_force()[0] == pytest.approx(P, rel=1e-12)
    assert state.normal_force.sum() == pytest.approx(P, rel=1e-12)


def test_pressure_centre_moves_by_the_couple_over_the_force():
    # one centred bump: its mirrored bell is symmetric about the origin, so the centre of the whole base pressure is
    # M / P = (h(P) Q + g P delta) / P, exactly (force and first moment are normalised on the grid)
    one = ReducedFingertip(ArrayFingertipDesign(rows=1, cols=1))
    grid = one.base_grid(0.25)
    force, shift, tangential = np.array([1.0]), np.array([[0.1, -0.05]]), np.array([[0.3, 0.2]])
    pressure = one.base_pressure(grid, force, np.array([1.5]), shift, tangential)
    centre = (pressure.ravel() @ grid.points) / pressure.sum()
    p = one.parameters
    expected = p.displacement_gain * shift[0] + p.couple_arm_at(1.0) * tangential[0]
    assert p.couple_arm_at(1.0) == pytest.approx(DESIGN.bump_radius + DESIGN.base_thickness)   # closed form: H
    assert centre == pytest.approx(expected, abs=1e-12)


def test_base_pressure_carries_each_couple_exactly():
    # 3 x 3 with different loads per bump: total force sum P_i and the first moment of the couples sum M_i, to
    # round-off of ~2e3 grid nodes; nothing outside the base layer, whose edges are mirrors of the kernel
    rng = np.random.default_rng(7)
    force = rng.uniform(0.2, 1.0, 9)
    tangential = rng.uniform(-0.4, 0.4, (9, 2)) * force[:, None]
    shift = rng.uniform(-0.2, 0.2, (9, 2))
    tip = ReducedFingertip(DESIGN, ReducedParameters.from_design(DESIGN))
    grid = tip.base_grid(0.5)
    with_couple = tip.base_pressure(grid, force, np.ones(9), shift, tangential)
    bells = tip.base_pressure(grid, force, np.ones(9), np.zeros((9, 2)), np.zeros((9, 2)))
    area = grid.spacing**2
    assert with_couple.sum() * area == pytest.approx(force.sum(), rel=1e-12)
    assert bells.sum() * area == pytest.approx(force.sum(), rel=1e-12)
    moment = ((with_couple - bells).ravel() * area) @ grid.points
    assert moment == pytest.approx(tip.couple(force, shift, tangential).sum(axis=0), rel=1e-12)
    half_x, half_y = DESIGN.footprint
    outside = (np.abs(grid.points[:, 0]) > half_x) | (np.abs(grid.points[:, 1]) > half_y)
    assert np.all(with_couple.ravel()[outside] == 0.0)


def test_base_pressure_is_linear_in_the_loads():
    # superposition, the premise of the model (the gel is linear): two load sets add. The arm h(P_i) is taken
    # constant and g = 0 here: h(P_i) Q_i and g P_i delta_i are products of loads, not linear in them.
    parameters = dataclasses.replace(TIP.parameters, couple_arm_slope=0.0, displacement_gain=0.0)
    tip = ReducedFingertip(DESIGN, parameters)
    grid = tip.base_grid(1.0)
    first = (np.full(9, 0.5), np.full((9, 2), 0.1), np.tile([0.2, 0.0], (9, 1)))
    second = (np.linspace(0.1, 0.9, 9), np.full((9, 2), -0.05), np.tile([0.0, 0.3], (9, 1)))
    fields = [tip.base_pressure(grid, force, np.ones(9), shift, load) for force, shift, load in (first, second)]
    both = tip.base_pressure(grid, *[a + b for a, b in zip(first[:1], second[:1])], np.ones(9),
                             first[1] + second[1], first[2] + second[2])
    # round-off of a sum over 27 separable terms
    assert both == pytest.approx(fields[0] + fields[1], abs=1e-14 * np.abs(both).max())


def test_couple_arm_law():
    p = dataclasses.replace(TIP.parameters, couple_arm=7.5, couple_arm_slope=2.0, couple_arm_limit=3.8)
    assert p.couple_arm_at(0.0) == pytest.approx(7.5)
    step = 1e-6
    slope = (p.couple_arm_at(step) - p.couple_arm_at(0.0)) / step
    assert slope == pytest.approx(-2.0, rel=1e-5)            # forward difference: O(step kappa / excess)
    assert p.couple_arm_at(1e9) == pytest.approx(3.8, rel=1e-6)
    assert np.all(np.diff(p.couple_arm_at(np.linspace(0.0, 20.0, 50))) < 0.0)


@pytest.mark.parametrize("change, match", [
    (dict(couple_arm_slope=1.0, couple_arm_limit=8.0), r"couple_arm_limit=8.0 outside allowed range"),
    (dict(couple_arm_slope=-0.1), r"couple_arm_slope=-0.1 outside allowed range"),
    (dict(displacement_gain=3.0), r"displacement_gain=3.0 outside allowed range"),
    (dict(kernel_width=0.0), r"kernel_width=0.0"),
])
def test_invalid_pressure_parameters_raise(change, match):
    with pytest.raises(ValueError, match=match):
        dataclasses.replace(TIP.parameters, **change)


@pytest.mark.parametrize("grid, loads, match", [
    (BaseGrid(np.linspace(-15.0, 15.0, 31), np.linspace(-25.0, 25.0, 51)), {}, r"grid\.x spans \[-15, 15\] mm"),
    (None, dict(bump_force=np.ones(8)), r"bump_force has shape \(8,\), expected \(9,\)"),
    (None, dict(tangential_force=np.ones(9)), r"tangential_force has shape \(9,\), expected \(9, 2\)"),
    (None, dict(bump_force=np.full(9, np.nan)), r"non-finite loads"),
])
def test_base_pressure_refuses_bad_input(grid, loads, match):
    arguments = dict(bump_force=np.ones(9), contact_radius=np.ones(9), shear_displacement=np.zeros((9, 2)),
                     tangential_force=np.zeros((9, 2)))
    arguments.update(loads)
    with pytest.raises(ValueError, match=match):
        TIP.base_pressure(grid or TIP.base_grid(1.0), **arguments)


def test_tilt_splits_the_normal_force_by_hertz():
    forces = normal_split(P, TIP.centres, TIP.parameters, tilt=(0.02, 0.0))
    assert forces.sum() == pytest.approx(P, rel=1e-12)
    depth = (forces / TIP.parameters.normal_stiffness) ** (2 / 3)
    touching = forces > 0
    slope = np.polyfit(TIP.centres[touching, 0], depth[touching], 1)[0]
    assert slope == pytest.approx(0.02, rel=1e-9)


def test_unloaded_bump_carries_nothing():
    response = bump_response(np.array([0.0, 1.0]), np.array([[0.1, 0.0], [0.0, 0.0]]), np.array([0.01, 0.0]), MU,
                             TIP.parameters)
    assert np.all(response.tangential_force[0] == 0.0) and response.torque[0] == 0.0
    assert not response.sliding.any()


def test_parameters_round_trip_through_json():
    data = json.loads(json.dumps(TIP.to_dict()))
    again = ReducedFingertip.from_dict(data)
    assert again.parameters == TIP.parameters and again.design == TIP.design
    assert TIP.parameters.source == "closed_form"
    with pytest.raises(ValueError, match="unknown ReducedParameters keys"):
        ReducedParameters.from_dict({**data["parameters"], "bump_count": 9})


@pytest.mark.parametrize("field, value, match", [
    ("pitch", 5.0, "pitch=5.0 outside"),
    ("poissons_ratio", 0.5, "poissons_ratio=0.5 outside"),
    ("rows", 0, r"rows=0 outside allowed range \[1, 12\]"),
    # a bool and a whole float used to pass (int(True) == True, int(3.0) == 3.0) and be kept as they came
    ("rows", True, r"rows=True \(a bool\) is not an integer"),
    ("cols", 3.0, r"cols=3.0 is not an integer \(allowed: 1 to 12\)"),
])
def test_invalid_design_raises(field, value, match):
    with pytest.raises(ValueError, match=match):
        ArrayFingertipDesign(**{field: value})


def test_a_design_counted_in_numpy_integers_is_stored_as_python_ints():
    # a sweep's grid hands numpy integers; the design's record is JSON
    design = ArrayFingertipDesign(rows=np.int64(3), cols=np.int32(4))
    assert type(design.rows) is int and type(design.cols) is int
    assert json.loads(json.dumps(dataclasses.asdict(design)))["cols"] == 4


@pytest.mark.parametrize("anisotropy", [1.0, -1.5, math.nan])
def test_the_slip_limit_refuses_an_anisotropy_outside_the_open_unit_interval(anisotropy):
    with pytest.raises(ValueError, match=r"anisotropy=.* outside allowed range \(-1.0, 1.0\)"):
        TIP.minimum_normal_force((0.0, 0.5), 0.0, MU, anisotropy=anisotropy)
