"""The closed loop's fingertip as a real build: FEM-derived bump laws and sensor plane, a capacitive array with its
hardware spread, and named errors of the build against the nominal design (``PlantFactors``).

What it is made of (the truth side of docs/design.md, sec. 9; nothing here is handed to an estimator):

* mechanics: the FEM-calibrated bump laws of the design (``PlantModel``: by default the shipped 3x3 fingertip's
  packaged ``ReducedFingertip.calibrated()``; any design calibrated on its own FEM by ``PlantModel.from_fit``), with
  the build's gel stiffness and bump height;
* sensor plane: each bump's base pressure from the FEM of the design (``contact.reduced.base_response``: per-bump
  influence fields, a response surface in P_i, Q_i and the spin torque), with the build's kernel width and couple arm;
* array: the paper's 11 x 13 capacitive nodes at 3 mm (``capacitive_array``: pads with gaps, saturating curve,
  crosstalk, noise, 16-bit converter), each built array with its own node gains, offsets and drifting baselines
  (``CapacitiveNode.realize``), plus the build's extra node-gain error.

Per frame the compiled kernel ``_sensor_kernel.plant_readings`` turns both fingertips' bump states into readings.

``SensorPlane.MODEL`` builds the other world, the one earlier rounds ran in and kept as a baseline: the sensor
plane is the reduced model's Gaussian kernel and pressure couple (the estimator's own form, with the calibrated
parameters) read by ideal cells with Gaussian noise - a world the estimator knows exactly.

Plant factors (relative errors, 0 = the nominal design; each a first-order model of one thing a real build gets wrong):

========================  ========================================================================================
kernel_width              every bump's sensor-plane field stretched about the bump's centre by 1 + e (force kept):
                          a base layer that spreads the load more (or less) than the FEM's
couple_arm                every bump's response to its tangential load (the pressure couple) scaled by 1 + e
youngs_modulus            the gel's E times 1 + e: k_n, G*, G_t scale with it, the contact radius with (1 + e)^(-1/3)
bump_height               bumps taller by 1 + e: the couple's arm grows with the height (tangential fields x 1 + e)
                          and a taller column is softer in shear (G*, G_t / (1 + e))
node_gain                 each node's gain off by a further e z_n (z_n standard normal per node, e >= 0)
friction_anisotropy       friction mu (1 + e) along the sensor's x axis and mu (1 - e) along y (elliptic limit)
========================  ========================================================================================
"""

from __future__ import annotations

import enum
import functools
import math
from dataclasses import dataclass, fields, replace

import numpy as np

from controller.sensing import CapacitiveNode, SensorArray, capacitive_array, cell_force_operator
from controller.sensing._node_kernel import node_law
from fem.validation import check_range

from ._model import PlantModel, nominal_model

__all__ = ["PlantFactors", "FingertipPlant", "SensorPlane", "FACTOR_LIMIT", "STRETCH_LEVELS", "plant_mechanics"]

FACTOR_LIMIT = 0.5               # |e| of a plant factor: beyond half the nominal value the build is another design
# kernel-width stretches with precomputed pad-force tables; a factor between two levels interpolates linearly
# (the tables are smooth in the stretch: the pad integral of a stretched smooth field)
STRETCH_LEVELS = np.round(np.arange(-0.5, 0.5001, 0.05), 10)


class SensorPlane(str, enum.Enum):
    """What makes the plant's sensor-plane pressure."""

    FEM = "fem"            # the FEM's per-bump fields of the design, read by capacitive nodes (the default)
    MODEL = "model"        # the reduced model's kernel read by ideal cells: the world the estimator knows exactly


# the MODEL plane's couple arm h(P) tabulated at these bump forces [N] (linear in log P between them: the arm's
# curvature leaves < 1e-4 of it)
MODEL_SHEAR_LEVELS = np.geomspace(1e-3, 100.0, 81)


