"""Sweep files: a base scene, parameter axes on dotted scene keys and the quantities to record; validated on entry.

A sweep file (TOML)::

    name = "stick-ratio-E-mu"
    scene = "../scenes/hcm1.toml"            # base scene, relative to this file; or an inline [scene] table
    outputs = ["stick_ratio@-1", "max_pressure@0", "contact_radius@*", "iterations"]

    [grid]                                   # cartesian product of the axes
    "material.E" = [0.5, 1.0, 2.0]

    [list]                                   # zipped: equal lengths, the i-th values form one point
    "contact.friction_coefficient" = [0.3, 0.5]
    "load.1.force" = [0.03, 0.05]            # [[load]] tables by index from 0

Cases are the product of the grid with the zipped list (either may be absent, not both). An axis key is a dotted
path into the scene document: ``SECTION.KEY`` (material, contact, mesh, body, gel) or ``load.INDEX.KEY``; each case
must give a valid scene (``contact.scene_from_dict``). Outputs: ``QUANTITY@INDEX`` for a per-increment quantity at
increment INDEX (from 0; negative counts from the end; ``*`` = every increment, one column each), or a case-level
quantity without ``@``. The column of an output is its text as written.
"""

from __future__ import annotations

import copy
import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from fem.validation import InputErrors, describe

__all__ = ["Output", "Case", "SweepSpec", "load_sweep", "sweep_from_dict", "increment_quantities",
           "CASE_QUANTITIES", "DERIVED_QUANTITIES", "set_dotted", "case_hash", "code_version"]

TOP_KEYS = ("name", "description", "scene", "outputs", "grid", "list")
SCENE_SECTIONS = ("gel", "material", "body", "contact", "mesh", "load")
QUICK_SIZE_CONTACT = 0.3            # mm; --quick coarsens the base scene's contact mesh to at least this (CI size)

# per-increment quantities computed by the sweep from the increment and the scene
DERIVED_QUANTITIES = {
    "load_ratio": "|Q| / (mu P), tangential load ratio [-]",
    "torque_ratio": "|T| / (mu P a), torsional load ratio with the FEM contact radius [-]",
}
# case-level quantities (no @INDEX)
CASE_QUANTITIES = {
    "wall_time": "seconds spent on the case, its share of prepare() included [s]",
    "prepare_time": "seconds of prepare() paid by this case (0 when it reused its group's) [s]",
    "solve_time": "seconds of solve_scene() [s]",
    "iterations": "Newton iterations summed over the increments [-]",
    "increments_done": "converged increments [-]",
    "dofs": "degrees of freedom of the mesh [-]",
    "elements": "tetrahedra [-]",
    "min_dihedral_deg": "smallest dihedral angle of the mesh [deg]",
    "compliance_columns": "surface compliance columns computed in this solve [-]",
}


def increment_quantities() -> tuple[str, ...]:
    """Names of the per-increment quantities: Increment.summary() with [x, y] vectors split, and the derived ones."""
    from contact.solver import Increment

    types = {f.name: str(f.type) for f in dataclasses.fields(Increment)}
    names = []
    for name in Increment.SCALARS:
        names.extend([f"{name}_x", f"{name}_y"] if types[name].startswith("list") else [name])
    return tuple(names) + tuple(DERIVED_QUANTITIES)


@dataclass(frozen=True)
class Output:
    """One recorded quantity; ``increment`` is None for a case-level quantity. ``text`` is the column name."""

    text: str
    quantity: str
    increment: int | None = None


@dataclass(frozen=True)
class Case:
    """One point of the sweep: its parameters (axis key -> value), the full scene document, its id and Scene."""

    case_id: str
    parameters: tuple[tuple[str, object], ...]
    document: dict = field(compare=False, repr=False)
    scene: object = field(compare=False, repr=False)

    @property
    def n_increments(self) -> int:
        return sum(len(load.values) for load in self.scene.loads)


@dataclass(frozen=True)
class SweepSpec:
    """A validated sweep: axes, outputs (``*`` expanded) and the cases in order."""

    name: str
    grid: tuple[tuple[str, tuple], ...]
    zipped: tuple[tuple[str, tuple], ...]
    outputs: tuple[Output, ...]
    cases: tuple[Case, ...]
    base_document: dict = field(compare=False, repr=False)
    source: str = ""

    @property
    def axes(self) -> tuple[str, ...]:
        return tuple(key for key, _ in self.grid + self.zipped)

    @property
    def zipped_axes(self) -> tuple[str, ...]:
        return tuple(key for key, _ in self.zipped)


