"""Reduced array-fingertip model (contact.reduced) against the closed-form theory it is built from (contact.theory).

With an untilted flat object every bump carries P / k, so each per-bump law must reproduce its single-contact
formula exactly (to the solver tolerance), and the array laws follow from statics alone.
"""

import json
import math

import numpy as np
import pytest

from contact.reduced import (ArrayFingertipDesign, ReducedFingertip, ReducedParameters, SlipMode, bump_response,
                             normal_split)
from contact.theory import effective_modulus, hertz, lubkin_twist, mindlin_shift, shear_modulus
from controller.sensor import PressureField

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


def test_base_pressure_carries_the_normal_force():
    state = TIP.load_state(P, (1.0, 0.5), 20.0, MU, tilt=(0.01, -0.005))
    grid = TIP.base_grid()
    field = PressureField.from_grid(grid.x, grid.y, TIP.state_pressure(grid, state))
    # the kernels stay off the grid border: exact up to round-off of ~1e4 nodes
    assert field.total_force()[0] == pytest.approx(P, rel=1e-12)
    assert state.normal_force.sum() == pytest.approx(P, rel=1e-12)


def test_pressure_centre_moves_with_shear_and_load_ratio():
    grid = TIP.base_grid(0.25)
    force, radius = np.array([1.0]), np.array([1.5])
    one = ReducedFingertip(ArrayFingertipDesign(rows=1, cols=1))
    shift, tangential = np.array([[0.1, 0.0]]), np.array([[0.3, 0.0]])
    pressure = one.base_pressure(grid, force, radius, shift, tangential)
    centre = (pressure.sum(axis=0) @ grid.x) / pressure.sum()
    expected = one.parameters.cop_gain * 0.1 + one.parameters.moment_arm * 0.3
    # nodal centroid of the paraboloid (a kink at its rim) sampled at h = 0.25 mm off its centre: O(h^2 / w) ~ 1e-4
    assert centre == pytest.approx(expected, abs=1e-3)


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
    ("rows", 0, "rows=0 must be an integer"),
])
def test_invalid_design_raises(field, value, match):
    with pytest.raises(ValueError, match=match):
        ArrayFingertipDesign(**{field: value})
