"""Finite strain: where the small-strain FEM holds at the paper's loads, against CalculiX and GetFEM.

Two problems. The press of each is solved three ways: the project's linear FEM (``contact.solver``), CalculiX with
the same linear gel (no NLGEOM), and CalculiX with a compressible Neo-Hookean gel (NLGEOM, the same small-strain
moduli), and the bump's by the FEM's own Neo-Hookean gel too:

- a rigid sphere (R = 5 mm, frictionless) pressed into a bonded layer (10 mm, E = 0.3 MPa, nu = 0.45) to d/R = 0.4
  (CalculiX axisymmetric, CAX8R): normal force and contact radius against depth;
- one bump of the paper's fingertip (hemisphere R = 4.67 mm on its 13.3 mm cell of the 3 mm base, the bench's
  gel) pressed by a rigid plate past the depth where the FEM carries 2.6 N (the closed loop's peak bump force;
  CalculiX axisymmetric): normal force, contact radius and the spread of the base pressure along the press; then
  held at the depth of 1.5 N (``HOLD_BUMP_FORCE``: CalculiX's 3D Neo-Hookean press stalls past 2.0 N) and at the
  2.6 N peak, and sheared towards gross slip (mu = 1) or twisted: tangential and torsional compliance, stick ratio
  and the shift of the base pressure's centre (the sensor plane) against the load ratio. CalculiX (C3D10, mortar
  contact) runs the 1.5 N hold's shear and twist with the linear gel; its Neo-Hookean gel diverges when friction
  comes on. GetFEM (``contact.getfem``: large-sliding contact, augmented Lagrangian, its own Newton) solves every
  hold with both gels on the FEM's own mesh: the independent finite-strain reference for shear and twist, and the
  validation of the FEM's Neo-Hookean gel there.

Each quantity's tolerance (``contact.envelope.SMALL_STRAIN_TOLERANCE``) decides how far up the load the linear FEM
holds against the Neo-Hookean gel: the envelope ``contact.limits`` warns with. CalculiX and GetFEM are system
programs: without ``ccx`` the study is skipped with a message, without GetFEM the shear and twist are judged against
the FEM's own Neo-Hookean gel only. Their runs are kept on disk by the input's hash, so a second run reads them
back. Default: CalculiX meshes 0.2 mm (sphere) and 0.5 mm (bump), FEM and GetFEM 0.3 mm; ``--quick`` coarser,
``--full`` finer.
"""

from __future__ import annotations

import dataclasses
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from studies._output import save_figure, write_csv_atomic, write_json_atomic

NAME = "finite-strain"
PRESS_FORCES = (0.25, 0.5, 1.0, 1.5, 2.0, 2.6)     # N per bump: the closed loop's range, settled ~1 N, peaks 2.6 N
PEAK_BUMP_FORCE = 2.6
# N per bump at which the bump is held while sheared and twisted: CalculiX's 3D mortar press of the Neo-Hookean gel
# stalls at a plate depth of 1.29 mm (the FEM's 2.0 N; increments cut to 6e-4 of the step, the active set chattering
# with the residual at 1e-13) on both bump meshes tried, so the shear and twist are compared at 1.5 N (d = 1.07 mm,
# a/R = 0.5), above the closed loop's settled ~1 N; the press (axisymmetric) goes past the 2.6 N peak
HOLD_BUMP_FORCE = 1.5
HOLD_PRESS_FORCES = tuple(f for f in PRESS_FORCES if f <= HOLD_BUMP_FORCE)
# per path: press with friction on from the start (both codes), or nearly frictionless and friction switched on at
# the hold (CalculiX's Neo-Hookean gel diverges at that switch: residual ~1600 N, too many cutbacks). With friction
# from the start CalculiX 2.20 stops inside spooles (exit code 255) during the press, linear and Neo-Hookean alike
FRICTIONAL_PRESS = {"shear": False, "twist": False}
NEO_HOOKE_PRESS = PRESS_FORCES + (3.2,)   # N: the FEM's Neo-Hookean press goes past the linear one's peak depth
PRESS_REACH = 1.15          # the axisymmetric CalculiX press goes this far past the FEM's depth at the peak force
SPHERE_FORCES = (0.05, 0.15, 0.3, 0.5, 0.8, 1.2, 1.7, 2.3, 3.0, 3.6, 4.4)   # N: d = 0.12 ... 1.98 mm
SETTINGS = {          # CalculiX sphere h, bump h, increments; the FEM's h for the layer and the bump [mm]
    "quick": dict(sphere_size=0.4, sphere_increments=10, bump_size=0.7, bump_increments=6, fem_layer=0.5,
                  fem_bump=0.5),
    "default": dict(sphere_size=0.2, sphere_increments=20, bump_size=0.5, bump_increments=10, fem_layer=0.3,
                    fem_bump=0.3),
    "full": dict(sphere_size=0.1, sphere_increments=40, bump_size=0.35, bump_increments=16, fem_layer=0.2,
                 fem_bump=0.2),
}


