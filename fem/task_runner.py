"""Resumable runs of many independent cases, on dask.distributed or in this process: the machinery of the scene
sweeps (``python -m studies sweep``) and the fingertip design sweeps (``controller.design``).

A case has an id (``case_id``). Cases are grouped into tasks (a task shares expensive work, e.g. one mesh and
factorization, among its cases). A task is a module-level generator function ``iterate(items, cases_dir, group)``
that yields one record (a JSON-ready dict with ``case_id`` and ``status``) per case as it finishes and writes it to
``cases_dir/<case_id>.json`` (atomically), so an interrupted run keeps every finished case; on a cluster without a
shared filesystem the client writes the records a task returns when it ends. A re-run reads the records already
there and runs only the other cases (``--retry-failed``: the failed ones too).
"""

from __future__ import annotations

import itertools
import json
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterable

from fem.atomic import atomic_path

__all__ = ["LOCAL", "SYNCHRONOUS", "ADDRESS_SCHEMES", "check_scheduler", "connect", "read_record", "write_record",
           "stored_records", "set_aside", "run_tasks", "collect", "axis_points"]

LOCAL = "local"                # a LocalCluster of worker processes on this machine
SYNCHRONOUS = "synchronous"    # no dask: the tasks run one after another in this process
ADDRESS_SCHEMES = ("tcp://", "tls://", "ucx://", "inproc://", "ws://", "wss://")
POLL_SECONDS = 0.5             # how often the client looks for case records written by running tasks


def check_scheduler(scheduler: str) -> str:
    """Return ``scheduler`` if it is "local", "synchronous" or an address with a dask scheme, else raise."""
    if scheduler not in (LOCAL, SYNCHRONOUS) and not str(scheduler).startswith(ADDRESS_SCHEMES):
        raise ValueError(f"scheduler={scheduler!r} is not {LOCAL!r}, {SYNCHRONOUS!r} or an address like "
                         f"'tcp://host:8786'")
    return scheduler


@contextmanager
def connect(scheduler: str = LOCAL, workers: int = 2, timeout: float = 5.0):
    """Yield a dask.distributed Client (None for "synchronous").

    ``scheduler``: "local" starts a LocalCluster of ``workers`` processes with one thread each (dask sets
    OMP/MKL/OpenBLAS threads to 1 in each); an address such as "tcp://host:8786" connects to a running scheduler
    within ``timeout`` seconds, else raises ConnectionError naming the address.
    """
    check_scheduler(scheduler)
    if scheduler == SYNCHRONOUS:
        yield None
        return
    try:
        from distributed import Client, LocalCluster
    except ImportError as error:
        raise ImportError(f"the sweep needs dask.distributed ({error}): pip install 'fingertip-contact[sweep]', or "
                          f"run with --scheduler {SYNCHRONOUS}") from None
    if scheduler == LOCAL:
        if not (isinstance(workers, int) and not isinstance(workers, bool) and workers >= 1):
            raise ValueError(f"workers={workers!r} must be an integer >= 1")
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
                Client(cluster) as client:
            yield client
        return
    try:
        client = Client(scheduler, timeout=timeout)
    except (OSError, TimeoutError) as error:
        raise ConnectionError(f"cannot reach the dask scheduler at {scheduler!r} within {timeout:g} s ({error}); "
                              f"is it running? (dask scheduler --port ...)") from None
    with client:
        yield client


def read_record(path: Path, required: Iterable[str] = ("case_id", "status")) -> dict | None:
    """The case record in ``path``, or None when absent, unreadable or not a record of this case (missing one of
    ``required``, another case's id, an unknown status; e.g. ``{}``): the case then runs again."""
    try:
        record = json.loads(Path(path).read_text())
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or any(key not in record for key in required):
        return None
    if record.get("case_id") != Path(path).stem or record.get("status") not in ("ok", "failed"):
        return None
    return record


def write_record(cases_dir, record: dict) -> Path:
    """Write ``record`` to ``cases_dir/<case_id>.json`` atomically (NaN refused: records are plain JSON)."""
    def plain(value):
        if hasattr(value, "tolist"):          # numpy scalars and arrays
            return value.tolist()
        raise TypeError(f"cannot write {type(value).__name__} to a case record")

    path = Path(cases_dir) / f"{record['case_id']}.json"
    with atomic_path(path) as temporary:
        temporary.write_text(json.dumps(record, indent=1, allow_nan=False, default=plain) + "\n")
    return path


