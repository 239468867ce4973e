"""FEM figure studies (Figs. 3, 4) in quick form, and the cap's contact radius converging toward Hertz."""

import csv

import numpy as np
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
    assert {"case", "load_ratio", "stick_ratio_fem", "stick_ratio_theory", "error", "error_vs_coupled"} <= set(rows[0])
    for row in rows:
        assert float(row["error"]) == pytest.approx(float(row["stick_ratio_fem"]) - float(row["stick_ratio_theory"]))
    # quick mesh h = a/5: the stick and contact edges are each known to +-h/2 (docs/theory.md, sec. 11.1), so c/a to
    # +-(h/2a)(1 + c/a) <= h/a = 0.2; checked up to Q/(mu P) = 0.9 (the mesh is the same on every run)
    judged = [r for r in rows if float(r["load_ratio"]) <= 0.9]
    assert max(abs(float(r["error"])) for r in judged) < QUICK_H_OVER_A
    assert summary["max_error"] < QUICK_H_OVER_A                    # the recovered FEM against the coupled half-space
    # the flat face keeps the stick zone: at Q/(mu P) = 0.9 more stays stuck the larger b/a is
    at_09 = {float(r["b_over_a"]): float(r["stick_ratio_fem"]) for r in rows if float(r["load_ratio"]) == 0.9}
    assert at_09[0.0] < at_09[0.5] < at_09[0.9]
    # the decomposition adds up: its four parts are steps between solutions, so they sum to FEM nodal - closed form
    # to round-off (the coupling part on finer cells is checked by the slow tests below: on the quick a/7.5 cells the
    # recovered boundaries of two half-space runs differ by up to 0.023 where the physics moves them < 0.005)
    from studies._fig3_parts import PARTS

    for row in rows:
        total = sum(float(row[part]) for part in PARTS)
        assert total == pytest.approx(float(row["error"]), abs=1e-12)


# the decomposition at one b/a on finer half-space cells: about 90 s on 2 loaded cores (three half-space solves on
# a/15 cells and the FEM), so slow; the quick figure test above checks the parts' sum at 3 b/a
@pytest.fixture(scope="module")
def fig3_parts_at_half():
    """FEM (h = a/5) and the half-space (cells a/15 and a/5) on the b/a = 0.5 cap of Fig. 3, Q/(mu P) = 0.25 ... 0.9."""
    from contact.solver import solve_scene
    from contact.theory import flat_curved, stick_ratio_profile
    from controller.estimation.bench import plate_shear_scene
    from studies import fig3
    from studies._fig3_parts import HALF_SPACE_SPACING, half_space_stick_ratios, parts

    ratios = (0.25, 0.5, 0.75, 0.9)
    profile = flat_curved(0.5, contact_radius=fig3.CONTACT_RADIUS, curvature_radius=fig3.EDGE_RADIUS)
    force = fig3.E / (1 - fig3.NU**2) * float(profile.force_per_modulus(fig3.CONTACT_RADIUS))
    scene = plate_shear_scene("fig3_half", fig3._gel(0.5), force, ratios, 0.4, fine_radius=3.4,
                              youngs_modulus=fig3.E, poissons_ratio=fig3.NU)
    fem = solve_scene(scene).increments
    half_space = half_space_stick_ratios(scene, HALF_SPACE_SPACING, 0.4)
    theory = [float(stick_ratio_profile(r, profile, contact_radius=fig3.CONTACT_RADIUS)) for r in ratios]
    rows = []
    for k, (ratio, value, increment) in enumerate(zip(ratios, theory, fem[1:])):
        coupled, uncoupled = half_space["coupled"][2][k], half_space["uncoupled"][2][k]
        rows.append(dict(load_ratio=ratio, theory=value, fem=increment.stick_ratio,
                         recovered=increment.recovered_stick_ratio, coupled=coupled,
                         uncoupled_nodal=half_space["uncoupled"][1][k], coupled_nodal=half_space["coupled"][1][k],
                         **parts(increment.stick_ratio, increment.recovered_stick_ratio, coupled, uncoupled, value)))
    return rows


@pytest.mark.slow
def test_fig3_decomposition_uncoupled_half_space_is_the_closed_form(fig3_parts_at_half):
    # the closed form (Ciavarella-Jager) is exact for an uncoupled half-space; counted by cell areas on a/15 cells
    # c/a is known to +-0.5 h/a = 0.033 (docs/theory.md, sec. 11.1): the grid is the only difference
    for row in fig3_parts_at_half:
        assert row["uncoupled_nodal"] == pytest.approx(row["theory"], abs=0.5 / 15)


@pytest.mark.slow
def test_fig3_decomposition_coupling_is_small_after_a_frictionless_press(fig3_parts_at_half):
    # Fig. 3 presses frictionless: only the tangential coupling acts, which moves c/a by less than 0.005 even at
    # nu = 0.3 (docs/theory.md, sec. 8.3); the same cells carry both, so their quantisation largely cancels: 0.01
    for row in fig3_parts_at_half:
        assert abs(row["part_coupling"]) < 0.01
        assert abs(row["coupled_nodal"] - row["uncoupled_nodal"]) < 0.01


@pytest.mark.slow
def test_fig3_decomposition_fem_follows_the_coupled_half_space(fig3_parts_at_half):
    # the right reference: the same profile, physics and path on a half-space. The recovered FEM at h = a/5 against
    # it: the FEM tolerance at a/5, +-0.5 h/a = 0.1 (docs/theory.md, sec. 11.1), holds the finite cap part too
    for row in fig3_parts_at_half:
        assert abs(row["part_finite_cap"]) < 0.1
    from studies._fig3_parts import PARTS

    total = [sum(row[part] for part in PARTS) for row in fig3_parts_at_half]
    np.testing.assert_allclose(total, [row["fem"] - row["theory"] for row in fig3_parts_at_half], atol=1e-12)


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
