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
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ._atomic import atomic_write, check_output_dir
from .errors import CvxGeodesicError, ParameterError, SolverError
from .tables import Column, text_table

__all__ = [
    "COLUMN_HELP", "CSV_COLUMNS", "TABLE_COLUMNS", "evaluate_methods", "format_table", "resolve_methods", "run_compare",
    "solve_methods", "table_legend", "write_csv", "write_pictures",
]

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
    def write(fh) -> None:
        fh.write(text.encode("utf-8"))

    atomic_write(path, write, allow=None)  # a read-only file in the folder is refused: no override here


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
    row: dict[str, Any] = dict.fromkeys(CSV_COLUMNS)
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
    Three steps, each a function of its own: :func:`solve_methods` (the exact field first, once,
    whether or not ``"exact"`` is in ``methods``: only then does it get a row and PNGs),
    :func:`evaluate_methods` (the rows, measured with
    :func:`cvxgeodesic.evaluation.summary.summarize_field`), :func:`write_csv` and
    :func:`write_pictures`. If the exact field cannot be computed (e.g. a non-manifold mesh), the
    error columns stay empty, no ``error_*.png`` is drawn and a warning goes to stderr. A method
    named twice under an alias (``"qgdf"`` and ``"lcqp-hessian"``) is solved once and reported
    under both names.
    """
    from .api import SOLVERS
    from .mesh.io import as_trimesh
    from .sources import resolve_sources

    mesh = as_trimesh(mesh)
    names = resolve_methods(methods)
    sset = resolve_sources(mesh, sources)
    if not isinstance(solver, str) or solver.lower() not in SOLVERS:
        raise ParameterError(f"unknown solver {solver!r}; choose one of {', '.join(SOLVERS)}")
    out = check_output_dir(out_dir, "out_dir")  # a folder that cannot take files fails now, not after the solves
    out.mkdir(parents=True, exist_ok=True)

    def say(text: str) -> None:
        if progress:
            print(text, file=sys.stderr, flush=True)

    results = solve_methods(mesh, sset, names, m=m, solver=solver, say=say)
    rows, rel_errors = evaluate_methods(mesh, sset.vertices, names, results)
    write_csv(out / "compare.csv", rows)  # the numbers first: they matter more than the pictures
    t_png = time.perf_counter()
    write_pictures(out, mesh, sset, names, results, rows, rel_errors)
    say(f"wrote {out / 'compare.csv'} and {sum(1 for _ in out.glob('*.png'))} PNGs in {out} "
        f"({time.perf_counter() - t_png:.1f} s for the pictures)")
    return rows


#: What :func:`solve_methods` keeps of one method: the result (None if it failed), the wall-clock
#: seconds, and the exception (None if it did not fail).
Outcome = tuple[Any, float, BaseException | None]  # (GeodesicResult or None, seconds, exception or None)


def _attempt(mesh, method: str, sources, m: float, solver: str) -> Outcome:
    t0 = time.perf_counter()
    try:
        return (*_solve(mesh, method, sources, m, solver), None)
    except Exception as exc:  # noqa: BLE001 - a failed method becomes a row, never the end of the comparison
        return None, time.perf_counter() - t0, exc


def solve_methods(mesh, sset, names, *, m: float = 1.0, solver: str = "auto", say=None) -> dict[str, Outcome]:
    """Solve the exact reference and every method once; a failure is kept, not raised.

    Parameters
    ----------
    mesh : TriMesh
        The surface.
    sset : SourceSet
        The resolved sources (:func:`cvxgeodesic.sources.resolve_sources`).
    names : list of str
        Method names as :func:`resolve_methods` returns them.
    m : float, default 1.0
        Smoothness multiplier.
    solver : str, default "auto"
        Backend of the convex formulations.
    say : callable, optional
        Receives one progress line per method (and a warning when there is no exact reference).

    Returns
    -------
    dict
        Canonical method name (aliases resolved) → ``(result or None, wall seconds, exception or None)``;
        always has ``"exact"``.
    """
    say = say or (lambda text: None)
    solve_src = sset.vertices if sset.vertex_only else sset
    width = max(len(n) for n in [*names, "exact"])
    results: dict[str, Outcome] = {"exact": _attempt(mesh, "exact", solve_src, m, solver)}
    _, ref_wall, ref_err = results["exact"]
    if ref_err is not None:
        say(f"warning: no exact reference, errors are not computed ({_error_message(ref_err)})")
    elif "exact" not in names:
        say(f"{'exact':<{width}}  {ref_wall:8.2f} s  (reference)")
    for i, name in enumerate(names, 1):
        key = _canonical(name)
        if key not in results:
            results[key] = _attempt(mesh, key, solve_src, m, solver)
        res, wall, err = results[key]
        tag = f"[{i}/{len(names)}] {name:<{width}}"
        if err is None:
            say(f"{tag}  {wall:8.2f} s  {res.info.status}, {res.info.iterations} it")
        else:
            say(f"{tag}  {wall:8.2f} s  FAILED: {_error_message(err)}")
    return results


def _failed_row(row: dict, wall: float, err: BaseException) -> None:
    row["time_s"] = float(wall)
    row["status"] = _error_message(err)
    if isinstance(err, SolverError):
        row["solver"] = str(err.solver)
        it = err.info.get("iterations")
        row["iterations"] = int(it) if isinstance(it, int | np.integer) else None


def evaluate_methods(mesh, src, names, results) -> tuple[list[dict], dict[str, np.ndarray]]:
    """The rows of the comparison: each method's solve record and its errors against the exact field.

    Parameters
    ----------
    mesh : TriMesh
        The surface, ``n`` vertices.
    src : (k,) int ndarray
        Source vertices, left out of the errors (none for point sources).
    names : list of str
        Method names, one row each, in this order.
    results : dict
        As :func:`solve_methods` returns it.

    Returns
    -------
    rows : list of dict
        Keys :data:`CSV_COLUMNS`; None where a value does not apply.
    rel_errors : dict
        Method name → (n,) per-vertex relative error, for the methods that were measured.
    """
    from .evaluation import relative_error
    from .evaluation.summary import summarize_field, summarize_run

    ref = results["exact"][0]
    d_exact = ref.distance if ref is not None else None
    rows: list[dict] = []
    rel_errors: dict[str, np.ndarray] = {}
    for name in names:
        res, wall, err = results[_canonical(name)]
        row = _empty_row(name)
        rows.append(row)
        if err is not None:
            _failed_row(row, wall, err)
            continue
        run = summarize_run(res.info)
        row.update({k: run[k] for k in ("solver", "time_s", "setup_s", "solve_s", "iterations", "status")})
        if d_exact is None:
            continue
        try:
            summary = summarize_field(mesh, res.distance, d_exact, src, gradient=False)
            rel_errors[name] = relative_error(res.distance, d_exact, src)
        except Exception as exc:  # noqa: BLE001
            row["status"] = f"{row['status']}; evaluation failed: {_error_message(exc)}"
            continue
        row.update({k: summary[k] for k in _ERROR_KEYS + _SMOOTH_KEYS})
    return rows, rel_errors


def write_csv(path: Path, rows: list[dict]) -> None:
    """Write the rows as ``compare.csv`` (columns :data:`CSV_COLUMNS`, empty cells for None), atomically."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(CSV_COLUMNS), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({k: _fmt_csv(row[k]) for k in CSV_COLUMNS})
    _atomic_write_text(path, buf.getvalue())


