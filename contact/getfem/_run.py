"""Running GetFEM on a bump scene: find an interpreter that imports getfem, write the job (the project's own tet mesh
of the scene, the gel, the loads), run ``_script.py`` in that interpreter, keep the outputs on disk by the job's
hash, and read them back as the CalculiX reference's records (``contact.calculix.BumpRecord``)."""

from __future__ import annotations

import functools
import hashlib
import os
import shutil
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["GetfemUnavailable", "GetfemFailed", "GetfemJob", "getfem_python", "getfem_version", "bump_job",
           "run_job", "INSTALL_HINT"]

PYTHON_ENV_VAR = "FINGERTIP_GETFEM_PYTHON"     # an interpreter with getfem other than the ones tried by default
INSTALL_HINT = ("install GetFEM's Python interface from the package registry (Debian/Ubuntu: apt-get install "
                "python3-getfem; it runs in the system's python3) or set FINGERTIP_GETFEM_PYTHON to an interpreter "
                "that imports getfem")
SCRIPT = Path(__file__).with_name("_script.py")
PRESS_STEPS = 8             # equal depth increments of the frictionless press before the hold


class GetfemUnavailable(OSError):
    """No interpreter imports getfem: the independent finite-strain shear and twist cannot run here."""


class GetfemFailed(RuntimeError):
    """GetFEM ran but did not finish the job; the message quotes its output."""


@functools.lru_cache(maxsize=None)
def _imports_getfem(python: str) -> str | None:
    """GetFEM's release if ``python`` imports getfem, else None."""
    try:
        completed = subprocess.run([python, "-I", "-c", "import getfem; print(getfem.getfem_env('release'))"],
                                   capture_output=True, text=True, timeout=120)
    except (OSError, subprocess.TimeoutExpired):
        return None
    if completed.returncode != 0:
        return None
    return completed.stdout.strip() or None


def getfem_python() -> str | None:
    """An interpreter that imports getfem: FINGERTIP_GETFEM_PYTHON, else the system's python3 (Debian's package
    installs there, for its own numpy), else this interpreter; None if none does."""
    explicit = os.environ.get(PYTHON_ENV_VAR)
    if explicit:
        return explicit if _imports_getfem(explicit) else None
    for python in ("/usr/bin/python3", shutil.which("python3"), sys.executable):
        if python and _imports_getfem(python):
            return python
    return None


def getfem_version() -> str:
    """'GetFEM <release>'; GetfemUnavailable without it."""
    python = getfem_python()
    if python is None:
        raise GetfemUnavailable(f"GetFEM was not found: {INSTALL_HINT}")
    return f"GetFEM {_imports_getfem(python)}"


