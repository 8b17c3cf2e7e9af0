"""The time a curve source takes to resolve (closest points, samples, pieces) against the solve it feeds.

Not a test: run it by hand (docs/sources.md, "Closest points")::

    python benchmarks/curve_sources.py --mesh bunny --points 65 --repeat 3
    python benchmarks/curve_sources.py --mesh spot --points 9 --repeat 1       # a smoke run

The curve: ``--points`` positions on the chord from vertex 0 to the vertex farthest from it, projected to the
surface (``cg.surface_point``), given to ``cg.SurfaceCurve`` as positions (so that they are searched too). One
process, one thread (``--threads``), the solves through ``GeodesicSolver.solve``:

``first``
    ``info.extra["source_time"]`` of the first solve of a fresh mesh object (the closest-point tree is built
    then);
``again``
    the same for a second solve of the same curve (the tree kept);
``solve``
    ``info.solve_time`` minus ``source_time`` (the convex solve alone);
``before``
    the search as it was before the tree (libigl's ``point_mesh_squared_distance``, which builds a tree per
    call, once per position and once per segment), timed here on the same curve (``--no-before``: skipped).

Each repetition measures all of them side by side; the medians and the ratios to the solve are printed, the
ratios first (the machine may be shared: they are steadier than the seconds). A mesh is a name in
``../shared/meshes`` (``bunny`` finds ``bunny.obj``) or a path.
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
SHARED = HERE.parents[1] / "shared" / "meshes"


def load(spec: str):
    import cvxgeodesic as cg

    path = Path(spec)
    if not path.exists():
        found = sorted(SHARED.glob(f"{spec}.*")) if SHARED.is_dir() else []
        if not found:
            raise SystemExit(f"no mesh {spec!r} (neither a file nor a name in {SHARED})")
        path = found[0]
    return cg.load_mesh(path), path.name


def make_curve(mesh, points: int):
    """(points, 3) positions on the surface under the chord from vertex 0 to the vertex farthest from it."""
    import cvxgeodesic as cg

    V = mesh.V
    b = int(np.argmax(np.linalg.norm(V - V[0], axis=1)))
    t = np.linspace(0.0, 1.0, points)[:, None]
    return np.array([p.position(mesh) for p in cg.surface_point(mesh, (1 - t) * V[0] + t * V[b])])


def search_before_the_index(mesh, X) -> float:
    """Seconds of the closest-point searches the library made for this curve before the tree: one libigl call
    (a tree built each time) per position and per segment with inner samples."""
    import igl

    from cvxgeodesic.sources import CURVE_STEP

    V = np.ascontiguousarray(mesh.V, dtype=np.float64)
    F = np.ascontiguousarray(mesh.F, dtype=np.int64)
    step = CURVE_STEP * mesh.mean_edge_length
    t0 = time.perf_counter()
    for x in X:
        igl.point_mesh_squared_distance(np.ascontiguousarray(x[None, :]), V, F)
    for xa, xb in zip(X[:-1], X[1:], strict=True):
        k = max(1, math.ceil(np.linalg.norm(xb - xa) / step))
        if k > 1:
            t = np.linspace(0.0, 1.0, k + 1)[1:-1, None]
            igl.point_mesh_squared_distance(np.ascontiguousarray((1 - t) * xa + t * xb), V, F)
    return time.perf_counter() - t0


def one_round(spec: str, points: int, method: str, threads: int, before: bool) -> dict:
    import cvxgeodesic as cg
    from cvxgeodesic.sources import resolve_sources

    mesh, name = load(spec)  # a fresh mesh object: its tree is built in the first solve
    X = make_curve(mesh, points)
    curve = cg.SurfaceCurve(X)
    solver = cg.GeodesicSolver(mesh, method=method, threads=threads)
    first = solver.solve(curve).info
    again = solver.solve(curve).info
    ss = resolve_sources(mesh, curve)
    return {"name": name, "faces": mesh.n_faces, "samples": len(ss.distinct_points(mesh)) + ss.vertices.size,
            "first": first.extra["source_time"], "again": again.extra["source_time"],
            "solve": again.solve_time - again.extra["source_time"],
            "before": search_before_the_index(mesh, X) if before else math.nan}


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mesh", default="bunny", help="a name in ../shared/meshes or a mesh file (default bunny)")
    ap.add_argument("--points", type=int, default=65, help="positions on the curve (default 65)")
    ap.add_argument("--method", default="qclp", help="the formulation solved (default qclp)")
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-before", action="store_true", help="skip the search as it was before the tree")
    args = ap.parse_args(argv)
    rounds = [one_round(args.mesh, args.points, args.method, args.threads, not args.no_before)
              for _ in range(args.repeat)]
    med = {key: statistics.median(r[key] for r in rounds) for key in ("first", "again", "solve", "before")}
    r0 = rounds[0]
    print(f"curve sources on {r0['name']} ({r0['faces']} faces), a {args.points}-point curve ({r0['samples']} "
          f"samples), {args.method}, {args.threads} thread(s), median of {args.repeat}:")
    for key, what in (("again", "source resolution"), ("first", "first resolution on the mesh (tree built)"),
                      ("before", "search before the tree (a tree per call)")):
        if not math.isnan(med[key]):
            r = med[key] / med["solve"]
            share = f"{r:.1f}× the solve" if r >= 1 else f"{r:.1%} of the solve"
            print(f"  {what}: {share} ({med[key]:.3g} s; solve {med['solve']:.3g} s)")
    for r in rounds:
        print("  round: " + ", ".join(f"{k} {r[k]:.3g} s" for k in ("first", "again", "solve", "before")))


if __name__ == "__main__":
    main()