@dataclass(frozen=True)
class PlantFactors:
    """Relative errors of a build against the nominal design [-] (module docstring); 0 everywhere is nominal."""

    kernel_width: float = 0.0
    couple_arm: float = 0.0
    youngs_modulus: float = 0.0
    bump_height: float = 0.0
    node_gain: float = 0.0
    friction_anisotropy: float = 0.0

    def __post_init__(self):
        for item in fields(self):
            value = getattr(self, item.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"plant factor {item.name}={value!r} must be a number (a relative error, e.g. 0.1)")
            low = 0.0 if item.name == "node_gain" else -FACTOR_LIMIT
            check_range(f"plant factor {item.name}", float(value), low, FACTOR_LIMIT)
            object.__setattr__(self, item.name, float(value))

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(item.name for item in fields(cls))

    @classmethod
    def random(cls, rng, spread: float, names=None) -> "PlantFactors":
        """Each factor of ``names`` (default all) uniform in [-spread, spread] ([0, spread] for node_gain)."""
        # abs: -0.0 passes the range check, and numpy's uniform refuses the interval [0, -0.0]
        spread = abs(check_range("plant spread", spread, 0.0, FACTOR_LIMIT))
        chosen = cls.names() if names is None else tuple(names)
        unknown = sorted(set(chosen) - set(cls.names()))
        if unknown:
            raise ValueError(f"unknown plant factors {unknown}; allowed: {list(cls.names())}")
        values = {name: float(rng.uniform(0.0 if name == "node_gain" else -spread, spread)) for name in chosen}
        return cls(**values)

    @classmethod
    def parse(cls, text: str) -> "PlantFactors":
        """From 'name=value,name=value' (the command line), each value a relative error; ValueError names the
        item that is wrong."""
        values = {}
        if not any(part.strip() for part in str(text).split(",")):
            raise ValueError(f"plant factors {text!r}: expected name=value[,name=value ...] with names of "
                             f"{list(cls.names())} (the nominal plant: --plant-spread 0)")
        for item in filter(None, (part.strip() for part in str(text).split(","))):
            name, equals, value = item.partition("=")
            name = name.strip()
            if not equals or name not in cls.names():
                raise ValueError(f"plant factor {item!r}: expected name=value with a name of {list(cls.names())}")
            if name in values:
                raise ValueError(f"plant factor {name} is given twice ({text!r}): give each factor once")
            try:
                values[name] = float(value)
            except ValueError:
                raise ValueError(f"plant factor {name}={value.strip()!r} is not a number") from None
            if not math.isfinite(values[name]):
                raise ValueError(f"plant factor {name}={value.strip()!r} must be finite")
        return cls(**values)

    def nonzero(self) -> dict:
        return {name: getattr(self, name) for name in self.names() if getattr(self, name) != 0.0}


def plant_mechanics(factors: PlantFactors = PlantFactors(), model: PlantModel | None = None):
    """The build's bump laws: the FEM-calibrated ``ReducedFingertip`` of ``model`` (default the shipped 3x3,
    ``nominal_model()``) with the gel's E and the bumps' height of ``factors`` (k_n, G*, G_t and the contact radius;
    the module docstring's table)."""
    from contact.reduced import ReducedFingertip

    nominal = (nominal_model() if model is None else model).mechanics
    p = nominal.parameters
    e_modulus, e_height = factors.youngs_modulus, factors.bump_height
    return ReducedFingertip(nominal.design, replace(
        p, normal_stiffness=p.normal_stiffness * (1.0 + e_modulus),
        radius_coefficient=p.radius_coefficient * (1.0 + e_modulus) ** (-1.0 / 3.0),
        tangential_modulus=p.tangential_modulus * (1.0 + e_modulus) / (1.0 + e_height),
        torsional_modulus=p.torsional_modulus * (1.0 + e_modulus) / (1.0 + e_height), source=f"{p.source}+plant"))


def _array_key(array: SensorArray) -> tuple:
    return (array.pitch, array.node_counts, array.centre, array.fill_factor)


@functools.lru_cache(maxsize=64)
def _stretched_tables(model: PlantModel, array_key: tuple, stretch: float) -> dict:
    """Pad-force tables of the model's response with every bump's field stretched by 1 + ``stretch`` about its
    centre (the field's force kept): a field at nodes c + s (x - c) with values p / s^2 integrates to the same force
    over the stretched triangles."""
    response = model.response
    pitch, counts, centre, fill = array_key
    array = SensorArray(pitch=pitch, node_counts=counts, centre=centre, fill_factor=fill)
    scale = 1.0 + stretch
    tables = {"normal": [], "shear": [], "spin": []}
    for bump, centre_xy in enumerate(response.centres):
        positions = centre_xy + scale * (response.positions - centre_xy)
        operator = cell_force_operator(positions, response.triangles, array).toarray() / scale**2
        tables["normal"].append(np.einsum("rn,ln->lr", operator, response.normal_fields[bump]))
        tables["shear"].append(np.einsum("rn,lan->lar", operator, response.shear_fields[bump]))
        tables["spin"].append(operator @ response.spin_fields[bump])
    return {name: np.ascontiguousarray(np.stack(values)) for name, values in tables.items()}


