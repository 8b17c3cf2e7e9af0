"""Side-by-side comparison of methods on one mesh, a surface or a volume: the engine behind ``cvxgeodesic compare``.

:func:`run_compare` solves the same sources with every requested method, measures each field against a reference
(computed once and reused) with the one evaluation record of the library
(:func:`cvxgeodesic.evaluation.summary.summarize`), and writes into an output folder

* ``compare.csv``: one row per method (columns in :data:`CSV_COLUMNS`);
* ``field_<method>.png``: the field with isolines (:func:`~cvxgeodesic.plotting.plot_field`; inside a tetrahedral
  mesh its slice through the centre, :func:`~cvxgeodesic.evaluation.slice_plot.plot_slice`), all methods on the
  colour range and isoline levels of the reference, so the pictures compare (``field_qclp_order2.png``: order 2);
* ``error_<method>.png``: the relative error (:func:`~cvxgeodesic.plotting.plot_error_map`, or on the slice),
  all methods on one colour scale (the median of their 99th percentiles);
* ``gradient_histogram.png``: area- (volume-) weighted histograms of the per-cell ``‖∇d|_t‖`` of every method
  next to the reference's (:func:`~cvxgeodesic.plotting.plot_gradient_histogram`).

The reference (the domain's, :attr:`cvxgeodesic.capabilities.Domain.reference`) is the exact polyhedral distance
(MMP, method ``"exact"``) on a surface; inside a solid, where no exact algorithm exists, the most accurate field the
library computes, ``qclp`` at order 2 (exact wherever the source is visible, docs/volumes.md), or a field the caller
gives (an analytic one). A reference that no method name asks for (order 2) is listed first.

A method that raises gets a row whose ``status`` is the error message, and no PNGs; the other methods go on.
:func:`format_table` turns the rows into the aligned text table the command line prints.
"""

from __future__ import annotations

import csv
import io
import math
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from ._atomic import atomic_write, check_output_dir, output_folder
from .errors import OutputError, ParameterError, SolverError, error_line
from .tables import Column, text_table

if TYPE_CHECKING:
    from .mesh.convert import MeshLike
    from .mesh.simplex import SimplexMesh

__all__ = [
    "COLUMN_HELP", "CSV_COLUMNS", "TABLE_COLUMNS", "evaluate_methods", "format_table",
    "resolve_methods", "run_compare", "solve_methods", "table_legend", "write_csv", "write_pictures",
]

#: Columns of ``compare.csv`` (and keys of every row returned by :func:`run_compare`), in order.
#:
#: ``order`` is the element order of the run (2: the volume reference). ``time_s`` is set-up plus solve (seconds,
#: what one call costs); ``setup_s`` the per-mesh part of it, paid once per solver object; ``solve_s`` the
#: per-source part. ``rel_*`` / ``abs_max`` compare with the reference (sources excluded; see
#: :func:`cvxgeodesic.evaluation.error_stats`). ``ridge_jump_p95`` is the 95th percentile of the normal-derivative
#: jump across edges in the band around the reference's ridge, ``ridge_jump_ratio`` the same divided by the
#: reference's (< 1: smoother than it at the ridge), ``off_ridge_rel_mean`` the mean relative error outside that band
#: (see :func:`cvxgeodesic.evaluation.smoothness_report`; surfaces only). ``reference`` names the reference;
#: ``status`` is the solver status (``"optimal"``, ...) or the error message of a failed method.
CSV_COLUMNS = (
    "method", "order", "solver", "time_s", "setup_s", "solve_s", "iterations",
    "rel_mean", "rel_max", "rel_p99", "abs_max",
    "ridge_jump_p95", "ridge_jump_ratio", "off_ridge_rel_mean", "reference", "status",
)

_RUN_KEYS = ("solver", "time_s", "setup_s", "solve_s", "iterations", "status")
_MEASURED_KEYS = ("rel_mean", "rel_max", "rel_p99", "abs_max", "ridge_jump_p95", "ridge_jump_ratio",
                  "off_ridge_rel_mean")

