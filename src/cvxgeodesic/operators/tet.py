"""P1 operators on tetrahedral meshes: per-tet gradients, the cotangent stiffness, the lumped mass, energies.

A vertex field ``d`` (n,) is linear on each tetrahedron ``t``; its gradient there is
``B_t @ d[T[t]]`` with ``B_t`` (3, 4) whose column ``i`` is the gradient of the hat function of
local vertex ``i`` (in world coordinates, no local frame is needed in 3-D). The cone of the convex
formulations is then ``‖B_t d_t‖ ≤ 1``, an SOC(4) on the four vertex values. The stiffness is
``L = Gᵀ diag(vol ⊗ 1₃) G`` (``dᵀ L d = Σ_t vol_t ‖∇d|_t‖²``), the same matrix as the cotangent
formula ``L_ij = −(1/6) Σ ℓ_kl cot θ_kl`` over the tetrahedra of edge ``ij`` (``ℓ_kl``, ``θ_kl``: the
length and dihedral angle of the opposite edge).

Tetrahedra of zero volume have no gradient (entries ``inf``/``nan`` in the blocks); the assembled
matrices leave them out (they have no volume to weigh them) unless told otherwise, and callers
that want to leave out *near*-degenerate ones pass ``tets=`` (see
:meth:`~cvxgeodesic.mesh.tetmesh.TetMesh.degenerate_tets`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike

from ..mesh.tetmesh import TET_FACES, TetMesh

__all__ = ["tet_dirichlet_energy_matrix", "tet_divergence", "tet_gradient_blocks", "tet_gradient_matrix",
           "tet_gradient_norms", "tet_laplacian_energy_matrix", "tet_mass_matrix", "tet_stiffness"]


def tet_gradient_blocks(mesh: TetMesh) -> np.ndarray:
    """Gradient of each tetrahedron's linear interpolant as a linear map of its four vertex values.

    Column ``i`` of ``blocks[t]`` is ``∇λ_i``, the gradient of the barycentric coordinate of local
    vertex ``i``: the normal of the opposite face, pointing towards vertex ``i``, of length
    ``1 / h_i`` (``h_i`` the altitude from vertex ``i``). The vertex order of ``T`` does not matter.

    Parameters
    ----------
    mesh : TetMesh
        ``k`` tetrahedra ``T`` (k, 4).

    Returns
    -------
    blocks : (k, 3, 4) float ndarray
        ``∇d|_t = blocks[t] @ d[T[t]]``; columns sum to 0 (a constant has no gradient).
        ``inf``/``nan`` on tetrahedra of zero volume.

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> mesh = tet_box(2)
    >>> B = tet_gradient_blocks(mesh)
    >>> g = B[0] @ (mesh.V[mesh.T[0]] @ [1.0, 2.0, 3.0])  # the gradient of a linear function
    >>> g.round(12).tolist()
    [1.0, 2.0, 3.0]
    """
    V, T = mesh.V, mesh.T
    out = np.empty((mesh.n_tets, 3, 4))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, (a, b, c) in enumerate(TET_FACES):
            pa = V[T[:, a]]
            nrm = np.cross(V[T[:, b]] - pa, V[T[:, c]] - pa)
            # ∇λ_i ∥ nrm and ∇λ_i · (p_i − p_a) = 1
            out[:, :, i] = nrm / np.einsum("ij,ij->i", nrm, V[T[:, i]] - pa)[:, None]
    return out


def _selected(mesh: TetMesh, tets: ArrayLike | None) -> np.ndarray:
    """Indices of the tetrahedra to assemble: ``tets``, or every one of nonzero volume."""
    if tets is None:
        return np.flatnonzero(mesh.volumes > 0)
    sel = np.asarray(tets)
    if sel.dtype == bool:
        if sel.shape != (mesh.n_tets,):
            raise ValueError(f"tets: a mask must have shape ({mesh.n_tets},), got {sel.shape}")
        return np.flatnonzero(sel)
    sel = sel.astype(np.int64).reshape(-1)
    if sel.size and (sel.min() < 0 or sel.max() >= mesh.n_tets):
        raise ValueError(f"tets: indices must lie in [0, {mesh.n_tets})")
    return sel


def tet_gradient_matrix(mesh: TetMesh, blocks: np.ndarray | None = None) -> sp.csr_matrix:
    """Sparse per-tetrahedron gradient operator.

    Parameters
    ----------
    mesh : TetMesh
    blocks : (k, 3, 4) float ndarray, optional
        Precomputed :func:`tet_gradient_blocks`.

    Returns
    -------
    G : (3k, n) scipy.sparse.csr_matrix
        Rows ``3t … 3t + 2`` are the x, y, z components of the gradient on tetrahedron ``t``.
    """
    if blocks is None:
        blocks = tet_gradient_blocks(mesh)
    k = mesh.n_tets
    rows = np.repeat(np.arange(3 * k), 4)
    cols = np.repeat(mesh.T, 3, axis=0).ravel()
    return sp.csr_matrix((blocks.reshape(-1), (rows, cols)), shape=(3 * k, mesh.n_vertices))


def tet_gradient_norms(mesh: TetMesh, d: ArrayLike, blocks: np.ndarray | None = None) -> np.ndarray:
    """Per-tetrahedron gradient norm ``‖∇d|_t‖`` of a vertex field.

    Parameters
    ----------
    mesh : TetMesh
    d : (n,) float array_like
    blocks : (k, 3, 4) float ndarray, optional

    Returns
    -------
    (k,) float ndarray
    """
    if blocks is None:
        blocks = tet_gradient_blocks(mesh)
    g = np.einsum("tij,tj->ti", blocks, np.asarray(d, dtype=float)[mesh.T])
    return np.linalg.norm(g, axis=1)


def tet_stiffness(mesh: TetMesh, *, tets: ArrayLike | None = None, blocks: np.ndarray | None = None) -> sp.csc_matrix:
    """Cotangent stiffness (positive semidefinite Laplacian) ``L = Σ_t vol_t B_tᵀ B_t``.

    ``dᵀ L d = Σ_t vol_t ‖∇d|_t‖²`` (libigl's ``cotmatrix`` is ``−L``); ``L 1 = 0``.

    Parameters
    ----------
    mesh : TetMesh
    tets : (s,) int or (k,) bool array_like, optional
        Tetrahedra to assemble; default every tetrahedron of nonzero volume.
    blocks : (k, 3, 4) float ndarray, optional
        Precomputed :func:`tet_gradient_blocks`.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix
    """
    sel = _selected(mesh, tets)
    if blocks is None:
        blocks = tet_gradient_blocks(mesh)
    B = blocks[sel]
    K = mesh.volumes[sel, None, None] * np.einsum("tki,tkj->tij", B, B)  # (s, 4, 4)
    Ts = mesh.T[sel]
    rows = np.repeat(Ts, 4, axis=1).ravel()
    cols = np.tile(Ts, (1, 4)).ravel()
    L = sp.csc_matrix((K.ravel(), (rows, cols)), shape=(mesh.n_vertices, mesh.n_vertices))
    return sp.csc_matrix(0.5 * (L + L.T))


def tet_mass_matrix(mesh: TetMesh, *, tets: ArrayLike | None = None) -> sp.dia_matrix:
    """Lumped (barycentric) mass: each vertex gets a quarter of the volume of each of its tetrahedra.

    The diagonal sums to the total volume of the assembled tetrahedra; vertices in none get 0.

    Parameters
    ----------
    mesh : TetMesh
    tets : (s,) int or (k,) bool array_like, optional
        Tetrahedra to assemble; default every tetrahedron of nonzero volume.

    Returns
    -------
    (n, n) scipy.sparse.dia_matrix
    """
    sel = _selected(mesh, tets)
    mass = np.zeros(mesh.n_vertices)
    np.add.at(mass, mesh.T[sel].ravel(), np.repeat(mesh.volumes[sel] / 4.0, 4))
    return sp.diags(mass)


def tet_divergence(mesh: TetMesh, X: ArrayLike, *, tets: ArrayLike | None = None,
                   blocks: np.ndarray | None = None) -> np.ndarray:
    """Integrated divergence of a per-tetrahedron vector field, ``Gᵀ diag(vol) X``, one value per vertex.

    The weak form: ``Σ_t vol_t X_t · ∇λ_i`` for vertex ``i``, so that ``L φ = tet_divergence(X)`` is the
    Poisson equation whose solution has gradient closest to ``X`` (least squares, volume-weighted).
    Sign: this is ``−∫ (div X) λ_i`` plus the boundary flux.

    Parameters
    ----------
    mesh : TetMesh
    X : (k, 3) float array_like
        One vector per tetrahedron.
    tets : (s,) int or (k,) bool array_like, optional
        Tetrahedra to assemble; default every tetrahedron of nonzero volume.
    blocks : (k, 3, 4) float ndarray, optional

    Returns
    -------
    (n,) float ndarray
    """
    sel = _selected(mesh, tets)
    if blocks is None:
        blocks = tet_gradient_blocks(mesh)
    Xs = np.asarray(X, dtype=float).reshape(mesh.n_tets, 3)[sel]
    per_corner = mesh.volumes[sel, None] * np.einsum("tki,tk->ti", blocks[sel], Xs)  # (s, 4)
    out = np.zeros(mesh.n_vertices)
    np.add.at(out, mesh.T[sel].ravel(), per_corner.ravel())
    return out


def tet_dirichlet_energy_matrix(mesh: TetMesh, *, tets: ArrayLike | None = None) -> sp.csc_matrix:
    """Volume-normalized Dirichlet energy ``E(d) = Σ_t vol_t ‖∇d|_t‖² / Σ_t vol_t = dᵀ Q d``.

    The volume counterpart of :func:`~cvxgeodesic.operators.energies.dirichlet_energy_matrix`:
    ``Q = L / |Ω|`` (``E = 1`` for a field of unit gradient everywhere).

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    sel = _selected(mesh, tets)
    return sp.csc_matrix(tet_stiffness(mesh, tets=sel) / mesh.volumes[sel].sum())


def tet_laplacian_energy_matrix(mesh: TetMesh, *, tets: ArrayLike | None = None) -> sp.csc_matrix:
    """Squared-Laplacian energy ``Q = L M⁻¹ L`` with the lumped mass ``M`` (vertices of zero mass left out).

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix, symmetric PSD
    """
    sel = _selected(mesh, tets)
    L = tet_stiffness(mesh, tets=sel)
    mass = tet_mass_matrix(mesh, tets=sel).diagonal()
    inv = np.zeros_like(mass)
    np.divide(1.0, mass, out=inv, where=mass > 0)
    Q = L @ sp.diags(inv) @ L
    return sp.csc_matrix(0.5 * (Q + Q.T))
