"""Dense Newton systems of the contact solver: an LU factorization reused as a GMRES preconditioner.

Every Newton iteration of an increment solves a dense system J x = b over the unknowns of the points in contact
(3 per point with friction, plus the force-controlled body coordinates). J = D C + B, with C the condensed surface
compliance (fixed for a mesh) and D, B block-diagonal per point: a point's rows change only where its state does
(open, stick, slip) or, for a sliding point, by a small amount (its slip direction and cone factor). So the LU
factors of one Jacobian are a near inverse of the next ones, across iterations and increments: right-preconditioned
GMRES with them converges in a few iterations, each costing two O(n^2) products instead of an O(n^3) factorization.
Where the states changed at many points (a rank too high for a few Krylov steps), or GMRES stalls, the current
Jacobian is factorized and becomes the preconditioner. Small systems are factorized directly: there the
factorization costs no more than a handful of Krylov steps.

On HCM-1 at 229k DOF the factorizations of 3m x 3m systems (m ~ 1900 points in contact) took half of the whole
path's time before (``python -m studies benchmark --scaling``).
"""

from __future__ import annotations

import math
import time
import warnings

import numpy as np
import scipy.linalg

__all__ = ["NewtonLinearSolver", "gmres", "eliminate_slip_directions", "restore_slip_directions"]

DIRECT_SIZE = 600            # systems up to this size are factorized: a few Krylov steps cost about as much
KRYLOV_SHARE = 1.0 / 40.0    # at most n / 40 Krylov steps (each 2 matrix-vector passes, memory-bound) before the
#                              O(n^3) factorization (compute-bound BLAS 3) would have been cheaper; capped below
MAX_KRYLOV = 150
CHANGED_SHARE = 0.5          # refactorize at once when more points changed state than this share of the Krylov cap
FRESH_KRYLOV = 20            # GMRES steps allowed on single-precision factors of the system itself


def gmres(matvec, precondition, residual, tolerance: float, max_iterations: int):
    """Right-preconditioned GMRES from x = 0 for A x = r: returns (x, converged, iterations, residual norm).

    ``matvec(v)`` applies A, ``precondition(v)`` applies M^-1 ~ A^-1; the true residual ||r - A x|| (not a
    preconditioned one) is minimised over x in M^-1 K_k(A M^-1, r) and stopped at ``tolerance`` (absolute). Modified
    Gram-Schmidt with one reorthogonalisation (classical, twice is enough: Giraud et al., Numer. Math. 101, 2005);
    Givens rotations track the residual norm. Gives up early when the reduction so far predicts more than
    ``max_iterations`` steps.
    """
    beta = float(np.linalg.norm(residual))
    if beta <= tolerance:
        return np.zeros_like(residual), True, 0, beta
    n = residual.size
    basis = np.empty((max_iterations + 1, n))
    directions = np.empty((max_iterations, n))
    hessenberg = np.zeros((max_iterations + 1, max_iterations))
    cosines, sines = np.zeros(max_iterations), np.zeros(max_iterations)
    rotated = np.zeros(max_iterations + 1)
    rotated[0] = beta
    basis[0] = residual / beta
    norm = beta
    for j in range(max_iterations):
        directions[j] = precondition(basis[j])
        w = matvec(directions[j])
        coefficients = basis[:j + 1] @ w
        w -= coefficients @ basis[:j + 1]
        again = basis[:j + 1] @ w
        w -= again @ basis[:j + 1]
        hessenberg[:j + 1, j] = coefficients + again
        hessenberg[j + 1, j] = np.linalg.norm(w)
        breakdown = hessenberg[j + 1, j] == 0.0                        # the Krylov space holds the solution
        if not breakdown:
            basis[j + 1] = w / hessenberg[j + 1, j]
        for i in range(j):                                            # earlier rotations on the new column
            upper, lower = hessenberg[i, j], hessenberg[i + 1, j]
            hessenberg[i, j] = cosines[i] * upper + sines[i] * lower
            hessenberg[i + 1, j] = -sines[i] * upper + cosines[i] * lower
        radius = math.hypot(hessenberg[j, j], hessenberg[j + 1, j])
        cosines[j], sines[j] = (hessenberg[j, j] / radius, hessenberg[j + 1, j] / radius) if radius > 0 else (1.0, 0.0)
        hessenberg[j, j], hessenberg[j + 1, j] = radius, 0.0
        rotated[j + 1] = -sines[j] * rotated[j]
        rotated[j] = cosines[j] * rotated[j]
        norm = abs(rotated[j + 1])
        steps = j + 1
        done = norm <= tolerance or breakdown
        if not done and steps >= 4:
            rate = (norm / beta) ** (1.0 / steps)                      # mean reduction per step so far
            if rate >= 1.0 or steps + math.log(tolerance / norm) / math.log(rate) > max_iterations:
                return None, False, steps, norm
        if done:
            coefficients = scipy.linalg.solve_triangular(hessenberg[:steps, :steps], rotated[:steps])
            return coefficients @ directions[:steps], norm <= tolerance, steps, norm
    return None, False, max_iterations, norm