#: One run of the comparison: ``(method name, element order)``.
Run = tuple[str, int]
#: What :func:`solve_methods` keeps of one run: the result (None if it failed), the wall-clock seconds, and the
#: exception (None if it did not fail).
Outcome = tuple[Any, float, BaseException | None]


def resolve_methods(methods: Any, domain: str = "surface") -> list[str]:
    """Normalize a method list: lower case, ``"all"`` expanded, duplicates removed, names checked.

    Parameters
    ----------
    methods : str or sequence of str
        Method names of :data:`cvxgeodesic.api.ALL_METHODS` (a comma-separated string is accepted too); ``"all"``
        stands for all of those that apply to the mesh. When ``"all"`` is expanded, the alias ``"qgdf"`` is left
        out if ``"lcqp-hessian"`` is in the list (it is the same formulation).
    domain : {"surface", "volume", "cloud"}
        The mesh's domain (``mesh.domain``): ``"all"`` takes the methods that apply there, and a method that does
        not is refused (:mod:`cvxgeodesic.capabilities`).

    Returns
    -------
    list of str
        The names in the given order, each once.

    Raises
    ------
    ParameterError
        Empty list, an unknown name, or a method that does not apply to volumes (the message names those that do).
    """
    from .api import ALL_METHODS
    from .capabilities import check, methods_for
    from .problems.formulations import ALIASES

    if isinstance(methods, str):
        methods = methods.split(",")
    try:
        names = [str(m).strip().lower() for m in methods]
    except TypeError:
        raise ParameterError(f"methods must be a list of method names, got {methods!r}") from None
    names = [m for m in names if m]
    if not names:
        raise ParameterError("methods is empty: give at least one method name (or 'all')")
    out: list[str] = []
    for name in names:
        for g in (methods_for(domain) if name == "all" else [name]):
            if g not in ALL_METHODS:
                raise ParameterError(f"unknown method {g!r}; choose from: all, {', '.join(ALL_METHODS)}")
            check(ALIASES.get(g, g), domain=domain)  # a surface method on a volume: the message names those that apply
            if g not in out:
                out.append(g)
    if "all" in names:
        out = [m for m in out if not (m in ALIASES and ALIASES[m] in out)]
    return out


def _key(run: Run) -> Run:
    """The run an alias stands for (``qgdf`` is ``lcqp-hessian``): solved once, reported under both names."""
    from .problems.formulations import ALIASES

    return ALIASES.get(run[0], run[0]), run[1]


def _label(run: Run, order: str = " order ") -> str:
    """The run in tables and titles (in file names: ``order="_order"``)."""
    return run[0] if run[1] == 1 else f"{run[0]}{order}{run[1]}"


