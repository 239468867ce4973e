"""Fig. 2b: stick ratio c/a against Q/(mu P) for power-law profiles n = 1, 2, 3, 4, 8 and the flat-punch limit.

Closed form: paper eq. 3, c/a = (1 - Q/(mu P))^(1/(n+1)). Independent check: the Ciavarella-Jager principle
with the force curve P(rho) from MDR quadrature of the profile f(r) = C r^n (``stick_ratio_profile``).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from contact.theory import power_law, stick_ratio_profile, stick_ratio_translational
from studies._output import largest_abs, save_figure, write_csv_atomic

NAME = "fig2b"
ORDERS = (1, 2, 3, 4, 8)


def run(out_dir, quick=False):
    """Write fig2b.csv/.png/.pdf; return the largest |eq. 3 - MDR quadrature| in c/a."""
    out_dir = Path(out_dir)
    load_ratios = np.linspace(0.0, 1.0, 21 if quick else 201)
    rows = []
    for n in ORDERS:
        closed = stick_ratio_translational(load_ratios, n)
        quadrature = stick_ratio_profile(load_ratios, power_law(n))
        rows += [dict(case=f"n={n}", profile_order=n, load_ratio=x, stick_ratio=c, stick_ratio_mdr_quadrature=q,
                      error=q - c) for x, c, q in zip(load_ratios, closed, quadrature)]
    flat = stick_ratio_translational(load_ratios, math.inf)
    # no quadrature check for the flat punch (no finite gap profile); the columns stay empty
    rows += [dict(case="flat", profile_order=math.inf, load_ratio=x, stick_ratio=c) for x, c in zip(load_ratios, flat)]
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    save_figure(_plot(rows), out_dir, NAME)
    return {"max_error": largest_abs(row["error"] for row in rows if "error" in row),
            "error_meaning": "largest |c/a eq. 3 - c/a Ciavarella-Jager with MDR quadrature| over n = 1-8"}


def _plot(rows):
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    colors = plt.cm.viridis(np.linspace(0.0, 0.85, len(ORDERS)))
    for n, color in zip(ORDERS, colors):
        case = [row for row in rows if row["case"] == f"n={n}"]
        x = np.array([row["load_ratio"] for row in case])
        ax.plot(x, [row["stick_ratio"] for row in case], color=color, lw=1.8, label=f"n = {n}")
        every = max(len(case) // 10, 1)
        ax.plot(x[::every], [row["stick_ratio_mdr_quadrature"] for row in case][::every], "o", color=color,
                mfc="none", ms=5)
    ax.plot([0.0, 1.0, 1.0], [1.0, 1.0, 0.0], color="k", lw=1.8, ls="--", label="flat (n → ∞)")
    ax.plot([], [], "o", color="gray", mfc="none", label="MDR quadrature check")
    ax.set(xlim=(0.0, 1.02), ylim=(0.0, 1.04), xlabel="load ratio Q / (μP)  [-]", ylabel="stick ratio c / a  [-]",
           title="Stick ratio of power-law profiles f = C rⁿ (paper Fig. 2b, eq. 3)")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower left", frameon=False)
    return fig
