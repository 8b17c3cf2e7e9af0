"""Dijkstra's algorithm on the edge graph of a triangle or tetrahedral mesh (equals the LCLP formulation, paper
Lemma 1)."""

from __future__ import annotations

from typing import Any

import numpy as np

from ..mesh.convert import MeshLike
from ..mesh.reference import TETRAHEDRON
from ..sources import SourceSet
from .base import BaselineSolver
from .points import dijkstra_sources, graph_distance


class DijkstraBaseline(BaselineSolver):
    """Shortest paths along mesh edges, ``scipy.sparse.csgraph.dijkstra``, on triangle and tetrahedral meshes.

    The distance is the length of the shortest edge path, so it never
    underestimates the geodesic distance and is metrically biased: on a regular
    grid of right triangles (axis edges plus diagonals), from a vertex where
    diagonals leave in all four directions, it overestimates the Euclidean
    distance by up to a factor ``sqrt(4 - 2 sqrt 2) ≈ 1.0824`` (in the direction
    22.5° off an axis). On a Kuhn grid of tetrahedra the edge directions are the
    axes, the face diagonals and the cube diagonal: up to about 8 % between them.
    The bias does not vanish under refinement.

    Works on any mesh (non-manifold, several components: unreachable vertices
    get ``inf``) and natively supports several sources (``min_only=True``): exactly
    the minimum of single runs. Inside a volume a point source is joined to the
    corners of its tetrahedron by straight segments and a boundary source starts
    from the vertices of its faces; on a surface, a point or curve is joined to the corners of
    its faces (:func:`~cvxgeodesic.baselines.points.dijkstra_sources`).

    Parameters
    ----------
    mesh : TriMesh, TetMesh, or (V, F) / (V, T) tuple
        ``V`` (n, 3) float, ``F`` (m, 3) int or ``T`` (k, 4) int.
    medium : Medium, optional
        A travel cost or metric on a surface (:mod:`cvxgeodesic.operators.metric`): the edges are weighted by
        their lengths in it (:attr:`~cvxgeodesic.operators.metric.Medium.edge_lengths`).

    Examples
    --------
    >>> from cvxgeodesic.mesh import grid_plane
    >>> d, info = DijkstraBaseline(grid_plane(4)).solve(np.array([0]))
    >>> round(float(d[24]), 6)  # opposite corner: four diagonals of length sqrt(2)/4
    1.414214
    >>> from cvxgeodesic.mesh.tet_generate import tet_box
    >>> d, info = DijkstraBaseline(tet_box(2)).solve(0)
    >>> round(float(d[26]), 6)  # the opposite corner: two cube diagonals of length sqrt(3)/2
    1.732051
    """

    name = "dijkstra"
    library = "scipy.sparse.csgraph.dijkstra"

    def __init__(self, mesh: MeshLike, medium: Any = None) -> None:
        self.medium = medium
        super().__init__(mesh)

    def _setup(self) -> None:
        if self.medium is None:
            self.graph = self.mesh.vertex_adjacency
        else:
            self.graph = self.medium.on(self.mesh).adjacency() * self.medium.scale

    def _solve(self, sources: Any) -> tuple[np.ndarray, dict]:
        return graph_distance(self.graph, sources), {}

    def _solve_sources(self, ss: SourceSet) -> tuple[np.ndarray, dict]:
        return dijkstra_sources(self.mesh, ss, self.graph, self.medium), {"sources": "virtual node with offsets"}


class VolumeDijkstraBaseline(DijkstraBaseline):
    """:class:`DijkstraBaseline` inside a tetrahedral mesh (what ``DijkstraBaseline(tetmesh)`` builds): every kind of
    volume source, the source vertices and the vertices of the source faces at 0, the corners of a point's
    tetrahedron at ``|v − p|``."""

    cells = (TETRAHEDRON,)
    source_sets = True

    def _solve(self, sources: Any) -> tuple[np.ndarray, dict]:
        near, offsets = sources.local_values(self.mesh)
        return graph_distance(self.graph, np.zeros(0, dtype=np.int64), near, offsets), {}


DijkstraBaseline.variants = (VolumeDijkstraBaseline,)
