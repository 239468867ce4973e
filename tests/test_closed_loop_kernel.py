"""The compiled closed loop (controller.closed_loop): its pieces against the library code they replace, its physics
against the recorded explicit 4 kHz loop, its implicit coupling against an explicit one, and its input checks."""

import json
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from controller import AccelerationController, AccelerationControlParameters
from controller.closed_loop import (ROTATION_LIMIT, TABLE_I_OBJECTS, ControllerKind, GraspObject, SensingChain,
                                    TargetDesign, TrialSettings)
from controller.closed_loop._bench import estimator_bench
from controller.closed_loop import _kernel as K
from controller.estimation.estimator import BumpReference, bump_positions, estimate_slip
from controller.control.filters import FirstOrderLowPass
from controller.plant import FingertipPlant, SensorPlane
from controller.sensing import SensorArray, cell_force_operator
from controller.sensing.sensor import PressureField, sample

REFERENCE = json.loads((Path(__file__).parent / "data" / "closed_loop_reference.json").read_text())
ROUND_OFF = 1e-12                        # relative: the compiled code sums in another order


def test_compiled_acceleration_control_is_the_controller_class():
    parameters = AccelerationControlParameters(torque_limit=400.0)
    reference = AccelerationController(parameters)
    config = np.zeros(K.C_SIZE)
    config[[K.C_ARM_RADIUS, K.C_NOMINAL_INERTIA, K.C_TARGET_INERTIA, K.C_TARGET_DAMPING, K.C_TORQUE_LIMIT]] = (
        parameters.arm_radius, parameters.nominal_inertia, parameters.target_inertia, parameters.target_damping,
        parameters.torque_limit)
    config[K.C_DOB_GAIN] = FirstOrderLowPass(parameters.dob_cutoff_hz, parameters.sample_rate_hz)._gain
    config[K.C_USE_DOB] = 1.0
    state = np.zeros(K.S_SIZE)
    rng = np.random.default_rng(3)
    angle, saturated = 0.0, 0
    for _ in range(3000):
        command, force = rng.uniform(0.0, 20.0), rng.uniform(0.0, 20.0)
        angle += rng.normal(0.0, 1e-3)
        expected = reference.step(command, force, angle)
        torque = K.acceleration_step(state, config, command, force, angle, 1.0 / parameters.sample_rate_hz)
        assert torque == pytest.approx(expected, rel=ROUND_OFF, abs=ROUND_OFF * parameters.torque_limit)
        saturated += abs(expected) == parameters.torque_limit
    assert saturated > 100                                        # the clipped branch was exercised too


@pytest.fixture(scope="module")
def known():
    """The known world: the plant's sensor plane is the estimator's own model, read by ideal cells."""
    plant = FingertipPlant(noise=0.0, plane=SensorPlane.MODEL)
    return plant, SensingChain(estimator_bench(SensorPlane.MODEL))


def _states(tip, rng, count):
    """Random array states (k, 4) and their ContactStates: total force, load ratio along x and y and a torque (all
    below the slip limit)."""
    for _ in range(count):
        total = rng.uniform(0.5, 25.0)
        load = rng.uniform(-0.4, 0.4, 2) * total
        state = tip.load_state(total, load, rng.uniform(-15.0, 15.0), 1.0)
        yield state, np.column_stack([state.normal_force, state.bump_tangential_force, state.bump_torque])


def test_model_plane_is_the_reduced_models_base_pressure_sampled_by_the_sensor(known):
    """The known world's plant reads what sampling the reduced model's base pressure with the paper's cells reads."""
    plant, _ = known
    tip = plant.mechanics
    grid = tip.base_grid(1.0)
    for state, states in _states(tip, np.random.default_rng(1), 8):
        pressure = tip.state_pressure(grid, state)
        field = PressureField.from_grid(grid.x, grid.y, pressure)
        expected = sample(field, SensorArray())[0]
        readings = plant.frame_readings(np.stack([states, states]), 0.0, np.zeros((2,) + plant.array.shape))[0]
        # the couple arm h(P) is tabulated in log P (81 levels from 1 mN to 100 N): linear interpolation of its
        # smooth hyperbola leaves < 1e-4 of it
        np.testing.assert_allclose(readings, expected, rtol=0, atol=1e-4 * np.abs(expected).max())


