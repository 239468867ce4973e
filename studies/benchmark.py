"""Benchmark: HCM-1 contact path against one linear-elastic solve on the same mesh, side by side in one run.

Reports medians over repeats of: mesh, assembly, factorization, compliance columns, the whole contact path, one
plain linear solve (assembly + factorization + one back-substitution), their ratio (target <= 3) and the peak
memory of the process. Timings are never asserted in tests: the machines are shared and noisy.

``--scaling`` times HCM-1 from 17k to 191k DOF (h = 0.25 ... 0.07 mm) against its limit, the cost of what no contact
solver on this mesh can avoid: mesh + assembly + one factorization + one back-substitution per contact unknown (3 per
point in contact at any converged increment). A back-substitution costs what one compliance column cost in the same
solve (the columns' time over their number: on a shared machine a separate timing lands under another load; it is
kept beside, ``back_substitution_separate``, a 256-column block solved after the path). total / limit <=
SCALING_TARGET at every size is the target (benchmark_scaling.csv / .json).

``--factorizations`` compares instead, on the stability study's nu = 0.4999 half block (h = 0.15 mm; 0.3 mm with
``--quick``), the three ways of factorizing the gel: standard P1 K, the nodal-average condensed K, and the
nodal-average saddle-point system the solver uses (``contact.solver.factorize_stiffness``): nonzeros of the matrix
and of its factor, factorization time and the time of 256 unit right-hand sides (compliance columns at the top
points nearest the contact), in benchmark_factorizations.csv / .json.

``--substeps`` times a 3x3 array's twist path with and without remembered Newton sub-steps
(``studies._benchmark_substeps``). ``--finite-strain`` times a bump's shear and twist paths with the Neo-Hookean gel
against the linear one (``studies._benchmark_finite_strain``).

Threads: every mode states the thread settings (MKL_NUM_THREADS, OMP_NUM_THREADS, OPENBLAS_NUM_THREADS,
NUMBA_NUM_THREADS and the pools' sizes) and, with ``--threads both`` (the default), times the same work with one
thread and with the default threads, side by side (``studies._threads``): the contact path's ratio to one linear
solve depends on them (0.8x with one thread, 3.1-4.1x with the default on two loaded cores).
"""

from __future__ import annotations

import dataclasses
import resource
import statistics
import time
from pathlib import Path

import numpy as np

from studies._output import write_csv_atomic, write_json_atomic

NAME = "benchmark"
SCENE = Path(__file__).parent / "scenes" / "hcm1.toml"
TARGET_RATIO = 3.0
SCALING_SIZES = (0.25, 0.2, 0.14, 0.1, 0.07)     # mm: 17k, 27k, 45k, 93k, 191k DOF (fine zone a/2 deep)
SCALING_TARGET = 1.3
RIGHT_HAND_SIDES = 256       # unit right-hand sides per timed multi-RHS solve (one chunk of the compliance columns)


def add_arguments(parser) -> None:
    parser.add_argument("--repeats", type=int, default=None,
                        help="solves per setting (1 to 1000, default 3, quick 1); medians are reported")
    parser.add_argument("--scaling", action="store_true",
                        help="HCM-1 from 17k to 191k DOF: whole solve against mesh + assembly + factorization + one "
                             "back-substitution per contact unknown")
    parser.add_argument("--factorizations", action="store_true",
                        help="compare the factorizations of standard P1, nodal-average K and its saddle-point "
                             "system on the stability block instead of timing HCM-1")
    parser.add_argument("--substeps", action="store_true",
                        help="a 3x3 array's twist path with and without remembered Newton sub-steps, side by side")
    parser.add_argument("--finite-strain", action="store_true",
                        help="a bump's shear and twist paths with the Neo-Hookean gel against the linear one")
    parser.add_argument("--threads", choices=("both", "1", "default"), default="both",
                        help="time with one thread, the default threads, or both side by side (default)")


