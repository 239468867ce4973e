"""Fig. 3b: stick ratio c/a against Q/(mu P) for the flat + curved cap, surface ratio b/a = 0, 0.25, 0.5, 0.75, 0.9.

Ciavarella-Jager, P(c) = P(a)(1 - Q/(mu P)), for the two readings of docs/theory.md, sec. 5.2: the rounded flat punch
(plotted, closed-form P(a)) and the flat + parabolic 1D MDR profile (dashed, extra CSV column). c/a falls
to b/a and drops to 0 at Q = mu P. Independent check: the same stick ratios with P(rho) from MDR quadrature
of each reading's 3D gap f(r) instead of the closed-form force curves.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from contact.theory import flat_curved, stick_ratio_profile
from studies._output import largest_abs, save_figure, write_csv_atomic

NAME = "fig3b"
SURFACE_RATIOS = (0.0, 0.25, 0.5, 0.75, 0.9)


def run(out_dir, quick=False):
    """Write fig3b.csv/.png/.pdf; return the largest |closed-form - quadrature| in c/a over both readings."""
    out_dir = Path(out_dir)
    # a fine tail near Q = mu P, where c/a creeps down to b/a; the last point is gross slip (c/a = 0)
    load_ratios = np.unique(np.concatenate([np.linspace(0.0, 0.95, 20 if quick else 96),
                                            1.0 - np.geomspace(0.05, 1e-6, 4 if quick else 24), [1.0]]))
    rows = []
    for b_over_a in SURFACE_RATIOS:
        stick = {}
        for reading in ("rounded_punch", "mdr_1d"):
            profile = flat_curved(b_over_a, reading=reading)
            stick[reading] = stick_ratio_profile(load_ratios, profile, method="closed_form")
            stick[reading + "_quadrature"] = stick_ratio_profile(load_ratios, profile)
        for i, x in enumerate(load_ratios):
            rows.append(dict(
                case=f"b/a={b_over_a:g}", b_over_a=b_over_a, load_ratio=x,
                stick_ratio=stick["rounded_punch"][i],
                stick_ratio_mdr_1d=stick["mdr_1d"][i],
                reading_gap=stick["mdr_1d"][i] - stick["rounded_punch"][i],
                stick_ratio_quadrature=stick["rounded_punch_quadrature"][i],
                stick_ratio_mdr_1d_quadrature=stick["mdr_1d_quadrature"][i],
                error=max(abs(stick["rounded_punch_quadrature"][i] - stick["rounded_punch"][i]),
                          abs(stick["mdr_1d_quadrature"][i] - stick["mdr_1d"][i])),
            ))
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    save_figure(_plot(rows), out_dir, NAME)
    return {"max_error": largest_abs(row["error"] for row in rows),
            "error_meaning": "largest |c/a closed-form P(a) - c/a MDR quadrature of f(r)|, both readings"}


def _plot(rows):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.8, 4.8))
    colors = plt.cm.plasma(np.linspace(0.0, 0.8, len(SURFACE_RATIOS)))
    for b_over_a, color in zip(SURFACE_RATIOS, colors):
        case = [row for row in rows if row["b_over_a"] == b_over_a and row["load_ratio"] < 1.0]
        x = [row["load_ratio"] for row in case]
        ax.plot(x, [row["stick_ratio"] for row in case], color=color, lw=1.9, label=f"b/a = {b_over_a:g}")
        ax.plot(x, [row["stick_ratio_mdr_1d"] for row in case], color=color, lw=1.0, ls="--")
        end = case[-1]["stick_ratio"]
        ax.plot([1.0, 1.0], [end, 0.0], color=color, lw=1.2, ls=":")            # the drop at gross slip
        ax.plot(1.0, end, "o", color=color, ms=5)
        ax.plot(1.0, 0.0, "o", color=color, mfc="white", ms=5)
    ax.plot([], [], color="gray", lw=1.9, label="rounded flat punch (3D)")
    ax.plot([], [], color="gray", lw=1.0, ls="--", label="flat+parabolic 1D MDR profile")
    ax.plot([], [], "o:", color="gray", label="drop b/a → 0 at Q = μP")
    ax.annotate("sudden drop:\nwhole contact slides", xy=(1.0, 0.62), xytext=(0.62, 0.25),
                arrowprops=dict(arrowstyle="->", color="0.3"), fontsize=9, color="0.2")
    ax.set(xlim=(0.0, 1.04), ylim=(0.0, 1.04), xlabel="load ratio Q / (μP)  [-]", ylabel="stick ratio c / a  [-]",
           title="Flat + curved cap: stick ratio falls to b/a, then drops to 0 (paper Fig. 3b)")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", frameon=False, fontsize=8.5, ncol=2)
    return fig
