"""Plant: what makes the data a controller reads - the gripper actuator and a closed-form Hertz fingertip; may import
controller.sensing, never estimation or control (docs/design.md, sec. 9: truth and belief apart)."""

from .actuator import ActuatorParameters, ActuatorPlant, contact_force
from .hertz_plant import ClosedFormContactPlant, HertzFingertip

__all__ = ["ActuatorParameters", "ActuatorPlant", "contact_force", "ClosedFormContactPlant", "HertzFingertip"]
