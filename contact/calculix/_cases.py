"""The two CalculiX reference problems, run and read back per increment: a rigid sphere pressed into a layer
(axisymmetric) and one bump of the paper's fingertip pressed, then sheared or twisted by a rigid plate (half model).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from contact.calculix._deck import GelLaw, bump_deck, sphere_press_deck
from contact.calculix._files import read_dat, read_frd
from contact.calculix._mesh import axisymmetric_bump, axisymmetric_layer, bump
from contact.calculix._run import CalculixFailed, run_deck, run_seconds
from fem.validation import check_all, check_bool, check_integer, check_positive, check_range, parse_choice

__all__ = ["CalculixJob", "SpherePress", "PressRecord", "sphere_press_job", "sphere_press", "BumpSetup", "BumpRecord",
           "bump_job", "bump_path", "bump_press_job", "SLIP_TOLERANCE", "contact_state"]

# mm: a contact node sticks in an increment when it moved with the plate to within this (5 x the elastic slip
# tau / STICK_SLOPE <= 1e-3 mm a stuck point has). The nodal stresses CalculiX writes for mortar contact are smoothed
# (|tau|/p reached 1.6 at some nodes and 0.9 at others that slid), so they cannot tell stick from slip
SLIP_TOLERANCE = 5e-3
PRESS_INCREMENTS = (6, 7, 9)     # the bump's press, and the retries when ccx stops on a singular system


@dataclass(frozen=True)
class SpherePress:
    """Rigid sphere (frictionless) into a bonded layer: radius, layer thickness and radius [mm], E [MPa], nu,
    final depth [mm] in ``increments`` equal steps, element size at the contact and far away [mm]."""

    sphere_radius: float = 5.0
    thickness: float = 10.0
    layer_radius: float = 30.0
    youngs_modulus: float = 0.3
    poissons_ratio: float = 0.45
    depth: float = 2.0
    increments: int = 20
    size_contact: float = 0.2
    size_far: float = 3.0

    def __post_init__(self):
        check_all(*[lambda name=name: check_positive(name, getattr(self, name), "mm")
                    for name in ("sphere_radius", "thickness", "layer_radius", "size_contact", "size_far")],
                  lambda: check_positive("youngs_modulus", self.youngs_modulus, "MPa"),
                  lambda: check_range("poissons_ratio", self.poissons_ratio, 0.0, 0.5, high_open=True),
                  lambda: check_range("depth", self.depth, 0.0, 0.6 * self.sphere_radius, "mm", low_open=True),
                  lambda: check_integer("increments", self.increments, 2, 1000))


@dataclass(frozen=True)
class PressRecord:
    """One increment of a press: depth [mm], normal force [N], contact radius [mm] (current geometry), and for the
    bump the radius of gyration of the force on the base [mm]."""

    depth: float
    normal_force: float
    contact_radius: float
    base_spread: float = math.nan


def _cap_base_radius(area: float, sphere_radius: float) -> float:
    """Radius [mm] of the rim of a spherical cap of the given surface ``area`` [mm^2]: A = 2 pi R^2 (1 - cos t),
    rim R sin t (the contact hugs the sphere; its area counts the curved surface)."""
    cosine = 1.0 - area / (2.0 * math.pi * sphere_radius**2)
    return sphere_radius * math.sqrt(max(0.0, 1.0 - cosine**2))


@dataclass(frozen=True)
class CalculixJob:
    """Decks ready to run and the reader of their outputs: ``run()`` runs the first deck, and the next when ccx stops
    on a singular system (mortar contact now and then meets one at some active set; another incrementation of the
    press passes it; any other failure is raised at once), and gives (records, wall time [s] of the run that
    finished, as measured when it was computed).
    Build jobs in one thread (gmsh meshes them), run them in several (each is a ccx process)."""

    decks: tuple
    name: str
    read: Callable[[Path], list]

    def run(self) -> tuple[list, float]:
        failures = []
        for deck in self.decks:
            try:
                folder = run_deck(deck, self.name)
            except CalculixFailed as error:
                failures.append(str(error))
                if "singular" not in str(error):      # a divergence is not helped by another press incrementation
                    break
                continue
            return self.read(folder), run_seconds(folder)
        raise CalculixFailed(f"every deck of {self.name!r} failed:\n" + "\n".join(failures))


def sphere_press_job(setup: SpherePress, law: GelLaw | str) -> CalculixJob:
    """The press as a CalculiX job; its records: every increment's depth, force and contact radius."""
    law = parse_choice("law", law, GelLaw)
    reach = min(0.95, math.asin(min(1.0, 1.25 * math.sqrt(setup.depth * setup.sphere_radius) / setup.sphere_radius)))
    mesh = axisymmetric_layer(setup.layer_radius, setup.thickness, setup.sphere_radius, setup.size_contact,
                              setup.size_far, 1.3 * setup.sphere_radius * math.sin(reach), reach)

    def read(folder: Path) -> list[PressRecord]:
        records = []
        tables = read_dat(folder / "press.dat")
        areas = {round(t.time, 9): 180.0 * t.array[3, 0] for t in tables if t.what == "statistics"}
        for table in tables:                   # CAX: printed for the 2 degree segment; x 180 for the whole ring
            time = round(table.time, 9)
            repeated = records and abs(table.time * setup.depth - records[-1].depth) < 1e-5 * setup.depth
            if table.set_name == "BAND" and table.what.startswith("total force") and time in areas and not repeated:
                records.append(PressRecord(table.time * setup.depth, float(-180.0 * table.array[0, 1]),
                                           _cap_base_radius(areas[time], setup.sphere_radius)))
        return records

    decks = tuple(sphere_press_deck(mesh, law, setup.youngs_modulus, setup.poissons_ratio, setup.depth, increments)
                  for increments in (setup.increments, setup.increments + 3))
    return CalculixJob(decks, "press", read)


