"""Frictional contact of a rigid body with a linear-elastic gel along a quasi-static load path (scene -> result)."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from contact._finite_strain import FiniteStrainGel, solve_finite_strain_increment
from contact._controls import check_feasible, controls as load_controls, scaled, solve_with_substeps
from contact._newton import OPEN, SLIP, STICK, ContactNotConverged, ContactState, solve_increment
from contact._newton_linear import NewtonLinearSolver
from contact.result import (ContactResult, ContactUnderResolved, Increment, LoadNotCarried, PathNotCompleted,
                            record_increment)
from contact.bumps import assign_bumps
from contact.compliance import ColumnCache, SurfaceCompliance, compliance_cache_key
from contact.limits import (PhysicalLimitError, check_increment_limits, check_resources, check_scene_limits,
                            contact_centers, estimated_contact, fine_depth, fine_zone)
from contact.recovery import surface_triangles
from contact.scene import MaterialLaw, Scene
from fem.elasticity import ElasticModel, assemble_elastic_model
from fem.linear_solver import SaddlePointFactorization, SpdFactorization
from fem.progress import ticking
from fem.mesh import BlockMeshSpec, graded_block_mesh, mesh_quality

__all__ = ["Increment", "ContactResult", "PathNotCompleted", "Prepared", "factorize_stiffness", "prepare",
           "preparation_key", "solve_scene",
           "OPEN", "STICK", "SLIP"]


MIN_POINTS_PER_CONTACT = 7   # a centre point and one ring: fewer cannot resolve a contact radius or a stick zone


@dataclass
class Prepared:
    """Mesh, assembled model and factorization of a scene: everything that does not depend on the load path."""

    model: ElasticModel
    factorization: SpdFactorization | SaddlePointFactorization   # solve(f) = stiffness_free^-1 f either way
    timings: dict
    mesh_info: dict
    fine_radius: float
    half: bool                        # mirror-symmetric half model (y >= 0): forces and areas count twice
    compliances: dict = field(default_factory=dict)   # SurfaceCompliance per candidate set, reused across solves
    finite_strain: object = None      # contact._finite_strain.FiniteStrainGel, built by the first finite-strain solve


def _fine_radius_and_half(scene: Scene) -> tuple[float, bool]:
    return fine_zone(scene)


def _gel_mesh(scene: Scene, fine_radius: float, half: bool):
    """The gel's tet mesh: a graded bisection mesh for a block, gmsh (cached on disk) for the other shapes."""
    size_contact = scene.mesh.size_contact * scene.mesh.order       # P2 elements carry mid-edge nodes
    if scene.gel.shape == "block":
        spec = BlockMeshSpec(width=scene.gel.width, depth=scene.gel.depth, thickness=scene.gel.thickness,
                             size_contact=size_contact, size_far=scene.mesh.size_far, fine_radius=fine_radius,
                             fine_depth=fine_depth(scene), fine_center=tuple(scene.body.center),
                             grading=scene.mesh.grading, half=half)
        return graded_block_mesh(spec)
    from fem.tetmesh import TetMeshSpec, mesh_gel

    spec = TetMeshSpec(size_contact=size_contact, size_far=scene.mesh.size_far, contact_radius=fine_radius,
                       grading=scene.mesh.grading, size_base=scene.mesh.size_base)
    return mesh_gel(scene.gel.geometry, spec).mesh


def gel_mesh(scene: Scene):
    """The scene's tet mesh as ``prepare`` builds it, without assembling or factorizing, and whether it is the
    mirror half model (for an external solver that needs only the mesh)."""
    fine_radius, half = _fine_radius_and_half(scene)
    return _gel_mesh(scene, fine_radius, half), half


def preparation_key(scene: Scene) -> tuple:
    """Hashable key of everything ``prepare`` depends on: scenes with equal keys can share one Prepared."""
    fine_radius, half = _fine_radius_and_half(scene)
    return (scene.gel, scene.material, scene.mesh, scene.body.center, round(fine_radius, 12),
            round(fine_depth(scene), 12), half)


