"""Frictional contact of a rigid body with a linear-elastic gel along a quasi-static load path (scene -> result)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from contact._newton import OPEN, SLIP, STICK, BodyControl, ContactNotConverged, ContactState, solve_increment
from contact.compliance import SurfaceCompliance
from contact.scene import LoadKind, Scene
from fem.elasticity import ElasticModel, assemble_elastic_model
from fem.linear_solver import SpdFactorization
from fem.mesh import BlockMeshSpec, graded_block_mesh, mesh_quality

__all__ = ["Increment", "ContactResult", "PathNotCompleted", "Prepared", "prepare", "preparation_key", "solve_scene",
           "OPEN", "STICK", "SLIP"]


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
    # fields (not written to result.json): per candidate point and per base point
    status: np.ndarray = field(repr=False, default=None)
    pressure: np.ndarray = field(repr=False, default=None)
    traction: np.ndarray = field(repr=False, default=None)
    base_pressure: np.ndarray = field(repr=False, default=None)
    base_traction: np.ndarray = field(repr=False, default=None)
    displacement_full: np.ndarray = field(repr=False, default=None)

    SCALARS = ("load_kind", "normal_force", "tangential_force", "torque", "depth", "shift", "angle", "contact_area",
               "stick_area", "contact_radius", "stick_radius", "stick_ratio", "max_pressure", "iterations",
               "residual", "seconds", "substeps")

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


def _max_normal_load(scene: Scene) -> tuple[float | None, float | None]:
    forces = [v for load in scene.loads if load.kind == LoadKind.PRESS and load.control == "force" for v in load.values]
    depths = [v for load in scene.loads if load.kind == LoadKind.PRESS and load.control == "displacement"
              for v in load.values]
    return (max(forces) if forces else None), (max(depths) if depths else None)


def contact_centers(scene: Scene) -> np.ndarray:
    """Where the body first touches the gel, (k, 2) [mm]: below a sphere's centre, or every bump top for a plane."""
    if scene.body.shape == "sphere":
        return np.array([scene.body.center], dtype=float)
    return np.asarray(scene.gel.geometry.contact_centers(), dtype=float).reshape(-1, 2)


def estimated_contact(scene: Scene) -> tuple[float, float]:
    """Half-space estimate of the contact radius [mm] and indentation [mm] at each contact centre, largest press.

    Curved contacts (sphere body or curved gel) use Hertz with 1/R = 1/R_body + 1/R_gel and the normal force shared
    equally by the contact centres; a flat-topped cap under a plane acts as a flat punch of its flat radius; a
    plane on a flat block covers the whole top. Only used to size the fine zone and to seed the first press.
    """
    force, depth = _max_normal_load(scene)
    e_star = scene.material.effective_modulus
    n_centers = len(contact_centers(scene))
    body_radius = scene.body.radius if scene.body.shape == "sphere" else math.inf
    curvature = 1.0 / body_radius + 1.0 / scene.gel.curvature_radius
    if curvature > 0.0:
        radius = 1.0 / curvature
        from_force = (3.0 * (force or 0.0) / n_centers * radius / (4.0 * e_star)) ** (1 / 3)
        contact_radius = max(from_force, math.sqrt(radius * depth) if depth else 0.0)
        return contact_radius, contact_radius**2 / radius
    if scene.gel.shape == "flat_cap":
        flat = scene.gel.geometry.flat_radius
        indentation = max(depth or 0.0, (force or 0.0) / n_centers / (2.0 * e_star * flat))
        return flat + math.sqrt(2.0 * scene.gel.geometry.edge_radius * indentation), indentation
    half_diagonal = 0.5 * math.hypot(scene.gel.width, scene.gel.depth)
    return half_diagonal, depth or 1e-3 * scene.gel.thickness


@dataclass
class Prepared:
    """Mesh, assembled model and factorization of a scene: everything that does not depend on the load path."""

    model: ElasticModel
    factorization: SpdFactorization
    timings: dict
    mesh_info: dict
    fine_radius: float
    half: bool                        # mirror-symmetric half model (y >= 0): forces and areas count twice
    compliances: dict = field(default_factory=dict)   # SurfaceCompliance per candidate set, reused across solves


def _fine_radius_and_half(scene: Scene) -> tuple[float, bool]:
    fine_radius = scene.mesh.fine_radius or (1.3 * estimated_contact(scene)[0] + 2.0 * scene.mesh.size_contact)
    return fine_radius, scene.contact.symmetry == "auto" and scene.mirror_symmetric


