"""Plant: what makes the data a controller reads - the gripper actuator, the closed loop's fingertip as built (FEM
sensor plane, capacitive arrays, named errors against the design), its sensor bench, and a closed-form Hertz
fingertip; may import controller.sensing, never estimation or control (docs/design.md, sec. 9: truth and belief
apart)."""

from .actuator import ActuatorParameters, ActuatorPlant, contact_force
from .bench_rig import BenchLoad, rig_states, run_bench
from .fingertip_plant import FACTOR_LIMIT, FingertipPlant, PlantFactors, SensorPlane, plant_mechanics
from .hertz_plant import ClosedFormContactPlant, HertzFingertip

__all__ = ["ActuatorParameters", "ActuatorPlant", "contact_force", "ClosedFormContactPlant", "HertzFingertip",
           "FingertipPlant", "PlantFactors", "SensorPlane", "plant_mechanics", "BenchLoad", "rig_states", "run_bench",
           "FACTOR_LIMIT"]
