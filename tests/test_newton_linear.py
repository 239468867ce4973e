"""Dense Newton systems: GMRES with a reused LU, the slip-direction elimination, against direct solves."""

import numpy as np
import pytest

from contact._newton_linear import (NewtonLinearSolver, eliminate_slip_directions, gmres, restore_slip_directions,
                                    rotate_slip_guess)

# direct LU solves of these well-conditioned systems (condition ~10) agree to ~1e-14; the iterative ones stop at an
# absolute residual of TOLERANCE, so their error is below TOLERANCE times the inverse's norm (< 1)
TOLERANCE = 1e-11


def system(size, seed):
    rng = np.random.default_rng(seed)
    return np.eye(size) * 4.0 + rng.standard_normal((size, size)) / np.sqrt(size), rng.standard_normal(size)


def test_gmres_with_an_exact_preconditioner_takes_one_step():
    matrix, rhs = system(50, 0)
    inverse = np.linalg.inv(matrix)
    solution, converged, steps, _ = gmres(lambda v: matrix @ v, lambda v: inverse @ v, rhs, TOLERANCE, 10)
    assert converged and steps == 1
    assert np.allclose(solution, np.linalg.solve(matrix, rhs), atol=TOLERANCE)


def test_gmres_with_a_stale_preconditioner_reaches_the_tolerance():
    matrix, rhs = system(80, 1)
    rng = np.random.default_rng(2)
    stale = np.linalg.inv(matrix + 0.05 * rng.standard_normal(matrix.shape) / np.sqrt(80))
    solution, converged, steps, norm = gmres(lambda v: matrix @ v, lambda v: stale @ v, rhs, TOLERANCE, 40)
    assert converged and norm <= TOLERANCE
    assert np.linalg.norm(rhs - matrix @ solution) <= 10 * TOLERANCE       # the true residual, not an estimate
    assert steps < 40


def test_gmres_gives_up_when_it_cannot_converge_in_time():
    matrix, rhs = system(80, 3)
    solution, converged, steps, _ = gmres(lambda v: matrix @ v, lambda v: v, rhs, 1e-30, 6)
    assert solution is None and not converged and steps <= 6


def test_reused_factorization_solves_a_sequence_of_changing_systems():
    size = 700                                           # above the direct size: the Krylov path is used
    solver = NewtonLinearSolver(direct_size=100)
    matrix, rhs = system(size, 4)
    keys = np.arange(size)
    states = np.ones(size, dtype=int)
    rng = np.random.default_rng(5)
    previous = np.zeros(size)
    for step in range(4):
        # small changes everywhere (sliding points' directions) and a few rows replaced (state changes)
        current = matrix + 1e-3 * rng.standard_normal(matrix.shape) / np.sqrt(size)
        changed = rng.choice(size, 2, replace=False)
        current[changed] = rng.standard_normal((2, size)) / np.sqrt(size) + 4.0 * np.eye(size)[changed]
        states = states.copy()
        states[changed] = 3 - states[changed]
        expected = np.linalg.solve(current, rhs)
        solution = solver.solve(current.copy(), rhs, keys, states, previous, TOLERANCE)
        assert np.allclose(solution, expected, atol=TOLERANCE)
        previous = solution
    # the first system: single-precision factors and GMRES on them; then up to 6 points changed since that
    # factorization (a rank-6 change plus small ones): GMRES with it each time, never a double-precision LU
    assert solver.factorizations == 1 and solver.krylov_solves == 4 and solver.double_precision == 0


def test_reused_factorization_serves_a_system_with_fewer_unknowns():
    size = 700
    solver = NewtonLinearSolver(direct_size=100)
    matrix, rhs = system(size, 6)
    keys, states = np.arange(size) * 3, np.ones(size, dtype=int)
    solver.solve(matrix.copy(), rhs, keys, states, np.zeros(size), TOLERANCE)
    kept = np.delete(np.arange(size), [10, 400])          # two points left the contact
    smaller = matrix[np.ix_(kept, kept)]
    solution = solver.solve(smaller.copy(), rhs[kept], keys[kept], states[kept], np.zeros(kept.size), TOLERANCE)
    assert np.allclose(solution, np.linalg.solve(smaller, rhs[kept]), atol=TOLERANCE)
    assert solver.factorizations == 1


def test_singular_system_raises():
    size = 700
    matrix, rhs = system(size, 7)
    matrix[5] = 0.0
    with pytest.raises(np.linalg.LinAlgError, match="singular"):
        NewtonLinearSolver(direct_size=100).solve(matrix, rhs, np.arange(size), np.ones(size, int),
                                                  np.zeros(size), TOLERANCE)


def test_eliminating_slip_directions_gives_the_full_solution():
    # a system whose sliding points' rows, projected on their slip direction d, read t.d - mu lambda = 0 (as the
    # Alart-Curnier linearisation gives): the reduced system must have the same solution
    points_count, mu = 40, 0.6
    size = 3 * points_count + 2                           # plus two body unknowns
    matrix, rhs = system(size, 8)
    rng = np.random.default_rng(9)
    sliding = np.sort(rng.choice(points_count, 15, replace=False))
    angle = rng.uniform(0, 2 * np.pi, sliding.size)
    direction = np.column_stack([np.cos(angle), np.sin(angle)])
    across = np.column_stack([-direction[:, 1], direction[:, 0]])
    for k, d, p in zip(sliding, direction, across):
        along_row = np.zeros(size)
        along_row[3 * k:3 * k + 3] = [d[0], d[1], -mu]
        across_row = rng.standard_normal(size) / np.sqrt(size) + 4.0 * (p[0] * np.eye(size)[3 * k]
                                                                         + p[1] * np.eye(size)[3 * k + 1])
        across_rhs = rng.standard_normal()
        matrix[3 * k] = d[0] * along_row + p[0] * across_row
        matrix[3 * k + 1] = d[1] * along_row + p[1] * across_row
        rhs[3 * k], rhs[3 * k + 1] = p[0] * across_rhs, p[1] * across_rhs
    expected = np.linalg.solve(matrix, rhs)
    reduced, reduced_rhs, kept = eliminate_slip_directions(matrix.copy(), rhs, sliding, direction, mu)
    assert reduced.shape == (size - sliding.size,) * 2
    solution = restore_slip_directions(np.linalg.solve(reduced, reduced_rhs), kept, size, sliding, direction, mu)
    # round-off of two LU solves of condition ~10 systems
    assert np.allclose(solution, expected, atol=1e-12)
    # and the current iterate maps into the reduced unknowns and back unchanged
    guess = rotate_slip_guess(expected, kept, sliding, direction)
    assert np.allclose(restore_slip_directions(guess, kept, size, sliding, direction, mu), expected, atol=1e-12)
