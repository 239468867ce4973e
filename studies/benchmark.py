"""Benchmark: HCM-1 contact path against one linear-elastic solve on the same mesh, side by side in one run.

Reports medians over repeats of: mesh, assembly, factorization, compliance columns, the whole contact path, one
plain linear solve (assembly + factorization + one back-substitution), their ratio (target <= 3) and the peak
memory of the process. Timings are never asserted in tests: the machines are shared and noisy.
"""

from __future__ import annotations

import dataclasses
import resource
import statistics
import time
from pathlib import Path

from studies._output import write_csv_atomic, write_json_atomic

NAME = "benchmark"
SCENE = Path(__file__).parent / "scenes" / "hcm1.toml"
TARGET_RATIO = 3.0


def add_arguments(parser) -> None:
    parser.add_argument("--repeats", type=int, default=3, help="solves per setting; medians are reported")


def run(out_dir, quick: bool = False, repeats: int = 3) -> dict:
    """Time the HCM-1 path; write benchmark.csv (one row per repeat) and benchmark.json (medians)."""
    from contact.scene import load_scene
    from contact.solver import solve_scene

    if repeats < 1:
        raise ValueError(f"repeats={repeats!r} must be >= 1")
    scene = load_scene(SCENE)
    if quick:
        scene = dataclasses.replace(scene, mesh=dataclasses.replace(scene.mesh, size_contact=0.25))
        repeats = 1
    rows = []
    for repeat in range(repeats):
        start = time.perf_counter()
        result = solve_scene(scene)
        wall = time.perf_counter() - start
        t = result.timings
        rows.append(dict(repeat=repeat, size_contact=scene.mesh.size_contact, dofs=result.mesh_info["dofs"],
                         half_model=result.mesh_info["half_model"], wall=wall, mesh=t["mesh"], assembly=t["assembly"],
                         factorization=t["factorization"], contact_path=t["contact"],
                         compliance_columns=t["compliance_columns"], linear_solve=t["linear_solve"],
                         ratio_contact_to_linear=t["contact"] / t["linear_solve"],
                         newton_iterations=sum(inc.iterations for inc in result.increments)))
    write_csv_atomic(Path(out_dir) / f"{NAME}.csv", rows)
    medians = {key: statistics.median(row[key] for row in rows)
               for key in ("wall", "mesh", "assembly", "factorization", "contact_path", "linear_solve",
                           "ratio_contact_to_linear")}
    medians["peak_memory_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    medians.update(dofs=rows[0]["dofs"], compliance_columns=rows[0]["compliance_columns"], repeats=repeats,
                   target_ratio=TARGET_RATIO, meets_target=medians["ratio_contact_to_linear"] <= TARGET_RATIO)
    write_json_atomic(Path(out_dir) / f"{NAME}.json", medians)
    print(f"{NAME}: HCM-1 h = {scene.mesh.size_contact} mm, {medians['dofs']} DOF: whole path {medians['wall']:.1f} s, "
          f"contact path {medians['contact_path']:.1f} s = {medians['ratio_contact_to_linear']:.1f}x one linear solve "
          f"({medians['linear_solve']:.2f} s; target {TARGET_RATIO:g}x), {medians['compliance_columns']} compliance "
          f"columns, peak memory {medians['peak_memory_mb']:.0f} MB (medians of {repeats})")
    return {}
