"""Grasp Force Control block against the closed-form Hertz-Mindlin-Lubkin fingertip, in the full multi-rate loop.

The controller gets u_x [mm] and the twist angle theta [rad] from the fixture plant (controller.plant.hertz_plant),
never mu, the loads or the object's mass. Its targets are designed for the lowest friction expected, mu_low = 0.5:
Q/(mu_low P) = 0.85 and T/(mu_low P a) = 0.5 (85 % of gross slip in each mode) at 1 N, scaled with the force
(controller.control.references). At the true mu the same targets hold the contact at the load ratios predicted below.
"""

import math
from dataclasses import replace

import numpy as np
import pytest

from controller import (AccelerationControlParameters, AccelerationController, ActuatorParameters, ActuatorPlant,
                        GraspForceController, GraspForceParameters, GraspPhase, MultiRateRunner, ReferenceGenerator,
                        ReferenceParameters)
from controller.plant.hertz_plant import (SLIP_TORQUE_RATIO, ClosedFormContactPlant, HertzFingertip,
                                          normalized_lubkin_torque, normalized_lubkin_twist, slip_factors)

DESIGN_FRICTION, DESIGN_LOAD_RATIO, DESIGN_TORQUE_RATIO = 0.5, 0.85, 0.5
TIP = HertzFingertip()
SLIP_FACTORS = slip_factors(DESIGN_LOAD_RATIO, DESIGN_TORQUE_RATIO)                  # about (1.49, 2.9)
REFERENCES = ReferenceParameters(*TIP.references(DESIGN_LOAD_RATIO, DESIGN_TORQUE_RATIO, DESIGN_FRICTION),
                                 translational_slip_factor=SLIP_FACTORS[0], rotational_slip_factor=SLIP_FACTORS[1])
GRASP = GraspForceParameters()
SLOW_MODE = 1.0 / 62.0                       # s, slowest mode of the force loop (test_controller_acceleration)
PERIOD = 1.0 / GRASP.sample_rate_hz


def _ramp(start, end, value):
    return lambda time: value * min(max((time - start) / (end - start), 0.0), 1.0)


def _phase(time, schedule):
    """Phase at ``time`` from [(end_time, phase), ...]."""
    return next(phase for end, phase in schedule if time < end)


def _closed_loop(fingertip, tangential_force, torque, schedule, duration, parameters=GRASP, coulomb=30.0):
    """Run the multi-rate loop (actuator Coulomb friction ``coulomb`` [N mm]); return the controller, the plant and
    arrays of time, F, u_x, theta, P_min."""
    plant = ClosedFormContactPlant(fingertip, tangential_force, torque)
    grasp = GraspForceController(parameters, REFERENCES)
    runner = MultiRateRunner(grasp, AccelerationController(AccelerationControlParameters()),
                             ActuatorPlant(ActuatorParameters(coulomb_friction=coulomb)), plant.sense)
    rows = []
    for k in range(int(round(duration / PERIOD))):
        time = k * PERIOD
        sample = runner.step(_phase(time, schedule))
        rows.append((time, sample.contact_force, sample.shear_displacement, sample.twist_angle,
                     fingertip.minimum_normal_force(tangential_force(time), torque(time))))
    return grasp, plant, np.array(rows).T


def _predicted_margins(friction):
    """P / P_min at the targets for the true mu: translation 1 / x, rotation (y_slip / y)^(3/4) (a ~ P^(1/3)).

    The scaled target fixes h(x) mu = h(x_d) mu_low with h(x) = 1 - (1 - x)^(2/3) (Mindlin) and f(y) mu = f(y_d)
    mu_low with f the normalised Lubkin twist; mu enters only this prediction, not the controller."""
    h = (1.0 - (1.0 - DESIGN_LOAD_RATIO) ** (2.0 / 3.0)) * DESIGN_FRICTION / friction
    load_ratio = 1.0 - (1.0 - h) ** 1.5
    torque_ratio = normalized_lubkin_torque(normalized_lubkin_twist(DESIGN_TORQUE_RATIO) * DESIGN_FRICTION / friction)
    return 1.0 / load_ratio, (SLIP_TORQUE_RATIO / torque_ratio) ** 0.75


# Load path: the object is lifted (Q ramps over 2 s), held, then the moment grows (T ramps over 2 s), held.
# (Lifting from F_min = 0.3 N to Q = 1.6 N in 1 s slips at mu = 0.6 with lambda = 20 rad/s: the lag is the limit.)
RAMP_Q, RAMP_T = (0.5, 2.5), (3.0, 5.0)
DURATION = 5.6
LIFT_SCHEDULE = [(0.05, GraspPhase.APPROACH), (0.5, GraspPhase.GRASP), (5.0, GraspPhase.LIFT),
                 (math.inf, GraspPhase.HOLD)]
