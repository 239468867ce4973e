"""CalculiX input decks as plain text: the axisymmetric sphere press and the bump's press-shear and press-twist.

The sphere press (frictionless) uses CalculiX's face-to-face penalty contact (``TYPE=SURFACE TO SURFACE``, a linear
pressure-overclosure law of slope ``PENALTY``); the bump, with friction, its mortar contact (``TYPE=MORTAR``: hard
contact by Lagrange multipliers, Coulomb friction with a stick slope ``STICK_SLOPE``; the penalty contact made the
frictional shear chatter between active sets for 60 iterations an increment). The gel is
either linear elastic without NLGEOM (small strain; contact still found in the deformed geometry) or a
compressible Neo-Hookean solid with NLGEOM (total Lagrangian; CalculiX manual, "*HYPERELASTIC": W = C10 (I1_bar -
3) + (J - 1)^2 / D1 with C10 = G/2, D1 = 2/K, so the small-strain shear and bulk moduli are G and K).
"""

from __future__ import annotations

import math

import numpy as np

from fem.validation import Choice

__all__ = ["GelLaw", "PENALTY", "STICK_SLOPE", "PRESS_FRICTION", "material_card", "sphere_press_deck", "bump_deck"]

# N/mm^3: penetration p / PENALTY at the sphere's peak pressures (0.1-0.2 MPa) is 1-2e-3 mm, below 0.2 % of the depths
PENALTY = 100.0
# N/mm^3: a stuck point's elastic slip tau / STICK_SLOPE stays below 1e-3 mm (tau <= mu p ~ 0.1 MPa), 0.3 % of a shear
# increment. CalculiX 2.20's mortar takes a non-positive slope, meant as the exact cone, but then lets stuck points
# creep (the bump's apex lagged the plate by 7 % per increment; with this slope it follows to 0.2 %)
STICK_SLOPE = 100.0
# the bump's press runs (nearly) frictionless and friction comes on with the shear or twist (*CHANGE FRICTION; ccx needs
# mu > 0): with friction in the press, mortar contact met singular systems at a depth of 1.0-1.3 mm at every stick
# slope tried (100, 1000), and without it the whole path passes. The FEM runs the same path (frictionless_press).
PRESS_FRICTION = 1e-3


class GelLaw(Choice):
    LINEAR = "linear"               # *ELASTIC, no NLGEOM: small strain (the project's gel law)
    NEO_HOOKE = "neo_hooke"         # *HYPERELASTIC, NEO HOOKE with NLGEOM: finite strain


def material_card(law: GelLaw, youngs_modulus: float, poissons_ratio: float) -> str:
    """The *MATERIAL block of the gel (name GEL) [MPa]."""
    if law == GelLaw.LINEAR:
        return f"*MATERIAL,NAME=GEL\n*ELASTIC\n{youngs_modulus:.10g},{poissons_ratio:.10g}\n"
    shear = youngs_modulus / (2.0 * (1.0 + poissons_ratio))
    bulk = youngs_modulus / (3.0 * (1.0 - 2.0 * poissons_ratio))
    return f"*MATERIAL,NAME=GEL\n*HYPERELASTIC,NEO HOOKE\n{shear / 2.0:.10g},{2.0 / bulk:.10g}\n"


def _lines(numbers, per_line: int = 12) -> str:
    numbers = [int(n) for n in numbers]
    return "".join(",".join(map(str, numbers[i:i + per_line])) + "\n" for i in range(0, len(numbers), per_line))


def _nset(name: str, numbers) -> str:
    return f"*NSET,NSET={name}\n" + _lines(numbers)


def _surface(name: str, faces: np.ndarray) -> str:
    return f"*SURFACE,NAME={name},TYPE=ELEMENT\n" + "".join(f"{e},S{f}\n" for e, f in faces)


def _nodes(nodes: np.ndarray) -> str:
    return "*NODE\n" + "".join(f"{i + 1}," + ",".join(f"{v:.12g}" for v in row) + "\n" for i, row in enumerate(nodes))


def _elements(kind: str, elset: str, connectivity: np.ndarray, first: int) -> str:
    return f"*ELEMENT,TYPE={kind},ELSET={elset}\n" + "".join(
        f"{first + k}," + ",".join(map(str, row)) + "\n" for k, row in enumerate(connectivity))


