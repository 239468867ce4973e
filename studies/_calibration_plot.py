"""Figure of the reduced-calibration study: FEM points (fitted on, held out) against the closed-form and calibrated
reduced model (``studies.reduced_calibration``; the rows come from ``studies._calibration_rows``)."""

from __future__ import annotations

import numpy as np

from studies._calibration_rows import MODELS, QUANTITIES, SIGNALS, largest_cop_error, largest_error


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


def plot_calibration(samples, predicted, models, rows, cop, fitted, plan, wall):
    """Nine panels: depth and contact radius against P, shear and torque curves, per-bump CoP shift parity (cells,
    sensor), CoP error per held-out case, the couple arm against the bump force, held-out error per quantity."""
    import matplotlib.pyplot as plt

    fig, grid = plt.subplots(3, 3, figsize=(17, 14.5))
    axes = grid.ravel()
    held_out = {case.name for case in plan.held_out}
    _press_panels(axes[0], axes[1], samples, models, plan, held_out)
    _load_panels(axes[2], axes[3], samples, models, held_out)
    for axis, signal, letter in ((axes[4], "cells", "e"), (axes[5], "sensor", "f")):
        _parity_panel(axis, cop, signal, letter)
    _case_error_panel(axes[6], cop)
    _arm_panel(axes[7], samples, models, fitted)
    _quantity_panel(axes[8], rows, models)
    fig.suptitle(f"Reduced 3x3 fingertip calibrated on FEM (h = {plan.size_contact:g} mm, "
                 f"{fitted.parameters.source}); black: fitted on, orange squares: held out ({wall:.0f} s)")
    fig.tight_layout()
    return fig


def _press_panels(depth_axis, radius_axis, samples, models, plan, held_out):
    """(a) plate approach and (b) bump contact radius against the normal force."""
    forces = np.linspace(0.5, 1.1 * max(f for case in plan.calibration for f in case.press_forces), 60)
    count = models["closed_form"].design.bump_count
    press = [samples[c.name] for c in plan.calibration if c.press_forces]
    held = [samples[name] for name in held_out if not (~samples[name].pressed).any()]
    for axis, quantity in ((depth_axis, "depth"), (radius_axis, "radius")):
        for label in ("closed_form", "calibrated"):
            p = models[label].parameters
            curve = (forces / count / p.normal_stiffness) ** (2 / 3) if quantity == "depth" else \
                p.radius_coefficient * np.cbrt(forces / count)
            axis.plot(forces, curve, lw=1.6, **STYLES[label])
        for paths, marker, text in ((press, FIT_MARKER, "FEM, fitted on"), (held, HELD_MARKER, "FEM, held out")):
            for j, data in enumerate(paths):
                mask = data.pressed
                label = text if j == 0 else None
                if quantity == "depth":
                    axis.plot(data.normal_force[mask], data.depth[mask], label=label, **marker)
                    continue
                radius = data.bump_contact_radius[mask]
                mean = radius.mean(axis=1)
                axis.errorbar(data.normal_force[mask], mean, yerr=[mean - radius.min(axis=1),
                              radius.max(axis=1) - mean], capsize=3,
                              label=label and label + " (mean, min-max of the bumps)", **marker)
        axis.set_xlabel("normal force P [N]")
        axis.set_ylabel("plate approach d [mm]" if quantity == "depth" else "bump contact radius a_i [mm]")
        axis.set_title("(a) depth: P/k = k_n d^1.5" if quantity == "depth" else "(b) a_i = c_a (P/k)^(1/3)",
                       fontsize=10)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=7)


