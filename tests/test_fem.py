"""Linear elasticity operators, meshes and solver backends: invariants that need no stored numbers."""

import numpy as np
import pytest
from skfem import Basis, ElementTetP1, ElementTetP2, ElementVector, MeshTet, asm

from fem.elasticity import assemble_elastic_model, elastic_stiffness, lame_parameters
from fem.linear_solver import SpdFactorization, available_backends
from fem.mesh import BlockMeshSpec, graded_block_mesh, mesh_quality


def rigid_body_modes(basis):
    """Six rigid-body displacement fields (3 translations, 3 small rotations) as dof vectors of a vector basis."""
    x, y, z = basis.doflocs
    zero, one = np.zeros_like(x), np.ones_like(x)
    fields = [(one, zero, zero), (zero, one, zero), (zero, zero, one), (-y, x, zero), (zero, -z, y), (z, zero, -x)]
    components = basis.split_indices()                  # dof indices of u_x, u_y, u_z
    modes = []
    for field in fields:
        mode = np.zeros(basis.N)
        for component, values in zip(components, field):
            mode[component] = values[component]
        modes.append(mode)
    return modes


@pytest.mark.parametrize("element", [ElementTetP1(), ElementTetP2()])
def test_rigid_body_modes_are_in_the_null_space(element):
    mesh = MeshTet.init_tensor(*[np.linspace(0, 1, 4)] * 3)
    basis = Basis(mesh, ElementVector(element))
    lam, mu = lame_parameters(1.0, 0.45)
    stiffness = asm(elastic_stiffness, basis, lame_lambda=lam, shear_modulus=mu)
    scale = abs(stiffness).max()
    for mode in rigid_body_modes(basis):
        # K is exact for rigid motions up to round-off of its assembly
        assert np.abs(stiffness @ mode).max() < 1e3 * np.finfo(float).eps * scale * np.abs(mode).max()
    assert abs(stiffness - stiffness.T).max() < 1e2 * np.finfo(float).eps * scale


def test_graded_block_mesh_meets_its_size_targets_and_volume():
    spec = BlockMeshSpec(width=10, depth=10, thickness=5, size_contact=0.3, size_far=2.0, fine_radius=1.0)
    mesh = graded_block_mesh(spec)
    corners = mesh.p[:, mesh.t]
    volumes = np.abs(np.linalg.det((corners[:, 1:] - corners[:, :1]).transpose(2, 1, 0))) / 6
    assert volumes.sum() == pytest.approx(10 * 10 * 5, rel=1e-12)
    edges = np.linalg.norm(corners[:, [0, 0, 0, 1, 1, 2]] - corners[:, [1, 2, 3, 2, 3, 3]], axis=0).max(axis=0)
    assert np.all(edges <= spec.target_size(corners.mean(axis=1)) * (1 + 1e-9))
    quality = mesh_quality(mesh.p, mesh.t)
    assert quality.min_dihedral_deg > 30.0             # longest-edge bisection of Kuhn cubes keeps shapes bounded


def test_half_block_has_half_the_top_area_and_a_symmetry_condition():
    spec = BlockMeshSpec(width=10, depth=10, thickness=5, size_contact=0.5, size_far=2.0, fine_radius=1.0, half=True)
    model = assemble_elastic_model(graded_block_mesh(spec), 1.0, 0.3, symmetry_plane_y=0.0)
    assert model.top.areas.sum() == pytest.approx(50.0, rel=1e-12)
    on_plane = np.abs(model.top.positions[:, 1]) < 1e-12
    assert np.all(np.isin(model.top.dofs[on_plane, 1], model.fixed_dofs))
    assert not np.any(np.isin(model.top.dofs[on_plane, 0], model.fixed_dofs))


def test_solver_backends_agree():
    mesh = graded_block_mesh(BlockMeshSpec(width=6, depth=6, thickness=3, size_contact=0.6, size_far=1.5,
                                           fine_radius=1.0))
    model = assemble_elastic_model(mesh, 1.0, 0.45)
    rhs = np.random.default_rng(0).standard_normal((model.free_dofs.size, 3))
    solutions = [SpdFactorization(model.stiffness_free, backend).solve(rhs) for backend in available_backends()]
    for solution in solutions:
        # both are direct solvers: residuals at the level of round-off times the condition number
        residual = model.stiffness_free @ solution - rhs
        assert np.abs(residual).max() < 1e-8 * np.abs(rhs).max()
    np.testing.assert_allclose(solutions[0], solutions[-1], rtol=1e-7, atol=1e-10 * np.abs(solutions[0]).max())


def test_unknown_backend_is_refused():
    mesh = MeshTet.init_tensor(*[np.linspace(0, 1, 2)] * 3)
    model = assemble_elastic_model(mesh, 1.0, 0.3)
    with pytest.raises(ValueError, match="backend='cholmod' is not one of"):
        SpdFactorization(model.stiffness_free, "cholmod")