class FingertipPlant:
    """Both fingertips of a build: mechanics, sensor-plane tables and the two arrays' nodes (module docstring).

    Parameters
    ----------
    factors : PlantFactors -- the build's errors against the nominal design.
    array : SensorArray, optional -- the array geometry and node model (default: ``capacitive_array()``, the
        paper's 11 x 13 nodes at 3 mm with the documented capacitive node).
    noise : float, optional -- rms node noise at small pressure [N] (sets the node's noise floor); None keeps the
        node's own.
    seed : int -- draws the arrays' baselines and drifts of the day and the build's node-gain error (node_gain).
    build : int -- draws the arrays' node gains: the physical pair of arrays (the bench calibrates build 0).
    plane : SensorPlane -- FEM (default) or MODEL (module docstring; the array is then ideal cells).
    model : PlantModel, optional -- the design's calibrated bump laws and FEM base response (default: the shipped
        3x3 fingertip, ``nominal_model()``; any design: ``PlantModel.from_fit``).
    """

    def __init__(self, factors: PlantFactors = PlantFactors(), array: SensorArray | None = None,
                 noise: float | None = None, seed: int = 0, plane: SensorPlane = SensorPlane.FEM, build: int = 0,
                 model: PlantModel | None = None):
        if not isinstance(factors, PlantFactors):
            raise ValueError(f"factors={factors!r} must be PlantFactors")
        if model is not None and not isinstance(model, PlantModel):
            raise ValueError(f"model={model!r} must be a PlantModel (e.g. PlantModel.from_fit(fit_fingertip(...)))")
        self.model = nominal_model() if model is None else model
        self.array_design = array             # the array as designed (None: the default), before noise and plane
        try:
            self.plane = SensorPlane(plane)
        except ValueError:
            raise ValueError(f"plane={plane!r} is not one of {[item.value for item in SensorPlane]}") from None
        if array is None:
            array = capacitive_array() if self.plane is SensorPlane.FEM else \
                SensorArray(node=CapacitiveNode.ideal())
        elif self.plane is SensorPlane.MODEL:
            array = replace(array, fill_factor=1.0, node=CapacitiveNode.ideal())
        if array.node is None:
            raise ValueError("the plant's array needs a node model (SensorArray.node: a CapacitiveNode)")
        node = array.node
        if noise is not None:
            check_range("noise", noise, 0.0, math.inf, "N", high_open=True)
            node = replace(node, noise_floor=noise * node.capacitance_per_area / node.dielectric_modulus)
            array = replace(array, node=node)
        self.factors, self.array, self.node = factors, array, node
        self.mechanics = plant_mechanics(factors, self.model)
        self.response = self.model.response
        # the build's arrays (their node gains) are one physical pair, calibrated on the bench as it is; the
        # baselines, their drift and the build's extra gain error (node_gain) are the day's: drawn from ``seed``
        built = [node.realize(array.shape, np.random.default_rng([build, finger, 0x4255494C44])) for finger in range(2)]
        rng = np.random.default_rng([seed, 0x504C414E54])
        today = [node.realize(array.shape, rng) for _ in range(2)]
        extra = 1.0 + factors.node_gain * rng.standard_normal((2,) + array.shape)
        self.gain = np.ascontiguousarray(np.stack([r.gain for r in built]) * extra)
        self.offset = np.ascontiguousarray(np.stack([r.offset for r in today]))
        self.drift = np.ascontiguousarray(np.stack([r.drift for r in today]))
        self.tables = self._tables() if self.plane is SensorPlane.FEM else self._model_tables()

    def _model_tables(self) -> dict:
        """Pad-force tables of the reduced model's kernel (the MODEL plane), with the build's kernel width and arm."""
        from controller.sensing import PressureField

        p = self.mechanics.parameters
        factors = self.factors
        tip = type(self.mechanics)(self.mechanics.design, replace(
            p, kernel_width=p.kernel_width * (1.0 + factors.kernel_width), displacement_gain=0.0))
        grid = tip.base_grid(1.0)
        field = PressureField.from_grid(grid.x, grid.y, np.zeros((len(grid.y), len(grid.x))))
        cells = cell_force_operator(field.positions, field.triangles, self.array)
        count = len(tip.centres)
        zeros = np.zeros((count, 2))
        normal, couple = np.zeros((count, 1, cells.shape[0])), np.zeros((count, 2, cells.shape[0]))
        arm0 = float(tip.parameters.couple_arm_at(0.0))
        for bump in range(count):
            force = np.zeros(count)
            force[bump] = 1.0
            normal[bump, 0] = cells @ tip.base_pressure(grid, force, np.zeros(count), zeros).ravel()
            for axis in range(2):
                tangential = zeros.copy()
                tangential[bump, axis] = 1.0 / arm0
                couple[bump, axis] = cells @ tip.base_pressure(grid, np.zeros(count), np.zeros(count), zeros,
                                                               tangential).ravel()
        arm = (1.0 + factors.couple_arm) * (1.0 + factors.bump_height) * tip.parameters.couple_arm_at(
            MODEL_SHEAR_LEVELS)                                                               # (M,) [mm]
        return {"normal_levels": np.ones(1), "normal": np.ascontiguousarray(normal),
                "shear_levels": MODEL_SHEAR_LEVELS.copy(),
                "shear": np.ascontiguousarray(arm[None, :, None, None] * couple[:, None]),
                "spin": np.zeros((count, cells.shape[0]))}

    def _tables(self) -> dict:
        """Pad-force tables of the build's sensor plane: normal (k, L, n), shear (k, M, 2, n), spin (k, n)."""
        key = _array_key(self.array)
        stretch = self.factors.kernel_width
        index = int(np.clip(np.searchsorted(STRETCH_LEVELS, stretch, side="right") - 1, 0, STRETCH_LEVELS.size - 2))
        low, high = STRETCH_LEVELS[index], STRETCH_LEVELS[index + 1]
        weight = (stretch - low) / (high - low)
        below = _stretched_tables(self.model, key, float(low))
        above = _stretched_tables(self.model, key, float(high)) if weight > 0.0 else below
        arm = (1.0 + self.factors.couple_arm) * (1.0 + self.factors.bump_height)
        tables = {name: (1.0 - weight) * below[name] + weight * above[name] for name in below}
        tables["shear"] = arm * tables["shear"]
        tables["normal_levels"] = self.response.normal_levels
        tables["shear_levels"] = self.response.shear_levels
        return {name: np.ascontiguousarray(value, dtype=float) for name, value in tables.items()}

    @property
    def friction_anisotropy(self) -> float:
        return self.factors.friction_anisotropy

    def pad_forces(self, states) -> np.ndarray:
        """Pad forces (m, ny, nx) [N] of one fingertip for bump states (m, k, 4): P_i, Q_i,x, Q_i,y, S_i."""
        from ._sensor_kernel import pad_forces

        states = np.asarray(states, dtype=float)
        states = np.ascontiguousarray(states[None] if states.ndim == 2 else states)
        out = np.empty((len(states),) + self.array.shape)
        t = self.tables
        for index, state in enumerate(states):
            pad_forces(state, t["normal_levels"], t["normal"], t["shear_levels"], t["shear"], t["spin"],
                       out[index].reshape(-1))
        return out

    def readings(self, states, rng, finger: int = 0, time: float = 0.0) -> np.ndarray:
        """Readings (m, ny, nx) [N] of fingertip ``finger``'s array for bump states (m, k, 4) at ``time`` [s]
        (its baseline drifts), noise from ``rng``."""
        from controller.sensing import NodeRealization

        realization = NodeRealization(self.gain[finger], self.offset[finger], self.drift[finger])
        return self.node.read(self.pad_forces(states), self.array.pad_area, rng, realization, time)

    def frame_noise(self, rng, frames: int) -> np.ndarray:
        """Standard-normal node noise (frames, 2, ny, nx) of the next ``frames`` frames of both arrays, drawn in
        frame order (the node's noise floor scales it); zeros for a noise-free node."""
        shape = (frames, 2) + self.array.shape
        return rng.standard_normal(shape) if self.node.noise_floor > 0.0 else np.zeros(shape)

    def frame_readings(self, states, time: float, noise) -> np.ndarray:
        """Both arrays' readings (2, ny, nx) [N] of bump states (2, k, 4) at ``time`` [s] with standard-normal
        ``noise`` (2, ny, nx): the compiled kernel of the closed loop's frames."""
        from ._sensor_kernel import plant_readings

        shape = self.array.shape
        readings = np.empty((2,) + shape)
        plant_readings(np.ascontiguousarray(states, dtype=float), *self.compiled_inputs(), float(time),
                       np.ascontiguousarray(noise, dtype=float), np.empty(shape), np.empty(shape), readings)
        return readings

    def compiled_inputs(self) -> tuple:
        """The constants ``_sensor_kernel.plant_readings`` takes, in its order."""
        t = self.tables
        return (t["normal_levels"], t["normal"], t["shear_levels"], t["shear"], t["spin"],
                float(self.array.pad_area), node_law(self.node), self.gain, self.offset, self.drift,
                float(self.node.noise_floor))

