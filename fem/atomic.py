"""Atomic file writes: a temporary file in the target's folder, then a rename, so a crash never leaves half a file."""

from __future__ import annotations

import contextlib
import os
import socket
import tempfile
import time
from pathlib import Path
from typing import Iterator

__all__ = ["atomic_path", "write_text_atomic", "remove_stale_temporaries"]

STALE_SECONDS = 24 * 3600.0     # a temporary file of another machine this old is debris of a killed run


@contextlib.contextmanager
def atomic_path(path) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; the caller writes it, and on success it replaces ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{_owner()}.", suffix=".tmp")
    os.close(handle)
    try:
        yield Path(temporary)
        os.chmod(temporary, 0o644)                 # mkstemp makes 0600; outputs and caches are meant to be shared
        os.replace(temporary, path)
    except BaseException:
        Path(temporary).unlink(missing_ok=True)
        raise


def _host() -> str:
    return socket.gethostname().replace(".", "_")


def _owner() -> str:
    return f"{_host()}-{os.getpid()}"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:                        # someone else's live process
        return True
    return True


def remove_stale_temporaries(folder) -> list[Path]:
    """Delete the temporary files that killed runs left in ``folder`` (``kill -9`` skips the clean-up): those of
    this machine whose process is gone, and any older than STALE_SECONDS. Returns the deleted paths."""
    host = _host()
    removed = []
    for path in Path(folder).glob(".*.tmp"):
        owner = path.name.rsplit(".", 3)[-3] if path.name.count(".") >= 3 else ""
        name, _, pid = owner.rpartition("-")
        try:
            dead = (name == host and pid.isdigit() and not _alive(int(pid))) \
                or time.time() - path.stat().st_mtime > STALE_SECONDS
            if dead:
                path.unlink()
                removed.append(path)
        except OSError:
            continue                               # gone meanwhile, or not ours to delete
    return removed


def write_text_atomic(path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (newlines as given); return the path."""
    with atomic_path(path) as temporary:
        temporary.write_text(text, newline="")
    return Path(path)
