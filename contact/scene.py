"""Scenes: a gel, its material, a rigid body, friction, mesh settings and a load path; TOML in, dataclasses out."""

from __future__ import annotations

import math
import sys
from dataclasses import dataclass, field, fields
from enum import Enum
from pathlib import Path

import numpy as np

from fem.elasticity import VOLUMETRIC_FORMULATIONS
from fem.validation import check_positive, check_range

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["GelSpec", "Material", "BodySpec", "ContactSpec", "MeshSettings", "Load", "LoadKind", "Scene",
           "load_scene", "scene_from_dict"]


class LoadKind(str, Enum):
    PRESS = "press"
    SHEAR = "shear"
    TWIST = "twist"


_GEL_SHAPES = {"block": "BlockGeometry", "cap": "CapGeometry", "flat_cap": "FlatCapGeometry", "array": "ArrayGeometry"}


@dataclass(frozen=True)
class GelSpec:
    """The gel: a shape and the parameters of its fem.geometry dataclass [mm]; base bonded, top point at z = 0.

    block: width, depth, thickness; cap: width, depth, base_thickness, cap_radius, sphere_radius (or exponent and
    power_law_height); flat_cap: width, depth, base_thickness, cap_radius, flat_radius, edge_radius; array: rows,
    cols, bump_radius, pitch, base_width, base_depth, base_thickness, fillet. Omitted parameters take the
    geometry's defaults.
    """

    shape: str = "block"
    parameters: tuple = (("width", 40.0), ("depth", 40.0), ("thickness", 20.0))

    def __post_init__(self):
        if self.shape not in _GEL_SHAPES:
            raise ValueError(f"gel.shape={self.shape!r} is not one of {sorted(_GEL_SHAPES)}")
        object.__setattr__(self, "_geometry", self._build_geometry())   # validated where the scene enters

    @property
    def geometry(self):
        """The fem.geometry dataclass of this gel (validated)."""
        return self._geometry

    def _build_geometry(self):
        import fem.geometry

        cls = getattr(fem.geometry, _GEL_SHAPES[self.shape])
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(dict(self.parameters)) - known)
        if unknown:
            raise ValueError(f"unknown key(s) {unknown} in [gel] for shape {self.shape!r}; allowed: {sorted(known)}")
        try:
            return cls(**dict(self.parameters))
        except (TypeError, ValueError) as error:
            raise ValueError(f"[gel] ({self.shape}): {error}") from None

    @property
    def curvature_radius(self) -> float:
        """Radius of curvature of the gel at its first-contact points [mm] (inf where it is flat)."""
        geometry = self.geometry
        if self.shape == "cap" and geometry.exponent in (None, 2, 2.0):
            return geometry.sphere_radius if geometry.exponent is None else 1.0 / (2.0 * geometry.profile_coefficient)
        if self.shape == "flat_cap" and geometry.flat_radius == 0.0:
            return geometry.edge_radius
        if self.shape == "array":
            return geometry.bump_radius
        return math.inf

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
    """Linear-elastic gel: Young's modulus E [MPa] and Poisson's ratio nu (0.5 excluded)."""

    E: float = 1.0
    nu: float = 0.45

    def __post_init__(self):
        check_positive("material.E", self.E, "MPa")
        check_range("material.nu", self.nu, -1.0, 0.5, low_open=True, high_open=True)

    @property
    def shear_modulus(self) -> float:
        return self.E / (2.0 * (1.0 + self.nu))

    @property
    def effective_modulus(self) -> float:
        """E* = E / (1 - nu^2) of a rigid body on this gel [MPa]."""
        return self.E / (1.0 - self.nu**2)


@dataclass(frozen=True)
class BodySpec:
    """Rigid counter-body: a sphere of given radius [mm] or a plane, initially touching the gel at ``center``."""

    shape: str = "sphere"
    radius: float = 10.0
    center: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        if self.shape not in ("sphere", "plane"):
            raise ValueError(f"body.shape={self.shape!r} is not one of ['plane', 'sphere']")
        if self.shape == "sphere":
            check_positive("body.radius", self.radius, "mm")
        if len(self.center) != 2:
            raise ValueError(f"body.center={self.center!r} must be [x, y] in mm")

    def initial_gap(self, xy: np.ndarray) -> np.ndarray:
        """Vertical distance from the body's lowest point level to its surface above points xy (n, 2) [mm]."""
        if self.shape == "plane":
            return np.zeros(len(xy))
        r2 = ((xy - np.asarray(self.center)) ** 2).sum(axis=1)
        return np.where(r2 < self.radius**2, self.radius - np.sqrt(np.maximum(self.radius**2 - r2, 0.0)), np.inf)


