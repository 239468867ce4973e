"""Reduced-model calibration: fit the 3x3 fingertip's reduced parameters to FEM paths, check them on held-out FEM cases.

The FEM bench of figs. 6/9 (3x3 hemispheres R = 4.67 mm, pitch 13.33 mm, 3 mm base, E = 0.3 MPa, nu = 0.45, mu = 1,
rigid plate) runs three calibration paths - a press at several normal forces, a plate shift and a plate twist at
the calibration force - and ``contact.reduced.calibration`` fits k_n, c_a, G*, G_t, s, cop_gain and moment_arm to
them. Then held-out FEM paths that no fit saw (a press at 1 and 4 N, shear forces at 1 and 4 N, torques at 4 N, a
shear force followed by torques at 2 N; all force-controlled except the press) are compared with the reduced model
with closed-form parameters, with the parameters of this run and with the packaged calibration file: one CSV row
per case, increment, quantity (and bump, for per-bump quantities). All paths share one mesh and one factorization
(and the compliance columns of the points in contact).

Errors: ``*_error`` = reduced - FEM in the quantity's unit; ``*_relative_error`` = that over |FEM|, except for the
base-pressure CoP shift (a vector per bump): its error is the length of the difference vector and its relative error
that length over the largest FEM CoP shift of the increment (a bump near the twist centre barely moves).
"""

from __future__ import annotations

import datetime
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic

NAME = "reduced-calibration"
CALIBRATION_FILE = "fingertip_3x3_calibrated.json"
MODELS = ("closed_form", "calibrated", "packaged")


@dataclass(frozen=True)
class HeldOutCase:
    """A held-out FEM path: press ``normal_force`` [N], then ``stages`` of (kind, values): kind "shear" (force
    along x [N]) or "twist" (torque [N mm]), force-controlled; no stages: a press path through ``press_forces``."""

    name: str
    normal_force: float
    stages: tuple = ()
    press_forces: tuple = ()


@dataclass(frozen=True)
class StudyPlan:
    """FEM settings and load paths of the study [mm, N, rad].

    shear_paths: (normal force [N], plate shifts [mm]) per calibration shear path; two forces, so that the CoP fit
    can tell the displacement term from the load-ratio term. angles [rad]: the twist path at calibration_force.
    """

    size_contact: float
    size_base: float
    press_forces: tuple
    shear_paths: tuple
    angles: tuple
    held_out: tuple
    calibration_force: float = 2.0
    size_far: float = 3.0

    @classmethod
    def default(cls, quick: bool = False) -> "StudyPlan":
        from controller.bench import BENCH_SIZE_BASE, BENCH_SIZE_CONTACT, NORMAL_FORCE

        press = (1.5, 2.0, 3.0, 5.0)
        if quick:      # fig9's quick mesh (shared through the mesh cache); 1 N still has >= 7 points per bump
            return cls(0.7, 1.5, press, ((NORMAL_FORCE, (0.1, 0.3, 0.6)), (5.0, (0.2, 0.6))), (0.005, 0.015, 0.03),
                       (HeldOutCase("press_1N_4N", 0.0, press_forces=(1.0, 4.0)),
                        HeldOutCase("shear_force_1N", 1.0, (("shear", (0.5,)),)),
                        HeldOutCase("shear_force_4N", 4.0, (("shear", (2.0,)),)),
                        HeldOutCase("twist_torque_4N", 4.0, (("twist", (20.0,)),)),
                        HeldOutCase("shear_then_twist_2N", 2.0, (("shear", (0.5,)), ("twist", (8.0,))))),
                       NORMAL_FORCE)
        return cls(BENCH_SIZE_CONTACT, BENCH_SIZE_BASE, press,
                   ((NORMAL_FORCE, (0.05, 0.15, 0.3, 0.5)), (5.0, (0.1, 0.3, 0.6))), (0.004, 0.012, 0.025),
                   (HeldOutCase("press_1N_4N", 0.0, press_forces=(1.0, 4.0)),
                    HeldOutCase("shear_force_1N", 1.0, (("shear", (0.3, 0.6)),)),
                    HeldOutCase("shear_force_4N", 4.0, (("shear", (1.2, 2.4)),)),
                    HeldOutCase("twist_torque_4N", 4.0, (("twist", (10.0, 25.0)),)),
                    HeldOutCase("shear_then_twist_2N", 2.0, (("shear", (0.5,)), ("twist", (8.0,))))),
                   NORMAL_FORCE)


def add_arguments(parser) -> None:
    """--write-package-data: also store the fitted file as contact/reduced/data (the packaged calibration)."""
    parser.add_argument("--write-package-data", action="store_true",
                        help=f"also write the calibration to contact/reduced/data/{CALIBRATION_FILE}")


