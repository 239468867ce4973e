"""The report of ``python -m studies all``: each figure beside the claim it reproduces, its error, time and verdict.

``CLAIMS`` holds, per study, the claim (the paper's words, or the design's target), what is measured, and the rule
that turns the study's returned summary and its CSV into a verdict: ``reproduced``, ``partly`` or ``not
reproduced``, with the numbers that decided it; ``unrated`` where no rule applies (the study's own verdict is
quoted). ``write_report`` writes ``index.html`` and ``REPORT.md`` into the output folder, next to the figures.
"""

from __future__ import annotations

import csv
import html
import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

REPRODUCED, PARTLY, NOT_REPRODUCED, UNRATED = "reproduced", "partly", "not reproduced", "unrated"
THEORY_ROUND_OFF = 1e-6       # closed form vs quadrature of the same theory: anything above is a bug, not physics


@dataclass(frozen=True)
class Claim:
    """What a study reproduces and how its verdict is decided.

    source : str -- where the claim comes from (paper figure/section, or docs/design.md)
    claim : str -- the claim, in the source's terms
    measure : str -- what the study measures against what, and the rule in words
    rule : callable (summary: dict, rows: list[dict]) -> (verdict, why) -- rows are the study's CSV (floats parsed)
    note : str -- free-text explanation shown with the verdict
    """

    source: str
    claim: str
    measure: str
    rule: Callable[[dict, list], tuple[str, str]]
    note: str = ""


# ---------------------------------------------------------------------------------------------------------------
# rules: plain functions of (summary, csv rows) -> (verdict, why)


def _grade(passed: list[bool]) -> str:
    return REPRODUCED if all(passed) else PARTLY if any(passed) else NOT_REPRODUCED


def _study_verdict(summary: dict, rows: list) -> tuple[str, str]:
    """No rule of our own: take the study's ``verdict`` when it starts with a verdict word, else quote it."""
    text = str(summary.get("verdict", "")).strip()
    for word in (NOT_REPRODUCED, "not", REPRODUCED, PARTLY):
        if text.lower().startswith(word):
            return (NOT_REPRODUCED if word == "not" else word), text
    return UNRATED, (f"the study's verdict: {text}" if text else "no rule for this study and no verdict returned")


def _theory_check(summary: dict) -> tuple[bool, str]:
    error = summary.get("max_error")
    ok = error is not None and error <= THEORY_ROUND_OFF
    return ok, f"independent check {'agrees' if ok else 'DISAGREES'} to {_number(error)} (limit {THEORY_ROUND_OFF:g})"


def _rule_fig2b(summary, rows):
    checked, why = _theory_check(summary)
    near_slip = [r for r in rows if r.get("case", "").startswith("n=") and abs(r["load_ratio"] - 0.9) < 1e-9]
    stick = [r["stick_ratio"] for r in sorted(near_slip, key=lambda r: r["profile_order"])]
    steeper = len(stick) > 1 and all(b > a for a, b in zip(stick, stick[1:]))
    return _grade([checked, steeper]), (
        f"{why}; at Q/(mu P) = 0.9, c/a = {', '.join(f'{s:.2f}' for s in stick)} for n = 1 ... 8: "
        f"{'the higher the order, the more c/a stays up and drops suddenly at Q = mu P' if steeper else 'not ordered by n'}")


def _rule_fig3b(summary, rows):
    checked, why = _theory_check(summary)
    drops = {}
    for row in rows:
        if row["load_ratio"] < 1.0:
            drops[row["b_over_a"]] = row["stick_ratio"]            # rows ascend in load: the last one before slip
    # docs/theory.md, sec. 5.3: the drop height at Q = mu P equals b/a
    sudden = bool(drops) and all(height >= b_over_a - 0.01 for b_over_a, height in drops.items())
    return _grade([checked, sudden]), (
        f"{why}; just before Q = mu P, c/a = {', '.join(f'{h:.2f}' for h in drops.values())} for b/a = "
        f"{', '.join(f'{b:g}' for b in drops)}: the stick ratio {'drops from b/a to 0' if sudden else 'does not drop'}"
        f" at gross slip, the larger b/a the larger the sudden drop")


