"""Fig. 6 (virtual bench): translational shear-displacement estimation error against bump array and sensor pitch.

FEM of the 40 x 40 mm fingertip with 1x1, 2x2, 3x3 and 4x4 hemisphere arrays under a rigid plate pressed with
2 N and shifted by known displacements; the base pressure is read at 1 mm and 3 mm pitch by three sensor models:

- ``cells``: every node integrates the pressure over its whole pitch x pitch cell, noise-free (the ideal array);
- ``small pads``: pads of a third of the pitch (fill 1/9), noise-free (the synthetic check of the issue);
- ``capacitive``: the capacitive node of ``controller.sensing.capacitive`` - 0.5 mm gaps between pads (fill 0.25 at
  1 mm, 0.69 at 3 mm), saturating pressure-capacitance curve, 2 % crosstalk, 0.5 fF noise, 16-bit converter - each state
  held 0.1 s (10 frames at 100 Hz, averaged), over NOISE_DRAWS noise draws (mean error; its spread in the CSV).

The estimator (per-bump centre of pressure, the mean over the bumps) gives the shear displacement, compared with the
applied shift on the held-out shifts, before calibration (the design gain: fitted once per array on the ideal 1 mm
cells, what a designer gets from the model) and after (gain re-fitted for this sensor model and pitch on
CALIBRATION_SHIFTS). The base-plane CoP moves about a tenth of the plate shift, so an uncalibrated gain of 1 would
read ~900 % high for every sensor: not a comparison worth plotting. The paper: a smaller pitch lowers the error;
more bumps lower it up to 3x3, not beyond.

``--grasp`` asks the figure's question of the grasp (``studies._fig6_grasp``): the same arrays at 1 and 3 mm pitch
through the design study's closed loop (each calibrated on its own FEM, its plant from that FEM, its estimator fitted
on its bench, Table I trials on the held-out draws), written to fig6_grasp.csv/.png/.pdf beside the bench's errors;
the 1x1 array is refused by the closed loop, and shown with its reason. The design records go to
``OUT/fig6_grasp/cases`` (a re-run resumes).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic

NAME = "fig6"
CALIBRATION_SHIFTS = (0.1, 0.2)        # mm, used to fit the gain; the others are held out
PITCHES = (1.0, 3.0)                   # mm
SENSORS = ("cells", "small pads", "capacitive")
NOISE_DRAWS = 10                       # noise draws of the capacitive sensor (seeds 0 ... 9)
FRAMES_PER_STATE = 10                  # frames averaged per quasi-static state: 0.1 s at 100 Hz


def add_arguments(parser) -> None:
    parser.add_argument("--grasp", action="store_true",
                        help="also judge each array and pitch by closed-loop grasp outcome (fig6_grasp.*)")
    parser.add_argument("--grasp-trials", type=int, default=None,
                        help="with --grasp: trials per Table I object (default 10; quick 1)")
    parser.add_argument("--grasp-only", action="store_true",
                        help="with --grasp: skip the FEM bench (the panel then shows the design study's error only)")
    parser.add_argument("--workers", type=int, default=None, help="with --grasp: design-sweep workers (default 2)")


def check_grasp_options(grasp: bool, grasp_trials, grasp_only: bool, workers) -> int:
    """Refuse bad --grasp options by name (ValueError: exit code 2 on the command line); the workers to use."""
    from fem.validation import check_integer
    from studies._trials import MAX_TRIALS

    if grasp_trials is not None:
        check_integer("grasp_trials", grasp_trials, 1, MAX_TRIALS)
    if workers is not None:
        # the closed loop's MAX_PROCESSES, not imported: controller.closed_loop loads numba, which a bench run skips
        check_integer("workers", workers, 1, 256)
    given = [flag for flag, value in (("--grasp-trials", grasp_trials), ("--workers", workers))
             if value is not None] + (["--grasp-only"] if grasp_only else [])
    if given and not grasp:
        raise ValueError(f"{' and '.join(given)} need{'s' if len(given) == 1 else ''} --grasp")
    return 2 if workers is None else workers


def sensor_model(sensor: str, pitch: float):
    """The SensorArray of a sensor model at ``pitch`` [mm] covering the 40 mm footprint."""
    from controller.estimation.bench import sensor_array
    from controller.sensing.capacitive import CapacitiveNode
    from controller.sensing.sensor import capacitive_array

    cells = sensor_array(pitch)
    if sensor == "cells":
        return cells
    if sensor == "small pads":
        return dataclasses.replace(cells, fill_factor=1.0 / 9.0)
    return capacitive_array(pitch, cells.node_counts, pad_gap=0.5, node=CapacitiveNode())


def cop_shifts(result, array, layout, seed: int | None, operator=None):
    """Per-bump CoP shifts (t, k, 2) [mm], readings averaged over FRAMES_PER_STATE frames per state (noisy sensor);
    ``operator``: ``controller.estimation.bench.readings_operator`` of the result and array, built once per seed set."""
    from controller.estimation.bench import averaged_cop_shifts

    return averaged_cop_shifts(result, array, layout, seed, FRAMES_PER_STATE, operator)[0]


def evaluate(cop_shift: np.ndarray, shifts, design_gain: float | None = None) -> dict:
    """Errors of the estimated shift with ``design_gain`` (before; None: this sensor's own fit, as for the reference
    sensor itself) and after calibrating the gain on CALIBRATION_SHIFTS [%]."""
    from controller.estimation.calibration import calibrate_gain

    shifts = np.asarray(shifts, dtype=float)
    truth = np.zeros_like(cop_shift)
    truth[1:, :, 0] = shifts[:, None]
    calibrating = np.isin(np.round(shifts, 9), CALIBRATION_SHIFTS)
    calibration = calibrate_gain(cop_shift[1:][calibrating], truth[1:][calibrating])
    raw = cop_shift[1:][~calibrating, :, 0].mean(axis=1)                 # mean over bumps [mm]
    applied = shifts[~calibrating]
    before = np.abs((calibration.gain if design_gain is None else design_gain) * raw - applied) / applied
    after = np.abs(calibration.gain * raw - applied) / applied
    return dict(error_before_percent=100 * float(before.mean()), error_after_percent=100 * float(after.mean()),
                worst_after_percent=100 * float(after.max()), gain=calibration.gain,
                calibration_r_squared=calibration.r_squared)


def run(out_dir, quick: bool = False, grasp: bool = False, grasp_trials: int | None = None,
        grasp_only: bool = False, workers: int | None = None) -> dict:
    """One FEM run per array, read by every sensor model at both pitches; CSV, PNG, PDF and the verdict; with
    ``grasp`` the arrays' closed-loop panel too (module docstring)."""
    workers = check_grasp_options(grasp, grasp_trials, grasp_only, workers)
    out_dir = Path(out_dir)
    arrays = (1, 3) if quick else (1, 2, 3, 4)
    summary, rows = ({"verdict": []}, []) if grasp_only else _bench(out_dir, quick, arrays)
    if grasp:
        summary = _grasp_panel(out_dir, quick, arrays, grasp_trials, workers, summary, rows)
    return summary


