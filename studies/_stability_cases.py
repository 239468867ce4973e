"""The stability study's cases: a sphere pressed on a block, then sheared or twisted, pushed to the edges of the
solver's range (nu -> 0.5 with P1, P2 and the locking-free P1 nodal-average option, modulus contrast, friction,
load ratio near gross slip, load size, mesh grading), and each result compared with the closed-form theory it
should follow.

Every case starts from ``BASE`` (sphere R = 10 mm on a 20 x 20 x 10 mm block, E = 1 MPa, nu = 0.45, mu = 0.5,
P = 0.2 N, frictionless press: no Spence pre-slip, so Cattaneo-Mindlin and Lubkin apply, docs/theory.md, sec. 8.3).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass

__all__ = ["StabilityCase", "CASES", "BASE", "build_scene", "compare_with_theory"]

BASE = {
    "name": "stability",
    "gel": {"shape": "block", "width": 20.0, "depth": 20.0, "thickness": 10.0},
    "material": {"E": 1.0, "nu": 0.45},
    "body": {"shape": "sphere", "radius": 10.0},
    "contact": {"friction_coefficient": 0.5, "frictionless_press": True},
    "mesh": {"size_contact": 0.15, "size_far": 4.0},
}
NORMAL_FORCE = 0.2          # N; Hertz a = 1.062 mm at E = 1 MPa, nu = 0.45, R = 10 mm
QUICK_SIZE_CONTACT = 0.3    # mm (CI size, about a/3.5)
SHEAR_STEP = 0.5            # a shear path to Q/(mu P) > 0.5 goes through 0.5 first
TWIST_STEP = 0.3            # a twist path to T/(mu P a) > 0.3 goes through 0.3 first
STEEP_LOAD_RATIO = 0.9      # c/a(Q) is steep beyond: compare the load ratio c/a implies (docs/theory.md, sec. 11.3)
STEEP_TORQUE_RATIO = 0.5


@dataclass(frozen=True)
class StabilityCase:
    """One case: ``changes`` (dotted scene key -> value) on BASE, the load kind and target ratio, what to expect.

    load: "shear" (target Q/(mu P)) or "twist" (target T/(mu P a_Hertz)), after the press.
    force_scale: the press force is NORMAL_FORCE * force_scale (the modulus cases scale it with E).
    """

    group: str
    label: str
    changes: tuple = ()
    load: str = "shear"
    ratio: float = 0.5
    force_scale: float = 1.0
    expect: str = "converged"          # or "error": the case must raise a clear error
    quick: bool = False


CASES = (
    # standard P1 and P2 lock as nu -> 0.5; P1 with average nodal pressure (mesh.volumetric) should not
    *(StabilityCase("poisson", f"nu={nu} {label}", (("material.nu", nu), ("mesh.order", order),
                                                    ("mesh.volumetric", volumetric)), quick=(nu == 0.4999))
      for nu in (0.49, 0.499, 0.4999)
      for label, order, volumetric in (("P1", 1, "standard"), ("P2", 2, "standard"),
                                       ("P1 nodal-average", 1, "nodal_average"))),
    StabilityCase("poisson", "nu=0.5 (excluded)", (("material.nu", 0.5),), expect="error", quick=True),
    *(StabilityCase("modulus", f"E={E:g} MPa, P={NORMAL_FORCE * E:g} N", (("material.E", E),), force_scale=E,
                    quick=E in (0.01, 1000.0))
      for E in (0.01, 0.1, 1.0, 10.0, 100.0, 1000.0)),
    *(StabilityCase("friction", f"mu={mu:g}", (("contact.friction_coefficient", mu),), quick=mu in (0.01, 2.0))
      for mu in (0.01, 0.1, 0.5, 1.0, 2.0)),
    *(StabilityCase("load ratio", f"Q/(mu P)={r:g}", ratio=r, quick=r == 0.99) for r in (0.9, 0.95, 0.99)),
    StabilityCase("load ratio", "Q/(mu P)=1 (gross slip)", ratio=1.0, expect="error", quick=True),
    *(StabilityCase("twist", f"T/(mu P a)={t:g}", load="twist", ratio=t, quick=t == 0.55) for t in (0.3, 0.5, 0.55)),
    StabilityCase("twist", "T/(mu P a)=0.62 (> 3 pi/16)", load="twist", ratio=0.62, expect="error"),
    # contact radius from about 1.5 elements (a = 0.25 a_ref) to a / R = 0.3 (a = 3 a_ref): P scales with a^3;
    # the large ones on the CI-size mesh (still a/h = 7 and 10; the fine zone grows with a, and so does the cost).
    # 1.5 elements is too few points for a contact radius: the solver must refuse it (ContactUnderResolved)
    *(StabilityCase("load size", f"a={s:g} a_ref (P={NORMAL_FORCE * s ** 3:.3g} N)", force_scale=s**3,
                    changes=(("mesh.size_contact", QUICK_SIZE_CONTACT),) if s > 1 else (), quick=s == 0.25,
                    expect="error" if s == 0.25 else "converged")
      for s in (0.25, 0.5, 2.0, 3.0)),
    StabilityCase("mesh", "grading=3", (("mesh.grading", 3.0),)),
    # a steep grading from a coarse far field: elements reaching into the fine zone must still be refined (the mesh
    # once refined by tet centroid only and answered on one contact node; now a corner inside the zone counts)
    StabilityCase("mesh", "grading=20, size_far=10", (("mesh.grading", 20.0), ("mesh.size_far", 10.0)), quick=True),
    StabilityCase("mesh", "fine_radius=0.5 mm < a=2.1 mm", (("mesh.fine_radius", 0.5),), force_scale=8.0,
                  expect="error", quick=True),
    # settings the Newton solver cannot meet: it must stop with its residual history, not return the last iterate
    StabilityCase("solver", "max_iterations=2", (("contact.max_iterations", 2),), expect="error"),
    StabilityCase("solver", "tolerance=1e-15 (round-off)", (("contact.tolerance", 1e-15),), expect="error"),
)


def hertz_radius(document: dict, force: float) -> float:
    """Hertz contact radius [mm] of the case's sphere, material and press force."""
    from contact.theory import effective_modulus, hertz

    material = document["material"]
    return float(hertz(force, document["body"]["radius"],
                       effective_modulus(material["E"], material["nu"])).contact_radius)