def factorize_stiffness(model: ElasticModel) -> SpdFactorization | SaddlePointFactorization:
    """A factorization whose ``solve`` applies ``model.stiffness_free``^-1.

    For the nodal-average gel it factorizes the uncondensed saddle-point system [[K_G, B^T], [B, -diag(V_n /
    lambda)]] (``model.saddle_point``) instead of the condensed K, whose B^T B couples second neighbours: on the
    26k-DOF stability block 3/8 of the factor's nonzeros and about half the factorization time
    (``python -m studies benchmark --factorizations``). Otherwise it factorizes K itself.
    """
    blocks = model.saddle_point
    if blocks is not None:
        return SaddlePointFactorization(blocks.shear_stiffness, blocks.pairing, blocks.pressure_compliance)
    return SpdFactorization(model.stiffness_free)


LOCKING_NU = 0.49     # above this tets lock: the stability study finds c/a ~0.1 low and a 12-21 % small (P1)


def prepare(scene: Scene, progress: bool = False) -> Prepared:
    """Mesh the gel, assemble K and factorize it once (reused by every increment and by scenes of equal key);
    ``progress``: a bar ticking through meshing, assembly and factorization (``fem.progress``)."""
    if scene.material.nu > LOCKING_NU and scene.mesh.volumetric == "standard":
        import warnings

        warnings.warn(f"material.nu={scene.material.nu} > {LOCKING_NU}: tetrahedra lock (P1 badly, P2 partly; "
                      f"studies stability measures c/a about 0.1 low); results are not reliable: use "
                      f"mesh.volumetric='nodal_average' (P1)", stacklevel=2)
    timings = {}
    start = time.perf_counter()
    fine_radius, half = _fine_radius_and_half(scene)
    estimate = check_resources(scene, fine_radius, half)         # before meshing: refuse what cannot fit
    with ticking(f"{scene.name}: meshing ({scene.gel.shape}, h = {scene.mesh.size_contact:g} mm)", progress):
        mesh = _gel_mesh(scene, fine_radius, half)
    timings["mesh"] = time.perf_counter() - start
    start = time.perf_counter()
    with ticking(f"{scene.name}: assembly and factorization", progress):
        model = assemble_elastic_model(mesh, scene.material.E, scene.material.nu, scene.mesh.order,
                                       symmetry_plane_y=0.0 if half else None, volumetric=scene.mesh.volumetric)
        timings["assembly"] = time.perf_counter() - start
        start = time.perf_counter()
        factorization = factorize_stiffness(model)
        timings["factorization"] = time.perf_counter() - start
    quality = mesh_quality(mesh.p, mesh.t)
    mesh_info = {"nodes": int(mesh.p.shape[1]), "elements": int(mesh.t.shape[1]), "dofs": int(model.n_dofs),
                 "free_dofs": int(model.free_dofs.size), "order": scene.mesh.order,
                 "volumetric": scene.mesh.volumetric, "stiffness_nonzeros": int(model.stiffness_free.nnz),
                 "top_points": int(model.top.areas.size), "min_dihedral_deg": quality.min_dihedral_deg,
                 "min_radius_ratio": quality.min_radius_ratio, "fine_radius": fine_radius,
                 "solver_backend": factorization.backend, "factor_nonzeros": factorization.factor_nonzeros,
                 "factorized_system": "saddle_point" if model.saddle_point is not None else "stiffness",
                 "half_model": half, "estimated_dofs": round(estimate["dofs"])}
    return Prepared(model, factorization, timings, mesh_info, fine_radius, half)


def _augmentation(areas: np.ndarray, effective_modulus: float) -> np.ndarray:
    """Alart-Curnier parameter per point: stiffness 2 E* rho of a rigid disc with the point's area [N/mm]."""
    return 2.0 * effective_modulus * np.sqrt(areas / np.pi)


