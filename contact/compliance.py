"""Condensed surface compliance of the gel: columns of K^-1 at contact-candidate dofs, computed only when needed.

The gel is linear and only the contact is not, so the surface displacement of the candidate points is exactly
u = C f, with C the inverse stiffness restricted to those dofs (a Schur complement, as boundary-element contact
codes use). A column costs one back-substitution with the stored factorization; columns are computed the first
time a point enters contact and reused by every later Newton iteration, increment and load path on that mesh.
"""

from __future__ import annotations

import numpy as np

from fem.elasticity import ElasticModel
from fem.linear_solver import SaddlePointFactorization, SpdFactorization

__all__ = ["SurfaceCompliance"]


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
            rhs = np.zeros((self.factorization.size, part.size))
            rhs[self.rows[missing[part]], np.arange(part.size)] = 1.0
            block[np.ix_(~self.constrained, part)] = self.factorization.solve(rhs)[kept_rows]
        self._store[:, self._count:needed] = block
        self._slot[missing] = np.arange(self._count, needed)
        self._count = needed
        self.solves += int(free.size)

    def block(self, row_index: np.ndarray | slice, columns: np.ndarray) -> np.ndarray:
        """C[rows, columns] (computing missing columns first); rows default to all candidate dofs."""
        self.ensure(columns)
        return self._store[row_index, :][:, self._slot[columns]]

    def displacement(self, columns: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """Displacement at every candidate dof [mm] for nodal forces [N] on the given columns."""
        if len(columns) == 0:
            return np.zeros(self.size)
        self.ensure(columns)
        return self._store[:, self._slot[columns]] @ forces

    @property
    def computed_columns(self) -> int:
        return self._count
