"""The locking-free average-nodal-pressure tetrahedron (mesh.volumetric = "nodal_average"): patch tests, identity
with standard P1 at lambda = 0, SPD, its saddle-point factorization against the condensed K, and nearly
incompressible contact against Hertz and Cattaneo-Mindlin."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.linalg import spsolve
from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, FacetBasis, LinearForm, MeshTet, asm

from contact.scene import ContactSpec, GelSpec, Load, LoadKind, Material, MeshSettings, Scene
from contact.solver import preparation_key, solve_scene
from contact.theory import hertz, stick_ratio_translational
from fem.elasticity import assemble_elastic_model, assemble_stiffness
from fem.linear_solver import SaddlePointFactorization, available_backends

E, NU_INCOMPRESSIBLE = 1.0, 0.4999          # MPa, -
# round-off amplified by cond(K) ~ (lambda / G) (L / h)^2 ~ 1e5 on the 4 x 4 x 4 patch at nu = 0.4999 (measured
# 7e4 nodal-average, 2e5 standard): 1e5 * eps ~ 2e-11 relative; 1e-9 leaves a factor 50 (observed: 2e-12)
PATCH_TOLERANCE = 1e-9


def distorted_cube(divisions: int = 4, seed: int = 0) -> MeshTet:
    """Unit cube [mm] of Kuhn tets with the interior nodes moved at random by up to 0.2 of the spacing (seeded)."""
    mesh = MeshTet.init_tensor(*[np.linspace(0.0, 1.0, divisions + 1)] * 3)
    points = mesh.p.copy()
    interior = np.all((points > 1e-12) & (points < 1.0 - 1e-12), axis=0)
    points[:, interior] += np.random.default_rng(seed).uniform(-0.2, 0.2, (3, int(interior.sum()))) / divisions
    return MeshTet(points, mesh.t)


def p1_basis(mesh) -> Basis:
    return Basis(mesh, ElementVector(ElementTetP1()), intorder=1)


def linear_field(basis: Basis, gradient: np.ndarray) -> np.ndarray:
    """Dof vector of u(x) = gradient @ x [mm], a homogeneous strain state, on a vector P1 basis."""
    values = gradient @ basis.doflocs                                   # (3, n_dofs): each component at each dof
    field = np.zeros(basis.N)
    for component, dofs in enumerate(basis.split_indices()):
        field[dofs] = values[component, dofs]
    return field


def solve_with_dirichlet(stiffness, force: np.ndarray, fixed: np.ndarray, fixed_values: np.ndarray) -> np.ndarray:
    """u [mm] of K u = f with u[fixed] = fixed_values (a dense solve: the patch meshes are tiny)."""
    free = np.setdiff1d(np.arange(stiffness.shape[0]), fixed)
    displacement = np.zeros(stiffness.shape[0])
    displacement[fixed] = fixed_values
    rhs = force[free] - stiffness[free][:, fixed] @ fixed_values
    displacement[free] = np.linalg.solve(stiffness[free][:, free].toarray(), rhs)
    return displacement


@pytest.mark.parametrize("volumetric", ["standard", "nodal_average"])
def test_prescribed_linear_displacement_is_reproduced(volumetric):
    # a general homogeneous strain (volumetric part included) on the whole boundary: every interior node must take
    # the linear field, since the nodal pressures of a uniform div(u) are all lambda div(u) (fem.elasticity)
    basis = p1_basis(distorted_cube())
    stiffness = assemble_stiffness(basis, E, NU_INCOMPRESSIBLE, volumetric)
    exact = linear_field(basis, np.random.default_rng(1).uniform(-1e-3, 1e-3, (3, 3)))
    boundary = basis.get_dofs().all()
    computed = solve_with_dirichlet(stiffness, np.zeros(basis.N), boundary, exact[boundary])
    assert np.abs(computed - exact).max() < PATCH_TOLERANCE * np.abs(exact).max()


@pytest.mark.parametrize("volumetric", ["standard", "nodal_average"])
def test_uniaxial_stress_is_exact(volumetric):
    # traction sigma on the top face, rollers on x = 0, y = 0, z = 0: the exact field u = sigma / E (-nu x, -nu y, z)
    # has tr(eps) = (1 - 2 nu) sigma / E, so this checks the size of the nodal volumetric stiffness, not only its form
    mesh = distorted_cube()
    basis = p1_basis(mesh)
    stress = 1e-3                                                       # MPa
    top = mesh.facets_satisfying(lambda x: np.isclose(x[2], 1.0))
    force = asm(LinearForm(lambda v, w: stress * v[2]), FacetBasis(mesh, basis.elem, facets=top))
    rollers = np.concatenate([basis.get_dofs(lambda x, axis=axis: np.isclose(x[axis], 0.0)).nodal[f"u^{axis + 1}"]
                              for axis in range(3)])
    computed = solve_with_dirichlet(assemble_stiffness(basis, E, NU_INCOMPRESSIBLE, volumetric), force, rollers,
                                    np.zeros(rollers.size))
    exact = linear_field(basis, stress / E * np.diag([-NU_INCOMPRESSIBLE, -NU_INCOMPRESSIBLE, 1.0]))
    assert np.abs(computed - exact).max() < PATCH_TOLERANCE * np.abs(exact).max()


def test_equals_standard_p1_without_lambda_and_stays_spd():
    basis = p1_basis(distorted_cube(divisions=3))
    # nu = 0: lambda = 0 removes the only term in which the formulations differ, so K is the same bit for bit
    assert abs(assemble_stiffness(basis, E, 0.0, "nodal_average") - assemble_stiffness(basis, E, 0.0)).max() == 0.0
    stiffness = assemble_stiffness(basis, E, NU_INCOMPRESSIBLE, "nodal_average")
    scale = abs(stiffness).max()
    assert abs(stiffness - stiffness.T).max() < 1e2 * np.finfo(float).eps * scale    # round-off of the product
    # fixing one face removes the 6 rigid modes. K = K_shear + lambda B^T V^-1 B with the second term positive
    # semi-definite, so by Weyl's inequality no eigenvalue drops below the smallest one of K_shear = 2 G eps:eps,
    # which is K(nu = 0) scaled by G(nu) / G(0) = 1 / (1 + nu); eigvalsh is backward stable to ~1e-12 relative here
    free = np.setdiff1d(np.arange(basis.N), basis.get_dofs(lambda x: np.isclose(x[2], 0.0)).all())
    eigenvalues = np.linalg.eigvalsh(stiffness[free][:, free].toarray())
    nu_zero = assemble_stiffness(basis, E, 0.0)[free][:, free].toarray()
    shear_part = np.linalg.eigvalsh(nu_zero) / (1.0 + NU_INCOMPRESSIBLE)
    assert shear_part[0] > 1e3 * np.finfo(float).eps * scale
    assert eigenvalues[0] >= shear_part[0] * (1.0 - 1e-10)


def test_nodal_average_is_p1_only_and_named_in_errors():
    basis = Basis(MeshTet(), ElementVector(ElementTetP2()))
    with pytest.raises(ValueError, match=r"volumetric='nodal_average' needs P1 tets .*ElementTetP2"):
        assemble_stiffness(basis, E, 0.45, "nodal_average")
    with pytest.raises(ValueError, match=r"volumetric='mixed' is not one of \['nodal_average', 'standard'\]"):
        assemble_stiffness(basis, E, 0.45, "mixed")
    with pytest.raises(ValueError, match=r"mesh.volumetric='mixed' is not one of \['standard', 'nodal_average'\]"):
        MeshSettings(volumetric="mixed")
    with pytest.raises(ValueError, match=r"mesh.volumetric='nodal_average' needs mesh.order=1 .* mesh.order=2"):
        MeshSettings(volumetric="nodal_average", order=2)


# the same round-off bound for a solve on the base-fixed, mirror-plane cube: cond(K) = 1.9e5 at nu = 0.4999, so
# each direct solve is good to ~cond * eps = 4e-11 relative (observed 2e-12 between the two systems)
SOLVE_TOLERANCE = 1e-10


@pytest.fixture(scope="module")
def incompressible_cube():
    # base fixed and u_y = 0 on the plane y = 0: pressure nodes on fixed dofs are kept in the saddle-point system
    return assemble_elastic_model(distorted_cube(), E, NU_INCOMPRESSIBLE, symmetry_plane_y=0.0,
                                  volumetric="nodal_average")


def test_saddle_point_blocks_condense_to_the_stiffness(incompressible_cube):
    blocks = incompressible_cube.saddle_point
    condensed = blocks.shear_stiffness + blocks.pairing.T @ sp.diags(1.0 / blocks.pressure_compliance) @ blocks.pairing
    scale = abs(incompressible_cube.stiffness_free).max()
    assert abs(condensed - incompressible_cube.stiffness_free).max() < 1e2 * np.finfo(float).eps * scale
    # lambda = 0 has no pressure to keep (V_n / lambda = inf): the condensed K (= K_G) is factorized as it is
    assert assemble_elastic_model(distorted_cube(), E, 0.0, volumetric="nodal_average").saddle_point is None
    assert assemble_elastic_model(distorted_cube(), E, NU_INCOMPRESSIBLE).saddle_point is None


@pytest.mark.parametrize("backend", available_backends())
def test_saddle_point_solve_equals_condensed_solve(incompressible_cube, backend):
    # K^-1 f is the displacement block of the saddle-point solution with zero pressure rows (linear_solver):
    # one column, a block of columns and a block split into chunks of 2 give the condensed K's solution
    blocks = incompressible_cube.saddle_point
    stiffness = incompressible_cube.stiffness_free.tocsc()
    rhs = np.random.default_rng(2).standard_normal((stiffness.shape[0], 5))
    expected = spsolve(stiffness, rhs)
    factorization = SaddlePointFactorization(blocks.shear_stiffness, blocks.pairing, blocks.pressure_compliance,
                                             backend, chunk=2)
    assert factorization.backend == backend and factorization.factor_nonzeros > 0
    single = factorization.solve(rhs[:, 0])
    assert single.shape == (stiffness.shape[0],)
    assert np.linalg.norm(single - expected[:, 0]) < SOLVE_TOLERANCE * np.linalg.norm(expected[:, 0])
    block = factorization.solve(rhs)
    assert block.shape == rhs.shape
    assert np.linalg.norm(block - expected) < SOLVE_TOLERANCE * np.linalg.norm(expected)


def test_saddle_point_needs_a_positive_pressure_compliance(incompressible_cube):
    blocks = incompressible_cube.saddle_point
    with pytest.raises(ValueError, match=r"compliance must be finite and > 0"):
        SaddlePointFactorization(blocks.shear_stiffness, blocks.pairing, 0.0 * blocks.pressure_compliance)


# nearly incompressible contact: the stability study's block (20 x 20 x 10 mm), sphere R = 10 mm, P = 0.2 N,
# friction switched on after the press (no Spence pre-slip; beta ~ 0.001 at nu = 0.499, docs/theory.md, sec. 8)
RADIUS, FORCE, MU, NU_CONTACT = 10.0, 0.2, 0.5, 0.499
H = 0.3                                  # mm, a/3.5: standard P1 locks visibly on this mesh
SHEAR_RATIOS = (0.5, 0.8)


def contact_scene(volumetric: str) -> Scene:
    loads = (Load(LoadKind.PRESS, "force", (FORCE,)),
             Load(LoadKind.SHEAR, "force", tuple(r * MU * FORCE for r in SHEAR_RATIOS)))
    return Scene(name="incompressible", gel=GelSpec(parameters=(("width", 20.0), ("depth", 20.0), ("thickness", 10.0))),
                 material=Material(E, NU_CONTACT), mesh=MeshSettings(size_contact=H, volumetric=volumetric),
                 contact=ContactSpec(friction_coefficient=MU, frictionless_press=True), loads=loads)


@pytest.fixture(scope="module")
def incompressible_results():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")                                 # the locking warning of standard P1
        return {volumetric: solve_scene(contact_scene(volumetric)) for volumetric in ("standard", "nodal_average")}


def stick_ratio_errors(result) -> np.ndarray:
    return np.array([inc.stick_ratio - float(stick_ratio_translational(ratio, 2))
                     for ratio, inc in zip(SHEAR_RATIOS, result.increments[1:])])


def test_nodal_average_contact_follows_hertz_and_cattaneo_mindlin(incompressible_results):
    result = incompressible_results["nodal_average"]
    assert result.mesh_info["volumetric"] == "nodal_average"            # reported in result.json's "mesh"
    assert result.mesh_info["factorized_system"] == "saddle_point"
    assert incompressible_results["standard"].mesh_info["factorized_system"] == "stiffness"
    a_hertz = float(hertz(FORCE, RADIUS, E / (1 - NU_CONTACT**2)).contact_radius)
    # the same tolerances as the nu = 0.3 tests (tests/test_contact_solver.py): a to +-h/2, c/a to +-h/(2a)
    assert result.increments[0].contact_radius == pytest.approx(a_hertz, abs=H / 2)
    tolerance = np.array([0.5 * H / inc.contact_radius for inc in result.increments[1:]])
    assert np.all(np.abs(stick_ratio_errors(result)) <= tolerance)


def test_standard_p1_locks_where_nodal_average_does_not(incompressible_results):
    # one volume constraint per tet over-stiffens the gel (locking). Both results share the mesh, so the points and
    # their +-h/(2a) classification band are the same: standard P1's c/a lies below the nodal-average one by more
    # than half that band at every increment (measured 0.14 and 0.11 against 0.08; below Cattaneo-Mindlin by 0.16
    # and 0.12, the nodal average by 0.02 and 0.01)
    standard = incompressible_results["standard"]
    tolerance = np.array([0.5 * H / inc.contact_radius for inc in standard.increments[1:]])
    gap = stick_ratio_errors(incompressible_results["nodal_average"]) - stick_ratio_errors(standard)
    assert np.all(gap > 0.5 * tolerance)


def test_formulation_is_part_of_the_preparation_key():
    standard, nodal = contact_scene("standard"), contact_scene("nodal_average")
    assert preparation_key(standard) != preparation_key(nodal)
    assert preparation_key(dataclasses.replace(nodal, mesh=dataclasses.replace(nodal.mesh, volumetric="standard"))) \
        == preparation_key(standard)
