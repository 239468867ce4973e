"""The tuning draws (seed 101): the trial sets the incipient-slip law's changes are judged on.

Every set draws from a generator of its own, ``default_rng(TUNING_SEED + offset)`` (``TuningSet.offset``), so a change
of one set leaves the others' draws as they were; none is the held-out seed's. The four sets of low-friction boxes reuse
offsets 0-3 with other objects and frictions (they were drawn that way when docs/design.md sec. 12 measured them; the
horizontal bottles below the prior took 11; a new set takes an offset from 12 on). Each trial is a randomised trial of
the protocol (``random_settings``: friction uniform in the set's range, grasp jitter, misalignment, sensor noise, every
plant factor within +-10 %); Table I's objects run the whole sequence, the Fig. 11 boxes lift and hold 4 s. `python -m
studies tuning` gives the numbers sec. 12 judges the law and its rejected changes by, for the law in this checkout. Not
part of ``studies all``: it is the tuning's measure, not a paper figure. Per set: held / turned out / dropped / crushed,
the held rate's 95 % Wilson interval, the trials whose friction was never measured (no slip seen), the settled grip over
the trial's own slip limit, the largest turn of a held object, the friction estimate's error. ``--sensor-noise-scale S``
runs the same draws with every array's node noise times S (the law reads its noise from a rest calibration, so it
follows): where the sensor, not the law, sets a limit (docs/design.md sec. 12); ``--swing-margin M`` runs them with the
law's swing margin (an option, off by default). Outputs: tuning.csv (one row per trial, resumable), tuning_summary.csv
(one row per set), tuning.png/pdf.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic
from studies._trials import (add_swing_argument, check_swing_margin, check_trials, run_trial_table, trial_columns,
                             trial_key)

NAME = "tuning"


@dataclass(frozen=True)
class TuningSet:
    """``trials`` draws at friction uniform in ``friction`` [-] from the generator TUNING_SEED + ``offset``, of the
    Table I object ``table_object`` or else of Fig. 11's box of ``box`` = (mass [kg], lever [m])."""

    name: str
    trials: int
    friction: tuple[float, float]
    offset: int
    table_object: str | None = None
    box: tuple[float, float] | None = None


def _box_set(mass: float, lever: float, trials: int, friction: tuple[float, float], offset: int,
             suffix: str = "") -> TuningSet:
    return TuningSet(f"box_{mass:g}kg_{1e3 * lever:g}mm{suffix}", trials, friction, offset, box=(mass, lever))


SETS = (TuningSet("eclair_mu_above_0.45", 150, (0.45, 1.2), 0, "eclair"),
        TuningSet("eclair_mu_below_0.45", 100, (0.2, 0.45), 1, "eclair"),
        TuningSet("bottle_upright", 30, (0.2, 1.2), 2, "bottle_upright"),
        TuningSet("bottle_horizontal", 30, (0.2, 1.2), 3, "bottle_horizontal"),
        TuningSet("eclair", 30, (0.2, 1.2), 4, "eclair"),
        _box_set(0.15, 0.0, 30, (0.2, 1.2), 5),
        *(_box_set(mass, lever, 20, (0.2, 1.2), 6 + index)
          for index, (mass, lever) in enumerate(((0.3, 0.025), (0.45, 0.05), (0.15, 0.05), (0.3, 0.0), (0.45, 0.0)))),
        # drawn after the held-out Fig. 11 showed a loss there (docs/design.md, sec. 12): moment-loaded boxes below
        # the prior, on the first four sets' generators
        *(_box_set(mass, lever, 30, (0.2, 0.4), index, "_low_friction")
          for index, (mass, lever) in enumerate(((0.3, 0.025), (0.45, 0.05), (0.45, 0.025), (0.3, 0.05)))),
        # drawn after the held-out robustness run showed a loss there (docs/design.md, sec. 12): the horizontal
        # bottle below the prior, which the set of its own draws in 0.2-1.2 reaches in 5 trials
        TuningSet("bottle_horizontal_low_friction", 120, (0.2, 0.4), 11, "bottle_horizontal"))


# the node noise times this at least (5 uN per node: the law sets its gates from the noise it reads at rest, and an
# array with next to none leaves them at next to nothing) and at most (200 mN, past any array the loop was built for)
NOISE_SCALE_RANGE = (0.01, 100.0)


def check_noise_scale(scale: object) -> float:
    """``--sensor-noise-scale`` must be a number in NOISE_SCALE_RANGE [-]."""
    from fem.validation import check_range

    return check_range("--sensor-noise-scale", scale, *NOISE_SCALE_RANGE)


