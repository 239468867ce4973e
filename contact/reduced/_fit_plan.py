"""The FEM load paths a design's own calibration runs: calibration and held-out paths on one mesh [mm, N, N mm].

Loads are set per bump, so that every design is calibrated over the same bump states whatever its bump count: the
closed loop's grip of about 2-24 N per finger on the shipped 3x3 fingertip is 0.25-2.7 N per bump. A plate (mu = 1)
presses at ``press_levels`` per bump; it shears along x and along y by force to ``load_ratios`` of the slip load at
each of ``shear_levels``; it twists at ``twist_level`` by ``torque_fractions`` of the array's slip torque estimate
mu P / k sum |r_i| (Coulomb point contacts at the bump centres); it shears along y then twists at the lowest shear
level. The held-out paths no fit sees: presses at other forces, a diagonal shear, and a shear along x then a
twist of the other sign, at forces between the calibrated ones.

The fine zone is sized for the largest press (``contact.limits.fine_zone``'s own rule), so that every path shares
one mesh, one factorization and the compliance columns of the points in contact; the element size at the bump tops
is the plan's, or less where the smallest press would leave fewer than the solver's 7 points per contact
(``contact_size``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_positive, check_range

from ._design import ArrayFingertipDesign

__all__ = ["FitPlan", "FitCase", "fit_scenes", "contact_size", "unrepresentable", "force_targets"]

X, Y, DIAGONAL = (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)
# elements across the smallest Hertz contact radius: 1.8 leaves >= 7 contact points (the solver's least) on the
# tetrahedral tops measured for the 2x2, 3x3 and 4x4 bench arrays
ELEMENTS_PER_RADIUS = 1.8


def _levels(name: str, values, low: float = 0.0, high: float = math.inf, unit: str = "N") -> tuple[float, ...]:
    if isinstance(values, (str, bytes)) or not hasattr(values, "__len__") or not len(values):
        raise ValueError(f"{name}={values!r} must be a non-empty list of numbers [{unit}]")
    values = tuple(float(v) for v in values)
    for index, value in enumerate(values):
        check_range(f"{name}[{index}]", value, low, high, unit, low_open=True, high_open=True)
    if any(b <= a for a, b in zip(values, values[1:])):
        raise ValueError(f"{name}={list(values)} must be increasing")
    return values


@dataclass(frozen=True)
class FitPlan:
    """FEM settings [mm] and per-bump loads [N] of a design's calibration (module docstring).

    size_contact, size_base, size_far : element sizes at the bump tops, on the sensor plane and elsewhere [mm].
    press_levels : per-bump forces of the press path [N], increasing, at least two.
    shear_levels : per-bump forces of the shear paths [N], increasing, at least two (the couple arm's fall).
    load_ratios : Q / (mu P) of the shear increments, increasing in (0, 1).
    twist_level : per-bump force of the twist path [N]; torque_fractions: its torques over mu P / k sum |r_i|.
    """

    size_contact: float = 0.7
    size_base: float = 1.0
    size_far: float = 3.0
    press_levels: tuple[float, ...] = (0.25, 0.7, 1.6, 2.7)
    shear_levels: tuple[float, ...] = (0.45, 1.6)
    load_ratios: tuple[float, ...] = (0.25, 0.5, 0.75)
    twist_level: float = 0.9
    torque_fractions: tuple[float, ...] = (0.15, 0.3, 0.45)
    friction: float = 1.0

    def __post_init__(self):
        for name in ("size_contact", "size_base", "size_far", "twist_level", "friction"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                raise ValueError(f"fit plan {name}={value!r} must be a number")
            check_positive(f"fit plan {name}", value)
        object.__setattr__(self, "press_levels", _levels("fit plan press_levels", self.press_levels))
        object.__setattr__(self, "shear_levels", _levels("fit plan shear_levels", self.shear_levels))
        object.__setattr__(self, "load_ratios", _levels("fit plan load_ratios", self.load_ratios, 0.0, 1.0, "-"))
        object.__setattr__(self, "torque_fractions",
                           _levels("fit plan torque_fractions", self.torque_fractions, 0.0, 1.0, "-"))
        for name in ("press_levels", "shear_levels"):
            if len(getattr(self, name)) < 2:
                raise ValueError(f"fit plan {name}={list(getattr(self, name))} needs at least two forces")
        if self.size_contact > self.size_far:
            raise ValueError(f"fit plan size_contact={self.size_contact} mm must not exceed size_far={self.size_far}")

    def document(self) -> dict:
        return {key: list(value) if isinstance(value, tuple) else value
                for key, value in dataclasses.asdict(self).items()}


@dataclass(frozen=True)
class FitCase:
    """One FEM path: a press to ``normal_force`` [N] then ``stages`` (kind, control, values, direction), or a press
    through ``press_forces`` [N]; ``role``: "press", "shear", "twist" (calibration) or "held_out"."""

    name: str
    role: str
    normal_force: float = 0.0
    stages: tuple = ()
    press_forces: tuple = ()


def unrepresentable(design: ArrayFingertipDesign) -> str | None:
    """Why the reduced model and the closed loop cannot represent ``design``, or None."""
    if design.bump_count < 2:
        return ("one bump: the closed loop's friction-limit model (Coulomb point contacts at the bump centres) "
                "carries no torque with a single contact, eq. 9's rigid transform needs two bumps, and the base "
                "pressure's couple arm cannot be told from its kernel without neighbours; a design needs 2 or more")
    return None


def contact_size(design: ArrayFingertipDesign, plan: FitPlan) -> float:
    """Element size at the bump tops [mm]: the plan's, or the smallest press's Hertz contact radius over
    ELEMENTS_PER_RADIUS if that is smaller."""
    e_star = design.youngs_modulus / (1.0 - design.poissons_ratio**2)
    radius = (3.0 * plan.press_levels[0] * design.bump_radius / (4.0 * e_star)) ** (1.0 / 3.0)
    return min(plan.size_contact, radius / ELEMENTS_PER_RADIUS)


def _slip_torque(design: ArrayFingertipDesign, bump_force: float, friction: float) -> float:
    """mu P_i sum |r_i| [N mm]: the array's slip torque about its centre with point contacts at the bump centres."""
    return friction * bump_force * float(np.linalg.norm(design.bump_centres, axis=1).sum())


def _round(values) -> tuple[float, ...]:
    return tuple(round(float(v), 9) for v in values)


def fit_cases(design: ArrayFingertipDesign, plan: FitPlan) -> tuple[FitCase, ...]:
    """The calibration and held-out paths of ``design`` (module docstring)."""
    count, mu = design.bump_count, plan.friction
    cases = [FitCase("press", "press", press_forces=_round(count * f for f in plan.press_levels))]
    for level in plan.shear_levels:
        force = count * level
        values = _round(r * mu * force for r in plan.load_ratios)
        cases += [FitCase(f"shear_x_{level:g}", "shear", round(force, 9), (("shear", "force", values, X),)),
                  FitCase(f"shear_y_{level:g}", "shear", round(force, 9), (("shear", "force", values, Y),))]
    torque = _slip_torque(design, plan.twist_level, mu)
    cases.append(FitCase("twist", "twist", round(count * plan.twist_level, 9),
                         (("twist", "force", _round(f * torque for f in plan.torque_fractions), X),)))
    low = plan.shear_levels[0]
    cases.append(FitCase("shear_twist", "twist", round(count * low, 9),
                         (("shear", "force", _round([0.3 * mu * count * low]), Y),
                          ("twist", "force", _round(f * _slip_torque(design, low, mu)
                                                    for f in plan.torque_fractions[:2]), X))))
    # held out: forces between the calibrated ones, a diagonal shear, shear then a twist of the other sign
    press = plan.press_levels
    middle = math.sqrt(press[0] * press[1]), math.sqrt(press[-2] * press[-1])
    cases.append(FitCase("held_out_press", "held_out", press_forces=_round(count * f for f in middle)))
    level = math.sqrt(plan.shear_levels[0] * plan.shear_levels[-1])
    cases.append(FitCase("held_out_shear_diagonal", "held_out", round(count * level, 9),
                         (("shear", "force", _round([0.3 * mu * count * level, 0.6 * mu * count * level]),
                           DIAGONAL),)))
    cases.append(FitCase("held_out_shear_twist", "held_out", round(count * level, 9),
                         (("shear", "force", _round([0.4 * mu * count * level]), X),
                          ("twist", "force", _round([-0.25 * _slip_torque(design, level, mu)]), X))))
    return tuple(cases)


def _scene(design: ArrayFingertipDesign, plan: FitPlan, name: str, loads, size: float, fine_radius):
    from contact.scene import BodySpec, ContactSpec, GelSpec, Material, MeshSettings, Scene

    half_x, half_y = design.footprint
    gel = GelSpec("array", (("rows", design.rows), ("cols", design.cols), ("bump_radius", design.bump_radius),
                            ("pitch", design.pitch), ("base_width", 2.0 * half_x), ("base_depth", 2.0 * half_y),
                            ("base_thickness", design.base_thickness)))
    return Scene(name=name, gel=gel, material=Material(design.youngs_modulus, design.poissons_ratio),
                 body=BodySpec("plane"), contact=ContactSpec(friction_coefficient=plan.friction),
                 mesh=MeshSettings(size_contact=size, size_far=plan.size_far, size_base=plan.size_base,
                                   fine_radius=fine_radius), loads=tuple(loads))


def fit_scenes(design: ArrayFingertipDesign, plan: FitPlan) -> dict:
    """{case name: (FitCase, Scene)} of ``design``, every scene on one mesh (the largest press's fine zone)."""
    from contact.limits import estimated_contact
    from contact.scene import Load, LoadKind

    def press(*forces):
        return Load(LoadKind.PRESS, "force", tuple(forces))

    reason = unrepresentable(design)
    if reason:
        raise ValueError(f"design {design.rows}x{design.cols} cannot be calibrated: {reason}")
    size = contact_size(design, plan)
    largest = design.bump_count * plan.press_levels[-1]
    probe = _scene(design, plan, "probe", [press(largest)], size, None)
    fine_radius = 1.3 * estimated_contact(probe)[0] + 2.0 * size
    scenes = {}
    for case in fit_cases(design, plan):
        if case.press_forces:
            loads = [press(*case.press_forces)]
        else:
            loads = [press(case.normal_force)] + [Load(LoadKind(kind), control, tuple(values), tuple(direction))
                                                  for kind, control, values, direction in case.stages]
        scenes[case.name] = (case, _scene(design, plan, case.name, loads, size, fine_radius))
    return scenes


def force_targets(scene) -> np.ndarray:
    """Per-increment (P [N], F_x [N], F_y [N], T [N mm]) targets of a force-controlled path (last value held)."""
    from contact.scene import LoadKind

    state = np.zeros(4)
    rows = []
    for load in scene.loads:
        for value in load.values:
            if load.kind == LoadKind.PRESS:
                state[0] = value
            elif load.kind == LoadKind.SHEAR:
                state[1:3] = value * np.asarray(load.direction) / math.hypot(*load.direction)
            else:
                state[3] = value
            rows.append(state.copy())
    return np.array(rows)
