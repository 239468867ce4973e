"""Any array fingertip calibrated from its own FEM: the reduced bump laws and the per-bump base response, together.

``fit_fingertip(design)`` runs the calibration and held-out paths of ``_fit_plan`` on one mesh of the design (one
factorization; compliance columns from the disk cache when an earlier run computed them), fits the reduced model's
parameters (``calibration.calibrate``: k_n, c_a, G*, G_t, the kernel and couple arm) and the plant's base response
(``base_response.fit_base_response``: each bump's FEM base-pressure field in P_i, Q_i and spin) to the calibration
paths, and scores both on the held-out paths (``held_out_errors``). The result is cached on disk under
``FINGERTIP_CACHE/fingertip-fit``, keyed by the design, the plan and the package version, so designs that differ
only in their sensor, and a re-run, reuse it. A design the model cannot represent (one bump) is refused with the
reason (``_fit_plan.unrepresentable``).
"""

from __future__ import annotations

import hashlib
import json
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ._design import ArrayFingertipDesign, ReducedParameters
from ._fit_plan import FitPlan, fit_scenes, force_targets, unrepresentable
from .base_response import BaseResponse

__all__ = ["FitPlan", "FittedFingertip", "fit_fingertip", "fit_key", "held_out_errors", "unrepresentable",
           "FIT_ERROR_QUANTITIES"]

# raise when the fit's arithmetic changes: cached fits are made again (2: the base response's fields at the float32
# precision of the cache before the held-out errors are scored, so a fresh and a cached fit give the same numbers)
FIT_REVISION = 2
CACHE_FOLDER = "fingertip-fit"
# held-out quantity -> meaning (each the largest relative error over the held-out increments and bumps)
FIT_ERROR_QUANTITIES = {
    "depth": "plate approach of a press, model (P / (k k_n))^(2/3) against the FEM",
    "contact_radius": "per-bump contact radius c_a P_i^(1/3) against the FEM's sqrt(A_i / pi), at the FEM's P_i",
    "plate_shift": "plate translation at the FEM's force targets, |model - FEM| / |FEM|",
    "twist_angle": "plate twist at the FEM's torque targets, |model - FEM| / |FEM|",
    "base_field": "per-bump base-pressure field of the response surface, relative L2 against the FEM's own field",
    "cop_shift": "per-bump cell CoP shift of the base pressure from the press, |response - FEM| over the "
                 "increment's largest FEM shift",
}


@dataclass(frozen=True, eq=False)
class FittedFingertip:
    """A design calibrated from its FEM: reduced ``parameters``, base ``response``, held-out ``errors`` (largest
    relative error per FIT_ERROR_QUANTITIES), stage ``timings`` [s], mesh facts, the plan and the cache ``key``."""

    design: ArrayFingertipDesign
    parameters: ReducedParameters
    response: BaseResponse
    errors: dict
    timings: dict
    mesh: dict
    plan: FitPlan
    key: str
    cached: bool = False

    @property
    def mechanics(self):
        """The calibrated ReducedFingertip of the design."""
        from ._model import ReducedFingertip

        return ReducedFingertip(self.design, self.parameters)