def _gel_mesh(scene: Scene, fine_radius: float, half: bool):
    """The gel's tet mesh: a graded bisection mesh for a block, pytetwild (cached on disk) for the other shapes."""
    size_contact = scene.mesh.size_contact * scene.mesh.order       # P2 elements carry mid-edge nodes
    if scene.gel.shape == "block":
        spec = BlockMeshSpec(width=scene.gel.width, depth=scene.gel.depth, thickness=scene.gel.thickness,
                             size_contact=size_contact, size_far=scene.mesh.size_far, fine_radius=fine_radius,
                             fine_center=tuple(scene.body.center), grading=scene.mesh.grading, half=half)
        return graded_block_mesh(spec)
    from fem.tetmesh import TetMeshSpec, mesh_gel

    spec = TetMeshSpec(size_contact=size_contact, size_far=scene.mesh.size_far, contact_radius=fine_radius,
                       grading=scene.mesh.grading, size_base=scene.mesh.size_base)
    return mesh_gel(scene.gel.geometry, spec).mesh


def preparation_key(scene: Scene) -> tuple:
    """Hashable key of everything ``prepare`` depends on: scenes with equal keys can share one Prepared."""
    fine_radius, half = _fine_radius_and_half(scene)
    return (scene.gel, scene.material, scene.mesh, scene.body.center, round(fine_radius, 12), half)


def prepare(scene: Scene) -> Prepared:
    """Mesh the gel, assemble K and factorize it once (reused by every increment and by scenes of equal key)."""
    timings = {}
    start = time.perf_counter()
    fine_radius, half = _fine_radius_and_half(scene)
    mesh = _gel_mesh(scene, fine_radius, half)
    timings["mesh"] = time.perf_counter() - start
    start = time.perf_counter()
    model = assemble_elastic_model(mesh, scene.material.E, scene.material.nu, scene.mesh.order,
                                   symmetry_plane_y=0.0 if half else None)
    timings["assembly"] = time.perf_counter() - start
    start = time.perf_counter()
    factorization = SpdFactorization(model.stiffness_free)
    timings["factorization"] = time.perf_counter() - start
    quality = mesh_quality(mesh.p, mesh.t)
    mesh_info = {"nodes": int(mesh.p.shape[1]), "elements": int(mesh.t.shape[1]), "dofs": int(model.n_dofs),
                 "free_dofs": int(model.free_dofs.size), "order": scene.mesh.order,
                 "top_points": int(model.top.areas.size), "min_dihedral_deg": quality.min_dihedral_deg,
                 "min_radius_ratio": quality.min_radius_ratio, "fine_radius": fine_radius,
                 "solver_backend": factorization.backend, "half_model": half}
    return Prepared(model, factorization, timings, mesh_info, fine_radius, half)


def _augmentation(areas: np.ndarray, effective_modulus: float) -> np.ndarray:
    """Alart-Curnier parameter per point: stiffness 2 E* rho of a rigid disc with the point's area [N/mm]."""
    return 2.0 * effective_modulus * np.sqrt(areas / np.pi)


def _controls(scene: Scene):
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


