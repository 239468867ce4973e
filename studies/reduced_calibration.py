"""Reduced-model calibration: fit the 3x3 fingertip's reduced parameters to FEM paths, check them on held-out FEM cases.

The FEM bench of figs. 6/9 (3x3 hemispheres R = 4.67 mm, pitch 13.33 mm, 3 mm base, E = 0.3 MPa, nu = 0.45, mu = 1,
rigid plate) runs the calibration paths - a press at 1-6 N; shear forces along x at 2 N and along y at 6 N; plate
shifts into full sliding along x at 1 N and along y at 2 N; torques at 4 N; a shear along y then torques at 1 N -
and ``contact.reduced.calibration`` fits k_n, c_a, G*, G_t and the base-pressure law (sigma, h_0, kappa, g) to
them. Then held-out FEM paths that no fit saw (other normal forces, directions and load ratios, combined loads, and
a shear at 10 N beyond the calibrated forces; force-controlled but for the press) are compared with the reduced
model with closed-form parameters, with the parameters of this run and with the packaged calibration file. All
paths share one mesh, one factorization and the compliance columns of the points in contact.

Outputs: ``reduced_calibration.csv`` (one row per held-out case, increment, quantity and bump: FEM, each model,
error, relative error; the CoP shift there as a vector per bump), ``reduced_calibration_cop.csv`` (the per-bump
CoP-shift table, both axes, measured alike on FEM and model in the bumps' cells of the sensor plane and through the
sensor model and estimator: ``studies._calibration_rows``), the figure, and the calibrated JSON.
"""

from __future__ import annotations

import datetime
import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from studies._calibration_rows import (COP_VARIANTS, MODELS, QUANTITIES, SENSOR_GRID_SPACING, SIGNALS, SensorView,
                                       cop_rows, largest_cop_error, largest_error, quantity_rows)
from studies._calibration_samples import force_targets, load_samples, save_samples
from studies._output import save_figure, write_csv_atomic

NAME = "reduced-calibration"
CALIBRATION_FILE = "fingertip_3x3_calibrated.json"
X, Y, DIAGONAL = (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)


@dataclass(frozen=True)
class LoadCase:
    """An FEM path of the bench: a press to ``normal_force`` [N] then ``stages``, or a press through
    ``press_forces`` [N] (no stages). A stage is (kind "shear" or "twist", control "force" or "displacement",
    values [N, N mm, mm or rad], direction (x, y) of a shear)."""

    name: str
    normal_force: float = 0.0
    stages: tuple = ()
    press_forces: tuple = ()

    @property
    def kinds(self) -> set:
        return {stage[0] for stage in self.stages}


