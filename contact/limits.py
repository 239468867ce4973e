"""Limits checked before and while solving: what the linear, small-strain, small-sliding model can answer, and what
the machine can hold.

Before meshing (``check_scene_limits``, ``check_resources``), from closed-form estimates of the largest press:
- small strain: indentation d against the gel's thickness H under the contact; past SMALL_STRAIN_WARN a warning,
  past SMALL_STRAIN_REFUSE refused (a linear gel pressed through half its thickness says nothing);
- a small contact against the curvature: a >= R refused; below, the small-strain envelope measured against a
  finite-strain gel (``contact.envelope``, per quantity: normal force and contact radius up to a contact width a/R,
  tangential and torsional compliance, stick ratio and the base pressure's centre up to a load ratio) warns;
- size: the tets, DOF and memory of the mesh the settings ask for (``fem.mesh.size_cells``), refused when the
  estimate exceeds the machine's physical memory, a warning when it exceeds what is free at that instant.
While solving (``check_increment_limits``), on each converged increment: the computed depth against the thickness
(same thresholds), its contact width and load ratios against the small-strain envelope (a warning per quantity), and,
for a sphere, the distance a contact point has slid against the contact radius (the gap is paired at the start:
small sliding); past SLIDING_WARN a warning, past SLIDING_REFUSE refused.
A refusal is ``PhysicalLimitError`` (a ValueError); a warning is ``PhysicalLimitWarning``. The finite-strain gel
(``material.law = "neo_hookean"``) is not warned about strain or the small-strain envelope; its refusals stand.
"""

from __future__ import annotations

import math
import os
import warnings

import numpy as np

from contact.envelope import outside_envelope
from contact.scene import BodyShape, GelShape, LoadKind, MaterialLaw, Scene, Volumetric

__all__ = ["PhysicalLimitError", "PhysicalLimitWarning", "check_scene_limits", "check_increment_limits",
           "check_resources", "estimate_resources", "machine_memory", "available_memory", "contact_centers",
           "estimated_contact", "fine_depth", "fine_zone",
           "SMALL_STRAIN_WARN", "SMALL_STRAIN_REFUSE", "CONTACT_WIDTH_REFUSE", "SLIDING_WARN",
           "SLIDING_REFUSE"]

SMALL_STRAIN_WARN = 0.1      # d / H: the linear answer's error grows with the strain, ~10 % here
SMALL_STRAIN_REFUSE = 0.5    # d / H: half the thickness pressed away; a linear gel says nothing there
CONTACT_WIDTH_REFUSE = 1.0   # a / R: a contact wider than the sphere's radius has no small-strain meaning
# below a/R = 1 the measured small-strain envelope (contact.envelope) warns per quantity, in place of the former rule
# of thumb a/R > 0.4
SLIDING_WARN = 0.1           # slid distance / a: the gap paired at the start is off by about this fraction of d
SLIDING_REFUSE = 0.5         # slid distance / a: half the contact has moved onto other body points
# peak memory = interpreter and libraries + factor (fill ~ n^(4/3)) + dense surface compliance. Measured peaks
# (resident set, whole process): HCM-1 at h = 0.2 / 0.1 / 0.07 mm 0.46 / 1.31 / 2.53 GB at 27k / 93k / 191k DOF;
# the stability block at h = 0.15 mm 0.60 GB (P1, 42.6k DOF), 1.21 GB (P2, 76.7k), 0.95 GB (nodal-average P1, 42.1k:
# its saddle-point system takes 2.2x the P1 memory above the 0.3 GB base); the Fig. 4 cap 0.41 GB (15.7k), the 3x3
# array 0.83 GB (37.2k). The factor term is calibrated on the largest with a margin of 1.5; with the mesh estimate the
# whole estimate is 1.7-5x these peaks (the most for the array's worst-case compliance and the finest HCM-1 mesh).
BASE_BYTES = 0.3e9
BYTES_PER_FACTOR_DOF = 1.5 * 2.53e9 / 190.6e3**(4 / 3)
SADDLE_POINT_MEMORY = 2.2


class PhysicalLimitError(ValueError):
    """The scene asks what the model cannot answer (or the machine cannot hold); ``result`` keeps the increments
    converged before (None when refused before the solve)."""

    def __init__(self, message: str, result=None):
        super().__init__(message)
        self.result = result


class PhysicalLimitWarning(UserWarning):
    """Past a stated threshold of small strain or small sliding: the answer is less accurate than usual."""


