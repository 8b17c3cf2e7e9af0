"""Levers of the adapted solve (``resolution=``): face fraction, error estimate, boundary kept or not.

For each mesh and source vertex: the exact field (MMP), the heat method (time unit), then order 2 ``qclp`` on
quadric copies at several fractions of the faces. Printed per row: mean and max relative error against exact, time
(decimation + solve + transfer, best of ``--repeats``) over heat's, and the error estimates:
``shortening`` (:func:`~cvxgeodesic.strategies.adapted.edge_shortening`, free) and ``half`` (the mean relative
difference to the solve at half the faces, which costs that solve).

Run from the repository root, one thread::

    CVXGEODESIC_THREADS=1 PYTHONPATH=src python benchmarks/adapted_levers.py kitten fandisk bimba
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.evaluation.errors import relative_error

MESHES = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def timed(fn, repeats: int):
    best, out = np.inf, None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return out, best


def rel_diff(a: np.ndarray, b: np.ndarray, src: int) -> float:
    keep = np.isfinite(a) & np.isfinite(b) & (b > 0)
    keep[src] = False
    return float(np.mean(np.abs(a[keep] - b[keep]) / b[keep]))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("meshes", nargs="+")
    ap.add_argument("--fractions", default="0.05,0.1,0.25")
    ap.add_argument("--source", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--method", default="qclp")
    ap.add_argument("--out", default=None, help="append JSON lines here")
    args = ap.parse_args()
    fractions = sorted(float(f) for f in args.fractions.split(","))
    for name in args.meshes:
        path = next(MESHES.glob(f"{name}.*"))
        mesh = cg.load_mesh(path)
        src = args.source
        exact = cg.geodesic_distance(mesh, src, method="exact")
        _, t_heat = timed(lambda mesh=mesh, src=src: cg.geodesic_distance(mesh, src, method="heat"), 3)
        fields: dict[float, np.ndarray] = {}
        for frac in fractions:
            def run(frac=frac, mesh=mesh, src=src):
                s = cg.GeodesicSolver(mesh, args.method, resolution=frac, m=0.0 if args.method == "qclp" else 1.0)
                return s.solve(src)
            res, t = timed(run, args.repeats)
            fields[frac] = res.distance
            ad = res.info.extra["adapted"]
            err = relative_error(res.distance, exact, [src])
            row = {"mesh": name, "faces": mesh.n_faces, "fraction": frac, "solve_faces": ad["faces"],
                   "mean_err": float(np.nanmean(err)), "max_err": float(np.nanmax(err)),
                   "signed": float(np.nanmean(np.where(np.isnan(err), np.nan, (res.distance - exact)
                                                       / np.where(exact > 0, exact, 1)))),
                   "time_over_heat": t / t_heat, "t_heat": t_heat, "t": t,
                   "decimate": ad["decimate_time"], "solve": ad["solve_time"], "transfer": ad["transfer_time"],
                   "shortening": ad["error_estimate"], "fallback": ad["fallback"],
                   "max_surface_distance_rel": ad.get("max_surface_distance", 0.0) / mesh.bbox_diagonal}
            half = [f for f in fractions if abs(f - frac / 2) < 1e-9 or abs(f - frac / 2.5) < 1e-9]
            if half:
                row["half"] = rel_diff(fields[half[0]], res.distance, src)
            print(json.dumps(row), flush=True)
            if args.out:
                with open(args.out, "a") as fh:
                    fh.write(json.dumps(row) + "\n")


if __name__ == "__main__":
    main()