@dataclass(frozen=True)
class ContactSpec:
    """Coulomb friction coefficient mu; ``frictionless_press`` switches friction on only after the press loads."""

    mu: float = 0.5
    frictionless_press: bool = False
    tolerance: float = 1e-10          # Newton residual, relative to the normal force
    max_iterations: int = 60
    symmetry: str = "auto"            # "auto": half model when the scene is mirror-symmetric about y = 0; "off"

    def __post_init__(self):
        if self.symmetry not in ("auto", "off"):
            raise ValueError(f"contact.symmetry={self.symmetry!r} is not one of ['auto', 'off']")
        check_range("contact.mu", self.mu, 0.0, 5.0)
        # below ~1e-13 the Newton residual meets round-off and can never be reached
        check_range("contact.tolerance", self.tolerance, 1e-13, 1e-3)
        check_range("contact.max_iterations", self.max_iterations, 1, 10_000)


@dataclass(frozen=True)
class MeshSettings:
    """Element size where contact can occur and far from it [mm], element order; fine zone radius (auto if None).

    ``volumetric``: "standard" (lambda tr(eps)^2 per element; P1 locks above nu ~ 0.49, P2 partly) or
    "nodal_average" (P1 only: average-nodal-pressure tets, locking-free for nu -> 0.5; fem.elasticity).
    """

    size_contact: float = 0.15
    size_far: float = 4.0
    order: int = 1
    fine_radius: float | None = None
    grading: float = 0.5
    size_base: float | None = None    # element size on the sensor plane [mm] (curved gels; None: size_far)
    volumetric: str = "standard"

    def __post_init__(self):
        check_positive("mesh.size_contact", self.size_contact, "mm")
        check_positive("mesh.size_far", self.size_far, "mm")
        if self.order not in (1, 2):
            raise ValueError(f"mesh.order={self.order!r} is not one of [1, 2]")
        if self.volumetric not in VOLUMETRIC_FORMULATIONS:
            raise ValueError(f"mesh.volumetric={self.volumetric!r} is not one of {sorted(VOLUMETRIC_FORMULATIONS)}")
        if self.volumetric == "nodal_average" and self.order != 1:
            raise ValueError(f"mesh.volumetric={self.volumetric!r} needs mesh.order=1 (P1 tets), got "
                             f"mesh.order={self.order}; use mesh.volumetric='standard' with P2")
        if self.fine_radius is not None:
            check_positive("mesh.fine_radius", self.fine_radius, "mm")
        if self.size_base is not None:
            check_positive("mesh.size_base", self.size_base, "mm")
        check_positive("mesh.grading", self.grading)


@dataclass(frozen=True)
class Load:
    """One stage of the load path; each value is one increment.

    press: ``force`` [N] or ``depth`` [mm]; shear: ``force`` [N] or ``shift`` [mm] along ``direction``;
    twist: ``torque`` [N mm] or ``angle`` [rad] about +z through the body centre.
    """

    kind: LoadKind
    control: str                      # "force" (force, torque) or "displacement" (depth, shift, angle)
    values: tuple[float, ...]
    direction: tuple[float, float] = (1.0, 0.0)

    def __post_init__(self):
        if self.control not in ("force", "displacement"):
            raise ValueError(f"load control={self.control!r} is not one of ['displacement', 'force']")
        if not self.values:
            raise ValueError(f"{self.kind.value} load has an empty list of values")
        for value in self.values:
            if self.kind == LoadKind.PRESS:
                check_positive(f"press {'force' if self.control == 'force' else 'depth'}", value,
                               "N" if self.control == "force" else "mm")
            else:
                check_range(f"{self.kind.value} value", value, -math.inf, math.inf)
        norm = math.hypot(*self.direction)
        if self.kind == LoadKind.SHEAR and not (math.isfinite(norm) and norm > 0):
            raise ValueError(f"shear direction={self.direction!r} must be a non-zero [x, y]")


