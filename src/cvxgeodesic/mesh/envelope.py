"""The largest field below given vertex values that is 1-Lipschitz along a mesh's edges.

A distance field ``d`` satisfies ``d_i ≤ d_j + |p_i − p_j|`` along every short edge ``ij`` (up to the chord's
shortfall from the geodesic, third order in the edge length). A field read from another surface can break it where
that surface lacks a connection the mesh has: a point cloud's field solved on the surface through its points
(:meth:`~cvxgeodesic.mesh.pointcloud.PointCloud.surface`, which drops the triangles the fans disagree on) goes around
the holes the cloud's own triangles close. :func:`lipschitz_envelope` lowers every value to the least
``d_j + (edge-graph distance from j)``: one Dijkstra run from a virtual vertex joined to each vertex ``j`` by an
edge of length ``d_j``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from .simplex import SimplexMesh

__all__ = ["lipschitz_envelope"]


def lipschitz_envelope(mesh: SimplexMesh, values: np.ndarray) -> np.ndarray:
    """``min_j (values[j] + dist(j, i))`` at every vertex ``i``, ``dist`` the shortest path along ``mesh``'s edges.

    Parameters
    ----------
    mesh : SimplexMesh
        ``n`` vertices; its edge graph (:attr:`~cvxgeodesic.mesh.simplex.SimplexMesh.vertex_adjacency`).
    values : (n,) float ndarray
        Finite values, or ``inf`` (no value: left ``inf``).

    Returns
    -------
    (n,) float ndarray
        At most ``values`` everywhere, equal to it where no edge path lowers it by more than round-off; ``inf`` where
        ``values`` is.

    Examples
    --------
    >>> import numpy as np
    >>> import cvxgeodesic as cg
    >>> from cvxgeodesic.mesh.envelope import lipschitz_envelope
    >>> mesh = cg.TriMesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]])
    >>> lipschitz_envelope(mesh, np.array([0.0, 5.0, 0.5])).round(3)
    array([0. , 1. , 0.5])
    """
    d = np.asarray(values, dtype=np.float64)
    n = mesh.n_vertices
    finite = np.flatnonzero(np.isfinite(d))
    if finite.size == 0:
        return d.copy()
    # a zero-length edge would be no edge in a sparse matrix: every edge from the virtual vertex is lengthened by
    # ``shift`` (the edges' scale: the round-off stays that of the values), taken off again after
    shift = mesh.mean_edge_length or 1.0
    A = mesh.vertex_adjacency.tocoo()
    rows = np.r_[A.row, np.full(finite.size, n)]
    cols = np.r_[A.col, finite]
    G = sp.csr_matrix((np.r_[A.data, d[finite] + shift], (rows, cols)), shape=(n + 1, n + 1))
    reached = dijkstra(G, directed=True, indices=n)[:n] - shift
    # a drop within round-off is none (collinear edges meet the triangle inequality with equality)
    with np.errstate(invalid="ignore"):
        lower = np.isfinite(d) & (reached < d - 1e-12 * (np.abs(d) + shift))
    return np.where(lower, reached, d)
