"""Where a distance field's ridge (cut locus) runs: interior edges, normal-derivative jumps, ridge seeds and bands.

The unchecked kernels of :mod:`cvxgeodesic.evaluation.smoothness` (which validates its inputs and documents the
measures) and of :func:`cvxgeodesic.problems.ridge_rounding.round_ridge` (which rounds the ridge they find): a
triangle mesh and a vertex field already checked by the caller, ``inf`` on unreached vertices.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from ..mesh.trimesh import TriMesh
from .gradient import gradient_blocks, gradient_norms, triangle_frames

__all__ = ["cut_locus_band", "edge_gradient_jumps", "interior_edges", "ridge_seeds", "ring_dilate",
           "triangle_gradients_3d"]


def ring_dilate(mesh: TriMesh, mask: np.ndarray, rings: int) -> np.ndarray:
    """(n,) bool: ``mask`` grown by ``rings`` rings of vertex neighbours."""
    A = mesh.vertex_adjacency
    A = sp.csr_matrix((np.ones_like(A.data), A.indices, A.indptr), shape=A.shape)
    out = mask.copy()
    for _ in range(rings):
        out = out | (A @ out.astype(np.float64) > 0)
    return out


def interior_edges(mesh: TriMesh) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Interior edges (exactly two faces): endpoints (k, 2) sorted per row, the two faces (k, 2) and the vertex of
    each face opposite the edge (k, 2)."""
    # the mesh's edge table (cell_edges: the edge opposite each corner), one row per (corner, face), corner-major
    face = np.tile(np.arange(mesh.n_faces), 3)
    opp = mesh.F.T.ravel()
    order = np.argsort(mesh.cell_edges.T.ravel(), kind="stable")
    counts = mesh.edge_cell_counts
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    two = np.flatnonzero(counts == 2)
    first, second = order[starts[two]], order[starts[two] + 1]
    return mesh.edges[two], np.column_stack([face[first], face[second]]), np.column_stack([opp[first], opp[second]])


def triangle_gradients_3d(mesh: TriMesh, d: np.ndarray) -> np.ndarray:
    """(m, 3): the gradient of the linear interpolant of the finite field ``d`` on each triangle, in its plane."""
    g2 = np.einsum("tij,tj->ti", gradient_blocks(mesh), d[mesh.F])
    ex, ey = triangle_frames(mesh)
    return g2[:, :1] * ex + g2[:, 1:] * ey


def edge_gradient_jumps(mesh: TriMesh, d: np.ndarray, *, signed: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Interior edges (k, 2) and the jump of ``d``'s normal derivative across each (k,): ``∂d/∂w1|t1 + ∂d/∂w2|t2``
    (``wᵢ`` in ``tᵢ``'s plane, perpendicular to the edge, into ``tᵢ``), its absolute value unless ``signed``; ``nan``
    where a vertex of either face is not finite or a face has zero area."""
    edges, faces, opp = interior_edges(mesh)
    finite = np.isfinite(d)
    with np.errstate(invalid="ignore", divide="ignore"):
        g = triangle_gradients_3d(mesh, np.where(finite, d, 0.0))
        V = mesh.V
        a = V[edges[:, 0]]
        u = V[edges[:, 1]] - a
        u /= np.linalg.norm(u, axis=1, keepdims=True)
        jump = np.zeros(len(edges))
        for k in range(2):
            r = V[opp[:, k]] - a
            w = r - np.einsum("ij,ij->i", r, u)[:, None] * u
            w /= np.linalg.norm(w, axis=1, keepdims=True)
            jump += np.einsum("ij,ij->i", g[faces[:, k]], w)
        if not signed:
            jump = np.abs(jump)
    ok = finite[mesh.F].all(axis=1) & (mesh.face_areas > 0)
    jump[~(ok[faces[:, 0]] & ok[faces[:, 1]])] = np.nan
    return edges, jump


def ridge_seeds(mesh: TriMesh, d: np.ndarray, sources: np.ndarray, *, threshold: float = 0.9,
                jump_threshold: float = 0.5, exclude_radius: float = 3.0) -> np.ndarray:
    """(n,) bool: the vertices of triangles whose gradient norm is below ``threshold`` and of interior edges whose
    signed jump is below ``-jump_threshold``, none touching a vertex near a source (the ``sources`` mask, its
    neighbours, and the vertices ``v`` with ``d[v] < exclude_radius · h_v``, ``h_v`` the longest edge at ``v``);
    finite vertices only (:func:`cvxgeodesic.evaluation.smoothness.ridge_band` documents why)."""
    finite = np.isfinite(d)
    h_v = mesh.vertex_adjacency.max(axis=1).toarray().ravel()
    near_src = ring_dilate(mesh, sources, 1) | (finite & (d < exclude_radius * h_v))
    valid = finite[mesh.F].all(axis=1) & (mesh.face_areas > 0) & ~near_src[mesh.F].any(axis=1)
    norms = gradient_norms(mesh, np.where(finite, d, 0.0))
    seeds = np.zeros(mesh.n_vertices, dtype=bool)
    seeds[mesh.F[valid & (norms < threshold)].ravel()] = True
    edges, jumps = edge_gradient_jumps(mesh, d, signed=True)
    with np.errstate(invalid="ignore"):
        crease = (jumps < -jump_threshold) & ~near_src[edges[:, 0]] & ~near_src[edges[:, 1]]
    seeds[edges[crease].ravel()] = True
    return seeds & finite


def cut_locus_band(mesh: TriMesh, d: np.ndarray, width: float, sources: np.ndarray, *, threshold: float = 0.9,
                   jump_threshold: float = 0.5, exclude_radius: float = 3.0) -> np.ndarray:
    """(n,) bool: the finite vertices within edge-graph distance ``width / 2`` of the :func:`ridge_seeds`."""
    seeds = ridge_seeds(mesh, d, sources, threshold=threshold, jump_threshold=jump_threshold,
                        exclude_radius=exclude_radius)
    if not seeds.any():
        return seeds
    dist = dijkstra(mesh.vertex_adjacency, indices=np.flatnonzero(seeds), min_only=True, limit=0.5 * width)
    return (dist <= 0.5 * width) & np.isfinite(d)
