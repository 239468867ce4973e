"""Per-bump results: sums equal the totals, the margin to gross slip, and their place in every output; the compliance
column cache on disk."""

import csv
import json

import numpy as np
import pytest

from contact.bumps import assign_bumps, bump_results
from contact.scene import BodySpec, ContactSpec, Load, LoadKind, Material, MeshSettings, Scene
from contact.solver import OPEN, SLIP, STICK, solve_scene

# sums of the same point forces grouped differently: equal to round-off of ~100 terms of ~1e-2 N
SUM_TOLERANCE = 1e-12


def test_bump_sums_of_synthetic_points():
    centers = np.array([[-5.0, 0.0], [5.0, 0.0]])
    positions = np.array([[-5.0, 0.0, 0.0], [-4.0, 0.0, 0.0], [5.0, 1.0, 0.0], [6.0, 0.0, 0.0], [9.0, 9.0, 0.0]])
    bump = assign_bumps(positions, centers)
    assert bump.tolist() == [0, 0, 1, 1, 1]
    status = np.array([STICK, SLIP, STICK, SLIP, OPEN])
    normal = np.array([0.4, 0.2, 0.3, 0.1, 0.0])
    tangential = np.array([[0.05, 0.0], [0.1, 0.0], [0.0, 0.1], [0.0, -0.05], [0.0, 0.0]])
    areas = np.array([1.0, 1.0, 2.0, 2.0, 3.0])
    lever = np.column_stack([-positions[:, 1], positions[:, 0]])            # twist about the origin
    mu = 0.5
    bumps = bump_results(bump, centers, status, normal, tangential, areas, positions, lever, mu)
    assert bumps.normal_force.tolist() == pytest.approx([0.6, 0.4])
    assert bumps.tangential_force.ravel().tolist() == pytest.approx([0.15, 0.0, 0.0, 0.05])
    assert bumps.torque.sum() == pytest.approx((lever * tangential).sum())
    # bump 1: forces (0, 0.1) at arm (0, 1) and (0, -0.05) at arm (1, 0) about its centre (5, 0)
    assert bumps.spin_torque[1] == pytest.approx(0.0 * 0.1 - 1.0 * 0.0 + 1.0 * -0.05)
    assert bumps.contact_area.tolist() == [2.0, 4.0] and bumps.stick_ratio.tolist() == pytest.approx([0.5**0.5] * 2)
    # margin: 1 - (0.05 + 0.1) / (0.5 * 0.6) = 0.5 and 1 - (0.1 + 0.05) / (0.5 * 0.4) = 0.25
    assert bumps.gross_slip_margin.tolist() == pytest.approx([0.5, 0.25])
    assert (bumps.open_points.tolist(), bumps.stick_points.tolist(), bumps.slip_points.tolist()) == \
        ([0, 1], [1, 1], [1, 1])
    flat = bumps.flat()
    assert flat["bump1_tangential_force_y"] == pytest.approx(0.05) and flat["bump0_slip_points"] == 1


def test_half_model_bumps_equal_the_whole_model_of_a_symmetric_load():
    # a 3 x 3 array under a load symmetric about y = 0 (shear along x, pressure bell per bump): summing the computed
    # half (y > 0 points, and points on the plane with half their force and area, as a half mesh carries them) with
    # multiplicity 2 must give every bump the whole model's values, the images of the computed bumps included
    pitch = 4.0
    centers = np.array([[x, y] for y in (-pitch, 0.0, pitch) for x in (-pitch, 0.0, pitch)])
    grid = np.arange(-1.5, 1.51, 0.5)
    offsets = np.array([[dx, dy] for dx in grid for dy in grid])
    positions = np.vstack([center + offsets for center in centers])
    positions = np.column_stack([positions, np.zeros(len(positions))])
    bump = assign_bumps(positions, centers)
    local = positions[:, :2] - centers[bump]
    normal = np.exp(-(local**2).sum(axis=1)) * (1.0 + 0.05 * centers[bump, 0])
    tangential = np.column_stack([0.3 * normal, 0.1 * normal * positions[:, 1]])          # y part odd in y
    status = np.where((local**2).sum(axis=1) < 1.0, STICK, np.where(normal > 0.05, SLIP, OPEN))
    areas = np.full(len(positions), 0.25)
    lever = np.column_stack([-positions[:, 1], positions[:, 0]])
    whole = bump_results(bump, centers, status, normal, tangential, areas, positions, lever, 0.5)
    keep = positions[:, 1] >= 0.0
    half = np.where(positions[keep, 1] == 0.0, 0.5, 1.0)
    halved = bump_results(bump[keep], centers, status[keep], half * normal[keep], half[:, None] * tangential[keep],
                          half * areas[keep], positions[keep], lever[keep], 0.5, multiplicity=2.0)
    for name in ("normal_force", "tangential_force", "torque", "spin_torque", "contact_area", "stick_ratio",
                 "gross_slip_margin"):
        assert getattr(halved, name) == pytest.approx(getattr(whole, name), abs=SUM_TOLERANCE), name
    off_plane = centers[:, 1] != 0.0
    assert np.array_equal(halved.stick_points[off_plane], whole.stick_points[off_plane])


