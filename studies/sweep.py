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
POLL_SECONDS = 0.5          # how often the client looks for case records written by running tasks


def add_arguments(parser) -> None:
    parser.add_argument("sweep_file", type=Path, help="sweep TOML file (see studies/sweeps/)")
    parser.add_argument("--scheduler", default="local",
                        help="'local' (a LocalCluster, default), 'synchronous' (no dask, in this process) or the "
                             "address of a running scheduler, e.g. tcp://host:8786 (workers must share DIR)")
    parser.add_argument("--workers", type=int, default=2, help="worker processes of the LocalCluster (default 2)")
    parser.add_argument("--connect-timeout", type=float, default=5.0, help="seconds to reach --scheduler (default 5)")
    parser.add_argument("--retry-failed", action="store_true", help="run the cases recorded as failed again")
    parser.add_argument("--no-share", action="store_true",
                        help="one task per case, each preparing its own mesh (to measure what sharing saves)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


RECORD_KEYS = ("case_id", "status", "increments")


def _read_record(path: Path) -> dict | None:
    """The case record in ``path``, or None when absent, unreadable or not a record of this case (e.g. ``{}``):
    the case then runs again."""
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or any(key not in record for key in RECORD_KEYS) \
            or record["case_id"] != path.stem or record["status"] not in ("ok", "failed"):
        return None
    return record


def _identity(spec) -> dict:
    """What makes two sweeps the same sweep for one --out: the name and the axes (keys)."""
    return {"name": spec.name, "axes": sorted(spec.axes)}


def check_out_dir(out_dir: Path, spec) -> None:
    """Refuse an --out that holds a different sweep (another name or other axes), or that cannot be written."""
    previous = out_dir / f"{NAME}.json"
    if previous.exists():
        try:
            stored = json.loads(previous.read_text())
            stored_identity = {"name": stored["name"], "axes": sorted([*stored["grid"], *stored["list"]])}
        except (OSError, ValueError, KeyError, TypeError):
            stored_identity = None
        if stored_identity != _identity(spec):
            raise ValueError(f"--out {str(out_dir)!r} holds another sweep ({stored_identity or 'unreadable sweep.json'}"
                             f"; this one is {_identity(spec)}): choose another --out, or delete that folder")
    from studies.run import check_writable

    check_writable(out_dir)


def _run_pending(tasks, client, cases_dir: Path, on_record) -> None:
    """Run the tasks (lists of cases) and call ``on_record(case, record)`` once per case as it finishes."""
    from studies._sweep_exec import failed_record, iter_group, solve_group

    def payload(task):
        return [(case.case_id, dict(case.parameters), case.document) for case in task]

    if client is None:
        for number, task in enumerate(tasks):
            for case, record in zip(task, iter_group(payload(task), str(cases_dir), f"g{number}")):
                on_record(case, record)
        return
    from distributed import wait

    futures = {client.submit(solve_group, payload(task), str(cases_dir), f"g{number}", pure=False): task
               for number, task in enumerate(tasks)}
    waiting = {case.case_id: case for task in tasks for case in task}
    pending = set(futures)
    while pending:
        try:
            done = wait(pending, timeout=POLL_SECONDS, return_when="FIRST_COMPLETED").done
        except TimeoutError:
            done = set()
        for case_id in list(waiting):     # records written by running tasks (shared filesystem)
            record = _read_record(cases_dir / f"{case_id}.json")
            if record is not None:
                on_record(waiting.pop(case_id), record)
        for future in done:
            pending.discard(future)
            try:
                records = future.result()
            except Exception as error:    # the task itself died (worker lost, out of memory): record its cases
                records = [failed_record(c.case_id, dict(c.parameters), f"task failed: {type(error).__name__}: "
                                                                         f"{error}") for c in futures[future]]
            for record in records:
                if record["case_id"] in waiting:
                    write_json_atomic(cases_dir / f"{record['case_id']}.json", record)
                    on_record(waiting.pop(record["case_id"]), record)


def run(out_dir, quick: bool = False, sweep_file: Path | None = None, scheduler: str = "local", workers: int = 2,
        connect_timeout: float = 5.0, retry_failed: bool = False, no_share: bool = False, quiet: bool = False) -> dict:
    """Run (or resume) the sweep; returns counts of cases (total, ran, skipped, ok, failed) and the wall time."""
    from tqdm import tqdm

    from studies._sweep_exec import check_scheduler, connect, plan_tasks
    from studies._sweep_spec import code_version, load_sweep
    from studies._sweep_table import case_row, plot_sweep, write_table

    if sweep_file is None:
        raise ValueError("sweep needs a sweep file: python -m studies sweep SWEEP.toml --out DIR")
    check_scheduler(scheduler)
    spec = load_sweep(sweep_file, quick=quick)           # every case validated before anything runs
    import pyarrow  # noqa: F401  (fail now, not after the solves, if the Parquet writer is missing)

    start = time.perf_counter()
    out_dir = Path(out_dir)
    check_out_dir(out_dir, spec)
    cases_dir = out_dir / "cases"
    cases_dir.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(cases_dir)       # left by a killed run (out_dir's: check_writable)
    write_json_atomic(out_dir / f"{NAME}.json", {
        "name": spec.name, "source": spec.source, "grid": dict(spec.grid), "list": dict(spec.zipped),
        "outputs": [o.text for o in spec.outputs], "cases": len(spec.cases), "base_scene": spec.base_document,
        "version": code_version()})
    records = {}
    for case in spec.cases:
        record = _read_record(cases_dir / f"{case.case_id}.json")
        if record is not None and (record["status"] == "ok" or not retry_failed):
            records[case.case_id] = record
    pending = [case for case in spec.cases if case.case_id not in records]
    skipped = len(spec.cases) - len(pending)

    def table_rows():
        return [case_row(case, records[case.case_id], spec.outputs) for case in spec.cases
                if case.case_id in records]

    bar = tqdm(total=len(spec.cases), initial=skipped, desc=spec.name, unit="case", disable=quiet)

    def on_record(case, record):
        records[case.case_id] = record
        write_table(table_rows(), out_dir, NAME)          # the table is always complete up to the last case
        bar.update(1)
        if record["status"] != "ok":
            bar.write(f"{NAME}: case {dict(case.parameters)} failed: {record['error'][:300]}")

    for case in pending:                  # a failed record being retried: keep it beside, out of the poller's way
        stale = cases_dir / f"{case.case_id}.json"
        if stale.exists():
            stale.replace(stale.with_suffix(".json.previous"))
    tasks = []
    if pending:
        with connect(scheduler, workers, connect_timeout) as client:
            slots = sum(client.nthreads().values()) if client is not None else 1     # task slots
            tasks = plan_tasks(pending, slots, share_prepare=not no_share)
            _run_pending(tasks, client, cases_dir, on_record)
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
