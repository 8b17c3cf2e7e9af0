"""Side-by-side comparison of methods inside a tetrahedral mesh: ``cvxgeodesic compare part.msh -s 0``.

No exact algorithm computes distance inside a general solid, so the reference is the most accurate field the
library computes, ``qclp`` at order 2 (exact wherever the source is visible, docs/volumes.md), unless the caller
gives one (an analytic field). :func:`run_tet_compare` solves the same sources with every method (the tet heat
method and Dijkstra included), measures each against the reference and writes ``compare.csv`` and one slice picture
per method (:func:`~cvxgeodesic.evaluation.tet_slice_plot.plot_tet_slice`, all on the reference's colour range).
"""

from __future__ import annotations

import csv
import io
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from ._atomic import atomic_write, check_output_dir
from .errors import CvxGeodesicError, ParameterError
from .tables import Column, text_table

__all__ = ["TET_CSV_COLUMNS", "format_tet_table", "run_tet_compare"]

#: Columns of the volume ``compare.csv``: ``rel_mean`` / ``rel_max`` / ``abs_max`` against the reference (sources
#: left out), ``reference`` names it.
TET_CSV_COLUMNS = ("method", "order", "solver", "time_s", "setup_s", "solve_s", "iterations", "rel_mean", "rel_max",
                   "abs_max", "reference", "status")
#: The reference when none is given: (method, order).
REFERENCE = ("qclp", 2)


def _resolve(methods: Any) -> list[str]:
    from .formulations import TET_METHODS, check_tet_method

    if isinstance(methods, str):
        methods = methods.split(",")
    names = [str(m).strip().lower() for m in methods if str(m).strip()]
    if not names:
        raise ParameterError("methods is empty: give at least one method name (or 'all')")
    out: list[str] = []
    for name in names:
        for g in (TET_METHODS if name == "all" else [check_tet_method(name)]):
            if g not in out:
                out.append(g)
    return out


def _solve(mesh: Any, method: str, order: int, sources: Any, m: float, solver: str) -> tuple[Any, float, Any]:
    from .api import GeodesicSolver

    t0 = time.perf_counter()
    try:
        kwargs: dict[str, Any] = {} if method in ("heat", "dijkstra") else {"solver": solver, "order": order}
        res = GeodesicSolver(mesh, method, m=m, **kwargs).solve(sources)
        return res, time.perf_counter() - t0, None
    except Exception as exc:  # noqa: BLE001 - a failed method becomes a row
        return None, time.perf_counter() - t0, exc