def _scene(plan: StudyPlan, name: str, loads, fine_radius: float):
    from contact.scene import BodySpec, ContactSpec, Material, MeshSettings, Scene
    from controller.bench import FRICTION, POISSONS_RATIO, YOUNGS_MODULUS, fingertip_gel

    return Scene(name=name, gel=fingertip_gel(3), material=Material(YOUNGS_MODULUS, POISSONS_RATIO),
                 body=BodySpec("plane"), contact=ContactSpec(friction_coefficient=FRICTION),
                 mesh=MeshSettings(size_contact=plan.size_contact, size_far=plan.size_far, size_base=plan.size_base,
                                   fine_radius=fine_radius), loads=tuple(loads))


def build_scenes(plan: StudyPlan) -> tuple[dict, dict]:
    """Calibration scenes {press, shear, twist} and held-out scenes {name: scene}, all on one mesh."""
    from contact.scene import Load, LoadKind
    from contact.solver import estimated_contact

    def press(*forces):
        return Load(LoadKind.PRESS, "force", tuple(forces))

    # the solver's own fine zone for the calibration press (1.3 a + 2 h): fig9's bench mesh, found in the disk cache;
    # fixed for every path so that all share one mesh and one factorization
    probe = _scene(plan, "probe", [press(plan.calibration_force)], None)
    fine_radius = 1.3 * estimated_contact(probe)[0] + 2.0 * plan.size_contact
    calibration = {"press": _scene(plan, "calibration_press", [press(*plan.press_forces)], fine_radius)}
    for force, shifts in plan.shear_paths:
        calibration[f"shear_{force:g}N"] = _scene(plan, f"calibration_shear_{force:g}N", [
            press(force), Load(LoadKind.SHEAR, "displacement", tuple(shifts))], fine_radius)
    calibration["twist"] = _scene(plan, "calibration_twist", [press(plan.calibration_force),
                                                              Load(LoadKind.TWIST, "displacement", plan.angles)],
                                  fine_radius)
    held_out = {}
    for case in plan.held_out:
        if not case.stages:
            held_out[case.name] = _scene(plan, case.name, [press(*case.press_forces)], fine_radius)
            continue
        stages = [Load(LoadKind(kind), "force", tuple(values)) for kind, values in case.stages]
        held_out[case.name] = _scene(plan, case.name, [press(case.normal_force), *stages], fine_radius)
    return calibration, held_out


def force_targets(scene) -> np.ndarray:
    """Per-increment (P [N], F_x [N], F_y [N], T [N mm]) targets of a force-controlled path (last value held)."""
    from contact.scene import LoadKind

    state = np.zeros(4)
    rows = []
    for load in scene.loads:
        for value in load.values:
            if load.kind == LoadKind.PRESS:
                state[0] = value
            elif load.kind == LoadKind.SHEAR:
                state[1:3] = value * np.asarray(load.direction) / math.hypot(*load.direction)
            else:
                state[3] = value
            rows.append(state.copy())
    return np.array(rows)


