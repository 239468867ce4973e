"""Fig. 11 (closed loop, MuJoCo): the grasp force the controller settles at against tau_min from constant-force trials.

A box (200 x 70 x 70 mm, as the horizontal bottle) of three masses, grasped at three distances from its centre of
mass (the moment about the fingertip normal), each case with several trials of the protocol (friction 0.2-1.2,
plant factors within +-10 %, grasp jitter, misalignment, sensor noise; the held-out seed). In each trial the
incipient-slip controller lifts and holds the box (4 s): tau is its grip over the last second of the hold. tau_min is
that trial's own minimum grasp force, found the way the paper does - constant-force trials (lift, then 1 s of hold)
with the same friction, jitter, noise, seed and plant (the same perturbed build) - from a bracket seen to fail and
hold (searched from the controller's grip in steps of 25 %), by bisection to 2 %
(``controller.closed_loop.minimum_grip_force``; the model's slip limit is not used, only reported). A trial is
held when the box neither touches the table nor turns out of the grasp.
Outputs: fig11.csv (one row per trial, written as each finishes; a re-run skips the trials already there),
fig11.png/pdf.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studies._output import save_figure
from studies._trials import (add_plant_arguments, add_swing_argument, check_trials, outcome_columns, plant_options,
                             run_trial_table, trial_key, trial_settings)

NAME = "fig11"
SIZE = (0.200, 0.070, 0.070)          # m, the horizontal bottle
GRASP_HEIGHT = 0.035                  # m, the fingertip centre above the table
TRIALS = 3
RESOLUTION = 0.02                     # tau_min bisection to 2 %
BRACKET_FACTOR = 1.25                 # the bracket search steps from the controller's own grip by this factor
CLOSE_MEAN, CLOSE_MAX = 1.3, 1.5      # the 'close to tau_min': mean and largest tau / tau_min


def add_arguments(parser) -> None:
    parser.add_argument("--trials", type=int, default=None, help=f"trials per case (default {TRIALS}, quick 1)")
    parser.add_argument("--processes", type=int, default=None, help="worker processes, 1 to 256 (default: every CPU)")
    add_plant_arguments(parser)
    add_swing_argument(parser)


def cases(quick: bool) -> list[tuple[float, float]]:
    """(mass [kg], lever [m]) of the boxes: 3 x 3 (quick: two)."""
    if quick:
        return [(0.3, 0.0), (0.2, 0.04)]
    return [(mass, lever) for mass in (0.15, 0.3, 0.45) for lever in (0.0, 0.025, 0.05)]


def trial_and_minimum(obj, settings) -> dict:
    """The controller's trial and the trial's tau_min (run in one worker: the bisection is sequential)."""
    from controller.closed_loop import minimum_grip_force, run_trial

    result = run_trial(obj, settings)
    start = result.hold_force_settled if result.success and not result.rotated else 1.0
    minimum = minimum_grip_force(obj, settings, RESOLUTION, start=start, factor=BRACKET_FACTOR)
    return dict(result=result, tau_min=minimum.force, tau_min_failing=minimum.failing,
                bisection_trials=len(minimum.trials))


def _row(value, info) -> dict:
    result = value["result"]
    held = result.outcome == "held"
    tau = result.hold_force_settled
    return dict(case=info["case"], trial=info["trial"], mass_kg=info["mass"], lever_mm=1e3 * info["lever"],
                moment_nmm=info["mass"] * 9.81 * info["lever"] * 1e3,
                friction_coefficient=result.settings.friction_coefficient, held=held,
                **outcome_columns(result, info["required"], np.inf), tau=tau,
                tau_min=value["tau_min"], tau_min_failing=value["tau_min_failing"],
                ratio=tau / value["tau_min"] if held else np.nan, model_limit=info["required"],
                bisection_trials=value["bisection_trials"])


def run(out_dir, quick: bool = False, trials: int | None = None, processes: int | None = None,
        plant_spread: float | None = None, plant: str | None = None, sensor_plane: str = "fem",
        swing_margin: float = 0.0) -> dict:
    """Controller trial and tau_min per trial; CSV and figure."""
    from controller.closed_loop import HELD_OUT_SEED, GraspObject

    out_dir = Path(out_dir)
    trials = (1 if quick else TRIALS) if trials is None else trials
    check_trials(trials)
    options = plant_options(plant_spread, plant, sensor_plane, swing_margin)
    rng = np.random.default_rng(HELD_OUT_SEED + 11)
    jobs = []
    for mass, lever in cases(quick):
        obj = GraspObject(f"box_{mass:g}kg_{1e3 * lever:g}mm", mass, SIZE, lever, GRASP_HEIGHT)
        for trial in range(trials):
            settings = trial_settings(rng, **options, place=False, hold_time=4.0)
            info = dict(case=obj.name, trial=trial, mass=mass, lever=lever)
            jobs.append((trial_key(obj, settings, "tau_min"), obj, settings, info))
    rows = run_trial_table(out_dir / f"{NAME}.csv", jobs, _row, processes, label=NAME,
                           function=trial_and_minimum)
    summary = _summary(rows)
    print(f"{NAME}: {len(rows)} trials in {len(cases(quick))} cases: {summary['held']} held, {summary['dropped']} "
          f"dropped, {summary['rotated']} turned out; tau / tau_min mean {summary['ratio_mean']:.3f}, range "
          f"[{summary['ratio_min']:.3f}, {summary['ratio_max']:.3f}] (target mean <= {CLOSE_MEAN}, max <= "
          f"{CLOSE_MAX}); tau_min / model limit {summary['tau_min_over_model_mean']:.3f} on average")
    save_figure(_plot(rows), out_dir, NAME)
    return {"max_error": float(summary["ratio_max"] - 1.0) if np.isfinite(summary["ratio_max"]) else None,
            "error_meaning": "largest tau / tau_min - 1 over the held trials", **summary}


def _summary(rows) -> dict:
    ratios = np.array([row["ratio"] for row in rows], dtype=float)
    held = ratios[np.isfinite(ratios)]
    return dict(trials=len(rows), held=int(sum(bool(r["held"]) for r in rows)),
                dropped=int(sum(bool(r["dropped"]) for r in rows)),
                rotated=int(sum(bool(r["rotated"]) for r in rows)),
                ratio_mean=float(held.mean()) if held.size else np.nan,
                ratio_min=float(held.min()) if held.size else np.nan,
                ratio_max=float(held.max()) if held.size else np.nan,
                tau_min_over_model_mean=float(np.mean([r["tau_min"] / r["model_limit"] for r in rows])),
                close_mean=CLOSE_MEAN, close_max=CLOSE_MAX)


def _plot(rows):
    import matplotlib.pyplot as plt

    names = list(dict.fromkeys(row["case"] for row in rows))
    fig, axes = plt.subplots(2, 1, figsize=(9, 7.5), sharex=True, gridspec_kw=dict(height_ratios=(3, 2)))
    for i, name in enumerate(names):
        mine = [r for r in rows if r["case"] == name]
        jitter = np.linspace(-0.15, 0.15, len(mine)) if len(mine) > 1 else np.zeros(1)
        x = i + jitter
        axes[0].scatter(x, [r["tau_min"] for r in mine], marker="s", color="#e6550d", zorder=3,
                        label="tau_min (constant-force trials)" if i == 0 else None)
        axes[0].scatter(x, [r["tau"] for r in mine], marker="o", color="#3182bd", zorder=4,
                        label="tau (controller, last second of the hold)" if i == 0 else None)
        axes[0].scatter(x, [r["model_limit"] for r in mine], marker="_", s=120, color="k", zorder=5,
                        label="slip limit of the reduced model" if i == 0 else None)
        colours = ["#31a354" if r["held"] else "#de2d26" for r in mine]
        axes[1].scatter(x, [r["ratio"] if r["held"] else 0.95 for r in mine], c=colours, zorder=3)
    axes[1].axhline(1.0, color="#e6550d", linewidth=1)
    axes[1].axhline(CLOSE_MAX, color="k", linestyle=":", linewidth=1, label=f"max {CLOSE_MAX}")
    axes[1].axhline(CLOSE_MEAN, color="k", linestyle="--", linewidth=1, label=f"mean {CLOSE_MEAN}")
    axes[0].set_ylabel("grasp force per finger [N]")
    axes[0].set_title("Fig. 11: tau against the trial's own tau_min (friction 0.2-1.2, plant factors +-10 %, jitter, "
                      "noise)", fontsize=10)
    axes[1].set_ylabel("tau / tau_min (red: not held)")
    labels = [f"{r['mass_kg']:g} kg\n{r['moment_nmm']:.0f} N mm" for r in
              (next(r for r in rows if r["case"] == name) for name in names)]
    axes[1].set_xticks(range(len(names)), labels, fontsize=8)
    for axis in axes:
        axis.grid(alpha=0.3)
        axis.legend(fontsize=8)
    fig.tight_layout()
    return fig
