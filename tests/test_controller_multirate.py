"""Multi-rate runner: 8 Acceleration Control steps per Grasp Force Control step; rate checks."""

import pytest

from controller import (AccelerationControlParameters, AccelerationController, ActuatorParameters, ActuatorPlant,
                        GraspForceController, GraspForceParameters, GraspPhase, MultiRateRunner, ReferenceParameters,
                        rate_ratio)


class _CountingPlant(ActuatorPlant):
    def __init__(self):
        super().__init__(ActuatorParameters())
        self.durations = []

    def step(self, torque, duration, external_torque=0.0):
        self.durations.append(duration)
        return super().step(torque, duration, external_torque)


def _runner(fast_hz=8000.0, slow_hz=1000.0, plant=None, angle=0.0):
    grasp = GraspForceController(GraspForceParameters(sample_rate_hz=slow_hz), ReferenceParameters())
    acceleration = AccelerationController(AccelerationControlParameters(sample_rate_hz=fast_hz), angle=angle)
    return MultiRateRunner(grasp, acceleration, plant or ActuatorPlant(ActuatorParameters(), angle=angle),
                           lambda time, force: (0.0, 0.0, 2 if force > 0.02 else 0))


def test_eight_fast_steps_per_slow_step():
    plant = _CountingPlant()
    runner = _runner(plant=plant)
    samples = [runner.step(GraspPhase.APPROACH) for _ in range(5)]
    assert runner.steps_per_grasp_step == 8
    assert len(plant.durations) == 40 and all(d == pytest.approx(1.0 / 8000.0, rel=1e-15) for d in plant.durations)
    assert samples[-1].time == pytest.approx(5e-3, rel=1e-12)


def test_approach_closes_and_holds_the_approach_force():
    # free space: the target impedance closes at r F_ref / D_a; in contact the force settles at F_ref
    # (50 mm * 0.05 N / 264 N mm s/rad = 0.47 mm/s: 0.1 mm in 0.21 s)
    runner = _runner(angle=-0.002)                                      # 0.1 mm open
    samples = [runner.step(GraspPhase.APPROACH) for _ in range(600)]
    assert samples[150].contact_force == 0.0
    assert samples[-1].contact_force == pytest.approx(GraspForceParameters().approach_force, rel=1e-3)


@pytest.mark.parametrize("fast_hz, slow_hz, match", [
    (8000.0, 3000.0, "not an integer multiple"),
    (500.0, 1000.0, "not an integer multiple"),
])
def test_rates_must_be_integer_multiples(fast_hz, slow_hz, match):
    with pytest.raises(ValueError, match=match):
        _runner(fast_hz, slow_hz)


def test_rate_ratio():
    assert rate_ratio(8000.0, 1000.0) == 8
    assert rate_ratio(1000.0, 1000.0) == 1
