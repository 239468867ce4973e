"""Coupled half-space reference (contact.halfspace): exact cell integrals, a symmetric positive-definite influence
matrix, the bonded punch of Mossakovskii, Hertz, Cattaneo-Mindlin at nu -> 0.5 and the frictional press with the
full coupling."""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from contact.halfspace import HalfSpaceCompliance, cell_integrals, solve_halfspace
from contact.scene import ContactSpec, Load, LoadKind, Material, Scene
from contact.theory import hertz, stick_ratio_translational

FORCE, RADIUS, MU = 0.2, 10.0, 0.5


def test_cell_integrals_match_quadrature():
    from scipy.integrate import dblquad

    spacing = 0.3
    kernels = {"1/rho": lambda y, x: 1 / np.hypot(x, y), "xx/rho3": lambda y, x: x * x / np.hypot(x, y) ** 3,
               "yy/rho3": lambda y, x: y * y / np.hypot(x, y) ** 3, "xy/rho3": lambda y, x: x * y / np.hypot(x, y) ** 3,
               "x/rho2": lambda y, x: x / (x * x + y * y), "y/rho2": lambda y, x: y / (x * x + y * y)}
    for x, y in ((0.3, 0.0), (0.6, -0.9), (-1.2, 0.3)):
        closed = cell_integrals(np.array(x), np.array(y), spacing)
        for name, kernel in kernels.items():
            numeric = dblquad(kernel, x - spacing / 2, x + spacing / 2, y - spacing / 2, y + spacing / 2)[0]
            assert float(closed[name]) == pytest.approx(numeric, abs=1e-12)     # smooth integrands: quadpack 1e-14


def test_influence_matrix_is_symmetric_positive_definite_and_fft_agrees():
    # Betti's reciprocity makes C symmetric; the elastic energy makes it positive definite
    for mirror in (False, True):
        compliance = HalfSpaceCompliance(0.35, 0.3, 0.2, 7, 6, mirror_y=mirror)
        columns = np.arange(compliance.size)
        matrix = compliance.block(slice(None), columns)
        np.testing.assert_allclose(matrix, matrix.T, atol=1e-14 * np.abs(matrix).max())
        assert np.linalg.eigvalsh(matrix).min() > 0
        forces = np.random.default_rng(19).normal(size=compliance.size)
        np.testing.assert_allclose(compliance.displacement(columns, forces), matrix @ forces,
                                   atol=1e-12 * np.abs(matrix @ forces).max())


def test_half_grid_with_mirror_equals_the_whole_grid():
    whole = HalfSpaceCompliance(0.35, 0.3, 0.2, 7, 8)
    half = HalfSpaceCompliance(0.35, 0.3, 0.2, 7, 4, mirror_y=True)
    forces = np.random.default_rng(7).normal(size=(7, 4, 3))
    mirrored = np.concatenate([forces[:, ::-1] * [1.0, -1.0, 1.0], forces], axis=1)     # t_y odd, t_x and p even
    expected = whole.displacement(np.arange(whole.size), mirrored.ravel()).reshape(7, 8, 3)[:, 4:]
    got = half.displacement(np.arange(half.size), forces.ravel()).reshape(7, 4, 3)
    np.testing.assert_allclose(got, expected, atol=1e-12 * np.abs(expected).max())


@pytest.mark.parametrize("poissons_ratio", [0.0, 0.3, 0.45])
def test_bonded_flat_punch_follows_mossakovskii(poissons_ratio):
    # A rigid flat punch bonded to the half-space needs (1 - nu) ln(3 - 4 nu) / (1 - 2 nu) times the force of a
    # frictionless one for the same depth (Mossakovskii 1954; Spence 1968): this ratio exists only through the
    # normal-tangential coupling. Measured on 8-16 cells per radius: error 0.031 h/a (nu = 0), first order.
    cells = 10
    spacing = 1.0 / cells
    compliance = HalfSpaceCompliance(1.0, poissons_ratio, spacing, 2 * cells + 1, 2 * cells + 1)
    under = np.flatnonzero(np.hypot(*compliance.positions.T) < 1.0)
    columns = compliance.unknown_index(under)
    bonded = np.linalg.solve(compliance.block(columns, columns), np.tile([0.0, 0.0, -1.0], under.size))
    normal = columns[2::3]
    frictionless = np.linalg.solve(compliance.block(normal, normal), -np.ones(under.size))
    nu = poissons_ratio
    expected = (1 - nu) * math.log(3 - 4 * nu) / (1 - 2 * nu)
    assert bonded[2::3].sum() / frictionless.sum() == pytest.approx(expected, rel=0.05 * spacing)


def half_space_scene(nu, shear_ratios=(0.2, 0.5, 0.8), press_steps=1, frictionless_press=False):
    press = tuple(FORCE * k / press_steps for k in range(1, press_steps + 1))
    return Scene(name="half-space", material=Material(1.0, nu), contact=ContactSpec(friction_coefficient=MU,
                 frictionless_press=frictionless_press),
                 loads=(Load(LoadKind.PRESS, "force", press),
                        Load(LoadKind.SHEAR, "force", tuple(r * MU * FORCE for r in shear_ratios))))


SPACING = 0.1       # mm, about a/10.6