def _rule_torsion(summary, rows):
    checked, why = _theory_check(summary)
    paper = [r for r in rows if r["case"] == "paper" and r["torque_ratio"] <= r["full_slip_torque_ratio"]]
    worst = max(paper, key=lambda r: abs(r["gap_vs_lubkin"]), default=None)
    if worst is None:
        return NOT_REPRODUCED, f"{why}; no rows of the paper's model in torsion-theory.csv"
    close = abs(worst["gap_vs_lubkin"]) <= 0.05               # docs/theory.md, sec. 11.1: c/a tolerance of an FEM check
    exact_at_slip = next((r["stick_ratio_lubkin"] for r in paper if r["torque_ratio"] == r["full_slip_torque_ratio"]),
                         math.nan)
    return (REPRODUCED if checked and close else PARTLY if checked else NOT_REPRODUCED), (
        f"{why}; the paper's eq. 6 (corrected) falls monotonically to c/a = 0 like the exact solution, but slides at "
        f"T = {worst['full_slip_torque_ratio']:.3f} mu P a, where the exact contact still has c/a = "
        f"{exact_at_slip:.2f} (full slip only at 3 pi/16 = 0.589); largest gap {worst['gap_vs_lubkin']:+.2f} in c/a "
        f"at T/(mu P a) = {worst['torque_ratio']:.3f}")


def _fem_tolerance(rows, radius_key: str) -> float:
    """docs/theory.md, sec. 11.1: stick/slip is decided per node, so c/a is known to +-0.5 h/a (0.05 at h = a/10)."""
    return max(0.5 * r["element_size"] / r[radius_key] for r in rows)


FIG3_AGREEMENT = 0.05     # docs/theory.md, sec. 11.1: c/a at h = a/10 is known to +-0.05; the models should meet it
FIG3_JUDGED_LOAD = 0.9    # sec. 11.3: beyond, the flat face makes c/a a jump and the stick edge a fraction of h


def _rule_fig3(summary, rows):
    """The FEM against the physics it solves: the coupled half-space on the same profile and load path."""
    resolved = lambda r: r.get("edge_resolved") in (True, "True", 1.0)
    loaded = [r for r in rows if r["load_ratio"] <= FIG3_JUDGED_LOAD]
    judged = [r for r in loaded if resolved(r)]
    if not judged or "error_vs_coupled" not in judged[0]:
        return NOT_REPRODUCED, "fig3.csv has no half-space columns (error_vs_coupled, edge_resolved)"
    worst = max(judged, key=lambda r: abs(r["error_vs_coupled"]))
    agrees = abs(worst["error_vs_coupled"]) <= FIG3_AGREEMENT
    top_load = max(r["load_ratio"] for r in judged)
    at_top = sorted((r["b_over_a"], r["stick_ratio_fem_recovered"]) for r in rows if r["load_ratio"] == top_load)
    ordered = all(b[1] > a[1] for a, b in zip(at_top, at_top[1:]))
    names = {"part_measure": "nodal measure", "part_finite_cap": "finite cap on its base",
             "part_coupling": "coupling at nu = 0.45", "part_edge": "rounded edge as recovered"}
    largest = ", ".join(f"{name} {max((r[part] for r in loaded), key=abs):+.3f}" for part, name in names.items())
    coarse = [r for r in loaded if not resolved(r)]
    unresolved = ""
    if coarse:
        edge = max(coarse, key=lambda r: abs(r["error_vs_coupled"]))
        lost = edge["stick_ratio_halfspace_coupled_coarse"] - edge["stick_ratio_halfspace_coupled_nodal"]
        unresolved = (f" At b/a = {edge['b_over_a']:g} the curved annulus a - b = "
                      f"{(1 - edge['b_over_a']) * edge['contact_radius_theory']:.2f} mm spans fewer than two elements "
                      f"(h = {edge['element_size']:g} mm): the FEM sits {edge['error_vs_coupled']:+.3f} from the "
                      f"coupled half-space at Q/(mu P) = {edge['load_ratio']:g} (the half-space on cells of that size "
                      f"{lost:+.3f}); not judged, a finer mesh is needed there.")
    near_slip = [r for r in rows if r["load_ratio"] > FIG3_JUDGED_LOAD]
    gap = min(((r["stick_ratio_theory"] - r["b_over_a_fem"]) * r["contact_radius_fem"] for r in near_slip),
              default=math.nan)
    return _grade([agrees, ordered]), (
        f"largest |recovered FEM - coupled half-space (same profile and path)| = {abs(worst['error_vs_coupled']):.3f}"
        f" for Q/(mu P) <= {FIG3_JUDGED_LOAD} where the mesh resolves the rounded edge ("
        f"{'within' if agrees else 'outside'} {FIG3_AGREEMENT}; at b/a = {worst['b_over_a']:g}, Q/(mu P) = "
        f"{worst['load_ratio']:g}). The FEM's nodal c/a leaves the closed form by up to "
        f"{max(abs(r['error']) for r in loaded):.3f}; largest parts: {largest}.{unresolved} Near gross slip "
        f"(Q/(mu P) > {FIG3_JUDGED_LOAD}) the stick edge lies as little as c - b = {gap:.2f} mm outside the flat "
        f"(closed form), below the element size: not judged there. At Q/(mu P) = {top_load:g} the recovered "
        f"FEM c/a is {', '.join(f'{c:.2f}' for _, c in at_top)} for b/a = {', '.join(f'{b:g}' for b, _ in at_top)}: "
        f"{'the flatter the cap, the more stays stuck until the sudden drop' if ordered else 'not ordered by b/a'}")


