"""Errors of a distance field against a reference (the paper's accuracy figures, §4).

The reference is normally the exact polyhedral distance (``baselines.ExactBaseline``).
Relative error per vertex is ``|d - d_exact| / d_exact``; sources (where it is
0/0) and vertices the reference does not reach (``d_exact = inf``) are left out.
A method that leaves a reachable vertex at ``inf`` (or ``nan``) gets an error of
``inf`` there: failures are never hidden by the statistics.
"""

from __future__ import annotations

import numpy as np

from ..validation import as_vertex_field, vertex_indices, vertex_mask


def _inputs(d, d_exact, sources):
    d_exact = as_vertex_field(d_exact, "d_exact")
    n = d_exact.shape[0]
    d = as_vertex_field(d, "d", n)
    sources = vertex_indices(sources, "sources", n)
    return d, d_exact, sources


def _compared(d_exact: np.ndarray, sources: np.ndarray) -> np.ndarray:
    keep = np.isfinite(d_exact) & (d_exact > 0)
    keep[sources] = False
    return keep


def relative_error(d, d_exact, sources) -> np.ndarray:
    """Per-vertex relative error ``|d - d_exact| / d_exact``.

    Parameters
    ----------
    d : (n,) float ndarray
        Distance field to evaluate.
    d_exact : (n,) float ndarray
        Reference distance field (``inf`` on vertices it does not reach).
    sources : (k,) int ndarray
        Source vertices.

    Returns
    -------
    (n,) float ndarray
        ``nan`` at sources and where ``d_exact`` is 0, ``inf`` or ``nan``;
        ``inf`` where ``d`` is not finite but ``d_exact`` is.

    Raises
    ------
    ValueError
        If the shapes do not match or a source index is out of range.
    """
    d, d_exact, sources = _inputs(d, d_exact, sources)
    keep = _compared(d_exact, sources)
    err = np.full(d.shape, np.nan)
    with np.errstate(invalid="ignore"):
        err[keep] = np.abs(d[keep] - d_exact[keep]) / d_exact[keep]
    err[keep & ~np.isfinite(d)] = np.inf
    return err


def percentile(x: np.ndarray, q: float) -> float:
    """Linear-interpolation percentile (as ``np.percentile``) that is ``inf``-safe.

    NumPy interpolates ``a + (inf - a) * 0 = nan``; here a percentile that
    falls on or next to an ``inf`` sample is ``inf``. ``nan`` for an empty array.
    """
    x = np.sort(np.asarray(x, dtype=np.float64).ravel())
    if x.size == 0:
        return float("nan")
    pos = q / 100.0 * (x.size - 1)
    lo = int(np.floor(pos))
    hi = min(lo + 1, x.size - 1)
    frac = pos - lo
    if frac == 0.0:
        return float(x[lo])
    if not np.isfinite(x[hi]):
        return float(x[hi])
    return float(x[lo] + (x[hi] - x[lo]) * frac)


def error_stats(d, d_exact, sources, mask=None) -> dict:
    """Summary of the errors of ``d`` against ``d_exact``.

    Parameters
    ----------
    d : (n,) float ndarray
    d_exact : (n,) float ndarray
    sources : (k,) int ndarray
    mask : (n,) bool ndarray, optional
        Restrict the comparison to these vertices.

    Returns
    -------
    dict
        ``rel_mean, rel_max, rel_p50, rel_p90, rel_p99`` (relative error),
        ``abs_mean, abs_max`` (absolute error, mesh units), ``n_compared``
        (vertices compared: not a source, ``d_exact`` finite and > 0),
        ``n_nonfinite`` (compared vertices where ``d`` is ``inf``/``nan``; each
        counts as an error ``inf``, so every statistic it enters is ``inf``),
        ``n_spurious`` (vertices the reference does not reach but ``d`` gives a
        finite value). Statistics are ``nan`` when nothing is compared.
    """
    d, d_exact, sources = _inputs(d, d_exact, sources)
    keep = _compared(d_exact, sources)
    if mask is not None:
        keep &= vertex_mask(mask, "mask", d.shape[0])
    rel = relative_error(d, d_exact, sources)[keep]
    with np.errstate(invalid="ignore"):
        ab = np.abs(d[keep] - d_exact[keep])
    ab[~np.isfinite(d[keep])] = np.inf
    return {
        "rel_mean": float(rel.mean()) if rel.size else float("nan"),
        "rel_max": float(rel.max()) if rel.size else float("nan"),
        "rel_p50": percentile(rel, 50),
        "rel_p90": percentile(rel, 90),
        "rel_p99": percentile(rel, 99),
        "abs_mean": float(ab.mean()) if ab.size else float("nan"),
        "abs_max": float(ab.max()) if ab.size else float("nan"),
        "n_compared": int(keep.sum()),
        "n_nonfinite": int(np.sum(~np.isfinite(d[keep]))),
        "n_spurious": int(np.sum(~np.isfinite(d_exact) & np.isfinite(d))),
    }