def bump_press_job(setup: "BumpSetup", law: GelLaw | str, depth: float, increments: int = 16) -> CalculixJob:
    """The bump pressed frictionless by a rigid plate to ``depth`` [mm], axisymmetric: the bump on a disc of the
    cell's area (radius base_width / sqrt(pi)), CAX8R at ``setup.size_contact`` / 2 (the 3D mortar press, C3D10 at
    the full size, met singular systems past 1.3 mm with the Neo-Hookean gel). Records: depth, force, contact
    radius and the base force's radius of gyration sqrt(sum r^2 F / sum F) [mm]."""
    law = parse_choice("law", law, GelLaw)
    base_radius = setup.base_width / math.sqrt(math.pi)
    mesh = axisymmetric_bump(setup.bump_radius, base_radius, setup.base_thickness, 0.5 * setup.size_contact,
                             setup.size_far, min(setup.contact_reach, 3.6), 1.5 * setup.bump_radius)

    def read(folder: Path) -> list[PressRecord]:
        records = []
        tables = read_dat(folder / "press.dat")
        areas = {round(t.time, 9): 180.0 * t.array[3, 0] for t in tables if t.what == "statistics"}
        bases = {round(t.time, 9): t.array for t in tables if t.what.startswith("forces") and t.set_name == "BASE"}
        for table in tables:
            time = round(table.time, 9)
            repeated = records and abs(table.time * depth - records[-1].depth) < 1e-5 * depth
            if table.set_name == "BAND" and table.what.startswith("total force") and time in areas and not repeated:
                base = bases[time]
                radius = mesh.nodes[base[:, 0].astype(int) - 1, 0]
                spread = math.sqrt((radius**2 * base[:, 2]).sum() / base[:, 2].sum())
                records.append(PressRecord(table.time * depth, float(-180.0 * table.array[0, 1]),
                                           math.sqrt(areas[time] / math.pi), spread))
        return records

    decks = tuple(sphere_press_deck(mesh, law, setup.youngs_modulus, setup.poissons_ratio, depth, count)
                  for count in (increments, increments + 5))
    return CalculixJob(decks, "press", read)


def sphere_press(setup: SpherePress, law: GelLaw | str) -> tuple[list[PressRecord], float]:
    """CalculiX records of every increment of the press and the run's wall time [s]."""
    return sphere_press_job(setup, law).run()


