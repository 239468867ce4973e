"""An independent computation of the coupled frictional half-space reference that tests/test_halfspace.py checks
``contact.halfspace`` against: ``python tests/data/coupled_halfspace_reference.py`` rewrites
``coupled_halfspace_reference.json`` beside it (3.3 CPU minutes; ``--spacing 0.053`` for the a/20 grid of
docs/coupled_reference.md, not timed here: 4x the cells).

What is shared with ``contact.halfspace`` is only the problem: a rigid sphere (R = 10 mm) pressed into an elastic
half-space (E = 1 MPa, nu, mu = 0.5) to P = 0.2 N (in 16 equal force steps with friction on, or in one without),
then sheared along x by force (``CASES``), with the surface in square cells of uniform traction (whole plane, cell centres at x = i h, y = (j + 1/2) h)
and the incremental Coulomb law (a cell sticks when its tangential displacement follows the body's, else slides
against its traction at mu p). How it is solved is not shared:

- influence coefficients by Gauss-Legendre quadrature of the Boussinesq-Cerruti point-load kernels over each cell
  (subdivided near the loaded cell; the self-cell integrals by symmetry and the square's closed form 8 a asinh(1)),
  not the corner sums of closed-form antiderivatives;
- the contact by a staggered (Panagiotopoulos) process of two active-set solves per round - the normal problem at
  fixed shear tractions, then the tangential problem at fixed pressure with slip directions iterated to a fixed
  point - not one semi-smooth Newton method on the Alart-Curnier equations.

Both converge to the same discrete solution when both are right; the test asserts that they do.
"""

from __future__ import annotations

import argparse
import functools
import json
import math
from pathlib import Path

import numpy as np

RADIUS, FORCE, MU, YOUNGS = 10.0, 0.2, 0.5, 1.0
# the paths of tests/test_halfspace.py (friction is path dependent: the same steps, or another answer): name ->
# (nu, press steps, friction during the press, shear load ratios Q / (mu P))
CASES = {"nu=0": (0.0, 16, True, (0.5,)), "nu=0.3": (0.3, 16, True, (0.5,)),
         "nu=0.3, frictionless press": (0.3, 1, False, (0.2, 0.5, 0.8))}
TOLERANCE = 1e-12          # relative change of the tractions between rounds
GAUSS = np.polynomial.legendre.leggauss(6)


def _cell_integral(kernel, x, y, spacing, split):
    """Integral of kernel(X, Y) over the square of side ``spacing`` centred at (x, y), split x split sub-squares of
    6 x 6 Gauss-Legendre points each."""
    points, weights = GAUSS
    sub = spacing / split
    offsets = (np.arange(split) - (split - 1) / 2) * sub
    local = 0.5 * sub * points
    xs = (x + offsets[:, None] + local[None, :]).ravel()
    ys = (y + offsets[:, None] + local[None, :]).ravel()
    w = np.tile(0.5 * sub * weights, split)
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    return float((w[:, None] * w[None, :] * kernel(X, Y)).sum())


