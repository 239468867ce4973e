"""Closed-form contact theory: Hertz, MDR / Cattaneo-Mindlin, Ciavarella-Jager, Lubkin torsion, the paper's equations.

Units: mm, N, MPa, N mm, rad. Every function accepts scalars or numpy arrays and raises ValueError naming
the argument for invalid input. Formulas, sources and the paper's corrections: docs/theory.md.
"""

from ._hertz import HertzContact, hertz, mindlin_shift
from ._mdr import mdr_modified_profile, mdr_normal_force, mdr_scale
from ._moduli import effective_modulus, shear_modulus, tangential_modulus
from ._paper_equations import (
    contact_radius_from_force,
    shear_displacement_rotational,
    shear_displacement_rotational_exact,
    shear_displacement_translational,
    shear_displacement_translational_exact,
    stick_ratio_from_rotation,
    stick_ratio_from_rotation_paper,
    stick_ratio_from_shear_displacement,
    stick_ratio_from_shear_displacement_paper,
)
from ._profiles import FLAT_CURVED_READINGS, AxisymmetricProfile, flat_curved, power_law
from ._stick_ratio import stick_ratio_profile, stick_ratio_translational
from ._torsion import (
    LUBKIN_SLIP_TORQUE_RATIO,
    TORSION_MODELS,
    full_slip_torque_ratio,
    lubkin_torque_twist,
    lubkin_twist,
    stick_ratio_torsion,
    torsion_torque_ratio,
)

__all__ = [
    "effective_modulus", "tangential_modulus", "shear_modulus",
    "HertzContact", "hertz", "mindlin_shift",
    "mdr_scale", "mdr_modified_profile", "mdr_normal_force",
    "AxisymmetricProfile", "power_law", "flat_curved", "FLAT_CURVED_READINGS",
    "stick_ratio_translational", "stick_ratio_profile",
    "TORSION_MODELS", "LUBKIN_SLIP_TORQUE_RATIO", "full_slip_torque_ratio", "torsion_torque_ratio",
    "stick_ratio_torsion", "lubkin_twist", "lubkin_torque_twist",
    "contact_radius_from_force", "shear_displacement_translational", "shear_displacement_translational_exact",
    "shear_displacement_rotational", "shear_displacement_rotational_exact",
    "stick_ratio_from_shear_displacement", "stick_ratio_from_shear_displacement_paper",
    "stick_ratio_from_rotation", "stick_ratio_from_rotation_paper",
]
