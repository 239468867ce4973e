"""The finite-strain study's figure: the models' curves above, each quantity's error against its tolerance below
(inside the grey band the small-strain FEM holds): the press against CalculiX's Neo-Hookean gel (and the FEM's own
Neo-Hookean gel against it, open markers), shear and twist against GetFEM's Neo-Hookean gel (the FEM's own where
GetFEM did not run; open markers: the FEM's Neo-Hookean gel against GetFEM's) at the 1.5 N hold (solid) and the
2.6 N peak (dashed), where CalculiX's does not converge."""

from __future__ import annotations

import numpy as np

__all__ = ["plot"]

STYLE = {"fem_linear": dict(color="k", lw=1.8, label="project FEM, linear"),
         "calculix_linear": dict(color="tab:blue", lw=1.4, ls="--", label="CalculiX, linear"),
         "calculix_neo_hooke": dict(color="tab:red", lw=1.6, label="CalculiX, Neo-Hookean (NLGEOM)"),
         "fem_neo_hooke": dict(color="tab:green", lw=1.6, ls="-.", label="project FEM, Neo-Hookean"),
         "getfem_neo_hooke": dict(color="tab:purple", lw=1.4, ls="--", label="GetFEM, Neo-Hookean (same mesh)")}
QUANTITY_STYLE = {"normal_force": ("tab:purple", "o"), "contact_radius": ("tab:green", "s"),
                  "base_pressure_spread": ("tab:gray", "D"),
                  "tangential_compliance": ("tab:orange", "o"), "stick_ratio": ("tab:blue", "s"),
                  "base_cop_shift": ("tab:brown", "^"), "torsional_compliance": ("tab:orange", "o"),
                  "stick_ratio_twist": ("tab:blue", "s")}


def _band(axis, top, reference):
    axis.axhspan(-1.0, 1.0, color="0.88", zorder=0)
    axis.axhline(0.0, color="0.5", lw=0.8)
    axis.set_ylim(-max(2.5, top), max(2.5, top))
    axis.set_ylabel(f"(linear FEM - {reference}) / tolerance")
    axis.grid(alpha=0.3)


def _errors(axis, rows, problems, title, xlabel, error="judged_error", reference="Neo-Hookean"):
    """Each quantity's ``error`` over its tolerance against the load; ``problems``: (problem, line style, note)."""
    top = 0.0
    if not any(r["problem"] == problem and np.isfinite(r[error]) for r in rows for problem, _, _ in problems):
        axis.text(0.5, 0.5, "no Neo-Hookean result (see the summary's calculix_failed and fem_stopped)", ha="center",
                  transform=axis.transAxes, fontsize=8)
    for problem, line, note in problems:
        for quantity in dict.fromkeys(r["quantity"] for r in rows if r["problem"] == problem):
            series = sorted((r for r in rows if r["problem"] == problem and r["quantity"] == quantity
                             and np.isfinite(r[error])), key=lambda r: r["load"])
            if not series:
                continue
            ratio = np.array([r[error] / r["tolerance"] for r in series])
            colour, marker = QUANTITY_STYLE[quantity]
            axis.plot([r["load"] for r in series], ratio, marker=marker, ls=line, color=colour, ms=4,
                      label=f"{quantity.replace('_', ' ')} ({series[0]['tolerance']:g}"
                            f"{'' if series[0]['relative_error'] else ' in c/a'}){note}")
            top = max(top, float(np.abs(ratio).max()) * 1.1)
    _band(axis, top, reference)
    axis.set_xlabel(xlabel)
    axis.set_title(title, fontsize=9)
    if axis.get_legend_handles_labels()[0]:
        axis.legend(fontsize=6.5, loc="lower left")


def _load_ratio_curves(axis, kind: str, abscissa: str, load: str, fem_paths, fem_neo, calculix,
                       friction: float) -> None:
    """One curve per solver of a ``kind`` path ("shear" or "twist"): ``load`` / (mu P) against ``abscissa``;
    ``calculix``: the reference codes' records by (path, model)."""
    own = {"fem_linear": fem_paths, "fem_neo_hooke": fem_neo}
    for name in STYLE:
        if name not in own and (kind, name) not in calculix:
            continue
        items = own[name][kind] if name in own else [vars(r) for r in calculix[kind, name]]
        items = [i for i in items if i["load_kind"] == kind]
        axis.plot([i[abscissa] for i in items], [i[load] / (friction * i["normal_force"]) for i in items],
                  marker=".", **STYLE[name])


