"""Small geometric kernels shared by the mesh-level modules (closest points, field transfer)."""

from __future__ import annotations

import numpy as np


def clipped_barycentric(P: np.ndarray, A: np.ndarray, B: np.ndarray, C: np.ndarray) -> np.ndarray:
    """(k, 3) barycentric coordinates of points ``P`` in triangles ``(A, B, C)``, clipped to the triangle.

    Degenerate triangles get weight 1 on their corner nearest to the point.
    """
    v0, v1, v2 = B - A, C - A, P - A
    d00 = np.einsum("ij,ij->i", v0, v0)
    d01 = np.einsum("ij,ij->i", v0, v1)
    d11 = np.einsum("ij,ij->i", v1, v1)
    d20 = np.einsum("ij,ij->i", v2, v0)
    d21 = np.einsum("ij,ij->i", v2, v1)
    denom = d00 * d11 - d01 * d01
    good = denom > 1e-14 * np.maximum(d00 * d11, np.finfo(float).tiny)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = (d11 * d20 - d01 * d21) / denom
        w = (d00 * d21 - d01 * d20) / denom
    W = np.column_stack([1.0 - v - w, v, w])
    W = np.clip(W, 0.0, 1.0)
    s = W.sum(axis=1)
    good &= np.isfinite(s) & (s > 0)
    W[good] /= s[good, None]
    if not good.all():
        bad = np.flatnonzero(~good)
        dist = np.stack([np.linalg.norm(P[bad] - X[bad], axis=1) for X in (A, B, C)], axis=1)
        W[bad] = 0.0
        W[bad, np.argmin(dist, axis=1)] = 1.0
    return W
