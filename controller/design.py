"""Fingertip design sweeps: designs through FEM -> sensor -> estimator, one row of metrics per design.

A design (``FingertipDesign``) is the paper's kind of fingertip - rows x cols hemispheres (bump radius, pitch) on a
base layer (thickness, footprint) of a linear-elastic gel (E, nu), read by a capacitive array (sensor pitch, pad
fill factor). A study (``DesignStudy``) fixes what every design goes through: a rigid plate pressed with the grasp
force, then (1) sheared by force control to the load ratios Q/(mu P) of ``load_ratios`` and (2), on another path from
the same press, twisted about the array centre (angle control, for two or more bumps). The sensor reads the FEM's
base pressure (``controller.sensor``, ``controller.capacitive``) and the estimator (``controller.estimator``) turns
it into shear displacements and rotations. Metrics (``METRICS``, one column each): translational and rotational
estimation errors, the stick-ratio drop near gross slip (the criterion of the paper's Figs. 3/4), force and torque
capacity per unit grasp force, and the mesh's error estimate.

``design_sweep`` runs many designs on dask.distributed (a LocalCluster by default, or a scheduler address) or in
this process, resumable: with ``out_dir`` each design's record is written as it finishes and a re-run skips the
designs recorded there (``fem.task_runner``). Designs that differ only in their sensor share one FEM solve; designs
that share a mesh share its factorization and compliance columns. ``python -m studies design DESIGN.toml`` is the
command (file format: ``controller._design_file``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import socket
import tempfile
import time
from dataclasses import dataclass
from enum import Enum
from pathlib import Path

import numpy as np

from fem.validation import check_positive, check_range

from ._design_file import DesignSweepSpec, load_design_file
from ._design_metrics import METRICS, capacity_metrics, drop_metrics, estimation_metrics, mesh_metrics

__all__ = ["FingertipDesign", "DesignStudy", "SensorModel", "METRICS", "design_scenes", "evaluate_designs",
           "design_sweep", "design_table", "increment_table", "pareto_front", "design_id", "load_design_file",
           "DesignSweepSpec"]


class SensorModel(str, Enum):
    """The sensor a design is read with."""

    CAPACITIVE = "capacitive"     # controller.capacitive: pads with 0.5 mm gaps set by pad_fill, the documented node
    CELLS = "cells"               # the ideal array: whole cells, noise-free (pad_fill still sets the pads)


def _check_integer(name: str, value, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or not low <= value <= high:
        raise ValueError(f"{name}={value!r} must be an integer in [{low}, {high}]")
    return int(value)


def _check_number(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name}={value!r} must be a number")
    return float(value)


@dataclass(frozen=True)
class FingertipDesign:
    """One fingertip (mm, MPa): defaults are the paper's 3x3 fingertip on a 40 x 40 mm base read at 3 mm.

    Parameters
    ----------
    bump_radius : hemisphere radius [mm].
    rows, cols : bumps along y and x (1 to 12).
    pitch : bump centre distance [mm]; larger than the bump diameter.
    base_thickness : gel between the bumps and the sensor plane [mm].
    youngs_modulus : E [MPa]; poissons_ratio : nu (< 0.5).
    sensor_pitch : node spacing of the sensor array [mm]; pad_fill : pad area / cell area, in (0, 1].
    base_width, base_depth : footprint [mm]; the sensor array covers it.
    """

    bump_radius: float = 0.35 * 40.0 / 3.0      # the Fig. 6 / 9 bench's fingertip (controller.bench), exactly
    rows: int = 3
    cols: int = 3
    pitch: float = 40.0 / 3.0
    base_thickness: float = 3.0
    youngs_modulus: float = 0.3
    poissons_ratio: float = 0.45
    sensor_pitch: float = 3.0
    pad_fill: float = 0.7
    base_width: float = 40.0
    base_depth: float = 40.0

    def __post_init__(self):
        for field in dataclasses.fields(self):
            value = getattr(self, field.name)
            if field.name in ("rows", "cols"):
                _check_integer(field.name, value, 1, 12)
            else:
                object.__setattr__(self, field.name, _check_number(field.name, value))
        check_positive("youngs_modulus", self.youngs_modulus, "MPa")
        check_range("poissons_ratio", self.poissons_ratio, -1.0, 0.5, low_open=True, high_open=True)
        check_positive("sensor_pitch", self.sensor_pitch, "mm")
        check_range("pad_fill", self.pad_fill, 0.0, 1.0, low_open=True)
        self.geometry                                           # the array's own checks (overlap, overhang)
        if self.sensor_pitch > min(self.base_width, self.base_depth):
            raise ValueError(f"sensor_pitch={self.sensor_pitch} mm is larger than the footprint "
                             f"({self.base_width} x {self.base_depth} mm)")

    @property
    def geometry(self):
        """The fem.geometry.ArrayGeometry of the gel."""
        from fem.geometry import ArrayGeometry

        return ArrayGeometry(rows=self.rows, cols=self.cols, bump_radius=self.bump_radius, pitch=self.pitch,
                             base_width=self.base_width, base_depth=self.base_depth,
                             base_thickness=self.base_thickness)

    @property
    def bumps(self) -> int:
        return self.rows * self.cols

    def gel(self):
        """The contact.scene.GelSpec of the gel."""
        from contact.scene import GelSpec

        return GelSpec("array", tuple(sorted(dict(rows=self.rows, cols=self.cols, bump_radius=self.bump_radius,
                                                  pitch=self.pitch, base_width=self.base_width,
                                                  base_depth=self.base_depth,
                                                  base_thickness=self.base_thickness).items())))

    def sensor(self, model: "SensorModel"):
        """The SensorArray reading this design: nodes at sensor_pitch over the footprint, pads of pad_fill."""
        from controller.capacitive import CapacitiveNode
        from controller.sensor import SensorArray

        counts = (max(1, round(self.base_width / self.sensor_pitch)),
                  max(1, round(self.base_depth / self.sensor_pitch)))
        node = CapacitiveNode() if SensorModel(model) is SensorModel.CAPACITIVE else None
        return SensorArray(pitch=self.sensor_pitch, node_counts=counts, fill_factor=self.pad_fill, node=node)

    def layout(self):
        """The estimator's BumpLayout: the bump centres."""
        from controller.estimator import BumpLayout

        return BumpLayout(tuple(map(tuple, self.geometry.bump_centers.tolist())))


