"""Run a scene file: press / shear / twist a rigid body on the gel; write result.json, steps.csv (and VTU files).

Usage: ``python -m studies run studies/scenes/hcm1.toml --out results/hcm1 [--vtu] [--quiet]``.

Nothing is lost and nothing stale survives: ``--out`` is checked writable before the solve and held by this run
(a second run into it at the same time is refused, ``fem.run_lock``), the outputs of an earlier run in it are
removed first, and a run that fails (a load the contact cannot carry, a contact too small for
the mesh, Newton not converging, a mesh that fails its check) still writes result.json with ``status = "failed"``,
the error and every increment converged before it (and steps.csv, and the VTU files if asked).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from fem.atomic import remove_stale_temporaries
from studies._output import write_csv_atomic, write_json_atomic

NAME = "run"
OUTPUTS = ("result.json", "steps.csv")          # plus increment_NNN.vtu and increments.pvd with --vtu


def add_arguments(parser) -> None:
    parser.add_argument("scene", type=Path, help="scene TOML file (see studies/scenes/hcm1.toml)")
    parser.add_argument("--vtu", action="store_true", help="also write one VTU file per increment and a .pvd time "
                                                          "series (ParaView)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")


def result_document(result, error: str | None = None) -> dict:
    """The result.json content: status, mesh facts, timings, what was left out, the error, and the per-increment
    table."""
    return {
        "scene": result.scene.name,
        "status": "failed" if (error or result.error) else "ok",
        "mesh": result.mesh_info,
        "timings": dict(result.timings),
        "left_out": result.left_out,
        "error": error or result.error,
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
    """One VTU per increment and the .pvd time series over them (studies._paraview)."""
    from studies._paraview import write_pvd, write_vtu as write_increments

    paths = write_increments(result, out_dir)
    write_pvd(paths, out_dir)
    return paths


def write_outputs(result, out_dir: Path, vtu: bool = False) -> None:
    """Write result.json, steps.csv and (optionally) VTU files; called also for a partial result."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    write_json_atomic(out_dir / "result.json", result_document(result))
    write_csv_atomic(out_dir / "steps.csv", step_rows(result))
    if vtu and result.increments:
        write_vtu(result, out_dir)


def check_writable(out_dir: Path) -> Path:
    """Create ``out_dir`` and check that a file can be written there (before any solve), else PermissionError."""
    out_dir = Path(out_dir)
    check_out_folder(out_dir)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        handle, probe = tempfile.mkstemp(dir=out_dir, prefix=".write-test-", suffix=".tmp")
        os.close(handle)
        os.unlink(probe)
    except OSError as error:
        raise PermissionError(f"--out {str(out_dir)!r} is not writable: {error.strerror or error}") from None
    remove_stale_temporaries(out_dir)              # left by a killed run
    return out_dir


def check_out_folder(out_dir: Path) -> None:
    """Refuse an --out that cannot become a writable folder, leaving nothing behind: a file, a path under a file, a
    place where no folder can be made (NotADirectoryError / PermissionError naming --out). The command line's check
    before any study starts; ``check_writable`` then makes the folder."""
    out_dir = Path(out_dir)
    name, existing, problem = f"--out {str(out_dir)!r}", None, None
    try:
        if out_dir.is_symlink() and not out_dir.exists():
            problem = f"{name} is a link to nothing, not a folder"
        elif out_dir.exists() and not out_dir.is_dir():
            problem = f"{name} is a file, not a folder"
        else:
            existing = out_dir if out_dir.exists() else next(p for p in out_dir.absolute().parents if p.exists())
            if not existing.is_dir():
                problem = f"{name} lies under {str(existing)!r}, a file, not a folder"
            else:
                os.rmdir(tempfile.mkdtemp(dir=existing, prefix=".write-test-"))
    except OSError as error:                        # a folder on the way that cannot be read, or written
        where = f" (no folder can be made in {str(existing)!r})" if existing not in (None, out_dir) else ""
        raise PermissionError(f"{name} is not writable{where}: {error.strerror or error}") from None
    if problem:
        raise NotADirectoryError(problem)


def prepare_out_dir(out_dir: Path) -> Path:
    """``check_writable``, then remove an earlier run's outputs, so that none survives this run."""
    out_dir = check_writable(out_dir)
    for path in [out_dir / name for name in OUTPUTS] + sorted(out_dir.glob("increment_[0-9][0-9][0-9].vtu")) \
            + [out_dir / "increments.pvd"]:
        path.unlink(missing_ok=True)
    return out_dir


def run(out_dir, quick: bool = False, scene: Path | None = None, vtu: bool = False, quiet: bool = False) -> dict:
    """Solve the scene's load path and write its outputs; a failed run still leaves the converged increments."""
    import dataclasses

    from contact.result import ContactUnderResolved, LoadNotCarried, PathNotCompleted
    from contact.scene import load_scene
    from contact.solver import solve_scene

    if scene is None:
        raise ValueError("run needs a scene file: python -m studies run SCENE.toml")
    problem = load_scene(scene)
    if quick:
        problem = dataclasses.replace(problem, mesh=dataclasses.replace(
            problem.mesh, size_contact=max(problem.mesh.size_contact, 0.25)))
    from fem.run_lock import hold_out_dir

    with hold_out_dir(check_writable(out_dir), f"run {problem.name!r}"):      # one run per --out at a time
        out_dir = prepare_out_dir(out_dir)
        try:
            result = solve_scene(problem, progress=not quiet)
        except (PathNotCompleted, LoadNotCarried, ContactUnderResolved) as error:
            write_outputs(error.result, out_dir, vtu)
            raise
        except Exception as error:          # before any increment (mesh, memory, limits): the error on disk too
            write_json_atomic(out_dir / "result.json", {"scene": problem.name, "status": "failed", "mesh": {},
                                                        "timings": {}, "left_out": [],
                                                        "error": f"{type(error).__name__}: {error}",
                                                        "increments": []})
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
