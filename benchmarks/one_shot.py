"""One-shot solves against the heat method, as issue 14 measures them: set-up + solve, one process per mesh.

Not a test: run it by hand on a quiet machine::

    python benchmarks/one_shot.py                                  # bimba, horse, armadillo; QCLP, QCQP-Hessian
    python benchmarks/one_shot.py --meshes spot bimba --repeat 3 --order2

For every mesh a fresh Python process loads the mesh, compiles or loads the kernels (``warm_up``, not
timed), then times ``GeodesicSolver(mesh, method).solve(0)`` (construction included: operators, energy,
PSD check, symbolic analysis) and potpourri3d's ``MeshHeatMethodDistanceSolver(V, F)`` +
``compute_distance(0)``, alternating, and keeps the minimum of ``--repeat`` runs of each. Columns:
seconds, iterations, the ratio to the heat method, the process's peak RSS, the load average.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
MESHES = ["bimba.obj", "horse.ply", "armadillo.obj"]
METHODS = ["qclp", "qcqp-hessian"]


def _resolve(name: str) -> Path:
    path = SHARED / name
    if path.exists():
        return path
    hits = sorted(SHARED.glob(name + ".*"))
    if not hits:
        raise SystemExit(f"{name}: not in {SHARED}")
    return hits[0]


def child(path: str, methods: list[str], repeat: int, order2: bool) -> dict:
    """Time every method and the heat method on one mesh, in this process."""
    import potpourri3d as pp3d

    import cvxgeodesic as cg
    from cvxgeodesic.strategies.warm_up import warm_up

    mesh = cg.load_mesh(path)
    warm_up()
    if order2:
        cg.GeodesicSolver(cg.icosphere(1), "qclp", order=2).solve(0)
    cases = [(m, 1) for m in methods] + ([("qclp", 2)] if order2 else [])
    best = {f"{m}/{o}": float("inf") for m, o in cases}
    best["heat"] = float("inf")
    iters = {}
    for _ in range(repeat):
        for method, order in cases:
            t = time.perf_counter()
            res = cg.GeodesicSolver(mesh, method, order=order).solve(0)
            key = f"{method}/{order}"
            best[key] = min(best[key], time.perf_counter() - t)
            iters[key] = res.info.iterations
        t = time.perf_counter()
        pp3d.MeshHeatMethodDistanceSolver(mesh.V, mesh.F).compute_distance(0)
        best["heat"] = min(best["heat"], time.perf_counter() - t)
    return {"mesh": Path(path).name, "faces": mesh.n_faces, "best": best, "iterations": iters,
            "rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0, "load": os.getloadavg()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--meshes", nargs="+", default=MESHES)
    ap.add_argument("--methods", nargs="+", default=METHODS)
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--order2", action="store_true", help="also order=2 qclp")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(args.child, args.methods, args.repeat, args.order2)))
        return 0
    print(f"{'mesh':<16}{'faces':>8}  {'case':<16}{'seconds':>9}{'it':>4}{'/ heat':>8}{'heat s':>8}"
          f"{'RSS MiB':>9}  load (1, 5, 15 min)")
    for name in args.meshes:
        cmd = [sys.executable, __file__, "--child", str(_resolve(name)), "--repeat", str(args.repeat),
               "--methods", *args.methods] + (["--order2"] if args.order2 else [])
        out = subprocess.run(cmd, capture_output=True, text=True, check=True)
        row = json.loads(out.stdout.strip().splitlines()[-1])
        heat = row["best"]["heat"]
        for key, t in row["best"].items():
            if key == "heat":
                continue
            print(f"{row['mesh']:<16}{row['faces']:>8}  {key:<16}{t:>8.3f}s{row['iterations'][key]:>4}"
                  f"{t / heat:>7.1f}x{heat:>7.3f}s{row['rss_mib']:>9.0f}  "
                  + " ".join(f"{x:.2f}" for x in row["load"]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
