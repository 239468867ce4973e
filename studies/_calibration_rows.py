"""Rows of the reduced-calibration study: FEM against reduced model per held-out quantity, and per-bump CoP shifts.

Shared by the study (``studies.reduced_calibration``) and its figure (``studies._calibration_plot``), which both
import from here and not from each other.

The per-bump CoP shift is measured alike on both sides, from the pressed state of the path, in two ways:
``cells`` - the centre of the sensor-plane pressure in each bump's Voronoi cell (FEM base nodes, model grid nodes);
``sensor`` - what the controller sees: the field sampled by ``controller.sensing.sensor.sample`` on the paper's 11 x 13
array at 3 mm pitch and reduced by ``controller.estimation.estimator.bump_positions`` (no noise, no noise gate).
Its error is the model minus the FEM per bump and axis, relative to the increment's largest FEM shift (a bump near
the twist centre or an axis across the load barely moves; the largest shift is the signal's scale).
"""

from __future__ import annotations

import math

import numpy as np

MODELS = ("closed_form", "calibrated", "packaged")
QUANTITIES = {            # quantity: unit
    "depth": "mm", "contact_radius": "mm", "base_spread": "mm", "base_total_force": "N", "plate_shift": "mm",
    "twist_angle": "rad", "stick_ratio": "-", "cop_shift": "mm"}
SIGNALS = ("cells", "sensor")
SENSOR_GRID_SPACING = 1.0          # mm, the closed loop's base grid (controller.closed_loop GRID_SPACING)


def largest_error(rows, label, quantity=None) -> float:
    """Largest finite |relative error| [-] of a model (column label) in the rows, of one quantity or all."""
    values = [abs(r[f"{label}_relative_error"]) for r in rows if quantity in (None, r["quantity"])]
    values = [v for v in values if math.isfinite(v)]
    return max(values) if values else math.nan


def quantity_rows(name, fem, predicted) -> list[dict]:
    """Tidy rows: FEM value, each model's value, error and relative error, per increment, quantity (and bump).

    ``fem`` and ``predicted[label]`` are PathSamples of one path. The CoP shift here is a vector per bump: its error
    is the length of the difference vector, relative to the increment's largest FEM shift (``cop_rows`` has the
    per-axis table).
    """
    rows = []
    has_shear = (fem.load_kind == "shear").any()
    press_only = not (~fem.pressed).any()
    bumps = fem.bump_normal_force.shape[1]
    fem_cop = fem.cop_shift
    model_cop = {label: model.cop_shift for label, model in predicted.items()}
    for i, kind in enumerate(fem.load_kind):
        head = dict(case=name, increment=i + 1, load_kind=str(kind), normal_force=float(fem.normal_force[i]),
                    tangential_force=float(np.hypot(*fem.tangential_force[i])), torque=float(fem.torque[i]))

        def add(quantity, fem_value, values, bump="", error=None, scale=None):
            row = dict(head, quantity=quantity, unit=QUANTITIES[quantity], bump=bump, fem=float(fem_value))
            for label in MODELS:
                value = values.get(label)
                row[label] = float(value) if value is not None else math.nan
            for label in MODELS:
                if label not in values:
                    row[f"{label}_error"] = row[f"{label}_relative_error"] = math.nan
                    continue
                difference = error[label] if error is not None else values[label] - fem_value
                reference = scale if scale is not None else abs(fem_value)
                row[f"{label}_error"] = float(difference)
                row[f"{label}_relative_error"] = float(difference / reference) if reference > 0 else math.nan
            rows.append(row)

        if kind == "press":
            if not press_only:
                continue
            add("depth", fem.depth[i], {k: m.depth[i] for k, m in predicted.items()})
            for b in range(bumps):
                add("contact_radius", fem.bump_contact_radius[i, b],
                    {k: m.bump_contact_radius[i, b] for k, m in predicted.items()}, bump=b)
            for b in range(bumps):
                add("base_spread", math.sqrt(max(fem.base_second_moment[i, b], 0.0)),
                    {k: math.sqrt(max(m.base_second_moment[i, b], 0.0)) for k, m in predicted.items()}, bump=b)
            add("base_total_force", fem.base_total_force[i], {k: m.base_total_force[i] for k, m in predicted.items()})
            continue
        if has_shear:             # a vector: the error is the length of the difference, relative to |FEM|
            add("plate_shift", np.linalg.norm(fem.shift[i]), {k: np.linalg.norm(m.shift[i]) for k, m in
                                                               predicted.items()},
                error={k: np.linalg.norm(m.shift[i] - fem.shift[i]) for k, m in predicted.items()})
        if kind == "twist":           # during a shear stage the FEM holds the angle (displacement control)
            add("twist_angle", fem.angle[i], {k: m.angle[i] for k, m in predicted.items()})
        add("stick_ratio", fem.stick_ratio[i], {k: m.stick_ratio[i] for k, m in predicted.items()})
        largest = float(np.linalg.norm(fem_cop[i], axis=1).max())
        for b in range(bumps):
            add("cop_shift", np.linalg.norm(fem_cop[i, b]), {k: np.linalg.norm(c[i, b]) for k, c in model_cop.items()},
                bump=b, error={k: np.linalg.norm(c[i, b] - fem_cop[i, b]) for k, c in model_cop.items()},
                scale=largest)
        add("base_total_force", fem.base_total_force[i], {k: m.base_total_force[i] for k, m in predicted.items()})
    return rows


