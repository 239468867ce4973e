"""A design judged by its grasp: each design calibrated on its own FEM (held-out error against that FEM, force balance
of its fields, the cache shared by designs that differ only in the sensor), its closed-loop columns in the design
table (typed, counts that add up, the Wilson interval against its closed form), designs the model cannot represent
refused with the reason, and bad closed-loop settings refused by name."""

import dataclasses
import math

import numpy as np
import pandas as pd
import pytest

from contact.recovery import tributary_areas
from contact.reduced import ArrayFingertipDesign
from contact.reduced.design_fit import FitPlan, fit_fingertip, unrepresentable
from controller.design import DesignStudy, FingertipDesign, design_sweep

# two bumps side by side (the cheapest array the closed loop can run), on a base half a pitch beyond them
PAIR = FingertipDesign(rows=1, cols=2, pitch=20.0, bump_radius=7.0, base_width=40.0, base_depth=20.0)
SINGLE = FingertipDesign(rows=1, cols=1, pitch=40.0, bump_radius=14.0)
# the quick sensor study of tests/test_design.py, one trial per Table I object, a coarse calibration mesh (the
# press's smallest contact still sets h = 0.84 mm: _fit_plan.contact_size)
STUDY = DesignStudy(size_contact=0.7, size_base=1.5, noise_draws=2, closed_loop=True, grasp_trials=1,
                    calibration_size_contact=1.0, calibration_size_base=2.0)
# Held-out errors of a design's own calibration against its FEM (largest over the held-out increments and bumps).
# depth and twist: the model's power laws on the FEM's force targets, a few per cent (the 3x3 at h = 0.7 mm:
# 1.5 % and 2.0 %); contact radius: the FEM's sqrt(A_i / pi) is quantised by the tributary areas, +-h/2 on
# ~2 mm radii at h = 0.84 mm (the 3x3 at h = 0.7 mm: 6.2 %); plate shift: Mindlin's law with one G* for every
# force (3.2 %); the response surface interpolates its fields linearly in log P between levels 2-3x apart (4.4 %)
FIT_TOLERANCE = {"depth": 0.05, "contact_radius": 0.12, "plate_shift": 0.08, "twist_angle": 0.06,
                 "base_field": 0.08, "cop_shift": 0.05}


@pytest.fixture(scope="module")
def grasp_sweep(tmp_path_factory):
    """A closed-loop sweep of the pair at two sensor pitches and of one bump, on a cache of its own: the pair's
    calibration is computed here, not read from an earlier run."""
    cache = tmp_path_factory.mktemp("cache")
    out = tmp_path_factory.mktemp("designs")
    designs = [PAIR, dataclasses.replace(PAIR, sensor_pitch=2.0), SINGLE]
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("FINGERTIP_CACHE", str(cache))
        table = design_sweep(designs, STUDY, out_dir=out, scheduler="synchronous", progress=False)
        fitted = fit_fingertip(_array(PAIR), FitPlan(size_contact=1.0, size_base=2.0))
    return out, cache, designs, table, fitted


def _array(design):
    from controller.design import array_design

    return array_design(design)


def test_a_design_reproduces_its_own_fem_on_held_out_paths(grasp_sweep):
    *_, fitted = grasp_sweep
    assert fitted.cached                                             # the sweep computed it; this read it back
    for quantity, tolerance in FIT_TOLERANCE.items():
        assert 0.0 < fitted.errors[quantity] < tolerance, (quantity, fitted.errors)
    # vertical equilibrium: a unit normal load on a bump puts 1 N on the base; a tangential load only a couple.
    # float32 storage (2^-24) summed over ~1e3 nodes: 1e-5
    response = fitted.response
    weights = tributary_areas(response.positions, response.triangles)
    assert np.abs(response.normal_fields @ weights - 1.0).max() < 1e-5
    assert np.abs(response.shear_fields @ weights).max() < 1e-5 * (np.abs(response.shear_fields) @ weights).max()
    # the contact radius law against Hertz: the FEM's c_a within the quantisation above of (3 R / (4 E*))^(1/3)
    design = fitted.design
    e_star = design.youngs_modulus / (1.0 - design.poissons_ratio**2)
    hertz = (3.0 * design.bump_radius / (4.0 * e_star)) ** (1.0 / 3.0)
    assert fitted.parameters.radius_coefficient == pytest.approx(hertz, rel=FIT_TOLERANCE["contact_radius"])