FIG4_LATE_LOAD = 0.8       # Q/(mu P) after which a 'sudden' drop happens (the last fifth of the load)


def _rule_fig4(summary, rows):
    cap = [r for r in rows if r["case"] == "spherical cap"]
    pad = [r for r in rows if r["case"] == "flat pad"]
    error, tolerance = summary.get("max_error"), _fem_tolerance(cap, "contact_radius")
    agrees = error is not None and error <= tolerance
    stick = {case: {r["load_ratio"]: r["stick_ratio_fem"] for r in group} for case, group in (("cap", cap),
                                                                                            ("pad", pad))}
    shared = sorted(set(stick["cap"]) & set(stick["pad"]))
    early = [x for x in shared if x <= FIG4_LATE_LOAD]
    if not early or shared[-1] <= early[-1]:
        return _grade([agrees, False]), f"no common loads both sides of Q/(mu P) = {FIG4_LATE_LOAD} ({shared})"
    # "drops suddenly": the pad stays more stuck than the cap up to FIG4_LATE_LOAD and loses a larger share of its
    # stick zone after it; "changes slowly": the cap follows Cattaneo-Mindlin (checked above)
    holds = all(stick["pad"][x] > stick["cap"][x] for x in early)
    late = {case: (stick[case][early[-1]] - stick[case][shared[-1]]) / (1.0 - stick[case][shared[-1]])
            for case in stick}
    sudden = holds and late["pad"] > late["cap"]
    return _grade([agrees, sudden]), (
        f"cap: largest |FEM - Cattaneo-Mindlin| = {_number(error)} for Q/(mu P) <= 0.9 "
        f"({'within' if agrees else 'outside'} +-0.5 h/a = {tolerance:.3f}); c/a pad / cap at Q/(mu P) = "
        + ", ".join(f"{x:g}: {stick['pad'][x]:.2f} / {stick['cap'][x]:.2f}" for x in shared)
        + f"; the pad loses {late['pad']:.0%} of its stick zone after Q/(mu P) = {early[-1]:g}, the cap "
        f"{late['cap']:.0%}: " + ("the pad holds, then lets go suddenly" if sudden else "no sudden drop of the pad"))


def _rule_fig6(summary, rows):
    # the capacitive sensor model after gain calibration (the paper's figure: a real sensor, a calibrated estimator)
    error = {(r["bumps"], r["sensor_pitch"]): r["error_after_percent"] for r in rows if r["sensor"] == "capacitive"}
    arrays = sorted({bumps for bumps, _ in error})
    pitches = sorted({pitch for _, pitch in error})
    finer = all(error[(n, min(pitches))] <= error[(n, max(pitches))] for n in arrays)
    # "more bumps lower the error except beyond 3x3": 3x3 below every smaller array and not above the larger ones
    best_3x3 = 9 in arrays and all(
        error[(9, p)] < error[(n, p)] for p in pitches for n in arrays if n < 9) and all(
        error[(9, p)] <= error[(n, p)] for p in pitches for n in arrays if n > 9)
    tested = "" if any(n > 9 for n in arrays) else " (no array above 3x3 in this run: 'not beyond 3x3' untested)"
    return _grade([finer, best_3x3]), (
        f"smaller pitch {'lowers' if finer else 'does not always lower'} the error; 3x3 "
        f"{'is' if best_3x3 else 'is not'} the best array at every pitch{tested}; errors [%]: "
        + ", ".join(f"{round(math.sqrt(n))}x{round(math.sqrt(n))} @ {p:g} mm: {e:.1f}" for (n, p), e in
                    sorted(error.items()))
        + (f". The study: {'; '.join(summary['verdict'])}" if summary.get("verdict") else ""))


FIG9_PAPER_ERROR = {"translation": 0.15, "rotation": 0.03}
FIG9_LINEAR = 0.95            # R^2 for a 'strong linear correlation'
FIG9_ERROR_SLACK = 0.05       # simulation vs hardware: a mean error within 5 points of the paper's counts as alike


