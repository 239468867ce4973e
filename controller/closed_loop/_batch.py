"""Many closed-loop trials at once: a process pool, results as they finish, progress on a bar.

Each trial is independent (its own MuJoCo world and random stream), so trials fan out over processes; a worker
warms its caches once (the compiled kernels, the calibrated fingertip, the sensing bench) and then runs job after
job. Results come back in completion order with the index of their job.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor, as_completed

from fem.validation import check_integer

from ._trial import GraspObject, TrialResult, TrialSettings

__all__ = ["run_trials", "map_trials", "default_processes", "available_cpus", "MAX_PROCESSES"]

MAX_PROCESSES = 256             # worker processes of one batch (fig6's --workers has the same bound)


def available_cpus() -> int:
    """The CPUs this process may use (``os.sched_getaffinity``; elsewhere ``os.cpu_count``), at least 1."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:                                                  # not on Linux
        return max(os.cpu_count() or 1, 1)


def default_processes() -> int:
    """Worker processes for a batch: ``FINGERTIP_PROCESSES`` if set (``studies all`` shares the CPUs out that way),
    else the CPUs this process may use (``os.sched_getaffinity``), 1 to MAX_PROCESSES."""
    setting = os.environ.get("FINGERTIP_PROCESSES")
    if setting:
        try:
            processes = int(setting)
        except ValueError:
            processes = 0
        if not 1 <= processes <= MAX_PROCESSES:
            raise ValueError(f"FINGERTIP_PROCESSES={setting!r} must be an integer in [1, {MAX_PROCESSES}]")
        return processes
    return min(available_cpus(), MAX_PROCESSES)


def _warm() -> None:
    """Compile the kernels and build the default fingertip's bench once per worker."""
    from ._trial import TABLE_I_OBJECTS
    from ._world import GraspWorld

    GraspWorld(TABLE_I_OBJECTS["eclair"], TrialSettings(hold_time=0.0, place=False))


def _call(index: int, function: Callable, arguments: tuple) -> tuple[int, object]:
    return index, function(*arguments)


def map_trials(function: Callable, jobs: Iterable[tuple], processes: int | None = None,
               progress: str | None = None) -> Iterator[tuple[int, object]]:
    """``function(*job)`` for every job over a process pool; yield (job index, value) as each finishes.

    ``function`` must be importable by name (a module-level function). ``processes``: default
    ``default_processes()``; 1 runs the jobs here, in order. ``progress``: a label for a progress bar on stderr
    (None: no bar).
    """
    from tqdm import tqdm

    jobs = list(jobs)
    if not jobs:
        return
    processes = default_processes() if processes is None else processes
    processes = check_integer("processes", processes, 1, MAX_PROCESSES)
    bar = tqdm(total=len(jobs), desc=progress, unit="job", disable=progress is None, leave=False)
    try:
        if processes == 1 or len(jobs) == 1:
            for index, job in enumerate(jobs):
                yield _call(index, function, job)
                bar.update()
            return
        with ProcessPoolExecutor(max_workers=min(processes, len(jobs)), initializer=_warm) as pool:
            futures = [pool.submit(_call, index, function, job) for index, job in enumerate(jobs)]
            for future in as_completed(futures):
                yield future.result()
                bar.update()
    finally:
        bar.close()


def _trial(obj: GraspObject, settings: TrialSettings, options: dict) -> TrialResult:
    from ._world import run_trial

    return run_trial(obj, settings, **options)


def run_trials(jobs: Iterable[tuple[GraspObject, TrialSettings]], processes: int | None = None,
               progress: str | None = None, **options) -> Iterator[tuple[int, TrialResult]]:
    """Run (object, settings) trials; yield (job index, TrialResult) as each finishes (``map_trials``).

    ``options`` go to ``run_trial`` (tip, controller parameters).
    """
    yield from map_trials(_trial, [(obj, settings, options) for obj, settings in jobs], processes, progress)
