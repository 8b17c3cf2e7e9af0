"""Per-cell gradient of piecewise-linear vertex functions on triangles and tetrahedra (paper eq. 2)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..mesh.simplex import SimplexMesh
from ..mesh.trimesh import TriMesh


def triangle_frames(mesh: TriMesh) -> tuple[np.ndarray, np.ndarray]:
    """Orthonormal 2D frame of each triangle's plane.

    Returns
    -------
    ex, ey : (m, 3) float ndarray
        ``ex`` along the edge v1→v2, ``ey = n̂ × ex`` (so ``(ex, ey, n̂)`` is right-handed).
        NaN on faces of zero area (no warning).
    """
    V, F = mesh.V, mesh.F
    e = V[F[:, 1]] - V[F[:, 0]]
    nrm = mesh.face_normals_unnormalized
    with np.errstate(divide="ignore", invalid="ignore"):
        ex = e / np.linalg.norm(e, axis=1, keepdims=True)
        nhat = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
    ey = np.cross(nhat, ex)
    return ex, ey


def _facet_normal(P: np.ndarray, facet: np.ndarray) -> np.ndarray:
    """(k, dim) normals of the facet of local corners ``facet`` (dim of them) of each cell, any length."""
    a = P[:, facet[0]]
    if len(facet) == 2:  # an edge in the plane: rotated by 90°
        e = P[:, facet[1]] - a
        return np.stack([-e[:, 1], e[:, 0]], axis=1)
    return np.cross(P[:, facet[1]] - a, P[:, facet[2]] - a)


def gradient_blocks(mesh: SimplexMesh) -> np.ndarray:
    """Gradient of each cell's linear interpolant as a linear map of its corner values, for any simplex.

    Column ``i`` of ``blocks[t]`` is ``∇λ_i``, the gradient of the barycentric coordinate of local corner ``i``:
    the normal of the facet opposite ``i``, pointing towards ``i``, of length ``1 / h_i`` (``h_i`` the altitude
    from ``i``), in the frame of the mesh's reference simplex
    (:meth:`~cvxgeodesic.mesh.reference.ReferenceSimplex.local_coordinates`). The corner order does not matter.

    Parameters
    ----------
    mesh : SimplexMesh
        ``k`` cells of ``dim + 1`` corners.

    Returns
    -------
    blocks : (k, dim, dim + 1) float ndarray
        ``∇d|_t = blocks[t] @ d[cells[t]]``; columns sum to 0 (a constant has no gradient). ``inf``/``nan`` on
        cells of zero measure.

    Examples
    --------
    >>> import cvxgeodesic as cg
    >>> mesh = cg.tet_box(2)
    >>> B = gradient_blocks(mesh)
    >>> (B[0] @ (mesh.V[mesh.T[0]] @ [1.0, 2.0, 3.0])).round(12).tolist()  # the gradient of a linear function
    [1.0, 2.0, 3.0]
    """
    P = mesh.reference.local_coordinates(mesh.V[mesh.cells])
    out = np.empty((mesh.n_cells, mesh.dim, mesh.dim + 1))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, facet in enumerate(mesh.reference.facets):
            nrm = _facet_normal(P, facet)
            # ∇λ_i ∥ nrm and ∇λ_i · (p_i − p_a) = 1
            out[:, :, i] = nrm / np.einsum("ij,ij->i", nrm, P[:, i] - P[:, facet[0]])[:, None]
    return out


def gradient_matrix(mesh: SimplexMesh, blocks: np.ndarray | None = None) -> sp.csr_matrix:
    """Sparse per-cell gradient operator.

    Parameters
    ----------
    mesh : SimplexMesh
        ``k`` cells, ``n`` vertices.
    blocks : (k, dim, dim + 1) float ndarray, optional
        Precomputed :func:`gradient_blocks`.

    Returns
    -------
    G : (dim·k, n) scipy.sparse.csr_matrix
        Rows ``dim·t … dim·t + dim − 1`` give the gradient on cell ``t`` (in the frame of
        ``mesh.reference.local_coordinates``), so ``Gᵀ diag(measure ⊗ 1_dim) G`` is the cotangent stiffness matrix.
    """
    if blocks is None:
        blocks = gradient_blocks(mesh)
    k, d = mesh.n_cells, mesh.dim
    rows = np.repeat(np.arange(d * k), d + 1)
    cols = np.repeat(mesh.cells, d, axis=0).ravel()
    return sp.csr_matrix((blocks.reshape(-1), (rows, cols)), shape=(d * k, mesh.n_vertices))


def gradient_norms(mesh: SimplexMesh, d: np.ndarray, blocks: np.ndarray | None = None) -> np.ndarray:
    """Per-cell gradient norm ``‖∇d|_t‖`` of a vertex field.

    Parameters
    ----------
    mesh : SimplexMesh
    d : (n,) float array_like
    blocks : (k, dim, dim + 1) float ndarray, optional

    Returns
    -------
    (k,) float ndarray
    """
    if blocks is None:
        blocks = gradient_blocks(mesh)
    g = np.einsum("tij,tj->ti", blocks, np.asarray(d, dtype=float)[mesh.cells])
    return np.linalg.norm(g, axis=1)
