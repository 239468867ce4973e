"""Running sweep cases: one task per group of cases sharing ``preparation_key`` (prepare once, solve each), on a
dask.distributed LocalCluster, an existing scheduler, or in this process ("synchronous").

A task writes each case's record to ``cases_dir/<case_id>.json`` (atomically) as soon as the case is done and also
returns the records, so an interrupted sweep keeps every finished case; on a cluster without a shared filesystem
the client writes the returned records itself when the task ends.

Across runs: a re-run of the same sweep prepares nothing, since every recorded case is skipped. The cases it does
run (new axis values, --retry-failed, an interrupted group, every case after an upgrade) prepare again per group:
curved gels read their gmsh mesh from the disk cache (fem.mesh_cache; meshing is the slow step, 1-15 s); a
block is bisected again (graded bisection is deterministic and took 0.3-0.6 s of a 1.3-2.9 s prepare in the
example sweep, 8.6k-12.5k DOF, so it is not cached); the stiffness is assembled and factorized again. The
factorization cannot go to disk: pypardiso keeps PARDISO's factors in MKL's memory (its ``pt`` holds raw
addresses) and scipy's SuperLU refuses to pickle. Storing only K would save the assembly (about 1 s there) for a
second cache to invalidate. The surface compliance columns, the largest share of a group's first solve (1.5-2.4 s
there, ~16 s on HCM-1 as written), are plain arrays and could be stored keyed by mesh, material, candidate points
and code version; not done yet.
"""

from __future__ import annotations

import math
import os
import socket
import time
from pathlib import Path

from fem.task_runner import LOCAL, SYNCHRONOUS, check_scheduler, connect
from studies._output import write_json_atomic

__all__ = ["solve_group", "iter_group", "plan_tasks", "check_scheduler", "connect", "LOCAL", "SYNCHRONOUS",
           "failed_record"]


def _worker_name() -> str:
    return f"{socket.gethostname()}:{os.getpid()}"


def failed_record(case_id: str, parameters: dict, error: str | None) -> dict:
    """Record of a case whose task died before it could report (worker lost, bug in the task); also the blank
    template that a running case fills in."""
    return {"case_id": case_id, "parameters": parameters, "status": "failed", "error": error, "increments": [],
            "mesh_info": {}, "timings": {}, "prepare_time": 0.0, "solve_time": 0.0, "wall_time": 0.0,
            "prepared_here": False, "group": "", "worker": ""}


def _increment_rows(result, mu: float) -> list[dict]:
    """Flat per-increment rows (vectors split into _x, _y) with the load ratios Q/(mu P) and T/(mu P a)."""
    from studies.run import step_rows

    rows = []
    for row in step_rows(result):
        row.pop("increment")
        capacity = mu * row["normal_force"]
        row["load_ratio"] = math.hypot(row["tangential_force_x"], row["tangential_force_y"]) / capacity \
            if capacity > 0 else None
        row["torque_ratio"] = abs(row["torque"]) / (capacity * row["contact_radius"]) \
            if capacity > 0 and row["contact_radius"] > 0 else None
        rows.append(row)
    return rows


def _non_finite(rows: list[dict]) -> list[str]:
    """Names 'increment i: key' of the NaN / inf values in the rows (set to None so the record stays valid JSON)."""
    bad = []
    for number, row in enumerate(rows):
        for key, value in row.items():
            if isinstance(value, float) and not math.isfinite(value):
                bad.append(f"increment {number}: {key}={value}")
                row[key] = None
    return bad


def _solve_one(case_id, parameters, document, prepared, group):
    """Solve one case with ``prepared`` (or prepare it); returns (record, prepared for the next case)."""
    from contact import ContactUnderResolved, LoadNotCarried, PathNotCompleted, prepare, scene_from_dict, solve_scene

    start = time.perf_counter()
    record = failed_record(case_id, parameters, None)
    record.update(status="ok", group=group, worker=_worker_name(), document=document)
    scene = scene_from_dict(document)
    result = None
    try:
        if prepared is None:
            prepared = prepare(scene)
            record["prepared_here"] = True
        record["prepare_time"] = time.perf_counter() - start
        solve_start = time.perf_counter()
        try:
            result = solve_scene(scene, prepared=prepared)
        except (PathNotCompleted, LoadNotCarried, ContactUnderResolved) as error:
            result = error.result                 # the increments converged before the failure are kept
            raise
        finally:
            record["solve_time"] = time.perf_counter() - solve_start
    except Exception as error:                    # recorded, and the sweep goes on (KeyboardInterrupt is not caught)
        record.update(status="failed", error=f"{type(error).__name__}: {error}")
    if result is not None:
        record["increments"] = _increment_rows(result, scene.contact.friction_coefficient)
        record["timings"] = {k: float(v) for k, v in result.timings.items()}
        record["mesh_info"] = dict(result.mesh_info)
        bad = _non_finite(record["increments"])
        if bad and record["status"] == "ok":
            record.update(status="failed", error=f"non-finite result, refused: {', '.join(bad[:5])}")
    record["wall_time"] = time.perf_counter() - start
    return record, prepared


def iter_group(items: list[tuple[str, dict, dict]], cases_dir: str | None, group: str = ""):
    """Solve the cases (case_id, parameters, scene document) of one group, yielding each record when it is done.

    The first case prepares (mesh, stiffness, factorization); the others reuse it. If prepare fails, every case of
    the group records that error (each one retries prepare: a failure can depend on the load, e.g. the fine zone).
    """
    prepared = None
    for case_id, parameters, document in items:
        record, prepared = _solve_one(case_id, parameters, document, prepared, group)
        if cases_dir is not None:
            write_json_atomic(Path(cases_dir) / f"{case_id}.json", record)
        yield record


def solve_group(items: list[tuple[str, dict, dict]], cases_dir: str | None, group: str = "") -> list[dict]:
    """``iter_group`` run to the end; the records of the group, in order."""
    return list(iter_group(items, cases_dir, group))


def plan_tasks(cases, n_workers: int, share_prepare: bool = True) -> list[list]:
    """Group cases by ``preparation_key`` (one prepare per group), then split the largest groups until there are at
    least ``n_workers`` tasks (each split costs one more prepare but keeps every worker busy). Largest first."""
    from contact import preparation_key

    if not share_prepare:
        return [[case] for case in cases]
    groups: dict = {}
    for case in cases:
        groups.setdefault(preparation_key(case.scene), []).append(case)
    tasks = sorted(groups.values(), key=len, reverse=True)
    while tasks and len(tasks) < n_workers and len(tasks[0]) > 1:
        largest = tasks.pop(0)
        half = (len(largest) + 1) // 2
        tasks = sorted(tasks + [largest[:half], largest[half:]], key=len, reverse=True)
    return tasks
