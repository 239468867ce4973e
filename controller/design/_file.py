"""Design files: the designs of a sweep and the study they go through, in TOML; validated where they enter.

A design file::

    name = "fingertip-designs"
    description = "array size against gel stiffness"

    [study]                         # optional: controller.design.DesignStudy fields (defaults otherwise)
    normal_force = 2.0              # N
    size_contact = 0.3              # mm

    [base]                          # optional: the FingertipDesign the axes vary (the paper's 3x3 otherwise)
    base_thickness = 3.0

    [grid]                          # cartesian product of the axes
    youngs_modulus = [0.3, 0.6]     # MPa

    [list]                          # zipped: equal lengths, the i-th values form one point
    rows = [2, 3, 4]
    cols = [2, 3, 4]
    pitch = [20.0, 13.3333, 10.0]
    bump_radius = [7.0, 4.6667, 3.5]

Designs are the product of the grid with the zipped list (either may be absent; both absent: the base design alone).
Axis keys are FingertipDesign fields. Every design is built here, so a bad file fails before any solve, with a
message naming the key (and, for an invalid design, its axis values).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path

from ._spec import DesignStudy, FingertipDesign

__all__ = ["DesignSweepSpec", "load_design_file", "design_spec_from_dict"]

TOP_KEYS = ("name", "description", "study", "base", "grid", "list")


@dataclass(frozen=True)
class DesignSweepSpec:
    """A validated design file: its name, the study, the axes and the designs in order."""

    name: str
    study: object
    grid: tuple[tuple[str, tuple], ...]
    zipped: tuple[tuple[str, tuple], ...]
    designs: tuple = field(repr=False)
    description: str = ""
    source: str = ""

    @property
    def axes(self) -> tuple[str, ...]:
        return tuple(key for key, _ in self.grid + self.zipped)


def load_design_file(path, quick: bool = False) -> DesignSweepSpec:
    """Read and validate a design file (``quick``: coarse meshes and two noise draws, for a fast look); every
    message names the file. A missing file, a folder, a named pipe or a device, a file too large to be a design
    file, or one that is not UTF-8 TOML is refused by ``contact.scene.read_toml_file``."""
    from contact.scene import read_toml_file

    data = read_toml_file(path, "design file")
    try:
        return design_spec_from_dict(data, quick=quick, source=str(path))
    except ValueError as error:
        raise ValueError(f"{path}: {error}") from None


def _table(data: dict, key: str) -> dict:
    table = data.get(key, {})
    if not isinstance(table, dict):
        raise ValueError(f"[{key}] must be a table, got {type(table).__name__} {table!r}")
    return table


def _build(cls, table: dict, section: str, prefix: str = ""):
    known = [f.name for f in dataclasses.fields(cls)]
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise ValueError(f"{prefix}[{section}]: unknown key(s) {unknown} in [{section}]; allowed: {known}")
    values = {key: tuple(value) if isinstance(value, list) else value for key, value in table.items()}
    try:
        return cls(**values)
    except (TypeError, ValueError) as error:
        raise ValueError(f"{prefix}[{section}]: {error}") from None


def _axes(table: dict, section: str, allowed: list[str]) -> tuple[tuple[str, tuple], ...]:
    axes = []
    for key, values in table.items():
        if key not in allowed:
            raise ValueError(f"[{section}] axis {key!r} is not a design field; allowed: {allowed}")
        if not isinstance(values, list) or not values:
            raise ValueError(f"[{section}] {key} must be a non-empty list of values, got {values!r}")
        axes.append((key, tuple(values)))
    return tuple(axes)


QUICK = {"size_contact": 0.7, "size_base": 1.5, "noise_draws": 2}   # --quick: the CI-size meshes of the quick benches


def design_spec_from_dict(data: dict, quick: bool = False, source: str = "") -> DesignSweepSpec:
    """DesignSweepSpec from a parsed design file; raises ValueError naming the offending key."""
    from contact.budget import check_case_count
    from fem.task_runner import axis_points

    if not isinstance(data, dict):
        raise ValueError(f"a design file is a TOML table, got {type(data).__name__}")
    unknown = sorted(set(data) - set(TOP_KEYS))
    if unknown:
        raise ValueError(f"unknown top-level key(s) {unknown} in the design file; allowed: {list(TOP_KEYS)}")
    texts = {"name": data.get("name", Path(source).stem if source else "designs"),
             "description": data.get("description", "")}
    for key, text in texts.items():
        if not isinstance(text, str) or (key == "name" and not text):
            raise ValueError(f"{key}={text!r} must be a {'non-empty ' if key == 'name' else ''}string")
    name, description = texts["name"], texts["description"]
    study = _build(DesignStudy, dict(_table(data, "study")), "study")     # checked as written: no coercion first
    if quick:                                                                 # then coarsened, never refined
        study = dataclasses.replace(study, noise_draws=min(study.noise_draws, QUICK["noise_draws"]),
                                    **{key: max(getattr(study, key), QUICK[key]) for key in ("size_contact",
                                                                                              "size_base")})
    base = _table(data, "base")
    _build(FingertipDesign, base, "base")
    allowed = [f.name for f in dataclasses.fields(FingertipDesign)]
    grid = _axes(_table(data, "grid"), "grid", allowed)
    zipped = _axes(_table(data, "list"), "list", allowed)
    check_case_count(math.prod(len(values) for _, values in grid) * (len(zipped[0][1]) if zipped else 1), "designs")
    designs, seen = [], {}
    for parameters in axis_points(grid, zipped):          # checks: no axis twice, equal [list] lengths
        point = dict(parameters)
        design = _build(FingertipDesign, {**base, **point}, "base", prefix=f"design {point} " if point else "")
        if design in seen:
            raise ValueError(f"designs {seen[design]} and {point} are the same design: an axis repeats a value")
        seen[design] = point
        designs.append(design)
    return DesignSweepSpec(name, study, grid, zipped, tuple(designs), description, source)