def _max_normal_load(scene: Scene) -> tuple[float | None, float | None]:
    forces = [v for load in scene.loads if load.kind == LoadKind.PRESS and load.control == "force" for v in load.values]
    depths = [v for load in scene.loads if load.kind == LoadKind.PRESS and load.control == "displacement"
              for v in load.values]
    return (max(forces) if forces else None), (max(depths) if depths else None)


def contact_centers(scene: Scene) -> np.ndarray:
    """Where the body first touches the gel, (k, 2) [mm]: below a sphere's centre, or every bump top for a plane."""
    if scene.body.shape == BodyShape.SPHERE:
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
    radius = _contact_curvature_radius(scene)
    if math.isfinite(radius):
        from_force = (3.0 * (force or 0.0) / n_centers * radius / (4.0 * e_star)) ** (1 / 3)
        contact_radius = max(from_force, math.sqrt(radius * depth) if depth else 0.0)
        return contact_radius, contact_radius**2 / radius
    if scene.gel.shape == "flat_cap":
        flat = scene.gel.geometry.flat_radius
        indentation = max(depth or 0.0, (force or 0.0) / n_centers / (2.0 * e_star * flat))
        return flat + math.sqrt(2.0 * scene.gel.geometry.edge_radius * indentation), indentation
    half_diagonal = 0.5 * math.hypot(scene.gel.width, scene.gel.depth)
    return half_diagonal, depth or 1e-3 * scene.gel.thickness


def fine_zone(scene: Scene) -> tuple[float, bool]:
    """Radius [mm] of the fine-element zone around each first contact (``mesh.fine_radius``, else 1.3 x the
    estimated contact radius + 2 h) and whether the scene is solved on its mirror half."""
    fine_radius = scene.mesh.fine_radius or (1.3 * estimated_contact(scene)[0] + 2.0 * scene.mesh.size_contact)
    return fine_radius, scene.contact.symmetry == "auto" and scene.mirror_symmetric


FINE_DEPTH_FRACTION = 0.5     # fine zone depth / contact radius: Hertz's largest shear stress lies at 0.48 a
SHALLOW_FINE_DEPTH = 0.2      # mm, fem.mesh.BlockMeshSpec's default: a plane pressing a block's whole top


def fine_depth(scene: Scene) -> float:
    """Depth [mm] below the top down to which a block's elements keep ``mesh.size_contact``: FINE_DEPTH_FRACTION x
    the estimated contact radius under a sphere (the subsurface stress field lives within about a of the surface; a
    fine layer only 0.2 mm deep left HCM-1's block 2-4 % too stiff, docs/coupled_reference.md), at most half the
    block; SHALLOW_FINE_DEPTH otherwise."""
    if scene.gel.shape != GelShape.BLOCK or scene.body.shape != BodyShape.SPHERE:
        return SHALLOW_FINE_DEPTH
    return min(max(FINE_DEPTH_FRACTION * estimated_contact(scene)[0], SHALLOW_FINE_DEPTH), 0.5 * scene.gel.thickness)


def _contact_curvature_radius(scene: Scene) -> float:
    """Effective radius R [mm] of the first contact, 1/R = 1/R_body + 1/R_gel (inf for flat on flat)."""
    body_radius = scene.body.radius if scene.body.shape == BodyShape.SPHERE else math.inf
    curvature = 1.0 / body_radius + 1.0 / scene.gel.curvature_radius
    return 1.0 / curvature if curvature > 0.0 else math.inf


def _estimated_depth(scene: Scene) -> float:
    """Indentation [mm] of the largest press: given (depth), Hertz / flat punch, or a plane pressing a block's whole
    top (uniform compression P H / (E W D))."""
    force, depth = _max_normal_load(scene)
    if depth is not None and force is None:
        return depth
    if scene.gel.shape == GelShape.BLOCK and scene.body.shape == BodyShape.PLANE:
        from_force = force * scene.gel.thickness / (scene.material.E * scene.gel.width * scene.gel.depth)
        return max(from_force, depth or 0.0)
    return estimated_contact(scene)[1]


def _level(ratio: float, warn: float, refuse: float) -> int:
    """0 within the model, 1 past ``warn``, 2 at or past ``refuse`` or not finite (no number to trust)."""
    if not math.isfinite(ratio) or ratio >= refuse:
        return 2
    return 1 if ratio > warn else 0


