"""Table I (closed loop, MuJoCo): grasp success rate and grasp force for the bottle (upright, horizontal) and eclair.

Each trial runs the paper's sequence - grasp on the table, lift 50 mm, hold 4 s, place, release - with the
incipient-slip controller (controller.control.incipient_slip) on the reduced 3x3-array fingertip, randomised friction mu
in [0.4, 1.0], grasp position (+-5 mm along the object, +-1 mm in height), object misalignment (+-1 deg) and sensor
noise (0.5-2 mN per node). The controller knows neither mass, moment nor mu. Outcomes are told apart: dropped (the
object touched the table in the hold: under-grip), crushed (a finger's force exceeded the object's crush force:
over-grip; the eclair's is 10 N), turned out of the grasp (more than 0.15 rad); success is neither dropped nor
crushed, as in the paper. The success rate comes with its 95 % Wilson interval: 30 trials that all succeed bound
the failure rate below 11 %, 10 below 28 %.
Outputs: table1.csv (one row per trial, written as each finishes; a re-run skips the trials already there),
table1_summary.json, table1.png/pdf.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_json_atomic
from studies._trials import check_trials, run_trial_table, trial_key

NAME = "table1"
PAPER_SUCCESS = {"bottle_upright": "10/10", "bottle_horizontal": "10/10", "eclair": "10/10"}
TRIALS = 30


def add_arguments(parser) -> None:
    parser.add_argument("--trials", type=int, default=None, help=f"trials per object (default {TRIALS}, quick 3)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the randomisation")
    parser.add_argument("--processes", type=int, default=None, help="worker processes (default: every CPU)")
    parser.add_argument("--objects", type=lambda text: [name for name in text.split(",") if name], default=None,
                        metavar="NAME,NAME", help="only these objects (bottle_upright, bottle_horizontal, eclair)")


def wilson_interval(successes: int, trials: int) -> tuple[float, float]:
    """95 % Wilson score interval of a success rate (scipy.stats.binomtest)."""
    from scipy.stats import binomtest

    interval = binomtest(int(successes), int(trials)).proportion_ci(confidence_level=0.95, method="wilson")
    return float(interval.low), float(interval.high)


def _row(result, info) -> dict:
    settings = result.settings
    return dict(object=info["object"], trial=info["trial"], friction_coefficient=settings.friction_coefficient,
                grasp_offset_x_mm=1e3 * settings.grasp_offset[0], grasp_offset_z_mm=1e3 * settings.grasp_offset[1],
                misalignment_deg=math.degrees(settings.misalignment), sensor_noise=settings.sensor_noise,
                success=result.success, dropped=result.dropped, crushed=result.crushed, rotated=result.rotated,
                max_rotation_mrad=result.max_rotation_mrad, hold_force_mean=result.hold_force_mean,
                hold_force_settled=result.hold_force_settled, max_force=result.max_force,
                required_force=info["required"], force_ratio=result.hold_force_settled / info["required"],
                crush_force=info["crush_force"], friction_estimate=result.friction_estimate,
                slips_detected=len(result.slip_events), creep_um_per_s=result.creep_um_per_s,
                hold_slip_mm=result.hold_slip_mm, real_time_factor=result.real_time_factor)


def run(out_dir, quick: bool = False, trials: int | None = None, seed: int = 1,
        processes: int | None = None, objects: list[str] | None = None) -> dict:
    """Run the trials of every Table I object (or of ``objects``); CSV, summary JSON and figure."""
    from controller.closed_loop import TABLE_I_OBJECTS, random_settings

    out_dir = Path(out_dir)
    trials = (3 if quick else TRIALS) if trials is None else trials
    check_trials(trials)
    unknown = sorted(set(objects or ()) - set(TABLE_I_OBJECTS))
    if unknown or objects == []:
        raise ValueError(f"objects={objects!r}: unknown {unknown}; allowed: {list(TABLE_I_OBJECTS)}")
    rng = np.random.default_rng(seed)
    jobs = []
    for name, obj in TABLE_I_OBJECTS.items():
        for trial in range(trials):
            settings = random_settings(rng)          # drawn for every object: a selection keeps the others' trials
            if objects is not None and name not in objects:
                continue
            info = dict(object=name, trial=trial, crush_force=obj.crush_force)
            jobs.append((trial_key(obj, settings), obj, settings, info))
    rows = run_trial_table(out_dir / f"{NAME}.csv", jobs, _row, processes, label=NAME)
    summary = _summary(rows)
    write_json_atomic(out_dir / f"{NAME}_summary.json", summary)
    for name, entry in summary["objects"].items():
        low, high = entry["success_interval"]
        print(f"{NAME}: {name}: success {entry['success']} (95 % Wilson interval {100 * low:.0f}-{100 * high:.0f} %; "
              f"paper {PAPER_SUCCESS[name]}), {entry['dropped']} dropped, {entry['crushed']} crushed, "
              f"{entry['rotated']} turned out; settled grip {entry['hold_force_mean']:.2f} +- "
              f"{entry['hold_force_std']:.2f} N, {entry['force_ratio_mean']:.2f} x the model's slip limit "
              f"(max {entry['force_ratio_max']:.2f})")
    print(f"{NAME}: real-time factor of one trial {summary['real_time_factor_median']:.1f} (median, simulated s per "
          f"wall s)")
    save_figure(_plot(rows, summary), out_dir, NAME)
    return {"max_error": summary["worst_failure_rate"], "error_meaning": "failure rate of the worst object",
            **summary}


def _summary(rows) -> dict:
    objects = {}
    for name in dict.fromkeys(row["object"] for row in rows):
        mine = [row for row in rows if row["object"] == name]
        force = np.array([row["hold_force_settled"] for row in mine], dtype=float)
        ratio = np.array([row["force_ratio"] for row in mine], dtype=float)
        successes = sum(bool(row["success"]) for row in mine)
        objects[name] = dict(success=f"{successes}/{len(mine)}", success_rate=successes / len(mine),
                             success_interval=wilson_interval(successes, len(mine)), trials=len(mine),
                             hold_force_mean=float(np.nanmean(force)), hold_force_std=float(np.nanstd(force)),
                             max_force=float(max(row["max_force"] for row in mine)),
                             force_ratio_mean=float(np.nanmean(ratio)), force_ratio_max=float(np.nanmax(ratio)),
                             creep_um_per_s_max=float(np.nanmax([row["creep_um_per_s"] for row in mine])),
                             dropped=sum(bool(row["dropped"]) for row in mine),
                             crushed=sum(bool(row["crushed"]) for row in mine),
                             rotated=sum(bool(row["rotated"]) for row in mine),
                             max_rotation_mrad=float(np.nanmax([row["max_rotation_mrad"] for row in mine])))
    return dict(objects=objects, worst_failure_rate=1.0 - min(o["success_rate"] for o in objects.values()),
                dropped=sum(o["dropped"] for o in objects.values()),
                crushed=sum(o["crushed"] for o in objects.values()),
                real_time_factor_median=float(np.median([row["real_time_factor"] for row in rows])))


def _plot(rows, summary):
    import matplotlib.pyplot as plt

    names = list(summary["objects"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    rates = np.array([summary["objects"][n]["success_rate"] for n in names])
    intervals = np.array([summary["objects"][n]["success_interval"] for n in names])
    axes[0].bar(range(len(names)), rates, color="#3182bd")
    axes[0].errorbar(range(len(names)), rates, yerr=[rates - intervals[:, 0], intervals[:, 1] - rates], fmt="none",
                     ecolor="k", capsize=5, label="95 % Wilson interval")
    for i, name in enumerate(names):
        entry = summary["objects"][name]
        axes[0].text(i, 0.05, f"{entry['success']}\n{entry['dropped']} dropped\n{entry['crushed']} crushed",
                     ha="center", color="white", fontsize=8)
    axes[0].set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
    axes[0].set_ylim(0, 1.1)
    axes[0].set_ylabel("success rate")
    axes[0].set_title("(a) success: no table contact in the hold, no crush", fontsize=10)
    axes[0].legend(fontsize=8, loc="lower right")
    for i, name in enumerate(names):
        mine = [row for row in rows if row["object"] == name]
        jitter = np.linspace(-0.2, 0.2, len(mine)) if len(mine) > 1 else np.zeros(1)
        points = axes[1].scatter(i + jitter, [r["force_ratio"] for r in mine],
                                 c=[r["friction_coefficient"] for r in mine], cmap="viridis", vmin=0.4, vmax=1.0,
                                 zorder=3)
    axes[1].axhline(1.0, color="k", linewidth=1, label="model's slip limit")
    axes[1].set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
    axes[1].set_ylabel("settled grip / slip limit [-]")
    axes[1].set_title("(b) grip the controller settled at, per trial", fontsize=10)
    fig.colorbar(points, ax=axes[1], label="friction coefficient (unknown to the controller)")
    axes[1].legend(fontsize=8)
    axes[1].grid(alpha=0.3)
    fig.suptitle("Table I: closed-loop grasp with incipient-slip detection (MuJoCo + reduced 3x3 fingertip)")
    fig.tight_layout()
    return fig
