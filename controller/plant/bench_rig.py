"""The sensor bench of paper Fig. 8 on the plant: a flat plate presses, shears, shifts and twists a built fingertip
with known loads, and the bench records the array's readings (``controller.sensing.BenchRecord``).

The rig knows what it applies (its force gauge, its stages) and reads the array; it does not know the fingertip's
per-bump loads. Each state is held ``frames`` sensor frames (100 Hz) and the readings averaged, the node baselines
drifting on over the bench's time. The plate's friction is the bench surface's (``BENCH_FRICTION``), high enough
to carry every tangential load asked for.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from controller.sensing import BenchRecord

from .fingertip_plant import FingertipPlant

__all__ = ["BenchLoad", "BENCH_FRICTION", "run_bench", "rig_states"]

BENCH_FRICTION = 1.0          # -, the bench plate's friction on the gel (rubbed-in sandpaper)
FRAME_PERIOD = 0.01           # s, the array's frame period (100 Hz)


@dataclass(frozen=True)
class BenchLoad:
    """A bench state: ``total_force`` [N] (0: the plate lifted, the array at rest) and either, by force control,
    ``tangential_force`` (2,) [N] and ``torque`` [N mm], or, by displacement control, ``shift`` (2,) [mm] and
    ``angle`` [rad]; ``kind`` names the series; ``friction`` the plate's [-]."""

    kind: str
    total_force: float = 0.0
    tangential_force: tuple[float, float] = (0.0, 0.0)
    torque: float = 0.0
    shift: tuple[float, float] = (0.0, 0.0)
    angle: float = 0.0
    force_controlled: bool = True
    friction: float = BENCH_FRICTION


def rig_states(plant: FingertipPlant, load: BenchLoad) -> np.ndarray:
    """The plant's bump states (k, 4) under a bench load: P_i, Q_i,x, Q_i,y [N], spin torque [N mm]."""
    count = len(plant.mechanics.centres)
    if load.total_force <= 0.0:
        return np.zeros((count, 4))
    if load.force_controlled:
        state = plant.mechanics.load_state(load.total_force, load.tangential_force, load.torque, load.friction)
    else:
        state = plant.mechanics.displacement_state(load.total_force, load.shift, load.angle, load.friction)
    return np.column_stack([state.normal_force, state.bump_tangential_force, state.bump_torque])


def run_bench(plant: FingertipPlant, loads, frames: int = 20, seed: int = 0, finger: int = 0,
              start_time: float = 0.0) -> list[BenchRecord]:
    """Each of ``loads`` held ``frames`` frames on fingertip ``finger`` of ``plant``, in order; the mean readings
    with what the rig applied. Noise from ``seed``; the bench's clock starts at ``start_time`` [s]."""
    if int(frames) != frames or frames < 1:
        raise ValueError(f"frames={frames!r} must be an integer >= 1")
    rng = np.random.default_rng([seed, 0x42454E4348])                      # "BENCH": its own stream
    records, time = [], start_time
    for load in loads:
        states = np.broadcast_to(rig_states(plant, load), (frames,) + (len(plant.mechanics.centres), 4))
        times = time + FRAME_PERIOD * np.arange(frames)
        readings = np.stack([plant.readings(states[index], rng, finger, times[index])[0]
                             for index in range(frames)])
        time += FRAME_PERIOD * frames
        records.append(BenchRecord(load.kind, load.total_force, readings.mean(axis=0), frames,
                                   tuple(load.tangential_force), load.torque, tuple(load.shift), load.angle,
                                   load.force_controlled))
    return records
