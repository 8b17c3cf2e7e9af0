"""Stiffness, lumped mass and divergence of piecewise-linear fields on triangles and tetrahedra.

On triangles the stiffness and the mixed-Voronoi mass are libigl's (``cotmatrix``, ``massmatrix``); on tetrahedra,
and on any subset of cells, they are assembled from the gradient blocks (:func:`~.gradient.gradient_blocks`):
``L = Σ_t |t| B_tᵀ B_t`` (``dᵀ L d = Σ_t |t| ‖∇d|_t‖²``), the same matrix as the cotangent formula (in 3-D
``L_ij = −(1/6) Σ ℓ_kl cot θ_kl`` over the tetrahedra of edge ``ij``, ``ℓ_kl``, ``θ_kl`` the length and dihedral
angle of the opposite edge). Cells of zero measure have no gradient; the assembled matrices leave them out unless
told otherwise (``cells=``).
"""

from __future__ import annotations

import igl
import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..mesh.simplex import SimplexMesh
from .gradient import gradient_blocks

__all__ = ["barycentric_mass", "cotan_stiffness", "divergence", "mass_matrix", "selected_cells"]


def selected_cells(mesh: SimplexMesh, cells: ArrayLike | None) -> np.ndarray:
    """Indices of the cells to assemble: ``cells`` (indices or a (k,) mask), or every one of nonzero measure.

    Raises
    ------
    ValueError
        A mask of the wrong shape or an index out of range.
    """
    if cells is None:
        return np.flatnonzero(mesh.cell_measures > 0)
    sel = np.asarray(cells)
    if sel.dtype == bool:
        if sel.shape != (mesh.n_cells,):
            raise ValueError(f"cells: a mask must have shape ({mesh.n_cells},), got {sel.shape}")
        return np.flatnonzero(sel)
    sel = sel.astype(np.int64).reshape(-1)
    if sel.size and (sel.min() < 0 or sel.max() >= mesh.n_cells):
        raise ValueError(f"cells: indices must lie in [0, {mesh.n_cells})")
    return sel


def cotan_stiffness(mesh: SimplexMesh, *, cells: ArrayLike | None = None,
                    blocks: np.ndarray | None = None) -> sp.csc_matrix:
    """Positive semidefinite cotangent Laplacian ``S = Σ_t |t| B_tᵀ B_t``.

    Sign convention: ``dᵀ S d = Σ_t |t| ‖∇d|_t‖²`` (libigl's ``cotmatrix`` is ``-S``); ``S 1 = 0``. A sum over
    cells, so non-manifold meshes work.

    Parameters
    ----------
    mesh : SimplexMesh
    cells : (s,) int or (k,) bool array_like, optional
        Cells to assemble; default every cell (triangles: libigl's ``cotmatrix``) or every tetrahedron of nonzero
        volume.
    blocks : (k, dim, dim + 1) float ndarray, optional
        Precomputed :func:`~.gradient.gradient_blocks`.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix
    """
    if mesh.reference.libigl_operators and cells is None and blocks is None:
        return sp.csc_matrix(-igl.cotmatrix(mesh.V, mesh.cells))
    sel = selected_cells(mesh, cells)
    B = (gradient_blocks(mesh) if blocks is None else blocks)[sel]
    K = mesh.cell_measures[sel, None, None] * np.einsum("tki,tkj->tij", B, B)  # (s, dim+1, dim+1)
    C, w = mesh.cells[sel], mesh.dim + 1
    rows = np.repeat(C, w, axis=1).ravel()
    cols = np.tile(C, (1, w)).ravel()
    L = sp.csc_matrix((K.ravel(), (rows, cols)), shape=(mesh.n_vertices, mesh.n_vertices))
    return sp.csc_matrix(0.5 * (L + L.T))


def barycentric_mass(mesh: SimplexMesh, *, cells: ArrayLike | None = None) -> sp.dia_matrix:
    """Lumped (barycentric) mass: each vertex gets ``1 / (dim + 1)`` of the measure of each of its cells.

    Parameters
    ----------
    mesh : SimplexMesh
    cells : (s,) int or (k,) bool array_like, optional
        Cells to assemble; default every cell of nonzero measure.

    Returns
    -------
    (n, n) scipy.sparse.dia_matrix
        Its diagonal sums to the measure of the assembled cells; vertices in none get 0.
    """
    sel = selected_cells(mesh, cells)
    w = mesh.dim + 1
    mass = np.zeros(mesh.n_vertices)
    np.add.at(mass, mesh.cells[sel].ravel(), np.repeat(mesh.cell_measures[sel] / w, w))
    return sp.diags(mass)


def mass_matrix(mesh: SimplexMesh) -> sp.dia_matrix:
    """Lumped mass matrix, diagonal: mixed-Voronoi on triangles (Meyer et al. 2003, libigl), barycentric on
    tetrahedra (:func:`barycentric_mass`).

    The diagonal sums to the total area (volume). Unreferenced vertices get 0.

    Returns
    -------
    (n, n) scipy.sparse.dia_matrix
    """
    if not mesh.reference.libigl_operators:
        return barycentric_mass(mesh)
    M = igl.massmatrix(mesh.V, mesh.cells, igl.MASSMATRIX_TYPE_VORONOI)
    diag = np.zeros(mesh.n_vertices)
    m = np.asarray(M.diagonal()).ravel()  # libigl sizes it by the largest referenced index + 1
    diag[: m.size] = m
    return sp.diags(diag)


def divergence(mesh: SimplexMesh, X: ArrayLike, *, cells: ArrayLike | None = None,
               blocks: np.ndarray | None = None) -> np.ndarray:
    """Integrated divergence of a per-cell vector field, ``Gᵀ diag(|t|) X``, one value per vertex.

    The weak form ``Σ_t |t| X_t · ∇λ_i`` for vertex ``i``, so that ``S φ = divergence(X)`` is the Poisson equation
    whose solution has the gradient closest to ``X`` (least squares, measure-weighted). Sign: this is
    ``−∫ (div X) λ_i`` plus the boundary flux.

    Parameters
    ----------
    mesh : SimplexMesh
    X : (k, dim) float array_like
        One vector per cell, in the frame of the gradient blocks (world coordinates on tetrahedra).
    cells : (s,) int or (k,) bool array_like, optional
        Cells to assemble; default every cell of nonzero measure.
    blocks : (k, dim, dim + 1) float ndarray, optional

    Returns
    -------
    (n,) float ndarray
    """
    sel = selected_cells(mesh, cells)
    B = (gradient_blocks(mesh) if blocks is None else blocks)[sel]
    Xs = np.asarray(X, dtype=float).reshape(mesh.n_cells, mesh.dim)[sel]
    per_corner = mesh.cell_measures[sel, None] * np.einsum("tki,tk->ti", B, Xs)  # (s, dim + 1)
    out = np.zeros(mesh.n_vertices)
    np.add.at(out, mesh.cells[sel].ravel(), per_corner.ravel())
    return out
