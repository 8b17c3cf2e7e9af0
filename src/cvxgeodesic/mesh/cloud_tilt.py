"""Fan triangles that stand across the surface a cloud samples: across a thin wall, or a crease sharper than 60°.

A point's fan is a Delaunay 1-ring in the plane fitted to its neighbours. Where a wall is about two spacings thin, the
points of its other side project into that plane among the near side's, and the fan joins them: its triangles stand
across the wall, and every field through them crosses it (fandisk's vertex cloud: 166 edges of the fans, between the
two sides of a flange 1.8 spacings thick, tripled its order-1 error). Such a triangle is turned far from the plane
fitted around its corners, and one of its corners lies far from that plane: :func:`tilted_triangles` finds the
triangles turned by more than :data:`TILT_ANGLE` degrees from the plane of the :data:`TILT_NEIGHBOURS` nearest points
of one of their corners, with a corner farther from such a plane than :data:`TILT_OFFSET` times the plane's spread
(noise tilts triangles too, but by its own height). :class:`~cvxgeodesic.mesh.pointcloud.PointCloud` leaves them out
of fans built without normals, and gives a point that this would cut off its whole fan back
(:func:`untilted_fans`).

Measured 2026-12-06 (``benchmarks/point_clouds.py --meshes kitten bimba max_planck fandisk --sets union --no-order2``,
from point n/2, one thread; mean error without → with): ``qclp`` order 1 on fandisk's cloud 5.24 → 1.84 % clean,
4.97 → 2.30 % at 0.1 % noise, 6.05 → 3.95 % at 0.3 %; max_planck 1.87 → 1.70, 1.59 → 1.42, 1.54 → 1.41 %; kitten
unchanged (1.14, 0.94, 2.80 → 2.83 %); bimba 0.67 → 0.61, 0.64, 3.44 → 3.93 % (its 0.3 % noise is 1/2.3 of its
spacing). The default (order 2 on a copy): fandisk 3.50 → 0.68, 3.69 → 1.41, 4.98 → 3.30 %. The angle alone (no
offset test) was measured too: it cut 245 points off bimba at 0.3 % noise (20,030 of its 46K triangles) and made its
order-1 error 5.4 %. 8 and 15 neighbours, and 50° and 70°: 8 was equal, 15 less accurate on the CAD part, 70° cut
points off, 50° kept more walls.
"""

from __future__ import annotations

import numpy as np

from .frames import neighbourhood_planes
from .simplex import unique_rows

__all__ = ["TILT_ANGLE", "TILT_NEIGHBOURS", "TILT_OFFSET", "principal_planes", "stranded_points", "tilted_triangles",
           "triangle_components", "untilted_fans"]

#: Neighbours of each point's principal plane: few enough that the plane of a point next to a crease is its own
#: face's (at 30, the fans' count, fandisk's clean field kept 2.91 % instead of 1.55 %).
TILT_NEIGHBOURS = 10
#: A triangle turned by more than this from the principal plane of one of its corners is left out; the angle of
#: :data:`~cvxgeodesic.mesh.pointcloud.NORMAL_FAN_ANGLE` for oriented normals.
TILT_ANGLE = 60.0
#: ... and one of its corners lies farther than this many times the spread of a corner's plane from that plane: a wall
#: is thicker than the noise; noise tilts triangles too (at 0.3 % noise, 1/2.3 of bimba's spacing, the angle alone
#: left out 20,030 of its 46K triangles and cut 245 points off).
TILT_OFFSET = 3.0