# Tracking bound during a ramp: the law is first order in ln F with rate lambda (module docstring), so a
# target force growing at d ln F*/dt = r lags by r / lambda in ln F, plus r tau_d for the delays of the
# shear-displacement filter (1 / (2 pi f_c)) and of the force loop (its slowest mode); the displacement ratio is
# (F*/F)^(1/p): ln(u/u_ref) <= r (1/lambda + tau_d) / p. In the second half of a ramp from zero,
# d ln Q/dt <= 2 / (ramp length) and F* ~ Q (p = 1) or F* ~ T^(3/4) (p = 3/4), and the slip factor phi (the
# exponent is p / phi; in partial slip the ratio moves up to phi times faster with ln F) multiplies both terms:
# ln(u/u_ref) <= (2 / ramp length) phi (1/lambda + tau_d), the same form for both channels.
TAU_DELAY = 1.0 / (2.0 * math.pi * GRASP.filter_cutoff_hz) + SLOW_MODE


def _ramp_bound(start, end, slip_factor):
    return math.exp(2.0 / (end - start) * slip_factor * (1.0 / GRASP.loop_rate + TAU_DELAY))


@pytest.mark.parametrize("friction", [0.6, 1.0])
def test_keeps_shear_at_reference_and_force_near_minimum_without_knowing_mu(friction):
    fingertip = HertzFingertip(friction_coefficient=friction)
    grasp, plant, (time, force, shear, twist, minimum) = _closed_loop(
        fingertip, _ramp(*RAMP_Q, 1.6), _ramp(*RAMP_T, 6.0), LIFT_SCHEDULE, DURATION, coulomb=0.0)
    assert not any(plant.slipped.values())
    assert TIP.second_contact_force <= grasp.minimum_force < TIP.second_contact_force + 0.05
    scale = np.maximum(force, 1e-12) / REFERENCES.reference_force
    exponent_x, exponent_theta = REFERENCES.force_exponents
    shear_ratio = shear / (REFERENCES.translational_reference * scale**exponent_x)
    twist_ratio = twist / (REFERENCES.rotational_reference * scale**exponent_theta)
    loaded = minimum > 0.0
    assert np.all(force[loaded] > minimum[loaded])                       # never below the slip limit
    translational_margin, rotational_margin = _predicted_margins(friction)
    # End of each hold: the active channel on its reference and the force at the predicted margin. After the
    # translational hold (0.5 s = 15 / lambda, transient e^-15) 1e-4; after the moment, 2e-3: the translational
    # share drains only in steps where the twist is at or below its target, so the last per-mille settles slowly.
    # (Actuator friction is off here: see the stiction test below.)
    end_q, end_t = int((RAMP_T[0] - 0.05) / PERIOD), int((DURATION - 0.05) / PERIOD)
    assert shear_ratio[end_q] == pytest.approx(1.0, abs=1e-4)
    assert twist_ratio[end_t] == pytest.approx(1.0, abs=2e-3)
    assert twist_ratio[end_q] < 1.0 and shear_ratio[end_t] < 1.0         # the other channel is below target
    assert force[end_q] / minimum[end_q] == pytest.approx(translational_margin, rel=1e-4)
    assert force[end_t] / minimum[end_t] == pytest.approx(rotational_margin, rel=2e-3)
    for (start, end), ratio, factor in zip((RAMP_Q, RAMP_T), (shear_ratio, twist_ratio), SLIP_FACTORS):
        window = (time >= 0.5 * (start + end)) & (time <= end)
        assert np.max(ratio[window]) < _ramp_bound(start, end, factor)


def test_actuator_stiction_makes_the_grip_hunt_but_not_slip():
    # With 30 N mm Coulomb friction the actuator sticks while the two integrators (DOB and grasp law) wind up,
    # then jumps: a limit cycle (measured +-3.5 % of the force at mu = 0.6, where the twist is most sensitive to
    # the force) around the friction-free equilibrium. It stays above the slip limit; its mean sits at the
    # predicted margin to within the cycle's asymmetry (2 %).
    fingertip = HertzFingertip(friction_coefficient=0.6)
    _, plant, (time, force, shear, twist, minimum) = _closed_loop(
        fingertip, _ramp(*RAMP_Q, 1.6), _ramp(*RAMP_T, 6.0), LIFT_SCHEDULE, DURATION + 1.0)
    assert not any(plant.slipped.values())
    window = time > RAMP_T[1] + 0.5
    margin = force[window] / minimum[window]
    assert margin.min() > 1.0
    assert np.mean(margin) == pytest.approx(_predicted_margins(0.6)[1], rel=0.02)
    assert np.ptp(force[window]) / np.mean(force[window]) < 0.1