_LOAD_KEYS = {
    LoadKind.PRESS: {"force": "force", "depth": "displacement"},
    LoadKind.SHEAR: {"force": "force", "shift": "displacement"},
    LoadKind.TWIST: {"torque": "force", "angle": "displacement"},
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
        if not self.loads:
            raise ValueError("scene has no [[load]]: give at least one press")
        if self.loads[0].kind != LoadKind.PRESS:
            raise ValueError(f"the first load must be a press, not {self.loads[0].kind.value!r}")

    @property
    def mirror_symmetric(self) -> bool:
        """True when gel, body and every load are symmetric about the plane y = 0 (press, shear along x)."""
        return (self.gel.shape == "block" and self.body.center[1] == 0.0 and all(
            load.kind == LoadKind.PRESS or (load.kind == LoadKind.SHEAR and load.direction[1] == 0.0)
            for load in self.loads))

    @property
    def has_tangential_load(self) -> bool:
        return any(load.kind != LoadKind.PRESS for load in self.loads)


def _build(cls, table: dict, section: str):
    """Dataclass ``cls`` from a TOML table, rejecting unknown keys by name."""
    if not isinstance(table, dict):
        raise ValueError(f"[{section}] must be a table, got {type(table).__name__}")
    known = {f.name for f in fields(cls)}
    unknown = sorted(set(table) - known)
    if unknown:
        raise ValueError(f"unknown key(s) {unknown} in [{section}]; allowed: {sorted(known)}")
    values = {}
    for key, value in table.items():
        if isinstance(value, list):
            value = tuple(value)
        values[key] = value
    try:
        return cls(**values)
    except TypeError as error:
        raise ValueError(f"[{section}]: {error}") from None


def _load_from_table(table: dict, index: int) -> Load:
    where = f"load #{index + 1}"
    if not isinstance(table, dict) or "kind" not in table:
        raise ValueError(f"{where} needs a 'kind' (one of {[k.value for k in LoadKind]})")
    try:
        kind = LoadKind(table["kind"])
    except ValueError:
        raise ValueError(f"{where}: kind={table['kind']!r} is not one of {[k.value for k in LoadKind]}") from None
    allowed = dict(_LOAD_KEYS[kind])
    extra = {"kind"} | ({"direction"} if kind == LoadKind.SHEAR else set())
    unknown = sorted(set(table) - set(allowed) - extra)
    if unknown:
        raise ValueError(f"{where} ({kind.value}): unknown key(s) {unknown}; allowed: {sorted(set(allowed) | extra)}")
    given = [key for key in allowed if key in table]
    if len(given) != 1:
        raise ValueError(f"{where} ({kind.value}) needs exactly one of {sorted(allowed)}, got {given}")
    raw = table[given[0]]
    values = tuple(raw) if isinstance(raw, (list, tuple)) else (raw,)
    for value in values:
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError(f"{where} ({kind.value}): {given[0]} must be a number or a list of numbers, got {raw!r}")
    direction = tuple(float(v) for v in table.get("direction", (1.0, 0.0)))
    return Load(kind, allowed[given[0]], tuple(float(v) for v in values), direction)


def scene_from_dict(data: dict) -> Scene:
    """Scene from a parsed TOML document (see studies/scenes/hcm1.toml)."""
    sections = {"gel": GelSpec, "material": Material, "body": BodySpec, "contact": ContactSpec, "mesh": MeshSettings}
    unknown = sorted(set(data) - set(sections) - {"name", "load"})
    if unknown:
        raise ValueError(f"unknown top-level key(s) {unknown}; allowed: {sorted(set(sections) | {'name', 'load'})}")
    for required in ("gel", "material", "body", "load"):
        if required not in data:
            raise ValueError(f"scene is missing [{required}]" if required != "load" else "scene is missing [[load]]")
    gel_table = data["gel"]
    if not isinstance(gel_table, dict):
        raise ValueError(f"[gel] must be a table, got {type(gel_table).__name__}")
    sections = {key: cls for key, cls in sections.items() if key != "gel"}
    parts = {key: _build(cls, data.get(key, {}), key) for key, cls in sections.items()}
    parts["gel"] = GelSpec(shape=gel_table.get("shape", "block"),
                           parameters=tuple(sorted((k, v) for k, v in gel_table.items() if k != "shape")))
    loads = data["load"]
    if not isinstance(loads, list):
        raise ValueError("'load' must be an array of tables: write [[load]]")
    return Scene(name=str(data.get("name", "scene")), loads=tuple(_load_from_table(t, i) for i, t in enumerate(loads)),
                 **parts)


def load_scene(path: str | Path) -> Scene:
    """Read a scene TOML file."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"scene file {str(path)!r} does not exist")
    with path.open("rb") as stream:
        try:
            data = tomllib.load(stream)
        except tomllib.TOMLDecodeError as error:
            raise ValueError(f"{path}: not valid TOML ({error})") from None
    return scene_from_dict(data)