def add_arguments(parser) -> None:
    """Options of ``python -m studies finite-strain``."""
    parser.add_argument("--full", action="store_true",
                        help="finer meshes and increments (CalculiX sphere 0.1 mm, bump 0.35 mm; FEM 0.2 mm)")


def _current_radius(result, increment) -> float:
    """The FEM's recovered contact radius [mm] with its contact points where they have moved to (the radius on the
    body; ``recovered_contact_radius`` is taken at the points' undeformed positions)."""
    from contact.recovery import recover_contact, surface_triangles

    model, candidates = result.model, result.candidates
    areas = model.top.areas[candidates]
    xy = model.top.positions[candidates, :2] + increment.displacement_full[model.top.dofs[candidates, :2]]
    triangles = surface_triangles(model.top.triangles, candidates, model.top.areas.size)
    return recover_contact(xy, triangles, areas, increment.pressure * areas, increment.traction * areas[:, None],
                           increment.status, result.scene.contact.friction_coefficient,
                           mirror_y=result.mesh_info["half_model"]).contact_radius


def _fem_sphere(setup, size):
    from contact.calculix import sphere_press_scene
    from contact.solver import solve_scene

    result = solve_scene(sphere_press_scene(setup, SPHERE_FORCES, size_contact=size))
    return [(inc.depth, inc.normal_force, _current_radius(result, inc)) for inc in result.increments]


def _bump_scene(setup, path, values, size, press_forces=PRESS_FORCES, hold=True, law="linear"):
    """The bump's scene for the FEM (and, on the same mesh, for GetFEM) with the gel ``law``."""
    from contact.calculix import bump_scene

    scene = bump_scene(setup, path, values, press_forces, size_contact=size, hold=hold)
    return dataclasses.replace(scene, name=f"{scene.name}_{law}_{setup.depth:.3f}",
                               material=dataclasses.replace(scene.material, law=law))


def _fem_bump(setup, path, values, size, press_forces=PRESS_FORCES, hold=True, law="linear", stopped=None):
    """The FEM's press (per force [N]) and path increments as dicts, with the base pressure's CoP [mm]; ``law``:
    the gel's ``contact.scene.MaterialLaw`` ("linear" or "neo_hookean")."""
    return _solve_bump(_bump_scene(setup, path, values, size, press_forces, hold, law), stopped)


def _solve_bump(scene, stopped=None):
    """The FEM's increments of a bump scene as dicts and its result. A path that stops early keeps its converged
    increments and is named in ``stopped`` (scene name -> reason)."""
    from contact.result import PathNotCompleted
    from contact.solver import solve_scene

    try:
        result = solve_scene(scene)
    except PathNotCompleted as error:        # the increments before the one that failed are kept and reported
        result = error.result
        reason = f"after {len(result.increments)} increments: {str(error)[:300]}"
        if stopped is not None:
            stopped[scene.name] = reason
        print(f"{NAME}: {scene.name} stopped {reason}")
    base = result.model.base
    rows = []
    for inc in result.increments:
        force = inc.base_pressure * base.areas
        radius = np.hypot(*(base.positions[:, :2] - result.bump_centers[0]).T)
        rows.append(dict(load_kind=inc.load_kind, depth=inc.depth, normal_force=inc.normal_force,
                         base_spread=float(np.sqrt((radius**2 * force).sum() / force.sum())),
                         tangential_force=inc.tangential_force[0], torque=inc.torque, shift=inc.shift[0],
                         angle=inc.angle, contact_radius=_current_radius(result, inc),
                         contact_radius_undeformed=inc.recovered_contact_radius,
                         stick_ratio=inc.recovered_stick_ratio,
                         base_cop_x=float((base.positions[:, 0] * force).sum() / force.sum())))
    return rows, result