def principal_planes(P: np.ndarray, idx: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The plane fitted to each point's nearest other points.

    Parameters
    ----------
    P : (n, 3) float ndarray
        Distinct points.
    idx : (n, k) int ndarray
        Each point's nearest other points, nearest first
        (:func:`~cvxgeodesic.mesh.cloud_outliers.nearest_neighbours`); the first :data:`TILT_NEIGHBOURS` are read.

    Returns
    -------
    normals : (n, 3) float ndarray
        Unit normals, unoriented.
    centres : (n, 3) float ndarray
        The neighbours' centroids (the planes pass through them).
    spread : (n,) float ndarray
        The root mean square distance of the neighbours from the plane.
    """
    centres, Q, _, normals = neighbourhood_planes(P[idx[:, :TILT_NEIGHBOURS]])
    # the spread from the heights: the least eigenvalue (their sum of squares) is good to 1e-16 of the largest only
    heights = np.einsum("nki,ni->nk", Q, normals)
    return normals, centres, np.sqrt(np.einsum("nk,nk->n", heights, heights) / Q.shape[1])


Planes = tuple[np.ndarray, np.ndarray, np.ndarray]


def untilted_fans(P: np.ndarray, tri: np.ndarray, owner: np.ndarray,
                  planes: Planes) -> tuple[np.ndarray, np.ndarray, int, int]:
    """The fans' triangles less the tilted ones (:func:`tilted_triangles`), and the whole fan of every point that
    leaving them out would cut off from the piece it reaches with them.

    Parameters
    ----------
    P : (n, 3) float ndarray
    tri : (m, 3) int64 ndarray
        Every fan's triangles, rows sorted.
    owner : (m,) int64 ndarray
        The point whose fan holds each.
    planes : (normals, centres, spread)
        :func:`principal_planes` of ``P``.

    Returns
    -------
    tri, owner : ndarray
        The triangles kept, and their owners.
    dropped : int
        Distinct triangles left out.
    restored : int
        Points whose fan was given back (with a tilted triangle in it).
    """
    uniq, inverse, _ = unique_rows(tri, P.shape[0])  # each triangle once (a fan's neighbours hold it too)
    tilted = tilted_triangles(P, uniq, planes)[inverse]
    if not tilted.any():
        return tri, owner, 0, 0
    stranded = stranded_points(P.shape[0], tri, tri[~tilted])
    given_back = np.isin(owner, stranded)
    keep = ~tilted | given_back
    dropped = np.unique(inverse[~keep]).size
    return tri[keep], owner[keep], dropped, np.unique(owner[tilted & given_back]).size


def stranded_points(n: int, tri: np.ndarray, kept: np.ndarray) -> np.ndarray:
    """The points that the triangles ``kept`` (a subset of ``tri``) leave outside the largest part of their piece of
    ``tri``'s edge graph (the largest by points; the lowest label among equals).

    Parameters
    ----------
    n : int
        Points.
    tri, kept : (m, 3), (k, 3) int arrays
        Triangles (indices below ``n``), and those kept.

    Returns
    -------
    (s,) int64 ndarray
        Ascending.
    """
    before, after = triangle_components(n, tri), triangle_components(n, kept)
    codes, counts = np.unique(before.astype(np.int64) * n + after, return_counts=True)  # labels are below n
    pairs = np.c_[codes // n, codes % n]
    best = np.full(before.max() + 1, -1)
    ranked = np.lexsort((-counts, pairs[:, 0]))  # per piece, the largest part first
    first = np.r_[True, pairs[ranked[1:], 0] != pairs[ranked[:-1], 0]]
    best[pairs[ranked[first], 0]] = pairs[ranked[first], 1]
    return np.flatnonzero(after != best[before]).astype(np.int64)


def triangle_components(n: int, tri: np.ndarray) -> np.ndarray:
    """The component label of every point in the edge graph of ``tri`` (a point in no triangle is its own): the labels
    of :attr:`~cvxgeodesic.mesh.simplex.SimplexMesh.component_labels` without building a mesh."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    i = np.r_[tri[:, 0], tri[:, 1], tri[:, 2]]
    j = np.r_[tri[:, 1], tri[:, 2], tri[:, 0]]
    graph = sp.coo_matrix((np.ones(i.size, dtype=bool), (i, j)), shape=(n, n))  # repeated edges stay one edge
    return connected_components(graph, directed=False)[1]


def tilted_triangles(P: np.ndarray, tri: np.ndarray, planes: Planes) -> np.ndarray:
    """Which triangles stand across the surface: turned by more than :data:`TILT_ANGLE` from the plane of one of their
    corners, with a corner farther than :data:`TILT_OFFSET` times a corner plane's spread from that plane.

    Parameters
    ----------
    P : (n, 3) float ndarray
        The points.
    tri : (m, 3) int array
        Triangles (indices into ``P``).
    planes : (normals, centres, spread)
        :func:`principal_planes` of ``P``.

    Returns
    -------
    (m,) bool ndarray
        True where tilted; a triangle of zero area is not (it has no plane).
    """
    normals, centres, spread = planes
    n = np.cross(P[tri[:, 1]] - P[tri[:, 0]], P[tri[:, 2]] - P[tri[:, 0]])
    length = np.linalg.norm(n, axis=1)
    flat = length > 0
    n[flat] /= length[flat, None]
    turned = np.abs(np.einsum("tij,tj->ti", normals[tri], n)).min(axis=1) < np.cos(np.radians(TILT_ANGLE))
    far = np.zeros(tri.shape[0], dtype=bool)
    for a in range(3):  # each corner's plane against the other two corners
        for b in (c for c in range(3) if c != a):
            height = np.abs(np.einsum("ij,ij->i", normals[tri[:, a]], P[tri[:, b]] - centres[tri[:, a]]))
            far |= height > TILT_OFFSET * spread[tri[:, a]]
    return flat & turned & far