def check_scene_limits(scene: Scene) -> list[str]:
    """Warn (PhysicalLimitWarning) past the small-strain and contact-width thresholds and refuse
    (PhysicalLimitError) past their limits, from closed-form estimates of the largest press; returns the warnings."""
    thickness = scene.gel.thickness_under_contact
    depth = _estimated_depth(scene)
    strain = depth / thickness
    problems, notes = [], []
    small_strain = scene.material.law == MaterialLaw.LINEAR     # the finite-strain gel needs no strain warning
    level = _level(strain, SMALL_STRAIN_WARN, SMALL_STRAIN_REFUSE)
    if level == 2:
        problems.append(f"the largest press would indent the gel about {depth:.3g} mm into its {thickness:g} mm "
                        f"(d/H = {strain:.3g}, half-space estimate): past d/H = {SMALL_STRAIN_REFUSE} "
                        + ("a linear, small-strain gel means nothing" if small_strain else
                           "the finite-strain gel is not validated (CalculiX's comparison reaches d/R = 0.39)")
                        + "; lower the press")
    elif level == 1 and small_strain:
        notes.append(f"the largest press indents the gel about {depth:.3g} mm into its {thickness:g} mm (d/H = "
                     f"{strain:.2f} > {SMALL_STRAIN_WARN}): past small strain, the linear answer is less accurate")
    radius = _contact_curvature_radius(scene)
    if math.isfinite(radius):
        contact_radius = estimated_contact(scene)[0]
        width = contact_radius / radius
        if not math.isfinite(width) or width >= CONTACT_WIDTH_REFUSE:
            problems.append(f"the contact radius would be about {contact_radius:.3g} mm on a curvature radius of "
                            f"{radius:.3g} mm (a/R = {width:.3g} >= {CONTACT_WIDTH_REFUSE}): not a small contact; "
                            f"lower the press")
        elif small_strain:
            loads = {load.kind.value for load in scene.loads}
            outside = outside_envelope(width, *_planned_load_ratios(scene, contact_radius), loads)
            if outside:
                notes.append(f"contact radius about {contact_radius:.3g} mm on a curvature radius of {radius:.3g} mm "
                             f"(a/R = {width:.2f}){_load_text(scene, contact_radius)}: outside the small-strain "
                             f"envelope measured against finite strain (docs/finite_strain.md) for "
                             + "; ".join(bound.describe() for bound in outside))
    if problems:
        raise PhysicalLimitError("\n".join(problems))
    for note in notes:
        warnings.warn(note, PhysicalLimitWarning, stacklevel=3)
    return notes


def check_increment_limits(scene: Scene, depth: float, slid: float, contact_radius: float, number: int, result,
                           warned: set) -> None:
    """After a converged increment: the computed ``depth`` [mm] against the thickness, and (a sphere) the largest
    distance ``slid`` [mm] by a contact point against the contact radius [mm]; warn once per kind, refuse past the
    limits (PhysicalLimitError keeping ``result``)."""
    thickness = scene.gel.thickness_under_contact
    strain = depth / thickness
    level = _level(strain, SMALL_STRAIN_WARN, SMALL_STRAIN_REFUSE)
    small_strain = scene.material.law == MaterialLaw.LINEAR
    if level == 2:
        beyond = "past small strain" if small_strain else "past what the finite-strain gel is validated for"
        raise PhysicalLimitError(f"increment {number}: the body is {depth:.3g} mm into the {thickness:g} mm gel "
                                 f"(d/H = {strain:.3g} >= {SMALL_STRAIN_REFUSE}): {beyond}, refused", result)
    if level == 1 and "strain" not in warned and small_strain:
        warned.add("strain")
        warnings.warn(f"increment {number}: depth {depth:.3g} mm of the {thickness:g} mm gel (d/H = {strain:.2f} > "
                      f"{SMALL_STRAIN_WARN}): past small strain", PhysicalLimitWarning, stacklevel=3)
    if small_strain:
        _check_envelope(scene, number, result, warned)
    if scene.body.shape != BodyShape.SPHERE or contact_radius <= 0.0:
        return                                   # a plane slides along itself, and a sphere twists in place
    sliding = slid / contact_radius
    level = _level(sliding, SLIDING_WARN, SLIDING_REFUSE)
    if level == 2:
        raise PhysicalLimitError(f"increment {number}: a contact point has slid {slid:.3g} mm, {sliding:.2f} of the "
                                 f"contact radius {contact_radius:.3g} mm (>= {SLIDING_REFUSE}): the contact is "
                                 f"paired at the start (small sliding), refused; shift less", result)
    if level == 1 and "sliding" not in warned:
        warned.add("sliding")
        warnings.warn(f"increment {number}: a contact point has slid {slid:.3g} mm, {sliding:.2f} of the contact "
                      f"radius (> {SLIDING_WARN}): the small-sliding gap is approximate", PhysicalLimitWarning,
                      stacklevel=3)