def solve_scene(scene: Scene, prepared: Prepared | None = None, progress: bool = False,
                cache_compliance: bool = True, remember_substeps: bool = True) -> ContactResult:
    """Solve the scene's load path increment by increment; raise PathNotCompleted (with the partial result) on failure.

    The physical limits (contact.limits) are checked first: a press past small strain or a contact wider than the
    body's curvature is refused before meshing, and each increment's depth and sliding are checked as it converges.
    ``cache_compliance``: read the surface compliance columns from the disk cache (``contact.compliance.ColumnCache``)
    and write the new ones back; off, every column is solved here (benchmarks that time the columns turn it off).
    ``remember_substeps``: an increment starts split as finely as the last one of its load kind needed
    (``contact._controls.solve_with_substeps``); off, each tries the whole step first (``studies benchmark
    --substeps`` compares the two).
    """
    check_scene_limits(scene)
    prepared = prepared or prepare(scene, progress)
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
    frictional = scene.has_tangential_load and scene.contact.friction_coefficient > 0
    if not frictional:
        left_out.append("tangential contact unknowns: the path has no shear or twist load, or "
                        "friction_coefficient = 0")
    components = (0, 1, 2) if frictional else (2,)
    compliance_key = (candidates.tobytes(), components)
    column_cache = ColumnCache() if cache_compliance else None
    disk_key = None
    if compliance_key not in prepared.compliances:
        compliance = SurfaceCompliance(model, prepared.factorization, candidates, components)
        if column_cache is not None:
            disk_key = compliance_cache_key(model, scene.material.E, scene.material.nu, candidates, components,
                                            prepared.half)
            stored = column_cache.load(disk_key, compliance.size)
            if stored is not None:
                compliance.preload(*stored)
        prepared.compliances[compliance_key] = compliance
    compliance = prepared.compliances[compliance_key]
    columns_before = compliance.computed_columns
    seconds_before = compliance.seconds
    positions = model.top.positions[candidates]
    gap0 = scene.body.initial_gap(positions[:, :2]) - positions[:, 2]       # the gel's top point is at z = 0
    def lever_at(xy, center=scene.body.center):
        """Rigid twist motion per radian at points xy (n, 2) about ``center``: (-(y - y_c), x - x_c) [mm/rad]."""
        return np.column_stack([-(xy[:, 1] - center[1]), xy[:, 0] - center[0]])

    lever = lever_at(positions[:, :2])
    areas = model.top.areas[candidates]
    candidate_triangles = surface_triangles(model.top.triangles, candidates, model.top.areas.size)
    augmentation = _augmentation(areas, scene.material.effective_modulus)
    n = candidates.size
    state = ContactState(np.zeros(n), np.zeros((n, 2)), np.zeros((n, 3)))
    # First Newton iterate of a force-controlled press: half the Hertz depth, whose geometric overlap
    # r < sqrt(2 R d) matches the Hertz contact radius; the full depth would start with sqrt(2) a and twice the
    # points (each needing compliance columns).
    seed_depth = 0.5 * estimated_contact(scene)[1]
    result = ContactResult(scene, model, candidates, timings=timings, mesh_info=dict(prepared.mesh_info),
                           left_out=left_out, candidate_bump=assign_bumps(positions, centers), bump_centers=centers)
    controls = list(load_controls(scene))
    finite_strain = None
    if scene.material.law == MaterialLaw.NEO_HOOKEAN:
        if prepared.finite_strain is None:
            prepared.finite_strain = FiniteStrainGel(model, scene.material.E, scene.material.nu)
        finite_strain = prepared.finite_strain
        iterations_before = finite_strain.iterations
        left_out.append("finite strain: the gap is paired along z at each point's moved position (exact for the "
                        "plane body); an increment's twist turns the points about the lever arms they have at its "
                        "start (first order in the increment's angle)")
    warned: set = set()
    linear_solver = NewtonLinearSolver()
    bar = None
    level, level_kind = 0, None      # sub-step level the last increment of this load kind needed (_controls)
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(controls), desc=scene.name, unit="increment")
    try:
        for kind, control, friction_on in controls:
            step_start = time.perf_counter()
            control = scaled(control, 1.0 / multiplicity)
            if finite_strain is not None:          # the plate turns the points where they are, about where it is
                lever = lever_at(positions[:, :2] + state.displacement[:, :2],
                                 np.asarray(scene.body.center) + state.shift)
            try:
                check_feasible(control, state, scene.contact.friction_coefficient, lever)
            except ValueError as error:
                raise LoadNotCarried(f"increment {len(result.increments) + 1} ({kind}): {error}", result) from None
            friction_coefficient = scene.contact.friction_coefficient if friction_on else 0.0

            def solve(start_state, target):
                if finite_strain is not None:
                    return solve_finite_strain_increment(finite_strain, candidates, gap0, lever, augmentation,
                                                         friction_coefficient, start_state, target,
                                                         seed_depth=seed_depth, tolerance=scene.contact.tolerance,
                                                         max_iterations=scene.contact.max_iterations,
                                                         mirror_y=prepared.half, frictional=frictional)
                return solve_increment(compliance, gap0, lever, augmentation, friction_coefficient, start_state,
                                       target, seed_depth=seed_depth, tolerance=scene.contact.tolerance,
                                       max_iterations=scene.contact.max_iterations, mirror_y=prepared.half,
                                       linear_solver=linear_solver)

            try:
                if kind != level_kind or not remember_substeps:
                    level, level_kind = 0, kind
                state, iterations, history, substeps, level = solve_with_substeps(solve, state, control, lever,
                                                                                  start_level=level)
            except ContactNotConverged as error:
                raise PathNotCompleted(f"increment {len(result.increments) + 1} ({kind}): {error}", result) from error
            result.increments.append(record_increment(kind, state, iterations, history, model, prepared.factorization,
                                                      candidates, areas, lever, scene,
                                                      time.perf_counter() - step_start, multiplicity, substeps,
                                                      candidate_triangles, result.candidate_bump, centers))
            increment = result.increments[-1]
            touching = state.status != OPEN
            tangential = increment.displacement_full[model.top.dofs[candidates[touching], :2]]    # (k, 2)
            slid = float(np.linalg.norm(tangential - np.asarray(increment.shift), axis=1).max(initial=0.0))
            check_increment_limits(scene, increment.depth, slid, increment.contact_radius, len(result.increments),
                                   result, warned)
            in_contact = int(np.count_nonzero(touching))
            if in_contact < MIN_POINTS_PER_CONTACT * len(centers):
                raise ContactUnderResolved(
                    f"increment {len(result.increments)} ({kind}): the contact covers only {in_contact} surface "
                    f"point(s) for {len(centers)} contact(s); at least {MIN_POINTS_PER_CONTACT} each "
                    f"are needed for a contact radius and a stick ratio: refine mesh.size_contact (now "
                    f"{scene.mesh.size_contact} mm) or raise the load", result)
            if bar is not None:
                bar.update(1)
    except (PathNotCompleted, LoadNotCarried, ContactUnderResolved, PhysicalLimitError) as error:
        result.error = str(error)
        raise
    finally:
        if bar is not None:
            bar.close()
        timings["contact"] = time.perf_counter() - contact_start
        timings["compliance_columns"] = compliance.computed_columns - columns_before   # new in this solve
        timings["compliance_seconds"] = compliance.seconds - seconds_before
        timings["compliance_columns_loaded"] = compliance.loaded if disk_key is not None else 0
        timings["newton_linear_seconds"] = linear_solver.seconds
        timings["newton_factorizations"] = linear_solver.factorizations
        timings["newton_krylov_iterations"] = linear_solver.krylov_iterations
        if finite_strain is not None:
            timings["finite_strain_newton_iterations"] = finite_strain.iterations - iterations_before
        if column_cache is not None and compliance.computed_columns > columns_before:
            key = disk_key or compliance_cache_key(model, scene.material.E, scene.material.nu, candidates, components,
                                                   prepared.half)
            try:
                column_cache.save(key, *compliance.stored())
            except OSError as error:                 # a full cache folder must not lose the result
                import warnings

                from fem.cache_dir import CacheWarning

                warnings.warn(f"compliance columns not cached in {str(column_cache.directory)!r} "
                              f"({error.strerror or error})", CacheWarning, stacklevel=2)
    return result
