"""Where the small-strain model holds: per quantity, how far up the load the project's linear FEM stays within its
tolerance of a finite-strain gel (compressible Neo-Hookean: CalculiX's, or the project's own), as measured by
``python -m studies finite-strain`` (docs/finite_strain.md). ``contact.limits`` warns with it.

A bound holds a quantity up to a contact width a/R (the press: normal force, contact radius, the spread of the base
pressure) or, for the shear and twist quantities, up to a load ratio Q/(mu P) or T/(mu P a) at the contact width
where it was measured; a smaller contact strains less, so the same load ratio is taken to hold there, and a wider one
is untested; a load ratio of 0 means outside at every ratio measured. The shear and twist bounds are measured against
the project's own Neo-Hookean gel (``contact._finite_strain``: CalculiX's does not converge under friction), which
is validated against CalculiX's on the press only. A bound marked ``assumed`` was not measured at all: it holds as
far as the press quantities do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["SMALL_STRAIN_TOLERANCE", "EnvelopeBound", "SMALL_STRAIN_ENVELOPE", "outside_envelope"]

# How far the linear FEM may sit from a finite-strain gel before a quantity counts as outside the small-strain model:
# the tolerance the FEM is already held to against theory (docs/theory.md, sec. 11.8), so that finite strain is the
# larger error exactly when it exceeds what the FEM claims. Relative except the stick ratios (absolute, in c/a).
SMALL_STRAIN_TOLERANCE = {
    "normal_force": 0.03,            # Hertz P(d) to 3 %
    "contact_radius": 0.05,          # +-h/2 at h = a/10
    "tangential_compliance": 0.05,   # Mindlin shift to 5 %
    "stick_ratio": 0.05,             # +-0.5 h/a at h = a/10
    "base_cop_shift": 0.05,          # a shift read like the tangential one (the estimator's input)
    "base_pressure_spread": 0.05,    # the reduced model meets the FEM base pressure to 3.8 % (cells) - 8.8 % (sensor)
    "torsional_compliance": 0.08,    # torsional stiffness 16 G a^3 / 3 to 8 %
    "stick_ratio_twist": 0.05,       # as under shear
}


@dataclass(frozen=True)
class EnvelopeBound:
    """quantity (a key of SMALL_STRAIN_TOLERANCE); load 'press', 'shear' or 'twist'; contact_width a/R up to which a
    press quantity holds, or at which a shear / twist quantity was measured; load_ratio Q/(mu P) or T/(mu P a) up to
    which it holds there (inf for the press); measured: where the numbers come from."""

    quantity: str
    load: str
    contact_width: float
    load_ratio: float = math.inf
    measured: str = ""
    assumed: bool = False     # not measured against finite strain: taken to hold as far as the press quantities do

    def describe(self) -> str:
        """The bound in words, e.g. 'stick ratio within 0.05 in c/a of a finite-strain gel up to ...'."""
        tolerance = SMALL_STRAIN_TOLERANCE[self.quantity]
        amount = f"{tolerance:g} in c/a" if self.quantity.startswith("stick_ratio") else f"{100 * tolerance:g} %"
        within = f"within {amount} of a finite-strain gel"
        if self.assumed:
            return (f"{self.quantity.replace('_', ' ')} not measured against a finite-strain gel, taken to hold up to "
                    f"a/R = {self.contact_width:.2f} as the press does")
        if self.load == "press":
            return f"{self.quantity.replace('_', ' ')} {within} up to a/R = {self.contact_width:.2f}"
        ratio = "Q/(mu P)" if self.load == "shear" else "T/(mu P a)"
        if self.load_ratio == 0.0:
            return (f"{self.quantity.replace('_', ' ')} not {within} at any {ratio} measured (a/R = "
                    f"{self.contact_width:.2f})")
        return (f"{self.quantity.replace('_', ' ')} {within} up to {ratio} = {self.load_ratio:.2f} at a/R = "
                f"{self.contact_width:.2f}")


_RUN = "python -m studies finite-strain --quick, CalculiX 2.20"
_GETFEM = "bump_{0} and its peak against GetFEM's Neo-Hookean gel (contact.getfem), finite-strain quick, CalculiX 2.20"
_OWN = ("bump_{0} and its peak against the project's Neo-Hookean gel (contact._finite_strain, validated on the "
        "press), finite-strain quick, CalculiX 2.20")
# measured by the run named above (its summary's ``differs_from_contact_envelope`` is empty when this table matches
# it): the bump's normal force at equal depth leaves 3 % between a/R = 0.52 (1.5 N, -3.0 %) and 0.58 (2.0 N, -6.3 %;
# -9.6 % at 2.6 N, a/R = 0.63), the layer's holds to the largest press (+1.5 % at a/R = 0.64); the bump's contact
# radius leaves 5 % at a/R = 0.58 (+5.1 %); the spread of the base pressure stays within 1.2 % to a/R = 0.63.
# Shear and twist against GetFEM's Neo-Hookean gel on the FEM's mesh (CalculiX's diverges when friction comes on;
# the project's own Neo-Hookean gel meets GetFEM's within 1.1 % in tangential compliance, 0.4 % in the base
# pressure's centre and 1.0 % in torsional compliance to T/(mu P a) = 0.43-0.46, 7.5 % at 0.52 near gross slip), held
# at the depths of 1.5 N (a/R = 0.52) and 2.6 N (0.63), the tighter of the two: the tangential compliance to Q/(mu P)
# = 0.51 (-7.9 % at 0.64; 0.77 at 1.5 N); the base pressure's centre is 22-39 % short at every load ratio measured
# and the torsional compliance 16-36 % long to T/(mu P a) = 0.50 (the normal force's moment on the sheared contact,
# the bulged contact's lever arms: docs/finite_strain.md, sec. 2.5). The stick ratios against the project's own gel
# (GetFEM's nodal reading sits an element ring short, 0.04-0.09 in c/a at moderate load): to Q/(mu P) = 0.36 (0.68
# at 1.5 N), under twist to T/(mu P a) = 0.42 (0.52 at 1.5 N, -0.079 at 0.54)
SMALL_STRAIN_ENVELOPE: tuple[EnvelopeBound, ...] = (
    EnvelopeBound("normal_force", "press", 0.52, measured=f"bump_press, {_RUN}"),
    EnvelopeBound("contact_radius", "press", 0.52, measured=f"bump_press, {_RUN}"),
    EnvelopeBound("base_pressure_spread", "press", 0.63, measured=f"bump_press, {_RUN}"),
    EnvelopeBound("tangential_compliance", "shear", 0.63, 0.51, measured=_GETFEM.format("shear")),
    EnvelopeBound("stick_ratio", "shear", 0.63, 0.36, measured=_OWN.format("shear")),
    EnvelopeBound("base_cop_shift", "shear", 0.63, 0.0, measured=_GETFEM.format("shear")),
    EnvelopeBound("torsional_compliance", "twist", 0.63, 0.0, measured=_GETFEM.format("twist")),
    EnvelopeBound("stick_ratio_twist", "twist", 0.63, 0.42, measured=_OWN.format("twist")),
)


def outside_envelope(contact_width: float, load_ratio: float = 0.0, torque_ratio: float = 0.0,
                     loads=("press", "shear", "twist")) -> list[EnvelopeBound]:
    """The bounds a state leaves: a press quantity past its a/R; a shear or twist quantity (of the ``loads`` the path
    has) past its load ratio, or at a contact wider than the one it was measured at (untested)."""
    outside = []
    for bound in SMALL_STRAIN_ENVELOPE:
        if bound.load not in loads:
            continue
        ratio = load_ratio if bound.load == "shear" else torque_ratio
        if contact_width > bound.contact_width or (bound.load != "press" and ratio > bound.load_ratio):
            outside.append(bound)
    return outside