def set_dotted(document: dict, key: str, value, check_only: bool = False) -> None:
    """Set ``document[a][b]...`` from the dotted ``key`` ("material.E", "load.1.force"); lists are indexed by number.
    ``check_only``: check the key's form (and a renamed key) without a document."""
    from contact.scene import RENAMED_KEYS

    parts = key.split(".")
    if len(parts) < 2 or parts[0] not in SCENE_SECTIONS or not all(parts):
        raise ValueError(f"axis {key!r}: a key is SECTION.KEY with SECTION one of {list(SCENE_SECTIONS)}, or "
                         f"load.INDEX.KEY")
    renamed = RENAMED_KEYS.get((parts[0], parts[-1])) if len(parts) == 2 else None
    if renamed:
        raise ValueError(f"axis {key!r} was renamed {parts[0]}.{renamed}: write \"{parts[0]}.{renamed}\"")
    if check_only:
        return
    node = document
    for depth, part in enumerate(parts[:-1]):
        where = ".".join(parts[: depth + 1])
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                raise ValueError(f"axis {key!r}: {where!r} is not an index of the scene's {len(node)} "
                                 f"[[{parts[depth - 1]}]] table(s) (0 to {len(node) - 1})")
            node = node[int(part)]
        else:
            node = node.setdefault(part, {})
        if not isinstance(node, (dict, list)):
            raise ValueError(f"axis {key!r}: {where!r} is a value ({node!r}), not a table")
    if not isinstance(node, dict):
        raise ValueError(f"axis {key!r}: give a key inside one [[{parts[0]}]] table, e.g. {parts[0]}.0.{parts[-1]}")
    node[parts[-1]] = value


def load_sweep(path: str | Path, quick: bool = False) -> SweepSpec:
    """Read and validate a sweep file; every case's scene is built here, so a bad file fails before any solve, with
    every problem of the file at once (InputErrors, each line naming the file)."""
    from contact.scene import read_toml_file

    data = read_toml_file(path, "sweep file")
    try:
        return sweep_from_dict(data, base_dir=Path(path).parent, quick=quick, source=str(path))
    except ValueError as error:
        problems = InputErrors.problems_of(error)
        raise InputErrors(f"{path}: {problem}" for problem in problems) from None


MAX_CASE_PROBLEMS = 10      # bad cases listed one by one; the rest are counted


def sweep_from_dict(data: dict, base_dir: str | Path = ".", quick: bool = False, source: str = "") -> SweepSpec:
    """SweepSpec from a parsed sweep document; raises InputErrors (a ValueError) with every problem, each naming
    the offending key."""
    problems: list[str] = []

    def attempt(build, default=None):
        try:
            return build()
        except ValueError as error:
            problems.extend(InputErrors.problems_of(error))
            return default

    for key in sorted(set(data) - set(TOP_KEYS)):
        problems.append(f"{key}: unknown top-level key in the sweep file; allowed: {list(TOP_KEYS)}")
    name = data.get("name", Path(source).stem if source else "sweep")
    if not isinstance(name, str) or not name:
        problems.append(f"name={describe(name)} must be a non-empty string")
    base = attempt(lambda: _base_document(data.get("scene"), Path(base_dir)))
    if quick and base is not None:
        mesh = base.setdefault("mesh", {})
        mesh["size_contact"] = max(mesh.get("size_contact", 0.0), QUICK_SIZE_CONTACT)
    grid = attempt(lambda: _axes(data.get("grid", {}), "grid"))
    zipped = attempt(lambda: _axes(data.get("list", {}), "list"))
    parsed_outputs = attempt(lambda: _parse_outputs(data.get("outputs")))
    if grid == () and zipped == ():
        problems.append("the sweep has no axes: give a [grid] and/or a [list] table of dotted keys")
    grid, zipped = grid or (), zipped or ()
    both = sorted({k for k, _ in grid} & {k for k, _ in zipped})
    if both:
        problems.append(f"axis {both[0]!r} is in both [grid] and [list]")
    lengths = {key: len(values) for key, values in zipped}
    if len(set(lengths.values())) > 1:
        problems.append(f"[list] axes are zipped and need equal lengths, got {lengths}")
    for key, _ in grid + zipped:
        attempt(lambda key=key: set_dotted({}, key, None, check_only=True))
    from contact.budget import check_case_count

    count = math.prod(len(values) for _, values in grid) * (len(zipped[0][1]) if zipped else 1)
    attempt(lambda: check_case_count(count))                 # before building them one by one
    if problems:
        raise InputErrors(problems)
    cases = _build_cases(base, grid, zipped)
    return SweepSpec(name=name, grid=grid, zipped=zipped, outputs=_expand_outputs(parsed_outputs, cases),
                     cases=tuple(cases), base_document=base, source=source)


