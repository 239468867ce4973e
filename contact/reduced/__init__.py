"""Reduced contact model of an array fingertip (3x3 hemispheres on a base layer) for the closed loop [mm, N, MPa].

Per bump: Hertz normal law and contact radius, Cattaneo-Mindlin shear, Lubkin twist, an elliptic combined friction
limit; per array: the normal split of a flat (possibly tilted) object, the rigid-motion kinematics of eq. 9, the
gross-slip limit in translation and rotation from the bumps' friction limits, and the base pressure that the sensor
model reads. Parameters default to the closed-form theory and are replaced by FEM-calibrated values later
(``ReducedParameters.to_dict`` / ``from_dict``, stored with the design).
"""

from ._bumps import (BumpResponse, bump_response, full_stick_stiffness, lubkin_stick_ratio, mindlin_displacement_ratio,
                     mindlin_load_ratio, normal_split, normalized_lubkin_torque, normalized_lubkin_twist)
from ._design import ArrayFingertipDesign, ReducedParameters
from ._model import BaseGrid, ContactState, ReducedFingertip, SlipMode

__all__ = ["ArrayFingertipDesign", "ReducedParameters", "ReducedFingertip", "ContactState", "SlipMode", "BaseGrid",
           "BumpResponse", "bump_response", "normal_split", "full_stick_stiffness", "mindlin_load_ratio",
           "mindlin_displacement_ratio", "normalized_lubkin_twist", "normalized_lubkin_torque", "lubkin_stick_ratio"]
