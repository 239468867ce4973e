"""Figure of the reduced-calibration study: FEM points (fitted on, held out) against the closed-form and calibrated
reduced model (``studies.reduced_calibration``)."""

from __future__ import annotations

import numpy as np

from studies.reduced_calibration import MODELS, QUANTITIES, largest_error


def _force_curves(tip, normal_force, shifts, angles, friction):
    """Model array force F_x [N] along a plate shift and torque [N mm] along a twist at P [N] (untilted)."""
    from contact.reduced import bump_response, normal_split

    count = len(tip.centres)
    bump_force = normal_split(np.full(len(shifts), normal_force), tip.centres, tip.parameters)
    shear = bump_response(bump_force, tip.bump_shear(np.column_stack([shifts, 0 * shifts]), 0 * shifts),
                          np.zeros((len(shifts), count)), friction, tip.parameters)
    twist = bump_response(bump_force, tip.bump_shear(np.zeros((len(angles), 2)), angles),
                          np.repeat(angles[:, None], count, axis=1), friction, tip.parameters)
    return tip.wrench(shear)[0][:, 0], tip.wrench(twist)[1]


def plot_calibration(samples, predicted, models, rows, fitted, plan, wall):
    """Six panels: depth and contact radius against P, shear force and torque curves, CoP parity, error bars."""
    import matplotlib.pyplot as plt

    styles = {"closed_form": dict(color="#969696", ls="--", label="reduced, closed form"),
              "calibrated": dict(color="#3182bd", ls="-", label="reduced, FEM-calibrated"),
              "packaged": dict(color="#31a354", ls=":", label="reduced, packaged file")}
    fit_marker = dict(marker="o", ls="none", color="k", ms=5)
    held_marker = dict(marker="s", ls="none", mfc="none", mec="#e6550d", ms=6, mew=1.4)
    fig, axes = plt.subplots(2, 3, figsize=(16, 9.6))
    press = samples["press"]
    held_press = next((samples[n] for n in predicted if not (~samples[n].pressed).any()), None)
    forces = np.linspace(0.5, 1.1 * max(plan.press_forces), 60)
    mu = press.friction
    count = models["closed_form"].design.bump_count
    # (a) depth, (b) contact radius against the normal force
    for axis, quantity in ((axes[0, 0], "depth"), (axes[0, 1], "radius")):
        for label in ("closed_form", "calibrated"):
            p = models[label].parameters
            curve = (forces / count / p.normal_stiffness) ** (2 / 3) if quantity == "depth" else \
                p.radius_coefficient * np.cbrt(forces / count)
            axis.plot(forces, curve, lw=1.6, **{k: v for k, v in styles[label].items()})
        for data, marker, text in ((press, fit_marker, "FEM, fitted on"), (held_press, held_marker, "FEM, held out")):
            if data is None:
                continue
            mask = data.pressed
            if quantity == "depth":
                axis.plot(data.normal_force[mask], data.depth[mask], label=text, **marker)
            else:
                radius = data.bump_contact_radius[mask]
                mean = radius.mean(axis=1)
                spread = [mean - radius.min(axis=1), radius.max(axis=1) - mean]
                axis.errorbar(data.normal_force[mask], mean, yerr=spread, capsize=3,
                              label=text + " (mean, min-max of 9 bumps)", **marker)
        axis.set_xlabel("normal force P [N]")
        axis.set_ylabel("plate approach d [mm]" if quantity == "depth" else "bump contact radius a_i [mm]")
        axis.set_title("(a) depth: P/9 = k_n d^1.5" if quantity == "depth" else "(b) a_i = c_a (P/9)^(1/3)",
                       fontsize=10)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    # (c) shear force against plate shift, (d) torque against twist, normalised by mu P
    shifts = np.linspace(0.0, 1.1 * max(max(values) for _, values in plan.shear_paths), 80)
    angles = np.linspace(0.0, 1.1 * max(plan.angles), 80)
    colours = {}
    for name, data in samples.items():
        if name == "press" or not (~data.pressed).any():
            continue
        colours.setdefault(round(float(data.normal_force[-1]), 6), None)
    colours = {force: plt.cm.plasma(0.85 * j / max(len(colours) - 1, 1)) for j, force in enumerate(sorted(colours))}
    for force, colour in colours.items():
        for label in ("closed_form", "calibrated"):
            shear, torque = _force_curves(models[label], force, shifts, angles, mu)
            kwargs = dict(color=colour, ls=styles[label]["ls"], lw=1.4)
            axes[0, 2].plot(shifts, shear / (mu * force), **kwargs)
            axes[1, 0].plot(angles * 1e3, torque / (mu * force), **kwargs)
    for name, data in samples.items():
        tangential = ~data.pressed
        if name == "press" or not tangential.any():
            continue
        force = round(float(data.normal_force[-1]), 6)
        marker = dict(fit_marker if name not in predicted else held_marker, color=colours[force],
                      mec=colours[force])
        is_shear, is_twist = data.load_kind == "shear", data.load_kind == "twist"
        if is_shear.any() and not is_twist.any():
            axes[0, 2].plot(data.shift[is_shear, 0], data.tangential_force[is_shear, 0] / (mu * force),
                            label=f"FEM {name}", **marker)
        if is_twist.any() and not is_shear.any():
            axes[1, 0].plot(data.angle[is_twist] * 1e3, data.torque[is_twist] / (mu * force), label=f"FEM {name}",
                            **marker)
    for axis, xlabel, ylabel, title in (
            (axes[0, 2], "plate shift [mm]", "F_x / (mu P) [-]", "(c) shear: dashed closed form, solid calibrated"),
            (axes[1, 0], "plate twist [mrad]", "T / (mu P) [mm]", "(d) twist: dashed closed form, solid calibrated")):
        for force, colour in colours.items():
            axis.plot([], [], color=colour, label=f"P = {force:g} N")
        axis.set_xlabel(xlabel)
        axis.set_ylabel(ylabel)
        axis.set_title(title, fontsize=10)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)
    # (e) base-pressure CoP shift per bump, held-out increments: reduced against FEM (x and y components)
    axis = axes[1, 1]
    reach = 0.0
    for name, by_model in predicted.items():
        data = samples[name]
        tangential = ~data.pressed
        if not tangential.any():
            continue
        fem_cop = data.cop_shift[tangential].ravel()
        reach = max(reach, np.abs(fem_cop).max())
        for label in ("closed_form", "calibrated"):
            axis.plot(fem_cop, by_model[label].cop_shift[tangential].ravel(), "o", ms=3, alpha=0.7,
                      color=styles[label]["color"])
    line = np.array([-reach, reach]) * 1.05
    axis.plot(line, line, "k:", lw=1, label="reduced = FEM")
    for label in ("closed_form", "calibrated"):
        axis.plot([], [], "o", color=styles[label]["color"], label=styles[label]["label"])
    p = fitted.parameters
    axis.set_title(f"(e) held-out CoP shift per bump (x, y): g = {p.cop_gain:.3g}, h = {p.moment_arm:.3g} mm",
                   fontsize=10)
    axis.set_xlabel("FEM CoP shift [mm]")
    axis.set_ylabel("reduced CoP shift [mm]")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7)
    # (f) largest held-out relative error per quantity and model
    axis = axes[1, 2]
    labels = [label for label in MODELS if label in models]
    shown = [q for q in QUANTITIES if q != "base_total_force"]       # equal to P by construction in the model
    width = 0.8 / len(labels)
    for j, label in enumerate(labels):
        values = [100 * largest_error(rows, label, q) for q in shown]
        position = np.arange(len(shown)) + (j - (len(labels) - 1) / 2) * width
        axis.bar(position, values, width, color=styles[label]["color"], label=styles[label]["label"])
        for x, value in zip(position, values):
            axis.text(x, value * 1.08, f"{value:.0f}" if value >= 10 else f"{value:.1f}", ha="center", fontsize=6)
    axis.set_xticks(np.arange(len(shown)), [q.replace("_", " ") for q in shown], rotation=30, ha="right", fontsize=8)
    axis.set_yscale("log")
    axis.set_ylabel("largest |relative error| on held-out cases [%]")
    axis.set_title("(f) held-out error per quantity (base force: exact in both)", fontsize=10)
    axis.grid(alpha=0.3, axis="y")
    axis.legend(fontsize=7)
    fig.suptitle(f"Reduced 3x3 fingertip calibrated on FEM (h = {plan.size_contact:g} mm, "
                 f"{fitted.parameters.source}); black: fitted on, orange squares: held out ({wall:.0f} s)")
    fig.tight_layout()
    return fig
