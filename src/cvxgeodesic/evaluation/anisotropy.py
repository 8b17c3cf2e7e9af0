"""Triangle anisotropy (paper §4.3.2, Fig. 7)."""

from __future__ import annotations

import numpy as np

from ._validate import check_mesh


def triangle_anisotropy(mesh) -> np.ndarray:
    """Per-triangle anisotropy ``τ(t) = P·H / (2√3·S)``.

    ``P`` is the half-perimeter, ``H`` the longest edge and ``S`` the area, so
    an equilateral triangle has ``τ = 1`` and any other triangle ``τ > 1``
    (a right isosceles triangle: ``(1 + √2)/√3 ≈ 1.394``).

    Parameters
    ----------
    mesh : TriMesh

    Returns
    -------
    (m,) float ndarray
        ``inf`` on zero-area triangles.
    """
    mesh = check_mesh(mesh)
    lengths = mesh.cell_facet_measures  # (m, 3): the edge opposite each corner
    P = 0.5 * lengths.sum(axis=1)
    H = lengths.max(axis=1)
    with np.errstate(divide="ignore"):
        return P * H / (2.0 * np.sqrt(3.0) * mesh.face_areas)


def mesh_anisotropy(mesh) -> float:
    """Mesh anisotropy ``τ(T)``: the mean of :func:`triangle_anisotropy`.

    Zero-area triangles (``τ = inf``) are left out of the mean.

    Parameters
    ----------
    mesh : TriMesh

    Returns
    -------
    float
        ``>= 1``; 1 for a mesh of equilateral triangles.
    """
    tau = triangle_anisotropy(mesh)
    tau = tau[np.isfinite(tau)]
    return float(tau.mean()) if tau.size else float("nan")