NEO_HOOKE = "neo_hookean"
# the peak's shear and twist paths, stretched from the 1.5 N hold's so that they too reach gross slip: the slip
# force grows like P, the twist's slip angle about like P / a^3 * a P ~ P^(1/3) ... P^(1/2) (Hertz a ~ P^(1/3))
PEAK_PATH_SCALE = {"shear": PEAK_BUMP_FORCE / HOLD_BUMP_FORCE, "twist": (PEAK_BUMP_FORCE / HOLD_BUMP_FORCE) ** 0.5}


NEO_HOOKE_REFERENCE = "fem_neo_hooke"


def _held_scene(setup, path, values, place, peak_depth, size, law):
    """The bump's scene held at the hold ("hold": the setup's depth, pressed through ``HOLD_PRESS_FORCES``) or at
    the linear FEM's depth of the 2.6 N peak ("peak": the path stretched to reach gross slip there)."""
    if place == "hold":
        return _bump_scene(setup, path, values, size, HOLD_PRESS_FORCES, law=law)
    return _bump_scene(dataclasses.replace(setup, depth=peak_depth), path, values * PEAK_PATH_SCALE[path], size,
                       PRESS_FORCES, law=law)


def _neo_hooke_validation(rows: list[dict]) -> dict:
    """The FEM's Neo-Hookean gel against CalculiX's on the bump's press, where the FEM resolves the contact: per
    quantity the largest error and whether it is within the quantity's tolerance, and the largest difference
    between the two codes' finite-strain effects (Neo-Hookean / linear - 1, each code on its own mesh)."""
    found = {}
    for quantity in ("normal_force", "contact_radius", "base_pressure_spread"):
        series = [r for r in rows if r["problem"] == "bump_press" and r["quantity"] == quantity and r["resolved"]
                  and np.isfinite(r["error_fem_neo_hooke_vs_neo_hooke"])]
        if not series:
            continue
        worst = max(series, key=lambda r: abs(r["error_fem_neo_hooke_vs_neo_hooke"]))
        effect = max(series, key=lambda r: abs(r["finite_strain_effect_fem"] - r["finite_strain_effect_calculix"]))
        found[quantity] = dict(
            largest_error=worst["error_fem_neo_hooke_vs_neo_hooke"], at_depth_over_radius=worst["load"],
            tolerance=worst["tolerance"], within=bool(abs(worst["error_fem_neo_hooke_vs_neo_hooke"])
                                                      <= worst["tolerance"]),
            effect_difference=effect["finite_strain_effect_fem"] - effect["finite_strain_effect_calculix"],
            effect_fem=effect["finite_strain_effect_fem"], effect_calculix=effect["finite_strain_effect_calculix"],
            effect_at_depth_over_radius=effect["load"], rows=len(series))
    return found


def _getfem_validation(rows: list[dict]) -> dict:
    """The FEM's gels against GetFEM's on the same mesh, per shear or twist quantity and hold: the largest error of
    the FEM's Neo-Hookean gel against GetFEM's (the finite-strain gel's validation) and of the linear FEM against
    GetFEM's linear gel (the two solvers on one law), each against the quantity's tolerance."""
    found = {}
    for key in dict.fromkeys((r["problem"], r["quantity"]) for r in rows
                             if r["problem"].startswith(("bump_shear", "bump_twist"))):
        series = [r for r in rows if (r["problem"], r["quantity"]) == key]
        item = {}
        for name, column in (("neo_hooke", "error_fem_neo_hooke_vs_getfem_neo_hooke"),
                             ("linear", "error_fem_linear_vs_getfem_linear")):
            measured = [r for r in series if np.isfinite(r[column])]
            if measured:
                worst = max(measured, key=lambda r: abs(r[column]))
                item[name] = dict(largest_error=worst[column], at_load=worst["load"],
                                  within=bool(abs(worst[column]) <= worst["tolerance"]), rows=len(measured))
        if item:
            found[f"{key[0]}:{key[1]}"] = dict(item, tolerance=series[0]["tolerance"], load_name=series[0]["load_name"])
    return found