def add_arguments(parser) -> None:
    parser.add_argument("--sets", type=lambda text: [name for name in text.split(",") if name], default=None,
                        metavar="NAME,NAME", help=f"only these sets ({', '.join(s.name for s in SETS)})")
    parser.add_argument("--trials", type=int, default=None,
                        help="the first N trials of each set, at most the set's own (default: all; quick 2)")
    parser.add_argument("--processes", type=int, default=None, help="worker processes, 1 to 256 (default: every CPU)")
    add_swing_argument(parser)
    parser.add_argument("--sensor-noise-scale", type=float, default=1.0, metavar="S",
                        help=f"every trial's node noise times S, the draws unchanged (default 1: the protocol's "
                             f"0.5-2 mN; allowed {NOISE_SCALE_RANGE[0]:g}-{NOISE_SCALE_RANGE[1]:g}); give it an --out "
                             f"of its own: the table keeps only the trials of its last run")


def grasp_object(entry: TuningSet):
    """The set's GraspObject: its Table I object, or Fig. 11's box (200 x 70 x 70 mm) of its mass and lever."""
    from controller.closed_loop import TABLE_I_OBJECTS, GraspObject
    from studies.fig11 import GRASP_HEIGHT, SIZE

    if entry.table_object is not None:
        return TABLE_I_OBJECTS[entry.table_object]
    mass, lever = entry.box
    return GraspObject(f"box_{mass:g}kg_{1e3 * lever:g}mm", mass, SIZE, lever, GRASP_HEIGHT)


def jobs(sets: list[str] | None = None, trials: int | None = None, quick: bool = False,
         sensor_noise_scale: float = 1.0, swing_margin: float = 0.0) -> list[tuple]:
    """The chosen sets' trials as ``run_trial_table`` jobs (key, object, settings, info), in set order; each trial's
    node noise [N] times ``sensor_noise_scale`` after its draw, and the law's ``swing_margin`` (the key follows the
    settings)."""
    from controller.closed_loop import TUNING_SEED, random_settings

    known = [entry.name for entry in SETS]
    unknown = sorted(set(sets or ()) - set(known))
    if unknown or sets == []:
        raise ValueError(f"sets={sets!r}: unknown {unknown}; allowed: {known}")
    if trials is not None:
        check_trials(trials)
    scale = check_noise_scale(sensor_noise_scale)
    margin = check_swing_margin(swing_margin)
    out = []
    for entry in SETS:
        if sets is not None and entry.name not in sets:
            continue
        obj = grasp_object(entry)
        fixed = {} if entry.box is None else {"place": False, "hold_time": 4.0}       # Fig. 11's lift and hold
        rng = np.random.default_rng(TUNING_SEED + entry.offset)
        for trial in range(min(entry.trials, trials if trials is not None else (2 if quick else entry.trials))):
            settings = random_settings(rng, friction_range=entry.friction, **fixed)
            settings = replace(settings, sensor_noise=settings.sensor_noise * scale, swing_margin=margin)
            info = {"set": entry.name, "trial": trial, "crush_force": obj.crush_force}
            # the set in the key: a renamed set runs again rather than reading its rows back under the old name
            out.append((trial_key(obj, settings, f"tuning:{entry.name}"), obj, settings, info))
    return out


def _row(result, info) -> dict:
    return dict(set=info["set"], object=result.object_name, trial=info["trial"], **trial_columns(result, info))


def run(out_dir, quick: bool = False, sets: list[str] | None = None, trials: int | None = None,
        processes: int | None = None, sensor_noise_scale: float = 1.0, swing_margin: float = 0.0) -> dict:
    """Every chosen set's trials (resumable), the per-set summary and the figure."""
    out_dir = Path(out_dir)
    chosen = jobs(sets, trials, quick, sensor_noise_scale, swing_margin)
    rows = run_trial_table(out_dir / f"{NAME}.csv", chosen, _row, processes, label=NAME)
    summary = summarise(rows, sensor_noise_scale)
    write_csv_atomic(out_dir / f"{NAME}_summary.csv", summary)
    for entry in summary:
        print(f"{NAME}: {entry['set']}: held {entry['held']}/{entry['trials']} (95 % Wilson interval "
              f"{100 * entry['success_low']:.0f}-{100 * entry['success_high']:.0f} %), {entry['turned_out']} turned "
              f"out, {entry['dropped']} dropped, {entry['crushed']} crushed ({entry['infeasible']} infeasible, "
              f"{entry['beyond_actuator']} past the actuator's grip); "
              f"{entry['no_slip_seen']} with no slip seen; settled grip {entry['grip_over_limit_mean']:.2f} x the slip "
              f"limit (max {entry['grip_over_limit_max']:.2f}); largest turn of a held object "
              f"{entry['rotation_max_mrad']:.0f} mrad; {_friction_error(entry)}")
    held = sum(entry["held"] for entry in summary)
    print(f"{NAME}: held {held} of {len(rows)} in all")
    save_figure(_plot(summary, sensor_noise_scale, swing_margin), out_dir, NAME)
    return {"max_error": 1.0 - held / len(rows), "error_meaning": "share of the tuning trials not held",
            "held": held, "trials": len(rows), "sets": summary}