def build_scene(case: StabilityCase, quick: bool):
    """The case's scene document (BASE + changes + load path) and its press force [N]; raises ValueError for an
    invalid scene (that is the outcome of the cases that expect one)."""
    from studies._sweep_spec import set_dotted

    document = copy.deepcopy(BASE)
    if quick:
        document["mesh"]["size_contact"] = QUICK_SIZE_CONTACT
    for key, value in case.changes:
        set_dotted(document, key, value)
    force = NORMAL_FORCE * case.force_scale
    mu = document["contact"]["friction_coefficient"]
    loads = [{"kind": "press", "force": force}]
    if case.load == "shear":
        path = [SHEAR_STEP, case.ratio] if case.ratio > SHEAR_STEP else [case.ratio]
        loads.append({"kind": "shear", "force": [r * mu * force for r in path]})
    elif case.load == "twist":
        lever = mu * force * hertz_radius(document, force)
        path = [TWIST_STEP, case.ratio] if case.ratio > TWIST_STEP else [case.ratio]
        loads.append({"kind": "twist", "torque": [t * lever for t in path]})
    document["load"] = loads
    return document, force


def _inverse_tolerance(curve, stick_ratio: float, delta: float) -> float:
    """Tolerance on a load ratio implied by c/a: half the spread of ``curve`` over c/a +- delta."""
    low, high = max(stick_ratio - delta, 0.0), min(stick_ratio + delta, 1.0)
    return 0.5 * abs(float(curve(high)) - float(curve(low)))


def compare_with_theory(case: StabilityCase, document: dict, force: float, result) -> dict:
    """Columns quantity, fem, theory, error, tolerance of the case's last increment, and the press's contact radius
    against Hertz. Stick ratios are measured with the FEM's own a (docs/theory.md, sec. 11.2); the tolerance is the
    node-wise stick/slip classification, +-0.5 h/a in c/a (sec. 11.1), carried through the curve where it is steep."""
    from contact.theory import stick_ratio_torsion, stick_ratio_translational, torsion_torque_ratio

    press, last = result.increments[0], result.increments[-1]
    a_hertz = hertz_radius(document, force)
    row = {"contact_radius": press.contact_radius, "contact_radius_hertz": a_hertz,
           "contact_radius_error": press.contact_radius / a_hertz - 1.0, "stick_ratio": last.stick_ratio}
    delta = 0.5 * document["mesh"]["size_contact"] / last.contact_radius
    mu = document["contact"]["friction_coefficient"]
    if case.load == "shear":
        ratio = math.hypot(*last.tangential_force) / (mu * last.normal_force)
        if ratio <= STEEP_LOAD_RATIO:
            theory = float(stick_ratio_translational(ratio))
            row.update(quantity="stick_ratio vs Cattaneo-Mindlin", fem=last.stick_ratio, theory=theory,
                       tolerance=delta)
        else:
            def curve(k):
                return 1.0 - k**3
            row.update(quantity="Q/(mu P) implied by c/a (Cattaneo-Mindlin)", fem=curve(last.stick_ratio),
                       theory=ratio, tolerance=_inverse_tolerance(curve, last.stick_ratio, delta))
    elif case.load == "twist":
        ratio = abs(last.torque) / (mu * last.normal_force * last.contact_radius)
        if ratio <= STEEP_TORQUE_RATIO:
            row.update(quantity="stick_ratio vs Lubkin", fem=last.stick_ratio,
                       theory=float(stick_ratio_torsion(min(ratio, 1.0))), tolerance=delta)
        else:
            row.update(quantity="T/(mu P a) implied by c/a (Lubkin)", fem=float(torsion_torque_ratio(last.stick_ratio)),
                       theory=ratio, tolerance=_inverse_tolerance(torsion_torque_ratio, last.stick_ratio, delta))
    else:
        raise ValueError(f"load={case.load!r} is not one of ['shear', 'twist']")
    row["error"] = row["fem"] - row["theory"]
    return row
