"""Run a scene file: press / shear / twist a rigid body on the gel; write result.json, steps.csv (and VTU files).

Usage: ``python -m studies run studies/scenes/hcm1.toml --out results/hcm1 [--vtu] [--quiet]``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studies._output import write_csv_atomic, write_json_atomic

NAME = "run"


def add_arguments(parser) -> None:
    parser.add_argument("scene", type=Path, help="scene TOML file (see studies/scenes/hcm1.toml)")
    parser.add_argument("--vtu", action="store_true", help="also write one VTU file per increment (ParaView)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def result_document(result) -> dict:
    """The result.json content: mesh facts, timings, what was left out, and the per-increment table."""
    timings = {k: v for k, v in result.timings.items()}
    return {
        "scene": result.scene.name,
        "mesh": result.mesh_info,
        "timings": timings,
        "left_out": result.left_out,
        "error": result.error,
        "increments": [_with_bumps(increment.summary(), increment, result) for increment in result.increments],
    }


def _has_bumps(result) -> bool:
    """Per-bump columns are written for scenes with more than one contact (bump arrays under a plate)."""
    return result.bump_centers is not None and len(result.bump_centers) > 1


def _with_bumps(summary: dict, increment, result) -> dict:
    if _has_bumps(result) and increment.bumps is not None:
        summary["bumps"] = increment.bumps.rows()
    return summary


def step_rows(result) -> list[dict]:
    """One flat row per increment for steps.csv (vectors split into _x, _y columns)."""
    rows = []
    for number, increment in enumerate(result.increments, start=1):
        row = {"increment": number}
        for key, value in increment.summary().items():
            if isinstance(value, list):
                row[f"{key}_x"], row[f"{key}_y"] = value
            else:
                row[key] = value
        if _has_bumps(result) and increment.bumps is not None:
            row.update(increment.bumps.flat())
        rows.append(row)
    return rows


def write_vtu(result, out_dir: Path) -> list[Path]:
    """One VTU per increment: displacement [mm], contact state (-1 not a candidate, 0 open, 1 stick, 2 slip),
    contact pressure and tangential traction [MPa] on the top points, nodal values on the mesh vertices; the bump
    of each candidate point (-1 elsewhere) and its bump's normal force [N], stick ratio and margin to gross slip
    painted on it (contact.bumps)."""
    import meshio

    model = result.model
    mesh = model.mesh
    n_vertices = mesh.p.shape[1]
    vertex_dofs = model.basis.nodal_dofs.T                             # (n_vertices, 3)
    top_vertex = model.top.dofs[:, 0]
    dof_to_vertex = np.full(model.n_dofs, -1)
    dof_to_vertex[vertex_dofs[:, 0]] = np.arange(n_vertices)
    candidate_vertex = dof_to_vertex[top_vertex[result.candidates]]
    on_vertex = candidate_vertex >= 0                                  # P2 midpoints are not mesh vertices
    paths = []
    for number, increment in enumerate(result.increments, start=1):
        state = np.full(n_vertices, -1.0)
        pressure = np.zeros(n_vertices)
        traction = np.zeros((n_vertices, 3))
        state[candidate_vertex[on_vertex]] = increment.status[on_vertex]
        pressure[candidate_vertex[on_vertex]] = increment.pressure[on_vertex]
        traction[candidate_vertex[on_vertex], :2] = increment.traction[on_vertex]
        bump_data = {}
        if increment.bumps is not None:
            bump = np.full(n_vertices, -1.0)
            bump[candidate_vertex[on_vertex]] = result.candidate_bump[on_vertex]
            bump_data["bump"] = bump
            for name in ("normal_force", "stick_ratio", "gross_slip_margin"):
                painted = np.zeros(n_vertices)
                painted[candidate_vertex[on_vertex]] = getattr(increment.bumps, name)[result.candidate_bump[on_vertex]]
                bump_data[f"bump_{name}"] = painted
        displacement = increment.displacement_full[vertex_dofs]
        path = Path(out_dir) / f"increment_{number:03d}.vtu"
        meshio.write(path, meshio.Mesh(mesh.p.T, [("tetra", mesh.t.T)],
                                       point_data={"displacement": displacement, "contact_state": state,
                                                   "contact_pressure": pressure, "tangential_traction": traction,
                                                   **bump_data}))
        paths.append(path)
    return paths


def write_outputs(result, out_dir: Path, vtu: bool = False) -> None:
    """Write result.json, steps.csv and (optionally) VTU files; called also for a partial result."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out_dir / "result.json", result_document(result))
    write_csv_atomic(out_dir / "steps.csv", step_rows(result))
    if vtu:
        write_vtu(result, out_dir)


def run(out_dir, quick: bool = False, scene: Path | None = None, vtu: bool = False, quiet: bool = False) -> dict:
    """Solve the scene's load path and write its outputs; a failed increment still leaves the converged ones."""
    import dataclasses

    from contact.scene import load_scene
    from contact.solver import PathNotCompleted, solve_scene

    if scene is None:
        raise ValueError("run needs a scene file: python -m studies run SCENE.toml")
    problem = load_scene(scene)
    if quick:
        problem = dataclasses.replace(problem, mesh=dataclasses.replace(
            problem.mesh, size_contact=max(problem.mesh.size_contact, 0.25)))
    try:
        result = solve_scene(problem, progress=not quiet)
    except PathNotCompleted as error:
        write_outputs(error.result, out_dir, vtu)
        raise
    write_outputs(result, out_dir, vtu)
    if not quiet:
        for row in step_rows(result):
            print(f"  {row['increment']:2d} {row['load_kind']:6s} P={row['normal_force']:.4g} N "
                  f"Q=({row['tangential_force_x']:.4g}, {row['tangential_force_y']:.4g}) N T={row['torque']:.4g} N mm"
                  f" a={row['contact_radius']:.4g} mm c/a={row['stick_ratio']:.4f} p_max={row['max_pressure']:.4g} MPa"
                  f" ({row['iterations']} it, {row['seconds']:.2f} s)")
        t = result.timings
        print(f"  timings: mesh {t['mesh']:.2f} s, assembly {t['assembly']:.2f} s, factorization "
              f"{t['factorization']:.2f} s, contact path {t['contact']:.2f} s "
              f"({t['contact'] / t['linear_solve']:.1f}x one linear solve of {t['linear_solve']:.2f} s)")
    return {}
