"""Quadrature on pieces with endpoint-smoothing substitution, and a vectorized root finder for monotone functions."""

from __future__ import annotations

import numpy as np

__all__ = ["piecewise_gauss", "solve_monotone"]

_GAUSS_ORDER = 48
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(_GAUSS_ORDER)
_S = 0.5 * (_NODES + 1.0)                     # (N,) nodes on [0, 1]
_W = 0.5 * _WEIGHTS                           # (N,) weights on [0, 1]


def piecewise_gauss(edges):
    """Gauss points and weights on the pieces between ``edges`` (..., K+1), each piece mapped as t = lo + (hi-lo) s^2.

    The substitution s^2 puts a zero derivative at the lower end of every piece, which removes the
    square-root (and (t-lo)^(3/2)) behaviour that MDR profiles have at a breakpoint or at zero, so
    Gauss-Legendre keeps its spectral accuracy. Returns points and weights of shape (..., K*N).
    """
    edges = np.asarray(edges, dtype=float)
    lower = edges[..., :-1, None]                                  # (..., K, 1)
    width = edges[..., 1:, None] - lower                           # (..., K, 1)
    points = lower + width * _S**2                                 # (..., K, N)
    weights = width * 2.0 * _S * _W                                # (..., K, N)
    shape = edges.shape[:-1] + (-1,)
    return points.reshape(shape), weights.reshape(shape)


def solve_monotone(residual, lower, upper, args=(), what="root"):
    """Root of a continuous monotone ``residual(x, *args)`` in [lower, upper], elementwise (Chandrupatla).

    Ends where the residual is exactly zero are returned as they are; a residual without a sign change
    or a failed iteration raises RuntimeError (a wrong number is never returned).
    """
    from scipy.optimize.elementwise import find_root

    lower, upper, *args = np.broadcast_arrays(np.asarray(lower, float), np.asarray(upper, float),
                                              *(np.asarray(a, float) for a in args))
    at_lower = residual(lower, *args)
    at_upper = residual(upper, *args)
    root = np.where(at_lower == 0.0, lower, upper)
    inner = (at_lower != 0.0) & (at_upper != 0.0)
    if np.any(inner & (np.sign(at_lower) == np.sign(at_upper))):
        raise RuntimeError(f"{what}: no sign change in the bracket; the function is not monotone there")
    if np.any(inner):
        result = find_root(residual, (lower[inner], upper[inner]), args=tuple(a[inner] for a in args),
                           tolerances=dict(xatol=1e-15, xrtol=4 * np.finfo(float).eps))
        if not np.all(result.success):
            raise RuntimeError(f"{what}: root finding did not converge (status {np.unique(result.status)})")
        root = root.copy()
        root[inner] = result.x
    return root
