"""Scenes: a gel, its material, a rigid body, friction, mesh settings and a load path; TOML in, dataclasses out.

Types are strict and every problem of a file is reported at once (``fem.validation.InputErrors``, one line per
problem naming the key, its value and what is allowed). String options become enums where they enter
(``GelShape``, ``BodyShape``, ``Symmetry``, ``Volumetric``, ``MaterialLaw``, ``LoadKind``, ``LoadControl``). The
friction coefficient is ``friction_coefficient`` everywhere; the old key ``mu`` is refused with the new name.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field, fields
from pathlib import Path

import numpy as np

from fem.validation import (Choice, InputErrors, check_all, check_bool, check_integer, check_positive,
                            check_range, describe, parse_choice)

from contact._toml_file import MAX_TOML_BYTES, read_toml_file  # noqa: F401  (re-exported: contact.scene's API)

__all__ = ["GelSpec", "Material", "BodySpec", "ContactSpec", "MeshSettings", "Load", "LoadKind", "LoadControl",
           "GelShape", "BodyShape", "Symmetry", "Volumetric", "MaterialLaw", "Scene", "load_scene", "scene_from_dict",
           "read_toml_file", "RENAMED_KEYS"]


class LoadKind(Choice):
    PRESS = "press"
    SHEAR = "shear"
    TWIST = "twist"


class LoadControl(Choice):
    FORCE = "force"                   # force [N] or torque [N mm]
    DISPLACEMENT = "displacement"     # depth, shift [mm] or angle [rad]


class GelShape(Choice):
    BLOCK = "block"
    CAP = "cap"
    FLAT_CAP = "flat_cap"
    ARRAY = "array"


class BodyShape(Choice):
    SPHERE = "sphere"
    PLANE = "plane"


class Symmetry(Choice):
    AUTO = "auto"                     # half model when the scene is mirror-symmetric about y = 0
    OFF = "off"


class MaterialLaw(Choice):
    LINEAR = "linear"                 # small strain: stress from the linearized strain, equilibrium on the start shape
    NEO_HOOKEAN = "neo_hookean"       # compressible Neo-Hookean, finite strain (fem.hyperelastic)


class Volumetric(Choice):
    STANDARD = "standard"             # lambda tr(eps)^2 per element
    NODAL_AVERAGE = "nodal_average"   # average nodal pressure (P1 only), locking-free for nu -> 0.5


_GEL_CLASSES = {GelShape.BLOCK: "BlockGeometry", GelShape.CAP: "CapGeometry", GelShape.FLAT_CAP: "FlatCapGeometry",
                GelShape.ARRAY: "ArrayGeometry"}
RENAMED_KEYS = {("contact", "mu"): "friction_coefficient"}     # (section, old key) -> new key


def _prefixed(prefix: str, error: ValueError) -> InputErrors:
    problems = InputErrors.problems_of(error)
    return InputErrors(f"{prefix}{problem}" for problem in problems)


@dataclass(frozen=True)
class GelSpec:
    """The gel: a shape and the parameters of its fem.geometry dataclass [mm]; base bonded, top point at z = 0.

    block: width, depth, thickness; cap: width, depth, base_thickness, cap_radius, sphere_radius (or exponent and
    power_law_height); flat_cap: width, depth, base_thickness, cap_radius, flat_radius, edge_radius; array: rows,
    cols, bump_radius, pitch, base_width, base_depth, base_thickness, fillet. Omitted parameters take the
    geometry's defaults.
    """

    shape: GelShape = GelShape.BLOCK
    parameters: tuple = (("width", 40.0), ("depth", 40.0), ("thickness", 20.0))

    def __post_init__(self):
        object.__setattr__(self, "shape", parse_choice("gel.shape", self.shape, GelShape))
        object.__setattr__(self, "_geometry", self._build_geometry())   # validated where the scene enters

    @property
    def geometry(self):
        """The fem.geometry dataclass of this gel (validated)."""
        return self._geometry

    def _build_geometry(self):
        import fem.geometry

        cls = getattr(fem.geometry, _GEL_CLASSES[self.shape])
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(dict(self.parameters)) - known)
        if unknown:
            raise ValueError(f"gel: unknown key(s) {unknown} for shape {self.shape.value!r}; allowed: "
                             f"{sorted(known | {'shape'})}")
        try:
            return cls(**dict(self.parameters))
        except ValueError as error:
            raise _prefixed("gel.", error) from None

    @property
    def curvature_radius(self) -> float:
        """Radius of curvature of the gel at its first-contact points [mm] (inf where it is flat)."""
        geometry = self.geometry
        if self.shape == GelShape.CAP and geometry.exponent in (None, 2, 2.0):
            return geometry.sphere_radius if geometry.exponent is None else 1.0 / (2.0 * geometry.profile_coefficient)
        if self.shape == GelShape.FLAT_CAP and geometry.flat_radius == 0.0:
            return geometry.edge_radius
        if self.shape == GelShape.ARRAY:
            return geometry.bump_radius
        return math.inf

    @property
    def thickness_under_contact(self) -> float:
        """Gel thickness [mm] below the first-contact points (top at z = 0, bonded base at z = -height)."""
        return float(self.geometry.height)

    def __getattr__(self, name):
        # width, depth, thickness, ... read through to the geometry (convenient for the block)
        if name.startswith("_") or name in ("shape", "parameters"):
            raise AttributeError(name)
        try:
            return getattr(self.geometry, name)
        except AttributeError:
            raise AttributeError(f"gel of shape {self.shape!r} has no {name!r}") from None


@dataclass(frozen=True)
class Material:
    """The gel: Young's modulus E [MPa] and Poisson's ratio nu (0.5 excluded) at small strain, and its ``law``:
    LINEAR (small strain) or NEO_HOOKEAN (compressible Neo-Hookean with the same small-strain moduli; finite strain,
    ``contact._finite_strain``; a plane body and the standard volumetric term only, checked by ``Scene``)."""

    E: float = 1.0
    nu: float = 0.45
    law: MaterialLaw = MaterialLaw.LINEAR

    def __post_init__(self):
        def law():
            object.__setattr__(self, "law", parse_choice("material.law", self.law, MaterialLaw))

        check_all(law, lambda: check_positive("material.E", self.E, "MPa"),
                  lambda: check_range("material.nu", self.nu, -1.0, 0.5, low_open=True, high_open=True))

    @property
    def shear_modulus(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def effective_modulus(self) -> float:
        """E* = E / (1 - nu^2) of a rigid body on this gel [MPa]."""
        return self.E / (1.0 - self.nu**2)


def _check_pair(name: str, value, unit: str) -> tuple[float, float]:
    """(x, y) of two finite numbers, else ValueError naming ``name``."""
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ValueError(f"{name}={describe(value)} must be two numbers [x, y] in {unit}")
    return (check_range(f"{name}[0]", value[0], -math.inf, math.inf, unit),
            check_range(f"{name}[1]", value[1], -math.inf, math.inf, unit))


@dataclass(frozen=True)
class BodySpec:
    """Rigid counter-body: a sphere of given radius [mm] or a plane, initially touching the gel at ``center``."""

    shape: BodyShape = BodyShape.SPHERE
    radius: float = 10.0
    center: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        def shape():
            object.__setattr__(self, "shape", parse_choice("body.shape", self.shape, BodyShape))

        def center():
            object.__setattr__(self, "center", _check_pair("body.center", self.center, "mm"))

        check_all(shape, center, lambda: check_positive("body.radius", self.radius, "mm"))

    def initial_gap(self, xy: np.ndarray) -> np.ndarray:
        """Vertical distance from the body's lowest point level to its surface above points xy (n, 2) [mm]."""
        if self.shape == BodyShape.PLANE:
            return np.zeros(len(xy))
        r2 = ((xy - np.asarray(self.center)) ** 2).sum(axis=1)
        return np.where(r2 < self.radius**2, self.radius - np.sqrt(np.maximum(self.radius**2 - r2, 0.0)), np.inf)


