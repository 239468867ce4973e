"""Fingertip design sweep (FEM -> sensor -> estimator, resumable, on dask): python -m studies design FILE --out DIR.

The design file lists fingertip designs and the study they go through (format: controller/design/_file.py; example:
studies/designs/array_size_and_stiffness.toml); ``controller.design.design_sweep`` does the work. Writes
DIR/cases/<id>.json as each design finishes, DIR/design.parquet and DIR/design.csv (one typed row per design: its
parameters, every metric, status, timings), DIR/design_increments.parquet (one row per design, path and increment)
and the Pareto figure DIR/design.png/.pdf. A re-run skips the designs recorded (id = hash of design, study and
package version).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from studies._output import save_figure, write_json_atomic

NAME = "design"
# objectives of the Pareto front: lower estimation errors and a gentler stick-ratio drop, more torque capacity
OBJECTIVES = {"translational_error": "lower", "rotational_error": "lower", "stick_ratio_drop": "lower",
              "torque_capacity": "higher", "combined_torque_capacity": "higher"}
# and with the closed loop ([study] closed_loop = true): more grasps held, at a grip nearer the slip limit
GRASP_OBJECTIVES = {"grasp_success_rate": "higher", "grip_over_slip_limit": "lower"}


def objectives(table) -> dict:
    """OBJECTIVES, and GRASP_OBJECTIVES when some design has closed-loop results."""
    closed = "grasp_success_rate" in table and table["grasp_success_rate"].notna().any()
    return {**OBJECTIVES, **GRASP_OBJECTIVES} if closed else dict(OBJECTIVES)


def add_arguments(parser) -> None:
    from studies.sweep import add_runner_arguments

    parser.add_argument("design_file", type=Path, help="design TOML file (see studies/designs/)")
    add_runner_arguments(parser)


def _check_out_dir(out_dir: Path, spec) -> dict:
    """The identity of this sweep; refuse an --out that holds another one (other name or axes). An unreadable
    design.json (a killed write, an edit) is not another sweep: it is reported and written again; the case records
    are known by design, study and version, so none of them is mistaken for this sweep's."""
    import warnings

    identity = {"name": spec.name, "axes": sorted(spec.axes)}
    previous = out_dir / f"{NAME}.json"
    if previous.exists():
        try:
            stored = json.loads(previous.read_text())
            stored = {"name": stored["name"], "axes": sorted(stored["axes"])}
        except (OSError, ValueError, KeyError, TypeError) as error:
            warnings.warn(f"{str(previous)!r} is unreadable ({type(error).__name__}): written again from this sweep",
                          stacklevel=2)
            stored = identity
        if stored != identity:
            raise ValueError(f"--out {str(out_dir)!r} holds another design sweep ({stored}; this one is "
                             f"{identity}): choose another --out, or delete that folder")
    return identity


def write_tables(records: list[dict], out_dir: Path) -> None:
    """design.parquet, design.csv and design_increments.parquet from the records so far (atomically)."""
    from controller.design import design_table, increment_table

    _write(design_table(records), increment_table(records), out_dir)


def _write(designs, increments, out_dir: Path) -> None:
    from fem.atomic import atomic_path

    for name, table in ((NAME, designs), (f"{NAME}_increments", increments)):
        with atomic_path(out_dir / f"{name}.parquet") as temporary:
            table.to_parquet(temporary, index=False)
    with atomic_path(out_dir / f"{NAME}.csv") as temporary:
        designs.to_csv(temporary, index=False)


