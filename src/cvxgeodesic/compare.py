"""Side-by-side comparison of methods on one mesh: the engine behind ``cvxgeodesic compare``.

:func:`run_compare` solves the same sources with every requested method,
measures each field against the exact polyhedral distance (MMP, method
``"exact"``, computed once and reused), and writes into an output folder

* ``compare.csv``: one row per method (columns in :data:`CSV_COLUMNS`);
* ``field_<method>.png``: the field with isolines (:func:`~cvxgeodesic.plotting.plot_field`),
  all methods on the colour range and isoline levels of the exact field, so the pictures compare;
* ``error_<method>.png``: the relative error (:func:`~cvxgeodesic.plotting.plot_error_map`),
  all methods on one colour scale (the median of their 99th percentiles);
* ``gradient_histogram.png``: area-weighted histograms of ``‖∇d|_t‖`` of every
  method next to the exact field's (:func:`~cvxgeodesic.plotting.plot_gradient_histogram`).

A method that raises gets a row whose ``status`` is the error message, and no
PNGs; the other methods go on. :func:`format_table` turns the rows into the
aligned text table the command line prints.
"""

from __future__ import annotations

import csv
import io
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

from ._atomic import atomic_write
from .errors import CvxGeodesicError, ParameterError, SolverError

__all__ = ["run_compare", "format_table", "resolve_methods", "CSV_COLUMNS"]

#: Columns of ``compare.csv`` (and keys of every row returned by :func:`run_compare`), in order.
#:
#: ``time_s`` is set-up plus solve (wall-clock seconds, what one call costs);
#: ``setup_s`` the per-mesh part of it, paid once per solver object; ``solve_s`` the per-source part.
#: ``rel_*`` / ``abs_max`` compare with the exact field (sources excluded; see
#: :func:`cvxgeodesic.evaluation.error_stats`). ``ridge_jump_p95`` is the 95th percentile of the
#: normal-derivative jump across edges in the band around the exact ridge, ``ridge_jump_ratio`` the
#: same divided by the exact field's (< 1: smoother than exact at the ridge), ``off_ridge_rel_mean``
#: the mean relative error outside that band (see :func:`cvxgeodesic.evaluation.smoothness_report`).
#: ``status`` is the solver status (``"optimal"``, ...) or the error message of a failed method.
CSV_COLUMNS = (
    "method", "solver", "time_s", "setup_s", "solve_s", "iterations",
    "rel_mean", "rel_max", "rel_p99", "abs_max",
    "ridge_jump_p95", "ridge_jump_ratio", "off_ridge_rel_mean", "status",
)

_ERROR_KEYS = ("rel_mean", "rel_max", "rel_p99", "abs_max")
_SMOOTH_KEYS = ("ridge_jump_p95", "ridge_jump_ratio", "off_ridge_rel_mean")


def resolve_methods(methods) -> list[str]:
    """Normalize a method list: lower case, ``"all"`` expanded, duplicates removed, names checked.

    Parameters
    ----------
    methods : str or sequence of str
        Method names of :data:`cvxgeodesic.api.ALL_METHODS` (a comma-separated
        string is accepted too); ``"all"`` stands for all of them. When ``"all"``
        is expanded, the alias ``"qgdf"`` is left out if ``"lcqp-hessian"`` is in
        the list (it is the same formulation).

    Returns
    -------
    list of str
        The names in the given order, each once.

    Raises
    ------
    ParameterError
        Empty list or an unknown name.
    """
    from .api import ALL_METHODS
    from .formulations import ALIASES

    if isinstance(methods, str):
        methods = [m for m in methods.split(",")]
    try:
        names = [str(m).strip().lower() for m in methods]
    except TypeError:
        raise ParameterError(f"methods must be a list of method names, got {methods!r}") from None
    names = [m for m in names if m]
    if not names:
        raise ParameterError("methods is empty: give at least one method name (or 'all')")
    out: list[str] = []
    expanded_all = "all" in names
    for name in names:
        group = list(ALL_METHODS) if name == "all" else [name]
        for g in group:
            if g not in ALL_METHODS:
                raise ParameterError(f"unknown method {g!r}; choose from: all, {', '.join(ALL_METHODS)}")
            if g not in out:
                out.append(g)
    if expanded_all:
        out = [m for m in out if not (m in ALIASES and ALIASES[m] in out)]
    return out


