"""Fingertip design sweeps: designs through FEM -> sensor -> estimator, one row of metrics per design.

A design (``FingertipDesign``) is the paper's kind of fingertip - rows x cols hemispheres (bump radius, pitch) on a
base layer (thickness, footprint) of a linear-elastic gel (E, nu), read by a capacitive array (sensor pitch, pad
fill factor). A study (``DesignStudy``) fixes what every design goes through: a rigid plate pressed with the grasp
force, then (1) sheared by force control to the load ratios Q/(mu P) of ``load_ratios`` and (2), on another path from
the same press, twisted about the array centre (angle control, for two or more bumps). The sensor reads the FEM's
base pressure (``controller.sensor``, ``controller.capacitive``) and the estimator (``controller.estimator``) turns
it into shear displacements and rotations. Metrics (``METRICS``, one column each): translational and rotational
estimation errors, the stick-ratio drop near gross slip (the criterion of the paper's Figs. 3/4), force and torque
capacity per unit grasp force, and the mesh's error estimate.

``design_sweep`` runs many designs on dask.distributed (a LocalCluster by default, or a scheduler address) or in
this process, resumable: with ``out_dir`` each design's record is written as it finishes and a re-run skips the
designs recorded there (``fem.task_runner``). Designs that differ only in their sensor share one FEM solve (one
task); designs of one geometry share its cached mesh, and a re-run reads the compliance columns from their disk cache.
``python -m studies design DESIGN.toml`` is the command (file format: ``controller._design_file``).
"""

from __future__ import annotations

import dataclasses
import tempfile
from dataclasses import dataclass
from pathlib import Path

from ._design_evaluate import design_record, evaluate_designs
from ._design_file import DesignSweepSpec, load_design_file
from ._design_metrics import METRICS
from ._design_spec import (DesignStudy, FingertipDesign, SensorModel, design_id, design_scenes, fem_key,
                           twist_angles)
from ._design_table import DESIGN_COLUMNS, design_table, increment_table, pareto_front

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

