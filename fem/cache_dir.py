"""The disk cache's folder (FINGERTIP_CACHE), whether it can be written, and the report of a damaged entry.

Every cache of the toolkit (meshes, compliance columns, compiled kernels) lives under one folder. A folder that cannot
hold the cache (read-only, a file, a path through a file) is reported once, by a ``CacheWarning`` naming the
variable, and the run goes on without a disk cache: nothing computed is wrong, only made again. A cache entry that
cannot be read back whole is reported once with its path, deleted, and made again by the caller.
"""

from __future__ import annotations

import os
import tempfile
import warnings
from pathlib import Path

__all__ = ["CACHE_ENV_VAR", "CacheWarning", "default_cache_dir", "usable_cache_dir", "writable_folder",
           "discard_damaged"]

CACHE_ENV_VAR = "FINGERTIP_CACHE"

_checked: dict[str, str | None] = {}      # folder -> None (usable) or why not; each folder is probed once
_reported: set[str] = set()               # damaged entries already reported


class CacheWarning(UserWarning):
    """The disk cache cannot be used, or one of its entries was damaged and is made again."""


def default_cache_dir() -> Path:
    """Folder from the environment variable FINGERTIP_CACHE, else ~/.cache/fingertip-contact."""
    configured = os.environ.get(CACHE_ENV_VAR)
    return Path(configured).expanduser() if configured else Path.home() / ".cache" / "fingertip-contact"


def _problem(folder: Path) -> str | None:
    """Why ``folder`` cannot hold cache files (created if missing), or None when a file can be written there."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
        handle, probe = tempfile.mkstemp(dir=folder, prefix=".probe-", suffix=".tmp")
        os.close(handle)
        os.unlink(probe)
    except OSError as error:
        return error.strerror or type(error).__name__
    return None


def writable_folder(folder: Path, what: str = "cache folder") -> bool:
    """True when files can be written in ``folder`` (probed once per folder and process); else one CacheWarning
    naming the folder (and FINGERTIP_CACHE when the folder comes from it) and False."""
    folder = Path(folder)
    root = default_cache_dir()
    if root in folder.parents and not writable_folder(root, what):
        return False                                   # one warning for the whole cache, not one per subfolder
    name = str(folder)
    if name not in _checked:
        _checked[name] = _problem(folder)
        if _checked[name] is not None:
            source = (f"{CACHE_ENV_VAR}={os.environ[CACHE_ENV_VAR]!r}" if CACHE_ENV_VAR in os.environ
                      else f"the default {CACHE_ENV_VAR} folder {str(root)!r}")
            inside = folder == root or root in folder.parents
            where = source if inside else f"{what} {name!r}"
            warnings.warn(f"{where} cannot hold the disk cache ({_checked[name]} at {name!r}): running without it, "
                          f"so meshes, compliance columns and compiled kernels are made again on every run; set "
                          f"{CACHE_ENV_VAR} to a writable folder", CacheWarning, stacklevel=3)
    return _checked[name] is None


def usable_cache_dir(subfolder: str = "") -> Path | None:
    """``default_cache_dir() / subfolder`` when it can be written, else None (after one CacheWarning)."""
    folder = default_cache_dir() / subfolder if subfolder else default_cache_dir()
    return folder if writable_folder(folder) else None


def discard_damaged(path: Path, reason: str) -> None:
    """Report a damaged cache entry once (CacheWarning with its path and what is wrong) and delete it, so that the
    caller makes it again; a file that cannot be deleted is left (the caller does not read it again this run)."""
    path = Path(path)
    if str(path) not in _reported:
        _reported.add(str(path))
        warnings.warn(f"damaged cache entry {str(path)!r} ({reason}): discarded, it is made again", CacheWarning,
                      stacklevel=3)
    try:
        path.unlink(missing_ok=True)
    except OSError:
        pass