def run_tet_compare(mesh: Any, sources: Any, methods: Any, out_dir: str | os.PathLike, *, m: float = 1.0,
                    solver: str = "auto", reference: np.ndarray | None = None, progress: bool = True) -> list[dict]:
    """Solve with several methods inside a tetrahedral mesh and compare each with a reference field.

    Parameters
    ----------
    mesh : TetMesh or (V, T) tuple
        ``n`` vertices.
    sources : anything :meth:`GeodesicSolver.solve` takes on a tetrahedral mesh
    methods : str or sequence of str
        Names of :data:`~cvxgeodesic.formulations_tet.TET_METHODS` (order 1), or ``"all"``.
    out_dir : str or os.PathLike
        Output folder (created if missing): ``compare.csv`` and ``slice_<method>.png``.
    m : float
        Smoothness multiplier of the quadratic formulations.
    solver : {"auto", "ipm", "clarabel"}
    reference : (n,) float ndarray, optional
        The reference field (e.g. analytic); default ``qclp`` at order 2, solved here and listed as a row.
    progress : bool
        One line per method on stderr.

    Returns
    -------
    list of dict
        Keys :data:`TET_CSV_COLUMNS`, one row per method (the reference first when it is solved here).

    Raises
    ------
    ParameterError
        A method that does not apply to volumes (the message names those that do), an empty list.
    """
    from .evaluation.tet_slice_plot import plot_tet_slice
    from .mesh.convert import as_mesh
    from .mesh.tetmesh import TetMesh
    from .sources import resolve_sources as resolve_tet_sources

    mesh = as_mesh(mesh)
    if not isinstance(mesh, TetMesh):
        raise ParameterError("run_tet_compare takes a tetrahedral mesh; use run_compare for surfaces")
    names = _resolve(methods)
    src = resolve_tet_sources(mesh, sources)
    out = check_output_dir(out_dir, "out_dir")  # a folder that cannot take files fails now, not after the solves
    out.mkdir(parents=True, exist_ok=True)
    runs: list[tuple[str, int]] = [(n, 1) for n in names]
    ref_label = "given"
    if reference is None:
        runs.insert(0, REFERENCE)
        ref_label = f"{REFERENCE[0]} order {REFERENCE[1]}"
    rows, fields = [], {}
    for i, (name, order) in enumerate(runs, 1):
        res, wall, err = _solve(mesh, name, order, src, m, solver)
        row: dict[str, Any] = dict.fromkeys(TET_CSV_COLUMNS)
        row.update(method=name, order=order, time_s=float(wall), reference=ref_label)
        if err is not None:
            row["status"] = " ".join(str(err).split()) if isinstance(err, CvxGeodesicError) else \
                f"{type(err).__name__}: {err}"
        else:
            info = res.info
            row.update(solver=info.solver, setup_s=float(info.setup_time), solve_s=float(info.solve_time),
                       iterations=int(info.iterations), status=info.status)
            fields[(name, order)] = res.distance
            if reference is None and (name, order) == REFERENCE:
                reference = res.distance
        rows.append(row)
        if progress:
            print(f"[{i}/{len(runs)}] {name} (order {order})  {wall:8.2f} s  {row['status']}", file=sys.stderr)
    fixed = src.fixed_vertices(mesh)
    if reference is not None:
        ref = np.asarray(reference, dtype=float)
        ok = np.isfinite(ref) & (ref > 0)
        ok[fixed] = False
        for row in rows:
            d = fields.get((row["method"], row["order"]))
            if d is None or not ok.any():
                continue
            err = np.abs(d[ok] - ref[ok])
            row.update(rel_mean=float(np.mean(err / ref[ok])), rel_max=float(np.max(err / ref[ok])),
                       abs_max=float(err.max()))
    _write_csv(out / "compare.csv", rows)
    top = float(np.max(reference[np.isfinite(reference)])) if reference is not None else None
    marks = mesh.V[fixed] if fixed.size else None
    for (name, order), d in fields.items():
        plot_tet_slice(mesh, d, out / f"slice_{name}{'_order2' if order == 2 else ''}.png", vmin=0.0, vmax=top,
                       title=f"{name} (order {order}), sources {src.description}", points=marks,
                       colorbar_label="distance")
    return rows


def _write_csv(path: Path, rows: list[dict]) -> None:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(TET_CSV_COLUMNS)
    for row in rows:
        w.writerow(["" if row[k] is None else (f"{row[k]:.6g}" if isinstance(row[k], float) else row[k])
                    for k in TET_CSV_COLUMNS])
    data = buf.getvalue().encode("utf-8")

    def write(fh) -> None:
        fh.write(data)

    atomic_write(path, write, allow=None)  # a read-only file in the folder is refused: no override here


def format_tet_table(rows: list[dict]) -> str:
    """The rows of :func:`run_tet_compare` as an aligned text table."""
    pct = lambda v: f"{100 * v:.3g} %"  # noqa: E731
    cols = [Column("method", "method", align="left"), Column("order", "order"), Column("time", "time_s",
            lambda v: f"{v:.2f} s"), Column("iter", "iterations"), Column("mean err", "rel_mean", pct),
            Column("max err", "rel_max", pct), Column("status", "status", align="left", max_len=60)]
    return text_table(rows, cols) + f"\n(errors against: {rows[0]['reference'] if rows else '-'})"
