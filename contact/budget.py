"""Budgets of many solves, checked before the first one starts: the memory of each solve against the machine, and
the estimated wall time of the whole plan against a stated limit; ``force`` runs past both.

A sweep of 22,500 cases or 8000 designs used to start and run for days, and a design with a 1e-4 mm sensor pitch
or a 1e6 mm base to start and fail deep inside. ``check_budget`` refuses such a plan before any work, with the
estimate and the way to go on (fewer cases, coarser settings, more workers, ``--max-hours`` or ``--force``).

The time model is an upper estimate fitted on runs measured on 2 cores shared with other jobs (load 4, about twice
a quiet machine's times): preparation 4 s x (DOF / 27.1k)^(4/3) (the factor's fill; HCM-1 at h = 0.2 mm took
4.2 s), three times that for a gmsh gel (meshing: the Fig. 4 cap 6.4 s, the 3x3 array 16 s); each increment
0.05 s x sqrt(candidate surface points) (HCM-1 1.1 s at 445 points, the cap 1.7 s at 1711, the array 2.9-3.8 s at
6259). The DOF and points come from ``contact.limits.estimate_resources`` (1.3-2.3x the mesh's), so the time is an
upper estimate within a factor of a few: enough to tell an hour from a week, which is what the limit is for.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from contact import limits
from contact.limits import PhysicalLimitError, estimate_resources, fine_zone
from contact.scene import Scene
from fem.validation import check_bool, check_integer, check_range

__all__ = ["DEFAULT_MAX_HOURS", "MAX_CASES", "Task", "scene_cost", "check_budget", "check_case_count"]

DEFAULT_MAX_HOURS = 12.0          # h: an overnight run; longer plans need --max-hours or --force
MAX_CASES = 100_000               # cases or designs in one file: each is built and checked before any solve
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


def check_case_count(count: int, what: str = "cases") -> None:
    """Refuse a file that asks for more than MAX_CASES cases (each is built and checked before any solve)."""
    if count > MAX_CASES:
        raise PhysicalLimitError(f"{count} {what} in one file is more than {MAX_CASES}: split the axes over "
                                 f"several files")


def check_budget(tasks: list[Task], workers: int, max_hours: float = DEFAULT_MAX_HOURS, force: bool = False,
                 what: str = "the plan") -> dict:
    """Refuse (PhysicalLimitError, a ValueError) a plan whose largest task needs more memory than this machine has
    per worker, or whose estimated wall time on ``workers`` exceeds ``max_hours``; ``force`` skips both refusals.
    Returns the estimate: tasks, peak bytes per worker, hours."""
    check_integer("workers", workers, 1, 100_000)
    check_range("max_hours", max_hours, 0.0, math.inf, "h", low_open=True, high_open=True)
    check_bool("force", force)
    peak = max((task.bytes for task in tasks), default=0.0)
    hours = sum(task.seconds for task in tasks) / workers / 3600.0
    estimate = {"tasks": len(tasks), "bytes": peak, "hours": hours}
    if force or not tasks:
        return estimate
    largest = max(tasks, key=lambda task: task.bytes)
    total, free = limits.machine_memory(), limits.available_memory()
    problems = []
    if total is not None and largest.bytes * min(workers, len(tasks)) > total:
        problems.append(f"{largest.label} needs about {largest.bytes / 1e9:.3g} GB (x {min(workers, len(tasks))} "
                        f"worker(s) at once); this machine has {total / 1e9:.3g} GB in all: coarser settings or "
                        f"fewer workers")
    if hours > max_hours:
        problems.append(f"{what} would take about {hours:.3g} h on {workers} worker(s) ({len(tasks)} task(s); an "
                        f"upper estimate), past the limit of {max_hours:g} h: fewer cases, coarser settings or more "
                        f"workers, or raise --max-hours")
    if problems:
        raise PhysicalLimitError("\n".join(problems + ["--force runs it anyway"]))
    if free is not None and largest.bytes * min(workers, len(tasks)) > free:
        import warnings

        from contact.limits import PhysicalLimitWarning

        warnings.warn(f"{largest.label} needs about {largest.bytes / 1e9:.3g} GB per worker; {free / 1e9:.3g} GB are "
                      f"free now: the run may swap", PhysicalLimitWarning, stacklevel=2)
    return estimate
