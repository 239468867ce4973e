"""Fig. 11 (closed loop, MuJoCo): grasp force from the controller against tau_min from constant-force trials.

A box (200 x 70 x 70 mm, as the horizontal bottle) of several masses, grasped at several distances from its centre of
mass (the moment about the fingertip normal), at mu = 0.6. tau_min is found as the paper does: constant grasp forces
are tried (grasp, lift, hold) and the least successful one is kept - here by bisection between brackets around the
reduced model's slip limit. The controller's hold force (range and mean over trials with different sensor noise and
grasp jitter) is compared with tau_min; the ratio tau / tau_min says how much more force the controller spends.
Outputs: fig11.csv (one row per case), fig11.png/pdf.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic

NAME = "fig11"
FRICTION = 0.6
SIZE = (0.200, 0.070, 0.070)          # m, the horizontal bottle
CONSTANT_FORCE_HOLD = 1.0             # s: a constant grip that slips does so at the lift (no creep in the model)


def add_arguments(parser) -> None:
    parser.add_argument("--trials", type=int, default=None, help="controller trials per case (default 3, quick 1)")


def _cases(quick: bool):
    if quick:
        return [(0.4, 0.0), (0.2, 0.04)]
    return [(mass, lever) for mass in (0.15, 0.3, 0.45) for lever in (0.0, 0.025, 0.05)]


def tau_min(obj, steps: int, rng, settings_base) -> tuple[float, int]:
    """Least successful constant grip force per finger [N] by bisection; returns (force, trials run)."""
    from dataclasses import replace

    from studies._grasp_world import required_grip_force, run_trial

    def succeeds(force):
        settings = replace(settings_base, constant_force=float(force), hold_time=CONSTANT_FORCE_HOLD, place=False,
                           seed=int(rng.integers(2**31)))
        return run_trial(obj, settings).success

    theory = required_grip_force(obj, settings_base.friction)
    low, high, count = 0.7 * theory, 1.5 * theory, 0
    while not succeeds(high):
        low, high, count = high, 1.5 * high, count + 1
    count += 1
    for _ in range(steps):
        middle = 0.5 * (low + high)
        if succeeds(middle):
            high = middle
        else:
            low = middle
        count += 1
    return high, count


def run(out_dir, quick: bool = False, trials: int | None = None) -> dict:
    """Controller trials and constant-force bisection per case; CSV and figure."""
    from studies._grasp_world import GraspObject, TrialSettings, random_settings, required_grip_force, run_trial

    out_dir = Path(out_dir)
    trials = (1 if quick else 3) if trials is None else int(trials)
    steps = 3 if quick else 5
    rng = np.random.default_rng(11)
    rows = []
    for mass, lever in _cases(quick):
        obj = GraspObject(f"box_{mass:g}kg_{1e3 * lever:g}mm", mass, SIZE, lever, 0.035)
        forces = []
        for _ in range(trials):
            settings = random_settings(rng, friction=FRICTION, place=False, hold_time=2.0 if quick else 4.0)
            result = run_trial(obj, settings)
            forces.append(result.hold_force_mean if result.success else np.nan)
        minimum, bisection_trials = tau_min(obj, steps, rng, TrialSettings(friction=FRICTION))
        forces = np.array(forces)
        rows.append(dict(mass_kg=mass, lever_mm=1e3 * lever, moment_nmm=mass * 9.81 * lever * 1e3,
                         tau_mean=float(np.nanmean(forces)), tau_min_trials=float(np.nanmin(forces)),
                         tau_max_trials=float(np.nanmax(forces)), failed_trials=int(np.isnan(forces).sum()),
                         tau_min=minimum, tau_min_theory=required_grip_force(obj, FRICTION),
                         ratio=float(np.nanmean(forces)) / minimum, bisection_trials=bisection_trials))
        row = rows[-1]
        print(f"{NAME}: m {mass:g} kg, moment {row['moment_nmm']:.0f} N mm: tau {row['tau_mean']:.2f} N "
              f"[{row['tau_min_trials']:.2f}, {row['tau_max_trials']:.2f}], tau_min {minimum:.2f} N "
              f"(model limit {row['tau_min_theory']:.2f} N), ratio {row['ratio']:.2f}")
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    save_figure(_plot(rows), out_dir, NAME)
    ratios = np.array([row["ratio"] for row in rows])
    print(f"{NAME}: tau / tau_min mean {np.nanmean(ratios):.2f}, range [{np.nanmin(ratios):.2f}, "
          f"{np.nanmax(ratios):.2f}] at mu = {FRICTION} (targets designed for mu = 0.4)")
    return {"max_error": float(np.nanmax(np.abs(ratios - 1.0))),
            "error_meaning": "largest |tau / tau_min - 1| (force spent above the least that holds)",
            "ratio_mean": float(np.nanmean(ratios))}


def _plot(rows):
    import matplotlib.pyplot as plt

    fig, axis = plt.subplots(figsize=(8, 4.5))
    labels = [f"{r['mass_kg']:g} kg\n{r['moment_nmm']:.0f} N mm" for r in rows]
    x = np.arange(len(rows))
    mean = np.array([r["tau_mean"] for r in rows])
    low = mean - np.array([r["tau_min_trials"] for r in rows])
    high = np.array([r["tau_max_trials"] for r in rows]) - mean
    axis.errorbar(x - 0.1, mean, yerr=[low, high], fmt="o", color="#3182bd", capsize=4,
                  label="grasp force tau (controller, range and mean)")
    axis.plot(x + 0.1, [r["tau_min"] for r in rows], "s", color="#e6550d", label="tau_min (constant-force trials)")
    axis.plot(x + 0.1, [r["tau_min_theory"] for r in rows], "_", color="k", markersize=14,
              label="slip limit of the reduced model")
    axis.set_xticks(x, labels, fontsize=8)
    axis.set_ylabel("grasp force per finger [N]")
    axis.set_title(f"Fig. 11: tau against tau_min over weight and moment (mu = {FRICTION})", fontsize=10)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=8)
    fig.tight_layout()
    return fig