def run(out_dir, quick: bool = False, write_package_data: bool = False) -> dict:
    """Calibration and held-out FEM paths, fit, comparison table, figure and the calibrated JSON."""
    from contact.reduced import (PACKAGED_CALIBRATION, ArrayFingertipDesign, PathSamples, ReducedFingertip,
                                 StoredCalibration, load_calibration, save_calibration)
    from contact.reduced.calibration import calibrate
    from contact.solver import prepare, preparation_key, solve_scene

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    plan = StudyPlan.default(quick)
    design = ArrayFingertipDesign()
    calibration_scenes, held_out_scenes = build_scenes(plan)
    scenes = {**calibration_scenes, **held_out_scenes}
    if len(scenes) != len(calibration_scenes) + len(held_out_scenes):
        raise ValueError(f"held-out case names {sorted(held_out_scenes)} reuse a calibration name "
                         f"{sorted(calibration_scenes)}")
    keys = {preparation_key(scene) for scene in scenes.values()}
    if len(keys) != 1:
        raise RuntimeError(f"the study's paths need {len(keys)} meshes; they must share one")
    prepared = prepare(calibration_scenes["press"])
    timings = {"prepare": time.perf_counter() - start, **{f"prepare_{k}": v for k, v in prepared.timings.items()}}
    samples = {}
    for name, scene in scenes.items():
        tic = time.perf_counter()
        samples[name] = PathSamples.from_result(solve_scene(scene, prepared), design, name)
        timings[f"fem_{name}"] = time.perf_counter() - tic
        print(f"{NAME}: FEM {name}: {len(samples[name].load_kind)} increments, {timings[f'fem_{name}']:.1f} s")
    tic = time.perf_counter()
    tag = f"bench3x3-h{plan.size_contact:g}"
    shear_names = [name for name in calibration_scenes if name.startswith("shear_")]
    fitted = calibrate(design, [samples["press"]], [samples[name] for name in shear_names], samples["twist"], tag)
    timings["fit"] = time.perf_counter() - tic
    models = {"closed_form": ReducedFingertip(design), "calibrated": ReducedFingertip(design, fitted.parameters)}
    if PACKAGED_CALIBRATION.exists():          # the file shipped before this run (also with --write-package-data)
        models["packaged"] = load_calibration(PACKAGED_CALIBRATION, design).fingertip()
    tic = time.perf_counter()
    predicted = {name: {label: _reduced_path(tip, samples[name], held_out_scenes[name]) for label, tip in
                        models.items()} for name in held_out_scenes}
    timings["reduced"] = time.perf_counter() - tic
    rows = [row for name in held_out_scenes for row in _rows(name, samples[name], predicted[name])]
    write_csv_atomic(out_dir / "reduced_calibration.csv", rows)
    provenance = _provenance(tag, plan, prepared, fitted, samples, calibration_scenes, held_out_scenes, rows)
    stored = StoredCalibration(design, fitted.parameters, provenance)
    save_calibration(out_dir / CALIBRATION_FILE, stored)
    if write_package_data:
        save_calibration(PACKAGED_CALIBRATION, stored)
    wall = time.perf_counter() - start
    from studies._calibration_plot import plot_calibration

    save_figure(plot_calibration(samples, predicted, models, rows, fitted, plan, wall), out_dir, NAME)
    summary = _summary(rows, fitted, wall, timings, prepared)
    for line in summary["lines"]:
        print(f"{NAME}: {line}")
    return summary


def _provenance(tag, plan, prepared, fitted, samples, calibration_scenes, held_out_scenes, rows) -> dict:
    from importlib.metadata import PackageNotFoundError, version

    try:
        package_version = version("fingertip-contact")
    except PackageNotFoundError:
        package_version = "unknown (not installed)"
    info = prepared.mesh_info
    mesh = {"size_contact": plan.size_contact, "size_base": plan.size_base, "size_far": plan.size_far,
            "fine_radius": info["fine_radius"], "order": info["order"], "dofs": info["dofs"],
            "free_dofs": info["free_dofs"], "elements": info["elements"], "nodes": info["nodes"],
            "solver_backend": info["solver_backend"]}
    return {"tag": tag, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "package_version": package_version, "mesh": mesh,
            "fem_cases": [dict(samples[name].provenance, friction=samples[name].friction)
                          for name in calibration_scenes],
            "fit": [fit.to_dict() for fit in fitted.fits], "diagnostics": fitted.diagnostics,
            "held_out": {"cases": [dict(samples[name].provenance, friction=samples[name].friction)
                                   for name in held_out_scenes],
                         "max_relative_error": {q: largest_error(rows, "calibrated", q) for q in QUANTITIES
                                                if math.isfinite(largest_error(rows, "calibrated", q))}}}


def _reduced_path(tip, fem, scene):
    """The reduced model's PathSamples along the FEM path: displacement control or the scene's force targets."""
    from contact.reduced import PathSamples

    if all(load.control == "displacement" for load in scene.loads[1:]):
        motion = np.column_stack([fem.shift, fem.angle])
        return PathSamples.from_reduced(tip, fem.case, fem.load_kind, fem.normal_force, fem.friction, motion,
                                        "displacement")
    targets = force_targets(scene)
    return PathSamples.from_reduced(tip, fem.case, fem.load_kind, targets[:, 0], fem.friction, targets[:, 1:],
                                    "force")


QUANTITIES = {            # quantity: unit
    "depth": "mm", "contact_radius": "mm", "base_spread": "mm", "base_total_force": "N", "plate_shift": "mm",
    "twist_angle": "rad", "stick_ratio": "-", "cop_shift": "mm"}


