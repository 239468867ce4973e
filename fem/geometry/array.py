"""The paper's fingertip (Fig. 5): rows x cols elastic hemispheres on a base layer bonded to the sensor, in mm."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fem.geometry._surface import arc_points, box_solid, revolved_solid, union_surface
from fem.validation import check_all, check_integer, check_positive, check_range

__all__ = ["ArrayGeometry"]

MAX_BUMPS_PER_SIDE = 12


@dataclass(frozen=True)
class ArrayGeometry:
    """rows x cols hemispheres of radius ``bump_radius`` at ``pitch`` on a base layer, centred on the z axis.

    The bump tops are at z = 0, the base top at z = -bump_radius, the sensor plane at z = -height. Bump (i, j),
    row i along y and column j along x, is centred at x = (j - (cols - 1)/2) pitch, y = (i - (rows - 1)/2) pitch.

    Parameters
    ----------
    rows, cols : int
        Number of bumps along y and x, 1 to 12.
    bump_radius : float
        Hemisphere radius r [mm].
    pitch : float
        Centre distance between neighbouring bumps [mm]; more than the footprint diameter (no overlap).
    base_width, base_depth, base_thickness : float
        Base layer [mm]; the bump footprints lie strictly inside it (no overhang).
    fillet : float
        Radius f [mm] of the concave torus fillet where a bump meets the base (0: a sharp edge). It widens the
        footprint to sqrt(r^2 + 2 r f).
    """

    rows: int = 3
    cols: int = 3
    bump_radius: float = 5.0
    pitch: float = 12.0
    base_width: float = 40.0
    base_depth: float = 40.0
    base_thickness: float = 5.0
    fillet: float = 0.0

    def __post_init__(self):
        check_all(lambda: check_integer("rows", self.rows, 1, MAX_BUMPS_PER_SIDE),
                  lambda: check_integer("cols", self.cols, 1, MAX_BUMPS_PER_SIDE),
                  *[lambda name=name: check_positive(name, getattr(self, name), "mm")
                    for name in ("bump_radius", "pitch", "base_width", "base_depth", "base_thickness")],
                  lambda: check_range("fillet", self.fillet, 0.0, math.inf, "mm", high_open=True))
        footprint = self.footprint_radius
        if max(self.rows, self.cols) > 1:
            check_range("pitch", self.pitch, 2.0 * footprint, math.inf,
                        f"mm (bumps overlap: pitch must exceed the footprint diameter 2 sqrt(r^2 + 2 r f) = "
                        f"{2.0 * footprint:g} mm)", low_open=True, high_open=True)
        for side, count in (("base_width", self.cols), ("base_depth", self.rows)):
            span = (count - 1) * self.pitch + 2.0 * footprint
            check_range(side, getattr(self, side), span, math.inf,
                        f"mm (bumps overhang the base: it must exceed (n - 1) pitch + footprint diameter = "
                        f"{span:g} mm)", low_open=True, high_open=True)

    @property
    def footprint_radius(self) -> float:
        """Radius [mm] where a bump (with its fillet) meets the base top: sqrt(r^2 + 2 r f)."""
        return math.sqrt(self.bump_radius**2 + 2.0 * self.bump_radius * self.fillet)

    @property
    def _fillet_top(self) -> float:
        """Height [mm] above the base top where the fillet meets the sphere: f r / (r + f)."""
        return self.fillet * self.bump_radius / (self.bump_radius + self.fillet)

    @property
    def n_bumps(self) -> int:
        return self.rows * self.cols

    @property
    def height(self) -> float:
        """Total height [mm] = base_thickness + bump_radius: the base is at z = -height."""
        return self.base_thickness + self.bump_radius

    @property
    def bump_centers(self) -> np.ndarray:
        """xy [mm] (rows * cols, 2) of the bump axes, row by row (y outer, x inner)."""
        x = (np.arange(self.cols) - 0.5 * (self.cols - 1)) * self.pitch
        y = (np.arange(self.rows) - 0.5 * (self.rows - 1)) * self.pitch
        grid_x, grid_y = np.meshgrid(x, y)
        return np.column_stack([grid_x.ravel(), grid_y.ravel()])

    def contact_centers(self) -> np.ndarray:
        """xy [mm] (k, 2) of the points touching first: the bump tops (all at z = 0)."""
        return self.bump_centers

    @property
    def bump_volume(self) -> float:
        """Volume of one bump above the base top [mm^3], closed form.

        Sphere cap above the fillet line, pi h_c^2 (3 r - h_c) / 3 with h_c = r - z_t, plus the solid of
        revolution under the fillet, pi int_0^z_t rho(z)^2 dz with rho(z) = rho_c - sqrt(f^2 - (f - z)^2).
        Without a fillet: 2 pi r^3 / 3.
        """
        r, f, z_top, rho_c = self.bump_radius, self.fillet, self._fillet_top, self.footprint_radius
        cap = r - z_top
        volume = math.pi * cap**2 * (3.0 * r - cap) / 3.0
        if f > 0.0:
            def primitive(u):   # int sqrt(f^2 - u^2) du
                return 0.5 * (u * math.sqrt(max(f**2 - u**2, 0.0)) + f**2 * math.asin(u / f))
            segment = primitive(f) - primitive(f - z_top)             # int_0^z_t sqrt(f^2 - (f - z)^2) dz
            square = f**2 * z_top - (f**3 - (f - z_top) ** 3) / 3.0   # int_0^z_t f^2 - (f - z)^2 dz
            volume += math.pi * (rho_c**2 * z_top - 2.0 * rho_c * segment + square)
        return volume

    @property
    def bump_area(self) -> float:
        """Curved area of one bump [mm^2]: 2 pi r (r - z_t) on the sphere plus 2 pi f (rho_c phi - f (1 - cos phi))
        on the fillet, cos phi = f / (r + f) (Pappus). Without a fillet: 2 pi r^2."""
        r, f, rho_c = self.bump_radius, self.fillet, self.footprint_radius
        sphere = 2.0 * math.pi * r * (r - self._fillet_top)
        phi = math.acos(f / (r + f))
        return sphere + 2.0 * math.pi * f * (rho_c * phi - f * (1.0 - math.cos(phi)))

    @property
    def volume(self) -> float:
        """Volume [mm^3] of base plus bumps."""
        return self.base_width * self.base_depth * self.base_thickness + self.n_bumps * self.bump_volume

    @property
    def top_area(self) -> float:
        """Area of the contact side [mm^2]: bump surfaces plus the base top between them."""
        flat = self.base_width * self.base_depth - self.n_bumps * math.pi * self.footprint_radius**2
        return flat + self.n_bumps * self.bump_area

    def profile(self, rho: np.ndarray) -> np.ndarray:
        """Bump surface height z [mm] at distance rho [mm] from its axis (0 <= rho <= footprint_radius)."""
        r, f, rho_c = self.bump_radius, self.fillet, self.footprint_radius
        rho = np.asarray(rho, dtype=float)
        sphere = np.sqrt(np.maximum(r**2 - rho**2, 0.0)) - r
        if f == 0.0:
            return sphere
        on_fillet = rho > rho_c * r / (r + f)
        fillet = -r + f - np.sqrt(np.maximum(f**2 - (rho_c - rho) ** 2, 0.0))
        return np.where(on_fillet, fillet, sphere)

    def top_surface_height(self, xy: np.ndarray) -> np.ndarray:
        """Height z [mm] (n,) of the contact side above points xy (n, 2): the highest bump, else the base top."""
        offsets = xy[:, None, :] - self.bump_centers[None, :, :]                    # (n, k, 2)
        rho = np.sqrt((offsets**2).sum(axis=2))                                     # (n, k)
        inside = rho < self.footprint_radius
        heights = np.where(inside, self.profile(np.minimum(rho, self.footprint_radius)), -self.bump_radius)
        return heights.max(axis=1)

    def _profile_points(self, segments: int) -> np.ndarray:
        r, f = self.bump_radius, self.fillet
        if f == 0.0:
            return arc_points(0.0, -r, r, math.pi / 2, 0.0, segments)
        contact_angle = math.atan2(f, self.footprint_radius)       # direction of the fillet centre from the sphere's
        sphere = arc_points(0.0, -r, r, math.pi / 2, contact_angle, segments)
        fillet = arc_points(self.footprint_radius, -r + f, f, math.pi + contact_angle, 1.5 * math.pi, segments)
        return np.vstack([sphere, fillet[1:]])

    def surface(self, segments: int = 96):
        """Closed triangle surface (trimesh.Trimesh): manifold union of the base block and the revolved bumps,
        watertight with outward normals, checked. ``segments`` chords per full turn (and along the profile)."""
        base_top = -self.bump_radius
        solids = [box_solid(self.base_width, self.base_depth, -self.height, base_top)]
        profile = self._profile_points(segments)
        floor = base_top - 0.5 * self.base_thickness
        solids += [revolved_solid(profile, floor, center, segments) for center in self.bump_centers]
        return union_surface(solids)
