"""Fig. 6 answered by grasp outcome (``python -m studies fig6 --grasp``): the bench's arrays through the closed loop.

The bench's fingertips (1x1 ... 4x4 on the 40 x 40 mm base, ``controller.estimation.bench``) read at 1 and 3 mm sensor
pitch go through the design study with its closed loop (``controller.design``, ``DesignStudy.closed_loop``): each
array calibrated on its own FEM, its plant built from that FEM (what makes the data) and its estimator's sensor model
fitted on its bench (what estimates it), then Table I trials on the held-out draws. One row per array and pitch:
success rate (held) with its 95 % Wilson interval, settled grip over the trial's slip limit (mean, sd, max over the
held trials), outcomes, and beside them the estimation errors (the design study's translational error and, when
the bench ran, Fig. 6's capacitive error after calibration). An array the closed loop cannot represent (1x1) is
kept with the reason it was refused. The verdict on the paper's "3x3 is best" is decided only where the intervals
say so.
"""

from __future__ import annotations

import math

import numpy as np

GRASP_TRIALS = 10                  # per Table I object (3 objects: 30 trials per design); quick: 1
Z_95 = 1.959963984540054           # two-sided 95 % normal quantile: the grip-ratio comparison's threshold


def bench_designs(arrays, pitches) -> list:
    """The Fig. 6 bench's fingertip of every array in ``arrays`` (n for n x n) read at every sensor pitch [mm]:
    pitch FOOTPRINT / n, bump radius BUMP_FILL x pitch, the bench's base, E and nu (the 3x3 is the shipped design)."""
    from controller.design import FingertipDesign
    from controller.estimation.bench import BASE_THICKNESS, BUMP_FILL, FOOTPRINT, POISSONS_RATIO, YOUNGS_MODULUS

    return [FingertipDesign(rows=n, cols=n, pitch=FOOTPRINT / n, bump_radius=BUMP_FILL * FOOTPRINT / n,
                            base_thickness=BASE_THICKNESS, youngs_modulus=YOUNGS_MODULUS,
                            poissons_ratio=POISSONS_RATIO, sensor_pitch=float(pitch), base_width=FOOTPRINT,
                            base_depth=FOOTPRINT)
            for n in arrays for pitch in pitches]


def grasp_study(quick: bool, trials: int):
    """The closed-loop DesignStudy of the panel: the bench's press and friction, the design study's defaults (the
    study of studies/designs/array_size_grasp.toml, so that the two share meshes and fits); quick: coarse meshes."""
    from controller.design import DesignStudy
    from controller.estimation.bench import FRICTION, NORMAL_FORCE

    coarse = dict(size_contact=0.7, size_base=1.5, noise_draws=2, calibration_size_contact=1.0,
                  calibration_size_base=2.0) if quick else {}
    return DesignStudy(normal_force=NORMAL_FORCE, friction_coefficient=FRICTION, closed_loop=True,
                       grasp_trials=trials, **coarse)


def _value(row, key):
    """A table cell as a float, None when missing."""
    import pandas as pd

    value = row[key]
    return None if pd.isna(value) else float(value)


def grasp_rows(table, bench_rows: list[dict]) -> list[dict]:
    """One row per array and sensor pitch from the closed-loop design table and Fig. 6's bench rows (capacitive
    sensor; empty when the bench did not run)."""
    bench = {(r["bumps"], r["sensor_pitch"]): r["error_after_percent"] for r in bench_rows
             if r["sensor"] == "capacitive"}
    rows = []
    for _, row in table.iterrows():
        n, pitch = int(row["rows"]), float(row["sensor_pitch"])
        trials = 0 if row["grasp_status"] != "ok" else int(row["grasp_trials"])
        translational = _value(row, "translational_error")
        rows.append(dict(case=f"{n}x{n}", bumps=n * n, sensor_pitch=pitch, status=row["status"],
                         grasp_status=row["grasp_status"], reason=row["grasp_error"], trials=trials,
                         held=int(row["grasp_held"]) if trials else None,
                         success_rate=_value(row, "grasp_success_rate"),
                         success_low=_value(row, "grasp_success_low"),
                         success_high=_value(row, "grasp_success_high"),
                         turned_out=int(row["grasp_turned_out"]) if trials else None,
                         dropped=int(row["grasp_dropped"]) if trials else None,
                         crushed=int(row["grasp_crushed"]) if trials else None,
                         grip_over_slip_limit=_value(row, "grip_over_slip_limit"),
                         grip_over_slip_limit_sd=_value(row, "grip_over_slip_limit_sd"),
                         grip_over_slip_limit_max=_value(row, "grip_over_slip_limit_max"),
                         grasp_slide_median_mm=_value(row, "grasp_slide_median"),
                         grasp_slide_max_mm=_value(row, "grasp_slide_max"),
                         friction_estimate_error=_value(row, "friction_estimate_error"),
                         detection_lead_time=_value(row, "detection_lead_time"),
                         translational_error_percent=None if translational is None else 100 * translational,
                         bench_error_after_percent=bench.get((n * n, pitch)),
                         calibration_wall=_value(row, "calibration_wall"), bench_wall=_value(row, "bench_wall"),
                         trials_wall=_value(row, "trials_wall")))
    return rows