def _rows(name, fem, predicted) -> list[dict]:
    """Tidy rows: FEM value, each model's value, error and relative error, per increment, quantity (and bump)."""
    rows = []
    has_shear = (fem.load_kind == "shear").any()
    press_only = not (~fem.pressed).any()
    bumps = fem.bump_normal_force.shape[1]
    fem_cop = fem.cop_shift
    model_cop = {label: model.cop_shift for label, model in predicted.items()}
    for i, kind in enumerate(fem.load_kind):
        head = dict(case=name, increment=i + 1, load_kind=str(kind), normal_force=float(fem.normal_force[i]),
                    tangential_force=float(np.hypot(*fem.tangential_force[i])), torque=float(fem.torque[i]))

        def add(quantity, fem_value, values, bump="", error=None, scale=None):
            row = dict(head, quantity=quantity, unit=QUANTITIES[quantity], bump=bump, fem=float(fem_value))
            for label in MODELS:
                value = values.get(label)
                row[label] = float(value) if value is not None else math.nan
            for label in MODELS:
                if label not in values:
                    row[f"{label}_error"] = row[f"{label}_relative_error"] = math.nan
                    continue
                difference = error[label] if error is not None else values[label] - fem_value
                reference = scale if scale is not None else abs(fem_value)
                row[f"{label}_error"] = float(difference)
                row[f"{label}_relative_error"] = float(difference / reference) if reference > 0 else math.nan
            rows.append(row)

        if kind == "press":
            if not press_only:
                continue
            add("depth", fem.depth[i], {k: m.depth[i] for k, m in predicted.items()})
            for b in range(bumps):
                add("contact_radius", fem.bump_contact_radius[i, b],
                    {k: m.bump_contact_radius[i, b] for k, m in predicted.items()}, bump=b)
            for b in range(bumps):
                add("base_spread", math.sqrt(max(fem.base_second_moment[i, b], 0.0)),
                    {k: math.sqrt(max(m.base_second_moment[i, b], 0.0)) for k, m in predicted.items()}, bump=b)
            add("base_total_force", fem.base_total_force[i], {k: m.base_total_force[i] for k, m in predicted.items()})
            continue
        if has_shear:
            add("plate_shift", fem.shift[i, 0], {k: m.shift[i, 0] for k, m in predicted.items()})
        if kind == "twist":           # during a shear stage the FEM holds the angle (displacement control)
            add("twist_angle", fem.angle[i], {k: m.angle[i] for k, m in predicted.items()})
        add("stick_ratio", fem.stick_ratio[i], {k: m.stick_ratio[i] for k, m in predicted.items()})
        largest = float(np.linalg.norm(fem_cop[i], axis=1).max())
        for b in range(bumps):
            add("cop_shift", np.linalg.norm(fem_cop[i, b]), {k: np.linalg.norm(c[i, b]) for k, c in model_cop.items()},
                bump=b, error={k: np.linalg.norm(c[i, b] - fem_cop[i, b]) for k, c in model_cop.items()},
                scale=largest)
        add("base_total_force", fem.base_total_force[i], {k: m.base_total_force[i] for k, m in predicted.items()})
    return rows


def largest_error(rows, label, quantity=None) -> float:
    """Largest finite |relative error| [-] of a model (column label) in the rows, of one quantity or all."""
    values = [abs(r[f"{label}_relative_error"]) for r in rows if quantity in (None, r["quantity"])]
    values = [v for v in values if math.isfinite(v)]
    return max(values) if values else math.nan


def _summary(rows, fitted, wall, timings, prepared) -> dict:
    closed = fitted.fits
    lines = [f"mesh: {prepared.mesh_info['elements']} tets, {prepared.mesh_info['dofs']} DOF"]
    for fit in closed:
        lines.append(f"{fit.parameter:>19}: fitted {fit.value:.5g}, closed form {fit.closed_form:.5g}, "
                     f"rms residual {fit.rms_residual:.3g} [{fit.residual_unit}]")
    labels = [label for label in MODELS if any(math.isfinite(r[label]) for r in rows)]
    per_quantity = {q: {label: largest_error(rows, label, q) for label in labels} for q in QUANTITIES}
    for quantity, errors in per_quantity.items():
        lines.append(f"held-out max |relative error| {quantity:>16}: " +
                     ", ".join(f"{label} {100 * value:.1f} %" for label, value in errors.items()))
    largest = largest_error(rows, "calibrated")
    worst = max((r for r in rows if math.isfinite(r["calibrated_relative_error"])),
                key=lambda r: abs(r["calibrated_relative_error"]))
    lines.append(f"largest held-out error of the calibrated model: {100 * largest:.1f} % ({worst['quantity']}, "
                 f"case {worst['case']}, increment {worst['increment']}, bump {worst['bump']!s}); closed form: "
                 f"{100 * largest_error(rows, 'closed_form'):.1f} %")
    lines.append("wall time: " + ", ".join(f"{k} {v:.1f} s" for k, v in timings.items()
                                           if not k.startswith("prepare_")) + f", total {wall:.1f} s")
    return {"max_error": largest, "error_meaning": "largest |relative error| of the calibrated reduced model on the "
            "held-out FEM cases", "closed_form_max_error": largest_error(rows, "closed_form"),
            "per_quantity": per_quantity, "parameters": fitted.parameters.to_dict(), "timings": timings,
            "wall_time": wall, "lines": lines}
