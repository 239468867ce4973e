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


def _record_problem(record: dict, case: _Case) -> str | None:
    """What is wrong with a stored record of ``case`` (``fem.task_runner.stored_records``), or None."""
    from fem.task_runner import is_scalar

    if record.get("design") != dataclasses.asdict(case.design):
        return "the record's design is not this case's"
    metrics = record.get("metrics")
    if not isinstance(metrics, dict) or not all(
            value is None or (isinstance(value, (int, float)) and not isinstance(value, bool))
            for value in metrics.values()):
        return "metrics is not a table of numbers"
    increments = record.get("increments", [])
    if not isinstance(increments, list) or not all(
            isinstance(row, dict) and all(is_scalar(value) for value in row.values()) for row in increments):
        return "increments is not a list of rows of numbers"
    if not isinstance(record.get("timings", {}), dict):
        return "timings is not a table"
    return None


def _check_runner_options(scheduler, workers, connect_timeout, max_hours, **flags) -> None:
    """The runner's options, checked before any work (types too: ``workers=2.5`` or ``progress="no"`` refused)."""
    from fem.task_runner import check_connect_timeout, check_scheduler
    from fem.validation import check_bool, check_integer, check_range

    check_scheduler(scheduler)
    check_integer("workers", workers, 1, 1024)
    check_connect_timeout(connect_timeout)
    check_range("max_hours", max_hours, 0.0, 1e6, "h", low_open=True)
    for name, value in flags.items():
        check_bool(name, value)


def design_sweep(designs, study: DesignStudy = DesignStudy(), out_dir=None, scheduler: str = "local",
                 workers: int = 2, connect_timeout: float = 5.0, retry_failed: bool = False, progress: bool = True,
                 on_record=None, with_increments: bool = False, force: bool = False, max_hours: float = 12.0,
                 on_stored=None):
    """Evaluate fingertip designs; returns the design table (``design_table``), one row per design.

    designs : a list (any iterable) of FingertipDesign, duplicates refused; a single design is refused with a
        TypeError (pass ``[design]``).
    study : DesignStudy shared by all designs.
    out_dir : folder for the case records (``out_dir/cases/<id>.json``); a re-run skips the designs recorded there
        (``retry_failed``: the failed ones run again). None: a temporary folder, nothing kept. One run at a time
        per folder (``fem.run_lock``).
    scheduler : "local" (a LocalCluster of ``workers`` processes, one thread each), "synchronous" (this process)
        or the address of a running dask scheduler (``connect_timeout`` seconds to reach it).
    on_record : called with each record as it arrives (the command writes its table there).
    on_stored : called once, before any design runs, with {case_id: record} of the designs already recorded in
        ``out_dir`` (validated: a record of another shape is skipped with a warning and its design runs again).
    with_increments : also return the increment table (``increment_table``): (designs, increments).
    force, max_hours : refuse designs whose FEM and sensor cannot fit this machine's memory, or whose estimated wall
        time exceeds ``max_hours`` (``check_design_resources``), unless ``force``.
    """
    from tqdm import tqdm

    from fem.run_lock import hold_out_dir
    from fem.task_runner import connect, run_tasks, set_aside, stored_records

    from ._resources import check_design_resources

    if isinstance(designs, (FingertipDesign, str, bytes, dict)) or not hasattr(designs, "__iter__"):
        raise TypeError(f"designs={designs!r} must be a list of FingertipDesign objects"
                        + (" (one design: pass [design])" if isinstance(designs, FingertipDesign) else ""))
    if not isinstance(study, DesignStudy):
        raise TypeError(f"study={study!r} must be a DesignStudy")
    for name, function in (("on_record", on_record), ("on_stored", on_stored)):
        if function is not None and not callable(function):
            raise TypeError(f"{name}={function!r} must be a function, or None")
    _check_runner_options(scheduler, workers, connect_timeout, max_hours, retry_failed=retry_failed,
                          progress=progress, with_increments=with_increments, force=force)
    cases, seen = [], {}
    for number, design in enumerate(designs):
        if not isinstance(design, FingertipDesign):
            raise TypeError(f"designs[{number}]={design!r} is a {type(design).__name__}, not a FingertipDesign")
        case_id = design_id(design, study)
        if case_id in seen:
            raise ValueError(f"design {design} appears twice")
        seen[case_id] = design
        cases.append(_Case(case_id, design, study))
    if not cases:
        raise ValueError("no designs given")
    slots = {"local": workers, "synchronous": 1}.get(scheduler)         # a cluster's: once connected
    temporary = tempfile.TemporaryDirectory(prefix="design-sweep-") if out_dir is None else None
    root = Path(temporary.name if temporary else out_dir)
    try:
        with hold_out_dir(root, f"design sweep of {len(cases)} designs"):
            cases_dir = root / "cases"
            cases_dir.mkdir(parents=True, exist_ok=True)
            records = stored_records(cases, cases_dir, retry_failed, required=("case_id", "status", "metrics"),
                                     check=_record_problem)
            pending = [case for case in cases if case.case_id not in records]
            if slots is not None:
                check_design_resources([case.design for case in pending], study, slots, force, max_hours)
            if on_stored is not None:
                on_stored(dict(records))
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
                    if slots is None:
                        check_design_resources([case.design for case in pending], study,
                                               sum(client.nthreads().values()), force, max_hours)
                    run_tasks(_plan(pending), evaluate_designs, _payload, _crashed, cases_dir, arrived, client)
            bar.close()
            ordered = [records[case.case_id] for case in cases]
    finally:
        if temporary is not None:
            temporary.cleanup()
    table = design_table(ordered)
    return (table, increment_table(ordered)) if with_increments else table