def plot(rows, fem_sphere, calculix, fem_paths, fem_neo, sphere, bump, wall):
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 3, figsize=(14.5, 8.6))
    # press: force against depth, the layer and the bump
    axis = axes[0, 0]
    depth = np.array(fem_sphere)
    axis.plot(depth[:, 0] / sphere.sphere_radius, depth[:, 1], **STYLE["fem_linear"])
    fem_press = np.array([(r["depth"], r["normal_force"]) for r in fem_paths["press"]])
    axis.plot(fem_press[:, 0] / bump.bump_radius, fem_press[:, 1], color="k", lw=1.8, ls=":")
    neo_press = np.array([(r["depth"], r["normal_force"]) for r in fem_neo["press"]])
    axis.plot(neo_press[:, 0] / bump.bump_radius, neo_press[:, 1], **dict(STYLE["fem_neo_hooke"], ls=":"))
    for name in ("calculix_linear", "calculix_neo_hooke"):
        for problem, radius, line in (("sphere", sphere.sphere_radius, "-"), ("press", bump.bump_radius, ":")):
            if (problem, name) in calculix:
                curve = np.array([(r.depth, r.normal_force) for r in calculix[problem, name]])
                style = dict(STYLE[name], ls=line, label=STYLE[name]["label"] if line == "-" else None)
                axis.plot(curve[:, 0] / radius, curve[:, 1], **style)
    axis.axhline(2.6, color="0.6", lw=0.8)
    axis.text(0.01, 2.65, "closed loop's peak bump force 2.6 N", fontsize=7, color="0.4")
    axis.set(xlabel="depth / radius  d/R", ylabel="normal force P [N]",
             title="Press: sphere into a 10 mm layer (solid), bump under a plate (dotted, CalculiX axisymmetric)")
    axis.title.set_fontsize(9)
    axis.legend(fontsize=7, loc="upper left")
    # shear: load ratio against shift
    axis = axes[0, 1]
    _load_ratio_curves(axis, "shear", "shift", "tangential_force", fem_paths, fem_neo, calculix,
                       bump.friction_coefficient)
    axis.set(xlabel="plate shift [mm] (depth held)", ylabel="load ratio Q / (mu P)",
             title=f"Bump sheared at the depth of {PEAK_TEXT}", ylim=(0, 1.05))
    axis.title.set_fontsize(9)
    axis.legend(fontsize=7, loc="lower right")
    # twist: torque ratio against angle
    axis = axes[0, 2]
    _load_ratio_curves(axis, "twist", "angle", "torque", fem_paths, fem_neo, calculix, bump.friction_coefficient)
    axis.set(xlabel="plate twist [rad] (depth held)", ylabel="T / (mu P)  [mm]",
             title=f"Bump twisted at the depth of {PEAK_TEXT}")
    axis.title.set_fontsize(9)
    for axis in axes[0]:
        axis.grid(alpha=0.3)
    _errors(axes[1, 0], rows, (("sphere_press", ":", " - layer"), ("bump_press", "-", "")),
            "Press vs CalculiX Neo-Hookean (open: FEM Neo-Hookean vs it)",
            "depth / radius  d/R")
    for quantity in ("normal_force", "contact_radius"):
        series = sorted((r for r in rows if r["problem"] == "bump_press" and r["quantity"] == quantity
                         and np.isfinite(r["error_fem_neo_hooke_vs_neo_hooke"])), key=lambda r: r["load"])
        colour, marker = QUANTITY_STYLE[quantity]
        axes[1, 0].plot([r["load"] for r in series],
                        [r["error_fem_neo_hooke_vs_neo_hooke"] / r["tolerance"] for r in series], marker=marker,
                        ls="--", color=colour, ms=5, mfc="none", lw=0.8)
    # each shear and twist quantity against the gel that bounds it: GetFEM's where it judged it, else the FEM's own
    independent = any(np.isfinite(r["judged_error_getfem"]) for r in rows)
    shear_and_twist = [dict(r, bounding_error=r["judged_error_getfem"] if np.isfinite(r["judged_error_getfem"])
                            else r["error_fem_vs_fem_neo_hooke"])
                       for r in rows if r["problem"].startswith(("bump_shear", "bump_twist"))]
    against = ("GetFEM's Neo-Hookean gel\n(stick ratios: the FEM's own; open: FEM Neo-Hookean vs GetFEM)" if independent
               else "the FEM's Neo-Hookean gel")
    for axis, path, ratio in ((axes[1, 1], "shear", "load ratio Q / (mu P)"),
                              (axes[1, 2], "twist", "T / (mu P a)  [-]")):
        _errors(axis, shear_and_twist, ((f"bump_{path}", "-", " 1.5 N"), (f"bump_{path}_peak", "--", " 2.6 N")),
                f"{path.capitalize()} vs {against}", ratio, error="bounding_error", reference="Neo-Hookean")
        for problem, line in ((f"bump_{path}", "-"), (f"bump_{path}_peak", "--")):
            for quantity in dict.fromkeys(r["quantity"] for r in rows if r["problem"] == problem
                                          and not r["quantity"].startswith("stick_ratio")):     # GetFEM's reads low
                series = sorted((r for r in rows if r["problem"] == problem and r["quantity"] == quantity
                                 and np.isfinite(r["error_fem_neo_hooke_vs_getfem_neo_hooke"])),
                                key=lambda r: r["load"])
                colour, marker = QUANTITY_STYLE[quantity]
                axis.plot([r["load"] for r in series],
                          [r["error_fem_neo_hooke_vs_getfem_neo_hooke"] / r["tolerance"] for r in series],
                          marker=marker, ls=line, color=colour, ms=5, mfc="none", lw=0.6)
    outside = sorted({r["quantity"].replace("_", " ") for r in rows if r["problem"] != "sphere_press"
                      and r.get("resolved", True) and (
                          (np.isfinite(r["judged_error"]) and not r["within_tolerance"])
                          or (r["problem"].startswith(("bump_shear", "bump_twist"))
                              and abs(r["judged_error_getfem"] if np.isfinite(r["judged_error_getfem"])
                                      else r["error_fem_vs_fem_neo_hooke"]) > r["tolerance"]))})
    fig.suptitle("Small strain against finite strain (compressible Neo-Hookean): "
                 + (f"outside at the paper's loads: {', '.join(outside)}" if outside else
                    "every quantity within its tolerance at the paper's loads") + f"  ({wall:.0f} s)", fontsize=10)
    fig.tight_layout()
    return fig


PEAK_TEXT = "1.5 N (FEM)"