def eliminate_slip_directions(jacobian: np.ndarray, rhs: np.ndarray, points: np.ndarray, direction: np.ndarray,
                              friction_coefficient: float):
    """The Newton system without the slip-direction force of each sliding point: (jacobian, rhs, kept unknowns).

    At a sliding point the linearised Alart-Curnier rows, projected on the slip direction d, read t . d - mu lambda
    = 0 exactly (the projector perp = I - d d^T of the other terms vanishes on d): the force along d is mu lambda.
    In the frame (d, p), p = z x d, the point's x row is replaced by that identity and its y row by the p row;
    t_d = mu lambda goes into the lambda column (column_lambda += mu column_d) and the d row and column are dropped.
    Each sliding point removes one unknown: near gross slip the system has ~2.2 instead of 3 unknowns per point,
    and its LU factorization ~40 % of the cost. ``points``: local indices of the sliding points (3 unknowns each,
    x, y, normal at 3k, 3k + 1, 3k + 2); ``direction``: their unit slip directions (s, 2). ``jacobian`` is modified.
    """
    d_x, d_y = direction[:, 0], direction[:, 1]
    p_x, p_y = -d_y, d_x
    x_index, y_index, normal_index = 3 * points, 3 * points + 1, 3 * points + 2
    rows_x, rows_y = jacobian[x_index], jacobian[y_index]                  # (s, N) copies (fancy indexing)
    jacobian[y_index] = p_x[:, None] * rows_x + p_y[:, None] * rows_y
    rhs = rhs.copy()
    rhs[y_index] = p_x * rhs[x_index] + p_y * rhs[y_index]
    columns_x, columns_y = jacobian[:, x_index], jacobian[:, y_index]      # (N, s)
    jacobian[:, y_index] = columns_x * p_x + columns_y * p_y
    jacobian[:, normal_index] += friction_coefficient * (columns_x * d_x + columns_y * d_y)
    keep = np.ones(rhs.size, dtype=bool)
    keep[x_index] = False
    kept = np.flatnonzero(keep)
    return jacobian[np.ix_(kept, kept)], rhs[kept], kept


def restore_slip_directions(solution: np.ndarray, kept: np.ndarray, size: int, points: np.ndarray,
                            direction: np.ndarray, friction_coefficient: float) -> np.ndarray:
    """Unknowns (size,) in the x, y frame from the solution of ``eliminate_slip_directions``' system."""
    full = np.zeros(size)
    full[kept] = solution
    along = friction_coefficient * full[3 * points + 2]                    # t . d = mu lambda
    across = full[3 * points + 1]                                          # t . p
    full[3 * points] = along * direction[:, 0] - across * direction[:, 1]
    full[3 * points + 1] = along * direction[:, 1] + across * direction[:, 0]
    return full


