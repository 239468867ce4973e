"""The compressible Neo-Hookean gel (fem.hyperelastic): its stress is the energy's derivative, it is the linear gel at
small strain, and its tangent stiffness is the internal force's derivative."""

import numpy as np
import pytest

from fem.elasticity import assemble_elastic_model, assemble_stiffness, lame_parameters
from fem.hyperelastic import (InvertedElement, bulk_modulus, displacement_gradient, internal_force, neo_hookean_stress,
                              tangent_stiffness)
from fem.mesh import BlockMeshSpec, graded_block_mesh

E, NU = 0.3, 0.45


def _energy(deformation, shear_modulus, bulk):
    """W = G/2 (J^(-2/3) I1 - 3) + K/2 (J - 1)^2 written out, apart from the code's stress [MPa]."""
    jacobian = np.linalg.det(deformation)
    return (shear_modulus / 2.0 * (jacobian ** (-2.0 / 3.0) * np.sum(deformation**2) - 3.0)
            + bulk / 2.0 * (jacobian - 1.0) ** 2)


def _force(model, displacement):
    return internal_force(model, displacement_gradient(model, displacement), E, NU)


@pytest.fixture(scope="module")
def block():
    spec = BlockMeshSpec(width=4.0, depth=4.0, thickness=2.0, size_contact=0.5, size_far=1.0, fine_radius=1.0,
                         fine_depth=1.0, fine_center=(0.0, 0.0), grading=1.3, half=False)
    return assemble_elastic_model(graded_block_mesh(spec), E, NU)


def test_stress_is_the_derivative_of_the_strain_energy():
    shear_modulus = lame_parameters(E, NU)[1]
    bulk = bulk_modulus(E, NU)
    gradient = np.array([[0.2, -0.1, 0.05], [0.15, -0.25, 0.1], [-0.05, 0.2, 0.3]])
    stress = neo_hookean_stress(gradient[:, :, None, None], shear_modulus, bulk)[:, :, 0, 0]
    step = 1e-6
    numeric = np.zeros((3, 3))
    for i in range(3):
        for j in range(3):
            shifted = np.zeros((3, 3))
            shifted[i, j] = step
            numeric[i, j] = (_energy(np.eye(3) + gradient + shifted, shear_modulus, bulk)
                             - _energy(np.eye(3) + gradient - shifted, shear_modulus, bulk)) / (2.0 * step)
    # central differences of W are exact to O(step^2) ~ 1e-12 of the stress's 0.1 MPa scale; 1e-7 is round-off room
    assert stress == pytest.approx(numeric, abs=1e-7)


def test_internal_force_is_the_linear_gel_to_second_order(block):
    stiffness = assemble_stiffness(block.basis, E, NU)
    direction = np.random.default_rng(0).normal(size=block.n_dofs) * 0.1
    remainders = [np.abs(_force(block, s * direction) - stiffness @ (s * direction)).max() for s in (1e-2, 1e-3)]
    linear = np.abs(stiffness @ (1e-3 * direction)).max()
    # r(u) = f_int(u) - K u is quadratic in u: a tenth of the displacement leaves a hundredth of it (to 1 %)
    assert remainders[0] / remainders[1] == pytest.approx(100.0, rel=0.01)
    assert remainders[1] < 1e-2 * linear


def test_tangent_stiffness_is_the_internal_forces_derivative(block):
    rng = np.random.default_rng(1)
    displacement = rng.normal(size=block.n_dofs) * 0.02          # strains of a few per cent, every element upright
    direction = rng.normal(size=block.n_dofs)
    tangent = tangent_stiffness(block, displacement_gradient(block, displacement), E, NU).tocsr()
    step = 1e-6
    numeric = (_force(block, displacement + step * direction)
               - _force(block, displacement - step * direction)) / (2.0 * step)
    # central differences: O(step^2) truncation and ~1e-10 round-off against forces of order 1 N/mm
    assert tangent @ direction == pytest.approx(numeric, abs=1e-7 * np.abs(numeric).max())
    assert abs(tangent - tangent.T).max() < 1e-12                  # a hyperelastic tangent is symmetric
    at_rest = tangent_stiffness(block, displacement_gradient(block, np.zeros(block.n_dofs)), E, NU).tocsr()
    assert abs(at_rest - assemble_stiffness(block.basis, E, NU)).max() < 1e-12


def test_an_inverted_element_is_reported_by_its_jacobian(block):
    displacement = np.zeros(block.n_dofs)
    displacement[block.basis.nodal_dofs[2]] = -3.0 * block.mesh.p[2]        # z -> -2 z: every element flipped
    with pytest.raises(InvertedElement, match=r"det F = -\d"):
        displacement_gradient(block, displacement)