def run(out_dir, quick: bool = False, design_file: Path | None = None, scheduler: str = "local", workers: int = 2,
        connect_timeout: float = 5.0, retry_failed: bool = False, quiet: bool = False, max_hours: float = 12.0,
        force: bool = False) -> dict:
    """Run (or resume) the design sweep; tables, Pareto figure; returns counts and the wall time. Refused before any
    solve: a bad flag or design file, designs past the resource limits (unless ``force``), an --out that holds
    another sweep or another live run."""
    from controller.design import DESIGN_COLUMNS, design_id, design_sweep, load_design_file, pareto_front
    from fem.run_lock import hold_out_dir
    from studies.run import check_writable
    from studies.sweep import check_runner_flags

    if design_file is None:
        raise ValueError("design needs a design file: python -m studies design DESIGN.toml --out DIR")
    check_runner_flags(scheduler, workers, connect_timeout, max_hours)
    spec = load_design_file(design_file, quick=quick)        # every design validated before anything runs
    import pyarrow  # noqa: F401  (fail now, not after the solves, if the Parquet writer is missing)

    out_dir = check_writable(Path(out_dir))
    identity = _check_out_dir(out_dir, spec)
    start = time.perf_counter()
    with hold_out_dir(out_dir, f"design sweep {spec.name!r}"):
        write_json_atomic(out_dir / f"{NAME}.json", {**identity, "source": spec.source,
                                                     "description": spec.description,
                                                     "grid": {k: list(v) for k, v in spec.grid},
                                                     "list": {k: list(v) for k, v in spec.zipped},
                                                     "study": spec.study.document(), "designs": len(spec.designs)})
        # the tables hold every design of this file recorded on disk, whichever run computed it: a resumed run that
        # is killed while writing them leaves the earlier designs in, not only its own
        known: dict = {}
        order = {design_id(design, spec.study): number for number, design in enumerate(spec.designs)}

        def on_record(record):
            known[record["case_id"]] = record
            write_tables(sorted(known.values(), key=lambda r: order[r["case_id"]]), out_dir)

        table, increments = design_sweep(spec.designs, spec.study, out_dir=out_dir, scheduler=scheduler,
                                         workers=workers, connect_timeout=connect_timeout, retry_failed=retry_failed,
                                         progress=not quiet, on_record=on_record, on_stored=known.update,
                                         with_increments=True, force=force, max_hours=max_hours)
        _write(table, increments, out_dir)
        goals = objectives(table)
        front = pareto_front(table, goals)
        seconds = time.perf_counter() - start
        save_figure(plot_pareto(table, front, spec.name, spec.axes or DESIGN_COLUMNS[:3], goals), out_dir, NAME)
    failed = int((table["status"] != "ok").sum())
    print(f"{NAME}: {len(table)} designs, {failed} failed, {int(front.sum())} on the Pareto front; {seconds:.1f} s")
    for _, row in table[front].iterrows():
        print(f"  front: {_label(row, spec.axes)}: translation {100 * row['translational_error']:.1f} %, rotation "
              f"{_percent(row['rotational_error'])}, drop {row['stick_ratio_drop']:.2f}, torque capacity "
              f"{row['torque_capacity']:.2f} mm{_grasp_words(row)}")
    for _, row in table[table["grasp_status"].isin(["refused", "failed"])].iterrows():
        print(f"  closed loop {row['grasp_status']}: {_label(row, spec.axes)}: {row['grasp_error']}")
    return {"designs": len(table), "failed": failed, "front": int(front.sum()), "wall_time": seconds}


def _grasp_words(row) -> str:
    """The closed loop's numbers of a table row, or nothing for a sensor-only one."""
    import pandas as pd

    if pd.isna(row["grasp_success_rate"]):
        return ""
    ratio = "-" if pd.isna(row["grip_over_slip_limit"]) else f"{row['grip_over_slip_limit']:.2f}"
    slide = "-" if pd.isna(row["grasp_slide_median"]) else f"{row['grasp_slide_median']:.2f} mm"
    return (f"; held {row['grasp_held']}/{row['grasp_trials']} (95 % {100 * row['grasp_success_low']:.0f}-"
            f"{100 * row['grasp_success_high']:.0f} %), grip / slip limit {ratio}, median slide from the lift's "
            f"start {slide}")


def _percent(value) -> str:
    import pandas as pd

    return "-" if pd.isna(value) else f"{100 * value:.1f} %"


def _label(row, axes) -> str:
    return ", ".join(f"{axis}={row[axis]:g}" if not isinstance(row[axis], str) else f"{axis}={row[axis]}"
                     for axis in axes)


