"""Compressible Neo-Hookean gel, total Lagrangian: stress, tangent modulus, nodal internal forces, tangent stiffness.

Strain energy per unit reference volume, the form CalculiX and Abaqus call NEO HOOKE:

    W = G/2 (J^(-2/3) I1 - 3) + K/2 (J - 1)^2,     F = I + grad u,  J = det F,  I1 = F : F,

with the shear modulus G and the bulk modulus K = E / (3 (1 - 2 nu)) of the linear gel, so that at small strain it
is the linear gel (C10 = G/2, D1 = 2/K in CalculiX's notation). First Piola-Kirchhoff stress:

    P = dW/dF = G J^(-2/3) (F - I1/3 F^-T) + K (J - 1) J F^-T.

Its directional derivative in the direction H = grad du (the tangent modulus A = dP/dF, ``tangent_modulus``):

    dP = G J^(-2/3) [H - 2/3 (F^-T : H) (F - I1/3 F^-T) - 2/3 (F : H) F^-T + I1/3 F^-T H^T F^-T]
         + K J [(2 J - 1) (F^-T : H) F^-T - (J - 1) F^-T H^T F^-T].

``contact._finite_strain`` solves the contact of this gel by Newton's method with the internal force and the
tangent stiffness assembled here. Tests: the internal force is the linear gel's to second order in u, and the
tangent stiffness is the internal force's derivative (central differences).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from skfem import LinearForm, asm
from skfem.helpers import ddot, det, grad, identity, inv, transpose

from fem.elasticity import ElasticModel, lame_parameters

__all__ = ["InvertedElement", "neo_hookean_stress", "tangent_modulus", "displacement_gradient", "internal_force",
           "tangent_stiffness", "bulk_modulus"]


def bulk_modulus(youngs_modulus: float, poissons_ratio: float) -> float:
    """K = lambda + 2 G / 3 [MPa]."""
    lame_lambda, shear_modulus = lame_parameters(youngs_modulus, poissons_ratio)
    return lame_lambda + 2.0 * shear_modulus / 3.0


def neo_hookean_stress(gradient: np.ndarray, shear_modulus: float, bulk: float) -> np.ndarray:
    """First Piola-Kirchhoff stress P [MPa] for displacement gradients (3, 3, ...)."""
    deformation = identity(gradient) + gradient
    jacobian = det(deformation)
    inverse_transpose = transpose(inv(deformation))
    first_invariant = ddot(deformation, deformation)
    return (shear_modulus * jacobian ** (-2.0 / 3.0) * (deformation - first_invariant / 3.0 * inverse_transpose)
            + bulk * (jacobian - 1.0) * jacobian * inverse_transpose)


def tangent_modulus(gradient: np.ndarray, shear_modulus: float, bulk: float) -> np.ndarray:
    """A = dP/dF [MPa], (3, 3, 3, 3, ...) with A[i, j, k, l] = dP_ij / dF_kl, for displacement gradients (3, 3, ...)."""
    deformation = identity(gradient) + gradient
    jacobian = det(deformation)
    f_inv_t = transpose(inv(deformation))
    first_invariant = ddot(deformation, deformation)
    deviatoric = deformation - first_invariant / 3.0 * f_inv_t
    scale = shear_modulus * jacobian ** (-2.0 / 3.0)
    modulus = np.empty((3, 3) + deformation.shape)
    for k in range(3):
        for m in range(3):
            # H = e_k (x) e_m: F^-T : H = F^-T[k, m], F : H = F[k, m], (F^-T H^T F^-T)_ij = F^-T[i, m] F^-T[k, j]
            swapped = np.einsum("i...,j...->ij...", f_inv_t[:, m], f_inv_t[k, :])
            unit = np.zeros_like(deformation)
            unit[k, m] = 1.0
            modulus[:, :, k, m] = (
                scale * (unit - 2.0 / 3.0 * f_inv_t[k, m] * deviatoric - 2.0 / 3.0 * deformation[k, m] * f_inv_t
                         + first_invariant / 3.0 * swapped)
                + bulk * jacobian * ((2.0 * jacobian - 1.0) * f_inv_t[k, m] * f_inv_t - (jacobian - 1.0) * swapped))
    return modulus


def _assemble_tangent(basis, modulus: np.ndarray, dofs: np.ndarray) -> sp.coo_matrix:
    """int grad v : A : grad u dV [N/mm] on the dofs ``dofs`` (in their order; duplicates not summed), A (3, 3, 3, 3,
    elements, points) at the quadrature points.

    Written on skfem's basis data rather than as a BilinearForm: a form evaluates A : grad u once per pair of local
    basis functions (144 for vector P1), contracting the 81 moduli each time, and took 8 of 10 s of a bump's press;
    here A : grad phi_i is formed once per basis function and each pair is a 9-term product."""
    shape = modulus.shape[4:]
    flat = modulus.reshape((9, 9) + shape)
    grads = [phi[0].grad.reshape((9,) + shape) for phi in basis.basis]
    stressed = [(flat * g[None]).sum(axis=1) for g in grads]                    # A : grad phi_i, (9, elements, points)
    count = len(grads)
    data = np.empty((count, count, shape[0]))
    for i in range(count):
        for j in range(count):
            data[j, i] = ((grads[j] * stressed[i]).sum(axis=0) * basis.dx).sum(axis=-1)
    position = np.full(basis.N, -1)
    position[dofs] = np.arange(dofs.size)
    local = position[basis.element_dofs]                                        # (count, elements), -1: left out
    rows = np.broadcast_to(local[:, None, :], data.shape).ravel()
    cols = np.broadcast_to(local[None, :, :], data.shape).ravel()
    kept = (rows >= 0) & (cols >= 0)
    return sp.coo_matrix((data.ravel()[kept], (rows[kept], cols[kept])), shape=(dofs.size, dofs.size))


@LinearForm
def _internal_work(v, w):
    """int P : grad v dV over the reference volume [N mm], P given at the quadrature points."""
    return ddot(w["stress"], grad(v))


class InvertedElement(ValueError):
    """A displacement turns an element inside out (det F <= 0), where the Neo-Hookean energy is not defined."""

    def __init__(self, smallest: float):
        super().__init__(f"an element of the finite-strain gel turned inside out (det F = {smallest:.3g} <= 0)")
        self.smallest = smallest


def displacement_gradient(model: ElasticModel, displacement: np.ndarray) -> np.ndarray:
    """grad u (3, 3, elements, points) at the quadrature points for a displacement on every dof [mm]; InvertedElement
    where det F <= 0 anywhere. ``internal_force`` and ``tangent_stiffness`` take it, so that a Newton iteration
    interpolates its iterate once."""
    gradient = model.basis.interpolate(displacement).grad
    smallest = float(det(identity(gradient) + gradient).min())
    if smallest <= 0.0:
        raise InvertedElement(smallest)
    return gradient


def internal_force(model: ElasticModel, gradient: np.ndarray, youngs_modulus: float,
                   poissons_ratio: float) -> np.ndarray:
    """Nodal internal forces f_int(u) [N] of the Neo-Hookean gel on every dof, for u's ``displacement_gradient``."""
    shear_modulus = lame_parameters(youngs_modulus, poissons_ratio)[1]
    # the stress once per quadrature point, not once per test function as a form evaluating it would
    stress = neo_hookean_stress(gradient, shear_modulus, bulk_modulus(youngs_modulus, poissons_ratio))
    return asm(_internal_work, model.basis, stress=stress)


def tangent_stiffness(model: ElasticModel, gradient: np.ndarray, youngs_modulus: float, poissons_ratio: float,
                      dofs: np.ndarray | None = None) -> sp.coo_matrix:
    """The tangent stiffness df_int/du [N/mm] between the dofs ``dofs`` (default all; COO, duplicates not summed), for
    u's ``displacement_gradient``."""
    shear_modulus = lame_parameters(youngs_modulus, poissons_ratio)[1]
    modulus = tangent_modulus(gradient, shear_modulus, bulk_modulus(youngs_modulus, poissons_ratio))
    return _assemble_tangent(model.basis, modulus, np.arange(model.n_dofs) if dofs is None else np.asarray(dofs))
