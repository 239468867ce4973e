"""The CalculiX finite-strain reference (contact.calculix): file readers, meshes and decks without ccx; with ccx, one
small press against the project's FEM, Hertz and the small-strain limit of the Neo-Hookean gel."""

import math

import numpy as np
import pytest

from contact.calculix import (BumpSetup, CalculixUnavailable, GelLaw, SpherePress, ccx_executable, read_dat,
                              read_frd, run_deck, sphere_press_job, sphere_press_scene)
from contact.calculix._deck import bump_deck, material_card, sphere_press_deck
from contact.calculix._mesh import axisymmetric_layer, bump

needs_ccx = pytest.mark.skipif(ccx_executable() is None, reason="CalculiX (ccx) not installed (apt-get install "
                                                                 "calculix-ccx)")


def test_dat_tables_are_read_with_set_time_and_rows(tmp_path):
    text = (" forces (fx,fy,fz) for set BASE and time  0.1500000E+01\n\n"
            "        12 -1.000000E-02  2.000000E-03  3.500000E-01\n        13  0.000000E+00  0.0 1.25E-01\n\n"
            " statistics for slave set TOP, master set BALL and time  0.2000000E+00\n\n"
            "   area,  normal force (+ = tension) and shear force (size)\n\n    4.4E+00 -2.7E-01  2.1E-02\n")
    (tmp_path / "job.dat").write_text(text)
    forces, statistics = read_dat(tmp_path / "job.dat")
    assert (forces.what, forces.set_name, forces.time) == ("forces (fx,fy,fz)", "BASE", 1.5)
    np.testing.assert_array_equal(forces.array, [[12, -0.01, 0.002, 0.35], [13, 0.0, 0.0, 0.125]])
    assert (statistics.set_name, statistics.time, statistics.array[0, 0]) == ("TOP/BALL", 0.2, 4.4)


def test_frd_blocks_are_read_with_touching_numbers(tmp_path):
    # fixed columns: ' -1', a 10-character node number, 12-character values that may touch (no blank before '-')
    lines = ["    2C                             2                                     1",
             " -1         1 0.00000E+00-1.00000E+01 0.00000E+00", " -1         2 3.00000E+01-1.00000E+01 1.50000E+00",
             " -3", "    1PSTEP                         1           1           1",
             "  100CL  101 2.50000E-01           2                     0    1           1",
             " -4  DISP        4    1", " -5  D1          1    2    1    0", " -5  D2          1    2    2    0",
             " -5  D3          1    2    3    0", " -5  ALL         1    2    0    0    1ALL",
             " -1         1 1.00000E-01-2.00000E-01 3.00000E-01", " -1         2-4.00000E-01 5.00000E-01-6.00000E-01",
             " -3"]
    (tmp_path / "job.frd").write_text("\n".join(lines) + "\n")
    coordinates, steps = read_frd(tmp_path / "job.frd")
    np.testing.assert_array_equal(coordinates[2], [30.0, -10.0, 1.5])
    assert len(steps) == 1 and steps[0].time == 0.25
    np.testing.assert_array_equal(steps[0].field("DISP", [2, 1]), [[-0.4, 0.5, -0.6], [0.1, -0.2, 0.3]])
    np.testing.assert_array_equal(steps[0].field("DISP", [2], "D3"), [-0.6])


def test_axisymmetric_layer_mesh_is_counter_clockwise_and_covers_the_layer():
    mesh = axisymmetric_layer(10.0, 5.0, 5.0, 0.4, 2.0, 3.0, 1.0)
    corners = mesh.nodes[mesh.quads[:, :4] - 1]
    area = 0.5 * np.sum(corners[:, :, 0] * np.roll(corners[:, :, 1], -1, 1) - np.roll(corners[:, :, 0], -1, 1)
                        * corners[:, :, 1], axis=1)
    assert np.all(area > 0)                                                  # CalculiX needs counter-clockwise
    assert area.sum() == pytest.approx(10.0 * 5.0, rel=1e-12)               # straight-sided quads fill the box
    band = mesh.nodes[mesh.band_nodes - 1]
    assert np.abs(np.hypot(band[:, 0], band[:, 1] - 5.0)).max() == pytest.approx(5.0, rel=1e-12)   # on the sphere


