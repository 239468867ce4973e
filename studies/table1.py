"""Table I (closed loop, MuJoCo): grasp success rate and grasp force for the bottle (upright, horizontal) and eclair.

Each trial runs the paper's sequence - grasp on the table, lift 50 mm, hold 4 s, place, release - with the grasp
force controller on the reduced 3x3-array fingertip (controller.closed_loop), randomised friction mu in [0.4, 1.0],
grasp position (+-5 mm along the object, +-1 mm in height), object misalignment (+-1 deg) and sensor noise
(0.5-2 mN per node). Success: the object never touches the table during the hold and no finger exceeds the
object's crush force (eclair: 10 N, see controller.closed_loop). The controller knows neither mass, moment nor mu.
Outputs: table1.csv (one row per trial, rewritten after each), table1_summary.json, table1.png/pdf.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic, write_json_atomic

NAME = "table1"
PAPER_SUCCESS = {"bottle_upright": "10/10", "bottle_horizontal": "10/10", "eclair": "10/10"}


def add_arguments(parser) -> None:
    parser.add_argument("--trials", type=int, default=None, help="trials per object (default 10, quick 1)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the randomisation")


def run(out_dir, quick: bool = False, trials: int | None = None, seed: int = 1) -> dict:
    """Run the trials of every Table I object; CSV, summary JSON and figure."""
    from controller.closed_loop import (PHYSICS_RATE_HZ, TABLE_I_OBJECTS, random_settings, required_grip_force,
                                      run_trial)

    out_dir = Path(out_dir)
    trials = (1 if quick else 10) if trials is None else int(trials)
    rng = np.random.default_rng(seed)
    rows = []
    for name, obj in TABLE_I_OBJECTS.items():
        for trial in range(trials):
            settings = random_settings(rng)
            result = run_trial(obj, settings)
            required = required_grip_force(obj, settings.friction_coefficient)
            rows.append(dict(object=name, trial=trial, mass_kg=obj.mass, moment_nmm=1e3 * obj.moment_nm,
                             friction_coefficient=settings.friction_coefficient, grasp_offset_x_mm=1e3 * settings.grasp_offset[0],
                             grasp_offset_z_mm=1e3 * settings.grasp_offset[1],
                             misalignment_deg=math.degrees(settings.misalignment), sensor_noise=settings.sensor_noise,
                             success=result.success, dropped=result.dropped, crushed=result.crushed,
                             rotated=result.rotated, max_rotation_mrad=result.max_rotation_mrad,
                             minimum_force=result.minimum_force, hold_force_mean=result.hold_force_mean,
                             hold_force_max=result.hold_force_max, max_force=result.max_force,
                             required_force=required, force_ratio=result.hold_force_mean / required,
                             crush_force=obj.crush_force, creep_um_per_s=result.creep_um_per_s,
                             rotation_creep_mrad_per_s=result.rotation_creep_mrad_per_s,
                             real_time_factor=result.real_time_factor))
            write_csv_atomic(out_dir / f"{NAME}.csv", rows)          # after every trial: nothing computed is lost
            print(f"{NAME}: {name} trial {trial}: mu {settings.friction_coefficient:.2f} success {result.success} "
                  f"hold force {result.hold_force_mean:.2f} N (needed {required:.2f} N), "
                  f"creep {result.creep_um_per_s:.3f} um/s, real-time factor {result.real_time_factor:.2f}")
    summary = _summary(rows)
    write_json_atomic(out_dir / f"{NAME}_summary.json", summary)
    for name, entry in summary["objects"].items():
        print(f"{NAME}: {name}: success {entry['success']} (paper {PAPER_SUCCESS[name]}), hold force "
              f"{entry['hold_force_mean']:.2f} +- {entry['hold_force_std']:.2f} N, force / needed "
              f"{entry['force_ratio_mean']:.2f}, creep {entry['creep_um_per_s_max']:.3f} um/s max, "
              f"largest rotation in the grasp {entry['max_rotation_mrad']:.1f} mrad ({entry['rotated']} turned out)")
    print(f"{NAME}: benchmark: real-time factor of one trial {summary['real_time_factor_mean']:.2f} "
          f"(simulated s per wall s; MuJoCo and contact {PHYSICS_RATE_HZ / 1e3:g} kHz, actuator 8 kHz, control 1 kHz, sensor 100 Hz)")
    save_figure(_plot(rows, summary), out_dir, NAME)
    return {"max_error": summary["worst_failure_rate"], "error_meaning": "failure rate of the worst object",
            **summary}


def _summary(rows) -> dict:
    objects = {}
    for name in dict.fromkeys(row["object"] for row in rows):
        mine = [row for row in rows if row["object"] == name]
        force = np.array([row["hold_force_mean"] for row in mine], dtype=float)
        ratio = np.array([row["force_ratio"] for row in mine], dtype=float)
        successes = sum(row["success"] for row in mine)
        objects[name] = dict(success=f"{successes}/{len(mine)}", success_rate=successes / len(mine),
                             hold_force_mean=float(np.nanmean(force)), hold_force_std=float(np.nanstd(force)),
                             hold_force_min=float(np.nanmin(force)), hold_force_max=float(np.nanmax(force)),
                             max_force=float(max(row["max_force"] for row in mine)),
                             force_ratio_mean=float(np.nanmean(ratio)),
                             creep_um_per_s_max=float(np.nanmax([row["creep_um_per_s"] for row in mine])),
                             dropped=sum(row["dropped"] for row in mine), crushed=sum(row["crushed"] for row in mine),
                             rotated=sum(row["rotated"] for row in mine),
                             max_rotation_mrad=float(np.nanmax([row["max_rotation_mrad"] for row in mine])))
    return dict(objects=objects, worst_failure_rate=1.0 - min(o["success_rate"] for o in objects.values()),
                real_time_factor_mean=float(np.mean([row["real_time_factor"] for row in rows])))


def _plot(rows, summary):
    import matplotlib.pyplot as plt

    names = list(summary["objects"])
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    rates = [summary["objects"][n]["success_rate"] for n in names]
    axes[0].bar(range(len(names)), rates, color="#3182bd")
    for i, name in enumerate(names):
        axes[0].text(i, rates[i] + 0.02, summary["objects"][name]["success"], ha="center")
    axes[0].set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
    axes[0].set_ylim(0, 1.15)
    axes[0].set_ylabel("success rate")
    axes[0].set_title("(a) success (no table contact in the hold, no crush)", fontsize=10)
    for i, name in enumerate(names):
        mine = [row for row in rows if row["object"] == name]
        jitter = np.linspace(-0.15, 0.15, len(mine)) if len(mine) > 1 else [0.0]
        axes[1].scatter(i + np.asarray(jitter), [r["hold_force_mean"] for r in mine], c=[r["friction_coefficient"] for r in mine],
                        cmap="viridis", vmin=0.4, vmax=1.0, zorder=3)
        axes[1].scatter(i + np.asarray(jitter), [r["required_force"] for r in mine], marker="_", s=200, c="k",
                        zorder=4, label="needed (reduced model)" if i == 0 else None)
        if math.isfinite(mine[0]["crush_force"]):
            axes[1].hlines(mine[0]["crush_force"], i - 0.3, i + 0.3, colors="r", label="crush force")
    axes[1].set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
    axes[1].set_ylabel("hold grasp force per finger [N]")
    axes[1].set_title("(b) grasp force in the hold (colour: mu 0.4 - 1.0)", fontsize=10)
    axes[1].legend(fontsize=8)
    axes[1].grid(alpha=0.3)
    fig.suptitle("Table I: closed-loop grasp with rotational incipient-slip detection (MuJoCo + reduced model)")
    fig.tight_layout()
    return fig