def run_compare(mesh: MeshLike, sources: Any, methods: Any, out_dir: str | os.PathLike, *, m: float = 1.0,
                solver: str = "auto", reference: Any = None, progress: bool = True, view: Any = None,
                up: Any = "auto") -> list[dict]:
    """Solve with several methods, compare each with the reference, write a CSV and PNGs.

    Parameters
    ----------
    mesh : TriMesh, TetMesh, or a (V, F) / (V, T) tuple
        ``n`` vertices.
    sources : anything :meth:`cvxgeodesic.GeodesicSolver.solve` takes on this mesh
        Methods that cannot take the kind of source get a failed row naming the methods that can.
    methods : sequence of str or str
        Method names (see :func:`resolve_methods`); ``"all"`` means every method that applies to the mesh.
    out_dir : str or os.PathLike
        Output folder, created if missing. Existing files of the same names are replaced; the CSV and the
        pictures appear together or not at all (they are written in a private folder inside it first).
    m : float, default 1.0
        Smoothness multiplier of the quadratic formulations (ignored by the others).
    solver : {"auto", "ipm", "clarabel"}, default "auto"
        Backend of the convex formulations (baselines use their own library).
    reference : (n,) float array_like, optional
        The field to compare with (e.g. an analytic one); default the mesh's domain's
        (:attr:`cvxgeodesic.capabilities.Domain.reference`), solved here.
    progress : bool, default True
        Print one line per method (name, time, status) to stderr.
    view, up : optional
        The camera of a surface's pictures (:func:`cvxgeodesic.plotting.plot_field`; default two panels: facing the
        first source, and the far side).

    Returns
    -------
    list of dict
        One row per run, keys :data:`CSV_COLUMNS`: the methods in the order of ``methods``, after the reference
        when it is a run no name asks for (``qclp`` at order 2 in a volume). Numbers are Python floats / ints; a
        value that does not apply (a failed method, no reference, the ridge in a volume) is None (an empty cell).

    Raises
    ------
    ParameterError
        Unknown method or solver name, a method that does not apply to the mesh, an empty method list, a
        ``reference`` of the wrong shape.
    SourceError
        Invalid sources (checked before anything is solved).
    OutputError
        An output could not be written (a full disk): the message names it, and nothing of the run is left in
        ``out_dir`` (files there from before are as they were).

    Notes
    -----
    Steps, each a function of its own: :func:`solve_methods` (the reference first, once, whether or not it is
    one of ``methods``), :func:`evaluate_methods` (the rows, measured with
    :func:`cvxgeodesic.evaluation.summary.summarize`), :func:`write_csv` and :func:`write_pictures`. If the
    reference cannot be computed (e.g. ``exact`` on a non-manifold mesh), the error columns stay empty, no
    ``error_*.png`` is drawn and a warning goes to stderr. A method named twice under an alias (``"qgdf"`` and
    ``"lcqp-hessian"``) is solved once and reported under both names.
    """
    from .api import SOLVERS
    from .capabilities import DOMAINS
    from .mesh.convert import as_mesh
    from .sources import resolve_sources
    from .validation import check_choice

    mesh = as_mesh(mesh)
    names = resolve_methods(methods, mesh.domain)
    sset = resolve_sources(mesh, sources)
    check_choice(solver, "solver", SOLVERS)
    _check_camera(mesh, view, up)  # before the solves
    runs: list[Run] = [(n, 1) for n in names]
    domain_run = DOMAINS[mesh.domain].reference
    ref_run: Run | None = domain_run
    if reference is not None:
        from .validation import as_vertex_field

        reference, ref_run = as_vertex_field(reference, "reference", mesh.n_vertices), None
    elif domain_run[1] != 1:  # no method name asks for it: listed first
        runs.insert(0, domain_run)
    out = check_output_dir(out_dir, "out_dir")  # a folder that cannot take files fails now, not after the solves
    out.mkdir(parents=True, exist_ok=True)

    def say(text: str) -> None:
        if progress:
            print(text, file=sys.stderr, flush=True)

    results = solve_methods(mesh, sset, runs, reference=ref_run, m=m, solver=solver, say=say)
    if ref_run is not None:
        ref_result = results[_key(ref_run)][0]
        reference = ref_result.distance if ref_result is not None else None
    rows, rel_errors = evaluate_methods(mesh, runs, results, reference, "given" if ref_run is None else _label(ref_run))
    t_png = time.perf_counter()
    try:
        # the CSV and every picture appear together or not at all (a full disk left compare.csv without pictures)
        with output_folder(out, allow=None) as stage:
            write_csv(stage / "compare.csv", rows)
            write_pictures(stage, mesh, sset, runs, results, rows, rel_errors, reference, view=view, up=up)
            n_png = sum(1 for _ in stage.glob("*.png"))
    except OSError as exc:
        name = Path(exc.filename).name if isinstance(exc.filename, str) else ""
        where = out / name if name and not name.startswith(".") else out  # a hidden name: the private folder
        raise OutputError(f"cannot write {where} ({exc.strerror or exc}); nothing of this comparison was written "
                          f"to {out}", str(where), exc.errno) from None
    say(f"wrote {out / 'compare.csv'} and {n_png} PNGs in {out} ({time.perf_counter() - t_png:.1f} s for the "
        "pictures)")
    return rows