def _canonical(method: str) -> str:
    from .formulations import ALIASES

    return ALIASES.get(method, method)


def _atomic_write_text(path: Path, text: str) -> None:
    atomic_write(path, lambda fh: fh.write(text.encode("utf-8")))


def _error_message(exc: BaseException) -> str:
    msg = " ".join(str(exc).split())  # one line, for the CSV and the table
    if isinstance(exc, CvxGeodesicError):
        return msg or type(exc).__name__
    return f"{type(exc).__name__}: {msg}" if msg else type(exc).__name__


def _solve(mesh, method: str, sources: np.ndarray, m: float, solver: str):
    from .api import BASELINE_METHODS, GeodesicSolver

    t0 = time.perf_counter()
    if method in BASELINE_METHODS:
        gs = GeodesicSolver(mesh, method=method, m=m)
    else:
        gs = GeodesicSolver(mesh, method=method, m=m, solver=solver)
    res = gs.solve(sources)
    return res, time.perf_counter() - t0


def _empty_row(method: str) -> dict:
    row = {c: None for c in CSV_COLUMNS}
    row["method"] = method
    return row


def _fmt_csv(v) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v) if not math.isfinite(v) else f"{v:.6g}"
    return str(v)


def _finite_or_none(x):
    return None if x is None or not np.isfinite(x) else float(x)