def _bench(out_dir: Path, quick: bool, arrays) -> tuple[dict, list[dict]]:
    """The FEM bench of the figure: rows in fig6.csv, the figure; (summary with the verdict, rows)."""
    from tqdm import tqdm

    from contact.solver import solve_scene
    from controller.estimation.bench import (
        BENCH_SIZE_BASE,
        BENCH_SIZE_CONTACT,
        bench_scene,
        bump_layout,
        readings_operator,
    )

    shifts = (0.1, 0.2, 0.3) if quick else (0.05, 0.1, 0.15, 0.2, 0.25, 0.3)
    size_contact, size_base = (0.7, 1.5) if quick else (BENCH_SIZE_CONTACT, BENCH_SIZE_BASE)
    draws = 2 if quick else NOISE_DRAWS
    rows = []
    start = time.perf_counter()
    for n in tqdm(arrays, desc=NAME, unit="array"):
        case_start = time.perf_counter()
        result = solve_scene(bench_scene(n, "shift", shifts, size_contact, size_base))
        seconds = time.perf_counter() - case_start
        layout = bump_layout(n)
        design_gain = None                 # the first model, noise-free cells at 1 mm, sets it for the array
        for sensor in SENSORS:
            for pitch in PITCHES:
                array = sensor_model(sensor, pitch)
                seeds = range(draws) if array.node is not None and array.node.noise_floor > 0 else (None,)
                operator = readings_operator(result, array)
                outcomes = [evaluate(cop_shifts(result, array, layout, seed, operator), shifts, design_gain)
                            for seed in seeds]
                if design_gain is None:
                    design_gain = outcomes[0]["gain"]
                mean = {key: float(np.mean([o[key] for o in outcomes])) for key in outcomes[0]}
                peak = float(np.max([increment.base_pressure.max() for increment in result.increments]))
                rows.append(dict(case=f"{n}x{n}", bumps=n * n, sensor=sensor, sensor_pitch=pitch,
                                 design_gain=design_gain,
                                 fill_factor=array.fill_factor, noise_draws=len(outcomes), **mean,
                                 error_after_spread_percent=float(np.std([o["error_after_percent"]
                                                                          for o in outcomes])),
                                 nodes_per_bump=float(np.prod(array.node_counts)) / (n * n),
                                 peak_base_pressure=peak, contact_area=result.increments[0].contact_area,
                                 dofs=result.mesh_info["dofs"], seconds=seconds))
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    wall = time.perf_counter() - start
    save_figure(_plot(rows, arrays, wall), out_dir, NAME)
    verdict = _verdict(rows, arrays)
    for line in verdict:
        print(f"{NAME}: {line}")
    primary = [r for r in rows if r["sensor"] == "capacitive"]
    return {"max_error": max(r["error_after_percent"] for r in primary) / 100,
            "error_meaning": "largest mean relative error of the estimated shear displacement after gain "
                             "calibration, capacitive sensor", "verdict": verdict}, rows