@dataclass(frozen=True)
class BumpSetup:
    """One bump of the paper's fingertip on its share of the base layer, under a rigid plate (Coulomb friction).

    bump_radius, base_width (the bump's cell of the array), base_thickness [mm]; E [MPa], nu; the plate is pressed
    to ``depth`` [mm] and held there while it shifts by ``shear_shift`` [mm] or turns by ``twist_angle`` [rad] in
    ``increments`` increments; element sizes at the top and far away [mm]."""

    bump_radius: float = 0.35 * 40.0 / 3.0
    base_width: float = 40.0 / 3.0
    base_thickness: float = 3.0
    youngs_modulus: float = 0.3
    poissons_ratio: float = 0.45
    friction_coefficient: float = 1.0
    depth: float = 1.54              # mm: the project's linear FEM reaches 2.6 N here (h = 0.3 mm)
    shear_shift: float = 4.0
    twist_angle: float = 1.2
    increments: int = 10
    size_contact: float = 0.5
    size_far: float = 1.5
    frictional_press: bool = False   # friction on in the press too (else nearly frictionless, then switched on)

    def __post_init__(self):
        check_all(*[lambda name=name: check_positive(name, getattr(self, name), "mm")
                    for name in ("bump_radius", "base_width", "base_thickness", "shear_shift", "size_contact",
                                 "size_far")],
                  lambda: check_range("depth", self.depth, 0.0, 0.6 * self.bump_radius, "mm", low_open=True),
                  lambda: check_range("friction_coefficient", self.friction_coefficient, 0.0, 5.0, low_open=True),
                  lambda: check_range("twist_angle", self.twist_angle, 0.0, 2.0, "rad", low_open=True),
                  lambda: check_bool("frictional_press", self.frictional_press),
                  lambda: check_integer("increments", self.increments, 2, 1000))

    @property
    def contact_reach(self) -> float:
        """Radius [mm] of the bump surface offered to contact: 0.92 r (the plate cannot reach the equator)."""
        return 0.92 * self.bump_radius


@dataclass(frozen=True)
class BumpRecord:
    """One increment of a bump path, whole-body values: load kind ('press', 'shear', 'twist'); forces [N], torque
    [N mm] (from the base reactions), plate depth, shift [mm], angle [rad]; contact radius [mm] (current geometry)
    and stick ratio [-] recovered below the element size (``contact.recovery``, the FEM's own measure; a point sticks
    when it moved with the plate in the increment) and the nodal stick ratio; base-pressure CoP x [mm]; the base
    reactions (nodes' xy [mm] and z-forces [N] of the computed part)."""

    load_kind: str
    normal_force: float
    tangential_force: float
    torque: float
    depth: float
    shift: float
    angle: float
    contact_radius: float
    stick_ratio: float
    stick_ratio_nodal: float
    base_cop_x: float
    base_xy: np.ndarray
    base_force: np.ndarray


def _whole_surface(mesh, current, fields):
    """The contact surface's points (xy in the current geometry), triangles and point fields (each (n,) or (n, 2)),
    a half model reflected about y = 0 (its points on the plane kept once; 2-vectors get their y part reversed)."""
    triangles = mesh.surface_triangles()
    points = np.unique(triangles)
    local = np.full(mesh.nodes.shape[0] + 1, -1)
    local[points] = np.arange(points.size)
    xy, tri = current[points - 1, :2], local[triangles]
    fields = [np.asarray(f)[points - 1] for f in fields]
    if not mesh.half:
        return xy, tri, fields
    on_plane = np.abs(mesh.nodes[points - 1, 1]) < 1e-9
    image = np.where(on_plane, np.arange(points.size), points.size + np.cumsum(~on_plane) - 1)
    flip = np.array([1.0, -1.0])
    mirror = lambda f: np.concatenate([f, f[~on_plane] * (flip if f.ndim == 2 else 1.0)])
    return np.vstack([xy, xy[~on_plane] * flip]), np.vstack([tri, image[tri][:, ::-1]]), [mirror(f) for f in fields]


def contact_state(xy, triangles, pressure, shear, stuck, friction_coefficient):
    """Recovered contact radius and stick ratio (``contact.recovery`` with the points' status) and the nodal stick
    ratio, from nodal pressures, shear stresses and whether each point moved with the plate."""
    from contact._newton import OPEN, SLIP, STICK
    from contact.recovery import recover_contact, tributary_areas

    areas = tributary_areas(xy, triangles)
    status = np.where(pressure <= 0.0, OPEN, np.where(stuck, STICK, SLIP))
    recovered = recover_contact(xy, triangles, areas, pressure * areas, shear * areas[:, None], status,
                                friction_coefficient)
    touching = status != OPEN
    nodal = math.sqrt(areas[status == STICK].sum() / areas[touching].sum()) if touching.any() else 0.0
    return recovered.contact_radius, recovered.stick_ratio, nodal


def _plate_carries(previous: np.ndarray, shift: tuple, angle: tuple) -> np.ndarray:
    """Where points (n, 2) on the plate at the previous increment are now: the plate's transform x -> R(angle) x +
    (shift, 0), undone for the previous (shift, angle) and applied for the present one."""
    def turn(xy, theta):
        c, s = math.cos(theta), math.sin(theta)
        return np.column_stack([c * xy[:, 0] - s * xy[:, 1], s * xy[:, 0] + c * xy[:, 1]])

    return turn(turn(previous - [shift[0], 0.0], -angle[0]), angle[1]) + [shift[1], 0.0]


