"""Single-contact gels: a flat pad, an axisymmetric (spherical or power-law) cap and a rounded flat punch, in mm.

Frame (docs/design.md, sec. 4): the highest point of the gel is at z = 0, where the rigid body first touches; the base
(sensor plane, bonded) is at z = -height; x, y tangential, the gel centred on the z axis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import quad

from fem.geometry._surface import arc_points, box_solid, revolved_solid, union_surface
from fem.validation import check_all, check_positive, check_range

__all__ = ["BlockGeometry", "CapGeometry", "FlatCapGeometry"]

_CENTER = np.zeros((1, 2))


@dataclass(frozen=True)
class BlockGeometry:
    """Flat pad x in [-width/2, width/2], y in [-depth/2, depth/2], z in [-thickness, 0] [mm]."""

    width: float = 40.0
    depth: float = 40.0
    thickness: float = 10.0

    def __post_init__(self):
        check_all(*[lambda name=name: check_positive(name, getattr(self, name), "mm")
                    for name in ("width", "depth", "thickness")])

    @property
    def height(self) -> float:
        """Total height [mm]: the base is at z = -height."""
        return self.thickness

    @property
    def volume(self) -> float:
        """Volume [mm^3]."""
        return self.width * self.depth * self.thickness

    @property
    def top_area(self) -> float:
        """Area of the contact side [mm^2] (the whole surface less the base and the four side walls)."""
        return self.width * self.depth

    def contact_centers(self) -> np.ndarray:
        """xy [mm] (1, 2) of the first contact: the pad touches everywhere at once; its centre is returned."""
        return _CENTER.copy()

    def top_surface_height(self, xy: np.ndarray) -> np.ndarray:
        """Height z [mm] (n,) of the contact side above points xy (n, 2)."""
        return np.zeros(len(xy))

    def surface(self, segments: int = 128):
        """Closed triangle surface (trimesh.Trimesh), watertight with outward normals; ``segments`` is unused."""
        return union_surface([box_solid(self.width, self.depth, -self.height, 0.0)])


class _CapOnBase:
    """An axisymmetric cap of footprint radius ``cap_radius`` on a block base of thickness ``base_thickness``.

    Subclasses give ``cap_height``, ``cap_volume`` and ``cap_lateral_area`` (closed forms), ``profile(rho)`` (z of
    the cap surface, 0 at the axis, -cap_height at the rim) and ``_profile_points(segments)`` (the tessellated
    profile from the axis to the rim).
    """

    def _check_base(self):
        check_all(*[lambda name=name: check_positive(name, getattr(self, name), "mm")
                    for name in ("width", "depth", "base_thickness", "cap_radius")])
        narrowest = min(self.width, self.depth)
        check_range("cap_radius", self.cap_radius, 0.0, narrowest / 2, "mm (the cap must fit inside the base)",
                    low_open=True, high_open=True)

    @property
    def height(self) -> float:
        """Total height [mm] = base_thickness + cap_height: the base is at z = -height."""
        return self.base_thickness + self.cap_height

    @property
    def volume(self) -> float:
        """Volume [mm^3] of base plus cap."""
        return self.width * self.depth * self.base_thickness + self.cap_volume

    @property
    def top_area(self) -> float:
        """Area of the contact side [mm^2]: the cap surface plus the base top outside the footprint."""
        return self.width * self.depth - math.pi * self.cap_radius**2 + self.cap_lateral_area

    def contact_centers(self) -> np.ndarray:
        """xy [mm] (1, 2) of the point that touches first: the apex (0, 0)."""
        return _CENTER.copy()

    def top_surface_height(self, xy: np.ndarray) -> np.ndarray:
        """Height z [mm] (n,) of the contact side above points xy (n, 2)."""
        rho = np.hypot(xy[:, 0], xy[:, 1])
        return np.where(rho < self.cap_radius, self.profile(np.minimum(rho, self.cap_radius)), -self.cap_height)

    def surface(self, segments: int = 128):
        """Closed triangle surface (trimesh.Trimesh), watertight with outward normals, checked.

        ``segments`` chords per full turn of the revolution, and the same angular step along curved profiles.
        """
        base_top = -self.cap_height
        base = box_solid(self.width, self.depth, -self.height, base_top)
        cap = revolved_solid(self._profile_points(segments), base_top - 0.5 * self.base_thickness, (0.0, 0.0),
                             segments)
        return union_surface([base, cap])


@dataclass(frozen=True)
class CapGeometry(_CapOnBase):
    """Axisymmetric cap on a base layer: spherical (radius ``sphere_radius``) or power law z = -C rho^n.

    Parameters
    ----------
    width, depth : float
        Base footprint [mm].
    base_thickness : float
        Thickness of the base layer under the cap [mm].
    cap_radius : float
        Footprint radius of the cap [mm]; less than half the base width and depth.
    sphere_radius : float
        Sphere radius R [mm] of the spherical profile (used when ``exponent`` is None); cap_radius <= R.
    exponent : float or None
        n of the power-law profile z = -C rho^n (docs/theory.md, sec. 3.2), 1 (cone) <= n <= 64; None for a sphere.
    power_law_height : float or None
        Cap height [mm] of the power-law profile, which sets C = power_law_height / cap_radius^n. Required with
        ``exponent`` and only then.
    """

    width: float = 40.0
    depth: float = 40.0
    base_thickness: float = 10.0
    cap_radius: float = 10.0
    sphere_radius: float = 20.0
    exponent: float | None = None
    power_law_height: float | None = None

    def __post_init__(self):
        check_all(self._check_base, self._check_profile)
        if self.exponent is None:
            check_range("cap_radius", self.cap_radius, 0.0, self.sphere_radius,
                        "mm (a spherical cap is at most a hemisphere: cap_radius <= sphere_radius)", low_open=True)

    def _check_profile(self):
        if self.exponent is None:
            if self.power_law_height is not None:
                raise ValueError(f"power_law_height={self.power_law_height!r} needs an exponent; a spherical cap "
                                 "takes its height from sphere_radius")
            check_positive("sphere_radius", self.sphere_radius, "mm")
        else:
            check_range("exponent", self.exponent, 1.0, 64.0)
            if self.power_law_height is None:
                raise ValueError("power_law_height=None: a power-law cap (exponent given) needs its height [mm]")
            check_positive("power_law_height", self.power_law_height, "mm")

    @property
    def is_spherical(self) -> bool:
        return self.exponent is None

    @property
    def profile_coefficient(self) -> float:
        """C [mm^(1-n)] of z = -C rho^n; for a sphere the paraboloid 1 / (2 R) that Hertz theory uses."""
        if self.is_spherical:
            return 1.0 / (2.0 * self.sphere_radius)
        return self.power_law_height / self.cap_radius**self.exponent

    @property
    def cap_height(self) -> float:
        """Height of the cap above the base layer [mm]."""
        if self.is_spherical:
            return self.sphere_radius - math.sqrt(self.sphere_radius**2 - self.cap_radius**2)
        return self.power_law_height

    @property
    def cap_volume(self) -> float:
        """Cap volume [mm^3]: pi h^2 (3 R - h) / 3 (sphere), pi a^2 h n / (n + 2) (power law)."""
        h = self.cap_height
        if self.is_spherical:
            return math.pi * h**2 * (3.0 * self.sphere_radius - h) / 3.0
        return math.pi * self.cap_radius**2 * h * self.exponent / (self.exponent + 2.0)

    @property
    def cap_lateral_area(self) -> float:
        """Curved cap area [mm^2]: 2 pi R h (sphere); 2 pi int_0^a rho sqrt(1 + z'^2) drho by quadrature (power law)."""
        if self.is_spherical:
            return 2.0 * math.pi * self.sphere_radius * self.cap_height
        n, c = self.exponent, self.profile_coefficient
        integrand = lambda rho: rho * math.sqrt(1.0 + (n * c * rho ** (n - 1.0)) ** 2)   # noqa: E731
        return 2.0 * math.pi * quad(integrand, 0.0, self.cap_radius, epsabs=0.0, epsrel=1e-12, limit=200)[0]

    def profile(self, rho: np.ndarray) -> np.ndarray:
        """Cap surface height z [mm] at radius rho [mm] (0 <= rho <= cap_radius)."""
        rho = np.asarray(rho, dtype=float)
        if self.is_spherical:
            return np.sqrt(self.sphere_radius**2 - rho**2) - self.sphere_radius
        return -self.profile_coefficient * rho**self.exponent

    def _profile_points(self, segments: int) -> np.ndarray:
        if self.is_spherical:
            rim_angle = math.asin(self.cap_radius / self.sphere_radius)
            return arc_points(0.0, -self.sphere_radius, self.sphere_radius, math.pi / 2, math.pi / 2 - rim_angle,
                              segments)
        # equal arc-length steps on the power-law curve, about as many as a quarter turn of the revolution
        dense = np.linspace(0.0, self.cap_radius, 20 * segments + 1)
        z = self.profile(dense)
        arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(dense), np.diff(z)))])
        rho = np.interp(np.linspace(0.0, arc[-1], max(8, segments // 2) + 1), arc, dense)
        return np.column_stack([rho, self.profile(rho)])


@dataclass(frozen=True)
class FlatCapGeometry(_CapOnBase):
    """Rounded flat punch on a base layer (paper Fig. 3, docs/theory.md, sec. 5.2): a flat top of radius b at z = 0
    blending tangentially into a circular arc of radius ``edge_radius`` down to the footprint radius ``cap_radius``.

    Parameters
    ----------
    width, depth, base_thickness : float
        Base layer [mm].
    cap_radius : float
        Footprint radius [mm]; flat_radius < cap_radius <= flat_radius + edge_radius.
    flat_radius : float
        b [mm], radius of the flat face (0 gives a spherical cap).
    edge_radius : float
        Radius [mm] of the edge arc, tangent to the flat face at rho = b.
    """

    width: float = 40.0
    depth: float = 40.0
    base_thickness: float = 10.0
    cap_radius: float = 10.0
    flat_radius: float = 5.0
    edge_radius: float = 10.0

    def __post_init__(self):
        check_all(self._check_base, lambda: check_positive("edge_radius", self.edge_radius, "mm"),
                  lambda: check_range("flat_radius", self.flat_radius, 0.0, math.inf, "mm", high_open=True))
        check_range("flat_radius", self.flat_radius, 0.0, self.cap_radius, "mm (below cap_radius)",
                    high_open=True)
        check_range("cap_radius", self.cap_radius, self.flat_radius, self.flat_radius + self.edge_radius,
                    "mm (the edge arc ends at most a quarter turn from the flat: <= flat_radius + edge_radius)",
                    low_open=True)

    @property
    def _arc_angle(self) -> float:
        return math.asin((self.cap_radius - self.flat_radius) / self.edge_radius)

    @property
    def cap_height(self) -> float:
        """Height of the cap above the base layer [mm]: R_e (1 - cos theta), sin theta = (a - b) / R_e."""
        return self.edge_radius * (1.0 - math.cos(self._arc_angle))

    @property
    def cap_volume(self) -> float:
        """Cap volume [mm^3], closed form: 2 pi int_0^a rho (z(rho) + h) drho with s = rho - b on the arc."""
        b, radius, h = self.flat_radius, self.edge_radius, self.cap_height
        w = self.cap_radius - b
        root = math.sqrt(radius**2 - w**2)
        s_root = (radius**3 - root**3) / 3.0                                # int_0^w s sqrt(R^2 - s^2) ds
        root_int = 0.5 * (w * root + radius**2 * math.asin(w / radius))     # int_0^w sqrt(R^2 - s^2) ds
        arc_part = (h - radius) * (0.5 * w**2 + b * w) + s_root + b * root_int
        return math.pi * b**2 * h + 2.0 * math.pi * arc_part

    @property
    def cap_lateral_area(self) -> float:
        """Cap area [mm^2]: pi b^2 + 2 pi R_e (b theta + R_e (1 - cos theta)) (Pappus on the arc)."""
        b, radius, theta = self.flat_radius, self.edge_radius, self._arc_angle
        return math.pi * b**2 + 2.0 * math.pi * radius * (b * theta + radius * (1.0 - math.cos(theta)))

    def profile(self, rho: np.ndarray) -> np.ndarray:
        """Cap surface height z [mm] at radius rho [mm] (0 <= rho <= cap_radius)."""
        s = np.maximum(np.asarray(rho, dtype=float) - self.flat_radius, 0.0)
        return np.sqrt(np.maximum(self.edge_radius**2 - s**2, 0.0)) - self.edge_radius

    def _profile_points(self, segments: int) -> np.ndarray:
        arc = arc_points(self.flat_radius, -self.edge_radius, self.edge_radius, math.pi / 2,
                         math.pi / 2 - self._arc_angle, segments)
        if self.flat_radius == 0.0:
            return arc
        return np.vstack([[[0.0, 0.0]], arc])
