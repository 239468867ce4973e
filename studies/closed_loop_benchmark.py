"""Closed-loop benchmark: simulated seconds per CPU second of one trial, against bare MuJoCo steps of the same world.

For each Table I object, one full trial (approach, grasp, lift, hold 4 s, place, release: 10 s simulated) at the
default rates (MuJoCo and contact at ``PHYSICS_RATE_HZ``, actuator loop at 8 kHz) and, for comparison, with MuJoCo
and the contact at 8 kHz (the rate the explicit loop needed). CPU time (``time.process_time``, robust to other jobs
on the machine) of building the world and of running it, medians over ``--repeats``; the floor is the CPU time of the
same number of bare ``mj_step`` calls on the same world (object on the table, no contact forces); cost / floor says
how much the contact, the actuator loop, the sensing and the controller add to MuJoCo's own step. The outcomes of the
two rates (hold force, largest rotation) are reported side by side. Throughput: ``--trials`` random Table I trials over
1 and 2 worker processes, trials per wall-clock second.
Outputs: closed_loop_benchmark.csv (one row per object, rate and repeat), closed_loop_benchmark.json (medians and
ratios), closed_loop_benchmark.png/pdf.
"""

from __future__ import annotations

import statistics
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic, write_json_atomic

NAME = "closed-loop-benchmark"
REFERENCE_RATE = 8000.0                   # Hz: the rate the explicit loop needed, beside the default
TARGET_REAL_TIME_FACTOR = 50.0            # simulated s per CPU s of one trial (issue target)


def add_arguments(parser) -> None:
    parser.add_argument("--repeats", type=int, default=None,
                        help="runs per object and rate (1 to 1000, default 3, quick 1); medians are reported")
    parser.add_argument("--trials", type=int, default=None,
                        help="trials for the throughput test (2 to 1000, default 8, quick 4)")


def _floor_seconds(world, steps: int) -> float:
    """CPU seconds of ``steps`` bare mj_step calls on a copy of the world's initial state."""
    import mujoco

    data = mujoco.MjData(world.model)
    mujoco.mj_forward(world.model, data)
    start = time.process_time()
    for _ in range(steps):
        mujoco.mj_step(world.model, data)
    return time.process_time() - start


def _timed_trial(obj, settings):
    from controller.closed_loop import GraspWorld

    start = time.process_time()
    world = GraspWorld(obj, settings)
    built = time.process_time()
    result = world.run()
    finished = time.process_time()
    steps = int(round(result.simulated_time * settings.physics_rate_hz))
    return result, built - start, finished - built, _floor_seconds(world, steps)