def _job(scene) -> dict:
    """The arrays ``_script.py`` reads: the scene's own tet mesh (meshed as the project's solver meshes it), the gel,
    the held depth and the shear shifts or twist angles."""
    from contact.scene import LoadControl, LoadKind
    from contact.solver import gel_mesh

    if scene.gel.shape != "array" or scene.body.shape != "plane":
        raise ValueError(f"scene {scene.name!r}: GetFEM runs a bump under a plate (gel.shape='array', "
                         f"body.shape='plane'), not {scene.gel.shape!r} under {scene.body.shape!r}")
    bumps = (scene.gel.geometry.rows, scene.gel.geometry.cols)
    if bumps != (1, 1):
        raise ValueError(f"scene {scene.name!r}: gel rows, cols = {bumps}; GetFEM runs one bump (1, 1)")
    if not scene.contact.frictionless_press:
        raise ValueError(f"scene {scene.name!r}: contact.frictionless_press=False; GetFEM presses frictionless")
    if scene.mesh.order != 1 or scene.mesh.volumetric != "standard":
        raise ValueError(f"scene {scene.name!r}: mesh.order={scene.mesh.order}, mesh.volumetric="
                         f"{str(scene.mesh.volumetric)!r}; GetFEM solves standard P1 (order 1, 'standard')")
    depth = [load for load in scene.loads if load.kind == LoadKind.PRESS and load.control == LoadControl.DISPLACEMENT]
    path = [load for load in scene.loads if load.kind in (LoadKind.SHEAR, LoadKind.TWIST)]
    if not depth or len(path) != 1 or path[0].control != LoadControl.DISPLACEMENT:
        raise ValueError(f"scene {scene.name!r}: GetFEM runs a press to a held depth, then one shift or angle path")
    if path[0].kind == LoadKind.SHEAR and tuple(path[0].direction) != (1.0, 0.0):
        raise ValueError(f"scene {scene.name!r}: shear direction={tuple(path[0].direction)}; GetFEM shifts along "
                         f"+x, (1.0, 0.0)")
    mesh, half = gel_mesh(scene)           # the FEM's mesh; its stiffness is not needed here
    if half:
        raise ValueError(f"scene {scene.name!r}: meshed as a half model; GetFEM runs the whole body")
    points, tets = mesh.p.T, mesh.t.T
    base_thickness = scene.gel.geometry.base_thickness
    return dict(points=points, tets=tets, base_z=points[:, 2].min(), apex_z=points[:, 2].max(),
                cap_floor=points[:, 2].min() + base_thickness + 1e-6, centre=np.asarray(scene.body.center, float),
                youngs_modulus=scene.material.E, poissons_ratio=scene.material.nu, law=str(scene.material.law),
                size=scene.mesh.size_contact, friction_coefficient=scene.contact.friction_coefficient,
                depth=depth[-1].values[-1], press_steps=PRESS_STEPS, path=path[0].kind.value,
                values=np.asarray(path[0].values, float))


def _cache_root() -> Path:
    from fem.mesh_cache import default_cache_dir

    return default_cache_dir() / "getfem"


def run_job(job: dict, timeout: float = 7200.0) -> tuple[Path, float]:
    """Run ``job`` with GetFEM; the outputs' path and the run's wall time [s] (as measured when computed). The
    folder is ``<FINGERTIP_CACHE>/getfem/<sha256 of the job, the script and GetFEM's release>``."""
    from fem.atomic import write_text_atomic

    python = getfem_python()
    if python is None:
        raise GetfemUnavailable(f"GetFEM was not found: {INSTALL_HINT}")
    digest = hashlib.sha256(getfem_version().encode() + SCRIPT.read_bytes())
    for name in sorted(job):
        digest.update(name.encode() + np.ascontiguousarray(job[name]).tobytes())
    folder = _cache_root() / digest.hexdigest()[:24]
    out, done, failed = folder / "out.npz", folder / "done", folder / "failed"
    if done.is_file() and out.is_file():
        return out, float(done.read_text())
    if failed.is_file():                         # the same job and release fail the same way: not again
        raise GetfemFailed(failed.read_text())
    folder.mkdir(parents=True, exist_ok=True)
    np.savez(folder / "job.npz", **job)
    target = folder / f"out.{os.getpid()}.partial.npz"          # renamed to out.npz when whole
    start = time.perf_counter()
    try:
        completed = subprocess.run([python, "-I", str(SCRIPT), str(folder / "job.npz"), str(target)],
                                   capture_output=True, text=True, timeout=timeout,
                                   env=dict(os.environ, OMP_NUM_THREADS="1"))
    except subprocess.TimeoutExpired:
        target.unlink(missing_ok=True)          # what a stopped run wrote is never read: each run writes its own
        raise GetfemFailed(f"GetFEM did not finish {folder / 'job.npz'} within {timeout:.0f} s") from None
    if completed.returncode != 0 or not target.is_file():
        target.unlink(missing_ok=True)
        tail = "\n".join((completed.stdout + completed.stderr).strip().splitlines()[-8:])
        message = f"GetFEM stopped on {folder / 'job.npz'} (exit code {completed.returncode}):\n{tail}"
        if completed.returncode > 0:            # the script's own error repeats; a signal (interrupt, OOM) may not
            write_text_atomic(failed, message)
        raise GetfemFailed(message)
    os.replace(target, out)
    seconds = time.perf_counter() - start
    write_text_atomic(done, f"{seconds:.3f}\n")
    return out, seconds


