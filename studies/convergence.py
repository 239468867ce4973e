"""Convergence on HCM-1: error against wall time for element size, element order and number of shear increments.

Errors: stick ratio against Cattaneo-Mindlin (largest over the shear increments), contact radius against Hertz,
tangential shift against Mindlin; wall time is the whole solve (mesh, assembly, factorization, contact path).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic

NAME = "convergence"
SCENE = Path(__file__).parent / "scenes" / "hcm1.toml"
TARGET_STICK_RATIO_ERROR = 0.02         # the solver issue's target for the HCM-1 path
KNEE_FACTOR = 1.15                      # knee: cheapest mesh whose error is within 15 % of the best one


ARRAY_SIZES = (0.9, 0.6, 0.4, 0.3)      # mm, element size at the bump tops of the 3x3 fingertip (not in --quick)
ARRAY_LOAD_RATIO = 0.5


def solve_array_case(size_contact: float) -> dict:
    """The 3x3 fingertip of figs. 6 and 9 under a plate: press 2 N (frictionless), shear to Q/(mu P) = 0.5.

    Errors: the array's stick ratio against Cattaneo-Mindlin (every bump carries Q/P = 0.5 of its own load) and
    the mean bump contact radius against Hertz with an equal share P/9 (the base couples the bumps a little).
    """
    from contact.scene import ContactSpec, Load, LoadKind, MeshSettings
    from contact.solver import solve_scene
    from contact.theory import hertz, stick_ratio_translational
    from studies import _fingertip as tip

    base = tip.bench_scene(3, "shift", (0.1,), size_contact, tip.BENCH_SIZE_BASE)
    scene = dataclasses.replace(
        base, contact=ContactSpec(mu=tip.FRICTION, frictionless_press=True),
        mesh=MeshSettings(size_contact=size_contact, size_far=3.0, size_base=tip.BENCH_SIZE_BASE),
        loads=(Load(LoadKind.PRESS, "force", (tip.NORMAL_FORCE,)),
               Load(LoadKind.SHEAR, "force", (ARRAY_LOAD_RATIO * tip.FRICTION * tip.NORMAL_FORCE,))))
    start = time.perf_counter()
    result = solve_scene(scene)
    wall = time.perf_counter() - start
    bumps = 9
    radius = float(hertz(tip.NORMAL_FORCE / bumps, scene.gel.geometry.bump_radius,
                         scene.material.effective_modulus).contact_radius)
    contact_radius = float(np.sqrt(result.increments[0].contact_area / (bumps * np.pi)))
    stick_error = result.increments[1].stick_ratio - float(stick_ratio_translational(ARRAY_LOAD_RATIO, 2))
    return dict(study="3x3 fingertip (P1)", size_contact=size_contact, order=1, n_shear=1,
                dofs=result.mesh_info["dofs"], elements=result.mesh_info["elements"],
                compliance_columns=result.timings["compliance_columns"], wall_time=wall,
                stick_ratio_error=abs(stick_error), stick_ratio_error_signed=stick_error,
                final_stick_ratio_error=stick_error, contact_radius_error=contact_radius / radius - 1.0,
                shift_error=float("nan"))


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
    from contact.solver import solve_scene
    from contact.theory import hertz, mindlin_shift, stick_ratio_translational

    scene = load_scene(SCENE)
    press, shear = scene.loads
    force, mu = press.values[0], scene.contact.mu
    final = max(shear.values)
    ratios = final / (mu * force) * np.arange(1, n_shear + 1) / n_shear
    scene = dataclasses.replace(
        scene, mesh=dataclasses.replace(scene.mesh, size_contact=size_contact, order=order),
        loads=(press, dataclasses.replace(shear, values=tuple(float(r * mu * force) for r in ratios))))
    start = time.perf_counter()
    result = solve_scene(scene)
    wall = time.perf_counter() - start
    material = scene.material
    reference = hertz(force, scene.body.radius, material.effective_modulus)
    shear_increments = result.increments[1:]
    stick_error = [inc.stick_ratio - float(stick_ratio_translational(r, 2)) for r, inc in zip(ratios, shear_increments)]
    shift_error = [inc.shift[0] / float(mindlin_shift(r * mu * force, force, mu, inc.contact_radius,
                                                      material.shear_modulus, material.nu)) - 1.0
                   for r, inc in zip(ratios, shear_increments)]
    return dict(dofs=result.mesh_info["dofs"], elements=result.mesh_info["elements"],
                compliance_columns=result.timings["compliance_columns"], wall_time=wall,
                stick_ratio_error=float(np.max(np.abs(stick_error))),
                stick_ratio_error_signed=float(stick_error[int(np.argmax(np.abs(stick_error)))]),
                final_stick_ratio_error=float(stick_error[-1]),
                contact_radius_error=float(result.increments[0].contact_radius / float(reference.contact_radius) - 1),
                shift_error=float(np.max(np.abs(shift_error))))


def run(out_dir, quick: bool = False) -> dict:
    """Run every case, write convergence.csv / .png / .pdf, and mark the knee of the P1 error-time curve."""
    from tqdm import tqdm

    out_dir = Path(out_dir)
    rows = []
    for case in tqdm(_cases(quick), desc=NAME, unit="case"):
        rows.append({**case, **solve_case(**{k: case[k] for k in ("size_contact", "order", "n_shear")})})
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)          # keep what is done if a later case fails
    for size in (() if quick else tqdm(ARRAY_SIZES, desc=f"{NAME} (3x3 fingertip)", unit="case")):
        rows.append(solve_array_case(size))
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    array_rows = [r for r in rows if r["study"] == "3x3 fingertip (P1)"]
    if array_rows:
        best_array = min(r["stick_ratio_error"] for r in array_rows)
        array_knee = min((r for r in array_rows if r["stick_ratio_error"] <= KNEE_FACTOR * best_array),
                         key=lambda r: r["wall_time"])
        print(f"{NAME}: 3x3 fingertip knee: size_contact = {array_knee['size_contact']} mm "
              f"({array_knee['wall_time']:.1f} s, stick-ratio error {array_knee['stick_ratio_error']:.4f})")
    sizes = [r for r in rows if r["study"] == "element size (P1)"]
    best = min(r["stick_ratio_error"] for r in sizes)
    # the knee: the cheapest P1 mesh within 15 % of the best error seen (finer meshes buy little more)
    knee = min((r for r in sizes if r["stick_ratio_error"] <= KNEE_FACTOR * best), key=lambda r: r["wall_time"])
    for row in rows:
        row["knee"] = row is knee
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    save_figure(_plot(rows, knee), out_dir, NAME)
    print(f"{NAME}: knee (cheapest P1 mesh within {KNEE_FACTOR:.2f}x of the best stick-ratio error): size_contact = "
          f"{knee['size_contact']} mm ({knee['wall_time']:.1f} s, error {knee['stick_ratio_error']:.4f})")
    finest = min((r for r in rows if r["study"] == "element size (P1)"), key=lambda r: r["size_contact"])
    return {"max_error": finest["stick_ratio_error"],
            "error_meaning": f"stick-ratio error against Cattaneo-Mindlin on the finest P1 mesh, "
                             f"size_contact = {finest['size_contact']} mm"}


def _plot(rows: list[dict], knee: dict | None):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    metrics = (("stick_ratio_error", "max |c/a - Cattaneo-Mindlin|"), ("contact_radius_error", "a / a_Hertz - 1"),
               ("shift_error", "max |shift / Mindlin - 1|"))
    markers = {"element size (P1)": "o-", "element order (P2)": "s-", "shear increments": "^--",
               "3x3 fingertip (P1)": "D-"}
    for axis, (key, label) in zip(axes, metrics):
        for study, style in markers.items():
            subset = [r for r in rows if r["study"] == study]
            if not subset:
                continue
            values = [abs(r[key]) for r in subset]
            axis.loglog([r["wall_time"] for r in subset], values, style, label=study)
            for r, v in zip(subset, values):
                tag = f"h={r['size_contact']}" if study != "shear increments" else f"n={r['n_shear']}"
                axis.annotate(tag, (r["wall_time"], v), textcoords="offset points", xytext=(4, 3), fontsize=7)
        if key == "stick_ratio_error":
            axis.axhline(TARGET_STICK_RATIO_ERROR, color="grey", ls=":", label=f"target {TARGET_STICK_RATIO_ERROR}")
            if knee:
                axis.plot(knee["wall_time"], knee["stick_ratio_error"], "r*", ms=16,
                          label=f"knee: cheapest within {KNEE_FACTOR:.2f}x best")
        axis.set_xlabel("wall time [s]")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.suptitle("HCM-1 (sphere R = 10 mm on a 40x40x20 mm block, nu = 0.45, mu = 0.5): error against run time")
    fig.tight_layout()
    return fig
