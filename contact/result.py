"""What a contact solve produces: per-increment records, the whole result, and their post-processing."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from contact._newton import OPEN, STICK, ContactState
from contact.bumps import BumpResults, bump_results
from contact.scene import Scene
from fem.elasticity import ElasticModel

__all__ = ["Increment", "ContactResult", "PathNotCompleted", "LoadNotCarried", "ContactUnderResolved",
           "record_increment"]


@dataclass
class Increment:
    """Scalars and fields of one converged increment (mm, N, MPa, N mm, rad, s)."""

    load_kind: str
    normal_force: float
    tangential_force: list[float]
    torque: float
    depth: float
    shift: list[float]
    angle: float
    contact_area: float
    stick_area: float
    contact_radius: float
    stick_radius: float
    stick_ratio: float
    max_pressure: float
    iterations: int
    residual: float
    seconds: float
    substeps: int = 1                 # > 1 when Newton needed the increment split (automatic bisection)
    # recovered below the element size from the contact forces (contact.recovery): p = 0 and |q| = mu p contours
    recovered_contact_radius: float | None = None    # [mm]
    recovered_stick_ratio: float | None = None       # [-]
    recovered_peak_pressure: float | None = None     # [MPa]
    # fields (not written to result.json): per candidate point and per base point
    status: np.ndarray = field(repr=False, default=None)
    pressure: np.ndarray = field(repr=False, default=None)
    traction: np.ndarray = field(repr=False, default=None)
    base_pressure: np.ndarray = field(repr=False, default=None)
    base_traction: np.ndarray = field(repr=False, default=None)
    displacement_full: np.ndarray = field(repr=False, default=None)
    bumps: BumpResults | None = field(repr=False, default=None)     # per-bump scalars (contact.bumps)

    SCALARS = ("load_kind", "normal_force", "tangential_force", "torque", "depth", "shift", "angle", "contact_area",
               "stick_area", "contact_radius", "stick_radius", "stick_ratio", "max_pressure", "iterations",
               "residual", "seconds", "substeps", "recovered_contact_radius", "recovered_stick_ratio",
               "recovered_peak_pressure")

    def summary(self) -> dict:
        return {name: getattr(self, name) for name in self.SCALARS}


@dataclass
class ContactResult:
    """Everything a solve produced: mesh facts, timings, what was left out, and the increments."""

    scene: Scene
    model: ElasticModel
    candidates: np.ndarray            # indices into model.top of the contact-candidate points
    increments: list[Increment] = field(default_factory=list)
    timings: dict = field(default_factory=dict)
    mesh_info: dict = field(default_factory=dict)
    left_out: list[str] = field(default_factory=list)
    error: str | None = None
    candidate_bump: np.ndarray | None = None    # (n,) the bump (nearest first-contact point) of each candidate
    bump_centers: np.ndarray | None = None      # (k, 2) first-contact points [mm]

    @property
    def candidate_positions(self) -> np.ndarray:
        return self.model.top.positions[self.candidates]

    @property
    def candidate_areas(self) -> np.ndarray:
        return self.model.top.areas[self.candidates]


class PathNotCompleted(RuntimeError):
    """A load increment failed; ``result`` keeps every increment converged before it."""

    def __init__(self, message: str, result: ContactResult):
        super().__init__(message)
        self.result = result


class LoadNotCarried(ValueError):
    """A force target the contact cannot carry (beyond gross slip); ``result`` keeps the increments before it."""

    def __init__(self, message: str, result: ContactResult):
        super().__init__(message)
        self.result = result


class ContactUnderResolved(ValueError):
    """The contact patch covers too few surface points for a stick ratio to mean anything; ``result`` is kept."""

    def __init__(self, message: str, result: ContactResult):
        super().__init__(message)
        self.result = result


def record_increment(kind, state: ContactState, iterations, history, model, factorization, candidates, areas,
                     lever, scene, seconds, multiplicity=1.0, substeps=1, candidate_triangles=None, bump=None,
                     bump_centers=None) -> Increment:
    """Post-process a converged state: areas, radii, stick ratio, pressures, full displacement and base traction,
    the boundaries and pressure recovered below the element size (``contact.recovery``), and the per-bump sums when
    ``bump`` (n,) and ``bump_centers`` (k, 2) are given (``contact.bumps``).

    ``multiplicity`` = 2 for a half model: whole-body forces and areas are twice those of the computed half.
    ``candidate_triangles``: the top triangles among the candidates (``contact.recovery.surface_triangles``).
    The bumps' margin to gross slip uses the scene's friction coefficient also in a frictionless press.
    """
    from contact.recovery import recover_contact, surface_triangles

    status = state.status
    contact_area = multiplicity * float(areas[status != OPEN].sum())
    stick_area = multiplicity * float(areas[status == STICK].sum())
    pressure = model.top.pressure(candidates, state.normal_force)      # P2: recovered per facet (fem.elasticity)
    traction = state.tangential_force / areas[:, None]
    # full field: one back-substitution with the contact forces (also gives the base reactions for the sensor)
    forces = np.zeros(model.n_dofs)
    dofs = model.top.dofs[candidates]
    forces[dofs[:, 0]] = state.tangential_force[:, 0]
    forces[dofs[:, 1]] = state.tangential_force[:, 1]
    forces[dofs[:, 2]] = -state.normal_force
    reaction = np.zeros(model.n_dofs)
    if state.gel_displacement is None:
        u_free = factorization.solve(forces[model.free_dofs])
        reaction[model.fixed_dofs] = model.stiffness_fixed_free @ u_free
    else:                                           # the finite-strain gel (contact._finite_strain) carries its own
        u_free = state.gel_displacement
        reaction[model.fixed_dofs] = state.fixed_force
    base_forces = reaction[model.base.dofs]                              # (n_base, 3) support force on the gel
    displacement_full = model.full_vector(u_free)
    check_no_penetration(model, candidates, displacement_full, scene, state.depth)
    if candidate_triangles is None:
        candidate_triangles = surface_triangles(model.top.triangles, candidates, model.top.areas.size)
    recovered = recover_contact(model.top.positions[candidates], candidate_triangles, areas, state.normal_force,
                                state.tangential_force, status, scene.contact.friction_coefficient, mirror_y=multiplicity == 2.0)
    bumps = None
    if bump is not None:
        bumps = bump_results(bump, bump_centers, status, state.normal_force, state.tangential_force, areas,
                             model.top.positions[candidates], lever, scene.contact.friction_coefficient, multiplicity)
    return Increment(
        load_kind=kind, normal_force=multiplicity * float(state.normal_force.sum()),
        # a mirror half carries half of F_x; its F_y and torque are cancelled by the other half
        tangential_force=[multiplicity * float(state.tangential_force[:, 0].sum()),
                          float(state.tangential_force[:, 1].sum()) if multiplicity == 1.0 else 0.0],
        torque=float((lever * state.tangential_force).sum()) if multiplicity == 1.0 else 0.0,
        depth=float(state.depth),
        shift=[float(v) for v in state.shift], angle=float(state.angle),
        contact_area=contact_area, stick_area=stick_area, contact_radius=math.sqrt(contact_area / math.pi),
        stick_radius=math.sqrt(stick_area / math.pi),
        stick_ratio=math.sqrt(stick_area / contact_area) if contact_area > 0 else 0.0,
        max_pressure=float(pressure.max()), iterations=int(iterations), residual=float(history[-1]),
        seconds=float(seconds), substeps=int(substeps), status=status.copy(), pressure=pressure, traction=traction,
        base_pressure=base_forces[:, 2] / model.base.areas, base_traction=base_forces[:, :2] / model.base.areas[:, None],
        displacement_full=displacement_full, recovered_contact_radius=recovered.contact_radius,
        recovered_stick_ratio=recovered.stick_ratio, recovered_peak_pressure=recovered.peak_pressure, bumps=bumps)


def check_no_penetration(model, candidates, displacement_full, scene, depth) -> None:
    """Top points outside the candidate set must stay clear of the body; else the candidate zone was too small."""
    others = np.setdiff1d(np.arange(model.top.areas.size), candidates)
    if others.size == 0:
        return
    xy = model.top.positions[others, :2]
    gap = (scene.body.initial_gap(xy) - model.top.positions[others, 2] - depth
           - displacement_full[model.top.dofs[others, 2]])
    if np.any(gap < 0):
        worst = others[np.argmin(gap)]
        raise ValueError(f"the body touches the gel outside the contact-candidate zone (point at "
                         f"{model.top.positions[worst, :2].round(3).tolist()} mm); raise mesh.fine_radius")
