"""A design judged by its grasp: its own FEM calibration -> its plant and its estimator's bench -> Table I trials.

For a ``FingertipDesign`` the closed loop (``DesignStudy.closed_loop``) runs, after the sensor study:

1. ``contact.reduced.design_fit.fit_fingertip``: the reduced bump laws and each bump's FEM base response, fitted
   on the design's own FEM paths and scored on held-out ones (cached on disk by the mechanical design and the fit
   plan: designs that differ only in their sensor share it);
2. the plant (``controller.plant.PlantModel.from_fit``) read by the design's capacitive array, and the estimator's
   sensor model fitted on that design's bench (``controller.closed_loop.estimator_bench``: a nominal build of the
   same model and array; the estimator sees readings and the rig's loads only);
3. ``grasp_trials`` randomised trials of each Table I object (``random_settings`` from ``grasp_seed``: the same
   frictions, jitter, noise and plant factors for every design, so that designs are compared on the same draws),
   each on its own build (its plant factors within +-``plant_spread``), with the incipient-slip controller as
   shipped.

Metrics (``GRASP_METRICS``): success rate (held) with its 95 % Wilson interval, outcomes, the settled grip over the
trial's own slip limit, the slide in the fingers from the lift's start, the friction estimate's error, and the
detection lead time before gross slip; and the calibration's held-out errors against the design's FEM
(``FIT_METRICS``).
"""

from __future__ import annotations

import math
import time

import numpy as np

__all__ = ["GRASP_METRICS", "FIT_METRICS", "grasp_refusal", "array_design", "fit_plan", "grasp_metrics",
           "fit_metrics", "wilson_interval", "detection_lead_time"]

# relative: a base layer half a pitch beyond the outer bump centres; design files round the pitch (13.3333 mm for
# 40 / 3: 2.5e-6 of the 40 mm footprint)
FOOTPRINT_TOLERANCE = 1e-4

# name -> (meaning, unit, better, type): the closed-loop columns of the design table
GRASP_METRICS = {
    "grasp_trials": ("closed-loop trials run (Table I objects x grasp_trials)", "1", None, "Int64"),
    "grasp_held": ("trials held (success: not crushed, not dropped, not turned out)", "1", None, "Int64"),
    "grasp_success_rate": ("held / trials", "-", "higher", "Float64"),
    "grasp_success_low": ("95 % Wilson interval of the success rate, lower bound", "-", None, "Float64"),
    "grasp_success_high": ("95 % Wilson interval of the success rate, upper bound", "-", None, "Float64"),
    "grasp_feasible": ("trials whose slip limit lies below the object's crush force", "1", None, "Int64"),
    "grasp_turned_out": ("trials turned out of the grasp (> 0.15 rad)", "1", "lower", "Int64"),
    "grasp_dropped": ("trials dropped", "1", "lower", "Int64"),
    "grasp_crushed": ("trials crushed", "1", "lower", "Int64"),
    "grip_over_slip_limit": ("mean settled grip over the trial's own slip limit (its build's bump laws), held "
                             "trials", "-", "lower", "Float64"),
    "grip_over_slip_limit_max": ("largest settled grip over slip limit, held trials", "-", None, "Float64"),
    "grip_over_slip_limit_sd": ("standard deviation (ddof 1) of the settled grip over slip limit over the held "
                                "trials (two or more)", "-", None, "Float64"),
    "grasp_slide_median": ("median over the held trials of the largest slide in the fingers from the lift's start "
                           "(the gel's elastic shear and a slip caught in the lift)", "mm", "lower", "Float64"),
    "grasp_slide_max": ("largest slide in the fingers from the lift's start, held trials", "mm", None, "Float64"),
    "friction_estimate_error": ("median |mu_hat / mu - 1| over the trials with a friction estimate", "-", "lower",
                                "Float64"),
    "gross_slips": ("trials whose grasp slid as a whole (every bump of both fingertips sliding) in lift or hold",
                    "1", None, "Int64"),
    "gross_slips_detected_before": ("of those, trials whose controller detected a slip before the gross slip",
                                    "1", "higher", "Int64"),
    "detection_lead_time": ("median time from the controller's first slip detection to the grasp's gross slip "
                            "over the trials that slid (negative: the first detection came after it; a trial with "
                            "no detection is not counted)", "s", "higher", "Float64"),
}
# the calibration's largest held-out relative errors against the design's own FEM (contact.reduced.design_fit)
FIT_METRICS = {f"fit_{name}_error": (meaning, "-", "lower", "Float64")
               for name, meaning in (("depth", "plate approach of a press"),
                                     ("contact_radius", "per-bump contact radius"),
                                     ("plate_shift", "plate translation at the force targets"),
                                     ("twist_angle", "plate twist at the torque targets"),
                                     ("base_field", "per-bump base-pressure field (relative L2)"),
                                     ("cop_shift", "per-bump cell CoP shift over the increment's largest"))}


