"""Reduced contact model of an array fingertip (3x3 hemispheres on a base layer) for the closed loop [mm, N, MPa].

Per bump: Hertz normal law and contact radius, Cattaneo-Mindlin shear, Lubkin twist, an elliptic combined friction
limit; per array: the normal split of a flat (possibly tilted) object, the rigid-motion kinematics of eq. 9, the
gross-slip limit in translation and rotation from the bumps' friction limits, and the base pressure that the sensor
model reads (``_base``: per bump a Gaussian bell carrying P_i and the pressure couple of its overturning moment,
mirrored at the base layer's edges). Parameters default to the closed-form theory; ``calibration`` fits them to FEM
paths of the same design, and ``load_calibrated()`` / ``ReducedFingertip.calibrated()`` read the FEM-calibrated file
shipped in ``contact/reduced/data`` (stored with its design and provenance, ``_store``); ``check_bump_forces`` says
when a bump force leaves the range that file was fitted and checked on, or the small-strain envelope (``_range``).
"""

from ._base import BaseGrid
from ._bumps import (BumpResponse, bump_law, bump_response, full_stick_stiffness, lubkin_stick_ratio,
                     mindlin_displacement_ratio, mindlin_load_ratio, normal_split, normalized_lubkin_torque,
                     normalized_lubkin_twist)
from ._design import ArrayFingertipDesign, ReducedParameters
from ._model import ContactState, ReducedFingertip, SlipMode, load_calibrated
from ._range import calibrated_bump_forces, check_bump_forces
from ._samples import PathSamples
from ._store import PACKAGED_CALIBRATION, StoredCalibration, load_calibration, parse_calibration, save_calibration

__all__ = ["ArrayFingertipDesign", "ReducedParameters", "ReducedFingertip", "ContactState", "SlipMode", "BaseGrid",
           "BumpResponse", "bump_response", "bump_law", "normal_split", "full_stick_stiffness", "mindlin_load_ratio",
           "mindlin_displacement_ratio", "normalized_lubkin_twist", "normalized_lubkin_torque", "lubkin_stick_ratio",
           "PathSamples", "StoredCalibration", "PACKAGED_CALIBRATION", "save_calibration", "load_calibration",
           "load_calibrated", "parse_calibration", "calibrated_bump_forces", "check_bump_forces"]