def influence(nu: float, shear_modulus: float, spacing: float, reach: int) -> np.ndarray:
    """(3, 3, 2 reach + 1, 2 reach + 1) displacement [mm/N] at cell offsets from a unit force spread over a cell
    (component a from force component b; z up, a pressing force has F_z < 0)."""
    kernels = {"1/rho": lambda X, Y: 1 / np.hypot(X, Y), "xx": lambda X, Y: X * X / np.hypot(X, Y) ** 3,
               "yy": lambda X, Y: Y * Y / np.hypot(X, Y) ** 3, "xy": lambda X, Y: X * Y / np.hypot(X, Y) ** 3,
               "x/rho2": lambda X, Y: X / (X * X + Y * Y), "y/rho2": lambda X, Y: Y / (X * X + Y * Y)}
    size = 2 * reach + 1
    table = {name: np.zeros((size, size)) for name in kernels}
    for i in range(-reach, reach + 1):
        for j in range(-reach, reach + 1):
            if i == 0 and j == 0:                       # self cell: odd kernels vanish, xx = yy = half of 1/rho
                self_inverse = 4.0 * spacing * math.asinh(1.0)
                table["1/rho"][reach, reach] = self_inverse
                table["xx"][reach, reach] = table["yy"][reach, reach] = 0.5 * self_inverse
                continue
            split = 8 if max(abs(i), abs(j)) <= 2 else 1
            for name, kernel in kernels.items():
                table[name][i + reach, j + reach] = _cell_integral(kernel, i * spacing, j * spacing, spacing, split)
    area = spacing**2
    t = 1.0 / (2 * math.pi * shear_modulus * area)
    c = (1 - 2 * nu) / (4 * math.pi * shear_modulus * area)
    result = np.zeros((3, 3, size, size))
    result[0, 0] = t * ((1 - nu) * table["1/rho"] + nu * table["xx"])
    result[1, 1] = t * ((1 - nu) * table["1/rho"] + nu * table["yy"])
    result[0, 1] = result[1, 0] = t * nu * table["xy"]
    result[2, 2] = t * (1 - nu) * table["1/rho"]
    result[0, 2], result[1, 2] = c * table["x/rho2"], c * table["y/rho2"]
    result[2, 0], result[2, 1] = -result[0, 2], -result[1, 2]
    return result


def solve(nu: float, spacing: float, press_steps: int, frictional_press: bool, shear_ratios) -> list[dict]:
    """The load path; per increment the cell contact radius, stick ratio, peak pressure and tangential force (a
    frictionless press has no stuck cells: they slide freely, as ``contact._newton`` reports them)."""
    shear_modulus = YOUNGS / (2 * (1 + nu))
    e_star = YOUNGS / (1 - nu**2)
    hertz_radius = (3 * FORCE * RADIUS / (4 * e_star)) ** (1 / 3)
    half = int(math.ceil(1.4 * hertz_radius / spacing))
    i, j = np.meshgrid(np.arange(-half, half + 1), np.arange(-half, half), indexing="ij")
    i, j = i.ravel(), j.ravel()
    xy = np.column_stack([i * spacing, (j + 0.5) * spacing])
    n = xy.shape[0]
    table = influence(nu, shear_modulus, spacing, 2 * half + 1)
    reach = 2 * half + 1
    di, dj = i[:, None] - i[None, :] + reach, j[:, None] - j[None, :] + reach
    C = np.block([[table[a, b][di, dj] for b in range(3)] for a in range(3)])     # (3n, 3n): x block, y, z
    gap0 = RADIUS - np.sqrt(RADIUS**2 - np.sum(xy**2, axis=1))           # the sphere's surface above each cell
    p, t = np.zeros(n), np.zeros((n, 2))
    u_previous, shift = np.zeros((n, 2)), np.zeros(2)
    depth = 0.0
    results = []
    loads = [("press", FORCE * k / press_steps, 0.0) for k in range(1, press_steps + 1)]
    loads += [("shear", FORCE, r * MU * FORCE) for r in shear_ratios]
    for kind, normal_force, tangential_force in loads:
        shift_previous = shift.copy()
        for _ in range(500):                              # rounds of the staggered process
            p_old, t_old = p.copy(), t.copy()
            p, depth = _normal(C, gap0, t, normal_force, p, n)
            if kind == "press" and not frictional_press:
                stick = np.zeros(n, bool)                  # t stays 0: one normal solve is the answer
            else:
                t, stick, shift = _tangential(C, p, t, u_previous, shift_previous, n,
                                              tangential_force if kind == "shear" else None)
            change = max(np.abs(p - p_old).max(), np.abs(t - t_old).max()) / FORCE
            if change < TOLERANCE:
                break
        else:
            raise RuntimeError(f"{kind} {normal_force}, {tangential_force}: the staggered process did not converge")
        u = _displacement(C, p, t, n)
        u_previous = u[:, :2]
        contact = p > 0
        area = spacing**2
        hertz_p0 = 3 * FORCE / (2 * math.pi * hertz_radius**2)
        results.append({"kind": kind, "normal_force": float(p.sum()), "tangential_force": float(t[:, 0].sum()),
                        "contact_radius": math.sqrt(contact.sum() * area / math.pi),
                        "stick_ratio": math.sqrt((contact & stick).sum() / contact.sum()),
                        "peak_pressure_ratio": float(p.max() / area / hertz_p0),
                        "contact_radius_ratio": math.sqrt(contact.sum() * area / math.pi) / hertz_radius,
                        "depth": depth})
    return results


