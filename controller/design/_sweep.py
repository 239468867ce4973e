"""``design_sweep``: many fingertip designs through the study on dask or in this process, resumable."""

from __future__ import annotations

import dataclasses
import tempfile
from dataclasses import dataclass
from pathlib import Path

from ._evaluate import design_record, evaluate_designs
from ._file import DesignSweepSpec, load_design_file
from ._metrics import METRICS
from ._spec import (DesignStudy, FingertipDesign, SensorModel, design_id, design_scenes, fem_key,
                           twist_angles)
from ._table import DESIGN_COLUMNS, design_table, increment_table, pareto_front

__all__ = ["FingertipDesign", "DesignStudy", "SensorModel", "METRICS", "design_scenes", "twist_angles",
           "evaluate_designs", "design_sweep", "design_table", "increment_table", "pareto_front", "design_id",
           "load_design_file", "DesignSweepSpec", "DESIGN_COLUMNS"]


def _payload(case) -> tuple:
    return case.case_id, dataclasses.asdict(case.design), case.study.document()


@dataclass(frozen=True)
class _Case:
    case_id: str
    design: FingertipDesign
    study: DesignStudy


def _crashed(case, message: str) -> dict:
    return design_record(case.case_id, case.design, "failed", message, {}, [], {}, "")


def _plan(cases: list) -> list[list]:
    """One task per FEM solution (designs differing only in the sensor); the largest first. A task is not split to
    fill idle workers: that would solve the same FEM twice."""
    groups: dict = {}
    for case in cases:
        groups.setdefault(fem_key(case.design), []).append(case)
    return sorted(groups.values(), key=len, reverse=True)


def design_sweep(designs, study: DesignStudy = DesignStudy(), out_dir=None, scheduler: str = "local",
                 workers: int = 2, connect_timeout: float = 5.0, retry_failed: bool = False, progress: bool = True,
                 on_record=None, with_increments: bool = False):
    """Evaluate fingertip designs; returns the design table (``design_table``), one row per design.

    designs : iterable of FingertipDesign (duplicates refused).
    study : DesignStudy shared by all designs.
    out_dir : folder for the case records (``out_dir/cases/<id>.json``); a re-run skips the designs recorded there
        (``retry_failed``: the failed ones run again). None: a temporary folder, nothing kept.
    scheduler : "local" (a LocalCluster of ``workers`` processes, one thread each), "synchronous" (this process)
        or the address of a running dask scheduler (``connect_timeout`` seconds to reach it).
    on_record : called with each record as it arrives (the command writes its table there).
    with_increments : also return the increment table (``increment_table``): (designs, increments).
    """
    from tqdm import tqdm

    from fem.task_runner import check_scheduler, connect, run_tasks, set_aside, stored_records

    check_scheduler(scheduler)
    cases, seen = [], {}
    for design in designs:
        if not isinstance(design, FingertipDesign):
            raise ValueError(f"designs must be FingertipDesign objects, got {type(design).__name__}")
        case_id = design_id(design, study)
        if case_id in seen:
            raise ValueError(f"design {design} appears twice")
        seen[case_id] = design
        cases.append(_Case(case_id, design, study))
    if not cases:
        raise ValueError("no designs given")
    temporary = tempfile.TemporaryDirectory(prefix="design-sweep-") if out_dir is None else None
    cases_dir = Path(temporary.name if temporary else Path(out_dir) / "cases")
    cases_dir.mkdir(parents=True, exist_ok=True)
    try:
        records = stored_records(cases, cases_dir, retry_failed, required=("case_id", "status", "metrics"))
        pending = [case for case in cases if case.case_id not in records]
        bar = tqdm(total=len(cases), initial=len(cases) - len(pending), desc="designs", unit="design",
                   disable=not progress)

        def arrived(case, record):
            records[case.case_id] = record
            bar.update(1)
            if record["status"] != "ok":
                bar.write(f"design {case.design} failed: {str(record['error'])[:300]}")
            if on_record is not None:
                on_record(record)

        set_aside(pending, cases_dir)
        if pending:
            with connect(scheduler, workers, connect_timeout) as client:
                run_tasks(_plan(pending), evaluate_designs, _payload, _crashed, cases_dir, arrived, client)
        bar.close()
        ordered = [records[case.case_id] for case in cases]
    finally:
        if temporary is not None:
            temporary.cleanup()
    table = design_table(ordered)
    return (table, increment_table(ordered)) if with_increments else table

