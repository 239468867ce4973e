"""FEM frictional contact against Hertz, Cattaneo-Mindlin, Mindlin and Lubkin, plus invariants of every increment."""

from __future__ import annotations

import math

import numpy as np
import pytest

from contact._newton import OPEN, SLIP
from contact.scene import ContactSpec, Load, LoadKind, Material, MeshSettings, Scene
from contact.solver import PathNotCompleted, solve_scene
from contact.theory import hertz, lubkin_torque_twist, mindlin_shift, stick_ratio_translational

RADIUS, FORCE, MU, E = 10.0, 0.2, 0.5, 1.0
SHEAR_RATIOS = (0.2, 0.5, 0.8)
TWIST_STICK = (0.9, 0.7, 0.5)          # stick ratios at which the Lubkin torque is applied
H = 0.2                                 # mm, CI-size element; a ~ 1.1 mm, so h ~ a/5.5


def scene(nu, loads, h=H, frictionless_press=True, mu=MU, **contact):
    return Scene(name="test", material=Material(E, nu), mesh=MeshSettings(size_contact=h),
                 contact=ContactSpec(friction_coefficient=mu, frictionless_press=frictionless_press, **contact), loads=loads)


def half_space(nu):
    e_star = E / (1 - nu**2)
    return hertz(FORCE, RADIUS, e_star)


@pytest.fixture(scope="module")
def shear_result():
    # nu = 0.3 with friction switched on after the press: docs/theory.md, sec. 8.3 shows this removes the Spence
    # pre-slip and leaves c/a within 0.005 of Cattaneo-Mindlin, so the test sees the discretisation error alone.
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)),
             Load(LoadKind.SHEAR, "force", tuple(r * MU * FORCE for r in SHEAR_RATIOS)))
    return solve_scene(scene(0.3, loads))


@pytest.fixture(scope="module")
def twist_result():
    nu = 0.3
    a = float(half_space(nu).contact_radius)
    torques = [float(lubkin_torque_twist(c, FORCE, MU, a, E / (2 * (1 + nu)))[0]) for c in TWIST_STICK]
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)), Load(LoadKind.TWIST, "force", tuple(torques)))
    return solve_scene(scene(nu, loads))


def test_base_reaction_balances_the_body_load(shear_result):
    # the supports carry the load the body applies: a linear FE identity, exact to the solver's round-off
    model = shear_result.model
    # a half model (mirror about y = 0) carries half of the x and z forces; its y forces close on the mirror plane
    halves = 2.0 if shear_result.mesh_info["half_model"] else 1.0
    for inc in shear_result.increments:
        base_force_z = halves * float((inc.base_pressure * model.base.areas).sum())
        base_force_x = halves * float((inc.base_traction[:, 0] * model.base.areas).sum())
        assert base_force_z == pytest.approx(inc.normal_force, rel=1e-8)
        assert base_force_x == pytest.approx(-inc.tangential_force[0], abs=1e-8 * FORCE)


def test_every_point_obeys_contact_and_coulomb(shear_result):
    # Alart-Curnier converged to 1e-10 relative: gaps, forces and the cone hold to that precision
    body = shear_result.scene.body
    positions = shear_result.candidate_positions
    model = shear_result.model
    tol_force = 1e-8 * FORCE
    for inc in shear_result.increments:
        u_z = inc.displacement_full[model.top.dofs[shear_result.candidates, 2]]
        gap = body.initial_gap(positions[:, :2]) - inc.depth - u_z
        assert gap.min() > -1e-8 * inc.depth, "penetration"
        normal = inc.pressure * shear_result.candidate_areas
        tangential = np.linalg.norm(inc.traction, axis=1) * shear_result.candidate_areas
        assert normal.min() > -tol_force
        mu = 0.0 if inc.load_kind == "press" else MU     # friction switched on after the press
        assert np.all(tangential <= mu * normal + tol_force), "traction outside the friction cone"
        assert np.all(normal[inc.status == OPEN] < tol_force)
        slipping = inc.status == SLIP
        np.testing.assert_allclose(tangential[slipping], mu * normal[slipping], atol=tol_force)