def _displacement(C, p, t, n):
    forces = np.concatenate([t[:, 0], t[:, 1], -p])
    return (C @ forces).reshape(3, n).T


def _normal(C, gap0, t, normal_force, p, n):
    """Pressure >= 0 and depth with sum p = P, gap >= 0 and p gap = 0, at the given shear tractions (active set)."""
    z = slice(2 * n, 3 * n)
    from_shear = C[z, :2 * n] @ np.concatenate([t[:, 0], t[:, 1]])           # u_z of the shear tractions
    active = p > 0 if np.any(p > 0) else gap0 <= np.sort(gap0)[9]
    for _ in range(200):
        index = np.flatnonzero(active)
        m = index.size
        system = np.zeros((m + 1, m + 1))
        system[:m, :m] = C[z, z][np.ix_(index, index)]     # u_z = from_shear - C_zz p; gap = gap0 - d - u_z = 0
        system[:m, m] = -1.0
        system[m, :m] = 1.0
        rhs = np.concatenate([-(gap0[index] - from_shear[index]), [normal_force]])
        solution = np.linalg.solve(system, rhs)
        pressure = np.zeros(n)
        pressure[index] = solution[:m]
        depth = solution[m]
        gap = gap0 - depth - (from_shear - C[z, z] @ pressure)
        negative = active & (pressure < 0)
        penetrating = ~active & (gap < -1e-14 * depth)
        if not negative.any() and not penetrating.any():
            return pressure, depth
        active = (active & ~negative) | penetrating
    raise RuntimeError("the normal active set did not settle")


def _tangential(C, p, t, u_previous, shift_previous, n, tangential_force):
    """Shear tractions at the given pressure and the body's x shift. At fixed pressure the incremental Coulomb law is
    the minimum of 1/2 t.A t - b.t over the discs |t_i| <= mu p_i (Kalker's principle of maximum dissipation: the
    minimum's conditions are w_i = 0 inside a disc and w_i against t_i on its rim, w = A t - b the slip increment),
    solved by projected Gauss-Seidel, one cell at a time: A's 2 x 2 diagonal blocks are multiples of I (square cells),
    so the projection onto the disc is the exact minimum over that cell. A tangential force target sets the shift by
    the secant method on sum t_x(shift), which increases with the shift."""
    contact = np.flatnonzero(p > 0)
    m = contact.size
    xy = np.concatenate([contact, contact + n])                       # rows of t_x, then t_y
    A = C[np.ix_(xy, xy)]
    b_press = -(C[np.ix_(xy, np.arange(2 * n, 3 * n))] @ -p)         # u_t of the pressure, moved to the right side
    limit = MU * p[contact]
    start = np.concatenate([t[contact, 0], t[contact, 1]])

    def minimum(shift):
        motion = np.concatenate([u_previous[contact, 0] + shift[0] - shift_previous[0],
                                 u_previous[contact, 1] + shift[1] - shift_previous[1]])
        return _projected_gauss_seidel(A, motion + b_press, limit, start.copy())

    shift = shift_previous.copy()
    if tangential_force is None:
        solution = minimum(shift)
    else:                                       # secant on the x shift: sum t_x grows with it
        def excess(dx):
            return minimum(shift_previous + [dx, 0.0])[:m].sum() - tangential_force

        x0, x1 = 0.0, tangential_force * A[:m, :m].mean()            # u_x of Q spread evenly: a first guess
        f0, f1 = excess(x0), excess(x1)
        for _ in range(200):
            if abs(f1) < 1e-14 * FORCE or f1 == f0:
                break
            x0, x1, f0 = x1, x1 - f1 * (x1 - x0) / (f1 - f0), f1
            f1 = excess(x1)
        shift = shift_previous + [x1, 0.0]
        solution = minimum(shift)
    traction = np.zeros((n, 2))
    traction[contact, 0], traction[contact, 1] = solution[:m], solution[m:]
    u = _displacement(C, p, traction, n)[:, :2]
    slip = np.linalg.norm(u - u_previous - (shift - shift_previous), axis=1)
    # stuck: inside its disc (a cell on the rim that does not move counts as stuck, as the Newton solver's status)
    stuck = np.zeros(n, bool)
    stuck[contact] = (np.linalg.norm(traction[contact], axis=1) < limit * (1 - 1e-8)) | (slip[contact] <= 1e-12 *
                                                                                          max(slip.max(), 1e-300))
    return traction, stuck, shift


