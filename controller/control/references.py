"""Grasp phases and the reference generator: target shear displacements from the phase (paper Fig. 7).

Why the reference may scale with the grasp force. For a power-law fingertip C r^n (Hertz: n = 2) the contact radius
is a ~ F_N^(1/(n+1)) (paper eq. 10). At a fixed load ratio the displacements at which a contact slips grow with F_N:

    translational (Cattaneo-Mindlin, docs/theory.md, sec. 4.4): u_x = mu (E*/G*) [d(a) - d(c)],  d ~ a^n ~ F_N^(n/(n+1))
    rotational (Lubkin, Hertz, docs/theory.md, sec. 6.3): theta = (mu F_N/(G a^2)) f(T/(mu F_N a)) ~ F_N^((n-1)/(n+1))

so a reference u_ref(F) = u_ref0 (F / F_0)^q with q = n/(n+1) (translation) and q = (n-1)/(n+1) (twist in rad)
keeps Q/(mu F_N) and T/(mu F_N a) at the values they have at u_ref0 and F_0, i.e. a constant stick ratio and a grasp
force a constant factor above the slip limit at every load. A fixed reference (q = 0, ``scale_with_force=False``,
the paper's choice) regulates u_x ~ Q / a(F_N) (paper eq. 12) and needs F_N ~ Q^(n+1): the margin grows with load.
Both need u_ref0 below the gross-slip displacement at the lowest friction expected; mu itself is never used.
"""

from __future__ import annotations

import enum
import math
from dataclasses import dataclass

from fem.validation import check_positive, check_range

__all__ = ["GraspPhase", "ReferenceParameters", "ReferenceGenerator"]


class GraspPhase(enum.Enum):
    """Task phase set by the grasp sequencer."""

    APPROACH = "approach"     # fingers close on the object; no shear control, small constant force
    GRASP = "grasp"           # force ramps until two bump contacts are seen, then shear control
    LIFT = "lift"             # shear control (the load grows)
    HOLD = "hold"             # shear control
    PLACE = "place"           # shear control (the table takes the load; force falls to the minimum)
    RELEASE = "release"       # reversed law: force falls when the shear displacements change; no minimum


@dataclass(frozen=True)
class ReferenceParameters:
    """Target shear displacements, as seen by the controller.

    Attributes
    ----------
    translational_reference : float -- target |u_x| at ``reference_force`` [mm], > 0.
    rotational_reference : float -- target |theta| (twist angle, not arc length) at ``reference_force`` [rad], > 0.
    reference_force : float -- grasp force F_0 at which the targets hold [N], > 0.
    profile_order : float -- n of the fingertip profile C r^n (2: hemisphere) [-], >= 1.
    scale_with_force : bool -- scale the targets with (F / F_0)^q (see module docstring); False: fixed targets.
    translational_force_exponent, rotational_force_exponent : float or None -- q_x, q_theta of the scaling
        u_ref ~ F^q when measured on the fingertip (e.g. an array, whose twist signal grows like F^(2/3) because its
        bumps translate); None: the single-profile values of the module docstring. Ignored without scaling.
    translational_slip_factor, rotational_slip_factor : float -- how much faster |u| / u_ref grows as F falls at
        the design point than in full stick (>= 1; 1 = full stick): the logarithmic slope of the partial-slip curve,
        x h'(x) / h(x) with h(x) = 1 - (1 - x)^(2/3) at x = Q/(mu P) (Mindlin), y f'(y) / f(y) with f the Lubkin
        twist at y = T/(mu P a). Dividing the inversion exponents by them keeps the loop gain at lambda at the
        design point (friction mu_low); at a higher mu the contact is nearer full stick and the loop slower.
    """

    translational_reference: float = 0.3
    rotational_reference: float = 0.1
    reference_force: float = 1.0
    profile_order: float = 2.0
    scale_with_force: bool = True
    translational_force_exponent: float | None = None
    rotational_force_exponent: float | None = None
    translational_slip_factor: float = 1.0
    rotational_slip_factor: float = 1.0

    def __post_init__(self):
        check_positive("translational_reference", self.translational_reference, "mm")
        check_positive("rotational_reference", self.rotational_reference, "rad")
        check_positive("reference_force", self.reference_force, "N")
        check_range("profile_order", self.profile_order, 1.0, math.inf, high_open=True)
        for name in ("translational_force_exponent", "rotational_force_exponent"):
            if getattr(self, name) is not None:
                check_range(name, getattr(self, name), 0.0, 2.0)
        check_range("translational_slip_factor", self.translational_slip_factor, 1.0, math.inf, high_open=True)
        check_range("rotational_slip_factor", self.rotational_slip_factor, 1.0, math.inf, high_open=True)

    @property
    def force_exponents(self) -> tuple[float, float]:
        """(q_x, q_theta): reference ~ F^q; the measured exponents or (n/(n+1), (n-1)/(n+1)) if scaled, else (0, 0)."""
        if not self.scale_with_force:
            return 0.0, 0.0
        n = self.profile_order
        q_x, q_theta = self.translational_force_exponent, self.rotational_force_exponent
        return (n / (n + 1.0) if q_x is None else q_x, (n - 1.0) / (n + 1.0) if q_theta is None else q_theta)

    @property
    def inversion_exponents(self) -> tuple[float, float]:
        """(p_x, p_theta) with F* = F (|u| / u_ref(F))^p the force that brings |u| to u_ref at a constant load.

        Full-stick laws (paper eq. 12, 14 with eq. 10): u_x ~ Q F^(-1/(n+1)), theta = u_theta / a ~ T F^(-3/(n+1)),
        so |u| / u_ref(F) ~ F^-(alpha + q) with alpha = 1/(n+1) or 3/(n+1), and p = 1 / (alpha + q):
        (1, (n+1)/(n+2)) = (1, 3/4) with scaling, (n+1, (n+1)/3) = (3, 1) without, for n = 2; each divided by its
        slip factor.
        """
        n = self.profile_order
        q_x, q_theta = self.force_exponents
        return (1.0 / ((1.0 / (n + 1.0) + q_x) * self.translational_slip_factor),
                1.0 / ((3.0 / (n + 1.0) + q_theta) * self.rotational_slip_factor))


class ReferenceGenerator:
    """Target shear displacements for a phase and the current grasp force.

    ``references(phase, force)`` returns (u_x_ref [mm], theta_ref [rad]), or None in APPROACH and RELEASE, where
    the shear displacements are not regulated (RELEASE uses the values latched when it starts).
    """

    _REGULATED = frozenset({GraspPhase.GRASP, GraspPhase.LIFT, GraspPhase.HOLD, GraspPhase.PLACE})

    def __init__(self, parameters: ReferenceParameters):
        self.parameters = parameters

    def references(self, phase: GraspPhase, force: float):
        """(u_x_ref [mm], theta_ref [rad]) at grasp force ``force`` [N] (> 0), or None if not regulated."""
        if GraspPhase(phase) not in self._REGULATED:
            return None
        p = self.parameters
        scale = check_positive("force", force, "N") / p.reference_force
        q_x, q_theta = p.force_exponents
        return p.translational_reference * scale**q_x, p.rotational_reference * scale**q_theta