@dataclass(frozen=True)
class StudyPlan:
    """FEM settings [mm] and the calibration and held-out load paths of the study.

    The fine zone of the mesh is sized for the largest calibration press (``fine_force``), so that every path
    shares one mesh; the held-out shear at 10 N stays inside it (its contact radius ~2.2 mm, the zone ~3 mm).
    """

    size_contact: float
    size_base: float
    calibration: tuple
    held_out: tuple
    size_far: float = 3.0

    @property
    def fine_force(self) -> float:
        return max(max(case.press_forces, default=case.normal_force) for case in self.calibration)

    @classmethod
    def default(cls, quick: bool = False) -> "StudyPlan":
        from controller.estimation.bench import BENCH_SIZE_BASE, BENCH_SIZE_CONTACT

        calibration = (
            LoadCase("press", press_forces=(1.0, 2.0, 4.0, 6.0)),
            LoadCase("shear_x_2N", 2.0, (("shear", "force", (0.5, 1.0, 1.5), X),)),
            LoadCase("shear_y_6N", 6.0, (("shear", "force", (1.5, 3.0, 4.5), Y),)),
            # into full sliding (Q_i = mu P_i while the plate moves on): the CoP must stop with the load
            LoadCase("slide_x_1N", 1.0, (("shear", "displacement", (0.2, 0.45, 0.7), X),)),
            LoadCase("slide_y_2N", 2.0, (("shear", "displacement", (0.45, 0.9, 1.2), Y),)),
            LoadCase("twist_4N", 4.0, (("twist", "force", (12.0, 24.0, 36.0), X),)),
            LoadCase("shear_twist_1N", 1.0, (("shear", "force", (0.4,), Y), ("twist", "force", (2.5, 5.0), X))))
        held_out = (
            LoadCase("press_1.5N_3N_5N", press_forces=(1.5, 3.0, 5.0)),
            LoadCase("shear_diagonal_3N", 3.0, (("shear", "force", (0.9, 1.8), DIAGONAL),)),
            LoadCase("shear_x_5N", 5.0, (("shear", "force", (1.5, 3.0), X),)),
            LoadCase("twist_1.5N", 1.5, (("twist", "force", (3.0, 6.0), X),)),
            LoadCase("shear_y_twist_5N", 5.0, (("shear", "force", (-1.5,), Y), ("twist", "force", (10.0, 20.0), X))),
            LoadCase("shear_x_twist_3N", 3.0, (("shear", "force", (1.2,), X), ("twist", "force", (-8.0,), X))),
            LoadCase("shear_y_10N", 10.0, (("shear", "force", (3.0, 6.0), Y),)))
        if quick:      # 1 N still has >= 7 points per bump; the sensor plane as fine as the default's (a coarser
            # one moves the FEM's sensor CoP by up to 15 % against the default mesh, more than the model's error)
            return cls(0.7, BENCH_SIZE_BASE, calibration, held_out)
        return cls(BENCH_SIZE_CONTACT, BENCH_SIZE_BASE, calibration, held_out)


def add_arguments(parser) -> None:
    """--write-package-data: also store the fitted file as contact/reduced/data; --samples: reuse stored FEM paths."""
    parser.add_argument("--write-package-data", action="store_true",
                        help=f"also write the calibration to contact/reduced/data/{CALIBRATION_FILE}")
    parser.add_argument("--samples", default=None, metavar="NPZ",
                        help="reuse the FEM paths of an earlier run (its reduced_calibration_samples.npz, same "
                             "--quick) instead of solving them")


def _scene(plan: StudyPlan, name: str, loads, fine_radius: float | None):
    from contact.scene import BodySpec, ContactSpec, Material, MeshSettings, Scene
    from controller.estimation.bench import FRICTION, POISSONS_RATIO, YOUNGS_MODULUS, fingertip_gel

    return Scene(name=name, gel=fingertip_gel(3), material=Material(YOUNGS_MODULUS, POISSONS_RATIO),
                 body=BodySpec("plane"), contact=ContactSpec(friction_coefficient=FRICTION),
                 mesh=MeshSettings(size_contact=plan.size_contact, size_far=plan.size_far, size_base=plan.size_base,
                                   fine_radius=fine_radius), loads=tuple(loads))


def build_scenes(plan: StudyPlan) -> tuple[dict, dict]:
    """Calibration scenes and held-out scenes {name: scene}, all on one mesh (the fine zone of ``fine_force``)."""
    from contact.scene import Load, LoadKind
    from contact.solver import estimated_contact

    def press(*forces):
        return Load(LoadKind.PRESS, "force", tuple(forces))

    probe = _scene(plan, "probe", [press(plan.fine_force)], None)
    fine_radius = 1.3 * estimated_contact(probe)[0] + 2.0 * plan.size_contact    # the solver's own rule

    def scene(case: LoadCase):
        if not case.stages:
            return _scene(plan, case.name, [press(*case.press_forces)], fine_radius)
        stages = [Load(LoadKind(kind), control, tuple(values), tuple(direction))
                  for kind, control, values, direction in case.stages]
        return _scene(plan, case.name, [press(case.normal_force), *stages], fine_radius)

    calibration = {case.name: scene(case) for case in plan.calibration}
    held_out = {case.name: scene(case) for case in plan.held_out}
    if set(calibration) & set(held_out):
        raise ValueError(f"held-out case names {sorted(held_out)} reuse a calibration name {sorted(calibration)}")
    return calibration, held_out


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


