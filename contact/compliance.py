"""Condensed surface compliance of the gel: columns of K^-1 at contact-candidate dofs, computed only when needed.

The gel is linear and only the contact is not, so the surface displacement of the candidate points is exactly
u = C f, with C the inverse stiffness restricted to those dofs (a Schur complement, as boundary-element contact
codes use). A column costs one back-substitution with the stored factorization; columns are computed the first
time a point enters contact and reused by every later Newton iteration, increment and load path on that mesh.

Columns are also kept on disk (``ColumnCache``), keyed by the mesh, the material, the element formulation, the
candidate points and the package version: a re-run, a resumed sweep or another load path on the same fingertip
reads them instead of solving again (the columns are 60-90 % of a contact path's time on 50k-230k DOF). A stored
set that does not read back whole or does not fit the compliance it is loaded for is reported once with its path and
computed again (``fem.cache_dir``).
"""

from __future__ import annotations

import hashlib
import json
import time
from pathlib import Path

import numpy as np

from fem.atomic import atomic_path
from fem.cache_dir import default_cache_dir, discard_damaged, writable_folder
from fem.elasticity import ElasticModel
from fem.linear_solver import SaddlePointFactorization, SpdFactorization

__all__ = ["SurfaceCompliance", "ColumnCache", "compliance_cache_key", "package_version",
           "MAX_CACHED_BYTES"]

PACKAGE = "fingertip-contact"
GATHER_BAND_BYTES = 4e6     # rows copied per band of SurfaceCompliance.gather: a few MB stay in cache
MAX_CACHED_BYTES = 2e9        # larger column sets (a 230k-DOF contact holds ~0.6 GB) are not written to disk


