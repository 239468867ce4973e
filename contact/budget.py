"""Budgets of many solves, checked before the first one starts: the memory of each solve against the machine, and
the estimated wall time of the whole plan against a stated limit; ``force`` runs past both.

A sweep of 22,500 cases or 8000 designs used to start and run for days, and a design with a 1e-4 mm sensor pitch
or a 1e6 mm base to start and fail deep inside. ``check_budget`` refuses such a plan before any work, with the
estimate and the way to go on (fewer cases, coarser settings, more workers, ``--max-hours`` or ``--force``).

The time model is fitted on runs measured on 2 cores shared with other jobs (load 4, about twice a quiet machine's
times): preparation 4 s x (DOF / 27.1k)^(4/3) (the factor's fill; HCM-1 at h = 0.2 mm took 4.2 s), three times that
for a gmsh gel (meshing: the Fig. 4 cap 6.4 s, the 3x3 array 16 s); each increment 0.05 s x sqrt(candidate surface
points) (HCM-1 1.1 s at 445 points, the cap 1.7 s at 1711, the array 2.9-3.8 s at 6259). The DOF and points come
from ``contact.limits.estimate_resources`` (1.3-2.3x the mesh's). Against whole runs: the example design files
3.2 min estimated for 2.6 min measured and 13 min for 13.6 min (2 workers), one 3x3 design 47 s for 43 s. An
estimate within a factor of about 2, then: enough to tell an hour from a week, which is what the limit is for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Iterable

from contact import limits
from contact.limits import PhysicalLimitError, estimate_resources, fine_zone
from contact.scene import Scene
from fem.validation import check_bool, check_integer, check_range

__all__ = ["DEFAULT_MAX_HOURS", "MAX_CASES", "SAMPLE", "Task", "scene_cost", "sampled", "check_budget",
           "check_case_count"]

DEFAULT_MAX_HOURS = 12.0          # h: an overnight run; longer plans need --max-hours or --force
MAX_CASES = 100_000               # cases or designs in one file: each is built and checked before any solve
SAMPLE = 200                      # a plan of more tasks is estimated from this many, evenly spaced (each ~20 ms)
PREPARE_REFERENCE = (27.1e3, 4.0)         # (DOF, s): mesh + assembly + factorization of a block (see above)
GMSH_FACTOR = 3.0                         # a cap or an array: meshing by gmsh on top
INCREMENT_SECONDS_PER_ROOT_POINT = 0.05   # s per increment per sqrt(candidate surface points)


@dataclass(frozen=True)
class Task:
    """One unit of a plan: what it is (for messages), its peak memory [bytes] and its wall time [s] on one worker."""

    label: str
    bytes: float
    seconds: float


def scene_cost(scene: Scene, increments: int | None = None, prepare: bool = True) -> dict:
    """Estimated DOF, peak memory [bytes] and seconds of one solve of ``scene`` (``increments``: of its load path by
    default; ``prepare``: include meshing, assembly and factorization)."""
    fine_radius, half = fine_zone(scene)
    estimate = estimate_resources(scene, fine_radius, half)
    dofs = estimate["dofs"]
    if increments is None:
        increments = sum(len(load.values) for load in scene.loads)
    seconds = increments * INCREMENT_SECONDS_PER_ROOT_POINT * math.sqrt(estimate["surface_points"])
    if prepare:
        meshing = 1.0 if scene.gel.shape == "block" else GMSH_FACTOR
        seconds += meshing * PREPARE_REFERENCE[1] * (dofs / PREPARE_REFERENCE[0]) ** (4.0 / 3.0)
    return {"dofs": dofs, "bytes": estimate["bytes"], "seconds": seconds}


def sampled(groups: list) -> tuple[list, float]:
    """At most SAMPLE of ``groups``, evenly spaced, and the factor that scales their time to all of them: a plan
    of 8000 designs is estimated in seconds. Each solve still checks its own memory before meshing
    (``contact.limits.check_resources``), so an outlier between the samples is refused when it comes."""
    step = max(1, -(-len(groups) // SAMPLE))
    chosen = groups[::step]
    return chosen, len(groups) / max(len(chosen), 1)


def check_case_count(count: int, what: str = "cases") -> None:
    """Refuse a file that asks for more than MAX_CASES cases (each is built and checked before any solve)."""
    if count > MAX_CASES:
        raise PhysicalLimitError(f"{count} {what} in one file is more than {MAX_CASES}: split the axes over "
                                 f"several files")


def check_budget(tasks: Iterable[Task], workers: int, max_hours: float = DEFAULT_MAX_HOURS, force: bool = False,
                 what: str = "the plan", count: int | None = None, total: int | None = None) -> dict:
    """Refuse (PhysicalLimitError, a ValueError) a plan whose largest task needs more memory than this machine has
    per worker, or whose estimated wall time on ``workers`` exceeds ``max_hours``; ``force`` skips both refusals.
    ``tasks`` may be a generator (``count`` of them, standing for ``total`` when ``sampled``): the estimate stops at
    the first task past a limit, so a plan of thousands is refused in seconds. Returns the estimate: tasks, peak
    bytes per worker, hours."""
    check_integer("workers", workers, 1, 100_000)
    check_range("max_hours", max_hours, 0.0, math.inf, "h", low_open=True, high_open=True)
    check_bool("force", force)
    machine, free = limits.machine_memory(), limits.available_memory()
    seen, seconds, largest = 0, 0.0, None
    for task in tasks:
        seen += 1
        seconds += task.seconds
        if largest is None or task.bytes > largest.bytes:
            largest = task
        at_once = min(workers, count or seen)
        if force:
            continue
        if machine is not None and task.bytes * at_once > machine:
            raise PhysicalLimitError(f"{task.label} needs about {task.bytes / 1e9:.3g} GB (x {at_once} worker(s) at "
                                     f"once); this machine has {machine / 1e9:.3g} GB in all: coarser settings or "
                                     f"fewer workers\n--force runs it anyway")
        hours = seconds / workers / 3600.0
        if hours > max_hours:
            stopped = bool(count and seen < count)
            basis = f"{seen} of {count} task(s)" if stopped else f"{seen} task(s)"
            if total and count and total > count:
                basis += f" standing for {total}"
            raise PhysicalLimitError(f"{what} would take {'more than' if stopped else 'about'} {hours:.3g} h on "
                                     f"{workers} worker(s) (estimated over {basis}), "
                                     f"past the limit of {max_hours:g} h: fewer cases, coarser settings or more "
                                     f"workers, or raise --max-hours\n--force runs it anyway")
    estimate = {"tasks": seen, "bytes": largest.bytes if largest else 0.0, "hours": seconds / workers / 3600.0}
    if not force and largest is not None and free is not None and largest.bytes * min(workers, seen) > free:
        import warnings

        from contact.limits import PhysicalLimitWarning

        warnings.warn(f"{largest.label} needs about {largest.bytes / 1e9:.3g} GB per worker; {free / 1e9:.3g} GB are "
                      f"free now: the run may swap", PhysicalLimitWarning, stacklevel=2)
    return estimate