def test_fem_plane_pad_forces_are_the_base_response_through_the_pads():
    """The compiled plant kernel's pad forces equal the FEM base response (``BaseResponse.pressure``, numpy)
    integrated over the pads by the sensor's own operator."""
    from contact.reduced.base_response import BaseResponse

    plant = FingertipPlant(noise=0.0)
    response = BaseResponse.load()
    operator = cell_force_operator(response.positions, response.triangles, plant.array)
    for _, states in _states(plant.mechanics, np.random.default_rng(5), 5):
        expected = operator @ response.pressure(states)
        pads = plant.pad_forces(states)[0].ravel()
        np.testing.assert_allclose(pads, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_sensor_frame_is_the_library_estimator(known):
    """u_x, theta and the contact count of a frame equal bump_positions -> reference -> estimate_slip."""
    plant, chain = known
    tip = plant.mechanics
    table_force, table_cop = chain.reference_table
    rng = np.random.default_rng(2)
    noise = np.random.default_rng(7).normal(0.0, 0.001, (2,) + chain.array.shape)
    for (left, left_states), (right, right_states) in zip(_states(tip, rng, 6), _states(tip, rng, 6)):
        readings = plant.frame_readings(np.stack([left_states, right_states]), 0.0,
                                        np.zeros((2,) + plant.array.shape)) + noise
        frame = chain.sense(readings.reshape(2, -1))
        u_x = theta = 0.0
        for f in range(2):
            force = bump_positions(readings[f], chain.array, chain.layout, chain.settings)[0][0]
            position = np.interp(np.log(np.maximum(force, table_force[0])), np.log(table_force),
                                 np.arange(len(table_force)))
            lower = np.minimum(position.astype(int), len(table_force) - 2)
            weight = (position - lower)[:, None]
            cop = (1 - weight) * table_cop[lower, np.arange(9)] + weight * table_cop[lower + 1, np.arange(9)]
            estimate = estimate_slip(readings[f], chain.array, chain.layout, BumpReference(cop, cop, force > 0),
                                     chain.calibration, chain.settings)
            np.testing.assert_allclose(frame.bump_force[f], force, rtol=ROUND_OFF, atol=ROUND_OFF)
            assert frame.in_contact[f].tolist() == estimate.in_contact[0].tolist()
            if estimate.transform.valid[0]:
                u_x = max(u_x, float(np.linalg.norm(estimate.transform.translation[0])))
                theta = max(theta, abs(float(estimate.transform.rotation[0])))
        assert frame.shear_displacement == pytest.approx(u_x, abs=1e-12)
        assert frame.twist_angle == pytest.approx(theta, abs=1e-12)


@pytest.mark.parametrize("total, load, torque", [(3.0, (0.0, 0.5), 0.0), (8.0, (0.6, 0.0), 0.0),
                                                 (15.0, (0.0, 0.0), 40.0), (4.0, (0.3, -0.3), 8.0),
                                                 (1.0, (-0.4, 0.2), -3.0)])
def test_known_world_reads_back_the_bump_loads_along_both_axes_and_under_twist(known, total, load, torque):
    """In the known world the estimator's model is the plant's sensor: noise-free, A^+ r gives the bump forces
    and the load ratios Q_i / P_i to round-off (the calibrated displacement gain is 0), along x, along y, under a
    twist and combined; the compiled frame equals the numpy path."""
    plant, chain = known
    state = plant.mechanics.load_state(total, np.asarray(load) * total, torque, 1.0)
    states = np.column_stack([state.normal_force, state.bump_tangential_force, state.bump_torque])
    readings = plant.frame_readings(np.stack([states, states]), 0.0, np.zeros((2,) + plant.array.shape))
    frame = chain.sense(readings.reshape(2, -1))
    # the couple arm's log-P table (see above) bounds the readings to 1e-4; its effect on the loads is the same
    scale = 1e-4
    np.testing.assert_allclose(frame.normal_force[0], state.normal_force, rtol=scale, atol=scale)
    truth = state.bump_tangential_force / state.normal_force[:, None]
    np.testing.assert_allclose(frame.load_ratio[0], truth, rtol=0, atol=scale)
    normal, ratio, _ = chain.bump_loads(readings[0].ravel())
    np.testing.assert_allclose(frame.load_ratio[0], ratio[0], rtol=1e-9, atol=1e-12)


mujoco = pytest.importorskip("mujoco")


def _settings(record, **changes):
    """The recorded trial's settings for the displacement-target law (the controller the explicit loop ran)."""
    values = dict(record["settings"])
    values["friction_coefficient"] = values.pop("friction")
    values["grasp_offset"] = tuple(values["grasp_offset"])
    targets = dict(values["targets"])
    targets["friction_coefficient"] = targets.pop("friction")
    values["targets"] = TargetDesign(**targets)
    # the recorded loop ran in the known world (the estimator's model as the sensor plane) with a force sensor
    return replace(TrialSettings(**values, controller=ControllerKind.DISPLACEMENT_TARGETS,
                                 sensor_plane=SensorPlane.MODEL, force_feedback="sensor"), **changes)


def _check_against_reference(record, result):
    # tolerances measured on the recorded set at the default 500 Hz (1 kHz within the same bounds): the hold force of
    # the bottles within 3.3 % (bottle_horizontal_1 settles on another step of its integrator); the light eclair
    # within 12 %, because the explicit loop is not converged there: at the same 8 kHz the fast loop, implicit or
    # explicit, holds eclair_2 at 5.87 N where it held 6.37 N, and doubling its rates moved it to 7.45 N; the fast
    # loop itself moves 4 % from 500 Hz to 8 kHz. Rotations within 3.2 mrad while held, 1.6 mrad in the hold; a
    # rotation verdict only where the record is clear of the 150 mrad limit by the rotation tolerance
    # the record's "success" is the paper's (neither dropped nor crushed); a turn out of the grasp is judged apart
    assert (not result.dropped and not result.crushed) == record["success"] and result.crushed == record["crushed"]
    if abs(record["max_rotation_mrad"] - 1e3 * ROTATION_LIMIT) > 5.0:
        assert result.rotated == record["rotated"]
    if not record["rotated"]:
        assert result.max_rotation_mrad == pytest.approx(record["max_rotation_mrad"], abs=5.0)
    tolerance = 0.12 if record["object"] == "eclair" else 0.04
    assert result.hold_force_mean == pytest.approx(record["hold_force_mean"], rel=tolerance)
    assert abs(result.hold_rotation_mrad - record["hold_rotation_mrad"]) < 2.0


@pytest.mark.parametrize("case", [r["case"] for r in REFERENCE["records"]])
def test_fast_loop_reproduces_the_recorded_explicit_loop(case):
    from controller.closed_loop import run_trial

    record = next(r for r in REFERENCE["records"] if r["case"] == case)
    _check_against_reference(record, run_trial(TABLE_I_OBJECTS[record["object"]], _settings(record)))


DIVERGED_FORCE = 5.0          # x the command: a stable contact stays near it (implicit: within 1 %)


def _explicit_diverges(box, settings) -> bool:
    """Whether a trial blows up: the world stops it because MuJoCo reset the simulation (its bad-acceleration
    warning, which MuJoCo 3 gave here), or the finger force runs past DIVERGED_FORCE times the command (MuJoCo 4
    integrates on: 19x at 2 ms)."""
    from controller.closed_loop import run_trial

    try:
        trial = run_trial(box, settings)
    except RuntimeError as error:
        if "reset the simulation" not in str(error):
            raise
        return True
    return trial.max_force > DIVERGED_FORCE * settings.constant_force


def test_implicit_coupling_holds_a_light_object_still_where_the_explicit_one_fails():
    """A 104 g box squeezed at 12 N per finger: the contact's damping alone gives c h / m ~ 2 at 1 ms, where
    explicit damping diverges. Coupled implicitly the box sits still at 2 ms and 1 ms steps and the finger force is
    the command; coupled explicitly it rattles between the fingers at 1 ms (the force peaks at over 1.5 times the
    command) and diverges at the default 2 ms, whatever the MuJoCo version does about it."""
    from controller.closed_loop import run_trial

    box = GraspObject("light_box", 0.104, (0.14, 0.03, 0.03), 0.0382, 0.015)
    settings = TrialSettings(friction_coefficient=0.8, constant_force=12.0, hold_time=0.5, place=False)
    for rate in (500.0, 1000.0):
        implicit = run_trial(box, replace(settings, physics_rate_hz=rate))
        assert implicit.success and implicit.hold_rotation_mrad < 0.1 and implicit.hold_slip_mm < 1e-3
        assert implicit.max_force == pytest.approx(12.0, rel=0.01)
    explicit = run_trial(box, replace(settings, physics_rate_hz=1000.0, implicit_coupling=False))
    assert 1.5 * 12.0 < explicit.max_force < DIVERGED_FORCE * 12.0              # rattles, does not diverge
    assert _explicit_diverges(box, replace(settings, physics_rate_hz=500.0, implicit_coupling=False))


@pytest.mark.parametrize("changes, match", [
    (dict(physics_rate_hz=3000.0), "actuator_rate_hz=8000.0 must be an integer multiple"),
    (dict(actuator_rate_hz=750.0), "actuator_rate_hz=750.0 must be an integer multiple"),
    (dict(physics_rate_hz=-1.0), "physics_rate_hz=-1.0 outside"),
    (dict(friction_coefficient=0.0), "friction_coefficient=0.0 outside"),
    (dict(sensor_noise=-0.001), "sensor_noise=-0.001 outside"),
    (dict(hold_time=math.nan), "hold_time=nan outside"),
    (dict(constant_force=-2.0), "constant_force=-2.0 outside"),
    (dict(place="no"), "place='no' must be True or False"),
    (dict(swing_margin=-3.0), "swing_margin=-3.0 outside"),
])
def test_bad_trial_settings_name_the_setting(changes, match):
    with pytest.raises(ValueError, match=match):
        TrialSettings(**changes)


@pytest.mark.parametrize("rate, match", [
    (250.0, "physics_rate_hz=250.0 Hz must be an integer multiple of the sensor rate 100.0 Hz"),
    (400.0, "physics_rate_hz=400.0 and the grasp-force loop rate 1000.0 Hz must be integer multiples of one another"),
])
def test_physics_rate_must_fit_the_sensor_and_control_rates(rate, match):
    from controller.closed_loop import GraspWorld

    with pytest.raises(ValueError, match=match):
        GraspWorld(TABLE_I_OBJECTS["eclair"], TrialSettings(physics_rate_hz=rate))


@pytest.mark.parametrize("changes, match", [
    (dict(mass=-0.1), "box.mass=-0.1 outside"),
    (dict(size=(0.1, 0.05)), "box.size=.* must be three lengths"),
    (dict(size=(0.1, 0.0, 0.1)), "box.size.y=0.0 outside"),
    (dict(lever=0.2), "box.lever=0.2 outside"),
    (dict(grasp_height=0.3), "box.grasp_height=0.3 outside"),
    (dict(crush_force=0.0), "box.crush_force=0.0 outside"),
])
def test_bad_objects_name_the_field(changes, match):
    values = dict(name="box", mass=0.2, size=(0.1, 0.05, 0.1), lever=0.0, grasp_height=0.05)
    with pytest.raises(ValueError, match=match):
        GraspObject(**{**values, **changes})


@pytest.mark.parametrize("touching", [False, True])
@pytest.mark.parametrize("closing", [1.0, 3.0, 4.6, 4.8, 6.0])
def test_a_bump_entering_deeper_than_its_radius_carries_no_force(closing, touching):
    # one finger's bump closing on a face: Hertz's k d^1.5 while the tip is within the bump's radius; a tip found
    # deeper on its first touch met the object edge-on (it slid out) and the bump law says nothing - no force, no
    # depth; a contact that was touching at the last step keeps its law however deep it went
    radius, stiffness = 4.67, 0.8
    config = np.zeros(K.C_SIZE)
    config[[K.C_NORMAL_STIFFNESS, K.C_MAX_DEPTH]] = stiffness, radius
    config[[K.C_HALF_X, K.C_HALF_Y, K.C_HALF_Z, K.C_FINGER_OFFSET]] = 20.0, 20.0, 20.0, 20.0
    geometry = np.zeros((2, K.G_SIZE))
    geometry[:, K.G_FACE] = 1.0, -1.0                      # left and right finger, each facing the object
    bumps, forces, fixed = np.zeros((2, K.B_SIZE)), np.zeros(2), np.zeros((2, 8))
    bumps[:, K.B_TOUCHING] = float(touching)
    arm, position, rotation, zero = np.zeros(3), np.zeros(3), np.eye(3), np.zeros(3)
    K._fixed_offsets(geometry, arm, position, rotation, fixed)
    K._normal_forces(config, geometry, bumps, arm, closing, 0.0, position, rotation, zero, zero, forces, fixed)
    law = closing <= radius or touching
    expected = stiffness * closing ** 1.5 if law else 0.0
    assert forces == pytest.approx([expected, expected], rel=1e-12, abs=1e-15)
    assert bumps[:, K.B_DEPTH] == pytest.approx([closing, closing] if law else [0.0, 0.0])
