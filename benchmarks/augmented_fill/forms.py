"""Augmented forms of the QCQP-Hessian Newton system (scratch, H-fill, 2026-12-02).

Builds the exact factors of the curved Hessian energy, Q = Gᵀ S G (G: libigl's CR vector gradient M⁻¹ D, two
unknowns per edge, par rows on the edge's 2 endpoints, perp rows on the edge's 4 diamond vertices; S = L + K, the
sum of 6 × 6 face blocks), from cvxgeodesic's compiled kernels (check.py verifies Gᵀ S G = Q to rounding), and the
matrices of the forms compared by measure.py (H: the QCLP vertex block, 1-ring):

  1   QCLP vertex matrix H (the floor: no energy)
  2   QCQP-Hessian now: H + λQ on kkt_pattern(n, F, edges, Q)
  3   edge unknowns y = G x with multipliers: [[H, 0, −Gᵀ], [0, S, I], [−G, I, 0]]
  4   quasi-definite per face: S_f = C_fᵀ Λ_f C_f, u_f = C_f G_f x (6 per face, no zero eigenvalue met):
      [[H, Bᵀ], [B, −Λ⁻¹]], B = C G
  5a  per-face copies with S_f kept: [[H, G_fᵀ], [G_f, −S_f⁻¹]] (pattern only; a dense 6 × 6 block per face)
  6   perp edge unknowns only (the par rows are 1-ring and stay in the vertex block):
      [[H + G_parᵀ S_pp G_par, G_parᵀ S_pq, −G_perpᵀ], [S_qp G_par, S_qq, I], [−G_perp, I, 0]]
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from cvxgeodesic.mesh.io import load_mesh
from cvxgeodesic.operators import curved_hessian
from cvxgeodesic.operators.energies import (
    curved_hessian_energy,  # noqa: F401 (re-exported for the scripts)
    curved_hessian_face_data,
)
from cvxgeodesic.problems.conic import kkt_pattern  # noqa: F401


def face_factors(mesh):
    """Per face: C (m, 6, 6) rows of G on the face's 6 edge unknowns (par_0..2, perp_0..2), columns verts (m, 6);
    LK (m, 6, 6) the face's block of S = L + K; unknown ids (m, 6) = 2 * edge + (0 par, 1 perp)."""
    F, E, n_edges, lsq, dA, theta, minv, sk = curved_hessian_face_data(mesh)
    Cs, verts = curved_hessian.gradient_blocks(F, E, curved_hessian.twins(E, n_edges), lsq, dA, minv)
    LKs = curved_hessian.laplacian_blocks(F, lsq, dA, theta, sk)
    unk = np.concatenate([2 * E, 2 * E + 1], axis=1)
    return Cs, LKs, verts, unk, n_edges


def global_G_S(mesh, Cs, LKs, verts, unk, n_edges):
    """G (2 n_edges, n) and S (2 n_edges, 2 n_edges) with Q = Gᵀ S G.

    Both faces of an edge compute the same row of G (libigl orients an edge unknown by its vertex indices, not
    by the face), so G's row is taken from either face and S is the plain sum of the faces' blocks; the check
    (check.py) is that Gᵀ S G equals cvxgeodesic's Q to rounding."""
    n = mesh.n_vertices
    ne2 = 2 * n_edges
    flat = unk.ravel()
    owner = np.empty(ne2, np.int64)
    owner[flat] = np.arange(flat.size)  # any writer: the rows agree
    of, oa = owner // 6, owner % 6
    rows = np.repeat(np.arange(ne2), 6)
    cols = verts[of].reshape(-1)
    vals = Cs[of, oa, :].reshape(-1)
    keep = (cols >= 0) & (vals != 0)
    G = sp.csr_matrix((vals[keep], (rows[keep], cols[keep])), shape=(ne2, n))
    G.sum_duplicates()
    G.eliminate_zeros()
    r = np.repeat(unk, 6, axis=1).ravel()
    c = np.tile(unk, (1, 6)).ravel()
    S = sp.csr_matrix((LKs.ravel(), (r, c)), shape=(ne2, ne2))
    S.sum_duplicates()
    S.eliminate_zeros()
    return G, S


def load(name):
    mesh = load_mesh(Path(__file__).resolve().parents[2].parent / "shared" / "meshes" / name)
    return mesh