def _projected_gauss_seidel(A, b, limit, t, over_relaxation=1.6, tolerance=1e-12, sweeps=20000):
    """argmin 1/2 t.A t - b.t over |(t_k, t_{k+m})| <= limit_k, from ``t``: per cell the unconstrained minimum of its
    2-vector, relaxed, projected onto its disc; sweeps until no cell moves by more than tolerance x max(limit)."""
    if limit.size == 0:
        return t
    if not _compiled_sweeps()(np.ascontiguousarray(A), b, limit, t, over_relaxation, tolerance * limit.max(), sweeps):
        raise RuntimeError("projected Gauss-Seidel did not converge")
    return t


@functools.cache
def _compiled_sweeps():
    from numba import njit

    return njit(cache=False)(_sweeps)


def _sweeps(A, b, limit, t, over_relaxation, scale, sweeps):
    """The sweeps of ``_projected_gauss_seidel`` on t in place (compiled); True when converged."""
    m = limit.size
    residual = b - A @ t                                      # kept current: one rank-2 update per changed cell
    for _ in range(sweeps):
        largest = 0.0
        for k in range(m):
            trial_x = t[k] + over_relaxation * residual[k] / A[k, k]
            trial_y = t[k + m] + over_relaxation * residual[k + m] / A[k, k]
            norm = math.sqrt(trial_x * trial_x + trial_y * trial_y)
            if norm > limit[k]:
                trial_x, trial_y = trial_x * limit[k] / norm, trial_y * limit[k] / norm
            change_x, change_y = trial_x - t[k], trial_y - t[k + m]
            if change_x != 0.0 or change_y != 0.0:
                for row in range(2 * m):
                    residual[row] -= A[row, k] * change_x + A[row, k + m] * change_y
                t[k], t[k + m] = trial_x, trial_y
                largest = max(largest, abs(change_x), abs(change_y))
        if largest < scale:
            return True
    return False


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spacing", type=float, default=0.1, help="cell size h [mm] (default 0.1, the test's)")
    parser.add_argument("--out", type=Path, default=Path(__file__).with_suffix(".json"))
    args = parser.parse_args(argv)
    document = {"spacing": args.spacing, "radius": RADIUS, "force": FORCE, "friction_coefficient": MU,
                "youngs_modulus": YOUNGS,
                "cases": {name: {"poissons_ratio": nu, "press_steps": steps, "frictional_press": frictional,
                                 "shear_ratios": list(ratios), "increments": solve(nu, args.spacing, steps, frictional,
                                                                                   ratios)}
                          for name, (nu, steps, frictional, ratios) in CASES.items()}}
    args.out.write_text(json.dumps(document, indent=1) + "\n")
    for name, case in document["cases"].items():
        pressed = case["increments"][case["press_steps"] - 1]
        print(f"{name}: after the press c/a = {pressed['stick_ratio']:.4f}, p_max / p0 = "
              f"{pressed['peak_pressure_ratio']:.4f}, a / a_H = {pressed['contact_radius_ratio']:.4f}; c/a under "
              f"shear {[round(row['stick_ratio'], 4) for row in case['increments'][case['press_steps']:]]}")


if __name__ == "__main__":
    main()