def _get(record, name):
    """A field of a FEM row (dict) or a CalculiX record (dataclass)."""
    return record[name] if isinstance(record, dict) else getattr(record, name)


def run(out_dir, quick: bool = False, full: bool = False) -> dict:
    """The models on both problems; CSV, PNG, PDF and the envelope (``NAME.envelope.json``)."""
    from contact.calculix import (INSTALL_HINT, BumpSetup, CalculixFailed, GelLaw, SpherePress, bump_job,
                                  bump_press_job, ccx_executable, ccx_version, sphere_press_job)
    from contact.envelope import SMALL_STRAIN_ENVELOPE
    from contact.getfem import INSTALL_HINT as GETFEM_HINT
    from contact.getfem import GetfemFailed, getfem_python, getfem_version
    from contact.getfem import bump_job as getfem_bump_job
    from studies._finite_strain_compare import envelope, envelope_bounds, press_rows, shear_rows, twist_rows
    from studies._finite_strain_plot import plot

    if quick and full:
        raise ValueError("--quick and --full exclude each other: choose one")
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if ccx_executable() is None:
        message = (f"skipped: CalculiX (ccx) was not found, and it is the independent finite-strain solver; "
                   f"{INSTALL_HINT}")
        print(f"{NAME}: {message}")
        return {"skipped": message, "verdict": f"not run ({message})"}
    stopped = {}                 # FEM paths that stopped before their end, by scene name
    mode = "full" if full else "quick" if quick else "default"
    settings = SETTINGS[mode]
    start = time.perf_counter()
    sphere = SpherePress(size_contact=settings["sphere_size"], increments=settings["sphere_increments"])
    bump = BumpSetup(size_contact=settings["bump_size"], increments=settings["bump_increments"])
    # the depths where the FEM bump carries the peak force (the press goes past it) and the holding force (both
    # codes are held there while shearing or twisting)
    fem_press, _ = _fem_bump(bump, "shear", (), settings["fem_bump"], hold=False)
    peak_depth = fem_press[PRESS_FORCES.index(PEAK_BUMP_FORCE)]["depth"]
    bump = dataclasses.replace(bump, depth=fem_press[PRESS_FORCES.index(HOLD_BUMP_FORCE)]["depth"])
    laws = {"calculix_linear": GelLaw.LINEAR, "calculix_neo_hooke": GelLaw.NEO_HOOKE}
    jobs = {("sphere", name): sphere_press_job(sphere, law) for name, law in laws.items()}
    jobs.update({("press", name): bump_press_job(bump, law, PRESS_REACH * peak_depth) for name, law in laws.items()})
    holding = {path: dataclasses.replace(bump, frictional_press=FRICTIONAL_PRESS[path]) for path in ("shear", "twist")}
    jobs.update({(path, name): bump_job(holding[path], law, path) for path in holding for name, law in laws.items()})
    path_values = {"shear": np.linspace(0.1, 1.0, 10) * bump.shear_shift,
                   "twist": np.linspace(0.1, 1.0, 10) * bump.twist_angle}
    # the held bump and its peak: the FEM's scene per path, place and law (GetFEM solves the same ones)
    scenes = {(path, place, law): _held_scene(holding[path], path, path_values[path], place, peak_depth,
                                              settings["fem_bump"], law)
              for path in holding for place in ("hold", "peak") for law in ("linear", NEO_HOOKE)}
    if getfem_python() is None:
        print(f"{NAME}: GetFEM was not found, so shear and twist are judged against the project's own "
              f"Neo-Hookean gel only; {GETFEM_HINT}")
    else:                                        # meshed here, in this thread (gmsh); run in the pool
        names = {"linear": "getfem_linear", NEO_HOOKE: "getfem_neo_hooke"}
        jobs.update({(path if place == "hold" else f"{path}_peak", names[law]): getfem_bump_job(scene)
                     for (path, place, law), scene in scenes.items()})
    with ThreadPoolExecutor(max_workers=2) as pool:       # each job is one ccx or GetFEM process on one thread
        futures = {key: pool.submit(job.run) for key, job in jobs.items()}
        fem_start = time.perf_counter()
        fem_sphere = _fem_sphere(sphere, settings["fem_layer"])
        fem_neo = {"press": _fem_bump(bump, "shear", (), settings["fem_bump"], NEO_HOOKE_PRESS, hold=False,
                                      law=NEO_HOOKE, stopped=stopped)[0]}
        fem_paths, fem_peak = {}, {}
        for path in holding:
            for law in ("linear", NEO_HOOKE):
                (fem_paths if law == "linear" else fem_neo)[path] = _solve_bump(scenes[path, "hold", law], stopped)[0]
                fem_peak[path, law] = _solve_bump(scenes[path, "peak", law], stopped)[0]
        fem_seconds = time.perf_counter() - fem_start
        done, failed = {}, {}
        for key, future in futures.items():
            try:
                done[key] = future.result()
            except (CalculixFailed, GetfemFailed) as error:      # reported, and the rows it would give are left out
                lines = str(error).splitlines()
                failed[f"{key[0]}_{key[1]}"] = next((line.strip() for line in lines if "*ERROR" in line), lines[-1])
    calculix, getfem, calculix_seconds, getfem_seconds, getfem_stopped = {}, {}, {}, {}, {}
    for key, found in done.items():          # CalculiX: (records, seconds); GetFEM: (records, seconds, why it stopped)
        name = f"{key[0]}_{key[1]}"
        if key[1].startswith("getfem"):
            getfem[key], getfem_seconds[name] = found[:2]
            if found[2]:
                getfem_stopped[name] = found[2]
        else:
            calculix[key], calculix_seconds[name] = found

    def by_model(problem, pick=lambda records: records):
        return {name: pick(calculix[problem, name]) for name in laws if (problem, name) in calculix}

    rows = press_rows("sphere_press", sphere.sphere_radius, fem_sphere, by_model("sphere"), settings["fem_layer"])
    fem_paths["press"] = fem_press
    fem_press_path = [(r["depth"], r["normal_force"], r["contact_radius"], r["base_spread"]) for r in fem_press]
    neo_press_path = [(r["depth"], r["normal_force"], r["contact_radius"], r["base_spread"])
                      for r in fem_neo["press"]]
    rows += press_rows("bump_press", bump.bump_radius, fem_press_path, by_model("press"), settings["fem_bump"],
                       fem_neo_hooke=neo_press_path)
    def held(records, kind):
        """The last press record (the held state), then the records of the ``kind`` path."""
        return [[r for r in records if _get(r, "load_kind") == "press"][-1]] + \
            [r for r in records if _get(r, "load_kind") == kind]

    def from_getfem(problem, path):
        return {name: held(records, path) for (key, name), records in getfem.items() if key == problem}

    mu = bump.friction_coefficient
    for path, make_rows in (("shear", shear_rows), ("twist", twist_rows)):
        radius = () if path == "shear" else (held(fem_paths[path], path)[0]["contact_radius"],)
        others = {**by_model(path, lambda r: held(r, path)), "fem_neo_hooke": held(fem_neo[path], path),
                  **from_getfem(path, path)}
        rows += make_rows(held(fem_paths[path], path), others, mu, *radius, problem=f"bump_{path}")
        radius = () if path == "shear" else (held(fem_peak[path, "linear"], path)[0]["contact_radius"],)
        rows += make_rows(held(fem_peak[path, "linear"], path),
                          {"fem_neo_hooke": held(fem_peak[path, NEO_HOOKE], path), **from_getfem(f"{path}_peak", path)},
                          mu, *radius, problem=f"bump_{path}_peak")
    for row in rows:
        row.update(mode=mode)
    write_csv_atomic(out_dir / f"{NAME}.csv", rows)
    found = envelope(rows)
    # shear and twist against the FEM's own finite-strain gel (CalculiX's diverges there), at the hold and the peak
    shear_and_twist = [r for r in rows if r["problem"].startswith(("bump_shear", "bump_twist"))]
    found_own = envelope(shear_and_twist, reference=NEO_HOOKE_REFERENCE)
    found_getfem = envelope(shear_and_twist, reference="getfem_neo_hooke")
    validation = _neo_hooke_validation(rows)
    getfem_validation = _getfem_validation(rows)
    getfem_name = getfem_version() if getfem_python() is not None else None
    hold_width = held(fem_paths["shear"], "shear")[0]["contact_radius"] / bump.bump_radius
    unmeasured = "; ".join(f"CalculiX Neo-Hookean {key.split('_')[0]} failed: {message}"
                           for key, message in failed.items() if key.endswith("calculix_neo_hooke"))
    peak_width = held(fem_peak["shear", "linear"], "shear")[0]["contact_radius"] / bump.bump_radius
    bounds = envelope_bounds({key: item for key, item in found.items() if item["holds_to"] is not None}, hold_width,
                             f"finite-strain {mode}, {ccx_version()}", unmeasured, found_own, peak_width,
                             found_getfem)
    shipped = {(b.quantity, b.load): (b.contact_width, b.load_ratio) for b in SMALL_STRAIN_ENVELOPE}
    differs = [b.describe() for b in bounds if shipped.get((b.quantity, b.load)) != (b.contact_width, b.load_ratio)]
    wall = time.perf_counter() - start
    stored = [dict(vars(b), load_ratio=None if np.isinf(b.load_ratio) else b.load_ratio) for b in bounds]   # no inf
    write_json_atomic(out_dir / f"{NAME}.envelope.json",
                      dict(envelope=found, envelope_against_fem_neo_hooke=found_own,
                           envelope_against_getfem_neo_hooke=found_getfem, getfem=getfem_name,
                           fem_against_getfem=getfem_validation, getfem_stopped=getfem_stopped,
                           fem_neo_hooke_validation=validation, fem_stopped=stopped, bounds=stored,
                           settings=settings, ccx=ccx_version(), bump_depth=bump.depth, peak_depth=peak_depth,
                           hold_bump_force=HOLD_BUMP_FORCE))
    save_figure(plot(rows, fem_sphere, {**calculix, **getfem}, fem_paths, fem_neo, sphere, bump, wall), out_dir, NAME)
    at_peak = [r for r in rows if r["problem"] != "sphere_press" and r.get("resolved", True)
               and np.isfinite(r["judged_error"])]
    worst = max(at_peak, key=lambda r: abs(r["judged_error"]) / r["tolerance"])
    outside = sorted({r["quantity"] for r in at_peak if not r["within_tolerance"]})
    return {"max_error": abs(worst["error_fem_vs_neo_hooke"]),
            "error_meaning": f"largest |linear FEM - Neo-Hookean| on the bump (relative, or c/a), against its "
                             f"tolerance: {worst['quantity']} at {worst['load_name']} = {worst['load']:.3g}",
            "envelope": found, "envelope_against_fem_neo_hooke": found_own,
            "envelope_against_getfem_neo_hooke": found_getfem, "getfem": getfem_name, "getfem_seconds": getfem_seconds,
            "fem_against_getfem": getfem_validation, "getfem_stopped": getfem_stopped,
            "fem_neo_hooke_validation": validation, "envelope_bounds": [b.describe() for b in bounds],
            "differs_from_contact_envelope": differs, "outside_at_the_paper_loads": outside, "bump_depth": bump.depth,
            "calculix_seconds": calculix_seconds,
            "calculix_failed": {key: why for key, why in failed.items() if "getfem" not in key},
            "getfem_failed": {key: why for key, why in failed.items() if "getfem" in key}, "fem_stopped": stopped,
            "fem_seconds": fem_seconds,
            "wall_time": wall, "mode": mode}