def _attempt(mesh: SimplexMesh, run: Run, sources: Any, m: float, solver: str) -> Outcome:
    from .api import BASELINE_METHODS, GeodesicSolver, Method

    t0 = time.perf_counter()
    method, order = run
    try:
        options: dict[str, Any] = {} if method in BASELINE_METHODS else {"solver": solver, "order": order}
        solver_obj = GeodesicSolver(mesh, method=cast(Method, method), m=m, **options)
        return solver_obj.solve(sources), time.perf_counter() - t0, None
    except Exception as exc:  # noqa: BLE001 - a failed method becomes a row, never the end of the comparison
        return None, time.perf_counter() - t0, exc


def solve_methods(mesh: SimplexMesh, sset: Any, runs: list[Run], *, reference: Run | None = None, m: float = 1.0,
                  solver: str = "auto", say: Any = None) -> dict[Run, Outcome]:
    """Solve the reference and every run once; a failure is kept, not raised.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
    sset : SourceSet or TetSources
        The resolved sources.
    runs : list of (str, int)
        ``(method, order)``, the method names as :func:`resolve_methods` returns them.
    reference : (str, int), optional
        The reference run, solved first (None: the caller has the reference field).
    m : float, default 1.0
        Smoothness multiplier.
    solver : str, default "auto"
        Backend of the convex formulations.
    say : callable, optional
        Receives one progress line per run (and a warning when the reference failed).

    Returns
    -------
    dict
        ``(method, order)`` with aliases resolved → ``(result or None, wall seconds, exception or None)``.
    """
    say = say or (lambda text: None)
    solve_src = sset.vertices if sset.vertex_only else sset
    width = max(len(_label(r)) for r in [*runs, *([reference] if reference else [])])
    results: dict[Run, Outcome] = {}
    if reference is not None:
        results[_key(reference)] = _attempt(mesh, reference, solve_src, m, solver)
        _, ref_wall, ref_err = results[_key(reference)]
        if ref_err is not None:
            say(f"warning: no {_label(reference)} reference, errors are not computed ({error_line(ref_err)})")
        elif reference not in runs:
            say(f"{_label(reference):<{width}}  {ref_wall:8.2f} s  (reference)")
    for i, run in enumerate(runs, 1):
        if _key(run) not in results:
            results[_key(run)] = _attempt(mesh, _key(run), solve_src, m, solver)
        res, wall, err = results[_key(run)]
        tag = f"[{i}/{len(runs)}] {_label(run):<{width}}"
        if err is None:
            say(f"{tag}  {wall:8.2f} s  {res.info.status}, {res.info.iterations} it")
        else:
            say(f"{tag}  {wall:8.2f} s  FAILED: {error_line(err)}")
    return results


def _failed_row(row: dict, wall: float, err: BaseException) -> None:
    row.update(time_s=float(wall), status=error_line(err))
    if isinstance(err, SolverError):
        row["solver"] = str(err.solver)
        it = err.info.get("iterations")
        row["iterations"] = int(it) if isinstance(it, int | np.integer) else None


def evaluate_methods(mesh: SimplexMesh, runs: list[Run], results: dict[Run, Outcome], reference: np.ndarray | None,
                     reference_label: str = "exact") -> tuple[list[dict], dict[Run, np.ndarray]]:
    """The rows of the comparison: each run's record of :func:`cvxgeodesic.evaluation.summary.summarize`.

    Parameters
    ----------
    mesh : TriMesh or TetMesh
        ``n`` vertices.
    runs : list of (str, int)
        One row each, in this order.
    results : dict
        As :func:`solve_methods` returns it.
    reference : (n,) float ndarray or None
        The reference field; None: nothing is measured.
    reference_label : str
        The ``reference`` column.

    Returns
    -------
    rows : list of dict
        Keys :data:`CSV_COLUMNS`; None where a value does not apply.
    rel_errors : dict
        Run → (n,) per-vertex relative error, for the runs that were measured.
    """
    from .evaluation import relative_error
    from .evaluation.summary import summarize, summarize_run

    rows: list[dict] = []
    rel_errors: dict[Run, np.ndarray] = {}
    for run in runs:
        res, wall, err = results[_key(run)]
        row: dict[str, Any] = dict.fromkeys(CSV_COLUMNS)
        row.update(method=run[0], order=run[1], reference=reference_label)
        rows.append(row)
        if err is not None:
            _failed_row(row, wall, err)
            continue
        row.update({k: v for k, v in summarize_run(res.info).items() if k in _RUN_KEYS})
        if reference is None:
            continue
        try:
            record = summarize(mesh, res, reference, gradient=False)
            rel_errors[run] = relative_error(res.distance, reference, res.sources)
        except Exception as exc:  # noqa: BLE001
            row["status"] = f"{row['status']}; evaluation failed: {error_line(exc)}"
            continue
        row.update({k: record[k] for k in _MEASURED_KEYS})
    return rows, rel_errors