def _rule_fig9(summary, rows):
    fits = summary.get("fits") or {}
    if set(fits) != set(FIG9_PAPER_ERROR):
        return NOT_REPRODUCED, f"no translation/rotation fits in the summary ({sorted(fits)})"
    linear = all(fit["r_squared"] >= FIG9_LINEAR for fit in fits.values())
    alike = all(fits[kind]["mean_relative_error"] <= FIG9_PAPER_ERROR[kind] + FIG9_ERROR_SLACK for kind in fits)
    return _grade([linear, alike]), "; ".join(
        f"{kind}: mean error {100 * fit['mean_relative_error']:.1f} % (paper {100 * FIG9_PAPER_ERROR[kind]:.0f} %), "
        f"R^2 = {fit['r_squared']:.4f}, slope {fit['slope']:.2f}" for kind, fit in fits.items()) + (
        f"; strong linear correlation (R^2 >= {FIG9_LINEAR}) {'in both' if linear else 'NOT in both'}; errors "
        f"{'within' if alike else 'beyond'} {100 * FIG9_ERROR_SLACK:.0f} points of the paper's")


PAPER_TRIALS = 10             # trials per object in the paper's Table I (and the fewest a 10/10 claim needs)


def _rule_fig10(summary, rows):
    """Moment-loaded objects held with rotational detection; under-gripped (turned out or dropped) without it."""
    counts = summary.get("counts") or {}
    keys = [key for key in counts if key.endswith(" with rotation")]
    if not keys:
        return _study_verdict(summary, rows)
    held = all(counts[key]["held"] == counts[key]["trials"] for key in keys)
    eclair = counts.get("eclair without rotation", {})
    under = eclair.get("turned out", 0) + eclair.get("dropped", 0)
    trials = min(counts[key]["trials"] for key in counts)
    bottle = (summary.get("series") or {}).get("bottle", {}).get("outcome") == "held"
    matched = [held, bottle, 2 * under >= eclair.get("trials", 0) > 0]
    verdict = _grade(matched)
    if verdict == REPRODUCED and trials < PAPER_TRIALS:
        verdict = PARTLY
    return verdict, "; ".join(
        f"{key}: " + ", ".join(f"{counts[key][label]} {label}" for label in ("held", "turned out", "dropped",
                                                                             "crushed")) + f" of {counts[key]['trials']}"
        for key in counts) + (f"; reproduced if every trial with rotational detection is held and at least half of the "
                              f"eclair's without it are under-gripped, from {PAPER_TRIALS} or more trials each")


FIG11_MEAN, FIG11_MAX = 1.3, 1.5   # 'close to tau_min': the human precision grip's 10-40 % margin (docs/design.md)
FIG11_CASES = 9


def _rule_fig11(summary, rows):
    mean, largest = summary.get("ratio_mean"), summary.get("ratio_max")
    trials, held = summary.get("trials", 0), summary.get("held", 0)
    cases = len({row.get("case") for row in rows}) if rows else 0
    close = mean is not None and largest is not None and mean <= FIG11_MEAN and largest <= FIG11_MAX
    verdict = REPRODUCED if close and held == trials else PARTLY if held == trials or close else NOT_REPRODUCED
    if verdict == REPRODUCED and cases < FIG11_CASES:
        verdict = PARTLY
    return verdict, (f"tau / tau_min mean {_number(mean)}, largest {_number(largest)} over {held} of {trials} trials "
                     f"held ({summary.get('dropped', 0)} dropped, {summary.get('rotated', 0)} turned out) in {cases} "
                     f"cases; reproduced if every trial holds, the mean is <= {FIG11_MEAN} and the largest <= "
                     f"{FIG11_MAX}, over >= {FIG11_CASES} cases")


def _rule_table1(summary, rows):
    objects = summary.get("objects") or {}
    worst = summary.get("max_error")
    trials = min((entry.get("trials", 0) for entry in objects.values()), default=0)
    verdict = (REPRODUCED if worst == 0 else PARTLY if worst is not None and worst <= 0.2 else NOT_REPRODUCED)
    if verdict == REPRODUCED and trials < PAPER_TRIALS:
        verdict = PARTLY
    text = ", ".join(f"{name}: {entry.get('success')} (95 % interval {100 * entry['success_interval'][0]:.0f}-"
                     f"{100 * entry['success_interval'][1]:.0f} %; {entry.get('dropped')} dropped, "
                     f"{entry.get('crushed')} crushed)" if entry.get("success_interval") else
                     f"{name}: {entry.get('success')}" for name, entry in objects.items())
    return verdict, text + (f" (paper: 10/10 each); reproduced only if every trial succeeds, from {PAPER_TRIALS} or "
                            f"more trials per object; partly up to a 20 % failure rate or from fewer trials")