def _interaction(penalty: float = PENALTY) -> str:
    return f"*SURFACE INTERACTION,NAME=CONTACT\n*SURFACE BEHAVIOR,PRESSURE-OVERCLOSURE=LINEAR\n{penalty:g}\n"


def _step(law: GelLaw, increment: float, body: str, minimum: float = 1e-5) -> str:
    geometry = ",NLGEOM" if law == GelLaw.NEO_HOOKE else ""
    return (f"*STEP{geometry},INC=2000\n*STATIC\n{increment:.6g},1.0,{minimum:.3g},{increment:.6g}\n{body}"
            f"*END STEP\n")


def sphere_press_deck(mesh, law: GelLaw, youngs_modulus: float, poissons_ratio: float, depth: float,
                      increments: int) -> str:
    """A rigid body (the band of prescribed nodes ``mesh.band``: a sphere's shell or a flat plate) pressed
    frictionless by ``depth`` [mm] into an axisymmetric gel in ``increments`` equal increments; prints the band's
    total reaction, the base's nodal reactions and the contact statistics, writes the contact stresses."""
    quads, band = mesh.quads, mesh.band
    output = ("*NODE PRINT,NSET=BAND,TOTALS=ONLY\nRF\n*NODE PRINT,NSET=BASE,TOTALS=YES\nRF\n"
              "*CONTACT PRINT,SLAVE=TOP,MASTER=BALL\nCF\n*NODE FILE\nU\n*CONTACT FILE\nCSTR\n")
    return (_nodes(mesh.nodes) + _elements("CAX8R", "LAYER", quads, 1)
            + _elements("CAX8R", "SPHERE", band, quads.shape[0] + 1)
            + _nset("BASE", mesh.base) + _nset("AXIS", mesh.axis) + _nset("BAND", mesh.band_nodes)
            + _surface("TOP", mesh.top_faces) + _surface("BALL", mesh.band_faces)
            + material_card(law, youngs_modulus, poissons_ratio) + "*MATERIAL,NAME=RIGID\n*ELASTIC\n1e6,0.3\n"
            + "*SOLID SECTION,ELSET=LAYER,MATERIAL=GEL\n*SOLID SECTION,ELSET=SPHERE,MATERIAL=RIGID\n"
            + _interaction() + "*CONTACT PAIR,INTERACTION=CONTACT,TYPE=SURFACE TO SURFACE\nTOP,BALL\n"
            + "*BOUNDARY\nBASE,1,2\nAXIS,1,1\nBAND,1,1\n"
            + _step(law, 1.0 / increments, f"*BOUNDARY\nBAND,2,2,{-depth:.10g}\n{output}"))