def _fmt_csv(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, float):
        return repr(v) if not math.isfinite(v) else f"{v:.6g}"
    return str(v)


def write_csv(path: Path, rows: list[dict]) -> None:
    """Write the rows as ``compare.csv`` (columns :data:`CSV_COLUMNS`, empty cells for None), atomically."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(CSV_COLUMNS), lineterminator="\n")
    writer.writeheader()
    writer.writerows({k: _fmt_csv(row[k]) for k in CSV_COLUMNS} for row in rows)
    data = buf.getvalue().encode("utf-8")
    atomic_write(path, lambda fh: fh.write(data), allow=None)  # a read-only file is refused: no override here


def _field_scale(results: dict[Run, Outcome], runs: list[Run], reference: np.ndarray | None) -> tuple[Any, Any]:
    """Colour range and isoline levels shared by every field picture: the reference's, else the first result's."""
    field_ref = reference
    if field_ref is None:
        ok = [results[_key(r)][0] for r in runs if results[_key(r)][0] is not None]
        field_ref = ok[0].distance if ok else None
    vmax_field: float | None = None
    levels: int | np.ndarray = 20
    if field_ref is not None:
        fin = field_ref[np.isfinite(field_ref)]
        if fin.size and fin.max() > 0:
            vmax_field = float(fin.max())
            levels = np.linspace(0.0, vmax_field, 22)[1:-1]
    return vmax_field, levels


def _check_camera(mesh: SimplexMesh, view: Any, up: Any) -> None:
    """``view`` and ``up`` of a surface's pictures checked before the solves (``"auto"`` is found when drawing)."""
    from .plotting import up_vector, view_list

    if mesh.reference.picture == "surface":  # a slice is seen along its normal
        view_list(view)
        if not (isinstance(up, str) and up == "auto"):
            up_vector(mesh.V, up)


def write_pictures(out: Path, mesh: SimplexMesh, sset: Any, runs: list[Run], results: dict[Run, Outcome],
                   rows: list[dict], rel_errors: dict[Run, np.ndarray], reference: np.ndarray | None, *,
                   view: Any = None, up: Any = "auto") -> None:
    """Write ``field_<method>.png``, ``error_<method>.png`` and ``gradient_histogram.png`` into ``out``.

    Parameters
    ----------
    out : Path
        The output folder (must exist).
    mesh, sset, runs
        As for :func:`solve_methods`.
    results, rows, rel_errors
        What :func:`solve_methods` and :func:`evaluate_methods` returned.
    reference : (n,) float ndarray or None
        The reference field: the colour range and the isolines of every field picture.
    """
    from .evaluation.slice_plot import draw_field

    # the vertices where every field is 0: marked in the pictures, left out of the histograms (a volume's source faces'
    # vertices too)
    src = sset.fixed_vertices(mesh) if sset.facets.size else sset.vertices
    vmax_field, levels = _field_scale(results, runs, reference)
    # one colour scale for every error map: the median of the methods' 99th percentiles (the reference's 0 aside),
    # so one very bad method does not wash out the others; the colour bar shows an arrow where it clips
    p99s = [p for p in (r["rel_p99"] for r in rows) if p is not None and np.isfinite(p) and p > 0]
    vmax_err = float(np.median(p99s)) if p99s else None
    src_txt = (", ".join(str(int(s)) for s in src[:5]) + (", ..." if len(src) > 5 else "") if sset.vertex_only
               else sset.description)
    for run, row in zip(runs, rows, strict=True):
        res = results[_key(run)][0]
        if res is None:
            continue
        title = f"{_label(run)} on {mesh.name} (source {src_txt})"
        draw_field(mesh, res, out / f"field_{_label(run, '_order')}.png", sources=src, title=title,
                   levels=levels, vmin=0.0 if vmax_field is not None else None, vmax=vmax_field, label="distance",
                   view=view, up=up)
        if run in rel_errors:
            rm = row["rel_mean"]
            mean_txt = f" (mean {100 * rm:.2f}%)" if rm is not None and np.isfinite(rm) else ""
            draw_field(mesh, rel_errors[run], out / f"error_{_label(run, '_order')}.png", sources=src, error=True,
                       vmax=vmax_err, title=f"{_label(run)}: relative error{mean_txt}", view=view, up=up)
    _write_histograms(out, mesh, src, runs, results, reference, rows[0]["reference"] if rows else "")


