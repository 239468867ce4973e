"""Fig. 4 (FEM): a rigid plate sheared over (a) an elastic flat pad and (b) an elastic spherical cap.

Stick ratio against the tangential load for both, and top views of the contact state (open / stick / slip) at a
few loads, as the paper shows its ANSYS results. The pad keeps most of its area stuck until close to Q = mu P and
then lets go at once (the flat-punch limit of eq. 3: no warning); the cap's stick zone shrinks gradually, following
Cattaneo-Mindlin (1 - Q/(mu P))^(1/3) (the theory curve drawn for it).
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic

NAME = "fig4"
MAP_RATIOS = (0.3, 0.7, 0.95)           # load ratios shown as state maps


def _cases(quick: bool):
    from contact.scene import GelSpec

    size = 0.4 if quick else 0.25
    pad = GelSpec("block", (("width", 8.0), ("depth", 8.0), ("thickness", 4.0)))
    cap = GelSpec("cap", (("width", 24.0), ("depth", 24.0), ("base_thickness", 8.0), ("cap_radius", 6.0),
                          ("sphere_radius", 20.0)))
    # pad: the plate covers its whole top; cap: P chosen for a Hertz contact radius of about 2 mm
    return (("flat pad", pad, 0.5, size), ("spherical cap", cap, 0.2, 0.4 if quick else 0.2))


def run(out_dir, quick: bool = False) -> dict:
    """Shear both gels by force control up to Q/(mu P) = 0.99; write fig4.csv, .png, .pdf."""
    from contact.solver import solve_scene
    from contact.theory import stick_ratio_translational
    from controller.estimation.bench import plate_shear_scene

    out_dir = Path(out_dir)
    ratios = (0.3, 0.5, 0.7, 0.95) if quick else (0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 0.95, 0.98, 0.99)
    rows, results = [], {}
    start = time.perf_counter()
    for case, gel, normal_force, size in _cases(quick):
        scene = plate_shear_scene(f"fig4_{case.replace(' ', '_')}", gel, normal_force, ratios, size)
        result = solve_scene(scene)
        results[case] = result
        for ratio, inc in zip(ratios, result.increments[1:]):
            theory = float(stick_ratio_translational(ratio, 2)) if case == "spherical cap" else float("nan")
            rows.append(dict(case=case, load_ratio=ratio, tangential_force=inc.tangential_force[0],
                             normal_force=inc.normal_force, contact_radius=inc.contact_radius,
                             stick_ratio_fem=inc.stick_ratio, stick_ratio_theory=theory,
                             error=inc.stick_ratio - theory, slip_area=inc.contact_area - inc.stick_area,
                             element_size=size))
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    wall = time.perf_counter() - start
    cap_errors = [abs(r["error"]) for r in rows if r["case"] == "spherical cap" and r["load_ratio"] <= 0.9]
    save_figure(_plot(rows, results, ratios, wall), out_dir, NAME)
    return {"max_error": max(cap_errors),
            "error_meaning": "largest |c/a FEM - Cattaneo-Mindlin| of the cap for Q/(mu P) <= 0.9"}


def _plot(rows, results, ratios, wall):
    import matplotlib.pyplot as plt

    from contact.theory import stick_ratio_translational
    from contact.plotting import state_legend, state_map

    fig = plt.figure(figsize=(13, 7.2))
    grid = fig.add_gridspec(2, 4, width_ratios=[1.6, 1, 1, 1], hspace=0.3, wspace=0.15)
    curve = fig.add_subplot(grid[:, 0])
    load = np.linspace(0, 1, 300)
    curve.plot(load, stick_ratio_translational(load, 2), "k-", lw=1, label="Cattaneo-Mindlin (sphere)")
    curve.plot([0, 0.999, 1.0], [1, 1, 0], "k:", lw=1, label="flat punch limit")
    for case, style in (("flat pad", "s-"), ("spherical cap", "o-")):
        points = [r for r in rows if r["case"] == case]
        curve.plot([0.0] + [r["load_ratio"] for r in points], [1.0] + [r["stick_ratio_fem"] for r in points], style,
                   ms=5, label=f"FEM: {case}")
    curve.set_xlabel("load ratio Q / (mu P)  [-]")
    curve.set_ylabel("stick ratio c / a  [-]")
    curve.set_xlim(0, 1.02)
    curve.set_ylim(0, 1.05)
    curve.grid(alpha=0.3)
    curve.legend(fontsize=8, loc="lower left")
    curve.set_title(f"Stick ratio under a rigid plate ({wall:.0f} s)", fontsize=10)
    for row_index, case in enumerate(("flat pad", "spherical cap")):
        result = results[case]
        half_width = 4.2 if case == "flat pad" else 2.8
        for column, target in enumerate(MAP_RATIOS):
            index = int(np.argmin(np.abs(np.asarray(ratios) - target)))
            axis = fig.add_subplot(grid[row_index, column + 1])
            increment = result.increments[1 + index]
            state_map(axis, result, increment, f"{case}, Q/(mu P) = {ratios[index]}\nc/a = "
                      f"{increment.stick_ratio:.2f}", half_width)
    state_legend(fig)
    fig.suptitle("Fig. 4: rigid plate sheared over an elastic flat pad (top) and an elastic spherical cap (bottom)")
    return fig
