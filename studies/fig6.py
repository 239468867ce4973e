"""Fig. 6 (virtual bench): translational shear-displacement estimation error against bump array and sensor pitch.

FEM of the 40 x 40 mm fingertip with 1x1, 2x2, 3x3 and 4x4 hemisphere arrays under a rigid plate pressed with
2 N and shifted by known displacements; the base pressure is read by sensor arrays of 1 mm and 3 mm pitch; the
estimator (per-bump centre of pressure, gain calibrated on two of the shifts) gives the shear displacement,
compared with the applied shift on the other shifts. The paper: a smaller pitch lowers the error; more bumps lower
it up to 3x3, not beyond.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic

NAME = "fig6"
CALIBRATION_SHIFTS = (0.1, 0.2)        # mm, used to fit the gain; the others are held out


def evaluate(result, n: int, pitch: float, shifts) -> dict:
    """Calibrate the CoP gain on CALIBRATION_SHIFTS and return the error on the other shifts."""
    from controller.calibration import calibrate_gain
    from controller.bench import bump_layout, sensor_array, shifts_of

    array, layout = sensor_array(pitch), bump_layout(n)
    _, _, cop_shift = shifts_of(result, array, layout)                 # (t, k, 2), t = 1 + len(shifts)
    truth = np.zeros_like(cop_shift)
    truth[1:, :, 0] = np.asarray(shifts)[:, None]
    calibrating = np.isin(np.round(shifts, 9), CALIBRATION_SHIFTS)
    calibration = calibrate_gain(cop_shift[1:][calibrating], truth[1:][calibrating])
    estimate = calibration.gain * cop_shift[1:][~calibrating, :, 0].mean(axis=1)   # mean over bumps [mm]
    applied = np.asarray(shifts)[~calibrating]
    relative = np.abs(estimate - applied) / applied
    return dict(gain=calibration.gain, calibration_r_squared=calibration.r_squared,
                error_percent=100 * float(relative.mean()), worst_error_percent=100 * float(relative.max()),
                estimates=estimate.tolist(), applied=applied.tolist())


def run(out_dir, quick: bool = False) -> dict:
    """One FEM run per array (both sensor pitches read the same run); CSV, PNG, PDF."""
    from tqdm import tqdm

    from contact.solver import solve_scene
    from controller.bench import BENCH_SIZE_BASE, BENCH_SIZE_CONTACT, bench_scene

    out_dir = Path(out_dir)
    arrays = (1, 3) if quick else (1, 2, 3, 4)
    shifts = (0.1, 0.2, 0.3) if quick else (0.05, 0.1, 0.15, 0.2, 0.25, 0.3)
    size_contact, size_base = (0.7, 1.5) if quick else (BENCH_SIZE_CONTACT, BENCH_SIZE_BASE)
    rows = []
    start = time.perf_counter()
    for n in tqdm(arrays, desc=NAME, unit="array"):
        case_start = time.perf_counter()
        result = solve_scene(bench_scene(n, "shift", shifts, size_contact, size_base))
        seconds = time.perf_counter() - case_start
        for pitch in (1.0, 3.0):
            outcome = evaluate(result, n, pitch, shifts)
            rows.append(dict(case=f"{n}x{n}", bumps=n * n, sensor_pitch=pitch, error_percent=outcome["error_percent"],
                             worst_error_percent=outcome["worst_error_percent"], gain=outcome["gain"],
                             calibration_r_squared=outcome["calibration_r_squared"],
                             contact_area=result.increments[0].contact_area, dofs=result.mesh_info["dofs"],
                             seconds=seconds))
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    wall = time.perf_counter() - start
    save_figure(_plot(rows, arrays, wall), out_dir, NAME)
    verdict = _verdict(rows, arrays)
    print(f"{NAME}: {verdict}")
    return {"max_error": max(r["error_percent"] for r in rows) / 100,
            "error_meaning": "largest mean relative error of the estimated shear displacement", "verdict": verdict}


def _verdict(rows, arrays) -> str:
    error = {(r["bumps"], r["sensor_pitch"]): r["error_percent"] for r in rows}
    finer = all(error[(n * n, 1.0)] <= error[(n * n, 3.0)] for n in arrays)
    best = {pitch: min(arrays, key=lambda n: error[(n * n, pitch)]) for pitch in (1.0, 3.0)}
    return (f"1 mm pitch {'lowers' if finer else 'does not always lower'} the error; lowest error at "
            f"{best[1.0]}x{best[1.0]} (1 mm) and {best[3.0]}x{best[3.0]} (3 mm)")


def _plot(rows, arrays, wall):
    import matplotlib.pyplot as plt

    fig, axis = plt.subplots(figsize=(7, 4.6))
    width = 0.38
    positions = np.arange(len(arrays))
    for offset, pitch, colour in ((-width / 2, 1.0, "#2b8cbe"), (width / 2, 3.0, "#fdae61")):
        values = [next(r["error_percent"] for r in rows if r["bumps"] == n * n and r["sensor_pitch"] == pitch)
                  for n in arrays]
        bars = axis.bar(positions + offset, values, width, color=colour, edgecolor="k", label=f"{pitch:g} mm pitch")
        axis.bar_label(bars, fmt="%.1f", fontsize=8)
    axis.set_xticks(positions, [f"{n} x {n}" for n in arrays])
    axis.set_xlabel("hemisphere array")
    axis.set_ylabel("shear-displacement estimation error  [%]")
    axis.set_title(f"Fig. 6: estimation error by array and sensor pitch (FEM bench, {wall:.0f} s)", fontsize=10)
    axis.grid(axis="y", alpha=0.3)
    axis.legend()
    return fig
