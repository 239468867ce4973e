"""One quasi-static increment of Coulomb frictional contact, by a semi-smooth Newton method on the condensed problem.

Unknowns are the nodal contact forces of the candidate points (normal lambda >= 0 pressing the gel, tangential t on
the gel) and the force-controlled rigid-body coordinates. Contact and friction are written as Alart-Curnier
equations (augmented Lagrangian complementarity functions):

    lambda - max(0, lambda - r g) = 0,       t - proj_{disc of radius mu max(0, lambda - r g)}(t - r w) = 0,

g the gap, w the slip increment of the gel relative to the body since the last converged increment (the circular
Coulomb cone, not a pyramid). Their generalized Newton derivative gives, per iteration, a linear system over the
points in contact only: open points have zero force and drop out. This is why the method suits the condensed
operator: a system of 3 x (points in contact) unknowns, exact line-search-free convergence once the stick/slip/open
sets stop changing (typically 4-10 iterations), and no penalty stiffness that would let stuck points creep.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from contact._newton_linear import (NewtonLinearSolver, eliminate_slip_directions, restore_slip_directions,
                                    rotate_slip_guess)
from contact.compliance import SurfaceCompliance

__all__ = ["ContactState", "BodyControl", "ContactNotConverged", "solve_increment"]

OPEN, STICK, SLIP = 0, 1, 2
ON_CONE = 1e-8       # relative distance to the friction cone within which a trial traction is on it (Newton tol 1e-10)
# An iteration that has not halved its first residual in this many steps is cycling between active sets (a large
# twist step of a bump array stays at ~0.1 for all 60 allowed steps, every time): give up early, so that the
# increment is bisected (contact._controls) after 12 instead of 60 wasted iterations. Converging increments halve
# their residual within 2-5 iterations.
STAGNATION_ITERATIONS = 12
STAGNATION_FACTOR = 0.5
FORCE_FLOOR = 1e-300   # N: keeps the residual's scale positive before any point carries a force


class ContactNotConverged(RuntimeError):
    """Raised when an increment does not converge; carries the residual history and the last iterate."""

    def __init__(self, message: str, residual_history: list[float]):
        super().__init__(f"{message}; residual history: " + ", ".join(f"{r:.3e}" for r in residual_history))
        self.residual_history = residual_history


@dataclass
class ContactState:
    """Converged state of the candidate points and the rigid body (all in mm, N, rad)."""

    normal_force: np.ndarray          # (n,) lambda_i >= 0 [N], force pressing point i into the gel
    tangential_force: np.ndarray      # (n, 2) [N], force of the body on the gel at point i
    displacement: np.ndarray          # (n, 3) gel displacement at the candidate points [mm]
    depth: float = 0.0                # body indentation: its lowest point is at z = -depth [mm]
    shift: np.ndarray = field(default_factory=lambda: np.zeros(2))   # body tangential displacement [mm]
    angle: float = 0.0                # body rotation about +z through the twist centre [rad]
    status: np.ndarray | None = None  # (n,) OPEN / STICK / SLIP
    # finite-strain gel only (contact._finite_strain): the displacement of every free dof [mm] and the gel's
    # internal force on the fixed (base) dofs [N]; the linear gel's follow from the contact forces
    gel_displacement: np.ndarray | None = None
    fixed_force: np.ndarray | None = None

    def copy(self) -> "ContactState":
        return ContactState(self.normal_force.copy(), self.tangential_force.copy(), self.displacement.copy(),
                            self.depth, self.shift.copy(), self.angle,
                            None if self.status is None else self.status.copy(),
                            None if self.gel_displacement is None else self.gel_displacement.copy(),
                            None if self.fixed_force is None else self.fixed_force.copy())


@dataclass(frozen=True)
class BodyControl:
    """Targets of one increment: each body coordinate is either prescribed or follows from a force target.

    ``normal_force`` / ``depth``, ``tangential_force`` / ``shift`` and ``torque`` / ``angle``: exactly one of each
    pair is not None; the other follows.
    """

    depth: float | None = None
    normal_force: float | None = None
    shift: tuple[float, float] | None = None
    tangential_force: tuple[float, float] | None = None
    angle: float | None = None
    torque: float | None = None


def _project_disc(vectors: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Project 2-vectors (n, 2) onto discs of radius (n,) >= 0."""
    norm = np.linalg.norm(vectors, axis=1)
    scale = np.where(norm > radius, radius / np.maximum(norm, 1e-300), 1.0)
    return vectors * scale[:, None]