def test_designs_differing_only_in_the_sensor_share_the_fem_and_the_calibration(grasp_sweep):
    _, _, _, table, fitted = grasp_sweep
    first, second = table.iloc[0], table.iloc[1]
    assert first["fit_key"] == second["fit_key"] == fitted.key
    assert first["calibration_fem"] > 0.0 and first["calibration_cached"] == 0.0     # computed by the sweep
    assert second["calibration_wall"] == 0.0 and second["calibration_cached"] == 1.0
    for column in [c for c in table if c.startswith("fit_") and c.endswith("_error")]:
        assert first[column] == second[column] == pytest.approx(fitted.errors[column[4:-6]], rel=0, abs=0)
    assert first["torque_capacity"] == second["torque_capacity"] and second["fem_wall"] == 0.0


def test_the_sweep_has_typed_closed_loop_columns_that_add_up(grasp_sweep):
    from controller.design import GRASP_METRICS

    out, _, _, table, _ = grasp_sweep
    for column, (_, _, _, kind) in GRASP_METRICS.items():
        assert str(table[column].dtype) == kind, column
    for _, row in table.iloc[:2].iterrows():
        assert row["status"] == "ok" and row["grasp_status"] == "ok"
        assert row["grasp_trials"] == 3 * STUDY.grasp_trials
        outcomes = row["grasp_held"] + row["grasp_turned_out"] + row["grasp_dropped"] + row["grasp_crushed"]
        assert outcomes == row["grasp_trials"]                       # every trial has exactly one outcome
        assert row["grasp_success_rate"] == row["grasp_held"] / row["grasp_trials"]
        assert row["grasp_success_low"] <= row["grasp_success_rate"] <= row["grasp_success_high"]
        assert row["gross_slips_detected_before"] <= row["gross_slips"] <= row["grasp_trials"]
        # every held object moves in the fingers from the lift's start at least by the gel's elastic shear
        assert 0.0 < row["grasp_slide_median"] <= row["grasp_slide_max"]
        assert row["bench_wall"] > 0.0 and row["trials_wall"] > 0.0
    import pyarrow  # noqa: F401

    path = out / "table.parquet"
    table.to_parquet(path, index=False)
    assert pd.read_parquet(path)["grasp_trials"].dtype == "Int64"


def test_a_design_the_model_cannot_represent_is_refused_with_the_reason(grasp_sweep):
    _, _, _, table, _ = grasp_sweep
    single = table.iloc[2]
    assert single["status"] == "ok" and single["grasp_status"] == "refused"      # its sensor metrics are kept
    assert "one bump" in single["grasp_error"] and not pd.isna(single["translational_error"])
    assert pd.isna(single["grasp_success_rate"]) and pd.isna(single["fit_depth_error"])
    one = ArrayFingertipDesign(rows=1, cols=1, pitch=40.0, bump_radius=14.0)
    assert "eq. 9's rigid transform needs two bumps" in unrepresentable(one)
    with pytest.raises(ValueError, match="design 1x1 cannot be calibrated: one bump"):
        fit_fingertip(one)
    from controller.design import grasp_refusal

    wide = dataclasses.replace(PAIR, base_depth=40.0)
    assert "base_depth=40 mm is not 1 x pitch = 20 mm" in grasp_refusal(wide)


