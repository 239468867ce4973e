"""The design sweep's tables (one typed row per design; one per design, path and increment) and its Pareto front."""

from __future__ import annotations

import numpy as np

from ._grasp import FIT_METRICS, GRASP_METRICS
from ._metrics import METRICS

__all__ = ["DESIGN_COLUMNS", "TIMING_COLUMNS", "CLOSED_LOOP_COLUMNS", "design_table", "increment_table",
           "pareto_front"]


DESIGN_COLUMNS = ("bump_radius", "rows", "cols", "pitch", "base_thickness", "youngs_modulus", "poissons_ratio",
                  "sensor_pitch", "pad_fill", "base_width", "base_depth")     # FingertipDesign's fields, in order
TIMING_COLUMNS = ("fem_wall", "sensor_wall", "prepare", "solve", "dofs", "calibration_wall", "calibration_fem",
                  "calibration_cached", "bench_wall", "trials_wall")
CLOSED_LOOP_COLUMNS = (*GRASP_METRICS, *FIT_METRICS)      # <NA> in a sensor-only sweep


def design_table(records: list[dict]):
    """One typed row per design: case_id, the design's fields, every metric of METRICS and the closed loop's
    (GRASP_METRICS, FIT_METRICS; counts Int64, rates Float64; missing: <NA>), status, error, the closed loop's
    status, reason and calibration key, timings [s] per stage and DOF."""
    import pandas as pd

    rows = []
    for record in records:
        row = {"case_id": record["case_id"]}
        row.update({key: record["design"].get(key) for key in DESIGN_COLUMNS})
        row.update({key: record["metrics"].get(key) for key in (*METRICS, *CLOSED_LOOP_COLUMNS)})
        grasp = record.get("grasp") or {}
        row.update(status=record["status"], error=record.get("error") or "", group=record.get("group", ""),
                   worker=record.get("worker", ""), grasp_status=grasp.get("status", "off"),
                   grasp_error=grasp.get("error", ""), fit_key=grasp.get("fit_key", ""))
        row.update({key: record.get("timings", {}).get(key) for key in TIMING_COLUMNS})
        rows.append(row)
    strings = ("status", "error", "group", "worker", "grasp_status", "grasp_error", "fit_key")
    table = pd.DataFrame(rows, columns=["case_id", *DESIGN_COLUMNS, *METRICS, *CLOSED_LOOP_COLUMNS, *strings,
                                        *TIMING_COLUMNS])
    types = {key: "Float64" for key in (*DESIGN_COLUMNS, *METRICS, *TIMING_COLUMNS)}
    types.update({key: entry[3] for key, entry in {**GRASP_METRICS, **FIT_METRICS}.items()})
    types.update(rows="Int64", cols="Int64", dofs="Int64", case_id="string", **{key: "string" for key in strings})
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
