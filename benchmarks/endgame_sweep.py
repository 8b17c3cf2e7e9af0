"""The solver's end game over many sources: does any solve on a manifold scan fall back to Clarabel, re-solve, or
take more than 2.5× its mesh's median time? (issue 41, docs/dev/endgame.md)

Not a test: run it by hand, one thread, on the shared manifold scans::

    CVXGEODESIC_THREADS=1 OMP_NUM_THREADS=1 PYTHONPATH=src python benchmarks/endgame_sweep.py
        [--quick] [--meshes bunny.obj,spot.obj] [--methods qcqp-hessian,qclp] [--sources N] [--large-sources N]
        [--seed 0] [--solver auto] [--no-warmup]

For each mesh, seeded random vertex sources (``--sources`` per mesh, ``--large-sources`` on meshes of 40K faces
and more) and each method (default ``qcqp-hessian`` and ``qclp``), one solve with ``solver="auto"`` and a
:class:`~cvxgeodesic.GeodesicSolver` reused across the sources of a mesh and method (the time is the solve's own,
setup excluded; one untimed solve from the first vertex first, since the first solve of a solver also builds what
the later ones reuse: ``--no-warmup`` times it too). One line per solve: mesh, source, method, the solver that
produced the field, the interior-point solver's own status (before any Clarabel retry), the final status,
iterations, re-solves (Clarabel retries and
``d >= 0`` re-solves recorded in ``info.notes``), time, and time ÷ the median of its mesh and method. Then the
summary: fallbacks, re-solves, almost-optimal stops, the worst time ratio. ``--quick``: the smaller meshes, 3
sources each (about a minute).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import cvxgeodesic as cg

SHARED = Path(__file__).resolve().parents[1].parent / "shared" / "meshes"
#: the manifold scans of ../shared/meshes (MANIFEST.tsv: manifold = yes), smallest first
MESHES = ["spot.obj", "fertility_genus4.off", "max_planck.obj", "fandisk.obj", "kitten.obj", "lucy_20k.obj",
          "dragon_20k.obj", "buddha.obj", "camelhead_open.off", "beetle_open.off", "bimba.obj", "bunny.obj",
          "armadillo.obj", "horse.ply"]
QUICK_MESHES = ["spot.obj", "fertility_genus4.off", "max_planck.obj", "fandisk.obj", "kitten.obj"]
LARGE_FACES = 40_000
OUTLIER_RATIO = 2.5


def sources_for(mesh: cg.TriMesh, count: int, seed: int) -> list[int]:
    """``count`` distinct referenced vertices, seeded by ``seed`` and the mesh's name (stable across runs)."""
    rng = np.random.default_rng([seed, sum(map(ord, mesh.name))])
    return [int(v) for v in rng.choice(np.flatnonzero(mesh.referenced), count, replace=False)]


def resolves(notes: list[str]) -> tuple[int, int]:
    """(Clarabel retries, ``d >= 0`` re-solves) recorded in ``notes``."""
    clarabel = sum("solving with Clarabel instead" in n for n in notes)
    nonneg = sum("re-solved with the bounds d >= 0" in n for n in notes)
    return clarabel, nonneg