def _friction_error(entry: dict) -> str:
    """The summary's friction error in words (none where no trial of the set measured it)."""
    if not np.isfinite(entry["friction_error_median"]):
        return "friction measured in no trial"
    return (f"friction read {100 * entry['friction_error_median']:+.0f} % at the median (lowest "
            f"{100 * entry['friction_error_min']:+.0f} %)")


def summarise(rows, sensor_noise_scale: float = 1.0) -> list[dict]:
    """One row per set: the node noise's scale, outcomes, the held rate and its Wilson interval, trials past the
    crush force (infeasible) and past the finger drive's largest grip (GRIP_LIMIT, 30 N: the reduced model's
    slip limit asks more than the gripper gives), trials with no slip seen, grip over the slip limit [-], the largest
    turn of a held object [mrad], the friction estimate's relative error [-] over the trials that measured it (a slip
    seen): median and most negative."""
    from controller.closed_loop import GRIP_LIMIT, OUTCOMES
    from controller.design import wilson_interval

    out = []
    for name in dict.fromkeys(row["set"] for row in rows):
        mine = [row for row in rows if row["set"] == name]
        held = [row for row in mine if row["outcome"] == "held"]
        low, high = wilson_interval(len(held), len(mine))
        grip = np.array([row["force_ratio"] for row in held], dtype=float)
        turns = np.array([row["max_rotation_mrad"] for row in held], dtype=float)
        errors = np.array([row["friction_estimate_error"] for row in mine if row["slips_detected"] > 0],
                          dtype=float)
        counts = {outcome: sum(row["outcome"] == outcome for row in mine) for outcome in OUTCOMES}
        out.append(dict(set=name, sensor_noise_scale=sensor_noise_scale, trials=len(mine), **counts,
                        success_rate=len(held) / len(mine), success_low=low, success_high=high,
                        infeasible=sum(not row["feasible"] for row in mine),
                        beyond_actuator=sum(row["required_force"] > GRIP_LIMIT for row in mine),
                        no_slip_seen=sum(row["slips_detected"] == 0 for row in mine),
                        grip_over_limit_mean=float(grip.mean()) if grip.size else float("nan"),
                        grip_over_limit_max=float(grip.max()) if grip.size else float("nan"),
                        rotation_max_mrad=float(turns.max()) if turns.size else float("nan"),
                        friction_error_median=float(np.median(errors)) if errors.size else float("nan"),
                        friction_error_min=float(errors.min()) if errors.size else float("nan")))
    return out


def _plot(summary, sensor_noise_scale: float = 1.0, swing_margin: float = 0.0):
    """Outcome shares per set, stacked horizontal bars, each set's friction range and held count on its label."""
    import matplotlib.pyplot as plt

    colours = {"held": "tab:green", "turned_out": "tab:orange", "dropped": "tab:red", "crushed": "tab:purple"}
    ranges = {entry.name: entry.friction for entry in SETS}
    fig, ax = plt.subplots(figsize=(8.5, 0.38 * len(summary) + 1.4), constrained_layout=True)
    labels = [f"{e['set']} (mu {ranges[e['set']][0]:g}-{ranges[e['set']][1]:g}): {e['held']}/{e['trials']}"
              for e in summary]
    left = np.zeros(len(summary))
    for outcome, colour in colours.items():
        share = np.array([entry[outcome] / entry["trials"] for entry in summary])
        ax.barh(labels, share, left=left, color=colour, label=outcome.replace("_", " "))
        left += share
    ax.invert_yaxis()
    ax.set_xlim(0.0, 1.0)
    ax.set_xlabel("share of the set's trials")
    noise = "" if sensor_noise_scale == 1.0 else f", node noise x{sensor_noise_scale:g}"
    noise += f", swing margin {swing_margin:g}" if swing_margin else ""
    ax.set_title(f"tuning draws{noise}: {sum(e['held'] for e in summary)} of {sum(e['trials'] for e in summary)} held")
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.1), fontsize=8, ncol=4, frameon=False)
    return fig
