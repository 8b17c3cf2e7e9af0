"""Levers of the adapted solve (``resolution=``): face fraction and error estimate.

For each mesh and source vertex: the exact field (MMP), the heat method (time unit), then order 2 ``qclp`` on
quadric copies at several fractions of the faces. Printed per row: mean and max relative error against exact, time
(solver construction with the decimation + solve + transfer, without the error estimate, best of ``--repeats``)
over heat's, and the error estimates of a second run: ``estimate`` (the library's: the mean relative difference to
the field solved on a copy with half the faces; ``t_est`` that run's time over heat's) and ``shortening``
(:func:`~cvxgeodesic.strategies.adapted.edge_shortening`, free).

Run from the repository root, one thread::

    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/adapted_levers.py kitten fandisk bimba
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.evaluation.errors import relative_error
from report_common import emit_row, timed

MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"




def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--fractions", default="0.05,0.1,0.25")
    ap.add_argument("--source", type=float, default=0, help="vertex index, or a fraction (0, 1) of the vertex count")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--method", default="qclp")
    ap.add_argument("--out", default=None, help="append JSON lines here")
    args = ap.parse_args()
    fractions = sorted(float(f) for f in args.fractions.split(","))
    for name in args.meshes:
        path = next(MESHES.glob(f"{name}.*"))
        mesh = cg.load_mesh(path)
        src = int(args.source * mesh.n_vertices) if 0 < args.source < 1 else int(args.source)
        exact = cg.geodesic_distance(mesh, src, method="exact")
        _, t_heat = timed(lambda mesh=mesh, src=src: cg.geodesic_distance(mesh, src, method="heat"), 3)
        for frac in fractions:
            def run(frac=frac, mesh=mesh, src=src):
                s = cg.GeodesicSolver(mesh, args.method, resolution=frac, m=0.0 if args.method == "qclp" else 1.0,
                                      estimate_error=False)
                return s.solve(src)
            res, t = timed(run, args.repeats)
            t0 = time.perf_counter()
            est = cg.GeodesicSolver(mesh, args.method, resolution=frac).solve(src).info.extra["adapted"]
            t_est = time.perf_counter() - t0
            ad = res.info.extra["adapted"]
            err = relative_error(res.distance, exact, [src])
            row = {"mesh": name, "faces": mesh.n_faces, "fraction": frac, "solve_faces": ad["faces"],
                   "mean_err": float(np.nanmean(err)), "max_err": float(np.nanmax(err)),
                   "signed": float(np.nanmean(np.where(np.isnan(err), np.nan, (res.distance - exact)
                                                       / np.where(exact > 0, exact, 1)))),
                   "time_over_heat": t / t_heat, "t_heat": t_heat, "t": t,
                   "decimate": ad["decimate_time"], "solve": ad["solve_time"], "transfer": ad["transfer_time"],
                   "estimate": est["error_estimate"], "t_est_over_heat": t_est / t_heat,
                   "shortening": ad.get("edge_shortening"), "fallback": ad["fallback"],
                   "max_surface_distance_rel": ad.get("max_surface_distance", 0.0) / mesh.bbox_diagonal}
            emit_row(row, args.out)


if __name__ == "__main__":
    main()
