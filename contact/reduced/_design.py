"""Fingertip design (3x3 hemisphere array on a base layer) and the reduced-model parameters, with JSON round trips.

The parameters are what an FEM calibration replaces (below); ``ReducedParameters.from_design`` gives the closed-form
defaults (each field says which formula):

    normal law        P_i = k_n d_i^(3/2)              k_n = (4/3) E* sqrt(R)            (Hertz, rigid flat on a bump)
    contact radius    a_i = c_a P_i^(1/3)              c_a = (3 R / (4 E*))^(1/3)         (Hertz)
    tangential law    Q_i(delta) = mu P_i [1 - (1 - delta/delta_s)^(3/2)],  delta_s = 3 mu P_i / (4 G* a_i)
                      G* = 4 G / (2 - nu)                                                  (Cattaneo-Mindlin)
    twist law         Lubkin: theta = mu P_i / (G_t a_i^2) f(T_i / (mu P_i a_i)),  G_t = G   (Lubkin 1951)
    base pressure     kernel p ~ (1 - r^2/w^2) for r < w,  w = sqrt(a_i^2 + s^2),  s = R (the load enters the base
                      through the bump's foot of radius R; its spread in the base layer is left to the FEM)
    CoP shift         kernel centre = bump centre + g_cop delta_i + h Q_i / P_i (at most half a pitch),
                      g_cop = 1: the base pressure follows the bump's contact (the paper's premise, sec. IV-A);
                      h = 0 by default. h is the overturning-moment term: the tangential load Q_i acts at the bump
                      top, R + t above the sensor plane, and moment balance of an isolated bump column moves the
                      centre of pressure by Q_i (R + t) / P_i. That term measures the load ratio, not the
                      displacement (it does not know mu), and a continuous base shares it with the neighbours; the
                      FEM bench (fig9: CoP moves 7.7 times the plate shift at 2 N; isolated column: 25) must decide
                      between g_cop and h - both are calibration parameters.
    damping           viscous time constant of the gel tau_d [s]: F += tau_d k_tangent rate (both directions)

FEM-calibrated values: ``ReducedFingertip.calibrated()`` (or ``load_calibrated()``) reads
``contact/reduced/data/fingertip_3x3_calibrated.json``, written by ``python -m studies reduced-calibration
--write-package-data`` (``contact.reduced.calibration``) from the FEM bench of figs. 6/9 (this default design, mu = 1,
rigid plate, h = 0.3 mm): a press at 1.5-5 N, plate shifts at 2 and 5 N and a plate twist at 2 N; the file keeps the
mesh, load paths, fit residuals and the error on held-out FEM paths. Against the closed forms above the FEM gives
k_n +14 % (the plate approach grows like P^0.64, no base settlement), c_a +1.5 %, G* -44 % (bump bending and base
shear), G_t -22 %, s = 7.9 mm (the base pressure is wider than half a pitch), and for the CoP g ~ 0, h = 5.2 mm: the
base CoP follows the overturning moment h Q_i / P_i, not the displacement (told apart by the two normal forces; at one
force the two terms are collinear). The closed loop (controller.closed_loop.default_tip) runs on these calibrated
parameters; ``from_design`` gives the closed forms.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

import numpy as np

from fem.validation import check_positive, check_range

__all__ = ["ArrayFingertipDesign", "ReducedParameters"]

FOOTPRINT = 40.0          # mm, the paper's square fingertip (sec. IV-B)


def _from_dict(cls, data: dict):
    """Dataclass from a plain dict; unknown keys raise ValueError naming them."""
    unknown = set(data) - {f.name for f in fields(cls)}
    if unknown:
        raise ValueError(f"unknown {cls.__name__} keys {sorted(unknown)}")
    return cls(**data)


@dataclass(frozen=True)
class ArrayFingertipDesign:
    """rows x cols elastic hemispheres on a base layer bonded to the sensor (paper Fig. 5), in mm and MPa.

    Attributes
    ----------
    rows, cols : int -- bumps along the sensor's y and x axes (1 to 12).
    bump_radius : float -- hemisphere radius R [mm], > 0.
    pitch : float -- centre distance of neighbouring bumps [mm], > 2 R (no overlap).
    base_thickness : float -- gel between the bump feet and the sensor plane [mm], > 0.
    youngs_modulus : float -- E of the gel [MPa], > 0.
    poissons_ratio : float -- nu of the gel [-], in (-1, 0.5).
    """

    rows: int = 3
    cols: int = 3
    bump_radius: float = 0.35 * FOOTPRINT / 3.0
    pitch: float = FOOTPRINT / 3.0
    base_thickness: float = 3.0
    youngs_modulus: float = 0.3
    poissons_ratio: float = 0.45

    def __post_init__(self):
        for name in ("rows", "cols"):
            value = getattr(self, name)
            if int(value) != value or not 1 <= value <= 12:
                raise ValueError(f"{name}={value!r} must be an integer in [1, 12]")
        check_positive("bump_radius", self.bump_radius, "mm")
        check_range("pitch", self.pitch, 2.0 * self.bump_radius, math.inf, "mm (pitch > 2 bump_radius)", True, True)
        check_positive("base_thickness", self.base_thickness, "mm")
        check_positive("youngs_modulus", self.youngs_modulus, "MPa")
        check_range("poissons_ratio", self.poissons_ratio, -1.0, 0.5, low_open=True, high_open=True)

    @property
    def bump_count(self) -> int:
        return int(self.rows * self.cols)

    @property
    def bump_centres(self) -> np.ndarray:
        """Bump centres (k, 2) [mm] on the sensor plane, row-major (y slowest), centred on the origin."""
        x = (np.arange(self.cols) - 0.5 * (self.cols - 1)) * self.pitch
        y = (np.arange(self.rows) - 0.5 * (self.rows - 1)) * self.pitch
        grid_x, grid_y = np.meshgrid(x, y)
        return np.stack([grid_x.ravel(), grid_y.ravel()], axis=1)

    @property
    def half_extent(self) -> float:
        """Half side of the square that holds every bump foot [mm]."""
        return 0.5 * (max(self.rows, self.cols) - 1) * self.pitch + self.bump_radius

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "ArrayFingertipDesign":
        return _from_dict(cls, data)


@dataclass(frozen=True)
class ReducedParameters:
    """Per-bump laws of the reduced model (module docstring); defaults via ``from_design`` (closed form).

    Attributes
    ----------
    normal_stiffness : float -- k_n in P_i = k_n d_i^(3/2) [N/mm^1.5].
    radius_coefficient : float -- c_a in a_i = c_a P_i^(1/3) [mm/N^(1/3)].
    tangential_modulus : float -- G* of the Mindlin law, full-stick stiffness 2 G* a_i [MPa].
    torsional_modulus : float -- G_t of the Lubkin twist law, full-stick stiffness 16 G_t a_i^3 / 3 [MPa].
    kernel_spread : float -- s in the pressure-kernel radius w = sqrt(a_i^2 + s^2) [mm].
    cop_gain : float -- kernel-centre shift per bump shear displacement [-].
    moment_arm : float -- h, kernel-centre shift per load ratio Q_i / P_i [mm].
    damping_time : float -- viscous time constant of the gel tau_d [s] (closed loop only).
    source : str -- where the values come from ("closed_form" or a calibration tag).
    """

    normal_stiffness: float
    radius_coefficient: float
    tangential_modulus: float
    torsional_modulus: float
    kernel_spread: float
    moment_arm: float = 0.0
    cop_gain: float = 1.0
    damping_time: float = 0.005
    source: str = "closed_form"

    def __post_init__(self):
        check_positive("normal_stiffness", self.normal_stiffness, "N/mm^1.5")
        check_positive("radius_coefficient", self.radius_coefficient, "mm/N^(1/3)")
        check_positive("tangential_modulus", self.tangential_modulus, "MPa")
        check_positive("torsional_modulus", self.torsional_modulus, "MPa")
        check_positive("kernel_spread", self.kernel_spread, "mm")
        check_positive("cop_gain", self.cop_gain)
        check_range("moment_arm", self.moment_arm, 0.0, math.inf, "mm", high_open=True)
        check_range("damping_time", self.damping_time, 0.0, 1.0, "s")

    @classmethod
    def from_design(cls, design: ArrayFingertipDesign) -> "ReducedParameters":
        """Closed-form defaults: Hertz, Cattaneo-Mindlin and Lubkin for one bump (rigid object, elastic gel)."""
        nu = design.poissons_ratio
        effective = design.youngs_modulus / (1.0 - nu**2)                       # E* [MPa]
        shear = design.youngs_modulus / (2.0 * (1.0 + nu))                      # G [MPa]
        return cls(normal_stiffness=4.0 / 3.0 * effective * math.sqrt(design.bump_radius),
                   radius_coefficient=(3.0 * design.bump_radius / (4.0 * effective)) ** (1.0 / 3.0),
                   tangential_modulus=4.0 * shear / (2.0 - nu), torsional_modulus=shear,
                   kernel_spread=design.bump_radius)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "ReducedParameters":
        return _from_dict(cls, data)
