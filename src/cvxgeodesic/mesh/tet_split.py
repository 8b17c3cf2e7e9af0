"""A tetrahedral mesh with source points inserted as vertices (the order-2 solve of a VolumePoint source)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from ..errors import SourceError
from .split import piece_coordinates
from .tetmesh import TetMesh

__all__ = ["TetSplitMesh"]


class TetSplitMesh:
    """A tetrahedral mesh with points inserted as vertices.

    A point inside a tetrahedron splits it into 4; a point on a face splits each tetrahedron of the face into 3;
    a point on an edge splits each tetrahedron of the edge into 2 (the conforming splits). Tetrahedron ``t`` of the
    original mesh keeps its index for its first piece; the other pieces are appended. Original vertices keep their
    indices; point ``i`` becomes vertex ``n + i``.

    Parameters
    ----------
    mesh : TetMesh
    points : sequence of VolumePoint
        Not at a vertex (a coordinate of exactly 0 means the point lies on the opposite face).

    Raises
    ------
    SourceError
        Two points in one tetrahedron (order 2 takes at most one per tetrahedron), or a point at a vertex.

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> from cvxgeodesic.sources import VolumePoint
    >>> split = TetSplitMesh(tet_box(1), [VolumePoint(0, [0.25, 0.25, 0.25, 0.25])])
    >>> split.mesh.n_tets, split.point_vertices.tolist()
    (9, [8])
    """

    def __init__(self, mesh: TetMesh, points):
        n = mesh.n_vertices
        T = mesh.T.tolist()
        V = [mesh.V]
        k = mesh.n_tets
        inc = sp.csr_matrix((np.ones(4 * k), (mesh.T.ravel(), np.repeat(np.arange(k), 4))), shape=(n, k))
        #: tet -> [(local corner replaced, piece index, bary of the point in the tet)]
        self.pieces: dict[int, list[tuple[int, int, np.ndarray]]] = {}
        new_ids = []
        for i, p in enumerate(points):
            vid = n + i
            new_ids.append(vid)
            V.append((p.bary @ mesh.V[mesh.T[p.tet]])[None])
            nz = np.flatnonzero(p.bary > 0)
            if nz.size < 2:
                raise SourceError(f"{p!r} lies at a vertex: give the vertex index instead")
            corners = mesh.T[p.tet, nz]
            # every tetrahedron holding the point's face, edge or itself: those with all its support corners
            around = np.flatnonzero(np.asarray(inc[corners].sum(axis=0)).ravel() == nz.size)
            for t in around.tolist():
                if t in self.pieces:
                    raise SourceError(f"two source points in tetrahedron {t}: order 2 takes at most one per "
                                      "tetrahedron")
                beta = np.zeros(4)
                for c, b in zip(corners, p.bary[nz], strict=True):
                    beta[mesh.T[t] == c] = b
                lst: list[tuple[int, int, np.ndarray]] = []
                for kk in np.flatnonzero(beta > 0).tolist():
                    tet = list(mesh.T[t])
                    tet[kk] = vid
                    if not lst:
                        T[t] = tet
                        idx = t
                    else:
                        T.append(tet)
                        idx = len(T) - 1
                    lst.append((kk, idx, beta))
                self.pieces[t] = lst
        self.mesh = TetMesh(np.vstack(V), np.asarray(T, dtype=np.int64), name=mesh.name)
        self.point_vertices = np.asarray(new_ids, dtype=np.int64)
        self.n_original = n

    def locate(self, tets: np.ndarray, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Original ``(tets (p,), bary (p, 4))`` pairs → the pieces holding the points and their coordinates there
        (:func:`~cvxgeodesic.mesh.split.piece_coordinates`)."""
        tets = np.array(tets, dtype=np.int64)
        bary = np.array(bary, dtype=float)
        for r, t in enumerate(tets.tolist()):
            lst = self.pieces.get(t)
            if lst:
                tets[r], bary[r] = piece_coordinates(bary[r], lst)
        return tets, bary