def test_bump_mesh_has_positive_tets_and_its_contact_faces_cover_the_cap():
    setup = BumpSetup(size_contact=0.8, size_far=2.0)
    for half in (True, False):
        mesh = bump(setup.bump_radius, setup.base_width, setup.base_thickness, 0.8, 2.0, 3.6, setup.contact_reach,
                    half)
        x = mesh.nodes[mesh.tets - 1]
        assert np.all(np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0]) > 0)
        xy = mesh.nodes[mesh.surface_triangles() - 1, :2]
        edge, other = xy[:, 1] - xy[:, 0], xy[:, 2] - xy[:, 0]
        projected = 0.5 * np.abs(edge[:, 0] * other[:, 1] - edge[:, 1] * other[:, 0]).sum() * (2 if half else 1)
        # the faces whose corners all lie within the reach fill the disc of that radius but for its jagged rim,
        # about one element (0.8 mm) of the 4.3 mm radius: between (r - h)^2 / r^2 = 0.66 and 1 of pi r^2
        assert 0.66 * math.pi * setup.contact_reach**2 < projected <= math.pi * setup.contact_reach**2


def test_decks_state_the_gel_law_and_the_contact():
    assert material_card(GelLaw.LINEAR, 0.3, 0.45) == "*MATERIAL,NAME=GEL\n*ELASTIC\n0.3,0.45\n"
    # C10 = G/2 and D1 = 2/K: the Neo-Hookean gel's small-strain moduli are the linear gel's
    neo = material_card(GelLaw.NEO_HOOKE, 0.3, 0.45).splitlines()[2].split(",")
    assert float(neo[0]) == pytest.approx(0.3 / (2 * 1.45) / 2) and float(neo[1]) == pytest.approx(2 / 1.0)
    layer = axisymmetric_layer(10.0, 5.0, 5.0, 0.4, 2.0, 3.0, 1.0)
    press = sphere_press_deck(layer, GelLaw.NEO_HOOKE, 0.3, 0.45, 1.0, 4)
    assert "*STEP,NLGEOM" in press and "TYPE=SURFACE TO SURFACE" in press and "BAND,2,2,-1\n" in press
    assert "NLGEOM" not in sphere_press_deck(layer, GelLaw.LINEAR, 0.3, 0.45, 1.0, 4)
    mesh = bump(4.67, 13.3, 3.0, 0.9, 2.0, 3.6, 4.3, half=False)
    twist = bump_deck(mesh, GelLaw.LINEAR, 0.3, 0.45, 1.0, 1.5, "twist", 0.6, 3, 40.0)
    assert twist.count("*STEP") == 4 and "TYPE=MORTAR" in twist and twist.count("*CHANGE FRICTION") == 1
    assert "*FRICTION\n0.001,100\n" in twist and "*FRICTION\n1,100\n" in twist       # friction on after the press
    rough = bump_deck(mesh, GelLaw.LINEAR, 0.3, 0.45, 1.0, 1.5, "twist", 0.6, 3, 40.0, frictional_press=True)
    assert "*CHANGE FRICTION" not in rough and "*FRICTION\n1,100\n" in rough and "0.001,100" not in rough
    with pytest.raises(ValueError, match="needs the half bump mesh"):
        bump_deck(mesh, GelLaw.LINEAR, 0.3, 0.45, 1.0, 1.5, "shear", 1.0, 3, 40.0)


def test_without_ccx_the_reference_says_how_to_install_it(monkeypatch, tmp_path):
    monkeypatch.setenv("FINGERTIP_CCX", str(tmp_path / "no-such-ccx"))
    with pytest.raises(CalculixUnavailable, match="apt-get install calculix-ccx"):
        run_deck("*HEADING\n")
    from studies import finite_strain

    summary = finite_strain.run(tmp_path, quick=True)
    assert summary["skipped"].startswith("skipped: CalculiX (ccx) was not found")


SMALL = SpherePress(layer_radius=15.0, depth=0.3, increments=3, size_contact=0.25, size_far=2.0)