@dataclass(frozen=True)
class ContactSpec:
    """Coulomb friction coefficient [-]; ``frictionless_press`` switches friction on only after the press loads."""

    friction_coefficient: float = 0.5
    frictionless_press: bool = False
    tolerance: float = 1e-10          # Newton residual, relative to the normal force
    max_iterations: int = 60
    symmetry: Symmetry = Symmetry.AUTO

    def __post_init__(self):
        def symmetry():
            object.__setattr__(self, "symmetry", parse_choice("contact.symmetry", self.symmetry, Symmetry))

        check_all(symmetry,
                  lambda: check_range("contact.friction_coefficient", self.friction_coefficient, 0.0, 5.0),
                  lambda: check_bool("contact.frictionless_press", self.frictionless_press),
                  # below ~1e-13 the Newton residual meets round-off and can never be reached
                  lambda: check_range("contact.tolerance", self.tolerance, 1e-13, 1e-3),
                  lambda: check_integer("contact.max_iterations", self.max_iterations, 1, 10_000))

    @property
    def mu(self) -> float:
        """Deprecated name of ``friction_coefficient``."""
        warnings.warn("ContactSpec.mu is renamed friction_coefficient", DeprecationWarning, stacklevel=2)
        return self.friction_coefficient


@dataclass(frozen=True)
class MeshSettings:
    """Element size where contact can occur and far from it [mm], element order; fine zone radius (auto if None).

    ``volumetric``: STANDARD (lambda tr(eps)^2 per element; P1 locks above nu ~ 0.49, P2 partly) or NODAL_AVERAGE
    (P1 only: average-nodal-pressure tets, locking-free for nu -> 0.5; fem.elasticity).
    """

    size_contact: float = 0.2        # mm; a/5 for HCM-1 (recovered c/a within 0.0023, docs/coupled_reference.md)
    size_far: float = 4.0
    order: int = 1
    fine_radius: float | None = None
    grading: float = 0.5
    size_base: float | None = None    # element size on the sensor plane [mm] (curved gels; None: size_far)
    volumetric: Volumetric = Volumetric.STANDARD

    def __post_init__(self):
        def volumetric():
            object.__setattr__(self, "volumetric", parse_choice("mesh.volumetric", self.volumetric, Volumetric))

        check_all(volumetric,
                  lambda: check_positive("mesh.size_contact", self.size_contact, "mm"),
                  lambda: check_positive("mesh.size_far", self.size_far, "mm"),
                  lambda: check_integer("mesh.order", self.order, 1, 2),
                  lambda: self.fine_radius is None or check_positive("mesh.fine_radius", self.fine_radius, "mm"),
                  lambda: self.size_base is None or check_positive("mesh.size_base", self.size_base, "mm"),
                  lambda: check_positive("mesh.grading", self.grading))
        if self.size_contact > self.size_far:
            raise ValueError(f"mesh.size_contact={self.size_contact} mm must not exceed mesh.size_far="
                             f"{self.size_far} mm")
        if self.volumetric == Volumetric.NODAL_AVERAGE and self.order != 1:
            raise ValueError(f"mesh.volumetric={self.volumetric.value!r} needs mesh.order=1 (P1 tets), got "
                             f"mesh.order={self.order}; use mesh.volumetric='standard' with P2")


