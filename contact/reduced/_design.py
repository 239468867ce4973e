"""Fingertip design (3x3 hemisphere array on a base layer) and the reduced-model parameters, with JSON round trips.

The parameters are what an FEM calibration replaces (below); ``ReducedParameters.from_design`` gives the closed-form
defaults (each field says which formula):

    normal law        P_i = k_n d_i^(3/2)              k_n = (4/3) E* sqrt(R)            (Hertz, rigid flat on a bump)
    contact radius    a_i = c_a P_i^(1/3)              c_a = (3 R / (4 E*))^(1/3)         (Hertz)
    tangential law    Q_i(delta) = mu P_i [1 - (1 - delta/delta_s)^(3/2)],  delta_s = 3 mu P_i / (4 G* a_i)
                      G* = 4 G / (2 - nu)                                                  (Cattaneo-Mindlin)
    twist law         Lubkin: theta = mu P_i / (G_t a_i^2) f(T_i / (mu P_i a_i)),  G_t = G   (Lubkin 1951)
    base pressure     per bump a Gaussian of standard deviation sigma carrying P_i, plus the pressure couple
                      M_i [N mm] that balances the bump's overturning moment (``_model.ReducedFingertip.
                      base_pressure``); the base's free side faces mirror both back into the footprint.
                      sigma = R / 2: the second moment of the bump's foot, a disc of radius R (its further
                      spread in the base layer is left to the FEM).
    pressure couple   M_i = h(P_i) Q_i + g P_i delta_i, the moment about the sensor plane of the bump's contact
                      loads. h: the tangential load acts at the bump top, H = R + t above the sensor plane; a flat
                      object holds the bump top level against the lean (the contact's rocking stiffness grows like
                      a_i^3 ~ P_i), which moves the contact's normal force back and shortens the arm from h_0 at
                      P_i -> 0 towards h_inf, the arm of a column whose top cannot turn (H / 2):
                      h(P_i) = h_inf + (h_0 - h_inf) / (1 + kappa P_i / (h_0 - h_inf)),  h'(0) = -kappa.
                      Closed form: h_0 = H, kappa = 0 (an isolated column on a rigid top load), h_inf = H / 2.
                      g P_i delta_i: the normal force acting at the displaced bump top (moment balance in the
                      deformed configuration); closed form g = 1.
                      The centre of bump i's own pressure (over the whole base) moves by M_i / P_i: it follows
                      the load ratio Q_i / P_i through h, the displacement only through g.
    damping           viscous time constant of the gel tau_d [s]: F += tau_d k_tangent rate (both directions)

FEM-calibrated values: ``ReducedFingertip.calibrated()`` reads ``contact/reduced/data/fingertip_3x3_calibrated.json``,
written by ``python -m studies reduced-calibration --write-package-data`` (``contact.reduced.calibration``) from the
FEM bench of figs. 6/9 (this default design, mu = 1, rigid plate, h = 0.3 mm): presses at 1-6 N, shears along x
at 2 N and along y at 6 N, shifts into full sliding at 1 and 2 N, torques at 4 N and a shear then torques at 1 N;
the file keeps the mesh, load paths, fit residuals and the error on held-out FEM paths. Against the closed forms
above the FEM gives k_n +16 % (no base settlement term), c_a -2 %, G* -41 % (bump bending and base shear),
G_t -29 %, and for the base pressure a wider kernel (sigma = 3.25 mm = 1.39 R / 2), an arm h_0 = 7.49 mm = 0.98 H
that falls at first by kappa = 1.36 mm per N of bump force (6.8 mm at the 6 N press, 5.9 mm at 2 N per bump), and
g = 0: in the small-strain FEM the contact loads act on the undeformed bump top, so the base pressure follows the
loads, not the displacement (its CoP stays put while a bump slides on; a free fit gives g = 0.26 +- 0.06, correlated
0.93 with kappa and 0.13 on another mesh: a trade between the two, not a displacement term). The closed loop
(controller.closed_loop.default_tip) runs on these calibrated parameters; ``from_design`` gives the closed forms.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, fields

import numpy as np

from fem.validation import check_integer, check_positive, check_range

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

    The base layer covers cols pitch x rows pitch (half a pitch beyond the outer bump centres, as the FEM bench's
    40 x 40 mm base under 3 x 3 bumps at 13.3 mm); the reduced model's base pressure lives on that footprint.

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
            # kept as a Python int: a numpy integer would not survive asdict + json.dumps (the design's record)
            object.__setattr__(self, name, check_integer(name, getattr(self, name), 1, 12))
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
    def bump_height(self) -> float:
        """Height H = R + t of a bump top above the sensor plane [mm]."""
        return self.bump_radius + self.base_thickness

    @property
    def footprint(self) -> tuple[float, float]:
        """Half widths (x, y) of the base layer [mm]: half a pitch beyond the outer bump centres (the FEM bench)."""
        return 0.5 * self.cols * self.pitch, 0.5 * self.rows * self.pitch

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
    kernel_width : float -- sigma, standard deviation of the Gaussian base-pressure kernel of a bump [mm].
    couple_arm : float -- h_0, arm of the pressure couple M_i = h(P_i) Q_i at vanishing bump force [mm].
    couple_arm_slope : float -- kappa = -dh/dP_i at P_i = 0 [mm/N], >= 0.
    couple_arm_limit : float -- h_inf, the arm at large bump force [mm], below couple_arm when kappa > 0.
    displacement_gain : float -- g in M_i += g P_i delta_i [-], in [-2, 2].
    damping_time : float -- viscous time constant of the gel tau_d [s] (closed loop only).
    source : str -- where the values come from ("closed_form" or "fem:<calibration tag>").
    """

    normal_stiffness: float
    radius_coefficient: float
    tangential_modulus: float
    torsional_modulus: float
    kernel_width: float
    couple_arm: float
    couple_arm_slope: float = 0.0
    couple_arm_limit: float = 0.0
    displacement_gain: float = 1.0
    damping_time: float = 0.005
    source: str = "closed_form"

    def __post_init__(self):
        check_positive("normal_stiffness", self.normal_stiffness, "N/mm^1.5")
        check_positive("radius_coefficient", self.radius_coefficient, "mm/N^(1/3)")
        check_positive("tangential_modulus", self.tangential_modulus, "MPa")
        check_positive("torsional_modulus", self.torsional_modulus, "MPa")
        check_positive("kernel_width", self.kernel_width, "mm")
        check_positive("couple_arm", self.couple_arm, "mm")
        check_range("couple_arm_slope", self.couple_arm_slope, 0.0, math.inf, "mm/N", high_open=True)
        high = self.couple_arm if self.couple_arm_slope > 0.0 else math.inf
        check_range("couple_arm_limit", self.couple_arm_limit, 0.0, high,
                    "mm (below couple_arm when couple_arm_slope > 0)", high_open=True)
        check_range("displacement_gain", self.displacement_gain, -2.0, 2.0)
        check_range("damping_time", self.damping_time, 0.0, 1.0, "s")
        if not isinstance(self.source, str) or not self.source:
            raise ValueError(f"source={self.source!r} must be a non-empty string")

    @classmethod
    def from_design(cls, design: ArrayFingertipDesign) -> "ReducedParameters":
        """Closed-form defaults: Hertz, Cattaneo-Mindlin and Lubkin for one bump (rigid object, elastic gel)."""
        nu = design.poissons_ratio
        effective = design.youngs_modulus / (1.0 - nu**2)                       # E* [MPa]
        shear = design.youngs_modulus / (2.0 * (1.0 + nu))                      # G [MPa]
        return cls(normal_stiffness=4.0 / 3.0 * effective * math.sqrt(design.bump_radius),
                   radius_coefficient=(3.0 * design.bump_radius / (4.0 * effective)) ** (1.0 / 3.0),
                   tangential_modulus=4.0 * shear / (2.0 - nu), torsional_modulus=shear,
                   kernel_width=0.5 * design.bump_radius, couple_arm=design.bump_height,
                   couple_arm_slope=0.0, couple_arm_limit=0.5 * design.bump_height, displacement_gain=1.0)

    def couple_arm_at(self, bump_force):
        """Arm h(P_i) [mm] of the pressure couple at bump forces P_i [N] (module docstring; array or float)."""
        force = np.maximum(bump_force, 0.0)
        if self.couple_arm_slope == 0.0:
            return np.full(np.shape(force), self.couple_arm)
        excess = self.couple_arm - self.couple_arm_limit
        return self.couple_arm_limit + excess / (1.0 + (self.couple_arm_slope / excess) * force)

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict) -> "ReducedParameters":
        return _from_dict(cls, data)
