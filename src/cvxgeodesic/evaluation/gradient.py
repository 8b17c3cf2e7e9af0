"""Statistics of the per-cell gradient norm ``‖∇d|_t‖`` (paper Fig. 2), on triangles or tetrahedra.

A true distance field has ``‖∇d‖ = 1`` almost everywhere. The linear
interpolant of the exact distance has norms near 1 on most triangles and below
1 on the triangles the ridge (cut locus) crosses. Every statistic here is
weighted by the cells' areas (volumes) and ignores cells with a non-finite vertex value or zero measure.
"""

from __future__ import annotations

import numpy as np

from ..operators.gradient import gradient_norms
from ..validation import as_vertex_field, vertex_indices
from ._validate import check_mesh


def _norms_and_weights(mesh, d, sources) -> tuple[np.ndarray, np.ndarray]:
    """The gradient norms (c,) of the cells used (finite values, nonzero measure, no source) and their measures (c,)."""
    mesh = check_mesh(mesh, volumes=True)
    d = as_vertex_field(d, "d", mesh.n_vertices)
    finite_v = np.isfinite(d)
    valid = finite_v[mesh.cells].all(axis=1) & (mesh.cell_measures > 0)
    if sources is not None:
        valid &= ~np.isin(mesh.cells, vertex_indices(sources, "sources", mesh.n_vertices)).any(axis=1)
    return gradient_norms(mesh, np.where(finite_v, d, 0.0))[valid], mesh.cell_measures[valid]


def gradient_norm_stats(mesh, d, *, sources=None, band: tuple[float, float] = (0.9, 1.1)) -> dict:
    """Area-weighted statistics of the per-triangle gradient norm.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    d : (n,) float ndarray
        Vertex values of a distance field.
    sources : (k,) int ndarray, optional
        If given, triangles incident to a source are left out (there the exact
        field's interpolant has ``‖∇d‖ > 1``, the paper's Situation #1).
    band : (float, float)
        The interval counted as "unit norm".

    Returns
    -------
    dict
        ``share_{lo}_{hi}`` (area share of triangles with ``lo <= ‖∇d‖ <= hi``;
        ``share_0.9_1.1`` with the default band), ``share_below_{lo}``,
        ``share_above_{hi}``, ``mean`` (area-weighted), ``max``, ``n_triangles``
        (triangles used). Shares and mean are ``nan`` if no triangle is used.
    """
    lo, hi = (float(b) for b in band)
    if not lo <= hi:
        raise ValueError(f"band must be (lo, hi) with lo <= hi, got {band!r}")
    norms, area = _norms_and_weights(mesh, d, sources)
    total = area.sum()
    nan = float("nan")

    def share(sel):
        return float(area[sel].sum() / total) if total > 0 else nan

    return {
        f"share_{lo:g}_{hi:g}": share((norms >= lo) & (norms <= hi)),
        f"share_below_{lo:g}": share(norms < lo),
        f"share_above_{hi:g}": share(norms > hi),
        "mean": float(np.sum(area * norms) / total) if total > 0 else nan,
        "max": float(norms.max()) if norms.size else nan,
        "n_triangles": int(norms.size),
    }


def gradient_norm_histogram(mesh, d, bins=50, *, range=None, sources=None) -> tuple[np.ndarray, np.ndarray]:
    """Area-weighted histogram of the per-triangle gradient norm (paper Fig. 2).

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    d : (n,) float ndarray
    bins : int or (b + 1,) float ndarray
        As in :func:`numpy.histogram`.
    range : (float, float), optional
        Histogram range; default: the range of the norms.
    sources : (k,) int ndarray, optional
        If given, triangles incident to a source are left out.

    Returns
    -------
    counts : (b,) float ndarray
        Share of the total area of the used triangles falling in each bin
        (sums to 1 when ``range`` covers every norm).
    edges : (b + 1,) float ndarray
        Bin edges.
    """
    norms, area = _norms_and_weights(mesh, d, sources)
    total = area.sum()
    counts, edges = np.histogram(norms, bins=bins, range=range, weights=area)
    if total > 0:
        counts = counts / total
    return counts, edges
