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

__all__ = ["LOCAL", "SYNCHRONOUS", "ADDRESS_SCHEMES", "check_scheduler", "check_connect_timeout", "connect",
           "read_record", "write_record", "stored_records", "set_aside", "run_tasks", "collect", "axis_points", "RecordWarning", "is_scalar"]

LOCAL = "local"                # a LocalCluster of worker processes on this machine
SYNCHRONOUS = "synchronous"    # no dask: the tasks run one after another in this process
ADDRESS_SCHEMES = ("tcp://",)
# dask schemes the runner does not take, and why (a clear refusal instead of a traceback from inside dask)
UNSUPPORTED_SCHEMES = {
    "tls://": "needs TLS certificates (a dask Security object), which the runner does not take",
    "wss://": "needs TLS certificates (a dask Security object), which the runner does not take",
    "ws://": "needs the websockets transport on every worker, which the runner does not set up",
    "ucx://": "needs UCX (ucx-py) on the scheduler and every worker",
    "inproc://": "is an address inside one process: the runner's workers are other processes",
}
MAX_CONNECT_SECONDS = 3600.0
POLL_SECONDS = 0.5             # how often the client looks for case records written by running tasks


def check_scheduler(scheduler) -> str:
    """Return ``scheduler`` if it is "local", "synchronous" or a dask address tcp://HOST:PORT, else raise ValueError
    naming the value and what is allowed (TypeError for what is not text)."""
    if not isinstance(scheduler, str):
        raise TypeError(f"scheduler={scheduler!r} must be text: {LOCAL!r}, {SYNCHRONOUS!r} or 'tcp://host:8786'")
    if scheduler in (LOCAL, SYNCHRONOUS):
        return scheduler
    allowed = f"allowed: {LOCAL!r}, {SYNCHRONOUS!r} or a dask scheduler address 'tcp://HOST:PORT'"
    one_of = f"one of {LOCAL!r}, {SYNCHRONOUS!r} or a dask scheduler address 'tcp://HOST:PORT'"
    for scheme, reason in UNSUPPORTED_SCHEMES.items():
        if scheduler.startswith(scheme):
            raise ValueError(f"--scheduler {scheduler!r}: {scheme} {reason}; {allowed}")
    if not scheduler.startswith(ADDRESS_SCHEMES):
        raise ValueError(f"--scheduler {scheduler!r} is not {one_of}")
    host, colon, port = scheduler[len("tcp://"):].rpartition(":")
    if not colon or not host or "/" in host or not port.isdigit() or not 1 <= int(port) <= 65535:
        raise ValueError(f"--scheduler {scheduler!r}: an address is tcp://HOST:PORT with PORT in [1, 65535], e.g. "
                         f"'tcp://localhost:8786'")
    return scheduler


def check_connect_timeout(seconds) -> float:
    """Seconds to reach a scheduler: a finite number in (0, MAX_CONNECT_SECONDS] (not inf, nan, -1 or a bool)."""
    from fem.validation import check_range

    return check_range("--connect-timeout", seconds, 0.0, MAX_CONNECT_SECONDS, "s", low_open=True)


@contextmanager
def connect(scheduler: str = LOCAL, workers: int = 2, timeout: float = 5.0):
    """Yield a dask.distributed Client (None for "synchronous").

    ``scheduler``: "local" starts a LocalCluster of ``workers`` processes with one thread each (dask sets
    OMP/MKL/OpenBLAS threads to 1 in each); an address such as "tcp://host:8786" connects to a running scheduler
    within ``timeout`` seconds, else raises ConnectionError naming the address.
    """
    check_scheduler(scheduler)
    check_connect_timeout(timeout)
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
    except (OSError, TimeoutError, ValueError) as error:      # ValueError: an address dask cannot parse
        raise ConnectionError(f"cannot reach the dask scheduler at {scheduler!r} within {timeout:g} s ({error}); "
                              f"is it running? (dask scheduler --port ...)") from None
    with client:
        yield client


def read_record(path: Path, required: Iterable[str] = ("case_id", "status"),
                check: Callable | None = None) -> dict | None:
    """The case record in ``path``, or None when absent, unreadable or not a record of this case (missing one of
    ``required``, another case's id, an unknown status, a non-string error; e.g. ``{}``; or ``check(record)``
    names a problem): the case then runs again."""
    return _record_and_problem(path, required, check)[0]


def _record_and_problem(path: Path, required, check) -> tuple[dict | None, str | None]:
    """(record, None), (None, what is wrong with the file), or (None, None) when there is no file."""
    try:
        record = json.loads(Path(path).read_text())
    except FileNotFoundError:
        return None, None
    except (OSError, ValueError) as error:
        return None, f"not readable JSON ({type(error).__name__})"
    if not isinstance(record, dict) or any(key not in record for key in required):
        return None, f"not a case record (needs {list(required)})"
    if record.get("case_id") != Path(path).stem or record.get("status") not in ("ok", "failed") \
            or not isinstance(record.get("error"), (str, type(None))):
        return None, "another case's id, an unknown status or an error that is not text"
    problem = check(record) if check is not None else None
    return (None, problem) if problem else (record, None)


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


class RecordWarning(UserWarning):
    """A stored case record that does not read back as a record of its case: skipped, the case runs again."""


def stored_records(cases, cases_dir, retry_failed: bool = False, required: Iterable[str] = ("case_id", "status"),
                   check: Callable | None = None) -> dict:
    """{case_id: record} of the cases recorded in ``cases_dir`` (ok ones, and failed ones unless ``retry_failed``).
    ``check(record, case)`` names what is wrong with a record of that case, or None. A record file that is not a
    valid record of its case is skipped with one RecordWarning listing the files (its case runs again)."""
    records, damaged = {}, []
    for case in cases:
        path = Path(cases_dir) / f"{case.case_id}.json"
        record, problem = _record_and_problem(path, tuple(required),
                                              None if check is None else (lambda record: check(record, case)))
        if problem:
            damaged.append(f"{path.name} ({problem})")
        elif record is not None and (record["status"] == "ok" or not retry_failed):
            records[case.case_id] = record
    if damaged:
        import warnings

        shown = "; ".join(damaged[:5]) + (f"; and {len(damaged) - 5} more" if len(damaged) > 5 else "")
        warnings.warn(f"{len(damaged)} case record(s) in {str(cases_dir)!r} skipped, their cases run again: {shown}",
                      RecordWarning, stacklevel=2)
    return records


def is_scalar(value) -> bool:
    """A plain JSON scalar a table cell can hold: a number, a string, a bool or None."""
    return value is None or isinstance(value, (bool, int, float, str))


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
