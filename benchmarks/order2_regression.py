"""Order-2 regression set: fields, iteration counts and times of the default order-2 solve on fixed cases.

Usage::

    PYTHONPATH=src python benchmarks/order2_regression.py record OUT.npz [--quick]
    PYTHONPATH=src python benchmarks/order2_regression.py compare BEFORE.npz AFTER.npz

``record`` solves every case with ``GeodesicSolver(mesh, "qclp", order=2)`` (set-up excluded from the time, the
minimum of ``--repeat`` solves) and stores the vertex field, the P2 field, the iteration count, the status and the
time. ``compare`` prints, per case, the largest field difference relative to the mesh's bounding-box diagonal, the
iteration counts and the time ratio, and exits 1 when a field moved by more than 1e-9 of the diagonal or an
iteration count by more than 1. Run the two versions alternately in one window (state the load) to compare times.
Meshes come from ../shared/meshes (cases whose file is absent are skipped).
"""

from __future__ import annotations

import sys
import time
import warnings
from pathlib import Path

import numpy as np

import cvxgeodesic as cg
from cvxgeodesic.mesh.generate import fan_plate, needle_strip

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"


def _neighbour(mesh: cg.TriMesh, v: int) -> int:
    """A vertex joined to ``v`` by an edge (adjacent sources: the P2 program's hardest source pattern)."""
    e = mesh.edges[(mesh.edges == v).any(axis=1)][0]
    return int(e[0] if e[1] == v else e[1])


def cases(quick: bool = False):
    """``(label, mesh, sources)``: generated flat meshes, then shared meshes that exist."""
    grid = cg.grid_plane(20, jitter=0.4, seed=1)
    sphere = cg.icosphere(3)
    fan = fan_plate()
    out = [
        ("grid20 vertices", grid, [0, 200, 37]),
        ("grid20 point", grid, [cg.SurfacePoint(37, [0.2, 0.3, 0.5])]),
        ("needle240 point", needle_strip(10, 240), [0, cg.SurfacePoint(4, [0.25, 0.25, 0.5])]),
        ("fan plate", fan, [0, 5, fan.n_vertices - 1]),
        ("icosphere3 adjacent", sphere, [0, _neighbour(sphere, 0)]),
    ]
    shared = [("spot.obj", [0]), ("bunny_7k.off", [0]), ("thingi_37881.stl", [0]), ("thingi_65395.stl", [0]),
              ("thingi_96457.stl", [0]), ("fandisk.obj", [0])]
    if not quick:
        shared += [("lucy_20k.obj", [0]), ("bimba.obj", [0]), ("bimba.obj", [0, 7])]
    for name, src in shared:
        path = SHARED / name
        if path.exists():
            out.append((f"{name} {src}", cg.load_mesh(path), src))
    return out


def record(out_path: str, quick: bool, repeat: int) -> None:
    data = {}
    for label, mesh, src in cases(quick):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            solver = cg.GeodesicSolver(mesh, "qclp", order=2)
            best = np.inf
            for _ in range(repeat):
                t0 = time.perf_counter()
                res = solver.solve(src)
                best = min(best, time.perf_counter() - t0)
        info = res.info
        key = label.replace(" ", "_")
        data[key + "/d"] = res.distance
        data[key + "/phi"] = res.field.phi
        last = info.extra.get("round_iterations", [info.iterations])[-1]  # the last cutting-plane round's solve
        data[key + "/meta"] = np.array([last, best, mesh.bbox_diagonal, info.status == "optimal",
                                        info.solver == "ipm"])
        print(f"{label:32s} {info.status:15s} {info.solver:8s} it {last:3d} {best:8.3f} s "
              f"notes: {'; '.join(info.notes)[:100]}", flush=True)
    np.savez(out_path, **data)


def compare(before: str, after: str) -> int:
    a, b = np.load(before), np.load(after)
    bad = 0
    keys = sorted({k.rsplit("/", 1)[0] for k in a.files} & {k.rsplit("/", 1)[0] for k in b.files})
    print(f"{'case':32s} {'field diff / diag':>18s} {'iterations':>12s} {'time after/before':>18s}")
    for k in keys:
        ma, mb = a[k + "/meta"], b[k + "/meta"]
        diag = ma[2]
        da, db = a[k + "/d"], b[k + "/d"]
        both = np.isfinite(da) & np.isfinite(db)
        diff = float(np.abs(da[both] - db[both]).max()) / diag if both.any() else 0.0
        same_inf = bool(np.array_equal(np.isfinite(da), np.isfinite(db)))
        it_a, it_b = int(ma[0]), int(mb[0])
        flag = diff > 1e-9 or abs(it_a - it_b) > 1 or not same_inf
        bad += flag
        print(f"{k:32s} {diff:18.2e} {it_a:5d} -> {it_b:3d} {mb[1] / ma[1]:18.2f}{'  <-- ' if flag else ''}")
    return 1 if bad else 0


if __name__ == "__main__":
    args = sys.argv[1:]
    if args and args[0] == "record":
        rep = next((int(a.split("=")[1]) for a in args if a.startswith("--repeat=")), 1)
        record(args[1], "--quick" in args, rep)
    elif args and args[0] == "compare":
        sys.exit(compare(args[1], args[2]))
    else:
        print(__doc__)
        sys.exit(2)