def test_contact_radius_and_depth_follow_hertz(shear_result):
    nu = 0.3
    reference = half_space(nu)
    press = shear_result.increments[0]
    # a is known to +-h/2 (the edge lies between a contact and an open point, docs/theory.md, sec. 11.1)
    assert press.contact_radius == pytest.approx(float(reference.contact_radius), abs=H / 2)
    # The fixed base 20 mm down removes the half-space settlement there, P (3 - 2 nu) / (4 pi G z) (Boussinesq);
    # what remains must match Hertz to the 3 % of docs/theory.md, sec. 11.8.
    shear_modulus = E / (2 * (1 + nu))
    settlement = FORCE * (3 - 2 * nu) / (4 * math.pi * shear_modulus * 20.0)
    assert press.depth == pytest.approx(float(reference.indentation) - settlement, rel=0.03)


def test_stick_ratio_follows_cattaneo_mindlin(shear_result):
    for ratio, inc in zip(SHEAR_RATIOS, shear_result.increments[1:]):
        expected = float(stick_ratio_translational(ratio, 2))
        # stick and contact edges are each known to +-h/2; c/a uses the FEM's own a (docs/theory.md, sec. 11.2)
        assert inc.stick_ratio == pytest.approx(expected, abs=0.5 * H / inc.contact_radius)


def test_tangential_shift_follows_mindlin(shear_result):
    nu = 0.3
    for ratio, inc in zip(SHEAR_RATIOS, shear_result.increments[1:]):
        expected = float(mindlin_shift(ratio * MU * FORCE, FORCE, MU, inc.contact_radius, E / (2 * (1 + nu)), nu))
        assert inc.shift[0] == pytest.approx(expected, rel=0.05)    # docs/theory.md, sec. 11.8: delta(Q) to 5 %


def test_stick_ratio_under_twist_follows_lubkin(twist_result):
    torques = twist_result.scene.loads[1].values
    for expected, torque, inc in zip(TWIST_STICK, torques, twist_result.increments[1:]):
        # torsion is uncoupled from the normal problem (docs/theory.md, sec. 6.3); edge quantisation +-h/2 as above
        assert inc.stick_ratio == pytest.approx(expected, abs=0.5 * H / inc.contact_radius)
        assert inc.torque == pytest.approx(torque, rel=1e-8)      # the torque target is met to Newton's tolerance


RECOVERED_STICK_TOLERANCE = 0.01
# Recovered c/a (contact.recovery) against the coupled half-space reference on the same load path: measured on
# HCM-1 at h = a/5 (0.2 mm) max 0.0023 (P1, nu = 0.45) and 0.0091 (nodal-average P1, nu = 0.49), 0.005 at a/10
# (docs/coupled_reference.md); here 0.0052. The tolerance is issue 19's target at h = a/5; nodal-area c/a at this
# size is off by up to 0.035.


@pytest.fixture(scope="module")
def shear_reference(shear_result):
    from contact.halfspace import solve_halfspace

    return solve_halfspace(shear_result.scene, 0.1)       # cells a/11: c/a within 0.003 of a/21 cells


def test_recovered_stick_ratio_follows_the_coupled_reference(shear_result, shear_reference):
    for inc, reference in zip(shear_result.increments[1:], shear_reference[1:]):
        assert inc.recovered_stick_ratio == pytest.approx(reference.recovered.stick_ratio,
                                                          abs=RECOVERED_STICK_TOLERANCE)


def test_recovered_contact_radius_and_peak_pressure_follow_hertz(shear_result):
    # frictionless press: Hertz is exact. Measured at h = a/5: recovered a +0.15 %, p_max +0.6 % (nodal +2.4 %);
    # over h = 0.35 ... 0.1 mm at nu = 0.45 a within 0.5 %, p_max within 1.7 % from 0.2 mm down: 1 % and 2 %
    press = shear_result.increments[0]
    reference = half_space(0.3)
    assert press.recovered_contact_radius == pytest.approx(float(reference.contact_radius), rel=0.01)
    assert press.recovered_peak_pressure == pytest.approx(float(reference.peak_pressure), rel=0.02)


