"""Isolated outliers and line-like neighbourhoods of a point cloud, found before its fans are built.

A stray point off the surface (a LiDAR return in the air) is among the nearest neighbours of the surface points below
it, so their local Delaunay fans (:mod:`cvxgeodesic.mesh.pointcloud`) reach up to it with long triangles: the field
would take shortcuts through it. A point whose neighbours lie on a line (a wire sticking out of a scan) has no surface
around it: its fan is empty or made of slivers. :func:`find_defects` finds both from statistics of every point's
:data:`DEFECT_NEIGHBOURS` nearest neighbours, all scale-free:

- ``spread``: the point's mean distance to its neighbours over the median of that mean among its neighbours (a
  local outlier factor: about 1 on the surface whatever the density, the outlier's height over the local spacing for
  a point off the surface);
- ``height``: the point's distance to the plane fitted to its neighbours (without it), over the same local spacing;
- ``isolation``: the point's mean distance over the cloud's median of it (statistical outlier removal as open3d does
  it, which a group of outliers that are each other's neighbours cannot hide from);
- ``flatness``: the second eigenvalue of the covariance of the neighbours over the first (0 on a line). Over fewer
  neighbours (10) it flagged 340 points of beetle_open's vertices, which lie along scan lines a few spacings apart:
  their 30 neighbours span several lines, a surface;
- ``group``: the size of the point's component in the graph that joins each point to its neighbours within
  :data:`GAP` times its nearest neighbour's distance. A group of outliers is a small component (at most
  :data:`DEFECT_NEIGHBOURS` points); a sparsely sampled part of the surface is joined to the rest. Isolation alone
  (above 10, the rule this replaces) flagged 50 of the 18,944 vertices of the CAD part thingi_32770, which lie on the
  edges of large flat faces; in a group, isolation above :data:`SPREAD_ISOLATION` flags a point (planted groups of 5
  found 5 spacings off: 26 → 79 of 540). The other rules were not given this condition: planted outliers that they
  alone find (a point beside the surface, nearly in its neighbours' plane) are not in small groups, and left in the
  fans they moved the field of max_planck's cloud by up to 1.5-5.4 % at some points.

The thresholds below were measured with benchmarks/cloud_outliers.py (docs/pointclouds.md has the numbers): no
false positive on the vertices and random surface points of the shared scans, clean and with Gaussian noise of 0.1 %
and 0.3 % of the diagonal, and the planted outliers listed there found.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .frames import neighbourhood_planes

__all__ = ["DEFECT_NEIGHBOURS", "GAP", "HEIGHT_MADS", "LINE_TOL", "SPREAD_HEIGHT",
           "SPREAD_ISOLATION", "SPREAD_MAX", "CloudDefects", "defect_statistics", "find_defects",
           "nearest_neighbours"]

#: Neighbours the statistics are taken over (fewer on a cloud of at most this many points): potpourri3d's fan size,
#: at which the thresholds below were measured.
DEFECT_NEIGHBOURS = 30
#: ``spread`` above this: an outlier (the 36 clouds of benchmarks/cloud_outliers.py: at most 1.85, max_planck's
#: uneven vertices; a random point in every face of the decimated lucy_20k: 4.7).
SPREAD_MAX = 6.0
#: ``spread`` above the first and ``height`` above the second: an outlier (a point lifted a few spacings off the
#: surface; its 30 neighbours still lie below it).
SPREAD_HEIGHT = (1.8, 1.5)
#: A noisy cloud's heights are larger everywhere: the height threshold is at least the cloud's median height plus
#: this many median absolute deviations (on the shared scans at 0.3 % noise: up to 1.9).
HEIGHT_MADS = 15.0
#: ``spread`` and ``isolation`` both above this: an outlier (one far enough off for its neighbours' plane to tilt
#: towards it); ``isolation`` above it in a group apart from the rest (:data:`GAP`): an outlier (a group of outliers
#: among each other's neighbours, whose ``spread`` is 1).
SPREAD_ISOLATION = 3.0
#: Points within this many times a point's nearest-neighbour distance of it (among its neighbours) are joined to it;
#: a component of at most :data:`DEFECT_NEIGHBOURS` points is a group apart from the surface.
GAP = 3.0
#: ``flatness`` below this: the point's neighbourhood is a line (its width under 5.5 % of its length), no surface.
LINE_TOL = 3e-3


@dataclass(frozen=True)
class CloudDefects:
    """What :func:`find_defects` found: point indices, ascending.

    Attributes
    ----------
    outliers : (a,) int64 ndarray
        Isolated points off the surface.
    lines : (b,) int64 ndarray
        Points whose neighbourhood lies on a line (not among ``outliers``).
    grouped : (c,) int64 ndarray
        The outliers in a small group apart from the rest (``group`` of :func:`defect_statistics`).
    """

    outliers: np.ndarray
    lines: np.ndarray
    grouped: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))

    @property
    def points(self) -> np.ndarray:
        """(a + b,) int64 ndarray: both kinds, ascending."""
        return np.union1d(self.outliers, self.lines)


def nearest_neighbours(P: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Each point's ``k`` nearest other points (capped at ``n - 1``), nearest first.

    Returns
    -------
    dist, idx : (n, k) ndarray
        Their distances (float) and indices (int).
    """
    from scipy.spatial import cKDTree

    dist, idx = cKDTree(P).query(P, k=min(k, P.shape[0] - 1) + 1)
    return dist[:, 1:], idx[:, 1:]  # column 0: the point itself (distinct points)


