"""The finite-strain study's comparison: the project's linear FEM, CalculiX linear and CalculiX Neo-Hookean at equal
loads, one tidy row per quantity and load, and the envelope each quantity keeps within its tolerance.

Loads are matched the way each quantity is used: the normal force at equal depth (the stiffness), the contact radius
and the spread of the base pressure at equal force, shear and twist at equal load ratio Q/(mu P) or T/(mu P) with
each model's own P (the closed loop knows its loads, not the gel's displacement). CalculiX curves are interpolated
at the FEM's loads:
force and radius against depth on log-log axes (P ~ d^1.5, a ~ d^0.5 locally, so the error is far below 0.1 %),
the rest linearly in the load ratio.
"""

from __future__ import annotations

import math

import numpy as np

from contact.envelope import SMALL_STRAIN_TOLERANCE

__all__ = ["press_rows", "shear_rows", "twist_rows", "envelope", "MIN_ELEMENTS_PER_RADIUS"]

# the FEM resolves a contact from a = 5 h on (the convergence study's knee, h = a/5): below, its misses are its own
# discretisation, which a finite-strain reference cannot judge, so those rows do not bound the envelope
MIN_ELEMENTS_PER_RADIUS = 5.0

MODELS = ("fem_linear", "fem_neo_hooke", "calculix_linear", "calculix_neo_hooke", "getfem_linear", "getfem_neo_hooke")
# the stick ratios the references read from point motions, not from a contact status: CalculiX's (a point sticks
# when it moved with the plate in the increment) is judged within CalculiX, its linear gel against its Neo-Hookean
# one; GetFEM's (the friction law's weighted slip, zero only where a point's whole neighbourhood sticks) reads 0.04-
# 0.09 below the FEM's on the same gel at moderate load, 0.13-0.18 near gross slip - an element ring at h = 0.5 mm
# (half that offset at h = 0.3 mm): it does not judge them
STICK_RATIOS = ("stick_ratio", "stick_ratio_twist")


def _loglog(x, xp, fp):
    return float(np.exp(np.interp(math.log(x), np.log(xp), np.log(fp))))


def _row(problem, quantity, load_name, load, values, relative, extra):
    """One comparison: the models' values (NaN where a model did not run or reach the load), the linear FEM's error
    against CalculiX's Neo-Hookean gel (``judged_error``, deciding the envelope), against GetFEM's
    (``judged_error_getfem``) and against the FEM's own Neo-Hookean gel (``error_fem_vs_fem_neo_hooke``), the FEM
    Neo-Hookean gel's error against each reference's (its validation), and the finite-strain effect (Neo-Hookean /
    linear) as each code sees it."""
    fem, fem_neo, linear, neo, getfem_linear, getfem_neo = (values.get(m, math.nan) for m in MODELS)
    error = (lambda a, b: a / b - 1.0) if relative else (lambda a, b: a - b)
    tolerance = SMALL_STRAIN_TOLERANCE[quantity]
    fem_error = error(fem, neo)
    stick = quantity in STICK_RATIOS
    judged = error(linear, neo) if stick else fem_error
    judged_getfem = math.nan if stick else error(fem, getfem_neo)
    own = error(fem, fem_neo)
    return dict(problem=problem, quantity=quantity, load_name=load_name, load=load,
                **{m: values.get(m, math.nan) for m in MODELS},
                error_fem_vs_neo_hooke=fem_error, error_fem_vs_calculix_linear=error(fem, linear),
                error_calculix_linear_vs_neo_hooke=error(linear, neo), relative_error=relative, tolerance=tolerance,
                judged_error=judged, within_tolerance=bool(abs(judged) <= tolerance),
                error_fem_vs_getfem_neo_hooke=error(fem, getfem_neo),
                error_getfem_linear_vs_neo_hooke=error(getfem_linear, getfem_neo),
                judged_error_getfem=judged_getfem, within_tolerance_getfem=bool(abs(judged_getfem) <= tolerance),
                error_fem_vs_fem_neo_hooke=own, within_tolerance_fem_neo_hooke=bool(abs(own) <= tolerance),
                error_fem_neo_hooke_vs_neo_hooke=error(fem_neo, neo),
                error_fem_neo_hooke_vs_getfem_neo_hooke=error(fem_neo, getfem_neo),
                error_fem_linear_vs_getfem_linear=error(fem, getfem_linear),
                finite_strain_effect_fem=error(fem_neo, fem), finite_strain_effect_calculix=error(neo, linear),
                finite_strain_effect_getfem=error(getfem_neo, getfem_linear),
                **extra)


