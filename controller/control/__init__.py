"""Control: the grasp-force laws (displacement targets, incipient slip), their references and filters, and the
acceleration control with its disturbance observer; may import controller.sensing and controller.estimation."""

from .acceleration_control import (AccelerationControlParameters, AccelerationController, DisturbanceObserver,
                                   ForceFeedback)
from .filters import FirstOrderLowPass, sample_period
from .grasp_force_control import GraspForceController, GraspForceParameters
from .incipient_slip import IncipientSlipController, IncipientSlipParameters
from .references import GraspPhase, ReferenceGenerator, ReferenceParameters

__all__ = ["AccelerationControlParameters", "AccelerationController", "DisturbanceObserver", "ForceFeedback",
           "FirstOrderLowPass", "sample_period", "GraspForceController", "GraspForceParameters",
           "IncipientSlipController", "IncipientSlipParameters", "GraspPhase", "ReferenceGenerator",
           "ReferenceParameters"]