@dataclass(frozen=True)
class Load:
    """One stage of the load path; each value is one increment.

    press: ``force`` [N] or ``depth`` [mm]; shear: ``force`` [N] or ``shift`` [mm] along ``direction``;
    twist: ``torque`` [N mm] or ``angle`` [rad] about +z through the body centre.
    """

    kind: LoadKind
    control: LoadControl
    values: tuple[float, ...]
    direction: tuple[float, float] = (1.0, 0.0)

    def __post_init__(self):
        object.__setattr__(self, "kind", parse_choice("load kind", self.kind, LoadKind))
        object.__setattr__(self, "control", parse_choice("load control", self.control, LoadControl))
        key = next(k for k, c in _LOAD_KEYS[self.kind].items() if c == self.control)
        unit = {"force": "N", "depth": "mm", "shift": "mm", "torque": "N mm", "angle": "rad"}[key]
        if isinstance(self.values, (str, bytes)) or not hasattr(self.values, "__len__"):
            raise ValueError(f"{key}={describe(self.values)} must be a number or a list of numbers [{unit}]")
        if not self.values:
            raise ValueError(f"{self.kind.value} load has an empty list of values: {key} = []")
        if self.kind == LoadKind.PRESS:
            check_all(*[lambda v=v: check_positive(f"{key}", v, unit) for v in self.values])
        else:
            check_all(*[lambda v=v: check_range(f"{key}", v, -math.inf, math.inf, unit) for v in self.values])
        direction = _check_pair("direction", self.direction, "any unit")
        if self.kind == LoadKind.SHEAR and not math.hypot(*direction) > 0:
            raise ValueError(f"direction={list(self.direction)!r} must be a non-zero [x, y]")
        object.__setattr__(self, "values", tuple(float(v) for v in self.values))
        object.__setattr__(self, "direction", direction)


