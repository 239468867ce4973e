"""The sweep's tidy table (one row per case, Parquet and CSV, written atomically) and its summary plot."""

from __future__ import annotations

from pathlib import Path

from fem.atomic import atomic_path
from studies._output import write_csv_atomic

__all__ = ["case_row", "write_table", "plot_sweep", "TIMING_COLUMNS"]

TIMING_COLUMNS = ("wall_time", "prepare_time", "solve_time", "prepared_here")


def exploded(key: str, value) -> dict:
    """A parameter as typed table columns: a scalar as itself, a list (a load path, a centre) one column per item,
    ``key[0]``, ``key[1]``, ... (nested lists ``key[0][1]``), so pandas and ParaView read numbers, not text."""
    if not isinstance(value, (list, tuple)):
        return {key: value}
    columns = {}
    for index, item in enumerate(value):
        columns.update(exploded(f"{key}[{index}]", item))
    return columns


def axis_value(row: dict, axis: str):
    """A case's value of a sweep axis from its table row: the scalar, or the tuple of a list axis' exploded items."""
    if axis in row:
        return row[axis]
    return tuple(value for column, value in row.items() if column.startswith(f"{axis}["))


def _case_quantity(record: dict, quantity: str):
    increments = record.get("increments", [])
    if quantity in TIMING_COLUMNS:
        return record.get(quantity)
    if quantity == "iterations":
        return sum(row["iterations"] for row in increments) if increments else None
    if quantity == "increments_done":
        return len(increments)
    if quantity == "compliance_columns":
        return record.get("timings", {}).get("compliance_columns")
    return record.get("mesh_info", {}).get(quantity)


def case_row(case, record: dict, outputs) -> dict:
    """The table row of a case: id, parameters, outputs (None where a failed case has no value), status, timings,
    worker and group, error message."""
    row = {"case_id": case.case_id}
    for key, value in case.parameters:
        row.update(exploded(key, value))
    increments = record.get("increments", [])
    for output in outputs:
        if output.increment is None:
            row[output.text] = _case_quantity(record, output.quantity)
        else:
            # a negative index counts from the end of the planned load path, not of what converged
            index = output.increment + (case.n_increments if output.increment < 0 else 0)
            row[output.text] = increments[index].get(output.quantity) if index < len(increments) else None
    row["status"] = record["status"]
    row["increments_done"] = len(increments)
    for key in TIMING_COLUMNS:
        row[key] = record.get(key)
    row["group"] = record.get("group", "")
    row["worker"] = record.get("worker", "")
    row["error"] = record.get("error") or ""
    return row


def _write_parquet_atomic(path: Path, rows: list[dict]) -> Path:
    import pyarrow as pa
    import pyarrow.parquet as pq

    columns: dict = {}                   # every row's keys in first-seen order: pyarrow would take the first row's
    for row in rows:                     # alone and drop, e.g., the items of a longer load path of a later case
        columns.update(dict.fromkeys(row))
    with atomic_path(path) as temporary:
        pq.write_table(pa.Table.from_pylist([{name: row.get(name) for name in columns} for row in rows]), temporary)
    return path


def write_table(rows: list[dict], out_dir: Path, name: str) -> list[Path]:
    """Write ``name.parquet`` and ``name.csv`` (each through a temporary file and a rename)."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    return [_write_parquet_atomic(out_dir / f"{name}.parquet", rows), write_csv_atomic(out_dir / f"{name}.csv", rows)]


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def plot_sweep(rows: list[dict], axes: tuple[str, ...], zipped_axes: tuple[str, ...], outputs, title: str):
    """One row of panels per axis, one panel per numeric output: output against the axis value, one line per
    combination of the other axes (the axes zipped with it move together, so they do not split lines); failed
    cases' partial values are marked x."""
    import matplotlib.pyplot as plt

    columns = [o.text for o in outputs if any(_is_number(r.get(o.text)) for r in rows)] or ["wall_time"]
    fig, grid = plt.subplots(len(axes), len(columns), figsize=(3.6 * len(columns), 3.0 * len(axes)), squeeze=False)
    for axis_row, axis in zip(grid, axes):
        partners = set(zipped_axes) if axis in zipped_axes else {axis}
        others = [a for a in axes if a not in partners]
        values = [axis_value(r, axis) for r in rows]
        numeric = all(_is_number(v) for v in values)
        categories = sorted({str(v) for v in values}) if not numeric else []
        lines: dict = {}
        for row in rows:
            lines.setdefault(tuple(axis_value(row, a) for a in others), []).append(row)

        def position(row):
            value = axis_value(row, axis)
            return value if numeric else categories.index(str(value))

        for panel, column in zip(axis_row, columns):
            for key, members in lines.items():
                members = sorted(members, key=position)
                xs = [position(r) for r in members]
                ys = [r.get(column) if _is_number(r.get(column)) else float("nan") for r in members]
                label = ", ".join(f"{a}={v}" for a, v in zip(others, key)) or None
                line, = panel.plot(xs, [y if r["status"] == "ok" else float("nan") for y, r in zip(ys, members)],
                                   "o-", ms=4, label=label)
                failed = [(x, y) for x, y, r in zip(xs, ys, members) if r["status"] != "ok"]
                if failed:
                    panel.plot(*zip(*failed), "x", color=line.get_color(), ms=7)
            if numeric and min(values) > 0 and max(values) / min(values) > 50:
                panel.set_xscale("log")
            if not numeric:
                panel.set_xticks(range(len(categories)), categories, rotation=30, fontsize=7)
            panel.set_xlabel(axis)
            panel.set_ylabel(column)
            panel.grid(True, alpha=0.3)
        if others and len(lines) <= 10:
            axis_row[0].legend(fontsize=6)
    fig.suptitle(f"{title}: {len(rows)} cases ({sum(r['status'] != 'ok' for r in rows)} failed, marked x)")
    fig.tight_layout()
    return fig
