"""Fig. 3's FEM stick ratio taken apart: the same flat + curved profile and load path on the half-space, coupled and
uncoupled (``contact.halfspace``), beside the FEM (nodal and recovered) and the closed form.

Each FEM point's nodal c/a differs from the closed form by four parts, each the step between two solutions that
differ in one thing only:

    measure     FEM nodal - FEM recovered                    the nodal-area count against the boundaries recovered
                                                             below the element size (``contact.recovery``)
    finite cap  FEM recovered - half-space coupled recovered the gel cap on its bonded base (and tetrahedra against
                                                             boundary cells), the same profile, physics and path
    coupling    half-space coupled - uncoupled (recovered)   the normal-tangential coupling at nu = 0.45 (Goodman)
    edge        half-space uncoupled recovered - closed form the rounded rim of the flat as the recovery reads it
                                                             (its quadratic fits meet the pressure's curvature jump
                                                             at r = b: 0.01-0.045 high at a/15 cells, where the nodal
                                                             count is within 0.005) and the closed form evaluated at
                                                             the b/a of the FEM's nodal contact area

so that their sum is FEM nodal - closed form, the study's ``error``. The half-space on cells of the FEM's size
(nodal) shows what that resolution alone loses at the rim (a - b is one element at b/a = 0.9).
"""

from __future__ import annotations

__all__ = ["HALF_SPACE_SPACING", "PARTS", "half_space_stick_ratios", "parts"]

HALF_SPACE_SPACING = 2.0 / 15.0   # mm = a/15 on the a = 2 mm contacts (a/20 costs 2.5 times as much)
PARTS = ("part_measure", "part_finite_cap", "part_coupling", "part_edge")


def half_space_stick_ratios(scene, spacing: float, coarse_spacing: float) -> dict:
    """Nodal and recovered c/a of each shear increment and the press's nodal contact radius [mm]: {'coupled':
    (radius, [nodal, ...], [recovered, ...]), 'uncoupled': ...} on cells of ``spacing`` [mm], 'coupled_coarse' on
    cells of ``coarse_spacing`` (the FEM's element size)."""
    from contact.halfspace import solve_halfspace

    found = {}
    for name, cell, coupled in (("coupled", spacing, True), ("uncoupled", spacing, False),
                                ("coupled_coarse", coarse_spacing, True)):
        increments = solve_halfspace(scene, cell, coupled=coupled)
        found[name] = (increments[0].contact_radius, [increment.stick_ratio for increment in increments[1:]],
                       [increment.recovered.stick_ratio for increment in increments[1:]])
    return found


def parts(fem: float, fem_recovered: float, coupled: float, uncoupled: float, theory: float) -> dict:
    """The four parts of FEM nodal - closed form (module docstring) [-]; the half-space values recovered."""
    return {"part_measure": fem - fem_recovered, "part_finite_cap": fem_recovered - coupled,
            "part_coupling": coupled - uncoupled, "part_edge": uncoupled - theory}
