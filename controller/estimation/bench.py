"""The FEM virtual bench of Figs. 6 and 9: an n x n hemisphere-array fingertip under a rigid plate, read by the sensor.

The FEM gives the pressure on the gel's base (the sensor plane); controller.sensing.sensor integrates it over the nodes'
cells and controller.estimation.estimator turns the readings into per-bump shear displacements and the eq. 9 rigid
transform
- the same code the closed loop runs on the reduced model.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FOOTPRINT", "BASE_THICKNESS", "BUMP_FILL", "YOUNGS_MODULUS", "POISSONS_RATIO", "FRICTION", "NORMAL_FORCE",
           "BENCH_SIZE_CONTACT", "BENCH_SIZE_BASE", "FRAMES_PER_STATE", "NOISE_GATE", "fingertip_gel", "bench_scene",
           "plate_shear_scene", "sensor_readings", "sensor_array", "bump_layout", "shifts_of", "estimator_settings",
           "averaged_cop_shifts", "base_pressure_field", "readings_operator"]

FOOTPRINT = 40.0          # mm, square fingertip (paper sec. IV-B)
BASE_THICKNESS = 3.0      # mm, gel layer between the bumps and the sensor
BUMP_FILL = 0.35          # bump radius / pitch (pitch = FOOTPRINT / n), so that the bumps never touch
YOUNGS_MODULUS = 0.3      # MPa, soft urethane gel
POISSONS_RATIO = 0.45
FRICTION = 1.0
NORMAL_FORCE = 2.0        # N, the plate's press, shared by all bumps
# mm at the bump tops, from the 3x3-fingertip P1 cases of `python -m studies convergence` (knee: cheapest size within
# 1.15x of the best stick-ratio error). On the fTetWild meshes used before, whose error scattered from one mesh draw to
# the next by up to +-0.03 at 0.9 and 0.6 mm, the knee of the worst case over three draws was 0.3 mm (0.4 mm sat at
# 0.055-0.061, 0.3 mm at 0.036-0.042: probably a model floor, a/R ~ 0.27 on bumps of finite height is not Hertz's
# half-space). Kept on the deterministic gmsh meshes: 0.9 mm would leave ~2 node spacings across a 4x4 bump's
# contact (a ~ 0.96 mm, fig6).
BENCH_SIZE_CONTACT = 0.3
BENCH_SIZE_BASE = 1.0     # mm on the sensor plane: a third of the 3 mm sensor pitch
FRAMES_PER_STATE = 10     # frames averaged per quasi-static state of a noisy sensor: 0.1 s at 100 Hz
NOISE_GATE = 3.0          # node readings below this many noise sigmas (of the averaged reading) count as zero


def fingertip_gel(n: int):
    """GelSpec of an n x n hemisphere array on the 40 x 40 mm base."""
    from contact.scene import GelSpec

    pitch = FOOTPRINT / n
    return GelSpec("array", (("rows", n), ("cols", n), ("bump_radius", BUMP_FILL * pitch), ("pitch", pitch),
                             ("base_width", FOOTPRINT), ("base_depth", FOOTPRINT),
                             ("base_thickness", BASE_THICKNESS)))


def bench_scene(n: int, kind: str, values, size_contact: float, size_base: float):
    """Plate pressed with NORMAL_FORCE, then shifted along x (kind 'shift', mm) or twisted (kind 'twist', rad)."""
    from contact.scene import BodySpec, ContactSpec, Load, LoadKind, Material, MeshSettings, Scene

    motion = Load(LoadKind.SHEAR, "displacement", tuple(values)) if kind == "shift" else \
        Load(LoadKind.TWIST, "displacement", tuple(values))
    return Scene(name=f"fingertip_{n}x{n}_{kind}", gel=fingertip_gel(n),
                 material=Material(YOUNGS_MODULUS, POISSONS_RATIO), body=BodySpec("plane"),
                 contact=ContactSpec(friction_coefficient=FRICTION),
                 mesh=MeshSettings(size_contact=size_contact, size_far=3.0, size_base=size_base),
                 loads=(Load(LoadKind.PRESS, "force", (NORMAL_FORCE,)), motion))


def plate_shear_scene(name: str, gel, normal_force: float, load_ratios, size_contact: float, size_far: float = 3.0,
                      fine_radius: float | None = None, youngs_modulus: float = 1.0, poissons_ratio: float = 0.45,
                      friction_coefficient: float = 0.5):
    """A rigid plate pressed on ``gel`` (a GelSpec) with ``normal_force`` [N] (frictionless), then sheared along +x
    by force control to Q/(mu P) = each of ``load_ratios`` (Figs. 3 and 4). Material E [MPa], nu; mesh sizes [mm]."""
    from contact.scene import BodySpec, ContactSpec, Load, LoadKind, Material, MeshSettings, Scene

    mu = friction_coefficient
    return Scene(name=name, gel=gel, material=Material(youngs_modulus, poissons_ratio), body=BodySpec("plane"),
                 contact=ContactSpec(friction_coefficient=mu, frictionless_press=True),
                 mesh=MeshSettings(size_contact=size_contact, size_far=size_far, fine_radius=fine_radius),
                 loads=(Load(LoadKind.PRESS, "force", (normal_force,)),
                        Load(LoadKind.SHEAR, "force", tuple(float(r * mu * normal_force) for r in load_ratios))))


def base_pressure_field(result):
    """The base pressure of every increment of an FEM result as a ``controller.sensing.PressureField`` (t frames)."""
    from controller.sensing.sensor import PressureField

    base = result.model.base
    pressure = np.stack([increment.base_pressure for increment in result.increments])      # (t, n_base)
    return PressureField(base.positions[:, :2], base.triangles, pressure)


def readings_operator(result, array):
    """The pad-force operator of ``array`` on the base mesh of ``result`` (``controller.sensing.cell_force_operator``):
    build it once per result and array, pass it to every frame and noise draw (its build costs ~20 frames)."""
    from controller.sensing.sensor import cell_force_operator

    base = result.model.base                       # the mesh alone: no need to stack every increment's pressure
    return cell_force_operator(base.positions[:, :2], base.triangles, array)


def sensor_readings(result, array, rng=None, operator=None) -> np.ndarray:
    """Readings (t, ny, nx) [N] of ``array`` for every increment of an FEM result (one frame per increment; the
    node model's noise, if any, drawn from ``rng``: a Generator, a seed or None); ``operator`` from
    ``readings_operator`` (built here when None)."""
    from controller.sensing.sensor import sample

    operator = readings_operator(result, array) if operator is None else operator
    return sample(base_pressure_field(result), array, rng=rng, operator=operator)


def sensor_array(pitch: float):
    """A node grid of the given pitch [mm] covering the 40 mm footprint."""
    from controller.sensing.sensor import SensorArray

    count = int(round(FOOTPRINT / pitch))
    return SensorArray(pitch=pitch, node_counts=(count, count))


def bump_layout(n: int):
    from controller.estimation.estimator import BumpLayout

    return BumpLayout.grid((n, n), FOOTPRINT / n)


def shifts_of(result, array, layout, settings=None, rng=None):
    """Readings, the reference (the pressed, unsheared first increment) and the per-bump CoP shifts (t, k, 2) [mm]
    against it; ``settings`` (EstimatorSettings) default, ``rng`` for the sensor's noise (``sensor_readings``)."""
    from controller.estimation.estimator import BumpReference, EstimatorSettings, estimate_slip

    settings = EstimatorSettings() if settings is None else settings
    readings = sensor_readings(result, array, rng)
    reference = BumpReference.from_readings(readings[:1], array, layout, settings)
    return readings, reference, estimate_slip(readings, array, layout, reference, settings=settings).cop_shift


def estimator_settings(array, frames: int = FRAMES_PER_STATE):
    """EstimatorSettings for ``array``: a noise gate at NOISE_GATE sigmas of a reading averaged over ``frames``
    frames when its node model has a noise floor, none otherwise (far from a bump the nodes read noise alone, and
    the centre of pressure would weigh it by its distance)."""
    from controller.estimation.estimator import EstimatorSettings

    if array.node is None or array.node.noise_floor == 0.0:
        return EstimatorSettings()
    return EstimatorSettings(node_floor=NOISE_GATE * array.node.force_noise() / np.sqrt(frames))


def averaged_cop_shifts(result, array, layout, seed=None, frames: int = FRAMES_PER_STATE, operator=None):
    """Per-bump CoP shifts (t, k, 2) [mm] against the first increment, from readings averaged over ``frames``
    frames per increment (one frame for a noise-free node model); the noise drawn from ``seed``; ``operator`` from
    ``readings_operator`` (built once here when None). Also returns the readings (t, ny, nx) [N], the reference
    and the estimator settings used."""
    from controller.estimation.estimator import BumpReference, estimate_slip
    from controller.sensing.sensor import sample

    rng = np.random.default_rng(seed)
    count = 1 if array.node is None or array.node.noise_floor == 0.0 else frames
    field = base_pressure_field(result)
    operator = readings_operator(result, array) if operator is None else operator
    readings = np.mean([sample(field, array, rng=rng, operator=operator) for _ in range(count)], axis=0)
    settings = estimator_settings(array, count)
    reference = BumpReference.from_readings(readings[:1], array, layout, settings)
    return estimate_slip(readings, array, layout, reference, settings=settings).cop_shift, readings, reference, \
        settings