def fit_key(design: ArrayFingertipDesign, plan: FitPlan) -> str:
    """SHA-256 of the design, the plan, FIT_REVISION and the package version (an upgrade fits again)."""
    from contact.compliance import package_version

    text = json.dumps({"design": design.to_dict(), "plan": plan.document(), "revision": FIT_REVISION,
                       "version": package_version()}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _cache_path(key: str) -> Path | None:
    from fem.cache_dir import usable_cache_dir

    folder = usable_cache_dir(CACHE_FOLDER)
    return None if folder is None else folder / f"fit-{key[:32]}.npz"


def _load(path: Path, key: str, design: ArrayFingertipDesign, plan: FitPlan) -> FittedFingertip | None:
    """The cached fit at ``path``, or None (absent; a damaged or foreign file is reported and deleted)."""
    from fem.cache_dir import discard_damaged

    if not path.is_file():
        return None
    try:
        response = BaseResponse.load(path)
        stored = response.provenance
        if stored.get("key") != key or response.design != design:
            raise ValueError("another design, plan or version")
        parameters = ReducedParameters.from_dict(stored["parameters"])
        return FittedFingertip(design, parameters, response, dict(stored["errors"]), dict(stored["timings"]),
                               dict(stored["mesh"]), plan, key, cached=True)
    except (ValueError, KeyError, TypeError) as error:
        discard_damaged(path, str(error))
        return None


def fit_fingertip(design: ArrayFingertipDesign, plan: FitPlan = FitPlan(), cache: bool = True,
                  log=None) -> FittedFingertip:
    """The design's reduced model and base response from its own FEM (module docstring); ``cache``: read and write
    the disk cache; ``log``: called with one line per FEM path. ValueError names why a design cannot be fitted."""
    if not isinstance(design, ArrayFingertipDesign):
        raise TypeError(f"design={design!r} must be an ArrayFingertipDesign")
    if not isinstance(plan, FitPlan):
        raise TypeError(f"plan={plan!r} must be a FitPlan")
    reason = unrepresentable(design)
    if reason:
        raise ValueError(f"design {design.rows}x{design.cols} cannot be calibrated: {reason}")
    key = fit_key(design, plan)
    path = _cache_path(key) if cache else None
    if path is not None:
        found = _load(path, key, design, plan)
        if found is not None:
            return found
    fitted = _fit(design, plan, key, log)
    if path is not None:
        try:
            fitted.response.save(path)
        except OSError as error:                       # a full cache folder must not lose the fit
            import warnings

            from fem.cache_dir import CacheWarning

            warnings.warn(f"fingertip fit not cached at {str(path)!r} ({error.strerror or error})", CacheWarning,
                          stacklevel=2)
    return fitted


def _solve(scenes: dict, design, log, limits: dict) -> tuple[dict, dict, dict, object]:
    """Every path on one prepared mesh: {name: (PathSamples, states (t, k, 4), fields (t, k, n))}, timings, mesh
    facts and the first result (its sensor-plane mesh); ``limits`` collects the solver's physical-limit warnings
    {message: first path} (the closed loop's 2.7 N per bump strains the gel past 10 %, as the packaged fit did)."""
    from contact.limits import PhysicalLimitWarning
    from contact.solver import prepare, solve_scene

    from ._samples import PathSamples
    from .base_response import bump_base_pressures, bump_states

    start = time.perf_counter()
    prepared = prepare(next(iter(scenes.values()))[1])
    timings = {"prepare": time.perf_counter() - start}
    paths, first = {}, None
    for name, (_, scene) in scenes.items():
        tic = time.perf_counter()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", PhysicalLimitWarning)
            result = solve_scene(scene, prepared)
        for warning in caught:                 # kept with the fit (``limits``), others passed on
            if issubclass(warning.category, PhysicalLimitWarning):
                limits.setdefault(str(warning.message).split(": ", 1)[-1], name)
            else:
                warnings.warn_explicit(warning.message, warning.category, warning.filename, warning.lineno)
        fields = bump_base_pressures(result, prepared.factorization)
        total = np.stack([increment.base_pressure for increment in result.increments])
        # superposition: the bumps' own fields add up to each increment's base pressure (the gel is linear)
        if np.abs(fields.sum(axis=1) - total).max() > 1e-8 * np.abs(total).max():
            raise RuntimeError(f"path {name}: the bumps' base fields do not add up to the base pressure")
        paths[name] = (PathSamples.from_result(result, design, name), bump_states(result), fields)
        first = result if first is None else first
        timings[f"fem_{name}"] = time.perf_counter() - tic
        if log is not None:
            log(f"FEM {name}: {len(result.increments)} increments, {timings[f'fem_{name}']:.1f} s")
    return paths, timings, dict(prepared.mesh_info), first


def _fit(design: ArrayFingertipDesign, plan: FitPlan, key: str, log) -> FittedFingertip:
    from .base_response import fit_base_response
    from .calibration import calibrate

    start = time.perf_counter()
    scenes = fit_scenes(design, plan)
    limits: dict = {}
    paths, timings, mesh, first = _solve(scenes, design, log, limits)
    timings["fem"] = time.perf_counter() - start
    tic = time.perf_counter()
    roles = {name: case.role for name, (case, _) in scenes.items()}

    def of(role):
        return [name for name, value in roles.items() if value == role]

    calibration = calibrate(design, [paths[n][0] for n in of("press")], [paths[n][0] for n in of("shear")],
                            [paths[n][0] for n in of("twist")], f"design-{key[:12]}")
    base = first.model.base
    provenance = {"key": key, "plan": plan.document(), "mesh": {"size_contact": scenes["press"][1].mesh.size_contact,
                                                                "fine_radius": scenes["press"][1].mesh.fine_radius,
                                                                **mesh}}
    response = fit_base_response(design, paths["press"][1:], [paths[n][1:] for n in of("shear")],
                                 [paths["twist"][1:]], base.positions[:, :2], base.triangles, first.bump_centers,
                                 provenance)
    timings["fit"] = time.perf_counter() - tic
    tic = time.perf_counter()
    from ._model import ReducedFingertip

    held_out = {name: (paths[name], scenes[name][1]) for name in of("held_out")}
    errors = held_out_errors(ReducedFingertip(design, calibration.parameters), response, held_out,
                             base.areas)
    timings["held_out"] = time.perf_counter() - tic
    timings["total"] = time.perf_counter() - start
    response.provenance.update(parameters=calibration.parameters.to_dict(), errors=errors, timings=timings,
                               fits=[fit.to_dict() for fit in calibration.fits], physical_limits=limits)
    return FittedFingertip(design, calibration.parameters, response, errors, timings, provenance["mesh"], plan, key)


def _cell_cop(positions, areas, field, centres):
    """Per-bump cell CoP (..., k, 2) [mm] of the summed base field (..., k, n) in the bumps' Voronoi cells."""
    from ._samples import cell_moments

    return cell_moments(positions, field.sum(axis=-2) * areas, centres)[1]


def held_out_errors(tip, response: BaseResponse, held_out: dict, areas) -> dict:
    """Largest relative errors (FIT_ERROR_QUANTITIES) of the model ``tip`` and ``response`` on held-out FEM paths
    {name: ((PathSamples, states (t, k, 4), fields (t, k, n)), scene)}; ``areas`` (n,) the sensor-plane nodes'
    tributary areas [mm^2]."""
    from ._samples import PathSamples

    errors = {name: 0.0 for name in FIT_ERROR_QUANTITIES}

    def worst(name, values):
        values = np.asarray(values, dtype=float)
        if values.size:
            errors[name] = max(errors[name], float(np.max(values)))

    for name, ((fem, states, fields), scene) in held_out.items():
        targets = force_targets(scene)
        model = PathSamples.from_reduced(tip, name, fem.load_kind, targets[:, 0], fem.friction, targets[:, 1:],
                                         "force")
        pressed = fem.pressed
        if pressed.all():
            worst("depth", np.abs(model.depth / fem.depth - 1.0))
            radius = tip.parameters.radius_coefficient * np.cbrt(fem.bump_normal_force)
            worst("contact_radius", np.abs(radius / fem.bump_contact_radius - 1.0))
        moved = ~pressed
        worst("plate_shift", np.linalg.norm(model.shift[moved] - fem.shift[moved], axis=1)
              / np.linalg.norm(fem.shift[moved], axis=1))
        twisted = fem.load_kind == "twist"
        worst("twist_angle", np.abs(model.angle[twisted] - fem.angle[twisted]) / np.abs(fem.angle[twisted]))
        predicted = response.bump_pressure(states)                                       # (t, k, n)
        worst("base_field", np.linalg.norm(predicted - fields, axis=-1) / np.linalg.norm(fields, axis=-1))
        if moved.any():
            positions = response.positions
            fem_cop = _cell_cop(positions, areas, fields, response.centres)
            model_cop = _cell_cop(positions, areas, predicted, response.centres)
            reference = fem.reference
            fem_shift = (fem_cop - fem_cop[reference])[moved]                           # (m, k, 2)
            model_shift = (model_cop - model_cop[reference])[moved]
            scale = np.linalg.norm(fem_shift, axis=-1).max(axis=1, keepdims=True)       # (m, 1)
            worst("cop_shift", np.linalg.norm(model_shift - fem_shift, axis=-1) / scale)
    return errors