_LOAD_KEYS = {
    LoadKind.PRESS: {"force": LoadControl.FORCE, "depth": LoadControl.DISPLACEMENT},
    LoadKind.SHEAR: {"force": LoadControl.FORCE, "shift": LoadControl.DISPLACEMENT},
    LoadKind.TWIST: {"torque": LoadControl.FORCE, "angle": LoadControl.DISPLACEMENT},
}


@dataclass(frozen=True)
class Scene:
    """A complete contact problem."""

    name: str = "scene"
    gel: GelSpec = field(default_factory=GelSpec)
    material: Material = field(default_factory=Material)
    body: BodySpec = field(default_factory=BodySpec)
    contact: ContactSpec = field(default_factory=ContactSpec)
    mesh: MeshSettings = field(default_factory=MeshSettings)
    loads: tuple[Load, ...] = ()

    def __post_init__(self):
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"name={describe(self.name)} must be a non-empty string")
        if not self.loads:
            raise ValueError("scene has no [[load]]: give at least one press")
        if self.loads[0].kind != LoadKind.PRESS:
            raise ValueError(f"load.0.kind={self.loads[0].kind.value!r}: the first load must be a press")
        if self.material.law == MaterialLaw.NEO_HOOKEAN:
            # the finite-strain gel pairs the gap along z with the points where they have moved to: exact for a
            # plane (its normal stays z), not for a sphere, whose normal at a moved point tilts
            if self.body.shape != BodyShape.PLANE:
                raise ValueError(f"material.law='neo_hookean' with body.shape={self.body.shape.value!r}: the "
                                 f"finite-strain gel needs body.shape='plane'")
            if self.mesh.volumetric != Volumetric.STANDARD:
                raise ValueError(f"material.law='neo_hookean' with mesh.volumetric={self.mesh.volumetric.value!r}: "
                                 f"the finite-strain gel needs mesh.volumetric='standard'")

    @property
    def mirror_symmetric(self) -> bool:
        """True when gel, body and every load are symmetric about the plane y = 0 (press, shear along x)."""
        return (self.gel.shape == GelShape.BLOCK and self.body.center[1] == 0.0 and all(
            load.kind == LoadKind.PRESS or (load.kind == LoadKind.SHEAR and load.direction[1] == 0.0)
            for load in self.loads))

    @property
    def has_tangential_load(self) -> bool:
        return any(load.kind != LoadKind.PRESS for load in self.loads)


def _build(cls, table, section: str):
    """Dataclass ``cls`` from a TOML table, rejecting unknown and renamed keys by name, all problems at once."""
    if not isinstance(table, dict):
        raise ValueError(f"[{section}] must be a table, got {describe(table)}")
    known = {f.name for f in fields(cls)}
    problems = []
    for key in sorted(set(table) - known):
        renamed = RENAMED_KEYS.get((section, key))
        if renamed:
            problems.append(f"{section}.{key} was renamed {section}.{renamed}: write {renamed} = {table[key]!r}")
        else:
            problems.append(f"{section}.{key}: unknown key; allowed: {sorted(known)}")
    values = {key: tuple(value) if isinstance(value, list) else value for key, value in table.items() if key in known}
    try:
        built = cls(**values)
    except ValueError as error:
        raise InputErrors(problems + InputErrors.problems_of(error)) from None
    if problems:
        raise InputErrors(problems)
    return built


