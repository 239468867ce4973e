"""One task of a design sweep: designs sharing a FEM solution, solved once, each read by its own sensor."""

from __future__ import annotations

import dataclasses
import math
import os
import socket
import time

from ._metrics import capacity_metrics, drop_metrics, estimation_metrics, mesh_metrics
from ._spec import DesignStudy, FingertipDesign, SensorModel, design_scenes

__all__ = ["evaluate_designs", "design_record"]


def design_record(case_id: str, design, status: str, error: str | None, metrics: dict, increments: list,
                  timings: dict, group: str, grasp: dict | None = None) -> dict:
    """The JSON record of one design: its fields, status, error, metrics, increment rows, timings, worker, and the
    closed loop's ``grasp`` {"status": off / ok / refused / failed, "error": reason, "fit_key": calibration}."""
    return {"case_id": case_id, "status": status, "error": error, "design": dataclasses.asdict(design),
            "metrics": metrics, "increments": increments, "timings": timings, "group": group,
            "worker": f"{socket.gethostname()}:{os.getpid()}",
            "grasp": dict(grasp) if grasp is not None else {"status": "off", "error": "", "fit_key": ""}}


def _group_fit(design, study) -> tuple[object, dict, dict]:
    """The calibration of a group's mechanical design: (FittedFingertip or None, grasp info, timings)."""
    from ._grasp import array_design, fit_plan, grasp_refusal

    if not study.closed_loop:
        return None, {"status": "off", "error": "", "fit_key": ""}, {}
    reason = grasp_refusal(design)
    if reason:
        return None, {"status": "refused", "error": reason, "fit_key": ""}, {}
    from contact.reduced.design_fit import fit_fingertip

    start = time.perf_counter()
    try:
        fitted = fit_fingertip(array_design(design), fit_plan(study))
    except (ValueError, RuntimeError, ArithmeticError) as failure:
        return None, {"status": "failed", "error": f"calibration: {type(failure).__name__}: {failure}",
                      "fit_key": ""}, {"calibration_wall": time.perf_counter() - start}
    timings = {"calibration_wall": time.perf_counter() - start, "calibration_cached": float(fitted.cached),
               "calibration_fem": float(fitted.timings.get("fem", math.nan))}
    return fitted, {"status": "ok", "error": "", "fit_key": fitted.key}, timings


def _grasp(design, study, fitted, grasp: dict) -> tuple[dict, dict, dict]:
    """The closed-loop metrics of one design (``_grasp.grasp_metrics``) with the calibration's errors: (metrics,
    grasp info, timings); a failure is recorded, not raised."""
    from ._grasp import fit_metrics, grasp_metrics

    if fitted is None:
        return {}, dict(grasp), {}
    metrics = fit_metrics(fitted)
    try:
        found, timings = grasp_metrics(design, study, fitted)
    except (ValueError, RuntimeError, ArithmeticError) as failure:
        return metrics, {**grasp, "status": "failed", "error": f"closed loop: {type(failure).__name__}: {failure}"}, {}
    return {**metrics, **found}, dict(grasp), timings


def _increment_rows(result, path: str, ratios, estimates, bumps_truth=None) -> list[dict]:
    """Rows of one path; ``estimates`` (t,) the estimated shift [mm] or angle [rad], ``bumps_truth`` (t,) what they
    estimate: the bumps' mean shear displacement [mm] or their eq. 9 rotation [rad] (``estimation_metrics``)."""
    rows = []
    for number, increment in enumerate(result.increments):
        bumps = increment.bumps
        row = {"path": path, "increment": number, "load_kind": increment.load_kind,
               "load_ratio": (float(ratios[number - 1]) if number else 0.0) if path == "shear" else None,
               "normal_force": increment.normal_force, "tangential_force": increment.tangential_force[0],
               "torque": increment.torque, "shift": increment.shift[0], "angle": increment.angle,
               "stick_ratio": increment.stick_ratio, "contact_area": increment.contact_area,
               "least_bump_margin": float(bumps.gross_slip_margin.min()),
               "least_bump_stick_ratio": float(bumps.stick_ratio.min()),
               "bump_shift": None, "bump_angle": None, "estimated_shift": None, "estimated_angle": None}
        if number and bumps_truth is not None:
            row["bump_shift" if path == "shear" else "bump_angle"] = float(bumps_truth[number - 1])
        if number and estimates is not None:
            key = "estimated_shift" if path == "shear" else "estimated_angle"
            row[key] = float(estimates[number - 1])
        rows.append(row)
    return rows


