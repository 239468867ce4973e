"""``python -m studies benchmark --substeps``: a bump array's twist path with and without remembered sub-steps.

The design study's 3x3 twist path (``controller.design``; h = 0.3 mm, 0.7 mm with ``--quick``) on one prepared
mesh, solved alternately with ``remember_substeps`` on (an increment starts split as finely as the last one needed)
and off (each increment tries the whole step first and bisects after Newton stagnates), side by side in one run.
Reports the medians, their ratio and the largest difference of the path's torques: round-off where bisection needed
the same split at every increment (the default mesh), the path's discretisation where it took a later step more
coarsely (1.5e-4 of the largest torque on the quick mesh).
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

from studies._output import write_csv_atomic, write_json_atomic

NAME = "benchmark_substeps"


def compare_substeps(out_dir, quick: bool = False, repeats: int = 1, modes=(("default threads", None),)) -> dict:
    """Time the twist path both ways, alternating, at each thread setting (``studies._threads``); write
    benchmark_substeps.csv and .json."""
    from contact.solver import prepare, solve_scene
    from controller.design import DesignStudy, FingertipDesign, design_scenes
    from studies._threads import describe_threads, limited_threads, thread_settings

    study = DesignStudy(size_contact=0.7, size_base=1.5) if quick else DesignStudy()
    _, twist = design_scenes(FingertipDesign(), study)
    prepared = prepare(twist)
    solve_scene(twist, prepared)                       # compliance columns computed once, before any timing
    rows, torques = [], {}
    for repeat in range(repeats):
        for (label, limit), remember in ((mode, remember) for mode in modes for remember in (True, False)):
            with limited_threads(limit):
                start = time.perf_counter()
                result = solve_scene(twist, prepared, remember_substeps=remember)
                wall = time.perf_counter() - start
            torques[remember] = np.array([increment.torque for increment in result.increments])
            rows.append(dict(threads=label, repeat=repeat, remember_substeps=remember, wall=wall,
                             dofs=result.mesh_info["dofs"],
                             substeps=sum(increment.substeps for increment in result.increments),
                             newton_iterations=sum(increment.iterations for increment in result.increments),
                             factorizations=result.timings["newton_factorizations"]))
    write_csv_atomic(Path(out_dir) / f"{NAME}.csv", rows)
    settings = thread_settings()
    summary = dict(dofs=rows[0]["dofs"], repeats=repeats, thread_settings=settings,
                   largest_torque_difference=float(np.max(np.abs(torques[True] - torques[False]))),
                   largest_torque=float(np.max(np.abs(torques[False]))), threads={})
    print(f"{NAME}: 3x3 twist path, {summary['dofs']} DOF, medians of {repeats}; threads: {describe_threads(settings)}")
    for label, _ in modes:
        median = {remember: statistics.median(row["wall"] for row in rows
                                              if row["remember_substeps"] is remember and row["threads"] == label)
                  for remember in (True, False)}
        summary["threads"][label] = dict(wall_remembered=median[True], wall_bisected=median[False],
                                         ratio=median[True] / median[False])
        print(f"  {label:15s}: {median[True]:.1f} s with remembered sub-steps, {median[False]:.1f} s bisecting each "
              f"increment anew (ratio {median[True] / median[False]:.2f})")
    write_json_atomic(Path(out_dir) / f"{NAME}.json", summary)
    print(f"  torques differ by {summary['largest_torque_difference']:.2g} of {summary['largest_torque']:.3g} N mm")
    return {}