def bump_job(setup: BumpSetup, law: GelLaw | str, path: str) -> CalculixJob:
    """The bump's press then shear (half model) or twist (whole) as a CalculiX job; its records: every increment of
    the press and of the shear or twist."""
    from contact.calculix._deck import _plate

    law = parse_choice("law", law, GelLaw)
    if path not in ("shear", "twist"):
        raise ValueError(f"path={path!r}; allowed: 'shear', 'twist'")
    half = path == "shear"
    mesh = bump(setup.bump_radius, setup.base_width, setup.base_thickness, setup.size_contact, setup.size_far,
                min(setup.contact_reach, 3.6), setup.contact_reach, half)
    target = setup.shear_shift if path == "shear" else setup.twist_angle
    plate_width = 3.0 * setup.base_width
    decks = tuple(bump_deck(mesh, law, setup.youngs_modulus, setup.poissons_ratio, setup.friction_coefficient,
                            setup.depth, path, target, setup.increments, plate_width, press_increments=press,
                            frictional_press=setup.frictional_press)
                  for press in PRESS_INCREMENTS)
    plate_nodes = _plate(mesh.nodes.shape[0] + 1, plate_width, 8, half)[0]
    centre = mesh.nodes.shape[0] + 1 + int(np.flatnonzero(np.all(np.abs(plate_nodes) < 1e-9, axis=1))[0])
    arm = mesh.nodes.shape[0] + 1 + int(np.flatnonzero((np.abs(plate_nodes[:, 0] - plate_width / 2) < 1e-9)
                                                       & (np.abs(plate_nodes[:, 1:]) < 1e-9).all(axis=1))[0])
    factor = 2.0 if half else 1.0

    def read(folder: Path) -> list[BumpRecord]:
        bases = {round(t.time, 9): t.array for t in read_dat(folder / f"{path}.dat")
                 if t.what.startswith("forces") and t.set_name == "BASE"}
        _, steps = read_frd(folder / f"{path}.frd")
        records, before, last_time = [], None, -1.0
        everything = np.arange(1, mesh.nodes.shape[0] + 1)
        for step in steps:
            key = round(step.time, 9)
            if key not in bases or "CONTACT" not in step.blocks or (records and key - last_time < 1e-5):
                continue              # a step starts by writing its first state again (0.999999 then 1.0)
            last_time = key
            base = bases[key]                                                     # node, fx, fy, fz
            xy = mesh.nodes[base[:, 0].astype(int) - 1, :2]
            plate = step.field("DISP", [centre, arm])
            shift, angle = float(plate[0, 0]), float(math.atan2(plate[1, 1], plate_width / 2 + plate[1, 0]))
            current = mesh.nodes + step.field("DISP", everything)
            pressure = step.field("CONTACT", everything, "CPRESS")
            shear = np.column_stack([step.field("CONTACT", everything, "CSHEAR1"),
                                     step.field("CONTACT", everything, "CSHEAR2")])
            if before is None:
                stuck = np.ones(mesh.nodes.shape[0], bool)
            else:
                carried = _plate_carries(before[0][:, :2], (before[1], shift), (before[2], angle))
                stuck = np.linalg.norm(current[:, :2] - carried, axis=1) <= SLIP_TOLERANCE
            before = (current, shift, angle)
            surface_xy, triangles, (surface_pressure, surface_shear, surface_stuck) = _whole_surface(
                mesh, current, (pressure, shear, stuck))
            radius, stick, nodal = contact_state(surface_xy, triangles, surface_pressure, surface_shear,
                                                  surface_stuck, setup.friction_coefficient)
            records.append(BumpRecord(
                load_kind="press" if key < 1.0 + 1e-9 else path, normal_force=float(factor * base[:, 3].sum()),
                tangential_force=float(-factor * base[:, 1].sum()),
                torque=float(-factor * (xy[:, 0] * base[:, 2] - xy[:, 1] * base[:, 1]).sum()),
                depth=float(-plate[0, 2]), shift=shift, angle=angle, contact_radius=radius, stick_ratio=stick,
                stick_ratio_nodal=nodal, base_cop_x=float((xy[:, 0] * base[:, 3]).sum() / base[:, 3].sum()),
                base_xy=xy, base_force=base[:, 3]))
        return records

    return CalculixJob(decks, path, read)


def bump_path(setup: BumpSetup, law: GelLaw | str, path: str) -> tuple[list[BumpRecord], float]:
    """CalculiX records of the bump's path and the run's wall time [s]."""
    return bump_job(setup, law, path).run()
