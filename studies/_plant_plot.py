"""Figure of the plant calibration: the FEM's per-bump base fields and how the response surface reproduces them."""

from __future__ import annotations

import numpy as np


def plot_plant_calibration(response, rows: list[dict], summary: dict):
    """2 x 2: unit normal fields of three bumps, the unit shear field of the centre bump, held-out CoP shifts
    (FEM against the response surface and the reduced model), field error against bump force."""
    import matplotlib.pyplot as plt
    from matplotlib.tri import Triangulation

    figure, axes = plt.subplots(2, 2, figsize=(11, 9.5))
    mesh = Triangulation(response.positions[:, 0], response.positions[:, 1], response.triangles)
    level = min(range(len(response.normal_levels)), key=lambda i: abs(response.normal_levels[i] - 1.0))
    bumps = (0, 1, 4)                                             # a corner, an edge and the centre bump
    normal = sum(response.normal_fields[i, level] for i in bumps)
    ax = axes[0, 0]
    shading = ax.tripcolor(mesh, 1e3 * normal, shading="gouraud", cmap="viridis")
    figure.colorbar(shading, ax=ax, label="base pressure per unit bump force [kPa / N]")
    ax.plot(*response.centres.T, "w+", ms=8)
    ax.set(title=f"unit normal fields of bumps {bumps} at P_i = {response.normal_levels[level]:.2f} N (FEM)",
           xlabel="x [mm]", ylabel="y [mm]", aspect="equal")
    ax = axes[0, 1]
    shear = response.shear_fields[4, min(1, len(response.shear_levels) - 1), 0]
    limit = np.abs(shear).max()
    shading = ax.tripcolor(mesh, 1e3 * shear, shading="gouraud", cmap="RdBu_r", vmin=-1e3 * limit, vmax=1e3 * limit)
    figure.colorbar(shading, ax=ax, label="base pressure per unit Q_x [kPa / N]")
    ax.set(title="unit shear field of the centre bump (Q along +x): the couple", xlabel="x [mm]", ylabel="y [mm]",
           aspect="equal")
    sheared = [row for row in rows if row["increment"] > 0]
    ax = axes[1, 0]
    fem = np.array([[row["cop_shift_fem_x"], row["cop_shift_fem_y"]] for row in sheared]).ravel()
    for label, key, marker in (("response surface", "response", "o"), ("reduced model (Gaussian kernel)", "reduced",
                                                                         "x")):
        model = np.array([[row[f"cop_shift_{key}_x"], row[f"cop_shift_{key}_y"]] for row in sheared]).ravel()
        ax.plot(fem, model, marker, ms=4, alpha=0.7, label=label)
    span = [fem.min(), fem.max()] if fem.size else [0, 1]
    ax.plot(span, span, "k-", lw=0.8)
    ax.set(title=f"held-out CoP shifts per bump and axis (largest error: response "
                 f"{100 * summary['largest_cop_shift_error']:.0f} %, reduced "
                 f"{100 * summary['largest_reduced_cop_shift_error']:.0f} %)",
           xlabel="FEM CoP shift in the bump's cell [mm]", ylabel="model [mm]")
    ax.legend(loc="upper left")
    ax = axes[1, 1]
    force = [row["normal_force"] for row in rows]
    ax.semilogy(force, [100 * row["field_error"] for row in rows], "o", ms=4, label="response surface")
    ax.semilogy(force, [100 * row["reduced_field_error"] for row in rows], "x", ms=4, label="reduced model")
    ax.set(title="held-out per-bump field error (relative L2)", xlabel="bump normal force P_i [N]",
           ylabel="error [%]")
    ax.legend()
    figure.suptitle(f"Plant calibration: the FEM's sensor-plane response of each bump "
                    f"({summary['mesh'].get('dofs')} DOF, {summary.get('wall_time', 0):.0f} s)")
    figure.tight_layout()
    return figure
