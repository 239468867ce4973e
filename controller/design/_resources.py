"""Resource estimate of a design sweep before it starts: each FEM solution's memory and time with its sensors', and
the whole sweep's wall time, checked by ``contact.budget.check_budget``.

A design with a 1e-4 mm sensor pitch asks for 1.6e11 sensor nodes, one with a 1e6 mm base for a mesh of 1e13
elements, and 8000 designs for days of FEM: all are refused here, before any solve, unless forced.
"""

from __future__ import annotations

import math

from contact.budget import DEFAULT_MAX_HOURS, SAMPLE, Task, check_budget, sampled, scene_cost

from ._spec import DesignStudy, FingertipDesign, design_scenes, fem_key

__all__ = ["design_tasks", "check_design_resources", "SENSOR_SECONDS_PER_NODE_FRAME"]

# The sensor's readings of a path are (states x frames, nodes) floats, held with their noisy and quantised copies
# and the clipping operator (about 3 overlaps per node when cells are smaller than the base's elements): an upper
# bound of 4 copies plus 24 bytes per node.
SENSOR_COPIES = 4
SENSOR_OPERATOR_BYTES_PER_NODE = 24.0
# sampling, noise and the estimator per node, frame and draw: measured 0.064 s for the 3x3 design's 13 x 13 nodes,
# 10 frames per state, 8 states, 2 paths and 2 draws (1.2e-6 s), on a machine at load 4; three times that here
SENSOR_SECONDS_PER_NODE_FRAME = 4e-6


def _sensor_cost(design: FingertipDesign, study: DesignStudy) -> tuple[float, float]:
    """(bytes, seconds) of reading one design's two paths with its sensor."""
    nodes = (max(1, round(design.base_width / design.sensor_pitch))
             * max(1, round(design.base_depth / design.sensor_pitch)))
    states = 2 + max(len(study.load_ratios), len(study.twist_fractions))
    frames = states * study.frames_per_state
    draws = study.noise_draws if study.sensor == "capacitive" else 1
    memory = nodes * (8.0 * SENSOR_COPIES * frames + SENSOR_OPERATOR_BYTES_PER_NODE)
    seconds = SENSOR_SECONDS_PER_NODE_FRAME * nodes * 2 * frames * draws
    return memory, seconds


def design_tasks(designs: list[FingertipDesign], study: DesignStudy):
    """One Task per FEM solution (designs that differ only in their sensor share it), with its designs' sensors;
    a generator (the budget stops at the first task past a limit). Past SAMPLE solutions, evenly spaced ones stand
    for the rest (``contact.budget.sampled``: their times scaled up)."""
    chosen, scale = sampled(list(_groups(designs).values()))
    for members in chosen:
        shear, twist = design_scenes(members[0], study)
        cost = scene_cost(shear)
        memory, seconds = cost["bytes"], cost["seconds"]
        if twist is not None:
            twisted = scene_cost(twist, prepare=False)
            memory, seconds = max(memory, twisted["bytes"]), seconds + twisted["seconds"]
        sensors = [_sensor_cost(design, study) for design in members]
        memory += max(bytes_ for bytes_, _ in sensors)
        seconds += sum(seconds_ for _, seconds_ in sensors)
        first = members[0]
        label = (f"the design {first.rows}x{first.cols}, bump radius {first.bump_radius:g} mm, base "
                 f"{first.base_width:g} x {first.base_depth:g} mm, sensor pitch {first.sensor_pitch:g} mm")
        yield Task(label, memory, scale * seconds if math.isfinite(seconds) else math.inf)


def _groups(designs: list[FingertipDesign]) -> dict:
    groups: dict = {}
    for design in designs:
        groups.setdefault(fem_key(design), []).append(design)
    return groups


def check_design_resources(designs: list[FingertipDesign], study: DesignStudy, workers: int, force: bool = False,
                           max_hours: float = DEFAULT_MAX_HOURS) -> dict:
    """Refuse a design sweep that cannot fit or would run past ``max_hours`` on ``workers`` (unless ``force``)."""
    solutions = len(_groups(designs))
    return check_budget(design_tasks(designs, study), workers, max_hours, force,
                        f"the sweep of {len(designs)} designs", count=min(solutions, SAMPLE), total=solutions)
