"""One increment of frictional contact with a finite-strain (compressible Neo-Hookean) gel: semi-smooth Newton on
every free dof.

The linear gel's increment is solved on the condensed surface compliance (``contact._newton``): K is constant, so
the contact points' displacements are C f. A finite-strain gel's stiffness changes with u, so here the unknowns are
the displacement of every free dof, the contact forces of the points in contact and the force-controlled body
coordinates, and each Newton iteration solves the uncondensed sparse system

    [ K_T(u)     -B^T S     0  ] [du]     [ f_int(u) - B^T S y        ]
    [ D_u         D_y      D_b ] [dy] = - [ Alart-Curnier residuals   ]
    [ 0           E_y       0  ] [db]     [ body equilibrium          ]

with the same Alart-Curnier equations as the linear solver (the circular Coulomb cone, the same generalized
derivatives), K_T the Neo-Hookean tangent stiffness (``fem.hyperelastic``) and B^T S y the contact forces on the
gel's dofs. Why not a fixed point on the linear compliance, which keeps every cached column: tried first, it needed
15-40 Anderson steps per frictionless press increment and did not converge in 200 under shear near gross slip
(stick-slip switches make the map non-smooth, and the compressed gel's tangent differs from K by its pressure).

The gap is paired along z at each point's moved position, exact for a plane body only (``contact.scene.Scene``
refuses a sphere); an increment's twist turns the points about the lever arms they have at its start.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from contact._newton import (ON_CONE, STAGNATION_FACTOR, STAGNATION_ITERATIONS, BodyControl, ContactNotConverged,
                             ContactState, _project_disc, point_status)
from fem.elasticity import ElasticModel
from fem.hyperelastic import InvertedElement, displacement_gradient, internal_force, tangent_stiffness
from fem.linear_solver import solve_sparse

__all__ = ["FiniteStrainGel", "solve_finite_strain_increment"]

CYCLE = 8       # Newton iterations without a new lowest residual after which the increment counts as cycling
BACKTRACKS = 4  # halvings of a Newton step that raises the residual
# the Alart-Curnier parameter is this share of the linear solver's (2 E* sqrt(A / pi) per point): it changes the
# Newton path, not the solution. At the full value a bump sheared at 1.5 N stalled from Q/(mu P) = 0.86 on (a point
# at the contact's edge switching between open and closed every iteration; 12 Newton iterations per increment and
# bisections before); at 0.1 it took 6 iterations per increment to 0.92, and the twist 5-6 (was 8-16)
AUGMENTATION_SCALE = 0.1


@dataclass(frozen=True)
class _Points:
    """The candidate points of one increment, fixed over its Newton iterations."""

    rows: np.ndarray                  # (n, 3) free-vector rows of each point's dofs, -1 where held
    held_y: np.ndarray                # (n,) u_y held by a symmetry plane: t_y = 0 there
    lever: np.ndarray                 # (n, 2) [mm] lever arms about the body's axis
    r: np.ndarray                     # (n,) Alart-Curnier parameters [N/mm]
    mu: float                         # friction coefficient [-]
    frictional: bool


@dataclass(frozen=True)
class _Body:
    """Which body coordinates are unknowns (force-controlled) in one increment, and the control that sets them."""

    control: BodyControl
    depth_free: bool
    shift_free: bool
    angle_free: bool
    shift_components: np.ndarray      # the shift's components that are unknowns (x only with a mirror plane)


@dataclass
class FiniteStrainGel:
    """A meshed gel with the Neo-Hookean law, and the counts of its Newton work over a path."""

    model: ElasticModel
    youngs_modulus: float
    poissons_ratio: float
    iterations: int = 0               # Newton steps, each one tangent assembly and one sparse factorization

    def __post_init__(self):
        if self.model.volumetric != "standard":
            raise ValueError(f"mesh.volumetric={self.model.volumetric!r}: the finite-strain gel needs 'standard'")

    def internal(self, u_free: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """f_int on the free dofs and on the fixed dofs [N], and grad u (for ``tangent``); ContactNotConverged where
        an element turns inside out (contact._controls then bisects the increment)."""
        model = self.model
        try:
            gradient = displacement_gradient(model, model.full_vector(u_free))
        except InvertedElement as error:
            raise ContactNotConverged(str(error), []) from None
        force = internal_force(model, gradient, self.youngs_modulus, self.poissons_ratio)
        return force[model.free_dofs], force[model.fixed_dofs], gradient

    def tangent(self, gradient: np.ndarray) -> sp.coo_matrix:
        """K_T between the free dofs [N/mm] (COO) at the displacement gradient ``internal`` returned."""
        return tangent_stiffness(self.model, gradient, self.youngs_modulus, self.poissons_ratio, self.model.free_dofs)


def solve_finite_strain_increment(gel: FiniteStrainGel, candidates: np.ndarray, gap0: np.ndarray, lever: np.ndarray,
                                  augmentation: np.ndarray, friction_coefficient: float, previous: ContactState,
                                  control: BodyControl, seed_depth: float | None = None, tolerance: float = 1e-10,
                                  max_iterations: int = 60, mirror_y: bool = False,
                                  frictional: bool = True) -> tuple[ContactState, int, list[float]]:
    """Solve one increment with the finite-strain gel; the arguments are those of ``contact._newton.solve_increment``
    (its compliance replaced by the gel and the candidate points' indices into ``model.top``). Returns the converged
    state (with ``gel_displacement`` and ``fixed_force``), the Newton iterations and the residual history (relative
    to the force the contact carries)."""
    model = gel.model
    mu, r = friction_coefficient, AUGMENTATION_SCALE * augmentation
    n = candidates.size
    free_position = np.full(model.n_dofs, -1)
    free_position[model.free_dofs] = np.arange(model.free_dofs.size)
    point_rows = free_position[model.top.dofs[candidates]]             # (n, 3) free-vector rows, -1 where held
    held_y = point_rows[:, 1] < 0                                      # u_y = 0 on a symmetry plane: t_y = 0 there
    n_free = model.free_dofs.size

    depth_free = control.depth is None
    shift_free = frictional and control.shift is None
    angle_free = frictional and control.angle is None
    shift_components = np.array([0] if mirror_y else [0, 1])
    points = _Points(point_rows, held_y, lever, r, mu, frictional)
    body = _Body(control, depth_free, shift_free, angle_free, shift_components)
    depth = previous.depth if depth_free else float(control.depth)
    if depth_free and seed_depth is not None and not np.any(previous.normal_force > 0):
        depth = seed_depth
    shift = previous.shift.copy() if (shift_free or control.shift is None) else np.asarray(control.shift, float)
    angle = previous.angle if (angle_free or control.angle is None) else float(control.angle)
    u = np.zeros(n_free) if previous.gel_displacement is None else previous.gel_displacement.copy()
    lam, tan = previous.normal_force.copy(), previous.tangential_force.copy()
    omega = previous.displacement[:, :2] - previous.shift - previous.angle * lever
    force_scale = max(abs(control.normal_force or 0.0), float(previous.normal_force.sum()))

    def at_points(u_free):
        """The candidate points' displacement (n, 3) [mm], 0 where a dof is held."""
        return np.where(point_rows >= 0, u_free[np.maximum(point_rows, 0)], 0.0)

    def contact_load(lam, tan):
        """Contact forces on the free dofs [N]: t on x, y and -lambda on z (the body presses the gel down)."""
        load = np.zeros(n_free)
        values = np.column_stack([tan, -lam]) if frictional else np.column_stack([np.zeros((n, 2)), -lam])
        kept = point_rows >= 0
        np.add.at(load, point_rows[kept], values[kept])
        return load

    def evaluate(u, lam, tan, depth, shift, angle) -> dict:
        """The residuals of an iterate (open points: lambda = 0 and t = 0) and its norm relative to the load."""
        internal, fixed_force, gradient = gel.internal(u)
        displacement = at_points(u)
        gap = gap0 - depth - displacement[:, 2]
        slip = displacement[:, :2] - omega - shift - angle * lever
        lam_hat = lam - r * gap
        trial = tan - r[:, None] * slip
        radius = mu * np.maximum(0.0, lam_hat)
        tangential = tan - _project_disc(trial, radius) if frictional else np.zeros((n, 2))
        tangential[held_y, 1] = tan[held_y, 1]
        body = []
        if depth_free:
            body.append(lam.sum() - control.normal_force)
        if shift_free:
            body.extend((tan.sum(axis=0) - np.asarray(control.tangential_force, float))[shift_components])
        if angle_free:
            body.append((lever * tan).sum() - control.torque)
        equilibrium = internal - contact_load(lam, tan)
        scale = max(force_scale, float(np.maximum(lam, 0.0).sum()), 1e-300)
        norm = float(np.linalg.norm(np.concatenate([equilibrium, lam - np.maximum(0.0, lam_hat), tangential.ravel(),
                                                    np.asarray(body, float)]))) / scale
        return dict(state=(u, lam, tan, depth, shift, angle), norm=norm, equilibrium=equilibrium, gap=gap,
                    slip=slip, lam_hat=lam_hat, trial=trial, displacement=displacement,
                    fixed_force=fixed_force, gradient=gradient)

    history: list[float] = []
    current = evaluate(u, lam, tan, depth, shift, angle)
    for iteration in range(1, max_iterations + 1):
        history.append(current["norm"])
        u, lam, tan, depth, shift, angle = current["state"]
        lam_hat, trial = current["lam_hat"], current["trial"]
        if current["norm"] < tolerance and iteration > 1:
            status = point_status(lam_hat, trial if frictional else None, mu)
            return (ContactState(lam.copy(), tan.copy(), current["displacement"], depth,
                                 np.asarray(shift, float).copy(), angle, status, u.copy(), current["fixed_force"]),
                    iteration - 1, history)
        if len(history) >= STAGNATION_ITERATIONS and (min(history[1:]) > STAGNATION_FACTOR * history[1] or
                                                      min(history[-CYCLE:]) > 0.5 * min(history[:-CYCLE])):
            # not halving the first residual, or not the lowest one in CYCLE iterations: the active sets cycle (a
            # point switching between stick and slip each iteration); contact._controls bisects the increment
            raise ContactNotConverged(f"stagnated: {len(history)} Newton iterations, the last {CYCLE} without "
                                      f"halving the lowest residual before them", history)
        contact = np.flatnonzero(lam_hat > 0)
        if contact.size == 0:
            raise ContactNotConverged("the body does not touch the gel (no point has a closed gap); increase the "
                                      "depth or the normal force", history)
        gel.iterations += 1
        step = _newton_step(gel.tangent(current["gradient"]), current, contact, points, body)
        target_lam, target_tan = np.zeros(n), np.zeros((n, 2))       # open points' forces go to zero
        target_lam[contact] = lam[contact] + step["lam"]
        if frictional:
            target_tan[contact] = tan[contact] + step["tan"]
        body_step = (step.get("depth", 0.0), _spread(step.get("shift", ()), shift_components if "shift" in step
                                                     else np.zeros(0, dtype=int)), step.get("angle", 0.0))
        closed = np.zeros(n)
        closed[contact] = 1.0
        # backtracking on the residual norm: a full step that raises it (the active sets of points at the stick-
        # slip or contact edge switching back and forth) is halved, up to BACKTRACKS times
        for halving in range(BACKTRACKS + 1):
            fraction = 0.5 ** halving
            try:
                # open points' forces are zero outright, not a fraction of the way (a point at the contact's edge
                # left with a small negative force by a shortened step came back into contact every other step)
                candidate = evaluate(u + fraction * step["u"], closed * (lam + fraction * (target_lam - lam)),
                                     closed[:, None] * (tan + fraction * (target_tan - tan)),
                                     depth + fraction * body_step[0],
                                     shift + fraction * body_step[1], angle + fraction * body_step[2])
            except ContactNotConverged:                              # inverted elements: a shorter step
                continue
            if candidate["norm"] < current["norm"] or halving == BACKTRACKS:
                break
        else:
            raise ContactNotConverged("every step length of the Newton direction turns an element inside out",
                                      history)
        current = candidate
    raise ContactNotConverged(f"no convergence in {max_iterations} Newton iterations", history)


def _spread(values: np.ndarray, components: np.ndarray) -> np.ndarray:
    """A 2-vector with ``values`` at ``components`` and 0 elsewhere."""
    out = np.zeros(2)
    out[components] = values
    return out


def _newton_step(tangent: sp.coo_matrix, iterate: dict, contact: np.ndarray, points: _Points, body: _Body) -> dict:
    """One Newton correction from ``iterate`` (what ``evaluate`` returned): assemble the sparse system over (du, the
    contact points' (t, lambda), body) and solve. ``contact``: the points in contact.

    Open points' forces are set to zero outright (their equations are lambda = 0, t = 0), so their load leaves the
    equilibrium residual here."""
    lam, tan = iterate["state"][1:3]
    equilibrium, gap, slip = iterate["equilibrium"], iterate["gap"], iterate["slip"]
    lam_hat, trial = iterate["lam_hat"], iterate["trial"]
    point_rows, held_y, lever, r, mu, frictional = (points.rows, points.held_y, points.lever, points.r, points.mu,
                                                    points.frictional)
    control, depth_free, shift_free, angle_free = body.control, body.depth_free, body.shift_free, body.angle_free
    shift_components = body.shift_components
    n_free = tangent.shape[0]
    m = contact.size
    n_comp = 3 if frictional else 1
    body_names = (["depth"] if depth_free else []) + (["shift"] * shift_components.size if shift_free else []) \
        + (["angle"] if angle_free else [])
    size = n_free + n_comp * m + len(body_names)
    force_col = n_free + np.arange(m) * n_comp                      # first unknown of each contact point
    lam_col = force_col + (n_comp - 1)
    body_col = n_free + n_comp * m + np.arange(len(body_names))
    rows, cols, vals = [], [], []

    def add(i, j, v):
        i, j, v = np.broadcast_arrays(np.asarray(i), np.asarray(j), np.asarray(v, float))
        rows.append(i.ravel()), cols.append(j.ravel()), vals.append(v.ravel())

    add(tangent.row, tangent.col, tangent.data)
    # equilibrium rows: K_T du - (contact load of the new forces) = -(f_int - contact load of the present forces),
    # with open points' present forces dropped (they become zero)
    open_points = np.setdiff1d(np.arange(lam.size), contact)
    rhs = np.zeros(size)
    dropped = np.zeros(n_free)
    point_z = point_rows[contact, 2]
    add(point_z, lam_col, 1.0)                                      # -(-lambda): the gel is pressed down
    if frictional:
        for a in range(2):
            kept = point_rows[contact, a] >= 0
            add(point_rows[contact, a][kept], force_col[kept] + a, -1.0)
        for a in range(2):
            kept = point_rows[open_points, a] >= 0
            np.add.at(dropped, point_rows[open_points, a][kept], tan[open_points, a][kept])
    np.add.at(dropped, point_rows[open_points, 2], -lam[open_points])
    rhs[:n_free] = -(equilibrium + dropped)
    # normal rows: r (g + dg) = 0 with dg = -du_z - d(depth)
    rc = r[contact]
    add(lam_col, point_z, -rc)
    if depth_free:
        add(lam_col, body_col[0], -rc)
    rhs[lam_col] = -rc * gap[contact]
    if frictional:
        z = trial[contact]
        z_norm = np.linalg.norm(z, axis=1)
        sliding = (z_norm > mu * lam_hat[contact] * (1.0 - ON_CONE)) | (mu == 0.0)
        direction = z / np.maximum(z_norm, 1e-300)[:, None]
        perp = np.eye(2)[None] - direction[:, :, None] * direction[:, None, :]
        alpha = np.where(sliding, mu * lam_hat[contact] / np.maximum(z_norm, 1e-300), 0.0)
        # the linear solver's generalized derivatives (contact._newton): stick r dw = -r w; slip
        # (I - alpha P) dt + alpha r P dw - mu d d(lambda_hat) = -(t - mu lambda_hat d)
        w_coef = np.where(sliding[:, None, None], (alpha * rc)[:, None, None] * perp, rc[:, None, None] * np.eye(2))
        t_coef = np.where(sliding[:, None, None], np.eye(2)[None] - alpha[:, None, None] * perp, 0.0)
        lam_coef = np.where(sliding[:, None], -mu * direction, 0.0)
        residual = np.where(sliding[:, None], tan[contact] - mu * np.maximum(lam_hat[contact], 0.0)[:, None]
                            * direction, rc[:, None] * slip[contact])
        shift_index = {a: body_col[int(depth_free) + k] for k, a in enumerate(shift_components)} if shift_free else {}
        for a in range(2):
            row = force_col + a
            for b in range(2):
                kept = point_rows[contact, b] >= 0
                add(row[kept], point_rows[contact, b][kept], w_coef[kept, a, b])     # dw_b = du_b - ...
                add(row, force_col + b, t_coef[:, a, b])
                if b in shift_index:
                    add(row, shift_index[b], -w_coef[:, a, b])
                if angle_free:
                    add(row, body_col[-1], -w_coef[:, a, b] * lever[contact, b])
            add(row, lam_col, lam_coef[:, a])
            # the cone's radius mu lambda_hat moves with the gap too: d lambda_hat = d lambda + r (du_z + d depth)
            add(row, point_z, rc * lam_coef[:, a])
            if depth_free:
                add(row, body_col[0], rc * lam_coef[:, a])
            rhs[row] = -residual[:, a]
        # t_y = 0 where u_y is held by the symmetry plane
        held = np.flatnonzero(held_y[contact])
        matrix_rows = force_col[held] + 1
        if held.size:
            rhs[matrix_rows] = -tan[contact[held], 1]
    # body equilibrium rows
    k = 0
    if depth_free:
        add(body_col[k], lam_col, 1.0)
        rhs[body_col[k]] = control.normal_force - lam[contact].sum()
        k += 1
    if shift_free:
        for a in shift_components:
            add(body_col[k], force_col + a, 1.0)
            rhs[body_col[k]] = control.tangential_force[a] - tan[contact, a].sum()
            k += 1
    if angle_free:
        add(body_col[k], force_col, lever[contact, 0])
        add(body_col[k], force_col + 1, lever[contact, 1])
        rhs[body_col[k]] = control.torque - (lever[contact] * tan[contact]).sum()
    matrix = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(size, size))
    if frictional and held.size:                                    # replace the held points' t_y rows by dt_y = ...
        keep = np.ones(size)
        keep[matrix_rows] = 0.0
        matrix = sp.diags(keep) @ matrix + sp.csr_matrix((np.ones(held.size), (matrix_rows, matrix_rows)),
                                                          shape=(size, size))
    try:
        solution = solve_sparse(matrix.tocsr(), rhs)
    except RuntimeError as error:
        raise ContactNotConverged(f"singular Newton system ({error})", []) from None
    step = {"u": solution[:n_free], "lam": solution[lam_col]}
    if frictional:
        step["tan"] = np.column_stack([solution[force_col], solution[force_col + 1]])
    k = 0
    if depth_free:
        step["depth"] = float(solution[body_col[k]])
        k += 1
    if shift_free:
        step["shift"] = solution[body_col[k:k + shift_components.size]]
        k += shift_components.size
    if angle_free:
        step["angle"] = float(solution[body_col[k]])
    return step
