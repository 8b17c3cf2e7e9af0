"""Point-set denoising: each point moved onto the jet (a local height polynomial) fitted to its nearest neighbours.

:func:`jet_project` is the jet smoothing of Cazals and Pouget ("Estimating differential quantities using polynomial
fitting of osculating jets", SGP 2003; CGAL's ``jet_smooth_point_set``): in the principal frame of a point's ``k``
nearest neighbours, fit the height over the tangent plane by a polynomial of degree 2 (Gaussian weights in the
distance to the point) and move the point along the frame's normal onto it. Degree 2 follows the surface's curvature,
so a clean curved surface is not shrunk (a plane fit, degree 1, pulls every point of a convex region inwards by about
``h² κ / 2``, ``h`` the neighbourhood's radius). Only the height moves: the point keeps its index and its tangential
position. Pure numpy and scipy; docs/pointclouds.md measures what it does to the distance fields of noisy clouds.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ..errors import ParameterError
from .frames import plane_fits, scatter_matrices, tangent_frames

__all__ = ["DEFAULT_DENOISE_NEIGHBOURS", "DEFAULT_PASSES", "DENOISE_PASSES", "MAX_DENOISE_PASSES", "NOISE_SAMPLE",
           "denoise_passes", "denoised_with_note", "jet_noise", "jet_project"]

#: Neighbours of each fit (the point itself not counted; a degree-2 jet has 6 coefficients). Measured on kitten and
#: bimba (docs/pointclouds.md, "Denoised clouds"): one pass of 24 (CGAL's examples) removes the most noise but costs
#: a clean cloud's order-2 field 2.1-2.4x its error; one pass of 12 costs it 1.1-1.6x, two (``denoise="jet"``)
#: 1.3-1.9x and remove more of the noise (order 2 at 0.3 %: 1.4-1.6 % against 1.8-2.0 % after one, 1.0-1.4 % with 24).
DEFAULT_DENOISE_NEIGHBOURS = 12
DEFAULT_PASSES = 1
#: Passes of jet projection of ``PointCloud``'s ``denoise="jet"`` (and of ``"auto"`` where it denoises;
#: docs/pointclouds.md, "Denoised clouds"), and the most it takes.
DENOISE_PASSES = 2
MAX_DENOISE_PASSES = 10
#: Points fitted at once: bounds the (chunk, k, 6) design arrays to a few tens of MB.
CHUNK = 20000
#: Relative ridge on the normal equations (coordinates scaled by each neighbourhood's radius): keeps a fit of
#: neighbours on one line (a scan line) finite; far below the weights of a well-spread neighbourhood.
RIDGE = 1e-9


def jet_project(P: np.ndarray, k: int = DEFAULT_DENOISE_NEIGHBOURS, passes: int = DEFAULT_PASSES,
                degree: int = 2, neighbours: np.ndarray | None = None) -> np.ndarray:
    """The points moved onto the jets fitted to their neighbourhoods, ``passes`` times.

    Parameters
    ----------
    P : (n, 3) float ndarray
        Distinct finite points, ``n > k``.
    k : int
        Neighbours of each fit, besides the point itself (at least 6 at degree 2).
    passes : int
        Times to project; each pass fits to the positions of the previous one (neighbours found again).
    degree : {1, 2}
        Of the height polynomial: 2, the jet; 1, the plane (for comparison: it shrinks curved regions).
    neighbours : (n, j) int ndarray, optional
        Each point's nearest other points, nearest first, ``j >= k``
        (:func:`~cvxgeodesic.mesh.cloud_outliers.nearest_neighbours`): the first pass's, found when None.

    Returns
    -------
    (n, 3) float ndarray
        The projected points, in ``P``'s order.
    """
    X = np.asarray(P, dtype=np.float64)
    for i in range(passes):
        if i == 0 and neighbours is not None:
            idx = np.c_[np.arange(X.shape[0]), neighbours[:, :k]]  # column 0: the point itself, as the query's
        else:
            idx = cKDTree(X).query(X, k=k + 1)[1]
        X = np.concatenate([_project(X, idx[s:s + CHUNK], np.arange(s, min(s + CHUNK, X.shape[0])), degree)
                            for s in range(0, X.shape[0], CHUNK)])
    return X


#: Points whose jets :func:`jet_noise` fits (evenly spaced in the cloud's order; all of a smaller cloud): 9 ms at 12
#: neighbours. 1,000 moved max_planck at 0.2 % noise from 0.079 to 0.073, across the threshold (bimba at 0.1 %: 0.069).
NOISE_SAMPLE = 2000


def jet_noise(P: np.ndarray, dist: np.ndarray, idx: np.ndarray, points: np.ndarray | None = None,
              k: int = DEFAULT_DENOISE_NEIGHBOURS) -> float:
    """The noise of a cloud in units of its spacing: the median distance from a point to the jet of its ``k`` nearest
    neighbours, over its mean distance to its 6 nearest.

    A jet (degree 2) follows the surface's curvature, so on a clean smooth scan the distance is about 0 (0.002-0.025
    at 12 neighbours on the vertex clouds of 10 shared scans), and it grows with the noise: about 0.55 of the noise's
    standard deviation over the spacing (kitten, bimba and max_planck at 0.1-0.3 % of the diagonal). Detail finer
    than the neighbourhood reads as noise too (lucy_20k 0.116, buddha 0.098), but it grows with ``k`` where noise
    does not: from 12 to 30 neighbours by 2.2-2.7× on those clean clouds, by 1.2-1.6× on the noisy ones.

    Parameters
    ----------
    P : (n, 3) float ndarray
        The points.
    dist, idx : (n, j) ndarray
        Each point's nearest other points, nearest first (:func:`~cvxgeodesic.mesh.cloud_outliers.nearest_neighbours`,
        ``j >= k``).
    points : (m,) int ndarray, optional
        The points to sample from (all when None); :data:`NOISE_SAMPLE` of them, evenly spaced.
    k : int
        Neighbours of each jet (at most ``j``).

    Returns
    -------
    float
    """
    points = np.arange(P.shape[0]) if points is None else np.asarray(points)
    rows = points[np.unique(np.linspace(0, points.size - 1, min(NOISE_SAMPLE, points.size)).astype(np.int64))]
    k = min(k, idx.shape[1])
    moved = np.linalg.norm(_project(P, np.c_[rows, idx[rows, :k]], rows, 2) - P[rows], axis=1)
    spacing = dist[rows, :6].mean(axis=1)
    return float(np.median(moved / np.maximum(spacing, np.finfo(float).tiny)))


def _project(X: np.ndarray, idx: np.ndarray, rows: np.ndarray, degree: int) -> np.ndarray:
    """Points ``X[rows]`` (m, 3) projected on the jets of their neighbours ``X[idx]`` (idx: (m, k + 1), column 0 the
    point itself)."""
    p = X[rows]
    Q = X[idx] - p[:, None, :]
    r2 = np.einsum("mkj,mkj->mk", Q, Q)
    h2 = r2.max(axis=1, keepdims=True)  # squared radius of the neighbourhood
    h2[h2 <= 0.0] = 1.0
    w = np.exp(-r2 / h2)  # Gaussian of width ~ the radius: the far neighbours count ~e^-1 as much
    c = np.einsum("mk,mkj->mj", w, Q) / w.sum(axis=1, keepdims=True)
    D = Q - c[:, None, :]
    frame = tangent_frames(plane_fits(scatter_matrices(D, w))[1])  # column 0 the normal
    scale = 1.0 / np.sqrt(h2)  # (height, u, v) in units of the radius
    z, u, v = (np.einsum("mkj,mj->mk", Q, frame[:, :, c]) * scale for c in range(3))
    one = np.ones_like(u)
    cols = [one, u, v] + ([u * u, u * v, v * v] if degree == 2 else [])
    A = np.stack(cols, axis=-1)  # (m, k + 1, terms)
    AtW = A.transpose(0, 2, 1) * w[:, None, :]
    N = AtW @ A
    N += RIDGE * np.trace(N, axis1=1, axis2=2)[:, None, None] * np.eye(A.shape[-1])
    coef = np.linalg.solve(N, np.einsum("mtk,mk->mt", AtW, z)[..., None])[..., 0]
    height = coef[:, 0] * np.sqrt(h2[:, 0])  # the fit's height at the point's own tangent position (u = v = 0)
    return p + height[:, None] * frame[:, :, 0]


def denoise_passes(denoise: Any) -> int | None:
    """The passes of jet projection that ``PointCloud``'s ``denoise`` asks for (0: none), None for ``"auto"``
    (decided by the cloud's noise)."""
    if denoise is None:
        return 0
    if isinstance(denoise, str) and denoise == "auto":
        return None
    if isinstance(denoise, str) and denoise == "jet":
        return DENOISE_PASSES
    if isinstance(denoise, int | np.integer) and not isinstance(denoise, bool) and 0 <= denoise <= MAX_DENOISE_PASSES:
        return int(denoise)
    raise ParameterError(f"denoise must be 'auto', None, 'jet' or an integer from 0 to {MAX_DENOISE_PASSES} "
                         f"(passes of jet projection), got {denoise!r}")


def denoised_with_note(P: np.ndarray, passes: int, name: str, notes: list[str],
                       neighbours: np.ndarray | None = None, why: str | None = None) -> np.ndarray:
    """``P`` moved onto the jets of its neighbourhoods ``passes`` times, with a note of how far (and ``why``, for
    ``denoise="auto"``); ``neighbours`` as :func:`~cvxgeodesic.mesh.denoise.jet_project` takes them."""
    k = min(DEFAULT_DENOISE_NEIGHBOURS, P.shape[0] - 1)
    X = jet_project(P, k=k, passes=passes, neighbours=neighbours)
    moved = np.linalg.norm(X - P, axis=1)
    notes.append(f"{name}: denoised{f' ({why})' if why else ''}: the points moved onto the degree-2 jets of their "
                 f"{k} nearest neighbours ({passes} pass{'es' if passes > 1 else ''}; mean move {moved.mean():.3g}, "
                 f"max {moved.max():.3g}); the triangles and lengths are the moved points'"
                 + ("; denoise=None keeps the points as given" if why else ""))
    return X
