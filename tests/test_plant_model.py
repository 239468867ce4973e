"""The plant of a design (PlantModel): the shipped 3x3 built through the general path is the packaged plant, bit for
bit, and a trial on it gives the same numbers; models are known by their key; the estimator's bench is keyed by the
design and its array, never by a trial's noise."""

import dataclasses
import json
import shutil

import numpy as np
import pytest

from contact.reduced import PACKAGED_CALIBRATION, ArrayFingertipDesign, ReducedFingertip, ReducedParameters
from contact.reduced.base_response import PACKAGED_BASE_RESPONSE, BaseResponse
from controller.plant import FingertipPlant, PlantFactors, PlantModel, SensorPlane, nominal_model

FACTORS = PlantFactors(kernel_width=0.07, couple_arm=-0.05, youngs_modulus=0.08, bump_height=0.03, node_gain=0.04,
                       friction_anisotropy=0.02)


@pytest.fixture(scope="module")
def shipped_copy(tmp_path_factory):
    """The shipped design's plant from copies of the packaged data, through the general constructors: the bump laws
    from the calibration file's parameters on the design FingertipDesign() maps to, the response file read anew."""
    from controller.design import FingertipDesign, array_design

    folder = tmp_path_factory.mktemp("packaged")
    response = BaseResponse.load(shutil.copy(PACKAGED_BASE_RESPONSE, folder / "response.npz"))
    stored = json.loads(shutil.copy(PACKAGED_CALIBRATION, folder / "calibration.json").read_text())
    design = array_design(FingertipDesign())
    mechanics = ReducedFingertip(design, ReducedParameters.from_dict(stored["parameters"]))
    return PlantModel(mechanics, response, "shipped-copy")


def _inputs(plant) -> list:
    return [np.asarray(value) for value in plant.compiled_inputs()]


@pytest.mark.parametrize("factors", [PlantFactors(), FACTORS])
def test_the_shipped_design_through_the_general_path_is_the_packaged_plant(shipped_copy, factors):
    assert shipped_copy.design == nominal_model().design == ArrayFingertipDesign()
    packaged = FingertipPlant(factors, noise=0.001, seed=5)
    general = FingertipPlant(factors, noise=0.001, seed=5, model=shipped_copy)
    assert general.mechanics.parameters == packaged.mechanics.parameters
    for ours, theirs in zip(_inputs(general), _inputs(packaged), strict=True):
        np.testing.assert_array_equal(ours, theirs)          # bit for bit: the same numbers, not close ones


def test_a_trial_on_the_general_path_gives_the_packaged_trial(shipped_copy):
    from controller.closed_loop import TABLE_I_OBJECTS, HELD_OUT_SEED, random_settings, run_trial

    settings = random_settings(np.random.default_rng(HELD_OUT_SEED), hold_time=0.5, place=False)
    obj = TABLE_I_OBJECTS["bottle_horizontal"]
    packaged = run_trial(obj, settings)
    general = run_trial(obj, settings, plant=FingertipPlant(settings.plant, noise=settings.sensor_noise,
                                                            seed=settings.seed, model=shipped_copy))
    for key in ("grip_force", "force_command", "rotation", "slip_x_mm", "friction_estimate"):
        np.testing.assert_array_equal(general.trace[key], packaged.trace[key])
    assert general.outcome == packaged.outcome and general.slip_events == packaged.slip_events


def test_models_are_known_by_their_key(shipped_copy):
    same = PlantModel(shipped_copy.mechanics, shipped_copy.response, shipped_copy.key)
    assert same == shipped_copy and hash(same) == hash(shipped_copy) and same != nominal_model()
    with pytest.raises(ValueError, match="key='' must be a non-empty string"):
        PlantModel(shipped_copy.mechanics, shipped_copy.response, "")
    other = ReducedFingertip(dataclasses.replace(ArrayFingertipDesign(), base_thickness=4.0))
    with pytest.raises(ValueError, match="a plant needs both of one design"):
        PlantModel(other, shipped_copy.response, "mixed")
    with pytest.raises(ValueError, match="model=.* must be a PlantModel"):
        FingertipPlant(model="3x3")


def test_the_bench_is_keyed_by_the_design_not_by_a_trials_noise(shipped_copy):
    from controller.closed_loop import estimator_bench
    from controller.sensing import capacitive_array

    default = estimator_bench(SensorPlane.FEM)
    noisy = dataclasses.replace(capacitive_array(), node=dataclasses.replace(capacitive_array().node,
                                                                             noise_floor=3e-3))
    # the paper's array at any noise floor is one bench (the bench sets its own noise), with the default's belief
    assert estimator_bench(SensorPlane.FEM, None, noisy) is estimator_bench(SensorPlane.FEM, None, capacitive_array())
    assert estimator_bench(SensorPlane.FEM, None, noisy).belief.kernel_width == default.belief.kernel_width
    # another model of the same numbers is another rig, and fits the same belief from the same readings
    copied = estimator_bench(SensorPlane.FEM, shipped_copy)
    assert copied is not default and copied.rig != default.rig
    np.testing.assert_array_equal(copied.reference_readings, default.reference_readings)
    assert copied.belief.couple_arm == default.belief.couple_arm
