"""Rows of a distance matrix: full rows, local rows (``max_distance``) and a loop over the heat method, in one run.

Not a test: run it by hand (needs potpourri3d and pygeodesic; meshes from ../shared/meshes)::

    python benchmarks/matrix.py                                   # kitten (18.9K faces), 100 rows, one thread
    python benchmarks/matrix.py --mesh bimba.obj --rows 100 --threads 1
    python benchmarks/matrix.py --big horse.ply --big-rows 1000   # + the 1,000-row local matrix (97K faces)
    python benchmarks/matrix.py --big horse.ply --big-rows 1000 --workers 2   # + the same on a local Dask cluster
    python benchmarks/matrix.py --rows 8 --exact-rows 4 --mesh spot.obj    # a smoke run (seconds)

What it measures, for ``--rows`` random distinct source vertices (``--seed``) of ``--mesh``:

``heat loop``
    ``potpourri3d.MeshHeatMethodDistanceSolver`` built once, then one ``compute_distance`` per row (what a user
    of potpourri3d writes; the issue's reference).
``full rows``
    ``distance_matrix(mesh, rows, method=--method)`` (default ``qclp``, order 1): one solver, one solve per row.
``local rows``
    ``distance_matrix(..., max_distance=r)`` with ``r = --radius`` (default 0.1) times the bounding-box diagonal
    (the "diameter" of the issue): each row solved on the patch of faces within ``1.5 r`` on the edge graph.
    ``--tol`` applies to the full and the local rows; without it each takes the library's default (1e-8 for full
    rows, ``api.LOCAL_ROW_TOL`` = 1e-5 for local rows: ~35 % less time, the same error against MMP to three
    digits, docs/performance.md).

Each condition runs in a fresh process (spawned; the compiled kernels are loaded there by one tiny solve before
the clock starts), with ``CVXGEODESIC_THREADS``/``OMP_NUM_THREADS`` = ``--threads``; its wall time and the peak
resident memory of that process are printed, and the ratios to the heat loop. Errors: the mean absolute error
against the exact distance (pygeodesic's MMP) over the vertices within ``r`` of the first ``--exact-rows`` rows,
both fields clipped at ``r`` (a local row only says "farther than r" beyond it), in % of ``r``; and the mean
relative error of the full rows over the whole mesh (heat likewise). ``--big`` adds a ``--big-rows`` local matrix
on that mesh (time, peak memory, stored entries), and with ``--workers N`` the same on a local Dask cluster of N
workers (``cpu_count // N`` threads each). The load average is printed before and after: on a loaded machine the
times are not a quiet-machine measurement, the ratios (same process conditions, back to back) are steadier.
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from unittest import mock

import numpy as np

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def _mesh(name: str):
    import cvxgeodesic as cg

    path = Path(name) if Path(name).exists() else SHARED / name
    if not path.exists():
        raise SystemExit(f"{name}: not found (development meshes are in ../shared/meshes)")
    return cg.load_mesh(path)


def _peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # kilobytes on Linux


def _warm() -> None:
    import cvxgeodesic as cg

    cg.distance_matrix(cg.icosphere(1), [0], method="qclp", progress=False)


def _heat(name: str, rows: list[int]) -> tuple[float, np.ndarray, float]:
    import potpourri3d as pp3d

    mesh = _mesh(name)
    t0 = time.perf_counter()
    solver = pp3d.MeshHeatMethodDistanceSolver(mesh.V, mesh.F)
    D = np.stack([solver.compute_distance(v) for v in rows])
    return time.perf_counter() - t0, D, _peak_mb()


def _rows(name: str, rows: list[int], method: str, r: float | None, tol: float | None,
          workers: int | None = None):
    import cvxgeodesic as cg

    mesh = _mesh(name)
    _warm()
    t0 = time.perf_counter()
    D = cg.distance_matrix(mesh, rows, method=method, max_distance=r, progress=False, workers=workers, tol=tol)
    return time.perf_counter() - t0, D, _peak_mb()


def _exact(name: str, rows: list[int]) -> np.ndarray:
    import cvxgeodesic as cg

    return cg.distance_matrix(_mesh(name), rows, method="exact", progress=False)


def _run(threads: int, fn, *args):
    """``fn(*args)`` in a fresh spawned process with ``threads`` threads (its peak memory is its own)."""
    env = {k: str(threads) for k in ("CVXGEODESIC_THREADS", "OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS",
                                     "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}
    with mock.patch.dict(os.environ, env):  # inherited by the spawned child, restored afterwards
        with ProcessPoolExecutor(max_workers=1, mp_context=get_context("spawn")) as pool:
            return pool.submit(fn, *args).result()


def _dense(L, n_cols: int) -> np.ndarray:
    out = np.full((L.shape[0], n_cols), np.inf)
    coo = L.tocoo()
    out[coo.row, coo.col] = coo.data
    return out


def _error_inside(D: np.ndarray, exact: np.ndarray, r: float) -> float:
    inside = exact <= r
    return float(np.abs(np.minimum(D, r) - exact)[inside].mean() / r * 100)


def _relative(D: np.ndarray, exact: np.ndarray) -> float:
    ok = np.isfinite(exact) & (exact > 0)
    return float((np.abs(D - exact)[ok] / exact[ok]).mean() * 100)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--mesh", default="kitten.obj", help="a file of ../shared/meshes or a path")
    parser.add_argument("--rows", type=int, default=100)
    parser.add_argument("--method", default="qclp")
    parser.add_argument("--radius", type=float, default=0.1, help="max_distance over the bounding-box diagonal")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--tol", type=float, default=None,
                        help="tol of the full and local rows (default: the library's, 1e-8 full and 1e-5 local)")
    parser.add_argument("--exact-rows", type=int, default=10, help="rows compared with the exact distance")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--big", default=None, help="mesh of the large local matrix (e.g. horse.ply, 97K faces)")
    parser.add_argument("--big-rows", type=int, default=1000)
    parser.add_argument("--workers", type=int, default=None, help="also the large local matrix on N Dask workers")
    args = parser.parse_args(argv)

    load = lambda: " ".join(f"{x:.2f}" for x in os.getloadavg())  # noqa: E731
    print(f"load average at the start: {load()}; {os.cpu_count()} cores; {args.threads} thread(s) per process",
          flush=True)
    mesh = _mesh(args.mesh)
    rng = np.random.default_rng(args.seed)
    rows = rng.choice(mesh.n_vertices, size=min(args.rows, mesh.n_vertices), replace=False).tolist()
    r = args.radius * mesh.bbox_diagonal
    print(f"{args.mesh}: {mesh.n_vertices} vertices, {mesh.n_faces} faces; {len(rows)} rows; method {args.method}; "
          f"r = {args.radius:g} × diagonal = {r:.4g}; tol {args.tol or 'default (1e-8 full, 1e-5 local)'}", flush=True)
    t_heat, D_heat, m_heat = _run(args.threads, _heat, args.mesh, rows)
    t_full, D_full, m_full = _run(args.threads, _rows, args.mesh, rows, args.method, None, args.tol)
    t_local, L, m_local = _run(args.threads, _rows, args.mesh, rows, args.method, r, args.tol)
    print(f"{'':<12} {'time':>9} {'per row':>9} {'× heat':>7} {'peak MB':>8}")
    for label, t, mem in (("heat loop", t_heat, m_heat), ("full rows", t_full, m_full),
                          ("local rows", t_local, m_local)):
        print(f"{label:<12} {t:>7.2f} s {t / len(rows) * 1e3:>6.1f} ms {t / t_heat:>7.1f} {mem:>8.0f}")
    k = min(args.exact_rows, len(rows))
    exact = _run(args.threads, _exact, args.mesh, rows[:k])
    D_local = _dense(L[:k], mesh.n_vertices)
    e_full, e_local = _error_inside(D_full[:k], exact, r), _error_inside(D_local, exact, r)
    print(f"mean error within r against exact MMP ({k} rows, % of r): heat {_error_inside(D_heat[:k], exact, r):.3f}, "
          f"full {e_full:.3f}, local {e_local:.3f} (local / full = {e_local / e_full:.3f})")
    print(f"mean relative error over the mesh ({k} rows, %): heat {_relative(D_heat[:k], exact):.2f}, "
          f"full {_relative(D_full[:k], exact):.2f}")
    print(f"local rows: {L.nnz / len(rows):.0f} stored entries per row", flush=True)
    if args.big:
        big = _mesh(args.big)
        rng = np.random.default_rng(args.seed)
        big_rows = rng.choice(big.n_vertices, size=min(args.big_rows, big.n_vertices), replace=False).tolist()
        rb = args.radius * big.bbox_diagonal
        t, Lb, mem = _run(args.threads, _rows, args.big, big_rows, args.method, rb, args.tol)
        print(f"{args.big}: {big.n_faces} faces, {len(big_rows)} local rows (r = {rb:.4g}): {t:.1f} s "
              f"({t / len(big_rows) * 1e3:.0f} ms per row), peak {mem:.0f} MB, {Lb.nnz} stored entries", flush=True)
        if args.workers:
            t, Lw, mem = _run(args.threads, _rows, args.big, big_rows, args.method, rb, args.tol, args.workers)
            same = abs(Lw - Lb).max() if Lw.nnz == Lb.nnz else float("nan")
            print(f"  on a local Dask cluster of {args.workers} workers: {t:.1f} s, peak of the calling process "
                  f"{mem:.0f} MB (workers not counted), max difference to in-process {same:.1e}", flush=True)
    print(f"load average at the end: {load()}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