@dataclass(frozen=True)
class DesignStudy:
    """What every design of a sweep goes through (N, mm, rad).

    Parameters
    ----------
    normal_force : grasp force of the plate [N].
    friction_coefficient : Coulomb friction of plate and gel [-].
    load_ratios : shear path, Q / (mu P) per increment, increasing in (0, 1); at least three (two calibrate the
        estimator's gain, the others measure its error).
    twist_fractions : twist path, angles as fractions of the twist at which the outermost bumps' Mindlin slip
        displacement is reached (3 mu P_i (2 - nu) / (16 G a_i) / r_max, Hertz a_i with P_i = P / bumps), increasing.
    size_contact, size_base, size_far : element sizes at the bump tops, on the sensor plane and elsewhere [mm].
    sensor : SensorModel of the sensor.
    noise_draws : noise draws per design (a noisy sensor; the errors are their mean), >= 1.
    frames_per_state : frames averaged per quasi-static state (0.1 s at 100 Hz), >= 1.
    """

    normal_force: float = 2.0
    friction_coefficient: float = 1.0
    load_ratios: tuple[float, ...] = (0.2, 0.4, 0.6, 0.8, 0.9, 0.95)
    twist_fractions: tuple[float, ...] = (0.25, 0.5, 0.75, 1.0)
    size_contact: float = 0.3
    size_base: float = 1.0
    size_far: float = 3.0
    sensor: SensorModel = SensorModel.CAPACITIVE
    noise_draws: int = 5
    frames_per_state: int = 10

    def __post_init__(self):
        for name in ("normal_force", "friction_coefficient", "size_contact", "size_base", "size_far"):
            object.__setattr__(self, name, check_positive(name, _check_number(name, getattr(self, name))))
        check_range("friction_coefficient", self.friction_coefficient, 0.0, 5.0, low_open=True)
        for name, low in (("load_ratios", 3), ("twist_fractions", 1)):
            values = getattr(self, name)
            if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
                raise ValueError(f"{name}={values!r} must be a list of numbers")
            values = tuple(_check_number(f"{name}[{k}]", v) for k, v in enumerate(values))
            if len(values) < low or any(b <= a for a, b in zip(values, values[1:])) or values[0] <= 0.0:
                raise ValueError(f"{name}={list(values)} must hold at least {low} increasing values > 0")
            object.__setattr__(self, name, values)
        if self.load_ratios[-1] >= 1.0:
            raise ValueError(f"load_ratios={list(self.load_ratios)} must stay below 1 (gross slip)")
        try:
            object.__setattr__(self, "sensor", SensorModel(self.sensor))
        except ValueError:
            raise ValueError(f"sensor={self.sensor!r} is not one of {[m.value for m in SensorModel]}") from None
        _check_integer("noise_draws", self.noise_draws, 1, 1000)
        _check_integer("frames_per_state", self.frames_per_state, 1, 10_000)

    def document(self) -> dict:
        return {**dataclasses.asdict(self), "load_ratios": list(self.load_ratios),
                "twist_fractions": list(self.twist_fractions), "sensor": self.sensor.value}