def _rule_robustness(summary, rows):
    """The issue's target: >= 29/30 held per object for every single plant factor up to +-15 %, from 30 trials."""
    from studies.robustness import TARGET_HELD, TARGET_LEVEL

    trials = summary.get("trials_per_cell", 0)
    met = summary.get("single_factor_target_met")
    worst = summary.get("max_error")
    if "single_factor_target_met" not in summary or worst is None:
        return _study_verdict(summary, rows)
    # not decided (None): no 30-trial cells at every factor's +-15 % - a screen, not a verdict
    verdict = UNRATED if met is None else REPRODUCED if met else PARTLY if worst <= 0.2 else NOT_REPRODUCED
    return verdict, (f"every single factor up to +-{100 * TARGET_LEVEL:.0f} %: target "
                     f"{ {True: 'met', False: 'not met', None: 'not decided'}[met]} (>= {30 * TARGET_HELD:.0f}/30 "
                     f"held per object); worst cell {summary.get('worst_cell')} ({summary.get('worst_object')}): "
                     f"failure rate {100 * worst:.0f} %; {trials} trials per object and cell"
                     + ("" if met is not None else " - too few to decide the target (--full runs 30 at every "
                        "factor's +-15 %)")
                     + "; held by friction over every cell: "
                     + ", ".join(f"{band['friction']} {band['held']}/{band['trials']}"
                                 for band in summary.get("friction_bands") or []))


def _rule_convergence(summary, rows):
    from studies.convergence import TARGET_STICK_RATIO_ERROR

    error = summary.get("max_error")
    verdict = (REPRODUCED if error is not None and error <= TARGET_STICK_RATIO_ERROR else
               PARTLY if error is not None and error <= 0.05 else NOT_REPRODUCED)
    knee = summary.get("knee_size_contact")
    return verdict, (f"{_number(error)} on the finest P1 mesh (target {TARGET_STICK_RATIO_ERROR}; "
                     f"docs/theory.md, sec. 11.1: +-0.05 at h = a/10 for 'partly'); knee "
                     + (f"h = {knee} mm" if knee is not None else "not reached"))


