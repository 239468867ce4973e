"""Sparse direct solver backends for the gel's stiffness: factorize once, solve many right-hand sides.

``SpdFactorization`` factorizes an SPD stiffness K itself. ``SaddlePointFactorization`` applies K^-1 for
K = A + C^T diag(1 / d) C without forming K: it factorizes the sparser symmetric indefinite system
[[A, C^T], [C, -diag(d)]] (the locking-free nodal-average K, whose B^T B term couples second neighbours).
Both have ``solve(rhs)`` on displacement-sized right-hand sides.
"""

from __future__ import annotations

import functools
import os
import site
import sys
from pathlib import Path

import numpy as np
import scipy.sparse as sp

__all__ = ["SaddlePointFactorization", "SpdFactorization", "available_backends", "solve_sparse"]

# MKL PARDISO controls for the saddle-point system, 1-based as in the MKL manual. Setting iparm 1 makes PARDISO take
# them instead of its defaults, which also refine every solve twice and so triple its cost. The matrix is
# quasi-definite ([[SPD, C^T], [C, negative definite]]): an LDL^T with 1 x 1 pivots exists in every symmetric
# order (Vanderbei, SIAM J. Optim. 5, 1995), so no weighted matching is needed. Measured on the 26k-DOF stability
# block at nu = 0.49 - 0.49999: no pivot perturbed (iparm 14 = 0), no refinement step, solutions within 3e-12 of
# the condensed K's; matching (iparm 11 = iparm 13 = 1) gave the same accuracy at up to 30 % more factorization time.
SADDLE_POINT_IPARM = {
    1: 1,     # use the values given here
    2: 2,     # nested-dissection (METIS) fill-in reducing ordering
    8: 0,     # iterative refinement only if pivots were perturbed (then 2 steps)
    10: 8,    # perturb pivots below 1e-8 ||A|| (the symmetric indefinite default)
    18: -1,   # report the nonzeros of the factor in iparm 18
    21: 1,    # Bunch-Kaufman pivoting with 1 x 1 and 2 x 2 blocks
}


# The same for the SPD stiffness: a Cholesky factor needs neither pivoting nor refinement (backward stable), and
# PARDISO's defaults (iparm 1 = 0) would refine every solve twice: 256 solves took 2.0 s with them, 0.73 s without
# (26k-DOF block), and the compliance columns of a contact path are such solves.
SPD_IPARM = {
    1: 1,     # use the values given here
    2: 2,     # nested-dissection (METIS) fill-in reducing ordering
    8: 0,     # no iterative refinement
    18: -1,   # report the nonzeros of the factor in iparm 18
    25: 2,    # parallel forward/backward solve for many right-hand sides
}


MKL_RUNTIME_ENV_VAR = "PYPARDISO_MKL_RT"     # pypardiso reads the path of MKL's runtime library from it


@functools.cache
def _pypardiso():
    """The pypardiso module, pointed at MKL's runtime library first.

    Without ``PYPARDISO_MKL_RT``, and with mkl_rt outside the loader's path (a pip-installed MKL in a virtual
    environment), every ``PyPardisoSolver()`` - one per factorization, and one at import - globs
    ``sys.prefix/lib*/**`` recursively: 2-4 s each on the measured venv, as long as a 20k-DOF factorization. The
    library sits directly in ``lib`` (Linux, macOS) or ``Library/bin`` (Windows): look there once, without recursion.
    A path set by the user wins; where nothing is found, pypardiso searches as before.
    """
    if MKL_RUNTIME_ENV_VAR not in os.environ:
        for prefix in (sys.prefix, site.USER_BASE):
            for folder in ("lib", "Lib", "Library/bin"):
                found = sorted(Path(prefix, folder).glob("*mkl_rt*"), key=lambda path: len(path.name))
                if found:
                    os.environ[MKL_RUNTIME_ENV_VAR] = str(found[0])
                    break
            if MKL_RUNTIME_ENV_VAR in os.environ:
                break
    import pypardiso

    return pypardiso


def available_backends() -> list[str]:
    """Backends usable on this machine, fastest first ('pardiso' needs MKL via pypardiso)."""
    backends = []
    try:
        _pypardiso()

        backends.append("pardiso")
    except ImportError:
        pass
    backends.append("splu")
    return backends


def _check_backend(backend: str | None) -> str:
    backend = backend or available_backends()[0]
    if backend not in available_backends():
        raise ValueError(f"backend={backend!r} is not one of {available_backends()}")
    return backend


