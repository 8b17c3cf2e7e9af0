"""The curved Hessian energy's matrix, assembled face by face in NumPy: libigl's matrix, without its products.

libigl's ``curved_hessian_energy`` (Stein et al. 2020) builds four sparse matrices on the Crouzeix–Raviart vector
space (two unknowns per edge) and multiplies them, ``Q = Dᵀ M⁻¹ (L + K) M⁻¹ D``, in Eigen: four sparse–sparse
products, single-threaded, with large temporaries (43–48 % of a one-shot QCQP-Hessian set-up on the development
scans, docs/dev/performance-log.md, "Set-up cost").

The same matrix is a sum over faces. ``L + K`` couples only the edges of one face, and a row of ``G = M⁻¹ D`` (one
edge unknown) involves only the four vertices of the edge's two faces, so ``Q = Σ_f G_fᵀ (L + K)_f G_f`` with
``G_f`` the 6 × 6 block of ``G`` on the face's six edge unknowns and its six vertices (its corners and the three
vertices across its edges). The blocks are computed as (k, 6, 6) arrays, k faces at a time, and summed
into the pattern of ``Q`` (the union of the blocks' cliques: the structural pattern of libigl's product). The
formulas are libigl's (``scalar_to_cr_vector_gradient``, ``cr_vector_mass``, ``cr_vector_laplacian``,
``cr_vector_curvature_correction``, ``orient_halfedges``, with its conventions: edge ``e`` of a face is opposite
corner ``e``, an edge unknown's sign is + when the half-edge runs from the lower to the higher vertex index, the
angle defect is 0 on boundary vertices); the result equals libigl's to rounding (``tests/test_operators.py``).

Why NumPy and not compiled kernels: this assembly was Numba kernels until 2026-12-06, whose compilation was 2.9 s
of the first QCQP-Hessian solve after an installation, and made it miss issue 41's first-run target (≤ 4× a warm
solve + 2 s) on the bundled mesh. The arrays take about 3× the kernels' time, 0.25 s against 0.09 s on a 97K-face
mesh: 3-5 % of a one-shot QCQP-Hessian solve at 46-97K faces (docs/dev/performance-log.md, "The curved Hessian
energy in NumPy").

Conventions: ``F`` (m, 3) int64, ``E`` (m, 3) int64 (the edge opposite each corner, as
:attr:`~cvxgeodesic.mesh.TriMesh.cell_edges`), half-edge ``h = 3 f + e``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["CHUNK_FACES", "energy_matrix", "face_blocks", "face_geometry", "gradient_blocks", "laplacian_blocks",
           "twins"]

_NEXT, _PREV = [1, 2, 0], [2, 0, 1]  # corner e + 1 and e + 2 of each corner e, as column indices
_ALL = slice(None)


def face_geometry(V: np.ndarray, F: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Squared edge lengths, doubled areas and corner angles of every face, from the edge lengths as libigl does.

    Parameters
    ----------
    V : (n, 3) float ndarray
    F : (m, 3) int ndarray

    Returns
    -------
    lsq : (m, 3) float ndarray
        Squared length of the edge opposite each corner.
    dA : (m,) float ndarray
        Twice the area (Kahan's Heron formula; 0 where it has no real value).
    theta : (m, 3) float ndarray
        The angle at each corner.
    """
    lsq = ((V[F[:, _NEXT]] - V[F[:, _PREV]]) ** 2).sum(axis=2)
    c1, b1, a1 = np.sort(np.sqrt(lsq), axis=1).T  # a1 >= b1 >= c1, exactly (Kahan's order)
    arg = (a1 + (b1 + c1)) * (c1 - (a1 - b1)) * (c1 + (a1 - b1)) * (a1 + (b1 - c1))
    dA = 0.5 * np.sqrt(np.maximum(arg, 0.0))
    s2, s3 = lsq[:, _NEXT], lsq[:, _PREV]
    with np.errstate(invalid="ignore", divide="ignore"):  # a degenerate face: caught by the caller's finite check
        theta = np.arccos((s3 + s2 - lsq) / (2.0 * np.sqrt(s3 * s2)))
    return lsq, dA, theta


def twins(E: np.ndarray, n_edges: int) -> np.ndarray:
    """(3m,) int64: the other half-edge ``3 f' + e'`` of each half-edge's edge, −1 where the edge has one face
    (the mesh is edge-manifold)."""
    edge = E.ravel()
    h = np.arange(edge.size)
    first, last = np.full(n_edges, edge.size, dtype=np.int64), np.full(n_edges, -1, dtype=np.int64)
    np.minimum.at(first, edge, h)
    np.maximum.at(last, edge, h)
    other = np.where(first[edge] == h, last[edge], first[edge])
    return np.where(other == h, -1, other)