def solve_scene(scene: Scene, prepared: Prepared | None = None, progress: bool = False) -> ContactResult:
    """Solve the scene's load path increment by increment; raise PathNotCompleted (with the partial result) on failure."""
    prepared = prepared or prepare(scene)
    model = prepared.model
    timings = dict(prepared.timings)
    left_out = []

    start = time.perf_counter()
    probe = np.zeros(model.free_dofs.size)
    probe[: min(3, probe.size)] = 1.0
    prepared.factorization.solve(probe)
    timings["back_substitution"] = time.perf_counter() - start
    timings["linear_solve"] = timings["assembly"] + timings["factorization"] + timings["back_substitution"]

    contact_start = time.perf_counter()
    xy = model.top.positions[:, :2]
    centers = contact_centers(scene)
    reach = np.min(np.linalg.norm(xy[:, None, :] - centers[None, :, :], axis=2), axis=1)
    candidate_radius = prepared.fine_radius + 3.0 * scene.mesh.size_contact
    candidates = np.flatnonzero((reach <= candidate_radius) & np.isfinite(scene.body.initial_gap(xy)))
    left_out.append(f"contact candidates: {candidates.size} of {xy.shape[0]} top points (within {candidate_radius:.3g}"
                    f" mm of the {len(centers)} first-contact point(s)); compliance columns only for points that "
                    f"enter contact")
    if prepared.half:
        left_out.append("the half y < 0: gel, body and loads are mirror-symmetric about y = 0 (press and shear along "
                        "x only); forces and areas are doubled in the report, fields cover y >= 0")
    multiplicity = 2.0 if prepared.half else 1.0
    if candidates.size == 0:
        raise ValueError(f"the body (a {scene.body.shape} at {list(scene.body.center)} mm) is not above the gel's "
                         f"top face: no point can come into contact")
    frictional = scene.has_tangential_load and scene.contact.mu > 0
    if not frictional:
        left_out.append("tangential contact unknowns: the path has no shear or twist load, or mu = 0")
    components = (0, 1, 2) if frictional else (2,)
    compliance_key = (candidates.tobytes(), components)
    if compliance_key not in prepared.compliances:
        prepared.compliances[compliance_key] = SurfaceCompliance(model, prepared.factorization, candidates, components)
    compliance = prepared.compliances[compliance_key]
    columns_before = compliance.computed_columns
    positions = model.top.positions[candidates]
    gap0 = scene.body.initial_gap(positions[:, :2]) - positions[:, 2]       # the gel's top point is at z = 0
    lever = np.column_stack([-(positions[:, 1] - scene.body.center[1]), positions[:, 0] - scene.body.center[0]])
    areas = model.top.areas[candidates]
    augmentation = _augmentation(areas, scene.material.effective_modulus)
    n = candidates.size
    state = ContactState(np.zeros(n), np.zeros((n, 2)), np.zeros((n, 3)))
    # First Newton iterate of a force-controlled press: half the Hertz depth, whose geometric overlap
    # r < sqrt(2 R d) matches the Hertz contact radius; the full depth would start with sqrt(2) a and twice the
    # points (each needing compliance columns).
    seed_depth = 0.5 * estimated_contact(scene)[1]
    result = ContactResult(scene, model, candidates, timings=timings, mesh_info=dict(prepared.mesh_info),
                           left_out=left_out)
    controls = list(_controls(scene))
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(controls), desc=scene.name, unit="increment")
    try:
        for kind, control, friction_on in controls:
            step_start = time.perf_counter()
            control = _scaled(control, 1.0 / multiplicity)
            _check_feasible(control, state, scene.contact.mu, lever)
            mu = scene.contact.mu if friction_on else 0.0

            def solve(start_state, target):
                return solve_increment(compliance, gap0, lever, augmentation, mu, start_state, target,
                                       seed_depth=seed_depth, tolerance=scene.contact.tolerance,
                                       max_iterations=scene.contact.max_iterations, mirror_y=prepared.half)

            try:
                state, iterations, history, substeps = _solve_with_substeps(solve, state, control, lever)
            except ContactNotConverged as error:
                raise PathNotCompleted(f"increment {len(result.increments) + 1} ({kind}): {error}", result) from error
            result.increments.append(_record(kind, state, iterations, history, model, prepared.factorization,
                                             compliance, candidates, areas, lever, scene,
                                             time.perf_counter() - step_start, multiplicity))
            result.increments[-1].substeps = substeps
            if bar is not None:
                bar.update(1)
    except PathNotCompleted as error:
        result.error = str(error)
        raise
    finally:
        if bar is not None:
            bar.close()
        timings["contact"] = time.perf_counter() - contact_start
        timings["compliance_columns"] = compliance.computed_columns - columns_before   # new in this solve
    return result


MAX_BISECTIONS = 6     # an increment may be split into up to 2^6 = 64 sub-steps


def _interpolated(control: BodyControl, state: ContactState, lever: np.ndarray, fraction: float) -> BodyControl:
    """The targets a ``fraction`` of the way from the converged ``state`` to ``control`` (same control modes)."""
    import dataclasses

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


