"""Acceleration Control block with disturbance observer (8 kHz) on the actuator plant model.

Loop design (defaults): contact stiffness k_c = 10 N/mm at arm radius r = 50 mm, I_a = 0.7 N mm s^2 and
D_a = 264 N mm s/rad (target impedance w_n = r sqrt(k_c / I_a) = 189 rad/s, zeta = 1), J_n = 0.1 N mm s^2,
DOB cut-off 200 Hz. The DOB also sees the load torque r F, whose residual (1 - Q) r F adds damping, so the
slowest closed-loop mode is slower than w_n; it is read off the discrete linearised loop (``_slowest_rate``).
"""

import math

import numpy as np
import pytest

from controller import AccelerationControlParameters, AccelerationController, ActuatorParameters, ActuatorPlant

DESIGN = AccelerationControlParameters()
RATE = DESIGN.sample_rate_hz
FORCE_PER_ANGLE = 10.0 * 50.0                      # k_c r [N/rad]
SETTLE = 0.1                                        # s: time before the step (start-up transient of the DOB)


def _pack(plant, controller):
    o = controller.observer
    return np.array([plant.angle, plant.velocity, *o.angles, *o.torques,
                     float(o.filter.previous_input), float(o.filter.output)])


def _unpack(state, plant, controller):
    o = controller.observer
    plant.angle, plant.velocity = state[0], state[1]
    o.angles, o.torques = state[2:4].copy(), state[4:6].copy()
    o.filter.previous_input, o.filter.output = np.array(state[6]), np.array(state[7])


def closed_loop_matrix(inertia_ratio, force=2.0):
    """State matrix A of the discrete closed loop (plant J = ratio * J_n) about rest at ``force`` [N].

    Without Coulomb friction and saturation, and in contact, one period is an affine map of the state
    (plant angle and velocity, DOB history and filter state), so finite differences give A exactly up to rounding.
    """
    plant = ActuatorPlant(ActuatorParameters(inertia=inertia_ratio * DESIGN.nominal_inertia, torque_limit=1e12))
    controller = AccelerationController(DESIGN)

    def period(state):
        _unpack(state, plant, controller)
        plant.step(controller.step(force, plant.contact_force, plant.angle), 1.0 / RATE)
        return _pack(plant, controller)

    rest = np.array([force / FORCE_PER_ANGLE] * 4 + [50.0 * force] * 4)
    base = period(rest.copy())
    columns = []
    for i in range(rest.size):
        shifted = rest.copy()
        shifted[i] += 1e-6 * max(1.0, abs(rest[i]))
        columns.append((period(shifted) - base) / (shifted[i] - rest[i]))
    return np.column_stack(columns)


def _slowest_rate(inertia_ratio=1.0):
    """Decay rate sigma = -ln(rho) f_s [1/s] of the slowest discrete closed-loop mode."""
    return -math.log(max(abs(np.linalg.eigvals(closed_loop_matrix(inertia_ratio))))) * RATE


def _simulate(duration, force_step=1.0, disturbance=0.0, coulomb=0.0, inertia_ratio=1.0):
    """Force error F_ref - F [N] per 8 kHz sample; at SETTLE the reference steps by ``force_step`` and the external
    torque ``disturbance`` [N mm] switches on."""
    start = 1.0 / FORCE_PER_ANGLE                                                     # at rest at 1 N
    plant = ActuatorPlant(ActuatorParameters(inertia=inertia_ratio * DESIGN.nominal_inertia,
                                             coulomb_friction=coulomb), angle=start)
    controller = AccelerationController(DESIGN, angle=start)
    errors = []
    for k in range(int(round((SETTLE + duration) * RATE))):
        after = k >= SETTLE * RATE
        reference = 1.0 + (force_step if after else 0.0)
        torque = controller.step(reference, plant.contact_force, plant.angle)
        plant.step(torque, 1.0 / RATE, disturbance if after else 0.0)
        errors.append(reference - plant.contact_force)
    return np.array(errors[int(SETTLE * RATE):])


def test_dob_leaves_no_static_error_for_a_constant_disturbance():
    # Final-value theorem on the linearised loop: the DOB filter has Q(1) = 1, so a constant torque is cancelled
    # exactly and the static force error is zero; finite-difference rounding (1e-6 steps on O(1e2) entries) is
    # below 1e-7 in the DC gain.
    a = closed_loop_matrix(1.0)
    input_torque = np.zeros(8)
    input_torque[1] = -1.0 / RATE / DESIGN.nominal_inertia                             # dv per N mm, 1st order
    steady = np.linalg.solve(np.eye(8) - a, input_torque)
    assert abs(FORCE_PER_ANGLE * steady[0]) < 1e-7


