"""Convergence of the 3x3 fingertip of Figs. 6 and 9: element size (P1), element order (P2), shear increments.

The fingertip is pressed with 2 N by a plate (frictionless press), then sheared to Q/(mu P) = 0.5 in ``n_shear``
equal force increments. Errors: the array's stick ratio at Q/(mu P) = 0.5 against Cattaneo-Mindlin (every bump
carries Q/P = 0.5 of its own load) and the mean bump contact radius after the press against Hertz with an equal
share P/9 (the base couples the bumps a little). Wall time is the whole solve (mesh - from the disk cache when it
is there, see ``mesh_time`` - assembly, factorization, contact path).

Sizes are chosen for run time (measured on 2 shared cores with the mesh cached, on the fTetWild meshes used before;
gmsh meshes a size in a few seconds from a cold cache):
- P1 at h = 0.9 / 0.6 / 0.4 / 0.3 mm: 27k to 57k DOF, 3 to 20 s each.
- P2 only at the two coarsest sizes, h = 0.9 and 0.6 mm (nodes spaced h, tets 2h): 105k and 108k DOF (the base
  layer holds most of them), 50 to 75 s each, mostly ~1400 compliance columns of one back-substitution each;
  stopping there keeps the two P2 cases near two minutes of the study's six. The sensor plane keeps the P1 node
  spacing (tets of 2 x BENCH_SIZE_BASE): with P1-sized tets there P2 had 154k DOF and took 1.7x as long for the
  same c/a (0.710 against 0.713 at h = 0.9).
- Increments 1, 2, 5 at h = 0.6 mm, coarser than the bench's 0.3 mm so that the three take ~25 s (at 0.3 mm:
  ~70 s, estimated); force-controlled monotonic shear is path independent in theory, so this measures the
  solver's path error alone.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

ARRAY_STUDIES = ("3x3 fingertip (P1)", "3x3 fingertip (P2)", "3x3 fingertip increments")
ARRAY_SIZES = (0.9, 0.6, 0.4, 0.3)      # mm, P1 element size at the bump tops (0.3 only with --full)
ARRAY_FULL_ONLY_SIZES = (0.3,)
ARRAY_QUADRATIC_SIZES = (0.9, 0.6)      # mm, P2 node spacing at the bump tops (tets twice as large)
ARRAY_INCREMENTS = (1, 2, 5)            # equal shear increments to the same final load
ARRAY_INCREMENT_SIZE = 0.6              # mm, P1 size of the increment cases
ARRAY_LOAD_RATIO = 0.5                  # final Q/(mu P)


def array_cases(full: bool = True) -> list[dict]:
    """The array cases in run order: element size (P1), element order (P2), shear increments (P1); without
    ``full`` the finest P1 size (ARRAY_FULL_ONLY_SIZES, ~40 s of the study's default few minutes) is left out."""
    sizes = ARRAY_SIZES if full else tuple(h for h in ARRAY_SIZES if h not in ARRAY_FULL_ONLY_SIZES)
    cases = [dict(study=ARRAY_STUDIES[0], size_contact=h, order=1, n_shear=1) for h in sizes]
    cases += [dict(study=ARRAY_STUDIES[1], size_contact=h, order=2, n_shear=1) for h in ARRAY_QUADRATIC_SIZES]
    cases += [dict(study=ARRAY_STUDIES[2], size_contact=ARRAY_INCREMENT_SIZE, order=1, n_shear=n)
              for n in ARRAY_INCREMENTS]
    return cases


def array_scene(size_contact: float, order: int = 1, n_shear: int = 1):
    """The bench's 3x3 fingertip: press NORMAL_FORCE (frictionless), then ``n_shear`` equal shear-force increments
    to Q = ARRAY_LOAD_RATIO mu P. P2: ``size_contact`` is the node spacing, and the sensor plane keeps P1's."""
    from contact.scene import ContactSpec, Load, LoadKind, MeshSettings
    from controller import bench as tip

    if not (isinstance(n_shear, int) and n_shear >= 1):
        raise ValueError(f"n_shear={n_shear!r} must be an integer >= 1")
    final = ARRAY_LOAD_RATIO * tip.FRICTION * tip.NORMAL_FORCE
    shear_forces = tuple(float(final * k / n_shear) for k in range(1, n_shear + 1))
    base = tip.bench_scene(3, "shift", (0.1,), size_contact, tip.BENCH_SIZE_BASE)
    return dataclasses.replace(
        base, contact=ContactSpec(friction_coefficient=tip.FRICTION, frictionless_press=True),
        mesh=MeshSettings(size_contact=size_contact, size_far=3.0, size_base=tip.BENCH_SIZE_BASE * order,
                          order=order),
        loads=(Load(LoadKind.PRESS, "force", (tip.NORMAL_FORCE,)), Load(LoadKind.SHEAR, "force", shear_forces)))


def solve_timed(scene):
    """Solve ``scene``; return the result and its cost columns: DOF, elements, compliance columns, wall and mesh
    time [s] (wall: the whole solve, mesh from the disk cache when it is there)."""
    from contact.solver import solve_scene

    start = time.perf_counter()
    result = solve_scene(scene, cache_compliance=False)      # time the columns, not the disk cache
    wall = time.perf_counter() - start
    return result, dict(dofs=result.mesh_info["dofs"], elements=result.mesh_info["elements"],
                        compliance_columns=result.timings["compliance_columns"], wall_time=wall,
                        mesh_time=float(result.timings["mesh"]))


def solve_array_case(size_contact: float, order: int = 1, n_shear: int = 1) -> dict:
    """Solve one array case; its errors against Cattaneo-Mindlin and Hertz(P/9), DOF and wall time [s]."""
    from contact.theory import hertz, stick_ratio_translational
    from controller import bench as tip

    scene = array_scene(size_contact, order, n_shear)
    result, cost = solve_timed(scene)
    bumps = 9
    radius = float(hertz(tip.NORMAL_FORCE / bumps, scene.gel.geometry.bump_radius,
                         scene.material.effective_modulus).contact_radius)
    contact_radius = float(np.sqrt(result.increments[0].contact_area / (bumps * np.pi)))
    stick_error = result.increments[-1].stick_ratio - float(stick_ratio_translational(ARRAY_LOAD_RATIO, 2))
    recovered_error = result.increments[-1].recovered_stick_ratio - float(stick_ratio_translational(ARRAY_LOAD_RATIO, 2))
    return dict(**cost, stick_ratio_error=abs(stick_error), stick_ratio_error_signed=stick_error,
                recovered_stick_ratio_error_cm=abs(recovered_error),
                final_stick_ratio_error=stick_error, contact_radius_error=contact_radius / radius - 1.0,
                shift_error=float("nan"))


def plot_errors_against_time(axis, rows: list[dict], key: str, styles: dict, increments_study: str) -> None:
    """|rows[key]| against wall time on log axes, one line per study in ``styles`` ({study: matplotlib format}),
    each point tagged with its element size (or its number of increments for ``increments_study``)."""
    for study, style in styles.items():
        subset = [r for r in rows if r["study"] == study]
        if not subset:
            continue
        values = [abs(r[key]) for r in subset]
        axis.loglog([r["wall_time"] for r in subset], values, style, label=study)
        for r, v in zip(subset, values):
            tag = f"n={r['n_shear']}" if study == increments_study else f"h={r['size_contact']}"
            axis.annotate(tag, (r["wall_time"], v), textcoords="offset points", xytext=(4, 3), fontsize=7)


def plot_array(axes, rows: list[dict], knee: dict | None, knee_factor: float) -> None:
    """Bottom row of the convergence figure: c/a error and bump radius error against wall time, knee starred;
    wall time against DOF for every case of the figure."""
    styles = {ARRAY_STUDIES[0]: "D-", ARRAY_STUDIES[1]: "s-", ARRAY_STUDIES[2]: "^--"}
    metrics = (("stick_ratio_error", f"|c/a - Cattaneo-Mindlin| at Q/(mu P) = {ARRAY_LOAD_RATIO}"),
               ("contact_radius_error", "|bump a / a_Hertz(P/9) - 1|"))
    for axis, (key, label) in zip(axes, metrics):
        plot_errors_against_time(axis, rows, key, styles, ARRAY_STUDIES[2])
        if key == "stick_ratio_error" and knee:
            axis.plot(knee["wall_time"], knee["stick_ratio_error"], "r*", ms=16,
                      label=f"knee: cheapest P1 within {knee_factor:.2f}x best")
        axis.set_xlabel("wall time [s]")
        axis.set_ylabel(label)
        axis.grid(True, which="both", alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title("3x3 fingertip of Figs. 6/9 (press 2 N, shear to Q/(mu P) = 0.5)", fontsize=9)