def _field_scale(results, names, d_exact):
    """Colour range and isoline levels shared by every field picture: the exact field's, else the first result's."""
    field_ref = d_exact
    if field_ref is None:
        ok = [results[_canonical(n)][0] for n in names if results[_canonical(n)][0] is not None]
        field_ref = ok[0].distance if ok else None
    vmax_field: float | None = None
    levels: int | np.ndarray = 20
    if field_ref is not None:
        fin = field_ref[np.isfinite(field_ref)]
        if fin.size and fin.max() > 0:
            vmax_field = float(fin.max())
            levels = np.linspace(0.0, vmax_field, 22)[1:-1]
    return vmax_field, levels


def write_pictures(out: Path, mesh, sset, names, results, rows, rel_errors) -> None:
    """Write ``field_<method>.png``, ``error_<method>.png`` and ``gradient_histogram.png`` into ``out``.

    Parameters
    ----------
    out : Path
        The output folder (must exist).
    mesh, sset, names
        As for :func:`solve_methods`.
    results, rows, rel_errors
        What :func:`solve_methods` and :func:`evaluate_methods` returned.
    """
    from .plotting import plot_error_map, plot_field

    src = sset.vertices
    ref = results["exact"][0]
    d_exact = ref.distance if ref is not None else None
    vmax_field, levels = _field_scale(results, names, d_exact)
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
    _write_histograms(out, mesh, src, names, results, d_exact)


