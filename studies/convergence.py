"""Convergence: error against run time for element size, element order and number of shear increments, on HCM-1
and on the 3x3 fingertip of Figs. 6 and 9 (studies/_convergence_array.py; not in --quick), each knee marked.

HCM-1 errors (largest over the shear increments): the stick ratio read two ways, from nodal tributary areas
(``stick_ratio``, quantised to about h/a) and recovered below the element size (``recovered_stick_ratio``,
contact.recovery), each against Cattaneo-Mindlin and against the coupled half-space reference that solves the same
load path with the full Boussinesq-Cerruti coupling (contact.halfspace; their difference is the coupling offset);
contact radius and peak pressure, nodal and recovered, against Hertz; tangential shift against Mindlin. A second
element-size series at nu = 0.49 with the locking-free nodal-average P1 shows the nearly uncoupled case. Wall and
CPU time are the whole solve (mesh, assembly, factorization, contact path).

Settings: the default runs HCM-1 at h = 0.35 ... 0.14 mm (the knee is 0.2 mm = a/5; one size finer, two coarser),
P2 at one size, 1 and 5 shear increments, nu = 0.49 at 0.35 / 0.2 / 0.14 mm, the coupled reference on a/15 cells
and the 3x3 fingertip down to 0.4 mm: 94 s on 2 cores (measured). ``--full`` adds HCM-1 at 0.1 and 0.07 mm (a/10,
where issue 19's peak-pressure target is set; up to 191k DOF), P2 at 0.17 and 0.12 mm, 2 and 10 increments at
0.15 mm, nu = 0.49 at 0.25 and 0.1 mm, the fingertip at 0.3 mm and the reference on a/21 cells: 584 s (measured,
peak memory 6.4 GB).
``--quick``: two P1 sizes, no fingertip.
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

import numpy as np

from studies._convergence_array import ARRAY_STUDIES, array_cases, solve_array_case, solve_timed
from studies._output import save_figure, write_csv_atomic

NAME = "convergence"
SCENE = Path(__file__).parent / "scenes" / "hcm1.toml"
TARGET_STICK_RATIO_ERROR = 0.01         # issue 19: recovered c/a against the coupled reference, at h = a/5
TARGET_PEAK_PRESSURE_ERROR = 0.03       # recovered p_max against Hertz: the 3 % Hertz tolerance of linear elements
KNEE_FACTOR = 1.15                      # 3x3 fingertip knee: cheapest mesh within 15 % of the best one
REFERENCE_SPACING = 0.05                # mm, half-space cells (a/21): recovered c/a within 0.002 of a/15 cells
DEFAULT_REFERENCE_SPACING = 0.07        # mm (a/15): within 0.001 of a/21 on HCM-1's path, a quarter of its time
QUICK_REFERENCE_SPACING = 0.1           # mm (a/11): within 0.003 of a/21 at nu = 0.45
SIZE_STUDY = "element size (P1)"
NEARLY_INCOMPRESSIBLE_STUDY = "element size (P1 nodal-average, nu = 0.49)"


# element sizes [mm] per setting; bisection refines by levels: these give distinct top-surface spacings (0.3 and
# 0.25 would not). Default: a/5 and the sizes around it, 94 s on 2 cores; --full adds the fine meshes (0.1 and
# 0.07 mm, up to 191k DOF) and the long P2 and 3x3 cases.
SIZES = {"quick": (0.35, 0.25), "default": (0.35, 0.25, 0.2, 0.14), "full": (0.35, 0.25, 0.2, 0.14, 0.1, 0.07)}
QUADRATIC_SIZES = {"quick": (0.35,), "default": (0.35,), "full": (0.35, 0.17, 0.12)}   # P2 tets are twice these
INCREMENTS = {"quick": (1, 5), "default": (1, 5), "full": (1, 2, 5, 10)}     # each path needs its own reference
INCREMENT_SIZE = {"quick": 0.25, "default": 0.2, "full": 0.15}     # mm
NEARLY_INCOMPRESSIBLE_SIZES = {"quick": (0.35,), "default": (0.35, 0.2, 0.14), "full": (0.35, 0.25, 0.2, 0.14, 0.1)}


def setting_name(quick: bool, full: bool) -> str:
    """"quick", "default" or "full" (--quick and --full together are refused)."""
    if quick and full:
        raise ValueError("--quick and --full exclude each other: choose one")
    return "quick" if quick else ("full" if full else "default")


def _cases(setting: str) -> list[dict]:
    cases = [dict(study=SIZE_STUDY, size_contact=h, order=1, n_shear=5) for h in SIZES[setting]]
    cases += [dict(study="element order (P2)", size_contact=h, order=2, n_shear=5) for h in QUADRATIC_SIZES[setting]]
    cases += [dict(study="shear increments", size_contact=INCREMENT_SIZE[setting], order=1, n_shear=n)
              for n in INCREMENTS[setting]]
    cases += [dict(study=NEARLY_INCOMPRESSIBLE_STUDY, size_contact=h, order=1, n_shear=5, nu=0.49,
                   volumetric="nodal_average") for h in NEARLY_INCOMPRESSIBLE_SIZES[setting]]
    return cases


def hcm1_case_scene(size_contact: float, order: int = 1, n_shear: int = 5, nu: float | None = None,
                    volumetric: str | None = None):
    """HCM-1 with the given mesh (and material) and ``n_shear`` equal shear increments to Q/(mu P) = 0.9; the
    scene and its load ratios."""
    from contact.scene import load_scene

    scene = load_scene(SCENE)
    press, shear = scene.loads
    force, mu = press.values[0], scene.contact.friction_coefficient
    ratios = max(shear.values) / (mu * force) * np.arange(1, n_shear + 1) / n_shear
    mesh = dataclasses.replace(scene.mesh, size_contact=size_contact, order=order,
                               volumetric=volumetric or scene.mesh.volumetric)
    material = dataclasses.replace(scene.material, nu=scene.material.nu if nu is None else nu)
    scene = dataclasses.replace(scene, mesh=mesh, material=material, loads=(
        press, dataclasses.replace(shear, values=tuple(float(r * mu * force) for r in ratios))))
    return scene, ratios


def _largest(errors) -> float:
    return float(np.max(np.abs(errors)))


def solve_case(size_contact: float, order: int, n_shear: int, nu: float | None = None,
               volumetric: str | None = None, reference_spacing: float = REFERENCE_SPACING) -> dict:
    """Solve one HCM-1 case; its errors (nodal and recovered, against Cattaneo-Mindlin, Hertz and the coupled
    half-space reference on the same load path), DOF, wall and CPU time."""
    from contact.halfspace import coupled_reference
    from contact.theory import hertz, mindlin_shift, stick_ratio_translational

    scene, ratios = hcm1_case_scene(size_contact, order, n_shear, nu, volumetric)
    force, mu = scene.loads[0].values[0], scene.contact.friction_coefficient
    cpu_start = time.process_time()
    result, cost = solve_timed(scene)
    cpu_time = time.process_time() - cpu_start
    material = scene.material
    reference = hertz(force, scene.body.radius, material.effective_modulus)
    coupled = coupled_reference(dataclasses.replace(scene, mesh=type(scene.mesh)()), reference_spacing)
    press, shear_increments, coupled_shear = result.increments[0], result.increments[1:], coupled[1:]
    theory = np.array([float(stick_ratio_translational(r, 2)) for r in ratios])
    nodal = np.array([inc.stick_ratio for inc in shear_increments])
    recovered = np.array([inc.recovered_stick_ratio for inc in shear_increments])
    reference_ratio = np.array([inc.recovered.stick_ratio for inc in coupled_shear])
    stick_error = nodal - theory
    shift_error = [inc.shift[0] / float(mindlin_shift(r * mu * force, force, mu, inc.contact_radius,
                                                      material.shear_modulus, material.nu)) - 1.0
                   for r, inc in zip(ratios, shear_increments)]
    offset = reference_ratio - theory
    return dict(**cost, cpu_time=cpu_time, stick_ratio_error=_largest(stick_error),
                stick_ratio_error_signed=float(stick_error[int(np.argmax(np.abs(stick_error)))]),
                final_stick_ratio_error=float(stick_error[-1]),
                recovered_stick_ratio_error_cm=_largest(recovered - theory),
                coupled_stick_ratio_error=_largest(nodal - reference_ratio),
                recovered_stick_ratio_error=_largest(recovered - reference_ratio),
                coupling_offset_first=float(offset[0]), coupling_offset_last=float(offset[-1]),
                coupling_offset_largest=float(offset[int(np.argmax(np.abs(offset)))]),
                contact_radius_error=float(press.contact_radius / float(reference.contact_radius) - 1),
                recovered_contact_radius_error=float(press.recovered_contact_radius / float(reference.contact_radius)
                                                     - 1),
                peak_pressure_error=float(press.max_pressure / float(reference.peak_pressure) - 1),
                recovered_peak_pressure_error=float(press.recovered_peak_pressure / float(reference.peak_pressure)
                                                    - 1),
                reference_peak_pressure_error=float(coupled[0].recovered.peak_pressure
                                                    / float(reference.peak_pressure) - 1),
                shift_error=_largest(shift_error))


def convergence_rate(rows: list[dict], key: str) -> float:
    """Least-squares slope of log |rows[key]| against log size_contact (the observed order of convergence)."""
    sizes = np.array([r["size_contact"] for r in rows], float)
    errors = np.abs(np.array([r[key] for r in rows], float))
    if sizes.size < 2 or np.any(errors <= 0):
        return float("nan")
    return float(np.polyfit(np.log(sizes), np.log(errors), 1)[0])


def accuracy_knee(rows: list[dict], stick_target: float = TARGET_STICK_RATIO_ERROR,
                  pressure_target: float = TARGET_PEAK_PRESSURE_ERROR) -> dict | None:
    """The cheapest row (least CPU time) whose recovered stick ratio and peak pressure meet their targets (against
    the coupled reference and Hertz): finer meshes only buy accuracy nobody asked for. None when no row does."""
    meeting = [r for r in rows if r["recovered_stick_ratio_error"] <= stick_target
               and abs(r["recovered_peak_pressure_error"]) <= pressure_target]
    return min(meeting, key=lambda r: r["cpu_time"]) if meeting else None


def knee(rows: list[dict], factor: float = KNEE_FACTOR) -> dict | None:
    """The cheapest row (least wall_time) whose stick_ratio_error is within ``factor`` x the best of ``rows``: past
    it, finer meshes buy little more. None for no rows."""
    if not rows:
        return None
    best = min(r["stick_ratio_error"] for r in rows)
    return min((r for r in rows if r["stick_ratio_error"] <= factor * best), key=lambda r: r["wall_time"])


def add_arguments(parser) -> None:
    """Options of ``python -m studies convergence``."""
    parser.add_argument("--full", action="store_true",
                        help="add the fine meshes (HCM-1 h = 0.1 and 0.07 mm, P2 0.17 and 0.12 mm, 3x3 fingertip "
                             "0.3 mm) and 2 and 10 shear increments: about 10 minutes (584 s measured) against the "
                             "default's 1.5")


def run(out_dir, quick: bool = False, full: bool = False) -> dict:
    """Run every case, write convergence.csv / .png / .pdf, mark the HCM-1 knee (cheapest P1 mesh whose recovered
    stick ratio and peak pressure meet their targets, ``accuracy_knee``) and, not in --quick, the 3x3
    fingertip's (cheapest P1 mesh within KNEE_FACTOR of its best nodal stick-ratio error). ``full``: the fine
    meshes too (SIZES etc. under "full")."""
    from tqdm import tqdm

    setting = setting_name(quick, full)
    out_dir = Path(out_dir)
    spacing = {"quick": QUICK_REFERENCE_SPACING, "default": DEFAULT_REFERENCE_SPACING,
               "full": REFERENCE_SPACING}[setting]
    rows, solved = [], {}
    for case in tqdm(_cases(setting), desc=NAME, unit="case"):
        options = {k: case[k] for k in ("size_contact", "order", "n_shear", "nu", "volumetric") if k in case}
        key = tuple(sorted(options.items()))      # a case of two series (h = 0.2 with 5 increments) is solved once
        if key not in solved:
            solved[key] = solve_case(**options, reference_spacing=spacing)
        rows.append({**case, **solved[key]})
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)          # keep what is done if a later case fails
    for case in (() if quick else tqdm(array_cases(full), desc=f"{NAME} (3x3 fingertip)", unit="case")):
        rows.append({**case, **solve_array_case(**{k: case[k] for k in ("size_contact", "order", "n_shear")})})
        write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    sizes = [r for r in rows if r["study"] == SIZE_STUDY]
    hcm1_knee = accuracy_knee(sizes)
    array_knee = knee([r for r in rows if r["study"] == ARRAY_STUDIES[0]])     # P1 sizes, as HCM-1
    for row in rows:
        row["knee"] = row is hcm1_knee or row is array_knee
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    save_figure(_plot(rows, hcm1_knee, array_knee), out_dir, NAME)
    rates = {key: convergence_rate(sizes, key) for key in ("coupled_stick_ratio_error", "recovered_stick_ratio_error",
                                                           "stick_ratio_error", "recovered_stick_ratio_error_cm")}
    print(f"{NAME}: HCM-1 P1 observed rates (error ~ h^rate): c/a nodal {rates['coupled_stick_ratio_error']:.2f}, "
          f"recovered {rates['recovered_stick_ratio_error']:.2f} (against the coupled reference)")
    if hcm1_knee is not None:
        print(f"{NAME}: HCM-1 knee (cheapest P1 mesh with recovered c/a error <= {TARGET_STICK_RATIO_ERROR} against "
              f"the coupled reference and p_max within {TARGET_PEAK_PRESSURE_ERROR:.0%} of Hertz): size_contact = "
              f"{hcm1_knee['size_contact']} mm ({hcm1_knee['cpu_time']:.1f} CPU s, c/a error "
              f"{hcm1_knee['recovered_stick_ratio_error']:.4f}, p_max {hcm1_knee['recovered_peak_pressure_error']:+.1%})")
    if array_knee is not None:
        print(f"{NAME}: 3x3 fingertip knee (cheapest P1 mesh within {KNEE_FACTOR:.2f}x of the best nodal stick-ratio "
              f"error): size_contact = {array_knee['size_contact']} mm ({array_knee['wall_time']:.1f} s, error "
              f"{array_knee['stick_ratio_error']:.4f})")
    finest = min(sizes, key=lambda r: r["size_contact"])
    summary = {"max_error": finest["recovered_stick_ratio_error"],
               "error_meaning": f"recovered stick-ratio error against the coupled half-space reference on the finest "
                                f"P1 mesh, size_contact = {finest['size_contact']} mm",
               "knee_size_contact": None if hcm1_knee is None else hcm1_knee["size_contact"],
               "rates": rates}
    if array_knee is not None:
        summary["array_knee_size_contact"] = array_knee["size_contact"]
    return summary


def _plot(rows: list[dict], hcm1_knee: dict | None, array_knee: dict | None = None):
    """HCM-1 (top row: c/a, a and peak-pressure errors against CPU time, nodal and recovered) and, when run, the 3x3
    fingertip (bottom row: c/a and bump-radius errors against wall time, then wall time against DOF)."""
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    from studies._convergence_array import plot_array

    with_array = any(r["study"] in ARRAY_STUDIES for r in rows)
    # a fourth, narrow column holds the legends, which inside the panels hid the knee and the finest points
    fig, grid = plt.subplots(2 if with_array else 1, 4, figsize=(19, 9.2 if with_array else 4.6), squeeze=False,
                             gridspec_kw={"width_ratios": (1, 1, 1, 0.8)})
    for legend_axis in grid[:, 3]:
        legend_axis.axis("off")
    axes = grid[0]
    panels = ((("coupled_stick_ratio_error", "nodal"), ("recovered_stick_ratio_error", "recovered"),
               ("stick_ratio_error", "nodal vs Cattaneo-Mindlin")),
              (("contact_radius_error", "nodal"), ("recovered_contact_radius_error", "recovered")),
              (("peak_pressure_error", "nodal"), ("recovered_peak_pressure_error", "recovered")))
    labels = ("max |c/a error| (coupled reference)", "|a / a_Hertz - 1|", "|p_max / p0_Hertz - 1|")
    styles = {SIZE_STUDY: "o", NEARLY_INCOMPRESSIBLE_STUDY: "D", "element order (P2)": "s", "shear increments": "^"}
    lines = {"nodal": "--", "recovered": "-", "nodal vs Cattaneo-Mindlin": ":"}
    for axis, panel, label in zip(axes[:3], panels, labels):
        for study, marker in styles.items():
            subset = [r for r in rows if r["study"] == study]
            for key, kind in panel:
                if subset and (study in (SIZE_STUDY, NEARLY_INCOMPRESSIBLE_STUDY) or kind == "recovered"):
                    axis.loglog([r["cpu_time"] for r in subset], [abs(r[key]) + 1e-5 for r in subset],
                                marker + lines[kind], ms=4, label=f"{study}, {kind}")
        axis.set_xlabel("CPU time [s]")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    for r in (r for r in rows if r["study"] == SIZE_STUDY):
        axes[0].annotate(f"h={r['size_contact']}", (r["cpu_time"], r["recovered_stick_ratio_error"] + 1e-5),
                         textcoords="offset points", xytext=(4, 3), fontsize=7)
    axes[0].axhline(TARGET_STICK_RATIO_ERROR, color="grey", ls=":", label=f"target {TARGET_STICK_RATIO_ERROR}")
    if hcm1_knee:
        axes[0].plot(hcm1_knee["cpu_time"], hcm1_knee["recovered_stick_ratio_error"], "r*", ms=16,
                     label="knee: cheapest P1 mesh meeting the c/a and p_max targets")
    grid[0][3].legend(*axes[0].get_legend_handles_labels(), loc="center left", fontsize=7.5, frameon=False)
    axes[0].set_title("HCM-1 (sphere R = 10 mm on a 40x40x20 mm block, nu = 0.45, mu = 0.5)", fontsize=9)
    if with_array:
        plot_array(grid[1][:2], rows, array_knee, KNEE_FACTOR)
        cost = grid[1][2]
        for study in list(styles) + list(ARRAY_STUDIES):
            subset = [r for r in rows if r["study"] == study]
            if subset:
                cost.loglog([r["dofs"] for r in subset], [r["wall_time"] for r in subset], "o", label=study)
        cost.set_xlabel("degrees of freedom")
        cost.set_ylabel("wall time [s]")
        cost.grid(True, which="both", alpha=0.3)
        grid[1][3].legend(*cost.get_legend_handles_labels(), loc="center left", fontsize=7.5, frameon=False,
                          title="wall time against DOF")
    for axis in fig.axes:                      # log axes spanning under a decade would label every minor tick
        axis.xaxis.set_minor_formatter(NullFormatter())
    fig.suptitle("Error against run time: nodal and recovered stick ratio, contact radius, peak pressure")
    fig.tight_layout()
    return fig