def run(out_dir, quick: bool = False, repeats: int | None = None, factorizations: bool = False, scaling: bool = False,
        substeps: bool = False, threads: str = "both", finite_strain: bool = False) -> dict:
    """Time the HCM-1 path; write benchmark.csv (one row per thread setting and repeat) and benchmark.json (the
    thread settings, then the medians per thread setting)."""
    from contact.scene import load_scene
    from contact.solver import solve_scene
    from fem.validation import check_integer
    from studies._threads import describe_threads, limited_threads, thread_modes, thread_settings

    # --quick sets the default; a count given explicitly is kept
    repeats = check_integer("--repeats", (1 if quick else 3) if repeats is None else repeats, 1, 1000)
    modes = thread_modes(threads)
    if scaling:
        return cost_scaling(out_dir, quick, modes)
    if factorizations:
        return compare_factorizations(out_dir, quick, repeats, modes)
    if substeps:
        from studies._benchmark_substeps import compare_substeps

        return compare_substeps(out_dir, quick, repeats, modes)
    if finite_strain:
        from studies._benchmark_finite_strain import compare_finite_strain

        return compare_finite_strain(out_dir, quick, repeats, modes)
    scene = load_scene(SCENE)
    if quick:
        scene = dataclasses.replace(scene, mesh=dataclasses.replace(scene.mesh, size_contact=0.25))
    settings = thread_settings()
    rows = []
    for repeat in range(repeats):
        for label, limit in modes:                     # alternating: both settings see the same machine load
            with limited_threads(limit):
                start = time.perf_counter()
                result = solve_scene(scene, cache_compliance=False)    # every repeat solves its columns
                wall = time.perf_counter() - start
            t = result.timings
            rows.append(dict(threads=label, repeat=repeat, size_contact=scene.mesh.size_contact,
                             dofs=result.mesh_info["dofs"], half_model=result.mesh_info["half_model"], wall=wall,
                             mesh=t["mesh"], assembly=t["assembly"], factorization=t["factorization"],
                             contact_path=t["contact"], compliance_columns=t["compliance_columns"],
                             linear_solve=t["linear_solve"], ratio_contact_to_linear=t["contact"] / t["linear_solve"],
                             newton_iterations=sum(inc.iterations for inc in result.increments)))
    write_csv_atomic(Path(out_dir) / f"{NAME}.csv", rows)
    summary = {"thread_settings": settings, "repeats": repeats, "target_ratio": TARGET_RATIO,
               "dofs": rows[0]["dofs"], "compliance_columns": rows[0]["compliance_columns"], "threads": {}}
    print(f"{NAME}: HCM-1 h = {scene.mesh.size_contact} mm, {rows[0]['dofs']} DOF, medians of {repeats}; threads: "
          f"{describe_threads(settings)}")
    for label, _ in modes:
        mine = [row for row in rows if row["threads"] == label]
        medians = {key: statistics.median(row[key] for row in mine)
                   for key in ("wall", "mesh", "assembly", "factorization", "contact_path", "linear_solve",
                               "ratio_contact_to_linear")}
        medians["meets_target"] = medians["ratio_contact_to_linear"] <= TARGET_RATIO
        summary["threads"][label] = medians
        print(f"  {label:15s}: whole path {medians['wall']:.1f} s, contact path {medians['contact_path']:.1f} s = "
              f"{medians['ratio_contact_to_linear']:.1f}x one linear solve ({medians['linear_solve']:.2f} s; target "
              f"{TARGET_RATIO:g}x)")
    summary["peak_memory_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    write_json_atomic(Path(out_dir) / f"{NAME}.json", summary)
    print(f"  {summary['compliance_columns']} compliance columns, peak memory {summary['peak_memory_mb']:.0f} MB")
    return {}


def _unit_right_hand_sides(model, count: int) -> np.ndarray:
    """(n_free, count) unit loads on the free top-surface dofs nearest the origin (the contact centre)."""
    free_position = np.full(model.n_dofs, -1)
    free_position[model.free_dofs] = np.arange(model.free_dofs.size)
    order = np.argsort(np.linalg.norm(model.top.positions[:, :2], axis=1))
    rows = free_position[model.top.dofs[order]].ravel()
    rows = rows[rows >= 0][:count]
    rhs = np.zeros((model.free_dofs.size, rows.size))
    rhs[rows, np.arange(rows.size)] = 1.0
    return rhs


def compare_factorizations(out_dir, quick: bool = False, repeats: int = 3,
                           modes=(("default threads", None),)) -> dict:
    """Factorize standard P1 K, nodal-average K and its saddle-point system on one mesh; time 256 solves each.

    Writes benchmark_factorizations.csv (one row per system and repeat) and benchmark_factorizations.json (medians
    per system, and the largest difference of the saddle-point compliance columns to the condensed K's relative to
    the largest entry); prints them side by side with the ratios to standard P1.
    """
    from contact import scene_from_dict
    from contact.solver import factorize_stiffness, prepare
    from fem.elasticity import assemble_elastic_model
    from fem.linear_solver import SpdFactorization
    from studies._stability_cases import StabilityCase, build_scene
    from studies._threads import describe_threads, limited_threads, thread_settings

    if repeats < 1:
        raise ValueError(f"repeats={repeats!r} must be >= 1")
    case = StabilityCase("poisson", "nu=0.4999 P1 nodal-average",
                         (("material.nu", 0.4999), ("mesh.volumetric", "nodal_average")))
    document, _ = build_scene(case, quick)
    scene = scene_from_dict(document)
    prepared = prepare(scene)                  # the mesh and the nodal-average model the contact solver would use
    prepared.factorization.release()
    nodal = prepared.model
    standard = assemble_elastic_model(nodal.mesh, scene.material.E, scene.material.nu, symmetry_plane_y=0.0
                                      if prepared.half else None, volumetric="standard")
    blocks = nodal.saddle_point
    saddle_nonzeros = blocks.shear_stiffness.nnz + 2 * blocks.pairing.nnz + blocks.pressure_compliance.size
    systems = {"P1 standard": (lambda: SpdFactorization(standard.stiffness_free), standard.stiffness_free.nnz),
               "nodal-average condensed K": (lambda: SpdFactorization(nodal.stiffness_free),
                                             nodal.stiffness_free.nnz),
               "nodal-average saddle point": (lambda: factorize_stiffness(nodal), saddle_nonzeros)}
    rhs = _unit_right_hand_sides(nodal, RIGHT_HAND_SIDES)
    reference = {}
    rows = []
    for repeat in range(repeats):
        for label, limit in modes:
            for name, (factorize, matrix_nonzeros) in systems.items():
                with limited_threads(limit):
                    start = time.perf_counter()
                    factorization = factorize()
                    factorization_time = time.perf_counter() - start
                    start = time.perf_counter()
                    solution = factorization.solve(rhs)
                    solve_time = time.perf_counter() - start
                backend, factor_nonzeros = factorization.backend, factorization.factor_nonzeros
                factorization.release()
                if name.startswith("nodal-average"):
                    reference.setdefault(name, solution)
                rows.append(dict(threads=label, system=name, repeat=repeat, free_dofs=factorization.size,
                                 backend=backend, matrix_nonzeros=matrix_nonzeros, factor_nonzeros=factor_nonzeros,
                                 factorization=factorization_time, solve=solve_time, right_hand_sides=rhs.shape[1]))
    write_csv_atomic(Path(out_dir) / f"{NAME}_factorizations.csv", rows)
    condensed = reference["nodal-average condensed K"]
    difference = float(np.abs(reference["nodal-average saddle point"] - condensed).max() / np.abs(condensed).max())
    settings = thread_settings()
    summary = {"size_contact": scene.mesh.size_contact, "nu": scene.material.nu, "repeats": repeats,
               "right_hand_sides": int(rhs.shape[1]), "saddle_point_vs_condensed_max_difference": difference,
               "thread_settings": settings, "threads": {}}
    for label, _ in modes:
        table = summary["threads"][label] = {}
        for name in systems:
            mine = [row for row in rows if row["system"] == name and row["threads"] == label]
            table[name] = {key: statistics.median(row[key] for row in mine) for key in ("factorization", "solve")}
            table[name].update({key: mine[0][key] for key in ("free_dofs", "backend", "matrix_nonzeros",
                                                               "factor_nonzeros")})
    print(f"{NAME}: factorizations, nu = {scene.material.nu} half block, h = {scene.mesh.size_contact} mm, "
          f"{rows[0]['free_dofs']} free DOF, medians of {repeats}, {rhs.shape[1]} right-hand sides; threads: "
          f"{describe_threads(settings)}")
    print(f"  {'threads':16s} {'system':28s} {'nnz(A)':>10s} {'nnz(factor)':>12s} {'factorize':>10s} {'solve':>8s}"
          f"  vs P1")
    for label, _ in modes:
        base = summary["threads"][label]["P1 standard"]
        for name in systems:
            row = summary["threads"][label][name]
            factor = f"{row['factor_nonzeros'] / 1e6:.2f}M" if row["factor_nonzeros"] else "-"
            print(f"  {label:16s} {name:28s} {row['matrix_nonzeros'] / 1e6:9.2f}M {factor:>12s} "
                  f"{row['factorization']:9.2f}s {row['solve']:7.2f}s  "
                  f"{row['factorization'] / base['factorization']:.1f}x, {row['solve'] / base['solve']:.1f}x")
    print(f"  saddle point vs condensed K: largest difference {difference:.1e} of the largest compliance entry")
    write_json_atomic(Path(out_dir) / f"{NAME}_factorizations.json", summary)
    return summary


def cost_scaling(out_dir, quick: bool = False, modes=(("default threads", None),)) -> dict:
    """HCM-1 at SCALING_SIZES, each solved once with a cold compliance (no disk cache): total wall time against the
    limit (module docstring), with the overheads split: columns beyond the contact unknowns, dense Newton systems,
    the rest (post-processing, Python). Writes benchmark_scaling.csv / .json."""
    from tqdm import tqdm

    from contact._newton import OPEN
    from contact.scene import load_scene
    from contact.solver import prepare, solve_scene
    from studies._threads import describe_threads, limited_threads, thread_settings

    scene = load_scene(SCENE)
    rows = []
    sizes = [(size, label, limit) for size in ((0.3, 0.25) if quick else SCALING_SIZES) for label, limit in modes]
    for size, label, limit in tqdm(sizes, desc=f"{NAME} scaling", unit="solve"):
        case = dataclasses.replace(scene, mesh=dataclasses.replace(scene.mesh, size_contact=size))
        with limited_threads(limit):
            start = time.perf_counter()
            prepared = prepare(case)
            result = solve_scene(case, prepared, cache_compliance=False)
            total = time.perf_counter() - start
        touched = np.zeros(result.candidates.size, dtype=bool)
        for increment in result.increments:
            touched |= increment.status != OPEN
        unknowns = 3 * int(touched.sum())
        rhs = np.asfortranarray(_unit_right_hand_sides(prepared.model, RIGHT_HAND_SIDES))
        with limited_threads(limit):
            solve_start = time.perf_counter()
            prepared.factorization.solve(rhs)
            separate = (time.perf_counter() - solve_start) / rhs.shape[1]
        prepared.factorization.release()
        t = result.timings
        per_column = t["compliance_seconds"] / t["compliance_columns"]
        bound = t["mesh"] + t["assembly"] + t["factorization"] + unknowns * per_column
        rows.append(dict(threads=label, size_contact=size, dofs=result.mesh_info["dofs"], total=total,
                         limit=bound, ratio=total / bound, mesh=t["mesh"], assembly=t["assembly"],
                         factorization=t["factorization"], contact_unknowns=unknowns,
                         back_substitution_per_column=per_column, back_substitution_separate=separate,
                         columns_computed=t["compliance_columns"],
                         column_seconds=t["compliance_seconds"], newton_linear_seconds=t["newton_linear_seconds"],
                         newton_factorizations=t["newton_factorizations"],
                         newton_krylov_iterations=t["newton_krylov_iterations"],
                         newton_iterations=sum(inc.iterations for inc in result.increments),
                         other_seconds=total - bound - (t["compliance_seconds"] - unknowns * per_column)
                         - t["newton_linear_seconds"]))
        write_csv_atomic(Path(out_dir) / f"{NAME}_scaling.csv", rows)
    worst = max(row["ratio"] for row in rows)
    settings = thread_settings()
    summary = {"rows": rows, "target": SCALING_TARGET, "worst_ratio": worst, "meets_target": worst <= SCALING_TARGET,
               "thread_settings": settings}
    write_json_atomic(Path(out_dir) / f"{NAME}_scaling.json", summary)
    print(f"{NAME}: HCM-1 total / limit (mesh + assembly + factorization + one back-substitution per contact unknown), "
          f"target <= {SCALING_TARGET}; threads: {describe_threads(settings)}")
    print(f"  {'threads':16s} {'h [mm]':>7s} {'DOF':>8s} {'total':>8s} {'limit':>8s} {'ratio':>6s} {'columns':>8s} "
          f"{'unknowns':>8s} {'newton':>8s} {'LU':>4s}")
    for row in rows:
        print(f"  {row['threads']:16s} {row['size_contact']:7.3f} {row['dofs']:8d} {row['total']:7.1f}s "
              f"{row['limit']:7.1f}s "
              f"{row['ratio']:6.2f} {row['columns_computed']:8d} {row['contact_unknowns']:8d} "
              f"{row['newton_linear_seconds']:7.1f}s {row['newton_factorizations']:4d}")
    return {"max_error": None, "worst_ratio": worst}