def press_rows(problem: str, radius: float, fem: list, calculix: dict, element_size: float,
               fem_neo_hooke: list | None = None) -> list[dict]:
    """The press at the FEM's increments inside CalculiX's range: the normal force at equal depth, the contact radius
    and (bump) the base force's radius of gyration at equal force (the closed loop sets forces, not depths).
    ``fem``: (depth, force, contact radius[, base spread]) per increment; ``fem_neo_hooke``: the same of the FEM's
    Neo-Hookean gel at the same forces and beyond (its depth must reach the linear one's); ``calculix``: records
    with depth, normal_force, contact_radius, base_spread by model; ``radius``: the sphere's or bump's radius R
    [mm]; ``element_size``: the FEM's h [mm] (a row is ``resolved`` when its contact radius is at least 5 h)."""
    curves = {name: np.array([(r.depth, r.normal_force, r.contact_radius, r.base_spread) for r in records
                              if r.normal_force > 0 and r.contact_radius > 0]) for name, records in calculix.items()}
    depths = (max(c[:, 0].min() for c in curves.values()), min(c[:, 0].max() for c in curves.values()))
    forces = (max(c[:, 1].min() for c in curves.values()), min(c[:, 1].max() for c in curves.values()))
    own = np.array([item[:4] for item in fem_neo_hooke]) if fem_neo_hooke else None
    rows = []
    for item in fem:
        depth, force, contact_radius = item[:3]
        spread = item[3] if len(item) > 3 else math.nan
        base = dict(depth_over_radius=depth / radius, contact_radius_over_radius=contact_radius / radius,
                    normal_force_fem=force, resolved=bool(contact_radius >= MIN_ELEMENTS_PER_RADIUS * element_size))
        at_force = {}
        if own is not None:
            same = np.flatnonzero(np.isclose(own[:, 1], force, rtol=1e-6))
            at_force = {} if same.size == 0 else dict(zip(("contact_radius", "spread"), own[same[0], 2:4]))
        if depths[0] <= depth <= depths[1]:
            values = {"fem_linear": force, **{n: _loglog(depth, c[:, 0], c[:, 1]) for n, c in curves.items()}}
            if own is not None and own[0, 0] <= depth <= own[-1, 0]:
                values["fem_neo_hooke"] = _loglog(depth, own[:, 0], own[:, 1])
            rows.append(_row(problem, "normal_force", "depth_over_radius", depth / radius, values, True, base))
        if forces[0] <= force <= forces[1]:
            values = {"fem_linear": contact_radius, **{n: _loglog(force, c[:, 1], c[:, 2]) for n, c in curves.items()}}
            if "contact_radius" in at_force:
                values["fem_neo_hooke"] = float(at_force["contact_radius"])
            rows.append(_row(problem, "contact_radius", "depth_over_radius", depth / radius, values, True, base))
            if math.isfinite(spread):
                values = {"fem_linear": spread, **{n: float(np.interp(force, c[:, 1], c[:, 3]))
                                                   for n, c in curves.items()}}
                if "spread" in at_force:
                    values["fem_neo_hooke"] = float(at_force["spread"])
                rows.append(_row(problem, "base_pressure_spread", "depth_over_radius", depth / radius, values, True,
                                 base))
    return rows


def _monotone(x, *columns):
    """The leading part of a curve while x rises (gross slip ends it: the load ratio stalls near 1)."""
    falls = np.flatnonzero(np.diff(x) <= 0.0)
    stop = int(falls[0]) + 1 if falls.size else len(x)
    return (x[:stop],) + tuple(c[:stop] for c in columns)


def shear_rows(fem: list, others: dict, friction_coefficient: float, problem: str = "bump_shear") -> list[dict]:
    """Tangential compliance (plate shift / Q [mm/N]), recovered stick ratio and base CoP shift at the FEM's load ratios
    Q/(mu P); ``fem``: dicts with normal_force, tangential_force, shift, stick_ratio, base_cop_x per increment (the
    first the pressed state); ``others``: the other models' records (dicts or CalculiX records, first the pressed
    state) by model name."""
    def curve(items):
        pressed = items[0]["base_cop_x"]
        table = np.array([(i["tangential_force"] / (friction_coefficient * i["normal_force"]),
                           i["shift"] / i["tangential_force"], i["stick_ratio"],
                           i["base_cop_x"] - pressed) for i in items[1:]])
        return _monotone(*table.T)

    return _at_fem_ratios(problem, "load_ratio", (("tangential_compliance", True), ("stick_ratio", False),
                                                  ("base_cop_shift", True)), curve, fem, others)