def solve_one(solver: cg.GeodesicSolver, source: int) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        res = solver.solve(source)
        elapsed = time.perf_counter() - t0
    info = res.info
    clarabel, nonneg = resolves(info.notes)
    extra = info.extra or {}
    ipm_status = extra.get("ipm_failure", info.status if info.solver == "ipm" else "-")
    return {"solver": info.solver, "ipm_status": ipm_status, "status": info.status, "iterations": info.iterations,
            "clarabel": clarabel, "nonneg": nonneg, "time": elapsed,
            "accepted": any("accepted" in n and "interior-point" in n for n in info.notes)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="the smaller meshes, 3 sources each")
    ap.add_argument("--meshes", help="comma-separated file names in ../shared/meshes (NAME@subdivN: split N times)")
    ap.add_argument("--methods", default="qcqp-hessian,qclp")
    ap.add_argument("--sources", type=int, default=10, help="sources per mesh below 40K faces")
    ap.add_argument("--large-sources", type=int, default=5, help="sources per mesh of 40K faces and more")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--solver", default="auto")
    ap.add_argument("--no-warmup", dest="warmup", action="store_false",
                    help="time the first solve of each mesh and method too (it includes lazy set-up)")
    args = ap.parse_args(argv)
    if not SHARED.is_dir():
        print(f"no shared meshes at {SHARED}", file=sys.stderr)
        return 2
    names = args.meshes.split(",") if args.meshes else (QUICK_MESHES if args.quick else MESHES)
    n_small, n_large = (3, 3) if args.quick else (args.sources, args.large_sources)
    methods = args.methods.split(",")
    load = Path("/proc/loadavg").read_text().split()[:3] if Path("/proc/loadavg").exists() else "?"
    print(f"# endgame sweep {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}, solver={args.solver}, "
          f"seed={args.seed}, load average {' '.join(load)}")
    header = (f"{'mesh':22s} {'source':>7s} {'method':13s} {'solver':8s} {'ipm status':15s} {'status':15s} "
              f"{'iters':>5s} {'re-solves':>9s} {'time s':>7s} {'÷median':>7s}")
    rows: list[dict] = []
    total_sources = 0
    for name in names:
        if "@" in name:  # NAME@subdivN: the mesh split N times (reliability_sweep.load), e.g. the split max_planck
            from reliability_sweep import load

            mesh = load(name)
        else:
            mesh = cg.load_mesh(SHARED / name)
        mesh.name = name
        srcs = sources_for(mesh, n_large if mesh.n_faces >= LARGE_FACES else n_small, args.seed)
        total_sources += len(srcs)
        for method in methods:
            solver = cg.GeodesicSolver(mesh, method=method, solver=args.solver, threads=1)
            if args.warmup:  # the first solve of a solver also builds what later ones reuse: not the end game's cost
                solve_one(solver, int(np.flatnonzero(mesh.referenced)[0]))
            block = []
            for s in srcs:
                r = solve_one(solver, s)
                r.update(mesh=name, source=s, method=method)
                block.append(r)
            median = statistics.median(r["time"] for r in block)
            print(header if not rows else "", end="\n" if not rows else "")
            for r in block:
                r["ratio"] = r["time"] / median
                print(f"{r['mesh']:22s} {r['source']:7d} {r['method']:13s} {r['solver']:8s} {r['ipm_status']:15s} "
                      f"{r['status']:15s} {r['iterations']:5d} {r['clarabel'] + r['nonneg']:9d} {r['time']:7.2f} "
                      f"{r['ratio']:7.2f}", flush=True)
            rows.extend(block)
    fallbacks = sum(r["solver"] != "ipm" for r in rows)
    clar = sum(r["clarabel"] for r in rows)
    nonneg = sum(r["nonneg"] for r in rows)
    almost = sum(r["ipm_status"] == "almost_optimal" for r in rows)
    accepted = sum(r["accepted"] for r in rows)
    worst = max(rows, key=lambda r: r["ratio"])
    over = sum(r["ratio"] > OUTLIER_RATIO for r in rows)
    print(f"\n# summary: {total_sources} sources on {len(names)} meshes, {len(rows)} solves ({', '.join(methods)})")
    print(f"#   Clarabel fallbacks: {fallbacks} (retries noted: {clar}); d >= 0 re-solves: {nonneg}; "
          f"interior-point almost_optimal stops: {almost} (accepted with a note: {accepted})")
    print(f"#   worst time ÷ its mesh's median: {worst['ratio']:.2f} ({worst['mesh']}, source {worst['source']}, "
          f"{worst['method']}); solves above {OUTLIER_RATIO}×: {over}")
    print(f"#   iterations: {min(r['iterations'] for r in rows)}–{max(r['iterations'] for r in rows)}; "
          f"load average at the end {' '.join(Path('/proc/loadavg').read_text().split()[:3])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
