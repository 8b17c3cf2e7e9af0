"""The default method of ``distance_matrix``: time per row and error of its candidates, side by side.

Not a test: run it by hand (needs potpourri3d and pygeodesic; meshes from ../shared/meshes)::

    CVXGEODESIC_THREADS=1 OMP_NUM_THREADS=1 python benchmarks/row_default.py
    python benchmarks/row_default.py --meshes spot.obj --rows 3 --repeat 1     # a smoke run

For every mesh, ``--rows`` random distinct source vertices (``--seed``) are solved by every ``--methods`` entry in
this one process, one method after the other for each row (so that the load is shared alike): one solver built
per mesh and method (its set-up is printed apart), then one ``solve`` per row, repeated ``--repeat`` times (the
minimum is kept). The error of a row is the mean over the mesh's vertices of ``|d − d_exact| / d_exact`` (vertices
other than the source), against pygeodesic's exact MMP (``method="exact"``). Printed: set-up, median time per row,
its ratio to ``heat``'s, and the mean error over the rows. The load average is printed before and after.
"""

from __future__ import annotations

import argparse
import os
import time
from pathlib import Path

import numpy as np

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def main() -> None:
    import cvxgeodesic as cg

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="+", default=["spot.obj", "kitten.obj", "bimba.obj"])
    ap.add_argument("--methods", nargs="+", default=["heat", "qclp", "qcqp-hessian"])
    ap.add_argument("--rows", type=int, default=4)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}; load average {os.getloadavg()}; "
          f"CVXGEODESIC_THREADS={os.environ.get('CVXGEODESIC_THREADS')}", flush=True)
    cg.distance_matrix(cg.icosphere(1), [0], method="qclp", progress=False)  # compiled kernels loaded
    print(f"{'mesh':<12}{'method':<14}{'set-up s':>9}{'s / row':>9}{'× heat':>8}{'mean rel err':>14}", flush=True)
    for name in args.meshes:
        mesh = cg.load_mesh(SHARED / name)
        rng = np.random.default_rng(args.seed)
        rows = sorted(rng.choice(mesh.n_vertices, size=args.rows, replace=False).tolist())
        exact = cg.distance_matrix(mesh, rows, method="exact", progress=False)
        solvers, times = {}, {}
        for method in args.methods:
            t0 = time.perf_counter()
            solvers[method] = cg.GeodesicSolver(mesh, method)
            times[method] = (time.perf_counter() - t0, [], [])
        for k, v in enumerate(rows):
            for method in args.methods:
                best, d = np.inf, None
                for _ in range(args.repeat):
                    t0 = time.perf_counter()
                    d = solvers[method].solve(v).distance
                    best = min(best, time.perf_counter() - t0)
                keep = np.isfinite(exact[k]) & (exact[k] > 0)
                times[method][1].append(best)
                times[method][2].append(float(np.mean(np.abs(d[keep] - exact[k][keep]) / exact[k][keep])))
        heat = float(np.median(times["heat"][1])) if "heat" in times else np.nan
        for method in args.methods:
            setup, per_row, err = times[method]
            t = float(np.median(per_row))
            print(f"{name:<12}{method:<14}{setup:9.2f}{t:9.3f}{t / heat:8.1f}{100 * np.mean(err):13.2f}%", flush=True)
    print(f"load average after: {os.getloadavg()}")


if __name__ == "__main__":
    main()