def test_fine_zone_reaches_half_the_contact_radius_below_a_sphere():
    from dataclasses import replace

    from contact.limits import SHALLOW_FINE_DEPTH, estimated_contact, fine_depth
    from contact.scene import BodySpec, GelSpec

    pressed = scene(0.45, (Load(LoadKind.PRESS, "force", (FORCE,)),))
    # the Hertz field's largest shear stress lies at 0.48 a below the surface (Johnson 1985, sec. 4.2)
    assert fine_depth(pressed) == pytest.approx(0.5 * estimated_contact(pressed)[0], rel=1e-12)
    assert fine_depth(replace(pressed, body=BodySpec(shape="plane"))) == SHALLOW_FINE_DEPTH
    thin = replace(pressed, gel=GelSpec(parameters=(("width", 40.0), ("depth", 40.0), ("thickness", 1.0))))
    assert fine_depth(thin) == 0.5                              # at most half the block


@pytest.mark.slow
def test_recovered_peak_pressure_within_two_percent_of_hertz_at_a_over_10():
    # HCM-1's block, material and press at h = a/10, frictionless: Hertz exact up to the sphere's own shape (a
    # +-0.1 % effect, half-space reference) and the 40 x 40 x 20 mm block (same numbers on one twice the size).
    # Measured: recovered p_max +1.1 %, a +0.1 % (nodal +3.4 %); with the fine zone only 0.2 mm deep (before
    # contact.limits.fine_depth) +2.0 % and -0.6 %: the block was too stiff. Issue 19's 2 %, and 1 % for a.
    nu = 0.45
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)),)
    press = solve_scene(scene(nu, loads, h=0.1)).increments[0]
    reference = half_space(nu)
    assert press.recovered_peak_pressure == pytest.approx(float(reference.peak_pressure), rel=0.02)
    assert press.recovered_contact_radius == pytest.approx(float(reference.contact_radius), rel=0.01)


def test_recovered_stick_ratio_under_twist_follows_lubkin(twist_result):
    # the deficit mu p - |q| vanishes like a square root at Lubkin's stick edge too. Measured at h = a/5: recovered
    # c/a within 0.005 at c/a = 0.9 and 0.7 and 0.024 at 0.5 (stick radius 2.7 h; nodal 0.024 / 0.006 / 0.012);
    # at c/a = 0.5 it reads -0.008 / -0.024 / +0.002 / -0.003 at h = 0.3 / 0.2 / 0.14 / 0.1 mm: 0.03, a third of the
    # nodal band +-h/(2a) = 0.089. (A stick patch of 80 points alone gave -0.017 at 0.14 mm: the cone of |q| ~ r.)
    for expected, inc in zip(TWIST_STICK, twist_result.increments[1:]):
        assert inc.recovered_stick_ratio == pytest.approx(expected, abs=0.03)


@pytest.fixture(scope="module")
def nearly_incompressible_result():
    # HCM-1's frictional press at nu = 0.49, locking-free P1: beta/mu = 0.04, Cattaneo-Mindlin holds
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)),
             Load(LoadKind.SHEAR, "force", tuple(r * MU * FORCE for r in SHEAR_RATIOS)))
    problem = scene(0.49, loads, frictionless_press=False)
    problem = Scene(name="nu049", material=problem.material, contact=problem.contact, loads=loads,
                    mesh=MeshSettings(size_contact=H, volumetric="nodal_average"))
    return solve_scene(problem)


