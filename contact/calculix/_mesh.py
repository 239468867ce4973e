"""Meshes for the CalculiX reference, made with gmsh on one thread (the same mesh on every run), in CalculiX's
node order: an axisymmetric layer of 8-node quadrilaterals (CAX8R) under a rigid spherical band, and a
hemisphere bump of 10-node tetrahedra (C3D10) on its base layer under a rigid plate: the half y >= 0 for a shear
along x (mirror plane u_y = 0), the whole bump for a twist (CalculiX's mortar contact must not see extra
constraint equations on its slave surface, which a half-turn symmetry would put on the cut).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["AxisymmetricMesh", "axisymmetric_layer", "axisymmetric_bump", "BumpMesh", "bump", "CAX8_FACES",
           "C3D10_FACES",
           "C3D8_FACES"]

CAX8_FACES = ((0, 1), (1, 2), (2, 3), (3, 0))                       # CalculiX faces S1..S4 of a quadrilateral
C3D10_FACES = ((0, 1, 2), (0, 3, 1), (1, 3, 2), (2, 3, 0))          # S1..S4 of a tetrahedron (corner nodes)
C3D8_FACES = ((0, 1, 2, 3), (4, 7, 6, 5), (0, 4, 5, 1), (1, 5, 6, 2), (2, 6, 7, 3), (3, 7, 4, 0))
GMSH_TO_C3D10 = [0, 1, 2, 3, 4, 5, 6, 7, 9, 8]     # gmsh's tet10 has the edges 2-3 and 1-3 the other way round


def _gmsh_session(name: str):
    import gmsh

    if gmsh.isInitialized():
        gmsh.finalize()
    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)          # deterministic: one thread
    gmsh.option.setNumber("Mesh.RandomSeed", 1)
    gmsh.model.add(name)
    return gmsh


def _size_field(gmsh, formula: str) -> None:
    field = gmsh.model.mesh.field.add("MathEval")
    gmsh.model.mesh.field.setString(field, "F", formula)
    gmsh.model.mesh.field.setAsBackgroundMesh(field)
    for option in ("Mesh.MeshSizeExtendFromBoundary", "Mesh.MeshSizeFromPoints", "Mesh.MeshSizeFromCurvature"):
        gmsh.option.setNumber(option, 0)


def _nodes(gmsh) -> tuple[np.ndarray, np.ndarray]:
    """Node numbers (n,) and coordinates (n, 3) of the whole gmsh model, sorted by number."""
    tags, xyz, _ = gmsh.model.mesh.getNodes()
    order = np.argsort(tags)
    return tags[order].astype(np.int64), xyz.reshape(-1, 3)[order]


@dataclass(frozen=True)
class AxisymmetricMesh:
    """CAX8R layer (radial x, axial y; top at y = 0, base at y = -thickness) and the rigid band of the sphere.

    nodes (n, 2) [mm], node numbers are row + 1; quads (m, 8) and band (k, 8) node numbers; top_faces (f, 2)
    (element number, face 1..4) of the layer's top within the reach of the sphere, band_faces the band's outer
    faces; base, axis and band_nodes node numbers."""

    nodes: np.ndarray
    quads: np.ndarray
    band: np.ndarray
    top_faces: np.ndarray
    band_faces: np.ndarray
    base: np.ndarray
    axis: np.ndarray
    band_nodes: np.ndarray


def _second_order_elements(gmsh, dim: int, element_type: int, nodes_per: int, what: str
                           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mesh the open model in ``dim`` dimensions at second order; its node tags, coordinates and the connectivity of
    its one element type (gmsh's ``element_type`` with ``nodes_per`` nodes), refused if gmsh made any other."""
    gmsh.model.mesh.generate(dim)
    gmsh.model.mesh.setOrder(2)
    tags, xyz = _nodes(gmsh)
    types, _, connectivity = gmsh.model.mesh.getElements(dim)
    if list(types) != [element_type]:
        raise RuntimeError(f"gmsh made element types {list(types)} in the {what}; expected {nodes_per}-node elements "
                           f"only ({element_type})")
    return tags, xyz, np.asarray(connectivity[0], dtype=np.int64).reshape(-1, nodes_per)