class SensorView:
    """The paper's sensor array and the estimator's bump positions, applied to FEM results and reduced models."""

    def __init__(self, design):
        from controller.estimation.estimator import BumpLayout
        from controller.sensing.sensor import SensorArray

        self.array = SensorArray()                                           # 11 x 13 nodes at 3 mm
        self.layout = BumpLayout.grid((design.cols, design.rows), design.pitch)
        self._operators = {}

    def cop(self, readings) -> np.ndarray:
        """Per-bump CoP (t, k, 2) [mm] of readings (t, ny, nx) [N] (``bump_positions``, no noise gate)."""
        from controller.estimation.estimator import bump_positions

        return bump_positions(readings, self.array, self.layout)[1]

    def fem_cop(self, result) -> np.ndarray:
        """Sensor CoP (t, k, 2) [mm] of every increment of an FEM result."""
        from controller.estimation.bench import sensor_readings

        return self.cop(sensor_readings(result, self.array))

    def model_cop(self, tip, bump_force, displacement, tangential_force) -> np.ndarray:
        """Sensor CoP (t, k, 2) [mm] of the reduced model's base pressure for per-increment bump loads (t, k[, 2])."""
        from controller.sensing.sensor import PressureField, cell_force_operator, sample

        grid = tip.base_grid(SENSOR_GRID_SPACING)
        radius = tip.parameters.radius_coefficient * np.cbrt(np.maximum(bump_force, 0.0))
        frames = np.stack([tip.base_pressure(grid, force, a, delta, q) for force, a, delta, q
                           in zip(bump_force, radius, displacement, tangential_force)])
        field = PressureField.from_grid(grid.x, grid.y, frames)
        key = (grid.x.size, grid.y.size, float(grid.x[0]), float(grid.y[0]))
        if key not in self._operators:
            self._operators[key] = cell_force_operator(field.positions, field.triangles, self.array)
        return self.cop(sample(field, self.array, operator=self._operators[key]))


COP_VARIANTS = {      # label: its error column
    "model": "error",                        # the calibrated reduced model along the path, its own bump loads
    "model_fem_loads": "error_fem_loads",    # its base pressure fed with the FEM's bump loads and displacements
    "closed_form": "error_closed_form"}      # the closed-form reduced model along the path


def cop_rows(name: str, role: str, fem, shifts: dict) -> list[dict]:
    """Per-bump, per-axis CoP-shift rows of the tangential increments of one path.

    ``shifts[signal][label]`` holds (t, k, 2) [mm] shifts from the pressed state, for label "fem" and the
    ``COP_VARIANTS``. Columns: case, role ("calibration" or "held_out"), increment, load_kind, normal_force [N],
    signal, bump, axis, fem [mm], then per variant its value [mm] and error (model - FEM over the increment's
    largest FEM shift of that signal, ``scale`` [mm]).
    """
    rows = []
    for signal, by_label in shifts.items():
        reference = by_label["fem"]
        for i in np.flatnonzero(~fem.pressed):
            scale = float(np.linalg.norm(reference[i], axis=1).max())
            for bump in range(reference.shape[1]):
                for axis, axis_name in enumerate("xy"):
                    row = dict(case=name, role=role, increment=int(i) + 1, load_kind=str(fem.load_kind[i]),
                               normal_force=float(fem.normal_force[i]), signal=signal, bump=bump, axis=axis_name,
                               fem=float(reference[i, bump, axis]))
                    for label, column in COP_VARIANTS.items():
                        if label in by_label:
                            row[label] = float(by_label[label][i, bump, axis])
                            row[column] = (row[label] - row["fem"]) / scale if scale > 0 else math.nan
                    row["scale"] = scale
                    rows.append(row)
    return rows


def largest_cop_error(rows, label: str = "model", signal: str | None = None, role: str = "held_out") -> float:
    """Largest finite |error| [-] of a CoP variant (``COP_VARIANTS``) over the rows of a role (and signal)."""
    column = COP_VARIANTS[label]
    values = [abs(r[column]) for r in rows if r["role"] == role and signal in (None, r["signal"]) and column in r]
    values = [v for v in values if math.isfinite(v)]
    return max(values) if values else math.nan