def _grasp_panel(out_dir: Path, quick: bool, arrays, grasp_trials, workers: int, summary: dict,
                 bench_rows: list[dict]) -> dict:
    """The closed-loop design sweep of the bench's arrays (``studies._fig6_grasp``) beside the bench's rows:
    fig6_grasp.csv/.png/.pdf and its verdict lines added to ``summary``."""
    from controller.design import design_sweep
    from studies._fig6_grasp import GRASP_TRIALS, bench_designs, grasp_rows, grasp_study, grasp_verdict, plot_grasp

    trials = grasp_trials if grasp_trials is not None else (1 if quick else GRASP_TRIALS)
    start = time.perf_counter()
    table = design_sweep(bench_designs(arrays, PITCHES), grasp_study(quick, trials), out_dir=out_dir / "fig6_grasp",
                         scheduler="synchronous" if workers == 1 else "local", workers=workers, progress=False)
    wall = time.perf_counter() - start
    rows = grasp_rows(table, bench_rows)
    write_csv_atomic(out_dir / f"{NAME}_grasp.csv", rows)
    save_figure(plot_grasp(rows, list(arrays), PITCHES, wall), out_dir, f"{NAME}_grasp")
    verdict = grasp_verdict(rows, PITCHES)
    for line in verdict:
        print(f"{NAME}: {line}")
    summary = dict(summary)
    summary["verdict"] = [*summary.get("verdict", []), *verdict]
    summary["grasp_wall_time"] = wall
    return summary


def _trend(rows, arrays, sensor: str, key: str) -> tuple[int, dict]:
    error = {(r["bumps"], r["sensor_pitch"]): r[key] for r in rows if r["sensor"] == sensor}
    finer = sum(error[(n * n, 1.0)] < error[(n * n, 3.0)] for n in arrays)
    best = {pitch: min(arrays, key=lambda n: error[(n * n, pitch)]) for pitch in PITCHES}
    return finer, best


def _verdict(rows, arrays) -> list[str]:
    """One line per sensor model and phase: does 1 mm beat 3 mm, which array is best; then the paper's claims."""
    lines = []
    for sensor in SENSORS:
        for phase, key in (("before calibration", "error_before_percent"),
                           ("after calibration", "error_after_percent")):
            finer, best = _trend(rows, arrays, sensor, key)
            lines.append(f"{sensor}, {phase}: 1 mm pitch lowers the error in {finer} of {len(arrays)} arrays; lowest "
                         f"error at {best[1.0]}x{best[1.0]} (1 mm) and {best[3.0]}x{best[3.0]} (3 mm)")
    finer, best = _trend(rows, arrays, "capacitive", "error_after_percent")
    pitch_claim = finer == len(arrays)
    bump_claim = 3 in arrays and best[3.0] == 3
    gains = {pitch: np.mean([r["gain"] for r in rows if r["sensor"] == "capacitive" and r["sensor_pitch"] == pitch])
             for pitch in PITCHES}
    lines.append(f"paper's claims with the capacitive sensor after calibration: smaller pitch lowers the error: "
                 f"{'reproduced' if pitch_claim else 'not reproduced'}; error lowest at 3x3 (3 mm pitch): "
                 f"{'reproduced' if bump_claim else 'not reproduced'} (mean calibrated gain {gains[1.0]:.2f} at 1 mm, "
                 f"{gains[3.0]:.2f} at 3 mm: the sensor-plane CoP moves 1/gain of the plate shift)")
    return lines


def _plot(rows, arrays, wall):
    import matplotlib.pyplot as plt

    fig, grid = plt.subplots(len(SENSORS), 2, figsize=(11, 3.2 * len(SENSORS)), squeeze=False, sharey="row")
    width = 0.38
    positions = np.arange(len(arrays))
    for axes, sensor in zip(grid, SENSORS):
        for axis, (phase, key) in zip(axes, (("before calibration", "error_before_percent"),
                                             ("after calibration", "error_after_percent"))):
            for offset, pitch, colour in ((-width / 2, 1.0, "#2b8cbe"), (width / 2, 3.0, "#fdae61")):
                values = [next(r[key] for r in rows if r["bumps"] == n * n and r["sensor_pitch"] == pitch
                               and r["sensor"] == sensor) for n in arrays]
                bars = axis.bar(positions + offset, values, width, color=colour, edgecolor="k",
                                label=f"{pitch:g} mm pitch")
                axis.bar_label(bars, fmt="%.1f", fontsize=7)
            axis.set_xticks(positions, [f"{n} x {n}" for n in arrays])
            axis.set_title(f"{sensor}: {phase}", fontsize=9)
            axis.grid(axis="y", alpha=0.3)
        axes[0].set_ylabel("shear-displacement error [%]")
    grid[0][0].legend(fontsize=8)
    for axis in grid[-1]:
        axis.set_xlabel("hemisphere array")
    fig.suptitle(f"Fig. 6: estimation error by array, sensor pitch and sensor model (FEM bench, {wall:.0f} s)")
    fig.tight_layout()
    return fig
