"""Per-bump results of a contact increment: each surface point belongs to the contact (bump) whose first-contact point
is nearest, and the increment's forces, areas and states are summed per contact.

A bump array under a rigid plate has one contact per bump; the array's totals (``Increment.normal_force``,
``contact_radius`` = sqrt(total area / pi), ``stick_ratio``) mix them. Per bump: normal force P_i, tangential force
Q_i, its share of the array torque T_i about the twist centre (sum T_i = T), its torque about its own first-contact
point (the spin the bump's own friction carries), contact radius a_i = sqrt(A_i / pi), stick ratio
c_i / a_i = sqrt(A_stick,i / A_i), point counts by state, and the margin to gross slip

    m_i = 1 - sum_j |t_j| / (mu sum_j lambda_j)      over the bump's points j,

the share of the bump's friction capacity left: 1 with no tangential load, 0 when every point of the bump is on the
friction limit (the bump slides as a whole). Under pure shear it is 1 - |Q_i| / (mu P_i), the load-ratio margin of
Cattaneo-Mindlin; under twist and combined loads it is the same measure of the bump's traction field.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from contact._newton import OPEN, SLIP, STICK

__all__ = ["BumpResults", "BUMP_FIELDS", "assign_bumps", "bump_results", "bump_shear_displacements"]

ROUND_OFF = 1e-9     # |margin| below this is 0: sliding points sit on the cone to the Newton tolerance, not exactly

# per-bump quantities written to result.json, steps.csv (as bump<i>_<name>) and the VTU; vectors get _x, _y
BUMP_FIELDS = ("normal_force", "tangential_force", "torque", "spin_torque", "contact_area", "contact_radius",
               "stick_ratio", "gross_slip_margin", "open_points", "stick_points", "slip_points")


@dataclass(frozen=True, eq=False)
class BumpResults:
    """Per-bump scalars of one increment, k bumps (mm, N, N mm).

    Attributes
    ----------
    centers : (k, 2) first-contact points of the bumps [mm].
    normal_force : (k,) P_i [N]; sums to the increment's normal force.
    tangential_force : (k, 2) Q_i [N]; sums to the increment's tangential force.
    torque : (k,) T_i about the twist centre [N mm]; sums to the increment's torque.
    spin_torque : (k,) torque of the bump's tractions about its own first-contact point [N mm].
    contact_area, stick_area : (k,) [mm^2]; contact_radius = sqrt(contact_area / pi) [mm].
    stick_ratio : (k,) sqrt(stick_area / contact_area) [-] (0 where the bump has no contact).
    gross_slip_margin : (k,) 1 - sum |t| / (mu sum lambda) [-] (module docstring); 1 where the bump carries no
        normal force, 0 with mu = 0.
    open_points, stick_points, slip_points : (k,) counts of the bump's contact-candidate points by state.
    """

    centers: np.ndarray
    normal_force: np.ndarray
    tangential_force: np.ndarray
    torque: np.ndarray
    spin_torque: np.ndarray
    contact_area: np.ndarray
    stick_area: np.ndarray
    contact_radius: np.ndarray
    stick_ratio: np.ndarray
    gross_slip_margin: np.ndarray
    open_points: np.ndarray
    stick_points: np.ndarray
    slip_points: np.ndarray

    @property
    def count(self) -> int:
        return len(self.normal_force)

    def rows(self) -> list[dict]:
        """One plain dict per bump (JSON-ready): index, centre and every field of BUMP_FIELDS."""
        rows = []
        for index in range(self.count):
            row = {"bump": index, "center": [float(v) for v in self.centers[index]]}
            for name in BUMP_FIELDS:
                value = getattr(self, name)[index]
                row[name] = [float(v) for v in value] if np.ndim(value) else (
                    int(value) if name.endswith("_points") else float(value))
            rows.append(row)
        return rows

    def flat(self) -> dict:
        """bump<i>_<name> -> value for every bump and field (vectors as _x, _y), for one row of steps.csv."""
        flat = {}
        for row in self.rows():
            for name in BUMP_FIELDS:
                value = row[name]
                if isinstance(value, list):
                    flat[f"bump{row['bump']}_{name}_x"], flat[f"bump{row['bump']}_{name}_y"] = value
                else:
                    flat[f"bump{row['bump']}_{name}"] = value
        return flat


def assign_bumps(positions: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """Index (n,) of the nearest first-contact point (k, 2) [mm] to each point (n, 2+) in the plane."""
    offsets = positions[:, None, :2] - np.asarray(centers, dtype=float)[None, :, :]          # (n, k, 2)
    return np.argmin((offsets**2).sum(axis=2), axis=1)


def half_model_bumps(centers: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The bumps of a mirror half model (y >= 0 computed): each bump's mirror image in y = 0 (k,) (itself on the
    plane), the bumps cut by the plane (k,) bool, and the images that are not computed (k,) bool (y < 0)."""
    centers = np.asarray(centers, dtype=float)
    mirror = np.argmin(np.linalg.norm(centers[:, None, :] - centers[None, :, :] * [1.0, -1.0], axis=2), axis=1)
    cut = mirror == np.arange(len(centers))
    return mirror, cut, (centers[:, 1] < 0.0) & ~cut


