"""Each bump's base pressure as the FEM computes it: per-bump influence fields of an array fingertip [mm, N, MPa].

The gel is linear and only the contact is not, so the pressure on the sensor plane is the sum of each bump's response
to its own contact forces. An FEM increment gives those forces at the contact-candidate points; one back-substitution
per bump (``bump_base_pressures``) turns them into the bump's own base-pressure field, and the fields of the k bumps
add up to the increment's base pressure to round-off. A response surface in the bump's state reproduces them:

    p_i(x) = P_i Phi_i(x; P_i) + Q_i,x Psi_i,x(x; P_i) + Q_i,y Psi_i,y(x; P_i) + S_i X_i(x)

P_i the bump's normal force [N], Q_i its tangential force [N], S_i the torque of its tractions about its own
first-contact point [N mm] (``contact.bumps``). Phi_i is the field per unit normal force at the bump forces of a press
path (``normal_levels``); Psi_i is fitted by least squares over the increments of shear paths pressed to a few
forces (``shear_levels``: the path's mean bump force), on what is left of each field after P_i Phi_i(P_i): the
response to Q is linear at each level (``BaseResponse.fit_residual`` says how far); X_i the same over a twist path
after both. Between levels each field is interpolated linearly in log P_i; beyond the end levels the end field holds.

This is the plant's sensor-plane physics in the closed loop (``controller.plant``), from the FEM of the design; the
estimator's own model (``controller.estimation``) is fitted on a bench and never reads it. The packaged fields of
the 3x3 bench fingertip are written by ``python -m studies plant-calibration --write-package-data``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fem.validation import check_finite_array

from ._design import ArrayFingertipDesign

__all__ = ["BaseResponse", "bump_base_pressures", "bump_states", "fit_base_response", "level_weights",
           "PACKAGED_BASE_RESPONSE"]

PACKAGED_BASE_RESPONSE = Path(__file__).parent / "data" / "fingertip_3x3_base_response.npz"
SCHEMA = "fingertip-contact/base-response/1"


def bump_base_pressures(result, factorization) -> np.ndarray:
    """Base pressure (t, k, n_base) [MPa] of each bump's own contact forces at every increment of an FEM ``result``
    of an array (P1), solved with the scene's ``factorization`` (``contact.solver.prepare``); summed over the bumps
    it is each increment's ``base_pressure``."""
    model = result.model
    if result.candidate_bump is None:
        raise ValueError(f"scene {result.scene.name!r}: the result has no bumps (an 'array' gel is needed)")
    if model.top.patches is not None:
        raise ValueError("bump_base_pressures needs P1 elements (nodal forces = pressure x tributary area)")
    candidates, areas, bump = result.candidates, result.candidate_areas, result.candidate_bump
    dofs = model.top.dofs[candidates]                                                   # (n, 3)
    count = len(result.bump_centers)
    position = np.full(model.n_dofs, -1)
    position[model.free_dofs] = np.arange(model.free_dofs.size)
    rows = position[dofs]                                                                # (n, 3) free-DOF rows
    if np.any(rows < 0):
        raise ValueError("a contact-candidate point has a fixed degree of freedom")
    fixed = np.full(model.n_dofs, -1)
    fixed[model.fixed_dofs] = np.arange(model.fixed_dofs.size)
    base_rows = fixed[model.base.dofs[:, 2]]                                             # (n_base,)
    fields = []
    for increment in result.increments:
        nodal = np.column_stack([increment.traction * areas[:, None], -increment.pressure * areas])   # (n, 3) [N]
        loads = np.zeros((model.free_dofs.size, count))
        for axis in range(3):
            np.add.at(loads, (rows[:, axis], bump), nodal[:, axis])
        reaction = model.stiffness_fixed_free @ factorization.solve(loads)               # (n_fixed, k)
        fields.append((reaction[base_rows] / model.base.areas[:, None]).T)               # (k, n_base)
    return np.stack(fields)


