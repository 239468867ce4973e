"""FEM figure studies (Figs. 3, 4) in quick form, and the cap's contact radius converging toward Hertz."""

import csv

import pytest

from contact.scene import BodySpec, ContactSpec, GelSpec, Load, LoadKind, Material, MeshSettings, Scene
from contact.solver import solve_scene
from contact.theory import hertz


QUICK_H_OVER_A = 0.2        # quick meshes of fig3 / fig4: h = 0.4 mm on contacts of radius a ~ 2 mm


def read_rows(path):
    with open(path) as stream:
        return list(csv.DictReader(stream))


def test_fig3_quick_follows_ciavarella_jager(tmp_path):
    from studies import fig3

    summary = fig3.run(tmp_path, quick=True)
    rows = read_rows(tmp_path / "fig3.csv")
    assert {"case", "load_ratio", "stick_ratio_fem", "stick_ratio_theory", "error"} <= set(rows[0])
    for row in rows:
        assert float(row["error"]) == pytest.approx(float(row["stick_ratio_fem"]) - float(row["stick_ratio_theory"]))
    # quick mesh h = a/5: the stick and contact edges are each known to +-h/2 (docs/theory.md, sec. 11.1), so c/a to
    # +-(h/2a)(1 + c/a) <= h/a = 0.2; checked up to Q/(mu P) = 0.9 (the mesh is the same on every run)
    assert summary["max_error"] < QUICK_H_OVER_A
    # the flat face keeps the stick zone: at Q/(mu P) = 0.9 more stays stuck the larger b/a is
    at_09 = {float(r["b_over_a"]): float(r["stick_ratio_fem"]) for r in rows if float(r["load_ratio"]) == 0.9}
    assert at_09[0.0] < at_09[0.5] < at_09[0.9]


def test_fig4_quick_pad_drops_late_and_cap_follows_mindlin(tmp_path):
    from studies import fig4

    summary = fig4.run(tmp_path, quick=True)
    rows = read_rows(tmp_path / "fig4.csv")
    pad = {float(r["load_ratio"]): float(r["stick_ratio_fem"]) for r in rows if r["case"] == "flat pad"}
    cap = {float(r["load_ratio"]): float(r["stick_ratio_fem"]) for r in rows if r["case"] == "spherical cap"}
    # cap at h = a/5: c/a to +-h/a as in the fig3 test; the check point Q/(mu P) = 0.5 explicitly
    assert summary["max_error"] < QUICK_H_OVER_A
    cap_at_half = next(r for r in rows if r["case"] == "spherical cap" and float(r["load_ratio"]) == 0.5)
    assert abs(float(cap_at_half["error"])) < QUICK_H_OVER_A
    # the pad stays almost fully stuck at moderate load and loses most of its stick area only near gross slip
    # (flat punch: c/a = 1 until Q -> mu P), the cap gradually (Cattaneo-Mindlin loses 0.33 of c/a up to
    # Q/(mu P) = 0.7 and 0.30 from there to 0.95): the pad's late loss is over twice its early loss, the cap's is not.
    # (This compared the pad's late loss with twice the cap's, 0.618 against 2 x 0.301 = 0.602 in theory: a 3 %
    # margin that mesh noise crossed.)
    assert pad[0.3] > 0.95 and pad[0.3] > cap[0.3]
    assert pad[0.7] - pad[0.95] > 2 * (1.0 - pad[0.7])
    assert cap[0.7] - cap[0.95] < 2 * (1.0 - cap[0.7])
    assert (tmp_path / "fig4.png").exists()


def plate_on_cap(size_contact):
    gel = GelSpec("cap", (("width", 20.0), ("depth", 20.0), ("base_thickness", 8.0), ("cap_radius", 4.0),
                          ("sphere_radius", 10.0)))
    return Scene(name="cap", gel=gel, material=Material(1.0, 0.3), body=BodySpec("plane"),
                 contact=ContactSpec(friction_coefficient=0.5), mesh=MeshSettings(size_contact=size_contact, size_far=3.0),
                 loads=(Load(LoadKind.PRESS, "force", (0.2,)),))


def test_cap_contact_radius_converges_toward_hertz():
    reference = float(hertz(0.2, 10.0, 1.0 / (1 - 0.3**2)).contact_radius)
    errors = [abs(solve_scene(plate_on_cap(h)).increments[0].contact_radius - reference) for h in (0.6, 0.3, 0.15)]
    # the error falls with h to within h/2 (edge quantisation) plus 3 % (finite cap and base, docs/theory.md, sec. 11.4)
    assert errors[2] < errors[0]
    assert errors[2] < 0.15 / 2 + 0.03 * reference
