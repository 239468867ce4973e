"""Calibrated reduced-model parameters stored with their fingertip design and provenance (JSON), and read back.

File layout (every key required, no other key allowed)::

    {"schema": "fingertip-contact/reduced-calibration/2",
     "design": {ArrayFingertipDesign fields}, "parameters": {ReducedParameters fields},
     "provenance": {"tag", "date", "package_version", "mesh", "fem_cases", "fit", "diagnostics", "held_out"}}

``provenance.mesh`` holds the element sizes and DOF count of the FEM runs, ``fem_cases`` their load paths,
``fit`` one record per fitted parameter with its residuals (``calibration.FitResult``), ``diagnostics`` further
numbers of the fit, ``held_out`` the FEM paths no fit saw and the model's largest relative error on each quantity.

Schema 2 (this one) holds the Gaussian base kernel with its pressure couple (kernel_width, couple_arm,
couple_arm_slope, couple_arm_limit, displacement_gain); schema 1 held the capped paraboloid kernel (kernel_spread,
cop_gain, moment_arm), whose base-pressure CoP lagged the FEM by half: such a file is refused with a message to
recalibrate. This module reads and writes files only; ``_model`` builds the fingertip from them.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, fields
from pathlib import Path

from fem.atomic import write_text_atomic

from ._design import ArrayFingertipDesign, ReducedParameters

__all__ = ["SCHEMA", "PACKAGED_CALIBRATION", "StoredCalibration", "save_calibration", "load_calibration",
           "parse_calibration"]

SCHEMA = "fingertip-contact/reduced-calibration/2"
_OLD_SCHEMAS = {"fingertip-contact/reduced-calibration/1": "the capped paraboloid base kernel (kernel_spread, "
                "cop_gain, moment_arm) of schema 1"}
PACKAGED_CALIBRATION = Path(__file__).parent / "data" / "fingertip_3x3_calibrated.json"
_TOP_KEYS = ("schema", "design", "parameters", "provenance")
_PROVENANCE_KEYS = ("tag", "date", "package_version", "mesh", "fem_cases", "fit", "diagnostics", "held_out")


@dataclass(frozen=True, eq=False)
class StoredCalibration:
    """A calibration file's content: design, parameters (source "fem:<tag>") and provenance (plain dict)."""

    design: ArrayFingertipDesign
    parameters: ReducedParameters
    provenance: dict

    def to_dict(self) -> dict:
        return {"schema": SCHEMA, "design": self.design.to_dict(), "parameters": self.parameters.to_dict(),
                "provenance": self.provenance}


def _check_keys(where: str, data, required) -> None:
    if not isinstance(data, dict):
        raise ValueError(f"{where} must be a JSON object, got {type(data).__name__}")
    unknown = sorted(set(data) - set(required))
    if unknown:
        raise ValueError(f"{where}: unknown keys {unknown}; allowed: {sorted(required)}")
    missing = sorted(set(required) - set(data))
    if missing:
        raise ValueError(f"{where}: missing keys {missing}")


def _from_dict(cls, data: dict, where: str):
    _check_keys(where, data, [f.name for f in fields(cls)])
    try:
        return cls.from_dict(data)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{where}: {error}") from None


def check_design(stored: ArrayFingertipDesign, expected: ArrayFingertipDesign, where: str = "calibration") -> None:
    """Raise ValueError naming every field where a stored design differs from the expected one."""
    wrong = [f"{f.name}: stored {getattr(stored, f.name)!r}, expected {getattr(expected, f.name)!r}"
             for f in fields(ArrayFingertipDesign)
             if not math.isclose(getattr(stored, f.name), getattr(expected, f.name), rel_tol=1e-12)]
    if wrong:
        raise ValueError(f"{where} was fitted on another fingertip design ({'; '.join(wrong)}); "
                         f"recalibrate for this design (python -m studies reduced-calibration)")


def parse_calibration(data: dict, where: str = "calibration") -> StoredCalibration:
    """StoredCalibration from a parsed JSON object; ValueError naming unknown, missing or bad keys."""
    if isinstance(data, dict) and data.get("schema") in _OLD_SCHEMAS:
        raise ValueError(f"{where}: schema={data['schema']!r} holds {_OLD_SCHEMAS[data['schema']]}, which this "
                         f"version no longer reads (expected {SCHEMA!r}); recalibrate with python -m studies "
                         f"reduced-calibration, or use the packaged file")
    _check_keys(where, data, _TOP_KEYS)
    if data["schema"] != SCHEMA:
        raise ValueError(f"{where}: schema={data['schema']!r}, expected {SCHEMA!r}")
    design = _from_dict(ArrayFingertipDesign, data["design"], f"{where}: design")
    parameters = _from_dict(ReducedParameters, data["parameters"], f"{where}: parameters")
    if not parameters.source.startswith("fem:"):
        raise ValueError(f"{where}: parameters.source={parameters.source!r} must start with 'fem:' (an FEM fit)")
    _check_keys(f"{where}: provenance", data["provenance"], _PROVENANCE_KEYS)
    if data["provenance"]["tag"] != parameters.source[4:]:
        raise ValueError(f"{where}: provenance.tag={data['provenance']['tag']!r} does not match "
                         f"parameters.source={parameters.source!r}")
    return StoredCalibration(design, parameters, data["provenance"])


def _non_finite_key(value, key: str = "") -> str:
    """Dotted key of the first NaN or inf in a JSON-like tree ("" if none)."""
    if isinstance(value, dict):
        items = value.items()
    elif isinstance(value, (list, tuple)):
        items = ((str(i), item) for i, item in enumerate(value))
    else:
        return key if isinstance(value, float) and not math.isfinite(value) else ""
    for name, item in items:
        found = _non_finite_key(item, f"{key}.{name}" if key else str(name))
        if found:
            return found
    return ""


def save_calibration(path, calibration: StoredCalibration) -> Path:
    """Write ``calibration`` as indented JSON to ``path`` atomically (temporary file and rename); return the path."""
    data = calibration.to_dict()
    try:
        text = json.dumps(data, indent=1, allow_nan=False) + "\n"
    except ValueError as error:                # NaN or inf somewhere: name where before anything is written
        raise ValueError(f"calibration for {path} holds a non-finite number at {_non_finite_key(data)}: {error}") \
            from None
    parse_calibration(json.loads(text), str(path))                      # what is written must read back
    return write_text_atomic(path, text)


def load_calibration(path=None, design: ArrayFingertipDesign | None = None) -> StoredCalibration:
    """Read a calibration file (default: the packaged 3x3 fingertip one); if ``design`` is given it must match."""
    path = PACKAGED_CALIBRATION if path is None else Path(path)
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{path}: not valid JSON ({error})") from None
    stored = parse_calibration(data, str(path))
    if design is not None:
        check_design(stored.design, design, str(path))
    return stored

