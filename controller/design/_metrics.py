"""Metrics of one fingertip design from its FEM paths and its sensor: estimation errors, the stick-ratio drop near
gross slip, force and torque capacity per unit grasp force, and the mesh's error estimate."""

from __future__ import annotations

import numpy as np

__all__ = ["METRICS", "capacity_metrics", "drop_metrics", "mesh_metrics", "estimation_metrics"]

# name -> (meaning, unit, better): the design table's metric columns
METRICS = {
    "translational_error": ("mean relative error of the estimated shear displacement against the bumps' own (their "
                            "contact's force-weighted tangential displacement: elastic, without the slip the plate "
                            "runs ahead by), held-out shear increments, gain calibrated on the first two", "-",
                            "lower"),
    "translational_error_uncalibrated": ("the same with gain 1 (the sensor-plane CoP shift itself)", "-", "lower"),
    "rotational_error": ("mean relative error of the eq. 9 rotation on the twist path (same gain) against the eq. 9 "
                         "rotation of the bumps' own shear displacements; none for one bump", "-", "lower"),
    "calibrated_gain": ("shear displacement per CoP shift fitted on the first two shear increments", "-", None),
    "stick_ratio_last": ("array stick ratio c/a at the last shear load ratio", "-", None),
    "stick_ratio_drop": ("c/a at the last load ratio r / (1 - r): mean slope of the drop still ahead at gross slip "
                         "(high: sudden, as a flat pad; Cattaneo-Mindlin gives (1 - r)^(1/3) / (1 - r))", "1", "lower"),
    "force_capacity": ("largest tangential force per unit grasp force, mu sum lambda / P (a rigid plate: mu)", "-",
                       "higher"),
    "torque_capacity": ("largest torque about the array centre per unit grasp force, no tangential load", "mm",
                        "higher"),
    "combined_torque_capacity": ("largest torque per unit grasp force while carrying half the force capacity",
                                 "mm", "higher"),
    "mesh_error_estimate": ("stick-ratio resolution 0.5 h / a of the smallest bump contact (docs/theory.md, "
                            "sec. 11.1)", "-", "lower"),
    "contact_radius_error": ("mean bump contact radius against Hertz with the bump's own normal force, minus 1",
                             "-", None),
}


def _least_torque(weights: np.ndarray, centres: np.ndarray, force: np.ndarray, iterations: int = 500) -> float:
    """min over v of sum_j w_j |v - c_j| - F . v (Weiszfeld iteration with the linear term; convex; converges for
    |F| < sum w). The torque a friction distribution w_j = mu lambda_j [N] at points r_j can carry about +z with a
    tangential load F [N]: for a sliding twist (v, omega = 1) the points slide with v + z x r_j = v - c_j,
    c_j = -z x r_j (docs/theory.md, sec. 9.2, with the FEM's point forces instead of bump ellipses)."""
    point = (weights[:, None] * centres).sum(axis=0) / weights.sum()
    for _ in range(iterations):
        distance = np.maximum(np.linalg.norm(point - centres, axis=1), 1e-12)
        updated = ((weights / distance)[:, None] * centres).sum(axis=0) + force
        updated /= (weights / distance).sum()
        if np.linalg.norm(updated - point) < 1e-12 * (1.0 + np.linalg.norm(point)):
            point = updated
            break
        point = updated
    return float((weights * np.linalg.norm(point - centres, axis=1)).sum() - force @ point)


def capacity_metrics(press, candidate_positions, candidate_areas, centre, friction_coefficient: float) -> dict:
    """Force and torque capacity per unit grasp force from the pressed state (``METRICS``)."""
    normal = press.pressure * candidate_areas                                   # (n,) [N]
    weights = friction_coefficient * normal
    loaded = weights > 0.0
    weights = weights[loaded]
    arm = candidate_positions[loaded, :2] - np.asarray(centre, dtype=float)
    centres = np.column_stack([arm[:, 1], -arm[:, 0]])                          # c_j = -z x r_j
    grasp = float(normal.sum())
    half = np.array([0.5 * weights.sum(), 0.0])
    return {"force_capacity": float(weights.sum()) / grasp,
            "torque_capacity": _least_torque(weights, centres, np.zeros(2)) / grasp,
            "combined_torque_capacity": _least_torque(weights, centres, half) / grasp}


def drop_metrics(shear_increments, load_ratios) -> dict:
    """Stick ratio at the last load ratio and the slope of the drop left to gross slip (``METRICS``)."""
    last = shear_increments[-1].stick_ratio
    ratio = float(load_ratios[len(shear_increments) - 1])
    return {"stick_ratio_last": float(last), "stick_ratio_drop": float(last) / (1.0 - ratio)}


