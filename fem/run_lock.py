"""One run per output folder: a lock file holding the owner's host and pid, refused while that run is alive.

Two sweeps into one ``--out`` at once both solved every case (each saw the other's cases as pending), and their
tables overwrote each other. ``hold_out_dir`` creates ``<out>/.run.lock`` atomically (``O_EXCL``); a second run finds
it and stops with a message naming the owner. A lock left by a killed run of this machine (its pid gone) is taken
over; one of another machine cannot be checked, so the message names the file to delete once that run is known to
be gone. The same process may enter the folder again (the command holds it while ``design_sweep`` runs inside).
"""

from __future__ import annotations

import contextlib
import json
import os
import time
from pathlib import Path
from typing import Iterator

from fem.atomic import _alive, _host

__all__ = ["LOCK_NAME", "OutDirBusy", "hold_out_dir"]

LOCK_NAME = ".run.lock"
_held: dict[str, int] = {}          # lock path -> nesting depth in this process


class OutDirBusy(ValueError):
    """Another live run writes into the same output folder."""


def _owner(lock: Path) -> dict | None:
    """The lock's content ({host, pid, started, command}); None when unreadable or of another shape."""
    try:
        owner = json.loads(lock.read_text())
    except (OSError, ValueError):
        return None
    return owner if isinstance(owner, dict) and isinstance(owner.get("pid"), int) else None


def _take(lock: Path, what: str) -> bool:
    """Create the lock file with this process as owner; False if it exists."""
    try:
        handle = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        return False
    with os.fdopen(handle, "w") as stream:
        json.dump({"host": _host(), "pid": os.getpid(), "started": time.strftime("%Y-%m-%d %H:%M:%S"),
                   "command": what}, stream)
    return True


@contextlib.contextmanager
def hold_out_dir(out_dir, what: str = "run") -> Iterator[Path]:
    """Hold ``out_dir`` for this run (created if missing); raise OutDirBusy naming the owner if another live run
    holds it. ``what`` names this run in the lock (e.g. "sweep stick-ratio")."""
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    lock = out_dir / LOCK_NAME
    key = str(lock.resolve())
    if _held.get(key):
        _held[key] += 1
        try:
            yield out_dir
        finally:
            _held[key] -= 1
        return
    for _ in range(3):                                   # a stale lock is removed, then taken; a race may repeat
        if _take(lock, what):
            break
        owner = _owner(lock)
        stale = owner is not None and owner.get("host") == _host() and not _alive(owner["pid"])
        if owner is None:                                # being written this instant, or damaged: look again once
            time.sleep(0.2)
            owner = _owner(lock)
            stale = owner is None or (owner.get("host") == _host() and not _alive(owner["pid"]))
        if not stale:
            raise OutDirBusy(f"--out {str(out_dir)!r} is in use by another run ({owner.get('command', 'a run')}, pid "
                             f"{owner['pid']} on {owner.get('host')}, since {owner.get('started')}): wait for it to "
                             f"finish or choose another --out; if that run is gone, delete {str(lock)!r}")
        lock.unlink(missing_ok=True)                     # its owner was killed: take it over
    else:
        raise OutDirBusy(f"--out {str(out_dir)!r}: could not take the lock {str(lock)!r} (other runs keep taking it)")
    _held[key] = 1
    try:
        yield out_dir
    finally:
        _held.pop(key, None)
        if (_owner(lock) or {}).get("pid") == os.getpid():
            lock.unlink(missing_ok=True)