def _solve_with_substeps(solve, state: ContactState, control: BodyControl, lever: np.ndarray, depth: int = 0):
    """Solve an increment; if Newton does not converge, split it in two halves (recursively, friction follows the
    finer path), up to MAX_BISECTIONS levels. Returns (state, iterations, history, sub-steps)."""
    try:
        new_state, iterations, history = solve(state, control)
        return new_state, iterations, history, 1
    except ContactNotConverged:
        if depth >= MAX_BISECTIONS or not np.any(state.normal_force > 0):
            raise
    middle, it1, _, n1 = _solve_with_substeps(solve, state, _interpolated(control, state, lever, 0.5), lever,
                                              depth + 1)
    final, it2, history, n2 = _solve_with_substeps(solve, middle, control, lever, depth + 1)
    return final, it1 + it2, history, n1 + n2


def _scaled(control: BodyControl, factor: float) -> BodyControl:
    """The control with its force targets multiplied by ``factor`` (a half model carries half of each force)."""
    import dataclasses

    def times(value):
        if value is None:
            return None
        return tuple(factor * v for v in value) if isinstance(value, tuple) else factor * value

    return dataclasses.replace(control, normal_force=times(control.normal_force),
                               tangential_force=times(control.tangential_force), torque=times(control.torque))


def _check_feasible(control: BodyControl, state: ContactState, mu: float, lever: np.ndarray) -> None:
    """Refuse force targets the contact cannot carry (beyond gross slip) before trying to solve them."""
    normal = control.normal_force if control.normal_force is not None else float(state.normal_force.sum())
    if control.tangential_force is not None:
        magnitude = math.hypot(*control.tangential_force)
        if magnitude >= mu * normal:
            raise ValueError(f"shear force {magnitude:.4g} N is not below mu*P = {mu * normal:.4g} N: the contact "
                             f"cannot carry it (gross slip); use a shift (displacement control) instead")
    if control.torque is not None and np.any(state.normal_force > 0):
        limit = mu * float((state.normal_force * np.linalg.norm(lever, axis=1)).sum())
        if abs(control.torque) >= limit:
            raise ValueError(f"torque {control.torque:.4g} N mm is not below the full-slip torque "
                             f"{limit:.4g} N mm of the current pressure: the contact cannot carry it")


def _record(kind, state: ContactState, iterations, history, model, factorization, compliance, candidates, areas,
            lever, scene, seconds, multiplicity=1.0) -> Increment:
    """Post-process a converged state: areas, radii, stick ratio, pressures, full displacement and base traction.

    ``multiplicity`` = 2 for a half model: whole-body forces and areas are twice those of the computed half.
    """
    status = state.status
    contact_area = multiplicity * float(areas[status != OPEN].sum())
    stick_area = multiplicity * float(areas[status == STICK].sum())
    pressure = state.normal_force / areas
    traction = state.tangential_force / areas[:, None]
    # full field: one back-substitution with the contact forces (also gives the base reactions for the sensor)
    forces = np.zeros(model.n_dofs)
    dofs = model.top.dofs[candidates]
    forces[dofs[:, 0]] = state.tangential_force[:, 0]
    forces[dofs[:, 1]] = state.tangential_force[:, 1]
    forces[dofs[:, 2]] = -state.normal_force
    u_free = factorization.solve(forces[model.free_dofs])
    reaction = np.zeros(model.n_dofs)
    reaction[model.fixed_dofs] = model.stiffness_fixed_free @ u_free
    base_forces = reaction[model.base.dofs]                              # (n_base, 3) support force on the gel
    displacement_full = model.full_vector(u_free)
    _check_no_penetration(model, candidates, displacement_full, scene, state.depth)
    return Increment(
        load_kind=kind, normal_force=multiplicity * float(state.normal_force.sum()),
        tangential_force=[multiplicity * float(v) for v in state.tangential_force.sum(axis=0)],
        torque=multiplicity * float((lever * state.tangential_force).sum()), depth=float(state.depth),
        shift=[float(v) for v in state.shift], angle=float(state.angle),
        contact_area=contact_area, stick_area=stick_area, contact_radius=math.sqrt(contact_area / math.pi),
        stick_radius=math.sqrt(stick_area / math.pi),
        stick_ratio=math.sqrt(stick_area / contact_area) if contact_area > 0 else 0.0,
        max_pressure=float(pressure.max()), iterations=int(iterations), residual=float(history[-1]),
        seconds=float(seconds), status=status.copy(), pressure=pressure, traction=traction,
        base_pressure=base_forces[:, 2] / model.base.areas, base_traction=base_forces[:, :2] / model.base.areas[:, None],
        displacement_full=displacement_full)


def _check_no_penetration(model, candidates, displacement_full, scene, depth) -> None:
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