def run_compare(mesh, sources, methods, out_dir, *, m=1.0, solver="auto", progress=True) -> list[dict]:
    """Solve with several methods, compare each with the exact distance, write a CSV and PNGs.

    Parameters
    ----------
    mesh : TriMesh or (V, F) tuple
        The surface, ``n`` vertices.
    sources : int, sequence of int, SurfacePoint, SurfaceCurve, "boundary", or a list mixing them
        As for :meth:`cvxgeodesic.GeodesicSolver.solve`; methods that cannot take the kind of source
        get a failed row naming the methods that can.
    methods : sequence of str or str
        Method names (see :func:`resolve_methods`); ``"all"`` means every method.
    out_dir : str or os.PathLike
        Output folder, created if missing. Existing files of the same names are replaced.
    m : float, default 1.0
        Smoothness multiplier of the quadratic formulations (ignored by the others).
    solver : {"auto", "ipm", "clarabel"}, default "auto"
        Backend of the convex formulations (baselines use their own library).
    progress : bool, default True
        Print one line per method (name, time, status) to stderr.

    Returns
    -------
    list of dict
        One row per method, in the order of ``methods``, keys :data:`CSV_COLUMNS`.
        Numbers are Python floats / ints; a value that does not apply (a failed
        method, or no exact reference) is None (an empty cell in the CSV).

    Raises
    ------
    ParameterError
        Unknown method or solver name, or an empty method list.
    SourceError
        Invalid source indices (checked before anything is solved).

    Notes
    -----
    The exact field is computed first, once, whether or not ``"exact"`` is in
    ``methods`` (only then does it get a row and PNGs). If it cannot be
    computed (e.g. a non-manifold mesh), the error columns stay empty, no
    ``error_*.png`` is drawn and a warning goes to stderr. A method named twice
    under an alias (``"qgdf"`` and ``"lcqp-hessian"``) is solved once and
    reported under both names.
    """
    from .evaluation import error_stats, gradient_norm_histogram, relative_error, smoothness_report
    from .mesh.io import as_trimesh
    from .plotting import plot_error_map, plot_field, plot_gradient_histogram

    mesh = as_trimesh(mesh)
    names = resolve_methods(methods)
    from .sources import resolve_sources

    sset = resolve_sources(mesh, sources)
    src = sset.vertices  # excluded from the error statistics and marked in the plots (none for point sources)
    solve_src = src if sset.vertex_only else sset
    from .api import SOLVERS

    if not isinstance(solver, str) or solver.lower() not in SOLVERS:
        raise ParameterError(f"unknown solver {solver!r}; choose one of {', '.join(SOLVERS)}")
    out = Path(os.fspath(out_dir))
    out.mkdir(parents=True, exist_ok=True)
    log = sys.stderr
    width = max(len(n) for n in [*names, "exact"])

    def say(text: str) -> None:
        if progress:
            print(text, file=log, flush=True)

    # -- the reference -------------------------------------------------------------------------------------------------
    results: dict[str, tuple] = {}  # canonical method -> (result or None, wall seconds, exception or None)
    t0 = time.perf_counter()
    try:
        res, wall = _solve(mesh, "exact", solve_src, m, solver)
        results["exact"] = (res, wall, None)
    except Exception as exc:  # noqa: BLE001 - a failed method becomes a row, never the end of the comparison
        results["exact"] = (None, time.perf_counter() - t0, exc)
    ref_res, ref_wall, ref_err = results["exact"]
    d_exact = ref_res.distance if ref_res is not None else None
    if ref_err is not None:
        say(f"warning: no exact reference, errors are not computed ({_error_message(ref_err)})")
    elif "exact" not in names:
        say(f"{'exact':<{width}}  {ref_wall:8.2f} s  (reference)")

    # -- every method --------------------------------------------------------------------------------------------------
    for i, name in enumerate(names, 1):
        key = _canonical(name)
        if key not in results:
            t0 = time.perf_counter()
            try:
                results[key] = (*_solve(mesh, key, solve_src, m, solver), None)
            except Exception as exc:  # noqa: BLE001
                results[key] = (None, time.perf_counter() - t0, exc)
        res, wall, err = results[key]
        tag = f"[{i}/{len(names)}] {name:<{width}}"
        if err is None:
            say(f"{tag}  {wall:8.2f} s  {res.info.status}, {res.info.iterations} it")
        else:
            say(f"{tag}  {wall:8.2f} s  FAILED: {_error_message(err)}")

    # -- rows and measurements ----------------------------------------------------------------------------------------
    rows: list[dict] = []
    rel_errors: dict[str, np.ndarray] = {}
    for name in names:
        res, wall, err = results[_canonical(name)]
        row = _empty_row(name)
        rows.append(row)
        if err is not None:
            row["time_s"] = float(wall)
            row["status"] = _error_message(err)
            if isinstance(err, SolverError):
                row["solver"] = str(err.solver)
                it = err.info.get("iterations")
                row["iterations"] = int(it) if isinstance(it, int | np.integer) else None
            continue
        info = res.info
        row.update(
            solver=str(info.solver), time_s=float(info.setup_time + info.solve_time),
            setup_s=float(info.setup_time), solve_s=float(info.solve_time), iterations=int(info.iterations),
            status=str(info.status),
        )
        if d_exact is None:
            continue
        try:
            stats = error_stats(res.distance, d_exact, src)
            smooth = smoothness_report(mesh, res.distance, d_exact, src)
            rel_errors[name] = relative_error(res.distance, d_exact, src)
        except Exception as exc:  # noqa: BLE001
            row["status"] = f"{info.status}; evaluation failed: {_error_message(exc)}"
            continue
        row.update({k: float(stats[k]) for k in _ERROR_KEYS})
        row.update({k: float(smooth[k]) for k in _SMOOTH_KEYS})

    # -- the CSV first (the numbers matter more than the pictures) ---------------------------------------------------
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(CSV_COLUMNS), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _fmt_csv(row[k]) for k in CSV_COLUMNS})
    _atomic_write_text(out / "compare.csv", buf.getvalue())

    # -- pictures -----------------------------------------------------------------------------------------------------
    t_png = time.perf_counter()
    field_ref = d_exact
    if field_ref is None:  # no reference: take the colour range from the first successful method
        ok = [results[_canonical(n)][0] for n in names if results[_canonical(n)][0] is not None]
        field_ref = ok[0].distance if ok else None
    vmax_field = None
    levels = 20
    if field_ref is not None:
        fin = field_ref[np.isfinite(field_ref)]
        if fin.size and fin.max() > 0:
            vmax_field = float(fin.max())
            levels = np.linspace(0.0, vmax_field, 22)[1:-1]
    # one colour scale for every error map: the median of the methods' 99th percentiles (the exact field's 0 aside),
    # so one very bad method does not wash out the others; the colour bar shows an arrow where it clips
    p99s = [p for p in (_finite_or_none(r["rel_p99"]) for r in rows) if p]
    vmax_err = float(np.median(p99s)) if p99s else None
    src_txt = ", ".join(str(int(s)) for s in src[:5]) + (", ..." if len(src) > 5 else "")
    if not sset.vertex_only:
        src_txt = sset.description
    for name, row in zip(names, rows, strict=True):
        res = results[_canonical(name)][0]
        if res is None:
            continue
        title = f"{name} on {mesh.name} (source {src_txt})"
        plot_field(mesh, res.distance, out / f"field_{name}.png", isolines=levels, title=title,
                   vmin=0.0 if vmax_field is not None else None, vmax=vmax_field, colorbar_label="distance",
                   sources=src)
        if name in rel_errors:
            rm = row["rel_mean"]
            mean_txt = f" (mean {100 * rm:.2f}%)" if rm is not None and np.isfinite(rm) else ""
            etitle = f"{name}: relative error{mean_txt}"
            plot_error_map(mesh, rel_errors[name], out / f"error_{name}.png", title=etitle, vmax=vmax_err, sources=src)

    # gradient-norm histograms: the exact field first (the reference), then every successful method
    hist_fields = {}
    if d_exact is not None:
        hist_fields["exact"] = d_exact
    for name in names:
        res = results[_canonical(name)][0]
        if res is not None and name not in hist_fields:
            hist_fields[name] = res.distance
    if hist_fields:
        edges = np.linspace(0.0, 2.0, 161)
        hists = {k: gradient_norm_histogram(mesh, d, bins=edges, sources=src) for k, d in hist_fields.items()}
        nonzero = [np.flatnonzero(c > 0) for c, _ in hists.values()]
        last = max((int(nz[-1]) for nz in nonzero if nz.size), default=len(edges) - 2)
        cut = min(max(last + 2, int(np.searchsorted(edges, 1.5))), len(edges) - 1)  # show at least [0, 1.5]
        hists = {k: (c[:cut], e[: cut + 1]) for k, (c, e) in hists.items()}
        plot_gradient_histogram(
            hists, out / "gradient_histogram.png",
            title=f"‖∇d‖ per triangle on {mesh.name} (area-weighted, source triangles excluded)",
        )
    say(f"wrote {out / 'compare.csv'} and {sum(1 for _ in out.glob('*.png'))} PNGs in {out} "
        f"({time.perf_counter() - t_png:.1f} s for the pictures)")
    return rows