def pattern(A):
    """Symmetric ones pattern with full diagonal, CSC, sorted."""
    A = sp.csc_matrix(A)
    P = sp.csc_matrix((np.ones(A.nnz), A.indices, A.indptr), shape=A.shape)
    P = P + P.T + sp.identity(A.shape[0], format="csc")
    P.data[:] = 1.0
    P.sort_indices()
    return P


def form3(Hp, G, S):
    ne2 = G.shape[0]
    eye = sp.identity(ne2, format="csr")
    return sp.bmat([[Hp, None, -G.T], [None, S, eye], [-G, eye, None]], format="csc")


def face_eig(LKs, tol=1e-12):
    """Λ (m, 6) and C (m, 6, 6) with S_f = Cᵀ diag(Λ) C (signed, in the global orientation)."""
    w, U = np.linalg.eigh(LKs)  # S_f = U diag(w) Uᵀ
    scale = np.abs(w).max(axis=1, keepdims=True)
    keep = np.abs(w) > tol * scale
    return w, np.transpose(U, (0, 2, 1)), keep


def form4(Hp, Cs, verts, w, Ct, keep, n):
    """[[H, Bᵀ], [B, -Λ⁻¹]], B rows u_{f,k} = (C_f G_f)_k on verts[f]."""
    B = np.einsum("fkj,fjv->fkv", Ct, Cs)  # (m, 6 eig, 6 verts)
    kf, kk = np.nonzero(keep)
    nu = kf.size
    rows = np.repeat(np.arange(nu), 6)
    cols = verts[kf].reshape(-1)
    vals = B[kf, kk, :].reshape(-1)
    ok = cols >= 0
    Bm = sp.csr_matrix((vals[ok], (rows[ok], cols[ok])), shape=(nu, n))
    D = sp.diags(-1.0 / w[kf, kk])
    return sp.bmat([[Hp, Bm.T], [Bm, D]], format="csc"), Bm, w[kf, kk]


def form5a(Hp, Cs, verts, n, LKs=None, lam=1.0):
    """[[H, G_fᵀ], [G_f, −(λ S_f)⁻¹]] with 6 per-face copies of the face's edge unknowns (a dense 6 × 6 block per
    face; its Schur complement on x is H + λ Σ_f G_fᵀ S_f G_f = H + λQ). Without ``LKs``: the pattern only."""
    m = len(Cs)
    rows = np.repeat(np.arange(6 * m), 6)
    cols = np.repeat(verts, 6, axis=0).reshape(-1)
    vals = Cs.reshape(-1)
    ok = (cols >= 0) & (vals != 0)
    Bm = sp.csr_matrix((vals[ok], (rows[ok], cols[ok])), shape=(6 * m, n))
    blocks = np.ones((m, 6, 6)) if LKs is None else -np.linalg.inv(lam * LKs)
    blocks = 0.5 * (blocks + np.transpose(blocks, (0, 2, 1)))
    base = 6 * np.arange(m)[:, None, None]
    r = np.broadcast_to(base + np.arange(6)[None, :, None], (m, 6, 6)).ravel()
    c = np.broadcast_to(base + np.arange(6)[None, None, :], (m, 6, 6)).ravel()
    D = sp.csr_matrix((blocks.ravel(), (r, c)), shape=(6 * m, 6 * m))
    return sp.bmat([[Hp, Bm.T], [Bm, D]], format="csc")


def form6(H, G, S):
    """Perpendicular edge unknowns only: z = G_perp x (one per edge) with multipliers; the parallel part, whose
    rows touch only an edge's endpoints, stays in the vertex block (its pattern is the faces' corners: 1-ring):
    [[H + G_parᵀ S_pp G_par, G_parᵀ S_pq, −G_perpᵀ], [S_qp G_par, S_qq, I], [−G_perp, I, 0]]."""
    Gp, Gq = G[0::2], G[1::2]
    S = sp.csr_matrix(S)
    Spp, Spq, Sqq = S[0::2][:, 0::2], S[0::2][:, 1::2], S[1::2][:, 1::2]
    ne = Gq.shape[0]
    eye = sp.identity(ne, format="csr")
    X = (H + Gp.T @ Spp @ Gp).tocsr()
    XZ = (Gp.T @ Spq).tocsr()
    return sp.bmat([[X, XZ, -Gq.T], [XZ.T, Sqq, eye], [-Gq, eye, None]], format="csc")
