"""Calibration of the reduced fingertip model (contact.reduced.calibration) and its stored file (reduced._store).

The fits are checked on synthetic paths made by the reduced model itself with known parameters (the fit must give
them back), the file on round trips and bad content, and the packaged calibration on one coarse held-out FEM path.
"""

import dataclasses
import json

import numpy as np
import pytest

from contact.reduced import (PACKAGED_CALIBRATION, ArrayFingertipDesign, PathSamples, ReducedFingertip,
                             ReducedParameters, StoredCalibration, load_calibrated, load_calibration,
                             save_calibration)
from contact.reduced.calibration import calibrate, fit_normal_stiffness

DESIGN = ArrayFingertipDesign()
CLOSED = ReducedParameters.from_design(DESIGN)
MU = 1.0
PRESS_FORCES = np.array([1.5, 2.0, 3.0, 5.0])                      # N, the study's press path
SHIFTS = np.array([0.0, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6])             # mm, from the pressed state
ANGLES = np.array([0.0, 0.003, 0.006, 0.01, 0.015, 0.02, 0.03])      # rad
# The synthetic paths are the model's own output, so every residual vanishes at the true parameters. k_n, c_a
# (one-parameter fits with closed-form starts) and g, h (a linear problem) are then exact up to round-off; G*, G_t
# and s come out of nonlinear least_squares, which stops at relative steps of 1e-10 to 1e-12 on residuals that are
# smooth there, with a forward-difference Jacobian of step 1e-6 (G*, G_t): 1e-6 relative leaves two orders of
# margin over what the fits reach (~1e-9).
EXACT = 1e-10
ITERATIVE = 1e-6


def _with_kernel_centres(path, tip):
    """The path with its base CoPs replaced by the model's kernel centres c_i = r_i + g delta_i + h Q_i / P_i.

    That is the law the CoP fit assumes (``_design``); the model's grid cells follow it only while its kernels stay
    inside their cells, so the exact law makes the synthetic check independent of the grid.
    """
    p = tip.parameters
    ratio = path.bump_tangential_force / np.where(path.bump_normal_force > 0, path.bump_normal_force, 1.0)[..., None]
    centre = tip.centres + p.cop_gain * path.bump_displacement(tip.centres) + p.moment_arm * ratio
    return dataclasses.replace(path, base_centre=centre)


def synthetic_paths(parameters, friction=MU):
    """Press, shear (at 2 and 5 N) and twist paths of the reduced model with ``parameters``, as the FEM gives them."""
    tip = ReducedFingertip(DESIGN, parameters)
    count = len(PRESS_FORCES)
    press = PathSamples.from_reduced(tip, "press", ["press"] * count, PRESS_FORCES, friction, np.zeros((count, 3)),
                                     "displacement")
    kinds = ["press"] + ["shear"] * (len(SHIFTS) - 1)
    shear = [_with_kernel_centres(PathSamples.from_reduced(
        tip, f"shear_{force:g}N", kinds, np.full(len(SHIFTS), force), friction,
        np.column_stack([SHIFTS, 0 * SHIFTS, 0 * SHIFTS]), "displacement"), tip) for force in (2.0, 5.0)]
    kinds = ["press"] + ["twist"] * (len(ANGLES) - 1)
    twist = _with_kernel_centres(PathSamples.from_reduced(
        tip, "twist", kinds, np.full(len(ANGLES), 2.0), friction, np.column_stack([0 * ANGLES, 0 * ANGLES, ANGLES]),
        "displacement"), tip)
    return press, shear, twist


TRUE_SETS = {
    # every field away from its closed-form start, both CoP terms active
    "both_cop_terms": dataclasses.replace(
        CLOSED, normal_stiffness=1.3 * CLOSED.normal_stiffness, radius_coefficient=0.9 * CLOSED.radius_coefficient,
        tangential_modulus=0.7 * CLOSED.tangential_modulus, torsional_modulus=1.5 * CLOSED.torsional_modulus,
        kernel_spread=7.0, cop_gain=3.0, moment_arm=2.0),
    # a narrow kernel and no moment arm: the bound h >= 0 must hold the fit at zero, not push it negative
    "gain_only": dataclasses.replace(
        CLOSED, normal_stiffness=0.8 * CLOSED.normal_stiffness, tangential_modulus=1.2 * CLOSED.tangential_modulus,
        torsional_modulus=0.6 * CLOSED.torsional_modulus, kernel_spread=3.0, cop_gain=6.0, moment_arm=0.0),
}


