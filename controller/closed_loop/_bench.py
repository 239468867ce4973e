"""The estimator's bench for the closed loop: the rig (``controller.plant.bench_rig``) on a nominal build of the
fingertip - never a trial's own, perturbed one - and what the estimator keeps of it.

On the FEM plane the sensor model is fitted to the bench's readings (``controller.estimation.fit_sensor_belief``:
presses at 1-32 N (the range the grip is driven over) and shears of 0.3 and 0.6 of the force along x and y, 20 averaged
frames each, rest records for the offsets); the records of the paper's estimator (unsheared presses at 40 forces for the
CoP reference, small shifts for its gain) and of the displacement-target law's design are kept for each trial's own
noise gate. On the MODEL plane (the known world) the estimator's model is the reduced model itself and the records are
noise-free, as in earlier rounds. Computed once per plane, design and array in a process (a few seconds).

The bench is of a design: by default the shipped 3x3 fingertip on the paper's array; ``model`` (a ``PlantModel``,
any design calibrated on its own FEM) and ``array`` (the design's sensor) make it the bench of another design, whose
nominal build the rig loads. The estimator still sees only what the rig applied and the readings; the bench keeps
the key of its rig (``EstimatorBench.rig``), by which the displacement law's design pairs are run on the same rig.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, replace

import numpy as np

from controller.estimation import BumpLayout
from controller.estimation.sensor_model import SensorBelief, fit_sensor_belief, sensor_operator
from controller.plant.bench_rig import BenchLoad, run_bench
from controller.plant import PlantModel, nominal_model
from controller.plant.fingertip_plant import FingertipPlant, PlantFactors, SensorPlane
from controller.sensing import SensorArray

__all__ = ["EstimatorBench", "estimator_bench", "bench_array", "tared_chain", "BENCH_SEED", "BENCH_NOISE",
           "BENCH_FRAMES", "SMALL_SHIFTS", "REFERENCE_FORCES"]

BENCH_SEED = 8                  # the bench fingertip's own node draws and noise (no trial uses this build)
BENCH_NOISE = 0.001             # N rms per node at small pressure: the array type the trials use
BENCH_FRAMES = 20               # frames averaged per bench state (0.2 s at 100 Hz)
REST_RECORDS = 5
FIT_FORCES = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)          # N on the whole fingertip: the drive's range (to 30 N)
FIT_RATIOS = (0.3, 0.6)                                # Q / P of the fit's shears (the bench plate has mu = 1)
REFERENCE_FORCES = tuple(np.geomspace(0.1, 60.0, 40))  # N: the unsheared CoP table of the paper's estimator
SMALL_SHIFTS = (0.0, 0.01, 0.02)                       # mm along x at REFERENCE_FORCE: its scalar CoP gain
REFERENCE_FORCE = 5.0                                  # N


@dataclass(frozen=True, eq=False)
class EstimatorBench:
    """What the estimator takes from its bench: the sensor model (``belief``), the rest readings' offsets, the
    unsheared presses (``references``: forces (n,) [N], readings (n, n_nodes) [N]) and the small shifts (readings
    (3, n_nodes) [N]) of the paper's estimator, the plane it was made on and the key of its rig (``_RIGS``: the
    design and array the rig loaded; a name, not the plant)."""

    plane: SensorPlane
    belief: SensorBelief
    offset: np.ndarray
    reference_forces: np.ndarray
    reference_readings: np.ndarray
    shift_readings: np.ndarray
    rig: tuple = ()


# rig key -> (PlantModel, SensorArray or None): the benches run in this process, for their design pairs
_RIGS: dict = {}


def bench_array(array: SensorArray | None) -> SensorArray | None:
    """The array a bench is keyed by: a trial's array with its node's noise floor cleared (the bench sets its own
    noise, ``BENCH_NOISE``), so that trials of one design at any noise share one bench; None stays None."""
    if array is None or array.node is None:
        return array
    return replace(array, node=replace(array.node, noise_floor=0.0))


def _rig(model: PlantModel | None, array: SensorArray | None) -> tuple:
    model = nominal_model() if model is None else model
    if not isinstance(model, PlantModel):
        raise ValueError(f"model={model!r} must be a PlantModel")
    if array is not None and not isinstance(array, SensorArray):
        raise ValueError(f"array={array!r} must be a SensorArray")
    array = bench_array(array)
    key = (model.key, None if array is None else repr(array))
    _RIGS[key] = (model, array)
    return key


def _records(plant, loads, noise_free: bool):
    frames = 1 if noise_free else BENCH_FRAMES
    return run_bench(plant, loads, frames, seed=BENCH_SEED)


def estimator_bench(plane: SensorPlane = SensorPlane.FEM, model: PlantModel | None = None,
                    array: SensorArray | None = None) -> EstimatorBench:
    """The bench of the module docstring on ``plane``, of the design of ``model`` (default the shipped 3x3) read
    by ``array`` (default the paper's; its noise floor is the bench's own); cached per process."""
    return _estimator_bench(SensorPlane(plane), _rig(model, array))


@functools.lru_cache(maxsize=16)
def _estimator_bench(plane: SensorPlane, rig: tuple) -> EstimatorBench:
    model, array = _RIGS[rig]
    known = plane is SensorPlane.MODEL
    plant = FingertipPlant(PlantFactors(), array, noise=0.0 if known else BENCH_NOISE, seed=BENCH_SEED, plane=plane,
                           model=model)
    design, array = plant.mechanics.design, plant.array
    layout = BumpLayout.grid((design.cols, design.rows), design.pitch)
    rest = [BenchLoad("rest") for _ in range(REST_RECORDS)]
    fit = [BenchLoad("press", force) for force in FIT_FORCES]
    fit += [BenchLoad("shear", force, tuple(ratio * force * np.asarray(axis)))
            for force in FIT_FORCES for ratio in FIT_RATIOS for axis in ((1.0, 0.0), (0.0, 1.0))]
    references = [BenchLoad("press", force) for force in REFERENCE_FORCES]
    shifts = [BenchLoad("shift", REFERENCE_FORCE, shift=(shift, 0.0), force_controlled=False)
              for shift in SMALL_SHIFTS]
    records = _records(plant, rest + fit + references + shifts, known)
    offset = np.mean([record.readings.ravel() for record in records[:REST_RECORDS]], axis=0)
    if known:
        belief = _known_belief(plant, array, layout, offset)
    else:
        belief = fit_sensor_belief(records[:REST_RECORDS + len(fit)], design, array, layout)
    cut = REST_RECORDS + len(fit)
    return EstimatorBench(plane, belief, offset, np.array(REFERENCE_FORCES),
                          np.stack([r.readings.ravel() for r in records[cut:cut + len(references)]]),
                          np.stack([r.readings.ravel() for r in records[cut + len(references):]]), rig)


def _known_belief(plant, array, layout, offset) -> SensorBelief:
    """The known world's estimator: the reduced model's own kernel and couple arm (no fit; the world is it)."""
    tip, p = plant.mechanics, plant.mechanics.parameters
    operator, inverse, region = sensor_operator(tip, array, layout)
    return SensorBelief(tip.design, array, layout, p.kernel_width, p.couple_arm, p.couple_arm_slope,
                        p.couple_arm_limit, 1.0, operator, inverse, region, offset, 0.0,
                        {"records": 0, "note": "the known world: the reduced model is the plant's sensor plane"})


def design_pairs(plane: SensorPlane, friction: float, load_ratio: float, torque_ratio: float, force: float,
                 rig: tuple = ()) -> dict:
    """Readings (2, n_nodes) [N] of (unloaded, loaded) bench pairs for the displacement-target law's design
    (``SensingChain.design_references``): a shear of ``load_ratio`` of the slip load and a twist of
    ``torque_ratio`` of the slip torque on a plate of ``friction``, at ``force`` and 4 ``force``, and at +-1 % of
    ``force`` with the load held, on the rig of an ``EstimatorBench`` (default the shipped design's). Cached."""
    rig = rig or _rig(None, None)
    if rig not in _RIGS:
        raise ValueError(f"rig={rig!r} is not a bench of this process (EstimatorBench.rig)")
    return _design_pairs(SensorPlane(plane), float(friction), float(load_ratio), float(torque_ratio), float(force),
                         rig)


DESIGN_STEP = 0.01        # +-1 % force change for the displacement law's slip factors


@functools.lru_cache(maxsize=16)
def _design_pairs(plane, friction, load_ratio, torque_ratio, force, rig) -> dict:
    model, array = _RIGS[rig]
    known = plane is SensorPlane.MODEL
    plant = FingertipPlant(PlantFactors(), array, noise=0.0 if known else BENCH_NOISE, seed=BENCH_SEED, plane=plane,
                           model=model)
    count = len(plant.mechanics.centres)

    def pair(total, load, torque):
        bump_force = np.full(count, total / count)
        radius = plant.mechanics.parameters.radius_coefficient * np.cbrt(bump_force)
        slip_torque = plant.mechanics.slip_margin(bump_force, radius, friction, (0.0, 0.0), 1.0)[0]
        loads = [BenchLoad("design", total, friction=friction),
                 BenchLoad("design", total, (load * friction * total, 0.0), torque * slip_torque, friction=friction)]
        return np.stack([record.readings.ravel() for record in _records(plant, loads, known)])

    pairs = {("translation", 1.0): pair(force, load_ratio, 0.0), ("twist", 1.0): pair(force, 0.0, torque_ratio),
             ("translation", 4.0): pair(4.0 * force, load_ratio, 0.0),
             ("twist", 4.0): pair(4.0 * force, 0.0, torque_ratio)}
    for scale in (1 - DESIGN_STEP, 1 + DESIGN_STEP):
        pairs["translation_at_constant_load", scale] = pair(force * scale, load_ratio / scale, 0.0)
        pairs["twist_at_constant_load", scale] = pair(force * scale, 0.0, torque_ratio / scale)
    return pairs


# held-out bench states no fit saw (force control, mu = 1): other forces, a diagonal shear, twists, shear with twist,
# up to 24 N
HELD_OUT_LOADS = (BenchLoad("press", 3.0), BenchLoad("press", 12.0), BenchLoad("shear", 5.0, (1.5, 1.5)),
                  BenchLoad("shear", 10.0, (-4.0, 2.0)), BenchLoad("twist", 6.0, torque=30.0),
                  BenchLoad("twist", 12.0, torque=-50.0), BenchLoad("shear", 12.0, (-4.0, 2.0), -20.0),
                  BenchLoad("shear", 3.0, (0.0, -1.5), 8.0), BenchLoad("shear", 24.0, (-6.0, 4.0), 40.0))


def tared_chain(plant: FingertipPlant, plane: SensorPlane = SensorPlane.FEM, model: PlantModel | None = None,
                array: SensorArray | None = None, seed: int = 0):
    """The estimator fitted on the bench of the design (``estimator_bench``), tared on ``REST_RECORDS`` rest records of
    ``plant`` (node noise from ``seed``): what reads a build on a bench once the estimator is calibrated."""
    from ._sensing import SensingChain

    chain = SensingChain(estimator_bench(plane, model, array))
    rest = run_bench(plant, [BenchLoad("rest") for _ in range(REST_RECORDS)], BENCH_FRAMES, seed=seed)
    chain.tare(np.stack([np.stack([r.readings.ravel()] * 2) for r in rest]))
    return chain


def belief_errors(plane: SensorPlane = SensorPlane.FEM, factors: PlantFactors = PlantFactors(), seed: int = 1,
                  model: PlantModel | None = None, array: SensorArray | None = None):
    """The estimator's per-bump errors on held-out bench states of a build with ``factors`` (default: nominal; its
    arrays the bench's own, build 0, on another day's noise, baselines and drift) of the design of ``model`` read by
    ``array`` (defaults: the shipped 3x3 on the paper's array), the estimator fitted on that design's bench:
    {"force": largest |P_hat / P - 1|, "ratio": largest |rho_hat - Q / P| [-], "ratio_relative": largest
    |rho_hat - rho| / |rho| where |rho| > 0.1}. The plant's truth is read here only to score the estimate (a study's
    question), never by the estimator."""
    from controller.plant.bench_rig import rig_states

    known = SensorPlane(plane) is SensorPlane.MODEL
    plant = FingertipPlant(factors, bench_array(array), noise=0.0 if known else BENCH_NOISE, seed=seed, plane=plane,
                           model=model)
    chain = tared_chain(plant, plane, model, array, seed=seed + 1)
    records = run_bench(plant, HELD_OUT_LOADS, BENCH_FRAMES, seed=seed + 2)
    force_error, ratio_error, relative = 0.0, 0.0, 0.0
    for load, record in zip(HELD_OUT_LOADS, records):
        truth = rig_states(plant, load)
        normal, ratio, _ = chain.bump_loads(record.readings.ravel())
        true_ratio = truth[:, 1:3] / truth[:, :1]
        force_error = max(force_error, float(np.abs(normal[0] / truth[:, 0] - 1.0).max()))
        difference = np.linalg.norm(ratio[0] - true_ratio, axis=1)
        ratio_error = max(ratio_error, float(difference.max()))
        size = np.linalg.norm(true_ratio, axis=1)
        if (size > 0.1).any():
            relative = max(relative, float((difference[size > 0.1] / size[size > 0.1]).max()))
    return {"force": force_error, "ratio": ratio_error, "ratio_relative": relative}