def stored_records(cases, cases_dir, retry_failed: bool = False,
                   required: Iterable[str] = ("case_id", "status")) -> dict:
    """{case_id: record} of the cases recorded in ``cases_dir`` (ok ones, and failed ones unless ``retry_failed``)."""
    records = {}
    for case in cases:
        record = read_record(Path(cases_dir) / f"{case.case_id}.json", required)
        if record is not None and (record["status"] == "ok" or not retry_failed):
            records[case.case_id] = record
    return records


def set_aside(cases, cases_dir) -> None:
    """Move the records of cases about to run again (failed ones being retried) to ``<id>.json.previous``, out of
    the way of the client that polls for new records."""
    for case in cases:
        stale = Path(cases_dir) / f"{case.case_id}.json"
        if stale.exists():
            stale.replace(stale.with_suffix(".json.previous"))


def collect(iterate: Callable, items: list, cases_dir: str | None, group: str = "") -> list[dict]:
    """Dask task: ``iterate(items, cases_dir, group)`` run to the end; its records, in order."""
    return list(iterate(items, cases_dir, group))


def run_tasks(tasks: list[list], iterate: Callable, payload: Callable, crashed: Callable, cases_dir: Path,
              on_record: Callable, client=None) -> None:
    """Run the tasks (lists of cases) and call ``on_record(case, record)`` once per case as it finishes.

    ``iterate``: module-level generator function (items, cases_dir, group) yielding records; ``payload(case)``: the
    picklable item a task receives for a case; ``crashed(case, message)``: the record of a case whose task died (a
    lost worker, a bug) before it could report. ``client``: a dask Client, or None to run here, one task after
    another.
    """
    if client is None:
        for number, task in enumerate(tasks):
            for case, record in zip(task, iterate([payload(case) for case in task], str(cases_dir), f"g{number}")):
                on_record(case, record)
        return
    from distributed import wait

    futures = {client.submit(collect, iterate, [payload(case) for case in task], str(cases_dir), f"g{number}",
                             pure=False): task for number, task in enumerate(tasks)}
    waiting = {case.case_id: case for task in tasks for case in task}
    pending = set(futures)
    while pending:
        try:
            done = wait(pending, timeout=POLL_SECONDS, return_when="FIRST_COMPLETED").done
        except TimeoutError:
            done = set()
        for case_id in list(waiting):     # records written by running tasks (shared filesystem)
            record = read_record(Path(cases_dir) / f"{case_id}.json")
            if record is not None:
                on_record(waiting.pop(case_id), record)
        for future in done:
            pending.discard(future)
            try:
                records = future.result()
            except Exception as error:    # the task itself died (worker lost, out of memory): record its cases
                records = [crashed(case, f"task failed: {type(error).__name__}: {error}") for case in futures[future]]
            for record in records:
                if record["case_id"] in waiting:
                    write_record(cases_dir, record)
                    on_record(waiting.pop(record["case_id"]), record)


def axis_points(grid, zipped) -> list[tuple[tuple[str, object], ...]]:
    """The points of a sweep: the cartesian product of the ``grid`` axes with the ``zipped`` axes, each given as
    ((key, values), ...); a point is ((key, value), ...), grid axes first. Refuses an axis in both and zipped axes of
    unequal lengths. No axes at all: one empty point."""
    both = sorted({key for key, _ in grid} & {key for key, _ in zipped})
    if both:
        raise ValueError(f"axis {both[0]!r} is in both [grid] and [list]")
    lengths = {key: len(values) for key, values in zipped}
    if len(set(lengths.values())) > 1:
        raise ValueError(f"[list] axes are zipped and need equal lengths, got {lengths}")
    grid_points = list(itertools.product(*[[(key, v) for v in values] for key, values in grid]))
    zip_points = list(zip(*[[(key, v) for v in values] for key, values in zipped])) or [()]
    return [tuple(g) + tuple(z) for g in grid_points for z in zip_points]
