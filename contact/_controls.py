"""Load-path controls: body targets per increment, force scaling for half models, feasibility, and bisection."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from contact._newton import BodyControl, ContactNotConverged, ContactState
from contact.scene import LoadKind, Scene

__all__ = ["controls", "scaled", "check_feasible", "solve_with_substeps", "MAX_BISECTIONS"]


def controls(scene: Scene):
    """Yield (load kind, BodyControl, frictional?) per increment; coordinates keep their last control."""
    normal = {"depth": None, "normal_force": None}
    tangential = {"shift": (0.0, 0.0), "tangential_force": None}
    twist = {"angle": 0.0, "torque": None}
    friction_on = not scene.contact.frictionless_press
    for load in scene.loads:
        for value in load.values:
            if load.kind == LoadKind.PRESS:
                normal = {"depth": value, "normal_force": None} if load.control == "displacement" else \
                    {"depth": None, "normal_force": value}
            elif load.kind == LoadKind.SHEAR:
                friction_on = True
                unit = np.asarray(load.direction, float) / math.hypot(*load.direction)
                vector = tuple(float(v) for v in unit * value)
                tangential = {"shift": vector, "tangential_force": None} if load.control == "displacement" else \
                    {"shift": None, "tangential_force": vector}
            else:
                friction_on = True
                twist = {"angle": value, "torque": None} if load.control == "displacement" else \
                    {"angle": None, "torque": value}
            yield load.kind.value, BodyControl(**normal, **tangential, **twist), friction_on


MAX_BISECTIONS = 6     # an increment may be split into up to 2^6 = 64 sub-steps


def interpolated(control: BodyControl, state: ContactState, lever: np.ndarray, fraction: float) -> BodyControl:
    """The targets a ``fraction`` of the way from the converged ``state`` to ``control`` (same control modes)."""
    def between(start, end):
        if end is None:
            return None
        if isinstance(end, tuple):
            return tuple(float(a + fraction * (b - a)) for a, b in zip(start, end))
        return float(start + fraction * (end - start))

    return dataclasses.replace(
        control, depth=between(state.depth, control.depth),
        normal_force=between(float(state.normal_force.sum()), control.normal_force),
        shift=between(tuple(state.shift), control.shift),
        tangential_force=between(tuple(state.tangential_force.sum(axis=0)), control.tangential_force),
        angle=between(state.angle, control.angle),
        torque=between(float((lever * state.tangential_force).sum()), control.torque))


def solve_with_substeps(solve, state: ContactState, control: BodyControl, lever: np.ndarray, depth: int = 0,
                        start_level: int = 0):
    """Solve an increment; if Newton does not converge, split it in two halves (recursively, friction follows the
    finer path), up to MAX_BISECTIONS levels. ``start_level``: split into 2^start_level sub-steps without trying
    the coarser ones first (the level an earlier increment of the same load needed: ``solve_scene`` passes it on,
    so a path whose steps all need quarter steps does not fail twice per increment first). Returns (state,
    iterations, history, sub-steps, level): ``level`` the deepest split that converged."""
    if depth >= start_level:
        try:
            new_state, iterations, history = solve(state, control)
            return new_state, iterations, history, 1, depth
        except ContactNotConverged:
            if depth >= MAX_BISECTIONS or not np.any(state.normal_force > 0):
                raise
    middle, it1, _, n1, level1 = solve_with_substeps(solve, state, interpolated(control, state, lever, 0.5), lever,
                                                     depth + 1, start_level)
    final, it2, history, n2, level2 = solve_with_substeps(solve, middle, control, lever, depth + 1, start_level)
    return final, it1 + it2, history, n1 + n2, max(level1, level2)


def scaled(control: BodyControl, factor: float) -> BodyControl:
    """The control with its force targets multiplied by ``factor`` (a half model carries half of each force)."""
    def times(value):
        if value is None:
            return None
        return tuple(factor * v for v in value) if isinstance(value, tuple) else factor * value

    return dataclasses.replace(control, normal_force=times(control.normal_force),
                               tangential_force=times(control.tangential_force), torque=times(control.torque))


def check_feasible(control: BodyControl, state: ContactState, friction_coefficient: float, lever: np.ndarray) -> None:
    """Refuse force targets the contact cannot carry (beyond gross slip) before trying to solve them."""
    normal = control.normal_force if control.normal_force is not None else float(state.normal_force.sum())
    if control.tangential_force is not None:
        magnitude = math.hypot(*control.tangential_force)
        if magnitude >= friction_coefficient * normal:
            raise ValueError(f"shear force {magnitude:.4g} N is not below friction_coefficient x P = "
                             f"{friction_coefficient * normal:.4g} N: the contact "
                             f"cannot carry it (gross slip); use a shift (displacement control) instead")
    if control.torque is not None and np.any(state.normal_force > 0):
        limit = friction_coefficient * float((state.normal_force * np.linalg.norm(lever, axis=1)).sum())
        if abs(control.torque) >= limit:
            raise ValueError(f"torque {control.torque:.4g} N mm is not below the full-slip torque "
                             f"{limit:.4g} N mm of the current pressure: the contact cannot carry it")