def _planned_load_ratios(scene: Scene, contact_radius: float) -> tuple[float, float]:
    """Largest Q/(mu P) and T/(mu P a) of the force-controlled shear and twist increments, with the largest press
    force and the estimated contact radius [mm] (0 where the path controls displacements: checked as it runs)."""
    force = _max_normal_load(scene)[0]
    mu = scene.contact.friction_coefficient
    if not force or mu <= 0.0:
        return 0.0, 0.0
    shear = [abs(v) for load in scene.loads if load.kind == LoadKind.SHEAR and load.control == "force"
             for v in load.values]
    twist = [abs(v) for load in scene.loads if load.kind == LoadKind.TWIST and load.control == "force"
             for v in load.values]
    return max(shear, default=0.0) / (mu * force), max(twist, default=0.0) / (mu * force * contact_radius)


def _load_text(scene: Scene, contact_radius: float) -> str:
    """', Q/(mu P) up to ..., T/(mu P a) up to ...' for the planned force-controlled loads ('' without them)."""
    shear, twist = _planned_load_ratios(scene, contact_radius)
    parts = ([f"Q/(mu P) up to {shear:.2f}"] if shear else []) + ([f"T/(mu P a) up to {twist:.2f}"] if twist else [])
    return f", {', '.join(parts)}" if parts else ""


def _check_envelope(scene: Scene, number: int, result, warned: set) -> None:
    """Warn once per quantity when a converged increment leaves the measured small-strain envelope
    (``contact.envelope``): its contact width a/R, load ratio Q/(mu P) and torque ratio T/(mu P a)."""
    radius = _contact_curvature_radius(scene)
    increment = result.increments[-1] if result is not None and result.increments else None
    if increment is None or not math.isfinite(radius) or increment.contact_radius <= 0.0:
        return
    mu = scene.contact.friction_coefficient
    bumps = getattr(increment, "bumps", None)
    if bumps is not None:
        # an array: each touching bump against the envelope - its own contact radius, Q_i / (mu P_i) and its spin
        # torque over mu P_i a_i (the array's torque is carried mostly by the bumps' tangential forces); the
        # widest bump is named
        touching = (bumps.normal_force > 0.0) & (bumps.contact_radius > 0.0)
        if not touching.any():
            return
        force, a = bumps.normal_force[touching], bumps.contact_radius[touching]
        shear = np.hypot(*np.asarray(bumps.tangential_force)[touching].T)
        states = [(a_i / radius, q / (mu * p) if mu > 0 else 0.0, abs(t) / (mu * p * a_i) if mu > 0 else 0.0)
                  for a_i, q, p, t in zip(a, shear, force, np.asarray(bumps.spin_torque)[touching])]
    else:
        force = increment.normal_force
        load_ratio = math.hypot(*increment.tangential_force) / (mu * force) if mu > 0 and force > 0 else 0.0
        torque_ratio = (abs(increment.torque) / (mu * force * increment.contact_radius) if mu > 0 and force > 0
                        else 0.0)
        states = [(increment.contact_radius / radius, load_ratio, torque_ratio)]
    loads = {load.kind.value for load in scene.loads}
    outside = {bound: state for state in states for bound in outside_envelope(*state, loads)}
    fresh = [bound for bound in outside if bound.quantity not in warned]
    if fresh:
        warned.update(bound.quantity for bound in fresh)
        width, load_ratio, torque_ratio = max(states)
        where = "" if bumps is None else f" (widest of {len(states)} touching bumps)"
        warnings.warn(f"increment {number}: a/R = {width:.2f}, Q/(mu P) = {load_ratio:.2f}, T/(mu P a) = "
                      f"{torque_ratio:.2f}{where}: outside the small-strain envelope measured against finite strain "
                      f"(docs/finite_strain.md) for " + "; ".join(bound.describe() for bound in fresh),
                      PhysicalLimitWarning, stacklevel=4)


def _meminfo(field: str) -> float | None:
    """A /proc/meminfo field [bytes] (Linux), None where unknown."""
    try:
        with open("/proc/meminfo") as stream:
            for line in stream:
                if line.startswith(f"{field}:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    return None


def _sysconf_pages(name: str) -> float | None:
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf(name))
    except (ValueError, OSError, AttributeError):
        return None