def test_without_rotational_detection_the_grip_is_too_weak_under_a_moment():
    # paper Fig. 10b: the translational channel alone settles at the force its own target asks for, which is
    # below the force the moment needs: the contact slips in rotation.
    parameters = GraspForceParameters(rotational_slip_detection=False)
    _, plant, (time, force, shear, twist, minimum) = _closed_loop(
        TIP, _ramp(*RAMP_Q, 1.6), _ramp(*RAMP_T, 6.0), LIFT_SCHEDULE, DURATION, parameters)
    assert plant.slipped["rotational"] and not plant.slipped["translational"]
    assert force[-1] < 0.9 * minimum[-1]
    _, with_rotation, _ = _closed_loop(TIP, _ramp(*RAMP_Q, 1.6), _ramp(*RAMP_T, 6.0), LIFT_SCHEDULE, DURATION)[0:3]
    assert not any(with_rotation.slipped.values())


HOLD_SCHEDULE = [(0.05, GraspPhase.APPROACH), (0.5, GraspPhase.GRASP), (1.5, GraspPhase.HOLD)]


@pytest.mark.parametrize("taken", [True, False], ids=["human_takes_weight", "nobody_takes_it"])
def test_release_opens_only_when_the_load_is_taken(taken):
    # Hand-over: the weight is lifted (Q to 1 N by 1 s), then RELEASE at 1.5 s; a human takes the weight over
    # 0.5 s (Q -> 0) or nobody does.
    weight = _ramp(0.5, 1.0, 1.0)
    tangential_force = (lambda t: weight(t) - _ramp(1.6, 2.1, 1.0)(t)) if taken else weight
    schedule = HOLD_SCHEDULE + [(math.inf, GraspPhase.RELEASE)]
    grasp, plant, (time, force, *_) = _closed_loop(TIP, tangential_force, lambda t: 0.0, schedule, 3.0)
    assert not any(plant.slipped.values())
    hold = force[int(1.49 / PERIOD)]
    if taken:
        assert force[-1] < 1e-3 < grasp.minimum_force                    # fully open, below the minimum force
    else:
        assert force[-1] == pytest.approx(hold, rel=0.03)                # held: nothing to release to


def test_place_lowers_force_to_minimum_then_release_opens():
    weight = lambda t: _ramp(0.5, 1.0, 1.0)(t) - _ramp(1.5, 2.0, 1.0)(t)          # the table takes the weight
    schedule = [(0.05, GraspPhase.APPROACH), (0.5, GraspPhase.GRASP), (1.5, GraspPhase.HOLD),
                (2.5, GraspPhase.PLACE), (math.inf, GraspPhase.RELEASE)]
    grasp, plant, (time, force, *_) = _closed_loop(TIP, weight, lambda t: 0.0, schedule, 3.3)
    assert not any(plant.slipped.values())
    assert force[int(2.45 / PERIOD)] == pytest.approx(grasp.minimum_force, rel=0.02)
    # nothing is loaded at the latch, so the force falls at lambda_r F_hold: zero after 1 / lambda_r = 0.5 s
    assert force[-1] < 1e-3


def test_minimum_force_is_the_command_when_two_contacts_are_first_seen():
    grasp = GraspForceController(GRASP, REFERENCES)
    assert grasp.step(0.0, 0.0, 1, GraspPhase.APPROACH) == GRASP.approach_force
    counts = [1] * 10 + [2] * 5
    commands = [grasp.step(0.0, 0.0, count, GraspPhase.GRASP) for count in counts]
    expected = GRASP.approach_force + 10 * GRASP.ramp_rate * PERIOD
    assert grasp.minimum_force == pytest.approx(expected, rel=1e-12)
    assert commands[-1] == pytest.approx(expected, rel=1e-12)              # no load: stays at the minimum


def test_full_stick_step_is_first_order_in_force():
    # Fixed target (p = 3) and a full-stick reading u = u_ref (F*/F)^(1/3) (paper eq. 12 with eq. 10): one step
    # must give F_{k+1} - F* = (1 - gamma)(F_k - F*), gamma = lambda T, whatever F* is.
    grasp = GraspForceController(GRASP, ReferenceParameters(scale_with_force=False))
    grasp.minimum_force, grasp.command, grasp.components = 0.1, 1.0, np.array([0.9, 0.0])
    gamma = GRASP.loop_rate * PERIOD
    for target in (0.5, 2.0):
        shear = grasp.generator.parameters.translational_reference * (target / grasp.command) ** (1.0 / 3.0)
        grasp.filter.reset([shear, 0.0])                                  # steady filter input
        before = grasp.command
        after = grasp.step(shear, 0.0, 2, GraspPhase.HOLD)
        assert after - target == pytest.approx((1.0 - gamma) * (before - target), rel=1e-9)


