"""A manifold cover of a non-manifold triangle mesh, for operators that need an edge-manifold mesh.

The curved Hessian energy (Stein et al. 2020) is built on edge (Crouzeix–Raviart) elements and needs
every edge to have at most two faces. :func:`manifold_cover` cuts a mesh along its non-manifold edges:
every corner of a face keeps its vertex's position, and two corners share a vertex of the cover exactly
when they are joined, around that vertex, through a chain of faces that meet across manifold edges
(edges with exactly two faces). Each sheet that meets a non-manifold edge is then a surface with
that edge on its boundary. A function ``d`` on the original vertices lifts to the cover as
``d[cover_to_mesh]``, so an energy ``Q_cover`` of the cover pulls back to ``Cᵀ Q_cover C`` on the
original vertices: the sum of the sheets' energies, positive semidefinite when ``Q_cover`` is, with no
bending penalized across a non-manifold edge (where "straight on" is not defined). On an
edge-manifold mesh the cover is the mesh itself, vertex-manifold or not.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components

from .trimesh import TriMesh


def manifold_cover(mesh: TriMesh) -> tuple[TriMesh, np.ndarray]:
    """Cut ``mesh`` along its non-manifold edges.

    Parameters
    ----------
    mesh : TriMesh

    Returns
    -------
    cover : TriMesh
        Same faces (in the same order), vertices duplicated along non-manifold edges; vertices of
        ``mesh`` in no face do not appear.
    cover_to_mesh : (n_cover,) int64 ndarray
        The vertex of ``mesh`` each cover vertex copies.

    Examples
    --------
    Three triangles on one edge (a "book" of three pages) fall apart into three sheets:

    >>> import numpy as np
    >>> V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1.0]])
    >>> F = np.array([[0, 1, 2], [1, 0, 3], [0, 1, 4]])
    >>> cover, to_mesh = manifold_cover(TriMesh(V, F))
    >>> cover.n_vertices, cover.is_edge_manifold
    (9, True)
    """
    F = mesh.F
    m = F.shape[0]
    # half-edge k of face f runs from corner (f, k) to corner (f, k+1)
    start = np.arange(3 * m).reshape(m, 3)
    end = start[:, [1, 2, 0]]
    a = F.ravel()
    edge = mesh.cell_edges[:, [2, 0, 1]].ravel()  # half-edge k lies on the edge opposite corner k+2
    manifold = np.flatnonzero(mesh.edge_cell_counts[edge] == 2)
    h = manifold[np.argsort(edge[manifold], kind="stable")].reshape(-1, 2)  # the two half-edges of each
    h1, h2 = h[:, 0], h[:, 1]
    s1, e1, s2, e2 = start.ravel()[h1], end.ravel()[h1], start.ravel()[h2], end.ravel()[h2]
    same_direction = a[h1] == a[h2]
    rows = np.r_[s1, e1]
    cols = np.r_[np.where(same_direction, s2, e2), np.where(same_direction, e2, s2)]
    G = sp.coo_matrix((np.ones(rows.size), (rows, cols)), shape=(3 * m, 3 * m))
    _, label = connected_components(G, directed=False)
    cover_to_mesh = np.zeros(label.max() + 1, dtype=np.int64)
    cover_to_mesh[label] = F.ravel()
    cover = TriMesh(mesh.V[cover_to_mesh], label.reshape(m, 3), name=f"{mesh.name} (manifold cover)")
    return cover, cover_to_mesh


def pull_back(Q_cover: sp.spmatrix, cover_to_mesh: np.ndarray, n: int) -> sp.csc_matrix:
    """``Cᵀ Q_cover C``: a quadratic form on the cover as one on the ``n`` original vertices.

    Parameters
    ----------
    Q_cover : (n_cover, n_cover) sparse matrix
    cover_to_mesh : (n_cover,) int ndarray
        From :func:`manifold_cover`.
    n : int
        Vertex count of the original mesh.

    Returns
    -------
    (n, n) scipy.sparse.csc_matrix
    """
    k = cover_to_mesh.size
    C = sp.csr_matrix((np.ones(k), (np.arange(k), cover_to_mesh)), shape=(k, n))
    return sp.csc_matrix(C.T @ sp.csr_matrix(Q_cover) @ C)
