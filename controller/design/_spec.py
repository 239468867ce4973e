"""A fingertip design, the study it goes through, and its two FEM scenes (controller.design)."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
from dataclasses import dataclass
from enum import Enum

import numpy as np

from fem.validation import check_integer, check_number, check_positive, check_range

__all__ = ["SensorModel", "FingertipDesign", "DesignStudy", "design_id", "fem_key", "twist_angles", "design_scenes"]

MAX_YOUNGS_MODULUS = 1000.0     # MPa: a stiff rubber; the stability study's stiffest gel (past it a gel is not soft)
# a twist's angle in units of the outer bumps' Mindlin slip twist: at 10 those bumps have slid by several contact
# radii, outside the small-sliding contact model
MAX_TWIST_FRACTION = 10.0


class SensorModel(str, Enum):
    """The sensor a design is read with."""

    CAPACITIVE = "capacitive"     # sensing.capacitive: 0.5 mm gaps between pads (pad_fill), the documented node
    CELLS = "cells"               # the ideal array: whole cells, noise-free (pad_fill still sets the pads)


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

    bump_radius: float = 0.35 * 40.0 / 3.0      # exactly the Fig. 6 / 9 bench's fingertip (estimation.bench)
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
                check_integer(field.name, value, 1, 12)
            else:
                object.__setattr__(self, field.name, check_number(field.name, value))
        check_range("youngs_modulus", self.youngs_modulus, 0.0, MAX_YOUNGS_MODULUS, "MPa", low_open=True)
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
        from controller.sensing.capacitive import CapacitiveNode
        from controller.sensing.sensor import SensorArray

        counts = (max(1, round(self.base_width / self.sensor_pitch)),
                  max(1, round(self.base_depth / self.sensor_pitch)))
        node = CapacitiveNode() if SensorModel(model) is SensorModel.CAPACITIVE else None
        return SensorArray(pitch=self.sensor_pitch, node_counts=counts, fill_factor=self.pad_fill, node=node)

    def layout(self):
        """The estimator's BumpLayout: the bump centres."""
        from controller.estimation.estimator import BumpLayout

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
    closed_loop : also judge each design by its grasp (``_grasp``): calibrate it on its own FEM, build its plant and
        its estimator's bench, run Table I trials; False: the sensor-only sweep (fast screening).
    grasp_trials : randomised trials per Table I object, 1 to 1000.
    grasp_objects : the Table I objects tried (names of ``controller.closed_loop.TABLE_I_OBJECTS``).
    grasp_seed : seed of the trials' draws (default the held-out seed, ``HELD_OUT_SEED``).
    plant_spread : each build's plant factors uniform in +-plant_spread, in [0, 0.5].
    calibration_size_contact, calibration_size_base : element sizes of the design's calibration mesh [mm]
        (``contact.reduced.design_fit.FitPlan``).
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
    closed_loop: bool = False
    grasp_trials: int = 10
    grasp_objects: tuple[str, ...] = ("bottle_upright", "bottle_horizontal", "eclair")
    grasp_seed: int = 7919                  # controller.closed_loop.HELD_OUT_SEED (tests/test_design_grasp.py)
    plant_spread: float = 0.1
    calibration_size_contact: float = 0.7
    calibration_size_base: float = 1.0

    def __post_init__(self):
        for name in ("normal_force", "friction_coefficient", "size_contact", "size_base", "size_far"):
            object.__setattr__(self, name, check_positive(name, check_number(name, getattr(self, name))))
        check_range("friction_coefficient", self.friction_coefficient, 0.0, 5.0, low_open=True)
        for name, low in (("load_ratios", 3), ("twist_fractions", 1)):
            values = getattr(self, name)
            if isinstance(values, (str, bytes)) or not hasattr(values, "__len__"):
                raise ValueError(f"{name}={values!r} must be a list of numbers")
            values = tuple(check_number(f"{name}[{k}]", v) for k, v in enumerate(values))
            if not all(math.isfinite(value) for value in values):
                raise ValueError(f"{name}={list(values)} must hold finite numbers")
            if len(values) < low or any(b <= a for a, b in zip(values, values[1:])) or values[0] <= 0.0:
                raise ValueError(f"{name}={list(values)} must hold at least {low} increasing values > 0")
            object.__setattr__(self, name, values)
        if self.load_ratios[-1] >= 1.0:
            raise ValueError(f"load_ratios={list(self.load_ratios)} must stay below 1 (gross slip)")
        if self.twist_fractions[-1] > MAX_TWIST_FRACTION:
            raise ValueError(f"twist_fractions={list(self.twist_fractions)} must stay at or below "
                             f"{MAX_TWIST_FRACTION} (the outer bumps would slide by several contact radii)")
        try:
            object.__setattr__(self, "sensor", SensorModel(self.sensor))
        except ValueError:
            raise ValueError(f"sensor={self.sensor!r} is not one of {[m.value for m in SensorModel]}") from None
        check_integer("noise_draws", self.noise_draws, 1, 1000)
        check_integer("frames_per_state", self.frames_per_state, 1, 10_000)
        self._check_closed_loop()

    def _check_closed_loop(self) -> None:
        """The closed-loop settings, each refused by name with what is allowed."""
        from controller.closed_loop._trial import TABLE_I_OBJECTS
        from controller.plant import FACTOR_LIMIT

        if not isinstance(self.closed_loop, bool):
            raise ValueError(f"closed_loop={self.closed_loop!r} must be true or false")
        check_integer("grasp_trials", self.grasp_trials, 1, 1000)
        check_integer("grasp_seed", self.grasp_seed, 0, 2**63 - 1)
        objects = self.grasp_objects
        if isinstance(objects, (str, bytes)) or not hasattr(objects, "__len__") or not objects:
            raise ValueError(f"grasp_objects={objects!r} must be a non-empty list of names of "
                             f"{list(TABLE_I_OBJECTS)}")
        unknown = [name for name in objects if name not in TABLE_I_OBJECTS]
        if unknown or len(set(objects)) != len(objects):
            problem = f"unknown {unknown}" if unknown else "a name repeats"
            raise ValueError(f"grasp_objects={list(objects)!r}: {problem}; allowed: {list(TABLE_I_OBJECTS)}")
        object.__setattr__(self, "grasp_objects", tuple(objects))
        spread = check_number("plant_spread", self.plant_spread)
        check_range("plant_spread", spread, 0.0, FACTOR_LIMIT)
        object.__setattr__(self, "plant_spread", spread)
        for name in ("calibration_size_contact", "calibration_size_base"):
            object.__setattr__(self, name, check_positive(name, check_number(name, getattr(self, name)), "mm"))

    def document(self) -> dict:
        """The study as plain values; the closed-loop fields only when ``closed_loop`` (a sensor-only study keeps
        the document, and so the design ids, it had before they existed)."""
        document = {**dataclasses.asdict(self), "load_ratios": list(self.load_ratios),
                    "twist_fractions": list(self.twist_fractions), "sensor": self.sensor.value,
                    "grasp_objects": list(self.grasp_objects)}
        if not self.closed_loop:
            for name in CLOSED_LOOP_FIELDS:
                document.pop(name)
        return document


CLOSED_LOOP_FIELDS = ("closed_loop", "grasp_trials", "grasp_objects", "grasp_seed", "plant_spread",
                      "calibration_size_contact", "calibration_size_base")


def design_id(design: FingertipDesign, study: DesignStudy) -> str:
    """Id of a design in a study: a hash of both and of the package version (an upgrade evaluates it again)."""
    from contact.compliance import package_version

    text = json.dumps({"design": dataclasses.asdict(design), "study": study.document(), "version": package_version()},
                      sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def fem_key(design: FingertipDesign) -> tuple:
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
                  body=BodySpec("plane"), contact=ContactSpec(friction_coefficient=mu),
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
