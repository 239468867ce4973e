"""Per-bump quantities of a load path on an array fingertip, from the FEM or from the reduced model, side by side.

The FEM gives fields on points: contact pressure and tangential traction on the candidate points of the gel's top,
pressure on the nodes of the sensor plane. Each point belongs to the bump whose centre is nearest (the Voronoi cell
the estimator uses on the sensor, ``controller.estimation.estimator.BumpLayout``); summing over a cell gives the bump's
normal and tangential force, its torque about its own axis, its contact area and, on the sensor plane, its share of the
base force with its centre of pressure (CoP) and second moment. The reduced model's states give the same arrays
(``PathSamples.from_reduced``: its base pressure on a grid, cut into the same cells), so that calibration and
held-out comparison read both sides alike. Everything is vectorised over increments and points.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from contact._newton import OPEN, STICK

from ._design import ArrayFingertipDesign

__all__ = ["PathSamples", "nearest_bump", "cell_moments", "model_cells", "check_scene_matches_design"]


def nearest_bump(xy, centres) -> np.ndarray:
    """Index (n,) of the nearest bump centre for points xy (n, 2) [mm] (ties to the lower index)."""
    xy, centres = np.asarray(xy, dtype=float), np.asarray(centres, dtype=float)
    distance = (xy[:, :1] - centres[:, 0]) ** 2 + (xy[:, 1:] - centres[:, 1]) ** 2           # (n, k)
    return np.argmin(distance, axis=1)


def cell_moments(xy, nodal_force, centres):
    """Force (..., k) [N], CoP (..., k, 2) [mm] and second moment <|x - CoP|^2> (..., k) [mm^2] per Voronoi cell.

    ``nodal_force`` (..., n) [N] is pressure times tributary area at the points xy (n, 2); signed (a bonded base
    carries tension where a bump tilts), so the moments are those of the signed field.
    """
    xy, nodal_force = np.asarray(xy, dtype=float), np.asarray(nodal_force, dtype=float)
    count, points = len(centres), len(xy)
    flat = nodal_force.reshape(-1, points)                                           # (m, n)
    bins = (np.arange(len(flat))[:, None] * count + nearest_bump(xy, centres)).ravel()  # (m n,) frame and cell

    def per_cell(values):                                                            # (m, n) -> (..., k)
        summed = np.bincount(bins, weights=values.ravel(), minlength=len(flat) * count)
        return summed.reshape(nodal_force.shape[:-1] + (count,))

    force = per_cell(flat)
    safe = np.where(force != 0.0, force, 1.0)
    centre = np.stack([per_cell(flat * xy[:, 0]), per_cell(flat * xy[:, 1])], axis=-1) / safe[..., None]
    second = per_cell(flat * (xy**2).sum(axis=1)) / safe - (centre**2).sum(axis=-1)   # parallel-axis theorem
    return force, centre, second


def model_cells(tip, grid, bump_force, displacement, tangential_force):
    """Cell force (m, k) [N], CoP (m, k, 2) [mm], second moment (m, k) [mm^2] of the model's base pressure.

    ``tip.base_pressure`` on ``grid`` for m bump states - normal forces (m, k) [N], displacements (m, k, 2) [mm],
    tangential forces (m, k, 2) [N] - cut into the bumps' Voronoi cells like an FEM sensor plane.
    """
    radius = tip.parameters.radius_coefficient * np.cbrt(np.maximum(bump_force, 0.0))
    nodal = np.stack([tip.base_pressure(grid, force, a, delta, q).ravel() for force, a, delta, q
                      in zip(bump_force, radius, displacement, tangential_force)]) * grid.spacing**2
    return cell_moments(grid.points, nodal, tip.centres)


def check_scene_matches_design(scene, design: ArrayFingertipDesign) -> None:
    """Raise ValueError naming each field where an FEM scene is not the fingertip ``design`` (or not a flat plate)."""
    if scene.gel.shape != "array" or scene.body.shape != "plane":
        raise ValueError(f"scene {scene.name!r}: gel.shape={scene.gel.shape!r}, body.shape={scene.body.shape!r}; "
                         f"a calibration needs an 'array' gel under a 'plane' body")
    geometry = scene.gel.geometry
    pairs = {"rows": geometry.rows, "cols": geometry.cols, "bump_radius": geometry.bump_radius,
             "pitch": geometry.pitch, "base_thickness": geometry.base_thickness,
             "youngs_modulus": scene.material.E, "poissons_ratio": scene.material.nu}
    wrong = {name: (value, getattr(design, name)) for name, value in pairs.items()
             if not math.isclose(value, getattr(design, name), rel_tol=1e-9)}
    for name, value, half in (("base_width", geometry.base_width, design.footprint[0]),
                              ("base_depth", geometry.base_depth, design.footprint[1])):
        if not math.isclose(value, 2.0 * half, rel_tol=1e-9):      # the model's base pressure lives on it
            wrong[name] = (value, 2.0 * half)
    if getattr(geometry, "fillet", 0.0) != 0.0:
        wrong["fillet"] = (geometry.fillet, 0.0)
    if tuple(scene.body.center) != (0.0, 0.0):
        wrong["body.center"] = (tuple(scene.body.center), (0.0, 0.0))
    if wrong:
        detail = ", ".join(f"{name}: scene {got!r} vs design {want!r}" for name, (got, want) in wrong.items())
        raise ValueError(f"scene {scene.name!r} is not the fingertip design ({detail})")


@dataclass(frozen=True, eq=False)
class PathSamples:
    """One load path (FEM or reduced model) as per-increment (t,) and per-bump (t, k) arrays [mm, N, N mm, rad].

    Attributes
    ----------
    case : str -- name of the load path.
    friction : float -- Coulomb mu of the scene [-].
    load_kind : (t,) str -- "press", "shear" or "twist" per increment.
    normal_force (t,) [N]; depth (t,) [mm] plate approach; shift (t, 2) [mm] plate translation; angle (t,) [rad]
    plate twist about the array centre; tangential_force (t, 2) [N]; torque (t,) [N mm] about the array centre;
    stick_ratio (t,) [-] sqrt(A_stick / A_contact) over all bumps.
    bump_normal_force (t, k) [N]; bump_tangential_force (t, k, 2) [N]; bump_torque (t, k) [N mm] about each bump's
    own axis; bump_contact_radius (t, k) [mm] sqrt(A_i / pi); bump_stick_ratio (t, k) [-].
    base_force (t, k) [N], base_centre (t, k, 2) [mm], base_second_moment (t, k) [mm^2]: the sensor-plane pressure
    per Voronoi cell; base_total_force (t,) [N] over the whole sensor plane.
    provenance : dict -- mesh sizes, DOF count and the load path, for the calibration record.
    """

    case: str
    friction: float
    load_kind: np.ndarray
    normal_force: np.ndarray
    depth: np.ndarray
    shift: np.ndarray
    angle: np.ndarray
    tangential_force: np.ndarray
    torque: np.ndarray
    stick_ratio: np.ndarray
    bump_normal_force: np.ndarray
    bump_tangential_force: np.ndarray
    bump_torque: np.ndarray
    bump_contact_radius: np.ndarray
    bump_stick_ratio: np.ndarray
    base_force: np.ndarray
    base_centre: np.ndarray
    base_second_moment: np.ndarray
    base_total_force: np.ndarray
    provenance: dict = field(default_factory=dict)

    @classmethod
    def from_result(cls, result, design: ArrayFingertipDesign, case: str | None = None) -> "PathSamples":
        """Samples of a ``contact.solver`` result of ``design`` (ValueError if its scene is another fingertip)."""
        scene = result.scene
        check_scene_matches_design(scene, design)
        if not result.increments:
            raise ValueError(f"result of scene {scene.name!r} has no converged increment")
        centres = design.bump_centres
        count = len(centres)
        points = result.candidate_positions[:, :2]                                   # (n, 2)
        areas = result.candidate_areas                                               # (n,)
        nearest = nearest_bump(points, centres)
        owner = np.eye(count)[nearest]                                               # (n, k)
        increments = result.increments
        status = np.stack([inc.status for inc in increments])                        # (t, n)
        normal = np.stack([inc.pressure for inc in increments]) * areas              # (t, n) [N]
        tangential = np.stack([inc.traction for inc in increments]) * areas[:, None]  # (t, n, 2) [N]
        arm = points - centres[nearest]                                              # (n, 2) from own centre
        spin = arm[:, 0] * tangential[..., 1] - arm[:, 1] * tangential[..., 0]        # (t, n) [N mm]
        contact_area = ((status != OPEN) * areas) @ owner                            # (t, k)
        stick_area = ((status == STICK) * areas) @ owner
        base = result.model.base
        base_nodal = np.stack([inc.base_pressure for inc in increments]) * base.areas  # (t, n_base) [N]
        base_force, base_centre, base_second = cell_moments(base.positions[:, :2], base_nodal, centres)
        provenance = {"case": case or scene.name, "loads": [_load_record(load) for load in scene.loads],
                      "size_contact": scene.mesh.size_contact, "size_base": scene.mesh.size_base,
                      "size_far": scene.mesh.size_far, "order": scene.mesh.order,
                      "fine_radius": result.mesh_info.get("fine_radius"), "dofs": result.mesh_info.get("dofs"),
                      "free_dofs": result.mesh_info.get("free_dofs"), "elements": result.mesh_info.get("elements")}
        return cls(
            case=case or scene.name, friction=float(scene.contact.friction_coefficient),
            load_kind=np.array([inc.load_kind for inc in increments]),
            normal_force=np.array([inc.normal_force for inc in increments]),
            depth=np.array([inc.depth for inc in increments]),
            shift=np.array([inc.shift for inc in increments], dtype=float),
            angle=np.array([inc.angle for inc in increments]),
            tangential_force=np.array([inc.tangential_force for inc in increments], dtype=float),
            torque=np.array([inc.torque for inc in increments]),
            stick_ratio=np.array([inc.stick_ratio for inc in increments]),
            bump_normal_force=normal @ owner,
            bump_tangential_force=np.stack([tangential[..., 0] @ owner, tangential[..., 1] @ owner], axis=-1),
            bump_torque=spin @ owner,
            bump_contact_radius=np.sqrt(contact_area / math.pi),
            bump_stick_ratio=np.sqrt(stick_area / np.where(contact_area > 0.0, contact_area, 1.0)),
            base_force=base_force, base_centre=base_centre, base_second_moment=base_second,
            base_total_force=base_nodal.sum(axis=1), provenance=provenance)

    @classmethod
    def from_reduced(cls, tip, case: str, load_kind, normal_force, friction: float, motion, control: str,
                     grid_spacing: float = 0.5) -> "PathSamples":
        """The reduced model ``tip`` (ReducedFingertip) along a load path, in the arrays an FEM path gives.

        ``motion`` (t, 3) is (t_x [mm], t_y [mm], theta [rad]) of the object for ``control="displacement"``
        (``displacement_state``) or (F_x [N], F_y [N], T [N mm]) about the array centre for ``control="force"``
        (``load_state``), at the total normal force ``normal_force`` (t,) [N] of an untilted plate. depth is the
        model's plate approach (P / (k k_n))^(2/3); the stick ratio sqrt(sum (c_i a_i)^2 / sum a_i^2) takes per bump
        the smaller of its translational and rotational c/a (the stick zone lies inside both). The base pressure is
        ``base_pressure`` of the states on a grid of ``grid_spacing`` [mm], cut into the bumps' Voronoi cells.
        """
        if control not in ("displacement", "force"):
            raise ValueError(f"control={control!r} is not one of ['displacement', 'force']")
        load_kind = np.asarray(load_kind)
        normal_force = np.asarray(normal_force, dtype=float)
        motion = np.asarray(motion, dtype=float).reshape(len(normal_force), 3)
        states = []
        for force, (first, second, third) in zip(normal_force, motion):
            if control == "displacement":
                states.append(tip.displacement_state(force, (first, second), third, friction))
            else:
                states.append(tip.load_state(force, (first, second), third, friction))
        base_force, base_centre, base_second = model_cells(
            tip, tip.base_grid(grid_spacing), np.stack([state.normal_force for state in states]),
            np.stack([state.shear_displacement for state in states]),
            np.stack([state.bump_tangential_force for state in states]))
        radius = np.stack([state.contact_radius for state in states])                     # (t, k)
        stick = np.stack([np.minimum(state.stick_ratio_translational, state.stick_ratio_rotational)
                          for state in states])
        bump_force = np.stack([state.normal_force for state in states])
        k_n = tip.parameters.normal_stiffness
        return cls(
            case=case, friction=float(friction), load_kind=load_kind, normal_force=normal_force,
            depth=(normal_force / len(tip.centres) / k_n) ** (2.0 / 3.0),
            shift=np.stack([state.translation for state in states]),
            angle=np.array([state.rotation for state in states]),
            tangential_force=np.stack([state.tangential_force for state in states]),
            torque=np.array([state.torque for state in states]),
            stick_ratio=np.sqrt(((stick * radius) ** 2).sum(axis=1) / (radius**2).sum(axis=1)),
            bump_normal_force=bump_force,
            bump_tangential_force=np.stack([state.bump_tangential_force for state in states]),
            bump_torque=np.stack([state.bump_torque for state in states]),
            bump_contact_radius=radius, bump_stick_ratio=stick,
            base_force=base_force, base_centre=base_centre, base_second_moment=base_second,
            base_total_force=base_force.sum(axis=1),
            provenance={"case": case, "model": tip.parameters.source, "control": control,
                        "grid_spacing": grid_spacing})

    def with_model_base(self, tip, grid_spacing: float = 0.5) -> "PathSamples":
        """This path with its sensor-plane fields from ``tip.base_pressure`` fed with the path's own bump loads.

        Bump normal and tangential forces and the plate displacement at each bump stay those of this path (e.g. the
        FEM's); base_force, base_centre, base_second_moment and base_total_force become the model's, on its grid
        of ``grid_spacing`` [mm] cut into the same cells. That isolates the base-pressure law from the bump laws.
        """
        grid = tip.base_grid(grid_spacing)
        force, centre, second = model_cells(tip, grid, self.bump_normal_force, self.bump_displacement(tip.centres),
                                            self.bump_tangential_force)
        return dataclasses.replace(self, base_force=force, base_centre=centre, base_second_moment=second,
                                   base_total_force=force.sum(axis=1),
                                   provenance=dict(self.provenance, base_model=tip.parameters.source))

    @property
    def pressed(self) -> np.ndarray:
        """Boolean mask (t,) of the press increments."""
        return self.load_kind == "press"

    @property
    def reference(self) -> np.ndarray:
        """Index (t,) of the press increment each increment starts from (the last press at or before it)."""
        index = np.where(self.pressed, np.arange(self.load_kind.size), -1)
        reference = np.maximum.accumulate(index)
        if reference[0] < 0:
            raise ValueError(f"case {self.case!r} does not start with a press")
        return reference

    @property
    def cop_shift(self) -> np.ndarray:
        """Base CoP shift per bump (t, k, 2) [mm] against the pressed state the increment started from."""
        return self.base_centre - self.base_centre[self.reference]

    def bump_displacement(self, centres) -> np.ndarray:
        """Plate displacement at each bump delta_i = t + theta z x r_i (t, k, 2) [mm], from the pressed state."""
        centres = np.asarray(centres, dtype=float)
        shift = self.shift - self.shift[self.reference]
        angle = self.angle - self.angle[self.reference]
        perpendicular = np.stack([-centres[:, 1], centres[:, 0]], axis=1)             # z x r_i (k, 2)
        return shift[:, None, :] + angle[:, None, None] * perpendicular


def _load_record(load) -> dict:
    return {"kind": load.kind.value, "control": load.control, "values": list(load.values),
            "direction": list(load.direction)}
