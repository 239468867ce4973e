"""Sub-element recovery of the contact and stick boundaries and of the pressure from nodal contact forces.

A nodal contact solve decides open / stick / slip per surface point, so an area summed from nodal tributary areas
moves in steps of one element: c/a = sqrt(A_stick / A_contact) is quantised to about h/a. The fields carry more.
Near a smooth (incomplete) contact edge the pressure vanishes like the square root of the distance to the edge
(Johnson 1985, sec. 4.2 and 5.2), and near a stick-slip boundary so does the traction deficit mu p - |q|
(Cattaneo-Mindlin and the Ciavarella-Jager principle: in the stick zone mu p - |q| = mu p_c, the pressure of the
same profile at the smaller radius c; Lubkin's torsion has the same root). Their squares are smooth through the
boundary, and for a Hertz contact exactly quadratic in x and y:

    p^2 = p0^2 (1 - r^2/a^2),        (mu p - |q|)^2 = mu^2 p0^2 (c/a)^2 (1 - r^2/c^2).

For each of the two fields the recovery (1) divides the nodal forces by the tributary areas, (2) fits the square
with an area-weighted moving least-squares quadratic over the points where the field is positive (contact points,
stick points) and evaluates the fit there and one ring of points beyond, (3) corrects the data for the nodal
averaging, which flattens the square root next to the boundary: a nodal force is the integral of the field times
the point's hat function, so the fitted field's own hat averages are computed and the difference to its point
values is added to the data before refitting, and (4) takes the zero contour of the piecewise-linear interpolant
of the fitted square on the surface triangulation as the boundary, with areas cut exactly per triangle. Each stick
zone is fitted over patches of 40 or 80 points, whichever has the lesser leave-one-out error (the stick field is the
difference of two nodal forces and scatters more than the pressure; a wide patch averages that out under shear but
bends towards the cone that |q| ~ r makes at the centre under twist), and its fit is capped at zero at the points the
solve found slipping: the recovered stick boundary lies below the element size, but never beyond a point that slips
(without the cap the fit of a stick zone a few points across could reach past them: HCM-1 at nu = 0.49, h = a/5,
Q/(mu P) = 0.9 put c/a 0.017 above the reference). docs/coupled_reference.md gives the measurements.

The area weights make the fit conserve force where the nodal pressure of linear tetrahedra oscillates between
points of different valence; the square root of the first fit of p^2 (inside the recovered edge) is the recovered
pressure and its maximum the recovered peak pressure. An L2 projection with the consistent surface mass matrix, the textbook alternative,
amplifies that oscillation instead (HCM-1, h = 0.2 mm: peak pressure +18 % against +5 % nodal), so it is not used.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["RecoveredContact", "recover_contact", "moving_least_squares", "lumped_average", "tributary_areas",
           "positive_area", "surface_triangles"]

PATCH_POINTS = 40          # sources per moving least-squares patch (a quadratic has 6 coefficients)
# mu p - |q| is the difference of two nodal forces of similar size: on HCM-1 at h = a/5 it scatters about a smooth
# radial fit by 7-11 % (rms) of its peak, the pressure on the same points by 2.5-6 %, and a wider patch averages that
# out where the field is smooth (a quadratic under shear). Under twist it has a cone at the centre (|q| grows like r),
# which a wide patch bends the boundary fit towards. So each stick zone takes the patch of least leave-one-out error.
STICK_PATCH_CHOICES = (PATCH_POINTS, 2 * PATCH_POINTS)
CORRECTION_STEPS = 4       # refits with the nodal-averaging correction; the boundary moves < 1e-4 a after 3


@dataclass(frozen=True)
class RecoveredContact:
    """Contact and stick boundaries and pressure recovered below the element size (whole-body values).

    contact_area, stick_area : areas inside the recovered p = 0 and |q| = mu p contours [mm^2]
    contact_radius : sqrt(contact_area / pi) [mm]; stick_ratio : sqrt(stick_area / contact_area) [-]
    peak_pressure : largest recovered pressure [MPa]; pressure : (n,) recovered pressure at the points [MPa]
    """

    contact_area: float
    stick_area: float
    contact_radius: float
    stick_ratio: float
    peak_pressure: float
    pressure: np.ndarray


def moving_least_squares(source_xy: np.ndarray, source_values: np.ndarray, target_xy: np.ndarray,
                         source_weights: np.ndarray | None = None, patch_points: int = PATCH_POINTS,
                         reach: float = math.inf, leave_out: np.ndarray | None = None) -> np.ndarray:
    """Values at ``target_xy`` (m, 2) of local quadratic fits to scattered ``source_values`` (n,) at ``source_xy``.

    Each target takes its ``patch_points`` nearest sources within ``reach`` [mm], weights them by
    w = source_weight (1 - d^2/rho^2)^2, rho 1.5 x the distance to the farthest, and fits
    a + b x + c y + d x^2 + e x y + f y^2 centred on the target by weighted least squares (a plane where fewer than
    10 sources are in reach, the mean where fewer than 3). Returns the fitted value a at each target.
    With ``leave_out`` (m,) source indices, each target is fitted without that source (from its ``patch_points``
    nearest others): the leave-one-out fit. A lone source cannot be left out and fits itself.
    """
    source_xy = np.asarray(source_xy, float)
    target_xy = np.asarray(target_xy, float)
    n = source_xy.shape[0]
    if n == 0:
        raise ValueError("moving_least_squares needs at least one source point")
    k = min(patch_points + (0 if leave_out is None else 1), n)
    distance, index = cKDTree(source_xy).query(target_xy, k=k, distance_upper_bound=reach)
    distance, index = distance.reshape(len(target_xy), k), index.reshape(len(target_xy), k)     # (m, k)
    found = np.isfinite(distance)
    if not np.all(found[:, 0]):
        raise ValueError(f"a target point has no source within reach={reach} mm")
    if leave_out is not None and n > 1:
        found &= index != np.asarray(leave_out)[:, None]
    index = np.where(found, index, 0)
    distance = np.where(found, distance, 0.0)
    rho = 1.5 * distance.max(axis=1, keepdims=True) + 1e-300
    weight = np.where(found, (1.0 - (distance / rho) ** 2) ** 2, 0.0)                            # (m, k)
    if source_weights is not None:
        weight = weight * np.asarray(source_weights, float)[index]
    offset = (source_xy[index] - target_xy[:, None, :]) / rho[:, :, None]                        # (m, k, 2)
    x, y = offset[..., 0], offset[..., 1]
    design = np.stack([np.ones_like(x), x, y, x * x, x * y, y * y], axis=-1)                     # (m, k, 6)
    count = found.sum(axis=1)
    terms = np.where(count >= 10, 6, np.where(count >= 3, 3, 1))                                 # (m,)
    design = design * (np.arange(6)[None, None, :] < terms[:, None, None])
    normal = np.einsum("mk,mki,mkj->mij", weight, design, design)                                # (m, 6, 6)
    rhs = np.einsum("mk,mki,mk->mi", weight, design, np.asarray(source_values, float)[index])     # (m, 6)
    # the pseudo-inverse drops unused terms and the undetermined part of a patch whose points lie on a line
    return np.einsum("mj,mj->m", np.linalg.pinv(normal, rcond=1e-10, hermitian=True)[:, 0, :], rhs)


def positive_area(triangle_xy: np.ndarray, triangle_values: np.ndarray) -> np.ndarray:
    """Area [mm^2] of the part of each triangle (t, 3, 2) where the linear interpolant of (t, 3) values is > 0."""
    corners = np.asarray(triangle_xy, float)[..., :2]
    values = np.asarray(triangle_values, float)
    edge1, edge2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0])
    positive = values > 0.0
    count = positive.sum(axis=1)
    fraction = np.where(count == 3, 1.0, 0.0)
    # a corner alone on its side cuts off the sub-triangle v0^2 / ((v0 - v1)(v0 - v2)) of the triangle
    for alone_positive, positive_count in ((True, 1), (False, 2)):
        rows = np.flatnonzero(count == positive_count)
        if rows.size == 0:
            continue
        alone = np.argmax(positive[rows] == alone_positive, axis=1)
        v0, v1, v2 = (values[rows, (alone + shift) % 3] for shift in range(3))
        corner = v0 * v0 / ((v0 - v1) * (v0 - v2))
        fraction[rows] = corner if alone_positive else 1.0 - corner
    return area * fraction


def _sub_triangle_points(order: int) -> np.ndarray:
    """Barycentric centroids (order^2, 3) of the order^2 equal sub-triangles of a triangle (a midpoint rule)."""
    up = [(i + 1 / 3, j + 1 / 3) for i in range(order) for j in range(order - i)]
    down = [(i + 2 / 3, j + 2 / 3) for i in range(order - 1) for j in range(order - 1 - i)]
    first_two = np.array(up + down) / order
    return np.column_stack([first_two, 1.0 - first_two.sum(axis=1)])


QUADRATURE = _sub_triangle_points(8)      # 64 points: sqrt(psi) has a kink where a triangle crosses psi = 0


def tributary_areas(xy: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Area [mm^2] each node of a linear triangle mesh carries, a third of each triangle around it: the weights that
    integrate a P1 field exactly (the lumped mass of a surface)."""
    corners = xy[triangles]
    edge1, edge2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0])
    return np.bincount(triangles.ravel(), np.repeat(area / 3.0, 3), minlength=len(xy))