def test_nearly_incompressible_half_space_follows_hertz_and_cattaneo_mindlin():
    # nu -> 0.5 removes the coupling (beta = 0), so Hertz and Cattaneo-Mindlin are exact. Measured at a/10.6 with
    # the recovery: a +0.04 %, p0 +0.3 %, c/a within 0.0014; at a/15: a -0.04 %, c/a within 0.0018.
    scene = half_space_scene(0.4999)
    increments = solve_halfspace(scene, SPACING)
    reference = hertz(FORCE, RADIUS, scene.material.effective_modulus)
    press = increments[0].recovered
    assert press.contact_radius == pytest.approx(float(reference.contact_radius), rel=0.005)
    assert press.peak_pressure == pytest.approx(float(reference.peak_pressure), rel=0.01)
    for ratio, increment in zip((0.2, 0.5, 0.8), increments[1:]):
        assert increment.tangential_force == pytest.approx(ratio * MU * FORCE, rel=1e-8)   # Newton's tolerance
        assert increment.recovered.stick_ratio == pytest.approx(float(stick_ratio_translational(ratio, 2)),
                                                                abs=0.004)


INDEPENDENT = Path(__file__).parent / "data" / "coupled_halfspace_reference.json"


def _independent(name: str) -> tuple[dict, list[dict]]:
    """The case ``name`` of tests/data/coupled_halfspace_reference.json (written by the script beside it)."""
    document = json.loads(INDEPENDENT.read_text())
    return document, document["cases"][name]


def _compare_with_the_independent_computation(name: str) -> list:
    # Two implementations of one discrete problem (the same cells, sphere and load path): contact.halfspace (closed-
    # form cell integrals, semi-smooth Newton to 1e-10) and the script's (Gauss quadrature of the kernels, a staggered
    # active-set / projected Gauss-Seidel process to 1e-12). The same cells must be in contact and stuck, and the
    # pressures agree to the solvers' tolerances: measured 1e-10 relative; 1e-8 bounds it. An error in either one's
    # kernels, coupling signs or friction law moves a cell or the pressure by far more.
    document, case = _independent(name)
    scene = half_space_scene(case["poissons_ratio"], shear_ratios=tuple(case["shear_ratios"]),
                             press_steps=case["press_steps"], frictionless_press=not case["frictional_press"])
    increments = solve_halfspace(scene, document["spacing"])
    p0 = float(hertz(FORCE, RADIUS, scene.material.effective_modulus).peak_pressure)
    assert len(increments) == len(case["increments"])
    for increment, expected in zip(increments, case["increments"]):
        assert increment.contact_radius == pytest.approx(expected["contact_radius"], abs=1e-12)
        assert increment.stick_ratio == pytest.approx(expected["stick_ratio"], abs=1e-12)
        assert increment.pressure.max() / p0 == pytest.approx(expected["peak_pressure_ratio"], rel=1e-8)
        assert increment.tangential_force == pytest.approx(expected["tangential_force"], abs=1e-10 * FORCE)
    return increments


def test_frictional_press_at_nu_zero_matches_the_independent_coupled_computation():
    increments = _compare_with_the_independent_computation("nu=0")
    # what the coupling does at nu = 0 (beta/mu = 1): after the press a central stick zone (c/a = 0.79 here), a
    # pressure peak 31 % above Hertz's, a contact 3 % smaller; under shear c/a well below Cattaneo-Mindlin (-0.21)
    pressed = increments[15]
    assert pressed.stick_ratio < 0.85 and pressed.pressure.max() > 1.25 * float(
        hertz(FORCE, RADIUS, 1.0).peak_pressure)
    assert increments[-1].stick_ratio < float(stick_ratio_translational(0.5, 2)) - 0.15


@pytest.mark.slow
def test_frictional_press_at_nu_03_matches_the_independent_coupled_computation():
    _compare_with_the_independent_computation("nu=0.3")


def test_coupling_vanishes_without_frictional_press():
    # with the press frictionless only the tangential coupling acts: contact.halfspace matches the independent
    # computation cell for cell (nodal c/a 0.934, 0.802, 0.602 against Cattaneo-Mindlin's 0.928, 0.794, 0.585: the
    # cells are a/10.6, so +-0.5 h/a = 0.047), and its recovered c/a stays within 0.009 of Cattaneo-Mindlin
    increments = _compare_with_the_independent_computation("nu=0.3, frictionless press")
    _, case = _independent("nu=0.3, frictionless press")
    for ratio, increment in zip(case["shear_ratios"], increments[1:]):
        assert increment.stick_ratio == pytest.approx(float(stick_ratio_translational(ratio, 2)), abs=0.047)
        assert increment.recovered.stick_ratio == pytest.approx(float(stick_ratio_translational(ratio, 2)),
                                                                abs=0.009)


@pytest.mark.slow
def test_the_independent_computation_reproduces_its_stored_numbers(tmp_path):
    # the stored numbers are what the script computes (a few minutes): the reference cannot drift from its source
    import subprocess
    import sys

    out = tmp_path / "again.json"
    subprocess.run([sys.executable, str(INDEPENDENT.with_suffix(".py")), "--out", str(out)], check=True,
                   capture_output=True)
    stored, again = json.loads(INDEPENDENT.read_text()), json.loads(out.read_text())
    for name, case in stored["cases"].items():
        for expected, got in zip(case["increments"], again["cases"][name]["increments"]):
            assert got["stick_ratio"] == expected["stick_ratio"]
            assert got["peak_pressure_ratio"] == pytest.approx(expected["peak_pressure_ratio"], rel=1e-9)


def test_plane_body_and_twist_are_refused():
    scene = half_space_scene(0.45)
    with pytest.raises(ValueError, match="a sphere on a block or a plane on a cap"):
        solve_halfspace(dataclasses.replace(scene, body=dataclasses.replace(scene.body, shape="plane")), SPACING)
    twist = dataclasses.replace(scene, loads=scene.loads[:1] + (Load(LoadKind.TWIST, "displacement", (0.01,)),))
    with pytest.raises(ValueError, match="press and shear loads only"):
        solve_halfspace(twist, SPACING)
    with pytest.raises(ValueError, match="spacing"):
        solve_halfspace(scene, -0.1)
