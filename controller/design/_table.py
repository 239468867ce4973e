"""The design sweep's tables (one typed row per design; one per design, path and increment) and its Pareto front."""

from __future__ import annotations

import numpy as np

from ._metrics import METRICS

__all__ = ["DESIGN_COLUMNS", "TIMING_COLUMNS", "design_table", "increment_table", "pareto_front"]


DESIGN_COLUMNS = ("bump_radius", "rows", "cols", "pitch", "base_thickness", "youngs_modulus", "poissons_ratio",
                  "sensor_pitch", "pad_fill", "base_width", "base_depth")     # FingertipDesign's fields, in order
TIMING_COLUMNS = ("fem_wall", "sensor_wall", "prepare", "solve", "dofs")


def design_table(records: list[dict]):
    """One typed row per design: case_id, the design's fields, every metric of METRICS (missing: <NA>), status,
    error, timings [s] and DOF."""
    import pandas as pd

    rows = []
    for record in records:
        row = {"case_id": record["case_id"]}
        row.update({key: record["design"].get(key) for key in DESIGN_COLUMNS})
        row.update({key: record["metrics"].get(key) for key in METRICS})
        row.update(status=record["status"], error=record.get("error") or "", group=record.get("group", ""),
                   worker=record.get("worker", ""))
        row.update({key: record.get("timings", {}).get(key) for key in TIMING_COLUMNS})
        rows.append(row)
    table = pd.DataFrame(rows, columns=["case_id", *DESIGN_COLUMNS, *METRICS, "status", "error", "group", "worker",
                                        *TIMING_COLUMNS])
    types = {key: "Float64" for key in (*DESIGN_COLUMNS, *METRICS, *TIMING_COLUMNS)}
    types.update(rows="Int64", cols="Int64", dofs="Int64", case_id="string", status="string", error="string",
                 group="string", worker="string")
    return table.astype(types)


def increment_table(records: list[dict]):
    """Tidy per-increment table: one row per design, path (shear / twist) and increment."""
    import pandas as pd

    rows = [{"case_id": record["case_id"], **row} for record in records for row in record.get("increments", [])]
    columns = ["case_id", "path", "increment", "load_kind", "load_ratio", "normal_force", "tangential_force",
               "torque", "shift", "angle", "stick_ratio", "contact_area", "least_bump_margin",
               "least_bump_stick_ratio", "bump_shift", "bump_angle", "estimated_shift",
               "estimated_angle"]
    table = pd.DataFrame(rows, columns=columns)
    types = {key: "Float64" for key in columns[4:]}
    types.update(case_id="string", path="string", load_kind="string", increment="Int64")
    return table.astype(types)


def pareto_front(table, objectives: dict) -> np.ndarray:
    """Boolean mask of the rows no other row dominates; ``objectives`` maps a column to "lower" or "higher".
    Rows with a missing objective are left out of the front (False)."""
    values = []
    for column, sense in objectives.items():
        if sense not in ("lower", "higher"):
            raise ValueError(f"objective {column!r}: sense={sense!r} is not 'lower' or 'higher'")
        data = table[column].astype("Float64").to_numpy(dtype=float, na_value=np.nan)
        values.append(data if sense == "lower" else -data)
    values = np.column_stack(values)                                   # (n, m), all to be minimised
    complete = np.all(np.isfinite(values), axis=1)
    front = complete.copy()
    for i in np.flatnonzero(complete):
        others = values[complete]
        dominated = np.any(np.all(others <= values[i], axis=1) & np.any(others < values[i], axis=1))
        front[i] = not dominated
    return front