def _cop_shifts(fem, fem_sensor, models, predicted, sensor: SensorView) -> dict:
    """{signal: {label: (t, k, 2) CoP shifts [mm]}} of one path: FEM and the ``COP_VARIANTS`` (cells and sensor)."""
    tip = models["calibrated"]
    centres = tip.centres
    reference = fem.reference
    fed = fem.with_model_base(tip)
    paths = {"model": predicted["calibrated"], "closed_form": predicted["closed_form"]}
    cells = {"fem": fem.cop_shift, "model_fem_loads": fed.cop_shift,
             **{label: path.cop_shift for label, path in paths.items()}}

    def through_sensor(model, path):
        cop = sensor.model_cop(model, path.bump_normal_force, path.bump_displacement(centres),
                               path.bump_tangential_force)
        return cop - cop[reference]

    readings = {"fem": fem_sensor - fem_sensor[reference], "model_fem_loads": through_sensor(tip, fem),
                "model": through_sensor(tip, paths["model"]),
                "closed_form": through_sensor(models["closed_form"], paths["closed_form"])}
    return {"cells": cells, "sensor": readings}


def run(out_dir, quick: bool = False, write_package_data: bool = False, samples: str | None = None) -> dict:
    """Calibration and held-out FEM paths, fit, comparison tables, figure and the calibrated JSON.

    ``samples``: a ``reduced_calibration_samples.npz`` of an earlier run with the same plan (``--quick`` alike):
    its FEM paths are reused and no FEM is solved (a refit after a change to the reduced model).
    """
    from contact.reduced import (PACKAGED_CALIBRATION, ArrayFingertipDesign, ReducedFingertip, StoredCalibration,
                                 save_calibration)
    from contact.reduced.calibration import calibrate

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    plan = StudyPlan.default(quick)
    design = ArrayFingertipDesign()
    calibration_scenes, held_out_scenes = build_scenes(plan)
    scenes = {**calibration_scenes, **held_out_scenes}
    sensor = SensorView(design)
    if samples is None:
        fem, timings = _solve(scenes, calibration_scenes["press"], design, sensor)
        save_samples(out_dir / "reduced_calibration_samples.npz", fem, scenes)
    else:
        fem, timings = load_samples(samples, scenes), {}
    paths, fem_sensor = fem["paths"], fem["sensor_cop"]
    tic = time.perf_counter()
    tag = f"bench3x3-h{plan.size_contact:g}"
    by_kind = {kind: [paths[case.name] for case in plan.calibration if role(case) == kind]
               for kind in ("press", "shear", "twist")}
    fitted = calibrate(design, by_kind["press"], by_kind["shear"], by_kind["twist"], tag)
    timings["fit"] = time.perf_counter() - tic
    models = {"closed_form": ReducedFingertip(design), "calibrated": ReducedFingertip(design, fitted.parameters)}
    packaged_error = _packaged(models, design, PACKAGED_CALIBRATION)
    tic = time.perf_counter()
    predicted = {name: {label: _reduced_path(tip, paths[name], scenes[name]) for label, tip in models.items()}
                 for name in scenes}
    rows = [row for name in held_out_scenes for row in quantity_rows(name, paths[name], predicted[name])]
    cop = [row for name in scenes if (~paths[name].pressed).any()
           for row in cop_rows(name, "held_out" if name in held_out_scenes else "calibration", paths[name],
                               _cop_shifts(paths[name], fem_sensor[name], models, predicted[name], sensor))]
    timings["reduced"] = time.perf_counter() - tic
    write_csv_atomic(out_dir / "reduced_calibration.csv", rows)
    write_csv_atomic(out_dir / "reduced_calibration_cop.csv", cop)
    provenance = _provenance(tag, plan, fem["mesh"], fitted, paths, calibration_scenes, held_out_scenes, rows, cop)
    stored = StoredCalibration(design, fitted.parameters, provenance)
    save_calibration(out_dir / CALIBRATION_FILE, stored)
    if write_package_data:
        save_calibration(PACKAGED_CALIBRATION, stored)
    speed = time_base_pressure(models["calibrated"], sensor)
    wall = time.perf_counter() - start
    from studies._calibration_plot import plot_calibration

    save_figure(plot_calibration(paths, predicted, models, rows, cop, fitted, plan, wall), out_dir, NAME)
    summary = _summary(rows, cop, fitted, wall, timings, fem["mesh"], speed, packaged_error)
    for line in summary["lines"]:
        print(f"{NAME}: {line}")
    return summary


