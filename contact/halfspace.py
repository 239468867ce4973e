"""Coupled half-space reference: a boundary-element compliance with the full Boussinesq-Cerruti coupling.

An elastic half-space z < 0 (shear modulus G, Poisson's ratio nu) is loaded on its surface by tractions that are
uniform over the square cells of a regular grid (spacing h); displacements are taken at the cell centres. A unit
surface force F at the origin displaces a surface point at (X, Y), rho = sqrt(X^2 + Y^2), by (Boussinesq
1885, Cerruti 1882; Johnson 1985, sec. 2.2 and 3.2), in the toolkit's frame (z up, the body pressing down):

    u_x = [(1 - nu)/rho + nu X^2/rho^3] F_x/(2 pi G) + nu X Y/rho^3 F_y/(2 pi G) + (1 - 2 nu) X/rho^2 F_z/(4 pi G)
    u_y = nu X Y/rho^3 F_x/(2 pi G) + [(1 - nu)/rho + nu Y^2/rho^3] F_y/(2 pi G) + (1 - 2 nu) Y/rho^2 F_z/(4 pi G)
    u_z = -(1 - 2 nu) (X F_x + Y F_y)/rho^2/(4 pi G) + (1 - nu)/rho F_z/(2 pi G)

The terms in (1 - 2 nu) are the normal-tangential coupling that Cattaneo-Mindlin leaves out: a normal load draws
the surface towards it, a tangential load lifts the surface behind it and depresses it ahead. The cell integrals of
1/rho, X^2/rho^3, X Y/rho^3 and X/rho^2 have closed forms (Love 1929 for the first), so the influence matrix is
exact for piecewise-constant tractions. It is a Toeplitz matrix: blocks are gathered from one kernel table and
displacements of a whole traction field come from an FFT convolution.

``HalfSpaceCompliance`` has the interface of ``contact.compliance.SurfaceCompliance``, so the same semi-smooth
Newton method (``contact._newton``) and load-path controls solve the frictional half-space problem along a scene's
load path (``solve_halfspace``): only the elastic body differs from the FEM, which makes the pair a direct measure
of what the finite gel and its discretisation add to the half-space physics.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.signal import fftconvolve

from contact.scene import BodyShape, GelShape, LoadKind, Scene

__all__ = ["HalfSpaceCompliance", "HalfSpaceIncrement", "cell_integrals", "grid_triangles", "solve_halfspace",
           "coupled_reference"]


def cell_integrals(x: np.ndarray, y: np.ndarray, spacing: float) -> dict[str, np.ndarray]:
    """Integrals over the square [x - h/2, x + h/2] x [y - h/2, y + h/2] of 1/rho, X^2/rho^3, Y^2/rho^3, XY/rho^3,
    X/rho^2 and Y/rho^2 [mm, mm, mm, mm, mm, mm], for offsets (x, y) that are whole multiples of h (corners never
    on an axis)."""
    half = 0.5 * spacing

    def corners(antiderivative):
        return (antiderivative(x + half, y + half) - antiderivative(x - half, y + half)
                - antiderivative(x + half, y - half) + antiderivative(x - half, y - half))

    # antiderivatives F with d^2 F / dX dY = f, each up to terms of one variable (they cancel in the corner sum)
    inverse = corners(lambda X, Y: X * np.arcsinh(Y / np.abs(X)) + Y * np.arcsinh(X / np.abs(Y)))
    xx = corners(lambda X, Y: Y * np.arcsinh(X / np.abs(Y)))
    yy = corners(lambda X, Y: X * np.arcsinh(Y / np.abs(X)))
    xy = corners(lambda X, Y: -np.hypot(X, Y))
    x_over = corners(lambda X, Y: 0.5 * Y * np.log(X * X + Y * Y) + X * np.arctan(Y / X))
    y_over = corners(lambda X, Y: 0.5 * X * np.log(X * X + Y * Y) + Y * np.arctan(X / Y))
    return {"1/rho": inverse, "xx/rho3": xx, "yy/rho3": yy, "xy/rho3": xy, "x/rho2": x_over, "y/rho2": y_over}


def _kernel(shear_modulus: float, poissons_ratio: float, spacing: float, reach_x: int, reach_y: int,
            coupled: bool = True) -> np.ndarray:
    """(3, 3, 2 reach_x + 1, 2 reach_y + 1) displacement [mm/N] at offsets (i h, j h) from a cell carrying a unit
    force spread uniformly over it, component a due to force component b; ``coupled=False`` drops the (1 - 2 nu)
    terms (Goodman's approximation, the closed forms' assumption: docs/theory.md, sec. 8.1)."""
    i, j = np.meshgrid(np.arange(-reach_x, reach_x + 1), np.arange(-reach_y, reach_y + 1), indexing="ij")
    integrals = cell_integrals(i * spacing, j * spacing, spacing)
    nu = poissons_ratio
    tangential = 1.0 / (2.0 * math.pi * shear_modulus * spacing**2)
    coupling = (1.0 - 2.0 * nu) / (4.0 * math.pi * shear_modulus * spacing**2) if coupled else 0.0
    kernel = np.empty((3, 3) + i.shape)
    kernel[0, 0] = tangential * ((1.0 - nu) * integrals["1/rho"] + nu * integrals["xx/rho3"])
    kernel[1, 1] = tangential * ((1.0 - nu) * integrals["1/rho"] + nu * integrals["yy/rho3"])
    kernel[0, 1] = kernel[1, 0] = tangential * nu * integrals["xy/rho3"]
    kernel[2, 2] = tangential * (1.0 - nu) * integrals["1/rho"]
    kernel[0, 2] = coupling * integrals["x/rho2"]
    kernel[1, 2] = coupling * integrals["y/rho2"]
    kernel[2, 0] = -kernel[0, 2]
    kernel[2, 1] = -kernel[1, 2]
    return kernel


STORED_BLOCK_BYTES = 256e6    # largest block of the influence matrix kept between Newton steps


class HalfSpaceCompliance:
    """Compliance [mm/N] between the dofs (x, y, z per cell) of an n_x x n_y grid of surface cells of spacing h.

    Cell centres: x = (i - (n_x - 1)/2) h; y likewise, or y = (j + 1/2) h for the half y > 0 of a body
    mirror-symmetric about y = 0 (``mirror_y``: the other half carries the mirrored tractions, t_y odd, t_x and the
    pressure even). ``coupled=False``: without the normal-tangential coupling (Goodman). Same interface as
    ``contact.compliance.SurfaceCompliance`` (no dof is constrained).
    """

    components = (0, 1, 2)

    def __init__(self, shear_modulus: float, poissons_ratio: float, spacing: float, n_x: int, n_y: int,
                 mirror_y: bool = False, coupled: bool = True):
        if not (n_x >= 2 and n_y >= 2):
            raise ValueError(f"n_x={n_x!r}, n_y={n_y!r}: a grid needs at least 2 x 2 cells")
        self.spacing, self.n_x, self.n_y, self.mirror_y = float(spacing), int(n_x), int(n_y), bool(mirror_y)
        i, j = np.meshgrid(np.arange(n_x), np.arange(n_y), indexing="ij")
        self.cell_i, self.cell_j = i.ravel(), j.ravel()                     # (N,) grid indices of each cell
        centre_x = (self.cell_i - 0.5 * (n_x - 1)) * spacing
        centre_y = (self.cell_j + 0.5) * spacing if mirror_y else (self.cell_j - 0.5 * (n_y - 1)) * spacing
        self.positions = np.column_stack([centre_x, centre_y])              # (N, 2) [mm]
        self.areas = np.full(self.positions.shape[0], spacing**2)           # (N,) [mm^2]
        self.size = 3 * self.positions.shape[0]
        self.constrained = np.zeros(self.size, bool)
        self.reach_y = 2 * n_y if mirror_y else n_y                        # offsets to mirrored cells reach 2 n_y - 1
        self.kernel = _kernel(shear_modulus, poissons_ratio, spacing, n_x - 1, self.reach_y - 1, coupled)
        self.solves = 0
        self._stored_dofs, self._stored = None, None                        # block over the dofs asked for so far

    def unknown_index(self, local_points: np.ndarray) -> np.ndarray:
        """Flat indices (3 len(points),) of the dofs of the given cells."""
        return (np.asarray(local_points)[:, None] * 3 + np.arange(3)).ravel()

    def ensure(self, columns: np.ndarray) -> None:
        """Nothing to compute: every column comes from the kernel table."""

    def _offset_j(self, row_j: np.ndarray, column_j: np.ndarray, mirrored: bool) -> np.ndarray:
        if mirrored:                                   # the mirror image of cell j sits at y = -(j + 1/2) h
            return row_j + column_j + 1
        return row_j - column_j

    def block(self, row_index: np.ndarray | slice, columns: np.ndarray) -> np.ndarray:
        """C[rows, columns] gathered from the kernel (rows default to all dofs)."""
        rows = np.arange(self.size)[row_index]
        columns = np.asarray(columns)
        row_cell, row_comp = rows // 3, rows % 3
        column_cell, column_comp = columns // 3, columns % 3
        offset_i = self.cell_i[row_cell][:, None] - self.cell_i[column_cell][None, :] + self.n_x - 1
        components = (row_comp[:, None], column_comp[None, :])
        row_j, column_j = self.cell_j[row_cell][:, None], self.cell_j[column_cell][None, :]
        matrix = self.kernel[components + (offset_i, self._offset_j(row_j, column_j, False) + self.reach_y - 1)]
        if self.mirror_y:
            sign = np.where(column_comp == 1, -1.0, 1.0)[None, :]           # t_y is odd in y, t_x and p even
            matrix = matrix + sign * self.kernel[components + (offset_i,
                                                               self._offset_j(row_j, column_j, True) + self.reach_y - 1)]
        return matrix

    def gather(self, row_index: np.ndarray, columns: np.ndarray, out: np.ndarray) -> np.ndarray:
        """C[rows, columns] written into ``out`` (the Newton step's interface with SurfaceCompliance). The block over
        every dof asked for so far is kept and grown to the union when a request leaves it: the Newton steps of a
        path gather nearly the same active set again and again, and slicing a stored block costs a fraction of
        indexing the kernel table."""
        rows = np.arange(self.size)[row_index]
        columns = np.asarray(columns)
        wanted = np.union1d(rows, columns)
        if self._stored_dofs is None or np.setdiff1d(wanted, self._stored_dofs, assume_unique=True).size:
            known = wanted if self._stored_dofs is None else np.union1d(self._stored_dofs, wanted)
            if known.size**2 * 8 > STORED_BLOCK_BYTES:
                out[...] = self.block(rows, columns)
                return out
            self._stored_dofs, self._stored = known, self.block(known, known)
        position = np.searchsorted(self._stored_dofs, rows), np.searchsorted(self._stored_dofs, columns)
        out[...] = self._stored[np.ix_(*position)]
        return out

    def traction_grid(self, columns: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """(3, n_x, n_y) cell forces [N] from forces on flat dof indices (the full plane's lower half mirrored in)."""
        grid = np.zeros((3, self.n_x, self.n_y))
        columns = np.asarray(columns)
        np.add.at(grid, (columns % 3, self.cell_i[columns // 3], self.cell_j[columns // 3]), forces)
        return grid

    def displacement(self, columns: np.ndarray, forces: np.ndarray) -> np.ndarray:
        """Displacement at every dof [mm] for forces [N] on the given flat dof indices (FFT convolution)."""
        if len(columns) == 0:
            return np.zeros(self.size)
        grid = self.traction_grid(columns, forces)
        if self.mirror_y:                              # whole plane: rows j = 0..n_y-1 are y < 0 (mirrored), then y > 0
            lower = grid[:, :, ::-1] * np.array([1.0, -1.0, 1.0])[:, None, None]
            plane = np.concatenate([lower, grid], axis=2)
        else:
            plane = grid
        displacement = np.zeros((3,) + plane.shape[1:])
        for a in range(3):
            for b in range(3):
                if np.any(plane[b]):
                    displacement[a] += fftconvolve(plane[b], self.kernel[a, b], mode="same")
        if self.mirror_y:
            displacement = displacement[:, :, self.n_y:]
        return displacement.reshape(3, -1).T.ravel()

    @property
    def computed_columns(self) -> int:
        return 0


def grid_triangles(n_x: int, n_y: int) -> np.ndarray:
    """(2 (n_x - 1)(n_y - 1), 3) triangles joining the centres of an n_x x n_y grid (cell k = i n_y + j)."""
    i, j = np.meshgrid(np.arange(n_x - 1), np.arange(n_y - 1), indexing="ij")
    corner = (i * n_y + j).ravel()
    right, up, both = corner + n_y, corner + 1, corner + n_y + 1
    return np.concatenate([np.column_stack([corner, right, both]), np.column_stack([corner, both, up])])


@dataclass
class HalfSpaceIncrement:
    """One converged increment of the half-space solve (mm, N, MPa); areas and forces of the whole body."""

    load_kind: str
    normal_force: float
    tangential_force: float
    contact_radius: float             # sqrt(A_contact / pi) from cell areas [mm]
    stick_ratio: float                # sqrt(A_stick / A_contact) from cell areas [-]
    recovered: object                 # contact.recovery.RecoveredContact: boundaries below the cell size
    status: np.ndarray = field(repr=False, default=None)
    pressure: np.ndarray = field(repr=False, default=None)
    traction: np.ndarray = field(repr=False, default=None)


def _recover_on_plane(compliance: HalfSpaceCompliance, xy: np.ndarray, state, friction_coefficient: float):
    """Recovered boundaries on the whole grid: a half grid stops h/2 short of y = 0, so it is mirrored first."""
    from contact.recovery import recover_contact

    normal, tangential, status = state.normal_force, state.tangential_force, state.status
    n_x, n_y = compliance.n_x, compliance.n_y
    if compliance.mirror_y:
        lower = np.arange(xy.shape[0]).reshape(n_x, n_y)[:, ::-1]          # mirror image of cell (i, n_y - 1 - j)
        cells = np.concatenate([lower, lower[:, ::-1]], axis=1).ravel()    # whole-plane cell (i, j') -> half cell
        below = np.tile(np.arange(2 * n_y) < n_y, n_x)                      # y < 0
        flip = np.where(below, -1.0, 1.0)
        xy = np.column_stack([xy[cells, 0], flip * xy[cells, 1]])
        tangential = np.column_stack([tangential[cells, 0], flip * tangential[cells, 1]])
        normal, status, n_y = normal[cells], status[cells], 2 * n_y
    areas = np.full(xy.shape[0], compliance.spacing**2)
    return recover_contact(xy, grid_triangles(n_x, n_y), areas, normal, tangential, status, friction_coefficient)


def solve_halfspace(scene: Scene, spacing: float, extent: float | None = None,
                    coupled: bool = True) -> list[HalfSpaceIncrement]:
    """Solve the scene's load path with its body, friction and material on an elastic half-space instead of the gel.

    spacing : cell size h [mm]; extent : half-width of the gridded square around the body centre [mm] (default
    1.4 x the Hertz contact radius of the largest press, which must stay outside the contact); coupled : with the
    normal-tangential coupling (False: Goodman's approximation, which the closed forms make). The initial gap is
    the body's surface above the gel's top (``top_surface_height``): a sphere on a block, or a plane on a cap or
    flat cap (the profile of Fig. 3). Press and shear loads only; the grid is halved when the scene is
    mirror-symmetric about y = 0.
    """
    from contact._controls import check_feasible, controls as load_controls, scaled, solve_with_substeps
    from contact._newton import OPEN, STICK, ContactState, solve_increment
    from contact.limits import estimated_contact

    curved_gel = scene.gel.shape in (GelShape.CAP, GelShape.FLAT_CAP)
    if not (scene.body.shape == BodyShape.SPHERE and scene.gel.shape == GelShape.BLOCK
            or scene.body.shape == BodyShape.PLANE and curved_gel):
        raise ValueError(f"body.shape={scene.body.shape!r} on gel.shape={scene.gel.shape!r}: the half-space "
                         f"reference takes a sphere on a block or a plane on a cap or flat_cap")
    if any(load.kind == LoadKind.TWIST for load in scene.loads):
        raise ValueError("the half-space reference takes press and shear loads only (a twist is uncoupled; use Lubkin)")
    if not (spacing > 0 and math.isfinite(spacing)):
        raise ValueError(f"spacing={spacing!r} must be a positive cell size in mm")
    contact_radius, depth = estimated_contact(scene)
    extent = extent or 1.4 * contact_radius
    if extent <= contact_radius:
        raise ValueError(f"extent={extent!r} mm must exceed the estimated contact radius {contact_radius:.4g} mm")
    # a half grid when gel, body and loads are mirror-symmetric about y = 0: the block's rule (Scene.mirror_symmetric)
    # also holds for a cap or flat cap, which are solids of revolution about the z axis under a plane
    along_x = all(load.kind == LoadKind.PRESS or load.direction[1] == 0.0 for load in scene.loads)
    mirror = scene.contact.symmetry == "auto" and (scene.mirror_symmetric or curved_gel and along_x
                                                   and scene.body.center[1] == 0.0)
    n_x = 2 * int(math.ceil(extent / spacing)) + 1                     # odd: a cell centred below the body
    n_y = int(math.ceil(extent / spacing)) if mirror else n_x
    material = scene.material
    compliance = HalfSpaceCompliance(material.shear_modulus, material.nu, spacing, n_x, n_y, mirror, coupled)
    xy = compliance.positions + np.asarray(scene.body.center)
    gap0 = scene.body.initial_gap(xy) - scene.gel.geometry.top_surface_height(xy)
    lever = np.column_stack([-(xy[:, 1] - scene.body.center[1]), xy[:, 0] - scene.body.center[0]])
    augmentation = 2.0 * material.effective_modulus * np.sqrt(compliance.areas / np.pi)
    n = xy.shape[0]
    state = ContactState(np.zeros(n), np.zeros((n, 2)), np.zeros((n, 3)))
    multiplicity = 2.0 if mirror else 1.0
    increments = []
    for kind, control, friction_on in load_controls(scene):
        control = scaled(control, 1.0 / multiplicity)
        check_feasible(control, state, scene.contact.friction_coefficient, lever)
        mu = scene.contact.friction_coefficient if friction_on else 0.0

        def solve(start_state, target):
            return solve_increment(compliance, gap0, lever, augmentation, mu, start_state, target,
                                   seed_depth=0.5 * depth, tolerance=scene.contact.tolerance,
                                   max_iterations=scene.contact.max_iterations, mirror_y=mirror)

        state = solve_with_substeps(solve, state, control, lever)[0]
        status = state.status
        if np.any(status[(compliance.cell_i == 0) | (compliance.cell_i == n_x - 1) | (compliance.cell_j == n_y - 1)]
                  != OPEN):
            raise ValueError(f"the contact reaches the edge of the gridded square (extent={extent} mm): enlarge it")
        contact_area = multiplicity * float(compliance.areas[status != OPEN].sum())
        stick_area = multiplicity * float(compliance.areas[status == STICK].sum())
        recovered = _recover_on_plane(compliance, xy, state, mu if mu > 0 else scene.contact.friction_coefficient)
        increments.append(HalfSpaceIncrement(
            load_kind=kind, normal_force=multiplicity * float(state.normal_force.sum()),
            tangential_force=multiplicity * float(state.tangential_force[:, 0].sum()),
            contact_radius=math.sqrt(contact_area / math.pi),
            stick_ratio=math.sqrt(stick_area / contact_area) if contact_area > 0 else 0.0, recovered=recovered,
            status=status.copy(), pressure=state.normal_force / compliance.areas,
            traction=state.tangential_force / compliance.areas[:, None]))
    return increments


@functools.lru_cache(maxsize=16)
def coupled_reference(scene: Scene, spacing: float, coupled: bool = True) -> tuple[HalfSpaceIncrement, ...]:
    """``solve_halfspace(scene, spacing, coupled=coupled)``, remembered per (scene, spacing, coupled): studies compare
    many meshes with one reference path."""
    return tuple(solve_halfspace(scene, spacing, coupled=coupled))
