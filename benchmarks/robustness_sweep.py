"""Robustness sweep: every mesh in ../shared/meshes through one method per family.

Not a test: run it by hand::

    python benchmarks/robustness_sweep.py                      # all shared meshes up to 25K faces, Clarabel
    python benchmarks/robustness_sweep.py --max-faces 0        # no size limit (slow: up to minutes per mesh)
    python benchmarks/robustness_sweep.py --solver ipm         # the structured interior-point solver instead
    python benchmarks/robustness_sweep.py --details            # one line per mesh and method

For every mesh (source vertex 0) and method it records one outcome:

``solved``
    The field passed every check: no NaN; ``inf`` exactly on the vertices not connected
    to the source; 0 at the source; for ``qclp`` and ``lclp`` below Dijkstra (``lclp``
    equal to it) within 1e-6 of the bounding-box diagonal.
``negative``
    Solved and passed the checks, but some distance is below ``-1e-6 · bbox`` (a
    property of the formulation on that mesh, not a crash; counted apart).
``rejected``
    A documented input error (:class:`~cvxgeodesic.errors.MeshError`, e.g.
    :class:`~cvxgeodesic.errors.NonManifoldError`), with its reason.
``solver failed``
    A documented :class:`~cvxgeodesic.errors.SolverError` (the backend's status).
``bad output``
    A field that failed a check above.
``crashed``
    Any other exception: a bug.
"""

from __future__ import annotations

import argparse
import collections
import sys
import time
import traceback
import warnings
from pathlib import Path

import numpy as np
from scipy.sparse.csgraph import dijkstra

import cvxgeodesic as cg
from cvxgeodesic.errors import MeshError, SolverError

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
METHODS = ["qclp", "lclp", "qcqp-laplacian", "qcqp-hessian", "dijkstra", "heat", "fmm", "exact"]
MESH_SUFFIXES = (".obj", ".off", ".ply", ".stl")


def mesh_files(root: Path) -> list[Path]:
    """thingi10k_small/* first, then the other shared meshes, each group sorted by name."""
    small = sorted(p for p in (root / "thingi10k_small").glob("*") if p.suffix.lower() in MESH_SUFFIXES)
    other = sorted(p for p in root.glob("*") if p.suffix.lower() in MESH_SUFFIXES)
    return small + other


def check_field(mesh, d: np.ndarray, sources: np.ndarray, method: str, d_dijkstra: np.ndarray) -> str:
    """Outcome of one solved field: ``"solved"``, ``"negative"`` or ``"bad output: <why>"``."""
    tol = 1e-6 * mesh.bbox_diagonal
    if d.shape != (mesh.n_vertices,):
        return f"bad output: shape {d.shape}"
    if np.isnan(d).any():
        return f"bad output: {int(np.isnan(d).sum())} NaN"
    unreachable = np.isinf(d_dijkstra)
    if not np.array_equal(np.isinf(d), unreachable):
        return "bad output: inf pattern differs from the unreachable vertices"
    if np.any(d[sources] != 0):
        return "bad output: nonzero at a source"
    fin = ~unreachable
    if method in ("qclp", "lclp") and np.any(d[fin] > d_dijkstra[fin] + tol):
        return "bad output: above Dijkstra"
    if method == "lclp" and np.any(np.abs(d[fin] - d_dijkstra[fin]) > tol):
        return "bad output: LCLP differs from Dijkstra"
    if d[fin].min() < -tol:
        return "negative"
    return "solved"


def run_one(mesh, method: str, solver: str, sources: np.ndarray, d_dijkstra: np.ndarray) -> tuple[str, str, float]:
    """Returns ``(outcome, detail, seconds)``."""
    kw = {} if method in cg.BASELINE_METHODS else {"solver": solver}
    t0 = time.perf_counter()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = cg.GeodesicSolver(mesh, method, **kw).solve(sources)
    except MeshError as exc:
        return "rejected", f"{type(exc).__name__}", time.perf_counter() - t0
    except SolverError as exc:
        return "solver failed", f"{exc.status}", time.perf_counter() - t0
    except Exception as exc:  # a bug
        return "crashed", f"{type(exc).__name__}: {exc}\n{traceback.format_exc()}", time.perf_counter() - t0
    dt = time.perf_counter() - t0
    outcome = check_field(mesh, res.distance, sources, method, d_dijkstra)
    detail = ""
    if outcome == "negative":
        detail = f"min {res.distance[np.isfinite(res.distance)].min() / mesh.bbox_diagonal:.1e}·bbox"
    elif outcome.startswith("bad output"):
        outcome, detail = "bad output", outcome.split(": ", 1)[1]
    return outcome, detail, dt


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--root", type=Path, default=SHARED, help="folder of meshes (default ../shared/meshes)")
    ap.add_argument("--methods", default=",".join(METHODS), help="comma-separated methods")
    ap.add_argument("--solver", default="clarabel", choices=["clarabel", "ipm", "auto"],
                    help="backend of the convex formulations (default clarabel)")
    ap.add_argument("--max-faces", type=int, default=25_000, help="skip bigger meshes (0: no limit)")
    ap.add_argument("--details", action="store_true", help="one line per mesh and method")
    args = ap.parse_args(argv)
    if not args.root.is_dir():
        print(f"no meshes at {args.root}", file=sys.stderr)
        return 1
    methods = [m.strip() for m in args.methods.split(",") if m.strip()]
    counts = {m: collections.Counter() for m in methods}
    reasons = {m: collections.Counter() for m in methods}
    times = collections.Counter()
    crashes = []
    n_meshes = 0
    for path in mesh_files(args.root):
        name = str(path.relative_to(args.root))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                mesh = cg.load_mesh(path)
        except Exception as exc:
            print(f"{name}: cannot load: {type(exc).__name__}: {exc}")
            continue
        if args.max_faces and mesh.n_faces > args.max_faces:
            continue
        n_meshes += 1
        sources = np.array([0])
        d_dij = dijkstra(mesh.vertex_adjacency, directed=False, indices=0)
        for method in methods:
            outcome, detail, dt = run_one(mesh, method, args.solver, sources, d_dij)
            counts[method][outcome] += 1
            times[method] += dt
            if outcome in ("rejected", "solver failed", "bad output", "negative"):
                reasons[method][detail.split("·")[0] if outcome != "negative" else "min < 0"] += 1
            if outcome == "crashed":
                crashes.append((name, method, detail))
            if args.details:
                print(f"{name:32s} {method:15s} {outcome:13s} {dt:7.2f} s  {detail.splitlines()[0] if detail else ''}")

    cols = ["solved", "negative", "rejected", "solver failed", "bad output", "crashed"]
    print(f"\n{n_meshes} meshes (source vertex 0, convex formulations via {args.solver!r}"
          + (f", meshes up to {args.max_faces} faces" if args.max_faces else "") + ")\n")
    print(f"| method | {' | '.join(cols)} | time (s) | reasons |")
    print("|---" * (len(cols) + 3) + "|")
    for m in methods:
        why = ", ".join(f"{k} ×{v}" for k, v in reasons[m].most_common())
        print(f"| {m} | " + " | ".join(str(counts[m][c]) for c in cols) + f" | {times[m]:.1f} | {why} |")
    for name, method, detail in crashes:
        print(f"\nCRASH {name} {method}: {detail}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
