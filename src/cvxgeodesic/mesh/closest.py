"""Closest points of a triangle mesh: one libigl AABB tree per mesh object, for any finite query.

:func:`closest_point_index` builds a :class:`ClosestPointIndex` on the first search of a mesh object and keeps it
beside the mesh (not on it: the tree cannot be pickled, the mesh can) for as long as the mesh lives;
:func:`cvxgeodesic.mesh.locate.closest_points` (surface points, curve sources, paths) is its search. Below it,
the distances from points to segments and triangles that the sources' bounds use.
"""

from __future__ import annotations

import math
import threading
import weakref

import numpy as np

from .geometry import clipped_barycentric
from .trimesh import TriMesh

#: A position farther than this many bounding-box diagonals from the box's center is moved in along the ray from
#: the center to that distance before its closest point is searched (:class:`ClosestPointIndex`): squares of its
#: coordinates could overflow. Exactly, ``|x − p|² = s² − 2 s (p̃·u − |p̃|²/(2s))`` for ``x`` at distance ``s``
#: along ``u`` and ``p̃ = p − center``, so the point closest at the moved distance ``R`` is farther than the
#: closest one by at most ``diag² / (8 R)``: ``diag / 8e7`` here, while rounding at ``R`` costs about
#: ``2e-16 R = 2e-9 diag``.
FAR_QUERY = 1e7
#: A mesh with a coordinate beyond this (or a bounding-box diagonal below its inverse) is searched for closest
#: points in its unit frame (:class:`ClosestPointIndex`): the point-triangle distances and the barycentric
#: coordinates take fourth powers of the coordinates, which overflow beyond 1e77 (measured: libigl finds other
#: faces from 1e90 on). Other meshes are searched as they are, so their results do not change by a bit.
UNIT_FRAME = 1e32


class ClosestPointIndex:
    """libigl's AABB tree over one mesh's faces, built once per mesh (:func:`closest_point_index`).

    A far query is moved in first (:data:`FAR_QUERY`); a mesh of huge or tiny coordinates is searched in its unit
    frame (:data:`UNIT_FRAME`): the box's center at the origin, scaled by a power of two to a diagonal in
    ``(0.5, 1]``.

    Parameters
    ----------
    mesh : TriMesh

    Attributes
    ----------
    V : (n, 3) float ndarray
        The vertices in the frame of the search: ``(mesh.V - shift) * scale``.
    F : (m, 3) int64 ndarray
    unit_frame : bool
    shift : (3,) float ndarray
    scale : float
        The frame: zeros and 1 unless ``unit_frame``.
    """

    def __init__(self, mesh: TriMesh) -> None:
        import igl

        lo, hi = mesh.V.min(axis=0), mesh.V.max(axis=0)
        self.center = 0.5 * (lo + hi)
        diag = mesh.bbox_diagonal
        self.shift, self.scale = np.zeros(3), 1.0
        self.unit_frame = float(np.abs(mesh.V).max()) > UNIT_FRAME or 0 < diag < 1.0 / UNIT_FRAME
        if self.unit_frame:
            self.shift, self.scale = self.center, 2.0 ** -math.ceil(math.log2(diag))
        self.V = np.ascontiguousarray((mesh.V - self.shift) * self.scale if self.unit_frame else mesh.V,
                                      dtype=np.float64)
        self.F = np.ascontiguousarray(mesh.F, dtype=np.int64)
        self.radius = FAR_QUERY * diag
        self.tree = igl.AABB()
        self.tree.init(self.V, self.F)

    def query(self, X: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Closest face, closest point and distance of each position.

        Parameters
        ----------
        X : (k, 3) float ndarray
            Finite positions.

        Returns
        -------
        faces : (k,) int64 ndarray
        bary : (k, 3) float ndarray
            The closest points' barycentric coordinates in their faces (found in the frame of the search: the same
            coordinates).
        dist : (k,) float ndarray
            Distance from each position to its closest point, in the mesh's units (``inf`` only where that exceeds
            the largest float).
        """
        Q = X - self.center
        # a direction and a length without squaring the coordinates (they may exceed 1e154)
        size = np.abs(Q).max(axis=1)
        unit = Q / np.where(size > 0, size, 1.0)[:, None]
        norm = np.linalg.norm(unit, axis=1)
        with np.errstate(over="ignore"):
            far = size * norm > self.radius
        P = X
        if far.any():
            Q[far] = unit[far] * (self.radius / norm[far])[:, None]
            P = Q + self.center
        if self.unit_frame:
            P = (P - self.shift) * self.scale
        sqd, faces, C = self.tree.squared_distance(self.V, self.F, np.ascontiguousarray(P, dtype=np.float64))
        C = np.asarray(C)
        dist = np.sqrt(np.maximum(np.asarray(sqd), 0.0)) / self.scale
        if far.any():  # the distance from the position itself, not from where it was moved
            D = X[far] - (C[far] / self.scale + self.shift)
            size = np.abs(D).max(axis=1)
            with np.errstate(over="ignore"):
                dist[far] = size * np.linalg.norm(D / size[:, None], axis=1)
        faces = np.asarray(faces, dtype=np.int64)
        T = self.V[self.F[faces]]
        return faces, clipped_barycentric(C, T[:, 0], T[:, 1], T[:, 2]), dist


_INDEXES: weakref.WeakKeyDictionary[TriMesh, ClosestPointIndex] = weakref.WeakKeyDictionary()
_INDEX_LOCK = threading.Lock()


def closest_point_index(mesh: TriMesh) -> ClosestPointIndex:
    """The mesh's :class:`ClosestPointIndex`, built on the first call for this mesh object and kept as long as
    the mesh lives (beside it, not on it: the tree cannot be pickled, the mesh can)."""
    with _INDEX_LOCK:
        index = _INDEXES.get(mesh)
        if index is None:
            index = _INDEXES[mesh] = ClosestPointIndex(mesh)
    return index


def segment_parameter(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(k,) parameter ``t ∈ [0, 1]`` of the closest point ``A + t (B − A)`` to each point P (all (k, 3))."""
    ab = B - A
    den = np.einsum("ij,ij->i", ab, ab)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(den > 0, np.einsum("ij,ij->i", P - A, ab) / den, 0.0)
    return np.clip(t, 0.0, 1.0)


