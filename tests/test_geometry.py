"""Gel geometries: closed-form volume and contact-side area against the tessellated surface, watertightness,
outward normals, bump positions, and one ValueError per impossible-parameter rule."""

import math

import numpy as np
import pytest

from fem.geometry import ArrayGeometry, BlockGeometry, CapGeometry, FlatCapGeometry

SEGMENTS = 64
STEP = 2.0 * math.pi / SEGMENTS     # angular step dt of the chords, around the axis and along circular profiles
# Inscribed chords, to leading order in dt: around the axis an N-gon loses dt^2/6 of the revolved volume and area;
# along a profile of curvature radius R each chord leaves a sliver of mean depth R dt^2/12, i.e. a volume of
# R dt^2/12 per unit of curved area, and shortens the profile's area by dt^2/24 + dt^2/8 (chord length, radius).
# MARGIN covers the dt^4 terms and the rounding up of chord counts on short arcs (measured <= 1.01 of the bound).
MARGIN = 1.1
EXACT = 1e-9    # flat faces only: round-off

GEOMETRIES = {
    "block": BlockGeometry(width=20.0, depth=16.0, thickness=5.0),
    "sphere_cap": CapGeometry(width=20.0, depth=20.0, base_thickness=4.0, cap_radius=6.0, sphere_radius=10.0),
    "hemisphere_cap": CapGeometry(width=20.0, depth=20.0, base_thickness=4.0, cap_radius=6.0, sphere_radius=6.0),
    "cone_cap": CapGeometry(width=20.0, depth=20.0, base_thickness=4.0, cap_radius=6.0, exponent=1.0,
                            power_law_height=2.0),
    "quartic_cap": CapGeometry(width=20.0, depth=20.0, base_thickness=4.0, cap_radius=6.0, exponent=4.0,
                               power_law_height=2.0),
    "flat_cap": FlatCapGeometry(width=20.0, depth=20.0, base_thickness=4.0, cap_radius=6.0, flat_radius=3.0,
                                edge_radius=5.0),
    "array_3x3": ArrayGeometry(rows=3, cols=3, bump_radius=3.0, pitch=8.0, base_width=30.0, base_depth=30.0,
                               base_thickness=3.0),
    "array_filleted": ArrayGeometry(rows=2, cols=3, bump_radius=3.0, pitch=9.0, base_width=30.0, base_depth=24.0,
                                    base_thickness=3.0, fillet=1.0),
}


# profile curvature radius R [mm] per case (power laws: the cap radius, a bound on their chord sag here)
CURVATURE_RADIUS = {"block": 0.0, "sphere_cap": 10.0, "hemisphere_cap": 6.0, "cone_cap": 0.0, "quartic_cap": 6.0,
                    "flat_cap": 5.0, "array_3x3": 3.0, "array_filleted": 3.0}


def _curved_part(geometry):
    """(volume, area) of the revolved parts, the only ones the tessellation approximates."""
    if isinstance(geometry, BlockGeometry):
        return 0.0, 0.0
    if isinstance(geometry, ArrayGeometry):
        return geometry.n_bumps * geometry.bump_volume, geometry.n_bumps * geometry.bump_area
    return geometry.cap_volume, geometry.cap_lateral_area


def _top_area(geometry, surface):
    """Area of the faces neither on the base plane nor on the four side walls."""
    width = getattr(geometry, "width", None) or geometry.base_width
    depth = getattr(geometry, "depth", None) or geometry.base_depth
    corners, normals = surface.vertices[surface.faces], surface.face_normals
    bottom = normals[:, 2] < -1.0 + 1e-9
    side = np.zeros(len(normals), dtype=bool)
    for axis, half in ((0, width / 2), (1, depth / 2)):
        side |= (np.abs(normals[:, axis]) > 1.0 - 1e-9) & np.all(np.abs(np.abs(corners[:, :, axis]) - half) < 1e-9, 1)
    return surface.area_faces[~bottom & ~side].sum()


