"""Resumable tables of closed-loop trials: one CSV row per trial, written as each finishes, skipped on a re-run.

A trial is known by a key made of its object, its settings and a hash of the closed loop's sources (``trial_key``): a
re-run with the same jobs reads the rows already in ``NAME_trials.csv`` and runs only the missing ones; after an edit
of the controller or the fingertip model, or with other settings, every trial runs again. Rows are kept in job order.

Every row carries ``row_check``, a digest of its own values: a row read back whose digest does not match (a
truncated line, an edited or bit-flipped value, a row of another shape) is skipped with one warning naming the file,
and its trial runs again; a file that is not CSV text at all is reported the same way and rebuilt.
"""

from __future__ import annotations

import csv
import functools
import hashlib
import json
import math
import warnings
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path

from fem.validation import check_integer
from studies._output import write_csv_atomic


@functools.lru_cache(maxsize=1)
def closed_loop_sources() -> str:
    """SHA-256 of the sources a trial runs (every file of the controller and contact packages, the calibration
    data and the plant's FEM base response included): an edit of the controller or the fingertip model makes every
    stored trial stale, where the package version of an editable install would not change."""
    import contact
    import controller

    digest = hashlib.sha256()
    for package in (controller, contact):
        root = Path(package.__file__).parent
        for path in sorted(root.rglob("*")):
            if path.suffix in (".py", ".json", ".npz") and "__pycache__" not in path.parts:
                digest.update(path.relative_to(root.parent).as_posix().encode())
                digest.update(path.read_bytes())
    return digest.hexdigest()


MAX_TRIALS = 1000             # per object or case: fig6's and the design file's grasp trials have the same bound


def check_trials(trials) -> int:
    """``trials`` per object or case: an integer in [1, MAX_TRIALS] (not a bool)."""
    return check_integer("trials", trials, 1, MAX_TRIALS)


