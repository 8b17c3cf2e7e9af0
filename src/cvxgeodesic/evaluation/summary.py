"""One evaluation record of a distance field against a reference: what compare, demo and the report print.

:func:`summarize_field` measures a field against the reference (accuracy, gradient norms, ridge
sharpness), :func:`summarize_run` reads the solve record (solver, status, times, iterations,
notes), :func:`summarize` joins both for a :class:`~cvxgeodesic.GeodesicResult`. Every record has
the keys of :data:`SUMMARY_KEYS`; a value that was not measured is None.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..operators.laplacian import barycentric_mass
from ._validate import check_mesh
from .errors import error_stats, relative_error
from .gradient import gradient_norm_stats
from .smoothness import smoothness_report

__all__ = [
    "ACCURACY_KEYS", "GRADIENT_KEYS", "RUN_KEYS", "SMOOTHNESS_KEYS", "SUMMARY_KEYS",
    "summarize", "summarize_field", "summarize_run",
]

#: Errors against the reference (sources and vertices it does not reach left out, see
#: :func:`~cvxgeodesic.evaluation.error_stats`): relative ``rel_mean, rel_max, rel_p99``, absolute
#: ``abs_max`` (mesh units), ``area_rel_mean`` (relative error averaged over the mesh, each vertex
#: weighted by a third of the area of its faces, a quarter of the volume of its tetrahedra), ``n_compared``,
#: ``n_nonfinite``.
ACCURACY_KEYS = ("rel_mean", "rel_max", "rel_p99", "abs_max", "area_rel_mean", "n_compared", "n_nonfinite")
#: Per-cell ``‖∇d‖``, weighted by area (volume), source cells left out (see
#: :func:`~cvxgeodesic.evaluation.gradient_norm_stats`): ``grad_mean``, ``grad_max``, and
#: ``grad_unit_share``, the area share with ``0.9 ≤ ‖∇d‖ ≤ 1.1``.
GRADIENT_KEYS = ("grad_mean", "grad_max", "grad_unit_share")
#: Ridge sharpness, surfaces only (see :func:`~cvxgeodesic.evaluation.smoothness_report`): the 95th percentile of
#: the normal-derivative jump in the band around the reference's ridge (``ridge_jump_p95``), the
#: reference's own (``exact_ridge_jump_p95``), their ratio (``ridge_jump_ratio``, < 1: smoother than
#: the reference), the mean relative error off and on that band, and the band's size in vertices.
SMOOTHNESS_KEYS = ("ridge_jump_p95", "ridge_jump_ratio", "exact_ridge_jump_p95", "off_ridge_rel_mean",
                   "on_ridge_rel_mean", "band_vertices")
#: The solve: ``method, solver, status``, ``time_s`` (set-up + solve, or the wall-clock time given),
#: ``setup_s``, ``solve_s``, ``iterations``, ``notes`` (the substitutions the library made, a list of str).
RUN_KEYS = ("method", "solver", "status", "time_s", "setup_s", "solve_s", "iterations", "notes")
#: Every key of a :func:`summarize` record, in this order.
SUMMARY_KEYS = RUN_KEYS + ACCURACY_KEYS + GRADIENT_KEYS + SMOOTHNESS_KEYS


def _area_rel_mean(mesh, d, d_exact, sources) -> float:
    rel = relative_error(d, d_exact, sources)
    keep = ~np.isnan(rel)  # compared vertices; an unreached one is +inf and stays in
    w = barycentric_mass(mesh).diagonal()[keep]  # a third of each triangle, a quarter of each tetrahedron
    if not keep.any() or w.sum() <= 0:
        return float("nan")
    with np.errstate(invalid="ignore"):
        return float(np.sum(w * rel[keep]) / w.sum())


def summarize_field(mesh, d, d_exact, sources, *, smoothness: bool = True, gradient: bool = True) -> dict:
    """Accuracy, gradient-norm and ridge statistics of a field against a reference.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        ``n`` vertices.
    d : (n,) float array_like
        The field to measure.
    d_exact : (n,) float array_like
        The reference (normally the exact distance); ``inf`` where it does not reach.
    sources : (k,) int array_like
        Source vertices (left out of the errors and the gradient statistics).
    smoothness : bool, default True
        Measure the ridge (:data:`SMOOTHNESS_KEYS`; surfaces only: None in a volume); the costliest part, off
        leaves them None.
    gradient : bool, default True
        Measure the gradient norms (:data:`GRADIENT_KEYS`); off leaves them None.

    Returns
    -------
    dict
        The keys of :data:`ACCURACY_KEYS`, :data:`GRADIENT_KEYS` and :data:`SMOOTHNESS_KEYS`:
        Python floats and ints, None where not measured.

    Raises
    ------
    ValueError
        A field whose shape is not ``(n,)``, or a source index out of range (the message names it).
    """
    mesh = check_mesh(mesh, volumes=True)
    st = error_stats(d, d_exact, sources)
    out: dict[str, Any] = {k: st[k] for k in ACCURACY_KEYS if k != "area_rel_mean"}
    out["area_rel_mean"] = _area_rel_mean(mesh, d, d_exact, sources)
    out.update(dict.fromkeys(GRADIENT_KEYS + SMOOTHNESS_KEYS))
    if gradient:
        g = gradient_norm_stats(mesh, d, sources=sources)
        out.update(grad_mean=g["mean"], grad_max=g["max"], grad_unit_share=g["share_0.9_1.1"])
    if smoothness and mesh.dim == 2:  # dimension: the ridge (evaluation/smoothness.py) is measured on surfaces only
        sm = smoothness_report(mesh, d, d_exact, sources)
        out.update({k: sm[k] for k in SMOOTHNESS_KEYS})
    return {k: (float(v) if isinstance(v, float | np.floating) else int(v) if isinstance(v, np.integer) else v)
            for k, v in out.items()}


def summarize_run(info, *, time_s: float | None = None) -> dict:
    """The solve part of a record, read from a :class:`~cvxgeodesic.SolveInfo`.

    Parameters
    ----------
    info : SolveInfo
        The solve record (``res.info``).
    time_s : float, optional
        Wall-clock seconds to report as ``time_s``; default ``setup_time + solve_time``.

    Returns
    -------
    dict
        The keys of :data:`RUN_KEYS`.
    """
    setup, solve = float(info.setup_time), float(info.solve_time)
    return {"method": str(info.method), "solver": str(info.solver), "status": str(info.status),
            "time_s": float(time_s) if time_s is not None else setup + solve, "setup_s": setup, "solve_s": solve,
            "iterations": int(info.iterations), "notes": list(info.notes)}


def summarize(mesh, result, d_exact, *, time_s: float | None = None, smoothness: bool = True,
              gradient: bool = True) -> dict:
    """The whole record of one result: :func:`summarize_run` and :func:`summarize_field` joined.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        The mesh the result was computed on.
    result : GeodesicResult
        ``distance`` ((n,) floats), ``sources`` and ``info``.
    d_exact : (n,) float array_like
        The reference field.
    time_s, smoothness, gradient
        As for :func:`summarize_run` and :func:`summarize_field`.

    Returns
    -------
    dict
        The keys of :data:`SUMMARY_KEYS`, in that order.
    """
    rec = summarize_run(result.info, time_s=time_s)
    rec.update(summarize_field(mesh, result.distance, d_exact, result.sources, smoothness=smoothness,
                               gradient=gradient))
    return {k: rec[k] for k in SUMMARY_KEYS}
