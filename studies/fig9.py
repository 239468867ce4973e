"""Fig. 9 (virtual bench): applied against estimated shear displacement, translation and rotation, 3x3 fingertip.

The paper's two-axis stage in simulation: the FEM fingertip (3x3 hemispheres, 40 x 40 mm) is pressed by a rigid
plate with 2 N, then shifted along x (translation) or twisted about the normal (rotation) by known amounts; a
3 mm-pitch sensor reads the base pressure; the estimator gives per-bump CoP displacements (gain calibrated on the
two smallest shifts of the translation run) and the eq. 9 rigid transform (theta, t_x, t_y). Regression line and R^2 as the paper
(which reports 15 % translational and 3 % rotational error with a strong linear correlation).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic

NAME = "fig9"
SENSOR_PITCH = 3.0


def run(out_dir, quick: bool = False) -> dict:
    """Two FEM runs (shift, twist); estimates, regression and errors; CSV, PNG, PDF."""
    from contact.solver import solve_scene
    from controller.estimation.calibration import calibrate_gain
    from controller.estimation.estimator import estimate_slip
    from controller.estimation.bench import (BENCH_SIZE_BASE, BENCH_SIZE_CONTACT, bench_scene, bump_layout,
                                             sensor_array, shifts_of)

    out_dir = Path(out_dir)
    shifts = (0.05, 0.1, 0.2) if quick else (0.04, 0.08, 0.12, 0.16, 0.2)       # >= 3 points: R^2 means something
    angles = (0.003, 0.006, 0.01) if quick else (0.002, 0.004, 0.006, 0.008, 0.01)
    size_contact, size_base = (0.7, 1.5) if quick else (BENCH_SIZE_CONTACT, BENCH_SIZE_BASE)
    array, layout = sensor_array(SENSOR_PITCH), bump_layout(3)
    start = time.perf_counter()
    translation = solve_scene(bench_scene(3, "shift", shifts, size_contact, size_base))
    rotation = solve_scene(bench_scene(3, "twist", angles, size_contact, size_base))
    readings, reference, cop_shift = shifts_of(translation, array, layout)
    truth = np.zeros_like(cop_shift)
    truth[1:, :, 0] = np.asarray(shifts)[:, None]
    calibration = calibrate_gain(cop_shift[1:3], truth[1:3])        # the two smallest shifts; all are estimated
    _store_calibration(out_dir / "fingertip_3x3_calibration.json", translation.scene, array, calibration)
    translated = estimate_slip(readings, array, layout, reference, calibration)
    twist_readings, twist_reference, _ = shifts_of(rotation, array, layout)
    twisted = estimate_slip(twist_readings, array, layout, twist_reference, calibration)
    rows = []
    for kind, applied, estimated in (
            ("translation", shifts, translated.transform.translation[1:, 0]),
            ("rotation", angles, twisted.transform.rotation[1:])):
        for a, e in zip(applied, estimated):
            rows.append(dict(case=kind, applied=a, estimated=float(e), error=float(e - a),
                             relative_error=float((e - a) / a), gain=calibration.gain))
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    wall = time.perf_counter() - start
    fits = {kind: _regression([r["applied"] for r in rows if r["case"] == kind],
                              [r["estimated"] for r in rows if r["case"] == kind]) for kind in ("translation", "rotation")}
    for kind, fit in fits.items():
        print(f"{NAME}: {kind}: mean |error| {100 * fit['mean_relative_error']:.1f} %, slope {fit['slope']:.3f}, "
              f"R^2 {fit['r_squared']:.4f}")
    save_figure(_plot(rows, fits, wall), out_dir, NAME)
    return {"max_error": max(fit["mean_relative_error"] for fit in fits.values()),
            "error_meaning": "mean relative estimation error (the larger of translation and rotation)",
            "fits": fits}


def _store_calibration(path: Path, scene, array, calibration) -> None:
    """The estimator calibration stored with the fingertip design it was fitted on (JSON)."""
    from studies._output import write_json_atomic

    write_json_atomic(path, {"design": {"gel": {"shape": scene.gel.shape, **dict(scene.gel.parameters)},
                                        "E": scene.material.E, "nu": scene.material.nu,
                                        "friction_coefficient": scene.contact.friction_coefficient,
                                        "sensor_pitch": array.pitch, "sensor_nodes": list(array.node_counts)},
                             "calibration": calibration.to_dict(),
                             "fitted_on": "FEM plate shifts (the two smallest) of the fig9 translation run"})


def _regression(applied, estimated) -> dict:
    applied, estimated = np.asarray(applied), np.asarray(estimated)
    slope, intercept = np.polyfit(applied, estimated, 1)
    predicted = slope * applied + intercept
    r_squared = 1 - np.sum((estimated - predicted) ** 2) / np.sum((estimated - estimated.mean()) ** 2)
    return dict(slope=float(slope), intercept=float(intercept), r_squared=float(r_squared),
                mean_relative_error=float(np.mean(np.abs(estimated - applied) / applied)))


def _plot(rows, fits, wall):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6))
    for axis, kind, unit, scale in ((axes[0], "translation", "mm", 1.0), (axes[1], "rotation", "mrad", 1e3)):
        applied = np.array([r["applied"] for r in rows if r["case"] == kind]) * scale
        estimated = np.array([r["estimated"] for r in rows if r["case"] == kind]) * scale
        fit = fits[kind]
        line = np.linspace(0, applied.max() * 1.1, 50)
        axis.plot(line, line, ":", color="#e6550d", label="estimated = applied")
        axis.plot(applied, estimated, "o", color="#3182bd", label="FEM bench + sensor + estimator")
        axis.plot(line, fit["slope"] * line + fit["intercept"] * scale, "-", color="#3182bd", lw=1,
                  label=f"regression: slope {fit['slope']:.2f}, R$^2$ = {fit['r_squared']:.4f}")
        axis.set_xlabel(f"applied {kind} [{unit}]")
        axis.set_ylabel(f"estimated {kind} [{unit}]")
        axis.set_title(f"({'a' if kind == 'translation' else 'b'}) {kind}: mean error "
                       f"{100 * fit['mean_relative_error']:.1f} %", fontsize=10)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8, loc="upper left")
    fig.suptitle(f"Fig. 9: shear-displacement estimation, 3x3 fingertip, {SENSOR_PITCH:g} mm sensor pitch "
                 f"({wall:.0f} s)")
    fig.tight_layout()
    return fig