def _solve(scenes: dict, first, design, sensor: SensorView) -> tuple[dict, dict]:
    """Every path on one prepared mesh: {"paths": PathSamples, "sensor_cop": (t, k, 2), "mesh": facts}, timings."""
    from contact.reduced import PathSamples
    from contact.solver import prepare, preparation_key, solve_scene

    keys = {preparation_key(scene) for scene in scenes.values()}
    if len(keys) != 1:
        raise RuntimeError(f"the study's paths need {len(keys)} meshes; they must share one")
    start = time.perf_counter()
    prepared = prepare(first)
    timings = {"prepare": time.perf_counter() - start, **{f"prepare_{k}": v for k, v in prepared.timings.items()}}
    paths, sensor_cop = {}, {}
    for name, scene in scenes.items():
        tic = time.perf_counter()
        result = solve_scene(scene, prepared)
        paths[name] = PathSamples.from_result(result, design, name)
        sensor_cop[name] = sensor.fem_cop(result)
        timings[f"fem_{name}"] = time.perf_counter() - tic
        print(f"{NAME}: FEM {name}: {len(paths[name].load_kind)} increments, {timings[f'fem_{name}']:.1f} s")
    return {"paths": paths, "sensor_cop": sensor_cop, "mesh": dict(prepared.mesh_info)}, timings


def role(case: LoadCase) -> str:
    """Which fit a calibration path feeds: "press" (no stages), "twist" (any twist stage) or "shear"."""
    if not case.stages:
        return "press"
    return "twist" if "twist" in case.kinds else "shear"


def _packaged(models: dict, design, path) -> str:
    """Add the packaged calibration to ``models`` if it loads; else the reason (an older schema, before a rerun)."""
    from contact.reduced import ReducedFingertip

    if not path.exists():
        return f"{path} does not exist"
    try:
        models["packaged"] = ReducedFingertip.calibrated(path, design)
    except ValueError as error:
        return str(error)
    return ""


def time_base_pressure(tip, sensor: SensorView, repeats: int = 7, calls: int = 200) -> dict:
    """Median wall time of one ``base_pressure`` call on the closed loop's 1 mm grid, beside one sensor sampling.

    Both are timed in the same loop (a 5 N state with shear and twist): the ratio is what to compare between
    machines; the closed loop calls both at 100 Hz per fingertip.
    """
    from controller.sensing.sensor import PressureField, cell_force_operator, sample

    grid = tip.base_grid(SENSOR_GRID_SPACING)
    state = tip.load_state(5.0, (1.0, 0.5), 10.0, 1.0)
    args = (grid, state.normal_force, state.contact_radius, state.shear_displacement, state.bump_tangential_force)
    field = PressureField.from_grid(grid.x, grid.y, tip.base_pressure(*args))
    operator = cell_force_operator(field.positions, field.triangles, sensor.array)
    pressure_times, sample_times = [], []
    for _ in range(repeats):
        tic = time.perf_counter()
        for _ in range(calls):
            tip.base_pressure(*args)
        pressure_times.append((time.perf_counter() - tic) / calls)
        tic = time.perf_counter()
        for _ in range(calls):
            sample(field, sensor.array, operator=operator)
        sample_times.append((time.perf_counter() - tic) / calls)
    pressure, sampling = float(np.median(pressure_times)), float(np.median(sample_times))
    return {"base_pressure_us": 1e6 * pressure, "sensor_sample_us": 1e6 * sampling, "ratio": pressure / sampling,
            "grid_nodes": int(grid.x.size * grid.y.size)}