@pytest.mark.parametrize("name", sorted(TRUE_SETS))
def test_fit_recovers_the_parameters_of_synthetic_paths(name):
    true = TRUE_SETS[name]
    press, shear, twist = synthetic_paths(true)
    result = calibrate(DESIGN, [press], shear, twist, "synthetic")
    fitted = result.parameters
    assert fitted.source == "fem:synthetic"
    assert fitted.normal_stiffness == pytest.approx(true.normal_stiffness, rel=EXACT)
    assert fitted.radius_coefficient == pytest.approx(true.radius_coefficient, rel=EXACT)
    for field in ("tangential_modulus", "torsional_modulus", "kernel_spread"):
        assert getattr(fitted, field) == pytest.approx(getattr(true, field), rel=ITERATIVE), field
    # the CoP law is linear in g and h: bounded linear least squares solves it to round-off; h = 0 has no relative
    # error, so it is compared in mm against the CoP shifts it produces (~1 mm)
    assert fitted.cop_gain == pytest.approx(true.cop_gain, rel=EXACT)
    assert fitted.moment_arm == pytest.approx(true.moment_arm, abs=EXACT)
    assert fitted.damping_time == CLOSED.damping_time
    for fit in result.fits:
        # the residuals of an exact model vanish: what is left is the solvers' tolerance
        assert fit.rms_residual < 1e-6, fit


def test_settlement_split_finds_a_linear_term():
    # depth = Hertz part + c_s P_i: the effective k_n absorbs it, the two-term diagnostic finds it back
    press, _, _ = synthetic_paths(CLOSED)
    hertz, settlement = 1.2, 0.25                                     # N/mm^1.5, mm/N
    bump_force = PRESS_FORCES / DESIGN.bump_count
    depth = (bump_force / hertz) ** (2 / 3) + settlement * bump_force
    press = dataclasses.replace(press, depth=depth)
    fit, diagnostics = fit_normal_stiffness([press], DESIGN)
    assert diagnostics["hertz_stiffness_two_term"] == pytest.approx(hertz, rel=1e-8)
    assert diagnostics["settlement_compliance"] == pytest.approx(settlement, rel=1e-8)
    assert fit.rms_residual > 1e-4            # a pure 1.5 power cannot follow the linear part exactly


def test_fit_refuses_a_single_press_force():
    press, shear, twist = synthetic_paths(CLOSED)
    single = dataclasses.replace(press, normal_force=np.full(len(PRESS_FORCES), 2.0))
    with pytest.raises(ValueError, match="at least two distinct normal forces"):
        calibrate(DESIGN, [single], shear, twist, "single")


def test_fit_refuses_paths_with_different_friction():
    press, shear, _ = synthetic_paths(CLOSED)
    _, _, twist = synthetic_paths(CLOSED, friction=0.5)
    with pytest.raises(ValueError, match="different friction coefficients"):
        calibrate(DESIGN, [press], shear, twist, "mixed")


def test_fit_refuses_a_bad_tag():
    press, shear, twist = synthetic_paths(CLOSED)
    with pytest.raises(ValueError, match="tag='has space'"):
        calibrate(DESIGN, [press], shear, twist, "has space")


# --- stored file ------------------------------------------------------------------------------------------------
def stored(parameters=None, tag="unit-test"):
    parameters = parameters or dataclasses.replace(TRUE_SETS["both_cop_terms"], source=f"fem:{tag}")
    provenance = {"tag": tag, "date": "2025-01-01T00:00:00+00:00", "package_version": "0.1.0",
                  "mesh": {"size_contact": 0.3}, "fem_cases": [], "fit": [], "diagnostics": {},
                  "held_out": {}}
    return StoredCalibration(DESIGN, parameters, provenance)


def test_file_round_trip(tmp_path):
    path = save_calibration(tmp_path / "calibration.json", stored())
    again = load_calibration(path, DESIGN)
    assert again.to_dict() == stored().to_dict()
    tip = ReducedFingertip.calibrated(path)
    assert tip.parameters == stored().parameters and tip.design == DESIGN
    assert load_calibrated(path).parameters == stored().parameters


def test_non_finite_number_is_named_and_nothing_is_written(tmp_path):
    bad = stored()
    bad.provenance["diagnostics"] = {"settlement": [0.1, float("nan")]}
    with pytest.raises(ValueError, match=r"non-finite number at provenance\.diagnostics\.settlement\.1"):
        save_calibration(tmp_path / "calibration.json", bad)
    assert not list(tmp_path.iterdir())


def _write(tmp_path, data):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize("where, key, match", [
    (None, "extra", r"unknown keys \['extra'\]"),
    ("design", "bump_count", r"design: unknown keys \['bump_count'\]"),
    ("parameters", "stiffness", r"parameters: unknown keys \['stiffness'\]"),
    ("provenance", "comment", r"provenance: unknown keys \['comment'\]"),
])
def test_file_with_unknown_keys_is_refused(tmp_path, where, key, match):
    data = stored().to_dict()
    (data if where is None else data[where])[key] = 1
    with pytest.raises(ValueError, match=match):
        load_calibration(_write(tmp_path, data))