def twist_rows(fem: list, others: dict, friction_coefficient: float, contact_radius: float,
               problem: str = "bump_twist") -> list[dict]:
    """Torsional compliance (twist angle / torque [rad/(N mm)]) and recovered stick ratio at the FEM's torque ratio
    T/(mu P a), a the FEM's contact radius [mm] at the held depth (one scale for every model: full slip of a Hertz
    contact at 3 pi / 16 = 0.59)."""
    def curve(items):
        table = np.array([(i["torque"] / (friction_coefficient * i["normal_force"] * contact_radius),
                           i["angle"] / i["torque"], i["stick_ratio"]) for i in items[1:]])
        return _monotone(*table.T)

    return _at_fem_ratios(problem, "torque_ratio", (("torsional_compliance", True), ("stick_ratio_twist", False)),
                          curve, fem, others)


def _at_fem_ratios(problem: str, axis: str, quantities, curve, fem: list, others: dict) -> list[dict]:
    """One row per quantity at each of the linear FEM's load ratios up to the highest any other model reached; each
    model's curve (``curve`` of its records: the ratio, then one column per quantity) read at that ratio, NaN outside
    the ratios that model reached (np.interp would repeat its end values there)."""
    models = {"fem_linear": curve(fem),
              **{name: curve([r if isinstance(r, dict) else vars(r) for r in records])
                 for name, records in others.items()}}
    top = max(c[0].max() for name, c in models.items() if name != "fem_linear")
    rows = []
    for k, ratio in enumerate(models["fem_linear"][0]):
        if ratio > top:
            break
        at = {name: [float(np.interp(ratio, c[0], column)) if c[0][0] <= ratio <= c[0][-1] else math.nan
                     for column in c[1:]] for name, c in models.items()}
        at["fem_linear"] = [c[k] for c in models["fem_linear"][1:]]
        for j, (quantity, relative) in enumerate(quantities):
            rows.append(_row(problem, quantity, axis, float(ratio), {name: at[name][j] for name in at}, relative, {}))
    return rows


def envelope(rows: list[dict], reference: str = "calculix_neo_hooke") -> dict:
    """Per (problem, quantity): the load range over which the FEM stays within the tolerance of the Neo-Hookean gel:
    from its first row within tolerance (``holds_from``; the misses before it are loads where the FEM's own mesh
    error dominates, a contact of a few elements, which a finite-strain reference cannot judge: ``resolved`` says
    where a >= 5 h) up to the last row before the next miss (``holds_to``; both None if no row is within), the largest
    error at or above ``holds_from`` and the load it is at. Rows without a Neo-Hookean value (its run failed) are
    left out. ``reference``: "calculix_neo_hooke" or "getfem_neo_hooke" (the independent gels) or "fem_neo_hooke"
    (the project's own finite-strain gel, validated against both)."""
    error, within = {"calculix_neo_hooke": ("judged_error", "within_tolerance"),
                     "getfem_neo_hooke": ("judged_error_getfem", "within_tolerance_getfem"),
                     "fem_neo_hooke": ("error_fem_vs_fem_neo_hooke", "within_tolerance_fem_neo_hooke")}[reference]
    found = {}
    for key in dict.fromkeys((r["problem"], r["quantity"]) for r in rows):
        series = sorted((r for r in rows if (r["problem"], r["quantity"]) == key
                         and math.isfinite(r[error])), key=lambda r: r["load"])
        if not series:
            continue
        start = next((k for k, row in enumerate(series) if row[within]), None)
        if start is None:                            # outside at every load measured
            worst = max(series, key=lambda r: abs(r[error]))
            found[f"{key[0]}:{key[1]}"] = dict(
                load_name=series[0]["load_name"], holds_from=None, holds_to=None,
                holds_to_contact_radius_over_radius=None, tested_from=series[0]["load"], tested_to=series[-1]["load"],
                tolerance=series[0]["tolerance"], largest_error=worst[error], at_load=worst["load"],
                first_miss=series[0]["load"], first_miss_error=series[0][error], reference=reference)
            continue
        held = start
        while held + 1 < len(series) and series[held + 1][within]:
            held += 1
        judged = series[start:]
        worst = max(judged, key=lambda r: abs(r[error]))
        found[f"{key[0]}:{key[1]}"] = dict(
            load_name=series[0]["load_name"], holds_from=series[start]["load"], holds_to=series[held]["load"],
            holds_to_contact_radius_over_radius=series[held].get("contact_radius_over_radius"),
            tested_from=series[0]["load"], tested_to=series[-1]["load"], tolerance=series[0]["tolerance"],
            largest_error=worst[error], at_load=worst["load"],
            first_miss=None if held + 1 == len(series) else series[held + 1]["load"],
            first_miss_error=None if held + 1 == len(series) else series[held + 1][error], reference=reference)
    return found


