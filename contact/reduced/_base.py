"""Base pressure of the reduced fingertip: what the sensor plane feels of each bump's loads [mm, N, MPa].

The gel is linear and the contact loads of bump i act on a patch of radius a_i ~ 1-2 mm, 7.7 mm above the sensor
plane: the pressure on the sensor plane is the superposition of each bump's response to its resultants (Saint-Venant),
P_i times a bell and the overturning moment of Q_i as a pressure couple (a tension-compression pair under the
leaning bump). The FEM's unit-load responses of single bumps fix the form:
the base carries the moment H Q_i of a load at the bump top (H = R + t; the unit fields' first moments are within
2 % of it), the bell and the couple have one width, and the base's free side faces reflect both (the FEM piles the
pressure up at the base edge; a cut-off kernel misses the edge bumps' CoP shifts by up to 14 %, the mirrored one
by 4 %). So per bump

    p_i(x) = P_i G(x - r_i) - M_i . (grad G)(x - r_i),    G = Gaussian of standard deviation sigma, mirrored at
                                                            the footprint's edges, zero outside it,

with the couple M_i = h(P_i) Q_i + g P_i delta_i (``_design``), so that p_i carries P_i and the moment M_i about
r_i exactly; to first order it is the bell moved by M_i / P_i, but linear in the loads (no cap, tension where the
couple exceeds the bell). Nothing in it depends on the contact radius: moving a unit load from a 1.0 to a 1.9 mm
patch changes its base second moment by 0.3 % in the FEM.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.validation import check_finite_array, check_positive

from ._design import ArrayFingertipDesign

__all__ = ["BaseGrid", "BaseKernel", "base_grid"]


@dataclass(frozen=True, eq=False)
class BaseGrid:
    """Regular grid on the sensor plane for the base pressure: x (nx,), y (ny,) [mm], reaching past the footprint.

    ``base_grid`` makes one; its border nodes lie outside the base layer, where the pressure is 0.
    """

    x: np.ndarray
    y: np.ndarray

    def __post_init__(self):
        for name in ("x", "y"):
            axis = check_finite_array(f"grid.{name}", getattr(self, name))
            if axis.ndim != 1 or axis.size < 3 or np.any(np.diff(axis) <= 0.0):
                raise ValueError(f"grid.{name} must be a strictly increasing 1D array of at least 3 points, "
                                 f"got shape {axis.shape}")
            object.__setattr__(self, name, axis)

    @property
    def spacing(self) -> float:
        return float(self.x[1] - self.x[0])

    @property
    def points(self) -> np.ndarray:
        """Grid points (ny nx, 2) [mm], row-major like a (ny, nx) pressure image raveled."""
        grid_x, grid_y = np.meshgrid(self.x, self.y)
        return np.column_stack([grid_x.ravel(), grid_y.ravel()])


def base_grid(design: ArrayFingertipDesign, spacing: float = 0.5) -> BaseGrid:
    """Square grid [mm] of the given spacing over the design's base layer, one node past its edges."""
    spacing = check_positive("spacing", spacing, "mm")
    count = int(math.floor(max(design.footprint) / spacing)) + 1
    axis = np.arange(-count, count + 1) * spacing
    return BaseGrid(axis, axis.copy())


class BaseKernel:
    """The bumps' base kernels on one grid: separable factors, so that a field is one small matrix product.

    p(x, y) = sum_j c_j Y_j(y) X_j(x) over 3 k terms per grid: the bell (c = P_i), the couple along x (M_x,i) and
    along y (M_y,i), each factor the mirrored Gaussian or its derivative along one axis (``mirrored_kernel``),
    scaled so that the bell carries 1 N and each couple has a first moment of 1 N mm on the grid.
    """

    def __init__(self, design: ArrayFingertipDesign, width: float, grid: BaseGrid):
        half_x, half_y = design.footprint
        for name, axis, half in (("x", grid.x, half_x), ("y", grid.y, half_y)):
            if not (axis[0] < -half and axis[-1] > half):
                raise ValueError(f"grid.{name} spans [{axis[0]:g}, {axis[-1]:g}] mm; it must reach past the base "
                                 f"layer's edges at +-{half:g} mm (use ReducedFingertip.base_grid)")
        centres = design.bump_centres
        self.grid = grid
        even_x, odd_x = mirrored_kernel(grid.x, centres[:, 0], width, half_x)                # (k, nx) each
        even_y, odd_y = mirrored_kernel(grid.y, centres[:, 1], width, half_y)                # (k, ny) each
        weight_x, weight_y = trapezoid_weights(grid.x), trapezoid_weights(grid.y)
        mass_x, mass_y = even_x @ weight_x, even_y @ weight_y                                # (k,)
        # a pure couple carries no force: the mirror line's grid node leaves the odd factor a net force of
        # O(h g(L)) (1 % of the bell for an edge bump at h = 1 mm); take it out with a multiple of the bell
        odd_x = odd_x - ((odd_x @ weight_x) / mass_x)[:, None] * even_x
        odd_y = odd_y - ((odd_y @ weight_y) / mass_y)[:, None] * even_y
        arm_x = (odd_x * (grid.x - centres[:, :1])) @ weight_x                                # first moments (k,)
        arm_y = (odd_y * (grid.y - centres[:, 1:])) @ weight_y
        self.along_y = np.concatenate([even_y, even_y, odd_y]).T                              # (ny, 3k)
        self.along_x = np.concatenate([even_x, odd_x, even_x])                                # (3k, nx)
        self.scale = np.concatenate([1.0 / (mass_x * mass_y), 1.0 / (arm_x * mass_y), 1.0 / (arm_y * mass_x)])

    def pressure(self, bump_force: np.ndarray, couple: np.ndarray) -> np.ndarray:
        """Pressure (ny, nx) [MPa] of bump forces (k,) [N] and couples (k, 2) [N mm] (ValueError if not finite)."""
        coefficient = np.concatenate([bump_force, couple.T.ravel()]) * self.scale               # (3k,)
        if not math.isfinite(coefficient.sum()):
            raise ValueError("base_pressure: non-finite loads (bump_force, shear_displacement or tangential_force)")
        return (self.along_y * coefficient) @ self.along_x


def mirrored_kernel(axis, centres, width, half):
    """One axis's factors of the bumps' base kernels: even (k, n) and odd (k, n), both zero beyond +-half [mm].

    even(u) = sum_s g(u - c_s), odd(u) = d even / d c = sum_s s (u - c_s) / sigma^2 g(u - c_s), with g(u) =
    exp(-u^2 / (2 sigma^2)) and the sources c_s = c, 2 L - c, -2 L - c of signs s = +1, -1, -1: the bump and its
    mirror images in the free side faces at +-L. Unnormalised (``BaseKernel`` scales them).
    """
    sources = np.stack([centres, 2.0 * half - centres, -2.0 * half - centres])              # (3, k)
    offset = axis[None, None, :] - sources[:, :, None]                                      # (3, k, n)
    bell = np.exp(-0.5 * (offset / width) ** 2)
    inside = np.abs(axis) <= half * (1.0 + 1e-12)                                           # (n,)
    sign = np.array([1.0, -1.0, -1.0])[:, None, None]
    return bell.sum(axis=0) * inside, (sign * offset * bell).sum(axis=0) * inside / width**2


def trapezoid_weights(axis) -> np.ndarray:
    """Trapezoid-rule weights (n,) [mm] of a 1D grid axis."""
    step = np.diff(axis)
    weight = np.zeros(axis.size)
    weight[:-1] += 0.5 * step
    weight[1:] += 0.5 * step
    return weight