def test_recovered_stick_ratio_follows_cattaneo_mindlin_at_nu_049(nearly_incompressible_result):
    # measured at h = a/5: recovered within 0.0074 of Cattaneo-Mindlin (nodal 0.021); on HCM-1 0.0091 against the
    # coupled reference at a/5, 0.003 at a/7. Issue 19's 0.01 plus the coupling offset of c/a at nu = 0.49 (< 0.003).
    for ratio, inc in zip(SHEAR_RATIOS, nearly_incompressible_result.increments[1:]):
        assert inc.recovered_stick_ratio == pytest.approx(float(stick_ratio_translational(ratio, 2)), abs=0.013)


def test_frictionless_contact_carries_no_tangential_force():
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)), Load(LoadKind.SHEAR, "displacement", (0.05,)))
    result = solve_scene(scene(0.3, loads, h=0.3, mu=0.0))
    inc = result.increments[-1]
    assert np.abs(inc.traction).max() == 0.0
    assert np.all(inc.status[inc.status != OPEN] == SLIP)


def test_shear_beyond_friction_limit_is_refused():
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)), Load(LoadKind.SHEAR, "force", (1.01 * MU * FORCE,)))
    with pytest.raises(ValueError, match="gross slip"):
        solve_scene(scene(0.3, loads, h=0.3))


def test_body_beside_the_gel_is_refused():
    from dataclasses import replace

    loads = (Load(LoadKind.PRESS, "force", (FORCE,)),)
    problem = scene(0.3, loads, h=0.3)
    problem = replace(problem, body=replace(problem.body, center=(100.0, 0.0)))
    with pytest.raises(ValueError, match="not above the gel"):
        solve_scene(problem)


def test_non_converged_increment_keeps_earlier_results(failing_after_press):
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)), Load(LoadKind.SHEAR, "force", (0.5 * MU * FORCE,)))
    with pytest.raises(PathNotCompleted, match=r"increment 2 \(shear\).*residual history: 1.000e\+00") as caught:
        solve_scene(scene(0.3, loads, h=0.3))
    assert caught.value.result.error is not None
    assert [inc.load_kind for inc in caught.value.result.increments] == ["press"]


@pytest.mark.slow
@pytest.mark.parametrize("load_ratio", [0.2, 0.4, 0.6, 0.8, 0.9])
def test_hcm1_as_written_follows_cattaneo_mindlin(load_ratio, hcm1_result):
    inc = hcm1_result.increments[1 + [0.2, 0.4, 0.6, 0.8, 0.9].index(load_ratio)]
    expected = float(stick_ratio_translational(load_ratio, 2))
    # nodal c/a is quantised to +-h/2 (docs/theory.md, sec. 11.1; h = 0.2 mm = a/5 as written: 0.094), plus the coupling of
    # the one-increment frictional press at nu = 0.45, up to 0.026 (docs/coupled_reference.md); measured 0.045
    h = hcm1_result.scene.mesh.size_contact
    assert inc.stick_ratio == pytest.approx(expected, abs=0.5 * h / inc.contact_radius + 0.026)


@pytest.mark.slow
def test_hcm1_recovered_stick_ratio_follows_the_coupled_reference(hcm1_result):
    from contact.halfspace import solve_halfspace

    reference = solve_halfspace(hcm1_result.scene, 0.05)          # cells a/21
    # the scene's own h (0.2 mm = a/5 by default): RECOVERED_STICK_TOLERANCE, measured max 0.009
    for inc, coupled in zip(hcm1_result.increments[1:], reference[1:]):
        assert inc.recovered_stick_ratio == pytest.approx(coupled.recovered.stick_ratio,
                                                          abs=RECOVERED_STICK_TOLERANCE)


@pytest.fixture(scope="module")
def hcm1_result():
    from pathlib import Path

    from contact.scene import load_scene

    return solve_scene(load_scene(Path(__file__).parents[1] / "studies" / "scenes" / "hcm1.toml"))