SHEAR_AND_TWIST_QUANTITIES = (("tangential_compliance", "shear"), ("stick_ratio", "shear"),
                              ("base_cop_shift", "shear"), ("torsional_compliance", "twist"),
                              ("stick_ratio_twist", "twist"))


def envelope_bounds(found: dict, hold_contact_width: float, measured: str, unmeasured: str = "",
                    own: dict | None = None, peak_contact_width: float | None = None,
                    independent: dict | None = None) -> list:
    """The envelope as ``contact.envelope.EnvelopeBound`` s: per quantity the tightest bound over the problems that
    measured it. A press quantity holds to the a/R of its last row within tolerance (``envelope``); a shear or twist
    quantity to its last load ratio within tolerance, at ``hold_contact_width`` (the FEM bump's a/R at the held
    depth). ``measured`` names the run. A shear or twist quantity without a CalculiX Neo-Hookean value is bounded by
    ``independent``, the envelope against GetFEM's Neo-Hookean gel (``envelope(..., reference="getfem_neo_hooke")``),
    or where GetFEM did not run or judge it (the stick ratios) by ``own``, the one against the FEM's own Neo-Hookean
    gel, at the peak's contact width ``peak_contact_width`` up to the smaller of the hold's and the peak's load
    ratios (0: outside at every ratio measured); without either, by the tightest press bound, marked ``assumed`` with
    the reason ``unmeasured``."""
    from contact.envelope import EnvelopeBound

    tightest = {}
    for key, item in found.items():
        problem, quantity = key.split(":")
        load = {"bump_shear": "shear", "bump_twist": "twist"}.get(problem, "press")
        if load == "press":
            width = item["holds_to_contact_radius_over_radius"] or 0.0
            bound = EnvelopeBound(quantity, load, round(width, 2), math.inf, f"{problem}, {measured}")
        else:
            bound = EnvelopeBound(quantity, load, round(hold_contact_width, 2), round(item["holds_to"] or 0.0, 2),
                                  f"{problem}, {measured}")
        held = tightest.get(quantity)
        if held is None or (bound.contact_width, bound.load_ratio) < (held.contact_width, held.load_ratio):
            tightest[quantity] = bound
    press = min((b.contact_width for b in tightest.values() if b.load == "press"), default=0.0)
    sources = ((independent or {}, "GetFEM's Neo-Hookean gel (contact.getfem)"),
               (own or {}, "the project's Neo-Hookean gel (contact._finite_strain, validated on the press)"))
    for quantity, load in SHEAR_AND_TWIST_QUANTITIES:
        if quantity in tightest:
            continue
        def first(key):                              # the first source that measured it, each hold on its own
            return next(((source[key], name) for source, name in sources if key in source), (None, ""))

        (hold, name), (peak, peak_name) = first(f"bump_{load}:{quantity}"), first(f"bump_{load}_peak:{quantity}")
        if peak is not None and peak_name != name:
            name = f"{name} (the peak against {peak_name})"
        if hold is None:                             # no Neo-Hookean run: only what the press says
            tightest[quantity] = EnvelopeBound(quantity, load, press, math.inf, unmeasured, assumed=True)
            continue
        # a shear or twist miss below the first load ratio within is not the mesh's (the contact is the held one):
        # such a quantity holds nowhere
        ratio = min(item["holds_to"] if item["holds_to"] is not None and item["holds_from"] == item["tested_from"]
                    else 0.0 for item in (hold, peak) if item is not None)
        width = peak_contact_width if peak is not None and peak_contact_width else hold_contact_width
        tightest[quantity] = EnvelopeBound(quantity, load, round(width, 2), round(ratio, 2),
                                           f"bump_{load} and its peak against {name}, {measured}")
    return list(tightest.values())