def solve_increment(compliance: SurfaceCompliance, gap0: np.ndarray, lever: np.ndarray, augmentation: np.ndarray,
                    friction_coefficient: float, previous: ContactState, control: BodyControl,
                    seed_depth: float | None = None, tolerance: float = 1e-10,
                    max_iterations: int = 60, mirror_y: bool = False,
                    linear_solver: NewtonLinearSolver | None = None,
                    reduce_slip: bool = True) -> tuple[ContactState, int, list[float]]:
    """Solve one increment; return the converged state, the number of iterations and the residual history.

    gap0 : (n,) initial gap of each candidate point to the body at zero depth [mm]
    lever : (n, 2) rigid twist motion per radian at each point, (-(y - y_c), x - x_c) [mm/rad]
    augmentation : (n,) Alart-Curnier parameter r_i [N/mm], of the order of the local contact stiffness
    seed_depth : starting depth when the body is force-controlled and not yet in contact [mm]
    mirror_y : the points are the half y >= 0 of a body mirror-symmetric about y = 0: the body's y-shift is held
        at 0 (the other half balances the y-forces of this one)
    linear_solver : reuses LU factors across the Newton systems of a path (``contact._newton_linear``); pass one
        per path. None: a fresh dense LU solve per iteration.
    reduce_slip : drop the slip-direction force of each sliding point from the Newton system (it is mu lambda
        there; ``eliminate_slip_directions``): the same solution from a smaller system.
    """
    frictional = compliance.components == (0, 1, 2)
    n_comp = len(compliance.components)
    n = gap0.size
    mu = friction_coefficient
    r = augmentation

    # body unknowns: which coordinates follow from a force target
    depth_free = control.depth is None
    shift_free = frictional and control.shift is None
    angle_free = frictional and control.angle is None
    depth = previous.depth if depth_free else float(control.depth)
    if depth_free and seed_depth is not None and not np.any(previous.normal_force > 0):
        depth = seed_depth
    shift = previous.shift.copy() if (shift_free or control.shift is None) else np.asarray(control.shift, float)
    shift_components = np.array([0] if mirror_y else [0, 1])       # force-controlled shift components
    angle = previous.angle if (angle_free or control.angle is None) else float(control.angle)
    target_normal = control.normal_force
    target_tangential = None if control.tangential_force is None else np.asarray(control.tangential_force, float)
    target_torque = control.torque
    # the residual is a force [N] relative to the load the contact carries: the normal force target, the last
    # converged force or (``scale()``, for a press by depth from no contact) the present iterate's, never a floor
    # alone (a press by depth from rest measured its residual against 1e-12 N and stalled at 1e-5 x 1e-12 N of
    # round-off, far above any tolerance)
    force_scale = max(abs(target_normal or 0.0), float(previous.normal_force.sum()))

    def scale() -> float:
        """Force scale [N] of the residual: ``force_scale``, or the iterate's total normal force if larger."""
        return max(force_scale, float(np.maximum(lam, 0.0).sum()), FORCE_FLOOR)

    lam = previous.normal_force.copy()
    tan = previous.tangential_force.copy()
    u_prev_t = previous.displacement[:, :2]
    omega = u_prev_t - previous.shift - previous.angle * lever      # w = u_t - omega - shift - angle * lever

    def forces_flat(points):
        if frictional:
            return np.column_stack([tan[points], -lam[points]]).ravel()
        return -lam[points]

    def kinematics():
        # every point carrying a force in this iterate (Newton iterates may hold negative lambda)
        loaded = np.flatnonzero((lam != 0) | np.any(tan != 0, axis=1) if frictional else lam != 0)
        u = compliance.displacement(compliance.unknown_index(loaded), forces_flat(loaded)).reshape(n, n_comp)
        gap = gap0 - depth - u[:, -1]
        slip_inc = (u[:, :2] - omega - shift - angle * lever) if frictional else None
        return u, gap, slip_inc

    def residual(gap, slip_inc):
        lam_hat = lam - r * gap
        parts = [lam - np.maximum(0.0, lam_hat)]
        if frictional:
            parts.append((tan - _project_disc(tan - r[:, None] * slip_inc, mu * np.maximum(0.0, lam_hat))).ravel())
        body = []
        if depth_free:
            body.append(lam.sum() - target_normal)
        if shift_free:
            body.extend((tan.sum(axis=0) - target_tangential)[shift_components])
        if angle_free:
            body.append((lever * tan).sum() - target_torque)
        return float(np.linalg.norm(np.concatenate(parts + [np.asarray(body)]))) / scale()

    history: list[float] = []
    for iteration in range(1, max_iterations + 1):
        u, gap, slip_inc = kinematics()
        lam_hat = lam - r * gap
        contact = np.flatnonzero(lam_hat > 0)
        if iteration > 1:
            history.append(residual(gap, slip_inc))
            if history[-1] < tolerance:
                return _finish(compliance, lam, tan, u, depth, shift, angle, gap, slip_inc, r, mu), iteration - 1, history
            if len(history) >= STAGNATION_ITERATIONS and min(history) > STAGNATION_FACTOR * history[0]:
                raise ContactNotConverged(f"stagnated: {len(history)} iterations without halving the first residual "
                                          f"(the active sets cycle)", history)
        if contact.size == 0:
            raise ContactNotConverged("the body does not touch the gel (no point has a closed gap); "
                                      "increase the depth or the normal force", history)
        m = contact.size
        cols = compliance.unknown_index(contact)
        sign = np.tile([1.0, 1.0, -1.0], m) if frictional else -np.ones(m)
        n_body = int(depth_free) + shift_components.size * int(shift_free) + int(angle_free)
        size = n_comp * m + n_body
        unknowns = n_comp * m
        # the Jacobian is built in place on the compliance block gathered into its top-left corner, by row
        # operations on strided views (each point's rows are a linear combination of its own rows of C): a few
        # passes over the (3m)^2 block and no temporaries of its size
        jac = np.empty((size, size))
        block = compliance.gather(cols, cols, jac[:unknowns, :unknowns])   # u at contact dofs = (block * sign) @ y
        block *= sign[None, :]
        jac[:unknowns, unknowns:] = 0.0
        jac[unknowns:] = 0.0
        rhs = np.zeros(size)
        rc = r[contact]
        normal_rows = np.arange(m) * n_comp + (n_comp - 1)
        col = n_comp * m
        depth_col = shift_cols = angle_col = None
        if depth_free:
            depth_col, col = col, col + 1
        if shift_free:
            shift_cols, col = col + np.arange(shift_components.size), col + shift_components.size
        if angle_free:
            angle_col = col
        if frictional:                                   # the tangential rows below need C's rows before scaling
            rows_x, rows_y = block[0::3], block[1::3]                       # (m, 3m) views
            original_x = rows_x.copy()
        # normal rows: r (gap0 - depth - u_z) = 0
        block[n_comp - 1::n_comp] *= -rc[:, None]
        if depth_free:
            jac[normal_rows, depth_col] = -rc
            rhs[normal_rows] = -rc * gap0[contact]
        else:
            rhs[normal_rows] = -rc * (gap0[contact] - depth)
        if frictional:
            z = tan[contact] - rc[:, None] * slip_inc[contact]
            z_norm = np.linalg.norm(z, axis=1)
            # on the cone within ON_CONE counts as sliding: at the start of an increment the sliding points of the
            # last one sit there (their slip increment is zero), and treating them as stuck (half of them, by
            # round-off) flipped hundreds of point states between the first two iterations of every increment
            slipping = (z_norm > mu * lam_hat[contact] * (1.0 - ON_CONE)) | (mu == 0.0)   # mu = 0: all slide
            direction = z / np.maximum(z_norm, 1e-300)[:, None]
            perp = np.eye(2)[None] - direction[:, :, None] * direction[:, None, :]
            alpha = np.where(slipping, mu * lam_hat[contact] / np.maximum(z_norm, 1e-300), 0.0)
            # tangential rows: A w + B t + c lambda = 0 (stick: A = r I; slip: Alart-Curnier linearization)
            w_coef = np.where(slipping[:, None, None], (alpha * rc)[:, None, None] * perp,
                              rc[:, None, None] * np.eye(2)[None])
            t_coef = np.where(slipping[:, None, None], np.eye(2)[None] - alpha[:, None, None] * perp, 0.0)
            lam_coef = np.where(slipping[:, None], -mu * direction, 0.0)
            rows = (np.arange(m)[:, None] * 3 + np.arange(2)).ravel()
            # rows (x, y) of point k become w_coef[k] @ (C_x, C_y): in place, x first from its copy
            rows_x *= w_coef[:, 0, :1]
            rows_x += w_coef[:, 0, 1:] * rows_y
            rows_y *= w_coef[:, 1, 1:]
            original_x *= w_coef[:, 1, :1]
            rows_y += original_x
            local = np.arange(m) * 3
            for a in range(2):
                for b in range(2):
                    jac[local + a, local + b] += t_coef[:, a, b]
                jac[local + a, local + 2] += lam_coef[:, a]
            known_motion = omega[contact] + (0.0 if shift_free else shift) + (0.0 if angle_free else angle * lever[contact])
            rhs[rows] = np.einsum("kab,kb->ka", w_coef, known_motion).ravel()
            if shift_free:
                jac[rows[:, None], shift_cols[None, :]] = -w_coef.reshape(2 * m, 2)[:, shift_components]
            if angle_free:
                jac[rows, angle_col] = -np.einsum("kab,kb->ka", w_coef, lever[contact]).ravel()
            held = np.flatnonzero(compliance.constrained[cols])          # u_y = 0 on a symmetry plane:
            jac[held] = 0.0                                              # there t_y = 0 by symmetry
            jac[held, held] = 1.0
            rhs[held] = 0.0
        # body equilibrium rows
        row = n_comp * m
        if depth_free:
            jac[row, normal_rows] = 1.0
            rhs[row] = target_normal
            row += 1
        if shift_free:
            for offset, a in enumerate(shift_components):
                jac[row + offset, np.arange(m) * 3 + a] = 1.0
                rhs[row + offset] = target_tangential[a]
            row += shift_components.size
        if angle_free:
            jac[row, np.arange(m) * 3] = lever[contact, 0]
            jac[row, np.arange(m) * 3 + 1] = lever[contact, 1]
            rhs[row] = target_torque
        eliminated = np.zeros(0, dtype=int)
        if frictional and reduce_slip:
            held_point = np.zeros(m, dtype=bool)
            held_point[held // 3] = True
            eliminated = np.flatnonzero(slipping & (z_norm > 0.0) & ~held_point)
        kept = None
        if eliminated.size:
            jac, rhs, kept = eliminate_slip_directions(jac, rhs, eliminated, direction[eliminated], mu)
        try:
            if linear_solver is None:
                solution = np.linalg.solve(jac, rhs)
            else:
                keys, states, guess = _unknowns(contact, n_comp, lam, tan, slipping if frictional else None,
                                                depth_free, depth, shift_free, shift_components, shift,
                                                angle_free, angle)
                if kept is not None:
                    keys, states = keys[kept], states[kept]
                    guess = rotate_slip_guess(guess, kept, eliminated, direction[eliminated])
                # the linear residual [N] enters the next Newton residual: keep it a tenth of the tolerance
                solution = linear_solver.solve(jac, rhs, keys, states, guess, 0.1 * tolerance * scale())
        except np.linalg.LinAlgError as error:
            raise ContactNotConverged(f"singular Newton system at iteration {iteration} ({error})", history) from None
        if kept is not None:
            solution = restore_slip_directions(solution, kept, size, eliminated, direction[eliminated], mu)
        lam = np.zeros(n)
        lam[contact] = solution[normal_rows]
        if frictional:
            tan = np.zeros((n, 2))
            tan[contact] = solution[:3 * m].reshape(m, 3)[:, :2]
        if depth_free:
            depth = float(solution[depth_col])
        if shift_free:
            shift = np.zeros(2)
            shift[shift_components] = solution[shift_cols]
        if angle_free:
            angle = float(solution[angle_col])
    raise ContactNotConverged(f"no convergence in {max_iterations} Newton iterations", history)


BODY_KEYS = {"depth": -1, "shift": (-2, -3), "angle": -4}    # names of the body unknowns in a Newton system


def _unknowns(contact, n_comp, lam, tan, slipping, depth_free, depth, shift_free, shift_components, shift,
              angle_free, angle):
    """Keys, state codes and current values of a Newton system's unknowns, in its column order."""
    keys = [(contact[:, None] * n_comp + np.arange(n_comp)).ravel()]
    point_state = np.where(slipping, SLIP, STICK) if slipping is not None else np.full(contact.size, STICK)
    states = [np.repeat(point_state, n_comp)]
    values = [np.column_stack([tan[contact], lam[contact]]).ravel() if n_comp == 3 else lam[contact]]
    body_keys, body_values = [], []
    if depth_free:
        body_keys.append(BODY_KEYS["depth"])
        body_values.append(depth)
    if shift_free:
        body_keys.extend(BODY_KEYS["shift"][a] for a in shift_components)
        body_values.extend(shift[a] for a in shift_components)
    if angle_free:
        body_keys.append(BODY_KEYS["angle"])
        body_values.append(angle)
    keys.append(np.asarray(body_keys, dtype=np.int64))
    states.append(np.full(len(body_keys), OPEN))
    values.append(np.asarray(body_values, dtype=float))
    return np.concatenate(keys), np.concatenate(states), np.concatenate(values)


def point_status(lam_hat: np.ndarray, trial: np.ndarray | None, mu: float) -> np.ndarray:
    """OPEN / STICK / SLIP (n,) of converged points from their Alart-Curnier branches: lam_hat = lambda - r g, the
    trial traction t - r w (None without tangential unknowns)."""
    status = np.full(lam_hat.size, OPEN)
    in_contact = lam_hat > 0
    # normal-only problems: frictionless points slide freely (SLIP); a press-only path with mu > 0 has no tangential
    # unknowns and its points are reported as STICK (the small Spence pre-slip is what that omission leaves out)
    status[in_contact] = SLIP if mu == 0.0 else STICK
    if trial is not None:
        # a point slips when its trial traction leaves the cone: |t - r w| > mu lambda (w != 0 on the limit)
        z_norm = np.linalg.norm(trial, axis=1)
        status[in_contact & ((z_norm > mu * lam_hat * (1.0 + 1e-8)) | (mu == 0.0))] = SLIP
    return status


def _finish(compliance, lam, tan, u, depth, shift, angle, gap, slip_inc, r, mu) -> ContactState:
    """Package the converged iterate; classify points as open, stick or slip from the Alart-Curnier branches."""
    n = lam.size
    lam_hat = lam - r * gap
    status = point_status(lam_hat, None if slip_inc is None else tan - r[:, None] * slip_inc, mu)
    displacement = np.zeros((n, 3))
    displacement[:, list(compliance.components)] = u
    return ContactState(lam.copy(), tan.copy(), displacement, depth, np.asarray(shift, float).copy(), angle, status)