def lumped_average(xy: np.ndarray, triangles: np.ndarray, squared: np.ndarray) -> np.ndarray:
    """Nodal averages int f phi_j dA / int phi_j dA of f = sqrt(max(psi, 0)), psi the piecewise-linear interpolant
    of ``squared`` (n,) on ``triangles``: what a nodal force divided by its tributary area reports of f."""
    corners = xy[triangles]
    edge1, edge2 = corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]
    area = 0.5 * np.abs(edge1[:, 0] * edge2[:, 1] - edge1[:, 1] * edge2[:, 0])                  # (t,)
    root = np.sqrt(np.maximum(squared[triangles] @ QUADRATURE.T, 0.0))                          # (t, q)
    moments = area[:, None] * (root @ QUADRATURE) / QUADRATURE.shape[0]                         # (t, 3)
    weights = tributary_areas(xy, triangles)
    integrals = np.bincount(triangles.ravel(), moments.ravel(), minlength=len(xy))
    return np.divide(integrals, weights, out=np.zeros(len(xy)), where=weights > 0)


def _connected_parts(triangles: np.ndarray, inside: np.ndarray) -> list[np.ndarray]:
    """The inside points grouped into parts joined by triangle edges between inside points (one per contact)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    edges = np.concatenate([triangles[:, [0, 1]], triangles[:, [1, 2]], triangles[:, [2, 0]]])
    edges = edges[inside[edges].all(axis=1)]
    graph = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(len(inside),) * 2)
    labels = connected_components(graph, directed=False)[1]
    return [np.flatnonzero(inside & (labels == label)) for label in np.unique(labels[inside])]


def _leave_one_out_error(source_xy, square, source_areas, part_areas, patch_points) -> float:
    """Area-weighted rms of the leave-one-out residuals of the fit of ``square`` at the part's own points (the first
    len(part_areas) sources; a mirror image stays in, as the whole body's own point would). Weighted by the points'
    own areas, not the doubled ones of points on a mirror plane, so that a half model scores as its whole body."""
    n_part = len(part_areas)
    fitted = moving_least_squares(source_xy, square, source_xy[:n_part], source_areas, patch_points,
                                  leave_out=np.arange(n_part))
    return float(np.sqrt(np.average((fitted - square[:n_part]) ** 2, weights=part_areas)))


def _recovered_square(xy, triangles, areas, values, inside, mirror_y,
                      patch_choices: tuple[int, ...] = (PATCH_POINTS,)) -> tuple[np.ndarray, np.ndarray]:
    """Recovered square of the field ``values`` (positive where ``inside``) at the inside points and one ring
    around them (-inf elsewhere): with the nodal-averaging correction, and the first fit without it. Each
    connected part (the patch of one bump of an array) is fitted from its own points only, with the patch size of
    ``patch_choices`` whose leave-one-out error on the part's data is least (the first on a tie)."""
    recovered = np.full(len(xy), -np.inf)
    first_fit = recovered.copy()
    for part in _connected_parts(triangles, inside):
        member = np.zeros(len(xy), bool)
        member[part] = True
        ring = np.zeros(len(xy), bool)
        ring[triangles[np.any(member[triangles], axis=1)].ravel()] = True
        ring_triangles = triangles[np.all(ring[triangles], axis=1)]
        source_xy, source_areas = xy[part], areas[part]
        mirrored = source_xy[:, 1] > 0
        if mirror_y:                              # the other half of a mirror-symmetric body: the field is even in y
            source_areas = np.where(mirrored, source_areas, 2.0 * source_areas)   # on y = 0: half a star each side
            source_xy = np.concatenate([source_xy, source_xy[mirrored] * [1.0, -1.0]])
            source_areas = np.concatenate([source_areas, source_areas[mirrored]])
        measured = values[part]
        patch_points = patch_choices[0]
        if len(patch_choices) > 1:
            square = measured * np.abs(measured)
            square = np.concatenate([square, square[mirrored]]) if mirror_y else square
            errors = [_leave_one_out_error(source_xy, square, source_areas, areas[part], choice)
                      for choice in patch_choices]
            floor = 1e-9 * float(np.abs(square).max())         # below it, round-off: a tie, the first choice
            patch_points = patch_choices[int(np.argmin(np.maximum(errors, floor)))]
        data = measured
        for step in range(CORRECTION_STEPS + 1):
            square = data * np.abs(data)
            if mirror_y:
                square = np.concatenate([square, square[mirrored]])
            recovered[ring] = moving_least_squares(source_xy, square, xy[ring], source_areas, patch_points)
            if step == 0:
                first_fit[ring] = recovered[ring]
            averaged = lumped_average(xy, ring_triangles, np.where(ring, recovered, 0.0))[part]
            data = measured + np.sqrt(np.maximum(recovered[part], 0.0)) - averaged
    return recovered, first_fit


