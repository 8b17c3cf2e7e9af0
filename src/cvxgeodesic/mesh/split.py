"""A mesh with source points inserted as vertices (the order-2 solve of a point source)."""

from __future__ import annotations

import numpy as np

from ..errors import SourceError
from .trimesh import TriMesh

__all__ = ["SplitMesh", "piece_coordinates"]


class SplitMesh:
    """A mesh with source points inserted as vertices (each face holding one is split into 2 or 3 faces).

    Face ``f`` of the original mesh keeps its index for its first piece; the other pieces are appended.
    Original vertices keep their indices; point ``i`` becomes vertex ``n + i``.

    Parameters
    ----------
    mesh : TriMesh
    points : list of objects with ``face`` and normalized ``bary`` (on an edge or inside a face)

    Raises
    ------
    SourceError
        Two points on one face.
    """

    def __init__(self, mesh: TriMesh, points):
        n = mesh.n_vertices
        F = [row for row in mesh.F.tolist()]
        V = [mesh.V]
        self.pieces: dict[int, list[tuple[int, int, np.ndarray]]] = {}  # face -> [(corner k, piece, bary)]
        new_ids = []
        for i, p in enumerate(points):
            vid = n + i
            new_ids.append(vid)
            V.append((p.bary @ mesh.V[mesh.F[p.face]])[None])
            nz = np.flatnonzero(p.bary > 0)
            corners = mesh.F[p.face, nz]
            if nz.size == 2:
                fs = np.flatnonzero((mesh.F == corners[0]).any(axis=1) & (mesh.F == corners[1]).any(axis=1))
            else:
                fs = np.array([p.face])
            for f in fs.tolist():
                if f in self.pieces:
                    raise SourceError(f"two source points on face {f}: order 2 takes at most one per face")
                beta = np.zeros(3)
                for kk in range(3):
                    hit = np.flatnonzero(corners == mesh.F[f, kk])
                    if hit.size:
                        beta[kk] = p.bary[nz[hit[0]]]
                lst = []
                for k in np.flatnonzero(beta > 0).tolist():
                    tri = list(mesh.F[f])
                    tri[k] = vid
                    if not lst:
                        F[f] = tri
                        idx = f
                    else:
                        F.append(tri)
                        idx = len(F) - 1
                    lst.append((k, idx, beta))
                self.pieces[f] = lst
        self.mesh = TriMesh(np.vstack(V), np.asarray(F, dtype=np.int64), name=mesh.name)
        #: (m',) int64 ndarray: the original face each face of :attr:`mesh` is a piece of
        self.face_parent = np.arange(len(F), dtype=np.int64)
        for f, lst in self.pieces.items():
            self.face_parent[[idx for _, idx, _ in lst]] = f
        self.point_vertices = np.asarray(new_ids, dtype=np.int64)
        self.n_original = n

    def locate(self, faces: np.ndarray, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Original (face, bary) pairs → (piece, bary in the piece)."""
        faces = faces.copy()
        bary = bary.copy()
        for r, f in enumerate(faces.tolist()):
            lst = self.pieces.get(f)
            if lst:
                faces[r], bary[r] = piece_coordinates(bary[r], lst)
        return faces, bary


def piece_coordinates(lam: np.ndarray, pieces: list) -> tuple[int, np.ndarray]:
    """The piece of a split simplex (triangle or tetrahedron) holding the point ``lam`` (barycentric in the
    original), and the point's coordinates there.

    ``pieces`` lists ``(k, piece, beta)``: the piece that replaces corner ``k`` by the inserted point ``beta``. In
    it, ``lam`` has coordinate ``lam_k / beta_k`` on the new vertex and ``lam_i − (lam_k / beta_k) beta_i`` on the
    others; the piece with the smallest ratio holds the point (all its coordinates are then >= 0).
    """
    beta = pieces[0][2]
    ratios = [lam[k] / beta[k] for k, _, _ in pieces]
    j = int(np.argmin(ratios))
    k, idx, _ = pieces[j]
    mu = lam - ratios[j] * beta
    mu[k] = ratios[j]  # corner k of the piece is the inserted point
    mu = np.clip(mu, 0.0, None)
    return idx, mu / mu.sum()