def _load_panels(shear_axis, twist_axis, samples, models, held_out):
    """(c) array tangential force against plate shift, (d) torque against twist, over mu P, for pure paths."""
    import matplotlib.pyplot as plt

    pure = {}
    for name, data in samples.items():
        kinds = set(data.load_kind[~data.pressed])
        if len(kinds) == 1:
            pure[name] = kinds.pop()
    forces = sorted({round(float(samples[name].normal_force[-1]), 6) for name in pure})
    colours = {force: plt.cm.plasma(0.85 * j / max(len(forces) - 1, 1)) for j, force in enumerate(forces)}
    mu = next(iter(samples.values())).friction
    reach = {"shear": 0.0, "twist": 0.0}
    for name, kind in pure.items():
        data = samples[name]
        tangential = ~data.pressed
        force = round(float(data.normal_force[-1]), 6)
        marker = dict(HELD_MARKER if name in held_out else FIT_MARKER, color=colours[force], mec=colours[force])
        if kind == "shear":
            shift = np.linalg.norm(data.shift[tangential], axis=1)
            load = np.linalg.norm(data.tangential_force[tangential], axis=1)
            shear_axis.plot(shift, load / (mu * force), label=f"FEM {name}", **marker)
            reach["shear"] = max(reach["shear"], shift.max())
        else:
            angle = np.abs(data.angle[tangential])
            twist_axis.plot(angle * 1e3, np.abs(data.torque[tangential]) / (mu * force), label=f"FEM {name}",
                            **marker)
            reach["twist"] = max(reach["twist"], angle.max())
    shifts = np.linspace(0.0, 1.1 * reach["shear"], 80)
    angles = np.linspace(0.0, 1.1 * reach["twist"], 80)
    for force, colour in colours.items():
        for label in ("closed_form", "calibrated"):
            shear, torque = _force_curves(models[label], force, shifts, angles, mu)
            kwargs = dict(color=colour, ls=STYLES[label]["ls"], lw=1.4)
            shear_axis.plot(shifts, shear / (mu * force), **kwargs)
            twist_axis.plot(angles * 1e3, torque / (mu * force), **kwargs)
    for axis, xlabel, ylabel, title in (
            (shear_axis, "plate shift [mm]", "|F| / (mu P) [-]", "(c) shear: dashed closed form, solid calibrated"),
            (twist_axis, "plate twist [mrad]", "|T| / (mu P) [mm]", "(d) twist: dashed closed form, solid calibrated")):
        for force, colour in colours.items():
            axis.plot([], [], color=colour, label=f"P = {force:g} N")
        axis.set_xlabel(xlabel)
        axis.set_ylabel(ylabel)
        axis.set_title(title, fontsize=10)
        axis.grid(alpha=0.3)
        axis.legend(fontsize=6)


def _parity_panel(axis, cop, signal, letter):
    """Per-bump CoP shift of the calibrated model (its own bump loads) against the FEM, x and y, one signal."""
    reach = 0.0
    for role, marker in (("calibration", dict(marker="o", mfc="none", color="#636363", ms=3.5, alpha=0.6)),
                         ("held_out", dict(marker="s", color="#e6550d", ms=3.5, alpha=0.8))):
        chosen = [r for r in cop if r["signal"] == signal and r["role"] == role]
        fem = np.array([r["fem"] for r in chosen])
        for label, colour in (("model", None), ("closed_form", "#bdbdbd")):
            model = np.array([r[label] for r in chosen])
            style = dict(marker, color=colour) if colour else marker
            axis.plot(fem, model, ls="none", **style,
                      label=f"{role.replace('_', ' ')}, {'calibrated' if label == 'model' else 'closed form'}")
        reach = max(reach, np.abs(fem).max(initial=0.0))
    line = np.array([-reach, reach]) * 1.05
    axis.plot(line, line, "k:", lw=1, label="reduced = FEM")
    error = largest_cop_error(cop, "model", signal)
    where = "bump cells of the sensor plane" if signal == "cells" else "11 x 13 sensor + estimator"
    axis.set_title(f"({letter}) per-bump CoP shift, x and y, {where}\nheld-out max |error| {100 * error:.1f} % "
                   f"of the increment's largest shift", fontsize=10)
    axis.set_xlabel("FEM CoP shift [mm]")
    axis.set_ylabel("reduced CoP shift [mm]")
    axis.grid(alpha=0.3)
    axis.legend(fontsize=6)


def _case_error_panel(axis, cop):
    """(g) largest |CoP error| per held-out case: model chain and its base pressure on FEM loads, both signals."""
    cases = sorted({r["case"] for r in cop if r["role"] == "held_out"})
    bars = [(signal, label) for signal in SIGNALS for label in ("model", "model_fem_loads")]
    width = 0.8 / len(bars)
    colours = {("cells", "model"): "#3182bd", ("cells", "model_fem_loads"): "#9ecae1",
               ("sensor", "model"): "#e6550d", ("sensor", "model_fem_loads"): "#fdae6b"}
    for j, (signal, label) in enumerate(bars):
        values = [100 * largest_cop_error([r for r in cop if r["case"] == case], label, signal) for case in cases]
        position = np.arange(len(cases)) + (j - (len(bars) - 1) / 2) * width
        text = f"{signal}, {'reduced model' if label == 'model' else 'its base pressure on FEM bump loads'}"
        axis.bar(position, values, width, color=colours[(signal, label)], label=text)
    axis.axhline(10.0, color="k", ls="--", lw=1, label="10 % target")
    axis.set_xticks(np.arange(len(cases)), cases, rotation=30, ha="right", fontsize=7)
    axis.set_ylabel("largest |CoP error| / largest FEM shift [%]")
    axis.set_title("(g) held-out per-bump CoP shift error per case (both axes)", fontsize=10)
    axis.grid(alpha=0.3, axis="y")
    axis.legend(fontsize=6)