# ----------------------------------------------------------------------------------------------------------------------
# text table
# ----------------------------------------------------------------------------------------------------------------------

_TABLE = (
    # header, key, formatter
    ("method", "method", str),
    ("time s", "time_s", lambda v: f"{v:.2f}"),
    ("setup s", "setup_s", lambda v: f"{v:.2f}"),
    ("iters", "iterations", lambda v: f"{int(v)}"),
    ("rel mean %", "rel_mean", lambda v: f"{100 * v:.2f}"),
    ("rel max %", "rel_max", lambda v: f"{100 * v:.1f}"),
    ("rel p99 %", "rel_p99", lambda v: f"{100 * v:.1f}"),
    ("off-ridge %", "off_ridge_rel_mean", lambda v: f"{100 * v:.2f}"),
    ("ridge jump p95", "ridge_jump_p95", lambda v: f"{v:.3f}"),
    ("vs exact", "ridge_jump_ratio", lambda v: f"{v:.2f}"),
    ("status", "status", str),
)


def format_table(rows) -> str:
    """Aligned plain-text table of :func:`run_compare` rows (what ``cvxgeodesic compare`` prints).

    Parameters
    ----------
    rows : list of dict
        Rows as returned by :func:`run_compare` (missing keys and None print as ``-``).

    Returns
    -------
    str
        Header, a rule and one line per row; numbers right-aligned, errors in
        percent, times in seconds. Long status messages are shortened to 60
        characters (the CSV keeps them whole).
    """
    cells = []
    for row in rows:
        line = []
        for _, key, fmt in _TABLE:
            v = row.get(key)
            if v is None or (isinstance(v, str) and not v and key != "method"):
                line.append("-")
                continue
            try:
                s = fmt(v)
            except (TypeError, ValueError):
                s = str(v)
            if key == "status" and len(s) > 60:
                s = s[:59] + "…"
            line.append(s)
        cells.append(line)
    heads = [h for h, _, _ in _TABLE]
    widths = [max([len(h)] + [len(c[j]) for c in cells]) for j, h in enumerate(heads)]
    left = {0, len(heads) - 1}  # method and status left-aligned

    def fmt_line(items):
        parts = [s.ljust(w) if j in left else s.rjust(w) for j, (s, w) in enumerate(zip(items, widths, strict=True))]
        return "  ".join(parts).rstrip()

    lines = [fmt_line(heads), "  ".join("-" * w for w in widths)]
    lines += [fmt_line(c) for c in cells]
    return "\n".join(lines)