def _load_from_table(table, index: int) -> Load:
    where = f"load.{index}"
    kinds = LoadKind.values()
    if not isinstance(table, dict):
        raise ValueError(f"{where} must be a table ([[load]]), got {describe(table)}")
    if "kind" not in table:
        raise ValueError(f"{where}.kind is missing: give kind = one of {kinds}")
    kind = parse_choice(f"{where}.kind", table["kind"], LoadKind)
    allowed = dict(_LOAD_KEYS[kind])
    extra = {"kind"} | ({"direction"} if kind == LoadKind.SHEAR else set())
    unknown = sorted(set(table) - set(allowed) - extra)
    if unknown:
        raise ValueError(f"{where} ({kind.value}): unknown key(s) {unknown}; allowed: "
                         f"{sorted(set(allowed) | extra)}")
    given = [key for key in allowed if key in table]
    if len(given) != 1:
        raise ValueError(f"{where} ({kind.value}) needs exactly one of {sorted(allowed)}, got {given}")
    raw = table[given[0]]
    values = tuple(raw) if isinstance(raw, list) else (raw,)
    try:
        return Load(kind, allowed[given[0]], values, table.get("direction", (1.0, 0.0)))
    except ValueError as error:
        raise _prefixed(f"{where}.", error) from None


SECTIONS = {"material": Material, "body": BodySpec, "contact": ContactSpec, "mesh": MeshSettings}


def scene_from_dict(data: dict) -> Scene:
    """Scene from a parsed TOML document (see studies/scenes/hcm1.toml); every problem is reported at once
    (InputErrors, a ValueError)."""
    if not isinstance(data, dict):
        raise ValueError(f"a scene is a table of sections, got {describe(data)}")
    problems: list[str] = []

    def attempt(build):
        try:
            return build()
        except ValueError as error:
            problems.extend(InputErrors.problems_of(error))
            return None

    allowed = sorted(set(SECTIONS) | {"gel", "name", "load"})
    for key in sorted(set(data) - set(allowed)):
        problems.append(f"{key}: unknown top-level key; allowed: {allowed}")
    for required in ("gel", "material", "body", "load"):
        if required not in data:
            problems.append(f"scene is missing [{required}]" if required != "load" else "scene is missing [[load]]")
    parts = {key: attempt(lambda key=key, cls=cls: _build(cls, data.get(key, {}), key))
             for key, cls in SECTIONS.items()}

    def gel():
        table = data["gel"]
        if not isinstance(table, dict):
            raise ValueError(f"[gel] must be a table, got {describe(table)}")
        return GelSpec(shape=table.get("shape", "block"),
                       parameters=tuple(sorted((k, v) for k, v in table.items() if k != "shape")))

    parts["gel"] = attempt(gel) if "gel" in data else None
    loads = None
    if "load" in data:
        if not isinstance(data["load"], list):
            problems.append("load must be an array of tables: write [[load]]")
        else:
            loads = [attempt(lambda table=table, index=index: _load_from_table(table, index))
                     for index, table in enumerate(data["load"])]
    name = data.get("name", "scene")
    if problems:
        raise InputErrors(problems)
    return _scene(name, tuple(loads), parts)


def _scene(name, loads, parts) -> Scene:
    try:
        return Scene(name=name, loads=loads, **parts)
    except ValueError as error:
        raise InputErrors([str(error)]) from None


def load_scene(path: str | Path) -> Scene:
    """Read a scene TOML file; every problem in it is reported at once, each line naming the file."""
    data = read_toml_file(path, "scene file")
    try:
        return scene_from_dict(data)
    except ValueError as error:
        raise _prefixed(f"{path}: ", error) from None