def test_a_bump_at_gross_slip_has_no_margin_and_an_unloaded_one_all_of_it():
    centers = np.array([[0.0, 0.0], [10.0, 0.0]])
    positions = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [10.0, 0.0, 0.0]])
    status = np.array([SLIP, SLIP, OPEN])
    normal = np.array([0.2, 0.1, 0.0])
    tangential = np.array([[0.1, 0.0], [0.0, 0.05], [0.0, 0.0]])           # |t| = mu lambda at both points
    bumps = bump_results(np.array([0, 0, 1]), centers, status, normal, tangential, np.ones(3), positions,
                         np.zeros((3, 2)), 0.5)
    assert bumps.gross_slip_margin.tolist() == [0.0, 1.0]
    assert bumps.stick_ratio.tolist() == [0.0, 0.0] and bumps.contact_radius[1] == 0.0


def array_scene():
    """The 3x3 fingertip of the quick Fig. 6 / 9 bench (h = 0.7 mm, its mesh cached) under press, shear and twist."""
    from controller.estimation.bench import fingertip_gel

    return Scene(name="array", gel=fingertip_gel(3), material=Material(0.3, 0.45), body=BodySpec("plane"),
                 contact=ContactSpec(friction_coefficient=1.0),
                 mesh=MeshSettings(size_contact=0.7, size_far=3.0, size_base=1.5),
                 loads=(Load(LoadKind.PRESS, "force", (2.0,)), Load(LoadKind.SHEAR, "force", (0.6,)),
                        Load(LoadKind.TWIST, "force", (8.0,))))


@pytest.fixture(scope="module")
def array_result():
    return solve_scene(array_scene())


def test_per_bump_forces_sum_to_the_totals(array_result):
    assert len(array_result.bump_centers) == 9
    for increment in array_result.increments:
        bumps = increment.bumps
        scale = increment.normal_force
        assert bumps.normal_force.sum() == pytest.approx(increment.normal_force, abs=SUM_TOLERANCE * scale)
        assert bumps.tangential_force.sum(axis=0) == pytest.approx(increment.tangential_force,
                                                                   abs=SUM_TOLERANCE * scale)
        assert bumps.torque.sum() == pytest.approx(increment.torque, abs=SUM_TOLERANCE * scale * 20.0)
        assert bumps.contact_area.sum() == pytest.approx(increment.contact_area, rel=SUM_TOLERANCE)
        assert np.all((bumps.gross_slip_margin >= 0.0) & (bumps.gross_slip_margin <= 1.0))
        # every candidate point is counted once
        counts = bumps.open_points + bumps.stick_points + bumps.slip_points
        assert counts.sum() == array_result.candidates.size


def test_twist_with_shear_loads_the_corners_where_both_add(array_result):
    twisted = array_result.increments[-1].bumps
    x, y = twisted.centers.T
    # a positive twist moves a point at (x, y) along (-y, x): at y < 0 with the +x shear, at y > 0 against it. The
    # two corners at y < 0 are farthest from the centre and get both: they have the least margin to gross slip
    least = set(np.argsort(twisted.gross_slip_margin)[:2].tolist())
    assert least == set(np.flatnonzero((y < -1.0) & (np.abs(x) > 1.0)).tolist())
    for column in np.unique(np.round(x, 6)):
        row_pair = (np.round(x, 6) == column)
        low, high = np.argmin(np.where(row_pair, y, np.inf)), np.argmax(np.where(row_pair, y, -np.inf))
        assert twisted.gross_slip_margin[low] < twisted.gross_slip_margin[high]


def test_run_writes_per_bump_columns_and_fields(tmp_path, array_result):
    import meshio

    from studies.run import write_outputs

    write_outputs(array_result, tmp_path, vtu=True)
    document = json.loads((tmp_path / "result.json").read_text())
    bumps = document["increments"][1]["bumps"]
    assert len(bumps) == 9 and {"normal_force", "stick_ratio", "gross_slip_margin", "torque"} <= set(bumps[0])
    with open(tmp_path / "steps.csv") as stream:
        rows = list(csv.DictReader(stream))
    total = sum(float(rows[1][f"bump{i}_normal_force"]) for i in range(9))
    assert total == pytest.approx(float(rows[1]["normal_force"]), rel=1e-9)     # CSV keeps 16 digits
    vtu = meshio.read(tmp_path / "increment_002.vtu")
    assert set(np.unique(vtu.point_data["bump"])) == set(range(-1, 9))
    assert vtu.point_data["bump_stick_ratio"].max() <= 1.0


def test_compliance_columns_come_back_from_the_disk_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("FINGERTIP_CACHE", str(tmp_path))
    scene = Scene(name="small", material=Material(1.0, 0.45), mesh=MeshSettings(size_contact=0.35),
                  contact=ContactSpec(friction_coefficient=0.5),
                  loads=(Load(LoadKind.PRESS, "force", (0.2,)), Load(LoadKind.SHEAR, "force", (0.05,))))
    first = solve_scene(scene)
    assert first.timings["compliance_columns"] > 0 and first.timings["compliance_columns_loaded"] == 0
    assert list((tmp_path / "compliance").glob("compliance-*.npz"))
    second = solve_scene(scene)
    assert second.timings["compliance_columns"] == 0
    assert second.timings["compliance_columns_loaded"] == first.timings["compliance_columns"]
    # the same columns (bit for bit), summed in another order (all stored columns at once): the same solution to
    # the Newton tolerance (1e-10 of the force scale)
    for a, b in zip(first.increments, second.increments):
        scale = np.abs(a.pressure).max()
        assert np.allclose(a.pressure, b.pressure, rtol=0, atol=1e-9 * scale)
        assert np.allclose(a.traction, b.traction, rtol=0, atol=1e-9 * scale)
    uncached = solve_scene(scene, cache_compliance=False)
    assert uncached.timings["compliance_columns"] == first.timings["compliance_columns"]