@pytest.fixture(scope="module", params=sorted(GEOMETRIES))
def shape(request):
    geometry = GEOMETRIES[request.param]
    return geometry, geometry.surface(SEGMENTS), CURVATURE_RADIUS[request.param]


def test_surface_is_closed_with_outward_normals(shape):
    geometry, surface, _ = shape
    assert surface.is_watertight and surface.is_winding_consistent
    assert surface.volume > 0.0                            # outward: a positive enclosed volume
    assert surface.bounds[1, 2] == pytest.approx(0.0, abs=EXACT)
    assert surface.bounds[0, 2] == pytest.approx(-geometry.height, abs=EXACT)


def test_volume_matches_closed_form(shape):
    geometry, surface, radius = shape
    curved_volume, curved_area = _curved_part(geometry)
    tolerance = MARGIN * (STEP**2 / 6.0 * curved_volume + radius * STEP**2 / 12.0 * curved_area) + EXACT
    assert surface.volume == pytest.approx(geometry.volume, abs=tolerance)
    assert surface.volume <= geometry.volume + EXACT       # inscribed chords only cut material away


def test_top_area_matches_closed_form(shape):
    geometry, surface, _ = shape
    _, curved_area = _curved_part(geometry)
    tolerance = MARGIN * (STEP**2 / 6.0 + STEP**2 / 24.0 + STEP**2 / 8.0) * curved_area + EXACT
    assert _top_area(geometry, surface) == pytest.approx(geometry.top_area, abs=tolerance)


def test_tessellation_error_falls_as_second_order():
    geometry = GEOMETRIES["array_filleted"]
    errors = [abs(geometry.surface(n).volume - geometry.volume) for n in (32, 64)]
    assert errors[0] / errors[1] == pytest.approx(4.0, rel=0.25)   # dt^2: halving the step quarters the error


def test_closed_forms_reduce_to_known_shapes():
    sphere = CapGeometry(cap_radius=6.0, sphere_radius=6.0)
    assert sphere.cap_volume == pytest.approx(2.0 / 3.0 * math.pi * 6.0**3)
    assert FlatCapGeometry(cap_radius=6.0, flat_radius=0.0, edge_radius=6.0).cap_volume == pytest.approx(
        sphere.cap_volume)
    paraboloid = CapGeometry(cap_radius=6.0, exponent=2.0, power_law_height=2.0)   # pi a^2 h / 2
    assert paraboloid.cap_volume == pytest.approx(math.pi * 36.0 * 2.0 / 2.0)
    c = paraboloid.profile_coefficient                                            # 2 pi int r sqrt(1 + 4 c^2 r^2)
    assert paraboloid.cap_lateral_area == pytest.approx(math.pi / (6 * c**2) * ((1 + 4 * c**2 * 36) ** 1.5 - 1))
    bare = ArrayGeometry(1, 1, bump_radius=3.0, base_width=10.0, base_depth=10.0)
    assert bare.bump_area == pytest.approx(2.0 * math.pi * 9.0)
    assert ArrayGeometry(1, 1, bump_radius=3.0, base_width=10.0, base_depth=10.0, fillet=1e-9).bump_volume == (
        pytest.approx(bare.bump_volume, rel=1e-6))


@pytest.mark.parametrize("size", [1, 2, 3, 4, 5])
def test_bump_count_and_positions(size):
    pitch = 7.0
    geometry = ArrayGeometry(rows=size, cols=size, bump_radius=3.0, pitch=pitch, base_width=40.0, base_depth=40.0)
    centers = geometry.bump_centers
    assert centers.shape == (size * size, 2)
    np.testing.assert_allclose(centers.mean(axis=0), 0.0, atol=EXACT)
    expected = (np.arange(size) - (size - 1) / 2) * pitch
    np.testing.assert_allclose(np.unique(centers[:, 0]), expected)
    np.testing.assert_allclose(np.unique(centers[:, 1]), expected)
    np.testing.assert_array_equal(geometry.contact_centers(), centers)
    np.testing.assert_allclose(geometry.top_surface_height(centers), 0.0, atol=EXACT)   # every top touches first
    surface = geometry.surface(16)
    tops = surface.vertices[np.abs(surface.vertices[:, 2]) < EXACT]
    assert len(tops) == size * size
    assert surface.body_count == 1