def bump_states(result) -> np.ndarray:
    """Per-bump state (t, k, 4) of every increment: P_i [N], Q_i,x, Q_i,y [N], spin torque S_i [N mm]."""
    return np.stack([np.column_stack([inc.bumps.normal_force, inc.bumps.tangential_force, inc.bumps.spin_torque])
                     for inc in result.increments])


def level_weights(levels: np.ndarray, force) -> tuple[np.ndarray, np.ndarray]:
    """Lower level index (...,) and weight of the upper level (...,) for linear interpolation in log force between
    ``levels`` (L,) [N], increasing; forces outside them take the end level (weight 0 or 1)."""
    levels = np.asarray(levels, dtype=float)
    if levels.size == 1:
        shape = np.shape(force)
        return np.zeros(shape, dtype=np.int64), np.zeros(shape)
    logs = np.log(levels)
    value = np.log(np.clip(np.asarray(force, dtype=float), levels[0], levels[-1]))
    index = np.clip(np.searchsorted(logs, value, side="right") - 1, 0, levels.size - 2)
    weight = (value - logs[index]) / (logs[index + 1] - logs[index])
    return index, weight


def _interpolate(table: np.ndarray, levels: np.ndarray, force: np.ndarray) -> np.ndarray:
    """table (k, L, ...) at each bump's force (k,): (k, ...)."""
    index, weight = level_weights(levels, force)
    bumps = np.arange(table.shape[0])
    lower, upper = table[bumps, index], table[bumps, np.minimum(index + 1, table.shape[1] - 1)]
    weight = weight.reshape(weight.shape + (1,) * (lower.ndim - 1))
    return (1.0 - weight) * lower + weight * upper