CLAIMS: dict[str, Claim] = {
    "fig2b": Claim(
        "paper Fig. 2b, eq. 3",
        "the stick ratio drops to zero suddenly when the tangential force reaches mu P; the drop is more sudden for "
        "higher orders n of the contact surface f = C r^n",
        "eq. 3 against the Ciavarella-Jager principle with an MDR quadrature of each profile; c/a at Q/(mu P) = 0.9 "
        "ordered by n", _rule_fig2b),
    "fig3b": Claim(
        "paper Fig. 3b",
        "the stick ratio drops suddenly when the flat surface ratio b/a is large",
        "Ciavarella-Jager stick ratio of the flat + curved profile (closed form against quadrature); the drop height "
        "at Q = mu P against b/a", _rule_fig3b,
        "Two readings of the paper's profile (rounded flat punch, flat + parabolic 1D MDR) are drawn; both drop by b/a."),
    "torsion-theory": Claim(
        "paper eq. 6 (sec. III-B)",
        "the rotational stick ratio follows the paper's 1D torsion model, eq. 6, which slides as a whole at "
        "T = 3/8 mu P a",
        "eq. 6 (corrected: outer square root, as eq. 8 shows) against the exact 3D Hertz torsion (Lubkin 1951); "
        "reproduced if within 0.05 in c/a up to the model's full slip", _rule_torsion,
        "The paper's model is qualitatively right but slides too early: an incipient-slip controller built on it is "
        "conservative. Eq. 6 as printed gives (c/a)^2."),
    "fig3": Claim(
        "paper Fig. 3 (ANSYS check, sec. IV-A)",
        "the stick ratio drops suddenly when the flat surface ratio b/a is large (FEM confirms the theory)",
        "FEM rigid plate on flat + curved gel caps, recovered c/a, against the coupled half-space on the same profile "
        "and load path (contact.halfspace), Q/(mu P) <= 0.9 where the mesh resolves the rim, within 0.05 "
        "(docs/theory.md, sec. 11.1); the nodal FEM's difference from Ciavarella-Jager taken apart into nodal "
        "measure, finite cap, coupling and rounded edge",
        _rule_fig3,
        "The closed form (half-space, no coupling) is the half-space solver's uncoupled answer; the FEM solves the "
        "coupled problem on a finite cap, so its reference is the coupled half-space (docs/coupled_reference.md)."),
    "fig4": Claim(
        "paper Fig. 4 (ANSYS, sec. IV-A)",
        "the stick ratio changes slowly for the curved surface contact, while it drops suddenly for the flat "
        "surface contact",
        "FEM cap against Cattaneo-Mindlin (Q/(mu P) <= 0.9, +-0.5 h/a); flat pad's c/a against the cap's at equal load",
        _rule_fig4),
    "fig6": Claim(
        "paper Fig. 6 (sec. IV-B)",
        "a smaller sensor pitch lowers the translational estimation error; more bumps lower it up to 3x3, not beyond",
        "FEM virtual bench: mean relative error of the estimated shear displacement per array and pitch, "
        "capacitive sensor model (pads, saturating curve, crosstalk, noise, converter) after gain calibration",
        _rule_fig6, "A rigid plate on a simulated fingertip, the sensor a model of a capacitive array: the trends are "
                    "what can be compared; fig6.csv also holds the ideal cell sensor and the errors before "
                    "calibration."),
    "fig9": Claim(
        "paper Fig. 9 (sec. VI-B)",
        "estimation error 15 % translational, 3 % rotational, with a strong linear correlation to the applied "
        "displacement",
        f"FEM virtual bench, 3x3 fingertip, 3 mm pitch: mean relative error and R^2 of estimated against applied; "
        f"reproduced if R^2 >= {FIG9_LINEAR} in both and each error within {100 * FIG9_ERROR_SLACK:.0f} points of "
        f"the paper's", _rule_fig9,
        "The paper measured on hardware (stage encoder); this is the same estimator on FEM sensor images."),
    "fig10": Claim(
        "paper Fig. 10 (sec. VI-C)",
        "the grasp force rises and falls at the moments of lifting and placing, following u_x and u_theta; without "
        "rotational slip detection the grasp force is not enough (eclair)",
        "MuJoCo closed loop with the reduced contact model and the incipient-slip controller: the bottle over time; "
        "randomised trials of the eclair and the horizontal bottle with and without rotational slip detection, "
        "outcomes counted apart (held, turned out, dropped, crushed)", _rule_fig10,
        "Without rotational detection the controller sees only the translational part of the bumps' load ratios."),
    "fig11": Claim(
        "paper Fig. 11 (sec. VI-C)",
        "the grasp force stays close to the minimum grasp force tau_min for different weights and moments",
        "MuJoCo closed loop: the grip the incipient-slip controller settles at against each trial's own tau_min from "
        "constant-force trials (bisection to 2 %), randomised friction, jitter and noise, per mass and moment",
        _rule_fig11,
        "The controller learns the friction in hand by probing the grip down until the first bump slides."),
    "table1": Claim(
        "paper Table I (sec. VI-C)",
        "10/10 grasp success for the bottle placed vertically (600 g, 0 mNm), horizontally (251 g, 120 mNm) and "
        "the eclair (104 g, 39 mNm)",
        "MuJoCo closed loop, incipient-slip controller: success rate per object with its 95 % Wilson interval (30 "
        "trials default, 3 quick), drops and crushes apart, randomised mu, grasp position and sensor noise",
        _rule_table1),
    "robustness": Claim(
        "this toolkit's robustness target (docs/design.md, sec. 12)",
        "the grasp survives a plant the estimator does not know: >= 29/30 held per object for every single plant "
        "factor up to +-15 %, friction 0.2-1.2",
        "MuJoCo closed loop, FEM sensor plane and capacitive arrays, estimator fitted on a nominal build's bench: held "
        "/ turned out / dropped / crushed per plant factor and level, random combinations and the known world",
        _rule_robustness,
        "Not a paper claim: the paper's sensor and estimator met one physical fingertip. The default run has a few "
        "trials per cell (a screen); --full has 30."),
    "convergence": Claim(
        "docs/design.md, sec. 8 (HCM-1 benchmark)",
        "the FEM stick ratio on HCM-1, recovered below the element size, follows the physics it solves (the coupled "
        "half-space reference on the same load path) to within 0.01 on the finest P1 mesh of the run",
        "largest |recovered c/a FEM - coupled half-space reference| on the finest P1 mesh, 5 equal shear increments "
        "to Q/(mu P) = 0.9; the knee is the cheapest mesh meeting 0.01 and p_max within 3 % of Hertz",
        _rule_convergence,
        "Not a paper claim: the solver's own accuracy, as error against wall time."),
}