class _Factorization:
    """Chunked many-right-hand-side solves on top of a backend's ``_solve_block``."""

    size: int                          # rows of the right-hand sides (displacement dofs)
    backend: str
    chunk: int                         # right-hand sides per backend call: (size x chunk) dense blocks bound memory
    factor_nonzeros: int | None        # entries of the factor(s): PARDISO's L, or SuperLU's L + U

    def _solve_block(self, block: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solution of K x = rhs for one or many right-hand sides (columns), in chunks to bound memory."""
        rhs = np.asarray(rhs, dtype=float)
        if rhs.shape[0] != self.size:
            raise ValueError(f"rhs has {rhs.shape[0]} rows, the matrix {self.size}")
        if rhs.ndim == 1 or rhs.shape[1] <= self.chunk:          # one block: no copy into an output array
            return self._solve_block(rhs)
        out = np.empty_like(rhs, order="F")
        for start in range(0, rhs.shape[1], self.chunk):
            out[:, start:start + self.chunk] = self._solve_block(rhs[:, start:start + self.chunk])
        return out

    def _pardiso_solve(self, block: np.ndarray) -> np.ndarray:
        """PARDISO's solve phase (33) on the stored factor, straight through pypardiso's handle to MKL.

        ``PyPardisoSolver.solve`` checks and compares the whole matrix with the factorized one, converts the
        right-hand sides to Fortran order, and copies the solution back to C order: three passes over (n x 256)
        blocks that took 65 s of the 5600 compliance columns of a 229k-DOF path. Here the index arrays are
        converted once and the solution stays in Fortran order (a right-hand side block already in Fortran order,
        as ``contact.compliance`` builds them, is not copied either).
        """
        import ctypes

        solver = self._solver
        if getattr(self, "_one_based", None) is None:
            self._one_based = (self._upper.indptr.astype(np.int32) + 1, self._upper.indices.astype(np.int32) + 1)
        rows, columns = self._one_based
        rhs = np.asfortranarray(block, dtype=np.float64)
        solution = np.empty_like(rhs, order="F")
        error = ctypes.c_int32(0)
        int_pointer, float_pointer = ctypes.POINTER(ctypes.c_int32), ctypes.POINTER(ctypes.c_double)
        solver.set_phase(33)
        solver._mkl_pardiso(solver.pt.ctypes.data_as(ctypes.POINTER(solver._pt_type[0])),
                            ctypes.byref(ctypes.c_int32(1)), ctypes.byref(ctypes.c_int32(1)),
                            ctypes.byref(ctypes.c_int32(solver.mtype)), ctypes.byref(ctypes.c_int32(33)),
                            ctypes.byref(ctypes.c_int32(self._upper.shape[0])),
                            self._upper.data.ctypes.data_as(float_pointer), rows.ctypes.data_as(int_pointer),
                            columns.ctypes.data_as(int_pointer), solver.perm.ctypes.data_as(int_pointer),
                            ctypes.byref(ctypes.c_int32(1 if rhs.ndim == 1 else rhs.shape[1])),
                            solver.iparm.ctypes.data_as(int_pointer), ctypes.byref(ctypes.c_int32(0)),
                            rhs.ctypes.data_as(float_pointer), solution.ctypes.data_as(float_pointer),
                            ctypes.byref(error))
        if error.value != 0:
            raise RuntimeError(f"PARDISO solve phase failed with error {error.value}")
        return solution

    def release(self) -> None:
        """Free the factor now (pypardiso keeps it in MKL's memory until the process ends); no solve after this."""
        solver = getattr(self, "_solver", None)
        if solver is not None:
            solver.free_memory(everything=True)
            self._solver = None
        self._lu = None


class SpdFactorization(_Factorization):
    """Factorization of a sparse SPD matrix; ``solve(B)`` takes (n,) or (n, k) right-hand sides.

    'pardiso' is MKL PARDISO in SPD mode (13 s vs 140 s for scipy's splu on 94k DOF, docs/design.md, sec. 11);
    'splu' is SuperLU from scipy, the fallback where MKL has no wheel.
    """

    def __init__(self, matrix: sp.spmatrix, backend: str | None = None, chunk: int = 256):
        self.size = matrix.shape[0]
        self.backend = _check_backend(backend)
        self.chunk = chunk
        if self.backend == "pardiso":
            pypardiso = _pypardiso()
            self._upper = sp.triu(matrix, format="csr")
            self._upper.sort_indices()
            self._solver = pypardiso.PyPardisoSolver(mtype=2)      # real SPD
            for index, value in SPD_IPARM.items():
                self._solver.set_iparm(index, value)
            self._solver.factorize(self._upper)
            self.factor_nonzeros = int(self._solver.get_iparm(18))
        else:
            from scipy.sparse.linalg import splu

            self._lu = splu(sp.csc_matrix(matrix), permc_spec="MMD_AT_PLUS_A")
            self.factor_nonzeros = int(self._lu.L.nnz + self._lu.U.nnz)

    def _solve_block(self, block: np.ndarray) -> np.ndarray:
        if self.backend == "pardiso":
            return self._pardiso_solve(block)
        return self._lu.solve(block)


class SaddlePointFactorization(_Factorization):
    """K^-1 for K = A + C^T diag(1 / d) C, applied through a factorization of the uncondensed saddle-point system.

    Parameters
    ----------
    stiffness : (n, n) sparse SPD matrix A (for the nodal-average gel: K_G = 2 G eps:eps on the free dofs [N/mm])
    constraint : (m, n) sparse matrix C (the divergence pairing B on the free dofs [mm^2])
    compliance : (m,) array d > 0 (V_n / lambda [mm^3/MPa])
    backend : 'pardiso' (MKL, real symmetric indefinite, mtype -2) or 'splu' (SuperLU LU of the whole matrix)

    ``solve(rhs)`` takes (n,) or (n, k) right-hand sides, exactly like ``SpdFactorization(K).solve``: it pads them
    with zeros for the m constraint rows and returns the first n rows of the solution of

        [[A, C^T], [C, -diag(d)]] [x; y] = [rhs; 0].

    The second block row gives y = diag(1 / d) C x, since diag(d) is invertible, and the first then reads
    (A + C^T diag(1 / d) C) x = rhs: x is the solution of the condensed system K x = rhs. The augmented matrix
    avoids C^T C, which couples second neighbours: on the 26k-DOF stability block its PARDISO factor has 3/8
    of the condensed K's nonzeros. Its inertia (n positive, m negative eigenvalues: Sylvester, since it is
    congruent to diag(K, -diag(d))) is checked after the factorization as a test that A + C^T C / d is SPD.
    """

    def __init__(self, stiffness: sp.spmatrix, constraint: sp.spmatrix, compliance: np.ndarray,
                 backend: str | None = None, chunk: int = 256):
        compliance = np.asarray(compliance, dtype=float)
        self.size = stiffness.shape[0]
        self.constraints = constraint.shape[0]
        if stiffness.shape != (self.size, self.size) or constraint.shape[1] != self.size \
                or compliance.shape != (self.constraints,):
            raise ValueError(f"block shapes do not fit: stiffness {stiffness.shape}, constraint {constraint.shape}, "
                             f"compliance {compliance.shape}")
        if not np.all(compliance > 0.0) or not np.all(np.isfinite(compliance)):
            raise ValueError(f"compliance must be finite and > 0 (it is V_n / lambda); smallest {compliance.min()!r}")
        self.backend = _check_backend(backend)
        self.chunk = chunk
        pressure_block = sp.diags(-compliance)
        if self.backend == "pardiso":
            pypardiso = _pypardiso()
            # real symmetric matrices go to PARDISO as their upper triangle in CSR, with every diagonal entry stored
            self._upper = sp.bmat([[sp.triu(stiffness), constraint.T], [None, pressure_block]], format="csr")
            self._upper.sort_indices()
            self._solver = pypardiso.PyPardisoSolver(mtype=-2)     # real symmetric indefinite
            for index, value in SADDLE_POINT_IPARM.items():
                self._solver.set_iparm(index, value)
            self._solver.factorize(self._upper)
            self.factor_nonzeros = int(self._solver.get_iparm(18))
            self.perturbed_pivots = int(self._solver.get_iparm(14))
            positive, negative = int(self._solver.get_iparm(22)), int(self._solver.get_iparm(23))
            if (positive, negative) != (self.size, self.constraints):
                self.release()
                raise ValueError(f"the saddle-point matrix has inertia ({positive} positive, {negative} negative), "
                                 f"not ({self.size}, {self.constraints}): the condensed stiffness is not positive "
                                 f"definite (a rigid-body mode left free?)")
        else:
            from scipy.sparse.linalg import splu

            whole = sp.bmat([[stiffness, constraint.T], [constraint, pressure_block]], format="csc")
            # LU with partial row pivoting (SuperLU's default threshold 1) after a fill-reducing column ordering of
            # A + A^T: indefiniteness needs nothing more; fill and time are those of a general LU, not of LDL^T
            self._lu = splu(whole, permc_spec="MMD_AT_PLUS_A")
            self.factor_nonzeros = int(self._lu.L.nnz + self._lu.U.nnz)
            self.perturbed_pivots = 0

    def _solve_block(self, block: np.ndarray) -> np.ndarray:
        padded = np.zeros((self.size + self.constraints,) + block.shape[1:], order="F")   # zero constraint rows
        padded[:self.size] = block
        if self.backend == "pardiso":
            solution = self._pardiso_solve(padded)
        else:
            solution = self._lu.solve(padded)
        return solution[:self.size]


def solve_sparse(matrix: sp.spmatrix, rhs: np.ndarray, backend: str | None = None) -> np.ndarray:
    """x of A x = rhs for one sparse square matrix A, not necessarily symmetric: MKL PARDISO (real unsymmetric,
    mtype 11) or SuperLU; RuntimeError when A is singular (a solution that is not finite)."""
    backend = _check_backend(backend)
    if backend == "pardiso":
        solver = _pypardiso().PyPardisoSolver(mtype=11)
        try:
            solution = solver.solve(sp.csr_matrix(matrix), np.asarray(rhs, dtype=float))
        finally:
            solver.free_memory(everything=True)
    else:
        from scipy.sparse.linalg import splu

        solution = splu(sp.csc_matrix(matrix)).solve(np.asarray(rhs, dtype=float))
    if not np.all(np.isfinite(solution)):
        raise RuntimeError("the matrix is singular: the solution is not finite")
    return solution
