"""The demo behind ``make demo`` / ``cvxgeodesic demo``: QCQP-Hessian on a mesh the package carries, next to the
other choices, and which to use for what (:func:`guidance`, the README's "Which method to use" in short)."""

from __future__ import annotations

import sys
from importlib import resources
from pathlib import Path

from .api import GeodesicSolver
from .mesh.io import load_mesh, save_distance
from .mesh.trimesh import TriMesh
from .tables import Column, text_table

#: The rows of the demo's table: ``(label, method, order)``; order 2 right after the order-1 ``qclp``.
DEMO_CASES = (("qcqp-hessian", "qcqp-hessian", 1), ("qclp", "qclp", 1), ("qclp order=2", "qclp", 2),
              ("heat", "heat", 1), ("fmm", "fmm", 1), ("dijkstra", "dijkstra", 1))


def demo_mesh() -> TriMesh:
    """Spot the cow (Keenan Crane, CC0), shipped in ``cvxgeodesic/data``: 2,930 vertices, 5,856 faces."""
    with resources.as_file(resources.files("cvxgeodesic") / "data" / "spot.obj") as path:
        return load_mesh(path)


def run_demo(out_dir: str | Path, *, source: int = 0, stream=None) -> list[dict]:
    """Solve QCQP-Hessian (and the other choices for comparison) on the demo mesh and write outputs.

    Writes ``spot_qcqp-hessian.ply`` (mesh with a per-vertex ``distance``
    property) and ``spot_qcqp-hessian.png`` (field with isolines) into
    ``out_dir`` and prints a table of time and error against the exact
    (MMP) distance, then which method to use for what (:func:`guidance`).

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
        One row per case of :data:`DEMO_CASES`, then the exact field's: the record of
        :func:`cvxgeodesic.evaluation.summary.summarize` (keys ``SUMMARY_KEYS``: ``method, solver,
        time_s, iterations, rel_mean, rel_max, ridge_jump_p95, off_ridge_rel_mean``, ...), whose
        ``method`` is the case's label (``"qclp order=2"``).
    """
    from ._atomic import check_output_dir
    from .evaluation.summary import summarize
    from .plotting import plot_field

    stream = stream or sys.stdout
    out = check_output_dir(out_dir, "out_dir")  # a folder that cannot take files fails now, not after the solves
    out.mkdir(parents=True, exist_ok=True)
    mesh = demo_mesh()
    exact = GeodesicSolver(mesh, "exact").solve(source)
    rows = []
    fields = {}
    for label, method, order in DEMO_CASES:
        res = GeodesicSolver(mesh, method, order=order).solve(source)
        fields[label] = res.distance
        rows.append({**summarize(mesh, res, exact.distance, gradient=False), "method": label})
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
    print(guidance(rows), file=stream)
    print(f"wrote {ply}\nwrote {png}", file=stream)
    return rows


def guidance(rows: list[dict]) -> str:
    """Which method to use for what, with this run's numbers (the README's "Which method to use" in short).

    Parameters
    ----------
    rows : list of dict
        The rows :func:`run_demo` returns (labels of :data:`DEMO_CASES`, then ``"exact"``).

    Returns
    -------
    str
        Five lines: smoothness at the ridge, accuracy, speed, exactness, and what only the convex methods take.
    """
    by = {r["method"]: r for r in rows}
    default, order2, exact, heat = by["qcqp-hessian"], by["qclp order=2"], by["exact"], by["heat"]
    best = min((r for r in rows if r["method"] not in ("qclp order=2", "exact")), key=lambda r: r["rel_mean"])
    lines = [
        "which method to use (the README's \"Which method to use\" has the numbers on more meshes):",
        f"  smooth isolines at the ridge  the default, qcqp-hessian: ridge {default['ridge_jump_p95']:.2f} "
        f"(heat {heat['ridge_jump_p95']:.2f}, exact {exact['ridge_jump_p95']:.2f})",
        f"  accuracy                      qclp with order=2: mean error {order2['rel_mean']:.3%}, "
        f"{best['rel_mean'] / order2['rel_mean']:.0f}x below the best",
        f"                                order-1 method here ({best['method']}), in "
        f"{order2['time_s'] / by['qclp']['time_s']:.0f}x the time of qclp",
        f"  speed                         heat: {heat['time_s']:.3f} s, mean error {heat['rel_mean']:.2%}; "
        "each further source costs two back-substitutions",
        "  exactness                     exact (MMP): on manifold meshes, from vertices and points",
        "  non-manifold meshes with sources inside faces and on curves: the convex methods (fmm and exact",
        "  refuse non-manifold meshes, heat takes vertex sources only, dijkstra follows the edges)",
    ]
    return "\n".join(lines)


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