def bump_results(bump: np.ndarray, centers: np.ndarray, status: np.ndarray, normal_force: np.ndarray,
                 tangential_force: np.ndarray, areas: np.ndarray, positions: np.ndarray, lever: np.ndarray,
                 friction_coefficient: float, multiplicity: float = 1.0) -> BumpResults:
    """Sum the point results of one increment per bump.

    bump (n,) bump index of each candidate point; centers (k, 2) [mm]; status (n,) OPEN/STICK/SLIP; normal_force
    (n,) [N]; tangential_force (n, 2) [N]; areas (n,) tributary areas [mm^2]; positions (n, 2+) [mm]; lever (n, 2)
    twist lever arms about the twist centre [mm/rad]. ``multiplicity`` = 2 for a mirror half model (y >= 0
    computed): a bump cut by the plane y = 0 counts its forces and areas along x twice and its y-force and torques
    cancel (as in ``contact.result.record_increment``); a bump off the plane is whole in the computed half, and its
    mirror takes its values with y-force and torques negated. The point counts are those of the computed points.
    """
    count = len(centers)

    def per_bump(values):
        return np.bincount(bump, weights=values, minlength=count)

    normal = per_bump(normal_force)
    tangential = np.column_stack([per_bump(tangential_force[:, 0]), per_bump(tangential_force[:, 1])])
    torque = per_bump((lever * tangential_force).sum(axis=1))
    arm = positions[:, :2] - np.asarray(centers, dtype=float)[bump]                        # (n, 2) [mm]
    spin = per_bump(arm[:, 0] * tangential_force[:, 1] - arm[:, 1] * tangential_force[:, 0])
    contact_area = per_bump(np.where(status != OPEN, areas, 0.0))
    stick_area = per_bump(np.where(status == STICK, areas, 0.0))
    used = per_bump(np.linalg.norm(tangential_force, axis=1))
    counts = [np.bincount(bump[status == code], minlength=count) for code in (OPEN, STICK, SLIP)]
    if multiplicity != 1.0:
        mirror, cut, image = half_model_bumps(centers)          # cut: half of the bump computed
        for values in (normal, tangential[:, 0], contact_area, stick_area, used):
            values[cut] *= multiplicity
        for values in (tangential[:, 1], torque, spin):
            values[cut] = 0.0
        source = mirror[image]                                  # an image that is not computed: its mirror's values
        for values in (normal, tangential[:, 0], contact_area, stick_area, used, *counts):
            values[image] = values[source]
        for values in (tangential[:, 1], torque, spin):
            values[image] = -values[source]
    touching = contact_area > 0.0
    capacity = friction_coefficient * normal
    margin = np.where(capacity > 0.0, 1.0 - used / np.where(capacity > 0.0, capacity, 1.0),
                      np.where(normal > 0.0, 0.0, 1.0))
    return BumpResults(
        centers=np.asarray(centers, dtype=float), normal_force=normal, tangential_force=tangential, torque=torque,
        spin_torque=spin, contact_area=contact_area, stick_area=stick_area,
        contact_radius=np.sqrt(contact_area / np.pi),
        stick_ratio=np.where(touching, np.sqrt(stick_area / np.where(touching, contact_area, 1.0)), 0.0),
        gross_slip_margin=np.where(np.abs(margin) < ROUND_OFF, 0.0, margin), open_points=counts[0],
        stick_points=counts[1], slip_points=counts[2])


def bump_shear_displacements(result) -> np.ndarray:
    """Shear displacement of each bump per increment, (t, k, 2) [mm]: the gel surface's tangential displacement
    averaged over the bump's contact with the contact normal forces as weights - its value at the bump's centre of
    pressure, the point whose motion the paper's CoP estimator tracks (sec. IV-B: "the displacement of the robot
    elastic fingertip in the tangential direction").

    It is the bump's elastic deformation, not the body's motion: a bump stuck to the body moves with it, one that
    slides (partly or as a whole) lags it by its slip. ``result``: a ``contact.result.ContactResult`` of a bump
    array (``candidate_bump``, ``bump_centers``). In a mirror half model (y >= 0 computed, ``half_model_bumps``) a
    bump on the other side takes its mirror's value with y negated, and a bump cut by the plane has no y part (by
    symmetry). A bump without contact in an increment is NaN there.
    """
    centers = np.asarray(result.bump_centers, dtype=float)
    count = len(centers)
    bump = result.candidate_bump
    dofs = result.model.top.dofs[result.candidates, :2]
    areas = result.candidate_areas
    half = bool(result.mesh_info.get("half_model"))
    mirror, cut, image = half_model_bumps(centers)
    shears = np.full((len(result.increments), count, 2), np.nan)
    for number, increment in enumerate(result.increments):
        weights = np.where(increment.status != OPEN, increment.pressure * areas, 0.0)
        total = np.bincount(bump, weights=weights, minlength=count)
        tangential = increment.displacement_full[dofs]                                   # (n, 2) [mm]
        touching = total > 0.0
        for axis in range(2):
            weighted = np.bincount(bump, weights=weights * tangential[:, axis], minlength=count)
            shears[number, touching, axis] = weighted[touching] / total[touching]
        if half:
            shears[number, cut & touching, 1] = 0.0
            shears[number, image] = shears[number, mirror[image]] * [1.0, -1.0]
    return shears
