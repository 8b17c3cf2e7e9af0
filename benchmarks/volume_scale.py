"""Distance inside a 100K-tetrahedron mesh: time and peak memory of each method, against the tet heat method.

Not a test: run it by hand (docs/volumes.md and docs/benchmarks.md quote it)::

    python benchmarks/volume_scale.py                         # L-shaped prism, n = 18: 104 976 tetrahedra
    python benchmarks/volume_scale.py --n 12 --order2         # 31 104 tetrahedra, order 2 too
    python benchmarks/volume_scale.py --repeat 3 --json out.json

Each (method, order) runs in a fresh process (``--child``): the compiled kernels are loaded first (``warm_up``,
not timed), the mesh is generated (``cg.tet_l_prism(n, jitter=0.2)``), then the solver is built (``setup``) and
solves from the vertex nearest (0.5, 1.5, 0.5) (``solve``); ``peak`` is the process's peak resident memory
(``ru_maxrss``) and ``base`` its resident memory just before the solver was built, so ``peak − base`` is what the
solve added. The error is the mean relative error against the exact distance (``l_prism_distance``). Every run
prints the machine's 1-minute load average: the machine may be shared; compare methods of one run, and take the
minimum of ``--repeat`` runs.
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

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
RUNS = (("heat", 1), ("dijkstra", 1), ("qclp", 1))


def _rss_mib() -> float:
    """The current resident memory of this process (``/proc/self/statm``), MiB."""
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def child(method: str, order: int, n: int) -> dict:
    import numpy as np

    import cvxgeodesic as cg
    from cvxgeodesic.mesh.tet_generate import l_prism_distance
    from cvxgeodesic.strategies.warm_up import warm_up

    warm_up()
    mesh = cg.tet_l_prism(n, jitter=0.2, seed=1)
    c = int(np.argmin(np.linalg.norm(mesh.V - [0.5, 1.5, 0.5], axis=1)))
    exact = l_prism_distance(mesh.V[c], mesh.V)
    base = _rss_mib()
    t0 = time.perf_counter()
    solver = cg.GeodesicSolver(mesh, method, order=order)
    t1 = time.perf_counter()
    res = solver.solve(c)
    t2 = time.perf_counter()
    k = exact > 0
    return {"method": method, "order": order, "tets": mesh.n_tets, "vertices": mesh.n_vertices,
            "setup_s": t1 - t0, "solve_s": t2 - t1, "iterations": res.info.iterations, "solver": res.info.solver,
            "status": res.info.status, "rounds": res.info.extra.get("rounds"),
            "n_dofs": res.info.extra.get("n_dofs", mesh.n_vertices),
            "mean_rel_err": float(np.mean(np.abs(res.distance - exact)[k] / exact[k])),
            "base_mib": base, "peak_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
            "loadavg_1min": round(os.getloadavg()[0], 2)}


def run(method: str, order: int, n: int, timeout: float) -> dict:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}
    cmd = [sys.executable, __file__, "--child", method, str(order), "--n", str(n)]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"method": method, "order": order, "error": f"timed out after {timeout:.0f} s"}
    if out.returncode != 0:
        return {"method": method, "order": order, "error": out.stderr.strip().splitlines()[-1][:200]}
    return json.loads(out.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, default=18, help="cells per unit length of the prism (18 n³ tetrahedra)")
    ap.add_argument("--order2", action="store_true", help="also qclp at order 2 (minutes and GiB at 100K)")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each method; the minimum times are kept")
    ap.add_argument("--timeout", type=float, default=3600.0, help="seconds per run")
    ap.add_argument("--json", default=None, help="write the records here")
    ap.add_argument("--child", nargs=2, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.child:
        print(json.dumps(child(args.child[0], int(args.child[1]), args.n)))
        return 0
    runs = [*RUNS, *((("qclp", 2),) if args.order2 else ())]
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; "
          f"threads: CVXGEODESIC_THREADS={os.environ.get('CVXGEODESIC_THREADS', '(default)')}", flush=True)
    records = []
    for method, order in runs:
        best = None
        for _ in range(args.repeat):
            rec = run(method, order, args.n, args.timeout)
            if "error" in rec:
                best = rec
                break
            if best is None or rec["setup_s"] + rec["solve_s"] < best["setup_s"] + best["solve_s"]:
                best = rec
        records.append(best)
        if "error" in best:
            print(f"{method} order {order}: {best['error']}", flush=True)
            continue
        print(f"{method:>8} order {order}: {best['tets']} tets, {best['n_dofs']} unknowns; set-up "
              f"{best['setup_s']:.2f} s, solve {best['solve_s']:.2f} s ({best['iterations']} it., {best['solver']}); "
              f"peak {best['peak_mib']:.0f} MiB (+{best['peak_mib'] - best['base_mib']:.0f} over the "
              f"{best['base_mib']:.0f} before the set-up); mean error {100 * best['mean_rel_err']:.2f} %; "
              f"load {best['loadavg_1min']}", flush=True)
    heat = next((r for r in records if r.get("method") == "heat" and "error" not in r), None)
    if heat is not None:
        for r in records:
            if "error" not in r and r is not heat:
                ratio = (r["setup_s"] + r["solve_s"]) / (heat["setup_s"] + heat["solve_s"])
                print(f"{r['method']} order {r['order']}: {ratio:.1f}x the heat method's time, "
                      f"{(r['peak_mib'] - r['base_mib']) / max(heat['peak_mib'] - heat['base_mib'], 1):.1f}x its "
                      "added memory")
    if args.json:
        Path(args.json).write_text(json.dumps(records, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