@dataclass(frozen=True, eq=False)
class BaseResponse:
    """Per-bump influence fields on the FEM's sensor-plane mesh (module docstring).

    positions (n, 2) [mm] and triangles (m, 3) of the sensor plane; centres (k, 2) [mm] of the bumps;
    normal_levels (L,) [N] and normal_fields (k, L, n) [MPa/N]; shear_levels (M,) [N] and shear_fields
    (k, M, 2, n) [MPa/N]; spin_fields (k, n) [MPa/(N mm)]; design; provenance (plain dict: mesh, paths, fit
    residuals, held-out errors).
    """

    design: ArrayFingertipDesign
    positions: np.ndarray
    triangles: np.ndarray
    centres: np.ndarray
    normal_levels: np.ndarray
    normal_fields: np.ndarray
    shear_levels: np.ndarray
    shear_fields: np.ndarray
    spin_fields: np.ndarray
    provenance: dict = field(default_factory=dict)

    def __post_init__(self):
        count, points = len(self.centres), len(self.positions)
        for name, shape in (("positions", (points, 2)), ("centres", (count, 2)),
                            ("normal_fields", (count, len(self.normal_levels), points)),
                            ("shear_fields", (count, len(self.shear_levels), 2, points)),
                            ("spin_fields", (count, points))):
            value = check_finite_array(name, getattr(self, name))
            if value.shape != shape:
                raise ValueError(f"base response {name} has shape {value.shape}, expected {shape}")
        for name in ("normal_levels", "shear_levels"):
            levels = np.asarray(getattr(self, name))
            if levels.ndim != 1 or not levels.size or np.any(levels <= 0) or np.any(np.diff(levels) <= 0):
                raise ValueError(f"base response {name}={levels!r} must be increasing positive forces [N]")
        if count != self.design.bump_count:
            raise ValueError(f"base response has {count} bumps, its design {self.design.bump_count}")

    def bump_pressure(self, states: np.ndarray) -> np.ndarray:
        """Each bump's base pressure (..., k, n) [MPa] for bump states (..., k, 4): P_i, Q_i,x, Q_i,y, S_i."""
        states = np.asarray(states, dtype=float)
        flat = states.reshape(-1, *states.shape[-2:])
        out = np.stack([self._one(state) for state in flat])
        return out.reshape(states.shape[:-1] + (len(self.positions),))

    def _one(self, state: np.ndarray) -> np.ndarray:
        force = np.maximum(state[:, 0], 0.0)
        normal = _interpolate(self.normal_fields, self.normal_levels, force)                # (k, n)
        shear = _interpolate(self.shear_fields, self.shear_levels, force)                   # (k, 2, n)
        return (force[:, None] * normal + np.einsum("ka,kan->kn", state[:, 1:3], shear)
                + state[:, 3:4] * self.spin_fields)

    def pressure(self, states: np.ndarray) -> np.ndarray:
        """Base pressure (..., n) [MPa] of the whole fingertip for bump states (..., k, 4)."""
        return self.bump_pressure(states).sum(axis=-2)

    def mapped(self, operator) -> dict:
        """Every field through a linear map of the sensor-plane field (``operator`` (r, n), e.g. a sensor's pad
        forces): {"normal": (k, L, r), "shear": (k, M, 2, r), "spin": (k, r)}."""
        return {"normal": np.einsum("rn,kln->klr", operator, self.normal_fields),
                "shear": np.einsum("rn,klan->klar", operator, self.shear_fields),
                "spin": np.einsum("rn,kn->kr", operator, self.spin_fields)}

    # --- storage --------------------------------------------------------------------------------------------
    def save(self, path) -> Path:
        """Write an .npz (fields as float32: the FEM's own discretisation error is larger; ``fit_base_response``
        returns them at that precision already) atomically."""
        from fem.atomic import atomic_path

        path = Path(path)
        with atomic_path(path) as temporary, open(temporary, "wb") as handle:
            np.savez_compressed(
                handle, schema=np.array(SCHEMA), design=np.array(json.dumps(self.design.to_dict())),
                provenance=np.array(json.dumps(self.provenance)), positions=self.positions,
                triangles=self.triangles.astype(np.int32), centres=self.centres, normal_levels=self.normal_levels,
                shear_levels=self.shear_levels, normal_fields=self.normal_fields.astype(np.float32),
                shear_fields=self.shear_fields.astype(np.float32), spin_fields=self.spin_fields.astype(np.float32))
        return path

    @classmethod
    def load(cls, path=PACKAGED_BASE_RESPONSE) -> "BaseResponse":
        """Read a file written by ``save`` (default: the packaged 3x3 fingertip); ValueError names what is wrong."""
        path = Path(path)
        try:
            with np.load(path, allow_pickle=False) as data:
                content = {name: data[name] for name in data.files}
        except (OSError, ValueError, EOFError) as error:
            raise ValueError(f"base-response file {path}: cannot be read ({error})") from None
        if str(content.get("schema")) != SCHEMA:
            raise ValueError(f"base-response file {path}: schema {content.get('schema')!r}, expected {SCHEMA!r}")
        design = ArrayFingertipDesign.from_dict(json.loads(str(content["design"])))
        return cls(design, content["positions"].astype(float), content["triangles"].astype(np.int64),
                   content["centres"].astype(float), content["normal_levels"].astype(float),
                   content["normal_fields"].astype(float), content["shear_levels"].astype(float),
                   content["shear_fields"].astype(float), content["spin_fields"].astype(float),
                   json.loads(str(content["provenance"])))