def plot_pareto(table, front, title: str, axes, goals: dict | None = None):
    """Trade-offs, each design a point (the Pareto front over all ``goals`` filled, default OBJECTIVES; the 2D
    front of the panel drawn): translational error against torque capacity, rotational error against the
    stick-ratio drop, and with the closed loop the grasp axis: success rate (95 % Wilson interval) against the
    translational error, and against the grip over the slip limit."""
    import matplotlib.pyplot as plt
    import numpy as np

    from controller.design import pareto_front

    goals = OBJECTIVES if goals is None else goals
    panels = [(("torque_capacity", "torque capacity per unit grasp force [mm]", 1.0),
               ("translational_error", "translational estimation error [%]", 100.0)),
              (("stick_ratio_drop", "stick-ratio drop before gross slip, c/a / (1 - Q/(mu P)) [1]", 1.0),
               ("rotational_error", "rotational estimation error [%]", 100.0))]
    if "grasp_success_rate" in goals:
        panels += [(("translational_error", "translational estimation error [%]", 100.0),
                    ("grasp_success_rate", "grasp success rate (held) [%]", 100.0)),
                   (("grip_over_slip_limit", "settled grip / the trial's slip limit [-]", 1.0),
                    ("grasp_success_rate", "grasp success rate (held) [%]", 100.0))]
    fig, grid = plt.subplots(1, len(panels), figsize=(6 * len(panels), 5))
    ok = (table["status"] == "ok").to_numpy()
    every = {**OBJECTIVES, **GRASP_OBJECTIVES}
    for axis, ((x_key, x_label, x_scale), (y_key, y_label, y_scale)) in zip(grid, panels):
        x = table[x_key].to_numpy(dtype=float, na_value=np.nan) * x_scale
        y = table[y_key].to_numpy(dtype=float, na_value=np.nan) * y_scale
        shown = ok & np.isfinite(x) & np.isfinite(y)
        axis.scatter(x[shown & ~front], y[shown & ~front], facecolors="none", edgecolors="#636363", label="design")
        axis.scatter(x[shown & front], y[shown & front], color="#de2d26", label="Pareto front (all objectives)",
                     zorder=3)
        if y_key == "grasp_success_rate":
            low, high = (table[key].to_numpy(dtype=float, na_value=np.nan) * y_scale
                         for key in ("grasp_success_low", "grasp_success_high"))
            axis.errorbar(x[shown], y[shown], yerr=[y[shown] - low[shown], high[shown] - y[shown]], fmt="none",
                          ecolor="#969696", capsize=3, zorder=1, label="95 % Wilson interval")
        local = pareto_front(table, {x_key: every[x_key], y_key: every[y_key]}) & shown
        order = np.argsort(x[local])
        axis.plot(x[local][order], y[local][order], "--", color="#de2d26", lw=1, label="front of this panel")
        for number, index in enumerate(np.flatnonzero(front), start=1):     # numbered; listed under the panels
            if shown[index]:
                axis.annotate(str(number), (x[index], y[index]), fontsize=8, color="#de2d26",
                              textcoords="offset points", xytext=(4, 3))
        axis.set_xlabel(x_label)
        axis.set_ylabel(y_label)
        axis.grid(alpha=0.3)
    grid[0].legend(fontsize=8)
    fig.suptitle(f"{title}: {int(ok.sum())} designs, {int(front.sum())} on the Pareto front\n"
                 f"(objectives: {', '.join(f'{k} {v}' for k, v in goals.items())})", fontsize=9)
    listing = [f"{number}: {_short_label(table.iloc[index], axes)}"
               for number, index in enumerate(np.flatnonzero(front), start=1)]
    fig.text(0.01, 0.01, "Pareto front:  " + ";   ".join(listing), fontsize=8, wrap=True, va="bottom")
    fig.tight_layout(rect=(0, 0.03 + 0.025 * (len(listing) // 3), 1, 1))
    return fig


SHORT_NAMES = {"youngs_modulus": ("E", " MPa"), "poissons_ratio": ("nu", ""), "sensor_pitch": ("sensor pitch", " mm"),
               "pad_fill": ("pad fill", ""), "pitch": ("pitch", " mm"), "bump_radius": ("R", " mm"),
               "base_thickness": ("base", " mm")}


def _short_label(row, axes) -> str:
    """The swept parameters of a design in a few words, e.g. ``3x3, E 0.3 MPa, sensor pitch 3 mm``."""
    parts = [f"{row['rows']:g}x{row['cols']:g}"] if "rows" in axes or "cols" in axes else []
    for axis in axes:
        if axis in ("rows", "cols"):
            continue
        name, unit = SHORT_NAMES.get(axis, (axis, ""))
        value = row[axis]
        parts.append(f"{name} {value:.3g}{unit}" if not isinstance(value, str) else f"{name} {value}")
    return ", ".join(parts)
