"""Cotangent stiffness and lumped mass matrices (libigl)."""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp

from ..mesh.trimesh import TriMesh


def cotan_stiffness(mesh: TriMesh) -> sp.csc_matrix:
    """Positive semidefinite cotangent Laplacian ``S = Σ_t A_t G_tᵀ G_t``.

    Sign convention: ``dᵀ S d = Σ_t A_t ‖∇d|_t‖²`` (libigl's ``cotmatrix`` is ``-S``).
    Works on non-manifold meshes (it is a sum over triangles).

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix
    """
    return sp.csc_matrix(-igl.cotmatrix(mesh.V, mesh.F))


def mass_matrix(mesh: TriMesh) -> sp.dia_matrix:
    """Mixed-Voronoi lumped mass matrix (Meyer et al. 2003), diagonal.

    The diagonal sums to the total surface area. Unreferenced vertices get 0.

    Returns
    -------
    (n, n) scipy.sparse.dia_matrix
    """
    M = igl.massmatrix(mesh.V, mesh.F, igl.MASSMATRIX_TYPE_VORONOI)
    diag = np.zeros(mesh.n_vertices)
    m = np.asarray(M.diagonal()).ravel()  # libigl sizes it by the largest referenced index + 1
    diag[: m.size] = m
    return sp.diags(diag)