def claim_for(name: str) -> Claim:
    """The tabled claim, or a placeholder for a figure/table study without one."""
    return CLAIMS.get(name) or Claim("-", "no claim recorded for this study (add it to studies/_report.py CLAIMS)",
                                     "the study's own verdict", _study_verdict)


def judge(name: str, record: dict, out_dir: Path) -> tuple[str, str]:
    """Verdict and reason of one study record (from ``NAME.summary.json``); a broken rule is reported, not raised."""
    if record.get("status") not in ("ok", "reused"):
        return record.get("status", "failed"), record.get("error", "")
    try:
        return claim_for(name).rule(record.get("summary") or {}, read_rows(Path(out_dir) / f"{name}.csv"))
    except Exception as error:  # a rule that cannot read the outputs must not hide the other studies
        return UNRATED, f"the verdict rule failed: {type(error).__name__}: {error}"


def read_rows(path: Path) -> list[dict]:
    """A study's CSV as dicts, numbers parsed to float (empty cells dropped); [] if the file is missing."""
    if not path.is_file():
        return []
    with open(path, newline="") as stream:
        return [{key: _parse(value) for key, value in row.items() if value != ""} for row in csv.DictReader(stream)]


def _parse(text: str):
    try:
        return float(text)
    except ValueError:
        return text


def _number(value) -> str:
    return "n/a" if value is None or (isinstance(value, float) and not math.isfinite(value)) else f"{value:.3g}"


def _seconds(value) -> str:
    return "-" if value is None else f"{value:.1f} s"


# ---------------------------------------------------------------------------------------------------------------
# writers


def _entries(records: list[dict], out_dir: Path) -> list[dict]:
    """Everything the two writers show, per study."""
    entries = []
    for record in records:
        name = record["name"]
        verdict, why = judge(name, record, out_dir)
        summary = record.get("summary") or {}
        shown = record.get("status") in ("ok", "reused")
        entries.append(dict(
            name=name, claim=claim_for(name), status=record.get("status", "failed"), verdict=verdict, why=why,
            max_error=summary.get("max_error"), error_meaning=summary.get("error_meaning", ""),
            wall_time=record.get("wall_time"), finished=record.get("finished", ""),
            extra={k: v for k, v in summary.items() if k not in ("max_error", "error_meaning", "verdict")},
            traceback=record.get("traceback", ""),
            figure=f"{name}.png" if shown and (out_dir / f"{name}.png").is_file() else None,
            files=[f for f in (f"{name}.csv", f"{name}.pdf", f"{name}.summary.json", record.get("log") or "")
                   if f and (out_dir / f).is_file()]))
    return entries


def _status_text(entry: dict) -> str:
    return {"ok": "computed in this run", "reused": f"up to date, reused (computed {entry['finished']})",
            "not available": "not available (no such study module yet)"}.get(entry["status"], "FAILED")


def _run_text(run_info: dict, entries: list[dict]) -> str:
    spent = {status: sum(e["wall_time"] or 0.0 for e in entries if e["status"] == status)
             for status in ("ok", "failed", "reused")}
    counts = {v: sum(e["verdict"] == v for e in entries) for v in (REPRODUCED, PARTLY, NOT_REPRODUCED, UNRATED,
                                                                    "failed", "not available")}
    return (f"{'Quick (coarse) settings' if run_info['quick'] else 'Default (full) settings'}; total wall time of "
            f"this run {run_info['wall_time']:.1f} s on {run_info['jobs']} job(s): {spent['ok'] + spent['failed']:.1f} s"
            f" of study time computed now, {spent['reused']:.1f} s reused from earlier runs of up-to-date studies; "
            f"finished {run_info['finished']}. Verdicts: " + ", ".join(f"{n} {v}" for v, n in counts.items() if n))


def write_report(out_dir, records: list[dict], run_info: dict) -> dict:
    """Write ``index.html`` and ``REPORT.md`` into ``out_dir``; return their paths."""
    from fem.atomic import write_text_atomic

    out_dir = Path(out_dir)
    entries = _entries(records, out_dir)
    html_path = write_text_atomic(out_dir / "index.html", _html(entries, run_info))
    md_path = write_text_atomic(out_dir / "REPORT.md", _markdown(entries, run_info))
    return {"html": html_path, "markdown": md_path}