def _arm_panel(axis, samples, models, fitted):
    """(h) the couple arm h(P_i) against the bump force; FEM: the whole base's first-moment change over Q."""
    top = 0.0
    for name, data in samples.items():
        kinds = set(data.load_kind[~data.pressed])
        if kinds != {"shear"}:
            continue
        total = data.base_force[..., None] * data.base_centre                   # first moments per cell (t, k, 2)
        moment = total.sum(axis=1) - total.sum(axis=1)[data.reference]
        force = data.tangential_force
        tangential = ~data.pressed & (np.linalg.norm(force, axis=1) > 0.0)
        arm = (moment * force).sum(axis=1)[tangential] / (force**2).sum(axis=1)[tangential]
        bump_force = data.normal_force[tangential] / data.bump_normal_force.shape[1]
        axis.plot(bump_force, arm, **FIT_MARKER, label="FEM: base first moment / Q" if top == 0.0 else None)
        top = max(top, bump_force.max())
    forces = np.linspace(0.0, max(1.2 * top, 2.5), 100)
    for label in ("closed_form", "calibrated"):
        axis.plot(forces, models[label].parameters.couple_arm_at(forces), lw=1.6, **STYLES[label])
    p = fitted.parameters
    axis.axhline(p.couple_arm_limit, color="k", ls=":", lw=1, label="h_inf = H / 2")
    axis.axvspan(0.0, top, color="#f0f0f0", label="bump forces of the paths")
    axis.set_xlabel("bump normal force P_i [N]")
    axis.set_ylabel("couple arm h [mm]")
    axis.set_title(f"(h) couple M_i = h(P_i) Q_i + g P_i delta_i: h_0 = {p.couple_arm:.3g} mm,\nkappa = "
                   f"{p.couple_arm_slope:.3g} mm/N, g = {p.displacement_gain:.2g}; kernel sigma = "
                   f"{p.kernel_width:.3g} mm", fontsize=10)
    axis.grid(alpha=0.3)
    axis.legend(fontsize=7)


def _quantity_panel(axis, rows, models):
    """(i) largest held-out relative error per quantity and model."""
    labels = [label for label in MODELS if label in models]
    shown = [q for q in QUANTITIES if q != "base_total_force"]       # equal to P by construction in the model
    width = 0.8 / len(labels)
    for j, label in enumerate(labels):
        values = [100 * largest_error(rows, label, q) for q in shown]
        position = np.arange(len(shown)) + (j - (len(labels) - 1) / 2) * width
        axis.bar(position, values, width, color=STYLES[label]["color"], label=STYLES[label]["label"])
        for x, value in zip(position, values):
            axis.text(x, value * 1.08, f"{value:.0f}" if value >= 10 else f"{value:.1f}", ha="center", fontsize=6)
    axis.set_xticks(np.arange(len(shown)), [q.replace("_", " ") for q in shown], rotation=30, ha="right", fontsize=8)
    axis.set_yscale("log")
    axis.set_ylabel("largest |relative error| on held-out cases [%]")
    axis.set_title("(i) held-out error per quantity (CoP shift as a vector; base force exact in both)", fontsize=10)
    axis.grid(alpha=0.3, axis="y")
    axis.legend(fontsize=7)


STYLES = {"closed_form": dict(color="#969696", ls="--", label="reduced, closed form"),
          "calibrated": dict(color="#3182bd", ls="-", label="reduced, FEM-calibrated"),
          "packaged": dict(color="#31a354", ls=":", label="reduced, packaged file")}
FIT_MARKER = dict(marker="o", ls="none", color="k", ms=5)
HELD_MARKER = dict(marker="s", ls="none", mfc="none", mec="#e6550d", ms=6, mew=1.4)