def _write_histograms(out: Path, mesh: SimplexMesh, src: np.ndarray, runs: list[Run], results: dict[Run, Outcome],
                      reference: np.ndarray | None, reference_label: str) -> None:
    """Gradient-norm histograms: the reference first, then every successful method."""
    from .evaluation import gradient_norm_histogram
    from .plotting import plot_gradient_histogram

    hist_fields = {} if reference is None else {reference_label: reference}
    for run in runs:
        res = results[_key(run)][0]
        if res is not None and _label(run) not in hist_fields:
            hist_fields[_label(run)] = res.distance
    if not hist_fields:
        return
    edges = np.linspace(0.0, 2.0, 161)
    hists = {k: gradient_norm_histogram(mesh, d, bins=edges, sources=src) for k, d in hist_fields.items()}
    nonzero = [np.flatnonzero(c > 0) for c, _ in hists.values()]
    last = max((int(nz[-1]) for nz in nonzero if nz.size), default=len(edges) - 2)
    cut = min(max(last + 2, int(np.searchsorted(edges, 1.5))), len(edges) - 1)  # show at least [0, 1.5]
    hists = {k: (c[:cut], e[: cut + 1]) for k, (c, e) in hists.items()}
    words = mesh.reference.words
    plot_gradient_histogram(hists, out / "gradient_histogram.png", title=f"‖∇d‖ per {words.one} on {mesh.name} "
                            f"({words.measure}-weighted, source {words.many} excluded)")


# ----------------------------------------------------------------------------------------------------------------------
# text table
# ----------------------------------------------------------------------------------------------------------------------

#: The columns of :func:`format_table`.
TABLE_COLUMNS = (
    Column("method", "method", align="left"),
    Column("order", "order", lambda v: f"{int(v)}"),
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
    "order": "its element order (2: the reference inside a tetrahedral mesh, qclp at order 2)",
    "time s": "set-up + solve, wall-clock seconds",
    "setup s": "the per-mesh part of it, paid once per solver",
    "iters": "solver iterations",
    "rel mean %": "mean of |d - ref| / ref over the vertices (sources excluded); ref: the exact distance on a "
                  "surface, qclp at order 2 inside a tetrahedral mesh",
    "rel max %": "its largest value",
    "rel p99 %": "its 99th percentile",
    "off-ridge %": "rel mean away from the ridge (cut locus) of the exact field (surfaces)",
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


def format_table(rows: list[dict]) -> str:
    """Aligned plain-text table of :func:`run_compare` rows (what ``cvxgeodesic compare`` prints).

    Parameters
    ----------
    rows : list of dict
        Rows as returned by :func:`run_compare` (missing keys and None print as ``-``).

    Returns
    -------
    str
        Header, a rule and one line per row; numbers right-aligned, errors in percent, times in seconds. Long
        status messages are shortened to 60 characters (the CSV keeps them whole). Laid out by
        :func:`cvxgeodesic.tables.text_table`.
    """
    return text_table(rows, TABLE_COLUMNS)