def design_id(design: FingertipDesign, study: DesignStudy) -> str:
    """Id of a design in a study: a hash of both and of the package version (an upgrade evaluates it again)."""
    from contact.compliance import package_version

    text = json.dumps({"design": dataclasses.asdict(design), "study": study.document(), "version": package_version()},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _fem_key(design: FingertipDesign) -> tuple:
    """Designs with equal keys have the same FEM solution: everything but the sensor."""
    return tuple((f.name, getattr(design, f.name)) for f in dataclasses.fields(design)
                 if f.name not in ("sensor_pitch", "pad_fill"))


def twist_angles(design: FingertipDesign, study: DesignStudy) -> tuple[float, ...]:
    """Angles [rad] of the twist path (``DesignStudy.twist_fractions``); empty for a single bump."""
    from contact.theory import hertz, mindlin_shift

    lever = float(np.linalg.norm(design.geometry.bump_centers, axis=1).max())
    if design.bumps < 2 or lever == 0.0:
        return ()
    share = study.normal_force / design.bumps
    e_star = design.youngs_modulus / (1.0 - design.poissons_ratio**2)
    shear_modulus = design.youngs_modulus / (2.0 * (1.0 + design.poissons_ratio))
    radius = float(hertz(share, design.bump_radius, e_star).contact_radius)
    slip = float(mindlin_shift(study.friction_coefficient * share, share, study.friction_coefficient, radius,
                               shear_modulus, design.poissons_ratio))
    return tuple(float(f * slip / lever) for f in study.twist_fractions)


def design_scenes(design: FingertipDesign, study: DesignStudy):
    """The design's shear scene and twist scene (None for a single bump): a plate pressed with the grasp force,
    then sheared by force to ``load_ratios`` or twisted by ``twist_angles``."""
    from contact.scene import BodySpec, ContactSpec, Load, LoadKind, Material, MeshSettings, Scene

    mu = study.friction_coefficient
    common = dict(gel=design.gel(), material=Material(design.youngs_modulus, design.poissons_ratio),
                  body=BodySpec("plane"), contact=ContactSpec(mu=mu),
                  mesh=MeshSettings(size_contact=study.size_contact, size_far=study.size_far,
                                    size_base=study.size_base))
    press = Load(LoadKind.PRESS, "force", (study.normal_force,))
    forces = tuple(float(r * mu * study.normal_force) for r in study.load_ratios)
    shear = Scene(name=f"design_{design.rows}x{design.cols}_shear",
                  loads=(press, Load(LoadKind.SHEAR, "force", forces)), **common)
    angles = twist_angles(design, study)
    twist = Scene(name=f"design_{design.rows}x{design.cols}_twist",
                  loads=(press, Load(LoadKind.TWIST, "displacement", angles)), **common) if angles else None
    return shear, twist


def _record(case_id: str, design: FingertipDesign, status: str, error: str | None, metrics: dict, increments: list,
            timings: dict, group: str) -> dict:
    return {"case_id": case_id, "status": status, "error": error, "design": dataclasses.asdict(design),
            "metrics": metrics, "increments": increments, "timings": timings, "group": group,
            "worker": f"{socket.gethostname()}:{os.getpid()}"}


def _increment_rows(result, path: str, ratios, estimates) -> list[dict]:
    rows = []
    for number, increment in enumerate(result.increments):
        bumps = increment.bumps
        row = {"path": path, "increment": number, "load_kind": increment.load_kind,
               "load_ratio": (float(ratios[number - 1]) if number else 0.0) if path == "shear" else None,
               "normal_force": increment.normal_force, "tangential_force": increment.tangential_force[0],
               "torque": increment.torque, "shift": increment.shift[0], "angle": increment.angle,
               "stick_ratio": increment.stick_ratio, "contact_area": increment.contact_area,
               "least_bump_margin": float(bumps.gross_slip_margin.min()),
               "least_bump_stick_ratio": float(bumps.stick_ratio.min()),
               "estimated_shift": None, "estimated_angle": None}
        if number and estimates is not None:
            key = "estimated_shift" if path == "shear" else "estimated_angle"
            row[key] = float(estimates[number - 1])
        rows.append(row)
    return rows


def evaluate_designs(items: list[tuple[str, dict, dict]], cases_dir: str | None = None, group: str = ""):
    """Evaluate designs that share one FEM solution (equal ``_fem_key``): yield one record per design, in order.

    ``items``: (case_id, design fields, study document). The shear and twist paths are solved once (one prepare,
    one set of compliance columns), then each design's sensor reads them. A failure keeps what was computed before
    it (the metrics of the shear path when the twist path fails) and records the error. Writes each record to
    ``cases_dir/<case_id>.json`` when given. This is the task ``design_sweep`` runs (``fem.task_runner``).
    """
    from contact.result import ContactUnderResolved, LoadNotCarried, PathNotCompleted
    from contact.solver import prepare, solve_scene
    from fem.task_runner import write_record

    designs = [(case_id, FingertipDesign(**fields), DesignStudy(**study)) for case_id, fields, study in items]
    first, study = designs[0][1], designs[0][2]
    shear_scene, twist_scene = design_scenes(first, study)
    timings, fem_metrics, results, error = {}, {}, {}, None
    start = time.perf_counter()
    try:
        prepared = prepare(shear_scene)
        timings["prepare"] = time.perf_counter() - start
        solve_start = time.perf_counter()
        results["shear"] = solve_scene(shear_scene, prepared)
        press = results["shear"].increments[0]
        fem_metrics.update(capacity_metrics(press, results["shear"].candidate_positions,
                                            results["shear"].candidate_areas, shear_scene.body.center,
                                            study.friction_coefficient))
        fem_metrics.update(drop_metrics(results["shear"].increments[1:], study.load_ratios))
        fem_metrics.update(mesh_metrics(press, study.size_contact, first.bump_radius, first.youngs_modulus,
                                        first.poissons_ratio))
        if twist_scene is not None:
            results["twist"] = solve_scene(twist_scene, prepared)
        timings["solve"] = time.perf_counter() - solve_start
        timings.update({f"fem_{k}": float(v) for k, v in results["shear"].timings.items()})
        timings["dofs"] = results["shear"].mesh_info["dofs"]
    except (PathNotCompleted, LoadNotCarried, ContactUnderResolved, ValueError, RuntimeError) as failure:
        error = f"{type(failure).__name__}: {failure}"
    fem_seconds = time.perf_counter() - start
    for case_id, design, study in designs:
        case_start = time.perf_counter()
        metrics = dict(fem_metrics)
        increments, status, message = [], "ok" if error is None else "failed", error
        if "shear" in results:                      # the shear path's metrics survive a failed twist path
            try:
                angles = twist_angles(design, study)
                draws = range(study.noise_draws) if study.sensor is SensorModel.CAPACITIVE else (0,)
                if "twist" not in results:
                    angles = ()
                estimated, estimates = estimation_metrics(results["shear"], results.get("twist"),
                                                          design.sensor(study.sensor), design.layout(), draws,
                                                          study.frames_per_state, angles)
                metrics.update(estimated)
                increments = _increment_rows(results["shear"], "shear", study.load_ratios, estimates["shift"])
                if "twist" in results:
                    increments += _increment_rows(results["twist"], "twist", (), estimates["angle"])
            except (ValueError, RuntimeError) as failure:
                status, message = "failed", f"{type(failure).__name__}: {failure}"
        bad = [key for key, value in metrics.items() if isinstance(value, float) and not math.isfinite(value)]
        if bad and status == "ok":
            status, message = "failed", f"non-finite metric(s) refused: {bad}"
            metrics = {key: (None if key in bad else value) for key, value in metrics.items()}
        case_timings = dict(timings, fem_wall=fem_seconds if case_id == designs[0][0] else 0.0,
                            sensor_wall=time.perf_counter() - case_start)
        record = _record(case_id, design, status, message, metrics, increments, case_timings, group)
        if cases_dir is not None:
            write_record(cases_dir, record)
        yield record


def _payload(case) -> tuple:
    return case.case_id, dataclasses.asdict(case.design), case.study.document()


@dataclass(frozen=True)
class _Case:
    case_id: str
    design: FingertipDesign
    study: DesignStudy


def _crashed(case, message: str) -> dict:
    return _record(case.case_id, case.design, "failed", message, {}, [], {}, "")


def _plan(cases: list) -> list[list]:
    """One task per FEM solution (designs differing only in the sensor); the largest first. A task is not split to
    fill idle workers: that would solve the same FEM twice."""
    groups: dict = {}
    for case in cases:
        groups.setdefault(_fem_key(case.design), []).append(case)
    return sorted(groups.values(), key=len, reverse=True)


def design_sweep(designs, study: DesignStudy = DesignStudy(), out_dir=None, scheduler: str = "local",
                 workers: int = 2, connect_timeout: float = 5.0, retry_failed: bool = False, progress: bool = True,
                 on_record=None, with_increments: bool = False):
    """Evaluate fingertip designs; returns the design table (``design_table``), one row per design.

    designs : iterable of FingertipDesign (duplicates refused).
    study : DesignStudy shared by all designs.
    out_dir : folder for the case records (``out_dir/cases/<id>.json``); a re-run skips the designs recorded there
        (``retry_failed``: the failed ones run again). None: a temporary folder, nothing kept.
    scheduler : "local" (a LocalCluster of ``workers`` processes, one thread each), "synchronous" (this process)
        or the address of a running dask scheduler (``connect_timeout`` seconds to reach it).
    on_record : called with each record as it arrives (the command writes its table there).
    with_increments : also return the increment table (``increment_table``): (designs, increments).
    """
    from tqdm import tqdm

    from fem.task_runner import check_scheduler, connect, run_tasks, set_aside, stored_records

    check_scheduler(scheduler)
    cases, seen = [], {}
    for design in designs:
        if not isinstance(design, FingertipDesign):
            raise ValueError(f"designs must be FingertipDesign objects, got {type(design).__name__}")
        case_id = design_id(design, study)
        if case_id in seen:
            raise ValueError(f"design {design} appears twice")
        seen[case_id] = design
        cases.append(_Case(case_id, design, study))
    if not cases:
        raise ValueError("no designs given")
    temporary = tempfile.TemporaryDirectory(prefix="design-sweep-") if out_dir is None else None
    cases_dir = Path(temporary.name if temporary else Path(out_dir) / "cases")
    cases_dir.mkdir(parents=True, exist_ok=True)
    try:
        records = stored_records(cases, cases_dir, retry_failed, required=("case_id", "status", "metrics"))
        pending = [case for case in cases if case.case_id not in records]
        bar = tqdm(total=len(cases), initial=len(cases) - len(pending), desc="designs", unit="design",
                   disable=not progress)

        def arrived(case, record):
            records[case.case_id] = record
            bar.update(1)
            if record["status"] != "ok":
                bar.write(f"design {case.design} failed: {str(record['error'])[:300]}")
            if on_record is not None:
                on_record(record)

        set_aside(pending, cases_dir)
        if pending:
            with connect(scheduler, workers, connect_timeout) as client:
                run_tasks(_plan(pending), evaluate_designs, _payload, _crashed, cases_dir, arrived, client)
        bar.close()
        ordered = [records[case.case_id] for case in cases]
    finally:
        if temporary is not None:
            temporary.cleanup()
    table = design_table(ordered)
    return (table, increment_table(ordered)) if with_increments else table


DESIGN_COLUMNS = tuple(f.name for f in dataclasses.fields(FingertipDesign))
TIMING_COLUMNS = ("fem_wall", "sensor_wall", "prepare", "solve", "dofs")


def design_table(records: list[dict]):
    """One typed row per design: case_id, the design's fields, every metric of METRICS (missing: <NA>), status,
    error, timings [s] and DOF."""
    import pandas as pd

    rows = []
    for record in records:
        row = {"case_id": record["case_id"]}
        row.update({key: record["design"].get(key) for key in DESIGN_COLUMNS})
        row.update({key: record["metrics"].get(key) for key in METRICS})
        row.update(status=record["status"], error=record.get("error") or "", group=record.get("group", ""),
                   worker=record.get("worker", ""))
        row.update({key: record.get("timings", {}).get(key) for key in TIMING_COLUMNS})
        rows.append(row)
    table = pd.DataFrame(rows, columns=["case_id", *DESIGN_COLUMNS, *METRICS, "status", "error", "group", "worker",
                                        *TIMING_COLUMNS])
    types = {key: "Float64" for key in (*DESIGN_COLUMNS, *METRICS, *TIMING_COLUMNS)}
    types.update(rows="Int64", cols="Int64", dofs="Int64", case_id="string", status="string", error="string",
                 group="string", worker="string")
    return table.astype(types)


def increment_table(records: list[dict]):
    """Tidy per-increment table: one row per design, path (shear / twist) and increment."""
    import pandas as pd

    rows = [{"case_id": record["case_id"], **row} for record in records for row in record.get("increments", [])]
    columns = ["case_id", "path", "increment", "load_kind", "load_ratio", "normal_force", "tangential_force",
               "torque", "shift", "angle", "stick_ratio", "contact_area", "least_bump_margin",
               "least_bump_stick_ratio", "estimated_shift", "estimated_angle"]
    table = pd.DataFrame(rows, columns=columns)
    types = {key: "Float64" for key in columns[4:]}
    types.update(case_id="string", path="string", load_kind="string", increment="Int64")
    return table.astype(types)


def pareto_front(table, objectives: dict) -> np.ndarray:
    """Boolean mask of the rows no other row dominates; ``objectives`` maps a column to "lower" or "higher".
    Rows with a missing objective are left out of the front (False)."""
    values = []
    for column, sense in objectives.items():
        if sense not in ("lower", "higher"):
            raise ValueError(f"objective {column!r}: sense={sense!r} is not 'lower' or 'higher'")
        data = table[column].astype("Float64").to_numpy(dtype=float, na_value=np.nan)
        values.append(data if sense == "lower" else -data)
    values = np.column_stack(values)                                   # (n, m), all to be minimised
    complete = np.all(np.isfinite(values), axis=1)
    front = complete.copy()
    for i in np.flatnonzero(complete):
        others = values[complete]
        dominated = np.any(np.all(others <= values[i], axis=1) & np.any(others < values[i], axis=1))
        front[i] = not dominated
    return front