def segment_point(P: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """(k, 3) closest points of the segments [A, B] to the points P (all (k, 3))."""
    return A + segment_parameter(P, A, B)[:, None] * (B - A)


def triangle_point(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """(k, 3) closest points of the closed triangles ``(A, B, C)`` to the points ``P`` (all (k, 3)).

    The foot of the perpendicular on the triangle's plane where it lies inside the triangle, else the nearest of
    the closest points of the three edges (the Voronoi regions of the corners, edges and face: Ericson, *Real-Time
    Collision Detection*, §5.1.5); a degenerate triangle gives the closest point of its nearest edge.
    """
    P, A, B, C = (np.asarray(x, dtype=float).reshape(-1, 3) for x in (P, A, B, C))
    dot = lambda u, v: np.einsum("ij,ij->i", u, v)  # noqa: E731
    edges = np.stack([segment_point(P, A, B), segment_point(P, B, C), segment_point(P, C, A)])  # (3, k, 3)
    nearest = edges[np.argmin(np.linalg.norm(P - edges, axis=2), axis=0), np.arange(len(P))]
    nrm = np.cross(B - A, C - A)
    nn = dot(nrm, nrm)
    with np.errstate(divide="ignore", invalid="ignore"):
        # barycentric coordinates of the foot on the plane; inside when all are >= 0
        foot = P - (dot(P - A, nrm) / nn)[:, None] * nrm
        u = dot(np.cross(C - B, foot - B), nrm) / nn
        v = dot(np.cross(A - C, foot - C), nrm) / nn
    inside = (nn > 0) & (u >= 0) & (v >= 0) & (u + v <= 1)
    return np.where(inside[:, None], foot, nearest)


def point_triangle_distance(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """(k,) distances from points ``P`` to the closed triangles ``(A, B, C)`` (all (k, 3); :func:`triangle_point`)."""
    P = np.asarray(P, dtype=float).reshape(-1, 3)
    return np.linalg.norm(P - triangle_point(P, A, B, C), axis=1)


def nearest_triangle_distance(V: np.ndarray, tri: np.ndarray, X: np.ndarray) -> np.ndarray:
    """(p,) distance from each row of ``X`` to the nearest of the triangles ``tri`` (f, 3) on the vertices ``V``."""
    import igl

    if not len(X) or not len(tri):
        return np.full(len(X), np.inf)
    sqd, _, _ = igl.point_mesh_squared_distance(np.ascontiguousarray(X, dtype=np.float64),
                                               np.ascontiguousarray(V, dtype=np.float64),
                                               np.ascontiguousarray(tri, dtype=np.int64))
    return np.sqrt(np.maximum(np.asarray(sqd, dtype=float).reshape(-1), 0.0))