def run(out_dir, quick: bool = False, repeats: int | None = None, trials: int | None = None) -> dict:
    """Time trials per object and rate, the bare-step floor and the pool's throughput; CSV, JSON and figure."""
    from controller.closed_loop import TABLE_I_OBJECTS, TrialSettings, random_settings, run_trial, run_trials
    from fem.validation import check_integer

    # --quick sets the defaults; a count given explicitly is kept
    repeats = check_integer("--repeats", (1 if quick else 3) if repeats is None else repeats, 1, 1000)
    # at least one trial for each of the throughput test's 2 processes
    trials = check_integer("--trials", (4 if quick else 8) if trials is None else trials, 2, 1000)
    out_dir = Path(out_dir)
    names = ["eclair"] if quick else list(TABLE_I_OBJECTS)
    base = TrialSettings(friction_coefficient=0.8, hold_time=1.0 if quick else 4.0, seed=5)
    rates = (base.physics_rate_hz, REFERENCE_RATE)
    run_trial(TABLE_I_OBJECTS["eclair"], replace(base, hold_time=0.0, place=False))      # compile, warm the caches
    rows = []
    for name in names:
        for rate in rates:
            settings = replace(base, physics_rate_hz=rate)
            for repeat in range(repeats):
                result, build, cpu, floor = _timed_trial(TABLE_I_OBJECTS[name], settings)
                rows.append(dict(object=name, physics_rate_hz=rate, repeat=repeat, simulated_s=result.simulated_time,
                                 build_cpu_s=build, run_cpu_s=cpu, floor_cpu_s=floor,
                                 real_time_factor=result.simulated_time / cpu,
                                 real_time_factor_with_build=result.simulated_time / (cpu + build),
                                 cost_over_floor=cpu / floor, success=result.success,
                                 hold_force_mean=result.hold_force_mean, max_rotation_mrad=result.max_rotation_mrad))
                write_csv_atomic(out_dir / f"{NAME}.csv", rows)
                row = rows[-1]
                print(f"{NAME}: {name} at {rate / 1e3:g} kHz: {row['real_time_factor']:.1f}x real time per CPU "
                      f"second ({row['real_time_factor_with_build']:.1f}x with the world's build), cost / floor "
                      f"{row['cost_over_floor']:.2f}, hold force {row['hold_force_mean']:.3f} N")
    summary = {"configurations": {}}
    for name in names:
        for rate in rates:
            mine = [r for r in rows if r["object"] == name and r["physics_rate_hz"] == rate]
            median = {key: statistics.median(r[key] for r in mine)
                      for key in ("real_time_factor", "real_time_factor_with_build", "cost_over_floor", "run_cpu_s",
                                  "floor_cpu_s", "build_cpu_s", "hold_force_mean", "max_rotation_mrad")}
            summary["configurations"][f"{name}@{rate:g}Hz"] = median
    default = [summary["configurations"][f"{name}@{rates[0]:g}Hz"] for name in names]
    reference = [summary["configurations"][f"{name}@{rates[1]:g}Hz"] for name in names]
    summary["real_time_factor_median"] = statistics.median(d["real_time_factor"] for d in default)
    summary["cost_over_floor_median"] = statistics.median(d["cost_over_floor"] for d in default)
    summary["speedup_over_reference"] = statistics.median(r["run_cpu_s"] / d["run_cpu_s"]
                                                          for d, r in zip(default, reference))
    summary["hold_force_difference_reference"] = max(abs(d["hold_force_mean"] / r["hold_force_mean"] - 1.0)
                                                for d, r in zip(default, reference))
    summary["throughput"] = _throughput(TABLE_I_OBJECTS, base, trials, random_settings, run_trials)
    # one trial is serial (MuJoCo's step and the compiled loop use one thread; CPU time is what is measured), so the
    # thread pools do not change it: they are stated, and the throughput above is 1 and 2 processes side by side
    from studies._threads import describe_threads, thread_settings

    summary["thread_settings"] = thread_settings()
    write_json_atomic(out_dir / f"{NAME}.json", summary)
    print(f"{NAME}: threads: {describe_threads(summary['thread_settings'])}")
    print(f"{NAME}: one trial at the default rates: {summary['real_time_factor_median']:.1f}x real time per CPU second "
          f"(target {TARGET_REAL_TIME_FACTOR:g}x), {summary['cost_over_floor_median']:.2f} x the bare mj_step floor, "
          f"{summary['speedup_over_reference']:.1f}x faster than at {REFERENCE_RATE / 1e3:g} kHz, hold forces within "
          f"{100 * summary['hold_force_difference_reference']:.1f} % of it")
    for processes, entry in summary["throughput"].items():
        print(f"{NAME}: {trials} trials over {processes} process(es): {entry['wall_s']:.1f} s wall, "
              f"{entry['trials_per_s']:.2f} trials/s")
    save_figure(_plot(rows, summary, names, rates), out_dir, NAME)
    return {"max_error": float(summary["hold_force_difference_reference"]),
            "error_meaning": f"largest relative difference of the hold force between {rates[0]:g} Hz and "
                             f"{REFERENCE_RATE:g} Hz physics",
            **{key: summary[key] for key in ("real_time_factor_median", "cost_over_floor_median",
                                             "speedup_over_reference")}}


def _throughput(objects, base, trials, random_settings, run_trials) -> dict:
    rng = np.random.default_rng(17)
    names = list(objects)
    jobs = [(objects[names[i % len(names)]], random_settings(rng, hold_time=base.hold_time)) for i in range(trials)]
    out = {}
    for processes in (1, 2):
        start = time.perf_counter()
        for _ in run_trials(jobs, processes):
            pass
        wall = time.perf_counter() - start
        out[str(processes)] = dict(wall_s=wall, trials_per_s=trials / wall)
    return out


def _plot(rows, summary, names, rates):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    width = 0.38
    for shift, rate, colour in ((-width / 2, rates[0], "#3182bd"), (width / 2, rates[1], "#bdbdbd")):
        values = [summary["configurations"][f"{name}@{rate:g}Hz"] for name in names]
        x = np.arange(len(names)) + shift
        axes[0].bar(x, [v["real_time_factor"] for v in values], width, color=colour,
                    label=f"MuJoCo + contact at {rate / 1e3:g} kHz")
        axes[1].bar(x, [v["cost_over_floor"] for v in values], width, color=colour)
    axes[0].axhline(TARGET_REAL_TIME_FACTOR, color="#e6550d", linestyle="--", label="target")
    axes[0].set_ylabel("simulated s per CPU s")
    axes[0].set_title("(a) one trial, real-time factor (CPU)", fontsize=10)
    axes[1].axhline(1.0, color="k", linewidth=1)
    axes[1].set_ylabel("trial CPU / bare mj_step CPU")
    axes[1].set_title("(b) cost over the floor of the same world", fontsize=10)
    for axis in axes:
        axis.set_xticks(range(len(names)), [n.replace("_", "\n") for n in names])
        axis.grid(alpha=0.3, axis="y")
    axes[0].legend(fontsize=8)
    fig.suptitle("Closed-loop cost: compiled loop, implicit contact (medians)")
    fig.tight_layout()
    return fig