def defect_statistics(P: np.ndarray, k: int = DEFECT_NEIGHBOURS,
                      knn: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """The four statistics of every point (the module's docstring defines them).

    Parameters
    ----------
    P : (n, 3) float ndarray
        Distinct points, ``n >= 2``.
    k : int
        Neighbours of each point (capped at ``n - 1``).
    knn : (dist, idx), optional
        :func:`nearest_neighbours` of ``P`` for ``k`` or more (the first ``k`` columns are read).

    Returns
    -------
    (n, 5) float ndarray
        Columns ``spread``, ``height``, ``isolation``, ``flatness``, ``group``.
    """
    k = min(k, P.shape[0] - 1)
    dist, idx = knn if knn is not None else nearest_neighbours(P, k)
    dist, idx = dist[:, :k], idx[:, :k]
    mean = dist.mean(axis=1)
    local = np.median(mean[idx], axis=1)
    centre, _, w, normal = neighbourhood_planes(P[idx])  # w ascending
    height = np.abs(np.einsum("ni,ni->n", P - centre, normal))
    flat = w[:, 1] / np.maximum(w[:, 2], np.finfo(float).tiny)
    return np.c_[mean / local, height / local, mean / np.median(mean), flat, _group_sizes(dist, idx)]


def _group_sizes(dist: np.ndarray, idx: np.ndarray) -> np.ndarray:
    """(n,) float: the size of each point's component of the graph joining a point to those of its neighbours within
    :data:`GAP` times its nearest neighbour's distance (either way)."""
    import scipy.sparse as sp
    from scipy.sparse.csgraph import connected_components

    n = idx.shape[0]
    near = dist <= GAP * dist[:, :1]
    graph = sp.coo_matrix((np.ones(np.count_nonzero(near)), (np.nonzero(near)[0], idx[near])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    return np.bincount(labels)[labels].astype(float)


def find_defects(P: np.ndarray, k: int = DEFECT_NEIGHBOURS,
                 knn: tuple[np.ndarray, np.ndarray] | None = None) -> CloudDefects:
    """Isolated outliers and points of line-like neighbourhoods of the distinct points ``P`` (n, 3); ``knn`` as
    :func:`defect_statistics` takes it.

    Returns
    -------
    CloudDefects
    """
    spread, height, isolation, flat, group = defect_statistics(P, k, knn).T
    med = np.median(height)
    tall = height > max(SPREAD_HEIGHT[1], med + HEIGHT_MADS * np.median(np.abs(height - med)))
    apart = group <= min(k, P.shape[0] - 1)
    # isolated and either spread or in a group apart from the rest: a group whose 30 nearest include far points of the
    # surface has a surface's spread and flatness, but its fans would join it to the surface with long triangles
    out = ((spread > SPREAD_MAX) | ((spread > SPREAD_HEIGHT[0]) & tall)
           | ((spread > SPREAD_ISOLATION) | apart) & (isolation > SPREAD_ISOLATION))
    line = (flat < LINE_TOL) & ~out
    return CloudDefects(*(np.flatnonzero(mask).astype(np.int64) for mask in (out, line, out & apart)))
