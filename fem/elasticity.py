"""Linear elasticity on tetrahedra (P1, P2): stiffness, fixed base, top-surface contact points and base traction.

Volumetric term: ``standard`` integrates lambda tr(eps) tr(eps) per element; ``nodal_average`` (P1 only) is the
average-nodal-pressure tetrahedron of Bonet & Burton (Commun. Numer. Meth. Eng. 14, 1998, 437-449), which does
not lock for nu -> 0.5.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from skfem import Basis, BilinearForm, ElementTetP1, ElementTetP2, ElementVector, LinearForm, asm
from skfem.helpers import ddot, div, sym_grad, trace

from fem.validation import check_choice, check_positive, check_range

__all__ = ["ElasticModel", "SaddlePointBlocks", "SurfacePoints", "VOLUMETRIC_FORMULATIONS", "assemble_elastic_model",
           "assemble_stiffness", "divergence_pairing", "elastic_stiffness", "lame_parameters",
           "nodal_average_volumetric_stiffness", "nodal_volume"]

VOLUMETRIC_FORMULATIONS = ("standard", "nodal_average")


def lame_parameters(youngs_modulus: float, poissons_ratio: float) -> tuple[float, float]:
    """Lame lambda and shear modulus G [MPa] from E [MPa] and nu."""
    check_positive("youngs_modulus", youngs_modulus, "MPa")
    check_range("poissons_ratio", poissons_ratio, -1.0, 0.5, low_open=True, high_open=True)
    shear_modulus = youngs_modulus / (2.0 * (1.0 + poissons_ratio))
    lame_lambda = youngs_modulus * poissons_ratio / ((1.0 + poissons_ratio) * (1.0 - 2.0 * poissons_ratio))
    return lame_lambda, shear_modulus


@BilinearForm
def elastic_stiffness(u, v, p):
    """a(u, v) = int sigma(eps(u)) : eps(v) dV, sigma = 2 G eps + lambda tr(eps) I  [N mm]."""
    eps_u, eps_v = sym_grad(u), sym_grad(v)
    return 2.0 * p["shear_modulus"] * ddot(eps_u, eps_v) + p["lame_lambda"] * trace(eps_u) * trace(eps_v)


@BilinearForm
def divergence_pairing(u, q, p):
    """b(u, q) = int q div(u) dV: vector displacement u against a scalar pressure test function q; B entries [mm^2]."""
    return div(u) * q


@LinearForm
def nodal_volume(q, p):
    """V_n = int phi_n dV, the lumped (row-sum) P1 mass: the volume a node carries [mm^3]."""
    return q


def _pairing_and_nodal_volumes(basis: Basis) -> tuple[sp.csr_matrix, np.ndarray]:
    """B [mm^2] (n_vertices, n_dofs) of ``divergence_pairing`` and the nodal volumes V_n [mm^3] (n_vertices,)."""
    pressure_basis = basis.with_element(ElementTetP1())                  # same quadrature as ``basis``
    return asm(divergence_pairing, basis, pressure_basis).tocsr(), asm(nodal_volume, pressure_basis)


def nodal_average_volumetric_stiffness(basis: Basis, lame_lambda: float) -> sp.csr_matrix:
    """Volumetric stiffness B^T diag(lambda / V_n) B [N/mm] of the average-nodal-pressure tetrahedron.

    It is the P1-P1 mixed u-p form (pressure p_n at the vertices, M p = lambda B u) with the pressure mass M
    lumped to diag(V_n) and p condensed: p_n = lambda (B u)_n / V_n, the volume-weighted mean of lambda div(u) over
    the tets around node n (Bonet & Burton 1998). Exact for uniform volumetric strain: div(u) = theta gives
    (B u)_n = theta V_n, so p = lambda theta everywhere and, as sum_n phi_n = 1, the pairing with any test field
    equals the standard int lambda theta div(v) dV. Why it does not lock: the standard P1 form penalises div(u)
    in every tet, about 5 constraints per node (4.6-5.3 tets per node on the graded block meshes) against 3
    displacement dofs, so as lambda -> inf almost no displacement field is left free; here there is one
    constraint per node. Being lambda / V_n >= 0 times B^T B it is symmetric positive semi-definite, so
    2 G eps:eps + this stays SPD.

    Cost: B^T B couples second neighbours, so this condensed K has 5x the nonzeros of P1 K and its factor 5x the
    fill, with factorization 3.5-4.5x and 256 back-substitutions 3x slower. The contact solver therefore never
    factorizes it: it factorizes the uncondensed saddle-point system [[K_G, B^T], [B, -diag(V_n / lambda)]]
    (``ElasticModel.saddle_point``, ``fem.linear_solver.SaddlePointFactorization``): factor 1.9x the fill of P1
    (3/8 of the condensed one), factorization 2x P1, 256 back-substitutions 0.7x P1 (no iterative refinement;
    measured on the 26k-DOF stability block at nu = 0.4999: ``python -m studies benchmark --factorizations``).
    This condensed K stays the model's stiffness for base reactions, energies and tests.
    """
    pairing, volumes = _pairing_and_nodal_volumes(basis)
    return (pairing.T @ sp.diags(lame_lambda / volumes) @ pairing).tocsr()


@dataclass
class SaddlePointBlocks:
    """The mixed u-p system whose pressure condensation is the nodal-average K on the free dofs.

    [[K_G, B^T], [B, -diag(V_n / lambda)]] [u; p] = [f; 0] gives p = lambda B u / V_n and
    (K_G + B^T diag(lambda / V_n) B) u = f, i.e. ``stiffness_free`` u = f.
    """

    shear_stiffness: sp.csr_matrix       # K_G = 2 G eps:eps on the free dofs [N/mm], (n_free, n_free), SPD
    pairing: sp.csr_matrix               # B on all vertices x free dofs [mm^2], (n_vertices, n_free)
    pressure_compliance: np.ndarray      # V_n / lambda [mm^3/MPa], (n_vertices,), > 0


@dataclass
class SurfacePoints:
    """Nodes of a flat face: positions (n, 3) [mm], dof indices (n, 3) into the full vector, tributary areas [mm^2].

    ``patches`` (P2 only): sparse (n, n_facets) share of each point's tributary area in each mesh facet, from which
    ``pressure`` recovers a nodal pressure that is exact for uniform pressure (see there).
    """

    positions: np.ndarray
    dofs: np.ndarray
    areas: np.ndarray
    triangles: np.ndarray      # (n_tri, 3) indices into positions: the face split into flat triangles
    patches: sp.csr_matrix | None = None

    def pressure(self, points: np.ndarray, normal_forces: np.ndarray) -> np.ndarray:
        """Nodal pressure [MPa] at ``points`` (indices) from their normal forces [N] (0 elsewhere).

        P1: force / tributary area. P2: the forces that balance a uniform pressure p are the consistent ones,
        p A/3 on each edge midpoint of a facet of area A and none on its vertices, while the four-triangle split
        gives a midpoint A/4 and a vertex A/12: force / area would read 4/3 p and 0. So each facet's pressure is
        taken as the force its points put on it (each point's force shared in proportion to its area in the
        facet) over its area, and a point's pressure as that of the facets around it, area-weighted: p exactly
        for a uniform p, on vertices and midpoints alike. Points without force read 0, unless every facet around
        them is loaded (P2 vertices inside the contact carry almost no force).
        """
        if self.patches is None:
            return normal_forces / self.areas[points]
        forces = np.zeros(self.areas.size)
        forces[points] = normal_forces
        share = self.patches.multiply(1.0 / self.areas[:, None]).tocsr()         # (n, n_facets) area fractions
        facet_force = share.T @ forces                                           # (n_facets,)
        facet_area = np.asarray(self.patches.sum(axis=0)).ravel()
        touching = (self.patches[points] > 0).astype(float)                      # (k, n_facets)
        pressure = (touching @ facet_force) / (touching @ facet_area)
        loaded_facets = touching @ (facet_force > 0.0)                          # (k,) facets with force
        inside = loaded_facets == np.asarray(touching.sum(axis=1)).ravel()     # every facet around is loaded
        return np.where((normal_forces > 0.0) | inside, pressure, 0.0)


@dataclass
class ElasticModel:
    """Assembled gel: stiffness on the free dofs, with the base (z = min) bonded."""

    mesh: object
    basis: Basis
    order: int
    volumetric: str                    # "standard" or "nodal_average" (VOLUMETRIC_FORMULATIONS)
    stiffness_free: sp.csr_matrix      # K restricted to free dofs
    stiffness_fixed_free: sp.csr_matrix  # rows: base dofs, cols: free dofs (for base reactions)
    free_dofs: np.ndarray
    fixed_dofs: np.ndarray
    top: SurfacePoints                 # contact side: upward-facing boundary (z = 0 for a block)
    base: SurfacePoints                # sensor plane, z = -thickness
    # nodal_average with lambda > 0 only: the uncondensed blocks of stiffness_free, which the contact solver
    # factorizes instead of the denser condensed K (fem.linear_solver.SaddlePointFactorization)
    saddle_point: SaddlePointBlocks | None = None

    @property
    def n_dofs(self) -> int:
        return self.basis.N

    def full_vector(self, free_values: np.ndarray) -> np.ndarray:
        """Scatter free-dof values (n_free,) or (n_free, k) into a full dof vector with zeros on the base."""
        shape = (self.basis.N,) + np.shape(free_values)[1:]
        full = np.zeros(shape)
        full[self.free_dofs] = free_values
        return full


def _boundary_facet_normals(mesh) -> tuple[np.ndarray, np.ndarray]:
    """Boundary facet ids and their outward unit normals (n_facets, 3)."""
    boundary = mesh.boundary_facets()
    corners = mesh.p[:, mesh.facets[:, boundary]]                       # (3, 3, n_facets)
    normals = np.cross((corners[:, 1] - corners[:, 0]).T, (corners[:, 2] - corners[:, 0]).T)
    tets = mesh.t[:, mesh.f2t[0, boundary]]                             # (4, n_facets)
    inner_vertex = mesh.p[:, tets].sum(axis=1) - corners.sum(axis=1)    # the tet vertex off the facet
    inward = np.einsum("ij,ij->i", normals, (inner_vertex - corners[:, 0]).T) > 0.0
    normals[inward] *= -1.0
    return boundary, normals / np.linalg.norm(normals, axis=1, keepdims=True)


def _face_points(basis: Basis, order: int, face_facets: np.ndarray) -> SurfacePoints:
    """Nodal points of a set of boundary facets, with tributary areas from a flat sub-triangulation."""
    mesh = basis.mesh
    vertex_tri = mesh.facets[:, face_facets].T                          # (n_tri, 3) vertex ids
    component_dofs = basis.nodal_dofs                                   # (3, n_vertices)
    if order == 1:
        triangles_global = vertex_tri
        point_ids = np.unique(vertex_tri)
        dof_table = component_dofs[:, point_ids].T                      # (n, 3)
        xyz = mesh.p[:, point_ids].T
    else:
        # P2: vertices and edge midpoints; each facet is split into 4 flat triangles so that every
        # quadratic node gets a positive tributary area (P2 vertex weights of the exact rule are zero).
        n_vertices = mesh.p.shape[1]
        edge_ids = mesh.f2e[:, face_facets].T                           # (n_tri, 3), order matched below
        edge_nodes = mesh.edges[:, edge_ids]                            # (2, n_tri, 3)
        mid = n_vertices + edge_ids                                     # pseudo ids for midpoints

        def midpoint(i, j):
            pair = np.sort(np.stack([vertex_tri[:, i], vertex_tri[:, j]]), axis=0)
            match = np.all(np.sort(edge_nodes, axis=0) == pair[:, :, None], axis=0)   # (n_tri, 3)
            return mid[np.arange(len(vertex_tri)), match.argmax(axis=1)]

        m01, m02, m12 = midpoint(0, 1), midpoint(0, 2), midpoint(1, 2)
        v0, v1, v2 = vertex_tri.T
        triangles_global = np.concatenate([np.stack(t, axis=1) for t in (
            (v0, m01, m02), (m01, v1, m12), (m02, m12, v2), (m01, m12, m02))])
        point_ids = np.unique(triangles_global)
        is_vertex = point_ids < n_vertices
        dof_table = np.empty((point_ids.size, 3), dtype=np.int64)
        dof_table[is_vertex] = component_dofs[:, point_ids[is_vertex]].T
        dof_table[~is_vertex] = basis.edge_dofs[:, point_ids[~is_vertex] - n_vertices].T
        xyz = np.empty((point_ids.size, 3))
        xyz[is_vertex] = mesh.p[:, point_ids[is_vertex]].T
        xyz[~is_vertex] = mesh.p[:, mesh.edges[:, point_ids[~is_vertex] - n_vertices]].mean(axis=1).T
    local = np.searchsorted(point_ids, triangles_global)
    corners = xyz[local]                                                # (n_tri, 3, 3)
    tri_area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    areas = np.bincount(local.ravel(), weights=np.repeat(tri_area / 3.0, 3), minlength=point_ids.size)
    patches = None
    if order != 1:                            # sub-triangle k of the 4 belongs to facet k mod n_facets
        facet = np.tile(np.arange(len(vertex_tri)), 4)
        patches = sp.coo_matrix((np.repeat(tri_area / 3.0, 3), (local.ravel(), np.repeat(facet, 3))),
                                shape=(point_ids.size, len(vertex_tri))).tocsr()
    return SurfacePoints(positions=xyz, dofs=dof_table, areas=areas, triangles=local, patches=patches)


def _assemble(basis: Basis, youngs_modulus: float, poissons_ratio: float, volumetric: str):
    """K [N/mm] on every dof and, for nodal_average, its parts (K_G [N/mm], B [mm^2], V_n [mm^3], lambda [MPa])."""
    check_choice("volumetric", volumetric, VOLUMETRIC_FORMULATIONS)
    scalar_element = type(getattr(basis.elem, "elem", basis.elem))
    if volumetric == "nodal_average" and scalar_element is not ElementTetP1:
        # P2 with vertex pressures (lumped Taylor-Hood) is locking-free too, but B^T B couples every P2 dof with
        # the stars of the neighbouring vertices: measured 10x the nonzeros and 15x the factorization time of P2
        raise ValueError(f"volumetric={volumetric!r} needs P1 tets (ElementTetP1), got {scalar_element.__name__}")
    lame_lambda, shear_modulus = lame_parameters(youngs_modulus, poissons_ratio)
    if volumetric == "standard":
        return asm(elastic_stiffness, basis, lame_lambda=lame_lambda, shear_modulus=shear_modulus).tocsr(), None
    shear_stiffness = asm(elastic_stiffness, basis, lame_lambda=0.0, shear_modulus=shear_modulus).tocsr()
    pairing, volumes = _pairing_and_nodal_volumes(basis)
    stiffness = (shear_stiffness + pairing.T @ sp.diags(lame_lambda / volumes) @ pairing).tocsr()
    return stiffness, (shear_stiffness, pairing, volumes, lame_lambda)


def assemble_stiffness(basis: Basis, youngs_modulus: float, poissons_ratio: float,
                       volumetric: str = "standard") -> sp.csr_matrix:
    """K [N/mm] on every dof of a vector P1/P2 basis, with the chosen volumetric term (no boundary conditions)."""
    return _assemble(basis, youngs_modulus, poissons_ratio, volumetric)[0]


def assemble_elastic_model(mesh, youngs_modulus: float, poissons_ratio: float, order: int = 1,
                           symmetry_plane_y: float | None = None, volumetric: str = "standard") -> ElasticModel:
    """Assemble K [N/mm] for P1 or P2 tets; the base (lowest z) is fixed, the top (z = 0) is the contact side.

    With ``symmetry_plane_y`` the mesh is half of a mirror-symmetric body: u_y = 0 on that plane.
    ``volumetric="nodal_average"`` (P1 only) replaces the element-wise lambda term by the locking-free
    average-nodal-pressure one (``nodal_average_volumetric_stiffness``).
    """
    check_choice("order", order, (1, 2))
    element = ElementVector(ElementTetP1() if order == 1 else ElementTetP2())
    basis = Basis(mesh, element, intorder=2 * (order - 1) if order > 1 else 1)
    stiffness, parts = _assemble(basis, youngs_modulus, poissons_ratio, volumetric)
    z_base = float(mesh.p[2].min())
    tol = 1e-9 * max(1.0, float(np.ptp(mesh.p)))
    fixed = basis.get_dofs(lambda x: np.abs(x[2] - z_base) < tol).all()
    if symmetry_plane_y is not None:
        mirror = basis.get_dofs(lambda x: np.abs(x[1] - symmetry_plane_y) < tol).all()
        mirror_y = mirror[np.isin(mirror, basis.nodal_dofs[1]) | (np.isin(mirror, basis.edge_dofs[1])
                                                                  if order == 2 else False)]
        fixed = np.union1d(fixed, mirror_y)
    free = np.setdiff1d(np.arange(basis.N), fixed)
    boundary, normals = _boundary_facet_normals(mesh)
    on_base = np.all(np.abs(mesh.p[2, mesh.facets[:, boundary]] - z_base) < tol, axis=0)
    # the contact side: every boundary facet facing up (n_z > 0.25, i.e. slopes below 75 deg) off the base; for a
    # block that is its top face, for caps and bump arrays the whole upper surface
    top = _face_points(basis, order, boundary[~on_base & (normals[:, 2] > 0.25)])
    base = _face_points(basis, order, boundary[on_base])
    saddle_point = None
    if parts is not None and parts[3] > 0.0:
        # every pressure node is kept, base and mirror-plane ones too: p_n = lambda (B u)_n / V_n holds at each node
        # whatever u is fixed, and stiffness_free below is K_G,ff + B_f^T diag(lambda / V_n) B_f summed over all n.
        # lambda <= 0 (nu <= 0) has no finite V_n / lambda > 0: the condensed K is factorized as before
        shear_stiffness, pairing, volumes, lame_lambda = parts
        saddle_point = SaddlePointBlocks(shear_stiffness=shear_stiffness[free][:, free].tocsr(),
                                         pairing=pairing[:, free].tocsr(), pressure_compliance=volumes / lame_lambda)
    return ElasticModel(
        mesh=mesh, basis=basis, order=order, volumetric=volumetric,
        stiffness_free=stiffness[free][:, free].tocsr(),
        stiffness_fixed_free=stiffness[fixed][:, free].tocsr(),
        free_dofs=free, fixed_dofs=fixed, top=top, base=base, saddle_point=saddle_point,
    )