def grasp_refusal(design) -> str | None:
    """Why the closed loop cannot run ``design`` (``contact.reduced.design_fit.unrepresentable``, a base layer that
    is not half a pitch beyond the outer bumps), or None."""
    from contact.reduced.design_fit import unrepresentable

    reason = unrepresentable(array_design(design, check=False))
    if reason:
        return reason
    for name, size, count in (("base_width", design.base_width, design.cols),
                              ("base_depth", design.base_depth, design.rows)):
        if not math.isclose(size, count * design.pitch, rel_tol=FOOTPRINT_TOLERANCE):
            return (f"{name}={size:g} mm is not {count} x pitch = {count * design.pitch:g} mm: the reduced model's "
                    f"base layer ends half a pitch beyond the outer bumps")
    return None


def array_design(design, check: bool = True):
    """The ``contact.reduced.ArrayFingertipDesign`` of a FingertipDesign (ValueError with the reason when the
    closed loop cannot represent it and ``check``)."""
    from contact.reduced import ArrayFingertipDesign

    if check:
        reason = grasp_refusal(design)
        if reason:
            raise ValueError(f"design {design.rows}x{design.cols} refused by the closed loop: {reason}")
    return ArrayFingertipDesign(rows=design.rows, cols=design.cols, bump_radius=design.bump_radius,
                                pitch=design.pitch, base_thickness=design.base_thickness,
                                youngs_modulus=design.youngs_modulus, poissons_ratio=design.poissons_ratio)


def fit_plan(study):
    """The FitPlan of a study: its calibration mesh sizes [mm], the plan's loads."""
    from contact.reduced.design_fit import FitPlan

    return FitPlan(size_contact=study.calibration_size_contact, size_base=study.calibration_size_base)


def fit_metrics(fitted) -> dict:
    """FIT_METRICS of a FittedFingertip."""
    return {f"fit_{name}_error": float(value) for name, value in fitted.errors.items()}


def wilson_interval(successes: int, trials: int) -> tuple[float, float]:
    """95 % Wilson score interval of a success rate (scipy.stats.binomtest)."""
    from scipy.stats import binomtest

    interval = binomtest(int(successes), int(trials)).proportion_ci(confidence_level=0.95, method="wilson")
    return float(interval.low), float(interval.high)


def detection_lead_time(result, bumps: int) -> float | None:
    """Time [s] from the controller's first slip event to the first frame of lift or hold in which every bump of
    both fingertips slides (the grasp's gross slip; the plant's state, read here only to score the trial):
    positive when the detection came first; None when the grasp never slid as a whole, NaN when it slid and the
    controller detected nothing."""
    trace = result.trace
    phases = np.asarray(trace["phase"])
    sliding = np.asarray(trace["sliding_bumps"]) >= 2 * bumps
    gross = np.flatnonzero(sliding & np.isin(phases, ("lift", "hold")))
    if gross.size == 0:
        return None
    onset = float(trace["time"][gross[0]])
    detections = [event[0] for event in result.slip_events]
    return onset - min(detections) if detections else math.nan


