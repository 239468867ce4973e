"""The range of the shipped calibration: the per-bump normal forces its FEM paths covered, and how wide the contact
gets there against the small-strain envelope measured with a finite-strain gel (``contact.envelope``).

The calibrated fingertip (``fingertip_3x3_calibrated.json``) was fitted on plate presses of 1-6 N over its nine
bumps and checked on held-out paths up to 10 N: per bump 0.11-0.67 N fitted, 1.1 N checked. The closed loop's bumps
carry about 1 N in the settled holds and up to 2.6 N at the peaks (docs/finite_strain.md): the settled hold is at the
edge of the checked range, the peaks are 2.4 times beyond it. ``check_bump_forces`` names what a bump force leaves.
"""

from __future__ import annotations

import numpy as np

__all__ = ["calibrated_bump_forces", "check_bump_forces"]


def _largest_press(cases) -> float:
    return max((max(load["values"]) for case in cases for load in case["loads"] if load["kind"] == "press"),
               default=0.0)


def calibrated_bump_forces(stored) -> tuple[float, float]:
    """Largest per-bump normal force [N] of the fitted FEM paths and of the held-out ones of a ``StoredCalibration``
    (the plate's press shared by the bumps: the presses are centred)."""
    count = stored.design.rows * stored.design.cols
    provenance = stored.provenance
    return (_largest_press(provenance["fem_cases"]) / count,
            _largest_press(provenance.get("held_out", {}).get("cases", [])) / count)


def check_bump_forces(bump_force, stored=None) -> list[str]:
    """Notes for the largest of the per-bump normal forces ``bump_force`` [N] that leaves the calibration's fitted or
    checked range, or (contact radius c_a P^(1/3) against the bump radius) the small-strain envelope's press bounds.
    ``stored``: the calibration (default the shipped one)."""
    from contact.envelope import SMALL_STRAIN_ENVELOPE

    from ._store import load_calibration

    stored = stored or load_calibration()
    largest = float(np.max(bump_force))
    fitted, checked = calibrated_bump_forces(stored)
    notes = []
    if largest > checked:
        notes.append(f"bump force {largest:.3g} N beyond the calibration's held-out FEM paths (to {checked:.3g} N per "
                     f"bump; fitted to {fitted:.3g} N): the reduced model extrapolates its FEM laws")
    elif largest > fitted:
        notes.append(f"bump force {largest:.3g} N beyond the calibration's fitted FEM paths (to {fitted:.3g} N per "
                     f"bump), within the held-out ones (to {checked:.3g} N)")
    width = stored.parameters.radius_coefficient * largest ** (1.0 / 3.0) / stored.design.bump_radius
    outside = [bound for bound in SMALL_STRAIN_ENVELOPE if bound.load == "press" and width > bound.contact_width]
    if outside:
        notes.append(f"bump force {largest:.3g} N: contact a/R = {width:.2f}, outside the small-strain envelope for "
                     + "; ".join(bound.describe() for bound in outside))
    return notes