def test_a_rerun_of_the_closed_loop_sweep_computes_nothing(grasp_sweep, monkeypatch):
    out, cache, designs, table, _ = grasp_sweep
    import contact.reduced.design_fit
    import controller.closed_loop

    monkeypatch.setenv("FINGERTIP_CACHE", str(cache))
    monkeypatch.setattr(contact.reduced.design_fit, "_fit", lambda *a: pytest.fail("a recorded design was fitted"))
    monkeypatch.setattr(controller.closed_loop, "run_trial", lambda *a, **k: pytest.fail("a trial was run again"))
    again = design_sweep(designs, STUDY, out_dir=out, scheduler="synchronous", progress=False)
    pd.testing.assert_frame_equal(again, table)


def test_a_sensor_only_sweep_keeps_its_ids_and_leaves_the_closed_loop_empty():
    from controller.design import CLOSED_LOOP_COLUMNS, design_id, design_table

    sensor_only = dataclasses.replace(STUDY, closed_loop=False)
    # the closed-loop fields leave a sensor-only study's document, and so its design ids, as they were
    assert "grasp_trials" not in sensor_only.document() and "closed_loop" not in sensor_only.document()
    assert design_id(PAIR, sensor_only) == design_id(PAIR, dataclasses.replace(sensor_only, grasp_trials=7))
    assert design_id(PAIR, STUDY) != design_id(PAIR, dataclasses.replace(STUDY, grasp_trials=7))
    record = {"case_id": "x", "status": "ok", "design": dataclasses.asdict(PAIR), "metrics": {}}
    row = design_table([record]).iloc[0]
    assert row["grasp_status"] == "off" and all(pd.isna(row[column]) for column in CLOSED_LOOP_COLUMNS)


def test_the_default_grasp_seed_is_the_held_out_seed():
    from controller.closed_loop import HELD_OUT_SEED

    assert DesignStudy().grasp_seed == HELD_OUT_SEED


@pytest.mark.parametrize("successes, trials", [(0, 9), (7, 9), (30, 30), (13, 30)])
def test_the_wilson_interval_is_its_closed_form(successes, trials):
    from controller.design import wilson_interval

    # Wilson (1927): (p + z^2 / 2n +- z sqrt(p (1 - p) / n + z^2 / 4n^2)) / (1 + z^2 / n), z the 97.5 % quantile
    z, p = 1.959963984540054, successes / trials
    centre, half = p + z**2 / (2 * trials), z * math.sqrt(p * (1 - p) / trials + z**2 / (4 * trials**2))
    low, high = wilson_interval(successes, trials)
    assert low == pytest.approx((centre - half) / (1 + z**2 / trials), abs=1e-12)
    assert high == pytest.approx((centre + half) / (1 + z**2 / trials), abs=1e-12)


def test_detection_lead_time_reads_the_first_gross_slip_of_lift_and_hold():
    from types import SimpleNamespace

    from controller.design._grasp import detection_lead_time

    phases = ["grasp"] * 2 + ["lift"] * 3 + ["hold"] * 3
    sliding = [4, 4, 1, 2, 4, 4, 0, 0]               # 2 bumps per fingertip: 4 is all of them; in grasp it is ignored
    trace = {"time": [0.01 * i for i in range(8)], "phase": phases, "sliding_bumps": sliding}
    early = SimpleNamespace(trace=trace, slip_events=[(0.02, 0.5, "bump"), (0.06, 0.4, "array")])
    assert detection_lead_time(early, 2) == pytest.approx(0.04 - 0.02)            # onset at frame 4
    late = SimpleNamespace(trace=trace, slip_events=[(0.07, 0.4, "array")])
    assert detection_lead_time(late, 2) == pytest.approx(0.04 - 0.07)             # negative: detected after
    assert math.isnan(detection_lead_time(SimpleNamespace(trace=trace, slip_events=[]), 2))
    still = dict(trace, sliding_bumps=[4, 4, 0, 0, 3, 0, 0, 0])
    assert detection_lead_time(SimpleNamespace(trace=still, slip_events=[]), 2) is None