def fit_base_response(design: ArrayFingertipDesign, press: tuple, shears: list[tuple], twists: list[tuple],
                      positions, triangles, centres, provenance: dict | None = None) -> BaseResponse:
    """The response surface from FEM paths, each given as (bump states (t, k, 4), bump fields (t, k, n)):
    ``press`` one press path at several forces; ``shears`` paths pressed then sheared (each at one press force,
    along x or y; their first increment is the press), grouped by press force; ``twists`` paths pressed then
    twisted. Returns the BaseResponse with each fit's relative rms residual in ``provenance["fit"]``."""
    states, fields = (np.asarray(a, dtype=float) for a in press)
    order = np.argsort(states[:, :, 0].mean(axis=1))
    states, fields = states[order], fields[order]
    normal_levels = states[:, :, 0].mean(axis=1)                                            # (L,) mean bump force
    count = states.shape[1]
    normal_fields = (fields / states[:, :, :1]).transpose(1, 0, 2)                          # (k, L, n)
    response = BaseResponse(design, np.asarray(positions, float), np.asarray(triangles), np.asarray(centres, float),
                            normal_levels, normal_fields, np.ones(1), np.zeros((count, 1, 2, len(positions))),
                            np.zeros((count, len(positions))))
    # shear: group the paths by their press force, fit Psi per level on what the normal part leaves
    groups: dict = {}
    for path_states, path_fields in shears:
        level = round(float(np.asarray(path_states)[0, :, 0].mean()), 6)
        groups.setdefault(level, []).append((np.asarray(path_states, float), np.asarray(path_fields, float)))
    shear_levels = np.array(sorted(groups))
    shear_fields = np.zeros((count, len(shear_levels), 2, len(positions)))
    residuals = {}
    for level_index, level in enumerate(shear_levels):
        rows = [(s[1:], f[1:] - response.bump_pressure(np.concatenate([s[1:, :, :1], 0 * s[1:, :, 1:]], axis=-1)))
                for s, f in groups[float(level)]]
        loads = np.concatenate([r[0] for r in rows])                                        # (m, k, 4)
        left = np.concatenate([r[1] for r in rows])                                         # (m, k, n)
        for bump in range(count):
            solution, *_ = np.linalg.lstsq(loads[:, bump, 1:3], left[:, bump], rcond=None)  # (2, n)
            shear_fields[bump, level_index] = solution
            misfit = left[:, bump] - loads[:, bump, 1:3] @ solution
            residuals.setdefault("shear", []).append(float(np.linalg.norm(misfit) / np.linalg.norm(left[:, bump])))
    response = BaseResponse(design, response.positions, response.triangles, response.centres, normal_levels,
                            normal_fields, shear_levels, shear_fields, response.spin_fields)
    # spin: what a twist leaves after the normal and shear parts, against each bump's own spin torque
    spin_fields = np.zeros((count, len(positions)))
    if twists:
        loads = np.concatenate([np.asarray(s, float)[1:] for s, _ in twists])
        left = np.concatenate([np.asarray(f, float)[1:] - response.bump_pressure(np.asarray(s, float)[1:])
                               for s, f in twists])
        for bump in range(count):
            spin = loads[:, bump, 3]
            if np.abs(spin).max() > 0.0:
                spin_fields[bump] = spin @ left[:, bump] / (spin @ spin)
                misfit = left[:, bump] - np.outer(spin, spin_fields[bump])
                residuals.setdefault("spin", []).append(float(np.linalg.norm(misfit)
                                                              / max(np.linalg.norm(left[:, bump]), 1e-300)))
    provenance = dict(provenance or {})
    provenance["fit"] = {name: {"rms_relative": float(np.sqrt(np.mean(np.square(values)))),
                                "max_relative": float(np.max(values))} for name, values in residuals.items()}
    # the fields at the precision ``save`` stores them in: a fit used as computed and the same fit read back from a
    # cache then give the same numbers (in float64 the closed loop's grip differed by up to 2e-5 between the two)
    return BaseResponse(design, response.positions, response.triangles, response.centres, normal_levels,
                        _stored(normal_fields), shear_levels, _stored(shear_fields), _stored(spin_fields), provenance)


def _stored(fields: np.ndarray) -> np.ndarray:
    """``fields`` rounded to float32, the precision of ``BaseResponse.save``, held as float64."""
    return np.asarray(fields, dtype=np.float32).astype(float)


def relative_error(response: BaseResponse, states, fields) -> float:
    """Relative L2 error of the response's per-bump fields against FEM ``fields`` (t, k, n) at ``states``."""
    model, fem = response.bump_pressure(np.asarray(states, float)), np.asarray(fields, float)
    return float(np.linalg.norm(model - fem) / max(np.linalg.norm(fem), 1e-300))
