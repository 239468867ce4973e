"""Torsion theory: the paper's model (eq. 6 corrected and as printed) against the exact Hertz solution (Lubkin).

Stick ratio c/a against torque ratio T/(mu P a) at constant normal force. The paper's 1D spring model slides
as a whole at T = 3/8 mu P a, the exact 3D contact at 3 pi/16 mu P a (docs/theory.md, sec. 6). Second panel: the
paper's c/a minus the exact one, at equal torque and at equal fraction of each model's own full-slip torque.
Independent check: Lubkin's T(c) formula against the superposition of rigid-disc rotations,
T = (4 pi/3) int_c^a t^3 w(t) dt with w(t) = (2 mu p0/pi) E(k_t)/t, by QUADPACK.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from contact.theory import (
    LUBKIN_SLIP_TORQUE_RATIO, full_slip_torque_ratio, lubkin_torque_twist, stick_ratio_torsion, torsion_torque_ratio,
)
from studies._output import largest_abs, save_figure, write_csv_atomic

NAME = "torsion-theory"
MODELS = {"lubkin": "exact Hertz torsion (Lubkin 1951)", "paper": "paper eq. 6 corrected (outer √)",
          "paper_as_printed": "paper eq. 6 as printed"}


def run(out_dir, quick=False):
    """Write torsion-theory.csv/.png/.pdf; return the largest |T(c) formula - disc quadrature| / (mu P a)."""
    out_dir = Path(out_dir)
    slip = {model: full_slip_torque_ratio(model) for model in MODELS}
    # a uniform torque grid plus each model's own curve sampled in c/a in (0, 1], dense towards c = 0 (steep near
    # full slip); the full-slip torques themselves are added for the paper's models (the exact twist is infinite there)
    stick_grid = np.concatenate([np.linspace(0.0, 1.0, 11 if quick else 101)[1:],
                                 np.geomspace(1e-3, 0.2, 6 if quick else 40)])
    torque_ratios = np.unique(np.concatenate([np.linspace(0.0, 0.58, 30 if quick else 233), [slip["paper"]]]
                                             + [torsion_torque_ratio(stick_grid, model) for model in MODELS]))
    exact = stick_ratio_torsion(torque_ratios, "lubkin")
    # dimensionless twist theta G a^2 / (mu P) of the exact solution at each torque (P = mu = a = G = 1)
    twist = lubkin_torque_twist(exact, 1.0, 1.0, 1.0, 1.0)[1]
    rows = []
    for model in MODELS:
        stick = stick_ratio_torsion(torque_ratios, model)
        fraction = torque_ratios / slip[model]
        exact_same_fraction = stick_ratio_torsion(np.minimum(fraction, 1.0) * LUBKIN_SLIP_TORQUE_RATIO, "lubkin")
        rows += [dict(case=model, torque_ratio=t, stick_ratio=c, stick_ratio_lubkin=e, gap_vs_lubkin=c - e,
                      full_slip_torque_ratio=slip[model], slip_fraction=f, stick_ratio_lubkin_same_fraction=s,
                      gap_same_fraction=c - s, twist_lubkin_normalized=w)
                 for t, c, e, f, s, w in zip(torque_ratios, stick, exact, fraction, exact_same_fraction, twist)]
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    save_figure(_plot(rows, slip), out_dir, NAME)
    return {"max_error": _lubkin_quadrature_gap(np.linspace(0.02, 1.0, 6 if quick else 50)),
            "error_meaning": "largest |Lubkin T(c) formula - disc-superposition quadrature| / (mu P a)"}


def _lubkin_quadrature_gap(stick_ratios):
    """Largest |T(c)/(mu P a) of the package - (4 pi/3) int_c^a t^3 w dt / (mu P a) by scipy quad| (a = mu = P = 1)."""
    from scipy.integrate import quad
    from scipy.special import ellipe

    p0 = 3.0 / (2.0 * math.pi)
    w = lambda t: 2.0 * p0 / math.pi * ellipe(1.0 - t * t) / t
    reference = [4.0 * math.pi / 3.0 * quad(lambda t: t**3 * w(t), c, 1.0, epsabs=1e-14, epsrel=1e-13)[0]
                 for c in stick_ratios]
    return largest_abs(torsion_torque_ratio(stick_ratios) - np.array(reference))


def _plot(rows, slip):
    import matplotlib.pyplot as plt

    fig, (ax, gap_ax) = plt.subplots(1, 2, figsize=(12.0, 4.8), gridspec_kw=dict(width_ratios=(1.15, 1.0)))
    styles = {"lubkin": dict(color="k", lw=2.2), "paper": dict(color="tab:red", lw=1.8),
              "paper_as_printed": dict(color="tab:orange", lw=1.5, ls="--")}
    for model, label in MODELS.items():
        case = [row for row in rows if row["case"] == model]
        sticking = [row for row in case if row["torque_ratio"] <= slip[model]]
        t = [row["torque_ratio"] for row in sticking]
        ax.plot(t + [slip[model]], [row["stick_ratio"] for row in sticking] + [0.0], label=label, **styles[model])
        ax.plot(slip[model], 0.0, "o", color=styles[model]["color"], ms=5, clip_on=False)
        if model != "lubkin":
            gap_ax.plot(t, [row["gap_vs_lubkin"] for row in sticking], label=f"{label}: at equal T", **styles[model])
    paper = [row for row in rows if row["case"] == "paper" and row["slip_fraction"] <= 1.0]
    gap_ax.plot([row["torque_ratio"] for row in paper], [row["gap_same_fraction"] for row in paper], color="tab:red",
                lw=1.2, ls=":", label="eq. 6 corrected: at equal T / T_slip")
    for value, text, color in ((slip["paper"], "paper: 3/8 = 0.375", "tab:red"),
                               (LUBKIN_SLIP_TORQUE_RATIO, "exact: 3π/16 = 0.589", "k")):
        ax.axvline(value, color=color, lw=0.8, ls="-.", alpha=0.7)
        ax.annotate(f"full slip\n{text}", xy=(value, 0.9), xytext=(value - 0.012, 0.93), ha="right", fontsize=8.5,
                    color=color)
    ax.set(xlim=(0.0, 0.62), ylim=(0.0, 1.04), xlabel="torque ratio T / (μPa)  [-]", ylabel="stick ratio c / a  [-]",
           title="Stick ratio under torsion, Hertz contact (n = 2)")
    gap_ax.axhline(0.0, color="0.5", lw=0.8)
    gap_ax.axvline(slip["paper"], color="tab:red", lw=0.8, ls="-.", alpha=0.7)
    gap_ax.annotate("paper model slides (c/a = 0);\nexact c/a still 0.74", xy=(slip["paper"], -0.74),
                    xytext=(0.02, -0.5), fontsize=8.5, color="tab:red",
                    arrowprops=dict(arrowstyle="->", color="tab:red"))
    gap_ax.set(xlim=(0.0, 0.4), xlabel="torque ratio T / (μPa)  [-]",
               ylabel="c/a (paper) − c/a (exact)  [-]", title="Error of the paper's torsion model")
    for axis in (ax, gap_ax):
        axis.grid(alpha=0.3)
    ax.legend(loc="lower left", frameon=False, fontsize=9)
    gap_ax.legend(loc="lower left", frameon=False, fontsize=8.5)
    fig.tight_layout()
    return fig
