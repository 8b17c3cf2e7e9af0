"""Per-triangle gradient of piecewise-linear vertex functions (paper eq. 2)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

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


def gradient_blocks(mesh: TriMesh) -> np.ndarray:
    """Gradient of each triangle's linear interpolant in its local 2D frame.

    For triangle t with vertex values ``d_t = d[F[t]]`` the gradient is
    ``blocks[t] @ d_t``, expressed in the frame of :func:`triangle_frames`:
    ``∇d|_t = (1 / 2A) Σ_i d_i (n̂ × e_i)`` with ``e_i`` the edge opposite vertex i.

    Parameters
    ----------
    mesh : TriMesh

    Returns
    -------
    blocks : (m, 2, 3) float ndarray
        Rows are the x and y components of the gradient of the three hat functions.
        Entries are ``inf``/``nan`` on zero-area triangles.
    """
    V, F = mesh.V, mesh.F
    ex, ey = triangle_frames(mesh)
    p = [V[F[:, k]] - V[F[:, 0]] for k in range(3)]
    # 2D coordinates of the three corners in the local frame (corner 0 at the origin)
    P2 = np.stack(
        [np.stack([np.einsum("ij,ij->i", pk, ex), np.einsum("ij,ij->i", pk, ey)], axis=1) for pk in p], axis=1
    )
    e_opp = np.stack([P2[:, 2] - P2[:, 1], P2[:, 0] - P2[:, 2], P2[:, 1] - P2[:, 0]], axis=1)  # (m, 3, 2)
    twice_area = 2.0 * mesh.face_areas
    with np.errstate(divide="ignore", invalid="ignore"):
        rot = np.stack([-e_opp[:, :, 1], e_opp[:, :, 0]], axis=1)  # (m, 2, 3): rotate each edge by +90°
        return rot / twice_area[:, None, None]


def gradient_matrix(mesh: TriMesh, blocks: np.ndarray | None = None) -> sp.csr_matrix:
    """Sparse per-triangle gradient operator.

    Parameters
    ----------
    mesh : TriMesh
    blocks : (m, 2, 3) float ndarray, optional
        Precomputed :func:`gradient_blocks`.

    Returns
    -------
    G : (2m, n) scipy.sparse.csr_matrix
        Rows ``2t`` and ``2t+1`` give the local-frame gradient on triangle t,
        so ``Gᵀ diag(A ⊗ 1₂) G`` is the cotangent stiffness matrix.
    """
    if blocks is None:
        blocks = gradient_blocks(mesh)
    m = mesh.n_faces
    rows = np.repeat(np.arange(2 * m), 3)
    cols = np.repeat(mesh.F, 2, axis=0).ravel()
    return sp.csr_matrix((blocks.reshape(-1), (rows, cols)), shape=(2 * m, mesh.n_vertices))


def gradient_norms(mesh: TriMesh, d: np.ndarray, blocks: np.ndarray | None = None) -> np.ndarray:
    """Per-triangle gradient norm ``‖∇d|_t‖`` of a vertex field.

    Parameters
    ----------
    mesh : TriMesh
    d : (n,) float ndarray
    blocks : (m, 2, 3) float ndarray, optional

    Returns
    -------
    (m,) float ndarray
    """
    if blocks is None:
        blocks = gradient_blocks(mesh)
    g = np.einsum("tij,tj->ti", blocks, np.asarray(d, dtype=float)[mesh.F])
    return np.linalg.norm(g, axis=1)