CLOSED_LOOP_SETTINGS = [
    ({"closed_loop": "yes"}, r"closed_loop='yes' must be true or false"),
    ({"closed_loop": 1}, r"closed_loop=1 must be true or false"),
    ({"grasp_trials": 0}, r"grasp_trials=0 outside allowed range \[1, 1000\]"),
    ({"grasp_trials": 2.5}, r"grasp_trials=2.5 is not an integer"),
    ({"grasp_objects": "eclair"}, r"grasp_objects='eclair' must be a non-empty list of names of \['bottle_upright'"),
    ({"grasp_objects": ["cup"]}, r"grasp_objects=\['cup'\]: unknown \['cup'\]; allowed: \['bottle_upright'"),
    ({"grasp_objects": ["eclair", "eclair"]}, r"grasp_objects=\['eclair', 'eclair'\]: a name repeats"),
    ({"grasp_seed": -1}, r"grasp_seed=-1 outside allowed range"),
    ({"plant_spread": 0.8}, r"plant_spread=0.8 outside allowed range \[0.0, 0.5\]"),
    ({"plant_spread": "10 %"}, r"plant_spread='10 %' \(a string\) is not a number"),
    ({"calibration_size_contact": 0.0}, r"calibration_size_contact=0.0 outside allowed range \(0.0, inf\) mm"),
    ({"calibration_size_base": True}, r"calibration_size_base=True \(a bool\) is not a number"),
]


@pytest.mark.parametrize("study, message", CLOSED_LOOP_SETTINGS)
def test_bad_closed_loop_settings_are_refused_by_name(study, message):
    with pytest.raises(ValueError, match=message):
        DesignStudy(**study)


@pytest.mark.parametrize("study, message", CLOSED_LOOP_SETTINGS[::3])
def test_bad_closed_loop_settings_in_a_design_file_exit_2(tmp_path, capsys, monkeypatch, study, message):
    import contact.solver
    from studies.__main__ import main
    from toml_files import write_toml

    monkeypatch.setattr(contact.solver, "prepare", lambda *a, **k: pytest.fail("a refused input was solved"))
    path = write_toml(tmp_path / "designs.toml", {"name": "bad", "study": study})
    code = main(["design", str(path), "--out", str(tmp_path / "out"), "--scheduler", "synchronous", "--quiet"])
    output = "".join(capsys.readouterr())
    assert code == 2 and "Traceback" not in output
    import re

    assert re.search(message, output) and str(path) in output


def test_fit_plans_refuse_bad_values_by_name():
    with pytest.raises(ValueError, match=r"fit plan press_levels=\[0.5\] needs at least two forces"):
        FitPlan(press_levels=(0.5,))
    with pytest.raises(ValueError, match=r"fit plan load_ratios\[1\]=1.2 outside allowed range \(0.0, 1.0\)"):
        FitPlan(load_ratios=(0.3, 1.2))
    with pytest.raises(ValueError, match=r"fit plan size_contact=True must be a number"):
        FitPlan(size_contact=True)


def test_the_closed_loop_cuts_the_bump_law_at_its_own_designs_radius(grasp_sweep):
    """The contact kernel's depth limit (C_MAX_DEPTH: a bump pressed past its radius carries no force) is the radius
    of the plant's design, not the shipped one: 7 mm for the pair, 0.35 x 40 / 3 mm for the packaged 3x3."""
    from controller.closed_loop import TABLE_I_OBJECTS, GraspWorld, TrialSettings
    from controller.closed_loop import _kernel as K
    from controller.design import SensorModel
    from controller.plant import FingertipPlant, PlantFactors, PlantModel

    *_, fitted = grasp_sweep
    obj = TABLE_I_OBJECTS["bottle_upright"]
    for model, radius in ((PlantModel.from_fit(fitted), PAIR.bump_radius), (None, 0.35 * 40.0 / 3.0)):
        array = PAIR.sensor(SensorModel.CAPACITIVE) if model is not None else None
        plant = FingertipPlant(PlantFactors(bump_height=0.1), array, model=model)
        world = GraspWorld(obj, TrialSettings(), plant=plant)
        assert world.bridge.config[K.C_MAX_DEPTH] == radius      # set from the design's own number, not computed