def _base_document(scene, base_dir: Path) -> dict:
    """The base scene document: a path relative to the sweep file, or an inline table; validated as a scene."""
    from contact.scene import read_toml_file, scene_from_dict

    if scene is None:
        raise ValueError("scene is missing: give scene = \"path/to/scene.toml\" (relative to the sweep file) or an "
                         "inline [scene] table")
    if isinstance(scene, str):
        try:
            document = read_toml_file((base_dir / scene).resolve(), f"scene={scene!r}: file")
        except OSError as error:                   # a problem of the sweep file: reported with the others
            raise ValueError(str(error)) from None
    elif isinstance(scene, dict):
        document = copy.deepcopy(scene)
    else:
        raise ValueError(f"scene={describe(scene)} must be a file path (string) or a [scene] table")
    try:
        scene_from_dict(copy.deepcopy(document))
    except ValueError as error:
        problems = InputErrors.problems_of(error)
        raise InputErrors(f"scene: {problem}" for problem in problems) from None
    return document


def _axes(table, section: str) -> tuple[tuple[str, tuple], ...]:
    if not isinstance(table, dict):
        raise ValueError(f"[{section}] must be a table of dotted keys, got {type(table).__name__}")
    axes = []
    for key, values in table.items():
        if isinstance(values, dict):
            raise ValueError(f"[{section}] {key!r} is a table: quote dotted keys, \"{key}.KEY\" = [...]")
        if not isinstance(values, list):
            raise ValueError(f"[{section}] axis {key!r} must be a list of values, got {values!r}")
        if not values:
            raise ValueError(f"[{section}] axis {key!r} is empty")
        for value in values:
            if not _is_plain(value):
                raise ValueError(f"[{section}] axis {key!r}: value {value!r} is not a number, string, boolean or "
                                 f"list of these")
        if any(isinstance(v, float) for v in values):          # 1 and 1.0 are the same point: one type per axis
            values = [float(v) if isinstance(v, int) and not isinstance(v, bool) else v for v in values]
        axes.append((key, tuple(values)))
    return tuple(axes)


def _is_plain(value) -> bool:
    if isinstance(value, list):
        return all(_is_plain(v) for v in value)
    if isinstance(value, float):
        return math.isfinite(value)
    return isinstance(value, (bool, int, str))


def _parse_outputs(outputs) -> list[tuple[str, str, str | None]]:
    """(text, quantity, index text or None) per output; checks the syntax and the quantity names."""
    if not isinstance(outputs, list) or not outputs:
        raise ValueError("outputs must be a non-empty list, e.g. outputs = [\"stick_ratio@-1\", \"wall_time\"]")
    per_increment = increment_quantities()
    parsed = []
    for text in outputs:
        if not isinstance(text, str):
            raise ValueError(f"outputs: {text!r} is not a string like \"stick_ratio@-1\"")
        quantity, at, index = text.partition("@")
        if at:
            if quantity not in per_increment:
                raise ValueError(f"outputs: {text!r}: {quantity!r} is not a per-increment quantity; allowed: "
                                 f"{list(per_increment)}")
            if index != "*" and not index.lstrip("-").isdigit():
                raise ValueError(f"outputs: {text!r}: the increment after @ must be an integer (from 0, negative "
                                 f"from the end) or *")
            parsed.append((text, quantity, index))
        elif quantity in CASE_QUANTITIES:
            parsed.append((text, quantity, None))
        elif quantity in per_increment:
            raise ValueError(f"outputs: {text!r} is per increment: say which, e.g. \"{quantity}@-1\" (last) or "
                             f"\"{quantity}@*\" (every increment)")
        else:
            raise ValueError(f"outputs: {text!r} is not a known quantity; per increment (with @INDEX): "
                             f"{list(per_increment)}; per case: {list(CASE_QUANTITIES)}")
    texts = [t for t, _, _ in parsed]
    repeated = sorted({t for t in texts if texts.count(t) > 1})
    if repeated:
        raise ValueError(f"outputs: {repeated[0]!r} is listed twice")
    return parsed