@pytest.mark.parametrize("disturbance, coulomb", [(50.0, 0.0), (0.0, 30.0)], ids=["step", "coulomb"])
def test_dob_rejects_step_and_coulomb_disturbances(disturbance, coulomb):
    # Bound: a residual torque d_res that the DOB has not cancelled shifts the force by at most
    # I_a d_res / (J_n r) (static gain of the overdamped target impedance); the residual starts at most at the
    # disturbance d0 (a step, or the Coulomb torque, constant while the joint moves one way: the response is
    # monotone) and, like the 1 N reference step, dies out no slower than the slowest closed-loop mode, so
    # |e(t)| <= (dF + I_a d0 / (J_n r)) exp(-sigma t). Steady state: zero (test above) up to rounding.
    sigma = _slowest_rate()
    errors = _simulate(0.3, disturbance=disturbance, coulomb=coulomb)
    amplitude = 1.0 + DESIGN.force_error_per_residual_torque() * max(disturbance, coulomb)
    for time in (0.05, 0.1, 0.3):
        index = int(time * RATE) - 1
        bound = amplitude * math.exp(-sigma * time) + 1e-12
        assert np.max(np.abs(errors[index:])) < bound, (time, np.max(np.abs(errors[index:])), bound)


def test_slowest_mode_is_the_designed_one():
    # 1 - Q(s) ~ s / g at low frequency turns the load torque r^2 k_c q into an extra damping r^2 k_c / g seen
    # through I_a / J_n: D = D_a + (I_a / J_n) r^2 k_c / g = 403 N mm s/rad, zeta = 1.52, slow root
    # w_n (zeta - sqrt(zeta^2 - 1)) = 71 rad/s; discretisation and the DOB dynamics move it by 10-15 %.
    sigma = _slowest_rate()
    assert 55.0 < sigma < 75.0


STABLE_RANGE = (0.15, 15.0)      # J / J_n, with margin inside the measured limits 0.096 and 23.8


@pytest.mark.parametrize("inertia_ratio", np.geomspace(*STABLE_RANGE, 7))
def test_stable_over_the_stated_nominal_inertia_mismatch(inertia_ratio):
    assert max(abs(np.linalg.eigvals(closed_loop_matrix(inertia_ratio)))) < 1.0


@pytest.mark.parametrize("inertia_ratio", [0.05, 50.0])
def test_unstable_beyond_the_mismatch_limits(inertia_ratio):
    # J_n far above J: the DOB feedback J_n / J exceeds what the 8 kHz loop tolerates; J far above J_n: the
    # residual inertia (J - J_n) q'' is rejected too slowly and the target impedance loses its damping.
    assert max(abs(np.linalg.eigvals(closed_loop_matrix(inertia_ratio)))) > 1.0


@pytest.mark.parametrize("inertia_ratio", STABLE_RANGE)
def test_mismatched_inertia_still_tracks_with_friction(inertia_ratio):
    errors = _simulate(0.4, coulomb=30.0, inertia_ratio=inertia_ratio)
    assert np.max(np.abs(errors[-400:])) < 1e-3


def test_torque_command_saturates():
    controller = AccelerationController(DESIGN)
    assert controller.step(1e6, 0.0, 0.0) == DESIGN.torque_limit


@pytest.mark.parametrize("field, value, match", [
    ("nominal_inertia", 0.0, "nominal_inertia=0.0 outside"),
    ("target_inertia", -1.0, "target_inertia=-1.0 outside"),
    ("target_damping", 0.0, "target_damping=0.0 outside"),
    ("dob_cutoff_hz", 4000.0, "dob_cutoff_hz=4000.0 outside"),
    ("sample_rate_hz", -8000.0, "sample_rate_hz=-8000.0 outside"),
    ("arm_radius", 0.0, "arm_radius=0.0 outside"),
    ("torque_limit", math.nan, "torque_limit=nan outside"),
])
def test_invalid_acceleration_parameters_raise(field, value, match):
    with pytest.raises(ValueError, match=match):
        AccelerationControlParameters(**{field: value})


@pytest.mark.parametrize("field, value, match", [
    ("inertia", 0.0, "inertia=0.0 outside"),
    ("viscous_friction", -1.0, "viscous_friction=-1.0 outside"),
    ("coulomb_friction", -1.0, "coulomb_friction=-1.0 outside"),
    ("torque_limit", 0.0, "torque_limit=0.0 outside"),
    ("contact_stiffness", 0.0, "contact_stiffness=0.0 outside"),
])
def test_invalid_actuator_parameters_raise(field, value, match):
    with pytest.raises(ValueError, match=match):
        ActuatorParameters(**{field: value})
