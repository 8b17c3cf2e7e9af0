"""Rows of ``distance_matrix`` in one process against a 2-worker Dask ``LocalCluster``, side by side.

Not a test: run it by hand (needs ``dask[distributed]`` and ../shared/meshes)::

    python benchmarks/matrix_rows.py                          # bimba and horse, QCLP and QCQP-Hessian, 16 rows
    python benchmarks/matrix_rows.py --meshes bimba --rows 8 --methods qclp

For every mesh and method the same ``--rows`` distinct source vertices (random, ``--seed``) are solved

``one process``
    ``distance_matrix(mesh, rows, method)`` here, with the default thread policy (``threads=None``:
    the free cores when the solver is built; the count is printed);
``cluster, warm``
    ``distance_matrix(..., scheduler=client)`` on a 2-worker local cluster started once by this script
    exactly as ``workers=2`` starts one (``cpu_count // 2`` threads per worker) and warmed up (imports,
    compiled kernels loaded) before the first measurement;
``workers=2, cold``
    ``distance_matrix(..., workers=2)``: a cluster started and closed inside the call, what a single
    call costs end to end.

``speed-up`` is the one-process time over the cluster's. The conditions run one after the other for each
(mesh, method), in the order above, ``--repeat`` times (the minimum is kept), and the largest difference
between the cluster's and the one-process matrix is printed in units of the bounding-box diagonal.
The load average (``os.getloadavg``) is printed before and after: on a shared machine the numbers are
not a quiet-machine measurement.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from contextlib import ExitStack
from pathlib import Path

import numpy as np

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
MESHES = {"bimba": "bimba.obj", "horse": "horse.ply"}


def _load(name: str):
    import cvxgeodesic as cg

    if name.startswith("icosphere"):
        return cg.icosphere(int(name[len("icosphere"):] or 4))
    path = SHARED / MESHES.get(name, name)
    if not path.exists():
        raise SystemExit(f"{path} not found (development data in ../shared/meshes)")
    return cg.load_mesh(path)


def _timed(fn):
    t0 = time.perf_counter()
    out = fn()
    return time.perf_counter() - t0, out


def _load_text() -> str:
    return " ".join(f"{x:.2f}" for x in os.getloadavg())


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--meshes", nargs="+", default=["bimba", "horse"])
    parser.add_argument("--methods", nargs="+", default=["qclp", "qcqp-hessian"])
    parser.add_argument("--rows", type=int, default=16)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--repeat", type=int, default=1)
    args = parser.parse_args(argv)

    import cvxgeodesic as cg
    from cvxgeodesic._cluster import open_client
    from cvxgeodesic._threads import resolve_threads

    print(f"load average at the start: {_load_text()}; {os.cpu_count()} cores; {args.rows} rows per matrix",
          flush=True)
    head = (f"{'mesh':<8} {'faces':>7} {'method':<13} {'threads':>7} {'one process':>12} {'cluster, warm':>14} "
            f"{'speed-up':>9} {'workers=2, cold':>16} {'speed-up':>9} {'max |ΔD|/diag':>14}")
    with ExitStack() as stack:
        client, _cluster = open_client(stack, None, 2)
        client.wait_for_workers(2)
        for method in args.methods:  # imports and compiled kernels loaded here and on both workers before timing
            cg.distance_matrix(cg.icosphere(2), [0, 1], method=method)
            cg.distance_matrix(cg.icosphere(2), [0, 1], method=method, scheduler=client)
        print(head, flush=True)
        for name in args.meshes:
            mesh = _load(name)
            rng = np.random.default_rng(args.seed)
            rows = rng.choice(mesh.n_vertices, size=min(args.rows, mesh.n_vertices), replace=False).tolist()
            for method in args.methods:
                best = [np.inf, np.inf, np.inf]
                diff = 0.0
                threads = resolve_threads(None)
                for _ in range(args.repeat):
                    t_one, D_one = _timed(lambda: cg.distance_matrix(mesh, rows, method=method))  # noqa: B023
                    t_warm, D_warm = _timed(lambda: cg.distance_matrix(mesh, rows, method=method,  # noqa: B023
                                                                       scheduler=client))
                    t_cold, D_cold = _timed(lambda: cg.distance_matrix(mesh, rows, method=method,  # noqa: B023
                                                                       workers=2))
                    best = [min(b, t) for b, t in zip(best, (t_one, t_warm, t_cold), strict=True)]
                    diff = max(diff, float(np.abs(D_warm - D_one).max()), float(np.abs(D_cold - D_one).max()))
                line = (f"{name:<8} {mesh.n_faces:>7} {method:<13} {threads:>7} {best[0]:>10.2f} s "
                        f"{best[1]:>12.2f} s {best[0] / best[1]:>8.2f}x {best[2]:>14.2f} s "
                        f"{best[0] / best[2]:>8.2f}x {diff / mesh.bbox_diagonal:>14.1e}")
                print(line, flush=True)
    print(f"load average at the end: {_load_text()}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