def test_substeps_start_at_the_level_an_earlier_increment_needed():
    # a synthetic increment solver that converges only for steps up to a quarter of 0.4 rad: the first increment
    # fails at the full and half step and converges in quarters (level 2); started at level 2 the next increment
    # is split into the same quarters at once, with no failed attempt, and lands on the same targets
    from contact._controls import solve_with_substeps
    from contact._newton import BodyControl, ContactNotConverged, ContactState

    attempts = []

    def solve(state, control):
        attempts.append(control.angle - state.angle)
        if control.angle - state.angle > 0.1 + 1e-12:
            raise ContactNotConverged("step too large", [1.0])
        return ContactState(state.normal_force, state.tangential_force, state.displacement, angle=control.angle), 3, [0.0]

    lever = np.zeros((1, 2))
    start = ContactState(np.ones(1), np.zeros((1, 2)), np.zeros((1, 3)))
    first = solve_with_substeps(solve, start, BodyControl(normal_force=1.0, angle=0.4), lever)
    assert first[0].angle == pytest.approx(0.4) and first[3:] == (4, 2)
    assert len(attempts) == 7                     # full, half, 2 quarters, half, 2 quarters
    attempts.clear()
    second = solve_with_substeps(solve, first[0], BodyControl(normal_force=1.0, angle=0.8), lever, start_level=2)
    assert second[0].angle == pytest.approx(0.8) and second[3:] == (4, 2)
    assert attempts == pytest.approx([0.1] * 4)   # no coarser attempt before the quarters


@pytest.mark.parametrize("nu, volumetric", [(0.45, "standard"), (0.49, "nodal_average")])
def test_hcm1_recovers_the_stick_ratio_within_001_of_the_coupled_reference_at_a_over_5(nu, volumetric):
    # Issue 19's target on HCM-1's own path (frictional press, 5 shear increments to Q/(mu P) = 0.9) at h = a/5.
    # Measured against the a/15 reference used here: max 0.0029 at nu = 0.45 and 0.0083 at nu = 0.49 (the last
    # increment, where the stick radius is 2.4 h); against a/21 cells 0.0023 / 0.0091. Nodal-area c/a: 0.015 / 0.035.
    # Before the stick patch was chosen by leave-one-out error and capped at slipping points: 0.0121 / 0.0166.
    from contact.halfspace import coupled_reference
    from studies.convergence import DEFAULT_REFERENCE_SPACING, hcm1_case_scene

    problem, ratios = hcm1_case_scene(0.2, 1, 5, nu, volumetric)
    result = solve_scene(problem, cache_compliance=False)
    reference = coupled_reference(problem, DEFAULT_REFERENCE_SPACING)
    assert len(result.increments) == len(reference) == len(ratios) + 1
    for inc, expected in zip(result.increments[1:], reference[1:]):
        assert inc.recovered_stick_ratio == pytest.approx(expected.recovered.stick_ratio, abs=RECOVERED_STICK_TOLERANCE)


@pytest.mark.parametrize("size_contact", [0.35, 0.2])
def test_resource_estimate_is_within_a_factor_two_of_the_mesh(size_contact):
    # The estimate refuses meshes that cannot fit the machine before meshing them: measured on HCM-1 at 0.35 ... 0.1
    # mm it gives 1.3-2.1x the DOF and tets of the mesh (about the factor of 2 it promises); at 0.07 mm 2.3x the DOF,
    # and 12 GB against a measured peak of 2.5 GB (it once said 23 GB and refused the mesh on a machine with 21 GB).
    from contact.limits import estimate_resources
    from contact.solver import prepare
    from studies.convergence import hcm1_case_scene

    problem = hcm1_case_scene(size_contact, 1, 1)[0]
    prepared = prepare(problem)
    estimate = estimate_resources(problem, prepared.fine_radius, prepared.half)
    assert 0.8 * prepared.mesh_info["dofs"] <= estimate["dofs"] <= 2.0 * prepared.mesh_info["dofs"]
    assert 0.8 * prepared.mesh_info["elements"] <= estimate["tets"] <= 2.0 * prepared.mesh_info["elements"]