def _trial_jobs(study):
    """(object, settings) of every trial: grasp_trials per object from ``grasp_seed`` (drawn for all objects in
    order, whatever ``grasp_objects`` keeps, as Table I does)."""
    from controller.closed_loop import TABLE_I_OBJECTS, random_settings

    rng = np.random.default_rng(study.grasp_seed)
    jobs = []
    for name, obj in TABLE_I_OBJECTS.items():
        for _ in range(study.grasp_trials):
            settings = random_settings(rng, plant_spread=study.plant_spread)
            if name in study.grasp_objects:
                jobs.append((obj, settings))
    return jobs


def grasp_metrics(design, study, fitted) -> tuple[dict, dict]:
    """GRASP_METRICS of ``design`` with its calibration ``fitted`` (FittedFingertip), and stage timings [s]."""
    from controller.closed_loop import estimator_bench, required_grip_force, run_trial
    from controller.plant import FingertipPlant, PlantModel, SensorPlane, plant_mechanics

    from ._spec import SensorModel

    model = PlantModel.from_fit(fitted)
    array = design.sensor(SensorModel.CAPACITIVE)              # the build's array: capacitive, whatever the study's
    tic = time.perf_counter()
    estimator_bench(SensorPlane.FEM, model, array)             # the estimator's bench of this design (cached)
    timings = {"bench_wall": time.perf_counter() - tic}
    tic = time.perf_counter()
    outcomes, ratios, slides, errors, leads, gross = [], [], [], [], [], 0
    feasible = 0
    for obj, settings in _trial_jobs(study):
        plant = FingertipPlant(settings.plant, array, noise=settings.sensor_noise, seed=settings.seed,
                               plane=SensorPlane.FEM, model=model)
        result = run_trial(obj, settings, plant=plant)
        required = required_grip_force(obj, settings.friction_coefficient, plant_mechanics(settings.plant, model),
                                       settings.plant.friction_anisotropy)
        outcomes.append(result.outcome)
        feasible += int(required < obj.crush_force)
        if result.outcome == "held":
            ratios.append(result.hold_force_settled / required)
            slides.append(result.grasp_slip_mm)
        if math.isfinite(result.friction_estimate):
            errors.append(abs(result.friction_estimate / settings.friction_coefficient - 1.0))
        lead = detection_lead_time(result, design.bumps)
        if lead is not None:
            gross += 1
            if math.isfinite(lead):
                leads.append(lead)
    timings["trials_wall"] = time.perf_counter() - tic
    trials, held = len(outcomes), outcomes.count("held")
    low, high = wilson_interval(held, trials)
    metrics = {"grasp_trials": trials, "grasp_held": held, "grasp_success_rate": held / trials,
               "grasp_success_low": low, "grasp_success_high": high, "grasp_feasible": feasible,
               "grasp_turned_out": outcomes.count("turned_out"), "grasp_dropped": outcomes.count("dropped"),
               "grasp_crushed": outcomes.count("crushed"),
               "grip_over_slip_limit": float(np.mean(ratios)) if ratios else None,
               "grip_over_slip_limit_max": float(np.max(ratios)) if ratios else None,
               "grip_over_slip_limit_sd": float(np.std(ratios, ddof=1)) if len(ratios) > 1 else None,
               "grasp_slide_median": float(np.median(slides)) if slides else None,
               "grasp_slide_max": float(np.max(slides)) if slides else None,
               "friction_estimate_error": float(np.median(errors)) if errors else None,
               "gross_slips": gross, "gross_slips_detected_before": int(sum(lead > 0.0 for lead in leads)),
               "detection_lead_time": float(np.median(leads)) if leads else None}
    return metrics, timings
