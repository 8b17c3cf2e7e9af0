"""The demo behind ``make demo`` / ``cvxgeodesic demo``: QCQP-Hessian on a mesh the package carries."""

from __future__ import annotations

import sys
from importlib import resources
from pathlib import Path

from .api import GeodesicSolver
from .mesh.io import load_mesh, save_distance
from .mesh.trimesh import TriMesh
from .tables import Column, text_table

DEMO_METHODS = ("qcqp-hessian", "qclp", "heat", "fmm", "dijkstra")


def demo_mesh() -> TriMesh:
    """Spot the cow (Keenan Crane, CC0), shipped in ``cvxgeodesic/data``: 2,930 vertices, 5,856 faces."""
    with resources.as_file(resources.files("cvxgeodesic") / "data" / "spot.obj") as path:
        return load_mesh(path)


def run_demo(out_dir: str | Path, *, source: int = 0, stream=None) -> list[dict]:
    """Solve QCQP-Hessian (and the baselines for comparison) on the demo mesh and write outputs.

    Writes ``spot_qcqp-hessian.ply`` (mesh with a per-vertex ``distance``
    property) and ``spot_qcqp-hessian.png`` (field with isolines) into
    ``out_dir`` and prints a table of time and error against the exact
    (MMP) distance.

    Parameters
    ----------
    out_dir : str or Path
        Created if missing.
    source : int
        Source vertex.
    stream : file-like, optional
        Where the table goes (default ``sys.stdout``).

    Returns
    -------
    list of dict
        One row per method of :data:`DEMO_METHODS`, then the exact field's: the record of
        :func:`cvxgeodesic.evaluation.summary.summarize` (keys ``SUMMARY_KEYS``: ``method, solver,
        time_s, iterations, rel_mean, rel_max, ridge_jump_p95, off_ridge_rel_mean``, ...).
    """
    from .evaluation.summary import summarize
    from .plotting import plot_field

    stream = stream or sys.stdout
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    mesh = demo_mesh()
    exact = GeodesicSolver(mesh, "exact").solve(source)
    rows = []
    fields = {}
    for method in DEMO_METHODS:
        res = GeodesicSolver(mesh, method).solve(source)
        fields[method] = res.distance
        rows.append(summarize(mesh, res, exact.distance, gradient=False))
    rows.append(summarize(mesh, exact, exact.distance, gradient=False))
    main = "qcqp-hessian"
    ply = out / f"spot_{main}.ply"
    png = out / f"spot_{main}.png"
    save_distance(ply, mesh, fields[main])
    plot_field(mesh, fields[main], png, title=f"{main} (m = 1), source vertex {source}", sources=[source],
               colorbar_label="geodesic distance")
    print(f"mesh: spot.obj ({mesh.n_vertices} vertices, {mesh.n_faces} faces), source vertex {source}", file=stream)
    print(format_rows(rows), file=stream)
    print("time includes per-mesh set-up; ridge = 95th percentile of the gradient jump near the exact ridge "
          "(lower is smoother); off-ridge = mean relative error away from it", file=stream)
    print(f"wrote {ply}\nwrote {png}", file=stream)
    return rows


#: The columns of :func:`format_rows`.
DEMO_COLUMNS = (
    Column("method", "method", align="left"),
    Column("solver", "solver", lambda s: str(s).split(".")[0], align="left"),
    Column("time [s]", "time_s", lambda v: f"{v:.3f}"),
    Column("iters", "iterations", lambda v: f"{int(v):d}"),
    Column("mean rel err", "rel_mean", lambda v: f"{v:.3%}"),
    Column("max rel err", "rel_max", lambda v: f"{v:.2%}"),
    Column("ridge", "ridge_jump_p95", lambda v: f"{v:.3f}"),
    Column("off-ridge err", "off_ridge_rel_mean", lambda v: f"{v:.3%}"),
)


def format_rows(rows: list[dict]) -> str:
    """Aligned text table of demo rows (:func:`cvxgeodesic.tables.text_table` with :data:`DEMO_COLUMNS`)."""
    return text_table(rows, DEMO_COLUMNS)