def rotate_slip_guess(values: np.ndarray, kept: np.ndarray, points: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """The current iterate in the unknowns of ``eliminate_slip_directions``' system (t . p in the y slot)."""
    values = values.copy()
    values[3 * points + 1] = -direction[:, 1] * values[3 * points] + direction[:, 0] * values[3 * points + 1]
    return values[kept]


class NewtonLinearSolver:
    """Solves the dense Newton systems of one load path, reusing an LU factorization across them.

    ``solve(jacobian, rhs, keys, states, guess, tolerance)``: ``keys`` (n,) name each unknown (a point's component,
    or a body coordinate) so that a factorization made for one set of points serves another; ``states`` (n,) the
    state code of each unknown's point (open / stick / slip; body unknowns any fixed code): unknowns whose state
    changed since the factorization count towards refactorizing at once. ``guess`` is the current iterate on the
    same unknowns: GMRES solves for the correction, to the absolute residual ``tolerance``.

    Counters: ``factorizations``, ``krylov_solves`` and ``krylov_iterations`` (for the benchmark).
    """

    def __init__(self, direct_size: int = DIRECT_SIZE):
        self.direct_size = direct_size
        self._factors = None
        self._keys = None                # (n_f,) sorted keys of the factorized system
        self._order = None               # positions in the factorized system of the sorted keys
        self._states = None
        self.factorizations = 0
        self.krylov_solves = 0
        self.krylov_iterations = 0
        self.seconds = 0.0                # spent in solve() [s]
        self.double_precision = 0         # factorizations in double precision (single precision's GMRES failed)

    def _factorize(self, jacobian: np.ndarray, keys: np.ndarray, states: np.ndarray, single: bool = False):
        # LAPACK factorizes column-major arrays: J^T of a C-ordered J is one, in place (J itself would be copied);
        # solves then use the transposed factors (trans=1). ``single``: factors of a float32 copy (J is kept)
        matrix = jacobian.T.astype(np.float32) if single else jacobian.T
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", scipy.linalg.LinAlgWarning)        # a zero pivot is raised below
            factors = scipy.linalg.lu_factor(matrix, overwrite_a=True, check_finite=False)
        if not np.all(np.isfinite(factors[0])) or np.any(np.diag(factors[0]) == 0.0):
            raise np.linalg.LinAlgError("singular matrix (a zero pivot in its LU factorization)")
        self.factorizations += 1
        order = np.argsort(keys, kind="stable")
        self._factors, self._keys, self._order, self._states = factors, keys[order], order, states[order]
        return factors

    def solve(self, jacobian: np.ndarray, rhs: np.ndarray, keys: np.ndarray, states: np.ndarray,
              guess: np.ndarray, tolerance: float) -> np.ndarray:
        start = time.perf_counter()
        try:
            return self._solve(jacobian, rhs, keys, states, guess, tolerance)
        finally:
            self.seconds += time.perf_counter() - start

    def _solve(self, jacobian, rhs, keys, states, guess, tolerance):
        n = rhs.size
        if n <= self.direct_size:
            return np.linalg.solve(jacobian, rhs)
        cap = int(min(MAX_KRYLOV, max(8, KRYLOV_SHARE * n)))
        if self._factors is not None:
            position = np.searchsorted(self._keys, keys)
            position = np.minimum(position, self._keys.size - 1)
            known = self._keys[position] == keys
            changed = int(np.count_nonzero(~known) + np.count_nonzero(self._states[position[known]] != states[known]))
            if changed <= CHANGED_SHARE * cap:
                correction = self._krylov(jacobian, rhs - jacobian @ guess, position, known, tolerance, cap)
                if correction is not None:
                    return guess + correction
        # single-precision factors (half the time of double's) as the preconditioner of GMRES to the full
        # tolerance: a few steps, since they invert J to ~1e-7 relative; double-precision factors where that fails
        try:
            self._factorize(jacobian, keys, states, single=True)
            correction = self._krylov(jacobian, rhs - jacobian @ guess, np.argsort(self._order),
                                      np.ones(n, dtype=bool), tolerance, FRESH_KRYLOV)
            if correction is not None:
                return guess + correction
        except np.linalg.LinAlgError:
            pass
        self.double_precision += 1
        factors = self._factorize(np.ascontiguousarray(jacobian), keys, states)     # overwrites jacobian
        return scipy.linalg.lu_solve(factors, rhs, trans=1, check_finite=False)

    def _krylov(self, jacobian, residual, position, known, tolerance, cap):
        lu_rows = self._order[position[known]]           # rows of the factorized system of the known unknowns
        diagonal = np.diag(jacobian).copy()
        diagonal[diagonal == 0.0] = 1.0
        size = self._keys.size

        def precondition(vector):
            padded = np.zeros(size)
            padded[lu_rows] = vector[known]
            result = vector / diagonal                    # new unknowns: Jacobi
            solved = scipy.linalg.lu_solve(self._factors, padded.astype(self._factors[0].dtype), trans=1,
                                           check_finite=False)
            result[known] = solved[lu_rows]
            return result

        self.krylov_solves += 1
        correction, converged, steps, _ = gmres(lambda v: jacobian @ v, precondition, residual, tolerance, cap)
        self.krylov_iterations += steps
        if not converged:
            return None
        true_residual = np.linalg.norm(residual - jacobian @ correction)
        return correction if true_residual <= 10.0 * tolerance else None