def _compare_success(three, other) -> int:
    """+1: the 3x3's success rate is above ``other``'s beyond both 95 % Wilson intervals; -1: below; 0: overlap."""
    if three["success_low"] > other["success_high"]:
        return 1
    if three["success_high"] < other["success_low"]:
        return -1
    return 0


def _compare_grip(three, other) -> int | None:
    """+1: the 3x3 holds nearer its slip limit (lower mean grip ratio) by more than 1.96 standard errors of the
    difference (Welch); -1: farther; 0: within; None: fewer than two held trials on a side."""
    values = []
    for row in (three, other):
        if row["grip_over_slip_limit_sd"] is None or not row["held"] or row["held"] < 2:
            return None
        values.append((row["grip_over_slip_limit"], row["grip_over_slip_limit_sd"] ** 2 / row["held"]))
    (mean_three, var_three), (mean_other, var_other) = values
    difference, error = mean_other - mean_three, math.sqrt(var_three + var_other)
    if abs(difference) <= Z_95 * error:
        return 0
    return 1 if difference > 0 else -1


def _judge(outcomes: list) -> str:
    """Supported when every comparison favours the 3x3, contradicted when any favours another, else not decided."""
    if any(outcome == -1 for outcome in outcomes):
        return "contradicted"
    if outcomes and all(outcome == 1 for outcome in outcomes):
        return "supported"
    return "not decided"


def grasp_verdict(rows: list[dict], pitches) -> list[str]:
    """Lines: the refused arrays and why; per pitch the success rates and grip ratios measured, and whether
    "3x3 is best" is supported, contradicted or not decided by them (Wilson intervals; Welch at 1.96 standard
    errors for the grip ratio)."""
    lines = [f"{r['case']} at {r['sensor_pitch']:g} mm refused by the closed loop: {r['reason']}"
             for r in rows if r["grasp_status"] == "refused"]
    lines += [f"{r['case']} at {r['sensor_pitch']:g} mm failed: {r['reason']}"
              for r in rows if r["grasp_status"] == "failed"]
    for pitch in pitches:
        ran = [r for r in rows if r["sensor_pitch"] == pitch and r["grasp_status"] == "ok"]
        if not ran:
            continue
        numbers = "; ".join(
            f"{r['case']} {r['held']}/{r['trials']} held (95 % {100 * r['success_low']:.0f}-"
            f"{100 * r['success_high']:.0f} %), grip/slip limit "
            + ("-" if r["grip_over_slip_limit"] is None else f"{r['grip_over_slip_limit']:.2f}"
               + ("" if r["grip_over_slip_limit_sd"] is None else f" +- {r['grip_over_slip_limit_sd']:.2f}"))
            for r in ran)
        lines.append(f"grasp at {pitch:g} mm sensor pitch: {numbers}")
        three = next((r for r in ran if r["bumps"] == 9), None)
        others = [r for r in ran if r["bumps"] != 9]
        if three is None or not others:
            lines.append(f"'3x3 is best' by grasp at {pitch:g} mm: not decided (the 3x3 or every other array "
                         f"did not run)")
            continue
        success = _judge([_compare_success(three, other) for other in others])
        grips = [_compare_grip(three, other) for other in others]
        grip = "not decided (fewer than two held trials)" if None in grips else _judge(grips)
        sizes = ", ".join(sorted({str(r["trials"]) for r in ran}))
        lines.append(f"'3x3 is best' by grasp at {pitch:g} mm ({sizes} trials per array): by success rate "
                     f"{success}; by grip over slip limit {grip}")
    return lines