def _gradient_rows(F: np.ndarray, lsq: np.ndarray, dA: np.ndarray, h: np.ndarray) -> np.ndarray:
    """(5, *h.shape): libigl's ``scalar_to_cr_vector_gradient`` entries of the half-edges ``h = 3 f + e``:
    (par_i, par_j, perp_i, perp_j, perp_k) with i, j, k = F[f, e+1], F[f, e+2], F[f, e]."""
    f, e = h // 3, h % 3
    e1, e2 = (e + 1) % 3, (e + 2) % 3
    return _rows(F[f, e1] < F[f, e2], lsq[f, e], lsq[f, e1], lsq[f, e2], dA[f])


def _face_gradient_rows(F: np.ndarray, lsq: np.ndarray, dA: np.ndarray) -> np.ndarray:
    """(5, k, 3): :func:`_gradient_rows` of the three half-edges of each face of ``F`` (k, 3), by columns."""
    return _rows(F[:, _NEXT] < F[:, _PREV], lsq, lsq[:, _NEXT], lsq[:, _PREV], dA[:, None])


def _rows(ascending, eij, ejk, eki, dA):
    """The five entries of a half-edge from its orientation (i < j), its squared edge lengths and its face's doubled
    area."""
    o = np.where(ascending, 1.0, -1.0)
    s = np.sqrt(eij)
    return np.stack([-o * dA / (6.0 * s), o * dA / (6.0 * s), -o * (eij + ejk - eki) / (12.0 * s),
                     -o * (eij - ejk + eki) / (12.0 * s), o * s / 6.0])