def test_reference_generator():
    generator = ReferenceGenerator(ReferenceParameters(0.3, 0.1, reference_force=1.0))
    assert generator.references(GraspPhase.APPROACH, 1.0) is None
    assert generator.references(GraspPhase.RELEASE, 1.0) is None
    u_x, theta = generator.references(GraspPhase.LIFT, 8.0)
    assert (u_x, theta) == pytest.approx((0.3 * 8.0 ** (2.0 / 3.0), 0.1 * 8.0 ** (1.0 / 3.0)), rel=1e-12)
    assert ReferenceParameters().inversion_exponents == pytest.approx((1.0, 0.75))
    assert ReferenceParameters(scale_with_force=False).inversion_exponents == pytest.approx((3.0, 1.0))
    with pytest.raises(ValueError, match="'lunch' is not a valid GraspPhase"):
        generator.references("lunch", 1.0)


def test_measured_force_exponents_replace_the_single_profile_ones():
    # an array whose twist signal grows like F^(2/3): theta_ref follows it, u_x keeps the hemisphere's 2/3, and the
    # inversion exponent of the twist channel is 1 / (3/(n+1) + q) = 1 / (1 + 2/3) = 0.6 for n = 2
    parameters = ReferenceParameters(0.3, 0.1, reference_force=1.0, rotational_force_exponent=2.0 / 3.0)
    u_x, theta = ReferenceGenerator(parameters).references(GraspPhase.HOLD, 8.0)
    assert (u_x, theta) == pytest.approx((0.3 * 4.0, 0.1 * 4.0), rel=1e-12)
    assert parameters.inversion_exponents == pytest.approx((1.0, 0.6), rel=1e-12)
    assert replace(parameters, scale_with_force=False).force_exponents == (0.0, 0.0)


@pytest.mark.parametrize("field, value, match", [
    ("sample_rate_hz", 0.0, "sample_rate_hz=0.0 outside"),
    ("filter_cutoff_hz", 600.0, "filter_cutoff_hz=600.0 outside"),
    ("loop_rate", 0.0, "loop_rate=0.0 outside"),
    ("loop_rate", 500.0, "loop_rate=500.0 outside"),
    ("release_rate", -1.0, "release_rate=-1.0 outside"),
    ("approach_force", 0.0, "approach_force=0.0 outside"),
    ("ramp_rate", 0.0, "ramp_rate=0.0 outside"),
    ("maximum_force", 0.01, "maximum_force=0.01 outside"),
    ("ratio_limit", 1.0, "ratio_limit=1.0 outside"),
    ("release_threshold", 0.0, "release_threshold=0.0 outside"),
])
def test_invalid_grasp_parameters_raise(field, value, match):
    with pytest.raises(ValueError, match=match):
        GraspForceParameters(**{field: value})


@pytest.mark.parametrize("field, value, match", [
    ("translational_reference", 0.0, "translational_reference=0.0 outside"),
    ("rotational_reference", -0.1, "rotational_reference=-0.1 outside"),
    ("reference_force", 0.0, "reference_force=0.0 outside"),
    ("profile_order", 0.5, "profile_order=0.5 outside"),
    ("rotational_force_exponent", -0.1, "rotational_force_exponent=-0.1 outside"),
    ("translational_force_exponent", 3.0, "translational_force_exponent=3.0 outside"),
])
def test_invalid_reference_parameters_raise(field, value, match):
    with pytest.raises(ValueError, match=match):
        ReferenceParameters(**{field: value})


@pytest.mark.parametrize("torque_ratio", [0.05, 0.3, 0.5, 0.55])
def test_fixture_lubkin_table_matches_contact_theory(torque_ratio):
    # 460 stick ratios, dense near full slip: linear interpolation error of the smooth curve is below 1e-4.
    from contact.theory import lubkin_twist
    P, mu, G = 2.0, 0.8, TIP.shear_modulus
    a = float(TIP.contact_radius(P))
    exact = lubkin_twist(torque_ratio * mu * P * a, P, mu, a, G)
    assert TIP.rotational_scale(P) * normalized_lubkin_twist(torque_ratio) == pytest.approx(exact, rel=1e-4)


def test_a_switched_off_rotational_channel_does_not_hold_the_force_up():
    # With rotational detection off, a large twist reading must not stop the translational share from draining
    # to where its own target puts it: at |u_x| = u_ref / 2 the force falls (the law's increment is negative).
    controller = GraspForceController(GraspForceParameters(rotational_slip_detection=False), REFERENCES)
    controller.minimum_force, controller.components, controller.command = 0.2, np.array([2.0, 0.0]), 2.2
    u_ref, theta_ref = controller.generator.references(GraspPhase.HOLD, controller.command)
    for _ in range(200):                       # 0.2 s: the filter settles on the constant readings
        controller.step(0.5 * u_ref, 10.0 * theta_ref, 9, GraspPhase.HOLD)
    assert controller.command < 0.9 * 2.2      # off: drains; the old code held it at 2.2 exactly
    assert controller.components[1] == 0.0