def machine_memory() -> float | None:
    """Bytes of physical memory of this machine (MemTotal), None where unknown: what a solve can never exceed."""
    return _meminfo("MemTotal") or _sysconf_pages("SC_PHYS_PAGES")


def available_memory() -> float | None:
    """Bytes available to a new allocation at this instant (MemAvailable), None where unknown: other processes
    change it from one second to the next, so it only warns, never refuses."""
    return _meminfo("MemAvailable") or _sysconf_pages("SC_AVPHYS_PAGES")


def estimate_resources(scene: Scene, fine_radius: float, half: bool) -> dict:
    """Estimated tets, nodes, DOF and peak memory [bytes] of the scene's mesh and solve, before meshing (factor ~2)."""
    from fem.mesh import BISECTION_TETS_PER_CELL, GMSH_TETS_PER_CELL, NODES_PER_TET, size_cells

    size_contact = scene.mesh.size_contact * scene.mesh.order
    geometry = scene.gel.geometry
    if scene.gel.shape == GelShape.BLOCK:
        from fem.mesh import BlockMeshSpec

        spec = BlockMeshSpec(width=geometry.width, depth=geometry.depth, thickness=geometry.thickness,
                             size_contact=min(size_contact, scene.mesh.size_far), size_far=scene.mesh.size_far,
                             fine_radius=fine_radius, fine_depth=fine_depth(scene),
                             fine_center=tuple(scene.body.center), grading=scene.mesh.grading)
        cells = size_cells(spec.target_size, [scene.body.center], geometry.width, geometry.depth / (2 if half else 1),
                           geometry.thickness, spec.size_contact)
        tets = BISECTION_TETS_PER_CELL * cells
    else:
        from fem.tetmesh import TetMeshSpec, _sizing

        spec = TetMeshSpec(size_contact=size_contact, size_far=max(scene.mesh.size_far, size_contact),
                           contact_radius=fine_radius, grading=scene.mesh.grading, size_base=scene.mesh.size_base)
        sizing = _sizing(geometry, spec)
        cells = size_cells(sizing.edge_length, sizing.centers, sizing.width, sizing.depth, geometry.height,
                           size_contact)
        tets = GMSH_TETS_PER_CELL * cells
    nodes = NODES_PER_TET * tets * (8.0 if scene.mesh.order == 2 else 1.0)     # + one node per edge (~7 per node)
    dofs = 3.0 * nodes
    surface_points = (math.pi * (fine_radius + 3.0 * scene.mesh.size_contact) ** 2 * len(contact_centers(scene))
                      / (0.5 * scene.mesh.size_contact**2) / (2 if half else 1))
    compliance_bytes = 8.0 * (3.0 * surface_points) ** 2                   # dense surface compliance, worst case
    factor_memory = SADDLE_POINT_MEMORY if scene.mesh.volumetric == Volumetric.NODAL_AVERAGE else 1.0
    return {"tets": tets, "nodes": nodes, "dofs": dofs, "surface_points": surface_points,
            "bytes": BASE_BYTES + factor_memory * BYTES_PER_FACTOR_DOF * dofs ** (4.0 / 3.0) + compliance_bytes}


def check_resources(scene: Scene, fine_radius: float, half: bool) -> dict:
    """Refuse (PhysicalLimitError) a mesh whose estimated memory exceeds this machine's physical memory; warn
    (PhysicalLimitWarning) when it exceeds what is available at this instant (other processes hold the rest)."""
    estimate = estimate_resources(scene, fine_radius, half)
    size = (f"mesh.size_contact={scene.mesh.size_contact} mm (order {scene.mesh.order}) would make about "
            f"{estimate['tets']:.2g} tets, {estimate['dofs']:.2g} DOF and need about {estimate['bytes'] / 1e9:.3g} GB")
    total, available = machine_memory(), available_memory()
    if total is not None and estimate["bytes"] > total:
        raise PhysicalLimitError(f"{size}; this machine has {total / 1e9:.3g} GB in all: raise mesh.size_contact or "
                                 f"mesh.size_far")
    if available is not None and estimate["bytes"] > available:
        warnings.warn(f"{size}; {available / 1e9:.3g} GB are free now (the estimate is 1.7-5x the measured peak): "
                      f"the solve may swap or be stopped", PhysicalLimitWarning, stacklevel=3)
    return estimate
