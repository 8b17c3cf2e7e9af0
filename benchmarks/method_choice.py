"""What each method buys, measured: the numbers behind the README's "Which method to use".

Not a test: run it by hand, on as quiet a machine as you have::

    python benchmarks/method_choice.py                                   # the bundled spot mesh
    python benchmarks/method_choice.py --meshes bimba.obj thingi_37881.stl --repeat 3

For every mesh (spot always; ``--meshes`` names files of ``--shared``, default ``../shared/meshes``), in this
process: the compiled kernels are loaded first (not timed), then every case of :data:`CASES` is timed as
``GeodesicSolver(mesh, method, order=order).solve(0)`` (set-up included), the minimum of ``--repeat`` runs,
the cases alternating. Its field is compared with the exact distance (MMP) by
:func:`cvxgeodesic.evaluation.summary.summarize`: mean relative error and the ridge sharpness against the
exact field's (``ridge_jump_ratio``: 1 = as creased as the exact field, lower = rounder isolines at the
ridge). Prints a Markdown table and the machine's load average before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import cvxgeodesic as cg
from cvxgeodesic.demo import demo_mesh
from cvxgeodesic.evaluation.summary import summarize

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
#: (label, method, order)
CASES = [("qcqp-hessian (default)", "qcqp-hessian", 1), ("qclp", "qclp", 1), ("qclp, order=2", "qclp", 2),
         ("heat", "heat", 1), ("exact", "exact", 1)]


def measure(mesh, repeat: int, cases=CASES) -> list[dict]:
    """One row per case of ``cases`` (``(label, method, order)``, one of them labelled ``exact``) on ``mesh``.

    Returns
    -------
    list of dict
        ``case, time_s`` (minimum of ``repeat`` runs, set-up included), ``rel_mean``, ``ridge_jump_ratio``,
        ``status``, ``iterations``.
    """
    best: dict[str, float] = {}
    results = {}
    for _ in range(repeat):
        for label, method, order in cases:
            t = time.perf_counter()
            res = cg.GeodesicSolver(mesh, method, order=order).solve(0)
            best[label] = min(best.get(label, float("inf")), time.perf_counter() - t)
            results[label] = res
    exact = results["exact"].distance
    rows = []
    for label, _, _ in cases:
        rec = summarize(mesh, results[label], exact, time_s=best[label], gradient=False)
        rows.append({"case": label, "time_s": rec["time_s"], "rel_mean": rec["rel_mean"],
                     "ridge_jump_ratio": rec["ridge_jump_ratio"], "status": rec["status"],
                     "iterations": rec["iterations"]})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--meshes", nargs="*", default=[], help="file names in --shared")
    ap.add_argument("--shared", type=Path, default=SHARED)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", type=Path, default=None, help="also write the rows here")
    args = ap.parse_args()

    cg.GeodesicSolver(cg.icosphere(1), "qclp", order=2).solve(0)  # load (or compile) the kernels, untimed
    cg.geodesic_distance(cg.icosphere(1), 0)
    load0 = os.getloadavg()
    meshes = [("spot", demo_mesh())] + [(name, cg.load_mesh(args.shared / name)) for name in args.meshes]
    out = {}
    for name, mesh in meshes:
        out[name] = {"faces": mesh.n_faces, "rows": measure(mesh, args.repeat)}
    load1 = os.getloadavg()
    print(f"{time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, threads: {os.environ.get('CVXGEODESIC_THREADS', 'default policy')}, "
          f"load average {load0[0]:.2f} -> {load1[0]:.2f}, min of {args.repeat}")
    print("| mesh (faces) | case | time | mean error | ridge vs exact | status, iterations |")
    print("|---|---|---|---|---|---|")
    for name, m in out.items():
        for r in m["rows"]:
            print(f"| {name} ({m['faces']:,}) | {r['case']} | {r['time_s']:.2f} s | {100 * r['rel_mean']:.3g} % | "
                  f"{r['ridge_jump_ratio']:.2f} | {r['status']}, {r['iterations']} |")
    if args.json:
        args.json.write_text(json.dumps({"load": [load0, load1], "meshes": out}, indent=1))


if __name__ == "__main__":
    main()
