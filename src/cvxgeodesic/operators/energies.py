"""The three smoothness energies of the paper, as quadratic forms ``E(d) = dᵀ Q d``."""

from __future__ import annotations

import warnings

import igl
import numpy as np
import scipy.sparse as sp

from ..errors import IndefiniteEnergyWarning
from ..linalg import is_positive_semidefinite
from ..mesh.cover import manifold_cover, pull_back
from ..mesh.trimesh import TriMesh
from .laplacian import cotan_stiffness, mass_matrix

ENERGIES = ("dirichlet", "laplacian", "hessian")


def dirichlet_energy_matrix(mesh: TriMesh) -> sp.csc_matrix:
    """Area-normalized Dirichlet energy (paper eq. 16).

    ``E(d) = Σ_t A_t ‖∇d|_t‖² / Σ_t A_t = dᵀ Q d`` with ``Q = S / area``.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    return sp.csc_matrix(cotan_stiffness(mesh) / mesh.face_areas.sum())


def laplacian_energy_matrix(mesh: TriMesh) -> sp.csc_matrix:
    """Squared-Laplacian energy (paper eq. 17): ``Q = S M⁻¹ S``.

    ``S`` is the cotangent stiffness matrix and ``M`` the mixed-Voronoi mass.
    Vertices with zero mass (unreferenced) get no contribution.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    S = cotan_stiffness(mesh)
    mass = mass_matrix(mesh).diagonal()
    inv = np.zeros_like(mass)
    np.divide(1.0, mass, out=inv, where=mass > 0)
    Q = S @ sp.diags(inv) @ S
    return sp.csc_matrix(0.5 * (Q + Q.T))


def hessian_energy_matrix(mesh: TriMesh, notes: list[str] | None = None) -> sp.csc_matrix:
    """Curved-surface Hessian energy (paper eq. 18; Stein et al. TOG 2020) via libigl.

    ``E(d) = dᵀ Q d ≈ ∫ ‖Hess d‖² dA``. It vanishes on functions linear on a
    flat mesh and, unlike the planar Hessian energy, has no boundary bias.

    The discretization uses edge (Crouzeix–Raviart) elements and needs an
    edge-manifold mesh. On a mesh with an edge of more than two faces the
    energy is built on :func:`~cvxgeodesic.mesh.cover.manifold_cover` (the mesh
    cut along its non-manifold edges, each sheet a surface with that edge on its
    boundary) and pulled back to the mesh's vertices.

    Parameters
    ----------
    mesh : TriMesh
    notes : list of str, optional
        Gets one line per substitution made (manifold cover, planar energy).

    Warns
    -----
    IndefiniteEnergyWarning
        The curved energy has a negative eigenvalue on this mesh (checked with one
        PARDISO or CHOLMOD factorization; skipped without either): the planar
        Hessian energy of Stein et al. 2018 (libigl ``hessian_energy``), which is
        PSD, is returned instead.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    notes = [] if notes is None else notes
    energy_mesh, to_mesh = mesh, None
    if not mesh.is_edge_manifold:
        bad = int(np.sum(mesh.edge_face_counts > 2))
        energy_mesh, to_mesh = manifold_cover(mesh)
        notes.append(f"{mesh.name}: {bad} non-manifold edge(s); the Hessian energy is built on the mesh cut along "
                     f"them ({energy_mesh.n_vertices} vertices instead of {int(mesh.referenced.sum())})")
        if not energy_mesh.is_edge_manifold:  # a sheet that closes up around a vertex of a non-manifold edge
            keep = ~(energy_mesh.edge_face_counts[energy_mesh.face_edges] > 2).any(axis=1)
            notes.append(f"{mesh.name}: {int((~keep).sum())} face(s) whose non-manifold edge the cut cannot open "
                         "carry no Hessian energy")
            energy_mesh = TriMesh(energy_mesh.V, energy_mesh.F[keep], name=energy_mesh.name)
    n = energy_mesh.n_vertices
    Q = _padded_symmetric(igl.curved_hessian_energy(energy_mesh.V, energy_mesh.F), n)
    if is_positive_semidefinite(Q) is False:
        # measured: lucy_20k and thingi_37881 (min eigenvalue -59 against a largest diagonal of 1.2e7); the
        # curvature correction of the curved energy is not PSD where the angle defect is large, and the QP would
        # then be non-convex. The planar Hessian energy (Stein et al. 2018) is PSD by construction.
        message = (f"{mesh.name}: libigl's curved Hessian energy is indefinite on this mesh (sharp corners or large "
                   "angle defects); using the planar Hessian energy (Stein et al. 2018) instead")
        warnings.warn(message, IndefiniteEnergyWarning, stacklevel=3)
        notes.append(message)
        Q = _padded_symmetric(igl.hessian_energy(energy_mesh.V, energy_mesh.F), n)
    return Q if to_mesh is None else pull_back(Q, to_mesh, mesh.n_vertices)


def _padded_symmetric(Q, n: int) -> sp.csc_matrix:
    """Symmetrized (n, n) copy; libigl sizes its matrices by the largest referenced vertex index + 1."""
    Q = sp.coo_matrix(Q)
    Q = sp.csc_matrix((Q.data, (Q.row, Q.col)), shape=(n, n))
    return sp.csc_matrix(0.5 * (Q + Q.T))


def energy_matrix(mesh: TriMesh, energy: str, notes: list[str] | None = None) -> sp.csc_matrix:
    """The matrix of a named energy (``"dirichlet"``, ``"laplacian"`` or ``"hessian"``).

    ``notes`` (optional list) gets one line per substitution made while building it.
    """
    if energy == "hessian":
        return hessian_energy_matrix(mesh, notes)
    return {"dirichlet": dirichlet_energy_matrix, "laplacian": laplacian_energy_matrix}[energy](mesh)