def evaluate_designs(items: list[tuple[str, dict, dict]], cases_dir: str | None = None, group: str = ""):
    """Evaluate designs that share one FEM solution (equal ``_fem_key``): yield one record per design, in order.

    ``items``: (case_id, design fields, study document). The shear and twist paths are solved once (one prepare,
    one set of compliance columns), then each design's sensor reads them. A failure keeps what was computed before
    it (the metrics of the shear path when the twist path fails) and records the error. Writes each record to
    ``cases_dir/<case_id>.json`` when given. This is the task ``design_sweep`` runs (``fem.task_runner``).
    """
    from contact.result import ContactUnderResolved, LoadNotCarried, PathNotCompleted
    from contact.solver import prepare, solve_scene
    from fem.task_runner import write_record

    designs = [(case_id, FingertipDesign(**fields), DesignStudy(**study)) for case_id, fields, study in items]
    first, study = designs[0][1], designs[0][2]
    shear_scene, twist_scene = design_scenes(first, study)
    timings, fem_metrics, results, error = {}, {}, {}, None
    start = time.perf_counter()
    try:
        prepared = prepare(shear_scene)
        timings["prepare"] = time.perf_counter() - start
        solve_start = time.perf_counter()
        results["shear"] = solve_scene(shear_scene, prepared)
        press = results["shear"].increments[0]
        fem_metrics.update(capacity_metrics(press, results["shear"].candidate_positions,
                                            results["shear"].candidate_areas, shear_scene.body.center,
                                            study.friction_coefficient))
        fem_metrics.update(drop_metrics(results["shear"].increments[1:], study.load_ratios))
        fem_metrics.update(mesh_metrics(press, study.size_contact, first.bump_radius, first.youngs_modulus,
                                        first.poissons_ratio))
        if twist_scene is not None:
            results["twist"] = solve_scene(twist_scene, prepared)
        timings["solve"] = time.perf_counter() - solve_start
        timings.update({f"fem_{k}": float(v) for k, v in results["shear"].timings.items()})
        timings["dofs"] = results["shear"].mesh_info["dofs"]
    except (PathNotCompleted, LoadNotCarried, ContactUnderResolved, ValueError, RuntimeError) as failure:
        error = f"{type(failure).__name__}: {failure}"
    fem_seconds = time.perf_counter() - start
    fitted, grasp, fit_timings = _group_fit(first, study)      # one calibration for the group's mechanical design
    for case_id, design, study in designs:
        case_start = time.perf_counter()
        metrics = dict(fem_metrics)
        increments, status, message = [], "ok" if error is None else "failed", error
        if "shear" in results:                      # the shear path's metrics survive a failed twist path
            try:
                draws = range(study.noise_draws) if study.sensor is SensorModel.CAPACITIVE else (0,)
                estimated, estimates = estimation_metrics(results["shear"], results.get("twist"),
                                                          design.sensor(study.sensor), design.layout(), draws,
                                                          study.frames_per_state)
                metrics.update(estimated)
                increments = _increment_rows(results["shear"], "shear", study.load_ratios, estimates["shift"],
                                             estimates["bump_shift"])
                if "twist" in results:
                    increments += _increment_rows(results["twist"], "twist", (), estimates["angle"],
                                                  estimates["bump_angle"])
            except (ValueError, RuntimeError) as failure:
                status, message = "failed", f"{type(failure).__name__}: {failure}"
        bad = [key for key, value in metrics.items() if isinstance(value, float) and not math.isfinite(value)]
        if bad and status == "ok":
            status, message = "failed", f"non-finite metric(s) refused: {bad}"
            metrics = {key: (None if key in bad else value) for key, value in metrics.items()}
        case_timings = dict(timings, fem_wall=fem_seconds if case_id == designs[0][0] else 0.0,
                            sensor_wall=time.perf_counter() - case_start)
        closed, case_grasp, closed_timings = _grasp(design, study, fitted, grasp)
        metrics.update(closed)
        if case_id == designs[0][0]:
            case_timings.update(fit_timings)
        elif fit_timings:                         # the group's first design paid for the shared calibration
            case_timings.update({key: 0.0 for key in fit_timings}, calibration_cached=1.0)
        case_timings.update(closed_timings)
        if case_grasp["status"] == "failed" and status == "ok":      # the sensor's metrics are kept beside it
            status, message = "failed", case_grasp["error"]
        record = design_record(case_id, design, status, message, metrics, increments, case_timings, group,
                               case_grasp)
        if cases_dir is not None:
            write_record(cases_dir, record)
        yield record