@pytest.mark.parametrize("where, key", [(None, "provenance"), ("design", "pitch"), ("parameters", "kernel_spread"),
                                        ("provenance", "fit")])
def test_file_with_missing_keys_is_refused(tmp_path, where, key):
    data = stored().to_dict()
    del (data if where is None else data[where])[key]
    with pytest.raises(ValueError, match=rf"missing keys \['{key}'\]"):
        load_calibration(_write(tmp_path, data))


def test_file_of_another_design_is_refused(tmp_path):
    path = save_calibration(tmp_path / "calibration.json", stored())
    other = dataclasses.replace(DESIGN, youngs_modulus=0.5)
    with pytest.raises(ValueError, match=r"another fingertip design \(youngs_modulus: stored 0.3, expected 0.5\)"):
        ReducedFingertip.calibrated(path, other)


def test_file_with_closed_form_parameters_is_refused(tmp_path):
    data = stored().to_dict()
    data["parameters"]["source"] = "closed_form"
    with pytest.raises(ValueError, match="must start with 'fem:'"):
        load_calibration(_write(tmp_path, data))


def test_file_with_out_of_range_parameter_is_refused(tmp_path):
    data = stored().to_dict()
    data["parameters"]["moment_arm"] = -1.0
    with pytest.raises(ValueError, match=r"parameters: moment_arm=-1.0 outside allowed range"):
        load_calibration(_write(tmp_path, data))


def test_packaged_calibration_is_the_default_design_fitted_on_fem():
    packaged = load_calibration(design=DESIGN)
    assert PACKAGED_CALIBRATION.exists()
    assert packaged.parameters.source.startswith("fem:bench3x3")
    assert packaged.provenance["mesh"]["dofs"] > 0
    assert {fit["parameter"] for fit in packaged.provenance["fit"]} >= {
        "normal_stiffness", "radius_coefficient", "tangential_modulus", "torsional_modulus", "kernel_spread",
        "cop_gain", "moment_arm"}
    assert ReducedFingertip.calibrated().parameters == packaged.parameters


# --- the packaged calibration against a coarse held-out FEM path ----------------------------------------------------
# Largest |relative error| of the packaged model on the press held out at 1 N and 4 N, as `python -m studies
# reduced-calibration --quick` measured it on this coarse mesh (fig9's quick mesh, h = 0.7 mm; the CSV's "packaged"
# columns: depth, the mean of the nine per-bump radius rows, the largest per-bump base spread). Re-measured on the
# gmsh mesh (issue 17; the packaged calibration was fitted on fTetWild meshes, which gave 0.020 / 0.034 / 0.048 here):
MEASURED_COARSE = {"depth": 0.042, "contact_radius": 0.057, "base_spread": 0.079}
# The mesh is now the same on every machine; the allowance below was set when fTetWild meshes of the same settings
# differed between runs: a re-meshing at h = 0.7 mm is taken to move these FEM values by no more than refining to
# h = 0.3 mm moves them, measured between the quick and the default study runs: depth 0.3 %, mean bump radius
# 3.2 %, per-bump base spread 2.7 %. The closed-form model is 11 % off in depth and 42 % in base spread here: the
# test tells the two apart.
MESH_VARIATION = {"depth": 0.003, "contact_radius": 0.032, "base_spread": 0.027}


def test_packaged_calibration_matches_a_held_out_fem_press():
    from contact.solver import prepare, solve_scene
    from studies.reduced_calibration import StudyPlan, build_scenes

    _, held_out = build_scenes(StudyPlan.default(quick=True))
    scene = held_out["press_1N_4N"]
    fem = PathSamples.from_result(solve_scene(scene, prepare(scene)), DESIGN, "press_1N_4N")
    tip = load_calibrated(design=DESIGN)
    count = len(fem.load_kind)
    model = PathSamples.from_reduced(tip, "press_1N_4N", fem.load_kind, fem.normal_force, fem.friction,
                                     np.zeros((count, 3)), "displacement")
    errors = {
        "depth": np.abs(model.depth / fem.depth - 1.0).max(),
        # the mean over the nine bumps: single radii are quantised by the mesh (+-h/2 on a ~1.3 mm radius)
        "contact_radius": np.abs(model.bump_contact_radius.mean(axis=1) / fem.bump_contact_radius.mean(axis=1)
                                 - 1.0).max(),
        "base_spread": np.abs(np.sqrt(model.base_second_moment / fem.base_second_moment) - 1.0).max()}
    for quantity, error in errors.items():
        assert error <= MEASURED_COARSE[quantity] + MESH_VARIATION[quantity], quantity
