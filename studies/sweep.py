"""Parameter sweep of a scene on dask (resumable; one tidy table): python -m studies sweep SWEEP.toml --out DIR.

The sweep file gives a base scene, axes on dotted scene keys ([grid]: cartesian product, [list]: zipped) and the
outputs to record (format: studies/_sweep_spec.py; example: studies/sweeps/stick_ratio_E_mu.toml). Cases that share
a mesh and factorization (contact.preparation_key) run as one task that prepares once. Writes DIR/cases/<id>.json
as each case finishes, DIR/sweep.parquet and DIR/sweep.csv (one row per case: parameters, outputs, status,
timings, error) and DIR/sweep.png/.pdf. A re-run skips the cases already recorded (id = hash of the case's scene and
of the package version, so an upgrade solves them again).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from fem.atomic import remove_stale_temporaries
from studies._output import save_figure, write_json_atomic

NAME = "sweep"


def add_runner_arguments(parser) -> None:
    """Options of a resumable run on dask (fem.task_runner): --scheduler, --workers, --connect-timeout,
    --retry-failed, --quiet; shared by the scene sweep and the design sweep."""
    parser.add_argument("--scheduler", default="local",
                        help="'local' (a LocalCluster, default), 'synchronous' (no dask, in this process) or the "
                             "address of a running scheduler, e.g. tcp://host:8786 (workers must share DIR)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the LocalCluster (default 2)")
    parser.add_argument("--connect-timeout", type=float, default=5.0, help="seconds to reach --scheduler (default 5)")
    parser.add_argument("--retry-failed", action="store_true", help="run the cases recorded as failed again")
    parser.add_argument("--max-hours", type=float, default=12.0,
                        help="refuse a run whose estimated wall time exceeds this (default 12 h; contact.budget)")
    parser.add_argument("--force", action="store_true",
                        help="run past the resource limits: the memory of one case and --max-hours")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def check_runner_flags(scheduler, workers, connect_timeout, max_hours) -> None:
    """The runner's flags, each refused by name before any work: the scheduler address, the workers, the connect
    timeout (finite, > 0) and --max-hours (finite, > 0)."""
    from fem.task_runner import check_connect_timeout, check_scheduler
    from fem.validation import check_all, check_integer, check_range

    check_all(lambda: check_scheduler(scheduler), lambda: check_integer("--workers", workers, 1, 1024),
              lambda: check_connect_timeout(connect_timeout),
              lambda: check_range("--max-hours", max_hours, 0.0, 1e6, "h", low_open=True))


def add_arguments(parser) -> None:
    parser.add_argument("sweep_file", type=Path, help="sweep TOML file (see studies/sweeps/)")
    add_runner_arguments(parser)
    parser.add_argument("--no-share", action="store_true",
                        help="one task per case, each preparing its own mesh (to measure what sharing saves)")


RECORD_KEYS = ("case_id", "status", "increments")


def _record_problem(record: dict, case=None) -> str | None:
    """What is wrong with a stored case record beyond its keys (``fem.task_runner.stored_records``), or None: the
    increments must be rows of plain values, the timings and mesh facts tables, the case-level times numbers."""
    from fem.task_runner import is_scalar
    from studies._sweep_table import TIMING_COLUMNS

    increments = record.get("increments")
    if not isinstance(increments, list) or not all(
            isinstance(row, dict) and all(is_scalar(value) for value in row.values()) for row in increments):
        return "increments is not a list of rows of plain values"
    if not all(isinstance(record.get(key, {}), dict) for key in ("timings", "mesh_info")):
        return "timings or mesh_info is not a table"
    if not all(is_scalar(record.get(key)) for key in TIMING_COLUMNS):
        return "a case-level time is not a plain value"
    return None


def _read_record(path: Path) -> dict | None:
    from fem.task_runner import read_record

    return read_record(path, RECORD_KEYS, _record_problem)   # absent, unreadable or not this case's: it runs again


def _identity(spec) -> dict:
    """What makes two sweeps the same sweep for one --out: the name and the axes (keys)."""
    return {"name": spec.name, "axes": sorted(spec.axes)}


def check_out_dir(out_dir: Path, spec) -> None:
    """Refuse an --out that holds a different sweep (another name or other axes), or that cannot be written. An
    unreadable sweep.json (a killed write, an edit) is not another sweep: it is reported and written again (the
    case records are known by their scene, so none of them is mistaken for this sweep's)."""
    import warnings

    previous = out_dir / f"{NAME}.json"
    if previous.exists():
        try:
            stored = json.loads(previous.read_text())
            stored_identity = {"name": stored["name"], "axes": sorted([*stored["grid"], *stored["list"]])}
        except (OSError, ValueError, KeyError, TypeError) as error:
            warnings.warn(f"{str(previous)!r} is unreadable ({type(error).__name__}): written again from this sweep",
                          stacklevel=2)
            stored_identity = _identity(spec)
        if stored_identity != _identity(spec):
            raise ValueError(f"--out {str(out_dir)!r} holds another sweep ({stored_identity}; this one is "
                             f"{_identity(spec)}): choose another --out, or delete that folder")
    from studies.run import check_writable

    check_writable(out_dir)


def check_sweep_budget(cases, slots: int, max_hours: float, force: bool, share: bool = True) -> dict:
    """Refuse (contact.budget) pending cases that cannot fit or would run past ``max_hours`` on ``slots`` workers:
    one task per group of cases sharing a preparation (as ``plan_tasks`` runs them)."""
    from contact import preparation_key
    from contact.budget import Task, check_budget, sampled, scene_cost

    groups: dict = {}
    for case in cases:
        groups.setdefault(preparation_key(case.scene) if share else case.case_id, []).append(case)
    chosen, scale = sampled(list(groups.values()))          # past SAMPLE groups, evenly spaced ones stand for all

    def tasks():
        for members in chosen:
            cost = scene_cost(members[0].scene, increments=sum(case.n_increments for case in members))
            yield Task(f"case {dict(members[0].parameters)}", cost["bytes"], scale * cost["seconds"])

    return check_budget(tasks(), slots, max_hours, force, f"{len(cases)} case(s)", count=len(chosen),
                        total=len(groups))


def _payload(case) -> tuple:
    return case.case_id, dict(case.parameters), case.document


def _crashed(case, message: str) -> dict:
    from studies._sweep_exec import failed_record

    return failed_record(case.case_id, dict(case.parameters), message)


def run(out_dir, quick: bool = False, sweep_file: Path | None = None, scheduler: str = "local", workers: int = 2,
        connect_timeout: float = 5.0, retry_failed: bool = False, no_share: bool = False, quiet: bool = False,
        max_hours: float = 12.0, force: bool = False) -> dict:
    """Run (or resume) the sweep; returns counts of cases (total, ran, skipped, ok, failed) and the wall time.
    Refused before any solve: a bad flag or sweep file, a plan past the resource limits (unless ``force``), an --out
    that holds another sweep or another live run (``fem.run_lock``)."""
    from tqdm import tqdm

    from fem.run_lock import hold_out_dir
    from fem.task_runner import connect, run_tasks, set_aside, stored_records
    from studies._sweep_exec import iter_group, plan_tasks
    from studies._sweep_spec import code_version, load_sweep
    from studies._sweep_table import case_row, plot_sweep, write_table

    if sweep_file is None:
        raise ValueError("sweep needs a sweep file: python -m studies sweep SWEEP.toml --out DIR")
    check_runner_flags(scheduler, workers, connect_timeout, max_hours)
    spec = load_sweep(sweep_file, quick=quick)           # every case validated before anything runs
    import pyarrow  # noqa: F401  (fail now, not after the solves, if the Parquet writer is missing)

    start = time.perf_counter()
    out_dir = Path(out_dir)
    check_out_dir(out_dir, spec)
    with hold_out_dir(out_dir, f"sweep {spec.name!r}"):
        cases_dir = out_dir / "cases"
        cases_dir.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(cases_dir)       # left by a killed run (out_dir's: check_writable)
        records = stored_records(spec.cases, cases_dir, retry_failed, RECORD_KEYS, _record_problem)
        pending = [case for case in spec.cases if case.case_id not in records]
        known_slots = {"local": workers, "synchronous": 1}.get(scheduler)      # a cluster's: once connected
        if known_slots is not None:
            check_sweep_budget(pending, known_slots, max_hours, force, not no_share)
        write_json_atomic(out_dir / f"{NAME}.json", {
            "name": spec.name, "source": spec.source, "grid": dict(spec.grid), "list": dict(spec.zipped),
            "outputs": [o.text for o in spec.outputs], "cases": len(spec.cases), "base_scene": spec.base_document,
            "version": code_version()})
        skipped = len(spec.cases) - len(pending)

        def table_rows():
            return [case_row(case, records[case.case_id], spec.outputs) for case in spec.cases
                    if case.case_id in records]

        bar = tqdm(total=len(spec.cases), initial=skipped, desc=spec.name, unit="case", disable=quiet)

        def on_record(case, record):
            records[case.case_id] = record
            write_table(table_rows(), out_dir, NAME)          # every case of this sweep on disk, up to the last one
            bar.update(1)
            if record["status"] != "ok":
                bar.write(f"{NAME}: case {dict(case.parameters)} failed: {record['error'][:300]}")

        set_aside(pending, cases_dir)         # a failed record being retried: keep it beside, out of the poller's way
        tasks = []
        if pending:
            with connect(scheduler, workers, connect_timeout) as client:
                slots = sum(client.nthreads().values()) if client is not None else 1     # task slots
                if known_slots is None:
                    check_sweep_budget(pending, slots, max_hours, force, not no_share)
                tasks = plan_tasks(pending, slots, share_prepare=not no_share)
                run_tasks(tasks, iter_group, _payload, _crashed, cases_dir, on_record, client)
        bar.close()
        rows = table_rows()
        write_table(rows, out_dir, NAME)
        save_figure(plot_sweep(rows, spec.axes, spec.zipped_axes, spec.outputs, spec.name), out_dir, NAME)
    failed = sum(row["status"] != "ok" for row in rows)
    seconds = time.perf_counter() - start
    print(f"{NAME}: {len(rows)} cases, {len(pending)} ran, {skipped} skipped (done before), {failed} failed; "
          f"{seconds:.1f} s")
    return {"cases": len(rows), "ran": len(pending), "skipped": skipped, "ok": len(rows) - failed, "failed": failed,
            "wall_time": seconds, "tasks": len(tasks)}