def plot_grasp(rows: list[dict], arrays, pitches, wall: float):
    """Three panels by array, bars per sensor pitch: success rate with its Wilson interval, grip over slip limit
    (mean, sd bars), estimation errors; a refused array is marked with its reason instead of a bar."""
    import textwrap

    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(16, 4.8))
    width = 0.8 / len(pitches)
    positions = np.arange(len(arrays))
    colours = ("#2b8cbe", "#fdae61", "#66c2a5")
    lookup = {(r["bumps"], r["sensor_pitch"]): r for r in rows}
    notes: dict = {}                          # reason -> the arrays refused or failed with it, listed under the panels
    for index, (pitch, colour) in enumerate(zip(pitches, colours)):
        offset = (index - (len(pitches) - 1) / 2) * width
        cells = [lookup.get((n * n, pitch)) for n in arrays]
        ran = [c is not None and c["grasp_status"] == "ok" for c in cells]
        x = positions[ran] + offset
        rate = np.array([100 * c["success_rate"] for c, ok in zip(cells, ran) if ok])
        low = np.array([100 * c["success_low"] for c, ok in zip(cells, ran) if ok])
        high = np.array([100 * c["success_high"] for c, ok in zip(cells, ran) if ok])
        if x.size:
            axes[0].bar(x, rate, width, color=colour, edgecolor="k", label=f"{pitch:g} mm pitch",
                        yerr=[rate - low, high - rate], capsize=3)
            for xi, c in zip(x, [c for c, ok in zip(cells, ran) if ok]):
                axes[0].annotate(f"{c['held']}/{c['trials']}", (xi, 2), ha="center", fontsize=7, rotation=90)
            grip = np.array([np.nan if c["grip_over_slip_limit"] is None else c["grip_over_slip_limit"]
                             for c, ok in zip(cells, ran) if ok])
            spread = np.array([0.0 if c["grip_over_slip_limit_sd"] is None else c["grip_over_slip_limit_sd"]
                               for c, ok in zip(cells, ran) if ok])
            axes[1].bar(x, grip, width, color=colour, edgecolor="k", yerr=spread, capsize=3,
                        label=f"{pitch:g} mm pitch")
        for n, cell in zip(arrays, cells):
            if cell is not None and cell["grasp_status"] != "ok":
                notes.setdefault(cell["reason"], []).append(f"{n}x{n} at {pitch:g} mm")
                mark = len(list(notes)[:list(notes).index(cell["reason"]) + 1])
                for axis in axes[:2]:
                    axis.text(positions[arrays.index(n)] + offset, 0.02, f"{cell['grasp_status']} at {pitch:g} mm "
                              f"[{mark}]", fontsize=7, rotation=90, ha="center", va="bottom",
                              transform=axis.get_xaxis_transform(), color="#b2182b")
        design_error = [np.nan if c is None or c["translational_error_percent"] is None
                        else c["translational_error_percent"] for c in cells]
        axes[2].plot(positions, design_error, "o-", color=colour, label=f"design study, {pitch:g} mm")
        bench = [np.nan if c is None or c["bench_error_after_percent"] is None else c["bench_error_after_percent"]
                 for c in cells]
        if np.isfinite(bench).any():
            axes[2].plot(positions, bench, "s--", color=colour, label=f"Fig. 6 bench (calibrated), {pitch:g} mm")
    axes[0].set_ylabel("success rate (held), 95 % Wilson [%]")
    axes[0].set_ylim(0, 105)
    axes[1].axhline(1.0, color="k", lw=0.8)
    axes[1].set_ylabel("settled grip / slip limit, held trials (mean, sd) [-]")
    axes[2].set_ylabel("shear-displacement estimation error [%]")
    for axis in axes:
        axis.set_xticks(positions, [f"{n} x {n}" for n in arrays])
        axis.set_xlim(-0.6, len(arrays) - 0.4)            # a refused array's note stays inside the panel
        axis.set_xlabel("hemisphere array")
        axis.grid(axis="y", alpha=0.3)
        axis.legend(fontsize=7)
    trials = sorted({r["trials"] for r in rows if r["trials"]})
    # a resumed run computes nothing: say what the recorded closed-loop stages took as well as this run
    stages = sum(r[name] or 0.0 for r in rows for name in ("calibration_wall", "bench_wall", "trials_wall"))
    fig.suptitle(f"Fig. 6 by grasp outcome: Table I objects, held-out draws, {'/'.join(map(str, trials)) or '-'} "
                 f"trials per array and pitch; plant from each design's FEM, estimator fitted on its bench "
                 f"(closed-loop stages {stages:.0f} s as recorded; this run {wall:.0f} s)", fontsize=9)
    listing = [f"[{mark}] {', '.join(cases)}: {reason}" for mark, (reason, cases) in enumerate(notes.items(), 1)]
    text = "\n".join(textwrap.fill(line, 200) for line in listing)
    fig.text(0.01, 0.01, text, fontsize=7, va="bottom", color="#b2182b")
    fig.tight_layout(rect=(0, 0.04 * text.count("\n") + (0.05 if text else 0.0), 1, 1))
    return fig