@pytest.fixture(scope="module")
def small_press():
    from concurrent.futures import ThreadPoolExecutor

    laws = (GelLaw.LINEAR, GelLaw.NEO_HOOKE)
    jobs = [sphere_press_job(SMALL, law) for law in laws]            # gmsh meshes in this thread only
    with ThreadPoolExecutor(max_workers=2) as pool:                  # two ccx processes, one thread each
        records = list(pool.map(lambda job: job.run()[0], jobs))
    return dict(zip(laws, records))


@needs_ccx
def test_small_press_linear_calculix_lies_between_hertz_and_the_bonded_layer(small_press):
    linear = small_press[GelLaw.LINEAR]
    # three equal increments; ccx prints the time to 7 digits (1/3 as 0.3333333), hence 1e-5
    assert [r.depth for r in linear] == pytest.approx([0.1, 0.2, 0.3], rel=1e-5)
    hertz = 4.0 / 3.0 * 0.3 / (1 - 0.45**2) * math.sqrt(5.0) * SMALL.depth**1.5
    # Hertz plus the bonded layer's stiffening, which at a/H = 0.12 is between 0 and the 12 % the FEM finds at
    # a/H = 0.1 on this layer (docs/finite_strain.md): the force lies above Hertz and below 1.15 x Hertz
    assert hertz < linear[-1].normal_force < 1.15 * hertz
    # the contact radius against sqrt(R d): CAX8R at h = 0.25 mm = a/5 finds the rim within one element
    assert linear[-1].contact_radius == pytest.approx(math.sqrt(5.0 * SMALL.depth), abs=0.25)


@needs_ccx
@pytest.mark.slow
def test_small_press_linear_calculix_agrees_with_the_project_fem(small_press):
    from contact.solver import solve_scene

    linear = small_press[GelLaw.LINEAR]
    fem = solve_scene(sphere_press_scene(SMALL, (linear[-1].normal_force,), size_contact=0.25)).increments[0]
    # both gels are linear and small strain; at d/R = 0.06 the contact found in the deformed geometry (CalculiX)
    # and the gap paired at the start (FEM) differ by < 1 % (the study measures it growing with d/R); the FEM's
    # depth at h = a/5 is the 3 % of docs/theory.md, sec. 11.8, and CalculiX's CAX8R at h = 0.25 mm within 0.1 %
    assert fem.depth == pytest.approx(SMALL.depth, rel=0.03)
    assert fem.recovered_contact_radius == pytest.approx(linear[-1].contact_radius, rel=0.03)


@needs_ccx
def test_small_press_neo_hookean_meets_the_linear_gel_at_small_strain(small_press):
    linear, neo = small_press[GelLaw.LINEAR], small_press[GelLaw.NEO_HOOKE]
    # the two laws share their small-strain moduli; at d/R = 0.02 ... 0.06 the strains are a few per cent and the
    # Neo-Hookean force is within 1 % of the linear one (the study: +1.7 % only at d/R = 0.14)
    assert len(neo) == len(linear) == SMALL.increments
    for first, second in zip(linear, neo):
        assert second.normal_force == pytest.approx(first.normal_force, rel=0.01)
        assert second.contact_radius == pytest.approx(first.contact_radius, rel=0.01)


def test_a_job_tries_the_next_deck_only_after_a_singular_system(monkeypatch, tmp_path):
    from contact.calculix import CalculixFailed, CalculixJob
    from contact.calculix import _cases

    ran = []

    def fake_run(deck, name):
        ran.append(deck)
        if deck == "ok":
            (tmp_path / "done").write_text("1.5\n")
            return tmp_path
        raise CalculixFailed(f"ccx stopped on {deck}:\n {deck}")

    monkeypatch.setattr(_cases, "run_deck", fake_run)
    job = CalculixJob(("matrix found to be singular", "ok"), "press", lambda folder: ["read"])
    assert job.run() == (["read"], 1.5) and ran == ["matrix found to be singular", "ok"]
    ran.clear()
    diverging = CalculixJob(("*ERROR: too many cutbacks", "ok"), "press", lambda folder: ["read"])
    with pytest.raises(CalculixFailed, match="too many cutbacks"):
        diverging.run()
    assert ran == ["*ERROR: too many cutbacks"]           # another press incrementation does not cure a divergence
