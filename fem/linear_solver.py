"""Sparse symmetric positive definite solver backends: factorize once, solve many right-hand sides."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["SpdFactorization", "available_backends"]


def available_backends() -> list[str]:
    """Backends usable on this machine, fastest first ('pardiso' needs MKL via pypardiso)."""
    backends = []
    try:
        import pypardiso  # noqa: F401

        backends.append("pardiso")
    except ImportError:
        pass
    backends.append("splu")
    return backends


class SpdFactorization:
    """Factorization of a sparse SPD matrix; ``solve(B)`` takes (n,) or (n, k) right-hand sides.

    'pardiso' is MKL PARDISO in SPD mode (13 s vs 140 s for scipy's splu on 94k DOF, DESIGN.md);
    'splu' is SuperLU from scipy, the fallback where MKL has no wheel.
    """

    def __init__(self, matrix: sp.spmatrix, backend: str | None = None, chunk: int = 256):
        self.size = matrix.shape[0]
        self.backend = backend or available_backends()[0]
        self.chunk = chunk
        if self.backend == "pardiso":
            import pypardiso

            self._upper = sp.triu(matrix, format="csr")
            self._upper.sort_indices()
            self._solver = pypardiso.PyPardisoSolver(mtype=2)      # real SPD
            self._solver.set_iparm(25, 2)                           # parallel solve for many right-hand sides
            self._solver.factorize(self._upper)
        elif self.backend == "splu":
            from scipy.sparse.linalg import splu

            self._lu = splu(sp.csc_matrix(matrix), permc_spec="MMD_AT_PLUS_A")
        else:
            raise ValueError(f"backend={backend!r} is not one of {available_backends()}")

    def _solve_block(self, block: np.ndarray) -> np.ndarray:
        if self.backend == "pardiso":
            return self._solver.solve(self._upper, np.ascontiguousarray(block))
        return self._lu.solve(block)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solution of K x = rhs for one or many right-hand sides (columns), in chunks to bound memory."""
        rhs = np.asarray(rhs, dtype=float)
        if rhs.shape[0] != self.size:
            raise ValueError(f"rhs has {rhs.shape[0]} rows, the matrix {self.size}")
        if rhs.ndim == 1:
            return self._solve_block(rhs)
        out = np.empty_like(rhs)
        for start in range(0, rhs.shape[1], self.chunk):
            out[:, start:start + self.chunk] = self._solve_block(rhs[:, start:start + self.chunk])
        return out
