"""Point location inside a tetrahedral mesh: the tetrahedron containing each of many points, and the point's
barycentric coordinates in it.

A k-d tree on the tetrahedra's centroids gives, for each point, every tetrahedron whose circumscribing ball around
its centroid (radius: its farthest vertex) holds the point, and the barycentric coordinates of those candidates
decide. No Delaunay triangulation of the vertices is involved, so non-convex meshes (an L-shaped prism) and meshes
with holes work. (On surfaces, the closest point plays this part: :mod:`cvxgeodesic.mesh.closest`.)
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from scipy.spatial import cKDTree

from ..validation import as_points
from .tetmesh import TET_FACES, TetMesh

__all__ = ["INSIDE_TOL", "locate_points"]

#: A point counts as inside a tetrahedron when its smallest barycentric coordinate is ``>= -INSIDE_TOL``
#: (points on a shared face or on the boundary surface, up to round-off).
INSIDE_TOL = 1e-9


def _barycentric(mesh: TetMesh, tets: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(p, 4) barycentric coordinates of ``X[j]`` in ``T[tets[j]]``; NaN rows for tetrahedra of zero volume."""
    V, T = mesh.V, mesh.T[tets]
    out = np.empty((len(tets), 4))
    with np.errstate(divide="ignore", invalid="ignore"):
        for i, (a, b, c) in enumerate(TET_FACES):
            pa = V[T[:, a]]
            nrm = np.cross(V[T[:, b]] - pa, V[T[:, c]] - pa)
            out[:, i] = np.einsum("ij,ij->i", nrm, X - pa) / np.einsum("ij,ij->i", nrm, V[T[:, i]] - pa)
    return out


class _Locator:
    """The k-d tree of one mesh's tetrahedron centroids (built once per mesh, cached on it)."""

    def __init__(self, mesh: TetMesh):
        P = mesh.V[mesh.T]  # (k, 4, 3)
        self.centroids = P.mean(axis=1)
        self.radius = float(np.linalg.norm(P - self.centroids[:, None], axis=2).max()) * (1 + 1e-9)
        self.tree = cKDTree(self.centroids)


def _locator(mesh: TetMesh) -> _Locator:
    loc = mesh.__dict__.get("_tet_locator")
    if loc is None:
        loc = _Locator(mesh)
        mesh.__dict__["_tet_locator"] = loc  # TetMesh is immutable: a cache like its cached properties
    return loc


def locate_points(mesh: TetMesh, points: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """The tetrahedron containing each point, and the point's barycentric coordinates in it.

    Parameters
    ----------
    mesh : TetMesh
    points : (p, 3) or (3,) float array_like

    Returns
    -------
    tets : (p,) int64 ndarray
        Index of the containing tetrahedron, ``-1`` for a point outside the mesh. A point on a
        shared face (or edge, vertex) gets the tetrahedron where it is deepest inside (largest
        smallest coordinate), so the answer is deterministic.
    bary : (p, 4) float ndarray
        Barycentric coordinates (clipped at 0 and renormalized); NaN rows for points outside.

    Raises
    ------
    ParameterError
        ``points`` not finite positions.
    """
    X = as_points(points, "points").reshape(-1, 3)
    loc = _locator(mesh)
    cand = loc.tree.query_ball_point(X, loc.radius, return_sorted=False)
    counts = np.fromiter((len(c) for c in cand), dtype=np.int64, count=len(cand))
    point_of = np.repeat(np.arange(len(X)), counts)
    tet_of = np.fromiter((t for c in cand for t in c), dtype=np.int64, count=int(counts.sum()))
    tets = np.full(len(X), -1, dtype=np.int64)
    bary = np.full((len(X), 4), np.nan)
    if tet_of.size:
        B = _barycentric(mesh, tet_of, X[point_of])
        depth = np.where(np.isnan(B).any(axis=1), -np.inf, B.min(axis=1))
        # best candidate per point: sort by (point, -depth) and take the first of each point
        order = np.lexsort((-depth, point_of))
        first = order[np.r_[True, point_of[order][1:] != point_of[order][:-1]]]
        ok = depth[first] >= -INSIDE_TOL
        p = point_of[first][ok]
        tets[p] = tet_of[first][ok]
        b = np.clip(B[first][ok], 0.0, None)
        bary[p] = b / b.sum(axis=1, keepdims=True)
    return tets, bary
