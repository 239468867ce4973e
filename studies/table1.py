"""Table I (closed loop, MuJoCo): grasp success rate and grasp force for the bottle (upright, horizontal) and eclair.

Each trial runs the paper's sequence - grasp on the table, lift 50 mm, hold 4 s, place, release - with the
incipient-slip controller (controller.control.incipient_slip) against a plant it does not know: the FEM's sensor plane
read by capacitive nodes, every plant factor (kernel width, couple arm, gel E, bump height, node gain, friction
anisotropy) drawn within +-10 % (``--plant-spread``, ``--plant``), while the estimator was calibrated on a nominal
build's bench. Randomised: friction mu in [0.2, 1.2] (beyond the controller's prior, 0.4, on both sides), grasp position
(+-5 mm along the object, +-1 mm in height), object misalignment (+-1 deg), sensor noise (0.5-2 mN per node); the draws
come from the held-out seed (``HELD_OUT_SEED``), none of them seen while the law was tuned. The controller knows neither
mass, moment nor mu. Outcomes (the worst that happened): crushed (a finger's force exceeded the object's crush force;
the eclair's is 10 N), dropped (the object touched the table in the hold), turned out of the grasp (more than 0.15 rad),
else held; success means held. A trial whose own slip limit lies above the crush force cannot be held by any grip
("infeasible"; none in 0.2-1.2: the eclair's slip limit at mu 0.2 is 7.3 N against its 10 N crush force); the rate is
given over all trials and over the feasible ones. The success rate comes with its 95 % Wilson interval: 30 trials that
all succeed bound the failure rate below 11 %, 10 below 28 %. Held still: per trial the slide and turn over the hold
and the creep after the friction is found, with the window it was fitted on; the summary counts the creep against
CREEP_TARGET where that window is CREEP_WINDOW (1 s) or longer (shorter, it is the grip step's settling).
Outputs: table1.csv (one row per trial, written as each finishes; a re-run skips the trials already there),
table1_summary.json, table1.png/pdf.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_json_atomic
from studies._trials import (add_plant_arguments, add_swing_argument, check_trials, outcome_columns, plant_description,
                             plant_options, run_trial_table, trial_key, trial_settings)

NAME = "table1"
PAPER_SUCCESS = {"bottle_upright": "10/10", "bottle_horizontal": "10/10", "eclair": "10/10"}
TRIALS = 30
CREEP_TARGET = 10.0                 # um/s: the creep after the friction is found that a held grasp may show at most
SLIDE_TARGET = 1.0                  # mm: the held-still bound on a held object's slide over the hold; the grasp's slide
                                    # from the lift's start is counted against it too


def add_arguments(parser) -> None:
    parser.add_argument("--trials", type=int, default=None, help=f"trials per object (default {TRIALS}, quick 3)")
    parser.add_argument("--seed", type=int, default=None, help="seed of the randomisation (default: the held-out "
                                                                  "seed, HELD_OUT_SEED)")
    parser.add_argument("--processes", type=int, default=None, help="worker processes, 1 to 256 (default: every CPU)")
    parser.add_argument("--objects", type=lambda text: [name for name in text.split(",") if name], default=None,
                        metavar="NAME,NAME", help="only these objects (bottle_upright, bottle_horizontal, eclair)")
    add_plant_arguments(parser)
    add_swing_argument(parser)


def _row(result, info) -> dict:
    settings = result.settings
    return dict(object=info["object"], trial=info["trial"], friction_coefficient=settings.friction_coefficient,
                grasp_offset_x_mm=1e3 * settings.grasp_offset[0], grasp_offset_z_mm=1e3 * settings.grasp_offset[1],
                misalignment_deg=math.degrees(settings.misalignment), sensor_noise=settings.sensor_noise,
                **outcome_columns(result, info["required"], info["crush_force"]),
                hold_force_mean=result.hold_force_mean, hold_force_settled=result.hold_force_settled,
                max_force=result.max_force, required_force=info["required"],
                force_ratio=result.hold_force_settled / info["required"], crush_force=info["crush_force"],
                creep_um_per_s=result.creep_um_per_s, real_time_factor=result.real_time_factor)


def run(out_dir, quick: bool = False, trials: int | None = None, seed: int | None = None,
        processes: int | None = None, objects: list[str] | None = None, plant_spread: float | None = None,
        plant: str | None = None, sensor_plane: str = "fem", swing_margin: float = 0.0) -> dict:
    """Run the trials of every Table I object (or of ``objects``); CSV, summary JSON and figure."""
    from controller.closed_loop import CREEP_WINDOW, HELD_OUT_SEED, TABLE_I_OBJECTS
    from fem.validation import check_integer

    out_dir = Path(out_dir)
    trials = (3 if quick else TRIALS) if trials is None else trials
    check_trials(trials)
    unknown = sorted(set(objects or ()) - set(TABLE_I_OBJECTS))
    if unknown or objects == []:
        raise ValueError(f"objects={objects!r}: unknown {unknown}; allowed: {list(TABLE_I_OBJECTS)}")
    options = plant_options(plant_spread, plant, sensor_plane, swing_margin)
    if seed is not None:
        check_integer("--seed", seed, 0, 2**63 - 1)
    rng = np.random.default_rng(HELD_OUT_SEED if seed is None else seed)
    jobs = []
    for name, obj in TABLE_I_OBJECTS.items():
        for trial in range(trials):
            settings = trial_settings(rng, **options)   # drawn for every object: a selection keeps the others' trials
            if objects is not None and name not in objects:
                continue
            info = dict(object=name, trial=trial, crush_force=obj.crush_force)
            jobs.append((trial_key(obj, settings), obj, settings, info))
    rows = run_trial_table(out_dir / f"{NAME}.csv", jobs, _row, processes, label=NAME)
    summary = _summary(rows)
    write_json_atomic(out_dir / f"{NAME}_summary.json", summary)
    for name, entry in summary["objects"].items():
        low, high = entry["success_interval"]
        error_low, error_high = entry["friction_error_min"], entry["friction_error_max"]
        errors = "n/a" if error_low is None else f"{100 * error_low:+.0f} ... {100 * error_high:+.0f} %"
        print(f"{NAME}: {name}: held {entry['success']} (95 % Wilson interval {100 * low:.0f}-{100 * high:.0f} %; "
              f"paper {PAPER_SUCCESS[name]}; {entry['held_feasible']} of the feasible), {entry['turned_out']} turned "
              f"out, {entry['dropped']} dropped, {entry['crushed']} crushed; settled grip "
              f"{_number(entry['force_ratio_mean'], '.2f')} x the trial's slip limit "
              f"(max {_number(entry['force_ratio_max'], '.2f')}); slide in the hold <= "
              f"{_number(entry['hold_slip_mm_max'], '.2f')} mm, in the grasp from the lift's start <= "
              f"{_number(entry['grasp_slip_mm_max'], '.2f')} mm (above {SLIDE_TARGET:g} mm in "
              f"{entry['grasp_slip_above_target']}), rotation <= "
              f"{_number(entry['max_rotation_mrad'], '.0f')} mrad, creep after the friction is found <= "
              f"{CREEP_TARGET:g} um/s in {entry['creep_within_target']} of the {entry['creep_measured']} held trials "
              f"with a window of {CREEP_WINDOW:g} s or more to fit it on, friction estimate {errors}")
    print(f"{NAME}: real-time factor of one trial {summary['real_time_factor_median']:.1f} (median, simulated s per "
          f"wall s)")
    save_figure(_plot(rows, summary, plant_description(options)), out_dir, NAME)
    return {"max_error": summary["worst_failure_rate"], "error_meaning": "failure rate of the worst object",
            **summary}


def _summary(rows) -> dict:
    from controller.closed_loop import OUTCOMES
    from controller.design import wilson_interval

    objects = {}
    for name in dict.fromkeys(row["object"] for row in rows):
        mine = [row for row in rows if row["object"] == name]
        feasible = [row for row in mine if row["feasible"]]
        held = [row for row in mine if row["outcome"] == "held"]
        ratio = np.array([row["force_ratio"] for row in held], dtype=float)
        measured = [row for row in held if row["creep_measurable"]]
        errors = np.array([row["friction_estimate_error"] for row in mine], dtype=float)
        successes = len(held)
        objects[name] = dict(success=f"{successes}/{len(mine)}", success_rate=successes / len(mine),
                             success_interval=wilson_interval(successes, len(mine)), trials=len(mine),
                             held_feasible=f"{sum(r['outcome'] == 'held' for r in feasible)}/{len(feasible)}",
                             infeasible=len(mine) - len(feasible),
                             **{outcome: sum(row["outcome"] == outcome for row in mine) for outcome in OUTCOMES},
                             hold_force_mean=_statistic(np.mean, [r["hold_force_settled"] for r in held]),
                             max_force=float(max(row["max_force"] for row in mine)),
                             force_ratio_mean=_statistic(np.mean, ratio),
                             force_ratio_max=_statistic(np.max, ratio),
                             creep_um_per_s_max=_statistic(np.max, [row["creep_um_per_s"] for row in held]),
                             creep_after_friction_max=_statistic(
                                 np.max, [row["creep_after_friction_um_per_s"] for row in held]),
                             # the creep fitted on a window of CREEP_WINDOW or more (shorter: a grip step's settling)
                             creep_measured=len(measured), creep_within_target=sum(
                                 row["creep_after_friction_um_per_s"] <= CREEP_TARGET for row in measured),
                             creep_after_friction_max_measured=_statistic(
                                 np.max, [row["creep_after_friction_um_per_s"] for row in measured]),
                             hold_slip_mm_max=_statistic(np.max, [row["hold_slip_mm"] for row in held]),
                             # a slip caught in the lift, which the hold's slide starts after (elastic shear in it)
                             grasp_slip_mm_max=_statistic(np.max, [row["grasp_slip_mm"] for row in held]),
                             grasp_slip_above_target=sum(row["grasp_slip_mm"] > SLIDE_TARGET for row in held),
                             max_rotation_mrad=_statistic(np.max, [row["max_rotation_mrad"] for row in held]),
                             friction_error_min=_statistic(np.min, errors),
                             friction_error_max=_statistic(np.max, errors))
    return dict(objects=objects, worst_failure_rate=1.0 - min(o["success_rate"] for o in objects.values()),
                dropped=sum(o["dropped"] for o in objects.values()),
                crushed=sum(o["crushed"] for o in objects.values()),
                turned_out=sum(o["turned_out"] for o in objects.values()),
                real_time_factor_median=float(np.median([row["real_time_factor"] for row in rows])))


def _statistic(reduce, values) -> float | None:
    """``reduce`` over the finite values; None (JSON null) when there are none (no held trial, no estimate)."""
    values = np.asarray(values, dtype=float)
    values = values[np.isfinite(values)]
    return float(reduce(values)) if values.size else None


def _number(value, spec: str) -> str:
    """``value`` formatted by ``spec``, or "n/a" for a statistic with no values."""
    return "n/a" if value is None else format(value, spec)


def _plot(rows, summary, plant: str):
    import matplotlib.pyplot as plt

    names = list(summary["objects"])
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.2))
    rates = np.array([summary["objects"][n]["success_rate"] for n in names])
    intervals = np.array([summary["objects"][n]["success_interval"] for n in names])
    axes[0].bar(range(len(names)), rates, color="#3182bd")
    axes[0].errorbar(range(len(names)), rates, yerr=[rates - intervals[:, 0], intervals[:, 1] - rates], fmt="none",
                     ecolor="k", capsize=5, label="95 % Wilson interval")
    for i, name in enumerate(names):
        entry = summary["objects"][name]
        axes[0].text(i, 0.05, f"{entry['success']} held\n{entry['turned_out']} turned\n{entry['dropped']} dropped\n"
                              f"{entry['crushed']} crushed", ha="center", color="white", fontsize=8)
    axes[0].set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
    axes[0].set_ylim(0, 1.18)
    axes[0].set_ylabel("success rate")
    axes[0].set_title("(a) held: no table contact, no crush, not turned out", fontsize=10)
    axes[0].legend(fontsize=8, loc="upper right")
    for i, name in enumerate(names):
        mine = [row for row in rows if row["object"] == name]
        jitter = np.linspace(-0.2, 0.2, len(mine)) if len(mine) > 1 else np.zeros(1)
        marker = ["o" if r["outcome"] == "held" else "x" for r in mine]
        for index, row in enumerate(mine):
            colour = dict(c=[row["friction_coefficient"]], cmap="viridis", vmin=0.2, vmax=1.2, marker=marker[index],
                          zorder=3)
            points = axes[1].scatter(i + jitter[index], row["force_ratio"], **colour)
            axes[2].scatter(i + jitter[index], row["grasp_slip_mm"], **colour)
    axes[1].axhline(1.0, color="k", linewidth=1, label="model's slip limit")
    axes[1].set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
    axes[1].set_ylabel("settled grip / slip limit [-]")
    axes[1].set_title("(b) grip the controller settled at, per trial (x: not held)", fontsize=10)
    axes[1].legend(fontsize=8)
    axes[1].grid(alpha=0.3)
    # the lift is where a held object slides: the hold's slide starts after it
    axes[2].axhline(SLIDE_TARGET, color="k", linestyle=":", linewidth=1, label=f"{SLIDE_TARGET:g} mm")
    axes[2].set_yscale("log")
    axes[2].set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
    axes[2].set_ylabel("slide from the lift's start [mm]")
    axes[2].set_title("(c) slide in the grasp over lift and hold (elastic shear in it)", fontsize=10)
    axes[2].legend(fontsize=8)
    axes[2].grid(alpha=0.3, which="both")
    fig.colorbar(points, ax=axes[2], label="friction coefficient (unknown to the controller)")
    fig.suptitle(f"Table I: closed-loop grasp with incipient-slip detection against an unknown plant ({plant})",
                 fontsize=10)
    fig.tight_layout()
    return fig
