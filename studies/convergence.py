"""Convergence: error against wall time for element size, element order and number of shear increments, on HCM-1
and on the 3x3 fingertip of Figs. 6 and 9 (studies/_convergence_array.py; not in --quick), each knee marked.

HCM-1 errors: stick ratio against Cattaneo-Mindlin (largest over the shear increments), contact radius against
Hertz, tangential shift against Mindlin; wall time is the whole solve (mesh, assembly, factorization, contact path).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from studies._convergence_array import ARRAY_STUDIES, array_cases, solve_array_case, solve_timed
from studies._output import save_figure, write_csv_atomic

NAME = "convergence"
SCENE = Path(__file__).parent / "scenes" / "hcm1.toml"
TARGET_STICK_RATIO_ERROR = 0.02         # the solver issue's target for the HCM-1 path
KNEE_FACTOR = 1.15                      # knee: cheapest mesh whose error is within 15 % of the best one


def _cases(quick: bool) -> list[dict]:
    # bisection refines by levels: these sizes give distinct top-surface spacings (0.3 and 0.25 would not)
    sizes = (0.35, 0.25) if quick else (0.35, 0.25, 0.17, 0.12, 0.1)
    quadratic = (0.35,) if quick else (0.35, 0.17, 0.12)       # P2 elements are twice these sizes
    increments = (1, 5) if quick else (1, 2, 5, 10)
    cases = [dict(study="element size (P1)", size_contact=h, order=1, n_shear=5) for h in sizes]
    cases += [dict(study="element order (P2)", size_contact=h, order=2, n_shear=5) for h in quadratic]
    cases += [dict(study="shear increments", size_contact=0.25 if quick else 0.15, order=1, n_shear=n)
              for n in increments]
    return cases


def solve_case(size_contact: float, order: int, n_shear: int) -> dict:
    """Solve HCM-1 with the given mesh and number of equal shear increments to Q/(mu P) = 0.9; errors and time."""
    from contact.scene import load_scene
    from contact.theory import hertz, mindlin_shift, stick_ratio_translational

    scene = load_scene(SCENE)
    press, shear = scene.loads
    force, mu = press.values[0], scene.contact.friction_coefficient
    final = max(shear.values)
    ratios = final / (mu * force) * np.arange(1, n_shear + 1) / n_shear
    scene = dataclasses.replace(
        scene, mesh=dataclasses.replace(scene.mesh, size_contact=size_contact, order=order),
        loads=(press, dataclasses.replace(shear, values=tuple(float(r * mu * force) for r in ratios))))
    result, cost = solve_timed(scene)
    material = scene.material
    reference = hertz(force, scene.body.radius, material.effective_modulus)
    shear_increments = result.increments[1:]
    stick_error = [inc.stick_ratio - float(stick_ratio_translational(r, 2)) for r, inc in zip(ratios, shear_increments)]
    shift_error = [inc.shift[0] / float(mindlin_shift(r * mu * force, force, mu, inc.contact_radius,
                                                      material.shear_modulus, material.nu)) - 1.0
                   for r, inc in zip(ratios, shear_increments)]
    return dict(**cost, stick_ratio_error=float(np.max(np.abs(stick_error))),
                stick_ratio_error_signed=float(stick_error[int(np.argmax(np.abs(stick_error)))]),
                final_stick_ratio_error=float(stick_error[-1]),
                contact_radius_error=float(result.increments[0].contact_radius / float(reference.contact_radius) - 1),
                shift_error=float(np.max(np.abs(shift_error))))


def knee(rows: list[dict], factor: float = KNEE_FACTOR) -> dict | None:
    """The cheapest row (least wall_time) whose stick_ratio_error is within ``factor`` x the best of ``rows``: past
    it, finer meshes buy little more. None for no rows."""
    if not rows:
        return None
    best = min(r["stick_ratio_error"] for r in rows)
    return min((r for r in rows if r["stick_ratio_error"] <= factor * best), key=lambda r: r["wall_time"])


def run(out_dir, quick: bool = False) -> dict:
    """Run every case, write convergence.csv / .png / .pdf, and mark the knee of the P1 error-time curves of HCM-1
    and (not in --quick) of the 3x3 fingertip."""
    from tqdm import tqdm

    out_dir = Path(out_dir)
    rows = []
    for case in tqdm(_cases(quick), desc=NAME, unit="case"):
        rows.append({**case, **solve_case(**{k: case[k] for k in ("size_contact", "order", "n_shear")})})
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)          # keep what is done if a later case fails
    for case in (() if quick else tqdm(array_cases(), desc=f"{NAME} (3x3 fingertip)", unit="case")):
        rows.append({**case, **solve_array_case(**{k: case[k] for k in ("size_contact", "order", "n_shear")})})
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    hcm1_knee = knee([r for r in rows if r["study"] == "element size (P1)"])
    array_knee = knee([r for r in rows if r["study"] == ARRAY_STUDIES[0]])     # P1 sizes, as HCM-1
    for row in rows:
        row["knee"] = row is hcm1_knee or row is array_knee
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    save_figure(_plot(rows, hcm1_knee, array_knee), out_dir, NAME)
    for label, point in (("HCM-1", hcm1_knee), ("3x3 fingertip", array_knee)):
        if point is not None:
            print(f"{NAME}: {label} knee (cheapest P1 mesh within {KNEE_FACTOR:.2f}x of the best stick-ratio "
                  f"error): size_contact = {point['size_contact']} mm ({point['wall_time']:.1f} s, error "
                  f"{point['stick_ratio_error']:.4f})")
    finest = min((r for r in rows if r["study"] == "element size (P1)"), key=lambda r: r["size_contact"])
    summary = {"max_error": finest["stick_ratio_error"],
               "error_meaning": f"stick-ratio error against Cattaneo-Mindlin on the finest P1 mesh, "
                                f"size_contact = {finest['size_contact']} mm",
               "knee_size_contact": hcm1_knee["size_contact"]}
    if array_knee is not None:
        summary["array_knee_size_contact"] = array_knee["size_contact"]
    return summary


def _plot(rows: list[dict], hcm1_knee: dict | None, array_knee: dict | None = None):
    """HCM-1 (top row: c/a, a and shift errors against wall time) and, when run, the 3x3 fingertip (bottom row:
    c/a and bump-radius errors against wall time, then wall time against DOF for every case)."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    from studies._convergence_array import plot_array, plot_errors_against_time

    with_array = any(r["study"] in ARRAY_STUDIES for r in rows)
    fig, grid = plt.subplots(2 if with_array else 1, 3, figsize=(15, 9.2 if with_array else 4.6), squeeze=False)
    axes = grid[0]
    metrics = (("stick_ratio_error", "max |c/a - Cattaneo-Mindlin|"), ("contact_radius_error", "a / a_Hertz - 1"),
               ("shift_error", "max |shift / Mindlin - 1|"))
    markers = {"element size (P1)": "o-", "element order (P2)": "s-", "shear increments": "^--"}
    for axis, (key, label) in zip(axes, metrics):
        plot_errors_against_time(axis, rows, key, markers, "shear increments")
        if key == "stick_ratio_error":
            axis.axhline(TARGET_STICK_RATIO_ERROR, color="grey", ls=":", label=f"target {TARGET_STICK_RATIO_ERROR}")
            if hcm1_knee:
                axis.plot(hcm1_knee["wall_time"], hcm1_knee["stick_ratio_error"], "r*", ms=16,
                          label=f"knee: cheapest within {KNEE_FACTOR:.2f}x best")
        axis.set_xlabel("wall time [s]")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title("HCM-1 (sphere R = 10 mm on a 40x40x20 mm block, nu = 0.45, mu = 0.5)", fontsize=9)
    if with_array:
        plot_array(grid[1][:2], rows, array_knee, KNEE_FACTOR)
        cost = grid[1][2]
        for study in list(markers) + list(ARRAY_STUDIES):
            subset = [r for r in rows if r["study"] == study]
            if subset:
                cost.loglog([r["dofs"] for r in subset], [r["wall_time"] for r in subset], "o", label=study)
        cost.set_xlabel("degrees of freedom")
        cost.set_ylabel("wall time [s]")
        cost.grid(True, which="both", alpha=0.3)
        cost.legend(fontsize=7)
    for axis in fig.axes:                      # log axes spanning under a decade would label every minor tick
        axis.xaxis.set_minor_formatter(NullFormatter())
    fig.suptitle("Error against run time")
    fig.tight_layout()
    return fig
