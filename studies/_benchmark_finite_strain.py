"""``python -m studies benchmark --finite-strain``: the Neo-Hookean gel's contact path against the linear one.

One fingertip bump (the finite-strain study's, ``contact.calculix.bump_scene``) pressed to 1.5 N, held, then
sheared or twisted (10 increments towards gross slip, mu = 1), solved with ``material.law`` linear and neo_hookean
on the same mesh, alternately, side by side in one run: whole solve and contact path (medians), their ratios (the
issue's aim: <= 10x), Newton iterations and sub-steps. Both with their compliance columns solved afresh (the linear
path's dominant cost on larger meshes; the finite-strain path needs none: it factorizes its tangent system each
Newton iteration instead). A path that stops early is named, and its increments until then are timed.
"""

from __future__ import annotations

import dataclasses
import statistics
import time
from pathlib import Path

import numpy as np

from studies._output import write_csv_atomic, write_json_atomic

NAME = "benchmark_finite_strain"
HOLD_DEPTH = 1.117       # mm: the linear FEM bump's depth at 1.5 N at h = 0.5 mm (1.122 mm at 0.3: both held here)


def compare_finite_strain(out_dir, quick: bool = False, repeats: int = 1, modes=(("default threads", None),)) -> dict:
    """Time the bump's shear and twist paths with both gel laws, alternating; write benchmark_finite_strain.csv and
    .json."""
    from contact.calculix import BumpSetup, bump_scene
    from contact.result import PathNotCompleted
    from contact.solver import solve_scene
    from studies._threads import describe_threads, limited_threads, thread_settings

    size = 0.5 if quick else 0.3
    setup = dataclasses.replace(BumpSetup(), depth=HOLD_DEPTH)
    steps = np.linspace(0.1, 1.0, 10)
    paths = {"shear": steps * setup.shear_shift, "twist": steps * setup.twist_angle}
    rows = []
    for repeat in range(repeats):
        for label, limit in modes:
            for path, values in paths.items():
                for law in ("linear", "neo_hookean"):
                    scene = bump_scene(setup, path, values, (0.25, 0.5, 1.0, 1.5), size_contact=size)
                    scene = dataclasses.replace(scene, material=dataclasses.replace(scene.material, law=law))
                    stopped = ""
                    with limited_threads(limit):
                        start = time.perf_counter()
                        try:
                            result = solve_scene(scene, cache_compliance=False)
                        except PathNotCompleted as error:
                            result, stopped = error.result, str(error)[:200]
                        wall = time.perf_counter() - start
                    rows.append(dict(threads=label, repeat=repeat, path=path, law=law, wall=wall,
                                     contact_path=result.timings["contact"], dofs=result.mesh_info["dofs"],
                                     increments=len(result.increments),
                                     newton_iterations=sum(i.iterations for i in result.increments),
                                     substeps=sum(i.substeps for i in result.increments), stopped=stopped))
    write_csv_atomic(Path(out_dir) / f"{NAME}.csv", rows)
    settings = thread_settings()
    summary = dict(dofs=rows[0]["dofs"], size_contact=size, repeats=repeats, thread_settings=settings, threads={})
    print(f"{NAME}: one bump, h = {size} mm, {summary['dofs']} DOF, medians of {repeats}; threads: "
          f"{describe_threads(settings)}")
    for label, _ in modes:
        summary["threads"][label] = {}
        for path in paths:
            median = {law: {key: statistics.median(row[key] for row in rows if row["threads"] == label
                                                   and row["path"] == path and row["law"] == law)
                            for key in ("wall", "contact_path", "newton_iterations", "increments")}
                      for law in ("linear", "neo_hookean")}
            ratio = median["neo_hookean"]["wall"] / median["linear"]["wall"]
            stopped = sorted({row["stopped"] for row in rows if row["path"] == path and row["stopped"]})
            summary["threads"][label][path] = dict(median, ratio_whole=ratio,
                                                   ratio_contact=median["neo_hookean"]["contact_path"]
                                                   / median["linear"]["contact_path"], stopped=stopped)
            print(f"  {label:15s} {path}: linear {median['linear']['wall']:.1f} s, Neo-Hookean "
                  f"{median['neo_hookean']['wall']:.1f} s = {ratio:.1f}x ({median['neo_hookean']['increments']:.0f} "
                  f"of {median['linear']['increments']:.0f} increments)"
                  + (f" - stopped: {stopped[0]}" if stopped else ""))
    write_json_atomic(Path(out_dir) / f"{NAME}.json", summary)
    return summary