def _write_histograms(out: Path, mesh, src, names, results, d_exact) -> None:
    """Gradient-norm histograms: the exact field first (the reference), then every successful method."""
    from .evaluation import gradient_norm_histogram
    from .plotting import plot_gradient_histogram

    hist_fields = {}
    if d_exact is not None:
        hist_fields["exact"] = d_exact
    for name in names:
        res = results[_canonical(name)][0]
        if res is not None and name not in hist_fields:
            hist_fields[name] = res.distance
    if not hist_fields:
        return
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


# ----------------------------------------------------------------------------------------------------------------------
# text table
# ----------------------------------------------------------------------------------------------------------------------

#: The columns of :func:`format_table`.
TABLE_COLUMNS = (
    Column("method", "method", align="left"),
    Column("time s", "time_s", lambda v: f"{v:.2f}"),
    Column("setup s", "setup_s", lambda v: f"{v:.2f}"),
    Column("iters", "iterations", lambda v: f"{int(v)}"),
    Column("rel mean %", "rel_mean", lambda v: f"{100 * v:.2f}"),
    Column("rel max %", "rel_max", lambda v: f"{100 * v:.1f}"),
    Column("rel p99 %", "rel_p99", lambda v: f"{100 * v:.1f}"),
    Column("off-ridge %", "off_ridge_rel_mean", lambda v: f"{100 * v:.2f}"),
    Column("ridge jump p95", "ridge_jump_p95", lambda v: f"{v:.3f}"),
    Column("vs exact", "ridge_jump_ratio", lambda v: f"{v:.2f}"),
    Column("status", "status", align="left", max_len=60),
)


#: What each column of :func:`format_table` means, by header (``cvxgeodesic compare --help`` prints it).
COLUMN_HELP = {
    "method": "the method",
    "time s": "set-up + solve, wall-clock seconds",
    "setup s": "the per-mesh part of it, paid once per solver",
    "iters": "solver iterations",
    "rel mean %": "mean of |d - exact| / exact over the vertices (sources excluded)",
    "rel max %": "its largest value",
    "rel p99 %": "its 99th percentile",
    "off-ridge %": "rel mean away from the ridge (cut locus) of the exact field",
    "ridge jump p95": "95th percentile of the jump of the normal derivative across the edges near that ridge "
                      "(how sharp the field's crease is there)",
    "vs exact": "ridge jump p95 divided by the exact field's: below 1 the field is smoother than the exact "
                "distance at the ridge (rounded isolines), 1 as sharp",
    "status": "the solver status, or why the method failed",
}


def table_legend() -> str:
    """One line per column of :func:`format_table`: ``"<header>: <meaning>"``.

    Returns
    -------
    str
    """
    return "\n".join(f"{c.header}: {COLUMN_HELP[c.header]}" for c in TABLE_COLUMNS)


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
        characters (the CSV keeps them whole). Laid out by :func:`cvxgeodesic.tables.text_table`.
    """
    return text_table(rows, TABLE_COLUMNS)
