"""On-disk cache of tetrahedral meshes (npz of nodes p and tets t), keyed by a hash of everything that made them.

A sweep must never re-mesh the same geometry (docs/design.md, sec. 11): the key hashes the geometry, the mesh parameters
and the mesher versions, and files are written atomically (temporary file in the same folder, then ``os.replace``),
so an interrupted run leaves either the old file or the new one, never half of one. A file that does not read back
whole (the zip's CRC, the arrays' shapes and ranges) is reported once with its path and made again
(``fem.cache_dir``); a folder that cannot be written leaves the run without a mesh cache, after one warning.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import numpy as np

from fem.atomic import atomic_path
from fem.cache_dir import CACHE_ENV_VAR, default_cache_dir, discard_damaged, writable_folder

__all__ = ["CACHE_ENV_VAR", "MeshCache", "cache_key", "default_cache_dir"]


def cache_key(payload: dict) -> str:
    """SHA-256 (hex, 64 chars) of ``payload`` as canonical JSON (sorted keys; floats by repr, so exact)."""
    text = json.dumps(payload, sort_keys=True, separators=(",", ":"), default=repr)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


class MeshCache:
    """Meshes stored as ``<directory>/mesh-<key>.npz`` holding ``p`` (3, n_nodes), ``t`` (4, n_tets) and a JSON
    ``metadata`` string (the inputs and the quality report, for a human looking at the folder)."""

    def __init__(self, directory: str | os.PathLike | None = None):
        self.directory = Path(directory) if directory is not None else default_cache_dir()

    def path(self, key: str) -> Path:
        return self.directory / f"mesh-{key}.npz"

    def load(self, key: str) -> tuple[np.ndarray, np.ndarray] | None:
        """(p, t) stored under ``key``, or None if absent. A file that cannot be read back whole (truncated, a bad
        CRC, not an npz, wrong arrays, tets pointing past the nodes, non-finite nodes) is reported and deleted
        (``fem.cache_dir.discard_damaged``), so that it is made again."""
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                nodes, tets = np.array(data["p"], dtype=float), np.array(data["t"], dtype=np.int64)
            valid = (nodes.ndim == 2 and nodes.shape[0] == 3 and tets.ndim == 2 and tets.shape[0] == 4
                     and tets.size > 0 and np.isfinite(nodes).all() and tets.min() >= 0
                     and tets.max() < nodes.shape[1])
            reason = "arrays of the wrong shape, tets past the nodes or non-finite nodes"
        except Exception as error:             # zipfile.BadZipFile, EOFError, OSError, KeyError, ValueError, ...
            valid, reason = False, f"{type(error).__name__}: {error}"
        if not valid:
            discard_damaged(path, reason)      # heal: the next save replaces it
            return None
        return nodes, tets

    def metadata(self, key: str) -> dict:
        """The metadata stored with ``key`` (empty dict if absent or unreadable)."""
        path = self.path(key)
        try:
            with np.load(path, allow_pickle=False) as data:
                return json.loads(str(data["metadata"])) if "metadata" in data else {}
        except Exception:
            return {}

    def save(self, key: str, nodes: np.ndarray, tets: np.ndarray, metadata: dict | None = None) -> Path | None:
        """Write (p, t) under ``key`` atomically; returns the file path, or None when the folder cannot be written
        (``fem.cache_dir.writable_folder`` warned once)."""
        if not writable_folder(self.directory):
            return None
        with atomic_path(self.path(key)) as temporary, open(temporary, "wb") as stream:    # a stream: np.savez
            np.savez(stream, p=np.asarray(nodes, dtype=float), t=np.asarray(tets, dtype=np.int64),  # adds no suffix
                     metadata=np.array(json.dumps(metadata or {}, sort_keys=True, default=repr)))
        return self.path(key)