def test_rectangular_array_rows_along_y():
    centers = ArrayGeometry(rows=2, cols=3, bump_radius=2.0, pitch=5.0, base_width=20.0, base_depth=20.0).bump_centers
    assert np.unique(centers[:, 0]).size == 3 and np.unique(centers[:, 1]).size == 2


def test_cap_contact_center_is_apex():
    for geometry in (GEOMETRIES["sphere_cap"], GEOMETRIES["flat_cap"], GEOMETRIES["block"]):
        np.testing.assert_array_equal(geometry.contact_centers(), [[0.0, 0.0]])
        assert geometry.top_surface_height(np.zeros((1, 2)))[0] == 0.0


BAD_PARAMETERS = [
    (BlockGeometry, dict(thickness=0.0), "thickness=0.0"),
    (BlockGeometry, dict(width=-1.0), "width=-1.0"),
    (BlockGeometry, dict(depth=math.nan), "depth=nan"),
    (CapGeometry, dict(base_thickness=0.0), "base_thickness=0.0"),
    (CapGeometry, dict(cap_radius=25.0, sphere_radius=30.0), "cap_radius=25.0.*fit inside the base"),
    (CapGeometry, dict(cap_radius=10.0, sphere_radius=8.0), "cap_radius=10.0.*hemisphere"),
    (CapGeometry, dict(exponent=0.5, power_law_height=1.0), "exponent=0.5"),
    (CapGeometry, dict(exponent=2.0), "power_law_height=None"),
    (CapGeometry, dict(exponent=2.0, power_law_height=-1.0), "power_law_height=-1.0"),
    (CapGeometry, dict(power_law_height=1.0), "power_law_height=1.0 needs an exponent"),
    (FlatCapGeometry, dict(flat_radius=10.0), "flat_radius=10.0"),
    (FlatCapGeometry, dict(flat_radius=2.0, edge_radius=5.0), "cap_radius=10.0.*flat_radius \\+ edge_radius"),
    (FlatCapGeometry, dict(edge_radius=0.0), "edge_radius=0.0"),
    (FlatCapGeometry, dict(cap_radius=21.0, flat_radius=15.0), "cap_radius=21.0.*fit inside the base"),
    (ArrayGeometry, dict(pitch=9.0), "pitch=9.0.*overlap"),
    (ArrayGeometry, dict(pitch=10.0), "pitch=10.0.*overlap"),                 # touching bumps: not a manifold
    (ArrayGeometry, dict(pitch=10.9, fillet=0.5), "pitch=10.9.*overlap"),     # the fillet widens the footprint
    (ArrayGeometry, dict(base_width=30.0), "base_width=30.0.*overhang"),
    (ArrayGeometry, dict(base_depth=34.0), "base_depth=34.0.*overhang"),
    (ArrayGeometry, dict(base_thickness=0.0), "base_thickness=0.0"),
    (ArrayGeometry, dict(bump_radius=-2.0), "bump_radius=-2.0"),
    (ArrayGeometry, dict(fillet=-0.1), "fillet=-0.1"),
    (ArrayGeometry, dict(rows=0), "rows=0"),
    (ArrayGeometry, dict(cols=2.5), "cols=2.5"),
    (ArrayGeometry, dict(rows=13), "rows=13"),
]


@pytest.mark.parametrize("cls, changes, message", BAD_PARAMETERS,
                         ids=[f"{cls.__name__}-{'-'.join(changes)}-{i}" for i, (cls, changes, _) in
                              enumerate(BAD_PARAMETERS)])
def test_impossible_parameters_raise_naming_them(cls, changes, message):
    with pytest.raises(ValueError, match=message):
        cls(**changes)


def test_geometries_are_frozen():
    with pytest.raises(AttributeError):
        GEOMETRIES["block"].width = 1.0