def _plate(first_node: int, width: float, cells: int, half: bool) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (n, 3) and C3D8 hexes (m, 8) (numbers from ``first_node``) of a plate (y >= 0 when ``half``), bottom at
    z = 0; a node sits at the origin (the plate's centre, ``cells`` even)."""
    xs = np.linspace(-width / 2, width / 2, cells + 1)
    ys = np.linspace(0.0, width / 2, cells // 2 + 1) if half else xs
    number, nodes = {}, []
    for k, z in enumerate((0.0, 0.5)):
        for i, x in enumerate(xs):
            for j, y in enumerate(ys):
                number[i, j, k] = first_node + len(nodes)
                nodes.append((x, y, z))
    hexes = [[number[i, j, 0], number[i + 1, j, 0], number[i + 1, j + 1, 0], number[i, j + 1, 0],
              number[i, j, 1], number[i + 1, j, 1], number[i + 1, j + 1, 1], number[i, j + 1, 1]]
             for i in range(len(xs) - 1) for j in range(len(ys) - 1)]
    return np.array(nodes), np.array(hexes)


def _plate_motion(nodes: np.ndarray, numbers: np.ndarray, depth: float, shift: float, angle: float) -> str:
    """*BOUNDARY lines moving each plate node rigidly: turned by ``angle`` [rad] about z, shifted by ``shift`` [mm]
    along x and lowered by ``depth`` [mm] (exact at the step's end; CalculiX ramps linearly within the step)."""
    cosine, sine = math.cos(angle), math.sin(angle)
    x, y = nodes[:, 0], nodes[:, 1]
    moved = np.column_stack([cosine * x - sine * y + shift - x, sine * x + cosine * y - y, np.full(x.size, -depth)])
    return "*BOUNDARY\n" + "".join(f"{n},{k + 1},{k + 1},{v:.12g}\n" for n, row in zip(numbers, moved)
                                   for k, v in enumerate(row))


def bump_deck(mesh, law: GelLaw, youngs_modulus: float, poissons_ratio: float, friction_coefficient: float,
              depth: float, path: str, target: float, increments: int, plate_width: float,
              press_increments: int = 6, frictional_press: bool = False) -> str:
    """A bump under a rigid plate, CalculiX mortar contact (hard; Coulomb friction with ``friction_coefficient``, stuck
    points held by STICK_SLOPE):
    step 1 presses it by ``depth`` [mm] in ``press_increments`` increments (friction PRESS_FRICTION); then, at that
    depth and with friction on, the plate is shifted
    along +x (``path='shear'``, one step of ``increments`` increments, half model) or turned about z through the bump
    axis (``'twist'``, ``increments`` steps of one rigid turn each, whole model) to ``target`` [mm or rad].
    ``frictional_press``: friction ``friction_coefficient`` from the start (no *CHANGE FRICTION; the Neo-Hookean gel
    diverges at that change). The plate's nodes are prescribed (a rigid body's constraint equations would sit on the
    mortar surfaces). Prints the base reactions; writes displacements and contact stresses of every increment."""
    if path not in ("shear", "twist"):
        raise ValueError(f"path={path!r}; allowed: 'shear', 'twist'")
    if (path == "shear") != mesh.half:
        raise ValueError(f"path={path!r} needs the {'half' if path == 'shear' else 'whole'} bump mesh")
    tets = mesh.tets
    first = mesh.nodes.shape[0] + 1
    plate_nodes, plate_hexes = _plate(first, plate_width, 8, mesh.half)
    numbers = np.arange(first, first + plate_nodes.shape[0])
    output = "*NODE PRINT,NSET=BASE,TOTALS=YES\nRF\n*NODE FILE\nU\n*CONTACT FILE\nCSTR\n"
    symmetry = (_nset("MIRROR", np.setdiff1d(mesh.mirror, mesh.base)) + "*BOUNDARY\nMIRROR,2,2\n") if mesh.half else ""
    friction = ("" if frictional_press else
                f"*CHANGE FRICTION,INTERACTION=CONTACT\n*FRICTION\n{friction_coefficient:.10g},{STICK_SLOPE:g}\n")
    press_friction = friction_coefficient if frictional_press else PRESS_FRICTION
    if path == "shear":
        motion = _step(law, 1.0 / increments, friction + _plate_motion(plate_nodes, numbers, depth, target, 0.0)
                       + output)
    else:
        motion = "".join(_step(law, 1.0, (friction if k == 1 else "")
                               + _plate_motion(plate_nodes, numbers, depth, 0.0, target * k / increments) + output)
                         for k in range(1, increments + 1))
    return (_nodes(np.vstack([mesh.nodes, plate_nodes])) + _elements("C3D10", "GEL", tets, 1)
            + _elements("C3D8", "PLATE", plate_hexes, tets.shape[0] + 1)
            + _nset("BASE", mesh.base) + _surface("BUMP", mesh.top_faces)
            + _surface("PLATE", np.column_stack([tets.shape[0] + 1 + np.arange(plate_hexes.shape[0]),
                                                 np.ones(plate_hexes.shape[0], int)]))
            + material_card(law, youngs_modulus, poissons_ratio) + "*MATERIAL,NAME=RIGID\n*ELASTIC\n1e6,0.3\n"
            + "*SOLID SECTION,ELSET=GEL,MATERIAL=GEL\n*SOLID SECTION,ELSET=PLATE,MATERIAL=RIGID\n"
            + f"*SURFACE INTERACTION,NAME=CONTACT\n*FRICTION\n{press_friction:g},{STICK_SLOPE:g}\n"
            + "*CONTACT PAIR,INTERACTION=CONTACT,TYPE=MORTAR\nBUMP,PLATE\n" + "*BOUNDARY\nBASE,1,3\n" + symmetry
            + _step(law, 1.0 / press_increments, _plate_motion(plate_nodes, numbers, depth, 0.0, 0.0) + output)
            + motion)
