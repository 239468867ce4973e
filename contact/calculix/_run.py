"""Running CalculiX (``ccx``): find the program, run a deck in its own folder, keep the outputs on disk by the
deck's hash (a second run of the same deck and version reads them back), fail with the log's last lines."""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import time
from pathlib import Path

__all__ = ["CalculixUnavailable", "CalculixFailed", "ccx_executable", "ccx_version", "run_deck", "INSTALL_HINT"]

CCX_ENV_VAR = "FINGERTIP_CCX"       # path of a ccx executable other than the one on PATH
INSTALL_HINT = ("install CalculiX from the package registry (Debian/Ubuntu: apt-get install calculix-ccx; conda: "
                "conda install -c conda-forge calculix) or set FINGERTIP_CCX to a ccx executable")


class CalculixUnavailable(OSError):
    """No CalculiX executable: the finite-strain reference cannot run here."""


class CalculixFailed(RuntimeError):
    """CalculiX ran but did not finish the deck (no convergence, an input error); the message quotes its log."""


def ccx_executable() -> str | None:
    """Path of the ccx executable (FINGERTIP_CCX, else ``ccx`` on PATH), None if there is none."""
    explicit = os.environ.get(CCX_ENV_VAR)
    if explicit:
        return explicit if Path(explicit).is_file() and os.access(explicit, os.X_OK) else None
    return shutil.which("ccx")


def ccx_version() -> str:
    """The version line CalculiX prints (e.g. 'Version 2.20'); CalculixUnavailable without ccx."""
    executable = ccx_executable()
    if executable is None:
        raise CalculixUnavailable(f"CalculiX (ccx) was not found: {INSTALL_HINT}")
    completed = subprocess.run([executable, "-v"], capture_output=True, text=True, timeout=60)
    lines = [line.strip() for line in (completed.stdout + completed.stderr).splitlines() if "Version" in line]
    return lines[0] if lines else "unknown version"


def _cache_root() -> Path:
    from fem.mesh_cache import default_cache_dir

    return default_cache_dir() / "calculix"


def run_deck(deck: str, job: str = "job", timeout: float = 3600.0, cache: bool = True) -> Path:
    """Run ``deck`` (the text of job.inp) with ccx on one thread; the folder holding job.dat and job.frd.

    The folder is ``<FINGERTIP_CACHE>/calculix/<sha256 of the deck and the ccx version>``; when it already holds a
    finished run (``done`` marker) nothing is run, and a run that failed (``failed``) fails again at once. Raises
    CalculixUnavailable without ccx, CalculixFailed when ccx
    stops early (exit code, no 'Job finished', or a timeout of ``timeout`` s).
    """
    executable = ccx_executable()
    if executable is None:
        raise CalculixUnavailable(f"CalculiX (ccx) was not found: {INSTALL_HINT}")
    digest = hashlib.sha256((ccx_version() + "\0" + deck).encode()).hexdigest()[:24]
    folder = _cache_root() / digest
    done, failed = folder / "done", folder / "failed"
    if cache and done.is_file():
        return folder
    if cache and failed.is_file():                 # the same deck and version stop the same way: not again
        raise CalculixFailed(failed.read_text())
    folder.mkdir(parents=True, exist_ok=True)
    (folder / f"{job}.inp").write_text(deck)
    environment = dict(os.environ, OMP_NUM_THREADS="1", CCX_NPROC_STIFFNESS="1", CCX_NPROC_EQUATION_SOLVER="1")
    start = time.perf_counter()
    try:
        completed = subprocess.run([executable, "-i", job], cwd=folder, capture_output=True, text=True,
                                   timeout=timeout, env=environment)
    except subprocess.TimeoutExpired:
        raise CalculixFailed(f"ccx did not finish {folder / job}.inp within {timeout:.0f} s") from None
    (folder / f"{job}.log").write_text(completed.stdout + completed.stderr)
    if completed.returncode != 0 or "Job finished" not in completed.stdout:
        tail = "\n".join((completed.stdout + completed.stderr).strip().splitlines()[-12:])
        message = f"ccx stopped on {folder / job}.inp (exit code {completed.returncode}):\n{tail}"
        failed.write_text(message)
        raise CalculixFailed(message)
    done.write_text(f"{time.perf_counter() - start:.3f}\n")
    return folder


def run_seconds(folder: Path) -> float:
    """Wall time [s] the run in ``folder`` took when it was computed."""
    return float((Path(folder) / "done").read_text())