def _quad8_mesh(gmsh, what: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mesh the open model's surfaces as 8-node quads (CAX8R); its node tags, coordinates and quad connectivity."""
    for option, value in (("Mesh.RecombineAll", 1), ("Mesh.Algorithm", 8), ("Mesh.RecombinationAlgorithm", 3),
                          ("Mesh.SecondOrderIncomplete", 1)):
        gmsh.option.setNumber(option, value)
    return _second_order_elements(gmsh, 2, 16, 8, what)


def _renumbered(tags: np.ndarray, connectivity: np.ndarray) -> np.ndarray:
    """Connectivity on node numbers from 1 in gmsh's node order (CalculiX's numbering)."""
    renumber = np.zeros(tags.max() + 1, dtype=np.int64)
    renumber[tags] = np.arange(1, tags.size + 1)
    return renumber[connectivity]


def _numbered_quads(tags: np.ndarray, xyz: np.ndarray, connectivity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Nodes (r, z) [mm] numbered from 1 in gmsh's order and the quads on those numbers, counter-clockwise."""
    nodes = xyz[:, :2].copy()
    return nodes, _counter_clockwise(nodes, _renumbered(tags, connectivity))


def _with_rigid_band(nodes, quads, top_faces, band_xy, number, cells: int, base_y: float) -> AxisymmetricMesh:
    """The mesh of a gel (nodes, quads, contact ``top_faces``) with a rigid body's band of ``cells`` quadratic quads
    appended: ``band_xy`` its node positions, numbered by ``number[row, k]`` on three rows (the middle one at even
    k only), face 1 of each quad the contact side; the gel's base nodes lie at y = ``base_y``, its axis at x = 0."""
    band = np.array([[number[0, k], number[0, k + 2], number[2, k + 2], number[2, k], number[0, k + 1],
                      number[1, k + 2], number[2, k + 1], number[1, k]] for k in range(0, 2 * cells, 2)])
    gel = np.unique(quads)
    base = gel[np.abs(nodes[gel - 1, 1] - base_y) < 1e-9]
    axis = gel[np.abs(nodes[gel - 1, 0]) < 1e-9]
    band_faces = np.column_stack([quads.shape[0] + 1 + np.arange(band.shape[0]), np.ones(band.shape[0], int)])
    return AxisymmetricMesh(np.vstack([nodes, band_xy]), quads, band,
                            np.array(top_faces, dtype=np.int64).reshape(-1, 2), band_faces, base, axis,
                            np.array(sorted(number.values())))


def axisymmetric_layer(layer_radius: float, thickness: float, sphere_radius: float, size_contact: float,
                       size_far: float, fine_radius: float, band_angle: float, band_thickness: float = 0.2
                       ) -> AxisymmetricMesh:
    """Quadrilateral CAX8R mesh of a layer (radius, thickness [mm]), h = size_contact within fine_radius of the
    axis and as deep, growing by 0.5 mm/mm to size_far; and a structured band of the rigid sphere (radius
    [mm], centre on the axis at y = radius) spanning ``band_angle`` [rad] from its lowest point."""
    gmsh = _gmsh_session("layer")
    try:
        gmsh.model.occ.addRectangle(0.0, -thickness, 0.0, layer_radius, thickness)
        gmsh.model.occ.synchronize()
        _size_field(gmsh, f"Min({size_far}, {size_contact} + 0.5 * Max(0, Max(x - {fine_radius}, "
                          f"-y - {fine_radius})))")
        tags, xyz, connectivity = _quad8_mesh(gmsh, "layer")
    finally:
        gmsh.finalize()
    nodes, quads = _numbered_quads(tags, xyz, connectivity)
    top_faces = [(element + 1, face + 1) for element, quad in enumerate(quads) for face, (i, j) in enumerate(CAX8_FACES)
                 if np.all(np.abs(nodes[quad[[i, j]] - 1, 1]) < 1e-9)
                 and nodes[quad[[i, j]] - 1, 0].max() <= sphere_radius * math.sin(band_angle)]
    # the band: arcs at radius R (the contact face), R - t/2 and R - t; quadratic quads, corners counter-clockwise
    count = max(4, int(math.ceil(band_angle * sphere_radius / size_contact)))
    angles = -0.5 * math.pi + np.linspace(0.0, band_angle, 2 * count + 1)
    first = nodes.shape[0] + 1
    band_xy, number = [], {}
    for ring, radius in enumerate((sphere_radius, sphere_radius - 0.5 * band_thickness,
                                   sphere_radius - band_thickness)):
        for k, angle in enumerate(angles):
            if ring == 1 and k % 2:
                continue
            number[ring, k] = first + len(band_xy)
            band_xy.append((radius * math.cos(angle), sphere_radius + radius * math.sin(angle)))
    return _with_rigid_band(nodes, quads, top_faces, band_xy, number, count, -thickness)


def axisymmetric_bump(bump_radius: float, base_radius: float, base_thickness: float, size_contact: float,
                      size_far: float, fine_radius: float, plate_width: float) -> AxisymmetricMesh:
    """CAX8R mesh of a bump (hemisphere of ``bump_radius`` [mm], top at y = 0) on a disc base (radius, thickness
    [mm]; base at y = -(r + thickness)), h = size_contact within fine_radius of the top, growing by 0.5 mm/mm to
    size_far; and the rigid plate as one row of quads on y >= 0 (``band``, its lower face the contact surface).
    ``top_faces`` are the edges on the hemisphere above the base top."""
    radius, height = bump_radius, bump_radius + base_thickness
    gmsh = _gmsh_session("axisymmetric_bump")
    try:
        occ = gmsh.model.occ
        base = occ.addRectangle(0.0, -height, 0.0, base_radius, base_thickness)
        ball = occ.addDisk(0.0, -radius, 0.0, radius, radius)
        keep = occ.addRectangle(0.0, -radius, 0.0, radius + 1.0, radius + 1.0)
        cap, _ = occ.intersect([(2, ball)], [(2, keep)])
        occ.fuse([(2, base)], cap)
        occ.synchronize()
        _size_field(gmsh, f"Min({size_far}, {size_contact} + 0.5 * Max(0, Sqrt(x^2 + y^2) - {fine_radius}))")
        tags, xyz, connectivity = _quad8_mesh(gmsh, "bump")
    finally:
        gmsh.finalize()
    nodes, quads = _numbered_quads(tags, xyz, connectivity)
    on_arc = lambda n: (np.abs(np.hypot(nodes[n - 1, 0], nodes[n - 1, 1] + radius) - radius) < 1e-6 * radius) & (
        nodes[n - 1, 1] > -radius + 1e-9)
    top_faces = [(element + 1, face + 1) for element, quad in enumerate(quads) for face, (i, j) in enumerate(CAX8_FACES)
                 if on_arc(quad[[i, j]]).all() and on_arc(quad[[4 + face]]).all()]
    # the plate: quads over [0, plate_width] x [0, 0.5], counter-clockwise, face 1 (the lower edge) the contact side
    cells = max(4, int(math.ceil(plate_width / size_far)))
    xs = np.linspace(0.0, plate_width, 2 * cells + 1)
    first = nodes.shape[0] + 1
    number, plate_xy = {}, []
    for row, y in enumerate((0.0, 0.25, 0.5)):
        for k, x in enumerate(xs):
            if row == 1 and k % 2:
                continue
            number[row, k] = first + len(plate_xy)
            plate_xy.append((x, y))
    return _with_rigid_band(nodes, quads, top_faces, plate_xy, number, cells, -height)


def _counter_clockwise(nodes: np.ndarray, quads: np.ndarray) -> np.ndarray:
    corners = nodes[quads[:, :4] - 1]
    area = 0.5 * np.sum(corners[:, :, 0] * np.roll(corners[:, :, 1], -1, axis=1)
                        - np.roll(corners[:, :, 0], -1, axis=1) * corners[:, :, 1], axis=1)
    quads = quads.copy()
    quads[area < 0] = quads[area < 0][:, [0, 3, 2, 1, 7, 6, 5, 4]]
    return quads


@dataclass(frozen=True)
class BumpMesh:
    """A bump of C3D10 tets (the half y >= 0, or whole), node numbers row + 1 of ``nodes`` (n, 3) [mm].

    tets (m, 10); top_faces (f, 2) (element, face 1..4) of the bump surface within the contact reach; base (the
    bonded sensor plane z = -height) and mirror (on y = 0, a half model only) node numbers; half: True for y >= 0."""

    nodes: np.ndarray
    tets: np.ndarray
    top_faces: np.ndarray
    base: np.ndarray
    mirror: np.ndarray
    half: bool

    def surface_triangles(self) -> np.ndarray:
        """(4 f, 3) node numbers of the flat triangles of the contact faces: each 6-node face split at its mid-side
        nodes into four (corner, mid, mid) and (mid, mid, mid)."""
        corner = np.array(C3D10_FACES)[self.top_faces[:, 1] - 1]               # (f, 3) local corners
        tets = self.tets[self.top_faces[:, 0] - 1]                              # (f, 10)
        middle = {(0, 1): 4, (1, 2): 5, (0, 2): 6, (0, 3): 7, (1, 3): 8, (2, 3): 9}
        rows = np.arange(tets.shape[0])
        a, b, c = (tets[rows, corner[:, k]] for k in range(3))
        mid = lambda i, j: tets[rows, [middle[tuple(sorted(pair))] for pair in zip(corner[:, i], corner[:, j])]]
        ab, bc, ca = mid(0, 1), mid(1, 2), mid(2, 0)
        return np.concatenate([np.column_stack(t) for t in ((a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca))])


def bump(bump_radius: float, base_width: float, base_thickness: float, size_contact: float, size_far: float,
         fine_radius: float, contact_reach: float, half: bool) -> BumpMesh:
    """Hemisphere (top at z = 0) on a square base layer (width [mm], sensor plane at z = -(r + thickness)), whole or
    the half y >= 0; h = size_contact within fine_radius of the top, growing by 0.5 mm/mm to size_far; the contact
    faces are those within ``contact_reach`` [mm] of the axis."""
    radius, height = bump_radius, bump_radius + base_thickness
    low_y = 0.0 if half else -base_width / 2
    gmsh = _gmsh_session("bump")
    try:
        occ = gmsh.model.occ
        box = occ.addBox(-base_width / 2, low_y, -height, base_width, base_width / 2 - low_y, base_thickness)
        ball = occ.addSphere(0.0, 0.0, -radius, radius)
        keep = occ.addBox(-radius - 1, min(low_y, -radius - 1) if not half else 0.0, -radius, 2 * radius + 2,
                          radius + 1 - (0.0 if half else min(low_y, -radius - 1)), radius + 1)
        cap, _ = occ.intersect([(3, ball)], [(3, keep)])
        occ.fuse([(3, box)], cap)
        occ.synchronize()
        _size_field(gmsh, f"Min({size_far}, {size_contact} + 0.5 * Max(0, Sqrt(x^2 + y^2 + z^2) - {fine_radius}))")
        gmsh.option.setNumber("Mesh.Algorithm3D", 1)
        gmsh.option.setNumber("Mesh.OptimizeNetgen", 1)
        tags, xyz, tets = _second_order_elements(gmsh, 3, 11, 10, "bump")
    finally:
        gmsh.finalize()
    tets = _renumbered(tags, tets[:, GMSH_TO_C3D10])
    used = np.unique(tets)
    nodes = xyz
    x = nodes[tets - 1]                                                   # (m, 10, 3)
    volume = np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0])
    flip = volume < 0
    tets[flip] = tets[flip][:, [0, 2, 1, 3, 6, 5, 4, 7, 9, 8]]
    base = used[np.abs(nodes[used - 1, 2] + height) < 1e-9]
    mirror = used[np.abs(nodes[used - 1, 1]) < 1e-9] if half else np.zeros(0, dtype=np.int64)
    return BumpMesh(nodes, tets, _bump_faces(nodes, tets, radius, contact_reach), base, mirror, half)


def _bump_faces(nodes, tets, radius, reach) -> np.ndarray:
    """Boundary faces (element, face 1..4) on the sphere within ``reach`` of the axis (all corners)."""
    faces = np.array(C3D10_FACES)
    corners = tets[:, :4][:, faces]                                       # (m, 4, 3)
    keys = np.sort(corners, axis=2).reshape(-1, 3)
    _, inverse, counts = np.unique(keys, axis=0, return_inverse=True, return_counts=True)
    boundary = counts[inverse.ravel()] == 1
    xyz = nodes[keys - 1]                                                 # (4 m, 3, 3)
    distance = np.linalg.norm(xyz - np.array([0.0, 0.0, -radius]), axis=2)
    on_sphere = np.all(np.abs(distance - radius) < 1e-6 * radius, axis=1)
    near = np.all(np.hypot(xyz[:, :, 0], xyz[:, :, 1]) <= reach, axis=1) & np.all(xyz[:, :, 2] > -radius + 1e-9, axis=1)
    chosen = np.flatnonzero(boundary & on_sphere & near)
    return np.column_stack([chosen // 4 + 1, chosen % 4 + 1])