def _markdown(entries: list[dict], run_info: dict) -> str:
    lines = ["# Fingertip contact: figures against the paper's claims", "", _run_text(run_info, entries), "",
             "| study | source | verdict | largest error | wall time | status |", "| --- | --- | --- | --- | --- | --- |"]
    lines += [f"| [{e['name']}](#{e['name']}) | {e['claim'].source} | **{e['verdict']}** | {_number(e['max_error'])} "
              f"| {_seconds(e['wall_time'])} | {_status_text(e)} |" for e in entries]
    for e in entries:
        lines += ["", f"## {e['name']}", "", f"*{e['claim'].source}* - {_status_text(e)}", ""]
        if e["figure"]:
            lines += [f"![{e['name']}]({e['figure']})", ""]
        lines += [f"- **Claim:** {e['claim'].claim}", f"- **Measured:** {e['claim'].measure}",
                  f"- **Largest error:** {_number(e['max_error'])} ({e['error_meaning'] or 'n/a'})",
                  f"- **Wall time:** {_seconds(e['wall_time'])}",
                  f"- **Verdict: {e['verdict']}** - {e['why']}"]
        if e["claim"].note:
            lines.append(f"- **Note:** {e['claim'].note}")
        if e["extra"]:
            lines.append(f"- **Summary:** `{json.dumps(e['extra'], default=str)}`")
        if e["files"]:
            lines.append("- **Files:** " + ", ".join(f"[{f}]({f})" for f in e["files"]))
        if e["traceback"]:
            lines += ["", "```", e["traceback"].rstrip(), "```"]
    return "\n".join(lines) + "\n"


_CSS = """body{font-family:sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
table{border-collapse:collapse}td,th{border:1px solid #ccc;padding:.3em .6em;text-align:left;vertical-align:top}
img{max-width:100%;border:1px solid #ddd}pre{background:#f6f6f6;padding:.6em;overflow-x:auto;font-size:85%}
.reproduced{background:#d9f0d3}.partly{background:#fff2cc}.not-reproduced,.failed{background:#f4cccc}
.unrated,.not-available{background:#eee}section{border-top:2px solid #888;margin-top:2em}"""


def _html(entries: list[dict], run_info: dict) -> str:
    e_ = html.escape
    css_class = lambda verdict: verdict.replace(" ", "-")
    rows = "".join(
        f"<tr><td><a href='#{e_(e['name'])}'>{e_(e['name'])}</a></td><td>{e_(e['claim'].source)}</td>"
        f"<td class='{css_class(e['verdict'])}'><b>{e_(e['verdict'])}</b></td><td>{_number(e['max_error'])}</td>"
        f"<td>{_seconds(e['wall_time'])}</td><td>{e_(_status_text(e))}</td></tr>" for e in entries)
    sections = []
    for e in entries:
        items = [("Claim", e_(e["claim"].claim)), ("Measured", e_(e["claim"].measure)),
                 ("Largest error", f"{_number(e['max_error'])} ({e_(e['error_meaning'] or 'n/a')})"),
                 ("Wall time", _seconds(e["wall_time"])),
                 ("Verdict", f"<span class='{css_class(e['verdict'])}'><b>{e_(e['verdict'])}</b></span> - "
                             f"{e_(e['why'])}")]
        if e["claim"].note:
            items.append(("Note", e_(e["claim"].note)))
        if e["extra"]:
            items.append(("Summary", f"<code>{e_(json.dumps(e['extra'], default=str))}</code>"))
        if e["files"]:
            items.append(("Files", ", ".join(f"<a href='{e_(f)}'>{e_(f)}</a>" for f in e["files"])))
        figure = f"<img src='{e_(e['figure'])}' alt='{e_(e['name'])}'>" if e["figure"] else ""
        trace = f"<pre>{e_(e['traceback'])}</pre>" if e["traceback"] else ""
        sections.append(
            f"<section id='{e_(e['name'])}'><h2>{e_(e['name'])}</h2><p><i>{e_(e['claim'].source)}</i> - "
            f"{e_(_status_text(e))}</p>{figure}<table>"
            + "".join(f"<tr><th>{k}</th><td>{v}</td></tr>" for k, v in items) + f"</table>{trace}</section>")
    return (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>Fingertip contact report</title>"
            f"<style>{_CSS}</style></head><body><h1>Fingertip contact: figures against the paper's claims</h1>"
            f"<p>{e_(_run_text(run_info, entries))}</p><table><tr><th>study</th><th>source</th><th>verdict</th>"
            f"<th>largest error</th><th>wall time</th><th>status</th></tr>{rows}</table>{''.join(sections)}"
            f"</body></html>\n")
