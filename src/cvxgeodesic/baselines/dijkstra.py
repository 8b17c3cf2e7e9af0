"""Dijkstra's algorithm on the edge graph (equals the LCLP formulation, paper Lemma 1)."""

from __future__ import annotations

import numpy as np
from scipy.sparse.csgraph import dijkstra

from .base import BaselineSolver


class DijkstraBaseline(BaselineSolver):
    """Shortest paths along mesh edges, ``scipy.sparse.csgraph.dijkstra``.

    The distance is the length of the shortest edge path, so it never
    underestimates the geodesic distance and is metrically biased: on a regular
    grid of right triangles (axis edges plus diagonals), from a vertex where
    diagonals leave in all four directions, it overestimates the Euclidean
    distance by up to a factor ``sqrt(4 - 2 sqrt 2) ≈ 1.0824`` (in the direction
    22.5° off an axis). The bias does not vanish under refinement.

    Works on any mesh (non-manifold, several components: unreachable vertices
    get ``inf``) and natively supports several sources (``min_only=True``).

    Parameters
    ----------
    mesh : TriMesh or (V, F) tuple
        ``V`` (n, 3) float, ``F`` (m, 3) int.
    medium : Medium, optional
        A travel cost or metric on the mesh (:mod:`cvxgeodesic.operators.metric`): the edges are weighted by
        their lengths in it (:attr:`~cvxgeodesic.operators.metric.Medium.edge_lengths`).

    Examples
    --------
    >>> from cvxgeodesic.mesh import grid_plane
    >>> d, info = DijkstraBaseline(grid_plane(4)).solve(np.array([0]))
    >>> round(float(d[24]), 6)  # opposite corner: four diagonals of length sqrt(2)/4
    1.414214
    """

    name = "dijkstra"
    library = "scipy.sparse.csgraph.dijkstra"
    supports_multiple_sources = True

    def __init__(self, mesh, medium=None) -> None:
        self.medium = medium
        super().__init__(mesh)

    def _setup(self) -> None:
        if self.medium is None:
            self.graph = self.mesh.vertex_adjacency
        else:
            self.graph = self.medium.on(self.mesh).adjacency() * self.medium.scale

    def _solve(self, sources: np.ndarray) -> tuple[np.ndarray, dict]:
        d = dijkstra(self.graph, directed=False, indices=sources, min_only=True)
        return np.asarray(d, dtype=np.float64), {}