def trial_key(obj, settings, extra: str = "") -> str:
    """Stable key of a trial: object, settings, ``extra`` (e.g. the controller) and the closed loop's sources."""
    text = json.dumps([asdict(obj), asdict(settings), extra, closed_loop_sources()], sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


CHECK = "row_check"


def row_check(row: dict) -> str:
    """Digest (16 hex digits) of a row's values as the CSV holds them (None and "" alike), ``row_check`` left out."""
    items = sorted((name, "" if value is None else str(value)) for name, value in row.items() if name != CHECK)
    text = "\x1f".join(f"{name}\x1e{value}" for name, value in items if value != "")
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _read(path: Path) -> dict[str, dict]:
    """The rows of an earlier run by key; rows that fail their ``row_check`` are skipped, with one TrialRowWarning
    naming the file (and the whole file when it is not CSV text)."""
    if not path.is_file():
        return {}
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            rows = list(csv.DictReader(stream))
    except (UnicodeDecodeError, csv.Error, OSError) as error:
        warnings.warn(f"trial table {str(path)!r} cannot be read ({type(error).__name__}: {error}): its trials run "
                      f"again and the file is rebuilt", TrialRowWarning, stacklevel=3)
        return {}
    valid = {row["key"]: row for row in rows
             if None not in row and None not in row.values() and row.get("key") and row.get(CHECK) == row_check(row)}
    if len(valid) < len(rows):
        warnings.warn(f"trial table {str(path)!r}: {len(rows) - len(valid)} of {len(rows)} row(s) damaged (truncated, "
                      f"edited or of another shape): skipped, their trials run again", TrialRowWarning, stacklevel=3)
    return valid


class TrialRowWarning(UserWarning):
    """Rows of a trial table that do not read back as written are skipped (and their trials run again)."""


def run_trial_table(path: Path, jobs: list[tuple[str, object, object, dict]], row: Callable[[object, dict], dict],
                    processes: int | None = None, label: str | None = None,
                    function: Callable | None = None) -> list[dict]:
    """Run the jobs (key, object, settings, info) not yet in the CSV at ``path``; return every job's row.

    Each job is ``function(object, settings)`` (default: one trial, ``run_trial``) in a process pool, beside the
    reduced model's slip limit ``required_grip_force`` at the trial's friction [N], which ``row(value, info)`` finds
    as ``info["required"]`` when it turns the value into the CSV row (the key is added). Rows read back from an
    earlier run pass through ``coerce`` (numbers and booleans from the CSV's strings).
    """
    from controller.closed_loop import map_trials, run_trial

    keys = [job[0] for job in jobs]
    on_disk = _read(path)
    written = {key: row for key, row in on_disk.items() if key in set(keys)}   # as on disk: their checks hold
    rows = {key: coerce(value) for key, value in written.items()}
    missing = [job for job in jobs if job[0] not in rows]
    if missing and len(on_disk) > len(written):
        warnings.warn(f"trial table {str(path)!r}: {len(on_disk) - len(written)} of its rows belong to another plan "
                      f"or to other closed-loop sources (an edit of controller/ or contact/ makes every trial stale) "
                      f"and are not kept; this run's {len(keys)} trials replace them", TrialRowWarning, stacklevel=2)
    if missing:
        results = map_trials(functools.partial(_with_required_force, function or run_trial),
                             [(obj, settings) for _, obj, settings, _ in missing], processes, progress=label)
        for index, (result, required) in results:
            key, _, _, info = missing[index]
            rows[key] = {"key": key, **row(result, {**info, "required": required})}
            rows[key][CHECK] = row_check(rows[key])
            written[key] = rows[key]
            write_csv_atomic(path, [written[k] for k in keys if k in written])     # after every trial: nothing lost
    return [rows[key] for key in keys]


def _with_required_force(function: Callable, obj, settings) -> tuple:
    # the slip limit (a third of a second each) is found in the workers, with the trial, and only for missing rows;
    # of the trial's own build (its plant factors change the bump laws)
    from controller.closed_loop import required_grip_force
    from controller.plant import plant_mechanics

    return function(obj, settings), required_grip_force(obj, settings.friction_coefficient,
                                                        plant_mechanics(settings.plant),
                                                        settings.plant.friction_anisotropy)


def coerce(row: dict) -> dict:
    """Numbers and booleans back from a CSV row's strings (values computed in this run pass unchanged)."""
    out = {}
    for name, value in row.items():
        if not isinstance(value, str) or name in ("key", CHECK):
            out[name] = value
        elif value in ("True", "False"):
            out[name] = value == "True"
        else:
            try:
                out[name] = float(value) if value.strip().lower() not in ("", "none") else None
            except ValueError:
                out[name] = value
    return out


def add_plant_arguments(parser) -> None:
    """The closed-loop studies' options on the plant the controller does not know (docs/design.md, sec. 9)."""
    parser.add_argument("--plant-spread", type=float, default=None, metavar="E",
                        help="each plant factor uniform in +-E per trial (default 0.1; 0: the nominal build)")
    parser.add_argument("--plant", default=None, metavar="NAME=E,...",
                        help="fixed plant factors instead (kernel_width, couple_arm, youngs_modulus, bump_height, "
                             "node_gain, friction_anisotropy; relative errors, e.g. couple_arm=0.15)")
    parser.add_argument("--sensor-plane", default="fem", choices=["fem", "model"],
                        help="fem: the plant's sensor from the FEM read by capacitive nodes (default); model: the "
                             "estimator's own model read by ideal cells (the known world of earlier rounds)")


def add_swing_argument(parser) -> None:
    """The closed-loop studies' option on the incipient-slip law's swing margin (docs/design.md, sec. 12)."""
    parser.add_argument("--swing-margin", type=float, default=0.0, metavar="M",
                        help="while probing, the slip tests' margins are at least M times each signal's spread about "
                             "its trend over the window (default 0: the sensor's noise alone; 3 was measured)")


def check_swing_margin(swing_margin) -> float:
    """``--swing-margin`` must be a finite number >= 0 [-]."""
    from fem.validation import check_range

    return check_range("--swing-margin", swing_margin, 0.0, math.inf, high_open=True)


def plant_options(plant_spread=None, plant=None, sensor_plane="fem", swing_margin=0.0) -> dict:
    """Checked options of ``add_plant_arguments`` and ``add_swing_argument`` as keywords of ``trial_settings``."""
    from controller.closed_loop import PLANT_SPREAD
    from controller.plant import FACTOR_LIMIT, PlantFactors, SensorPlane

    if plant is not None and plant_spread is not None:
        raise ValueError(f"--plant={plant!r} fixes the plant factors and --plant-spread={plant_spread!r} draws them: "
                         f"give one")
    spread = PLANT_SPREAD if plant_spread is None else plant_spread
    if isinstance(spread, bool) or not isinstance(spread, (int, float)) or not 0.0 <= spread <= FACTOR_LIMIT:
        raise ValueError(f"--plant-spread={plant_spread!r} must be a number in [0, {FACTOR_LIMIT}]")
    factors = None if plant is None else (plant if isinstance(plant, PlantFactors) else PlantFactors.parse(plant))
    try:
        plane = SensorPlane(sensor_plane)
    except ValueError:
        raise ValueError(f"--sensor-plane={sensor_plane!r} is not one of {[p.value for p in SensorPlane]}") from None
    return dict(plant_spread=abs(float(spread)), plant=factors, sensor_plane=plane,
                swing_margin=check_swing_margin(swing_margin))


def plant_description(options: dict) -> str:
    """A figure title's words for ``plant_options``: sensor plane, plant factors, the friction range and the law's
    swing margin where one is set."""
    from controller.closed_loop import FRICTION_RANGE

    fixed = options["plant"].nonzero() if options["plant"] is not None else None
    plant = ("nominal plant" if fixed == {} else
             "plant " + ", ".join(f"{name} {100 * value:+.0f} %" for name, value in fixed.items()) if fixed
             else f"plant factors +-{100 * options['plant_spread']:.0f} %")
    swing = f", swing margin {options['swing_margin']:g}" if options.get("swing_margin") else ""
    return (f"{options['sensor_plane'].value} sensor plane, {plant}, "
            f"mu {FRICTION_RANGE[0]:g}-{FRICTION_RANGE[1]:g}{swing}")


def trial_settings(rng, plant_spread: float, plant=None, sensor_plane="fem", **fixed):
    """A randomised trial (``random_settings``: friction 0.2-1.2, jitter, noise, plant factors within
    +-``plant_spread``), with ``plant`` (fixed factors) in place of the drawn ones if given. The draws are the
    same whatever the plant options, so the same seed gives the same objects, frictions and jitter."""
    from dataclasses import replace

    from controller.closed_loop import random_settings

    settings = random_settings(rng, plant_spread=plant_spread, **fixed)
    if plant is not None:
        settings = replace(settings, plant=plant)
    return replace(settings, sensor_plane=sensor_plane)


def trial_columns(result, info: dict) -> dict:
    """A trial's row after its own labels: friction, ``outcome_columns``, the settled grip over the trial's slip limit
    ``info["required"]`` [N] (what ``run_trial_table`` hands the row), the forces [N] and the real-time factor."""
    return dict(friction_coefficient=result.settings.friction_coefficient,
                **outcome_columns(result, info["required"], info["crush_force"]),
                force_ratio=result.hold_force_settled / info["required"], required_force=info["required"],
                hold_force_settled=result.hold_force_settled, max_force=result.max_force,
                real_time_factor=result.real_time_factor)


def outcome_columns(result, required: float, crush_force: float) -> dict:
    """The per-trial columns every closed-loop table shares: outcome, held-still measures, the friction estimate and
    whether the trial could be held at all (its slip limit below the object's crush force)."""
    import math

    settings = result.settings
    columns = dict(outcome=result.outcome, success=result.success, dropped=result.dropped, crushed=result.crushed,
                   rotated=result.rotated, feasible=bool(required < crush_force),
                   hold_slip_mm=result.hold_slip_mm, hold_rotation_mrad=result.hold_rotation_mrad,
                   grasp_slip_mm=result.grasp_slip_mm, max_rotation_mrad=result.max_rotation_mrad,
                   creep_after_friction_um_per_s=result.creep_after_friction_um_per_s,
                   creep_window_s=result.creep_window_s, creep_measurable=result.creep_measurable,
                   friction_estimate=result.friction_estimate,
                   friction_estimate_error=result.friction_estimate / settings.friction_coefficient - 1.0
                   if math.isfinite(result.friction_estimate) else math.nan,
                   slips_detected=len(result.slip_events),
                   first_slip=result.slip_events[0][2] if result.slip_events else "",
                   sensor_plane=settings.sensor_plane.value)
    columns.update({f"plant_{name}": value for name, value in vars(settings.plant).items()})
    return columns