def _provenance(tag, plan, info, fitted, samples, calibration_scenes, held_out_scenes, rows, cop) -> dict:
    from importlib.metadata import PackageNotFoundError, version

    try:
        package_version = version("fingertip-contact")
    except PackageNotFoundError:
        package_version = "unknown (not installed)"
    mesh = {"size_contact": plan.size_contact, "size_base": plan.size_base, "size_far": plan.size_far,
            "fine_radius": info["fine_radius"], "order": info["order"], "dofs": info["dofs"],
            "free_dofs": info["free_dofs"], "elements": info["elements"], "nodes": info["nodes"],
            "solver_backend": info["solver_backend"]}
    errors = {q: largest_error(rows, "calibrated", q) for q in QUANTITIES}
    errors.update({f"cop_shift_{signal}_per_axis": largest_cop_error(cop, "model", signal) for signal in SIGNALS})
    return {"tag": tag, "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "package_version": package_version, "mesh": mesh,
            "fem_cases": [dict(samples[name].provenance, friction=samples[name].friction)
                          for name in calibration_scenes],
            "fit": [fit.to_dict() for fit in fitted.fits], "diagnostics": fitted.diagnostics,
            "held_out": {"cases": [dict(samples[name].provenance, friction=samples[name].friction)
                                   for name in held_out_scenes],
                         "max_relative_error": {q: e for q, e in errors.items() if math.isfinite(e)}}}


def _summary(rows, cop, fitted, wall, timings, mesh, speed, packaged_error) -> dict:
    lines = [f"mesh: {mesh['elements']} tets, {mesh['dofs']} DOF"]
    for fit in fitted.fits:
        how = "held" if fit.note.startswith(("held", "not fitted")) else "fitted"
        lines.append(f"{fit.parameter:>19}: {how} {fit.value:.5g}, closed form {fit.closed_form:.5g}, "
                     f"rms residual {fit.rms_residual:.3g} [{fit.residual_unit}]")
    if packaged_error:
        lines.append(f"packaged calibration not compared: {packaged_error}")
    labels = [label for label in MODELS if any(math.isfinite(r[label]) for r in rows)]
    per_quantity = {q: {label: largest_error(rows, label, q) for label in labels} for q in QUANTITIES}
    for quantity, errors in per_quantity.items():
        lines.append(f"held-out max |relative error| {quantity:>16}: " +
                     ", ".join(f"{label} {100 * value:.1f} %" for label, value in errors.items()))
    cop_errors = {signal: {label: largest_cop_error(cop, label, signal) for label in COP_VARIANTS}
                  for signal in SIGNALS}
    for signal, errors in cop_errors.items():
        lines.append(f"held-out per-bump CoP shift ({signal}, both axes, over the increment's largest shift): " +
                     ", ".join(f"{label} {100 * value:.1f} %" for label, value in errors.items()))
    cases = sorted({r["case"] for r in cop if r["role"] == "held_out"})
    for case in cases:
        case_rows = [r for r in cop if r["case"] == case]
        lines.append(f"  {case:>20}: " + ", ".join(
            f"{signal} {100 * largest_cop_error(case_rows, 'model', signal):.1f} %" for signal in SIGNALS))
    largest = max(cop_errors["cells"]["model"], cop_errors["sensor"]["model"])
    lines.append(f"base_pressure on the 1 mm grid ({speed['grid_nodes']} nodes): {speed['base_pressure_us']:.0f} us "
                 f"per call, {speed['ratio']:.2f} x one sensor sampling ({speed['sensor_sample_us']:.0f} us)")
    lines.append("wall time: " + ", ".join(f"{k} {v:.1f} s" for k, v in timings.items()
                                           if not k.startswith("prepare_")) + f", total {wall:.1f} s")
    return {"max_error": largest, "error_meaning": "largest held-out per-bump CoP-shift error of the calibrated "
            "reduced model (cells and sensor, both axes), over the increment's largest FEM shift",
            "closed_form_max_error": largest_cop_error(cop, "closed_form"), "per_quantity": per_quantity,
            "cop_errors": cop_errors, "parameters": fitted.parameters.to_dict(), "timings": timings,
            "base_pressure_timing": speed, "wall_time": wall, "lines": lines}