def package_version() -> str:
    """Installed version of the package, "unknown" when it runs from a source tree that was never installed."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(PACKAGE)
    except PackageNotFoundError:
        return "unknown"


def _digest(*arrays) -> str:
    sha = hashlib.sha256()
    for array in arrays:
        array = np.ascontiguousarray(array)
        sha.update(str((array.dtype.str, array.shape)).encode())
        sha.update(array.tobytes())
    return sha.hexdigest()


def compliance_cache_key(model: ElasticModel, youngs_modulus: float, poissons_ratio: float, points: np.ndarray,
                         components: tuple[int, ...], half: bool) -> str:
    """SHA-256 key of a compliance column set: mesh nodes and tets, E [MPa], nu, element order and volumetric
    formulation, mirror half, candidate points, components and the package version (an upgrade recomputes)."""
    payload = {"mesh": _digest(model.mesh.p, model.mesh.t), "E": repr(float(youngs_modulus)),
               "nu": repr(float(poissons_ratio)), "order": model.order, "volumetric": model.volumetric,
               "half": bool(half), "points": _digest(np.asarray(points, dtype=np.int64)),
               "components": list(components), "free_dofs": _digest(model.free_dofs), "version": package_version()}
    return hashlib.sha256(json.dumps(payload, sort_keys=True).encode()).hexdigest()


class ColumnCache:
    """Compliance columns on disk: ``<directory>/compliance-<key>.npz`` with the flat unknown indices
    ``columns`` (c,) and their values (rows, c) [mm/N]; written atomically, an unreadable file counts as absent.
    Default directory: ``compliance`` in the mesh cache's folder (FINGERTIP_CACHE or ~/.cache/fingertip-contact).
    """

    def __init__(self, directory=None):
        self.directory = Path(directory) if directory is not None else default_cache_dir() / "compliance"

    def path(self, key: str) -> Path:
        return self.directory / f"compliance-{key}.npz"

    def load(self, key: str, rows: int | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """(columns, values) stored under ``key``, None when absent. A file that does not read back whole (a bad
        CRC, truncated, not an npz) or does not fit (``rows`` rows of the compliance it is for; column indices
        unique and in range; finite values) is reported, deleted and None returned: the columns are computed and
        written again."""
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as data:
                columns, values = np.array(data["columns"]), np.array(data["values"])
        except Exception as error:             # zipfile.BadZipFile ("Bad CRC-32"), EOFError, OSError, KeyError, ...
            discard_damaged(path, f"{type(error).__name__}: {error}")
            return None
        problem = _column_set_problem(columns, values, rows)
        if problem:
            discard_damaged(path, problem)
            return None
        return columns.astype(np.int64), values.astype(float)

    def save(self, key: str, columns: np.ndarray, values: np.ndarray) -> Path | None:
        """Write the columns (skipped above MAX_CACHED_BYTES, or when the folder cannot be written: one warning);
        returns the path, or None when skipped."""
        if values.nbytes > MAX_CACHED_BYTES or not writable_folder(self.directory):
            return None
        with atomic_path(self.path(key)) as temporary, open(temporary, "wb") as stream:
            np.savez(stream, columns=np.asarray(columns, dtype=np.int64), values=values)
        return self.path(key)


def _column_set_problem(columns: np.ndarray, values: np.ndarray, rows: int | None) -> str | None:
    """What is wrong with a stored column set (flat indices ``columns`` (c,), ``values`` (rows, c)), or None."""
    if columns.ndim != 1 or not np.issubdtype(columns.dtype, np.integer):
        return f"column indices of shape {columns.shape} and type {columns.dtype}, not a list of integers"
    if values.ndim != 2 or not np.issubdtype(values.dtype, np.floating) or values.shape[1] != columns.size:
        return f"values of shape {values.shape} and type {values.dtype} for {columns.size} columns"
    if rows is not None and values.shape[0] != rows:
        return f"{values.shape[0]} rows where this compliance has {rows}"
    if columns.size and (columns.min() < 0 or columns.max() >= values.shape[0]
                         or np.unique(columns).size != columns.size):
        return f"column indices outside [0, {values.shape[0]}) or repeated"
    if not np.isfinite(values).all():
        return "non-finite values"
    return None


class SurfaceCompliance:
    """Lazily built compliance C [mm/N] between the dofs of candidate top-surface points.

    Parameters
    ----------
    model : ElasticModel
    factorization : whose ``solve`` applies ``model.stiffness_free``^-1 (``contact.solver.factorize_stiffness``:
        of K itself, or of the nodal-average saddle-point system)
    points : (n,) indices into ``model.top`` of the candidate points
    components : dof components carried per point, (0, 1, 2) for x, y, z or (2,) for normal-only contact
    """

    def __init__(self, model: ElasticModel, factorization: SpdFactorization | SaddlePointFactorization,
                 points: np.ndarray, components: tuple[int, ...] = (0, 1, 2)):
        self.model = model
        self.factorization = factorization
        self.points = np.asarray(points)
        self.components = tuple(components)
        free_position = np.full(model.n_dofs, -1)
        free_position[model.free_dofs] = np.arange(model.free_dofs.size)
        dofs = model.top.dofs[self.points][:, self.components]          # (n, n_comp) full dof ids
        self.rows = free_position[dofs].ravel()                         # (n * n_comp,) free-vector positions
        # dofs held by a Dirichlet condition (u_y = 0 on a symmetry plane) have zero rows and columns
        self.constrained = self.rows < 0
        if np.any(self.constrained[len(self.components) - 1::len(self.components)]):
            raise ValueError("a contact candidate point has its normal displacement fixed (it lies on the base)")
        self.size = self.rows.size
        self._slot = np.full(self.size, -1)                             # column -> storage slot
        self._store = np.empty((self.size, 0))
        self._count = 0
        self.solves = 0
        self.seconds = 0.0                                              # spent computing columns [s]
        self.loaded = 0                                                 # columns read from a cache

    def preload(self, columns: np.ndarray, values: np.ndarray) -> None:
        """Take stored columns (flat unknown indices (c,), values (size, c)); only into an empty compliance."""
        if self._count:
            raise ValueError("preload needs an empty compliance")
        columns = np.asarray(columns, dtype=np.int64)
        if values.shape != (self.size, columns.size) or columns.size and (columns.min() < 0
                                                                          or columns.max() >= self.size):
            raise ValueError(f"stored columns do not fit this compliance: values {values.shape}, "
                             f"{self.size} rows, column indices up to {columns.max(initial=-1)}")
        self._store = np.array(values, dtype=float)
        self._slot[columns] = np.arange(columns.size)
        self._count = self.loaded = int(columns.size)

    def stored(self) -> tuple[np.ndarray, np.ndarray]:
        """The computed columns: flat unknown indices (c,) and their values (size, c) (a view)."""
        columns = np.empty(self._count, dtype=np.int64)
        used = np.flatnonzero(self._slot >= 0)
        columns[self._slot[used]] = used
        return columns, self._store[:, :self._count]

    def unknown_index(self, local_points: np.ndarray) -> np.ndarray:
        """Flat indices (len(points) * n_comp,) of the dofs of the given local candidate points."""
        n_comp = len(self.components)
        return (np.asarray(local_points)[:, None] * n_comp + np.arange(n_comp)).ravel()

    def ensure(self, columns: np.ndarray) -> None:
        """Compute the missing columns among ``columns`` (flat unknown indices) in one multi-RHS solve."""
        columns = np.asarray(columns)
        missing = columns[self._slot[columns] < 0]
        if missing.size == 0:
            return
        start_time = time.perf_counter()
        needed = self._count + missing.size
        if needed > self._store.shape[1]:
            grown = np.empty((self.size, max(needed, 2 * self._store.shape[1], 64)))
            grown[:, :self._count] = self._store[:, :self._count]
            self._store = grown
        free = np.flatnonzero(~self.constrained[missing])
        block = np.zeros((self.size, missing.size))
        kept_rows = self.rows[~self.constrained]
        # unit right-hand sides in chunks: the dense (n_free x chunk) blocks bound the memory, not the column count
        for start in range(0, free.size, self.factorization.chunk):
            part = free[start:start + self.factorization.chunk]
            rhs = np.zeros((self.factorization.size, part.size), order="F")     # the backend's column order
            rhs[self.rows[missing[part]], np.arange(part.size)] = 1.0
            block[np.ix_(~self.constrained, part)] = self.factorization.solve(rhs)[kept_rows]
        self._store[:, self._count:needed] = block
        self._slot[missing] = np.arange(self._count, needed)
        self._count = needed
        self.solves += int(free.size)
        self.seconds += time.perf_counter() - start_time

    def gather(self, row_index: np.ndarray, columns: np.ndarray, out: np.ndarray) -> np.ndarray:
        """C[rows, columns] written into ``out`` (len(rows), len(columns)), e.g. the top-left block of a larger
        system, in bands of rows: no temporary of the block's size (a 230k-DOF contact's is 240 MB per Newton
        iteration), and a band's take is one call (row by row, the Python loop cost twice the copy at 1.7k rows)."""
        self.ensure(columns)
        slots = self._slot[columns]
        row_index = np.asarray(row_index)
        band = max(1, int(GATHER_BAND_BYTES // (8 * max(self._count, 1))))
        for start in range(0, row_index.size, band):
            rows = row_index[start:start + band]
            np.take(self._store[rows, :self._count], slots, axis=1, out=out[start:start + rows.size])
        return out

    def block(self, row_index: np.ndarray, columns: np.ndarray) -> np.ndarray:
        """C[rows, columns] (computing missing columns first), one gather of the stored entries."""
        self.ensure(columns)
        return self._store[np.ix_(np.asarray(row_index), self._slot[columns])]

    def displacement(self, columns: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """Displacement at every candidate dof [mm] for nodal forces [N] on the given columns.

        The forces are scattered onto the stored columns and multiplied in place: gathering the columns first would
        copy a (candidate dofs x loaded dofs) block per call (5 s of a 53 s HCM-1 path at 53k DOF).
        """
        if len(columns) == 0:
            return np.zeros(self.size)
        self.ensure(columns)
        weights = np.zeros(self._count)
        np.add.at(weights, self._slot[columns], forces)
        return self._store[:, :self._count] @ weights

    @property
    def computed_columns(self) -> int:
        return self._count
