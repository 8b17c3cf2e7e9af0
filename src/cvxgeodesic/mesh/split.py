"""A simplex mesh with source points inserted as vertices (the order-2 solve of a point source)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Generic

import numpy as np

from ..errors import SourceError
from .locate import CellPoint, cells_around
from .reference import ReferenceSimplex
from .simplex import MeshT

__all__ = ["SplitMesh", "piece_coordinates"]


class SplitMesh(Generic[MeshT]):
    """A triangle or tetrahedral mesh with points inserted as vertices (the conforming splits).

    A point inside a cell splits it into ``dim + 1`` pieces; a point on a facet or an edge splits every cell around
    that facet or edge (each into as many pieces as the point has nonzero coordinates). Cell ``t`` of the original
    mesh keeps its index for its first piece; the other pieces are appended. Original vertices keep their indices;
    point ``i`` becomes vertex ``n + i``.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    points : sequence of CellPoint (SurfacePoint, VolumePoint)
        Not at a vertex (a coordinate of exactly 0 means the point lies on the opposite facet).

    Attributes
    ----------
    mesh : TriMesh or TetMesh
        The split mesh (same type as the original).
    cell_parent : (k',) int64 ndarray
        The original cell each cell of :attr:`mesh` is a piece of.
    point_vertices : (p,) int64 ndarray
        The vertices the points became.
    n_original : int
        The original mesh's vertex count.

    Raises
    ------
    SourceError
        Two points in one cell (order 2 takes at most one per cell), or a point at a vertex.

    Examples
    --------
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> from cvxgeodesic.mesh.locate import VolumePoint
    >>> split = SplitMesh(tet_box(1), [VolumePoint(0, [0.25, 0.25, 0.25, 0.25])])
    >>> split.mesh.n_tets, split.point_vertices.tolist()
    (9, [8])
    """

    def __init__(self, mesh: MeshT, points: Sequence[CellPoint]):
        n, cells = mesh.n_vertices, mesh.cells
        self._cells = cells.tolist()
        V = [mesh.V]
        #: cell -> [(local corner replaced, piece index, bary of the point in the cell)]
        self.pieces: dict[int, list[tuple[int, int, np.ndarray]]] = {}
        for i, p in enumerate(points):
            t0 = int(p.cell)
            V.append((p.bary @ mesh.V[cells[t0]])[None])
            nz = np.flatnonzero(p.bary > 0)
            if nz.size < 2:
                raise SourceError(f"{p!r} lies at a vertex: give the vertex index instead")
            corners = cells[t0, nz]
            # every cell holding the point's edge, facet or itself: those with all its support corners
            for t in cells_around(mesh, corners.tolist()):
                self._split_cell(t, n + i, cells[t], corners, p.bary[nz], mesh.reference)
        self.mesh: MeshT = type(mesh)(np.vstack(V), np.asarray(self._cells, dtype=np.int64), name=mesh.name)
        self.cell_parent = np.arange(len(self._cells), dtype=np.int64)
        del self._cells
        for t, lst in self.pieces.items():
            self.cell_parent[[idx for _, idx, _ in lst]] = t
        self.point_vertices = n + np.arange(len(points), dtype=np.int64)
        self.n_original = n

    def _split_cell(self, t: int, vid: int, cell: np.ndarray, corners: np.ndarray, weights: np.ndarray,
                    reference: ReferenceSimplex) -> None:
        """Replace cell ``t`` by its pieces around the new vertex ``vid`` (at ``weights`` on ``corners``)."""
        if t in self.pieces:
            one, prep = reference.words.one, reference.words.preposition
            raise SourceError(f"two source points {prep} {one} {t}: order 2 takes at most one per {one}")
        beta = np.zeros(cell.size)
        for corner, b in zip(corners, weights, strict=True):
            beta[cell == corner] = b
        lst: list[tuple[int, int, np.ndarray]] = []
        for kk in np.flatnonzero(beta > 0).tolist():
            piece = list(cell)
            piece[kk] = vid
            if not lst:
                self._cells[t] = piece
                idx = t
            else:
                self._cells.append(piece)
                idx = len(self._cells) - 1
            lst.append((kk, idx, beta))
        self.pieces[t] = lst

    def locate(self, cells: np.ndarray, bary: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Original ``(cells (p,), bary (p, dim + 1))`` pairs → the pieces holding the points and their coordinates
        there (:func:`piece_coordinates`)."""
        cells = np.array(cells, dtype=np.int64)
        bary = np.array(bary, dtype=float)
        for r, t in enumerate(cells.tolist()):
            lst = self.pieces.get(t)
            if lst:
                cells[r], bary[r] = piece_coordinates(bary[r], lst)
        return cells, bary


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