@dataclass(frozen=True)
class GetfemJob:
    """A bump scene written out for GetFEM: ``run()`` gives its records (``contact.calculix.BumpRecord`` s of the
    press, in equal depth steps and frictionless, then of the shear or twist), the run's wall time [s] and why the
    path stopped early ('' when it did not; its converged increments are kept). Build jobs in one thread (gmsh
    meshes the scene), run them in several (each is a process of its own)."""

    arrays: dict
    friction_coefficient: float
    name: str

    def run(self, timeout: float = 7200.0) -> tuple[list, float, str]:
        out, seconds = run_job(self.arrays, timeout)
        with np.load(out) as found:
            stopped = str(found["stopped"])
            if not (found["kinds"] == 1).any():              # no held state to compare from
                raise GetfemFailed(f"GetFEM's {self.name} stopped before its path: {stopped}")
            return _records(self.arrays, found, self.friction_coefficient), seconds, stopped


def bump_job(scene) -> GetfemJob:
    """The bump scene (a 1 x 1 array under a plate, pressed to a held depth, then one shift or angle path) as a
    GetFEM job on the project's own tet mesh of it, with the scene's gel law (``material.law``)."""
    return GetfemJob(_job(scene), scene.contact.friction_coefficient, scene.name)


def _records(job: dict, found, friction_coefficient: float) -> list:
    """The increments' whole-body values from GetFEM's nodal fields."""
    from contact.calculix import SLIP_TOLERANCE, BumpRecord, contact_state
    from contact.recovery import tributary_areas

    points, contact, base = job["points"], found["contact_points"], found["base_points"]
    local = np.full(points.shape[0], -1)
    local[contact] = np.arange(contact.size)
    triangles = local[found["triangles"]]
    base_xy = points[base, :2] - job["centre"]
    records = []
    for load, kind, u, contact_force, force, slip in zip(found["loads"], found["kinds"], found["u"],
                                                         found["contact_force"], found["base_force"],
                                                         found["contact_slip"]):
        current = points[contact] + u[contact]
        # a point sticks where its neighbourhood's weighted slip against the plate in the increment is below the
        # CalculiX reference's tolerance (the friction law's own measure, see _script.py)
        stuck = (np.linalg.norm(slip, axis=1) <= SLIP_TOLERANCE) if kind == 1 else np.ones(contact.size, bool)
        # stresses whose products with contact_state's tributary areas are the nodal forces; a point presses where
        # its force is above the round-off (~1e-19 N) of the mass-matrix product that is zero off the contact
        areas = tributary_areas(current[:, :2], triangles)
        pressing = -contact_force[:, 2] > 1e-9 * np.abs(contact_force[:, 2]).max()
        pressure = np.where(pressing, -contact_force[:, 2] / areas, 0.0)
        radius, stick, nodal = contact_state(current[:, :2], triangles, pressure, contact_force[:, :2] / areas[:, None],
                                             stuck, friction_coefficient)
        arm = base_xy + u[base, :2]                              # the base only rises
        records.append(BumpRecord(
            load_kind="press" if kind == 0 else job["path"], normal_force=float(force[:, 2].sum()),
            tangential_force=float(-force[:, 0].sum()),
            torque=float(-(arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0]).sum()), depth=float(load[0]),
            shift=float(load[1]), angle=float(load[2]), contact_radius=radius, stick_ratio=stick,
            stick_ratio_nodal=nodal, base_cop_x=float((base_xy[:, 0] * force[:, 2]).sum() / force[:, 2].sum()),
            base_xy=base_xy, base_force=force[:, 2]))
    return records