def _expand_outputs(parsed, cases: list[Case]) -> tuple[Output, ...]:
    """Resolve ``*`` to every increment of the longest path, and check each index against every case's path."""
    shortest = min(case.n_increments for case in cases)
    longest = max(case.n_increments for case in cases)
    outputs = []
    for text, quantity, index in parsed:
        if index is None:
            outputs.append(Output(text, quantity))
        elif index == "*":
            outputs.extend(Output(f"{quantity}@{i}", quantity, i) for i in range(longest))
        else:
            number = int(index)
            if not -shortest <= number < shortest:
                raise ValueError(f"outputs: {text!r}: increment {number} does not exist in every case (the shortest "
                                 f"load path has {shortest} increments: {-shortest} to {shortest - 1})")
            outputs.append(Output(text, quantity, number))
    return tuple(outputs)


def _build_cases(base: dict, grid, zipped) -> list[Case]:
    """Every case's scene, built and checked; all bad cases reported at once (the first MAX_CASE_PROBLEMS in full)."""
    from contact.scene import scene_from_dict
    from fem.task_runner import axis_points

    cases, seen, problems, bad_cases = [], {}, [], 0
    for parameters in axis_points(grid, zipped):
        document = copy.deepcopy(base)
        try:
            for key, value in parameters:
                set_dotted(document, key, copy.deepcopy(value))
            scene = scene_from_dict(copy.deepcopy(document))
        except ValueError as error:
            bad_cases += 1
            if bad_cases <= MAX_CASE_PROBLEMS:
                lines = InputErrors.problems_of(error)
                problems.extend(f"case {dict(parameters)}: {line}" for line in lines)
            continue
        case_id = case_hash(scene)
        if case_id in seen:
            problems.append(f"cases {seen[case_id]} and {dict(parameters)} are the same scene: an axis repeats "
                            f"a value")
            continue
        seen[case_id] = dict(parameters)
        cases.append(Case(case_id, parameters, document, scene))
    if bad_cases > MAX_CASE_PROBLEMS:
        problems.append(f"... and {bad_cases - MAX_CASE_PROBLEMS} more bad case(s)")
    if problems:
        raise InputErrors(problems)
    return cases


PACKAGE = "fingertip-contact"


def code_version() -> str:
    """Installed version of the package (importlib.metadata), "unknown" when it runs from a source tree that was
    never installed."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version(PACKAGE)
    except PackageNotFoundError:
        return "unknown"


def case_hash(scene) -> str:
    """Id of a case: SHA-256 of its physical case and of the installed package version (``code_version()``).

    The physical case is the validated Scene, not the text that made it: defaults filled in, 1 and 1.0 alike, a
    load given as one value or a list of one alike, shear directions as unit vectors ([2, 0] is [1, 0]), the name
    left out; so two spellings of one case are solved once. The version makes a re-run after an upgrade solve every
    case again instead of skipping it on a record the old code wrote (the old records stay in cases/, unused). An
    editable install changes the id only when the version in pyproject.toml is raised, not at every edit."""
    identity = dataclasses.asdict(scene)
    identity.pop("name", None)
    for load in identity["loads"]:
        norm = math.hypot(*load["direction"])
        load["direction"] = [float(f"{component / norm:.12g}") for component in load["direction"]]

    def canonical(value):
        if isinstance(value, dict):
            return {str(k): canonical(v) for k, v in value.items()}
        if isinstance(value, (list, tuple)):
            return [canonical(v) for v in value]
        if isinstance(value, str):                # enum members (str subclasses) as their text
            return str(value.value) if hasattr(value, "value") else value
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        return value

    text = json.dumps({"scene": canonical(identity), "version": code_version()}, sort_keys=True,
                      separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]