def mesh_metrics(press, size_contact: float, bump_radius: float, youngs_modulus: float, poissons_ratio: float) -> dict:
    """The mesh's error estimate and the bump contact radii against Hertz (``METRICS``)."""
    from contact.theory import hertz

    bumps = press.bumps
    touching = bumps.contact_radius > 0.0
    radius = bumps.contact_radius[touching]
    e_star = youngs_modulus / (1.0 - poissons_ratio**2)
    reference = np.asarray(hertz(bumps.normal_force[touching], bump_radius, e_star).contact_radius, dtype=float)
    return {"mesh_error_estimate": 0.5 * size_contact / float(radius.min()),
            "contact_radius_error": float(np.mean(radius / reference) - 1.0)}


def _mean_relative(estimated: np.ndarray, applied: np.ndarray) -> float:
    return float(np.mean(np.abs(estimated - applied) / np.abs(applied)))


def estimation_metrics(shear, twist, array, layout, draws, frames: int) -> tuple[dict, dict]:
    """Translational and rotational estimation errors (``METRICS``), averaged over noise draws ``draws`` (seeds);
    and per-increment mean estimates {"shift": (t,), "angle": (t,)} and the bumps' mean shear displacement
    {"bump_shift": (t,)} for the increment table.

    Translation: what the estimator estimates is the bumps' shear displacement (``contact.bumps
    .bump_shear_displacements``, against the press), not the plate's shift: force control up to Q / (mu P) = 0.95
    lets the bumps' edges slide, and the plate then runs ahead of the gel by the slip. The estimate is the gain
    times the bumps' mean CoP shift along x, the gain fitted per bump on the first two shear increments
    (``controller.estimation.calibration.calibrate_gain``), the error taken over the others against the bumps' mean
    shear displacement along x. Rotation: the eq. 9 rotation of the gain-scaled CoP shifts on the twist path against the
    eq. 9 rotation of the bumps' own shear displacements (the plate's angle less the bumps' slip).
    """
    from contact.bumps import bump_shear_displacements
    from controller.estimation.bench import averaged_cop_shifts, readings_operator
    from controller.estimation.calibration import EstimatorCalibration, calibrate_gain
    from controller.estimation.estimator import estimate_slip
    from controller.estimation.rigid_transform import fit_rigid_transform

    bump_shift = bump_shear_displacements(shear)
    bump_shift = bump_shift[1:] - bump_shift[0]                                              # (t, k, 2) [mm]
    if not np.all(np.isfinite(bump_shift)):
        raise ValueError("a bump lost contact on the shear path: its shear displacement is undefined")
    applied = bump_shift[:, :, 0].mean(axis=1)                                               # (t,) [mm]
    if twist is not None:
        turned = bump_shear_displacements(twist)
        if not np.all(np.isfinite(turned)):
            raise ValueError("a bump lost contact on the twist path: its shear displacement is undefined")
        centers = np.asarray(twist.bump_centers, dtype=float)
        applied_angles = fit_rigid_transform(centers, centers + (turned[1:] - turned[0])).rotation     # (t,) [rad]
    outcomes, shifts, angles = [], [], []
    shear_operator = readings_operator(shear, array)                  # built once for every draw
    twist_operator = readings_operator(twist, array) if twist is not None else None
    for seed in draws:
        cop_shift = averaged_cop_shifts(shear, array, layout, seed, frames, shear_operator)[0]  # (t + 1, k, 2)
        calibration = calibrate_gain(cop_shift[1:3], bump_shift[:2])
        raw = cop_shift[1:, :, 0].mean(axis=1)
        estimate = calibration.gain * raw
        outcome = {"translational_error": _mean_relative(estimate[2:], applied[2:]),
                   "translational_error_uncalibrated": _mean_relative(raw[2:], applied[2:]),
                   "calibrated_gain": calibration.gain}
        shifts.append(estimate)
        if twist is not None:
            _, readings, reference, settings = averaged_cop_shifts(twist, array, layout, seed, frames,
                                                                          twist_operator)
            rotation = estimate_slip(readings, array, layout, reference,
                                     EstimatorCalibration(gain=calibration.gain), settings).transform.rotation[1:]
            outcome["rotational_error"] = _mean_relative(rotation, applied_angles)
            angles.append(rotation)
        outcomes.append(outcome)
    metrics = {key: float(np.mean([o[key] for o in outcomes])) for key in outcomes[0]}
    if twist is None:
        metrics["rotational_error"] = None                  # one bump: eq. 9 needs two (the table shows <NA>)
    estimates = {"shift": np.mean(shifts, axis=0), "angle": np.mean(angles, axis=0) if angles else None,
                 "bump_shift": applied, "bump_angle": applied_angles if twist is not None else None}
    return metrics, estimates