def gradient_blocks(F, E, twin, lsq, dA, minv, faces=_ALL):
    """Rows of ``G = M⁻¹ D`` on the six edge unknowns of the faces ``faces`` (k, 6, 6), on the columns ``verts``
    (k, 6): the corners, then the vertex across each edge (−1 on the boundary)."""
    own = np.arange(F.shape[0])[faces, None] * 3 + np.arange(3)  # (k, 3) half-edges
    Fk, Ek = F[faces], E[faces]
    t = twin[own]
    has = t >= 0
    w = minv[Ek]
    rows = _face_gradient_rows(Fk, lsq[faces], dA[faces]) * w
    trows = _gradient_rows(F, lsq, dA, np.where(has, t, 0)) * np.where(has, w, 0.0)
    g, ge = np.where(has, t // 3, 0), np.where(has, t % 3, 0)
    verts = np.concatenate([Fk, np.where(has, F[g, ge], -1)], axis=1)
    flip = F[g, (ge + 1) % 3] != Fk[:, [1, 2, 0]]  # the twin runs the other way: its i is our j
    C = np.zeros((6, 6, Fk.shape[0]))  # entry-major: each update below is a contiguous pass over the faces
    for e in range(3):
        a, b = (e + 1) % 3, (e + 2) % 3  # local corners of i and j
        pi, pj, qi, qj, qk = rows[:, :, e]
        tpi, tpj, tqi, tqj, tqk = trows[:, :, e]
        fl = flip[:, e]
        C[e, a] += pi
        C[e, b] += pj
        C[3 + e, a] += qi
        C[3 + e, b] += qj
        C[3 + e, e] += qk
        C[e, a] += np.where(fl, tpj, tpi)
        C[e, b] += np.where(fl, tpi, tpj)
        C[3 + e, a] += np.where(fl, tqj, tqi)
        C[3 + e, b] += np.where(fl, tqi, tqj)
        C[3 + e, 3 + e] += tqk
    return C.transpose(2, 0, 1), verts


def laplacian_blocks(F, lsq, dA, theta, sk):
    """libigl's ``cr_vector_laplacian`` plus ``cr_vector_curvature_correction`` on every face's edge unknowns
    (m, 6, 6)."""
    LK = np.zeros((6, 6, F.shape[0]))
    for e in range(3):
        e1, e2 = (e + 1) % 3, (e + 2) % 3
        i, j, k = F[:, e1], F[:, e2], F[:, e]
        o2 = np.where(i < j, 1.0, -1.0) * np.where(k < i, 1.0, -1.0)
        eij, ejk, eki = lsq[:, e], lsq[:, e1], lsq[:, e2]
        lens = np.sqrt(eij * eki)
        q = eij - ejk + eki
        ki, kj, kk = sk[i] * theta[:, e1], sk[j] * theta[:, e2], sk[k] * theta[:, e]
        diag = 2.0 / dA * eij + (ki + kj + kk)
        par = o2 * q * q / (2.0 * lens * dA) - o2 * (ki - kj - kk) * (q / (2.0 * lens))
        perp = -o2 * q / lens + o2 * (ki - kj - kk) * np.sqrt(1.0 - q * q / (4.0 * eij * eki))
        LK[e, e] += diag
        LK[3 + e, 3 + e] += diag
        LK[e, e2] += par
        LK[e2, e] += par
        LK[3 + e, 3 + e2] += par
        LK[3 + e2, 3 + e] += par
        LK[e, 3 + e2] += perp
        LK[3 + e2, e] += perp
        LK[3 + e, e2] -= perp
        LK[e2, 3 + e] -= perp
    return LK.transpose(2, 0, 1)


def face_blocks(F: np.ndarray, E: np.ndarray, twin: np.ndarray, lsq: np.ndarray, dA: np.ndarray,
                theta: np.ndarray, minv: np.ndarray, sk: np.ndarray,
                faces: slice = _ALL) -> tuple[np.ndarray, np.ndarray]:
    """Each face's 6 × 6 block ``G_fᵀ (L + K)_f G_f`` of ``Q``, symmetrized, and the vertices it sits on.

    Parameters
    ----------
    F, E : (m, 3) int64 ndarray
        Faces and the edge opposite each corner.
    twin : (3m,) int64 ndarray
        :func:`twins`.
    lsq, dA, theta : (m, 3), (m,), (m, 3) float ndarray
        :func:`face_geometry`.
    minv : (n_edges,) float ndarray
        Inverse Crouzeix–Raviart mass per edge (0 where it is 0).
    sk : (n,) float ndarray
        Angle defect divided by the angle sum per vertex (0 on boundary vertices).
    faces : slice, optional
        The faces whose blocks are made (all by default).

    Returns
    -------
    blocks : (k, 6, 6) float ndarray
    verts : (k, 6) int64 ndarray
        The corners, then the vertex across each edge (−1 on the boundary).
    """
    with np.errstate(invalid="ignore", divide="ignore"):  # degenerate faces: the caller's finite check
        C, verts = gradient_blocks(F, E, twin, lsq, dA, minv, faces)
        LK = laplacian_blocks(F[faces], lsq[faces], dA[faces], theta[faces], sk)
        B = np.swapaxes(C, 1, 2) @ (LK @ C)
    return 0.5 * (B + np.swapaxes(B, 1, 2)), verts


#: Faces per pass of :func:`energy_matrix`: its temporaries (five (k, 6, 6) arrays) stay near 100 MB, where the
#: whole mesh's would be 1.6 GB at 1.1M faces.
CHUNK_FACES = 65536


def energy_matrix(F: np.ndarray, E: np.ndarray, n_edges: int, lsq: np.ndarray, dA: np.ndarray, theta: np.ndarray,
                  minv: np.ndarray, sk: np.ndarray, n: int) -> sp.csc_matrix | None:
    """The (n, n) curved Hessian energy matrix, the blocks of :func:`face_blocks` summed, exactly symmetric;
    ``None`` where a block is not finite (a face without a proper shape: zero area, a zero-length edge).

    The blocks' upper triangle (row ≤ column, by vertex index) is summed and mirrored: summing both triangles would
    add the duplicates of (u, v) and (v, u) in different orders, a matrix symmetric only to rounding. Which entries
    are kept depends on the vertices only, so the triplets are counted first, allocated once and filled pass by
    pass (every temporary is of one pass's size).
    """
    twin = twins(E, n_edges)
    index = np.int32 if n < np.iinfo(np.int32).max else np.int64
    passes = [slice(start, start + CHUNK_FACES) for start in range(0, F.shape[0], CHUNK_FACES)]
    vertices = [_block_vertices(F, twin, faces).astype(index) for faces in passes]
    kept = [_upper(verts) for verts in vertices]
    size = sum(int(np.count_nonzero(k)) for k in kept)
    data, rows, cols = np.empty(size), np.empty(size, dtype=index), np.empty(size, dtype=index)
    end = 0
    for faces, verts, keep in zip(passes, vertices, kept, strict=True):
        blocks, _ = face_blocks(F, E, twin, lsq, dA, theta, minv, sk, faces)
        if not np.isfinite(blocks).all():
            return None
        k = int(np.count_nonzero(keep))
        data[end:end + k] = blocks[keep]
        rows[end:end + k] = np.broadcast_to(verts[:, :, None], keep.shape)[keep]
        cols[end:end + k] = np.broadcast_to(verts[:, None, :], keep.shape)[keep]
        end += k
    upper = sp.csc_matrix((data, (rows, cols)), shape=(n, n))
    return sp.csc_matrix(upper + sp.triu(upper, 1).T)


def _upper(verts: np.ndarray) -> np.ndarray:
    """(k, 6, 6) bool: the block entries on two vertices (no −1) in the upper triangle (row ≤ column)."""
    r, c = verts[:, :, None], verts[:, None, :]
    return (r >= 0) & (r <= c)


def _block_vertices(F: np.ndarray, twin: np.ndarray, faces: slice) -> np.ndarray:
    """(k, 6) int64: the corners of the faces ``faces``, then the vertex across each edge (−1 on the boundary), as
    :func:`face_blocks` orders them."""
    t = twin.reshape(-1, 3)[faces]
    has = t >= 0
    across = F[np.where(has, t // 3, 0), np.where(has, t % 3, 0)]
    return np.concatenate([F[faces], np.where(has, across, -1)], axis=1)