def surface_triangles(triangles: np.ndarray, points: np.ndarray, n_points: int) -> np.ndarray:
    """The triangles (t, 3) whose corners are all among ``points``, renumbered to positions in ``points``."""
    local = np.full(n_points, -1)
    local[np.asarray(points)] = np.arange(len(points))
    renumbered = local[np.asarray(triangles)]
    return renumbered[np.all(renumbered >= 0, axis=1)]


def recover_contact(xy: np.ndarray, triangles: np.ndarray, areas: np.ndarray, normal_force: np.ndarray,
                    tangential_force: np.ndarray, status: np.ndarray, friction_coefficient: float,
                    mirror_y: bool = False) -> RecoveredContact:
    """Recover contact radius, stick ratio and pressure from nodal contact forces on a surface triangulation.

    xy : (n, 2) point positions [mm]; triangles : (t, 3) indices into them (flat triangles of the contact surface)
    areas : (n,) nodal tributary areas [mm^2]; normal_force : (n,) [N]; tangential_force : (n, 2) [N]
    status : (n,) OPEN / STICK / SLIP per point; friction_coefficient : mu [-]
    mirror_y : the points are the half y >= 0 of a body mirror-symmetric about y = 0 (areas count twice)
    """
    from contact._newton import OPEN, SLIP, STICK

    xy = np.asarray(xy, float)[:, :2]
    triangles = np.asarray(triangles)
    areas = np.asarray(areas, float)
    normal_force = np.asarray(normal_force, float)
    tangential_force = np.asarray(tangential_force, float).reshape(-1, 2)
    status = np.asarray(status)
    if not (len(areas) == len(normal_force) == len(tangential_force) == len(status) == len(xy)):
        raise ValueError("xy, areas, normal_force, tangential_force and status need one entry per point")
    if not np.all(areas > 0):
        raise ValueError("areas must be positive")
    pressure = normal_force / areas
    deficit = (friction_coefficient * normal_force - np.linalg.norm(tangential_force, axis=1)) / areas
    in_contact = (status != OPEN) & (pressure > 0)
    stick = (status == STICK) & in_contact & (deficit > 0)
    square_pressure, fitted_pressure = _recovered_square(xy, triangles, areas, pressure, in_contact, mirror_y)
    square_deficit, _ = _recovered_square(xy, triangles, areas, deficit, stick, mirror_y, STICK_PATCH_CHOICES)
    # the recovered stick zone holds no point that the solve found slipping: where the fit extrapolates a positive
    # deficit to a slip point, the boundary is put at that point (the nodal solution's own bound on it)
    slipping = (status == SLIP) & np.isfinite(square_deficit)
    square_deficit[slipping] = np.minimum(square_deficit[slipping], 0.0)
    # mu p - |q| <= mu p: the stick zone lies inside the contact, also where too few points make the fits loose
    bound = square_pressure.copy()
    finite = np.isfinite(bound)
    bound[finite] *= friction_coefficient**2
    square_deficit = np.minimum(square_deficit, bound)
    multiplicity = 2.0 if mirror_y else 1.0

    def area_inside(square):
        values = np.where(np.isfinite(square), square, -1.0)[triangles]
        return multiplicity * float(positive_area(xy[triangles], values).sum())

    contact_area, stick_area = area_inside(square_pressure), area_inside(square_deficit)
    # the pressure field is the first fit: away from the edge the nodal averaging is O(h^2/a^2) (0.1 % at h = a/8),
    # below the point-to-point noise that the correction would feed back
    recovered_pressure = np.sqrt(np.maximum(np.where(np.isfinite(fitted_pressure) & (square_pressure > 0),
                                                     fitted_pressure, 0.0), 0.0))
    return RecoveredContact(
        contact_area=contact_area, stick_area=stick_area, contact_radius=math.sqrt(contact_area / math.pi),
        stick_ratio=math.sqrt(min(stick_area / contact_area, 1.0)) if contact_area > 0 else 0.0,
        peak_pressure=float(recovered_pressure.max()), pressure=recovered_pressure)
